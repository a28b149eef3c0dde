/* gi_delaunay: Delaunay triangulations on the unit disc and the unit sphere
 * with exact integer predicates (Laine 2007 Sec. 4.1, 4.3, 4.5-4.7; see
 * gi_delaunay.h for the conventions). */
#include "gi_delaunay.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef __int128 gi__i128;

#define GI__DEAD 0u
#define GI__LIVE 1u
#define GI__CAV 2u /* in the cavity being replaced */

/* ------------------------------------------------------------ predicates */

/* > 0 if c lies left of a->b. |diff| < 2^26: products < 2^52, exact in int64. */
static int gi__orient2d(const int64_t *a, const int64_t *b, const int64_t *c)
{
    int64_t d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    return (d > 0) - (d < 0);
}

/* > 0 if d lies inside the circle through a, b, c (CCW). */
static int gi__incircle(const int64_t *a, const int64_t *b, const int64_t *c, const int64_t *d)
{
    int64_t adx = a[0] - d[0], ady = a[1] - d[1], bdx = b[0] - d[0], bdy = b[1] - d[1];
    int64_t cdx = c[0] - d[0], cdy = c[1] - d[1];
    int64_t al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy, cl = cdx * cdx + cdy * cdy; /* < 2^53 */
    int64_t bc = bdx * cdy - cdx * bdy, ca = cdx * ady - adx * cdy, ab = adx * bdy - bdx * ady;
    gi__i128 det = (gi__i128)al * bc + (gi__i128)bl * ca + (gi__i128)cl * ab;
    return (det > 0) - (det < 0);
}

/* > 0 if p lies on the outer side of the plane through a, b, c (normal
 * (b - a) x (c - a)): "p sees the face". */
static int gi__side3(const int64_t *a, const int64_t *b, const int64_t *c, const int64_t *p)
{
    int64_t ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    int64_t vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    int64_t nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx; /* < 2^53 */
    gi__i128 d = (gi__i128)nx * (p[0] - a[0]) + (gi__i128)ny * (p[1] - a[1]) + (gi__i128)nz * (p[2] - a[2]);
    return (d > 0) - (d < 0);
}

/* Sign of p . (a x b): which side of the great circle through a, b. */
static int gi__side_origin(const int64_t *a, const int64_t *b, const int64_t *p)
{
    int64_t nx = a[1] * b[2] - a[2] * b[1], ny = a[2] * b[0] - a[0] * b[2], nz = a[0] * b[1] - a[1] * b[0];
    gi__i128 d = (gi__i128)nx * p[0] + (gi__i128)ny * p[1] + (gi__i128)nz * p[2];
    return (d > 0) - (d < 0);
}

static int gi__same(const int64_t *a, const int64_t *b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

/* ------------------------------------------------------------ storage */

pf_result gi_dt_init(gi_dt *dt, gi_dt_domain domain, uint32_t cap, pf_error *err)
{
    memset(dt, 0, sizeof *dt);
    dt->domain = domain;
    dt->cap = cap;
    dt->tri_cap = 4 * cap + 64; /* 2n triangles, plus a whole fan before the cavity is freed */
    dt->ip = calloc(cap + 1, sizeof *dt->ip);
    dt->p = calloc(cap + 1, sizeof *dt->p);
    dt->present = calloc(cap + 1, 1);
    dt->in_dt = calloc(cap + 1, 1);
    dt->vt = calloc(cap + 1, sizeof(uint32_t));
    dt->tri = calloc(dt->tri_cap, sizeof(gi_dt_tri));
    dt->stack = calloc(dt->tri_cap, sizeof(uint32_t));
    dt->cavity = calloc(dt->tri_cap, sizeof(uint32_t));
    dt->newt = calloc(dt->tri_cap, sizeof(uint32_t));
    dt->poly = calloc(4 * ((size_t)cap + 8), sizeof(double));
    dt->order = calloc(cap + 1, sizeof(uint64_t));
    dt->by_v1 = calloc(cap + 1, sizeof(uint32_t));
    if (!dt->ip || !dt->p || !dt->present || !dt->in_dt || !dt->vt || !dt->tri || !dt->stack || !dt->cavity ||
        !dt->newt || !dt->poly || !dt->order || !dt->by_v1) {
        gi_dt_free(dt);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory (Delaunay triangulation of %u points)", cap);
    }
    dt->free_head = GI_DT_INF;
    return PF_OK;
}

void gi_dt_free(gi_dt *dt)
{
    free(dt->ip), free(dt->p), free(dt->present), free(dt->in_dt), free(dt->vt), free(dt->tri);
    free(dt->stack), free(dt->cavity), free(dt->newt), free(dt->poly), free(dt->order), free(dt->by_v1);
    memset(dt, 0, sizeof *dt);
}

static void gi__snap_int(gi_dt_domain domain, const double in[3], int64_t out[3])
{
    for (int k = 0; k < 3; k++) {
        double x = in[k];
        if (!(x >= -1.0)) x = -1.0; /* also NaN */
        if (x > 1.0) x = 1.0;
        out[k] = (domain == GI_DT_DISC && k == 2) ? 0 : llround(x * GI_DT_SCALE);
    }
}

void gi_dt_snap(gi_dt_domain domain, const double in[3], double out[3])
{
    int64_t q[3];
    gi__snap_int(domain, in, q);
    for (int k = 0; k < 3; k++) out[k] = (double)q[k] / GI_DT_SCALE;
}

void gi_dt_set_point(gi_dt *dt, uint32_t v, const double p[3])
{
    gi__snap_int(dt->domain, p, dt->ip[v]);
    for (int k = 0; k < 3; k++) dt->p[v][k] = (double)dt->ip[v][k] / GI_DT_SCALE;
    dt->present[v] = 1;
    dt->in_dt[v] = 0;
}

uint32_t gi_dt_count(const gi_dt *dt)
{
    uint32_t n = 0;
    for (uint32_t v = 0; v < dt->cap; v++) n += dt->present[v] != 0;
    return n;
}

static uint32_t gi__tri_new(gi_dt *dt)
{
    uint32_t t;
    if (dt->free_head != GI_DT_INF) {
        t = dt->free_head;
        dt->free_head = dt->tri[t].n[0];
    } else {
        if (dt->tri_count == dt->tri_cap) return GI_DT_INF;
        t = dt->tri_count++;
    }
    dt->tri[t].alive = GI__LIVE;
    return t;
}

static void gi__tri_release(gi_dt *dt, uint32_t t)
{
    dt->tri[t].alive = GI__DEAD;
    dt->tri[t].n[0] = dt->free_head;
    dt->free_head = t;
}

static int gi__is_ghost(const gi_dt_tri *t) { return t->v[0] == GI_DT_INF || t->v[1] == GI_DT_INF || t->v[2] == GI_DT_INF; }

/* Circumcentre (doubles; only used to choose locations and areas, never
 * for a combinatorial decision). */
static void gi__tri_centre(gi_dt *dt, uint32_t t)
{
    gi_dt_tri *T = &dt->tri[t];
    if (dt->domain == GI_DT_SPHERE) {
        const int64_t *a = dt->ip[T->v[0]], *b = dt->ip[T->v[1]], *c = dt->ip[T->v[2]];
        int64_t ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
        int64_t vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
        double n[3] = {(double)(uy * vz - uz * vy), (double)(uz * vx - ux * vz), (double)(ux * vy - uy * vx)};
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0.0)) l = 1.0;
        double r2 = 0.0;
        for (int k = 0; k < 3; k++) {
            T->c[k] = n[k] / l;
            double d = T->c[k] - dt->p[T->v[0]][k];
            r2 += d * d;
        }
        T->r2 = r2;
        return;
    }
    if (gi__is_ghost(T)) {
        T->c[0] = T->c[1] = T->c[2] = 0.0;
        T->r2 = INFINITY;
        return;
    }
    const double *a = dt->p[T->v[0]], *b = dt->p[T->v[1]], *c = dt->p[T->v[2]];
    double bx = b[0] - a[0], by = b[1] - a[1], cx = c[0] - a[0], cy = c[1] - a[1];
    double d = 2.0 * (bx * cy - by * cx);
    double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
    double ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;
    T->c[0] = a[0] + ux;
    T->c[1] = a[1] + uy;
    T->c[2] = 0.0;
    T->r2 = ux * ux + uy * uy;
}

/* Does point v conflict with triangle t (lie in its open circumcircle, or
 * see the face)? */
static int gi__conflict(const gi_dt *dt, uint32_t t, uint32_t v)
{
    const gi_dt_tri *T = &dt->tri[t];
    const int64_t *p = dt->ip[v];
    if (dt->domain == GI_DT_SPHERE) return gi__side3(dt->ip[T->v[0]], dt->ip[T->v[1]], dt->ip[T->v[2]], p) > 0;
    if (gi__is_ghost(T)) {
        int k = T->v[0] == GI_DT_INF ? 0 : T->v[1] == GI_DT_INF ? 1 : 2;
        const int64_t *a = dt->ip[T->v[(k + 1) % 3]], *b = dt->ip[T->v[(k + 2) % 3]];
        int o = gi__orient2d(a, b, p);
        if (o > 0) return 1;
        if (o < 0) return 0;
        /* collinear: inside the open segment ab? */
        int64_t d1 = (p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1]);
        int64_t d2 = (p[0] - b[0]) * (a[0] - b[0]) + (p[1] - b[1]) * (a[1] - b[1]);
        return d1 > 0 && d2 > 0;
    }
    return gi__incircle(dt->ip[T->v[0]], dt->ip[T->v[1]], dt->ip[T->v[2]], p) > 0;
}

/* Links the neighbour pointers of a few triangles by their shared edges
 * (the initial triangle / tetrahedron). */
static void gi__link_all(gi_dt *dt, const uint32_t *ts, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++)
        for (int e = 0; e < 3; e++) {
            gi_dt_tri *A = &dt->tri[ts[i]];
            uint32_t a = A->v[(e + 1) % 3], b = A->v[(e + 2) % 3];
            for (uint32_t j = 0; j < n; j++) {
                if (j == i) continue;
                const gi_dt_tri *B = &dt->tri[ts[j]];
                for (int f = 0; f < 3; f++)
                    if (B->v[(f + 1) % 3] == b && B->v[(f + 2) % 3] == a) A->n[e] = ts[j];
            }
        }
}

static void gi__set_tri(gi_dt *dt, uint32_t t, uint32_t a, uint32_t b, uint32_t c)
{
    dt->tri[t].v[0] = a, dt->tri[t].v[1] = b, dt->tri[t].v[2] = c;
    for (int k = 0; k < 3; k++)
        if (dt->tri[t].v[k] != GI_DT_INF) dt->vt[dt->tri[t].v[k]] = t;
}

/* Point location: a triangle in conflict with v, or GI_DT_INF. A visibility
 * walk from the last new triangle (disc: across edges v lies right of;
 * sphere: across great circles), with a step cap and a linear scan as the
 * fallback, so it always terminates with the right answer. */
static uint32_t gi__locate(const gi_dt *dt, uint32_t v)
{
    const int64_t *p = dt->ip[v];
    uint32_t t = dt->last;
    if (t >= dt->tri_count || dt->tri[t].alive != GI__LIVE) t = GI_DT_INF;
    uint32_t steps = 0, max_steps = 64 + dt->tri_count;
    while (t != GI_DT_INF && steps++ < max_steps) {
        const gi_dt_tri *T = &dt->tri[t];
        if (dt->domain == GI_DT_DISC && gi__is_ghost(T)) {
            if (gi__conflict(dt, t, v)) return t;
            int k = T->v[0] == GI_DT_INF ? 0 : T->v[1] == GI_DT_INF ? 1 : 2;
            t = T->n[k]; /* the solid triangle across the hull edge */
            continue;
        }
        if (dt->domain == GI_DT_SPHERE && gi__conflict(dt, t, v)) return t;
        uint32_t next = GI_DT_INF;
        for (uint32_t j = 0; j < 3; j++) {
            uint32_t i = (j + steps) % 3;
            const int64_t *a = dt->ip[T->v[(i + 1) % 3]], *b = dt->ip[T->v[(i + 2) % 3]];
            int s = dt->domain == GI_DT_DISC ? gi__orient2d(a, b, p) : gi__side_origin(a, b, p);
            if (s < 0) {
                next = T->n[i];
                break;
            }
        }
        if (next == GI_DT_INF) {
            if (gi__conflict(dt, t, v)) return t;
            break; /* disc: a duplicate; sphere: maybe inside, or a walk that lost its way */
        }
        t = next;
    }
    for (uint32_t u = 0; u < dt->tri_count; u++)
        if (dt->tri[u].alive == GI__LIVE && gi__conflict(dt, u, v)) return u;
    return GI_DT_INF;
}

/* Bowyer-Watson: replaces the triangles in conflict with v by the fan from
 * v to the cavity's boundary. 0: rejected (no conflict), -1 out of memory. */
static int gi__insert_core(gi_dt *dt, uint32_t v)
{
    uint32_t t0 = gi__locate(dt, v);
    if (t0 == GI_DT_INF) return 0;
    uint32_t ns = 0, nc = 0, nn = 0;
    dt->tri[t0].alive = GI__CAV;
    dt->stack[ns++] = t0;
    while (ns) {
        uint32_t c = dt->stack[--ns];
        dt->cavity[nc++] = c;
        for (int i = 0; i < 3; i++) {
            uint32_t nb = dt->tri[c].n[i];
            if (dt->tri[nb].alive == GI__CAV) continue;
            if (gi__conflict(dt, nb, v)) {
                dt->tri[nb].alive = GI__CAV;
                dt->stack[ns++] = nb;
            }
        }
    }
    /* the fan: one new triangle per boundary edge (c, i), v replacing v[i] */
    for (uint32_t k = 0; k < nc; k++) {
        uint32_t c = dt->cavity[k];
        for (int i = 0; i < 3; i++) {
            uint32_t nb = dt->tri[c].n[i];
            if (dt->tri[nb].alive == GI__CAV) continue;
            uint32_t t = gi__tri_new(dt);
            if (t == GI_DT_INF) return -1;
            gi__set_tri(dt, t, v, dt->tri[c].v[(i + 1) % 3], dt->tri[c].v[(i + 2) % 3]);
            dt->tri[t].n[0] = nb;
            for (int j = 0; j < 3; j++)
                if (dt->tri[nb].n[j] == c) dt->tri[nb].n[j] = t;
            dt->newt[nn++] = t;
        }
    }
    /* link the fan: (v, a, b) meets (v, b, x) across v-b and (v, y, a) across v-a */
    for (uint32_t i = 0; i < nn; i++) {
        const gi_dt_tri *A = &dt->tri[dt->newt[i]];
        dt->by_v1[A->v[1] == GI_DT_INF ? dt->cap : A->v[1]] = dt->newt[i];
    }
    for (uint32_t i = 0; i < nn; i++) {
        gi_dt_tri *A = &dt->tri[dt->newt[i]];
        uint32_t b = dt->by_v1[A->v[2] == GI_DT_INF ? dt->cap : A->v[2]];
        A->n[1] = b;
        dt->tri[b].n[2] = dt->newt[i];
    }
    for (uint32_t k = 0; k < nc; k++) gi__tri_release(dt, dt->cavity[k]);
    for (uint32_t i = 0; i < nn; i++) gi__tri_centre(dt, dt->newt[i]);
    /* sphere: vertices of the cavity not on its boundary left the hull */
    if (dt->domain == GI_DT_SPHERE)
        for (uint32_t k = 0; k < nc; k++)
            for (int j = 0; j < 3; j++) {
                uint32_t x = dt->tri[dt->cavity[k]].v[j];
                if (dt->in_dt[x] && dt->tri[dt->vt[x]].alive != GI__LIVE) dt->in_dt[x] = 0, dt->present[x] = 0;
            }
    dt->in_dt[v] = 1;
    dt->last = dt->newt[0];
    dt->solid += nn - nc;
    return 1;
}

/* The first triangle (disc, with its 3 ghosts) or tetrahedron (sphere) from
 * the first present points in general position; 0 if there are none. */
static int gi__seed(gi_dt *dt, uint32_t *used)
{
    uint32_t idx[4], n = 0, need = dt->domain == GI_DT_DISC ? 3 : 4;
    if (dt->domain == GI_DT_SPHERE) {
        /* the points furthest along the 4 directions of a regular
         * tetrahedron: on a well-covered sphere their hull contains the
         * origin, which the great-circle walk of gi__locate needs */
        static const int dirs[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
        uint32_t e[4];
        for (int k = 0; k < 4; k++) {
            int64_t best = INT64_MIN;
            e[k] = GI_DT_INF;
            for (uint32_t v = 0; v < dt->cap; v++) {
                if (!dt->present[v]) continue;
                int64_t d = dt->ip[v][0] * dirs[k][0] + dt->ip[v][1] * dirs[k][1] + dt->ip[v][2] * dirs[k][2];
                if (d > best) best = d, e[k] = v;
            }
        }
        if (e[0] != GI_DT_INF && e[0] != e[1] && e[0] != e[2] && e[0] != e[3] && e[1] != e[2] && e[1] != e[3] &&
            e[2] != e[3] && gi__side3(dt->ip[e[0]], dt->ip[e[1]], dt->ip[e[2]], dt->ip[e[3]]) != 0) {
            memcpy(idx, e, sizeof idx);
            n = 4;
        }
    }
    for (uint32_t v = 0; v < dt->cap && n < need; v++) {
        if (!dt->present[v]) continue;
        if (n == 0) idx[n++] = v;
        else if (n == 1) {
            if (!gi__same(dt->ip[v], dt->ip[idx[0]])) idx[n++] = v;
        } else if (n == 2) {
            const int64_t *a = dt->ip[idx[0]], *b = dt->ip[idx[1]], *c = dt->ip[v];
            int64_t cx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
            int64_t cy = (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]);
            int64_t cz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if (cx || cy || cz) idx[n++] = v;
        } else if (gi__side3(dt->ip[idx[0]], dt->ip[idx[1]], dt->ip[idx[2]], dt->ip[v]) != 0)
            idx[n++] = v;
    }
    if (n < need) return 0;
    uint32_t ts[4];
    for (uint32_t k = 0; k < 4; k++) ts[k] = gi__tri_new(dt);
    if (dt->domain == GI_DT_DISC) {
        uint32_t a = idx[0], b = idx[1], c = idx[2];
        if (gi__orient2d(dt->ip[a], dt->ip[b], dt->ip[c]) < 0) b = idx[2], c = idx[1];
        gi__set_tri(dt, ts[0], a, b, c);
        gi__set_tri(dt, ts[1], b, a, GI_DT_INF);
        gi__set_tri(dt, ts[2], c, b, GI_DT_INF);
        gi__set_tri(dt, ts[3], a, c, GI_DT_INF);
        dt->solid = 4;
    } else {
        uint32_t a = idx[0], b = idx[1], c = idx[2], d = idx[3];
        if (gi__side3(dt->ip[a], dt->ip[b], dt->ip[c], dt->ip[d]) > 0) b = idx[2], c = idx[1];
        /* abc faces away from d; the other faces likewise */
        gi__set_tri(dt, ts[0], a, b, c);
        gi__set_tri(dt, ts[1], a, d, b);
        gi__set_tri(dt, ts[2], b, d, c);
        gi__set_tri(dt, ts[3], c, d, a);
        dt->solid = 4;
    }
    gi__link_all(dt, ts, 4);
    for (uint32_t k = 0; k < 4; k++) gi__tri_centre(dt, ts[k]);
    for (uint32_t k = 0; k < need; k++) dt->in_dt[idx[k]] = 1, used[k] = idx[k];
    dt->last = ts[0];
    return (int)need;
}

static int gi__cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

pf_result gi_dt_rebuild(gi_dt *dt, pf_error *err)
{
    dt->tri_count = 0;
    dt->free_head = GI_DT_INF;
    dt->solid = 0;
    dt->last = 0;
    memset(dt->in_dt, 0, dt->cap);
    uint32_t used[4] = {GI_DT_INF, GI_DT_INF, GI_DT_INF, GI_DT_INF};
    int ns = gi__seed(dt, used);
    if (ns == 0) {
        /* degenerate: keep the distinct points (brute-force mode) */
        for (uint32_t v = 0; v < dt->cap; v++) {
            if (!dt->present[v]) continue;
            int dup = 0;
            for (uint32_t u = 0; u < v && !dup; u++) dup = dt->in_dt[u] && gi__same(dt->ip[u], dt->ip[v]);
            if (dup) dt->present[v] = 0;
            else dt->in_dt[v] = 1;
        }
        return PF_OK;
    }
    /* insertion in Morton order of the grid cells (ties by index), so the
     * walk of each insertion starts next to its point */
    uint32_t m = 0;
    for (uint32_t v = 0; v < dt->cap; v++) {
        if (!dt->present[v] || v == used[0] || v == used[1] || v == used[2] || v == used[3]) continue;
        uint64_t key = 0;
        for (int b = 0; b < 9; b++)
            for (int k = 0; k < 3; k++) {
                uint64_t c = (uint64_t)(dt->ip[v][k] + 16777216) >> 16; /* 9 bits */
                key |= ((c >> b) & 1u) << (3 * b + k);
            }
        dt->order[m++] = key << 32 | v;
    }
    qsort(dt->order, m, sizeof(uint64_t), gi__cmp_u64);
    for (uint32_t k = 0; k < m; k++) {
        uint32_t v = (uint32_t)dt->order[k];
        int r = gi__insert_core(dt, v);
        if (r < 0) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "Delaunay triangulation: out of triangles");
        if (r == 0) dt->present[v] = 0;
    }
    return PF_OK;
}

int gi_dt_insert(gi_dt *dt, uint32_t v, const double p[3], pf_error *err)
{
    gi_dt_set_point(dt, v, p);
    if (dt->solid == 0) {
        if (gi_dt_rebuild(dt, err) != PF_OK) return -1;
        return dt->present[v];
    }
    int r = gi__insert_core(dt, v);
    if (r < 0) {
        pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "Delaunay triangulation: out of triangles");
        return -1;
    }
    if (r == 0) dt->present[v] = 0;
    return r;
}

/* Would triangle (a, b, c) (one may be GI_DT_INF) be a Delaunay triangle
 * of the hole left by deleting v, judged against the hole's vertices
 * P[0..m)? Disc: CCW and no vertex in its circumcircle (ghost: in its
 * half-plane); sphere: v sees it (outward orientation) and no vertex does. */
static int gi__ear_ok(const gi_dt *dt, uint32_t a, uint32_t b, uint32_t c, uint32_t v, const uint32_t *P, uint32_t m)
{
    gi_dt_tri T = {{a, b, c}, {0, 0, 0}, {0, 0, 0}, 0.0, GI__LIVE};
    int ghost = a == GI_DT_INF || b == GI_DT_INF || c == GI_DT_INF;
    if (dt->domain == GI_DT_SPHERE) {
        if (ghost || gi__side3(dt->ip[a], dt->ip[b], dt->ip[c], dt->ip[v]) <= 0) return 0;
    } else if (!ghost && gi__orient2d(dt->ip[a], dt->ip[b], dt->ip[c]) <= 0)
        return 0;
    for (uint32_t k = 0; k < m; k++) {
        uint32_t w = P[k];
        if (w == a || w == b || w == c || w == GI_DT_INF) continue;
        const int64_t *p = dt->ip[w];
        if (dt->domain == GI_DT_SPHERE) {
            if (gi__side3(dt->ip[a], dt->ip[b], dt->ip[c], p) > 0) return 0;
        } else if (ghost) {
            int g = a == GI_DT_INF ? 0 : b == GI_DT_INF ? 1 : 2;
            const int64_t *x = dt->ip[T.v[(g + 1) % 3]], *y = dt->ip[T.v[(g + 2) % 3]];
            int o = gi__orient2d(x, y, p);
            if (o > 0) return 0;
            if (o == 0) {
                int64_t d1 = (p[0] - x[0]) * (y[0] - x[0]) + (p[1] - x[1]) * (y[1] - x[1]);
                int64_t d2 = (p[0] - y[0]) * (x[0] - y[0]) + (p[1] - y[1]) * (x[1] - y[1]);
                if (d1 > 0 && d2 > 0) return 0;
            }
        } else if (gi__incircle(dt->ip[a], dt->ip[b], dt->ip[c], p) > 0)
            return 0;
    }
    return 1;
}

static void gi__link_back(gi_dt *dt, uint32_t o, uint32_t from, uint32_t to, uint32_t t)
{
    /* o holds the edge to -> from (the reverse of t's from -> to) */
    for (int x = 0; x < 3; x++)
        if (dt->tri[o].v[(x + 1) % 3] == to && dt->tri[o].v[(x + 2) % 3] == from) dt->tri[o].n[x] = t;
}

/* Deletes vertex v locally: its star's polygon is re-triangulated by
 * clipping Delaunay ears (Devillers' vertex deletion, with the ear test of
 * gi__ear_ok and the first valid ear in polygon order, so it is
 * deterministic). 0 if the local update does not apply (tiny sets, or no
 * valid ear: a degenerate configuration); the caller then rebuilds. */
static int gi__remove_local(gi_dt *dt, uint32_t v)
{
    if (dt->solid == 0 || !dt->in_dt[v]) return 0;
    uint32_t *P = dt->newt, *own = dt->cavity, *star = dt->stack, m = 0;
    uint32_t t0 = dt->vt[v], t = t0;
    do {
        const gi_dt_tri *T = &dt->tri[t];
        int i = T->v[0] == v ? 0 : T->v[1] == v ? 1 : 2;
        if (m + 8 > dt->tri_cap / 3) return 0;
        P[m] = T->v[(i + 1) % 3];
        own[m] = T->n[i]; /* across the polygon edge P[m] -> P[m + 1] */
        star[m++] = t;
        t = T->n[(i + 1) % 3];
    } while (t != t0);
    uint32_t present = 0;
    for (uint32_t u = 0; u < dt->cap && present < 8; u++) present += dt->in_dt[u];
    if (present < 6 || m < 3) return 0;
    /* new triangles go to the tail of the scratch: committed only if every ear is found */
    uint32_t *made = dt->newt + dt->tri_cap / 3, nm = 0, *Pall = dt->newt + 2 * (dt->tri_cap / 3), mall = m;
    memcpy(Pall, P, sizeof(uint32_t) * m);
    while (m > 3) {
        uint32_t j;
        for (j = 0; j < m; j++)
            if (gi__ear_ok(dt, P[j], P[(j + 1) % m], P[(j + 2) % m], v, Pall, mall)) break;
        if (j == m) {
            for (uint32_t k = 0; k < nm; k++) gi__tri_release(dt, made[k]);
            return 0;
        }
        uint32_t j1 = (j + 1) % m, j2 = (j + 2) % m;
        uint32_t nt = gi__tri_new(dt);
        if (nt == GI_DT_INF) {
            for (uint32_t k = 0; k < nm; k++) gi__tri_release(dt, made[k]);
            return 0;
        }
        gi_dt_tri *T = &dt->tri[nt];
        T->v[0] = P[j], T->v[1] = P[j1], T->v[2] = P[j2];
        T->n[2] = own[j], T->n[0] = own[j1], T->n[1] = GI_DT_INF;
        made[nm++] = nt;
        /* the polygon loses P[j1]; edge P[j] -> P[j2] is now owned by nt */
        own[j] = nt;
        for (uint32_t k = j1; k + 1 < m; k++) P[k] = P[k + 1], own[k] = own[k + 1];
        m--;
    }
    if (!gi__ear_ok(dt, P[0], P[1], P[2], v, Pall, mall)) {
        for (uint32_t k = 0; k < nm; k++) gi__tri_release(dt, made[k]);
        return 0;
    }
    uint32_t nt = gi__tri_new(dt);
    if (nt == GI_DT_INF) {
        for (uint32_t k = 0; k < nm; k++) gi__tri_release(dt, made[k]);
        return 0;
    }
    dt->tri[nt].v[0] = P[0], dt->tri[nt].v[1] = P[1], dt->tri[nt].v[2] = P[2];
    dt->tri[nt].n[2] = own[0], dt->tri[nt].n[0] = own[1], dt->tri[nt].n[1] = own[2];
    made[nm++] = nt;
    /* a hole filled with ghosts only (the disc around a hull vertex of
     * degree 2, or a collinear remainder): leave that to the rebuild, which
     * also recognises degenerate sets */
    uint32_t solid_made = 0;
    for (uint32_t k = 0; k < nm; k++) solid_made += !gi__is_ghost(&dt->tri[made[k]]);
    if (!solid_made) {
        for (uint32_t k = 0; k < nm; k++) gi__tri_release(dt, made[k]);
        return 0;
    }
    /* commit: back-links from every neighbour, then vertex map, centres */
    for (uint32_t k = 0; k < nm; k++) {
        uint32_t a = made[k];
        for (int e = 0; e < 3; e++) {
            uint32_t o = dt->tri[a].n[e];
            if (o == GI_DT_INF) continue;
            gi__link_back(dt, o, dt->tri[a].v[(e + 1) % 3], dt->tri[a].v[(e + 2) % 3], a);
        }
    }
    for (uint32_t k = 0; k < mall; k++) gi__tri_release(dt, star[k]);
    for (uint32_t k = 0; k < nm; k++) {
        gi_dt_tri *T = &dt->tri[made[k]];
        for (int e = 0; e < 3; e++)
            if (T->v[e] != GI_DT_INF) dt->vt[T->v[e]] = made[k];
        gi__tri_centre(dt, made[k]);
    }
    dt->last = made[0];
    dt->solid = dt->solid + nm - mall;
    dt->present[v] = 0;
    dt->in_dt[v] = 0;
    return 1;
}

pf_result gi_dt_remove(gi_dt *dt, uint32_t v, pf_error *err)
{
    if (gi__remove_local(dt, v)) return PF_OK;
    dt->present[v] = 0;
    dt->in_dt[v] = 0;
    return gi_dt_rebuild(dt, err);
}

/* ------------------------------------------------------------ neighbours */

uint32_t gi_dt_neighbours(const gi_dt *dt, uint32_t v, uint32_t *nb, uint32_t max)
{
    uint32_t n = 0;
    if (!dt->in_dt[v]) return 0;
    if (dt->solid == 0) {
        for (uint32_t u = 0; u < dt->cap && n < max; u++)
            if (u != v && dt->in_dt[u]) nb[n++] = u;
        return n;
    }
    uint32_t t0 = dt->vt[v], t = t0, guard = 0;
    do {
        const gi_dt_tri *T = &dt->tri[t];
        int i = T->v[0] == v ? 0 : T->v[1] == v ? 1 : 2;
        uint32_t a = T->v[(i + 1) % 3];
        if (a != GI_DT_INF && n < max) nb[n++] = a;
        t = T->n[(i + 1) % 3]; /* across (b, v): the next triangle CCW around v */
    } while (t != t0 && ++guard < dt->tri_count);
    return n;
}

static double gi__d2(const double *a, const double *b)
{
    double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return x * x + y * y + z * z;
}

uint32_t gi_dt_deletion_candidate(const gi_dt *dt)
{
    uint32_t *nb = dt->stack; /* scratch: tri_cap >= cap */
    double best = INFINITY;
    uint32_t ea = GI_DT_INF, eb = GI_DT_INF;
    /* 1. the shortest Delaunay edge */
    for (uint32_t v = 0; v < dt->cap; v++) {
        if (!dt->in_dt[v]) continue;
        uint32_t n = gi_dt_neighbours(dt, v, nb, dt->tri_cap);
        for (uint32_t k = 0; k < n; k++) {
            if (nb[k] <= v) continue;
            double d = gi__d2(dt->p[v], dt->p[nb[k]]);
            if (d < best) best = d, ea = v, eb = nb[k];
        }
    }
    if (ea == GI_DT_INF) return GI_DT_INF;
    /* 2. the distance of each end to its second-closest neighbour */
    double second[2];
    uint32_t ends[2] = {ea, eb};
    for (int e = 0; e < 2; e++) {
        uint32_t n = gi_dt_neighbours(dt, ends[e], nb, dt->tri_cap);
        double m1 = INFINITY, m2 = INFINITY;
        for (uint32_t k = 0; k < n; k++) {
            double d = gi__d2(dt->p[ends[e]], dt->p[nb[k]]);
            if (d < m1) m2 = m1, m1 = d;
            else if (d < m2) m2 = d;
        }
        second[e] = m2;
    }
    /* 3. delete the one whose second-closest neighbour is nearer */
    return second[0] < second[1] ? ea : eb;
}

/* ------------------------------------------------------------ probes */

/* Probe point k of n: disc: a grid over [-1,1]^2 (points outside skipped by
 * the caller) then the boundary circle; sphere: the Fibonacci lattice. */
static int gi__probe(gi_dt_domain domain, uint32_t k, uint32_t n, double q[3])
{
    if (domain == GI_DT_SPHERE) {
        double z = 1.0 - (2.0 * k + 1.0) / n, r = sqrt(fmax(0.0, 1.0 - z * z));
        double phi = k * 2.39996322972865332;
        q[0] = r * cos(phi), q[1] = r * sin(phi), q[2] = z;
        return 1;
    }
    uint32_t nb = n / 8, ng = n - nb, g = (uint32_t)sqrt((double)ng);
    if (k < g * g) {
        q[0] = -1.0 + (k % g + 0.5) * 2.0 / g, q[1] = -1.0 + (k / g + 0.5) * 2.0 / g, q[2] = 0.0;
        return q[0] * q[0] + q[1] * q[1] <= 1.0;
    }
    if (k < ng) return 0;
    double a = 2.0 * 3.14159265358979323846 * (k - ng) / nb;
    q[0] = cos(a), q[1] = sin(a), q[2] = 0.0;
    return 1;
}

static double gi__nearest(const gi_dt *dt, const double q[3], uint32_t *which)
{
    double best = INFINITY;
    *which = GI_DT_INF;
    for (uint32_t v = 0; v < dt->cap; v++)
        if (dt->in_dt[v]) {
            double d = gi__d2(q, dt->p[v]);
            if (d < best) best = d, *which = v;
        }
    return best;
}

double gi_dt_dispersion_brute(const gi_dt *dt, uint32_t n)
{
    double best = 0.0, q[3];
    uint32_t w;
    for (uint32_t k = 0; k < n; k++)
        if (gi__probe(dt->domain, k, n, q)) best = fmax(best, gi__nearest(dt, q, &w));
    return sqrt(best);
}

/* ------------------------------------------------------------ largest empty circle */

double gi_dt_largest_empty(const gi_dt *dt, double centre[3], int *kind)
{
    int kd = 0;
    double best = -1.0, q[3];
    centre[0] = centre[1] = centre[2] = 0.0;
    if (dt->solid == 0) {
        /* degenerate: brute force over probes */
        uint32_t w, n = dt->domain == GI_DT_SPHERE ? 4096 : 8192;
        if (dt->domain == GI_DT_SPHERE) centre[2] = 1.0;
        for (uint32_t k = 0; k < n; k++)
            if (gi__probe(dt->domain, k, n, q)) {
                double d = gi__nearest(dt, q, &w);
                if (w == GI_DT_INF) return dt->domain == GI_DT_SPHERE ? 2.0 : 1.0; /* no points */
                if (d > best) best = d, memcpy(centre, q, sizeof q);
            }
        if (kind) *kind = 0;
        return sqrt(best);
    }
    if (dt->domain == GI_DT_SPHERE) {
        /* only Voronoi vertices (Sec. 4.6): the face with the largest circumcap */
        for (uint32_t t = 0; t < dt->tri_count; t++)
            if (dt->tri[t].alive == GI__LIVE && dt->tri[t].r2 > best) best = dt->tri[t].r2, memcpy(centre, dt->tri[t].c, sizeof q);
        if (kind) *kind = 1;
        return sqrt(best);
    }
    for (uint32_t t = 0; t < dt->tri_count; t++) {
        const gi_dt_tri *T = &dt->tri[t];
        if (T->alive != GI__LIVE) continue;
        /* case 1: a Voronoi vertex inside the disc */
        if (!gi__is_ghost(T) && T->c[0] * T->c[0] + T->c[1] * T->c[1] <= 1.0 && T->r2 > best)
            best = T->r2, centre[0] = T->c[0], centre[1] = T->c[1], kd = 1;
        /* case 2: the Voronoi edge of Delaunay edge a->b (T on its left)
         * meets the boundary circle */
        for (int i = 0; i < 3; i++) {
            uint32_t a = T->v[(i + 1) % 3], b = T->v[(i + 2) % 3];
            if (a == GI_DT_INF || b == GI_DT_INF || a > b) continue;
            const gi_dt_tri *R = &dt->tri[T->n[i]];
            const double *pa = dt->p[a], *pb = dt->p[b];
            double m[2] = {0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])};
            double u[2] = {-(pb[1] - pa[1]), pb[0] - pa[0]};
            double ul = sqrt(u[0] * u[0] + u[1] * u[1]);
            u[0] /= ul, u[1] /= ul;
            double lo = -INFINITY, hi = INFINITY;
            double tl = gi__is_ghost(T) ? INFINITY : (T->c[0] - m[0]) * u[0] + (T->c[1] - m[1]) * u[1];
            double tr = gi__is_ghost(R) ? -INFINITY : (R->c[0] - m[0]) * u[0] + (R->c[1] - m[1]) * u[1];
            lo = fmin(tl, tr), hi = fmax(tl, tr);
            double mu = m[0] * u[0] + m[1] * u[1], disc = mu * mu - (m[0] * m[0] + m[1] * m[1] - 1.0);
            if (!(disc >= 0.0)) continue;
            double sq = sqrt(disc), roots[2] = {-mu - sq, -mu + sq};
            for (int r = 0; r < 2; r++) {
                double s = roots[r];
                if (!(s >= lo && s <= hi)) continue;
                double x[3] = {m[0] + s * u[0], m[1] + s * u[1], 0.0};
                double d = gi__d2(x, pa);
                if (d > best) best = d, centre[0] = x[0], centre[1] = x[1], kd = 2;
            }
        }
    }
    /* case 3: the boundary point opposite a site through the origin, when the
     * site's Voronoi cell reaches it */
    uint32_t *nb = dt->stack;
    for (uint32_t v = 0; v < dt->cap; v++) {
        if (!dt->in_dt[v]) continue;
        const double *p = dt->p[v];
        double l = sqrt(p[0] * p[0] + p[1] * p[1]);
        if (!(l > 0.0)) continue;
        double x[3] = {-p[0] / l, -p[1] / l, 0.0};
        double d = gi__d2(x, p);
        if (!(d > best)) continue;
        uint32_t n = gi_dt_neighbours(dt, v, nb, dt->tri_cap), k;
        for (k = 0; k < n; k++)
            if (gi__d2(x, dt->p[nb[k]]) < d) break;
        if (k == n) best = d, centre[0] = x[0], centre[1] = x[1], kd = 3;
    }
    if (kind) *kind = kd;
    return sqrt(best);
}

/* ------------------------------------------------------------ Voronoi areas */

/* Signed area of triangle (origin, a, b) intersected with the unit disc. */
static double gi__tri_disc_area(const double *a, const double *b)
{
    double d[2] = {b[0] - a[0], b[1] - a[1]};
    double A = d[0] * d[0] + d[1] * d[1], B = a[0] * d[0] + a[1] * d[1], C = a[0] * a[0] + a[1] * a[1] - 1.0;
    double ts[4] = {0.0, 0.0, 1.0, 1.0};
    if (A > 0.0) {
        double disc = B * B - A * C;
        if (disc > 0.0) {
            double sq = sqrt(disc);
            ts[1] = fmin(1.0, fmax(0.0, (-B - sq) / A));
            ts[2] = fmin(1.0, fmax(0.0, (-B + sq) / A));
        } else
            ts[1] = ts[2] = 1.0; /* never inside: one sector */
    } else
        return 0.0;
    double sum = 0.0;
    for (int k = 0; k < 3; k++) {
        double p[2] = {a[0] + ts[k] * d[0], a[1] + ts[k] * d[1]}, q[2] = {a[0] + ts[k + 1] * d[0], a[1] + ts[k + 1] * d[1]};
        double cr = p[0] * q[1] - p[1] * q[0], dt = p[0] * q[0] + p[1] * q[1];
        if (k == 1) sum += 0.5 * cr; /* the chord inside the disc */
        else if (ts[k + 1] > ts[k]) sum += 0.5 * atan2(cr, dt); /* outside: a sector */
    }
    return sum;
}

/* Clips polygon in[0..n) by the half-plane (x - m) . g <= 0 into out. */
static uint32_t gi__clip(const double *in, uint32_t n, const double m[2], const double g[2], double *out)
{
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        const double *p = in + 2 * i, *q = in + 2 * ((i + 1) % n);
        double sp = (p[0] - m[0]) * g[0] + (p[1] - m[1]) * g[1], sq = (q[0] - m[0]) * g[0] + (q[1] - m[1]) * g[1];
        if (sp <= 0.0) out[2 * k] = p[0], out[2 * k + 1] = p[1], k++;
        if ((sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0)) {
            double s = sp / (sp - sq);
            out[2 * k] = p[0] + s * (q[0] - p[0]), out[2 * k + 1] = p[1] + s * (q[1] - p[1]), k++;
        }
    }
    return k;
}

void gi_dt_voronoi_areas(gi_dt *dt, double *area)
{
    memset(area, 0, sizeof(double) * dt->cap);
    if (dt->solid == 0) {
        /* degenerate: nearest-site counts over probes */
        uint32_t n = dt->domain == GI_DT_SPHERE ? 16384 : 32768, total = 0, w;
        double q[3];
        for (uint32_t k = 0; k < n; k++)
            if (gi__probe(dt->domain, k, n, q) && (dt->domain == GI_DT_SPHERE || k < n - n / 8)) {
                total++;
                gi__nearest(dt, q, &w);
                if (w != GI_DT_INF) area[w] += 1.0;
            }
        double full = dt->domain == GI_DT_SPHERE ? 4.0 * 3.14159265358979323846 : 3.14159265358979323846;
        for (uint32_t v = 0; v < dt->cap; v++) area[v] *= full / total;
        return;
    }
    for (uint32_t v = 0; v < dt->cap; v++) {
        if (!dt->in_dt[v]) continue;
        const double *p = dt->p[v];
        if (dt->domain == GI_DT_SPHERE) {
            /* the fan apex on the sphere (the snapped point is off it by < 1e-7;
             * the circumcentres are unit vectors) */
            double pl = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), pu[3] = {p[0] / pl, p[1] / pl, p[2] / pl};
            p = pu;
            /* the spherical polygon of the circumcentres around v, as a fan of
             * solid angles (Van Oosterom-Strackee) */
            uint32_t t0 = dt->vt[v], t = t0, guard = 0;
            double sum = 0.0;
            do {
                const gi_dt_tri *T = &dt->tri[t];
                int i = T->v[0] == v ? 0 : T->v[1] == v ? 1 : 2;
                uint32_t tn = T->n[(i + 1) % 3];
                const double *a = T->c, *b = dt->tri[tn].c;
                double cr[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
                double num = p[0] * cr[0] + p[1] * cr[1] + p[2] * cr[2];
                double den = 1.0 + (p[0] * a[0] + p[1] * a[1] + p[2] * a[2]) + (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) +
                             (b[0] * p[0] + b[1] * p[1] + b[2] * p[2]);
                sum += 2.0 * atan2(num, den);
                t = tn;
            } while (t != t0 && ++guard < dt->tri_count);
            area[v] = sum;
            continue;
        }
        /* disc: a square around the disc cut by the bisector with every
         * Delaunay neighbour, then intersected with the unit disc */
        double *A = dt->poly, *B = dt->poly + 2 * ((size_t)dt->cap + 8);
        uint32_t n = 4;
        const double sq[8] = {-1.5, -1.5, 1.5, -1.5, 1.5, 1.5, -1.5, 1.5};
        memcpy(A, sq, sizeof sq);
        uint32_t *nb = dt->stack, nn = gi_dt_neighbours(dt, v, nb, dt->tri_cap);
        for (uint32_t k = 0; k < nn && n > 0; k++) {
            const double *w = dt->p[nb[k]];
            double m[2] = {0.5 * (p[0] + w[0]), 0.5 * (p[1] + w[1])}, g[2] = {w[0] - p[0], w[1] - p[1]};
            n = gi__clip(A, n, m, g, B);
            double *tmp = A;
            A = B, B = tmp;
        }
        double s = 0.0;
        for (uint32_t i = 0; i < n; i++) s += gi__tri_disc_area(A + 2 * i, A + 2 * ((i + 1) % n));
        area[v] = s;
    }
}
