/* rs_raster_kernels: the tile raster's per-pixel kernels, written once over
 * the SIMD vocabulary (src/base/simd/simd.h) in rs_raster_kernels.c and
 * compiled once per instruction set; rs_raster.c picks a table at run time
 * (rs_raster_kernels_for). Private to src/raster: the set-up triangle
 * record is shared by the setup (rs_raster.c) and the kernels.
 *
 * What every path computes per pixel is written at rs__tile_in: exact
 * integers for coverage and one float expression for depth, so every path
 * gives the scalar path's bits. */
#ifndef RS_RASTER_KERNELS_H
#define RS_RASTER_KERNELS_H

#include <stddef.h>
#include <stdint.h>

#include "rs_raster.h"

#define RS__NOT_MASKED 0xffffffffu
#define RS_SUB 256 /* 1 << RS_SUBPIXEL_BITS */

/* A triangle after setup: what a tile needs to rasterize it, in 128 bytes
 * (two cache lines: the tile raster reads these records scattered over the
 * chunks, so their size is memory traffic). */
typedef struct rs__tri {
    /* E_k(px, py) = a px + b py + c in subpixels (fixed point, fill rule
     * folded into c); |a|, |b| < 2^25 (snapped coordinates < 2^24), c up to
     * 2^50. A small triangle (flags & RS__SMALL) keeps, instead of c, c32 =
     * E_k at the centre of its bounding box's first pixel (x0, y0): every
     * value the kernels take over the box (and 8 pixels around it) then
     * fits 32 bits: E_k(x, y) = c32 + 256 a (x - x0) + 256 b (y - y0). */
    int32_t a[3], b[3];
    union {
        int64_t c[3];
        int32_t c32[3];
    };
    /* depth plane, kept in double relative to vertex 0 so that clipped
     * vertices far out in the guard band do not cost precision through
     * cancellation: zs(x, y) = zv + dzdx (x + .5 - xv) + dzdy (y + .5 - yv) */
    double zv, xv, yv, dzdx_d, dzdy_d;
    float zmin, zmax;       /* clamp range (vertex zs) */
    int32_t x0, y0, x1, y1; /* pixel bounding box, inclusive, inside the target */
    uint32_t prim;
    uint32_t masked; /* alphaMode MASK: index into the chunk's rs__tri_masked (per-pixel alpha test,
                        scalar, all paths), RS__NOT_MASKED otherwise */
    uint32_t flags;  /* RS__SMALL */
} rs__tri;
_Static_assert(sizeof(rs__tri) <= 128, "rs__tri: two cache lines");
#define RS__SMALL 1u
/* The margin (pixels) around a small triangle's box within which its 32-bit
 * edge values are guaranteed: the kernels' stamps start up to 3 pixels
 * before the box and their walks step up to one stamp past it. */
#define RS__SMALL_MARGIN 8

/* A small triangle's 32-bit edge values (rs__tri.c32, RS__SMALL): when
 * every value over its pixel box [x0, x1] x [y0, y1] widened by
 * RS__SMALL_MARGIN pixels on each side lies in (-2^31, 2^31), c (exact, 64
 * bits) is replaced by its values at the box's first pixel centre. Bounds
 * in exact integers: |E(ref)| + |256 a| (w + margin) + |256 b| (h + margin).
 * The setup calls it once a, b, c and the box are set. */
static inline void rs__tri_classify(rs__tri *r)
{
    int64_t e[3], pxr = (int64_t)r->x0 * RS_SUB + RS_SUB / 2, pyr = (int64_t)r->y0 * RS_SUB + RS_SUB / 2;
    int64_t w = (int64_t)r->x1 - r->x0 + RS__SMALL_MARGIN, h = (int64_t)r->y1 - r->y0 + RS__SMALL_MARGIN;
    r->flags &= ~RS__SMALL;
    for (int k = 0; k < 3; k++) {
        e[k] = r->a[k] * pxr + r->b[k] * pyr + r->c[k];
        int64_t a = (int64_t)r->a[k] * RS_SUB, b = (int64_t)r->b[k] * RS_SUB;
        a = a < 0 ? -a : a, b = b < 0 ? -b : b;
        if ((e[k] < 0 ? -e[k] : e[k]) + a * w + b * h >= INT32_MAX || a >= ((int64_t)1 << 28) ||
            b >= ((int64_t)1 << 28))
            return;
    }
    r->flags |= RS__SMALL;
    for (int k = 0; k < 3; k++) r->c32[k] = (int32_t)e[k];
}

/* The tile raster's buffers (rs_raster.c): RS_TILE x RS_TILE pixels in
 * stamps of RS_STAMP_W x stamp_h pixels (stamp_h = SIMD_W / RS_STAMP_W of
 * the kernel's instruction set: 4 on AVX-512, 2 on AVX2 and the scalar
 * path), each stamp's pixels contiguous (lane l = column l % RS_STAMP_W of
 * row l / RS_STAMP_W), stamps row by row: stamp (sx, sy) at
 * (sy * RS_TILE / RS_STAMP_W + sx) * SIMD_W. One vector load or store is
 * one stamp. */
#define RS_STAMP_W 4
#define RS_STAMPS_X (RS_TILE / RS_STAMP_W)

/* The alpha test of a masked triangle at pixel (x, y) (image coordinates):
 * 1 if the texel's alpha keeps the pixel. `masked` is the triangle's alpha
 * record (rs__tile_in.masked). The same scalar function on every path. */
typedef int (*rs__alpha_fn)(const void *ctx, const void *masked, const rs__tri *t, int32_t x, int32_t y);

/* One tile's work, filled by the tile loop (rs_raster.c rs__raster_tile):
 * its triangles in drawing order and the tile buffer. For each triangle the
 * kernel takes the rectangle of whole stamps around the triangle's bounding
 * box inside the tile and, per pixel of it,
 *   covered = E0 >= 0 && E1 >= 0 && E2 >= 0, the edge functions at the
 *             pixel centre (exact: in 32-bit lanes where every value over
 *             the rectangle fits, else rebased per stamp in 64 bits);
 *   z = (zt + dzdx * (float)(x - x0)) + dzdy * (float)(y - y0), clamped to
 *       [zmin, zmax], where (x0, y0) is the tile's first pixel, zt the
 *       double plane at its centre rounded once, dzdx and dzdy the plane's
 *       slopes rounded to float (no FMA);
 * and writes depth (greater wins) and, where `prim` is not NULL, the
 * triangle id; `coverage` (tests only, may be NULL) counts every covered
 * pixel before the depth test. */
typedef struct rs__tile_in {
    const rs__tri *const *tris;
    const void *const *masked; /* per triangle: its alpha record, NULL unless t->masked != RS__NOT_MASKED */
    uint32_t count;
    int32_t x0, y0;     /* the tile's first pixel (image coordinates) */
    int32_t xlim, ylim; /* tile-relative pixels at or beyond these are outside the image */
    rs__alpha_fn alpha;
    const void *alpha_ctx;
    float *depth;       /* the tile buffer, in stamp order */
    uint32_t *prim;     /* may be NULL */
    uint32_t *coverage; /* may be NULL */
} rs__tile_in;

typedef void (*rs__tile_fn)(const rs__tile_in *in);

/* One compiled kernel file: a table per instruction set. */
typedef struct rs_raster_kernels {
    const char *isa;  /* SIMD_NAME of the vocabulary it was compiled with */
    uint32_t stamp_h; /* rows of a stamp: SIMD_W / RS_STAMP_W */
    rs__tile_fn tile;
} rs_raster_kernels;

extern const rs_raster_kernels rs_raster_kernels_scalar;
extern const rs_raster_kernels rs_raster_kernels_avx2;   /* x86 only */
extern const rs_raster_kernels rs_raster_kernels_avx512; /* x86 only */

/* The table for a SIMD path (rs_raster.c). */
const rs_raster_kernels *rs_raster_kernels_for(rs_simd simd);

#endif
