/* test_raster: the triangle rasterizer (rs_raster).
 * - fill rule and watertightness: meshes in the image plane (fans with many
 *   edge angles, slivers, grids) and a closed sphere cover every pixel inside
 *   their silhouette exactly once and nothing outside (exact counts);
 * - clipping: triangles crossing the near plane, wholly behind the camera,
 *   enormous (1e6), degenerate: correct coverage or clean rejection;
 * - scalar vs AVX2 vs AVX-512 and 1 vs 2 vs 5 threads: identical bytes;
 * - rasterized vs Embree G-buffer (Cornell box, Sibenik, conference room):
 *   depth and normal agree on >= 99.5% of pixels;
 * - golden hash of the Cornell box G-buffer (scalar path), with its picture
 *   (tests/data/golden/raster-gbuffer-cornell.png: depth, position, normal,
 *   albedo and triangle id side by side);
 * - the AVX2 G-buffer resolve gives the scalar resolve's planes bit for bit;
 * - vertex blocks: passes that transform only the visible clusters' vertex
 *   blocks, after passes of other views, equal passes of a fresh context. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_rt.h"
#include "rs_raster.h"
#include "rs_shadow.h"
#include "test_frame_fixture.h"
#include "test_util.h"
#include "tu_golden.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SIBENIK SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"
#define CONFERENCE SOFTGI_SHARED_SCENES "/conference/conference.gltf"

/* Golden: rasterized Cornell box G-buffer, 160x120, scalar path, all planes. */
#define GOLDEN_GBUFFER_CORNELL 0xe697fc892483a7d3ull

/* ------------------------------------------------------------ helpers */

/* A scene from raw triangles (positions only, one white material). */
static void scene_from_tris(pf_scene *s, const pf_vec3 *p, uint32_t tri_count)
{
    memset(s, 0, sizeof *s);
    s->vertex_count = 3 * tri_count;
    s->tri_count = tri_count;
    s->positions = calloc(s->vertex_count + 1, sizeof(pf_vec3));
    s->normals = calloc(s->vertex_count, sizeof(pf_vec3));
    s->uvs = calloc(s->vertex_count, sizeof(pf_vec2));
    s->indices = calloc(3 * tri_count, sizeof(uint32_t));
    s->tri_material = calloc(tri_count, sizeof(uint32_t));
    s->material_count = 1;
    s->materials = calloc(1, sizeof(pf_material));
    s->materials[0].base_color[0] = s->materials[0].base_color[1] = s->materials[0].base_color[2] = 1.0f;
    s->materials[0].base_color[3] = 1.0f;
    s->materials[0].base_color_texture = -1;
    for (uint32_t i = 0; i < s->vertex_count; i++) {
        s->positions[i] = p[i];
        s->indices[i] = i;
    }
    for (uint32_t t = 0; t < tri_count; t++) {
        pf_vec3 n = pf_v3_normalize(pf_v3_cross(pf_v3_sub(p[3 * t + 1], p[3 * t]), pf_v3_sub(p[3 * t + 2], p[3 * t])));
        s->normals[3 * t] = s->normals[3 * t + 1] = s->normals[3 * t + 2] = n;
    }
}

typedef struct raster_fx {
    pf_jobs *jobs;
    rs_context *ctx;
    rs_target t;
} raster_fx;

static void fx_begin(raster_fx *fx, const pf_scene *s, uint32_t w, uint32_t h, uint32_t threads, rs_simd simd)
{
    pf_error err;
    fx->jobs = pf_jobs_create(threads);
    assert_non_null(fx->jobs);
    assert_int_equal(rs_context_create(&fx->ctx, s, fx->jobs, simd, &err), PF_OK);
    fx->t.width = w;
    fx->t.height = h;
    fx->t.depth = calloc((size_t)w * h, sizeof(float));
    fx->t.prim = calloc((size_t)w * h, sizeof(uint32_t));
    fx->t.coverage = calloc((size_t)w * h, sizeof(uint32_t));
}

static void fx_end(raster_fx *fx)
{
    free(fx->t.depth);
    free(fx->t.prim);
    free(fx->t.coverage);
    rs_context_destroy(fx->ctx);
    pf_jobs_destroy(fx->jobs);
}

/* Orthographic view of the z = 0 plane: [-1,1]^2 maps onto the image. */
static rs_pass ortho_pass(rs_cull cull)
{
    rs_pass p;
    p.view_proj = rs_mat4_ortho(pf_v3(0, 0, 5), pf_v3(0, 0, -1), pf_v3(0, 1, 0), 1.0f, 1.0f, 1.0f, 10.0f);
    p.cull = cull;
    return p;
}

/* pixel centre of (x, y) in the z = 0 plane under ortho_pass */
static void pixel_to_plane(uint32_t w, uint32_t h, uint32_t x, uint32_t y, double *px, double *py)
{
    *px = ((x + 0.5) / w) * 2.0 - 1.0;
    *py = 1.0 - ((y + 0.5) / h) * 2.0;
}

/* ------------------------------------------------------------ fill rule */

/* A regular n-gon fan around (cx, cy), radius r, in the z = 0 plane, plus a
 * second ring of slivers outside it; every pixel strictly inside the outer
 * polygon must be covered exactly once, every pixel outside not at all. */
static void check_fan(uint32_t n, double cx, double cy, double r, double rot, uint32_t w, uint32_t h)
{
    pf_vec3 *p = calloc(3 * n, sizeof(pf_vec3));
    for (uint32_t i = 0; i < n; i++) {
        double a0 = rot + 2.0 * M_PI * i / n, a1 = rot + 2.0 * M_PI * (i + 1) / n;
        p[3 * i] = pf_v3((float)cx, (float)cy, 0);
        p[3 * i + 1] = pf_v3((float)(cx + r * cos(a0)), (float)(cy + r * sin(a0)), 0);
        p[3 * i + 2] = pf_v3((float)(cx + r * cos(a1)), (float)(cy + r * sin(a1)), 0);
    }
    pf_scene s;
    scene_from_tris(&s, p, n);
    raster_fx fx;
    fx_begin(&fx, &s, w, h, 2, RS_SIMD_SCALAR);
    rs_pass pass = ortho_pass(RS_CULL_NONE);
    rs_render(fx.ctx, &pass, &fx.t, NULL);
    uint32_t inside = 0;
    double apothem = r * cos(M_PI / n);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            double px, py;
            pixel_to_plane(w, h, x, y, &px, &py);
            double dx = px - cx, dy = py - cy, d = sqrt(dx * dx + dy * dy);
            /* distance to the polygon boundary, via the sector's edge */
            double a = atan2(dy, dx) - rot;
            a = fmod(fmod(a, 2 * M_PI / n) + 2 * M_PI / n, 2 * M_PI / n) - M_PI / n;
            double edge_dist = apothem - d * cos(a);
            uint32_t c = fx.t.coverage[y * w + x];
            if (edge_dist > 2e-3) {
                if (c != 1) fail_msg("fan n=%u: pixel (%u,%u) inside covered %u times", n, x, y, c);
                assert_int_not_equal(fx.t.prim[y * w + x], RS_NO_PRIM);
                inside++;
            } else if (edge_dist < -2e-3) {
                if (c != 0) fail_msg("fan n=%u: pixel (%u,%u) outside covered %u times", n, x, y, c);
            } else {
                assert_true(c <= 1); /* on the boundary: at most once */
            }
        }
    assert_true(inside > 100);
    fx_end(&fx);
    pf_scene_free(&s);
    free(p);
}

static void test_fill_rule_fans(void **state)
{
    (void)state;
    check_fan(3, 0.0, 0.0, 0.9, 0.1, 64, 64);
    check_fan(8, 0.05, -0.02, 0.8, 0.0, 97, 61);
    check_fan(37, -0.1, 0.1, 0.7, 0.3, 128, 128);
    check_fan(720, 0.0, 0.0, 0.95, 0.01, 200, 150); /* slivers: 0.5 degree wedges */
    /* centre exactly on a pixel centre and on pixel corners: many edges through it */
    check_fan(64, (0.5 + 31) / 64 * 2 - 1, 1 - (0.5 + 31) / 64 * 2, 0.9, 0.0, 64, 64);
    check_fan(16, 0.0, 0.0, 0.9, 0.0, 64, 64);
}

/* A jittered grid of n x n cells of 2 triangles covering more than a w x h
 * screen: every pixel exactly once. */
static void check_grid(int N, uint32_t w, uint32_t h)
{
    pf_vec3 v[24][24];
    assert_true(N <= 23);
    uint32_t seed = 12345;
    for (int j = 0; j <= N; j++)
        for (int i = 0; i <= N; i++) {
            seed = seed * 1664525u + 1013904223u;
            float jx = (i > 0 && i < N) ? ((int)((seed >> 8) % 1000) - 500) * 3e-5f : 0.0f;
            seed = seed * 1664525u + 1013904223u;
            float jy = (j > 0 && j < N) ? ((int)((seed >> 8) % 1000) - 500) * 3e-5f : 0.0f;
            v[j][i] = pf_v3(-1.2f + 2.4f * i / N + jx, -1.2f + 2.4f * j / N + jy, 0);
        }
    pf_vec3 *p = calloc(6 * N * N, sizeof(pf_vec3));
    uint32_t n = 0;
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            /* alternate the diagonal so shared edges run at many angles */
            if ((i + j) & 1) {
                p[n++] = v[j][i], p[n++] = v[j][i + 1], p[n++] = v[j + 1][i + 1];
                p[n++] = v[j][i], p[n++] = v[j + 1][i + 1], p[n++] = v[j + 1][i];
            } else {
                p[n++] = v[j][i], p[n++] = v[j][i + 1], p[n++] = v[j + 1][i];
                p[n++] = v[j][i + 1], p[n++] = v[j + 1][i + 1], p[n++] = v[j + 1][i];
            }
        }
    pf_scene s;
    scene_from_tris(&s, p, n / 3);
    const rs_simd simds[2] = {RS_SIMD_SCALAR, rs_simd_for_isa(pf_isa_detect())}; /* the scalar and the best path */
    for (int k = 0; k < 2; k++) {
        raster_fx fx;
        fx_begin(&fx, &s, w, h, 2, simds[k]);
        rs_pass pass = ortho_pass(RS_CULL_NONE);
        rs_render(fx.ctx, &pass, &fx.t, NULL);
        for (uint32_t i = 0; i < w * h; i++)
            if (fx.t.coverage[i] != 1)
                fail_msg("grid %d, %s: pixel %u covered %u times", N, rs_simd_name(simds[k]), i, fx.t.coverage[i]);
        /* back-face culling removes exactly the clockwise ones: all are CCW here */
        pass.cull = RS_CULL_FRONT;
        rs_render(fx.ctx, &pass, &fx.t, NULL);
        for (uint32_t i = 0; i < w * h; i++) assert_int_equal(fx.t.coverage[i], 0);
        fx_end(&fx);
    }
    pf_scene_free(&s);
    free(p);
}

static void test_fill_rule_grid(void **state)
{
    (void)state;
    check_grid(23, 211, 157);
    /* cells of 200-400 pixels: triangles whose edge values over a tile do
     * not fit 32 bits in 1/256 pixel, which the tiles walk in pixel units
     * (rs_raster_kernels.c rs__triangle): a wrong floor there covers the
     * centres on a shared edge twice or not at all */
    check_grid(3, 1024, 768);
    check_grid(5, 997, 1013);
}

/* Alpha-masked triangles (alphaMode MASK) take the per-pixel alpha test on
 * every path: three full-screen quads, the nearest masked out (alpha 0.2 <
 * 0.5), the next masked but kept (0.8), an opaque one behind; every pixel
 * must show the kept quad. Fails when a tile forgets which of its
 * triangles are masked (the bin entries' flag, rs_raster.c). */
static void test_alpha_mask(void **state)
{
    (void)state;
    pf_scene s;
    tu_make_alpha_stack(&s, 1.5f);
    pf_error err;
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    const rs_simd simds[2] = {RS_SIMD_SCALAR, rs_simd_for_isa(pf_isa_detect())};
    enum { W = 150, H = 70 }; /* several tiles, a partial one at the right */
    for (int k = 0; k < 2; k++) {
        raster_fx fx;
        fx_begin(&fx, &s, W, H, 2, simds[k]);
        rs_pass pass = ortho_pass(RS_CULL_NONE);
        rs_render(fx.ctx, &pass, &fx.t, NULL);
        for (uint32_t i = 0; i < W * H; i++) {
            uint32_t prim = fx.t.prim[i];
            if (prim == RS_NO_PRIM || s.tri_material[prim] != 1)
                fail_msg("%s: pixel %u shows triangle %u, not the kept quad", rs_simd_name(simds[k]), i, prim);
        }
        fx_end(&fx);
    }
    pf_scene_free(&s);
}

/* A closed outward icosphere seen in perspective with back faces culled:
 * every pixel inside the silhouette exactly once; without culling, twice. */
static void test_watertight_sphere(void **state)
{
    (void)state;
    /* icosphere by subdividing an octahedron 4 times, shared vertices */
    enum { MAXT = 8 * 256 };
    static pf_vec3 tris[MAXT * 3];
    uint32_t n = 0;
    const pf_vec3 o[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int i = 0; i < 8; i++) tris[n++] = o[f[i][0]], tris[n++] = o[f[i][1]], tris[n++] = o[f[i][2]];
    for (int level = 0; level < 4; level++) {
        uint32_t m = n;
        static pf_vec3 out[MAXT * 3];
        uint32_t k = 0;
        for (uint32_t t = 0; t < m; t += 3) {
            pf_vec3 a = tris[t], b = tris[t + 1], c = tris[t + 2];
            pf_vec3 ab = pf_v3_normalize(pf_v3_add(a, b)), bc = pf_v3_normalize(pf_v3_add(b, c)),
                    ca = pf_v3_normalize(pf_v3_add(c, a));
            pf_vec3 q[12] = {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca};
            for (int z = 0; z < 12; z++) out[k++] = q[z];
        }
        memcpy(tris, out, sizeof(pf_vec3) * k);
        n = k;
    }
    pf_scene s;
    scene_from_tris(&s, tris, n / 3);
    raster_fx fx;
    fx_begin(&fx, &s, 160, 120, 2, RS_SIMD_SCALAR);
    rs_pass pass;
    pass.view_proj = rs_mat4_perspective(pf_v3(0.3f, 0.2f, 3.0f), pf_v3_normalize(pf_v3(-0.1f, -0.07f, -1.0f)),
                                         pf_v3(0, 1, 0), pf_radians(50.0f), 160.0f / 120.0f, 0.1f);
    pass.cull = RS_CULL_BACK;
    rs_render(fx.ctx, &pass, &fx.t, NULL);
    uint32_t covered = 0;
    for (uint32_t i = 0; i < 160 * 120; i++) {
        assert_true(fx.t.coverage[i] <= 1);
        covered += fx.t.coverage[i];
    }
    assert_true(covered > 3000);
    /* the silhouette is filled: no empty pixel has covered 4-neighbours on
     * all sides (a crack would) */
    for (uint32_t y = 1; y + 1 < 120; y++)
        for (uint32_t x = 1; x + 1 < 160; x++) {
            uint32_t i = y * 160 + x;
            if (fx.t.coverage[i] == 0)
                assert_false(fx.t.coverage[i - 1] && fx.t.coverage[i + 1] && fx.t.coverage[i - 160] &&
                             fx.t.coverage[i + 160]);
        }
    uint32_t front = covered;
    pass.cull = RS_CULL_NONE;
    rs_render(fx.ctx, &pass, &fx.t, NULL);
    covered = 0;
    for (uint32_t i = 0; i < 160 * 120; i++) {
        assert_true(fx.t.coverage[i] == 0 || fx.t.coverage[i] == 2);
        covered += fx.t.coverage[i];
    }
    assert_int_equal(covered, 2 * front);
    pass.cull = RS_CULL_FRONT; /* back faces alone: the same silhouette */
    rs_render(fx.ctx, &pass, &fx.t, NULL);
    covered = 0;
    for (uint32_t i = 0; i < 160 * 120; i++) covered += fx.t.coverage[i];
    assert_int_equal(covered, front);
    fx_end(&fx);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------ clipping */

static uint32_t count_covered(const rs_target *t)
{
    uint32_t c = 0;
    for (uint32_t i = 0; i < t->width * t->height; i++) c += t->prim[i] != RS_NO_PRIM;
    return c;
}

static void test_clipping(void **state)
{
    (void)state;
    const uint32_t W = 128, H = 96;
    /* camera at the origin looking down -z, near 0.1 */
    rs_pass pass;
    pass.view_proj = rs_mat4_perspective(pf_v3(0, 0, 0), pf_v3(0, 0, -1), pf_v3(0, 1, 0), pf_radians(60.0f),
                                         (float)W / H, 0.1f);
    pass.cull = RS_CULL_NONE;
    pf_error err;
    /* 1. a floor quad y = -1 from z = +50 (behind) to z = -50 (in front): it
     *    crosses the near plane; compare with Embree primary rays */
    {
        pf_vec3 p[6] = {{-50, -1, 50}, {50, -1, 50}, {50, -1, -50}, {-50, -1, 50}, {50, -1, -50}, {-50, -1, -50}};
        pf_scene s;
        scene_from_tris(&s, p, 2);
        assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
        raster_fx fx;
        fx_begin(&fx, &s, W, H, 2, RS_SIMD_SCALAR);
        rs_render(fx.ctx, &pass, &fx.t, NULL);
        pf_rt *rt;
        assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
        pf_camera cam;
        assert_int_equal(pf_camera_look_at(&cam, pf_v3(0, 0, 0), pf_v3(0, 0, -1), pf_radians(60.0f), &err), PF_OK);
        cam.znear = 0.1f;
        uint32_t mismatch = 0, hits = 0;
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++) {
                pf_hit h = pf_rt_intersect1(rt, gi_camera_ray(&cam, W, H, x, y));
                int ray_hit = h.prim != PF_RT_MISS, ras_hit = fx.t.prim[y * W + x] != RS_NO_PRIM;
                mismatch += ray_hit != ras_hit;
                hits += ray_hit;
                if (ray_hit && ras_hit && fabsf(fx.t.depth[y * W + x] - 0.1f / h.t) > 1e-4f * (0.1f / h.t))
                    fail_msg("pixel (%u,%u): raster zs %.9g, ray %.9g (t %.6g)", x, y, fx.t.depth[y * W + x],
                             0.1f / h.t, h.t);
            }
        assert_true(hits > W * H / 3);
        if (mismatch > W) print_message("mismatch %u hits %u\n", mismatch, hits);
        assert_true(mismatch <= W); /* at most the pixels along the far edge of the quad */
        /* every covered pixel was covered exactly once (the two triangles share an edge) */
        for (uint32_t i = 0; i < W * H; i++) assert_true(fx.t.coverage[i] <= 1);
        pf_rt_destroy(rt);
        fx_end(&fx);
        pf_scene_free(&s);
    }
    /* 2. wholly behind the camera; 3. degenerate; 4. enormous; 5. vertices
     *    at w = 0 and beyond the guard band */
    {
        pf_vec3 p[] = {
            {-1, -1, 2},       {1, -1, 2},        {0, 1, 2},        /* behind */
            {0, 0, -1},        {0, 0, -1},        {1, 1, -1},       /* repeated vertex */
            {0, 0, -1},        {1, 1, -1},        {2, 2, -1},       /* collinear */
            {-1e6f, -1e6f, -5}, {1e6f, -1e6f, -5}, {0, 1e6f, -5},   /* enormous, facing the camera */
            {0.5f, 0.3f, 0},   {0.4f, -0.1f, -2}, {-0.3f, 0.2f, -2}, /* a vertex on the w = 0 plane */
            {-3e4f, 0.5f, -1}, {3e4f, 0.5f, -1},  {0, 0.6f, -1},    /* far beyond the guard band */
        };
        pf_scene s;
        scene_from_tris(&s, p, 6);
        raster_fx fx;
        fx_begin(&fx, &s, W, H, 2, RS_SIMD_SCALAR);
        rs_stats st;
        rs_render(fx.ctx, &pass, &fx.t, &st);
        assert_true(st.triangles_clipped >= 2);
        /* the enormous triangle covers every pixel; nothing else is in front of it
         * except the two near ones, which are closer */
        assert_int_equal(count_covered(&fx.t), W * H);
        uint32_t by_prim[6] = {0};
        for (uint32_t i = 0; i < W * H; i++) by_prim[fx.t.prim[i]]++;
        assert_int_equal(by_prim[0], 0); /* behind */
        assert_int_equal(by_prim[1], 0); /* degenerate */
        assert_int_equal(by_prim[2], 0);
        assert_true(by_prim[4] > 0);     /* clipped at the near plane, still drawn */
        assert_true(by_prim[5] > 0);     /* clipped at the guard band, still drawn */
        for (uint32_t i = 0; i < W * H; i++) assert_true(fx.t.coverage[i] >= 1);
        fx_end(&fx);
        pf_scene_free(&s);
    }
}

/* ------------------------------------------------------------ paths and threads */

/* A camera inside the scene's bounds looking across it. */
static pf_camera scene_camera(const pf_scene *s)
{
    if (s->camera_count) return s->cameras[0];
    pf_vec3 c = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    pf_vec3 e = pf_v3_sub(s->bounds_max, s->bounds_min);
    pf_camera cam;
    pf_error err;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3_add(c, pf_v3(-0.35f * e.x, -0.2f * e.y, 0.1f * e.z)),
                                       pf_v3_add(c, pf_v3(0.3f * e.x, -0.1f * e.y, -0.05f * e.z)), pf_radians(70.0f),
                                       &err),
                     PF_OK);
    return cam;
}

static void render_hashes(const pf_scene *s, uint32_t threads, rs_simd simd, uint64_t *hd, uint64_t *hp)
{
    raster_fx fx;
    fx_begin(&fx, s, 320, 240, threads, simd);
    free(fx.t.coverage);
    fx.t.coverage = NULL;
    pf_camera cam = scene_camera(s);
    rs_pass pass = {rs_mat4_camera(&cam, 320, 240), RS_CULL_NONE};
    rs_render(fx.ctx, &pass, &fx.t, NULL);
    *hd = pf_imageio_hash(fx.t.depth, 320 * 240);
    *hp = pf_imageio_hash((const float *)fx.t.prim, 320 * 240);
    pass.cull = RS_CULL_BACK;
    rs_render(fx.ctx, &pass, &fx.t, NULL);
    *hd ^= pf_imageio_hash(fx.t.depth, 320 * 240) * 7;
    fx_end(&fx);
}

static void check_paths(const char *path)
{
    pf_scene s;
    if (!tu_load_or_skip(&s, path)) return;
    pf_isa best = pf_isa_detect();
    uint64_t d0, p0;
    render_hashes(&s, 1, RS_SIMD_SCALAR, &d0, &p0);
    const rs_simd simds[3] = {RS_SIMD_SCALAR, RS_SIMD_AVX2, RS_SIMD_AVX512};
    const uint32_t threads[3] = {1, 2, 5};
    for (int i = 0; i < 3; i++) {
        if (simds[i] == RS_SIMD_AVX2 && best < PF_ISA_AVX2) continue;
        if (simds[i] == RS_SIMD_AVX512 && best < PF_ISA_AVX512) continue;
        for (int j = 0; j < 3; j++) {
            uint64_t d, p;
            render_hashes(&s, threads[j], simds[i], &d, &p);
            if (d != d0 || p != p0)
                fail_msg("%s: %s with %u threads differs from scalar with 1 thread", path, rs_simd_name(simds[i]),
                         threads[j]);
        }
    }
    pf_scene_free(&s);
}

static void test_paths_cornell(void **state)
{
    (void)state;
    check_paths(CORNELL);
}
static void test_paths_sibenik(void **state)
{
    (void)state;
    check_paths(SIBENIK);
}

/* ------------------------------------------------------------ vertex blocks */

/* The vertex stage transforms only the blocks of welded positions that the
 * pass's visible clusters use, so a context's vertex records keep what
 * earlier passes of other views left in the rest. A cube map's six faces
 * (a light at the camera, each face culling most clusters) drawn one after
 * another by one context must equal each face drawn alone by a fresh
 * context, on the scalar and the best path. */
static void check_vertex_blocks(const char *path)
{
    pf_scene s;
    if (!tu_load_or_skip(&s, path)) return;
    pf_camera cam = scene_camera(&s);
    pf_light light = {.type = PF_LIGHT_POINT, .position = cam.eye, .color = {1, 1, 1}, .intensity = 1};
    pf_scene lit = s;
    lit.lights = &light;
    lit.light_count = 1;
    pf_jobs *jobs = pf_jobs_create(2);
    pf_error err;
    rs_shadow_desc desc = {.size = 256};
    rs_shadow_map kept, alone;
    assert_int_equal(rs_shadow_map_init(&kept, &lit, 0, &desc, &err), PF_OK);
    assert_int_equal(rs_shadow_map_init(&alone, &lit, 0, &desc, &err), PF_OK);
    const rs_simd simds[2] = {RS_SIMD_SCALAR, rs_simd_for_isa(pf_isa_detect())};
    for (int k = 0; k < 2; k++) {
        rs_context *ctx;
        assert_int_equal(rs_context_create(&ctx, &lit, jobs, simds[k], &err), PF_OK);
        rs_shadow_render(ctx, &kept, 1, NULL);
        rs_shadow_render(ctx, &kept, 1, NULL); /* face 0 too after the others */
        uint32_t culled_most = 0;
        for (uint32_t f = 0; f < 6; f++) {
            rs_context *fresh;
            assert_int_equal(rs_context_create(&fresh, &lit, jobs, simds[k], &err), PF_OK);
            rs_pass pass = {.view_proj = alone.view_proj[f], .cull = RS_CULL_NONE};
            rs_target t = {.width = 256, .height = 256, .depth = rs_shadow_map_face(&alone, f)};
            rs_stats st;
            rs_render(fresh, &pass, &t, &st);
            culled_most += st.clusters_culled * 2 > (s.tri_count + 255) / 256;
            if (memcmp(rs_shadow_map_face(&kept, f), rs_shadow_map_face(&alone, f), sizeof(float) * 256 * 256))
                fail_msg("%s, %s: cube face %u drawn after the others differs from it drawn alone", path,
                         rs_simd_name(simds[k]), f);
            rs_context_destroy(fresh);
        }
        assert_true(culled_most >= 3); /* most faces skip most clusters: the case tested */
        rs_context_destroy(ctx);
    }
    rs_shadow_map_free(&kept);
    rs_shadow_map_free(&alone);
    pf_jobs_destroy(jobs);
    pf_scene_free(&s);
}

static void test_vertex_blocks_sibenik(void **state)
{
    (void)state;
    check_vertex_blocks(SIBENIK);
}
static void test_vertex_blocks_conference(void **state)
{
    (void)state;
    check_vertex_blocks(CONFERENCE);
}

/* ------------------------------------------------------------ raster vs Embree */

static void check_vs_embree(const char *path)
{
    tu_fx x;
    if (!tu_load_or_skip(&x.scene, path)) return;
    enum { W = 320, H = 240 };
    pf_error err;
    pf_camera cam = scene_camera(&x.scene);
    /* frame a rasterized (the fixture's), frame b ray traced, on one Embree
     * scene and one rasterizer at the CPU's best ISA */
    tu_fx_desc d = {.threads = 2, .simd = rs_simd_for_isa(pf_isa_detect()), .isa = pf_isa_detect(),
                    .build_threads = 2, .w = W, .h = H, .cam = &cam, .shadow_size = 1024};
    tu_fx_begin_with(&x, &d);
    gi_frame *a = &x.f, b;
    gi_frame_desc bd = {.scene = &x.scene, .rt = x.rt, .jobs = x.jobs, .raster = x.rs, .camera = &cam, .width = W,
                        .height = H};
    assert_int_equal(gi_frame_create(&b, &bd, &err), PF_OK);
    gi_stage_gbuffer_raster(a);
    gi_stage_gbuffer_resolve(a);
    gi_stage_gbuffer_raytrace(&b);
    uint32_t agree = 0, hits = 0;
    for (uint32_t i = 0; i < W * H; i++) {
        float da = a->gbuf.depth[i], db = b.gbuf.depth[i];
        int ok;
        if (isinf(da) || isinf(db)) ok = isinf(da) && isinf(db);
        else {
            float dn = a->gbuf.nrm_x[i] * b.gbuf.nrm_x[i] + a->gbuf.nrm_y[i] * b.gbuf.nrm_y[i] +
                       a->gbuf.nrm_z[i] * b.gbuf.nrm_z[i];
            ok = fabsf(da - db) <= 1e-3f * db && dn > 0.999f;
            hits++;
        }
        agree += ok;
    }
    double frac = (double)agree / (W * H);
    print_message("%s: raster vs Embree G-buffer agree on %.4f%% of pixels (%u hit)\n", path, 100.0 * frac, hits);
    assert_true(hits > W * H / 4);
    assert_true(frac >= 0.995);
    gi_frame_free(&b);
    tu_fx_end(&x);
}

static void test_vs_embree_cornell(void **state)
{
    (void)state;
    check_vs_embree(CORNELL);
}
static void test_vs_embree_sibenik(void **state)
{
    (void)state;
    check_vs_embree(SIBENIK);
}
static void test_vs_embree_conference(void **state)
{
    (void)state;
    check_vs_embree(CONFERENCE);
}

/* ------------------------------------------------------------ SIMD resolve */

/* Gives every third triangle of `s` a new material with a 4x4 checker
 * baseColor texture (uvs from the positions), so a resolve meets textured
 * and untextured triangles side by side, in groups of 8 pixels too. */
static void add_checker_material(pf_scene *s)
{
    pf_error err;
    uint8_t texels[4 * 4 * 4];
    for (int i = 0; i < 16; i++) {
        uint8_t v = ((i & 1) ^ (i >> 2 & 1)) ? 230 : 40;
        texels[4 * i + 0] = v, texels[4 * i + 1] = (uint8_t)(255 - v), texels[4 * i + 2] = 128, texels[4 * i + 3] = 255;
    }
    s->images = realloc(s->images, sizeof(pf_image) * (s->image_count + 1));
    s->textures = realloc(s->textures, sizeof(pf_texture) * (s->texture_count + 1));
    s->materials = realloc(s->materials, sizeof(pf_material) * (s->material_count + 1));
    assert_true(s->images && s->textures && s->materials);
    assert_int_equal(pf_image_build_mips(&s->images[s->image_count], texels, 4, 4, &err), PF_OK);
    s->textures[s->texture_count] = (pf_texture){s->image_count, PF_WRAP_REPEAT, PF_WRAP_MIRROR, 1, 1, 1, 1};
    pf_material m = s->materials[0];
    m.base_color[0] = 0.9f, m.base_color[1] = 0.8f, m.base_color[2] = 0.7f;
    m.base_color_texture = (int32_t)s->texture_count;
    s->materials[s->material_count] = m;
    float scale = 4.0f / pf_v3_max_comp(pf_v3_sub(s->bounds_max, s->bounds_min));
    for (uint32_t v = 0; v < s->vertex_count; v++)
        s->uvs[v] = (pf_vec2){s->positions[v].x * scale, (s->positions[v].y + s->positions[v].z) * scale};
    for (uint32_t t = 0; t < s->tri_count; t += 3) s->tri_material[t] = s->material_count;
    s->image_count++, s->texture_count++, s->material_count++;
}

/* rs_gbuffer_resolve_simd (the per-triangle table, AVX2 groups of 8 pixels)
 * against the scalar rs_gbuffer_resolve without the table on the same
 * visibility buffer: every plane bit for bit (Cornell box, Sibenik,
 * conference room, and Sibenik with every third triangle textured; width
 * 1021 leaves partial groups at row ends). */
static void check_simd_resolve(const char *path, int textured)
{
    if (pf_isa_detect() < PF_ISA_AVX2) {
        print_message("SKIP: no AVX2\n");
        return;
    }
    pf_scene s;
    if (!tu_load_or_skip(&s, path)) return;
    if (textured) add_checker_material(&s);
    enum { W = 1021, H = 384 };
    pf_error err;
    pf_jobs *jobs = pf_jobs_create(2);
    rs_context *ctx;
    assert_int_equal(rs_context_create(&ctx, &s, jobs, RS_SIMD_SCALAR, &err), PF_OK);
    pf_camera cam = scene_camera(&s);
    gi_frame f;
    gi_frame_desc fd = {.scene = &s, .jobs = jobs, .raster = ctx, .camera = &cam, .width = W, .height = H};
    assert_int_equal(gi_frame_create(&f, &fd, &err), PF_OK);
    gi_stage_gbuffer_raster(&f);
    rs_gbuffer *g = &f.gbuf;
    float *planes[] = {g->depth, g->pos_x, g->pos_y, g->pos_z, g->nrm_x, g->nrm_y, g->nrm_z, g->alb_r, g->alb_g, g->alb_b};
    enum { NP = sizeof planes / sizeof planes[0] };
    float *ref = malloc(sizeof(float) * W * H * NP);
    assert_non_null(ref);
    rs_gbuffer_resolve(g, &s, &cam, jobs);
    for (int k = 0; k < NP; k++) memcpy(ref + (size_t)k * W * H, planes[k], sizeof(float) * W * H);
    for (int k = 0; k < NP; k++) memset(planes[k], 0xff, sizeof(float) * W * H);
    rs_gbuffer_resolve_simd(g, &s, rs_context_resolve_table(ctx), &cam, jobs, 1);
    uint32_t covered = 0;
    for (uint32_t i = 0; i < W * H; i++) covered += g->prim[i] != RS_GBUFFER_EMPTY;
    for (int k = 0; k < NP; k++) assert_memory_equal(ref + (size_t)k * W * H, planes[k], sizeof(float) * W * H);
    uint32_t with_texture = 0;
    for (uint32_t i = 0; i < W * H; i++)
        with_texture += g->prim[i] != RS_GBUFFER_EMPTY && s.tri_material[g->prim[i]] == s.material_count - 1 && textured;
    print_message("%s%s: SIMD resolve == scalar on all planes (%u of %u pixels covered, %u textured)\n", path,
                  textured ? " + checker" : "", covered, W * H, with_texture);
    if (textured) assert_true(with_texture > W * H / 8);
    assert_true(covered > W * H / 4);
    free(ref);
    gi_frame_free(&f);
    rs_context_destroy(ctx);
    pf_jobs_destroy(jobs);
    pf_scene_free(&s);
}

static void test_gbuffer_simd_resolve(void **state)
{
    (void)state;
    check_simd_resolve(CORNELL, 0);
    check_simd_resolve(SIBENIK, 0);
    check_simd_resolve(CONFERENCE, 0);
    check_simd_resolve(SIBENIK, 1);
}

/* ------------------------------------------------------------ golden */

static void test_golden_gbuffer(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    const pf_scene *s = &x.scene;
    tu_fx_desc d = {.threads = 2, .w = 160, .h = 120, .shadow_size = 1024};
    tu_fx_begin_with(&x, &d);
    gi_stage_gbuffer_raster(&x.f);
    gi_stage_gbuffer_resolve(&x.f);
    const rs_gbuffer *g = &x.f.gbuf;
    const float *planes[] = {g->depth, g->pos_x, g->pos_y, g->pos_z, g->nrm_x, g->nrm_y,
                             g->nrm_z, g->alb_r, g->alb_g, g->alb_b, (const float *)g->prim};
    uint64_t h = 0;
    for (size_t i = 0; i < sizeof planes / sizeof planes[0]; i++) h = h * 31 + pf_imageio_hash(planes[i], 160 * 120);
    /* the picture: depth (nearest to farthest surface), position (over the
     * box's bounds), normal, albedo and triangle id */
    enum { W = 160, H = 120 };
    float dlo = INFINITY, dhi = 0.0f;
    for (int i = 0; i < W * H; i++)
        if (isfinite(g->depth[i])) dlo = fminf(dlo, g->depth[i]), dhi = fmaxf(dhi, g->depth[i]);
    float lo = fminf(fminf(s->bounds_min.x, s->bounds_min.y), s->bounds_min.z);
    float hi = fmaxf(fmaxf(s->bounds_max.x, s->bounds_max.y), s->bounds_max.z);
    tu_golden_picture pic;
    tu_golden_picture_init(&pic, 5 * W, H);
    tu_golden_put_plane(&pic, 0, 0, g->depth, 1, W, H, dlo, dhi);
    tu_golden_put_planes3(&pic, W, 0, g->pos_x, g->pos_y, g->pos_z, 1, W, H, lo, hi);
    tu_golden_put_planes3(&pic, 2 * W, 0, g->nrm_x, g->nrm_y, g->nrm_z, 1, W, H, -1.0f, 1.0f);
    tu_golden_put_planes3(&pic, 3 * W, 0, g->alb_r, g->alb_g, g->alb_b, 1, W, H, 0.0f, 1.0f);
    tu_golden_put_ids(&pic, 4 * W, 0, g->prim, W, H, RS_GBUFFER_EMPTY);
    tu_golden_check("raster-gbuffer-cornell", h, GOLDEN_GBUFFER_CORNELL, &pic);
    tu_golden_picture_free(&pic);
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fill_rule_fans),     cmocka_unit_test(test_fill_rule_grid),
        cmocka_unit_test(test_alpha_mask),
        cmocka_unit_test(test_watertight_sphere),  cmocka_unit_test(test_clipping),
        cmocka_unit_test(test_paths_cornell),      cmocka_unit_test(test_paths_sibenik),
        cmocka_unit_test(test_vs_embree_cornell),  cmocka_unit_test(test_vs_embree_sibenik),
        cmocka_unit_test(test_vs_embree_conference), cmocka_unit_test(test_golden_gbuffer),
        cmocka_unit_test(test_gbuffer_simd_resolve), cmocka_unit_test(test_vertex_blocks_sibenik),
        cmocka_unit_test(test_vertex_blocks_conference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
