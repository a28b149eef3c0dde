/* gi_indirect_kernels: the many-light accumulation and Laine's box filter,
 * SIMD_W pixels at a time, written once over the SIMD vocabulary and
 * compiled once per instruction set (-DGI_INDIRECT_KERNELS=
 * gi_indirect_kernels_<isa>; docs/raster.md "The SIMD vocabulary").
 *
 * Accumulation: gi_vpl_irradiance and the paraboloid lookup
 * (rs_para_lookup.h, the project's one lookup) lane-wise with the scalar
 * path's operations in its order (sqrt and division correctly rounded,
 * min/max/floor and the integer texel arithmetic exact), so every lane gets
 * the scalar loop's bits (tests/test_vpl.c compares every SIMD path with the
 * scalar one). The VPL loop is the outer one: one VPL's map serves all the
 * runs before the next is read; each pixel still adds its VPLs in the
 * tile's order, so its sum is the same.
 *
 * Filter: the scalar box filter's tests and sums, lane-wise, the window in
 * the scalar loop's order; rows outside the image are skipped for every
 * lane, as the scalar loop skips them.
 *
 * Upsampling (--indirect-scale): the joint upsampling's four samples
 * lane-wise (gi__upsample below).
 *
 * A-trous (--filter atrous): gi_atrous.c's box pass and level, lane-wise
 * with its operations in its order (gi_atrous_math.h's polynomial exp and
 * squarings); a tap the reference skips (no surface) adds +0 here. */
#include "gi_indirect_kernels.h"

#include <string.h>

#include "gi_atrous_math.h"
#include "rs_para_lookup.h"
#include "simd.h"

#ifndef GI_INDIRECT_KERNELS
#error "compile with -DGI_INDIRECT_KERNELS=<table name> (CMakeLists.txt)"
#endif

static simd_f gi__dot3(simd_f ax, simd_f ay, simd_f az, simd_f bx, simd_f by, simd_f bz)
{
    return simd_add_f(simd_add_f(simd_mul_f(ax, bx), simd_mul_f(ay, by)), simd_mul_f(az, bz));
}

static void gi__accumulate(const gi_accumulate_in *in, const float *px_, const float *py_, const float *pz_,
                           const float *nx_, const float *ny_, const float *nz_, uint32_t groups, uint32_t a0,
                           uint32_t a1, float *e)
{
    const uint32_t R = in->para_res;
    const size_t map = (size_t)R * R;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f), b = simd_set1_f(in->b);
    simd_f acc[GI_ACC_GROUPS][3];
    for (uint32_t g = 0; g < groups; g++) acc[g][0] = acc[g][1] = acc[g][2] = zero;
    for (uint32_t q = a0; q < a1; q++) {
        const uint32_t vi = in->assign[q];
        const gi_vpl *v = &in->vpls[vi];
        const simd_f vx = simd_set1_f(v->pos.x), vy = simd_set1_f(v->pos.y), vz = simd_set1_f(v->pos.z);
        const simd_f mx = simd_set1_f(v->nrm.x), my = simd_set1_f(v->nrm.y), mz = simd_set1_f(v->nrm.z);
        const simd_f ir = simd_set1_f(v->intensity.x), ig = simd_set1_f(v->intensity.y);
        const simd_f ib = simd_set1_f(v->intensity.z);
        const uint16_t *mp = in->atlas + vi * map;
        for (uint32_t g = 0; g < groups; g++) {
            const size_t o = (size_t)SIMD_W * g;
            const simd_f Px = simd_loadu_f(px_ + o), Py = simd_loadu_f(py_ + o), Pz = simd_loadu_f(pz_ + o);
            const simd_f Nx = simd_loadu_f(nx_ + o), Ny = simd_loadu_f(ny_ + o), Nz = simd_loadu_f(nz_ + o);
            /* gi_vpl_irradiance */
            simd_f dx = simd_sub_f(vx, Px), dy = simd_sub_f(vy, Py), dz = simd_sub_f(vz, Pz);
            simd_f r2 = gi__dot3(dx, dy, dz, dx, dy, dz);
            simd_mask ok = simd_gt_f(r2, zero);
            simd_f inv = simd_div_f(one, simd_sqrt_f(r2));
            simd_f wx = simd_mul_f(dx, inv), wy = simd_mul_f(dy, inv), wz = simd_mul_f(dz, inv);
            simd_f c1 = gi__dot3(Nx, Ny, Nz, wx, wy, wz);
            simd_f c2 = simd_sub_f(zero, gi__dot3(mx, my, mz, wx, wy, wz)); /* -dot: exact negation */
            ok = simd_mask_and(ok, simd_mask_and(simd_gt_f(c1, zero), simd_gt_f(c2, zero)));
            if (!simd_mask_bits(ok)) continue;
            simd_f G = simd_div_f(simd_mul_f(c1, c2), r2);
            G = simd_select_f(simd_gt_f(G, b), b, G); /* the bounded geometry term */
            /* the VPL's map (rs_para_visible_scaled lane-wise), receiver cosine n . w */
            simd_mask vis = simd_mask_and(ok, rs_para_visible_lanes(mp, R, in->range, in->bias_scale, &in->frames[vi],
                                                                    Px, Py, Pz, c1, in->plane, Nx, Ny, Nz));
            acc[g][0] = simd_add_f(acc[g][0], simd_select_f(vis, simd_mul_f(ir, G), zero));
            acc[g][1] = simd_add_f(acc[g][1], simd_select_f(vis, simd_mul_f(ig, G), zero));
            acc[g][2] = simd_add_f(acc[g][2], simd_select_f(vis, simd_mul_f(ib, G), zero));
        }
    }
    for (uint32_t g = 0; g < groups; g++) {
        float c[3][SIMD_W];
        for (int ch = 0; ch < 3; ch++) simd_storeu_f(c[ch], acc[g][ch]);
        for (uint32_t i = 0; i < SIMD_W; i++)
            for (int ch = 0; ch < 3; ch++) e[3 * (SIMD_W * g + i) + ch] = c[ch][i];
    }
}

/* Laine's box test (Fig. 5) of the window pixels j.. against the run's
 * pixels: a surface, |p_j - p|^2 < alpha^2 and n_j . n > beta; with cap2 > 0
 * the tangent-plane test in place of the distance one, (n . (p_j - p))^2 <
 * alpha^2 and |p_j - p|^2 < cap2 (gi_filter_near). */
static simd_mask gi__laine_take(const rs_gbuffer *g, size_t j, simd_f px, simd_f py, simd_f pz, simd_f nx, simd_f ny,
                                simd_f nz, simd_f a2, simd_f beta, float cap2, simd_i empty)
{
    simd_mask valid = simd_mask_not(simd_eq_i(simd_loadu_i((const int32_t *)(g->prim + j)), empty));
    simd_f ddx = simd_sub_f(simd_loadu_f(g->pos_x + j), px);
    simd_f ddy = simd_sub_f(simd_loadu_f(g->pos_y + j), py);
    simd_f ddz = simd_sub_f(simd_loadu_f(g->pos_z + j), pz);
    simd_f d2 = gi__dot3(ddx, ddy, ddz, ddx, ddy, ddz);
    simd_f nd = gi__dot3(nx, ny, nz, simd_loadu_f(g->nrm_x + j), simd_loadu_f(g->nrm_y + j), simd_loadu_f(g->nrm_z + j));
    simd_mask near;
    if (cap2 > 0.0f) {
        simd_f dp = gi__dot3(ddx, ddy, ddz, nx, ny, nz);
        near = simd_mask_and(simd_lt_f(simd_mul_f(dp, dp), a2), simd_lt_f(d2, simd_set1_f(cap2)));
    } else {
        near = simd_lt_f(d2, a2);
    }
    return simd_mask_and(valid, simd_mask_and(near, simd_gt_f(nd, beta)));
}

static void gi__filter_box(const gi_filter_in *in, int x, int y, float *out)
{
    const rs_gbuffer *g = in->g;
    const int H = (int)in->h, n = (int)in->n, m = (int)in->m;
    const size_t i0 = (size_t)y * in->w + (size_t)x;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    const simd_f a2 = simd_set1_f(in->alpha2), beta = simd_set1_f(in->beta);
    const simd_f px = simd_loadu_f(g->pos_x + i0), py = simd_loadu_f(g->pos_y + i0), pz = simd_loadu_f(g->pos_z + i0);
    const simd_f nx = simd_loadu_f(g->nrm_x + i0), ny = simd_loadu_f(g->nrm_y + i0), nz = simd_loadu_f(g->nrm_z + i0);
    const simd_i empty = simd_set1_i((int32_t)RS_GBUFFER_EMPTY);
    simd_f ar = zero, ag = zero, ab = zero, ws = zero;
    for (int dy = 0; dy < m; dy++) {
        int ty = y + dy - m / 2;
        if (ty < 0 || ty >= H) continue;
        for (int dx = 0; dx < n; dx++) {
            size_t j = (size_t)ty * in->w + (size_t)(x + dx - n / 2);
            simd_mask take = gi__laine_take(g, j, px, py, pz, nx, ny, nz, a2, beta, in->cap2, empty);
            simd_f er, eg, eb; /* the run's RGB triples, de-interleaved */
            simd_load3_f(in->combined + 3 * j, &er, &eg, &eb);
            ar = simd_add_f(ar, simd_select_f(take, er, zero));
            ag = simd_add_f(ag, simd_select_f(take, eg, zero));
            ab = simd_add_f(ab, simd_select_f(take, eb, zero));
            ws = simd_add_f(ws, simd_select_f(take, one, zero));
        }
    }
    float r[SIMD_W], gg[SIMD_W], bb[SIMD_W], w[SIMD_W];
    simd_storeu_f(r, ar), simd_storeu_f(gg, ag), simd_storeu_f(bb, ab), simd_storeu_f(w, ws);
    for (int k = 0; k < SIMD_W; k++) {
        size_t i = i0 + (size_t)k;
        float *o = out + 3 * (size_t)k;
        if (g->prim[i] == RS_GBUFFER_EMPTY || !(w[k] > 0.0f)) memcpy(o, in->combined + 3 * i, 3 * sizeof(float));
        else o[0] = r[k] / w[k], o[1] = gg[k] / w[k], o[2] = bb[k] / w[k];
    }
}

/* The joint upsampling's four samples, lane-wise with gi__upsample_row's
 * operations (gi_indirect.c, the reference): a sample that is skipped there
 * adds +0 here, which changes no sum (a sum of products of non-negative
 * weights and irradiances is never -0). The reduced samples of a run lie in
 * at most SIMD_W consecutive reduced columns (s >= 2), so each plane is one
 * load per reduced row and one permutation per sample instead of gathers. */
static uint32_t gi__upsample(const gi_upsample_in *in, uint32_t x, uint32_t y, float *out)
{
    const rs_gbuffer *g = in->g;
    const uint32_t s = in->s, w = in->w, h = in->h;
    const float inv_s = 1.0f / (float)s;
    const uint32_t Y0 = y / s, Y1 = Y0 + 1 < h ? Y0 + 1 : Y0, base = x / s;
    const float ty = (float)(y - Y0 * s) * inv_s;
    /* each lane's two reduced columns and its fraction, as the scalar code */
    int32_t i0[SIMD_W], i1[SIMD_W];
    float txa[SIMD_W];
    for (uint32_t l = 0, X0 = base, r = x - base * s; l < SIMD_W; l++) { /* X0 = (x + l) / s, r its remainder */
        uint32_t X1 = X0 + 1 < w ? X0 + 1 : X0;
        i0[l] = (int32_t)(X0 - base), i1[l] = (int32_t)(X1 - base);
        txa[l] = (float)r * inv_s; /* (float)(x + l - X0 s) * inv_s */
        if (++r == s) r = 0, X0++;
    }
    const simd_i idx[2] = {simd_loadu_i(i0), simd_loadu_i(i1)};
    const simd_f one = simd_set1_f(1.0f), zero = simd_zero_f(), tx = simd_loadu_f(txa), tyv = simd_set1_f(ty);
    const simd_f bw[4] = {simd_mul_f(simd_sub_f(one, tx), simd_sub_f(one, tyv)), simd_mul_f(tx, simd_sub_f(one, tyv)),
                          simd_mul_f(simd_sub_f(one, tx), tyv), simd_mul_f(tx, tyv)};
    const size_t i = (size_t)y * in->W + x;
    const simd_i empty = simd_set1_i((int32_t)RS_GBUFFER_EMPTY);
    const simd_mask covered = simd_mask_not(simd_eq_i(simd_loadu_i((const int32_t *)g->prim + i), empty));
    const simd_f px = simd_loadu_f(g->pos_x + i), py = simd_loadu_f(g->pos_y + i), pz = simd_loadu_f(g->pos_z + i);
    const simd_f nx = simd_loadu_f(g->nrm_x + i), ny = simd_loadu_f(g->nrm_y + i), nz = simd_loadu_f(g->nrm_z + i);
    const simd_f a2 = simd_set1_f(in->a2), beta = simd_set1_f(in->beta);
    simd_f acc[3] = {zero, zero, zero}, wsum = zero;
    for (int r = 0; r < 2; r++) {
        const size_t k = (size_t)(r ? Y1 : Y0) * w + base;
        const simd_i lp = simd_loadu_i((const int32_t *)in->lprim + k);
        const simd_f lx = simd_loadu_f(in->lpx + k), ly = simd_loadu_f(in->lpy + k), lz = simd_loadu_f(in->lpz + k);
        const simd_f mx = simd_loadu_f(in->lnx + k), my = simd_loadu_f(in->lny + k), mz = simd_loadu_f(in->lnz + k);
        simd_f e[3];
        simd_load3_f(in->le + 3 * k, &e[0], &e[1], &e[2]);
        for (int c = 0; c < 2; c++) { /* sample (X0 or X1, this row): bw[2 r + c] */
            const simd_i ix = idx[c];
            simd_f dx = simd_sub_f(simd_permute_f(lx, ix), px), dy = simd_sub_f(simd_permute_f(ly, ix), py);
            simd_f dz = simd_sub_f(simd_permute_f(lz, ix), pz);
            simd_f d2 = gi__dot3(dx, dy, dz, dx, dy, dz);
            simd_f nd = gi__dot3(nx, ny, nz, simd_permute_f(mx, ix), simd_permute_f(my, ix), simd_permute_f(mz, ix));
            const simd_f b = bw[2 * r + c];
            simd_mask ok = simd_mask_and(simd_mask_and(covered, simd_gt_f(b, zero)),
                                         simd_mask_not(simd_eq_i(simd_permute_i(lp, ix), empty)));
            ok = simd_mask_and(ok, simd_mask_and(simd_lt_f(d2, a2), simd_gt_f(nd, beta)));
            for (int ch = 0; ch < 3; ch++)
                acc[ch] = simd_add_f(acc[ch], simd_select_f(ok, simd_mul_f(b, simd_permute_f(e[ch], ix)), zero));
            wsum = simd_add_f(wsum, simd_select_f(ok, b, zero));
        }
    }
    const simd_mask has = simd_gt_f(wsum, zero);
    float o[3][SIMD_W];
    for (int ch = 0; ch < 3; ch++) simd_storeu_f(o[ch], simd_select_f(has, simd_div_f(acc[ch], wsum), zero));
    for (uint32_t l = 0; l < SIMD_W; l++) out[3 * l] = o[0][l], out[3 * l + 1] = o[1][l], out[3 * l + 2] = o[2][l];
    return simd_mask_bits(simd_mask_andnot(covered, has));
}


/* ------------------------------------------------ a-trous (gi_atrous.c) */

static void gi__atrous_box(const gi_filter_in *in, int x, int y, const gi_atrous_planes *o)
{
    const rs_gbuffer *g = in->g;
    const int H = (int)in->h, n = (int)in->n, m = (int)in->m;
    const size_t i0 = (size_t)y * in->w + (size_t)x;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    const simd_f a2 = simd_set1_f(in->alpha2), beta = simd_set1_f(in->beta);
    const simd_f lr = simd_set1_f(GI_ATROUS_LR), lg = simd_set1_f(GI_ATROUS_LG), lb = simd_set1_f(GI_ATROUS_LB);
    const simd_f px = simd_loadu_f(g->pos_x + i0), py = simd_loadu_f(g->pos_y + i0), pz = simd_loadu_f(g->pos_z + i0);
    const simd_f nx = simd_loadu_f(g->nrm_x + i0), ny = simd_loadu_f(g->nrm_y + i0), nz = simd_loadu_f(g->nrm_z + i0);
    const simd_i empty = simd_set1_i((int32_t)RS_GBUFFER_EMPTY);
    simd_f ar = zero, ag = zero, ab = zero, l1 = zero, l2 = zero, ws = zero;
    for (int dy = 0; dy < m; dy++) {
        int ty = y + dy - m / 2;
        if (ty < 0 || ty >= H) continue;
        for (int dx = 0; dx < n; dx++) {
            size_t j = (size_t)ty * in->w + (size_t)(x + dx - n / 2);
            simd_mask take = gi__laine_take(g, j, px, py, pz, nx, ny, nz, a2, beta, in->cap2, empty);
            simd_f er, eg, eb;
            simd_load3_f(in->combined + 3 * j, &er, &eg, &eb);
            simd_f l = gi__dot3(lr, lg, lb, er, eg, eb);
            ar = simd_add_f(ar, simd_select_f(take, er, zero));
            ag = simd_add_f(ag, simd_select_f(take, eg, zero));
            ab = simd_add_f(ab, simd_select_f(take, eb, zero));
            l1 = simd_add_f(l1, simd_select_f(take, l, zero));
            l2 = simd_add_f(l2, simd_select_f(take, simd_mul_f(l, l), zero));
            ws = simd_add_f(ws, simd_select_f(take, one, zero));
        }
    }
    float r[SIMD_W], gg[SIMD_W], bb[SIMD_W], s1[SIMD_W], s2[SIMD_W], w[SIMD_W];
    simd_storeu_f(r, ar), simd_storeu_f(gg, ag), simd_storeu_f(bb, ab);
    simd_storeu_f(s1, l1), simd_storeu_f(s2, l2), simd_storeu_f(w, ws);
    for (int k = 0; k < SIMD_W; k++) { /* gi__atrous_box_pixel's ending */
        size_t i = i0 + (size_t)k;
        const float *c = in->combined + 3 * i;
        float R = c[0], G = c[1], B = c[2], var = 0.0f;
        if (g->prim[i] != RS_GBUFFER_EMPTY && w[k] > 0.0f) {
            float cnt = w[k];
            R = r[k] / cnt, G = gg[k] / cnt, B = bb[k] / cnt;
            float mean = s1[k] / cnt, v = s2[k] / cnt - mean * mean;
            var = cnt > 1.0f && v > 0.0f ? v / (cnt - 1.0f) : 0.0f;
        }
        o->r[i] = R, o->g[i] = G, o->b[i] = B, o->lum[i] = gi_atrous_lum(R, G, B), o->var[i] = var;
    }
}

/* gi_atrous_expneg lane-wise */
static simd_f gi__expneg(simd_f t)
{
    simd_f y = simd_min_f(simd_mul_f(t, simd_set1_f(GI_ATROUS_LOG2E)), simd_set1_f(125.0f));
    simd_f n = simd_floor_f(y), f = simd_sub_f(y, n);
    simd_f p = simd_add_f(simd_mul_f(simd_set1_f(GI_ATROUS_C5), f), simd_set1_f(GI_ATROUS_C4));
    p = simd_add_f(simd_mul_f(p, f), simd_set1_f(GI_ATROUS_C3));
    p = simd_add_f(simd_mul_f(p, f), simd_set1_f(GI_ATROUS_C2));
    p = simd_add_f(simd_mul_f(p, f), simd_set1_f(GI_ATROUS_C1));
    p = simd_add_f(simd_mul_f(p, f), simd_set1_f(1.0f));
    simd_i bits = simd_slli_i(simd_sub_i(simd_set1_i(127), simd_f2i_trunc(n)), 23);
    return simd_mul_f(p, simd_asfloat_i(bits));
}

static void gi__atrous_level(const gi_atrous_in *lv, int x, int y)
{
    const rs_gbuffer *g = lv->g;
    const int H = (int)lv->h, s = lv->step;
    const size_t i0 = (size_t)y * lv->w + (size_t)x;
    const gi_atrous_planes *src = &lv->src, *dst = &lv->dst;
    const simd_f zero = simd_zero_f();
    const simd_f px = simd_loadu_f(g->pos_x + i0), py = simd_loadu_f(g->pos_y + i0), pz = simd_loadu_f(g->pos_z + i0);
    const simd_f nx = simd_loadu_f(g->nrm_x + i0), ny = simd_loadu_f(g->nrm_y + i0), nz = simd_loadu_f(g->nrm_z + i0);
    const simd_f li = simd_loadu_f(src->lum + i0), isp = simd_set1_f(lv->inv_sigma_p);
    const simd_f inv_sd = simd_loadu_f(lv->inv_sd + i0);
    const simd_i empty = simd_set1_i((int32_t)RS_GBUFFER_EMPTY);
    simd_f ar = zero, ag = zero, ab = zero, ws = zero, vs = zero;
    for (int a = 0; a < 3; a++) {
        int ty = y + (a - 1) * s;
        if (ty < 0 || ty >= H) continue;
        for (int b = 0; b < 3; b++) {
            size_t j = (size_t)ty * lv->w + (size_t)(x + (b - 1) * s);
            simd_mask valid = simd_mask_not(simd_eq_i(simd_loadu_i((const int32_t *)(g->prim + j)), empty));
            simd_f dp = gi__dot3(nx, ny, nz, simd_sub_f(simd_loadu_f(g->pos_x + j), px),
                                 simd_sub_f(simd_loadu_f(g->pos_y + j), py), simd_sub_f(simd_loadu_f(g->pos_z + j), pz));
            simd_f c = gi__dot3(nx, ny, nz, simd_loadu_f(g->nrm_x + j), simd_loadu_f(g->nrm_y + j),
                                simd_loadu_f(g->nrm_z + j));
            simd_f wn = simd_max_f(c, zero);
            for (int k = 0; k < 7; k++) wn = simd_mul_f(wn, wn);
            simd_f inv_dl = simd_min_f(inv_sd, simd_loadu_f(lv->inv_sd + j));
            simd_f t = simd_add_f(simd_mul_f(simd_abs_f(dp), isp),
                                  simd_mul_f(simd_abs_f(simd_sub_f(li, simd_loadu_f(src->lum + j))), inv_dl));
            simd_f w = simd_mul_f(simd_mul_f(simd_set1_f(gi_atrous_h[a] * gi_atrous_h[b]), wn), gi__expneg(t));
            w = simd_select_f(valid, w, zero);
            ar = simd_add_f(ar, simd_mul_f(w, simd_loadu_f(src->r + j)));
            ag = simd_add_f(ag, simd_mul_f(w, simd_loadu_f(src->g + j)));
            ab = simd_add_f(ab, simd_mul_f(w, simd_loadu_f(src->b + j)));
            ws = simd_add_f(ws, w);
            vs = simd_add_f(vs, simd_mul_f(simd_mul_f(w, w), simd_loadu_f(src->var + j)));
        }
    }
    /* lanes with no surface or no weight keep their pixel (the reference's early exits) */
    simd_mask keep = simd_mask_or(simd_eq_i(simd_loadu_i((const int32_t *)(g->prim + i0)), empty),
                                  simd_mask_not(simd_gt_f(ws, zero)));
    simd_f inv = simd_div_f(simd_set1_f(1.0f), simd_select_f(keep, simd_set1_f(1.0f), ws));
    simd_f r = simd_mul_f(ar, inv), gg = simd_mul_f(ag, inv), b = simd_mul_f(ab, inv);
    simd_f l = gi__dot3(simd_set1_f(GI_ATROUS_LR), simd_set1_f(GI_ATROUS_LG), simd_set1_f(GI_ATROUS_LB), r, gg, b);
    simd_f v = simd_mul_f(simd_mul_f(vs, inv), inv);
    simd_storeu_f(dst->r + i0, simd_select_f(keep, simd_loadu_f(src->r + i0), r));
    simd_storeu_f(dst->g + i0, simd_select_f(keep, simd_loadu_f(src->g + i0), gg));
    simd_storeu_f(dst->b + i0, simd_select_f(keep, simd_loadu_f(src->b + i0), b));
    simd_storeu_f(dst->lum + i0, simd_select_f(keep, li, l));
    simd_storeu_f(dst->var + i0, simd_select_f(keep, simd_loadu_f(src->var + i0), v));
}

const gi_indirect_kernels GI_INDIRECT_KERNELS = {SIMD_NAME,       SIMD_W,           gi__accumulate,
                                                 gi__filter_box,  gi__upsample,     gi__atrous_box,
                                                 gi__atrous_level};
