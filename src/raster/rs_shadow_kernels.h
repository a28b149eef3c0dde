/* rs_shadow_kernels: the shadow maps' PCF lookup (rs_shadow_lookup.h)
 * compiled once per instruction set in rs_shadow_kernels.c; rs_shadow.c
 * picks a table at run time (rs_shadow_kernels_for). Private to
 * src/raster. */
#ifndef RS_SHADOW_KERNELS_H
#define RS_SHADOW_KERNELS_H

#include "rs_shadow.h"

#define RS_SHADOW_MAX_LANES 16

typedef struct rs_shadow_kernels {
    const char *isa; /* SIMD_NAME of the vocabulary it was compiled with */
    uint32_t lanes;  /* SIMD_W: the points of one visibility call */
    /* rs_shadow_visibility of `lanes` points (arrays of `lanes`), for the
     * lanes of `active` (0 in the others); the map must be
     * rs_shadow_lookup_eligible */
    void (*visibility)(const rs_shadow_map *m, const float *px, const float *py, const float *pz, const float *ngx,
                       const float *ngy, const float *ngz, unsigned active, float *out);
} rs_shadow_kernels;

extern const rs_shadow_kernels rs_shadow_kernels_scalar;
extern const rs_shadow_kernels rs_shadow_kernels_avx2;   /* x86 only */
extern const rs_shadow_kernels rs_shadow_kernels_avx512; /* x86 only */

const rs_shadow_kernels *rs_shadow_kernels_for(rs_simd simd);

#endif
