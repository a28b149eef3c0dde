/* rs_gbuffer: G-buffer planes and the deferred attribute resolve (see
 * rs_gbuffer.h), scalar and 8 pixels at a time with AVX2. */
#include "rs_gbuffer.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "rs_gbuffer_kernels.h"
#include "simd.h" /* the baseline vocabulary (SSE2 on x86-64): rs__normalize_row */

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

void rs__gbuf_tri_setup(rs__tri_consts *c, const rs__resolve_ctx *rc, uint32_t prim)
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

/* A covered pixel whose normal came out zero (the interpolated normal
 * vanished) gets the camera-facing geometric normal, as pf_scene_surface
 * does. */
void rs__gbuf_normal_fallback(const rs__resolve_ctx *rc, uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    const pf_camera *cam = rc->cam;
    size_t i = (size_t)y * g->width + x;
    if (g->prim[i] == RS_GBUFFER_EMPTY || g->nrm_x[i] != 0.0f || g->nrm_y[i] != 0.0f || g->nrm_z[i] != 0.0f) return;
    pf_vec3 ng = pf_scene_face_normal(rc->scene, g->prim[i]);
    pf_vec3 d =
        pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, rc->sx[x]), pf_v3_scale(cam->up, rc->sy[y])));
    if (pf_v3_dot(ng, d) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
    g->nrm_x[i] = ng.x, g->nrm_y[i] = ng.y, g->nrm_z[i] = ng.z;
}

void rs__gbuf_normalize_pixel(const rs__resolve_ctx *rc, uint32_t x, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    size_t i = (size_t)y * g->width + x;
    pf_vec3 n = pf_v3_normalize(pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]));
    g->nrm_x[i] = n.x, g->nrm_y[i] = n.y, g->nrm_z[i] = n.z;
    rs__gbuf_normal_fallback(rc, x, y);
}

/* Normalises the row's normals as rs__gbuf_normalize_pixel does, SIMD_W at
 * a time with the baseline vocabulary (four with SSE2) whose sqrt/div round
 * exactly like the scalar ones, so the bits are the scalar function's; taken
 * out of the scalar path's per-pixel loop because its sqrt -> divide
 * latency chain dominated it. The SIMD loop flags vanished normals itself,
 * so the row is read once. */
static void rs__normalize_row(const rs__resolve_ctx *rc, uint32_t y)
{
    rs_gbuffer *g = rc->g;
    float *nx = g->nrm_x + (size_t)y * g->width, *ny = g->nrm_y + (size_t)y * g->width;
    float *nz = g->nrm_z + (size_t)y * g->width;
    uint32_t x = 0;
    const simd_f zero = simd_zero_f(), one = simd_set1_f(1.0f);
    for (; x + SIMD_W <= g->width; x += SIMD_W) {
        simd_f a = simd_loadu_f(nx + x), b = simd_loadu_f(ny + x), c = simd_loadu_f(nz + x);
        simd_f l = simd_sqrt_f(simd_add_f(simd_add_f(simd_mul_f(a, a), simd_mul_f(b, b)), simd_mul_f(c, c)));
        simd_f inv = simd_select_f(simd_gt_f(l, zero), simd_div_f(one, l), zero);
        a = simd_mul_f(a, inv), b = simd_mul_f(b, inv), c = simd_mul_f(c, inv);
        simd_storeu_f(nx + x, a);
        simd_storeu_f(ny + x, b);
        simd_storeu_f(nz + x, c);
        simd_mask vanished = simd_mask_and(simd_mask_and(simd_eq_f(a, zero), simd_eq_f(b, zero)), simd_eq_f(c, zero));
        for (uint32_t m = simd_mask_bits(vanished); m; m &= m - 1)
            rs__gbuf_normal_fallback(rc, x + (uint32_t)__builtin_ctz(m), y);
    }
    for (; x < g->width; x++) rs__gbuf_normalize_pixel(rc, x, y);
}

/* One pixel (x, y) of the resolve, scalar; the reference for the SIMD path. */
void rs__gbuf_resolve_pixel(const rs__resolve_ctx *rc, rs__tri_consts *c, uint32_t x, uint32_t y)
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
    if (prim != c->prim) rs__gbuf_tri_setup(c, rc, prim);
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
     * shading); normalised afterwards (rs__gbuf_normalize_pixel) */
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

/* Software prefetch of the table entries of the triangles that pixels
 * i..i+n-1 of a row show: a resolve starts a new triangle every few pixels
 * (Sibenik at 1024x768: 142K setups for 786K pixels) and each start would
 * otherwise wait for a miss to memory. Issued a fixed distance ahead of the
 * pixels being resolved; changes no result. */
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

/* The scalar path: row y pixel by pixel, then its normals. */
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
    for (uint32_t x = 0; x < g->width; x++) {
        if (x % 8 == 0) rs__prefetch(rc, row + x + RS__PREFETCH_AHEAD, 8, &last);
        rs__gbuf_resolve_pixel(rc, &c, x, y);
    }
    rs__normalize_row(rc, y);
}

/* The SIMD paths: band b (rows of blocks, kern->rows pixel rows) block by
 * block; blocks the kernel leaves (textured triangles, many triangles, the
 * image's right and bottom edge) pixel by pixel. */
static void rs__resolve_band(void *p, uint32_t b, uint32_t worker)
{
    (void)worker;
    const rs__resolve_ctx *rc = p;
    rs_gbuffer *g = rc->g;
    const uint32_t rows = rc->kern->rows, y0 = b * rows;
    rs__tri_consts c;
    memset(&c, 0, sizeof c);
    c.prim = RS_GBUFFER_EMPTY;
    uint32_t last[4] = {RS_GBUFFER_EMPTY, RS_GBUFFER_EMPTY, RS_GBUFFER_EMPTY, RS_GBUFFER_EMPTY};
    for (uint32_t r = 0; r < rows && y0 + r < g->height; r++)
        rs__prefetch(rc, (size_t)(y0 + r) * g->width, RS__PREFETCH_AHEAD, &last[r]);
    for (uint32_t x = 0; x < g->width; x += 4) {
        /* the table entries the block RS__PREFETCH_AHEAD pixels ahead shows:
         * its rows' first pixels (a block rarely shows a triangle that none
         * of them shows, and a miss there only costs time) */
        if (rc->table && x + RS__PREFETCH_AHEAD < g->width)
            for (uint32_t r = 0; r < rows && y0 + r < g->height; r++) {
                uint32_t prim = g->prim[(size_t)(y0 + r) * g->width + x + RS__PREFETCH_AHEAD];
                if (prim == last[r] || prim == RS_GBUFFER_EMPTY) continue;
                last[r] = prim;
                __builtin_prefetch(&rc->table[prim]);
                __builtin_prefetch((const char *)&rc->table[prim] + 64);
            }
        if (x + 4 <= g->width && y0 + rows <= g->height && rc->kern->group(rc, &c, x, y0)) continue;
        for (uint32_t y = y0; y < y0 + rows && y < g->height; y++)
            for (uint32_t xx = x; xx < x + 4 && xx < g->width; xx++) {
                rs__gbuf_resolve_pixel(rc, &c, xx, y);
                rs__gbuf_normalize_pixel(rc, xx, y);
            }
    }
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

void rs_resolve_table_update(rs_resolve_tri *table, const pf_scene *scene, uint32_t first, uint32_t count)
{
    for (uint32_t t = first; t < first + count && t < scene->tri_count; t++) rs__tri_fill(&table[t], scene, t);
}

void rs_resolve_table_destroy(rs_resolve_tri *table) { free(table); }

void rs_gbuffer_resolve(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs)
{
    rs_gbuffer_resolve_simd(g, scene, NULL, cam, jobs, 0);
}

void rs_gbuffer_resolve_simd(rs_gbuffer *g, const pf_scene *scene, const rs_resolve_tri *table, const pf_camera *cam,
                             pf_jobs *jobs, int simd)
{
    const rs_gbuffer_kernels *kern = NULL; /* RS_SIMD_SCALAR: pixel by pixel, the reference */
#if SIMD_X86
    if (simd == RS_SIMD_AVX512) kern = &rs_gbuffer_kernels_avx512;
    if (simd == RS_SIMD_AVX2) kern = &rs_gbuffer_kernels_avx2;
#endif
    rs__resolve_ctx rc = {g, scene, table, cam, g->ray_sx, g->ray_sy, kern};
    /* screen offsets of pixel centres, one more than the image for the
     * neighbour rays; bit-identical to pf_camera_ray_dir's terms */
    float th = tanf(0.5f * cam->yfov), aspect = (float)g->width / (float)g->height;
    for (uint32_t x = 0; x <= g->width; x++) rc.sx[x] = (2.0f * ((float)x + 0.5f) / (float)g->width - 1.0f) * th * aspect;
    for (uint32_t y = 0; y <= g->height; y++) rc.sy[y] = (1.0f - 2.0f * ((float)y + 0.5f) / (float)g->height) * th;
    if (kern)
        pf_jobs_parallel_for(jobs, rs__resolve_band, &rc, (g->height + kern->rows - 1) / kern->rows, 1);
    else
        pf_jobs_parallel_for(jobs, rs__resolve_row, &rc, g->height, 4);
}
