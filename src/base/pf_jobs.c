/* pf_jobs: the job system (pf_jobs.h): a fixed pthread pool that runs a
 * per-frame task graph of parallel-fors.
 *
 * How it works:
 * - One mutex guards the graph: job fields other than the two item counters,
 *   the dependents lists, the ready list and all bookkeeping counts. Only item
 *   claiming (`next`) and item completion (`done`) are lock-free atomics, so
 *   threads meet on the mutex once per job, not once per chunk.
 * - Readiness: a job counts its unfinished deps in `pending` and is linked
 *   into each such dep's dependents list. When a job finishes, its dependents'
 *   counts drop; those reaching zero go to the back of the ready list (FIFO,
 *   so every thread piles onto the oldest parallel-for first). A count-0 job
 *   finishes the moment it becomes ready.
 * - Chunks: a thread that picks a ready job claims `grain` items at a time
 *   with atomic_fetch_add on `next` until it passes `count`; several threads
 *   share one job this way. Whoever brings `done` to `count` finishes the job.
 *   Exhausted jobs leave the ready list lazily, when someone next looks.
 * - Wakeups: idle workers sleep on work_cv, signalled (once per chunk, up to
 *   the number of sleepers) when jobs become ready. Threads inside
 *   pf_jobs_wait / pf_jobs_wait_all sleep on wait_cv, which is broadcast when
 *   jobs become ready, finish, or the last running thread lets go of a job, so
 *   a waiter never sleeps while there is work it could help with.
 * - Storage: jobs live in fixed-size pages that never move once allocated,
 *   because threads use job pointers outside the mutex; only the page table,
 *   the ready list and the dependency edges (touched solely under the mutex)
 *   are realloc'ed. Everything is reset, not freed, at pf_jobs_wait_all, so a
 *   steady frame loop stops allocating after its first frame.
 *
 * Worker indices: worker threads are 0 .. thread_count-2; the one external
 * thread that waits (the frame loop) runs items as thread_count-1. A job
 * that waits inside a worker keeps that worker's index. Only one external
 * thread may call the wait functions at a time, or two threads would share
 * index thread_count-1 and with it per-worker scratch.
 *
 * Profile (pf_jobs.h, off unless a benchmark turns it on): each thread
 * times the items of a chunk, adds their sum and maximum to the job's two
 * profile counters (relaxed atomics, published by the acq_rel on `done`),
 * and the thread that finishes the job folds them into the pool's totals
 * under the mutex. A wait inside an item adds its duration to a
 * thread-local "excluded" count that the item subtracts from its own time,
 * so nested jobs are counted once; items run inside that wait restore the
 * count when they end, so nothing is subtracted twice.
 *
 * Waiting inside a job helps with any ready job, so it cannot deadlock while
 * the awaited job does not depend (directly or not) on a job that is already
 * running: a helper may be parked, under its own stack frames, inside such a
 * running job. Waiting for jobs that the waiting job added itself is the
 * intended use and is always safe. */
#define _POSIX_C_SOURCE 200809L

#include "pf_jobs.h"

#include "pf_fpenv.h"

#include <assert.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

/* 256 jobs of two cache lines each (the second holds only the profile
 * counters, untouched unless profiling): 32 KiB pages. */
#define PF__PAGE_SHIFT 8u
#define PF__PAGE_JOBS (1u << PF__PAGE_SHIFT)
#define PF__NO_EDGE 0xffffffffu
/* With grain 0, each thread gets about this many chunks of a job: enough to
 * even out uneven items, few enough that claiming stays cheap. */
#define PF__CHUNKS_PER_THREAD 4u

typedef struct pf__job {
    /* Lock-free: first unclaimed item (64-bit, because every thread that
     * finds the job exhausted still adds one grain past `count`), and the
     * number of items finished. */
    _Alignas(64) atomic_uint_fast64_t next;
    atomic_uint done;
    /* Written under the mutex before the job becomes ready; read-only while
     * it runs. */
    uint32_t count;
    uint32_t grain;
    pf_job_fn fn;
    void *ctx;
    /* Under the mutex. */
    uint32_t pending;    /* deps not yet finished */
    uint32_t first_edge; /* head of the dependents list, PF__NO_EDGE if none */
    struct pf__job *link; /* pf__finish's work stack */
    uint8_t finished;
    uint8_t auto_grain; /* grain was 0: the profile's predictions rescale it */
    /* Profile only: item nanoseconds summed, and the longest item. */
    atomic_uint_fast64_t prof_work_ns, prof_longest_ns;
} pf__job;

typedef struct pf__job_page {
    pf__job jobs[PF__PAGE_JOBS];
} pf__job_page;

/* "Job `job` waits for the job whose list holds this edge." */
typedef struct pf__edge {
    uint32_t job;
    uint32_t next;
} pf__edge;

typedef struct pf__worker {
    pthread_t thread;
    pf_jobs *jobs;
    uint32_t index;
} pf__worker;

struct pf_jobs {
    pthread_mutex_t mutex;
    pthread_cond_t work_cv; /* idle workers */
    pthread_cond_t wait_cv; /* threads in pf_jobs_wait / pf_jobs_wait_all */
    uint32_t thread_count;
    uint32_t started; /* worker threads running */
    pf__worker *workers;
    int stop;

    /* Everything below is under the mutex. */
    pf__job_page **pages;
    uint32_t page_count, page_cap;
    uint32_t job_count;      /* ids handed out since the last wait_all */
    uint32_t finished_count; /* of those, finished */

    /* Ids of jobs that became ready, in order. A job enters at most once per
     * frame, so one slot per job of capacity (page_cap pages) always
     * suffices and pushing never allocates. [ready_head, ready_tail) may
     * still hold exhausted jobs. */
    uint32_t *ready;
    uint32_t ready_head, ready_tail;

    pf__edge *edges;
    uint32_t edge_count, edge_cap;
    uint32_t fail_growth; /* tests (pf_jobs_test_fail_growth): refuse this many growths of the bookkeeping */

    uint32_t idle_workers;     /* asleep on work_cv */
    uint32_t sleeping_waiters; /* asleep on wait_cv */
    uint32_t active;           /* threads holding a job pointer outside the mutex */

    /* Profile (pf_jobs.h): `profile` is written only between frames by the
     * external thread (atomic, so threads read it without the mutex); the
     * totals are under the mutex. */
    atomic_int profile;
    uint64_t prof_wait_ns, prof_wait_cpu_ns, prof_work_ns, prof_span_ns, prof_jobs, prof_items;
    double prof_predicted_ns[PF_JOBS_PROFILE_CORES];
};

const uint32_t pf_jobs_profile_cores[PF_JOBS_PROFILE_CORES] = {1, 2, 4, 8, 16, 32, 64, 128};

/* Which pool, if any, this thread is a worker of, and how many job bodies
 * are on its stack (wait_all inside a job would wait for itself). */
static _Thread_local const pf_jobs *pf__tls_pool;
static _Thread_local uint32_t pf__tls_worker;
static _Thread_local uint32_t pf__tls_depth;
/* Profile: nanoseconds of waits inside the item this thread is running. */
static _Thread_local uint64_t pf__tls_excluded_ns;

static uint64_t pf__ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static pf__job *pf__job_at(const pf_jobs *jobs, uint32_t id)
{
    return &jobs->pages[id >> PF__PAGE_SHIFT]->jobs[id & (PF__PAGE_JOBS - 1)];
}

static uint32_t pf__self(const pf_jobs *jobs)
{
    return pf__tls_pool == jobs ? pf__tls_worker : jobs->thread_count - 1;
}

/* Adds one page of job slots. Under the mutex. */
static int pf__grow_jobs(pf_jobs *jobs)
{
    if (jobs->fail_growth) {
        jobs->fail_growth--;
        return 0;
    }
    if (jobs->page_count == jobs->page_cap) {
        uint32_t cap = jobs->page_cap ? jobs->page_cap * 2 : 8;
        /* Ids are 32-bit with PF_JOB_NONE reserved; never need more pages. */
        if (cap > (1u << (32 - PF__PAGE_SHIFT))) cap = 1u << (32 - PF__PAGE_SHIFT);
        if (cap == jobs->page_cap) return 0;
        pf__job_page **pages = realloc(jobs->pages, (size_t)cap * sizeof *pages);
        if (!pages) return 0;
        jobs->pages = pages;
        uint32_t *ready = realloc(jobs->ready, (size_t)cap * PF__PAGE_JOBS * sizeof *ready);
        if (!ready) return 0;
        jobs->ready = ready;
        jobs->page_cap = cap;
    }
    pf__job_page *page = aligned_alloc(_Alignof(pf__job_page), sizeof *page);
    if (!page) return 0;
    jobs->pages[jobs->page_count++] = page;
    return 1;
}

/* Wakes sleepers after `chunks` chunks of work became ready. Under the mutex. */
static void pf__wake(pf_jobs *jobs, uint64_t chunks)
{
    if (jobs->idle_workers) {
        if (chunks >= jobs->idle_workers)
            pthread_cond_broadcast(&jobs->work_cv);
        else
            for (uint64_t i = 0; i < chunks; i++) pthread_cond_signal(&jobs->work_cv);
    }
    if (jobs->sleeping_waiters) pthread_cond_broadcast(&jobs->wait_cv);
}

static uint64_t pf__chunk_count(const pf__job *job)
{
    return ((uint64_t)job->count + job->grain - 1) / job->grain;
}

/* Adds a finished job's profile counters to the pool's totals (see
 * pf_jobs.h for the prediction). Under the mutex. */
static void pf__profile_fold(pf_jobs *jobs, pf__job *job)
{
    uint64_t work = atomic_load_explicit(&job->prof_work_ns, memory_order_relaxed);
    uint64_t longest = atomic_load_explicit(&job->prof_longest_ns, memory_order_relaxed);
    jobs->prof_work_ns += work;
    jobs->prof_span_ns += longest;
    jobs->prof_jobs++;
    jobs->prof_items += job->count;
    for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++) {
        uint64_t n = pf_jobs_profile_cores[k];
        uint64_t grain = job->grain;
        if (job->auto_grain) {
            grain = job->count / (n * PF__CHUNKS_PER_THREAD);
            if (grain == 0) grain = 1;
        }
        uint64_t chunks = (job->count + grain - 1) / grain;
        double t = (double)((chunks + n - 1) / n) * ((double)work / (double)chunks);
        jobs->prof_predicted_ns[k] += t > (double)longest ? t : (double)longest;
    }
}

/* Marks `job` finished and releases its dependents; count-0 dependents
 * finish at once, which can cascade, so this walks an explicit stack rather
 * than recursing. Under the mutex. */
static void pf__finish(pf_jobs *jobs, pf__job *job)
{
    uint64_t chunks = 0;
    job->link = NULL;
    pf__job *stack = job;
    while (stack) {
        pf__job *j = stack;
        stack = j->link;
        j->finished = 1;
        jobs->finished_count++;
        if (j->count && atomic_load_explicit(&jobs->profile, memory_order_relaxed)) pf__profile_fold(jobs, j);
        for (uint32_t e = j->first_edge; e != PF__NO_EDGE; e = jobs->edges[e].next) {
            uint32_t id = jobs->edges[e].job;
            pf__job *d = pf__job_at(jobs, id);
            assert(d->pending > 0);
            if (--d->pending) continue;
            if (d->count == 0) {
                d->link = stack;
                stack = d;
            } else {
                jobs->ready[jobs->ready_tail++] = id;
                chunks += pf__chunk_count(d);
            }
        }
    }
    /* Waiters want to hear about finished jobs even when nothing new is
     * ready; pf__wake broadcasts to them in any case. */
    pf__wake(jobs, chunks);
}

/* A ready job with unclaimed items, or NULL. `prefer` (may be NULL) is taken
 * first when it is runnable: a waiter gets its own job done soonest by
 * working on it. Under the mutex. */
static pf__job *pf__pick(pf_jobs *jobs, pf__job *prefer)
{
    if (prefer && prefer->pending == 0 && atomic_load_explicit(&prefer->next, memory_order_relaxed) < prefer->count)
        return prefer;
    while (jobs->ready_head < jobs->ready_tail) {
        pf__job *job = pf__job_at(jobs, jobs->ready[jobs->ready_head]);
        if (atomic_load_explicit(&job->next, memory_order_relaxed) < job->count) return job;
        jobs->ready_head++;
    }
    return NULL;
}

/* The calling thread's CPU time (about 1 us a read here, 25 times a
 * monotonic clock read: read only where an item looks preempted). */
static uint64_t pf__cpu_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* An item at least this long may hold a preemption (a loaded machine takes
 * the core away for a scheduler slice, milliseconds): its thread's CPU time
 * is checked. */
#define PF__SUSPECT_NS 300000u

/* One thread's run through a job (pf__run_chunks): its CPU time when last
 * checked and the item wall time since. */
typedef struct pf__prof_run {
    uint64_t cpu, wall;
} pf__prof_run;

/* Runs items [begin, end) of `job` timing each one (the profile), and adds
 * their sum and maximum to the job's counters.
 *
 * Items are timed by the wall clock (cheap), which on a loaded machine
 * also counts the time another process held the core: one preempted row
 * would pass for the frame's longest item. So when a chunk's longest item
 * is long, the thread's CPU time is read, and the wall time since the last
 * check beyond it (time not running) is taken off that item and the
 * chunk's sum. Items that waited (nested jobs) skip the check: their
 * thread's CPU time includes the items it ran meanwhile. */
static void pf__run_profiled(pf__job *job, uint32_t begin, uint32_t end, uint32_t worker, pf__prof_run *run)
{
    uint64_t sum = 0, longest = 0;
    int nested = 0;
    for (uint32_t item = begin; item < end; item++) {
        uint64_t excluded = pf__tls_excluded_ns, t0 = pf__ns();
        job->fn(job->ctx, item, worker);
        uint64_t t = pf__ns() - t0, waited = pf__tls_excluded_ns - excluded;
        pf__tls_excluded_ns = excluded; /* this item's waits are not its caller's */
        nested |= waited != 0;
        t = t > waited ? t - waited : 0;
        sum += t;
        if (t > longest) longest = t;
    }
    run->wall += sum;
    if (nested) {
        run->cpu = pf__cpu_ns();
        run->wall = 0;
    } else if (longest >= PF__SUSPECT_NS) {
        uint64_t cpu = pf__cpu_ns(), ran = cpu - run->cpu;
        uint64_t idle = run->wall > ran ? run->wall - ran : 0;
        if (idle > longest) idle = longest;
        longest -= idle;
        sum -= idle < sum ? idle : sum;
        run->cpu = cpu;
        run->wall = 0;
    }
    atomic_fetch_add_explicit(&job->prof_work_ns, sum, memory_order_relaxed);
    uint_fast64_t old = atomic_load_explicit(&job->prof_longest_ns, memory_order_relaxed);
    while (old < longest &&
           !atomic_compare_exchange_weak_explicit(&job->prof_longest_ns, &old, longest, memory_order_relaxed,
                                                  memory_order_relaxed)) {
    }
}

/* Claims and runs chunks of `job` until none are left. Outside the mutex.
 * Returns 1 when this thread ran the job's last item and so must finish it. */
static int pf__run_chunks(pf__job *job, uint32_t worker, int profile)
{
    const uint32_t count = job->count, grain = job->grain;
    pf__prof_run run = {0, 0};
    for (;;) {
        uint64_t begin = atomic_fetch_add_explicit(&job->next, grain, memory_order_relaxed);
        if (begin >= count) return 0;
        uint32_t end = begin + grain < count ? (uint32_t)(begin + grain) : count;
        if (profile && run.cpu == 0) run.cpu = pf__cpu_ns();
        if (profile) pf__run_profiled(job, (uint32_t)begin, end, worker, &run);
        else
            for (uint32_t item = (uint32_t)begin; item < end; item++) job->fn(job->ctx, item, worker);
        /* acq_rel: the thread that completes the job has then seen every
         * other thread's item writes, and publishes them to dependents
         * through the mutex in pf__finish. */
        uint32_t n = end - (uint32_t)begin;
        if (atomic_fetch_add_explicit(&job->done, n, memory_order_acq_rel) + n == count) return 1;
    }
}

/* Runs chunks of one ready job (preferring `prefer`). Called and returns
 * with the mutex held. Returns 0 when nothing was ready. */
static int pf__help(pf_jobs *jobs, uint32_t worker, pf__job *prefer)
{
    pf__job *job = pf__pick(jobs, prefer);
    if (!job) return 0;
    jobs->active++;
    pthread_mutex_unlock(&jobs->mutex);
    pf__tls_depth++;
    int completed = pf__run_chunks(job, worker, atomic_load_explicit(&jobs->profile, memory_order_relaxed));
    pf__tls_depth--;
    pthread_mutex_lock(&jobs->mutex);
    jobs->active--;
    if (completed)
        pf__finish(jobs, job);
    else if (jobs->active == 0 && jobs->sleeping_waiters)
        pthread_cond_broadcast(&jobs->wait_cv); /* wait_all may be waiting for the last pointer to drop */
    return 1;
}

static void *pf__worker_main(void *arg)
{
    pf__worker *self = arg;
    pf_jobs *jobs = self->jobs;
    pf_fpenv_set();
    pf__tls_pool = jobs;
    pf__tls_worker = self->index;
    pthread_mutex_lock(&jobs->mutex);
    while (!jobs->stop) {
        if (pf__help(jobs, self->index, NULL)) continue;
        jobs->idle_workers++;
        pthread_cond_wait(&jobs->work_cv, &jobs->mutex);
        jobs->idle_workers--;
    }
    pthread_mutex_unlock(&jobs->mutex);
    return NULL;
}

/* Stops and joins the started workers and frees everything. */
static void pf__shutdown(pf_jobs *jobs)
{
    pthread_mutex_lock(&jobs->mutex);
    jobs->stop = 1;
    pthread_cond_broadcast(&jobs->work_cv);
    pthread_mutex_unlock(&jobs->mutex);
    for (uint32_t i = 0; i < jobs->started; i++) pthread_join(jobs->workers[i].thread, NULL);
    pthread_cond_destroy(&jobs->wait_cv);
    pthread_cond_destroy(&jobs->work_cv);
    pthread_mutex_destroy(&jobs->mutex);
    for (uint32_t p = 0; p < jobs->page_count; p++) free(jobs->pages[p]);
    free(jobs->pages);
    free(jobs->ready);
    free(jobs->edges);
    free(jobs->workers);
    free(jobs);
}

pf_jobs *pf_jobs_create(uint32_t thread_count)
{
    assert(thread_count >= 1 && thread_count <= PF_JOBS_MAX_THREADS);
    if (thread_count < 1) thread_count = 1;
    if (thread_count > PF_JOBS_MAX_THREADS) thread_count = PF_JOBS_MAX_THREADS;

    pf_jobs *jobs = calloc(1, sizeof *jobs);
    if (!jobs) return NULL;
    atomic_init(&jobs->profile, 0);
    if (pthread_mutex_init(&jobs->mutex, NULL)) {
        free(jobs);
        return NULL;
    }
    if (pthread_cond_init(&jobs->work_cv, NULL)) {
        pthread_mutex_destroy(&jobs->mutex);
        free(jobs);
        return NULL;
    }
    if (pthread_cond_init(&jobs->wait_cv, NULL)) {
        pthread_cond_destroy(&jobs->work_cv);
        pthread_mutex_destroy(&jobs->mutex);
        free(jobs);
        return NULL;
    }
    jobs->thread_count = thread_count;

    uint32_t worker_count = thread_count - 1;
    if (worker_count) {
        jobs->workers = calloc(worker_count, sizeof *jobs->workers);
        if (!jobs->workers) {
            pf__shutdown(jobs);
            return NULL;
        }
    }
    for (uint32_t i = 0; i < worker_count; i++) {
        jobs->workers[i].jobs = jobs;
        jobs->workers[i].index = i;
        if (pthread_create(&jobs->workers[i].thread, NULL, pf__worker_main, &jobs->workers[i])) {
            pf__shutdown(jobs);
            return NULL;
        }
        jobs->started++;
    }
    return jobs;
}

void pf_jobs_destroy(pf_jobs *jobs)
{
    if (!jobs) return;
    /* Jobs still queued would otherwise run against freed storage; running
     * them is the only way to let every thread go cleanly. */
    pf_jobs_wait_all(jobs);
    pf__shutdown(jobs);
}

uint32_t pf_jobs_thread_count(const pf_jobs *jobs)
{
    return jobs->thread_count;
}

/* Room for `more` dependency edges; 0 when memory is short. Under the mutex. */
static int pf__reserve_edges(pf_jobs *jobs, uint32_t more)
{
    if (more <= jobs->edge_cap - jobs->edge_count) return 1;
    if (jobs->fail_growth) {
        jobs->fail_growth--;
        return 0;
    }
    uint64_t need = (uint64_t)jobs->edge_count + more, cap = jobs->edge_cap ? jobs->edge_cap : 256;
    while (cap < need) cap *= 2;
    if (cap > UINT32_MAX) return 0;
    pf__edge *edges = realloc(jobs->edges, (size_t)cap * sizeof *edges);
    if (!edges) return 0;
    jobs->edges = edges;
    jobs->edge_cap = (uint32_t)cap;
    return 1;
}

/* pf_jobs_add has no error path (it runs inside hot loops): when the
 * bookkeeping cannot grow (out of memory, or 2^32-1 jobs since the last
 * pf_jobs_wait_all) the job runs at once on the calling thread, after its
 * dependencies (waited for, helping, as pf_jobs_wait), and its id is
 * PF_JOB_NONE, which later jobs' deps and pf_jobs_wait take as finished.
 * Items write disjoint outputs, so the bytes are those of a scheduled run;
 * only the parallelism is lost. */
static pf_job_id pf__run_inline(pf_jobs *jobs, pf_job_fn fn, void *ctx, uint32_t count, const pf_job_id *deps,
                                uint32_t dep_count)
{
    for (uint32_t i = 0; i < dep_count; i++) pf_jobs_wait(jobs, deps[i]);
    const uint32_t worker = pf__self(jobs);
    pf__tls_depth++;
    for (uint32_t item = 0; item < count; item++) fn(ctx, item, worker);
    pf__tls_depth--;
    return PF_JOB_NONE;
}

void pf_jobs_test_fail_growth(pf_jobs *jobs, uint32_t times)
{
    pthread_mutex_lock(&jobs->mutex);
    jobs->fail_growth = times;
    pthread_mutex_unlock(&jobs->mutex);
}

pf_job_id pf_jobs_add(pf_jobs *jobs, pf_job_fn fn, void *ctx, uint32_t count, uint32_t grain,
                      const pf_job_id *deps, uint32_t dep_count)
{
    assert(fn || count == 0);
    assert(deps || dep_count == 0);
    const uint8_t auto_grain = grain == 0;
    if (grain == 0) {
        grain = count / (jobs->thread_count * PF__CHUNKS_PER_THREAD);
        if (grain == 0) grain = 1;
    }

    pthread_mutex_lock(&jobs->mutex);
    pf_job_id id = jobs->job_count;
    if (id == PF_JOB_NONE || (id == jobs->page_count * PF__PAGE_JOBS && !pf__grow_jobs(jobs)) ||
        !pf__reserve_edges(jobs, dep_count)) {
        pthread_mutex_unlock(&jobs->mutex);
        return pf__run_inline(jobs, fn, ctx, count, deps, dep_count);
    }
    jobs->job_count++;

    pf__job *job = pf__job_at(jobs, id);
    atomic_store_explicit(&job->next, 0, memory_order_relaxed);
    atomic_store_explicit(&job->done, 0, memory_order_relaxed);
    job->count = count;
    job->grain = grain;
    job->fn = fn;
    job->ctx = ctx;
    job->pending = 0;
    job->first_edge = PF__NO_EDGE;
    job->link = NULL;
    job->finished = 0;
    job->auto_grain = auto_grain;
    if (atomic_load_explicit(&jobs->profile, memory_order_relaxed)) {
        atomic_store_explicit(&job->prof_work_ns, 0, memory_order_relaxed);
        atomic_store_explicit(&job->prof_longest_ns, 0, memory_order_relaxed);
    }

    for (uint32_t i = 0; i < dep_count; i++) {
        pf_job_id dep = deps[i];
        if (dep == PF_JOB_NONE) continue;
        /* Deps must be earlier ids of this frame: that is what makes the
         * graph acyclic. */
        assert(dep < id);
        if (dep >= id) continue;
        pf__job *d = pf__job_at(jobs, dep);
        if (d->finished) continue;
        uint32_t e = jobs->edge_count++; /* reserved above */
        jobs->edges[e].job = id;
        jobs->edges[e].next = d->first_edge;
        d->first_edge = e;
        job->pending++;
    }

    if (job->pending == 0) {
        if (count == 0) {
            pf__finish(jobs, job);
        } else {
            jobs->ready[jobs->ready_tail++] = id;
            pf__wake(jobs, pf__chunk_count(job));
        }
    }
    pthread_mutex_unlock(&jobs->mutex);
    return id;
}

/* A wait of `ns` ended: inside an item, the item excludes it; outside any,
 * it is the external thread's parallel region, and `cpu0` its CPU time
 * when the wait began. Under the mutex. */
static void pf__profile_wait(pf_jobs *jobs, uint64_t ns, uint64_t cpu0)
{
    if (pf__tls_depth) pf__tls_excluded_ns += ns;
    else {
        jobs->prof_wait_ns += ns;
        jobs->prof_wait_cpu_ns += pf__cpu_ns() - cpu0;
    }
}

void pf_jobs_wait(pf_jobs *jobs, pf_job_id id)
{
    if (id == PF_JOB_NONE) return;
    uint32_t worker = pf__self(jobs);
    const int profile = atomic_load_explicit(&jobs->profile, memory_order_relaxed);
    uint64_t t0 = profile ? pf__ns() : 0, cpu0 = profile && !pf__tls_depth ? pf__cpu_ns() : 0;
    pthread_mutex_lock(&jobs->mutex);
    /* An id from before the last wait_all is stale; in release builds treat
     * ids past the end as finished rather than reading a missing page. */
    assert(id < jobs->job_count);
    if (id < jobs->job_count) {
        pf__job *job = pf__job_at(jobs, id);
        while (!job->finished) {
            if (pf__help(jobs, worker, job)) continue;
            jobs->sleeping_waiters++;
            pthread_cond_wait(&jobs->wait_cv, &jobs->mutex);
            jobs->sleeping_waiters--;
        }
    }
    if (profile) pf__profile_wait(jobs, pf__ns() - t0, cpu0);
    pthread_mutex_unlock(&jobs->mutex);
}

void pf_jobs_wait_all(pf_jobs *jobs)
{
    assert(pf__tls_depth == 0 && pf__tls_pool != jobs);
    uint32_t worker = jobs->thread_count - 1;
    const int profile = atomic_load_explicit(&jobs->profile, memory_order_relaxed);
    uint64_t t0 = profile ? pf__ns() : 0, cpu0 = profile && !pf__tls_depth ? pf__cpu_ns() : 0;
    pthread_mutex_lock(&jobs->mutex);
    /* Finished is not enough before ids recycle: a thread that just found a
     * job exhausted still holds its pointer (`active`) and will touch its
     * `next` counter once more. */
    while (jobs->finished_count < jobs->job_count || jobs->active) {
        if (pf__help(jobs, worker, NULL)) continue;
        jobs->sleeping_waiters++;
        pthread_cond_wait(&jobs->wait_cv, &jobs->mutex);
        jobs->sleeping_waiters--;
    }
    jobs->job_count = 0;
    jobs->finished_count = 0;
    jobs->ready_head = jobs->ready_tail = 0;
    jobs->edge_count = 0;
    if (profile) pf__profile_wait(jobs, pf__ns() - t0, cpu0);
    pthread_mutex_unlock(&jobs->mutex);
}

void pf_jobs_parallel_for(pf_jobs *jobs, pf_job_fn fn, void *ctx, uint32_t count, uint32_t grain)
{
    pf_jobs_wait(jobs, pf_jobs_add(jobs, fn, ctx, count, grain, NULL, 0));
}

uint32_t pf_jobs_core_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1) return 1;
    if (n > PF_JOBS_MAX_THREADS) return PF_JOBS_MAX_THREADS;
    return (uint32_t)n;
}

/* ---------------------------------------------------------------- profile */

void pf_jobs_profile_enable(pf_jobs *jobs, int on)
{
    pthread_mutex_lock(&jobs->mutex);
    atomic_store_explicit(&jobs->profile, on != 0, memory_order_relaxed);
    jobs->prof_wait_ns = jobs->prof_wait_cpu_ns = jobs->prof_work_ns = jobs->prof_span_ns = 0;
    jobs->prof_jobs = jobs->prof_items = 0;
    for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++) jobs->prof_predicted_ns[k] = 0.0;
    pthread_mutex_unlock(&jobs->mutex);
}

void pf_jobs_profile_read(pf_jobs *jobs, pf_jobs_profile *out)
{
    pthread_mutex_lock(&jobs->mutex);
    out->wait_ms = (double)jobs->prof_wait_ns * 1e-6;
    out->wait_cpu_ms = (double)jobs->prof_wait_cpu_ns * 1e-6;
    out->work_ms = (double)jobs->prof_work_ns * 1e-6;
    out->span_ms = (double)jobs->prof_span_ns * 1e-6;
    for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++) out->predicted_ms[k] = jobs->prof_predicted_ns[k] * 1e-6;
    out->jobs = jobs->prof_jobs;
    out->items = jobs->prof_items;
    pthread_mutex_unlock(&jobs->mutex);
}

pf_jobs_profile pf_jobs_profile_delta(const pf_jobs_profile *a, const pf_jobs_profile *b)
{
    pf_jobs_profile d;
    d.wait_ms = b->wait_ms - a->wait_ms;
    d.wait_cpu_ms = b->wait_cpu_ms - a->wait_cpu_ms;
    d.work_ms = b->work_ms - a->work_ms;
    d.span_ms = b->span_ms - a->span_ms;
    for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++) d.predicted_ms[k] = b->predicted_ms[k] - a->predicted_ms[k];
    d.jobs = b->jobs - a->jobs;
    d.items = b->items - a->items;
    return d;
}
