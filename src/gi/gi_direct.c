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

/* gi__direct_sm_row, 8 pixels at a time: per light the unshadowed
 * irradiance of each pixel (scalar gi_light_irradiance, as above), then the
 * shadow lookups of the pixels it reaches in one rs_shadow_visibility8 call
 * (the SIMD lookup, bit-identical to the scalar one); pixels the light does
 * not reach are skipped as above, and every pixel sums its lights in the
 * same order with the same operations, so the row's bits are the scalar
 * row's (tests/test_shadow.c test_simd_matches_scalar). */
static void gi__direct_sm_row8(void *ctx, uint32_t y, uint32_t worker)
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
        float px[8], py[8], pz[8], ngx[8], ngy[8], ngz[8], vis[8], e[8][3];
        pf_vec3 nrm[8];
        unsigned live = 0;
        memset(e, 0, sizeof e);
        for (uint32_t i = 0; i < 8; i++) {
            size_t p = (size_t)y * f->width + x0 + i;
            px[i] = py[i] = pz[i] = ngx[i] = ngy[i] = ngz[i] = 0.0f;
            nrm[i] = pf_v3(0.0f, 0.0f, 0.0f);
            if (x0 + i >= f->width || g->prim[p] == RS_GBUFFER_EMPTY) continue;
            px[i] = g->pos_x[p];
            py[i] = g->pos_y[p];
            pz[i] = g->pos_z[p];
            nrm[i] = pf_v3(g->nrm_x[p], g->nrm_y[p], g->nrm_z[p]);
            if (g->prim[p] != ng_prim) { /* runs of pixels share a triangle */
                ng_prim = g->prim[p];
                ng = pf_scene_face_normal(s, ng_prim);
            }
            ngx[i] = ng.x;
            ngy[i] = ng.y;
            ngz[i] = ng.z;
            live |= 1u << i;
        }
        if (!live) continue;
        for (uint32_t l = 0; l < s->light_count && l < f->shadows.count; l++) {
            gi_light_sample ls[8];
            unsigned reached = 0;
            for (uint32_t i = 0; i < 8; i++)
                if ((live >> i) & 1u && gi_light_irradiance(&s->lights[l], pf_v3(px[i], py[i], pz[i]), nrm[i], &ls[i]))
                    reached |= 1u << i;
            if (!reached) continue;
            rs_shadow_visibility8(&f->shadows.maps[l], simd, px, py, pz, ngx, ngy, ngz, reached, vis);
            for (uint32_t i = 0; i < 8; i++) {
                if (!((reached >> i) & 1u) || vis[i] <= 0.0f) continue;
                e[i][0] += ls[i].irradiance.x * vis[i];
                e[i][1] += ls[i].irradiance.y * vis[i];
                e[i][2] += ls[i].irradiance.z * vis[i];
            }
        }
        for (uint32_t i = 0; i < 8; i++) {
            if (!((live >> i) & 1u)) continue;
            size_t p = (size_t)y * f->width + x0 + i;
            if (f->area_maps.rendered) {
                pf_vec3 ea = gi__area_irradiance_maps(&f->area_maps, pf_v3(px[i], py[i], pz[i]), nrm[i]);
                e[i][0] += ea.x;
                e[i][1] += ea.y;
                e[i][2] += ea.z;
            }
            float *o = out + 3 * (size_t)(x0 + i);
            o[0] = e[i][0] * g->alb_r[p] * PF_INV_PI;
            o[1] = e[i][1] * g->alb_g[p] * PF_INV_PI;
            o[2] = e[i][2] * g->alb_b[p] * PF_INV_PI;
        }
    }
}

/* The scalar row is the reference; with a SIMD raster path the 8-wide rows
 * give the same bits. */
void gi_stage_direct_shadowmap(gi_frame *f)
{
    int simd = f->raster && rs_context_simd(f->raster) != RS_SIMD_SCALAR;
    pf_jobs_parallel_for(f->jobs, simd ? gi__direct_sm_row8 : gi__direct_sm_row, f, f->height, 1);
}
