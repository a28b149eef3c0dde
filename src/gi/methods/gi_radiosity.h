/* gi_radiosity: the radiosity of a surface point by path tracing with
 * next-event estimation, the estimator Sequential Monte Carlo Instant
 * Radiosity uses for its VPLs (Hedman 2017 Sec. 3.2.3: "16 samples from a
 * path tracer with next event estimation", seeded per VPL so the estimate
 * of one VPL stays the same over its life).
 *
 * What it estimates: the irradiance E(y) arriving at a point y on the side
 * its normal n faces, from
 *   - punctual lights (gi_light.h units: E = I cos / r^2), exact per vertex;
 *   - area lights (gi_area.h: emissive triangles of radiance Le, one-sided
 *     unless two-sided), one point per vertex and sample, chosen by power:
 *       E ~ Le cos_y cos_l / (r^2 pdf_area);
 *   - light that reached y after 1 .. bounces-1 further diffuse bounces:
 *     a cosine-weighted direction (pdf cos / pi) to the next vertex z gives
 *     E ~ pi L(z) = albedo(z) E(z), with E(z) estimated the same way.
 * So with bounces = B, a VPL at y carries the light of paths with up to B
 * diffuse reflections before the camera's point, as Instant Radiosity with
 * B bounces does (gi_ir.c) and the reference's --bounces B (gi_reference.h).
 * Emission met by a bounce ray is not added: area lights are counted by
 * next-event estimation only (no double counting). The radiance y reflects
 * (its "radiosity" in the paper's Eq. 4-6) is L(y) = albedo(y) / pi E(y).
 *
 * Random numbers: a counter hash of (seed, sample, vertex, dimension), so
 * a sample's path does not depend on the order work is done in. */
#ifndef GI_RADIOSITY_H
#define GI_RADIOSITY_H

#include <stdint.h>

#include "pf_rt.h"
#include "pf_scene.h"
#include "gi_area.h"

#define GI_RADIOSITY_MAX_SPP 256
#define GI_RADIOSITY_MAX_BOUNCES 16

typedef struct gi_radiosity_ctx {
    const pf_scene *scene;
    const pf_rt *rt;
    const gi_area_lights *area; /* may be NULL or empty */
    uint32_t spp;               /* samples, 1 .. GI_RADIOSITY_MAX_SPP */
    uint32_t bounces;           /* 1: direct light at y only; 1 .. GI_RADIOSITY_MAX_BOUNCES */
} gi_radiosity_ctx;

/* A float in [0, 1) from a 64-bit seed and three counters (SplitMix64
 * finaliser, the same construction as pf_random). */
float gi_radiosity_random(uint64_t seed, uint32_t a, uint32_t b, uint32_t c);
/* The diffuse bounce ray from surface point p: a cosine-weighted direction
 * around the unit shading normal ns (Malley's method, pdf cos / pi),
 * mirrored about the geometric surface (normal ng) where it points below
 * it, from p pushed off along ng (pf_rt_offset_origin), t in [0, inf):
 * every diffuse bounce of the estimates and SMC's line 5 rays. */
pf_ray gi_radiosity_bounce_ray(pf_vec3 p, pf_vec3 ns, pf_vec3 ng, float u0, float u1);
/* A well-mixed 64-bit word from two counters, for deriving seeds. */
uint64_t gi_radiosity_hash(uint64_t a, uint64_t b);

/* The mean over ctx->spp samples of the irradiance E(y) at point p (on the
 * surface: it is pushed off along ng by the ray-offset rule) with unit
 * geometric normal ng and shading normal ns, both turned to the side the
 * estimate is for. RGB, W/m^2. Pure function of its arguments. */
pf_vec3 gi_radiosity_irradiance(const gi_radiosity_ctx *ctx, pf_vec3 p, pf_vec3 ng, pf_vec3 ns, uint64_t seed);

/* ---------------------------------------------------------------- the two halves
 *
 * An estimate in two halves, for callers that estimate the same point again
 * when only the punctual lights have moved (SMC's line 18 under a moving
 * light). The paths' vertices, their throughputs and the area-light samples
 * (area lights do not move) depend on the point, the seed, spp, bounces and
 * the scene, never on the punctual lights:
 *   gi_radiosity_trace   the light-independent half: every path's vertices
 *                        and its area-light sample at each vertex;
 *   gi_radiosity_gather  the light-dependent half: the punctual lights'
 *                        shadow rays at y and at every vertex, and the sum.
 * gather(trace(...)) returns the bits gi_radiosity_irradiance returns: the
 * per-path sums are added in the same order (vertex by vertex, the lights in
 * scene order, then that vertex's area sample) and the paths in sample
 * order; how rays are grouped into Embree packets does not change a ray's
 * result (pf_rt.h). Both take `count` estimates at once, so their rays fill
 * the packets. */

/* An estimate's point: on the surface, normals turned to the estimate's side. */
typedef struct gi_radiosity_site {
    pf_vec3 p, ng, ns;
} gi_radiosity_site;

/* Vertex j of one path (j = 0 is y itself), light-independent. */
typedef struct gi_radiosity_vertex {
    pf_vec3 p, ng, ns; /* normals turned to the side the light arrives on */
    pf_vec3 T;         /* throughput: the albedos of the vertices after y */
    pf_vec3 area;      /* the area-light sample's T Le cos_y cos_l / (r^2 pdf), when `flags` has LIT */
    uint32_t flags;    /* GI_RADIOSITY_ALIVE: the path reached this vertex; GI_RADIOSITY_LIT: area adds */
} gi_radiosity_vertex;

#define GI_RADIOSITY_ALIVE 1u
#define GI_RADIOSITY_LIT 2u

/* Vertex records one estimate needs: spp x bounces (both clamped as the
 * estimator clamps them), stored v[j * spp + s] for path s, vertex j. */
uint32_t gi_radiosity_vertex_count(const gi_radiosity_ctx *ctx);

/* The light-independent half of `count` estimates: estimate e at y[e] with
 * seed seeds[e] writes its gi_radiosity_vertex_count records to v[e]. */
void gi_radiosity_trace(const gi_radiosity_ctx *ctx, const gi_radiosity_site *y, const uint64_t *seeds, uint32_t count,
                        gi_radiosity_vertex *const *v);

/* The light-dependent half: out[e] = E(y[e]) with the scene's punctual
 * lights now, from the records v[e] that gi_radiosity_trace wrote for it
 * (with the same ctx: spp, bounces, scene, area lights). */
void gi_radiosity_gather(const gi_radiosity_ctx *ctx, const gi_radiosity_site *y,
                         const gi_radiosity_vertex *const *v, uint32_t count, pf_vec3 *out);

#endif
