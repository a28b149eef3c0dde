/* test_vpl: the many-light stages (gi_indirect, gi_ir).
 * - one VPL's irradiance on a floor against the analytic answer, with
 *   Embree-ray and paraboloid-map visibility;
 * - the clamp bounds every VPL's contribution (E <= I b);
 * - split then combine returns the G-buffer bit-exactly (several tilings and
 *   image sizes that the tiles do not divide);
 * - the box filter removes a 4x4 structured pattern on a flat wall and does
 *   not blur across a depth discontinuity;
 * - Instant Radiosity: a static scene keeps a static VPL set (nothing moved
 *   on the second frame), flux conservation for one bounce;
 * - every stage of the Cornell box GI frame identical with 1 and 2 threads,
 *   and golden hashes of every stage, each with its picture in
 *   tests/data/golden/vpl-cornell-STAGE.png (tu_golden.h). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "gi_lightpath.h"
#include "gi_reference.h"
#include "gi_view.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "test_frame_fixture.h"
#include "test_util.h"
#include "tu_golden.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

typedef tu_fx fx;

static void fx_begin(fx *x, uint32_t threads, uint32_t w, uint32_t h, const pf_camera *cam,
                     const gi_indirect_options *io)
{
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, w, h, cam, io, 0);
}

static void fx_end(fx *x) { tu_fx_end(x); }

/* A 20 x 20 floor at y = 0 seen from above. */
static void floor_scene(pf_scene *s)
{
    tu_quad q = {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f};
    tu_make_scene(s, &q, 1);
}

static void one_vpl(int raytrace)
{
    fx x;
    floor_scene(&x.scene);
    pf_camera cam;
    pf_error err;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0.2f, 4, 0.1f), pf_v3(0, 0, 0), pf_radians(60), &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.no_interleave = 1;
    io.visibility_raytrace = raytrace;
    io.clamp = 0.0f; /* off */
    io.vpls = 4;
    fx_begin(&x, 2, 64, 48, &cam, &io);
    gi_frame *f = &x.f;
    gi_stage_gbuffer_raster(f);
    gi_stage_gbuffer_resolve(f);
    /* one VPL 1.5 above the floor, facing down at an angle */
    gi_vpl v = {{0.3f, 1.5f, -0.2f}, {0, -1, 0}, {2.0f, 1.0f, 0.5f}, 7, 1};
    v.nrm = pf_v3_normalize(pf_v3(0.3f, -1.0f, 0.2f));
    assert_int_equal(gi_vpl_set_reserve(&f->ind.vpls, 1, &err), PF_OK);
    f->ind.vpls.v[0] = v;
    f->ind.vpls.count = 1;
    gi_stage_vpl_shadow_maps(f);
    gi_stage_split(f);
    gi_stage_assign(f);
    gi_stage_accumulate(f);
    gi_stage_combine(f);
    int checked = 0;
    for (uint32_t i = 0; i < 64 * 48; i++) {
        if (f->gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
        double px = f->gbuf.pos_x[i], py = f->gbuf.pos_y[i], pz = f->gbuf.pos_z[i];
        double dx = v.pos.x - px, dy = v.pos.y - py, dz = v.pos.z - pz, r2 = dx * dx + dy * dy + dz * dz;
        double r = sqrt(r2), c1 = dy / r, c2 = -(v.nrm.x * dx + v.nrm.y * dy + v.nrm.z * dz) / r;
        double G = c1 > 0 && c2 > 0 ? c1 * c2 / r2 : 0.0;
        const double I[3] = {2.0, 1.0, 0.5};
        for (int c = 0; c < 3; c++) {
            double want = I[c] * G, got = f->ind.combined[3 * i + c];
            if (fabs(got - want) > 1e-4 * want + 1e-7) fail_msg("pixel %u: E %.8g, analytic %.8g", i, got, want);
        }
        checked++;
    }
    assert_true(checked > 1000);
    fx_end(&x);
}

static void test_one_vpl_raytrace(void **state)
{
    (void)state;
    one_vpl(1);
}

static void test_one_vpl_paraboloid(void **state)
{
    (void)state;
    one_vpl(0);
}

/* E from any VPL never exceeds I b, whatever the distance. */
static void test_clamp_bounds(void **state)
{
    (void)state;
    fx x;
    floor_scene(&x.scene);
    pf_camera cam;
    pf_error err;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0.2f, 4, 0.1f), pf_v3(0, 0, 0), pf_radians(60), &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.clamp = 50.0f;
    fx_begin(&x, 1, 64, 48, &cam, &io);
    gi_frame *f = &x.f;
    float b = f->ind.b;
    assert_true(b > 0.0f && isfinite(b));
    gi_stage_gbuffer_raster(f);
    gi_stage_gbuffer_resolve(f);
    gi_vpl v = {{0.0f, 0.01f, 0.0f}, {0, -1, 0}, {1, 1, 1}, 1, 1}; /* 1 cm above the floor: G up to 1e4 */
    assert_int_equal(gi_vpl_set_reserve(&f->ind.vpls, 1, &err), PF_OK);
    f->ind.vpls.v[0] = v;
    f->ind.vpls.count = 1;
    gi_stage_split(f);
    gi_stage_assign(f);
    gi_stage_accumulate(f);
    gi_stage_combine(f);
    int at_clamp = 0;
    for (uint32_t i = 0; i < 64 * 48; i++) {
        assert_true(f->ind.combined[3 * i] <= b * 1.0000001f);
        at_clamp += f->ind.combined[3 * i] == b;
    }
    assert_true(at_clamp > 0); /* the clamp was reached under the VPL */
    fx_end(&x);
}

/* split positions, store them as the split irradiance, combine: the
 * G-buffer's positions come back bit for bit. */
static void check_split_combine(uint32_t n, uint32_t m, uint32_t w, uint32_t h)
{
    fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.tiles_n = n;
    io.tiles_m = m;
    io.visibility_raytrace = 1;
    fx_begin(&x, 2, w, h, &x.scene.cameras[0], &io);
    gi_frame *f = &x.f;
    gi_stage_gbuffer_raster(f);
    gi_stage_gbuffer_resolve(f);
    gi_stage_split(f);
    for (uint32_t k = 0; k < w * h; k++) {
        f->ind.split_e[3 * k] = f->ind.split_px[k];
        f->ind.split_e[3 * k + 1] = f->ind.split_py[k];
        f->ind.split_e[3 * k + 2] = f->ind.split_pz[k];
    }
    gi_stage_combine(f);
    for (uint32_t i = 0; i < w * h; i++) {
        assert_memory_equal(&f->ind.combined[3 * i], &f->gbuf.pos_x[i], sizeof(float));
        assert_memory_equal(&f->ind.combined[3 * i + 1], &f->gbuf.pos_y[i], sizeof(float));
        assert_memory_equal(&f->ind.combined[3 * i + 2], &f->gbuf.pos_z[i], sizeof(float));
    }
    /* the split layout is a permutation: every texel written exactly once */
    assert_int_equal(f->ind.tile_x0[n * m], w * h);
    fx_end(&x);
}

static void test_split_combine_exact(void **state)
{
    (void)state;
    check_split_combine(4, 4, 160, 120);
    check_split_combine(3, 2, 37, 29);
    check_split_combine(5, 7, 64, 48);
    check_split_combine(1, 1, 33, 17);
}

/* A 96 x 64 frame of the quads seen from the origin along -z, its
 * G-buffer drawn and COMBINED set to a 4x4 pattern around base[0] on quad 0
 * (prims 0, 1) and base[1] on the others, then filtered with alpha_rel
 * and the filter's position test (distance_test: Laine's). */
static gi_frame *pattern_filtered(fx *x, const tu_quad *q, uint32_t nq, const float base[2], float alpha_rel,
                                  int distance_test)
{
    tu_make_scene(&x->scene, q, nq);
    pf_camera cam;
    pf_error err;
    assert_int_equal(pf_camera_look_at(&cam, pf_v3(0, 0, 0), pf_v3(0, 0, -1), pf_radians(40), &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.visibility_raytrace = 1;
    io.alpha_rel = alpha_rel;
    io.filter_distance = distance_test;
    fx_begin(x, 2, 96, 64, &cam, &io);
    gi_frame *f = &x->f;
    gi_stage_gbuffer_raster(f);
    gi_stage_gbuffer_resolve(f);
    /* pattern values with exact binary sums */
    for (uint32_t y = 0; y < 64; y++)
        for (uint32_t x0 = 0; x0 < 96; x0++) {
            size_t i = (size_t)y * 96 + x0;
            float b = base[f->gbuf.prim[i] < 2 ? 0 : 1];
            float p = ((x0 % 4) * 4 + (y % 4)) / 8.0f - 0.9375f; /* sums to 0 over a 4x4 block */
            for (int c = 0; c < 3; c++) f->ind.combined[3 * i + c] = b + p;
        }
    gi_stage_filter(f);
    return f;
}

/* Two walls facing the camera, the right half 1 m farther: a 4x4 pattern on
 * each is removed completely, and the two walls' values do not mix. */
static void test_box_filter(void **state)
{
    (void)state;
    fx x;
    tu_quad q[2] = {
        {{-1, 0, -3}, {1, 0, 0}, {0, 2, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{1, 0, -4}, {1, 0, 0}, {0, 2, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    /* mean 1.0 on the near wall, 3.0 far; alpha 5% of the 4.5 m diagonal: well under the 1 m step */
    const float base[2] = {1.0f, 3.0f};
    gi_frame *f = pattern_filtered(&x, q, 2, base, 0.05f, 0);
    int interior = 0;
    for (uint32_t y = 2; y + 2 < 64; y++)
        for (uint32_t x0 = 2; x0 + 2 < 96; x0++) {
            size_t i = (size_t)y * 96 + x0;
            if (f->gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
            /* a window that lies on one wall only */
            int mixed = 0;
            for (int dy = -2; dy <= 1; dy++)
                for (int dx = -2; dx <= 1; dx++)
                    mixed |= (f->gbuf.prim[i + dy * 96 + dx] < 2) != (f->gbuf.prim[i] < 2) ||
                             f->gbuf.prim[i + dy * 96 + dx] == RS_GBUFFER_EMPTY;
            float want = f->gbuf.prim[i] < 2 ? 1.0f : 3.0f;
            if (!mixed) {
                if (f->ind.filtered[3 * i] != want) fail_msg("pixel (%u,%u): %.9g, want %g", x0, y, f->ind.filtered[3 * i], want);
                interior++;
            } else {
                /* next to the step: only same-wall samples, so within that wall's pattern range */
                assert_true(fabsf(f->ind.filtered[3 * i] - want) <= 0.95f);
            }
        }
    assert_true(interior > 1000);
    fx_end(&x);
}

/* A floor seen at a grazing angle, a 4x4 pattern on it: the filter's
 * tangent-plane test (the default) keeps each window whole where the floor's
 * pixels lie further apart than alpha, so the pattern goes; Laine's distance
 * test cuts those windows and leaves it (the stripes of issue 18). Returns
 * the share of the floor's whole-window pixels that come out exactly at the
 * mean. */
static double grazing_floor_exact(int distance_test)
{
    fx x;
    tu_quad q = {{0, -0.3f, -6}, {2, 0, 0}, {0, 0, -5}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f};
    const float base[2] = {1.0f, 1.0f};
    /* alpha 11 cm: under the spacing of the floor's rows beyond a few metres */
    gi_frame *f = pattern_filtered(&x, &q, 1, base, 0.01f, distance_test);
    const float a = f->ind.alpha;
    int whole = 0, exact = 0, spread = 0;
    for (uint32_t y = 2; y + 2 < 64; y++)
        for (uint32_t x0 = 2; x0 + 2 < 96; x0++) {
            size_t i = (size_t)y * 96 + x0;
            int ok = 1;
            float far = 0.0f;
            for (int dy = -2; dy <= 1; dy++)
                for (int dx = -2; dx <= 1; dx++) {
                    size_t j = i + (size_t)((ptrdiff_t)dy * 96 + dx);
                    ok &= f->gbuf.prim[j] != RS_GBUFFER_EMPTY;
                    if (ok) {
                        float ex = f->gbuf.pos_x[j] - f->gbuf.pos_x[i], ez = f->gbuf.pos_z[j] - f->gbuf.pos_z[i];
                        float d = sqrtf(ex * ex + ez * ez);
                        far = d > far ? d : far;
                    }
                }
            /* windows on the floor, within the plane test's reach, and some of them wider than alpha */
            if (!ok || !(far < GI_FILTER_PLANE_CAP * a)) continue;
            whole++;
            spread += far > a;
            exact += f->ind.filtered[3 * i] == 1.0f;
        }
    print_message("grazing floor, %s test: %d of %d whole windows exactly at the mean (%d wider than alpha)\n",
                  distance_test ? "distance" : "plane", exact, whole, spread);
    assert_true(whole > 300 && spread > 100);
    fx_end(&x);
    return (double)exact / whole;
}

static void test_box_filter_grazing(void **state)
{
    (void)state;
    assert_true(grazing_floor_exact(0) > 0.99);
    assert_true(grazing_floor_exact(1) < 0.8);
}

/* Instant Radiosity on the Cornell box: the second frame of a static scene
 * moves nothing, and the set is the same. */
static void test_ir_static(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, CORNELL, NULL, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    void *st;
    assert_int_equal(gi_method_ir.create(&st, NULL, &err), PF_OK);
    gi_vpl_set a = {0}, b = {0};
    gi_area_lights area = {0};
    gi_vpl_inputs in = {&s, rt, NULL, &s.cameras[0], 0, 256, 3, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    assert_int_equal(gi_method_ir.update(st, &in, &a, &err), PF_OK);
    in.frame = 1;
    assert_int_equal(gi_method_ir.update(st, &in, &b, &err), PF_OK);
    assert_int_equal(a.count, 256);
    assert_int_equal(b.count, 256);
    uint32_t moved = 0;
    for (uint32_t i = 0; i < b.count; i++) moved += b.v[i].moved;
    assert_int_equal(moved, 0);
    for (uint32_t i = 0; i < a.count; i++) {
        assert_int_equal(a.v[i].id, b.v[i].id);
        assert_true(a.v[i].moved == 1);
    }
    /* moving the light regenerates everything */
    s.lights[0].position.x += 0.05f;
    in.frame = 2;
    assert_int_equal(gi_method_ir.update(st, &in, &b, &err), PF_OK);
    moved = 0;
    for (uint32_t i = 0; i < b.count; i++) moved += b.v[i].moved;
    assert_true(moved > b.count * 9 / 10);
    gi_method_ir.destroy(st);
    gi_vpl_set_free(&a);
    gi_vpl_set_free(&b);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* The GI frame with 1 and 2 threads: every stage's buffer identical; golden. */
static const char *const k_stage_names[8] = {"vpls",     "maps",     "split",  "accumulated",
                                             "combined", "filtered", "direct", "final"};

/* A split-layout buffer (3 floats a texel, or 1: nx) as the tile mosaic the
 * viewer shows (gi_view_mosaic_index), into rgb (3 floats a pixel). */
static void mosaic(const gi_frame *f, const float *split, int channels, float *rgb)
{
    for (uint32_t y = 0; y < f->height; y++)
        for (uint32_t x = 0; x < f->width; x++) {
            size_t k = gi_view_mosaic_index(f, x, y), o = 3 * ((size_t)y * f->width + x);
            for (int c = 0; c < 3; c++)
                rgb[o + c] = k == SIZE_MAX ? 0.0f : split[(size_t)channels * k + (channels == 3 ? c : 0)];
        }
}

/* The pictures of the eight stage hashes: the VPLs from above (x, z) and
 * from the front (x, y); the first 64 paraboloid maps, every 4th texel, in
 * an 8 x 8 grid; the split normals' x and the accumulated irradiance as
 * tile mosaics; combined, filtered, direct and final through the display
 * transform. */
static void stage_pictures(const gi_frame *f, tu_golden_picture pic[8])
{
    const gi_indirect *ind = &f->ind;
    uint32_t W = f->width, H = f->height;
    const float lo[3] = {f->scene->bounds_min.x, f->scene->bounds_min.y, f->scene->bounds_min.z};
    const float hi[3] = {f->scene->bounds_max.x, f->scene->bounds_max.y, f->scene->bounds_max.z};
    tu_golden_picture_init(&pic[0], 2 * W, H);
    tu_golden_put_points(&pic[0], 0, 0, W, H, &ind->vpls.v[0].pos.x, sizeof(gi_vpl) / 4, ind->vpls.count, 0, 2, lo, hi);
    tu_golden_put_points(&pic[0], W, 0, W, H, &ind->vpls.v[0].pos.x, sizeof(gi_vpl) / 4, ind->vpls.count, 0, 1, lo,
                         hi);
    tu_golden_picture_init(&pic[1], 8 * 32, 8 * 32);
    for (uint32_t m = 0; m < ind->vpls.count && m < 64; m++)
        for (uint32_t j = 0; j < 32; j++)
            for (uint32_t i = 0; i < 32; i++) {
                uint16_t code = ind->atlas[(size_t)m * 128 * 128 + (size_t)(4 * j) * 128 + 4 * i];
                uint8_t *o = pic[1].rgb + 3 * ((size_t)((m / 8) * 32 + j) * pic[1].w + (m % 8) * 32 + i);
                o[0] = o[1] = o[2] = (uint8_t)(code >> 8);
            }
    float *tmp = malloc(sizeof(float) * 3 * W * H);
    assert_non_null(tmp);
    tu_golden_picture_init(&pic[2], W, H);
    mosaic(f, ind->split_nx, 1, tmp);
    tu_golden_put_plane(&pic[2], 0, 0, tmp, 3, W, H, -1.0f, 1.0f);
    tu_golden_picture_init(&pic[3], W, H);
    mosaic(f, ind->split_e, 3, tmp);
    tu_golden_put_linear(&pic[3], 0, 0, tmp, W, H, 0.0f);
    free(tmp);
    const float *linear[4] = {ind->combined, ind->filtered, f->direct, f->final};
    for (int k = 0; k < 4; k++) {
        tu_golden_picture_init(&pic[4 + k], W, H);
        tu_golden_put_linear(&pic[4 + k], 0, 0, linear[k], W, H, 0.0f);
    }
}

/* pics (may be NULL) gets the stages' pictures. */
static uint64_t gi_hashes(uint32_t threads, uint64_t stage[8], tu_golden_picture *pics)
{
    fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 64;
    fx_begin(&x, threads, 80, 60, &x.scene.cameras[0], &io);
    gi_frame_render_raster(&x.f);
    uint64_t n = 80 * 60;
    const gi_indirect *ind = &x.f.ind;
    stage[0] = pf_imageio_hash((const float *)ind->vpls.v, ind->vpls.count * (sizeof(gi_vpl) / 4));
    stage[1] = pf_imageio_hash((const float *)ind->atlas, (uint64_t)ind->vpls.count * 128 * 128 / 2);
    stage[2] = pf_imageio_hash(ind->split_nx, n);
    stage[3] = pf_imageio_hash(ind->split_e, 3 * n);
    stage[4] = pf_imageio_hash(ind->combined, 3 * n);
    stage[5] = pf_imageio_hash(ind->filtered, 3 * n);
    stage[6] = pf_imageio_hash(x.f.direct, 3 * n);
    stage[7] = pf_imageio_hash(x.f.final, 3 * n);
    uint64_t all = 0;
    for (int k = 0; k < 8; k++) all = all * 31 + stage[k];
    if (pics) stage_pictures(&x.f, pics);
    fx_end(&x);
    return all;
}

/* The accumulation's and the filter's SIMD paths give the scalar path's bits: whole GI
 * frames with the scalar, AVX2 and AVX-512 raster contexts (the
 * accumulation follows the context's path), on the Cornell box and Sibenik. */
static void simd_frame(const char *path, rs_simd simd, uint64_t *h_acc, uint64_t *h_final)
{
    fx x;
    pf_error err;
    if (!tu_load_or_skip(&x.scene, path)) {
        *h_acc = *h_final = 0;
        return;
    }
    pf_camera cam;
    if (x.scene.camera_count) cam = x.scene.cameras[0];
    else {
        assert_int_equal(pf_camera_look_at(&cam, pf_v3(-18, -11, 0), pf_v3(10, -8, 0), pf_radians(70), &err), PF_OK);
        pf_light L = {.type = PF_LIGHT_POINT, .position = {0, 0, 0}, .color = {1, 1, 1}, .intensity = 50};
        assert_int_equal(pf_scene_add_light(&x.scene, &L, &err), PF_OK);
    }
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 96;
    fx_begin(&x, 2, 83, 61, &cam, &io); /* tile widths not multiples of 8: SIMD and scalar tails */
    rs_context_set_simd(x.rs, simd);
    gi_frame_render_raster(&x.f);
    *h_acc = pf_imageio_hash(x.f.ind.split_e, 3 * 83 * 61) ^ pf_imageio_hash(x.f.ind.filtered, 3 * 83 * 61) * 3;
    *h_final = pf_imageio_hash(x.f.final, 3 * 83 * 61);
    fx_end(&x);
}

static void test_accumulate_simd_identical(void **state)
{
    (void)state;
    const char *paths[2] = {CORNELL, SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"};
    for (int p = 0; p < 2; p++) {
        uint64_t a0, f0;
        simd_frame(paths[p], RS_SIMD_SCALAR, &a0, &f0);
        if (a0 == 0 && f0 == 0) continue; /* skipped */
        const rs_simd simds[2] = {RS_SIMD_AVX2, RS_SIMD_AVX512};
        for (int k = 0; k < 2; k++) {
            if (pf_isa_detect() < (simds[k] == RS_SIMD_AVX2 ? PF_ISA_AVX2 : PF_ISA_AVX512)) continue;
            uint64_t a, fh;
            simd_frame(paths[p], simds[k], &a, &fh);
            if (a != a0 || fh != f0)
                fail_msg("%s: %s accumulation or filter differs from scalar", paths[p], rs_simd_name(simds[k]));
        }
    }
}

/* The rasterizer's SIMD paths, and whether this CPU runs each. */
static const rs_simd k_simds[3] = {RS_SIMD_SCALAR, RS_SIMD_AVX2, RS_SIMD_AVX512};
static int simd_runs(rs_simd s)
{
    return s == RS_SIMD_SCALAR || pf_isa_detect() >= (s == RS_SIMD_AVX2 ? PF_ISA_AVX2 : PF_ISA_AVX512);
}

static void load_cornell(fx *x)
{
    pf_error err;
    memset(x, 0, sizeof *x);
    if (pf_gltf_load(&x->scene, CORNELL, NULL, &err) != PF_OK) fail_msg("%s", err.message);
}

/* A method that breaks the frame's contract: NaN, zero and non-unit
 * normals, NaN and negative intensities, a non-finite position, more VPLs
 * than the budget. The frame must make those entries inert (gi__vpl_check):
 * every path (scalar, AVX2, AVX-512 accumulation) renders without reading
 * out of bounds and gives a finite image. */
static pf_result bad_create(void **state, const gi_params *p, pf_error *err)
{
    return gi_method_ir.create(state, p, err);
}
static void bad_destroy(void *state) { gi_method_ir.destroy(state); }
static pf_result bad_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    pf_result r = gi_method_ir.update(state, in, out, err);
    if (r != PF_OK) return r;
    uint32_t n = out->count;
    assert_true(n >= 8 && gi_vpl_set_reserve(out, n + 40, err) == PF_OK);
    for (uint32_t i = 0; i < 40; i++) { /* past the budget: dropped */
        out->v[n + i] = out->v[i];
        out->v[n + i].intensity = pf_v3(1e6f, 1e6f, 1e6f);
    }
    out->count = n + 40;
    out->v[0].nrm = pf_v3(NAN, 0, 1);
    out->v[1].nrm = pf_v3(0, 0, 0);
    out->v[2].nrm = pf_v3(0, 3, 0);
    out->v[3].intensity = pf_v3(NAN, 1, 1);
    out->v[4].intensity = pf_v3(-1, 1, 1);
    out->v[5].pos = pf_v3(INFINITY, 0, 0);
    return PF_OK;
}

static void test_bad_vpls_are_inert(void **state)
{
    (void)state;
    static const gi_vpl_method bad = {.name = "bad", .paper = "test", .create = bad_create, .update = bad_update,
                                      .destroy = bad_destroy};
    for (int k = 0; k < 3; k++) {
        if (!simd_runs(k_simds[k])) continue;
        fx x;
        load_cornell(&x);
        gi_indirect_options io;
        memset(&io, 0, sizeof io);
        io.method = &bad;
        io.vpls = 64;
        io.clamp = -1.0f;
        tu_fx_begin(&x, 2, k_simds[k], 40, 30, &x.scene.cameras[0], &io, 1);
        gi_frame_render_raster(&x.f);
        const gi_vpl_set *vs = &x.f.ind.vpls;
        assert_int_equal(vs->count, 64);
        for (uint32_t i = 0; i < vs->count; i++) {
            const gi_vpl *v = &vs->v[i];
            assert_true(isfinite(v->pos.x) && isfinite(v->nrm.x) && isfinite(v->intensity.x));
            assert_true(v->intensity.x >= 0.0f && fabsf(pf_v3_length(v->nrm) - 1.0f) < 1e-3f);
        }
        for (uint32_t i = 0; i < 6; i++) assert_true(vs->v[i].intensity.x == 0.0f); /* made inert */
        double sum = 0.0;
        for (size_t i = 0; i < (size_t)40 * 30 * 3; i++) {
            assert_true(isfinite(x.f.final[i]));
            sum += x.f.final[i];
        }
        assert_true(sum > 0.0); /* the valid VPLs still light the box */
        fx_end(&x);
    }
}

/* Golden: 80x60 Cornell box GI frame (64 VPLs, 4x4 tiles, paraboloid maps,
 * scalar raster, Embree pinned to sse2): vpls, maps, split, accumulated,
 * combined, filtered, direct, final. */
static const uint64_t k_golden[8] = {
    0x7002257d27805b4aull, 0x03462f940a9b3c38ull, 0x108a925dc7f00a3aull, 0x1d7dcf36712bb113ull,
    0x5939617ac6a69da7ull, 0x62f7c11384d3e7ddull, 0x780c259c74ba52c4ull, 0xfbf0a9c7dad5af97ull,
};

/* A pixel exactly behind a VPL on its axis (here background pixels, which
 * the split buffers hold at the origin, below VPLs at (0, y, 0) facing +y):
 * the pixel's paraboloid coordinates are 0/0 = NaN. The AVX2 accumulation gathers a texel for every lane before
 * masking, and a NaN index once read ~4 GiB before the atlas (SIGSEGV). Every
 * path must render it, give a finite image and the scalar path's bits. */
static pf_result origin_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    pf_result r = gi_method_ir.update(state, in, out, err);
    if (r != PF_OK) return r;
    /* VPLs above the origin facing up: background pixels (at the origin) lie
     * on their axis behind them; the ceiling above is lit by them */
    for (uint32_t i = 0; i < out->count && i < 4; i++) {
        out->v[i].pos = pf_v3(0, 0.1f + 0.1f * (float)i, 0);
        out->v[i].nrm = pf_v3(0, 1, 0);
    }
    return PF_OK;
}

static void test_vpl_at_pixel_position(void **state)
{
    (void)state;
    static const gi_vpl_method origin = {.name = "origin", .paper = "test", .create = bad_create,
                                         .update = origin_update, .destroy = bad_destroy};
    uint64_t h0 = 0;
    for (int k = 0; k < 3; k++) {
        if (!simd_runs(k_simds[k])) continue;
        fx x;
        load_cornell(&x);
        pf_error err;
        pf_camera cam; /* from outside the box, so that background (origin) pixels exist */
        assert_int_equal(pf_camera_look_at(&cam, pf_v3(0.1f, 0.35f, -0.9f), pf_v3(0.3f, 0.3f, 0.3f), pf_radians(70), &err),
                         PF_OK);
        gi_indirect_options io;
        memset(&io, 0, sizeof io);
        io.method = &origin;
        io.vpls = 64;
        io.no_interleave = 1; /* every pixel sees every VPL */
        tu_fx_begin(&x, 2, k_simds[k], 40, 30, &cam, &io, 1);
        gi_frame_render_raster(&x.f);
        uint32_t background = 0;
        for (uint32_t i = 0; i < 40 * 30; i++) background += x.f.gbuf.prim[i] == RS_GBUFFER_EMPTY;
        assert_true(background > 0);
        for (size_t i = 0; i < (size_t)40 * 30 * 3; i++) assert_true(isfinite(x.f.final[i]) && x.f.final[i] >= 0.0f);
        uint64_t h = pf_imageio_hash(x.f.final, 40 * 30 * 3);
        if (k == 0) h0 = h;
        else assert_true(h == h0);
        fx_end(&x);
    }
}

static void test_frame_threads_and_golden(void **state)
{
    (void)state;
    uint64_t s1[8], s2[8];
    tu_golden_picture pics[8];
    uint64_t h1 = gi_hashes(1, s1, pics), h2 = gi_hashes(2, s2, NULL);
    for (int k = 0; k < 8; k++) assert_true(s1[k] == s2[k]);
    assert_true(h1 == h2);
    /* every stage checked (and its pictures written on a mismatch) before failing */
    static char msg[8][8192];
    int failed = 0;
    for (int k = 0; k < 8; k++) {
        char name[64];
        snprintf(name, sizeof name, "vpl-cornell-%s", k_stage_names[k]);
        if (tu_golden_verify(SOFTGI_GOLDEN_DIR, SOFTGI_GOLDEN_FAILURES, name, s1[k], k_golden[k], &pics[k], msg[k],
                             sizeof msg[k])) {
            print_error("stage %d (%s): %s\n", k, k_stage_names[k], msg[k]);
            failed++;
        }
        tu_golden_picture_free(&pics[k]);
    }
    if (failed) fail_msg("%d of the 8 stage goldens failed (above)", failed);
}

/* Instant Radiosity against the path-traced reference (issue 4's
 * convergence check): the Cornell box, indirect light only, every pixel
 * seeing every VPL through Embree rays, 16384 VPLs, no clamp, no filter,
 * against `softgi reference` with the same 3 bounces. Deviation from the
 * issue: the point light is moved from 1 cm under the ceiling to the middle
 * of the box (0.278, 0.35, 0.28): under the ceiling it makes the reference
 * converge so slowly (fireflies from paths that pass next to the light;
 * 2048 and 16384 spp still differ by 25% per pixel) that no test-suite
 * budget separates method error from reference noise. Pixels whose 3x3
 * neighbourhood sees more than one triangle are left out: the reference
 * averages over the pixel's area, the G-buffer samples its centre. */
/* Whether pixel i (not on the image border) and its 3x3 neighbourhood see
 * one surface: the same material in the same plane (the Cornell walls are
 * quads of two triangles). The reference averages each pixel over its area
 * and the frame samples its centre, so pixels that span surfaces are left
 * out of comparisons. */
static int interior_pixel(const fx *x, int W, size_t i)
{
    uint32_t p = x->f.gbuf.prim[i];
    if (p == RS_GBUFFER_EMPTY) return 0;
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            size_t j = i + (size_t)(dy * W + dx);
            uint32_t q = x->f.gbuf.prim[j];
            if (q == p) continue;
            if (q == RS_GBUFFER_EMPTY || x->scene.tri_material[q] != x->scene.tri_material[p] ||
                !(fabsf(x->f.gbuf.nrm_x[i] - x->f.gbuf.nrm_x[j]) < 1e-3f) ||
                !(fabsf(x->f.gbuf.nrm_y[i] - x->f.gbuf.nrm_y[j]) < 1e-3f) ||
                !(fabsf(x->f.gbuf.nrm_z[i] - x->f.gbuf.nrm_z[j]) < 1e-3f))
                return 0;
        }
    return 1;
}

static void test_ir_converges_to_reference(void **state)
{
    (void)state;
    enum { W = 48, H = 36 };
    fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    x.scene.lights[0].position = pf_v3(0.278f, 0.35f, 0.28f);
    x.scene.lights[0].intensity = 0.3f;
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.vpls = 16384;
    io.clamp = 0.0f;
    io.filter = GI_FILTER_NONE;
    fx_begin(&x, 2, W, H, &x.scene.cameras[0], &io);
    x.f.show_direct = 0; /* indirect only */
    gi_frame_render_raster(&x.f);
    static float ref[3 * W * H];
    gi_reference_options ro;
    memset(&ro, 0, sizeof ro);
    ro.spp = 32768; /* its noise dominates the error: 4096 spp gives 4.8%, 16384 gives 2.8% */
    ro.bounces = 3;
    ro.indirect_only = 1;
    assert_int_equal(gi_reference_render(ref, &x.scene, x.rt, x.jobs, &x.scene.cameras[0], W, H, &ro, &err), PF_OK);
    double sum = 0.0, sum_ir = 0.0, sum_ref = 0.0;
    int n = 0;
    for (int y = 1; y + 1 < H; y++)
        for (int xx = 1; xx + 1 < W; xx++) {
            size_t i = (size_t)y * W + (size_t)xx;
            if (!interior_pixel(&x, W, i)) continue;
            double a = 0.2126 * x.f.final[3 * i] + 0.7152 * x.f.final[3 * i + 1] + 0.0722 * x.f.final[3 * i + 2];
            double b = 0.2126 * ref[3 * i] + 0.7152 * ref[3 * i + 1] + 0.0722 * ref[3 * i + 2];
            if (!(b > 1e-5)) continue;
            sum += fabs(a - b) / b;
            sum_ir += a, sum_ref += b;
            n++;
        }
    double mre = sum / n;
    print_message("IR vs reference: mean relative error %.4f over %d pixels, ratio of means %.4f\n", mre, n,
                  sum_ir / sum_ref);
    assert_true(n > W * H / 3);
    assert_true(mre < 0.03);
    assert_true(fabs(sum_ir / sum_ref - 1.0) < 0.02);
    fx_end(&x);
}

/* The clamped reference (Hedman 2017 Fig. 8's "clamped path tracing"):
 * Instant Radiosity with a bounded geometry term b converges to the
 * reference with the same bound on the x1 - x2 segment, not to the
 * unclamped one. Cornell box, light 18 cm from every
 * surface, 16384 VPLs seen through Embree rays, no interleaving, no filter;
 * means over the pixels that see one surface (interior_pixel). */
static void test_clamped_reference(void **state)
{
    (void)state;
    enum { W = 32, H = 24 };
    fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    x.scene.lights[0].position = pf_v3(0.278f, 0.35f, 0.15f);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.vpls = 16384;
    io.clamp = 20.0f; /* b = 20 / diagonal^2, a twentieth of the default: the bound reaches ~20 cm from the
                         corners, so pixels that see one surface feel it (the default's ~1 cm band is
                         mostly pixels that span a corner) */
    io.filter = GI_FILTER_NONE;
    fx_begin(&x, 2, W, H, &x.scene.cameras[0], &io);
    x.f.show_direct = 0;
    gi_frame_render_raster(&x.f);
    static float ref[2][3 * W * H];
    double mean[3] = {0, 0, 0};
    for (int k = 0; k < 2; k++) {
        gi_reference_options ro;
        memset(&ro, 0, sizeof ro);
        ro.spp = 2048;
        ro.bounces = 3;
        ro.indirect_only = 1;
        ro.clamp = k ? 20.0f : 0.0f; /* the frame's --clamp 20 */
        assert_int_equal(gi_reference_render(ref[k], &x.scene, x.rt, x.jobs, &x.scene.cameras[0], W, H, &ro, &err),
                         PF_OK);
    }
    for (int y = 1; y + 1 < H; y++)
        for (int xx = 1; xx + 1 < W; xx++) {
            size_t i = (size_t)y * W + (size_t)xx;
            if (!interior_pixel(&x, W, i)) continue;
            for (int c = 0; c < 3; c++)
                mean[0] += x.f.final[3 * i + c], mean[1] += ref[0][3 * i + c], mean[2] += ref[1][3 * i + c];
        }
    print_message("clamped IR / clamped reference %.4f, / unclamped reference %.4f (clamped / unclamped "
                  "reference %.4f)\n",
                  mean[0] / mean[2], mean[0] / mean[1], mean[2] / mean[1]);
    assert_true(fabs(mean[0] / mean[2] - 1.0) < 0.01);
    assert_true(mean[2] / mean[1] < 0.99); /* the bound takes light away: not vacuous */
    fx_end(&x);
}

/* One albedo rule for VPLs (gi_vpl.h, GI_VPL_ALBEDO_LOD): a light path's
 * VPL on a mipmapped 2x2 checker takes the blurred texture (mip 4 clamps to
 * the 1x1 top level, the checker's average), not the texel under it. */
static void test_vpl_albedo_rule(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, SOFTGI_TEST_DATA "/gltf/texture_datauri.gltf", NULL, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt = NULL;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    /* the plane z = 3 holds material 3, "linear_mips" (tools/make_test_gltf.py) */
    pf_ray ray = {pf_v3(0.2f, 0.3f, 3.5f), 0.0f, pf_v3(0, 0, -1), INFINITY};
    pf_hit h = pf_rt_intersect1(rt, ray);
    assert_true(h.prim != PF_RT_MISS);
    pf_surface sf;
    pf_rt_surface(rt, &h, 0.0f, &sf);
    assert_int_equal(s.materials[sf.material].base_color_texture >= 0, 1);
    float texel[4], mean[4];
    pf_material_sample(&s, sf.material, sf.uv, 0.0f, texel);
    pf_material_sample(&s, sf.material, sf.uv, 16.0f, mean);
    assert_true(fabsf(texel[0] - mean[0]) > 0.1f); /* not vacuous: the texel is not the average */
    gi_vpl v;
    pf_vec3 albedo;
    assert_true(gi_lightpath_hit(rt, ray, pf_v3(1, 1, 1), &v, &albedo));
    assert_float_equal(albedo.x, mean[0], 1e-6f);
    assert_float_equal(albedo.y, mean[1], 1e-6f);
    assert_float_equal(albedo.z, mean[2], 1e-6f);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_vpl_raytrace),  cmocka_unit_test(test_one_vpl_paraboloid),
        cmocka_unit_test(test_clamp_bounds),      cmocka_unit_test(test_split_combine_exact),
        cmocka_unit_test(test_box_filter),        cmocka_unit_test(test_box_filter_grazing),
        cmocka_unit_test(test_ir_static),
        cmocka_unit_test(test_frame_threads_and_golden),   cmocka_unit_test(test_accumulate_simd_identical),
        cmocka_unit_test(test_ir_converges_to_reference), cmocka_unit_test(test_clamped_reference),
        cmocka_unit_test(test_vpl_albedo_rule),
        cmocka_unit_test(test_bad_vpls_are_inert),
        cmocka_unit_test(test_vpl_at_pixel_position),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
