/* app_sequence: `softgi sequence FILE.seq.json [render options]`.
 *
 * Renders the frames of a sequence (pf_sequence.h: scene, camera and light
 * keyframes) to a folder, keeping one gi_frame alive across frames so the
 * VPL method keeps its state (Laine 2007 Sec. 3: VPLs persist and only new
 * or moved ones get new paraboloid maps):
 *
 *   load sequence -> load scene (app_scene_load, with the sequence's scene,
 *   first camera and replacing lights) -> check every frame's camera and
 *   lights -> build Embree, jobs, rasterizer and the frame once ->
 *   per frame: set frame.camera and the scene's lights (the frame re-renders
 *   the shadow maps of the lights that changed), render, write
 *     DIR/frame_NNNN.pfm        linear RGB
 *     DIR/frame_NNNN.png        tone mapped (--exposure), for viewing
 *     DIR/frame_NNNN.view       the camera (gi_metrics.h)
 *     DIR/frame_NNNN.depth.pfm  the G-buffer's view depth
 *   and print its time and how many VPLs moved.
 *
 * The folder is -o DIR (anywhere: the user's choice), else the file's
 * "output" under out/, else out/<name>; a folder a sequence file chooses is
 * created without following symbolic links and must resolve inside out/
 * (pf_sequence.h, "Where frames go"). softgi never deletes a file: frame
 * files of an older, longer run stay, and DIR/frames.txt (the manifest,
 * pf_sequence.h) tells `softgi compare` how many frames this run wrote; it
 * says "running" from before frame 0 until every file is written, so a
 * failed or interrupted run is never read as a finished one. Every file is
 * written to a temporary file and renamed into place when complete
 * (pf_imageio.h); a frame with a NaN, infinite or negative value stops the
 * run (exit 1). DIR/track.txt lists the file's "track" pixels ("X,Y" per
 * line, for `softgi compare --track`; scaled when --size differs from the
 * file's "size"); it is written empty when the file has none (compare then
 * tracks its default grid), replacing any older list. --hash prints one FNV-1a
 * hash over all frames (the per-frame hashes of the linear images, hashed in
 * frame order).
 *
 * The CLI's render options apply (--size overrides the file's size;
 * --camera/--light act as in render when the file has no camera keys / no
 * full lights, and are refused when it has: the file would override them
 * silently otherwise). Without camera keys, a camera in the scene or
 * --camera, the camera is render's automatic one (pf_defaults.h), and so
 * is the light. --exposure auto is picked on frame 0 and held. Instant Radiosity regenerates every VPL when a light
 * moves (the expected baseline); a moving camera alone moves none.
 *
 * "animation" (pf_sequence.h): the scene's glTF animations are posed at
 * each frame's time (pf_anim_pose) before it renders. Embree's scene keeps
 * what an animation can move in instances of its own (pf_rt_create_dynamic,
 * for every scene with animations, as softgi render builds it), and a
 * frame whose pose moves anything updates it (pf_rt_update, REBUILD: the
 * moved primitives' BVHs rebuilt, a fresh build's bytes), and the
 * rasterizer and the frame in place (rs_context_update,
 * gi_frame_geometry_moved: shadow, VPL and emitter maps redrawn only where
 * the moved bounds can change them; gi_motion.h): the VPL method keeps its
 * state and is told what moved, and the --temporal / --taa / pipeline
 * histories go on, as under a moving light (api_geometry_moved). The first
 * frame rendered is posed before anything is built. Updating is
 * deterministic, so --frames A:B still gives a full run's bytes (the frames
 * before A are rendered to carry the state). The pose's time is in the mean
 * table as "pose (+ update when
 * moved)", and each frame's line says how many objects moved. A pose that
 * would put geometry beyond PF_SCENE_MAX_COORD stops the run at that frame
 * (exit 1, the manifest left "running").
 *
 * --aa N renders every frame with N jittered samples per pixel, --taa N
 * accumulates the frames' jittered samples with reprojection (temporal
 * anti-aliasing, its history kept from frame to frame like the VPL
 * method's state: gi_aa.h); neither with --reference, whose path tracer
 * box-filters every pixel already.
 *
 * --pipeline on (default off): each frame's VPL update runs as a job
 * alongside the frame and its set is used one frame later (frame 0 is
 * unchanged; frame N >= 1 shades with frame N-1's set; gi_indirect.h,
 * "Pipelining"). The moved count printed is that of the set the frame
 * shaded with.
 *
 * --frames A:B (offline work spread over machines by a
 * batch scheduler): only frames A..B-1 are written (zero-based as the
 * file names, B excluded; "A:" to the end), under the names and with the
 * bytes a full run gives them, so the folders of runs 0:10, 10:20, ...
 * merged by file name equal a full run's folder. Every run writes the same
 * track.txt and the same finished manifest (frames N, complete; "running"
 * while it works), and `softgi compare` checks that every listed frame is
 * there, so a merge that lacks a range is refused, not read short. What a
 * frame's bytes depend on decides what a range costs:
 * - the frame keeps state from frame to frame: the VPL method's (and with
 *   --pipeline the previous frame's set), and even without indirect light
 *   the area lights' emitter points (test_frames found it), so frames
 *   0..A-1 are rendered, not written, to bring that state to frame A; only
 *   the writing of those frames is saved;
 * - --reference frames depend only on their camera and lights (the path
 *   tracer's random numbers are seeded by pixel and sample, not by frame
 *   order): frames before A are skipped;
 * - --exposure auto is picked on frame 0 and held, so a range without
 *   frame 0 renders frame 0 first for it (not written).
 * --hash then hashes the range's frames.
 *
 * Progress (app_progress.h): on a terminal and without -q, one bar over
 * the frames to render, advanced within a frame by its stages (through
 * pf_stage_hook; the previous frame's stage count is the expected one) or,
 * for --reference, by the path tracer's rows; the per-frame lines print
 * above it. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "app_progress.h"
#include "gi_frame.h"
#include "gi_metrics.h"
#include "gi_reference.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_sequence.h"
#include "pf_timer.h"
#include "api_setup.h"
#include "pf_anim.h"

static int app__light_equal(const pf_light *a, const pf_light *b)
{
    return a->type == b->type && !memcmp(&a->position, &b->position, sizeof a->position) &&
           !memcmp(&a->direction, &b->direction, sizeof a->direction) &&
           !memcmp(&a->color, &b->color, sizeof a->color) && a->intensity == b->intensity &&
           a->inner_cone == b->inner_cone && a->outer_cone == b->outer_cone;
}

/* The scene's lights at `frame` into dst[0..scene->light_count). `base` is
 * the lights as loaded (what entries naming a scene light animate). */
static pf_result app__lights_at(const pf_sequence *seq, uint32_t frame, const pf_light *base, uint32_t base_count,
                                pf_light *dst, pf_error *err)
{
    if (seq->lights_replace) {
        for (uint32_t i = 0; i < seq->light_count; i++) {
            pf_result r = pf_sequence_light_at(seq, i, frame, NULL, &dst[i], err);
            if (r != PF_OK) return r;
        }
        return PF_OK;
    }
    memcpy(dst, base, sizeof *dst * base_count);
    for (uint32_t i = 0; i < seq->light_count; i++) {
        int32_t l = seq->lights[i].scene_light;
        if ((uint32_t)l >= base_count)
            return pf_error_set(err, PF_ERR_INDEX_RANGE, "%s: lights[%u]: the scene has no light %d (it has %u)",
                                seq->file, i, l, base_count);
        pf_result r = pf_sequence_light_at(seq, i, frame, &base[l], &dst[l], err);
        if (r != PF_OK) {
            char m[sizeof err->message];
            snprintf(m, sizeof m, "%s", err->message);
            return pf_error_set(err, r, "%s: %s", seq->file, m);
        }
    }
    return PF_OK;
}

/* DIR/frame_NNNN<suffix> */
static void app__frame_path(char *dst, size_t size, const char *dir, uint32_t frame, const char *suffix)
{
    snprintf(dst, size, "%s/frame_%04u%s", dir, frame, suffix);
}

static uint64_t app__fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

/* The bar over the frames to render (the top comment). */
typedef struct app__seq_progress {
    app_progress bar;
    uint32_t done, total;      /* frames rendered, to render */
    uint32_t frame;            /* the frame being rendered */
    uint32_t stages, expected; /* its stages done so far; the last frame's count */
    char what[96];
} app__seq_progress;

static void app__seq_progress_show(app__seq_progress *p, double frac, const char *step)
{
    if (frac > 0.99) frac = 0.99;
    snprintf(p->what, sizeof p->what, "frame %u (%u of %u)%s%s", p->frame, p->done + 1, p->total, step ? ": " : "",
             step ? step : "");
    app_progress_update(&p->bar, p->done + frac, p->total, p->what);
}

/* pf_stage_hook: a stage of the frame being rendered has finished. */
static void app__seq_progress_stage(void *user, const char *name, double ms)
{
    (void)ms;
    app__seq_progress *p = user;
    p->stages++;
    app__seq_progress_show(p, p->expected ? (double)p->stages / p->expected : 0.0, name);
}

/* gi_reference's progress: rows of the frame's reference. */
static void app__seq_progress_rows(void *user, uint32_t done, uint32_t total)
{
    app__seq_progress_show(user, total ? (double)done / total : 0.0, "path tracing");
}

/* Everything the run owns, freed by app__cleanup. */
typedef struct app__seq_run {
    pf_sequence seq;
    pf_scene scene;
    int scene_loaded;
    pf_light *base_lights, *lights;
    pf_rt *rt;
    pf_jobs *jobs;
    rs_context *raster;
    gi_frame frame;
    int frame_ready;
    /* --reference --track-spp: the pixels `softgi compare` will track */
    uint32_t track_xy[2 * PF_SEQUENCE_MAX_TRACK];
    uint32_t track_count;
    app__seq_progress progress;
    /* "animation": the scene's animations over the frames */
    pf_anim anim;            /* kept for every animated scene (Embree's split, pf_rt.h) */
    pf_anim_moved *moved;    /* anim.prim_count: the last pose's report (pf_rt_update) */
    int32_t clip;            /* the animation played (PF_ANIM_ALL: every one) */
    double t_start, t_end;   /* its time at frame 0 and at the last frame */
} app__seq_run;

static void app__cleanup(app__seq_run *s)
{
    if (s->frame_ready) gi_frame_free(&s->frame);
    rs_context_destroy(s->raster);
    pf_jobs_destroy(s->jobs);
    if (s->rt) pf_rt_destroy(s->rt);
    if (s->scene_loaded) pf_scene_free(&s->scene);
    free(s->base_lights);
    free(s->lights);
    pf_sequence_free(&s->seq);
    pf_anim_free(&s->anim);
    free(s->moved);
}

/* The file's "animation" against the loaded scene: the animation it plays
 * and the time range mapped onto the frames (default [0, its last key]). */
static pf_result app__seq_animation(app__seq_run *s, pf_error *err)
{
    const pf_sequence *seq = &s->seq;
    pf_result r;
    s->clip = PF_ANIM_ALL;
    if (seq->anim_name[0]) r = pf_anim_find(&s->anim, seq->anim_name, 0, &s->clip, err);
    else if (seq->anim_index >= 0) r = pf_anim_find(&s->anim, NULL, seq->anim_index, &s->clip, err);
    else r = s->anim.clip_count ? PF_OK : pf_anim_find(&s->anim, NULL, 0, &s->clip, err); /* none: the message */
    if (r != PF_OK) {
        char m[sizeof err->message];
        snprintf(m, sizeof m, "%s", err->message);
        return pf_error_set(err, r, "%s: animation: %s: %s", seq->file,
                            seq->scene_embedded ? PF_SEQUENCE_EMBEDDED_CORNELL : seq->scene_path, m);
    }
    s->t_start = seq->anim_time_set ? seq->anim_start : 0.0;
    s->t_end = seq->anim_time_set ? seq->anim_end : pf_anim_end(&s->anim, s->clip);
    if (!(s->moved = calloc(s->anim.prim_count ? s->anim.prim_count : 1, sizeof *s->moved)))
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the pose's report");
    return PF_OK;
}

/* The scene posed at frame f's animation time (*moved: how many instanced
 * primitives moved), the message naming the file and the frame. */
static pf_result app__seq_pose(app__seq_run *s, uint32_t f, uint32_t *moved, pf_error *err)
{
    const double t = pf_sequence_time_at(&s->seq, f, s->t_start, s->t_end);
    pf_result r = pf_anim_pose(&s->scene, s->moved, moved, &s->anim, s->clip, t, err);
    if (r != PF_OK) {
        char m[sizeof err->message];
        snprintf(m, sizeof m, "%s", err->message);
        pf_error_set(err, r, "%s: frame %u: %s", s->seq.file, f, m);
    }
    return r;
}

/* --reference: the frame's G-buffer (for the depth file TID reprojects
 * with) and the path-traced image in place of the VPL frame's. */
static pf_result app__render_reference(app__seq_run *s, const pf_options *o, const char *dir, uint32_t frame,
                                        pf_error *err)
{
    gi_frame *fr = &s->frame;
    if (o->raytrace) gi_stage_gbuffer_raytrace(fr);
    else {
        gi_stage_gbuffer_raster(fr);
        gi_stage_gbuffer_resolve(fr);
    }
    gi_reference_options ro;
    app_reference_options(o, &ro);
    fr->times.count = 0;
    double t0 = pf_time_now();
    pf_result r = PF_OK;
    if (o->reuse_frames) {
        /* --reuse-frames: the image the folder already holds (made with
         * the same settings but fewer tracked-pixel samples) */
        char path[4200];
        float *rgb = NULL;
        uint32_t w = 0, h = 0;
        app__frame_path(path, sizeof path, dir, frame, ".pfm");
        r = pf_imageio_read_pfm(path, &rgb, &w, &h, err);
        if (r == PF_OK && (w != fr->width || h != fr->height))
            r = pf_error_set(err, PF_ERR_ARGUMENT, "%s: %ux%u, this sequence renders %ux%u (--reuse-frames)", path, w,
                             h, fr->width, fr->height);
        if (r == PF_OK) memcpy(fr->final, rgb, sizeof(float) * 3 * w * h);
        free(rgb);
    } else {
        if (s->progress.bar.on) {
            ro.progress = app__seq_progress_rows;
            ro.progress_user = &s->progress;
        }
        r = gi_reference_render(fr->final, &s->scene, s->rt, s->jobs, &fr->camera, fr->width, fr->height, &ro, err);
        ro.progress = NULL;
    }
    pf_stage_add(&fr->times, o->reuse_frames ? "reference (reused)" : "reference", (pf_time_now() - t0) * 1e3);
    if (r != PF_OK || o->track_spp <= ro.spp) return r;
    /* The tracked pixels again with more samples: |E| and |E'| are measured
     * there, and a noisy reference would add its own frame-to-frame noise to
     * every method's |E'|. */
    t0 = pf_time_now();
    ro.spp = o->track_spp;
    r = gi_reference_render_pixels(fr->final, &s->scene, s->rt, s->jobs, &fr->camera, fr->width, fr->height,
                                   s->track_xy, s->track_count, &ro, err);
    pf_stage_add(&fr->times, "reference: tracked pixels", (pf_time_now() - t0) * 1e3);
    return r;
}

static int app__fail_run(app__seq_run *s, const pf_error *err)
{
    app_progress_end(&s->progress.bar);
    int st = app_fail(err);
    app__cleanup(s);
    return st;
}

int app_sequence(const pf_options *o)
{
    pf_error err;
    app__seq_run s;
    memset(&s, 0, sizeof s);
    uint32_t threads = o->threads ? o->threads : pf_jobs_core_count();
    pf_isa isa;
    if (pf_isa_resolve(o->isa, &isa, &err) != PF_OK) return app_fail(&err);

    /* Sequence */
    pf_result r = pf_sequence_load(&s.seq, o->scene_path, &err);
    if (r != PF_OK) return app__fail_run(&s, &err);
    const pf_sequence *seq = &s.seq;
    uint32_t width = o->width ? o->width : seq->width ? seq->width : 640;
    uint32_t height = o->height ? o->height : seq->height ? seq->height : 480;
    if (seq->camera.count && o->has_camera)
        r = pf_error_set(&err, PF_ERR_ARGUMENT, "--camera: %s has camera keys; edit the file instead", seq->file);
    if (seq->lights_replace && o->light_count)
        r = pf_error_set(&err, PF_ERR_ARGUMENT, "--light: %s gives its own lights; edit the file instead", seq->file);
    /* --frames A:B: the frames this run writes, [first, end) */
    uint32_t first = 0, end = seq->frames;
    if (r == PF_OK && o->frame_range) {
        first = o->frame_first;
        end = o->frame_end;
        r = pf_cli_check_frame_range("--frames", seq->frames, first, &end, &err);
    }
    /* Tracked pixels are in the file's image size: --size scales them. */
    uint32_t track[PF_SEQUENCE_MAX_TRACK][2];
    for (uint32_t i = 0; i < seq->track_count && r == PF_OK; i++) {
        track[i][0] = seq->width ? (uint32_t)((uint64_t)seq->track[i][0] * width / seq->width) : seq->track[i][0];
        track[i][1] = seq->height ? (uint32_t)((uint64_t)seq->track[i][1] * height / seq->height) : seq->track[i][1];
        if (track[i][0] >= width || track[i][1] >= height)
            r = pf_error_set(&err, PF_ERR_ARGUMENT, "%s: track[%u]: pixel (%u, %u) is outside the %ux%u image",
                             seq->file, i, seq->track[i][0], seq->track[i][1], width, height);
    }
    if (r != PF_OK) return app__fail_run(&s, &err);
    /* the pixels compare tracks: the file's, else compare's default grid */
    if (seq->track_count) {
        for (uint32_t i = 0; i < seq->track_count; i++) {
            s.track_xy[2 * i] = track[i][0];
            s.track_xy[2 * i + 1] = track[i][1];
        }
        s.track_count = seq->track_count;
    } else {
        gi_metrics_pixel grid[GI_METRICS_DEFAULT_TRACKED];
        s.track_count = gi_metrics_track_grid(grid, GI_METRICS_DEFAULT_TRACKED, width, height);
        for (uint32_t i = 0; i < s.track_count; i++) {
            s.track_xy[2 * i] = grid[i].x;
            s.track_xy[2 * i + 1] = grid[i].y;
        }
    }

    /* Scene: the sequence's scene, its first camera and its full lights
     * through the same path as `render`'s --camera and --light. */
    double t_load = pf_time_now();
    pf_options so = *o;
    so.scene_path = seq->scene_embedded ? NULL : seq->scene_path;
    so.width = width; /* the automatic light aims through this image (pf_defaults.h) */
    so.height = height;
    if (seq->camera.count) {
        so.has_camera = 1;
        pf_sequence_camera_at(seq, 0, &so.camera_eye, &so.camera_target, &so.camera_fovy_deg);
    }
    if (seq->lights_replace) {
        so.light_count = seq->light_count; /* <= PF_SEQUENCE_MAX_LIGHTS == PF_CLI_MAX_LIGHTS */
        for (uint32_t i = 0; i < seq->light_count && r == PF_OK; i++)
            r = pf_sequence_light_at(seq, i, 0, NULL, &so.lights[i], &err);
    }
    pf_camera camera;
    char stem[256];
    if (r == PF_OK)
        r = app_scene_load_sequence(&so, seq, &s.scene, &s.anim, &camera, stem, sizeof stem, &err);
    if (r != PF_OK) return app__fail_run(&s, &err);
    s.scene_loaded = 1;
    if (seq->anim_set && (r = app__seq_animation(&s, &err)) != PF_OK) return app__fail_run(&s, &err);
    t_load = pf_time_now() - t_load;

    /* Check every frame before rendering any: cameras and lights. */
    uint32_t nl = s.scene.light_count;
    s.base_lights = malloc(sizeof(pf_light) * (nl ? nl : 1));
    s.lights = malloc(sizeof(pf_light) * (nl ? nl : 1));
    if (!s.base_lights || !s.lights) {
        pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "out of memory");
        return app__fail_run(&s, &err);
    }
    memcpy(s.base_lights, s.scene.lights, sizeof(pf_light) * nl);
    for (uint32_t f = 0; f < seq->frames && r == PF_OK; f++) {
        pf_vec3 eye, target;
        float fovy;
        pf_camera cam;
        if (pf_sequence_camera_at(seq, f, &eye, &target, &fovy) &&
            pf_camera_look_at(&cam, eye, target, pf_radians(fovy), &err) != PF_OK) {
            char m[sizeof err.message];
            snprintf(m, sizeof m, "%s", err.message);
            r = pf_error_set(&err, PF_ERR_PARSE, "%s: frame %u: %s", seq->file, f, m);
        }
        if (r == PF_OK) r = app__lights_at(seq, f, s.base_lights, nl, s.lights, &err);
        for (uint32_t i = 0; i < nl && r == PF_OK; i++)
            if (!pf_v3_is_finite(s.lights[i].position) || !pf_v3_is_finite(s.lights[i].color) ||
                !isfinite(s.lights[i].intensity))
                r = pf_error_set(&err, PF_ERR_NONFINITE, "%s: frame %u: light %u is not finite", seq->file, f, i);
    }
    if (r != PF_OK) return app__fail_run(&s, &err);

    /* Output folder: -o is the user's; what the file chooses stays in out/ */
    char dir[4096], path[4200];
    if (o->out_path) {
        snprintf(dir, sizeof dir, "%s", o->out_path);
        size_t dl = strlen(dir);
        while (dl > 1 && dir[dl - 1] == '/') dir[--dl] = 0;
        app__frame_path(path, sizeof path, dir, 0, ".pfm");
        r = pf_imageio_make_parent_dirs(path, &err);
    } else {
        const size_t bl = strlen(PF_SEQUENCE_OUTPUT_BASE);
        const char *rel = seq->output[0] ? seq->output + bl + 1 : seq->name; /* seq->output = "out/<rel>" */
        r = pf_imageio_make_dir_inside(PF_SEQUENCE_OUTPUT_BASE, rel, dir, sizeof dir, &err);
        if (r != PF_OK) {
            char m[sizeof err.message];
            snprintf(m, sizeof m, "%s", err.message);
            r = pf_error_set(&err, r, "%s: output folder %s", seq->file, m);
        }
    }
    if (r != PF_OK) return app__fail_run(&s, &err);
    /* --reuse-frames reads the images of a finished run of this sequence */
    pf_sequence_manifest man = {seq->frames, 0};
    int had_manifest = 0;
    pf_sequence_manifest old;
    if (o->reuse_frames && (r = pf_sequence_manifest_read(dir, &old, &had_manifest, &err)) == PF_OK &&
        had_manifest && (!old.complete || old.frames != seq->frames))
        r = pf_error_set(&err, PF_ERR_ARGUMENT, "--reuse-frames: %s/%s lists %s run of %u frames, this sequence has %u",
                         dir, PF_SEQUENCE_MANIFEST, old.complete ? "a finished" : "an unfinished", old.frames,
                         seq->frames);
    if (r != PF_OK) return app__fail_run(&s, &err);

    /* the frame's state runs through every frame; references stand alone */
    const int carry = !o->reference;
    /* Animation: posed at the first frame the loop renders before anything
     * is built; later frames pose again and rebuild when something moved. */
    const uint32_t f_start = carry || o->exposure_auto ? 0 : first;
    uint32_t moved_objects = 0;
    if (seq->anim_set && (r = app__seq_pose(&s, f_start, &moved_objects, &err)) != PF_OK)
        return app__fail_run(&s, &err);

    /* Embree, jobs, rasterizer, frame: once for the whole sequence (Embree
     * updated, the rest again, after a frame's pose moves geometry). */
    double t_build = pf_time_now();
    if ((r = pf_rt_create_dynamic(&s.rt, &s.scene, &s.anim, isa, threads, &err)) != PF_OK)
        return app__fail_run(&s, &err);
    s.jobs = pf_jobs_create(threads);
    if (!s.jobs) r = pf_error_set(&err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", threads);
    if (r == PF_OK && !o->raytrace) r = rs_context_create(&s.raster, &s.scene, s.jobs, rs_simd_for_isa(isa), &err);
    if (r == PF_OK) {
        r = app_frame_init(o, &s.frame, &s.scene, s.rt, s.raster, s.jobs, &camera, width, height, !o->reference, &err);
        s.frame_ready = r == PF_OK;
        if (r == PF_OK) r = api_declare_dynamic(&s.frame, &s.anim, &err);
    }
    if (r != PF_OK) return app__fail_run(&s, &err);
    t_build = pf_time_now() - t_build;
    gi_frame *fr = &s.frame;

    if (!o->quiet) {
        printf("softgi sequence: %s, scene %s, %u frames, %u triangles, %u lights, %ux%u, %u threads, isa %s, %s\n",
               seq->name, stem, seq->frames, s.scene.tri_count, nl, width, height, threads, pf_isa_name(isa),
               o->reference ? "path-traced reference" : o->raytrace ? "ray-traced G-buffer" : "rasterized G-buffer");
        if (fr->indirect)
            printf("indirect: %s, budget %u VPLs, %ux%u tiles, visibility %s, pipeline %s\n",
                   fr->ind.opt.method->name, fr->ind.opt.vpls, fr->ind.n, fr->ind.m,
                   fr->ind.ism ? "imperfect shadow maps" : fr->ind.para ? "paraboloid maps" : "Embree rays",
                   fr->ind.opt.pipeline ? "on (frames >= 1 shade with the previous frame's VPLs)" : "off");
        printf("load %.1f ms, build %.1f ms; writing %s/frame_NNNN.{pfm,png,view,depth.pfm}\n", t_load * 1e3,
               t_build * 1e3, dir);
    }

    /* Frames: the manifest says "running" until the last file is written.
     * [first, end): the frames written; frames before `first` are rendered
     * only to carry the frame's state (or frame 0 for --exposure auto). */
    if ((r = pf_sequence_manifest_write(dir, &man, &err)) != PF_OK) return app__fail_run(&s, &err);
    pf_stage_times total;
    memset(&total, 0, sizeof total);
    uint64_t hash = 0xcbf29ce484222325ull;
    double render_sum = 0.0, write_sum = 0.0;
    uint64_t moved_sum = 0;
    float exposure = o->exposure; /* --exposure auto: picked on frame 0 and held, so the PNGs do not flicker */
    app__seq_progress *prog = &s.progress;
    app_progress_begin(&prog->bar, "sequence", o->quiet);
    prog->total = carry ? end : end - first + (o->exposure_auto && first > 0);
    for (uint32_t f = 0; f < end && r == PF_OK; f++) {
        const int write = f >= first;
        if (!write && !carry && !(f == 0 && o->exposure_auto)) continue;
        prog->frame = f;
        prog->stages = 0;
        app__seq_progress_show(prog, 0.0, NULL);
        /* the animation at frame f: what moved updates Embree, the
         * rasterizer and the frame (api_geometry_moved) */
        moved_objects = 0;
        double t_pose = pf_time_now();
        if (seq->anim_set && f != f_start) {
            r = app__seq_pose(&s, f, &moved_objects, &err);
            if (r == PF_OK && moved_objects) /* in place; a failure (out of memory) stops the run */
                r = api_geometry_moved(s.rt, s.raster, s.frame_ready ? &s.frame : NULL, s.moved, s.anim.prim_count,
                                       &err);
            if (r != PF_OK) break;
        }
        t_pose = (pf_time_now() - t_pose) * 1e3;
        /* camera and lights of frame f (checked above) */
        pf_vec3 eye, target;
        float fovy;
        if (pf_sequence_camera_at(seq, f, &eye, &target, &fovy))
            pf_camera_look_at(&fr->camera, eye, target, pf_radians(fovy), &err);
        app__lights_at(seq, f, s.base_lights, nl, s.lights, &err);
        uint32_t lights_changed = 0;
        for (uint32_t i = 0; i < nl; i++) {
            if (app__light_equal(&s.scene.lights[i], &s.lights[i])) continue;
            s.scene.lights[i] = s.lights[i];
            lights_changed++;
        }

        /* render */
        double t0 = pf_time_now();
        pf_stage_hook hook = pf_stage_hook_set((pf_stage_hook){prog->bar.on ? app__seq_progress_stage : NULL, prog});
        if (o->reference) r = app__render_reference(&s, o, dir, f, &err);
        else if (o->raytrace) gi_frame_render_raytraced(fr);
        else gi_frame_render_raster(fr);
        pf_stage_hook_set(hook);
        if (r == PF_OK && fr->status != PF_OK) r = fr->status, err = fr->error;
        double t_render = (pf_time_now() - t0) * 1e3;
        prog->expected = prog->stages;
        prog->done++;
        app_progress_clear(&prog->bar); /* lines and notes follow; the next frame draws it again */
        uint32_t moved = 0;
        if (fr->indirect)
            for (uint32_t i = 0; i < fr->ind.vpls.count; i++) moved += fr->ind.vpls.v[i].moved != 0;

        if (r != PF_OK) break;
        if (!write) { /* a frame before the range: its state (or frame 0's exposure) only */
            if (f == 0) {
                exposure = app_exposure(o, fr->final, width, height);
                app_hint_dark(o, fr->final, width, height, exposure);
            }
            if (!o->quiet)
                printf("frame %04u  render %8.1f ms  (before --frames %u:%u: not written; %s)\n", f, t_render, first,
                       end, carry ? "carries the frame's state" : "picks --exposure auto");
            continue;
        }
        moved_sum += moved;
        if (seq->anim_set) pf_stage_add(&total, "pose (+ update when moved)", t_pose);
        for (uint32_t i = 0; i < fr->times.count; i++) pf_stage_add(&total, fr->times.name[i], fr->times.ms[i]);
        /* write */
        t0 = pf_time_now();
        gi_metrics_view view;
        gi_metrics_view_from_camera(&view, &fr->camera, width, height);
        app__frame_path(path, sizeof path, dir, f, ".pfm");
        r = pf_imageio_write_pfm(path, fr->final, width, height, &err);
        app__frame_path(path, sizeof path, dir, f, ".png");
        if (r == PF_OK && f == 0) {
            exposure = app_exposure(o, fr->final, width, height);
            app_hint_dark(o, fr->final, width, height, exposure);
        }
        if (r == PF_OK) r = pf_imageio_write_png(path, fr->final, width, height, exposure, &err);
        app__frame_path(path, sizeof path, dir, f, ".view");
        if (r == PF_OK) r = gi_metrics_view_write(path, &view, &err);
        app__frame_path(path, sizeof path, dir, f, ".depth.pfm");
        if (r == PF_OK) r = gi_metrics_depth_write(path, fr->gbuf.depth, width, height, &err);
        double t_write = (pf_time_now() - t0) * 1e3;
        render_sum += t_render;
        write_sum += t_write;
        uint64_t fh = pf_imageio_hash(fr->final, (uint64_t)width * height * 3);
        hash = app__fnv1a(hash, &fh, sizeof fh);
        if (r == PF_OK && !o->quiet) {
            printf("frame %04u  render %8.1f ms  write %6.1f ms", f, t_render, t_write);
            if (fr->indirect)
                printf("  VPLs %u, moved %u, maps %u", fr->ind.vpls.count, moved, fr->ind.maps_rendered);
            if (lights_changed) printf("  (%u light%s moved)", lights_changed, lights_changed > 1 ? "s" : "");
            if (moved_objects)
                printf("  (%u object%s moved: renderer updated)", moved_objects, moved_objects > 1 ? "s" : "");
            printf("\n");
        }
    }
    app_progress_end(&prog->bar);
    if (r != PF_OK) return app__fail_run(&s, &err);

    /* track.txt (empty without "track": compare's default grid), then the
     * manifest that makes the folder this run's finished sequence */
    snprintf(path, sizeof path, "%s/track.txt", dir);
    char track_text[PF_SEQUENCE_MAX_TRACK * 24 + 1];
    size_t tl = 0;
    for (uint32_t i = 0; i < seq->track_count; i++)
        tl += (size_t)snprintf(track_text + tl, sizeof track_text - tl, "%u,%u\n", track[i][0], track[i][1]);
    r = pf_imageio_write_file(path, track_text, tl, &err);
    man.complete = 1;
    if (r == PF_OK) r = pf_sequence_manifest_write(dir, &man, &err);
    if (r != PF_OK) return app__fail_run(&s, &err);

    if (!o->quiet) {
        double n = (double)(end - first);
        printf("%u frames: render %.1f ms/frame (total %.2f s), write %.1f ms/frame", end - first, render_sum / n,
               render_sum * 1e-3, write_sum / n);
        if (fr->indirect) printf(", %.1f VPLs moved/frame", (double)moved_sum / n);
        printf("\nmean per frame:\n");
        for (uint32_t i = 0; i < total.count; i++) total.ms[i] /= n;
        pf_stage_print(&total, stdout);
        if (end - first == seq->frames) printf("wrote %u frames to %s\n", seq->frames, dir);
        else
            printf("wrote frames %u..%u (%u of %u; --frames %u:%u) to %s\n", first, end - 1, end - first, seq->frames,
                   first, end, dir);
    }
    if (o->print_hash) printf("hash %016llx (isa %s)\n", (unsigned long long)hash, pf_isa_name(isa));
    app__cleanup(&s);
    return 0;
}
