/* app_scene: what the commands share before they render: the scene loading
 * (the file or the embedded default scene, the --camera / --light
 * overrides, validation, the automatic camera and light of pf_defaults.h
 * and the user-facing warnings and notes), the PNG exposure (--exposure
 * auto) and the nearly-black hint, the scene + Embree +
 * jobs setup of `render` and `reference`, and the frame and path-tracer
 * options the command line describes. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pf_sequence.h"
#include "app.h"
#include "pf_defaults.h"
#include "gi_frame.h"
#include "gi_indirect.h"
#include "gi_ism.h"
#include "gi_reference.h"
#include "pf_budget.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"

extern const unsigned char softgi_default_scene[];
extern const unsigned long softgi_default_scene_size;

int app_fail(const pf_error *err)
{
    fprintf(stderr, "softgi: %s\n", err->message);
    return pf_result_exit_code(err->code);
}

/* "dir/name.gltf" -> "name" */
static void app__stem(const char *path, char *buf, size_t size)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    snprintf(buf, size, "%s", base);
    char *dot = strrchr(buf, '.');
    if (dot && dot != buf) *dot = 0;
}

/* Whether any triangle's material emits (an area light, gi_area.h). */
static int app__has_emitters(const pf_scene *scene)
{
    for (uint32_t t = 0; t < scene->tri_count; t++) {
        const float *e = scene->materials[scene->tri_material[t]].emission;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f) return 1;
    }
    return 0;
}

/* The image size the command will render (render's default 640x480;
 * sequence passes the file's size in o->width/height when it has one). */
static void app__image_size(const pf_options *o, uint32_t *w, uint32_t *h)
{
    *w = o->width ? o->width : 640;
    *h = o->height ? o->height : 480;
}

/* No camera anywhere: pf_defaults_camera, printed as a --camera value and
 * parsed back from that text, so that copying the line gives the same
 * image bit for bit. */
static pf_result app__default_camera(const pf_options *o, const pf_scene *scene, pf_camera *camera, const char *name,
                                     pf_error *err)
{
    pf_default_camera dc;
    pf_defaults_camera(&dc, scene);
    char spec[256];
    pf_vec3 eye, target;
    float fovy;
    pf_result r = PF_OK;
    /* 5 digits read well; 9 give every float back exactly, for a small
     * scene far from the origin whose eye and target 5 digits would merge */
    for (int digits = 5; digits <= 9; digits += 4) {
        snprintf(spec, sizeof spec, "%.*g,%.*g,%.*g:%.*g,%.*g,%.*g:%g", digits, (double)dc.eye.x, digits,
                 (double)dc.eye.y, digits, (double)dc.eye.z, digits, (double)dc.target.x, digits, (double)dc.target.y,
                 digits, (double)dc.target.z, (double)dc.fovy_deg);
        r = pf_cli_parse_camera(spec, &eye, &target, &fovy, err);
        if (r == PF_OK) r = pf_camera_look_at(camera, eye, target, pf_radians(fovy), err);
        if (r == PF_OK) break;
    }
    if (r != PF_OK) return r;
    snprintf(camera->name, sizeof camera->name, "default");
    if (!o->quiet) {
        if (dc.interior)
            fprintf(stderr,
                    "softgi: note: %s has no camera; using --camera %s (an interior: %u of %u rays from the bounds' "
                    "centre hit; looking down its %c axis%s)\n",
                    name, spec, dc.hits, dc.rays, dc.axis, dc.open_end ? " through its open end" : "");
        else
            fprintf(stderr,
                    "softgi: note: %s has no camera; using --camera %s (outside: the bounds fill 80%% of the "
                    "view)\n",
                    name, spec);
    }
    return PF_OK;
}

/* No light and no emitter: pf_defaults_light, printed as a --light value
 * and parsed back (as app__default_camera). */
static pf_result app__default_light(const pf_options *o, pf_scene *scene, const pf_camera *camera, const char *name,
                                    pf_error *err)
{
    uint32_t w, h;
    app__image_size(o, &w, &h);
    pf_light l;
    float median;
    pf_defaults_light(&l, &median, scene, camera, w, h);
    char spec[256];
    pf_light parsed;
    pf_result r = PF_OK;
    /* 5 digits unless they move the light by more than 1% of the median
     * distance (a small scene far from the origin): then 9, exact */
    for (int digits = 5; digits <= 9; digits += 4) {
        snprintf(spec, sizeof spec, "point:%.*g,%.*g,%.*g:1,1,1:%.3g", digits, (double)l.position.x, digits,
                 (double)l.position.y, digits, (double)l.position.z, (double)l.intensity);
        if ((r = pf_cli_parse_light(spec, &parsed, err)) != PF_OK) continue;
        pf_vec3 moved = pf_v3_sub(parsed.position, l.position);
        if (pf_v3_max_comp(pf_v3(fabsf(moved.x), fabsf(moved.y), fabsf(moved.z))) <= 0.01f * median) break;
    }
    if (r != PF_OK) return r;
    l = parsed;
    snprintf(l.name, sizeof l.name, "default");
    if ((r = pf_scene_add_light(scene, &l, err)) != PF_OK) return r;
    if (!o->quiet)
        fprintf(stderr,
                "softgi: note: %s has no lights; added --light %s (at the camera: %g W/m^2 at the median distance "
                "%.3g)\n",
                name, spec, (double)APP_DEFAULT_IRRADIANCE, (double)median);
    return PF_OK;
}

pf_result app_scene_load(const pf_options *o, pf_scene *scene, pf_camera *camera, char *stem, size_t stem_size,
                         pf_error *err)
{
    return app_scene_load_sequence(o, NULL, scene, camera, stem, stem_size, err);
}

pf_result app_scene_load_sequence(const pf_options *o, const pf_sequence *seq, pf_scene *scene, pf_camera *camera,
                                  char *stem, size_t stem_size, pf_error *err)
{
    pf_result r;
    pf_gltf_options go = {.max_memory = o->max_memory};
    if (o->scene_path) {
        r = pf_gltf_load(scene, o->scene_path, &go, err);
        app__stem(o->scene_path, stem, stem_size);
    } else {
        r = pf_gltf_load_memory(scene, softgi_default_scene, softgi_default_scene_size, NULL,
                                "embedded scenes/cornell-box", &go, err);
        snprintf(stem, stem_size, "cornell-box");
    }
    if (r != PF_OK) return r;
    /* a sequence file's emitters are part of the scene from here on */
    if (seq && (r = pf_sequence_apply_emitters(seq, scene, err)) != PF_OK) {
        pf_scene_free(scene);
        return r;
    }
    if (scene->warnings[0] && !o->quiet) fprintf(stderr, "softgi: warnings:\n%s", scene->warnings);
    if (o->has_camera) {
        r = pf_camera_look_at(camera, o->camera_eye, o->camera_target, pf_radians(o->camera_fovy_deg), err);
    } else if (scene->camera_count > 0) {
        *camera = scene->cameras[0];
    } /* else app__default_camera below, once the scene is validated */
    if (r == PF_OK && o->light_count > 0) {
        scene->light_count = 0; /* given lights replace the file's */
        for (uint32_t i = 0; i < o->light_count && r == PF_OK; i++) r = pf_scene_add_light(scene, &o->lights[i], err);
    }
    if (r == PF_OK) r = pf_scene_validate(scene, err);
    const char *name = o->scene_path ? o->scene_path : "the scene";
    if (r == PF_OK && !o->has_camera && scene->camera_count == 0) r = app__default_camera(o, scene, camera, name, err);
    /* emissive triangles are lights too (gi_area.h) */
    if (r == PF_OK && scene->light_count == 0 && !app__has_emitters(scene))
        r = app__default_light(o, scene, camera, name, err);
    if (r != PF_OK) {
        pf_scene_free(scene);
        return r;
    }
    return PF_OK;
}

float app_exposure(const pf_options *o, const float *rgb, uint32_t width, uint32_t height)
{
    if (!o->exposure_auto) return o->exposure;
    double avg;
    float ev = pf_defaults_exposure(rgb, width, height, &avg);
    if (!o->quiet)
        fprintf(stderr,
                "softgi: note: --exposure auto: %+.2f stops (the lit pixels' log-average luminance %.4g to %g%% grey)"
                "\n",
                (double)ev, avg, 100.0 * APP_DEFAULT_GREY);
    return ev;
}

void app_hint_dark(const pf_options *o, const float *rgb, uint32_t width, uint32_t height, float exposure)
{
    if (o->quiet || !pf_defaults_nearly_black(rgb, width, height, exposure)) return;
    fprintf(stderr,
            "softgi: note: the image is nearly black (99%% of its pixels below luminance %g at exposure %+.2f); "
            "try %s\n",
            (double)APP_DARK_LUMINANCE, (double)exposure,
            o->exposure_auto ? "a brighter --light (W/sr for point and spot, W/m^2 for dir)"
                             : "--exposure auto or a brighter --light (W/sr for point and spot, W/m^2 for dir)");
}

void app_reference_options(const pf_options *o, gi_reference_options *ro)
{
    memset(ro, 0, sizeof *ro);
    ro->spp = o->spp ? o->spp : GI_REFERENCE_DEFAULT_SPP;
    ro->bounces = o->bounces ? o->bounces : GI_REFERENCE_DEFAULT_BOUNCES;
    ro->direct_only = o->direct_only;
    ro->indirect_only = o->indirect_only;
    ro->clamp = o->clamp_set ? o->clamp : 0.0f; /* reference --clamp: clamped path tracing */
}

pf_result app_indirect_options(const pf_options *o, gi_indirect_options *io, pf_error *err)
{
    memset(io, 0, sizeof *io);
    io->method = gi_vpl_method_find(o->method);
    if (!io->method)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method '%s': softgi knows %s", o->method, gi_vpl_method_names());
    io->vpls = o->vpls;
    io->bounces = o->bounces;
    io->tiles_n = o->tiles_n;
    io->tiles_m = o->tiles_m;
    io->no_interleave = o->no_interleave;
    io->visibility_raytrace = o->visibility_raytrace;
    io->visibility_ism = o->visibility_ism;
    if (o->visibility_ism && o->visibility_raytrace)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--visibility: give one of paraboloid, ism or raytrace");
    if (!o->visibility_ism && (o->ism_res || o->ism_points || o->ism_bias != 0.0f))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--ism-res, --ism-points and --ism-bias need --visibility ism");
    io->ism.resolution = o->ism_res;
    io->ism.points = o->ism_points;
    io->ism.bias_scale = o->ism_bias;
    for (uint32_t i = 0; i < o->param_count; i++) {
        pf_result r = gi_params_add(&io->params, o->params[i], err);
        if (r != PF_OK) return r;
    }
    io->clamp = o->clamp_set ? o->clamp : -1.0f;
    io->pipeline = o->pipeline == 1; /* default off for every command */
    io->scale = o->indirect_scale;
    io->temporal = o->temporal;
    io->compensate = o->compensate;
    io->filter = !o->filter || !strcmp(o->filter, "box") ? GI_FILTER_BOX
                 : !strcmp(o->filter, "bilateral")       ? GI_FILTER_BILATERAL
                 : !strcmp(o->filter, "gaussian")        ? GI_FILTER_GAUSSIAN
                                                         : GI_FILTER_NONE;
    return PF_OK;
}

pf_result app_budget_check(const pf_options *o, const pf_scene *scene, uint32_t width, uint32_t height, int frame,
                           int indirect, pf_error *err)
{
    pf_budget b;
    pf_budget_init(&b, o->max_memory);
    pf_result r = pf_budget_take(&b, scene->memory_bytes, "the scene", err);
    if (r != PF_OK) return r;
    if (!frame) { /* the path tracer: its image and per-pixel sums */
        r = pf_budget_take(&b, pf_budget_mul((uint64_t)width * height, 64), "the image", err);
        if (r == PF_OK) pf_budget_warn(&b, "a smaller scene or --size");
        return r;
    }
    uint32_t vpls = indirect && !o->direct_only ? (o->vpls ? o->vpls : 256) : 0;
    uint32_t res = o->visibility_raytrace ? 1 : o->visibility_ism ? (o->ism_res ? o->ism_res : GI_ISM_DEFAULT_RES) : 0;
    uint32_t area = app__has_emitters(scene) ? (o->area_points ? o->area_points : GI_AREA_DEFAULT_POINTS) : 0;
    char what[160];
    snprintf(what, sizeof what, "the frame (%ux%u, %u lights with shadow maps of %u^2, %u VPLs)", width, height,
             scene->light_count, o->shadow_size ? o->shadow_size : RS_SHADOW_DEFAULT_SIZE, vpls);
    uint64_t all = gi_frame_memory_estimate(scene, width, height, o->shadow_size, vpls, res, area);
    r = pf_budget_take(&b, all, what, err);
    /* which knob helps, for the refusal or the warning */
    uint64_t no_vpls = gi_frame_memory_estimate(scene, width, height, o->shadow_size, 0, res, area);
    uint64_t no_shadows = all - gi_frame_memory_estimate(scene, 0, 0, o->shadow_size, 0, res, 0);
    const char *hint = all - no_vpls > all / 2      ? "use fewer VPLs or --visibility raytrace (--vpls N)"
                       : all - no_shadows > all / 2 ? "use fewer lights or a smaller --shadow-size"
                                                    : "use a smaller --size";
    if (r != PF_OK) {
        size_t n = strlen(err->message);
        snprintf(err->message + n, sizeof err->message - n, "; %s", hint);
    } else
        pf_budget_warn(&b, hint);
    return r;
}

pf_result app_frame_init(const pf_options *o, gi_frame *f, const pf_scene *scene, const pf_rt *rt, rs_context *raster,
                         pf_jobs *jobs, const pf_camera *camera, uint32_t width, uint32_t height, int indirect,
                         pf_error *err)
{
    pf_result r = app_budget_check(o, scene, width, height, 1, indirect, err);
    if (r != PF_OK) return r;
    gi_indirect_options io;
    int with_indirect = indirect && !o->direct_only;
    if (with_indirect && (r = app_indirect_options(o, &io, err)) != PF_OK) return r;
    gi_frame_desc d = {.scene = scene, .rt = rt, .jobs = jobs, .raster = raster, .camera = camera,
                       .width = width, .height = height, .shadow_size = o->shadow_size,
                       .area_strata = o->area_strata, .area_points = o->area_points,
                       .indirect = with_indirect ? &io : NULL, .indirect_only = o->indirect_only,
                       .aa_samples = o->aa, .taa_frames = o->taa};
    return gi_frame_create(f, &d, err);
}

pf_result app_setup_begin(const pf_options *o, app_setup *s, pf_stage_times *t, pf_error *err)
{
    memset(s, 0, sizeof *s);
    s->width = o->width ? o->width : 640;
    s->height = o->height ? o->height : 480;
    s->threads = o->threads ? o->threads : pf_jobs_core_count();
    pf_result r = pf_isa_resolve(o->isa, &s->isa, err);
    if (r != PF_OK) return r;
    double t0 = pf_time_now();
    if ((r = app_scene_load(o, &s->scene, &s->camera, s->stem, sizeof s->stem, err)) != PF_OK) return r;
    pf_stage_add(t, "load scene", (pf_time_now() - t0) * 1e3);
    t0 = pf_time_now();
    if ((r = pf_rt_create(&s->rt, &s->scene, s->isa, s->threads, err)) != PF_OK) {
        pf_scene_free(&s->scene);
        return r;
    }
    pf_stage_add(t, "embree build", (pf_time_now() - t0) * 1e3);
    if (!(s->jobs = pf_jobs_create(s->threads))) {
        app_setup_end(s);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", s->threads);
    }
    return PF_OK;
}

void app_setup_end(app_setup *s)
{
    if (s->jobs) pf_jobs_destroy(s->jobs);
    pf_rt_destroy(s->rt);
    pf_scene_free(&s->scene);
    memset(s, 0, sizeof *s);
}
