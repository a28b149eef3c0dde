/* test_defaults: scenes that just work (issue 16, item 2; pf_defaults.h).
 * - every shared scene (../shared/scenes; skipped when absent) rendered with
 *   no --camera and no --light gives a lit image (mean luminance above a
 *   floor, no nearly-black hint) and says what it chose in one note line
 *   each; copying the printed --camera and --light gives the same image bit
 *   for bit;
 * - a scene with a camera and lights renders exactly as before: no note,
 *   and the golden hash of the embedded Cornell box, with its picture;
 * - --exposure auto changes the PNG, never the linear image;
 * - a tiny light gets the nearly-black hint; bad --exposure values exit 2;
 * - the pure functions: an enclosed room is looked down from inside, a lone
 *   quad from outside, hostile coordinates stay in range, the exposure maps
 *   the log-average to 18% grey; a sequence without camera keys uses the
 *   same automatic camera and light. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "pf_defaults.h"
#include "pf_imageio.h"
#include "test_util.h"
#include "tu_golden.h"

#define DATA SOFTGI_TEST_DATA "/gltf/"
#define SHARED SOFTGI_SHARED_SCENES "/"

/* softgi render --isa sse2 --size 160x120 --hash (the embedded Cornell box,
 * camera and lights in the file): the hash printed before the defaults
 * existed (commit b000459, c0e3866d3f782e79), changed since only by the
 * paraboloid maps' receiver-plane test (2026-12-03, docs/frame.md): a
 * scene with a camera and lights must not change with the defaults. */
#define GOLDEN_CLI_CORNELL_SSE2 0xa75db235fa702a56ull

static char g_tmp[256];

/* The value after `key` in `out` up to the next space or ')' into buf. */
static int value_after(const char *out, const char *key, char *buf, size_t size)
{
    const char *p = strstr(out, key);
    if (!p) return 0;
    p += strlen(key);
    size_t n = strcspn(p, " )\n");
    if (n == 0 || n >= size) return 0;
    memcpy(buf, p, n);
    buf[n] = 0;
    return 1;
}

/* Mean BT.709 luminance of a PFM. */
static double mean_luminance(const char *path)
{
    float *rgb;
    uint32_t w, h;
    pf_error err;
    if (pf_imageio_read_pfm(path, &rgb, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
    double sum = 0.0;
    for (uint64_t i = 0; i < (uint64_t)w * h; i++) sum += pf_luminance(pf_v3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]));
    free(rgb);
    return sum / ((double)w * h);
}

static void test_shared_scenes(void **state)
{
    (void)state;
    static const struct {
        const char *file, *name;
        int emitters; /* lit by its own emissive triangles: no default light */
    } k[] = {
        {SHARED "sibenik/sibenik.gltf", "sibenik", 0},
        {SHARED "conference/conference.gltf", "conference", 0},
        {SHARED "sponza_dabrovic/sponza.gltf", "sponza", 0},
        {SHARED "cornell_box/CornellBox-Original.gltf", "cornell", 1},
    };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        if (!tu_file_exists(k[i].file)) {
            print_message("SKIP: %s is absent (the shared scenes are not checked out beside the repo)\n", k[i].file);
            continue;
        }
        static char out[32768], out2[32768];
        char args[2048], camera[256], light[256] = "", path[512];
        snprintf(args, sizeof args, "render %s --size 96x72 --isa sse2 --hash -o %s/%s.png", k[i].file, g_tmp,
                 k[i].name);
        assert_int_equal(tu_softgi_run(args, out, sizeof out), 0);
        if (!value_after(out, "has no camera; using --camera ", camera, sizeof camera))
            fail_msg("%s: no camera note:\n%s", k[i].name, out);
        int has_light = value_after(out, "has no lights; added --light ", light, sizeof light);
        if (has_light == k[i].emitters) fail_msg("%s: light note %d, want %d:\n%s", k[i].name, has_light, !k[i].emitters, out);
        if (strstr(out, "nearly black")) fail_msg("%s: nearly black:\n%s", k[i].name, out);
        snprintf(path, sizeof path, "%s/%s.pfm", g_tmp, k[i].name);
        double mean = mean_luminance(path);
        print_message("%s: --camera %s --light %s: mean luminance %.4f\n", k[i].name, camera,
                      has_light ? light : "(its emitters)", mean);
        assert_true(mean > 0.02);
        /* the printed values, copied, give the same image */
        snprintf(args, sizeof args, "render %s --size 96x72 --isa sse2 --hash -o %s/%s-copy.png --camera %s%s%s",
                 k[i].file, g_tmp, k[i].name, camera, has_light ? " --light " : "", has_light ? light : "");
        assert_int_equal(tu_softgi_run(args, out2, sizeof out2), 0);
        assert_null(strstr(out2, "softgi: note:"));
        const char *h1 = strstr(out, "hash "), *h2 = strstr(out2, "hash ");
        assert_non_null(h1);
        assert_non_null(h2);
        if (strncmp(h1, h2, 21) != 0) fail_msg("%s: the copied camera and light differ:\n%s\n%s", k[i].name, h1, h2);
    }
}

static void test_camera_and_lights_unchanged(void **state)
{
    (void)state;
    char args[1024], out[16384];
    snprintf(args, sizeof args, "render --isa sse2 --size 160x120 --hash -o %s/golden.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out, sizeof out), 0);
    assert_null(strstr(out, "softgi: note:"));
    const char *line = strncmp(out, "hash ", 5) == 0 ? out : strstr(out, "\nhash ");
    unsigned long long h;
    if (!line || sscanf(line + (*line == '\n'), "hash %16llx", &h) != 1) fail_msg("no hash line:\n%s", out);
    char png[4200];
    snprintf(png, sizeof png, "%s/golden.png", g_tmp);
    tu_golden_picture pic; /* the PNG softgi wrote */
    tu_golden_picture_load(&pic, png);
    tu_golden_check("cli-render-cornell", h, GOLDEN_CLI_CORNELL_SSE2, &pic);
    tu_golden_picture_free(&pic);
}

/* The bytes of a file (caller frees); fails the test if unreadable. */
static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return b;
}

static void test_exposure_auto(void **state)
{
    (void)state;
    char args[1024], out1[16384], out2[16384], p[512];
    snprintf(args, sizeof args, "render --size 64x48 --isa sse2 --hash -o %s/e0.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out1, sizeof out1), 0);
    snprintf(args, sizeof args, "render --size 64x48 --isa sse2 --hash --exposure auto -o %s/ea.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out2, sizeof out2), 0);
    if (!strstr(out2, "softgi: note: --exposure auto: ")) fail_msg("no exposure note:\n%s", out2);
    /* the linear image is the same, the PNG is not */
    assert_int_equal(strncmp(strstr(out1, "hash "), strstr(out2, "hash "), 21), 0);
    size_t n0, na;
    snprintf(p, sizeof p, "%s/e0.png", g_tmp);
    char *png0 = slurp(p, &n0);
    snprintf(p, sizeof p, "%s/ea.png", g_tmp);
    char *pnga = slurp(p, &na);
    assert_true(n0 != na || memcmp(png0, pnga, n0) != 0);
    free(png0);
    free(pnga);
    /* bad values */
    tu_softgi_expect("render --exposure autox", 2, "--exposure 'autox': expected a number of stops in -64..64, or auto");
    tu_softgi_expect("render --exposure AUTO", 2, "--exposure");
    tu_softgi_expect("render --exposure ''", 2, "--exposure");
    tu_softgi_expect("render --exposure nan", 2, "--exposure");
    tu_softgi_expect("render --exposure 65", 2, "--exposure");
    tu_softgi_expect("render --exposure", 2, "--exposure needs a value");
    tu_softgi_expect("render --help", 0, "--exposure STOPS|auto");
}

static void test_nearly_black_hint(void **state)
{
    (void)state;
    char args[1024];
    /* a tiny light: the hint; --exposure auto rescues it (no hint) */
    snprintf(args, sizeof args,
             "render " DATA "quad_u16.gltf --camera 0.5,0.5,2:0.5,0.5,0:50 --light point:0.5,0.5,1:1,1,1:1e-6 "
             "--size 32x24 -o %s/dark.png",
             g_tmp);
    tu_softgi_expect(args, 0, "softgi: note: the image is nearly black");
    tu_softgi_expect(args, 0, "try --exposure auto or a brighter --light");
    char out[16384];
    snprintf(args, sizeof args,
             "render " DATA "quad_u16.gltf --camera 0.5,0.5,2:0.5,0.5,0:50 --light point:0.5,0.5,1:1,1,1:1e-6 "
             "--size 32x24 --exposure auto -o %s/dark-auto.png",
             g_tmp);
    assert_int_equal(tu_softgi_run(args, out, sizeof out), 0);
    assert_null(strstr(out, "nearly black"));
    /* -q: no notes at all */
    snprintf(args, sizeof args, "render " DATA "quad_u16.gltf --size 32x24 -q -o %s/quiet.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out, sizeof out), 0);
    assert_null(strstr(out, "note"));
    /* no camera, no light: both notes, and a lit quad */
    snprintf(args, sizeof args, "render " DATA "quad_u16.gltf --size 32x24 -o %s/quad.png", g_tmp);
    assert_int_equal(tu_softgi_run(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "has no camera; using --camera "));
    assert_non_null(strstr(out, "(outside: the bounds fill 80% of the view)"));
    assert_non_null(strstr(out, "has no lights; added --light point:"));
    assert_null(strstr(out, "nearly black"));
}

static void test_sequence_defaults(void **state)
{
    (void)state;
    char p[512], args[1024], out[16384];
    snprintf(p, sizeof p, "%s/quad.seq.json", g_tmp);
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fprintf(f, "{\"scene\": \"%s\", \"frames\": 2, \"size\": [32, 24]}\n", DATA "quad_u16.gltf");
    fclose(f);
    snprintf(args, sizeof args, "sequence %s --exposure auto -o %s/seq", p, g_tmp);
    assert_int_equal(tu_softgi_run(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "has no camera; using --camera "));
    assert_non_null(strstr(out, "has no lights; added --light point:"));
    assert_non_null(strstr(out, "--exposure auto: "));
    assert_null(strstr(out, "nearly black"));
}

/* ---------------------------------------------------------------- the pure functions */

static void test_camera_choice(void **state)
{
    (void)state;
    /* a closed room 8 x 3 x 4 (x longest), walls facing in */
    const tu_quad room[6] = {
        {{0, 0, 0}, {0, 0, 2}, {4, 0, 0}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},  /* floor */
        {{0, 3, 0}, {4, 0, 0}, {0, 0, 2}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},  /* ceiling */
        {{-4, 1.5f, 0}, {0, 1.5f, 0}, {0, 0, 2}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},
        {{4, 1.5f, 0}, {0, 0, 2}, {0, 1.5f, 0}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},
        {{0, 1.5f, -2}, {4, 0, 0}, {0, 1.5f, 0}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},
        {{0, 1.5f, 2}, {0, 1.5f, 0}, {4, 0, 0}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},
    };
    pf_scene s;
    pf_error err;
    tu_make_scene(&s, room, 6);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_default_camera c;
    pf_defaults_camera(&c, &s);
    assert_true(c.interior);
    assert_int_equal(c.hits, 26);
    assert_int_equal(c.axis, 'x');
    assert_true(fabsf(c.eye.x) > 2.0f && fabsf(c.eye.x) < 4.0f); /* near one end, inside */
    assert_true(c.eye.x * c.target.x < 0.0f);                    /* looking down the room */
    /* the light: above the eye, under the ceiling, 1 W/m^2 at the median distance */
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, c.eye, c.target, pf_radians(c.fovy_deg), &err), PF_OK);
    pf_light l;
    float d;
    pf_defaults_light(&l, &d, &s, &cam, 64, 48);
    assert_true(d > 1.0f && d < 8.0f);
    assert_true(l.position.y > c.eye.y && l.position.y < 3.0f);
    assert_float_equal(l.intensity, APP_DEFAULT_IRRADIANCE * d * d, 1e-3f * d * d);
    pf_scene_free(&s);

    /* a lone quad: outside, the bounds in view */
    const tu_quad quad = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1}, 0, 0};
    tu_make_scene(&s, &quad, 1);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_defaults_camera(&c, &s);
    assert_false(c.interior);
    assert_true(c.eye.z > 1.0f);
    assert_float_equal(c.target.x, 0.0f, 1e-6f);
    pf_scene_free(&s);

    /* hostile: a quad at the coordinate limit; the camera and light stay in range */
    const tu_quad far = {{9.9e6f, 9.9e6f, 0}, {1e5f, 0, 0}, {0, 1e5f, 0}, {1, 1, 1, 1}, 0, 0};
    tu_make_scene(&s, &far, 1);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_defaults_camera(&c, &s);
    assert_true(pf_scene_coord_ok(c.eye) && pf_scene_coord_ok(c.target));
    assert_int_equal(pf_camera_look_at(&cam, c.eye, c.target, pf_radians(c.fovy_deg), &err), PF_OK);
    pf_defaults_light(&l, &d, &s, &cam, 64, 48);
    assert_true(pf_scene_coord_ok(l.position));
    assert_true(l.intensity > 0.0f && l.intensity <= PF_MAX_RADIANCE);
    pf_scene_free(&s);
}

static void test_exposure_maths(void **state)
{
    (void)state;
    float img[3 * 4 * 4];
    for (int i = 0; i < 16; i++) img[3 * i] = img[3 * i + 1] = img[3 * i + 2] = i < 8 ? 2.0f : 0.0f;
    double avg;
    float ev = pf_defaults_exposure(img, 4, 4, &avg); /* black pixels ignored */
    assert_float_equal((float)avg, 2.0f, 1e-5f);
    float x = 2.0f * exp2f(ev);
    assert_float_equal(x / (1.0f + x), APP_DEFAULT_GREY, 1e-5f);
    assert_false(pf_defaults_nearly_black(img, 4, 4, 0.0f));
    assert_true(pf_defaults_nearly_black(img, 4, 4, -10.0f)); /* 2 / 1024 < 0.01 */
    memset(img, 0, sizeof img);
    assert_float_equal(pf_defaults_exposure(img, 4, 4, NULL), 0.0f, 0.0f);
    assert_true(pf_defaults_nearly_black(img, 4, 4, 0.0f));
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-defaults");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_choice),
        cmocka_unit_test(test_exposure_maths),
        cmocka_unit_test(test_camera_and_lights_unchanged),
        cmocka_unit_test(test_exposure_auto),
        cmocka_unit_test(test_nearly_black_hint),
        cmocka_unit_test(test_sequence_defaults),
        cmocka_unit_test(test_shared_scenes),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
