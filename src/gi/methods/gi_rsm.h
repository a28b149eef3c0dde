/* gi_rsm: reflective shadow maps (Dachsbacher and Stamminger 2005, as
 * Barak 2013 Sec. 3 and Ritschel 2011 use them): for every punctual light
 * the scene is rasterized from the light (src/raster, rs_render), for the
 * area lights it is ray traced from points on the emitters, and each
 * texel keeps the surface the light sees there: world position, unit
 * normal, and the flux that surface reflects. Every texel is a potential
 * VPL (pVPL, Barak 2013 Sec. 4.1).
 *
 * Maps (one per punctual light, in scene light order, then one for all
 * area lights; like rs_shadow.h but without the PCF margin, so the texels
 * tile the light's emission exactly once):
 * - GI_RSM_SPOT: one perspective map along the spot axis, fov = 2 outer cone
 *   (spots whose outer cone exceeds RS_SHADOW_SPOT_MAX_CONE use a cube).
 * - GI_RSM_CUBE (point lights): six 90-degree perspective faces, face order
 *   and axes those of rs_shadow.h (+X, -X, +Y, -Y, +Z, -Z).
 * - GI_RSM_ORTHO (directional): an orthographic box around the scene bounds
 *   seen along the light direction.
 * - GI_RSM_AREA (the area lights, gi_area.h: all emissive triangles
 *   together): one hemispherical map with K faces, face k seen from the
 *   k-th of K fixed, power-weighted points on the emitters (gi_rsm_area.h;
 *   beyond the papers, which light with punctual lights only). It comes
 *   after the punctual lights' maps: maps[punctual].
 *
 * Texel layout: all maps' texels in one flat index space. Map m owns
 * [maps[m].first, maps[m].first + maps[m].texel_count); inside a map the
 * texel of face f, row y (top row first), column x is at
 *   first + (f * size + y) * size + x,
 * i.e. a cube map is its six faces stacked vertically (6 size rows).
 * Face f's texel (x, y) looks along the ray through NDC
 *   (2 (x + 0.5) / size - 1,  1 - 2 (y + 0.5) / size)
 * (perspective: from eye along forward + ndc.x tan_half right + ndc.y
 * tan_half up; ortho: from eye + ndc.x half_w right + ndc.y half_h up
 * along forward; area: from faces[f].org along the NDC point's
 * cosine-weighted hemisphere direction, gi_rsm_area_dir).
 *
 * Units: flux_* is the flux (W, RGB) the texel's surface REFLECTS, i.e.
 * albedo x the flux it receives:
 *   perspective texel: received = I(w) * Omega_texel, where I(w) is the
 *     light's intensity (W/sr, times the spot cone factor at the texel
 *     centre's direction) and Omega_texel the texel's exact solid angle;
 *   ortho texel: received = E * A_texel (E in W/m^2 across the beam);
 *   area texel: received = Le A_k pi / size^2 (the point's radiance times
 *     its share A_k of the emitter area times the texel's projected solid
 *     angle, the same for every texel: gi_rsm_area.h).
 * So the fluxes of a map sum to the power the light's lit surfaces reflect
 * (4 pi I albedo for a point light inside a closed box of albedo `albedo`),
 * and a VPL made from texel v and chosen with probability p out of N gets
 * intensity flux_v / (pi N p) (gi_vpl.h units, W/sr).
 * valid: 1 where a surface is seen AND the light reaches it (spot texels
 * outside the cone are 0); pos/nrm/flux are 0 where valid is 0.
 * nrm is the interpolated shading normal turned to face the light
 * (two-sided, as softgi shades); ng_* is the geometric normal, same side.
 *
 * Lifetime: gi_rsm_set_init (no allocation), gi_rsm_set_update every
 * frame (allocates on the first call and whenever the lights' map layout
 * changes; re-renders only when a light changed since the last update, the
 * scene geometry being static; the area map is traced once, emitters being
 * static too), gi_rsm_set_free. The set owns its own rs_context for the
 * scene (recreated if the scene or jobs pointer changes).
 *
 * Determinism: rs_render, the attribute resolve and the area map's rays
 * (pf_rt: the same bits for a ray alone or in a packet) are bit-exact for
 * any thread count (rows are resolved in parallel, each writing only
 * itself). A scene without emitters gives exactly the maps it gave before
 * the area map existed. */
#ifndef GI_RSM_H
#define GI_RSM_H

#include <stdint.h>

#include "gi_area.h"
#include "pf_jobs.h"
#include "pf_result.h"
#include "gi_motion.h"
#include "pf_rt.h"
#include "pf_scene.h"
#include "rs_raster.h"

#define GI_RSM_DEFAULT_SIZE 128u /* texels per side (per cube face) */
#define GI_RSM_MIN_SIZE 8u
#define GI_RSM_MAX_SIZE 2048u
#define GI_RSM_DEFAULT_AREA_POINTS 8u /* faces of the area lights' map (K) */
#define GI_RSM_MAX_AREA_POINTS 256u
#define GI_RSM_NO_LIGHT 0xffffffffu /* gi_rsm_map.light of the area lights' map */

typedef enum gi_rsm_kind { GI_RSM_SPOT = 0, GI_RSM_CUBE, GI_RSM_ORTHO, GI_RSM_AREA } gi_rsm_kind;

/* One face of the area lights' map: an emitter point (gi_rsm_area.h). */
typedef struct gi_rsm_face {
    pf_vec3 org;        /* ray origin: the point, pushed off the emitter on its emitting side */
    pf_vec3 n, t, b;    /* emitting normal and tangents (pf_v3_basis(n)) */
    pf_vec3 texel_flux; /* Le A_k pi / size^2: the flux (W, RGB) every texel of the face receives */
} gi_rsm_face;

typedef struct gi_rsm_map {
    uint32_t light;       /* index into scene->lights (GI_RSM_NO_LIGHT: the area lights) */
    gi_rsm_kind kind;
    uint32_t size;        /* texels per side of each face */
    uint32_t face_count;  /* 6 for GI_RSM_CUBE, K for GI_RSM_AREA, else 1 */
    uint32_t first;       /* index of the map's first texel in the set's planes */
    uint32_t texel_count; /* face_count * size * size */
    rs_mat4 view_proj[6];
    pf_vec3 eye;          /* light position; ortho: the box's eye point */
    pf_vec3 forward[6], right[6], up[6];
    float tan_half;       /* perspective: tan of half the fov */
    float half_w, half_h; /* ortho: half extents of the box across the beam */
    float znear, zfar;    /* ortho depth range; perspective: znear only */
    float *solid_angle;   /* perspective: size*size exact texel solid angles (sr), shared by the faces; else NULL */
    gi_rsm_face *faces;   /* GI_RSM_AREA: face_count emitter points; else NULL */
    pf_vec3 power;        /* GI_RSM_AREA: the flux the points emit, sum of pi Le A_k (W, RGB) */
} gi_rsm_map;

typedef struct gi_rsm_set {
    uint32_t size;        /* requested texels per side (0 in init: GI_RSM_DEFAULT_SIZE) */
    uint32_t area_points; /* K, faces of the area lights' map (0 in init: GI_RSM_DEFAULT_AREA_POINTS) */
    uint32_t count;       /* maps: the scene's punctual lights, then one for the area lights if any */
    uint32_t punctual;    /* maps[0 .. punctual) are the punctual lights' in scene order */
    gi_rsm_map *maps;
    uint32_t texel_count; /* over all maps */
    /* per texel (structure of arrays, texel_count each) */
    float *pos_x, *pos_y, *pos_z;
    float *nrm_x, *nrm_y, *nrm_z;
    float *ng_x, *ng_y, *ng_z;
    float *flux_r, *flux_g, *flux_b;
    uint8_t *valid;
    uint32_t *prim;       /* triangle seen (RS_NO_PRIM where none) */
    /* bookkeeping */
    uint32_t updates;     /* gi_rsm_set_update calls that re-rendered the maps */
    int changed;          /* 1 if the last gi_rsm_set_update re-rendered */
    /* private */
    float *depth_;        /* rasterizer depth scratch, texel_count */
    pf_light *lights_;    /* the lights the maps were rendered for */
    rs_context *raster_;
    const pf_scene *raster_scene_;
    pf_jobs *raster_jobs_;
    const gi_area_lights *area_; /* the emitters the area map was laid out for */
    int area_rendered_;          /* the area map is current (emitters do not move) */
} gi_rsm_set;

/* Zeroes the set and records the resolution (0: default); area_points may
 * be set afterwards (0: default). No allocation. */
void gi_rsm_set_init(gi_rsm_set *set, uint32_t size);
/* Makes the maps current for scene's punctual lights and, when `area` has
 * emitters, for the area lights: lays them out, rasterizes and resolves
 * the punctual maps when any punctual light changed (or on the first call),
 * traces the area map (with rt) once. area may be NULL (no area map); rt may
 * be NULL when area has no emitters. Fails on a size outside
 * [GI_RSM_MIN_SIZE, GI_RSM_MAX_SIZE], area_points outside
 * [1, GI_RSM_MAX_AREA_POINTS], a non-finite light, emitters without rt, or
 * out of memory. A scene without lights and emitters gives count 0 and
 * texel_count 0. */
pf_result gi_rsm_set_update(gi_rsm_set *set, const pf_scene *scene, const gi_area_lights *area, const pf_rt *rt,
                            pf_jobs *jobs, pf_error *err);
void gi_rsm_set_free(gi_rsm_set *set);
/* Geometry moved (gi_motion.h; motion may be NULL: nothing did): the set's
 * rasterizer follows the pose (rs_context_update) and the next
 * gi_rsm_set_update draws every map again (and traces the area map again),
 * the lights being unchanged or not. An RSM is the light's view of the
 * whole scene, so any moved triangle can change any texel; the maps are
 * small (256^2 a face) next to what a partial redraw would save. */
pf_result gi_rsm_set_geometry_moved(gi_rsm_set *set, const gi_motion *motion, pf_error *err);

/* The map owning flat texel index t (binary search over the maps). */
uint32_t gi_rsm_map_of(const gi_rsm_set *set, uint32_t t);

/* The light's emitted power that the RSM parametrisation covers (W, RGB,
 * no albedo): 4 pi I for a point light, 2 pi I int cone(cos) dcos for a
 * spot, E * (box cross-section) for a directional light, map->power for
 * the area lights' map (light ignored, may be NULL). For tests. */
pf_vec3 gi_rsm_light_power(const gi_rsm_map *map, const pf_light *light);

#endif
