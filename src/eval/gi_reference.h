/* gi_reference: the reference path tracer (`softgi reference`), the ground
 * truth the VPL methods are compared against.
 *
 * This work is based on: Kajiya 1986, "The Rendering Equation" (path
 * tracing), in the notation of the many-light survey, Dachsbacher et al.
 * 2014, Sec. 2: radiance at x1 is the sum over path lengths (Eq. 3) of
 * integrals over paths x1 .. xk of the throughput T_1^k times Le(xk) (Eq. 2),
 * estimated by drawing one path per sample (Eq. 4). Per vertex x:
 *
 *   Lo(x) = Le(x) + albedo/pi * sum_lights E_l(x) V_l(x)        punctual lights: NEE
 *                 + albedo/pi * integral_emitters Le cos cos' / r^2 V dA   area lights: NEE
 *                 + albedo/pi * integral Lr(y(x, wi)) cos dwi   reflected light: BSDF sampling
 *
 * The same sum over path lengths the VPL methods split at x2 (the survey's
 * Eq. 5), so the reference and a VPL image estimate the same quantity.
 *
 * Materials and units are exactly the renderer's (README "Light units",
 * gi_light.h): Lambertian BRDF albedo/pi with albedo = baseColor (mip level 0,
 * as the --raytrace path), point/spot lights in W/sr with the KHR cone
 * factor, directional lights in W/m^2, emission as radiance W/(sr m^2).
 *
 * Bounces (what --bounces B means; default 3). A path starts at the camera,
 * meets its first surface at x1 and is continued by B diffuse bounces to
 * x2 .. x_{B+1}. Emissive triangles are area lights (gi_area.h) exactly as
 * punctual lights are lights: light that leaves a light and is reflected at
 * most B + 1 times (x1 included) counts. The estimator adds
 *   - the emission Le(x1) of the surface the camera sees (two-sided, as the
 *     renderer's compose), and
 *   - at every vertex x1 .. x_{B+1}, next-event estimation: for every
 *     punctual light albedo/pi * E with E = gi_light_irradiance (the
 *     renderer's units exactly) times a shadow ray (pf_rt_occluded), and for
 *     the area lights one emitter point chosen by power, uniform on its
 *     triangle (gi_area_sample_point), albedo/pi * Le cos cos' / (r^2
 *     pdf_area) times a shadow ray (gi_area_sample_irradiance).
 * Emission met by a bounce (x2 ..) is not added: that light path is the one
 * NEE at the previous vertex counts (each light path is counted by exactly
 * one strategy, or by two with weights that sum to one, so the estimate is
 * unbiased; punctual lights could never be hit anyway). So B = 0 is
 * "emission seen directly + direct light of all lights" (what `softgi
 * render` computes), B = 1 adds one-bounce indirect light, and inside a
 * closed sphere of uniform emission Le and albedo rho the expected value is
 * exactly Le * sum_{k=0..B+1} rho^k (-> Le / (1 - rho) as B grows; the
 * furnace test).
 *
 * Light vertices (default; no_light_paths turns them off). NEE alone has
 * unbounded variance when a point light sits close to a surface: a bounce
 * that lands near the Cornell box's light, 1 cm under the ceiling, finds E ~
 * I / r^2 = 10^4 I, and the indirect light of the whole box stays noisy
 * (a relative standard error of about 0.25 per pixel at 1024 spp). So every
 * path vertex x_k with k <= B also gets, per point and spot light, one
 * direction drawn from the light (uniform over the sphere, or within a
 * spot's outer cone), whose first hit y is joined to x_k by a shadow ray:
 * the path x_k -> y -> light of k bounces, the one the bounce from x_k and
 * NEE at x_{k+1} also find. The two strategies are combined with the
 * balance heuristic (Veach 1997, Ch. 9; the bidirectional path tracer's
 * light paths of one vertex, joined to every eye vertex but x_0), weights
 * in gi_reference.c. The connection's own G ~ 1 / r^2 is what NEE handles
 * well, so the variance stays bounded. Directional lights and emitters
 * keep NEE alone. Cost: one more ray and one shadow ray per light and
 * bounce. A light lying exactly on a surface loses what its light vertices
 * at distance ~0 would carry (they are skipped; NEE counts those paths
 * with weight ~0): a vanishing part of the image.
 *
 * no_area_nee (tests only) replaces the area-light NEE by BSDF sampling:
 * the emission Le(xk) of every surface a path hits is added, for x1 .. and
 * x_{B+2} (one segment further, so the same light paths count and the
 * expectation is the same). In the furnace every path of that estimator
 * returns exactly the expected value (zero variance), which NEE on a
 * tessellated sphere does not.
 *
 * indirect_only drops the first-hit terms (Le(x1) and the direct light at
 * x1: NEE at x1, or with no_area_nee the emission of x2): what is left is
 * the light that reached x1 after at least one bounce, the part the VPL
 * methods approximate. direct_only sets B = 0.
 *
 * No Russian roulette: paths stop after B bounces, when they leave the scene
 * or when the throughput is zero (a black surface). The estimate of the
 * truncated sum is unbiased and the work per path bounded by B + 1.
 * Nothing is clamped either (unless clamp_b: below).
 *
 * Sampling. Cosine-weighted directions around the shading normal (Malley's
 * method: a uniform disc point lifted to the hemisphere), pdf = cos/pi, so the
 * throughput update f_r cos / pdf = (albedo/pi) cos / (cos/pi) = albedo
 * exactly. Shading is two-sided like the renderer's: the normal is turned to
 * face the incoming ray. With interpolated normals a direction may fall
 * below the geometric surface although it lies above the shading one; it is
 * then mirrored in the geometric tangent plane (keeps the throughput albedo,
 * so energy is conserved and the path stays on the side it came from; flat
 * meshes never need it).
 *
 * Random numbers: counter-based, a 64-bit hash of (pixel index, sample index,
 * path vertex, dimension) (pf_random), never of the thread, so the
 * image is bit-identical for any thread count. Camera rays go through the
 * pixel jittered uniformly within it (box filter) by the vertex-0 numbers.
 *
 * Parallel structure: one job item per image row; an item traces its pixels
 * 8 at a time (the 8 paths of one sample index travel together, so rays go
 * to Embree as 8-wide packets, the fixed width of pf_rt) and writes only its
 * row. Each pixel sums its samples in sample order (in double), then divides
 * by spp. */
#ifndef GI_REFERENCE_H
#define GI_REFERENCE_H

#include <stdint.h>

#include "pf_jobs.h"
#include "pf_random.h"
#include "pf_result.h"
#include "pf_rt.h"
#include "pf_scene.h"

#define GI_REFERENCE_DEFAULT_SPP 64u
#define GI_REFERENCE_DEFAULT_BOUNCES 3u
#define GI_REFERENCE_MAX_BOUNCES 1024u
/* What the estimator is, for the stamps of cached references (evaluate): a
 * reference made by another estimator is rendered again. */
#define GI_REFERENCE_ESTIMATOR "nee+light-vertices-mis"

/* Progress: rows finished so far out of the image's height. Called only on the
 * thread that called gi_reference_render (the job system's waiting thread
 * helps run rows; it reports after each row it finishes, and once more with
 * rows_done == rows_total at the end), so the callback needs no locking. */
typedef void (*gi_reference_progress_fn)(void *user, uint32_t rows_done, uint32_t rows_total);

/* Zero-initialise for defaults. */
typedef struct gi_reference_options {
    uint32_t spp;      /* samples per pixel; 0: GI_REFERENCE_DEFAULT_SPP */
    uint32_t bounces;  /* B as defined above; 0: GI_REFERENCE_DEFAULT_BOUNCES (use direct_only for B = 0) */
    int direct_only;   /* B = 0: emission seen directly + direct light */
    int indirect_only; /* drop Le(x1) and the direct light at x1 */
    int no_area_nee;   /* emitters only by BSDF sampling (same expectation; for tests) */
    int no_light_paths; /* NEE alone for punctual lights (same expectation, far more noise near a light) */
    /* Clamped path tracing (Hedman 2017 Fig. 8, "path tracing with simulated
     * clamping", `softgi reference --clamp C`): C > 0 bounds the geometry
     * term of the segment x1 - x2 by the frame's b = C / diagonal^2
     * (gi_clamp_bound): the path's throughput from x2 on is scaled by
     * min(1, b / G), G = cos1 cos2 / r^2 with the shading normals turned as
     * the frame turns them, so the estimate is the one a VPL renderer with
     * every VPL at x2 and the same --clamp converges to. 0: off. */
    float clamp;
    gi_reference_progress_fn progress; /* may be NULL */
    void *progress_user;
    /* Optional (NULL: none), width * height floats, caller-owned: each
     * pixel's relative standard error of its mean luminance, sqrt(s^2 / spp)
     * / mean with s^2 the samples' variance (NaN where the mean is 0), so a
     * user can see how far the reference itself is from converged
     * (gi_reference_noise summarises it). gi_reference_render only. */
    float *noise_out;
} gi_reference_options;

/* The mean of the per-pixel relative standard errors over the pixels whose
 * mean luminance exceeds `floor` (the pixels the quality metrics use). */
double gi_reference_noise(const float *noise, const float *rgb, size_t pixel_count, float floor);

/* Renders the reference image into out_rgb (width * height * 3 floats, linear
 * RGB, top row first; caller-owned). rt must be built from `scene`. Returns
 * PF_ERR_ARGUMENT for a zero size, a bounce count above
 * GI_REFERENCE_MAX_BOUNCES or direct_only together with indirect_only. */
pf_result gi_reference_render(float *out_rgb, const pf_scene *scene, const pf_rt *rt, pf_jobs *jobs,
                              const pf_camera *camera, uint32_t width, uint32_t height,
                              const gi_reference_options *opts, pf_error *err);

/* Renders only the `count` pixels (xy[2 i], xy[2 i + 1]) into out_rgb (the
 * same layout as gi_reference_render; other pixels are left as they are).
 * Each listed pixel gets exactly the value gi_reference_render gives it with
 * the same options (same random numbers, the same fixed-width packets):
 * `softgi sequence --reference --track-spp N` uses it to render the tracked
 * pixels with many more samples than the rest of the image. */
pf_result gi_reference_render_pixels(float *out_rgb, const pf_scene *scene, const pf_rt *rt, pf_jobs *jobs,
                                     const pf_camera *camera, uint32_t width, uint32_t height, const uint32_t *xy,
                                     uint32_t count, const gi_reference_options *opts, pf_error *err);

/* Random numbers: pf_random (base/pf_random.h) of (pixel = y * width + x,
 * sample, path vertex, dimension). Vertex 0 is the camera (dimensions 0, 1:
 * the jitter within the pixel); vertex k >= 1 is the bounce leaving x_k
 * (dimensions 0, 1: the hemisphere sample; 2, 3, 4: the area-light sample of
 * the NEE at x_k; 5 + 2 l, 6 + 2 l: the direction leaving punctual light l
 * for the light vertex joined to x_k). */

/* The camera ray of pixel (x, y), sample `sample`: through the pixel at the
 * jittered position (x + u0, y + u1), dir scaled as gi_camera_ray's (t =
 * view depth). Exposed so tests can recompute the exact hit points. */
pf_ray gi_reference_camera_ray(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y,
                               uint32_t sample);

#endif
