/* rs_simplify: a simplified copy of a scene's geometry for shadow maps.
 *
 * Laine et al. 2007 (Sec. 6, Fig. 6) render their paraboloid maps from a
 * separate, *tessellated* copy of the scene (Sibenik: 80K -> 109K
 * triangles) because GPU rasterization draws straight edges straight.
 * softgi's paraboloid maps are exact on any mesh (rs_paraboloid.h), so the
 * separate shadow copy can go the other way: fewer triangles, bought with a
 * measured loss of accuracy. This module makes that copy with meshoptimizer
 * (Kapoulkine, meshoptimizer 0.18: meshopt_generateVertexRemap,
 * meshopt_simplify, an edge-collapse simplifier with quadric error metrics
 * after Garland & Heckbert 1997):
 *   1. weld: vertices with bit-identical positions become one (normals,
 *      uvs and materials are ignored: shadow geometry only). Flat-shaded
 *      scenes store three vertices per triangle, so without this nothing
 *      could collapse;
 *   2. simplify towards ratio * triangles, stopping early if the deformation
 *      would exceed max_error (relative to the mesh extent);
 *   3. compact: unused vertices dropped, triangles kept in the simplifier's
 *      output order, degenerate ones (repeated index or zero area) dropped.
 * The result is a plain pf_scene (one white material, smooth vertex normals,
 * no uvs, lights or cameras): rs_para_context_create and pf_rt_create take it
 * like the full scene. What it costs in accuracy is measured by
 * tests/test_paraboloid.c (test_simplified_accuracy; the numbers are in the
 * header of that file). */
#ifndef RS_SIMPLIFY_H
#define RS_SIMPLIFY_H

#include <stdint.h>

#include "pf_result.h"
#include "pf_scene.h"

/* Zero-initialised means defaults. */
typedef struct rs_simplify_options {
    float ratio;     /* target triangle count / input count, in (0, 1] (0: 0.5) */
    float max_error; /* meshopt target_error, relative to the mesh extent (0: 1, i.e. the ratio decides) */
    int lock_border; /* 1: keep vertices on open borders in place (meshopt_SimplifyLockBorder) */
} rs_simplify_options;

typedef struct rs_simplify_report {
    uint32_t tri_in, tri_out;
    uint32_t vertex_in, vertex_welded, vertex_out;
    float error_relative; /* meshopt's result_error: deformation / mesh extent */
    float error_absolute; /* the same in scene units */
} rs_simplify_report;

/* Fills *dst (zeroed first; free with pf_scene_free) with the simplified
 * geometry of src. report may be NULL. Fails on bad options, an empty scene
 * or out of memory. */
pf_result rs_simplify_scene(pf_scene *dst, const pf_scene *src, const rs_simplify_options *opts,
                            rs_simplify_report *report, pf_error *err);

#endif
