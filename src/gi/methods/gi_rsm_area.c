/* gi_rsm_area: the area lights' reflective shadow map, a hemispherical map
 * per power-weighted emitter point (see gi_rsm_area.h; beyond Dachsbacher
 * 2005 / Barak 2013 Sec. 3 / Aranha Sec. III-A, which use punctual lights).
 *
 *   1. gi_rsm_area_layout  the K emitter points and their texel flux;
 *   2. gi_rsm_area_render  per face row: the rays through the texel centres
 *                          (concentric map + Malley's lift), their closest
 *                          hits, the surfaces and the reflected fluxes. */
#include "gi_rsm_area.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_vpl.h" /* gi_halton */

/* --------------------------------------------------------------- 1. layout */

pf_result gi_rsm_area_layout(gi_rsm_map *m, const gi_area_lights *area, uint32_t points, uint32_t size,
                             pf_error *err)
{
    free(m->faces);
    m->faces = calloc(points, sizeof *m->faces);
    if (!m->faces) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for %u area-light RSM faces", points);
    m->kind = GI_RSM_AREA;
    m->light = GI_RSM_NO_LIGHT;
    m->size = size;
    m->face_count = points;
    m->texel_count = points * size * size;
    m->power = pf_v3(0.0f, 0.0f, 0.0f);
    /* projected solid angle of one texel, pi / size^2 (see the header) */
    const double texel_psa = PF_PI / ((double)size * (double)size);
    for (uint32_t k = 0; k < points; k++) {
        gi_area_sample as;
        gi_area_sample_point(area, ((double)k + 0.5) / points, (float)gi_halton(k + 1, 2), (float)gi_halton(k + 1, 3),
                             &as);
        gi_rsm_face *f = &m->faces[k];
        f->org = pf_rt_offset_origin(as.p, as.n, as.n);
        f->n = as.n;
        pf_v3_basis(as.n, &f->t, &f->b);
        /* A_k = 1 / (K pdf_area), in double: pdf_area can be tiny */
        double a_k = as.pdf_area > 0.0f ? 1.0 / ((double)points * (double)as.pdf_area) : 0.0;
        f->texel_flux = pf_v3((float)(as.radiance.x * a_k * texel_psa), (float)(as.radiance.y * a_k * texel_psa),
                              (float)(as.radiance.z * a_k * texel_psa));
        m->power = pf_v3_add(m->power, pf_v3_scale(as.radiance, (float)(PF_PI * a_k)));
    }
    return PF_OK;
}

/* ---------------------------------------------------------- 2. render */

pf_vec2 gi_rsm_concentric(float a, float b)
{
    pf_vec2 d = {0.0f, 0.0f};
    if (a == 0.0f && b == 0.0f) return d;
    float r, phi;
    if (fabsf(a) > fabsf(b)) { /* the left and right wedges */
        r = a;
        phi = (0.25f * PF_PI) * (b / a);
    } else { /* top and bottom */
        r = b;
        phi = 0.5f * PF_PI - (0.25f * PF_PI) * (a / b);
    }
    d.x = r * cosf(phi);
    d.y = r * sinf(phi);
    return d;
}

pf_vec3 gi_rsm_area_dir(const gi_rsm_face *f, uint32_t size, uint32_t x, uint32_t y)
{
    float texel = 2.0f / (float)size;
    pf_vec2 d = gi_rsm_concentric(((float)x + 0.5f) * texel - 1.0f, 1.0f - ((float)y + 0.5f) * texel);
    float z = sqrtf(fmaxf(0.0f, 1.0f - d.x * d.x - d.y * d.y)); /* Malley: the disc point lifted */
    return pf_v3_add(pf_v3_add(pf_v3_scale(f->t, d.x), pf_v3_scale(f->b, d.y)), pf_v3_scale(f->n, z));
}

typedef struct gi__area_ctx {
    gi_rsm_set *set;
    const gi_rsm_map *map;
    const pf_rt *rt;
} gi__area_ctx;

#define GI__AREA_CHUNK 64u /* rays per pf_rt_intersect call (on the stack) */

/* Texel i from the hit of the ray along d (the ray's origin side is lit). */
static void gi__area_texel(gi_rsm_set *s, size_t i, const pf_rt *rt, const pf_hit *h, pf_vec3 d, pf_vec3 texel_flux)
{
    s->valid[i] = 0;
    s->pos_x[i] = s->pos_y[i] = s->pos_z[i] = 0.0f;
    s->nrm_x[i] = s->nrm_y[i] = s->nrm_z[i] = 0.0f;
    s->ng_x[i] = s->ng_y[i] = s->ng_z[i] = 0.0f;
    s->flux_r[i] = s->flux_g[i] = s->flux_b[i] = 0.0f;
    s->prim[i] = RS_NO_PRIM;
    if (h->prim == PF_RT_MISS) return; /* the flux leaves the scene */
    pf_surface sf;
    pf_rt_surface(rt, h, GI_VPL_ALBEDO_LOD, &sf); /* a texel is a VPL site: gi_vpl.h's albedo rule */
    /* two-sided: both normals face the emitter point */
    pf_vec3 ng = sf.ng, ns = sf.ns;
    if (pf_v3_dot(ng, d) > 0.0f) ng = pf_v3_scale(ng, -1.0f);
    if (pf_v3_dot(ns, ng) < 0.0f) ns = pf_v3_scale(ns, -1.0f);
    s->valid[i] = 1;
    s->prim[i] = h->prim;
    s->pos_x[i] = sf.p.x, s->pos_y[i] = sf.p.y, s->pos_z[i] = sf.p.z;
    s->nrm_x[i] = ns.x, s->nrm_y[i] = ns.y, s->nrm_z[i] = ns.z;
    s->ng_x[i] = ng.x, s->ng_y[i] = ng.y, s->ng_z[i] = ng.z;
    s->flux_r[i] = texel_flux.x * sf.albedo[0];
    s->flux_g[i] = texel_flux.y * sf.albedo[1];
    s->flux_b[i] = texel_flux.z * sf.albedo[2];
}

/* Item = row y of face f (row = f * size + y): writes only that row. */
static void gi__area_row(void *p, uint32_t row, uint32_t worker)
{
    (void)worker;
    const gi__area_ctx *c = p;
    const gi_rsm_map *m = c->map;
    const uint32_t n = m->size, f = row / n, y = row % n;
    const gi_rsm_face *face = &m->faces[f];
    pf_ray rays[GI__AREA_CHUNK];
    pf_hit hits[GI__AREA_CHUNK];
    for (uint32_t x0 = 0; x0 < n; x0 += GI__AREA_CHUNK) {
        uint32_t cnt = n - x0 < GI__AREA_CHUNK ? n - x0 : GI__AREA_CHUNK;
        for (uint32_t k = 0; k < cnt; k++) {
            rays[k].org = face->org;
            rays[k].dir = gi_rsm_area_dir(face, n, x0 + k, y);
            rays[k].tnear = 0.0f;
            rays[k].tfar = INFINITY;
        }
        pf_rt_intersect(c->rt, rays, hits, cnt);
        for (uint32_t k = 0; k < cnt; k++)
            gi__area_texel(c->set, m->first + (size_t)row * n + x0 + k, c->rt, &hits[k], rays[k].dir, face->texel_flux);
    }
}

void gi_rsm_area_render(gi_rsm_set *s, uint32_t map, const pf_rt *rt, pf_jobs *jobs)
{
    const gi_rsm_map *m = &s->maps[map];
    gi__area_ctx c = {s, m, rt};
    uint32_t rows = m->face_count * m->size;
    if (jobs)
        pf_jobs_parallel_for(jobs, gi__area_row, &c, rows, 0);
    else
        for (uint32_t r = 0; r < rows; r++) gi__area_row(&c, r, 0);
}
