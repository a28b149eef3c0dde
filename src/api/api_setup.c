/* api_setup: the set-up shared by the library and the program (api_setup.h). */
#include "api_setup.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "gi_indirect.h"
#include "gi_ism.h"
#include "pf_anim.h"
#include "pf_budget.h"
#include "pf_gltf.h"
#include "rs_shadow.h"

/* The built-in scene (scenes/cornell-box, embedded by CMake). */
extern const unsigned char softgi_api_default_scene[];
extern const unsigned long softgi_api_default_scene_size;

int api_scene_has_emitters(const pf_scene *scene)
{
    for (uint32_t t = 0; t < scene->tri_count; t++) {
        const float *e = scene->materials[scene->tri_material[t]].emission;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f) return 1;
    }
    return 0;
}

pf_result api_scene_read(pf_scene *scene, pf_anim *anim, const char *path, uint64_t max_memory, pf_error *err)
{
    pf_gltf_options go = {.max_memory = max_memory, .anim = anim};
    if (path) return pf_gltf_load(scene, path, &go, err);
    return pf_gltf_load_memory(scene, softgi_api_default_scene, softgi_api_default_scene_size, NULL,
                               "embedded scenes/cornell-box", &go, err);
}

pf_result api_anim_clip(const pf_anim *anim, const char *scene_name, const char *animation, int32_t *clip,
                        pf_error *err)
{
    pf_result r = PF_OK;
    *clip = PF_ANIM_ALL;
    if (anim->clip_count == 0) r = pf_anim_find(anim, NULL, 0, clip, err); /* "the scene has no animations" */
    else if (animation) {
        size_t n = strlen(animation), digits = strspn(animation, "0123456789");
        if (n > 0 && digits == n && n <= 9) r = pf_anim_find(anim, NULL, strtoll(animation, NULL, 10), clip, err);
        else r = pf_anim_find(anim, animation, 0, clip, err);
    }
    if (r != PF_OK) {
        char m[sizeof err->message];
        snprintf(m, sizeof m, "%s", err->message);
        pf_error_set(err, r, "%s: %s", scene_name, m);
    }
    return r;
}

pf_result api_scene_pose(pf_scene *scene, pf_anim *anim, const char *scene_name, double seconds,
                         const char *animation, uint32_t *moved, pf_anim_moved *report, pf_error *err)
{
    int32_t clip;
    pf_result r = api_anim_clip(anim, scene_name, animation, &clip, err);
    if (r != PF_OK) return r; /* named already */
    if ((r = pf_anim_pose(scene, report, moved, anim, clip, seconds, err)) != PF_OK) {
        char m[sizeof err->message];
        snprintf(m, sizeof m, "%s", err->message);
        pf_error_set(err, r, "%s: %s", scene_name, m);
    }
    return r;
}

pf_result api_geometry_moved(pf_rt *rt, rs_context *raster, gi_frame *frame, const pf_anim_moved *moved,
                             uint32_t count, pf_error *err)
{
    pf_result r = pf_rt_update(rt, moved, count, PF_RT_REBUILD, err);
    if (r == PF_OK && raster) r = rs_context_update(raster, moved, count, err);
    if (r == PF_OK && frame) r = gi_frame_geometry_moved(frame, moved, count, err);
    return r;
}

pf_result api_declare_dynamic(gi_frame *frame, const pf_anim *anim, pf_error *err)
{
    for (uint32_t k = 0; k < anim->prim_count; k++) {
        const pf_anim_prim *p = &anim->prims[k];
        if (!p->dynamic) continue;
        pf_anim_moved m = {.vertex_first = p->vertex_first, .vertex_count = p->vertex_count,
                           .tri_first = p->tri_first, .tri_count = p->tri_count, .moved = 1};
        pf_result r = gi_frame_declare_dynamic(frame, &m, 1, err);
        if (r != PF_OK) return r;
    }
    return PF_OK;
}

/* One number as the program prints it (printf "%.*g" with `digits`) and
 * parses it back (strtof, as pf_cli does). */
static float api__text_round(int digits, float v)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.*g", digits, (double)v);
    return strtof(buf, NULL);
}

pf_result api_default_camera(const pf_scene *scene, pf_camera *camera, pf_default_camera *dc_out, char *spec,
                             size_t spec_size, pf_error *err)
{
    pf_default_camera dc;
    pf_defaults_camera(&dc, scene);
    if (dc_out) *dc_out = dc;
    pf_result r = PF_OK;
    /* 5 digits read well; 9 give every float back exactly, for a small
     * scene far from the origin whose eye and target 5 digits would merge */
    for (int digits = 5; digits <= 9; digits += 4) {
        snprintf(spec, spec_size, "%.*g,%.*g,%.*g:%.*g,%.*g,%.*g:%g", digits, (double)dc.eye.x, digits,
                 (double)dc.eye.y, digits, (double)dc.eye.z, digits, (double)dc.target.x, digits, (double)dc.target.y,
                 digits, (double)dc.target.z, (double)dc.fovy_deg);
        pf_vec3 eye = pf_v3(api__text_round(digits, dc.eye.x), api__text_round(digits, dc.eye.y),
                            api__text_round(digits, dc.eye.z));
        pf_vec3 target = pf_v3(api__text_round(digits, dc.target.x), api__text_round(digits, dc.target.y),
                               api__text_round(digits, dc.target.z));
        float fovy = api__text_round(6, dc.fovy_deg); /* "%g" */
        /* pf_cli_parse_camera's checks */
        if (!pf_scene_coord_ok(eye) || !pf_scene_coord_ok(target) || !(fovy > 0.0f && fovy < 180.0f) ||
            (eye.x == target.x && eye.y == target.y && eye.z == target.z))
            r = pf_error_set(err, PF_ERR_ARGUMENT, "the automatic camera --camera %s is not a valid camera", spec);
        else r = pf_camera_look_at(camera, eye, target, pf_radians(fovy), err);
        if (r == PF_OK) break;
    }
    if (r != PF_OK) return r;
    snprintf(camera->name, sizeof camera->name, "default");
    return PF_OK;
}

pf_result api_default_light(const pf_scene *scene, const pf_camera *camera, uint32_t width, uint32_t height,
                            pf_light *out, float *median_out, char *spec, size_t spec_size, pf_error *err)
{
    pf_light l;
    float median;
    pf_defaults_light(&l, &median, scene, camera, width, height);
    if (median_out) *median_out = median;
    pf_light parsed;
    pf_result r = PF_OK;
    /* 5 digits unless they move the light by more than 1% of the median
     * distance (a small scene far from the origin): then 9, exact */
    for (int digits = 5; digits <= 9; digits += 4) {
        snprintf(spec, spec_size, "point:%.*g,%.*g,%.*g:1,1,1:%.3g", digits, (double)l.position.x, digits,
                 (double)l.position.y, digits, (double)l.position.z, (double)l.intensity);
        memset(&parsed, 0, sizeof parsed);
        parsed.type = PF_LIGHT_POINT;
        parsed.position = pf_v3(api__text_round(digits, l.position.x), api__text_round(digits, l.position.y),
                                api__text_round(digits, l.position.z));
        parsed.color = pf_v3(1.0f, 1.0f, 1.0f);
        parsed.intensity = api__text_round(3, l.intensity);
        /* pf_cli_parse_light's checks */
        if (!pf_scene_coord_ok(parsed.position) || !isfinite(parsed.intensity) || !(parsed.intensity >= 0.0f) ||
            (double)parsed.intensity > PF_MAX_RADIANCE) {
            r = pf_error_set(err, PF_ERR_ARGUMENT, "the automatic light --light %s is not a valid light", spec);
            continue;
        }
        r = PF_OK;
        pf_vec3 moved = pf_v3_sub(parsed.position, l.position);
        if (pf_v3_max_comp(pf_v3(fabsf(moved.x), fabsf(moved.y), fabsf(moved.z))) <= 0.01f * median) break;
    }
    if (r != PF_OK) return r;
    *out = parsed;
    snprintf(out->name, sizeof out->name, "default");
    return PF_OK;
}

pf_result api_budget_check(const softgi_desc *d, const pf_scene *scene, int frame, int indirect, int warn,
                           pf_error *err)
{
    const uint32_t width = d->width ? d->width : API_DEFAULT_WIDTH;
    const uint32_t height = d->height ? d->height : API_DEFAULT_HEIGHT;
    pf_budget b;
    pf_budget_init(&b, d->max_memory);
    pf_result r = pf_budget_take(&b, scene->memory_bytes, "the scene", err);
    if (r != PF_OK) return r;
    if (!frame) { /* the path tracer: its image and per-pixel sums */
        r = pf_budget_take(&b, pf_budget_mul((uint64_t)width * height, 64), "the image", err);
        if (r == PF_OK && warn) pf_budget_warn(&b, "a smaller scene or --size");
        return r;
    }
    const int ism = d->visibility && !strcmp(d->visibility, "ism");
    const int rays = d->visibility && !strcmp(d->visibility, "raytrace");
    uint32_t vpls = indirect && !(d->flags & SOFTGI_DIRECT_ONLY) ? (d->vpls ? d->vpls : 256) : 0;
    if (d->vpl_cycle > 1 && vpls <= GI_INDIRECT_MAX_SET / d->vpl_cycle) vpls *= d->vpl_cycle; /* the whole set */
    uint32_t res = rays ? 1 : ism ? (d->ism_res ? d->ism_res : GI_ISM_DEFAULT_RES) : 0;
    uint32_t area = api_scene_has_emitters(scene) ? (d->area_points ? d->area_points : GI_AREA_DEFAULT_POINTS) : 0;
    char what[160];
    snprintf(what, sizeof what, "the frame (%ux%u, %u lights with shadow maps of %u^2, %u VPLs)", width, height,
             scene->light_count, d->shadow_size ? d->shadow_size : RS_SHADOW_DEFAULT_SIZE, vpls);
    uint64_t all = gi_frame_memory_estimate(scene, width, height, d->shadow_size, vpls, res, area);
    r = pf_budget_take(&b, all, what, err);
    /* which knob helps, for the refusal or the warning */
    uint64_t no_vpls = gi_frame_memory_estimate(scene, width, height, d->shadow_size, 0, res, area);
    uint64_t no_shadows = all - gi_frame_memory_estimate(scene, 0, 0, d->shadow_size, 0, res, 0);
    const char *hint = all - no_vpls > all / 2      ? "use fewer VPLs or --visibility raytrace (--vpls N)"
                       : all - no_shadows > all / 2 ? "use fewer lights or a smaller --shadow-size"
                                                    : "use a smaller --size";
    if (r != PF_OK) {
        size_t n = strlen(err->message);
        snprintf(err->message + n, sizeof err->message - n, "; %s", hint);
    } else if (warn)
        pf_budget_warn(&b, hint);
    return r;
}

uint32_t api_refine_fit(softgi_desc *d, const pf_scene *scene, int indirect, uint32_t slices)
{
    d->temporal = API_REFINE_TEMPORAL, d->taa = API_REFINE_TAA;
    for (uint32_t s = slices; s >= 2; s /= 2) {
        d->vpl_cycle = s, d->cycle_maps = API_REFINE_MAPS;
        pf_error e;
        if (api_budget_check(d, scene, 1, indirect, 0, &e) == PF_OK) return s;
    }
    d->vpl_cycle = d->cycle_maps = 0;
    return 0;
}

pf_result api_indirect_options(const softgi_desc *d, gi_indirect_options *io, pf_error *err)
{
    memset(io, 0, sizeof *io);
    const char *method = d->method ? d->method : "ir";
    io->method = gi_vpl_method_find(method);
    if (!io->method)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method '%s': softgi knows %s", method, gi_vpl_method_names());
    io->vpls = d->vpls;
    io->bounces = d->bounces;
    io->tiles_n = d->tiles_n;
    io->tiles_m = d->tiles_m;
    io->no_interleave = (d->flags & SOFTGI_NO_INTERLEAVE) != 0;
    io->visibility_ism = d->visibility && !strcmp(d->visibility, "ism");
    io->visibility_raytrace = d->visibility && !strcmp(d->visibility, "raytrace");
    io->para_slope = d->visibility && !strcmp(d->visibility, "paraboloid-slope");
    if (!io->visibility_ism && (d->ism_res || d->ism_points || d->ism_bias != 0.0f))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--ism-res, --ism-points and --ism-bias need --visibility ism");
    io->ism.resolution = d->ism_res;
    io->ism.points = d->ism_points;
    io->ism.bias_scale = d->ism_bias;
    for (uint32_t i = 0; i < d->param_count; i++) {
        pf_result r = gi_params_add(&io->params, d->params[i], err);
        if (r != PF_OK) return r;
    }
    /* gi_indirect_options.clamp: < 0 the default 400, 0 off */
    io->clamp = d->clamp == 0.0f ? -1.0f : d->clamp < 0.0f ? 0.0f : d->clamp;
    io->pipeline = (d->flags & SOFTGI_PIPELINE) != 0;
    io->scale = d->indirect_scale;
    io->temporal = d->temporal;
    io->cycle = d->vpl_cycle;
    io->cycle_maps = d->cycle_maps;
    io->compensate = (d->flags & SOFTGI_COMPENSATE) != 0;
    io->filter_distance = (d->flags & SOFTGI_FILTER_DISTANCE) != 0;
    io->filter = !d->filter || !strcmp(d->filter, "box") ? GI_FILTER_BOX
                 : !strcmp(d->filter, "bilateral")       ? GI_FILTER_BILATERAL
                 : !strcmp(d->filter, "gaussian")        ? GI_FILTER_GAUSSIAN
                 : !strcmp(d->filter, "atrous")          ? GI_FILTER_ATROUS
                                                         : GI_FILTER_NONE;
    return PF_OK;
}

pf_result api_frame_create(gi_frame *f, const softgi_desc *d, const pf_scene *scene, const pf_rt *rt,
                           rs_context *raster, pf_jobs *jobs, const pf_camera *camera, int indirect, int warn,
                           pf_error *err)
{
    pf_result r = api_budget_check(d, scene, 1, indirect, warn, err);
    if (r != PF_OK) return r;
    gi_indirect_options io;
    const int with_indirect = indirect && !(d->flags & SOFTGI_DIRECT_ONLY);
    if (with_indirect && (r = api_indirect_options(d, &io, err)) != PF_OK) return r;
    gi_frame_desc fd = {.scene = scene, .rt = rt, .jobs = jobs, .raster = raster, .camera = camera,
                        .width = d->width ? d->width : API_DEFAULT_WIDTH,
                        .height = d->height ? d->height : API_DEFAULT_HEIGHT, .shadow_size = d->shadow_size,
                        .area_strata = d->area_strata, .area_points = d->area_points,
                        .area_slope = d->visibility && !strcmp(d->visibility, "paraboloid-slope"),
                        .indirect = with_indirect ? &io : NULL,
                        .indirect_only = (d->flags & SOFTGI_INDIRECT_ONLY) != 0, .aa_samples = d->aa,
                        .taa_frames = d->taa};
    return gi_frame_create(f, &fd, err);
}
