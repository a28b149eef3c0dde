/* gi_area: area lights, i.e. the scene's emissive triangles as primary
 * lights (Hedman 2017 Sec. 5 lights its scenes with them; the McGuire
 * Cornell box has one).
 *
 * Every triangle whose material has a non-zero emission is an emitter of
 * constant radiance Le (W/(sr m^2), pf_material.emission). It emits from its
 * front face (the counter-clockwise side, pf_scene_face_normal), and from
 * both faces when the material is double-sided. One face of area A emits
 * flux pi A Le (Lambertian emitter); a point light-path sample from it
 * carries Phi = pi A Le / pdf with a cosine-distributed direction.
 *
 * The table is built once per scene (emissive geometry does not move in
 * softgi: moving lights are punctual). Triangles are chosen with a CDF over
 * their luminance power, so bright emitters get more samples. */
#ifndef GI_AREA_H
#define GI_AREA_H

#include <stdint.h>

#include "pf_scene.h"

typedef struct gi_area_light {
    uint32_t prim;        /* scene triangle */
    pf_vec3 v0, e1, e2;   /* point = v0 + s e1 + t e2, s, t >= 0, s + t <= 1 */
    pf_vec3 normal;       /* unit geometric normal of the front face */
    pf_vec3 radiance;     /* Le, RGB */
    float area;           /* m^2 (one face) */
    uint32_t two_sided;   /* emits from both faces */
} gi_area_light;

typedef struct gi_area_lights {
    uint32_t count;
    gi_area_light *tri;
    double *cdf;          /* count entries, cdf[count-1] == total_power */
    double total_power;   /* sum over triangles of faces * pi * A * lum(Le), W */
    pf_vec3 power_rgb;    /* the same sum per channel */
    pf_vec3 centroid;     /* power-weighted centre of all emitters */
} gi_area_lights;

/* Collects the emissive triangles. A scene without any gives count 0. */
pf_result gi_area_lights_build(gi_area_lights *a, const pf_scene *scene, pf_error *err);
void gi_area_lights_free(gi_area_lights *a);

typedef struct gi_area_sample {
    uint32_t index;   /* into a->tri */
    pf_vec3 p;        /* point on the emitter */
    pf_vec3 n;        /* unit normal of the emitting face the sample uses */
    pf_vec3 radiance; /* Le */
    float pdf_area;   /* density of p w.r.t. area over all emitters (and faces) */
} gi_area_sample;

/* Chooses a triangle by power with u0 in [0,1), then a point uniformly on it
 * with (u1, u2) in [0,1)^2 (square-root warp), and for two-sided triangles a
 * face (u0 reused after the CDF search). Requires a->count > 0. */
void gi_area_sample_point(const gi_area_lights *a, double u0, float u1, float u2, gi_area_sample *out);

/* The density gi_area_sample_point gives to a point on triangle `index`
 * (per unit area, one face), for multiple importance sampling. */
float gi_area_pdf(const gi_area_lights *a, uint32_t index);

/* Unshadowed irradiance estimate at receiver point p (unit normal n) from
 * one emitter sample: the area-measure estimator of E = integral Le cos_r
 * cos_e / r^2 dA,
 *   E ~ Le max(0, n.w) max(0, -n_e.w) / (r^2 pdf_area),   w = (sample - p) / r
 * (an emitter point is a cosine emitter: it lights p like a VPL of intensity
 * Le dA). Returns 0 and zero irradiance when a cosine is <= 0 or r = 0;
 * otherwise 1 with the direction to the sample and its distance, so
 * gi_light_shadow_ray gives the shadow ray (it stops just short of the
 * emitter, which therefore does not shadow itself). */
int gi_area_sample_irradiance(const gi_area_sample *s, pf_vec3 p, pf_vec3 n, pf_vec3 *irradiance, pf_vec3 *wi,
                              float *distance);

/* Index of the emitter for scene triangle `prim`, or UINT32_MAX. O(log n). */
uint32_t gi_area_find(const gi_area_lights *a, uint32_t prim);

#endif
