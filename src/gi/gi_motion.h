/* gi_motion: what moved geometry asks of a frame, and
 * what a VPL method is told about it.
 *
 * A rasterizer needs no acceleration structure, so after a pose
 * (pf_anim_pose) the renderer redoes only what the moved geometry can
 * change. The caller first brings the scene-wide structures up to date,
 * then tells the frame:
 *
 *   pf_anim_pose(scene, moved, ...)         positions and normals in place
 *   pf_rt_update(rt, moved, ...)            Embree: refit or rebuild (pf_rt.h)
 *   rs_context_update(raster, moved, ...)   the rasterizer's welded positions,
 *                                           cluster boxes, resolve table
 *   gi_frame_geometry_moved(f, moved, ...)  the frame's own (gi_frame.h):
 *     - the paraboloid contexts' triangle copies (VPL maps, area-light maps:
 *       rs_para_context_update) and the ISM points' triangles and densities
 *       (gi_ism_update: Barak 2013 Sec. 5, points per posed area);
 *     - the direct-light shadow maps: at the next gi_stage_shadow_maps each
 *       face is drawn again only over the tiles the moved geometry's bounds
 *       (before and after) project to (rs_shadow_render_box); faces the
 *       bounds lie outside of are not touched;
 *     - the VPLs' paraboloid maps: at the next gi_stage_vpl_shadow_maps the
 *       maps of VPLs that did not move are drawn again only over the texels
 *       through which the bounds can be seen (rs_para_render_box); maps the
 *       bounds lie behind are not touched; new and moved VPLs get whole
 *       maps as always; with dynamic primitives declared (gi_frame_declare_
 *       dynamic, which this call does for what it is told moved) each map
 *       keeps a static map, and the redraw starts from its codes and draws
 *       the dynamic triangles alone (rs_para_render_box_split);
 *     - the area-light maps likewise, or, when an emitter moved, the
 *       emitters' sampling and their K maps afresh;
 *     - the VPL method: the next update sees a gi_motion (gi_vpl_inputs.
 *       motion) naming the triangles that moved since its last update.
 *
 * The maps equal maps rendered afresh from the posed scene
 * (tests/test_moving.c), so a frame after a move shows the bytes a frame
 * whose maps were all drawn again shows. What the maps were set up with is
 * kept: a VPL map's distance range and a perspective shadow map's near
 * plane come from the scene's bounds when the frame (or the light) was set
 * up; a directional light's box is made again (and its map drawn whole)
 * only when the posed scene leaves the box.
 *
 * How each method reacts (gi_vpl.h; docs/methods.md "Moving geometry"):
 * IR traces its paths again every frame, so it regenerates; IIR's validity
 * test (Laine 2007 Sec. 4.4) also deletes the VPLs that sit on a moved
 * triangle, and its shadow rays (Embree, updated) catch the VPLs a moved
 * object now occludes; ... (the method files say what they do). */
#ifndef GI_MOTION_H
#define GI_MOTION_H

#include <stdint.h>

#include "pf_anim.h"
#include "pf_math.h"

typedef struct gi_motion {
    uint32_t epoch;     /* how many times geometry moved since the frame was made */
    uint32_t tri_count; /* the scene's triangles (tri_moved's length) */
    uint32_t moved;     /* triangles flagged in tri_moved (0: nothing moved since the last update) */
    uint8_t *tri_moved; /* per triangle: 1 if it moved since the method's last update */
    pf_vec3 lo, hi;     /* the moved triangles' bounds before and after (empty when nothing moved) */
    int emitters;       /* an emissive triangle moved: the area lights were sampled again */
    /* the pose reports since the method's last update, merged: entry k is
     * instanced primitive k (pf_anim_moved), `moved` where it moved in any
     * of them, its bounds the union (for a method's own copies of the
     * geometry: rs_context_update of its rasterizer) */
    pf_anim_moved *ranges;
    uint32_t range_count;
} gi_motion;

/* Moved bounds a stage has yet to catch up with (the union of every move
 * since it last ran). */
typedef struct gi_moved_box {
    int pending;
    pf_vec3 lo, hi;
    pf_anim_moved *ranges; /* the pose reports merged as gi_motion.ranges (for rs_para_render_box) */
    uint32_t range_count;
} gi_moved_box;

/* What the last frame redid for moved geometry (for `softgi bench frame
 * --moving-object` and the tests): integers, sums over the frame. */
typedef struct gi_motion_stats {
    uint32_t shadow_faces;      /* shadow-map faces drawn again in part (rs_shadow_render_box) */
    uint32_t shadow_faces_whole; /* drawn whole (a directional box made again) */
    uint64_t shadow_texels;     /* texels they drew */
    uint32_t vpl_maps;          /* kept VPLs' maps drawn again in part (rs_para_render_box) */
    uint64_t vpl_texels;        /* texels tested in them */
    uint32_t area_maps;         /* area-light maps drawn again in part, or whole after an emitter moved */
    uint32_t shadow_tiles;      /* shadow-map tiles drawn for the frame's receivers (rs_shadow_render_needed) */
} gi_motion_stats;

/* 1 if triangle `prim` moved since the method's last update (m may be NULL:
 * nothing moved). */
static inline int gi_motion_tri(const gi_motion *m, uint32_t prim)
{
    return m && m->moved && prim < m->tri_count && m->tri_moved[prim];
}

/* 1 if anything moved since the method's last update. */
static inline int gi_motion_any(const gi_motion *m) { return m && (m->moved || m->emitters); }

/* 1 if point p lies in the moved bounds widened by `margin`. */
static inline int gi_motion_near(const gi_motion *m, pf_vec3 p, float margin)
{
    return gi_motion_any(m) && p.x >= m->lo.x - margin && p.x <= m->hi.x + margin && p.y >= m->lo.y - margin &&
           p.y <= m->hi.y + margin && p.z >= m->lo.z - margin && p.z <= m->hi.z + margin;
}

#endif
