/* gi_aa: anti-aliasing of the frame: one sub-pixel jitter pattern, and the
 * two ways softgi averages it, N samples in one frame (`--aa N`,
 * supersampling) and one sample a frame accumulated over frames (`--taa N`,
 * temporal anti-aliasing).
 *
 * This work is based on:
 * - the pixel as a box filter estimated with low-discrepancy samples: the
 *   Halton sequence (Halton 1960) under a Cranley-Patterson rotation
 *   (Cranley and Patterson 1976), as in pbrt (Pharr, Jakob and Humphreys,
 *   Physically Based Rendering, 3rd ed., Sec. 7.4 and 7.8); softgi's path
 *   tracer (gi_reference) already box-filters each pixel;
 * - temporal anti-aliasing: reprojection caches (Nehab et al. 2007; Yang et
 *   al. 2009, "Amortized supersampling") and Karis 2014 ("High quality
 *   temporal supersampling", SIGGRAPH course): a Halton jitter per frame, the
 *   history fetched bilinearly at the reprojected position and clamped to the
 *   current 3 x 3 neighbourhood.
 *
 * The pattern (gi_aa_jitter). Point j is the Halton point (bases 2 and 3)
 * rotated by (1/2, 1/2) on the unit torus and centred on the pixel:
 *   (jx, jy) = (frac(h2(j) + 1/2) - 1/2, frac(h3(j) + 1/2) - 1/2) in [-1/2, 1/2)^2,
 * an offset in pixels from the pixel's centre, x to the right and y down (the
 * image's axes). Point 0 is (0, 0), the pixel centre, so one sample is
 * today's image bit for bit. The rotation keeps the Halton points' low
 * discrepancy (a toroidal shift), and the first 2^k x-offsets (k >= 1) are
 * the k-bit grid exactly, so a vertical edge's coverage is found within
 * 1 / 2^k.
 * Nothing in it is random: the same points on every machine, thread count
 * and run.
 *
 * One definition everywhere. Sample (jx, jy) of pixel (x, y) sees what the
 * primary ray through the image point (x + 1/2 + jx, y + 1/2 + jy) sees:
 * - the ray-traced G-buffer casts exactly that ray (gi_camera_ray_at);
 * - the rasterized G-buffer draws with the view-projection shifted in clip
 *   space, x_clip -= 2 jx / W w_clip and y_clip += 2 jy / H w_clip
 *   (gi_aa_view_proj): the image moves by (-jx, -jy) pixels, so the pixel
 *   centres the rasterizer samples land on the jittered points; and the
 *   attribute resolve intersects the triangle with the same ray, given as a
 *   camera whose forward axis is tilted by the offset (gi_aa_resolve_camera;
 *   the view depth is then recomputed with the true axis).
 * Nothing else in the frame looks at the jitter: every later stage reads
 * positions and normals from the G-buffer. The camera the frame keeps
 * (gi_frame.camera) is always the unjittered one: reprojection (the
 * indirect light's temporal stage, the TAA) maps a sample's surface into
 * last frame's unjittered pixel grid, where a still camera's sample of
 * pixel (x, y) falls into pixel (x, y) itself.
 *
 * Supersampling (--aa N, gi_frame_set_aa; 1..GI_AA_MAX_SAMPLES, default
 * 1). A frame renders N samples, the pattern's points 0..N-1, in the order
 * 1, 2, ..., N-1, 0, and averages their linear radiance (`final`) before
 * anything is written or tone mapped. Per sample: the G-buffer (visibility
 * and attributes, or the primary rays), the direct light (shadow-map
 * lookups or shadow rays; the ray-traced area-light samples decorrelated by
 * the pattern index), split, accumulate, combine, compensate, filter,
 * upsample, temporal and compose. Once per frame, with the first sample,
 * what does not depend on the camera: the VPL update, the VPLs' maps (or
 * ISMs), the VPL-to-tile assignment, the lights' shadow maps and the area
 * lights' maps. The interleaved tiles' VPL groups rotate from sample to
 * sample (tile t shades sample s with group (t + s) mod n m, as the
 * temporal stage rotates them from frame to frame), so N samples of an
 * n x m interleaving see up to N of its groups: the samples reduce the
 * VPL noise as well as the aliasing. The centre sample is rendered last,
 * so the frame's other buffers (G-buffer, direct, the indirect stages) are
 * the pixel centres' after the frame: dumps, the stepper, the probe and
 * sequence's depth files see exactly the frame of --aa 1 (with the VPL set
 * of the first sample). Methods that read the G-buffer (SMC, MIR, InvTM,
 * TCAS, SSVP) update from the first sample's; with --pipeline on the next
 * frame's update is started after the last (the centre) sample's G-buffer,
 * which no later stage overwrites. With --temporal, every sample blends with
 * the previous frame's history and only the centre sample writes it. The
 * average is the sum in sample order divided by N, per pixel, so the image
 * is the same for any thread count.
 *
 * Temporal anti-aliasing (--taa N, 2..GI_AA_MAX_TAA; 0: off). Frame k
 * (counted from when the TAA was set) renders its samples at pattern
 * points (k mod N) * S + s, s = 0..S-1 (S = --aa, usually 1), so over N
 * frames a still pixel sees N S points; frame 0 is the pixel centres. After
 * the frame's own samples are averaged, stage gi_stage_taa blends `final`
 * with a history:
 * - reprojection: the nearest surface point of the pixel's 3 x 3
 *   neighbourhood (Karis 2014: so an edge pixel whose sample missed the
 *   foreground moves with the foreground; none: the pixel sample's
 *   direction, the background at infinity) is projected into last frame's
 *   and this frame's unjittered cameras; the difference is the pixel's
 *   motion, and the history is fetched bilinearly at the pixel's centre plus
 *   the motion (exactly the pixel itself when the camera has not moved);
 * - blend: the running mean over the last min(n, N) frames,
 *   H' = H + (C - H) / min(n + 1, N) (the indirect light's temporal stage's
 *   rule), so a still camera under static lights converges to the average
 *   of N S pattern points: frame N - 1 equals --aa N S up to rounding; in a
 *   frame whose camera moved, over min(n, GI_TAA_MOVING_FRAMES) frames and
 *   with the history fetched by a Catmull-Rom filter (Karis 2014), both
 *   against the blur of resampling the history every frame;
 * - disocclusion and change: a history position off the screen restarts
 *   the pixel (H' = C); and in a frame whose camera or lights differ from
 *   the last frame's, the history is first clamped per channel to the
 *   minimum and maximum of the current frame's 3 x 3 neighbourhood (Karis
 *   2014), so a surface uncovered by the motion, or a moved shadow, takes
 *   the current image's colours instead of a ghost. In a frame with the
 *   camera and lights unchanged no clamp applies: the clamp would cut thin
 *   features no sample of the neighbourhood hit this frame (the dashes
 *   along Sibenik's ribs), so a still view keeps converging; changes of the VPL set
 *   alone (IIR, SMC) are followed within N frames, as the indirect light's
 *   temporal stage follows them.
 * Changing the TAA's settings restarts its history and its pattern. */
#ifndef GI_AA_H
#define GI_AA_H

#include <stddef.h>
#include <stdint.h>

#include "pf_result.h"
#include "pf_scene.h"
#include "rs_raster.h"

#define GI_AA_MAX_SAMPLES 256u /* --aa */
#define GI_AA_MAX_TAA 256u     /* --taa */
/* The TAA history's weight in a frame whose camera moved: the running mean
 * over at most this many frames. Every moved frame resamples the history
 * (a Catmull-Rom fetch), which blurs it a little each time; a shorter
 * memory keeps a moving image sharper at the price of less anti-aliasing
 * while the camera moves. Measured on scenes/sequences/sibenik-camera at
 * 320x240, frame 11 against the same frame with --aa 16 (MRE): no cap
 * (--taa 16) 0.089, 8: 0.083, 4: 0.067, 3: 0.064, 2: 0.067; no TAA 0.096
 * (docs/aa.md). */
#define GI_TAA_MOVING_FRAMES 4u

/* One worker's row of the TAA's separable 3 x 3 searches (gi_aa.c). */
typedef struct gi__taa_scratch {
    float *lo, *hi; /* RGB minimum and maximum of each column's three rows */
    float *nd;      /* each column's nearest surface's view depth */
    size_t *near;   /* and its pixel */
} gi__taa_scratch;

/* Temporal anti-aliasing's state (--taa N). */
typedef struct gi_taa {
    uint32_t frames;     /* N (0: off) */
    uint32_t frame;      /* frames blended since set: the pattern's frame index */
    float *hist[2];      /* RGB radiance, the frame's size: [cur] is last frame's */
    uint16_t *count[2];  /* frames in each pixel's history */
    int cur;
    pf_camera camera;    /* last frame's camera (unjittered) */
    pf_light *lights;    /* last frame's lights (to tell a changed frame) */
    uint32_t light_count, light_cap;
    gi__taa_scratch *scratch; /* one per worker of the frame's job system */
    uint32_t workers;
} gi_taa;

/* The frame's anti-aliasing state (gi_frame.aa). */
typedef struct gi_aa {
    uint32_t samples; /* N per pixel per frame (1: the pixel centres) */
    uint32_t sample;  /* the sample being rendered, 0..N-1 (rendered 1, ..., N-1, 0) */
    uint32_t index;   /* its point of the pattern */
    float jx, jy;     /* its offset from the pixel centre, pixels (x right, y down) */
    float *sum;       /* N > 1: the samples' RGB radiance summed, the frame's size */
    gi_taa taa;
} gi_aa;

/* 1 while the frame's first sample renders (sample 1 of N > 1, else 0):
 * what is done once a frame, before any sample, goes there. */
static inline int gi_aa_first_render(const gi_aa *aa) { return aa->sample == 1u % (aa->samples ? aa->samples : 1u); }

struct gi_frame;

/* Point `index` of the pattern: *jx, *jy in [-1/2, 1/2); point 0 is (0, 0). */
void gi_aa_jitter(uint32_t index, float *jx, float *jy);

/* The camera's view-projection for a width x height image with the pixel
 * centres moved onto the jittered points (x + 1/2 + jx, y + 1/2 + jy);
 * rs_mat4_camera's matrix itself (the same bits) for (0, 0). */
rs_mat4 gi_aa_view_proj(const pf_camera *cam, uint32_t width, uint32_t height, float jx, float jy);

/* A camera whose ray through pixel (x, y)'s centre (the expression of
 * pf_camera_ray_dir) is the ray through (x + 1/2 + jx, y + 1/2 + jy) of
 * `cam`: its forward axis tilted by the offset (no longer unit length, so
 * view depth along it is not depth); `cam` itself for (0, 0). What the
 * G-buffer resolve, which traces the pixel centres' rays, is given. */
pf_camera gi_aa_resolve_camera(const pf_camera *cam, uint32_t width, uint32_t height, float jx, float jy);

/* Sets samples per pixel (1..GI_AA_MAX_SAMPLES) and the TAA's history
 * length (0: off, else 2..GI_AA_MAX_TAA); allocates what they need and
 * restarts the TAA's history. gi_frame_create calls it. */
pf_result gi_frame_set_aa(struct gi_frame *f, uint32_t samples, uint32_t taa_frames, pf_error *err);
void gi_aa_free(gi_aa *aa);

/* Before the k-th sample a frame renders (k = 0..N-1): sample (k + 1) mod
 * N, its pattern index and offset. */
void gi_aa_sample_begin(struct gi_frame *f, uint32_t k);

/* Stages (the stage table in gi_frame.c). gi_stage_aa_resolve, after each
 * sample's compose (N > 1): adds `final` to the sum; after the last,
 * `final` = sum / N. gi_stage_taa, once a frame after the samples (--taa):
 * blends `final` with the reprojected history (above). */
void gi_stage_aa_resolve(struct gi_frame *f);
void gi_stage_taa(struct gi_frame *f);

/* After a jittered resolve (gi_aa_resolve_camera): the G-buffer's view
 * depth recomputed along the camera's true forward axis (a no-op for the
 * centre sample). */
void gi_aa_resolve_depth(struct gi_frame *f);

#endif
