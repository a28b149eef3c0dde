/* gi_atrous: step 9 of the frame with --filter atrous, an edge-avoiding
 * a-trous wavelet filter (Dammertz, Sewtz, Hanika and Lensch, HPG 2010)
 * guided by a per-pixel variance (Schied et al., SVGF, HPG 2017, Sec. 4.3-4.4)
 * after Laine's geometry-aware box (Laine 2007 Fig. 5).
 *
 * Why after the box: the interleaved irradiance (Laine Sec. 5) gives each
 * pixel of an n x m block a different 1/(n m) of the VPLs, so the box first
 * turns the block into the every-VPL estimate, and the spread across the
 * block gives the variance of that estimate (the block's sample variance /
 * (pixels - 1)). The a-trous levels then widen the support (holes of 2^k
 * pixels at level k: a footprint of 2 (2^K - 1) + 1 pixels after K levels)
 * where the geometry and the luminance allow:
 *   w = h(dx) h(dy) . max(0, n . n_q)^sigma_n
 *       . exp(-|n . (p_q - p)| / sigma_p - |l - l_q| / (sigma_l sqrt(max(g3x3(var), g3x3(var_q))) + eps))
 * with the normal exponent and the luminance scale of SVGF (128 and 4), the
 * plane distance of the neighbour's point from the pixel's tangent plane
 * (beyond the papers: SVGF's screen-space depth gradient, in world space and
 * free of the camera; sigma_p = alpha / 4), and the variance carried through
 * the levels with the squared weights (SVGF Eq. 4-5).
 *
 * Deviations, measured (docs/frame.md): 3 x 3 taps (1, 2, 1) / 4 a level
 * instead of Dammertz's and SVGF's 5 x 5 B3 spline, and 4 levels instead of
 * SVGF's 5: 36 taps a pixel instead of 125, the error against the reference
 * within 0.003 of 5 x 5 with 4 levels on the Cornell box, and 3 to 6 levels
 * within 0.006 of each other; the luminance test's scale from the larger of
 * the two pixels' variances (SVGF: the centre pixel's), which keeps the
 * box's energy (the centre's alone darkened the Cornell box by 1-3%); exp by
 * a polynomial (gi_atrous_math.h) so that the SIMD paths give the scalar
 * bits.
 *
 * Deterministic: every level reads the previous level's buffers only, each
 * pixel sums its taps in a fixed order, so any thread count gives the same
 * bytes. */
#ifndef GI_ATROUS_H
#define GI_ATROUS_H

#include <stdint.h>

#include "pf_jobs.h"
#include "rs_gbuffer.h"

struct gi_indirect_kernels;

#define GI_ATROUS_DEFAULT_LEVELS 4u
#define GI_ATROUS_MAX_LEVELS 8u
#define GI_ATROUS_DEFAULT_SIGMA_L 4.0f   /* SVGF's sigma_l */

typedef struct gi_atrous_params {
    uint32_t levels;  /* a-trous levels after the box (0: GI_ATROUS_DEFAULT_LEVELS) */
    float sigma_l;    /* luminance scale in standard deviations (0: default) */
    float sigma_p;    /* plane distance scale in scene units */
} gi_atrous_params;

/* What the filter reads and writes, explicitly. */
typedef struct gi_atrous_io {
    const float *combined;   /* COMBINED, 3 floats a pixel, w x h */
    const rs_gbuffer *g;     /* GBUFFER at the indirect resolution */
    uint32_t w, h, n, m;     /* the indirect image's size; the tiles (the box is n x m) */
    float alpha2, beta;      /* Laine's box tests: |p_j - p|^2 < alpha2, n_j . n > beta */
    gi_atrous_params par;
    /* scratch: gi_atrous_scratch_floats(w, h) floats (two sets of
     * gi_atrous_planes and the blurred variance) */
    float *scratch;
    const struct gi_indirect_kernels *kt; /* the SIMD path's kernels, NULL on the scalar path */
    float *out;              /* FILTERED (or filtered_low), 3 floats a pixel */
    float cap2;              /* the box's position test: 0 Laine's distance test, > 0 the tangent-plane
                                test within |p_j - p|^2 < cap2 (gi_filter_in.cap2) */
} gi_atrous_io;

/* Floats of scratch the filter needs for w x h pixels. */
size_t gi_atrous_scratch_floats(uint32_t w, uint32_t h);
void gi_atrous_run(pf_jobs *jobs, const gi_atrous_io *io);

#endif
