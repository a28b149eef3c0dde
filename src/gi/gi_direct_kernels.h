/* gi_direct_kernels: the shadow-mapped direct light's row (stage 2b),
 * written once over the SIMD vocabulary (src/base/simd/simd.h) in
 * gi_direct_kernels.c and compiled once per instruction set; gi_direct.c
 * picks the table of the frame's SIMD path. Private to gi_direct. */
#ifndef GI_DIRECT_KERNELS_H
#define GI_DIRECT_KERNELS_H

#include "gi_frame.h"

/* Irradiance at (pos, nrm) from the area lights' K emitter points, each
 * visible per its paraboloid map (scalar, every path; gi_direct.c). */
pf_vec3 gi__direct_area_irradiance(const gi_area_maps *m, pf_vec3 pos, pf_vec3 nrm);

typedef struct gi_direct_kernels {
    const char *isa; /* SIMD_NAME of the vocabulary it was compiled with */
    /* one row y of f->direct: a pf_jobs parallel-for body over rows */
    void (*row)(void *frame, uint32_t y, uint32_t worker);
} gi_direct_kernels;

extern const gi_direct_kernels gi_direct_kernels_scalar;
extern const gi_direct_kernels gi_direct_kernels_avx2;   /* x86 only */
extern const gi_direct_kernels gi_direct_kernels_avx512; /* x86 only */

#endif
