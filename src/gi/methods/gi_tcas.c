/* gi_tcas: temporally coherent adaptive sampling of VPLs by parallel
 * Independent Metropolis-Hastings chains (Barak, Bittner, Havran 2013,
 * Sec. 4.3, Algorithm 1, estimator Eq. 3) over the importance map of
 * reflective shadow maps (Ritschel 2011; gi_rsm.h, gi_importance.h).
 *
 * Per frame (the paper's outline):
 *   1. gi_rsm_set_update       a reflective shadow map per light;
 *   2. gi_importance_update    f(v) over all RSM texels from P camera points
 *                              (Eq. 1-2, no visibility);
 *   3. gi_imh_chain            one IM-H chain per VPL j (parallel over
 *                              chains), M samples, the last one kept;
 *   4. gi__tcas_make_vpls      VPL j at the chain's final texel v_j with the
 *                              weight of Eq. 3: intensity
 *                              Phi_v * w_j / (pi N f(v_j)).
 *
 * Algorithm 1 as implemented (chain j of N, length M):
 *   v   <- proposal(h(j, 0))                      k = 0: the initial sample
 *   s   <- g(v)
 *   for k = 1 .. M-1:
 *       v'  <- proposal(h(j, k))
 *       s   <- s + g(v')
 *       if g(v') / g(v) >= h7(h(j, k)): v <- v'   (always when g(v) = 0)
 *   w   <- s / M
 * h(i) = (h2(i), h3(i), h5(i)) is the Halton vector of index i and h7(i)
 * its 4th dimension ("rand.nextScalar()"), and
 *   h(j, k) = 1 + pi(j + N k)   (gi_imh_index; pi a fixed permutation)
 * The seeds j + N k (0 <= k < M) of Sec. 4.3 (permuted: deviation, see
 * gi_imh_index) give every chain disjoint proposals, the same every frame
 * ("we use the same Halton sequence in each frame"); index 0 (all zeros)
 * is skipped by the + 1. g(v) = f(v) / q(v) is the importance per unit volume
 * of the proposal space [0, 1)^3 (q = the proposal's texel probability,
 * gi_importance.h), which is the paper's f when all maps have as many
 * texels; with a spot map and a cube map the maps' texels have different
 * proposal volumes and g keeps the chain's target proportional to f.
 * Deviation in the loop bounds: Algorithm 1's listing draws M moves after
 * the initial sample and averages only those, but the text ("for M = 1 the
 * algorithm degenerates to uniform sampling ... w = f(v)") and Fig. 3 ("M =
 * 5 ... the M - 1 proposed moves") count the initial sample among the M; we
 * follow the text, so M = 1 is exactly uniform sampling with w = g(v).
 * Eq. 3 then reads, per VPL, flux Phi_v w / (N f(v)): w / f(v) stands for
 * 1 / p(v) with w estimating sum f (M = 1: 1 / q, uniform sampling).
 *
 * Parameters (--param): M=   chain length, default 16 (Hedman 2017 Sec. 5.1
 *                            ran TCAS with 16);
 *                       rsm= RSM texels per side (per cube face);
 *                       P=   camera points;
 *                       area_points= K, emitter points (faces) of the area
 *                            lights' RSM, default GI_RSM_DEFAULT_AREA_POINTS;
 *                       weight=local|single|global, Eq. 3's chain weight:
 *                            the paper's (default) or the two variants its
 *                            Sec. 6 compares with (gi__tcas_weight).
 * A chain whose M samples all have f = 0 yields a VPL of zero intensity
 * (it keeps its slot, at last frame's position when it had one).
 * Area lights (gi_area.h) have one RSM of K hemispherical faces after the
 * punctual lights' (gi_rsm_area.h, beyond the paper): it is one more
 * "light" of the sampling domain.
 * VPL j keeps slot j and id j; moved = position or normal changed.
 * Determinism: chains are independent and each writes only its own slot. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_importance.h"
#include "gi_vpl.h"

#define GI_TCAS_DEFAULT_M 16u

/* ------------------------------------------------------- 3. one IM-H chain */

/* The Halton index of chain j's k-th proposal: 1 + pi(j + N k), pi a fixed
 * bijection of [0, N M) (cycle-walking an invertible xorshift-multiply hash
 * on the next power of two). So the chains together use exactly the first
 * N M Halton points, each once (the paper's disjoint seeds j + N k), the
 * same every frame, but a chain's successive proposals are no longer a
 * fixed rotation of each other. Deviation, measured: with the plain index
 * 1 + j + N k the proposals along a chain are (in every base b) shifted by
 * the constant N / b^a digits, the chain becomes a deterministic rotation,
 * and its final samples do not follow f: in test_rsm_methods' 1D case
 * (f(i) = 1 + i on 16 cells, N = 20000, M = 16) chi-square is 15907 with
 * bases 2, 3, 5, 7 and 2006 with bases coprime to N, against a 0.001
 * critical value of 37.8; with pi it passes (gi_tcas.c, README). */
uint32_t gi_imh_index(uint32_t j, uint32_t k, uint32_t N, uint32_t M)
{
    uint64_t L = (uint64_t)N * M, i = (uint64_t)j + (uint64_t)N * k;
    uint32_t m = 1;
    while (((uint64_t)1 << m) < L) m++;
    uint64_t mask = ((uint64_t)1 << m) - 1, x = i;
    do { /* each operation is a bijection of [0, 2^m) */
        for (int r = 0; r < 3; r++) {
            x ^= x >> ((m + 1) / 2);
            x = (x * 0x2c1b3c6dull) & mask;
            x ^= x >> ((m + 1) / 3 + 1);
            x = (x * 0x297a2d39ull) & mask;
        }
    } while (x >= L);
    return (uint32_t)(x + 1);
}

uint32_t gi_imh_chain(const gi_sample_domain *d, const float *f, uint32_t j, uint32_t N, uint32_t M, double *w,
                      float *fv, double *g0)
{
    double q;
    uint32_t h = gi_imh_index(j, 0, N, M);
    uint32_t v = gi_domain_texel(d, gi_halton(h, 2), gi_halton(h, 3), gi_halton(h, 5), &q);
    double gv = (double)f[v] / q, s = gv;
    if (g0) *g0 = gv;
    for (uint32_t k = 1; k < M; k++) {
        h = gi_imh_index(j, k, N, M);
        uint32_t vn = gi_domain_texel(d, gi_halton(h, 2), gi_halton(h, 3), gi_halton(h, 5), &q);
        double gn = (double)f[vn] / q;
        s += gn;
        /* a = g(v') / g(v) >= xi, written without the division */
        if (gv == 0.0 || gn >= gi_halton(h, 7) * gv) {
            v = vn;
            gv = gn;
        }
    }
    *w = s / (double)M;
    *fv = f[v];
    return v;
}

/* ------------------------------------------------------------------ method */

/* The chain weight w of Eq. 3 (Barak 2013 Sec. 4.3 and Fig. 6-7):
 * LOCAL, the paper's method ("M-H-Our"): the chain's mean of its M
 * proposals' g, which also removes the start-up bias; SINGLE ("M-H-Single",
 * after Veach and Guibas 1997): g of the chain's initial sample, drawn from
 * the proposal; GLOBAL ("Our w/o bias reduction", Fig. 6): one weight for
 * every chain, the mean of g over all N M proposals, as if every chain had
 * reached f's distribution. */
typedef enum gi__tcas_weight { GI__TCAS_LOCAL = 0, GI__TCAS_SINGLE, GI__TCAS_GLOBAL } gi__tcas_weight;

typedef struct gi__tcas_state {
    uint32_t M, weight;
    gi_rsm_set rsm;
    gi_importance imp;
    gi_vpl_set prev;
    /* per frame, per chain (allocated for the budget) */
    uint32_t *texel;
    double *w, *g0;
    float *fv;
    uint32_t cap;
} gi__tcas_state;

static void gi__tcas_destroy(void *state)
{
    gi__tcas_state *s = state;
    if (!s) return;
    gi_rsm_set_free(&s->rsm);
    gi_importance_free(&s->imp);
    gi_vpl_set_free(&s->prev);
    free(s->texel);
    free(s->w);
    free(s->g0);
    free(s->fv);
    free(s);
}

static pf_result gi__tcas_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"M", "rsm", "P", "area_points", "weight", NULL};
    static const char *const weights[] = {"local", "single", "global", NULL};
    *state = NULL;
    pf_result r = gi_params_check(params, "tcas", known, err);
    uint32_t M = GI_TCAS_DEFAULT_M, size = GI_RSM_DEFAULT_SIZE, P = GI_IMPORTANCE_DEFAULT_P;
    uint32_t K = GI_RSM_DEFAULT_AREA_POINTS;
    if (r == PF_OK) r = gi_param_u32(params, "M", 1, 4096, &M, err);
    if (r == PF_OK) r = gi_param_u32(params, "rsm", GI_RSM_MIN_SIZE, GI_RSM_MAX_SIZE, &size, err);
    if (r == PF_OK) r = gi_param_u32(params, "P", 1, 1u << 20, &P, err);
    if (r == PF_OK) r = gi_param_u32(params, "area_points", 1, GI_RSM_MAX_AREA_POINTS, &K, err);
    uint32_t weight = GI__TCAS_LOCAL;
    if (r == PF_OK) r = gi_param_choice(params, "weight", weights, &weight, err);
    if (r != PF_OK) return r;
    gi__tcas_state *s = calloc(1, sizeof *s);
    if (!s) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    s->M = M;
    s->weight = weight;
    gi_rsm_set_init(&s->rsm, size);
    s->rsm.area_points = K;
    gi_importance_init(&s->imp, P);
    *state = s;
    return PF_OK;
}

typedef struct gi__chains_ctx {
    gi__tcas_state *s;
    uint32_t N;
} gi__chains_ctx;

static void gi__tcas_chain_job(void *p, uint32_t j, uint32_t worker)
{
    (void)worker;
    const gi__chains_ctx *c = p;
    gi__tcas_state *s = c->s;
    s->texel[j] = gi_imh_chain(&s->imp.domain, s->imp.f, j, c->N, s->M, &s->w[j], &s->fv[j], &s->g0[j]);
}

/* The weights of weight=single and weight=global (local: as the chains
 * left them). The global mean is summed in chain order (any thread count
 * gives the same bits). */
static void gi__tcas_weights(gi__tcas_state *s, uint32_t N)
{
    if (s->weight == GI__TCAS_SINGLE)
        for (uint32_t j = 0; j < N; j++) s->w[j] = s->g0[j];
    if (s->weight != GI__TCAS_GLOBAL) return;
    double sum = 0.0;
    for (uint32_t j = 0; j < N; j++) sum += s->w[j];
    for (uint32_t j = 0; j < N; j++) s->w[j] = sum / (double)N;
}

/* 4. VPL j from chain j's final sample, weighted by Eq. 3. */
static void gi__tcas_make_vpls(gi__tcas_state *s, const pf_scene *scene, uint32_t N, gi_vpl_set *out)
{
    for (uint32_t j = 0; j < N; j++) {
        gi_vpl *v = &out->v[out->count++];
        uint32_t t = s->texel[j];
        if (s->fv[j] > 0.0f) {
            gi_rsm_vpl(&s->rsm, t, s->w[j] / ((double)N * (double)s->fv[j]), j, v);
            continue;
        }
        /* every sample of the chain had f = 0: a dark VPL that stays put */
        if (j < s->prev.count) {
            v->pos = s->prev.v[j].pos;
            v->nrm = s->prev.v[j].nrm;
        } else {
            v->pos = pf_v3_scale(pf_v3_add(scene->bounds_min, scene->bounds_max), 0.5f);
            v->nrm = pf_v3(0.0f, 1.0f, 0.0f);
        }
        v->intensity = pf_v3(0.0f, 0.0f, 0.0f);
        v->id = j;
        v->moved = 1;
    }
}

static pf_result gi__tcas_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__tcas_state *s = state;
    out->count = 0;
    if (!in->gbuf)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method tcas needs the frame's G-buffer (camera points)");
    if (!in->jobs) return pf_error_set(err, PF_ERR_ARGUMENT, "--method tcas needs a job system");
    uint32_t N = in->budget;
    if ((uint64_t)N * s->M >= 0xffffffffull)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method tcas: %u VPLs x M=%u proposals exceed the Halton index range",
                            N, s->M);
    pf_result r = gi_vpl_set_reserve(out, N ? N : 1, err);
    if (r != PF_OK) return r;
    if (s->cap < N) {
        free(s->texel);
        free(s->w);
        free(s->g0);
        free(s->fv);
        s->texel = malloc(sizeof(uint32_t) * N);
        s->w = malloc(sizeof(double) * N);
        s->g0 = malloc(sizeof(double) * N);
        s->fv = malloc(sizeof(float) * N);
        s->cap = s->texel && s->w && s->g0 && s->fv ? N : 0;
        if (!s->cap) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u chains", N);
    }
    r = gi_rsm_set_geometry_moved(&s->rsm, in->motion, err); /* moved geometry: the RSMs are drawn again */
    if (r == PF_OK) r = gi_rsm_set_update(&s->rsm, in->scene, in->area, in->rt, in->jobs, err);
    float diag = pf_v3_length(pf_v3_sub(in->scene->bounds_max, in->scene->bounds_min));
    if (r == PF_OK) r = gi_importance_update(&s->imp, &s->rsm, in->gbuf, diag, in->simd, in->jobs, err);
    if (r != PF_OK) return r;
    if (s->rsm.texel_count > 0 && N > 0) {
        gi__chains_ctx c = {s, N};
        pf_jobs_parallel_for(in->jobs, gi__tcas_chain_job, &c, N, 0);
        gi__tcas_weights(s, N);
        gi__tcas_make_vpls(s, in->scene, N, out);
    }
    return gi_vpl_mark_moved(out, &s->prev, err);
}

/* ------------------------------------------------------- the view */

/* Where RSM texel t is drawn: every face of every map is one square cell of
 * a grid (cells across, cell pixels a side, from (ox, oy)). */
static int gi__tcas_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__tcas_state *s = state;
    if (!s) return 0;
    const gi_rsm_set *R = &s->rsm;
    const gi_importance *im = &s->imp;
    gi_importance_canvas cv;
    if (!gi_importance_canvas_draw(&cv, R, im, c, rgb)) return 0;
    static const uint8_t white[3] = {255, 255, 255}, cyan[3] = {40, 220, 230}, yellow[3] = {255, 230, 0};
    uint32_t N = c->vpls->count < s->cap ? c->vpls->count : s->cap;
    float x, y;
    for (uint32_t j = 0; j < N; j++) {
        gi_importance_canvas_texel_xy(&cv, R, s->texel[j], &x, &y);
        c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, white);
    }
    if (N) { /* the chosen chain, replayed */
        uint32_t j = c->vpl % N;
        double q, gv = 0.0;
        uint32_t v = 0;
        float px = 0.0f, py = 0.0f;
        for (uint32_t k = 0; k < s->M; k++) {
            uint32_t h = gi_imh_index(j, k, N, s->M);
            uint32_t vn = gi_domain_texel(&im->domain, gi_halton(h, 2), gi_halton(h, 3), gi_halton(h, 5), &q);
            double gn = (double)im->f[vn] / q;
            gi_importance_canvas_texel_xy(&cv, R, vn, &x, &y);
            c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, cyan);
            if (k == 0 || gv == 0.0 || gn >= gi_halton(h, 7) * gv) { /* accepted (k = 0: the start) */
                if (k > 0) c->line(c, rgb, (int)floorf(px), (int)floorf(py), (int)floorf(x), (int)floorf(y), yellow);
                v = vn, gv = gn, px = x, py = y;
            }
        }
        gi_importance_canvas_texel_xy(&cv, R, v, &x, &y);
        c->line(c, rgb, (int)floorf(x) - 5, (int)floorf(y) - 5, (int)floorf(x) + 5, (int)floorf(y) + 5, yellow);
        c->line(c, rgb, (int)floorf(x) - 5, (int)floorf(y) + 5, (int)floorf(x) + 5, (int)floorf(y) - 5, yellow);
        char text[120];
        snprintf(text, sizeof text, "%u RSM faces, %u chains of M = %u; chain %u: proposals cyan, accepted yellow",
                 cv.faces, N, s->M, j);
        c->text(c, rgb, 4, 2, text, white);
    }
    c->legend(c, rgb, "importance f (Eq. 1-2)", cv.lo, cv.hi, 1);
    return 1;
}

static uint32_t gi__rsm_bounce(const void *state, const gi_vpl *v, uint32_t bounces)
{
    (void)state, (void)v, (void)bounces;
    return 1; /* RSM texels: surfaces the lights see directly */
}

const gi_vpl_method gi_method_tcas = {
    .name = "tcas",
    .paper = "Independent Metropolis-Hastings RSM sampling, TCAS (Barak 2013 Sec. 4, Algorithm 1)",
    .create = gi__tcas_create,
    .update = gi__tcas_update,
    .destroy = gi__tcas_destroy,
    .parts = NULL,
    .why = "VPLs should follow where they light what the camera sees, but resampling them afresh each frame makes "
           "them jump, so each VPL is the end of an Independent Metropolis-Hastings chain on fixed Halton numbers "
           "and moves only when the importance changes (Barak 2013 Sec. 4.3)",
    .view_caption = "the RSM texels' importance f (Eq. 1-2), each chain's final sample (white) and the chosen VPL's "
                    "chain: its M proposals (cyan) and the samples it accepted (yellow, Algorithm 1)",
    .view = gi__tcas_view,
    .bounce = gi__rsm_bounce,
};
