/* gi_indirect_kernels: the many-light accumulation (step 7) and Laine's box
 * filter (step 9), written once over the SIMD vocabulary
 * (src/base/simd/simd.h) in gi_indirect_kernels.c and compiled once per
 * instruction set; gi_indirect.c picks the table of the frame's SIMD path
 * (the AVX2 or AVX-512 one; the scalar path keeps its per-pixel loops, the
 * reference the tables are tested against). Private to gi_indirect. */
#ifndef GI_INDIRECT_KERNELS_H
#define GI_INDIRECT_KERNELS_H

#include "gi_frame.h"

/* Runs of `width` pixels processed together: at most this many per call. */
#define GI_ACC_GROUPS 128
/* Tile rows per job item of the accumulation (gi_indirect.c). */
#define GI_ACC_BAND 8

/* What the accumulation (step 7) reads: the VPLs, the tiles' VPL lists and
 * the VPLs' maps (exact paraboloid maps or ISMs), explicitly. */
typedef struct gi_accumulate_in {
    const gi_vpl *vpls;            /* VPLS: the set's VPLs */
    const uint32_t *assign;        /* ASSIGNMENT: VPL indices, grouped by tile */
    const uint16_t *atlas;         /* VPL_MAPS: map k at atlas + k R^2 */
    const rs_para_frame *frames;   /* each map's VPL frame */
    uint32_t para_res;             /* R */
    float range, bias_scale;       /* the maps' quantisation range; the lookup's bias scale */
    int plane;                     /* 1: the receiver-plane test (exact maps; rs_paraboloid.h "Lookup") */
    float b;                       /* the bounded geometry term's bound */
} gi_accumulate_in;

/* What Laine's box filter (step 9) reads: COMBINED and the indirect image's
 * G-buffer, explicitly. */
typedef struct gi_filter_in {
    const float *combined;   /* COMBINED, 3 floats a pixel */
    const rs_gbuffer *g;     /* GBUFFER (the reduced one with --indirect-scale) */
    uint32_t w, h, n, m;     /* the indirect image's size; the tiles (the window is n x m) */
    float alpha2, beta;      /* the tests: |p_j - p|^2 < alpha2, n_j . n > beta */
    float cap2;              /* 0: that distance test (Laine 2007 Fig. 5); > 0: the tangent-plane test
                                instead, (n . (p_j - p))^2 < alpha2 and |p_j - p|^2 < cap2
                                (gi_indirect.h, GI_FILTER_PLANE_CAP) */
} gi_filter_in;

/* Laine's position test (Fig. 5), |p_j - p|^2 = d2 < alpha^2; or, with
 * cap2 > 0 (the default, beyond the paper: gi_indirect.h
 * GI_FILTER_PLANE_CAP), the neighbour's distance from the pixel's tangent
 * plane, (n . (p_j - p))^2 = dp2 < alpha^2, within |p_j - p|^2 < cap2. On a
 * surface seen at a grazing angle pixels two apart on screen lie further
 * apart than alpha along it, so the distance test cut the n x m windows on
 * such walls and faces and the interleaving's missing groups showed as
 * stripes; the plane test keeps the surface and still rejects a parallel one
 * behind it. The SIMD kernels repeat it lane-wise (gi__laine_take). */
static inline int gi_filter_near(const gi_filter_in *in, float d2, float dp2)
{
    return in->cap2 > 0.0f ? dp2 < in->alpha2 && d2 < in->cap2 : d2 < in->alpha2;
}

/* What the joint upsampling (step 9b, --indirect-scale s > 1) reads: the
 * frame's G-buffer, the reduced one and the reduced irradiance, explicitly. */
typedef struct gi_upsample_in {
    const rs_gbuffer *g;                        /* GBUFFER, the frame's */
    const float *lpx, *lpy, *lpz, *lnx, *lny, *lnz; /* the reduced G-buffer's planes */
    const uint32_t *lprim;
    const float *le;      /* FILTERED at the reduced size, 3 floats a pixel */
    uint32_t s, w, h, W;  /* scale, reduced size, frame width */
    float a2, beta;       /* the filter's tests */
} gi_upsample_in;

/* The a-trous filter's planes (--filter atrous, gi_atrous.c): irradiance in
 * three planes, its luminance and the variance of its luminance, w x h. */
typedef struct gi_atrous_planes {
    float *r, *g, *b, *lum, *var;
} gi_atrous_planes;

/* One a-trous level (gi_atrous.c, the reference): taps 3 x 3 at holes of
 * `step` pixels over `src`, the luminance test's scales in `inv_sd`. */
typedef struct gi_atrous_in {
    const rs_gbuffer *g;            /* GBUFFER at the indirect resolution */
    uint32_t w, h;
    gi_atrous_planes src, dst;      /* this level's input and output */
    const float *inv_sd;            /* 1 / (sigma_l sqrt(g3x3(src.var)) + eps) */
    int step;
    float inv_sigma_p, sigma_l;
} gi_atrous_in;

typedef struct gi_indirect_kernels {
    const char *isa;  /* SIMD_NAME of the vocabulary it was compiled with */
    uint32_t width;   /* SIMD_W: pixels per run */
    /* `groups` runs of `width` consecutive tile pixels (split planes at px..nz)
     * against the VPLs assign[a0..a1) with their paraboloid maps (exact or
     * ISMs): e[3 width g + 3 i + c] gets the unweighted sum of run g, lane i,
     * colour c, each pixel adding its VPLs in the tile's order. */
    void (*accumulate)(const gi_accumulate_in *in, const float *px, const float *py, const float *pz,
                       const float *nx, const float *ny, const float *nz, uint32_t groups, uint32_t a0, uint32_t a1,
                       float *e);
    /* Laine's box filter for `width` interior pixels x.. of row y of the
     * indirect image (every window pixel on screen horizontally); out gets 3
     * floats a pixel. */
    void (*filter_box)(const gi_filter_in *in, int x, int y, float *out);
    /* The upsampling of `width` pixels x.. of frame row y whose reduced
     * samples lie in columns x / s .. x / s + width - 1 of the reduced
     * image (the caller checks): out (3 floats a pixel) gets each pixel's
     * bilinear blend of the samples that pass, 0 elsewhere. Returns the
     * lanes (bit i: pixel x + i) with a surface that no sample passes: the
     * caller gives them the 3 x 3 fallback. */
    uint32_t (*upsample)(const gi_upsample_in *in, uint32_t x, uint32_t y, float *out);
    /* --filter atrous: the box pass (the box filter's mean, in planes, with
     * its luminance and the variance of that mean) and one a-trous level,
     * for `width` pixels x.. of row y whose windows lie on screen
     * horizontally (the caller checks; gi_atrous.c is the reference). */
    void (*atrous_box)(const gi_filter_in *in, int x, int y, const gi_atrous_planes *out);
    void (*atrous_level)(const gi_atrous_in *in, int x, int y);
} gi_indirect_kernels;

extern const gi_indirect_kernels gi_indirect_kernels_scalar;
extern const gi_indirect_kernels gi_indirect_kernels_avx2;   /* x86 only */
extern const gi_indirect_kernels gi_indirect_kernels_avx512; /* x86 only */

#endif
