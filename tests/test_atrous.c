/* test_atrous: --filter atrous (gi_atrous.h: Laine's box, then
 * variance-guided edge-avoiding a-trous levels):
 * - its exp(-t) (gi_atrous_math.h) against libm's expf, and exp(0) = 1;
 * - on a synthetic G-buffer: a constant irradiance on a plane stays
 *   constant; two perpendicular planes keep their own values exactly (the
 *   normal weight max(0, n . n_q)^128 is 0 across the edge); noise on a
 *   plane keeps its mean and loses most of its variance;
 * - the same bytes with 1 and 2 threads and on every SIMD path, at an odd
 *   size with empty pixels (every row's scalar ends and SIMD runs);
 * - on the Cornell box: the frame's energy within 2% of the box filter's,
 *   and a smoother image (the interleaving's 4 x 4 pattern removed);
 * - more levels than GI_ATROUS_MAX_LEVELS is a clear error. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_atrous.h"
#include "gi_atrous_math.h"
#include "gi_indirect_kernels.h"
#include "pf_isa.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

static void test_expneg(void **state)
{
    (void)state;
    assert_true(gi_atrous_expneg(0.0f) == 1.0f);
    /* the polynomial's error, then t log2 e's rounding (an ulp of y = 100 is
     * 7.6e-6 / 100 of it, times ln 2 in the result) */
    double worst_small = 0.0, worst = 0.0;
    for (int k = 0; k <= 80000; k++) {
        float t = (float)k * 0.001f;
        double e = exp(-(double)t), a = gi_atrous_expneg(t);
        double rel = fabs(a - e) / e;
        if (rel > worst) worst = rel;
        if (t <= 4.0f && rel > worst_small) worst_small = rel;
    }
    print_message("exp(-t): largest relative error %.3g for t in [0, 4], %.3g in [0, 80]\n", worst_small, worst);
    assert_true(worst_small < 1e-6);
    assert_true(worst < 1e-5);
    /* beyond the clamp: tiny and positive, never 0 or NaN */
    assert_true(gi_atrous_expneg(1e6f) > 0.0f && gi_atrous_expneg(1e6f) < 1e-37f);
    assert_true(gi_atrous_expneg(NAN) >= 0.0f);
}

/* A synthetic indirect image: w x h, the G-buffer and the combined RGB. */
typedef struct syn {
    uint32_t w, h;
    rs_gbuffer g;
    float *combined, *scratch, *out;
    float cap2; /* the box's position test (gi_atrous_io.cap2): 0 Laine's distance test */
} syn;

static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16, x *= 0x7feb352du, x ^= x >> 15, x *= 0x846ca68bu, x ^= x >> 16;
    return x;
}

/* kind 0: one plane z = 0 facing +z; 1: the left half on z = 0 facing +z,
 * the right half on x = 0 facing +x; 2: like 1 with every 7th pixel empty.
 * value: 1 (left) and 0.25 (right), times 1 + noise * u, u in [-1, 1). */
static void syn_make(syn *s, uint32_t w, uint32_t h, int kind, float noise)
{
    pf_error err;
    s->w = w, s->h = h;
    s->cap2 = 0.0f;
    assert_int_equal(rs_gbuffer_init(&s->g, w, h, &err), PF_OK);
    size_t px = (size_t)w * h;
    s->combined = calloc(3 * px, sizeof(float));
    s->scratch = calloc(gi_atrous_scratch_floats(w, h), sizeof(float));
    s->out = calloc(3 * px, sizeof(float));
    assert_non_null(s->combined), assert_non_null(s->scratch), assert_non_null(s->out);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            int right = kind != 0 && x >= w / 2;
            if (kind == 2 && i % 7 == 3) continue; /* prim stays EMPTY */
            s->g.prim[i] = (uint32_t)right;
            float u = (float)(hash32((uint32_t)i) >> 8) / 8388608.0f - 1.0f;
            if (right) {
                s->g.pos_x[i] = 0.0f, s->g.pos_y[i] = 0.01f * (float)y, s->g.pos_z[i] = 0.01f * (float)(x - w / 2);
                s->g.nrm_x[i] = 1.0f, s->g.nrm_y[i] = 0.0f, s->g.nrm_z[i] = 0.0f;
            } else {
                s->g.pos_x[i] = 0.01f * (float)x, s->g.pos_y[i] = 0.01f * (float)y, s->g.pos_z[i] = 0.0f;
                s->g.nrm_x[i] = 0.0f, s->g.nrm_y[i] = 0.0f, s->g.nrm_z[i] = 1.0f;
            }
            float v = (right ? 0.25f : 1.0f) * (1.0f + noise * u);
            s->combined[3 * i] = v, s->combined[3 * i + 1] = 0.5f * v, s->combined[3 * i + 2] = 0.25f * v;
        }
}

static void syn_free(syn *s)
{
    rs_gbuffer_free(&s->g);
    free(s->combined), free(s->scratch), free(s->out);
}

static void syn_run(syn *s, uint32_t threads, const gi_indirect_kernels *kt)
{
    pf_jobs *jobs = pf_jobs_create(threads);
    assert_non_null(jobs);
    gi_atrous_io io = {s->combined, &s->g, s->w, s->h,  4,      4,     0.05f * 0.05f, 0.8f, {0, 0, 0.02f},
                       s->scratch, kt,   s->out, s->cap2};
    gi_atrous_run(jobs, &io);
    pf_jobs_destroy(jobs);
}

static void test_constant_plane(void **state)
{
    (void)state;
    syn s;
    syn_make(&s, 64, 48, 0, 0.0f);
    syn_run(&s, 2, NULL);
    for (size_t i = 0; i < (size_t)s.w * s.h * 3; i++)
        assert_true(fabsf(s.out[i] - s.combined[i]) <= 1e-6f * s.combined[i]);
    syn_free(&s);
}

static void test_edges_kept(void **state)
{
    (void)state;
    syn s;
    syn_make(&s, 64, 48, 1, 0.0f);
    syn_run(&s, 2, NULL);
    for (size_t i = 0; i < (size_t)s.w * s.h * 3; i++)
        if (fabsf(s.out[i] - s.combined[i]) > 1e-6f * s.combined[i])
            fail_msg("value %zu: %g, expected %g (light crossed the edge)", i, (double)s.out[i],
                     (double)s.combined[i]);
    syn_free(&s);
}

static void test_noise_reduced(void **state)
{
    (void)state;
    syn s;
    syn_make(&s, 96, 64, 0, 0.5f);
    syn_run(&s, 2, NULL);
    double m_in = 0, m_out = 0, v_in = 0, v_out = 0;
    size_t n = (size_t)s.w * s.h;
    for (size_t i = 0; i < n; i++) m_in += s.combined[3 * i], m_out += s.out[3 * i];
    m_in /= (double)n, m_out /= (double)n;
    for (size_t i = 0; i < n; i++) {
        v_in += (s.combined[3 * i] - m_in) * (s.combined[3 * i] - m_in);
        v_out += (s.out[3 * i] - m_out) * (s.out[3 * i] - m_out);
    }
    print_message("noise: mean %.4f -> %.4f, variance %.3g -> %.3g\n", m_in, m_out, v_in / (double)n,
                  v_out / (double)n);
    assert_true(fabs(m_out / m_in - 1.0) < 0.01);
    assert_true(v_out < 0.02 * v_in);
    syn_free(&s);
}

/* Every path and thread count gives the scalar path's bytes: at 203 x 97
 * (SIMD runs, the overlapping last run, scalar ends) and 21 x 9 (rows too
 * short for a run at the wider holes). */
static void identical_at(uint32_t w, uint32_t h, float cap2)
{
    syn a;
    syn_make(&a, w, h, 2, 0.6f);
    a.cap2 = cap2;
    syn_run(&a, 1, NULL);
    const size_t bytes = (size_t)a.w * a.h * 3 * sizeof(float);
    syn b;
    syn_make(&b, w, h, 2, 0.6f);
    b.cap2 = cap2;
    syn_run(&b, 2, NULL);
    assert_memory_equal(a.out, b.out, bytes);
    pf_isa isa = pf_isa_detect();
    const gi_indirect_kernels *paths[2] = {NULL, NULL};
#if SIMD_X86
    if (isa >= PF_ISA_AVX2) paths[0] = &gi_indirect_kernels_avx2;
    if (isa >= PF_ISA_AVX512) paths[1] = &gi_indirect_kernels_avx512;
#endif
    (void)isa;
    for (int p = 0; p < 2; p++) {
        if (!paths[p]) continue;
        memset(b.out, 0, bytes);
        syn_run(&b, 2, paths[p]);
        size_t differ = 0;
        for (size_t i = 0; i < (size_t)a.w * a.h * 3; i++) differ += memcmp(&a.out[i], &b.out[i], sizeof(float)) != 0;
        if (differ) fail_msg("%ux%u, %s: %zu values differ from the scalar path", w, h, paths[p]->isa, differ);
    }
    syn_free(&a);
    syn_free(&b);
}

static void test_identical(void **state)
{
    (void)state;
    identical_at(203, 97, 0.0f);
    identical_at(21, 9, 0.0f);
    /* the tangent-plane test (the frame's default) */
    identical_at(203, 97, 16.0f * 0.05f * 0.05f);
    identical_at(21, 9, 16.0f * 0.05f * 0.05f);
}

static void render(tu_fx *x, gi_filter_kind filter, int distance_test, rs_simd simd)
{
    tu_load(&x->scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 256;
    io.filter = filter;
    io.filter_distance = distance_test;
    tu_fx_begin(x, 2, simd, 160, 120, &x->scene.cameras[0], &io, 1);
    gi_frame_render_raster(&x->f);
}

/* The mean |E(x + 1, y) - E(x, y)| / E over neighbours on one surface. */
static double roughness(const tu_fx *x)
{
    const rs_gbuffer *g = &x->f.gbuf;
    const float *e = x->f.ind.filtered;
    double s = 0;
    size_t n = 0;
    for (uint32_t y = 0; y < g->height; y++)
        for (uint32_t xx = 0; xx + 1 < g->width; xx++) {
            size_t i = (size_t)y * g->width + xx;
            if (g->prim[i] == RS_GBUFFER_EMPTY || g->prim[i + 1] != g->prim[i]) continue;
            double a = e[3 * i] + e[3 * i + 1] + e[3 * i + 2], b = e[3 * i + 3] + e[3 * i + 4] + e[3 * i + 5];
            if (a + b > 0) s += fabs(b - a) / (0.5 * (a + b)), n++;
        }
    return n ? s / (double)n : 0;
}

static void test_cornell(void **state)
{
    (void)state;
    tu_fx box, at, laine;
    render(&box, GI_FILTER_BOX, 0, RS_SIMD_SCALAR);
    render(&at, GI_FILTER_ATROUS, 0, RS_SIMD_SCALAR);
    render(&laine, GI_FILTER_BOX, 1, RS_SIMD_SCALAR);
    double eb = 0, ea = 0, el = 0;
    for (size_t i = 0; i < (size_t)160 * 120 * 3; i++)
        eb += box.f.ind.filtered[i], ea += at.f.ind.filtered[i], el += laine.f.ind.filtered[i];
    double rb = roughness(&box), ra = roughness(&at), rl = roughness(&laine);
    print_message("Cornell box: energy a-trous / box %.4f, box / Laine's box %.4f; roughness Laine's box %.4f, "
                  "box (tangent-plane test) %.4f, a-trous %.4f\n",
                  ea / eb, eb / el, rl, rb, ra);
    assert_true(fabs(ea / eb - 1.0) < 0.02);
    assert_true(fabs(eb / el - 1.0) < 0.02);
    /* the plane test keeps the windows whole on the walls and faces seen at a grazing angle, whose stripes
     * the distance test left; the a-trous levels halve what is left of Laine's box */
    assert_true(rb < 0.85 * rl);
    assert_true(ra < 0.5 * rl);
    assert_true(ra < 0.8 * rb);
    tu_fx_end(&laine);
    /* the frame's SIMD path gives the same image */
    if (pf_isa_detect() >= PF_ISA_AVX512) {
        tu_fx v;
        render(&v, GI_FILTER_ATROUS, 0, RS_SIMD_AVX512);
        assert_memory_equal(v.f.final, at.f.final, (size_t)160 * 120 * 3 * sizeof(float));
        tu_fx_end(&v);
    }
    tu_fx_end(&box);
    tu_fx_end(&at);
}

static void test_bad_levels(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.filter = GI_FILTER_ATROUS;
    io.atrous.levels = GI_ATROUS_MAX_LEVELS + 1;
    tu_fx_begin(&x, 1, RS_SIMD_SCALAR, 32, 24, &x.scene.cameras[0], NULL, 0);
    pf_error err;
    assert_int_equal(gi_frame_enable_indirect(&x.f, &io, 0, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "levels"));
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_expneg),        cmocka_unit_test(test_constant_plane),
        cmocka_unit_test(test_edges_kept),    cmocka_unit_test(test_noise_reduced),
        cmocka_unit_test(test_identical),     cmocka_unit_test(test_cornell),
        cmocka_unit_test(test_bad_levels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
