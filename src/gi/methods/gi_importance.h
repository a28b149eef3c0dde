/* gi_importance: view-adaptive VPL sampling over reflective shadow maps
 * (Ritschel et al. 2011, "Making imperfect shadow maps view-adaptive";
 * Barak, Bittner, Havran 2013 Sec. 4): the importance map and the two
 * samplers that draw VPLs from it, shared by the `invtm` and `tcas`
 * methods.
 *
 * Importance (Barak 2013 Eq. 1-2, visibility left out as the paper says):
 *   f(v) = sum_k I(v) H(x_k, w_k, v),  H = f_r(x_k) G(x_k, r(v))
 * over P camera-visible points x_k taken from the frame's G-buffer, for
 * every RSM texel v. With Lambertian receivers f_r = albedo_k / pi and
 * I(v) = Phi_v / pi (Phi_v the texel's reflected flux); the constant 1/pi^2
 * is dropped (f only matters up to a factor), luminance is used for RGB, and
 *   G = max(0, n_k.d) max(0, -n_v.d) / |d|^4,  d = r(v) - x_k,
 * bounded by g_max (the frame's default bounded geometry term, 400 /
 * diagonal^2; Dachsbacher 2014 Sec. 5) so a texel next to a camera point
 * does not take all samples. Invalid texels have f = 0.
 * Camera points: pixel k (k = 0 .. P-1) is (floor(W h2(k+1)), floor(H
 * h3(k+1))), h_b the base-b radical inverse: a fixed pattern, the same
 * every frame (temporal coherence, Barak 2013's reason for fixed Halton
 * numbers); pixels that see nothing are skipped.
 *
 * Sampling domain (Barak 2013 Fig. 2/3): the VPL description vector v =
 * (l, row, column) from three uniform numbers: l = floor(xi1 L) picks one
 * of the L maps, row = floor(xi2 rows_l), column = floor(xi3 cols_l) (a cube
 * map's 6 faces stacked as 6 size rows, the area lights' map's K faces as
 * K size rows: gi_rsm_area.h, one more "light" of the domain). That
 * proposal has probability
 *   q(v) = 1 / (L rows_l cols_l)
 * per texel, uniform when all maps have as many texels, as in the paper.
 *
 * VPLs: a VPL made from texel v gets intensity Phi_v * s / pi with
 * s = 1 / (N p(v)) (InvTM, p = f / sum f) or s = w / (N f(v)) (IM-H,
 * Barak 2013 Eq. 3), so the sum over VPLs is an (approximately, for IM-H)
 * unbiased estimate of the first bounce (gi_vpl.h units). */
#ifndef GI_IMPORTANCE_H
#define GI_IMPORTANCE_H

#include <stdint.h>

#include "gi_rsm.h"
#include "gi_vpl.h"
#include "pf_jobs.h"
#include "rs_gbuffer.h"

#define GI_IMPORTANCE_DEFAULT_P 256u

/* -------------------------------------------------------- sampling domain */

/* L maps of rows x cols texels; map m's texel (row, col) is the flat index
 * first[m] + row * cols[m] + col. The arrays are owned by the caller. */
typedef struct gi_sample_domain {
    uint32_t maps;
    const uint32_t *first, *rows, *cols;
    uint32_t total; /* sum of rows * cols */
} gi_sample_domain;

/* The proposal of Barak 2013 Sec. 4.3: uniform numbers in [0, 1) -> flat
 * texel index; *q (may be NULL) receives its proposal probability. */
uint32_t gi_domain_texel(const gi_sample_domain *d, double xi1, double xi2, double xi3, double *q);

/* ---------------------------------------------------------- importance map */

typedef struct gi_importance {
    uint32_t P;          /* camera points asked for */
    uint32_t count;      /* camera points found (non-empty pixels) */
    float *x, *y, *z;    /* camera points (count) */
    float *nx, *ny, *nz;
    float *alb;          /* luminance of the albedo */
    float *f;            /* importance per RSM texel (texel_count) */
    uint32_t f_cap;
    /* the domain of the RSM set the map was computed for */
    uint32_t *first, *rows, *cols;
    uint32_t map_cap;
    gi_sample_domain domain;
} gi_importance;

/* P: camera points (>= 1). No allocation until the first update. */
void gi_importance_init(gi_importance *im, uint32_t P);
void gi_importance_free(gi_importance *im);
/* Camera points from g, then f(v) for every texel of rsm (parallel over
 * texel rows, deterministic), and the sampling domain of rsm's maps.
 * G is bounded by 400 / diagonal^2 (diagonal: the scene's bounding box).
 * simd (an rs_simd, gi_vpl_inputs.simd): the SIMD kernel of that path
 * (gi_importance_kernels.h), with the scalar loop's bits; 0: the loop. */
pf_result gi_importance_update(gi_importance *im, const gi_rsm_set *rsm, const rs_gbuffer *g, float diagonal,
                               uint32_t simd, pf_jobs *jobs, pf_error *err);

/* -------------------------------------------------------------- samplers */

/* Inverse transform method (Barak 2013 Sec. 4.2, Ritschel 2011): CDFs over
 * maps, rows within a map and texels within a row (gi_invtm.c). */
typedef struct gi_invtm_cdf {
    double *map_cdf;   /* maps: inclusive prefix sums of the maps' masses */
    double *row_cdf;   /* one entry per row of every map: prefix sums within the map */
    double *texel_cdf; /* one entry per texel: prefix sums within the row */
    uint32_t *row_first; /* per map: index of its first row in row_cdf */
    uint32_t map_cap, row_cap, texel_cap;
    double total;      /* sum of f */
} gi_invtm_cdf;

pf_result gi_invtm_build(gi_invtm_cdf *c, const gi_sample_domain *d, const float *f, pf_jobs *jobs, pf_error *err);
void gi_invtm_free(gi_invtm_cdf *c);
/* Three binary searches. dims 3: xi1 picks the map, xi2 the row, xi3 the
 * column; dims 2: xi1 picks the map and, renormalised to [0, 1) within the
 * map's CDF interval, the row; xi2 the column (xi3 unused) (Sec. 4.2, "as
 * for direct lighting [SW91]"). Returns the texel; total must be > 0. */
uint32_t gi_invtm_sample(const gi_invtm_cdf *c, const gi_sample_domain *d, int dims, double xi1, double xi2,
                         double xi3);

/* Independent Metropolis-Hastings, one chain (Barak 2013 Algorithm 1, in
 * gi_tcas.c): chain j of N, length M (M samples: the initial proposal and
 * M - 1 moves), proposal k from Halton index gi_imh_index(j, k, N, M)
 * (bases 2, 3, 5 for the vector, 7 for the acceptance number).
 * Returns the final texel; *w the chain's mean of f(v)/q(v) over its M
 * proposals (an estimate of sum f), *fv = f(final), *g0 (may be NULL)
 * f(v)/q(v) of the initial sample (M-H-Single's weight). */
/* Halton index of chain j's k-th proposal: 1 + pi(j + N k), pi a fixed
 * permutation of [0, N M) (gi_tcas.c says why). N M must be < 2^32 - 1. */
uint32_t gi_imh_index(uint32_t j, uint32_t k, uint32_t N, uint32_t M);
uint32_t gi_imh_chain(const gi_sample_domain *d, const float *f, uint32_t j, uint32_t N, uint32_t M, double *w,
                      float *fv, double *g0);

/* ------------------------------------------------------------------ views */

/* The learner's view of an importance map (InvTM's and TCAS's own view,
 * gi_vpl_method.view): every RSM face as a square cell in a grid fitted to
 * the picture, each pixel the heat of f at the texel under it (black where
 * the RSM saw nothing). gi_importance_canvas_draw lays out and draws it and
 * fills lo..hi, the range of f the legend names; returns 0 when there is
 * nothing to draw or the picture is too small. */
typedef struct gi_importance_canvas {
    uint32_t across, cell, ox, oy, faces;
    uint32_t face0[64]; /* per map: the index of its first face among all faces */
    float lo, hi;
} gi_importance_canvas;
int gi_importance_canvas_draw(gi_importance_canvas *cv, const gi_rsm_set *R, const gi_importance *im,
                              const gi_vpl_view_ctx *c, uint8_t *rgb);
/* The picture point at the centre of texel t. */
void gi_importance_canvas_texel_xy(const gi_importance_canvas *cv, const gi_rsm_set *R, uint32_t t, float *x,
                                   float *y);

/* ------------------------------------------------------------------ VPLs */

/* The VPL of texel t (valid) with intensity flux_t * scale / pi, the
 * position pushed off the surface along the geometric normal. */
void gi_rsm_vpl(const gi_rsm_set *rsm, uint32_t t, double scale, uint32_t id, gi_vpl *out);
/* moved = position or normal differs from prev's slot i (or prev has no
 * slot i); then copies cur into prev. */
pf_result gi_vpl_mark_moved(gi_vpl_set *cur, gi_vpl_set *prev, pf_error *err);

#endif
