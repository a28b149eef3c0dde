/* gi_radiosity: the per-VPL radiosity path tracer of Sequential Monte Carlo
 * Instant Radiosity (Hedman 2017 Sec. 3.2.3; see gi_radiosity.h).
 *
 * The paths of one point (of several points at once) are traced together,
 * vertex by vertex, so every Embree query is a batch (pf_rt_intersect /
 * occluded pack them 8 wide):
 *   vertex 0 = y:      punctual lights once (the same for every sample),
 *                      one area-light sample per path
 *   vertex j = 1..B-1: a cosine-weighted bounce from vertex j-1, then the
 *                      same next-event estimation at the new vertex,
 *                      weighted by the throughput T = product of albedos
 * and each path's sum is added to the mean in sample order (double).
 *
 * In two halves (gi_radiosity.h): gi__trace writes each path's vertices
 * with their area-light samples (the light-independent part), gi__gather
 * adds, path by path, the area sample of vertex 0, then for each vertex
 * j >= 1 the punctual lights in scene order and the vertex's area sample,
 * which is the order a single pass adds them in. gi_radiosity_irradiance
 * runs both on groups of GI__GROUP paths, so it needs no buffer of all
 * spp x bounces vertices. */
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

static pf_vec3 gi__bounce_dir(pf_vec3 ns, pf_vec3 ng, float u0, float u1)
{
    float r = sqrtf(u0), phi = 2.0f * PF_PI * u1;
    pf_vec3 t, b;
    pf_v3_basis(ns, &t, &b);
    pf_vec3 w = pf_v3_add(pf_v3_add(pf_v3_scale(t, r * cosf(phi)), pf_v3_scale(b, r * sinf(phi))),
                          pf_v3_scale(ns, sqrtf(fmaxf(0.0f, 1.0f - u0))));
    /* below the geometric surface (interpolated normals): mirror, as gi_reference.c */
    float d = pf_v3_dot(w, ng);
    return d < 0.0f ? pf_v3_sub(w, pf_v3_scale(ng, 2.0f * d)) : w;
}

pf_ray gi_radiosity_bounce_ray(pf_vec3 p, pf_vec3 ns, pf_vec3 ng, float u0, float u1)
{
    return (pf_ray){.org = pf_rt_offset_origin(p, ng, ng), .tnear = 0.0f, .dir = gi__bounce_dir(ns, ng, u0, u1),
                    .tfar = INFINITY};
}

#define GI__RAYS 256   /* rays per Embree call (stack arrays) */
#define GI__PATHS 1024 /* paths one gather pass holds (estimates x spp) */
#define GI__GROUP 16   /* paths per pass of gi_radiosity_irradiance */

static uint32_t gi__spp(const gi_radiosity_ctx *c)
{
    return c->spp < 1 ? 1 : (c->spp > GI_RADIOSITY_MAX_SPP ? GI_RADIOSITY_MAX_SPP : c->spp);
}

static uint32_t gi__bounces(const gi_radiosity_ctx *c)
{
    return c->bounces < 1 ? 1 : (c->bounces > GI_RADIOSITY_MAX_BOUNCES ? GI_RADIOSITY_MAX_BOUNCES : c->bounces);
}

static int gi__has_area(const gi_radiosity_ctx *c) { return c->area && c->area->count > 0 && c->area->total_power > 0.0; }

uint32_t gi_radiosity_vertex_count(const gi_radiosity_ctx *c) { return gi__spp(c) * gi__bounces(c); }

/* The paths [s0, s0 + m) of `count` estimates: path s's vertex j is
 * v[e][j * stride + (s - s0)]. */
typedef struct gi__range {
    uint32_t B, s0, m, stride;
} gi__range;

/* One area-light sample per live path at vertex j: sets LIT and area = T Le
 * cos_y cos_l / (r^2 pdf) where the sample is unshadowed. */
static void gi__area_nee(const gi_radiosity_ctx *c, const gi__range *g, const uint64_t *seeds, uint32_t count,
                         gi_radiosity_vertex *const *v, uint32_t j)
{
    pf_ray rays[GI__RAYS];
    gi_radiosity_vertex *who[GI__RAYS];
    pf_vec3 w[GI__RAYS];
    uint8_t occ[GI__RAYS];
    uint32_t q = 0;
    for (uint32_t e = 0; e < count; e++)
        for (uint32_t k = 0; k < g->m; k++) {
            gi_radiosity_vertex *V = &v[e][j * g->stride + k];
            if (!(V->flags & GI_RADIOSITY_ALIVE)) continue;
            uint32_t s = g->s0 + k;
            gi_area_sample as;
            gi_area_sample_point(c->area, (double)gi_radiosity_random(seeds[e], s, j, 0),
                                 gi_radiosity_random(seeds[e], s, j, 1), gi_radiosity_random(seeds[e], s, j, 2), &as);
            pf_vec3 d = pf_v3_sub(as.p, V->p);
            float r2 = pf_v3_dot(d, d);
            if (!(r2 > 0.0f) || !(as.pdf_area > 0.0f)) continue;
            float r = sqrtf(r2);
            pf_vec3 wi = pf_v3_scale(d, 1.0f / r);
            float cy = pf_v3_dot(V->ns, wi), cl = -pf_v3_dot(as.n, wi);
            if (!(cy > 0.0f) || !(cl > 0.0f) || !(pf_v3_dot(V->ng, wi) > 0.0f)) continue;
            w[q] = pf_v3_scale(pf_v3_mul(V->T, as.radiance), cy * cl / (r2 * as.pdf_area));
            pf_ray *ray = &rays[q];
            ray->org = pf_rt_offset_origin(V->p, V->ng, wi);
            ray->dir = pf_v3_sub(as.p, ray->org); /* t = 1 at the light point */
            ray->tnear = 0.0f;
            ray->tfar = 1.0f - 1.0e-4f;          /* stop short of the emitter itself */
            who[q++] = V;
            if (q == GI__RAYS) {
                pf_rt_occluded(c->rt, rays, occ, q);
                for (uint32_t i = 0; i < q; i++)
                    if (!occ[i]) who[i]->area = w[i], who[i]->flags |= GI_RADIOSITY_LIT;
                q = 0;
            }
        }
    if (!q) return;
    pf_rt_occluded(c->rt, rays, occ, q);
    for (uint32_t i = 0; i < q; i++)
        if (!occ[i]) who[i]->area = w[i], who[i]->flags |= GI_RADIOSITY_LIT;
}

/* The hits of a chunk of bounce rays: vertex j + 1 of each path. */
static void gi__bounce_hits(const gi_radiosity_ctx *c, const pf_ray *rays, const pf_hit *hits,
                            gi_radiosity_vertex *const *from, gi_radiosity_vertex *const *to, uint32_t q)
{
    for (uint32_t i = 0; i < q; i++) {
        if (hits[i].prim == PF_RT_MISS) continue; /* to[i] stays dead */
        gi_radiosity_vertex *R = to[i];
        pf_surface sf;
        pf_rt_surface(c->rt, &hits[i], 0.0f, &sf);
        int back = pf_v3_dot(sf.ng, rays[i].dir) > 0.0f; /* two-sided: face the incoming ray */
        R->p = sf.p;
        R->ng = back ? pf_v3_scale(sf.ng, -1.0f) : sf.ng;
        R->ns = back ? pf_v3_scale(sf.ns, -1.0f) : sf.ns;
        if (pf_v3_dot(R->ns, R->ng) <= 0.0f) R->ns = R->ng;
        R->T = pf_v3_mul(from[i]->T, pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]));
        R->flags = pf_v3_max_comp(R->T) <= 0.0f ? 0u : GI_RADIOSITY_ALIVE;
    }
}

/* The light-independent half for the paths of g: vertices, throughputs and
 * area-light samples. */
static void gi__trace(const gi_radiosity_ctx *c, const gi__range *g, const gi_radiosity_site *y, const uint64_t *seeds,
                      uint32_t count, gi_radiosity_vertex *const *v)
{
    const uint32_t B = g->B;
    const int area = gi__has_area(c);
    for (uint32_t e = 0; e < count; e++)
        for (uint32_t j = 0; j < B; j++)
            for (uint32_t k = 0; k < g->m; k++) {
                gi_radiosity_vertex *V = &v[e][j * g->stride + k];
                memset(V, 0, sizeof *V);
                if (j) continue;
                V->p = y[e].p, V->ng = y[e].ng, V->ns = y[e].ns;
                V->T = pf_v3(1, 1, 1);
                V->flags = GI_RADIOSITY_ALIVE;
            }
    for (uint32_t j = 0; j < B; j++) {
        if (area) gi__area_nee(c, g, seeds, count, v, j);
        if (j + 1 == B) break;
        /* continue: a cosine-weighted bounce (f_r cos / pdf = albedo of the next vertex) */
        pf_ray rays[GI__RAYS];
        pf_hit hits[GI__RAYS];
        gi_radiosity_vertex *from[GI__RAYS], *to[GI__RAYS];
        uint32_t q = 0, any = 0;
        for (uint32_t e = 0; e < count; e++)
            for (uint32_t k = 0; k < g->m; k++) {
                gi_radiosity_vertex *V = &v[e][j * g->stride + k];
                if (!(V->flags & GI_RADIOSITY_ALIVE)) continue;
                uint32_t s = g->s0 + k;
                float u0 = gi_radiosity_random(seeds[e], s, j, 3), u1 = gi_radiosity_random(seeds[e], s, j, 4);
                rays[q] = gi_radiosity_bounce_ray(V->p, V->ns, V->ng, u0, u1);
                from[q] = V;
                to[q++] = &v[e][(j + 1) * g->stride + k];
                any = 1;
                if (q == GI__RAYS) {
                    pf_rt_intersect(c->rt, rays, hits, q);
                    gi__bounce_hits(c, rays, hits, from, to, q);
                    q = 0;
                }
            }
        if (!any) break;
        if (q) {
            pf_rt_intersect(c->rt, rays, hits, q);
            gi__bounce_hits(c, rays, hits, from, to, q);
        }
    }
}

/* A batch of q punctual-light shadow rays: out[who[i]] += w[i] for each
 * unoccluded ray, in batch order. Returns 0 (the batch is empty again). */
static uint32_t gi__shadow_flush(const gi_radiosity_ctx *c, const pf_ray *rays, const pf_vec3 *w,
                                 const uint32_t *who, uint32_t q, pf_vec3 *out)
{
    if (!q) return 0;
    uint8_t occ[GI__RAYS];
    pf_rt_occluded(c->rt, rays, occ, q);
    for (uint32_t i = 0; i < q; i++)
        if (!occ[i]) out[who[i]] = pf_v3_add(out[who[i]], w[i]);
    return 0;
}

/* Punctual lights at y of each estimate, exact and the same for every
 * sample: e0[e] = sum over the lights (scene order) of the unshadowed ones. */
static void gi__punctual_y(const gi_radiosity_ctx *c, const gi_radiosity_site *y, uint32_t count, pf_vec3 *e0)
{
    for (uint32_t e = 0; e < count; e++) e0[e] = pf_v3(0, 0, 0);
    for (uint32_t l = 0; l < c->scene->light_count; l++) {
        pf_ray rays[GI__RAYS];
        pf_vec3 w[GI__RAYS];
        uint32_t who[GI__RAYS], q = 0;
        for (uint32_t e = 0; e < count; e++) {
            gi_light_sample ls;
            if (!gi_light_irradiance(&c->scene->lights[l], y[e].p, y[e].ns, &ls)) continue;
            rays[q] = gi_light_shadow_ray(&ls, y[e].p, y[e].ng);
            w[q] = ls.irradiance;
            who[q++] = e;
            if (q == GI__RAYS) q = gi__shadow_flush(c, rays, w, who, q, e0);
        }
        gi__shadow_flush(c, rays, w, who, q, e0);
    }
}

/* The light-dependent half for the paths of g (count * g->m <= GI__PATHS):
 * adds each path's irradiance, in path order, to acc[e]. */
static void gi__gather(const gi_radiosity_ctx *c, const gi__range *g, const gi_radiosity_vertex *const *v,
                       uint32_t count, double (*acc)[3])
{
    pf_vec3 E[GI__PATHS];
    const uint32_t m = g->m;
    for (uint32_t e = 0; e < count; e++)
        for (uint32_t k = 0; k < m; k++) {
            const gi_radiosity_vertex *V = &v[e][k];
            E[e * m + k] = (V->flags & GI_RADIOSITY_LIT) ? pf_v3_add(pf_v3(0, 0, 0), V->area) : pf_v3(0, 0, 0);
        }
    for (uint32_t j = 1; j < g->B; j++) {
        /* punctual lights at vertex j, one batch of shadow rays per light: E += T E_l */
        for (uint32_t l = 0; l < c->scene->light_count; l++) {
            pf_ray rays[GI__RAYS];
            pf_vec3 w[GI__RAYS];
            uint32_t who[GI__RAYS], q = 0;
            for (uint32_t e = 0; e < count; e++)
                for (uint32_t k = 0; k < m; k++) {
                    const gi_radiosity_vertex *V = &v[e][j * g->stride + k];
                    gi_light_sample ls;
                    if (!(V->flags & GI_RADIOSITY_ALIVE) || !gi_light_irradiance(&c->scene->lights[l], V->p, V->ns, &ls))
                        continue;
                    rays[q] = gi_light_shadow_ray(&ls, V->p, V->ng);
                    w[q] = pf_v3_mul(V->T, ls.irradiance);
                    who[q++] = e * m + k;
                    if (q == GI__RAYS) q = gi__shadow_flush(c, rays, w, who, q, E);
                }
            gi__shadow_flush(c, rays, w, who, q, E);
        }
        /* then the vertex's area-light sample */
        for (uint32_t e = 0; e < count; e++)
            for (uint32_t k = 0; k < m; k++) {
                const gi_radiosity_vertex *V = &v[e][j * g->stride + k];
                if (V->flags & GI_RADIOSITY_LIT) E[e * m + k] = pf_v3_add(E[e * m + k], V->area);
            }
    }
    for (uint32_t e = 0; e < count; e++)
        for (uint32_t k = 0; k < m; k++) {
            const pf_vec3 *x = &E[e * m + k];
            acc[e][0] += x->x, acc[e][1] += x->y, acc[e][2] += x->z;
        }
}

void gi_radiosity_trace(const gi_radiosity_ctx *c, const gi_radiosity_site *y, const uint64_t *seeds, uint32_t count,
                        gi_radiosity_vertex *const *v)
{
    const uint32_t n = gi__spp(c);
    const gi__range g = {gi__bounces(c), 0, n, n};
    for (uint32_t e0 = 0; e0 < count; e0 += GI__PATHS / n) {
        uint32_t k = count - e0 < GI__PATHS / n ? count - e0 : GI__PATHS / n;
        gi__trace(c, &g, y + e0, seeds + e0, k, v + e0);
    }
}

void gi_radiosity_gather(const gi_radiosity_ctx *c, const gi_radiosity_site *y, const gi_radiosity_vertex *const *v,
                         uint32_t count, pf_vec3 *out)
{
    const uint32_t n = gi__spp(c), per = GI__PATHS / n;
    const gi__range g = {gi__bounces(c), 0, n, n};
    for (uint32_t e0 = 0; e0 < count; e0 += per) {
        uint32_t k = count - e0 < per ? count - e0 : per;
        double acc[GI__PATHS][3];
        pf_vec3 p0[GI__PATHS];
        memset(acc, 0, sizeof(double) * 3 * k);
        gi__gather(c, &g, v + e0, k, acc);
        gi__punctual_y(c, y + e0, k, p0);
        for (uint32_t e = 0; e < k; e++)
            out[e0 + e] = pf_v3(p0[e].x + (float)(acc[e][0] / n), p0[e].y + (float)(acc[e][1] / n),
                                p0[e].z + (float)(acc[e][2] / n));
    }
}

pf_vec3 gi_radiosity_irradiance(const gi_radiosity_ctx *c, pf_vec3 p, pf_vec3 ng, pf_vec3 ns, uint64_t seed)
{
    const uint32_t n = gi__spp(c), B = gi__bounces(c);
    const gi_radiosity_site y = {p, ng, ns};
    gi_radiosity_vertex buf[GI__GROUP * GI_RADIOSITY_MAX_BOUNCES];
    gi_radiosity_vertex *v = buf;
    double acc[1][3] = {{0, 0, 0}};
    for (uint32_t s0 = 0; s0 < n; s0 += GI__GROUP) {
        const gi__range g = {B, s0, n - s0 < GI__GROUP ? n - s0 : GI__GROUP, GI__GROUP};
        gi__trace(c, &g, &y, &seed, 1, &v);
        gi__gather(c, &g, (const gi_radiosity_vertex *const *)&v, 1, acc);
    }
    pf_vec3 e0;
    gi__punctual_y(c, &y, 1, &e0);
    return pf_v3(e0.x + (float)(acc[0][0] / n), e0.y + (float)(acc[0][1] / n), e0.z + (float)(acc[0][2] / n));
}
