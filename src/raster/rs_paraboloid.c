/* rs_paraboloid: exact paraboloid shadow maps (see rs_paraboloid.h for the
 * mapping, the storage format and the lookup).
 *
 * Who calls what: rs_para_render -> one job item per map -> rs__render_map:
 *   1. rs__cluster_bound   per cluster: behind the tangent plane? else the
 *                          image of its bounding sphere's cone (a disc, see
 *                          "Cluster bound" below) as a texel rectangle and
 *                          its nearest possible distance;
 *   2. rs__sort_clusters   front to back (stable radix sort on a 16-bit
 *                          distance key), so near occluders come first;
 *   3. rs__draw_cluster    unless rs__occluded (every 8x8 tile its disc
 *                          touches is nearer than the cluster): the front end
 *                          rs__front (a kernel: 8 or 16 triangles at
 *                          a time: local coordinates, hemisphere
 *                          cull, conservative (u, v) bound, texel rectangle),
 *                          then per survivor the same occlusion test with the
 *                          triangle's nearest possible distance,
 *                          rs__setup_triangle (edge normals, filter bounds,
 *                          orientation, tighter bound) and rs__scan (a
 *                          kernel: 8 or 16 texels of a row at a time): the
 *                          exact per-texel test, nearest distance;
 *   4. quantise            float distances -> 16-bit codes.
 *
 * The exact test. All rays start at the VPL o, so a triangle with local
 * vertices A, B, C (relative to o) is hit by the ray along D iff D lies in
 * the cone the triangle subtends: with the edge normals
 *     e0 = A x B,  e1 = B x C,  e2 = C x A,   det = A . (B x C),
 * the ray meets the triangle in front of o iff sign(det) = sign(D . e_k) for
 * k = 0..2. This is the watertight test of Woop, Benthin and Wald (JCGT 2013)
 * for a common ray origin: their shear to ray space is not needed because
 * the edge functions are already the triple products D . (A x B). With
 * s = sign(det) and the oriented normals e'_k = s e_k the test is
 * D . e'_k > 0, and the distance is
 *     t = det' |D| / (D . N'),   N' = s (B - A) x (C - A),  det' = |det|,
 * where |D| = 1 + u^2 + v^2 = W for the texel direction D = (2u, 2v, 1-u^2-v^2)
 * (tabulated once per resolution). N is precomputed per triangle in world
 * space (in double, stored as float) and rotated into the VPL frame, so the
 * distance keeps float precision even for small far triangles.
 *
 * Watertightness. Two triangles sharing the edge PQ and lying on either side
 * of it as seen from o get exactly opposite oriented normals for that edge:
 * the shared vertices have the same local coordinates (same float
 * expression), the cross product of the two vectors swapped is the exact
 * negation (x y - y x rounds symmetrically), and s flips exactly when the
 * orientation as seen flips. So D . e' evaluates to exactly negated values in
 * the two triangles, and any decision rule that is odd in e' gives the texel
 * to exactly one of them. The rule: the sign of D . e'; where it is zero in
 * double (the centre lies on the edge's plane) the sign of the first nonzero
 * component of e' (x, then y, then z) decides, i.e. the ray is perturbed by
 * (eps, eps^2, eps^3) (Simulation of Simplicity, Edelsbrunner & Muecke 1990),
 * the same perturbation for every edge, so vertices are owned once too.
 *
 * Float filter (all paths evaluate the same float expressions, then fall
 * back to double where float cannot decide). Local coordinates are computed
 * in float from the float world positions: each component within 4u |A| of
 * the real value (u = 2^-24; the basis t, b, n is taken as exact), so
 * |dA| <= 7u |A|; the float cross product e_f is within (7 + 7 + 4) u |A||B|
 * of the real A x B per component, and g = (D.x e.x + D.y e.y) + D.z e.z in
 * float within
 *     |D|_1 (18 + 3.01) u |A||B| <= 60 u |A||B|      (|D|_1 <= 2 sqrt 2)
 * of the real D . (A x B). So |g| > 2^-17 |A||B| (128 u, twice the error)
 * fixes the sign, and the sign is the one the double evaluation finds too
 * (its error is ~1e-16 |A||B|). Texel centres closer to an edge's plane than
 * about 8e-6 / sin(angle AB) rad take the double path (the edge normal from
 * double local coordinates, rs_para_stats.texels_exact_fallback): rare, and
 * antisymmetric like the float path. det gets the same treatment (its float
 * error is below 16 u |A||N|; the filter is 2^-17 |A| |N|_1). The decisions
 * are those of the double evaluation in every path, so the coverage is that
 * of the float scene to ~1e-16 rad, far inside the bound's margin.
 *
 * Triangle bound. The image of the triangle (clipped to z >= 0) is bounded by
 * circular arcs, each the image of a great-circle arc of less than 180
 * degrees: an edge's plane through o, e . d = 0, maps to
 *     2u e.x + 2v e.y + (1 - u^2 - v^2) e.z = 0,
 * the circle of centre (e.x, e.y) / e.z and radius r = |e| / |e.z| >= 1 (a
 * line when e.z = 0), and the clipped part, z = 0, maps to the unit circle.
 * Every such circle meets the unit circle at two antipodal points (where its
 * great circle crosses the horizon), so its part inside the disc is at most a
 * semicircle and every edge's image is a minor arc. A minor arc with chord c
 * deviates from its chord by at most its sagitta
 *     h = (c^2 / 4) / (r + sqrt(r^2 - c^2 / 4))  <=  c^2 / 4   (r >= 1),
 * so the image lies in the bounding box of the projected (clipped) vertices
 * grown by the largest h (the region lies in the convex hull of its boundary
 * arcs). The front end uses c^2 / 4 (no edge normals needed yet); the setup
 * tightens it with each edge's exact h when that matters (more than 1/8
 * texel). A margin of RS__UV_EPS (4e-6, against ~5e-7 of float error in the
 * projections) makes the bound conservative. Triangles crossing the tangent
 * plane are clipped in double (their clip points can lie close to o, where
 * float would lose the direction).
 *
 * Cluster bound. A cluster's bounding sphere (centre c, radius r, distance
 * L = |c - o| > r) subtends the cap of half-angle alpha = asin(r / L) around
 * the direction at polar angle phi. Stereographic projection maps circles to
 * circles, and the cap's boundary is symmetric about the plane through n and
 * c, so its image is the disc whose diameter joins the images of the polar
 * angles phi - alpha and phi + alpha on that plane: rho(theta) = tan(theta/2)
 * = sin(theta) / (1 + cos(theta)), evaluated with the angle-sum formulas (no
 * trigonometric calls). The cluster is skipped when its sphere lies wholly
 * behind the tangent plane, or when every tile its disc touches already holds
 * depths all nearer than L - r (hierarchical occlusion culling; clusters are
 * drawn front to back). A triangle is skipped likewise when every point of
 * it, at least min |vertex| - longest edge from o, lies beyond the tiles its
 * rectangle touches. These tests only drop triangles that cannot change the
 * minimum (up to the float error of hits within ~0.1 degree of grazing, see
 * rs__draw_cluster), so the map does not depend on them, nor on the draw
 * order: the minimum of floats is order-free. They are the same in every
 * path, so the bytes do not depend on the path either way.
 *
 * SIMD. rs__front and rs__scan are written once over the SIMD vocabulary
 * (rs_para_kernels.c, compiled per instruction set: 8 plain-C lanes for the
 * scalar path, 8 on AVX2, 16 on AVX-512). Every compile makes, lane by
 * lane, the same IEEE operations in the same order (no FMA: softgi builds
 * with -ffp-contract=off and the vocabulary has only plain mul/add/div/
 * sqrt/min/max/round), and undecided lanes go through the same scalar
 * rs__para_resolve, so every path gives the same bits and the same
 * statistics (tested). */
#include "rs_paraboloid.h"

#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rs_para_kernels.h"
#include "rs_para_lod.h"
#include "simd.h" /* SIMD_X86 */

/* ------------------------------------------------------------------ mapping */

rs_para_frame rs_para_frame_make(pf_vec3 position, pf_vec3 normal)
{
    rs_para_frame f;
    f.o = position;
    f.n = pf_v3_normalize(normal);
    pf_v3_basis(f.n, &f.t, &f.b);
    return f;
}

/* A world-space vector in the map's frame (no translation). */
static pf_vec3 rs__rotate(const rs_para_frame *f, pf_vec3 v)
{
    return pf_v3((v.x * f->t.x + v.y * f->t.y) + v.z * f->t.z, (v.x * f->b.x + v.y * f->b.y) + v.z * f->b.z,
                 (v.x * f->n.x + v.y * f->n.y) + v.z * f->n.z);
}

pf_vec3 rs_para_to_local(const rs_para_frame *f, pf_vec3 p)
{
    return rs__rotate(f, pf_v3(p.x - f->o.x, p.y - f->o.y, p.z - f->o.z));
}

static inline float rs__texel_centre(uint32_t res, uint32_t i)
{
    return ((float)(2 * i + 1) - (float)res) / (float)res;
}

pf_vec2 rs_para_texel_uv(uint32_t resolution, uint32_t i, uint32_t j)
{
    pf_vec2 r = {rs__texel_centre(resolution, i), rs__texel_centre(resolution, j)};
    return r;
}

int rs_para_texel_inside(uint32_t resolution, uint32_t i, uint32_t j)
{
    int64_t a = 2 * (int64_t)i + 1 - resolution, b = 2 * (int64_t)j + 1 - resolution;
    return a * a + b * b <= (int64_t)resolution * resolution;
}


uint32_t rs_para_texel_of(uint32_t resolution, pf_vec3 d)
{
    float u, v;
    if (d.z > 0.0f) {
        float den = pf_v3_length(d) + d.z;
        u = d.x / den;
        v = d.y / den;
    } else {
        /* at or below the horizon: the rim point of the same azimuth (the
         * straight-down direction -n has none; it takes azimuth 0) */
        float rr = sqrtf(d.x * d.x + d.y * d.y);
        u = rr > 0.0f ? d.x / rr : 1.0f;
        v = rr > 0.0f ? d.y / rr : 0.0f;
    }
    return rs_para_texel_of_uv(resolution, u, v);
}

/* floor(a) clamped to [0, R - 1], a NaN to 0, without libm's floorf (a
 * call in the plain x86-64 build, which has no rounding instruction): for
 * 0 <= a the truncation of min(a, R) is the floor, clamped the same. */
static inline uint32_t rs__texel_index(float a, uint32_t resolution)
{
    if (!(a >= 0.0f)) return 0; /* negative or NaN (0/0 on the axis behind the VPL): converting a NaN to an
                                   integer is undefined, and the SIMD paths gather with this index before masking */
    float r = (float)resolution;
    uint32_t i = (uint32_t)(a < r ? a : r);
    return i < resolution - 1 ? i : resolution - 1;
}

uint32_t rs_para_texel_of_uv(uint32_t resolution, float u, float v)
{
    float h = 0.5f * (float)resolution;
    for (int pass = 0; pass < 2; pass++) {
        /* floor((u + 1) h), clamped to [0, R-1] */
        uint32_t i = rs__texel_index((u + 1.0f) * h, resolution);
        uint32_t j = rs__texel_index((v + 1.0f) * h, resolution);
        if (rs_para_texel_inside(resolution, i, j) || pass == 1) return j * resolution + i;
        /* The texel holding (u, v) has its centre outside the disc: move
         * (u, v) in to radius 1 - 1.5/R. The texel holding a point at that
         * radius has its centre within sqrt(2)/R < 1.5/R of it, so inside. */
        float rr = sqrtf(u * u + v * v);
        float k = (1.0f - 1.5f / (float)resolution) / (rr > 0.0f ? rr : 1.0f);
        u *= k;
        v *= k;
    }
    return 0; /* not reached */
}

uint16_t rs_para_fetch(const uint16_t *map, uint32_t resolution, pf_vec3 d_local)
{
    return map[rs_para_texel_of(resolution, d_local)];
}

float rs_para_decode(uint16_t code, float range)
{
    if (code > RS_PARA_MAX_CODE) return INFINITY;
    return ((float)code + 1.0f) * (range / RS_PARA_CODES);
}

float rs_para_depth(const uint16_t *map, uint32_t resolution, float range, const rs_para_frame *f, pf_vec3 dir)
{
    return rs_para_decode(rs_para_fetch(map, resolution, rs__rotate(f, dir)), range);
}

float rs_para_texel_world_size(uint32_t resolution, float dist, pf_vec3 d)
{
    pf_vec2 uv = rs_para_dir_to_uv(pf_v3_normalize(d));
    float rho2 = uv.x * uv.x + uv.y * uv.y;
    return dist * (4.0f / (float)resolution) / (1.0f + rho2);
}

float rs_para_bias(uint32_t resolution, float range, const rs_para_frame *f, pf_vec3 p, pf_vec3 ng)
{
    pf_vec3 to = pf_v3_sub(f->o, p);
    float dist = pf_v3_length(to);
    if (!(dist > 0.0f)) return 2.0f * range / RS_PARA_CODES;
    pf_vec3 n = pf_v3_normalize(ng);
    float c = fabsf(pf_v3_dot(n, to)) / dist;
    float s = sqrtf(fmaxf(0.0f, 1.0f - c * c));
    float tan_t = c > s / RS_PARA_TAN_MAX ? s / c : RS_PARA_TAN_MAX;
    float w = rs_para_texel_world_size(resolution, dist, rs_para_to_local(f, p));
    return w * (1.0f + tan_t) + 2.0f * range / RS_PARA_CODES;
}

int rs_para_visible_scaled(const uint16_t *map, uint32_t resolution, float range, const rs_para_frame *f,
                           pf_vec3 p, const pf_vec3 *plane_n, float cos_receiver, float bias_scale)
{
    /* rs_para_bias + rs_para_visible in one pass: the local direction, its
     * length and its (u, v) are computed once (the many-light accumulation
     * makes this call per VPL per pixel). rs_para_visible_lanes
     * (rs_para_lookup.h) is the same lookup over the SIMD vocabulary. */
    pf_vec3 d = rs_para_to_local(f, p);
    if (!(d.z > 0.0f)) return 0; /* behind the VPL: it emits nothing there */
    float dist = pf_v3_length(d), den = dist + d.z;
    float u = d.x / den, v = d.y / den; /* rs_para_dir_to_uv of d / dist */
    float w = dist * (4.0f / (float)resolution) / (1.0f + (u * u + v * v));
    float c = fabsf(cos_receiver), s = sqrtf(fmaxf(0.0f, 1.0f - c * c));
    float tan_t = c > s / RS_PARA_TAN_MAX ? s / c : RS_PARA_TAN_MAX;
    uint32_t t = rs_para_texel_of_uv(resolution, u, v);
    uint16_t code = map[t];
    if (code > RS_PARA_MAX_CODE) return 1;
    float step2 = 2.0f * range / RS_PARA_CODES;
    float bias = w * (1.0f + tan_t) + step2;
    if (!plane_n) return dist <= rs_para_decode(code, range) + bias_scale * bias;
    /* The receiver-plane test (see the header): the distance at which the
     * texel centre's ray meets the receiver's plane, kept within the slope
     * bias of the point's own distance, against the stored distance. */
    float R = (float)resolution, fi = (float)(t % resolution), fj = (float)(t / resolution);
    float uc = ((fi + fi + 1.0f) - R) / R, vc = ((fj + fj + 1.0f) - R) / R;
    float rc = uc * uc + vc * vc;
    pf_vec3 n = rs__rotate(f, *plane_n);
    float num = (n.x * d.x + n.y * d.y) + n.z * d.z;
    float dn = (n.x * (uc + uc) + n.y * (vc + vc)) + n.z * (1.0f - rc);
    float lo = dist - bias, hi = dist + bias, at = lo;
    if (fabsf(dn) > RS_PARA_PLANE_MIN_COS) {
        float sp = num * (1.0f + rc) / dn;
        if (sp > 0.0f) at = sp < lo ? lo : (sp > hi ? hi : sp);
    }
    return at <= rs_para_decode(code, range) + (w * RS_PARA_PLANE_EPS + step2);
}

int rs_para_visible(const uint16_t *map, uint32_t resolution, float range, const rs_para_frame *f, pf_vec3 p,
                    float bias)
{
    pf_vec3 d = rs_para_to_local(f, p);
    if (!(d.z > 0.0f)) return 0; /* behind the VPL: it emits nothing there */
    float dist = pf_v3_length(d);
    uint16_t code = rs_para_fetch(map, resolution, d);
    if (code > RS_PARA_MAX_CODE) return 1;
    return dist <= rs_para_decode(code, range) + bias;
}

float rs_para_default_range(const pf_scene *scene)
{
    pf_vec3 ext = pf_v3_sub(scene->bounds_max, scene->bounds_min);
    float diag = pf_v3_length(ext);
    return diag > 0.0f ? 1.01f * diag : 1.0f;
}

/* Distance -> code (see the header): floor(t S), clamped. */
static inline uint16_t rs__quantise_one(float t, float scale)
{
    if (t == INFINITY) return RS_PARA_EMPTY;
    float q = t * scale;
    if (!(q < (float)RS_PARA_MAX_CODE)) return RS_PARA_MAX_CODE;
    return (uint16_t)q; /* truncation = floor for q >= 0 */
}

/* ------------------------------------------------------------------ context */

static void rs__scratch_free(rs__scratch *s)
{
    free(s->depth);
    free(s->tile_max);
    free(s->tile_dirty);
    free(s->tile_skip);
    free(s->tile_class);
    free(s->crect);
    free(s->cnear);
    free(s->key);
    free(s->order);
    free(s->order_tmp);
    free(s->batch_block);
}

static int rs__scratch_init(rs__scratch *s, const rs_para_context *ctx)
{
    memset(s, 0, sizeof *s);
    size_t texels = (size_t)ctx->res * ctx->res, cl = ctx->cluster_count, cs = ctx->cluster_size;
    s->depth = calloc(texels + RS__LANES, sizeof(float)); /* padded: rs__scan's whole-vector loads and stores */
    s->tile_max = malloc((size_t)ctx->tiles * ctx->tiles * sizeof(float));
    s->tile_dirty = malloc((size_t)ctx->tiles * ctx->tiles);
    s->tile_skip = calloc((size_t)ctx->tiles * ctx->tiles, 1);
    s->tile_class = calloc((size_t)ctx->tiles * ctx->tiles, 1);
    s->crect = malloc(cl * sizeof(rs__rect));
    s->cnear = malloc(cl * sizeof(float));
    s->key = malloc(cl * sizeof(uint16_t));
    s->order = malloc(cl * sizeof(uint32_t));
    s->order_tmp = malloc(cl * sizeof(uint32_t));
    /* 26 arrays of cluster_size 4-byte words: tri, 9 l, 3 len, 3 pu, 3 pv,
     * c2max, 4 rect, crossing; each with RS__LANES words of room after
     * them, which the front end's whole-vector left-packing may write
     * (simd_pack_storeu_f: up to SIMD_W <= RS__LANES past the last kept) */
    const size_t stride = cs + RS__LANES;
    s->batch_block = malloc(26 * stride * 4);
    if (!s->depth || !s->tile_max || !s->tile_dirty || !s->tile_skip || !s->tile_class || !s->crect || !s->cnear || !s->key || !s->order ||
        !s->order_tmp || !s->batch_block) {
        rs__scratch_free(s);
        return 0;
    }
    uint32_t *w = s->batch_block;
    rs__batch *b = &s->batch;
    b->tri = w;
    w += stride;
    for (int k = 0; k < 9; k++, w += stride) b->l[k] = (float *)w;
    for (int k = 0; k < 3; k++, w += stride) b->len[k] = (float *)w;
    for (int k = 0; k < 3; k++, w += stride) b->pu[k] = (float *)w;
    for (int k = 0; k < 3; k++, w += stride) b->pv[k] = (float *)w;
    b->c2max = (float *)w;
    w += stride;
    for (int k = 0; k < 4; k++, w += stride) b->rect[k] = (int32_t *)w;
    b->crossing = (int32_t *)w;
    return 1;
}

static int rs__scratch_reserve(rs_para_context *ctx, uint32_t count)
{
    if (count <= ctx->scratch_count) return 1;
    rs__scratch **grown = realloc(ctx->scratch, count * sizeof(rs__scratch *));
    if (!grown) return 0;
    ctx->scratch = grown;
    for (uint32_t k = ctx->scratch_count; k < count; k++) {
        rs__scratch *sc = aligned_alloc(64, sizeof(rs__scratch)); /* sizeof is a multiple of 64 */
        if (!sc) return 0;
        if (!rs__scratch_init(sc, ctx)) {
            free(sc);
            return 0;
        }
        ctx->scratch[k] = sc;
        ctx->scratch_count = k + 1;
    }
    return 1;
}

static rs_simd rs__simd_supported(rs_simd want)
{
#if SIMD_X86
    pf_isa isa = pf_isa_detect();
    if (want == RS_SIMD_AVX512 && isa >= PF_ISA_AVX512) return RS_SIMD_AVX512;
    if (want >= RS_SIMD_AVX2 && isa >= PF_ISA_AVX2) return RS_SIMD_AVX2;
#else
    (void)want;
#endif
    return RS_SIMD_SCALAR;
}

/* Slot t of the structure of arrays: the corners, the plane normal
 * (B - A) x (C - A) made in double and rounded once, and the longest edge. */
static void rs__fill_tri(rs_para_context *ctx, size_t t, pf_vec3 a, pf_vec3 b, pf_vec3 c)
{
    const pf_vec3 q[3] = {a, b, c};
    double p[3][3];
    for (int v = 0; v < 3; v++) {
        ctx->soa[3 * v + 0][t] = q[v].x;
        ctx->soa[3 * v + 1][t] = q[v].y;
        ctx->soa[3 * v + 2][t] = q[v].z;
        p[v][0] = q[v].x;
        p[v][1] = q[v].y;
        p[v][2] = q[v].z;
    }
    double ab[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    double ac[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    ctx->soa[9][t] = (float)(ab[1] * ac[2] - ab[2] * ac[1]);
    ctx->soa[10][t] = (float)(ab[2] * ac[0] - ab[0] * ac[2]);
    ctx->soa[11][t] = (float)(ab[0] * ac[1] - ab[1] * ac[0]);
    /* longest edge, rounded up: every point of the triangle lies within it
     * of each vertex */
    double bc[3] = {p[2][0] - p[1][0], p[2][1] - p[1][1], p[2][2] - p[1][2]};
    double e2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    double e2b = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2], e2c = bc[0] * bc[0] + bc[1] * bc[1] + bc[2] * bc[2];
    e2 = e2b > e2 ? e2b : e2;
    e2 = e2c > e2 ? e2c : e2;
    ctx->soa[12][t] = nextafterf((float)(sqrt(e2) * (1.0 + 1e-6)), INFINITY);
}

/* A cluster's bounding sphere: around its box centre, radius measured in
 * double and rounded up. */
static void rs__cluster_sphere(const rs_para_context *ctx, rs__cluster *cl)
{
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t t = cl->first; t < cl->first + cl->count; t++)
        for (int v = 0; v < 3; v++)
            for (int a = 0; a < 3; a++) {
                float x = ctx->soa[3 * v + a][t];
                lo[a] = x < lo[a] ? x : lo[a];
                hi[a] = x > hi[a] ? x : hi[a];
            }
    cl->cx = 0.5f * (lo[0] + hi[0]);
    cl->cy = 0.5f * (lo[1] + hi[1]);
    cl->cz = 0.5f * (lo[2] + hi[2]);
    double r2 = 0.0;
    for (uint32_t t = cl->first; t < cl->first + cl->count; t++)
        for (int v = 0; v < 3; v++) {
            double dx = (double)ctx->soa[3 * v][t] - cl->cx, dy = (double)ctx->soa[3 * v + 1][t] - cl->cy,
                   dz = (double)ctx->soa[3 * v + 2][t] - cl->cz;
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 > r2) r2 = d2;
        }
    cl->r = nextafterf((float)(sqrt(r2) * (1.0 + 1e-6)), INFINITY);
}

/* The batches of cluster c (RS__LANES triangles each, cluster sizes being
 * multiples of it) with their spheres. */
static void rs__lane_spheres(rs_para_context *ctx, uint32_t c)
{
    const rs__cluster *cl = &ctx->clusters[c];
    for (uint32_t base = cl->first; base < cl->first + cl->count; base += RS__LANES) {
        rs__cluster *ln = &ctx->lanes[base / RS__LANES];
        ln->first = base;
        ln->count = cl->first + cl->count - base < RS__LANES ? cl->first + cl->count - base : RS__LANES;
        rs__cluster_sphere(ctx, ln);
    }
}

/* Super-cluster g: the triangles of clusters [g RS__SUPER, ...) (exact maps:
 * contiguous), one sphere. */
static void rs__super_sphere(rs_para_context *ctx, uint32_t g)
{
    uint32_t c0 = g * RS__SUPER, c1 = c0 + RS__SUPER < ctx->cluster_count ? c0 + RS__SUPER : ctx->cluster_count;
    rs__cluster *sp = &ctx->supers[g];
    sp->first = ctx->clusters[c0].first;
    sp->count = ctx->clusters[c1 - 1].first + ctx->clusters[c1 - 1].count - sp->first;
    rs__cluster_sphere(ctx, sp);
}

pf_result rs_para_context_create(rs_para_context **out, const pf_scene *scene, const rs_para_options *opts,
                                 pf_error *err)
{
    *out = NULL;
    rs_para_options o = {0};
    if (opts) o = *opts;
    if (o.resolution == 0) o.resolution = RS_PARA_DEFAULT_RES;
    if (o.cluster_size == 0) o.cluster_size = RS_PARA_DEFAULT_CLUSTER;
    if (o.resolution < RS_PARA_MIN_RES || o.resolution > RS_PARA_MAX_RES)
        return pf_error_set(err, PF_ERR_ARGUMENT, "paraboloid map resolution %u is outside %u..%u", o.resolution,
                            RS_PARA_MIN_RES, RS_PARA_MAX_RES);
    if (o.cluster_size < RS__LANES || o.cluster_size > 1024 || o.cluster_size % RS__LANES)
        return pf_error_set(err, PF_ERR_ARGUMENT, "paraboloid cluster size %u is not a multiple of %u in %u..1024",
                            o.cluster_size, RS__LANES, RS__LANES);
    if (!scene || scene->tri_count == 0)
        return pf_error_set(err, PF_ERR_NO_TRIANGLES, "paraboloid maps: the scene has no triangles");
    if (!(o.lod >= 0.0f && o.lod <= RS_PARA_MAX_LOD))
        return pf_error_set(err, PF_ERR_ARGUMENT, "paraboloid level-of-detail factor %g is outside 0..%g",
                            (double)o.lod, (double)RS_PARA_MAX_LOD);

    rs_para_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "paraboloid maps: out of memory");
    uint32_t R = o.resolution;
    ctx->res = R;
    ctx->tiles = (R + RS__TILE - 1) / RS__TILE;
    ctx->tri_count = scene->tri_count;
    ctx->cluster_size = o.cluster_size;
    ctx->cluster_count = (scene->tri_count + o.cluster_size - 1) / o.cluster_size;
    ctx->tri_padded = ctx->cluster_count * o.cluster_size;
    ctx->simd = o.force_scalar ? RS_SIMD_SCALAR : rs__simd_supported(RS_SIMD_AVX512);

    rs__lod lod = {0};
    if (o.lod > 0.0f) {
        pf_result r = rs__lod_build(&lod, scene, err);
        if (r != PF_OK) {
            rs_para_context_destroy(ctx);
            return r;
        }
        /* one run of clusters per group and level, each starting on a
         * cluster boundary */
        ctx->cluster_count = 0;
        for (uint32_t g = 0; g < lod.group_count; g++)
            for (uint32_t L = 0; L < lod.groups[g].levels; L++)
                ctx->cluster_count += (lod.groups[g].count[L] + o.cluster_size - 1) / o.cluster_size;
        ctx->tri_padded = ctx->cluster_count * o.cluster_size;
        ctx->lod = o.lod;
        ctx->lod_count = lod.group_count;
        ctx->lod_groups = calloc(lod.group_count, sizeof(rs__lod_sel));
    }
    ctx->soa_block = aligned_alloc(64, (size_t)13 * ctx->tri_padded * sizeof(float));
    ctx->clusters = calloc(ctx->cluster_count, sizeof(rs__cluster));
    ctx->cluster_moved = calloc(ctx->cluster_count ? ctx->cluster_count : 1, 1);
    ctx->cluster_dynamic = calloc(ctx->cluster_count ? ctx->cluster_count : 1, 1);
    ctx->cluster_static = malloc(ctx->cluster_count ? ctx->cluster_count : 1);
    ctx->lane_count = ctx->tri_padded / RS__LANES;
    ctx->lanes = calloc(ctx->lane_count ? ctx->lane_count : 1, sizeof(rs__cluster));
    ctx->u = malloc(R * sizeof(float));
    /* d2, dz and w padded by a batch of lanes (zeros): the scan reads whole
     * vectors of them past a row's last texel and masks those lanes */
    ctx->d2 = calloc((size_t)R + RS__LANES, sizeof(float));
    ctx->dz = calloc((size_t)R * R + RS__LANES, sizeof(float));
    ctx->w = calloc((size_t)R * R + RS__LANES, sizeof(float));
    ctx->row_lo = malloc(R * sizeof(int32_t));
    ctx->row_hi = malloc(R * sizeof(int32_t));
    if (ctx->cluster_static) memset(ctx->cluster_static, 1, ctx->cluster_count ? ctx->cluster_count : 1);
    if (!ctx->soa_block || !ctx->clusters || !ctx->cluster_moved || !ctx->cluster_dynamic || !ctx->cluster_static ||
        !ctx->lanes || !ctx->u || !ctx->d2 || !ctx->dz || !ctx->w || !ctx->row_lo ||
        !ctx->row_hi || (o.lod > 0.0f && !ctx->lod_groups)) {
        rs__lod_free(&lod);
        rs_para_context_destroy(ctx);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "paraboloid maps: out of memory");
    }

    /* Triangles in structure of arrays, zero padding (padding lanes are
     * masked off): exact maps take the scene's in scene order, cluster c
     * holding triangles [c * cluster_size, ...); with levels of detail each
     * group's levels follow one another, each level's run of clusters
     * starting on a cluster boundary. */
    memset(ctx->soa_block, 0, (size_t)13 * ctx->tri_padded * sizeof(float));
    for (int k = 0; k < 13; k++) ctx->soa[k] = ctx->soa_block + (size_t)k * ctx->tri_padded;
    if (o.lod > 0.0f) {
        uint32_t c = 0;
        for (uint32_t g = 0; g < lod.group_count; g++) {
            const rs__lod_group *gr = &lod.groups[g];
            rs__lod_sel *sel = &ctx->lod_groups[g];
            sel->cx = gr->cx, sel->cy = gr->cy, sel->cz = gr->cz, sel->r = gr->r;
            sel->levels = gr->levels;
            for (uint32_t L = 0; L < gr->levels; L++) {
                uint32_t n = gr->count[L], nc = (n + o.cluster_size - 1) / o.cluster_size;
                sel->err[L] = gr->err[L];
                sel->cl_first[L] = c;
                sel->cl_count[L] = nc;
                for (uint32_t k = 0; k < n; k++) {
                    const pf_vec3 *q = &lod.tri[3 * (size_t)(gr->first[L] + k)];
                    rs__fill_tri(ctx, c * o.cluster_size + k, q[0], q[1], q[2]);
                }
                for (uint32_t j = 0; j < nc; j++, c++) {
                    ctx->clusters[c].first = c * o.cluster_size;
                    ctx->clusters[c].count = n - j * o.cluster_size < o.cluster_size ? n - j * o.cluster_size
                                                                                     : o.cluster_size;
                }
            }
        }
        ctx->tri_count = lod.tri_count;
        rs__lod_free(&lod);
    } else {
        for (uint32_t t = 0; t < scene->tri_count; t++) {
            const uint32_t *i = &scene->indices[3 * t];
            rs__fill_tri(ctx, t, scene->positions[i[0]], scene->positions[i[1]], scene->positions[i[2]]);
        }
        for (uint32_t c = 0; c < ctx->cluster_count; c++) {
            ctx->clusters[c].first = c * o.cluster_size;
            ctx->clusters[c].count = scene->tri_count - ctx->clusters[c].first < o.cluster_size
                                         ? scene->tri_count - ctx->clusters[c].first
                                         : o.cluster_size;
        }
    }
    for (uint32_t c = 0; c < ctx->cluster_count; c++) rs__cluster_sphere(ctx, &ctx->clusters[c]);
    for (uint32_t c = 0; c < ctx->cluster_count; c++) rs__lane_spheres(ctx, c);
    if (!ctx->lod_groups) {
        ctx->super_count = (ctx->cluster_count + RS__SUPER - 1) / RS__SUPER;
        ctx->supers = calloc(ctx->super_count ? ctx->super_count : 1, sizeof(rs__cluster));
        if (!ctx->supers) {
            rs_para_context_destroy(ctx);
            return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "paraboloid maps: out of memory");
        }
        for (uint32_t g = 0; g < ctx->super_count; g++) rs__super_sphere(ctx, g);
    }

    /* Texel tables. */
    for (uint32_t i = 0; i < R; i++) {
        ctx->u[i] = rs__texel_centre(R, i);
        ctx->d2[i] = 2.0f * ctx->u[i];
    }
    for (uint32_t j = 0; j < R; j++) {
        int32_t lo = (int32_t)R, hi = -1;
        for (uint32_t i = 0; i < R; i++) {
            float s = ctx->u[i] * ctx->u[i] + ctx->u[j] * ctx->u[j];
            ctx->dz[(size_t)j * R + i] = 1.0f - s;
            ctx->w[(size_t)j * R + i] = 1.0f + s;
            if (rs_para_texel_inside(R, i, j)) {
                if ((int32_t)i < lo) lo = (int32_t)i;
                hi = (int32_t)i;
            }
        }
        ctx->row_lo[j] = lo;
        ctx->row_hi[j] = hi;
    }
    *out = ctx;
    return PF_OK;
}

pf_result rs_para_context_update(rs_para_context *ctx, const pf_scene *scene, const pf_anim_moved *moved,
                                 uint32_t count, pf_error *err)
{
    if (ctx->lod_groups)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "paraboloid maps: levels of detail cannot follow moving geometry; make the context again");
    if (scene->tri_count != ctx->tri_count)
        return pf_error_set(err, PF_ERR_ARGUMENT, "paraboloid maps: the scene has %u triangles, the maps %u",
                            scene->tri_count, ctx->tri_count);
    for (uint32_t m = 0; m < count; m++) {
        const pf_anim_moved *r = &moved[m];
        if ((uint64_t)r->tri_first + r->tri_count > scene->tri_count)
            return pf_error_set(err, PF_ERR_ARGUMENT, "paraboloid maps: range %u (triangles %u+%u) is outside the scene",
                                m, r->tri_first, r->tri_count);
    }
    for (uint32_t m = 0; m < count; m++) {
        const pf_anim_moved *r = &moved[m];
        if (!r->moved || r->tri_count == 0) continue;
        for (uint32_t t = r->tri_first; t < r->tri_first + r->tri_count; t++) {
            const uint32_t *i = &scene->indices[3 * t];
            rs__fill_tri(ctx, t, scene->positions[i[0]], scene->positions[i[1]], scene->positions[i[2]]);
        }
        for (uint32_t c = r->tri_first / ctx->cluster_size; c <= (r->tri_first + r->tri_count - 1) / ctx->cluster_size;
             c++) {
            rs__cluster_sphere(ctx, &ctx->clusters[c]);
            rs__lane_spheres(ctx, c);
        }
        uint32_t c0 = r->tri_first / ctx->cluster_size, c1 = (r->tri_first + r->tri_count - 1) / ctx->cluster_size;
        for (uint32_t g = c0 / RS__SUPER; g <= c1 / RS__SUPER; g++) rs__super_sphere(ctx, g);
    }
    return PF_OK;
}

/* Sets flags[c] = 1 for every cluster holding a triangle of the ranges
 * flagged moved (triangle t lies in cluster t / cluster_size on exact
 * maps); 0 when a range lies outside the context's triangles. */
static int rs__mark_clusters(const rs_para_context *ctx, uint8_t *flags, const pf_anim_moved *ranges, uint32_t count)
{
    for (uint32_t m = 0; m < count; m++) {
        const pf_anim_moved *r = &ranges[m];
        if (!r->moved || !r->tri_count) continue;
        if ((uint64_t)r->tri_first + r->tri_count > ctx->tri_count) return 0;
        for (uint32_t c = r->tri_first / ctx->cluster_size; c <= (r->tri_first + r->tri_count - 1) / ctx->cluster_size;
             c++)
            flags[c] = 1;
    }
    return 1;
}

pf_result rs_para_set_dynamic(rs_para_context *ctx, const pf_anim_moved *ranges, uint32_t count, int *grew,
                              pf_error *err)
{
    *grew = 0;
    if (ctx->lod_groups)
        return pf_error_set(err, PF_ERR_ARGUMENT, "paraboloid maps: levels of detail cannot follow moving geometry");
    memset(ctx->cluster_moved, 0, ctx->cluster_count);
    if (!rs__mark_clusters(ctx, ctx->cluster_moved, ranges, count))
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "paraboloid maps: a dynamic range lies outside the scene's %u triangles", ctx->tri_count);
    for (uint32_t c = 0; c < ctx->cluster_count; c++)
        if (ctx->cluster_moved[c] && !ctx->cluster_dynamic[c]) {
            ctx->cluster_dynamic[c] = 1;
            ctx->cluster_static[c] = 0;
            *grew = 1;
        }
    return PF_OK;
}

void rs_para_context_destroy(rs_para_context *ctx)
{
    if (!ctx) return;
    for (uint32_t k = 0; k < ctx->scratch_count; k++) {
        rs__scratch_free(ctx->scratch[k]);
        free(ctx->scratch[k]);
    }
    free(ctx->scratch);
    free(ctx->soa_block);
    free(ctx->clusters);
    free(ctx->lanes);
    free(ctx->supers);
    free(ctx->cluster_moved);
    free(ctx->cluster_dynamic);
    free(ctx->cluster_static);
    free(ctx->lod_groups);
    free(ctx->u);
    free(ctx->d2);
    free(ctx->dz);
    free(ctx->w);
    free(ctx->row_lo);
    free(ctx->row_hi);
    free(ctx);
}

uint32_t rs_para_resolution(const rs_para_context *ctx) { return ctx->res; }
rs_simd rs_para_simd(const rs_para_context *ctx) { return ctx->simd; }
void rs_para_set_simd(rs_para_context *ctx, rs_simd simd) { ctx->simd = rs__simd_supported(simd); }

/* ------------------------------------------------------------------ bounds */

static inline float rs__minf(float a, float b) { return a < b ? a : b; }
static inline float rs__maxf(float a, float b) { return a > b ? a : b; }

/* (u, v) interval -> inclusive texel range: centre u_i = (2i+1-R)/R >= lo
 * <=> i >= (lo + 1) R/2 - 1/2. Written as the SIMD front end computes it. */
static inline void rs__uv_to_texels(float lo, float hi, uint32_t res, int32_t *a, int32_t *b)
{
    float h = 0.5f * (float)res, top = (float)res - 1.0f;
    float fa = ceilf((lo + 1.0f) * h - 0.5f), fb = floorf((hi + 1.0f) * h - 0.5f);
    fa = rs__maxf(fa, 0.0f);
    fb = rs__minf(fb, top);
    if (!(fa <= fb)) { /* empty (or NaN) */
        *a = 1;
        *b = 0;
        return;
    }
    *a = (int32_t)fa;
    *b = (int32_t)fb;
}

static inline rs__rect rs__uv_rect(float umin, float umax, float vmin, float vmax, uint32_t res)
{
    rs__rect r;
    rs__uv_to_texels(umin, umax, res, &r.i0, &r.i1);
    rs__uv_to_texels(vmin, vmax, res, &r.j0, &r.j1);
    return r;
}

static inline int rs__rect_empty(rs__rect r) { return r.i0 > r.i1 || r.j0 > r.j1; }

static inline rs__rect rs__rect_meet(rs__rect a, rs__rect b)
{
    rs__rect r = {a.i0 > b.i0 ? a.i0 : b.i0, a.i1 < b.i1 ? a.i1 : b.i1, a.j0 > b.j0 ? a.j0 : b.j0,
                  a.j1 < b.j1 ? a.j1 : b.j1};
    return r;
}

/* Local coordinates in float (the front end, every path) ... */
static inline void rs__local_f(const rs_para_frame *f, float x, float y, float z, float out[3])
{
    float px = x - f->o.x, py = y - f->o.y, pz = z - f->o.z;
    out[0] = (px * f->t.x + py * f->t.y) + pz * f->t.z;
    out[1] = (px * f->b.x + py * f->b.y) + pz * f->b.z;
    out[2] = (px * f->n.x + py * f->n.y) + pz * f->n.z;
}

/* ... and in double (clipping and the exact fallback; differences of float
 * world coordinates are exact in double). */
static inline void rs__local_d(const rs_para_frame *f, float x, float y, float z, double out[3])
{
    double px = (double)x - (double)f->o.x, py = (double)y - (double)f->o.y, pz = (double)z - (double)f->o.z;
    out[0] = (px * f->t.x + py * f->t.y) + pz * f->t.z;
    out[1] = (px * f->b.x + py * f->b.y) + pz * f->b.z;
    out[2] = (px * f->n.x + py * f->n.y) + pz * f->n.z;
}

static inline void rs__tri_local_d(const rs_para_context *ctx, const rs_para_frame *f, uint32_t t, double a[3][3])
{
    for (int v = 0; v < 3; v++)
        rs__local_d(f, ctx->soa[3 * v][t], ctx->soa[3 * v + 1][t], ctx->soa[3 * v + 2][t], a[v]);
}

/* Bound of a triangle crossing the tangent plane, in double: the polygon
 * clipped to z >= 0, its vertices projected (clip points land on the unit
 * circle), grown by the c^2/4 sagitta bound of each arc. */
static rs__rect rs__crossing_rect(const rs_para_context *ctx, const double a[3][3])
{
    double pu[4], pv[4];
    int n = 0, degenerate = 0;
    for (int k = 0; k < 3; k++) {
        int l = k == 2 ? 0 : k + 1;
        const double *p = a[k], *q = a[l];
        if (p[2] > 0.0) {
            double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            pu[n] = p[0] / (len + p[2]);
            pv[n] = p[1] / (len + p[2]);
            n++;
        }
        if ((p[2] > 0.0) != (q[2] > 0.0)) {
            double s = p[2] / (p[2] - q[2]);
            double x = p[0] + s * (q[0] - p[0]), y = p[1] + s * (q[1] - p[1]);
            double len = sqrt(x * x + y * y);
            if (!(len > 0.0)) {
                degenerate = 1;
                break;
            }
            pu[n] = x / len;
            pv[n] = y / len;
            n++;
        }
    }
    if (degenerate || n < 2) return rs__uv_rect(-1.0f, 1.0f, -1.0f, 1.0f, ctx->res);
    double umin = 1e30, umax = -1e30, vmin = 1e30, vmax = -1e30, c2max = 0.0;
    for (int k = 0; k < n; k++) {
        int l = k == n - 1 ? 0 : k + 1;
        double du = pu[l] - pu[k], dv = pv[l] - pv[k];
        double c2 = du * du + dv * dv;
        c2max = c2 > c2max ? c2 : c2max;
        umin = pu[k] < umin ? pu[k] : umin;
        umax = pu[k] > umax ? pu[k] : umax;
        vmin = pv[k] < vmin ? pv[k] : vmin;
        vmax = pv[k] > vmax ? pv[k] : vmax;
    }
    double m = c2max * 0.25 + RS__UV_EPS;
    return rs__uv_rect((float)(umin - m), (float)(umax + m), (float)(vmin - m), (float)(vmax + m), ctx->res);
}

/* ------------------------------------------------------------------ front end */

/* The front end is a kernel (rs_para_kernels.c, one table per instruction
 * set): rs__front, SIMD_W triangles at a time. */

const rs_para_kernels *rs_para_kernels_for(rs_simd simd)
{
#if SIMD_X86
    if (simd == RS_SIMD_AVX512) return &rs_para_kernels_avx512;
    if (simd == RS_SIMD_AVX2) return &rs_para_kernels_avx2;
#endif
    (void)simd;
    return &rs_para_kernels_scalar;
}

/* ------------------------------------------------------------------ setup */

/* The double path of triangle s->tri: oriented edge normals from double
 * local coordinates. */
static void rs__setup_double(rs__setup *s)
{
    double a[3][3];
    rs__tri_local_d(s->ctx, s->f, s->tri, a);
    for (int k = 0; k < 3; k++) {
        const double *p = a[k], *q = a[k == 2 ? 0 : k + 1];
        s->ed[k][0] = s->sgn * (p[1] * q[2] - p[2] * q[1]);
        s->ed[k][1] = s->sgn * (p[2] * q[0] - p[0] * q[2]);
        s->ed[k][2] = s->sgn * (p[0] * q[1] - p[1] * q[0]);
    }
    s->have_d = 1;
}

/* Setup of batch entry k (see the file comment). Returns 0 when the triangle
 * cannot cover a texel centre (the VPL in its plane), else fills *s and *rect
 * (the front end's rectangle tightened by each edge's exact sagitta, or the
 * crossing bound). */
static int rs__setup_triangle(const rs_para_context *ctx, const rs_para_frame *f, const rs__batch *b, uint32_t k,
                              rs__setup *s, rs__rect *rect)
{
    const uint32_t t = b->tri[k];
    float a[3][3], len[3];
    for (int v = 0; v < 3; v++) {
        for (int c = 0; c < 3; c++) a[v][c] = b->l[3 * v + c][k];
        len[v] = b->len[v][k];
    }
    s->ctx = ctx;
    s->f = f;
    s->tri = t;
    s->have_d = 0;

    /* orientation: det = A . N with N rotated from world space */
    float nw[3] = {ctx->soa[9][t], ctx->soa[10][t], ctx->soa[11][t]};
    float n[3] = {(nw[0] * f->t.x + nw[1] * f->t.y) + nw[2] * f->t.z,
                  (nw[0] * f->b.x + nw[1] * f->b.y) + nw[2] * f->b.z,
                  (nw[0] * f->n.x + nw[1] * f->n.y) + nw[2] * f->n.z};
    float det = (a[0][0] * n[0] + a[0][1] * n[1]) + a[0][2] * n[2];
    float detb = RS__FILTER * (len[0] * ((fabsf(nw[0]) + fabsf(nw[1])) + fabsf(nw[2])));
    float sgn;
    if (det > detb) {
        sgn = 1.0f;
    } else if (det < -detb) {
        sgn = -1.0f;
    } else {
        double ad[3][3];
        rs__tri_local_d(ctx, f, t, ad);
        double bc[3] = {ad[1][1] * ad[2][2] - ad[1][2] * ad[2][1], ad[1][2] * ad[2][0] - ad[1][0] * ad[2][2],
                        ad[1][0] * ad[2][1] - ad[1][1] * ad[2][0]};
        double dd = ad[0][0] * bc[0] + ad[0][1] * bc[1] + ad[0][2] * bc[2];
        if (dd == 0.0) return 0;
        sgn = dd > 0.0 ? 1.0f : -1.0f;
    }
    s->sgn = sgn;
    s->det = sgn * det;
    if (!(s->det > 0.0f)) return 0; /* nearly edge-on: no texel centre is met in front */
    for (int c = 0; c < 3; c++) s->nf[c] = sgn * n[c];
    for (int e = 0; e < 3; e++) {
        const float *p = a[e], *q = a[e == 2 ? 0 : e + 1];
        s->e[e][0] = sgn * (p[1] * q[2] - p[2] * q[1]);
        s->e[e][1] = sgn * (p[2] * q[0] - p[0] * q[2]);
        s->e[e][2] = sgn * (p[0] * q[1] - p[1] * q[0]);
        s->bound[e] = RS__FILTER * (len[e] * len[e == 2 ? 0 : e + 1]);
    }

    if (b->crossing[k]) {
        double ad[3][3];
        rs__tri_local_d(ctx, f, t, ad);
        *rect = rs__crossing_rect(ctx, ad);
        return 1;
    }
    rs__rect r = {b->rect[0][k], b->rect[1][k], b->rect[2][k], b->rect[3][k]};
    *rect = r;
    /* Tighten when the c^2/4 margin exceeds 1/8 texel: each edge's chord box
     * grown by its own sagitta h = (c^2/4) |e.z| / (|e| + sqrt(|e|^2 -
     * (c^2/4) e.z^2)) (r = |e| / |e.z|), inflated by 1e-3 against the float
     * error of e. */
    if (b->c2max[k] * 0.25f > 0.25f / (float)ctx->res) {
        float umin = FLT_MAX, umax = -FLT_MAX, vmin = FLT_MAX, vmax = -FLT_MAX;
        for (int e = 0; e < 3; e++) {
            int l = e == 2 ? 0 : e + 1;
            float pu0 = b->pu[e][k], pu1 = b->pu[l][k], pv0 = b->pv[e][k], pv1 = b->pv[l][k];
            float du = pu1 - pu0, dv = pv1 - pv0;
            float q = 0.25f * (du * du + dv * dv);
            const float *ek = s->e[e];
            float ee = (ek[0] * ek[0] + ek[1] * ek[1]) + ek[2] * ek[2];
            float ez = fabsf(ek[2]);
            float h = ee > 0.0f ? q * ez / (sqrtf(ee) + sqrtf(rs__maxf(0.0f, ee - q * ez * ez))) : q;
            h = h * 1.001f + RS__UV_EPS;
            umin = rs__minf(umin, rs__minf(pu0, pu1) - h);
            umax = rs__maxf(umax, rs__maxf(pu0, pu1) + h);
            vmin = rs__minf(vmin, rs__minf(pv0, pv1) - h);
            vmax = rs__maxf(vmax, rs__maxf(pv0, pv1) + h);
        }
        *rect = rs__rect_meet(*rect, rs__uv_rect(umin, umax, vmin, vmax, ctx->res));
    }
    return 1;
}

/* ------------------------------------------------------------------ texel test */

/* Texel with direction (dx, dy, dz) given its three float edge values: 1 if
 * covered. Shared by every path (the scan kernels call it for the lanes the
 * filter left undecided). */
int rs__para_resolve(rs__setup *s, const float g[3], float dx, float dy, float dz, uint64_t *fallbacks)
{
    for (int k = 0; k < 3; k++)
        if (g[k] < -s->bound[k]) return 0;
    for (int k = 0; k < 3; k++) {
        if (g[k] > s->bound[k]) continue;
        (*fallbacks)++;
        if (!s->have_d) rs__setup_double(s);
        const double *e = s->ed[k];
        double gd = ((double)dx * e[0] + (double)dy * e[1]) + (double)dz * e[2];
        /* SoS: on the plane, the first nonzero component of e' decides */
        int in = gd != 0.0 ? gd > 0.0 : e[0] != 0.0 ? e[0] > 0.0 : e[1] != 0.0 ? e[1] > 0.0 : e[2] > 0.0;
        if (!in) return 0;
    }
    return 1;
}

/* The texel loop is a kernel (rs_para_kernels.c): rs__scan. */

/* ------------------------------------------------------------------ per map */

/* Cluster cap -> texel rectangle and nearest distance; 0 = nothing to draw
 * (behind the tangent plane, or no texel centre in the cap's image). */
static int rs__cluster_bound(const rs_para_context *ctx, const rs_para_frame *f, const rs__cluster *cl,
                             rs__rect *rect, float *near)
{
    float c[3];
    rs__local_f(f, cl->cx, cl->cy, cl->cz, c);
    float rho2 = c[0] * c[0] + c[1] * c[1];
    float dist = sqrtf(rho2 + c[2] * c[2]);
    /* Wholly behind the tangent plane (float error of c[2] is below
     * 4 u dist; the margin is 1e-6 dist). */
    if (c[2] + cl->r < -1e-6f * dist) return 0;
    float sa = cl->r / dist * 1.00001f;
    if (!(dist > 0.0f) || !(sa < 1.0f)) { /* the VPL is inside the sphere */
        *near = 0.0f;
        *rect = rs__uv_rect(-1.0f, 1.0f, -1.0f, 1.0f, ctx->res);
        return 1;
    }
    *near = (dist - cl->r) - 1e-4f * dist; /* the margin: see rs__draw_cluster */
    float ca = sqrtf(1.0f - sa * sa);
    float sxy = sqrtf(rho2);
    float sphi = sxy / dist, cphi = c[2] / dist;
    float s_lo = sphi * ca - cphi * sa, c_lo = cphi * ca + sphi * sa; /* phi - alpha */
    float s_hi = sphi * ca + cphi * sa, c_hi = cphi * ca - sphi * sa; /* phi + alpha */
    /* phi + alpha >= pi (sin <= 0): the cap holds the south pole -n, whose
     * image is at infinity; the part above the horizon may be anywhere. */
    if (!(s_hi > 0.0f) || !(1.0f + c_hi > 1e-3f)) {
        *rect = rs__uv_rect(-1.0f, 1.0f, -1.0f, 1.0f, ctx->res);
        return 1;
    }
    float r_lo = s_lo / (1.0f + c_lo), r_hi = s_hi / (1.0f + c_hi);
    float mid = 0.5f * (r_lo + r_hi), rad = 0.5f * (r_hi - r_lo) * 1.0001f + 1e-5f;
    float cx = sxy > 0.0f ? c[0] / sxy : 1.0f, cy = sxy > 0.0f ? c[1] / sxy : 0.0f;
    float mu = mid * cx, mv = mid * cy;
    *rect = rs__uv_rect(rs__maxf(mu - rad, -1.0f), rs__minf(mu + rad, 1.0f), rs__maxf(mv - rad, -1.0f),
                        rs__minf(mv + rad, 1.0f), ctx->res);
    return !rs__rect_empty(*rect);
}

/* Maximum depth over tile (ti, tj)'s inside texels that the map renders
 * (sc->limit; -INFINITY: none). Every rectangle tested against it is met
 * with the limit first, so texels outside it, never drawn, do not keep
 * their tile from culling. */
static float rs__tile_max(const rs_para_context *ctx, const rs__scratch *sc, int32_t ti, int32_t tj)
{
    const uint32_t R = ctx->res;
    const rs__rect L = sc->limit;
    float m = -INFINITY;
    int32_t j0 = tj * RS__TILE > L.j0 ? tj * RS__TILE : L.j0;
    int32_t jend = (tj + 1) * RS__TILE < (int32_t)R ? (tj + 1) * RS__TILE : (int32_t)R;
    jend = jend < L.j1 + 1 ? jend : L.j1 + 1;
    for (int32_t j = j0; j < jend; j++) {
        int32_t lo = ti * RS__TILE > ctx->row_lo[j] ? ti * RS__TILE : ctx->row_lo[j];
        int32_t hi = (ti + 1) * RS__TILE - 1 < ctx->row_hi[j] ? (ti + 1) * RS__TILE - 1 : ctx->row_hi[j];
        lo = lo > L.i0 ? lo : L.i0, hi = hi < L.i1 ? hi : L.i1;
        const float *d = sc->depth + (size_t)j * R;
        for (int32_t i = lo; i <= hi; i++) m = d[i] > m ? d[i] : m;
    }
    return m;
}

/* Marks the tiles the texel rectangle r touched: their maxima are
 * recomputed when an occlusion test next reads them. */
static void rs__dirty_tiles(const rs_para_context *ctx, rs__scratch *sc, rs__rect r)
{
    for (int32_t tj = r.j0 / RS__TILE; tj <= r.j1 / RS__TILE; tj++)
        for (int32_t ti = r.i0 / RS__TILE; ti <= r.i1 / RS__TILE; ti++) sc->tile_dirty[tj * ctx->tiles + ti] = 1;
}

/* 1 if every tile r touches holds only depths nearer than `near` (so nothing
 * at distance >= near can change the map there). Stops at the first tile that
 * does not. */
static int rs__occluded(const rs_para_context *ctx, rs__scratch *sc, rs__rect r, float near)
{
    for (int32_t tj = r.j0 / RS__TILE; tj <= r.j1 / RS__TILE; tj++)
        for (int32_t ti = r.i0 / RS__TILE; ti <= r.i1 / RS__TILE; ti++) {
            uint32_t t = tj * ctx->tiles + ti;
            if (sc->tile_skip[t]) continue; /* a tile this pass does not draw: nothing there can matter */
            if (sc->tile_dirty[t]) {
                sc->tile_max[t] = rs__tile_max(ctx, sc, ti, tj);
                sc->tile_dirty[t] = 0;
            }
            if (!(near > sc->tile_max[t])) return 0;
        }
    return 1;
}

/* Stable LSD radix sort of order[0..n) by key (two 8-bit passes; the result
 * is back in sc->order). */
static void rs__sort_clusters(rs__scratch *sc, uint32_t n)
{
    uint32_t *src = sc->order, *dst = sc->order_tmp;
    for (int pass = 0; pass < 2; pass++) {
        uint32_t count[257] = {0};
        int shift = 8 * pass;
        for (uint32_t k = 0; k < n; k++) count[((sc->key[src[k]] >> shift) & 255) + 1]++;
        for (int b = 0; b < 256; b++) count[b + 1] += count[b];
        for (uint32_t k = 0; k < n; k++) dst[count[(sc->key[src[k]] >> shift) & 255]++] = src[k];
        uint32_t *tmp = src;
        src = dst;
        dst = tmp;
    }
}

/* Prefetch hint: every 64-byte line of a cluster's range in the nine
 * position arrays (what rs__front reads). */
static void rs__prefetch_positions(const rs_para_context *ctx, const rs__cluster *cl)
{
    for (int a = 0; a < 9; a++) {
        const char *p = (const char *)(ctx->soa[a] + cl->first);
        const char *e = (const char *)(ctx->soa[a] + cl->first + cl->count);
        for (; p < e; p += 64) __builtin_prefetch(p);
    }
}

/* Draws one cluster: front end, then setup and scan of every survivor.
 * Returns the texel rectangle written to (for the tile maxima). */
static rs__rect rs__draw_cluster(const rs_para_context *ctx, rs__scratch *sc, const rs_para_frame *f,
                                 const rs__cluster *cl, rs__rect limit)
{
    rs__rect dirty = {(int32_t)ctx->res, -1, (int32_t)ctx->res, -1};
    rs__batch *b = &sc->batch;
    b->n = 0;
    const rs_para_kernels *kern = rs_para_kernels_for(ctx->simd);
    if (!sc->partial) {
        kern->front(ctx, sc, f, cl);
    } else {
        /* a partial render: only the batches whose sphere's image meets the
         * texels it draws, and is not hidden there already, reach the front
         * end (in order; the depth kept per texel, the nearest, does not
         * depend on what is skipped) */
        for (uint32_t base = cl->first; base < cl->first + cl->count; base += RS__LANES) {
            const rs__cluster *ln = &ctx->lanes[base / RS__LANES];
            rs__rect r;
            float near;
            if (!rs__cluster_bound(ctx, f, ln, &r, &near)) continue;
            r = rs__rect_meet(r, limit);
            if (rs__rect_empty(r) || rs__occluded(ctx, sc, r, near)) {
                sc->stats.triangles_occluded += ln->count;
                continue;
            }
            kern->front(ctx, sc, f, ln);
        }
    }
    /* the setup reads each survivor's normal and longest edge from the
     * scene-order arrays, which the front end did not touch and which the
     * hardware prefetcher does not follow (a cluster's survivors are a few
     * scattered triangles): ask for all of them first (a hint, no result
     * changes; docs/perf.md, 2026-12-02 evening) */
    for (uint32_t k = 0; k < b->n; k++)
        for (int a = 9; a < 13; a++) __builtin_prefetch(ctx->soa[a] + b->tri[k]);
    for (uint32_t k = 0; k < b->n; k++) {
        rs__setup s;
        rs__rect rect;
        if (!b->crossing[k]) {
            /* Occluded already? Every point of the triangle is at least
             * min |vertex| - longest edge from the VPL; if that is beyond
             * every depth in the tiles its rectangle touches, it cannot
             * change the map. Tiles written earlier in this cluster keep
             * maxima that may be too large (they are marked dirty only after
             * the cluster), which only culls less. The margin, 1e-4 of the
             * distance (also for clusters), covers the float error of the
             * lengths (~3e-7) and of the hit distances t the scan would
             * compute, except at incidences within ~0.1 degree of grazing,
             * where t itself is that uncertain (several codes). */
            float lmin = rs__minf(rs__minf(b->len[0][k], b->len[1][k]), b->len[2][k]);
            float near = (lmin - ctx->soa[12][b->tri[k]]) - 1e-4f * lmin;
            rs__rect r = rs__rect_meet((rs__rect){b->rect[0][k], b->rect[1][k], b->rect[2][k], b->rect[3][k]}, limit);
            if (rs__rect_empty(r)) continue; /* outside the texels the map renders */
            if (near > 0.0f && rs__occluded(ctx, sc, r, near)) {
                sc->stats.triangles_occluded++;
                continue;
            }
        }
        if (!rs__setup_triangle(ctx, f, b, k, &s, &rect)) continue;
        rect = rs__rect_meet(rect, limit);
        if (rs__rect_empty(rect)) continue;
        sc->stats.triangles_drawn++;
        sc->stats.texels_tested += kern->scan(ctx, sc, &s, rect);
        dirty = (rs__rect){rect.i0 < dirty.i0 ? rect.i0 : dirty.i0, rect.i1 > dirty.i1 ? rect.i1 : dirty.i1,
                           rect.j0 < dirty.j0 ? rect.j0 : dirty.j0, rect.j1 > dirty.j1 ? rect.j1 : dirty.j1};
    }
    return dirty;
}

/* What rs_para_render_box knows besides the texels: which clusters hold
 * moved triangles and the moved bounds' distance range from the map's
 * origin (the sphere's nearest and farthest points, with the clusters'
 * 1e-4 margin). */
typedef struct rs__moved {
    const uint8_t *cluster_moved;
    float near, far;
} rs__moved;

/* One pass over the texels of `limit` whose tiles sc->tile_skip does not
 * skip: depth starts at INFINITY, or (start_old) at an upper bound of the
 * distance `out`'s code stands for; the clusters (those `only` flags when
 * not NULL) are culled, sorted front to back and drawn; each texel's code
 * is then its depth's, or (min_old) the smaller of that and its old code. */
static void rs__pass(rs_para_context *ctx, rs__scratch *sc, const rs_para_frame *fr, float range, uint16_t *out,
                     rs__rect limit, const uint8_t *only, int start_old, int min_old)
{
    const uint32_t R = ctx->res;
    const rs_para_frame f = *fr;
    const float inv_scale = range / RS_PARA_CODES;
    for (uint32_t j = (uint32_t)limit.j0; j <= (uint32_t)limit.j1; j++) { /* only these texels are read */
        const uint8_t *skip = sc->tile_skip + (j / RS__TILE) * ctx->tiles;
        for (uint32_t i = (uint32_t)limit.i0; i <= (uint32_t)limit.i1; i++) {
            if (skip[i / RS__TILE]) continue;
            size_t idx = (size_t)j * R + i;
            float d = INFINITY;
            if (start_old && out[idx] < RS_PARA_MAX_CODE) /* the code's upper end, rounded up */
                d = (float)(((double)out[idx] + 1.0) * (double)inv_scale * (1.0 + 1e-6));
            sc->depth[idx] = d;
        }
    }
    for (uint32_t k = 0; k < ctx->tiles * ctx->tiles; k++) {
        sc->tile_max[k] = INFINITY;
        sc->tile_dirty[k] = start_old ? 1 : 0; /* the maxima of what the old codes put there */
    }

    /* 1. cull clusters, bound the rest (with levels of detail: the clusters
     * of each group's level for this map) */
    uint32_t n = 0;
    float key_scale = 65535.0f / range;
    const uint32_t groups = ctx->lod_groups ? ctx->lod_count : 1;
    /* smallest texel footprint per unit distance (the rim's angle), times
     * the allowed fraction */
    const float lod_per_dist = ctx->lod * 2.0f / (float)R;
    for (uint32_t g = 0; g < groups; g++) {
        uint32_t c0 = 0, c1 = ctx->cluster_count;
        if (ctx->lod_groups) {
            const rs__lod_sel *sel = &ctx->lod_groups[g];
            float dx = sel->cx - f.o.x, dy = sel->cy - f.o.y, dz = sel->cz - f.o.z;
            float near = sqrtf(dx * dx + dy * dy + dz * dz) - sel->r;
            float allowed = near > 0.0f ? near * lod_per_dist : 0.0f;
            uint32_t L = 0;
            while (L + 1 < sel->levels && sel->err[L + 1] <= allowed) L++;
            c0 = sel->cl_first[L];
            c1 = c0 + sel->cl_count[L];
            sc->stats.lod_levels += L;
        }
        for (uint32_t c = c0; c < c1; c++) {
            if (only && !only[c]) continue;
            if (!only && sc->partial && ctx->supers && c % RS__SUPER == 0) { /* a whole super-cluster outside? */
                rs__rect sr;
                float snear;
                const rs__cluster *sp = &ctx->supers[c / RS__SUPER];
                if (!rs__cluster_bound(ctx, &f, sp, &sr, &snear) || rs__rect_empty(rs__rect_meet(sr, limit))) {
                    uint32_t skip = c + RS__SUPER < c1 ? RS__SUPER : c1 - c;
                    sc->stats.clusters_in += skip;
                    sc->stats.clusters_behind += skip;
                    c += skip - 1;
                    continue;
                }
            }
            sc->stats.clusters_in++;
            if (!rs__cluster_bound(ctx, &f, &ctx->clusters[c], &sc->crect[c], &sc->cnear[c])) {
                sc->stats.clusters_behind++;
                continue;
            }
            sc->crect[c] = rs__rect_meet(sc->crect[c], limit);
            if (rs__rect_empty(sc->crect[c])) {
                sc->stats.clusters_behind++; /* outside the re-rendered rectangle */
                continue;
            }
            float k = sc->cnear[c] * key_scale;
            /* a cluster reaching behind the map's origin has a negative near
             * distance (key 0: first); converting a negative or NaN float to
             * uint16_t is undefined */
            sc->key[c] = !(k > 0.0f) ? 0 : k < 65535.0f ? (uint16_t)k : 65535;
            sc->order[n++] = c;
        }
    }
    /* 2. front to back */
    rs__sort_clusters(sc, n);

    /* 3. draw, skipping clusters behind what is drawn already */
    for (uint32_t k = 0; k < n; k++) {
        uint32_t c = sc->order[k];
        /* the clusters come in depth order, so the front end reads the
         * triangle arrays in jumps the hardware prefetcher does not follow:
         * ask for the next cluster's positions (a hint, no result changes;
         * docs/perf.md, 2026-12-02 evening) */
        if (k + 1 < n) rs__prefetch_positions(ctx, &ctx->clusters[sc->order[k + 1]]);
        if (rs__occluded(ctx, sc, sc->crect[c], sc->cnear[c])) {
            sc->stats.clusters_occluded++;
            continue;
        }
        const rs__cluster *cl = &ctx->clusters[c];
        sc->stats.triangles_in += cl->count;
        rs__rect dirty = rs__draw_cluster(ctx, sc, &f, cl, limit);
        if (!rs__rect_empty(dirty)) rs__dirty_tiles(ctx, sc, dirty);
    }

    /* 4. quantise */
    float scale = RS_PARA_CODES / range;
    for (uint32_t j = (uint32_t)limit.j0; j <= (uint32_t)limit.j1; j++) {
        const uint8_t *skip = sc->tile_skip + (j / RS__TILE) * ctx->tiles;
        for (uint32_t i = (uint32_t)limit.i0; i <= (uint32_t)limit.i1; i++) {
            if (skip[i / RS__TILE]) continue;
            size_t idx = (size_t)j * R + i;
            int inside = (int32_t)i >= ctx->row_lo[j] && (int32_t)i <= ctx->row_hi[j];
            uint16_t q = inside ? rs__quantise_one(sc->depth[idx], scale) : RS_PARA_OUTSIDE;
            out[idx] = min_old && inside && out[idx] < q ? out[idx] : q;
        }
    }
}

/* Tile classes of a partial render after geometry moved (rs__render_map). */
enum { RS__KEEP = 0, RS__MOVED_ONLY = 1, RS__ALL = 2, RS__OUT = 3 /* a tile the rectangle does not meet */ };

/* Renders one map, or with `limit` not covering the whole map only the
 * texels of that rectangle (the others keep their codes in `out`): every
 * texel's depth is the nearest hit over all triangles whatever else is
 * drawn, so the rectangle's codes are those of a whole render.
 *
 * With `mv` (rs_para_render_box: `out` holds the map drawn before the
 * geometry of mv->cluster_moved moved inside the bounds whose distances
 * from the origin lie in [mv->near, mv->far]) each 8 x 8 tile of the
 * rectangle is classed by the old codes of its inside texels, each code c
 * standing for a distance in [c, c + 1) range / RS_PARA_CODES:
 *   KEEP        every old hit nearer than the bounds: static geometry in
 *               front of everything that moved, so the codes stay;
 *   MOVED_ONLY  every old hit nearer than the bounds or beyond them (or
 *               nothing hit): the old hit is static and stays, and only the
 *               moved triangles can come nearer: code = min(old, the moved
 *               triangles' own), drawn with only the moved clusters;
 *   ALL         some old hit within the bounds' range (it may have been the
 *               moved geometry): drawn with every triangle.
 * min commutes with the (monotonic) quantisation, so every texel gets the
 * code a whole render gives it (tests/test_moving.c). */
static void rs__render_map(rs_para_context *ctx, rs__scratch *sc, pf_vec3 pos, pf_vec3 nrm, float range,
                           uint16_t *out, rs__rect limit, const rs__moved *mv, uint16_t *static_out)
{
    const uint32_t R = ctx->res, T = ctx->tiles;
    if (rs__rect_empty(limit)) return;
    rs_para_frame f = rs_para_frame_make(pos, nrm);
    sc->limit = limit;
    sc->partial = limit.i0 > 0 || limit.j0 > 0 || limit.i1 < (int32_t)R - 1 || limit.j1 < (int32_t)R - 1;
    sc->stats.maps++;
    memset(sc->tile_skip, 0, (size_t)T * T);
    if (!mv && static_out) { /* the static map, then the dynamic clusters over it */
        assert(!sc->partial);
        rs__pass(ctx, sc, &f, range, static_out, limit, ctx->cluster_static, 0, 0);
        memcpy(out, static_out, (size_t)R * R * sizeof(uint16_t));
        rs__pass(ctx, sc, &f, range, out, limit, ctx->cluster_dynamic, 1, 1);
        return;
    }
    if (!mv) {
        rs__pass(ctx, sc, &f, range, out, limit, NULL, 0, 0);
        return;
    }
    /* classify the tiles the rectangle meets */
    const double step = (double)range / RS_PARA_CODES;
    const double near = mv->near, far = mv->far;
    int any_all = 0, any_moved = 0;
    memset(sc->tile_class, RS__OUT, (size_t)T * T);
    for (int32_t tj = limit.j0 / RS__TILE; tj <= limit.j1 / RS__TILE; tj++)
        for (int32_t ti = limit.i0 / RS__TILE; ti <= limit.i1 / RS__TILE; ti++) {
            int cls = RS__KEEP;
            int32_t j0 = tj * RS__TILE > limit.j0 ? tj * RS__TILE : limit.j0;
            int32_t j1 = (tj + 1) * RS__TILE - 1 < limit.j1 ? (tj + 1) * RS__TILE - 1 : limit.j1;
            for (int32_t j = j0; j <= j1 && cls != RS__ALL; j++) {
                int32_t i0 = ti * RS__TILE > limit.i0 ? ti * RS__TILE : limit.i0;
                int32_t i1 = (ti + 1) * RS__TILE - 1 < limit.i1 ? (ti + 1) * RS__TILE - 1 : limit.i1;
                i0 = i0 > ctx->row_lo[j] ? i0 : ctx->row_lo[j];
                i1 = i1 < ctx->row_hi[j] ? i1 : ctx->row_hi[j];
                for (int32_t i = i0; i <= i1; i++) {
                    uint16_t c = out[(size_t)j * R + i];
                    double lo = c == RS_PARA_EMPTY ? INFINITY : (double)c * step * (1.0 - 1e-6);
                    double hi = c >= RS_PARA_MAX_CODE ? INFINITY : ((double)c + 1.0) * step * (1.0 + 1e-6);
                    if (hi < near) continue;                    /* in front of the bounds */
                    if (lo > far) cls = RS__MOVED_ONLY;         /* beyond them */
                    else {
                        cls = RS__ALL;
                        break;
                    }
                }
            }
            sc->tile_class[tj * T + ti] = (uint8_t)cls;
            any_all |= cls == RS__ALL, any_moved |= cls == RS__MOVED_ONLY;
        }
    if (any_all && static_out) {
        /* with the static map: an ALL tile starts from the static codes
         * and, like the MOVED_ONLY ones, takes the dynamic clusters' over
         * them (a superset of the moved ones: min(static, dynamic) is the
         * whole render's code, min(old, dynamic) too) */
        for (int32_t j = limit.j0; j <= limit.j1; j++)
            for (int32_t i = limit.i0; i <= limit.i1; i++)
                if (sc->tile_class[(j / RS__TILE) * T + i / RS__TILE] == RS__ALL)
                    out[(size_t)j * R + i] = static_out[(size_t)j * R + i];
        for (uint32_t k = 0; k < T * T; k++)
            sc->tile_skip[k] = sc->tile_class[k] != RS__ALL && sc->tile_class[k] != RS__MOVED_ONLY;
        rs__pass(ctx, sc, &f, range, out, limit, ctx->cluster_dynamic, 1, 1);
        memset(sc->tile_skip, 0, (size_t)T * T);
        return;
    }
    if (any_all) { /* every triangle, over the ALL tiles */
        for (uint32_t k = 0; k < T * T; k++) sc->tile_skip[k] = sc->tile_class[k] != RS__ALL;
        rs__pass(ctx, sc, &f, range, out, limit, NULL, 0, 0);
    }
    if (any_moved) { /* the moved triangles, over the MOVED_ONLY tiles */
        for (uint32_t k = 0; k < T * T; k++) sc->tile_skip[k] = sc->tile_class[k] != RS__MOVED_ONLY;
        rs__pass(ctx, sc, &f, range, out, limit, mv->cluster_moved, 1, 1);
    }
    memset(sc->tile_skip, 0, (size_t)T * T);
}

/* ------------------------------------------------------------------ render calls */

typedef struct rs__job {
    rs_para_context *ctx;
    uint16_t *atlas;
    const pf_vec3 *positions, *normals;
    const uint32_t *slots; /* NULL: map k in slot k */
    float range;
    const rs__cluster *box; /* not NULL: re-render only the texels this sphere can be seen through */
    pf_vec3 lo, hi;         /* with box: the world box the sphere bounds */
    const uint8_t *cluster_moved; /* with box, not NULL: the clusters holding moved triangles (rs__render_map) */
    uint16_t *static_atlas;       /* not NULL: the static maps (rs_para_render_split), slots as in atlas */
} rs__job;

static void rs__map_job(void *p, uint32_t item, uint32_t worker)
{
    rs__job *job = p;
    const rs_para_context *ctx = job->ctx;
    size_t texels = (size_t)ctx->res * ctx->res;
    size_t slot = job->slots ? job->slots[item] : item;
    rs__rect limit = {0, (int32_t)ctx->res - 1, 0, (int32_t)ctx->res - 1};
    rs__moved mv, *mvp = NULL;
    if (job->box) {
        rs_para_frame f = rs_para_frame_make(job->positions[item], job->normals[item]);
        /* every corner of the box behind the tangent plane (a margin of 1e-6
         * of the distance for the float error of z): nothing changes */
        int front = 0;
        for (int k = 0; k < 8 && !front; k++) {
            float c[3];
            rs__local_f(&f, k & 1 ? job->hi.x : job->lo.x, k & 2 ? job->hi.y : job->lo.y, k & 4 ? job->hi.z : job->lo.z,
                        c);
            front = c[2] >= -1e-6f * sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        }
        float near;
        if (!front || !rs__cluster_bound(ctx, &f, job->box, &limit, &near)) return;
        if (job->cluster_moved) { /* the distance range of the sphere, with the clusters' margin */
            float c[3];
            rs__local_f(&f, job->box->cx, job->box->cy, job->box->cz, c);
            float dist = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            mv.cluster_moved = job->cluster_moved;
            mv.near = (dist - job->box->r) - 1e-4f * dist;
            mv.far = (dist + job->box->r) + 1e-4f * dist;
            mvp = &mv;
        }
    }
    uint16_t *static_out = job->static_atlas ? job->static_atlas + texels * slot : NULL;
    rs__render_map(job->ctx, job->ctx->scratch[worker], job->positions[item], job->normals[item], job->range,
                   job->atlas + texels * slot, limit, mvp, static_out);
}

void rs_para_render(uint16_t *atlas, rs_para_context *ctx, pf_jobs *jobs, const pf_vec3 *positions,
                    const pf_vec3 *normals, uint32_t count, float range, rs_para_stats *stats)
{
    rs_para_render_slots(atlas, ctx, jobs, positions, normals, NULL, count, range, stats);
}

static void rs__render_jobs(uint16_t *atlas, uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                            const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                            float range, const rs__cluster *box, pf_vec3 lo, pf_vec3 hi,
                            const uint8_t *cluster_moved, rs_para_stats *stats);

void rs_para_render_slots(uint16_t *atlas, rs_para_context *ctx, pf_jobs *jobs, const pf_vec3 *positions,
                          const pf_vec3 *normals, const uint32_t *slots, uint32_t count, float range,
                          rs_para_stats *stats)
{
    rs__render_jobs(atlas, NULL, ctx, jobs, positions, normals, slots, count, range, NULL, pf_v3(0, 0, 0),
                    pf_v3(0, 0, 0), NULL, stats);
}

void rs_para_render_split(uint16_t *atlas, uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                          const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                          float range, rs_para_stats *stats)
{
    rs__render_jobs(atlas, ctx->lod_groups ? NULL : static_atlas, ctx, jobs, positions, normals, slots, count, range,
                    NULL, pf_v3(0, 0, 0), pf_v3(0, 0, 0), NULL, stats);
}

/* rs_para_render_box and its split twin: static_atlas NULL, or the static
 * maps (read only here: a box render never draws them) */
static void rs__render_box(uint16_t *atlas, uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                           const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                           float range, pf_vec3 lo, pf_vec3 hi, const pf_anim_moved *moved, uint32_t moved_count,
                           rs_para_stats *stats)
{
    /* the box's bounding sphere, radius rounded up as the clusters' are */
    rs__cluster box = {0};
    box.cx = 0.5f * (lo.x + hi.x), box.cy = 0.5f * (lo.y + hi.y), box.cz = 0.5f * (lo.z + hi.z);
    double dx = (double)hi.x - box.cx, dy = (double)hi.y - box.cy, dz = (double)hi.z - box.cz;
    double ex = (double)box.cx - lo.x, ey = (double)box.cy - lo.y, ez = (double)box.cz - lo.z;
    dx = dx > ex ? dx : ex, dy = dy > ey ? dy : ey, dz = dz > ez ? dz : ez;
    box.r = nextafterf((float)(sqrt(dx * dx + dy * dy + dz * dz) * (1.0 + 1e-6)), INFINITY);
    /* the clusters the moved triangles lie in (exact maps: triangle t in
     * cluster t / cluster_size); with levels of detail, or ranges outside
     * the context, every texel the sphere reaches is drawn with everything */
    const uint8_t *cm = NULL;
    if (moved && !ctx->lod_groups) {
        memset(ctx->cluster_moved, 0, ctx->cluster_count);
        if (rs__mark_clusters(ctx, ctx->cluster_moved, moved, moved_count)) cm = ctx->cluster_moved;
    }
    /* static maps need every moved cluster declared dynamic (else the
     * static maps hold what moved): without, the maps are drawn as above */
    for (uint32_t c = 0; static_atlas && c < ctx->cluster_count; c++)
        if (!cm || (cm[c] && !ctx->cluster_dynamic[c])) static_atlas = NULL;
    rs__render_jobs(atlas, static_atlas, ctx, jobs, positions, normals, slots, count, range, &box, lo, hi, cm, stats);
}

void rs_para_render_box(uint16_t *atlas, rs_para_context *ctx, pf_jobs *jobs, const pf_vec3 *positions,
                        const pf_vec3 *normals, const uint32_t *slots, uint32_t count, float range, pf_vec3 lo,
                        pf_vec3 hi, const pf_anim_moved *moved, uint32_t moved_count, rs_para_stats *stats)
{
    rs__render_box(atlas, NULL, ctx, jobs, positions, normals, slots, count, range, lo, hi, moved, moved_count,
                   stats);
}

void rs_para_render_box_split(uint16_t *atlas, const uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                              const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                              float range, pf_vec3 lo, pf_vec3 hi, const pf_anim_moved *moved, uint32_t moved_count,
                              rs_para_stats *stats)
{
    rs__render_box(atlas, (uint16_t *)static_atlas, ctx, jobs, positions, normals, slots, count, range, lo, hi, moved,
                   moved_count, stats);
}

static void rs__render_jobs(uint16_t *atlas, uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                            const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                            float range, const rs__cluster *box, pf_vec3 lo, pf_vec3 hi,
                            const uint8_t *cluster_moved, rs_para_stats *stats)
{
    assert(range > 0.0f);
    uint32_t threads = jobs ? pf_jobs_thread_count(jobs) : 1;
    if (!rs__scratch_reserve(ctx, threads)) {
        /* Out of memory growing the scratch: fall back to the scratch we have
         * (at least one is needed). */
        assert(ctx->scratch_count > 0);
        jobs = NULL;
    }
    for (uint32_t k = 0; k < ctx->scratch_count; k++) memset(&ctx->scratch[k]->stats, 0, sizeof(rs_para_stats));
    rs__job job = {ctx, atlas, positions, normals, slots, range, box, lo, hi, cluster_moved, static_atlas};
    if (jobs)
        pf_jobs_parallel_for(jobs, rs__map_job, &job, count, 1);
    else
        for (uint32_t k = 0; k < count; k++) rs__map_job(&job, k, 0);
    if (stats) {
        memset(stats, 0, sizeof *stats);
        for (uint32_t k = 0; k < ctx->scratch_count; k++) {
            const rs_para_stats *s = &ctx->scratch[k]->stats;
            stats->maps += s->maps;
            stats->clusters_in += s->clusters_in;
            stats->clusters_behind += s->clusters_behind;
            stats->clusters_occluded += s->clusters_occluded;
            stats->triangles_in += s->triangles_in;
            stats->triangles_behind += s->triangles_behind;
            stats->triangles_between_texels += s->triangles_between_texels;
            stats->triangles_occluded += s->triangles_occluded;
            stats->triangles_drawn += s->triangles_drawn;
            stats->texels_tested += s->texels_tested;
            stats->texels_exact_fallback += s->texels_exact_fallback;
            stats->lod_levels += s->lod_levels;
        }
    }
}

/* The Embree reference. */
typedef struct rs__traced_job {
    uint16_t *atlas;
    uint32_t res;
    const pf_rt *rt;
    const pf_vec3 *positions, *normals;
    float range;
    pf_ray *rays;   /* per worker: res*res */
    pf_hit *hits;   /* per worker: res*res */
    uint32_t *idx;  /* per worker: res*res */
} rs__traced_job;

static void rs__traced_map(void *p, uint32_t item, uint32_t worker)
{
    rs__traced_job *job = p;
    const uint32_t R = job->res;
    size_t texels = (size_t)R * R;
    pf_ray *rays = job->rays + texels * worker;
    pf_hit *hits = job->hits + texels * worker;
    uint32_t *idx = job->idx + texels * worker;
    uint16_t *out = job->atlas + texels * item;
    rs_para_frame f = rs_para_frame_make(job->positions[item], job->normals[item]);
    uint32_t n = 0;
    for (uint32_t j = 0; j < R; j++)
        for (uint32_t i = 0; i < R; i++) {
            if (!rs_para_texel_inside(R, i, j)) {
                out[(size_t)j * R + i] = RS_PARA_OUTSIDE;
                continue;
            }
            /* the same float direction the rasterizer tests, D / |D| */
            float u = rs__texel_centre(R, i), v = rs__texel_centre(R, j);
            float s = u * u + v * v;
            float dx = 2.0f * u, dy = 2.0f * v, dz = 1.0f - s, w = 1.0f + s;
            pf_vec3 d = pf_v3((f.t.x * dx + f.b.x * dy) + f.n.x * dz, (f.t.y * dx + f.b.y * dy) + f.n.y * dz,
                              (f.t.z * dx + f.b.z * dy) + f.n.z * dz);
            pf_ray ray = {f.o, 0.0f, pf_v3_scale(d, 1.0f / w), INFINITY};
            rays[n] = ray;
            idx[n++] = j * R + i;
        }
    pf_rt_intersect(job->rt, rays, hits, n);
    float scale = RS_PARA_CODES / job->range;
    for (uint32_t k = 0; k < n; k++)
        out[idx[k]] = hits[k].prim == PF_RT_MISS ? RS_PARA_EMPTY : rs__quantise_one(hits[k].t, scale);
}

void rs_para_render_traced(uint16_t *atlas, uint32_t resolution, const pf_rt *rt, pf_jobs *jobs,
                           const pf_vec3 *positions, const pf_vec3 *normals, uint32_t count, float range)
{
    uint32_t threads = jobs ? pf_jobs_thread_count(jobs) : 1;
    size_t texels = (size_t)resolution * resolution;
    rs__traced_job job = {atlas, resolution, rt, positions, normals, range, NULL, NULL, NULL};
    job.rays = malloc(texels * threads * sizeof(pf_ray));
    job.hits = malloc(texels * threads * sizeof(pf_hit));
    job.idx = malloc(texels * threads * sizeof(uint32_t));
    if (!job.rays || !job.hits || !job.idx) {
        /* tests and the bench only: report by leaving maps empty */
        for (size_t k = 0; k < texels * count; k++) atlas[k] = RS_PARA_EMPTY;
    } else if (jobs) {
        pf_jobs_parallel_for(jobs, rs__traced_map, &job, count, 1);
    } else {
        for (uint32_t k = 0; k < count; k++) rs__traced_map(&job, k, 0);
    }
    free(job.rays);
    free(job.hits);
    free(job.idx);
}
