/* gi_direct: direct light from shadow maps (Laine 2007 Sec. 3 step 5's
 * "direct illumination" with the shadow maps of Sec. 6): every light's
 * unshadowed irradiance (gi_light) times its shadow map's 16-tap PCF
 * visibility (rs_shadow_visibility; the rows are gi_direct_kernels.c, SIMD_W
 * pixels at a time), albedo / pi. The ray-traced
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

#include "gi_direct_kernels.h"
#include "gi_frame.h"
#include "gi_light.h"
#include "rs_shadow_lookup.h" /* rs_shadow_marks_receivers */
#include "simd.h" /* SIMD_X86 */

/* 1 if the box [lo, hi] lies inside [blo, bhi]. */
static int gi__box_inside(pf_vec3 lo, pf_vec3 hi, pf_vec3 blo, pf_vec3 bhi)
{
    return lo.x >= blo.x && lo.y >= blo.y && lo.z >= blo.z && hi.x <= bhi.x && hi.y <= bhi.y && hi.z <= bhi.z;
}

/* The direct light's row kernels for the frame's SIMD path
 * (gi_direct_kernels.c, written once over the SIMD vocabulary and compiled
 * per instruction set; the scalar compile is the reference the others give
 * the bits of), and what they read and write. */
static const gi_direct_kernels *gi__direct_kernels(const gi_frame *f)
{
    const gi_direct_kernels *k = &gi_direct_kernels_scalar;
#if SIMD_X86
    rs_simd simd = f->raster ? rs_context_simd(f->raster) : RS_SIMD_SCALAR;
    if (simd == RS_SIMD_AVX512) k = &gi_direct_kernels_avx512;
    if (simd == RS_SIMD_AVX2) k = &gi_direct_kernels_avx2;
#endif
    return k;
}

static gi_direct_io gi__direct_io(const gi_frame *f)
{
    const gi_direct_io io = {f->scene,
                             &f->gbuf,
                             f->shadows.maps,
                             f->shadows.count,
                             f->area_maps.rendered ? &f->area_maps : NULL,
                             f->raster ? rs_context_resolve_table(f->raster) : NULL,
                             f->width,
                             f->direct};
    return io;
}

/* Which lights changed since the maps were drawn (the frame's first
 * sample): a changed light's map takes the light's kind, matrices and
 * range with none of its tiles valid; static lights keep their tiles,
 * drawn again where moved geometry can change them (gi_motion.h): the
 * valid tiles its bounds project to, or, for a directional light whose box
 * the posed scene left, a new box. */
static void gi__shadow_lights(gi_frame *f)
{
    const pf_scene *s = f->scene;
    rs_shadow_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.size = f->shadow_size;
    pf_error err;
    gi_motion_stats *ms = &f->motion_stats;
    if (!f->shadows_rendered || f->shadow_lights.count != s->light_count || f->shadows.count != s->light_count) {
        /* lights added or removed: new maps; the first frame (or the one
         * after the lights could not be copied): the maps set up afresh for
         * the lights as they are now; nothing valid either way */
        if (f->shadows_rendered || f->shadows.count != s->light_count) {
            rs_shadow_set_free(&f->shadows);
            if (rs_shadow_set_init(&f->shadows, s, &desc, &err) != PF_OK) {
                fprintf(stderr, "softgi: shadow maps: %s\n", err.message);
                return;
            }
        } else {
            for (uint32_t i = 0; i < f->shadows.count; i++)
                if (rs_shadow_map_update(&f->shadows.maps[i], s, i, &desc, &err) != PF_OK) {
                    fprintf(stderr, "softgi: shadow map of light %u: %s\n", i, err.message);
                    memset(&f->shadows.maps[i], 0, sizeof f->shadows.maps[i]);
                }
        }
        f->shadow_bounds_lo = s->bounds_min, f->shadow_bounds_hi = s->bounds_max;
    } else {
        const gi_moved_box *mb = &f->moved_shadows;
        const int left = mb->pending && !gi__box_inside(s->bounds_min, s->bounds_max, f->shadow_bounds_lo,
                                                         f->shadow_bounds_hi);
        for (uint32_t i = 0; i < s->light_count; i++) {
            rs_shadow_map *m = &f->shadows.maps[i];
            m->fresh = 0; /* set again by rs_shadow_map_update */
            int changed = !gi_light_copy_same(&f->shadow_lights, s, i);
            if (!changed && left && m->kind == RS_SHADOW_ORTHO) changed = 1, ms->shadow_faces_whole++;
            if (!changed) {
                if (mb->pending)
                    ms->shadow_faces += rs_shadow_render_box(f->raster, m, 1, mb->lo, mb->hi, &ms->shadow_texels, NULL);
                continue;
            }
            if (rs_shadow_map_update(m, s, i, &desc, &err) != PF_OK) {
                fprintf(stderr, "softgi: shadow map of light %u: %s\n", i, err.message);
                memset(m, 0, sizeof *m);
            }
        }
        if (left) f->shadow_bounds_lo = s->bounds_min, f->shadow_bounds_hi = s->bounds_max;
    }
    f->moved_shadows.pending = 0;
    if (!gi_light_copy_take(&f->shadow_lights, s)) {
        f->shadows_rendered = 0; /* everything again next frame */
        return;
    }
    f->shadows_rendered = 1;
}

/* Stage 2a, once per sample (the receivers move with the jitter): the
 * lights' changes at the frame's first, then the tiles to draw where they
 * are not valid yet (rs_shadow_render_needed):
 * - a fresh map (its light new or changed this frame): the tiles this
 *   sample's lookups read, marked from the G-buffer with the lookup's own
 *   projection (gi_direct_kernels.c need_row), so a moving light draws only
 *   what the view needs and a first frame comes sooner;
 * - a map whose light stayed: every tile, i.e. the rest of it once, after
 *   which the light costs nothing (no marking, nothing drawn) while it
 *   stays, whatever the camera does.
 * A lookup reads valid tiles only. */
void gi_stage_shadow_maps(gi_frame *f)
{
    if (gi_aa_first_render(&f->aa)) gi__shadow_lights(f);
    if (!f->shadows.maps) return;
    rs_shadow_need_clear(f->shadows.maps, f->shadows.count);
    int mark = 0;
    for (uint32_t l = 0; l < f->shadows.count; l++) {
        rs_shadow_map *m = &f->shadows.maps[l];
        if (rs_shadow_marks_receivers(m))
            mark = 1;
        else
            rs_shadow_need_all(m);
    }
    if (mark) {
        const gi_direct_io io = gi__direct_io(f);
        pf_jobs_parallel_for(f->jobs, gi__direct_kernels(f)->need_row, (void *)&io, f->height, 4);
    }
    f->motion_stats.shadow_tiles += rs_shadow_render_needed(f->raster, f->shadows.maps, f->shadows.count, NULL);
}

void gi_stage_area_shadow_maps(gi_frame *f)
{
    gi_area_maps *m = &f->area_maps;
    gi_moved_box *mb = &f->moved_area;
    m->plane = !f->area_slope;
    if (m->count == 0 || (m->rendered && !mb->pending)) return; /* drawn once, again where geometry moved */
    pf_vec3 pos[64], nrm[64];
    size_t map = (size_t)RS_PARA_DEFAULT_RES * RS_PARA_DEFAULT_RES;
    for (uint32_t k0 = 0; k0 < m->count; k0 += 64) {
        uint32_t n = m->count - k0 < 64 ? m->count - k0 : 64;
        for (uint32_t k = 0; k < n; k++) {
            pos[k] = m->frames[k0 + k].o;
            nrm[k] = m->frames[k0 + k].n;
        }
        if (!m->rendered) {
            rs_para_render(m->atlas + k0 * map, m->para, f->jobs, pos, nrm, n, m->range, NULL);
        } else {
            rs_para_stats st;
            rs_para_render_box(m->atlas + k0 * map, m->para, f->jobs, pos, nrm, NULL, n, m->range, mb->lo, mb->hi,
                               mb->ranges, mb->range_count, &st);
            f->motion_stats.area_maps += st.maps;
        }
    }
    m->rendered = 1;
    mb->pending = 0;
}

/* Irradiance at (pos, nrm) from the K emitter points, each visible per its
 * paraboloid map: sum_k Le A_k cos_r cos_e / r^2 V_k. Called per pixel by
 * the row kernels (gi_direct_kernels.c). */
pf_vec3 gi__direct_area_irradiance(const gi_area_maps *m, pf_vec3 pos, pf_vec3 nrm)
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
        if (!rs_para_visible_scaled(m->atlas + k * map, RS_PARA_DEFAULT_RES, m->range, fr, pos, m->plane ? &nrm : NULL,
                                    cr, 1.0f))
            continue;
        e = pf_v3_add(e, pf_v3_scale(m->weight[k], cr * ce / r2));
    }
    return e;
}

/* Stage 2b: one job item per row, each the row kernel of the frame's SIMD
 * path. */
void gi_stage_direct_shadowmap(gi_frame *f)
{
    const gi_direct_io io = gi__direct_io(f);
    pf_jobs_parallel_for(f->jobs, gi__direct_kernels(f)->row, (void *)&io, f->height, 1);
}
