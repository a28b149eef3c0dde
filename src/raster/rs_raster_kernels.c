/* rs_raster_kernels: the tile raster, written once over the SIMD vocabulary
 * and compiled once per instruction set (see rs_raster_kernels.h and
 * docs/raster.md "The SIMD vocabulary"). CMake compiles this file three
 * times, each time naming the table it exports with
 * -DRS_RASTER_KERNELS=rs_raster_kernels_<isa>:
 *
 *   scalar   -DSIMD_FORCE_SCALAR            8 plain-C lanes (the reference)
 *   avx2     -mavx2                         8 lanes
 *   avx512   -mavx512f -mavx512dq ...bw ...vl   16 lanes
 *
 * One vector is one stamp of RS_STAMP_W x RS__SH pixels (4 x 4 on AVX-512,
 * 4 x 2 otherwise), stored contiguously in the tile buffer, so a stamp's
 * depth test is one load, one compare and one masked store. A triangle
 * walks the stamps of its bounding rectangle band by band (a band: one row
 * of stamps), each band cut to the stamps its edges can reach, with the
 * three edge functions stepped in 32-bit lanes (Pineda's incremental edge
 * functions, as Larrabee and Masked Occlusion Culling step them): exact
 * because every value over the rectangle is checked to fit or, for the few
 * large triangles where one does not, rebased per stamp in 64 bits.
 *
 * Every path computes, for each pixel, the same integers for coverage and
 * the same float expression for depth (rs_raster_kernels.h), so all give
 * the scalar path's bits. */
#include "rs_raster_kernels.h"

#include <math.h>
#include <string.h>

#include "simd.h"

#ifndef RS_RASTER_KERNELS
#error "compile with -DRS_RASTER_KERNELS=<table name> (CMakeLists.txt)"
#endif

_Static_assert(SIMD_W % RS_STAMP_W == 0 && SIMD_W / RS_STAMP_W <= 4, "a stamp is whole rows of 4 pixels");
#define RS__SH (SIMD_W / RS_STAMP_W) /* rows of a stamp */
#define RS__PREFETCH 4               /* triangle records fetched ahead of use */

/* What every triangle of a tile shares. */
typedef struct rs__tile_ctx {
    const rs__tile_in *in;
    simd_i col, row;   /* each lane's column and row in its stamp */
    simd_f colf, rowf; /* the same as floats */
    int partial;       /* the tile reaches past the image */
} rs__tile_ctx;

/* One triangle in the tile: the rectangle of stamps around its bounding
 * box and its edge values at the rectangle's first pixel. */
typedef struct rs__pair {
    const rs__tri *t;
    const void *masked;
    int64_t e[3];
    int32_t pa[3], pb[3];       /* the edges' steps per pixel, 256 a and 256 b (32-bit walks); 0 for an edge
                                   positive over the whole rectangle, dropped (e then 0) */
    uint32_t dropped;           /* bit k: edge k dropped */
    int32_t sx0, sx1, sy0, sy1; /* stamps, tile-relative, inclusive */
    simd_f zt, dzdx, dzdy, zmin, zmax;
    simd_i prim;
} rs__pair;

/* The depth test and write of stamp (sx, sy) for its covered lanes `cov`:
 * z = (zt + dzdx * fx) + dzdy * fy (fx, fy: tile-relative pixel, exact in
 * float; `zy` = dzdy * fy of the stamp's band), clamped to the vertices'
 * range (the definition z < zmin ? zmin : (z > zmax ? zmax : z) for the
 * non-NaN depths of a set-up triangle; the one difference, -0 against
 * zmin = +0, gives a zero that fails the depth test either way). */
static inline void rs__stamp(const rs__tile_ctx *c, const rs__pair *p, int32_t sx, int32_t sy, simd_f zy,
                             simd_mask cov)
{
    const rs__tile_in *in = c->in;
    size_t o = ((size_t)sy * RS_STAMPS_X + (size_t)sx) * SIMD_W;
    if (in->coverage) {
        uint32_t bits = simd_mask_bits(cov);
        for (int l = 0; l < SIMD_W; l++) in->coverage[o + (size_t)l] += bits >> l & 1;
    }
    simd_f fx = simd_add_f(c->colf, simd_set1_f((float)(sx * RS_STAMP_W)));
    simd_f z = simd_add_f(simd_add_f(p->zt, simd_mul_f(p->dzdx, fx)), zy);
    z = simd_max_f(simd_min_f(z, p->zmax), p->zmin);
    simd_f old = simd_load_f(in->depth + o);
    simd_mask pass = simd_mask_and(simd_gt_f(z, old), cov);
    if (p->masked) {
        uint32_t bits = simd_mask_bits(pass);
        for (int l = 0; l < SIMD_W; l++)
            if (bits >> l & 1 &&
                !in->alpha(in->alpha_ctx, p->masked, p->t, in->x0 + sx * RS_STAMP_W + (l & 3), in->y0 + sy * RS__SH + (l >> 2)))
                bits &= ~(1u << l);
        if (!bits) return;
        pass = simd_mask_from_bits(bits);
    }
    /* no branch on the depth test (it mispredicts often: an empty stamp
     * costs less) and whole-vector stores of the blend rather than masked
     * stores, so the next triangle's load of the stamp is forwarded */
    simd_store_f(in->depth + o, simd_select_f(pass, z, old));
    if (in->prim) {
        int32_t *q = (int32_t *)in->prim + o;
        simd_store_i(q, simd_select_i(pass, p->prim, simd_load_i(q)));
    }
}

/* dzdy * fy for the stamps of band sy */
static inline simd_f rs__zy(const rs__tile_ctx *c, const rs__pair *p, int32_t sy)
{
    return simd_mul_f(p->dzdy, simd_add_f(c->rowf, simd_set1_f((float)(sy * RS__SH))));
}

/* Lanes of stamp (sx, sy) inside the image (tiles on its right and bottom
 * edges only). */
static inline simd_mask rs__inside(const rs__tile_ctx *c, int32_t sx, int32_t sy, simd_mask cov)
{
    if (!c->partial) return cov;
    return simd_mask_and(cov, simd_mask_and(simd_gt_i(simd_set1_i(c->in->xlim - sx * RS_STAMP_W), c->col),
                                            simd_gt_i(simd_set1_i(c->in->ylim - sy * RS__SH), c->row)));
}

/* Which stamps of each band can hold a covered pixel. An edge with a > 0
 * bounds x from below on every pixel row, x >= -(e + b y) / a (a < 0: from
 * above), a line in y, so over a band the bound is the line at the band's
 * first or last row, and from band to band it moves by a fixed step: one
 * add per edge and band. In double with a margin (RS__BAND_MARGIN):
 * conservative, the exact test decides. Cuts the empty stamps of a thin or slanted
 * triangle's bounding rectangle. */
/* The bounds' margin (pixels) against their rounding: the line bound and
 * its steps are computed in double from integers below 2^32, so over the
 * at most RS_TILE / RS__SH bands of a tile its error stays below 2^-16
 * pixel; 1/64 pixel is ample (a margin of a whole pixel, until 2026-12-03,
 * visited an extra stamp at a band's end a quarter of the time). */
#define RS__BAND_MARGIN (1.0 / 64.0)

typedef struct rs__bands {
    double lb[3], dlb[3], rb[3], drb[3]; /* lower / upper x bound of the current band per edge, step per band */
    double xmax;                         /* the rectangle's last pixel column (rectangle-relative) */
} rs__bands;

static void rs__bands_init(rs__bands *b, const rs__pair *p, const int32_t ax[3], const int32_t by[3])
{
    b->xmax = (double)((p->sx1 - p->sx0 + 1) * RS_STAMP_W - 1);
    for (int k = 0; k < 3; k++) {
        b->lb[k] = -INFINITY, b->rb[k] = INFINITY, b->dlb[k] = b->drb[k] = 0.0;
        if (!ax[k]) continue;
        double pa = (double)ax[k], pb = (double)by[k], e = (double)p->e[k];
        double slope = -pb / pa; /* dx/dy of the bound */
        if (ax[k] > 0) { /* lower bound: the band's smallest, at its first row if the bound grows */
            double dy = slope < 0.0 ? RS__SH - 1 : 0;
            b->lb[k] = -(e + pb * dy) / pa, b->dlb[k] = slope * RS__SH;
        } else {
            double dy = slope > 0.0 ? RS__SH - 1 : 0;
            b->rb[k] = -(e + pb * dy) / pa, b->drb[k] = slope * RS__SH;
        }
    }
}

/* The current band's stamps [*lo, *hi] (rectangle-relative; empty if
 * lo > hi), then the bounds step to the next band. */
static inline void rs__bands_next(rs__bands *b, int32_t *lo, int32_t *hi)
{
    double l = b->lb[0] > b->lb[1] ? b->lb[0] : b->lb[1], r = b->rb[0] < b->rb[1] ? b->rb[0] : b->rb[1];
    l = (l > b->lb[2] ? l : b->lb[2]) - RS__BAND_MARGIN;
    r = (r < b->rb[2] ? r : b->rb[2]) + RS__BAND_MARGIN;
    for (int k = 0; k < 3; k++) b->lb[k] += b->dlb[k], b->rb[k] += b->drb[k];
    l = l > 0.0 ? l : 0.0;
    r = r < b->xmax ? r : b->xmax;
    if (!(l <= r)) {
        *lo = 1, *hi = 0;
        return;
    }
    *lo = (int32_t)l / RS_STAMP_W; /* l >= 0: truncation is floor */
    *hi = (int32_t)r / RS_STAMP_W;
}

/* Stamps sx0..sx1 of band sy with rs__stamp's operations, for the usual
 * case (no alpha test, no coverage count, the tile inside the image): the
 * triangle's and the tile's constants in registers, fx stepped by 4 (exact
 * small integers, the same values as rs__stamp's), no branch but the loop. */
static inline void rs__band_fast(const rs__tile_ctx *c, const rs__pair *p, int32_t sy, int32_t sx0, int32_t sx1,
                                 simd_i e[3], const simd_i stepx[3], simd_f zy)
{
    float *restrict depth = c->in->depth + ((size_t)sy * RS_STAMPS_X + (size_t)sx0) * SIMD_W;
    int32_t *restrict prim = c->in->prim ? (int32_t *)c->in->prim + ((size_t)sy * RS_STAMPS_X + (size_t)sx0) * SIMD_W
                                         : NULL;
    const simd_f zt = p->zt, dzdx = p->dzdx, zmin = p->zmin, zmax = p->zmax, four = simd_set1_f((float)RS_STAMP_W);
    const simd_i id = p->prim;
    simd_f fx = simd_add_f(c->colf, simd_set1_f((float)(sx0 * RS_STAMP_W)));
    simd_i e0 = e[0], e1 = e[1], e2 = e[2];
    for (int32_t sx = sx0; sx <= sx1; sx++, depth += SIMD_W) {
        simd_mask cov = simd_mask_not(simd_negative_i(simd_or_i(simd_or_i(e0, e1), e2)));
        e0 = simd_add_i(e0, stepx[0]), e1 = simd_add_i(e1, stepx[1]), e2 = simd_add_i(e2, stepx[2]);
        simd_f z = simd_max_f(simd_min_f(simd_add_f(simd_add_f(zt, simd_mul_f(dzdx, fx)), zy), zmax), zmin);
        fx = simd_add_f(fx, four);
        simd_f old = simd_load_f(depth);
        simd_mask pass = simd_mask_and(simd_gt_f(z, old), cov);
        simd_store_f(depth, simd_select_f(pass, z, old));
        if (prim) {
            simd_store_i(prim, simd_select_i(pass, id, simd_load_i(prim)));
            prim += SIMD_W;
        }
    }
}

/* Stamps lo..hi (rectangle-relative) of band sy, from the band's edge
 * values at the rectangle's first stamp. */
static inline void rs__walk32_band(const rs__tile_ctx *c, const rs__pair *p, int32_t sy, int32_t lo, int32_t hi,
                                   const simd_i erow[3], const int32_t ax[3], const simd_i stepx[3], int fast)
{
    if (lo > hi) return;
    simd_i e[3];
    for (int k = 0; k < 3; k++)
        e[k] = simd_add_i(erow[k], simd_set1_i((int32_t)((uint32_t)ax[k] * RS_STAMP_W * (uint32_t)lo)));
    simd_f zy = rs__zy(c, p, sy);
    if (fast) {
        rs__band_fast(c, p, sy, p->sx0 + lo, p->sx0 + hi, e, stepx, zy);
        return;
    }
    for (int32_t sx = p->sx0 + lo; sx <= p->sx0 + hi; sx++) {
        simd_mask cov = simd_mask_not(simd_negative_i(simd_or_i(simd_or_i(e[0], e[1]), e[2])));
        for (int k = 0; k < 3; k++) e[k] = simd_add_i(e[k], stepx[k]);
        /* no branch on coverage: an empty stamp costs less than a
         * mispredicted branch */
        rs__stamp(c, p, sx, sy, zy, rs__inside(c, sx, sy, cov));
    }
}

/* The stamp walk when every edge value fits 32 bits. */
static void rs__walk32(const rs__tile_ctx *c, const rs__pair *p)
{
    simd_i erow[3], stepx[3], stepy[3];
    int32_t ax[3], by[3];
    for (int k = 0; k < 3; k++) {
        /* the per-pixel steps (256 a, or a where the edges are in pixel
         * units, rs__triangle) times a stamp's extent fit: the values over
         * the rectangle, checked, contain these steps */
        ax[k] = p->pa[k], by[k] = p->pb[k];
        erow[k] = simd_add_i(simd_set1_i((int32_t)p->e[k]), simd_add_i(simd_mullo_i(c->col, simd_set1_i(ax[k])),
                                                                        simd_mullo_i(c->row, simd_set1_i(by[k]))));
        stepx[k] = simd_set1_i((int32_t)((uint32_t)ax[k] * RS_STAMP_W));
        stepy[k] = simd_set1_i((int32_t)((uint32_t)by[k] * RS__SH));
    }
    const int fast = !p->masked && !c->in->coverage && !c->partial;
    /* bands pay off on rectangles at least 6 stamps wide and 2 high
     * (measured with `bench raster`: from 2, 4, 5, 6, 7 or 9 stamps on, 5-7
     * best and alike, docs/perf.md); the band bounds exist only then (no
     * memset of them for the others: its rep stos cost more than a small
     * triangle's walk) */
    if (p->sx1 - p->sx0 >= 5 && p->sy1 > p->sy0) {
        rs__bands bands;
        rs__bands_init(&bands, p, ax, by);
        for (int32_t sy = p->sy0; sy <= p->sy1; sy++) {
            int32_t lo, hi;
            rs__bands_next(&bands, &lo, &hi);
            rs__walk32_band(c, p, sy, lo, hi, erow, ax, stepx, fast);
            for (int k = 0; k < 3; k++) erow[k] = simd_add_i(erow[k], stepy[k]);
        }
        return;
    }
    for (int32_t sy = p->sy0; sy <= p->sy1; sy++) {
        rs__walk32_band(c, p, sy, 0, p->sx1 - p->sx0, erow, ax, stepx, fast);
        for (int k = 0; k < 3; k++) erow[k] = simd_add_i(erow[k], stepy[k]);
    }
}

/* The walk of a triangle whose rectangle is at most 2 x 2 stamps (about
 * half of all pairs), with 32-bit values: all four stamps without a loop or
 * a branch (stamps past the rectangle but inside the tile hold no covered
 * pixel: the bounding box contains every covered one). */
static void rs__walk2x2(const rs__tile_ctx *c, const rs__pair *p)
{
    simd_i e00 = simd_set1_i(0), e10 = e00, e01 = e00, e11 = e00;
    for (int k = 0; k < 3; k++) {
        int32_t ax = p->pa[k], by = p->pb[k];
        simd_i e = simd_add_i(simd_set1_i((int32_t)p->e[k]),
                              simd_add_i(simd_mullo_i(c->col, simd_set1_i(ax)), simd_mullo_i(c->row, simd_set1_i(by))));
        simd_i sx = simd_set1_i((int32_t)((uint32_t)ax * RS_STAMP_W)), sy = simd_set1_i((int32_t)((uint32_t)by * RS__SH));
        e00 = simd_or_i(e00, e);
        e10 = simd_or_i(e10, simd_add_i(e, sx));
        e01 = simd_or_i(e01, simd_add_i(e, sy));
        e11 = simd_or_i(e11, simd_add_i(simd_add_i(e, sx), sy));
    }
    int32_t x = p->sx0, y = p->sy0;
    simd_f zy0 = rs__zy(c, p, y), zy1 = rs__zy(c, p, y + 1);
    if (!p->masked && !c->in->coverage && !c->partial) {
        /* rs__band_fast's two bands of two stamps */
        const simd_i zero = simd_set1_i(0);
        const simd_i st[3] = {zero, zero, zero};
        simd_i r0[3] = {e00, zero, zero}, r1[3] = {e01, zero, zero};
        simd_i q0[3] = {e10, zero, zero}, q1[3] = {e11, zero, zero};
        rs__band_fast(c, p, y, x, x, r0, st, zy0);
        rs__band_fast(c, p, y, x + 1, x + 1, q0, st, zy0);
        rs__band_fast(c, p, y + 1, x, x, r1, st, zy1);
        rs__band_fast(c, p, y + 1, x + 1, x + 1, q1, st, zy1);
        return;
    }
    rs__stamp(c, p, x, y, zy0, rs__inside(c, x, y, simd_mask_not(simd_negative_i(e00))));
    rs__stamp(c, p, x + 1, y, zy0, rs__inside(c, x + 1, y, simd_mask_not(simd_negative_i(e10))));
    rs__stamp(c, p, x, y + 1, zy1, rs__inside(c, x, y + 1, simd_mask_not(simd_negative_i(e01))));
    rs__stamp(c, p, x + 1, y + 1, zy1, rs__inside(c, x + 1, y + 1, simd_mask_not(simd_negative_i(e11))));
}

/* The stamp walk of a large triangle: each edge rebased in 64 bits at every
 * stamp; an edge positive over the whole stamp drops out, one negative over
 * it rejects the stamp, and one that crosses it takes 32-bit lanes when its
 * values there fit (any edge not reaching far into the guard band), else
 * exact 64-bit lanes one by one. */
static void rs__walk64(const rs__tile_ctx *c, const rs__pair *p)
{
    const rs__tri *t = p->t;
    int64_t sxs[3], sys[3], px[3], py[3], lo[3], hi[3];
    int lanes32 = 1;
    for (int k = 0; k < 3; k++) {
        px[k] = (int64_t)t->a[k] * RS_SUB, py[k] = (int64_t)t->b[k] * RS_SUB;
        sxs[k] = px[k] * RS_STAMP_W, sys[k] = py[k] * RS__SH;
        int64_t ox = px[k] * (RS_STAMP_W - 1), oy = py[k] * (RS__SH - 1);
        lo[k] = (ox < 0 ? ox : 0) + (oy < 0 ? oy : 0);
        hi[k] = (ox > 0 ? ox : 0) + (oy > 0 ? oy : 0);
        if (hi[k] - lo[k] >= ((int64_t)1 << 30)) lanes32 = 0;
    }
    simd_i off[3];
    for (int k = 0; k < 3; k++)
        off[k] = lanes32 ? simd_add_i(simd_mullo_i(c->col, simd_set1_i((int32_t)px[k])),
                                      simd_mullo_i(c->row, simd_set1_i((int32_t)py[k])))
                         : simd_set1_i(0);
    for (int32_t sy = p->sy0; sy <= p->sy1; sy++)
        for (int32_t sx = p->sx0; sx <= p->sx1; sx++) {
            int64_t e[3];
            int rejected = 0, exact = 0;
            simd_i any = simd_set1_i(0);
            for (int k = 0; k < 3; k++) {
                e[k] = p->e[k] + sxs[k] * (sx - p->sx0) + sys[k] * (sy - p->sy0);
                if (p->dropped >> k & 1) continue; /* positive over the rectangle */
                if (e[k] + hi[k] < 0) rejected = 1;
                else if (e[k] + lo[k] >= 0) continue; /* positive over the stamp */
                else if (lanes32 && e[k] + lo[k] > INT32_MIN && e[k] + hi[k] < INT32_MAX)
                    any = simd_or_i(any, simd_add_i(simd_set1_i((int32_t)e[k]), off[k]));
                else exact = 1;
            }
            if (rejected) continue;
            simd_mask cov = simd_mask_not(simd_negative_i(any));
            if (exact) {
                uint32_t bits = simd_mask_bits(cov);
                for (int l = 0; l < SIMD_W; l++)
                    for (int k = 0; k < 3; k++)
                        if (!(p->dropped >> k & 1) && e[k] + px[k] * (l & 3) + py[k] * (l >> 2) < 0) bits &= ~(1u << l);
                cov = simd_mask_from_bits(bits);
            }
            cov = rs__inside(c, sx, sy, cov);
            if (simd_mask_any(cov)) rs__stamp(c, p, sx, sy, rs__zy(c, p, sy), cov);
        }
}

/* Exact edge-function bounds over the box [0, dx] x [0, dy] pixels from a
 * pixel centre: the increase to its lowest and highest corner. */
static inline void rs__edge_range(const rs__tri *t, int k, int64_t dx, int64_t dy, int64_t *lo, int64_t *hi)
{
    int64_t ox = (int64_t)t->a[k] * RS_SUB * dx, oy = (int64_t)t->b[k] * RS_SUB * dy;
    *lo = (ox < 0 ? ox : 0) + (oy < 0 ? oy : 0);
    *hi = (ox > 0 ? ox : 0) + (oy > 0 ? oy : 0);
}

/* One triangle in the tile: the rectangle of whole stamps around its
 * bounding box, walked with its edge values at the first stamp: from the
 * 32-bit values of a small triangle, else in 64 bits (rejected when an edge
 * is negative over all of it, and walked in 32-bit lanes where every value
 * fits). */
static void rs__triangle(const rs__tile_ctx *c, const rs__tri *t, const void *masked)
{
    const rs__tile_in *in = c->in;
    int32_t tx1 = in->x0 + in->xlim - 1, ty1 = in->y0 + in->ylim - 1;
    int32_t bx0 = t->x0 > in->x0 ? t->x0 : in->x0, bx1 = t->x1 < tx1 ? t->x1 : tx1;
    int32_t by0 = t->y0 > in->y0 ? t->y0 : in->y0, by1 = t->y1 < ty1 ? t->y1 : ty1;
    if (bx0 > bx1 || by0 > by1) return;
    rs__pair p;
    p.t = t;
    p.masked = masked;
    p.sx0 = (bx0 - in->x0) / RS_STAMP_W, p.sx1 = (bx1 - in->x0) / RS_STAMP_W;
    p.sy0 = (by0 - in->y0) / RS__SH, p.sy1 = (by1 - in->y0) / RS__SH;
    int32_t ox = in->x0 + p.sx0 * RS_STAMP_W, oy = in->y0 + p.sy0 * RS__SH; /* the first stamp's first pixel */
    int e32 = 1;
    p.dropped = 0;
    if (t->flags & RS__SMALL) {
        /* within RS__SMALL_MARGIN of the box: no overflow (wrapping arithmetic all the same) */
        uint32_t dx = (uint32_t)(ox - t->x0), dy = (uint32_t)(oy - t->y0);
        for (int k = 0; k < 3; k++) {
            p.pa[k] = (int32_t)((uint32_t)t->a[k] * RS_SUB), p.pb[k] = (int32_t)((uint32_t)t->b[k] * RS_SUB);
            p.e[k] = (int32_t)((uint32_t)t->c32[k] + (uint32_t)p.pa[k] * dx + (uint32_t)p.pb[k] * dy);
        }
    } else {
        /* The 32-bit walks take the edges in pixel units: E = 256 (a x + b
         * y) + C at pixel centres (x, y relative to the first stamp's first
         * pixel), so with q = floor(C / 256), E >= 0 <=> a x + b y + q >= 0
         * (the left side is 256 times an integer plus C - 256 q, which lies in
         * [0, 256)): the same coverage from values 256 times smaller, so
         * large triangles (a cube face's walls) take 32-bit lanes too. The
         * 64-bit walk, for what still does not fit, keeps E itself. */
        int64_t nx = p.sx1 - p.sx0 + 1, ny = p.sy1 - p.sy0 + 1;
        int64_t px0 = (int64_t)ox * RS_SUB + RS_SUB / 2, py0 = (int64_t)oy * RS_SUB + RS_SUB / 2;
        int64_t full[3];
        for (int k = 0; k < 3; k++) {
            int64_t e = t->a[k] * px0 + t->b[k] * py0 + t->c[k], lo, hi;
            rs__edge_range(t, k, nx * RS_STAMP_W - 1, ny * RS__SH - 1, &lo, &hi);
            if (e + hi < 0) return; /* negative over the whole rectangle */
            full[k] = e;
            p.pa[k] = t->a[k], p.pb[k] = t->b[k];
            p.e[k] = e >> RS_SUBPIXEL_BITS; /* floor (arithmetic shift) */
            /* the 32-bit walks also step one stamp past the last in x and
             * one band past the last in y */
            int64_t lo1, hi1;
            rs__edge_range(t, k, (nx + 1) * RS_STAMP_W - 1, (ny + 1) * RS__SH - 1, &lo1, &hi1);
            if (e + lo1 >= 0) { /* positive over the rectangle (and the step past it): no test needed */
                full[k] = p.e[k] = 0, p.pa[k] = p.pb[k] = 0;
                p.dropped |= 1u << k;
                continue;
            }
            /* lo1, hi1 are 256 times the pixel-unit range; the steps a, b
             * times a stamp's extent fit as well */
            int64_t m = (t->a[k] < 0 ? -(int64_t)t->a[k] : t->a[k]) > (t->b[k] < 0 ? -(int64_t)t->b[k] : t->b[k])
                            ? (t->a[k] < 0 ? -(int64_t)t->a[k] : t->a[k])
                            : (t->b[k] < 0 ? -(int64_t)t->b[k] : t->b[k]);
            if (!(p.e[k] + lo1 / RS_SUB > INT32_MIN && p.e[k] + hi1 / RS_SUB < INT32_MAX) || m >= ((int64_t)1 << 26))
                e32 = 0;
        }
        if (!e32) /* rs__walk64's exact values */
            for (int k = 0; k < 3; k++) p.e[k] = full[k];
    }
    /* the depth plane at the tile's first pixel, rounded once */
    double zt = t->zv + t->dzdx_d * ((double)in->x0 + 0.5 - t->xv) + t->dzdy_d * ((double)in->y0 + 0.5 - t->yv);
    p.zt = simd_set1_f((float)zt);
    p.dzdx = simd_set1_f((float)t->dzdx_d);
    p.dzdy = simd_set1_f((float)t->dzdy_d);
    p.zmin = simd_set1_f(t->zmin);
    p.zmax = simd_set1_f(t->zmax);
    p.prim = simd_set1_i((int32_t)t->prim);
    if (!e32) rs__walk64(c, &p);
    else if (p.sx1 - p.sx0 <= 1 && p.sy1 - p.sy0 <= 1 && p.sx0 < RS_STAMPS_X - 1 && p.sy0 < RS_TILE / RS__SH - 1)
        rs__walk2x2(c, &p);
    else rs__walk32(c, &p);
}

static void rs__tile(const rs__tile_in *in)
{
    rs__tile_ctx c;
    c.in = in;
    const simd_i lane = simd_iota_i();
    c.col = simd_and_i(lane, simd_set1_i(RS_STAMP_W - 1));
    c.row = simd_srli_i(lane, 2);
    c.colf = simd_i2f(c.col);
    c.rowf = simd_i2f(c.row);
    c.partial = in->xlim < RS_TILE || in->ylim < RS_TILE;
    for (uint32_t i = 0; i < in->count; i++) {
        if (i + RS__PREFETCH < in->count) {
            const char *next = (const char *)in->tris[i + RS__PREFETCH];
            __builtin_prefetch(next);
            __builtin_prefetch(next + 64);
        }
        rs__triangle(&c, in->tris[i], in->masked[i]);
    }
}

const rs_raster_kernels RS_RASTER_KERNELS = {SIMD_NAME, RS__SH, rs__tile};
