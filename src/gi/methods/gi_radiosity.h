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
/* A well-mixed 64-bit word from two counters, for deriving seeds. */
uint64_t gi_radiosity_hash(uint64_t a, uint64_t b);

/* The mean over ctx->spp samples of the irradiance E(y) at point p (on the
 * surface: it is pushed off along ng by the ray-offset rule) with unit
 * geometric normal ng and shading normal ns, both turned to the side the
 * estimate is for. RGB, W/m^2. Pure function of its arguments. */
pf_vec3 gi_radiosity_irradiance(const gi_radiosity_ctx *ctx, pf_vec3 p, pf_vec3 ng, pf_vec3 ns, uint64_t seed);

#endif
