/* gi_motion: a frame brought up to date for moved geometry (see
 * gi_motion.h for what is redone and how). */
#include "gi_frame.h"
#include "gi_ism.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GI__STATIC_MAX ((size_t)1 << 30) /* the largest static-map atlas (gi_frame_declare_dynamic) */

/* The reports merged into *ranges (count entries, instanced primitive k at
 * k): `moved` where any report moved it, the bounds the union. A report of
 * another length starts the merge afresh. 0 when out of memory. */
static int gi__ranges_merge(pf_anim_moved **ranges, uint32_t *have, int fresh, const pf_anim_moved *moved,
                            uint32_t count)
{
    if (*have != count) {
        pf_anim_moved *rg = realloc(*ranges, sizeof *rg * (count ? count : 1));
        if (!rg) return 0;
        *ranges = rg;
        *have = count;
        fresh = 1;
    }
    for (uint32_t k = 0; k < count; k++) {
        pf_anim_moved *g = &(*ranges)[k];
        if (fresh) memset(g, 0, sizeof *g);
        if (!moved[k].moved) {
            if (!g->moved) *g = moved[k];
            continue;
        }
        if (!g->moved) {
            *g = moved[k];
            g->moved = 1;
            continue;
        }
        g->before_min = pf_v3_min(g->before_min, moved[k].before_min);
        g->before_max = pf_v3_max(g->before_max, moved[k].before_max);
        g->after_min = pf_v3_min(g->after_min, moved[k].after_min);
        g->after_max = pf_v3_max(g->after_max, moved[k].after_max);
    }
    return 1;
}

static int gi__box_add(gi_moved_box *b, pf_vec3 lo, pf_vec3 hi, const pf_anim_moved *moved, uint32_t count)
{
    if (!gi__ranges_merge(&b->ranges, &b->range_count, !b->pending, moved, count)) return 0;
    if (!b->pending) b->lo = lo, b->hi = hi;
    else b->lo = pf_v3_min(b->lo, lo), b->hi = pf_v3_max(b->hi, hi);
    b->pending = 1;
    return 1;
}

static int gi__emissive(const pf_scene *s, uint32_t t)
{
    const float *e = s->materials[s->tri_material[t]].emission;
    return e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f;
}

pf_result gi_frame_declare_dynamic(gi_frame *f, const pf_anim_moved *ranges, uint32_t count, pf_error *err)
{
    gi_indirect *ind = &f->ind;
    if (!f->indirect || !ind->para) return PF_OK; /* no exact VPL maps */
    int grew = 0;
    pf_result r = rs_para_set_dynamic(ind->para, ranges, count, &grew, err);
    if (r != PF_OK) return r;
    if (!grew) return PF_OK;
    /* the static maps double the maps' memory: kept up to GI__STATIC_MAX
     * bytes (32768 VPLs at 128^2); beyond, or when the allocation fails,
     * the maps are drawn without them (rs_para_render_box) */
    size_t bytes = rs_para_atlas_bytes(ind->opt.para_res, ind->opt.vpls);
    if (!ind->static_atlas && bytes <= GI__STATIC_MAX) ind->static_atlas = malloc(bytes);
    ind->static_stale = 1; /* the kept maps' static maps are drawn at the next VPL maps stage */
    return PF_OK;
}

pf_result gi_frame_geometry_moved(gi_frame *f, const pf_anim_moved *moved, uint32_t count, pf_error *err)
{
    const pf_scene *s = f->scene;
    /* check every range first, so a bad report changes nothing */
    uint32_t n = 0;
    pf_vec3 lo = pf_v3(INFINITY, INFINITY, INFINITY), hi = pf_v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t k = 0; k < count; k++) {
        const pf_anim_moved *m = &moved[k];
        if (!m->moved) continue;
        if (m->tri_first > s->tri_count || m->tri_count > s->tri_count - m->tri_first ||
            m->vertex_first > s->vertex_count || m->vertex_count > s->vertex_count - m->vertex_first)
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "moved geometry: triangles %u..+%u, vertices %u..+%u outside the scene's %u, %u",
                                m->tri_first, m->tri_count, m->vertex_first, m->vertex_count, s->tri_count,
                                s->vertex_count);
        lo = pf_v3_min(lo, pf_v3_min(m->before_min, m->after_min));
        hi = pf_v3_max(hi, pf_v3_max(m->before_max, m->after_max));
        n++;
    }
    if (!n) return PF_OK;
    pf_result r = PF_OK;
    /* the VPL method's record: which triangles, where, and whether an
     * emitter is among them */
    gi_motion *mo = &f->motion;
    if (!mo->tri_moved) {
        mo->tri_moved = calloc(s->tri_count ? s->tri_count : 1, 1);
        if (!mo->tri_moved) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the moved triangles");
        mo->tri_count = s->tri_count;
    }
    if (!gi__ranges_merge(&mo->ranges, &mo->range_count, 0, moved, count))
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the moved geometry's ranges");
    const int fresh = !mo->moved && !mo->emitters; /* nothing recorded since the method last looked */
    int emitters = 0;
    for (uint32_t k = 0; k < count; k++) {
        const pf_anim_moved *m = &moved[k];
        if (!m->moved) continue;
        for (uint32_t t = m->tri_first; t < m->tri_first + m->tri_count; t++) {
            mo->moved += !mo->tri_moved[t];
            mo->tri_moved[t] = 1;
            if (f->area.count && gi__emissive(s, t)) emitters = 1;
        }
    }
    if (fresh) mo->lo = lo, mo->hi = hi;
    else mo->lo = pf_v3_min(mo->lo, lo), mo->hi = pf_v3_max(mo->hi, hi);
    mo->epoch++;
    mo->emitters |= emitters;

    /* the frame's own copies of the triangles */
    if (f->area_maps.para && (r = rs_para_context_update(f->area_maps.para, s, moved, count, err)) != PF_OK)
        goto failed;
    if (f->indirect && f->ind.para && (r = rs_para_context_update(f->ind.para, s, moved, count, err)) != PF_OK)
        goto failed;
    if ((r = gi_frame_declare_dynamic(f, moved, count, err)) != PF_OK) goto failed; /* what moved may move again */
    if (f->indirect && f->ind.ism && (r = gi_ism_update(f->ind.ism, s, moved, count, err)) != PF_OK) goto failed;

    /* area lights: a moved emitter is sampled again (new points, new maps,
     * drawn whole at the next frame); otherwise the K maps catch up with
     * the box */
    if (emitters) {
        gi_area_lights_free(&f->area);
        if ((r = gi_area_lights_build(&f->area, s, err)) != PF_OK) goto failed;
        if ((r = gi_frame_set_area_sampling(f, f->area_strata, f->area_points, err)) != PF_OK) goto failed;
        f->moved_area.pending = 0;
    } else if (f->area_maps.rendered && !gi__box_add(&f->moved_area, lo, hi, moved, count)) {
        goto oom;
    }
    if (f->shadows_rendered && !gi__box_add(&f->moved_shadows, lo, hi, moved, count)) goto oom;
    if (f->indirect && f->ind.para && f->ind.atlas_slots && !gi__box_add(&f->moved_maps, lo, hi, moved, count))
        goto oom;
    return PF_OK;
oom:
    r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the moved geometry's ranges");
failed: /* the frame's copies are part-updated: the caller makes the frame again */
    return r;
}
