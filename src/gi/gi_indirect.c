/* gi_indirect: the many-light stages of a frame (see gi_indirect.h). */
#include "gi_indirect.h"
#include "gi_indirect_kernels.h"
#include "pf_random.h"
#include "simd.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"


#define GI__DEFAULT_CLAMP 400.0f
#define GI__MAPS_CHUNK 64u /* VPL maps rendered between two progress reports */
#define GI__COMP_MAX_TAPS 1024u /* clamp compensation: taps per pixel at most */
/* Paraboloid maps are 2 bytes a texel: 32768 maps of 128^2 = 1 GiB. */
#define GI__MAX_MAP_BYTES ((size_t)4 << 30)


typedef struct gi__lumkey {
    float lum;
    uint32_t index;
} gi__lumkey;

pf_result gi_indirect_init(gi_frame *f, const gi_indirect_options *opt_in, pf_error *err)
{
    gi_indirect *ind = &f->ind;
    memset(ind, 0, sizeof *ind);
    gi_indirect_options o = *opt_in;
    if (!o.method) o.method = &gi_method_ir;
    if (!o.vpls) o.vpls = 256;
    if (!o.bounces) o.bounces = 3;
    if (!o.tiles_n) o.tiles_n = 4;
    if (!o.tiles_m) o.tiles_m = 4;
    if (o.no_interleave) o.tiles_n = o.tiles_m = 1;
    if (o.clamp < 0.0f) o.clamp = GI__DEFAULT_CLAMP;
    if (!(o.alpha_rel > 0.0f)) o.alpha_rel = 0.02f;
    if (!(o.beta > 0.0f)) o.beta = 0.8f;
    if (o.visibility_ism && o.visibility_raytrace)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--visibility: give one of paraboloid, ism or raytrace");
    if (o.visibility_ism) o.para_res = o.ism.resolution ? o.ism.resolution : GI_ISM_DEFAULT_RES;
    if (!o.para_res) o.para_res = RS_PARA_DEFAULT_RES;
    o.scale = gi_indirect_scale_for(o.scale, f->width, f->height);
    if (o.temporal == 1 || o.temporal > GI_INDIRECT_MAX_TEMPORAL)
        return pf_error_set(err, PF_ERR_ARGUMENT, "temporal accumulation over %u frames: expected 0 (off) or 2..%u",
                            o.temporal, GI_INDIRECT_MAX_TEMPORAL);
    if (o.scale > GI_INDIRECT_MAX_SCALE)
        return pf_error_set(err, PF_ERR_ARGUMENT, "indirect-light scale %u: expected 1..%u", o.scale,
                            GI_INDIRECT_MAX_SCALE);
    if (!o.cycle) o.cycle = 1;
    if (o.cycle > GI_INDIRECT_MAX_CYCLE)
        return pf_error_set(err, PF_ERR_ARGUMENT, "VPL cycling over %u slices: expected 0 or 1 (off) or 2..%u",
                            o.cycle, GI_INDIRECT_MAX_CYCLE);
    if (o.cycle > 1 && !o.temporal)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "VPL cycling (--vpl-cycle %u) needs --temporal N: without the history each frame "
                            "would show one slice of the VPLs",
                            o.cycle);
    if (o.cycle > 1 && o.visibility_ism)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "VPL cycling (--vpl-cycle) keeps every VPL's map; imperfect shadow maps are remade "
                            "every frame: use --visibility paraboloid or raytrace");
    if ((uint64_t)o.vpls * o.cycle > GI_INDIRECT_MAX_SET)
        return pf_error_set(err, PF_ERR_ARGUMENT, "%u VPLs a frame cycled over %u slices: a set of more than %u VPLs",
                            o.vpls, o.cycle, GI_INDIRECT_MAX_SET);
    if (o.cycle_maps && o.cycle < 2)
        return pf_error_set(err, PF_ERR_ARGUMENT, "the progressive warm-up (--cycle-maps %u) needs --vpl-cycle C",
                            o.cycle_maps);
    ind->cycle = o.cycle;
    /* the progressive warm-up only where there are maps to draw */
    ind->cycle_live = o.cycle_maps && !o.visibility_raytrace ? 1u : o.cycle;
    o.vpls *= o.cycle; /* from here on the whole set */
    ind->opt = o;
    ind->bias_scale = 1.0f;
    const pf_scene *s = f->scene;
    float diag = pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min));
    ind->b = gi_clamp_bound(s, o.clamp);
    ind->alpha = o.alpha_rel * diag;
    ind->n = o.tiles_n;
    ind->m = o.tiles_m;
    pf_result r = o.method->create(&ind->method_state, &o.params, err);
    if (r != PF_OK) return r;
    uint32_t T = ind->n * ind->m, G = T * o.cycle; /* tiles; groups of VPLs */
    ind->scale = o.scale;
    ind->w = (f->width + o.scale - 1) / o.scale;
    ind->h = (f->height + o.scale - 1) / o.scale;
    size_t px = (size_t)ind->w * ind->h;
    pf_arena *mem = &ind->mem;
    ind->tile_x0 = pf_arena_calloc(mem, T + 1, sizeof(uint32_t));
    ind->tile_w = pf_arena_calloc(mem, T, sizeof(uint32_t));
    ind->tile_h = pf_arena_calloc(mem, T, sizeof(uint32_t));
    ind->assign_start = pf_arena_calloc(mem, G + 1, sizeof(uint32_t));
    ind->map_ok = pf_arena_calloc(mem, o.vpls, 1);
    ind->assign = pf_arena_calloc(mem, o.vpls, sizeof(uint32_t));
    ind->tile_of = pf_arena_calloc(mem, o.vpls, sizeof(uint32_t));
    ind->assigned_id = pf_arena_calloc(mem, o.vpls, sizeof(uint32_t));
    float **planes[] = {&ind->split_px, &ind->split_py, &ind->split_pz, &ind->split_nx, &ind->split_ny, &ind->split_nz};
    for (size_t k = 0; k < 6; k++) *planes[k] = pf_arena_calloc(mem, px, sizeof(float));
    ind->split_valid = pf_arena_calloc(mem, px, sizeof(uint32_t));
    ind->split_e = pf_arena_calloc(mem, 3 * px, sizeof(float));
    ind->combined = pf_arena_calloc(mem, 3 * px, sizeof(float));
    ind->filtered = pf_arena_calloc(mem, 3 * (size_t)f->width * f->height, sizeof(float));
    if (o.compensate) {
        if (!o.compensate_taps) o.compensate_taps = 32;
        if (o.compensate_taps > GI__COMP_MAX_TAPS)
            return pf_error_set(err, PF_ERR_ARGUMENT, "clamp compensation with %u taps: expected 1..%u",
                                o.compensate_taps, GI__COMP_MAX_TAPS);
        ind->opt.compensate_taps = o.compensate_taps;
        if (!(ind->comp = pf_arena_calloc(mem, 3 * px, sizeof(float))))
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the clamp compensation");
    }
    if (o.filter == GI_FILTER_ATROUS) {
        if (o.atrous.levels > GI_ATROUS_MAX_LEVELS)
            return pf_error_set(err, PF_ERR_ARGUMENT, "a-trous filter with %u levels: expected 0..%u",
                                o.atrous.levels, GI_ATROUS_MAX_LEVELS);
        if (!(ind->atrous_scratch = pf_arena_calloc(mem, gi_atrous_scratch_floats(ind->w, ind->h), sizeof(float))))
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the a-trous filter");
    }
    if (o.temporal) { /* at the indirect stages' size (gi_stage_temporal) */
        size_t fpx = px;
        for (int b = 0; b < 2; b++) {
            ind->hist[b] = pf_arena_calloc(mem, 3 * fpx, sizeof(float));
            ind->hist_n[b] = pf_arena_calloc(mem, fpx, sizeof(uint16_t));
            ind->hist_prim[b] = pf_arena_calloc(mem, fpx, sizeof(uint32_t));
            for (int c = 0; c < 3; c++) {
                ind->hist_p[b][c] = pf_arena_calloc(mem, fpx, sizeof(float));
                ind->hist_nrm[b][c] = pf_arena_calloc(mem, fpx, sizeof(float));
                if (!ind->hist_p[b][c] || !ind->hist_nrm[b][c])
                    return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the temporal history");
            }
            if (!ind->hist[b] || !ind->hist_n[b] || !ind->hist_prim[b])
                return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the temporal history");
        }
    }
    if (o.scale > 1) {
        ind->filtered_low = pf_arena_calloc(mem, 3 * px, sizeof(float));
        r = rs_gbuffer_init(&ind->low, ind->w, ind->h, err);
        if (r != PF_OK) return r;
    }
    int ok = ind->tile_x0 && ind->tile_w && ind->tile_h && ind->assign_start && ind->assign && ind->split_valid &&
             ind->split_e && ind->combined && ind->filtered && (o.scale == 1 || ind->filtered_low) && ind->tile_of &&
             ind->assigned_id && ind->map_ok;
    for (size_t k = 0; k < 6; k++) ok = ok && *planes[k];
    if (ok && !o.visibility_raytrace && rs_para_atlas_bytes(o.para_res, o.vpls) > GI__MAX_MAP_BYTES)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "%u VPLs need %.1f GiB of %ux%u paraboloid maps (softgi allows %.0f GiB); use fewer VPLs "
                            "or --visibility raytrace",
                            o.vpls, (double)rs_para_atlas_bytes(o.para_res, o.vpls) / (1u << 30), o.para_res,
                            o.para_res, (double)GI__MAX_MAP_BYTES / (1u << 30));
    if (ok && !o.visibility_raytrace) {
        if (o.visibility_ism) {
            r = gi_ism_create(&ind->ism, s, &o.ism, f->jobs ? pf_jobs_thread_count(f->jobs) : 1, err);
            if (r != PF_OK) return r;
            ind->bias_scale = gi_ism_bias_scale(ind->ism);
        } else {
            ind->plane = !o.para_slope;
            rs_para_options po;
            memset(&po, 0, sizeof po);
            po.resolution = o.para_res;
            r = rs_para_context_create(&ind->para, s, &po, err);
            if (r != PF_OK) return r;
        }
        /* +64 bytes: the SIMD accumulation gathers 4 bytes at a 2-byte texel */
        ind->atlas = pf_arena_alloc(mem, rs_para_atlas_bytes(o.para_res, o.vpls) + 64);
        ind->frames = pf_arena_calloc(mem, o.vpls, sizeof(rs_para_frame));
        ind->range = rs_para_default_range(s);
        ok = ind->atlas && ind->frames;
    }
    if (!ok) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the indirect-light buffers");
    /* tile (i, j): columns i, i + n, ... and rows j, j + m, ... */
    uint32_t off = 0;
    for (uint32_t j = 0; j < ind->m; j++)
        for (uint32_t i = 0; i < ind->n; i++) {
            uint32_t t = j * ind->n + i;
            ind->tile_w[t] = ind->w > i ? (ind->w - i + ind->n - 1) / ind->n : 0;
            ind->tile_h[t] = ind->h > j ? (ind->h - j + ind->m - 1) / ind->m : 0;
            ind->tile_x0[t] = off;
            off += ind->tile_w[t] * ind->tile_h[t];
        }
    ind->tile_x0[T] = off;
    return PF_OK;
}

void gi_indirect_free(gi_indirect *ind)
{
    if (ind->opt.method && ind->method_state) ind->opt.method->destroy(ind->method_state);
    gi_vpl_set_free(&ind->vpls);
    gi_vpl_set_free(&ind->vpls_next);
    rs_para_context_destroy(ind->para);
    free(ind->static_atlas);
    gi_ism_destroy(ind->ism);
    rs_gbuffer_free(&ind->low);
    pf_arena_release(&ind->mem); /* every buffer above */
    memset(ind, 0, sizeof *ind);
}

float gi_clamp_bound(const pf_scene *scene, float clamp)
{
    float diag = pf_v3_length(pf_v3_sub(scene->bounds_max, scene->bounds_min));
    return clamp > 0.0f ? clamp / (diag * diag) : INFINITY;
}

uint32_t gi_split_index(const gi_indirect *ind, uint32_t width, uint32_t x, uint32_t y)
{
    (void)width;
    uint32_t t = (y % ind->m) * ind->n + (x % ind->n);
    return ind->tile_x0[t] + (y / ind->m) * ind->tile_w[t] + x / ind->n;
}

/* ---------------------------------------------------------- 3. VPL update */

/* The method's update into `out`; a failure renders without VPLs and says
 * so (only out-of-memory can fail once init succeeded). */
static int gi__finite3(pf_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* The frame's contract on a method's VPL set, checked after every update so
 * no method can make a later stage read out of bounds: at most the budget
 * (the stages' buffers are sized for it), finite positions, unit normals and
 * finite, non-negative intensities. An entry that breaks it (e.g. a slot a
 * method keeps free, with no surface behind it) is kept in its slot but made
 * inert: zero intensity, a valid frame for its map. */
static void gi__vpl_check(gi_indirect *ind, gi_vpl_set *out)
{
    if (out->count > ind->opt.vpls) out->count = ind->opt.vpls;
    for (uint32_t i = 0; i < out->count; i++) {
        gi_vpl *v = &out->v[i];
        float len = pf_v3_length(v->nrm);
        int ok = gi__finite3(v->pos) && gi__finite3(v->nrm) && fabsf(len - 1.0f) < 1e-3f &&
                 gi__finite3(v->intensity) && v->intensity.x >= 0.0f && v->intensity.y >= 0.0f &&
                 v->intensity.z >= 0.0f;
        if (ok) continue;
        if (!gi__finite3(v->pos)) v->pos = pf_v3(0, 0, 0);
        v->nrm = pf_v3(0, 0, 1);
        v->intensity = pf_v3(0, 0, 0);
    }
}

/* The frame's SIMD path (its rasterizer's), for the methods' kernels. */
static uint32_t gi__simd(const gi_frame *f) { return f->raster ? (uint32_t)rs_context_simd(f->raster) : 0u; }

static void gi__vpl_update_into(gi_indirect *ind, const gi_vpl_inputs *in, gi_vpl_set *out)
{
    pf_error err;
    if (ind->opt.method->update(ind->method_state, in, out, &err) != PF_OK) {
        fprintf(stderr, "softgi: VPL update failed: %s\n", err.message);
        out->count = 0;
    }
    gi__vpl_check(ind, out);
}

/* `vpls` became a new set: the maps of its new and moved VPLs, and of
 * the slots past its end, no longer hold their VPLs. */
static void gi__set_changed(gi_indirect *ind)
{
    const uint32_t N = ind->vpls.count;
    for (uint32_t i = 0; i < N; i++)
        if (ind->vpls.v[i].moved) ind->map_ok[i] = 0;
    memset(ind->map_ok + N, 0, ind->opt.vpls - N);
}

/* The method has seen the moves (gi_vpl_inputs.motion): the record starts
 * afresh. */
static void gi__motion_seen(gi_motion *m)
{
    if (m->moved) memset(m->tri_moved, 0, m->tri_count);
    for (uint32_t k = 0; k < m->range_count; k++) m->ranges[k].moved = 0;
    m->moved = 0;
    m->emitters = 0;
}

static void gi__cycle_inputs(gi_indirect *ind, int ahead, gi_vpl_inputs *in);

void gi_stage_vpl_update(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    gi_vpl_inputs in = {f->scene,         f->rt,    f->jobs,  &f->camera, ind->frame, ind->opt.vpls,
                        ind->opt.bounces, &f->gbuf, f->width, f->height,  &f->area,   &f->motion,
                        gi__simd(f),      ind->cycle,     0,          0};
    gi__cycle_inputs(ind, 0, &in);
    gi__vpl_update_into(ind, &in, &ind->vpls);
    gi__motion_seen(&f->motion);
    ind->frame++;
    ind->have_set = 1;
    gi__set_changed(ind);
}


/* The pipelined update: one job of one item. It touches only the method's
 * state, vpls_next and pipe_ms; the frame's stages meanwhile read `vpls`
 * and the G-buffer, so nothing is shared that either side writes. The
 * method may use the job system inside (pf_jobs_wait from a job is
 * allowed); with one thread the job runs when the frame thread first waits
 * with nothing else to do (at the latest in pf_jobs_wait_all). */
static void gi__vpl_update_job(void *ctx, uint32_t item, uint32_t worker)
{
    (void)item, (void)worker;
    gi_indirect *ind = ctx;
    double t0 = pf_time_now();
    gi__vpl_update_into(ind, &ind->pipe_in, &ind->vpls_next);
    ind->pipe_ms = (pf_time_now() - t0) * 1e3;
}

void gi_stage_vpl_update_begin(gi_frame *f, int gbuffer_ready)
{
    gi_indirect *ind = &f->ind;
    if (!f->indirect || !ind->opt.pipeline || !ind->have_set) return;
    if (ind->next_ready) { /* the set made during the last frame becomes this frame's */
        gi_vpl_set t = ind->vpls;
        ind->vpls = ind->vpls_next;
        ind->vpls_next = t;
        ind->next_ready = 0;
        gi__set_changed(ind);
    } else if (!gbuffer_ready && !ind->pending) {
        /* the first pipelined frame after frame 0 shades with frame 0's set
         * again: nothing in it moved since the last frame */
        for (uint32_t i = 0; i < ind->vpls.count; i++) ind->vpls.v[i].moved = 0;
    }
    if (ind->pending) return;
    if (!gbuffer_ready && !ind->opt.method->gbuffer_free) return;
    ind->pipe_camera = f->camera;
    gi_vpl_inputs in = {f->scene,        f->rt,
                        f->jobs,         &ind->pipe_camera,
                        ind->frame,      ind->opt.vpls,
                        ind->opt.bounces, gbuffer_ready ? &f->gbuf : NULL,
                        f->width,        f->height,
                        &f->area,        &f->motion,
                        gi__simd(f),     ind->cycle,
                        0,               0};
    gi__cycle_inputs(ind, 1, &in);
    ind->pipe_in = in;
    ind->frame++;
    ind->pipe_ms = 0.0;
    ind->pending = 1;
    pf_jobs_add(f->jobs, gi__vpl_update_job, ind, 1, 1, NULL, 0);
}

void gi_stage_vpl_update_end(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    if (!ind->pending) return;
    ind->pending = 0;
    ind->next_ready = 1; /* swapped in at the next frame's begin, so `vpls` stays this frame's set */
    gi__motion_seen(&f->motion); /* the job has read it */
    pf_stage_add(&f->times, gi_stage_get(GI_STAGE_VPL_UPDATE)->name, ind->pipe_ms);
}

/* ---------------------------------------------------------- 4. VPL shadow maps */

/* VPL cycling: the slice frame k shades and how often it was shaded
 * before (ind->slice, ind->cycle_base), k counted as the temporal history
 * counts frames, so every anti-aliasing sample of a frame shades the same
 * slice; slice 0 without cycling. With every slice in the rotation from
 * the start, slice k mod C, shaded k / C times before; during the
 * progressive warm-up (gi_indirect.h), the slices in the rotation in turn,
 * chosen once per frame (cycle_key). */
/* The progressive warm-up is on: cycle_maps given and maps to draw (with
 * ray-traced visibility every slice is in the rotation from the start). */
static int gi__warming(const gi_indirect *ind) { return ind->opt.cycle_maps && !ind->opt.visibility_raytrace; }

static void gi__cycle_schedule(gi_indirect *ind)
{
    const uint32_t C = ind->cycle, k = ind->temporal_frames;
    if (C <= 1) {
        ind->slice = ind->cycle_base = 0;
        return;
    }
    if (!gi__warming(ind)) {
        ind->slice = k % C, ind->cycle_base = k / C;
        return;
    }
    if (ind->cycle_key == k + 1u) return; /* chosen for this frame */
    ind->cycle_key = k + 1u;
    const uint32_t s = ind->cycle_next < ind->cycle_live ? ind->cycle_next : 0u;
    ind->slice = s;
    ind->cycle_base = ind->cycle_shaded[s]++;
    ind->cycle_next = s + 1u < ind->cycle_live ? s + 1u : 0u;
}

static uint32_t gi__slice(gi_indirect *ind)
{
    gi__cycle_schedule(ind);
    return ind->slice;
}

/* What a VPL update is told of the cycle (gi_vpl_inputs.slice, live): for
 * this frame's set (ahead = 0) or, pipelined, the next frame's (ahead = 1):
 * the slice that frame shades and the slices it may touch, those in the
 * rotation and the one drawn ahead (during the warm-up; one more for the
 * next frame, whose rotation this frame's maps may grow). */
static void gi__cycle_inputs(gi_indirect *ind, int ahead, gi_vpl_inputs *in)
{
    const uint32_t C = ind->cycle;
    in->slice = in->live = 0;
    if (C <= 1) return;
    gi__cycle_schedule(ind);
    if (!gi__warming(ind)) {
        in->slice = ahead ? (ind->temporal_frames + 1u) % C : ind->slice;
        in->live = C;
        return;
    }
    in->slice = ahead ? ind->cycle_next : ind->slice; /* cycle_next < cycle_live, or 0 */
    uint32_t live = ind->cycle_live + 1u + (ahead ? 1u : 0u);
    in->live = live < C ? live : C;
}

/* Slot i's map to be drawn this frame: marked as holding its VPL and
 * listed (map_pos, map_nrm, map_slot at *todo), its frame made. */
static void gi__list_map(gi_indirect *ind, uint32_t i, pf_vec3 *map_pos, pf_vec3 *map_nrm, uint32_t *map_slot,
                         uint32_t *todo)
{
    ind->map_ok[i] = 1;
    map_pos[*todo] = ind->vpls.v[i].pos;
    map_nrm[*todo] = ind->vpls.v[i].nrm;
    map_slot[(*todo)++] = i;
    ind->frames[i] = rs_para_frame_make(ind->vpls.v[i].pos, ind->vpls.v[i].nrm);
}

/* The progressive warm-up's step in the maps stage: up to cycle_maps maps
 * of slice L = cycle_live, the first not in the rotation, added to the
 * frame's list (from entry todo); returns the new length. */
static uint32_t gi__maps_ahead(gi_indirect *ind, pf_vec3 *map_pos, pf_vec3 *map_nrm, uint32_t *map_slot,
                               uint32_t todo)
{
    const uint32_t C = ind->cycle, N = ind->vpls.count, L = ind->cycle_live;
    if (!gi__warming(ind) || L >= C || ind->ahead_hold) return todo;
    for (uint32_t i = L; i < N && ind->maps_ahead < ind->opt.cycle_maps; i += C) {
        if (ind->map_ok[i]) continue;
        gi__list_map(ind, i, map_pos, map_nrm, map_slot, &todo);
        ind->maps_ahead++;
    }
    return todo;
}

/* After the maps are drawn: slice L joins the rotation once every map of
 * it holds its VPL (the next frame may shade it). */
static void gi__cycle_admit(gi_indirect *ind)
{
    const uint32_t C = ind->cycle, N = ind->vpls.count, L = ind->cycle_live;
    if (!gi__warming(ind) || L >= C) return;
    for (uint32_t i = L; i < N; i += C)
        if (!ind->map_ok[i]) return;
    ind->cycle_live = L + 1u;
}

void gi_stage_vpl_shadow_maps(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    ind->maps_rendered = ind->maps_ahead = 0;
    if (ind->ism) {
        /* Imperfect shadow maps: every VPL's map is rebuilt every frame, moved
         * or not, since the points are regenerated and reassigned to VPLs at
         * random each frame (Ritschel 2008; Barak 2013 Sec. 5.2) */
        uint32_t N = ind->vpls.count;
        for (uint32_t i = 0; i < N; i++) ind->frames[i] = rs_para_frame_make(ind->vpls.v[i].pos, ind->vpls.v[i].nrm);
        gi_ism_render(ind->ism, ind->atlas, f->jobs, ind->frames, N, ind->range, ind->frame, NULL);
        ind->maps_rendered = N;
        ind->atlas_slots = N;
        return;
    }
    if (!ind->para) return;
    /* this frame's maps to render, k-th: its VPL's position, normal and
     * atlas slot (the frame's scratch) */
    pf_vec3 *map_pos = gi_frame_scratch(f, ind->vpls.count, sizeof(pf_vec3), "the VPL maps' list");
    pf_vec3 *map_nrm = gi_frame_scratch(f, ind->vpls.count, sizeof(pf_vec3), "the VPL maps' list");
    uint32_t *map_slot = gi_frame_scratch(f, ind->vpls.count, sizeof(uint32_t), "the VPL maps' list");
    if (!map_pos || !map_nrm || !map_slot) return; /* the frame's status says so */
    /* Moved geometry (gi_motion.h): the maps of the VPLs that keep theirs
     * are drawn again over the texels through which the moved bounds can be
     * seen, before the new and moved VPLs' maps are drawn whole. */
    uint32_t N = ind->vpls.count, todo = 0;
    gi_moved_box *mb = &f->moved_maps;
    /* With static maps (gi_frame_declare_dynamic), the partial renders
     * start from the static codes (rs_para_render_box_split); when a range
     * became dynamic, the kept maps are drawn whole once, static maps with
     * them. */
    uint16_t *sa = ind->static_atlas;
    if (mb->pending || (sa && ind->static_stale)) {
        for (uint32_t i = 0; i < N && i < ind->atlas_slots; i++) {
            if (!ind->map_ok[i]) continue; /* drawn whole below */
            map_pos[todo] = ind->vpls.v[i].pos; /* what its map was drawn for (not moved) */
            map_nrm[todo] = ind->vpls.v[i].nrm;
            map_slot[todo++] = i;
        }
        rs_para_stats st;
        if (sa && ind->static_stale)
            rs_para_render_split(ind->atlas, sa, ind->para, f->jobs, map_pos, map_nrm, map_slot, todo,
                                 ind->range, &st);
        else if (sa)
            rs_para_render_box_split(ind->atlas, sa, ind->para, f->jobs, map_pos, map_nrm, map_slot,
                                     todo, ind->range, mb->lo, mb->hi, mb->ranges, mb->range_count, &st);
        else
            rs_para_render_box(ind->atlas, ind->para, f->jobs, map_pos, map_nrm, map_slot, todo,
                               ind->range, mb->lo, mb->hi, mb->ranges, mb->range_count, &st);
        f->motion_stats.vpl_maps += (uint32_t)st.maps;
        f->motion_stats.vpl_texels += st.texels_tested;
        mb->pending = 0;
        todo = 0;
    }
    ind->static_stale = 0;
    /* The slots whose map does not hold their VPL (new or moved since it
     * was drawn; with VPL cycling, of this frame's slice only) are listed
     * (map_pos, map_nrm, map_slot: the k-th map to render and its slot) and
     * rendered straight into their slots by one call, which spreads them
     * over the workers however scattered the slots are; the others keep
     * their maps (pipelined frame 1 shades with frame 0's set again: all
     * of its maps are there). */
    const uint32_t C = ind->cycle;
    for (uint32_t i = gi__slice(ind); i < N; i += C)
        if (!ind->map_ok[i]) gi__list_map(ind, i, map_pos, map_nrm, map_slot, &todo);
    todo = gi__maps_ahead(ind, map_pos, map_nrm, map_slot, todo);
    /* Calls of at most GI__MAPS_CHUNK maps, so a listener hears of progress
     * between them (a first frame of 100,000 VPLs takes minutes); the maps
     * are independent, so the pieces change no bits. */
    const uint32_t chunk = f->progress ? GI__MAPS_CHUNK : UINT32_MAX;
    for (uint32_t k = 0; k < todo;) {
        uint32_t n = todo - k < chunk ? todo - k : chunk;
        rs_para_render_split(ind->atlas, sa, ind->para, f->jobs, map_pos + k, map_nrm + k, map_slot + k,
                             n, ind->range, NULL);
        k += n;
        ind->maps_rendered = k;
        if (f->progress) f->progress(f->progress_user, gi_stage_get(GI_STAGE_VPL_MAPS)->name, k, todo);
    }
    ind->atlas_slots = N;
    gi__cycle_admit(ind);
}

/* ---------------------------------------------------------- 5. split */

/* The SIMD kernels of the frame's path (gi_indirect_kernels.h); NULL on the
 * scalar path, which runs the per-pixel loops, the reference. */
static const gi_indirect_kernels *gi__kernels(const gi_frame *f)
{
    rs_simd simd = f->raster ? rs_context_simd(f->raster) : RS_SIMD_SCALAR;
#if SIMD_X86
    if (simd == RS_SIMD_AVX512) return &gi_indirect_kernels_avx512;
    if (simd == RS_SIMD_AVX2) return &gi_indirect_kernels_avx2;
#endif
    (void)simd;
    return NULL;
}

/* The G-buffer the indirect stages read: the frame's, or its samples. */
static const rs_gbuffer *gi__indirect_gbuffer(const gi_frame *f)
{
    return f->ind.scale > 1 ? &f->ind.low : &f->gbuf;
}

/* The interleave tiles' layout, as split and combine read it: tile column i
 * of tile row j holds the pixels (a n + i, b m + j); tile t = j n + i starts
 * at tile_x0[t] in the tile-layout planes and is tile_w[t] wide. */
typedef struct gi__tiles {
    uint32_t n, m, w;  /* tiles per row and column; the indirect image's width */
    const uint32_t *x0; /* tile_x0 */
    const uint32_t *tw; /* tile_w */
} gi__tiles;

static gi__tiles gi__tiles_of(const gi_indirect *ind) { return (gi__tiles){ind->n, ind->m, ind->w, ind->tile_x0, ind->tile_w}; }

/* Split (step 5): its inputs and outputs, explicitly (the stage table's
 * reads and writes). */
typedef struct gi__split_io {
    const rs_gbuffer *gbuf; /* GBUFFER: the frame's */
    rs_gbuffer *low;        /* scale > 1: the reduced G-buffer, filled here first (NULL at scale 1) */
    uint32_t scale, width;  /* opt.scale; the frame's width */
    gi__tiles tiles;
    float *px, *py, *pz, *nx, *ny, *nz; /* SPLIT: position and normal planes, tile layout */
    uint32_t *valid;                    /* SPLIT: 1 where a surface was hit */
} gi__split_io;

/* Reduced resolution (opt.scale s > 1): row y of the indirect image takes
 * the G-buffer's pixels (s X, s y), the top-left pixel of each s x s block,
 * so sample X of the indirect image sits exactly on a frame pixel (the
 * upsampling below relies on it). Only what the indirect stages read is
 * copied: position, normal, triangle id. */
static void gi__sample_row(const gi__split_io *io, uint32_t y)
{
    const rs_gbuffer *g = io->gbuf;
    rs_gbuffer *lo = io->low;
    const uint32_t s = io->scale;
    for (uint32_t x = 0; x < io->tiles.w; x++) {
        size_t i = (size_t)y * s * io->width + (size_t)x * s, k = (size_t)y * io->tiles.w + x;
        lo->pos_x[k] = g->pos_x[i], lo->pos_y[k] = g->pos_y[i], lo->pos_z[k] = g->pos_z[i];
        lo->nrm_x[k] = g->nrm_x[i], lo->nrm_y[k] = g->nrm_y[i], lo->nrm_z[k] = g->nrm_z[i];
        lo->prim[k] = g->prim[i];
    }
}

/* Image row y -> its tile row: tile column i holds pixels x = a n + i, so
 * walking each tile column avoids a division per pixel (gi_split_index's
 * mapping, written incrementally). */
static void gi__split_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__split_io *io = p;
    const gi__tiles *tl = &io->tiles;
    if (io->low) gi__sample_row(io, y);
    const rs_gbuffer *g = io->low ? io->low : io->gbuf;
    const size_t row = (size_t)y * tl->w;
    for (uint32_t i = 0; i < tl->n && i < tl->w; i++) {
        uint32_t t = (y % tl->m) * tl->n + i;
        uint32_t k = tl->x0[t] + (y / tl->m) * tl->tw[t];
        for (uint32_t x = i; x < tl->w; x += tl->n, k++) {
            size_t s = row + x;
            io->px[k] = g->pos_x[s], io->py[k] = g->pos_y[s], io->pz[k] = g->pos_z[s];
            io->nx[k] = g->nrm_x[s], io->ny[k] = g->nrm_y[s], io->nz[k] = g->nrm_z[s];
            io->valid[k] = g->prim[s] != RS_GBUFFER_EMPTY;
        }
    }
}

void gi_stage_split(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    const gi__split_io io = {&f->gbuf,     ind->scale > 1 ? &ind->low : NULL,
                             ind->scale,   f->width,
                             gi__tiles_of(ind),
                             ind->split_px, ind->split_py, ind->split_pz, ind->split_nx, ind->split_ny, ind->split_nz,
                             ind->split_valid};
    pf_jobs_parallel_for(f->jobs, gi__split_row, (void *)&io, ind->h, 8);
}

/* ---------------------------------------------------------- 6. assign */


static int gi__by_lum(const void *a, const void *b)
{
    const gi__lumkey *x = a, *y = b;
    if (x->lum != y->lum) return x->lum > y->lum ? -1 : 1; /* brightest first */
    return x->index < y->index ? -1 : (x->index > y->index); /* ties: stable by index */
}

/* Deals every emitting VPL anew: sorted by luminance, brightest first, in
 * boustrophedon order 0..T-1, T-1..0, ... so each tile's share of the bright
 * VPLs is as even as the counts allow. VPLs that emit nothing (a method's
 * free slots) go to no tile: they would add exactly zero. Their key -1 sorts
 * them after every other, so the others are dealt exactly as if they were
 * not there. */
/* The assignment's inputs, state and outputs, explicitly (the stage
 * table's reads: VPLS; writes: ASSIGNMENT; its own state: the tiles and ids
 * of the last assignment). */
typedef struct gi__assign_io {
    const gi_vpl *v;              /* VPLS */
    uint32_t N, T;                /* VPL slots; tiles */
    uint32_t first, step, g0;     /* the slice: slots first, first + step, ... < N, dealt to groups g0 .. g0 + T - 1
                                     (VPL cycling; 0, 1, 0 without) */
    uint32_t *tile_of;            /* state: each slot's tile (UINT32_MAX: none) */
    uint32_t *assigned_id;        /* state: the id each slot had when assigned */
    uint32_t *assigned_count;     /* state: slots assigned last time */
    gi__lumkey *keys;             /* scratch (the frame's), N */
    double *load;                 /* scratch (the frame's), T */
    uint32_t *cursor;             /* scratch (the frame's), T */
    uint32_t *assign, *assign_start; /* ASSIGNMENT */
    uint32_t *kept;               /* survivors kept in their tile (statistic) */
} gi__assign_io;

static void gi__assign_deal(const gi__assign_io *io)
{
    const uint32_t T = io->T, N = io->N;
    gi__lumkey *keys = io->keys;
    uint32_t live = 0, M = 0;
    for (uint32_t i = io->first; i < N; i += io->step) {
        pf_vec3 c = io->v[i].intensity;
        int emits = c.x > 0.0f || c.y > 0.0f || c.z > 0.0f;
        keys[M++] = (gi__lumkey){emits ? pf_luminance(c) : -1.0f, i};
        io->tile_of[i] = UINT32_MAX;
        live += (uint32_t)emits;
    }
    qsort(keys, M, sizeof *keys, gi__by_lum);
    for (uint32_t r = 0; r < live; r++) {
        uint32_t round = r / T, pos = r % T;
        io->tile_of[keys[r].index] = io->g0 + ((round & 1) ? T - 1 - pos : pos);
    }
}

/* Keeps every survivor in its tile and inserts the others, brightest
 * first, each into the tile with the least luminance so far (ties: fewer
 * VPLs, then the lower tile). A survivor is a slot that emits, is not
 * moved, carries the id it had when last assigned and had a tile then.
 * Returns 0 (and changes nothing) when there is no survivor. */
static int gi__assign_keep(const gi__assign_io *io)
{
    const uint32_t T = io->T, N = io->N;
    gi__lumkey *keys = io->keys;
    double *load = io->load;
    uint32_t *count = io->cursor, *tile_of = io->tile_of, fresh = 0, kept = 0;
    for (uint32_t t = 0; t < T; t++) load[t] = 0.0, count[t] = 0;
    for (uint32_t i = io->first; i < N; i += io->step) {
        const gi_vpl *v = &io->v[i];
        int emits = v->intensity.x > 0.0f || v->intensity.y > 0.0f || v->intensity.z > 0.0f;
        int survives = emits && !v->moved && i < *io->assigned_count && io->assigned_id[i] == v->id &&
                       tile_of[i] != UINT32_MAX;
        if (survives) {
            load[tile_of[i] - io->g0] += pf_luminance(v->intensity);
            count[tile_of[i] - io->g0]++;
            kept++;
        } else {
            tile_of[i] = UINT32_MAX;
            if (emits) keys[fresh++] = (gi__lumkey){pf_luminance(v->intensity), i};
        }
    }
    if (!kept) return 0;
    qsort(keys, fresh, sizeof *keys, gi__by_lum);
    for (uint32_t r = 0; r < fresh; r++) {
        uint32_t best = 0;
        for (uint32_t t = 1; t < T; t++)
            if (load[t] < load[best] || (load[t] == load[best] && count[t] < count[best])) best = t;
        tile_of[keys[r].index] = io->g0 + best;
        load[best] += keys[r].lum;
        count[best]++;
    }
    *io->kept += kept;
    return 1;
}

/* Laine 2007 Sec. 7 deals VPLs to tiles "in the order they are generated",
 * which keeps a surviving VPL in its tile; sorting by intensity every frame
 * balances the tiles better but re-deals survivors whenever intensities
 * change (SMC, IIR, TCAS re-weight every frame), so each pixel would see a
 * different subset every frame and the method's temporal coherence would
 * be lost. So: a survivor keeps its tile, new VPLs are balanced in as they
 * arrive (gi__assign_keep); a set with no survivor (the first frame, or IR
 * after its light moved) is dealt anew (gi__assign_deal). */
void gi_stage_assign(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    const uint32_t T = ind->n * ind->m, N = ind->vpls.count, C = ind->cycle, G = T * C;
    gi__lumkey *keys = gi_frame_scratch(f, N, sizeof(gi__lumkey), "the VPL assignment");
    double *load = gi_frame_scratch(f, T, sizeof(double), "the VPL assignment");
    uint32_t *cursor = gi_frame_scratch(f, G, sizeof(uint32_t), "the VPL assignment");
    ind->assign_kept = 0;
    if (!keys || !load || !cursor) { /* no tile gets a VPL; the frame's status says why */
        memset(ind->assign_start, 0, sizeof(uint32_t) * (G + 1));
        ind->assigned_count = 0;
        return;
    }
    /* each slice on its own (one slice, every slot, without cycling): its
     * slots dealt to its T groups */
    gi__assign_io io = {ind->vpls.v,      N,      T,           0, 1, 0, ind->tile_of,
                        ind->assigned_id, &ind->assigned_count, keys, load,
                        cursor,           ind->assign,       ind->assign_start, &ind->assign_kept};
    for (uint32_t c = 0; c < C; c++) {
        io.first = c, io.step = C, io.g0 = c * T;
        if (!gi__assign_keep(&io)) gi__assign_deal(&io);
    }
    const uint32_t *tile_of = io.tile_of;
    for (uint32_t i = 0; i < N; i++) io.assigned_id[i] = io.v[i].id;
    *io.assigned_count = N;
    memset(io.assign_start, 0, sizeof(uint32_t) * (G + 1));
    for (uint32_t i = 0; i < N; i++)
        if (tile_of[i] != UINT32_MAX) io.assign_start[tile_of[i] + 1]++;
    for (uint32_t t = 0; t < G; t++) io.assign_start[t + 1] += io.assign_start[t];
    memcpy(io.cursor, io.assign_start, sizeof(uint32_t) * G);
    for (uint32_t i = 0; i < N; i++) /* VPL order within a tile */
        if (tile_of[i] != UINT32_MAX) io.assign[io.cursor[tile_of[i]]++] = i;
}

/* ---------------------------------------------------------- 7. accumulate */

pf_vec3 gi_vpl_irradiance(const gi_vpl *v, pf_vec3 p, pf_vec3 n, float b, pf_vec3 *w_out, float *r_out, float *g_out,
                          int *clamped)
{
    pf_vec3 d = pf_v3_sub(v->pos, p);
    float r2 = pf_v3_dot(d, d);
    if (!(r2 > 0.0f)) return pf_v3(0, 0, 0);
    float r = sqrtf(r2);
    pf_vec3 w = pf_v3_scale(d, 1.0f / r);
    float c1 = pf_v3_dot(n, w), c2 = -pf_v3_dot(v->nrm, w);
    if (!(c1 > 0.0f) || !(c2 > 0.0f)) return pf_v3(0, 0, 0);
    float G = c1 * c2 / r2;
    if (clamped) *clamped = G > b;
    if (G > b) G = b; /* the bounded geometry term (survey Sec. 5) */
    *w_out = w;
    *r_out = r;
    if (g_out) *g_out = G;
    return pf_v3_scale(v->intensity, G);
}


/* The accumulation's inputs and output, explicitly (the stage table's
 * reads: SPLIT, VPLS, VPL_MAPS, ASSIGNMENT; writes: ACCUMULATED). */
typedef struct gi__accumulate_io {
    gi_accumulate_in in;              /* the VPLs, their lists and maps (the kernels' input) */
    const pf_rt *rt;                  /* --visibility raytrace (no atlas): Embree's scene */
    const gi_indirect_kernels *kt;    /* the SIMD path's kernels, NULL on the scalar path */
    uint32_t T, bands;                /* tiles; the tallest tile's bands of GI_ACC_BAND rows */
    const uint32_t *tile_x0, *tile_w, *tile_h; /* the tile layout */
    const uint32_t *assign_start;     /* ASSIGNMENT: group g's VPLs at assign[assign_start[g]..[g + 1]) */
    uint32_t shift;                   /* the tiles' group rotation (gi_indirect_tile_group) */
    uint32_t slice;                   /* this frame's slice (VPL cycling; 0 without) */
    float weight;                     /* gi_indirect_tile_weight */
    const float *px, *py, *pz, *nx, *ny, *nz; /* SPLIT */
    const uint32_t *valid;            /* SPLIT */
    float *split_e;                   /* ACCUMULATED */
} gi__accumulate_io;

/* One job item: a band of GI_ACC_BAND rows of one tile. A tile's rows lie
 * one after another in the split layout, so the band is one run of pixels,
 * handed to the kernel GI_ACC_GROUPS x SIMD_W at a time: each VPL's map is
 * read for that many neighbouring pixels before the next VPL's (measured:
 * rows one at a time cost 7-10% more on Sibenik at 1024x768, the maps'
 * texels coming from further down the cache hierarchy). Pixels fall to the
 * scalar lookup only at the band's end, with the same bits. */
static void gi__accumulate_band(void *p, uint32_t item, uint32_t worker)
{
    (void)worker;
    const gi__accumulate_io *io = p;
    const gi_accumulate_in *in = &io->in;
    uint32_t T = io->T, bands = io->bands;
    uint32_t t = item / bands, r0 = item % bands * GI_ACC_BAND;
    if (t >= T || r0 >= io->tile_h[t]) return;
    uint32_t r1 = r0 + GI_ACC_BAND < io->tile_h[t] ? r0 + GI_ACC_BAND : io->tile_h[t];
    const uint32_t k1 = io->tile_x0[t] + r1 * io->tile_w[t];
    uint32_t k = io->tile_x0[t] + r0 * io->tile_w[t];
    const float weight = io->weight; /* each tile sees 1/T of the VPLs (of its slice's, 1/C of them) */
    const uint32_t grp = gi_tile_group(t, io->shift, T, io->slice);
    uint32_t a0 = io->assign_start[grp], a1 = io->assign_start[grp + 1];
    const uint32_t R = in->para_res;
    const size_t map = (size_t)R * R;
    const gi_indirect_kernels *kt = io->kt;
    if (in->atlas && kt) {
        const uint32_t W = kt->width;
        float ew[3 * 16 * GI_ACC_GROUPS];
        while (k + W <= k1) {
            uint32_t groups = (k1 - k) / W;
            if (groups > GI_ACC_GROUPS) groups = GI_ACC_GROUPS;
            kt->accumulate(in, io->px + k, io->py + k, io->pz + k, io->nx + k, io->ny + k, io->nz + k, groups, a0, a1,
                           ew);
            for (uint32_t i = 0; i < W * groups; i++) {
                float *e = io->split_e + 3 * (size_t)(k + i);
                int valid = io->valid[k + i] != 0;
                e[0] = valid ? ew[3 * i] * weight : 0.0f;
                e[1] = valid ? ew[3 * i + 1] * weight : 0.0f;
                e[2] = valid ? ew[3 * i + 2] * weight : 0.0f;
            }
            k += W * groups;
        }
    }
    for (; k < k1; k++) {
        float *e = io->split_e + 3 * (size_t)k;
        e[0] = e[1] = e[2] = 0.0f;
        if (!io->valid[k]) continue;
        pf_vec3 pos = pf_v3(io->px[k], io->py[k], io->pz[k]);
        pf_vec3 nrm = pf_v3(io->nx[k], io->ny[k], io->nz[k]);
        pf_vec3 sum = pf_v3(0, 0, 0);
        for (uint32_t q = a0; q < a1; q++) {
            uint32_t vi = in->assign[q];
            const gi_vpl *v = &in->vpls[vi];
            pf_vec3 w;
            float r;
            pf_vec3 c = gi_vpl_irradiance(v, pos, nrm, in->b, &w, &r, NULL, NULL);
            if (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f) continue;
            int visible;
            if (in->atlas) { /* exact maps (the receiver-plane test or bias_scale 1) or ISMs: the one lookup */
                visible = rs_para_visible_scaled(in->atlas + vi * map, R, in->range, &in->frames[vi], pos,
                                                 in->plane ? &nrm : NULL, pf_v3_dot(nrm, w), in->bias_scale);
            } else {
                pf_ray ray = {pf_rt_offset_origin(pos, nrm, w), 0.0f, w, r * (1.0f - 1.0e-4f)};
                visible = !pf_rt_occluded1(io->rt, ray);
            }
            if (visible) sum = pf_v3_add(sum, c);
        }
        e[0] = sum.x * weight, e[1] = sum.y * weight, e[2] = sum.z * weight;
    }
}

void gi_stage_accumulate(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    uint32_t T = ind->n * ind->m, rows = 0;
    /* with temporal accumulation, frame k's tiles shade with the groups
     * rotated by k (gi_indirect_tile_group); with anti-aliasing samples
     * (gi_aa.h), sample s of frame k by k N + s, and without temporal
     * accumulation by the sample's pattern index (the TAA's frame included),
     * so each sample sees other groups; 0 for one sample of a plain frame */
    uint64_t rot = ind->opt.temporal ? (uint64_t)ind->temporal_frames * f->aa.samples + f->aa.sample : f->aa.index;
    /* with VPL cycling, the frame that shades slice b for the a-th time
     * (frame k = a C + b without the warm-up) rotates its groups by a + b,
     * so the frames that shade one slice rotate through all its groups */
    gi__cycle_schedule(ind);
    if (ind->cycle > 1) {
        rot = ((uint64_t)ind->cycle_base + ind->slice) * f->aa.samples + f->aa.sample;
    }
    ind->shift = (uint32_t)(rot % T);
    for (uint32_t t = 0; t < T; t++) rows = ind->tile_h[t] > rows ? ind->tile_h[t] : rows;
    const gi__accumulate_io io = {
        {ind->vpls.v, ind->assign, ind->atlas, ind->frames, ind->opt.para_res, ind->range, ind->bias_scale, ind->plane,
         ind->b},
        f->rt,
        gi__kernels(f),
        T,
        (rows + GI_ACC_BAND - 1) / GI_ACC_BAND,
        ind->tile_x0,
        ind->tile_w,
        ind->tile_h,
        ind->assign_start,
        ind->shift,
        ind->slice,
        gi_indirect_tile_weight(ind),
        ind->split_px,
        ind->split_py,
        ind->split_pz,
        ind->split_nx,
        ind->split_ny,
        ind->split_nz,
        ind->split_valid,
        ind->split_e};
    pf_jobs_parallel_for(f->jobs, gi__accumulate_band, (void *)&io, T * io.bands, 1);
}

/* ---------------------------------------------------------- 8. combine */

/* Combine (step 8): ACCUMULATED (split_e, tile layout) in, COMBINED (image
 * layout) out. */
typedef struct gi__combine_io {
    gi__tiles tiles;
    const float *split_e; /* ACCUMULATED */
    float *combined;      /* COMBINED */
} gi__combine_io;

static void gi__combine_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__combine_io *io = p;
    const gi__tiles *tl = &io->tiles;
    const size_t row = (size_t)y * tl->w;
    for (uint32_t i = 0; i < tl->n && i < tl->w; i++) { /* as gi__split_row */
        uint32_t t = (y % tl->m) * tl->n + i;
        uint32_t k = tl->x0[t] + (y / tl->m) * tl->tw[t];
        for (uint32_t x = i; x < tl->w; x += tl->n, k++)
            memcpy(io->combined + 3 * (row + x), io->split_e + 3 * (size_t)k, 3 * sizeof(float));
    }
}

void gi_stage_combine(gi_frame *f)
{
    const gi__combine_io io = {gi__tiles_of(&f->ind), f->ind.split_e, f->ind.combined};
    pf_jobs_parallel_for(f->jobs, gi__combine_row, (void *)&io, f->ind.h, 8);
}

/* ---------------------------------------------------------- 8b. compensate */

/* Screen-space compensation of the bounded geometry term's bias (the
 * survey's Sec. 5.2 after Novak, Engelhardt and Dachsbacher 2011; one step
 * of their recursion, T_r applied once). The clamp removes, at receiver x,
 * the residual transport
 *   E_r(x) = integral over surfaces y of L(y) G_r(x, y) V dA_y,
 *   G_r = max(G - b, 0),  L(y) = direct + albedo / pi x bounded indirect,
 * the light y reflects (emission excluded: the direct light already
 * carries it). G_r > 0 needs |x - y| < 1 / sqrt(b), a disc of R = r_b /
 * (pixel size at x's depth) pixels around x on screen, so the integral is
 * estimated from the image itself: K taps on a Vogel spiral over that disc
 * (equal-area, rotated per pixel by a stable random angle),
 *   E_r ~ (pi R^2 / K) sum_k L(y_k) G_r(x, y_k) a(y_k),
 * with a(y) the surface area pixel y covers (its footprint at its depth over
 * |cos| of its normal to the view ray, at most 10x the frontal one). What
 * the screen cannot show is missing (surfaces off screen or hidden behind
 * others), visibility between x and y is not tested, and the noise of the
 * K taps is left to the filter that follows. The residual is written to
 * `comp` and then added to `combined`, so every tap reads the bounded
 * image. */
/* The compensation's inputs and outputs, explicitly (the stage table's
 * reads: GBUFFER, DIRECT, COMBINED; writes: COMBINED, through comp). */
typedef struct gi__comp_ctx {
    const rs_gbuffer *g;     /* GBUFFER of the indirect image (the reduced one at scale > 1) */
    const rs_gbuffer *fg;    /* GBUFFER of the frame: the albedo at a sample's frame pixel */
    const float *direct;     /* DIRECT */
    const pf_camera *cam;
    uint32_t w, h, s, K, fw; /* indirect size, scale, taps, the frame's width */
    float b;                 /* the clamp's bound */
    float *combined;         /* COMBINED: read by the taps, then the residual added */
    float *comp;             /* the residual, per pixel */
    float th;   /* tan(fov / 2) */
    float rb;   /* 1 / sqrt(b), world units */
    float (*spiral)[2]; /* the K taps of the unit disc: sqrt((k + 1/2) / K) (cos, sin)(golden angle k) */
} gi__comp_ctx;

static void gi__compensate_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__comp_ctx *c = p;
    const rs_gbuffer *g = c->g, *fg = c->fg;
    const uint32_t w = c->w, h = c->h, s = c->s, K = c->K;
    const pf_camera *cam = c->cam;
    const float b = c->b, pix = 2.0f * c->th / (float)h; /* a pixel's size at depth 1 */
    for (uint32_t x = 0; x < w; x++) {
        size_t i = (size_t)y * w + x;
        float *out = c->comp + 3 * i;
        out[0] = out[1] = out[2] = 0.0f;
        if (g->prim[i] == RS_GBUFFER_EMPTY) continue;
        pf_vec3 px = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]), nx = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
        float zx = pf_v3_dot(pf_v3_sub(px, cam->eye), cam->forward);
        if (!(zx > 0.0f)) continue;
        float R = c->rb / (zx * pix); /* the disc's radius in pixels */
        if (!(R >= 1.0f)) continue;
        if (R > 128.0f) R = 128.0f;
        const float rot = 2.0f * PF_PI * pf_random((uint32_t)i, 0, 0x434f4d50u, 0);
        const float cr = R * cosf(rot), sr = R * sinf(rot); /* the spiral rotated and scaled to the disc */
        float acc[3] = {0, 0, 0};
        for (uint32_t k = 0; k < K; k++) {
            const float sx = c->spiral[k][0], sy = c->spiral[k][1];
            int tx = (int)x + (int)lrintf(sx * cr - sy * sr), ty = (int)y + (int)lrintf(sx * sr + sy * cr);
            if (tx < 0 || ty < 0 || tx >= (int)w || ty >= (int)h) continue;
            size_t j = (size_t)ty * w + (size_t)tx;
            if (j == i || g->prim[j] == RS_GBUFFER_EMPTY) continue;
            pf_vec3 py = pf_v3(g->pos_x[j], g->pos_y[j], g->pos_z[j]), ny = pf_v3(g->nrm_x[j], g->nrm_y[j], g->nrm_z[j]);
            pf_vec3 d = pf_v3_sub(py, px);
            float r2 = pf_v3_dot(d, d);
            if (!(r2 > 0.0f)) continue;
            float cx = pf_v3_dot(nx, d), cy = -pf_v3_dot(ny, d);
            if (!(cx > 0.0f) || !(cy > 0.0f)) continue;
            float G = cx * cy / (r2 * r2); /* cos cos / r^2 with unnormalised d: / r^4 */
            if (!(G > b)) continue;
            /* the area pixel j covers: its footprint at its depth over the cosine to the view ray */
            pf_vec3 v = pf_v3_sub(py, cam->eye);
            float zy = pf_v3_dot(v, cam->forward), vl = sqrtf(pf_v3_dot(v, v));
            float cv = fabsf(pf_v3_dot(ny, v)) / vl;
            if (cv < 0.1f) cv = 0.1f;
            float a = (zy * pix) * (zy * pix) / cv;
            /* L(y): the frame pixel the sample is (s X, s Y) */
            size_t fj = (size_t)ty * s * c->fw + (size_t)tx * s;
            float wgt = (G - b) * a;
            for (int ch = 0; ch < 3; ch++) {
                const float *alb = ch == 0 ? fg->alb_r : ch == 1 ? fg->alb_g : fg->alb_b;
                float L = c->direct[3 * fj + ch] + alb[fj] * PF_INV_PI * c->combined[3 * j + ch];
                acc[ch] += L * wgt;
            }
        }
        float area = PF_PI * R * R / (float)K;
        out[0] = acc[0] * area, out[1] = acc[1] * area, out[2] = acc[2] * area;
    }
}

static void gi__compensate_add(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__comp_ctx *c = p;
    for (size_t i = (size_t)y * c->w * 3; i < (size_t)(y + 1) * c->w * 3; i++) c->combined[i] += c->comp[i];
}

void gi_stage_compensate(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    if (!ind->opt.compensate || !(ind->b < INFINITY)) return;
    float spiral[GI__COMP_MAX_TAPS][2];
    const uint32_t K = ind->opt.compensate_taps;
    for (uint32_t k = 0; k < K; k++) {
        float rr = sqrtf(((float)k + 0.5f) / (float)K), ang = 2.39996323f * (float)k; /* the golden angle */
        spiral[k][0] = rr * cosf(ang), spiral[k][1] = rr * sinf(ang);
    }
    const gi__comp_ctx c = {gi__indirect_gbuffer(f),
                            &f->gbuf,
                            f->direct,
                            &f->camera,
                            ind->w,
                            ind->h,
                            ind->scale,
                            K,
                            f->width,
                            ind->b,
                            ind->combined,
                            ind->comp,
                            tanf(0.5f * f->camera.yfov),
                            1.0f / sqrtf(ind->b),
                            spiral};
    pf_jobs_parallel_for(f->jobs, gi__compensate_row, (void *)&c, ind->h, 4);
    pf_jobs_parallel_for(f->jobs, gi__compensate_add, (void *)&c, ind->h, 16);
}

/* ---------------------------------------------------------- 9. filter */


/* The weight of the neighbour at (dx, dy) pixels, squared distance d2,
 * squared distance from the pixel's tangent plane dp2 and normal cosine nd;
 * 0 leaves it out.
 *   box (Laine 2007 Fig. 5): 1 where the position test passes
 *     (gi_filter_near: Laine's |p2 - p| < alpha, or by default the
 *     tangent-plane test) and n2 . n > beta;
 *   gaussian (Aranha, SSVP Sec. III-D, "an edge-aware gaussian blur"; the
 *     paper gives no kernel): the same edge tests, times a Gaussian of
 *     sigma = max(n, m) / 2 pixels;
 *   bilateral (Hedman 2017 Sec. 4): a Gaussian of sigma = max(n, m) / 2
 *     pixels times a Gaussian in position (sigma = alpha / 2) times
 *     (n2 . n)^8. */
static float gi__filter_weight(const gi_filter_in *in, gi_filter_kind kind, int dx, int dy, float d2, float dp2,
                               float nd)
{
    const int n = (int)in->n, m = (int)in->m;
    const float a2 = in->alpha2, beta = in->beta;
    if (kind == GI_FILTER_BOX) return gi_filter_near(in, d2, dp2) && nd > beta ? 1.0f : 0.0f;
    if (kind == GI_FILTER_GAUSSIAN) {
        float sg = 0.5f * (float)(n > m ? n : m);
        return gi_filter_near(in, d2, dp2) && nd > beta ? expf(-(float)(dx * dx + dy * dy) / (2.0f * sg * sg))
                                                         : 0.0f;
    }
    if (!(nd > 0.0f)) return 0.0f;
    float ss = 0.5f * (float)(n > m ? n : m), sp2 = 0.25f * a2;
    float nd2 = nd * nd, nd4 = nd2 * nd2;
    return expf(-(float)(dx * dx + dy * dy) / (2.0f * ss * ss)) * expf(-d2 / (2.0f * sp2)) * nd4 * nd4;
}

/* The filter's inputs and output, explicitly (the stage table's reads:
 * GBUFFER, COMBINED; writes: FILTERED, or the reduced filtered_low). */
typedef struct gi__filter_io {
    gi_filter_in in;               /* combined, the G-buffer, sizes and tests */
    gi_filter_kind kind;           /* opt.filter */
    const gi_indirect_kernels *kt; /* the SIMD path's kernels, NULL on the scalar path */
    float *filtered;               /* FILTERED */
} gi__filter_io;

static void gi__filter_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__filter_io *io = p;
    const gi_filter_in *in = &io->in;
    const rs_gbuffer *g = in->g;
    float *filtered = io->filtered;
    const int W = (int)in->w, H = (int)in->h, n = (int)in->n, m = (int)in->m;
    /* SIMD for the interior of the row: windows [x - n/2, x + lanes - 1 + n - 1 - n/2] on screen */
    const gi_indirect_kernels *kt = io->kt;
    int simd_x0 = W, simd_x1 = W, lanes = kt ? (int)kt->width : 1;
    if (io->kind == GI_FILTER_BOX && kt) {
        simd_x0 = n / 2;
        simd_x1 = W - (n - 1 - n / 2) - (lanes - 1); /* last x with x + lanes - 1 + (n - 1 - n/2) < W */
    }
    for (int x = 0; x < W; x++) {
        if (x >= simd_x0 && x < simd_x1) {
            kt->filter_box(in, x, (int)y, filtered + 3 * ((size_t)y * in->w + (size_t)x));
            x += lanes - 1;
            continue;
        }
        size_t i = (size_t)y * in->w + (size_t)x;
        float *out = filtered + 3 * i;
        if (g->prim[i] == RS_GBUFFER_EMPTY || io->kind == GI_FILTER_NONE) {
            memcpy(out, in->combined + 3 * i, 3 * sizeof(float));
            continue;
        }
        pf_vec3 pos = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]);
        pf_vec3 nrm = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
        float acc[3] = {0, 0, 0}, wsum = 0.0f;
        /* the window: Laine's n x m box (Fig. 5), or (2n+1) x (2m+1) for the
         * Gaussian and the cross-bilateral filter */
        int box = io->kind == GI_FILTER_BOX;
        int x0 = box ? -(n / 2) : -n, x1 = box ? n - 1 - n / 2 : n;
        int y0 = box ? -(m / 2) : -m, y1 = box ? m - 1 - m / 2 : m;
        for (int dy = y0; dy <= y1; dy++)
            for (int dx = x0; dx <= x1; dx++) {
                int tx = x + dx, ty = (int)y + dy;
                if (tx < 0 || ty < 0 || tx >= W || ty >= H) continue;
                size_t j = (size_t)ty * in->w + (size_t)tx;
                if (g->prim[j] == RS_GBUFFER_EMPTY) continue;
                pf_vec3 d = pf_v3_sub(pf_v3(g->pos_x[j], g->pos_y[j], g->pos_z[j]), pos);
                float nd = nrm.x * g->nrm_x[j] + nrm.y * g->nrm_y[j] + nrm.z * g->nrm_z[j];
                float dp = pf_v3_dot(d, nrm); /* the SIMD path's order: d.x n.x + d.y n.y + d.z n.z */
                float w = gi__filter_weight(in, io->kind, dx, dy, pf_v3_dot(d, d), dp * dp, nd);
                if (!(w > 0.0f)) continue;
                const float *e = in->combined + 3 * j;
                acc[0] += w * e[0], acc[1] += w * e[1], acc[2] += w * e[2];
                wsum += w;
            }
        if (wsum > 0.0f) out[0] = acc[0] / wsum, out[1] = acc[1] / wsum, out[2] = acc[2] / wsum;
        else memcpy(out, in->combined + 3 * i, 3 * sizeof(float));
    }
}

/* gi_filter_in.cap2: 0 for Laine's distance test, else the plane test's reach */
static float gi__filter_cap2(const gi_indirect *ind)
{
    return ind->opt.filter_distance ? 0.0f : GI_FILTER_PLANE_CAP * GI_FILTER_PLANE_CAP * ind->alpha * ind->alpha;
}

void gi_stage_filter(gi_frame *f)
{
    const gi_indirect *ind = &f->ind;
    if (ind->opt.filter == GI_FILTER_ATROUS) {
        gi_atrous_io a = {ind->combined, gi__indirect_gbuffer(f), ind->w, ind->h, ind->n, ind->m,
                          ind->alpha * ind->alpha, ind->opt.beta, ind->opt.atrous, ind->atrous_scratch,
                          gi__kernels(f), ind->scale > 1 ? ind->filtered_low : ind->filtered, gi__filter_cap2(ind)};
        if (!(a.par.sigma_p > 0.0f)) a.par.sigma_p = 0.25f * ind->alpha;
        gi_atrous_run(f->jobs, &a);
        return;
    }
    const gi__filter_io io = {
        {ind->combined, gi__indirect_gbuffer(f), ind->w, ind->h, ind->n, ind->m, ind->alpha * ind->alpha, ind->opt.beta,
         gi__filter_cap2(ind)},
        ind->opt.filter,
        gi__kernels(f),
        ind->scale > 1 ? ind->filtered_low : ind->filtered};
    pf_jobs_parallel_for(f->jobs, gi__filter_row, (void *)&io, ind->h, 4);
}

/* ---------------------------------------------------------- 9b. upsample */

/* Joint (geometry-aware) upsampling of the reduced-resolution irradiance
 * (opt.scale s > 1; beyond Laine 2007, after Kopf et al. 2007's joint
 * bilateral upsampling with Laine's edge tests as the range term). Frame
 * pixel (x, y) lies between the samples X0 = floor(x / s), X0 + 1 (sample X
 * sits on frame pixel s X) at the fraction tx = x / s - X0, likewise in y;
 * each of the four samples weighs its bilinear weight if it passes the
 * filter's tests against the pixel's own surface (valid, |p_s - p| < alpha,
 * n_s . n > beta). A pixel none of them passes (an edge the samples miss:
 * a thin object, a silhouette) takes the passing sample nearest in position
 * from the 3 x 3 samples around it, else the nearest valid one, else 0.
 * Sample pixels themselves (tx = ty = 0) get their sample's value exactly. */
/* The planes the upsampling reads, as local restrict pointers (the output
 * never aliases them, and the loop then keeps them in registers). */
typedef struct gi__up_planes {
    const float *restrict px, *restrict py, *restrict pz, *restrict nx, *restrict ny, *restrict nz;
    const uint32_t *restrict prim;
    const float *restrict e; /* filtered_low */
} gi__up_planes;

/* 2: sample k passes the tests against (p, n); 1: valid only; 0: empty. */
static inline int gi__up_ok(const gi__up_planes *lo, size_t k, pf_vec3 p, pf_vec3 n, float a2, float beta,
                            float *d2_out)
{
    if (lo->prim[k] == RS_GBUFFER_EMPTY) return 0;
    float dx = lo->px[k] - p.x, dy = lo->py[k] - p.y, dz = lo->pz[k] - p.z;
    float d2 = dx * dx + dy * dy + dz * dz, nd = n.x * lo->nx[k] + n.y * lo->ny[k] + n.z * lo->nz[k];
    *d2_out = d2;
    return d2 < a2 && nd > beta ? 2 : 1;
}

/* Upsample's inputs and output, explicitly (the stage table's reads and
 * writes): the frame's G-buffer, the reduced one and the reduced
 * irradiance in, FILTERED at the frame's size out. */
typedef struct gi__upsample_io {
    const rs_gbuffer *gbuf; /* GBUFFER, the frame's */
    gi__up_planes lo;       /* the reduced G-buffer and filtered_low */
    float *filtered;        /* FILTERED */
    uint32_t s, w, h, W;    /* scale, reduced size, frame width */
    float a2, beta;         /* the filter's tests */
    const gi_indirect_kernels *kern; /* the SIMD path's runs, or NULL: pixel by pixel */
} gi__upsample_io;

/* No sample passes among the four: the best of the 3 x 3 around
 * (reduced sample X0, Y0 of frame pixel (x, y)). */
static void gi__upsample_fallback(const gi__upsample_io *io, size_t i, uint32_t X0, uint32_t Y0, float *out)
{
    const rs_gbuffer *g = io->gbuf;
    const gi__up_planes lo = io->lo;
    pf_vec3 pos = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]), nrm = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
    size_t best = SIZE_MAX;
    int best_ok = 0;
    float best_d2 = INFINITY, d2;
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int X = (int)X0 + dx, Y = (int)Y0 + dy;
            if (X < 0 || Y < 0 || X >= (int)io->w || Y >= (int)io->h) continue;
            size_t k = (size_t)Y * io->w + (size_t)X;
            int ok = gi__up_ok(&lo, k, pos, nrm, INFINITY, io->beta, &d2);
            if (ok > best_ok || (ok == best_ok && ok > 0 && d2 < best_d2)) best = k, best_ok = ok, best_d2 = d2;
        }
    if (best != SIZE_MAX) memcpy(out, lo.e + 3 * best, 3 * sizeof(float));
}

/* Frame pixel (x, y): the reference the SIMD kernel (gi__upsample,
 * gi_indirect_kernels.c) gives the bits of. */
static void gi__upsample_pixel(const gi__upsample_io *io, uint32_t x, uint32_t y)
{
    const rs_gbuffer *g = io->gbuf;
    const gi__up_planes lo = io->lo;
    const uint32_t s = io->s, w = io->w, h = io->h, W = io->W;
    const float a2 = io->a2, beta = io->beta, inv_s = 1.0f / (float)s;
    const uint32_t Y0 = y / s, Y1 = Y0 + 1 < h ? Y0 + 1 : Y0;
    const float ty = (float)(y - Y0 * s) * inv_s;
    size_t i = (size_t)y * W + x;
    float *out = io->filtered + 3 * i;
    out[0] = out[1] = out[2] = 0.0f;
    if (g->prim[i] == RS_GBUFFER_EMPTY) return;
    pf_vec3 pos = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]), nrm = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
    const uint32_t X0 = x / s, X1 = X0 + 1 < w ? X0 + 1 : X0;
    const float tx = (float)(x - X0 * s) * inv_s;
    const uint32_t xs[4] = {X0, X1, X0, X1}, ys[4] = {Y0, Y0, Y1, Y1};
    const float bw[4] = {(1.0f - tx) * (1.0f - ty), tx * (1.0f - ty), (1.0f - tx) * ty, tx * ty};
    float acc0 = 0.0f, acc1 = 0.0f, acc2 = 0.0f, wsum = 0.0f, d2;
    for (int c = 0; c < 4; c++) {
        size_t k = (size_t)ys[c] * w + xs[c];
        if (!(bw[c] > 0.0f) || gi__up_ok(&lo, k, pos, nrm, a2, beta, &d2) != 2) continue;
        const float *e = lo.e + 3 * k;
        acc0 += bw[c] * e[0], acc1 += bw[c] * e[1], acc2 += bw[c] * e[2];
        wsum += bw[c];
    }
    if (wsum > 0.0f) {
        out[0] = acc0 / wsum, out[1] = acc1 / wsum, out[2] = acc2 / wsum;
        return;
    }
    gi__upsample_fallback(io, i, X0, Y0, out);
}

static void gi__upsample_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__upsample_io *io = p;
    const gi_indirect_kernels *k = io->kern;
    uint32_t x = 0;
    if (k) {
        const uint32_t n = k->width;
        const gi_upsample_in in = {io->gbuf, io->lo.px, io->lo.py, io->lo.pz, io->lo.nx, io->lo.ny, io->lo.nz,
                                   io->lo.prim, io->lo.e, io->s, io->w, io->h, io->W, io->a2, io->beta};
        /* runs whose reduced samples lie inside the reduced row (s >= 2:
         * at most n consecutive reduced columns) */
        for (; x + n <= io->W && x / io->s + n <= io->w; x += n) {
            size_t i = (size_t)y * io->W + x;
            uint32_t fb = k->upsample(&in, x, y, io->filtered + 3 * i);
            for (; fb; fb &= fb - 1) {
                uint32_t l = (uint32_t)__builtin_ctz(fb);
                gi__upsample_fallback(io, i + l, (x + l) / io->s, y / io->s, io->filtered + 3 * (i + l));
            }
        }
    }
    for (; x < io->W; x++) gi__upsample_pixel(io, x, y);
}

void gi_stage_upsample(gi_frame *f)
{
    const gi_indirect *ind = &f->ind;
    if (ind->scale <= 1) return;
    const gi__upsample_io io = {&f->gbuf,
                                {ind->low.pos_x, ind->low.pos_y, ind->low.pos_z, ind->low.nrm_x, ind->low.nrm_y,
                                 ind->low.nrm_z, ind->low.prim, ind->filtered_low},
                                ind->filtered,
                                ind->scale,
                                ind->w,
                                ind->h,
                                f->width,
                                ind->alpha * ind->alpha,
                                ind->opt.beta,
                                gi__kernels(f)};
    pf_jobs_parallel_for(f->jobs, gi__upsample_row, (void *)&io, f->height, 8);
}

/* ---------------------------------------------------------- 9c. temporal */

/* Temporal accumulation with reprojection (opt.temporal = N; beyond Laine
 * 2007, after the reprojection caches of Nehab et al. 2007 and SVGF's
 * temporal pass, Schied et al. 2017). Each frame the tiles shade with a
 * rotated group of VPLs (gi_indirect_tile_group: tile t takes group
 * (t + frame) mod T), so over T frames a pixel has seen every VPL once, and
 * the history averages those frames: with a stable VPL set (IIR, SMC, TCAS,
 * a static light) the accumulated image tends to the one without
 * interleaving. Per pixel: its surface is projected into last frame's
 * camera; the history pixel there is taken when it saw a surface within
 * alpha of this one with a normal within beta (the filter's tests), else
 * the history restarts (disocclusion, a pixel that left the screen). The
 * blend is the running mean over the last min(n, N) frames,
 *   E = H + (E_new - H) / min(n + 1, N),
 * so a static view converges like an average of N frames and a moving light
 * or changing VPLs are followed within N frames (the lag is the price; N is
 * the knob). Nearest-pixel reprojection, no clamping of the history.
 * Anti-aliasing samples (--aa N, gi_aa.h): every sample blends with last
 * frame's history; only the last one rendered, the centre sample, writes
 * this frame's history and advances the frame count.
 * With --indirect-scale s > 1 the stage runs on the reduced image (the
 * filter's output and the reduced G-buffer `low`, before the upsampling):
 * s^2 fewer pixels, and low pixel (X, Y) is the frame's sample (s X, s Y),
 * so a surface projected to frame position p takes the history of the
 * nearest sample, X = floor((p_x - 1/2) / s + 1/2). */
/* The temporal stage's inputs and outputs, explicitly (the stage table's
 * reads and writes: GBUFFER and FILTERED in, FILTERED out, and the
 * history, read from one buffer pair and written to the other). */
typedef struct gi__temporal_ctx {
    const rs_gbuffer *gbuf;  /* GBUFFER */
    float *filtered;         /* FILTERED, blended in place */
    const pf_camera *pc;     /* last frame's camera */
    uint32_t W, H, N;        /* the image's size (the indirect stages'); opt.temporal */
    uint32_t s;              /* the indirect scale: the frame is s W x s H (about) */
    float inv_s;             /* 1 / s */
    float fw, fh;            /* the frame's size */
    float a2, beta;          /* the filter's tests */
    const float *hp[3], *hn[3], *h;
    const uint32_t *hprim;
    const uint16_t *hcount;
    float *op[3], *on[3], *o;
    uint32_t *oprim;
    uint16_t *ocount;
    int have;  /* a history exists */
    int write; /* this sample writes the history (o, oprim, ocount, op, on) */
    float th, ta; /* last camera: tan(fov / 2), and its aspect-scaled value */
} gi__temporal_ctx;

static void gi__temporal_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__temporal_ctx *c = p;
    const rs_gbuffer *g = c->gbuf;
    const pf_camera *pc = c->pc;
    const uint32_t W = c->W, H = c->H, N = c->N;
    const float a2 = c->a2, beta = c->beta;
    for (uint32_t x = 0; x < W; x++) {
        size_t i = (size_t)y * W + x;
        float *e = c->filtered + 3 * i;
        uint32_t prim = g->prim[i];
        if (c->write) {
            c->op[0][i] = g->pos_x[i], c->op[1][i] = g->pos_y[i], c->op[2][i] = g->pos_z[i];
            c->on[0][i] = g->nrm_x[i], c->on[1][i] = g->nrm_y[i], c->on[2][i] = g->nrm_z[i];
            c->oprim[i] = prim;
        }
        uint32_t n = 0;
        size_t j = SIZE_MAX;
        if (c->have && prim != RS_GBUFFER_EMPTY) {
            /* the surface in last frame's camera (pf_camera_ray_dir inverted) */
            pf_vec3 d = pf_v3_sub(pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]), pc->eye);
            float z = pf_v3_dot(d, pc->forward);
            if (z > 0.0f) {
                float sx = pf_v3_dot(d, pc->right) / z, sy = pf_v3_dot(d, pc->up) / z;
                float px = (sx / c->ta + 1.0f) * 0.5f * c->fw, py = (1.0f - sy / c->th) * 0.5f * c->fh;
                if (c->s > 1) /* the nearest reduced sample */
                    px = (px - 0.5f) * c->inv_s + 0.5f, py = (py - 0.5f) * c->inv_s + 0.5f;
                if (px >= 0.0f && py >= 0.0f && px < (float)W && py < (float)H) {
                    size_t k = (size_t)(uint32_t)py * W + (uint32_t)px;
                    float dx = c->hp[0][k] - g->pos_x[i], dy = c->hp[1][k] - g->pos_y[i], dz = c->hp[2][k] - g->pos_z[i];
                    float nd = c->hn[0][k] * g->nrm_x[i] + c->hn[1][k] * g->nrm_y[i] + c->hn[2][k] * g->nrm_z[i];
                    if (c->hprim[k] != RS_GBUFFER_EMPTY && dx * dx + dy * dy + dz * dz < a2 && nd > beta)
                        j = k, n = c->hcount[k];
                }
            }
        }
        uint32_t m = n + 1 < N ? n + 1 : N;
        if (j != SIZE_MAX) {
            const float *h = c->h + 3 * j;
            float inv = 1.0f / (float)m;
            for (int ch = 0; ch < 3; ch++) e[ch] = h[ch] + (e[ch] - h[ch]) * inv;
        }
        if (!c->write) continue;
        memcpy(c->o + 3 * i, e, 3 * sizeof(float));
        c->ocount[i] = (uint16_t)(prim != RS_GBUFFER_EMPTY ? m : 0);
    }
}

void gi_stage_temporal(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    if (!ind->opt.temporal) return;
    const int prev = ind->hist_cur, next = 1 - prev;
    gi__temporal_ctx c;
    memset(&c, 0, sizeof c);
    const int low = ind->scale > 1;
    c.gbuf = low ? &ind->low : &f->gbuf;
    c.filtered = low ? ind->filtered_low : ind->filtered;
    c.pc = &ind->hist_camera;
    c.W = ind->w, c.H = ind->h, c.N = ind->opt.temporal;
    c.s = ind->scale, c.inv_s = 1.0f / (float)ind->scale, c.fw = (float)f->width, c.fh = (float)f->height;
    c.a2 = ind->alpha * ind->alpha, c.beta = ind->opt.beta;
    for (int k = 0; k < 3; k++) {
        c.hp[k] = ind->hist_p[prev][k], c.hn[k] = ind->hist_nrm[prev][k];
        c.op[k] = ind->hist_p[next][k], c.on[k] = ind->hist_nrm[next][k];
    }
    c.h = ind->hist[prev], c.hprim = ind->hist_prim[prev], c.hcount = ind->hist_n[prev];
    c.o = ind->hist[next], c.oprim = ind->hist_prim[next], c.ocount = ind->hist_n[next];
    c.have = ind->temporal_frames > 0;
    c.write = f->aa.sample == 0;
    c.th = tanf(0.5f * ind->hist_camera.yfov);
    c.ta = c.th * (float)f->width / (float)f->height;
    pf_jobs_parallel_for(f->jobs, gi__temporal_row, &c, c.H, 8);
    if (!c.write) return;
    ind->hist_cur = next;
    ind->hist_camera = f->camera;
    ind->temporal_frames++;
}
