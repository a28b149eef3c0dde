/* app_bench_moving: `softgi bench frame --moving-object` — what a moving
 * object costs the frame.
 *
 * Sibenik (from --scenes, textures ignored, as `bench frame`) at 1024x768
 * with `bench frame`'s camera and point light, and one object appended to
 * it: a torus of BM_SEG x BM_RING x 2 = 4096 triangles (1.9 m across, grey
 * albedo 0.6), standing on the nave's floor in view of the camera. Two
 * worlds are made side by side, each its own scene copy, Embree scene (with
 * the dynamic split, pf_rt_create_dynamic: the object a child scene of its
 * own), rasterizer and frame, with the method of --method (default iir:
 * the target is Incremental Instant Radiosity's frame), --vpls
 * (default 256), --threads (default 2), pipelining --pipeline (default
 * off):
 *   static  the object stands still at its first pose;
 *   moving  before frame i the object is rigidly moved to pose i: rotated
 *           by 2 pi i / BM_PERIOD about the vertical and carried along a
 *           circle of radius BM_RADIUS m around its first place (about
 *           0.6 m a frame), and the renderer is brought up to date:
 *             pose             the object's vertices and normals (rest x pose)
 *             embree rebuild   pf_rt_update REBUILD, what softgi sequence
 *                              and softgi_set_time use (a fresh build's
 *                              bytes; counted in the frame)
 *             embree refit     pf_rt_update REFIT of a second Embree
 *                              scene of the same world, timed for
 *                              comparison and not counted ("refit
 *                              ... where that is enough, rebuild where it
 *                              is not; measure both")
 *             raster update    rs_context_update
 *             frame update     gi_frame_geometry_moved (gi_motion.h)
 * The worlds' frames alternate (frame i of each, then frame i + 1), one
 * warm-up frame, then --frames (default 15); rows are stage medians, the
 * "frame" row the median of the whole frame (updates included for the
 * moving world). What the frame redrew for the object is printed
 * (gi_motion_stats means): shadow-map faces and texels, VPL maps drawn
 * again in part and the texels tested in them. The target:
 * moving / static - 1 <= 25% with 2 threads. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_setup.h"
#include "app.h"
#include "pf_jobs.h"
#include "gi_frame.h"
#include "pf_anim.h"
#include "pf_gltf.h"
#include "pf_rt.h"
#include "pf_timer.h"
#include "rs_raster.h"

#define BM_W 1024
#define BM_H 768
#define BM_SEG 64    /* torus: segments around the main circle */
#define BM_RING 32   /* and around the tube */
#define BM_MAJOR 0.7f
#define BM_MINOR 0.25f
#define BM_PERIOD 16 /* frames a turn */
#define BM_RADIUS 1.5f
#define BM_TARGET 0.25 /* moving / static - 1 */
#define BM_TARGET_THREADS 2u

/* Sibenik as `bench frame` shows it: camera, light; the object's centre. */
static const pf_vec3 bm_eye = {-18.0f, -11.0f, 0.0f}, bm_target = {10.0f, -8.0f, 0.0f};
static const float bm_fovy = 70.0f;
static const pf_vec3 bm_light = {0.0f, 0.0f, 0.0f};
static const float bm_light_intensity = 50.0f;
static const pf_vec3 bm_centre = {-7.0f, -11.6f, 0.0f};

/* One world: its scene (geometry arrays its own, materials and textures
 * shared with the loaded scene's copy), the object's rest shape, the
 * dynamic split, Embree (and the second one only timed), the rasterizer, the
 * frame. */
typedef struct bm_world {
    pf_scene scene;
    pf_light light;
    uint32_t v0, nv, t0, nt; /* the object's vertices and triangles */
    pf_vec3 *rest_p, *rest_n; /* object space, centred */
    pf_vec3 static_lo, static_hi; /* the loaded scene's bounds (the scene's are these and the object's) */
    pf_anim anim;             /* two instanced primitives: the scene (static), the object (dynamic) */
    pf_anim_prim prims[2];
    pf_anim_moved moved[2];
    pf_rt *rt, *rt_refit;
    rs_context *raster;
    gi_frame frame;
    int frame_ready;
} bm_world;

/* The scene's geometry copied, the torus appended with a material of its
 * own (arrays sized for it; the padding position kept). */
static pf_result bm__world_scene(bm_world *w, const pf_scene *src, pf_error *err)
{
    pf_scene *s = &w->scene;
    *s = *src;
    w->nv = (BM_SEG + 1) * (BM_RING + 1);
    w->nt = BM_SEG * BM_RING * 2;
    w->v0 = src->vertex_count, w->t0 = src->tri_count;
    w->static_lo = src->bounds_min, w->static_hi = src->bounds_max;
    size_t nv = (size_t)src->vertex_count + w->nv, nt = (size_t)src->tri_count + w->nt;
    s->positions = malloc(sizeof(pf_vec3) * (nv + 1));
    s->normals = malloc(sizeof(pf_vec3) * nv);
    s->uvs = malloc(sizeof(pf_vec2) * nv);
    s->indices = malloc(sizeof(uint32_t) * 3 * nt);
    s->tri_material = malloc(sizeof(uint32_t) * nt);
    s->materials = malloc(sizeof(pf_material) * (src->material_count + 1));
    w->rest_p = malloc(sizeof(pf_vec3) * w->nv);
    w->rest_n = malloc(sizeof(pf_vec3) * w->nv);
    if (!s->positions || !s->normals || !s->uvs || !s->indices || !s->tri_material || !s->materials || !w->rest_p ||
        !w->rest_n)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the moving object's scene");
    memcpy(s->positions, src->positions, sizeof(pf_vec3) * src->vertex_count);
    memcpy(s->normals, src->normals, sizeof(pf_vec3) * src->vertex_count);
    memcpy(s->uvs, src->uvs, sizeof(pf_vec2) * src->vertex_count);
    memcpy(s->indices, src->indices, sizeof(uint32_t) * 3 * src->tri_count);
    memcpy(s->tri_material, src->tri_material, sizeof(uint32_t) * src->tri_count);
    memcpy(s->materials, src->materials, sizeof(pf_material) * src->material_count);
    pf_material *m = &s->materials[src->material_count];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "bench moving object");
    m->base_color[0] = m->base_color[1] = m->base_color[2] = 0.6f;
    m->base_color[3] = 1.0f;
    m->base_color_texture = -1;
    m->alpha_mode = PF_ALPHA_OPAQUE;
    m->alpha_cutoff = 0.5f;
    /* a torus standing upright (its axis along z), seams duplicated */
    for (uint32_t i = 0; i <= BM_SEG; i++)
        for (uint32_t j = 0; j <= BM_RING; j++) {
            float a = 2.0f * PF_PI * (float)(i % BM_SEG) / BM_SEG, b = 2.0f * PF_PI * (float)(j % BM_RING) / BM_RING;
            pf_vec3 c = pf_v3(BM_MAJOR * cosf(a), BM_MAJOR * sinf(a), 0.0f);
            pf_vec3 n = pf_v3(cosf(b) * cosf(a), cosf(b) * sinf(a), sinf(b));
            uint32_t k = i * (BM_RING + 1) + j;
            w->rest_p[k] = pf_v3_add(c, pf_v3_scale(n, BM_MINOR));
            w->rest_n[k] = n;
            s->uvs[w->v0 + k] = (pf_vec2){(float)i / BM_SEG, (float)j / BM_RING};
        }
    uint32_t t = src->tri_count;
    for (uint32_t i = 0; i < BM_SEG; i++)
        for (uint32_t j = 0; j < BM_RING; j++) {
            uint32_t a = w->v0 + i * (BM_RING + 1) + j, b = a + BM_RING + 1;
            uint32_t q[6] = {a, b, b + 1, a, b + 1, a + 1};
            for (int k = 0; k < 6; k++) s->indices[3 * (size_t)t + (size_t)k] = q[k];
            s->tri_material[t] = s->tri_material[t + 1] = src->material_count;
            t += 2;
        }
    s->vertex_count = (uint32_t)nv;
    s->tri_count = (uint32_t)nt;
    s->material_count = src->material_count + 1;
    s->memory_bytes = 0;
    w->light = (pf_light){.type = PF_LIGHT_POINT, .position = bm_light, .color = {1, 1, 1},
                          .intensity = bm_light_intensity};
    snprintf(w->light.name, sizeof w->light.name, "bench point light");
    s->lights = &w->light;
    s->light_count = 1;
    return PF_OK;
}

static pf_vec3 bm__rot_y(pf_vec3 p, float c, float s) { return pf_v3(c * p.x + s * p.z, p.y, -s * p.x + c * p.z); }

/* The object at pose i (rest shape rotated and carried along the circle);
 * the report of what moved into w->moved. */
static void bm__pose(bm_world *w, uint32_t i)
{
    pf_scene *s = &w->scene;
    float a = 2.0f * PF_PI * (float)(i % BM_PERIOD) / BM_PERIOD, c = cosf(a), sn = sinf(a);
    pf_vec3 at = pf_v3_add(bm_centre, pf_v3(BM_RADIUS * (c - 1.0f), 0.0f, BM_RADIUS * sn));
    pf_anim_moved *m = &w->moved[1];
    m->before_min = m->after_min, m->before_max = m->after_max;
    pf_vec3 lo = pf_v3(INFINITY, INFINITY, INFINITY), hi = pf_v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t k = 0; k < w->nv; k++) {
        pf_vec3 p = pf_v3_add(at, bm__rot_y(w->rest_p[k], c, sn));
        s->positions[w->v0 + k] = p;
        s->normals[w->v0 + k] = bm__rot_y(w->rest_n[k], c, sn);
        lo = pf_v3_min(lo, p);
        hi = pf_v3_max(hi, p);
    }
    s->positions[s->vertex_count] = s->positions[s->vertex_count - 1];
    m->after_min = lo, m->after_max = hi;
    m->moved = i > 0;
    /* the scene's bounds, as pf_scene_validate keeps them */
    pf_vec3 blo = w->static_lo, bhi = w->static_hi;
    s->bounds_min = pf_v3_min(blo, lo);
    s->bounds_max = pf_v3_max(bhi, hi);
}

static void bm__world_free(bm_world *w)
{
    if (w->frame_ready) gi_frame_free(&w->frame);
    rs_context_destroy(w->raster);
    if (w->rt) pf_rt_destroy(w->rt);
    if (w->rt_refit) pf_rt_destroy(w->rt_refit);
    free(w->scene.positions), free(w->scene.normals), free(w->scene.uvs), free(w->scene.indices);
    free(w->scene.tri_material), free(w->scene.materials);
    free(w->rest_p), free(w->rest_n);
    memset(w, 0, sizeof *w);
}

static pf_result bm__world_make(bm_world *w, const pf_scene *src, pf_isa isa, pf_jobs *jobs, uint32_t threads,
                                const pf_options *o, uint32_t vpls, pf_error *err)
{
    memset(w, 0, sizeof *w);
    pf_result r = bm__world_scene(w, src, err);
    if (r != PF_OK) return r;
    /* the split: the loaded scene's triangles static, the object dynamic */
    w->prims[0] = (pf_anim_prim){.vertex_first = 0, .vertex_count = w->v0, .tri_first = 0, .tri_count = w->t0,
                                 .skin = -1};
    w->prims[1] = (pf_anim_prim){.vertex_first = w->v0, .vertex_count = w->nv, .tri_first = w->t0,
                                 .tri_count = w->nt, .skin = -1, .dynamic = 1};
    w->anim.prim_count = 2;
    w->anim.prims = w->prims;
    w->anim.dynamic_count = 1;
    for (int k = 0; k < 2; k++)
        w->moved[k] = (pf_anim_moved){.vertex_first = w->prims[k].vertex_first,
                                      .vertex_count = w->prims[k].vertex_count,
                                      .tri_first = w->prims[k].tri_first,
                                      .tri_count = w->prims[k].tri_count};
    bm__pose(w, 0); /* pose 0: the report's "after" bounds, the scene's bounds */
    if ((r = pf_rt_create_dynamic(&w->rt, &w->scene, &w->anim, isa, threads, err)) != PF_OK) return r;
    if ((r = pf_rt_create_dynamic(&w->rt_refit, &w->scene, &w->anim, isa, threads, err)) != PF_OK) return r;
    if ((r = rs_context_create(&w->raster, &w->scene, jobs, rs_simd_for_isa(isa), err)) != PF_OK) return r;
    pf_camera cam;
    if ((r = pf_camera_look_at(&cam, bm_eye, bm_target, pf_radians(bm_fovy), err)) != PF_OK) return r;
    gi_frame_desc fd = {.scene = &w->scene, .rt = w->rt, .jobs = jobs, .raster = w->raster, .camera = &cam,
                        .width = BM_W, .height = BM_H, .area_slope = o->visibility_slope};
    if ((r = gi_frame_create(&w->frame, &fd, err)) != PF_OK) return r;
    w->frame_ready = 1;
    gi_indirect_options io;
    if ((r = app_indirect_options(o, &io, err)) != PF_OK) return r;
    if (!o->method) io.method = gi_vpl_method_find("iir");
    io.vpls = vpls;
    io.pipeline = o->pipeline > 0;
    return gi_frame_enable_indirect(&w->frame, &io, 0, err);
}

static int bm__cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double bm__median(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, bm__cmp);
    return n ? (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2])) : 0.0;
}

/* The rows: the frame's stages by name, then the update rows. */
typedef struct bm_rows {
    pf_stage_times names;
    double *ms[2]; /* [world][row * frames + frame] */
} bm_rows;

static void bm__row(bm_rows *t, uint32_t world, const char *name, double ms, uint32_t frames, uint32_t frame)
{
    uint32_t k = 0;
    while (k < t->names.count && strcmp(t->names.name[k], name)) k++;
    if (k == t->names.count) {
        if (k == PF_MAX_STAGES) return;
        t->names.name[k] = name;
        t->names.count++;
        for (uint32_t w = 0; w < 2; w++)
            for (uint32_t j = 0; j < frames; j++) t->ms[w][k * frames + j] = 0.0;
    }
    t->ms[world][k * frames + frame] = ms;
}

int app_bench_frame_moving(const pf_options *o)
{
    pf_error err;
    pf_isa isa;
    if (o->moving_light || o->aa > 1 || o->taa || o->tiles_n) {
        fprintf(stderr, "softgi: bench frame --moving-object: %s does not apply (it takes --threads, --frames, "
                        "--scenes, --isa, --vpls, --method, --param, --visibility, --pipeline)\n",
                o->moving_light ? "--moving-light" : o->aa > 1 ? "--aa" : o->taa ? "--taa" : "--tiles");
        return 2;
    }
    if (pf_isa_resolve(o->isa, &isa, &err) != PF_OK) return app_fail(&err);
    const char *dir = o->scenes_dir ? o->scenes_dir : "../shared/scenes";
    const uint32_t frames = o->frames ? o->frames : 15, vpls = o->vpls ? o->vpls : 256;
    const uint32_t threads = o->threads ? o->threads : BM_TARGET_THREADS;
    if (threads > pf_jobs_core_count()) {
        fprintf(stderr, "softgi: bench frame --moving-object: --threads %u: this machine has %u cores\n", threads,
                pf_jobs_core_count());
        return 2;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/sibenik/sibenik.gltf", dir);
    pf_scene src;
    pf_gltf_options go = {.ignore_textures = 1};
    if (pf_gltf_load(&src, path, &go, &err) != PF_OK) {
        fprintf(stderr, "softgi: bench frame --moving-object: %s (give the folder with --scenes)\n", err.message);
        return 1;
    }
    pf_jobs *jobs = pf_jobs_create(threads);
    bm_world w[2];
    memset(w, 0, sizeof w);
    bm_rows rows;
    memset(&rows, 0, sizeof rows);
    double *frame_ms[2] = {malloc(sizeof(double) * frames), malloc(sizeof(double) * frames)};
    rows.ms[0] = malloc(sizeof(double) * frames * PF_MAX_STAGES);
    rows.ms[1] = malloc(sizeof(double) * frames * PF_MAX_STAGES);
    gi_motion_stats sum;
    memset(&sum, 0, sizeof sum);
    pf_result r = jobs && frame_ms[0] && frame_ms[1] && rows.ms[0] && rows.ms[1]
                      ? PF_OK
                      : pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "out of memory for the bench");
    for (int k = 0; k < 2 && r == PF_OK; k++) r = bm__world_make(&w[k], &src, isa, jobs, threads, o, vpls, &err);
    /* the moving world's object declared dynamic, as a caller that knows
     * its animation does: its VPL maps keep static maps (gi_frame_declare_
     * dynamic); the static world, where nothing moves, declares nothing */
    if (r == PF_OK) r = api_declare_dynamic(&w[1].frame, &w[1].anim, &err);
    if (r == PF_OK)
        printf("softgi bench frame --moving-object: sibenik + a %u-triangle torus, %dx%d, isa %s, %u threads, method "
               "%s, %u VPLs, pipelining %s, indirect light at 1/%u resolution; 1 warm-up frame then median of %u\n",
               w[0].nt, BM_W, BM_H, pf_isa_name(isa), threads, w[0].frame.ind.opt.method->name, vpls,
               o->pipeline > 0 ? "on" : "off", gi_indirect_scale_for(o->indirect_scale, BM_W, BM_H), frames);
    fflush(stdout);
    for (uint32_t i = 0; i <= frames && r == PF_OK; i++) {
        for (uint32_t k = 0; k < 2 && r == PF_OK; k++) {
            bm_world *x = &w[k];
            double t0 = pf_time_now(), t_pose = 0, t_refit = 0, t_rebuild = 0, t_raster = 0, t_frame = 0;
            if (k == 1 && i > 0) { /* the moving world: pose, then every update */
                double t = pf_time_now();
                bm__pose(x, i);
                t_pose = pf_time_now() - t, t = pf_time_now();
                if ((r = pf_rt_update(x->rt, x->moved, 2, PF_RT_REBUILD, &err)) != PF_OK) break;
                t_rebuild = pf_time_now() - t, t = pf_time_now();
                if ((r = rs_context_update(x->raster, x->moved, 2, &err)) != PF_OK) break;
                t_raster = pf_time_now() - t, t = pf_time_now();
                if ((r = gi_frame_geometry_moved(&x->frame, x->moved, 2, &err)) != PF_OK) break;
                t_frame = pf_time_now() - t;
            }
            double t_updates = pf_time_now() - t0;
            gi_frame_render_raster(&x->frame);
            double ms = (pf_time_now() - t0) * 1e3;
            if (x->frame.status != PF_OK) {
                r = x->frame.status, err = x->frame.error;
                break;
            }
            if (k == 1 && i > 0) { /* for comparison only: the same update by refitting */
                double t = pf_time_now();
                if ((r = pf_rt_update(x->rt_refit, x->moved, 2, PF_RT_REFIT, &err)) != PF_OK) break;
                t_refit = pf_time_now() - t;
                const gi_motion_stats *ms_ = &x->frame.motion_stats;
                sum.shadow_faces += ms_->shadow_faces, sum.shadow_faces_whole += ms_->shadow_faces_whole;
                sum.shadow_texels += ms_->shadow_texels, sum.vpl_maps += ms_->vpl_maps;
                sum.vpl_texels += ms_->vpl_texels;
            }
            if (i == 0) continue;
            frame_ms[k][i - 1] = ms;
            bm__row(&rows, k, "pose (the object's vertices)", t_pose * 1e3, frames, i - 1);
            bm__row(&rows, k, "embree update (rebuild)", t_rebuild * 1e3, frames, i - 1);
            bm__row(&rows, k, "raster update", t_raster * 1e3, frames, i - 1);
            bm__row(&rows, k, "frame update (gi_frame_geometry_moved)", t_frame * 1e3, frames, i - 1);
            bm__row(&rows, k, "updates, all", t_updates * 1e3, frames, i - 1);
            for (uint32_t s = 0; s < x->frame.times.count; s++)
                bm__row(&rows, k, x->frame.times.name[s], x->frame.times.ms[s], frames, i - 1);
            bm__row(&rows, k, "embree refit instead (not counted)", t_refit * 1e3, frames, i - 1);
        }
    }
    if (r == PF_OK) {
        printf("\n%-44s %12s %12s\n", "stage (ms, median)", "static", "moving");
        for (uint32_t s = 0; s < rows.names.count; s++) {
            double a = bm__median(rows.ms[0] + s * frames, frames), b = bm__median(rows.ms[1] + s * frames, frames);
            printf("%-44s %12.2f %12.2f\n", rows.names.name[s], a, b);
        }
        double fa = bm__median(frame_ms[0], frames), fb = bm__median(frame_ms[1], frames);
        double cost = fb / fa - 1.0;
        printf("%-44s %12.2f %12.2f\n", "frame (updates included)", fa, fb);
        printf("\nper moving frame (means): %.1f of 6 shadow-map faces drawn again in part (%.0f texels), %.1f whole; "
               "%.1f of %u VPL maps drawn again in part (%.0f texels tested)\n",
               (double)sum.shadow_faces / frames, (double)sum.shadow_texels / frames,
               (double)sum.shadow_faces_whole / frames, (double)sum.vpl_maps / frames, w[1].frame.ind.vpls.count,
               (double)sum.vpl_texels / frames);
        printf("target: the moving object costs the %s frame %+.1f%% (<= +%.0f%% with %u threads): "
               "%s\n",
               w[1].frame.ind.opt.method->name, 100.0 * cost, 100.0 * BM_TARGET, BM_TARGET_THREADS,
               threads != BM_TARGET_THREADS ? "not measured (needs 2 threads)" : cost <= BM_TARGET ? "met" : "NOT met");
        printf("json: {\"bench\":\"frame-moving-object\",\"width\":%d,\"height\":%d,\"isa\":\"%s\",\"threads\":%u,"
               "\"method\":\"%s\",\"vpls\":%u,\"triangles\":%u,\"frames\":%u,\"static_ms\":%.3f,\"moving_ms\":%.3f,"
               "\"cost\":%.4f,\"stages_ms\":{",
               BM_W, BM_H, pf_isa_name(isa), threads, w[1].frame.ind.opt.method->name, vpls, w[1].nt, frames, fa, fb,
               cost);
        for (uint32_t s = 0; s < rows.names.count; s++)
            printf("%s\"%s\":[%.3f,%.3f]", s ? "," : "", rows.names.name[s],
                   bm__median(rows.ms[0] + s * frames, frames), bm__median(rows.ms[1] + s * frames, frames));
        printf("}}\n");
    }
    for (int k = 0; k < 2; k++) bm__world_free(&w[k]);
    free(frame_ms[0]), free(frame_ms[1]), free(rows.ms[0]), free(rows.ms[1]);
    if (jobs) pf_jobs_destroy(jobs);
    pf_scene_free(&src);
    if (r != PF_OK) {
        fprintf(stderr, "softgi: bench frame --moving-object: %s\n", err.message);
        return pf_result_exit_code(r);
    }
    return 0;
}
