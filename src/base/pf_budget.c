/* pf_budget: the memory budget (see pf_budget.h). */
#include "pf_budget.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

uint64_t pf_budget_mul(uint64_t a, uint64_t b)
{
    if (a && b > UINT64_MAX / a) return UINT64_MAX;
    return a * b;
}

/* The first unsigned number in a small file, or 0 ("max" and unreadable
 * files give 0: no limit from there). */
static uint64_t pf__read_limit(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    char buf[64] = {0};
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(buf, &end, 10);
    if (end == buf || errno) return 0;
    return (uint64_t)v;
}

uint64_t pf_memory_machine(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    uint64_t mem = pages > 0 && page > 0 ? pf_budget_mul((uint64_t)pages, (uint64_t)page) : 0;
    const char *cgroups[2] = {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"};
    for (int i = 0; i < 2; i++) {
        uint64_t lim = pf__read_limit(cgroups[i]);
        if (lim && (mem == 0 || lim < mem)) mem = lim;
    }
    return mem ? mem : (uint64_t)1 << 30;
}

uint64_t pf_budget_default(void) { return pf_memory_machine() / 2; }

pf_result pf_budget_parse(const char *text, uint64_t *bytes, pf_error *err)
{
    char *end;
    errno = 0;
    double v = text ? strtod(text, &end) : 0.0;
    if (!text || end == text || errno || !isfinite(v) || v <= 0.0)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--max-memory '%s': expected a size such as 8G or 512M",
                            text ? text : "");
    double unit = 1.0;
    switch (*end) {
    case 'k': case 'K': unit = 1024.0; end++; break;
    case 'm': case 'M': unit = 1048576.0; end++; break;
    case 'g': case 'G': unit = 1073741824.0; end++; break;
    case 't': case 'T': unit = 1099511627776.0; end++; break;
    default: break;
    }
    if (*end == 'i' && unit > 1.0) end++; /* "GiB" */
    if (*end == 'B' || *end == 'b') end++;
    if (*end)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--max-memory '%s': expected a size such as 8G or 512M", text);
    double b = v * unit;
    if (b < 67108864.0) return pf_error_set(err, PF_ERR_ARGUMENT, "--max-memory '%s': at least 64M", text);
    *bytes = b >= 1.8e19 ? UINT64_MAX : (uint64_t)b;
    return PF_OK;
}

void pf_budget_init(pf_budget *b, uint64_t limit)
{
    b->limit = limit ? limit : pf_budget_default();
    b->used = 0;
}

static double pf__mib(uint64_t bytes) { return (double)bytes / 1048576.0; }

pf_result pf_budget_take(pf_budget *b, uint64_t bytes, const char *what, pf_error *err)
{
    uint64_t total = b->used + bytes < b->used ? UINT64_MAX : b->used + bytes;
    if (total > b->limit)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY,
                            "%s needs about %.0f MiB; with the %.0f MiB already planned that exceeds the memory "
                            "budget of %.0f MiB (--max-memory; the default is half of this machine's memory)",
                            what, pf__mib(bytes), pf__mib(b->used), pf__mib(b->limit));
    b->used = total;
    return PF_OK;
}

int pf_budget_warn(const pf_budget *b, const char *hint)
{
    uint64_t machine = pf_memory_machine();
    double share = (double)b->used / (double)machine;
    if (share < PF_BUDGET_WARN_SHARE) return 0;
    fprintf(stderr, "softgi: warning: this run will take about %.1f GiB, %.0f%% of this machine's %.1f GiB%s; %s\n",
            pf__mib(b->used) / 1024.0, 100.0 * share, pf__mib(machine) / 1024.0,
            share > 1.0 ? " (more than it has: it will swap or be killed)" : "", hint);
    return 1;
}
