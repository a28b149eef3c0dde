/* test_simd: every compiled SIMD kernel table against the scalar path, bit
 * for bit, on random inputs that reach every branch (issue 17: "same bits
 * on every path"). The kernels are written once over the SIMD vocabulary
 * (src/base/simd) and compiled once per instruction set; the scalar compile
 * is the reference. What is checked:
 * - the tile raster (rs_raster_kernels): random tiles of small, medium and
 *   huge triangles (masked ones too) over random earlier depths, partial
 *   tiles at the image's edge; depth, triangle id and coverage of every
 *   table (scalar included) equal a pixel-by-pixel int64 reference, which
 *   checks the 32-bit forms and walks against exact integers;
 * - the paraboloid lookup (rs_para_lookup.h, rs_para_kernels.visible)
 *   against the scalar rs_para_visible_scaled: random maps (empty and
 *   outside codes included), VPL frames, points in front, behind, on the
 *   axis and near the rim, the slope test with bias scales 1 and 3 and the
 *   receiver-plane test with random, zero and grazing normals;
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

/* A set-up triangle from three snapped vertices (1/256 pixel), as
 * rs__setup_tri makes it (edge functions with the top-left rule, the box of
 * covered pixel centres inside a target of tw x th, the small-triangle
 * form), with a random depth plane; `c` gets the exact 64-bit constants
 * (the record may hold the 32-bit form instead). 0 for a triangle of zero
 * area or one covering no pixel centre. */
static int make_tri(uint64_t *s, rs__tri *t, int64_t c[3], const int64_t X[3], const int64_t Y[3], int32_t tw,
                    int32_t th)
{
    memset(t, 0, sizeof *t);
    int64_t x[3] = {X[0], X[1], X[2]}, y[3] = {Y[0], Y[1], Y[2]};
    int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    if (area == 0) return 0;
    if (area < 0) {
        int64_t tx = x[1], ty = y[1];
        x[1] = x[2], y[1] = y[2], x[2] = tx, y[2] = ty;
    }
    int64_t minx = x[0], maxx = x[0], miny = y[0], maxy = y[0];
    for (int k = 1; k < 3; k++) {
        minx = x[k] < minx ? x[k] : minx, maxx = x[k] > maxx ? x[k] : maxx;
        miny = y[k] < miny ? y[k] : miny, maxy = y[k] > maxy ? y[k] : maxy;
    }
    int64_t px0 = (minx - RS_SUB / 2 + RS_SUB - 1) >> 8, px1 = (maxx - RS_SUB / 2) >> 8;
    int64_t py0 = (miny - RS_SUB / 2 + RS_SUB - 1) >> 8, py1 = (maxy - RS_SUB / 2) >> 8;
    px0 = px0 < 0 ? 0 : px0, py0 = py0 < 0 ? 0 : py0;
    px1 = px1 > tw - 1 ? tw - 1 : px1, py1 = py1 > th - 1 ? th - 1 : py1;
    if (px0 > px1 || py0 > py1) return 0;
    for (int k = 0; k < 3; k++) {
        int a = k, b = (k + 1) % 3;
        int64_t A = y[a] - y[b], B = x[b] - x[a], C = -A * x[a] - B * y[a];
        int top_left = (A == 0 && B > 0) || A > 0;
        t->a[k] = (int32_t)A, t->b[k] = (int32_t)B;
        c[k] = t->c[k] = C - (top_left ? 0 : 1);
    }
    t->x0 = (int32_t)px0, t->x1 = (int32_t)px1, t->y0 = (int32_t)py0, t->y1 = (int32_t)py1;
    rs__tri_classify(t);
    t->zv = rng_unit(s);
    t->xv = (double)x[0] / RS_SUB;
    t->yv = (double)y[0] / RS_SUB;
    t->dzdx_d = (rng_unit(s) - 0.5) * 0.004;
    t->dzdy_d = (rng_unit(s) - 0.5) * 0.004;
    t->zmin = (float)rng_unit(s) * 0.5f;
    t->zmax = t->zmin + (float)rng_unit(s) * 0.7f;
    t->prim = (uint32_t)rng_next(s);
    t->masked = RS__NOT_MASKED;
    return 1;
}

/* The test's alpha test: a fixed hash of the pixel and triangle. */
static int test_alpha(const void *ctx, const void *masked, const rs__tri *t, int32_t x, int32_t y)
{
    (void)ctx, (void)masked;
    uint32_t h = (uint32_t)x * 0x9E3779B1u ^ (uint32_t)y * 0x85EBCA77u ^ t->prim;
    return (h ^ h >> 15) % 3 != 0;
}

/* The tile raster's definition, pixel by pixel in exact int64 (what
 * rs_raster_kernels.h writes down): every table must give its bits. */
static void ref_tile(const rs__tri *const *tris, const int64_t (*c)[3], const int *masked, uint32_t count,
                     int32_t x0, int32_t y0, int32_t xlim, int32_t ylim, float *depth, uint32_t *prim,
                     uint32_t *coverage)
{
    for (uint32_t i = 0; i < count; i++) {
        const rs__tri *t = tris[i];
        float zt = (float)(t->zv + t->dzdx_d * ((double)x0 + 0.5 - t->xv) + t->dzdy_d * ((double)y0 + 0.5 - t->yv));
        float dzdx = (float)t->dzdx_d, dzdy = (float)t->dzdy_d;
        for (int32_t y = 0; y < ylim; y++)
            for (int32_t x = 0; x < xlim; x++) {
                int64_t px = (int64_t)(x0 + x) * RS_SUB + RS_SUB / 2, py = (int64_t)(y0 + y) * RS_SUB + RS_SUB / 2;
                int in = 1;
                for (int k = 0; k < 3; k++) in &= t->a[k] * px + t->b[k] * py + c[i][k] >= 0;
                if (!in) continue;
                size_t o = (size_t)y * 64 + (size_t)x;
                if (coverage) coverage[o]++;
                float z = (zt + dzdx * (float)x) + dzdy * (float)y;
                z = z < t->zmin ? t->zmin : (z > t->zmax ? t->zmax : z);
                if (!(z > depth[o])) continue;
                if (masked[i] && !test_alpha(NULL, NULL, t, x0 + x, y0 + y)) continue;
                depth[o] = z;
                if (prim) prim[o] = t->prim;
            }
    }
}

/* A kernel's tile buffer (stamp order, rs_raster_kernels.h) as rows of 64. */
static void unstamp(const uint32_t *in, uint32_t *out, uint32_t stamp_h)
{
    for (uint32_t y = 0; y < 64; y++)
        for (uint32_t x = 0; x < 64; x++)
            out[y * 64 + x] = in[((y / stamp_h) * 16 + x / 4) * 4 * stamp_h + (y % stamp_h) * 4 + x % 4];
}
static void stamp(const uint32_t *in, uint32_t *out, uint32_t stamp_h)
{
    for (uint32_t y = 0; y < 64; y++)
        for (uint32_t x = 0; x < 64; x++)
            out[((y / stamp_h) * 16 + x / 4) * 4 * stamp_h + (y % stamp_h) * 4 + x % 4] = in[y * 64 + x];
}

/* Random tiles of a few triangles each: small ones (the 32-bit form and the
 * 2 x 2 walk), medium ones (banded walks), huge ones reaching far into the
 * guard band (64-bit rebasing, dropped edges), partial tiles at the image's
 * edge, masked triangles, with and without the id and coverage planes;
 * every table (scalar included) against the int64 reference. */
static void test_raster_kernels(void **state)
{
    (void)state;
    rs_simd simd[3];
    int n = tables(simd);
    uint64_t s = 17;
    enum { MAXT = 12 };
    _Alignas(64) uint32_t depth[64 * 64], prim[64 * 64], cov[64 * 64];
    uint32_t rdepth[64 * 64], rprim[64 * 64], rcov[64 * 64], got[64 * 64], init[64 * 64];
    uint64_t written = 0, pixels = 0, small = 0, large = 0, tiles = 0;
    for (int it = 0; it < 3000; it++) {
        int32_t tw = 64 * (int32_t)rng_range(&s, 1, 8), th = 64 * (int32_t)rng_range(&s, 1, 8);
        if (it % 5 == 0) tw -= (int32_t)rng_range(&s, 1, 63), th -= (int32_t)rng_range(&s, 1, 63);
        int32_t x0 = 64 * (int32_t)rng_range(&s, 0, (tw - 1) / 64), y0 = 64 * (int32_t)rng_range(&s, 0, (th - 1) / 64);
        int32_t xlim = tw - x0 < 64 ? tw - x0 : 64, ylim = th - y0 < 64 ? th - y0 : 64;
        rs__tri tri[MAXT];
        const rs__tri *tp[MAXT];
        const void *mp[MAXT];
        int64_t c[MAXT][3];
        int masked[MAXT];
        uint32_t count = 0;
        for (int k = 0; k < MAXT; k++) {
            int kind = (int)rng_range(&s, 0, 9); /* 0-5 small, 6-8 medium, 9 huge */
            int64_t spread = kind < 6 ? 12 * 256 : kind < 9 ? 120 * 256 : (int64_t)30000 * 256;
            int64_t cx = ((int64_t)x0 + rng_range(&s, -8, 72)) * 256, cy = ((int64_t)y0 + rng_range(&s, -8, 72)) * 256;
            int64_t X[3], Y[3];
            for (int v = 0; v < 3; v++) X[v] = cx + rng_range(&s, -spread, spread), Y[v] = cy + rng_range(&s, -spread, spread);
            if (!make_tri(&s, &tri[count], c[count], X, Y, tw, th)) continue;
            masked[count] = rng_range(&s, 0, 7) == 0;
            tri[count].masked = masked[count] ? 0u : RS__NOT_MASKED;
            mp[count] = masked[count] ? &tri[count] : NULL;
            tp[count] = &tri[count];
            small += tri[count].flags & RS__SMALL ? 1 : 0;
            large += kind == 9;
            count++;
        }
        tiles++;
        for (int i = 0; i < 64 * 64; i++) {
            float z = (float)rng_unit(&s) * 0.8f;
            if (it % 4 == 0) z = 0.0f; /* a cleared tile */
            memcpy(&init[i], &z, 4);
        }
        int with_prim = it % 3 != 0, with_cov = it % 4 == 1;
        memcpy(rdepth, init, sizeof init);
        memset(rprim, 0xab, sizeof rprim);
        memset(rcov, 0, sizeof rcov);
        ref_tile(tp, (const int64_t(*)[3])c, masked, count, x0, y0, xlim, ylim, (float *)rdepth,
                 with_prim ? rprim : NULL, with_cov ? rcov : NULL);
        for (int i = 0; i < 64 * 64; i++) pixels++, written += rdepth[i] != init[i];
        for (int p = 0; p < n; p++) {
            const rs_raster_kernels *kern = rs_raster_kernels_for(simd[p]);
            stamp(init, depth, kern->stamp_h);
            memset(prim, 0xab, sizeof prim);
            memset(cov, 0, sizeof cov);
            rs__tile_in in = {tp, mp, count, x0, y0, xlim, ylim, test_alpha, NULL, (float *)depth,
                              with_prim ? prim : NULL, with_cov ? cov : NULL};
            kern->tile(&in);
            unstamp(depth, got, kern->stamp_h);
            for (int i = 0; i < 64 * 64; i++)
                if (got[i] != rdepth[i] && (i % 64 < xlim && i / 64 < ylim))
                    fail_msg("raster kernel %s: depth differs at (%d, %d) of tile %d (iteration %d)", kern->isa,
                             i % 64, i / 64, (int)tiles, it);
            if (with_prim) {
                unstamp(prim, got, kern->stamp_h);
                for (int i = 0; i < 64 * 64; i++)
                    if (got[i] != rprim[i] && (i % 64 < xlim && i / 64 < ylim))
                        fail_msg("raster kernel %s: id differs at (%d, %d) (iteration %d)", kern->isa, i % 64, i / 64, it);
            }
            if (with_cov) {
                unstamp(cov, got, kern->stamp_h);
                for (int i = 0; i < 64 * 64; i++)
                    if (got[i] != rcov[i] && (i % 64 < xlim && i / 64 < ylim))
                        fail_msg("raster kernel %s: coverage differs at (%d, %d) (iteration %d)", kern->isa, i % 64,
                                 i / 64, it);
            }
        }
    }
    print_message("raster kernels: %llu tiles, %llu small and %llu huge triangles, %.1f%% of pixels written, %d paths "
                  "identical\n",
                  (unsigned long long)tiles, (unsigned long long)small, (unsigned long long)large,
                  100.0 * (double)written / (double)pixels, n);
    assert_true(written > pixels / 20 && written < pixels);
    assert_true(small > 1000 && large > 1000);
}

/* ------------------------------------------------------------ paraboloid lookup */

static void test_para_lookup(void **state)
{
    (void)state;
    rs_simd simd[3];
    int n = tables(simd);
    uint64_t s = 99;
    const uint32_t res[2] = {128, 67};
    uint32_t visible = 0, total = 0, plane_visible = 0, plane_total = 0;
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
            const int mode = it % 3; /* slope x 1, slope x 3, receiver plane */
            float scale = mode == 1 ? 3.0f : 1.0f;
            float px[16], py[16], pz[16], cr[16], nx[16], ny[16], nz[16];
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
                pf_vec3 m = pf_v3_normalize(
                    pf_v3((float)rng_unit(&s) - 0.5f, (float)rng_unit(&s) - 0.5f, (float)rng_unit(&s) - 0.5f));
                if (i == 9) m = pf_v3(0, 0, 0);                      /* no plane: the window's near end */
                if (i == 10) m = pf_v3_normalize(pf_v3_cross(d, f.t)); /* grazing: the ray in the plane */
                if (i == 11) m = pf_v3_normalize(d);                 /* facing the VPL */
                nx[i] = m.x, ny[i] = m.y, nz[i] = m.z;
            }
            uint32_t ref = 0;
            for (int i = 0; i < 16; i++) {
                pf_vec3 m = pf_v3(nx[i], ny[i], nz[i]);
                ref |= (uint32_t)rs_para_visible_scaled(map, R, range, &f, pf_v3(px[i], py[i], pz[i]),
                                                        mode == 2 ? &m : NULL, cr[i], scale)
                       << i;
            }
            visible += (uint32_t)__builtin_popcount(ref);
            total += 16;
            if (mode == 2) plane_visible += (uint32_t)__builtin_popcount(ref), plane_total += 16;
            for (int p = 0; p < n; p++) {
                const rs_para_kernels *k = rs_para_kernels_for(simd[p]);
                uint32_t got = 0;
                for (uint32_t i0 = 0; i0 < 16; i0 += k->lanes)
                    got |= k->visible(map, R, range, scale, &f, px + i0, py + i0, pz + i0, cr + i0,
                                      mode == 2 ? nx + i0 : NULL, mode == 2 ? ny + i0 : NULL,
                                      mode == 2 ? nz + i0 : NULL)
                           << i0;
                if (got != ref)
                    fail_msg("paraboloid lookup %s: %#x, scalar %#x (R %u, iteration %d)", k->isa, got, ref, R, it);
            }
        }
        free(map);
    }
    print_message("paraboloid lookup: %u of %u points visible (receiver plane: %u of %u), %d paths identical\n",
                  visible, total, plane_visible, plane_total, n);
    assert_true(visible > total / 10 && visible < total);
    assert_true(plane_visible > plane_total / 10 && plane_visible < plane_total);
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
