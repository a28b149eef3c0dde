/* rs_raster: softgi's triangle rasterizer: the pass every G-buffer and
 * shadow map is made with.
 *
 * Pipeline (llvmpipe-style; each step a named function in rs_raster.c):
 *   1. rs__cull_clusters   clusters of 256 triangles (in scene order) are
 *                          culled by their bounding boxes against the clip
 *                          volume before any vertex is touched;
 *   2. rs__setup_bin       per triangle: clip-space transform, trivial reject,
 *                          homogeneous clipping against the near plane (w - z
 *                          >= 0), the far plane (z >= 0) and, only when a
 *                          vertex leaves the guard band, the guard-band
 *                          planes; snap to 8-bit sub-pixel fixed point; back-
 *                          face cull; edge functions with the top-left rule;
 *                          binning into 64x64-pixel tiles;
 *   3. rs__raster_tile     every tile is rasterized by one job item: its
 *                          triangles, gathered from the bins in triangle
 *                          order, go to the tile kernel in one call
 *                          (rs_raster_kernels.c: written once over the SIMD
 *                          vocabulary, compiled scalar, AVX2 and AVX-512),
 *                          which walks each triangle's rectangle of stamps
 *                          (4x4 pixels on AVX-512, 4x2 otherwise: one vector)
 *                          band by band, with exact coverage of every pixel
 *                          centre and the depth test per stamp, into a tile
 *                          buffer copied to the target once.
 *
 * Exactness: vertex positions are snapped to 1/256 pixel and edge functions
 * are evaluated exactly (64-bit integers, or 32-bit lanes where every value
 * is known to fit), so coverage is exact: a closed mesh
 * covers every pixel centre inside its silhouette exactly once, and of two
 * triangles sharing an edge exactly one covers a pixel centre on it (top-
 * left fill rule). Depth is interpolated in float with one fixed expression
 * per tile (z = (zt + dzdx * x) + dzdy * y from the tile's first pixel, no
 * FMA; rs_raster_kernels.h) in every path, so the SIMD paths give the same
 * bits as the scalar one.
 *
 * Depth convention (reversed): the rasterizer interpolates zs = z_clip /
 * w_clip linearly in screen space and keeps the GREATEST value; 0 means
 * nothing drawn. rs_mat4_perspective gives zs = znear / view_depth (1 at the
 * near plane, towards 0 at infinity: float precision where it matters);
 * rs_mat4_ortho gives zs = 1 - (view_depth - znear) / (zfar - znear).
 * Ties keep the earlier triangle (scene order), so results never depend on
 * scheduling.
 *
 * Screen space: pixel (x, y) has its centre at (x + 0.5, y + 0.5), y down;
 * NDC (-1, 1) is the top-left corner. Image size up to 16384 a side. */
#ifndef RS_RASTER_H
#define RS_RASTER_H

#include <stdint.h>

#include "pf_isa.h"
#include "pf_jobs.h"
#include "pf_anim.h"
#include "pf_scene.h"
#include "rs_gbuffer.h"

#define RS_NO_PRIM 0xffffffffu
#define RS_SUBPIXEL_BITS 8
#define RS_TILE 64
#define RS_MAX_SIZE 16384

typedef enum rs_simd { RS_SIMD_SCALAR = 0, RS_SIMD_AVX2, RS_SIMD_AVX512 } rs_simd;
/* sse2/sse4.2 -> scalar, avx2 -> AVX2, avx512 -> AVX-512 (README "Determinism"). */
rs_simd rs_simd_for_isa(pf_isa isa);
const char *rs_simd_name(rs_simd simd);

/* Column-major 4x4: clip = m * (x, y, z, 1). */
typedef struct rs_mat4 {
    float m[16];
} rs_mat4;

/* View-projection of a perspective camera looking along `forward` with
 * `up`, vertical fov `yfov` (radians), aspect = width / height, and an
 * infinite far plane; zs = znear / view_depth. */
rs_mat4 rs_mat4_perspective(pf_vec3 eye, pf_vec3 forward, pf_vec3 up, float yfov, float aspect, float znear);
/* Orthographic view-projection: the box [-half_w, half_w] x [-half_h, half_h]
 * x [znear, zfar] in front of `eye` along `forward`. */
rs_mat4 rs_mat4_ortho(pf_vec3 eye, pf_vec3 forward, pf_vec3 up, float half_w, float half_h, float znear, float zfar);
/* The camera's view-projection for an image of width x height. */
rs_mat4 rs_mat4_camera(const pf_camera *cam, uint32_t width, uint32_t height);
/* clip = m * (p, 1) */
void rs_mat4_transform(const rs_mat4 *m, pf_vec3 p, float clip[4]);
/* The pixel rectangle [r[0], r[2]) x [r[1], r[3]) of a width x height
 * target through which geometry inside the world box [lo, hi] can be seen
 * by view_proj: the bounding rectangle of the projected corners widened by
 * a pixel (snapping moves a vertex by at most 1/512 pixel). 0 when the box
 * lies outside one of the clip planes (nothing in it reaches the target);
 * the whole target when a corner is not in front of the eye (the projection
 * is unbounded). */
int rs_box_rect(const rs_mat4 *view_proj, uint32_t width, uint32_t height, pf_vec3 lo, pf_vec3 hi, uint32_t r[4]);

typedef enum rs_cull { RS_CULL_NONE = 0, RS_CULL_BACK, RS_CULL_FRONT } rs_cull;

/* Where a pass draws. depth is required (width*height floats); prim is
 * optional (NULL for depth-only passes such as shadow maps). The pass clears
 * them (depth 0, prim RS_NO_PRIM). `coverage`, optional, counts for every
 * pixel how many triangles cover its centre, before the depth test: an
 * overdraw view for learners, and how the tests prove that a closed mesh
 * covers each pixel exactly once (counting runs on the scalar path; it is
 * exact integer arithmetic in every path anyway). */
typedef struct rs_target {
    uint32_t width, height;
    float *depth;
    uint32_t *prim;
    uint32_t *coverage;
} rs_target;

typedef struct rs_pass {
    rs_mat4 view_proj;
    rs_cull cull; /* back = clockwise on screen, i.e. facing away for CCW-front triangles */
} rs_pass;

/* Per-pass statistics (for the bench and tests). */
typedef struct rs_stats {
    uint64_t clusters_culled, triangles_in, triangles_clipped, triangles_culled, triangles_binned;
} rs_stats;

typedef struct rs_context rs_context;

/* Prepares the scene for rasterization (clusters, bounds, per-worker bins).
 * `scene` and `jobs` must outlive the context. */
pf_result rs_context_create(rs_context **out, const pf_scene *scene, pf_jobs *jobs, rs_simd simd, pf_error *err);
void rs_context_destroy(rs_context *ctx);
rs_simd rs_context_simd(const rs_context *ctx);
/* The scene's per-triangle constants for rs_gbuffer_resolve_simd. */
const rs_resolve_tri *rs_context_resolve_table(const rs_context *ctx);
/* Switches the SIMD path (tests compare paths on one context). */
void rs_context_set_simd(rs_context *ctx, rs_simd simd);
/* Brings the context up to date after the scene's positions and normals
 * changed in place (pf_anim_pose, with the same vertex and triangle counts):
 * for the ranges reported moved, the welded positions (welding the scene
 * again only when a moved vertex shared its position with one that did not
 * move alike), the culling clusters' boxes and the resolve's per-triangle
 * table. Every later pass then gives the bytes a context made afresh from
 * the posed scene gives (tests/test_raster.c). A scratch of
 * rs_scratch_create made before must be made again when the update welded
 * again (rs_render_serial then refuses it: rs_scratch_status). Fails on a
 * range outside the scene or out of memory. */
pf_result rs_context_update(rs_context *ctx, const pf_anim_moved *moved, uint32_t count, pf_error *err);

/* Rasterizes the whole scene into `target` (cleared first), in parallel over
 * the context's jobs, deterministic for any thread count and SIMD path. */
void rs_render(rs_context *ctx, const rs_pass *pass, rs_target *target, rs_stats *stats);
/* rs_render limited to the tiles whose bit is set in `tiles` (bit
 * ty * tiles_x + tx of the target's ceil(width / 64) x ceil(height / 64)
 * tiles, 64 per word): each is cleared and drawn with the bytes rs_render
 * gives it, the others keep what they hold, and triangles meeting none of
 * them are dropped at setup (counted as culled). For drawing only the part
 * of a shadow map that visible receivers read (rs_shadow_render_needed) or
 * that moved geometry can change (rs_shadow_render_box). Returns how many
 * tiles were drawn. */
uint32_t rs_render_tiles(rs_context *ctx, const rs_pass *pass, rs_target *target, const uint64_t *tiles,
                         rs_stats *stats);
/* Bit t of a tile mask in rs_render_tiles' layout (64 tiles a word). */
static inline int rs_tile_bit(const uint64_t *tiles, uint64_t t) { return (int)(tiles[t / 64] >> (t % 64) & 1u); }

/* The same for a single-threaded caller that already runs inside a job (used
 * to render many small maps at once, one per job item): no jobs are
 * spawned; `scratch` is per-caller memory from rs_scratch_create. */
typedef struct rs_scratch rs_scratch;
rs_scratch *rs_scratch_create(const rs_context *ctx);
void rs_scratch_destroy(rs_scratch *s);
void rs_render_serial(const rs_context *ctx, rs_scratch *scratch, const rs_pass *pass, rs_target *target,
                      rs_stats *stats);
/* Whether the passes since the last call, with this scratch
 * (rs_render_serial) or with the context's own (rs_render), ran out of
 * memory; the call clears what it reports. No pass aborts: the setup's
 * growing arrays report a failure here instead, and the pass then lacks the
 * triangles of the setup chunks that failed (or, when even the per-tile
 * statistics could not be allocated, draws nothing). Returns PF_OK, or
 * PF_ERR_OUT_OF_MEMORY with a message saying what was lost; the caller
 * turns it into its error (a stage checks after its passes: one call covers
 * every face of a shadow-map set). */
pf_result rs_scratch_status(rs_scratch *scratch, pf_error *err);
pf_result rs_context_status(rs_context *ctx, pf_error *err);

#endif
