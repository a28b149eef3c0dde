/* pf_timer: monotonic clock and the per-stage timing table (pf_timer.h). */
#define _POSIX_C_SOURCE 199309L
#include "pf_timer.h"

#include <string.h>
#include <time.h>

double pf_time_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

void pf_stage_add(pf_stage_times *t, const char *name, double ms)
{
    for (uint32_t i = 0; i < t->count; i++)
        if (strcmp(t->name[i], name) == 0) {
            t->ms[i] += ms;
            return;
        }
    if (t->count == PF_MAX_STAGES) return;
    t->name[t->count] = name;
    t->ms[t->count] = ms;
    t->count++;
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
