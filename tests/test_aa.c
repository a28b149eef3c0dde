/* test_aa: anti-aliasing (issue 18 deliverable 4; gi_aa.h, docs/aa.md).
 *
 * 1. The pattern: point 0 is the pixel centre, every point lies in
 *    [-1/2, 1/2)^2, no two of the first 4096 coincide, the first 2^k
 *    x-offsets (k >= 1) are the 2^k-grid (so the x-discrepancy of 2^k
 *    points is 2^-k), and the unjittered matrix and ray are today's bits.
 * 2. An analytic edge: emissive quads (albedo 0, so a pixel's radiance is
 *    the emission of what it sees) on a black background, their vertical
 *    edges at known fractions c of a pixel column and their horizontal edges
 *    at known fractions of a pixel row. With N samples every covered-pixel
 *    value is Le x (the samples the edge covers) / N, and so within D_N of
 *    the coverage c x Le, D_N being the pattern's one-dimensional
 *    discrepancy for N points (computed here; 1/N for a power of two in x):
 *    for the rasterized and the ray-traced G-buffer, 1 to 64 samples. This
 *    is also what shows that the rasterizer's clip-space shift and the ray
 *    offsets move the image the same way, in both axes.
 * 3. --aa 1 is today's image: docs/architecture.md's golden hashes (default,
 *    --direct-only, --raytrace at 160x120, sse2) with --aa 1.
 * 4. Determinism: --aa 4 gives the same bytes with 1 and 2 threads and on
 *    every ISA the machine has (sse2, avx2, avx512), rasterized and
 *    ray-traced; a sequence with --aa 2 --taa 4 --temporal 4 and a
 *    pipelined G-buffer-reading method (mir) likewise with 1 and 2 threads.
 * 5. Temporal anti-aliasing on the edge scene: with a still camera, frame
 *    N - 1 of --taa N equals --aa N (the same pattern points) up to
 *    rounding; a one-pixel camera step carries the converged edge along
 *    (reprojection, with the moving camera's shorter history), pixels that
 *    come into view restart, turning around
 *    restarts everything; a thin strip (0.3 pixel) keeps its converged
 *    value while nothing changes, and is clamped to the current
 *    neighbourhood in a frame where a light moved (gi_aa.h, "disocclusion
 *    and change"). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_aa.h"
#include "gi_frame.h"
#include "pf_isa.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

static char g_tmp[256]; /* the CLI's outputs */

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-aa");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

/* ---------------------------------------------------------------- 1. the pattern */

static int by_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

/* The star discrepancy of the N values 1/2 + d (d = the pattern's x (axis 0)
 * or y (axis 1) offsets): sup over c in [0, 1] of |#{1/2 + d_i < c} / N - c|,
 * the largest error a coverage estimate of an axis-aligned edge can have. */
static double discrepancy(uint32_t N, int axis)
{
    float *u = malloc(N * sizeof *u);
    assert_non_null(u);
    for (uint32_t i = 0; i < N; i++) {
        float jx, jy;
        gi_aa_jitter(i, &jx, &jy);
        u[i] = 0.5f + (axis ? jy : jx);
    }
    qsort(u, N, sizeof *u, by_float);
    double d = 0.0;
    for (uint32_t i = 0; i < N; i++) d = fmax(d, fmax(fabs((double)i / N - u[i]), fabs((double)(i + 1) / N - u[i])));
    free(u);
    return d;
}

static void test_pattern(void **state)
{
    (void)state;
    enum { K = 4096 };
    static float px[K], py[K];
    for (uint32_t i = 0; i < K; i++) {
        gi_aa_jitter(i, &px[i], &py[i]);
        assert_true(px[i] >= -0.5f && px[i] < 0.5f && py[i] >= -0.5f && py[i] < 0.5f);
    }
    assert_true(px[0] == 0.0f && py[0] == 0.0f); /* sample 0: the pixel centre */
    /* no duplicates: sort (x, y) pairs by x, then compare neighbours */
    static uint64_t key[K];
    for (uint32_t i = 0; i < K; i++) {
        uint32_t bx, by;
        memcpy(&bx, &px[i], 4), memcpy(&by, &py[i], 4);
        key[i] = ((uint64_t)bx << 32) | by;
    }
    int dup = 0;
    for (uint32_t i = 0; i < K && !dup; i++)
        for (uint32_t j = i + 1; j < K; j++)
            if (key[i] == key[j]) {
                dup = 1;
                print_message("points %u and %u coincide\n", i, j);
                break;
            }
    assert_false(dup);
    /* the first 2^k x-offsets, shifted by 1/2, are {0, 1, ..., 2^k - 1} / 2^k (k >= 1; one point is the centre) */
    for (uint32_t N = 2; N <= 256; N *= 2) {
        uint8_t seen[256] = {0};
        for (uint32_t i = 0; i < N; i++) {
            float g = (0.5f + px[i]) * (float)N;
            assert_true(g == floorf(g) && g < (float)N && !seen[(int)g]);
            seen[(int)g] = 1;
        }
        assert_true(fabs(discrepancy(N, 0) - 1.0 / N) < 1e-6);
    }
    for (uint32_t N = 4; N <= 64; N *= 4)
        print_message("N = %2u: discrepancy of the x-offsets %.4f, of the y-offsets %.4f\n", N, discrepancy(N, 0),
                      discrepancy(N, 1));
    /* the unjittered matrix and ray are today's bits */
    pf_error err;
    pf_camera cam;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(1, 2, 3), pf_v3(0, 0.5f, 0), pf_radians(55.0f), &err), PF_OK);
    rs_mat4 a = rs_mat4_camera(&cam, 97, 61), b = gi_aa_view_proj(&cam, 97, 61, 0.0f, 0.0f);
    assert_memory_equal(&a, &b, sizeof a);
    for (uint32_t y = 0; y < 61; y += 7)
        for (uint32_t x = 0; x < 97; x += 5) {
            pf_ray r0 = gi_camera_ray(&cam, 97, 61, x, y), r1 = gi_camera_ray_at(&cam, 97, 61, x, y, 0.0f, 0.0f);
            assert_memory_equal(&r0, &r1, sizeof r0);
        }
    pf_camera rc = gi_aa_resolve_camera(&cam, 97, 61, 0.0f, 0.0f);
    assert_memory_equal(&rc, &cam, sizeof cam);
}

/* ---------------------------------------------------------------- 2. the analytic edge */

#define EW 64
#define EH 48
#define DEPTH 2.0 /* the quads' plane: z = -DEPTH, the camera at the origin looking down -z */
#define LE 2.0f   /* emitted radiance */
#define BANDS 6   /* vertical edges: band b covers rows 8b..8b+7, x < XB(b) + k_cx[b] */
#define XB(b) (10u + 3u * (b))
#define HROW 30u /* horizontal edges: quad q covers columns 36 + 8q .. 43 + 8q, y < HROW + k_cy[q] */
#define HQUADS 3
#define STRIP_X 31u /* the thin strip: x in [31.6, 31.9) on every row */
/* Edge positions in a pixel: odd multiples of 1/128 in x, so at least
 * 1/128 pixel from every x-offset of up to 64 samples (a multiple of 1/64,
 * far beyond the rasterizer's 1/256 snapping); in y at least 0.011 pixel
 * from the first 64 y-offsets (base 3). */
static const double k_cx[BANDS] = {13 / 128.0, 29 / 128.0, 47 / 128.0, 63 / 128.0, 81 / 128.0, 101 / 128.0};
static const double k_cy[HQUADS] = {0.265, 0.45, 0.71};

/* The world point of image position (px, py) on the plane z = -DEPTH
 * (pf_camera_ray_dir of the camera below, in double). */
static double wx(double px, double th) { return (2.0 * px / EW - 1.0) * th * ((double)EW / EH) * DEPTH; }
static double wy(double py, double th) { return (1.0 - 2.0 * py / EH) * th * DEPTH; }

/* An emissive, black quad covering image positions [x0, x1] x [y0, y1]. */
static tu_quad edge_quad(double x0, double x1, double y0, double y1, double th)
{
    tu_quad q;
    memset(&q, 0, sizeof q);
    double X0 = wx(x0, th), X1 = wx(x1, th), Y0 = wy(y1, th), Y1 = wy(y0, th);
    q.centre = pf_v3((float)(0.5 * (X0 + X1)), (float)(0.5 * (Y0 + Y1)), (float)-DEPTH);
    q.a = pf_v3((float)(0.5 * (X1 - X0)), 0, 0);
    q.b = pf_v3(0, (float)(0.5 * (Y1 - Y0)), 0); /* a x b = +z: facing the camera */
    q.albedo[3] = 1.0f;
    return q;
}

/* The edge scene (with a thin strip and a point light for the TAA tests:
 * both black, the light changes nothing in the image) and its camera. */
static void edge_scene(tu_fx *x, pf_camera *cam)
{
    pf_error err;
    assert_int_equal(pf_camera_look_at(cam, pf_v3(0, 0, 0), pf_v3(0, 0, -1), pf_radians(60.0f), &err), PF_OK);
    const double th = tanf(0.5f * cam->yfov);
    tu_quad q[BANDS + HQUADS + 1];
    uint32_t n = 0;
    for (uint32_t b = 0; b < BANDS; b++)
        q[n++] = edge_quad(-8.0, XB(b) + k_cx[b], b == 0 ? -8.0 : 8.0 * b, b + 1 == BANDS ? EH + 8.0 : 8.0 * (b + 1),
                           th);
    for (uint32_t k = 0; k < HQUADS; k++) q[n++] = edge_quad(36.0 + 8 * k, 44.0 + 8 * k, -8.0, HROW + k_cy[k], th);
    q[n++] = edge_quad(STRIP_X + 0.6, STRIP_X + 0.9, -8.0, EH + 8.0, th);
    tu_make_scene(&x->scene, q, n);
    for (uint32_t m = 0; m < n; m++) x->scene.materials[m].emission[0] = x->scene.materials[m].emission[1] =
        x->scene.materials[m].emission[2] = LE;
    pf_light L = {.type = PF_LIGHT_POINT, .position = {0, 1, 1}, .color = {1, 1, 1}, .intensity = 1.0f};
    assert_int_equal(pf_scene_add_light(&x->scene, &L, &err), PF_OK);
}

static void edge_begin(tu_fx *x, pf_camera *cam, uint32_t threads, uint32_t samples, uint32_t taa)
{
    edge_scene(x, cam);
    tu_fx_desc d = {.threads = threads, .w = EW, .h = EH, .cam = cam};
    tu_fx_begin_with(x, &d);
    pf_error err;
    assert_int_equal(gi_frame_set_aa(&x->f, samples, taa, &err), PF_OK);
}

/* The samples of N whose offset along `axis` puts them before fraction c of the pixel. */
static uint32_t covered(uint32_t N, int axis, double c)
{
    uint32_t k = 0;
    for (uint32_t i = 0; i < N; i++) {
        float jx, jy;
        gi_aa_jitter(i, &jx, &jy);
        k += 0.5 + (axis ? jy : jx) < c;
    }
    return k;
}

/* The analytic answer at pixel (x, y) with N samples; -1 where the test does
 * not look (rows and columns on the quads' shared or integer edges, the strip). */
static double edge_expected(uint32_t N, uint32_t x, uint32_t y)
{
    if (x < 34) {
        if (x >= STRIP_X - 1) return -1.0;
        uint32_t b = y / 8;
        if (y % 8 == 0 || y % 8 == 7) return -1.0; /* the bands' shared edges */
        return x < XB(b) ? LE : x > XB(b) ? 0.0 : LE * (double)covered(N, 0, k_cx[b]) / N;
    }
    if (x < 37 || x >= 59 || (x - 36) % 8 == 0 || (x - 36) % 8 == 7) return -1.0; /* integer vertical edges */
    uint32_t k = (x - 36) / 8;
    return y < HROW ? LE : y > HROW ? 0.0 : LE * (double)covered(N, 1, k_cy[k]) / N;
}

static void test_analytic_edge(void **state)
{
    (void)state;
    static const uint32_t Ns[] = {1, 2, 4, 16, 64};
    for (size_t t = 0; t < sizeof Ns / sizeof Ns[0]; t++) {
        const uint32_t N = Ns[t];
        const double dx = discrepancy(N, 0), dy = discrepancy(N, 1);
        tu_fx x;
        pf_camera cam;
        edge_begin(&x, &cam, 2, N, 0);
        for (int raster = 0; raster < 2; raster++) {
            if (raster) gi_frame_render_raster(&x.f);
            else gi_frame_render_raytraced(&x.f);
            double worst_exact = 0.0, worst_cov = 0.0;
            uint32_t checked = 0;
            for (uint32_t y = 0; y < EH; y++)
                for (uint32_t px = 0; px < EW; px++) {
                    double want = edge_expected(N, px, y);
                    if (want < 0.0) continue;
                    const float *v = x.f.final + 3 * ((size_t)y * EW + px);
                    for (int c = 0; c < 3; c++) {
                        double e = fabs(v[c] - want) / LE;
                        worst_exact = fmax(worst_exact, e);
                        if (e > 1e-5)
                            fail_msg("%s, N = %u, pixel (%u, %u): %.7g, the covered samples give %.7g",
                                     raster ? "rasterized" : "ray-traced", N, px, y, v[c], want);
                    }
                    /* against the exact coverage, within the pattern's discrepancy */
                    int on_x = px < 34 && px == XB(y / 8), on_y = px >= 34 && y == HROW;
                    if (on_x || on_y) {
                        double c = on_x ? k_cx[y / 8] : k_cy[(px - 36) / 8], D = on_x ? dx : dy;
                        double e = fabs(v[0] / LE - c);
                        worst_cov = fmax(worst_cov, e);
                        assert_true(e <= D + 1e-5);
                    }
                    checked++;
                }
            print_message("%s, N = %2u: %u pixels, worst |value - covered samples| %.2g Le; worst |value - coverage| "
                          "%.4f Le (discrepancy: x %.4f, y %.4f)\n",
                          raster ? "rasterized" : "ray-traced", N, checked, worst_exact, worst_cov, dx, dy);
        }
        tu_fx_end(&x);
    }
}

/* ---------------------------------------------------------------- 3. --aa 1 is today's image */

static void expect_hash(const char *args, const char *hash)
{
    char out[16384], cmd[1024];
    snprintf(cmd, sizeof cmd, "%s -o %s/x.pfm", args, g_tmp);
    int st = tu_softgi_run(cmd, out, sizeof out);
    if (st != 0 || !strstr(out, hash)) fail_msg("softgi %s: exit %d, want hash %s:\n%s", args, st, hash, out);
}

static void test_one_sample_is_today(void **state)
{
    (void)state;
    /* docs/architecture.md's goldens ("Determinism"): --aa 1 is the image
     * without anti-aliasing (changed since it came only by the paraboloid
     * maps' receiver-plane test and the filter's tangent-plane test, in the
     * default and --raytrace rows) */
    expect_hash("render --size 160x120 --isa sse2 --hash -q --aa 1", "hash a75db235fa702a56");
    expect_hash("render --size 160x120 --isa sse2 --hash -q --aa 1 --direct-only",
                "hash 65ccd5c418f10077");
    expect_hash("render --size 160x120 --isa sse2 --hash -q --aa 1 --raytrace",
                "hash f4d2ea7cafc8f099");
}

/* ---------------------------------------------------------------- 4. determinism */

/* The hash `softgi ARGS` prints ("hash %016llx"). */
static void hash_of(const char *args, char hash[17])
{
    char out[16384];
    int st = tu_softgi_run(args, out, sizeof out);
    /* (args names its output) */
    const char *h = strstr(out, "hash ");
    if (st != 0 || !h) fail_msg("softgi %s: exit %d:\n%s", args, st, out);
    memcpy(hash, h + 5, 16);
    hash[16] = 0;
}

static void test_threads_and_isas(void **state)
{
    (void)state;
    static const char *const isas[] = {"sse2", "avx2", "avx512"};
    const pf_isa have = pf_isa_detect();
    for (int raytrace = 0; raytrace < 2; raytrace++) {
        char first[17] = "";
        for (size_t i = 0; i < 3; i++) {
            if ((i == 1 && have < PF_ISA_AVX2) || (i == 2 && have < PF_ISA_AVX512)) continue;
            for (int threads = 1; threads <= 2; threads++) {
                char args[512], h[17];
                snprintf(args, sizeof args,
                         "render --size 96x72 --aa 4 --isa %s --threads %d --hash -q -o %s/x.pfm%s", isas[i],
                         threads, g_tmp, raytrace ? " --raytrace" : "");
                hash_of(args, h);
                print_message("%s, --aa 4, %s, %d thread%s: %s\n", raytrace ? "ray-traced" : "rasterized", isas[i],
                              threads, threads > 1 ? "s" : "", h);
                if (!first[0]) memcpy(first, h, sizeof first);
                assert_string_equal(h, first);
            }
        }
    }
    /* temporal accumulation, TAA and a pipelined update that reads the G-buffer, over a moving camera */
    char args[1024], h1[17], h2[17];
    for (int threads = 1; threads <= 2; threads++) {
        snprintf(args, sizeof args,
                 "sequence " SOFTGI_SOURCE_DIR "/scenes/cornell-box/camera-orbit.seq.json --size 64x48 --frames 0:4 "
                 "--aa 2 --taa 4 --temporal 4 --method mir --pipeline on --isa sse2 --threads %d --hash -q -o %s/t%d",
                 threads, g_tmp, threads);
        hash_of(args, threads == 1 ? h1 : h2);
    }
    print_message("sequence --aa 2 --taa 4 --temporal 4 --method mir --pipeline on: %s (1 thread), %s (2)\n", h1, h2);
    assert_string_equal(h1, h2);
}

/* ---------------------------------------------------------------- 5. temporal anti-aliasing */

static const float *px_at(const gi_frame *f, uint32_t x, uint32_t y) { return f->final + 3 * ((size_t)y * EW + x); }

static void test_taa(void **state)
{
    (void)state;
    enum { N = 16 };
    tu_fx ref, x;
    pf_camera cam;
    edge_begin(&ref, &cam, 2, N, 0);
    gi_frame_render_raster(&ref.f);
    edge_begin(&x, &cam, 2, 1, N);
    for (int k = 0; k < N; k++) gi_frame_render_raster(&x.f);
    /* a still camera: frame N - 1 is the average of pattern points 0..N-1, as --aa N */
    double worst = 0.0;
    for (size_t i = 0; i < (size_t)EW * EH * 3; i++) worst = fmax(worst, fabs(x.f.final[i] - ref.f.final[i]) / LE);
    print_message("still camera: frame %d of --taa %d against --aa %d: largest difference %.2g Le\n", N, N, N, worst);
    assert_true(worst < 1e-5);
    const float strip = px_at(&x.f, STRIP_X, 20)[0], edge = px_at(&x.f, XB(2), 20)[0];
    assert_true(fabsf(strip - LE * (float)covered(N, 0, 0.9) / N + LE * (float)covered(N, 0, 0.6) / N) < 1e-5f);

    /* nothing changes: the running mean goes on, no clamp (the strip keeps its value; this frame's centre sample misses it) */
    gi_frame_render_raster(&x.f);
    float want = strip + (0.0f - strip) / (float)N;
    print_message("a static frame: the strip %.5f -> %.5f (running mean %.5f)\n", strip, px_at(&x.f, STRIP_X, 20)[0],
                  want);
    assert_true(fabsf(px_at(&x.f, STRIP_X, 20)[0] - want) < 1e-5f);

    /* a light moved (the image does not change): the history is clamped to the current 3 x 3 neighbourhood,
     * where no sample hit the strip this frame */
    x.scene.lights[0].position.x += 0.5f;
    gi_frame_render_raster(&x.f);
    print_message("a frame whose light moved: the strip -> %.5f (clamped)\n", px_at(&x.f, STRIP_X, 20)[0]);
    assert_true(px_at(&x.f, STRIP_X, 20)[0] == 0.0f);

    /* a camera step of one pixel to the left: the image moves one pixel right and the edge's history comes along
     * (reprojection: this frame's sample of the edge pixel misses the band, so its motion is its neighbour's,
     * the nearest surface of its 3 x 3), blended with this frame's one sample */
    const double th = tanf(0.5f * cam.yfov), step = wx(1.0, th) - wx(0.0, th);
    float before[EW];
    for (uint32_t c = 0; c < EW; c++) before[c] = px_at(&x.f, c, 20)[0];
    const uint16_t *cnt = x.f.aa.taa.count[x.f.aa.taa.cur];
    assert_int_equal(cnt[20 * EW + XB(2)], N);
    x.f.camera.eye.x -= (float)step;
    gi_frame_render_raster(&x.f);
    cnt = x.f.aa.taa.count[x.f.aa.taa.cur];
    float jx, jy; /* this frame's pattern point */
    gi_aa_jitter((uint32_t)(x.f.aa.taa.frame - 1) % N, &jx, &jy);
    const float sample = 0.5f + jx < k_cx[2] ? LE : 0.0f;
    float moved = px_at(&x.f, XB(2) + 1, 20)[0];
    /* a frame whose camera moved keeps GI_TAA_MOVING_FRAMES frames of history at most */
    float blend = before[XB(2)] + (sample - before[XB(2)]) / (float)GI_TAA_MOVING_FRAMES;
    print_message("after a one-pixel step: the edge pixel %.5f moved to column %u: %.5f (history blended with this "
                  "frame's sample %.1f: %.5f); first column's count %u, the others' %u\n",
                  edge, XB(2) + 1, moved, (double)sample, blend, cnt[20 * EW], cnt[20 * EW + 5]);
    assert_true(fabsf(moved - blend) < 2e-3f * LE);
    assert_int_equal(cnt[20 * EW], 1); /* column 0 came into view: restarted */
    assert_int_equal(cnt[20 * EW + 5], GI_TAA_MOVING_FRAMES);

    /* turning around: every direction seen now was behind last frame's camera */
    x.f.camera.forward = pf_v3_scale(x.f.camera.forward, -1.0f);
    x.f.camera.right = pf_v3_scale(x.f.camera.right, -1.0f);
    gi_frame_render_raster(&x.f);
    cnt = x.f.aa.taa.count[x.f.aa.taa.cur];
    uint32_t kept = 0;
    for (size_t i = 0; i < (size_t)EW * EH; i++) kept += cnt[i] > 1;
    print_message("after turning around: %u pixels keep a history\n", kept);
    assert_int_equal(kept, 0);

    /* bad settings */
    pf_error err;
    assert_int_equal(gi_frame_set_aa(&x.f, 0, 0, &err), PF_ERR_ARGUMENT);
    assert_int_equal(gi_frame_set_aa(&x.f, GI_AA_MAX_SAMPLES + 1, 0, &err), PF_ERR_ARGUMENT);
    assert_int_equal(gi_frame_set_aa(&x.f, 1, 1, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "2..256"));
    tu_fx_end(&ref);
    tu_fx_end(&x);
}

/* The rasterized and the ray-traced G-buffer of one jittered sample see the
 * same triangles (the clip-space shift and the ray offset agree) on the
 * Cornell box; with the jitter's sign flipped in one of them they would
 * disagree on every edge pixel. */
static void test_raster_matches_rays(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    tu_fx_begin(&x, 2, RS_SIMD_SCALAR, 128, 96, NULL, NULL, 0);
    const size_t n = 128 * 96;
    uint32_t *rt = malloc(n * sizeof *rt);
    float *rpos = malloc(3 * n * sizeof *rpos);
    assert_true(rt && rpos);
    for (uint32_t j = 0; j < 8; j++) {
        gi_aa_jitter(j, &x.f.aa.jx, &x.f.aa.jy);
        gi_stage_gbuffer_raytrace(&x.f);
        memcpy(rt, x.f.gbuf.prim, n * sizeof *rt);
        for (size_t i = 0; i < n; i++)
            rpos[3 * i] = x.f.gbuf.pos_x[i], rpos[3 * i + 1] = x.f.gbuf.pos_y[i], rpos[3 * i + 2] = x.f.gbuf.depth[i];
        gi_stage_gbuffer_raster(&x.f);
        gi_stage_gbuffer_resolve(&x.f);
        uint32_t differ = 0;
        double worst = 0.0;
        for (size_t i = 0; i < n; i++) {
            if (x.f.gbuf.prim[i] != rt[i]) {
                differ++;
                continue;
            }
            if (rt[i] == RS_GBUFFER_EMPTY) continue;
            worst = fmax(worst, fabs(x.f.gbuf.pos_x[i] - rpos[3 * i]) + fabs(x.f.gbuf.pos_y[i] - rpos[3 * i + 1]));
            worst = fmax(worst, fabs(x.f.gbuf.depth[i] - rpos[3 * i + 2]));
        }
        print_message("sample %u (%+.3f, %+.3f): %u of %zu pixels see another triangle; worst position or depth "
                      "difference %.2g\n",
                      j, (double)x.f.aa.jx, (double)x.f.aa.jy, differ, n, worst);
        assert_true(differ <= n / 500);
        assert_true(worst < 1e-4);
    }
    free(rt);
    free(rpos);
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pattern),
        cmocka_unit_test(test_analytic_edge),
        cmocka_unit_test(test_one_sample_is_today),
        cmocka_unit_test(test_threads_and_isas),
        cmocka_unit_test(test_taa),
        cmocka_unit_test(test_raster_matches_rays),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
