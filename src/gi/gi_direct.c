/* gi_direct: direct light from shadow maps (Laine 2007 Sec. 3 step 5's
 * "direct illumination" with the shadow maps of Sec. 6): every light's
 * unshadowed irradiance (gi_light) times its shadow map's 16-tap PCF
 * visibility (rs_shadow_visibility), albedo / pi. The ray-traced
 * counterpart is gi_stage_direct_raytrace (--raytrace), the reference these
 * maps are tested against. One job item per row; each writes its own row.
 *
 * Area lights (emissive triangles, gi_area.h): K fixed points on the
 * emitters, each a cosine emitter of intensity Le A_k with its own
 * paraboloid shadow map (rs_paraboloid.h), rendered once and reused (see
 * gi_frame.h "Area lights" for the quadrature and its error). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "gi_light.h"

void gi_stage_shadow_maps(gi_frame *f)
{
    const pf_scene *s = f->scene;
    rs_shadow_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.size = f->shadow_size;
    pf_error err;
    if (!f->shadows_rendered || f->shadow_light_count != s->light_count || f->shadows.count != s->light_count) {
        /* first frame, or lights added/removed: all maps */
        if (f->shadows_rendered) {
            rs_shadow_set_free(&f->shadows);
            if (rs_shadow_set_init(&f->shadows, s, &desc, &err) != PF_OK) {
                fprintf(stderr, "softgi: shadow maps: %s\n", err.message);
                return;
            }
        }
        rs_shadow_set_render(f->raster, &f->shadows, NULL);
    } else {
        /* only the lights that changed: their map's kind, matrices and range
         * follow the light; static lights keep last frame's maps */
        for (uint32_t i = 0; i < s->light_count; i++) {
            if (memcmp(&f->shadow_lights[i], &s->lights[i], sizeof(pf_light)) == 0) continue;
            rs_shadow_map *m = &f->shadows.maps[i];
            rs_shadow_map_free(m);
            if (rs_shadow_map_init(m, s, i, &desc, &err) != PF_OK) {
                fprintf(stderr, "softgi: shadow map of light %u: %s\n", i, err.message);
                memset(m, 0, sizeof *m);
                continue;
            }
            rs_shadow_render(f->raster, m, 1, NULL);
        }
    }
    pf_light *copy = realloc(f->shadow_lights, sizeof(pf_light) * (s->light_count ? s->light_count : 1));
    if (!copy) {
        f->shadows_rendered = 0; /* render everything next frame */
        return;
    }
    f->shadow_lights = copy;
    if (s->light_count) memcpy(f->shadow_lights, s->lights, sizeof(pf_light) * s->light_count);
    f->shadow_light_count = s->light_count;
    f->shadows_rendered = 1;
}

void gi_stage_area_shadow_maps(gi_frame *f)
{
    gi_area_maps *m = &f->area_maps;
    if (m->count == 0 || m->rendered) return; /* emitters do not move: drawn once */
    pf_vec3 pos[64], nrm[64];
    size_t map = (size_t)RS_PARA_DEFAULT_RES * RS_PARA_DEFAULT_RES;
    for (uint32_t k0 = 0; k0 < m->count; k0 += 64) {
        uint32_t n = m->count - k0 < 64 ? m->count - k0 : 64;
        for (uint32_t k = 0; k < n; k++) {
            pos[k] = m->frames[k0 + k].o;
            nrm[k] = m->frames[k0 + k].n;
        }
        rs_para_render(m->atlas + k0 * map, m->para, f->jobs, pos, nrm, n, m->range, NULL);
    }
    m->rendered = 1;
}

/* Irradiance at (pos, nrm) from the K emitter points, each visible per its
 * paraboloid map: sum_k Le A_k cos_r cos_e / r^2 V_k. */
static pf_vec3 gi__area_irradiance_maps(const gi_area_maps *m, pf_vec3 pos, pf_vec3 nrm)
{
    size_t map = (size_t)RS_PARA_DEFAULT_RES * RS_PARA_DEFAULT_RES;
    pf_vec3 e = pf_v3(0, 0, 0);
    for (uint32_t k = 0; k < m->count; k++) {
        const rs_para_frame *fr = &m->frames[k];
        pf_vec3 d = pf_v3_sub(fr->o, pos);
        float r2 = pf_v3_dot(d, d);
        if (!(r2 > 0.0f)) continue;
        float r = sqrtf(r2);
        pf_vec3 w = pf_v3_scale(d, 1.0f / r);
        float cr = pf_v3_dot(nrm, w), ce = -pf_v3_dot(fr->n, w);
        if (!(cr > 0.0f) || !(ce > 0.0f)) continue;
        if (!rs_para_visible_at(m->atlas + k * map, RS_PARA_DEFAULT_RES, m->range, fr, pos, cr)) continue;
        e = pf_v3_add(e, pf_v3_scale(m->weight[k], cr * ce / r2));
    }
    return e;
}

static void gi__direct_sm_row(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    gi_frame *f = ctx;
    const rs_gbuffer *g = &f->gbuf;
    const pf_scene *s = f->scene;
    float *out = f->direct + (size_t)y * f->width * 3;
    memset(out, 0, (size_t)f->width * 3 * sizeof(float));
    for (uint32_t x = 0; x < f->width; x++) {
        size_t p = (size_t)y * f->width + x;
        if (g->prim[p] == RS_GBUFFER_EMPTY) continue;
        pf_vec3 pos = pf_v3(g->pos_x[p], g->pos_y[p], g->pos_z[p]);
        pf_vec3 nrm = pf_v3(g->nrm_x[p], g->nrm_y[p], g->nrm_z[p]);
        pf_vec3 ng = pf_scene_face_normal(s, g->prim[p]);
        float e[3] = {0, 0, 0};
        for (uint32_t l = 0; l < s->light_count && l < f->shadows.count; l++) {
            gi_light_sample ls;
            if (!gi_light_irradiance(&s->lights[l], pos, nrm, &ls)) continue;
            float vis = rs_shadow_visibility(&f->shadows.maps[l], pos, ng);
            if (vis <= 0.0f) continue;
            e[0] += ls.irradiance.x * vis;
            e[1] += ls.irradiance.y * vis;
            e[2] += ls.irradiance.z * vis;
        }
        if (f->area_maps.rendered) {
            pf_vec3 ea = gi__area_irradiance_maps(&f->area_maps, pos, nrm);
            e[0] += ea.x;
            e[1] += ea.y;
            e[2] += ea.z;
        }
        out[3 * x + 0] = e[0] * g->alb_r[p] * PF_INV_PI;
        out[3 * x + 1] = e[1] * g->alb_g[p] * PF_INV_PI;
        out[3 * x + 2] = e[2] * g->alb_b[p] * PF_INV_PI;
    }
}

/* gi__direct_sm_row, 8 pixels at a time with AVX2: per light the unshadowed
 * irradiance (gi__light_irradiance8, gi_light_irradiance lane-wise), then
 * the shadow lookups of the pixels it reaches in one rs_shadow_visibility8
 * call (bit-identical to the scalar lookup); pixels the light does not
 * reach or that are fully shadowed are skipped as in the scalar row, and
 * every pixel sums its lights in the same order with the same operations,
 * so the row's bits are the scalar row's (tests/test_shadow.c
 * test_simd_matches_scalar). */
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define GI__DIRECT_X86 1

/* gi_light_irradiance for 8 points (unit normals n): the irradiance's three
 * components and the mask of lanes it reaches, with the scalar function's
 * operations in its order (the spot factor's cosines are per light, the
 * same cosf calls as gi_light_spot_factor). */
__attribute__((target("avx2"))) static __m256 gi__light_irradiance8(const pf_light *L, __m256 px, __m256 py,
                                                                   __m256 pz, __m256 nx, __m256 ny, __m256 nz,
                                                                   __m256 irr[3])
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 wx, wy, wz, e0 = _mm256_set1_ps(L->intensity), ok = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    if (L->type == PF_LIGHT_DIRECTIONAL) {
        pf_vec3 wi = pf_v3_scale(L->direction, -1.0f);
        wx = _mm256_set1_ps(wi.x), wy = _mm256_set1_ps(wi.y), wz = _mm256_set1_ps(wi.z);
    } else {
        __m256 dx = _mm256_sub_ps(_mm256_set1_ps(L->position.x), px);
        __m256 dy = _mm256_sub_ps(_mm256_set1_ps(L->position.y), py);
        __m256 dz = _mm256_sub_ps(_mm256_set1_ps(L->position.z), pz);
        __m256 r2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
        ok = _mm256_cmp_ps(r2, zero, _CMP_GT_OQ);
        __m256 inv = _mm256_div_ps(one, _mm256_sqrt_ps(r2));
        wx = _mm256_mul_ps(dx, inv), wy = _mm256_mul_ps(dy, inv), wz = _mm256_mul_ps(dz, inv);
        e0 = _mm256_div_ps(e0, r2);
        if (L->type == PF_LIGHT_SPOT) {
            /* gi_light_spot_factor(L, -dot(wi, direction)) */
            float cos_outer = cosf(L->outer_cone), cos_inner = cosf(L->inner_cone);
            float scale = 1.0f / fmaxf(0.001f, cos_inner - cos_outer);
            __m256 ca = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wx, _mm256_set1_ps(L->direction.x)),
                                                    _mm256_mul_ps(wy, _mm256_set1_ps(L->direction.y))),
                                      _mm256_mul_ps(wz, _mm256_set1_ps(L->direction.z)));
            ca = _mm256_xor_ps(ca, _mm256_set1_ps(-0.0f));
            __m256 t = _mm256_mul_ps(_mm256_sub_ps(ca, _mm256_set1_ps(cos_outer)), _mm256_set1_ps(scale));
            /* pf_clampf(t, 0, 1): t < 0 ? 0 : (t > 1 ? 1 : t) */
            t = _mm256_blendv_ps(_mm256_blendv_ps(t, one, _mm256_cmp_ps(t, one, _CMP_GT_OQ)), zero,
                                 _mm256_cmp_ps(t, zero, _CMP_LT_OQ));
            e0 = _mm256_mul_ps(e0, _mm256_mul_ps(t, t));
        }
    }
    __m256 cos_t = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, wx), _mm256_mul_ps(ny, wy)), _mm256_mul_ps(nz, wz));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(cos_t, zero, _CMP_GT_OQ), _mm256_cmp_ps(e0, zero, _CMP_GT_OQ)));
    __m256 k = _mm256_mul_ps(e0, cos_t);
    irr[0] = _mm256_mul_ps(_mm256_set1_ps(L->color.x), k);
    irr[1] = _mm256_mul_ps(_mm256_set1_ps(L->color.y), k);
    irr[2] = _mm256_mul_ps(_mm256_set1_ps(L->color.z), k);
    return ok;
}

__attribute__((target("avx2"))) static void gi__direct_sm_row8(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    gi_frame *f = ctx;
    const rs_gbuffer *g = &f->gbuf;
    const pf_scene *s = f->scene;
    const rs_simd simd = rs_context_simd(f->raster);
    float *out = f->direct + (size_t)y * f->width * 3;
    memset(out, 0, (size_t)f->width * 3 * sizeof(float));
    uint32_t ng_prim = RS_GBUFFER_EMPTY;
    pf_vec3 ng = pf_v3(0.0f, 0.0f, 0.0f);
    for (uint32_t x0 = 0; x0 < f->width; x0 += 8) {
        /* the 8 pixels' G-buffer values (zeros past the row's end) */
        float in[6][8], ngv[3][8], ev[3][8];
        unsigned live = 0;
        const float *planes[6] = {g->pos_x, g->pos_y, g->pos_z, g->nrm_x, g->nrm_y, g->nrm_z};
        for (uint32_t i = 0; i < 8; i++) {
            size_t p = (size_t)y * f->width + x0 + i;
            int on = x0 + i < f->width && g->prim[p] != RS_GBUFFER_EMPTY;
            for (int c = 0; c < 6; c++) in[c][i] = on ? planes[c][p] : 0.0f;
            if (on && g->prim[p] != ng_prim) { /* runs of pixels share a triangle */
                ng_prim = g->prim[p];
                ng = pf_scene_face_normal(s, ng_prim);
            }
            ngv[0][i] = on ? ng.x : 0.0f;
            ngv[1][i] = on ? ng.y : 0.0f;
            ngv[2][i] = on ? ng.z : 0.0f;
            live |= (unsigned)on << i;
        }
        if (!live) continue;
        const __m256 px = _mm256_loadu_ps(in[0]), py = _mm256_loadu_ps(in[1]), pz = _mm256_loadu_ps(in[2]);
        const __m256 nx = _mm256_loadu_ps(in[3]), ny = _mm256_loadu_ps(in[4]), nz = _mm256_loadu_ps(in[5]);
        __m256 e[3] = {_mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps()};
        for (uint32_t l = 0; l < s->light_count && l < f->shadows.count; l++) {
            __m256 irr[3];
            unsigned reached =
                (unsigned)_mm256_movemask_ps(gi__light_irradiance8(&s->lights[l], px, py, pz, nx, ny, nz, irr)) & live;
            if (!reached) continue;
            float vis[8];
            rs_shadow_visibility8(&f->shadows.maps[l], simd, in[0], in[1], in[2], ngv[0], ngv[1], ngv[2], reached,
                                  vis);
            /* e += irradiance * vis where reached and vis > 0 (skipped
             * lanes keep e untouched, as the scalar `continue` does) */
            __m256 v = _mm256_loadu_ps(vis);
            const __m256i bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            __m256 take = _mm256_castsi256_ps(
                _mm256_cmpeq_epi32(_mm256_and_si256(bits, _mm256_set1_epi32((int)reached)), bits));
            take = _mm256_and_ps(take, _mm256_cmp_ps(v, _mm256_setzero_ps(), _CMP_GT_OQ));
            for (int c = 0; c < 3; c++) e[c] = _mm256_blendv_ps(e[c], _mm256_add_ps(e[c], _mm256_mul_ps(irr[c], v)), take);
        }
        for (int c = 0; c < 3; c++) _mm256_storeu_ps(ev[c], e[c]);
        for (uint32_t i = 0; i < 8; i++) {
            if (!((live >> i) & 1u)) continue;
            size_t p = (size_t)y * f->width + x0 + i;
            float ex = ev[0][i], ey = ev[1][i], ez = ev[2][i];
            if (f->area_maps.rendered) {
                pf_vec3 ea = gi__area_irradiance_maps(&f->area_maps, pf_v3(in[0][i], in[1][i], in[2][i]),
                                                      pf_v3(in[3][i], in[4][i], in[5][i]));
                ex += ea.x;
                ey += ea.y;
                ez += ea.z;
            }
            float *o = out + 3 * (size_t)(x0 + i);
            o[0] = ex * g->alb_r[p] * PF_INV_PI;
            o[1] = ey * g->alb_g[p] * PF_INV_PI;
            o[2] = ez * g->alb_b[p] * PF_INV_PI;
        }
    }
}
#endif

/* The scalar row is the reference; with a SIMD raster path the 8-wide rows
 * give the same bits. */
void gi_stage_direct_shadowmap(gi_frame *f)
{
#ifdef GI__DIRECT_X86
    if (f->raster && rs_context_simd(f->raster) != RS_SIMD_SCALAR) {
        pf_jobs_parallel_for(f->jobs, gi__direct_sm_row8, f, f->height, 1);
        return;
    }
#endif
    pf_jobs_parallel_for(f->jobs, gi__direct_sm_row, f, f->height, 1);
}
