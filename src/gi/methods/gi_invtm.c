/* gi_invtm: view-adaptive VPLs by the inverse transform method (Ritschel et
 * al. 2011; Barak, Bittner, Havran 2013 Sec. 4.2, the "InvTM" baseline).
 *
 * Per frame (the paper's outline):
 *   1. gi_rsm_set_update         a reflective shadow map per light (gi_rsm.h);
 *   2. gi_importance_update      the importance map f(v) over all RSM texels
 *                                from P camera points (Eq. 1-2);
 *   3. gi_invtm_build            the CDFs: "first constructed over all rows
 *                                of all IMs, then over the last column of
 *                                all IMs and finally, the values of all
 *                                lights/IMs are cumulated";
 *   4. gi__invtm_sample_vpls     N VPLs, VPL i from Halton index i + 1 (the
 *                                same numbers every frame), three binary
 *                                searches each (gi_invtm_sample), intensity
 *                                Phi_v / (pi N p(v)), p = f / sum f.
 * Parameters (--param): rsm=   RSM texels per side (per cube face),
 *                              default GI_RSM_DEFAULT_SIZE;
 *                       P=     camera points, default GI_IMPORTANCE_DEFAULT_P;
 *                       dims=  3 (default, the paper's r3: xi1 light, xi2
 *                              row, xi3 column) or 2 (r2: xi1 light and,
 *                              renormalised, row; xi2 column);
 *                       area_points= K, emitter points (faces) of the area
 *                              lights' RSM, default GI_RSM_DEFAULT_AREA_POINTS.
 * VPL i keeps slot i and id i; moved = position or normal changed.
 * Area lights (gi_area.h) have one RSM of K hemispherical faces after the
 * punctual lights' (gi_rsm_area.h, beyond the paper): it is one more
 * "light" of the sampling domain.
 *
 * Determinism: the CDF rows are summed in parallel, each row by one item in
 * texel order; the row and map prefix sums are serial; sampling is serial
 * in VPL order. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_importance.h"
#include "gi_vpl.h"

/* ------------------------------------------------------------ 3. CDF build */

typedef struct gi__cdf_ctx {
    gi_invtm_cdf *c;
    const float *f;
    uint32_t row_len; /* texels per row (all rows of a domain built from RSMs are equally long) */
    const gi_sample_domain *d;
} gi__cdf_ctx;

/* Item = one row of one map (rows are numbered over all maps in order):
 * its texels' inclusive prefix sum, in double. */
static void gi__invtm_row(void *p, uint32_t row, uint32_t worker)
{
    (void)worker;
    const gi__cdf_ctx *x = p;
    const gi_sample_domain *d = x->d;
    /* map of this row: rows are laid out map after map */
    uint32_t m = 0;
    while (m + 1 < d->maps && x->c->row_first[m + 1] <= row) m++;
    uint32_t r = row - x->c->row_first[m];
    uint32_t t0 = d->first[m] + r * d->cols[m];
    double acc = 0.0;
    for (uint32_t k = 0; k < d->cols[m]; k++) {
        acc += (double)x->f[t0 + k];
        x->c->texel_cdf[t0 + k] = acc;
    }
}

static pf_result gi__grow(void **p, uint32_t *cap, uint32_t need, size_t elem, pf_error *err)
{
    if (*cap >= need && *p) return PF_OK;
    void *q = realloc(*p, (size_t)(need ? need : 1) * elem);
    if (!q) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the InvTM CDF");
    *p = q;
    *cap = need;
    return PF_OK;
}

pf_result gi_invtm_build(gi_invtm_cdf *c, const gi_sample_domain *d, const float *f, pf_jobs *jobs, pf_error *err)
{
    uint32_t rows = 0;
    for (uint32_t m = 0; m < d->maps; m++) rows += d->rows[m];
    pf_result r;
    uint32_t mc = c->map_cap;
    if ((r = gi__grow((void **)&c->map_cdf, &mc, d->maps, sizeof(double), err)) != PF_OK) return r;
    mc = c->map_cap;
    if ((r = gi__grow((void **)&c->row_first, &mc, d->maps, sizeof(uint32_t), err)) != PF_OK) return r;
    c->map_cap = mc;
    if ((r = gi__grow((void **)&c->row_cdf, &c->row_cap, rows, sizeof(double), err)) != PF_OK) return r;
    if ((r = gi__grow((void **)&c->texel_cdf, &c->texel_cap, d->total, sizeof(double), err)) != PF_OK) return r;
    for (uint32_t m = 0, acc = 0; m < d->maps; m++) {
        c->row_first[m] = acc;
        acc += d->rows[m];
    }
    /* CDF over every row (parallel, one row per item) */
    gi__cdf_ctx x = {c, f, 0, d};
    if (jobs)
        pf_jobs_parallel_for(jobs, gi__invtm_row, &x, rows, 0);
    else
        for (uint32_t row = 0; row < rows; row++) gi__invtm_row(&x, row, 0);
    /* over the last column of every map (the rows' totals), then the maps */
    double total = 0.0;
    for (uint32_t m = 0; m < d->maps; m++) {
        double acc = 0.0;
        for (uint32_t rr = 0; rr < d->rows[m]; rr++) {
            acc += c->texel_cdf[d->first[m] + rr * d->cols[m] + d->cols[m] - 1];
            c->row_cdf[c->row_first[m] + rr] = acc;
        }
        total += acc;
        c->map_cdf[m] = total;
    }
    c->total = total;
    return PF_OK;
}

void gi_invtm_free(gi_invtm_cdf *c)
{
    free(c->map_cdf);
    free(c->row_cdf);
    free(c->texel_cdf);
    free(c->row_first);
    memset(c, 0, sizeof *c);
}

/* The first index i in [0, n) with cdf[i] > u (an inclusive prefix sum),
 * or the last index with positive mass when rounding puts u at the end. */
static uint32_t gi__upper_bound(const double *cdf, uint32_t n, double u)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] > u)
            hi = mid;
        else
            lo = mid + 1;
    }
    if (lo >= n) { /* u >= total: the last entry that adds mass */
        lo = n - 1;
        while (lo > 0 && cdf[lo] == cdf[lo - 1]) lo--;
    }
    return lo;
}

uint32_t gi_invtm_sample(const gi_invtm_cdf *c, const gi_sample_domain *d, int dims, double xi1, double xi2,
                         double xi3)
{
    /* 1st search: the light (map) */
    double u = xi1 * c->total;
    uint32_t m = gi__upper_bound(c->map_cdf, d->maps, u);
    double before = m ? c->map_cdf[m - 1] : 0.0, mass = c->map_cdf[m] - before;
    double xr = xi2, xc = xi3;
    if (dims == 2) { /* renormalise xi1 within the chosen map's interval */
        xr = mass > 0.0 ? (u - before) / mass : 0.0;
        xr = xr < 0.0 ? 0.0 : (xr >= 1.0 ? nextafter(1.0, 0.0) : xr);
        xc = xi2;
    }
    /* 2nd search: the row within the map */
    const double *rows = c->row_cdf + c->row_first[m];
    uint32_t row = gi__upper_bound(rows, d->rows[m], xr * rows[d->rows[m] - 1]);
    /* 3rd search: the column within the row */
    const double *texels = c->texel_cdf + d->first[m] + row * d->cols[m];
    uint32_t col = gi__upper_bound(texels, d->cols[m], xc * texels[d->cols[m] - 1]);
    return d->first[m] + row * d->cols[m] + col;
}

/* ------------------------------------------------------------------ method */

typedef struct gi__invtm_state {
    uint32_t dims;
    gi_rsm_set rsm;
    gi_importance imp;
    gi_invtm_cdf cdf;
    gi_vpl_set prev;
} gi__invtm_state;

static void gi__invtm_destroy(void *state)
{
    gi__invtm_state *s = state;
    if (!s) return;
    gi_rsm_set_free(&s->rsm);
    gi_importance_free(&s->imp);
    gi_invtm_free(&s->cdf);
    gi_vpl_set_free(&s->prev);
    free(s);
}

static pf_result gi__invtm_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"rsm", "P", "dims", "area_points", NULL};
    *state = NULL;
    pf_result r = gi_params_check(params, "invtm", known, err);
    uint32_t size = GI_RSM_DEFAULT_SIZE, P = GI_IMPORTANCE_DEFAULT_P, dims = 3, K = GI_RSM_DEFAULT_AREA_POINTS;
    if (r == PF_OK) r = gi_param_u32(params, "rsm", GI_RSM_MIN_SIZE, GI_RSM_MAX_SIZE, &size, err);
    if (r == PF_OK) r = gi_param_u32(params, "area_points", 1, GI_RSM_MAX_AREA_POINTS, &K, err);
    if (r == PF_OK) r = gi_param_u32(params, "P", 1, 1u << 20, &P, err);
    if (r == PF_OK) r = gi_param_u32(params, "dims", 2, 3, &dims, err);
    if (r != PF_OK) return r;
    gi__invtm_state *s = calloc(1, sizeof *s);
    if (!s) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    s->dims = dims;
    gi_rsm_set_init(&s->rsm, size);
    s->rsm.area_points = K;
    gi_importance_init(&s->imp, P);
    *state = s;
    return PF_OK;
}

/* 4. N VPLs from the same Halton numbers every frame. */
static void gi__invtm_sample_vpls(gi__invtm_state *s, uint32_t N, gi_vpl_set *out)
{
    const gi_sample_domain *d = &s->imp.domain;
    for (uint32_t i = 0; i < N; i++) {
        double xi1 = gi_halton(i + 1, 2), xi2 = gi_halton(i + 1, 3), xi3 = gi_halton(i + 1, 5);
        uint32_t t = gi_invtm_sample(&s->cdf, d, (int)s->dims, xi1, xi2, xi3);
        double p = (double)s->imp.f[t] / s->cdf.total; /* > 0: the searches never land on zero mass */
        gi_rsm_vpl(&s->rsm, t, 1.0 / ((double)N * p), i, &out->v[out->count++]);
    }
}

static pf_result gi__invtm_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__invtm_state *s = state;
    out->count = 0;
    if (!in->gbuf)
        return pf_error_set(err, PF_ERR_ARGUMENT, "--method invtm needs the frame's G-buffer (camera points)");
    if (!in->jobs) return pf_error_set(err, PF_ERR_ARGUMENT, "--method invtm needs a job system");
    pf_result r = gi_vpl_set_reserve(out, in->budget ? in->budget : 1, err);
    if (r == PF_OK) r = gi_rsm_set_geometry_moved(&s->rsm, in->motion, err); /* moved geometry: drawn again */
    if (r == PF_OK) r = gi_rsm_set_update(&s->rsm, in->scene, in->area, in->rt, in->jobs, err);
    float diag = pf_v3_length(pf_v3_sub(in->scene->bounds_max, in->scene->bounds_min));
    if (r == PF_OK) r = gi_importance_update(&s->imp, &s->rsm, in->gbuf, diag, in->simd, in->jobs, err);
    if (r == PF_OK) r = gi_invtm_build(&s->cdf, &s->imp.domain, s->imp.f, in->jobs, err);
    if (r != PF_OK) return r;
    if (s->rsm.texel_count > 0 && s->cdf.total > 0.0) gi__invtm_sample_vpls(s, in->budget, out);
    return gi_vpl_mark_moved(out, &s->prev, err);
}

/* ------------------------------------------------------------ the view */

/* The importance map f (Eq. 1-2) over the RSM texels, one square cell per
 * map face in heat colours (black: invalid texels), and the texel each VPL
 * was drawn from (white), replayed from the same Halton numbers as
 * gi__invtm_sample_vpls: the samples crowd where f is large. */
static int gi__invtm_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__invtm_state *s = state;
    if (!s || !(s->cdf.total > 0.0)) return 0;
    const gi_rsm_set *R = &s->rsm;
    const gi_importance *im = &s->imp;
    gi_importance_canvas cv;
    if (!gi_importance_canvas_draw(&cv, R, im, c, rgb)) return 0;
    static const uint8_t white[3] = {255, 255, 255};
    for (uint32_t i = 0; i < c->vpls->count; i++) {
        double xi1 = gi_halton(i + 1, 2), xi2 = gi_halton(i + 1, 3), xi3 = gi_halton(i + 1, 5);
        float x, y;
        gi_importance_canvas_texel_xy(&cv, R, gi_invtm_sample(&s->cdf, &im->domain, (int)s->dims, xi1, xi2, xi3),
                                      &x, &y);
        c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, white);
    }
    char text[96];
    snprintf(text, sizeof text, "%u RSM faces; white: the texel of each of %u VPLs", cv.faces, c->vpls->count);
    c->text(c, rgb, 4, 2, text, white);
    c->legend(c, rgb, "importance f (Eq. 1-2)", cv.lo, cv.hi, 1);
    return 1;
}

static uint32_t gi__invtm_bounce(const void *state, const gi_vpl *v, uint32_t bounces)
{
    (void)state, (void)v, (void)bounces;
    return 1; /* RSM texels: surfaces the lights see directly */
}

const gi_vpl_method gi_method_invtm = {
    .name = "invtm",
    .paper = "Inverse transform sampling of reflective shadow maps (Ritschel 2011; Barak 2013 Sec. 4.2)",
    .create = gi__invtm_create,
    .update = gi__invtm_update,
    .destroy = gi__invtm_destroy,
    .parts = NULL,
    .why = "every texel of a reflective shadow map is a potential VPL; drawing them in proportion to how much they "
           "light what the camera sees (the importance, Eq. 1-2) puts VPLs where they matter (Ritschel 2011; "
           "Barak 2013 Sec. 4.2)",
    .view_caption = "the RSM texels' importance f (Eq. 1-2) and the texel each VPL was drawn from by the inverse "
                    "transform (white)",
    .view = gi__invtm_view,
    .bounce = gi__invtm_bounce,
};
