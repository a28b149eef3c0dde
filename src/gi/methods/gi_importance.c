/* gi_importance: the importance map of RSM texels from camera points
 * (Barak 2013 Sec. 4.1, Eq. 1-2; Ritschel 2011) and the VPL helpers the
 * RSM methods share. Conventions in gi_importance.h. */
#include "gi_importance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_importance_kernels.h"
#include "pf_rt.h"
#include "rs_raster.h"
#include "simd_arch.h"

void gi_importance_init(gi_importance *im, uint32_t P)
{
    memset(im, 0, sizeof *im);
    im->P = P ? P : GI_IMPORTANCE_DEFAULT_P;
}

void gi_importance_free(gi_importance *im)
{
    float **planes[] = {&im->x, &im->y, &im->z, &im->nx, &im->ny, &im->nz, &im->alb, &im->f};
    for (size_t k = 0; k < sizeof planes / sizeof planes[0]; k++) {
        free(*planes[k]);
        *planes[k] = NULL;
    }
    free(im->first);
    free(im->rows);
    free(im->cols);
    im->first = im->rows = im->cols = NULL;
}

uint32_t gi_domain_texel(const gi_sample_domain *d, double xi1, double xi2, double xi3, double *q)
{
    uint32_t l = (uint32_t)(xi1 * d->maps);
    if (l >= d->maps) l = d->maps - 1;
    uint32_t row = (uint32_t)(xi2 * d->rows[l]), col = (uint32_t)(xi3 * d->cols[l]);
    if (row >= d->rows[l]) row = d->rows[l] - 1;
    if (col >= d->cols[l]) col = d->cols[l] - 1;
    if (q) *q = 1.0 / ((double)d->maps * d->rows[l] * d->cols[l]);
    return d->first[l] + row * d->cols[l] + col;
}

/* ------------------------------------------------- 1. camera points x_k */


static void gi__importance_camera_points(gi_importance *im, const rs_gbuffer *g)
{
    im->count = 0;
    for (uint32_t k = 0; k < im->P; k++) {
        uint32_t x = (uint32_t)(gi_halton(k + 1, 2) * g->width), y = (uint32_t)(gi_halton(k + 1, 3) * g->height);
        if (x >= g->width) x = g->width - 1;
        if (y >= g->height) y = g->height - 1;
        size_t i = (size_t)y * g->width + x;
        if (g->prim[i] == RS_GBUFFER_EMPTY) continue;
        uint32_t c = im->count++;
        im->x[c] = g->pos_x[i], im->y[c] = g->pos_y[i], im->z[c] = g->pos_z[i];
        im->nx[c] = g->nrm_x[i], im->ny[c] = g->nrm_y[i], im->nz[c] = g->nrm_z[i];
        im->alb[c] = pf_luminance(pf_v3(g->alb_r[i], g->alb_g[i], g->alb_b[i]));
    }
}

/* --------------------------------------------- 2. f(v), Eq. 1-2 per texel */

typedef struct gi__imp_ctx {
    gi_importance *im;
    const gi_rsm_set *rsm;
    float g_max;
    uint32_t row_len;
    const gi_importance_kernels *kt; /* the SIMD path's kernel, NULL on the scalar path */
} gi__imp_ctx;

/* Camera point k's term of Eq. 2 for a texel at p with normal v:
 * albedo_k G, G clamped to g_max. */
static inline float gi__importance_term(const gi_importance *im, uint32_t k, float px, float py, float pz, float vx,
                                        float vy, float vz, float g_max)
{
    float dx = px - im->x[k], dy = py - im->y[k], dz = pz - im->z[k];
    float d2 = dx * dx + dy * dy + dz * dz;
    float ck = im->nx[k] * dx + im->ny[k] * dy + im->nz[k] * dz;
    float cv = -(vx * dx + vy * dy + vz * dz);
    ck = ck > 0.0f ? ck : 0.0f;
    cv = cv > 0.0f ? cv : 0.0f;
    float d4 = d2 * d2;
    d4 = d4 > 1e-30f ? d4 : 1e-30f;
    float G = ck * cv / d4;
    G = G < g_max ? G : g_max;
    return im->alb[k] * G;
}

/* f for the texels [row * row_len, (row + 1) * row_len): a fixed-order sum
 * over the camera points, written so the compiler can vectorise it (no
 * branches, no sqrt: G = max(0, n_k.d) max(0, -n_v.d) / |d|^4). */
static void gi__importance_row(void *p, uint32_t row, uint32_t worker)
{
    (void)worker;
    const gi__imp_ctx *c = p;
    const gi_importance *im = c->im;
    const gi_rsm_set *s = c->rsm;
    const uint32_t K = im->count;
    const float g_max = c->g_max;
    const gi_importance_kernels *kt = c->kt;
    const gi_importance_in in = {im->x, im->y, im->z, im->nx, im->ny, im->nz, im->alb, K, g_max};
    for (uint32_t t = row * c->row_len, e = t + c->row_len; t < e; t++) {
        if (kt && t + kt->width <= e) {
            /* SIMD: the sums of width texels (texels with no light get one
             * too, and are then given 0 as below) */
            float sum[16];
            kt->texels(&in, s->pos_x + t, s->pos_y + t, s->pos_z + t, s->nrm_x + t, s->nrm_y + t, s->nrm_z + t, sum);
            for (uint32_t l = 0; l < kt->width; l++) {
                float I = pf_luminance(pf_v3(s->flux_r[t + l], s->flux_g[t + l], s->flux_b[t + l]));
                im->f[t + l] = s->valid[t + l] && I > 0.0f ? I * sum[l] : 0.0f;
            }
            t += kt->width - 1;
            continue;
        }
        float I = pf_luminance(pf_v3(s->flux_r[t], s->flux_g[t], s->flux_b[t]));
        if (!s->valid[t] || !(I > 0.0f)) {
            im->f[t] = 0.0f;
            continue;
        }
        const float px = s->pos_x[t], py = s->pos_y[t], pz = s->pos_z[t];
        const float vx = s->nrm_x[t], vy = s->nrm_y[t], vz = s->nrm_z[t];
        /* 8 partial sums (lane l takes the points k = l mod 8), added in a
         * fixed order at the end: the same bits for any thread count, and
         * the lanes let the compiler use SIMD without reassociating. The
         * ternaries are max/min without libm's NaN rules (no calls). */
        float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        uint32_t k = 0;
        for (; k + 8 <= K; k += 8)
            for (uint32_t l = 0; l < 8; l++) acc[l] += gi__importance_term(im, k + l, px, py, pz, vx, vy, vz, g_max);
        for (uint32_t l = 0; k < K; k++, l++) acc[l] += gi__importance_term(im, k, px, py, pz, vx, vy, vz, g_max);
        float sum = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
        im->f[t] = I * sum;
    }
}

static pf_result gi__grow(void **p, uint32_t *cap, uint32_t need, size_t elem, pf_error *err)
{
    if (*cap >= need && *p) return PF_OK;
    void *q = realloc(*p, (size_t)(need ? need : 1) * elem);
    if (!q) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the importance map");
    *p = q;
    *cap = need;
    return PF_OK;
}

/* The kernel of SIMD path simd (an rs_simd); NULL: the scalar loop. */
static const gi_importance_kernels *gi__importance_kernels(uint32_t simd)
{
#if SIMD_X86
    if (simd == RS_SIMD_AVX512) return &gi_importance_kernels_avx512;
    if (simd == RS_SIMD_AVX2) return &gi_importance_kernels_avx2;
#endif
    (void)simd;
    return NULL;
}

pf_result gi_importance_update(gi_importance *im, const gi_rsm_set *rsm, const rs_gbuffer *g, float diagonal,
                               uint32_t simd, pf_jobs *jobs, pf_error *err)
{
    pf_result r;
    if (!im->x) {
        float **planes[] = {&im->x, &im->y, &im->z, &im->nx, &im->ny, &im->nz, &im->alb};
        for (size_t k = 0; k < sizeof planes / sizeof planes[0]; k++)
            if (!(*planes[k] = malloc((size_t)im->P * sizeof(float))))
                return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the importance map");
    }
    uint32_t fcap = im->f_cap;
    if ((r = gi__grow((void **)&im->f, &fcap, rsm->texel_count, sizeof(float), err)) != PF_OK) return r;
    im->f_cap = fcap;
    uint32_t mc = im->map_cap, mc2 = im->map_cap, mc3 = im->map_cap;
    if ((r = gi__grow((void **)&im->first, &mc, rsm->count, sizeof(uint32_t), err)) != PF_OK ||
        (r = gi__grow((void **)&im->rows, &mc2, rsm->count, sizeof(uint32_t), err)) != PF_OK ||
        (r = gi__grow((void **)&im->cols, &mc3, rsm->count, sizeof(uint32_t), err)) != PF_OK)
        return r;
    im->map_cap = mc;
    for (uint32_t m = 0; m < rsm->count; m++) {
        im->first[m] = rsm->maps[m].first;
        im->rows[m] = rsm->maps[m].face_count * rsm->maps[m].size;
        im->cols[m] = rsm->maps[m].size;
    }
    im->domain = (gi_sample_domain){rsm->count, im->first, im->rows, im->cols, rsm->texel_count};
    gi__importance_camera_points(im, g);
    if (rsm->texel_count == 0) return PF_OK;
    gi__imp_ctx c = {im, rsm, 400.0f / (diagonal * diagonal), rsm->size, gi__importance_kernels(simd)};
    pf_jobs_parallel_for(jobs, gi__importance_row, &c, rsm->texel_count / rsm->size, 0);
    return PF_OK;
}

/* ------------------------------------------------------------------ VPLs */

void gi_rsm_vpl(const gi_rsm_set *s, uint32_t t, double scale, uint32_t id, gi_vpl *out)
{
    pf_vec3 p = pf_v3(s->pos_x[t], s->pos_y[t], s->pos_z[t]);
    pf_vec3 ng = pf_v3(s->ng_x[t], s->ng_y[t], s->ng_z[t]);
    float k = (float)(scale * (double)PF_INV_PI);
    out->pos = pf_rt_offset_origin(p, ng, ng);
    out->nrm = pf_v3(s->nrm_x[t], s->nrm_y[t], s->nrm_z[t]);
    out->intensity = pf_v3(s->flux_r[t] * k, s->flux_g[t] * k, s->flux_b[t] * k);
    out->id = id;
    out->moved = 1;
}

pf_result gi_vpl_mark_moved(gi_vpl_set *cur, gi_vpl_set *prev, pf_error *err)
{
    for (uint32_t i = 0; i < cur->count; i++) {
        gi_vpl *v = &cur->v[i];
        v->moved = !(i < prev->count && !memcmp(&prev->v[i].pos, &v->pos, sizeof v->pos) &&
                     !memcmp(&prev->v[i].nrm, &v->nrm, sizeof v->nrm));
    }
    pf_result r = gi_vpl_set_reserve(prev, cur->count ? cur->count : 1, err);
    if (r != PF_OK) return r;
    memcpy(prev->v, cur->v, sizeof(gi_vpl) * cur->count);
    prev->count = cur->count;
    return PF_OK;
}

/* ------------------------------------------------------------------ views */

int gi_importance_canvas_draw(gi_importance_canvas *cv, const gi_rsm_set *R, const gi_importance *im,
                              const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    memset(cv, 0, sizeof *cv);
    if (!R->count || R->count > 64 || !R->texel_count || !im->f || im->domain.total != R->texel_count) return 0;
    for (uint32_t m = 0; m < R->count; m++) cv->face0[m] = cv->faces, cv->faces += R->maps[m].face_count;
    cv->across = 1;
    for (uint32_t a = 1; a <= cv->faces; a++) { /* the most cells across whose square cells are largest */
        uint32_t down = (cv->faces + a - 1) / a;
        uint32_t side = c->width / a < c->height / down ? c->width / a : c->height / down;
        if (side > cv->cell) cv->cell = side, cv->across = a;
    }
    if (cv->cell < 4) return 0;
    uint32_t down = (cv->faces + cv->across - 1) / cv->across;
    cv->ox = (c->width - cv->across * cv->cell) / 2, cv->oy = (c->height - down * cv->cell) / 2;
    float lo = INFINITY, hi = -INFINITY;
    for (uint32_t t = 0; t < R->texel_count; t++)
        if (R->valid[t]) lo = fminf(lo, im->f[t]), hi = fmaxf(hi, im->f[t]);
    if (!(lo <= hi)) lo = hi = 0.0f;
    cv->lo = lo, cv->hi = hi;
    /* the cells, pixel by pixel: the texel under each pixel */
    for (uint32_t m = 0; m < R->count; m++) {
        const gi_rsm_map *M = &R->maps[m];
        for (uint32_t fc = 0; fc < M->face_count; fc++) {
            uint32_t k = cv->face0[m] + fc, x0 = cv->ox + k % cv->across * cv->cell;
            uint32_t y0 = cv->oy + k / cv->across * cv->cell;
            for (uint32_t y = 0; y < cv->cell; y++)
                for (uint32_t x = 0; x < cv->cell; x++) {
                    uint32_t row = (uint32_t)((uint64_t)y * M->size / cv->cell);
                    uint32_t col = (uint32_t)((uint64_t)x * M->size / cv->cell);
                    uint32_t t = M->first + (fc * M->size + row) * M->size + col;
                    uint8_t *o = rgb + 3 * ((size_t)(y0 + y) * c->width + x0 + x);
                    if (!R->valid[t]) o[0] = o[1] = o[2] = 0;
                    else c->heat(hi > lo ? sqrtf((im->f[t] - lo) / (hi - lo)) : 1.0f, o);
                }
        }
    }
    return 1;
}

void gi_importance_canvas_texel_xy(const gi_importance_canvas *cv, const gi_rsm_set *R, uint32_t t, float *x,
                                   float *y)
{
    uint32_t m = gi_rsm_map_of(R, t), size = R->maps[m].size, local = t - R->maps[m].first;
    uint32_t face = cv->face0[m] + local / (size * size), row = local % (size * size) / size, col = local % size;
    *x = (float)(cv->ox + face % cv->across * cv->cell) + ((float)col + 0.5f) * (float)cv->cell / (float)size;
    *y = (float)(cv->oy + face / cv->across * cv->cell) + ((float)row + 0.5f) * (float)cv->cell / (float)size;
}
