/* rs_shadow: direct-light shadow maps, one per punctual light, and their
 * 16-tap percentage-closer lookup (Laine et al. 2007, Sec. 6: "For direct
 * illumination we compute a shadow cube map with 1024x1024 resolution on
 * each side. The direct shadow lookup is smoothed using a 16-tap
 * percentage-closer filter [RSC87]").
 *
 * Map kinds (chosen per light by rs_shadow_map_init)
 * - RS_SHADOW_SPOT: one perspective map looking along the spot direction,
 *   fov = 2 outer_cone widened by a 2-texel margin so every PCF tap of a
 *   point inside the cone stays inside the map. Spots wider than
 *   RS_SHADOW_SPOT_MAX_CONE (60 degrees half-angle) get a cube map instead:
 *   a perspective map's texels grow without bound as the fov nears 180
 *   degrees, and at 60 degrees the centre texel already spans 1.7x the
 *   angle of a cube face's.
 * - RS_SHADOW_CUBE: six perspective faces of 90 degrees (plus the same
 *   2-texel margin, so taps near a face edge stay on the face the point
 *   projects to and no tap has to hop to a neighbouring face). Face order
 *   and axes are the standard cube-map ones (OpenGL 4.6 Sec. 8.13 "Cube Map
 *   Texture Selection", D3D alike): +X, -X, +Y, -Y, +Z, -Z, face f rendered
 *   by a camera looking along its axis with up = -Y (the four side faces),
 *   +Z (+Y face) or -Z (-Y face), the usual lookAt ups for cube shadow
 *   maps, so a face's columns run along GL's s. softgi stores the top row
 *   first, so its rows run opposite to GL's t (each face is the upright
 *   image its camera sees). A lookup uses the face of the major axis of
 *   (p - light): the largest |component|, ties going to x, then y, then z.
 * - RS_SHADOW_ORTHO (directional): an orthographic box around the scene's
 *   bounds seen along the light direction (lateral extent again widened by 2
 *   texels), its near plane in front of the whole scene.
 *
 * Depth: the planes hold what rs_render writes, reversed depth zs (greater =
 * closer to the light, 0 = nothing drawn). Perspective maps have an infinite
 * far plane and znear = 1e-4 of the scene diagonal (anything nearer the light
 * than that is clipped and casts no shadow).
 *
 * Lookup (rs_shadow_visibility): lit fraction in [0, 1].
 * - PCF (default): a 4x4 grid of point comparisons at offsets (+-0.5, +-1.5)
 *   texels around the point, i.e. the 4x4 texels whose centres surround it,
 *   box-weighted: 17 levels 0, 1/16, ..., 1. Laine et al. name only "16-tap
 *   PCF [RSC87]"; the regular grid with nearest-texel taps (no bilinear
 *   weights) is our choice: exact in binary fractions, so bit-identical on
 *   every path. RS_SHADOW_PCF1 is the single nearest-texel comparison.
 * - Slope-scaled bias (derivation and measurements in rs_shadow.c), with
 *   w the world size of a texel at p and theta the angle between the
 *   geometric normal and the direction to the light. A tap counts p as lit
 *   when its texel's stored depth is no nearer the light than
 *     [p's receiver plane at the tap's texel centre]
 *       - w (bias_const + bias_slope min(tan(theta), tan_max)).
 *   The first term is the slope-scaled bias taken per tap along the
 *   plane's depth gradient (receiver plane depth bias; its size is offset *
 *   w * tan(theta)): exact for planes, it needs no worst-case slope term
 *   and so hides fewer real shadows. Defaults: bias_const 1 texel,
 *   bias_slope 0.5 texel, tan_max 100 (89.4 degrees), no normal offset.
 * - Spot: points outside the frustum are unlit (the cone factor is 0 there).
 *   Directional: points outside the box are lit. Points nearer the light
 *   than znear (after bias) are lit.
 * Surfaces are two-sided: the normal is turned to face the light.
 *
 * Rendering culls nothing: scenes may be open meshes (the Cornell blocks have
 * no bottom, a wall may be a single quad), so front- or back-face culling
 * would drop real occluders.
 *
 * Determinism: rs_render gives the same bytes for any thread count and SIMD
 * path; the maps are rendered one pass after another in light order and
 * face order, and the lookup is a pure function of its inputs. */
#ifndef RS_SHADOW_H
#define RS_SHADOW_H

#include <stdint.h>

#include "pf_result.h"
#include "pf_scene.h"
#include "rs_raster.h"

#define RS_SHADOW_DEFAULT_SIZE 1024u
#define RS_SHADOW_MIN_SIZE 16u
#define RS_SHADOW_MAX_FACES 6
/* Words of a face's tile mask at the largest size (rs_shadow_map.valid). */
#define RS_SHADOW_MASK_WORDS (((RS_MAX_SIZE + RS_TILE - 1) / RS_TILE * ((RS_MAX_SIZE + RS_TILE - 1) / RS_TILE) + 63) / 64)
/* Spots with a wider outer cone (radians, half-angle) get a cube map. */
#define RS_SHADOW_SPOT_MAX_CONE 1.04719755f
/* Texels of margin around the region a map must cover, so that every PCF tap
 * (reach 2 texels per axis) of a covered point lands inside the map. */
#define RS_SHADOW_MARGIN_TEXELS 2.0f
/* Bias defaults (texels at the receiver; tan_max: cap on tan(theta)). */
#define RS_SHADOW_BIAS_CONST 1.0f
#define RS_SHADOW_BIAS_SLOPE 0.5f
#define RS_SHADOW_TAN_MAX 100.0f

typedef enum rs_shadow_kind { RS_SHADOW_SPOT = 0, RS_SHADOW_CUBE, RS_SHADOW_ORTHO } rs_shadow_kind;
typedef enum rs_shadow_filter { RS_SHADOW_PCF16 = 0, RS_SHADOW_PCF1 } rs_shadow_filter;

/* Zero-initialised means defaults. The filter and biases only affect
 * lookups and may be changed after rendering. */
typedef struct rs_shadow_desc {
    uint32_t size;           /* texels per side (0: RS_SHADOW_DEFAULT_SIZE); cube: per face */
    rs_shadow_filter filter; /* 0: 16-tap PCF */
    float bias_const;        /* texels (0: RS_SHADOW_BIAS_CONST) */
    float bias_slope;        /* texels per unit tan(theta) (0: RS_SHADOW_BIAS_SLOPE) */
    float normal_offset;     /* texels along the normal, times sin(theta) (0: none) */
    float tan_max;           /* slope cap (0: RS_SHADOW_TAN_MAX) */
} rs_shadow_desc;

typedef struct rs_shadow_map {
    rs_shadow_kind kind;
    uint32_t light; /* index into the scene's lights */
    uint32_t size;  /* texels per side (of each face) */
    uint32_t face_count;
    rs_shadow_desc desc;
    rs_mat4 view_proj[RS_SHADOW_MAX_FACES];
    pf_vec3 forward[RS_SHADOW_MAX_FACES]; /* unit view axis of each face */
    pf_vec3 right[RS_SHADOW_MAX_FACES], up[RS_SHADOW_MAX_FACES];
    pf_vec3 eye;                          /* light position; ortho: the box's eye point */
    float tan_half;                       /* perspective: tan(half fov), margin included */
    float znear, zfar;                    /* ortho: depth range of the box; perspective: zfar unused */
    float half_w, half_h;                 /* ortho: half extents of the box */
    float *depth; /* face_count planes of size*size floats, face f at depth + f*size*size */
    /* Which 64 x 64 tiles (RS_TILE) of each face hold the light's depths
     * (valid) and which the frame's receivers read (need): bit t of face f
     * in word f * tile_words + t / 64, tiles row by row (rs_render_tiles).
     * rs_shadow_render makes every tile valid, rs_shadow_map_update (the
     * light changed) none; rs_shadow_render_needed draws the needed tiles
     * that are not valid. A lookup must read valid tiles only. */
    uint32_t tiles_side, tile_words;
    uint64_t *valid, *need;
    /* 1 from rs_shadow_map_init / rs_shadow_map_update (a new or changed
     * light) until its user clears it: gi_stage_shadow_maps draws a fresh
     * map's needed tiles only, and a map whose light stayed a frame whole */
    int fresh;
} rs_shadow_map;

/* Sets up the map of scene->lights[light] (kind, matrices) and allocates its
 * planes (zeroed: everything lit until rendered). desc may be NULL. Fails on
 * a bad light index, a size outside [RS_SHADOW_MIN_SIZE, RS_MAX_SIZE], a
 * light that is not finite or has no direction, or out of memory. */
pf_result rs_shadow_map_init(rs_shadow_map *map, const pf_scene *scene, uint32_t light, const rs_shadow_desc *desc,
                             pf_error *err);
/* rs_shadow_map_init for a light that changed, keeping the planes when the
 * kind (face count) and size stay, since rendering rewrites every texel: a
 * moving light's map costs no allocation (and no page faults) per frame.
 * On failure the planes are freed (map->depth NULL). */
pf_result rs_shadow_map_update(rs_shadow_map *map, const pf_scene *scene, uint32_t light, const rs_shadow_desc *desc,
                               pf_error *err);
void rs_shadow_map_free(rs_shadow_map *map);
/* Face f's depth plane (size*size floats, top row first). */
float *rs_shadow_map_face(const rs_shadow_map *map, uint32_t face);

/* The maps of all of a scene's lights, map i for light i. */
typedef struct rs_shadow_set {
    uint32_t count;
    rs_shadow_map *maps;
} rs_shadow_set;

pf_result rs_shadow_set_init(rs_shadow_set *set, const pf_scene *scene, const rs_shadow_desc *desc, pf_error *err);
void rs_shadow_set_free(rs_shadow_set *set);

/* Renders every face of maps[0..count) with rs_render (parallel over tiles,
 * one pass after another). The maps must have been set up for the scene of
 * ctx. stats (may be NULL) receives the sum over all passes. */
void rs_shadow_render(rs_context *ctx, rs_shadow_map *maps, uint32_t count, rs_stats *stats);
static inline void rs_shadow_set_render(rs_context *ctx, rs_shadow_set *set, rs_stats *stats)
{
    rs_shadow_render(ctx, set->maps, set->count, stats);
}

/* rs_shadow_render restricted to what geometry inside the world box
 * [lo, hi] can change (a moved object's bounds before and after it moved):
 * per face, the valid tiles that meet the box's projection are drawn again
 * (rs_render_tiles; invalid ones wait for rs_shadow_render_needed), faces
 * the box lies outside of are not touched, so each map's valid tiles equal
 * one rendered afresh (tests/test_moving.c). Returns how many
 * faces were drawn again; *texels (may be NULL) is increased by the texels
 * they drew. */
uint32_t rs_shadow_render_box(rs_context *ctx, rs_shadow_map *maps, uint32_t count, pf_vec3 lo, pf_vec3 hi,
                              uint64_t *texels, rs_stats *stats);

/* Receiver-driven rendering (beyond Laine 2007, which renders the whole
 * cube; after the "only the pages visible receivers touch" idea of
 * resolution-matched and virtual shadow maps, Lefohn et al. 2007): the
 * direct-light stage marks in map->need every tile its lookups will read
 * (rs_shadow_need_lanes, rs_shadow_lookup.h, with the lookup's own
 * projection) and this draws the needed tiles that are not valid, with the
 * bytes rs_render gives them, then marks them valid. A light that stays
 * keeps its tiles while the camera moves; a moving light draws only what
 * the view needs. Returns the tiles drawn. */
uint32_t rs_shadow_render_needed(rs_context *ctx, rs_shadow_map *maps, uint32_t count, rs_stats *stats);
/* Clears every map's need (before a frame marks it). */
void rs_shadow_need_clear(rs_shadow_map *maps, uint32_t count);
/* Marks every tile of every face needed (a lookup the marking cannot
 * follow: a normal offset moves the point). */
void rs_shadow_need_all(rs_shadow_map *map);
/* 1 if texel (x, y) of face f lies in a valid tile. */
static inline int rs_shadow_texel_valid(const rs_shadow_map *m, uint32_t face, uint32_t x, uint32_t y)
{
    uint32_t t = y / RS_TILE * m->tiles_side + x / RS_TILE;
    return m->valid && rs_tile_bit(m->valid + (size_t)face * m->tile_words, t);
}

/* The face of a cube map that world point p projects to (major axis of
 * p - eye; ties to x, then y, then z). */
uint32_t rs_shadow_cube_face(pf_vec3 eye, pf_vec3 p);

/* Fraction of the light reaching world point p on a surface with geometric
 * normal ng (either orientation; need not be unit length), in [0, 1]. */
float rs_shadow_visibility(const rs_shadow_map *map, pf_vec3 p, pf_vec3 ng);

/* rs_shadow_visibility of 8 points (SoA: px[i], py[i], pz[i] and normals
 * ngx[i], ...), lane i only where bit i of `active` is set (other lanes get
 * 0; their inputs must still be initialised). Every simd path runs
 * rs_shadow_visibility_lanes (rs_shadow_lookup.h, written once over the
 * SIMD vocabulary; AVX-512 with the 8 points in the first of 16 lanes),
 * which gives exactly the scalar lookup's bits (tests/test_shadow.c
 * test_simd_matches_scalar); maps with a normal offset loop
 * rs_shadow_visibility. */
void rs_shadow_visibility8(const rs_shadow_map *map, rs_simd simd, const float *px, const float *py, const float *pz,
                           const float *ngx, const float *ngy, const float *ngz, unsigned active, float *out);

#endif
