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

    /* Scene, Embree, jobs */
    app_setup su;
    pf_result r = app_setup_begin(o, &su, &t, &err);
    if (r != PF_OK) return app_fail(&err);
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
    if (o->raytrace) gi_frame_render_raytraced(&frame);
    else gi_frame_render_raster(&frame);
    for (uint32_t i = 0; i < frame.times.count; i++) pf_stage_add(&t, frame.times.name[i], frame.times.ms[i]);

    /* Output */
    double t0 = pf_time_now();
    char png[4096], pfm[4096], def[4096];
    snprintf(def, sizeof def, "out/%s.png", su.stem);
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
            pf_stage_print(&t, stdout);
            printf("wrote %s and %s\n", png, pfm);
        }
        if (o->print_hash)
            printf("hash %016llx\n",
                   (unsigned long long)pf_imageio_hash(frame.final, (uint64_t)width * height * 3));
    }
    gi_frame_free(&frame);
    rs_context_destroy(raster);
    app_setup_end(&su);
    return status;
}
