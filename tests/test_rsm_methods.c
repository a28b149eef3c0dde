/* test_rsm_methods: reflective shadow maps (gi_rsm, gi_rsm_area), the
 * importance-map samplers (gi_importance: InvTM and Independent
 * Metropolis-Hastings) and the `invtm` and `tcas` VPL methods (Barak 2013
 * Sec. 4; Ritschel 2011), and `ssvp` on area lights.
 * - IM-H (Algorithm 1): for known 1D and 2D importance functions (the 2D one
 *   over two maps of different sizes) the chains' final samples follow f:
 *   chi-square goodness of fit at p-value 0.001 (the Halton proposals are
 *   fixed, so the test is deterministic);
 * - IM-H with M = 1: the samples are the uniform proposals and w = f / q;
 * - InvTM: samples follow a known discrete distribution (chi-square, p =
 *   0.001), with 3 and with 2 Halton numbers; zero-mass texels never drawn;
 * - RSM flux: the texels' reflected fluxes sum to the analytic power (point
 *   light inside a closed box, spot over a plane, directional light on a
 *   quad, an area light inside a closed box), and every texel's position
 *   lies on its texel's ray; the area lights' map is cosine-distributed and
 *   the same with 1 and 2 threads; with a point light and an emitter the
 *   point light's map is bit for bit the one made without area lights;
 * - each method: 30 frames (moving camera, a light that moves for a few
 *   frames) give bit-identical VPL sets with 1 and 2 threads, equal to the
 *   hashes recorded before area lights had RSMs (golden pictures of the VPLs
 *   in tests/data/golden/rsm-*.png, tu_golden.h), and a static frame moves
 *   no VPL; under a camera pan TCAS moves fewer than half as many VPLs as
 *   InvTM (Barak 2013's temporal coherence);
 * - each method converges to Instant Radiosity (1 bounce, many VPLs) on the
 *   Cornell box, indirect light only;
 * - area lights (gi_rsm_area.h): in a room lit only by an emissive quad,
 *   InvTM, TCAS and SSVP (first bounce) give indirect light within 3% of
 *   the path tracer's (image means), and bit-identical VPL sets with 1 and
 *   2 threads;
 * - bad parameters are errors.
 * Chi-square critical values: Wilson-Hilferty, chi2_{df, 1-a} ~ df (1 -
 * 2/(9 df) + z sqrt(2/(9 df)))^3 with z = 3.0902 (a = 0.001), within 0.5%
 * of the tables for df >= 15.
 * Timing is not a test's job: `softgi bench frame --method invtm` (or tcas)
 * times the VPL update (docs/perf.md). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "gi_importance.h"
#include "gi_reference.h"
#include "gi_rsm.h"
#include "gi_rsm_area.h"
#include "gi_vpl.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_isa.h"
#include "rs_raster.h"
#include "test_frame_fixture.h"
#include "test_util.h"
#include "tu_golden.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SIBENIK SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"

static double chi2_crit(int df)
{
    double k = 2.0 / (9.0 * df);
    double c = 1.0 - k + 3.0902 * sqrt(k);
    return df * c * c * c;
}

/* chi-square statistic of counts against probabilities (cells with p > 0);
 * *df = cells - 1. Fails if a zero-probability cell was drawn. */
static double chi2(const uint32_t *count, const double *p, uint32_t cells, uint32_t n, int *df)
{
    double x = 0.0;
    int used = 0;
    for (uint32_t i = 0; i < cells; i++) {
        if (p[i] == 0.0) {
            assert_int_equal(count[i], 0);
            continue;
        }
        double e = p[i] * n;
        x += (count[i] - e) * (count[i] - e) / e;
        used++;
    }
    *df = used - 1;
    return x;
}

/* ------------------------------------------------------------------ IM-H */

static void imh_check(const gi_sample_domain *d, const float *f, uint32_t N, uint32_t M, const char *what)
{
    uint32_t *count = calloc(d->total, sizeof *count);
    double *p = calloc(d->total, sizeof *p), sum = 0.0;
    for (uint32_t t = 0; t < d->total; t++) sum += f[t];
    for (uint32_t t = 0; t < d->total; t++) p[t] = f[t] / sum;
    double wsum = 0.0;
    for (uint32_t j = 0; j < N; j++) {
        double w;
        float fv;
        uint32_t t = gi_imh_chain(d, f, j, N, M, &w, &fv, NULL);
        assert_true(t < d->total);
        assert_true(fv == f[t]);
        count[t]++;
        wsum += w;
    }
    int df;
    double x = chi2(count, p, d->total, N, &df);
    print_message("IM-H %s: M=%u N=%u chi2 %.2f, df %d, critical (p=0.001) %.2f; mean w / sum f = %.4f\n", what, M,
                  N, x, df, chi2_crit(df), wsum / N / sum);
    assert_true(x < chi2_crit(df));
    /* w estimates the normaliser sum f (Sec. 4.3.1) */
    assert_true(fabs(wsum / N / sum - 1.0) < 0.01);
    free(count);
    free(p);
}

static void test_imh_1d(void **state)
{
    (void)state;
    enum { K = 16 };
    float f[K];
    for (int i = 0; i < K; i++) f[i] = 1.0f + (float)i;
    uint32_t first = 0, rows = 1, cols = K;
    gi_sample_domain d = {1, &first, &rows, &cols, K};
    imh_check(&d, f, 20000, 16, "1D f(i) = 1 + i");
    imh_check(&d, f, 20000, 8, "1D f(i) = 1 + i");
}

static void test_imh_2d(void **state)
{
    (void)state;
    /* one 8 x 8 map, f(x, y) = 1 + x + 2 y */
    float f[64];
    for (int y = 0; y < 8; y++)
        for (int x = 0; x < 8; x++) f[y * 8 + x] = 1.0f + (float)x + 2.0f * (float)y;
    uint32_t first = 0, rows = 8, cols = 8;
    gi_sample_domain d = {1, &first, &rows, &cols, 64};
    imh_check(&d, f, 20000, 16, "2D f(x,y) = 1 + x + 2y");
    /* two maps of different sizes (2 x 2 and 4 x 4): the target stays
     * proportional to f although their texels have different proposal
     * probabilities */
    float g[20];
    for (int t = 0; t < 20; t++) g[t] = 1.0f + (float)(t % 5);
    uint32_t firsts[2] = {0, 4}, rs[2] = {2, 4}, cs[2] = {2, 4};
    gi_sample_domain d2 = {2, firsts, rs, cs, 20};
    imh_check(&d2, g, 20000, 16, "two maps, f = 1 + t mod 5");
}

/* M = 1: the chain is its initial proposal, uniform over the unit cube, and
 * w = f(v) / q(v) (the paper's "w = f" per unit proposal volume). */
static void test_imh_m1_uniform(void **state)
{
    (void)state;
    float g[20];
    for (int t = 0; t < 20; t++) g[t] = 1.0f + (float)(t % 5);
    uint32_t firsts[2] = {0, 4}, rs[2] = {2, 4}, cs[2] = {2, 4};
    gi_sample_domain d = {2, firsts, rs, cs, 20};
    enum { N = 16000 };
    uint32_t count[20] = {0};
    double p[20];
    for (int t = 0; t < 20; t++) p[t] = t < 4 ? 1.0 / 8.0 : 1.0 / 32.0; /* q: half the mass per map */
    for (uint32_t j = 0; j < N; j++) {
        double w, q;
        float fv;
        double g0 = -1.0, wm, g0m;
        uint32_t t = gi_imh_chain(&d, g, j, N, 1, &w, &fv, &g0);
        uint32_t h = gi_imh_index(j, 0, N, 1);
        uint32_t t0 = gi_domain_texel(&d, gi_halton(h, 2), gi_halton(h, 3), gi_halton(h, 5), &q);
        assert_int_equal(t, t0);
        assert_true(w == (double)g[t] / q);
        assert_true(g0 == w); /* M-H-Single's weight is the initial sample's g: for M = 1 the same */
        /* longer chains: g0 is still the initial proposal's g, w the mean of all M */
        gi_imh_chain(&d, g, j, N, 4, &wm, &fv, &g0m);
        h = gi_imh_index(j, 0, N, 4);
        t0 = gi_domain_texel(&d, gi_halton(h, 2), gi_halton(h, 3), gi_halton(h, 5), &q);
        assert_true(g0m == (double)g[t0] / q);
        count[t]++;
    }
    int df;
    double x = chi2(count, p, 20, N, &df);
    print_message("IM-H M=1: chi2 against the uniform proposal %.2f (df %d, critical %.2f)\n", x, df, chi2_crit(df));
    assert_true(x < chi2_crit(df));
}

/* ----------------------------------------------------------------- InvTM */

static void test_invtm_distribution(void **state)
{
    (void)state;
    /* three maps (1 x 6, 3 x 5, 4 x 4), zero mass on every 4th texel */
    enum { T = 6 + 15 + 16 };
    uint32_t firsts[3] = {0, 6, 21}, rs[3] = {1, 3, 4}, cs[3] = {6, 5, 4};
    gi_sample_domain d = {3, firsts, rs, cs, T};
    float f[T];
    double p[T], sum = 0.0;
    for (int t = 0; t < T; t++) sum += f[t] = t % 4 == 0 ? 0.0f : 1.0f + (float)(t % 7);
    for (int t = 0; t < T; t++) p[t] = f[t] / sum;
    gi_invtm_cdf c;
    memset(&c, 0, sizeof c);
    pf_error err;
    assert_int_equal(gi_invtm_build(&c, &d, f, NULL, &err), PF_OK);
    assert_true(fabs(c.total - sum) < 1e-9);
    for (int dims = 2; dims <= 3; dims++) {
        enum { N = 20000 };
        uint32_t count[T] = {0};
        for (uint32_t i = 0; i < N; i++) {
            uint32_t t = gi_invtm_sample(&c, &d, dims, gi_halton(i + 1, 2), gi_halton(i + 1, 3), gi_halton(i + 1, 5));
            assert_true(t < T);
            count[t]++;
        }
        int df;
        double x = chi2(count, p, T, N, &df);
        print_message("InvTM, %d numbers: chi2 %.2f (df %d, critical %.2f)\n", dims, x, df, chi2_crit(df));
        assert_true(x < chi2_crit(df));
    }
    /* the edges of [0, 1): the first and the last texel with mass */
    assert_int_equal(gi_invtm_sample(&c, &d, 3, 0.0, 0.0, 0.0), 1);
    assert_int_equal(gi_invtm_sample(&c, &d, 3, nextafter(1.0, 0.0), nextafter(1.0, 0.0), nextafter(1.0, 0.0)), T - 2);
    assert_int_equal(gi_invtm_sample(&c, &d, 2, nextafter(1.0, 0.0), nextafter(1.0, 0.0), 0.0), T - 2);
    gi_invtm_free(&c);
}

/* ------------------------------------------------------------- RSM flux */

typedef struct rsm_fx {
    pf_scene scene;
    pf_jobs *jobs;
    gi_rsm_set set;
} rsm_fx;

static void rsm_run(rsm_fx *x, uint32_t size, uint32_t threads)
{
    pf_error err;
    assert_int_equal(pf_scene_validate(&x->scene, &err), PF_OK);
    x->jobs = pf_jobs_create(threads);
    gi_rsm_set_init(&x->set, size);
    assert_int_equal(gi_rsm_set_update(&x->set, &x->scene, NULL, NULL, x->jobs, &err), PF_OK);
}

static void rsm_end(rsm_fx *x)
{
    gi_rsm_set_free(&x->set);
    pf_jobs_destroy(x->jobs);
    pf_scene_free(&x->scene);
}

static pf_vec3 rsm_flux_sum(const gi_rsm_set *s, uint32_t *valid)
{
    double r = 0, g = 0, b = 0;
    *valid = 0;
    for (uint32_t t = 0; t < s->texel_count; t++) {
        r += s->flux_r[t], g += s->flux_g[t], b += s->flux_b[t];
        *valid += s->valid[t];
    }
    return pf_v3((float)r, (float)g, (float)b);
}

/* Every valid texel's surface point lies on the ray through its centre. */
static void rsm_check_rays(const gi_rsm_set *s)
{
    for (uint32_t m = 0; m < s->count; m++) {
        const gi_rsm_map *mp = &s->maps[m];
        float texel = 2.0f / (float)mp->size;
        for (uint32_t f = 0; f < mp->face_count; f++)
            for (uint32_t y = 0; y < mp->size; y++)
                for (uint32_t x = 0; x < mp->size; x++) {
                    uint32_t t = mp->first + (f * mp->size + y) * mp->size + x;
                    if (!s->valid[t]) continue;
                    float nx = ((float)x + 0.5f) * texel - 1.0f, ny = 1.0f - ((float)y + 0.5f) * texel;
                    pf_vec3 p = pf_v3(s->pos_x[t], s->pos_y[t], s->pos_z[t]), o, d;
                    if (mp->kind == GI_RSM_AREA) {
                        o = mp->faces[f].org;
                        d = gi_rsm_area_dir(&mp->faces[f], mp->size, x, y);
                    } else if (mp->kind == GI_RSM_ORTHO) {
                        o = pf_v3_add(mp->eye, pf_v3_add(pf_v3_scale(mp->right[f], nx * mp->half_w),
                                                         pf_v3_scale(mp->up[f], ny * mp->half_h)));
                        d = mp->forward[f];
                    } else {
                        o = mp->eye;
                        d = pf_v3_normalize(pf_v3_add(mp->forward[f],
                                                      pf_v3_add(pf_v3_scale(mp->right[f], nx * mp->tan_half),
                                                                pf_v3_scale(mp->up[f], ny * mp->tan_half))));
                    }
                    float off = pf_v3_length(pf_v3_cross(pf_v3_sub(p, o), d));
                    if (off > 1e-3f) fail_msg("texel %u (face %u, %u, %u) is %g off its ray", t, f, x, y, (double)off);
                    /* the normal faces the light */
                    assert_true(s->nrm_x[t] * d.x + s->nrm_y[t] * d.y + s->nrm_z[t] * d.z <= 1e-6f);
                }
    }
}

static void test_rsm_flux_point_box(void **state)
{
    (void)state;
    const float alb[4] = {0.5f, 0.25f, 0.8f, 1.0f};
    tu_quad q[6] = {
        {{0, -1, 0}, {0, 0, 1}, {1, 0, 0}, {0}, 0, 0}, {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0}, 0, 0},
        {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0}, 0, 0}, {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0}, 0, 0},
        {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0}, 0, 0}, {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0}, 0, 0},
    };
    for (int k = 0; k < 6; k++) memcpy(q[k].albedo, alb, sizeof alb);
    for (uint32_t threads = 1; threads <= 2; threads++) {
        rsm_fx x;
        tu_make_scene(&x.scene, q, 6);
        pf_light L;
        memset(&L, 0, sizeof L);
        L.type = PF_LIGHT_POINT;
        L.position = pf_v3(0.1f, 0.05f, -0.07f);
        L.color = pf_v3(1.0f, 0.5f, 2.0f);
        L.intensity = 3.0f;
        pf_error err;
        assert_int_equal(pf_scene_add_light(&x.scene, &L, &err), PF_OK);
        rsm_run(&x, 64, threads);
        assert_int_equal(x.set.count, 1);
        assert_int_equal(x.set.maps[0].kind, GI_RSM_CUBE);
        assert_int_equal(x.set.texel_count, 6 * 64 * 64);
        uint32_t valid;
        pf_vec3 sum = rsm_flux_sum(&x.set, &valid);
        pf_vec3 power = gi_rsm_light_power(&x.set.maps[0], &x.scene.lights[0]);
        double want[3] = {4 * PF_PI * 3.0 * 1.0 * 0.5, 4 * PF_PI * 3.0 * 0.5 * 0.25, 4 * PF_PI * 3.0 * 2.0 * 0.8};
        print_message("point light in a closed box: flux sum %.6f %.6f %.6f, analytic %.6f %.6f %.6f\n", (double)sum.x,
                      (double)sum.y, (double)sum.z, want[0], want[1], want[2]);
        assert_int_equal(valid, x.set.texel_count); /* closed: every texel sees a wall */
        assert_true(fabs(sum.x / want[0] - 1.0) < 1e-4);
        assert_true(fabs(sum.y / want[1] - 1.0) < 1e-4);
        assert_true(fabs(sum.z / want[2] - 1.0) < 1e-4);
        assert_true(fabs(power.x / (4 * PF_PI * 3.0) - 1.0) < 1e-6);
        rsm_check_rays(&x.set);
        /* a second update with the same light renders nothing */
        assert_int_equal(gi_rsm_set_update(&x.set, &x.scene, NULL, NULL, x.jobs, &err), PF_OK);
        assert_int_equal(x.set.changed, 0);
        /* moving the light re-renders (no reallocation needed) and still sums right */
        x.scene.lights[0].position = pf_v3(-0.3f, 0.2f, 0.1f);
        assert_int_equal(gi_rsm_set_update(&x.set, &x.scene, NULL, NULL, x.jobs, &err), PF_OK);
        assert_int_equal(x.set.changed, 1);
        sum = rsm_flux_sum(&x.set, &valid);
        assert_true(fabs(sum.x / want[0] - 1.0) < 1e-4);
        rsm_end(&x);
    }
}

static void test_rsm_flux_spot_and_directional(void **state)
{
    (void)state;
    /* spot 1 m over a 100 x 100 m floor, straight down, cone 20/30 degrees */
    tu_quad floor_q = {{0, 0, 0}, {0, 0, 50}, {50, 0, 0}, {0.6f, 0.6f, 0.6f, 1.0f}, 0, 0};
    rsm_fx x;
    tu_make_scene(&x.scene, &floor_q, 1);
    pf_light L;
    memset(&L, 0, sizeof L);
    L.type = PF_LIGHT_SPOT;
    L.position = pf_v3(0.0f, 1.0f, 0.0f);
    L.direction = pf_v3(0.0f, -1.0f, 0.0f);
    L.color = pf_v3(1, 1, 1);
    L.intensity = 5.0f;
    L.inner_cone = pf_radians(20.0f);
    L.outer_cone = pf_radians(30.0f);
    pf_error err;
    assert_int_equal(pf_scene_add_light(&x.scene, &L, &err), PF_OK);
    rsm_run(&x, 128, 2);
    assert_int_equal(x.set.maps[0].kind, GI_RSM_SPOT);
    uint32_t valid;
    pf_vec3 sum = rsm_flux_sum(&x.set, &valid);
    double co = cos(pf_radians(30.0f)), ci = cos(pf_radians(20.0f));
    double want = 0.6 * 5.0 * 2.0 * PF_PI * ((ci - co) / 3.0 + (1.0 - ci));
    print_message("spot over a plane: flux sum %.6f, analytic %.6f (rel. error %.2e)\n", (double)sum.x, want,
                  sum.x / want - 1.0);
    assert_true(fabs(sum.x / want - 1.0) < 2e-3);
    rsm_check_rays(&x.set);
    rsm_end(&x);

    /* directional light at 30 degrees from the vertical on a 2 x 2 m quad */
    tu_quad small = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0.5f, 0.5f, 0.5f, 1.0f}, 0, 0};
    tu_make_scene(&x.scene, &small, 1);
    memset(&L, 0, sizeof L);
    L.type = PF_LIGHT_DIRECTIONAL;
    L.direction = pf_v3_normalize(pf_v3(0.5f, -(float)sqrt(3.0) / 2.0f, 0.0f));
    L.color = pf_v3(1, 1, 1);
    L.intensity = 2.0f;
    assert_int_equal(pf_scene_add_light(&x.scene, &L, &err), PF_OK);
    rsm_run(&x, 256, 1);
    assert_int_equal(x.set.maps[0].kind, GI_RSM_ORTHO);
    sum = rsm_flux_sum(&x.set, &valid);
    want = 0.5 * 2.0 * 4.0 * sqrt(3.0) / 2.0; /* albedo E A cos(theta) */
    print_message("directional on a quad: flux sum %.6f, analytic %.6f (rel. error %.2e)\n", (double)sum.x, want,
                  sum.x / want - 1.0);
    assert_true(fabs(sum.x / want - 1.0) < 0.01);
    rsm_check_rays(&x.set);
    rsm_end(&x);
}

/* ------------------------------------------------------ area lights' RSM */

/* The closed box of test_rsm_flux_point_box (walls of albedo alb) with a
 * 0.4 x 0.4 m one-sided emitter quad at y = 0.5 facing down (Le (2, 1,
 * 0.5), albedo 0.3): its points' rays go down, so every one meets a wall. */
static void area_box(pf_scene *s, const float alb[4])
{
    tu_quad q[7] = {
        {{0, -1, 0}, {0, 0, 1}, {1, 0, 0}, {0}, 0, 0}, {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0}, 0, 0},
        {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0}, 0, 0}, {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0}, 0, 0},
        {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0}, 0, 0}, {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0}, 0, 0},
        {{0, 0.5f, 0}, {0.2f, 0, 0}, {0, 0, 0.2f}, {0.3f, 0.3f, 0.3f, 1}, 0, 0},
    };
    for (int k = 0; k < 6; k++) memcpy(q[k].albedo, alb, 4 * sizeof(float));
    tu_make_scene(s, q, 7);
    s->materials[6].emission[0] = 2.0f;
    s->materials[6].emission[1] = 1.0f;
    s->materials[6].emission[2] = 0.5f;
}

/* A whole map's planes, for bit-exact comparisons. */
static int rsm_map_equal(const gi_rsm_set *a, uint32_t ma, const gi_rsm_set *b, uint32_t mb)
{
    size_t n = a->maps[ma].texel_count, oa = a->maps[ma].first, ob = b->maps[mb].first;
    if (n != b->maps[mb].texel_count) return 0;
    const float *pa[] = {a->pos_x, a->pos_y, a->pos_z, a->nrm_x, a->nrm_y, a->nrm_z, a->ng_x, a->ng_y, a->ng_z,
                         a->flux_r, a->flux_g, a->flux_b};
    const float *pb[] = {b->pos_x, b->pos_y, b->pos_z, b->nrm_x, b->nrm_y, b->nrm_z, b->ng_x, b->ng_y, b->ng_z,
                         b->flux_r, b->flux_g, b->flux_b};
    for (int k = 0; k < 12; k++)
        if (memcmp(pa[k] + oa, pb[k] + ob, n * sizeof(float))) return 0;
    return !memcmp(a->valid + oa, b->valid + ob, n) && !memcmp(a->prim + oa, b->prim + ob, n * sizeof(uint32_t));
}

/* The area lights' map (gi_rsm_area.h): in a closed box every texel is
 * valid and the reflected fluxes sum to albedo x pi Le A (all of the
 * emitter's flux, once); the texel directions are cosine-distributed (the
 * mean cos over a face is 2/3, the cosine-weighted hemisphere's); every
 * texel lies on its ray; the same bits with 1 and 2 threads. */
static void test_rsm_flux_area_box(void **state)
{
    (void)state;
    const float alb[4] = {0.5f, 0.25f, 0.8f, 1.0f};
    const uint32_t K = 8, R = 64;
    gi_rsm_set sets[2];
    pf_scene scenes[2];
    pf_rt *rts[2];
    pf_jobs *jobs[2];
    gi_area_lights areas[2];
    pf_error err;
    for (uint32_t th = 0; th < 2; th++) {
        area_box(&scenes[th], alb);
        assert_int_equal(pf_scene_validate(&scenes[th], &err), PF_OK);
        assert_int_equal(pf_rt_create(&rts[th], &scenes[th], PF_ISA_SSE2, 1, &err), PF_OK);
        jobs[th] = pf_jobs_create(th + 1);
        assert_int_equal(gi_area_lights_build(&areas[th], &scenes[th], &err), PF_OK);
        assert_int_equal(areas[th].count, 2);
        gi_rsm_set_init(&sets[th], R);
        sets[th].area_points = K;
        /* emitters but no ray tracer: an error, not a crash */
        assert_int_equal(gi_rsm_set_update(&sets[th], &scenes[th], &areas[th], NULL, jobs[th], &err), PF_ERR_ARGUMENT);
        assert_int_equal(gi_rsm_set_update(&sets[th], &scenes[th], &areas[th], rts[th], jobs[th], &err), PF_OK);
        const gi_rsm_set *s = &sets[th];
        assert_int_equal(s->count, 1);
        assert_int_equal(s->punctual, 0);
        assert_int_equal(s->maps[0].kind, GI_RSM_AREA);
        assert_int_equal(s->maps[0].face_count, K);
        assert_int_equal(s->texel_count, K * R * R);
        uint32_t valid;
        pf_vec3 sum = rsm_flux_sum(s, &valid);
        const double le[3] = {2.0, 1.0, 0.5}, A = 0.16;
        double want[3];
        for (int c = 0; c < 3; c++) want[c] = alb[c] * PF_PI * le[c] * A;
        pf_vec3 power = gi_rsm_light_power(&s->maps[0], NULL);
        print_message("area light in a closed box (K = %u, %u^2 per face, %u thread(s)): flux sum %.6f %.6f %.6f, "
                      "analytic %.6f %.6f %.6f; power %.6f (pi Le A %.6f)\n",
                      K, R, th + 1, (double)sum.x, (double)sum.y, (double)sum.z, want[0], want[1], want[2],
                      (double)power.x, PF_PI * le[0] * A);
        assert_int_equal(valid, s->texel_count);
        assert_true(fabs(sum.x / want[0] - 1.0) < 1e-4);
        assert_true(fabs(sum.y / want[1] - 1.0) < 1e-4);
        assert_true(fabs(sum.z / want[2] - 1.0) < 1e-4);
        assert_true(fabs(power.x / (PF_PI * le[0] * A) - 1.0) < 1e-5);
        rsm_check_rays(s);
        /* cosine-distributed: mean cos theta over each face is 2/3 */
        for (uint32_t f = 0; f < K; f++) {
            const gi_rsm_face *fc = &s->maps[0].faces[f];
            assert_true(fc->n.y < -0.99f); /* the emitting side */
            double mc = 0.0;
            for (uint32_t y = 0; y < R; y++)
                for (uint32_t x = 0; x < R; x++) mc += pf_v3_dot(gi_rsm_area_dir(fc, R, x, y), fc->n);
            mc /= (double)R * R;
            if (fabs(mc - 2.0 / 3.0) > 2e-3) fail_msg("face %u: mean cos %.5f, want 2/3", f, mc);
        }
        /* nothing changed: nothing rendered */
        assert_int_equal(gi_rsm_set_update(&sets[th], &scenes[th], &areas[th], rts[th], jobs[th], &err), PF_OK);
        assert_int_equal(sets[th].changed, 0);
    }
    assert_true(rsm_map_equal(&sets[0], 0, &sets[1], 0));
    for (uint32_t th = 0; th < 2; th++) {
        gi_rsm_set_free(&sets[th]);
        gi_area_lights_free(&areas[th]);
        pf_jobs_destroy(jobs[th]);
        pf_rt_destroy(rts[th]);
        pf_scene_free(&scenes[th]);
    }
}

/* A scene with a point light and an emitter gets both maps; the point
 * light's map is bit for bit the one the set makes without area lights,
 * and moving the light re-renders it while the area map stays. */
static void test_rsm_point_and_area(void **state)
{
    (void)state;
    const float alb[4] = {0.6f, 0.6f, 0.6f, 1.0f};
    pf_scene sc;
    area_box(&sc, alb);
    pf_light L;
    memset(&L, 0, sizeof L);
    L.type = PF_LIGHT_POINT;
    L.position = pf_v3(0.1f, -0.3f, -0.07f);
    L.color = pf_v3(1.0f, 1.0f, 1.0f);
    L.intensity = 1.0f;
    pf_error err;
    assert_int_equal(pf_scene_add_light(&sc, &L, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&sc, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &sc, PF_ISA_SSE2, 1, &err), PF_OK);
    pf_jobs *jobs = pf_jobs_create(2);
    gi_area_lights area;
    assert_int_equal(gi_area_lights_build(&area, &sc, &err), PF_OK);
    gi_rsm_set both, point;
    gi_rsm_set_init(&both, 32);
    gi_rsm_set_init(&point, 32);
    assert_int_equal(gi_rsm_set_update(&both, &sc, &area, rt, jobs, &err), PF_OK);
    assert_int_equal(gi_rsm_set_update(&point, &sc, NULL, NULL, jobs, &err), PF_OK);
    assert_int_equal(both.count, 2);
    assert_int_equal(both.punctual, 1);
    assert_int_equal(both.maps[0].kind, GI_RSM_CUBE);
    assert_int_equal(both.maps[1].kind, GI_RSM_AREA);
    assert_int_equal(both.maps[1].face_count, GI_RSM_DEFAULT_AREA_POINTS);
    assert_int_equal(both.maps[1].first, 6 * 32 * 32);
    assert_int_equal(point.count, 1);
    assert_true(rsm_map_equal(&both, 0, &point, 0));
    size_t n = both.maps[1].texel_count, o = both.maps[1].first;
    float *flux = malloc(n * sizeof(float));
    memcpy(flux, both.flux_g + o, n * sizeof(float));
    uint32_t updates = both.updates;
    sc.lights[0].position = pf_v3(-0.2f, -0.4f, 0.1f);
    assert_int_equal(gi_rsm_set_update(&both, &sc, &area, rt, jobs, &err), PF_OK);
    assert_int_equal(gi_rsm_set_update(&point, &sc, NULL, NULL, jobs, &err), PF_OK);
    assert_int_equal(both.changed, 1);
    assert_int_equal(both.updates, updates + 1);
    assert_true(rsm_map_equal(&both, 0, &point, 0));
    assert_true(!memcmp(flux, both.flux_g + o, n * sizeof(float)));
    free(flux);
    gi_rsm_set_free(&both);
    gi_rsm_set_free(&point);
    gi_area_lights_free(&area);
    pf_jobs_destroy(jobs);
    pf_rt_destroy(rt);
    pf_scene_free(&sc);
}

/* ------------------------------------------------------ methods in frames */

typedef tu_fx fx;

static void fx_begin(fx *x, uint32_t threads, uint32_t w, uint32_t h, const gi_indirect_options *io)
{
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, w, h, &x->scene.cameras[0], io, 1);
}

static void fx_end(fx *x) { tu_fx_end(x); }

/* 30 frames of a method on the Cornell box: the camera turns a little every
 * frame except 20-24 (static), the light moves on frames 10-14. Returns a
 * hash of all VPL sets; *static_moved counts moved VPLs on frames 21-24. */
static uint32_t g_pan_moved; /* moved VPLs on frames 1-9 of the last method_frames (camera turning, light static) */
/* The SIMD path the methods' kernels take in method_frames (an rs_simd;
 * the importance map's, gi_importance_kernels.h). */
static uint32_t g_simd = RS_SIMD_SCALAR;

static uint64_t method_frames(const gi_vpl_method *method, const char *param, uint32_t threads,
                              uint32_t *static_moved, tu_golden_picture *pic)
/* (small RSMs and few camera points keep the 4 x 30 frames fast; the code
 * paths are the same at any size) */
{
    fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    fx_begin(&x, threads, 64, 48, NULL);
    gi_params params;
    memset(&params, 0, sizeof params);
    assert_int_equal(gi_params_add(&params, "rsm=32", &err), PF_OK);
    assert_int_equal(gi_params_add(&params, "P=64", &err), PF_OK);
    if (param) assert_int_equal(gi_params_add(&params, param, &err), PF_OK);
    void *st;
    assert_int_equal(method->create(&st, &params, &err), PF_OK);
    gi_vpl_set set = {0};
    uint64_t hash = 1469598103934665603ull;
    *static_moved = 0;
    g_pan_moved = 0;
    pf_camera cam0 = x.scene.cameras[0];
    pf_vec3 light0 = x.scene.lights[0].position;
    /* the picture: the VPLs of frames 0, 9 (camera turned), 14 (light moved)
     * and 29 from above (x, z; top row) and from the front (x, y) */
    const float lo[3] = {x.scene.bounds_min.x, x.scene.bounds_min.y, x.scene.bounds_min.z};
    const float hi[3] = {x.scene.bounds_max.x, x.scene.bounds_max.y, x.scene.bounds_max.z};
    uint32_t panel = 0;
    if (pic) tu_golden_picture_init(pic, 4 * 64, 2 * 64);
    for (uint32_t frame = 0; frame < 30; frame++) {
        uint32_t cf = frame < 20 ? frame : (frame < 25 ? 20 : frame);
        pf_vec3 target = pf_v3_add(cam0.eye, cam0.forward);
        target.x += 0.01f * (float)cf;
        assert_int_equal(pf_camera_look_at(&x.f.camera, cam0.eye, target, cam0.yfov, &err), PF_OK);
        x.scene.lights[0].position = light0;
        if (frame >= 10 && frame < 15) x.scene.lights[0].position.x += 0.02f * (float)(frame - 9);
        gi_stage_gbuffer_raster(&x.f);
        gi_stage_gbuffer_resolve(&x.f);
        gi_vpl_inputs in = {&x.scene, x.rt,        x.jobs,    &x.f.camera, frame, 128, 1, &x.f.gbuf, 64, 48,
                            &x.f.area, NULL, g_simd, 0, 0, 0};
        assert_int_equal(method->update(st, &in, &set, &err), PF_OK);
        assert_int_equal(set.count, 128);
        for (uint32_t i = 0; i < set.count; i++) {
            assert_int_equal(set.v[i].id, i);
            assert_true(pf_v3_is_finite(set.v[i].pos) && pf_v3_is_finite(set.v[i].intensity));
            if (frame >= 21 && frame < 25) *static_moved += set.v[i].moved;
            if (frame >= 1 && frame < 10) g_pan_moved += set.v[i].moved;
            if (frame == 0) assert_int_equal(set.v[i].moved, 1);
        }
        hash = hash * 1099511628211ull ^ pf_imageio_hash((const float *)set.v, set.count * (sizeof(gi_vpl) / 4));
        if (pic && (frame == 0 || frame == 9 || frame == 14 || frame == 29)) {
            const float *xyz = &set.v[0].pos.x;
            tu_golden_put_points(pic, 64 * panel, 0, 64, 64, xyz, sizeof(gi_vpl) / 4, set.count, 0, 2, lo, hi);
            tu_golden_put_points(pic, 64 * panel, 64, 64, 64, xyz, sizeof(gi_vpl) / 4, set.count, 0, 1, lo, hi);
            panel++;
        }
    }
    method->destroy(st);
    gi_vpl_set_free(&set);
    fx_end(&x);
    return hash;
}

/* golden: the hash the point-lit Cornell box gave before the area lights'
 * map existed (gi_rsm_area.h): scenes without emitters must not change. */
static void check_deterministic(const gi_vpl_method *m, const char *param, const char *name, uint64_t golden)
{
    uint32_t moved1, moved2;
    tu_golden_picture pic;
    uint64_t h1 = method_frames(m, param, 1, &moved1, &pic), h2 = method_frames(m, param, 2, &moved2, NULL);
    print_message("%s %s: moved on static frames %u\n", m->name, param ? param : "", moved2);
    assert_true(h1 == h2);
    /* the importance map's SIMD kernels give the scalar path's VPLs */
    pf_isa isa = pf_isa_detect();
    for (uint32_t simd = RS_SIMD_AVX2; simd <= RS_SIMD_AVX512; simd++) {
        if (isa < (simd == RS_SIMD_AVX2 ? PF_ISA_AVX2 : PF_ISA_AVX512)) continue;
        uint32_t moved3;
        g_simd = simd;
        uint64_t h3 = method_frames(m, param, 2, &moved3, NULL);
        g_simd = RS_SIMD_SCALAR;
        if (h3 != h1) fail_msg("%s %s: the %s path's VPLs differ from the scalar path's", m->name, param ? param : "",
                               rs_simd_name((rs_simd)simd));
    }
    tu_golden_check(name, h1, golden, &pic);
    tu_golden_picture_free(&pic);
    assert_int_equal(moved1, 0);
    assert_int_equal(moved2, 0);
}

static void test_invtm_deterministic(void **state)
{
    (void)state;
    check_deterministic(&gi_method_invtm, NULL, "rsm-invtm-cornell", 0x42ec617c0ca5d89eull);
    check_deterministic(&gi_method_invtm, "dims=2", "rsm-invtm-dims2-cornell", 0x609e45a35d342518ull);
}

static void test_tcas_deterministic(void **state)
{
    (void)state;
    check_deterministic(&gi_method_tcas, NULL, "rsm-tcas-cornell", 0xae7c8a7d38a9b58full);
}

/* Barak 2013's claim (Sec. 4.3, 6.2): under a moving camera IM-H keeps most
 * VPLs where they were, while InvTM's global CDF shifts almost all of them.
 * Frames 1-9 of method_frames (the camera turns, the light is static, 128
 * VPLs): TCAS must move fewer than half as many VPLs as InvTM. */
static void test_tcas_more_coherent(void **state)
{
    (void)state;
    uint32_t unused;
    method_frames(&gi_method_invtm, NULL, 2, &unused, NULL);
    uint32_t inv = g_pan_moved;
    method_frames(&gi_method_tcas, NULL, 2, &unused, NULL);
    uint32_t tc = g_pan_moved;
    print_message("moved VPLs over 9 frames of a camera pan (128 VPLs): invtm %u, tcas %u\n", inv, tc);
    assert_true(inv > 0);
    assert_true(2 * tc < inv);
}

/* Indirect light (1 bounce) of the Cornell box with `method`, every pixel
 * seeing every VPL through Embree rays, no clamp, no filter. */
static void indirect_image(const gi_vpl_method *method, const char *param, uint32_t vpls, float *out, uint32_t w,
                           uint32_t h, uint32_t *prim)
{
    fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = method;
    if (param) assert_int_equal(gi_params_add(&io.params, param, &err), PF_OK);
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.vpls = vpls;
    io.bounces = 1;
    io.clamp = 0.0f;
    io.filter = GI_FILTER_NONE;
    fx_begin(&x, 2, w, h, &io);
    gi_frame_render_raster(&x.f);
    memcpy(out, x.f.final, sizeof(float) * 3 * w * h);
    if (prim) memcpy(prim, x.f.gbuf.prim, sizeof(uint32_t) * w * h);
    fx_end(&x);
}

/* Mean relative error of img against ir (luminance, covered pixels where
 * IR is not black) and the ratio of the means. */
static double rel_error(const float *img, const float *ir, const uint32_t *prim, int n_px, double *ratio, int *n)
{
    double sum = 0.0, sa = 0.0, sb = 0.0;
    *n = 0;
    for (int i = 0; i < n_px; i++) {
        if (prim[i] == RS_GBUFFER_EMPTY) continue;
        double a = 0.2126 * img[3 * i] + 0.7152 * img[3 * i + 1] + 0.0722 * img[3 * i + 2];
        double b = 0.2126 * ir[3 * i] + 0.7152 * ir[3 * i + 1] + 0.0722 * ir[3 * i + 2];
        if (!(b > 1e-4)) continue;
        sum += fabs(a - b) / b;
        sa += a, sb += b;
        (*n)++;
    }
    *ratio = sa / sb;
    return sum / *n;
}

/* Convergence to Instant Radiosity: both methods sample the same first
 * bounce (IR with 1 bounce, 16384 VPLs, is the target; measured, IR itself
 * with 8192 VPLs is 1.7% off it per pixel). With 8192 VPLs the stated
 * tolerance: mean relative error per pixel under 5% for InvTM (measured
 * 2.9%, both dims), under 8% for TCAS (measured 6.2%: its Eq. 3 weights vary
 * per chain, so it is noisier, as Barak 2013 Sec. 6.2 reports), and the
 * ratio of the image means within 2% (measured 0.993-0.998). 2048 VPLs are
 * rendered and printed for comparison. */
static void test_converge_to_ir(void **state)
{
    (void)state;
    enum { W = 40, H = 30 };
    static float ir[3 * W * H], img[3 * W * H];
    static uint32_t prim[W * H];
    indirect_image(&gi_method_ir, NULL, 16384, ir, W, H, prim);
    const struct {
        const gi_vpl_method *m;
        const char *param;
        double tol;
    } cases[] = {{&gi_method_invtm, NULL, 0.05}, {&gi_method_invtm, "dims=2", 0.05}, {&gi_method_tcas, NULL, 0.08}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double mre[2], ratio[2];
        int n[2];
        for (int k = 0; k < 2; k++) {
            uint32_t vpls = k ? 8192 : 2048;
            indirect_image(cases[c].m, cases[c].param, vpls, img, W, H, NULL);
            mre[k] = rel_error(img, ir, prim, W * H, &ratio[k], &n[k]);
            print_message("%s %s (%u VPLs) vs IR (16384 VPLs), 1 bounce, indirect only: mean relative error %.4f over "
                          "%d pixels, ratio of means %.4f\n",
                          cases[c].m->name, cases[c].param ? cases[c].param : "", vpls, mre[k], n[k], ratio[k]);
        }
        assert_true(n[1] > W * H / 2);
        assert_true(mre[1] < cases[c].tol);
        assert_true(fabs(ratio[1] - 1.0) < 0.02);
    }
}

/* ------------------------------------------- area-lit scene: every method */

/* A Cornell-like room lit only by an emissive quad: a closed 1 m box (grey
 * floor, ceiling, back and front walls, red left and green right wall), a
 * 0.3 x 0.6 x 0.3 m block, and a 0.3 x 0.3 m emitter 1 cm under the ceiling
 * facing down (Le 5). No punctual light. */
static void area_room(pf_scene *s)
{
    const float g = 0.7f;
    tu_quad q[12] = {
        {{0, 0, 0}, {0.5f, 0, 0}, {0, 0, -0.5f}, {g, g, g, 1}, 0, 0},             /* floor */
        {{0, 1, 0}, {0.5f, 0, 0}, {0, 0, 0.5f}, {g, g, g, 1}, 0, 0},              /* ceiling */
        {{0, 0.5f, -0.5f}, {0.5f, 0, 0}, {0, 0.5f, 0}, {g, g, g, 1}, 0, 0},       /* back */
        {{0, 0.5f, 0.5f}, {0.5f, 0, 0}, {0, -0.5f, 0}, {g, g, g, 1}, 0, 0},       /* front */
        {{-0.5f, 0.5f, 0}, {0, 0.5f, 0}, {0, 0, 0.5f}, {0.7f, 0.1f, 0.1f, 1}, 0, 0}, /* left, red */
        {{0.5f, 0.5f, 0}, {0, 0, 0.5f}, {0, 0.5f, 0}, {0.1f, 0.7f, 0.1f, 1}, 0, 0},  /* right, green */
        {{0, 0.99f, 0}, {0.15f, 0, 0}, {0, 0, 0.15f}, {0.5f, 0.5f, 0.5f, 1}, 0, 0},  /* emitter */
        {{0.15f, 0.6f, -0.2f}, {0.15f, 0, 0}, {0, 0, -0.15f}, {g, g, g, 1}, 0, 0},   /* block: top */
        {{0.3f, 0.3f, -0.2f}, {0, 0.3f, 0}, {0, 0, 0.15f}, {g, g, g, 1}, 0, 0},      /* +x */
        {{0.0f, 0.3f, -0.2f}, {0, 0, 0.15f}, {0, 0.3f, 0}, {g, g, g, 1}, 0, 0},      /* -x */
        {{0.15f, 0.3f, -0.05f}, {0.15f, 0, 0}, {0, 0.3f, 0}, {g, g, g, 1}, 0, 0},    /* +z */
        {{0.15f, 0.3f, -0.35f}, {0, 0.3f, 0}, {0.15f, 0, 0}, {g, g, g, 1}, 0, 0},    /* -z */
    };
    tu_make_scene(s, q, 12);
    for (int c = 0; c < 3; c++) s->materials[6].emission[c] = 5.0f;
}

static void area_room_camera(pf_camera *cam)
{
    pf_error err;
    assert_int_equal(pf_camera_look_at(cam, pf_v3(-0.1f, 0.5f, 0.45f), pf_v3(0.05f, 0.4f, -0.5f), pf_radians(75), &err),
                     PF_OK);
}

static double mean_lum(const float *rgb, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += 0.2126 * rgb[3 * i] + 0.7152 * rgb[3 * i + 1] + 0.0722 * rgb[3 * i + 2];
    return s / (double)n;
}

/* Energy of the area-lit room against the path tracer: the indirect light
 * (1 bounce, the bounce InvTM and TCAS make and SSVP's first), every pixel
 * seeing every VPL through Embree rays, no clamp, no filter, 8192 VPLs, is
 * within 3% of gi_reference's mean (1 bounce, indirect only, 2048 spp).
 * Measured: see docs/rsm.md. */
static void test_area_energy_vs_reference(void **state)
{
    (void)state;
    enum { W = 24, H = 18 };
    static float ref[3 * W * H], img[3 * W * H];
    pf_camera cam;
    area_room_camera(&cam);
    double ref_mean;
    {
        fx x;
        area_room(&x.scene);
        tu_fx_begin(&x, 2, RS_SIMD_SCALAR, W, H, &cam, NULL, 1);
        gi_reference_options ro;
        memset(&ro, 0, sizeof ro);
        ro.spp = 2048;
        ro.bounces = 1;
        ro.indirect_only = 1;
        pf_error err;
        assert_int_equal(gi_reference_render(ref, &x.scene, x.rt, x.jobs, &cam, W, H, &ro, &err), PF_OK);
        ref_mean = mean_lum(ref, W * H);
        fx_end(&x);
    }
    const struct {
        const gi_vpl_method *m;
        const char *param;
    } cases[] = {{&gi_method_invtm, NULL}, {&gi_method_tcas, NULL}, {&gi_method_ssvp, "first=8192"}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        fx x;
        pf_error err;
        area_room(&x.scene);
        gi_indirect_options io;
        memset(&io, 0, sizeof io);
        io.method = cases[c].m;
        if (cases[c].param) assert_int_equal(gi_params_add(&io.params, cases[c].param, &err), PF_OK);
        io.no_interleave = 1;
        io.visibility_raytrace = 1;
        io.vpls = 8192;
        io.bounces = 1;
        io.clamp = 0.0f;
        io.filter = GI_FILTER_NONE;
        tu_fx_begin(&x, 2, RS_SIMD_SCALAR, W, H, &cam, &io, 1);
        assert_int_equal(x.f.area.count, 2);
        assert_int_equal(x.scene.light_count, 0);
        gi_frame_render_raster(&x.f);
        memcpy(img, x.f.final, sizeof img);
        double ratio = mean_lum(img, W * H) / ref_mean;
        print_message("area-lit room, %s %s, 8192 VPLs, 1 bounce, indirect only, ray-traced visibility, no clamp: "
                      "image mean / reference mean = %.4f\n",
                      cases[c].m->name, cases[c].param ? cases[c].param : "", ratio);
        assert_true(fabs(ratio - 1.0) < 0.03);
        fx_end(&x);
    }
}

/* The area-lit room, 8 frames (the camera turns on frames 1-5, then
 * stands): a hash of every VPL set, the VPLs of the static frames that
 * (frames 6, 7) moved, and the lowest total VPL luminance of a frame. */
static uint64_t area_frames(const gi_vpl_method *m, uint32_t threads, uint32_t *static_moved, double *min_total)
{
    fx x;
    pf_error err;
    area_room(&x.scene);
    pf_camera cam0;
    area_room_camera(&cam0);
    tu_fx_begin(&x, threads, RS_SIMD_SCALAR, 48, 36, &cam0, NULL, 1);
    gi_params params;
    memset(&params, 0, sizeof params);
    const char *ps[3] = {"rsm=32", "P=64", "area_points=4"};
    const char *pss[3] = {"rsm_res=32", "map_res=32", "area_points=4"};
    for (int k = 0; k < 3; k++)
        assert_int_equal(gi_params_add(&params, m == &gi_method_ssvp ? pss[k] : ps[k], &err), PF_OK);
    void *st;
    assert_int_equal(m->create(&st, &params, &err), PF_OK);
    gi_vpl_set set = {0};
    uint64_t hash = 1469598103934665603ull;
    *static_moved = 0;
    *min_total = INFINITY;
    for (uint32_t frame = 0; frame < 8; frame++) {
        uint32_t cf = frame < 6 ? frame : 5;
        pf_vec3 target = pf_v3_add(cam0.eye, cam0.forward);
        target.x += 0.02f * (float)cf;
        assert_int_equal(pf_camera_look_at(&x.f.camera, cam0.eye, target, cam0.yfov, &err), PF_OK);
        gi_stage_gbuffer_raster(&x.f);
        gi_stage_gbuffer_resolve(&x.f);
        gi_vpl_inputs in = {&x.scene, x.rt,      x.jobs, &x.f.camera, frame, 128, 2, &x.f.gbuf,
                            48,       36,        &x.f.area, NULL,    0,     0, 0, 0};
        assert_int_equal(m->update(st, &in, &set, &err), PF_OK);
        assert_true(set.count > 0);
        double total = 0.0;
        for (uint32_t i = 0; i < set.count; i++) {
            assert_true(pf_v3_is_finite(set.v[i].pos) && pf_v3_is_finite(set.v[i].intensity));
            total += pf_luminance(set.v[i].intensity);
            if (frame >= 6) *static_moved += set.v[i].moved;
        }
        if (total < *min_total) *min_total = total;
        hash = hash * 1099511628211ull ^ pf_imageio_hash((const float *)set.v, set.count * (sizeof(gi_vpl) / 4));
    }
    m->destroy(st);
    gi_vpl_set_free(&set);
    fx_end(&x);
    return hash;
}

/* Every RSM method lights the area-lit room (VPLs with light in every
 * frame), with the same bits for 1 and 2 threads, and a static frame moves
 * no VPL. */
static void test_area_methods_deterministic(void **state)
{
    (void)state;
    const gi_vpl_method *ms[3] = {&gi_method_invtm, &gi_method_tcas, &gi_method_ssvp};
    for (int k = 0; k < 3; k++) {
        uint32_t moved1, moved2;
        double t1, t2;
        uint64_t h1 = area_frames(ms[k], 1, &moved1, &t1), h2 = area_frames(ms[k], 2, &moved2, &t2);
        print_message("area-lit room, %s: 8 frames, hash %016llx (1 thread) %016llx (2 threads); moved on the static "
                      "frame %u; least VPL luminance sum %.4g\n",
                      ms[k]->name, (unsigned long long)h1, (unsigned long long)h2, moved2, t1);
        assert_true(h1 == h2);
        assert_int_equal(moved1, 0);
        assert_int_equal(moved2, 0);
        assert_true(t1 > 0.0);
    }
}

static void test_bad_params(void **state)
{
    (void)state;
    const struct {
        const gi_vpl_method *m;
        const char *kv;
    } bad[] = {
        {&gi_method_tcas, "M=0"},       {&gi_method_tcas, "M=x"},      {&gi_method_tcas, "rsm=4"},
        {&gi_method_tcas, "dims=2"},    {&gi_method_invtm, "dims=4"},  {&gi_method_invtm, "M=3"},
        {&gi_method_invtm, "P=0"},      {&gi_method_invtm, "rsm=99999"},
        {&gi_method_invtm, "area_points=0"}, {&gi_method_tcas, "area_points=257"}, {&gi_method_ssvp, "area_points=0"},
        {&gi_method_tcas, "weight=median"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        gi_params p;
        memset(&p, 0, sizeof p);
        pf_error err;
        assert_int_equal(gi_params_add(&p, bad[i].kv, &err), PF_OK);
        void *st = (void *)1;
        assert_int_not_equal(bad[i].m->create(&st, &p, &err), PF_OK);
        assert_null(st);
        assert_true(strstr(err.message, bad[i].kv) != NULL || strstr(err.message, "unknown") != NULL ||
                    strstr(err.message, bad[i].m->name) != NULL);
    }
    /* no G-buffer: a clear error, not a crash */
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, CORNELL, NULL, &err), PF_OK);
    const gi_vpl_method *ms[2] = {&gi_method_invtm, &gi_method_tcas};
    for (int k = 0; k < 2; k++) {
        void *st;
        assert_int_equal(ms[k]->create(&st, NULL, &err), PF_OK);
        gi_vpl_set set = {0};
        gi_area_lights area = {0};
        gi_vpl_inputs in = {&s, NULL, NULL, &s.cameras[0], 0, 16, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
        assert_int_equal(ms[k]->update(st, &in, &set, &err), PF_ERR_ARGUMENT);
        assert_non_null(strstr(err.message, "G-buffer"));
        ms[k]->destroy(st);
        gi_vpl_set_free(&set);
    }
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_imh_1d),
        cmocka_unit_test(test_imh_2d),
        cmocka_unit_test(test_imh_m1_uniform),
        cmocka_unit_test(test_invtm_distribution),
        cmocka_unit_test(test_rsm_flux_point_box),
        cmocka_unit_test(test_rsm_flux_spot_and_directional),
        cmocka_unit_test(test_rsm_flux_area_box),
        cmocka_unit_test(test_rsm_point_and_area),
        cmocka_unit_test(test_invtm_deterministic),
        cmocka_unit_test(test_tcas_deterministic),
        cmocka_unit_test(test_tcas_more_coherent),
        cmocka_unit_test(test_converge_to_ir),
        cmocka_unit_test(test_area_energy_vs_reference),
        cmocka_unit_test(test_area_methods_deterministic),
        cmocka_unit_test(test_bad_params),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
