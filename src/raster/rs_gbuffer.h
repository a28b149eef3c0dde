/* rs_gbuffer: the G-buffer every shading stage reads (Laine 2007 Sec. 3,
 * step 1: "render the scene from the camera into a G-buffer").
 *
 * Layout: structure of arrays, one plane per attribute, row-major from the
 * top-left pixel, so a shading job that walks a tile touches only the planes
 * it needs. Filled by the rasterizer (issue "rasterizer") or by Embree
 * primary rays (gi_raytrace.c, the --raytrace reference path).
 *
 * Conventions
 * - depth: view-space distance along the camera's forward axis (not along
 *   the ray), +inf where nothing is hit.
 * - pos/nrm: world space; nrm is the unit shading normal turned to face the
 *   camera (softgi shades every surface two-sided; README).
 * - albedo: linear RGB baseColor (texture-filtered).
 * - prim: triangle index into the scene, RS_GBUFFER_EMPTY where nothing is hit. */
#ifndef RS_GBUFFER_H
#define RS_GBUFFER_H

#include <stdint.h>

#include "pf_jobs.h"
#include "pf_result.h"
#include "pf_scene.h"

#define RS_GBUFFER_EMPTY 0xffffffffu

typedef struct rs_gbuffer {
    uint32_t width, height;
    float *depth;
    float *pos_x, *pos_y, *pos_z;
    float *nrm_x, *nrm_y, *nrm_z;
    float *alb_r, *alb_g, *alb_b;
    uint32_t *prim;
    float *ray_sx, *ray_sy; /* resolve scratch: width + 1 and height + 1 screen offsets */
} rs_gbuffer;

/* Allocates all planes (zeroed; depth +inf, prim EMPTY). */
pf_result rs_gbuffer_init(rs_gbuffer *g, uint32_t width, uint32_t height, pf_error *err);
void rs_gbuffer_free(rs_gbuffer *g);
void rs_gbuffer_clear(rs_gbuffer *g);

/* Deferred attribute resolve of a visibility buffer: g->prim holds the
 * triangle per pixel (written by rs_render); for each covered pixel the
 * camera ray through its centre is intersected with the triangle's plane,
 * which gives perspective-correct barycentrics, the view depth (t along a
 * ray whose forward component is 1) and, from the rays through the
 * neighbouring pixel centres, the uv footprint that picks the texture mip
 * level. Attributes are interpolated as pf_scene_surface does on the
 * ray-traced path (same formulas; the per-triangle terms are cached).
 * Barycentrics are clamped to the triangle (a pixel centre covered by the
 * snapped triangle may lie a hair outside the exact one). Parallel over
 * rows, deterministic. */
void rs_gbuffer_resolve(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs);
/* The same with 8 pixels at a time where simd is nonzero (an AVX2 path for
 * runs of 8 pixels on one untextured triangle, the scalar code elsewhere);
 * bit-identical to rs_gbuffer_resolve (tests/test_raster.c
 * test_gbuffer_simd_resolve). simd 0 is rs_gbuffer_resolve. */
void rs_gbuffer_resolve_simd(rs_gbuffer *g, const pf_scene *scene, const pf_camera *cam, pf_jobs *jobs, int simd);

#endif
