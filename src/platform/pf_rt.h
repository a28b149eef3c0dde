/* pf_rt: the one thin ray-query interface through which softgi reaches
 * Embree 3. Every sampling-side ray (primary rays of the --raytrace path,
 * shadow rays, VPL tracing, path tracing) goes through here.
 *
 * Reproducibility (README "Determinism"):
 * - The device is created with `ignore_config_files=1` (no ~/.embree3 can
 *   change results), `isa=` pinned when --isa names one, and an error
 *   callback that prints a clear message.
 * - The scene is built at RTC_BUILD_QUALITY_MEDIUM (the high-quality
 *   spatial-split builder is not deterministic) with RTC_SCENE_FLAG_ROBUST
 *   (watertight edges: no light leaks between triangles sharing an edge).
 * - One fixed query width, PF_RT_WIDTH = 8, for every query: single rays and
 *   batches of any size are all traced as 8-wide packets (rtcIntersect8 /
 *   rtcOccluded8) with inactive lanes masked off, so a ray gives the same
 *   bits whether it is traced alone or with others (tested).
 * - FTZ/DAZ are set on every thread that queries (pf_fpenv.h).
 * - Closest hits return t, u, v recomputed in double precision from the
 *   triangle Embree found, never Embree's own (its rcp() approximation
 *   differs between processors), so results are the same on every machine
 *   and every Embree ISA (README "Determinism").
 *
 * Alpha-masked materials (alphaMode MASK) are honoured by Embree filter
 * functions: a hit whose texture alpha is below the cutoff is ignored. */
#ifndef PF_RT_H
#define PF_RT_H

#include <stdint.h>

#include "pf_isa.h"
#include "pf_scene.h"

#define PF_RT_WIDTH 8
#define PF_RT_MISS 0xffffffffu

typedef struct pf_rt pf_rt;

typedef struct pf_ray {
    pf_vec3 org;
    float tnear;
    pf_vec3 dir; /* need not be unit length; t is in units of |dir| */
    float tfar;
} pf_ray;

/* What a closest-hit query returns. prim == PF_RT_MISS for no hit. */
typedef struct pf_hit {
    float t;
    uint32_t prim; /* triangle index into the scene */
    float u, v;    /* barycentrics of vertices 1 and 2 */
} pf_hit;

/* Builds the Embree device and scene for `scene` (which must outlive it).
 * isa: a resolved ISA (not AUTO) to pin Embree to; build_threads: Embree's
 * BVH build threads (1 for bit-exact builds regardless of --threads). */
pf_result pf_rt_create(pf_rt **out, const pf_scene *scene, pf_isa isa, uint32_t build_threads, pf_error *err);
void pf_rt_destroy(pf_rt *rt);
const pf_scene *pf_rt_scene(const pf_rt *rt);

/* Closest hits for rays[0..count), in packets of PF_RT_WIDTH. */
void pf_rt_intersect(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint32_t count);
/* The same with Embree's own t, u, v (not recomputed): faster (about 20% on
 * a primary-ray pass over Sibenik), but their last bits depend on the
 * processor. For benchmarks that compare with Embree, never for images. */
void pf_rt_intersect_embree(const pf_rt *rt, const pf_ray *rays, pf_hit *hits, uint32_t count);
/* Occlusion: occluded[i] = 1 if anything lies on rays[i] within (tnear, tfar). */
void pf_rt_occluded(const pf_rt *rt, const pf_ray *rays, uint8_t *occluded, uint32_t count);

/* Convenience single-ray forms (same 8-wide path, one lane active). */
pf_hit pf_rt_intersect1(const pf_rt *rt, pf_ray ray);
int pf_rt_occluded1(const pf_rt *rt, pf_ray ray);

/* Interpolates the surface of a hit (pf_scene_surface); `lod` is the texture mip level. */
void pf_rt_surface(const pf_rt *rt, const pf_hit *hit, float lod, pf_surface *out);

/* A ray origin pushed off a surface along its geometric normal, towards the
 * side `towards` points to, by an offset that scales with the coordinate
 * magnitude (float spacing), so secondary rays do not re-hit their own
 * surface. */
pf_vec3 pf_rt_offset_origin(pf_vec3 p, pf_vec3 ng, pf_vec3 towards);

#endif
