/* gi_ism: imperfect shadow maps (ISMs) for VPL visibility.
 *
 * This work is based on:
 * - Ritschel, Grosch, Kim, Seidel, Dachsbacher, Kautz: Imperfect Shadow Maps
 *   for Efficient Computation of Indirect Illumination (SIGGRAPH Asia 2008):
 *   many low-resolution paraboloid depth maps, one per VPL, each made from a
 *   random subset of a point sampling of the scene, all in one atlas, holes
 *   filled by pull-push.
 * - Barak, Bittner, Havran: Temporally Coherent Adaptive Sampling for
 *   Imperfect Shadow Maps (EGSR 2013), Sec. 5.2 (points generated on the fly
 *   per triangle in proportion to its area, by the tessellator, instead of a
 *   stored point cloud; each point splatted into one randomly chosen ISM),
 *   Sec. 3 (pull-push after Marroquim, Kraus, Cavalcanti 2007) and Sec. 6
 *   (defaults: a 2048 x 2048 ISM atlas for 1024 VPLs = 64 x 64 per map).
 *
 * The stages (gi_ism_render), mirroring Barak 2013 Sec. 5.2's pipeline:
 *   gi_ism_stage_clear       every map: inside texels EMPTY (no splat yet),
 *                            outside texels OUTSIDE
 *   gi_ism_stage_splat       per triangle (the tessellation control shader):
 *                            a point count proportional to its area; per
 *                            point (evaluation shader): a stratified
 *                            barycentric position and a seed; (geometry
 *                            shader) one VPL chosen at random from the seed,
 *                            the point projected into its paraboloid map;
 *                            (fragment shader + depth test) the nearest
 *                            depth code kept per texel
 *   gi_ism_stage_pull_push   per map: holes (inside texels no point hit)
 *                            filled from a pyramid of averages (pull) and
 *                            interpolated back down (push)
 *
 * Maps are exactly rs_paraboloid's (rs_paraboloid.h): same stereographic
 * parametrisation, texel layout R x R per map, map k at atlas + k R R, the
 * same 16-bit distance codes (code = floor(t * 65534 / range)), so the
 * frame's lookup (rs_para_visible_scaled and the SIMD accumulation) reads
 * them unchanged; only the test differs: the slope-scaled bias times
 * bias_scale (see GI_ISM_DEFAULT_BIAS), where the exact maps take the
 * receiver-plane test (a splatted depth is not the texel centre's ray).
 *
 * Every VPL's ISM is rebuilt every frame: a map costs a few thousand splats,
 * and the points are regenerated and reassigned to VPLs at random each frame
 * (seeded by triangle id and frame), so no map stays valid.
 *
 * Points (deviations from the papers):
 * - count: triangle i gets n_i = floor(P A_i / A) or one more, the extra one
 *   with probability equal to the fraction (seeded by triangle id and frame):
 *   the expected total is exactly P;
 * - positions: point k of n is u1 = (k + xi_k) / n (stratified), u2 =
 *   frac(k phi + xi) (a golden-ratio lattice, randomly shifted), mapped to
 *   the triangle by the area-preserving warp p = v0 + sqrt(u1) ((1 - u2) e1 +
 *   u2 e2), so the n points cover the triangle evenly;
 * - splat size (Barak 2013 Sec. 5.2's geometry shader "calculates the size
 *   of the splat" without saying how): a point stands for its VPL's share of
 *   the surface, a disc of area A count / P (A: the scene's area, count: the
 *   VPLs); the splat covers the texel the point falls in and every inside
 *   texel whose centre lies within that disc's image (radius r / dist in
 *   radians, (1 + u^2 + v^2) R / 4 texels per radian), capped at
 *   GI_ISM_MAX_SPLAT texels, all at the point's depth. Without it, near
 *   surfaces (few points, large solid angle) let the far surfaces' points
 *   through: Sibenik's ISM/ray agreement was 0.695 with one-texel splats and
 *   0.794 with sized splats (bias 1, test_ism);
 * - pull-push: the plain average pull and bilinear push of Marroquim 2007
 *   without its occlusion test (a pull averaging only children within 10% of
 *   the nearest was tried: Sibenik agreement 0.785 vs 0.789, bias 1.5; an
 *   occlusion test replacing samples 10% behind the coarser level spread
 *   the nearest depth over whole maps: agreement 0.45).
 *
 * Parallelism and determinism: the splat's job items are runs of
 * consecutive triangles of about 4096 expected points (a larger triangle is
 * split into runs of its points). The splat keeps the nearer 16-bit code of
 * a texel, which is order-free, so the maps do not depend on which thread
 * splats which point: by default binned (a batch of items makes splat
 * records, sorted by map per item; then one job item splats a few maps with
 * plain mins from every item's bucket for them), else (atomic_splat, or an
 * item larger than a batch) every point at once by an atomic min; the same
 * maps either way (tested). Clear and pull-push run one map per job item.
 * Same bytes for any thread count (tested).
 *
 * Memory: everything at create (triangles, per-triangle point densities,
 * per-worker pull-push pyramids, the splat's bins: about 14 MB); the bins'
 * generation buffers grow in gi_ism_update when the densities change;
 * gi_ism_render allocates nothing. */
#ifndef GI_ISM_H
#define GI_ISM_H

#include <stddef.h>
#include <stdint.h>

#include "pf_anim.h"
#include "pf_jobs.h"
#include "pf_result.h"
#include "pf_scene.h"
#include "rs_paraboloid.h"

/* Barak 2013 Sec. 6: 2048^2 ISM texels for 1024 VPLs. */
#define GI_ISM_DEFAULT_RES 64u
#define GI_ISM_MIN_RES 8u
#define GI_ISM_MAX_RES 512u
/* Barak 2013 gives no splat count with its Sec. 6 defaults; Table 3 measures
 * 10^4 .. 3.2 10^7 splats. softgi takes the 10^6 row: ~4000 points per map
 * for 256 VPLs (a 64^2 map has 3228 inside texels; a VPL sees about half of
 * its points in front of it, the pull-push fills the rest). */
#define GI_ISM_DEFAULT_POINTS 1000000u
#define GI_ISM_MIN_POINTS 1000u
#define GI_ISM_MAX_POINTS 100000000u
/* Bias: the exact maps' bias, w (1 + tan theta) + 2 code steps (w: the
 * texel's world size at the receiver, rs_para_bias), times this. ISMs need
 * more than exact maps: a texel holds the nearest of the points splatted
 * into it (anywhere in the texel and splat footprint, not the texel centre's
 * ray) or an average over neighbouring texels (pull-push), so a lit
 * receiver's own surface sits up to a few texel footprints nearer than it.
 * 2 was chosen by measurement (indirect-only image against Embree
 * visibility, 256 IR VPLs): Sibenik RMSE 0.00449 / 0.00356 / 0.00340 /
 * 0.00452 and Cornell box 0.0635 / 0.0472 / 0.0443 / 0.0475 for scales
 * 1 / 1.5 / 2 / 3 (README notes); below 2 surfaces shadow themselves, above
 * it light leaks under contacts. */
#define GI_ISM_DEFAULT_BIAS 2.0f
#define GI_ISM_MIN_BIAS 1.0f
/* Largest splat radius in texels (near points; see gi_ism_stage_splat). */
/* Sibenik's ISM/ray agreement (test_ism): cap 2 0.774 vs cap 4 0.789 at
 * bias 1.5; cap 8 0.781 vs cap 4 0.794 at bias 1 (larger flat splats shadow
 * tilted receivers near the VPL). */
#define GI_ISM_MAX_SPLAT 4.0f
#define GI_ISM_MAX_BIAS 64.0f

/* Zero-initialised means defaults. */
typedef struct gi_ism_options {
    uint32_t resolution; /* texels per side, a power of two in GI_ISM_MIN_RES..GI_ISM_MAX_RES (0: 64) */
    uint32_t points;     /* points per frame over the whole scene (0: 10^6) */
    float bias_scale;    /* bias = this x the exact maps' bias (0: GI_ISM_DEFAULT_BIAS) */
    int atomic_splat;    /* 1: splat every point with atomic mins as it is made (the binned splat's
                            fallback; the same maps, tests compare the two) */
} gi_ism_options;

/* What a render did (integers: order-free sums). */
typedef struct gi_ism_stats {
    uint64_t points;       /* generated */
    uint64_t splatted;     /* in front of their VPL */
    uint64_t holes_filled; /* inside texels set by the pull-push */
    uint64_t texels;       /* inside texels of all maps */
} gi_ism_stats;

typedef struct gi_ism gi_ism;

/* Checks the options (PF_ERR_ARGUMENT naming the bad one), copies the
 * triangles and their point densities, sizes the per-worker scratch for
 * `threads` workers (pf_jobs_thread_count of the jobs gi_ism_render will
 * get; 1 for NULL jobs). */
pf_result gi_ism_create(gi_ism **out, const pf_scene *scene, const gi_ism_options *opt, uint32_t threads,
                        pf_error *err);
void gi_ism_destroy(gi_ism *ism);
/* The triangles the ranges reported moved (pf_anim_pose: the scene's
 * positions changed in place) copied again with their areas, and every
 * triangle's point count recomputed from the new total area: a deforming
 * triangle gets points in proportion to its posed area, as Barak 2013 Sec. 5
 * generates them per triangle per frame. Renders after it give the bytes of
 * ISMs created afresh from the posed scene (tests/test_moving.c). Fails for
 * a range outside the scene, a scene whose triangles lost all area or out
 * of memory (the ISMs then keep the old triangles' points but must not be
 * used: make them again). */
pf_result gi_ism_update(gi_ism *ism, const pf_scene *scene, const pf_anim_moved *moved, uint32_t count,
                        pf_error *err);
uint32_t gi_ism_resolution(const gi_ism *ism);
uint32_t gi_ism_points(const gi_ism *ism);
float gi_ism_bias_scale(const gi_ism *ism);

/* Renders the ISMs of VPLs 0..count-1 (frames[k]: VPL k's paraboloid frame)
 * into atlas (count R R codes, rs_paraboloid layout), for frame number
 * `frame` (the seed of the points). range: the quantisation range. stats may
 * be NULL. */
void gi_ism_render(gi_ism *ism, uint16_t *atlas, pf_jobs *jobs, const rs_para_frame *frames, uint32_t count,
                   float range, uint32_t frame, gi_ism_stats *stats);

/* The stages, for tests and the learner (gi_ism_render calls them in order). */
void gi_ism_stage_clear(gi_ism *ism, uint16_t *atlas, pf_jobs *jobs, uint32_t count);
void gi_ism_stage_splat(gi_ism *ism, uint16_t *atlas, pf_jobs *jobs, const rs_para_frame *frames, uint32_t count,
                        float range, uint32_t frame, gi_ism_stats *stats);
void gi_ism_stage_pull_push(gi_ism *ism, uint16_t *atlas, pf_jobs *jobs, uint32_t count, gi_ism_stats *stats);

/* Pull-push on one R x R map (R a power of two): every inside texel holding
 * RS_PARA_EMPTY gets a code interpolated from its neighbourhood; codes and
 * OUTSIDE texels are kept. A map with no code at all stays as it is.
 * scratch: gi_ism_pull_push_scratch_floats(R) floats. Returns the number of
 * texels filled. */
size_t gi_ism_pull_push_scratch_floats(uint32_t resolution);
uint32_t gi_ism_pull_push(uint16_t *map, uint32_t resolution, float *scratch);

#endif
