/* rs_raster_kernels: the tile raster's row and block kernels, written once
 * over the SIMD vocabulary and compiled once per instruction set (see
 * rs_raster_kernels.h and docs/raster.md "The SIMD vocabulary"). CMake
 * compiles this file three times, each time naming the table it exports
 * with -DRS_RASTER_KERNELS=rs_raster_kernels_<isa>:
 *
 *   scalar   -DSIMD_FORCE_SCALAR            8 plain-C lanes (the reference)
 *   avx2     -mavx2                         8 lanes
 *   avx512   -mavx512f -mavx512dq ...bw ...vl   16 lanes = two rows of 8
 *
 * Lane l of a vector is column l & 7 of row l >> 3 of the block. */
#include "rs_raster_kernels.h"

#include "simd.h"

#ifndef RS_RASTER_KERNELS
#error "compile with -DRS_RASTER_KERNELS=<table name> (CMakeLists.txt)"
#endif

_Static_assert(SIMD_W % 8 == 0, "the raster kernels take whole rows of 8 pixels");
#define RS__ROWS (SIMD_W / 8) /* rows of 8 pixels per vector */

/* zb(row) + dzdx * column, clamped to the vertices' depth range: the
 * definition z < zmin ? zmin : (z > zmax ? zmax : z) for the non-NaN depths
 * of a set-up triangle (zmin <= zmax); the one difference, -0 against
 * zmin = +0, gives a zero that fails the depth test (depth > 0 or cleared
 * to +0) either way */
static inline simd_f rs__depths(const rs__tri *t, simd_f zb, simd_f colf)
{
    simd_f z = simd_add_f(zb, simd_mul_f(simd_set1_f(t->dzdx), colf));
    return simd_max_f(simd_min_f(z, simd_set1_f(t->zmax)), simd_set1_f(t->zmin));
}

/* The row kernel: coverage in exact 64-bit lanes (SIMD_WL at a time), then
 * the depth test of the row's 8 pixels in the vector's first row. */
static int rs__row(const rs__tri *t, int32_t x, int32_t y, float zrow, const int64_t e[3], const int64_t step[3],
                   unsigned lanes, float *depth, uint32_t *prim)
{
    (void)x, (void)y;
    uint32_t neg = 0;
    for (int c = 0; c < 8; c += SIMD_WL) {
        simd_l acc = simd_set1_l(0);
        for (int k = 0; k < 3; k++) acc = simd_or_l(acc, simd_ramp_l(e[k] + step[k] * c, step[k]));
        neg |= simd_negative_l(acc) << c;
    }
    uint32_t covered = ~neg & lanes & 0xffu;
    if (!covered) return 0;
    simd_mask cov = simd_mask_from_bits(covered);
    simd_f colf = simd_i2f(simd_and_i(simd_iota_i(), simd_set1_i(7)));
    simd_f z = rs__depths(t, simd_set1_f(zrow), colf);
    simd_f old = simd_maskz_loadu_rows8_f(depth, 0, cov);
    simd_mask pass = simd_mask_and(simd_gt_f(z, old), cov);
    if (!simd_mask_any(pass)) return 0;
    simd_mask_storeu_rows8_f(depth, 0, pass, z);
    if (prim) simd_mask_storeu_rows8_i((int32_t *)prim, 0, pass, simd_set1_i((int32_t)t->prim));
    return 1;
}

/* A block row by row with the row kernel: triangles too large for 32-bit
 * lanes. */
static int rs__block_rows(const rs__tri *t, int32_t x, int32_t y0, int32_t y1, const int64_t e_in[3], unsigned lanes,
                          float *depth, uint32_t *prim, size_t stride)
{
    int64_t e[3] = {e_in[0], e_in[1], e_in[2]}, step[3];
    for (int k = 0; k < 3; k++) step[k] = (int64_t)t->a[k] * RS_SUB;
    int wrote = 0;
    for (int32_t y = y0; y <= y1; y++) {
        size_t o = (size_t)(y - y0) * stride;
        wrote |= rs__row(t, x, y, rs__zrow(t, x, y), e, step, lanes, depth + o, prim ? prim + o : NULL);
        for (int k = 0; k < 3; k++) e[k] += (int64_t)t->b[k] * RS_SUB;
    }
    return wrote;
}

/* int64 edge value -> int32 lane start: a value above 2^30 stays positive
 * over the block (it varies by less than 2^29), and one below -2^30 cannot
 * occur (such a block was rejected before) */
static inline int32_t rs__clamp32(int64_t v) { return v > ((int64_t)1 << 30) ? (int32_t)1 << 30 : (int32_t)v; }

/* The block kernel: small triangles in 32-bit lanes, RS__ROWS rows of 8
 * pixels per step; every lane holds the exact sign of its edge functions. */
static int rs__block(const rs__tri *t, int32_t x, int32_t y0, int32_t y1, const int64_t e_in[3], unsigned lanes,
                     float *depth, uint32_t *prim, size_t stride)
{
    if (!t->small) return rs__block_rows(t, x, y0, y1, e_in, lanes, depth, prim, stride);
    const simd_i lane = simd_iota_i();
    const simd_i col = simd_and_i(lane, simd_set1_i(7)), row = simd_srli_i(lane, 3);
    const simd_f colf = simd_i2f(col);
    simd_i ev[3], sy[3];
    for (int k = 0; k < 3; k++) {
        int32_t sxk = (int32_t)((int64_t)t->a[k] * RS_SUB), syk = (int32_t)((int64_t)t->b[k] * RS_SUB);
        ev[k] = simd_add_i(simd_set1_i(rs__clamp32(e_in[k])),
                           simd_add_i(simd_mullo_i(col, simd_set1_i(sxk)), simd_mullo_i(row, simd_set1_i(syk))));
        sy[k] = simd_set1_i(RS__ROWS * syk);
    }
    /* the lanes of every row, and of the first row only (the last step when
     * the block has an odd number of rows and a vector holds two) */
    uint32_t lanes_all = 0;
    for (int r = 0; r < RS__ROWS; r++) lanes_all |= (lanes & 0xffu) << (8 * r);
    const simd_mask valid_all = simd_mask_from_bits(lanes_all), valid_one = simd_mask_from_bits(lanes & 0xffu);
    int wrote = 0;
    for (int32_t y = y0; y <= y1; y += RS__ROWS) {
        int rows = y1 - y + 1 < RS__ROWS ? (int)(y1 - y + 1) : RS__ROWS;
        simd_mask valid = rows == RS__ROWS ? valid_all : valid_one;
        simd_i any = simd_or_i(simd_or_i(ev[0], ev[1]), ev[2]);
        simd_mask cov = simd_mask_andnot(valid, simd_negative_i(any));
        for (int k = 0; k < 3; k++) ev[k] = simd_add_i(ev[k], sy[k]);
        if (!simd_mask_any(cov)) continue;
        float zr[RS__ROWS];
        for (int r = 0; r < RS__ROWS; r++) zr[r] = rs__zrow(t, x, r < rows ? y + r : y);
        simd_f z = rs__depths(t, simd_set_rows8_f(zr), colf);
        size_t o = (size_t)(y - y0) * stride;
        simd_f old = simd_maskz_loadu_rows8_f(depth + o, stride, cov);
        simd_mask pass = simd_mask_and(simd_gt_f(z, old), cov);
        if (!simd_mask_any(pass)) continue;
        simd_mask_storeu_rows8_f(depth + o, stride, pass, z);
        if (prim) simd_mask_storeu_rows8_i((int32_t *)prim + o, stride, pass, simd_set1_i((int32_t)t->prim));
        wrote = 1;
    }
    return wrote;
}

const rs_raster_kernels RS_RASTER_KERNELS = {SIMD_NAME, rs__row, rs__block};
