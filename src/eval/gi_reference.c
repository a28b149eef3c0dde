/* gi_reference: the reference path tracer (see gi_reference.h for the
 * estimator, the bounce definition and the random-number scheme).
 *
 * Per job item (one image row), per group of 8 pixels, per sample index:
 *   1. camera rays       gi__camera_ray jittered within the pixel
 *   2. for vertex k = 1 .. B+1 (B+2 with no_area_nee):
 *      a. intersect      the live paths, compacted into one packet
 *      b. emission       L += T Le(x_k) (k = 1 only, unless no_area_nee)
 *      c. next event     per punctual light and one area-light sample:
 *                        irradiance, shadow packet, L += T albedo/pi E
 *                        (from x2 on, point and spot lights: times the
 *                        MIS weight against the light vertex of 2d)
 *      d. light vertex   per point/spot light (k <= B, light_paths): one
 *                        direction leaving the light, its first hit y,
 *                        a shadow ray x_k - y, the MIS-weighted connection
 *      e. continue       cosine-weighted bounce, T *= albedo
 *   3. accumulate        L of every path into its pixel's sum, in sample order */
#include <math.h>
#include <stdatomic.h>
#include <string.h>

#include "gi_area.h"
#include "gi_light.h"
#include "gi_reference.h"
#include "gi_indirect.h"

/* ---------------------------------------------------------------- camera rays */

pf_ray gi_reference_camera_ray(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y,
                               uint32_t sample)
{
    uint32_t pixel = y * width + x;
    /* Box filter: a point uniform in the pixel square [x, x+1) x [y, y+1). */
    float jx = pf_random(pixel, sample, 0, 0), jy = pf_random(pixel, sample, 0, 1);
    pf_ray r;
    r.org = cam->eye;
    r.dir = pf_camera_ray_dir(cam, width, height, (float)x + jx, (float)y + jy);
    r.tnear = cam->znear;
    r.tfar = cam->zfar > 0.0f ? cam->zfar : INFINITY;
    return r;
}

/* ---------------------------------------------------------------- sampling */

/* Cosine-weighted direction around unit n (Malley's method): a point uniform
 * on the unit disc, (r cos phi, r sin phi) with r = sqrt(u0), phi = 2 pi u1,
 * lifted to the hemisphere z = sqrt(1 - r^2). The disc's uniform density 1/pi
 * projects to pdf(w) = cos(theta) / pi over solid angle. */
static pf_vec3 gi__sample_cosine(pf_vec3 n, float u0, float u1)
{
    float r = sqrtf(u0), phi = 2.0f * PF_PI * u1;
    float lx = r * cosf(phi), ly = r * sinf(phi), lz = sqrtf(fmaxf(0.0f, 1.0f - u0));
    pf_vec3 t, b;
    pf_v3_basis(n, &t, &b);
    return pf_v3_add(pf_v3_add(pf_v3_scale(t, lx), pf_v3_scale(b, ly)), pf_v3_scale(n, lz));
}

/* ---------------------------------------------------------------- path tracing */

typedef struct gi__ref_ctx {
    float *out;
    const pf_scene *scene;
    const pf_rt *rt;
    const pf_camera *camera;
    uint32_t width, height, spp, bounces;
    int indirect_only;
    int no_area_nee;            /* emitters only through BSDF-sampled hits */
    int light_paths;            /* the light-vertex strategy with MIS (punctual lights) */
    float clamp_b;              /* > 0: the bounded geometry term of x1 - x2 */
    const gi_area_lights *area; /* the scene's emissive triangles */
    gi_reference_progress_fn progress;
    void *progress_user;
    float *noise;               /* opts->noise_out: per-pixel relative standard error, or NULL */
    uint32_t caller_worker; /* the job system's id of the thread that waits */
    atomic_uint rows_done;
} gi__ref_ctx;

/* The state of one path (one lane of a packet). */
typedef struct gi__path {
    pf_ray ray;      /* the segment to trace next */
    pf_vec3 T;       /* throughput: product of the albedos so far (f_r cos / pdf per bounce) */
    pf_vec3 L;       /* radiance gathered so far */
    int alive;
    /* the surface at the current vertex */
    pf_vec3 p, ng, ns; /* ng: the triangle's, unflipped; ns: turned to face the incoming ray */
    pf_vec3 ng_front;  /* ng turned to the incoming side */
    pf_vec3 nee_w;     /* T * albedo / pi: the weight of an irradiance at this vertex */
    pf_vec3 n_bounce;  /* the normal the bounce leaving this vertex is sampled around */
    pf_vec3 prev_p;    /* the vertex before this one (k >= 2) */
    float bounce_pdf;  /* the solid-angle pdf at prev_p of the direction that reached this vertex */
} gi__path;

/* ---------------------------------------------------------------- the light-vertex strategy
 *
 * A path x_j -> z -> light (z = x_{j+1}, j >= 1) is found two ways: by the
 * bounce from x_j (pdf p_A, cosine-weighted) and NEE at z, or by a
 * direction leaving the light (pdf p_w) whose first hit y = z is joined to
 * x_j by a shadow ray. In solid angle at x_j the second has the density
 *   p_B = p_w |ng_z . w_L| r_jz^2 / (r_Lz^2 |ng_z . w|)
 * (w_L from the light to z, w from x_j to z; the Jacobians of the two
 * changes of variable, light direction -> area at z -> direction at x_j).
 * The balance heuristic weights each by p / (p_A + p_B) (Veach 1997,
 * Ch. 9), which sums to one over the two for every path, so the estimate
 * stays unbiased. Where z lies close to the light (p_B large) NEE's E ~
 * I / r^2 is weighted down, and where x_j and z are close (p_A large) the
 * connection's G ~ 1 / r^2 is: the estimator's variance stays bounded
 * where either alone would be unbounded (the Cornell box's light, 1 cm under
 * the ceiling, and its corners). */

/* The lights with a light-vertex strategy: point lights, and spot lights
 * with a cone (their directions are drawn within the outer cone).
 * Directional lights have no 1/r^2 to tame: NEE alone. */
static int gi__light_emits(const pf_light *L)
{
    if (!(L->intensity > 0.0f)) return 0;
    if (L->type == PF_LIGHT_POINT) return 1;
    return L->type == PF_LIGHT_SPOT && 1.0f - cosf(L->outer_cone) > 1e-6f;
}

/* The solid-angle pdf of the direction w (unit, leaving the light): uniform
 * over the sphere for point lights, uniform within the outer cone for spots. */
static float gi__light_emit_pdf(const pf_light *L, pf_vec3 w)
{
    if (L->type == PF_LIGHT_POINT) return 0.25f * PF_INV_PI;
    float cos_outer = cosf(L->outer_cone);
    if (pf_v3_dot(w, L->direction) < cos_outer) return 0.0f;
    return 1.0f / (2.0f * PF_PI * (1.0f - cos_outer));
}

/* A direction leaving light L from (u0, u1), distributed as
 * gi__light_emit_pdf: cos(theta) uniform in [cos_max, 1] around the axis
 * (the whole sphere for a point light). */
static pf_vec3 gi__light_emit_dir(const pf_light *L, float u0, float u1)
{
    pf_vec3 axis = L->type == PF_LIGHT_POINT ? pf_v3(0.0f, 0.0f, 1.0f) : L->direction;
    float cos_max = L->type == PF_LIGHT_POINT ? -1.0f : cosf(L->outer_cone);
    float z = 1.0f - u0 * (1.0f - cos_max);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.0f * PF_PI * u1;
    pf_vec3 t, b;
    pf_v3_basis(axis, &t, &b);
    return pf_v3_add(pf_v3_add(pf_v3_scale(t, r * cosf(phi)), pf_v3_scale(b, r * sinf(phi))), pf_v3_scale(axis, z));
}

/* The solid-angle pdf with which the bounce of 2e leaving a vertex (sampling
 * normal n, geometric normal ng_front on the path's side) goes along unit w:
 * cosine-weighted around n, and the directions below the geometric surface
 * mirrored into it, so w also collects its mirror image's density. */
static float gi__bounce_pdf(pf_vec3 n, pf_vec3 ng_front, pf_vec3 w)
{
    float d = pf_v3_dot(w, ng_front);
    if (!(d > 0.0f)) return 0.0f;
    pf_vec3 m = pf_v3_sub(w, pf_v3_scale(ng_front, 2.0f * d));
    return (fmaxf(0.0f, pf_v3_dot(n, w)) + fmaxf(0.0f, pf_v3_dot(n, m))) * PF_INV_PI;
}

/* NEE's MIS weight p_A / (p_A + p_B) at vertex P (k >= 2) for light L seen
 * at unit direction wl and distance dist (the terms multiplied through by
 * r_Lz^2 |ng_z . w| so that neither distance can divide by zero). */
static float gi__nee_weight(const pf_light *L, const gi__path *P, pf_vec3 wl, float dist)
{
    pf_vec3 from_light = pf_v3_scale(wl, -1.0f);
    float pw = gi__light_emit_pdf(L, from_light);
    if (!(pw > 0.0f)) return 1.0f;
    pf_vec3 d = pf_v3_sub(P->p, P->prev_p);
    float r2 = pf_v3_dot(d, d);
    if (!(r2 > 0.0f)) return 1.0f;
    float cw = fabsf(pf_v3_dot(P->ng, d)) / sqrtf(r2);
    float a = P->bounce_pdf * dist * dist * cw;
    float b = pw * fabsf(pf_v3_dot(P->ng, from_light)) * r2;
    return a + b > 0.0f ? a / (a + b) : 1.0f;
}

/* 2c for the paths of a packet that hit a surface at vertex k: every
 * punctual light, then (unless no_area_nee) one point on the emitters. */
static void gi__next_event(const gi__ref_ctx *c, gi__path *paths, const uint32_t *lanes, uint32_t m, uint32_t pixel0,
                           uint32_t sample, uint32_t k)
{
    const pf_scene *s = c->scene;
    if (!c->no_area_nee && c->area->count > 0) {
        /* Area lights: one emitter point per path vertex, chosen by power
         * (gi_area_sample_point, numbers of dimensions 2-4 of vertex k, so the
         * bounce's dimensions 0-1 are untouched), and the area-measure
         * estimator Le cos cos / (r^2 pdf) (gi_area_sample_irradiance). */
        pf_ray rays[PF_RT_WIDTH];
        pf_vec3 irr[PF_RT_WIDTH];
        uint32_t who[PF_RT_WIDTH], q = 0;
        for (uint32_t j = 0; j < m; j++) {
            gi__path *P = &paths[lanes[j]];
            uint32_t pixel = pixel0 + lanes[j];
            gi_area_sample as;
            gi_area_sample_point(c->area, pf_random(pixel, sample, k, 2),
                                 pf_random(pixel, sample, k, 3), pf_random(pixel, sample, k, 4),
                                 &as);
            gi_light_sample ls;
            if (!gi_area_sample_irradiance(&as, P->p, P->ns, &ls.irradiance, &ls.wi, &ls.distance)) continue;
            irr[q] = ls.irradiance;
            rays[q] = gi_light_shadow_ray(&ls, P->p, P->ng);
            who[q] = lanes[j];
            q++;
        }
        if (q > 0) {
            uint8_t occ[PF_RT_WIDTH];
            pf_rt_occluded(c->rt, rays, occ, q);
            for (uint32_t j = 0; j < q; j++)
                if (!occ[j]) paths[who[j]].L = pf_v3_add(paths[who[j]].L, pf_v3_mul(paths[who[j]].nee_w, irr[j]));
        }
    }
    for (uint32_t l = 0; l < s->light_count; l++) {
        pf_ray rays[PF_RT_WIDTH];
        gi_light_sample ls[PF_RT_WIDTH];
        uint32_t who[PF_RT_WIDTH], q = 0;
        for (uint32_t j = 0; j < m; j++) {
            gi__path *P = &paths[lanes[j]];
            if (!gi_light_irradiance(&s->lights[l], P->p, P->ns, &ls[q])) continue;
            /* The shadow ray exactly as the renderer's (gi_raytrace.c): from the
             * point offset to the light's side, stopping just short of the light
             * so that a light lying on a surface does not shadow itself. */
            rays[q] = gi_light_shadow_ray(&ls[q], P->p, P->ng);
            who[q] = lanes[j];
            q++;
        }
        if (q == 0) continue;
        uint8_t occ[PF_RT_WIDTH];
        pf_rt_occluded(c->rt, rays, occ, q);
        int mis = c->light_paths && k >= 2 && k <= c->bounces + 1 && gi__light_emits(&s->lights[l]);
        for (uint32_t j = 0; j < q; j++) {
            if (occ[j]) continue;
            gi__path *P = &paths[who[j]];
            /* Lr = f_r E = albedo/pi E for a Lambertian surface */
            pf_vec3 e = ls[j].irradiance;
            if (mis) e = pf_v3_scale(e, gi__nee_weight(&s->lights[l], P, ls[j].wi, ls[j].distance));
            P->L = pf_v3_add(P->L, pf_v3_mul(P->nee_w, e));
        }
    }
}

/* clamp_b: the factor min(1, b / G) for the segment from x1 (p1, its turned
 * shading normal n1) to x2 (p2, n2 turned to face x1): the frame's bounded
 * geometry term between the receiver x1 and a VPL at x2 (gi_indirect.c:
 * cos1 = n1 . w, cos2 = -n2 . w, both normals shading normals facing each
 * other's side, as the frame turns them). */
static float gi__clamp_factor(float b, pf_vec3 p1, pf_vec3 n1, pf_vec3 p2, pf_vec3 n2)
{
    pf_vec3 d = pf_v3_sub(p2, p1);
    float r2 = pf_v3_dot(d, d);
    if (!(r2 > 0.0f)) return 1.0f;
    pf_vec3 w = pf_v3_scale(d, 1.0f / sqrtf(r2));
    float G = fabsf(pf_v3_dot(n1, w)) * fabsf(pf_v3_dot(n2, w)) / r2;
    return G > b ? b / G : 1.0f;
}

/* 2d for the paths of a packet at vertex k (1 <= k <= B): per point and spot
 * light, a direction leaving it (numbers of dimensions 5 + 2 l and 6 + 2 l
 * of vertex k), its first hit y, and the path's connection x_k -> y -> light
 * weighted p_B / (p_A + p_B) (above): with g the path's contribution per
 * unit solid angle at x_k, g / (p_A + p_B) =
 *   T_k albedo_k / pi * albedo_y * E_y r_Ly^2 p_A |ng_y . w|
 *     / (p_A r_Ly^2 |ng_y . w| + p_w |ng_y . w_L| r_ky^2)
 * with E_y the light's irradiance at y (its shading normal turned to face
 * x_k, as the bounce from x_k would find it) and a shadow ray x_k - y. */
static void gi__light_vertices(const gi__ref_ctx *c, gi__path *paths, const uint32_t *lanes, uint32_t m,
                               uint32_t pixel0, uint32_t sample, uint32_t k)
{
    const pf_scene *s = c->scene;
    for (uint32_t l = 0; l < s->light_count; l++) {
        const pf_light *L = &s->lights[l];
        if (!gi__light_emits(L)) continue;
        pf_ray rays[PF_RT_WIDTH];
        pf_hit hits[PF_RT_WIDTH];
        float pw[PF_RT_WIDTH];
        uint32_t who[PF_RT_WIDTH], q = 0;
        for (uint32_t j = 0; j < m; j++) {
            if (!(pf_v3_max_comp(paths[lanes[j]].nee_w) > 0.0f)) continue;
            uint32_t pixel = pixel0 + lanes[j];
            pf_vec3 w = gi__light_emit_dir(L, pf_random(pixel, sample, k, 5u + 2u * l),
                                           pf_random(pixel, sample, k, 6u + 2u * l));
            pw[q] = gi__light_emit_pdf(L, w);
            rays[q].org = L->position;
            rays[q].dir = w;
            rays[q].tnear = 0.0f;
            rays[q].tfar = INFINITY;
            who[q++] = lanes[j];
        }
        if (q == 0) continue;
        pf_rt_intersect(c->rt, rays, hits, q);
        pf_ray shadow[PF_RT_WIDTH];
        pf_vec3 add[PF_RT_WIDTH];
        uint32_t to[PF_RT_WIDTH], v = 0;
        for (uint32_t j = 0; j < q; j++) {
            if (hits[j].prim == PF_RT_MISS || !(pw[j] > 0.0f)) continue;
            gi__path *P = &paths[who[j]];
            pf_surface sf;
            pf_rt_surface(c->rt, &hits[j], 0.0f, &sf);
            pf_vec3 d = pf_v3_sub(sf.p, P->p);
            float r2 = pf_v3_dot(d, d);
            if (!(r2 > 0.0f)) continue;
            float r = sqrtf(r2);
            pf_vec3 w = pf_v3_scale(d, 1.0f / r);
            float pa = gi__bounce_pdf(P->n_bounce, P->ng_front, w);
            if (!(pa > 0.0f)) continue;
            /* y's normals turned to face x_k, as 2b turns them for a bounce */
            pf_vec3 ns_y = pf_v3_dot(sf.ng, w) > 0.0f ? pf_v3_scale(sf.ns, -1.0f) : sf.ns;
            gi_light_sample ls;
            if (!gi_light_irradiance(L, sf.p, ns_y, &ls)) continue;
            float rl2 = ls.distance * ls.distance;
            float cw = fabsf(pf_v3_dot(sf.ng, w));
            float num = pa * rl2 * cw, den = num + pw[j] * fabsf(pf_v3_dot(sf.ng, rays[j].dir)) * r2;
            if (!(den > 0.0f) || !(num > 0.0f)) continue;
            float f = num / den;
            if (k == 1 && c->clamp_b > 0.0f) f *= gi__clamp_factor(c->clamp_b, P->p, P->ns, sf.p, ns_y);
            pf_vec3 albedo = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
            add[v] = pf_v3_mul(pf_v3_mul(P->nee_w, albedo), pf_v3_scale(ls.irradiance, f));
            shadow[v].org = pf_rt_offset_origin(P->p, P->ng, w);
            shadow[v].dir = w;
            shadow[v].tnear = 0.0f;
            shadow[v].tfar = r * (1.0f - 1.0e-4f); /* short of y, which lies on its surface */
            to[v++] = who[j];
        }
        if (v == 0) continue;
        uint8_t occ[PF_RT_WIDTH];
        pf_rt_occluded(c->rt, shadow, occ, v);
        for (uint32_t j = 0; j < v; j++)
            if (!occ[j]) paths[to[j]].L = pf_v3_add(paths[to[j]].L, add[j]);
    }
}

/* One sample index for n <= 8 neighbouring pixels of row y: traces their paths
 * together and adds each path's radiance to acc. */
static void gi__trace_packet(const gi__ref_ctx *c, uint32_t x0, uint32_t y, uint32_t n, uint32_t sample,
                             double acc[PF_RT_WIDTH][4])
{
    const pf_scene *s = c->scene;
    gi__path paths[PF_RT_WIDTH];
    for (uint32_t i = 0; i < n; i++) {
        gi__path *P = &paths[i];
        memset(P, 0, sizeof *P);
        P->ray = gi_reference_camera_ray(c->camera, c->width, c->height, x0 + i, y, sample);
        P->T = pf_v3(1.0f, 1.0f, 1.0f);
        P->alive = 1;
    }
    /* Vertex k is the k-th surface the path meets: x1 seen from the camera,
     * x2 .. x_{B+1} after 1 .. B bounces (and x_{B+2}, for its emission
     * only, with no_area_nee: there the emitter seen from x_{B+1} is what NEE
     * at x_{B+1} would have counted). */
    uint32_t last = c->bounces + 1 + (c->no_area_nee ? 1u : 0u);
    for (uint32_t k = 1; k <= last; k++) {
        /* 2a. intersect the live paths as one compacted packet */
        pf_ray rays[PF_RT_WIDTH];
        pf_hit hits[PF_RT_WIDTH];
        uint32_t lanes[PF_RT_WIDTH], m = 0;
        for (uint32_t i = 0; i < n; i++)
            if (paths[i].alive) {
                rays[m] = paths[i].ray;
                lanes[m++] = i;
            }
        if (m == 0) break;
        pf_rt_intersect(c->rt, rays, hits, m);

        /* 2b. emission of the surfaces hit, and the surface frames */
        uint32_t hit_lanes[PF_RT_WIDTH], h = 0;
        /* indirect_only: nothing from x1 itself, neither its emission nor its
         * direct light (NEE at x1, or with no_area_nee the emission of x2). */
        int counts = !(c->indirect_only && k == 1);
        int emits = c->no_area_nee ? !(c->indirect_only && k <= 2) : (k == 1 && !c->indirect_only);
        for (uint32_t j = 0; j < m; j++) {
            gi__path *P = &paths[lanes[j]];
            if (hits[j].prim == PF_RT_MISS) { /* left the scene: no environment light */
                P->alive = 0;
                continue;
            }
            pf_surface sf;
            pf_rt_surface(c->rt, &hits[j], 0.0f, &sf);
            /* Two-sided shading, as the renderer: turn the normals to face the
             * incoming ray (decided by the geometric normal). */
            int back = pf_v3_dot(sf.ng, rays[j].dir) > 0.0f;
            if (k == 2 && c->clamp_b > 0.0f)
                P->T = pf_v3_scale(P->T, gi__clamp_factor(c->clamp_b, P->p, P->ns, sf.p,
                                                          back ? pf_v3_scale(sf.ns, -1.0f) : sf.ns));
            P->prev_p = P->p;
            P->p = sf.p;
            P->ng = sf.ng;
            P->ng_front = back ? pf_v3_scale(sf.ng, -1.0f) : sf.ng;
            P->ns = back ? pf_v3_scale(sf.ns, -1.0f) : sf.ns;
            /* A shading normal that points below the (turned) geometric
             * surface, possible with bad vertex normals, is replaced by ng
             * for the bounce. */
            P->n_bounce = pf_v3_dot(P->ns, P->ng_front) > 0.0f ? P->ns : P->ng_front;
            pf_vec3 albedo = pf_v3(sf.albedo[0], sf.albedo[1], sf.albedo[2]);
            P->nee_w = pf_v3_mul(P->T, pf_v3_scale(albedo, PF_INV_PI));
            if (emits) {
                const float *e = s->materials[sf.material].emission;
                P->L = pf_v3_add(P->L, pf_v3_mul(P->T, pf_v3(e[0], e[1], e[2])));
            }
            /* the throughput of the bounce leaving x_k (used in 2e) */
            P->T = pf_v3_mul(P->T, albedo);
            hit_lanes[h++] = lanes[j];
        }

        /* 2c. next-event estimation to every light (none at x_{B+2}) */
        if (counts && h > 0 && k <= c->bounces + 1) gi__next_event(c, paths, hit_lanes, h, y * c->width + x0, sample, k);

        /* 2d. the light vertices joined to x_k (paths of k bounces) */
        if (c->light_paths && h > 0 && k <= c->bounces)
            gi__light_vertices(c, paths, hit_lanes, h, y * c->width + x0, sample, k);

        /* 2e. continue: a cosine-weighted bounce, throughput *= albedo
         * (f_r cos / pdf = (albedo/pi) cos / (cos/pi)); none after x_{B+1} */
        for (uint32_t j = 0; j < h; j++) {
            gi__path *P = &paths[hit_lanes[j]];
            if (k == last || pf_v3_max_comp(P->T) <= 0.0f) {
                P->alive = 0;
                continue;
            }
            uint32_t pixel = y * c->width + x0 + hit_lanes[j];
            float u0 = pf_random(pixel, sample, k, 0), u1 = pf_random(pixel, sample, k, 1);
            pf_vec3 wi = gi__sample_cosine(P->n_bounce, u0, u1);
            /* Below the geometric surface (interpolated normals only): mirror
             * in its tangent plane, w - 2 (w.ng) ng. Keeps |w| = 1 and the
             * throughput albedo, and the path on the side it arrived from. */
            float d = pf_v3_dot(wi, P->ng_front);
            if (d < 0.0f) wi = pf_v3_sub(wi, pf_v3_scale(P->ng_front, 2.0f * d));
            if (c->light_paths) P->bounce_pdf = gi__bounce_pdf(P->n_bounce, P->ng_front, wi);
            P->ray.org = pf_rt_offset_origin(P->p, P->ng_front, P->ng_front);
            P->ray.dir = wi;
            P->ray.tnear = 0.0f;
            P->ray.tfar = INFINITY;
        }
    }
    /* 3. accumulate (double: 2^20 samples of float radiance lose no bits that matter) */
    for (uint32_t i = 0; i < n; i++) {
        acc[i][0] += paths[i].L.x;
        acc[i][1] += paths[i].L.y;
        acc[i][2] += paths[i].L.z;
        double Y = pf_luminance(paths[i].L); /* for the noise estimate only */
        acc[i][3] += Y * Y;
    }
}

/* The relative standard error of pixel i's mean luminance from its sums of
 * Y and Y^2 over spp samples: sqrt(var / spp) / mean, var the unbiased
 * sample variance; NaN when the mean is 0 or spp is 1. */
static float gi__relative_stderr(const double acc[4], uint32_t spp)
{
    double mean = (0.2126 * acc[0] + 0.7152 * acc[1] + 0.0722 * acc[2]) / spp;
    if (!(mean > 0.0) || spp < 2) return NAN;
    double var = (acc[3] / spp - mean * mean) * spp / (spp - 1);
    return (float)(sqrt(fmax(var, 0.0) / spp) / mean);
}

static void gi__reference_row(void *ctx, uint32_t y, uint32_t worker)
{
    gi__ref_ctx *c = ctx;
    float *out = c->out + (size_t)y * c->width * 3;
    for (uint32_t x0 = 0; x0 < c->width; x0 += PF_RT_WIDTH) {
        uint32_t n = c->width - x0 < PF_RT_WIDTH ? c->width - x0 : PF_RT_WIDTH;
        double acc[PF_RT_WIDTH][4];
        memset(acc, 0, sizeof acc);
        for (uint32_t sample = 0; sample < c->spp; sample++) gi__trace_packet(c, x0, y, n, sample, acc);
        for (uint32_t i = 0; i < n; i++) {
            for (int ch = 0; ch < 3; ch++) out[3 * (x0 + i) + ch] = (float)(acc[i][ch] / c->spp);
            if (c->noise) c->noise[(size_t)y * c->width + x0 + i] = gi__relative_stderr(acc[i], c->spp);
        }
    }
    /* Progress: a relaxed counter (it orders nothing: the image is only read
     * after pf_jobs_parallel_for returns, which synchronises); reported only
     * on the caller's thread so the callback needs no lock. */
    uint32_t done = atomic_fetch_add_explicit(&c->rows_done, 1u, memory_order_relaxed) + 1u;
    if (c->progress && worker == c->caller_worker) c->progress(c->progress_user, done, c->height);
}

/* The options checked and the context filled (c->area points at `area`,
 * which the caller frees with gi_area_lights_free). */
static pf_result gi__reference_setup(gi__ref_ctx *c, gi_area_lights *area, float *out_rgb, const pf_scene *scene,
                                     const pf_rt *rt, pf_jobs *jobs, const pf_camera *camera, uint32_t width,
                                     uint32_t height, const gi_reference_options *opts, pf_error *err)
{
    gi_reference_options o;
    if (opts) o = *opts;
    else memset(&o, 0, sizeof o);
    if (width == 0 || height == 0 || (uint64_t)width * height > 0xffffffffull)
        return pf_error_set(err, PF_ERR_ARGUMENT, "reference: bad image size %ux%u", width, height);
    if (o.direct_only && o.indirect_only)
        return pf_error_set(err, PF_ERR_ARGUMENT, "reference: direct_only and indirect_only exclude each other");
    if (o.bounces > GI_REFERENCE_MAX_BOUNCES)
        return pf_error_set(err, PF_ERR_ARGUMENT, "reference: %u bounces (at most %u)", o.bounces,
                            GI_REFERENCE_MAX_BOUNCES);
    memset(c, 0, sizeof *c);
    c->out = out_rgb;
    c->scene = scene;
    c->rt = rt;
    c->camera = camera;
    c->width = width;
    c->height = height;
    c->spp = o.spp ? o.spp : GI_REFERENCE_DEFAULT_SPP;
    c->bounces = o.direct_only ? 0u : (o.bounces ? o.bounces : GI_REFERENCE_DEFAULT_BOUNCES);
    c->indirect_only = o.indirect_only;
    c->no_area_nee = o.no_area_nee;
    c->light_paths = !o.no_light_paths;
    c->clamp_b = o.clamp > 0.0f && isfinite(o.clamp) ? gi_clamp_bound(scene, o.clamp) : 0.0f;
    pf_result r = gi_area_lights_build(area, scene, err);
    if (r != PF_OK) return r;
    c->area = area;
    c->progress = o.progress;
    c->progress_user = o.progress_user;
    c->noise = o.noise_out;
    c->caller_worker = pf_jobs_thread_count(jobs) - 1u;
    atomic_init(&c->rows_done, 0u);
    return PF_OK;
}

pf_result gi_reference_render(float *out_rgb, const pf_scene *scene, const pf_rt *rt, pf_jobs *jobs,
                              const pf_camera *camera, uint32_t width, uint32_t height,
                              const gi_reference_options *opts, pf_error *err)
{
    gi__ref_ctx c;
    gi_area_lights area;
    pf_result r = gi__reference_setup(&c, &area, out_rgb, scene, rt, jobs, camera, width, height, opts, err);
    if (r != PF_OK) return r;
    /* grain 1: rows cost very different amounts (sky vs. deep corners) */
    pf_jobs_parallel_for(jobs, gi__reference_row, &c, height, 1);
    if (c.progress) c.progress(c.progress_user, height, height);
    gi_area_lights_free(&area);
    return PF_OK;
}

typedef struct gi__pixels_ctx {
    gi__ref_ctx *c;
    const uint32_t *xy;
} gi__pixels_ctx;

/* One listed pixel, traced alone: a packet of one path per sample index.
 * Packets have one fixed width in pf_rt and the random numbers depend only
 * on (pixel, sample, vertex, dimension), so this is the very estimate the
 * pixel gets inside a full image with the same options. */
static void gi__reference_pixel(void *ctx, uint32_t i, uint32_t worker)
{
    (void)worker;
    const gi__pixels_ctx *p = ctx;
    gi__ref_ctx *c = p->c;
    uint32_t x = p->xy[2 * i], y = p->xy[2 * i + 1];
    double acc[PF_RT_WIDTH][4];
    memset(acc, 0, sizeof acc);
    for (uint32_t sample = 0; sample < c->spp; sample++) gi__trace_packet(c, x, y, 1, sample, acc);
    float *out = c->out + ((size_t)y * c->width + x) * 3;
    for (int ch = 0; ch < 3; ch++) out[ch] = (float)(acc[0][ch] / c->spp);
}

pf_result gi_reference_render_pixels(float *out_rgb, const pf_scene *scene, const pf_rt *rt, pf_jobs *jobs,
                                     const pf_camera *camera, uint32_t width, uint32_t height, const uint32_t *xy,
                                     uint32_t count, const gi_reference_options *opts, pf_error *err)
{
    for (uint32_t i = 0; i < count; i++)
        if (xy[2 * i] >= width || xy[2 * i + 1] >= height)
            return pf_error_set(err, PF_ERR_ARGUMENT, "reference: pixel (%u, %u) is outside the %ux%u image",
                                xy[2 * i], xy[2 * i + 1], width, height);
    gi__ref_ctx c;
    gi_area_lights area;
    pf_result r = gi__reference_setup(&c, &area, out_rgb, scene, rt, jobs, camera, width, height, opts, err);
    if (r != PF_OK) return r;
    c.progress = NULL;
    gi__pixels_ctx p = {&c, xy};
    if (count) pf_jobs_parallel_for(jobs, gi__reference_pixel, &p, count, 1);
    gi_area_lights_free(&area);
    return PF_OK;
}

double gi_reference_noise(const float *noise, const float *rgb, size_t pixel_count, float floor)
{
    double s = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < pixel_count; i++) {
        float Y = 0.2126f * rgb[3 * i] + 0.7152f * rgb[3 * i + 1] + 0.0722f * rgb[3 * i + 2];
        if (!(Y > floor) || !(noise[i] == noise[i])) continue;
        s += noise[i];
        n++;
    }
    return n ? s / (double)n : 0.0;
}
