/* pf_cli: command-line parsing for the softgi program.
 *
 * Every value is checked strictly (whole token consumed, finite, in range);
 * a bad value gives PF_ERR_ARGUMENT with a message naming the option and
 * what was expected, and the program exits with status 2.
 *
 * One help text per command: `softgi COMMAND --help` lists exactly the
 * options COMMAND takes (pf_cli_usage_command), `softgi --help` the
 * commands (pf_cli_usage). An option the command does not take is refused
 * with one line naming the option, the command and the commands that take
 * it, e.g. "--spp does not apply to render (--spp: only reference and
 * sequence take it; see softgi render --help)" (exit 2). Both come from one
 * table in pf_cli.c (option -> value, commands, help). `bench raster` and
 * `bench frame` count as two commands. compare and evaluate parse their own
 * options (app_compare.c, app_evaluate.c).
 *
 * Scene overrides (for scenes that lack a camera or lights):
 *   --camera ex,ey,ez:tx,ty,tz:fovy_deg
 *   --light point:x,y,z:r,g,b:I                  (I in W/sr)
 *   --light spot:x,y,z:dx,dy,dz:inner_deg,outer_deg:r,g,b:I
 *   --light dir:dx,dy,dz:r,g,b:E                 (E in W/m^2)
 * --light may repeat; given lights replace the scene's own lights. Without
 * them a scene gets an automatic camera and light (src/scene/pf_defaults.h).
 * --exposure takes STOPS or "auto" (exposure_auto; the PNG only).
 * --time SECONDS [--animation NAME|INDEX] (render, reference) poses the
 * scene's glTF animations (pf_anim.h) after the automatic camera and light
 * are chosen on the static pose. */
#ifndef PF_CLI_H
#define PF_CLI_H

#include <stdint.h>
#include <stdio.h>

#include "pf_isa.h"
#include "pf_scene.h"

#define PF_CLI_MAX_LIGHTS 64

/* The commands pf_cli parses, as bits of the set of commands an option
 * applies to. */
#define PF_CLI_RENDER (1u << 0)
#define PF_CLI_VIEW (1u << 1)
#define PF_CLI_REFERENCE (1u << 2)
#define PF_CLI_SEQUENCE (1u << 3)
#define PF_CLI_BENCH_RASTER (1u << 4)
#define PF_CLI_BENCH_FRAME (1u << 5)

/* --dump-format bits (0: not given, the pictures only) */
#define PF_CLI_DUMP_PNG 1u
#define PF_CLI_DUMP_EXR 2u

typedef struct pf_options {
    const char *command;    /* "render", "view", "reference", "sequence" or "bench" (compare and evaluate parse
                               their own arguments) */
    const char *scene_path; /* render: NULL = the embedded default scene (Cornell box); bench: what to bench;
                               sequence: the sequence file */
    const char *scenes_dir; /* bench: folder of the shared scenes (default ../shared/scenes) */
    uint32_t frames;        /* bench: repetitions per measurement (0: default 15); view: frames to show */
    const char *frames_arg; /* --frames as given: N (view, bench) or A:B (sequence), parsed by command */
    /* sequence --frames A:B: render frames A..B-1 only (zero-based, B
     * excluded, as Python's A:B; see pf_cli_parse_frame_range) */
    int frame_range;              /* --frames given to sequence */
    uint32_t frame_first, frame_end; /* frame_end PF_CLI_FRAMES_END: to the last frame */
    uint32_t shadow_size;   /* direct-light shadow map texels per side (0: 1024) */
    uint32_t area_strata;   /* ray-traced area-light samples: N x N per pixel (0: default 4) */
    uint32_t area_points;   /* rasterized area light: K emitter points with paraboloid maps (0: default 32) */
    /* many-light frame and the reference path tracer */
    int indirect_only, direct_only;
    int no_interleave;       /* every pixel sees every VPL */
    int visibility_raytrace; /* --visibility raytrace: Embree shadow rays to VPLs */
    uint32_t vpls;           /* VPL budget (0: 256) */
    uint32_t tiles_n, tiles_m; /* interleaved tiles (0: 4x4) */
    float clamp;             /* bounded geometry term b = clamp / diag^2 (default 400); 0: off */
    int clamp_set;           /* --clamp given */
    int refine_set;          /* --temporal, --vpl-cycle, --cycle-maps or --taa given (view: no progressive default) */
    const char *method;      /* VPL method (NULL: "ir") */
    uint32_t param_count;    /* --param KEY=VALUE (repeatable): method parameters */
    const char *params[32];
    int visibility_ism;      /* --visibility ism: imperfect shadow maps */
    int visibility_slope;    /* --visibility paraboloid-slope: exact maps, slope-scaled bias */
    uint32_t ism_res;        /* --ism-res N: ISM texels per side (0: gi_ism.h default) */
    uint32_t ism_points;     /* --ism-points N: ISM points per frame (0: default) */
    float ism_bias;          /* --ism-bias S: ISM bias scale (0: default) */
    uint32_t bounces;        /* light bounces (0: 3) */
    const char *filter;      /* "box" (default), "bilateral", "gaussian", "atrous", "none" */
    const char *dump_dir;    /* --dump-stages DIR */
    uint32_t dump_format;    /* --dump-format: PF_CLI_DUMP_* bits; 0: not given (png) */
    const char *screenshot_path; /* view: --screenshot FILE (saved after --frames N) */
    int pipeline;            /* --pipeline on|off: 1, 0; -1 when not given (the command's default) */
    uint32_t indirect_scale; /* --indirect-scale N|auto: indirect light at 1/N resolution (0: auto,
                                GI_INDIRECT_SCALE_AUTO) */
    uint32_t temporal;       /* --temporal N: temporal accumulation over up to N frames (0: off) */
    uint32_t vpl_cycle;      /* --vpl-cycle C: C slices of VPLs shaded in turn (0: off) */
    uint32_t cycle_maps;     /* --cycle-maps B: the progressive warm-up, B maps a frame ahead (0: off) */
    int compensate;          /* --compensate on: screen-space clamp compensation */
    int filter_distance;     /* --filter-test distance: Laine's |p2 - p| < alpha instead of the plane test */
    int no_light_paths;      /* reference --light-paths off: NEE alone */
    uint32_t aa;             /* --aa N: jittered samples per pixel (0: 1, the pixel centres; gi_aa.h) */
    uint32_t taa;            /* --taa N: temporal anti-aliasing over up to N frames (0: off) */
    int moving_light;        /* bench frame: --moving-light (the light circles, every method must update) */
    int moving_object;       /* bench frame: --moving-object (an object moves in Sibenik: app_bench_moving.c) */
    float para_lod;          /* bench raster: --para-lod F, paraboloid maps from levels of detail (0: exact) */
    uint32_t spp;            /* reference: samples per pixel (0: 64) */
    uint32_t track_spp;      /* sequence --reference --track-spp N: tracked pixels with N samples (0: --spp) */
    int reuse_frames;        /* sequence --reference --reuse-frames: keep the folder's images, redo tracked pixels */
    int reference;           /* sequence --reference: path-traced frames (gi_reference) instead of the VPL frame */
    const char *out_path;   /* -o: .png, .exr or .pfm (pf_imageio_outputs_resolve); NULL: out/<scene name>.png;
                               sequence: the frames' folder */
    const char *hdr_path;   /* --hdr: the linear image (.exr or .pfm) beside a PNG; NULL: PNG path with .pfm */
    uint32_t width, height; /* 0: default 640x480 */
    uint32_t threads;       /* 0: number of cores */
    uint64_t max_memory;    /* --max-memory: memory budget in bytes (0: half the machine's; pf_budget.h) */
    pf_isa isa;
    float exposure; /* stops; PNG scale 2^exposure */
    int exposure_auto; /* --exposure auto: picked from the image (pf_defaults_exposure); exposure is then 0 */
    int time_set;           /* --time SECONDS: the scene's animations posed at `time` (render, reference) */
    float time;             /* seconds, 0..PF_ANIM_MAX_TIME */
    const char *animation;  /* --animation NAME|INDEX (with --time); NULL: every animation together */
    int has_camera;
    pf_vec3 camera_eye, camera_target;
    float camera_fovy_deg;
    uint32_t light_count;
    pf_light lights[PF_CLI_MAX_LIGHTS];
    int print_hash;
    int raytrace; /* --raytrace: Embree primary rays for the G-buffer and ray-traced direct light */
    int quiet;
    int help, version;
} pf_options;

/* Parses argv[1..argc). Zero-initialises *o first. With --help or
 * --version nothing but the values and the command name is checked. */
pf_result pf_cli_parse(pf_options *o, int argc, char **argv, pf_error *err);
/* `softgi --help`: the commands. */
void pf_cli_usage(FILE *out);
/* `softgi COMMAND --help`: COMMAND's usage and options (command NULL: the
 * command list; bench without raster or frame: both). PF_ERR_ARGUMENT for
 * an unknown command. */
pf_result pf_cli_usage_command(FILE *out, const char *command, const char *subject, pf_error *err);

/* The command bit of COMMAND [SUBJECT] ("bench", "frame"); 0 if none. */
uint32_t pf_cli_command_bit(const char *command, const char *subject);
/* The commands (PF_CLI_* bits) that take `option` ("--spp", "-o"); 0 for an
 * unknown option. */
uint32_t pf_cli_option_commands(const char *option);
/* The i-th option's long name, i = 0, 1, ...; NULL past the last. */
const char *pf_cli_option_name(uint32_t i);

/* "A:B" (frames A..B-1: zero-based like frame_NNNN, B excluded, so the
 * ranges 0:10, 10:20, ... tile a sequence), "A:" (A to the end), ":B"
 * (0..B-1) or "N" (frame N alone, N:N+1: one frame per array task):
 * digits only, A < B, both below 1000000. `opt` names the option
 * in the message. *end is PF_CLI_FRAMES_END for an open end. */
#define PF_CLI_FRAMES_END UINT32_MAX
pf_result pf_cli_parse_frame_range(const char *opt, const char *val, uint32_t *first, uint32_t *end, pf_error *err);
/* The frame range against a sequence of `frames` frames: PF_ERR_ARGUMENT
 * when A is not one of its frames or B is past its end; an open end
 * becomes `frames`. */
pf_result pf_cli_check_frame_range(const char *opt, uint32_t frames, uint32_t first, uint32_t *end, pf_error *err);

/* Parsers used by the CLI, exposed for tests. */
pf_result pf_cli_parse_light(const char *spec, pf_light *out, pf_error *err);
pf_result pf_cli_parse_camera(const char *spec, pf_vec3 *eye, pf_vec3 *target, float *fovy_deg, pf_error *err);

#endif
