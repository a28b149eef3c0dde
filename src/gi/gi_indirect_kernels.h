/* gi_indirect_kernels: the many-light accumulation (step 7) and Laine's box
 * filter (step 9), written once over the SIMD vocabulary
 * (src/base/simd/simd.h) in gi_indirect_kernels.c and compiled once per
 * instruction set; gi_indirect.c picks the table of the frame's SIMD path
 * (the AVX2 or AVX-512 one; the scalar path keeps its per-pixel loops, the
 * reference the tables are tested against). Private to gi_indirect. */
#ifndef GI_INDIRECT_KERNELS_H
#define GI_INDIRECT_KERNELS_H

#include "gi_frame.h"

/* Runs of `width` pixels processed together: at most this many per call. */
#define GI_ACC_GROUPS 32

typedef struct gi_indirect_kernels {
    const char *isa;  /* SIMD_NAME of the vocabulary it was compiled with */
    uint32_t width;   /* SIMD_W: pixels per run */
    /* `groups` runs of `width` consecutive tile pixels (split planes at px..nz)
     * against the VPLs assign[a0..a1) with their paraboloid maps (exact or
     * ISMs): e[3 width g + 3 i + c] gets the unweighted sum of run g, lane i,
     * colour c, each pixel adding its VPLs in the tile's order. */
    void (*accumulate)(const gi_indirect *ind, const float *px, const float *py, const float *pz, const float *nx,
                       const float *ny, const float *nz, uint32_t groups, uint32_t a0, uint32_t a1, float *e);
    /* Laine's box filter for `width` interior pixels x.. of row y of the
     * indirect image (every window pixel on screen horizontally), reading
     * the G-buffer g and combined; out gets 3 floats a pixel. */
    void (*filter_box)(const gi_indirect *ind, const rs_gbuffer *g, int x, int y, float *out);
} gi_indirect_kernels;

extern const gi_indirect_kernels gi_indirect_kernels_scalar;
extern const gi_indirect_kernels gi_indirect_kernels_avx2;   /* x86 only */
extern const gi_indirect_kernels gi_indirect_kernels_avx512; /* x86 only */

#endif
