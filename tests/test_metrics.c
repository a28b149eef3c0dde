/* test_metrics: gi_metrics and `softgi compare` (issue 4).
 * - luminance, the Reinhard curve, RMSE, MAE and |E| on hand-made images
 *   with known values;
 * - |E| and |E'| (Hedman 2017 Eq. 10) on synthetic series: a constant error
 *   gives |E'| = 0, an error alternating +-d gives |E'| = 2d;
 * - TID (Barak 2013 Sec. 6.2): 0 for a static camera and image, the known
 *   value for a known flicker (sky excluded), and ~0 for a camera
 *   translating over a ray-cast two-plane scene whose content stays put in
 *   the world, with the disocclusions excluded by the depth test;
 * - the .view/.depth.pfm files round-trip bit for bit and bad files fail;
 * - the softgi binary end to end: values, Markdown table, SVG with one
 *   polyline per series and tracked pixel, and every error message. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "gi_metrics.h"
#include "pf_imageio.h"
#include "test_util.h"


static char g_tmp[256];

static void near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol)) fail_msg("%s: got %.9g, want %.9g (tolerance %g)", what, got, want, tol);
}

/* ---------------------------------------------------------------- pixels and images */

static void test_luminance_reinhard(void **state)
{
    (void)state;
    const float white[3] = {1, 1, 1}, red[3] = {1, 0, 0}, green[3] = {0, 1, 0}, blue[3] = {0, 0, 1};
    near(gi_metrics_luminance(white), 1.0, 1e-6, "Y(white)");
    near(gi_metrics_luminance(red), 0.2126, 1e-7, "Y(red)");
    near(gi_metrics_luminance(green), 0.7152, 1e-7, "Y(green)");
    near(gi_metrics_luminance(blue), 0.0722, 1e-7, "Y(blue)");
    near(gi_metrics_reinhard(1.0f), 0.5, 0, "T(1)");
    near(gi_metrics_reinhard(3.0f), 0.75, 0, "T(3)");
    near(gi_metrics_reinhard(0.0f), 0.0, 0, "T(0)");
    near(gi_metrics_reinhard(-2.0f), 0.0, 0, "T(-2)");
    near(gi_metrics_reinhard(NAN), 0.0, 0, "T(NaN)");
    near(gi_metrics_reinhard(INFINITY), 1.0, 0, "T(inf)");
    const float grey3[3] = {3, 3, 3};
    near(gi_metrics_display_luminance(grey3, 1.0f), 0.75, 1e-6, "T(Y(3,3,3))");
    near(gi_metrics_display_luminance(white, 2.0f), 2.0 / 3.0, 1e-6, "T(2 Y(white))");
}

static void test_rmse_mae(void **state)
{
    (void)state;
    /* Differences 1, 2, 3, 0, 0, -4: squares sum to 30, absolutes to 10. */
    const float a[6] = {1, 2, 3, 0, 0, 0}, ref[6] = {0, 0, 0, 0, 0, 4};
    near(gi_metrics_rmse(a, ref, 2), sqrt(30.0 / 6.0), 1e-12, "RMSE");
    near(gi_metrics_mae(a, ref, 2), 10.0 / 6.0, 1e-12, "MAE");
    near(gi_metrics_rmse(a, a, 2), 0.0, 0, "RMSE(a, a)");
    near(gi_metrics_mae(ref, ref, 2), 0.0, 0, "MAE(ref, ref)");
    near(gi_metrics_rmse(a, ref, 0), 0.0, 0, "RMSE of nothing");
    /* |E| over all pixels: T(1) = 0.5 vs T(3) = 0.75 on one pixel, equal on the other. */
    const float b[6] = {1, 1, 1, 2, 2, 2}, bref[6] = {3, 3, 3, 2, 2, 2};
    near(gi_metrics_abs_error_image(b, bref, 2, 1.0f), 0.125, 1e-6, "|E| image");
}

static void test_track_grid(void **state)
{
    (void)state;
    gi_metrics_pixel px[64];
    /* 8 pixels on 4:3: a 4 x 2 grid of cell centres. */
    assert_int_equal(gi_metrics_track_grid(px, 8, 640, 480), 8);
    const uint32_t xs[4] = {80, 240, 400, 560}, ys[2] = {120, 360};
    for (int k = 0; k < 8; k++) {
        assert_int_equal(px[k].x, xs[k % 4]);
        assert_int_equal(px[k].y, ys[k / 4]);
    }
    /* Tiny and thin images: distinct pixels, in range, never more than exist. */
    const uint32_t sizes[][3] = {{2, 2, 8}, {1, 100, 8}, {100, 1, 8}, {3, 5, 15}, {7, 3, 1}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        uint32_t w = sizes[s][0], h = sizes[s][1], want = sizes[s][2];
        uint32_t n = gi_metrics_track_grid(px, want, w, h);
        assert_int_equal(n, want < w * h ? want : w * h);
        for (uint32_t i = 0; i < n; i++) {
            assert_true(px[i].x < w && px[i].y < h);
            for (uint32_t j = 0; j < i; j++) assert_false(px[i].x == px[j].x && px[i].y == px[j].y);
        }
    }
    assert_int_equal(gi_metrics_track_grid(px, 0, 10, 10), 0);
}

/* ---------------------------------------------------------------- |E| and |E'| */

#define SER_T 6
#define SER_K 3

static void test_abs_error_constant(void **state)
{
    (void)state;
    float ref[SER_T * SER_K], m[SER_T * SER_K];
    for (int t = 0; t < SER_T; t++)
        for (int k = 0; k < SER_K; k++) {
            ref[t * SER_K + k] = 0.1f * (float)k + 0.05f * (float)t; /* the reference itself changes */
            m[t * SER_K + k] = ref[t * SER_K + k] + 0.125f;
        }
    near(gi_metrics_abs_error(m, ref, SER_T, SER_K), 0.125, 1e-6, "|E| constant error");
    near(gi_metrics_abs_error_rate(m, ref, SER_T, SER_K), 0.0, 1e-6, "|E'| constant error");
}

static void test_abs_error_alternating(void **state)
{
    (void)state;
    const float d = 0.0625f;
    float ref[SER_T * SER_K], m[SER_T * SER_K];
    for (int t = 0; t < SER_T; t++)
        for (int k = 0; k < SER_K; k++) {
            ref[t * SER_K + k] = 0.3f + 0.1f * (float)k;
            m[t * SER_K + k] = ref[t * SER_K + k] + ((t & 1) ? -d : d);
        }
    near(gi_metrics_abs_error(m, ref, SER_T, SER_K), d, 1e-6, "|E| alternating");
    near(gi_metrics_abs_error_rate(m, ref, SER_T, SER_K), 2.0 * d, 1e-6, "|E'| alternating = 2d");
    /* One frame: no finite difference. */
    assert_true(isnan(gi_metrics_abs_error_rate(m, ref, 1, SER_K)));
    assert_true(isnan(gi_metrics_abs_error(m, ref, 0, SER_K)));
}

/* ---------------------------------------------------------------- TID */

#define TW 64
#define TH 48

static gi_metrics_view look_down_z(float ex)
{
    /* forward -Z, up +Y, right = forward x up = +X; tan(yfov/2) = 0.5. */
    gi_metrics_view v = {pf_v3(ex, 0, 0), pf_v3(0, 0, -1), pf_v3(0, 1, 0), pf_v3(1, 0, 0),
                         2.0f * atanf(0.5f), TW, TH};
    return v;
}

static void fill_grey(float *rgb, float g)
{
    for (int i = 0; i < 3 * TW * TH; i++) rgb[i] = g;
}

static void test_tid_static(void **state)
{
    (void)state;
    static float rgb[3 * TW * TH], depth[TW * TH];
    gi_metrics_view v = look_down_z(0);
    for (int i = 0; i < TW * TH; i++) {
        depth[i] = (i % 7 == 0) ? INFINITY : 3.0f + 0.01f * (float)(i % 11);
        rgb[3 * i] = (float)(i % 13) * 0.3f, rgb[3 * i + 1] = (float)(i % 5), rgb[3 * i + 2] = 0.25f;
    }
    gi_metrics_frame f = {rgb, depth, &v};
    gi_metrics_tid_sum acc = {0};
    gi_metrics_tid_pair(&acc, &f, &f, NULL);
    gi_metrics_tid_pair(&acc, &f, &f, NULL);
    uint64_t finite = 0;
    for (int i = 0; i < TW * TH; i++) finite += isfinite(depth[i]);
    assert_int_equal(acc.count, 2 * finite);
    near(gi_metrics_tid_value(&acc), 0.0, 0, "TID static");
    gi_metrics_tid_sum none = {0};
    assert_true(isnan(gi_metrics_tid_value(&none)));
}

static void test_tid_flicker(void **state)
{
    (void)state;
    static float a[3 * TW * TH], b[3 * TW * TH], depth[TW * TH];
    gi_metrics_view v = look_down_z(0);
    fill_grey(a, 0.2f);
    fill_grey(b, 0.5f);
    uint64_t finite = 0;
    for (int i = 0; i < TW * TH; i++) {
        int sky = (i / TW) < TH / 3; /* the top third is sky: its flicker is not counted */
        depth[i] = sky ? INFINITY : 5.0f;
        if (sky) a[3 * i] = 100.0f, b[3 * i + 2] = -7.0f;
        finite += !sky;
    }
    gi_metrics_frame fa = {a, depth, &v}, fb = {b, depth, &v};
    gi_metrics_tid_sum acc = {0};
    gi_metrics_tid_pair(&acc, &fa, &fb, NULL); /* a -> b */
    gi_metrics_tid_pair(&acc, &fb, &fa, NULL); /* b -> a */
    assert_int_equal(acc.count, 2 * finite);
    near(gi_metrics_tid_value(&acc), 0.3, 1e-5, "TID linear flicker 0.2 <-> 0.5");
    gi_metrics_tid_desc tm = {.tonemapped = 1};
    gi_metrics_tid_sum acc2 = {0};
    gi_metrics_tid_pair(&acc2, &fa, &fb, &tm);
    near(gi_metrics_tid_value(&acc2), 0.5 / 1.5 - 0.2 / 1.2, 1e-5, "TID tone-mapped flicker");
}

/* Ray-casts the two-plane scene for a camera: a background plane at depth 4
 * (z = -4) and a near square |x|, |y| <= 0.3 at depth 2 (z = -2). Radiance
 * is a smooth function of the world point, different on the two, so the
 * content stays put in the world as the camera moves. */
static void render_planes(float *rgb, float *depth, const gi_metrics_view *v)
{
    pf_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.eye = v->eye, cam.forward = v->forward, cam.up = v->up, cam.right = v->right, cam.yfov = v->yfov;
    for (uint32_t y = 0; y < TH; y++)
        for (uint32_t x = 0; x < TW; x++) {
            size_t i = (size_t)y * TW + x;
            pf_vec3 d = pf_camera_ray_dir(&cam, TW, TH, (float)x + 0.5f, (float)y + 0.5f);
            pf_vec3 pn = pf_v3_add(v->eye, pf_v3_scale(d, 2.0f));
            float g;
            if (fabsf(pn.x) <= 0.3f && fabsf(pn.y) <= 0.3f) {
                depth[i] = 2.0f;
                g = 8.0f + sinf(5.0f * pn.x) * cosf(4.0f * pn.y);
            } else {
                pf_vec3 pf = pf_v3_add(v->eye, pf_v3_scale(d, 4.0f));
                depth[i] = 4.0f;
                g = 0.5f + 0.4f * sinf(3.0f * pf.x) * cosf(2.0f * pf.y);
            }
            rgb[3 * i] = g, rgb[3 * i + 1] = 0.5f * g, rgb[3 * i + 2] = 0.25f * g;
        }
}

static void test_tid_translated_camera(void **state)
{
    (void)state;
    enum { N = 4 };
    static float rgb[N][3 * TW * TH], depth[N][TW * TH];
    gi_metrics_view views[N];
    /* One pixel at depth 4 spans 2 * 4 * tan(yfov/2) / H world units; moving
     * the camera by that much shifts the background by exactly 1 pixel and
     * the near square by 2, so pixel centres land on pixel centres. */
    const float step = 2.0f * 4.0f * 0.5f / (float)TH;
    for (int t = 0; t < N; t++) {
        views[t] = look_down_z(step * (float)t);
        render_planes(rgb[t], depth[t], &views[t]);
    }
    gi_metrics_tid_sum acc = {0}, loose = {0}, static_cam = {0};
    gi_metrics_tid_desc no_depth_test = {.depth_tolerance = 1e6f};
    for (int t = 1; t < N; t++) {
        gi_metrics_frame p = {rgb[t - 1], depth[t - 1], &views[t - 1]}, c = {rgb[t], depth[t], &views[t]};
        gi_metrics_tid_pair(&acc, &p, &c, NULL);
        gi_metrics_tid_pair(&loose, &p, &c, &no_depth_test);
        /* Pretending the camera did not move: the content slides under the pixels. */
        gi_metrics_frame ps = {rgb[t - 1], depth[t - 1], &views[t]};
        gi_metrics_tid_pair(&static_cam, &ps, &c, NULL);
    }
    /* Per pair: the background column entering on the right (1 column off
     * screen) and the background disoccluded on the square's left edge (1
     * column per row of the square) are excluded. */
    const uint64_t all = (uint64_t)(N - 1) * TW * TH;
    assert_true(acc.count > all * 9 / 10);
    assert_true(acc.count < all - (uint64_t)(N - 1) * TH);
    near(gi_metrics_tid_value(&acc), 0.0, 1e-4, "TID of a translated camera over a static scene");
    /* Without the depth test only the off-screen column is excluded, and the
     * disoccluded pixels compare the background with the square. */
    assert_int_equal(loose.count, all - (uint64_t)(N - 1) * TH);
    assert_true(gi_metrics_tid_value(&loose) > 0.2);
    assert_true(gi_metrics_tid_value(&static_cam) > 0.01);
}

/* ---------------------------------------------------------------- files */

static void test_view_depth_files(void **state)
{
    (void)state;
    char path[512], dpath[512];
    snprintf(path, sizeof path, "%s/files/frame_0000.view", g_tmp);
    snprintf(dpath, sizeof dpath, "%s/files/frame_0000.depth.pfm", g_tmp);
    pf_camera cam;
    pf_error err;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(1.1f, 2.3f, -7.7f), pf_v3(0.3f, 0.1f, 0.2f), 0.7f, &err), PF_OK);
    gi_metrics_view v, r;
    gi_metrics_view_from_camera(&v, &cam, 33, 17);
    assert_int_equal(gi_metrics_view_write(path, &v, &err), PF_OK);
    assert_int_equal(gi_metrics_view_read(path, &r, &err), PF_OK);
    assert_memory_equal(&v.eye, &r.eye, sizeof v.eye);
    assert_memory_equal(&v.forward, &r.forward, sizeof v.forward);
    assert_memory_equal(&v.up, &r.up, sizeof v.up);
    assert_memory_equal(&v.right, &r.right, sizeof v.right);
    assert_memory_equal(&v.yfov, &r.yfov, sizeof v.yfov);
    assert_int_equal(r.width, 33);
    assert_int_equal(r.height, 17);

    float depth[6] = {1.5f, INFINITY, 0.25f, 1e30f, 3.0f, INFINITY};
    assert_int_equal(gi_metrics_depth_write(dpath, depth, 3, 2, &err), PF_OK);
    float *back;
    uint32_t w, h;
    assert_int_equal(gi_metrics_depth_read(dpath, &back, &w, &h, &err), PF_OK);
    assert_int_equal(w, 3);
    assert_int_equal(h, 2);
    assert_memory_equal(back, depth, sizeof depth);
    free(back);

    /* Bad files. */
    snprintf(path, sizeof path, "%s/files/missing.view", g_tmp);
    assert_int_equal(gi_metrics_view_read(path, &r, &err), PF_ERR_IO);
    const char *bad[] = {
        "hello\n",
        "softgi-view 2\nwidth 4\nheight 4\neye 0 0 0\nforward 0 0 -1\nup 0 1 0\nright 1 0 0\nyfov 1\n",
        "softgi-view 1\nwidth 0\nheight 4\neye 0 0 0\nforward 0 0 -1\nup 0 1 0\nright 1 0 0\nyfov 1\n",
        "softgi-view 1\nwidth 4\nheight 4\neye 0 nan 0\nforward 0 0 -1\nup 0 1 0\nright 1 0 0\nyfov 1\n",
        "softgi-view 1\nwidth 4\nheight 4\neye 0 0 0\nforward 0 0 -1\nup 0 1 0\nright 1 0 0\nyfov 4\n",
        "softgi-view 1\nwidth 4\nheight 4\neye 0 0 0\nforward 0 0 -2\nup 0 1 0\nright 1 0 0\nyfov 1\n",
        "softgi-view 1\nwidth 4\nheight 4\neye 0 0 0\nforward 0 0 -1\nup 0 1 0\n",
    };
    snprintf(path, sizeof path, "%s/files/bad.view", g_tmp);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        FILE *f = fopen(path, "w");
        assert_non_null(f);
        fputs(bad[i], f);
        fclose(f);
        if (gi_metrics_view_read(path, &r, &err) != PF_ERR_PARSE) fail_msg("bad view %zu accepted:\n%s", i, bad[i]);
    }
}

/* ---------------------------------------------------------------- the command */

/* `softgi compare ARGS` */
static int run(const char *args, char *out, size_t size)
{
    char a[4096];
    snprintf(a, sizeof a, "compare %s", args);
    return tu_softgi_run(a, out, size);
}

static void expect(const char *args, int status, const char *needle)
{
    char a[4096];
    snprintf(a, sizeof a, "compare %s", args);
    tu_softgi_expect(a, status, needle);
}

#define SW 16
#define SH 12

static void write_grey(const char *path, uint32_t w, uint32_t h, float g)
{
    float *rgb = malloc((size_t)w * h * 3 * sizeof(float));
    for (size_t i = 0; i < (size_t)w * h * 3; i++) rgb[i] = g;
    pf_error err;
    if (pf_imageio_write_pfm(path, rgb, w, h, &err) != PF_OK) fail_msg("%s", err.message);
    free(rgb);
}

/* A sequence of grey frames g(t); with_views adds the static camera over a
 * plane at depth 3. */
static void write_sequence(const char *dir, int frames, float (*g)(int), int with_views)
{
    char path[1024];
    pf_error err;
    static float depth[SW * SH];
    for (int i = 0; i < SW * SH; i++) depth[i] = 3.0f;
    gi_metrics_view v = {pf_v3(0, 1, 2), pf_v3(0, 0, -1), pf_v3(0, 1, 0), pf_v3(1, 0, 0), 0.8f, SW, SH};
    for (int t = 0; t < frames; t++) {
        snprintf(path, sizeof path, "%s/frame_%04d.pfm", dir, t);
        write_grey(path, SW, SH, g(t));
        if (!with_views) continue;
        snprintf(path, sizeof path, "%s/frame_%04d.view", dir, t);
        if (gi_metrics_view_write(path, &v, &err) != PF_OK) fail_msg("%s", err.message);
        snprintf(path, sizeof path, "%s/frame_%04d.depth.pfm", dir, t);
        if (gi_metrics_depth_write(path, depth, SW, SH, &err) != PF_OK) fail_msg("%s", err.message);
    }
}

static float g_ref(int t) { return (void)t, 1.0f; }              /* T = 0.5 */
static float g_const(int t) { return (void)t, 3.0f; }            /* T = 0.75: E = +0.25 always */
static float g_alt(int t) { return (t & 1) ? 1.0f / 3.0f : 3.0f; } /* T = 0.25 / 0.75: E = -+0.25 */

/* Finds the table row of `name` and reads its numbers ('-' reads as NaN). */
static void row_values(const char *out, const char *name, double v[5])
{
    char key[64];
    snprintf(key, sizeof key, "\n| %s |", name);
    const char *p = strstr(out, key);
    if (!p) fail_msg("no row '%s' in:\n%s", name, out);
    p += strlen(key);
    for (int i = 0; i < 5; i++) {
        while (*p == ' ') p++;
        if (*p == '-') {
            v[i] = NAN;
            p++;
        } else {
            char *end;
            v[i] = strtod(p, &end);
            if (end == p) fail_msg("row '%s': cannot read value %d in:\n%s", name, i, out);
            p = end;
        }
        while (*p == ' ') p++;
        if (*p != '|') fail_msg("row '%s': expected '|' after value %d in:\n%s", name, i, out);
        p++;
    }
}

static int count_substr(const char *s, const char *needle)
{
    int n = 0;
    for (const char *p = strstr(s, needle); p; p = strstr(p + 1, needle)) n++;
    return n;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s was not written", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    s[fread(s, 1, (size_t)n, f)] = 0;
    fclose(f);
    return s;
}

static void test_compare_images(void **state)
{
    (void)state;
    char a[512], b[512], small[512], args[2048], out[16384];
    snprintf(a, sizeof a, "%s/img/a.pfm", g_tmp);
    snprintf(b, sizeof b, "%s/img/b.pfm", g_tmp);
    snprintf(small, sizeof small, "%s/img/small.pfm", g_tmp);
    write_grey(a, 8, 6, 3.0f);
    write_grey(b, 8, 6, 1.0f);
    write_grey(small, 4, 6, 1.0f);
    snprintf(args, sizeof args, "%s %s", a, b);
    assert_int_equal(run(args, out, sizeof out), 0);
    double rmse = -1, mae = -1, e = -1;
    const char *p;
    if (!(p = strstr(out, "RMSE")) || sscanf(p, "RMSE %lf", &rmse) != 1) fail_msg("no RMSE in:\n%s", out);
    if (!(p = strstr(out, "MAE")) || sscanf(p, "MAE %lf", &mae) != 1) fail_msg("no MAE in:\n%s", out);
    if (!(p = strstr(out, "|E|")) || sscanf(p, "|E| %lf", &e) != 1) fail_msg("no |E| in:\n%s", out);
    near(rmse, 2.0, 1e-5, "RMSE 3 vs 1");
    near(mae, 2.0, 1e-5, "MAE 3 vs 1");
    near(e, 0.25, 1e-5, "|E| T(3) - T(1)");
    snprintf(args, sizeof args, "%s %s --exposure 1", a, b); /* T(6) - T(2) */
    assert_int_equal(run(args, out, sizeof out), 0);
    if (!(p = strstr(out, "|E|")) || sscanf(p, "|E| %lf", &e) != 1) fail_msg("no |E| in:\n%s", out);
    near(e, 6.0 / 7.0 - 2.0 / 3.0, 1e-5, "|E| at exposure +1");

    expect("--help", 0, "usage: softgi compare");
    expect("", 2, "nothing to compare");
    snprintf(args, sizeof args, "%s", a);
    expect(args, 2, "missing REFERENCE.pfm");
    snprintf(args, sizeof args, "%s %s %s", a, b, b);
    expect(args, 2, "unexpected argument");
    snprintf(args, sizeof args, "%s/img/nope.pfm %s", g_tmp, b);
    expect(args, 1, "nope.pfm: cannot open");
    snprintf(args, sizeof args, "%s %s", a, small);
    expect(args, 1, "size mismatch");
    snprintf(args, sizeof args, "%s %s --frob", a, b);
    expect(args, 2, "unknown option '--frob'");
    snprintf(args, sizeof args, "%s %s --exposure x", a, b);
    expect(args, 2, "--exposure 'x'");
    snprintf(args, sizeof args, "%s %s --plot p.svg", a, b);
    expect(args, 2, "apply to sequences");
    FILE *f = fopen(b, "w");
    fputs("P6\n1 1\n255\nabc", f);
    fclose(f);
    snprintf(args, sizeof args, "%s %s", a, b);
    expect(args, 1, "not a 3-channel PFM");
}

static void test_compare_sequences(void **state)
{
    (void)state;
    char ref[512], mc[512], ma[512], args[4096], out[16384], svg[512], md[512];
    snprintf(ref, sizeof ref, "%s/seq/ref", g_tmp);
    snprintf(mc, sizeof mc, "%s/seq/const", g_tmp);
    snprintf(ma, sizeof ma, "%s/seq/alt", g_tmp);
    snprintf(svg, sizeof svg, "%s/seq/out/plot.svg", g_tmp);
    snprintf(md, sizeof md, "%s/seq/out/table.md", g_tmp);
    write_sequence(ref, 4, g_ref, 1);
    write_sequence(mc, 4, g_const, 0); /* borrows the reference's views */
    write_sequence(ma, 4, g_alt, 1);

    snprintf(args, sizeof args, "--reference %s --name const:%s --name 'alt|x':%s --track 1,1 --track 8,6 --plot %s "
             "--table %s", ref, mc, ma, svg, md);
    assert_int_equal(run(args, out, sizeof out), 0);
    double v[5];
    row_values(out, "reference", v);
    near(v[0], 4, 0, "reference frames");
    assert_true(isnan(v[1]) && isnan(v[2]) && isnan(v[4]));
    near(v[3], 0.0, 1e-6, "reference TID");
    row_values(out, "const", v);
    near(v[1], 0.25, 1e-5, "const |E|");
    near(v[2], 0.0, 1e-5, "const |E'|");
    near(v[3], 0.0, 1e-5, "const TID");
    near(v[4], 2.0, 1e-5, "const RMSE");
    row_values(out, "alt\\|x", v); /* the name's '|' is escaped for Markdown */
    near(v[1], 0.25, 1e-5, "alt |E|");
    near(v[2], 0.5, 1e-5, "alt |E'| = 2d");
    near(v[3], 3.0 - 1.0 / 3.0, 1e-4, "alt TID (linear luminance)");
    near(v[4], (2.0 + 2.0 / 3.0) / 2.0, 1e-5, "alt RMSE");
    assert_non_null(strstr(out, "(1,1) (8,6)"));

    char *table = slurp(md);
    assert_non_null(strstr(table, "| method | frames |"));
    assert_non_null(strstr(table, "| const | 4 |"));
    free(table);
    char *plot = slurp(svg);
    assert_non_null(strstr(plot, "<svg"));
    assert_non_null(strstr(plot, "</svg>"));
    assert_int_equal(count_substr(plot, "<polyline"), 2 * 3); /* 2 pixels x (reference + 2 methods) */
    assert_non_null(strstr(plot, "alt|x"));
    free(plot);

    /* Default tracking: 8 grid pixels, so 8 x 3 polylines; TID on T(Y). */
    snprintf(args, sizeof args, "--reference %s --name const:%s --name alt:%s --plot %s --tid-tonemapped", ref, mc,
             ma, svg);
    assert_int_equal(run(args, out, sizeof out), 0);
    row_values(out, "alt", v);
    near(v[3], 0.5, 1e-5, "alt TID on T(Y)");
    plot = slurp(svg);
    assert_int_equal(count_substr(plot, "<polyline"), 8 * 3);
    free(plot);

    /* Without views anywhere: TID is '-' with a warning, the rest still works. */
    char noview[512];
    snprintf(noview, sizeof noview, "%s/seq/noview", g_tmp);
    write_sequence(noview, 4, g_ref, 0);
    snprintf(args, sizeof args, "--reference %s --name const:%s", noview, mc);
    assert_int_equal(run(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "no TID for 'const'"));
    row_values(out, "const", v);
    assert_true(isnan(v[3]));
    near(v[1], 0.25, 1e-5, "const |E| without views");

    /* Frame counts differ: the common prefix, with a warning. */
    char shortdir[512];
    snprintf(shortdir, sizeof shortdir, "%s/seq/short", g_tmp);
    write_sequence(shortdir, 2, g_alt, 0);
    snprintf(args, sizeof args, "--reference %s --name short:%s", ref, shortdir);
    assert_int_equal(run(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "comparing the first 2"));
    row_values(out, "short", v);
    near(v[0], 2, 0, "short frames");

    /* Errors. */
    char empty[512], big[512], path[1024];
    snprintf(empty, sizeof empty, "%s/seq/empty", g_tmp);
    assert_int_equal(mkdir(empty, 0777), 0);
    snprintf(big, sizeof big, "%s/seq/big", g_tmp);
    snprintf(path, sizeof path, "%s/frame_0000.pfm", big);
    write_grey(path, SW + 1, SH, 1.0f);
    snprintf(args, sizeof args, "--reference %s --name e:%s", ref, empty);
    expect(args, 1, "empty sequence (no frame_0000.pfm)");
    snprintf(args, sizeof args, "--reference %s/seq/nothere --name c:%s", g_tmp, mc);
    expect(args, 1, "nothere: no such directory");
    snprintf(args, sizeof args, "--reference %s --name b:%s", ref, big);
    expect(args, 1, "size mismatch");
    snprintf(args, sizeof args, "--reference %s --name c:%s --track 16,0", ref, mc);
    expect(args, 2, "--track 16,0 is outside the 16x12 frames");
    snprintf(args, sizeof args, "--reference %s", ref);
    expect(args, 2, "at least one --name");
    snprintf(args, sizeof args, "--name c:%s", mc);
    expect(args, 2, "--name needs --reference");
    snprintf(args, sizeof args, "--reference %s --name nodir", ref);
    expect(args, 2, "expected NAME:DIR");
    snprintf(args, sizeof args, "--reference %s --name :%s", ref, mc);
    expect(args, 2, "expected NAME:DIR");
    snprintf(args, sizeof args, "--reference %s --name c:%s --plot out.png", ref, mc);
    expect(args, 2, "the plot is SVG");
    snprintf(args, sizeof args, "--reference %s --name c:%s --track 3", ref, mc);
    expect(args, 2, "expected X,Y");
    snprintf(args, sizeof args, "--reference %s --name c:%s --tracked 0", ref, mc);
    expect(args, 2, "--tracked '0'");
    snprintf(args, sizeof args, "--reference %s --name c:%s --reference", ref, mc);
    expect(args, 2, "--reference needs a value");
    snprintf(args, sizeof args, "a.pfm --reference %s --name c:%s", ref, mc);
    expect(args, 2, "not both");

    /* A broken view file is an error, not a silent '-'. */
    char broken[512];
    snprintf(broken, sizeof broken, "%s/seq/broken", g_tmp);
    write_sequence(broken, 3, g_alt, 1);
    snprintf(path, sizeof path, "%s/frame_0002.view", broken);
    FILE *f = fopen(path, "w");
    fputs("softgi-view 1\nwidth 16\n", f);
    fclose(f);
    snprintf(args, sizeof args, "--reference %s --name b:%s", ref, broken);
    expect(args, 1, "frame_0002.view: not a softgi-view 1 file");
    snprintf(path, sizeof path, "%s/frame_0001.depth.pfm", broken);
    remove(path);
    expect(args, 1, "frame_0001.depth.pfm: cannot open");
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-test-metrics");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_luminance_reinhard),
        cmocka_unit_test(test_rmse_mae),
        cmocka_unit_test(test_track_grid),
        cmocka_unit_test(test_abs_error_constant),
        cmocka_unit_test(test_abs_error_alternating),
        cmocka_unit_test(test_tid_static),
        cmocka_unit_test(test_tid_flicker),
        cmocka_unit_test(test_tid_translated_camera),
        cmocka_unit_test(test_view_depth_files),
        cmocka_unit_test(test_compare_images),
        cmocka_unit_test(test_compare_sequences),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
