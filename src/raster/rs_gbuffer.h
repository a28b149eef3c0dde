/* rs_gbuffer: the G-buffer every shading stage reads (Laine 2007 Sec. 3,
 * step 1: "render the scene from the camera into a G-buffer").
 *
 * Layout: structure of arrays, one plane per attribute, row-major from the
 * top-left pixel, so a shading job that walks a tile touches only the planes
 * it needs. Filled by the rasterizer or by Embree
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

#include <stddef.h>
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

/* Zeroed memory for an image plane, 64-byte aligned (so 64-pixel tiles of a
 * row whose length is a multiple of 16 share no cache line between the
 * threads that write them); free with free(). NULL when out of memory. */
void *rs_plane_alloc(size_t bytes);

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
/* The camera-free per-triangle constants of the resolve, 128 bytes a
 * triangle (two cache lines): a resolve that starts a new triangle reads one
 * entry instead of the index, three positions, three normals, three uvs and
 * the material, spread over the scene's arrays. rs_context keeps one table
 * per scene (rs_context_resolve_table). Bit-identical to computing them per
 * setup: the same operations on the same values. */
typedef struct rs_resolve_tri {
    pf_vec3 p0, e1, e2;   /* p1 - p0, p2 - p0 */
    pf_vec3 n_det;        /* e2 x e1 */
    pf_vec3 ng;           /* unit geometric normal, normalize(e1 x e2) */
    pf_vec3 n0, n1, n2;   /* vertex normals */
    pf_vec2 uv0, uv1, uv2;
    uint32_t material;
    int32_t textured;     /* the material has a baseColor texture */
} rs_resolve_tri;

/* NULL when out of memory. */
rs_resolve_tri *rs_resolve_table_create(const pf_scene *scene);
/* Refills the entries of triangles [first, first + count) from the scene
 * (their positions or normals changed). */
void rs_resolve_table_update(rs_resolve_tri *table, const pf_scene *scene, uint32_t first, uint32_t count);
void rs_resolve_table_destroy(rs_resolve_tri *table);

/* The same as rs_gbuffer_resolve, bit for bit (tests/test_raster.c
 * test_gbuffer_simd_resolve), with the table when `table` is not NULL and,
 * where simd is an rs_simd other than RS_SIMD_SCALAR (0), SIMD_W pixels at a
 * time (1 = RS_SIMD_AVX2: 8 pixels; 2 = RS_SIMD_AVX512: 16): each group on
 * up to SIMD_W / 2 untextured triangles is resolved once per triangle for
 * all lanes and blended (rs_gbuffer_kernels.c, written once over the SIMD
 * vocabulary); other groups take the scalar code pixel by pixel. */
void rs_gbuffer_resolve_simd(rs_gbuffer *g, const pf_scene *scene, const rs_resolve_tri *table, const pf_camera *cam,
                             pf_jobs *jobs, int simd);

#endif
