/* rs_para_lod: distance-dependent levels of detail for paraboloid maps
 * (private to src/raster; rs_paraboloid.h documents the option).
 *
 * Why. A 128x128 paraboloid map is small: a texel spans 2/R to 4/R radians,
 * so 20 cm at 4 m from the VPL and 50 cm at 10 m. Every scene triangle in
 * front of the VPL still costs the exact renderer its front end and, when
 * its bound holds a texel centre, its setup and scan, so a detailed scene
 * costs per map in proportion to its triangles, where a ray tracer's cost
 * grows with their logarithm. Laine et al. 2007 (Sec. 6) render their
 * paraboloid maps from a separate copy of the scene (tessellated, for the
 * GPU's straight edges); Hedman et al. 2017 (Sec. 4) resample cube maps.
 * softgi's exact maps need neither, and this module goes the other way: a
 * copy of the scene in spatial groups, each with coarser versions of itself,
 * and per map, per group, the coarsest version whose simplification error
 * stays below a fraction of the texel footprint at the group's distance.
 * The same idea as a terrain or Nanite-style cluster LOD selected by
 * screen-space error, here by texel-space error; beyond the papers.
 *
 * How (rs__lod_build, once per context):
 *   1. groups: triangles sorted by the Morton code of their centroid (10
 *      bits per axis in the scene's box; ties by triangle index), cut into
 *      runs of RS__LOD_GROUP triangles, so a group is compact in space;
 *   2. per group, its corners welded by bit-identical position
 *      (meshopt_generateVertexRemap), then level L >= 1 =
 *      meshopt_simplify(level 0, target 1/2^L of the triangles,
 *      meshopt_SimplifyLockBorder), meshoptimizer 0.18's edge collapse with
 *      quadric error metrics (Garland & Heckbert 1997). Locked borders keep
 *      the group's outline where it was, so neighbouring groups at different
 *      levels leave no cracks between them. Levels stop when one removes
 *      less than 15% of the triangles or none are left; degenerate
 *      triangles are dropped. A level's error is meshoptimizer's result
 *      error in scene units (relative error times meshopt_simplifyScale),
 *      made non-decreasing over the levels: an estimate of how far the
 *      simplified surface lies from the original, not a proven bound;
 *      what it costs in accuracy is measured (rs_paraboloid.h).
 *   3. per group its bounding sphere (level 0's vertices contain every
 *      level's: an edge collapse keeps one of the two vertices).
 * Per map (rs_paraboloid.c): the group's nearest distance d = |c - o| - r
 * gives the smallest texel footprint there, d * 2/R (the angle a texel spans
 * at the disc's rim); the coarsest level with error <= lod * d * 2/R is
 * drawn (lod: rs_para_options.lod). Deterministic: meshoptimizer is
 * single-threaded and depends only on its input arrays. */
#ifndef RS_PARA_LOD_H
#define RS_PARA_LOD_H

#include <stdint.h>

#include "pf_result.h"
#include "pf_scene.h"

#define RS__LOD_LEVELS 8    /* level 0 (the scene's triangles) and up to 7 coarser */
#define RS__LOD_GROUP 2048u /* triangles per group at level 0 */

typedef struct rs__lod_group {
    float cx, cy, cz, r; /* bounding sphere (every level inside it) */
    uint32_t levels;     /* 1..RS__LOD_LEVELS */
    float err[RS__LOD_LEVELS];          /* scene units, err[0] = 0, non-decreasing */
    uint32_t first[RS__LOD_LEVELS];     /* level L: triangles [first, first + count) of rs__lod.tri */
    uint32_t count[RS__LOD_LEVELS];
} rs__lod_group;

typedef struct rs__lod {
    uint32_t group_count;
    rs__lod_group *groups;
    uint32_t tri_count; /* every level of every group */
    pf_vec3 *tri;       /* 3 corners per triangle */
} rs__lod;

/* Builds the groups and levels of `scene`'s triangles. Fails only when out
 * of memory. */
pf_result rs__lod_build(rs__lod *lod, const pf_scene *scene, pf_error *err);
void rs__lod_free(rs__lod *lod);

#endif
