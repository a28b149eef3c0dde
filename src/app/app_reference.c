/* app_reference: `softgi reference`, the path-traced reference
 * image (gi_reference.h: estimator, bounces, random numbers).
 *
 * load scene -> apply --camera/--light overrides (exactly as `softgi render`,
 * app_render.c) -> build the Embree scene -> path trace (--spp, --bounces,
 * --indirect-only, --direct-only) with a progress bar -> write the PNG and
 * the linear image (default out/<scene>-reference.png and .pfm), printing
 * the time of every step and, with --hash, the hash of the linear image. -o
 * and --hdr follow render's rules (app_render.c, pf_imageio_outputs_resolve:
 * .png, .exr or .pfm by extension): checked before the path tracing starts,
 * both files complete or neither replaced.
 *
 * The progress bar (app_progress.h) goes to stderr, only when stderr is a
 * terminal and not --quiet; gi_reference calls it on this thread only
 * (after every row this thread finishes), so it needs no locking. */
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "app_progress.h"
#include "gi_reference.h"
#include "gi_metrics.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"

/* gi_reference's progress callback: rows done of all rows. */
static void app__progress_rows(void *user, uint32_t done, uint32_t total)
{
    app_progress_update(user, done, total, NULL);
}

/* ---------------------------------------------------------------- command */

int app_reference(const pf_options *o)
{
    pf_error err;
    pf_stage_times t;
    memset(&t, 0, sizeof t);
    if (o->bounces > GI_REFERENCE_MAX_BOUNCES) {
        pf_error_set(&err, PF_ERR_ARGUMENT, "--bounces: %u is too many (at most %u)", o->bounces,
                     GI_REFERENCE_MAX_BOUNCES);
        return app_fail(&err);
    }

    /* -o / --hdr: usage errors before any work */
    pf_imageio_outputs out;
    pf_result r = pf_imageio_outputs_resolve(&out, o->out_path, o->hdr_path, "out/scene-reference.png", &err);
    if (r != PF_OK) return app_fail(&err);

    /* Scene, Embree, jobs (as app_render.c), the image */
    app_setup su;
    r = app_setup_begin(o, &su, &t, &err);
    if (r != PF_OK) return app_fail(&err);
    uint32_t width = su.width, height = su.height;
    float *image = NULL;
    r = app_budget_check(o, &su.scene, width, height, 0, 0, &err);
    if (r == PF_OK && !(image = malloc((size_t)width * height * 3 * sizeof(float))))
        r = pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "no memory for a %ux%u image", width, height);

    /* Path trace */
    gi_reference_options ro;
    app_reference_options(o, &ro);
    float *noise = r == PF_OK ? malloc((size_t)width * height * sizeof(float)) : NULL;
    ro.noise_out = noise; /* NULL (no estimate) if short of memory */
    app_progress prog;
    app_progress_begin(&prog, "reference", o->quiet);
    if (prog.on) {
        ro.progress = app__progress_rows;
        ro.progress_user = &prog;
    }
    if (r == PF_OK) {
        double t0 = pf_time_now();
        r = gi_reference_render(image, &su.scene, su.rt, su.jobs, &su.camera, width, height, &ro, &err);
        pf_stage_add(&t, "path trace", (pf_time_now() - t0) * 1e3);
    }
    app_progress_end(&prog);

    /* Output */
    float exposure = o->exposure;
    if (r == PF_OK) {
        double t0 = pf_time_now();
        char def[4096];
        snprintf(def, sizeof def, "out/%s-reference.png", su.stem);
        r = pf_imageio_outputs_resolve(&out, o->out_path, o->hdr_path, def, &err);
        if (r == PF_OK) exposure = app_exposure(o, image, width, height);
        if (r == PF_OK) r = pf_imageio_outputs_write(&out, image, width, height, exposure, &err);
        pf_stage_add(&t, "write images", (pf_time_now() - t0) * 1e3);
    }
    int status = 0;
    if (r != PF_OK) status = app_fail(&err);
    else {
        if (!o->quiet) {
            uint32_t b = ro.direct_only ? 0u : ro.bounces;
            printf("softgi reference: %s, %u triangles, %u lights, %ux%u, %u spp, %u bounces%s, %u threads, isa %s\n",
                   su.stem, su.scene.tri_count, su.scene.light_count, width, height, ro.spp, b,
                   ro.indirect_only ? " (indirect only)" : (ro.direct_only ? " (direct only)" : ""), su.threads,
                   pf_isa_name(su.isa));
            pf_stage_print(&t, stdout);
            if (out.png[0]) printf("wrote %s and %s\n", out.png, out.linear);
            else printf("wrote %s\n", out.linear);
            if (noise)
                printf("noise: %.4f mean relative standard error per pixel (luminance > %g; it falls as 1/sqrt(spp) "
                       "only where the variance is finite)\n",
                       gi_reference_noise(noise, image, (size_t)width * height, GI_METRICS_MRE_FLOOR),
                       (double)GI_METRICS_MRE_FLOOR);
            fflush(stdout); /* before the hint on stderr */
        }
        app_hint_dark(o, image, width, height, exposure);
        if (o->print_hash)
            printf("hash %016llx (isa %s)\n", (unsigned long long)pf_imageio_hash(image, (uint64_t)width * height * 3),
                   pf_isa_name(su.isa));
    }
    free(image);
    free(noise);
    app_setup_end(&su);
    return status;
}
