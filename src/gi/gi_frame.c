/* gi_frame: frame buffers, the camera model, the compose stage and the frame
 * outline (see gi_frame.h). */
#include "gi_frame.h"

#include "pf_budget.h"

#include <stdlib.h>
#include <string.h>

static const char *const gi__buffer_names[GI_BUF_COUNT] = {
    "depth", "position", "normal", "albedo", "prim", "direct", "vpls", "split", "accumulated", "combined", "filtered",
    "final",
};
static const char *const gi__buffer_captions[GI_BUF_COUNT] = {
    "G-buffer depth: view-space distance of the visible surface (Laine 2007 Sec. 3, step 1)",
    "G-buffer world position of the visible surface",
    "G-buffer shading normal, turned to face the camera",
    "G-buffer albedo: filtered baseColor, linear RGB",
    "G-buffer primitive id: which triangle each pixel sees",
    "Direct light: every light with its shadow test, albedo E / pi (Laine 2007 Sec. 3, step 5)",
    "VPL set: each VPL drawn where it projects, coloured by its intensity (Laine 2007 Sec. 4; survey Sec. 4.1)",
    "Split G-buffer: n x m interleaved tiles, each the image sub-sampled with its own offset (Laine 2007 Sec. 5.1)",
    "Accumulated: each tile's irradiance from its share of the VPLs, bounded geometry term (Sec. 5.1; survey Sec. 5)",
    "Combined: the tiles back in image layout; the n x m structured noise is visible (Laine 2007 Fig. 4a)",
    "Filtered: geometry-aware n x m box filter (Laine 2007 Fig. 5) removes the pattern",
    "Final: emission + direct + albedo / pi x filtered indirect, linear RGB",
};

const char *gi_buffer_name(gi_buffer_id id) { return (unsigned)id < GI_BUF_COUNT ? gi__buffer_names[id] : "?"; }
const char *gi_buffer_caption(gi_buffer_id id)
{
    return (unsigned)id < GI_BUF_COUNT ? gi__buffer_captions[id] : "?";
}

static void gi__area_maps_free(gi_area_maps *m)
{
    rs_para_context_destroy(m->para);
    free(m->atlas);
    free(m->frames);
    free(m->weight);
    memset(m, 0, sizeof *m);
}

/* The K fixed emitter points of the rasterized direct light (see
 * gi_frame.h): positions, frames and weights now, maps at the first frame. */
static pf_result gi__area_maps_init(gi_frame *f, uint32_t K, pf_error *err)
{
    gi_area_maps *m = &f->area_maps;
    gi__area_maps_free(m);
    if (!f->raster || f->area.count == 0) return PF_OK;
    pf_result r = rs_para_context_create(&m->para, f->scene, NULL, err);
    if (r != PF_OK) return r;
    m->atlas = malloc(rs_para_atlas_bytes(RS_PARA_DEFAULT_RES, K));
    m->frames = calloc(K, sizeof *m->frames);
    m->weight = calloc(K, sizeof *m->weight);
    if (!m->atlas || !m->frames || !m->weight) {
        gi__area_maps_free(m);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u area-light maps", K);
    }
    for (uint32_t k = 0; k < K; k++) {
        gi_area_sample as;
        gi_area_sample_point(&f->area, ((double)k + 0.5) / K, (float)gi_halton(k + 1, 2), (float)gi_halton(k + 1, 3),
                             &as);
        /* the map's centre just off the emitter, on its emitting side */
        pf_vec3 o = pf_rt_offset_origin(as.p, as.n, as.n);
        m->frames[k] = rs_para_frame_make(o, as.n);
        m->weight[k] = pf_v3_scale(as.radiance, 1.0f / ((float)K * as.pdf_area));
    }
    m->count = K;
    m->range = rs_para_default_range(f->scene);
    return PF_OK;
}

pf_result gi_frame_set_area_sampling(gi_frame *f, uint32_t strata, uint32_t points, pf_error *err)
{
    if (strata < 1 || strata > GI_AREA_MAX_STRATA)
        return pf_error_set(err, PF_ERR_ARGUMENT, "area-light strata %u: expected 1..%u", strata, GI_AREA_MAX_STRATA);
    if (points < 1 || points > GI_AREA_MAX_POINTS)
        return pf_error_set(err, PF_ERR_ARGUMENT, "area-light points %u: expected 1..%u", points, GI_AREA_MAX_POINTS);
    f->area_strata = strata;
    return gi__area_maps_init(f, points, err);
}

uint64_t gi_frame_memory_estimate(const pf_scene *scene, uint32_t width, uint32_t height, uint32_t shadow_size,
                                  uint32_t vpls, uint32_t para_res, uint32_t area_points)
{
    uint64_t bytes = pf_budget_mul((uint64_t)width * height, GI_FRAME_BYTES_PER_PIXEL);
    uint64_t side = shadow_size ? shadow_size : RS_SHADOW_DEFAULT_SIZE;
    for (uint32_t l = 0; l < scene->light_count; l++) {
        const pf_light *L = &scene->lights[l];
        uint64_t faces = L->type == PF_LIGHT_POINT || (L->type == PF_LIGHT_SPOT && L->outer_cone > RS_SHADOW_SPOT_MAX_CONE)
                             ? 6
                             : 1;
        bytes += pf_budget_mul(faces * side * side, sizeof(float));
    }
    uint64_t R = para_res ? para_res : RS_PARA_DEFAULT_RES;
    /* per VPL: its map (2 bytes a texel), its frame and bookkeeping */
    bytes += pf_budget_mul(vpls, R * R * 2 + 512);
    if (area_points) bytes += pf_budget_mul(area_points, (uint64_t)RS_PARA_DEFAULT_RES * RS_PARA_DEFAULT_RES * 2 + 512);
    return bytes;
}

pf_result gi_frame_init(gi_frame *f, const pf_scene *scene, const pf_rt *rt, rs_context *raster, pf_jobs *jobs,
                        const pf_camera *camera, uint32_t width, uint32_t height, uint32_t shadow_size, pf_error *err)
{
    memset(f, 0, sizeof *f);
    f->scene = scene;
    f->rt = rt;
    f->raster = raster;
    f->jobs = jobs;
    f->camera = *camera;
    f->width = width;
    f->height = height;
    f->show_direct = 1;
    pf_result r = rs_gbuffer_init(&f->gbuf, width, height, err);
    if (r != PF_OK) return r;
    r = gi_area_lights_build(&f->area, scene, err);
    if (r != PF_OK) {
        gi_frame_free(f);
        return r;
    }
    size_t n = (size_t)width * height * 3;
    f->direct = calloc(n, sizeof(float));
    f->final = calloc(n, sizeof(float));
    if (!f->direct || !f->final) {
        gi_frame_free(f);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%u frame", width, height);
    }
    f->area_strata = GI_AREA_DEFAULT_STRATA;
    r = gi_frame_set_area_sampling(f, GI_AREA_DEFAULT_STRATA, GI_AREA_DEFAULT_POINTS, err);
    if (r != PF_OK) {
        gi_frame_free(f);
        return r;
    }
    if (raster) {
        rs_shadow_desc desc;
        memset(&desc, 0, sizeof desc);
        desc.size = shadow_size;
        f->shadow_size = shadow_size;
        r = rs_shadow_set_init(&f->shadows, scene, &desc, err);
        if (r != PF_OK) {
            gi_frame_free(f);
            return r;
        }
    }
    return PF_OK;
}

void gi_frame_free(gi_frame *f)
{
    rs_gbuffer_free(&f->gbuf);
    rs_shadow_set_free(&f->shadows);
    free(f->shadow_lights);
    gi_indirect_free(&f->ind);
    gi__area_maps_free(&f->area_maps);
    gi_area_lights_free(&f->area);
    free(f->direct);
    free(f->final);
    memset(f, 0, sizeof *f);
}

pf_ray gi_camera_ray(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y)
{
    pf_ray r;
    r.org = cam->eye;
    r.dir = pf_camera_ray_dir(cam, width, height, (float)x + 0.5f, (float)y + 0.5f);
    r.tnear = cam->znear;
    r.tfar = cam->zfar > 0.0f ? cam->zfar : INFINITY;
    return r;
}

/* Compose: emission of the visible surface + direct light + albedo / pi x
 * the filtered indirect irradiance. Misses are black. */
typedef struct gi__compose_ctx {
    gi_frame *f;
} gi__compose_ctx;

static void gi__compose_rows(void *ctx, uint32_t row, uint32_t worker)
{
    (void)worker;
    gi_frame *f = ((gi__compose_ctx *)ctx)->f;
    for (uint32_t x = 0; x < f->width; x++) {
        size_t i = (size_t)row * f->width + x;
        uint32_t prim = f->gbuf.prim[i];
        float e[3] = {0, 0, 0};
        if (prim != RS_GBUFFER_EMPTY && f->show_direct)
            memcpy(e, f->scene->materials[f->scene->tri_material[prim]].emission, sizeof e);
        const float alb[3] = {f->gbuf.alb_r[i], f->gbuf.alb_g[i], f->gbuf.alb_b[i]};
        for (int c = 0; c < 3; c++) {
            float v = e[c] + (f->show_direct ? f->direct[3 * i + c] : 0.0f);
            if (f->indirect) v += alb[c] * PF_INV_PI * f->ind.filtered[3 * i + c];
            f->final[3 * i + c] = v;
        }
    }
}

void gi_stage_compose(gi_frame *f)
{
    gi__compose_ctx ctx = {f};
    pf_jobs_parallel_for(f->jobs, gi__compose_rows, &ctx, f->height, 8);
}

static void gi__timed(gi_frame *f, const char *name, void (*stage)(gi_frame *))
{
    double t0 = pf_time_now();
    stage(f);
    pf_stage_add(&f->times, name, (pf_time_now() - t0) * 1e3);
}

void gi_stage_gbuffer_raster(gi_frame *f)
{
    rs_target t = {f->width, f->height, f->gbuf.depth, f->gbuf.prim, NULL};
    rs_pass pass;
    pass.view_proj = rs_mat4_camera(&f->camera, f->width, f->height);
    pass.cull = RS_CULL_NONE; /* two-sided shading, like the ray-traced path */
    rs_render(f->raster, &pass, &t, NULL);
}

void gi_stage_gbuffer_resolve(gi_frame *f)
{
    int simd = f->raster && rs_context_simd(f->raster) != RS_SIMD_SCALAR;
    rs_gbuffer_resolve_simd(&f->gbuf, f->scene, f->raster ? rs_context_resolve_table(f->raster) : NULL, &f->camera,
                            f->jobs, simd);
}

pf_result gi_frame_enable_indirect(gi_frame *f, const gi_indirect_options *opt, int indirect_only, pf_error *err)
{
    pf_result r = gi_indirect_init(f, opt, err);
    if (r != PF_OK) return r;
    f->indirect = 1;
    f->show_direct = !indirect_only;
    return PF_OK;
}

/* Steps 3-9 (both frames). Pipelined (after frame 0), step 3 is the
 * update job for the next frame, started here unless it started before the
 * G-buffer; steps 4-9 shade with the set made during the previous frame. */
static void gi__indirect_stages(gi_frame *f)
{
    if (!f->indirect) return;
    if (f->ind.opt.pipeline && f->ind.have_set) gi_stage_vpl_update_begin(f, 1);
    else gi__timed(f, "VPL update", gi_stage_vpl_update);
    gi__timed(f, "VPL paraboloid maps", gi_stage_vpl_shadow_maps);
    gi__timed(f, "split", gi_stage_split);
    gi__timed(f, "assign VPLs to tiles", gi_stage_assign);
    gi__timed(f, "accumulate", gi_stage_accumulate);
    gi__timed(f, "combine", gi_stage_combine);
    gi__timed(f, "filter", gi_stage_filter);
}

void gi_frame_render_raytraced(gi_frame *f)
{
    memset(&f->times, 0, sizeof f->times);
    gi_stage_vpl_update_begin(f, 0); /* pipelined, G-buffer-free methods: overlap everything */
    gi__timed(f, "gbuffer (embree)", gi_stage_gbuffer_raytrace);
    if (f->show_direct) gi__timed(f, "direct light (shadow rays)", gi_stage_direct_raytrace);
    gi__indirect_stages(f);
    gi__timed(f, "compose", gi_stage_compose);
    pf_jobs_wait_all(f->jobs);
    gi_stage_vpl_update_end(f);
}

void gi_frame_render_raster(gi_frame *f)
{
    memset(&f->times, 0, sizeof f->times);
    gi_stage_vpl_update_begin(f, 0); /* pipelined, G-buffer-free methods: overlap everything */
    gi__timed(f, "gbuffer raster (visibility)", gi_stage_gbuffer_raster);
    gi__timed(f, "gbuffer resolve (attributes)", gi_stage_gbuffer_resolve);
    if (f->show_direct) {
        gi__timed(f, "shadow maps", gi_stage_shadow_maps);
        gi__timed(f, "area-light maps", gi_stage_area_shadow_maps);
        gi__timed(f, "direct light (shadow maps)", gi_stage_direct_shadowmap);
    }
    gi__indirect_stages(f);
    gi__timed(f, "compose", gi_stage_compose);
    pf_jobs_wait_all(f->jobs);
    gi_stage_vpl_update_end(f);
}
