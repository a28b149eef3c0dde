/* gi_lightpath: Instant Radiosity's light paths (Keller 1997; survey Sec.
 * 4.1), shared by `ir` and `mir` (see gi_lightpath.h). */
#include "gi_lightpath.h"

#include <math.h>
#include <string.h>

#include "gi_light.h"

double gi_lightpath_light_power(const pf_light *l, double radius)
{
    double c = pf_luminance(l->color) * (double)l->intensity;
    switch (l->type) {
    case PF_LIGHT_POINT: return 4.0 * PF_PI * c;
    case PF_LIGHT_SPOT: {
        /* 2 pi integral of the cone factor over cos(angle), midpoint rule */
        double co = cos((double)l->outer_cone), sum = 0.0;
        for (int k = 0; k < 256; k++) {
            double ct = co + (1.0 - co) * (k + 0.5) / 256.0;
            sum += gi_light_spot_factor(l, (float)ct);
        }
        return 2.0 * PF_PI * c * sum * (1.0 - co) / 256.0;
    }
    default: return c * PF_PI * radius * radius;
    }
}

void gi_lightpath_lights_init(gi_lightpath_lights *c, const pf_scene *s, const gi_area_lights *area)
{
    memset(c, 0, sizeof *c);
    c->scene = s;
    c->area = area;
    c->centre = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    c->radius = 0.5f * pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min)) * 1.001f;
    c->np = s->light_count < GI_LIGHTPATH_MAX_LIGHTS ? s->light_count : GI_LIGHTPATH_MAX_LIGHTS;
    c->nl = c->np;
    for (uint32_t l = 0; l < c->np; l++) {
        c->total += gi_lightpath_light_power(&s->lights[l], c->radius);
        c->cdf[l] = c->total;
    }
    if (area && area->count > 0 && area->total_power > 0.0) {
        c->total += area->total_power;
        c->cdf[c->nl++] = c->total;
    }
}

uint32_t gi_lightpath_choose(const gi_lightpath_lights *c, double choice, double *lo, double *hi)
{
    double ul = choice * c->total;
    uint32_t l = 0;
    while (l + 1 < c->nl && c->cdf[l] <= ul) l++;
    *lo = l ? c->cdf[l - 1] : 0.0;
    *hi = c->cdf[l];
    return l;
}

/* Unit vector in the frame around axis n from cos(theta) and phi. */
static pf_vec3 gi__around(pf_vec3 n, float cos_t, float phi)
{
    pf_vec3 t, b;
    pf_v3_basis(n, &t, &b);
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    return pf_v3_add(pf_v3_add(pf_v3_scale(t, sin_t * cosf(phi)), pf_v3_scale(b, sin_t * sinf(phi))),
                     pf_v3_scale(n, cos_t));
}

uint32_t gi_lightpath_emit(const gi_lightpath_lights *c, const gi_lightpath_numbers *u, pf_ray *ray, pf_vec3 *phi)
{
    double lo, hi;
    uint32_t l = gi_lightpath_choose(c, u->choice, &lo, &hi);
    const pf_light *L = l < c->np ? &c->scene->lights[l] : NULL;
    double pl = (hi - lo) / c->total;
    float u1 = u->u1, u2 = u->u2, radius = c->radius;
    ray->tnear = 0.0f;
    ray->tfar = INFINITY;
    if (!L) {
        gi_area_sample as;
        gi_area_sample_point(c->area, u->area, u1, u2, &as);
        ray->org = pf_rt_offset_origin(as.p, as.n, as.n);
        ray->dir = gi__around(as.n, sqrtf(1.0f - u->a1), 2.0f * PF_PI * u->a2);
        *phi = pf_v3_scale(as.radiance, (float)(PF_PI / ((double)as.pdf_area * pl)));
    } else if (L->type == PF_LIGHT_POINT) {
        ray->org = L->position;
        ray->dir = gi__around(pf_v3(0, 0, 1), 1.0f - 2.0f * u1, 2.0f * PF_PI * u2);
        *phi = pf_v3_scale(L->color, (float)(L->intensity * 4.0 * PF_PI / pl));
    } else if (L->type == PF_LIGHT_SPOT) {
        float co = cosf(L->outer_cone), ct = 1.0f - u1 * (1.0f - co);
        ray->org = L->position;
        ray->dir = gi__around(L->direction, ct, 2.0f * PF_PI * u2);
        float w = gi_light_spot_factor(L, ct) * 2.0f * PF_PI * (1.0f - co);
        *phi = pf_v3_scale(L->color, (float)(L->intensity * w / pl));
    } else {
        pf_vec3 t, b;
        pf_v3_basis(L->direction, &t, &b);
        float rr = radius * sqrtf(u1), a = 2.0f * PF_PI * u2;
        ray->org = pf_v3_add(pf_v3_sub(c->centre, pf_v3_scale(L->direction, 2.0f * radius)),
                             pf_v3_add(pf_v3_scale(t, rr * cosf(a)), pf_v3_scale(b, rr * sinf(a))));
        ray->dir = L->direction;
        *phi = pf_v3_scale(L->color, (float)(L->intensity * PF_PI * radius * radius / pl));
    }
    return l;
}

static const uint32_t gi__primes[] = {2,  3,  5,  7,  11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59,
                                      61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107, 109, 113, 127, 131,
                                      137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193, 197, 199};
#define GI__DIMS (sizeof gi__primes / sizeof gi__primes[0])

/* The emission numbers of path hi; returns the first dimension not used. */
static uint32_t gi__numbers_halton(const gi_lightpath_lights *c, uint32_t hi, gi_lightpath_numbers *u)
{
    memset(u, 0, sizeof *u);
    u->choice = gi_halton(hi, 2);
    u->u1 = (float)gi_halton(hi, 3);
    u->u2 = (float)gi_halton(hi, 5);
    double lo, hi_cdf;
    if (gi_lightpath_choose(c, u->choice, &lo, &hi_cdf) != c->np) return 3;
    /* an area light: the triangle from the choice's position inside the
     * area lights' CDF range, the direction from two more primes */
    double ua = (u->choice * c->total - lo) / (hi_cdf - lo);
    if (!(ua < 1.0)) ua = 0x1.fffffffffffffp-1;
    if (!(ua >= 0.0)) ua = 0.0;
    u->area = ua;
    u->a1 = (float)gi_halton(hi, gi__primes[3]);
    u->a2 = (float)gi_halton(hi, gi__primes[4]);
    return 5;
}

uint32_t gi_lightpath_trace_halton(const gi_lightpath_lights *c, const pf_rt *rt, uint32_t hi, uint32_t bounces,
                                   uint32_t max, gi_vpl *out)
{
    gi_lightpath_numbers u;
    uint32_t dim0 = gi__numbers_halton(c, hi, &u);
    pf_ray ray;
    pf_vec3 phi;
    gi_lightpath_emit(c, &u, &ray, &phi);
    uint32_t n = 0;
    for (uint32_t k = 0; k < bounces && n < max; k++) {
        gi_vpl *v = &out[n];
        pf_vec3 albedo;
        if (!gi_lightpath_hit(rt, ray, phi, v, &albedo)) break;
        n++;
        /* Russian roulette by albedo, then a cosine-weighted bounce */
        uint32_t d = dim0 + 3 * k;
        if (d + 2 >= GI__DIMS) break;
        float rr = (float)gi_halton(hi, gi__primes[d + 2]);
        float a1 = (float)gi_halton(hi, gi__primes[d]), a2 = (float)gi_halton(hi, gi__primes[d + 1]);
        if (!gi_lightpath_bounce(v, albedo, rr, a1, a2, &phi, &ray)) break;
    }
    return n;
}

/* gi_lightpath_hit after the intersection: the hit h of `ray` (not a miss). */
static void gi__hit_surface(const pf_rt *rt, const pf_ray *ray, const pf_hit *h, pf_vec3 phi, gi_vpl *v,
                            pf_vec3 *albedo)
{
    pf_surface sf;
    pf_rt_surface(rt, h, GI_VPL_ALBEDO_LOD, &sf); /* the VPL's albedo: gi_vpl.h's rule */
    pf_vec3 n = sf.ns, ng = sf.ng;
    if (pf_v3_dot(ng, ray->dir) > 0.0f) ng = pf_v3_scale(ng, -1.0f); /* two-sided: face the photon */
    if (pf_v3_dot(n, ng) < 0.0f) n = pf_v3_scale(n, -1.0f);
    *albedo = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
    v->pos = pf_rt_offset_origin(sf.p, ng, ng);
    v->nrm = n;
    v->intensity = pf_v3_scale(pf_v3_mul(phi, *albedo), PF_INV_PI);
}

#define GI__BATCH 64 /* paths per Embree call of gi_lightpath_trace_halton_batch */

void gi_lightpath_trace_halton_batch(const gi_lightpath_lights *c, const pf_rt *rt, uint32_t hi0, uint32_t count,
                                     uint32_t bounces, gi_vpl *out, uint32_t *got)
{
    for (uint32_t b0 = 0; b0 < count; b0 += GI__BATCH) {
        const uint32_t m = count - b0 < GI__BATCH ? count - b0 : GI__BATCH;
        pf_ray ray[GI__BATCH], rays[GI__BATCH];
        pf_vec3 phi[GI__BATCH];
        pf_hit hits[GI__BATCH];
        uint32_t dim0[GI__BATCH], who[GI__BATCH];
        uint8_t alive[GI__BATCH];
        for (uint32_t i = 0; i < m; i++) {
            gi_lightpath_numbers u;
            dim0[i] = gi__numbers_halton(c, hi0 + b0 + i, &u);
            gi_lightpath_emit(c, &u, &ray[i], &phi[i]);
            got[b0 + i] = 0;
            alive[i] = bounces > 0;
        }
        for (uint32_t k = 0; k < bounces; k++) {
            uint32_t q = 0;
            for (uint32_t i = 0; i < m; i++)
                if (alive[i]) rays[q] = ray[i], who[q++] = i;
            if (!q) break;
            pf_rt_intersect(rt, rays, hits, q);
            for (uint32_t j = 0; j < q; j++) {
                const uint32_t i = who[j], hi = hi0 + b0 + i;
                if (hits[j].prim == PF_RT_MISS) {
                    alive[i] = 0;
                    continue;
                }
                gi_vpl *v = &out[(size_t)(b0 + i) * bounces + got[b0 + i]];
                pf_vec3 albedo;
                gi__hit_surface(rt, &rays[j], &hits[j], phi[i], v, &albedo);
                got[b0 + i]++;
                /* Russian roulette by albedo, then a cosine-weighted bounce */
                uint32_t d = dim0[i] + 3 * k;
                if (k + 1 == bounces || d + 2 >= GI__DIMS) {
                    alive[i] = 0;
                    continue;
                }
                float rr = (float)gi_halton(hi, gi__primes[d + 2]);
                float a1 = (float)gi_halton(hi, gi__primes[d]), a2 = (float)gi_halton(hi, gi__primes[d + 1]);
                alive[i] = (uint8_t)gi_lightpath_bounce(v, albedo, rr, a1, a2, &phi[i], &ray[i]);
            }
        }
    }
}

int gi_lightpath_hit(const pf_rt *rt, pf_ray ray, pf_vec3 phi, gi_vpl *v, pf_vec3 *albedo)
{
    pf_hit h = pf_rt_intersect1(rt, ray);
    if (h.prim == PF_RT_MISS) return 0;
    gi__hit_surface(rt, &ray, &h, phi, v, albedo);
    return 1;
}

int gi_lightpath_bounce(const gi_vpl *v, pf_vec3 albedo, float rr, float a1, float a2, pf_vec3 *phi, pf_ray *ray)
{
    float q = fminf(1.0f, pf_v3_max_comp(albedo));
    if (!(rr < q)) return 0;
    *phi = pf_v3_scale(pf_v3_mul(*phi, albedo), 1.0f / q);
    ray->org = v->pos;
    ray->dir = gi__around(v->nrm, sqrtf(1.0f - a1), 2.0f * PF_PI * a2);
    ray->tnear = 0.0f;
    ray->tfar = INFINITY;
    return 1;
}
