/* rs_gbuffer: G-buffer planes and the deferred attribute resolve (see
 * rs_gbuffer.h), scalar and 8 pixels at a time with AVX2. */
#include "rs_gbuffer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

pf_result rs_gbuffer_init(rs_gbuffer *g, uint32_t width, uint32_t height, pf_error *err)
{
    memset(g, 0, sizeof *g);
    size_t n = (size_t)width * height;
    g->width = width;
    g->height = height;
    float **planes[] = {&g->depth, &g->pos_x, &g->pos_y, &g->pos_z, &g->nrm_x,
                        &g->nrm_y, &g->nrm_z, &g->alb_r, &g->alb_g, &g->alb_b};
    for (size_t i = 0; i < sizeof planes / sizeof planes[0]; i++)
        if (!(*planes[i] = calloc(n ? n : 1, sizeof(float)))) goto oom;
    if (!(g->prim = calloc(n ? n : 1, sizeof(uint32_t)))) goto oom;
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

typedef struct rs__resolve_ctx {
    rs_gbuffer *g;
    const pf_scene *scene;
    const pf_camera *cam;
    float th, aspect; /* tan(yfov/2) and width/height, as pf_camera_ray_dir computes them */
    float *sx, *sy;   /* per column / row: the screen offsets of pixel centres (+1 for the neighbour) */
    int simd;         /* take rs__resolve8_avx2 for runs of 8 pixels on one untextured triangle */
} rs__resolve_ctx;


/* Per-triangle constants of the resolve. With the ray origin o fixed (the
 * eye), Moller-Trumbore's terms that do not involve the direction d are
 * constant per triangle: with tv = o - p0, e1 = p1 - p0, e2 = p2 - p0,
 *   det = d . (e2 x e1),  u = d . (e2 x tv) / det,  v = d . (tv x e1) / det,
 * so a pixel costs three dot products and a division. Pixels come in runs
 * that share a triangle, so the constants are cached across a run. */
typedef struct rs__tri_consts {
    uint32_t prim;
    pf_vec3 n_det, n_u, n_v;   /* e2 x e1, e2 x tv, tv x e1 */
    pf_vec3 p0, e1, e2;
    pf_vec3 ng;                /* unit geometric normal */
    pf_vec3 n0, n1, n2;        /* vertex normals */
    pf_vec2 uv0, uv1, uv2;
    uint32_t material;
    int textured;
} rs__tri_consts;

static void rs__tri_setup(rs__tri_consts *c, const pf_scene *s, pf_vec3 eye, uint32_t prim)
{
    const uint32_t *tri = &s->indices[3 * prim];
    c->prim = prim;
    c->p0 = s->positions[tri[0]];
    c->e1 = pf_v3_sub(s->positions[tri[1]], c->p0);
    c->e2 = pf_v3_sub(s->positions[tri[2]], c->p0);
    pf_vec3 tv = pf_v3_sub(eye, c->p0);
    c->n_det = pf_v3_cross(c->e2, c->e1);
    c->n_u = pf_v3_cross(c->e2, tv);
    c->n_v = pf_v3_cross(tv, c->e1);
    c->ng = pf_v3_normalize(pf_v3_cross(c->e1, c->e2));
    c->n0 = s->normals[tri[0]];
    c->n1 = s->normals[tri[1]];
    c->n2 = s->normals[tri[2]];
    c->uv0 = s->uvs[tri[0]];
    c->uv1 = s->uvs[tri[1]];
    c->uv2 = s->uvs[tri[2]];
    c->material = s->tri_material[prim];
    c->textured = s->materials[c->material].base_color_texture >= 0;
}

/* Unclamped barycentrics of direction d on the triangle's plane. */
static int rs__bary(const rs__tri_consts *c, pf_vec3 d, float *u, float *v)
{
    float det = pf_v3_dot(d, c->n_det);
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
 * interpolated normal vanishes gets the camera-facing geometric normal, as
 * pf_scene_surface does. */
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
        _mm_storeu_ps(nx + x, _mm_mul_ps(a, inv));
        _mm_storeu_ps(ny + x, _mm_mul_ps(b, inv));
        _mm_storeu_ps(nz + x, _mm_mul_ps(c, inv));
    }
#endif
    for (; x < g->width; x++) {
        pf_vec3 n = pf_v3_normalize(pf_v3(nx[x], ny[x], nz[x]));
        nx[x] = n.x, ny[x] = n.y, nz[x] = n.z;
    }
    for (x = 0; x < g->width; x++) {
        size_t i = (size_t)y * g->width + x;
        if (g->prim[i] == RS_GBUFFER_EMPTY || nx[x] != 0.0f || ny[x] != 0.0f || nz[x] != 0.0f) continue;
        pf_vec3 ng = pf_scene_face_normal(s, g->prim[i]);
        pf_vec3 d = pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, sx[x]), pf_v3_scale(cam->up, sy)));
        if (pf_v3_dot(ng, d) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
        nx[x] = ng.x, ny[x] = ng.y, nz[x] = ng.z;
    }
}

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define RS__GBUF_X86 1
/* rs__resolve_row's per-pixel work for 8 pixels x..x+7 of row y that all show
 * the untextured triangle c: the same operations in the same order lane by
 * lane (ray direction, rs__bary, clamping and renormalising the
 * barycentrics, position, the camera-facing interpolated normal, view
 * depth, the material's base colour), so the bits are the scalar loop's. */
__attribute__((target("avx2"))) static void rs__resolve8_avx2(const rs__resolve_ctx *rc, const rs__tri_consts *c,
                                                              uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    const pf_camera *cam = rc->cam;
    size_t i = (size_t)y * g->width + x;
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 sx = _mm256_loadu_ps(rc->sx + x), sy = _mm256_set1_ps(rc->sy[y]);
#define RS__DIR(k) _mm256_add_ps(_mm256_set1_ps(cam->forward.k), _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(cam->right.k), sx), \
                                                                         _mm256_mul_ps(_mm256_set1_ps(cam->up.k), sy)))
    __m256 dx = RS__DIR(x), dy = RS__DIR(y), dz = RS__DIR(z);
#undef RS__DIR
#define RS__DOT(v)                                                                                                     \
    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, _mm256_set1_ps((v).x)), _mm256_mul_ps(dy, _mm256_set1_ps((v).y))),   \
                  _mm256_mul_ps(dz, _mm256_set1_ps((v).z)))
    /* rs__bary: u = v = 0 where det == 0 */
    __m256 det = RS__DOT(c->n_det);
    __m256 inv = _mm256_div_ps(one, det), has = _mm256_cmp_ps(det, zero, _CMP_NEQ_UQ);
    __m256 u = _mm256_and_ps(has, _mm256_mul_ps(RS__DOT(c->n_u), inv));
    __m256 v = _mm256_and_ps(has, _mm256_mul_ps(RS__DOT(c->n_v), inv));
    __m256 facing = _mm256_cmp_ps(RS__DOT(c->ng), zero, _CMP_GT_OQ);
#undef RS__DOT
    /* x < 0 ? 0 : (x > 1 ? 1 : x) */
    u = _mm256_blendv_ps(_mm256_blendv_ps(u, one, _mm256_cmp_ps(u, one, _CMP_GT_OQ)), zero,
                         _mm256_cmp_ps(u, zero, _CMP_LT_OQ));
    v = _mm256_blendv_ps(_mm256_blendv_ps(v, one, _mm256_cmp_ps(v, one, _CMP_GT_OQ)), zero,
                         _mm256_cmp_ps(v, zero, _CMP_LT_OQ));
    __m256 sum = _mm256_add_ps(u, v), over = _mm256_cmp_ps(sum, one, _CMP_GT_OQ);
    u = _mm256_blendv_ps(u, _mm256_div_ps(u, sum), over);
    v = _mm256_blendv_ps(v, _mm256_div_ps(v, sum), over);
    __m256 w = _mm256_sub_ps(_mm256_sub_ps(one, u), v);
#define RS__POS(k)                                                                                                     \
    _mm256_add_ps(_mm256_set1_ps(c->p0.k), _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(c->e1.k), u),                    \
                                                         _mm256_mul_ps(_mm256_set1_ps(c->e2.k), v)))
    __m256 px = RS__POS(x), py = RS__POS(y), pz = RS__POS(z);
#undef RS__POS
    /* ns, times -1 (a multiplication, as pf_v3_scale does) where the
     * triangle faces away from the camera */
    __m256 flip = _mm256_blendv_ps(one, _mm256_set1_ps(-1.0f), facing);
#define RS__NRM(k)                                                                                                     \
    _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(c->n0.k), w),                               \
                                              _mm256_mul_ps(_mm256_set1_ps(c->n1.k), u)),                              \
                                _mm256_mul_ps(_mm256_set1_ps(c->n2.k), v)),                                            \
                  flip)
    __m256 nx = RS__NRM(x), ny = RS__NRM(y), nz = RS__NRM(z);
#undef RS__NRM
    /* where no flip happens the product is by 1: exact, the same bits */
    __m256 depth = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(px, _mm256_set1_ps(cam->eye.x)), _mm256_set1_ps(cam->forward.x)),
                      _mm256_mul_ps(_mm256_sub_ps(py, _mm256_set1_ps(cam->eye.y)), _mm256_set1_ps(cam->forward.y))),
        _mm256_mul_ps(_mm256_sub_ps(pz, _mm256_set1_ps(cam->eye.z)), _mm256_set1_ps(cam->forward.z)));
    const float *albedo = rc->scene->materials[c->material].base_color;
    _mm256_storeu_ps(g->depth + i, depth);
    _mm256_storeu_ps(g->pos_x + i, px);
    _mm256_storeu_ps(g->pos_y + i, py);
    _mm256_storeu_ps(g->pos_z + i, pz);
    _mm256_storeu_ps(g->nrm_x + i, nx);
    _mm256_storeu_ps(g->nrm_y + i, ny);
    _mm256_storeu_ps(g->nrm_z + i, nz);
    _mm256_storeu_ps(g->alb_r + i, _mm256_set1_ps(albedo[0]));
    _mm256_storeu_ps(g->alb_g + i, _mm256_set1_ps(albedo[1]));
    _mm256_storeu_ps(g->alb_b + i, _mm256_set1_ps(albedo[2]));
}

/* Whether pixels i..i+7 all show triangle prim. */
__attribute__((target("avx2"))) static int rs__run8_avx2(const uint32_t *prim_row, uint32_t prim)
{
    __m256i p = _mm256_loadu_si256((const __m256i *)prim_row);
    __m256i eq = _mm256_cmpeq_epi32(p, _mm256_set1_epi32((int)prim));
    return _mm256_movemask_epi8(eq) == -1;
}
#endif

static void rs__resolve_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const rs__resolve_ctx *rc = p;
    rs_gbuffer *g = rc->g;
    const pf_scene *s = rc->scene;
    const pf_camera *cam = rc->cam;
    rs__tri_consts c;
    memset(&c, 0, sizeof c);
    c.prim = RS_GBUFFER_EMPTY;
    for (uint32_t x = 0; x < g->width; x++) {
        size_t i = (size_t)y * g->width + x;
        uint32_t prim = g->prim[i];
        if (prim == RS_GBUFFER_EMPTY) {
            g->depth[i] = INFINITY;
            g->pos_x[i] = g->pos_y[i] = g->pos_z[i] = 0.0f;
            g->nrm_x[i] = g->nrm_y[i] = g->nrm_z[i] = 0.0f;
            g->alb_r[i] = g->alb_g[i] = g->alb_b[i] = 0.0f;
            continue;
        }
        if (prim != c.prim) rs__tri_setup(&c, s, cam->eye, prim);
#ifdef RS__GBUF_X86
        if (rc->simd && !c.textured && x + 8 <= g->width && rs__run8_avx2(g->prim + i, prim)) {
            rs__resolve8_avx2(rc, &c, x, y);
            x += 7;
            continue;
        }
#endif
        /* pf_camera_ray_dir's expression, its per-column and per-row factors
         * taken from the tables (same formulas, same bits) */
        pf_vec3 d = pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, rc->sx[x]), pf_v3_scale(cam->up, rc->sy[y])));
        float u = 0.0f, v = 0.0f;
        rs__bary(&c, d, &u, &v);
        /* uv footprint from the neighbouring pixel centres' rays on the same plane */
        float lod = 0.0f;
        if (c.textured) {
            float ux, vx, uy, vy;
            pf_vec3 dx = pf_v3_add(cam->forward,
                                   pf_v3_add(pf_v3_scale(cam->right, rc->sx[x + 1]), pf_v3_scale(cam->up, rc->sy[y])));
            pf_vec3 dy = pf_v3_add(cam->forward,
                                   pf_v3_add(pf_v3_scale(cam->right, rc->sx[x]), pf_v3_scale(cam->up, rc->sy[y + 1])));
            if (rs__bary(&c, dx, &ux, &vx) && rs__bary(&c, dy, &uy, &vy)) {
                float du1 = c.uv1.x - c.uv0.x, du2 = c.uv2.x - c.uv0.x, dv1 = c.uv1.y - c.uv0.y,
                      dv2 = c.uv2.y - c.uv0.y;
                lod = pf_material_lod(s, c.material, du1 * (ux - u) + du2 * (vx - v), dv1 * (ux - u) + dv2 * (vx - v),
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
        pf_vec3 pos = pf_v3_add(c.p0, pf_v3_add(pf_v3_scale(c.e1, u), pf_v3_scale(c.e2, v)));
        /* the interpolated normal, turned to face the camera (two-sided
         * shading); normalised for the whole row by rs__normalize_row */
        pf_vec3 ns = pf_v3_add(pf_v3_add(pf_v3_scale(c.n0, w), pf_v3_scale(c.n1, u)), pf_v3_scale(c.n2, v));
        if (pf_v3_dot(c.ng, d) > 0.0f) ns = pf_v3_scale(ns, -1.0f);
        float albedo[4];
        if (c.textured) {
            pf_vec2 uv = {w * c.uv0.x + u * c.uv1.x + v * c.uv2.x, w * c.uv0.y + u * c.uv1.y + v * c.uv2.y};
            pf_material_sample(s, c.material, uv, lod, albedo);
        } else {
            memcpy(albedo, s->materials[c.material].base_color, sizeof albedo); /* what pf_material_sample returns */
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
    rs__normalize_row(g, s, cam, rc->sx, rc->sy[y], y);
}

void rs_gbuffer_resolve(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs)
{
    rs_gbuffer_resolve_simd(g, scene, cam, jobs, 0);
}

void rs_gbuffer_resolve_simd(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs, int simd)
{
    rs__resolve_ctx rc = {g, scene, cam, tanf(0.5f * cam->yfov), (float)g->width / (float)g->height, NULL, NULL, simd};
    /* screen offsets of pixel centres, one more than the image for the
     * neighbour rays; bit-identical to rs__ray_dir's terms */
    rc.sx = g->ray_sx;
    rc.sy = g->ray_sy;
    for (uint32_t x = 0; x <= g->width; x++)
        rc.sx[x] = (2.0f * ((float)x + 0.5f) / (float)g->width - 1.0f) * rc.th * rc.aspect;
    for (uint32_t y = 0; y <= g->height; y++) rc.sy[y] = (1.0f - 2.0f * ((float)y + 0.5f) / (float)g->height) * rc.th;
    pf_jobs_parallel_for(jobs, rs__resolve_row, &rc, g->height, 4);
}
