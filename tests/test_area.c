/* test_area: emissive triangles as area lights (gi_area, the direct light
 * of both frames, the reference's NEE, Instant Radiosity's light paths).
 *
 * - Analytic: a square emitter (Le, 1 x 1, facing down, black) at height 1
 *   above a floor (albedo rho). A floor point receives E = pi Le F with F the
 *   point-to-parallel-rectangle form factor, written as the signed sum of
 *   four corner rectangles (each corner above the point, X = dx/h, Y = dz/h):
 *     G(X, Y) = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))]
 *     F = G(x1', z1') - G(x0', z1') - G(x1', z0') + G(x0', z0'),  x' = (x - px)/h
 *   (G is odd in X and in Y, so the sum holds for points outside the
 *   footprint too). The frame's direct radiance rho/pi E = rho Le F is
 *   checked at every floor pixel (its G-buffer position), with errors
 *   relative to the largest value rho Le F(centre):
 *     ray-traced, 16 x 16 stratified samples: mean < 0.5%, worst < 3%
 *       (and the default 4 x 4: mean < 3%);
 *     raster, K = 32 points with paraboloid maps: mean < 2%, worst < 6%
 *       (a 32-point quadrature of a smooth integrand; no shadows here), and
 *       K = 256 must be closer than K = 32;
 *   and the reference (direct only, NEE) at single points seen through an
 *   8 x 8 image with a 0.01 degree field of view (64 independent estimates
 *   of 256 spp), within 5 standard errors (estimated from their spread;
 *   the standard error itself must be < 1%); its
 *   indirect-only image is exactly 0 (the only bounce lands on the black
 *   emitter).
 * - Furnace with NEE (closed sphere): the mean over independent pixels
 *   within 5 standard errors of sum_{k=0..B+1} rho^k, B = 0, 1, 2.
 * - Convergence: Instant Radiosity with the area light as its only light
 *   (8192 VPLs, Embree visibility, no clamp, no filter) against the
 *   reference (4096 spp), indirect only, 3 bounces, in a closed box lit by
 *   an emissive quad under its ceiling: mean relative error per pixel < 4%
 *   (measured 1.3%) and ratio of means within 2% (measured 0.3%).
 * - Determinism: the direct light of both frames and the IR frame with the
 *   area light are identical with 1 and 2 threads.
 * - The McGuire Cornell box (shared scenes; skipped when absent): the
 *   raster direct light's residual against the ray-traced one, printed for
 *   the README (relative L1), with loose bounds and K = 128 closer than
 *   K = 32. */
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

static const float k_rho = 0.6f, k_le = 2.0f, k_h = 1.0f;

/* Floor at y = 0 and the emitter [-0.5, 0.5]^2 at y = h, facing down. */
static void emitter_scene(pf_scene *s)
{
    tu_quad q[2] = {
        {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {k_rho, k_rho, k_rho, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, k_h, 0}, {0.5f, 0, 0}, {0, 0, 0.5f}, {0, 0, 0, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    tu_make_scene(s, q, 2);
    for (int c = 0; c < 3; c++) s->materials[1].emission[c] = k_le;
    pf_error err;
    assert_int_equal(pf_scene_validate(s, &err), PF_OK);
}

static double corner_g(double X, double Y)
{
    double sx = sqrt(1 + X * X), sy = sqrt(1 + Y * Y);
    return (X / sx * atan(Y / sx) + Y / sy * atan(X / sy)) / (2.0 * M_PI);
}

/* Form factor from floor point (px, pz) to the emitter. */
static double form_factor(double px, double pz)
{
    double x0 = (-0.5 - px) / k_h, x1 = (0.5 - px) / k_h, z0 = (-0.5 - pz) / k_h, z1 = (0.5 - pz) / k_h;
    return corner_g(x1, z1) - corner_g(x0, z1) - corner_g(x1, z0) + corner_g(x0, z0);
}

typedef tu_fx fx;

static void fx_begin(fx *x, uint32_t threads, uint32_t w, uint32_t h, const pf_camera *cam)
{
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, w, h, cam, NULL, 0);
}

static void fx_end(fx *x) { tu_fx_end(x); }

static void floor_camera(pf_camera *cam)
{
    pf_error err;
    assert_int_equal(pf_camera_look_at(cam, pf_v3(0.03f, 0.7f, 0.02f), pf_v3(0, 0, 0), pf_radians(100), &err), PF_OK);
}

/* Mean and worst |direct - rho Le F| / (rho Le F(0, 0)) over floor pixels. */
static void direct_error(const gi_frame *f, double *mean, double *worst)
{
    double top = k_rho * k_le * form_factor(0, 0), sum = 0.0;
    int n = 0;
    *worst = 0.0;
    for (size_t i = 0; i < (size_t)f->width * f->height; i++) {
        if (f->gbuf.prim[i] != 0 && f->gbuf.prim[i] != 1) continue; /* the floor's two triangles */
        double want = k_rho * k_le * form_factor(f->gbuf.pos_x[i], f->gbuf.pos_z[i]);
        for (int c = 0; c < 3; c++) {
            double e = fabs(f->direct[3 * i + c] - want) / top;
            sum += e;
            *worst = fmax(*worst, e);
            n++;
        }
    }
    assert_true(n > 3 * 1000);
    *mean = sum / n;
}

static void test_direct_raytrace_analytic(void **state)
{
    (void)state;
    fx x;
    emitter_scene(&x.scene);
    pf_camera cam;
    floor_camera(&cam);
    fx_begin(&x, 2, 64, 64, &cam);
    pf_error err;
    assert_int_equal(gi_frame_set_area_sampling(&x.f, 16, GI_AREA_DEFAULT_POINTS, &err), PF_OK);
    gi_stage_gbuffer_raytrace(&x.f);
    gi_stage_direct_raytrace(&x.f);
    double mean, worst;
    direct_error(&x.f, &mean, &worst);
    print_message("ray-traced direct (256 stratified samples): mean error %.5f, worst %.5f of the peak\n", mean, worst);
    assert_true(mean < 0.005);
    assert_true(worst < 0.03);
    /* the default 4 x 4 strata: noisier, still unbiased on average */
    assert_int_equal(gi_frame_set_area_sampling(&x.f, GI_AREA_DEFAULT_STRATA, GI_AREA_DEFAULT_POINTS, &err), PF_OK);
    gi_stage_direct_raytrace(&x.f);
    direct_error(&x.f, &mean, &worst);
    print_message("ray-traced direct (16 stratified samples): mean error %.5f, worst %.5f of the peak\n", mean, worst);
    assert_true(mean < 0.03);
    fx_end(&x);
}

static void test_direct_raster_analytic(void **state)
{
    (void)state;
    fx x;
    emitter_scene(&x.scene);
    pf_camera cam;
    floor_camera(&cam);
    fx_begin(&x, 2, 64, 64, &cam);
    pf_error err;
    double mean32, worst32, mean256, worst256;
    gi_frame_render_raster(&x.f);
    direct_error(&x.f, &mean32, &worst32);
    assert_int_equal(gi_frame_set_area_sampling(&x.f, GI_AREA_DEFAULT_STRATA, 256, &err), PF_OK);
    gi_frame_render_raster(&x.f);
    direct_error(&x.f, &mean256, &worst256);
    print_message("raster direct K=32: mean error %.5f, worst %.5f; K=256: mean %.5f, worst %.5f of the peak\n",
                  mean32, worst32, mean256, worst256);
    assert_true(mean32 < 0.02);
    assert_true(worst32 < 0.06);
    assert_true(mean256 < mean32);
    assert_true(gi_frame_set_area_sampling(&x.f, 1, 0, &err) == PF_ERR_ARGUMENT);
    assert_true(gi_frame_set_area_sampling(&x.f, 17, 32, &err) == PF_ERR_ARGUMENT);
    fx_end(&x);
}

/* The reference at floor point (px, pz): direct only (NEE) and indirect only. */
static void test_reference_analytic(void **state)
{
    (void)state;
    pf_scene s;
    emitter_scene(&s);
    pf_error err;
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    pf_jobs *jobs = pf_jobs_create(2);
    const float pts[4][2] = {{0.0f, 0.0f}, {0.3f, -0.2f}, {0.7f, 0.1f}, {1.2f, 0.9f}};
    for (int k = 0; k < 4; k++) {
        pf_camera cam;
        assert_int_equal(pf_camera_look_at(&cam, pf_v3(pts[k][0] + 0.001f, 0.5f, pts[k][1]),
                                           pf_v3(pts[k][0], 0, pts[k][1]), pf_radians(0.01f), &err),
                         PF_OK);
        /* 8 x 8 pixels through a 0.01 degree view all see the point (to
         * 1e-4): 64 independent estimates (the random numbers hash the
         * pixel), 256 spp each, give the mean and its standard error */
        enum { N = 8 };
        gi_reference_options o = {0};
        o.spp = 256;
        o.direct_only = 1;
        float img[3 * N * N];
        assert_int_equal(gi_reference_render(img, &s, rt, jobs, &cam, N, N, &o, &err), PF_OK);
        double want = k_rho * k_le * form_factor(pts[k][0], pts[k][1]), m = 0.0, v = 0.0;
        for (int i = 0; i < N * N; i++) m += img[3 * i] / (N * N);
        for (int i = 0; i < N * N; i++) v += (img[3 * i] - m) * (img[3 * i] - m) / (N * N - 1);
        double se = sqrt(v / (N * N));
        print_message("reference direct at (%.1f, %.1f): %.6f, analytic %.6f (%.3f%%, %.2f standard errors of %.3f%%)\n",
                      pts[k][0], pts[k][1], m, want, 100.0 * (m - want) / want, fabs(m - want) / se, 100.0 * se / want);
        assert_true(fabs(m - want) < 5.0 * se);
        assert_true(se < 0.01 * want);
        for (int i = 0; i < N * N; i++) assert_true(img[3 * i] == img[3 * i + 1] && img[3 * i] == img[3 * i + 2]);
        o.direct_only = 0;
        o.indirect_only = 1;
        o.bounces = 1;
        assert_int_equal(gi_reference_render(img, &s, rt, jobs, &cam, N, N, &o, &err), PF_OK);
        for (int c = 0; c < 3 * N * N; c++) assert_true(img[c] == 0.0f);
    }
    pf_jobs_destroy(jobs);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* The furnace with NEE: inside scenes/closed-sphere (its point light
 * removed; ~1280 inward emitting triangles, Le = 1, rho = 0.5) the expected
 * radiance with B bounces is sum_{k=0..B+1} rho^k (the emitters are lights:
 * B = 0 holds their direct light). NEE on flat facets is not zero-variance
 * (test_reference checks the BSDF-only estimator exactly), so: the mean over
 * 24 x 24 independent pixels within 5 standard errors, and the standard
 * error < 0.1%. */
#define SPHERE SOFTGI_SOURCE_DIR "/scenes/closed-sphere/closed-sphere.gltf"

static void test_furnace_nee(void **state)
{
    (void)state;
    enum { N = 24 };
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, SPHERE, NULL, &err), PF_OK);
    s.light_count = 0;
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    pf_jobs *jobs = pf_jobs_create(2);
    static float img[3 * N * N];
    double want = 1.0, term = 1.0;
    for (uint32_t b = 0; b <= 2; b++) {
        gi_reference_options o = {0};
        o.spp = 16;
        o.bounces = b;
        o.direct_only = b == 0;
        assert_int_equal(gi_reference_render(img, &s, rt, jobs, &s.cameras[0], N, N, &o, &err), PF_OK);
        term *= 0.5;
        want += term;
        double m = 0.0, v = 0.0;
        for (int i = 0; i < N * N; i++) m += img[3 * i] / (N * N);
        for (int i = 0; i < N * N; i++) v += (img[3 * i] - m) * (img[3 * i] - m) / (N * N - 1);
        double se = sqrt(v / (N * N));
        print_message("furnace with NEE, B=%u: mean %.6f, expected %.6f (%.2f standard errors of %.4f%%)\n", b, m, want,
                      fabs(m - want) / se, 100.0 * se / want);
        assert_true(fabs(m - want) < 5.0 * se);
        assert_true(se < 0.001 * want);
    }
    pf_jobs_destroy(jobs);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* A closed 1 x 1 x 1 box (inward faces, grey walls, one red and one green
 * wall) with a 0.3 x 0.3 emitter 1 cm under the ceiling, facing down. */
static void box_scene(pf_scene *s)
{
    tu_quad q[7] = {
        {{0, 0, 0}, {0.5f, 0, 0}, {0, 0, -0.5f}, {0.7f, 0.7f, 0.7f, 1}, PF_ALPHA_OPAQUE, 0.5f},   /* floor */
        {{0, 1, 0}, {0.5f, 0, 0}, {0, 0, 0.5f}, {0.7f, 0.7f, 0.7f, 1}, PF_ALPHA_OPAQUE, 0.5f},    /* ceiling */
        {{0, 0.5f, -0.5f}, {0.5f, 0, 0}, {0, 0.5f, 0}, {0.7f, 0.7f, 0.7f, 1}, PF_ALPHA_OPAQUE, 0.5f}, /* back */
        {{0, 0.5f, 0.5f}, {0.5f, 0, 0}, {0, -0.5f, 0}, {0.7f, 0.7f, 0.7f, 1}, PF_ALPHA_OPAQUE, 0.5f}, /* front */
        {{-0.5f, 0.5f, 0}, {0, 0.5f, 0}, {0, 0, 0.5f}, {0.7f, 0.1f, 0.1f, 1}, PF_ALPHA_OPAQUE, 0.5f}, /* left */
        {{0.5f, 0.5f, 0}, {0, 0, 0.5f}, {0, 0.5f, 0}, {0.1f, 0.7f, 0.1f, 1}, PF_ALPHA_OPAQUE, 0.5f},  /* right */
        {{0, 0.99f, 0}, {0.15f, 0, 0}, {0, 0, 0.15f}, {0.5f, 0.5f, 0.5f, 1}, PF_ALPHA_OPAQUE, 0.5f},  /* light */
    };
    tu_make_scene(s, q, 7);
    for (int c = 0; c < 3; c++) s->materials[6].emission[c] = 5.0f;
    pf_error err;
    assert_int_equal(pf_scene_validate(s, &err), PF_OK);
}

static void box_camera(pf_camera *cam)
{
    pf_error err;
    assert_int_equal(pf_camera_look_at(cam, pf_v3(0.0f, 0.5f, 0.45f), pf_v3(0, 0.45f, -0.5f), pf_radians(80), &err),
                     PF_OK);
}

static void test_box_normals_inward(void **state)
{
    (void)state;
    pf_scene s;
    box_scene(&s);
    pf_vec3 c = pf_v3(0, 0.5f, 0);
    for (uint32_t t = 0; t < 12; t++) { /* the six walls face the centre */
        pf_vec3 p = s.positions[s.indices[3 * t]];
        assert_true(pf_v3_dot(pf_scene_face_normal(&s, t), pf_v3_sub(c, p)) > 0.0f);
    }
    assert_true(pf_scene_face_normal(&s, 12).y < -0.99f); /* the emitter faces down */
    pf_scene_free(&s);
}

static void ir_frame(fx *x, uint32_t threads, uint32_t w, uint32_t h, uint32_t vpls)
{
    box_scene(&x->scene);
    pf_camera cam;
    box_camera(&cam);
    fx_begin(x, threads, w, h, &cam);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.vpls = vpls;
    io.clamp = 0.0f;
    io.filter = GI_FILTER_NONE;
    pf_error err;
    assert_int_equal(gi_frame_enable_indirect(&x->f, &io, 1, &err), PF_OK);
}

static void test_ir_converges_to_reference(void **state)
{
    (void)state;
    enum { W = 32, H = 24 };
    fx x;
    ir_frame(&x, 2, W, H, 8192);
    gi_frame_render_raster(&x.f);
    static float ref[3 * W * H];
    gi_reference_options ro;
    memset(&ro, 0, sizeof ro);
    ro.spp = 4096;
    ro.bounces = 3;
    ro.indirect_only = 1;
    pf_error err;
    pf_camera cam;
    box_camera(&cam);
    assert_int_equal(gi_reference_render(ref, &x.scene, x.rt, x.jobs, &cam, W, H, &ro, &err), PF_OK);
    double sum = 0.0, sum_ir = 0.0, sum_ref = 0.0;
    int n = 0;
    for (int y = 1; y + 1 < H; y++)
        for (int xx = 1; xx + 1 < W; xx++) {
            size_t i = (size_t)y * W + (size_t)xx;
            uint32_t p = x.f.gbuf.prim[i] / 2; /* quad */
            int edge = 0; /* the reference averages over the pixel, the G-buffer samples its centre */
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) edge |= x.f.gbuf.prim[i + (size_t)(dy * W + dx)] / 2 != p;
            if (edge || p == 6) continue;
            double a = 0.2126 * x.f.final[3 * i] + 0.7152 * x.f.final[3 * i + 1] + 0.0722 * x.f.final[3 * i + 2];
            double b = 0.2126 * ref[3 * i] + 0.7152 * ref[3 * i + 1] + 0.0722 * ref[3 * i + 2];
            sum += fabs(a - b) / b;
            sum_ir += a, sum_ref += b;
            n++;
        }
    double mre = sum / n;
    print_message("IR (area light) vs reference: mean relative error %.4f over %d pixels, ratio of means %.4f\n", mre, n,
                  sum_ir / sum_ref);
    assert_true(n > W * H / 2);
    assert_true(mre < 0.04);
    assert_true(fabs(sum_ir / sum_ref - 1.0) < 0.02);
    fx_end(&x);
}

/* The McGuire Cornell box (an emissive quad is its only light): the raster
 * direct light (K points with paraboloid maps) against the ray-traced one on
 * the same rasterized G-buffer, so only the light evaluation differs. The
 * numbers go into the README; the bounds only catch a broken path. */
#define MCGUIRE SOFTGI_SHARED_SCENES "/cornell_box/CornellBox-Original.gltf"

static double rel_l1(const float *a, const float *b, size_t n)
{
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < n; i++) {
        num += fabs((double)a[i] - b[i]);
        den += fabs((double)b[i]);
    }
    return num / den;
}

static void test_mcguire_residual(void **state)
{
    (void)state;
    enum { W = 160, H = 120 };
    fx x;
    if (!tu_load_or_skip(&x.scene, MCGUIRE)) return;
    pf_error err;
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0, 1, 3.4f), pf_v3(0, 1, 0), pf_radians(40), &err), PF_OK);
    fx_begin(&x, 2, W, H, &cam);
    assert_true(x.scene.light_count == 0 && x.f.area.count == 2);
    static float rt256[3 * W * H], rt16[3 * W * H], k32[3 * W * H], k128[3 * W * H];
    const size_t n = 3u * W * H;
    gi_stage_gbuffer_raster(&x.f);
    gi_stage_gbuffer_resolve(&x.f);
    assert_int_equal(gi_frame_set_area_sampling(&x.f, 16, 128, &err), PF_OK);
    gi_stage_direct_raytrace(&x.f);
    memcpy(rt256, x.f.direct, sizeof rt256);
    gi_stage_area_shadow_maps(&x.f);
    gi_stage_direct_shadowmap(&x.f);
    memcpy(k128, x.f.direct, sizeof k128);
    assert_int_equal(gi_frame_set_area_sampling(&x.f, GI_AREA_DEFAULT_STRATA, GI_AREA_DEFAULT_POINTS, &err), PF_OK);
    gi_stage_direct_raytrace(&x.f);
    memcpy(rt16, x.f.direct, sizeof rt16);
    gi_stage_area_shadow_maps(&x.f);
    gi_stage_direct_shadowmap(&x.f);
    memcpy(k32, x.f.direct, sizeof k32);
    double e32 = rel_l1(k32, rt256, n), e128 = rel_l1(k128, rt256, n), e16 = rel_l1(rt16, rt256, n);
    print_message("McGuire Cornell box direct light, relative L1 against ray-traced 256 samples/pixel: raster K=32 "
                  "%.4f, raster K=128 %.4f, ray-traced 16 samples/pixel %.4f\n",
                  e32, e128, e16);
    assert_true(e128 < e32);
    assert_true(e32 < 0.04);
    assert_true(e16 < 0.06);
    fx_end(&x);
}

/* --area-strata / --area-points: bad values are clear errors; good ones
 * change the image (the McGuire box is lit by its emitter only). */
static void test_cli_options(void **state)
{
    (void)state;
    tu_softgi_expect("render --area-points 0 -q", 2, "--area-points '0': expected an integer in 1..1024");
    tu_softgi_expect("render --area-strata 17 -q", 2, "--area-strata '17': expected an integer in 1..16");
    if (!tu_file_exists(MCGUIRE)) return;
    char out[3][16384];
    const char *args[3] = {"", "--area-points 8", "--raytrace --area-strata 2"};
    for (int k = 0; k < 3; k++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd,
                 "render %s --camera 0,1,3.4:0,1,0:40 --size 32x24 --direct-only -q --hash -o /tmp/softgi-test-area-%d.png "
                 "%s",
                 MCGUIRE, k, args[k]);
        assert_int_equal(tu_softgi_run(cmd, out[k], sizeof out[k]), 0);
        assert_non_null(strstr(out[k], "hash"));
        snprintf(cmd, sizeof cmd, "/tmp/softgi-test-area-%d.png", k);
        remove(cmd);
        snprintf(cmd, sizeof cmd, "/tmp/softgi-test-area-%d.pfm", k);
        remove(cmd);
    }
    assert_true(strcmp(out[0], out[1]) != 0);
    assert_true(strcmp(out[0], out[2]) != 0);
}

static uint64_t hash_floats(const float *v, size_t n)
{
    uint64_t h = 1469598103934665603ull;
    const unsigned char *b = (const unsigned char *)v;
    for (size_t i = 0; i < n * sizeof(float); i++) h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

static void frame_hashes(uint32_t threads, uint64_t out[3])
{
    fx x;
    ir_frame(&x, threads, 40, 30, 512);
    x.f.show_direct = 1;
    gi_frame_render_raster(&x.f); /* raster direct + IR indirect */
    out[0] = hash_floats(x.f.direct, 3u * 40 * 30);
    out[1] = hash_floats(x.f.final, 3u * 40 * 30);
    gi_frame_render_raytraced(&x.f);
    out[2] = hash_floats(x.f.direct, 3u * 40 * 30);
    fx_end(&x);
}

static void test_threads_identical(void **state)
{
    (void)state;
    uint64_t a[3], b[3];
    frame_hashes(1, a);
    frame_hashes(2, b);
    for (int k = 0; k < 3; k++) assert_true(a[k] == b[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_direct_raytrace_analytic), cmocka_unit_test(test_direct_raster_analytic),
        cmocka_unit_test(test_reference_analytic),       cmocka_unit_test(test_box_normals_inward),
        cmocka_unit_test(test_ir_converges_to_reference), cmocka_unit_test(test_threads_identical),
        cmocka_unit_test(test_mcguire_residual),         cmocka_unit_test(test_furnace_nee),         cmocka_unit_test(test_cli_options),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
