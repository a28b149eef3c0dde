/* pf_cli: strict command-line parsing (see pf_cli.h).
 *
 * One table (k_options) says, for every option, its value, the commands
 * that take it and its help text; the per-command help and the refusal of
 * an option a command does not take are both read from it, so they cannot
 * disagree. An option may have several rows when its help differs by
 * command (-o is a file for render and a folder for sequence); the rows of
 * one name share its id and whether it takes a value. */
#include "pf_cli.h"
#include "pf_anim.h"
#include "pf_budget.h"
#include "pf_imageio.h"
#include "gi_aa.h"
#include "gi_indirect.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---------------------------------------------------------------- the tables */

typedef enum pf__opt_id {
    PF__OPT_OUTPUT, PF__OPT_HDR, PF__OPT_SIZE, PF__OPT_THREADS, PF__OPT_ISA, PF__OPT_EXPOSURE, PF__OPT_CAMERA,
    PF__OPT_LIGHT, PF__OPT_SHADOW_SIZE, PF__OPT_MAX_MEMORY, PF__OPT_AREA_STRATA, PF__OPT_AREA_POINTS,
    PF__OPT_INDIRECT_ONLY, PF__OPT_DIRECT_ONLY, PF__OPT_VPLS, PF__OPT_METHOD, PF__OPT_BOUNCES, PF__OPT_TILES,
    PF__OPT_NO_INTERLEAVE, PF__OPT_CLAMP, PF__OPT_FILTER, PF__OPT_FILTER_TEST, PF__OPT_VISIBILITY, PF__OPT_ISM_RES,
    PF__OPT_ISM_POINTS, PF__OPT_ISM_BIAS, PF__OPT_PARAM, PF__OPT_DUMP_STAGES, PF__OPT_DUMP_FORMAT, PF__OPT_PIPELINE, PF__OPT_SPP,
    PF__OPT_REFERENCE, PF__OPT_TRACK_SPP, PF__OPT_REUSE_FRAMES, PF__OPT_RAYTRACE, PF__OPT_HASH, PF__OPT_QUIET,
    PF__OPT_FRAMES, PF__OPT_SCREENSHOT, PF__OPT_SCENES, PF__OPT_MOVING_LIGHT, PF__OPT_MOVING_OBJECT, PF__OPT_PARA_LOD, PF__OPT_HELP, PF__OPT_VERSION,
    PF__OPT_INDIRECT_SCALE, PF__OPT_TEMPORAL, PF__OPT_VPL_CYCLE, PF__OPT_CYCLE_MAPS, PF__OPT_COMPENSATE, PF__OPT_QUALITY, PF__OPT_AA, PF__OPT_TAA,
    PF__OPT_TIME, PF__OPT_ANIMATION, PF__OPT_LIGHT_PATHS,
    PF__OPT_COUNT
} pf__opt_id;

typedef struct pf__opt {
    pf__opt_id id;
    const char *name;  /* "--size" */
    const char *alias; /* "-o", or NULL */
    const char *value; /* what follows it ("WxH"); NULL: a flag */
    uint32_t commands; /* PF_CLI_* bits of the commands that take it */
    const char *help;  /* lines separated by '\n' */
    const char *note;  /* added to the refusal (may be NULL) */
} pf__opt;

#define R PF_CLI_RENDER
#define V PF_CLI_VIEW
#define F PF_CLI_REFERENCE
#define S PF_CLI_SEQUENCE
#define BR PF_CLI_BENCH_RASTER
#define BF PF_CLI_BENCH_FRAME
#define SCENE (R | V | F | S) /* the commands that load a scene and render it */
#define FRAME (R | V | S)     /* the commands that build the many-light frame (app_frame_init) */
#define ALL (SCENE | BR | BF)

/* In help order. */
static const pf__opt k_options[] = {
    {PF__OPT_OUTPUT, "--output", "-o", "FILE", R,
     "by extension: FILE.png writes the PNG and the linear image\nbeside it (FILE.pfm, or --hdr); FILE.exr or "
     "FILE.pfm writes only\nthe linear image (default out/<scene>.png)",
     NULL},
    {PF__OPT_OUTPUT, "--output", "-o", "FILE", F,
     "by extension: FILE.png writes the PNG and the linear image\nbeside it (FILE.pfm, or --hdr); FILE.exr or "
     "FILE.pfm writes only\nthe linear image (default out/<scene>-reference.png)",
     NULL},
    {PF__OPT_OUTPUT, "--output", "-o", "DIR", S, "the frames' folder (default: the file's \"output\" under out/)",
     NULL},
    {PF__OPT_HDR, "--hdr", NULL, "FILE", R | F,
     "the linear image beside -o NAME.png: FILE.exr or FILE.pfm\n(default: the PNG's name with .pfm)", NULL},
    {PF__OPT_SIZE, "--size", NULL, "WxH", R | V | F, "image size (default 640x480)", NULL},
    {PF__OPT_SIZE, "--size", NULL, "WxH", S, "image size (default: the file's \"size\", else 640x480)", NULL},
    {PF__OPT_THREADS, "--threads", NULL, "N", SCENE, "worker threads incl. the main one (default: cores)", NULL},
    {PF__OPT_THREADS, "--threads", NULL, "N", BR | BF,
     "measure only N threads, at most the cores (default: 1 and 2);\nthe Amdahl table predicts 8, 16 and 64 cores",
     NULL},
    {PF__OPT_ISA, "--isa", NULL, "auto|sse2|sse4.2|avx2|avx512", ALL, "pin Embree's and softgi's SIMD ISA (default auto)",
     NULL},
    {PF__OPT_EXPOSURE, "--exposure", NULL, "STOPS|auto", SCENE,
     "PNG exposure, 2^STOPS before Reinhard (default 0); auto: the\nlit pixels' log-average to 18% grey (printed); "
     "the linear\nimage is the same either way",
     NULL},
    {PF__OPT_CAMERA, "--camera", NULL, "ex,ey,ez:tx,ty,tz:fovy_deg", SCENE, "the camera (replaces the scene's)", NULL},
    {PF__OPT_LIGHT, "--light", NULL, "SPEC", SCENE,
     "point:x,y,z:r,g,b:I (I: W/sr)\n"
     "spot:x,y,z:dx,dy,dz:inner_deg,outer_deg:r,g,b:I\n"
     "dir:dx,dy,dz:r,g,b:E (E: W/m^2)\n"
     "repeatable; lights given replace the scene's lights",
     NULL},
    {PF__OPT_TIME, "--time", NULL, "SECONDS", R | F,
     "pose the scene's glTF animations at SECONDS (0..1000000): node\ntransforms, skins and morph weights; before "
     "an animation's first\nkey its first value, after its last key its last (docs/scenes.md)",
     "sequence files play animations with their \"animation\" key (docs/formats.md)"},
    {PF__OPT_ANIMATION, "--animation", NULL, "NAME|INDEX", R | F,
     "with --time: play only the animation of that name (or index, when\nit is all digits; default: every "
     "animation of the file together)",
     "sequence files play animations with their \"animation\" key (docs/formats.md)"},
    {PF__OPT_SHADOW_SIZE, "--shadow-size", NULL, "N", FRAME | BF, "direct-light shadow map resolution (default 1024)", NULL},
    {PF__OPT_MAX_MEMORY, "--max-memory", NULL, "SIZE", SCENE,
     "memory budget, e.g. 8G or 512M (default: half of this\nmachine's memory); larger scenes and frames are refused",
     NULL},
    {PF__OPT_AREA_STRATA, "--area-strata", NULL, "N", FRAME,
     "area lights, ray-traced direct light: N x N stratified\nsamples per pixel (1..16, default 4)", NULL},
    {PF__OPT_AREA_POINTS, "--area-points", NULL, "K", FRAME,
     "area lights, rasterized direct light: K emitter points,\neach with a paraboloid shadow map (1..1024, default 32)",
     NULL},
    {PF__OPT_INDIRECT_ONLY, "--indirect-only", NULL, NULL, SCENE, "only the indirect light (no emission, no direct)",
     NULL},
    {PF__OPT_DIRECT_ONLY, "--direct-only", NULL, NULL, SCENE, "only emission and direct light", NULL},
    {PF__OPT_VPLS, "--vpls", NULL, "N", FRAME, "VPL budget (default 256)", NULL},
    {PF__OPT_VPLS, "--vpls", NULL, "N", BF, "measure only N VPLs (default: 256 and 2048)", NULL},
    {PF__OPT_METHOD, "--method", NULL, "NAME", FRAME | BF,
     "VPL method (default ir): ir, iir, smc, mir, invtm, tcas, ssvp", NULL},
    {PF__OPT_BOUNCES, "--bounces", NULL, "B", FRAME, "light bounces of the VPLs (default 3)", NULL},
    {PF__OPT_BOUNCES, "--bounces", NULL, "B", F, "bounces of the reference's paths (default 3)", NULL},
    {PF__OPT_TILES, "--tiles", NULL, "NxM", FRAME | BF, "interleaved tiles (default 4x4)", NULL},
    {PF__OPT_NO_INTERLEAVE, "--no-interleave", NULL, NULL, FRAME, "every pixel sees every VPL", NULL},
    {PF__OPT_CLAMP, "--clamp", NULL, "C", FRAME, "bounded geometry term b = C / diagonal^2 (default 400, 0 = off)",
     NULL},
    {PF__OPT_CLAMP, "--clamp", NULL, "C", F,
     "clamped path tracing (Hedman 2017 Fig. 8): the first bounce's geometry\nterm bounded as the frame's --clamp C "
     "bounds it (default 0 = off)",
     NULL},
    {PF__OPT_FILTER, "--filter", NULL, "box|bilateral|gaussian|atrous|none", FRAME | BF,
     "indirect-light filter (default box, Laine 2007 Fig. 5;\ngaussian: Aranha SSVP Sec. III-D edge-aware Gaussian;\n"
     "atrous: the box, then variance-guided a-trous levels,\nDammertz 2010 and SVGF 2017; docs/frame.md)",
     NULL},
    {PF__OPT_FILTER_TEST, "--filter-test", NULL, "plane|distance", FRAME | BF,
     "the filter's position test: a neighbour's distance from the\npixel's tangent plane under alpha (the default; "
     "beyond the\npaper), or Laine 2007's |p2 - p| < alpha (distance); docs/frame.md",
     NULL},
    {PF__OPT_VISIBILITY, "--visibility", NULL, "paraboloid|paraboloid-slope|ism|raytrace", FRAME | BF,
     "VPL visibility (default: exact paraboloid maps with the\nreceiver-plane test; paraboloid-slope: the same maps "
     "with the\npapers' slope-scaled bias; docs/frame.md)",
     NULL},
    {PF__OPT_ISM_RES, "--ism-res", NULL, "N", FRAME | BF,
     "--visibility ism: texels per ISM side, a power of two 8..512\n(default 64)", NULL},
    {PF__OPT_ISM_POINTS, "--ism-points", NULL, "N", FRAME | BF,
     "--visibility ism: points splatted per frame (default 1000000)", NULL},
    {PF__OPT_ISM_BIAS, "--ism-bias", NULL, "S", FRAME | BF,
     "--visibility ism: bias, x the exact maps' bias, 1..64 (default 2)", NULL},
    {PF__OPT_PARAM, "--param", NULL, "KEY=VALUE", FRAME | BF, "a parameter of the VPL method (repeatable; see README)",
     NULL},
    {PF__OPT_DUMP_STAGES, "--dump-stages", NULL, "DIR", R | V,
     "write every stage of the frame as an image, with captions.txt", NULL},
    {PF__OPT_DUMP_FORMAT, "--dump-format", NULL, "png|exr|both", R,
     "--dump-stages: the pictures (png, the default), the stages'\nfloat data as OpenEXR (exr), or both", NULL},
    {PF__OPT_INDIRECT_SCALE, "--indirect-scale", NULL, "N|auto", FRAME | BF,
     "indirect light at 1/N of the resolution (1..4), upsampled\ngeometry-aware; auto (the default): 2 from 1024x768 "
     "up, else 1\n(docs/frame.md)",
     NULL},
    {PF__OPT_COMPENSATE, "--compensate", NULL, "on|off", FRAME | BF,
     "add back the light the clamp removes, gathered in screen\nspace (survey Sec. 5.2; default off; docs/frame.md)",
     NULL},
    {PF__OPT_TEMPORAL, "--temporal", NULL, "N", FRAME | BF,
     "average the indirect light over up to N frames (2..256) with\nreprojection, the tiles' VPL groups rotating "
     "each frame\n(default 0: off; docs/frame.md)",
     NULL},
    {PF__OPT_VPL_CYCLE, "--vpl-cycle", NULL, "C", FRAME | BF,
     "with --temporal: keep C x --vpls VPLs with their maps and shade\none slice of --vpls a frame, so the history "
     "averages\nall of them (2..64; default 0: off; docs/frame.md)",
     NULL},
    {PF__OPT_CYCLE_MAPS, "--cycle-maps", NULL, "B", FRAME | BF,
     "with --vpl-cycle: the progressive warm-up, the slices joining\nthe rotation one by one, B maps a frame "
     "drawn ahead\n(default 0: every slice from the first frame; docs/frame.md)",
     NULL},
    {PF__OPT_AA, "--aa", NULL, "N", FRAME | BF,
     "anti-aliasing: N jittered samples per pixel (1..256), averaged\nin linear radiance before the tone map "
     "(default 1: the pixel\ncentres; docs/aa.md)",
     NULL},
    {PF__OPT_TAA, "--taa", NULL, "N", V | S | BF,
     "temporal anti-aliasing: the samples jittered from frame to\nframe, averaged over up to N frames (2..256) with "
     "reprojection\n(default 0: off; docs/aa.md)",
     "one frame has no history to average; render takes --aa N"},
    {PF__OPT_PIPELINE, "--pipeline", NULL, "on|off", FRAME,
     "overlap the next frame's VPL update with this frame\n(one frame of VPL delay; default off)", NULL},
    {PF__OPT_PIPELINE, "--pipeline", NULL, "on|off", BF, "measure only with or only without pipelining (default: both)",
     NULL},
    {PF__OPT_SPP, "--spp", NULL, "N", F, "samples per pixel (default 64)", NULL},
    {PF__OPT_SPP, "--spp", NULL, "N", S, "--reference: samples per pixel (default 64)", NULL},
    {PF__OPT_LIGHT_PATHS, "--light-paths", NULL, "on|off", F | S,
     "the reference's light vertices joined to every bounce, with\nMIS (default on; off: NEE alone, far noisier near a "
     "point\nlight; docs/evaluation.md)",
     NULL},
    {PF__OPT_REFERENCE, "--reference", NULL, NULL, S, "path-trace every frame (the references evaluate uses)",
     "softgi reference renders one image; --reference is an option of sequence"},
    {PF__OPT_TRACK_SPP, "--track-spp", NULL, "N", S, "--reference: the tracked pixels with N samples", NULL},
    {PF__OPT_REUSE_FRAMES, "--reuse-frames", NULL, NULL, S,
     "--reference --track-spp: keep the folder's frames, redo only\nthe tracked pixels", NULL},
    {PF__OPT_RAYTRACE, "--raytrace", NULL, NULL, FRAME,
     "Embree primary rays and shadow rays (the reference path)\ninstead of the rasterized G-buffer and shadow maps", NULL},
    {PF__OPT_HASH, "--hash", NULL, NULL, R | F | S,
     "print a 64-bit hash of the linear output and the ISA used\n(the same on every ISA and processor)", NULL},
    {PF__OPT_QUIET, "--quiet", "-q", NULL, SCENE, "no timing table", NULL},
    {PF__OPT_FRAMES, "--frames", NULL, "N", V, "render N frames, then exit (after --screenshot)", NULL},
    {PF__OPT_FRAMES, "--frames", NULL, "N", R,
     "render N frames of the still view and write the last (1..1000,\ndefault 1); N > 1 without --temporal, "
     "--vpl-cycle or --cycle-maps:\nsoftgi view's progressive refinement (docs/view.md)",
     NULL},
    {PF__OPT_FRAMES, "--frames", NULL, "N", BR | BF, "repetitions per measurement (default 15)", NULL},
    {PF__OPT_FRAMES, "--frames", NULL, "A:B", S,
     "render only frames A..B-1 (zero-based as frame_NNNN, B excluded;\nA: to the end, N: frame N alone), named as "
     "a full run names\nthem, so runs of 0:10, 10:20, ... merged into one folder equal\na full run's (README: a batch "
     "scheduler); "
     "the frames before A are\nrendered, not written, to carry the frame's state (references:\nskipped)",
     NULL},
    {PF__OPT_SCREENSHOT, "--screenshot", NULL, "FILE.png", V,
     "save the window (without the HUD) after --frames N (default 1)", NULL},
    {PF__OPT_SCENES, "--scenes", NULL, "DIR", BR | BF, "folder with sibenik/ and conference/ (default ../shared/scenes)",
     NULL},
    {PF__OPT_MOVING_LIGHT, "--moving-light", NULL, NULL, BF, "the light moves on a small circle every frame", NULL},
    {PF__OPT_MOVING_OBJECT, "--moving-object", NULL, NULL, BF,
     "Sibenik with a 4096-triangle object moving every frame, against the same frame with it still",
     NULL},
    {PF__OPT_PARA_LOD, "--para-lod", NULL, "F", BR,
     "paraboloid maps from levels of detail: per group of triangles\nthe coarsest whose error is at most F texel "
     "footprints\n(0..16; default 0: exact maps; docs/raster.md)",
     NULL},
    {PF__OPT_HELP, "--help", "-h", NULL, ALL, "this text", NULL},
    {PF__OPT_VERSION, "--version", NULL, NULL, 0, "softgi's version (no command)", NULL},
    /* evaluate parses its own options (app_evaluate.c, whose help lists
     * --quality); this row only makes the other commands refuse it with a
     * pointer there instead of "unknown option" */
    {PF__OPT_QUALITY, "--quality", NULL, NULL, 0,
     "evaluate only: the image-quality table (method x scene x setting:\nerror, energy ratio, frame time)",
     "it is an option of softgi evaluate: softgi evaluate --quality"},
};
#define PF__OPTIONS (sizeof k_options / sizeof k_options[0])

typedef struct pf__cmd {
    uint32_t bit;
    const char *name;    /* as named in messages */
    const char *usage;   /* the usage line */
    const char *summary; /* one line for the command list */
    const char *about;   /* the command's help, before its options */
} pf__cmd;

static const pf__cmd k_commands[] = {
    {R, "render", "softgi render [SCENE.gltf|SCENE.glb] [options]",
     "render SCENE (default: the embedded Cornell box) to a PNG and a linear .pfm/.exr",
     "Renders SCENE (default: the embedded Cornell box) with softgi's many-light frame to a\n"
     "PNG and a linear HDR image, printing per-stage timings."},
    {V, "view", "softgi view [SCENE.gltf|SCENE.glb] [options]", "the interactive viewer and frame-stage stepper",
     "Shows the frame of `softgi render` in a window, re-rendered every frame; P pauses and\n"
     "N / B step through its stages (keys: H in the window)."},
    {F, "reference", "softgi reference [SCENE.gltf|SCENE.glb] [options]", "the path-traced reference image",
     "Path-traces SCENE (gi_reference: the ground truth the VPL methods are measured\n"
     "against) to a PNG and a linear HDR image, with a progress bar."},
    {S, "sequence", "softgi sequence SEQUENCE.json [options]", "render a camera/light sequence to a folder of frames",
     "Renders the frames of a sequence file (scene, camera and light keyframes) to a folder,\n"
     "keeping the VPL method's state from frame to frame."},
    {BR, "bench raster", "softgi bench raster [options]", "the rasterizer's passes against Embree",
     "Times the G-buffer pass, paraboloid maps and a cube shadow map against Embree on\n"
     "Sibenik and the conference room (from --scenes)."},
    {BF, "bench frame", "softgi bench frame [options]", "the whole many-light frame, stage by stage",
     "Times every stage of the many-light frame on Sibenik and the conference room (from\n"
     "--scenes), with and without pipelining."},
};
#define PF__COMMANDS (sizeof k_commands / sizeof k_commands[0])

#undef R
#undef V
#undef F
#undef S
#undef BR
#undef BF
#undef SCENE
#undef FRAME
#undef ALL

uint32_t pf_cli_command_bit(const char *command, const char *subject)
{
    if (!command) return 0;
    if (!strcmp(command, "bench"))
        return !subject ? 0 : !strcmp(subject, "raster") ? PF_CLI_BENCH_RASTER
                          : !strcmp(subject, "frame")    ? PF_CLI_BENCH_FRAME
                                                         : 0;
    for (size_t c = 0; c < PF__COMMANDS; c++) /* "bench raster" is two arguments, never one */
        if (!strchr(k_commands[c].name, ' ') && !strcmp(k_commands[c].name, command)) return k_commands[c].bit;
    return 0;
}

/* The first row of an option by name or alias; NULL for none. */
static const pf__opt *pf__find(const char *arg)
{
    for (size_t i = 0; i < PF__OPTIONS; i++)
        if (!strcmp(arg, k_options[i].name) || (k_options[i].alias && !strcmp(arg, k_options[i].alias)))
            return &k_options[i];
    return NULL;
}

/* Every command that takes option `id` (the union of its rows). */
static uint32_t pf__commands_of(pf__opt_id id)
{
    uint32_t set = 0;
    for (size_t i = 0; i < PF__OPTIONS; i++)
        if (k_options[i].id == id) set |= k_options[i].commands;
    return set;
}

uint32_t pf_cli_option_commands(const char *option)
{
    const pf__opt *e = pf__find(option);
    return e ? pf__commands_of(e->id) : 0;
}

const char *pf_cli_option_name(uint32_t i)
{
    /* the distinct names, in table order */
    uint32_t k = 0;
    for (size_t r = 0; r < PF__OPTIONS; r++) {
        if (pf__find(k_options[r].name) != &k_options[r]) continue; /* a later row of a name */
        if (k++ == i) return k_options[r].name;
    }
    return NULL;
}

/* "render, view and sequence" */
static void pf__command_list(uint32_t set, char *buf, size_t size)
{
    size_t n = 0, count = 0, done = 0;
    for (size_t c = 0; c < PF__COMMANDS; c++) count += (set & k_commands[c].bit) != 0;
    buf[0] = 0;
    for (size_t c = 0; c < PF__COMMANDS && n < size; c++) {
        if (!(set & k_commands[c].bit)) continue;
        const char *sep = done == 0 ? "" : done + 1 == count ? " and " : ", ";
        int w = snprintf(buf + n, size - n, "%s%s", sep, k_commands[c].name);
        if (w < 0) break;
        n += (size_t)w;
        done++;
    }
}

/* ---------------------------------------------------------------- help */

/* "  -o, --output FILE       first line of help" and its further lines,
 * indented to the help column. */
static void pf__print_option(FILE *out, const pf__opt *e)
{
    enum { HEAD = 22 };
    char head[96];
    snprintf(head, sizeof head, "%s%s%s%s%s", e->alias ? e->alias : "", e->alias ? ", " : "", e->name,
             e->value ? " " : "", e->value ? e->value : "");
    fprintf(out, "  %-*s", HEAD, head);
    if (strlen(head) > HEAD) fprintf(out, "\n  %*s", HEAD, "");
    for (const char *p = e->help; *p;) {
        size_t n = strcspn(p, "\n");
        fprintf(out, "  %.*s\n", (int)n, p);
        p += n;
        if (*p == '\n') {
            p++;
            fprintf(out, "  %*s", HEAD, "");
        }
    }
}

static void pf__print_command(FILE *out, const pf__cmd *c)
{
    fprintf(out, "usage: %s\n\n%s\n\noptions:\n", c->usage, c->about);
    for (size_t i = 0; i < PF__OPTIONS; i++)
        if (k_options[i].commands & c->bit) pf__print_option(out, &k_options[i]);
}

void pf_cli_usage(FILE *out)
{
    fputs("softgi: a pure-CPU software-rasterizing renderer with VPL global illumination.\n\n", out);
    for (size_t c = 0; c < PF__COMMANDS; c++)
        fprintf(out, "%s %s\n", c == 0 ? "usage:" : "      ", k_commands[c].usage);
    fputs("       softgi compare IMAGE REFERENCE | --reference DIR --name NAME:DIR ...\n"
          "       softgi evaluate [options]\n"
          "       softgi --version\n\ncommands:\n",
          out);
    for (size_t c = 0; c < PF__COMMANDS; c++) fprintf(out, "  %-13s %s\n", k_commands[c].name, k_commands[c].summary);
    fputs("  compare       metrics between images (.pfm, .exr) or sequences (Hedman 2017 Table 1)\n"
          "  evaluate      every VPL method against path-traced references on the shipped sequences\n"
          "\n`softgi COMMAND --help` lists the options of COMMAND; a command refuses options it does not take.\n",
          out);
}

pf_result pf_cli_usage_command(FILE *out, const char *command, const char *subject, pf_error *err)
{
    if (!command) {
        pf_cli_usage(out);
        return PF_OK;
    }
    uint32_t bits = pf_cli_command_bit(command, subject);
    if (!strcmp(command, "bench") && !bits) bits = PF_CLI_BENCH_RASTER | PF_CLI_BENCH_FRAME; /* both */
    int printed = 0;
    for (size_t c = 0; c < PF__COMMANDS; c++)
        if (k_commands[c].bit & bits) {
            if (printed++) fputc('\n', out);
            pf__print_command(out, &k_commands[c]);
        }
    if (printed) return PF_OK;
    return pf_error_set(err, PF_ERR_ARGUMENT,
                        "unknown command '%s' (softgi knows: render, view, reference, sequence, bench, compare, "
                        "evaluate)",
                        command);
}

/* ---------------------------------------------------------------- values */

/* Parses exactly one finite float from [s, s+len). */
static int pf__float(const char *s, size_t len, float *out)
{
    char buf[64];
    if (len == 0 || len >= sizeof buf) return 0;
    memcpy(buf, s, len);
    buf[len] = 0;
    char *end;
    errno = 0;
    float v = strtof(buf, &end);
    if (*end != 0 || errno == ERANGE || !isfinite(v)) return 0;
    *out = v;
    return 1;
}

/* Splits `s` at `sep` into up to `max` fields; returns the field count. */
static int pf__split(const char *s, char sep, const char **start, size_t *len, int max)
{
    int n = 0;
    const char *p = s;
    for (;;) {
        const char *q = strchr(p, sep);
        if (n == max) return max + 1;
        start[n] = p;
        len[n] = q ? (size_t)(q - p) : strlen(p);
        n++;
        if (!q) return n;
        p = q + 1;
    }
}

/* Parses "a,b,c" (exactly `count` floats) from a field. */
static int pf__floats(const char *s, size_t len, float *out, int count)
{
    char buf[256];
    if (len >= sizeof buf) return 0;
    memcpy(buf, s, len);
    buf[len] = 0;
    const char *st[8];
    size_t ln[8];
    if (pf__split(buf, ',', st, ln, 8) != count) return 0;
    for (int i = 0; i < count; i++)
        if (!pf__float(st[i], ln[i], &out[i])) return 0;
    return 1;
}

pf_result pf_cli_parse_camera(const char *spec, pf_vec3 *eye, pf_vec3 *target, float *fovy, pf_error *err)
{
    const char *st[4];
    size_t ln[4];
    float e[3], t[3];
    if (pf__split(spec, ':', st, ln, 3) != 3 || !pf__floats(st[0], ln[0], e, 3) ||
        !pf__floats(st[1], ln[1], t, 3) || !pf__float(st[2], ln[2], fovy))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': expected ex,ey,ez:tx,ty,tz:fovy_deg", spec);
    *eye = pf_v3(e[0], e[1], e[2]);
    *target = pf_v3(t[0], t[1], t[2]);
    /* as scene coordinates: beyond, target - eye overflows and shading is meaningless */
    if (!pf_scene_coord_ok(*eye) || !pf_scene_coord_ok(*target))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': coordinates must lie within +-%g", spec,
                                (double)PF_SCENE_MAX_COORD);
    if (!(*fovy > 0.0f && *fovy < 180.0f))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': fovy must be in (0, 180) degrees", spec);
    if (e[0] == t[0] && e[1] == t[1] && e[2] == t[2])
        return pf_error_set(err, PF_ERR_ARGUMENT, "--camera '%s': eye and target must differ", spec);
    return PF_OK;
}

static pf_result pf__colour_intensity(const char *spec, const char *cs, size_t cl, const char *is, size_t il,
                                      pf_light *out, pf_error *err)
{
    float c[3];
    if (!pf__floats(cs, cl, c, 3) || !pf__float(is, il, &out->intensity))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': bad colour r,g,b or intensity", spec);
    if (c[0] < 0 || c[1] < 0 || c[2] < 0 || out->intensity < 0)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': colour and intensity must be >= 0", spec);
    double cmax = fmax(c[0], fmax(c[1], c[2]));
    if (cmax * out->intensity > PF_MAX_RADIANCE)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': intensity x colour must be at most %g", spec,
                            (double)PF_MAX_RADIANCE);
    out->color = pf_v3(c[0], c[1], c[2]);
    return PF_OK;
}

static pf_result pf__direction(const char *spec, const char *s, size_t l, pf_vec3 *out, pf_error *err)
{
    float d[3];
    if (!pf__floats(s, l, d, 3))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': bad direction dx,dy,dz", spec);
    /* normalised in double: (1e38, 1e38, 0) overflows a float length */
    double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
    if (!(len > 0.0) || !isfinite(len))
        return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': direction must not be zero", spec);
    *out = pf_v3((float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len));
    return PF_OK;
}

pf_result pf_cli_parse_light(const char *spec, pf_light *out, pf_error *err)
{
    memset(out, 0, sizeof *out);
    const char *st[8];
    size_t ln[8];
    int n = pf__split(spec, ':', st, ln, 7);
    float v[3];
    pf_result r;
    if (n >= 1 && ln[0] == 5 && strncmp(st[0], "point", 5) == 0) {
        if (n != 4 || !pf__floats(st[1], ln[1], v, 3))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': expected point:x,y,z:r,g,b:I", spec);
        out->type = PF_LIGHT_POINT;
        out->position = pf_v3(v[0], v[1], v[2]);
        if (!pf_scene_coord_ok(out->position))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': position must lie within +-%g", spec,
                                (double)PF_SCENE_MAX_COORD);
        snprintf(out->name, sizeof out->name, "cli-point");
        return pf__colour_intensity(spec, st[2], ln[2], st[3], ln[3], out, err);
    }
    if (n >= 1 && ln[0] == 4 && strncmp(st[0], "spot", 4) == 0) {
        float cone[2];
        if (n != 6 || !pf__floats(st[1], ln[1], v, 3) || !pf__floats(st[3], ln[3], cone, 2))
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "--light '%s': expected spot:x,y,z:dx,dy,dz:inner_deg,outer_deg:r,g,b:I", spec);
        out->type = PF_LIGHT_SPOT;
        out->position = pf_v3(v[0], v[1], v[2]);
        if (!pf_scene_coord_ok(out->position))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': position must lie within +-%g", spec,
                                (double)PF_SCENE_MAX_COORD);
        if ((r = pf__direction(spec, st[2], ln[2], &out->direction, err)) != PF_OK) return r;
        if (!(cone[0] >= 0.0f && cone[0] < cone[1] && cone[1] <= 90.0f))
            return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': need 0 <= inner < outer <= 90 degrees", spec);
        out->inner_cone = pf_radians(cone[0]);
        out->outer_cone = pf_radians(cone[1]);
        snprintf(out->name, sizeof out->name, "cli-spot");
        return pf__colour_intensity(spec, st[4], ln[4], st[5], ln[5], out, err);
    }
    if (n >= 1 && ln[0] == 3 && strncmp(st[0], "dir", 3) == 0) {
        if (n != 4) return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': expected dir:dx,dy,dz:r,g,b:E", spec);
        out->type = PF_LIGHT_DIRECTIONAL;
        if ((r = pf__direction(spec, st[1], ln[1], &out->direction, err)) != PF_OK) return r;
        snprintf(out->name, sizeof out->name, "cli-dir");
        return pf__colour_intensity(spec, st[2], ln[2], st[3], ln[3], out, err);
    }
    return pf_error_set(err, PF_ERR_ARGUMENT, "--light '%s': type must be point, spot or dir", spec);
}
/* ---------------------------------------------------------------- parsing */

static pf_result pf__uint(const char *opt, const char *s, uint32_t lo, uint32_t hi, uint32_t *out, pf_error *err)
{
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (*s < '0' || *s > '9' || *end != 0 || errno == ERANGE || v < lo || v > hi)
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s': expected an integer in %u..%u", opt, s, lo, hi);
    *out = (uint32_t)v;
    return PF_OK;
}

/* "AxB" into *a and *b, each lo..hi; `example` for the message. */
static pf_result pf__pair(const char *opt, const char *val, const char *example, uint32_t lo, uint32_t hi,
                          uint32_t *a, uint32_t *b, pf_error *err)
{
    const char *x = strchr(val, 'x');
    char abuf[16], name[48];
    if (!x || (size_t)(x - val) >= sizeof abuf)
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s': expected %s", opt, val, example);
    memcpy(abuf, val, (size_t)(x - val));
    abuf[x - val] = 0;
    snprintf(name, sizeof name, "%s %s", opt, !strcmp(opt, "--size") ? "width" : "n");
    pf_result r = pf__uint(name, abuf, lo, hi, a, err);
    snprintf(name, sizeof name, "%s %s", opt, !strcmp(opt, "--size") ? "height" : "m");
    return r == PF_OK ? pf__uint(name, x + 1, lo, hi, b, err) : r;
}

static pf_result pf__size(pf_options *o, const char *val, pf_error *err)
{
    pf_result r = pf__pair("--size", val, "WxH, e.g. 640x480", 1, 16384, &o->width, &o->height, err);
    /* a frame keeps ~130 bytes a pixel (G-buffer, split buffers, irradiance): 8 GiB here */
    if (r == PF_OK && (uint64_t)o->width * o->height > (uint64_t)1 << 26)
        r = pf_error_set(err, PF_ERR_ARGUMENT, "--size %ux%u: at most 67108864 pixels (e.g. 8192x8192)", o->width,
                         o->height);
    return r;
}

static pf_result pf__float_option(const char *a, const char *val, float lo, float hi, const char *expected,
                                  float *out, pf_error *err)
{
    if (!pf__float(val, strlen(val), out) || !(*out >= lo && *out <= hi))
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s': expected %s", a, val, expected);
    return PF_OK;
}

/* One of the words of `choices` ("png|exr|both"): its index, or -1. */
static int pf__choice(const char *val, const char *choices)
{
    int k = 0;
    for (const char *p = choices; *p; k++) {
        size_t n = strcspn(p, "|");
        if (strlen(val) == n && !strncmp(val, p, n)) return k;
        p += n + (p[n] == '|');
    }
    return -1;
}

static pf_result pf__light(pf_options *o, const char *val, pf_error *err)
{
    if (o->light_count == PF_CLI_MAX_LIGHTS)
        return pf_error_set(err, PF_ERR_ARGUMENT, "at most %d --light options", PF_CLI_MAX_LIGHTS);
    return pf_cli_parse_light(val, &o->lights[o->light_count++], err);
}

static pf_result pf__param(pf_options *o, const char *val, pf_error *err)
{
    if (o->param_count >= 32) return pf_error_set(err, PF_ERR_ARGUMENT, "--param: at most 32 parameters");
    if (!strchr(val, '=') || val[0] == '=')
        return pf_error_set(err, PF_ERR_ARGUMENT, "--param '%s': expected KEY=VALUE", val);
    o->params[o->param_count++] = val;
    return PF_OK;
}

/* Option `id` (spelt `a`) with its value `val` (NULL for a flag) into *o. */
static pf_result pf__apply(pf_options *o, pf__opt_id id, const char *a, const char *val, pf_error *err)
{
    pf_result r = PF_OK;
    int k;
    switch (id) {
    case PF__OPT_OUTPUT: o->out_path = val; break;
    case PF__OPT_HDR: o->hdr_path = val; break;
    case PF__OPT_SIZE: r = pf__size(o, val, err); break;
    case PF__OPT_THREADS: r = pf__uint(a, val, 1, 256, &o->threads, err); break;
    case PF__OPT_ISA: r = pf_isa_parse(val, &o->isa, err); break;
    case PF__OPT_EXPOSURE:
        o->exposure_auto = !strcmp(val, "auto");
        o->exposure = 0.0f;
        if (!o->exposure_auto)
            r = pf__float_option(a, val, -64.0f, 64.0f, "a number of stops in -64..64, or auto", &o->exposure, err);
        break;
    case PF__OPT_CAMERA:
        r = pf_cli_parse_camera(val, &o->camera_eye, &o->camera_target, &o->camera_fovy_deg, err);
        o->has_camera = 1;
        break;
    case PF__OPT_LIGHT: r = pf__light(o, val, err); break;
    case PF__OPT_SHADOW_SIZE: r = pf__uint(a, val, 16, 8192, &o->shadow_size, err); break;
    case PF__OPT_MAX_MEMORY: r = pf_budget_parse(val, &o->max_memory, err); break;
    case PF__OPT_AREA_STRATA: r = pf__uint(a, val, 1, 16, &o->area_strata, err); break;
    case PF__OPT_AREA_POINTS: r = pf__uint(a, val, 1, 1024, &o->area_points, err); break;
    case PF__OPT_INDIRECT_ONLY: o->indirect_only = 1; break;
    case PF__OPT_DIRECT_ONLY: o->direct_only = 1; break;
    case PF__OPT_VPLS: r = pf__uint(a, val, 1, 1u << 20, &o->vpls, err); break;
    case PF__OPT_METHOD: o->method = val; break;
    case PF__OPT_BOUNCES: r = pf__uint(a, val, 1, 64, &o->bounces, err); break;
    case PF__OPT_TILES: r = pf__pair("--tiles", val, "NxM, e.g. 4x4", 1, 16, &o->tiles_n, &o->tiles_m, err); break;
    case PF__OPT_NO_INTERLEAVE: o->no_interleave = 1; break;
    case PF__OPT_CLAMP:
        r = pf__float_option(a, val, 0.0f, INFINITY, "a number >= 0 (0 = off)", &o->clamp, err);
        o->clamp_set = 1;
        break;
    case PF__OPT_FILTER:
        o->filter = val;
        if (pf__choice(val, "box|bilateral|gaussian|atrous|none") < 0)
            r = pf_error_set(err, PF_ERR_ARGUMENT, "--filter '%s': expected box, bilateral, gaussian, atrous or none",
                             val);
        break;
    case PF__OPT_FILTER_TEST:
        k = pf__choice(val, "plane|distance");
        if (k < 0) r = pf_error_set(err, PF_ERR_ARGUMENT, "--filter-test '%s': expected plane or distance", val);
        o->filter_distance = k == 1;
        break;
    case PF__OPT_VISIBILITY:
        k = pf__choice(val, "paraboloid|ism|raytrace|paraboloid-slope");
        if (k < 0)
            r = pf_error_set(err, PF_ERR_ARGUMENT,
                             "--visibility '%s': expected paraboloid, paraboloid-slope, ism or raytrace", val);
        o->visibility_ism |= k == 1;
        o->visibility_raytrace |= k == 2;
        o->visibility_slope |= k == 3;
        break;
    case PF__OPT_ISM_RES:
        r = pf__uint(a, val, 8, 512, &o->ism_res, err);
        if (r == PF_OK && (o->ism_res & (o->ism_res - 1)))
            r = pf_error_set(err, PF_ERR_ARGUMENT, "--ism-res '%s': expected a power of two in 8..512", val);
        break;
    case PF__OPT_ISM_POINTS: r = pf__uint(a, val, 1000, 100000000, &o->ism_points, err); break;
    case PF__OPT_ISM_BIAS: r = pf__float_option(a, val, 1.0f, 64.0f, "a number in 1..64", &o->ism_bias, err); break;
    case PF__OPT_PARAM: r = pf__param(o, val, err); break;
    case PF__OPT_DUMP_STAGES: o->dump_dir = val; break;
    case PF__OPT_DUMP_FORMAT:
        k = pf__choice(val, "png|exr|both");
        if (k < 0) r = pf_error_set(err, PF_ERR_ARGUMENT, "--dump-format '%s': expected png, exr or both", val);
        o->dump_format = k == 0 ? PF_CLI_DUMP_PNG : k == 1 ? PF_CLI_DUMP_EXR : PF_CLI_DUMP_PNG | PF_CLI_DUMP_EXR;
        break;
    case PF__OPT_INDIRECT_SCALE:
        if (strcmp(val, "auto") == 0) o->indirect_scale = GI_INDIRECT_SCALE_AUTO;
        else r = pf__uint(a, val, 1, GI_INDIRECT_MAX_SCALE, &o->indirect_scale, err);
        break;
    case PF__OPT_TEMPORAL:
        o->refine_set = 1;
        r = pf__uint(a, val, 0, GI_INDIRECT_MAX_TEMPORAL, &o->temporal, err);
        if (r == PF_OK && o->temporal == 1)
            r = pf_error_set(err, PF_ERR_ARGUMENT, "--temporal '%s': expected 0 (off) or 2..%u frames", val,
                             GI_INDIRECT_MAX_TEMPORAL);
        break;
    case PF__OPT_VPL_CYCLE:
        o->refine_set = 1;
        r = pf__uint(a, val, 0, GI_INDIRECT_MAX_CYCLE, &o->vpl_cycle, err);
        if (r == PF_OK && o->vpl_cycle == 1) o->vpl_cycle = 0; /* one slice: off */
        break;
    case PF__OPT_CYCLE_MAPS:
        o->refine_set = 1;
        r = pf__uint(a, val, 0, GI_INDIRECT_MAX_SET, &o->cycle_maps, err);
        break;
    case PF__OPT_AA: r = pf__uint(a, val, 1, GI_AA_MAX_SAMPLES, &o->aa, err); break;
    case PF__OPT_TAA:
        o->refine_set = 1;
        r = pf__uint(a, val, 0, GI_AA_MAX_TAA, &o->taa, err);
        if (r == PF_OK && o->taa == 1)
            r = pf_error_set(err, PF_ERR_ARGUMENT, "--taa '%s': expected 0 (off) or 2..%u frames", val, GI_AA_MAX_TAA);
        break;
    case PF__OPT_COMPENSATE:
        k = pf__choice(val, "off|on");
        if (k < 0) r = pf_error_set(err, PF_ERR_ARGUMENT, "--compensate '%s': expected on or off", val);
        o->compensate = k == 1;
        break;
    case PF__OPT_LIGHT_PATHS:
        k = pf__choice(val, "off|on");
        if (k < 0) r = pf_error_set(err, PF_ERR_ARGUMENT, "--light-paths '%s': expected on or off", val);
        o->no_light_paths = k == 0;
        break;
    case PF__OPT_PIPELINE:
        k = pf__choice(val, "off|on");
        if (k < 0) r = pf_error_set(err, PF_ERR_ARGUMENT, "--pipeline '%s': expected on or off", val);
        o->pipeline = k < 0 ? -1 : k;
        break;
    case PF__OPT_SPP: r = pf__uint(a, val, 1, 1u << 20, &o->spp, err); break;
    case PF__OPT_REFERENCE: o->reference = 1; break;
    case PF__OPT_TRACK_SPP: r = pf__uint(a, val, 1, 1u << 24, &o->track_spp, err); break;
    case PF__OPT_REUSE_FRAMES: o->reuse_frames = 1; break;
    case PF__OPT_RAYTRACE: o->raytrace = 1; break;
    case PF__OPT_HASH: o->print_hash = 1; break;
    case PF__OPT_QUIET: o->quiet = 1; break;
    case PF__OPT_FRAMES: o->frames_arg = val; break; /* N or A:B: parsed once the command is known */
    case PF__OPT_SCREENSHOT: {
        size_t n = strlen(val);
        o->screenshot_path = val;
        if (n < 5 || strcasecmp(val + n - 4, ".png") != 0)
            r = pf_error_set(err, PF_ERR_ARGUMENT, "--screenshot '%.200s': the screenshot is a PNG (name it .png)",
                             val);
        break;
    }
    case PF__OPT_SCENES: o->scenes_dir = val; break;
    case PF__OPT_MOVING_LIGHT: o->moving_light = 1; break;
    case PF__OPT_MOVING_OBJECT: o->moving_object = 1; break;
    case PF__OPT_PARA_LOD:
        r = pf__float_option(a, val, 0.0f, RS_PARA_MAX_LOD, "a number in 0..16", &o->para_lod, err);
        break;
    case PF__OPT_TIME:
        r = pf__float_option(a, val, 0.0f, (float)PF_ANIM_MAX_TIME, "a time in seconds, 0..1000000", &o->time, err);
        o->time_set = 1;
        break;
    case PF__OPT_ANIMATION:
        o->animation = val;
        if (!val[0]) r = pf_error_set(err, PF_ERR_ARGUMENT, "--animation '': expected an animation's name or index");
        break;
    case PF__OPT_HELP: o->help = 1; break;
    case PF__OPT_VERSION: o->version = 1; break;
    case PF__OPT_QUALITY: break; /* refused by every command pf_cli parses (pf__check_command) */
    case PF__OPT_COUNT: break;
    }
    return r;
}

/* The command and its subject, then every option given against the
 * commands that take it (k_options), then the options that need others. */
static pf_result pf__check_command(const pf_options *o, const char *const given[PF__OPT_COUNT], pf_error *err)
{
    const char *cmd = o->command;
    if (o->version || (o->help && !cmd)) return PF_OK;
    if (!cmd) return pf_error_set(err, PF_ERR_ARGUMENT, "no command given (see softgi --help)");
    int bench = !strcmp(cmd, "bench");
    if (!bench && !pf_cli_command_bit(cmd, NULL))
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "unknown command '%s' (softgi knows: render, view, reference, sequence, bench, compare, "
                            "evaluate)",
                            cmd);
    if (o->help) return PF_OK; /* `softgi bench --help` needs no subject */
    uint32_t bit = pf_cli_command_bit(cmd, o->scene_path);
    if (bench && !bit)
        return pf_error_set(err, PF_ERR_ARGUMENT, "bench '%s': softgi can bench: raster, frame",
                            o->scene_path ? o->scene_path : "");
    if (!strcmp(cmd, "sequence") && !o->scene_path)
        return pf_error_set(err, PF_ERR_ARGUMENT, "sequence: give the sequence file (softgi sequence FILE.json)");
    for (int id = 0; id < PF__OPT_COUNT; id++) {
        uint32_t takes = pf__commands_of((pf__opt_id)id);
        if (!given[id] || (takes & bit)) continue;
        const pf__opt *e = pf__find(given[id]);
        char by[128], name[32];
        pf__command_list(takes, by, sizeof by);
        pf__command_list(bit, name, sizeof name);
        if (!takes) /* an option of a command that parses its own (--quality: evaluate) */
            return pf_error_set(err, PF_ERR_ARGUMENT, "%s does not apply to %s (%s; see softgi evaluate --help)",
                                given[id], name, e->note ? e->note : "no command pf_cli parses takes it");
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s does not apply to %s (%s: only %s take%s it%s%s; see softgi %s --help)",
                            given[id], name, given[id], by, (takes & (takes - 1)) ? "" : "s", e->note ? "; " : "",
                            e->note ? e->note : "", cmd);
    }
    return PF_OK;
}

/* --frames by command: A:B for sequence, a count elsewhere. */
static pf_result pf__frames(pf_options *o, const char *spelt, pf_error *err)
{
    if (!o->frames_arg || !o->command) return PF_OK;
    if (!strcmp(o->command, "sequence")) {
        o->frame_range = 1;
        return pf_cli_parse_frame_range(spelt, o->frames_arg, &o->frame_first, &o->frame_end, err);
    }
    if (strchr(o->frames_arg, ':'))
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s': %s takes a frame count N (1..1000); ranges A:B are for "
                            "sequence", spelt, o->frames_arg, o->command);
    return pf__uint(spelt, o->frames_arg, 1, 1000, &o->frames, err);
}

/* The options that depend on others (after pf__check_command). */
static pf_result pf__check_combinations(const pf_options *o, pf_error *err)
{
    if (o->reuse_frames && !o->track_spp)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--reuse-frames: only with sequence --reference --track-spp");
    if (o->track_spp && !o->reference)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--track-spp: only with sequence --reference");
    if (o->indirect_only && o->direct_only)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--indirect-only and --direct-only exclude each other");
    if (o->animation && !o->time_set)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--animation: only with --time SECONDS");
    if (o->dump_format && !o->dump_dir)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--dump-format: only with --dump-stages DIR");
    if (o->reference && (o->aa || o->taa))
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "--aa and --taa: not with --reference (the path tracer box-filters every pixel already)");
    return PF_OK;
}

pf_result pf_cli_parse(pf_options *o, int argc, char **argv, pf_error *err)
{
    memset(o, 0, sizeof *o);
    o->pipeline = -1;
    const char *given[PF__OPT_COUNT] = {0}; /* how each option given was spelt ("-o" or "--output") */
    pf_result r = PF_OK;
    for (int i = 1; i < argc && r == PF_OK; i++) {
        const char *a = argv[i];
        const pf__opt *e = pf__find(a);
        if (e) {
            const char *val = NULL;
            if (e->value) {
                if (i + 1 >= argc) return pf_error_set(err, PF_ERR_ARGUMENT, "%s needs a value", a);
                val = argv[++i];
            }
            if (!given[e->id]) given[e->id] = a;
            r = pf__apply(o, e->id, a, val, err);
        } else if (a[0] == '-' && a[1] != 0)
            r = pf_error_set(err, PF_ERR_ARGUMENT, "unknown option '%s' (see softgi --help)", a);
        else if (!o->command) {
            o->command = a;
            if (!strcmp(a, "compare") || !strcmp(a, "evaluate")) /* main.c hands them argv when they come first */
                return pf_error_set(err, PF_ERR_ARGUMENT,
                                    "%s parses its own options: put them after it (softgi %s --help)", a, a);
        } else if (!o->scene_path)
            o->scene_path = a;
        else
            r = pf_error_set(err, PF_ERR_ARGUMENT, "unexpected argument '%s'", a);
    }
    if (r == PF_OK) r = pf__check_command(o, given, err);
    if (r == PF_OK && !o->version && !o->help) r = pf__frames(o, given[PF__OPT_FRAMES], err);
    if (r == PF_OK && !o->version && !o->help) r = pf__check_combinations(o, err);
    return r;
}

/* Digits only, at most 6 of them (below 1000000): no sign, space or
 * exponent slips through strtoul. */
static int pf__frame_number(const char *s, size_t n, uint32_t *out)
{
    if (n == 0 || n > 6) return 0;
    uint32_t v = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        v = v * 10 + (uint32_t)(s[i] - '0');
    }
    *out = v;
    return 1;
}

pf_result pf_cli_parse_frame_range(const char *opt, const char *val, uint32_t *first, uint32_t *end, pf_error *err)
{
    const char *colon = strchr(val, ':');
    if (!colon && pf__frame_number(val, strlen(val), first)) { /* N: frame N alone, N:N+1 */
        *end = *first + 1;
        return PF_OK;
    }
    if (!colon || strchr(colon + 1, ':') || (colon == val && !colon[1]))
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "%s '%.40s': expected A:B (frames A..B-1, zero-based), A: (A to the end), :B or N (frame "
                            "N alone)",
                            opt, val);
    size_t la = (size_t)(colon - val), lb = strlen(colon + 1);
    uint32_t a = 0, b = PF_CLI_FRAMES_END;
    if ((la && !pf__frame_number(val, la, &a)) || (lb && !pf__frame_number(colon + 1, lb, &b)))
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "%s '%.40s': A and B are frame numbers 0..999999 (digits only; frames A..B-1)", opt, val);
    if (b != PF_CLI_FRAMES_END && b <= a)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "%s '%.40s': B must be greater than A (the range is frames A..B-1; B is not rendered)",
                            opt, val);
    *first = a;
    *end = b;
    return PF_OK;
}

pf_result pf_cli_check_frame_range(const char *opt, uint32_t frames, uint32_t first, uint32_t *end, pf_error *err)
{
    if (first >= frames || (*end != PF_CLI_FRAMES_END && *end > frames)) {
        char given[32];
        if (*end == PF_CLI_FRAMES_END) snprintf(given, sizeof given, "%u:", first);
        else snprintf(given, sizeof given, "%u:%u", first, *end);
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "%s '%s': the sequence has %u frame%s (0..%u), so A must be below %u and B at most %u "
                            "(A: renders to the end)",
                            opt, given, frames, frames > 1 ? "s" : "", frames - 1, frames, frames);
    }
    if (*end == PF_CLI_FRAMES_END) *end = frames;
    return PF_OK;
}
