/* gi_knn: k-d tree k-nearest-neighbour queries (see gi_knn.h; Hedman 2017
 * Sec. 3.2.4 and Sec. 4). */
#include "gi_knn.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static inline float gi__coord(const pf_vec3 *p, uint32_t a) { return a == 0 ? p->x : (a == 1 ? p->y : p->z); }

/* The total order the split uses: coordinate on axis a, then index. */
static inline int gi__less(const gi_knn *t, uint32_t a, uint32_t i, uint32_t j)
{
    float ci = gi__coord(&t->pts[i], a), cj = gi__coord(&t->pts[j], a);
    return ci < cj || (ci == cj && i < j);
}

/* Quickselect: permutes idx[lo, hi) so that idx[m] is the element of rank
 * m - lo in the order above, smaller ones before it, larger after. Pivot:
 * median of three, so sorted input stays O(n). */
static void gi__select(gi_knn *t, uint32_t a, uint32_t lo, uint32_t hi, uint32_t m)
{
    uint32_t *x = t->idx;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2, last = hi - 1;
        /* order x[lo], x[mid], x[last]; the median goes to x[last] as pivot */
        if (gi__less(t, a, x[mid], x[lo])) { uint32_t s = x[mid]; x[mid] = x[lo]; x[lo] = s; }
        if (gi__less(t, a, x[last], x[lo])) { uint32_t s = x[last]; x[last] = x[lo]; x[lo] = s; }
        if (gi__less(t, a, x[mid], x[last])) { uint32_t s = x[mid]; x[mid] = x[last]; x[last] = s; }
        uint32_t pivot = x[last], store = lo;
        for (uint32_t i = lo; i < last; i++)
            if (gi__less(t, a, x[i], pivot)) { uint32_t s = x[i]; x[i] = x[store]; x[store] = s; store++; }
        x[last] = x[store];
        x[store] = pivot;
        if (store == m) return;
        if (m < store) hi = store;
        else lo = store + 1;
    }
}

static void gi__build(gi_knn *t, uint32_t lo, uint32_t hi)
{
    while (hi - lo > 1) {
        pf_vec3 mn = t->pts[t->idx[lo]], mx = mn;
        for (uint32_t i = lo + 1; i < hi; i++) {
            pf_vec3 p = t->pts[t->idx[i]];
            mn = pf_v3(fminf(mn.x, p.x), fminf(mn.y, p.y), fminf(mn.z, p.z));
            mx = pf_v3(fmaxf(mx.x, p.x), fmaxf(mx.y, p.y), fmaxf(mx.z, p.z));
        }
        pf_vec3 e = pf_v3_sub(mx, mn);
        uint32_t a = e.x >= e.y && e.x >= e.z ? 0u : (e.y >= e.z ? 1u : 2u);
        uint32_t mid = lo + (hi - lo) / 2;
        gi__select(t, a, lo, hi, mid);
        t->axis[mid] = (uint8_t)a;
        gi__build(t, lo, mid);
        lo = mid + 1; /* the right half iteratively */
    }
    if (hi - lo == 1) t->axis[lo] = 0;
}

pf_result gi_knn_build(gi_knn *t, const pf_vec3 *pts, uint32_t count, pf_error *err)
{
    if (count > t->cap) {
        uint32_t cap = count;
        pf_vec3 *p = realloc(t->pts, sizeof(pf_vec3) * cap);
        if (p) t->pts = p;
        uint32_t *ix = realloc(t->idx, sizeof(uint32_t) * cap);
        if (ix) t->idx = ix;
        uint8_t *ax = realloc(t->axis, cap);
        if (ax) t->axis = ax;
        pf_vec3 *tp = realloc(t->tpts, sizeof(pf_vec3) * cap);
        if (tp) t->tpts = tp;
        if (!p || !ix || !ax || !tp)
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %u-point k-d tree", count);
        t->cap = cap;
    }
    t->count = count;
    if (count) memcpy(t->pts, pts, sizeof(pf_vec3) * count);
    for (uint32_t i = 0; i < count; i++) t->idx[i] = i;
    gi__build(t, 0, count);
    for (uint32_t i = 0; i < count; i++) t->tpts[i] = t->pts[t->idx[i]];
    return PF_OK;
}

void gi_knn_free(gi_knn *t)
{
    free(t->pts);
    free(t->idx);
    free(t->axis);
    free(t->tpts);
    memset(t, 0, sizeof *t);
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

static void gi__query(const gi_knn *t, uint32_t lo, uint32_t hi, pf_vec3 q, uint32_t exclude, gi__heap *h)
{
    while (hi > lo) {
        if (hi - lo <= 8) { /* small node: scan */
            for (uint32_t i = lo; i < hi; i++) {
                if (t->idx[i] == exclude) continue;
                pf_vec3 d = pf_v3_sub(t->tpts[i], q);
                gi__push(h, pf_v3_dot(d, d));
            }
            return;
        }
        uint32_t mid = lo + (hi - lo) / 2;
        if (t->idx[mid] != exclude) {
            pf_vec3 d = pf_v3_sub(t->tpts[mid], q);
            gi__push(h, pf_v3_dot(d, d));
        }
        float delta = gi__coord(&q, t->axis[mid]) - gi__coord(&t->tpts[mid], t->axis[mid]);
        /* near side first, the far side only if the splitting plane is
         * closer than the current k-th distance */
        uint32_t nlo = delta < 0.0f ? lo : mid + 1, nhi = delta < 0.0f ? mid : hi;
        uint32_t flo = delta < 0.0f ? mid + 1 : lo, fhi = delta < 0.0f ? hi : mid;
        gi__query(t, nlo, nhi, q, exclude, h);
        if (!(delta * delta <= gi__worst(h))) return;
        lo = flo, hi = fhi;
    }
}

float gi_knn_kth_dist2(const gi_knn *t, pf_vec3 q, uint32_t k, uint32_t exclude)
{
    gi__heap h;
    h.k = k < 1 ? 1 : (k > GI_KNN_MAX_K ? GI_KNN_MAX_K : k);
    h.n = 0;
    gi__query(t, 0, t->count, q, exclude, &h);
    return gi__worst(&h);
}

/* The best (d2, index) so far in the total order (distance, index), among
 * the points ok accepts (all when ok is NULL). */
typedef struct gi__best {
    float d2;
    uint32_t i;
    int (*ok)(const void *ctx, uint32_t index);
    const void *ctx;
} gi__best;

static void gi__offer(gi__best *b, float d2, uint32_t i)
{
    if ((d2 < b->d2 || (d2 == b->d2 && i < b->i)) && (!b->ok || b->ok(b->ctx, i))) b->d2 = d2, b->i = i;
}

static void gi__nearest(const gi_knn *t, uint32_t lo, uint32_t hi, pf_vec3 q, gi__best *b)
{
    while (hi > lo) {
        if (hi - lo <= 8) {
            for (uint32_t i = lo; i < hi; i++) {
                pf_vec3 d = pf_v3_sub(t->tpts[i], q);
                gi__offer(b, pf_v3_dot(d, d), t->idx[i]);
            }
            return;
        }
        uint32_t mid = lo + (hi - lo) / 2;
        pf_vec3 d = pf_v3_sub(t->tpts[mid], q);
        gi__offer(b, pf_v3_dot(d, d), t->idx[mid]);
        float delta = gi__coord(&q, t->axis[mid]) - gi__coord(&t->tpts[mid], t->axis[mid]);
        uint32_t nlo = delta < 0.0f ? lo : mid + 1, nhi = delta < 0.0f ? mid : hi;
        uint32_t flo = delta < 0.0f ? mid + 1 : lo, fhi = delta < 0.0f ? hi : mid;
        gi__nearest(t, nlo, nhi, q, b);
        /* <=: a point on the far side at the same distance may have a lower index */
        if (!(delta * delta <= b->d2)) return;
        lo = flo, hi = fhi;
    }
}

uint32_t gi_knn_nearest(const gi_knn *t, pf_vec3 q, float *dist2)
{
    gi__best b = {INFINITY, GI_KNN_NONE, NULL, NULL};
    gi__nearest(t, 0, t->count, q, &b);
    if (dist2) *dist2 = b.d2;
    return b.i;
}

uint32_t gi_knn_nearest_where(const gi_knn *t, pf_vec3 q, int (*ok)(const void *ctx, uint32_t index),
                              const void *ctx, float *dist2)
{
    gi__best b = {INFINITY, GI_KNN_NONE, ok, ctx};
    gi__nearest(t, 0, t->count, q, &b);
    if (dist2) *dist2 = b.d2;
    return b.i;
}

float gi_knn_density(uint32_t k, uint32_t n, float r2)
{
    if (isinf(r2) || n == 0) return 0.0f;
    if (!(r2 > 0.0f)) return INFINITY;
    return (float)((double)k / ((double)n * PF_PI * (double)r2));
}
