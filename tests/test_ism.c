/* test_ism: imperfect shadow maps (gi_ism; Ritschel 2008, Barak 2013 Sec. 5).
 * - pull-push: a constant map's holes are filled with the constant exactly;
 *   a plane's depth map with 70% of its texels removed is filled within a
 *   stated error, kept texels and outside texels untouched, an empty map
 *   stays empty;
 * - the point budget: a frame generates P points up to the randomised
 *   rounding (|generated - P| within 5 sigma), every map is rebuilt;
 * - ISM vs ray-traced visibility: the fraction of (receiver, VPL) pairs
 *   whose visibility agrees, printed and bounded, on the Cornell box and
 *   (when the shared scenes are present) Sibenik, next to the exact
 *   paraboloid maps' agreement;
 * - the same ISM frame is byte-identical for 1 and 2 threads, and with the
 *   scalar and the SIMD accumulation;
 * - the binned splat (records sorted by map, plain mins per map) gives the
 *   atomic splat's maps byte for byte, on the Cornell box and on Sibenik
 *   (several batches of records), with 1 and 2 threads;
 * - bad option values are errors (API and CLI).
 * Timing is not a test's job: `softgi bench frame --visibility ism` times
 * the ISM frame stage by stage (docs/perf.md). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <unistd.h>

#include "gi_frame.h"
#include "gi_ism.h"
#include "pf_gltf.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SIBENIK SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"

typedef tu_fx fx;

static void fx_begin(fx *x, uint32_t threads, rs_simd simd, uint32_t w, uint32_t h, const pf_camera *cam,
                     const gi_indirect_options *io)
{
    tu_fx_begin(x, threads, simd, w, h, cam, io, 1);
}

static void fx_end(fx *x) { tu_fx_end(x); }

/* Sibenik as `softgi bench frame` lights and views it: one point light in
 * the nave. */
static void sibenik_setup(pf_scene *s, pf_camera *cam)
{
    pf_error err;
    s->light_count = 0;
    pf_light l;
    memset(&l, 0, sizeof l);
    l.type = PF_LIGHT_POINT;
    l.position = pf_v3(0, 0, 0);
    l.color = pf_v3(1, 1, 1);
    l.intensity = 50.0f;
    assert_int_equal(pf_scene_add_light(s, &l, &err), PF_OK);
    assert_int_equal(pf_camera_look_at(cam, pf_v3(-18, -11, 0), pf_v3(10, -8, 0), pf_radians(70), &err), PF_OK);
}

/* ------------------------------------------------------------------ pull-push */

static void test_pull_push_constant(void **state)
{
    (void)state;
    enum { R = 32 };
    static uint16_t map[R * R];
    float *scratch = calloc(gi_ism_pull_push_scratch_floats(R), sizeof(float));
    assert_non_null(scratch);
    /* an empty map stays empty */
    for (uint32_t j = 0; j < R; j++)
        for (uint32_t i = 0; i < R; i++) map[j * R + i] = rs_para_texel_inside(R, i, j) ? RS_PARA_EMPTY : RS_PARA_OUTSIDE;
    assert_int_equal(gi_ism_pull_push(map, R, scratch), 0);
    for (uint32_t k = 0; k < R * R; k++) assert_true(map[k] == RS_PARA_EMPTY || map[k] == RS_PARA_OUTSIDE);
    /* one code anywhere: every hole takes it (averages of a constant) */
    uint32_t holes = 0;
    for (uint32_t k = 0; k < R * R; k++) holes += map[k] == RS_PARA_EMPTY;
    map[(R / 2) * R + 3] = 1234;
    assert_int_equal(gi_ism_pull_push(map, R, scratch), holes - 1);
    for (uint32_t j = 0; j < R; j++)
        for (uint32_t i = 0; i < R; i++)
            assert_int_equal(map[j * R + i], rs_para_texel_inside(R, i, j) ? 1234 : RS_PARA_OUTSIDE);
    free(scratch);
}

/* The plane z = 1 in the VPL frame: distance 1 / d.z along d, so the
 * distance grows as (1 + rho^2) / (1 - rho^2) with the map radius rho and
 * changes by a relative 2 rho (1 / (1 - rho^2) + 1 / (1 + rho^2)) / (R / 2)
 * per texel: 1.3% at rho = 0.25, 6.7% at 0.5, 17% at 0.8 for R = 64.
 * 70% of the inside texels are removed at random, pull-push fills them, and
 * the filled distances are compared with the plane's per ring of rho. The
 * bounds hold the measured errors (README) with margin: a hole's value is an
 * average over about one to two texels around it, so its error is of the
 * order of one to two texels' change. */
static void test_pull_push_plane(void **state)
{
    (void)state;
    enum { R = 64 };
    const float range = 100.0f, S = RS_PARA_CODES / range;
    static uint16_t map[R * R], truth[R * R];
    float *scratch = calloc(gi_ism_pull_push_scratch_floats(R), sizeof(float));
    assert_non_null(scratch);
    uint32_t removed = 0, inside = 0;
    for (uint32_t j = 0; j < R; j++)
        for (uint32_t i = 0; i < R; i++) {
            uint32_t k = j * R + i;
            if (!rs_para_texel_inside(R, i, j)) {
                map[k] = truth[k] = RS_PARA_OUTSIDE;
                continue;
            }
            pf_vec3 d = rs_para_uv_to_dir(rs_para_texel_uv(R, i, j));
            float t = 1.0f / d.z;
            truth[k] = t * S < (float)RS_PARA_MAX_CODE ? (uint16_t)(t * S) : RS_PARA_MAX_CODE;
            inside++;
            int drop = pf_hash32(k * 2654435761u + 17u) % 100u < 70u;
            map[k] = drop ? RS_PARA_EMPTY : truth[k];
            removed += (uint32_t)drop;
        }
    assert_true(removed > inside * 6 / 10 && removed < inside * 8 / 10);
    assert_int_equal(gi_ism_pull_push(map, R, scratch), removed);
    /* rings: rho < 0.25, < 0.5, < 0.8, the rest */
    double sum[4] = {0, 0, 0, 0}, mx[4] = {0, 0, 0, 0};
    uint32_t n[4] = {0, 0, 0, 0};
    for (uint32_t j = 0; j < R; j++)
        for (uint32_t i = 0; i < R; i++) {
            uint32_t k = j * R + i;
            if (truth[k] == RS_PARA_OUTSIDE) {
                assert_int_equal(map[k], RS_PARA_OUTSIDE);
                continue;
            }
            assert_true(map[k] <= RS_PARA_MAX_CODE); /* every hole filled */
            if (map[k] == truth[k]) continue;         /* kept (or filled exactly) */
            double want = ((double)truth[k] + 0.5) / S, got = ((double)map[k] + 0.5) / S;
            double e = fabs(got - want) / want;
            pf_vec2 uv = rs_para_texel_uv(R, i, j);
            float rho = sqrtf(uv.x * uv.x + uv.y * uv.y);
            int ring = rho < 0.25f ? 0 : rho < 0.5f ? 1 : rho < 0.8f ? 2 : 3;
            sum[ring] += e, n[ring]++;
            mx[ring] = e > mx[ring] ? e : mx[ring];
        }
    static const char *const names[4] = {"rho < 0.25", "0.25 <= rho < 0.5", "0.5 <= rho < 0.8", "rho >= 0.8"};
    for (int r = 0; r < 4; r++)
        print_message("pull-push, plane, 70%% removed (R = %d), %-17s: %4u filled texels differ, relative distance "
                      "error mean %.4f max %.4f\n",
                      R, names[r], n[r], n[r] ? sum[r] / n[r] : 0.0, mx[r]);
    const double mean_bound[4] = {0.015, 0.03, 0.08, 0.8}, max_bound[4] = {0.06, 0.10, 0.40, 6.0};
    for (int r = 0; r < 4; r++) {
        assert_true(n[r] > 0);
        assert_true(sum[r] / n[r] < mean_bound[r]);
        assert_true(mx[r] < max_bound[r]);
    }
    free(scratch);
}

/* ------------------------------------------------------------------ frames */

static void cornell_frame(fx *x, uint32_t threads, rs_simd simd, const gi_indirect_options *io, uint32_t W,
                          uint32_t H)
{
    pf_error err;
    assert_int_equal(pf_gltf_load(&x->scene, CORNELL, NULL, &err), PF_OK);
    fx_begin(x, threads, simd, W, H, &x->scene.cameras[0], io);
}

static gi_indirect_options ism_options(void)
{
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.visibility_ism = 1;
    io.vpls = 256;
    io.clamp = -1.0f;
    return io;
}

/* Every map is rebuilt every frame; a frame generates P points up to the
 * randomised rounding: each triangle adds a Bernoulli(frac) to floor(P
 * A_i / A), so |generated - P| <= 5 sqrt(sum frac (1 - frac)) <= 5 sqrt(T / 4). */
static void test_point_budget(void **state)
{
    (void)state;
    fx x;
    gi_indirect_options io = ism_options();
    io.ism.points = 200000;
    cornell_frame(&x, 2, RS_SIMD_SCALAR, &io, 32, 24);
    gi_frame *f = &x.f;
    gi_frame_render_raster(f);
    uint32_t N = f->ind.vpls.count;
    assert_true(N > 100);
    assert_int_equal(f->ind.maps_rendered, N);
    gi_ism_stats st;
    memset(&st, 0, sizeof st);
    gi_ism_render(f->ind.ism, f->ind.atlas, f->jobs, f->ind.frames, N, f->ind.range, 7, &st);
    double sigma5 = 5.0 * sqrt(x.scene.tri_count / 4.0);
    print_message("points: %llu generated (P = 200000, T = %u triangles), %llu in front of their VPL, %llu of %llu "
                  "texels filled by pull-push\n",
                  (unsigned long long)st.points, x.scene.tri_count, (unsigned long long)st.splatted,
                  (unsigned long long)st.holes_filled, (unsigned long long)st.texels);
    assert_true(fabs((double)st.points - 200000.0) <= sigma5 + 1.0);
    assert_true(st.splatted > st.points / 4 && st.splatted < st.points);
    assert_true(st.holes_filled < st.texels);
    /* no hole is left in a map that got any point */
    const size_t map = (size_t)f->ind.opt.para_res * f->ind.opt.para_res;
    for (size_t k = 0; k < map * N; k++) assert_true(f->ind.atlas[k] != RS_PARA_EMPTY);
    fx_end(&x);
}

/* Fraction of (receiver, VPL) pairs with G > 0 whose map visibility agrees
 * with an Embree shadow ray (the frame's own ray, gi__accumulate_row). */
static double agreement(gi_frame *f, uint64_t *pairs, double *lit_ray, double *lit_map)
{
    gi_indirect *ind = &f->ind;
    const uint32_t R = ind->opt.para_res;
    const size_t map = (size_t)R * R;
    uint64_t agree = 0, n = 0, vr = 0, vm = 0;
    for (size_t i = 0; i < (size_t)f->width * f->height; i++) {
        if (f->gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
        pf_vec3 pos = pf_v3(f->gbuf.pos_x[i], f->gbuf.pos_y[i], f->gbuf.pos_z[i]);
        pf_vec3 nrm = pf_v3(f->gbuf.nrm_x[i], f->gbuf.nrm_y[i], f->gbuf.nrm_z[i]);
        for (uint32_t vi = 0; vi < ind->vpls.count; vi++) {
            const gi_vpl *v = &ind->vpls.v[vi];
            pf_vec3 d = pf_v3_sub(v->pos, pos);
            float r = pf_v3_length(d);
            if (!(r > 0.0f)) continue;
            pf_vec3 w = pf_v3_scale(d, 1.0f / r);
            if (!(pf_v3_dot(nrm, w) > 0.0f) || !(-pf_v3_dot(v->nrm, w) > 0.0f)) continue;
            pf_ray ray = {pf_rt_offset_origin(pos, nrm, w), 0.0f, w, r * (1.0f - 1.0e-4f)};
            int ray_vis = !pf_rt_occluded1(f->rt, ray);
            int map_vis = rs_para_visible_scaled(ind->atlas + vi * map, R, ind->range, &ind->frames[vi], pos, NULL,
                                                 pf_v3_dot(nrm, w), ind->bias_scale);
            agree += (uint64_t)(ray_vis == map_vis);
            vr += (uint64_t)ray_vis, vm += (uint64_t)map_vis;
            n++;
        }
    }
    *pairs = n;
    *lit_ray = (double)vr / (double)n;
    *lit_map = (double)vm / (double)n;
    return (double)agree / (double)n;
}

/* ISM and exact-map agreement with ray-traced visibility on one scene:
 * min_ism bounds the ISMs' agreement. */
static void agreement_on(const char *name, pf_scene *scene_in, const pf_camera *cam, double min_exact,
                         double min_ism)
{
    double a[2];
    for (int ism = 0; ism < 2; ism++) {
        fx x;
        x.scene = *scene_in;
        gi_indirect_options io = ism_options();
        io.visibility_ism = ism;
        fx_begin(&x, 2, RS_SIMD_SCALAR, 64, 48, cam, &io);
        gi_frame_render_raster(&x.f);
        uint64_t n;
        double lr, lm;
        a[ism] = agreement(&x.f, &n, &lr, &lm);
        print_message("%s: %s (R = %u): visibility agrees with Embree rays for %.4f of %llu (receiver, VPL) pairs; "
                      "visible: rays %.4f, maps %.4f\n",
                      name, ism ? "ISM" : "exact paraboloid maps", x.f.ind.opt.para_res, a[ism],
                      (unsigned long long)n, lr, lm);
        tu_fx_end_frame(&x); /* the scene is the caller's */
    }
    assert_true(a[0] > min_exact); /* the exact maps */
    assert_true(a[1] > min_ism);   /* the ISMs */
    assert_true(a[1] <= a[0]);     /* imperfect: not better than exact */
}

static void test_agreement_cornell(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, CORNELL, NULL, &err), PF_OK);
    pf_camera cam = s.cameras[0];
    agreement_on("Cornell box", &s, &cam, 0.98, 0.93); /* measured 0.985, 0.952 */
    pf_scene_free(&s);
}

static void test_agreement_sibenik(void **state)
{
    (void)state;
    pf_scene s;
    if (!tu_load_or_skip(&s, SIBENIK)) return;
    pf_camera cam;
    sibenik_setup(&s, &cam);
    agreement_on("Sibenik", &s, &cam, 0.92, 0.72); /* measured 0.935, 0.762 */
    pf_scene_free(&s);
}

/* The same ISM frame with 1 and 2 threads, and with the scalar and SIMD
 * accumulation: the same maps and the same image, byte for byte. A second
 * frame re-seeds the points: its maps differ. */
static void test_threads_deterministic(void **state)
{
    (void)state;
    enum { W = 80, H = 60 };
    static float img[3][3 * W * H];
    static uint16_t maps[3][256 * 64 * 64];
    const rs_simd simd[3] = {RS_SIMD_SCALAR, RS_SIMD_SCALAR, RS_SIMD_AVX2};
    const uint32_t threads[3] = {1, 2, 2};
    size_t bytes = 0;
    for (int run = 0; run < 3; run++) {
        fx x;
        gi_indirect_options io = ism_options();
        cornell_frame(&x, threads[run], simd[run], &io, W, H);
        gi_frame_render_raster(&x.f);
        assert_int_equal(x.f.ind.opt.para_res, 64);
        bytes = rs_para_atlas_bytes(64, x.f.ind.vpls.count);
        assert_true(bytes <= sizeof maps[run]);
        memcpy(maps[run], x.f.ind.atlas, bytes);
        memcpy(img[run], x.f.final, sizeof img[run]);
        if (run == 0) {
            gi_frame_render_raster(&x.f); /* frame 2: new points */
            assert_true(memcmp(maps[0], x.f.ind.atlas, bytes) != 0);
        }
        fx_end(&x);
    }
    assert_memory_equal(maps[0], maps[1], bytes);
    assert_memory_equal(img[0], img[1], sizeof img[0]);
    assert_memory_equal(img[1], img[2], sizeof img[1]); /* SIMD accumulation (if the CPU has AVX2) = scalar */
}

/* The binned splat against the atomic one: the maps of one frame, byte for
 * byte (min is order-free, so the two must agree exactly), with the
 * threads given; Sibenik's million points fill more than one batch. */
static void splat_paths_agree(pf_scene *scene, const pf_camera *cam, uint32_t threads, const char *name)
{
    enum { W = 96, H = 72 };
    uint16_t *maps[2] = {NULL, NULL};
    size_t bytes = 0;
    for (int atomic = 0; atomic < 2; atomic++) {
        fx x;
        x.scene = *scene;
        gi_indirect_options io = ism_options();
        io.ism.atomic_splat = atomic;
        tu_fx_desc d = {.threads = threads, .w = W, .h = H, .cam = cam, .io = &io, .indirect_only = 1};
        tu_fx_begin_with(&x, &d);
        gi_frame_render_raster(&x.f);
        bytes = rs_para_atlas_bytes(64, x.f.ind.vpls.count);
        maps[atomic] = malloc(bytes);
        assert_non_null(maps[atomic]);
        memcpy(maps[atomic], x.f.ind.atlas, bytes);
        tu_fx_end_frame(&x); /* the scene is the caller's */
    }
    size_t differ = 0;
    for (size_t i = 0; i < bytes / 2; i++) differ += maps[0][i] != maps[1][i];
    print_message("%s, %u threads: %zu of %zu texels differ between the binned and the atomic splat\n", name,
                  threads, differ, bytes / 2);
    assert_true(differ == 0);
    free(maps[0]), free(maps[1]);
}

static void test_binned_splat(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, CORNELL, NULL, &err), PF_OK);
    pf_camera cam = s.cameras[0];
    splat_paths_agree(&s, &cam, 1, "Cornell box");
    splat_paths_agree(&s, &cam, 2, "Cornell box");
    pf_scene_free(&s);
    if (!tu_load_or_skip(&s, SIBENIK)) return;
    sibenik_setup(&s, &cam);
    splat_paths_agree(&s, &cam, 2, "Sibenik");
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ options */

static void test_bad_options(void **state)
{
    (void)state;
    tu_fx x;
    pf_error err;
    tu_load(&x.scene, CORNELL);
    const pf_scene *s = &x.scene;
    const gi_ism_options bad[] = {
        {48, 0, 0, 0},   {4, 0, 0, 0},       {1024, 0, 0, 0},    {0, 10, 0, 0},  {0, 200000000, 0, 0},
        {0, 0, 0.5f, 0}, {0, 0, 100.0f, 0},  {0, 0, NAN, 0},     {0, 0, -2.0f, 0},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        gi_ism *m = (gi_ism *)&err; /* must be set to NULL */
        memset(&err, 0, sizeof err);
        assert_int_equal(gi_ism_create(&m, s, &bad[k], 2, &err), PF_ERR_ARGUMENT);
        assert_null(m);
        assert_true(strlen(err.message) > 0);
    }
    gi_ism *m = NULL;
    assert_int_equal(gi_ism_create(&m, s, NULL, 2, &err), PF_OK);
    assert_int_equal(gi_ism_resolution(m), GI_ISM_DEFAULT_RES);
    assert_int_equal(gi_ism_points(m), GI_ISM_DEFAULT_POINTS);
    gi_ism_destroy(m);
    pf_scene empty;
    memset(&empty, 0, sizeof empty);
    assert_int_equal(gi_ism_create(&m, &empty, NULL, 1, &err), PF_ERR_ARGUMENT);
    /* through the frame: the error reaches gi_frame_enable_indirect */
    tu_fx_begin(&x, 2, RS_SIMD_SCALAR, 16, 16, NULL, NULL, 0);
    gi_indirect_options io = ism_options();
    io.ism.resolution = 100;
    assert_int_equal(gi_frame_enable_indirect(&x.f, &io, 1, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "power of two"));
    tu_fx_end(&x);
    /* the CLI */
    tu_softgi_expect("render --visibility ism --ism-res 48 -q", 2, "--ism-res '48': expected a power of two");
    tu_softgi_expect("render --visibility ism --ism-res 1024 -q", 2, "--ism-res");
    tu_softgi_expect("render --visibility ism --ism-points 5 -q", 2, "--ism-points");
    tu_softgi_expect("render --visibility ism --ism-points 1e6 -q", 2, "--ism-points");
    tu_softgi_expect("render --visibility ism --ism-bias 0.5 -q", 2, "--ism-bias '0.5'");
    tu_softgi_expect("render --visibility ism --ism-bias nan -q", 2, "--ism-bias");
    tu_softgi_expect("render --ism-res 64 -q", 2, "need --visibility ism");
    tu_softgi_expect("bench frame --visibility ism --ism-res 48", 2, "--ism-res '48'");
    /* and good values render */
    char out[4096];
    snprintf(out, sizeof out, "render --visibility ism --ism-res 32 --ism-points 20000 --ism-bias 2.5 --size 32x24 "
                              "--indirect-only --vpls 16 -o /tmp/test_ism_%d.png",
             (int)getpid());
    tu_softgi_expect(out, 0, "visibility imperfect shadow maps");
    snprintf(out, sizeof out, "/tmp/test_ism_%d.png", (int)getpid());
    remove(out);
    snprintf(out, sizeof out, "/tmp/test_ism_%d.pfm", (int)getpid());
    remove(out);
    tu_softgi_expect("render --visibility raytrace --ism-bias 2 -q", 2, "need --visibility ism");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pull_push_constant), cmocka_unit_test(test_pull_push_plane),
        cmocka_unit_test(test_point_budget),       cmocka_unit_test(test_agreement_cornell),
        cmocka_unit_test(test_agreement_sibenik),  cmocka_unit_test(test_threads_deterministic),
        cmocka_unit_test(test_binned_splat),       cmocka_unit_test(test_bad_options),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
