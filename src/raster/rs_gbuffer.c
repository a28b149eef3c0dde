/* rs_gbuffer: G-buffer planes and the deferred attribute resolve (see
 * rs_gbuffer.h), scalar and 8 pixels at a time with AVX2. */
#include "rs_gbuffer.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

void *rs_plane_alloc(size_t bytes)
{
    size_t rounded = (bytes + 63) / 64 * 64;
    void *p = aligned_alloc(64, rounded ? rounded : 64);
    if (p) memset(p, 0, rounded ? rounded : 64);
    return p;
}

pf_result rs_gbuffer_init(rs_gbuffer *g, uint32_t width, uint32_t height, pf_error *err)
{
    memset(g, 0, sizeof *g);
    size_t n = (size_t)width * height;
    g->width = width;
    g->height = height;
    float **planes[] = {&g->depth, &g->pos_x, &g->pos_y, &g->pos_z, &g->nrm_x,
                        &g->nrm_y, &g->nrm_z, &g->alb_r, &g->alb_g, &g->alb_b};
    for (size_t i = 0; i < sizeof planes / sizeof planes[0]; i++)
        if (!(*planes[i] = rs_plane_alloc(n * sizeof(float)))) goto oom;
    if (!(g->prim = rs_plane_alloc(n * sizeof(uint32_t)))) goto oom;
    if (!(g->ray_sx = calloc((size_t)width + 1, sizeof(float))) || !(g->ray_sy = calloc((size_t)height + 1, sizeof(float))))
        goto oom;
    rs_gbuffer_clear(g);
    return PF_OK;
oom:
    rs_gbuffer_free(g);
    return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for a %ux%u G-buffer", width, height);
}

void rs_gbuffer_clear(rs_gbuffer *g)
{
    size_t n = (size_t)g->width * g->height;
    for (size_t i = 0; i < n; i++) {
        g->depth[i] = INFINITY;
        g->prim[i] = RS_GBUFFER_EMPTY;
    }
}

void rs_gbuffer_free(rs_gbuffer *g)
{
    free(g->depth);
    free(g->pos_x);
    free(g->pos_y);
    free(g->pos_z);
    free(g->nrm_x);
    free(g->nrm_y);
    free(g->nrm_z);
    free(g->alb_r);
    free(g->alb_g);
    free(g->alb_b);
    free(g->prim);
    free(g->ray_sx);
    free(g->ray_sy);
    memset(g, 0, sizeof *g);
}

/* The per-triangle constants of the resolve that do not depend on the
 * camera (see rs_resolve_tri in rs_gbuffer.h). */
static void rs__tri_fill(rs_resolve_tri *r, const pf_scene *s, uint32_t prim)
{
    const uint32_t *tri = &s->indices[3 * prim];
    r->p0 = s->positions[tri[0]];
    r->e1 = pf_v3_sub(s->positions[tri[1]], r->p0);
    r->e2 = pf_v3_sub(s->positions[tri[2]], r->p0);
    r->n_det = pf_v3_cross(r->e2, r->e1);
    r->ng = pf_v3_normalize(pf_v3_cross(r->e1, r->e2));
    r->n0 = s->normals[tri[0]];
    r->n1 = s->normals[tri[1]];
    r->n2 = s->normals[tri[2]];
    r->uv0 = s->uvs[tri[0]];
    r->uv1 = s->uvs[tri[1]];
    r->uv2 = s->uvs[tri[2]];
    r->material = s->tri_material[prim];
    r->textured = s->materials[r->material].base_color_texture >= 0;
}

typedef struct rs__resolve_ctx {
    rs_gbuffer *g;
    const pf_scene *scene;
    const rs_resolve_tri *table; /* per-triangle constants, or NULL: made per setup from the scene */
    const pf_camera *cam;
    float *sx, *sy; /* per column / row: the screen offsets of pixel centres (+1 for the neighbour) */
    int simd;       /* take the AVX2 path for groups of 8 pixels on untextured triangles */
} rs__resolve_ctx;

/* Per-triangle constants of the resolve for one camera. With the ray origin
 * o fixed (the eye), Moller-Trumbore's terms that do not involve the
 * direction d are constant per triangle: with tv = o - p0, e1 = p1 - p0,
 * e2 = p2 - p0,
 *   det = d . (e2 x e1),  u = d . (e2 x tv) / det,  v = d . (tv x e1) / det,
 * so a pixel costs three dot products and a division. Pixels come in runs
 * that share a triangle, so the constants are cached across a run; the
 * camera-free part comes from the scene's table (two cache lines) instead
 * of the index, vertex and material arrays. */
typedef struct rs__tri_consts {
    uint32_t prim;
    const rs_resolve_tri *t; /* the table's entry, or &own */
    pf_vec3 n_u, n_v;        /* e2 x tv, tv x e1 */
    rs_resolve_tri own;
} rs__tri_consts;

static void rs__tri_setup(rs__tri_consts *c, const rs__resolve_ctx *rc, uint32_t prim)
{
    c->prim = prim;
    if (rc->table) {
        c->t = &rc->table[prim];
    } else {
        rs__tri_fill(&c->own, rc->scene, prim);
        c->t = &c->own;
    }
    pf_vec3 tv = pf_v3_sub(rc->cam->eye, c->t->p0);
    c->n_u = pf_v3_cross(c->t->e2, tv);
    c->n_v = pf_v3_cross(tv, c->t->e1);
}

/* Unclamped barycentrics of direction d on the triangle's plane. */
static int rs__bary(const rs__tri_consts *c, pf_vec3 d, float *u, float *v)
{
    float det = pf_v3_dot(d, c->t->n_det);
    if (det == 0.0f) return 0;
    float inv = 1.0f / det;
    *u = pf_v3_dot(d, c->n_u) * inv;
    *v = pf_v3_dot(d, c->n_v) * inv;
    return 1;
}

/* Normalises the row's normals (pf_v3_normalize's operations: l =
 * sqrt((x*x + y*y) + z*z), n * (1 / l)), four at a time with SSE2 whose
 * sqrtps/divps round exactly like the scalar sqrtss/divss, so the bits are
 * the scalar function's; taken out of the per-pixel loop because its
 * sqrt -> divide latency chain dominated the resolve. A covered pixel whose
 * normal comes out zero (the interpolated normal vanished) gets the
 * camera-facing geometric normal, as pf_scene_surface does: the SIMD loop
 * flags such lanes itself, so the row is read once. */
static void rs__normal_fallback(rs_gbuffer *g, const pf_scene *s, const pf_camera *cam, const float *sx, float sy,
                                uint32_t x, uint32_t y)
{
    size_t i = (size_t)y * g->width + x;
    if (g->prim[i] == RS_GBUFFER_EMPTY || g->nrm_x[i] != 0.0f || g->nrm_y[i] != 0.0f || g->nrm_z[i] != 0.0f) return;
    pf_vec3 ng = pf_scene_face_normal(s, g->prim[i]);
    pf_vec3 d = pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, sx[x]), pf_v3_scale(cam->up, sy)));
    if (pf_v3_dot(ng, d) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
    g->nrm_x[i] = ng.x, g->nrm_y[i] = ng.y, g->nrm_z[i] = ng.z;
}

static void rs__normalize_row(rs_gbuffer *g, const pf_scene *s, const pf_camera *cam, const float *sx, float sy,
                              uint32_t y)
{
    float *nx = g->nrm_x + (size_t)y * g->width, *ny = g->nrm_y + (size_t)y * g->width;
    float *nz = g->nrm_z + (size_t)y * g->width;
    uint32_t x = 0;
#if defined(__SSE2__)
    for (; x + 4 <= g->width; x += 4) {
        __m128 a = _mm_loadu_ps(nx + x), b = _mm_loadu_ps(ny + x), c = _mm_loadu_ps(nz + x);
        __m128 l = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(a, a), _mm_mul_ps(b, b)), _mm_mul_ps(c, c)));
        __m128 pos = _mm_cmpgt_ps(l, _mm_setzero_ps());
        __m128 inv = _mm_and_ps(pos, _mm_div_ps(_mm_set1_ps(1.0f), l));
        a = _mm_mul_ps(a, inv), b = _mm_mul_ps(b, inv), c = _mm_mul_ps(c, inv);
        _mm_storeu_ps(nx + x, a);
        _mm_storeu_ps(ny + x, b);
        _mm_storeu_ps(nz + x, c);
        const __m128 zero = _mm_setzero_ps();
        __m128 vanished = _mm_and_ps(_mm_and_ps(_mm_cmpeq_ps(a, zero), _mm_cmpeq_ps(b, zero)), _mm_cmpeq_ps(c, zero));
        for (unsigned m = (unsigned)_mm_movemask_ps(vanished); m; m &= m - 1)
            rs__normal_fallback(g, s, cam, sx, sy, x + (uint32_t)__builtin_ctz(m), y);
    }
#endif
    for (; x < g->width; x++) {
        pf_vec3 n = pf_v3_normalize(pf_v3(nx[x], ny[x], nz[x]));
        nx[x] = n.x, ny[x] = n.y, nz[x] = n.z;
        rs__normal_fallback(g, s, cam, sx, sy, x, y);
    }
}

/* One pixel (x, y) of the resolve, scalar; the reference for the SIMD path. */
static void rs__resolve_pixel(const rs__resolve_ctx *rc, rs__tri_consts *c, uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    const pf_scene *s = rc->scene;
    const pf_camera *cam = rc->cam;
    size_t i = (size_t)y * g->width + x;
    uint32_t prim = g->prim[i];
    if (prim == RS_GBUFFER_EMPTY) {
        g->depth[i] = INFINITY;
        g->pos_x[i] = g->pos_y[i] = g->pos_z[i] = 0.0f;
        g->nrm_x[i] = g->nrm_y[i] = g->nrm_z[i] = 0.0f;
        g->alb_r[i] = g->alb_g[i] = g->alb_b[i] = 0.0f;
        return;
    }
    if (prim != c->prim) rs__tri_setup(c, rc, prim);
    const rs_resolve_tri *t = c->t;
    /* pf_camera_ray_dir's expression, its per-column and per-row factors
     * taken from the tables (same formulas, same bits) */
    pf_vec3 d = pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, rc->sx[x]), pf_v3_scale(cam->up, rc->sy[y])));
    float u = 0.0f, v = 0.0f;
    rs__bary(c, d, &u, &v);
    /* uv footprint from the neighbouring pixel centres' rays on the same plane */
    float lod = 0.0f;
    if (t->textured) {
        float ux, vx, uy, vy;
        pf_vec3 dx =
            pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, rc->sx[x + 1]), pf_v3_scale(cam->up, rc->sy[y])));
        pf_vec3 dy =
            pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, rc->sx[x]), pf_v3_scale(cam->up, rc->sy[y + 1])));
        if (rs__bary(c, dx, &ux, &vx) && rs__bary(c, dy, &uy, &vy)) {
            float du1 = t->uv1.x - t->uv0.x, du2 = t->uv2.x - t->uv0.x, dv1 = t->uv1.y - t->uv0.y,
                  dv2 = t->uv2.y - t->uv0.y;
            lod = pf_material_lod(s, t->material, du1 * (ux - u) + du2 * (vx - v), dv1 * (ux - u) + dv2 * (vx - v),
                                  du1 * (uy - u) + du2 * (vy - v), dv1 * (uy - u) + dv2 * (vy - v));
        }
    }
    u = u < 0.0f ? 0.0f : (u > 1.0f ? 1.0f : u);
    v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
    if (u + v > 1.0f) {
        float sum = u + v;
        u /= sum;
        v /= sum;
    }
    float w = 1.0f - u - v;
    pf_vec3 pos = pf_v3_add(t->p0, pf_v3_add(pf_v3_scale(t->e1, u), pf_v3_scale(t->e2, v)));
    /* the interpolated normal, turned to face the camera (two-sided
     * shading); normalised for the whole row by rs__normalize_row */
    pf_vec3 ns = pf_v3_add(pf_v3_add(pf_v3_scale(t->n0, w), pf_v3_scale(t->n1, u)), pf_v3_scale(t->n2, v));
    if (pf_v3_dot(t->ng, d) > 0.0f) ns = pf_v3_scale(ns, -1.0f);
    float albedo[4];
    if (t->textured) {
        pf_vec2 uv = {w * t->uv0.x + u * t->uv1.x + v * t->uv2.x, w * t->uv0.y + u * t->uv1.y + v * t->uv2.y};
        pf_material_sample(s, t->material, uv, lod, albedo);
    } else {
        memcpy(albedo, s->materials[t->material].base_color, sizeof albedo); /* what pf_material_sample returns */
    }
    g->depth[i] = pf_v3_dot(pf_v3_sub(pos, cam->eye), cam->forward); /* view depth of the point */
    g->pos_x[i] = pos.x;
    g->pos_y[i] = pos.y;
    g->pos_z[i] = pos.z;
    g->nrm_x[i] = ns.x;
    g->nrm_y[i] = ns.y;
    g->nrm_z[i] = ns.z;
    g->alb_r[i] = albedo[0];
    g->alb_g[i] = albedo[1];
    g->alb_b[i] = albedo[2];
}

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define RS__GBUF_X86 1
/* rs__resolve8's constants are read as floats: T = the rs_resolve_tri from
 * p0 to n2 (24 floats), UV = n_u, n_v (6), ALB = the base colour (3). */
_Static_assert(offsetof(rs_resolve_tri, e1) == 12 && offsetof(rs_resolve_tri, e2) == 24 &&
                   offsetof(rs_resolve_tri, n_det) == 36 && offsetof(rs_resolve_tri, ng) == 48 &&
                   offsetof(rs_resolve_tri, n0) == 60 && offsetof(rs_resolve_tri, n1) == 72 &&
                   offsetof(rs_resolve_tri, n2) == 84,
               "rs_resolve_tri: p0..n2 must be 24 consecutive floats");
_Static_assert(offsetof(rs__tri_consts, n_v) == offsetof(rs__tri_consts, n_u) + 12, "n_u, n_v must be consecutive");
enum { RS__T_P0 = 0, RS__T_E1 = 3, RS__T_E2 = 6, RS__T_NDET = 9, RS__T_NG = 12, RS__T_N0 = 15, RS__T_N1 = 18,
       RS__T_N2 = 21, RS__T_COUNT = 24, RS__UV_NU = 0, RS__UV_NV = 3, RS__UV_COUNT = 6 };

/* rs__resolve_pixel's work for the 8 pixels x..x+7 of row y on untextured
 * triangles: the same operations in the same order lane by lane (ray
 * direction, rs__bary, clamping and renormalising the barycentrics,
 * position, the camera-facing interpolated normal, view depth, the
 * material's base colour), so the bits are the scalar code's. The
 * constants (T, UV, ALB as above) are one triangle's, broadcast to all
 * lanes. o: depth, position, normal, albedo (10 planes). */
enum { RS__GROUP_MAX_TRIS = 4 }; /* more triangles in a group of 8: the scalar code (measured as fast) */
static inline __attribute__((always_inline, target("avx2"))) void
rs__resolve8_avx2(const rs__resolve_ctx *rc, const float *T, const float *UV, const float *ALB, uint32_t x, uint32_t y,
                  __m256 o[10])
{
#define RS__LD(base, i) _mm256_broadcast_ss((base) + (i))
    const pf_camera *cam = rc->cam;
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 sx = _mm256_loadu_ps(rc->sx + x), sy = _mm256_set1_ps(rc->sy[y]);
#define RS__DIR(k) _mm256_add_ps(_mm256_set1_ps(cam->forward.k), _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(cam->right.k), sx), \
                                                                         _mm256_mul_ps(_mm256_set1_ps(cam->up.k), sy)))
    __m256 dx = RS__DIR(x), dy = RS__DIR(y), dz = RS__DIR(z);
#undef RS__DIR
#define RS__DOT(base, f)                                                                                               \
    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, RS__LD(base, f)), _mm256_mul_ps(dy, RS__LD(base, (f) + 1))),         \
                  _mm256_mul_ps(dz, RS__LD(base, (f) + 2)))
    /* rs__bary: u = v = 0 where det == 0 */
    __m256 det = RS__DOT(T, RS__T_NDET);
    __m256 inv = _mm256_div_ps(one, det), has = _mm256_cmp_ps(det, zero, _CMP_NEQ_UQ);
    __m256 u = _mm256_and_ps(has, _mm256_mul_ps(RS__DOT(UV, RS__UV_NU), inv));
    __m256 v = _mm256_and_ps(has, _mm256_mul_ps(RS__DOT(UV, RS__UV_NV), inv));
    __m256 facing = _mm256_cmp_ps(RS__DOT(T, RS__T_NG), zero, _CMP_GT_OQ);
#undef RS__DOT
    /* x < 0 ? 0 : (x > 1 ? 1 : x) as max(0, min(1, x)): minps(a, b) is
     * a < b ? a : b and maxps(a, b) is a > b ? a : b, so with the constant
     * first a NaN or -0 passes through exactly as in the ternaries */
    u = _mm256_max_ps(zero, _mm256_min_ps(one, u));
    v = _mm256_max_ps(zero, _mm256_min_ps(one, v));
    __m256 sum = _mm256_add_ps(u, v), over = _mm256_cmp_ps(sum, one, _CMP_GT_OQ);
    u = _mm256_blendv_ps(u, _mm256_div_ps(u, sum), over);
    v = _mm256_blendv_ps(v, _mm256_div_ps(v, sum), over);
    __m256 w = _mm256_sub_ps(_mm256_sub_ps(one, u), v);
#define RS__POS(k)                                                                                                     \
    _mm256_add_ps(RS__LD(T, RS__T_P0 + (k)), _mm256_add_ps(_mm256_mul_ps(RS__LD(T, RS__T_E1 + (k)), u),                \
                                                           _mm256_mul_ps(RS__LD(T, RS__T_E2 + (k)), v)))
    __m256 px = RS__POS(0), py = RS__POS(1), pz = RS__POS(2);
#undef RS__POS
    /* ns, times -1 (a multiplication, as pf_v3_scale does) where the
     * triangle faces away from the camera; elsewhere the product is by 1:
     * exact, the same bits */
    __m256 flip = _mm256_blendv_ps(one, _mm256_set1_ps(-1.0f), facing);
#define RS__NRM(k)                                                                                                     \
    _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(RS__LD(T, RS__T_N0 + (k)), w),                             \
                                              _mm256_mul_ps(RS__LD(T, RS__T_N1 + (k)), u)),                            \
                                _mm256_mul_ps(RS__LD(T, RS__T_N2 + (k)), v)),                                          \
                  flip)
    o[4] = RS__NRM(0), o[5] = RS__NRM(1), o[6] = RS__NRM(2);
#undef RS__NRM
    o[0] = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(px, _mm256_set1_ps(cam->eye.x)), _mm256_set1_ps(cam->forward.x)),
                      _mm256_mul_ps(_mm256_sub_ps(py, _mm256_set1_ps(cam->eye.y)), _mm256_set1_ps(cam->forward.y))),
        _mm256_mul_ps(_mm256_sub_ps(pz, _mm256_set1_ps(cam->eye.z)), _mm256_set1_ps(cam->forward.z)));
    o[1] = px, o[2] = py, o[3] = pz;
    o[7] = RS__LD(ALB, 0), o[8] = RS__LD(ALB, 1), o[9] = RS__LD(ALB, 2);
#undef RS__LD
}

/* The 8 pixels x..x+7 of row y with AVX2: each distinct triangle among them
 * is resolved for all 8 lanes and blended into the lanes that show it;
 * empty lanes get rs__resolve_pixel's empty values. Returns 0 (nothing
 * written) when a lane shows a textured triangle or the group shows more
 * than RS__GROUP_MAX_TRIS triangles; the caller then takes the scalar path
 * (per-lane constants transposed from 8 setups were measured no faster).
 * The distinct triangles and their lanes come from 8-lane compares (one
 * per triangle, not a scalar search per lane); the (scalar, SSE-encoded)
 * triangle setups then all run after a vzeroupper and before any further
 * 256-bit register is live, so their loads overlap and no AVX/SSE mixing
 * occurs (without the vzeroupper the resolve ran 60% slower).
 * The cache `c` keeps its triangle if the group shows it, else takes the
 * last lane's, which the next group most likely continues. */
__attribute__((target("avx2"))) static int rs__resolve_group8_avx2(const rs__resolve_ctx *rc, rs__tri_consts *c,
                                                                   uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    size_t i = (size_t)y * g->width + x;
    const uint32_t *prim = g->prim + i;
    __m256i prims = _mm256_loadu_si256((const __m256i *)prim);
    /* the distinct triangles in lane order, each with its lanes */
    uint32_t tris[RS__GROUP_MAX_TRIS];
    unsigned lanes[RS__GROUP_MAX_TRIS];
    int n = 0;
    unsigned left = ~(unsigned)_mm256_movemask_ps(
                        _mm256_castsi256_ps(_mm256_cmpeq_epi32(prims, _mm256_set1_epi32((int)RS_GBUFFER_EMPTY)))) &
                    0xffu;
    while (left) {
        if (n == RS__GROUP_MAX_TRIS) return 0;
        uint32_t p = prim[__builtin_ctz(left)];
        unsigned m = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(prims, _mm256_set1_epi32((int)p))));
        tris[n] = p, lanes[n++] = m;
        left &= ~m;
    }
    /* the setups below are SSE-encoded: no dirty upper halves across them */
    _mm256_zeroupper();
    rs__tri_consts other[RS__GROUP_MAX_TRIS];
    const rs__tri_consts *consts[RS__GROUP_MAX_TRIS];
    int keep = 0;
    for (int j = 0; j < n; j++) keep |= tris[j] == c->prim;
    for (int j = 0; j < n; j++) {
        if (tris[j] == c->prim || (!keep && tris[j] == prim[7])) {
            if (tris[j] != c->prim) rs__tri_setup(c, rc, tris[j]);
            consts[j] = c;
        } else {
            rs__tri_setup(&other[j], rc, tris[j]);
            consts[j] = &other[j];
        }
        if (consts[j]->t->textured) return 0;
    }
    __m256 acc[10], o[10];
    acc[0] = _mm256_set1_ps(INFINITY);
    for (int k = 1; k < 10; k++) acc[k] = _mm256_setzero_ps();
    const pf_material *mat = rc->scene->materials;
    const __m256i bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    for (int j = 0; j < n; j++) {
        const rs__tri_consts *cj = consts[j];
        rs__resolve8_avx2(rc, &cj->t->p0.x, &cj->n_u.x, mat[cj->t->material].base_color, x, y, o);
        __m256 mask = _mm256_castsi256_ps(
            _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32((int)lanes[j]), bits), bits));
        for (int k = 0; k < 10; k++) acc[k] = _mm256_blendv_ps(acc[k], o[k], mask);
    }
    _mm256_storeu_ps(g->depth + i, acc[0]);
    _mm256_storeu_ps(g->pos_x + i, acc[1]);
    _mm256_storeu_ps(g->pos_y + i, acc[2]);
    _mm256_storeu_ps(g->pos_z + i, acc[3]);
    _mm256_storeu_ps(g->nrm_x + i, acc[4]);
    _mm256_storeu_ps(g->nrm_y + i, acc[5]);
    _mm256_storeu_ps(g->nrm_z + i, acc[6]);
    _mm256_storeu_ps(g->alb_r + i, acc[7]);
    _mm256_storeu_ps(g->alb_g + i, acc[8]);
    _mm256_storeu_ps(g->alb_b + i, acc[9]);
    return 1;
}
#endif

/* Software prefetch of the table entries of the triangles that pixels
 * i..i+n-1 (row-major over the image) show: a resolve starts a new triangle
 * every few pixels (Sibenik at 1024x768: 142K setups for 786K pixels) and
 * each start would otherwise wait for a miss to memory. Issued a fixed
 * distance ahead of the pixel being resolved; changes no result. */
static void rs__prefetch(const rs__resolve_ctx *rc, size_t i, size_t n, uint32_t *last)
{
    const rs_gbuffer *g = rc->g;
    size_t end = (size_t)g->width * g->height;
    if (!rc->table || i >= end) return;
    if (n > end - i) n = end - i;
    for (size_t k = i; k < i + n; k++) {
        uint32_t prim = g->prim[k];
        if (prim == *last || prim == RS_GBUFFER_EMPTY) continue;
        *last = prim;
        const char *e = (const char *)&rc->table[prim];
        __builtin_prefetch(e);
        __builtin_prefetch(e + 64);
    }
}

enum { RS__PREFETCH_AHEAD = 64 }; /* pixels */

static void rs__resolve_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const rs__resolve_ctx *rc = p;
    rs_gbuffer *g = rc->g;
    rs__tri_consts c;
    memset(&c, 0, sizeof c);
    c.prim = RS_GBUFFER_EMPTY;
    size_t row = (size_t)y * g->width;
    uint32_t last = RS_GBUFFER_EMPTY;
    rs__prefetch(rc, row, RS__PREFETCH_AHEAD, &last);
    for (uint32_t x = 0; x < g->width;) {
        rs__prefetch(rc, row + x + RS__PREFETCH_AHEAD, 8, &last);
#ifdef RS__GBUF_X86
        if (rc->simd && x + 8 <= g->width) {
            if (!rs__resolve_group8_avx2(rc, &c, x, y))
                for (uint32_t k = 0; k < 8; k++) rs__resolve_pixel(rc, &c, x + k, y);
            x += 8;
            continue;
        }
#endif
        for (uint32_t k = 0; k < 8 && x < g->width; k++, x++) rs__resolve_pixel(rc, &c, x, y);
    }
    rs__normalize_row(g, rc->scene, rc->cam, rc->sx, rc->sy[y], y);
}

rs_resolve_tri *rs_resolve_table_create(const pf_scene *scene)
{
    size_t n = scene->tri_count ? scene->tri_count : 1;
    rs_resolve_tri *table = aligned_alloc(64, n * sizeof *table);
    if (!table) return NULL;
    memset(table, 0, n * sizeof *table);
    for (uint32_t t = 0; t < scene->tri_count; t++) rs__tri_fill(&table[t], scene, t);
    return table;
}

void rs_resolve_table_destroy(rs_resolve_tri *table) { free(table); }

void rs_gbuffer_resolve(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs)
{
    rs_gbuffer_resolve_simd(g, scene, NULL, cam, jobs, 0);
}

void rs_gbuffer_resolve_simd(rs_gbuffer *g, const pf_scene *scene, const rs_resolve_tri *table, const pf_camera *cam,
                             pf_jobs *jobs, int simd)
{
    rs__resolve_ctx rc = {g, scene, table, cam, g->ray_sx, g->ray_sy, simd};
    /* screen offsets of pixel centres, one more than the image for the
     * neighbour rays; bit-identical to pf_camera_ray_dir's terms */
    float th = tanf(0.5f * cam->yfov), aspect = (float)g->width / (float)g->height;
    for (uint32_t x = 0; x <= g->width; x++) rc.sx[x] = (2.0f * ((float)x + 0.5f) / (float)g->width - 1.0f) * th * aspect;
    for (uint32_t y = 0; y <= g->height; y++) rc.sy[y] = (1.0f - 2.0f * ((float)y + 0.5f) / (float)g->height) * th;
    pf_jobs_parallel_for(jobs, rs__resolve_row, &rc, g->height, 4);
}
