/* gi_direct_kernels: the shadow-mapped direct light of one row, SIMD_W
 * pixels at a time, written once over the SIMD vocabulary and compiled once
 * per instruction set (-DGI_DIRECT_KERNELS=gi_direct_kernels_<isa>; see
 * docs/raster.md "The SIMD vocabulary"). Per light: the unshadowed
 * irradiance of gi_light_irradiance lane-wise, then the 16-tap PCF lookup of
 * the pixels it reaches (rs_shadow_lookup.h, inlined); pixels the light
 * does not reach or that are fully shadowed add nothing, every pixel sums
 * its lights in the scene's order with gi_light_irradiance's and
 * rs_shadow_visibility's operations, so every path gives the same bits
 * (tests/test_shadow.c test_simd_matches_scalar compares the scalar compile
 * with the best one). The area lights' emitter points are added per pixel
 * by the scalar gi__direct_area_irradiance. */
#include "gi_direct_kernels.h"

#include <math.h>
#include <string.h>

#include "gi_light.h"
#include "rs_shadow_lookup.h"
#include "simd.h"

#ifndef GI_DIRECT_KERNELS
#error "compile with -DGI_DIRECT_KERNELS=<table name> (CMakeLists.txt)"
#endif

/* gi_light_irradiance for SIMD_W points (unit normals n): the irradiance's
 * three components and the mask of lanes it reaches, with the scalar
 * function's operations in its order (the spot factor's cosines are per
 * light, the same cosf calls as gi_light_spot_factor). */
static simd_mask gi__light_irradiance_w(const pf_light *L, simd_f px, simd_f py, simd_f pz, simd_f nx, simd_f ny,
                                        simd_f nz, simd_f irr[3])
{
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    simd_f wx, wy, wz, e0 = simd_set1_f(L->intensity);
    simd_mask ok = simd_mask_from_bits(SIMD_FULL);
    if (L->type == PF_LIGHT_DIRECTIONAL) {
        pf_vec3 wi = pf_v3_scale(L->direction, -1.0f);
        wx = simd_set1_f(wi.x), wy = simd_set1_f(wi.y), wz = simd_set1_f(wi.z);
    } else {
        simd_f dx = simd_sub_f(simd_set1_f(L->position.x), px);
        simd_f dy = simd_sub_f(simd_set1_f(L->position.y), py);
        simd_f dz = simd_sub_f(simd_set1_f(L->position.z), pz);
        simd_f r2 = rs__sdot(dx, dy, dz, dx, dy, dz);
        ok = simd_gt_f(r2, zero);
        simd_f inv = simd_div_f(one, simd_sqrt_f(r2));
        wx = simd_mul_f(dx, inv), wy = simd_mul_f(dy, inv), wz = simd_mul_f(dz, inv);
        e0 = simd_div_f(e0, r2);
        if (L->type == PF_LIGHT_SPOT) {
            /* gi_light_spot_factor(L, -dot(wi, direction)) */
            float cos_outer = cosf(L->outer_cone), cos_inner = cosf(L->inner_cone);
            float scale = 1.0f / fmaxf(0.001f, cos_inner - cos_outer);
            simd_f ca = simd_neg_f(rs__sdot(wx, wy, wz, simd_set1_f(L->direction.x), simd_set1_f(L->direction.y),
                                            simd_set1_f(L->direction.z)));
            simd_f t = simd_mul_f(simd_sub_f(ca, simd_set1_f(cos_outer)), simd_set1_f(scale));
            /* pf_clampf(t, 0, 1): t < 0 ? 0 : (t > 1 ? 1 : t) */
            t = simd_select_f(simd_lt_f(t, zero), zero, simd_select_f(simd_gt_f(t, one), one, t));
            e0 = simd_mul_f(e0, simd_mul_f(t, t));
        }
    }
    simd_f cos_t = rs__sdot(nx, ny, nz, wx, wy, wz);
    ok = simd_mask_and(ok, simd_mask_and(simd_gt_f(cos_t, zero), simd_gt_f(e0, zero)));
    simd_f k = simd_mul_f(e0, cos_t);
    irr[0] = simd_mul_f(simd_set1_f(L->color.x), k);
    irr[1] = simd_mul_f(simd_set1_f(L->color.y), k);
    irr[2] = simd_mul_f(simd_set1_f(L->color.z), k);
    return ok;
}

/* A G-buffer plane's SIMD_W values, zeros in the lanes without a surface:
 * a plain load when every lane has one (`whole`), the same values without
 * the masked load (slower on AMD Zen 3, docs/perf.md 2026-12-02 evening) */
static inline simd_f gi__load_live(const float *p, int whole, simd_mask live)
{
    return whole ? simd_loadu_f(p) : simd_maskz_loadu_f(p, live);
}

/* The n (<= SIMD_W) pixels from index i of the G-buffer: their triangles,
 * the lanes with a surface (the returned bits) and their positions, zeros
 * in the other lanes; masked loads only where the group is partial (a
 * whole group of surfaces, most of them, takes plain loads, the same
 * values). */
static inline uint32_t gi__group(const rs_gbuffer *g, size_t i, uint32_t n, simd_i *prims, simd_mask *live_lanes,
                                 simd_f *px, simd_f *py, simd_f *pz)
{
    const simd_mask in_row = simd_mask_from_bits(n == SIMD_W ? SIMD_FULL : (1u << n) - 1u);
    *prims = n == SIMD_W ? simd_loadu_i((const int32_t *)g->prim + i)
                         : simd_maskz_loadu_i((const int32_t *)g->prim + i, in_row);
    *live_lanes = simd_mask_and(in_row, simd_mask_not(simd_eq_i(*prims, simd_set1_i((int32_t)RS_GBUFFER_EMPTY))));
    const uint32_t live = simd_mask_bits(*live_lanes);
    if (!live) return 0;
    const int whole = live == SIMD_FULL;
    *px = gi__load_live(g->pos_x + i, whole, *live_lanes);
    *py = gi__load_live(g->pos_y + i, whole, *live_lanes);
    *pz = gi__load_live(g->pos_z + i, whole, *live_lanes);
    return live;
}

/* One row of the direct light (stage 2b): io->direct = irradiance x PCF
 * visibility x albedo / pi, emission added later by compose. */
static void gi__direct_row(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi_direct_io *io = ctx;
    const rs_gbuffer *g = io->gbuf;
    const pf_scene *s = io->scene;
    const uint32_t width = io->width;
    float *out = io->direct + (size_t)y * width * 3;
    memset(out, 0, (size_t)width * 3 * sizeof(float));
    uint32_t ng_prim = RS_GBUFFER_EMPTY;
    pf_vec3 ng = pf_v3(0.0f, 0.0f, 0.0f);
    const size_t row = (size_t)y * width;
    for (uint32_t x0 = 0; x0 < width; x0 += SIMD_W) {
        /* the pixels' G-buffer values, zeros in the lanes without a surface
         * (and past the row's end); the unit face normals from the
         * rasterizer's table (rs_resolve_tri.ng: pf_scene_face_normal's
         * operations, the same bits), else from the scene */
        float in[6][SIMD_W], ngv[3][SIMD_W], ev[3][SIMD_W];
        const uint32_t n = width - x0 < SIMD_W ? width - x0 : SIMD_W;
        simd_i prims;
        simd_mask live_lanes;
        simd_f px, py, pz;
        const uint32_t live = gi__group(g, row + x0, n, &prims, &live_lanes, &px, &py, &pz);
        if (!live) continue;
        const int whole = live == SIMD_FULL;
        const simd_f nx = gi__load_live(g->nrm_x + row + x0, whole, live_lanes);
        const simd_f ny = gi__load_live(g->nrm_y + row + x0, whole, live_lanes);
        const simd_f nz = gi__load_live(g->nrm_z + row + x0, whole, live_lanes);
        simd_f gx, gy, gz;
        if (io->tri_table) {
            const float *t0 = &io->tri_table[0].ng.x;
            const simd_i idx = simd_mullo_i(prims, simd_set1_i((int32_t)(sizeof(rs_resolve_tri) / sizeof(float))));
            gx = simd_maskz_gather_f(t0, idx, live_lanes);
            gy = simd_maskz_gather_f(t0 + 1, idx, live_lanes);
            gz = simd_maskz_gather_f(t0 + 2, idx, live_lanes);
        } else {
            for (uint32_t i = 0; i < SIMD_W; i++) {
                uint32_t p = (uint32_t)(live >> i & 1u) ? g->prim[row + x0 + i] : RS_GBUFFER_EMPTY;
                if (p != RS_GBUFFER_EMPTY && p != ng_prim) { /* runs of pixels share a triangle */
                    ng_prim = p;
                    ng = pf_scene_face_normal(s, ng_prim);
                }
                ngv[0][i] = p != RS_GBUFFER_EMPTY ? ng.x : 0.0f;
                ngv[1][i] = p != RS_GBUFFER_EMPTY ? ng.y : 0.0f;
                ngv[2][i] = p != RS_GBUFFER_EMPTY ? ng.z : 0.0f;
            }
            gx = simd_loadu_f(ngv[0]), gy = simd_loadu_f(ngv[1]), gz = simd_loadu_f(ngv[2]);
        }
        simd_f e[3] = {simd_zero_f(), simd_zero_f(), simd_zero_f()};
        for (uint32_t l = 0; l < s->light_count && l < io->shadow_count; l++) {
            simd_f irr[3];
            simd_mask reached =
                simd_mask_and(gi__light_irradiance_w(&s->lights[l], px, py, pz, nx, ny, nz, irr), live_lanes);
            if (!simd_mask_any(reached)) continue;
            const rs_shadow_map *m = &io->shadows[l];
            simd_f v;
            if (rs_shadow_lookup_eligible(m)) {
                v = rs_shadow_visibility_lanes(m, px, py, pz, gx, gy, gz, reached);
            } else { /* normal offset: the scalar lookup lane by lane */
                float vis[SIMD_W];
                simd_storeu_f(in[0], px), simd_storeu_f(in[1], py), simd_storeu_f(in[2], pz);
                simd_storeu_f(ngv[0], gx), simd_storeu_f(ngv[1], gy), simd_storeu_f(ngv[2], gz);
                uint32_t r = simd_mask_bits(reached);
                for (int i = 0; i < SIMD_W; i++)
                    vis[i] = r >> i & 1 ? rs_shadow_visibility(m, pf_v3(in[0][i], in[1][i], in[2][i]),
                                                                     pf_v3(ngv[0][i], ngv[1][i], ngv[2][i]))
                                              : 0.0f;
                v = simd_loadu_f(vis);
            }
            /* e += irradiance * vis where reached and vis > 0 */
            simd_mask take = simd_mask_and(reached, simd_gt_f(v, simd_zero_f()));
            for (int c = 0; c < 3; c++) e[c] = simd_select_f(take, simd_add_f(e[c], simd_mul_f(irr[c], v)), e[c]);
        }
        float *o = out + 3 * (size_t)x0;
        if (!io->area_maps) {
            /* direct = irradiance x albedo / pi, (e a) / pi as the scalar
             * code rounds it; the lanes without a surface hold 0 x 0 */
            const float *alb[3] = {g->alb_r, g->alb_g, g->alb_b};
            for (int c = 0; c < 3; c++)
                simd_storeu_f(ev[c], simd_mul_f(simd_mul_f(e[c], gi__load_live(alb[c] + row + x0, whole, live_lanes)),
                                                simd_set1_f(PF_INV_PI)));
            for (uint32_t i = 0; i < n; i++) o[3 * i] = ev[0][i], o[3 * i + 1] = ev[1][i], o[3 * i + 2] = ev[2][i];
            continue;
        }
        for (int c = 0; c < 3; c++) simd_storeu_f(ev[c], e[c]);
        simd_storeu_f(in[0], px), simd_storeu_f(in[1], py), simd_storeu_f(in[2], pz);
        simd_storeu_f(in[3], nx), simd_storeu_f(in[4], ny), simd_storeu_f(in[5], nz);
        for (uint32_t i = 0; i < SIMD_W; i++) {
            if (!((live >> i) & 1u)) continue;
            size_t p = row + x0 + i;
            pf_vec3 ea = gi__direct_area_irradiance(io->area_maps, pf_v3(in[0][i], in[1][i], in[2][i]),
                                                    pf_v3(in[3][i], in[4][i], in[5][i]));
            o[3 * i] = (ev[0][i] + ea.x) * g->alb_r[p] * PF_INV_PI;
            o[3 * i + 1] = (ev[1][i] + ea.y) * g->alb_g[p] * PF_INV_PI;
            o[3 * i + 2] = (ev[2][i] + ea.z) * g->alb_b[p] * PF_INV_PI;
        }
    }
}

/* The tiles row y's lookups read (stage 2a, before the maps are drawn):
 * gi__direct_row looks up the pixels with a surface that a light reaches;
 * this marks every pixel with a surface (a superset: the lights' reach
 * would cost the normals' loads, a square root and two divisions a lane,
 * and the tiles of the back-facing pixels are mostly needed by others
 * anyway: measured on the bench views, 1% more tiles), with the lookup's
 * own projection. */
static void gi__need_row(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi_direct_io *io = ctx;
    const rs_gbuffer *g = io->gbuf;
    const pf_scene *s = io->scene;
    const uint32_t width = io->width;
    const size_t row = (size_t)y * width;
    for (uint32_t x0 = 0; x0 < width; x0 += SIMD_W) {
        const uint32_t n = width - x0 < SIMD_W ? width - x0 : SIMD_W;
        simd_i prims;
        simd_mask live_lanes;
        simd_f px, py, pz;
        if (!gi__group(g, row + x0, n, &prims, &live_lanes, &px, &py, &pz)) continue;
        for (uint32_t l = 0; l < s->light_count && l < io->shadow_count; l++) {
            const rs_shadow_map *m = &io->shadows[l];
            if (!rs_shadow_marks_receivers(m)) continue; /* marked whole (gi_stage_shadow_maps) */
            rs_shadow_need_lanes(m, px, py, pz, live_lanes);
        }
    }
}

const gi_direct_kernels GI_DIRECT_KERNELS = {SIMD_NAME, gi__direct_row, gi__need_row};
