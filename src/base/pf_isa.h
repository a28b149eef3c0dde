/* pf_isa: which SIMD instruction set softgi and Embree use.
 *
 * Why it is an option: Embree's hit bits depend on its ISA (its triangle test
 * uses approximate reciprocals refined differently on SSE, AVX2 and
 * AVX-512), and softgi's own SIMD paths are chosen at run time. `--isa`
 * pins both, so golden images match on every CPU that has the pinned ISA:
 *
 *   --isa   Embree device config       softgi SIMD path
 *   auto    best the CPU has           best the CPU has (default, fastest)
 *   sse2    isa=sse2                   scalar
 *   sse4.2  isa=sse4.2                 scalar
 *   avx2    isa=avx2                   AVX2 (8-wide)
 *   avx512  isa=avx512                 AVX-512 (16-wide)
 *
 * The golden tests pin sse2, which every x86-64 CPU has. */
#ifndef PF_ISA_H
#define PF_ISA_H

#include "pf_result.h"

typedef enum pf_isa { PF_ISA_AUTO = 0, PF_ISA_SSE2, PF_ISA_SSE42, PF_ISA_AVX2, PF_ISA_AVX512 } pf_isa;

/* Parses "auto", "sse2", "sse4.2", "avx2", "avx512". */
pf_result pf_isa_parse(const char *s, pf_isa *out, pf_error *err);
const char *pf_isa_name(pf_isa isa);
/* The best ISA this CPU supports (never AUTO). */
pf_isa pf_isa_detect(void);
/* AUTO resolves to pf_isa_detect(); a pinned ISA the CPU lacks is an error. */
pf_result pf_isa_resolve(pf_isa want, pf_isa *out, pf_error *err);

#endif
