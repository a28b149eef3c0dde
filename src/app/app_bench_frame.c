/* app_bench_frame: `softgi bench frame` — the whole many-light frame, stage
 * by stage, and what frame pipelining gains (Laine 2007
 * Sec. 3 and 6: VPL management overlapped with the frame).
 *
 * For Sibenik and the conference room (from --scenes, default
 * ../shared/scenes, textures ignored) at 1024x768, with 256 and 2048 VPLs
 * (or --vpls N) and 1 and 2 threads (or --threads N):
 * - the scene's lights are replaced by one static point light (Sibenik:
 *   (0, 0, 0), 50 W/sr; the conference room, whose unit is 1/0.003 m:
 *   (300, 550, -100), 2e5 W/sr); cameras as `softgi bench raster`;
 * - the rasterized frame (gi_frame_render_raster) with indirect light on:
 *   the VPL method of --method (default ir: Instant Radiosity) with its
 *   --param values, 4x4 interleaved tiles (or --tiles), box filter,
 *   visibility by paraboloid maps (or --visibility raytrace|ism);
 * - pipelining: with --pipeline on or off only that; without --pipeline
 *   every configuration is measured both ways in the same run (two frames,
 *   off and on, sharing the job pool, Embree scene and rasterizer, their
 *   frames alternating), and the gain of the frame median is printed per
 *   VPL count and thread count;
 * - one warm-up frame (the first frame: every VPL is new, so every
 *   paraboloid map is rendered; reported on its own), then --frames frames
 *   (default 15). With the static light IR returns the same VPL set and the
 *   frame re-renders no map: the moved-VPL and rendered-map counts after
 *   the first frame are printed to show it (they should be 0).
 * - --moving-light: before frame i (0 = the warm-up frame) the light is
 *   moved to its position + r (cos(2 pi i / 16), 0, sin(2 pi i / 16)), a
 *   horizontal circle (glTF's y is up) of radius r = 1% of the scene's
 *   bounding-box diagonal, so every frame has a changed light: every method
 *   must update its VPLs and the light's cube shadow map is re-rendered.
 *   The moved VPLs and rendered maps per frame are printed (means).
 * Each stage's figure is the median over the frames of its time in
 * f->times; "frame" is the median wall-clock time of the whole
 * gi_frame_render_raster call (so it is not the sum of the stage medians).
 * Shares are stage median / frame median. The "VPL update" row is the
 * method's update (VPL management, Laine's steps 1-4) on its own row; with
 * pipelining it is the update job's own time, which overlaps the other
 * stages (its share then says how much of the frame it hides in).
 * Output: one table per scene (stages as rows, configurations as columns,
 * ms and share of the frame), the same frame in Hedman 2017 Table 2's
 * columns (with the method's own parts of its update where it reports
 * them: SMC's candidate sampling, resampling, indirect visibility,
 * radiosity and kNN), the target lines (bf__target: the frame rates
 * the real-time work asks of each case on 2 threads, pipelining off) and
 * one JSON line (prefix "json: ").
 *
 * Scaling past two cores: the job profile (pf_jobs.h) is
 * on for every frame of the run, and for each configuration without
 * pipelining a table gives every stage's serial part (outside
 * parallel-fors) beside its parallel work and span, with the frame's
 * predicted time and speed-up on 8, 16 and 64 cores (app_amdahl_print,
 * below, which `bench raster` uses too). With pipelining the VPL update
 * overlaps the other stages, so its stage boundaries say nothing about a
 * critical path and no table is printed. The profile costs two clock
 * reads per job item (a few thousand items a frame).
 *
 * Anti-aliasing (docs/aa.md): --aa N renders every frame with N jittered
 * samples, --taa N adds the temporal anti-aliasing stage. A stage that runs
 * once per sample (gi_stage_info.per_sample) then has the sum of its N runs
 * in its row; two more rows give the per-sample stages' time per sample and
 * the once-a-frame stages' time, so the cost of each extra sample reads
 * directly. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "app.h"
#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_rt.h"
#include "pf_timer.h"
#include "rs_raster.h"

#define BF_W 1024
#define BF_H 768
#define BF_MAX_CONFIGS 8 /* per scene: 2 VPL counts x 2 thread counts x pipelining off/on */
#define BF_LIGHT_PERIOD 16 /* --moving-light: frames per circle */
#define BF_LIGHT_RADIUS 0.01f /* --moving-light: circle radius / scene diagonal */
#define BF_UPDATE_STAGE (gi_stage_get(GI_STAGE_VPL_UPDATE)->name) /* the stage table's name of step 3 */
#define BF_TARGET_THREADS 2u

/* The frame rate the real-time work asks of a case (1024x768, 2 threads,
 * pipelining off), 0 where it names none: IR with 256 VPLs and a static
 * light 40 frames/s; with a moving light, 256 VPLs: IIR 30, SMC 25, TCAS with
 * ISM visibility 15; SMC with 2048 VPLs on the conference room 10. */
static double bf__target(const char *method, int moving_light, const char *visibility, uint32_t vpls,
                         const char *scene)
{
    if (!moving_light) return !strcmp(method, "ir") && vpls == 256u ? 40.0 : 0.0;
    if (vpls == 2048u) return !strcmp(method, "smc") && !strcmp(scene, "conference") ? 10.0 : 0.0;
    if (vpls != 256u) return 0.0;
    if (!strcmp(method, "iir")) return 30.0;
    if (!strcmp(method, "smc")) return 25.0;
    if (!strcmp(method, "tcas") && !strcmp(visibility, "ism")) return 15.0;
    return 0.0;
}
#define BF_MAPS_STAGE (gi_stage_get(GI_STAGE_VPL_MAPS)->name) /* and of step 4 */
#define BF_TAIL_STAGE "(end of frame: wait for jobs)"
#define BF_SERIAL_TARGET 0.05 /* the serial part's target: <= 5% of the 1-thread frame */

typedef struct bf_scene {
    const char *name, *file;
    pf_vec3 eye, target;
    float fovy_deg;
    pf_vec3 light_pos;
    float light_intensity; /* W/sr in the scene's units */
} bf_scene;

/* The cameras of `softgi bench raster` (README "Benchmarks"); the lights: one
 * point light inside the nave, one above the conference table. */
static const bf_scene k_scenes[] = {
    {"sibenik", "sibenik/sibenik.gltf", {-18.0f, -11.0f, 0.0f}, {10.0f, -8.0f, 0.0f}, 70.0f, {0.0f, 0.0f, 0.0f}, 50.0f},
    {"conference", "conference/conference.gltf", {1400.0f, 420.0f, 500.0f}, {-600.0f, 150.0f, -700.0f}, 65.0f,
     {300.0f, 550.0f, -100.0f}, 2e5f},
};
#define BF_SCENES (sizeof k_scenes / sizeof k_scenes[0])

typedef struct bf_result {
    const char *scene;
    uint32_t vpl_budget, vpl_count, threads;
    int pipeline;
    /* medians over the measured frames */
    pf_stage_times stages; /* names in the order the frame ran them, ms = median */
    pf_stage_times parts;  /* the method's own parts of its update (gi_vpl_method.parts), ms = median */
    double frame_ms, fps;
    /* the first (warm-up) frame: every VPL new, every map rendered */
    pf_stage_times first;
    double first_ms;
    uint32_t first_moved, first_maps;
    /* summed over the measured frames: should be 0 with a static light */
    uint64_t moved_after, maps_after;
    /* direct-light shadow-map tiles drawn (gi_stage_shadow_maps): the first
     * frame's, the later frames' sum, and how many the maps hold */
    uint32_t first_tiles, tiles_total;
    uint64_t tiles_after;
    /* pipelining off: the job profile per stage, medians (app_amdahl) */
    int have_amdahl;
    app_amdahl amdahl;
} bf_result;

/* ---------------------------------------------------------------- Amdahl (app.h) */

/* This thread's CPU time, ms. */
static double app__cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* An interval of `wall` ms in which this (the external) thread used `cpu`
 * ms of CPU time, and the profile moved by `d`. */
static void app__amdahl_add(app_amdahl *a, const char *name, double wall, double cpu, const pf_jobs_profile *d)
{
    uint32_t i = 0;
    while (i < a->count && strcmp(a->name[i], name)) i++;
    if (i == a->count) {
        if (i == PF_MAX_STAGES) return;
        a->name[i] = name;
        a->wall[i] = a->serial[i] = a->work[i] = a->span[i] = 0.0;
        for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++) a->predicted[i][k] = 0.0;
        a->count++;
    }
    /* the external thread's CPU time outside every parallel region (not
     * its wall time: on a loaded machine that counts other processes too);
     * never below 0 (clock granularity) */
    double serial = cpu - d->wait_cpu_ms > 0.0 ? cpu - d->wait_cpu_ms : 0.0;
    a->wall[i] += wall;
    a->serial[i] += serial;
    a->work[i] += d->work_ms;
    a->span[i] += d->span_ms;
    for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++) a->predicted[i][k] += serial + d->predicted_ms[k];
}

void app_amdahl_mark(app_amdahl_probe *pr, const char *name)
{
    double now = pf_time_now(), cpu = app__cpu_ms();
    pf_jobs_profile p;
    pf_jobs_profile_read(pr->jobs, &p);
    pf_jobs_profile d = pf_jobs_profile_delta(&pr->p, &p);
    app__amdahl_add(pr->out, name, (now - pr->t) * 1e3, cpu - pr->cpu, &d);
    pr->p = p;
    pr->cpu = app__cpu_ms(); /* the read itself is not the next stage's */
    pr->t = pf_time_now();
}

void app_amdahl_skip(app_amdahl_probe *pr)
{
    pf_jobs_profile_read(pr->jobs, &pr->p);
    pr->cpu = app__cpu_ms();
    pr->t = pf_time_now();
}

static void app__amdahl_hook(void *user, const char *name, double ms)
{
    (void)ms; /* the interval since the last boundary: it includes what runs between two stages */
    app_amdahl_mark(user, name);
}

void app_amdahl_begin(app_amdahl_probe *pr, pf_jobs *jobs, app_amdahl *out)
{
    pr->jobs = jobs;
    pr->out = out;
    out->count = 0;
    pr->old = pf_stage_hook_set((pf_stage_hook){app__amdahl_hook, pr});
    app_amdahl_skip(pr);
}

void app_amdahl_end(app_amdahl_probe *pr, const char *tail)
{
    double now = pf_time_now(), cpu = app__cpu_ms();
    pf_jobs_profile p;
    pf_jobs_profile_read(pr->jobs, &p);
    pf_jobs_profile d = pf_jobs_profile_delta(&pr->p, &p);
    double wall = (now - pr->t) * 1e3;
    if (tail && (wall >= 0.01 || d.jobs)) app__amdahl_add(pr->out, tail, wall, cpu - pr->cpu, &d);
    pf_stage_hook_set(pr->old);
}

static int app__cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The median over the frames of the double at byte `offset` + stage index
 * x `stride` doubles in an app_amdahl, for stage `name` (0 where a frame
 * lacks the stage); `tmp`: n doubles. */
static double app__amdahl_field(const app_amdahl *frames, uint32_t n, const char *name, size_t offset, size_t stride,
                                double *tmp)
{
    for (uint32_t j = 0; j < n; j++) {
        const app_amdahl *a = &frames[j];
        tmp[j] = 0.0;
        for (uint32_t i = 0; i < a->count; i++)
            if (!strcmp(a->name[i], name)) tmp[j] = *(const double *)((const char *)a + offset + i * stride * sizeof(double));
    }
    qsort(tmp, n, sizeof *tmp, app__cmp_double);
    return n % 2 ? tmp[n / 2] : 0.5 * (tmp[n / 2 - 1] + tmp[n / 2]);
}

void app_amdahl_median(app_amdahl *out, const app_amdahl *frames, uint32_t n)
{
    memset(out, 0, sizeof *out);
    double *tmp = malloc(sizeof(double) * (n ? n : 1));
    if (!tmp || !n) {
        free(tmp);
        return;
    }
    for (uint32_t j = 0; j < n; j++)
        for (uint32_t i = 0; i < frames[j].count; i++) {
            uint32_t k = 0;
            while (k < out->count && strcmp(out->name[k], frames[j].name[i])) k++;
            if (k == out->count && k < PF_MAX_STAGES) out->name[out->count++] = frames[j].name[i];
        }
    for (uint32_t i = 0; i < out->count; i++) {
        const char *nm = out->name[i];
        out->wall[i] = app__amdahl_field(frames, n, nm, offsetof(app_amdahl, wall), 1, tmp);
        out->serial[i] = app__amdahl_field(frames, n, nm, offsetof(app_amdahl, serial), 1, tmp);
        out->work[i] = app__amdahl_field(frames, n, nm, offsetof(app_amdahl, work), 1, tmp);
        out->span[i] = app__amdahl_field(frames, n, nm, offsetof(app_amdahl, span), 1, tmp);
        for (uint32_t k = 0; k < PF_JOBS_PROFILE_CORES; k++)
            out->predicted[i][k] = app__amdahl_field(frames, n, nm, offsetof(app_amdahl, predicted) + k * sizeof(double),
                                                     PF_JOBS_PROFILE_CORES, tmp);
    }
    free(tmp);
}

/* The profile's column for `cores` (pf_jobs_profile_cores), or -1. */
static int app__amdahl_column(uint32_t cores)
{
    for (int k = 0; k < PF_JOBS_PROFILE_CORES; k++)
        if (pf_jobs_profile_cores[k] == cores) return k;
    return -1;
}

void app_amdahl_print(const app_amdahl *a, const char *title, uint32_t threads, const char *sum_label)
{
    static const uint32_t show[] = {2, 8, 16, 64};
    enum { SHOW = sizeof show / sizeof show[0] };
    printf("%s, measured with %u thread%s (ms, medians):\n", title, threads, threads > 1 ? "s" : "");
    printf("  %-30s %8s %8s %8s %8s |", "stage", "wall", "serial", "work", "span");
    for (int c = 0; c < SHOW; c++) printf(" %5u cores", show[c]);
    printf("\n");
    double wall = 0, serial = 0, work = 0, span = 0, pred[SHOW] = {0};
    for (uint32_t i = 0; i < a->count; i++) {
        printf("  %-30.30s %8.2f %8.2f %8.2f %8.2f |", a->name[i], a->wall[i], a->serial[i], a->work[i], a->span[i]);
        for (int c = 0; c < SHOW; c++) {
            double v = a->predicted[i][app__amdahl_column(show[c])];
            printf(" %11.2f", v);
            pred[c] += v;
        }
        printf("\n");
        wall += a->wall[i], serial += a->serial[i], work += a->work[i], span += a->span[i];
    }
    double one = serial + work; /* the 1-core time: every item one after the other */
    printf("  %-30s %8.2f %8.2f %8.2f %8.2f |", sum_label, wall, serial, work, span);
    for (int c = 0; c < SHOW; c++) printf(" %11.2f", pred[c]);
    printf("\n  %-30s %8s %8s %8s %8s |", "speed-up over 1 core", "", "", "", "");
    for (int c = 0; c < SHOW; c++) printf(" %10.2fx", pred[c] > 0.0 ? one / pred[c] : 0.0);
    double share = one > 0.0 ? serial / one : 0.0;
    printf("\n  1 core (serial + work) %.2f ms; unlimited cores (serial + span) %.2f ms, %.1fx; serial part %.1f%% "
           "of the 1-core time (target <= %.0f%%: %s)\n",
           one, serial + span, serial + span > 0.0 ? one / (serial + span) : 0.0, 100.0 * share,
           100.0 * BF_SERIAL_TARGET, share <= BF_SERIAL_TARGET ? "met" : "NOT met");
    /* work is CPU time (pf_jobs.c takes preemption out of the items), wall is not */
    if (threads == 1 && one > 0.0 && wall > 1.2 * one)
        printf("  the wall clock took %.1fx the 1-core time: this core was shared with other processes (the\n"
               "  predictions count CPU time and assume cores of their own)\n",
               wall / one);
}

/* The frame's predicted time on `cores` cores (app__amdahl_column's), or 0. */
static double bf__amdahl_frame(const app_amdahl *a, uint32_t cores)
{
    int k = app__amdahl_column(cores);
    double t = 0.0;
    for (uint32_t i = 0; i < a->count && k >= 0; i++) t += a->predicted[i][k];
    return t;
}

static int bf__cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double bf__median(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, bf__cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static double bf__stage_ms(const pf_stage_times *t, const char *name)
{
    for (uint32_t i = 0; i < t->count; i++)
        if (!strcmp(t->name[i], name)) return t->ms[i];
    return 0.0;
}

/* 1 when `name` is a stage the frame runs once per anti-aliasing sample. */
static int bf__per_sample(const char *name)
{
    for (int id = 0; id < GI_STAGE_COUNT; id++)
        if (!strcmp(gi_stage_get((gi_stage_id)id)->name, name)) return gi_stage_get((gi_stage_id)id)->per_sample;
    return 0;
}

static uint32_t bf__moved(const gi_frame *f)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < f->ind.vpls.count; i++) n += f->ind.vpls.v[i].moved != 0;
    return n;
}

/* The bench light's position before frame i (see the top comment). */
static pf_vec3 bf__light_at(const bf_scene *bs, const pf_scene *scene, int moving, uint32_t i)
{
    if (!moving) return bs->light_pos;
    float r = BF_LIGHT_RADIUS * pf_v3_length(pf_v3_sub(scene->bounds_max, scene->bounds_min));
    float a = 2.0f * PF_PI * (float)(i % BF_LIGHT_PERIOD) / (float)BF_LIGHT_PERIOD;
    return pf_v3_add(bs->light_pos, pf_v3(r * cosf(a), 0.0f, r * sinf(a)));
}

/* One VPL count on an already built Embree scene and raster context, for
 * each pipelining mode in modes[0..nmodes): one gi_frame per mode, a
 * warm-up frame, then `frames` measured frames. The modes' frames alternate
 * (frame i of every mode, then frame i + 1), so a change in the machine's
 * load during the run falls on both alike. `light` is the scene's one light
 * (moved before each frame with --moving-light; every mode's frame i sees
 * the same position). */
/* Frame `frame`'s times t into the per-frame table ms ([name][frame]),
 * matched by name into `names`, so a stage a frame skips counts 0 ms. */
static void bf__collect(pf_stage_times *names, double *ms, const pf_stage_times *t, uint32_t frames, uint32_t frame)
{
    for (uint32_t s = 0; s < t->count; s++) {
        uint32_t k = 0;
        while (k < names->count && strcmp(names->name[k], t->name[s])) k++;
        if (k == names->count) {
            if (k == PF_MAX_STAGES) continue;
            names->name[k] = t->name[s];
            names->count++;
            for (uint32_t j = 0; j < frames; j++) ms[k * frames + j] = 0.0;
        }
        ms[k * frames + frame] = t->ms[s];
    }
}

static pf_result bf__measure(const pf_scene *lit, pf_light *light, const bf_scene *bs, pf_rt *rt, rs_context *rs,
                             pf_jobs *jobs, uint32_t threads, uint32_t vpls, const int *modes, uint32_t nmodes,
                             const pf_options *o, uint32_t frames, bf_result *out, pf_error *err)
{
    pf_camera cam;
    pf_result r = pf_camera_look_at(&cam, bs->eye, bs->target, pf_radians(bs->fovy_deg), err);
    if (r != PF_OK) return r;
    light->position = bf__light_at(bs, lit, o->moving_light, 0);
    gi_frame f[2];
    double *frame_ms[2] = {NULL, NULL}, *stage_ms[2] = {NULL, NULL}; /* stage_ms: [stage][frame] */
    double *part_ms[2] = {NULL, NULL};                                /* part_ms: [part][frame] */
    app_amdahl *amdahl[2] = {NULL, NULL};                             /* pipelining off: [frame] */
    uint32_t ready = 0;
    for (uint32_t m = 0; m < nmodes && r == PF_OK; m++) {
        memset(&out[m], 0, sizeof out[m]);
        out[m].scene = bs->name;
        out[m].vpl_budget = vpls;
        out[m].threads = threads;
        out[m].pipeline = modes[m];
        gi_frame_desc fd = {.scene = lit, .rt = rt, .jobs = jobs, .raster = rs, .camera = &cam, .width = BF_W,
                            .height = BF_H, .shadow_size = o->shadow_size, .area_slope = o->visibility_slope,
                            .aa_samples = o->aa,
                            .taa_frames = o->taa};
        if ((r = gi_frame_create(&f[m], &fd, err)) != PF_OK) break;
        ready++;
        /* the command line's method, --param and --visibility; --vpls and
         * --pipeline are this configuration's (defaults as `softgi render`) */
        gi_indirect_options io;
        r = app_indirect_options(o, &io, err);
        io.vpls = vpls;
        io.pipeline = modes[m];
        if (r == PF_OK) r = gi_frame_enable_indirect(&f[m], &io, 0, err);
        frame_ms[m] = malloc(sizeof(double) * frames);
        stage_ms[m] = malloc(sizeof(double) * frames * PF_MAX_STAGES);
        part_ms[m] = malloc(sizeof(double) * frames * PF_MAX_STAGES);
        if (!modes[m]) amdahl[m] = malloc(sizeof(app_amdahl) * frames);
        if (r == PF_OK && (!frame_ms[m] || !stage_ms[m] || !part_ms[m] || (!modes[m] && !amdahl[m])))
            r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u frames of timings", frames);
    }
    for (uint32_t i = 0; i <= frames && r == PF_OK; i++) { /* i == 0: the first frame, every map rendered */
        light->position = bf__light_at(bs, lit, o->moving_light, i);
        for (uint32_t m = 0; m < nmodes && r == PF_OK; m++) {
            bf_result *res = &out[m];
            app_amdahl_probe probe;
            if (i > 0 && amdahl[m]) app_amdahl_begin(&probe, jobs, &amdahl[m][i - 1]);
            double t0 = pf_time_now();
            gi_frame_render_raster(&f[m]);
            double ms = (pf_time_now() - t0) * 1e3;
            if (i > 0 && amdahl[m]) app_amdahl_end(&probe, BF_TAIL_STAGE);
            uint32_t moved = bf__moved(&f[m]);
            if (i == 0) {
                res->first = f[m].times;
                res->first_ms = ms;
                res->first_moved = moved;
                res->first_maps = f[m].ind.maps_rendered;
                res->first_tiles = f[m].motion_stats.shadow_tiles;
                res->tiles_total = 0;
                for (uint32_t l = 0; l < f[m].shadows.count; l++)
                    res->tiles_total += f[m].shadows.maps[l].face_count * f[m].shadows.maps[l].tiles_side *
                                        f[m].shadows.maps[l].tiles_side;
                res->vpl_count = f[m].ind.vpls.count;
                res->stages.count = 0;
                res->parts.count = 0;
                if (!res->vpl_count) /* e.g. a method that failed its update (its message is above) */
                    r = pf_error_set(err, PF_ERR_ARGUMENT, "method %s made no VPLs in the first frame",
                                     f[m].ind.opt.method->name);
                continue;
            }
            res->moved_after += moved;
            res->maps_after += f[m].ind.maps_rendered;
            res->tiles_after += f[m].motion_stats.shadow_tiles;
            frame_ms[m][i - 1] = ms;
            bf__collect(&res->stages, stage_ms[m], &f[m].times, frames, i - 1);
            const gi_vpl_method *method = f[m].ind.opt.method;
            if (method->parts) bf__collect(&res->parts, part_ms[m], method->parts(f[m].ind.method_state), frames, i - 1);
        }
    }
    for (uint32_t m = 0; m < nmodes && r == PF_OK; m++) {
        for (uint32_t k = 0; k < out[m].stages.count; k++)
            out[m].stages.ms[k] = bf__median(stage_ms[m] + k * frames, frames);
        for (uint32_t k = 0; k < out[m].parts.count; k++)
            out[m].parts.ms[k] = bf__median(part_ms[m] + k * frames, frames);
        out[m].frame_ms = bf__median(frame_ms[m], frames);
        out[m].fps = 1e3 / out[m].frame_ms;
        if (amdahl[m]) {
            app_amdahl_median(&out[m].amdahl, amdahl[m], frames);
            out[m].have_amdahl = 1;
        }
    }
    for (uint32_t m = 0; m < nmodes; m++) {
        free(frame_ms[m]), free(stage_ms[m]), free(part_ms[m]), free(amdahl[m]);
        if (m < ready) gi_frame_free(&f[m]);
    }
    return r;
}

/* Every configuration of one scene: one Embree scene, raster context and job
 * pool per thread count, shared by the VPL counts. */
static pf_result bf__scene(const pf_scene *scene, const bf_scene *bs, const uint32_t *vpl_list, uint32_t nvpls,
                           const uint32_t *thread_list, uint32_t nthreads, pf_isa isa, const pf_options *o,
                           uint32_t frames, bf_result *results, pf_error *err)
{
    pf_scene lit = *scene; /* shallow copy with our one light; the arrays stay the scene's */
    pf_light light;
    memset(&light, 0, sizeof light);
    snprintf(light.name, sizeof light.name, "bench point light");
    light.type = PF_LIGHT_POINT;
    light.position = bs->light_pos;
    light.color = pf_v3(1, 1, 1);
    light.intensity = bs->light_intensity;
    lit.lights = &light;
    lit.light_count = 1;
    int modes[2] = {0, 1}; /* pipelining off, then on */
    uint32_t nmodes = 2;
    if (o->pipeline >= 0) modes[0] = o->pipeline, nmodes = 1;
    pf_result r = PF_OK;
    for (uint32_t t = 0; t < nthreads && r == PF_OK; t++) {
        pf_jobs *jobs = pf_jobs_create(thread_list[t]);
        pf_rt *rt = NULL;
        rs_context *rs = NULL;
        if (!jobs) r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", thread_list[t]);
        else pf_jobs_profile_enable(jobs, 1); /* every frame, both modes alike: the same small cost */
        if (r == PF_OK) r = pf_rt_create(&rt, &lit, isa, thread_list[t], err);
        if (r == PF_OK) r = rs_context_create(&rs, &lit, jobs, rs_simd_for_isa(isa), err);
        for (uint32_t v = 0; v < nvpls && r == PF_OK; v++) {
            bf_result *res = &results[(v * nthreads + t) * nmodes];
            r = bf__measure(&lit, &light, bs, rt, rs, jobs, thread_list[t], vpl_list[v], modes, nmodes, o, frames,
                            res, err);
            for (uint32_t m = 0; m < nmodes && r == PF_OK; m++)
                fprintf(stderr, "  %s, %u VPLs, %u thread%s, pipeline %s: first frame %.0f ms, then %.1f ms/frame\n",
                        bs->name, vpl_list[v], thread_list[t], thread_list[t] > 1 ? "s" : "",
                        res[m].pipeline ? "on" : "off", res[m].first_ms, res[m].frame_ms);
        }
        rs_context_destroy(rs);
        pf_rt_destroy(rt);
        if (jobs) pf_jobs_destroy(jobs);
    }
    return r;
}

/* One scene's table: stages as rows, its configurations as columns, each
 * "ms share" (up to 28 + 8 x 17 = 164 columns), then the pipelining gains. */
/* The union of the configurations' stage names (parts: the methods' own
 * parts instead), in the order they first ran: a table's rows. */
static void bf__union(pf_stage_times *rows, const bf_result *res, uint32_t n, int parts)
{
    memset(rows, 0, sizeof *rows);
    for (uint32_t c = 0; c < n; c++) {
        const pf_stage_times *t = parts ? &res[c].parts : &res[c].stages;
        for (uint32_t s = 0; s < t->count; s++) pf_stage_add(rows, t->name[s], 0.0);
    }
}

/* The frame in Hedman 2017 Table 2's columns (medians, ms): the method's
 * own parts of VPL sampling where it reports them (SMC), VPL sampling in
 * all (the update), shadow maps (the VPLs' maps), interleaved shading with
 * the G-buffer (Hedman's "Interl. shading": visibility, attributes, split,
 * assign, accumulate, combine, filter) and the totals. Direct light and
 * compose are not indirect light and not in these columns. */
static void bf__print_hedman_table2(const bf_result *res, uint32_t n)
{
    static const gi_stage_id shading[] = {GI_STAGE_GBUFFER_RASTER, GI_STAGE_GBUFFER_RESOLVE, GI_STAGE_SPLIT,
                                          GI_STAGE_ASSIGN,         GI_STAGE_ACCUMULATE,      GI_STAGE_COMBINE,
                                          GI_STAGE_COMPENSATE,     GI_STAGE_FILTER,          GI_STAGE_UPSAMPLE,
                                          GI_STAGE_TEMPORAL};
    printf("in Hedman 2017 Table 2's columns (ms):\n");
    pf_stage_times rows;
    bf__union(&rows, res, n, 1);
    for (uint32_t s = 0; s < rows.count; s++) {
        printf("  %-26.26s", rows.name[s]);
        for (uint32_t c = 0; c < n; c++) printf("  %8.2f %6s", bf__stage_ms(&res[c].parts, rows.name[s]), "");
        printf("\n");
    }
    const char *labels[] = {"VPL sampling total", "shadow maps", "interleaved shading", "final rendering total",
                            "indirect light total"};
    for (uint32_t l = 0; l < 5; l++) {
        printf("  %-26s", labels[l]);
        for (uint32_t c = 0; c < n; c++) {
            double sampling = bf__stage_ms(&res[c].stages, BF_UPDATE_STAGE);
            double maps = bf__stage_ms(&res[c].stages, BF_MAPS_STAGE), shade = 0.0;
            for (size_t k = 0; k < sizeof shading / sizeof shading[0]; k++)
                shade += bf__stage_ms(&res[c].stages, gi_stage_get(shading[k])->name);
            const double v[] = {sampling, maps, shade, maps + shade, sampling + maps + shade};
            printf("  %8.2f %6s", v[l], "");
        }
        printf("\n");
    }
}

static void bf__print_table(const bf_scene *bs, const pf_scene *scene, const bf_result *res, uint32_t n,
                            uint32_t frames, int moving, uint32_t aa)
{
    float r = BF_LIGHT_RADIUS * pf_v3_length(pf_v3_sub(scene->bounds_max, scene->bounds_min));
    printf("\n%s: %u triangles, point light (%g, %g, %g) %g W/sr", bs->name, scene->tri_count,
           (double)bs->light_pos.x, (double)bs->light_pos.y, (double)bs->light_pos.z, (double)bs->light_intensity);
    if (moving) printf(" moving on a circle of radius %g (%u frames a turn)", (double)r, BF_LIGHT_PERIOD);
    printf("; median of %u frames, ms and share of the frame\n", frames);
    printf("%-28s", "stage");
    for (uint32_t c = 0; c < n; c++) {
        char h[32];
        snprintf(h, sizeof h, "%uV %ut pipe %s", res[c].vpl_budget, res[c].threads, res[c].pipeline ? "on" : "off");
        printf("  %15s", h);
    }
    printf("\n");
    pf_stage_times rows;
    bf__union(&rows, res, n, 0);
    for (uint32_t s = 0; s < rows.count; s++) {
        printf("%-28.28s", rows.name[s]);
        for (uint32_t c = 0; c < n; c++) {
            double ms = bf__stage_ms(&res[c].stages, rows.name[s]);
            printf("  %8.2f %5.1f%%", ms, 100.0 * ms / res[c].frame_ms);
        }
        printf("\n");
    }
    printf("%-28s", "frame (wall clock)");
    for (uint32_t c = 0; c < n; c++) printf("  %8.2f %6s", res[c].frame_ms, "100%");
    printf("\n%-28s", "frames/s");
    for (uint32_t c = 0; c < n; c++) printf("  %8.2f %6s", res[c].fps, "");
    if (aa > 1) { /* --aa N: the rows above hold each per-sample stage's N runs */
        double per[BF_MAX_CONFIGS], once[BF_MAX_CONFIGS];
        for (uint32_t c = 0; c < n; c++) {
            per[c] = once[c] = 0.0;
            for (uint32_t s = 0; s < res[c].stages.count; s++) {
                if (bf__per_sample(res[c].stages.name[s])) per[c] += res[c].stages.ms[s];
                else once[c] += res[c].stages.ms[s];
            }
        }
        char label[64];
        snprintf(label, sizeof label, "per-sample stages, ms/sample");
        printf("\n%-28s", label);
        for (uint32_t c = 0; c < n; c++) printf("  %8.2f %5.1f%%", per[c] / aa, 100.0 * per[c] / aa / res[c].frame_ms);
        printf("\n%-28s", "once-a-frame stages, ms");
        for (uint32_t c = 0; c < n; c++) printf("  %8.2f %5.1f%%", once[c], 100.0 * once[c] / res[c].frame_ms);
    }
    printf("\n%-28s", "VPL management (update) ms");
    for (uint32_t c = 0; c < n; c++)
        printf("  %8.2f %6s", bf__stage_ms(&res[c].stages, BF_UPDATE_STAGE), res[c].pipeline ? "overl." : "serial");
    printf("\n%-28s", "VPLs (set)");
    for (uint32_t c = 0; c < n; c++) printf("  %8u %6s", res[c].vpl_count, "");
    if (moving) {
        printf("\n%-28s", "moved VPLs/frame after 1st");
        for (uint32_t c = 0; c < n; c++) printf("  %8.1f %6s", (double)res[c].moved_after / frames, "");
        printf("\n%-28s", "maps rendered/frame after 1st");
        for (uint32_t c = 0; c < n; c++) printf("  %8.1f %6s", (double)res[c].maps_after / frames, "");
        printf("\n%-28s", "shadow tiles/frame after 1st");
        for (uint32_t c = 0; c < n; c++) printf("  %8.1f %6u", (double)res[c].tiles_after / frames, res[c].tiles_total);
    } else {
        printf("\n%-28s", "moved VPLs after frame 1");
        for (uint32_t c = 0; c < n; c++) printf("  %8llu %6s", (unsigned long long)res[c].moved_after, "");
        printf("\n%-28s", "maps rendered after frame 1");
        for (uint32_t c = 0; c < n; c++) printf("  %8llu %6s", (unsigned long long)res[c].maps_after, "");
    }
    printf("\nfirst frame (all VPLs new):\n%-28s", "  frame (wall clock) ms");
    for (uint32_t c = 0; c < n; c++) printf("  %8.2f %6s", res[c].first_ms, "");
    char maps_row[64];
    snprintf(maps_row, sizeof maps_row, "  %s ms", BF_MAPS_STAGE);
    printf("\n%-28s", maps_row);
    for (uint32_t c = 0; c < n; c++) printf("  %8.2f %5.1f%%", bf__stage_ms(&res[c].first, BF_MAPS_STAGE),
                                            100.0 * bf__stage_ms(&res[c].first, BF_MAPS_STAGE) / res[c].first_ms);
    printf("\n%-28s", "  maps rendered");
    for (uint32_t c = 0; c < n; c++) printf("  %8u %6s", res[c].first_maps, "");
    printf("\n%-28s", "  shadow tiles drawn (of)");
    for (uint32_t c = 0; c < n; c++) printf("  %8u %6u", res[c].first_tiles, res[c].tiles_total);
    printf("\n%-28s", "  ms per map");
    for (uint32_t c = 0; c < n; c++)
        printf("  %8.3f %6s", res[c].first_maps ? bf__stage_ms(&res[c].first, BF_MAPS_STAGE) / res[c].first_maps : 0.0,
               "");
    printf("\n");
    bf__print_hedman_table2(res, n);
    for (uint32_t c = 0; c < n; c++) {
        if (!res[c].have_amdahl) continue;
        char title[160];
        snprintf(title, sizeof title, "\n%s, %u VPLs, pipelining off: Amdahl's law", bs->name, res[c].vpl_budget);
        app_amdahl_print(&res[c].amdahl, title, res[c].threads, "frame (sum of stages)");
        /* the model against a measurement: the 1-thread profile's 2-core
         * prediction beside the 2-thread run's frame */
        for (uint32_t d = 0; d < n && res[c].threads == 1; d++)
            if (res[d].have_amdahl && res[d].threads == 2 && res[d].vpl_budget == res[c].vpl_budget)
                printf("  check: this 1-thread profile predicts %.2f ms on 2 cores; the 2-thread run measured "
                       "%.2f ms\n",
                       bf__amdahl_frame(&res[c].amdahl, 2), res[d].frame_ms);
    }
    if (n && !res[0].have_amdahl)
        printf("(no Amdahl table with pipelining on: the VPL update overlaps the other stages; use --pipeline off)\n");
    /* pipelining gains: consecutive off/on pairs of one VPL count and thread count */
    for (uint32_t c = 0; c + 1 < n; c++) {
        const bf_result *off = &res[c], *on = &res[c + 1];
        if (off->pipeline || !on->pipeline || off->vpl_budget != on->vpl_budget || off->threads != on->threads)
            continue;
        printf("pipelining, %u VPLs, %u thread%s: frame %.2f -> %.2f ms (%+.1f%%), %.2f -> %.2f frames/s\n",
               off->vpl_budget, off->threads, off->threads > 1 ? "s" : "", off->frame_ms, on->frame_ms,
               100.0 * (on->frame_ms - off->frame_ms) / off->frame_ms, off->fps, on->fps);
    }
}

/* Stage names are static literals, but quote them properly anyway. */
static void bf__json_string(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        if (*s == '"' || *s == '\\') printf("\\%c", *s);
        else if ((unsigned char)*s < 0x20) printf("\\u%04x", (unsigned)(unsigned char)*s);
        else putchar(*s);
    }
    putchar('"');
}

static void bf__json_stages(const pf_stage_times *t)
{
    putchar('{');
    for (uint32_t s = 0; s < t->count; s++) {
        if (s) putchar(',');
        bf__json_string(t->name[s]);
        printf(":%.3f", t->ms[s]);
    }
    putchar('}');
}

/* bench frame honours --threads, --frames, --scenes, --isa, --vpls (one
 * count instead of 256 and 2048), --tiles, --method, --param, --visibility,
 * --pipeline, --moving-light, --aa and --taa (and the optional stages'
 * options); any other frame option would silently change what is
 * measured, so it is refused. */
static pf_result bf__check_options(const pf_options *o, pf_error *err)
{
    const char *bad = o->width                 ? "--size"
                      : o->raytrace            ? "--raytrace"
                      : o->direct_only         ? "--direct-only"
                      : o->indirect_only       ? "--indirect-only"
                      : o->no_interleave       ? "--no-interleave"
                      : o->bounces             ? "--bounces"
                      : o->clamp_set           ? "--clamp"
                      : o->area_strata         ? "--area-strata"
                      : o->area_points         ? "--area-points"
                      : o->has_camera          ? "--camera"
                      : o->light_count         ? "--light"
                      : o->dump_dir            ? "--dump-stages"
                      : o->spp                 ? "--spp"
                      : o->out_path            ? "--output"
                      : o->hdr_path            ? "--hdr"
                      : o->print_hash          ? "--hash"
                      : o->exposure != 0.0f    ? "--exposure"
                                               : NULL;
    if (bad)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "bench frame: %s does not apply (it takes --threads, --frames, --scenes, --isa, --vpls, "
                            "--tiles, --method, --param, --visibility, --pipeline, --moving-light, --shadow-size, --filter, "
                            "--filter-test, "
                            "--aa, --taa)",
                            bad);
    /* the method and its parameters now, before minutes of scene loading */
    gi_indirect_options io;
    pf_result r = app_indirect_options(o, &io, err);
    if (r != PF_OK) return r;
    void *state = NULL;
    if ((r = io.method->create(&state, &io.params, err)) != PF_OK) return r;
    io.method->destroy(state);
    return PF_OK;
}

int app_bench_frame(const pf_options *o)
{
    pf_error err;
    pf_isa isa;
    if (bf__check_options(o, &err) != PF_OK) return app_fail(&err);
    if (o->moving_object) return app_bench_frame_moving(o);
    if (pf_isa_resolve(o->isa, &isa, &err) != PF_OK) return app_fail(&err);
    const char *dir = o->scenes_dir ? o->scenes_dir : "../shared/scenes";
    const char *method = o->method ? o->method : "ir";
    const char *visibility = o->visibility_raytrace ? "raytrace"
                             : o->visibility_ism    ? "ism"
                             : o->visibility_slope  ? "paraboloid-slope"
                                                    : "paraboloid";
    uint32_t frames = o->frames ? o->frames : 15;
    const uint32_t aa = o->aa ? o->aa : 1;
    uint32_t thread_list[2] = {1, 2}, nthreads = 2;
    if (o->threads) thread_list[0] = o->threads, nthreads = 1;
    if (o->threads > pf_jobs_core_count()) {
        fprintf(stderr, "softgi: bench frame: --threads %u: this machine has %u cores (the Amdahl table predicts "
                        "more)\n",
                o->threads, pf_jobs_core_count());
        return 2;
    }
    uint32_t vpl_list[2] = {256, 2048}, nvpls = 2;
    if (o->vpls) vpl_list[0] = o->vpls, nvpls = 1;
    uint32_t nmodes = o->pipeline >= 0 ? 1 : 2;
    uint32_t tn = o->tiles_n ? o->tiles_n : 4, tm = o->tiles_m ? o->tiles_m : 4;
    const uint32_t shadow = o->shadow_size ? o->shadow_size : RS_SHADOW_DEFAULT_SIZE;
    const char *filter = o->filter ? o->filter : "box";
    const int default_filter = !strcmp(filter, "box");
    uint32_t per_scene = nvpls * nthreads * nmodes;
    bf_result results[BF_SCENES * BF_MAX_CONFIGS];
    printf("softgi bench frame: %dx%d, isa %s, raster path %s, method %s, visibility %s, %ux%u tiles, %s filter, "
           "indirect light at 1/%u resolution%s,\n%s point light (shadow map %u^2 per face%s), pipelining %s, 1 warm-up "
           "frame then median of %u\n",
           BF_W, BF_H, pf_isa_name(isa), rs_simd_name(rs_simd_for_isa(isa)), method, visibility, tn, tm, filter,
           gi_indirect_scale_for(o->indirect_scale, BF_W, BF_H),
           o->indirect_scale == GI_INDIRECT_SCALE_AUTO ? " (--indirect-scale auto)" : "",
           o->moving_light ? "moving" : "static", shadow, shadow == RS_SHADOW_DEFAULT_SIZE ? "" : ", --shadow-size",
           o->pipeline < 0 ? "off and on" : o->pipeline ? "on" : "off", frames);
    if (aa > 1 || o->taa)
        printf("anti-aliasing: %u sample%s per pixel (a per-sample stage's row sums its %u runs), temporal "
               "anti-aliasing %s\n",
               aa, aa > 1 ? "s" : "", aa, o->taa ? "on" : "off");
    fflush(stdout);
    for (size_t k = 0; k < BF_SCENES; k++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, k_scenes[k].file);
        pf_scene scene;
        pf_gltf_options go = {.ignore_textures = 1}; /* textures ignored: albedo = material factor */
        if (pf_gltf_load(&scene, path, &go, &err) != PF_OK) {
            fprintf(stderr, "softgi: bench frame: %s (give the folder with --scenes)\n", err.message);
            return 1;
        }
        bf_result *res = &results[k * per_scene];
        pf_result r = bf__scene(&scene, &k_scenes[k], vpl_list, nvpls, thread_list, nthreads, isa, o, frames, res, &err);
        if (r == PF_OK) bf__print_table(&k_scenes[k], &scene, res, per_scene, frames, o->moving_light, aa);
        pf_scene_free(&scene);
        if (r != PF_OK) {
            fprintf(stderr, "softgi: bench frame: %s: %s\n", k_scenes[k].name, err.message);
            return pf_result_exit_code(r);
        }
        fflush(stdout);
    }
    uint32_t n = (uint32_t)BF_SCENES * per_scene;
    int static_ok = 1;
    for (uint32_t i = 0; i < n; i++) static_ok &= results[i].moved_after == 0 && results[i].maps_after == 0;
    if (o->moving_light)
        printf("\nmoving light: the VPL counts above say how many VPLs moved and maps were re-rendered per frame\n");
    else
        printf("\nstatic light: %s\n", static_ok ? "no VPL moved and no map was re-rendered after the first frame"
                                                 : "WARNING: VPLs moved or maps were re-rendered after the first frame");

    /* the targets, per scene: the 2-thread run of a VPL count with one,
     * pipelining off where both were run */
    const bf_result *target_of[BF_SCENES];
    for (size_t k = 0; k < BF_SCENES; k++) {
        target_of[k] = NULL;
        for (uint32_t i = 0; i < per_scene; i++) {
            const bf_result *r = &results[k * per_scene + i];
            if (r->threads == BF_TARGET_THREADS && bf__target(method, o->moving_light, visibility, r->vpl_budget,
                                                              k_scenes[k].name) > 0.0 &&
                (!target_of[k] || !r->pipeline))
                target_of[k] = r;
        }
    }
    printf("targets (1024x768, %u threads; IR 256 VPLs static light >= 40 frames/s, moving light: IIR >= 30, SMC "
           ">= 25, TCAS --visibility ism >= 15, SMC 2048 VPLs on the conference room >= 10):\n",
           BF_TARGET_THREADS);
    for (size_t k = 0; k < BF_SCENES; k++) {
        const bf_result *t = target_of[k];
        if (t) {
            double want = bf__target(method, o->moving_light, visibility, t->vpl_budget, k_scenes[k].name);
            printf("  %-11s %.2f frames/s (%.2f ms, %u VPLs, pipeline %s) against %.0f: %s%s\n", k_scenes[k].name,
                   t->fps, t->frame_ms, t->vpl_budget, t->pipeline ? "on" : "off", want,
                   t->fps >= want ? "met" : "NOT met",
                   shadow != RS_SHADOW_DEFAULT_SIZE ? " (not the default frame: --shadow-size)"
                   : !default_filter                ? " (not the default frame: --filter)"
                                                    : "");
        } else
            printf("  %-11s no target for this case (%s, %s light, %s visibility)\n", k_scenes[k].name, method,
                   o->moving_light ? "moving" : "static", visibility);
    }

    printf("json: {\"bench\":\"frame\",\"width\":%d,\"height\":%d,\"isa\":\"%s\",\"method\":",
           BF_W, BF_H, pf_isa_name(isa));
    bf__json_string(method);
    printf(",\"params\":[");
    for (uint32_t i = 0; i < o->param_count; i++) {
        if (i) putchar(',');
        bf__json_string(o->params[i]);
    }
    printf("],\"visibility\":\"%s\",\"pipeline\":\"%s\",\"moving_light\":%s,\"shadow_size\":%u,\"filter\":\"%s\","
           "\"tiles\":[%u,%u],\"frames\":%u,\"aa\":%u,\"taa\":%u,\"static_ok\":%s,\"results\":[",
           visibility, o->pipeline < 0 ? "both" : o->pipeline ? "on" : "off", o->moving_light ? "true" : "false",
           shadow, filter, tn, tm, frames, aa, o->taa, static_ok ? "true" : "false");
    for (uint32_t i = 0; i < n; i++) {
        const bf_result *r = &results[i];
        printf("%s{\"scene\":\"%s\",\"vpls\":%u,\"vpl_count\":%u,\"threads\":%u,\"pipeline\":%s,\"frame_ms\":%.3f,"
               "\"fps\":%.3f,\"vpl_update_ms\":%.3f,\"stages_ms\":",
               i ? "," : "", r->scene, r->vpl_budget, r->vpl_count, r->threads, r->pipeline ? "true" : "false",
               r->frame_ms, r->fps, bf__stage_ms(&r->stages, BF_UPDATE_STAGE));
        bf__json_stages(&r->stages);
        printf(",\"moved_after_first\":%llu,\"maps_after_first\":%llu,\"shadow_tiles_after_first\":%llu,"
               "\"shadow_tiles_first\":%u,\"shadow_tiles_total\":%u,\"first_frame_ms\":%.3f,"
               "\"first_frame_maps\":%u,\"first_frame_moved\":%u,\"first_frame_stages_ms\":",
               (unsigned long long)r->moved_after, (unsigned long long)r->maps_after,
               (unsigned long long)r->tiles_after, r->first_tiles, r->tiles_total, r->first_ms, r->first_maps,
               r->first_moved);
        bf__json_stages(&r->first);
        printf(",\"method_parts_ms\":");
        bf__json_stages(&r->parts);
        if (r->have_amdahl) { /* the job profile's sums over the stages (app_amdahl_print's "frame" row) */
            const app_amdahl *am = &r->amdahl;
            double serial = 0.0, work = 0.0, span = 0.0;
            for (uint32_t s = 0; s < am->count; s++) serial += am->serial[s], work += am->work[s], span += am->span[s];
            printf(",\"amdahl\":{\"serial_ms\":%.3f,\"work_ms\":%.3f,\"span_ms\":%.3f,\"predicted_ms\":{", serial,
                   work, span);
            for (int k = 0; k < PF_JOBS_PROFILE_CORES; k++)
                printf("%s\"%u\":%.3f", k ? "," : "", pf_jobs_profile_cores[k], bf__amdahl_frame(am, pf_jobs_profile_cores[k]));
            printf("}}");
        }
        printf("}");
    }
    printf("],\"target\":{\"threads\":%u", BF_TARGET_THREADS);
    for (size_t k = 0; k < BF_SCENES; k++) {
        const bf_result *t = target_of[k];
        if (!t) {
            printf(",\"%s\":\"not measured\"", k_scenes[k].name);
            continue;
        }
        double want = bf__target(method, o->moving_light, visibility, t->vpl_budget, k_scenes[k].name);
        printf(",\"%s\":{\"vpls\":%u,\"fps\":%.0f,\"verdict\":\"%s\"}", k_scenes[k].name, t->vpl_budget, want,
               t->fps >= want ? "met" : "not met");
    }
    printf("}}\n");
    return 0;
}
