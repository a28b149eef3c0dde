/* gi_rsm_area: a reflective shadow map for the area lights (emissive
 * triangles, gi_area.h), so the RSM methods (invtm, tcas, ssvp) light
 * every scene. Beyond the papers: Dachsbacher and Stamminger 2005, Barak
 * 2013 Sec. 3 ("we create reflective shadow map (RSM) for each primary
 * light source") and Aranha Sec. III-A render RSMs of punctual lights
 * only; this module gives an emitter the hemispherical RSM that a
 * Lambertian emitter needs, with the units of gi_rsm.h.
 *
 * Emitter points. The area lights' map has K faces (K = set->area_points);
 * face k is the emitter point the rasterized direct light uses too
 * (gi_frame.h "Area lights"): u0 = (k + 1/2) / K through the power CDF
 * (gi_area_sample_point), (u1, u2) = Halton(k + 1) in bases 2 and 3, so the
 * points are stratified by power and fixed (no random state: the same
 * points every frame, for any thread count). Point k stands for the area
 *   A_k = 1 / (K pdf_area(p_k))
 * (sum_k A_k is the emitters' area in expectation over the points, exactly
 * when the emitters all have one luminance), and, being a patch of a
 * Lambertian emitter of radiance Le, emits the flux pi Le A_k with cosine
 * distribution around its emitting normal n (a two-sided emitter's point
 * emits from the face gi_area_sample_point picked).
 *
 * Hemisphere parametrisation: Shirley and Chiu's concentric map (1997) from
 * the face's square to the unit disc, then Malley's method (the disc point
 * (x, y) lifted to the hemisphere, z = sqrt(1 - x^2 - y^2)). The concentric
 * map preserves area (Jacobian pi / 4 everywhere) and Malley's lift turns
 * disc area into projected solid angle (cos theta d omega = dx dy), so
 * every texel of a size x size face covers exactly the projected solid angle
 *   integral_texel cos theta d omega = pi / size^2,
 * and receives the flux Le A_k pi / size^2 (gi_rsm_face.texel_flux), the
 * same for all texels of the face. The texels of face k sum to pi Le A_k,
 * all of the point's flux, with no texel outside the hemisphere (a
 * paraboloid map, rs_paraboloid.h, wastes the 1 - pi/4 of its texels
 * outside the unit disc and weights the others by 4 cos / (1 + r^2)^2:
 * uniform proposals, TCAS's and SSVP's Hammersley points, would land on
 * dead or unequal texels).
 *
 * Texels: each texel keeps what the ray from face k's point through its
 * centre direction meets first (Embree, pf_rt_intersect, in chunks of 64
 * rays; one job item per row of a face): position, shading and geometric
 * normals turned to face the point, the triangle, and the reflected flux
 * albedo x texel_flux (albedo at mip level 0, as the ray-traced paths, IR,
 * SMC and SSVP's cluster maps take it). A ray that leaves the scene gives
 * an invalid texel (its flux escapes). Only the texel centre's ray is
 * traced, as the punctual maps do.
 *
 * Energy: the map's reflected fluxes sum to albedo-weighted pi sum_k Le A_k
 * (tested: in a closed box of one albedo, albedo x pi Le A exactly to float
 * rounding), so a VPL made from texel v with probability p out of N gets
 * intensity flux_v / (pi N p) exactly as for the punctual maps; the first
 * bounce these VPLs estimate is the K-point quadrature of the emitters
 * (error measured in docs/rsm.md). */
#ifndef GI_RSM_AREA_H
#define GI_RSM_AREA_H

#include <stdint.h>

#include "gi_area.h"
#include "gi_rsm.h"
#include "pf_jobs.h"
#include "pf_result.h"
#include "pf_rt.h"

/* Lays out the area lights' map m for `points` emitter points of `area`
 * (count > 0) at `size` texels per side: kind, light, face_count,
 * texel_count, power and the faces (allocated here, freed with the set).
 * m->first is left to the caller. */
pf_result gi_rsm_area_layout(gi_rsm_map *m, const gi_area_lights *area, uint32_t points, uint32_t size,
                             pf_error *err);

/* Traces and resolves every texel of the set's area map `map` (one job item
 * per face row; jobs may be NULL: on the caller's thread). */
void gi_rsm_area_render(gi_rsm_set *set, uint32_t map, const pf_rt *rt, pf_jobs *jobs);

/* Shirley-Chiu's concentric map: (a, b) in [-1, 1]^2 -> the unit disc,
 * area-preserving (Jacobian pi / 4). */
pf_vec2 gi_rsm_concentric(float a, float b);

/* The unit world direction of texel (x, y) of a size x size face: the
 * concentric image of the texel centre's NDC point (gi_rsm.h) lifted to the
 * hemisphere around face->n. */
pf_vec3 gi_rsm_area_dir(const gi_rsm_face *face, uint32_t size, uint32_t x, uint32_t y);

#endif
