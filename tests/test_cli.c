/* test_cli: the softgi program as a user meets it.
 * - bad input of every kind gives a one-line message and a non-zero exit
 *   (2 for bad usage, 1 for a bad scene or file), never a crash;
 * - one help text per command: `softgi COMMAND --help` lists exactly the
 *   options the parser accepts for COMMAND (every option against every
 *   command, in process), `softgi --help` the commands; an option a command
 *   does not take exits 2 with one line naming both;
 * - `softgi render` writes its PNG and PFM, and the same render with
 *   --threads 1 and --threads 2 prints the same --hash;
 * - the PFM it writes holds exactly the hashed data. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "pf_cli.h"
#include "pf_imageio.h"
#include "test_util.h"

#define DATA SOFTGI_TEST_DATA "/gltf/"

static char g_tmp[256];

static void test_usage_errors(void **state)
{
    (void)state;
    tu_softgi_expect("--help", 0, "usage: softgi render");
    tu_softgi_expect("-h", 0, "commands:");
    tu_softgi_expect("--version", 0, "softgi ");
    tu_softgi_expect("", 2, "no command given");
    tu_softgi_expect("frobnicate", 2, "unknown command 'frobnicate'");
    tu_softgi_expect("render --indirect-only --direct-only", 2, "exclude each other");
    tu_softgi_expect("render --tiles 4", 2, "expected NxM");
    tu_softgi_expect("render --tiles 0x4", 2, "--tiles n");
    tu_softgi_expect("render --clamp -1", 2, "--clamp");
    tu_softgi_expect("render --filter gauss", 2, "--filter 'gauss'");
    tu_softgi_expect("render --visibility fog", 2, "--visibility 'fog'");
    tu_softgi_expect("render --param vpls", 2, "--param 'vpls': expected KEY=VALUE");
    tu_softgi_expect("render --param nosuch=1", 2, "method ir has no such parameter");
    tu_softgi_expect("render --vpls 0", 2, "--vpls");
    tu_softgi_expect("render --bounces 0", 2, "--bounces");
    tu_softgi_expect("render --aa 0", 2, "--aa '0': expected an integer in 1..256");
    tu_softgi_expect("render --aa 257", 2, "--aa '257': expected an integer in 1..256");
    tu_softgi_expect("render --aa 2x", 2, "--aa '2x'");
    tu_softgi_expect("view --taa 1", 2, "--taa '1': expected 0 (off) or 2..256 frames");
    tu_softgi_expect("sequence x.seq.json --taa 300", 2, "--taa '300'");
    /* 1,000,000 paraboloid maps (31 GiB) exceed the memory budget: refused before allocating, with the hint */
    tu_softgi_expect("render --vpls 1000000 --max-memory 8G -q -o /dev/null/x.png", 1,
                     "use fewer VPLs or --visibility raytrace");
    /* --time and --animation (pf_anim.h) */
    tu_softgi_expect("render --time -1", 2, "--time '-1': expected a time in seconds, 0..1000000");
    tu_softgi_expect("render --time nan", 2, "--time 'nan'");
    tu_softgi_expect("render --time inf", 2, "--time 'inf'");
    tu_softgi_expect("render --time 2e6", 2, "--time '2e6'");
    tu_softgi_expect("render --time 1s", 2, "--time '1s'");
    tu_softgi_expect("reference --animation walk", 2, "--animation: only with --time SECONDS");
    tu_softgi_expect("sequence x.seq.json --time 1", 2, "--time does not apply to sequence");
    tu_softgi_expect("view --time 1", 2, "--time does not apply to view");
    tu_softgi_expect("render --time 1 -q -o /dev/null/x.png", 2, "the built-in Cornell box: the scene has no animations");
    tu_softgi_expect("render " SOFTGI_TEST_DATA "/gltf/anim/anim_linear.gltf --time 1 --animation walk -q -o "
                     "/dev/null/x.png",
                     2, "no animation named 'walk' (the file has 4: 0 'slide', 1 'spin'");
    tu_softgi_expect("render " SOFTGI_TEST_DATA "/gltf/anim/anim_linear.gltf --time 1 --animation 9 -q -o "
                     "/dev/null/x.png",
                     2, "no animation 9");
    tu_softgi_expect("reference " SOFTGI_TEST_DATA "/gltf/anim/anim_far.gltf --time 1 -q -o /dev/null/x.png", 1,
                     "every animation at 1 s puts mesh 0 primitive 0 (node 0) vertex 0 at (1e+30, 0, 0)");
    tu_softgi_expect("render --frob", 2, "unknown option '--frob'");
    tu_softgi_expect("render a.gltf b.gltf", 2, "unexpected argument");
    tu_softgi_expect("render --size", 2, "--size needs a value");
    tu_softgi_expect("render --size 0x10", 2, "--size width '0'");
    tu_softgi_expect("render --size 640", 2, "expected WxH");
    tu_softgi_expect("render --size 64x99999", 2, "--size height");
    tu_softgi_expect("render --size 12ax10", 2, "--size width");
    tu_softgi_expect("render --size 16384x16384", 2, "at most 67108864 pixels");
    tu_softgi_expect("render --threads 0", 2, "--threads '0'");
    tu_softgi_expect("render --threads 100000", 2, "--threads");
    tu_softgi_expect("render --threads -1", 2, "--threads");
    tu_softgi_expect("render --isa avx9000", 2, "--isa 'avx9000'");
    tu_softgi_expect("render --exposure inf", 2, "--exposure");
    tu_softgi_expect("render --exposure 1e99", 2, "--exposure");
    tu_softgi_expect("render --camera nan,0,0:0,0,1:60", 2, "--camera");
    tu_softgi_expect("render --camera 0,0,0:0,0,0:60", 2, "eye and target must differ");
    tu_softgi_expect("render --camera 0,0,0:0,0,1:180", 2, "fovy");
    tu_softgi_expect("render --camera 0,0,0:0,0,1", 2, "--camera");
    tu_softgi_expect("render --light point:1,2:1,1,1:1", 2, "expected point:x,y,z:r,g,b:I");
    tu_softgi_expect("render --light point:1,2,3:1,1,1:-1", 2, "must be >= 0");
    tu_softgi_expect("render --light spot:0,1,0:0,-1,0:40,30:1,1,1:1", 2, "inner < outer");
    tu_softgi_expect("render --light spot:0,1,0:0,0,0:10,30:1,1,1:1", 2, "direction must not be zero");
    tu_softgi_expect("render --light dir:0,-1,0:1,1,1", 2, "expected dir:dx,dy,dz:r,g,b:E");
    tu_softgi_expect("render --light area:0,0,0:1,1,1:1", 2, "type must be point, spot or dir");
    /* fuzz_cli findings: coordinates beyond the scene limit made target - eye overflow to inf (a NaN camera);
     * intensity x colour overflowed in shading; a huge direction's float length overflowed */
    tu_softgi_expect("render --camera -3e38,0,0:3e38,0,0:60", 2, "within +-1e+07");
    tu_softgi_expect("render --camera 0,0,0:2e7,0,0:60", 2, "within +-1e+07");
    tu_softgi_expect("render --light point:1e8,0,0:1,1,1:1", 2, "position must lie within");
    tu_softgi_expect("render --light point:0,0,0:1,1,1:1e38", 2, "intensity x colour must be at most");
    tu_softgi_expect("render --light spot:1e7,-1e7,0:1e-19,1,0:5,90:1e38,0,1:3", 2, "");
    tu_softgi_expect("render --light dir:1e38,1e38,0:1,1,1:1 --size 32x24 -q -o /dev/null/x.png", 1, "/dev/null");
}

static void test_bad_scenes(void **state)
{
    (void)state;
    tu_softgi_expect("render /nonexistent/scene.gltf", 1, "no such file");
    tu_softgi_expect("render " SOFTGI_TEST_DATA, 1, "not a regular file");
    tu_softgi_expect("render " DATA "bad_json.gltf", 1, "not a loadable glTF");
    tu_softgi_expect("render " DATA "bad_truncated.glb", 1, "bad_truncated.glb");
    tu_softgi_expect("render " DATA "bad_nan.gltf", 1, "not finite");
    tu_softgi_expect("render " DATA "bad_index_range.gltf", 1, "out of range");
    tu_softgi_expect("render " DATA "bad_accessor_past_view.gltf", 1, "past the end");
    tu_softgi_expect("render " DATA "bad_missing_texture.gltf", 1, "could not be loaded");
    tu_softgi_expect("render " DATA "bad_only_degenerate.gltf", 1, "degenerate");
    /* a scene without a camera gets one (test_defaults.c), then the unwritable output fails */
    tu_softgi_expect("render " DATA "quad_u16.gltf -o /dev/null/x.png", 1, "has no camera; using --camera");
}

static void test_render_outputs_and_threads(void **state)
{
    (void)state;
    char args[1024], out1[16384], out2[16384];
    snprintf(args, sizeof args, "render --size 96x72 --isa sse2 --threads 1 --hash -o %s/a/b/c1.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out1, sizeof out1), 0);
    snprintf(args, sizeof args, "render --size 96x72 --isa sse2 --threads 2 --hash -o %s/c2.png --hdr %s/c2.pfm", g_tmp,
             g_tmp);
    assert_int_equal(tu_softgi_run(args, out2, sizeof out2), 0);
    const char *h1 = strstr(out1, "hash "), *h2 = strstr(out2, "hash ");
    assert_non_null(h1);
    assert_non_null(h2);
    if (strncmp(h1, h2, 21) != 0) fail_msg("--threads 1 and 2 differ:\n%s\n%s", h1, h2);
    assert_non_null(strstr(out1, "gbuffer")); /* the per-stage timing table */
    char p[512];
    snprintf(p, sizeof p, "%s/a/b/c1.png", g_tmp);
    assert_true(tu_file_exists(p));
    snprintf(p, sizeof p, "%s/a/b/c1.pfm", g_tmp);
    assert_true(tu_file_exists(p));
    /* the PFM holds exactly the hashed linear image */
    float *rgb;
    uint32_t w, h;
    pf_error err;
    snprintf(p, sizeof p, "%s/c2.pfm", g_tmp);
    assert_int_equal(pf_imageio_read_pfm(p, &rgb, &w, &h, &err), PF_OK);
    assert_int_equal(w, 96);
    assert_int_equal(h, 72);
    char want[32];
    snprintf(want, sizeof want, "hash %016llx", (unsigned long long)pf_imageio_hash(rgb, 3ull * w * h));
    assert_int_equal(strncmp(h2, want, 21), 0);
    free(rgb);
    /* --light replaces the scene's light: a different image */
    char out3[16384];
    snprintf(args, sizeof args,
             "render --size 96x72 --isa sse2 --hash -q -o %s/d.png --light dir:0.3,-1,0.2:1,1,1:2", g_tmp);
    assert_int_equal(tu_softgi_run(args, out3, sizeof out3), 0);
    assert_int_not_equal(strncmp(strstr(out3, "hash "), h1, 21), 0);
    /* an unwritable output is a clean error */
    tu_softgi_expect("render --size 8x8 -q -o /proc/softgi-test/x.png", 1, "cannot");
    /* a scene without a camera renders once one is given */
    snprintf(args, sizeof args, "render " DATA "quad_u16.gltf --camera 0,0,3:0,0,0:50 --light point:0,0,2:1,1,1:1 --size 16x16 -q -o %s/q.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out3, sizeof out3), 0);
}

/* ---------------------------------------------------------------- help and options per command */

/* The commands pf_cli parses: argv after "softgi", and the command's bit. */
static const struct {
    const char *args[2]; /* command [subject] */
    uint32_t bit;
} k_cmds[] = {
    {{"render", NULL}, PF_CLI_RENDER},         {{"view", NULL}, PF_CLI_VIEW},
    {{"reference", NULL}, PF_CLI_REFERENCE},   {{"sequence", "x.seq.json"}, PF_CLI_SEQUENCE},
    {{"bench", "raster"}, PF_CLI_BENCH_RASTER}, {{"bench", "frame"}, PF_CLI_BENCH_FRAME},
};

/* A valid value for every option (NULL: a flag) and what it needs beside it. */
static const struct {
    const char *name, *value, *needs[4];
} k_samples[] = {
    {"--output", "x.png", {0}},        {"--hdr", "x.exr", {0}},          {"--size", "8x8", {0}},
    {"--threads", "1", {0}},           {"--isa", "sse2", {0}},           {"--exposure", "1", {0}},
    {"--camera", "0,0,1:0,0,0:40", {0}}, {"--light", "point:0,0,0:1,1,1:1", {0}},
    {"--shadow-size", "64", {0}},      {"--max-memory", "1G", {0}},      {"--area-strata", "2", {0}},
    {"--area-points", "4", {0}},       {"--indirect-only", NULL, {0}},   {"--direct-only", NULL, {0}},
    {"--vpls", "8", {0}},              {"--method", "ir", {0}},          {"--bounces", "1", {0}},
    {"--tiles", "2x2", {0}},           {"--no-interleave", NULL, {0}},   {"--clamp", "1", {0}},
    {"--filter", "box", {0}},          {"--filter-test", "distance", {0}},
    {"--visibility", "raytrace", {0}}, {"--ism-res", "64", {0}},
    {"--ism-points", "1000", {0}},     {"--ism-bias", "2", {0}},         {"--para-lod", "4", {0}},         {"--param", "a=1", {0}},
    {"--dump-stages", "d", {0}},       {"--dump-format", "exr", {"--dump-stages", "d"}},
    {"--pipeline", "on", {0}},         {"--indirect-scale", "2", {0}}, {"--temporal", "4", {0}},
    {"--vpl-cycle", "4", {"--temporal", "4"}},
    {"--cycle-maps", "8", {"--temporal", "4", "--vpl-cycle", "4"}},
    {"--compensate", "on", {0}},       {"--spp", "4", {0}},              {"--reference", NULL, {0}},
    {"--light-paths", "off", {0}},
    {"--track-spp", "4", {"--reference"}}, {"--reuse-frames", NULL, {"--reference", "--track-spp", "4"}},
    {"--raytrace", NULL, {0}},         {"--hash", NULL, {0}},            {"--quiet", NULL, {0}},
    {"--frames", "1", {0}},            {"--screenshot", "s.png", {0}},   {"--scenes", "d", {0}},
    {"--moving-light", NULL, {0}},     {"--moving-object", NULL, {0}},  {"--quality", NULL, {0}},        {"--aa", "4", {0}},
    {"--taa", "8", {0}},               {"--time", "1", {0}},             {"--animation", "0", {"--time", "1"}},
};

/* `softgi CMD --help` as text (pf_cli_usage_command). */
static void help_of(int c, char *buf, size_t size)
{
    FILE *m = fmemopen(buf, size, "w");
    assert_non_null(m);
    pf_error err;
    assert_int_equal(pf_cli_usage_command(m, k_cmds[c].args[0], k_cmds[c].args[1], &err), PF_OK);
    fclose(m);
}

/* 1 when a row of the help lists `name` ("  --spp N   ..." or "  -o, --output FILE   ..."), not only
 * mentions it in another option's text. */
static int help_lists(const char *help, const char *name)
{
    for (const char *line = help; line && *line; line = strchr(line, '\n'), line = line ? line + 1 : NULL) {
        if (strncmp(line, "  -", 3) != 0) continue;
        const char *p = line + 2, *end = strstr(p, "  "), *nl = strchr(p, '\n');
        if (!end || (nl && nl < end)) end = nl ? nl : p + strlen(p);
        size_t n = strlen(name);
        for (const char *q = p; q + n <= end; q++)
            if (!strncmp(q, name, n) && (q == p || q[-1] == ' ') && (q + n == end || q[n] == ' ' || q[n] == ','))
                return 1;
    }
    return 0;
}

/* Parses `softgi CMD OPTION [VALUE] [NEEDS...]` in process. */
static pf_result parse_with(int c, int s, pf_options *o, pf_error *err)
{
    char *argv[12];
    int argc = 0;
    argv[argc++] = "softgi";
    for (int k = 0; k < 2; k++)
        if (k_cmds[c].args[k]) argv[argc++] = (char *)k_cmds[c].args[k];
    argv[argc++] = (char *)k_samples[s].name;
    if (k_samples[s].value) argv[argc++] = (char *)k_samples[s].value;
    for (int k = 0; k < 4 && k_samples[s].needs[k]; k++) argv[argc++] = (char *)k_samples[s].needs[k];
    argv[argc] = NULL;
    return pf_cli_parse(o, argc, argv, err);
}

static void test_help_matches_parser(void **state)
{
    (void)state;
    /* every option has a sample here (a new option must be added to k_samples) */
    for (uint32_t i = 0; pf_cli_option_name(i); i++) {
        const char *name = pf_cli_option_name(i);
        int found = !strcmp(name, "--help") || !strcmp(name, "--version");
        for (size_t s = 0; s < sizeof k_samples / sizeof k_samples[0]; s++) found |= !strcmp(k_samples[s].name, name);
        if (!found) fail_msg("option %s has no sample value in test_cli.c", name);
    }
    static char help[16384];
    for (int c = 0; c < (int)(sizeof k_cmds / sizeof k_cmds[0]); c++) {
        help_of(c, help, sizeof help);
        assert_true(help_lists(help, "--help"));
        for (int s = 0; s < (int)(sizeof k_samples / sizeof k_samples[0]); s++) {
            pf_options o;
            pf_error err;
            pf_result r = parse_with(c, s, &o, &err);
            int listed = help_lists(help, k_samples[s].name);
            int takes = (pf_cli_option_commands(k_samples[s].name) & k_cmds[c].bit) != 0;
            if ((r == PF_OK) != listed || takes != listed)
                fail_msg("softgi %s %s %s: parse %s (%s), help %s it", k_cmds[c].args[0],
                         k_cmds[c].args[1] ? k_cmds[c].args[1] : "", k_samples[s].name, r == PF_OK ? "accepts" : "refuses",
                         r == PF_OK ? "" : err.message, listed ? "lists" : "does not list");
            if (r != PF_OK) {
                assert_int_equal(r, PF_ERR_ARGUMENT);
                assert_int_equal(pf_result_exit_code(r), 2);
                if (!k_samples[s].needs[0]) { /* the message names the option and the command */
                    char want[128];
                    snprintf(want, sizeof want, "%s does not apply to %s%s%s", k_samples[s].name, k_cmds[c].args[0],
                             k_cmds[c].bit & (PF_CLI_BENCH_RASTER | PF_CLI_BENCH_FRAME) ? " " : "",
                             k_cmds[c].bit & (PF_CLI_BENCH_RASTER | PF_CLI_BENCH_FRAME) ? k_cmds[c].args[1] : "");
                    if (!strstr(err.message, want)) fail_msg("'%s' does not say '%s'", err.message, want);
                }
            }
        }
    }
}

static void test_help_per_command(void **state)
{
    (void)state;
    static const struct {
        const char *args, *has[4], *not[4];
    } k[] = {
        {"render --help", {"usage: softgi render", "--hdr", "--dump-format", "--raytrace"},
         {"--spp", "--screenshot", "--scenes", "--reference"}},
        {"view --help", {"usage: softgi view", "--screenshot", "--frames", "--dump-stages"},
         {"--output", "--hdr", "--hash", "--spp"}},
        {"reference --help", {"usage: softgi reference", "--spp", "--bounces", "--hdr"},
         {"--method", "--vpls", "--shadow-size", "--raytrace"}},
        {"sequence --help", {"usage: softgi sequence", "--reference", "--track-spp", "--method"},
         {"--hdr", "--screenshot", "--dump-stages", "--scenes"}},
        {"bench --help", {"usage: softgi bench raster", "usage: softgi bench frame", "--scenes", "--moving-light"},
         {"--size", "--output", "--camera", "--hash"}},
        {"bench frame --help", {"usage: softgi bench frame", "--moving-object", "--vpls", "--pipeline"},
         {"usage: softgi bench raster", "--size", "--camera", "--spp"}},
    };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        char out[16384];
        int st = tu_softgi_run(k[i].args, out, sizeof out);
        if (st != 0) fail_msg("softgi %s: exit %d\n%s", k[i].args, st, out);
        for (int j = 0; j < 4; j++) {
            if (k[i].has[j] && !strstr(out, k[i].has[j])) fail_msg("softgi %s lacks %s:\n%s", k[i].args, k[i].has[j], out);
            if (k[i].not[j] && help_lists(out, k[i].not[j]))
                fail_msg("softgi %s lists %s:\n%s", k[i].args, k[i].not[j], out);
            if (k[i].not[j] && !strncmp(k[i].not[j], "usage", 5) && strstr(out, k[i].not[j]))
                fail_msg("softgi %s shows %s", k[i].args, k[i].not[j]);
        }
    }
    /* the command list, and the commands that parse their own options */
    tu_softgi_expect("--help", 0, "softgi COMMAND --help");
    tu_softgi_expect("compare --help", 0, "usage: softgi compare");
    tu_softgi_expect("evaluate --help", 0, "usage: softgi evaluate");
    tu_softgi_expect("frobnicate --help", 2, "unknown command 'frobnicate'");
    tu_softgi_expect("-q compare a b", 2, "compare parses its own options");
}

static void test_wrong_command_options(void **state)
{
    (void)state;
    tu_softgi_expect("render --spp 64", 2, "--spp does not apply to render (--spp: only reference and sequence take it");
    tu_softgi_expect("reference --method iir", 2, "--method does not apply to reference");
    tu_softgi_expect("reference --vpls 8", 2, "--vpls does not apply to reference");
    tu_softgi_expect("view -o x.png", 2, "-o does not apply to view");
    tu_softgi_expect("view --hash", 2, "--hash does not apply to view");
    tu_softgi_expect("sequence x.seq.json --hdr x.exr", 2, "--hdr does not apply to sequence");
    tu_softgi_expect("sequence x.seq.json --screenshot s.png", 2, "--screenshot does not apply to sequence");
    tu_softgi_expect("bench raster --vpls 8", 2, "--vpls does not apply to bench raster");
    tu_softgi_expect("render --para-lod 4", 2, "--para-lod does not apply to render");
    tu_softgi_expect("bench raster --para-lod 17", 2, "--para-lod '17': expected a number in 0..16");
    tu_softgi_expect("bench frame -q", 2, "-q does not apply to bench frame");
    tu_softgi_expect("render --scenes d", 2, "see softgi render --help");
    tu_softgi_expect("render --taa 8", 2, "--taa does not apply to render (--taa: only view, sequence and bench frame "
                                          "take it; one frame has no history to average; render takes --aa N");
    tu_softgi_expect("reference --aa 4", 2, "--aa does not apply to reference");
    /* options that need another */
    tu_softgi_expect("render --dump-format exr", 2, "--dump-format: only with --dump-stages");
    tu_softgi_expect("render --dump-format tiff --dump-stages d", 2, "--dump-format 'tiff': expected png, exr or both");
    /* -o and --hdr by extension (details in test_output.c) */
    tu_softgi_expect("render -o x.jpg", 2, "-o 'x.jpg': unsupported output format '.jpg' (supported: .png");
    tu_softgi_expect("reference -o x.tiff", 2, "unsupported output format '.tiff'");
    tu_softgi_expect("render --hdr x.hdr", 2, "--hdr 'x.hdr': unsupported linear format '.hdr' (supported: .exr and .pfm)");
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-test-cli");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_usage_errors),
        cmocka_unit_test(test_help_matches_parser),
        cmocka_unit_test(test_help_per_command),
        cmocka_unit_test(test_wrong_command_options),
        cmocka_unit_test(test_bad_scenes),
        cmocka_unit_test(test_render_outputs_and_threads),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
