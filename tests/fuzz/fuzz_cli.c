/* fuzz_cli: libFuzzer target for the command-line parsers (pf_cli.h).
 *
 * The input is split at NUL bytes into argv strings (argv[0] = "softgi", at
 * most FUZZ_CLI_MAX_ARGS; each string in its own allocation, so reading past
 * one's terminator is an ASan report, not a quiet read of the next) and
 * given to pf_cli_parse; every string is also given to pf_cli_parse_light
 * and pf_cli_parse_camera on its own. The contract under test (pf_cli.h,
 * pf_cli.c):
 *
 * - failure: a PF_ERR_ARGUMENT with a non-empty message;
 * - success: every value is finite and in the range the parser documents
 *   (pf_cli_usage and the checks in pf_cli.c: counts and sizes in their
 *   intervals or 0 for "default", both or neither of --size and --tiles'
 *   halves, a power-of-two --ism-res, a known --filter, --pipeline -1/0/1);
 * - a returned light passes the checks pf_scene_validate makes of lights
 *   (finite, non-negative colour and intensity, 0 <= inner < outer <= pi/2
 *   in radians) and its direction is a unit vector;
 * - a returned camera has a field of view in (0, 180) degrees and distinct
 *   finite eye and target, and pf_camera_look_at (what the program does
 *   with it next) either refuses it with a message or gives a finite,
 *   orthonormal frame;
 * - the parser writes nothing to stdout (the target points fd 1 at a memory
 *   file and checks it after every input) and never calls exit() (libFuzzer
 *   reports a target that exits as a crash: "fuzz target exited").
 * pf_cli_parse allocates nothing (its strings point into argv); the target
 * frees its own argv copies, so a leak report means a leak in the parser.
 *
 * Seeds: tests/fuzz/seeds/cli/ (command lines from README.md, NUL
 * separated); dictionary: tests/fuzz/cli.dict. Run with tools/fuzz.sh. */
#define _GNU_SOURCE
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "pf_cli.h"
#include "pf_fpenv.h"

#define FUZZ_CLI_MAX_ARGS 256 /* enough to reach the 64-light and 32-parameter limits */

static int fuzz_cli_stdout_fd = -1; /* the real stdout, restored before a report */

#define FUZZ_CLI_CHECK(cond, ...)                                                                                     \
    do {                                                                                                              \
        if (!(cond)) fuzz_cli_fail(__LINE__, #cond, __VA_ARGS__);                                                     \
    } while (0)

static void fuzz_cli_fail(int line, const char *cond, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static void fuzz_cli_fail(int line, const char *cond, const char *fmt, ...)
{
    fprintf(stderr, "\nfuzz_cli.c:%d: invariant failed: %s\n  ", line, cond);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    abort();
}

static int fuzz_cli_unit(pf_vec3 v)
{
    return pf_v3_is_finite(v) && fabsf(pf_v3_length(v) - 1.0f) <= 1e-4f;
}

static int fuzz_cli_in(uint32_t v, uint32_t lo, uint32_t hi) { return v == 0 || (v >= lo && v <= hi); }

/* What pf_scene_validate and the renderer require of a light the CLI gives
 * (its position may be anywhere finite: validation refuses |x| > 1e7 later,
 * with a message). */
static void fuzz_cli_check_light(const pf_light *l, const char *spec)
{
    FUZZ_CLI_CHECK(l->type == PF_LIGHT_POINT || l->type == PF_LIGHT_SPOT || l->type == PF_LIGHT_DIRECTIONAL,
                   "'%s': type %d", spec, (int)l->type);
    FUZZ_CLI_CHECK(pf_v3_is_finite(l->position) && pf_v3_is_finite(l->color) && isfinite(l->intensity),
                   "'%s': non-finite value", spec);
    FUZZ_CLI_CHECK(l->color.x >= 0.0f && l->color.y >= 0.0f && l->color.z >= 0.0f && l->intensity >= 0.0f,
                   "'%s': negative colour or intensity", spec);
    FUZZ_CLI_CHECK(l->name[0] != 0 && memchr(l->name, 0, sizeof l->name) != NULL, "'%s': no name", spec);
    if (l->type != PF_LIGHT_POINT) {
        pf_vec3 d = l->direction;
        FUZZ_CLI_CHECK(fuzz_cli_unit(d), "'%s': direction (%g, %g, %g) is not a unit vector (length %.9g)", spec,
                       (double)d.x, (double)d.y, (double)d.z, (double)pf_v3_length(d));
    }
    if (l->type == PF_LIGHT_SPOT)
        FUZZ_CLI_CHECK(l->inner_cone >= 0.0f && l->inner_cone < l->outer_cone && l->outer_cone <= 0.5f * PF_PI,
                       "'%s': cones %.9g, %.9g rad (pf_scene_validate needs 0 <= inner < outer <= pi/2)", spec,
                       (double)l->inner_cone, (double)l->outer_cone);
}

static void fuzz_cli_check_camera(pf_vec3 eye, pf_vec3 target, float fovy, const char *spec)
{
    FUZZ_CLI_CHECK(pf_v3_is_finite(eye) && pf_v3_is_finite(target), "'%s'", spec);
    FUZZ_CLI_CHECK(fovy > 0.0f && fovy < 180.0f, "'%s': fovy %g", spec, (double)fovy);
    FUZZ_CLI_CHECK(eye.x != target.x || eye.y != target.y || eye.z != target.z, "'%s': eye == target", spec);
    /* the program's next step (app_scene_load) */
    pf_camera cam;
    pf_error err = {0};
    if (pf_camera_look_at(&cam, eye, target, pf_radians(fovy), &err) != PF_OK) {
        FUZZ_CLI_CHECK(err.message[0] != 0, "'%s': pf_camera_look_at failed without a message", spec);
        return;
    }
    FUZZ_CLI_CHECK(fuzz_cli_unit(cam.forward) && fuzz_cli_unit(cam.right) && fuzz_cli_unit(cam.up),
                   "'%s': pf_camera_look_at accepted it with forward (%g, %g, %g), right (%g, %g, %g), "
                   "up (%g, %g, %g)",
                   spec, (double)cam.forward.x, (double)cam.forward.y, (double)cam.forward.z, (double)cam.right.x,
                   (double)cam.right.y, (double)cam.right.z, (double)cam.up.x, (double)cam.up.y, (double)cam.up.z);
    FUZZ_CLI_CHECK(fabsf(pf_v3_dot(cam.forward, cam.right)) < 1e-4f && fabsf(pf_v3_dot(cam.forward, cam.up)) < 1e-4f,
                   "'%s': camera frame not orthogonal", spec);
    FUZZ_CLI_CHECK(cam.yfov > 0.0f && cam.yfov < PF_PI, "'%s': yfov %g rad", spec, (double)cam.yfov);
}

static int fuzz_cli_is_arg(char **argv, int argc, const char *p)
{
    for (int i = 0; i < argc; i++)
        if (p == argv[i]) return 1;
    return 0;
}

/* pf_cli_parse succeeded: everything in range (pf_cli.c). */
static void fuzz_cli_check_options(const pf_options *o, int argc, char **argv)
{
    if (!o->help && !o->version) {
        FUZZ_CLI_CHECK(o->command != NULL, "no command");
        FUZZ_CLI_CHECK(!strcmp(o->command, "render") || !strcmp(o->command, "bench") ||
                           !strcmp(o->command, "reference") || !strcmp(o->command, "sequence") ||
                           !strcmp(o->command, "view"),
                       "command '%s'", o->command);
        FUZZ_CLI_CHECK(!(o->indirect_only && o->direct_only), "both --indirect-only and --direct-only");
        FUZZ_CLI_CHECK(!o->reference || !strcmp(o->command, "sequence"), "--reference outside sequence");
    }
    if (o->command) FUZZ_CLI_CHECK(fuzz_cli_is_arg(argv, argc, o->command), "command not an argument");
    const char *const strings[] = {o->scene_path, o->scenes_dir,      o->method,   o->filter, o->dump_dir,
                                   o->out_path,   o->screenshot_path, o->hdr_path};
    for (size_t i = 0; i < sizeof strings / sizeof strings[0]; i++)
        if (strings[i]) FUZZ_CLI_CHECK(fuzz_cli_is_arg(argv, argc, strings[i]), "string %zu not an argument", i);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->threads, 1, 256), "--threads %u", o->threads);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->frames, 1, 1000), "--frames %u", o->frames);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->shadow_size, 16, 8192), "--shadow-size %u", o->shadow_size);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->area_strata, 1, 16), "--area-strata %u", o->area_strata);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->area_points, 1, 1024), "--area-points %u", o->area_points);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->vpls, 1, 1u << 20), "--vpls %u", o->vpls);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->bounces, 1, 64), "--bounces %u", o->bounces);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->spp, 1, 1u << 20), "--spp %u", o->spp);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->track_spp, 1, 1u << 24), "--track-spp %u", o->track_spp);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->tiles_n, 1, 16) && fuzz_cli_in(o->tiles_m, 1, 16) &&
                       (o->tiles_n == 0) == (o->tiles_m == 0),
                   "--tiles %ux%u", o->tiles_n, o->tiles_m);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->ism_res, 8, 512) && (o->ism_res & (o->ism_res - 1)) == 0, "--ism-res %u",
                   o->ism_res);
    FUZZ_CLI_CHECK(fuzz_cli_in(o->ism_points, 1000, 100000000), "--ism-points %u", o->ism_points);
    FUZZ_CLI_CHECK(o->ism_bias == 0.0f || (o->ism_bias >= 1.0f && o->ism_bias <= 64.0f), "--ism-bias %g",
                   (double)o->ism_bias);
    FUZZ_CLI_CHECK(isfinite(o->clamp) && o->clamp >= 0.0f && (o->clamp_set || o->clamp == 0.0f), "--clamp %g",
                   (double)o->clamp);
    FUZZ_CLI_CHECK(isfinite(o->exposure) && fabsf(o->exposure) <= 64.0f, "--exposure %g", (double)o->exposure);
    FUZZ_CLI_CHECK((o->width == 0) == (o->height == 0) && o->width <= 16384 && o->height <= 16384 &&
                       (uint64_t)o->width * o->height <= (uint64_t)1 << 26,
                   "--size %ux%u", o->width, o->height);
    FUZZ_CLI_CHECK(o->isa >= PF_ISA_AUTO && o->isa <= PF_ISA_AVX512, "--isa %d", (int)o->isa);
    FUZZ_CLI_CHECK(o->pipeline >= -1 && o->pipeline <= 1, "--pipeline %d", o->pipeline);
    FUZZ_CLI_CHECK(!o->filter || !strcmp(o->filter, "box") || !strcmp(o->filter, "bilateral") ||
                       !strcmp(o->filter, "gaussian") || !strcmp(o->filter, "atrous") ||
                       !strcmp(o->filter, "none"),
                   "--filter '%s'", o->filter);
    FUZZ_CLI_CHECK(o->param_count <= 32, "%u parameters", o->param_count);
    for (uint32_t i = 0; i < o->param_count; i++)
        FUZZ_CLI_CHECK(fuzz_cli_is_arg(argv, argc, o->params[i]) && strchr(o->params[i], '=') &&
                           o->params[i][0] != '=',
                       "--param '%s'", o->params[i]);
    FUZZ_CLI_CHECK(o->light_count <= PF_CLI_MAX_LIGHTS, "%u lights", o->light_count);
    for (uint32_t i = 0; i < o->light_count; i++) fuzz_cli_check_light(&o->lights[i], "--light");
    if (o->has_camera) fuzz_cli_check_camera(o->camera_eye, o->camera_target, o->camera_fovy_deg, "--camera");
}

static void fuzz_cli_check_stdout(const char *what)
{
    fflush(stdout);
    off_t n = lseek(STDOUT_FILENO, 0, SEEK_CUR);
    if (n <= 0) return;
    char buf[512] = {0};
    if (pread(STDOUT_FILENO, buf, sizeof buf - 1, 0) < 0) buf[0] = 0;
    if (fuzz_cli_stdout_fd >= 0) dup2(fuzz_cli_stdout_fd, STDOUT_FILENO);
    fprintf(stderr, "\nfuzz_cli: %s wrote %lld bytes to stdout, beginning:\n%s\n", what, (long long)n, buf);
    abort();
}

/* At exit the real stdout comes back (atexit handlers run before stdio's
 * final flush), so a driver's closing line (replay_main's count) is seen. */
static void fuzz_cli_restore_stdout(void)
{
    if (fuzz_cli_stdout_fd >= 0) dup2(fuzz_cli_stdout_fd, STDOUT_FILENO); /* what is still buffered goes there */
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    pf_fpenv_set(); /* as main() does before parsing: FTZ/DAZ, so denormals behave as in the program */
    /* stdout goes to a memory file: libFuzzer and the sanitizers write to
     * stderr, so anything there came from the code under test */
    fflush(stdout);
    int fd = memfd_create("fuzz_cli_stdout", 0);
    if (fd >= 0) {
        fuzz_cli_stdout_fd = dup(STDOUT_FILENO);
        dup2(fd, STDOUT_FILENO);
        close(fd);
        atexit(fuzz_cli_restore_stdout);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *argv[FUZZ_CLI_MAX_ARGS + 1];
    int argc = 0;
    argv[argc++] = strdup("softgi");
    size_t start = 0;
    while (start < size && argc < FUZZ_CLI_MAX_ARGS) {
        const uint8_t *nul = memchr(data + start, 0, size - start);
        size_t len = nul ? (size_t)(nul - (data + start)) : size - start;
        char *a = malloc(len + 1);
        if (!a) abort();
        memcpy(a, data + start, len);
        a[len] = 0;
        argv[argc++] = a;
        start += len + 1;
    }
    argv[argc] = NULL;

    /* the whole command line */
    pf_options *o = malloc(sizeof *o); /* ~8 KiB of lights: heap, so ASan sees overruns */
    if (!o) abort();
    pf_error err;
    memset(&err, 0, sizeof err);
    pf_result r = pf_cli_parse(o, argc, argv, &err);
    if (r == PF_OK) fuzz_cli_check_options(o, argc, argv);
    else
        FUZZ_CLI_CHECK(r == PF_ERR_ARGUMENT && err.code == r && err.message[0] != 0 &&
                           memchr(err.message, 0, sizeof err.message) != NULL,
                       "pf_cli_parse failed (%d) without a message", (int)r);
    fuzz_cli_check_stdout("pf_cli_parse");

    /* each string alone, as --light and --camera values */
    for (int i = 1; i < argc; i++) {
        pf_light light;
        memset(&err, 0, sizeof err);
        if (pf_cli_parse_light(argv[i], &light, &err) == PF_OK) fuzz_cli_check_light(&light, argv[i]);
        else FUZZ_CLI_CHECK(err.message[0] != 0, "pf_cli_parse_light('%s') failed without a message", argv[i]);
        pf_vec3 eye, target;
        float fovy;
        memset(&err, 0, sizeof err);
        if (pf_cli_parse_camera(argv[i], &eye, &target, &fovy, &err) == PF_OK)
            fuzz_cli_check_camera(eye, target, fovy, argv[i]);
        else FUZZ_CLI_CHECK(err.message[0] != 0, "pf_cli_parse_camera('%s') failed without a message", argv[i]);
        pf_isa isa;
        memset(&err, 0, sizeof err);
        if (pf_isa_parse(argv[i], &isa, &err) == PF_OK)
            FUZZ_CLI_CHECK(isa >= PF_ISA_AUTO && isa <= PF_ISA_AVX512, "pf_isa_parse('%s') = %d", argv[i], (int)isa);
        else FUZZ_CLI_CHECK(err.message[0] != 0, "pf_isa_parse('%s') failed without a message", argv[i]);
    }
    fuzz_cli_check_stdout("pf_cli_parse_light / pf_cli_parse_camera");

    free(o);
    for (int i = 0; i < argc; i++) free(argv[i]);
    return 0;
}
