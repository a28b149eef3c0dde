/* test_jobs: unit tests of the job system (pf_jobs.h). Every multi-threaded
 * test runs with 1, 2 and 7 threads and checks its outputs against a serial
 * reference, so a job that runs before its dependencies, twice, or not at
 * all shows up as a wrong value (and as a data race under ThreadSanitizer).
 * Checks inside jobs only count failures into atomics: cmocka's asserts
 * longjmp and must run on the test's own thread. */
#define _POSIX_C_SOURCE 200809L

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "pf_fpenv.h"
#include "pf_jobs.h"
#include "pf_math.h"
#include "pf_timer.h"

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

static const uint32_t thread_counts[] = {1, 2, 7};
#define THREAD_CONFIGS (sizeof thread_counts / sizeof thread_counts[0])

static uint64_t splitmix64(uint64_t *state) { return pf_mix64(*state += 0x9e3779b97f4a7c15ull); }

/* Order-sensitive mix: results differ if inputs are read in another order
 * or before they were written. */
static uint64_t mix(uint64_t h, uint64_t v)
{
    h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h *= 0xff51afd7ed558ccdull;
    return h ^ (h >> 33);
}

/* Keeps a job busy for a while so that jobs added after it find it still
 * running. */
static void spin(uint32_t iterations)
{
    volatile uint32_t sink = 0;
    for (uint32_t i = 0; i < iterations; i++) sink += i;
    (void)sink;
}

static pf_jobs *create_jobs(uint32_t thread_count)
{
    pf_jobs *jobs = pf_jobs_create(thread_count);
    assert_non_null(jobs);
    assert_int_equal(pf_jobs_thread_count(jobs), thread_count);
    return jobs;
}

/* ------------------------------------------------------------ random DAG */

#define DAG_JOBS 5000
#define DAG_MAX_DEPS 5
#define DAG_MAX_ITEMS 4
#define DAG_NONE 0xffffffffu

typedef struct dag dag;
typedef struct dag_job {
    dag *g;
    uint32_t index;
} dag_job;

struct dag {
    uint32_t count[DAG_JOBS];
    uint32_t grain[DAG_JOBS];
    uint32_t dep_count[DAG_JOBS];
    uint32_t deps[DAG_JOBS][DAG_MAX_DEPS]; /* job indices, or DAG_NONE */
    uint32_t offset[DAG_JOBS];             /* first output of each job */
    uint32_t wait_every;                   /* 0, or pf_jobs_wait on a recent job every so many adds */
    dag_job ctx[DAG_JOBS];
    pf_job_id ids[DAG_JOBS];
    uint64_t *out;
    uint32_t thread_count;
    atomic_uint bad_worker;
};

/* A dependency's value: all its items' outputs, or, for a count-0 job (no
 * outputs), the values of its own deps, which the count-0 job must also have
 * waited for. */
static uint64_t dag_read(const dag *g, uint32_t d, uint64_t h)
{
    if (g->count[d] == 0) {
        for (uint32_t k = 0; k < g->dep_count[d]; k++)
            if (g->deps[d][k] != DAG_NONE) h = dag_read(g, g->deps[d][k], h);
        return mix(h, d);
    }
    for (uint32_t u = 0; u < g->count[d]; u++) h = mix(h, g->out[g->offset[d] + u]);
    return h;
}

static void dag_item(void *ctx, uint32_t item, uint32_t worker)
{
    dag_job *job = ctx;
    dag *g = job->g;
    uint32_t i = job->index;
    if (worker >= g->thread_count) atomic_fetch_add(&g->bad_worker, 1);
    uint64_t h = mix((uint64_t)i * 16 + item, 12345);
    for (uint32_t k = 0; k < g->dep_count[i]; k++)
        if (g->deps[i][k] != DAG_NONE) h = dag_read(g, g->deps[i][k], h);
    g->out[g->offset[i] + item] = h;
}

static dag *dag_build(uint64_t seed)
{
    dag *g = calloc(1, sizeof *g);
    assert_non_null(g);
    uint64_t rng = seed;
    uint32_t total = 0;
    for (uint32_t i = 0; i < DAG_JOBS; i++) {
        uint64_t r = splitmix64(&rng);
        g->count[i] = r % 10 == 0 ? 0 : 1 + (uint32_t)((r >> 8) % DAG_MAX_ITEMS);
        g->grain[i] = (uint32_t)((r >> 16) % 3); /* 0 = let pf_jobs choose */
        uint32_t n = (uint32_t)((r >> 24) % (DAG_MAX_DEPS + 1));
        if (n > i) n = i;
        g->dep_count[i] = n;
        for (uint32_t k = 0; k < n; k++) {
            uint64_t s = splitmix64(&rng);
            if (s % 8 == 0)
                g->deps[i][k] = DAG_NONE;
            else if (s & 8) /* a recent job: most likely still running */
                g->deps[i][k] = i - 1 - (uint32_t)((s >> 8) % (i < 16 ? i : 16));
            else
                g->deps[i][k] = (uint32_t)((s >> 8) % i);
        }
        g->offset[i] = total;
        total += g->count[i];
        g->ctx[i].g = g;
        g->ctx[i].index = i;
    }
    g->out = malloc((size_t)total * sizeof *g->out);
    assert_non_null(g->out);
    return g;
}

static uint32_t dag_total(const dag *g)
{
    return g->offset[DAG_JOBS - 1] + g->count[DAG_JOBS - 1];
}

static void dag_run_serial(dag *g)
{
    g->thread_count = 1;
    for (uint32_t i = 0; i < DAG_JOBS; i++)
        for (uint32_t t = 0; t < g->count[i]; t++) dag_item(&g->ctx[i], t, 0);
}

static void dag_run(dag *g, pf_jobs *jobs)
{
    g->thread_count = pf_jobs_thread_count(jobs);
    for (uint32_t i = 0; i < DAG_JOBS; i++) {
        pf_job_id deps[DAG_MAX_DEPS];
        for (uint32_t k = 0; k < g->dep_count[i]; k++)
            deps[k] = g->deps[i][k] == DAG_NONE ? PF_JOB_NONE : g->ids[g->deps[i][k]];
        g->ids[i] = pf_jobs_add(jobs, dag_item, &g->ctx[i], g->count[i], g->grain[i], deps, g->dep_count[i]);
        /* Waiting now and then makes later jobs depend on finished ones. */
        if (g->wait_every && i % g->wait_every == g->wait_every - 1) pf_jobs_wait(jobs, g->ids[i - 7]);
    }
    pf_jobs_wait_all(jobs);
}

static void check_dag(uint64_t seed, uint32_t wait_every)
{
    dag *g = dag_build(seed);
    g->wait_every = wait_every;
    size_t bytes = (size_t)dag_total(g) * sizeof *g->out;
    dag_run_serial(g);
    uint64_t *reference = malloc(bytes);
    assert_non_null(reference);
    memcpy(reference, g->out, bytes);

    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        pf_jobs *jobs = create_jobs(thread_counts[c]);
        memset(g->out, 0xab, bytes);
        atomic_store(&g->bad_worker, 0);
        dag_run(g, jobs);
        assert_int_equal(atomic_load(&g->bad_worker), 0);
        assert_memory_equal(g->out, reference, bytes);
        /* Again on the same pool: ids recycled by wait_all. */
        memset(g->out, 0xcd, bytes);
        dag_run(g, jobs);
        assert_memory_equal(g->out, reference, bytes);
        pf_jobs_destroy(jobs);
    }
    free(reference);
    free(g->out);
    free(g);
}

static void test_dag_matches_serial(void **state)
{
    (void)state;
    check_dag(1, 0);
    check_dag(0x5eed, 0);
}

static void test_dag_with_waits_matches_serial(void **state)
{
    (void)state;
    check_dag(42, 97);
}

/* ------------------------------------------------------------ parallel-for */

#define PFOR_ITEMS 100000u

typedef struct pfor {
    double *out;
    uint32_t thread_count;
    pthread_t caller;
    atomic_uint bad_worker;
    atomic_uint per_worker[8];
} pfor;

static double pfor_value(uint32_t i)
{
    double x = (double)i * 0.001;
    return ((x * 0.5 - 1.25) * x + 3.0) * x - 7.0 / (1.0 + x);
}

static void pfor_item(void *ctx, uint32_t item, uint32_t worker)
{
    pfor *p = ctx;
    /* The calling thread is always the last index; workers the others. */
    int is_caller = pthread_equal(pthread_self(), p->caller);
    if (worker >= p->thread_count || (is_caller != 0) != (worker == p->thread_count - 1))
        atomic_fetch_add(&p->bad_worker, 1);
    else
        atomic_fetch_add_explicit(&p->per_worker[worker], 1, memory_order_relaxed);
    p->out[item] = pfor_value(item);
}

static void test_parallel_for_100k(void **state)
{
    (void)state;
    double *reference = malloc(PFOR_ITEMS * sizeof *reference);
    pfor p = {.out = malloc(PFOR_ITEMS * sizeof *p.out), .caller = pthread_self()};
    assert_non_null(reference);
    assert_non_null(p.out);
    for (uint32_t i = 0; i < PFOR_ITEMS; i++) reference[i] = pfor_value(i);

    const uint32_t grains[] = {0, 1, 7, 4096, PFOR_ITEMS * 2};
    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        pf_jobs *jobs = create_jobs(thread_counts[c]);
        p.thread_count = thread_counts[c];
        for (uint32_t g = 0; g < sizeof grains / sizeof grains[0]; g++) {
            memset(p.out, 0, PFOR_ITEMS * sizeof *p.out);
            atomic_store(&p.bad_worker, 0);
            for (uint32_t w = 0; w < 8; w++) atomic_store(&p.per_worker[w], 0);
            pf_jobs_parallel_for(jobs, pfor_item, &p, PFOR_ITEMS, grains[g]);
            assert_int_equal(atomic_load(&p.bad_worker), 0);
            assert_memory_equal(p.out, reference, PFOR_ITEMS * sizeof *p.out);
            uint32_t items = 0;
            for (uint32_t w = 0; w < 8; w++) items += atomic_load(&p.per_worker[w]);
            assert_int_equal(items, PFOR_ITEMS); /* every item exactly once */
        }
        pf_jobs_wait_all(jobs);
        pf_jobs_destroy(jobs);
    }
    free(p.out);
    free(reference);
}

/* ------------------------------------------------------------ worker indices */

/* Per-worker scratch is only safe if no two threads ever run with the same
 * index at once, and one index always means one thread. */
typedef struct index_check {
    uint32_t thread_count;
    atomic_int in_use[PF_JOBS_MAX_THREADS];
    pthread_mutex_t mutex;
    pthread_t owner[PF_JOBS_MAX_THREADS];
    int owned[PF_JOBS_MAX_THREADS];
    atomic_uint errors;
    atomic_uint items;
} index_check;

static void index_item(void *ctx, uint32_t item, uint32_t worker)
{
    index_check *c = ctx;
    if (worker >= c->thread_count) {
        atomic_fetch_add(&c->errors, 1);
        return;
    }
    if (atomic_exchange(&c->in_use[worker], 1)) atomic_fetch_add(&c->errors, 1);
    pthread_mutex_lock(&c->mutex);
    if (!c->owned[worker]) {
        c->owned[worker] = 1;
        c->owner[worker] = pthread_self();
    } else if (!pthread_equal(c->owner[worker], pthread_self())) {
        atomic_fetch_add(&c->errors, 1);
    }
    pthread_mutex_unlock(&c->mutex);
    spin(200 + item % 7 * 100);
    atomic_store(&c->in_use[worker], 0);
    atomic_fetch_add(&c->items, 1);
}

static void test_worker_indices_in_range(void **state)
{
    (void)state;
    const uint32_t counts[] = {1, 2, 3, 7, 16};
    for (uint32_t t = 0; t < sizeof counts / sizeof counts[0]; t++) {
        index_check *c = calloc(1, sizeof *c);
        assert_non_null(c);
        assert_int_equal(pthread_mutex_init(&c->mutex, NULL), 0);
        c->thread_count = counts[t];
        pf_jobs *jobs = create_jobs(counts[t]);
        pf_job_id prev = PF_JOB_NONE;
        for (uint32_t j = 0; j < 40; j++) prev = pf_jobs_add(jobs, index_item, c, 50, 1 + j % 3, &prev, j % 2);
        pf_jobs_wait_all(jobs);
        assert_int_equal(atomic_load(&c->errors), 0);
        assert_int_equal(atomic_load(&c->items), 40 * 50);
        /* The caller (this thread) is index thread_count-1 whenever it ran. */
        uint32_t last = counts[t] - 1;
        if (c->owned[last]) assert_true(pthread_equal(c->owner[last], pthread_self()));
        for (uint32_t w = 0; w < last; w++)
            if (c->owned[w]) assert_false(pthread_equal(c->owner[w], pthread_self()));
        pf_jobs_destroy(jobs);
        pthread_mutex_destroy(&c->mutex);
        free(c);
    }
}

/* ------------------------------------------------------------ jobs adding jobs */

#define TREE_FANOUT 4u
#define TREE_DEPTH 4u
#define TREE_NODES (1u + 4u + 16u + 64u + 256u) /* complete 4-ary tree of depth 4 */

typedef struct tree tree;
typedef struct tree_node {
    tree *t;
    uint32_t index;
} tree_node;

struct tree {
    pf_jobs *jobs;
    tree_node node[TREE_NODES];
    uint64_t value[TREE_NODES];
    uint64_t sum[TREE_NODES]; /* of the children's values, by a job that depends on them */
    atomic_uint visits[TREE_NODES];
    atomic_uint sums_done[TREE_NODES];
};

static uint32_t tree_depth(uint32_t n)
{
    uint32_t d = 0;
    while (n) {
        n = (n - 1) / TREE_FANOUT;
        d++;
    }
    return d;
}

static uint64_t tree_value(uint32_t n, uint64_t parent_value)
{
    return mix(parent_value, n);
}

static void tree_sum_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    tree_node *node = ctx;
    tree *t = node->t;
    uint64_t h = 0;
    for (uint32_t k = 1; k <= TREE_FANOUT; k++) h = mix(h, t->value[node->index * TREE_FANOUT + k]);
    t->sum[node->index] = h;
    atomic_fetch_add(&t->sums_done[node->index], 1);
}

static void tree_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    tree_node *node = ctx;
    tree *t = node->t;
    uint32_t n = node->index;
    uint64_t parent = n ? t->value[(n - 1) / TREE_FANOUT] : 7;
    t->value[n] = tree_value(n, parent);
    atomic_fetch_add(&t->visits[n], 1);
    if (tree_depth(n) >= TREE_DEPTH) return;
    pf_job_id children[TREE_FANOUT];
    for (uint32_t k = 0; k < TREE_FANOUT; k++) {
        uint32_t child = n * TREE_FANOUT + 1 + k;
        children[k] = pf_jobs_add(t->jobs, tree_item, &t->node[child], 1, 1, NULL, 0);
    }
    /* A job added from inside a job, depending on jobs that may still run. */
    pf_jobs_add(t->jobs, tree_sum_item, node, 1, 1, children, TREE_FANOUT);
}

static void test_jobs_add_jobs(void **state)
{
    (void)state;
    tree *ref = calloc(1, sizeof *ref);
    assert_non_null(ref);
    for (uint32_t n = 0; n < TREE_NODES; n++)
        ref->value[n] = tree_value(n, n ? ref->value[(n - 1) / TREE_FANOUT] : 7);
    for (uint32_t n = 0; n * TREE_FANOUT + TREE_FANOUT < TREE_NODES; n++) {
        uint64_t h = 0;
        for (uint32_t k = 1; k <= TREE_FANOUT; k++) h = mix(h, ref->value[n * TREE_FANOUT + k]);
        ref->sum[n] = h;
    }

    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        tree *t = calloc(1, sizeof *t);
        assert_non_null(t);
        t->jobs = create_jobs(thread_counts[c]);
        for (uint32_t n = 0; n < TREE_NODES; n++) t->node[n] = (tree_node){t, n};
        for (int frame = 0; frame < 3; frame++) {
            for (uint32_t n = 0; n < TREE_NODES; n++) {
                atomic_store(&t->visits[n], 0);
                atomic_store(&t->sums_done[n], 0);
            }
            memset(t->value, 0, sizeof t->value);
            memset(t->sum, 0, sizeof t->sum);
            pf_jobs_add(t->jobs, tree_item, &t->node[0], 1, 1, NULL, 0);
            pf_jobs_wait_all(t->jobs); /* must also wait for the jobs the jobs added */
            for (uint32_t n = 0; n < TREE_NODES; n++) {
                assert_int_equal(atomic_load(&t->visits[n]), 1);
                int inner = tree_depth(n) < TREE_DEPTH;
                assert_int_equal(atomic_load(&t->sums_done[n]), inner ? 1 : 0);
            }
            assert_memory_equal(t->value, ref->value, sizeof t->value);
            assert_memory_equal(t->sum, ref->sum, sizeof t->sum);
        }
        pf_jobs_destroy(t->jobs);
        free(t);
    }
    free(ref);
}

/* ------------------------------------------------------------ wait inside a job */

#define OUTER_ITEMS 12u
#define INNER_ITEMS 600u

typedef struct nested {
    pf_jobs *jobs;
    uint32_t thread_count;
    uint64_t inner[OUTER_ITEMS][INNER_ITEMS];
    uint64_t outer[OUTER_ITEMS];
    atomic_uint bad_worker;
} nested;

typedef struct inner_ctx {
    nested *n;
    uint32_t outer;
} inner_ctx;

static void inner_item(void *ctx, uint32_t item, uint32_t worker)
{
    inner_ctx *c = ctx;
    if (worker >= c->n->thread_count) atomic_fetch_add(&c->n->bad_worker, 1);
    if (item % 64 == 0) spin(2000);
    c->n->inner[c->outer][item] = mix(c->outer, item);
}

static void spin_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)ctx;
    (void)item;
    (void)worker;
    spin(20000);
}

static uint64_t outer_reduce(const uint64_t *values)
{
    uint64_t h = 0;
    for (uint32_t k = 0; k < INNER_ITEMS; k++) h = mix(h, values[k]);
    return h;
}

static void outer_item(void *ctx, uint32_t item, uint32_t worker)
{
    nested *n = ctx;
    uint32_t before = worker;
    inner_ctx c = {n, item};
    /* Half wait by id on a job with an unfinished dep, half through
     * pf_jobs_parallel_for; both must help rather than block. */
    if (item % 2) {
        pf_job_id gate = pf_jobs_add(n->jobs, spin_item, NULL, 1, 1, NULL, 0);
        pf_job_id id = pf_jobs_add(n->jobs, inner_item, &c, INNER_ITEMS, 16, &gate, 1);
        pf_jobs_wait(n->jobs, id);
    } else {
        pf_jobs_parallel_for(n->jobs, inner_item, &c, INNER_ITEMS, 16);
    }
    if (worker != before || worker >= n->thread_count) atomic_fetch_add(&n->bad_worker, 1);
    n->outer[item] = outer_reduce(n->inner[item]);
}

static void test_wait_inside_job(void **state)
{
    (void)state;
    uint64_t reference[OUTER_ITEMS];
    for (uint32_t i = 0; i < OUTER_ITEMS; i++) {
        uint64_t values[INNER_ITEMS];
        for (uint32_t k = 0; k < INNER_ITEMS; k++) values[k] = mix(i, k);
        reference[i] = outer_reduce(values);
    }
    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        nested *n = calloc(1, sizeof *n);
        assert_non_null(n);
        n->jobs = create_jobs(thread_counts[c]);
        n->thread_count = thread_counts[c];
        for (int rep = 0; rep < 3; rep++) {
            memset(n->outer, 0, sizeof n->outer);
            pf_job_id outer = pf_jobs_add(n->jobs, outer_item, n, OUTER_ITEMS, 1, NULL, 0);
            pf_jobs_wait(n->jobs, outer);
            assert_memory_equal(n->outer, reference, sizeof reference);
            pf_jobs_wait_all(n->jobs);
        }
        assert_int_equal(atomic_load(&n->bad_worker), 0);
        pf_jobs_destroy(n->jobs);
        free(n);
    }
}

/* ------------------------------------------------------------ count 0 */

typedef struct slot {
    uint64_t value;
    uint64_t copy;
    atomic_uint calls;
} slot;

static void slow_write_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    slot *s = ctx;
    spin(20000);
    s->value = 0x1234567890abcdefull;
    atomic_fetch_add(&s->calls, 1);
}

static void copy_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    slot *s = ctx;
    s->copy = s->value;
    atomic_fetch_add(&s->calls, 1);
}

static void never_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    atomic_fetch_add(&((slot *)ctx)->calls, 1000);
}

static void test_count_zero_jobs(void **state)
{
    (void)state;
    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        pf_jobs *jobs = create_jobs(thread_counts[c]);

        /* No deps: finished at once; the body is never called. */
        slot empty = {0};
        pf_job_id z = pf_jobs_add(jobs, never_item, &empty, 0, 0, NULL, 0);
        pf_jobs_wait(jobs, z);
        pf_jobs_parallel_for(jobs, never_item, &empty, 0, 0);
        pf_jobs_add(jobs, NULL, NULL, 0, 0, NULL, 0);
        assert_int_equal(atomic_load(&empty.calls), 0);

        /* A count-0 job between a slow writer and a reader must order them. */
        for (int rep = 0; rep < 20; rep++) {
            slot s = {0};
            pf_job_id a = pf_jobs_add(jobs, slow_write_item, &s, 1, 1, NULL, 0);
            pf_job_id barrier = pf_jobs_add(jobs, never_item, &s, 0, 0, &a, 1);
            pf_job_id b = pf_jobs_add(jobs, copy_item, &s, 1, 1, &barrier, 1);
            pf_jobs_wait(jobs, barrier);
            assert_int_equal(s.value, 0x1234567890abcdefull); /* the barrier finished after its dep */
            pf_jobs_wait(jobs, b);
            assert_int_equal(s.copy, 0x1234567890abcdefull);
            assert_int_equal(atomic_load(&s.calls), 2);
        }

        /* A long chain of count-0 jobs cascades when its head finishes. */
        slot s = {0};
        pf_job_id prev = pf_jobs_add(jobs, slow_write_item, &s, 1, 1, NULL, 0);
        for (int i = 0; i < 20000; i++) prev = pf_jobs_add(jobs, never_item, &s, 0, 0, &prev, 1);
        pf_job_id last = pf_jobs_add(jobs, copy_item, &s, 1, 1, &prev, 1);
        pf_jobs_wait(jobs, last);
        assert_int_equal(s.copy, 0x1234567890abcdefull);
        assert_int_equal(atomic_load(&s.calls), 2);
        pf_jobs_wait_all(jobs);
        pf_jobs_destroy(jobs);
    }
}

/* ------------------------------------------------------------ finished deps */

static void test_deps_on_finished_jobs(void **state)
{
    (void)state;
    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        pf_jobs *jobs = create_jobs(thread_counts[c]);
        slot s = {0};
        pf_job_id a = pf_jobs_add(jobs, slow_write_item, &s, 1, 1, NULL, 0);
        pf_jobs_wait(jobs, a);
        pf_jobs_wait(jobs, a); /* twice is fine */
        pf_jobs_wait(jobs, PF_JOB_NONE);

        /* Finished, NONE and a repeated dep: runs once, after a. */
        pf_job_id deps[] = {a, PF_JOB_NONE, a};
        pf_job_id b = pf_jobs_add(jobs, copy_item, &s, 1, 1, deps, 3);
        pf_jobs_wait(jobs, b);
        assert_int_equal(s.copy, 0x1234567890abcdefull);
        assert_int_equal(atomic_load(&s.calls), 2);

        /* Only NONE deps: ready at once. */
        slot t = {.value = 99};
        pf_job_id nones[] = {PF_JOB_NONE, PF_JOB_NONE};
        pf_jobs_wait(jobs, pf_jobs_add(jobs, copy_item, &t, 1, 1, nones, 2));
        assert_int_equal(t.copy, 99);

        /* A mix of a finished and an unfinished dep waits for the latter. */
        slot u = {0};
        pf_job_id slow = pf_jobs_add(jobs, slow_write_item, &u, 1, 1, NULL, 0);
        pf_job_id mixed[] = {a, slow, b};
        pf_job_id d = pf_jobs_add(jobs, copy_item, &u, 1, 1, mixed, 3);
        pf_jobs_wait(jobs, d);
        assert_int_equal(u.copy, 0x1234567890abcdefull);
        pf_jobs_wait_all(jobs);
        pf_jobs_destroy(jobs);
    }
}

/* Out of memory for the bookkeeping: the job runs at once on the caller,
 * after its deps, and its id is PF_JOB_NONE (no abort); the pool goes on. */
static void count_item(void *ctx, uint32_t item, uint32_t worker);
static void test_add_without_memory(void **state)
{
    (void)state;
    for (uint32_t c = 0; c < THREAD_CONFIGS; c++) {
        pf_jobs *jobs = create_jobs(thread_counts[c]);
        /* a dependency edge cannot be had: b waits for a inline */
        slot s = {0};
        pf_job_id a = pf_jobs_add(jobs, slow_write_item, &s, 1, 1, NULL, 0);
        pf_jobs_test_fail_growth(jobs, 1);
        pf_job_id b = pf_jobs_add(jobs, copy_item, &s, 1, 1, &a, 1);
        assert_int_equal(b, PF_JOB_NONE);
        assert_int_equal(s.copy, 0x1234567890abcdefull); /* done when add returned, after a */
        pf_jobs_wait(jobs, b);
        /* a job page cannot be had: the first add that needs one runs inline */
        atomic_uint n = 0;
        pf_jobs_test_fail_growth(jobs, 1);
        uint32_t added = 0, inline_runs = 0;
        for (; added < 1u << 17 && !inline_runs; added++) {
            pf_job_id id = pf_jobs_add(jobs, count_item, &n, 3, 1, NULL, 0);
            if (id == PF_JOB_NONE) {
                inline_runs++;
                assert_true(atomic_load(&n) >= 3); /* its items ran before add returned */
            }
        }
        assert_int_equal(inline_runs, 1);
        pf_job_id after = pf_jobs_add(jobs, count_item, &n, 5, 1, &b, 1); /* a NONE dep: ready at once */
        assert_int_not_equal(after, PF_JOB_NONE);
        pf_jobs_wait_all(jobs);
        assert_int_equal(atomic_load(&n), 3 * added + 5);
        pf_jobs_destroy(jobs);
    }
}

/* ------------------------------------------------------------ create/destroy */

static void count_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    atomic_fetch_add_explicit((atomic_uint *)ctx, 1, memory_order_relaxed);
}

static void test_create_destroy_many(void **state)
{
    (void)state;
    for (uint32_t i = 0; i < 150; i++) {
        uint32_t threads = 1 + i % 8;
        pf_jobs *jobs = create_jobs(threads);
        atomic_uint calls = 0;
        uint32_t expected = 0;
        if (i % 5 != 0) { /* every fifth pool is destroyed unused */
            pf_job_id prev = PF_JOB_NONE;
            for (uint32_t j = 0; j < 10; j++) {
                prev = pf_jobs_add(jobs, count_item, &calls, 1 + j, 0, &prev, 1);
                expected += 1 + j;
            }
            if (i % 2) { /* the others are destroyed with jobs still queued */
                pf_jobs_wait_all(jobs);
                assert_int_equal(atomic_load(&calls), expected);
            }
        }
        pf_jobs_destroy(jobs); /* runs what is left, then joins */
        assert_int_equal(atomic_load(&calls), expected);
    }
    pf_jobs_destroy(NULL);
}

/* ------------------------------------------------------------ wait_all + reuse */

typedef struct frame_job {
    uint64_t *values;
    uint32_t index;
} frame_job;

static void chain_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    (void)worker;
    frame_job *f = ctx;
    f->values[f->index] = mix(f->index ? f->values[f->index - 1] : 1, f->index);
}

#define FRAME_JOBS 20000u

static void test_wait_all_then_reuse(void **state)
{
    (void)state;
    uint64_t *values = malloc(FRAME_JOBS * sizeof *values);
    uint64_t *reference = malloc(FRAME_JOBS * sizeof *reference);
    frame_job *ctx = malloc(FRAME_JOBS * sizeof *ctx);
    assert_non_null(values);
    assert_non_null(reference);
    assert_non_null(ctx);
    for (uint32_t i = 0; i < FRAME_JOBS; i++) {
        reference[i] = mix(i ? reference[i - 1] : 1, i);
        ctx[i] = (frame_job){values, i};
    }
    pf_jobs *jobs = create_jobs(3);
    pf_job_id first_id = PF_JOB_NONE;
    for (int frame = 0; frame < 12; frame++) {
        /* Frame 0 has 20k jobs (far past any small fixed limit), the others
         * fewer, with every job depending on the one before it. */
        uint32_t n = frame == 0 ? FRAME_JOBS : 300 + (uint32_t)frame * 50;
        memset(values, 0, FRAME_JOBS * sizeof *values);
        pf_job_id prev = PF_JOB_NONE;
        for (uint32_t i = 0; i < n; i++) {
            prev = pf_jobs_add(jobs, chain_item, &ctx[i], 1, 1, &prev, 1);
            if (i == 0) {
                if (frame == 0) first_id = prev;
                assert_int_equal(prev, first_id); /* ids recycle at wait_all */
            }
        }
        pf_jobs_wait_all(jobs);
        assert_memory_equal(values, reference, n * sizeof *values);
        pf_jobs_wait_all(jobs); /* with nothing to do */
    }
    pf_jobs_destroy(jobs);
    free(ctx);
    free(reference);
    free(values);
}

/* ------------------------------------------------------------ misc */

#if defined(__x86_64__) || defined(__i386__)
typedef struct fpenv_check {
    uint32_t thread_count;
    atomic_uint worker_items, errors;
} fpenv_check;

static void fpenv_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item;
    fpenv_check *c = ctx;
    if (worker + 1 == c->thread_count) {
        /* The caller's MXCSR is the caller's business. Hold it back (up to
         * ~5 s) until a worker has run an item, so that on a loaded or
         * single-core machine the check still sees at least one worker. */
        for (int i = 0; i < 5000 && atomic_load(&c->worker_items) == 0; i++)
            nanosleep(&(struct timespec){.tv_nsec = 1000000}, NULL);
        return;
    }
    unsigned csr = _mm_getcsr();
    if (!(csr & 0x8000u) || !(csr & 0x0040u)) atomic_fetch_add(&c->errors, 1); /* FTZ, DAZ */
    atomic_fetch_add(&c->worker_items, 1);
}
#endif

static void test_workers_set_fpenv(void **state)
{
    (void)state;
#if defined(__x86_64__) || defined(__i386__)
    fpenv_check c = {.thread_count = 4};
    pf_jobs *jobs = create_jobs(c.thread_count);
    pf_jobs_parallel_for(jobs, fpenv_item, &c, 64, 1);
    assert_int_equal(atomic_load(&c.errors), 0);
    assert_true(atomic_load(&c.worker_items) > 0); /* the check did look at workers */
    pf_jobs_destroy(jobs);
#else
    skip();
#endif
}

static void test_core_count(void **state)
{
    (void)state;
    uint32_t n = pf_jobs_core_count();
    assert_true(n >= 1 && n <= PF_JOBS_MAX_THREADS);
}

/* pf_timer's CPU tick counters, which `bench` uses (like the core count) to
 * describe the machine: the share arithmetic, the invalid cases, and on
 * Linux a real sample that only grows. */
static void test_cpu_steal_share(void **state)
{
    (void)state;
    pf_cpu_ticks a = {1, 1000, 10}, b = {1, 3000, 210}, bad = {0, 5000, 500};
    assert_true(pf_cpu_steal_share(a, b) == 0.1);
    assert_true(pf_cpu_steal_share(a, a) == -1.0);   /* no time passed */
    assert_true(pf_cpu_steal_share(b, a) == -1.0);   /* backwards */
    assert_true(pf_cpu_steal_share(a, bad) == -1.0); /* unreadable */
    assert_true(pf_cpu_steal_share(bad, b) == -1.0);
#ifdef __linux__
    pf_cpu_ticks t0 = pf_cpu_ticks_now();
    assert_true(t0.valid && t0.total > 0 && t0.steal <= t0.total);
    volatile double x = 0.0;
    for (int i = 0; i < 20000000; i++) x += 1e-9 * i; /* let a few clock ticks pass */
    pf_cpu_ticks t1 = pf_cpu_ticks_now();
    assert_true(t1.valid && t1.total >= t0.total && t1.steal >= t0.steal);
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dag_matches_serial),
        cmocka_unit_test(test_dag_with_waits_matches_serial),
        cmocka_unit_test(test_parallel_for_100k),
        cmocka_unit_test(test_worker_indices_in_range),
        cmocka_unit_test(test_jobs_add_jobs),
        cmocka_unit_test(test_wait_inside_job),
        cmocka_unit_test(test_count_zero_jobs),
        cmocka_unit_test(test_deps_on_finished_jobs),
        cmocka_unit_test(test_add_without_memory),
        cmocka_unit_test(test_create_destroy_many),
        cmocka_unit_test(test_wait_all_then_reuse),
        cmocka_unit_test(test_workers_set_fpenv),
        cmocka_unit_test(test_core_count),
        cmocka_unit_test(test_cpu_steal_share),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
