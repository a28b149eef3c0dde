/* rs_gbuffer: G-buffer planes (see rs_gbuffer.h). */
#include "rs_gbuffer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    memset(g, 0, sizeof *g);
}

typedef struct rs__resolve_ctx {
    rs_gbuffer *g;
    const pf_scene *scene;
    const pf_camera *cam;
    float th, aspect; /* tan(yfov/2) and width/height, as pf_camera_ray_dir computes them */
} rs__resolve_ctx;

/* pf_camera_ray_dir with its per-frame constants hoisted (same operations,
 * same bits). */
static pf_vec3 rs__ray_dir(const rs__resolve_ctx *rc, float x, float y)
{
    const pf_camera *cam = rc->cam;
    float sx = (2.0f * x / (float)rc->g->width - 1.0f) * rc->th * rc->aspect;
    float sy = (1.0f - 2.0f * y / (float)rc->g->height) * rc->th;
    return pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, sx), pf_v3_scale(cam->up, sy)));
}

/* Barycentrics (u, v) and t of the ray o + t d on the plane of (p0, p1, p2)
 * (Moller-Trumbore without the inside test). Returns 0 for a ray parallel
 * to the plane. */
static int rs__plane_bary(pf_vec3 o, pf_vec3 d, pf_vec3 p0, pf_vec3 e1, pf_vec3 e2, float *u, float *v, float *t)
{
    pf_vec3 pv = pf_v3_cross(d, e2);
    float det = pf_v3_dot(e1, pv);
    if (det == 0.0f || !isfinite(det)) return 0;
    float inv = 1.0f / det;
    pf_vec3 tv = pf_v3_sub(o, p0);
    pf_vec3 qv = pf_v3_cross(tv, e1);
    *u = pf_v3_dot(tv, pv) * inv;
    *v = pf_v3_dot(d, qv) * inv;
    *t = pf_v3_dot(e2, qv) * inv;
    return 1;
}

static void rs__resolve_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const rs__resolve_ctx *rc = p;
    rs_gbuffer *g = rc->g;
    const pf_scene *s = rc->scene;
    const pf_camera *cam = rc->cam;
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
        const uint32_t *tri = &s->indices[3 * prim];
        pf_vec3 p0 = s->positions[tri[0]];
        pf_vec3 e1 = pf_v3_sub(s->positions[tri[1]], p0), e2 = pf_v3_sub(s->positions[tri[2]], p0);
        pf_vec3 d = rs__ray_dir(rc, (float)x + 0.5f, (float)y + 0.5f);
        float u = 0.0f, v = 0.0f, t = 0.0f;
        rs__plane_bary(cam->eye, d, p0, e1, e2, &u, &v, &t);
        /* uv footprint from the neighbouring pixel centres' rays on the same plane */
        float lod = 0.0f;
        if (s->materials[s->tri_material[prim]].base_color_texture >= 0) {
            float ux, vx, tx, uy, vy, ty;
            pf_vec3 dx = rs__ray_dir(rc, (float)x + 1.5f, (float)y + 0.5f);
            pf_vec3 dy = rs__ray_dir(rc, (float)x + 0.5f, (float)y + 1.5f);
            if (rs__plane_bary(cam->eye, dx, p0, e1, e2, &ux, &vx, &tx) &&
                rs__plane_bary(cam->eye, dy, p0, e1, e2, &uy, &vy, &ty)) {
                pf_vec2 a = s->uvs[tri[0]], b = s->uvs[tri[1]], c = s->uvs[tri[2]];
                float du1 = b.x - a.x, du2 = c.x - a.x, dv1 = b.y - a.y, dv2 = c.y - a.y;
                lod = pf_material_lod(s, s->tri_material[prim], du1 * (ux - u) + du2 * (vx - v),
                                      dv1 * (ux - u) + dv2 * (vx - v), du1 * (uy - u) + du2 * (vy - v),
                                      dv1 * (uy - u) + dv2 * (vy - v));
            }
        }
        u = u < 0.0f ? 0.0f : (u > 1.0f ? 1.0f : u);
        v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
        if (u + v > 1.0f) {
            float sum = u + v;
            u /= sum;
            v /= sum;
        }
        pf_surface sf;
        pf_scene_surface(s, prim, u, v, lod, &sf);
        pf_vec3 ns = sf.ns;
        if (pf_v3_dot(sf.ng, d) > 0.0f) ns = pf_v3_scale(ns, -1.0f); /* two-sided shading */
        /* view depth of the interpolated position (t of the plane hit, but
         * from the clamped point so depth and position agree) */
        g->depth[i] = pf_v3_dot(pf_v3_sub(sf.p, cam->eye), cam->forward);
        g->pos_x[i] = sf.p.x;
        g->pos_y[i] = sf.p.y;
        g->pos_z[i] = sf.p.z;
        g->nrm_x[i] = ns.x;
        g->nrm_y[i] = ns.y;
        g->nrm_z[i] = ns.z;
        g->alb_r[i] = sf.albedo[0];
        g->alb_g[i] = sf.albedo[1];
        g->alb_b[i] = sf.albedo[2];
    }
}

void rs_gbuffer_resolve(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs)
{
    rs__resolve_ctx rc = {g, scene, cam, tanf(0.5f * cam->yfov), (float)g->width / (float)g->height};
    pf_jobs_parallel_for(jobs, rs__resolve_row, &rc, g->height, 4);
}
