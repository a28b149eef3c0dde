/* test_simd: every compiled SIMD kernel table against the scalar path, bit
 * for bit, on random inputs that reach every branch (issue 17: "same bits
 * on every path"). The kernels are written once over the SIMD vocabulary
 * (src/base/simd) and compiled once per instruction set; the scalar compile
 * is the reference. What is checked:
 * - the tile raster's row and block kernels (rs_raster_kernels): random
 *   small and large triangles over an 8x8 block with random earlier depths,
 *   every lane mask and row count; depth, triangle id and the "wrote"
 *   result of every table (scalar included) equal a pixel-by-pixel int64
 *   reference, which checks the 32-bit lanes of small triangles;
 * - the paraboloid lookup (rs_para_lookup.h, rs_para_kernels.visible)
 *   against the scalar rs_para_visible_scaled: random maps (empty and
 *   outside codes included), VPL frames, points in front, behind, on the
 *   axis and near the rim, bias scales 1 and 3;
 * - that rs_para_visible_at is rs_para_visible_scaled with scale 1;
 * - the shadow maps' PCF lookup (rs_shadow_visibility8 on every path, AVX-512
 *   included) against the scalar rs_shadow_visibility: spot, cube and
 *   orthographic maps, power-of-two and other sizes, PCF16 and PCF1, points
 *   over the scene's bounds with random normals (zero normals included) and
 *   random lane masks;
 * - the G-buffer resolve's group kernels (rs_gbuffer_kernels) of every
 *   path against the scalar resolve, every plane (test_raster checks the
 *   AVX2 groups with textured triangles too).
 * The scene-level cross-checks (whole passes, maps and frames on every
 * path, golden hashes) are in test_raster, test_paraboloid, test_shadow and
 * the golden tests. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_isa.h"
#include "rs_para_kernels.h"
#include "rs_paraboloid.h"
#include "rs_raster_kernels.h"
#include "rs_shadow.h"
#include "test_util.h"

static uint64_t rng_next(uint64_t *s) /* splitmix64 */
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double rng_unit(uint64_t *s) { return (double)(rng_next(s) >> 11) * 0x1p-53; }
static int64_t rng_range(uint64_t *s, int64_t lo, int64_t hi) { return lo + (int64_t)(rng_next(s) % (uint64_t)(hi - lo + 1)); }

/* The tables this CPU can run, scalar first. */
static int tables(rs_simd out[3])
{
    int n = 0;
    out[n++] = RS_SIMD_SCALAR;
    pf_isa isa = pf_isa_detect();
    if (isa >= PF_ISA_AVX2) out[n++] = RS_SIMD_AVX2;
    if (isa >= PF_ISA_AVX512) out[n++] = RS_SIMD_AVX512;
    if (n < 3) print_message("note: this CPU runs %d of the 3 SIMD paths\n", n);
    return n;
}

/* ------------------------------------------------------------ raster */

static void random_tri(uint64_t *s, rs__tri *t, int small)
{
    memset(t, 0, sizeof *t);
    int64_t lim = small ? (1 << 14) : (1 << 24); /* |a|, |b| in 1/256 pixel units: 2^14 keeps reach < 2^29 */
    for (int k = 0; k < 3; k++) {
        t->a[k] = (int32_t)rng_range(s, -lim, lim);
        t->b[k] = (int32_t)rng_range(s, -lim, lim);
    }
    if (small) { /* rs__setup_tri's test */
        t->small = 1;
        for (int k = 0; k < 3; k++) {
            int64_t A = t->a[k], B = t->b[k];
            if (((A < 0 ? -A : A) + (B < 0 ? -B : B)) * RS_SUB * 7 >= ((int64_t)1 << 29)) t->small = 0;
        }
    }
    t->zv = rng_unit(s);
    t->xv = rng_range(s, 0, 64) + rng_unit(s);
    t->yv = rng_range(s, 0, 64) + rng_unit(s);
    t->dzdx_d = (rng_unit(s) - 0.5) * 0.02;
    t->dzdy_d = (rng_unit(s) - 0.5) * 0.02;
    t->dzdx = (float)t->dzdx_d;
    t->zmin = (float)rng_unit(s) * 0.5f;
    t->zmax = t->zmin + (float)rng_unit(s) * 0.7f;
    t->prim = (uint32_t)rng_next(s);
}

/* The tile raster's definition, pixel by pixel in exact int64 (the scalar
 * row of softgi before the kernels were written over the vocabulary): every
 * table must give its bits. */
static int ref_rows(const rs__tri *t, int32_t x, int32_t y0, int32_t y1, const int64_t e_in[3], unsigned lanes,
                    float *depth, uint32_t *prim, size_t stride)
{
    int64_t e[3] = {e_in[0], e_in[1], e_in[2]};
    int wrote = 0;
    for (int32_t y = y0; y <= y1; y++) {
        float zrow = rs__zrow(t, x, y);
        float *d = depth + (size_t)(y - y0) * stride;
        uint32_t *pr = prim ? prim + (size_t)(y - y0) * stride : NULL;
        for (int i = 0; i < 8; i++) {
            if (!(lanes >> i & 1)) continue;
            int64_t e0 = e[0] + (int64_t)t->a[0] * RS_SUB * i, e1 = e[1] + (int64_t)t->a[1] * RS_SUB * i;
            int64_t e2 = e[2] + (int64_t)t->a[2] * RS_SUB * i;
            if ((e0 | e1 | e2) < 0) continue;
            float z = zrow + t->dzdx * (float)i;
            z = z < t->zmin ? t->zmin : (z > t->zmax ? t->zmax : z);
            if (z > d[i]) {
                d[i] = z;
                if (pr) pr[i] = t->prim;
                wrote = 1;
            }
        }
        for (int k = 0; k < 3; k++) e[k] += (int64_t)t->b[k] * RS_SUB;
    }
    return wrote;
}

static void test_raster_kernels(void **state)
{
    (void)state;
    rs_simd simd[3];
    int n = tables(simd);
    uint64_t s = 17;
    enum { STRIDE = 64 };
    float depth[3][8 * STRIDE], rdepth[8 * STRIDE];
    uint32_t prim[3][8 * STRIDE], rprim[8 * STRIDE];
    uint32_t blocks = 0, wrote = 0;
    for (int it = 0; it < 40000; it++) {
        rs__tri t;
        random_tri(&s, &t, it % 4 != 0);
        int32_t x = (int32_t)rng_range(&s, 0, 56), y0 = (int32_t)rng_range(&s, 0, 56);
        int32_t y1 = y0 + (int32_t)rng_range(&s, 0, 7);
        unsigned lanes = (unsigned)rng_range(&s, 1, 255);
        if (it % 3 == 0) lanes = 0xffu;
        /* edge values at (x, y0): near the edges, so coverage varies over
         * the block; blocks an edge misses entirely are rejected before the
         * kernels, as rs__raster_tri does */
        int64_t e[3], step[3];
        int reject = 0;
        for (int k = 0; k < 3; k++) {
            step[k] = (int64_t)t.a[k] * RS_SUB;
            int64_t span = (int64_t)(t.a[k] < 0 ? -t.a[k] : t.a[k]) * RS_SUB * 8 +
                           (int64_t)(t.b[k] < 0 ? -t.b[k] : t.b[k]) * RS_SUB * 8 + 1;
            e[k] = rng_range(&s, -span, 2 * span);
            if (it % 7 == 0) e[k] += (int64_t)1 << 31; /* far inside: the 2^30 clamp */
            int64_t emax = (t.a[k] > 0 ? step[k] * 7 : 0) + (t.b[k] > 0 ? (int64_t)t.b[k] * RS_SUB * (y1 - y0) : 0);
            reject |= e[k] + emax < 0;
        }
        if (reject) continue;
        blocks++;
        float init[8 * STRIDE];
        for (int i = 0; i < 8 * STRIDE; i++) init[i] = (float)rng_unit(&s) * 0.8f;
        int w[3];
        for (int p = 0; p < n; p++) {
            const rs_raster_kernels *k = rs_raster_kernels_for(simd[p]);
            memcpy(depth[p], init, sizeof init);
            memset(prim[p], 0xab, sizeof prim[p]);
            if (it % 2)
                w[p] = k->block(&t, x, y0, y1, e, lanes, depth[p], it % 5 ? prim[p] : NULL, STRIDE);
            else { /* one row */
                w[p] = k->row(&t, x, y0, rs__zrow(&t, x, y0), e, step, lanes, depth[p], it % 5 ? prim[p] : NULL);
            }
        }
        memcpy(rdepth, init, sizeof init);
        memset(rprim, 0xab, sizeof rprim);
        int rw = ref_rows(&t, x, y0, it % 2 ? y1 : y0, e, lanes, rdepth, it % 5 ? rprim : NULL, STRIDE);
        wrote += (uint32_t)rw;
        for (int p = 0; p < n; p++) {
            if (w[p] != rw || memcmp(depth[p], rdepth, sizeof rdepth) || memcmp(prim[p], rprim, sizeof rprim))
                fail_msg("raster kernel %s differs from the reference at iteration %d (small %u, lanes %#x, rows %d)",
                         rs_raster_kernels_for(simd[p])->isa, it, t.small, lanes, (int)(y1 - y0 + 1));
        }
    }
    print_message("raster kernels: %u blocks and rows, %u wrote, %d paths identical\n", blocks, wrote, n);
    assert_true(wrote > blocks / 4 && wrote < blocks);
}

/* ------------------------------------------------------------ paraboloid lookup */

static void test_para_lookup(void **state)
{
    (void)state;
    rs_simd simd[3];
    int n = tables(simd);
    uint64_t s = 99;
    const uint32_t res[2] = {128, 67};
    uint32_t visible = 0, total = 0;
    for (int r = 0; r < 2; r++) {
        uint32_t R = res[r];
        uint16_t *map = malloc(((size_t)R * R + 8) * sizeof(uint16_t));
        assert_non_null(map);
        const float range = 20.0f;
        for (size_t i = 0; i < (size_t)R * R + 8; i++) {
            uint64_t k = rng_next(&s) % 10;
            map[i] = k == 0 ? 0xFFFFu : k == 1 ? 0xFFFEu : (uint16_t)(rng_next(&s) % 20000u);
        }
        for (int it = 0; it < 2000; it++) {
            pf_vec3 o = pf_v3((float)rng_unit(&s) * 4 - 2, (float)rng_unit(&s) * 4 - 2, (float)rng_unit(&s) * 4 - 2);
            pf_vec3 nn = pf_v3((float)rng_unit(&s) - 0.5f, (float)rng_unit(&s) - 0.5f, (float)rng_unit(&s) - 0.5f);
            if (it % 50 == 0) nn = pf_v3(0, 0, 1);
            rs_para_frame f = rs_para_frame_make(o, nn);
            float scale = it % 2 ? 1.0f : 3.0f;
            float px[16], py[16], pz[16], cr[16];
            for (int i = 0; i < 16; i++) {
                pf_vec3 d = pf_v3((float)rng_unit(&s) * 2 - 1, (float)rng_unit(&s) * 2 - 1, (float)rng_unit(&s) * 2 - 1);
                float t = (float)rng_unit(&s) * 6.0f;
                if (i == 3) d = pf_v3_scale(f.n, -1.0f); /* straight behind: (u, v) = 0/0 */
                if (i == 4) d = f.n;                     /* on the axis */
                if (i == 5) d = pf_v3_add(f.t, pf_v3_scale(f.n, 1e-4f)); /* near the rim */
                if (i == 6) t = 0.0f;                                      /* the VPL itself */
                pf_vec3 p = pf_v3_add(o, pf_v3_scale(d, t));
                px[i] = p.x, py[i] = p.y, pz[i] = p.z;
                cr[i] = (float)rng_unit(&s) * 2.0f - 1.0f;
                if (i == 7) cr[i] = 0.0f;
                if (i == 8) cr[i] = 1.0f;
            }
            uint32_t ref = 0;
            for (int i = 0; i < 16; i++)
                ref |= (uint32_t)rs_para_visible_scaled(map, R, range, &f, pf_v3(px[i], py[i], pz[i]), cr[i], scale)
                       << i;
            if (scale == 1.0f)
                for (int i = 0; i < 16; i++)
                    assert_int_equal(rs_para_visible_at(map, R, range, &f, pf_v3(px[i], py[i], pz[i]), cr[i]),
                                     (int)(ref >> i & 1));
            visible += (uint32_t)__builtin_popcount(ref);
            total += 16;
            for (int p = 0; p < n; p++) {
                const rs_para_kernels *k = rs_para_kernels_for(simd[p]);
                uint32_t got = 0;
                for (uint32_t i0 = 0; i0 < 16; i0 += k->lanes)
                    got |= k->visible(map, R, range, scale, &f, px + i0, py + i0, pz + i0, cr + i0) << i0;
                if (got != ref)
                    fail_msg("paraboloid lookup %s: %#x, scalar %#x (R %u, iteration %d)", k->isa, got, ref, R, it);
            }
        }
        free(map);
    }
    print_message("paraboloid lookup: %u of %u points visible, %d paths identical\n", visible, total, n);
    assert_true(visible > total / 10 && visible < total);
}

/* ------------------------------------------------------------ PCF lookup */

static pf_light test_light(pf_light_type type, pf_vec3 pos, pf_vec3 dir)
{
    pf_light L;
    memset(&L, 0, sizeof L);
    L.type = type;
    L.position = pos;
    L.direction = pf_v3_normalize(dir);
    L.color = pf_v3(1, 1, 1);
    L.intensity = 10.0f;
    L.inner_cone = pf_radians(30.0f);
    L.outer_cone = pf_radians(40.0f);
    return L;
}

static void test_shadow_lookup(void **state)
{
    (void)state;
    rs_simd simd[3];
    int n = tables(simd);
    pf_scene s;
    if (!tu_load_or_skip(&s, SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf")) return;
    pf_light *lights = realloc(s.lights, 3 * sizeof(pf_light));
    assert_non_null(lights);
    s.lights = lights;
    s.light_count = 3;
    lights[0] = test_light(PF_LIGHT_SPOT, pf_v3(0.45f, 0.5f, 0.1f), pf_v3(-0.2f, -0.5f, 0.25f));
    lights[1] = test_light(PF_LIGHT_POINT, pf_v3(0.278f, 0.5388f, 0.2795f), pf_v3(0, -1, 0));
    lights[2] = test_light(PF_LIGHT_DIRECTIONAL, pf_v3(0, 0, 0), pf_v3(-0.3f, -0.6f, 1.0f));
    pf_error err;
    pf_jobs *jobs = pf_jobs_create(2);
    rs_context *ctx;
    assert_int_equal(rs_context_create(&ctx, &s, jobs, RS_SIMD_SCALAR, &err), PF_OK);
    uint64_t rng = 5;
    uint32_t points = 0, fractional = 0;
    const uint32_t sizes[2] = {256, 300};
    for (int si = 0; si < 2; si++) {
        rs_shadow_desc desc;
        memset(&desc, 0, sizeof desc);
        desc.size = sizes[si];
        rs_shadow_set set;
        assert_int_equal(rs_shadow_set_init(&set, &s, &desc, &err), PF_OK);
        rs_shadow_set_render(ctx, &set, NULL);
        assert_int_equal(rs_context_status(ctx, &err), PF_OK); /* nothing ran out of memory */
        pf_vec3 lo = s.bounds_min, hi = s.bounds_max;
        for (uint32_t l = 0; l < set.count; l++) {
            rs_shadow_map *m = &set.maps[l];
            for (int filter = 0; filter < 2; filter++) {
                m->desc.filter = filter ? RS_SHADOW_PCF1 : RS_SHADOW_PCF16;
                for (int it = 0; it < 1500; it++) {
                    float p[6][8];
                    for (int i = 0; i < 8; i++) {
                        p[0][i] = lo.x + (hi.x - lo.x) * (float)rng_unit(&rng);
                        p[1][i] = lo.y + (hi.y - lo.y) * (float)rng_unit(&rng);
                        p[2][i] = lo.z + (hi.z - lo.z) * (float)rng_unit(&rng);
                        for (int a = 3; a < 6; a++) p[a][i] = i == 5 ? 0.0f : (float)(2.0 * rng_unit(&rng) - 1.0);
                    }
                    unsigned active = it % 3 ? 0xffu : (unsigned)(rng_next(&rng) & 0xffu);
                    float ref[8];
                    for (int i = 0; i < 8; i++) {
                        ref[i] = active >> i & 1 ? rs_shadow_visibility(m, pf_v3(p[0][i], p[1][i], p[2][i]),
                                                                        pf_v3(p[3][i], p[4][i], p[5][i]))
                                                 : 0.0f;
                        fractional += ref[i] > 0.0f && ref[i] < 1.0f;
                    }
                    points += 8;
                    for (int q = 0; q < n; q++) {
                        float got[8];
                        rs_shadow_visibility8(m, simd[q], p[0], p[1], p[2], p[3], p[4], p[5], active, got);
                        if (memcmp(got, ref, sizeof ref))
                            fail_msg("PCF lookup %s differs from scalar: map %u (size %u), filter %d, iteration %d",
                                     rs_simd_name(simd[q]), l, sizes[si], filter, it);
                    }
                }
            }
        }
        rs_shadow_set_free(&set);
    }
    print_message("PCF lookup: %u points (%u fractional), %d paths identical\n", points, fractional, n);
    assert_true(fractional > 0);
    rs_context_destroy(ctx);
    pf_jobs_destroy(jobs);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------ resolve */

static void check_resolve(const char *path, const pf_vec3 *eye_target) /* NULL: the scene's camera */
{
    rs_simd simd[3];
    int n = tables(simd);
    pf_scene s;
    if (!tu_load_or_skip(&s, path)) return;
    enum { W = 509, H = 200 }; /* partial groups at every row's end */
    pf_error err;
    pf_jobs *jobs = pf_jobs_create(2);
    rs_context *ctx;
    assert_int_equal(rs_context_create(&ctx, &s, jobs, RS_SIMD_SCALAR, &err), PF_OK);
    pf_camera cam;
    if (eye_target)
        assert_int_equal(pf_camera_look_at(&cam, eye_target[0], eye_target[1], pf_radians(70.0f), &err), PF_OK);
    else
        cam = s.cameras[0];
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
    for (int p = 1; p < n; p++) {
        for (int k = 0; k < NP; k++) memset(planes[k], 0xff, sizeof(float) * W * H);
        rs_gbuffer_resolve_simd(g, &s, rs_context_resolve_table(ctx), &cam, jobs, (int)simd[p]);
        for (int k = 0; k < NP; k++)
            if (memcmp(ref + (size_t)k * W * H, planes[k], sizeof(float) * W * H))
                fail_msg("%s: resolve %s differs from scalar in plane %d", path, rs_simd_name(simd[p]), k);
    }
    uint32_t covered = 0;
    for (uint32_t i = 0; i < W * H; i++) covered += g->prim[i] != RS_GBUFFER_EMPTY;
    print_message("%s: resolve identical on %d paths (%u of %u pixels covered)\n", strrchr(path, '/') + 1, n, covered,
                  W * H);
    assert_true(covered > W * H / 4);
    free(ref);
    gi_frame_free(&f);
    rs_context_destroy(ctx);
    pf_jobs_destroy(jobs);
    pf_scene_free(&s);
}

static void test_gbuffer_resolve(void **state)
{
    (void)state;
    check_resolve(SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf", NULL);
    const pf_vec3 nave[2] = {{-18.0f, -11.0f, 0.0f}, {10.0f, -8.0f, 0.0f}};
    check_resolve(SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf", nave);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_raster_kernels),
        cmocka_unit_test(test_para_lookup),
        cmocka_unit_test(test_shadow_lookup),
        cmocka_unit_test(test_gbuffer_resolve),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
