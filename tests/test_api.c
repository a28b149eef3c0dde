/* test_api: the public C API (include/softgi/softgi.h, docs/api.md).
 * - lifetimes: create/destroy with and without a scene, destroy(NULL), a
 *   context reused after a failed load, two scenes in a row;
 * - bad inputs give their result code and a one-line message naming the
 *   value, never a crash: NULL arguments, half-given or huge sizes, bad
 *   threads, ISA, method, method parameters, flags, memory budget, missing
 *   and malformed files, a frame larger than the budget, bad cameras,
 *   lights, targets and stages, calls out of order;
 * - bit identity with the program: the image the API renders equals, bit
 *   for bit, the linear image `softgi render` writes with the same options
 *   (its PFM, and its --hash): the default Cornell box (built in, 640x480,
 *   every default), the file at 160x120, a ray-traced indirect-only TCAS
 *   frame, --camera / --light against softgi_set_camera / softgi_set_lights,
 *   and the automatic camera and light of a scene that has neither; every
 *   frame field of softgi_desc (shadow size, area sampling, tiles, clamp,
 *   filter, visibility and the ISM settings, indirect scale, temporal,
 *   compensate, pipeline, anti-aliasing) against its option, and whole
 *   option sets (`softgi render` is itself built on the API, so these check
 *   its option mapping; the goldens elsewhere check the frame), bad values
 *   of each refused with the program's limits;
 * - softgi_set_time against --time / --animation (the same bits), a second
 *   pose rebuilding what it must, bad times and names refused, a pose that
 *   would leave the coordinate range refused with the scene unchanged;
 * - softgi_dump_stages against --dump-stages (the same bytes), the progress
 *   callback (every stage once, the image unchanged), temporal
 *   anti-aliasing over successive frames (deterministic);
 * - the stages read back (final = the rendered image, depth one channel,
 *   no irradiance without VPLs), the timings, two contexts rendering at
 *   once on two threads, and the caller's MXCSR left as it was. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

#include "softgi/softgi.h"

#include "pf_imageio.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define NO_CAMERA_NO_LIGHT SOFTGI_TEST_DATA "/gltf/hierarchy_trs.gltf"

static char g_tmp[256];

static int group_setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-test-api");
}

static int group_teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

/* Fails unless `r` is `code` and the message holds `needle`. */
static void expect_error(softgi_result r, const softgi_error *err, softgi_result code, const char *needle)
{
    if (r != code || err->code != code || !strstr(err->message, needle) || strchr(err->message, '\n'))
        fail_msg("got %d (%s) '%s', want %d (%s) with '%s'", (int)r, softgi_result_name(r), err->message, (int)code,
                 softgi_result_name(code), needle);
}

static softgi_context *create_or_fail(const softgi_desc *d)
{
    softgi_error err;
    softgi_context *c = softgi_create(d, &err);
    if (!c) fail_msg("softgi_create: %s", err.message);
    assert_int_equal(err.code, SOFTGI_OK);
    return c;
}

static void ok_or_fail(softgi_result r, const softgi_error *err)
{
    if (r != SOFTGI_OK) fail_msg("%s", err->message);
}

/* ---------------------------------------------------------------- lifetimes */

static void test_create_destroy(void **state)
{
    (void)state;
    softgi_destroy(NULL);
    softgi_context *c = create_or_fail(NULL); /* NULL: every default */
    softgi_info info;
    softgi_error err;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.width, 640);
    assert_int_equal(info.height, 480);
    assert_true(info.threads >= 1);
    assert_string_equal(info.method, "ir");
    assert_non_null(info.isa);
    assert_int_equal(info.scene_loaded, 0);
    assert_int_equal(softgi_get_timings(c, NULL, 0), 0);
    softgi_destroy(c); /* no scene */

    softgi_desc d = {.width = 32, .height = 24, .threads = 1};
    c = create_or_fail(&d);
    ok_or_fail(softgi_load_scene(c, CORNELL, &err), &err);
    ok_or_fail(softgi_load_scene(c, NULL, &err), &err); /* a second scene replaces the first */
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.scene_loaded, 1);
    assert_true(info.triangles > 0);
    assert_int_equal(info.auto_camera, 0);
    assert_int_equal(info.auto_light, 0);
    softgi_destroy(c); /* a scene, no frame */

    assert_string_equal(softgi_result_name(SOFTGI_ERR_IO), "i/o error");
    assert_non_null(strstr(softgi_method_names(), "smc"));
    assert_true(strlen(softgi_version()) > 0);
}

/* ---------------------------------------------------------------- bad inputs */

static void test_bad_desc(void **state)
{
    (void)state;
    const char *bad_param[] = {"nosuchkey=1"};
    const char *not_kv[] = {"novalue"};
    const char *null_param[] = {NULL};
    const struct {
        softgi_desc d;
        softgi_result code;
        const char *needle;
    } cases[] = {
        {{.width = 100}, SOFTGI_ERR_ARGUMENT, "give both"},
        {{.height = 100}, SOFTGI_ERR_ARGUMENT, "give both"},
        {{.width = 20000, .height = 10}, SOFTGI_ERR_ARGUMENT, "each must be 1..16384"},
        {{.threads = 1000}, SOFTGI_ERR_ARGUMENT, "threads 1000"},
        {{.vpls = (1u << 20) + 1}, SOFTGI_ERR_ARGUMENT, "vpls 1048577"},
        {{.bounces = 65}, SOFTGI_ERR_ARGUMENT, "bounces 65"},
        {{.max_memory = 1000}, SOFTGI_ERR_ARGUMENT, "at least 64 MiB"},
        {{.flags = 128}, SOFTGI_ERR_ARGUMENT, "unknown bits"},
        {{.flags = SOFTGI_DIRECT_ONLY | SOFTGI_INDIRECT_ONLY}, SOFTGI_ERR_ARGUMENT, "exclude each other"},
        {{.method = "nosuch"}, SOFTGI_ERR_ARGUMENT, "method 'nosuch': softgi knows ir"},
        {{.isa = "avx9"}, SOFTGI_ERR_ARGUMENT, "avx9"},
        {{.method = "ir", .params = bad_param, .param_count = 1}, SOFTGI_ERR_ARGUMENT, "nosuchkey"},
        {{.params = not_kv, .param_count = 1}, SOFTGI_ERR_ARGUMENT, "expected KEY=VALUE"},
        {{.params = null_param, .param_count = 1}, SOFTGI_ERR_ARGUMENT, "params[0] is NULL"},
        {{.params = NULL, .param_count = 2}, SOFTGI_ERR_ARGUMENT, "param_count 2"},
        /* the frame's options, with the limits of their command-line options (pf_cli.c) */
        {{.shadow_size = 8}, SOFTGI_ERR_ARGUMENT, "shadow_size 8: must be 16..8192"},
        {{.shadow_size = 8193}, SOFTGI_ERR_ARGUMENT, "shadow_size 8193"},
        {{.area_strata = 17}, SOFTGI_ERR_ARGUMENT, "area_strata 17: must be 1..16"},
        {{.area_points = 1025}, SOFTGI_ERR_ARGUMENT, "area_points 1025: must be 1..1024"},
        {{.tiles_n = 4}, SOFTGI_ERR_ARGUMENT, "tiles_n 4 x tiles_m 0: give both"},
        {{.tiles_n = 17, .tiles_m = 4}, SOFTGI_ERR_ARGUMENT, "tiles_n 17"},
        {{.clamp = -2.0f}, SOFTGI_ERR_ARGUMENT, "clamp -2"},
        {{.clamp = INFINITY}, SOFTGI_ERR_ARGUMENT, "clamp inf"},
        {{.clamp = NAN}, SOFTGI_ERR_ARGUMENT, "clamp nan"},
        {{.filter = "median"}, SOFTGI_ERR_ARGUMENT, "filter 'median': expected box, bilateral, gaussian, atrous or none"},
        {{.visibility = "cones"},
         SOFTGI_ERR_ARGUMENT,
         "visibility 'cones': expected paraboloid, paraboloid-slope, ism or raytrace"},
        {{.visibility = "ism", .ism_res = 48}, SOFTGI_ERR_ARGUMENT, "ism_res 48: must be a power of two in 8..512"},
        {{.visibility = "ism", .ism_res = 1024}, SOFTGI_ERR_ARGUMENT, "ism_res 1024"},
        {{.visibility = "ism", .ism_points = 999}, SOFTGI_ERR_ARGUMENT, "ism_points 999"},
        {{.visibility = "ism", .ism_bias = 0.5f}, SOFTGI_ERR_ARGUMENT, "ism_bias 0.5: must be 1..64"},
        {{.ism_res = 64}, SOFTGI_ERR_ARGUMENT, "need --visibility ism"},
        {{.visibility = "raytrace", .ism_bias = 2}, SOFTGI_ERR_ARGUMENT, "need --visibility ism"},
        {{.indirect_scale = 5}, SOFTGI_ERR_ARGUMENT, "indirect_scale 5: must be 1..4"},
        {{.temporal = 1}, SOFTGI_ERR_ARGUMENT, "temporal 1: must be 2..256"},
        {{.temporal = 257}, SOFTGI_ERR_ARGUMENT, "temporal 257"},
        {{.vpl_cycle = 1}, SOFTGI_ERR_ARGUMENT, "vpl_cycle 1: must be 2..64"},
        {{.vpl_cycle = 65}, SOFTGI_ERR_ARGUMENT, "vpl_cycle 65"},
        {{.aa = 257}, SOFTGI_ERR_ARGUMENT, "aa 257: must be 1..256"},
        {{.taa = 1}, SOFTGI_ERR_ARGUMENT, "taa 1: must be 2..256"},
        {{.flags = 128}, SOFTGI_ERR_ARGUMENT, "flags 0x80"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        softgi_error err;
        memset(&err, 0, sizeof err);
        softgi_context *c = softgi_create(&cases[i].d, &err);
        if (c) fail_msg("case %zu ('%s') created a context", i, cases[i].needle);
        expect_error(err.code, &err, cases[i].code, cases[i].needle);
    }
    assert_null(softgi_create(&cases[0].d, NULL)); /* err may be NULL */
}

static void test_bad_scene(void **state)
{
    (void)state;
    softgi_desc d = {.width = 32, .height = 24, .threads = 2};
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    float rgb[32 * 24 * 3];
    softgi_target t = {.rgb = rgb};
    /* out of order: nothing loaded */
    expect_error(softgi_render(c, &t, &err), &err, SOFTGI_ERR_ARGUMENT, "no scene loaded");
    softgi_camera cam = {{0, 0, 1}, {0, 0, 0}, 45};
    expect_error(softgi_set_camera(c, &cam, &err), &err, SOFTGI_ERR_ARGUMENT, "no scene loaded");
    softgi_light l = {.type = SOFTGI_LIGHT_POINT, .color = {1, 1, 1}, .intensity = 1};
    expect_error(softgi_set_lights(c, &l, 1, &err), &err, SOFTGI_ERR_ARGUMENT, "no scene loaded");
    expect_error(softgi_read_stage(c, SOFTGI_STAGE_FINAL, rgb, 0, &err), &err, SOFTGI_ERR_ARGUMENT,
                 "no frame rendered");
    /* files: missing, malformed, hostile; each leaves the context usable */
    expect_error(softgi_load_scene(c, "/nonexistent/scene.gltf", &err), &err, SOFTGI_ERR_IO, "/nonexistent/scene.gltf");
    expect_error(softgi_load_scene(c, SOFTGI_TEST_DATA "/gltf/bad_accessor_past_view.gltf", &err), &err,
                 SOFTGI_ERR_ACCESSOR, "bad_accessor_past_view.gltf");
    softgi_result r = softgi_load_scene(c, SOFTGI_TEST_DATA "/gltf/bad_inf.gltf", &err);
    assert_int_not_equal(r, SOFTGI_OK);
    assert_non_null(strstr(err.message, "bad_inf.gltf"));
    r = softgi_load_scene(c, SOFTGI_TEST_DATA "/gltf/bad_cycle.gltf", &err);
    assert_int_not_equal(r, SOFTGI_OK);
    assert_non_null(strstr(err.message, "bad_cycle.gltf"));
    expect_error(softgi_render(c, &t, &err), &err, SOFTGI_ERR_ARGUMENT, "no scene loaded");
    ok_or_fail(softgi_load_scene(c, CORNELL, &err), &err);
    ok_or_fail(softgi_render(c, &t, &err), &err);
    /* NULLs */
    expect_error(softgi_load_scene(NULL, CORNELL, &err), &err, SOFTGI_ERR_ARGUMENT, "context is NULL");
    expect_error(softgi_render(NULL, &t, &err), &err, SOFTGI_ERR_ARGUMENT, "context is NULL");
    expect_error(softgi_render(c, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "target is NULL");
    softgi_target none = {0};
    expect_error(softgi_render(c, &none, &err), &err, SOFTGI_ERR_ARGUMENT, "neither rgb nor rgba8");
    softgi_target narrow = {.rgb = rgb, .rgb_stride = 10};
    expect_error(softgi_render(c, &narrow, &err), &err, SOFTGI_ERR_ARGUMENT, "rgb_stride 10");
    uint8_t rgba[32 * 24 * 4];
    softgi_target dark = {.rgba8 = rgba, .exposure = NAN};
    expect_error(softgi_render(c, &dark, &err), &err, SOFTGI_ERR_ARGUMENT, "exposure nan");
    expect_error(softgi_set_camera(c, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "camera is NULL");
    expect_error(softgi_set_lights(c, NULL, 1, &err), &err, SOFTGI_ERR_ARGUMENT, "lights is NULL");
    expect_error(softgi_get_info(c, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "info is NULL");
    expect_error(softgi_read_stage(c, SOFTGI_STAGE_FINAL, NULL, 0, &err), &err, SOFTGI_ERR_ARGUMENT, "dst is NULL");
    expect_error(softgi_read_stage(c, SOFTGI_STAGE_COUNT, rgb, 0, &err), &err, SOFTGI_ERR_ARGUMENT, "unknown stage");
    expect_error(softgi_read_stage(c, SOFTGI_STAGE_FINAL, rgb, 5, &err), &err, SOFTGI_ERR_ARGUMENT, "stride 5");
    assert_int_equal(softgi_stage_channels((softgi_stage)99), 0);
    assert_int_equal(softgi_get_timings(NULL, NULL, 0), 0);
    /* cameras */
    const softgi_camera bad_cams[] = {
        {{0, 0, 1}, {0, 0, 1}, 45}, {{0, 0, 1}, {0, 0, 0}, 0}, {{0, 0, 1}, {0, 0, 0}, 180},
        {{NAN, 0, 1}, {0, 0, 0}, 45}, {{2e7f, 0, 1}, {0, 0, 0}, 45},
    };
    const char *cam_needles[] = {"must differ", "fovy_deg 0", "fovy_deg 180", "finite", "finite"};
    for (int i = 0; i < 5; i++)
        expect_error(softgi_set_camera(c, &bad_cams[i], &err), &err, SOFTGI_ERR_ARGUMENT, cam_needles[i]);
    /* lights */
    const softgi_light bad_lights[] = {
        {.type = (softgi_light_type)7, .color = {1, 1, 1}, .intensity = 1},
        {.type = SOFTGI_LIGHT_POINT, .color = {-1, 1, 1}, .intensity = 1},
        {.type = SOFTGI_LIGHT_POINT, .color = {1, 1, 1}, .intensity = INFINITY},
        {.type = SOFTGI_LIGHT_POINT, .color = {1, 1, 1}, .intensity = 1e13f},
        {.type = SOFTGI_LIGHT_POINT, .position = {NAN, 0, 0}, .color = {1, 1, 1}, .intensity = 1},
        {.type = SOFTGI_LIGHT_DIRECTIONAL, .color = {1, 1, 1}, .intensity = 1},
        {.type = SOFTGI_LIGHT_SPOT, .direction = {0, -1, 0}, .color = {1, 1, 1}, .intensity = 1, .inner_deg = 30,
         .outer_deg = 20},
    };
    const char *light_needles[] = {"type 7", "colour and intensity", "colour and intensity", "at most",
                                   "position",  "direction",             "inner_deg < outer_deg"};
    for (int i = 0; i < 7; i++)
        expect_error(softgi_set_lights(c, &bad_lights[i], 1, &err), &err, SOFTGI_ERR_ARGUMENT, light_needles[i]);
    expect_error(softgi_set_lights(c, bad_lights, 0, &err), &err, SOFTGI_ERR_ARGUMENT, "count 0");
    expect_error(softgi_set_lights(c, bad_lights, 65, &err), &err, SOFTGI_ERR_ARGUMENT, "count 65");
    /* none of that changed the frame: it still renders */
    ok_or_fail(softgi_render(c, &t, &err), &err);
    softgi_destroy(c);
}

/* A frame larger than the memory budget is refused at load, before the
 * Embree scene or the frame is built, with the program's message. */
static void test_budget(void **state)
{
    (void)state;
    softgi_desc d = {.width = 16384, .height = 16384, .threads = 1, .max_memory = 64ull << 20};
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    expect_error(softgi_load_scene(c, CORNELL, &err), &err, SOFTGI_ERR_OUT_OF_MEMORY,
                 "the frame (16384x16384, 1 lights with shadow maps of 1024^2, 256 VPLs) needs about");
    assert_non_null(strstr(err.message, "exceeds the memory budget of 64 MiB"));
    softgi_info info;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.scene_loaded, 0);
    softgi_destroy(c);
}

/* ---------------------------------------------------------------- bit identity */

/* `softgi render ARGS --hash -o DIR/cli-N.pfm`: its hash, and its image
 * into *rgb (malloc'ed, w x h x 3). */
static uint64_t cli_render(const char *args, float **rgb, uint32_t *w, uint32_t *h)
{
    static int n;
    char pfm[512], cmd[4096], out[16384];
    snprintf(pfm, sizeof pfm, "%s/cli-%d.pfm", g_tmp, n++);
    snprintf(cmd, sizeof cmd, "render %s --hash -o %s", args, pfm);
    int st = tu_softgi_run(cmd, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", cmd, st, out);
    const char *hp = strstr(out, "hash ");
    if (!hp) fail_msg("softgi %s printed no hash:\n%s", cmd, out);
    uint64_t hash = strtoull(hp + 5, NULL, 16);
    pf_error err;
    if (pf_imageio_read_pfm(pfm, rgb, w, h, &err) != PF_OK) fail_msg("%s", err.message);
    return hash;
}

/* The API's frame of `path` with `d` (camera and lights when not NULL)
 * equals `softgi render cli_args` bit for bit. */
static void expect_same_as_cli(const softgi_desc *d, const char *path, const softgi_camera *cam,
                               const softgi_light *lights, uint32_t light_count, const char *cli_args)
{
    float *cli = NULL;
    uint32_t w = 0, h = 0;
    uint64_t cli_hash = cli_render(cli_args, &cli, &w, &h);
    softgi_context *c = create_or_fail(d);
    softgi_error err;
    ok_or_fail(softgi_load_scene(c, path, &err), &err);
    if (cam) ok_or_fail(softgi_set_camera(c, cam, &err), &err);
    if (lights) ok_or_fail(softgi_set_lights(c, lights, light_count, &err), &err);
    softgi_info info;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.width, w);
    assert_int_equal(info.height, h);
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    assert_non_null(rgb);
    softgi_target t = {.rgb = rgb};
    ok_or_fail(softgi_render(c, &t, &err), &err);
    uint64_t api_hash = softgi_image_hash(rgb, w, h, 0);
    size_t differ = 0;
    for (size_t i = 0; i < (size_t)w * h * 3; i++) differ += memcmp(&rgb[i], &cli[i], sizeof(float)) != 0;
    if (differ || api_hash != cli_hash)
        fail_msg("softgi render %s: hash %016llx; the API's %016llx, %zu of %zu values differ", cli_args,
                 (unsigned long long)cli_hash, (unsigned long long)api_hash, differ, (size_t)w * h * 3);
    free(rgb);
    free(cli);
    softgi_destroy(c);
}

static void test_same_as_cli_default(void **state)
{
    (void)state;
    /* `softgi render` with no argument at all: the built-in Cornell box,
     * 640 x 480, IR, 256 VPLs; softgi_desc all zero but the threads */
    softgi_desc d = {.threads = 2};
    expect_same_as_cli(&d, NULL, NULL, NULL, 0, "--threads 2 -q");
}

static void test_same_as_cli_file(void **state)
{
    (void)state;
    softgi_desc d = {.width = 160, .height = 120, .threads = 2};
    expect_same_as_cli(&d, CORNELL, NULL, NULL, 0, CORNELL " --size 160x120 --threads 2 -q");
    /* threads never decide a result: 1 thread, the same image */
    d.threads = 1;
    expect_same_as_cli(&d, CORNELL, NULL, NULL, 0, CORNELL " --size 160x120 --threads 2 -q");
}

static void test_same_as_cli_options(void **state)
{
    (void)state;
    const char *params[] = {"M=8"};
    softgi_desc d = {.width = 96, .height = 72, .threads = 2, .method = "tcas", .vpls = 64, .bounces = 2,
                     .params = params, .param_count = 1, .flags = SOFTGI_RAYTRACE | SOFTGI_INDIRECT_ONLY};
    expect_same_as_cli(&d, CORNELL, NULL, NULL, 0,
                       CORNELL " --size 96x72 --threads 2 --method tcas --vpls 64 --bounces 2 --param M=8 --raytrace "
                               "--indirect-only -q");
    softgi_desc direct = {.width = 96, .height = 72, .threads = 2, .flags = SOFTGI_DIRECT_ONLY};
    expect_same_as_cli(&direct, CORNELL, NULL, NULL, 0, CORNELL " --size 96x72 --threads 2 --direct-only -q");
}

static void test_same_as_cli_camera_lights(void **state)
{
    (void)state;
    softgi_desc d = {.width = 120, .height = 90, .threads = 2};
    const softgi_camera cam = {{0.2f, 0.3f, -0.7f}, {0.278f, 0.27f, 0.3f}, 45.0f};
    const softgi_light lights[2] = {
        {.type = SOFTGI_LIGHT_POINT, .position = {0.3f, 0.5f, 0.2f}, .color = {1, 0.9f, 0.8f}, .intensity = 0.5f},
        {.type = SOFTGI_LIGHT_SPOT, .position = {0.1f, 0.5f, 0.1f}, .direction = {0.2f, -1, 0.1f},
         .color = {0.5f, 0.6f, 1}, .intensity = 2, .inner_deg = 20, .outer_deg = 35},
    };
    expect_same_as_cli(&d, CORNELL, &cam, lights, 2,
                       CORNELL " --size 120x90 --threads 2 --camera 0.2,0.3,-0.7:0.278,0.27,0.3:45 "
                               "--light point:0.3,0.5,0.2:1,0.9,0.8:0.5 "
                               "--light spot:0.1,0.5,0.1:0.2,-1,0.1:20,35:0.5,0.6,1:2 -q");
    const softgi_light sun = {.type = SOFTGI_LIGHT_DIRECTIONAL, .direction = {0.3f, -1, -0.2f}, .color = {1, 1, 1},
                              .intensity = 3};
    expect_same_as_cli(&d, NULL, NULL, &sun, 1, "--size 120x90 --threads 2 --light dir:0.3,-1,-0.2:1,1,1:3 -q");
}

/* Every frame option of softgi_desc against its command-line option, one
 * or two at a time (small images: each is one run of the program). */
static void test_same_as_cli_frame_options(void **state)
{
    (void)state;
    const struct {
        softgi_desc d;
        const char *args;
    } cases[] = {
        {{.shadow_size = 64}, "--shadow-size 64"},
        {{.tiles_n = 2, .tiles_m = 3}, "--tiles 2x3"},
        {{.flags = SOFTGI_NO_INTERLEAVE, .vpls = 32}, "--no-interleave --vpls 32"},
        {{.clamp = 40.0f}, "--clamp 40"},
        {{.clamp = SOFTGI_CLAMP_OFF}, "--clamp 0"},
        {{.filter = "bilateral"}, "--filter bilateral"},
        {{.filter = "gaussian"}, "--filter gaussian"},
        {{.filter = "none"}, "--filter none"},
        {{.visibility = "raytrace", .vpls = 64}, "--visibility raytrace --vpls 64"},
        {{.visibility = "ism", .ism_res = 32, .ism_points = 20000, .ism_bias = 3}, 
         "--visibility ism --ism-res 32 --ism-points 20000 --ism-bias 3"},
        {{.visibility = "paraboloid", .vpls = 16}, "--visibility paraboloid --vpls 16"},
        {{.indirect_scale = 2}, "--indirect-scale 2"},
        {{.temporal = 4}, "--temporal 4"},
        {{.temporal = 4, .vpl_cycle = 4}, "--temporal 4 --vpl-cycle 4"},
        {{.temporal = 4, .vpl_cycle = 4, .cycle_maps = 8}, "--temporal 4 --vpl-cycle 4 --cycle-maps 8"},
        {{.flags = SOFTGI_COMPENSATE}, "--compensate on"},
        {{.flags = SOFTGI_FILTER_DISTANCE}, "--filter-test distance"},
        {{.flags = SOFTGI_PIPELINE, .method = "iir"}, "--pipeline on --method iir"},
        {{.aa = 4}, "--aa 4"},
        {{.aa = 2, .flags = SOFTGI_RAYTRACE}, "--aa 2 --raytrace"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        softgi_desc d = cases[i].d;
        d.width = 64, d.height = 48, d.threads = 2;
        char args[1024];
        snprintf(args, sizeof args, "%s --size 64x48 --threads 2 %s -q", CORNELL, cases[i].args);
        expect_same_as_cli(&d, CORNELL, NULL, NULL, 0, args);
    }
    /* area lights: a scene whose emissive triangles are its light */
    const char *sphere = SOFTGI_SOURCE_DIR "/scenes/closed-sphere/closed-sphere.gltf";
    softgi_desc area = {.width = 64, .height = 48, .threads = 2, .area_points = 8};
    char args[1024];
    snprintf(args, sizeof args, "%s --size 64x48 --threads 2 --area-points 8 -q", sphere);
    expect_same_as_cli(&area, sphere, NULL, NULL, 0, args);
    softgi_desc strata = {.width = 64, .height = 48, .threads = 2, .area_strata = 2, .flags = SOFTGI_RAYTRACE};
    snprintf(args, sizeof args, "%s --size 64x48 --threads 2 --area-strata 2 --raytrace -q", sphere);
    expect_same_as_cli(&strata, sphere, NULL, NULL, 0, args);
}

/* The program built on the API: a handful of whole option sets, each the
 * same bytes through the program and through an API program. */
static void test_same_as_cli_option_sets(void **state)
{
    (void)state;
    const char *params[] = {"k=4"};
    softgi_desc smc = {.width = 80, .height = 60, .threads = 2, .method = "smc", .vpls = 48, .bounces = 2,
                       .params = params, .param_count = 1, .tiles_n = 2, .tiles_m = 2, .clamp = 100.0f,
                       .filter = "bilateral", .shadow_size = 256, .aa = 2};
    expect_same_as_cli(&smc, CORNELL, NULL, NULL, 0,
                       CORNELL " --size 80x60 --threads 2 --method smc --vpls 48 --bounces 2 --param k=4 --tiles 2x2 "
                               "--clamp 100 --filter bilateral --shadow-size 256 --aa 2 -q");
    softgi_desc ism = {.width = 80, .height = 60, .threads = 1, .method = "ssvp", .visibility = "ism",
                       .ism_res = 16, .flags = SOFTGI_INDIRECT_ONLY | SOFTGI_COMPENSATE, .indirect_scale = 2};
    expect_same_as_cli(&ism, CORNELL, NULL, NULL, 0,
                       CORNELL " --size 80x60 --threads 2 --method ssvp --visibility ism --ism-res 16 "
                               "--indirect-only --compensate on --indirect-scale 2 -q");
    softgi_desc rt = {.width = 80, .height = 60, .threads = 2, .method = "invtm", .visibility = "raytrace",
                      .flags = SOFTGI_RAYTRACE | SOFTGI_NO_INTERLEAVE, .vpls = 32, .filter = "none"};
    const softgi_camera cam = {{0.2f, 0.3f, -0.7f}, {0.278f, 0.27f, 0.3f}, 45.0f};
    expect_same_as_cli(&rt, CORNELL, &cam, NULL, 0,
                       CORNELL " --size 80x60 --threads 2 --method invtm --visibility raytrace --raytrace "
                               "--no-interleave --vpls 32 --filter none --camera 0.2,0.3,-0.7:0.278,0.27,0.3:45 -q");
    softgi_desc direct = {.width = 80, .height = 60, .threads = 2, .flags = SOFTGI_DIRECT_ONLY, .shadow_size = 128,
                          .aa = 3};
    expect_same_as_cli(&direct, NULL, NULL, NULL, 0, "--size 80x60 --threads 2 --direct-only --shadow-size 128 "
                                                     "--aa 3 -q");
}

/* softgi_desc.progress: every stage reported once, in the timings' order,
 * on the calling thread; the image unchanged. */
typedef struct progress_log {
    uint32_t stages, work;
    const char *names[64];
} progress_log;

static void on_progress(void *user, const char *what, uint32_t done, uint32_t total)
{
    progress_log *p = user;
    if (!total) {
        if (p->stages < 64) p->names[p->stages] = what;
        p->stages++;
    } else {
        assert_true(done <= total);
        p->work++;
    }
}

static void test_progress(void **state)
{
    (void)state;
    progress_log log;
    memset(&log, 0, sizeof log);
    softgi_desc d = {.width = 64, .height = 48, .threads = 2, .progress = on_progress, .progress_user = &log};
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    ok_or_fail(softgi_load_scene(c, CORNELL, &err), &err);
    float *rgb = malloc(64 * 48 * 3 * sizeof *rgb), *plain = malloc(64 * 48 * 3 * sizeof *plain);
    assert_non_null(rgb);
    assert_non_null(plain);
    softgi_target t = {.rgb = rgb};
    ok_or_fail(softgi_render(c, &t, &err), &err);
    softgi_timing timing[64];
    uint32_t n = softgi_get_timings(c, timing, 64);
    uint32_t load = 3; /* load scene, embree build, raster setup */
    assert_true(n > load);
    assert_int_equal(log.stages, n - load);
    for (uint32_t i = 0; i < log.stages && i < 64; i++) assert_string_equal(log.names[i], timing[load + i].name);
    softgi_destroy(c);
    d.progress = NULL, d.progress_user = NULL;
    c = create_or_fail(&d);
    ok_or_fail(softgi_load_scene(c, CORNELL, &err), &err);
    t.rgb = plain;
    ok_or_fail(softgi_render(c, &t, &err), &err);
    assert_memory_equal(rgb, plain, 64 * 48 * 3 * sizeof *rgb);
    softgi_destroy(c);
    free(rgb);
    free(plain);
}

/* softgi_desc.taa (`softgi sequence --taa`, not a render option): the
 * frames blend, so the second differs from the first, and the same
 * description gives the same frames again. */
static void test_taa_frames(void **state)
{
    (void)state;
    softgi_desc d = {.width = 48, .height = 36, .threads = 2, .taa = 4, .vpls = 32};
    float *a[2], *b[2];
    for (int run = 0; run < 2; run++) {
        softgi_context *c = create_or_fail(&d);
        softgi_error err;
        ok_or_fail(softgi_load_scene(c, CORNELL, &err), &err);
        float **out = run ? b : a;
        for (int f = 0; f < 2; f++) {
            out[f] = malloc(48 * 36 * 3 * sizeof(float));
            assert_non_null(out[f]);
            softgi_target t = {.rgb = out[f]};
            ok_or_fail(softgi_render(c, &t, &err), &err);
        }
        softgi_info info;
        ok_or_fail(softgi_get_info(c, &info, &err), &err);
        assert_int_equal(info.frames, 2);
        softgi_destroy(c);
    }
    assert_memory_not_equal(a[0], a[1], 48 * 36 * 3 * sizeof(float));
    for (int f = 0; f < 2; f++) {
        assert_memory_equal(a[f], b[f], 48 * 36 * 3 * sizeof(float));
        free(a[f]);
        free(b[f]);
    }
}

/* Reads a whole file (malloc'ed) into *data; its size, 0 if unreadable. */
static size_t read_all(const char *path, unsigned char **data)
{
    *data = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    *data = malloc(n > 0 ? (size_t)n : 1);
    size_t got = *data ? fread(*data, 1, (size_t)n, f) : 0;
    fclose(f);
    return got;
}

/* softgi_dump_stages writes what `softgi render --dump-stages` writes:
 * the same captions and the same bytes in a picture and a float file. */
static void test_dump_stages(void **state)
{
    (void)state;
    char cli_dir[512], api_dir[512], cmd[2048], out[16384];
    snprintf(cli_dir, sizeof cli_dir, "%s/dump-cli", g_tmp);
    snprintf(api_dir, sizeof api_dir, "%s/dump-api", g_tmp);
    snprintf(cmd, sizeof cmd, "render %s --size 64x48 --threads 2 --exposure 1 --dump-stages %s --dump-format both "
             "-o %s/dump.pfm -q", CORNELL, cli_dir, g_tmp);
    int st = tu_softgi_run(cmd, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", cmd, st, out);
    softgi_desc d = {.width = 64, .height = 48, .threads = 2};
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    expect_error(softgi_dump_stages(c, api_dir, 0, SOFTGI_DUMP_PNG, &err), &err, SOFTGI_ERR_ARGUMENT,
                 "no frame rendered yet");
    ok_or_fail(softgi_load_scene(c, CORNELL, &err), &err);
    float *rgb = malloc(64 * 48 * 3 * sizeof *rgb);
    assert_non_null(rgb);
    softgi_target t = {.rgb = rgb};
    ok_or_fail(softgi_render(c, &t, &err), &err);
    expect_error(softgi_dump_stages(c, api_dir, 0, (softgi_dump_format)4, &err), &err, SOFTGI_ERR_ARGUMENT,
                 "format 4");
    expect_error(softgi_dump_stages(c, api_dir, NAN, SOFTGI_DUMP_PNG, &err), &err, SOFTGI_ERR_ARGUMENT,
                 "exposure nan");
    ok_or_fail(softgi_dump_stages(c, api_dir, 1.0f, SOFTGI_DUMP_BOTH, &err), &err);
    const char *files[] = {"captions.txt", "00-depth.png", "00-depth.exr"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char a[1024], b[1024];
        snprintf(a, sizeof a, "%s/%s", cli_dir, files[i]);
        snprintf(b, sizeof b, "%s/%s", api_dir, files[i]);
        unsigned char *da, *db;
        size_t na = read_all(a, &da), nb = read_all(b, &db);
        if (!na || na != nb || memcmp(da, db, na)) fail_msg("%s: %zu bytes, %s: %zu bytes, or they differ", a, na, b, nb);
        free(da);
        free(db);
    }
    free(rgb);
    softgi_destroy(c);
}

/* A scene with neither camera nor light: the automatic camera and light
 * (pf_defaults.h), rounded as the program prints them; and with a camera
 * given, the automatic light placed at that camera, as --camera does. */
static void test_same_as_cli_automatic(void **state)
{
    (void)state;
    softgi_desc d = {.width = 96, .height = 72, .threads = 2};
    expect_same_as_cli(&d, NO_CAMERA_NO_LIGHT, NULL, NULL, 0, NO_CAMERA_NO_LIGHT " --size 96x72 --threads 2 -q");
    const softgi_camera cam = {{3, 3, 9}, {4, 1, 2.5f}, 50};
    expect_same_as_cli(&d, NO_CAMERA_NO_LIGHT, &cam, NULL, 0,
                       NO_CAMERA_NO_LIGHT " --size 96x72 --threads 2 --camera 3,3,9:4,1,2.5:50 -q");
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    ok_or_fail(softgi_load_scene(c, NO_CAMERA_NO_LIGHT, &err), &err);
    softgi_info info;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.auto_camera, 1);
    assert_int_equal(info.auto_light, 1);
    assert_int_equal(info.lights, 1);
    softgi_destroy(c);
    /* the shared McGuire box: no camera, an emissive ceiling (no light added) */
    const char *mcguire = SOFTGI_SHARED_SCENES "/cornell_box/CornellBox-Original.gltf";
    if (!tu_file_exists(mcguire)) {
        print_message("SKIP: %s is absent\n", mcguire);
        return;
    }
    char args[1024];
    snprintf(args, sizeof args, "%s --size 96x72 --threads 2 -q", mcguire);
    expect_same_as_cli(&d, mcguire, NULL, NULL, 0, args);
}

/* ---------------------------------------------------------------- animation */

#define ANIM_SKIN SOFTGI_TEST_DATA "/gltf/anim/anim_skin.gltf"
#define ANIM_HIER SOFTGI_TEST_DATA "/gltf/anim/anim_hierarchy.gltf"
#define ANIM_FAR SOFTGI_TEST_DATA "/gltf/anim/anim_far.gltf"

/* The image of a loaded context posed at `t` of `animation` (then rendered
 * once), its hash. */
static uint64_t api_posed_hash(softgi_context *c, double t, const char *animation, float *rgb)
{
    softgi_error err;
    ok_or_fail(softgi_set_time(c, t, animation, &err), &err);
    softgi_target tg = {.rgb = rgb};
    ok_or_fail(softgi_render(c, &tg, &err), &err);
    softgi_info info;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    return softgi_image_hash(rgb, info.width, info.height, 0);
}

/* softgi_set_time = `softgi render --time T --animation A`, bit for bit,
 * on a first frame; a second pose updates the renderer in place: the
 * direct light then equals a fresh context's posed there (Embree, the
 * rasterizer and the shadow maps are a fresh build's) and the whole image
 * is the same for every context that went through the same poses; a time
 * that moves nothing keeps the frame going. */
static void test_set_time(void **state)
{
    (void)state;
    softgi_desc d = {.width = 96, .height = 72, .threads = 2};
    float *cli = NULL, rgb[96 * 72 * 3];
    uint32_t w, h;
    const uint64_t cli_bend = cli_render(ANIM_SKIN " --size 96x72 --threads 2 --time 0.5 --animation bend -q", &cli,
                                         &w, &h);
    free(cli);
    const uint64_t cli_wave = cli_render(ANIM_HIER " --size 96x72 --threads 2 --time 1 --animation 0 --direct-only -q",
                                         &cli, &w, &h);
    free(cli);
    const uint64_t cli_static = cli_render(ANIM_HIER " --size 96x72 --threads 2 --direct-only -q", &cli, &w, &h);
    free(cli);

    softgi_error err;
    softgi_context *c = create_or_fail(&d);
    ok_or_fail(softgi_load_scene(c, ANIM_SKIN, &err), &err);
    softgi_info info;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.animations, 1);
    assert_true(api_posed_hash(c, 0.5, "bend", rgb) == cli_bend);
    softgi_destroy(c);

    softgi_desc dd = d;
    dd.flags = SOFTGI_DIRECT_ONLY;
    c = create_or_fail(&dd);
    ok_or_fail(softgi_load_scene(c, ANIM_HIER, &err), &err);
    assert_true(api_posed_hash(c, 0.3, NULL, rgb) != cli_wave);
    assert_true(api_posed_hash(c, 1.0, NULL, rgb) == cli_wave);     /* updated: as a fresh context at t = 1 */
    assert_true(api_posed_hash(c, 0.0, "wave", rgb) == cli_static); /* t = 0 is the static pose here */
    softgi_destroy(c);
    /* with VPLs: two contexts through the same poses, the same images */
    uint64_t hs[2][3];
    for (int k = 0; k < 2; k++) {
        c = create_or_fail(&d);
        ok_or_fail(softgi_load_scene(c, ANIM_HIER, &err), &err);
        hs[k][0] = api_posed_hash(c, 0.3, NULL, rgb);
        hs[k][1] = api_posed_hash(c, 1.0, NULL, rgb);
        hs[k][2] = api_posed_hash(c, 0.0, "wave", rgb);
        if (k == 0) softgi_destroy(c);
    }
    assert_memory_equal(hs[0], hs[1], sizeof hs[0]);
    assert_true(hs[0][0] != hs[0][1]);
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    const uint32_t frames = info.frames;
    ok_or_fail(softgi_set_time(c, 0.0, "0", &err), &err); /* moves nothing: the frame goes on */
    softgi_target tg = {.rgb = rgb};
    ok_or_fail(softgi_render(c, &tg, &err), &err);
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.frames, frames + 1);

    /* refused, the context unchanged */
    expect_error(softgi_set_time(c, NAN, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "seconds");
    expect_error(softgi_set_time(c, -1.0, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "seconds");
    expect_error(softgi_set_time(c, 2e6, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "seconds");
    expect_error(softgi_set_time(c, 1.0, "walk", &err), &err, SOFTGI_ERR_ARGUMENT, "no animation named 'walk'");
    expect_error(softgi_set_time(c, 1.0, "3", &err), &err, SOFTGI_ERR_ARGUMENT, "no animation 3");
    expect_error(softgi_set_time(NULL, 1.0, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "NULL");
    softgi_destroy(c);

    c = create_or_fail(&d);
    expect_error(softgi_set_time(c, 1.0, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "no scene loaded");
    ok_or_fail(softgi_load_scene(c, NULL, &err), &err);
    expect_error(softgi_set_time(c, 1.0, NULL, &err), &err, SOFTGI_ERR_ARGUMENT, "no animations");
    ok_or_fail(softgi_load_scene(c, ANIM_FAR, &err), &err);
    const uint64_t before = api_posed_hash(c, 0.0, NULL, rgb);
    expect_error(softgi_set_time(c, 1.0, NULL, &err), &err, SOFTGI_ERR_NONFINITE, "beyond");
    ok_or_fail(softgi_render(c, &tg, &err), &err); /* still the scene it was */
    assert_true(softgi_image_hash(rgb, 96, 72, 0) == before);
    softgi_destroy(c);
}

/* ---------------------------------------------------------------- reading back */

static void test_stages_and_timings(void **state)
{
    (void)state;
    const uint32_t W = 64, H = 48;
    softgi_desc d = {.width = W, .height = H, .threads = 2, .vpls = 64};
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    ok_or_fail(softgi_load_scene(c, NULL, &err), &err);
    /* padded rows: the stride is honoured and the padding left alone */
    const size_t stride = 3 * W + 5, stride8 = 4 * W + 3;
    float *rgb = malloc(stride * H * sizeof *rgb), *stage = malloc(stride * H * sizeof *stage);
    uint8_t *rgba = malloc(stride8 * H);
    assert_non_null(rgb);
    assert_non_null(stage);
    assert_non_null(rgba);
    for (size_t i = 0; i < stride * H; i++) rgb[i] = -1.0f;
    memset(rgba, 7, stride8 * H);
    softgi_target t = {.rgb = rgb, .rgb_stride = stride, .rgba8 = rgba, .rgba8_stride = stride8, .exposure = 1.0f};
    ok_or_fail(softgi_render(c, &t, &err), &err);
    for (uint32_t y = 0; y < H; y++) {
        for (uint32_t x = 3 * W; x < stride; x++) assert_true(rgb[y * stride + x] == -1.0f);
        for (uint32_t x = 4 * W; x < stride8; x++) assert_int_equal(rgba[y * stride8 + x], 7);
        for (uint32_t x = 0; x < W; x++) {
            const float *p = rgb + y * stride + 3 * x;
            const uint8_t *q = rgba + y * stride8 + 4 * x;
            for (int k = 0; k < 3; k++) assert_int_equal(q[k], pf_imageio_display(p[k], 2.0f)); /* 2^1 */
            assert_int_equal(q[3], 255);
        }
    }
    /* the final stage is the rendered image */
    ok_or_fail(softgi_read_stage(c, SOFTGI_STAGE_FINAL, stage, stride, &err), &err);
    for (uint32_t y = 0; y < H; y++) assert_memory_equal(stage + y * stride, rgb + y * stride, 3 * W * sizeof(float));
    assert_int_equal(softgi_stage_channels(SOFTGI_STAGE_DEPTH), 1);
    ok_or_fail(softgi_read_stage(c, SOFTGI_STAGE_DEPTH, stage, 0, &err), &err);
    assert_true(stage[(H / 2) * W + W / 2] > 0.0f && isfinite(stage[(H / 2) * W + W / 2]));
    for (int s = 0; s < SOFTGI_STAGE_COUNT; s++) ok_or_fail(softgi_read_stage(c, (softgi_stage)s, stage, 0, &err), &err);
    /* indirect irradiance somewhere in the box */
    ok_or_fail(softgi_read_stage(c, SOFTGI_STAGE_FILTERED, stage, 0, &err), &err);
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)W * H * 3; i++) sum += stage[i];
    assert_true(sum > 0.0);
    /* the timings: the load's steps, then the frame's stages */
    softgi_timing tm[64];
    uint32_t n = softgi_get_timings(c, tm, 64);
    assert_true(n > 5 && n <= 64);
    assert_string_equal(tm[0].name, "load scene");
    assert_string_equal(tm[1].name, "embree build");
    assert_string_equal(tm[2].name, "raster setup");
    for (uint32_t i = 0; i < n; i++) assert_true(tm[i].ms >= 0.0);
    assert_int_equal(softgi_get_timings(c, tm, 2), n); /* the count even when fewer fit */
    softgi_info info;
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.frames, 1);
    assert_true(info.vpls > 0 && info.vpls <= 64);
    assert_true(info.exposure == 1.0f);
    /* a second frame continues; a moved camera renders */
    softgi_camera cam = {{0.3f, 0.3f, -0.7f}, {0.278f, 0.27f, 0.3f}, 40.0f};
    ok_or_fail(softgi_set_camera(c, &cam, &err), &err);
    ok_or_fail(softgi_render(c, &t, &err), &err);
    /* a different number of lights rebuilds the frame */
    softgi_light two[2] = {
        {.type = SOFTGI_LIGHT_POINT, .position = {0.3f, 0.5f, 0.2f}, .color = {1, 1, 1}, .intensity = 0.5f},
        {.type = SOFTGI_LIGHT_POINT, .position = {0.2f, 0.5f, 0.3f}, .color = {1, 1, 1}, .intensity = 0.5f},
    };
    ok_or_fail(softgi_set_lights(c, two, 2, &err), &err);
    ok_or_fail(softgi_render(c, &t, &err), &err);
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_int_equal(info.frames, 3);
    assert_int_equal(info.lights, 2);
    softgi_destroy(c);

    /* no VPLs: no irradiance to read */
    softgi_desc direct = {.width = W, .height = H, .threads = 1, .flags = SOFTGI_DIRECT_ONLY};
    c = create_or_fail(&direct);
    ok_or_fail(softgi_load_scene(c, NULL, &err), &err);
    ok_or_fail(softgi_render(c, &t, &err), &err);
    expect_error(softgi_read_stage(c, SOFTGI_STAGE_IRRADIANCE, stage, 0, &err), &err, SOFTGI_ERR_ARGUMENT,
                 "no indirect light");
    ok_or_fail(softgi_get_info(c, &info, &err), &err);
    assert_null(info.method);
    softgi_destroy(c);
    free(rgb);
    free(stage);
    free(rgba);
}

/* ---------------------------------------------------------------- threads, FP environment */

typedef struct job {
    uint64_t hash;
    int ok;
} job;

static void *render_one(void *arg)
{
    job *j = arg;
    softgi_desc d = {.width = 80, .height = 60, .threads = 2, .vpls = 64};
    softgi_error err;
    softgi_context *c = softgi_create(&d, &err);
    float rgb[80 * 60 * 3];
    softgi_target t = {.rgb = rgb};
    j->ok = c && softgi_load_scene(c, NULL, &err) == SOFTGI_OK && softgi_render(c, &t, &err) == SOFTGI_OK;
    j->hash = softgi_image_hash(rgb, 80, 60, 0);
    softgi_destroy(c);
    return NULL;
}

/* Two contexts on two threads at once share nothing: each gives the image
 * one context gives alone. */
static void test_two_contexts(void **state)
{
    (void)state;
    job alone = {0}, a = {0}, b = {0};
    render_one(&alone);
    assert_true(alone.ok);
    pthread_t ta, tb;
    assert_int_equal(pthread_create(&ta, NULL, render_one, &a), 0);
    assert_int_equal(pthread_create(&tb, NULL, render_one, &b), 0);
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    assert_true(a.ok && b.ok);
    assert_true(a.hash == alone.hash && b.hash == alone.hash);
}

/* The calls set FTZ/DAZ for themselves and give the caller's MXCSR back. */
static void test_fpenv_restored(void **state)
{
    (void)state;
#if defined(__x86_64__) || defined(__i386__)
    const unsigned int before = _mm_getcsr();
    _mm_setcsr(before & ~(0x8040u)); /* FTZ and DAZ off, as a program's default */
    const unsigned int mine = _mm_getcsr();
    softgi_desc d = {.width = 32, .height = 24, .threads = 2};
    softgi_context *c = create_or_fail(&d);
    softgi_error err;
    ok_or_fail(softgi_load_scene(c, NULL, &err), &err);
    assert_int_equal(_mm_getcsr(), mine);
    float rgb[32 * 24 * 3];
    softgi_target t = {.rgb = rgb};
    ok_or_fail(softgi_render(c, &t, &err), &err);
    assert_int_equal(_mm_getcsr(), mine);
    softgi_destroy(c);
    _mm_setcsr(before);
#else
    skip();
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_destroy),
        cmocka_unit_test(test_bad_desc),
        cmocka_unit_test(test_bad_scene),
        cmocka_unit_test(test_budget),
        cmocka_unit_test(test_same_as_cli_default),
        cmocka_unit_test(test_same_as_cli_file),
        cmocka_unit_test(test_same_as_cli_options),
        cmocka_unit_test(test_same_as_cli_camera_lights),
        cmocka_unit_test(test_same_as_cli_automatic),
        cmocka_unit_test(test_set_time),
        cmocka_unit_test(test_same_as_cli_frame_options),
        cmocka_unit_test(test_same_as_cli_option_sets),
        cmocka_unit_test(test_progress),
        cmocka_unit_test(test_taa_frames),
        cmocka_unit_test(test_dump_stages),
        cmocka_unit_test(test_stages_and_timings),
        cmocka_unit_test(test_two_contexts),
        cmocka_unit_test(test_fpenv_restored),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
