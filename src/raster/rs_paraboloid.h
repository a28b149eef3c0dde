/* rs_paraboloid: exact paraboloid shadow maps for virtual point lights.
 *
 * This work is based on:
 * - Brabec, Annen, Seidel: Shadow mapping for hemispherical and
 *   omnidirectional light sources (CGI 2002): the paraboloid mapping.
 * - Laine, Saransaari, Kontkanen, Lehtinen, Aila: Incremental Instant
 *   Radiosity for Real-Time Indirect Illumination (EGSR 2007), Sec. 4.6 (one
 *   paraboloid shadow map per new VPL) and Sec. 6 (256x256 maps, 16-bit
 *   depth; the scene had to be tessellated because the paraboloid projection
 *   bends straight edges).
 * - Hedman, Karras, Lehtinen: Sequential Monte Carlo Instant Radiosity (TVCG
 *   2017), Sec. 4 (128x128 maps, resampled from cube maps to avoid the
 *   tessellation) and Sec. 5.4 (memory: 2048 maps).
 *
 * softgi needs neither tessellation nor resampling: every texel is decided
 * exactly. Per texel the ray from the VPL along the texel centre's direction
 * is intersected with each triangle whose conservative image bound contains
 * the centre (edge tests in the ray's space, watertight, see rs_paraboloid.c),
 * and the nearest distance is kept. The result is the map a ray tracer shoots
 * through the texel centres, bit for bit up to float rounding at edges.
 *
 * Mapping (the VPL frame: normal n is +z, tangents t = x, b = y from
 * pf_v3_basis(n); local p = ((q-o).t, (q-o).b, (q-o).n)):
 *   direction d (unit, d.z >= 0)  ->  (u, v) = (d.x, d.y) / (1 + d.z)
 *   (u, v) in the unit disc       ->  d = (2u, 2v, 1 - u^2 - v^2) / (1 + u^2 + v^2)
 * This is the stereographic projection from -n: the hemisphere maps onto the
 * unit disc, great circles (the images of straight edges) onto circles.
 * Texel (i, j) of an R x R map covers [-1, 1]^2 with its centre at
 *   u_i = (2i + 1 - R) / R,  v_j = (2j + 1 - R) / R,
 * stored at map[j * R + i] (row j = v, column i = u). A texel is inside iff
 * its centre is inside the unit disc, decided in integers:
 * (2i+1-R)^2 + (2j+1-R)^2 <= R^2 (never equal). About pi/4 of the texels
 * are inside; the others hold RS_PARA_OUTSIDE.
 *
 * Storage: one uint16 per texel, nothing else per map (a 128x128 map is
 * 32 KiB, so 2048 maps are exactly 64 MiB). Codes:
 *   0 .. RS_PARA_MAX_CODE  distance t from the VPL, quantised with the
 *                          call's `range`: code = min(floor(t * S), MAX_CODE),
 *                          S = RS_PARA_CODES / range. The code brackets the
 *                          distance: code/S <= t < (code+1)/S (one step =
 *                          range / 65534; hits beyond `range` clamp to
 *                          MAX_CODE and read back as nearer than they are);
 *   RS_PARA_EMPTY          inside the disc, nothing hit;
 *   RS_PARA_OUTSIDE        texel centre outside the unit disc.
 * rs_para_default_range gives the scene's bounding-box diagonal (times 1.01),
 * so no hit between two points of the scene clamps.
 *
 * Lookup (rs_para_visible): the texel whose square contains the point's
 * (u, v) (nearest texel centre; points whose texel is outside the disc use
 * the nearest inside texel along the same radius). The point is visible iff
 *   |p - o| <= (code + 1) / S + bias,
 * i.e. it is compared with the upper end of the code's interval, so the
 * quantisation never shadows a surface by itself; it can let light through
 * an occluder closer than one step (range / 65534: 0.8 mm on Sibenik, 0.05
 * units = 0.15 mm on the conference room) behind the point. The bias must
 * cover the texel footprint: a receiver at distance d is compared with the
 * depth of the texel centre's ray, which sees the receiver's plane up to
 * w * tan(theta) away (w = rs_para_texel_world_size, theta = angle between
 * the receiver's normal and the direction to the VPL); a bias of
 * w * (1 + tan(theta)) (theta clamped as rs_shadow does) is the usual choice
 * (rs_para_bias). The tests compare rendered maps texel by texel (same
 * directions), where the codes of two correct maps differ by at most 1.
 *
 * Receiver-plane test (the frame's default for exact maps; beyond the
 * papers, which use a constant or slope-scaled bias): the stored code is
 * the distance along the texel centre's ray, so the receiver is compared
 * at that ray rather than at its own direction. With c = (2 uc, 2 vc,
 * 1 - rc) the texel centre's direction times 1 + rc (uc = (2i + 1 - R) / R,
 * rc = uc^2 + vc^2) and nl the receiver's normal in the map's frame, the
 * receiver's plane meets that ray at s = (nl . d)(1 + rc) / (nl . c);
 * s is clamped to the slope bias's window [|d| - b, |d| + b] (b the bias
 * above; a grazing or backward plane takes |d| - b, so the test is never
 * looser than the slope test by more than its tolerance) and the point is
 * visible iff s <= (code + 1) / S + 0.75 w + 2 steps (RS_PARA_PLANE_EPS).
 * A lit plane then needs no footprint bias, so the light the slope bias
 * lets through where a receiver meets an occluder stays out: against
 * ray-traced visibility (IIR, 1024 VPLs, no interleaving, indirect light,
 * the scenes' default views) the error per pixel falls from 3.5% to 2.9% on
 * Sibenik, 3.9% to 2.9% on the conference room and 8.9% to 6.0% on Sponza,
 * the energy from +1.5%, +3.4%, +4.2% to -1.0%, +0.4%, +0.7%; the Cornell
 * box stays at 7% (docs/frame.md, "Paraboloid lookup"). The tolerance
 * trades the acne of concave corners and curved tessellations (the texel
 * centre's ray meets the neighbouring face first) against the leak. The
 * receiver's normal is the G-buffer's (shading) normal; the window bounds
 * the error of a curved or normal-mapped surface. Imperfect shadow maps
 * keep the slope bias (their depths are splats, not texel-centre rays).
 *
 * Determinism: every map is written by one job item from read-only inputs;
 * the depth kept per texel is the minimum over triangles (order-free); the
 * SIMD paths (rs_para_kernels.c, written once over the SIMD vocabulary:
 * AVX-512 16 lanes, AVX2 8) evaluate the same float expressions as the
 * scalar compile of the same kernels (no FMA, IEEE sqrt and division), so the
 * bytes are the same for any thread count and SIMD path (tested). Release
 * and Debug builds give the same bytes too (the golden hash test runs in
 * both).
 *
 * Speed: against Embree used directly (16-wide coherent packets over 4x4
 * texels, `softgi bench raster`, docs/perf.md), one 128x128 map takes
 * softgi 1.5x (Sibenik) and 2.3x (conference room) as long on AVX-512 with
 * 1 thread, since the front end's compress-stores no longer go to memory
 * (src/base/simd/simd_avx512.h); the real-time issue's target (2x faster
 * than Embree) is open. Levels of detail (rs_para_options.lod,
 * rs_para_lod.h) buy 1.1-1.2x within 0.5% of the texels (docs/raster.md).
 *
 * Geometry: all triangles are two-sided occluders, alpha masks are ignored
 * (shadow geometry only; the Embree reference honours them, so compare on
 * opaque scenes). Triangles through the VPL (VPL in their plane) cast
 * nothing. */
#ifndef RS_PARABOLOID_H
#define RS_PARABOLOID_H

#include <stddef.h>
#include <stdint.h>

#include "pf_anim.h"
#include "pf_jobs.h"
#include "pf_result.h"
#include "pf_rt.h"
#include "pf_scene.h"
#include "rs_raster.h"

#define RS_PARA_DEFAULT_RES 128u
#define RS_PARA_MIN_RES 4u
#define RS_PARA_MAX_RES 4096u
#define RS_PARA_DEFAULT_CLUSTER 64u
#define RS_PARA_EMPTY 0xFFFFu
#define RS_PARA_OUTSIDE 0xFFFEu
#define RS_PARA_MAX_CODE 0xFFFDu
/* Number of distance codes; one step is range / RS_PARA_CODES. */
#define RS_PARA_CODES 65534.0f
/* rs_para_bias: tan(theta) is clamped here (grazing receivers). */
#define RS_PARA_TAN_MAX 8.0f
/* The receiver-plane test (header, "Lookup"): its tolerance is
 * RS_PARA_PLANE_EPS w + 2 steps, and a plane
 * whose normal makes a cosine of at most RS_PARA_PLANE_MIN_COS with the
 * texel centre's ray (or meets it behind the VPL) is taken at the near end
 * of its window. */
#define RS_PARA_PLANE_EPS 0.75f
#define RS_PARA_PLANE_MIN_COS 1.0e-4f
/* rs_para_options.lod: largest factor. */
#define RS_PARA_MAX_LOD 16.0f

/* Zero-initialised means defaults. */
typedef struct rs_para_options {
    uint32_t resolution;   /* texels per side (0: RS_PARA_DEFAULT_RES), RS_PARA_MIN_RES..RS_PARA_MAX_RES */
    uint32_t cluster_size; /* triangles per cluster (0: RS_PARA_DEFAULT_CLUSTER), 16..1024, multiple of 16 */
    int force_scalar;      /* 1: the scalar reference path, whatever the CPU has (0: the widest it has) */
    float lod;             /* levels of detail (rs_para_lod.h): per map and spatial group of triangles, the
                              coarsest simplified level whose error is at most lod x the smallest texel
                              footprint at the group's distance; 0: none, the exact maps (0..RS_PARA_MAX_LOD) */
} rs_para_options;

/* What a render call did, summed over its maps (integers: order-free). */
typedef struct rs_para_stats {
    uint64_t maps;
    uint64_t clusters_in;              /* clusters x maps */
    uint64_t clusters_behind;          /* wholly behind the tangent plane (or between texel centres) */
    uint64_t clusters_occluded;        /* nearer geometry already covers their image */
    uint64_t triangles_in;             /* triangles of the clusters drawn */
    uint64_t triangles_behind;         /* all vertices at z <= 0 */
    uint64_t triangles_between_texels; /* bound holds no texel centre */
    uint64_t triangles_occluded;       /* nearer geometry already covers their bound */
    uint64_t triangles_drawn;          /* set up exactly and scanned */
    uint64_t texels_tested;            /* texel centres given the exact test */
    uint64_t texels_exact_fallback;    /* edge tests that needed the double path */
    uint64_t lod_levels;               /* levels of detail: the levels drawn, summed over groups and maps */
} rs_para_stats;

typedef struct rs_para_context rs_para_context;

/* Builds the scene-lifetime data: triangles copied in scene order (structure
 * of arrays), clusters of cluster_size consecutive triangles with bounding
 * spheres, the texel direction tables. `scene` may be freed afterwards; it may
 * be a simplified copy (rs_simplify.h). Fails on an empty scene, bad options
 * or out of memory. */
pf_result rs_para_context_create(rs_para_context **out, const pf_scene *scene, const rs_para_options *opts,
                                 pf_error *err);
void rs_para_context_destroy(rs_para_context *ctx);
uint32_t rs_para_resolution(const rs_para_context *ctx);
rs_simd rs_para_simd(const rs_para_context *ctx);
/* Switches the path (tests compare paths on one context); a path the CPU
 * lacks falls back to the next narrower one (AVX-512 -> AVX2 -> scalar). */
void rs_para_set_simd(rs_para_context *ctx, rs_simd simd);

/* Bytes of one map and of `count` maps (no per-map overhead). */
static inline size_t rs_para_map_bytes(uint32_t resolution)
{
    return (size_t)resolution * resolution * sizeof(uint16_t);
}
static inline size_t rs_para_atlas_bytes(uint32_t resolution, uint32_t count)
{
    return rs_para_map_bytes(resolution) * count;
}
/* The scene's bounding-box diagonal times 1.01: the default `range`. */
float rs_para_default_range(const pf_scene *scene);

/* Renders maps[0..count): map k (R*R codes at atlas + k*R*R) for the VPL at
 * positions[k] with normal normals[k] (any length > 0; normalised here),
 * one job item per map over `jobs` (NULL: on the caller's thread), with
 * per-worker scratch owned by the context (grown on first use, so the call
 * is not reentrant on one context). range > 0: the quantisation range.
 * stats may be NULL. */
void rs_para_render(uint16_t *atlas, rs_para_context *ctx, pf_jobs *jobs, const pf_vec3 *positions,
                    const pf_vec3 *normals, uint32_t count, float range, rs_para_stats *stats);
/* The same with map k written to slot slots[k] of the atlas (atlas +
 * slots[k] * R * R; the slots distinct): maps scattered over an atlas (the
 * VPLs a method moved this frame) are spread over the workers in one call.
 * slots NULL: slot k. */
void rs_para_render_slots(uint16_t *atlas, rs_para_context *ctx, pf_jobs *jobs, const pf_vec3 *positions,
                          const pf_vec3 *normals, const uint32_t *slots, uint32_t count, float range,
                          rs_para_stats *stats);

/* rs_para_render_slots restricted to what moved geometry can change: for
 * each map (holding its codes from before the move), only the texels through
 * which the world box [lo, hi] (the moved geometry's bounds before and after
 * it moved) can be seen from the VPL (the cap of the box's bounding sphere)
 * are rendered again; maps the box lies behind are not touched. With
 * `moved` (the ranges pose reported moved, moved_count entries; may be
 * NULL) the cap's 8 x 8 tiles are classed by their old codes: tiles whose
 * old hits are all nearer than the box are kept, tiles whose old hits are
 * all nearer or beyond it are drawn with the moved triangles alone (code =
 * min(old, theirs)), the rest with every triangle (rs_paraboloid.c,
 * rs__render_map). Each texel gets exactly the code a whole render gives,
 * so the maps equal maps rendered afresh (tests/test_moving.c). */
void rs_para_render_box(uint16_t *atlas, rs_para_context *ctx, pf_jobs *jobs, const pf_vec3 *positions,
                        const pf_vec3 *normals, const uint32_t *slots, uint32_t count, float range, pf_vec3 lo,
                        pf_vec3 hi, const pf_anim_moved *moved, uint32_t moved_count, rs_para_stats *stats);

/* Static maps (beyond the papers; docs/raster.md "Static maps"): a map
 * that moved geometry changes is drawn again, over the texels its bounds
 * can be seen through, from a copy of the map of the geometry that cannot
 * move, instead of from every triangle behind the bounds.
 *
 * rs_para_set_dynamic declares the triangle ranges that may move (entries
 * flagged `moved`, as pf_anim_pose reports them; the clusters holding any
 * of their triangles are the dynamic ones, the rest static). *grew = 1 when
 * a cluster became dynamic: static maps drawn before are stale (draw them
 * again with rs_para_render_split). Fails for levels of detail or a range
 * outside the context.
 *
 * rs_para_render_split is rs_para_render_slots that also writes each map's
 * static map (the static clusters alone) to the same slot of static_atlas:
 * the static map, copied, then the dynamic clusters drawn over it (min of
 * the codes: the bytes of rs_para_render_slots). Without levels of detail
 * only (with them, static_atlas is left alone).
 *
 * rs_para_render_box_split is rs_para_render_box given the static maps of
 * the same slots (drawn for the same positions and normals since the
 * static geometry last changed): the tiles whose old codes the moved bounds
 * may have made (class ALL) start from the static codes and take the
 * dynamic clusters' over them, with the moved-only tiles. Every moved range
 * must lie in the declared dynamic ones, else the maps are drawn as
 * rs_para_render_box draws them. The maps equal maps rendered afresh. */
pf_result rs_para_set_dynamic(rs_para_context *ctx, const pf_anim_moved *ranges, uint32_t count, int *grew,
                              pf_error *err);
void rs_para_render_split(uint16_t *atlas, uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                          const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                          float range, rs_para_stats *stats);
void rs_para_render_box_split(uint16_t *atlas, const uint16_t *static_atlas, rs_para_context *ctx, pf_jobs *jobs,
                              const pf_vec3 *positions, const pf_vec3 *normals, const uint32_t *slots, uint32_t count,
                              float range, pf_vec3 lo, pf_vec3 hi, const pf_anim_moved *moved, uint32_t moved_count,
                              rs_para_stats *stats);

/* Brings the context's copy of the triangles and its cluster spheres up to
 * date after the scene's positions changed in place (pf_anim_pose) for the
 * ranges reported moved. Fails for a context with levels of detail (their
 * simplified meshes cannot follow: make the context again) or a range
 * outside the scene. */
pf_result rs_para_context_update(rs_para_context *ctx, const pf_scene *scene, const pf_anim_moved *moved,
                                 uint32_t count, pf_error *err);

/* The reference: the same maps traced with Embree, one ray per inside texel
 * centre along its direction (pf_rt_intersect, 8-wide packets), quantised the
 * same way. For tests and the bench. */
void rs_para_render_traced(uint16_t *atlas, uint32_t resolution, const pf_rt *rt, pf_jobs *jobs,
                           const pf_vec3 *positions, const pf_vec3 *normals, uint32_t count, float range);

/* ---------------------------------------------------------------- mapping */

/* The VPL frame: o = position, n = normalised normal, t and b from
 * pf_v3_basis(n). */
typedef struct rs_para_frame {
    pf_vec3 o, t, b, n;
} rs_para_frame;
rs_para_frame rs_para_frame_make(pf_vec3 position, pf_vec3 normal);
/* World point -> local coordinates (z along n). */
pf_vec3 rs_para_to_local(const rs_para_frame *f, pf_vec3 p);

/* Unit local direction (d.z >= 0) -> (u, v); d.z = -1 has no image. */
static inline pf_vec2 rs_para_dir_to_uv(pf_vec3 d)
{
    float k = 1.0f / (1.0f + d.z);
    pf_vec2 r = {d.x * k, d.y * k};
    return r;
}
/* (u, v) -> unit local direction (d.z >= 0 inside the unit disc). */
static inline pf_vec3 rs_para_uv_to_dir(pf_vec2 uv)
{
    float s = uv.x * uv.x + uv.y * uv.y;
    float k = 1.0f / (1.0f + s);
    return pf_v3(2.0f * uv.x * k, 2.0f * uv.y * k, (1.0f - s) * k);
}
/* Centre of texel (i, j) and whether it is inside the disc. */
pf_vec2 rs_para_texel_uv(uint32_t resolution, uint32_t i, uint32_t j);
int rs_para_texel_inside(uint32_t resolution, uint32_t i, uint32_t j);
/* The inside texel a local direction (any length, z may be < 0: it is
 * clamped to the horizon) is looked up in: its (u, v)'s texel, or the nearest
 * inside texel on the same radius. */
uint32_t rs_para_texel_of(uint32_t resolution, pf_vec3 d_local);
/* The texel (u, v) (the stereographic coordinates rs_para_texel_of computes
 * for z > 0) is looked up in: its own, or the nearest inside texel on the
 * same radius. */
uint32_t rs_para_texel_of_uv(uint32_t resolution, float u, float v);

/* The code stored for local direction d (any length > 0). */
uint16_t rs_para_fetch(const uint16_t *map, uint32_t resolution, pf_vec3 d_local);
/* The distance that code stands for, the upper end of its interval
 * ((code + 1) * range / RS_PARA_CODES); INFINITY for EMPTY and OUTSIDE. */
float rs_para_decode(uint16_t code, float range);
/* Distance at world direction `dir` from the VPL (INFINITY: nothing hit). */
float rs_para_depth(const uint16_t *map, uint32_t resolution, float range, const rs_para_frame *f, pf_vec3 dir);

/* World size of one texel at distance `dist` along local direction d (unit):
 * the angle a texel spans there is (2 / R) * 2 / (1 + u^2 + v^2) radians
 * (d(theta) = 2 d(rho) / (1 + rho^2) for rho = tan(theta / 2)). */
float rs_para_texel_world_size(uint32_t resolution, float dist, pf_vec3 d_local);
/* The suggested bias for a receiver at p with geometric normal ng (either
 * orientation): w * (1 + min(tan(theta), RS_PARA_TAN_MAX)) + 2 steps. */
float rs_para_bias(uint32_t resolution, float range, const rs_para_frame *f, pf_vec3 p, pf_vec3 ng);
/* 1 if world point p is visible from the VPL: in front of its tangent plane
 * and no nearer than the stored distance + bias (see the header). */
/* The one paraboloid lookup: rs_para_visible with rs_para_bias's bias,
 * fused, the bias (texel footprint and quantisation terms) multiplied by
 * bias_scale (1 for exact maps: x 1 is exact; imperfect shadow maps pass
 * their own scale, gi_ism.h). `cos_receiver` is the cosine between the
 * receiver's normal and the direction to the VPL. With plane_n (the
 * receiver's unit normal, either orientation) the test is the
 * receiver-plane test of the header's "Lookup" (bias_scale is then
 * ignored); NULL gives the slope-scaled bias test. rs_para_visible_lanes
 * (rs_para_lookup.h) is this function over the SIMD vocabulary, SIMD_W
 * points at a time, with the same bits. */
int rs_para_visible_scaled(const uint16_t *map, uint32_t resolution, float range, const rs_para_frame *f,
                           pf_vec3 p, const pf_vec3 *plane_n, float cos_receiver, float bias_scale);
int rs_para_visible(const uint16_t *map, uint32_t resolution, float range, const rs_para_frame *f, pf_vec3 p,
                    float bias);

#endif
