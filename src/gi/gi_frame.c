/* gi_frame: frame buffers, the camera model, the compose stage and the frame
 * outline (see gi_frame.h). */
#include "gi_frame.h"

#include "pf_budget.h"

#include <stdlib.h>
#include <string.h>

static const char *const gi__buffer_names[GI_BUF_COUNT] = {
    "visibility", "gbuffer", "shadow maps", "area-light maps", "direct", "VPL set", "VPL maps",
    "split", "assignment", "accumulated", "combined", "filtered", "final",
};

const char *gi_buffer_name(gi_buffer_id id) { return (unsigned)id < GI_BUF_COUNT ? gi__buffer_names[id] : "?"; }

#define B(id) GI_BUFFER_BIT(GI_BUF_##id)
/* The stage table (gi_frame.h). Reads and writes name the frame's buffers;
 * the VPL update also reads the lights and, for methods that say so
 * (gi_vpl_method.reads_gbuffer), the G-buffer. */
static const gi_stage_info gi__stages[GI_STAGE_COUNT] = {
    [GI_STAGE_GBUFFER_RASTER] = {"gbuffer raster (visibility)", 1, "Laine 2007 Sec. 3 step 5, Sec. 5.1",
                                 "G-buffer, visibility: the nearest triangle and its depth per pixel, rasterized",
                                 0, B(VISIBILITY), gi_stage_gbuffer_raster, 1},
    [GI_STAGE_GBUFFER_RAYTRACE] = {"gbuffer (embree)", 1, "Laine 2007 Sec. 3 step 5 (ray-traced, the reference)",
                                   "G-buffer from Embree primary rays: visibility and attributes in one pass", 0,
                                   B(VISIBILITY) | B(GBUFFER), gi_stage_gbuffer_raytrace, 1},
    [GI_STAGE_GBUFFER_RESOLVE] = {"gbuffer resolve (attributes)", 1, "Laine 2007 Sec. 5.1",
                                  "G-buffer attributes: position, camera-facing normal and albedo of each visible "
                                  "triangle",
                                  B(VISIBILITY), B(GBUFFER), gi_stage_gbuffer_resolve, 1},
    [GI_STAGE_SHADOW_MAPS] = {"shadow maps", 2, "Laine 2007 Sec. 6",
                              "Direct light's shadow maps: one map per light (a cube for point lights), the tiles the "
                              "visible receivers read, kept while the light stays",
                              B(GBUFFER), B(SHADOW_MAPS), gi_stage_shadow_maps, 1},
    [GI_STAGE_AREA_MAPS] = {"area-light maps", 2, "Brabec 2002 paraboloid maps",
                            "Area lights' maps: paraboloid maps of K fixed emitter points, first frame only", 0,
                            B(AREA_MAPS), gi_stage_area_shadow_maps, 0},
    [GI_STAGE_DIRECT_SHADOWMAP] = {"direct light (shadow maps)", 2, "Laine 2007 Sec. 3 (beside steps 1-4), Sec. 6",
                                   "Direct light: every light with its 16-tap PCF shadow test, E per pixel",
                                   B(GBUFFER) | B(SHADOW_MAPS) | B(AREA_MAPS), B(DIRECT),
                                   gi_stage_direct_shadowmap, 1},
    [GI_STAGE_DIRECT_RAYTRACE] = {"direct light (shadow rays)", 2, "Laine 2007 Sec. 3 (ray-traced, the reference)",
                                  "Direct light with Embree shadow rays; area lights by stratified samples",
                                  B(GBUFFER), B(DIRECT), gi_stage_direct_raytrace, 1},
    [GI_STAGE_VPL_UPDATE] = {"VPL update", 3, "Laine 2007 Sec. 3 steps 1-4; survey Sec. 4.1; the method's paper",
                             "VPL set: the method places the VPLs and sets their intensities", B(GBUFFER),
                             B(VPLS), gi_stage_vpl_update, 0},
    [GI_STAGE_VPL_MAPS] = {"VPL paraboloid maps", 4, "Laine 2007 Sec. 3 step 3, Sec. 4.6; Brabec 2002",
                           "VPL shadow maps: paraboloid maps of new and moved VPLs (or every VPL's ISM)", B(VPLS),
                           B(VPL_MAPS), gi_stage_vpl_shadow_maps, 0},
    [GI_STAGE_SPLIT] = {"split", 5, "Laine 2007 Sec. 3 step 6, Sec. 5.1",
                        "Split G-buffer: n x m interleaved tiles, each the image sub-sampled with its own offset",
                        B(GBUFFER), B(SPLIT), gi_stage_split, 1},
    [GI_STAGE_ASSIGN] = {"assign VPLs to tiles", 6, "Laine 2007 Sec. 5.1 and Sec. 7",
                         "Assignment: each VPL to one tile, a surviving VPL keeps its tile", B(VPLS),
                         B(ASSIGNMENT), gi_stage_assign, 0},
    [GI_STAGE_ACCUMULATE] = {"accumulate", 7, "Laine 2007 Sec. 3 step 7, Sec. 5.1; survey Sec. 5",
                             "Accumulated: each tile's irradiance from its share of the VPLs, bounded geometry term",
                             B(SPLIT) | B(VPLS) | B(VPL_MAPS) | B(ASSIGNMENT), B(ACCUMULATED),
                             gi_stage_accumulate, 1},
    [GI_STAGE_COMBINE] = {"combine", 8, "Laine 2007 Sec. 3 step 8, Sec. 5.1",
                          "Combined: the tiles back in image layout; the n x m structured noise is visible (Fig. 4a)",
                          B(ACCUMULATED), B(COMBINED), gi_stage_combine, 1},
    [GI_STAGE_COMPENSATE] = {"compensate", 8, "survey Sec. 5.2; Novak 2011 screen-space bias compensation",
                             "Compensated: the light the clamp removed, gathered from nearby pixels, added back",
                             B(GBUFFER) | B(DIRECT) | B(COMBINED), B(COMBINED), gi_stage_compensate, 1},
    [GI_STAGE_FILTER] = {"filter", 9, "Laine 2007 Sec. 3 step 9, Sec. 5.2, Fig. 5",
                         "Filtered: the geometry-aware n x m box filter (or the chosen filter) removes the pattern",
                         B(GBUFFER) | B(COMBINED), B(FILTERED), gi_stage_filter, 1},
    [GI_STAGE_UPSAMPLE] = {"upsample", 9, "beyond the papers: joint bilateral upsampling (Kopf 2007) with Laine's tests",
                           "Upsampled: the reduced-resolution irradiance to the frame's size, geometry-aware",
                           B(GBUFFER) | B(FILTERED), B(FILTERED), gi_stage_upsample, 1},
    [GI_STAGE_TEMPORAL] = {"temporal", 9, "beyond the papers: reprojected history (Nehab 2007; Schied 2017)",
                           "Temporal: the filtered irradiance averaged with last frames' at the same surface",
                           B(GBUFFER) | B(FILTERED), B(FILTERED), gi_stage_temporal, 1},
    [GI_STAGE_COMPOSE] = {"compose", 10, "Laine 2007 Sec. 3 (after step 9)",
                          "Final: emission + direct + albedo / pi x filtered indirect, linear RGB",
                          B(VISIBILITY) | B(GBUFFER) | B(DIRECT) | B(FILTERED), B(FINAL), gi_stage_compose, 1},
    [GI_STAGE_AA_RESOLVE] = {"anti-aliasing (average)", 10, "supersampling: the pixel's box filter, N jittered samples "
                             "(pbrt 3rd ed. Sec. 7.8)",
                             "Final: the N jittered samples' linear radiance averaged (--aa N)", B(FINAL), B(FINAL),
                             gi_stage_aa_resolve, 1},
    [GI_STAGE_TAA] = {"temporal anti-aliasing", 10, "beyond the papers: Yang 2009; Karis 2014 (reprojection, clamp)",
                      "Final: averaged with the reprojected history of earlier frames, each jittered (--taa N)",
                      B(VISIBILITY) | B(GBUFFER) | B(FINAL), B(FINAL), gi_stage_taa, 0},
};
#undef B

const gi_stage_info *gi_stage_get(gi_stage_id id) { return (unsigned)id < GI_STAGE_COUNT ? &gi__stages[id] : NULL; }

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
    f->area_points = points;
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

/* The frame's buffers, shadow-map set and default area sampling; gi_frame_create
 * adds the rest of the description. */
static pf_result gi__frame_init(gi_frame *f, const pf_scene *scene, const pf_rt *rt, rs_context *raster,
                                pf_jobs *jobs, const pf_camera *camera, uint32_t width, uint32_t height,
                                uint32_t shadow_size, pf_error *err)
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
    f->aa.samples = 1;
    pf_result r = rs_gbuffer_init(&f->gbuf, width, height, err);
    if (r != PF_OK) return r;
    r = gi_area_lights_build(&f->area, scene, err);
    if (r != PF_OK) {
        gi_frame_free(f);
        return r;
    }
    size_t n = (size_t)width * height * 3;
    f->direct = pf_arena_calloc(&f->mem, n, sizeof(float));
    f->final = pf_arena_calloc(&f->mem, n, sizeof(float));
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

pf_result gi_frame_create(gi_frame *f, const gi_frame_desc *d, pf_error *err)
{
    memset(f, 0, sizeof *f);
    if (!d || !d->scene || !d->jobs || d->width == 0 || d->height == 0)
        return pf_error_set(err, PF_ERR_ARGUMENT, "frame: a scene, a job system and a size are required");
    const pf_camera *cam = d->camera;
    if (!cam) {
        if (d->scene->camera_count == 0) return pf_error_set(err, PF_ERR_ARGUMENT, "frame: the scene has no camera");
        cam = &d->scene->cameras[0];
    }
    pf_result r = gi__frame_init(f, d->scene, d->rt, d->raster, d->jobs, cam, d->width, d->height, d->shadow_size, err);
    f->area_slope = d->area_slope;
    if (r == PF_OK && (d->area_strata || d->area_points))
        r = gi_frame_set_area_sampling(f, d->area_strata ? d->area_strata : GI_AREA_DEFAULT_STRATA,
                                       d->area_points ? d->area_points : GI_AREA_DEFAULT_POINTS, err);
    if (r == PF_OK && d->indirect) r = gi_frame_enable_indirect(f, d->indirect, d->indirect_only, err);
    if (r == PF_OK) r = gi_frame_set_aa(f, d->aa_samples ? d->aa_samples : 1, d->taa_frames, err);
    if (r != PF_OK) gi_frame_free(f);
    return r;
}

void gi_frame_free(gi_frame *f)
{
    rs_gbuffer_free(&f->gbuf);
    rs_shadow_set_free(&f->shadows);
    gi_light_copy_free(&f->shadow_lights);
    gi_indirect_free(&f->ind);
    gi__area_maps_free(&f->area_maps);
    gi_area_lights_free(&f->area);
    gi_aa_free(&f->aa);
    free(f->motion.tri_moved);
    free(f->motion.ranges);
    free(f->moved_shadows.ranges), free(f->moved_area.ranges), free(f->moved_maps.ranges);
    pf_arena_release(&f->mem); /* direct, final */
    pf_arena_release(&f->scratch);
    memset(f, 0, sizeof *f);
}

void *gi_frame_scratch(gi_frame *f, size_t count, size_t size, const char *what)
{
    /* count 0 gets one element: callers pass the pointer to memset/qsort */
    void *p = pf_arena_calloc(&f->scratch, count ? count : 1, size);
    if (!p && f->status == PF_OK)
        f->status = pf_error_set(&f->error, PF_ERR_OUT_OF_MEMORY, "out of memory for %s (%zu x %zu bytes)", what,
                                 count, size);
    return p;
}

/* What every frame does first: its scratch and status afresh. */
static void gi__frame_begin(gi_frame *f)
{
    memset(&f->times, 0, sizeof f->times);
    pf_arena_reset(&f->scratch);
    f->status = PF_OK;
}

pf_ray gi_camera_ray(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y)
{
    return gi_camera_ray_at(cam, width, height, x, y, 0.0f, 0.0f);
}

pf_ray gi_camera_ray_at(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y, float jx,
                        float jy)
{
    pf_ray r;
    r.org = cam->eye;
    /* x + 1/2 + 0 is x + 1/2 exactly: the centre's bits for (0, 0) */
    r.dir = pf_camera_ray_dir(cam, width, height, (float)x + 0.5f + jx, (float)y + 0.5f + jy);
    r.tnear = cam->znear;
    r.tfar = cam->zfar > 0.0f ? cam->zfar : INFINITY;
    return r;
}

/* Compose: emission of the visible surface + direct light + albedo / pi x
 * the filtered indirect irradiance. Misses are black. Its inputs and its
 * output, explicitly (the stage table's reads and writes): */
typedef struct gi__compose_io {
    const pf_scene *scene;   /* emission, through the triangle's material */
    const rs_gbuffer *gbuf;  /* VISIBILITY (prim) and GBUFFER (albedo) */
    const float *direct;     /* DIRECT; NULL: not shown (emission neither) */
    const float *filtered;   /* FILTERED; NULL: no indirect light */
    float *final;            /* FINAL */
    uint32_t width;
} gi__compose_io;

static void gi__compose_rows(void *ctx, uint32_t row, uint32_t worker)
{
    (void)worker;
    const gi__compose_io *io = ctx;
    for (uint32_t x = 0; x < io->width; x++) {
        size_t i = (size_t)row * io->width + x;
        uint32_t prim = io->gbuf->prim[i];
        float e[3] = {0, 0, 0};
        if (prim != RS_GBUFFER_EMPTY && io->direct)
            memcpy(e, io->scene->materials[io->scene->tri_material[prim]].emission, sizeof e);
        const float alb[3] = {io->gbuf->alb_r[i], io->gbuf->alb_g[i], io->gbuf->alb_b[i]};
        for (int c = 0; c < 3; c++) {
            float v = e[c] + (io->direct ? io->direct[3 * i + c] : 0.0f);
            if (io->filtered) v += alb[c] * PF_INV_PI * io->filtered[3 * i + c];
            io->final[3 * i + c] = v;
        }
    }
}

void gi_stage_compose(gi_frame *f)
{
    const gi__compose_io io = {f->scene, &f->gbuf, f->show_direct ? f->direct : NULL,
                               f->indirect ? f->ind.filtered : NULL, f->final, f->width};
    pf_jobs_parallel_for(f->jobs, gi__compose_rows, (void *)&io, f->height, 8);
}

/* Direct light is computed when the image shows it, and for the clamp
 * compensation, which reflects it (--indirect-only --compensate). */
static int gi__needs_direct(const gi_frame *f) { return f->show_direct || (f->indirect && f->ind.opt.compensate); }

/* Runs stage `id` of the table and adds its time under the table's name. */
static void gi__run(gi_frame *f, gi_stage_id id)
{
    const gi_stage_info *s = &gi__stages[id];
    double t0 = pf_time_now();
    s->run(f);
    pf_stage_add(&f->times, s->name, (pf_time_now() - t0) * 1e3);
}

void gi_stage_gbuffer_raster(gi_frame *f)
{
    rs_target t = {f->width, f->height, f->gbuf.depth, f->gbuf.prim, NULL};
    rs_pass pass;
    /* the sample's jitter (gi_aa.h): rs_mat4_camera's matrix at the centre */
    pass.view_proj = gi_aa_view_proj(&f->camera, f->width, f->height, f->aa.jx, f->aa.jy);
    pass.cull = RS_CULL_NONE; /* two-sided shading, like the ray-traced path */
    rs_render(f->raster, &pass, &t, NULL);
}

void gi_stage_gbuffer_resolve(gi_frame *f)
{
    /* the frame's SIMD path: 8 lanes with AVX2, 16 with AVX-512 (same bits) */
    int simd = f->raster ? (int)rs_context_simd(f->raster) : 0;
    /* the resolve traces the pixel centres' rays: a jittered sample's rays
     * are those of a camera with a tilted forward axis (gi_aa.h) */
    pf_camera cam = gi_aa_resolve_camera(&f->camera, f->width, f->height, f->aa.jx, f->aa.jy);
    rs_gbuffer_resolve_simd(&f->gbuf, f->scene, f->raster ? rs_context_resolve_table(f->raster) : NULL, &cam,
                            f->jobs, simd);
    gi_aa_resolve_depth(f);
}

pf_result gi_frame_enable_indirect(gi_frame *f, const gi_indirect_options *opt, int indirect_only, pf_error *err)
{
    pf_result r = gi_indirect_init(f, opt, err);
    if (r != PF_OK) return r;
    f->indirect = 1;
    f->show_direct = !indirect_only;
    return PF_OK;
}

/* Steps 3-9 (both frames) of one anti-aliasing sample: the VPL update, its
 * maps and the assignment with the frame's first sample only (`first`).
 * Pipelined (after frame 0), step 3 is the update job for the next frame,
 * started here, after the last sample's G-buffer (`last`: the centre
 * sample's, which nothing overwrites before the frame ends), unless it
 * started before the G-buffer; steps 4-9 shade with the set made during the
 * previous frame. With one sample (the default) first and last are the same
 * sample and this is the paper's outline. */
static void gi__indirect_stages(gi_frame *f, int first, int last)
{
    if (!f->indirect) return;
    const int pipelined = f->ind.opt.pipeline && f->ind.have_set;
    if (pipelined && last) gi_stage_vpl_update_begin(f, 1);
    if (first) {
        if (!pipelined) gi__run(f, GI_STAGE_VPL_UPDATE);
        gi__run(f, GI_STAGE_VPL_MAPS);
    }
    gi__run(f, GI_STAGE_SPLIT);
    if (first) gi__run(f, GI_STAGE_ASSIGN);
    gi__run(f, GI_STAGE_ACCUMULATE);
    gi__run(f, GI_STAGE_COMBINE);
    if (f->ind.opt.compensate) gi__run(f, GI_STAGE_COMPENSATE);
    gi__run(f, GI_STAGE_FILTER);
    if (f->ind.opt.temporal) gi__run(f, GI_STAGE_TEMPORAL); /* at the reduced size, before the upsampling */
    if (f->ind.scale > 1) gi__run(f, GI_STAGE_UPSAMPLE);
}

/* The samples of the frame (gi_aa.h): k-th of N renders sample (k + 1)
 * mod N, the centre last; each ends by adding its `final` to the average
 * (N > 1), and the temporal anti-aliasing (--taa) follows the last. */
void gi_frame_render_raytraced(gi_frame *f)
{
    gi__frame_begin(f);
    gi_stage_vpl_update_begin(f, 0); /* pipelined, G-buffer-free methods: overlap everything */
    const uint32_t N = f->aa.samples;
    for (uint32_t k = 0; k < N; k++) {
        gi_aa_sample_begin(f, k);
        gi__run(f, GI_STAGE_GBUFFER_RAYTRACE);
        if (gi__needs_direct(f)) gi__run(f, GI_STAGE_DIRECT_RAYTRACE);
        gi__indirect_stages(f, k == 0, k + 1 == N);
        gi__run(f, GI_STAGE_COMPOSE);
        if (N > 1) gi__run(f, GI_STAGE_AA_RESOLVE);
    }
    if (f->aa.taa.frames) gi__run(f, GI_STAGE_TAA);
    pf_jobs_wait_all(f->jobs);
    gi_stage_vpl_update_end(f);
}

void gi_frame_render_raster(gi_frame *f)
{
    gi__frame_begin(f);
    memset(&f->motion_stats, 0, sizeof f->motion_stats);
    gi_stage_vpl_update_begin(f, 0); /* pipelined, G-buffer-free methods: overlap everything */
    const uint32_t N = f->aa.samples;
    for (uint32_t k = 0; k < N; k++) {
        gi_aa_sample_begin(f, k);
        gi__run(f, GI_STAGE_GBUFFER_RASTER);
        gi__run(f, GI_STAGE_GBUFFER_RESOLVE);
        if (gi__needs_direct(f)) {
            gi__run(f, GI_STAGE_SHADOW_MAPS); /* the tiles this sample's receivers read */
            if (k == 0) gi__run(f, GI_STAGE_AREA_MAPS); /* these do not depend on the camera */
            gi__run(f, GI_STAGE_DIRECT_SHADOWMAP);
        }
        gi__indirect_stages(f, k == 0, k + 1 == N);
        gi__run(f, GI_STAGE_COMPOSE);
        if (N > 1) gi__run(f, GI_STAGE_AA_RESOLVE);
    }
    if (f->aa.taa.frames) gi__run(f, GI_STAGE_TAA);
    pf_jobs_wait_all(f->jobs);
    gi_stage_vpl_update_end(f);
    /* the G-buffer's and the shadow maps' passes, all at once (after a
     * stage's own failure, which came first) */
    if (f->status == PF_OK) f->status = rs_context_status(f->raster, &f->error);
}
