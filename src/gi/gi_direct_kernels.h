/* gi_direct_kernels: the shadow-mapped direct light's row (stage 2b),
 * written once over the SIMD vocabulary (src/base/simd/simd.h) in
 * gi_direct_kernels.c and compiled once per instruction set; gi_direct.c
 * picks the table of the frame's SIMD path. Private to gi_direct. */
#ifndef GI_DIRECT_KERNELS_H
#define GI_DIRECT_KERNELS_H

#include "gi_frame.h"

/* Irradiance at (pos, nrm) from the area lights' K emitter points, each
 * visible per its paraboloid map (scalar, every path; gi_direct.c). */
pf_vec3 gi__direct_area_irradiance(const gi_area_maps *m, pf_vec3 pos, pf_vec3 nrm);

/* What the direct light (stage 2b) reads and writes, explicitly (the stage
 * table's reads: GBUFFER, SHADOW_MAPS, AREA_MAPS; writes: DIRECT). */
typedef struct gi_direct_io {
    const pf_scene *scene;          /* the lights, the triangles' face normals */
    const rs_gbuffer *gbuf;         /* GBUFFER */
    const rs_shadow_map *shadows;   /* SHADOW_MAPS: map l for light l */
    uint32_t shadow_count;
    const gi_area_maps *area_maps;  /* AREA_MAPS; NULL when not rendered */
    const rs_resolve_tri *tri_table; /* the rasterizer's per-triangle table (its unit face normals), or NULL */
    uint32_t width;
    float *direct;                  /* DIRECT, 3 floats a pixel */
} gi_direct_io;

typedef struct gi_direct_kernels {
    const char *isa; /* SIMD_NAME of the vocabulary it was compiled with */
    /* one row y of io->direct: a pf_jobs parallel-for body over rows, ctx a
     * const gi_direct_io */
    void (*row)(void *io, uint32_t y, uint32_t worker);
    /* the same row's shadow-map tiles: the lookups `row` will make, marked
     * in each map's need (rs_shadow_need_lanes) */
    void (*need_row)(void *io, uint32_t y, uint32_t worker);
} gi_direct_kernels;

extern const gi_direct_kernels gi_direct_kernels_scalar;
extern const gi_direct_kernels gi_direct_kernels_avx2;   /* x86 only */
extern const gi_direct_kernels gi_direct_kernels_avx512; /* x86 only */

#endif
