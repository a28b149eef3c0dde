/* app_scene: what the commands share before they render: the options as
 * a softgi_desc (app_desc: every frame option means what it means to the
 * library), the scene loading (the file or the built-in Cornell box, the
 * --camera / --light overrides, validation, the automatic camera and light
 * and the user-facing warnings and notes), the PNG exposure (--exposure
 * auto) and the nearly-black hint, the scene + Embree + jobs setup of the
 * commands that use the modules (reference, view, sequence, evaluate), and
 * the frame and path-tracer options the command line describes.
 *
 * The set-up itself is the library's (src/api/api_setup.h: reading the
 * scene, the automatic camera and light with their rounding through the
 * printed text, the memory budget, the many-light options, the frame), so
 * `softgi render` (on the public API), the library and the other commands
 * run one implementation; this file adds the program's parts: the notes
 * and warnings on stderr and the mapping from pf_options. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pf_anim.h"
#include "pf_sequence.h"
#include "api_setup.h"
#include "app.h"
#include "pf_defaults.h"
#include "gi_frame.h"
#include "gi_indirect.h"
#include "gi_reference.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"

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

void app_stem(const pf_options *o, char *stem, size_t size)
{
    if (o->scene_path) app__stem(o->scene_path, stem, size);
    else snprintf(stem, size, "cornell-box");
}

pf_result app_desc(const pf_options *o, uint32_t width, uint32_t height, softgi_desc *d, pf_error *err)
{
    memset(d, 0, sizeof *d);
    if (o->visibility_ism + o->visibility_raytrace + o->visibility_slope > 1 && !o->direct_only)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "--visibility: give one of paraboloid, paraboloid-slope, ism or raytrace");
    d->width = width;
    d->height = height;
    d->threads = o->threads;
    d->isa = pf_isa_name(o->isa);
    d->max_memory = o->max_memory;
    d->method = o->method;
    d->vpls = o->vpls;
    d->bounces = o->bounces;
    d->params = o->params;
    d->param_count = o->param_count;
    d->flags = (o->direct_only ? SOFTGI_DIRECT_ONLY : 0u) | (o->indirect_only ? SOFTGI_INDIRECT_ONLY : 0u) |
               (o->raytrace ? SOFTGI_RAYTRACE : 0u) | (o->no_interleave ? SOFTGI_NO_INTERLEAVE : 0u) |
               (o->pipeline == 1 ? SOFTGI_PIPELINE : 0u) /* default off for every command */ |
               (o->compensate ? SOFTGI_COMPENSATE : 0u) | (o->filter_distance ? SOFTGI_FILTER_DISTANCE : 0u);
    d->shadow_size = o->shadow_size;
    d->area_strata = o->area_strata;
    d->area_points = o->area_points;
    d->tiles_n = o->tiles_n;
    d->tiles_m = o->tiles_m;
    d->clamp = !o->clamp_set ? 0.0f : o->clamp == 0.0f ? SOFTGI_CLAMP_OFF : o->clamp;
    d->filter = o->filter;
    d->visibility = o->visibility_ism         ? "ism"
                    : o->visibility_raytrace  ? "raytrace"
                    : o->visibility_slope     ? "paraboloid-slope"
                                              : NULL;
    d->ism_res = o->ism_res;
    d->ism_points = o->ism_points;
    d->ism_bias = o->ism_bias;
    d->indirect_scale = o->indirect_scale;
    d->temporal = o->temporal;
    d->vpl_cycle = o->vpl_cycle;
    d->cycle_maps = o->cycle_maps;
    d->aa = o->aa;
    d->taa = o->taa;
    return PF_OK;
}

void app_note_camera(const pf_options *o, const char *name, const pf_default_camera *dc, const char *spec)
{
    if (o->quiet) return;
    if (dc->interior)
        fprintf(stderr,
                "softgi: note: %s has no camera; using --camera %s (an interior: %u of %u rays from the bounds' "
                "centre hit; looking down its %c axis%s)\n",
                name, spec, dc->hits, dc->rays, dc->axis, dc->open_end ? " through its open end" : "");
    else
        fprintf(stderr,
                "softgi: note: %s has no camera; using --camera %s (outside: the bounds fill 80%% of the view)\n",
                name, spec);
}

void app_note_light(const pf_options *o, const char *name, const char *spec, float median)
{
    if (o->quiet) return;
    fprintf(stderr,
            "softgi: note: %s has no lights; added --light %s (at the camera: %g W/m^2 at the median distance "
            "%.3g)\n",
            name, spec, (double)APP_DEFAULT_IRRADIANCE, (double)median);
}

static pf_result app__scene_read(const pf_options *o, const pf_sequence *seq, pf_scene *scene, pf_anim *anim,
                                 pf_camera *camera, char *stem, size_t stem_size, pf_error *err);

pf_result app_scene_load(const pf_options *o, pf_scene *scene, pf_camera *camera, char *stem, size_t stem_size,
                         pf_error *err)
{
    return app_scene_load_sequence(o, NULL, scene, NULL, camera, stem, stem_size, err);
}

pf_result app_scene_load_sequence(const pf_options *o, const pf_sequence *seq, pf_scene *scene, pf_anim *anim,
                                  pf_camera *camera, char *stem, size_t stem_size, pf_error *err)
{
    pf_anim own; /* --time without a caller to keep the animations: posed once, then let go */
    memset(&own, 0, sizeof own);
    pf_anim *a = anim ? anim : &own;
    pf_result r = app__scene_read(o, seq, scene, a, camera, stem, stem_size, err);
    if (r == PF_OK && o->time_set) {
        r = api_scene_pose(scene, a, o->scene_path ? o->scene_path : "the scene", o->time, o->animation, NULL, NULL,
                           err);
        if (r != PF_OK) pf_scene_free(scene);
    }
    if (!anim || r != PF_OK) pf_anim_free(a);
    return r;
}

/* app_scene_load_sequence up to the automatic camera and light, on the
 * static pose. */
static pf_result app__scene_read(const pf_options *o, const pf_sequence *seq, pf_scene *scene, pf_anim *anim,
                                 pf_camera *camera, char *stem, size_t stem_size, pf_error *err)
{
    pf_result r = api_scene_read(scene, anim, o->scene_path, o->max_memory, err);
    app_stem(o, stem, stem_size);
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
    } /* else the automatic camera below, once the scene is validated */
    if (r == PF_OK && o->light_count > 0) {
        scene->light_count = 0; /* given lights replace the file's */
        for (uint32_t i = 0; i < o->light_count && r == PF_OK; i++) r = pf_scene_add_light(scene, &o->lights[i], err);
    }
    if (r == PF_OK) r = pf_scene_validate(scene, err);
    const char *name = o->scene_path ? o->scene_path : "the scene";
    char spec[256];
    if (r == PF_OK && !o->has_camera && scene->camera_count == 0) {
        pf_default_camera dc;
        r = api_default_camera(scene, camera, &dc, spec, sizeof spec, err);
        if (r == PF_OK) app_note_camera(o, name, &dc, spec);
    }
    /* emissive triangles are lights too (gi_area.h) */
    if (r == PF_OK && scene->light_count == 0 && !api_scene_has_emitters(scene)) {
        pf_light l;
        float median;
        r = api_default_light(scene, camera, o->width ? o->width : API_DEFAULT_WIDTH,
                              o->height ? o->height : API_DEFAULT_HEIGHT, &l, &median, spec, sizeof spec, err);
        if (r == PF_OK) r = pf_scene_add_light(scene, &l, err);
        if (r == PF_OK) app_note_light(o, name, spec, median);
    }
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
    ro->no_light_paths = o->no_light_paths;
}

uint32_t app_refine_slices(const char *method, int ism, int raytrace, uint32_t vpls, uint32_t para_res)
{
    const char *m = method ? method : "ir";
    if (ism || !strcmp(m, "mir")) return 0;
    uint64_t n = vpls ? vpls : 256, res = para_res ? para_res : RS_PARA_DEFAULT_RES;
    uint64_t slice = raytrace ? 1 : n * res * res * 2u;
    uint64_t c = APP_REFINE_MAP_BYTES / slice;
    if (c > API_REFINE_SLICES) c = API_REFINE_SLICES;
    if (c * n > GI_INDIRECT_MAX_SET) c = GI_INDIRECT_MAX_SET / n;
    return c >= 2 ? (uint32_t)c : 0;
}

pf_result app_indirect_options(const pf_options *o, gi_indirect_options *io, pf_error *err)
{
    softgi_desc d;
    pf_result r = app_desc(o, o->width, o->height, &d, err);
    return r == PF_OK ? api_indirect_options(&d, io, err) : r;
}

pf_result app_budget_check(const pf_options *o, const pf_scene *scene, uint32_t width, uint32_t height, int frame,
                           int indirect, pf_error *err)
{
    softgi_desc d;
    pf_result r = app_desc(o, width, height, &d, err);
    return r == PF_OK ? api_budget_check(&d, scene, frame, indirect, 1, err) : r;
}

pf_result app_frame_init(const pf_options *o, gi_frame *f, const pf_scene *scene, const pf_rt *rt, rs_context *raster,
                         pf_jobs *jobs, const pf_camera *camera, uint32_t width, uint32_t height, int indirect,
                         pf_error *err)
{
    softgi_desc d;
    pf_result r = app_desc(o, width, height, &d, err);
    return r == PF_OK ? api_frame_create(f, &d, scene, rt, raster, jobs, camera, indirect, 1, err) : r;
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
    /* the animations are kept until Embree is built: what they can move is
     * split off as softgi render (the API) and sequence split it, so a
     * posed scene gives the same hits in every command (pf_rt.h) */
    pf_anim anim;
    memset(&anim, 0, sizeof anim);
    if ((r = app_scene_load_sequence(o, NULL, &s->scene, &anim, &s->camera, s->stem, sizeof s->stem, err)) != PF_OK)
        return r;
    pf_stage_add(t, "load scene", (pf_time_now() - t0) * 1e3);
    t0 = pf_time_now();
    r = pf_rt_create_dynamic(&s->rt, &s->scene, &anim, s->isa, s->threads, err);
    pf_anim_free(&anim);
    if (r != PF_OK) {
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
