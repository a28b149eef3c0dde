/* pf_timer: monotonic clock and the per-stage timing table (pf_timer.h). */
#define _POSIX_C_SOURCE 199309L
#include "pf_timer.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

double pf_time_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static _Thread_local pf_stage_hook pf__hook;

pf_stage_hook pf_stage_hook_set(pf_stage_hook hook)
{
    pf_stage_hook old = pf__hook;
    pf__hook = hook;
    return old;
}

void pf_stage_add(pf_stage_times *t, const char *name, double ms)
{
    uint32_t i = 0;
    while (i < t->count && strcmp(t->name[i], name) != 0) i++;
    if (i < t->count) t->ms[i] += ms;
    else if (t->count < PF_MAX_STAGES) {
        t->name[t->count] = name;
        t->ms[t->count] = ms;
        t->count++;
    }
    if (pf__hook.fn) pf__hook.fn(pf__hook.user, name, ms);
}

void pf_stage_print(const pf_stage_times *t, FILE *out)
{
    double total = 0.0;
    for (uint32_t i = 0; i < t->count; i++) {
        fprintf(out, "  %-28s %10.2f ms\n", t->name[i], t->ms[i]);
        total += t->ms[i];
    }
    fprintf(out, "  %-28s %10.2f ms\n", "total", total);
}

pf_cpu_ticks pf_cpu_ticks_now(void)
{
    pf_cpu_ticks t = {0, 0, 0};
    FILE *f = fopen("/proc/stat", "r");
    if (!f) return t;
    /* cpu  user nice system idle iowait irq softirq steal guest guest_nice
     * (guest time is already counted in user) */
    unsigned long long v[8] = {0};
    int n = fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                   &v[7]);
    fclose(f);
    if (n != 8) return t;
    for (int i = 0; i < 8; i++) t.total += v[i];
    t.steal = v[7];
    t.valid = 1;
    return t;
}

double pf_cpu_steal_share(pf_cpu_ticks a, pf_cpu_ticks b)
{
    if (!a.valid || !b.valid || b.total <= a.total || b.steal < a.steal) return -1.0;
    return (double)(b.steal - a.steal) / (double)(b.total - a.total);
}
