/* test_cli: the softgi program as a user meets it.
 * - bad input of every kind gives a one-line message and a non-zero exit
 *   (2 for bad usage, 1 for a bad scene or file), never a crash;
 * - `softgi render` writes its PNG and PFM, and the same render with
 *   --threads 1 and --threads 2 prints the same --hash;
 * - the PFM it writes holds exactly the hashed data. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "pf_imageio.h"
#include "test_util.h"

#define DATA SOFTGI_TEST_DATA "/gltf/"

static char g_tmp[256];

static void test_usage_errors(void **state)
{
    (void)state;
    tu_softgi_expect("--help", 0, "usage: softgi render");
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
    /* 1,000,000 paraboloid maps (31 GiB) exceed the memory budget: refused before allocating, with the hint */
    tu_softgi_expect("render --vpls 1000000 --max-memory 8G -q -o /dev/null/x.png", 1,
                     "use fewer VPLs or --visibility raytrace");
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
    /* a scene without a camera needs --camera */
    tu_softgi_expect("render " DATA "quad_u16.gltf -o /dev/null/x.png", 1, "has no camera");
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
        cmocka_unit_test(test_bad_scenes),
        cmocka_unit_test(test_render_outputs_and_threads),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
