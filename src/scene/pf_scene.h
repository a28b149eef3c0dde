/* pf_scene: the loaded scene as plain C data, owned by one struct and freed by
 * one call (pf_scene_free). Filled by the glTF shim (pf_gltf.h) or by code.
 *
 * Conventions
 * - World space, right-handed, +Y up, metres or whatever unit the file uses.
 * - Geometry is flattened: every mesh primitive instanced by a node is
 *   transformed to world space and appended. Triangles are counter-clockwise
 *   when seen from their front (node transforms with negative determinant
 *   have their winding flipped back, as glTF prescribes).
 * - Vertex arrays are structure-of-arrays friendly: positions, normals and uvs
 *   are separate arrays indexed by the same vertex id. `positions` carries one
 *   extra padding element so Embree may read 16 bytes at the last vertex.
 * - Primitives without NORMAL get flat normals (glTF 2.0 Sec. 3.7.2.1): their
 *   vertices are unwelded so each triangle carries its face normal.
 * - Zero-area triangles (and ones with repeated indices) are dropped at load
 *   and counted in `dropped_degenerate`.
 *
 * Light units (README "Light units")
 * - point/spot: `intensity` is radiant intensity I in W/sr; irradiance at a
 *   surface is E = I cos(theta) / r^2 (times the spot cone factor).
 * - directional: `intensity` is irradiance E in W/m^2 on a surface facing it.
 * - `color` multiplies intensity per channel (linear RGB).
 * - Materials are Lambertian: outgoing radiance = albedo * E / pi with albedo
 *   = baseColor. Emission is radiance in W/(sr m^2) = emissiveFactor times
 *   KHR_materials_emissive_strength. No 683 lm/W factor anywhere. */
#ifndef PF_SCENE_H
#define PF_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include "pf_math.h"
#include "pf_result.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PF_MAX_MIPS 16

/* An image with its full mip chain, 8-bit RGBA. baseColor images are stored as
 * the file has them (sRGB-encoded); mips are built in linear space and
 * re-encoded. Level l has size level_w[l] x level_h[l] at texels+level_offset[l]. */
typedef struct pf_image {
    uint32_t width, height, level_count;
    uint32_t level_w[PF_MAX_MIPS], level_h[PF_MAX_MIPS];
    size_t level_offset[PF_MAX_MIPS]; /* in texels */
    uint8_t *texels;                  /* RGBA8, all levels */
} pf_image;

typedef enum pf_wrap { PF_WRAP_REPEAT = 0, PF_WRAP_CLAMP, PF_WRAP_MIRROR } pf_wrap;

/* A glTF texture: an image and its sampler. */
typedef struct pf_texture {
    uint32_t image;
    pf_wrap wrap_s, wrap_t;
    int mag_linear;   /* magFilter LINEAR (default) vs NEAREST */
    int min_linear;   /* minFilter uses LINEAR within a level */
    int min_mipmap;   /* minFilter uses mipmaps (default yes) */
    int mip_linear;   /* blend between mip levels (LINEAR_MIPMAP_LINEAR, default) */
} pf_texture;

typedef enum pf_alpha_mode { PF_ALPHA_OPAQUE = 0, PF_ALPHA_MASK, PF_ALPHA_BLEND } pf_alpha_mode;

typedef struct pf_material {
    char name[64];
    float base_color[4];        /* linear RGBA factor */
    int32_t base_color_texture; /* index into textures, -1 for none */
    float emission[3];          /* radiance, W/(sr m^2) */
    pf_alpha_mode alpha_mode;   /* BLEND is rendered as OPAQUE (README) */
    float alpha_cutoff;         /* MASK: alpha < cutoff is a hole */
    int double_sided;
} pf_material;

typedef enum pf_camera_kind { PF_CAMERA_PERSPECTIVE = 0 } pf_camera_kind;

typedef struct pf_camera {
    char name[64];
    pf_vec3 eye;
    pf_vec3 forward, up, right; /* orthonormal, right = forward x up */
    float yfov;                 /* radians, full vertical field of view */
    float znear, zfar;          /* zfar 0: infinite */
    float aspect;               /* 0: take it from the image size */
} pf_camera;

typedef enum pf_light_type { PF_LIGHT_POINT = 0, PF_LIGHT_SPOT, PF_LIGHT_DIRECTIONAL } pf_light_type;

/* The largest light intensity x colour (W/sr, W/m^2) and emitted radiance
 * softgi accepts. Far below float's 3.4e38 so that shading (intensity x
 * albedo x geometry term / distance^2, summed over thousands of VPLs) stays
 * finite; far above any physical light in these units (the sun is about
 * 1e3 W/m^2). */
#define PF_MAX_RADIANCE 1e10f

typedef struct pf_light {
    char name[64];
    pf_light_type type;
    pf_vec3 position;  /* point, spot */
    pf_vec3 direction; /* spot, directional: unit vector the light travels along */
    pf_vec3 color;     /* linear RGB */
    float intensity;   /* W/sr (point, spot) or W/m^2 (directional) */
    float inner_cone;  /* radians, spot only */
    float outer_cone;  /* radians, spot only */
    float range;       /* glTF range; 0 = infinite. Ignored by softgi (README). */
} pf_light;

typedef struct pf_scene {
    /* geometry (world space) */
    uint32_t vertex_count;
    pf_vec3 *positions; /* vertex_count + 1 (padding) */
    pf_vec3 *normals;   /* vertex_count, unit length */
    pf_vec2 *uvs;       /* vertex_count (0,0 where the file has none) */
    uint32_t tri_count;
    uint32_t *indices;      /* 3 * tri_count */
    uint32_t *tri_material; /* tri_count */

    uint32_t material_count;
    pf_material *materials; /* always >= 1: index 0 may be the glTF default */
    uint32_t texture_count;
    pf_texture *textures;
    uint32_t image_count;
    pf_image *images;

    uint32_t camera_count;
    pf_camera *cameras;
    uint32_t light_count;
    pf_light *lights;

    pf_vec3 bounds_min, bounds_max;
    uint32_t dropped_degenerate; /* zero-area triangles removed at load */
    char warnings[1024];         /* load warnings, newline separated */
    uint64_t memory_bytes;       /* the loader's estimate of what the scene costs (pf_budget.h): triangles
                                    through the pipeline and texels with mips; 0 for scenes built in memory */
} pf_scene;

/* The surface at a point of a triangle, interpolated from the scene. */
typedef struct pf_surface {
    pf_vec3 p;       /* position (barycentric interpolation of the vertices) */
    pf_vec3 ng;      /* unit geometric normal of the CCW triangle */
    pf_vec3 ns;      /* unit shading normal (interpolated vertex normals; ng if they cancel) */
    pf_vec2 uv;
    float albedo[4]; /* filtered baseColor (linear RGBA) */
    uint32_t material;
    uint32_t prim;
} pf_surface;

/* Largest |coordinate| softgi accepts anywhere in world space. Beyond this a
 * float keeps under 1 unit of precision per 1e7 and the rasterizer's
 * fixed-point snapping and Embree's epsilons stop being meaningful. */
#define PF_SCENE_MAX_COORD 1.0e7f

/* A position softgi accepts: finite and within PF_SCENE_MAX_COORD. */
static inline int pf_scene_coord_ok(pf_vec3 p)
{
    return pf_v3_is_finite(p) && fabsf(p.x) <= PF_SCENE_MAX_COORD && fabsf(p.y) <= PF_SCENE_MAX_COORD &&
           fabsf(p.z) <= PF_SCENE_MAX_COORD;
}

void pf_scene_free(pf_scene *scene);

/* Recomputes bounds and validates the scene: finite positions/normals/uvs,
 * coordinates within PF_SCENE_MAX_COORD, indices and material ids in range,
 * at least one triangle, lights and cameras finite. */
pf_result pf_scene_validate(pf_scene *scene, pf_error *err);

/* Appends a light (used by --light overrides). */
pf_result pf_scene_add_light(pf_scene *scene, const pf_light *light, pf_error *err);

/* Emissive quads added by code (sequence files' "emitters", pf_sequence.h):
 * an area light like a glTF emissive quad, for the shared scenes that have
 * none (Hedman 2017 Sec. 5 lights Sibenik and the conference room with one).
 *
 * corners[0..3] in order, counter-clockwise seen from the emitting side (the
 * glTF front-face rule: the face normal is (c1 - c0) x (c2 - c0)). Accepted
 * when (tolerances relative to d, the longer diagonal, in double precision):
 * - every corner lies within +-PF_SCENE_MAX_COORD;
 * - convex with corners in order: at every corner the turn to the next edge,
 *   (c[i] - c[i-1]) x (c[i+1] - c[i]) . n, is above 1e-6 d^2 (no repeated or
 *   collinear corners, no bow-tie, no reflex corner), and the area is at
 *   least PF_SCENE_EMITTER_MIN_AREA (units^2, so the float cross products the
 *   renderer takes neither underflow nor lose their direction);
 * - planar: every corner within PF_SCENE_EMITTER_PLANARITY x d of the plane
 *   through the corners' mean with normal n = (c2 - c0) x (c3 - c1);
 * - emission finite, each channel in [0, PF_MAX_RADIANCE], not all zero.
 * *normal (may be NULL) gets the unit face normal n. PF_ERR_NONFINITE for a
 * non-finite or huge value, PF_ERR_PARSE for a bad shape or emission, with a
 * message without a file name (callers prefix theirs). */
#define PF_SCENE_EMITTER_PLANARITY 1e-3
#define PF_SCENE_EMITTER_MIN_AREA 1e-12
pf_result pf_scene_emitter_quad_check(const pf_vec3 corners[4], pf_vec3 emission, pf_vec3 *normal, pf_error *err);

/* Appends an emissive quad (checked as above): 4 vertices with the face
 * normal and uvs (0,0) (1,0) (1,1) (0,1), triangles (0,1,2) and (0,2,3),
 * and a material of its own: `emission` (W/(sr m^2)), double-sided when
 * two_sided (then it emits from both faces, gi_area.h), baseColor 0.78 grey
 * (McGuire's CornellBox-Original light material: an emitter's diffuser
 * reflects too, and all three area-lit sequences then treat their emitter
 * alike). Keeps every array's invariant (positions padded by one); on
 * failure the scene is unchanged (some arrays may have grown). The caller
 * runs pf_scene_validate afterwards (it recomputes the bounds). */
pf_result pf_scene_add_emitter_quad(pf_scene *scene, const pf_vec3 corners[4], pf_vec3 emission, int two_sided,
                                    pf_error *err);

/* A camera looking from eye to target with a +Y-up roll, fovy in radians. */
pf_result pf_camera_look_at(pf_camera *cam, pf_vec3 eye, pf_vec3 target, float yfov, pf_error *err);

/* Unit geometric normal of triangle `prim` (counter-clockwise front). */
pf_vec3 pf_scene_face_normal(const pf_scene *scene, uint32_t prim);

/* The surface of triangle `prim` at barycentrics (u, v) (weights of
 * vertices 1 and 2), texture filtered at mip level `lod`. Shared by the
 * ray-traced and the rasterized paths so both interpolate identically. */
void pf_scene_surface(const pf_scene *scene, uint32_t prim, float u, float v, float lod, pf_surface *out);

/* Direction of the primary ray through the centre of pixel (x, y) of a
 * width x height image (y down), scaled so that t along it is view depth
 * (its component along forward is 1). Pinhole model: the image plane at
 * distance 1 spans tan(yfov/2) * (aspect, 1); the aspect is the image's. */
pf_vec3 pf_camera_ray_dir(const pf_camera *cam, uint32_t width, uint32_t height, float x, float y);

/* Mip level for a footprint given the uv derivatives per pixel: log2 of the
 * larger texel extent, for the material's baseColor texture (0 without). */
float pf_material_lod(const pf_scene *scene, uint32_t material, float dudx, float dvdx, float dudy, float dvdy);

/* Builds the mip chain of an image whose level 0 is filled in (sRGB RGBA8:
 * averaging happens in linear space). Allocates image->texels anew from the
 * level-0 data passed in. */
pf_result pf_image_build_mips(pf_image *img, const uint8_t *rgba8_level0, uint32_t w, uint32_t h, pf_error *err);

/* Material albedo/alpha at a uv with a level of detail (log2 texels per
 * unit-uv footprint; 0 = finest). Returns linear RGBA: baseColorFactor times
 * the decoded texture, bilinear within a level and linear between levels as
 * the sampler asks. */
void pf_material_sample(const pf_scene *scene, uint32_t material, pf_vec2 uv, float lod, float out_rgba[4]);

/* sRGB transfer functions (IEC 61966-2-1). */
float pf_srgb_to_linear(float c);
float pf_linear_to_srgb(float c);

#ifdef __cplusplus
}
#endif

#endif
