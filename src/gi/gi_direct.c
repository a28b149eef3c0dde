/* gi_direct: direct light from shadow maps (Laine 2007 Sec. 3 step 5's
 * "direct illumination" with the shadow maps of Sec. 6): every light's
 * unshadowed irradiance (gi_light) times its shadow map's 16-tap PCF
 * visibility (rs_shadow_visibility), albedo / pi. The ray-traced
 * counterpart is gi_stage_direct_raytrace (--raytrace), the reference these
 * maps are tested against. One job item per row; each writes its own row. */
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
        out[3 * x + 0] = e[0] * g->alb_r[p] * PF_INV_PI;
        out[3 * x + 1] = e[1] * g->alb_g[p] * PF_INV_PI;
        out[3 * x + 2] = e[2] * g->alb_b[p] * PF_INV_PI;
    }
}

void gi_stage_direct_shadowmap(gi_frame *f) { pf_jobs_parallel_for(f->jobs, gi__direct_sm_row, f, f->height, 1); }
