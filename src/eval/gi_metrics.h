/* gi_metrics: image and sequence metrics for comparing renders with a
 * reference, and the per-frame camera/depth files a sequence
 * carries so that the temporal metric can reproject.
 *
 * This work is based on:
 * - Hedman, Karras, Lehtinen 2017, "Sequential Monte Carlo Instant
 *   Radiosity", Sec. 5.2, Table 1, Eq. 10 and Fig. 7: the luminance of a few
 *   tracked pixels is followed over time, "after applying the Reinhard tone
 *   mapping operator [38]". |E| is the mean absolute error of that tone-mapped
 *   luminance against the reference over all tracked pixels and frames; E' =
 *   dError/dt (Eq. 10) is its finite difference between consecutive frames
 *   (dt = 1 frame) and |E'| the mean of its absolute value.
 * - Barak et al. 2013, "Temporally Coherent Adaptive Sampling for Imperfect
 *   Shadow Maps", Sec. 6.2: the temporal image difference TID, "a RMS value
 *   of differences among intensities of matching pixels for all consecutive
 *   pairs of frames", pixels matched by reprojection through their
 *   world-space positions.
 * - Reinhard et al. 2002, "Photographic Tone Reproduction", Eq. 3:
 *   L_d = L / (1 + L).
 *
 * Choices (argued in gi_metrics.c)
 * - Luminance: Rec. 709 / sRGB weights on linear RGB,
 *   Y = 0.2126 R + 0.7152 G + 0.0722 B.
 * - Tone map for |E|, |E'| and the tracked-pixel plot: Reinhard Eq. 3 applied
 *   to the luminance, T(Y) = s Y / (1 + s Y) with s = 2^exposure (1 by
 *   default), no sRGB encoding. Reinhard defines the operator on luminance
 *   and Hedman tracks "the luminance ... after applying the Reinhard tone
 *   mapping operator", so the tracked quantity is Reinhard's display
 *   luminance. (pf_imageio_display applies the same curve per channel for
 *   the PNG; for grey pixels the two agree exactly.)
 * - RMSE and MAE: over all pixels and the three channels of linear RGB.
 * - TID intensities: linear luminance by default (Barak measures the
 *   radiosity solution, "pixel intensities", with no tone map mentioned);
 *   gi_metrics_tid_desc.tonemapped switches to T(Y) to put TID on |E|'s scale.
 * - Reprojection direction: Barak carries frame t-1's pixels forward to
 *   frame t; we gather instead: each pixel of frame t with finite depth is
 *   reconstructed in world space, projected into camera t-1 and compared
 *   with the nearest pixel there if that pixel is on screen and its depth
 *   agrees within a relative tolerance (disocclusions excluded). Both give
 *   the same matched pairs up to resampling; gathering has no splat
 *   collisions.
 *
 * Per-frame sequence files (written by `softgi sequence`, read by
 * `softgi compare`), NNNN the zero-padded frame index from 0000:
 *   DIR/frame_NNNN.pfm        linear RGB (pf_imageio PFM)
 *   DIR/frame_NNNN.view       the camera, text (gi_metrics_view_write):
 *                               softgi-view 1
 *                               width W
 *                               height H
 *                               eye X Y Z
 *                               forward X Y Z
 *                               up X Y Z
 *                               right X Y Z
 *                               yfov RADIANS
 *                             floats printed with %.9g (exact round trip);
 *                             forward/up/right orthonormal, right =
 *                             forward x up, as pf_camera.
 *   DIR/frame_NNNN.depth.pfm  view depth (distance along forward, as
 *                             rs_gbuffer.depth) in R, G = B = 0, +inf for
 *                             sky; 3-channel PFM of size W x H.
 *
 * Conventions: images are row-major from the top row, 3 floats per pixel
 * (pf_imageio). Pixel (x, y) has its centre at (x + 0.5, y + 0.5) and looks
 * along pf_camera_ray_dir(cam, W, H, x + 0.5, y + 0.5), the pinhole model
 * whose aspect is W / H. */
#ifndef GI_METRICS_H
#define GI_METRICS_H

#include <stddef.h>
#include <stdint.h>

#include "pf_math.h"
#include "pf_result.h"
#include "pf_scene.h"

/* Hedman 2017 tracks 8 pixels per sequence. */
#define GI_METRICS_DEFAULT_TRACKED 8
/* Depth agreement for a reprojected match: |z - z_prev| <= tol * max(z, z_prev). */
#define GI_METRICS_DEFAULT_DEPTH_TOLERANCE 0.01f

/* ---------------------------------------------------------------- pixels */

/* Rec. 709 luminance of one linear RGB triple. */
float gi_metrics_luminance(const float *rgb);
/* Reinhard 2002 Eq. 3, x / (1 + x): 0 for x <= 0 or NaN, 1 for +inf. */
float gi_metrics_reinhard(float x);
/* The quantity |E| and the plot track: reinhard(exposure_scale * luminance). */
float gi_metrics_display_luminance(const float *rgb, float exposure_scale);

/* ---------------------------------------------------------------- images */

/* Root mean square and mean absolute difference over pixel_count pixels x 3
 * channels of linear RGB. 0 for pixel_count 0. */
double gi_metrics_rmse(const float *rgb, const float *ref, size_t pixel_count);
double gi_metrics_mae(const float *rgb, const float *ref, size_t pixel_count);
/* The mean relative error per pixel the quality targets use:
 * mean over the pixels whose reference luminance Y_ref exceeds `floor` of
 * |Y - Y_ref| / Y_ref (Rec. 709 luminance of linear RGB); *counted (may be
 * NULL) gets how many pixels took part. 0 when none does. */
#define GI_METRICS_MRE_FLOOR 1e-4f
double gi_metrics_mean_relative_error(const float *rgb, const float *ref, size_t pixel_count, float floor,
                                      size_t *counted);
/* Energy ratio: the sum of luminance of rgb over that of ref (NaN when the
 * reference is black). */
double gi_metrics_energy_ratio(const float *rgb, const float *ref, size_t pixel_count);
/* Mean over all pixels of |T(Y) - T(Y_ref)| (Hedman's |E| for one frame,
 * every pixel tracked). */
double gi_metrics_abs_error_image(const float *rgb, const float *ref, size_t pixel_count, float exposure_scale);

/* ---------------------------------------------------------------- tracked pixels */

typedef struct gi_metrics_pixel {
    uint32_t x, y;
} gi_metrics_pixel;

/* Writes `count` deterministic tracked pixels of a width x height image into
 * dst: the centres of the cells of a cols x rows grid, cols = ceil(sqrt(count
 * * W / H)), filled row by row and stopping after count (8 pixels on a 4:3
 * image: a 4 x 2 grid). Returns the number written (count, or fewer only
 * for an image with fewer pixels than count). */
uint32_t gi_metrics_track_grid(gi_metrics_pixel *dst, uint32_t count, uint32_t width, uint32_t height);

/* dst[k] = gi_metrics_display_luminance of pixel px[k] of the image. */
void gi_metrics_track_sample(float *dst, const float *rgb, uint32_t width, uint32_t height,
                             const gi_metrics_pixel *px, uint32_t count, float exposure_scale);

/* Series of tracked values: value[t * count + k] for frame t, pixel k.
 * |E|: mean over frames and pixels of |method - ref|. 0 frames: NaN. */
double gi_metrics_abs_error(const float *method, const float *ref, uint32_t frames, uint32_t count);
/* |E'| (Hedman Eq. 10): mean over t >= 1 and pixels of
 * |(method_t - ref_t) - (method_{t-1} - ref_{t-1})|. Fewer than 2 frames: NaN. */
double gi_metrics_abs_error_rate(const float *method, const float *ref, uint32_t frames, uint32_t count);

/* ---------------------------------------------------------------- views and reprojection */

typedef struct gi_metrics_view {
    pf_vec3 eye, forward, up, right; /* as pf_camera */
    float yfov;                      /* radians, full vertical field of view */
    uint32_t width, height;          /* image size; aspect = width / height */
} gi_metrics_view;

void gi_metrics_view_from_camera(gi_metrics_view *view, const pf_camera *cam, uint32_t width, uint32_t height);
/* Writes / reads DIR/frame_NNNN.view (format above). Reading checks the
 * header, finite values, nonzero size, 0 < yfov < pi and a roughly
 * orthonormal basis (PF_ERR_PARSE otherwise). */
pf_result gi_metrics_view_write(const char *path, const gi_metrics_view *view, pf_error *err);
pf_result gi_metrics_view_read(const char *path, gi_metrics_view *view, pf_error *err);
/* Writes / reads DIR/frame_NNNN.depth.pfm: depth[y * W + x] in R. */
pf_result gi_metrics_depth_write(const char *path, const float *depth, uint32_t width, uint32_t height,
                                 pf_error *err);
pf_result gi_metrics_depth_read(const char *path, float **depth, uint32_t *width, uint32_t *height, pf_error *err);

/* One frame of a sequence for TID; rgb and depth are view->width x height. */
typedef struct gi_metrics_frame {
    const float *rgb;
    const float *depth;
    const gi_metrics_view *view;
} gi_metrics_frame;

/* Zero-initialise for the defaults. */
typedef struct gi_metrics_tid_desc {
    float depth_tolerance; /* relative; 0: GI_METRICS_DEFAULT_DEPTH_TOLERANCE */
    int tonemapped;        /* 0: linear luminance (Barak); 1: T(Y) as |E| */
    float exposure_scale;  /* for tonemapped; 0: 1 */
} gi_metrics_tid_desc;

/* Running sums over all consecutive pairs of a sequence. */
typedef struct gi_metrics_tid_sum {
    double sum_sq;  /* sum of squared intensity differences */
    uint64_t count; /* matched pixels */
} gi_metrics_tid_sum;

/* Adds the matched pixels of the pair (prev = frame t-1, cur = frame t) to
 * acc. The two frames may differ in size. desc may be NULL. */
void gi_metrics_tid_pair(gi_metrics_tid_sum *acc, const gi_metrics_frame *prev, const gi_metrics_frame *cur,
                         const gi_metrics_tid_desc *desc);
/* sqrt(sum_sq / count); NaN when nothing matched. */
double gi_metrics_tid_value(const gi_metrics_tid_sum *acc);

#endif
