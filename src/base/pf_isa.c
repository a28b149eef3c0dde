/* pf_isa: ISA names, CPU detection and pinning (see pf_isa.h). */
#include "pf_isa.h"

#include "simd_arch.h"

#include <string.h>

static const char *const pf__isa_names[] = {"auto", "sse2", "sse4.2", "avx2", "avx512"};

pf_result pf_isa_parse(const char *s, pf_isa *out, pf_error *err)
{
    for (int i = 0; i < (int)(sizeof pf__isa_names / sizeof pf__isa_names[0]); i++)
        if (strcmp(s, pf__isa_names[i]) == 0) {
            *out = (pf_isa)i;
            return PF_OK;
        }
    return pf_error_set(err, PF_ERR_ARGUMENT, "--isa '%s': expected auto, sse2, sse4.2, avx2 or avx512", s);
}

const char *pf_isa_name(pf_isa isa)
{
    return (unsigned)isa < sizeof pf__isa_names / sizeof pf__isa_names[0] ? pf__isa_names[isa] : "?";
}

pf_isa pf_isa_detect(void)
{
#if SIMD_X86
    __builtin_cpu_init();
    /* Embree's AVX-512 path needs F, DQ, CD, BW and VL (Skylake-X). */
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512vl"))
        return PF_ISA_AVX512;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2"))
        return PF_ISA_AVX2;
    if (__builtin_cpu_supports("sse4.2")) return PF_ISA_SSE42;
#endif
    return PF_ISA_SSE2;
}

pf_result pf_isa_resolve(pf_isa want, pf_isa *out, pf_error *err)
{
    pf_isa best = pf_isa_detect();
    if (want == PF_ISA_AUTO) {
        *out = best;
        return PF_OK;
    }
    if (want > best)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--isa %s: this CPU supports at most %s", pf_isa_name(want),
                            pf_isa_name(best));
    *out = want;
    return PF_OK;
}
