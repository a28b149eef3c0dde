/* gi_atrous: Laine's box, then variance-guided edge-avoiding a-trous levels
 * (Dammertz et al. 2010; Schied et al. 2017 Sec. 4.3-4.4); see gi_atrous.h.
 * The per-pixel functions here are the reference the SIMD kernels
 * (gi_indirect_kernels.c) repeat for the interior of each row. */
#include "gi_atrous.h"

#include <string.h>

#include "gi_atrous_math.h"
#include "gi_indirect_kernels.h"

/* two gi_atrous_planes (r, g, b, lum, var) and the luminance test's scales */
size_t gi_atrous_scratch_floats(uint32_t w, uint32_t h) { return (size_t)w * h * (5 + 5 + 1); }

typedef struct gi__atrous_pass {
    const gi_atrous_io *io;
    gi_atrous_in lv;           /* the level (src, dst, inv_sd, step, ...) */
    gi_filter_in box;          /* the box pass's inputs */
} gi__atrous_pass;

/* ------------------------------------------------------------- box pass */

static void gi__atrous_box_pixel(const gi_filter_in *in, int x, int y, const gi_atrous_planes *o)
{
    const rs_gbuffer *g = in->g;
    const int W = (int)in->w, H = (int)in->h, n = (int)in->n, m = (int)in->m;
    const size_t i = (size_t)y * in->w + (size_t)x;
    const float *c = in->combined + 3 * i;
    float r = c[0], gg = c[1], b = c[2], var = 0.0f;
    if (g->prim[i] != RS_GBUFFER_EMPTY) {
        const float px = g->pos_x[i], py = g->pos_y[i], pz = g->pos_z[i];
        const float nx = g->nrm_x[i], ny = g->nrm_y[i], nz = g->nrm_z[i];
        float ar = 0.0f, ag = 0.0f, ab = 0.0f, l1 = 0.0f, l2 = 0.0f, cnt = 0.0f;
        for (int dy = 0; dy < m; dy++) {
            int ty = y + dy - m / 2;
            if (ty < 0 || ty >= H) continue;
            for (int dx = 0; dx < n; dx++) {
                int tx = x + dx - n / 2;
                if (tx < 0 || tx >= W) continue;
                size_t j = (size_t)ty * in->w + (size_t)tx;
                if (g->prim[j] == RS_GBUFFER_EMPTY) continue;
                float ddx = g->pos_x[j] - px, ddy = g->pos_y[j] - py, ddz = g->pos_z[j] - pz;
                float d2 = ddx * ddx + ddy * ddy + ddz * ddz;
                float nd = nx * g->nrm_x[j] + ny * g->nrm_y[j] + nz * g->nrm_z[j];
                float dp = ddx * nx + ddy * ny + ddz * nz; /* the SIMD path's order */
                if (!(gi_filter_near(in, d2, dp * dp) && nd > in->beta)) continue;
                const float *e = in->combined + 3 * j;
                float l = gi_atrous_lum(e[0], e[1], e[2]);
                ar += e[0], ag += e[1], ab += e[2];
                l1 += l, l2 += l * l;
                cnt += 1.0f;
            }
        }
        if (cnt > 0.0f) {
            r = ar / cnt, gg = ag / cnt, b = ab / cnt;
            float mean = l1 / cnt, v = l2 / cnt - mean * mean;
            /* the variance of the mean of cnt samples */
            var = cnt > 1.0f && v > 0.0f ? v / (cnt - 1.0f) : 0.0f;
        }
    }
    o->r[i] = r, o->g[i] = gg, o->b[i] = b, o->lum[i] = gi_atrous_lum(r, gg, b), o->var[i] = var;
}

static void gi__atrous_box_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__atrous_pass *ps = p;
    const gi_filter_in *in = &ps->box;
    const gi_indirect_kernels *kt = ps->io->kt;
    const int W = (int)in->w, n = (int)in->n, lanes = kt ? (int)kt->width : 1;
    /* SIMD for the runs whose windows lie on screen horizontally: [x0, x1) */
    const int x0 = n / 2, x1 = W - (n - 1 - n / 2);
    int x = 0;
    if (kt && x1 - x0 >= lanes) {
        for (; x < x0; x++) gi__atrous_box_pixel(in, x, (int)y, &ps->lv.dst);
        for (; x < x1; x += lanes) {
            /* the last run ends at x1, overlapping the one before it: those
             * pixels get the same values again */
            int xs = x + lanes <= x1 ? x : x1 - lanes;
            kt->atrous_box(in, xs, (int)y, &ps->lv.dst);
        }
        x = x1;
    }
    for (; x < W; x++) gi__atrous_box_pixel(in, x, (int)y, &ps->lv.dst);
}

/* ------------------------------------------------- the variance's blur */

/* The luminance test's scale of each pixel, 1 / (sigma_l sqrt(g3x3(var)) +
 * eps), into inv_sd: g3x3 the (1 2 1)^2 / 16 Gaussian of src.var (SVGF Sec.
 * 4.4), off-screen taps left out (the weights renormalised). */
static float gi__atrous_blur_pixel(const gi_atrous_in *lv, int x, int y)
{
    const int W = (int)lv->w, H = (int)lv->h;
    const float *v = lv->src.var, *h = gi_atrous_h;
    float s = 0.0f, ws = 0.0f;
    for (int a = 0; a < 3; a++) {
        int ty = y + a - 1;
        if (ty < 0 || ty >= H) continue;
        for (int b = 0; b < 3; b++) {
            int tx = x + b - 1;
            if (tx < 0 || tx >= W) continue;
            float w = h[a] * h[b];
            s += w * v[(size_t)ty * lv->w + (size_t)tx];
            ws += w;
        }
    }
    return 1.0f / (lv->sigma_l * sqrtf(s / ws) + GI_ATROUS_EPS);
}

static void gi__atrous_blur_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi_atrous_in *lv = &((const gi__atrous_pass *)p)->lv;
    const int W = (int)lv->w, H = (int)lv->h, yy = (int)y;
    float *out = (float *)lv->inv_sd + (size_t)y * lv->w;
    if (yy < 1 || yy + 1 >= H || W < 3) { /* every pixel has off-screen taps */
        for (int x = 0; x < W; x++) out[x] = gi__atrous_blur_pixel(lv, x, yy);
        return;
    }
    /* inside the row every tap is on screen: the weights sum to 1 exactly
     * (they are dyadic), so this is gi__atrous_blur_pixel's value without
     * its tests, in its order */
    const float *h = gi_atrous_h, sl = lv->sigma_l;
    const float *r0 = lv->src.var + (size_t)(yy - 1) * lv->w, *r1 = r0 + lv->w, *r2 = r1 + lv->w;
    out[0] = gi__atrous_blur_pixel(lv, 0, yy);
    for (int x = 1; x < W - 1; x++) {
        float s = 0.0f;
        s += h[0] * h[0] * r0[x - 1], s += h[0] * h[1] * r0[x], s += h[0] * h[2] * r0[x + 1];
        s += h[1] * h[0] * r1[x - 1], s += h[1] * h[1] * r1[x], s += h[1] * h[2] * r1[x + 1];
        s += h[2] * h[0] * r2[x - 1], s += h[2] * h[1] * r2[x], s += h[2] * h[2] * r2[x + 1];
        out[x] = 1.0f / (sl * sqrtf(s) + GI_ATROUS_EPS);
    }
    out[W - 1] = gi__atrous_blur_pixel(lv, W - 1, yy);
}

/* ------------------------------------------------------ a-trous levels */

static void gi__atrous_level_pixel(const gi_atrous_in *lv, int x, int y)
{
    const rs_gbuffer *g = lv->g;
    const int W = (int)lv->w, H = (int)lv->h, s = lv->step;
    const size_t i = (size_t)y * lv->w + (size_t)x;
    const gi_atrous_planes *src = &lv->src, *dst = &lv->dst;
    if (g->prim[i] == RS_GBUFFER_EMPTY) {
        dst->r[i] = src->r[i], dst->g[i] = src->g[i], dst->b[i] = src->b[i];
        dst->lum[i] = src->lum[i], dst->var[i] = src->var[i];
        return;
    }
    const float px = g->pos_x[i], py = g->pos_y[i], pz = g->pos_z[i];
    const float nx = g->nrm_x[i], ny = g->nrm_y[i], nz = g->nrm_z[i];
    const float li = src->lum[i];
    const float inv_sd = lv->inv_sd[i];
    float ar = 0.0f, ag = 0.0f, ab = 0.0f, ws = 0.0f, vs = 0.0f;
    for (int a = 0; a < 3; a++) {
        int ty = y + (a - 1) * s;
        if (ty < 0 || ty >= H) continue;
        for (int b = 0; b < 3; b++) {
            int tx = x + (b - 1) * s;
            if (tx < 0 || tx >= W) continue;
            size_t j = (size_t)ty * lv->w + (size_t)tx;
            if (g->prim[j] == RS_GBUFFER_EMPTY) continue;
            float dp = nx * (g->pos_x[j] - px) + ny * (g->pos_y[j] - py) + nz * (g->pos_z[j] - pz);
            float wn = gi_atrous_pow128(nx * g->nrm_x[j] + ny * g->nrm_y[j] + nz * g->nrm_z[j]);
            /* the luminance test's scale: sigma_l standard deviations of the larger of the two pixels'
             * blurred variances (symmetric, so that a bright noisy pixel does not take in its dark
             * neighbours while they refuse it: that darkened the image by 1-3%) */
            float inv_dl = inv_sd < lv->inv_sd[j] ? inv_sd : lv->inv_sd[j];
            float t = fabsf(dp) * lv->inv_sigma_p + fabsf(li - src->lum[j]) * inv_dl;
            float w = gi_atrous_h[a] * gi_atrous_h[b] * wn * gi_atrous_expneg(t);
            ar += w * src->r[j], ag += w * src->g[j], ab += w * src->b[j];
            ws += w;
            vs += w * w * src->var[j];
        }
    }
    /* the centre tap's weight is h(0)^2 |n|^256 > 0 for a unit normal; a
     * degenerate normal keeps the pixel */
    if (!(ws > 0.0f)) {
        dst->r[i] = src->r[i], dst->g[i] = src->g[i], dst->b[i] = src->b[i];
        dst->lum[i] = src->lum[i], dst->var[i] = src->var[i];
        return;
    }
    const float inv = 1.0f / ws;
    const float r = ar * inv, gg = ag * inv, b = ab * inv;
    dst->r[i] = r, dst->g[i] = gg, dst->b[i] = b;
    dst->lum[i] = gi_atrous_lum(r, gg, b);
    dst->var[i] = vs * inv * inv;
}

static void gi__atrous_level_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__atrous_pass *ps = p;
    const gi_atrous_in *lv = &ps->lv;
    const gi_indirect_kernels *kt = ps->io->kt;
    const int W = (int)lv->w, s = lv->step, lanes = kt ? (int)kt->width : 1;
    /* SIMD for the runs whose taps lie on screen horizontally: [s, W - s),
     * the last run overlapping the one before it (as the box pass) */
    const int x0 = s, x1 = W - s;
    int x = 0;
    if (kt && x1 - x0 >= lanes) {
        for (; x < x0; x++) gi__atrous_level_pixel(lv, x, (int)y);
        for (; x < x1; x += lanes) kt->atrous_level(lv, x + lanes <= x1 ? x : x1 - lanes, (int)y);
        x = x1;
    }
    for (; x < W; x++) gi__atrous_level_pixel(lv, x, (int)y);
}

/* The last level's planes into the interleaved output. */
static void gi__atrous_out_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__atrous_pass *ps = p;
    const gi_atrous_planes *o = &ps->lv.dst;
    float *out = ps->io->out + 3 * (size_t)y * ps->lv.w;
    for (size_t x = 0, i = (size_t)y * ps->lv.w; x < ps->lv.w; x++, i++)
        out[3 * x] = o->r[i], out[3 * x + 1] = o->g[i], out[3 * x + 2] = o->b[i];
}

static gi_atrous_planes gi__atrous_planes_at(float *base, size_t px)
{
    gi_atrous_planes p = {base, base + px, base + 2 * px, base + 3 * px, base + 4 * px};
    return p;
}

void gi_atrous_run(pf_jobs *jobs, const gi_atrous_io *io)
{
    const size_t px = (size_t)io->w * io->h;
    gi_atrous_planes planes[2] = {gi__atrous_planes_at(io->scratch, px), gi__atrous_planes_at(io->scratch + 5 * px, px)};
    uint32_t levels = io->par.levels ? io->par.levels : GI_ATROUS_DEFAULT_LEVELS;
    if (levels > GI_ATROUS_MAX_LEVELS) levels = GI_ATROUS_MAX_LEVELS;
    gi__atrous_pass ps;
    memset(&ps, 0, sizeof ps);
    ps.io = io;
    ps.box = (gi_filter_in){io->combined, io->g, io->w, io->h, io->n, io->m, io->alpha2, io->beta, io->cap2};
    ps.lv.g = io->g;
    ps.lv.w = io->w, ps.lv.h = io->h;
    ps.lv.inv_sd = io->scratch + 10 * px;
    ps.lv.sigma_l = io->par.sigma_l > 0.0f ? io->par.sigma_l : GI_ATROUS_DEFAULT_SIGMA_L;
    ps.lv.inv_sigma_p = 1.0f / io->par.sigma_p;
    ps.lv.dst = planes[0];
    pf_jobs_parallel_for(jobs, gi__atrous_box_row, &ps, io->h, 4);
    for (uint32_t k = 0; k < levels; k++) {
        ps.lv.src = planes[k & 1];
        ps.lv.dst = planes[(k & 1) ^ 1];
        ps.lv.step = 1 << k;
        pf_jobs_parallel_for(jobs, gi__atrous_blur_row, &ps, io->h, 8);
        pf_jobs_parallel_for(jobs, gi__atrous_level_row, &ps, io->h, 4);
    }
    pf_jobs_parallel_for(jobs, gi__atrous_out_row, &ps, io->h, 16);
}
