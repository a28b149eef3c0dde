/* gi_importance_kernels: Eq. 2's sum over the camera points for SIMD_W RSM
 * texels at a time (Barak 2013 Sec. 4.1; gi_importance.c is the reference),
 * written once over the SIMD vocabulary and compiled once per instruction
 * set (-DGI_IMPORTANCE_KERNELS=gi_importance_kernels_<isa>; docs/raster.md
 * "The SIMD vocabulary"). */
#ifndef GI_IMPORTANCE_KERNELS_H
#define GI_IMPORTANCE_KERNELS_H

#include <stdint.h>

/* The camera points x_k (count of them) and the clamp of G. */
typedef struct gi_importance_in {
    const float *x, *y, *z, *nx, *ny, *nz, *alb;
    uint32_t count;
    float g_max;
} gi_importance_in;

typedef struct gi_importance_kernels {
    const char *isa;
    uint32_t width; /* texels per call */
    /* sum[l] = the sum over the camera points of albedo_k G for the texel
     * at (px[l], py[l], pz[l]) with normal (vx[l], vy[l], vz[l]), l <
     * width, in gi__importance_row's order (8 partial sums, k mod 8, added
     * as a fixed tree) */
    void (*texels)(const gi_importance_in *in, const float *px, const float *py, const float *pz, const float *vx,
                   const float *vy, const float *vz, float *sum);
} gi_importance_kernels;

extern const gi_importance_kernels gi_importance_kernels_scalar;
extern const gi_importance_kernels gi_importance_kernels_avx2;   /* x86 only */
extern const gi_importance_kernels gi_importance_kernels_avx512; /* x86 only */

#endif
