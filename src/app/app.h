/* app: the softgi program's commands. main.c parses the command line and
 * dispatches; each command lives in its own app_*.c. */
#ifndef APP_H
#define APP_H

#include "pf_cli.h"
#include "pf_defaults.h"
#include "softgi/softgi.h"

/* Prints "softgi: <message>" and returns the exit status for err->code. */
int app_fail(const pf_error *err);

/* Loads the scene render and reference draw (SCENE or the embedded Cornell
 * box), applies --camera and --light, validates it, and prints its load
 * warnings; `stem` gets the output base name ("cornell-box"). Without a
 * camera (file, --camera) it frames the scene, and without a light or an
 * emitter it adds a point light at the camera (pf_defaults.h), each said
 * in one "softgi: note:" line as a --camera / --light value to copy. On
 * failure the scene is freed. */
pf_result app_scene_load(const pf_options *o, pf_scene *scene, pf_camera *camera, char *stem, size_t stem_size,
                         pf_error *err);
/* The output base name: SCENE's file name without its extension, or
 * "cornell-box" for the built-in scene. */
void app_stem(const pf_options *o, char *stem, size_t size);
struct pf_sequence;
struct pf_anim;
/* app_scene_load for `softgi sequence` (and so `softgi evaluate`): the
 * sequence file's emitters, and its "lights": [], are applied
 * (pf_sequence_apply_emitters) right after the scene is read, before
 * --light, validation and the automatic camera and light. seq may be NULL.
 * With `anim` not NULL the scene's animations are kept there (pf_anim.h,
 * freed by the caller; empty on failure). app_scene_load and this both
 * pose the scene at --time (api_scene_pose) after the automatic camera and
 * light are chosen on the static pose. */
pf_result app_scene_load_sequence(const pf_options *o, const struct pf_sequence *seq, pf_scene *scene,
                                  struct pf_anim *anim, pf_camera *camera, char *stem, size_t stem_size,
                                  pf_error *err);

/* The options as the library's frame description (softgi.h): the image
 * width x height (0 x 0: 640 x 480), threads, ISA, budget, the VPL method
 * and every frame option (--shadow-size ... --aa, --taa). Pointers point
 * into `o`. PF_ERR_ARGUMENT when --visibility was given as both ism and
 * raytrace (with indirect light). `softgi render` passes it to
 * softgi_create; app_frame_init, app_budget_check and app_indirect_options
 * pass it to the library's set-up (src/api/api_setup.h). */
pf_result app_desc(const pf_options *o, uint32_t width, uint32_t height, softgi_desc *d, pf_error *err);

/* The "softgi: note:" lines (unless -q) of the automatic camera (with the
 * reasons pf_defaults_camera gives) and light of scene `name`, each with
 * the --camera / --light value that gives the same image. */
void app_note_camera(const pf_options *o, const char *name, const pf_default_camera *dc, const char *spec);
void app_note_light(const pf_options *o, const char *name, const char *spec, float median);

/* The PNG's exposure in stops: --exposure STOPS, or for --exposure auto
 * the stops pf_defaults_exposure picks from the linear image (said in one
 * note unless -q). Only the PNG and the pictures change, never the linear
 * image. */
float app_exposure(const pf_options *o, const float *rgb, uint32_t width, uint32_t height);

/* One "softgi: note:" line (unless -q) when the image, at `exposure`, is
 * nearly black (pf_defaults_nearly_black), suggesting --exposure auto or
 * a brighter --light. */
void app_hint_dark(const pf_options *o, const float *rgb, uint32_t width, uint32_t height, float exposure);

struct pf_rt;
struct pf_jobs;
struct pf_stage_times;
/* What render and reference both start with: the image size, threads and
 * ISA the options give, the scene with its camera (app_scene_load), Embree
 * and the job system. */
typedef struct app_setup {
    uint32_t width, height, threads;
    pf_isa isa;
    pf_scene scene;
    pf_camera camera;
    char stem[256];
    struct pf_rt *rt;
    struct pf_jobs *jobs;
} app_setup;
/* Fills `s`, timing "load scene" and "embree build" into `t`. On failure
 * nothing is left to free. */
pf_result app_setup_begin(const pf_options *o, app_setup *s, struct pf_stage_times *t, pf_error *err);
void app_setup_end(app_setup *s);

struct gi_reference_options;
/* The path tracer's options given on the command line (--spp, --bounces,
 * --direct-only, --indirect-only), for reference and sequence --reference. */
void app_reference_options(const pf_options *o, struct gi_reference_options *ro);

struct gi_indirect_options;
/* The many-light options given on the command line (--method, --vpls, ...). */
pf_result app_indirect_options(const pf_options *o, struct gi_indirect_options *io, pf_error *err);

/* The memory budget (--max-memory, pf_budget.h) against the scene as
 * loaded plus what the command will allocate: with `frame`, a frame of
 * width x height (gi_frame_memory_estimate: planes, shadow maps, VPL maps,
 * with `indirect` the VPLs --vpls asks for); without, the path tracer's
 * image. Refused with one line before anything is allocated. */
pf_result app_budget_check(const pf_options *o, const pf_scene *scene, uint32_t width, uint32_t height, int frame,
                           int indirect, pf_error *err);

/* The progressive refinement's VPL slices (softgi view's default and
 * render --frames N, docs/view.md): API_REFINE_SLICES, fewer where their 16-bit maps of
 * para_res^2 (0: the default 128) would pass 256 MB or the set
 * GI_INDIRECT_MAX_SET VPLs, 0 (the temporal history alone) for MIR, whose
 * update runs over the whole cycled set every frame (SMC's runs over one
 * chain, gi_smc.c "VPL cycling"), and for imperfect shadow maps, which
 * cycling refuses (at most API_REFINE_SLICES). The memory
 * budget comes after (api_refine_fit). */
#define APP_REFINE_MAP_BYTES ((uint64_t)256 << 20)
uint32_t app_refine_slices(const char *method, int ism, int raytrace, uint32_t vpls, uint32_t para_res);

struct gi_frame;
struct rs_context;
/* The frame the command line describes, on a loaded scene: gi_frame_create
 * with --shadow-size, --area-strata/--area-points and the indirect stages
 * (app_indirect_options) unless --direct-only or `indirect` is 0
 * (sequence --reference). render, sequence and view all build their frame
 * here, so each option means the same in each. On failure nothing is left
 * to free. */
pf_result app_frame_init(const pf_options *o, struct gi_frame *f, const pf_scene *scene, const struct pf_rt *rt,
                         struct rs_context *raster, struct pf_jobs *jobs, const pf_camera *camera, uint32_t width,
                         uint32_t height, int indirect, pf_error *err);

/* `softgi render`: load, override, build, render, write. Returns the exit status. */
int app_render(const pf_options *opts);

/* ---------------------------------------------------------------- Amdahl (bench)
 *
 * Where each stage's time goes between one thread and many, from the job
 * profile (pf_jobs.h, "profile"): per stage its wall time, its serial part
 * (the calling thread's CPU time outside parallel-fors: set-up,
 * reductions, single-threaded code), its parallel work (item time summed over items and threads), its
 * span (each job's longest item, summed) and its predicted time on N cores,
 * serial + the jobs' predicted time on N cores. Both benches print this
 * table (app_bench_frame.c defines it). */
#include "pf_jobs.h"
#include "pf_timer.h"

typedef struct app_amdahl {
    uint32_t count;
    const char *name[PF_MAX_STAGES]; /* static strings */
    double wall[PF_MAX_STAGES], serial[PF_MAX_STAGES], work[PF_MAX_STAGES], span[PF_MAX_STAGES];
    double predicted[PF_MAX_STAGES][PF_JOBS_PROFILE_CORES]; /* serial included */
} app_amdahl;

/* Reads the profile at stage boundaries into `out` (the caller has turned
 * the pool's profile on, pf_jobs_profile_enable): app_amdahl_begin clears
 * `out` and installs a pf_stage_hook, so
 * every pf_stage_add on this thread (gi_frame's stages) closes a stage
 * interval under its name; app_amdahl_mark closes one by hand,
 * app_amdahl_skip starts the next interval now without recording, and
 * app_amdahl_end closes the rest under `tail` (when it holds any time or
 * work) and puts the previous hook back. Intervals with a name already
 * recorded add to it. */
typedef struct app_amdahl_probe {
    pf_jobs *jobs;
    app_amdahl *out;
    double t, cpu; /* when the interval began: s, and this thread's CPU time, ms */
    pf_jobs_profile p;
    pf_stage_hook old;
} app_amdahl_probe;
void app_amdahl_begin(app_amdahl_probe *pr, pf_jobs *jobs, app_amdahl *out);
void app_amdahl_mark(app_amdahl_probe *pr, const char *name);
void app_amdahl_skip(app_amdahl_probe *pr);
void app_amdahl_end(app_amdahl_probe *pr, const char *tail);
/* The median over frames[0..n) of every figure, stage by stage (stages
 * matched by name, in the order they first appear). */
void app_amdahl_median(app_amdahl *out, const app_amdahl *frames, uint32_t n);
/* The table on stdout: one row per stage, then the sum (`sum_label`), the
 * predicted speed-ups on 2, 8, 16 and 64 cores and the serial share of
 * the 1-core time (serial + work). `title` heads it; `threads` is the
 * measured run's. */
void app_amdahl_print(const app_amdahl *a, const char *title, uint32_t threads, const char *sum_label);

/* `softgi bench raster`: per-stage medians of the rasterizer passes against
 * Embree, as a table and one JSON line. Returns the exit status. */
int app_bench_raster(const pf_options *opts);

/* `softgi sequence FILE.json`: renders a camera/light sequence to a folder,
 * keeping VPL state between frames (app_sequence.c). */
int app_sequence(const pf_options *opts);

/* `softgi bench frame`: per-stage medians of the whole frame (app_bench_frame.c). */
int app_bench_frame(const pf_options *opts);
/* `softgi bench frame --moving-object`: a moving object's cost (app_bench_moving.c). */
int app_bench_frame_moving(const pf_options *opts);

/* `softgi reference`: the path-traced reference (gi_reference). */
int app_reference(const pf_options *opts);

/* `softgi compare`: metrics between renders and references, with a plot.
 * Parses its own arguments (argv[1] == "compare"). */
int app_compare(int argc, char **argv);

/* `softgi view [SCENE]`: the interactive GLFW viewer and frame-stage
 * stepper (app_view.c). */
int app_view(const pf_options *opts);

/* `softgi evaluate`: Hedman 2017 Table 1 on our sequences, every method
 * against per-frame references (app_evaluate.c). Parses its own arguments. */
int app_evaluate(int argc, char **argv);

/* `softgi evaluate --quality` (app_quality.c): every
 * method at its paper defaults, with clamp compensation and with temporal
 * accumulation, on a static view of each scene, against a path-traced
 * reference and a many-VPL proxy of the indirect light: a Markdown table of
 * mean relative error, energy ratio and frame time. The strings are
 * evaluate's arguments as given (NULL: not given, the default); argc and
 * argv are the command line, quoted in the table. */
typedef struct app_quality_args {
    const char *const *methods; /* --methods entries (METHOD+KEY=VALUE...); none: ir, iir, smc, mir, invtm,
                                   tcas, ssvp */
    uint32_t method_count;
    const char *const *params; /* --param KEY=VALUE, to the methods that know KEY */
    uint32_t param_count;
    const char *out;        /* the cache (OUT/quality/SCENE) and OUT/quality.md */
    const char *table;      /* --table FILE: the table here too */
    const char *scene_list; /* --quality-scenes (default cornell,sibenik) */
    const char *scenes_dir; /* --scenes (default SOURCE/../shared/scenes) */
    const char *size, *spp, *vpls, *proxy_vpls, *threads, *isa;
    int rerun_reference, quiet;
} app_quality_args;
int app_quality(const app_quality_args *a, int argc, char **argv);

#endif
