/* gi_mir: the MIR-style comparison baseline of Hedman et al. 2017, Sec. 5.1:
 * "MIR [Segovia et al. 2007] relies on light paths that are distributed
 * according to the radiance they bring the camera, which the original
 * implementation generates using Metropolis Light Transport. [...] we
 * instead generate these paths by resampling paths from our path tracer.
 * We use a resampling rate of 256:1." The VPL set is built from scratch,
 * independently, every frame (no temporal coherence: every VPL is `moved`
 * every frame; that is the point of the baseline).
 *
 * Per frame (each step a function below):
 *   1. camera points      gi__mir_camera_points: P points of the G-buffer
 *                         (in->gbuf, the directly visible surfaces), one
 *                         jittered pixel per cell of a grid over the image,
 *                         new jitter every frame; empty pixels are skipped.
 *   2. candidate VPLs     gi__mir_trace_candidates: M = ratio x budget
 *                         candidates from light paths exactly as Instant
 *                         Radiosity builds them (gi_ir.c: light chosen by
 *                         power, area lights included, a VPL at every
 *                         diffuse hit, intensity Phi albedo / pi, Russian
 *                         roulette by albedo, divided by the paths started),
 *                         with random numbers hashed from (path, frame,
 *                         vertex, dimension) instead of the fixed Halton
 *                         sequence, so every frame is independent.
 *   3. image contribution gi__mir_weigh_candidates: for candidate c,
 *                         g_c = 1/E sum_j lum(albedo_j)/pi min(G(x_j, y_c), b) V(x_j, y_c)
 *                         over E camera points x_j drawn uniformly from step 1
 *                         (V an Embree shadow ray; G = cos cos / r^2 bounded
 *                         by the frame's default clamp b = 400 / diagonal^2),
 *                         and the resampling target
 *                           p^_c = lum(I_c) ((1 - d) g_c / g_mean + d)
 *                         with g_mean the lum(I)-weighted mean of g and d the
 *                         defensive fraction (a candidate whose E rays all
 *                         missed may still light the image: without d it
 *                         could never be chosen and the estimate would be
 *                         biased).
 *   4. resample           gi__mir_resample: `budget` VPLs from the M
 *                         candidates with probability q_c = p^_c / S
 *                         (S = sum p^), systematic resampling (one uniform
 *                         number per frame, N equally spaced points on the
 *                         CDF, expected count N q_c per candidate). A chosen
 *                         candidate's intensity becomes I_c / (N q_c), so
 *                         the resampled set estimates the same indirect light
 *                         as the candidates (unbiased; Talbot's resampled
 *                         importance sampling with the weights folded into
 *                         the intensity). Units are gi_ir.c's exactly.
 *
 * Parameters (--param KEY=VALUE): ratio (candidates per VPL, default 256,
 * the paper's 256:1), points (camera points P, default 1024), evals (camera
 * points per candidate E, 1..8, default 8), defensive (d, 0..1, default
 * 0.3). The defaults of E and d were chosen by measurement (README): with
 * E = 4 or d = 0.1 the weight estimate's noise gives single VPLs several
 * times the mean intensity (a candidate that the camera rays missed but that
 * lies next to a visible wall keeps up to 1/d times its share) and the
 * Cornell box images were 2-3x noisier.
 *
 * Deviations: Segovia's MIR samples the paths with Metropolis; Hedman's
 * baseline resamples path-traced light paths, as here. The image-contribution
 * estimate (E camera points, bounded G, lum(albedo)), the defensive fraction
 * and the systematic resampling are this implementation's choices: the paper
 * does not say how the contribution was estimated.
 *
 * Determinism: steps 1 and 4 run in a fixed order on the calling thread;
 * steps 2 (light paths, in rounds appended in path order) and 3 are
 * parallel loops whose items write disjoint slots, reduced in index order
 * afterwards. Random numbers hash stable ids only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_area.h"
#include "gi_light.h"
#include "pf_random.h"
#include "gi_lightpath.h"
#include "gi_vpl.h"

#define GI__MIR_TAG_CAM 0x4d495201u  /* stream tags for pf_random */
#define GI__MIR_TAG_EVAL 0x4d495202u
#define GI__MIR_TAG_RES 0x4d495203u
#define GI__MIR_MAX_CANDIDATES (1u << 26)
#define GI__MIR_MAX_EVALS 8u

typedef struct gi__mir_state {
    uint32_t ratio, points, evals;
    float defensive;
    /* candidates (grown once to ratio x budget) */
    uint32_t cap, count;
    gi_vpl *cand;
    float *g;   /* image contribution estimate per candidate */
    /* light-path scratch of one round: GI__MIR_ROUND paths x B VPLs */
    gi_vpl *scratch;
    uint8_t *path_n;
    uint32_t scratch_b;
    /* camera points */
    uint32_t pcap, pcount;
    pf_vec3 *xp, *xn, *xg; /* position, shading normal, geometric normal (turned to the camera) */
    float *xa;             /* lum(albedo) / pi */
} gi__mir_state;

static pf_result gi__mir_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"ratio", "points", "evals", "defensive", NULL};
    *state = NULL;
    pf_result r = gi_params_check(params, "mir", known, err);
    if (r != PF_OK) return r;
    gi__mir_state *s = calloc(1, sizeof *s);
    if (!s) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    s->ratio = 256;
    s->points = 1024;
    s->evals = 8;
    s->defensive = 0.3f;
    if ((r = gi_param_u32(params, "ratio", 1, 4096, &s->ratio, err)) != PF_OK ||
        (r = gi_param_u32(params, "points", 1, 1u << 20, &s->points, err)) != PF_OK ||
        (r = gi_param_u32(params, "evals", 1, GI__MIR_MAX_EVALS, &s->evals, err)) != PF_OK ||
        (r = gi_param_f32(params, "defensive", 0.0f, 1.0f, &s->defensive, err)) != PF_OK) {
        free(s);
        return r;
    }
    *state = s;
    return PF_OK;
}

static void gi__mir_destroy(void *state)
{
    gi__mir_state *s = state;
    if (!s) return;
    free(s->cand);
    free(s->g);
    free(s->scratch);
    free(s->path_n);
    free(s->xp);
    free(s->xn);
    free(s->xg);
    free(s->xa);
    free(s);
}


/* ---------------------------------------------------------- 1. camera points */

/* A grid of about `points` cells with the image's aspect: gx x gy. */
static void gi__mir_grid(const gi__mir_state *s, uint32_t W, uint32_t H, uint32_t *gx, uint32_t *gy)
{
    uint32_t x = (uint32_t)ceil(sqrt((double)s->points * W / H));
    if (x < 1) x = 1;
    if (x > W) x = W;
    uint32_t y = (s->points + x - 1) / x;
    if (y > H) y = H;
    *gx = x;
    *gy = y;
}

static void gi__mir_camera_points(gi__mir_state *s, const gi_vpl_inputs *in)
{
    const rs_gbuffer *g = in->gbuf;
    uint32_t W = g->width, H = g->height, gx, gy;
    gi__mir_grid(s, W, H, &gx, &gy);
    s->pcount = 0;
    for (uint32_t cy = 0; cy < gy; cy++)
        for (uint32_t cx = 0; cx < gx; cx++) {
            uint32_t cell = cy * gx + cx;
            uint32_t x0 = (uint32_t)((uint64_t)cx * W / gx), x1 = (uint32_t)((uint64_t)(cx + 1) * W / gx);
            uint32_t y0 = (uint32_t)((uint64_t)cy * H / gy), y1 = (uint32_t)((uint64_t)(cy + 1) * H / gy);
            if (x1 <= x0 || y1 <= y0) continue;
            uint32_t x = x0 + (uint32_t)(pf_random(cell, in->frame, GI__MIR_TAG_CAM, 0) * (float)(x1 - x0));
            uint32_t y = y0 + (uint32_t)(pf_random(cell, in->frame, GI__MIR_TAG_CAM, 1) * (float)(y1 - y0));
            if (x >= x1) x = x1 - 1;
            if (y >= y1) y = y1 - 1;
            size_t p = (size_t)y * W + x;
            if (g->prim[p] == RS_GBUFFER_EMPTY) continue;
            pf_vec3 n = pf_v3(g->nrm_x[p], g->nrm_y[p], g->nrm_z[p]);
            pf_vec3 ng = pf_scene_face_normal(in->scene, g->prim[p]);
            if (pf_v3_dot(ng, n) < 0.0f) ng = pf_v3_scale(ng, -1.0f);
            uint32_t k = s->pcount++;
            s->xp[k] = pf_v3(g->pos_x[p], g->pos_y[p], g->pos_z[p]);
            s->xn[k] = n;
            s->xg[k] = ng;
            s->xa[k] = pf_luminance(pf_v3(g->alb_r[p], g->alb_g[p], g->alb_b[p])) * PF_INV_PI;
        }
}

/* ---------------------------------------------------------- 2. candidates */

/* Random number of light path `path` this frame: vertex 0 = emission. */
static float gi__u(const gi_vpl_inputs *in, uint32_t path, uint32_t vertex, uint32_t dim)
{
    return pf_random(path, in->frame, vertex, dim);
}

/* What every light path of a frame shares: the light CDF (entry np is the
 * area lights) and the scene's bounding disc for directional lights. */
typedef struct gi__mir_lights {
    const gi_vpl_inputs *in;
    gi_lightpath_lights lp;
    uint32_t B;
} gi__mir_lights;

/* Traces light path `path` (its numbers depend on (path, frame) only) and
 * writes its VPLs, at most B, to out; returns how many. Intensities are not
 * yet divided by the number of paths. */
static uint32_t gi__mir_trace_path(const gi__mir_lights *c, uint32_t path, gi_vpl *out)
{
    const gi_vpl_inputs *in = c->in;
    gi_lightpath_numbers u;
    u.choice = (double)gi__u(in, path, 0, 0);
    u.u1 = gi__u(in, path, 0, 1);
    u.u2 = gi__u(in, path, 0, 2);
    u.area = gi__u(in, path, 0, 3);
    u.a1 = gi__u(in, path, 0, 4);
    u.a2 = gi__u(in, path, 0, 5);
    pf_ray ray;
    pf_vec3 phi;
    gi_lightpath_emit(&c->lp, &u, &ray, &phi);
    uint32_t n = 0;
    for (uint32_t k = 0; k < c->B; k++) {
        gi_vpl *v = &out[n];
        pf_vec3 albedo;
        if (!gi_lightpath_hit(in->rt, ray, phi, v, &albedo)) break;
        n++;
        v->id = path;
        v->moved = 1;
        float rr = gi__u(in, path, k + 1, 2), a1 = gi__u(in, path, k + 1, 0), a2 = gi__u(in, path, k + 1, 1);
        if (!gi_lightpath_bounce(v, albedo, rr, a1, a2, &phi, &ray)) break;
    }
    return n;
}

/* Light paths are traced in rounds of GI__MIR_ROUND paths, GI__MIR_PATHS
 * per job item, each into its own slots of the state's scratch (B VPLs per
 * path); the rounds are then appended in path order until M candidates. The
 * result is exactly the serial loop's (a path's VPLs depend on its index
 * only; the last path may be cut short), for any thread count. */
#define GI__MIR_PATHS 64u
#define GI__MIR_ROUND (GI__MIR_PATHS * 32u)

typedef struct gi__mir_round_ctx {
    const gi__mir_lights *lights;
    gi__mir_state *s;
    uint32_t first, count; /* paths of this round */
} gi__mir_round_ctx;

static void gi__mir_trace_item(void *ctx, uint32_t item, uint32_t worker)
{
    (void)worker;
    gi__mir_round_ctx *c = ctx;
    uint32_t B = c->lights->B;
    for (uint32_t j = item * GI__MIR_PATHS; j < (item + 1) * GI__MIR_PATHS && j < c->count; j++)
        c->s->path_n[j] = (uint8_t)gi__mir_trace_path(c->lights, c->first + j, c->s->scratch + (size_t)j * B);
}

static void gi__mir_trace_candidates(gi__mir_state *s, const gi_vpl_inputs *in, uint32_t M)
{
    gi__mir_lights c;
    memset(&c, 0, sizeof c);
    c.in = in;
    c.B = in->bounces ? in->bounces : 3;
    s->count = 0;
    gi_lightpath_lights_init(&c.lp, in->scene, in->area);
    if (c.lp.nl == 0 || !(c.lp.total > 0.0)) return;
    uint64_t limit = (uint64_t)M * 64u, paths = 0;
    while (s->count < M && paths < limit) {
        gi__mir_round_ctx rc = {&c, s, (uint32_t)paths, 0};
        rc.count = limit - paths < GI__MIR_ROUND ? (uint32_t)(limit - paths) : GI__MIR_ROUND;
        uint32_t items = (rc.count + GI__MIR_PATHS - 1) / GI__MIR_PATHS;
        if (in->jobs) pf_jobs_parallel_for(in->jobs, gi__mir_trace_item, &rc, items, 1);
        else
            for (uint32_t i = 0; i < items; i++) gi__mir_trace_item(&rc, i, 0);
        for (uint32_t j = 0; j < rc.count && s->count < M; j++) {
            paths++;
            for (uint32_t k = 0; k < s->path_n[j] && s->count < M; k++)
                s->cand[s->count++] = s->scratch[(size_t)j * c.B + k];
        }
    }
    float inv = 1.0f / (float)paths;
    for (uint32_t i = 0; i < s->count; i++) s->cand[i].intensity = pf_v3_scale(s->cand[i].intensity, inv);
}

/* ---------------------------------------------------------- 3. image contribution */

typedef struct gi__mir_weigh_ctx {
    gi__mir_state *s;
    const gi_vpl_inputs *in;
    float b; /* bound on G */
} gi__mir_weigh_ctx;

#define GI__MIR_CHUNK 256u

static void gi__mir_weigh_chunk(void *ctx, uint32_t item, uint32_t worker)
{
    (void)worker;
    gi__mir_weigh_ctx *c = ctx;
    gi__mir_state *s = c->s;
    uint32_t end = (item + 1) * GI__MIR_CHUNK < s->count ? (item + 1) * GI__MIR_CHUNK : s->count;
    for (uint32_t i = item * GI__MIR_CHUNK; i < end; i++) {
        const gi_vpl *v = &s->cand[i];
        pf_ray rays[GI__MIR_MAX_EVALS];
        float w[GI__MIR_MAX_EVALS];
        uint32_t m = 0;
        for (uint32_t j = 0; j < s->evals; j++) {
            uint32_t k = (uint32_t)(pf_random(i, c->in->frame, GI__MIR_TAG_EVAL, j) * (float)s->pcount);
            if (k >= s->pcount) k = s->pcount - 1;
            gi_light_sample ls;
            pf_vec3 d = pf_v3_sub(v->pos, s->xp[k]);
            float r2 = pf_v3_dot(d, d);
            if (!(r2 > 0.0f)) continue;
            float r = sqrtf(r2);
            ls.wi = pf_v3_scale(d, 1.0f / r);
            ls.distance = r;
            float cx = pf_v3_dot(s->xn[k], ls.wi), cy = -pf_v3_dot(v->nrm, ls.wi);
            if (!(cx > 0.0f) || !(cy > 0.0f)) continue;
            w[m] = s->xa[k] * fminf(cx * cy / r2, c->b);
            rays[m++] = gi_light_shadow_ray(&ls, s->xp[k], s->xg[k]);
        }
        float g = 0.0f;
        if (m > 0) {
            uint8_t occ[GI__MIR_MAX_EVALS];
            pf_rt_occluded(c->in->rt, rays, occ, m);
            for (uint32_t j = 0; j < m; j++)
                if (!occ[j]) g += w[j];
        }
        s->g[i] = g / (float)s->evals;
    }
}

static void gi__mir_weigh_candidates(gi__mir_state *s, const gi_vpl_inputs *in)
{
    const pf_scene *sc = in->scene;
    float diag2 = pf_v3_dot(pf_v3_sub(sc->bounds_max, sc->bounds_min), pf_v3_sub(sc->bounds_max, sc->bounds_min));
    gi__mir_weigh_ctx c = {s, in, 400.0f / fmaxf(diag2, 1e-30f)};
    if (s->pcount == 0) { /* nothing visible: the target falls back to lum(I) */
        for (uint32_t i = 0; i < s->count; i++) s->g[i] = 0.0f;
        return;
    }
    uint32_t chunks = (s->count + GI__MIR_CHUNK - 1) / GI__MIR_CHUNK;
    if (in->jobs) pf_jobs_parallel_for(in->jobs, gi__mir_weigh_chunk, &c, chunks, 1);
    else
        for (uint32_t i = 0; i < chunks; i++) gi__mir_weigh_chunk(&c, i, 0);
}

/* ---------------------------------------------------------- 4. resample */

static void gi__mir_resample(gi__mir_state *s, const gi_vpl_inputs *in, gi_vpl_set *out, uint32_t N)
{
    /* g_mean: the lum(I)-weighted mean of g (index order) */
    double sl = 0.0, slg = 0.0;
    for (uint32_t i = 0; i < s->count; i++) {
        double l = pf_luminance(s->cand[i].intensity);
        sl += l;
        slg += l * s->g[i];
    }
    if (!(sl > 0.0)) return;
    double gmean = slg / sl, d = s->defensive;
    if (!(gmean > 0.0)) d = 1.0; /* no candidate reached a camera point */
    /* p^_c into g (reused), and S */
    double S = 0.0;
    for (uint32_t i = 0; i < s->count; i++) {
        double p = pf_luminance(s->cand[i].intensity) * ((1.0 - d) * (d < 1.0 ? s->g[i] / gmean : 0.0) + d);
        s->g[i] = (float)p;
        S += s->g[i];
    }
    if (!(S > 0.0)) return;
    /* systematic resampling: points (k + u) S / N on the CDF */
    double u = pf_random(0, in->frame, GI__MIR_TAG_RES, 0), acc = 0.0;
    uint32_t i = 0;
    for (uint32_t k = 0; k < N; k++) {
        double x = ((double)k + u) * S / N;
        while (i + 1 < s->count && (acc + s->g[i] <= x || !(s->g[i] > 0.0f))) acc += s->g[i++];
        if (!(s->g[i] > 0.0f)) break; /* only zero weights left (rounding at the end) */
        gi_vpl *v = &out->v[out->count++];
        *v = s->cand[i];
        /* I_c / (N q_c), q_c = p^_c / S */
        v->intensity = pf_v3_scale(v->intensity, (float)(S / ((double)N * s->g[i])));
        v->id = k;
        v->moved = 1; /* independent every frame */
    }
}

static pf_result gi__mir_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__mir_state *s = state;
    out->count = 0;
    if (!in->gbuf)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method mir: needs the frame's G-buffer (camera-visible points)");
    uint32_t N = in->budget;
    if ((uint64_t)N * s->ratio > GI__MIR_MAX_CANDIDATES)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method mir: %u VPLs x ratio %u exceeds %u candidates", N, s->ratio,
                            GI__MIR_MAX_CANDIDATES);
    uint32_t M = N * s->ratio;
    pf_result r = gi_vpl_set_reserve(out, N ? N : 1, err);
    if (r != PF_OK) return r;
    if (M > s->cap) {
        gi_vpl *c = realloc(s->cand, sizeof *c * M);
        if (c) s->cand = c;
        float *g = realloc(s->g, sizeof *g * M);
        if (g) s->g = g;
        if (!c || !g) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "--method mir: out of memory for %u candidates", M);
        s->cap = M;
    }
    uint32_t gx, gy;
    gi__mir_grid(s, in->gbuf->width ? in->gbuf->width : 1, in->gbuf->height ? in->gbuf->height : 1, &gx, &gy);
    if (gx * gy > s->pcap) {
        uint32_t P = gx * gy;
        free(s->xp), free(s->xn), free(s->xg), free(s->xa);
        s->xp = malloc(sizeof(pf_vec3) * P);
        s->xn = malloc(sizeof(pf_vec3) * P);
        s->xg = malloc(sizeof(pf_vec3) * P);
        s->xa = malloc(sizeof(float) * P);
        s->pcap = 0;
        if (!s->xp || !s->xn || !s->xg || !s->xa)
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "--method mir: out of memory for camera points");
        s->pcap = P;
    }
    uint32_t B = in->bounces ? in->bounces : 3;
    if (B > 255) return pf_error_set(err, PF_ERR_ARGUMENT, "--method mir: at most 255 bounces");
    if (B > s->scratch_b) {
        free(s->scratch);
        free(s->path_n);
        s->scratch = malloc(sizeof(gi_vpl) * GI__MIR_ROUND * B);
        s->path_n = malloc(GI__MIR_ROUND);
        s->scratch_b = 0;
        if (!s->scratch || !s->path_n)
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "--method mir: out of memory for light paths");
        s->scratch_b = B;
    }
    if (N == 0) return PF_OK;
    gi__mir_camera_points(s, in);
    gi__mir_trace_candidates(s, in, M);
    gi__mir_weigh_candidates(s, in);
    gi__mir_resample(s, in, out, N);
    return PF_OK;
}

/* ------------------------------------------------------------ the view */

/* Steps 1-4 over the image: the camera points (grey), the candidates the
 * camera sees, in heat colours by their image-contribution estimate g
 * (step 3; those the camera does not see are left out), and the VPLs the
 * resampling kept (white boxes). */
static int gi__mir_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__mir_state *s = state;
    if (!s || !s->count || !s->g) return 0;
    static const uint8_t grey[3] = {150, 150, 150}, white[3] = {255, 255, 255};
    c->background(c, rgb);
    float x, y, lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < s->pcount; i++)
        if (c->project(c, s->xp[i], &x, &y)) c->fill(c, rgb, (int)floorf(x), (int)floorf(y), 1, 1, grey);
    for (uint32_t i = 0; i < s->count; i++) lo = fminf(lo, s->g[i]), hi = fmaxf(hi, s->g[i]);
    if (!(lo <= hi)) lo = hi = 0.0f;
    uint32_t seen = 0;
    for (uint32_t i = 0; i < s->count; i++) {
        if (!c->project(c, s->cand[i].pos, &x, &y) || !c->visible(c, s->cand[i].pos)) continue;
        uint8_t col[3];
        c->heat(hi > lo ? sqrtf((s->g[i] - lo) / (hi - lo)) : 1.0f, col);
        c->fill(c, rgb, (int)floorf(x), (int)floorf(y), 1, 1, col);
        seen++;
    }
    for (uint32_t i = 0; i < c->vpls->count; i++) {
        const gi_vpl *v = &c->vpls->v[i];
        if (!c->project(c, v->pos, &x, &y) || !c->visible(c, v->pos)) continue;
        c->line(c, rgb, (int)floorf(x) - 2, (int)floorf(y) - 2, (int)floorf(x) + 2, (int)floorf(y) - 2, white);
        c->line(c, rgb, (int)floorf(x) - 2, (int)floorf(y) + 2, (int)floorf(x) + 2, (int)floorf(y) + 2, white);
        c->line(c, rgb, (int)floorf(x) - 2, (int)floorf(y) - 2, (int)floorf(x) - 2, (int)floorf(y) + 2, white);
        c->line(c, rgb, (int)floorf(x) + 2, (int)floorf(y) - 2, (int)floorf(x) + 2, (int)floorf(y) + 2, white);
    }
    char text[128];
    snprintf(text, sizeof text, "%u camera points (grey), %u candidates (%u seen), %u VPLs kept (white)", s->pcount,
             s->count, seen, c->vpls->count);
    c->text(c, rgb, 4, 2, text, white);
    c->legend(c, rgb, "image contribution g", lo, hi, 1);
    return 1;
}

const gi_vpl_method gi_method_mir = {
    .name = "mir",
    .paper = "MIR-style resampled light paths (Hedman 2017 Sec. 5.1)",
    .create = gi__mir_create,
    .update = gi__mir_update,
    .destroy = gi__mir_destroy,
    .parts = NULL,
    .view_caption = "the camera points (grey), the light-path candidates by their estimated image contribution "
                    "(heat) and the VPLs the 256:1 resampling kept (white boxes)",
    .view = gi__mir_view,
    .why = "most light paths from the lights end where the camera never looks, so MIR traces many and keeps the "
           "ones that contribute most to the image, resampled 256:1 (Hedman 2017 Sec. 5.1's baseline)",
};
