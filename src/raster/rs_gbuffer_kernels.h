/* rs_gbuffer_kernels: the G-buffer resolve's groups of pixels, written once
 * over the SIMD vocabulary (src/base/simd/simd.h) in rs_gbuffer_kernels.c
 * and compiled once per instruction set; rs_gbuffer.c picks a table from
 * the caller's SIMD path. Private to src/raster: the resolve's context and
 * per-triangle constants (see rs_gbuffer.c). */
#ifndef RS_GBUFFER_KERNELS_H
#define RS_GBUFFER_KERNELS_H

#include <stddef.h>
#include <stdint.h>

#include "rs_gbuffer.h"
#include "rs_raster.h"

typedef struct rs__resolve_ctx {
    rs_gbuffer *g;
    const pf_scene *scene;
    const rs_resolve_tri *table; /* per-triangle constants, or NULL: made per setup from the scene */
    const pf_camera *cam;
    float *sx, *sy; /* per column / row: the screen offsets of pixel centres (+1 for the neighbour) */
    const struct rs_gbuffer_kernels *kern; /* groups of SIMD_W pixels on untextured triangles, or NULL: scalar */
} rs__resolve_ctx;

/* Per-triangle constants of the resolve for one camera. With the ray origin
 * o fixed (the eye), Moller-Trumbore's terms that do not involve the
 * direction d are constant per triangle: with tv = o - p0, e1 = p1 - p0,
 * e2 = p2 - p0,
 *   det = d . (e2 x e1),  u = d . (e2 x tv) / det,  v = d . (tv x e1) / det,
 * so a pixel costs three dot products and a division. Pixels come in runs
 * that share a triangle, so the constants are cached across a run; the
 * camera-free part comes from the scene's table (two cache lines) instead
 * of the index, vertex and material arrays. */
typedef struct rs__tri_consts {
    uint32_t prim;
    const rs_resolve_tri *t; /* the table's entry, or &own */
    pf_vec3 n_u, n_v;        /* e2 x tv, tv x e1 */
    rs_resolve_tri own;
} rs__tri_consts;

/* The constants of triangle prim for the context's camera (rs_gbuffer.c). */
void rs__gbuf_tri_setup(rs__tri_consts *c, const rs__resolve_ctx *rc, uint32_t prim);
/* One pixel of the resolve, scalar: the reference (rs_gbuffer.c). Its
 * normal is left unnormalised: rs__gbuf_normalize_pixel finishes it. */
void rs__gbuf_resolve_pixel(const rs__resolve_ctx *rc, rs__tri_consts *c, uint32_t x, uint32_t y);
/* The pixel's normal normalised (pf_v3_normalize's operations), and a
 * covered pixel whose normal vanished given the camera-facing geometric
 * normal, as pf_scene_surface does. */
void rs__gbuf_normalize_pixel(const rs__resolve_ctx *rc, uint32_t x, uint32_t y);
/* The second half of it alone, for a pixel whose normal is normalised and
 * came out zero. */
void rs__gbuf_normal_fallback(const rs__resolve_ctx *rc, uint32_t x, uint32_t y);

/* The group kernels read a triangle's constants as floats: T = the
 * rs_resolve_tri from p0 to n2 (24 floats), UV = n_u, n_v (6). */
_Static_assert(offsetof(rs_resolve_tri, e1) == 12 && offsetof(rs_resolve_tri, e2) == 24 &&
                   offsetof(rs_resolve_tri, n_det) == 36 && offsetof(rs_resolve_tri, ng) == 48 &&
                   offsetof(rs_resolve_tri, n0) == 60 && offsetof(rs_resolve_tri, n1) == 72 &&
                   offsetof(rs_resolve_tri, n2) == 84,
               "rs_resolve_tri: p0..n2 must be 24 consecutive floats");
_Static_assert(offsetof(rs__tri_consts, n_v) == offsetof(rs__tri_consts, n_u) + 12, "n_u, n_v must be consecutive");

typedef struct rs_gbuffer_kernels {
    const char *isa; /* SIMD_NAME of the vocabulary it was compiled with */
    uint32_t rows;   /* SIMD_W / 4: a block is 4 pixels wide and this many rows high */
    /* the block of pixels x .. x + 3, y .. y + rows - 1 (all inside the
     * image; x a multiple of 4, y of rows); returns 0 and writes nothing
     * when the block is left to rs__gbuf_resolve_pixel */
    int (*group)(const rs__resolve_ctx *rc, rs__tri_consts *c, uint32_t x, uint32_t y);
} rs_gbuffer_kernels;

extern const rs_gbuffer_kernels rs_gbuffer_kernels_scalar;
extern const rs_gbuffer_kernels rs_gbuffer_kernels_avx2;   /* x86 only */
extern const rs_gbuffer_kernels rs_gbuffer_kernels_avx512; /* x86 only */

#endif
