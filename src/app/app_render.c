/* app_render: `softgi render` (see pf_cli.h for the options).
 *
 * load scene -> apply --camera/--light overrides -> build the Embree scene ->
 * render the frame (gi_frame_render_raster, or gi_frame_render_raytraced
 * with --raytrace) -> write the images, printing the time of every step.
 *
 * Outputs (pf_imageio.h, by extension): -o NAME.png writes the PNG and the
 * linear image NAME.pfm (or --hdr FILE.exr / FILE.pfm); -o NAME.exr or
 * NAME.pfm writes only that linear image, at exactly that name; any other
 * extension, and two outputs naming the same file (with the --dump-stages
 * files too), are refused before anything is rendered (exit 2). Every file
 * is written to a temporary file and renamed over its target when
 * complete; an image with a NaN, infinite or negative value is not written
 * (exit 1). --dump-stages DIR writes the stages (gi_dump.h) as pictures,
 * float OpenEXR data or both (--dump-format png|exr|both, default png).
 * --exposure auto picks the PNG's (and the pictures') exposure from the
 * image (app_exposure); a nearly black image gets a one-line hint.
 *
 * A frame that takes long (large --vpls: every VPL's paraboloid map is
 * rendered in the first frame) shows, on a terminal and without -q, the
 * time so far and the last stage finished (app_progress.h; through
 * pf_stage_hook, so the frame knows nothing of it).
 *
 * --aa N (gi_aa.h): N jittered samples per pixel, averaged in linear
 * radiance before anything is written; --aa 1 (the default) is the
 * unjittered frame, bit for bit.
 *
 * --pipeline on|off (default off) is accepted: it
 * changes only multi-frame work (one frame renders bit-identically either
 * way, since frame 0 runs the VPL update in place; gi_indirect.h). */
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "app_progress.h"
#include "gi_dump.h"
#include "gi_frame.h"
#include "gi_view.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"

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

/* pf_stage_hook: a stage of the frame has finished. */
typedef struct app__render_progress {
    app_progress bar;
    uint32_t stages;
    char what[96];
} app__render_progress;

static void app__render_stage(void *user, const char *name, double ms)
{
    (void)ms;
    app__render_progress *p = user;
    p->stages++;
    snprintf(p->what, sizeof p->what, "frame: %u stages done, the last %s", p->stages, name);
    app_progress_update(&p->bar, 0.0, 0.0, p->what);
}

/* gi_frame_progress_fn: a long stage's progress (the VPL maps). */
static void app__render_work(void *user, const char *what, uint32_t done, uint32_t total)
{
    app__render_progress *p = user;
    snprintf(p->what, sizeof p->what, "%s %u/%u", what, done, total);
    app_progress_update(&p->bar, done, total, p->what);
}

int app_render(const pf_options *o)
{
    pf_error err;
    pf_stage_times t;
    memset(&t, 0, sizeof t);
    /* -o / --hdr: usage errors before any work (the default name is always valid) */
    pf_imageio_outputs out;
    pf_result r = app__check_outputs(o, "out/scene.png", &out, &err);
    if (r != PF_OK) return app_fail(&err);

    /* Scene, Embree, jobs */
    app_setup su;
    r = app_setup_begin(o, &su, &t, &err);
    if (r != PF_OK) return app_fail(&err);
    char def[4096];
    snprintf(def, sizeof def, "out/%s.png", su.stem);
    if ((r = app__check_outputs(o, def, &out, &err)) != PF_OK) {
        app_setup_end(&su);
        return app_fail(&err);
    }
    const pf_scene *scene = &su.scene;
    uint32_t width = su.width, height = su.height;
    rs_context *raster = NULL;
    gi_frame frame;
    if (!o->raytrace) {
        double t0 = pf_time_now();
        r = rs_context_create(&raster, scene, su.jobs, rs_simd_for_isa(su.isa), &err);
        pf_stage_add(&t, "raster setup", (pf_time_now() - t0) * 1e3);
    }
    if (r == PF_OK) r = app_frame_init(o, &frame, scene, su.rt, raster, su.jobs, &su.camera, width, height, 1, &err);
    if (r != PF_OK) {
        rs_context_destroy(raster);
        app_setup_end(&su);
        return app_fail(&err);
    }

    /* Frame */
    app__render_progress prog = {.stages = 0};
    app_progress_begin(&prog.bar, "render", o->quiet);
    pf_stage_hook hook = pf_stage_hook_set((pf_stage_hook){prog.bar.on ? app__render_stage : NULL, &prog});
    if (prog.bar.on) frame.progress = app__render_work, frame.progress_user = &prog;
    if (o->raytrace) gi_frame_render_raytraced(&frame);
    else gi_frame_render_raster(&frame);
    pf_stage_hook_set(hook);
    app_progress_end(&prog.bar);
    if (frame.status != PF_OK) {
        err = frame.error;
        gi_frame_free(&frame);
        rs_context_destroy(raster);
        app_setup_end(&su);
        return app_fail(&err);
    }
    for (uint32_t i = 0; i < frame.times.count; i++) pf_stage_add(&t, frame.times.name[i], frame.times.ms[i]);

    /* Output */
    double t0 = pf_time_now();
    const float exposure = app_exposure(o, frame.final, width, height); /* the PNG's; the linear image is as rendered */
    r = pf_imageio_outputs_write(&out, frame.final, width, height, exposure, &err);
    if (r == PF_OK && o->dump_dir) {
        gi_view_settings vs = {exposure, 0}; /* the views `softgi view` shows at this exposure */
        r = gi_dump_stages(&frame, o->dump_dir, &vs, app__dump_format(o), &err);
    }
    pf_stage_add(&t, o->dump_dir ? "write images + dump" : "write images", (pf_time_now() - t0) * 1e3);
    int status = 0;
    if (r != PF_OK) status = app_fail(&err);
    else {
        if (!o->quiet) {
            printf("softgi render: %s, %u triangles, %u lights, %ux%u, %u threads, isa %s, %s\n", su.stem,
                   scene->tri_count, scene->light_count, width, height, su.threads, pf_isa_name(su.isa),
                   o->raytrace ? "ray-traced G-buffer" : "rasterized G-buffer");
            if (frame.indirect)
                printf("indirect: %s, %u VPLs (%u maps rendered), %ux%u tiles, clamp b = %g, visibility %s\n",
                       frame.ind.opt.method->name, frame.ind.vpls.count, frame.ind.maps_rendered, frame.ind.n,
                       frame.ind.m, (double)frame.ind.b,
                       frame.ind.ism    ? "imperfect shadow maps"
                       : frame.ind.para ? "paraboloid maps"
                                        : "Embree rays");
            if (frame.aa.samples > 1)
                printf("anti-aliasing: %u jittered samples per pixel, averaged (the per-sample stages' times are "
                       "their sums)\n",
                       frame.aa.samples);
            pf_stage_print(&t, stdout);
            if (out.png[0]) printf("wrote %s and %s\n", out.png, out.linear);
            else printf("wrote %s\n", out.linear);
            fflush(stdout); /* before the hint on stderr */
        }
        app_hint_dark(o, frame.final, width, height, exposure);
        if (o->print_hash)
            printf("hash %016llx (isa %s)\n",
                   (unsigned long long)pf_imageio_hash(frame.final, (uint64_t)width * height * 3),
                   pf_isa_name(su.isa));
    }
    gi_frame_free(&frame);
    rs_context_destroy(raster);
    app_setup_end(&su);
    return status;
}
