/* rs_para_lookup: the paraboloid shadow-map lookup of SIMD_W points at
 * once, written once over the SIMD vocabulary: the one lookup of the
 * project's SIMD paths (the exact maps of rs_paraboloid and the imperfect
 * shadow maps of gi_ism share the map format; ISMs scale the bias). Include
 * it after simd.h in a file compiled once per instruction set
 * (rs_para_kernels.c exports it as rs_para_kernels.visible; the many-light
 * accumulation inlines it).
 *
 * Lane by lane it makes the operations of rs_para_visible_scaled
 * (rs_paraboloid.c, the scalar reference) in the same order: the local
 * direction d, the texel of its (u, v) moved inside the disc when its centre
 * is not (rs_para_texel_of_uv, two passes), the stored code, and
 *   visible = d.z > 0 && (code empty || |d| <= decode(code) + bias_scale (w (1 + tan) + 2 steps))
 * with w = |d| (4 / R) / (1 + u^2 + v^2) and tan = min(tan(theta), RS_PARA_TAN_MAX) from
 * cos_receiver, or with receiver normals the receiver-plane test
 * (rs_paraboloid.h "Lookup": the plane's distance along the texel centre's
 * ray, from the texel's column and row, clamped to |d| -+ bias, against
 * decode(code) + RS_PARA_PLANE_EPS w + 2 steps). sqrt and division are
 * correctly rounded, floor, min/max
 * and the integer texel arithmetic exact, so every lane gets the scalar
 * bits. Every lane is gathered (indices are clamped into the map even for
 * NaN directions), so the map needs RS_PARA_LOOKUP_SLACK bytes after its
 * last code (simd_gather_u16). */
#ifndef RS_PARA_LOOKUP_H
#define RS_PARA_LOOKUP_H

#include "rs_paraboloid.h"
#include "simd.h"

#define RS_PARA_LOOKUP_SLACK 2

/* a . (x, y, z) for a frame axis a, in rs_para_to_local's order */
static inline simd_f rs__para_dot(simd_f x, simd_f y, simd_f z, pf_vec3 a)
{
    return simd_add_f(simd_add_f(simd_mul_f(x, simd_set1_f(a.x)), simd_mul_f(y, simd_set1_f(a.y))),
                      simd_mul_f(z, simd_set1_f(a.z)));
}

/* The texel index of (u, v) for every lane: rs_para_texel_of_uv; its
 * column and row as floats in *col and *row. */
static inline simd_i rs_para_texel_lanes(uint32_t R, simd_f u, simd_f v, simd_f *col, simd_f *row)
{
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    const simd_f h = simd_set1_f(0.5f * (float)R), rmax = simd_set1_f((float)R - 1.0f);
    const simd_f shrink = simd_set1_f(1.0f - 1.5f / (float)R);
    const simd_i iR = simd_set1_i((int32_t)R), iR2 = simd_set1_i((int32_t)(R * R)), ione = simd_set1_i(1);
    simd_i idx = simd_set1_i(0);
    simd_f ci = simd_zero_f(), cj = simd_zero_f();
    simd_mask done = simd_mask_from_bits(0);
    for (int pass = 0; pass < 2; pass++) {
        simd_f fi = simd_floor_f(simd_mul_f(simd_add_f(u, one), h));
        simd_f fj = simd_floor_f(simd_mul_f(simd_add_f(v, one), h));
        /* clamped to [0, R-1], a NaN to 0 (max(NaN, 0) is 0) */
        fi = simd_min_f(simd_max_f(fi, zero), rmax);
        fj = simd_min_f(simd_max_f(fj, zero), rmax);
        simd_i ii = simd_f2i_trunc(fi), jj = simd_f2i_trunc(fj);
        simd_i t = simd_add_i(simd_mullo_i(jj, iR), ii);
        /* rs_para_texel_inside: (2i+1-R)^2 + (2j+1-R)^2 <= R^2 (R <= RS_PARA_MAX_RES: no overflow) */
        simd_i ai = simd_sub_i(simd_add_i(simd_add_i(ii, ii), ione), iR);
        simd_i aj = simd_sub_i(simd_add_i(simd_add_i(jj, jj), ione), iR);
        simd_i d2 = simd_add_i(simd_mullo_i(ai, ai), simd_mullo_i(aj, aj));
        simd_mask inside = pass == 0 ? simd_mask_not(simd_gt_i(d2, iR2)) : simd_mask_from_bits(SIMD_FULL);
        simd_mask take = simd_mask_andnot(inside, done);
        idx = simd_select_i(take, t, idx);
        ci = simd_select_f(take, fi, ci);
        cj = simd_select_f(take, fj, cj);
        done = simd_mask_or(done, take);
        if (pass == 0) {
            if (simd_mask_bits(done) == SIMD_FULL) break;
            /* move (u, v) in to radius 1 - 1.5/R */
            simd_f rr = simd_sqrt_f(simd_add_f(simd_mul_f(u, u), simd_mul_f(v, v)));
            simd_f k = simd_div_f(shrink, simd_select_f(simd_gt_f(rr, zero), rr, one));
            u = simd_mul_f(u, k);
            v = simd_mul_f(v, k);
        }
    }
    *col = ci;
    *row = cj;
    return idx;
}

/* The lanes whose point (px, py, pz) the map's VPL (frame f) sees, with the
 * receiver's cosine cos_receiver (either sign) and the bias scaled by
 * bias_scale (1 for exact maps: x 1 is exact); with `plane` the
 * receiver-plane test with the receivers' normals (nx, ny, nz)
 * (rs_para_visible_scaled with plane_n; bias_scale unused). */
static inline simd_mask rs_para_visible_lanes(const uint16_t *map, uint32_t R, float range, float bias_scale,
                                              const rs_para_frame *f, simd_f px, simd_f py, simd_f pz,
                                              simd_f cos_receiver, int plane, simd_f nx, simd_f ny, simd_f nz)
{
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f), tanmax = simd_set1_f(RS_PARA_TAN_MAX);
    /* rs_para_to_local */
    simd_f qx = simd_sub_f(px, simd_set1_f(f->o.x)), qy = simd_sub_f(py, simd_set1_f(f->o.y));
    simd_f qz = simd_sub_f(pz, simd_set1_f(f->o.z));
    simd_f lx = rs__para_dot(qx, qy, qz, f->t), ly = rs__para_dot(qx, qy, qz, f->b);
    simd_f lz = rs__para_dot(qx, qy, qz, f->n);
    simd_mask front = simd_gt_f(lz, zero);
    /* |d|, (u, v), the texel footprint w */
    simd_f dist = simd_sqrt_f(simd_add_f(simd_add_f(simd_mul_f(lx, lx), simd_mul_f(ly, ly)), simd_mul_f(lz, lz)));
    simd_f den = simd_add_f(dist, lz);
    simd_f u = simd_div_f(lx, den), v = simd_div_f(ly, den);
    simd_f w = simd_div_f(simd_mul_f(dist, simd_set1_f(4.0f / (float)R)),
                          simd_add_f(one, simd_add_f(simd_mul_f(u, u), simd_mul_f(v, v))));
    /* tan(theta) from the receiver's cosine, capped; fmaxf(0, x) is max(x, 0) */
    simd_f c = simd_abs_f(cos_receiver);
    simd_f s = simd_sqrt_f(simd_max_f(simd_sub_f(one, simd_mul_f(c, c)), zero));
    simd_f tan_t = simd_select_f(simd_gt_f(c, simd_div_f(s, tanmax)), simd_div_f(s, c), tanmax);
    /* the stored code and the test */
    simd_f fi, fj;
    simd_i code = simd_gather_u16(map, rs_para_texel_lanes(R, u, v, &fi, &fj));
    simd_mask empty = simd_gt_i(code, simd_set1_i((int32_t)RS_PARA_MAX_CODE));
    simd_f decoded = simd_mul_f(simd_add_f(simd_i2f(code), one), simd_set1_f(range / RS_PARA_CODES));
    simd_f step2 = simd_set1_f(2.0f * range / RS_PARA_CODES);
    simd_f bias = simd_add_f(simd_mul_f(w, simd_add_f(one, tan_t)), step2);
    if (!plane) {
        simd_f limit = simd_add_f(decoded, simd_mul_f(simd_set1_f(bias_scale), bias));
        return simd_mask_and(front, simd_mask_or(empty, simd_le_f(dist, limit)));
    }
    /* the receiver-plane test: the plane's distance along the texel centre's ray */
    const simd_f Rf = simd_set1_f((float)R);
    simd_f uc = simd_div_f(simd_sub_f(simd_add_f(simd_add_f(fi, fi), one), Rf), Rf);
    simd_f vc = simd_div_f(simd_sub_f(simd_add_f(simd_add_f(fj, fj), one), Rf), Rf);
    simd_f rc = simd_add_f(simd_mul_f(uc, uc), simd_mul_f(vc, vc));
    simd_f mx = rs__para_dot(nx, ny, nz, f->t), my = rs__para_dot(nx, ny, nz, f->b);
    simd_f mz = rs__para_dot(nx, ny, nz, f->n);
    simd_f num = simd_add_f(simd_add_f(simd_mul_f(mx, lx), simd_mul_f(my, ly)), simd_mul_f(mz, lz));
    simd_f dn = simd_add_f(simd_add_f(simd_mul_f(mx, simd_add_f(uc, uc)), simd_mul_f(my, simd_add_f(vc, vc))),
                           simd_mul_f(mz, simd_sub_f(one, rc)));
    simd_f lo = simd_sub_f(dist, bias), hi = simd_add_f(dist, bias);
    simd_f sp = simd_div_f(simd_mul_f(num, simd_add_f(one, rc)), dn);
    simd_f cl = simd_select_f(simd_lt_f(sp, lo), lo, simd_select_f(simd_gt_f(sp, hi), hi, sp));
    simd_mask ok = simd_mask_and(simd_gt_f(simd_abs_f(dn), simd_set1_f(RS_PARA_PLANE_MIN_COS)), simd_gt_f(sp, zero));
    simd_f at = simd_select_f(ok, cl, lo);
    simd_f tol = simd_add_f(simd_mul_f(w, simd_set1_f(RS_PARA_PLANE_EPS)), step2);
    return simd_mask_and(front, simd_mask_or(empty, simd_le_f(at, simd_add_f(decoded, tol))));
}

#endif
