/* app_render: `softgi render` (see pf_cli.h for the options), built on the
 * public API (include/softgi/softgi.h, docs/api.md):
 *
 * options -> softgi_desc (app_desc) -> softgi_create -> softgi_load_scene
 * -> --camera (softgi_set_camera) / --light (softgi_internal_set_scene_lights)
 * -> softgi_render into a linear RGB buffer -> write the images
 * (softgi_dump_stages for --dump-stages), printing the time of every step
 * (softgi_get_timings) and what the frame was (softgi_get_info).
 *
 * What only the program does (src/api/softgi_internal.h): the
 * "softgi: note:" lines of the automatic camera and light with their
 * reasons, the memory warning, and --light applied as parsed.
 *
 * Outputs (pf_imageio.h, by extension): -o NAME.png writes the PNG and the
 * linear image NAME.pfm (or --hdr FILE.exr / FILE.pfm); -o NAME.exr or
 * NAME.pfm writes only that linear image, at exactly that name; any other
 * extension, and two outputs naming the same file (with the --dump-stages
 * files too), are refused before anything is rendered (exit 2). Every file
 * is written to a temporary file and renamed over its target when
 * complete; an image with a NaN, infinite or negative value is not written
 * (exit 1; softgi_render refuses such a frame). --dump-stages DIR writes
 * the stages (gi_dump.h) as pictures, float OpenEXR data or both
 * (--dump-format png|exr|both, default png). --exposure auto picks the
 * PNG's (and the pictures') exposure from the image (app_exposure); a
 * nearly black image gets a one-line hint.
 *
 * A frame that takes long (large --vpls: every VPL's paraboloid map is
 * rendered in the first frame) shows, on a terminal and without -q, the
 * time so far and the last stage finished (app_progress.h; through
 * softgi_desc.progress, so the frame knows nothing of it).
 *
 * --time SECONDS [--animation NAME|INDEX] poses the scene's glTF
 * animations (softgi_set_time, pf_anim.h) after --camera and --light: the
 * automatic camera and light are those of the static pose, so every time
 * of an animation is framed and lit alike.
 *
 * --aa N (gi_aa.h): N jittered samples per pixel, averaged in linear
 * radiance before anything is written; --aa 1 (the default) is the
 * unjittered frame, bit for bit.
 *
 * --frames N (default 1) renders N frames of the still view and writes the
 * last (its stages with --dump-stages): with N > 1 and none of --temporal,
 * --vpl-cycle, --cycle-maps given, softgi view's progressive refinement
 * (softgi_internal_refine: --temporal 32 --taa 16 and VPL cycling with its
 * warm-up, app_refine_slices), so the written image is the view's frame N.
 *
 * --pipeline on|off (default off) is accepted: it
 * changes only multi-frame work (one frame renders bit-identically either
 * way, since frame 0 runs the VPL update in place; gi_indirect.h). */
#include <stdlib.h>
#include <string.h>

#include "api_setup.h"
#include "app.h"
#include "app_progress.h"
#include "gi_dump.h"
#include "gi_view.h"
#include "pf_imageio.h"
#include "pf_timer.h"
#include "softgi_internal.h"

/* --dump-format as gi_dump's format (not given: the pictures). */
static gi_dump_format app__dump_format(const pf_options *o)
{
    return o->dump_format == (PF_CLI_DUMP_PNG | PF_CLI_DUMP_EXR) ? GI_DUMP_BOTH
           : o->dump_format == PF_CLI_DUMP_EXR                   ? GI_DUMP_EXR
                                                                 : GI_DUMP_PNG;
}

/* An output that is also the dump file `dump`: refused. */
static pf_result app__not_dumped(const pf_imageio_outputs *out, const char *dump, pf_error *err)
{
    const char *same = out->png[0] && pf_imageio_same_output(out->png, dump) ? out->png
                       : pf_imageio_same_output(out->linear, dump)          ? out->linear
                                                                             : NULL;
    if (!same) return PF_OK;
    return pf_error_set(err, PF_ERR_ARGUMENT, "'%s' is also a --dump-stages file (%s); give another -o or --hdr", same,
                        dump);
}

/* The files this render will write (into *out), checked before anything is
 * rendered: supported extensions, and no two outputs naming the same file. */
static pf_result app__check_outputs(const pf_options *o, const char *default_png, pf_imageio_outputs *out,
                                    pf_error *err)
{
    char dump[4200];
    const gi_dump_format fmt = app__dump_format(o);
    pf_result r = pf_imageio_outputs_resolve(out, o->out_path, o->hdr_path, default_png, err);
    if (r == PF_OK && o->dump_dir) {
        snprintf(dump, sizeof dump, "%s/captions.txt", o->dump_dir);
        r = app__not_dumped(out, dump, err);
    }
    for (int v = 0; r == PF_OK && o->dump_dir && v < GI_VIEW_COUNT; v++) {
        const char *name = gi_view_name((gi_view_id)v);
        snprintf(dump, sizeof dump, "%s/%02d-%s.png", o->dump_dir, v, name);
        if (fmt & GI_DUMP_PNG) r = app__not_dumped(out, dump, err);
        snprintf(dump, sizeof dump, "%s/%02d-%s.exr", o->dump_dir, v, name);
        if (r == PF_OK && (fmt & GI_DUMP_EXR) && gi_dump_has_exr((gi_view_id)v)) r = app__not_dumped(out, dump, err);
    }
    return r;
}

/* softgi_progress_fn: a stage of the frame has finished (done = total =
 * 0), or a long stage's progress (the VPL maps). */
typedef struct app__render_progress {
    app_progress bar;
    uint32_t stages;
    char what[96];
} app__render_progress;

static void app__render_progress_fn(void *user, const char *what, uint32_t done, uint32_t total)
{
    app__render_progress *p = user;
    if (!total) {
        p->stages++;
        snprintf(p->what, sizeof p->what, "frame: %u stages done, the last %s", p->stages, what);
        app_progress_update(&p->bar, 0.0, 0.0, p->what);
    } else {
        snprintf(p->what, sizeof p->what, "%s %u/%u", what, done, total);
        app_progress_update(&p->bar, done, total, p->what);
    }
}

/* A library error as the program's (app_fail prints it). */
static int app__fail_api(const softgi_error *se)
{
    pf_error e;
    e.code = (pf_result)se->code;
    snprintf(e.message, sizeof e.message, "%s", se->message);
    return app_fail(&e);
}

/* The frame: from the scene to the linear image in rgb (malloc'ed,
 * width x height x 3), on `ctx`. Returns the exit status (0: rendered). */
static int app__render_frame(const pf_options *o, softgi_context *ctx, app__render_progress *prog, float **rgb)
{
    softgi_error se;
    if (softgi_load_scene(ctx, o->scene_path, &se) != SOFTGI_OK) return app__fail_api(&se);
    softgi_info info;
    softgi_get_info(ctx, &info, NULL);
    if (info.warnings[0] && !o->quiet) fprintf(stderr, "softgi: warnings:\n%s", info.warnings);
    /* --camera and --light replace the scene's (the automatic light moves to
     * the given camera); then the notes of what is still automatic */
    if (o->has_camera) {
        const softgi_camera cam = {{o->camera_eye.x, o->camera_eye.y, o->camera_eye.z},
                                   {o->camera_target.x, o->camera_target.y, o->camera_target.z},
                                   o->camera_fovy_deg};
        if (softgi_set_camera(ctx, &cam, &se) != SOFTGI_OK) return app__fail_api(&se);
    }
    if (o->light_count && softgi_internal_set_scene_lights(ctx, o->lights, o->light_count, &se) != SOFTGI_OK)
        return app__fail_api(&se);
    /* --time: posed after the camera and lights, which (automatic or not)
     * are placed on the static pose, as app_scene_load does for reference */
    if (o->time_set && softgi_set_time(ctx, o->time, o->animation, &se) != SOFTGI_OK) return app__fail_api(&se);
    const softgi_internal_notes *n = softgi_internal_notes_get(ctx);
    const char *name = o->scene_path ? o->scene_path : "the scene";
    if (n->auto_camera) app_note_camera(o, name, &n->camera, n->camera_spec);
    if (n->auto_light) app_note_light(o, name, n->light_spec, n->light_median);

    const uint32_t frames = o->frames ? o->frames : 1;
    if (frames > 1 && !o->refine_set) { /* the viewer's progressive refinement */
        uint32_t slices = app_refine_slices(o->method, o->visibility_ism, o->visibility_raytrace, o->vpls, 0), got = 0;
        if (softgi_internal_refine(ctx, o->direct_only ? 0 : slices, &got, &se) != SOFTGI_OK) return app__fail_api(&se);
        if (!o->quiet && !o->direct_only) {
            char cyc[64] = " (no VPL cycling)";
            if (got) snprintf(cyc, sizeof cyc, ", VPL cycling over %u slices", got);
            fprintf(stderr, "softgi: %u frames of the still view: temporal accumulation over %u frames%s, temporal "
                            "anti-aliasing over %u (docs/view.md)\n",
                    frames, API_REFINE_TEMPORAL, cyc, API_REFINE_TAA);
        }
    }
    const uint32_t w = info.width, h = info.height;
    if (!(*rgb = malloc((size_t)w * h * 3 * sizeof **rgb))) {
        pf_error e;
        pf_error_set(&e, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%u image", w, h);
        return app_fail(&e);
    }
    app_progress_begin(&prog->bar, "render", o->quiet); /* the clock from the frame on */
    softgi_target target = {.rgb = *rgb};
    softgi_result r = SOFTGI_OK;
    for (uint32_t k = 0; k < frames && r == SOFTGI_OK; k++) r = softgi_render(ctx, &target, &se); /* the last stays */
    app_progress_end(&prog->bar);
    return r == SOFTGI_OK ? 0 : app__fail_api(&se);
}

int app_render(const pf_options *o)
{
    pf_error err;
    /* -o / --hdr: usage errors before any work (the default name is always valid) */
    pf_imageio_outputs out;
    pf_result r = app__check_outputs(o, "out/scene.png", &out, &err);
    if (r != PF_OK) return app_fail(&err);
    char stem[256], def[4096];
    app_stem(o, stem, sizeof stem);
    snprintf(def, sizeof def, "out/%s.png", stem);
    if ((r = app__check_outputs(o, def, &out, &err)) != PF_OK) return app_fail(&err);

    softgi_desc d;
    if ((r = app_desc(o, o->width, o->height, &d, &err)) != PF_OK) return app_fail(&err);
    app__render_progress prog = {.stages = 0};
    app_progress_begin(&prog.bar, "render", o->quiet); /* whether a bar will be drawn */
    if (prog.bar.on) d.progress = app__render_progress_fn, d.progress_user = &prog;
    softgi_error se;
    softgi_context *ctx = softgi_create(&d, &se);
    if (!ctx) return app__fail_api(&se);
    softgi_internal_warn(ctx, 1);
    float *rgb = NULL;
    int status = app__render_frame(o, ctx, &prog, &rgb);
    if (status) {
        free(rgb);
        softgi_destroy(ctx);
        return status;
    }
    softgi_info info;
    softgi_get_info(ctx, &info, NULL);
    const uint32_t width = info.width, height = info.height;
    pf_stage_times t;
    memset(&t, 0, sizeof t);
    softgi_timing timing[PF_MAX_STAGES];
    uint32_t nt = softgi_get_timings(ctx, timing, PF_MAX_STAGES);
    for (uint32_t i = 0; i < nt && i < PF_MAX_STAGES; i++) pf_stage_add(&t, timing[i].name, timing[i].ms);

    /* Output */
    double t0 = pf_time_now();
    const float exposure = app_exposure(o, rgb, width, height); /* the PNG's; the linear image is as rendered */
    r = pf_imageio_outputs_write(&out, rgb, width, height, exposure, &err);
    if (r == PF_OK && o->dump_dir) {
        /* the views `softgi view` shows at this exposure */
        const softgi_dump_format fmt = (softgi_dump_format)app__dump_format(o);
        if (softgi_dump_stages(ctx, o->dump_dir, exposure, fmt, &se) != SOFTGI_OK) {
            r = (pf_result)se.code;
            err.code = r;
            snprintf(err.message, sizeof err.message, "%s", se.message);
        }
    }
    pf_stage_add(&t, o->dump_dir ? "write images + dump" : "write images", (pf_time_now() - t0) * 1e3);
    if (r != PF_OK) status = app_fail(&err);
    else {
        if (!o->quiet) {
            printf("softgi render: %s, %u triangles, %u lights, %ux%u, %u threads, isa %s, %s\n", stem,
                   info.triangles, info.lights, width, height, info.threads, info.isa,
                   o->raytrace ? "ray-traced G-buffer" : "rasterized G-buffer");
            if (info.visibility)
                printf("indirect: %s, %u VPLs (%u maps rendered), %ux%u tiles, clamp b = %g, visibility %s\n",
                       info.method, info.vpls, info.maps_rendered, info.tiles_n, info.tiles_m,
                       (double)info.clamp_b, info.visibility);
            if (o->time_set)
                printf("animation: %s%s%s at %g s (%u in the file)\n", o->animation ? "'" : "",
                       o->animation ? o->animation : "every animation", o->animation ? "'" : "", (double)o->time,
                       info.animations);
            if (info.aa_samples > 1)
                printf("anti-aliasing: %u jittered samples per pixel, averaged (the per-sample stages' times are "
                       "their sums)\n",
                       info.aa_samples);
            pf_stage_print(&t, stdout);
            if (out.png[0]) printf("wrote %s and %s\n", out.png, out.linear);
            else printf("wrote %s\n", out.linear);
            fflush(stdout); /* before the hint on stderr */
        }
        app_hint_dark(o, rgb, width, height, exposure);
        if (o->print_hash)
            printf("hash %016llx (isa %s)\n", (unsigned long long)softgi_image_hash(rgb, width, height, 0), info.isa);
    }
    free(rgb);
    softgi_destroy(ctx);
    return status;
}
