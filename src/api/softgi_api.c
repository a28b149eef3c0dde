/* softgi_api: the public C API (include/softgi/softgi.h) over the modules,
 * and the program's `softgi render` (src/app/app_render.c) is built on it,
 * so a frame rendered here is the program's frame with the same options.
 *
 *   softgi_create       the description checked (the program's limits), ISA
 *                       resolved (pf_isa), jobs started (pf_jobs)
 *   softgi_load_scene   api_scene_read with the memory budget -> the file's
 *                       camera, or api_default_camera -> pf_scene_validate ->
 *                       api_default_light when nothing lights the scene ->
 *                       api_budget_check -> pf_rt_create_dynamic (what an
 *                       animation can move apart: pf_rt.h) -> rs_context_create
 *   softgi_set_camera   pf_camera_look_at, as --camera
 *   softgi_set_lights   the scene's lights replaced, as --light
 *   softgi_set_time     the scene posed at a time (api_scene_pose), as --time;
 *                       when geometry moved, Embree (pf_rt_update, REBUILD:
 *                       a fresh build's bytes), the rasterizer and the frame
 *                       updated in place (gi_frame_geometry_moved)
 *   softgi_render       api_frame_create at the first frame, then
 *                       gi_frame_render_raster (or _raytraced)
 *   softgi_dump_stages  gi_dump_stages, as --dump-stages
 *
 * The set-up (the scene, the automatic camera and light, the budget, the
 * frame's options) is api_setup.c, which the program's other commands
 * call too. What only the program reads (the automatic camera's and light's
 * reasons for its notes, the budget warning) is softgi_internal.h.
 *
 * Order: the camera and lights are set after the scene is loaded. The only
 * difference that could make is the automatic light, which `--camera`
 * places at the given camera; softgi_set_camera therefore re-places an
 * automatic light at the new camera, which gives the same scene. */
#include "softgi/softgi.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_setup.h"
#include "softgi_internal.h"
#include "gi_aa.h"
#include "gi_dump.h"
#include "gi_frame.h"
#include "gi_indirect.h"
#include "gi_ism.h"
#include "pf_anim.h"
#include "pf_fpenv.h"
#include "pf_imageio.h"
#include "pf_isa.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"
#include "rs_raster.h"

#ifndef SOFTGI_VERSION
#define SOFTGI_VERSION "unknown"
#endif

/* The codes are the program's, value for value. */
_Static_assert(SOFTGI_OK == (int)PF_OK && SOFTGI_ERR_IO == (int)PF_ERR_IO &&
                   SOFTGI_ERR_ARGUMENT == (int)PF_ERR_ARGUMENT && SOFTGI_ERR_ARGUMENT + 1 == (int)PF_ERR_COUNT &&
                   SOFTGI_ERR_OUT_OF_MEMORY == (int)PF_ERR_OUT_OF_MEMORY && SOFTGI_ERR_EMBREE == (int)PF_ERR_EMBREE,
               "softgi_result must equal pf_result value for value");
_Static_assert(sizeof(((softgi_error *)0)->message) == sizeof(((pf_error *)0)->message), "message sizes");

/* The program's limits on the same values (src/app/pf_cli.c). */
#define API__MAX_SIDE 16384u
#define API__MAX_THREADS 256u
#define API__MAX_VPLS (1u << 20)
#define API__MAX_BOUNCES 64u
#define API__MAX_PARAMS 32u
#define API__MAX_LIGHTS 64u /* PF_CLI_MAX_LIGHTS */
#define API__MIN_MEMORY (64ull << 20)
#define API__FLAGS                                                                                                    \
    (SOFTGI_DIRECT_ONLY | SOFTGI_INDIRECT_ONLY | SOFTGI_RAYTRACE | SOFTGI_NO_INTERLEAVE | SOFTGI_PIPELINE |          \
     SOFTGI_COMPENSATE | SOFTGI_FILTER_DISTANCE)

struct softgi_context {
    /* options (softgi_create): the description with every pointer into
     * this context (the method's and the choices' static names, owned
     * copies of the parameters), width, height and threads resolved */
    softgi_desc desc;
    pf_isa isa;
    const gi_vpl_method *method;
    char *params[API__MAX_PARAMS]; /* owned copies: gi_params keeps pointers */
    int warn;                      /* softgi_internal_warn */
    pf_jobs *jobs;
    /* scene lifetime (softgi_load_scene) */
    int loaded;
    pf_scene scene;
    pf_anim anim;          /* what posing the scene needs (softgi_set_time) */
    pf_anim_moved *moved;  /* anim.prim_count: the last pose's report (pf_rt_update) */
    char scene_name[256];  /* the path as given, for messages */
    pf_camera camera;
    softgi_internal_notes notes; /* auto_camera, auto_light and their text */
    pf_rt *rt;
    rs_context *raster;
    pf_stage_times load_times;
    /* frame lifetime (the first softgi_render after a load or a change of the light count) */
    int frame_ready;
    gi_frame frame;
    uint32_t frames;
    float exposure;
};

/* ---------------------------------------------------------------- small helpers */

static softgi_result api__fail(softgi_error *err, const pf_error *e)
{
    if (err) {
        err->code = (softgi_result)e->code;
        memcpy(err->message, e->message, sizeof err->message);
    }
    return (softgi_result)e->code;
}

static softgi_result api__error(softgi_error *err, softgi_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static softgi_result api__error(softgi_error *err, softgi_result code, const char *fmt, ...)
{
    if (err) {
        err->code = code;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

static void api__ok(softgi_error *err)
{
    if (err) {
        err->code = SOFTGI_OK;
        err->message[0] = 0;
    }
}

/* The floating-point environment every softgi thread computes with
 * (pf_fpenv.h), on the caller's thread for one call, then the caller's own
 * back: the calling thread runs jobs too, and FTZ/DAZ are part of the
 * determinism contract, but a library must not leave them changed. */
static pf_fpenv_state api__fpenv_enter(void)
{
    pf_fpenv_state s = pf_fpenv_save();
    pf_fpenv_set();
    return s;
}

static void api__fpenv_leave(pf_fpenv_state s) { pf_fpenv_restore(s); }

const char *softgi_result_name(softgi_result code) { return pf_result_name((pf_result)code); }

const char *softgi_version(void) { return SOFTGI_VERSION; }

const char *softgi_method_names(void) { return gi_vpl_method_names(); }

/* ---------------------------------------------------------------- create, destroy */

static void api__scene_free(softgi_context *c)
{
    if (c->frame_ready) gi_frame_free(&c->frame);
    c->frame_ready = 0;
    rs_context_destroy(c->raster);
    c->raster = NULL;
    pf_rt_destroy(c->rt);
    c->rt = NULL;
    if (c->loaded) pf_scene_free(&c->scene);
    memset(&c->scene, 0, sizeof c->scene);
    pf_anim_free(&c->anim);
    free(c->moved);
    c->moved = NULL;
    c->loaded = 0;
    memset(&c->notes, 0, sizeof c->notes);
    c->frames = 0;
    memset(&c->load_times, 0, sizeof c->load_times);
}

void softgi_destroy(softgi_context *c)
{
    if (!c) return;
    api__scene_free(c);
    if (c->jobs) pf_jobs_destroy(c->jobs);
    for (uint32_t i = 0; i < c->desc.param_count; i++) free(c->params[i]);
    free(c);
}

/* `name` if it is one of the '|'-separated `choices` (as pf_cli's
 * choices): the static string in `choices`' table; NULL otherwise. */
static const char *api__choice(const char *name, const char *const *choices)
{
    for (; *choices; choices++)
        if (!strcmp(name, *choices)) return *choices;
    return NULL;
}

/* The fields beyond the basics, with the program's limits (pf_cli.c). */
static softgi_result api__check_frame_fields(const softgi_desc *d, softgi_error *err)
{
#define API__RANGE(field, lo, hi, what)                                                                               \
    if (d->field && (d->field < (lo) || d->field > (hi)))                                                             \
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: " #field " %u: must be %u..%u (0: %s)",           \
                          (unsigned)d->field, (unsigned)(lo), (unsigned)(hi), what);
    API__RANGE(shadow_size, 16u, 8192u, "1024")
    API__RANGE(area_strata, 1u, 16u, "4")
    API__RANGE(area_points, 1u, 1024u, "32")
    API__RANGE(ism_points, 1000u, GI_ISM_MAX_POINTS, "the default")
    API__RANGE(indirect_scale, 1u, GI_INDIRECT_MAX_SCALE, "automatic: 2 from 1024x768 up, else 1")
    API__RANGE(temporal, 2u, GI_INDIRECT_MAX_TEMPORAL, "off")
    API__RANGE(vpl_cycle, 2u, GI_INDIRECT_MAX_CYCLE, "off")
    API__RANGE(cycle_maps, 1u, GI_INDIRECT_MAX_SET, "off")
    API__RANGE(aa, 1u, GI_AA_MAX_SAMPLES, "1")
    API__RANGE(taa, 2u, GI_AA_MAX_TAA, "off")
#undef API__RANGE
    if ((d->tiles_n == 0) != (d->tiles_m == 0) || d->tiles_n > 16 || d->tiles_m > 16)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: tiles_n %u x tiles_m %u: give both (1..16) or "
                          "neither (4 x 4)", d->tiles_n, d->tiles_m);
    if (d->ism_res && (d->ism_res < 8 || d->ism_res > GI_ISM_MAX_RES || (d->ism_res & (d->ism_res - 1))))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: ism_res %u: must be a power of two in 8..%u "
                          "(0: %u)", d->ism_res, GI_ISM_MAX_RES, GI_ISM_DEFAULT_RES);
    if (d->ism_bias != 0.0f && !(d->ism_bias >= 1.0f && d->ism_bias <= GI_ISM_MAX_BIAS))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: ism_bias %g: must be 1..%g (0: the default)",
                          (double)d->ism_bias, (double)GI_ISM_MAX_BIAS);
    if (!(d->clamp >= 0.0f && isfinite(d->clamp)) && d->clamp != SOFTGI_CLAMP_OFF)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: clamp %g: must be finite and > 0 (0: 400, "
                          "SOFTGI_CLAMP_OFF: off)", (double)d->clamp);
    return SOFTGI_OK;
}

static const char *const api__filters[] = {"box", "bilateral", "gaussian", "atrous", "none", NULL};
static const char *const api__visibilities[] = {"paraboloid", "paraboloid-slope", "ism", "raytrace", NULL};

/* The method's own checks of its parameters (its create), now rather
 * than at the first frame, after the many-light options' own checks. */
static pf_result api__check_indirect(const softgi_context *c, pf_error *e)
{
    gi_indirect_options io;
    pf_result r = api_indirect_options(&c->desc, &io, e);
    if (r != PF_OK) return r;
    void *state = NULL;
    r = c->method->create(&state, &io.params, e);
    if (r == PF_OK && c->method->destroy) c->method->destroy(state);
    return r;
}

softgi_context *softgi_create(const softgi_desc *desc, softgi_error *err)
{
    static const softgi_desc defaults;
    const softgi_desc *d = desc ? desc : &defaults;
    if ((d->width == 0) != (d->height == 0)) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: width %u x height %u: give both (1..%u) or neither "
                   "(640 x 480)", d->width, d->height, API__MAX_SIDE);
        return NULL;
    }
    if (d->width > API__MAX_SIDE || d->height > API__MAX_SIDE) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: width %u x height %u: each must be 1..%u", d->width,
                   d->height, API__MAX_SIDE);
        return NULL;
    }
    if (d->threads > API__MAX_THREADS) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: threads %u: must be 1..%u (0: the number of cores)",
                   d->threads, API__MAX_THREADS);
        return NULL;
    }
    if (d->vpls > API__MAX_VPLS || d->bounces > API__MAX_BOUNCES) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: vpls %u, bounces %u: must be 1..%u and 1..%u (0: default)",
                   d->vpls, d->bounces, API__MAX_VPLS, API__MAX_BOUNCES);
        return NULL;
    }
    if (d->max_memory && d->max_memory < API__MIN_MEMORY) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: max_memory %llu bytes: at least 64 MiB (0: half of this "
                   "machine's memory)", (unsigned long long)d->max_memory);
        return NULL;
    }
    if (d->flags & ~API__FLAGS) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: flags 0x%x: unknown bits", d->flags);
        return NULL;
    }
    if ((d->flags & SOFTGI_DIRECT_ONLY) && (d->flags & SOFTGI_INDIRECT_ONLY)) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: SOFTGI_DIRECT_ONLY and SOFTGI_INDIRECT_ONLY exclude each "
                   "other");
        return NULL;
    }
    if (d->param_count > API__MAX_PARAMS || (d->param_count && !d->params)) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: param_count %u: at most %u, with params not NULL",
                   d->param_count, API__MAX_PARAMS);
        return NULL;
    }
    if (api__check_frame_fields(d, err) != SOFTGI_OK) return NULL;
    const char *filter = d->filter ? api__choice(d->filter, api__filters) : NULL;
    if (d->filter && !filter) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: filter '%.100s': expected box, bilateral, gaussian, "
                   "atrous or none", d->filter);
        return NULL;
    }
    const char *visibility = d->visibility ? api__choice(d->visibility, api__visibilities) : NULL;
    if (d->visibility && !visibility) {
        api__error(err, SOFTGI_ERR_ARGUMENT,
                   "softgi_desc: visibility '%.100s': expected paraboloid, paraboloid-slope, ism or raytrace",
                   d->visibility);
        return NULL;
    }
    const char *method = d->method ? d->method : "ir";
    const gi_vpl_method *m = gi_vpl_method_find(method);
    if (!m) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: method '%s': softgi knows %s", method,
                   gi_vpl_method_names());
        return NULL;
    }
    pf_error e;
    pf_isa isa = PF_ISA_AUTO;
    if (d->isa && pf_isa_parse(d->isa, &isa, &e) != PF_OK) {
        api__fail(err, &e);
        return NULL;
    }
    pf_isa resolved;
    if (pf_isa_resolve(isa, &resolved, &e) != PF_OK) {
        api__fail(err, &e);
        return NULL;
    }

    softgi_context *c = calloc(1, sizeof *c);
    if (!c) {
        api__error(err, SOFTGI_ERR_OUT_OF_MEMORY, "out of memory creating a softgi context");
        return NULL;
    }
    c->desc = *d;
    c->desc.width = d->width ? d->width : API_DEFAULT_WIDTH;
    c->desc.height = d->height ? d->height : API_DEFAULT_HEIGHT;
    c->desc.threads = d->threads ? d->threads : pf_jobs_core_count();
    c->desc.isa = pf_isa_name(resolved);
    c->desc.method = m->name;
    c->desc.filter = filter;
    c->desc.visibility = visibility;
    c->desc.params = (const char *const *)c->params;
    c->desc.param_count = 0;
    c->isa = resolved;
    c->method = m;
    for (uint32_t i = 0; i < d->param_count; i++) {
        if (!d->params[i]) {
            softgi_destroy(c);
            api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_desc: params[%u] is NULL", i);
            return NULL;
        }
        size_t len = strlen(d->params[i]) + 1;
        if (!(c->params[i] = malloc(len))) {
            softgi_destroy(c);
            api__error(err, SOFTGI_ERR_OUT_OF_MEMORY, "out of memory copying the method's parameters");
            return NULL;
        }
        memcpy(c->params[i], d->params[i], len);
        c->desc.param_count = i + 1;
    }
    if (!(c->desc.flags & SOFTGI_DIRECT_ONLY) && api__check_indirect(c, &e) != PF_OK) {
        softgi_destroy(c);
        api__fail(err, &e);
        return NULL;
    }
    if (!(c->jobs = pf_jobs_create(c->desc.threads))) {
        api__error(err, SOFTGI_ERR_OUT_OF_MEMORY, "cannot start %u threads", c->desc.threads);
        softgi_destroy(c);
        return NULL;
    }
    api__ok(err);
    return c;
}

void softgi_internal_warn(softgi_context *c, int on)
{
    if (c) c->warn = on;
}

softgi_result softgi_internal_refine(softgi_context *c, uint32_t slices, uint32_t *cycle, softgi_error *err)
{
    if (!c || !c->loaded || c->frame_ready)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_internal_refine: after softgi_load_scene, before the first "
                                                    "frame");
    const uint32_t got = api_refine_fit(&c->desc, &c->scene, 1, slices);
    if (cycle) *cycle = got;
    api__ok(err);
    return SOFTGI_OK;
}

const softgi_internal_notes *softgi_internal_notes_get(const softgi_context *c)
{
    return c && c->loaded ? &c->notes : NULL;
}

/* ---------------------------------------------------------------- the scene */

/* The scene of softgi_load_scene, before Embree: read, camera, validate,
 * light, budget (the program's order, app_scene_load). */
static pf_result api__scene_load(softgi_context *c, const char *path, pf_error *e)
{
    pf_result r = api_scene_read(&c->scene, &c->anim, path, c->desc.max_memory, e);
    if (r != PF_OK) return r;
    c->loaded = 1;
    snprintf(c->scene_name, sizeof c->scene_name, "%s", path ? path : "the built-in Cornell box");
    if (c->scene.camera_count > 0) c->camera = c->scene.cameras[0];
    if ((r = pf_scene_validate(&c->scene, e)) != PF_OK) return r;
    softgi_internal_notes *n = &c->notes;
    if (c->scene.camera_count == 0) {
        r = api_default_camera(&c->scene, &c->camera, &n->camera, n->camera_spec, sizeof n->camera_spec, e);
        if (r != PF_OK) return r;
        n->auto_camera = 1;
    }
    /* emissive triangles are lights too (gi_area.h) */
    if (c->scene.light_count == 0 && !api_scene_has_emitters(&c->scene)) {
        pf_light l;
        r = api_default_light(&c->scene, &c->camera, c->desc.width, c->desc.height, &l, &n->light_median,
                              n->light_spec, sizeof n->light_spec, e);
        if (r == PF_OK) r = pf_scene_add_light(&c->scene, &l, e);
        if (r != PF_OK) return r;
        n->auto_light = 1;
    }
    return api_budget_check(&c->desc, &c->scene, 1, 1, 0, e);
}

softgi_result softgi_load_scene(softgi_context *c, const char *path, softgi_error *err)
{
    if (!c) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_load_scene: the context is NULL");
    pf_fpenv_state env = api__fpenv_enter();
    api__scene_free(c);
    pf_error e;
    double t0 = pf_time_now();
    pf_result r = api__scene_load(c, path, &e);
    pf_stage_add(&c->load_times, "load scene", (pf_time_now() - t0) * 1e3);
    if (r == PF_OK) {
        t0 = pf_time_now();
        /* what an animation can move in instances of its own (pf_rt.h) */
        r = pf_rt_create_dynamic(&c->rt, &c->scene, &c->anim, c->isa, c->desc.threads, &e);
        pf_stage_add(&c->load_times, "embree build", (pf_time_now() - t0) * 1e3);
    }
    if (r == PF_OK && !(c->desc.flags & SOFTGI_RAYTRACE)) {
        t0 = pf_time_now();
        r = rs_context_create(&c->raster, &c->scene, c->jobs, rs_simd_for_isa(c->isa), &e);
        pf_stage_add(&c->load_times, "raster setup", (pf_time_now() - t0) * 1e3);
    }
    api__fpenv_leave(env);
    if (r != PF_OK) {
        api__scene_free(c);
        return api__fail(err, &e);
    }
    api__ok(err);
    return SOFTGI_OK;
}

softgi_result softgi_set_camera(softgi_context *c, const softgi_camera *cam, softgi_error *err)
{
    if (!c || !cam) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_camera: the context or camera is NULL");
    if (!c->loaded) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_camera: no scene loaded");
    /* pf_cli_parse_camera's checks */
    pf_vec3 eye = pf_v3(cam->eye[0], cam->eye[1], cam->eye[2]);
    pf_vec3 target = pf_v3(cam->target[0], cam->target[1], cam->target[2]);
    if (!pf_scene_coord_ok(eye) || !pf_scene_coord_ok(target))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_camera: coordinates must be finite and lie within +-%g",
                          (double)PF_SCENE_MAX_COORD);
    if (!(cam->fovy_deg > 0.0f && cam->fovy_deg < 180.0f))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_camera: fovy_deg %g must be in (0, 180) degrees",
                          (double)cam->fovy_deg);
    if (eye.x == target.x && eye.y == target.y && eye.z == target.z)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_camera: eye and target must differ");
    pf_camera next;
    pf_error e;
    if (pf_camera_look_at(&next, eye, target, pf_radians(cam->fovy_deg), &e) != PF_OK) return api__fail(err, &e);
    softgi_internal_notes *n = &c->notes;
    if (n->auto_light) { /* the program places its light at the camera it renders with */
        pf_fpenv_state env = api__fpenv_enter();
        pf_light l;
        float median;
        char spec[sizeof n->light_spec];
        pf_result r = api_default_light(&c->scene, &next, c->desc.width, c->desc.height, &l, &median, spec,
                                        sizeof spec, &e);
        api__fpenv_leave(env);
        if (r != PF_OK) return api__fail(err, &e);
        c->scene.lights[0] = l;
        n->light_median = median;
        memcpy(n->light_spec, spec, sizeof spec);
    }
    c->camera = next;
    n->auto_camera = 0;
    if (c->frame_ready) c->frame.camera = next;
    api__ok(err);
    return SOFTGI_OK;
}

/* One API light as pf_cli_parse_light makes it from the same numbers. */
static softgi_result api__light(const softgi_light *in, uint32_t i, pf_light *out, softgi_error *err)
{
    memset(out, 0, sizeof *out);
    if (in->type != SOFTGI_LIGHT_POINT && in->type != SOFTGI_LIGHT_SPOT && in->type != SOFTGI_LIGHT_DIRECTIONAL)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: light %u: type %d is not point, spot or "
                          "directional", i, (int)in->type);
    if (in->type != SOFTGI_LIGHT_DIRECTIONAL) {
        out->position = pf_v3(in->position[0], in->position[1], in->position[2]);
        if (!pf_scene_coord_ok(out->position))
            return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: light %u: position must be finite and lie "
                              "within +-%g", i, (double)PF_SCENE_MAX_COORD);
    }
    if (in->type != SOFTGI_LIGHT_POINT) {
        /* normalised in double: (1e38, 1e38, 0) overflows a float length */
        const float *d = in->direction;
        double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
        if (!(len > 0.0) || !isfinite(len))
            return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: light %u: direction must be finite and "
                              "not zero", i);
        out->direction = pf_v3((float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len));
    }
    if (in->type == SOFTGI_LIGHT_SPOT) {
        if (!(in->inner_deg >= 0.0f && in->inner_deg < in->outer_deg && in->outer_deg <= 90.0f))
            return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: light %u: need 0 <= inner_deg < outer_deg "
                              "<= 90", i);
        out->inner_cone = pf_radians(in->inner_deg);
        out->outer_cone = pf_radians(in->outer_deg);
    }
    const float *col = in->color;
    if (!isfinite(col[0]) || !isfinite(col[1]) || !isfinite(col[2]) || !isfinite(in->intensity) || col[0] < 0 ||
        col[1] < 0 || col[2] < 0 || in->intensity < 0)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: light %u: colour and intensity must be finite "
                          "and >= 0", i);
    double cmax = fmax(col[0], fmax(col[1], col[2]));
    if (cmax * in->intensity > PF_MAX_RADIANCE)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: light %u: intensity x colour must be at most %g",
                          i, (double)PF_MAX_RADIANCE);
    out->type = in->type == SOFTGI_LIGHT_POINT  ? PF_LIGHT_POINT
                : in->type == SOFTGI_LIGHT_SPOT ? PF_LIGHT_SPOT
                                                : PF_LIGHT_DIRECTIONAL;
    out->color = pf_v3(col[0], col[1], col[2]);
    out->intensity = in->intensity;
    snprintf(out->name, sizeof out->name, "%s", in->type == SOFTGI_LIGHT_POINT  ? "cli-point"
                                                : in->type == SOFTGI_LIGHT_SPOT ? "cli-spot"
                                                                                : "cli-dir");
    return SOFTGI_OK;
}

/* The scene's punctual lights replaced by `next` (malloc'ed, owned from
 * here on), as softgi_set_lights documents. */
static void api__replace_lights(softgi_context *c, pf_light *next, uint32_t count)
{
    if (count == c->scene.light_count) {
        /* moved in place, as `softgi sequence` moves them: the frame sees
         * the same array and re-renders the maps of the lights that changed */
        memcpy(c->scene.lights, next, count * sizeof *next);
        free(next);
    } else {
        if (c->frame_ready) { /* the frame's shadow maps are per light: rebuilt at the next render */
            gi_frame_free(&c->frame);
            c->frame_ready = 0;
        }
        free(c->scene.lights);
        c->scene.lights = next;
        c->scene.light_count = count;
    }
    c->notes.auto_light = 0;
}

/* softgi_set_lights' checks and the new array (count lights, uninitialised)
 * shared with softgi_internal_set_scene_lights; NULL with *r set on failure. */
static pf_light *api__lights_begin(const softgi_context *c, const void *lights, uint32_t count, softgi_error *err,
                                   softgi_result *r)
{
    *r = SOFTGI_ERR_ARGUMENT;
    if (!c || !lights) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: the context or lights is NULL");
        return NULL;
    }
    if (!c->loaded) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: no scene loaded");
        return NULL;
    }
    if (count == 0 || count > API__MAX_LIGHTS) {
        api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_lights: count %u: give 1..%u lights", count, API__MAX_LIGHTS);
        return NULL;
    }
    pf_light *next = malloc(count * sizeof *next);
    if (!next) *r = api__error(err, SOFTGI_ERR_OUT_OF_MEMORY, "out of memory setting %u lights", count);
    return next;
}

softgi_result softgi_set_lights(softgi_context *c, const softgi_light *lights, uint32_t count, softgi_error *err)
{
    softgi_result r;
    pf_light *next = api__lights_begin(c, lights, count, err, &r);
    if (!next) return r;
    for (uint32_t i = 0; i < count; i++) {
        softgi_result r = api__light(&lights[i], i, &next[i], err);
        if (r != SOFTGI_OK) {
            free(next);
            return r;
        }
    }
    api__replace_lights(c, next, count);
    api__ok(err);
    return SOFTGI_OK;
}

softgi_result softgi_internal_set_scene_lights(softgi_context *c, const pf_light *lights, uint32_t count,
                                               softgi_error *err)
{
    softgi_result r;
    pf_light *next = api__lights_begin(c, lights, count, err, &r);
    if (!next) return r;
    memcpy(next, lights, count * sizeof *next);
    api__replace_lights(c, next, count);
    api__ok(err);
    return SOFTGI_OK;
}

softgi_result softgi_set_time(softgi_context *c, double seconds, const char *animation, softgi_error *err)
{
    if (!c) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_time: the context is NULL");
    if (!c->loaded) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_time: no scene loaded");
    if (!(seconds >= 0.0 && seconds <= PF_ANIM_MAX_TIME))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_set_time: %g seconds: must be finite and in 0..%g",
                          seconds, PF_ANIM_MAX_TIME);
    pf_fpenv_state env = api__fpenv_enter();
    pf_error e;
    uint32_t moved = 0;
    pf_result r = PF_OK;
    if (!c->moved && c->anim.prim_count && !(c->moved = calloc(c->anim.prim_count, sizeof *c->moved)))
        r = pf_error_set(&e, PF_ERR_OUT_OF_MEMORY, "out of memory for the pose's report");
    if (r == PF_OK) r = api_scene_pose(&c->scene, &c->anim, c->scene_name, seconds, animation, &moved, c->moved, &e);
    int updated = 0;
    if (r == PF_OK && moved) {
        updated = 1;
        r = api_geometry_moved(c->rt, c->raster, c->frame_ready ? &c->frame : NULL, c->moved, c->anim.prim_count,
                               &e); /* in place: the frame goes on, as after softgi_set_lights */
    }
    api__fpenv_leave(env);
    if (r != PF_OK) {
        if (updated) api__scene_free(c); /* an update failed part-way: no scene is left */
        return api__fail(err, &e);
    }
    api__ok(err);
    return SOFTGI_OK;
}

/* ---------------------------------------------------------------- frames */

/* pf_stage_hook: a stage of the frame has finished (softgi_desc.progress). */
static void api__stage_done(void *user, const char *name, double ms)
{
    (void)ms;
    const softgi_context *c = user;
    c->desc.progress(c->desc.progress_user, name, 0, 0);
}

static softgi_result api__check_target(const softgi_context *c, const softgi_target *t, softgi_error *err)
{
    if (!t) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: the target is NULL");
    if (!t->rgb && !t->rgba8)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: the target has neither rgb nor rgba8");
    const uint32_t w = c->desc.width;
    if (t->rgb && t->rgb_stride && t->rgb_stride < (size_t)3 * w)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: rgb_stride %zu is less than 3 x width (%u)",
                          t->rgb_stride, 3 * w);
    if (t->rgba8 && t->rgba8_stride && t->rgba8_stride < (size_t)4 * w)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: rgba8_stride %zu is less than 4 x width (%u)",
                          t->rgba8_stride, 4 * w);
    if (!t->auto_exposure && !(fabsf(t->exposure) <= 64.0f))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: exposure %g: must be within +-64 stops",
                          (double)t->exposure);
    return SOFTGI_OK;
}

softgi_result softgi_render(softgi_context *c, const softgi_target *t, softgi_error *err)
{
    if (!c) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: the context is NULL");
    softgi_result sr = api__check_target(c, t, err);
    if (sr != SOFTGI_OK) return sr;
    if (!c->loaded) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_render: no scene loaded (softgi_load_scene)");
    pf_fpenv_state env = api__fpenv_enter();
    pf_error e;
    pf_result r = PF_OK;
    if (!c->frame_ready) {
        r = api_frame_create(&c->frame, &c->desc, &c->scene, c->rt, c->raster, c->jobs, &c->camera, 1, c->warn, &e);
        if (r == PF_OK) c->frame_ready = 1;
        if (r == PF_OK) r = api_declare_dynamic(&c->frame, &c->anim, &e);
    }
    if (r == PF_OK) {
        /* progress: the stages through the timer's hook, the VPL maps
         * through the frame's own callback; both on this thread */
        pf_stage_hook hook = {NULL, NULL};
        if (c->desc.progress) {
            hook = pf_stage_hook_set((pf_stage_hook){api__stage_done, c});
            c->frame.progress = c->desc.progress, c->frame.progress_user = c->desc.progress_user;
        }
        if (c->desc.flags & SOFTGI_RAYTRACE) gi_frame_render_raytraced(&c->frame);
        else gi_frame_render_raster(&c->frame);
        if (c->desc.progress) pf_stage_hook_set(hook);
        c->frames++;
        if (c->frame.status != PF_OK) r = c->frame.status, e = c->frame.error;
        /* what the program refuses to write is not returned either */
        if (r == PF_OK)
            r = pf_imageio_check("the frame", c->frame.final, c->desc.width, c->desc.height, PF_IMAGEIO_RADIANCE,
                                 &e);
    }
    if (r == PF_OK) {
        const float *src = c->frame.final;
        const uint32_t w = c->desc.width, h = c->desc.height;
        if (t->rgb) {
            size_t stride = t->rgb_stride ? t->rgb_stride : (size_t)3 * w;
            for (uint32_t y = 0; y < h; y++)
                memcpy(t->rgb + y * stride, src + (size_t)y * w * 3, (size_t)w * 3 * sizeof(float));
        }
        if (t->rgba8) {
            c->exposure = t->auto_exposure ? pf_defaults_exposure(src, w, h, NULL) : t->exposure;
            const float scale = exp2f(c->exposure); /* as pf_imageio_stage_png */
            size_t stride = t->rgba8_stride ? t->rgba8_stride : (size_t)4 * w;
            for (uint32_t y = 0; y < h; y++) {
                uint8_t *o = t->rgba8 + y * stride;
                const float *p = src + (size_t)y * w * 3;
                for (uint32_t x = 0; x < w; x++) {
                    o[4 * x + 0] = pf_imageio_display(p[3 * x + 0], scale);
                    o[4 * x + 1] = pf_imageio_display(p[3 * x + 1], scale);
                    o[4 * x + 2] = pf_imageio_display(p[3 * x + 2], scale);
                    o[4 * x + 3] = 255;
                }
            }
        }
    }
    api__fpenv_leave(env);
    if (r != PF_OK) return api__fail(err, &e);
    api__ok(err);
    return SOFTGI_OK;
}

/* ---------------------------------------------------------------- reading back */

uint32_t softgi_stage_channels(softgi_stage stage)
{
    if ((unsigned)stage >= SOFTGI_STAGE_COUNT) return 0;
    return stage == SOFTGI_STAGE_DEPTH ? 1 : 3;
}

softgi_result softgi_read_stage(const softgi_context *c, softgi_stage stage, float *dst, size_t stride,
                                softgi_error *err)
{
    if (!c || !dst) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_read_stage: the context or dst is NULL");
    const uint32_t ch = softgi_stage_channels(stage);
    if (!ch) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_read_stage: unknown stage %d", (int)stage);
    if (!c->frame_ready || !c->frames)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_read_stage: no frame rendered yet (softgi_render)");
    const gi_frame *f = &c->frame;
    const uint32_t w = f->width, h = f->height;
    if (stride && stride < (size_t)ch * w)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_read_stage: stride %zu is less than %u x width (%u)",
                          stride, ch, ch * w);
    if (!stride) stride = (size_t)ch * w;
    const rs_gbuffer *g = &f->gbuf;
    const float *planes[3] = {NULL, NULL, NULL}, *rgb = NULL;
    switch (stage) {
    case SOFTGI_STAGE_DEPTH: planes[0] = g->depth; break;
    case SOFTGI_STAGE_POSITION: planes[0] = g->pos_x, planes[1] = g->pos_y, planes[2] = g->pos_z; break;
    case SOFTGI_STAGE_NORMAL: planes[0] = g->nrm_x, planes[1] = g->nrm_y, planes[2] = g->nrm_z; break;
    case SOFTGI_STAGE_ALBEDO: planes[0] = g->alb_r, planes[1] = g->alb_g, planes[2] = g->alb_b; break;
    case SOFTGI_STAGE_DIRECT: rgb = f->direct; break;
    case SOFTGI_STAGE_IRRADIANCE: rgb = f->indirect ? f->ind.combined : NULL; break;
    case SOFTGI_STAGE_FILTERED: rgb = f->indirect ? f->ind.filtered : NULL; break;
    default: rgb = f->final; break;
    }
    if (!planes[0] && !rgb)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_read_stage: the frame has no indirect light "
                          "(SOFTGI_DIRECT_ONLY)");
    for (uint32_t y = 0; y < h; y++) {
        float *o = dst + y * stride;
        if (rgb) {
            memcpy(o, rgb + (size_t)y * w * 3, (size_t)w * 3 * sizeof(float));
        } else if (ch == 1) {
            memcpy(o, planes[0] + (size_t)y * w, (size_t)w * sizeof(float));
        } else { /* as gi_dump.c: 0 where no surface was hit */
            for (uint32_t x = 0; x < w; x++) {
                size_t i = (size_t)y * w + x;
                int hit = g->prim[i] != RS_GBUFFER_EMPTY;
                for (uint32_t k = 0; k < 3; k++) o[3 * x + k] = hit ? planes[k][i] : 0.0f;
            }
        }
    }
    api__ok(err);
    return SOFTGI_OK;
}

uint32_t softgi_get_timings(const softgi_context *c, softgi_timing *out, uint32_t max)
{
    if (!c) return 0;
    uint32_t n = 0;
    const pf_stage_times *tables[2] = {&c->load_times, c->frame_ready && c->frames ? &c->frame.times : NULL};
    for (int k = 0; k < 2; k++) {
        if (!tables[k]) continue;
        for (uint32_t i = 0; i < tables[k]->count; i++, n++)
            if (out && n < max) out[n] = (softgi_timing){tables[k]->name[i], tables[k]->ms[i]};
    }
    return n;
}

softgi_result softgi_get_info(const softgi_context *c, softgi_info *info, softgi_error *err)
{
    if (!c || !info) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_get_info: the context or info is NULL");
    memset(info, 0, sizeof *info);
    info->width = c->desc.width;
    info->height = c->desc.height;
    info->threads = c->desc.threads;
    info->isa = pf_isa_name(c->isa);
    info->method = c->desc.flags & SOFTGI_DIRECT_ONLY ? NULL : c->method->name;
    info->scene_loaded = c->loaded;
    info->warnings = "";
    info->exposure = c->exposure;
    if (c->loaded) {
        info->triangles = c->scene.tri_count;
        info->lights = c->scene.light_count;
        info->auto_camera = c->notes.auto_camera;
        info->auto_light = c->notes.auto_light;
        info->warnings = c->scene.warnings;
        info->animations = c->anim.clip_count;
        const pf_camera *cam = &c->camera;
        pf_vec3 t = pf_v3_add(cam->eye, cam->forward);
        info->camera = (softgi_camera){{cam->eye.x, cam->eye.y, cam->eye.z}, {t.x, t.y, t.z},
                                       cam->yfov * (180.0f / PF_PI)};
        info->frames = c->frames;
        if (c->frame_ready && c->frames) {
            const gi_frame *f = &c->frame;
            info->aa_samples = f->aa.samples ? f->aa.samples : 1;
            if (f->indirect) {
                info->vpls = f->ind.vpls.count;
                info->maps_rendered = f->ind.maps_rendered;
                info->tiles_n = f->ind.n;
                info->tiles_m = f->ind.m;
                info->clamp_b = f->ind.b;
                info->visibility = f->ind.ism     ? "imperfect shadow maps"
                                   : !f->ind.para ? "Embree rays"
                                   : f->ind.plane ? "paraboloid maps"
                                                  : "paraboloid maps, slope bias";
                info->indirect_scale = f->ind.scale;
            }
        }
    }
    api__ok(err);
    return SOFTGI_OK;
}

softgi_result softgi_dump_stages(const softgi_context *c, const char *dir, float exposure, softgi_dump_format format,
                                 softgi_error *err)
{
    if (!c || !dir) return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_dump_stages: the context or dir is NULL");
    if (format != SOFTGI_DUMP_PNG && format != SOFTGI_DUMP_EXR && format != SOFTGI_DUMP_BOTH)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_dump_stages: format %d: SOFTGI_DUMP_PNG, _EXR or _BOTH",
                          (int)format);
    if (!(fabsf(exposure) <= 64.0f))
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_dump_stages: exposure %g: must be within +-64 stops",
                          (double)exposure);
    if (!c->frame_ready || !c->frames)
        return api__error(err, SOFTGI_ERR_ARGUMENT, "softgi_dump_stages: no frame rendered yet (softgi_render)");
    gi_view_settings vs = {exposure, 0}; /* the views `softgi view` shows at this exposure */
    pf_error e;
    const gi_dump_format fmt = format == SOFTGI_DUMP_BOTH ? GI_DUMP_BOTH
                               : format == SOFTGI_DUMP_EXR ? GI_DUMP_EXR
                                                           : GI_DUMP_PNG;
    if (gi_dump_stages(&c->frame, dir, &vs, fmt, &e) != PF_OK) return api__fail(err, &e);
    api__ok(err);
    return SOFTGI_OK;
}

uint64_t softgi_image_hash(const float *rgb, uint32_t width, uint32_t height, size_t stride)
{
    /* pf_imageio_hash over the rows in order: the same FNV-1a 64 state
     * carried across rows, so a packed buffer gives the program's --hash */
    uint64_t hsh = 0xcbf29ce484222325ull;
    if (!rgb) return hsh;
    if (!stride) stride = (size_t)3 * width;
    for (uint32_t y = 0; y < height; y++) {
        const uint8_t *b = (const uint8_t *)(rgb + y * stride);
        for (size_t i = 0; i < (size_t)width * 3 * sizeof(float); i++) {
            hsh ^= b[i];
            hsh *= 0x100000001b3ull;
        }
    }
    return hsh;
}
