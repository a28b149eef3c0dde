/* pf_jobs: the job system. A fixed pool of worker threads runs a small task
 * graph per frame: each job is a parallel-for over `count` items (count 1 for
 * a plain task) that may start only once the jobs it depends on have
 * finished.
 *
 * Determinism contract (what keeps softgi's output bit-exact for any thread
 * count): items are claimed dynamically, so *which* worker runs an item is
 * not fixed, but every item must write only its own disjoint outputs and may
 * use per-worker scratch only as scratch. Reductions are done by the caller
 * afterwards, in item order. Nothing in this module gives results that
 * depend on scheduling.
 *
 * Threads: `thread_count` counts the calling thread. pf_jobs_create(1)
 * starts no worker threads and runs everything on the caller inside
 * pf_jobs_wait. The waiting thread always helps run ready jobs, so waiting
 * never idles a core. Every worker sets FTZ/DAZ the same way (pf_fpenv.h).
 *
 * Lifetimes: a job id is valid until the next pf_jobs_wait_all (ids are
 * frame-lifetime). */
#ifndef PF_JOBS_H
#define PF_JOBS_H

#include <stdint.h>

typedef struct pf_jobs pf_jobs;

/* A job's body, called once per item. `worker` is in [0, thread_count) and
 * names the per-worker scratch the item may use: worker threads are
 * 0 .. thread_count-2, the external thread that waits (the frame loop) is
 * thread_count-1. So only one external thread may call the wait functions
 * (and pf_jobs_parallel_for) at a time; jobs may wait from any worker. */
typedef void (*pf_job_fn)(void *ctx, uint32_t item, uint32_t worker);

typedef uint32_t pf_job_id;
#define PF_JOB_NONE 0xffffffffu

/* thread_count >= 1 (the CLI rejects 0 and values above PF_JOBS_MAX_THREADS).
 * Returns NULL only when the OS refuses threads or memory. */
#define PF_JOBS_MAX_THREADS 256
pf_jobs *pf_jobs_create(uint32_t thread_count);
/* Runs any jobs still queued (as pf_jobs_wait_all), then joins the threads. */
void pf_jobs_destroy(pf_jobs *jobs);
uint32_t pf_jobs_thread_count(const pf_jobs *jobs);

/* Adds a job of `count` items (count 0 is a no-op job that completes as soon
 * as its dependencies do) depending on deps[0..dep_count). Deps may be
 * PF_JOB_NONE (ignored) or ids of earlier jobs, finished or not. The job may
 * start running at once. Thread-safe: jobs may add jobs. `grain` items are
 * claimed at a time (0 = pick one that gives each thread several chunks). */
pf_job_id pf_jobs_add(pf_jobs *jobs, pf_job_fn fn, void *ctx, uint32_t count, uint32_t grain,
                      const pf_job_id *deps, uint32_t dep_count);

/* (pf_jobs_add never fails: when its bookkeeping cannot grow, out of
 * memory, it runs the job at once on the calling thread after its
 * dependencies and returns PF_JOB_NONE, which deps and the wait functions
 * take as finished.) For tests: the next `times` growths of the
 * bookkeeping fail as if memory were short. */
void pf_jobs_test_fail_growth(pf_jobs *jobs, uint32_t times);

/* Waits until job `id` has finished, running ready jobs meanwhile. From
 * inside a job this is safe when `id` does not depend, directly or not, on a
 * job that is already running (e.g. waiting for jobs the job just added). */
void pf_jobs_wait(pf_jobs *jobs, pf_job_id id);

/* Waits for every job added so far, then recycles job ids. Must be called from
 * outside any job (the frame loop), never from inside one. */
void pf_jobs_wait_all(pf_jobs *jobs);

/* Convenience: add a job with no dependencies and wait for it. */
void pf_jobs_parallel_for(pf_jobs *jobs, pf_job_fn fn, void *ctx, uint32_t count, uint32_t grain);

/* Number of cores the OS reports (the default for --threads). */
uint32_t pf_jobs_core_count(void);

/* ---------------------------------------------------------------- profile
 *
 * Where a frame's time goes between one thread and many (Amdahl's law), for
 * `softgi bench`. Off by default: then the only cost is one predictable
 * branch per chunk and per wait. On, every item is timed (two clock reads)
 * and each job, when it finishes, is folded into cumulative totals:
 *
 * - wait: the external thread's time inside top-level waits
 *   (pf_jobs_wait, pf_jobs_parallel_for, pf_jobs_wait_all called outside
 *   any job): the frame's parallel regions, in wall and in CPU time. The
 *   external thread's CPU time outside them is a stage's serial part
 *   (set-up, reductions, single-threaded code): CPU time, because on a
 *   loaded machine the wall clock also counts the time another process
 *   held the core;
 * - work: every item's time, summed over items and threads. An item that
 *   waits inside (nested jobs) counts without its waits, so nothing is
 *   counted twice. Items are timed by the wall clock, with the time their
 *   thread was not running taken off (pf_jobs.c, pf__run_profiled): CPU
 *   time, near enough;
 * - span: each job's longest item, summed over jobs: the parallel part's
 *   time on unlimited cores (load imbalance bounds it);
 * - predicted[k]: each job's time on pf_jobs_profile_cores[k] cores,
 *   summed over jobs: max(its longest item, ceil(C / N) chunks of its mean
 *   chunk time), where C is the chunk count that job would have with N
 *   threads (an explicit grain keeps its chunks; grain 0 makes about 4 per
 *   thread). Jobs are summed as if they ran one after the other, so jobs
 *   that overlap (the rasterizer's vertex and cull jobs) are predicted
 *   slightly long. Memory bandwidth shared by the cores is not modelled.
 *
 * A stage's time on N cores is then its serial part + predicted[N]; on 1
 * core serial + work. Timings never feed back into results: the output is
 * the same with the profile on or off. */
#define PF_JOBS_PROFILE_CORES 8
extern const uint32_t pf_jobs_profile_cores[PF_JOBS_PROFILE_CORES]; /* 1, 2, 4, 8, 16, 32, 64, 128 */

typedef struct pf_jobs_profile {
    double wait_ms;     /* top-level waits of the external thread */
    double wait_cpu_ms; /* its CPU time in them (items it ran) */
    double work_ms;  /* every item, summed */
    double span_ms;  /* longest item of each job, summed */
    double predicted_ms[PF_JOBS_PROFILE_CORES];
    uint64_t jobs, items; /* finished jobs (count > 0) and their items */
} pf_jobs_profile;

/* Turns the profile on or off (from the external thread, between frames:
 * no job running). Turning it on clears the totals. */
void pf_jobs_profile_enable(pf_jobs *jobs, int on);
/* The totals since pf_jobs_profile_enable (zeros when off). Jobs still
 * running are not in them yet. From the external thread. */
void pf_jobs_profile_read(pf_jobs *jobs, pf_jobs_profile *out);
/* b - a, field by field (what happened between two reads). */
pf_jobs_profile pf_jobs_profile_delta(const pf_jobs_profile *a, const pf_jobs_profile *b);

#endif
