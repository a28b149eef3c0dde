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
#include "simd.h" /* SIMD_X86 */

/* 1 if the box [lo, hi] lies inside [blo, bhi]. */
static int gi__box_inside(pf_vec3 lo, pf_vec3 hi, pf_vec3 blo, pf_vec3 bhi)
{
    return lo.x >= blo.x && lo.y >= blo.y && lo.z >= blo.z && hi.x <= bhi.x && hi.y <= bhi.y && hi.z <= bhi.z;
}

void gi_stage_shadow_maps(gi_frame *f)
{
    const pf_scene *s = f->scene;
    rs_shadow_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.size = f->shadow_size;
    pf_error err;
    gi_motion_stats *ms = &f->motion_stats;
    if (!f->shadows_rendered || f->shadow_lights.count != s->light_count || f->shadows.count != s->light_count) {
        /* first frame, or lights added/removed: all maps */
        if (f->shadows_rendered) {
            rs_shadow_set_free(&f->shadows);
            if (rs_shadow_set_init(&f->shadows, s, &desc, &err) != PF_OK) {
                fprintf(stderr, "softgi: shadow maps: %s\n", err.message);
                return;
            }
        }
        rs_shadow_set_render(f->raster, &f->shadows, NULL);
        f->shadow_bounds_lo = s->bounds_min, f->shadow_bounds_hi = s->bounds_max;
    } else {
        /* only the lights that changed: their map's kind, matrices and range
         * follow the light; static lights keep last frame's maps, drawn
         * again where moved geometry can change them (gi_motion.h): only
         * the tiles its bounds project to, or, for a directional light
         * whose box the posed scene left, a new box drawn whole */
        const gi_moved_box *mb = &f->moved_shadows;
        const int left = mb->pending && !gi__box_inside(s->bounds_min, s->bounds_max, f->shadow_bounds_lo,
                                                         f->shadow_bounds_hi);
        for (uint32_t i = 0; i < s->light_count; i++) {
            rs_shadow_map *m = &f->shadows.maps[i];
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
                continue;
            }
            rs_shadow_render(f->raster, m, 1, NULL);
        }
        if (left) f->shadow_bounds_lo = s->bounds_min, f->shadow_bounds_hi = s->bounds_max;
    }
    f->moved_shadows.pending = 0;
    if (!gi_light_copy_take(&f->shadow_lights, s)) {
        f->shadows_rendered = 0; /* render everything next frame */
        return;
    }
    f->shadows_rendered = 1;
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
 * path (gi_direct_kernels.c, written once over the SIMD vocabulary and
 * compiled per instruction set; the scalar compile is the reference the
 * others give the bits of). */
void gi_stage_direct_shadowmap(gi_frame *f)
{
    const gi_direct_kernels *k = &gi_direct_kernels_scalar;
#if SIMD_X86
    rs_simd simd = f->raster ? rs_context_simd(f->raster) : RS_SIMD_SCALAR;
    if (simd == RS_SIMD_AVX512) k = &gi_direct_kernels_avx512;
    if (simd == RS_SIMD_AVX2) k = &gi_direct_kernels_avx2;
#endif
    const gi_direct_io io = {f->scene,
                             &f->gbuf,
                             f->shadows.maps,
                             f->shadows.count,
                             f->area_maps.rendered ? &f->area_maps : NULL,
                             f->raster ? rs_context_resolve_table(f->raster) : NULL,
                             f->width,
                             f->direct};
    pf_jobs_parallel_for(f->jobs, k->row, (void *)&io, f->height, 1);
}
