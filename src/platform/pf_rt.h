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
 * functions: a hit whose texture alpha is below the cutoff is ignored.
 *
 * Moving geometry (glTF animations, pf_anim.h). A scene an
 * animation can move is built with a dynamic split (pf_rt_create_dynamic):
 *
 *   top scene (static BVH over instances, identity transforms)
 *     instance 0: the static triangles, one child scene, built once
 *     instance k: dynamic instanced primitive k, a child scene of its own
 *
 * so after pf_anim_pose rewrote the positions (Embree reads the scene's own
 * arrays: shared buffers), pf_rt_update rebuilds (or refits) only the
 * children of the primitives that moved, then the small top scene. Without
 * anything dynamic (no animation, none that can move a primitive) the scene
 * is one triangle geometry, built exactly as before the split existed: the
 * same BVH and the same bytes for every static scene. The static triangles
 * are one child whatever their order (one geometry per run between the
 * dynamic primitives); pf_hit.prim is always the scene's triangle index
 * (Embree's instance, geometry and primitive ids mapped back).
 *
 * Determinism of updates. Every child scene and the top scene are built
 * with Embree's static builder (no RTC_SCENE_FLAG_DYNAMIC): a commit after
 * a change builds that scene afresh, exactly as a first build does. So in
 * PF_RT_REBUILD mode a pose reached by any sequence of pf_rt_update calls
 * gives the bytes of a fresh pf_rt_create_dynamic of the posed scene with
 * the same split (tested): hits, occlusion, every image. PF_RT_REFIT keeps
 * a moved primitive's BVH topology and refits its boxes (the child scene
 * switched to RTC_SCENE_FLAG_DYNAMIC with RTC_BUILD_QUALITY_LOW, its
 * geometry to RTC_BUILD_QUALITY_REFIT: Embree honours the geometry's
 * quality only in that configuration).
 *
 * What a different BVH can change. A ray that meets a triangle inside,
 * away from its edges, is found whatever the BVH (ROBUST traversal; at the
 * instance level, which Embree 3 traverses with its fast box test only,
 * rounding is monotone, so a child is missed only by rays touching its
 * bounds where its triangles have edges). A ray that meets triangles only
 * at their edges or vertices (a ray through a shared edge, the corner of a
 * box, within a few ulps) is decided by Embree's float arithmetic, whose
 * path through the BVH and its leaves differs: it may hit one of them,
 * another, or pass between them; and of two triangles hit at the same
 * distance (coplanar ones) either may be returned. So REFIT gives
 * REBUILD's answer for every ray except those edge cases, occlusion
 * included (tested: each difference is such a case; 294 of 163840 rays of
 * test_rt_update, which aims a fifth of them at vertices and edges), and
 * the split differs from one geometry (a scene loaded without its
 * animations, or before the split existed) in the same way: an animated
 * scene's images are not byte for byte those of earlier softgi, while
 * every static scene's are.
 *
 * A REFIT's topology comes from the pose its primitive was first refitted
 * in (the first REFIT of a primitive builds its refittable BVH: a rebuild's
 * cost once), so its quality decays as the pose moves away from that one;
 * a REBUILD call rebuilds every primitive last refitted as well as the
 * moved ones, so REBUILD's guarantee holds again right after it. */
#ifndef PF_RT_H
#define PF_RT_H

#include <stdint.h>

#include "pf_anim.h"
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
 * BVH build threads (1 for bit-exact builds regardless of --threads).
 * One triangle geometry: pf_rt_create_dynamic with anim NULL. */
pf_result pf_rt_create(pf_rt **out, const pf_scene *scene, pf_isa isa, uint32_t build_threads, pf_error *err);

/* The same with the dynamic split (top comment) taken from `anim`, the
 * animation data `scene` was loaded with (perhaps posed since, perhaps
 * with emitters appended after its primitives): every instanced primitive
 * with pf_anim_prim.dynamic and triangles gets a child scene of its own.
 * anim NULL, or without such primitives: one geometry, as pf_rt_create.
 * anim is read here only (the ranges are copied). PF_ERR_INDEX_RANGE when
 * a primitive's ranges lie outside the scene, overlap or are out of order,
 * or when triangles outside a dynamic primitive use its vertices (a moved
 * vertex would then move a static triangle). */
pf_result pf_rt_create_dynamic(pf_rt **out, const pf_scene *scene, const pf_anim *anim, pf_isa isa,
                               uint32_t build_threads, pf_error *err);
void pf_rt_destroy(pf_rt *rt);
const pf_scene *pf_rt_scene(const pf_rt *rt);
/* The dynamic primitives of the split (0: one geometry). */
uint32_t pf_rt_dynamic_count(const pf_rt *rt);

typedef enum pf_rt_update_mode {
    PF_RT_REBUILD = 0, /* the moved primitives' BVHs built afresh: a fresh pf_rt_create_dynamic's bytes */
    PF_RT_REFIT        /* their boxes refitted: the same answers except for rays at triangle edges (top comment) */
} pf_rt_update_mode;

/* Brings Embree up to date after pf_anim_pose rewrote the scene's positions:
 * `moved` is pose's report (count entries, usually anim->prim_count); each
 * entry with `moved` set and triangles must be a dynamic primitive of the
 * split (its triangle and vertex ranges exactly), or, for a pf_rt of one
 * geometry, lie inside the scene (the one geometry is then rebuilt: a
 * fresh pf_rt_create's bytes again). Entries without `moved` are only
 * range-checked. Then the moved primitives' child scenes are rebuilt or
 * refitted (mode; REBUILD also rebuilds the ones last refitted), and the
 * top scene over them. No query may run meanwhile. Every entry is checked
 * before anything is touched: PF_ERR_INDEX_RANGE for ranges outside the
 * scene, PF_ERR_ARGUMENT for a moved range that is not a dynamic primitive
 * or a bad mode, and rt is then unchanged. PF_ERR_EMBREE if Embree fails
 * while building: rt must then be destroyed. */
pf_result pf_rt_update(pf_rt *rt, const pf_anim_moved *moved, uint32_t count, pf_rt_update_mode mode,
                       pf_error *err);

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
