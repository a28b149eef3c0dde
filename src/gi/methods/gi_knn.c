/* gi_knn: k-d tree k-nearest-neighbour queries (see gi_knn.h; Hedman 2017
 * Sec. 3.2.4 and Sec. 4). */
#include "gi_knn.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A point during the build: its coordinates and its index, moved as one. */
struct gi_knn_rec {
    float c[3];
    uint32_t i;
};

/* An inner node: [lo, mid) at or below `split` on `axis`, [mid, hi) at or
 * above; the left child is the next node, the right one is `right`. */
struct gi_knn_node {
    float split;
    uint32_t mid, right, axis;
};

/* Inner nodes of a tree over n points: every split leaves at least
 * n / 8 >= 2 points on each side, so leaves hold two points or more and
 * there are fewer than n / 2 inner nodes. */
static uint32_t gi__node_cap(uint32_t n) { return n / 2 + 1; }

/* Selection (Wirth's variant of Hoare's): permutes r[0, n) so that r[k]
 * has rank k on axis a, with r[0, k) at or below it and r(k, n) at or
 * above it. Equal coordinates split evenly (many duplicates stay O(n));
 * the pivot's own value stops both scans, so they stay inside the range. */
static void gi__select(gi_knn_rec *r, uint32_t n, uint32_t k, uint32_t a)
{
    int64_t l = 0, m = (int64_t)n - 1;
    while (l < m) {
        const float x = r[k].c[a];
        int64_t i = l, j = m;
        do {
            while (r[i].c[a] < x) i++;
            while (x < r[j].c[a]) j--;
            if (i <= j) {
                gi_knn_rec t = r[i];
                r[i] = r[j];
                r[j] = t;
                i++, j--;
            }
        } while (i <= j);
        if (j < (int64_t)k) l = i;
        if ((int64_t)k < i) m = j;
    }
}

/* Branch-free partition: r[0, m) < v <= r[m, n) on axis a; returns m. */
static uint32_t gi__partition(gi_knn_rec *r, uint32_t n, uint32_t a, float v)
{
    uint32_t j = 0;
    for (uint32_t i = 0; i < n; i++) {
        gi_knn_rec t = r[i];
        r[i] = r[j];
        r[j] = t;
        j += t.c[a] < v;
    }
    return j;
}

/* The median of up to 15 evenly spaced coordinates of r[0, n) on axis a. */
static float gi__sample_median(const gi_knn_rec *r, uint32_t n, uint32_t a)
{
    float s[15];
    uint32_t m = n < 15 ? n : 15;
    for (uint32_t i = 0; i < m; i++) {
        float c = r[(uint32_t)(((uint64_t)(2 * i + 1) * n) / (2 * m))].c[a];
        uint32_t j = i;
        for (; j > 0 && s[j - 1] > c; j--) s[j] = s[j - 1];
        s[j] = c;
    }
    return s[m / 2];
}

static void gi__build(gi_knn *t, uint32_t lo, uint32_t hi)
{
    while (hi - lo > GI_KNN_LEAF) {
        gi_knn_rec *r = t->rec + lo;
        const uint32_t n = hi - lo;
        float mn[3] = {r[0].c[0], r[0].c[1], r[0].c[2]}, mx[3] = {mn[0], mn[1], mn[2]};
        for (uint32_t i = 1; i < n; i++) /* compares, not fminf: libm calls here cost more than the split */
            for (int a = 0; a < 3; a++) {
                float c = r[i].c[a];
                mn[a] = c < mn[a] ? c : mn[a];
                mx[a] = c > mx[a] ? c : mx[a];
            }
        float ex = mx[0] - mn[0], ey = mx[1] - mn[1], ez = mx[2] - mn[2];
        uint32_t a = ex >= ey && ex >= ez ? 0u : (ey >= ez ? 1u : 2u);
        float v = gi__sample_median(r, n, a);
        uint32_t m = gi__partition(r, n, a, v);
        if (m < n / 8 || n - m < n / 8) { /* a poor sample (or many equal coordinates): the exact median */
            m = n / 2;
            gi__select(r, n, m, a);
            v = r[m].c[a];
        }
        gi_knn_node *N = &t->node[t->node_count++];
        N->axis = a, N->split = v, N->mid = lo + m;
        gi__build(t, lo, lo + m);
        N->right = t->node_count;
        lo += m; /* the right half iteratively */
    }
}

static pf_result gi__reserve(gi_knn *t, uint32_t count, int facing, pf_error *err)
{
    uint32_t nodes = gi__node_cap(count);
    if (count > t->cap || !t->rec || (facing && !t->nx)) {
        uint32_t cap = count > t->cap ? count : t->cap;
        cap = cap ? cap : 1;
        free(t->x), free(t->y), free(t->z), free(t->idx), free(t->rec), free(t->nx), free(t->ny), free(t->nz);
        t->x = malloc(sizeof(float) * cap), t->y = malloc(sizeof(float) * cap), t->z = malloc(sizeof(float) * cap);
        t->nx = malloc(sizeof(float) * cap), t->ny = malloc(sizeof(float) * cap), t->nz = malloc(sizeof(float) * cap);
        t->idx = malloc(sizeof(uint32_t) * cap);
        t->rec = malloc(sizeof(gi_knn_rec) * cap);
        t->cap = t->x && t->y && t->z && t->nx && t->ny && t->nz && t->idx && t->rec ? cap : 0;
        if (!t->cap) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %u-point k-d tree", count);
    }
    if (nodes > t->node_cap) {
        free(t->node);
        t->node = malloc(sizeof(gi_knn_node) * nodes);
        t->node_cap = t->node ? nodes : 0;
        if (!t->node_cap) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %u-point k-d tree", count);
    }
    return PF_OK;
}

static pf_result gi__build_tree(gi_knn *t, const pf_vec3 *pts, const pf_vec3 *nrms, uint32_t count, pf_error *err)
{
    pf_result r = gi__reserve(t, count, nrms != NULL, err);
    if (r != PF_OK) return r;
    t->count = count;
    t->node_count = 0;
    t->facing = nrms != NULL;
    for (uint32_t i = 0; i < count; i++) t->rec[i] = (gi_knn_rec){{pts[i].x, pts[i].y, pts[i].z}, i};
    gi__build(t, 0, count);
    for (uint32_t i = 0; i < count; i++) {
        t->x[i] = t->rec[i].c[0], t->y[i] = t->rec[i].c[1], t->z[i] = t->rec[i].c[2];
        t->idx[i] = t->rec[i].i;
    }
    if (nrms)
        for (uint32_t i = 0; i < count; i++) {
            const pf_vec3 *n = &nrms[t->idx[i]];
            t->nx[i] = n->x, t->ny[i] = n->y, t->nz[i] = n->z;
        }
    return PF_OK;
}

pf_result gi_knn_build(gi_knn *t, const pf_vec3 *pts, uint32_t count, pf_error *err)
{
    return gi__build_tree(t, pts, NULL, count, err);
}

pf_result gi_knn_build_facing(gi_knn *t, const pf_vec3 *pts, const pf_vec3 *nrms, uint32_t count, pf_error *err)
{
    return gi__build_tree(t, pts, nrms, count, err);
}

void gi_knn_free(gi_knn *t)
{
    free(t->x), free(t->y), free(t->z), free(t->nx), free(t->ny), free(t->nz), free(t->idx), free(t->rec);
    free(t->node);
    memset(t, 0, sizeof *t);
}

/* Squared distances from q to the points [lo, lo + n) of a leaf, each
 * dot(p - q, p - q) as the brute force computes it. */
static void gi__leaf_dist2(const gi_knn *t, uint32_t lo, uint32_t n, const float q[3], float *d)
{
    const float *x = t->x + lo, *y = t->y + lo, *z = t->z + lo;
    for (uint32_t i = 0; i < n; i++) {
        float dx = x[i] - q[0], dy = y[i] - q[1], dz = z[i] - q[2];
        d[i] = dx * dx + dy * dy + dz * dz;
    }
}

/* The k best squared distances so far, ascending (insertion: k <= 64). */
typedef struct gi__heap {
    uint32_t k, n;
    float d[GI_KNN_MAX_K];
} gi__heap;

static float gi__worst(const gi__heap *h) { return h->n < h->k ? INFINITY : h->d[h->k - 1]; }

static void gi__push(gi__heap *h, float d2)
{
    if (h->n == h->k && !(d2 < h->d[h->k - 1])) return;
    uint32_t i = h->n < h->k ? h->n++ : h->k - 1;
    while (i > 0 && h->d[i - 1] > d2) {
        h->d[i] = h->d[i - 1];
        i--;
    }
    h->d[i] = d2;
}

/* The squared distance from q to a cell that lies off[a] away from it on
 * each axis, a lower bound on every point's of the cell: each point's
 * |p_a - q_a| rounds to at least off[a] = |split - q_a| (the split lies
 * between them), and squares and sums round monotonically, so
 * (dx dx + dy dy) + dz dz >= (off_x off_x + off_y off_y) + off_z off_z
 * (Arya and Mount's incremental distance, computed afresh, never updated
 * by differences that could round below the bound). */
static inline float gi__cell_dist2(const float off[3]) { return off[0] * off[0] + off[1] * off[1] + off[2] * off[2]; }

/* Near side first, the far side only if its cell is no farther than the
 * current k-th distance. */
static void gi__query(const gi_knn *t, uint32_t node, uint32_t lo, uint32_t hi, const float q[3], float o0, float o1,
                      float o2, uint32_t exclude, gi__heap *hp)
{
    float off[3] = {o0, o1, o2};
    while (hi - lo > GI_KNN_LEAF) {
        const gi_knn_node *N = &t->node[node];
        float delta = q[N->axis] - N->split;
        if (delta < 0.0f) {
            gi__query(t, node + 1, lo, N->mid, q, off[0], off[1], off[2], exclude, hp);
            node = N->right, lo = N->mid;
        } else {
            gi__query(t, N->right, N->mid, hi, q, off[0], off[1], off[2], exclude, hp);
            node = node + 1, hi = N->mid;
        }
        off[N->axis] = fabsf(delta);
        if (!(gi__cell_dist2(off) <= gi__worst(hp))) return;
    }
    float d[GI_KNN_LEAF];
    gi__leaf_dist2(t, lo, hi - lo, q, d);
    for (uint32_t i = 0; i < hi - lo; i++)
        if (t->idx[lo + i] != exclude) gi__push(hp, d[i]);
}

float gi_knn_kth_dist2(const gi_knn *t, pf_vec3 q, uint32_t k, uint32_t exclude)
{
    gi__heap h;
    h.k = k < 1 ? 1 : (k > GI_KNN_MAX_K ? GI_KNN_MAX_K : k);
    h.n = 0;
    const float qq[3] = {q.x, q.y, q.z};
    if (t->count) gi__query(t, 0, 0, t->count, qq, 0.0f, 0.0f, 0.0f, exclude, &h);
    return gi__worst(&h);
}

/* The best (d2, index) so far in the total order (distance, index), among
 * the points ok accepts (all when ok is NULL), or (facing) among those
 * whose normal m has pf_v3_dot(m, n) >= cos_min. */
typedef struct gi__best {
    float d2;
    uint32_t i;
    int (*ok)(const void *ctx, uint32_t index);
    const void *ctx;
    int facing;
    float n[3], cos_min;
} gi__best;

/* <=: a point of the far cell at the same distance may have a lower index */
static void gi__nearest(const gi_knn *t, uint32_t node, uint32_t lo, uint32_t hi, const float q[3], float o0, float o1,
                        float o2, gi__best *b)
{
    float off[3] = {o0, o1, o2};
    while (hi - lo > GI_KNN_LEAF) {
        const gi_knn_node *N = &t->node[node];
        float delta = q[N->axis] - N->split;
        if (delta < 0.0f) {
            gi__nearest(t, node + 1, lo, N->mid, q, off[0], off[1], off[2], b);
            node = N->right, lo = N->mid;
        } else {
            gi__nearest(t, N->right, N->mid, hi, q, off[0], off[1], off[2], b);
            node = node + 1, hi = N->mid;
        }
        off[N->axis] = fabsf(delta);
        if (!(gi__cell_dist2(off) <= b->d2)) return;
    }
    const uint32_t n = hi - lo;
    float d[GI_KNN_LEAF];
    gi__leaf_dist2(t, lo, n, q, d);
    if (b->facing) {
        const float *nx = t->nx + lo, *ny = t->ny + lo, *nz = t->nz + lo;
        float f[GI_KNN_LEAF];
        for (uint32_t i = 0; i < n; i++) f[i] = nx[i] * b->n[0] + ny[i] * b->n[1] + nz[i] * b->n[2];
        for (uint32_t i = 0; i < n; i++) {
            uint32_t ix = t->idx[lo + i];
            if (f[i] >= b->cos_min && (d[i] < b->d2 || (d[i] == b->d2 && ix < b->i))) b->d2 = d[i], b->i = ix;
        }
        return;
    }
    for (uint32_t i = 0; i < n; i++) {
        uint32_t ix = t->idx[lo + i];
        if ((d[i] < b->d2 || (d[i] == b->d2 && ix < b->i)) && (!b->ok || b->ok(b->ctx, ix))) b->d2 = d[i], b->i = ix;
    }
}

static uint32_t gi__nearest_root(const gi_knn *t, pf_vec3 q, gi__best *b, float *dist2)
{
    const float qq[3] = {q.x, q.y, q.z};
    if (t->count) gi__nearest(t, 0, 0, t->count, qq, 0.0f, 0.0f, 0.0f, b);
    if (dist2) *dist2 = b->d2;
    return b->i;
}

uint32_t gi_knn_nearest(const gi_knn *t, pf_vec3 q, float *dist2)
{
    gi__best b = {INFINITY, GI_KNN_NONE, NULL, NULL, 0, {0, 0, 0}, 0.0f};
    return gi__nearest_root(t, q, &b, dist2);
}

uint32_t gi_knn_nearest_where(const gi_knn *t, pf_vec3 q, int (*ok)(const void *ctx, uint32_t index),
                              const void *ctx, float *dist2)
{
    gi__best b = {INFINITY, GI_KNN_NONE, ok, ctx, 0, {0, 0, 0}, 0.0f};
    return gi__nearest_root(t, q, &b, dist2);
}

uint32_t gi_knn_nearest_facing(const gi_knn *t, pf_vec3 q, pf_vec3 n, float cos_min, float *dist2)
{
    gi__best b = {INFINITY, GI_KNN_NONE, NULL, NULL, t->facing, {n.x, n.y, n.z}, cos_min};
    if (!t->facing) { /* no normals: nothing qualifies */
        if (dist2) *dist2 = INFINITY;
        return GI_KNN_NONE;
    }
    return gi__nearest_root(t, q, &b, dist2);
}

float gi_knn_density(uint32_t k, uint32_t n, float r2)
{
    if (isinf(r2) || n == 0) return 0.0f;
    if (!(r2 > 0.0f)) return INFINITY;
    return (float)((double)k / ((double)n * PF_PI * (double)r2));
}
