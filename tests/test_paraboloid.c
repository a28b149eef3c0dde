/* test_paraboloid: exact paraboloid shadow maps (rs_paraboloid) and their
 * simplified shadow geometry (rs_simplify).
 * - the mapping round trip (direction -> uv -> direction, texel lookup);
 * - the storage size: 2048 maps of 128x128 are exactly 64 MiB, and a render
 *   writes exactly its maps;
 * - cross-check against the Embree-traced map (one ray per texel centre):
 *   >= 99.9% of the inside texels agree (both empty, or both hit with codes
 *   at most 1 apart) on the Cornell box, Sibenik and the conference room;
 * - watertightness: VPLs inside the closed sphere see it in every texel at
 *   the right distance; a plane meshed along the texel rays of an odd-sized
 *   map (edges and a vertex exactly on texel centres) has no holes;
 * - the same bytes for 1 and 2 threads and for the scalar and SIMD paths;
 * - a golden FNV-1a 64 hash of one Cornell-box map, with its picture
 *   (tests/data/golden/paraboloid-cornell.png, tu_golden.h);
 * - lookups (rs_para_visible) against Embree shadow rays;
 * - the simplified-scene path: it works, and its measured disagreement with
 *   the full-scene map stays below a stated bound.
 *
 * Timing is not a test's job: `softgi bench raster` times the maps against
 * Embree (docs/perf.md); docs/raster.md has the measured per-map times and
 * the simplification table. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "pf_gltf.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "rs_paraboloid.h"
#include "rs_simplify.h"
#include "test_util.h"
#include "tu_golden.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SPHERE SOFTGI_SOURCE_DIR "/scenes/closed-sphere/closed-sphere.gltf"
#define SIBENIK SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"
#define CONFERENCE SOFTGI_SHARED_SCENES "/conference/conference.gltf"

/* Golden hash of the Cornell-box map in test_golden_hash (FNV-1a 64 over the
 * 128x128 uint16 codes, little-endian). */
#define GOLDEN_CORNELL 0xb47204a5d499b253ull

static uint64_t fnv1a(const void *data, size_t n)
{
    const uint8_t *p = data;
    uint64_t h = 0xcbf29ce484222325ull;
    for (size_t k = 0; k < n; k++) {
        h ^= p[k];
        h *= 0x100000001b3ull;
    }
    return h;
}

/* xorshift64* */
static uint64_t rng_next(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 0x2545F4914F6CDD1Dull;
}
static float rng_float(uint64_t *s) { return (float)(rng_next(s) >> 40) * 0x1p-24f; }

/* VPLs on the scene's surfaces: a random point on a random triangle (seeded),
 * offset by 1e-3 of the diagonal along the triangle's geometric normal,
 * which is also the VPL's normal. */
static void sample_vpls(const pf_scene *s, uint32_t count, uint64_t seed, pf_vec3 *pos, pf_vec3 *nrm)
{
    uint64_t st = seed * 0x9E3779B97F4A7C15ull + 1;
    float off = 1e-3f * pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min));
    for (uint32_t k = 0; k < count; k++) {
        uint32_t t = (uint32_t)(rng_next(&st) % s->tri_count);
        pf_vec3 a = s->positions[s->indices[3 * t]], b = s->positions[s->indices[3 * t + 1]],
                c = s->positions[s->indices[3 * t + 2]];
        float r1 = rng_float(&st), r2 = rng_float(&st);
        if (r1 + r2 > 1.0f) {
            r1 = 1.0f - r1;
            r2 = 1.0f - r2;
        }
        pf_vec3 p = pf_v3_add(a, pf_v3_add(pf_v3_scale(pf_v3_sub(b, a), r1), pf_v3_scale(pf_v3_sub(c, a), r2)));
        pf_vec3 n = pf_v3_normalize(pf_v3_cross(pf_v3_sub(b, a), pf_v3_sub(c, a)));
        pos[k] = pf_v3_add(p, pf_v3_scale(n, off));
        nrm[k] = n;
    }
}

typedef struct agreement {
    uint64_t inside, agree, both_hit, code_diff_max, state_diff;
} agreement;

/* Texel-by-texel comparison of two atlases: agree = both empty, or both hit
 * with codes at most `tol` apart. */
static agreement compare_maps(const uint16_t *a, const uint16_t *b, uint32_t res, uint32_t count, uint32_t tol)
{
    agreement g = {0};
    for (size_t k = 0; k < (size_t)res * res * count; k++) {
        uint32_t t = (uint32_t)(k % ((size_t)res * res));
        int inside = rs_para_texel_inside(res, t % res, t / res);
        if (!inside) {
            assert_int_equal(a[k], RS_PARA_OUTSIDE);
            assert_int_equal(b[k], RS_PARA_OUTSIDE);
            continue;
        }
        g.inside++;
        int ea = a[k] == RS_PARA_EMPTY, eb = b[k] == RS_PARA_EMPTY;
        if (ea != eb) {
            g.state_diff++;
            continue;
        }
        if (ea) {
            g.agree++;
            continue;
        }
        g.both_hit++;
        uint32_t d = a[k] > b[k] ? a[k] - b[k] : b[k] - a[k];
        if (d > g.code_diff_max) g.code_diff_max = d;
        if (d <= tol) g.agree++;
    }
    return g;
}

/* Renders `count` VPL maps of scene s both ways and asserts >= 99.9%
 * agreement. Returns the fraction. */
static double check_vs_traced(const pf_scene *s, uint32_t count, uint32_t res, const char *name)
{
    pf_error err;
    rs_para_options o = {.resolution = res};
    rs_para_context *ctx;
    assert_int_equal(rs_para_context_create(&ctx, s, &o, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, s, pf_isa_detect(), 1, &err), PF_OK);
    pf_vec3 *pos = malloc(count * sizeof(pf_vec3)), *nrm = malloc(count * sizeof(pf_vec3));
    sample_vpls(s, count, 1, pos, nrm);
    float range = rs_para_default_range(s);
    uint16_t *a = malloc(rs_para_atlas_bytes(res, count)), *b = malloc(rs_para_atlas_bytes(res, count));
    pf_jobs *jobs = pf_jobs_create(2);
    rs_para_stats st;
    rs_para_render(a, ctx, jobs, pos, nrm, count, range, &st);
    rs_para_render_traced(b, res, rt, jobs, pos, nrm, count, range);
    agreement g = compare_maps(a, b, res, count, 1);
    double frac = (double)g.agree / (double)g.inside;
    print_message("%s: %u maps %ux%u: %.4f%% of %llu inside texels agree (%llu hit by both, %llu covered in one "
                  "only, max code diff %llu among agreeing states); %llu exact fallbacks\n",
                  name, count, res, res, 100.0 * frac, (unsigned long long)g.inside,
                  (unsigned long long)g.both_hit, (unsigned long long)g.state_diff,
                  (unsigned long long)g.code_diff_max, (unsigned long long)st.texels_exact_fallback);
    assert_true(frac >= 0.999);
    assert_true(g.both_hit > g.inside / 4); /* the maps are not trivially empty */
    pf_jobs_destroy(jobs);
    free(a);
    free(b);
    free(pos);
    free(nrm);
    pf_rt_destroy(rt);
    rs_para_context_destroy(ctx);
    return frac;
}

/* ------------------------------------------------------------------ tests */

static void test_mapping_round_trip(void **state)
{
    (void)state;
    uint64_t st = 7;
    for (int k = 0; k < 100000; k++) {
        /* uniform direction on the upper hemisphere */
        float z = rng_float(&st), phi = 2.0f * PF_PI * rng_float(&st);
        float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        pf_vec3 d = pf_v3(r * cosf(phi), r * sinf(phi), z);
        pf_vec2 uv = rs_para_dir_to_uv(d);
        assert_true(uv.x * uv.x + uv.y * uv.y <= 1.0f + 1e-6f);
        pf_vec3 e = rs_para_uv_to_dir(uv);
        assert_float_equal(e.x, d.x, 1e-6f);
        assert_float_equal(e.y, d.y, 1e-6f);
        assert_float_equal(e.z, d.z, 1e-6f);
    }
    /* the pole and the rim */
    pf_vec2 c = rs_para_dir_to_uv(pf_v3(0, 0, 1));
    assert_true(c.x == 0.0f && c.y == 0.0f);
    pf_vec2 rim = rs_para_dir_to_uv(pf_v3(1, 0, 0));
    assert_float_equal(rim.x, 1.0f, 0.0f);
    /* every inside texel's centre direction looks up that texel, and a few
     * texels hold exactly pi/4 of the map */
    for (uint32_t res = 4; res <= 130; res += 21) {
        uint32_t inside = 0;
        for (uint32_t j = 0; j < res; j++)
            for (uint32_t i = 0; i < res; i++) {
                if (!rs_para_texel_inside(res, i, j)) continue;
                inside++;
                pf_vec3 d = rs_para_uv_to_dir(rs_para_texel_uv(res, i, j));
                assert_int_equal(rs_para_texel_of(res, pf_v3_scale(d, 3.0f)), j * res + i);
            }
        double frac = (double)inside / ((double)res * res);
        assert_true(fabs(frac - PF_PI / 4.0) < 4.0 / res);
    }
    /* directions at the horizon, below it, and rim texels whose square
     * reaches past the disc all land on inside texels */
    for (int k = 0; k < 1000; k++) {
        float phi = 2.0f * PF_PI * (float)k / 1000.0f;
        for (float z = -0.2f; z <= 0.01f; z += 0.05f) {
            uint32_t t = rs_para_texel_of(128, pf_v3(cosf(phi), sinf(phi), z));
            assert_true(rs_para_texel_inside(128, t % 128, t / 128));
        }
    }
}

static void test_atlas_size(void **state)
{
    (void)state;
    /* Hedman 2017 Sec. 5.4 budget: 2048 VPLs; 16 bit per texel, nothing more */
    assert_int_equal(rs_para_map_bytes(128), 128 * 128 * 2);
    assert_int_equal(rs_para_atlas_bytes(128, 2048), (size_t)64 * 1024 * 1024);

    /* a render writes exactly its maps: guard words after the atlas stay */
    pf_scene s;
    assert_true(tu_load_or_skip(&s, CORNELL));
    pf_error err;
    rs_para_context *ctx;
    rs_para_options o = {.resolution = 32};
    assert_int_equal(rs_para_context_create(&ctx, &s, &o, &err), PF_OK);
    assert_int_equal(rs_para_resolution(ctx), 32);
    enum { N = 3 };
    size_t n = rs_para_atlas_bytes(32, N) / 2;
    uint16_t *atlas = malloc((n + 64) * sizeof(uint16_t));
    for (size_t k = 0; k < n + 64; k++) atlas[k] = 0x5a5a;
    pf_vec3 pos[N], nrm[N];
    sample_vpls(&s, N, 3, pos, nrm);
    rs_para_render(atlas, ctx, NULL, pos, nrm, N, rs_para_default_range(&s), NULL);
    for (size_t k = 0; k < n; k++) assert_true(atlas[k] != 0x5a5a);
    for (size_t k = n; k < n + 64; k++) assert_int_equal(atlas[k], 0x5a5a);
    free(atlas);
    rs_para_context_destroy(ctx);

    /* bad options */
    rs_para_options bad = {.resolution = 2};
    assert_int_equal(rs_para_context_create(&ctx, &s, &bad, &err), PF_ERR_ARGUMENT);
    rs_para_options bad2 = {.cluster_size = 40};
    assert_int_equal(rs_para_context_create(&ctx, &s, &bad2, &err), PF_ERR_ARGUMENT);
    pf_scene_free(&s);
}

static void test_cornell_vs_traced(void **state)
{
    (void)state;
    pf_scene s;
    assert_true(tu_load_or_skip(&s, CORNELL));
    check_vs_traced(&s, 64, 128, "cornell");
    check_vs_traced(&s, 16, 67, "cornell (odd resolution)");
    pf_scene_free(&s);
}

static void test_sibenik_vs_traced(void **state)
{
    (void)state;
    pf_scene s;
    if (!tu_load_or_skip(&s, SIBENIK)) return;
    check_vs_traced(&s, 24, 128, "sibenik");
    pf_scene_free(&s);
}

static void test_conference_vs_traced(void **state)
{
    (void)state;
    pf_scene s;
    if (!tu_load_or_skip(&s, CONFERENCE)) return;
    check_vs_traced(&s, 12, 128, "conference");
    pf_scene_free(&s);
}

/* VPLs inside the closed sphere (icosphere of radius 1, 1280 flat facets):
 * every inside texel is covered, at the distance of the facet plane the ray
 * meets, which lies between the inscribed and the circumscribed sphere. */
static void test_closed_sphere_watertight(void **state)
{
    (void)state;
    pf_scene s;
    assert_true(tu_load_or_skip(&s, SPHERE));
    pf_error err;
    rs_para_context *ctx;
    assert_int_equal(rs_para_context_create(&ctx, &s, NULL, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, pf_isa_detect(), 1, &err), PF_OK);
    enum { N = 24 };
    pf_vec3 pos[N], nrm[N];
    uint64_t st = 11;
    for (int k = 0; k < N; k++) {
        /* the centre, points near the wall and random points inside */
        float rr = k == 0 ? 0.0f : (k < 8 ? 0.97f : 0.8f * rng_float(&st));
        pf_vec3 d = pf_v3_normalize(pf_v3(rng_float(&st) - 0.5f, rng_float(&st) - 0.5f, rng_float(&st) - 0.5f));
        pos[k] = pf_v3_scale(d, rr);
        nrm[k] = pf_v3_normalize(pf_v3(rng_float(&st) - 0.5f, rng_float(&st) - 0.5f, rng_float(&st) - 0.5f));
    }
    /* axis-aligned normals through the centre: texel rays in symmetric
     * configurations with the icosphere's vertices */
    nrm[0] = pf_v3(0, 0, 1);
    nrm[1] = pf_v3(0, 1, 0);
    pos[1] = pf_v3(0, 0, 0);
    const uint32_t R = 128;
    float range = 2.0f;
    uint16_t *a = malloc(rs_para_atlas_bytes(R, N)), *b = malloc(rs_para_atlas_bytes(R, N));
    rs_para_render(a, ctx, NULL, pos, nrm, N, range, NULL);
    rs_para_render_traced(b, R, rt, NULL, pos, nrm, N, range);
    /* the icosphere's facets are at least cos(max facet angle) from the centre */
    const float inner = 0.99f;
    for (int k = 0; k < N; k++) {
        rs_para_frame f = rs_para_frame_make(pos[k], nrm[k]);
        for (uint32_t j = 0; j < R; j++)
            for (uint32_t i = 0; i < R; i++) {
                uint16_t c = a[(size_t)k * R * R + j * R + i];
                if (!rs_para_texel_inside(R, i, j)) {
                    assert_int_equal(c, RS_PARA_OUTSIDE);
                    continue;
                }
                if (c == RS_PARA_EMPTY) fail_msg("VPL %d: texel (%u, %u) sees through the closed sphere", k, i, j);
                /* distance along the texel direction to the unit sphere */
                pf_vec3 dl = rs_para_uv_to_dir(rs_para_texel_uv(R, i, j));
                pf_vec3 dw =
                    pf_v3_add(pf_v3_add(pf_v3_scale(f.t, dl.x), pf_v3_scale(f.b, dl.y)), pf_v3_scale(f.n, dl.z));
                float pd = pf_v3_dot(pos[k], dw), pp = pf_v3_dot(pos[k], pos[k]);
                float t_out = -pd + sqrtf(pd * pd - (pp - 1.0f));
                float t_in = -pd + sqrtf(fmaxf(0.0f, pd * pd - (pp - inner * inner)));
                float lo = (float)c * range / RS_PARA_CODES, hi = ((float)c + 1.0f) * range / RS_PARA_CODES;
                if (!(hi >= t_in - 1e-4f && lo <= t_out + 1e-4f))
                    fail_msg("VPL %d texel (%u, %u): depth [%g, %g] outside [%g, %g]", k, i, j, (double)lo, (double)hi,
                             (double)t_in, (double)t_out);
                uint16_t cb = b[(size_t)k * R * R + j * R + i];
                assert_true(cb != RS_PARA_EMPTY);
                assert_true(abs((int)c - (int)cb) <= 1);
            }
    }
    free(a);
    free(b);
    pf_rt_destroy(rt);
    rs_para_context_destroy(ctx);
    pf_scene_free(&s);
}

/* A plane z = 1 meshed so that texel rays of an odd-sized map run exactly
 * along its edges: with R odd, the middle column has u = 0 and the middle row
 * v = 0 exactly, so every centre in them lies on the planes x = 0 and y = 0,
 * and the middle texel looks straight at the vertex (0, 0, 1) that 8
 * triangles share. Edges through it in every direction (a fan of diagonals
 * too) give ties the rule has to break once. No texel may stay empty. */
static void test_plane_ties(void **state)
{
    (void)state;
    enum { G = 8 }; /* grid cells per side over [-4, 4]^2 */
    pf_scene s;
    memset(&s, 0, sizeof s);
    s.vertex_count = (G + 1) * (G + 1);
    s.tri_count = 2 * G * G;
    s.positions = calloc(s.vertex_count + 1, sizeof(pf_vec3));
    s.normals = calloc(s.vertex_count, sizeof(pf_vec3));
    s.uvs = calloc(s.vertex_count, sizeof(pf_vec2));
    s.indices = calloc(3 * s.tri_count, sizeof(uint32_t));
    s.tri_material = calloc(s.tri_count, sizeof(uint32_t));
    s.material_count = 1;
    s.materials = calloc(1, sizeof(pf_material));
    s.materials[0].base_color_texture = -1;
    for (int y = 0; y <= G; y++)
        for (int x = 0; x <= G; x++) {
            s.positions[y * (G + 1) + x] = pf_v3((float)(x - G / 2), (float)(y - G / 2), 1.0f);
            s.normals[y * (G + 1) + x] = pf_v3(0, 0, -1);
        }
    uint32_t t = 0;
    for (int y = 0; y < G; y++)
        for (int x = 0; x < G; x++) {
            uint32_t v00 = y * (G + 1) + x, v10 = v00 + 1, v01 = v00 + G + 1, v11 = v01 + 1;
            /* diagonals alternate so that the centre vertex has 8 triangles */
            int flip = (x < G / 2) != (y < G / 2);
            uint32_t q[6] = {v00, v10, v11, v00, v11, v01};
            uint32_t p[6] = {v00, v10, v01, v10, v11, v01};
            memcpy(&s.indices[3 * t], flip ? p : q, sizeof q);
            t += 2;
        }
    pf_error err;
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    for (uint32_t res = 33; res <= 129; res += 96) {
        rs_para_options o = {.resolution = res, .force_scalar = 1};
        rs_para_context *ctx;
        assert_int_equal(rs_para_context_create(&ctx, &s, &o, &err), PF_OK);
        uint16_t *m = malloc(rs_para_map_bytes(res));
        pf_vec3 pos = pf_v3(0, 0, 0), n = pf_v3(0, 0, 1);
        rs_para_stats st;
        rs_para_render(m, ctx, NULL, &pos, &n, 1, 20.0f, &st);
        assert_true(st.texels_exact_fallback > 0); /* ties were met */
        uint32_t checked = 0;
        for (uint32_t j = 0; j < res; j++)
            for (uint32_t i = 0; i < res; i++) {
                if (!rs_para_texel_inside(res, i, j)) continue;
                pf_vec3 d = rs_para_uv_to_dir(rs_para_texel_uv(res, i, j));
                /* the ray meets z = 1 at d / d.z: inside the plane's square? */
                float x = d.x / d.z, y = d.y / d.z;
                if (fabsf(x) > 3.99f || fabsf(y) > 3.99f) continue;
                checked++;
                uint16_t c = m[j * res + i];
                if (c == RS_PARA_EMPTY) fail_msg("res %u: hole at texel (%u, %u)", res, i, j);
                float dist = 1.0f / d.z;
                float lo = (float)c * 20.0f / RS_PARA_CODES, hi = ((float)c + 1.0f) * 20.0f / RS_PARA_CODES;
                assert_true(lo <= dist * 1.000001f && hi >= dist * 0.999999f);
            }
        assert_true(checked > res * res / 3);
        free(m);
        rs_para_context_destroy(ctx);
    }
    pf_scene_free(&s);
}

static void check_same_bytes(const pf_scene *s, uint32_t count)
{
    pf_error err;
    rs_para_context *ctx;
    assert_int_equal(rs_para_context_create(&ctx, s, NULL, &err), PF_OK);
    pf_vec3 *pos = malloc(count * sizeof(pf_vec3)), *nrm = malloc(count * sizeof(pf_vec3));
    sample_vpls(s, count, 5, pos, nrm);
    size_t bytes = rs_para_atlas_bytes(128, count);
    uint16_t *ref = malloc(bytes), *other = malloc(bytes);
    float range = rs_para_default_range(s);
    rs_simd best = rs_para_simd(ctx);
    rs_para_set_simd(ctx, RS_SIMD_SCALAR);
    rs_para_stats st_ref, st;
    pf_jobs *j1 = pf_jobs_create(1), *j2 = pf_jobs_create(2);
    rs_para_render(ref, ctx, j1, pos, nrm, count, range, &st_ref);
    const rs_simd paths[3] = {RS_SIMD_SCALAR, RS_SIMD_AVX2, RS_SIMD_AVX512};
    for (int p = 0; p < 3; p++) {
        rs_para_set_simd(ctx, paths[p]);
        if (rs_para_simd(ctx) != paths[p]) continue; /* the CPU lacks it */
        memset(other, 0, bytes);
        rs_para_render(other, ctx, j2, pos, nrm, count, range, &st);
        assert_memory_equal(ref, other, bytes);
        assert_int_equal(st.triangles_drawn, st_ref.triangles_drawn);
        assert_int_equal(st.texels_tested, st_ref.texels_tested);
        assert_int_equal(st.texels_exact_fallback, st_ref.texels_exact_fallback);
        memset(other, 0, bytes);
        rs_para_render(other, ctx, NULL, pos, nrm, count, range, NULL);
        assert_memory_equal(ref, other, bytes);
    }
    rs_para_set_simd(ctx, best);
    /* rs_para_render_slots: the maps in reverse order, each into its slot
     * (map k of the list to slot count-1-k), spread over two workers, give
     * the same atlas; slots NULL is rs_para_render */
    pf_vec3 *rpos = malloc(count * sizeof(pf_vec3)), *rnrm = malloc(count * sizeof(pf_vec3));
    uint32_t *slots = malloc(count * sizeof(uint32_t));
    for (uint32_t k = 0; k < count; k++) {
        rpos[k] = pos[count - 1 - k];
        rnrm[k] = nrm[count - 1 - k];
        slots[k] = count - 1 - k;
    }
    memset(other, 0, bytes);
    rs_para_render_slots(other, ctx, j2, rpos, rnrm, slots, count, range, NULL);
    assert_memory_equal(ref, other, bytes);
    memset(other, 0, bytes);
    rs_para_render_slots(other, ctx, j2, pos, nrm, NULL, count, range, NULL);
    assert_memory_equal(ref, other, bytes);
    free(rpos);
    free(rnrm);
    free(slots);
    pf_jobs_destroy(j1);
    pf_jobs_destroy(j2);
    free(ref);
    free(other);
    free(pos);
    free(nrm);
    rs_para_context_destroy(ctx);
}

static void test_threads_and_paths_identical(void **state)
{
    (void)state;
    pf_scene s;
    assert_true(tu_load_or_skip(&s, CORNELL));
    check_same_bytes(&s, 16);
    pf_scene_free(&s);
    if (tu_load_or_skip(&s, SIBENIK)) {
        check_same_bytes(&s, 6);
        pf_scene_free(&s);
    }
}

static void test_golden_hash(void **state)
{
    (void)state;
    pf_scene s;
    assert_true(tu_load_or_skip(&s, CORNELL));
    pf_error err;
    rs_para_context *ctx;
    assert_int_equal(rs_para_context_create(&ctx, &s, NULL, &err), PF_OK);
    /* a VPL on the floor under the light, facing up */
    pf_vec3 pos = pf_v3(0.278f, 0.001f, 0.2795f), n = pf_v3(0, 1, 0);
    uint16_t *m = malloc(rs_para_map_bytes(128));
    rs_para_render(m, ctx, NULL, &pos, &n, 1, 1.0f, NULL);
    uint8_t bytes[128 * 128 * 2];
    for (int k = 0; k < 128 * 128; k++) {
        bytes[2 * k] = (uint8_t)(m[k] & 255);
        bytes[2 * k + 1] = (uint8_t)(m[k] >> 8);
    }
    uint64_t h = fnv1a(bytes, sizeof bytes);
    /* the picture: the map's codes as grey (their high byte) */
    tu_golden_picture pic;
    tu_golden_picture_init(&pic, 128, 128);
    for (int k = 0; k < 128 * 128; k++) pic.rgb[3 * k] = pic.rgb[3 * k + 1] = pic.rgb[3 * k + 2] = bytes[2 * k + 1];
    tu_golden_check("paraboloid-cornell", h, GOLDEN_CORNELL, &pic);
    tu_golden_picture_free(&pic);
    free(m);
    rs_para_context_destroy(ctx);
    pf_scene_free(&s);
}

/* rs_para_visible with the suggested bias (rs_para_bias) vs Embree shadow
 * rays, at receivers found by random rays (so not at texel centres), on the
 * Cornell box. A nearest-texel lookup is wrong near shadow boundaries (the
 * texel centre's ray passes the occluder's edge on the other side), in a band
 * about one texel wide, so the disagreement falls like 1/R; receivers more
 * grazing than the bias's tan(theta) clamp (RS_PARA_TAN_MAX) are left out (a
 * plane seen at theta > 83 degrees needs a larger bias than the clamp gives).
 * Measured: 98.5% agree at 128x128 (0.13% falsely shadowed), 99.4% at 256,
 * 99.7% at 512, 99.96% at 2048. The receiver-plane test (geometric
 * normals) on the same receivers: 99.2% agree at 128 (191 -> 66 falsely
 * lit, 18 -> 40 falsely shadowed of 13857) and 99.8% at 512 (32 -> 10,
 * 5 -> 14). */
static void check_lookups(const pf_scene *s, const pf_rt *rt, uint32_t res, double want, double max_false_shadow)
{
    pf_error err;
    rs_para_options o = {.resolution = res};
    rs_para_context *ctx;
    assert_int_equal(rs_para_context_create(&ctx, s, &o, &err), PF_OK);
    enum { N = 8, P = 4000 };
    pf_vec3 pos[N], nrm[N];
    sample_vpls(s, N, 9, pos, nrm);
    float range = rs_para_default_range(s);
    uint16_t *m = malloc(rs_para_atlas_bytes(res, N));
    rs_para_render(m, ctx, NULL, pos, nrm, N, range, NULL);
    uint64_t st = 3;
    uint32_t total = 0, agree = 0, lit = 0, false_shadow = 0, false_lit = 0;
    uint32_t p_agree = 0, p_false_shadow = 0, p_false_lit = 0; /* the receiver-plane test */
    for (int k = 0; k < N; k++) {
        rs_para_frame f = rs_para_frame_make(pos[k], nrm[k]);
        const uint16_t *map = m + (size_t)k * res * res;
        for (int p = 0; p < P; p++) {
            /* a receiver: the first hit of a random ray from a random point
             * of the box's interior */
            pf_vec3 o3 = pf_v3(0.05f + 0.45f * rng_float(&st), 0.05f + 0.45f * rng_float(&st),
                               0.05f + 0.45f * rng_float(&st));
            float z = 2.0f * rng_float(&st) - 1.0f, phi = 2.0f * PF_PI * rng_float(&st);
            float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
            pf_ray ray = {o3, 0.0f, pf_v3(r * cosf(phi), r * sinf(phi), z), INFINITY};
            pf_hit h = pf_rt_intersect1(rt, ray);
            if (h.prim == PF_RT_MISS) continue;
            pf_surface sf;
            pf_rt_surface(rt, &h, 0.0f, &sf);
            if (!(rs_para_to_local(&f, sf.p).z > 0.0f)) continue;
            /* ground truth: a shadow ray from the receiver to the VPL */
            pf_vec3 from = pf_rt_offset_origin(sf.p, sf.ng, pf_v3_sub(f.o, sf.p));
            pf_vec3 to = pf_v3_sub(f.o, from);
            float len = pf_v3_length(to);
            pf_vec3 dir = pf_v3_scale(to, 1.0f / len);
            if (fabsf(pf_v3_dot(sf.ng, dir)) < 1.0f / sqrtf(1.0f + RS_PARA_TAN_MAX * RS_PARA_TAN_MAX)) continue;
            pf_ray sr = {from, 0.0f, dir, len * 0.9999f};
            int vis_rt = !pf_rt_occluded1(rt, sr);
            float bias = rs_para_bias(res, range, &f, sf.p, sf.ng);
            int vis = rs_para_visible(map, res, range, &f, sf.p, bias);
            total++;
            agree += vis == vis_rt;
            lit += vis_rt;
            false_shadow += vis_rt && !vis;
            false_lit += vis && !vis_rt;
            pf_vec3 ng = pf_v3_normalize(sf.ng);
            int pvis = rs_para_visible_scaled(map, res, range, &f, sf.p, &ng, pf_v3_dot(ng, dir), 1.0f);
            p_agree += pvis == vis_rt;
            p_false_shadow += vis_rt && !pvis;
            p_false_lit += pvis && !vis_rt;
            /* the depth fetched along the receiver's direction agrees */
            float dd = rs_para_depth(map, res, range, &f, pf_v3_sub(sf.p, f.o));
            assert_true(dd > 0.0f);
            if (vis) assert_true(dd == INFINITY || len <= dd + bias + 1e-3f);
        }
    }
    print_message("cornell lookups %ux%u: %u of %u agree with shadow rays (%u lit); slope bias: %u falsely shadowed, "
                  "%u falsely lit; receiver plane: %u agree, %u falsely shadowed, %u falsely lit\n",
                  res, res, agree, total, lit, false_shadow, false_lit, p_agree, p_false_shadow, p_false_lit);
    assert_true(total > N * P / 4);
    assert_true(lit > total / 4 && lit < total);
    assert_true((double)agree >= want * total);
    assert_true((double)false_shadow <= max_false_shadow * total);
    /* the receiver-plane test: as many agree, and it lets through less of
     * the light the slope bias leaks where receivers meet occluders */
    assert_true((double)p_agree >= want * total);
    assert_true((double)p_false_shadow <= max_false_shadow * total);
    assert_true(p_false_lit * 2 <= false_lit);
    free(m);
    rs_para_context_destroy(ctx);
}

static void test_lookup_vs_shadow_rays(void **state)
{
    (void)state;
    pf_scene s;
    assert_true(tu_load_or_skip(&s, CORNELL));
    pf_error err;
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, pf_isa_detect(), 1, &err), PF_OK);
    check_lookups(&s, rt, 128, 0.98, 0.005);
    check_lookups(&s, rt, 512, 0.995, 0.002);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ simplified geometry */

typedef struct simpl_cmp {
    double state_diff, depth_diff, depth_diff_eps, total;
    double median_map; /* median over the maps of each map's disagreeing fraction (bias w) */
} simpl_cmp;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Disagreement of map b (simplified) with map a (full): texels whose
 * covered/empty state differs, or whose distances differ by more than the
 * bias. Bias w: one texel footprint at that distance, w = d 4 / (R (1 +
 * rho^2)), plus one code step: the smallest bias any lookup uses
 * (rs_para_bias is w (1 + tan theta) + 2 steps). Bias w + eps: plus the
 * simplifier's absolute error eps, which a lookup into a simplified map must
 * add anyway (a receiver on the full surface may lie up to eps behind the
 * simplified one). */
static simpl_cmp compare_simplified(const uint16_t *a, const uint16_t *b, uint32_t res, uint32_t count, float range,
                                    float eps)
{
    simpl_cmp c = {0, 0, 0, 0, 0};
    double *per_map = calloc(count, sizeof(double));
    for (uint32_t m = 0; m < count; m++) {
        double inside = 0, bad = 0;
        for (uint32_t t = 0; t < res * res; t++) {
            size_t k = (size_t)m * res * res + t;
            uint32_t i = t % res, j = t / res;
            if (!rs_para_texel_inside(res, i, j)) continue;
            inside += 1;
            int ea = a[k] == RS_PARA_EMPTY, eb = b[k] == RS_PARA_EMPTY;
            if (ea != eb) {
                c.state_diff += 1;
                bad += 1;
                continue;
            }
            if (ea) continue;
            pf_vec2 uv = rs_para_texel_uv(res, i, j);
            float da = rs_para_decode(a[k], range), db = rs_para_decode(b[k], range);
            float w = da * 4.0f / ((float)res * (1.0f + uv.x * uv.x + uv.y * uv.y)) + range / RS_PARA_CODES;
            if (fabsf(da - db) > w) {
                c.depth_diff += 1;
                bad += 1;
            }
            if (fabsf(da - db) > w + eps) c.depth_diff_eps += 1;
        }
        c.total += inside;
        per_map[m] = bad / inside;
    }
    qsort(per_map, count, sizeof(double), cmp_double);
    c.median_map = count % 2 ? per_map[count / 2] : 0.5 * (per_map[count / 2 - 1] + per_map[count / 2]);
    free(per_map);
    return c;
}

/* Bounds asserted for the simplified path (16 VPLs on Sibenik, or on the
 * closed sphere without the shared scenes). Measured on Sibenik: ratio 0.75
 * 0.37% disagree; ratio 0.5 0.07% covered/empty, 12.0% depth beyond w,
 * 7.0% beyond w + eps (most of it from the few VPLs a few cm from a
 * surface the simplifier moved by a comparable amount; median map 6.3%). */
#define SIMPLIFY_BOUND_075 0.01   /* all disagreements, bias w, ratio 0.75 */
#define SIMPLIFY_BOUND_STATE 0.005 /* covered/empty, ratio 0.5 */
#define SIMPLIFY_BOUND_EPS 0.10    /* all disagreements, bias w + eps, ratio 0.5 */

static void test_simplified(void **state)
{
    (void)state;
    pf_scene full;
    /* Without the shared scenes the path still runs, on the closed sphere,
     * but its accuracy bounds are Sibenik's: a sphere of 1280 facets loses
     * its shape at these ratios, with the VPLs 3.5 mm inside it. */
    int bounds = tu_file_exists(SIBENIK);
    const char *path = bounds ? SIBENIK : SPHERE;
    if (!bounds)
        print_message("SKIP: %s is absent: the simplified path runs on the sphere, bounds unchecked\n", SIBENIK);
    assert_true(tu_load_or_skip(&full, path));
    pf_error err;
    rs_para_context *cf;
    assert_int_equal(rs_para_context_create(&cf, &full, NULL, &err), PF_OK);
    enum { N = 16 };
    pf_vec3 pos[N], nrm[N];
    sample_vpls(&full, N, 1, pos, nrm);
    float range = rs_para_default_range(&full);
    uint16_t *a = malloc(rs_para_atlas_bytes(128, N)), *b = malloc(rs_para_atlas_bytes(128, N));
    rs_para_render(a, cf, NULL, pos, nrm, N, range, NULL);
    const float ratios[2] = {0.75f, 0.5f};
    for (int r = 0; r < 2; r++) {
        pf_scene simple;
        rs_simplify_options so = {.ratio = ratios[r]};
        rs_simplify_report rep;
        assert_int_equal(rs_simplify_scene(&simple, &full, &so, &rep, &err), PF_OK);
        assert_int_equal(rep.tri_in, full.tri_count);
        assert_int_equal(rep.tri_out, simple.tri_count);
        assert_true(rep.tri_out <= rep.tri_in * (ratios[r] + 0.05f) && rep.tri_out >= rep.tri_in * (ratios[r] - 0.2f));
        rs_para_context *cs;
        assert_int_equal(rs_para_context_create(&cs, &simple, NULL, &err), PF_OK);
        rs_para_render(b, cs, NULL, pos, nrm, N, range, NULL);
        simpl_cmp c = compare_simplified(a, b, 128, N, range, rep.error_absolute);
        double all = (c.state_diff + c.depth_diff) / c.total, all_eps = (c.state_diff + c.depth_diff_eps) / c.total;
        print_message("%s at %.2f: %u -> %u triangles (%u vertices welded to %u), error %.4f%% of the extent "
                      "(%g): disagree %.3f%% (covered/empty %.3f%%, depth beyond w %.3f%%; beyond w + eps "
                      "%.3f%%; median map %.3f%%)\n",
                      path, (double)ratios[r], rep.tri_in, rep.tri_out, rep.vertex_in, rep.vertex_welded,
                      100.0 * rep.error_relative, (double)rep.error_absolute, 100.0 * all,
                      100.0 * c.state_diff / c.total, 100.0 * c.depth_diff / c.total, 100.0 * all_eps,
                      100.0 * c.median_map);
        if (r == 0 && bounds) assert_true(all < SIMPLIFY_BOUND_075);
        if (r == 1) {
            if (bounds) assert_true(c.state_diff / c.total < SIMPLIFY_BOUND_STATE);
            if (bounds) assert_true(all_eps < SIMPLIFY_BOUND_EPS);
            /* the simplified scene also works with Embree (same pf_scene form) */
            pf_rt *rt;
            assert_int_equal(pf_rt_create(&rt, &simple, pf_isa_detect(), 1, &err), PF_OK);
            pf_rt_destroy(rt);
        }
        rs_para_context_destroy(cs);
        pf_scene_free(&simple);
    }
    /* ratio 1 only welds: the maps are the same bits */
    {
        pf_scene welded;
        rs_simplify_options so = {.ratio = 1.0f};
        assert_int_equal(rs_simplify_scene(&welded, &full, &so, NULL, &err), PF_OK);
        assert_int_equal(welded.tri_count, full.tri_count);
        rs_para_context *cw;
        assert_int_equal(rs_para_context_create(&cw, &welded, NULL, &err), PF_OK);
        rs_para_render(b, cw, NULL, pos, nrm, N, range, NULL);
        assert_memory_equal(a, b, rs_para_atlas_bytes(128, N));
        rs_para_context_destroy(cw);
        pf_scene_free(&welded);
    }
    /* bad options */
    pf_scene bad;
    rs_simplify_options bo = {.ratio = 1.5f};
    assert_int_equal(rs_simplify_scene(&bad, &full, &bo, NULL, &err), PF_ERR_ARGUMENT);
    rs_simplify_options be = {.ratio = 0.5f, .max_error = -1.0f};
    assert_int_equal(rs_simplify_scene(&bad, &full, &be, NULL, &err), PF_ERR_ARGUMENT);
    free(a);
    free(b);
    rs_para_context_destroy(cf);
    pf_scene_free(&full);
}

/* Levels of detail (rs_para_options.lod, rs_para_lod.h): bad factors are
 * refused; lod 0 is the exact map; on Sibenik at the factor docs/raster.md
 * names (4) at most 1% of the inside texels differ from the exact maps by
 * coverage or by more than a texel's footprint (issue 13's bound for
 * simplified paraboloid geometry), fewer clusters are considered, and the
 * maps are the same bytes on every path and thread count. */
static double lod_error(const uint16_t *a, const uint16_t *b, uint32_t count, float range)
{
    size_t inside = 0, off = 0;
    for (uint32_t k = 0; k < count; k++)
        for (uint32_t j = 0; j < 128; j++)
            for (uint32_t i = 0; i < 128; i++) {
                size_t id = ((size_t)k * 128 + j) * 128 + i;
                if (a[id] == RS_PARA_OUTSIDE) continue;
                inside++;
                int ea = a[id] == RS_PARA_EMPTY, eb = b[id] == RS_PARA_EMPTY;
                if (ea != eb) {
                    off++;
                } else if (!ea) {
                    float da = rs_para_decode(a[id], range), db = rs_para_decode(b[id], range);
                    pf_vec3 d = rs_para_uv_to_dir(rs_para_texel_uv(128, i, j));
                    off += fabsf(da - db) > rs_para_texel_world_size(128, da, d);
                }
            }
    return (double)off / (double)inside;
}

static void test_lod(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    rs_para_context *ctx;
    assert_true(tu_load_or_skip(&s, CORNELL));
    rs_para_options bad[] = {{.lod = -1.0f}, {.lod = RS_PARA_MAX_LOD * 2.0f}, {.lod = NAN}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        assert_int_equal(rs_para_context_create(&ctx, &s, &bad[k], &err), PF_ERR_ARGUMENT);
        assert_null(ctx);
    }
    pf_scene_free(&s);
    if (!tu_load_or_skip(&s, SIBENIK)) return;
    enum { COUNT = 24 };
    pf_vec3 pos[COUNT], nrm[COUNT];
    sample_vpls(&s, COUNT, 11, pos, nrm);
    float range = rs_para_default_range(&s);
    size_t bytes = rs_para_atlas_bytes(128, COUNT);
    uint16_t *exact = malloc(bytes), *lod = malloc(bytes), *other = malloc(bytes);
    rs_para_stats st_exact, st_lod, st;
    assert_int_equal(rs_para_context_create(&ctx, &s, NULL, &err), PF_OK);
    rs_para_render(exact, ctx, NULL, pos, nrm, COUNT, range, &st_exact);
    rs_para_context_destroy(ctx);
    assert_int_equal(rs_para_context_create(&ctx, &s, &(rs_para_options){.lod = 4.0f}, &err), PF_OK);
    rs_para_render(lod, ctx, NULL, pos, nrm, COUNT, range, &st_lod);
    double e = lod_error(exact, lod, COUNT, range);
    printf("sibenik, lod 4, %u maps: %.3f%% of inside texels off; clusters considered %llu (exact %llu), "
           "triangles drawn %llu (exact %llu), levels %llu\n",
           COUNT, 100.0 * e, (unsigned long long)st_lod.clusters_in, (unsigned long long)st_exact.clusters_in,
           (unsigned long long)st_lod.triangles_drawn, (unsigned long long)st_exact.triangles_drawn,
           (unsigned long long)st_lod.lod_levels);
    assert_true(e <= 0.01);
    assert_true(e > 0.0); /* the levels were used, */
    assert_true(st_lod.lod_levels > 0 && st_lod.clusters_in < st_exact.clusters_in); /* and drew less */
    pf_jobs *j2 = pf_jobs_create(2);
    const rs_simd paths[3] = {RS_SIMD_SCALAR, RS_SIMD_AVX2, RS_SIMD_AVX512};
    for (int p = 0; p < 3; p++) {
        rs_para_set_simd(ctx, paths[p]);
        if (rs_para_simd(ctx) != paths[p]) continue;
        memset(other, 0, bytes);
        rs_para_render(other, ctx, j2, pos, nrm, COUNT, range, &st);
        assert_memory_equal(lod, other, bytes);
        assert_int_equal(st.lod_levels, st_lod.lod_levels);
    }
    pf_jobs_destroy(j2);
    rs_para_context_destroy(ctx);
    free(exact);
    free(lod);
    free(other);
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mapping_round_trip),
        cmocka_unit_test(test_atlas_size),
        cmocka_unit_test(test_cornell_vs_traced),
        cmocka_unit_test(test_sibenik_vs_traced),
        cmocka_unit_test(test_conference_vs_traced),
        cmocka_unit_test(test_closed_sphere_watertight),
        cmocka_unit_test(test_plane_ties),
        cmocka_unit_test(test_threads_and_paths_identical),
        cmocka_unit_test(test_golden_hash),
        cmocka_unit_test(test_lookup_vs_shadow_rays),
        cmocka_unit_test(test_simplified),
        cmocka_unit_test(test_lod),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
