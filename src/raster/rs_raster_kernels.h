/* rs_raster_kernels: the tile raster's per-pixel kernels, written once over
 * the SIMD vocabulary (src/base/simd/simd.h) in rs_raster_kernels.c and
 * compiled once per instruction set; rs_raster.c picks a table at run time
 * (rs_raster_kernels_for). Private to src/raster: the set-up triangle
 * record is shared by the setup (rs_raster.c) and the kernels.
 *
 * What every path computes for pixel i of a row (rs_raster.c "tile raster"):
 *   covered = e0 + i*step0 >= 0 && ... (exact integers)
 *   z = zrow + dzdx * (float)i, clamped to the vertices' range
 *   written iff covered && z > depth[i]
 * so every path gives the scalar path's bits. */
#ifndef RS_RASTER_KERNELS_H
#define RS_RASTER_KERNELS_H

#include <stddef.h>
#include <stdint.h>

#include "rs_raster.h"

#define RS_SUB 256 /* 1 << RS_SUBPIXEL_BITS */

/* A triangle after setup: what a tile needs to rasterize it, in 128 bytes
 * (two cache lines: the tile raster reads these records scattered over the
 * chunks, so their size is memory traffic). */
typedef struct rs__tri {
    /* E_k(px, py) = a px + b py + c (fixed point, fill rule folded into c);
     * |a|, |b| < 2^25 (snapped coordinates < 2^24), c up to 2^50 */
    int32_t a[3], b[3];
    int64_t c[3];
    /* depth plane, kept in double relative to vertex 0 so that clipped
     * vertices far out in the guard band do not cost precision through
     * cancellation: zs(x, y) = zv + dzdx (x + .5 - xv) + dzdy (y + .5 - yv) */
    double zv, xv, yv, dzdx_d, dzdy_d;
    float dzdx;                /* lane step within a row */
    float zmin, zmax;          /* clamp range (vertex zs), zmax also feeds hierarchical Z */
    int32_t x0, y0, x1, y1;    /* pixel bounding box, inclusive */
    uint32_t prim;
    uint32_t masked; /* alphaMode MASK: index into the chunk's rs__tri_masked (per-pixel alpha test,
                        scalar, all paths), RS__NOT_MASKED otherwise */
    uint32_t small;  /* edge functions vary by < 2^29 over an 8x8 block: 32-bit lanes are exact */
} rs__tri;
_Static_assert(sizeof(rs__tri) == 128, "rs__tri: two cache lines");

/* Depth at the centre of pixel (x, y) from the double plane, rounded once. */
static inline float rs__zrow(const rs__tri *t, int32_t x, int32_t y)
{
    return (float)(t->zv + t->dzdx_d * ((double)x + 0.5 - t->xv) + t->dzdy_d * ((double)y + 0.5 - t->yv));
}

/* One row of up to 8 pixels starting at (x, y): coverage of pixel centres
 * by the three edge functions, depth test (greater wins), write. `lanes`
 * masks pixels past the tile, image or bounding box. Returns 1 if any pixel
 * was written. e[k] = edge k at pixel (x, y); step[k] = edge k's increase
 * per pixel in x; zrow = depth at pixel (x, y) (rs__zrow). 64-bit lanes: any
 * triangle. */
typedef int (*rs__row_fn)(const rs__tri *t, int32_t x, int32_t y, float zrow, const int64_t e[3],
                          const int64_t step[3], unsigned lanes, float *depth, uint32_t *prim);

/* One 8-pixel-wide block, rows y0..y1, of one triangle; e_in = the edge
 * functions at (x, y0), depth and prim at (x, y0) with row stride `stride`.
 * "Small" triangles (edge functions vary by less than 2^29 over a block)
 * take 32-bit lanes, SIMD_W / 8 rows at a time; the others go row by row
 * through the row kernel. */
typedef int (*rs__block_fn)(const rs__tri *t, int32_t x, int32_t y0, int32_t y1, const int64_t e_in[3],
                            unsigned lanes, float *depth, uint32_t *prim, size_t stride);

/* One compiled kernel file: a table per instruction set. */
typedef struct rs_raster_kernels {
    const char *isa; /* SIMD_NAME of the vocabulary it was compiled with */
    rs__row_fn row;
    rs__block_fn block;
} rs_raster_kernels;

extern const rs_raster_kernels rs_raster_kernels_scalar;
extern const rs_raster_kernels rs_raster_kernels_avx2;   /* x86 only */
extern const rs_raster_kernels rs_raster_kernels_avx512; /* x86 only */

/* The table for a SIMD path (rs_raster.c). */
const rs_raster_kernels *rs_raster_kernels_for(rs_simd simd);

#endif
