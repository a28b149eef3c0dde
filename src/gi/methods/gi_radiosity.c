/* gi_radiosity: the per-VPL radiosity path tracer of Sequential Monte Carlo
 * Instant Radiosity (Hedman 2017 Sec. 3.2.3; see gi_radiosity.h).
 *
 * The ctx->spp paths of one point are traced together, vertex by vertex, so
 * every Embree query is a batch (pf_rt_intersect/occluded pack them 8 wide):
 *   vertex 0 = y:      punctual lights once (the same for every sample),
 *                      one area-light sample per path
 *   vertex j = 1..B-1: a cosine-weighted bounce from vertex j-1, then the
 *                      same next-event estimation at the new vertex,
 *                      weighted by the throughput T = product of albedos
 * and each path's sum is added to the mean in sample order (double). */
#include "gi_radiosity.h"

#include <math.h>
#include <string.h>

#include "gi_light.h"

uint64_t gi_radiosity_hash(uint64_t a, uint64_t b) { return pf_mix64(pf_mix64(a + 0x9e3779b97f4a7c15ull) ^ b); }

float gi_radiosity_random(uint64_t seed, uint32_t a, uint32_t b, uint32_t c)
{
    uint64_t h = pf_mix64(pf_mix64(seed ^ 0x6a09e667f3bcc909ull) ^ (((uint64_t)a << 40) ^ ((uint64_t)b << 20) ^ c));
    return (float)(h >> 40) * 0x1p-24f; /* k 2^-24, k < 2^24: exactly in [0, 1) */
}

/* Cosine-weighted direction around unit n (Malley's method, pdf cos / pi). */
static pf_vec3 gi__cosine_dir(pf_vec3 n, float u0, float u1)
{
    float r = sqrtf(u0), phi = 2.0f * PF_PI * u1;
    pf_vec3 t, b;
    pf_v3_basis(n, &t, &b);
    return pf_v3_add(pf_v3_add(pf_v3_scale(t, r * cosf(phi)), pf_v3_scale(b, r * sinf(phi))),
                     pf_v3_scale(n, sqrtf(fmaxf(0.0f, 1.0f - u0))));
}

/* Irradiance from every punctual light at a point, shadowed (one ray each). */
static pf_vec3 gi__punctual(const gi_radiosity_ctx *c, pf_vec3 p, pf_vec3 ng, pf_vec3 ns)
{
    pf_vec3 e = pf_v3(0, 0, 0);
    for (uint32_t l = 0; l < c->scene->light_count; l++) {
        gi_light_sample ls;
        if (!gi_light_irradiance(&c->scene->lights[l], p, ns, &ls)) continue;
        if (pf_rt_occluded1(c->rt, gi_light_shadow_ray(&ls, p, ng))) continue;
        e = pf_v3_add(e, ls.irradiance);
    }
    return e;
}

typedef struct gi__rpath {
    pf_vec3 p, ng, ns; /* current vertex, normals turned to the side the light arrives on */
    pf_vec3 T;         /* throughput: albedos of the vertices after y */
    pf_vec3 E;         /* irradiance at y gathered so far */
    int alive;
} gi__rpath;

/* Punctual lights at the current vertex of every live path: E += T E_l,
 * one batch of shadow rays per light. */
static void gi__punctual_batch(const gi_radiosity_ctx *c, gi__rpath *P, uint32_t n)
{
    for (uint32_t l = 0; l < c->scene->light_count; l++) {
        pf_ray rays[GI_RADIOSITY_MAX_SPP];
        pf_vec3 w[GI_RADIOSITY_MAX_SPP];
        uint32_t who[GI_RADIOSITY_MAX_SPP], q = 0;
        uint8_t occ[GI_RADIOSITY_MAX_SPP];
        for (uint32_t s = 0; s < n; s++) {
            gi_light_sample ls;
            if (!P[s].alive || !gi_light_irradiance(&c->scene->lights[l], P[s].p, P[s].ns, &ls)) continue;
            rays[q] = gi_light_shadow_ray(&ls, P[s].p, P[s].ng);
            w[q] = pf_v3_mul(P[s].T, ls.irradiance);
            who[q++] = s;
        }
        if (!q) continue;
        pf_rt_occluded(c->rt, rays, occ, q);
        for (uint32_t k = 0; k < q; k++)
            if (!occ[k]) P[who[k]].E = pf_v3_add(P[who[k]].E, w[k]);
    }
}

/* One area-light sample per live path at its current vertex: E += T Le
 * cos_y cos_l / (r^2 pdf), if unshadowed. */
static void gi__area_nee(const gi_radiosity_ctx *c, gi__rpath *P, uint32_t n, uint64_t seed, uint32_t vertex)
{
    pf_ray rays[GI_RADIOSITY_MAX_SPP];
    pf_vec3 w[GI_RADIOSITY_MAX_SPP];
    uint32_t who[GI_RADIOSITY_MAX_SPP], q = 0;
    uint8_t occ[GI_RADIOSITY_MAX_SPP];
    for (uint32_t s = 0; s < n; s++) {
        if (!P[s].alive) continue;
        gi_area_sample as;
        gi_area_sample_point(c->area, (double)gi_radiosity_random(seed, s, vertex, 0),
                             gi_radiosity_random(seed, s, vertex, 1), gi_radiosity_random(seed, s, vertex, 2), &as);
        pf_vec3 d = pf_v3_sub(as.p, P[s].p);
        float r2 = pf_v3_dot(d, d);
        if (!(r2 > 0.0f) || !(as.pdf_area > 0.0f)) continue;
        float r = sqrtf(r2);
        pf_vec3 wi = pf_v3_scale(d, 1.0f / r);
        float cy = pf_v3_dot(P[s].ns, wi), cl = -pf_v3_dot(as.n, wi);
        if (!(cy > 0.0f) || !(cl > 0.0f) || !(pf_v3_dot(P[s].ng, wi) > 0.0f)) continue;
        w[q] = pf_v3_scale(pf_v3_mul(P[s].T, as.radiance), cy * cl / (r2 * as.pdf_area));
        pf_ray *ray = &rays[q];
        ray->org = pf_rt_offset_origin(P[s].p, P[s].ng, wi);
        ray->dir = pf_v3_sub(as.p, ray->org); /* t = 1 at the light point */
        ray->tnear = 0.0f;
        ray->tfar = 1.0f - 1.0e-4f;          /* stop short of the emitter itself */
        who[q++] = s;
    }
    if (!q) return;
    pf_rt_occluded(c->rt, rays, occ, q);
    for (uint32_t j = 0; j < q; j++)
        if (!occ[j]) P[who[j]].E = pf_v3_add(P[who[j]].E, w[j]);
}

pf_vec3 gi_radiosity_irradiance(const gi_radiosity_ctx *c, pf_vec3 p, pf_vec3 ng, pf_vec3 ns, uint64_t seed)
{
    uint32_t n = c->spp < 1 ? 1 : (c->spp > GI_RADIOSITY_MAX_SPP ? GI_RADIOSITY_MAX_SPP : c->spp);
    uint32_t B = c->bounces < 1 ? 1 : (c->bounces > GI_RADIOSITY_MAX_BOUNCES ? GI_RADIOSITY_MAX_BOUNCES : c->bounces);
    int area = c->area && c->area->count > 0 && c->area->total_power > 0.0;
    gi__rpath P[GI_RADIOSITY_MAX_SPP];
    for (uint32_t s = 0; s < n; s++) {
        P[s].p = p, P[s].ng = ng, P[s].ns = ns;
        P[s].T = pf_v3(1, 1, 1);
        P[s].E = pf_v3(0, 0, 0);
        P[s].alive = 1;
    }
    /* vertex 0: punctual lights are exact, the same for every sample */
    pf_vec3 e0 = gi__punctual(c, p, ng, ns);
    for (uint32_t j = 0; j < B; j++) {
        if (j > 0) gi__punctual_batch(c, P, n); /* punctual lights at the bounce vertices */
        if (area) gi__area_nee(c, P, n, seed, j);
        if (j + 1 == B) break;
        /* continue: a cosine-weighted bounce (f_r cos / pdf = albedo of the next vertex) */
        pf_ray rays[GI_RADIOSITY_MAX_SPP];
        pf_hit hits[GI_RADIOSITY_MAX_SPP];
        uint32_t who[GI_RADIOSITY_MAX_SPP], q = 0;
        for (uint32_t s = 0; s < n; s++) {
            if (!P[s].alive) continue;
            float u0 = gi_radiosity_random(seed, s, j, 3), u1 = gi_radiosity_random(seed, s, j, 4);
            pf_vec3 wi = gi__cosine_dir(P[s].ns, u0, u1);
            /* below the geometric surface (interpolated normals): mirror, as gi_reference.c */
            float d = pf_v3_dot(wi, P[s].ng);
            if (d < 0.0f) wi = pf_v3_sub(wi, pf_v3_scale(P[s].ng, 2.0f * d));
            rays[q].org = pf_rt_offset_origin(P[s].p, P[s].ng, P[s].ng);
            rays[q].dir = wi;
            rays[q].tnear = 0.0f;
            rays[q].tfar = INFINITY;
            who[q++] = s;
        }
        if (!q) break;
        pf_rt_intersect(c->rt, rays, hits, q);
        for (uint32_t k = 0; k < q; k++) {
            gi__rpath *R = &P[who[k]];
            if (hits[k].prim == PF_RT_MISS) {
                R->alive = 0;
                continue;
            }
            pf_surface sf;
            pf_rt_surface(c->rt, &hits[k], 0.0f, &sf);
            int back = pf_v3_dot(sf.ng, rays[k].dir) > 0.0f; /* two-sided: face the incoming ray */
            R->p = sf.p;
            R->ng = back ? pf_v3_scale(sf.ng, -1.0f) : sf.ng;
            R->ns = back ? pf_v3_scale(sf.ns, -1.0f) : sf.ns;
            if (pf_v3_dot(R->ns, R->ng) <= 0.0f) R->ns = R->ng;
            R->T = pf_v3_mul(R->T, pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]));
            if (pf_v3_max_comp(R->T) <= 0.0f) R->alive = 0;
        }
    }
    double acc[3] = {0, 0, 0};
    for (uint32_t s = 0; s < n; s++) acc[0] += P[s].E.x, acc[1] += P[s].E.y, acc[2] += P[s].E.z;
    return pf_v3(e0.x + (float)(acc[0] / n), e0.y + (float)(acc[1] / n), e0.z + (float)(acc[2] / n));
}
