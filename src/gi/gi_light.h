/* gi_light: irradiance from punctual lights (KHR_lights_punctual), the
 * direct-light term every frame and the reference share.
 *
 * Units (README "Light units"): point and spot lights have radiant
 * intensity I (W/sr), so the irradiance at a surface point at distance r is
 * E = I cos(theta) / r^2, theta between the surface normal and the direction
 * to the light. Spot lights multiply that by the extension's cone
 * attenuation (KHR_lights_punctual, "Inner and Outer Cone Angles"):
 *   t = clamp((cos(a) - cos(outer)) / max(0.001, cos(inner) - cos(outer)), 0, 1)
 *   factor = t * t
 * with a the angle between the spot direction and the direction to the
 * point. Directional lights give E = E0 cos(theta). A Lambertian surface
 * then reflects radiance L = albedo E / pi. */
#ifndef GI_LIGHT_H
#define GI_LIGHT_H

#include "pf_rt.h"
#include "pf_scene.h"

typedef struct gi_light_sample {
    pf_vec3 irradiance; /* RGB W/m^2 on the surface, without visibility */
    pf_vec3 wi;         /* unit direction from the point towards the light */
    float distance;     /* to the light; INFINITY for directional */
} gi_light_sample;

/* Spot cone attenuation for cos(angle to the spot axis), as above. */
float gi_light_spot_factor(const pf_light *light, float cos_angle);

/* Unshadowed irradiance at point p with unit normal n. Returns 0 (and zero
 * irradiance) when the light cannot reach the point's front side. */
int gi_light_irradiance(const pf_light *light, pf_vec3 p, pf_vec3 n, gi_light_sample *out);

/* The shadow ray for a light sample at surface point p with geometric
 * normal ng: from p pushed off the surface towards the light, stopping just
 * short of the light (a light lying on a surface does not shadow itself). */
pf_ray gi_light_shadow_ray(const gi_light_sample *ls, pf_vec3 p, pf_vec3 ng);

/* A copy of a scene's lights, to tell later what changed (the direct
 * light's shadow maps, gi_direct.c; IR's unchanged set, gi_ir.c).
 * Zero-initialise; lights compare as bytes, field for field (pf_light has
 * no padding). */
typedef struct gi_light_copy {
    pf_light *v;
    uint32_t count;
} gi_light_copy;
/* 1 when the copy has a light i equal to light i of s. */
int gi_light_copy_same(const gi_light_copy *c, const pf_scene *s, uint32_t i);
/* 1 when the copy holds exactly s's lights (as many, each the same). */
int gi_light_copy_all_same(const gi_light_copy *c, const pf_scene *s);
/* Copies s's lights in; 0 (the copy unchanged) when out of memory. */
int gi_light_copy_take(gi_light_copy *c, const pf_scene *s);
void gi_light_copy_free(gi_light_copy *c);

#endif
