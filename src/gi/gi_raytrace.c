/* gi_raytrace: the ray-traced reference stages of a frame: the G-buffer from
 * Embree primary rays and direct light with Embree shadow rays. This is the
 * `--raytrace` path: the reference the rasterized G-buffer and the shadow
 * maps are tested against. Area lights (emissive triangles) add stratified
 * emitter samples per pixel with shadow rays (gi_frame.h "Area lights").
 *
 * Parallel structure: one job item per image row; every item writes only its
 * row of every buffer, and rays go to Embree in 8-pixel packets (the fixed
 * query width of pf_rt), so the output is the same for any thread count. */
#include <string.h>

#include "gi_frame.h"
#include "gi_light.h"
#include "pf_random.h"

/* The ray-traced G-buffer's inputs and output, explicitly (the stage
 * table's writes: VISIBILITY and GBUFFER). */
typedef struct gi__gbuffer_io {
    const pf_rt *rt;
    const pf_camera *camera;
    uint32_t width, height;
    float jx, jy;     /* the anti-aliasing sample's offset (gi_aa.h; (0, 0): the pixel centres) */
    rs_gbuffer *gbuf; /* VISIBILITY, GBUFFER */
} gi__gbuffer_io;

static void gi__gbuffer_row(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__gbuffer_io *io = ctx;
    rs_gbuffer *g = io->gbuf;
    const uint32_t width = io->width;
    for (uint32_t x0 = 0; x0 < width; x0 += PF_RT_WIDTH) {
        uint32_t n = width - x0 < PF_RT_WIDTH ? width - x0 : PF_RT_WIDTH;
        pf_ray rays[PF_RT_WIDTH];
        pf_hit hits[PF_RT_WIDTH];
        for (uint32_t i = 0; i < n; i++)
            rays[i] = gi_camera_ray_at(io->camera, width, io->height, x0 + i, y, io->jx, io->jy);
        pf_rt_intersect(io->rt, rays, hits, n);
        for (uint32_t i = 0; i < n; i++) {
            size_t p = (size_t)y * width + x0 + i;
            if (hits[i].prim == PF_RT_MISS) {
                g->depth[p] = INFINITY;
                g->prim[p] = RS_GBUFFER_EMPTY;
                g->pos_x[p] = g->pos_y[p] = g->pos_z[p] = 0.0f;
                g->nrm_x[p] = g->nrm_y[p] = g->nrm_z[p] = 0.0f;
                g->alb_r[p] = g->alb_g[p] = g->alb_b[p] = 0.0f;
                continue;
            }
            pf_surface s;
            pf_rt_surface(io->rt, &hits[i], 0.0f, &s);
            /* Two-sided shading: turn the normal to face the camera. */
            pf_vec3 ns = s.ns;
            if (pf_v3_dot(s.ng, rays[i].dir) > 0.0f) ns = pf_v3_scale(ns, -1.0f);
            g->depth[p] = hits[i].t; /* |forward| = 1, so t is view depth */
            g->prim[p] = hits[i].prim;
            g->pos_x[p] = s.p.x;
            g->pos_y[p] = s.p.y;
            g->pos_z[p] = s.p.z;
            g->nrm_x[p] = ns.x;
            g->nrm_y[p] = ns.y;
            g->nrm_z[p] = ns.z;
            g->alb_r[p] = s.albedo[0];
            g->alb_g[p] = s.albedo[1];
            g->alb_b[p] = s.albedo[2];
        }
    }
}

void gi_stage_gbuffer_raytrace(gi_frame *f)
{
    const gi__gbuffer_io io = {f->rt, &f->camera, f->width, f->height, f->aa.jx, f->aa.jy, &f->gbuf};
    pf_jobs_parallel_for(f->jobs, gi__gbuffer_row, (void *)&io, f->height, 1);
}

/* The ray-traced direct light's inputs and output, explicitly (the stage
 * table's reads: GBUFFER; writes: DIRECT). */
typedef struct gi__direct_rt_io {
    const pf_scene *scene;   /* the punctual lights, face normals */
    const pf_rt *rt;
    const gi_area_lights *area; /* the emissive triangles */
    uint32_t strata;         /* area samples per side */
    uint32_t aa_index;       /* the anti-aliasing sample's pattern index (gi_aa.h) */
    const rs_gbuffer *gbuf;  /* GBUFFER */
    uint32_t width;
    float *direct;           /* DIRECT */
} gi__direct_rt_io;

/* Irradiance at a visible point from the area lights: S = strata^2
 * stratified emitter samples (see gi_frame.h), shadow rays in packets of 8,
 * summed in sample order. Random numbers: pf_random(pixel, sample,
 * GI__AREA_STREAM + j, dim), a hash of stable ids only; j is the
 * anti-aliasing sample's pattern index (gi_aa.h), 0 for the pixel centre, so
 * the samples of one pixel draw other emitter points. */
#define GI__AREA_STREAM 0x41524541u /* "AREA": a vertex index no path reaches (nor does it plus j < 2^16) */
static pf_vec3 gi__area_irradiance_rays(const gi__direct_rt_io *io, uint32_t pixel, pf_vec3 pos, pf_vec3 nrm,
                                        pf_vec3 ng)
{
    uint32_t sd = io->strata, S = sd * sd;
    const uint32_t stream = GI__AREA_STREAM + io->aa_index;
    /* per-pixel rotation of the (u1, u2) points (Cranley-Patterson) */
    float r1 = pf_random(pixel, 0, stream, 1), r2 = pf_random(pixel, 0, stream, 2);
    pf_vec3 sum = pf_v3(0, 0, 0);
    for (uint32_t k0 = 0; k0 < S; k0 += PF_RT_WIDTH) {
        uint32_t n = S - k0 < PF_RT_WIDTH ? S - k0 : PF_RT_WIDTH, m = 0;
        pf_ray rays[PF_RT_WIDTH];
        pf_vec3 irr[PF_RT_WIDTH];
        for (uint32_t i = 0; i < n; i++) {
            uint32_t k = k0 + i;
            double u0 = ((double)k + pf_random(pixel, k, stream, 0)) / S;
            float u1 = (float)gi_halton(k, 2) + r1, u2 = (float)gi_halton(k, 3) + r2;
            u1 -= u1 >= 1.0f ? 1.0f : 0.0f;
            u2 -= u2 >= 1.0f ? 1.0f : 0.0f;
            gi_area_sample as;
            gi_area_sample_point(io->area, u0, fminf(u1, 0x1.fffffep-1f), fminf(u2, 0x1.fffffep-1f), &as);
            gi_light_sample ls;
            if (!gi_area_sample_irradiance(&as, pos, nrm, &ls.irradiance, &ls.wi, &ls.distance)) continue;
            irr[m] = ls.irradiance;
            rays[m++] = gi_light_shadow_ray(&ls, pos, ng);
        }
        if (m == 0) continue;
        uint8_t occ[PF_RT_WIDTH];
        pf_rt_occluded(io->rt, rays, occ, m);
        for (uint32_t j = 0; j < m; j++)
            if (!occ[j]) sum = pf_v3_add(sum, irr[j]);
    }
    return pf_v3_scale(sum, 1.0f / (float)S);
}

/* Direct light of one row: for each light, an 8-wide packet of shadow rays
 * from the visible points towards the light; radiance = albedo/pi * sum E. */
static void gi__direct_row(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__direct_rt_io *io = ctx;
    const rs_gbuffer *g = io->gbuf;
    const pf_scene *s = io->scene;
    const uint32_t width = io->width;
    float *out = io->direct + (size_t)y * width * 3;
    memset(out, 0, (size_t)width * 3 * sizeof(float));
    for (uint32_t x0 = 0; x0 < width; x0 += PF_RT_WIDTH) {
        uint32_t n = width - x0 < PF_RT_WIDTH ? width - x0 : PF_RT_WIDTH;
        for (uint32_t l = 0; l < s->light_count; l++) {
            pf_ray rays[PF_RT_WIDTH];
            gi_light_sample ls[PF_RT_WIDTH];
            uint32_t pix[PF_RT_WIDTH], m = 0;
            for (uint32_t i = 0; i < n; i++) {
                size_t p = (size_t)y * width + x0 + i;
                if (g->prim[p] == RS_GBUFFER_EMPTY) continue;
                pf_vec3 pos = pf_v3(g->pos_x[p], g->pos_y[p], g->pos_z[p]);
                pf_vec3 nrm = pf_v3(g->nrm_x[p], g->nrm_y[p], g->nrm_z[p]);
                if (!gi_light_irradiance(&s->lights[l], pos, nrm, &ls[m])) continue;
                pf_vec3 ng = pf_scene_face_normal(s, g->prim[p]);
                rays[m] = gi_light_shadow_ray(&ls[m], pos, ng);
                pix[m] = x0 + i;
                m++;
            }
            if (m == 0) continue;
            uint8_t occ[PF_RT_WIDTH];
            pf_rt_occluded(io->rt, rays, occ, m);
            for (uint32_t k = 0; k < m; k++) {
                if (occ[k]) continue;
                float *o = out + 3 * pix[k];
                o[0] += ls[k].irradiance.x;
                o[1] += ls[k].irradiance.y;
                o[2] += ls[k].irradiance.z;
            }
        }
        if (io->area->count > 0)
            for (uint32_t i = 0; i < n; i++) {
                size_t p = (size_t)y * width + x0 + i;
                if (g->prim[p] == RS_GBUFFER_EMPTY) continue;
                pf_vec3 e = gi__area_irradiance_rays(io, (uint32_t)p, pf_v3(g->pos_x[p], g->pos_y[p], g->pos_z[p]),
                                                     pf_v3(g->nrm_x[p], g->nrm_y[p], g->nrm_z[p]),
                                                     pf_scene_face_normal(s, g->prim[p]));
                float *o = out + 3 * (x0 + i);
                o[0] += e.x;
                o[1] += e.y;
                o[2] += e.z;
            }
        for (uint32_t i = 0; i < n; i++) {
            size_t p = (size_t)y * width + x0 + i;
            float *o = out + 3 * (x0 + i);
            o[0] *= g->alb_r[p] * PF_INV_PI;
            o[1] *= g->alb_g[p] * PF_INV_PI;
            o[2] *= g->alb_b[p] * PF_INV_PI;
        }
    }
}

void gi_stage_direct_raytrace(gi_frame *f)
{
    const gi__direct_rt_io io = {f->scene,  f->rt,    &f->area, f->area_strata, f->aa.index,
                                 &f->gbuf,  f->width, f->direct};
    pf_jobs_parallel_for(f->jobs, gi__direct_row, (void *)&io, f->height, 1);
}
