/* gi_indirect: the many-light stages of a frame (see gi_indirect.h). */
#include "gi_indirect.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"

#define GI__DEFAULT_CLAMP 400.0f
/* Paraboloid maps are 2 bytes a texel: 32768 maps of 128^2 = 1 GiB. */
#define GI__MAX_MAP_BYTES ((size_t)4 << 30)

static float gi__lum(pf_vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

pf_result gi_indirect_init(gi_frame *f, const gi_indirect_options *opt_in, pf_error *err)
{
    gi_indirect *ind = &f->ind;
    memset(ind, 0, sizeof *ind);
    gi_indirect_options o = *opt_in;
    if (!o.method) o.method = &gi_method_ir;
    if (!o.vpls) o.vpls = 256;
    if (!o.bounces) o.bounces = 3;
    if (!o.tiles_n) o.tiles_n = 4;
    if (!o.tiles_m) o.tiles_m = 4;
    if (o.no_interleave) o.tiles_n = o.tiles_m = 1;
    if (o.clamp < 0.0f) o.clamp = GI__DEFAULT_CLAMP;
    if (!(o.alpha_rel > 0.0f)) o.alpha_rel = 0.02f;
    if (!(o.beta > 0.0f)) o.beta = 0.8f;
    if (!o.para_res) o.para_res = RS_PARA_DEFAULT_RES;
    ind->opt = o;
    const pf_scene *s = f->scene;
    float diag = pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min));
    ind->b = o.clamp > 0.0f ? o.clamp / (diag * diag) : INFINITY;
    ind->alpha = o.alpha_rel * diag;
    ind->n = o.tiles_n;
    ind->m = o.tiles_m;
    pf_result r = o.method->create(&ind->method_state, err);
    if (r != PF_OK) return r;
    uint32_t T = ind->n * ind->m;
    size_t px = (size_t)f->width * f->height;
    ind->tile_x0 = calloc(T + 1, sizeof(uint32_t));
    ind->tile_w = calloc(T, sizeof(uint32_t));
    ind->tile_h = calloc(T, sizeof(uint32_t));
    ind->assign_start = calloc(T + 1, sizeof(uint32_t));
    ind->assign = calloc(o.vpls, sizeof(uint32_t));
    float **planes[] = {&ind->split_px, &ind->split_py, &ind->split_pz, &ind->split_nx, &ind->split_ny, &ind->split_nz};
    for (size_t k = 0; k < 6; k++) *planes[k] = calloc(px, sizeof(float));
    ind->split_valid = calloc(px, sizeof(uint32_t));
    ind->split_e = calloc(3 * px, sizeof(float));
    ind->combined = calloc(3 * px, sizeof(float));
    ind->filtered = calloc(3 * px, sizeof(float));
    int ok = ind->tile_x0 && ind->tile_w && ind->tile_h && ind->assign_start && ind->assign && ind->split_valid &&
             ind->split_e && ind->combined && ind->filtered;
    for (size_t k = 0; k < 6; k++) ok = ok && *planes[k];
    if (ok && !o.visibility_raytrace && rs_para_atlas_bytes(o.para_res, o.vpls) > GI__MAX_MAP_BYTES)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "%u VPLs need %.1f GiB of %ux%u paraboloid maps (softgi allows %.0f GiB); use fewer VPLs "
                            "or --visibility raytrace",
                            o.vpls, (double)rs_para_atlas_bytes(o.para_res, o.vpls) / (1u << 30), o.para_res,
                            o.para_res, (double)GI__MAX_MAP_BYTES / (1u << 30));
    if (ok && !o.visibility_raytrace) {
        rs_para_options po;
        memset(&po, 0, sizeof po);
        po.resolution = o.para_res;
        r = rs_para_context_create(&ind->para, s, &po, err);
        if (r != PF_OK) return r;
        ind->atlas = malloc(rs_para_atlas_bytes(o.para_res, o.vpls));
        ind->frames = calloc(o.vpls, sizeof(rs_para_frame));
        ind->range = rs_para_default_range(s);
        ok = ind->atlas && ind->frames;
    }
    if (!ok) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the indirect-light buffers");
    /* tile (i, j): columns i, i + n, ... and rows j, j + m, ... */
    uint32_t off = 0;
    for (uint32_t j = 0; j < ind->m; j++)
        for (uint32_t i = 0; i < ind->n; i++) {
            uint32_t t = j * ind->n + i;
            ind->tile_w[t] = f->width > i ? (f->width - i + ind->n - 1) / ind->n : 0;
            ind->tile_h[t] = f->height > j ? (f->height - j + ind->m - 1) / ind->m : 0;
            ind->tile_x0[t] = off;
            off += ind->tile_w[t] * ind->tile_h[t];
        }
    ind->tile_x0[T] = off;
    return PF_OK;
}

void gi_indirect_free(gi_indirect *ind)
{
    if (ind->opt.method && ind->method_state) ind->opt.method->destroy(ind->method_state);
    gi_vpl_set_free(&ind->vpls);
    rs_para_context_destroy(ind->para);
    free(ind->atlas);
    free(ind->frames);
    free(ind->tile_x0), free(ind->tile_w), free(ind->tile_h), free(ind->assign), free(ind->assign_start);
    free(ind->split_px), free(ind->split_py), free(ind->split_pz);
    free(ind->split_nx), free(ind->split_ny), free(ind->split_nz), free(ind->split_valid);
    free(ind->split_e), free(ind->combined), free(ind->filtered);
    memset(ind, 0, sizeof *ind);
}

uint32_t gi_split_index(const gi_indirect *ind, uint32_t width, uint32_t x, uint32_t y)
{
    (void)width;
    uint32_t t = (y % ind->m) * ind->n + (x % ind->n);
    return ind->tile_x0[t] + (y / ind->m) * ind->tile_w[t] + x / ind->n;
}

/* ---------------------------------------------------------- 3. VPL update */

void gi_stage_vpl_update(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    gi_vpl_inputs in = {f->scene, f->rt, f->jobs, &f->camera, ind->frame, ind->opt.vpls, ind->opt.bounces};
    pf_error err;
    if (ind->opt.method->update(ind->method_state, &in, &ind->vpls, &err) != PF_OK) {
        /* only out-of-memory can fail here: render without VPLs, say so once */
        fprintf(stderr, "softgi: VPL update failed: %s\n", err.message);
        ind->vpls.count = 0;
    }
    ind->frame++;
}

/* ---------------------------------------------------------- 4. VPL shadow maps */

void gi_stage_vpl_shadow_maps(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    ind->maps_rendered = 0;
    if (!ind->para) return;
    uint32_t R = ind->opt.para_res, n = 0;
    size_t map = (size_t)R * R;
    /* moved VPLs are rendered into the slots after the set, then copied to
     * their own slots, so the call renders them all at once */
    pf_vec3 *pos = malloc(sizeof(pf_vec3) * (ind->vpls.count + 1)), *nrm = malloc(sizeof(pf_vec3) * (ind->vpls.count + 1));
    uint32_t *slot = malloc(sizeof(uint32_t) * (ind->vpls.count + 1));
    uint16_t *tmp = NULL;
    if (!pos || !nrm || !slot) goto done;
    for (uint32_t i = 0; i < ind->vpls.count; i++) {
        const gi_vpl *v = &ind->vpls.v[i];
        if (!v->moved && i < ind->atlas_slots) continue;
        pos[n] = v->pos;
        nrm[n] = v->nrm;
        slot[n++] = i;
        ind->frames[i] = rs_para_frame_make(v->pos, v->nrm);
    }
    if (n) {
        tmp = malloc(rs_para_atlas_bytes(R, n));
        if (!tmp) goto done;
        rs_para_render(tmp, ind->para, f->jobs, pos, nrm, n, ind->range, NULL);
        for (uint32_t k = 0; k < n; k++) memcpy(ind->atlas + slot[k] * map, tmp + k * map, map * sizeof(uint16_t));
    }
    ind->atlas_slots = ind->vpls.count;
    ind->maps_rendered = n;
done:
    free(tmp), free(pos), free(nrm), free(slot);
}

/* ---------------------------------------------------------- 5. split */

static void gi__split_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    gi_frame *f = p;
    gi_indirect *ind = &f->ind;
    const rs_gbuffer *g = &f->gbuf;
    for (uint32_t x = 0; x < f->width; x++) {
        size_t i = (size_t)y * f->width + x;
        uint32_t k = gi_split_index(ind, f->width, x, y);
        ind->split_px[k] = g->pos_x[i], ind->split_py[k] = g->pos_y[i], ind->split_pz[k] = g->pos_z[i];
        ind->split_nx[k] = g->nrm_x[i], ind->split_ny[k] = g->nrm_y[i], ind->split_nz[k] = g->nrm_z[i];
        ind->split_valid[k] = g->prim[i] != RS_GBUFFER_EMPTY;
    }
}

void gi_stage_split(gi_frame *f) { pf_jobs_parallel_for(f->jobs, gi__split_row, f, f->height, 8); }

/* ---------------------------------------------------------- 6. assign */

typedef struct gi__lumkey {
    float lum;
    uint32_t index;
} gi__lumkey;

static int gi__by_lum(const void *a, const void *b)
{
    const gi__lumkey *x = a, *y = b;
    if (x->lum != y->lum) return x->lum > y->lum ? -1 : 1; /* brightest first */
    return x->index < y->index ? -1 : (x->index > y->index); /* ties: stable by index */
}

void gi_stage_assign(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    uint32_t T = ind->n * ind->m, N = ind->vpls.count;
    gi__lumkey *keys = malloc(sizeof(gi__lumkey) * (N + 1));
    uint32_t *tile_of = malloc(sizeof(uint32_t) * (N + 1));
    if (!keys || !tile_of) {
        free(keys), free(tile_of);
        memset(ind->assign_start, 0, sizeof(uint32_t) * (T + 1));
        return;
    }
    for (uint32_t i = 0; i < N; i++) keys[i] = (gi__lumkey){gi__lum(ind->vpls.v[i].intensity), i};
    qsort(keys, N, sizeof *keys, gi__by_lum);
    /* deal in boustrophedon order: 0..T-1, T-1..0, ... so each tile's share
     * of the bright VPLs is as even as the counts allow */
    for (uint32_t r = 0; r < N; r++) {
        uint32_t round = r / T, pos = r % T;
        tile_of[keys[r].index] = (round & 1) ? T - 1 - pos : pos;
    }
    memset(ind->assign_start, 0, sizeof(uint32_t) * (T + 1));
    for (uint32_t i = 0; i < N; i++) ind->assign_start[tile_of[i] + 1]++;
    for (uint32_t t = 0; t < T; t++) ind->assign_start[t + 1] += ind->assign_start[t];
    uint32_t *cursor = malloc(sizeof(uint32_t) * T);
    if (cursor) {
        memcpy(cursor, ind->assign_start, sizeof(uint32_t) * T);
        for (uint32_t i = 0; i < N; i++) ind->assign[cursor[tile_of[i]]++] = i; /* VPL order within a tile */
    }
    free(cursor), free(keys), free(tile_of);
}

/* ---------------------------------------------------------- 7. accumulate */

/* Irradiance at (p, n) from one VPL, bounded geometry term, no visibility. */
static pf_vec3 gi__vpl_irradiance(const gi_vpl *v, pf_vec3 p, pf_vec3 n, float b, pf_vec3 *w_out, float *r_out)
{
    pf_vec3 d = pf_v3_sub(v->pos, p);
    float r2 = pf_v3_dot(d, d);
    if (!(r2 > 0.0f)) return pf_v3(0, 0, 0);
    float r = sqrtf(r2);
    pf_vec3 w = pf_v3_scale(d, 1.0f / r);
    float c1 = pf_v3_dot(n, w), c2 = -pf_v3_dot(v->nrm, w);
    if (!(c1 > 0.0f) || !(c2 > 0.0f)) return pf_v3(0, 0, 0);
    float G = c1 * c2 / r2;
    if (G > b) G = b; /* the bounded geometry term (survey Sec. 5) */
    *w_out = w;
    *r_out = r;
    return pf_v3_scale(v->intensity, G);
}

static void gi__accumulate_row(void *p, uint32_t item, uint32_t worker)
{
    (void)worker;
    gi_frame *f = p;
    gi_indirect *ind = &f->ind;
    uint32_t T = ind->n * ind->m, rows = 0;
    for (uint32_t t = 0; t < T; t++) rows = ind->tile_h[t] > rows ? ind->tile_h[t] : rows;
    uint32_t t = item / rows, row = item % rows;
    if (t >= T || row >= ind->tile_h[t]) return;
    const float weight = (float)T; /* each tile sees 1/T of the VPLs */
    uint32_t a0 = ind->assign_start[t], a1 = ind->assign_start[t + 1];
    const uint32_t R = ind->opt.para_res;
    const size_t map = (size_t)R * R;
    for (uint32_t a = 0; a < ind->tile_w[t]; a++) {
        uint32_t k = ind->tile_x0[t] + row * ind->tile_w[t] + a;
        float *e = ind->split_e + 3 * (size_t)k;
        e[0] = e[1] = e[2] = 0.0f;
        if (!ind->split_valid[k]) continue;
        pf_vec3 pos = pf_v3(ind->split_px[k], ind->split_py[k], ind->split_pz[k]);
        pf_vec3 nrm = pf_v3(ind->split_nx[k], ind->split_ny[k], ind->split_nz[k]);
        pf_vec3 sum = pf_v3(0, 0, 0);
        for (uint32_t q = a0; q < a1; q++) {
            uint32_t vi = ind->assign[q];
            const gi_vpl *v = &ind->vpls.v[vi];
            pf_vec3 w;
            float r;
            pf_vec3 c = gi__vpl_irradiance(v, pos, nrm, ind->b, &w, &r);
            if (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f) continue;
            int visible;
            if (ind->para) {
                visible = rs_para_visible_at(ind->atlas + vi * map, R, ind->range, &ind->frames[vi], pos,
                                             pf_v3_dot(nrm, w));
            } else {
                pf_ray ray = {pf_rt_offset_origin(pos, nrm, w), 0.0f, w, r * (1.0f - 1.0e-4f)};
                visible = !pf_rt_occluded1(f->rt, ray);
            }
            if (visible) sum = pf_v3_add(sum, c);
        }
        e[0] = sum.x * weight, e[1] = sum.y * weight, e[2] = sum.z * weight;
    }
}

void gi_stage_accumulate(gi_frame *f)
{
    gi_indirect *ind = &f->ind;
    uint32_t T = ind->n * ind->m, rows = 0;
    for (uint32_t t = 0; t < T; t++) rows = ind->tile_h[t] > rows ? ind->tile_h[t] : rows;
    pf_jobs_parallel_for(f->jobs, gi__accumulate_row, f, T * rows, 1);
}

/* ---------------------------------------------------------- 8. combine */

static void gi__combine_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    gi_frame *f = p;
    gi_indirect *ind = &f->ind;
    for (uint32_t x = 0; x < f->width; x++) {
        uint32_t k = gi_split_index(ind, f->width, x, y);
        memcpy(ind->combined + 3 * ((size_t)y * f->width + x), ind->split_e + 3 * (size_t)k, 3 * sizeof(float));
    }
}

void gi_stage_combine(gi_frame *f) { pf_jobs_parallel_for(f->jobs, gi__combine_row, f, f->height, 8); }

/* ---------------------------------------------------------- 9. filter */

static void gi__filter_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    gi_frame *f = p;
    gi_indirect *ind = &f->ind;
    const rs_gbuffer *g = &f->gbuf;
    const int W = (int)f->width, H = (int)f->height, n = (int)ind->n, m = (int)ind->m;
    const float a2 = ind->alpha * ind->alpha, beta = ind->opt.beta;
    for (int x = 0; x < W; x++) {
        size_t i = (size_t)y * f->width + (size_t)x;
        float *out = ind->filtered + 3 * i;
        if (g->prim[i] == RS_GBUFFER_EMPTY || ind->opt.filter == GI_FILTER_NONE) {
            memcpy(out, ind->combined + 3 * i, 3 * sizeof(float));
            continue;
        }
        pf_vec3 pos = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]);
        pf_vec3 nrm = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
        float acc[3] = {0, 0, 0}, wsum = 0.0f;
        if (ind->opt.filter == GI_FILTER_BOX) {
            /* Laine 2007 Fig. 5: the n x m box whose size matches the
             * interleaving pattern, restricted to similar geometry */
            for (int dy = 0; dy < m; dy++)
                for (int dx = 0; dx < n; dx++) {
                    int tx = x + dx - n / 2, ty = (int)y + dy - m / 2;
                    if (tx < 0 || ty < 0 || tx >= W || ty >= H) continue;
                    size_t j = (size_t)ty * f->width + (size_t)tx;
                    if (g->prim[j] == RS_GBUFFER_EMPTY) continue;
                    pf_vec3 d = pf_v3_sub(pf_v3(g->pos_x[j], g->pos_y[j], g->pos_z[j]), pos);
                    float nd = nrm.x * g->nrm_x[j] + nrm.y * g->nrm_y[j] + nrm.z * g->nrm_z[j];
                    if (!(pf_v3_dot(d, d) < a2) || !(nd > beta)) continue;
                    const float *e = ind->combined + 3 * j;
                    acc[0] += e[0], acc[1] += e[1], acc[2] += e[2];
                    wsum += 1.0f;
                }
        } else {
            /* cross-bilateral (Hedman 2017 Sec. 4): a Gaussian over 2n x 2m
             * pixels weighted by position and normal similarity */
            int rx = n, ry = m;
            float ss = 0.5f * (float)(n > m ? n : m), sp2 = 0.25f * a2;
            for (int dy = -ry; dy <= ry; dy++)
                for (int dx = -rx; dx <= rx; dx++) {
                    int tx = x + dx, ty = (int)y + dy;
                    if (tx < 0 || ty < 0 || tx >= W || ty >= H) continue;
                    size_t j = (size_t)ty * f->width + (size_t)tx;
                    if (g->prim[j] == RS_GBUFFER_EMPTY) continue;
                    pf_vec3 d = pf_v3_sub(pf_v3(g->pos_x[j], g->pos_y[j], g->pos_z[j]), pos);
                    float nd = nrm.x * g->nrm_x[j] + nrm.y * g->nrm_y[j] + nrm.z * g->nrm_z[j];
                    if (!(nd > 0.0f)) continue;
                    float nd2 = nd * nd, nd4 = nd2 * nd2;
                    float w = expf(-(float)(dx * dx + dy * dy) / (2.0f * ss * ss)) * expf(-pf_v3_dot(d, d) / (2.0f * sp2)) *
                              nd4 * nd4;
                    const float *e = ind->combined + 3 * j;
                    acc[0] += w * e[0], acc[1] += w * e[1], acc[2] += w * e[2];
                    wsum += w;
                }
        }
        if (wsum > 0.0f) out[0] = acc[0] / wsum, out[1] = acc[1] / wsum, out[2] = acc[2] / wsum;
        else memcpy(out, ind->combined + 3 * i, 3 * sizeof(float));
    }
}

void gi_stage_filter(gi_frame *f) { pf_jobs_parallel_for(f->jobs, gi__filter_row, f, f->height, 4); }
