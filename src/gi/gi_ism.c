/* gi_ism: imperfect shadow maps, Ritschel 2008 and Barak 2013 Sec. 5 (see
 * gi_ism.h for the outline, the conventions and the deviations). */
#include "gi_ism.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Expected points per splat job item: items are runs of consecutive
 * triangles, and a triangle with more points is split into runs of its
 * points, so a scene of few large triangles spreads over the workers too. */
#define GI__ISM_ITEM_POINTS 4096.0f
/* Maps per clear / pull-push / binned-splat job item. */
#define GI__ISM_MAP_GRAIN 4u
/* The binned splat (gi_ism_stage_splat): splat records per batch, and the
 * batch's bucket offsets, items x (maps + 1). */
#define GI__ISM_REC_CAP (1u << 19)
#define GI__ISM_OFF_CAP (1u << 18)

typedef struct gi__ism_tri {
    float v0[3], e1[3], e2[3];
} gi__ism_tri;

/* A splat job item: triangles t0..t1-1, their points k0..min(k1, n)-1. */
typedef struct gi__ism_item {
    uint32_t t0, t1, k0, k1;
} gi__ism_item;

/* One point's splat: its map, the texel it falls in, the disc (centre x, y
 * and radius rt in texels; rt <= 0.5: that texel only) and its code. */
typedef struct gi__ism_rec {
    float x, y, rt;
    uint32_t texel, vi;
    uint16_t code, pad;
} gi__ism_rec;

struct gi_ism {
    gi_ism_options opt;
    uint32_t tri_count;
    gi__ism_tri *tris;
    double *tri_area;   /* A_i */
    float *density;     /* expected points per frame of each triangle: P A_i / A */
    gi__ism_item *items;
    uint32_t item_count;
    /* the binned splat: each item's most points, their records sorted by
     * map per batch of items, per-worker generation buffers, the batch's
     * bucket offsets and each item's first record; binned 0: every splat
     * is an atomic min straight from the points (options.atomic_splat, or
     * an item too large for the bins) */
    uint32_t *item_cap, *item_base;
    uint32_t max_item_cap;
    gi__ism_rec *sorted, **gen;
    uint32_t *bucket;
    uint32_t gen_cap;
    int binned;
    uint16_t *template_map; /* R x R: EMPTY inside the disc, OUTSIDE out of it */
    uint32_t inside_texels;
    int *row_lo, *row_hi; /* per map row: the inside texels' columns (lo > hi: none) */
    uint32_t workers;
    float **scratch;    /* per worker: the pull-push pyramid */
    /* the call in flight (gi_ism_render is not reentrant on one gi_ism) */
    uint16_t *atlas;
    const rs_para_frame *frames;
    uint32_t count, frame;
    float scale; /* code steps per unit distance */
    float point_radius; /* radius of the disc of area A / P a point stands for */
    double area;
    uint64_t splatted, generated, filled;
};

/* ------------------------------------------------------------------ create */

static int gi__is_pow2(uint32_t x) { return x && !(x & (x - 1)); }

/* The splat job items (see GI__ISM_ITEM_POINTS): two passes, count then
 * fill. */
static pf_result gi__ism_make_items(gi_ism *m)
{
    for (int pass = 0; pass < 2; pass++) {
        uint32_t n = 0, start = 0;
        float acc = 0.0f;
#define GI__ISM_ITEM(a, b, c, d)                                                                                       \
    do {                                                                                                               \
        if (pass) m->items[n] = (gi__ism_item){(a), (b), (c), (d)};                                                    \
        n++;                                                                                                           \
    } while (0)
        for (uint32_t t = 0; t < m->tri_count; t++) {
            float d = m->density[t];
            if (d > GI__ISM_ITEM_POINTS) { /* close the run, then split this triangle */
                if (t > start) GI__ISM_ITEM(start, t, 0, UINT32_MAX);
                uint32_t pieces = (uint32_t)ceilf(d / GI__ISM_ITEM_POINTS);
                for (uint32_t q = 0; q < pieces; q++)
                    GI__ISM_ITEM(t, t + 1, q * (uint32_t)GI__ISM_ITEM_POINTS,
                                 q + 1 == pieces ? UINT32_MAX : (q + 1) * (uint32_t)GI__ISM_ITEM_POINTS);
                start = t + 1, acc = 0.0f;
                continue;
            }
            acc += d;
            if (acc >= GI__ISM_ITEM_POINTS) {
                GI__ISM_ITEM(start, t + 1, 0, UINT32_MAX);
                start = t + 1, acc = 0.0f;
            }
        }
        if (m->tri_count > start) GI__ISM_ITEM(start, m->tri_count, 0, UINT32_MAX);
#undef GI__ISM_ITEM
        if (!pass) {
            free(m->item_cap), free(m->item_base);
            m->items = malloc(sizeof(gi__ism_item) * (n ? n : 1));
            m->item_cap = malloc(sizeof(uint32_t) * (n ? n : 1));
            m->item_base = malloc(sizeof(uint32_t) * (n ? n : 1));
            if (!m->items || !m->item_cap || !m->item_base) return PF_ERR_OUT_OF_MEMORY;
        }
        m->item_count = n;
    }
    return PF_OK;
}

/* Triangles [t0, t1) of the scene as (v0, e1, e2) and their areas. */
static void gi__ism_triangles(gi_ism *m, const pf_scene *scene, uint32_t t0, uint32_t t1)
{
    for (uint32_t t = t0; t < t1; t++) {
        const uint32_t *ix = scene->indices + 3 * (size_t)t;
        pf_vec3 a = scene->positions[ix[0]], b = scene->positions[ix[1]], c = scene->positions[ix[2]];
        pf_vec3 e1 = pf_v3_sub(b, a), e2 = pf_v3_sub(c, a);
        gi__ism_tri *T = &m->tris[t];
        T->v0[0] = a.x, T->v0[1] = a.y, T->v0[2] = a.z;
        T->e1[0] = e1.x, T->e1[1] = e1.y, T->e1[2] = e1.z;
        T->e2[0] = e2.x, T->e2[1] = e2.y, T->e2[2] = e2.z;
        m->tri_area[t] = 0.5 * (double)pf_v3_length(pf_v3_cross(e1, e2));
    }
}

/* The binned splat's sizes: each item's most points (a triangle of density
 * d makes floor(d) or floor(d) + 1), the largest, and the generation
 * buffers for it; an item beyond GI__ISM_REC_CAP leaves the splat atomic. */
static pf_result gi__ism_bins(gi_ism *m, pf_error *err)
{
    uint64_t most = 0;
    for (uint32_t i = 0; i < m->item_count; i++) {
        const gi__ism_item *it = &m->items[i];
        uint64_t cap = 0;
        for (uint32_t t = it->t0; t < it->t1; t++) {
            uint64_t n = (uint64_t)floorf(m->density[t]) + 1;
            cap += (n < it->k1 ? n : it->k1) - (n < it->k0 ? n : it->k0);
        }
        m->item_cap[i] = cap < UINT32_MAX ? (uint32_t)cap : UINT32_MAX;
        if (cap > most) most = cap;
    }
    m->max_item_cap = most < UINT32_MAX ? (uint32_t)most : UINT32_MAX;
    m->binned = !m->opt.atomic_splat && most <= GI__ISM_REC_CAP;
    if (!m->binned || most <= m->gen_cap) return PF_OK;
    for (uint32_t w = 0; w < m->workers; w++) {
        gi__ism_rec *g = realloc(m->gen[w], sizeof(gi__ism_rec) * (size_t)most);
        if (!g) {
            m->binned = 0; /* the buffers are too small for these items: the atomic splat */
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the ISMs' splat bins");
        }
        m->gen[w] = g;
    }
    m->gen_cap = (uint32_t)most;
    return PF_OK;
}

/* The densities, each triangle's share of the P points (Barak 2013 Sec.
 * 5.2: "calculate the triangle surface area, set the number of points to be
 * generated"), and the splat job items, from the areas. The total is summed
 * in triangle order in double, each share from the area rounded to float. */
static pf_result gi__ism_densities(gi_ism *m, pf_error *err)
{
    double total = 0.0;
    for (uint32_t t = 0; t < m->tri_count; t++) total += m->tri_area[t];
    if (!(total > 0.0)) return pf_error_set(err, PF_ERR_ARGUMENT, "ISM: the scene's triangles have no area");
    m->area = total;
    for (uint32_t t = 0; t < m->tri_count; t++)
        m->density[t] = (float)((double)m->opt.points * (double)(float)m->tri_area[t] / total);
    free(m->items);
    m->items = NULL;
    m->item_count = 0; /* nothing splats until the items are made */
    if (gi__ism_make_items(m) != PF_OK) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the ISMs");
    return gi__ism_bins(m, err);
}

pf_result gi_ism_update(gi_ism *m, const pf_scene *scene, const pf_anim_moved *moved, uint32_t count, pf_error *err)
{
    if (scene->tri_count != m->tri_count)
        return pf_error_set(err, PF_ERR_ARGUMENT, "ISM update: the scene has %u triangles, the ISMs were made for %u",
                            scene->tri_count, m->tri_count);
    uint32_t n = 0;
    for (uint32_t k = 0; k < count; k++) {
        const pf_anim_moved *mv = &moved[k];
        if (!mv->moved) continue;
        if (mv->tri_first > m->tri_count || mv->tri_count > m->tri_count - mv->tri_first)
            return pf_error_set(err, PF_ERR_ARGUMENT, "ISM update: triangles %u..+%u outside the scene's %u",
                                mv->tri_first, mv->tri_count, m->tri_count);
        gi__ism_triangles(m, scene, mv->tri_first, mv->tri_first + mv->tri_count);
        n++;
    }
    return n ? gi__ism_densities(m, err) : PF_OK;
}

pf_result gi_ism_create(gi_ism **out, const pf_scene *scene, const gi_ism_options *opt_in, uint32_t threads,
                        pf_error *err)
{
    *out = NULL;
    gi_ism_options o;
    if (opt_in) o = *opt_in;
    else memset(&o, 0, sizeof o);
    if (!o.resolution) o.resolution = GI_ISM_DEFAULT_RES;
    if (!o.points) o.points = GI_ISM_DEFAULT_POINTS;
    if (o.bias_scale == 0.0f) o.bias_scale = GI_ISM_DEFAULT_BIAS;
    if (!gi__is_pow2(o.resolution) || o.resolution < GI_ISM_MIN_RES || o.resolution > GI_ISM_MAX_RES)
        return pf_error_set(err, PF_ERR_ARGUMENT, "ISM resolution %u: expected a power of two in %u..%u",
                            o.resolution, GI_ISM_MIN_RES, GI_ISM_MAX_RES);
    if (o.points < GI_ISM_MIN_POINTS || o.points > GI_ISM_MAX_POINTS)
        return pf_error_set(err, PF_ERR_ARGUMENT, "ISM points %u: expected %u..%u", o.points, GI_ISM_MIN_POINTS,
                            GI_ISM_MAX_POINTS);
    if (!(o.bias_scale >= GI_ISM_MIN_BIAS && o.bias_scale <= GI_ISM_MAX_BIAS))
        return pf_error_set(err, PF_ERR_ARGUMENT, "ISM bias %g: expected a scale in %g..%g", (double)o.bias_scale,
                            (double)GI_ISM_MIN_BIAS, (double)GI_ISM_MAX_BIAS);
    if (!scene || scene->tri_count == 0) return pf_error_set(err, PF_ERR_ARGUMENT, "ISM: the scene has no triangles");
    if (threads == 0) threads = 1;
    gi_ism *m = calloc(1, sizeof *m);
    if (!m) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the ISMs");
    m->opt = o;
    m->tri_count = scene->tri_count;
    m->workers = threads;
    const uint32_t R = o.resolution;
    m->tris = malloc(sizeof(gi__ism_tri) * scene->tri_count);
    m->density = malloc(sizeof(float) * scene->tri_count);
    m->tri_area = malloc(sizeof(double) * scene->tri_count);
    m->template_map = malloc(rs_para_map_bytes(R));
    m->scratch = calloc(threads, sizeof(float *));
    m->row_lo = malloc(sizeof(int) * R);
    m->row_hi = malloc(sizeof(int) * R);
    m->gen = calloc(threads, sizeof(gi__ism_rec *));
    if (!o.atomic_splat) {
        m->sorted = malloc(sizeof(gi__ism_rec) * GI__ISM_REC_CAP);
        m->bucket = malloc(sizeof(uint32_t) * GI__ISM_OFF_CAP);
    }
    int ok = m->tris && m->density && m->tri_area && m->template_map && m->scratch && m->row_lo && m->row_hi &&
             m->gen && (o.atomic_splat || (m->sorted && m->bucket));
    for (uint32_t w = 0; ok && w < threads; w++) {
        m->scratch[w] = calloc(gi_ism_pull_push_scratch_floats(R), sizeof(float));
        ok = m->scratch[w] != NULL;
    }
    if (!ok) {
        gi_ism_destroy(m);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for the ISMs");
    }
    gi__ism_triangles(m, scene, 0, scene->tri_count);
    pf_result r = gi__ism_densities(m, err);
    if (r != PF_OK) {
        gi_ism_destroy(m);
        return r;
    }
    for (uint32_t j = 0; j < R; j++) {
        m->row_lo[j] = (int)R, m->row_hi[j] = -1;
        for (uint32_t i = 0; i < R; i++) {
            int in = rs_para_texel_inside(R, i, j);
            m->template_map[j * R + i] = in ? RS_PARA_EMPTY : RS_PARA_OUTSIDE;
            m->inside_texels += (uint32_t)in;
            if (in && (int)i < m->row_lo[j]) m->row_lo[j] = (int)i;
            if (in) m->row_hi[j] = (int)i;
        }
    }
    *out = m;
    return PF_OK;
}

void gi_ism_destroy(gi_ism *m)
{
    if (!m) return;
    if (m->scratch)
        for (uint32_t w = 0; w < m->workers; w++) free(m->scratch[w]);
    free(m->scratch);
    if (m->gen)
        for (uint32_t w = 0; w < m->workers; w++) free(m->gen[w]);
    free(m->gen), free(m->sorted), free(m->bucket), free(m->item_cap), free(m->item_base);
    free(m->items);
    free(m->tris), free(m->density), free(m->tri_area), free(m->template_map), free(m->row_lo), free(m->row_hi);
    free(m);
}

uint32_t gi_ism_resolution(const gi_ism *m) { return m->opt.resolution; }
uint32_t gi_ism_points(const gi_ism *m) { return m->opt.points; }
float gi_ism_bias_scale(const gi_ism *m) { return m->opt.bias_scale; }

/* Runs fn over count items on jobs, or on this thread (worker 0) without. */
static void gi__ism_for(pf_jobs *jobs, pf_job_fn fn, void *ctx, uint32_t count, uint32_t grain)
{
    if (jobs) pf_jobs_parallel_for(jobs, fn, ctx, count, grain);
    else
        for (uint32_t i = 0; i < count; i++) fn(ctx, i, 0);
}

/* ------------------------------------------------------------------ 1. clear */

static void gi__ism_clear_map(void *p, uint32_t k, uint32_t worker)
{
    (void)worker;
    gi_ism *m = p;
    memcpy(m->atlas + (size_t)k * m->opt.resolution * m->opt.resolution, m->template_map,
           rs_para_map_bytes(m->opt.resolution));
}

void gi_ism_stage_clear(gi_ism *m, uint16_t *atlas, pf_jobs *jobs, uint32_t count)
{
    m->atlas = atlas;
    gi__ism_for(jobs, gi__ism_clear_map, m, count, GI__ISM_MAP_GRAIN);
}

/* ------------------------------------------------------------------ 2. splat */

static inline float gi__unit24(uint64_t h) { return (float)(h >> 40) * 0x1p-24f; } /* [0, 1) */

/* The depth test of the splat: keep the nearer code (atomic min on 16 bits;
 * min is order-free, so the result does not depend on the splat order). */
static inline void gi__atomic_min_u16(uint16_t *p, uint16_t v)
{
    uint16_t cur = __atomic_load_n(p, __ATOMIC_RELAXED);
    while (v < cur && !__atomic_compare_exchange_n(p, &cur, v, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
}

/* The splat of record r into its map mp: the texel the point falls in,
 * plus (geometry shader: "calculate the size of the splat") every inside
 * texel whose centre is within the splat's radius. atomic: by atomic mins
 * (maps shared between threads), else plain mins (the map is this
 * thread's); the same texels and codes either way. */
/* floorf and ceilf of v as int, exactly, for |v| < 2^31 (rt <= 4 and the
 * splat's centre is in the map, so every argument below is): the plain
 * x86-64 build has no rounding instruction, and libm's took a quarter of
 * the splat. */
static inline int gi__floor_int(float v)
{
    int t = (int)v;
    return t - (v < (float)t);
}
static inline int gi__ceil_int(float v)
{
    int t = (int)v;
    return t + (v > (float)t);
}

static inline void gi__ism_splat_rec(const gi_ism *m, uint16_t *mp, const gi__ism_rec *r, int atomic)
{
    const uint32_t R = m->opt.resolution;
    const uint16_t code = r->code;
    if (atomic) gi__atomic_min_u16(mp + r->texel, code);
    else if (code < mp[r->texel]) mp[r->texel] = code;
    const float rt = r->rt, x = r->x, y = r->y;
    if (!(rt > 0.5f)) return;
    int i0 = gi__floor_int(x - rt), i1 = gi__floor_int(x + rt);
    int j0 = gi__floor_int(y - rt), j1 = gi__floor_int(y + rt);
    if (i0 < 0) i0 = 0;
    if (j0 < 0) j0 = 0;
    if (i1 > (int)R - 1) i1 = (int)R - 1;
    if (j1 > (int)R - 1) j1 = (int)R - 1;
    for (int j = j0; j <= j1; j++) {
        /* the row's texels whose centres are in the splat's circle,
         * (i + 0.5 - x)^2 <= rt^2 - cy^2, and in the disc */
        float cy = (float)j + 0.5f - y, h2 = rt * rt - cy * cy;
        if (!(h2 >= 0.0f)) continue;
        float hw = sqrtf(h2);
        int ia = gi__ceil_int(x - hw - 0.5f), ib = gi__floor_int(x + hw - 0.5f);
        if (ia < i0) ia = i0;
        if (ib > i1) ib = i1;
        if (ia < m->row_lo[j]) ia = m->row_lo[j];
        if (ib > m->row_hi[j]) ib = m->row_hi[j];
        uint16_t *row = mp + (size_t)j * R;
        if (atomic)
            for (int k = ia; k <= ib; k++) gi__atomic_min_u16(row + k, code);
        else
            for (int k = ia; k <= ib; k++) row[k] = code < row[k] ? code : row[k];
    }
}

/* The points of splat job item `item` (the tessellation and geometry
 * shaders): with out, each point in front of its VPL becomes a record in
 * out (returns how many); without, each is splatted at once by atomic
 * mins. The points, their VPLs and their records are the same either way. */
static uint32_t gi__ism_item_points(gi_ism *m, uint32_t item, gi__ism_rec *out)
{
    const uint32_t R = m->opt.resolution, N = m->count;
    const size_t map = (size_t)R * R;
    const float scale = m->scale;
    const gi__ism_item *it = &m->items[item];
    uint64_t generated = 0;
    uint32_t splatted = 0;
    for (uint32_t t = it->t0; t < it->t1; t++) {
        /* tessellation control shader: this triangle's point count,
         * floor(P A_i / A) plus one with probability of the fraction */
        uint64_t seed = pf_mix64(((uint64_t)m->frame << 32 | t) ^ 0x5851f42d4c957f2dull);
        float dens = m->density[t];
        float whole = floorf(dens);
        uint32_t n = (uint32_t)whole + (gi__unit24(seed) < dens - whole ? 1u : 0u);
        if (n == 0) continue;
        const gi__ism_tri *T = &m->tris[t];
        uint32_t shift = (uint32_t)(pf_mix64(seed + 1) >> 32);
        float inv_n = 1.0f / (float)n;
        uint32_t k0 = it->k0 < n ? it->k0 : n, k1 = it->k1 < n ? it->k1 : n;
        for (uint32_t k = k0; k < k1; k++) {
            /* tessellation evaluation shader: a stratified position and the
             * point's seed */
            uint64_t h = pf_mix64(seed + ((uint64_t)k + 2) * 0x9e3779b97f4a7c15ull);
            float u1 = ((float)k + gi__unit24(h)) * inv_n;
            /* frac(k phi + shift) in 32-bit fixed point: exact for any k */
            float u2 = (float)(((uint32_t)k * 2654435769u + shift) >> 8) * 0x1p-24f;
            float s = sqrtf(u1), a = s * (1.0f - u2), b = s * u2;
            pf_vec3 q = pf_v3(T->v0[0] + (a * T->e1[0] + b * T->e2[0]), T->v0[1] + (a * T->e1[1] + b * T->e2[1]),
                              T->v0[2] + (a * T->e1[2] + b * T->e2[2]));
            /* geometry shader: one VPL at random, the point in its map */
            uint32_t vi = (uint32_t)(((h & 0xffffffffull) * N) >> 32);
            const rs_para_frame *f = &m->frames[vi];
            pf_vec3 d = rs_para_to_local(f, q);
            if (!(d.z > 0.0f)) continue; /* behind the VPL's tangent plane */
            float dist = pf_v3_length(d);
            float c = dist * scale; /* rs_paraboloid's quantisation: floor(t S), clamped */
            gi__ism_rec r;
            r.code = c < (float)RS_PARA_MAX_CODE ? (uint16_t)c : (uint16_t)RS_PARA_MAX_CODE;
            r.pad = 0;
            r.vi = vi;
            /* the texel it falls in (rs_para_texel_of's u, v for z > 0) and
             * the splat's size: the point's disc of area A count / P (its
             * VPL's share of the points) seen from the VPL: angle r / dist,
             * in texels r / dist (1 + u^2 + v^2) R / 4 (dtheta = 2 drho /
             * (1 + rho^2), R / 2 texels per unit of u), capped */
            float den = dist + d.z, u = d.x / den, v = d.y / den;
            r.texel = rs_para_texel_of_uv(R, u, v);
            float rt = m->point_radius / dist * (1.0f + (u * u + v * v)) * (float)R * 0.25f;
            r.rt = rt > GI_ISM_MAX_SPLAT ? GI_ISM_MAX_SPLAT : rt;
            r.x = (u + 1.0f) * (float)R * 0.5f, r.y = (v + 1.0f) * (float)R * 0.5f;
            if (out) out[splatted] = r;
            else gi__ism_splat_rec(m, m->atlas + vi * map, &r, 1);
            splatted++;
        }
        generated += k1 - k0;
    }
    __atomic_fetch_add(&m->generated, generated, __ATOMIC_RELAXED);
    __atomic_fetch_add(&m->splatted, (uint64_t)splatted, __ATOMIC_RELAXED);
    return splatted;
}

/* The atomic splat: one job item's points straight into the shared maps. */
static void gi__ism_splat_chunk(void *p, uint32_t item, uint32_t worker)
{
    (void)worker;
    gi__ism_item_points(p, item, NULL);
}

/* The binned splat, a batch of items b0.. at a time: each item's records
 * (made in the worker's buffer) are sorted by map into the item's run of
 * `sorted` (a counting sort that keeps their order), its bucket offsets in
 * bucket + q (N + 1); then each map is splatted by one thread from every
 * item's bucket for it, with plain mins on a map that fits the L1 cache. */
typedef struct gi__ism_batch {
    gi_ism *m;
    uint32_t b0, items;
} gi__ism_batch;

static void gi__ism_bin_item(void *p, uint32_t q, uint32_t worker)
{
    const gi__ism_batch *b = p;
    gi_ism *m = b->m;
    const uint32_t N = m->count;
    gi__ism_rec *gen = m->gen[worker];
    uint32_t n = gi__ism_item_points(m, b->b0 + q, gen);
    uint32_t *off = m->bucket + (size_t)q * (N + 1);
    memset(off, 0, sizeof(uint32_t) * (N + 1));
    for (uint32_t k = 0; k < n; k++) off[gen[k].vi + 1]++;
    for (uint32_t v = 0; v < N; v++) off[v + 1] += off[v];
    /* off[v]: bucket v's start; after the scatter, its end (bucket v + 1's start) */
    gi__ism_rec *dst = m->sorted + m->item_base[q];
    for (uint32_t k = 0; k < n; k++) dst[off[gen[k].vi]++] = gen[k];
}

static void gi__ism_splat_maps(void *p, uint32_t g, uint32_t worker)
{
    (void)worker;
    const gi__ism_batch *b = p;
    const gi_ism *m = b->m;
    const uint32_t R = m->opt.resolution, N = m->count;
    const size_t map = (size_t)R * R;
    uint32_t v1 = (g + 1) * GI__ISM_MAP_GRAIN < N ? (g + 1) * GI__ISM_MAP_GRAIN : N;
    for (uint32_t v = g * GI__ISM_MAP_GRAIN; v < v1; v++) {
        uint16_t *mp = m->atlas + v * map;
        for (uint32_t q = 0; q < b->items; q++) {
            const uint32_t *off = m->bucket + (size_t)q * (N + 1);
            const gi__ism_rec *run = m->sorted + m->item_base[q];
            for (uint32_t k = v ? off[v - 1] : 0; k < off[v]; k++) gi__ism_splat_rec(m, mp, &run[k], 0);
        }
    }
}

void gi_ism_stage_splat(gi_ism *m, uint16_t *atlas, pf_jobs *jobs, const rs_para_frame *frames, uint32_t count,
                        float range, uint32_t frame, gi_ism_stats *stats)
{
    m->atlas = atlas;
    m->frames = frames;
    m->count = count;
    m->frame = frame;
    m->scale = RS_PARA_CODES / range;
    /* each VPL gets P / count of the points: one stands for A count / P */
    m->point_radius = (float)sqrt(m->area * (double)count / ((double)m->opt.points * 3.14159265358979));
    m->generated = m->splatted = 0;
    if (count == 0) return;
    if (!m->binned || (uint64_t)count + 1 > GI__ISM_OFF_CAP) {
        gi__ism_for(jobs, gi__ism_splat_chunk, m, m->item_count, 1);
    } else {
        const uint32_t most_items = GI__ISM_OFF_CAP / (count + 1);
        for (uint32_t b0 = 0; b0 < m->item_count;) {
            /* the batch: as many items as the records and offsets hold */
            uint32_t q = 0, used = 0;
            while (b0 + q < m->item_count && q < most_items && m->item_cap[b0 + q] <= GI__ISM_REC_CAP - used) {
                m->item_base[q] = used;
                used += m->item_cap[b0 + q];
                q++;
            }
            gi__ism_batch b = {m, b0, q};
            gi__ism_for(jobs, gi__ism_bin_item, &b, q, 1);
            gi__ism_for(jobs, gi__ism_splat_maps, &b, (count + GI__ISM_MAP_GRAIN - 1) / GI__ISM_MAP_GRAIN, 1);
            b0 += q;
        }
    }
    if (stats) stats->points += m->generated, stats->splatted += m->splatted;
}

/* ------------------------------------------------------------------ 3. pull-push */

size_t gi_ism_pull_push_scratch_floats(uint32_t R)
{
    size_t n = 0;
    for (uint32_t s = R; s >= 1; s /= 2) n += 2 * (size_t)s * s; /* value and weight per level */
    return n;
}

/* Pull-push (Grossman and Dally 1998; Marroquim et al. 2007), on the R x R
 * map and its pyramid of R/2, R/4, ..., 1 texels per side:
 * - pull: a coarse texel is the average of its (up to 4) valid children and
 *   is valid if any child is (weights min(1, sum of the children's weights)
 *   with 0/1 weights at the finest level);
 * - push: from the coarsest level down, every invalid texel takes the
 *   bilinear interpolation of the 4 nearest coarser texels (weights 9, 3, 3,
 *   1 / 16, renormalised over the valid ones), and becomes valid.
 * Codes are distances in steps, so averaging codes averages distances. */
uint32_t gi_ism_pull_push(uint16_t *map, uint32_t R, float *scratch)
{
    float *val[32], *wgt[32];
    uint32_t L = 0;
    float *p = scratch;
    for (uint32_t s = R; s >= 1; s /= 2, L++) {
        val[L] = p, p += (size_t)s * s;
        wgt[L] = p, p += (size_t)s * s;
    }
    /* level 0: the splatted codes */
    size_t have = 0;
    for (size_t i = 0; i < (size_t)R * R; i++) {
        uint16_t c = map[i];
        int ok = c <= RS_PARA_MAX_CODE;
        val[0][i] = ok ? (float)c : 0.0f;
        wgt[0][i] = ok ? 1.0f : 0.0f;
        have += (size_t)ok;
    }
    if (have == 0) return 0; /* nothing to interpolate from */
    /* pull */
    for (uint32_t l = 1; l < L; l++) {
        uint32_t s = R >> l, cs = s * 2;
        for (uint32_t j = 0; j < s; j++)
            for (uint32_t i = 0; i < s; i++) {
                float sum = 0.0f, w = 0.0f;
                for (uint32_t dj = 0; dj < 2; dj++)
                    for (uint32_t di = 0; di < 2; di++) {
                        size_t c = (size_t)(2 * j + dj) * cs + (2 * i + di);
                        sum += wgt[l - 1][c] * val[l - 1][c];
                        w += wgt[l - 1][c];
                    }
                val[l][j * s + i] = w > 0.0f ? sum / w : 0.0f;
                wgt[l][j * s + i] = w > 1.0f ? 1.0f : w;
            }
    }
    /* push */
    for (uint32_t l = L - 1; l-- > 0;) {
        uint32_t s = R >> l, ps = s / 2;
        for (uint32_t j = 0; j < s; j++)
            for (uint32_t i = 0; i < s; i++) {
                size_t k = (size_t)j * s + i;
                if (wgt[l][k] > 0.0f) continue;
                int pi = (int)(i / 2), pj = (int)(j / 2);
                int di = (i & 1) ? 1 : -1, dj = (j & 1) ? 1 : -1;
                const int oi[4] = {0, di, 0, di}, oj[4] = {0, 0, dj, dj};
                const float wk[4] = {9.0f, 3.0f, 3.0f, 1.0f};
                float sum = 0.0f, w = 0.0f;
                for (int q = 0; q < 4; q++) {
                    int x = pi + oi[q], y = pj + oj[q];
                    if (x < 0 || y < 0 || x >= (int)ps || y >= (int)ps) continue;
                    size_t c = (size_t)y * ps + (size_t)x;
                    if (!(wgt[l + 1][c] > 0.0f)) continue;
                    sum += wk[q] * val[l + 1][c];
                    w += wk[q];
                }
                if (w > 0.0f) {
                    val[l][k] = sum / w;
                    wgt[l][k] = 1.0f;
                }
            }
    }
    /* back to codes: only the holes inside the disc change */
    uint32_t filled = 0;
    for (size_t i = 0; i < (size_t)R * R; i++) {
        if (map[i] != RS_PARA_EMPTY || !(wgt[0][i] > 0.0f)) continue;
        float c = val[0][i] + 0.5f; /* round to the nearest code */
        map[i] = c < (float)RS_PARA_MAX_CODE ? (uint16_t)c : (uint16_t)RS_PARA_MAX_CODE;
        filled++;
    }
    return filled;
}

static void gi__ism_pull_push_map(void *p, uint32_t k, uint32_t worker)
{
    gi_ism *m = p;
    const uint32_t R = m->opt.resolution;
    uint32_t filled = gi_ism_pull_push(m->atlas + (size_t)k * R * R, R, m->scratch[worker]);
    __atomic_fetch_add(&m->filled, (uint64_t)filled, __ATOMIC_RELAXED);
}

void gi_ism_stage_pull_push(gi_ism *m, uint16_t *atlas, pf_jobs *jobs, uint32_t count, gi_ism_stats *stats)
{
    m->atlas = atlas;
    m->filled = 0;
    gi__ism_for(jobs, gi__ism_pull_push_map, m, count, GI__ISM_MAP_GRAIN);
    if (stats) stats->holes_filled += m->filled, stats->texels += (uint64_t)m->inside_texels * count;
}

/* ------------------------------------------------------------------ render */

void gi_ism_render(gi_ism *m, uint16_t *atlas, pf_jobs *jobs, const rs_para_frame *frames, uint32_t count,
                   float range, uint32_t frame, gi_ism_stats *stats)
{
    if (jobs && pf_jobs_thread_count(jobs) > m->workers) jobs = NULL; /* scratch sized for fewer: stay serial */
    gi_ism_stage_clear(m, atlas, jobs, count);
    gi_ism_stage_splat(m, atlas, jobs, frames, count, range, frame, stats);
    gi_ism_stage_pull_push(m, atlas, jobs, count, stats);
}

/* ------------------------------------------------------------------ lookup */
