/* app_render: `softgi render` (see pf_cli.h for the options).
 *
 * load scene -> apply --camera/--light overrides -> build the Embree scene ->
 * render the frame (gi_frame_render_raytraced) -> write PNG + PFM, printing
 * the time of every step. --pipeline on|off (default off) is accepted: it
 * changes only multi-frame work (one frame renders bit-identically either
 * way, since frame 0 runs the VPL update in place; gi_indirect.h). */
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "gi_frame.h"
#include "gi_view.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"

int app_render(const pf_options *o)
{
    pf_error err;
    pf_stage_times t;
    memset(&t, 0, sizeof t);
    uint32_t width = o->width ? o->width : 640, height = o->height ? o->height : 480;
    uint32_t threads = o->threads ? o->threads : pf_jobs_core_count();
    pf_isa isa;
    if (pf_isa_resolve(o->isa, &isa, &err) != PF_OK) return app_fail(&err);

    /* Scene */
    double t0 = pf_time_now();
    pf_scene scene;
    pf_camera camera;
    char stem[256];
    pf_result r = app_scene_load(o, &scene, &camera, stem, sizeof stem, &err);
    if (r != PF_OK) return app_fail(&err);
    pf_stage_add(&t, "load scene", (pf_time_now() - t0) * 1e3);

    /* Embree + jobs */
    t0 = pf_time_now();
    pf_rt *rt;
    if ((r = pf_rt_create(&rt, &scene, isa, threads, &err)) != PF_OK) {
        pf_scene_free(&scene);
        return app_fail(&err);
    }
    pf_stage_add(&t, "embree build", (pf_time_now() - t0) * 1e3);
    pf_jobs *jobs = pf_jobs_create(threads);
    rs_context *raster = NULL;
    gi_frame frame;
    if (!jobs) r = pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", threads);
    if (r == PF_OK && !o->raytrace) {
        t0 = pf_time_now();
        r = rs_context_create(&raster, &scene, jobs, rs_simd_for_isa(isa), &err);
        pf_stage_add(&t, "raster setup", (pf_time_now() - t0) * 1e3);
    }
    if (r == PF_OK) r = app_frame_init(o, &frame, &scene, rt, raster, jobs, &camera, width, height, 1, &err);
    if (r != PF_OK) {
        rs_context_destroy(raster);
        pf_jobs_destroy(jobs);
        pf_rt_destroy(rt);
        pf_scene_free(&scene);
        return app_fail(&err);
    }

    /* Frame */
    if (o->raytrace) gi_frame_render_raytraced(&frame);
    else gi_frame_render_raster(&frame);
    for (uint32_t i = 0; i < frame.times.count; i++) pf_stage_add(&t, frame.times.name[i], frame.times.ms[i]);

    /* Output */
    t0 = pf_time_now();
    char png[4096], pfm[4096], def[4096];
    snprintf(def, sizeof def, "out/%s.png", stem);
    r = app_write_image(o, def, frame.final, width, height, png, pfm, &err);
    if (r == PF_OK && o->dump_dir) {
        gi_view_settings vs = {o->exposure, 0}; /* the views `softgi view` shows at this exposure */
        r = gi_view_dump(&frame, o->dump_dir, &vs, &err);
    }
    pf_stage_add(&t, "write png + pfm", (pf_time_now() - t0) * 1e3);
    int status = 0;
    if (r != PF_OK) status = app_fail(&err);
    else {
        if (!o->quiet) {
            printf("softgi render: %s, %u triangles, %u lights, %ux%u, %u threads, isa %s, %s\n", stem,
                   scene.tri_count, scene.light_count, width, height, threads, pf_isa_name(isa),
                   o->raytrace ? "ray-traced G-buffer" : "rasterized G-buffer");
            if (frame.indirect)
                printf("indirect: %s, %u VPLs (%u maps rendered), %ux%u tiles, clamp b = %g, visibility %s\n",
                       frame.ind.opt.method->name, frame.ind.vpls.count, frame.ind.maps_rendered, frame.ind.n,
                       frame.ind.m, (double)frame.ind.b,
                       frame.ind.ism    ? "imperfect shadow maps"
                       : frame.ind.para ? "paraboloid maps"
                                        : "Embree rays");
            pf_stage_print(&t, stdout);
            printf("wrote %s and %s\n", png, pfm);
        }
        if (o->print_hash)
            printf("hash %016llx\n",
                   (unsigned long long)pf_imageio_hash(frame.final, (uint64_t)width * height * 3));
    }
    gi_frame_free(&frame);
    rs_context_destroy(raster);
    pf_jobs_destroy(jobs);
    pf_rt_destroy(rt);
    pf_scene_free(&scene);
    return status;
}
