/* pf_defaults: what softgi assumes when a scene or the command line leaves
 * something out, so that any scene "just works":
 *
 * - no camera (none in the file, no --camera, no sequence camera keys):
 *   pf_defaults_camera frames the scene from its bounds. If the bounds'
 *   centre is enclosed (most of 26 rays from it hit geometry: a cathedral,
 *   a room, an atrium) the eye goes inside, near the more open end of the
 *   longer horizontal axis, looking down it (or, if that end is open, out
 *   in front of the opening, looking in); otherwise it stands outside,
 *   in front (+Z, 17 degrees up), with the bounding sphere filling 80% of
 *   the vertical field of view. fovy is 60 degrees.
 * - no light (no punctual light, no emissive triangle, no --light):
 *   pf_defaults_light puts a white point light just above the camera's
 *   eye whose intensity gives the surfaces at the median first-hit distance
 *   of the camera's rays an irradiance of APP_DEFAULT_IRRADIANCE (1 W/m^2;
 *   E = I cos(theta) / r^2, pf_scene.h's light units).
 * - --exposure auto: pf_defaults_exposure maps the log-average luminance
 *   of the lit pixels (Reinhard et al. 2002, Eq. 1) to 18% grey after the
 *   tone map x / (1 + x) (pf_imageio.h), i.e. to x = 0.18 / 0.82.
 * - pf_defaults_nearly_black: whether 99% of the pixels display darker
 *   than APP_DARK_LUMINANCE, for the one-line hint.
 *
 * All are pure functions of their inputs. The rays are cast by brute force
 * over the triangles, not through Embree (pf_rt.h): the camera is chosen
 * while the scene loads, before the ISA is resolved and the Embree scene
 * built, and a plain loop in one fixed order gives the same camera on every
 * ISA and machine. 26 + 50 rays over the conference room's 331k triangles
 * take about 0.1 s, once, and only for scenes without a camera or light.
 * Alpha-masked holes count as hits. The app prints what was chosen in the
 * --camera / --light syntax (app_scene.c), so it can be copied. */
#ifndef PF_DEFAULTS_H
#define PF_DEFAULTS_H

#include <stdint.h>

#include "pf_scene.h"

#define APP_DEFAULT_FOVY_DEG 60.0f
#define APP_DEFAULT_IRRADIANCE 1.0f /* W/m^2 at the median first-hit distance */
#define APP_DEFAULT_GREY 0.18f      /* what --exposure auto makes the log-average after the tone map */
#define APP_DARK_LUMINANCE 0.01f    /* "nearly black": 99% of pixels below this, exposed, before the tone map */

/* The camera pf_defaults_camera chooses. */
typedef struct pf_default_camera {
    pf_vec3 eye, target;
    float fovy_deg;
    int interior;        /* the bounds' centre is enclosed: the eye is inside */
    uint32_t hits, rays; /* of the enclosure test from the centre */
    char axis;           /* interior: 'x' or 'z', the axis looked down */
    int open_end;        /* interior: the end the eye is at is open; the eye stands outside it */
} pf_default_camera;

/* A camera for `scene` (validated: bounds computed, >= 1 triangle). Eye and
 * target lie within PF_SCENE_MAX_COORD and differ. */
void pf_defaults_camera(pf_default_camera *out, const pf_scene *scene);

/* A point light for `scene` seen by `camera` through a width x height image:
 * white, just above the eye (5% of the median distance, at most half way
 * to the surface above), intensity APP_DEFAULT_IRRADIANCE * d^2 within
 * (0, PF_MAX_RADIANCE], d the median first-hit distance of a 7 x 7 grid of
 * the camera's rays (the bounding sphere's radius if none hits). *median
 * gets d. */
void pf_defaults_light(pf_light *out, float *median, const pf_scene *scene, const pf_camera *camera, uint32_t width,
                        uint32_t height);

/* --exposure auto: the stops that take the log-average luminance (BT.709) of
 * the pixels with a positive luminance to APP_DEFAULT_GREY after the tone
 * map, clamped to [-64, 64]; 0 when no pixel is lit. *log_average (may be
 * NULL) gets that average. Summed in double in pixel order: deterministic. */
float pf_defaults_exposure(const float *rgb, uint32_t width, uint32_t height, double *log_average);

/* 1 when fewer than 1% of the pixels have a luminance x 2^exposure of at
 * least APP_DARK_LUMINANCE (their 99th percentile is below it). */
int pf_defaults_nearly_black(const float *rgb, uint32_t width, uint32_t height, float exposure);

#endif
