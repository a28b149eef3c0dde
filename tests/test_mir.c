/* test_mir: the MIR-style baseline (gi_mir.c, Hedman 2017 Sec. 5.1).
 * - Convergence: MIR's indirect image (1024 and 4096 VPLs resampled 16:1,
 *   the test-time stand-in for 256:1; Embree visibility, the default clamp,
 *   no filter) against Instant Radiosity's with 16384 VPLs (test_vpl checks
 *   IR against the reference) on the Cornell box with its light in the
 *   middle (as test_vpl): the mean relative error per pixel falls from 1024
 *   to 4096 VPLs (measured 11.5% -> 6.8%) and is < 10% at 4096; the image
 *   means agree within 3% at both (measured 0.7%: resampling keeps the
 *   estimate unbiased; the clamp takes a little more or less energy
 *   depending on where the VPLs are).
 * - Determinism: the VPL set of a frame is identical with 1 and 2 threads;
 *   every VPL is `moved` every frame, and two frames differ (independent).
 * - View adaptation: a floor and a ceiling lit by a point light between
 *   them, the camera looking at the left half of the floor only: IR puts
 *   half the VPLs above each half; MIR with the default defensive fraction
 *   d = 0.3 puts > 70% above the visible half (at most about
 *   (1 - d) + d / 2 = 85% can be), with d = 0.05 > 85%.
 * - Bad parameters and a missing G-buffer give clear errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "gi_reference.h"
#include "pf_gltf.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

typedef tu_fx fx;

static void fx_begin_clamp(fx *x, uint32_t threads, uint32_t w, uint32_t h, const pf_camera *cam, const char *method,
                           uint32_t vpls, const char *param, float clamp)
{
    pf_error err;
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = gi_vpl_method_find(method);
    if (param) assert_int_equal(gi_params_add(&io.params, param, &err), PF_OK);
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.vpls = vpls;
    io.clamp = clamp;
    io.filter = GI_FILTER_NONE;
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, w, h, cam, &io, 1);
}

static void fx_begin(fx *x, uint32_t threads, uint32_t w, uint32_t h, const pf_camera *cam, const char *method,
                     uint32_t vpls, const char *param)
{
    fx_begin_clamp(x, threads, w, h, cam, method, vpls, param, 0.0f);
}

static void fx_end(fx *x) { tu_fx_end(x); }

static void cornell(fx *x)
{
    pf_error err;
    assert_int_equal(pf_gltf_load(&x->scene, CORNELL, NULL, &err), PF_OK);
    x->scene.lights[0].position = pf_v3(0.278f, 0.35f, 0.28f);
    x->scene.lights[0].intensity = 0.3f;
}

/* Mean relative luminance error of MIR (vpls, 16:1) against the IR image
 * `ir` (W x H) and the ratio of the image means. */
enum { CW = 40, CH = 30 };
static void mir_vs_ir(uint32_t vpls, const float *ir, double *mre, double *ratio)
{
    fx a;
    cornell(&a);
    fx_begin_clamp(&a, 2, CW, CH, &a.scene.cameras[0], "mir", vpls, "ratio=16", -1.0f);
    gi_frame_render_raster(&a.f);
    assert_int_equal(a.f.ind.vpls.count, vpls);
    double sum = 0.0, sa = 0.0, sb = 0.0;
    int n = 0;
    for (size_t i = 0; i < (size_t)CW * CH; i++) {
        double ya = 0.2126 * a.f.final[3 * i] + 0.7152 * a.f.final[3 * i + 1] + 0.0722 * a.f.final[3 * i + 2];
        double yb = 0.2126 * ir[3 * i] + 0.7152 * ir[3 * i + 1] + 0.0722 * ir[3 * i + 2];
        if (!(yb > 1e-5)) continue;
        sum += fabs(ya - yb) / yb;
        sa += ya, sb += yb;
        n++;
    }
    assert_true(n > CW * CH / 2);
    *mre = sum / n;
    *ratio = sa / sb;
    print_message("MIR (%u VPLs, 16:1) vs IR (16384), default clamp: mean relative error %.4f over %d pixels, ratio of "
                  "means %.4f\n",
                  vpls, *mre, n, *ratio);
    fx_end(&a);
}

static void test_converges_to_ir(void **state)
{
    (void)state;
    static float ir[3 * CW * CH];
    fx b;
    cornell(&b);
    fx_begin_clamp(&b, 2, CW, CH, &b.scene.cameras[0], "ir", 16384, NULL, -1.0f);
    gi_frame_render_raster(&b.f);
    memcpy(ir, b.f.final, sizeof ir);
    fx_end(&b);
    double m1, r1, m4, r4;
    mir_vs_ir(1024, ir, &m1, &r1);
    mir_vs_ir(4096, ir, &m4, &r4);
    assert_true(m4 < m1); /* more VPLs: closer */
    assert_true(m4 < 0.10);
    assert_true(fabs(r1 - 1.0) < 0.03 && fabs(r4 - 1.0) < 0.03);
}

static uint64_t hash_vpls(const gi_vpl_set *s)
{
    uint64_t h = 1469598103934665603ull;
    const unsigned char *p = (const unsigned char *)s->v;
    for (size_t i = 0; i < sizeof(gi_vpl) * s->count; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

static void two_frames(uint32_t threads, uint64_t h[2])
{
    fx x;
    cornell(&x);
    fx_begin(&x, threads, 32, 24, &x.scene.cameras[0], "mir", 256, "ratio=32");
    for (int k = 0; k < 2; k++) {
        gi_frame_render_raster(&x.f);
        assert_int_equal(x.f.ind.vpls.count, 256);
        for (uint32_t i = 0; i < x.f.ind.vpls.count; i++) assert_int_equal(x.f.ind.vpls.v[i].moved, 1);
        h[k] = hash_vpls(&x.f.ind.vpls);
    }
    fx_end(&x);
}

static void test_threads_identical(void **state)
{
    (void)state;
    uint64_t a[2], b[2];
    two_frames(1, a);
    two_frames(2, b);
    assert_true(a[0] == b[0] && a[1] == b[1]);
    assert_true(a[0] != a[1]); /* a new, independent set every frame */
}

/* Floor (y = 0) and ceiling (y = 2), 20 x 20, a point light at (0, 1, 0);
 * the camera at x = -5 looks down at the floor around x = -5 only. */
static double visible_half_fraction(const char *method, const char *param)
{
    fx x;
    tu_quad q[2] = {
        {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {0.8f, 0.8f, 0.8f, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 2, 0}, {10, 0, 0}, {0, 0, 10}, {0.8f, 0.8f, 0.8f, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    tu_make_scene(&x.scene, q, 2);
    pf_light L;
    memset(&L, 0, sizeof L);
    L.type = PF_LIGHT_POINT;
    L.position = pf_v3(0, 1, 0);
    L.color = pf_v3(1, 1, 1);
    L.intensity = 10.0f;
    pf_error err;
    assert_int_equal(pf_scene_add_light(&x.scene, &L, &err), PF_OK);
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(-5, 1.5f, 0.01f), pf_v3(-5, 0, 0), pf_radians(90), &err), PF_OK);
    fx_begin(&x, 2, 32, 32, &cam, method, 1024, param);
    gi_frame_render_raster(&x.f);
    uint32_t left = 0, n = x.f.ind.vpls.count;
    for (uint32_t i = 0; i < n; i++) left += x.f.ind.vpls.v[i].pos.x < 0.0f;
    fx_end(&x);
    assert_true(n > 0);
    return (double)left / n;
}

static void test_concentrates_in_view(void **state)
{
    (void)state;
    double mir = visible_half_fraction("mir", NULL), ir = visible_half_fraction("ir", NULL);
    double mir05 = visible_half_fraction("mir", "defensive=0.05");
    print_message("VPLs above the visible half: MIR %.1f%% (d = 0.05: %.1f%%), IR %.1f%%\n", 100.0 * mir, 100.0 * mir05,
                  100.0 * ir);
    assert_true(mir > 0.70);
    assert_true(mir05 > 0.85);
    assert_true(fabs(ir - 0.5) < 0.1);
}

static void test_bad_input(void **state)
{
    (void)state;
    const gi_vpl_method *m = gi_vpl_method_find("mir");
    assert_non_null(m);
    const char *bad[] = {"ratio=0", "ratio=x", "evals=9", "defensive=2", "points=0", "colour=1"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        gi_params p = {0};
        pf_error err;
        assert_int_equal(gi_params_add(&p, bad[k], &err), PF_OK);
        void *st = NULL;
        assert_int_equal(m->create(&st, &p, &err), PF_ERR_ARGUMENT);
        assert_null(st);
        print_message("%s: %s\n", bad[k], err.message);
    }
    /* no G-buffer: a clear error, not a crash */
    pf_scene s;
    tu_quad q = {{0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f};
    tu_make_scene(&s, &q, 1);
    pf_error err;
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    void *st;
    assert_int_equal(m->create(&st, NULL, &err), PF_OK);
    gi_area_lights area = {0};
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0, 1, 0.01f), pf_v3(0, 0, 0), pf_radians(60), &err), PF_OK);
    gi_vpl_inputs in = {&s, rt, NULL, &cam, 0, 16, 3, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    gi_vpl_set out = {0};
    assert_int_equal(m->update(st, &in, &out, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "G-buffer"));
    m->destroy(st);
    gi_vpl_set_free(&out);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_converges_to_ir),
        cmocka_unit_test(test_threads_identical),
        cmocka_unit_test(test_concentrates_in_view),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
