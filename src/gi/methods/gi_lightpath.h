/* gi_lightpath: the light paths of Instant Radiosity (Keller 1997; survey
 * Sec. 4.1, Eq. 6) that `ir` and `mir` both trace: a light chosen by power,
 * a first segment from it, and a VPL at every diffuse hit with Russian
 * roulette by albedo. The methods differ only in their random numbers (IR:
 * a fixed Halton sequence; MIR: per-frame hashed numbers), so the numbers
 * are passed in.
 *
 * Emission (per path, light l chosen with probability p_l proportional to
 * its power):
 *   point:       direction uniform on the sphere, Phi = 4 pi I / p_l
 *   spot:        direction uniform on the outer cone's cap,
 *                Phi = I * cone(w) * 2 pi (1 - cos outer) / p_l
 *   directional: origin uniform on a disc of the scene's bounding radius R
 *                across the beam, Phi = E pi R^2 / p_l
 *   area lights: a point by power (gi_area.h), a cosine-weighted direction,
 *                Phi = pi Le / (pdf_area p_l)
 * At each surface hit a VPL with intensity Phi * albedo / pi; the path goes
 * on with probability q = min(1, max albedo), Phi *= albedo / q, in a
 * cosine-weighted direction (pdf cos / pi cancels the BRDF's cos / pi). */
#ifndef GI_LIGHTPATH_H
#define GI_LIGHTPATH_H

#include "gi_vpl.h"

#define GI_LIGHTPATH_MAX_LIGHTS 64 /* punctual lights considered (+1 entry for all area lights) */

/* The light-choice CDF: the scene's punctual lights by luminance power,
 * then (entry np, when the scene has emitters) all area lights together. */
typedef struct gi_lightpath_lights {
    const pf_scene *scene;
    const gi_area_lights *area;
    double total, cdf[GI_LIGHTPATH_MAX_LIGHTS + 1];
    uint32_t np, nl; /* punctual lights, all entries */
    pf_vec3 centre;  /* of the scene bounds */
    float radius;    /* half the bounds' diagonal, x 1.001 */
} gi_lightpath_lights;

/* Fills c; c->nl == 0 or c->total == 0 when nothing emits. */
void gi_lightpath_lights_init(gi_lightpath_lights *c, const pf_scene *scene, const gi_area_lights *area);

/* Luminance-weighted power of a punctual light (W), the measure lights are
 * chosen by: 4 pi I, I x the spot's cone solid angle, E pi R^2. */
double gi_lightpath_light_power(const pf_light *l, double radius);

/* The numbers one emission uses, each in [0, 1). */
typedef struct gi_lightpath_numbers {
    double choice; /* picks the light */
    float u1, u2;  /* point lights: direction; spots: direction; directional: disc point; area: point */
    double area;   /* area lights: picks the emitter triangle */
    float a1, a2;  /* area lights: the cosine-weighted direction */
} gi_lightpath_numbers;

/* Starts a path: the first segment and its flux Phi. Returns the chosen
 * entry (np: the area lights). Requires c->nl > 0 and c->total > 0. */
uint32_t gi_lightpath_emit(const gi_lightpath_lights *c, const gi_lightpath_numbers *u, pf_ray *ray, pf_vec3 *phi);

/* The entry `choice` picks and its [lo, hi) range of choice * total (IR
 * reuses the position inside the range to pick an area-light triangle). */
uint32_t gi_lightpath_choose(const gi_lightpath_lights *c, double choice, double *lo, double *hi);

/* Light path `hi` (>= 1) with IR's numbers, the Halton sequence: choice,
 * u1, u2 in the primes 2, 3, 5; for an area light the triangle from the
 * choice's position inside the area lights' range of the CDF and the
 * direction from 7 and 11; then per bounce k three more primes (the
 * direction's two, Russian roulette's one), from the 4th (or 6th) on.
 * Writes a VPL (gi_lightpath_hit: no id, moved) per hit, at most `bounces`
 * and at most `max`, and returns how many. */
uint32_t gi_lightpath_trace_halton(const gi_lightpath_lights *c, const pf_rt *rt, uint32_t hi, uint32_t bounces,
                                   uint32_t max, gi_vpl *out);
/* gi_lightpath_trace_halton for the `count` paths hi0 .. hi0 + count - 1 at
 * once, segment by segment, so each segment's rays share Embree packets:
 * path i writes its hits to out[i * bounces ..] and their number to
 * got[i], the same bits as count calls of gi_lightpath_trace_halton with
 * max = bounces (a ray's result does not depend on its packet, pf_rt.h). */
void gi_lightpath_trace_halton_batch(const gi_lightpath_lights *c, const pf_rt *rt, uint32_t hi0, uint32_t count,
                                     uint32_t bounces, gi_vpl *out, uint32_t *got);
/* Traces `ray`; on a hit writes the VPL (position pushed off the surface,
 * normal facing the photon, intensity Phi * albedo / pi, id and moved = 1
 * left to the caller) and the surface albedo, and returns 1; 0 on a miss. */
int gi_lightpath_hit(const pf_rt *rt, pf_ray ray, pf_vec3 phi, gi_vpl *v, pf_vec3 *albedo);

/* Russian roulette and the next segment after VPL v: returns 0 when the path
 * ends (rr >= q), else updates phi and ray with the direction (a1, a2). */
int gi_lightpath_bounce(const gi_vpl *v, pf_vec3 albedo, float rr, float a1, float a2, pf_vec3 *phi, pf_ray *ray);

#endif
