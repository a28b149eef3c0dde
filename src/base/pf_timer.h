/* pf_timer: monotonic wall-clock timing of frame stages. A pf_stage_times
 * records named stages in the order they ran, so `render` can print the
 * per-stage table a learner reads next to the paper's outline. Timings never
 * feed back into results (determinism). */
#ifndef PF_TIMER_H
#define PF_TIMER_H

#include <stdint.h>
#include <stdio.h>

#define PF_MAX_STAGES 32

typedef struct pf_stage_times {
    uint32_t count;
    const char *name[PF_MAX_STAGES]; /* static strings */
    double ms[PF_MAX_STAGES];
} pf_stage_times;

/* Seconds since an arbitrary fixed point (CLOCK_MONOTONIC). */
double pf_time_now(void);
/* Adds `ms` to the stage called `name` (appending it on first use). */
void pf_stage_add(pf_stage_times *t, const char *name, double ms);
/* A function told of every pf_stage_add this thread makes (name and ms),
 * after the table is updated: how `softgi bench` reads the job profile at
 * each stage boundary (pf_jobs.h) and how long commands draw progress,
 * without the frame knowing. Per thread, so a pipelined job adding a stage
 * on a worker does not call it; NULL (the default) turns it off. The
 * previous hook is returned so a caller can put it back. */
typedef void (*pf_stage_hook_fn)(void *user, const char *name, double ms);
typedef struct pf_stage_hook {
    pf_stage_hook_fn fn;
    void *user;
} pf_stage_hook;
pf_stage_hook pf_stage_hook_set(pf_stage_hook hook);

/* Prints "stage  ms" lines and a total. */
void pf_stage_print(const pf_stage_times *t, FILE *out);

/* The machine's CPU time counters (Linux /proc/stat, all CPUs, in clock
 * ticks), for benchmarks to report how much of a run the hypervisor took
 * away ("steal": time a virtual CPU wanted to run but the host ran something
 * else). valid = 0 where they cannot be read. */
typedef struct pf_cpu_ticks {
    int valid;
    uint64_t total, steal;
} pf_cpu_ticks;
pf_cpu_ticks pf_cpu_ticks_now(void);
/* Steal as a share of all CPU time between a and b (0..1), or -1 when
 * either sample is invalid or no time passed. */
double pf_cpu_steal_share(pf_cpu_ticks a, pf_cpu_ticks b);

#endif
