/* app_bench_embree: the Embree baselines of `softgi bench raster`: each job
 * the rasterizer does, done by Embree as fast as Embree does it, so the
 * bench's ratios say how softgi compares with a well-used ray tracer.
 *
 * What "as fast as Embree does it" means here (Embree 3 API manual:
 * rtcIntersect4/8/16, RTCIntersectContext, rtcSetSceneFlags,
 * rtcSetSceneBuildQuality):
 * - Embree's API directly, not pf_rt: pf_rt recomputes every hit in double
 *   precision for bit-exact images (pf_rt.h) and traces fixed 8-wide
 *   packets; a baseline pays for neither.
 * - Its own scene: robust mode off (RTC_SCENE_FLAG_NONE: no watertight edge
 *   test), built once, outside the timing, at RTC_BUILD_QUALITY_MEDIUM
 *   (HIGH traced no faster: app_bench_embree.c).
 * - Ray packets as wide as the ISA's SIMD registers (16 lanes on AVX-512,
 *   8 on AVX2, 4 below), each over a compact block of pixels or texels
 *   (4x4, 4x2, 2x2), traced with RTC_INTERSECT_CONTEXT_FLAG_COHERENT.
 * - Image passes as one job item per 16x16-pixel tile on softgi's job system
 *   (pf_jobs.h), so 1 and 2 threads compare as the rasterizer's do;
 *   paraboloid maps as one job item per map, as rs_para_render does.
 * - Each pass writes what the rasterizer's pass writes, in its layout:
 *   the visibility buffer's reversed depth zs = znear / view depth (0:
 *   nothing) and triangle id; the whole G-buffer (rs_gbuffer.h: view depth,
 *   position, camera-facing unit shading normal, albedo, triangle id);
 *   paraboloid maps' 16-bit distance codes (rs_paraboloid.h); cube/spot
 *   shadow maps' reversed depth per face (rs_shadow.h).
 *
 * Attributes come from the hit as cheaply as Embree allows: position
 * org + t dir, Embree's u, v for the vertex normals (fetched and
 * interpolated here; rtcInterpolate is a call per ray), Embree's geometric
 * normal for the facing test, the material's base colour (textures are
 * sampled at mip 0 where a material has one; `bench raster` loads none).
 * Every triangle is opaque: alpha masks are ignored (the bench's scenes
 * have none).
 *
 * Not for images: Embree's hits differ in their last bits between
 * processors and ISAs (pf_rt.h), and edges are not watertight. */
#ifndef APP_BENCH_EMBREE_H
#define APP_BENCH_EMBREE_H

#include <stdint.h>

#include "pf_isa.h"
#include "pf_jobs.h"
#include "pf_result.h"
#include "pf_scene.h"
#include "rs_gbuffer.h"
#include "rs_shadow.h"

typedef struct app_embree app_embree;

/* Builds the device and scene for `scene` (which must outlive it). isa: a
 * resolved ISA (not AUTO) to pin Embree to; it also picks the packet
 * width. build_threads: Embree's threads for the build only. */
pf_result app_embree_create(app_embree **out, const pf_scene *scene, pf_isa isa, uint32_t build_threads,
                            pf_error *err);
void app_embree_destroy(app_embree *e);
/* Rays per packet (16, 8 or 4) and the build's wall time. */
uint32_t app_embree_packet_width(const app_embree *e);
double app_embree_build_ms(const app_embree *e);

/* Visibility buffer of `cam` at width x height: depth[i] = znear / view
 * depth of the nearest hit beyond znear (0: none), prim[i] its triangle
 * (RS_GBUFFER_EMPTY: none); rs_render's outputs. */
void app_embree_visibility(float *depth, uint32_t *prim, const app_embree *e, pf_jobs *jobs, const pf_camera *cam,
                           uint32_t width, uint32_t height);
/* The whole G-buffer of `cam` at g's size: every plane the rasterized
 * visibility buffer and rs_gbuffer_resolve fill together. */
void app_embree_gbuffer(rs_gbuffer *g, const app_embree *e, pf_jobs *jobs, const pf_camera *cam);
/* Paraboloid maps as rs_para_render makes them (same atlas layout, codes
 * and texel directions), one ray per inside texel centre. */
void app_embree_paraboloid(uint16_t *atlas, const app_embree *e, pf_jobs *jobs, uint32_t resolution,
                           const pf_vec3 *positions, const pf_vec3 *normals, uint32_t count, float range);
/* Every face of a perspective (cube or spot) shadow map, as rs_shadow_render
 * renders them: map->depth. */
void app_embree_shadow(rs_shadow_map *map, const app_embree *e, pf_jobs *jobs);

#endif
