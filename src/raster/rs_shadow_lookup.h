/* rs_shadow_lookup: the shadow maps' 16-tap PCF lookup of SIMD_W points at
 * once, written once over the SIMD vocabulary. Include it after simd.h in a
 * file compiled once per instruction set (rs_shadow_kernels.c, and the
 * direct-light row in gi_direct_kernels.c inlines it).
 *
 * Lane by lane it makes the very IEEE operations of rs_shadow_visibility
 * (rs_shadow.c, the scalar reference), in the same order and association
 * (no FMA, no approximate reciprocals), so the bits agree. Each early return
 * of the scalar code becomes a lane mask applied at the end, latest check
 * first so that the earliest one wins as it does there; a cube map's
 * per-face constants are gathered by each lane's face; the PCF taps are
 * loads of four consecutive texels per lane and row (or gathers at the
 * clamped indices near a face's edge), the same texels. The
 * normal offset (step 3, off by default) is not vectorised:
 * rs_shadow_lookup_eligible sends such maps to the scalar lookup. */
#ifndef RS_SHADOW_LOOKUP_H
#define RS_SHADOW_LOOKUP_H

#include <math.h>

#include "rs_shadow.h"
#include "simd.h"

/* (a . b) in the order (ax bx + ay by) + az bz, as pf_v3_dot */
static inline simd_f rs__sdot(simd_f ax, simd_f ay, simd_f az, simd_f bx, simd_f by, simd_f bz)
{
    return simd_add_f(simd_add_f(simd_mul_f(ax, bx), simd_mul_f(ay, by)), simd_mul_f(az, bz));
}

/* Element k of a per-face array (stride floats per face) for each lane's
 * face: gathered (base: face 0) or, when every lane has the same face,
 * broadcast (base: that face). */
static inline simd_f rs__face_val(const float *base, int gather, simd_i face_off, int k)
{
    if (!gather) return simd_set1_f(base[k]);
    return simd_gather_f(base, simd_add_i(face_off, simd_set1_i(k)));
}

/* rs__face: the cube face of the major axis of v = p - eye (ties to x,
 * then y, then z; a NaN falls through to z like the scalar code); 0 for
 * the other kinds. */
static inline simd_i rs__shadow_face_lanes(const rs_shadow_map *m, simd_f v_x, simd_f v_y, simd_f v_z)
{
    if (m->kind != RS_SHADOW_CUBE) return simd_set1_i(0);
    const simd_f zero = simd_zero_f();
    simd_f ax = simd_abs_f(v_x), ay = simd_abs_f(v_y), az = simd_abs_f(v_z);
    simd_mask is_x = simd_mask_and(simd_ge_f(ax, ay), simd_ge_f(ax, az));
    simd_mask is_y = simd_ge_f(ay, az);
    /* v >= 0 ? 2a : 2a + 1 */
    simd_i f_x = simd_select_i(simd_ge_f(v_x, zero), simd_set1_i(0), simd_set1_i(1));
    simd_i f_y = simd_select_i(simd_ge_f(v_y, zero), simd_set1_i(2), simd_set1_i(3));
    simd_i f_z = simd_select_i(simd_ge_f(v_z, zero), simd_set1_i(4), simd_set1_i(5));
    return simd_select_i(is_x, f_x, simd_select_i(is_y, f_y, f_z));
}

/* The clip coordinates c of p by each lane's face matrix (vp: face 0's
 * when gathering, else the shared face's): c[r] = m[r] x + m[4+r] y +
 * m[8+r] z + m[12+r], rs_mat4_transform's order. */
static inline void rs__shadow_clip_lanes(const float *vp, int gather, simd_i off16, simd_f p_x, simd_f p_y,
                                         simd_f p_z, simd_f c[4])
{
    for (int r = 0; r < 4; r++) {
        simd_f acc = simd_mul_f(rs__face_val(vp, gather, off16, r), p_x);
        acc = simd_add_f(acc, simd_mul_f(rs__face_val(vp, gather, off16, 4 + r), p_y));
        acc = simd_add_f(acc, simd_mul_f(rs__face_val(vp, gather, off16, 8 + r), p_z));
        c[r] = simd_add_f(acc, rs__face_val(vp, gather, off16, 12 + r));
    }
}

/* NDC (x, y) to texels (fx, fy), clamped (max(v, lo) drops a NaN as fmaxf
 * does), and the first texel column and row the lookup reads. */
static inline void rs__shadow_texel_lanes(const rs_shadow_map *m, simd_f x, simd_f y, simd_f *fx, simd_f *fy,
                                          simd_i *x0, simd_i *y0)
{
    const int pcf = m->desc.filter != RS_SHADOW_PCF1;
    const float s_s = (float)m->size;
    const simd_f s = simd_set1_f(s_s);
    const simd_f half = simd_set1_f(0.5f), lo = simd_set1_f(-8.0f), hi = simd_set1_f(s_s + 8.0f);
    *fx = simd_min_f(simd_max_f(simd_mul_f(simd_add_f(simd_mul_f(half, x), half), s), lo), hi);
    *fy = simd_min_f(simd_max_f(simd_mul_f(simd_sub_f(half, simd_mul_f(half, y)), s), lo), hi);
    const simd_f start = simd_set1_f(1.5f);
    *x0 = simd_f2i_trunc(simd_floor_f(pcf ? simd_sub_f(*fx, start) : *fx));
    *y0 = simd_f2i_trunc(simd_floor_f(pcf ? simd_sub_f(*fy, start) : *fy));
}

/* rs_shadow_visibility of points (p_x, p_y, p_z) with geometric normals
 * (g_x, g_y, g_z) for the lanes of `active`; 0 in the other lanes (whose
 * inputs must still be finite or at least initialised). */
static inline simd_f rs_shadow_visibility_lanes(const rs_shadow_map *m, simd_f p_x, simd_f p_y, simd_f p_z,
                                                simd_f g_x, simd_f g_y, simd_f g_z, simd_mask active)
{
    const int pcf = m->desc.filter != RS_SHADOW_PCF1;
    const int ortho = m->kind == RS_SHADOW_ORTHO, cube = m->kind == RS_SHADOW_CUBE, spot = m->kind == RS_SHADOW_SPOT;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    const simd_i izero = simd_set1_i(0), ione = simd_set1_i(1);

    /* rs__face: v = p - eye; the cube face of the major axis of v (ties to
     * x, then y, then z; a NaN falls through to z like the scalar code),
     * and the depth along the face's axis. */
    simd_f v_x = simd_sub_f(p_x, simd_set1_f(m->eye.x));
    simd_f v_y = simd_sub_f(p_y, simd_set1_f(m->eye.y));
    simd_f v_z = simd_sub_f(p_z, simd_set1_f(m->eye.z));
    const simd_i face = rs__shadow_face_lanes(m, v_x, v_y, v_z);
    /* the face's constants: broadcast when the points share a face (the
     * usual case), gathered per lane otherwise */
    const int32_t f0 = simd_lane0_i(face);
    const int one_face = simd_mask_bits(simd_eq_i(face, simd_set1_i(f0))) == SIMD_FULL;
    const int gather = cube && !one_face;
    const int fb = gather ? 0 : f0;
    const simd_i off3 = simd_mullo_i(face, simd_set1_i(3));
    const simd_i off16 = simd_slli_i(face, 4);
    const float *fwd = &m->forward[fb].x, *rgt = &m->right[fb].x, *upv = &m->up[fb].x, *vp = m->view_proj[fb].m;
    simd_f f_x = rs__face_val(fwd, gather, off3, 0), f_y = rs__face_val(fwd, gather, off3, 1);
    simd_f f_z = rs__face_val(fwd, gather, off3, 2);
    simd_f depth = rs__sdot(v_x, v_y, v_z, f_x, f_y, f_z);

    /* l (unit, towards the light) and texel (world size of a texel at p) */
    simd_f l_x, l_y, l_z, texel;
    simd_mask behind = simd_mask_from_bits(0);
    if (ortho) {
        pf_vec3 l = pf_v3_scale(m->forward[0], -1.0f);
        l_x = simd_set1_f(l.x);
        l_y = simd_set1_f(l.y);
        l_z = simd_set1_f(l.z);
        texel = simd_set1_f(2.0f * fmaxf(m->half_w, m->half_h) / (float)m->size);
    } else {
        behind = simd_mask_not(simd_gt_f(depth, zero)); /* !(depth > 0) */
        simd_f d_x = simd_sub_f(simd_set1_f(m->eye.x), p_x);
        simd_f d_y = simd_sub_f(simd_set1_f(m->eye.y), p_y);
        simd_f d_z = simd_sub_f(simd_set1_f(m->eye.z), p_z);
        simd_f len = simd_sqrt_f(rs__sdot(d_x, d_y, d_z, d_x, d_y, d_z));
        simd_f inv = simd_div_f(one, len);
        simd_mask ok = simd_gt_f(len, zero); /* pf_v3_normalize: 0 for a zero vector */
        l_x = simd_select_f(ok, simd_mul_f(d_x, inv), zero);
        l_y = simd_select_f(ok, simd_mul_f(d_y, inv), zero);
        l_z = simd_select_f(ok, simd_mul_f(d_z, inv), zero);
        /* a power-of-two size divides exactly as a multiplication by its
         * reciprocal (also exact), which is cheaper */
        simd_f t2d = simd_mul_f(simd_set1_f(2.0f * m->tan_half), depth);
        texel = (m->size & (m->size - 1)) == 0 ? simd_mul_f(t2d, simd_set1_f(1.0f / (float)m->size))
                                               : simd_div_f(t2d, simd_set1_f((float)m->size));
    }

    /* n: unit geometric normal (l where it has none); the slope and bias */
    simd_f nlen = simd_sqrt_f(rs__sdot(g_x, g_y, g_z, g_x, g_y, g_z));
    simd_f ninv = simd_div_f(one, nlen);
    simd_mask has_n = simd_gt_f(nlen, zero);
    simd_f n_x = simd_select_f(has_n, simd_mul_f(g_x, ninv), l_x);
    simd_f n_y = simd_select_f(has_n, simd_mul_f(g_y, ninv), l_y);
    simd_f n_z = simd_select_f(has_n, simd_mul_f(g_z, ninv), l_z);
    simd_f cos_t = simd_abs_f(rs__sdot(n_x, n_y, n_z, l_x, l_y, l_z));
    /* fmaxf(0, v): max(v, 0) returns its second operand for a NaN v, like fmaxf */
    simd_f sin_t = simd_sqrt_f(simd_max_f(simd_sub_f(one, simd_mul_f(cos_t, cos_t)), zero));
    const float tan_max_s = m->desc.tan_max > 0.0f ? m->desc.tan_max : RS_SHADOW_TAN_MAX;
    const simd_f tan_max = simd_set1_f(tan_max_s);
    simd_f tmax_cos = simd_mul_f(tan_max, cos_t);
    simd_mask capped = simd_mask_not(simd_lt_f(sin_t, tmax_cos)); /* !(sin_t < tan_max cos_t) */
    simd_f tan_t = simd_select_f(capped, tan_max, simd_div_f(sin_t, cos_t));
    float b_const = m->desc.bias_const > 0.0f ? m->desc.bias_const : RS_SHADOW_BIAS_CONST;
    float b_slope = m->desc.bias_slope > 0.0f ? m->desc.bias_slope : RS_SHADOW_BIAS_SLOPE;
    simd_f bias = simd_mul_f(texel, simd_add_f(simd_set1_f(b_const), simd_mul_f(simd_set1_f(b_slope), tan_t)));

    /* project with the face's matrix */
    simd_f c[4];
    rs__shadow_clip_lanes(vp, gather, off16, p_x, p_y, p_z, c);
    const float s_s = (float)m->size;
    const simd_f s = simd_set1_f(s_s);
    simd_f nr = rs__sdot(n_x, n_y, n_z, rs__face_val(rgt, gather, off3, 0), rs__face_val(rgt, gather, off3, 1),
                         rs__face_val(rgt, gather, off3, 2));
    simd_f nu = rs__sdot(n_x, n_y, n_z, rs__face_val(upv, gather, off3, 0), rs__face_val(upv, gather, off3, 1),
                         rs__face_val(upv, gather, off3, 2));
    simd_f cap = simd_select_f(simd_mask_and(capped, simd_gt_f(sin_t, zero)), simd_div_f(tmax_cos, sin_t), one);
    simd_f x, y, zs_p, zs_bias, k;
    simd_mask lit_early, unlit_early = simd_mask_from_bits(0);
    if (ortho) {
        x = c[0];
        y = c[1];
        zs_p = c[2];
        simd_mask inside = simd_mask_and(simd_mask_and(simd_le_f(simd_abs_f(x), one), simd_le_f(simd_abs_f(y), one)),
                                         simd_mask_and(simd_ge_f(zs_p, zero), simd_le_f(zs_p, one)));
        lit_early = simd_mask_not(inside);
        float inv_range = 1.0f / (m->zfar - m->znear);
        zs_bias = simd_mul_f(bias, simd_set1_f(inv_range));
        simd_f nf = rs__sdot(n_x, n_y, n_z, f_x, f_y, f_z);
        k = simd_mul_f(simd_div_f(simd_set1_f(2.0f * inv_range), simd_mul_f(s, nf)), cap);
        k = simd_select_f(simd_mask_not(simd_eq_f(nf, zero)), k, zero); /* nf != 0 ? ... : 0 */
        nr = simd_mul_f(nr, simd_set1_f(m->half_w));
        nu = simd_mul_f(nu, simd_set1_f(m->half_h));
    } else {
        x = simd_div_f(c[0], c[3]);
        y = simd_div_f(c[1], c[3]);
        zs_p = simd_div_f(c[2], c[3]);
        simd_f wb = simd_sub_f(c[3], bias);
        lit_early = simd_mask_not(simd_gt_f(wb, c[2])); /* !(wb > c2): nearer than znear */
        if (spot) unlit_early = simd_mask_not(simd_mask_and(simd_le_f(simd_abs_f(x), one), simd_le_f(simd_abs_f(y), one)));
        zs_bias = simd_sub_f(simd_div_f(c[2], wb), zs_p);
        simd_f d = rs__sdot(n_x, n_y, n_z, v_x, v_y, v_z);
        k = simd_mul_f(simd_div_f(simd_set1_f(2.0f * m->znear * m->tan_half), simd_mul_f(s, d)), cap);
        k = simd_select_f(simd_mask_not(simd_eq_f(d, zero)), k, zero);
    }
    simd_f gx = simd_mul_f(k, nr), gy = simd_mul_f(simd_neg_f(k), nu);

    /* NDC to texels */
    const simd_f half = simd_set1_f(0.5f);
    const int n = pcf ? 4 : 1;
    simd_f fx, fy;
    simd_i x0, y0;
    rs__shadow_texel_lanes(m, x, y, &fx, &fy, &x0, &y0);

    /* rs__pcf: count the taps whose stored zs is no nearer than the
     * receiver's plane at the tap's texel centre plus the bias */
    const simd_i last = simd_set1_i((int32_t)m->size - 1), size_i = simd_set1_i((int32_t)m->size);
    const simd_i plane_off = simd_mullo_i(face, simd_set1_i((int32_t)(m->size * m->size)));
    /* A row's four taps are four consecutive texels: where every active
     * lane's columns x0 .. x0 + 3 lie inside the face (no clamping, the
     * usual case: faces carry a margin), one 4-float load per lane and row
     * (simd_gather4_f; the other lanes read the plane's first texels),
     * else one gather per tap at the clamped column. The same texels
     * either way. */
    const uint32_t act = simd_mask_bits(active);
    const int rows4 = pcf && m->size >= 4 &&
                      (simd_mask_bits(simd_mask_and(simd_mask_not(simd_gt_i(izero, x0)),
                                                    simd_mask_not(simd_gt_i(x0, simd_set1_i((int32_t)m->size - 4))))) &
                       act) == act;
    simd_i lit = izero;
    for (int j = 0; j < n; j++) {
        simd_i yy = simd_add_i(y0, simd_set1_i(j));
        simd_i yc = simd_min_i(simd_max_i(yy, izero), last);
        simd_i row = simd_add_i(plane_off, simd_mullo_i(yc, size_i));
        simd_f ty = simd_sub_f(simd_add_f(simd_i2f(yy), half), fy);
        simd_f zy = simd_add_f(simd_add_f(zs_p, simd_mul_f(gy, ty)), zs_bias);
        simd_f taps[4];
        if (rows4) simd_gather4_f(m->depth, simd_select_i(active, simd_add_i(row, x0), izero), taps);
        for (int i = 0; i < n; i++) {
            simd_i xx = simd_add_i(x0, simd_set1_i(i));
            simd_f tap;
            if (rows4) {
                tap = taps[i];
            } else {
                simd_i xc = simd_min_i(simd_max_i(xx, izero), last);
                tap = simd_maskz_gather_f(m->depth, simd_add_i(row, xc), active);
            }
            simd_f tx = simd_sub_f(simd_add_f(simd_i2f(xx), half), fx);
            simd_mask le = simd_le_f(tap, simd_add_f(zy, simd_mul_f(gx, tx)));
            lit = simd_add_i(lit, simd_select_i(le, ione, izero));
        }
    }
    /* lit / (n n): n n is 16 or 1, so the multiplication by 1/16 or 1 is the
     * same exact operation */
    simd_f vis = simd_mul_f(simd_i2f(lit), simd_set1_f(pcf ? 0.0625f : 1.0f));

    /* the scalar code's early returns, latest first */
    vis = simd_select_f(lit_early, one, vis);
    vis = simd_select_f(unlit_early, zero, vis);
    if (!ortho) vis = simd_select_f(behind, spot ? zero : one, vis);
    return simd_select_f(active, vis, zero);
}

/* Sets bit k of need with a relaxed atomic OR, skipped when it is set
 * already (other rows mark the same words; the union is the same for any
 * schedule). */
static inline void rs__need_mark(uint64_t *need, uint32_t k)
{
    uint64_t *w = &need[k / 64], bit = (uint64_t)1 << (k % 64);
    if (!(__atomic_load_n(w, __ATOMIC_RELAXED) & bit)) __atomic_fetch_or(w, bit, __ATOMIC_RELAXED);
}

/* Marks in m->need the tiles rs_shadow_visibility_lanes reads for the lanes
 * of `active` (rs_shadow_render_needed then draws them): the same face, the
 * same projection and the same first texel as the lookup (the helpers
 * above), the n x n taps' clamped columns and rows, each tile's bit set
 * with a relaxed atomic OR (other rows mark the same words; the union is
 * the same for any schedule). Maps with a normal offset are marked whole by
 * the caller (rs_shadow_need_all). */
static inline void rs_shadow_need_lanes(const rs_shadow_map *m, simd_f p_x, simd_f p_y, simd_f p_z,
                                        simd_mask active)
{
    const uint32_t act = simd_mask_bits(active);
    if (!act || !m->need) return;
    const int cube = m->kind == RS_SHADOW_CUBE, ortho = m->kind == RS_SHADOW_ORTHO;
    simd_f v_x = simd_sub_f(p_x, simd_set1_f(m->eye.x));
    simd_f v_y = simd_sub_f(p_y, simd_set1_f(m->eye.y));
    simd_f v_z = simd_sub_f(p_z, simd_set1_f(m->eye.z));
    const simd_i face = rs__shadow_face_lanes(m, v_x, v_y, v_z);
    const int32_t f0 = simd_lane0_i(face);
    const int gather = cube && simd_mask_bits(simd_eq_i(face, simd_set1_i(f0))) != SIMD_FULL;
    simd_f c[4];
    rs__shadow_clip_lanes(m->view_proj[gather ? 0 : f0].m, gather, simd_slli_i(face, 4), p_x, p_y, p_z, c);
    simd_f x = ortho ? c[0] : simd_div_f(c[0], c[3]), y = ortho ? c[1] : simd_div_f(c[1], c[3]);
    simd_f fx, fy;
    simd_i x0, y0;
    rs__shadow_texel_lanes(m, x, y, &fx, &fy, &x0, &y0);
    /* the window's clamped first and last texels, their tiles (RS_TILE is
     * 64: shifts) and the face's first bit in need */
    const int32_t n = m->desc.filter != RS_SHADOW_PCF1 ? 4 : 1;
    const simd_i izero = simd_set1_i(0), last = simd_set1_i((int32_t)m->size - 1), n1 = simd_set1_i(n - 1);
    simd_i xa = simd_min_i(simd_max_i(x0, izero), last), xb = simd_min_i(simd_max_i(simd_add_i(x0, n1), izero), last);
    simd_i ya = simd_min_i(simd_max_i(y0, izero), last), yb = simd_min_i(simd_max_i(simd_add_i(y0, n1), izero), last);
    xa = simd_srli_i(xa, 6), xb = simd_srli_i(xb, 6), ya = simd_srli_i(ya, 6), yb = simd_srli_i(yb, 6);
    const simd_i fk = simd_mullo_i(face, simd_set1_i((int32_t)(m->tile_words * 64)));
    /* the usual case: the lanes' windows on one face, their tiles' bounding
     * box at most 2 x 2 tiles (neighbouring pixels, a tile edge between
     * them): that box, a superset of the windows' tiles */
    const int32_t k0 = simd_lane0_i(fk);
    if ((act & 1u) && (simd_mask_bits(simd_eq_i(fk, simd_set1_i(k0))) & act) == act) {
        const simd_f big = simd_set1_f(1.0e9f), nbig = simd_set1_f(-1.0e9f);
        /* small integers, exact as floats: the vocabulary's float minimum */
        float bx0 = simd_hmin_f(simd_select_f(active, simd_i2f(xa), big));
        float by0 = simd_hmin_f(simd_select_f(active, simd_i2f(ya), big));
        float bx1 = -simd_hmin_f(simd_select_f(active, simd_neg_f(simd_i2f(xb)), nbig));
        float by1 = -simd_hmin_f(simd_select_f(active, simd_neg_f(simd_i2f(yb)), nbig));
        if (bx1 - bx0 <= 1.0f && by1 - by0 <= 1.0f) {
            for (uint32_t ty = (uint32_t)by0; ty <= (uint32_t)by1; ty++)
                for (uint32_t tx = (uint32_t)bx0; tx <= (uint32_t)bx1; tx++) {
                    rs__need_mark(m->need, (uint32_t)k0 + ty * m->tiles_side + tx);
                }
            return;
        }
    }
    int32_t fl[SIMD_W], xal[SIMD_W], xbl[SIMD_W], yal[SIMD_W], ybl[SIMD_W];
    simd_storeu_i(fl, fk), simd_storeu_i(xal, xa), simd_storeu_i(xbl, xb), simd_storeu_i(yal, ya), simd_storeu_i(ybl, yb);
    uint32_t prev = UINT32_MAX; /* runs of lanes share a one-tile window */
    for (int l = 0; l < SIMD_W; l++) {
        if (!(act >> l & 1u)) continue;
        if (xal[l] == xbl[l] && yal[l] == ybl[l]) {
            uint32_t k = (uint32_t)fl[l] + (uint32_t)yal[l] * m->tiles_side + (uint32_t)xal[l];
            if (k == prev) continue;
            prev = k;
        }
        for (int32_t ty = yal[l]; ty <= ybl[l]; ty++)
            for (int32_t tx = xal[l]; tx <= xbl[l]; tx++) {
                rs__need_mark(m->need, (uint32_t)fl[l] + (uint32_t)ty * m->tiles_side + (uint32_t)tx);
            }
    }
}

#if RS_TILE != 64
#error "rs_shadow_need_lanes divides by RS_TILE with shifts by 6"
#endif

/* Whether a map can take rs_shadow_visibility_lanes (else the scalar lookup
 * point by point): texel indices fit 31 bits, no normal offset. */
static inline int rs_shadow_lookup_eligible(const rs_shadow_map *m)
{
    uint64_t texels = (uint64_t)m->face_count * m->size * m->size;
    return m->depth && m->size > 0 && texels < ((uint64_t)1 << 31) && !(m->desc.normal_offset > 0.0f);
}

/* Whether a frame marks the tiles m's lookups read (rs_shadow_need_lanes):
 * a fresh map the SIMD lookup serves; every other map is needed whole
 * (rs_shadow_need_all). */
static inline int rs_shadow_marks_receivers(const rs_shadow_map *m) { return m->fresh && rs_shadow_lookup_eligible(m); }

#endif
