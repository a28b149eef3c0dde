/* gi_indirect: the many-light part of a frame, Laine 2007 Sec. 3 steps 3-9
 * and Sec. 5 (interleaved sampling after Keller and Heidrich 2001 and Wald
 * 2004; the bounded geometry term of the survey's Sec. 5):
 *
 *   gi_stage_vpl_update        the VPL method's update (step 3)
 *   gi_stage_vpl_update_begin  the same update for the next frame, started
 *   gi_stage_vpl_update_end    as a task that overlaps this frame's stages
 *                              (--pipeline on: Laine 2007 Sec. 3 and 6, the
 *                              one-frame delay in VPL positions and
 *                              intensities; see "Pipelining" below)
 *   gi_stage_vpl_shadow_maps   paraboloid maps, re-rendered only for new or
 *                              moved VPLs (step 4, Laine 2007 Sec. 6); or
 *                              (--visibility ism) imperfect shadow maps of
 *                              every VPL, rebuilt every frame (gi_ism.h)
 *   gi_stage_split             the G-buffer split into n x m interleaved
 *                              tiles: pixel (a, b) of tile (i, j) is pixel
 *                              (a n + i, b m + j) of the image (Sec. 5.1)
 *   gi_stage_assign            VPLs to tiles, stable over a VPL's life: a
 *                              surviving VPL keeps its tile (Laine 2007
 *                              Sec. 7), new ones go to the tile with the
 *                              least luminance; a set with no survivor is
 *                              sorted by luminance and dealt in boustrophedon
 *                              order, so every tile gets a representative
 *                              subset (the problem Laine 2007 Sec. 7 names)
 *   gi_stage_accumulate        each tile pixel's irradiance from its tile's
 *                              VPLs: E = T * sum I G_b V, with G_b =
 *                              min(cos cos / r^2, b) and V from the VPL's
 *                              paraboloid map (or its ISM, with the ISM
 *                              bias, or an Embree ray); T = n m
 *                              makes the n x m average the full sum
 *   gi_stage_combine           back to image layout (Sec. 5.1)
 *   gi_stage_filter            Laine's geometry-aware n x m box filter
 *                              (Fig. 5: |p2 - p| < alpha, n2 . n > beta), or a
 *                              cross-bilateral filter, an edge-aware
 *                              Gaussian (Aranha Sec. III-D), or none (Sec. 5.2)
 *
 * VPL cycling (opt.cycle = C >= 2; beyond the papers, with --temporal):
 * the method keeps C times the budget of VPLs (its update sees a budget of
 * C x vpls), every slot s in slice s mod C, and frame k shades slice k mod
 * C only, its vpls VPLs dealt to the n x m tiles as above, weighted C T.
 * So a frame costs the accumulation of `vpls` VPLs, and the temporal
 * history of C frames (C dividing --temporal N) averages the whole set of
 * C x vpls, the interleaving of Keller and Heidrich 2001 stretched over
 * time. A slot's map is drawn the first time its slice is shaded after the
 * VPL was made or moved (map_ok), so a static scene draws every map once,
 * vpls of them a frame during the first C frames, and none after.
 * The progressive warm-up (opt.cycle_maps = B > 0; beyond the papers): the
 * rotation starts with slice 0 alone and takes in slice L (L = 1, 2, ...)
 * once its maps are drawn, B of them a frame ahead of its first shading;
 * the frames shade the slices in the rotation in turn. So no frame draws
 * more than one slice's missing maps plus B (not vpls every frame for C
 * frames), and a still view's history takes in a new slice every
 * ceil(vpls / B) frames. A slice's frame is its own unbiased estimate
 * (weighted C T as above), so the warm-up only weights the early slices
 * more for a while.
 *
 * The receiving surface's albedo is applied at compose: radiance = albedo /
 * pi * E (Sec. 5.1: "the color of the receiving surface is not taken into
 * account at this point").
 *
 * Pipelining (opt.pipeline; Laine 2007 Sec. 3: "G-buffer rendering and
 * splitting ... can be performed in parallel with VPL management", Sec. 6:
 * "allowing one-frame delay in the positions and intensities of the VPLs").
 * The VPL set is double-buffered: `vpls` is the set this frame shades with
 * (paraboloid maps, assign, accumulate, the VPL dump), `vpls_next` the set
 * the method's update writes. Frame 0 runs the update in place, as without
 * pipelining. Every later frame N shades with the set the update made
 * during frame N-1 and adds the update for frame N as one job of the job
 * system (no extra thread): it starts before the G-buffer for methods that
 * never read the G-buffer (gi_vpl_method.gbuffer_free: IR and IIR),
 * else right after the G-buffer is resolved, and runs alongside the
 * remaining stages; the two sets swap at the start of the next frame (so
 * after a frame `vpls` is still the set it shaded with, for the dumps and
 * the moved counts).
 * The update for frame N sees exactly what the unpipelined update of frame
 * N sees (frame number N, frame N's lights, camera and G-buffer), so what
 * lags is only its result: frame N >= 1 is shaded with the VPL set of frame
 * N-1 (positions, normals, intensities, moved flags), while its G-buffer,
 * direct light and shadow maps are frame N's. Pipelined frame N equals the
 * unpipelined frame N rendered with the unpipelined frame N-1's set
 * (tests/test_pipeline.c checks it bit for bit). */
#ifndef GI_INDIRECT_H
#define GI_INDIRECT_H

#include "pf_arena.h"
#include "gi_vpl.h"
#include "gi_ism.h"
#include "rs_paraboloid.h"
#include "gi_atrous.h"

/* GI_FILTER_GAUSSIAN: Aranha's "edge-aware gaussian blur" (SSVP Sec. III-D).
 * GI_FILTER_ATROUS: Laine's box, then variance-guided edge-avoiding a-trous
 * levels (Dammertz 2010, SVGF 2017; gi_atrous.h). */
typedef enum gi_filter_kind {
    GI_FILTER_BOX = 0,
    GI_FILTER_BILATERAL,
    GI_FILTER_NONE,
    GI_FILTER_GAUSSIAN,
    GI_FILTER_ATROUS
} gi_filter_kind;

typedef struct gi_indirect_options {
    const gi_vpl_method *method; /* NULL: Instant Radiosity */
    gi_params params;            /* --param KEY=VALUE for the method */
    uint32_t vpls;               /* budget (0: 256) */
    uint32_t bounces;            /* (0: 3) */
    uint32_t tiles_n, tiles_m;   /* (0: 4 x 4) */
    int no_interleave;           /* 1 x 1 tiles: every pixel sees every VPL */
    int visibility_raytrace;     /* Embree shadow rays instead of paraboloid maps */
    int visibility_ism;          /* imperfect shadow maps (Ritschel 2008) instead of exact paraboloid maps */
    int para_slope;              /* exact maps: the slope-scaled bias test instead of the receiver-plane
                                    test (rs_paraboloid.h "Lookup"; --visibility paraboloid-slope) */
    float clamp;                 /* b = clamp / diagonal^2; 0 = off; < 0 = default 400 */
    gi_filter_kind filter;
    float alpha_rel;             /* filter position threshold, x diagonal (0: 0.02) */
    float beta;                  /* filter normal threshold (0: 0.8, Laine 2007) */
    int filter_distance;         /* 1: the filter's position test is Laine's |p2 - p| < alpha (the paper);
                                    0: the neighbour's distance from the pixel's tangent plane,
                                    |n . (p2 - p)| < alpha, within GI_FILTER_PLANE_CAP alpha
                                    (--filter-test distance|plane; docs/frame.md) */
    gi_atrous_params atrous;     /* GI_FILTER_ATROUS: levels, sigma_l; sigma_p 0: alpha / 4 */
    uint32_t para_res;           /* paraboloid map resolution (0: 128); with ISMs: the ISM resolution */
    gi_ism_options ism;          /* --visibility ism: resolution, points, bias (zero: gi_ism.h defaults) */
    int pipeline;                /* 1: VPL update of the next frame overlaps this frame (see above) */
    int compensate;              /* 1: screen-space compensation of the energy the clamp removes
                                    (gi_stage_compensate; the survey's Sec. 5.2, after Novak 2011) */
    uint32_t compensate_taps;    /* samples per pixel (0: 32) */
    uint32_t temporal;           /* 0: off; N >= 2: temporal accumulation of the filtered irradiance over
                                    up to N frames, with reprojection (gi_stage_temporal; beyond Laine
                                    2007) and the tiles' VPL groups rotated every frame */
    uint32_t scale;              /* 1: the indirect stages run at full resolution; 2..4: at
                                    (width / scale) x (height / scale), upsampled geometry-aware
                                    (gi_stage_upsample; beyond the papers); 0 (GI_INDIRECT_SCALE_AUTO):
                                    2 for frames of at least GI_INDIRECT_AUTO_PIXELS, else 1 */
    uint32_t cycle;              /* 0 or 1: off; C in 2..GI_INDIRECT_MAX_CYCLE: VPL cycling (see above), the
                                    set C x vpls, one slice of vpls shaded a frame; needs temporal and
                                    paraboloid maps or ray-traced visibility */
    uint32_t cycle_maps;         /* with cycle and paraboloid maps, the progressive warm-up: the most maps a
                                    frame draws ahead for a slice not yet in the rotation (see above); 0: no
                                    limit, every slice in the rotation from frame 0 */
} gi_indirect_options;

/* The tangent-plane test's reach: neighbours within this many alpha of
 * the pixel (docs/frame.md: 2, 4, 8 and no cap measured within 0.003 of
 * each other on the quality views, 4 the best). */
#define GI_FILTER_PLANE_CAP 4.0f

#define GI_INDIRECT_MAX_CYCLE 64u
#define GI_INDIRECT_MAX_SET (1u << 20) /* VPLs in a set (with cycling: C x vpls) */

#define GI_INDIRECT_MAX_SCALE 4u
/* The automatic indirect scale: the indirect stages at half resolution from
 * 1024 x 768 up (the real-time size of softgi bench frame), where the
 * geometry-aware upsampling adds 2-5% to the indirect light's error against
 * a low-noise ground truth and halves the frame's indirect stages
 * (docs/perf.md); full resolution below, where it would add more. */
#define GI_INDIRECT_SCALE_AUTO 0u
#define GI_INDIRECT_AUTO_PIXELS (1024u * 768u)
/* The scale `scale` (0: automatic) resolves to for a frame of w x h. */
static inline uint32_t gi_indirect_scale_for(uint32_t scale, uint32_t w, uint32_t h)
{
    if (scale != GI_INDIRECT_SCALE_AUTO) return scale;
    return (uint64_t)w * h >= GI_INDIRECT_AUTO_PIXELS ? 2u : 1u;
}
#define GI_INDIRECT_MAX_TEMPORAL 256u

typedef struct gi_indirect {
    gi_indirect_options opt;
    pf_arena mem;             /* every array below: allocated by gi_indirect_init, released by gi_indirect_free */
    void *method_state;
    gi_vpl_set vpls;          /* the set this frame shades with */
    uint32_t frame;           /* frame number the next update gets */
    /* pipelining: the set being made for the next frame, and its job */
    gi_vpl_set vpls_next;
    int have_set;             /* an update has run (frame 0 done) */
    int pending;              /* an update job was added this frame */
    int next_ready;           /* vpls_next holds the finished set for the next frame */
    pf_camera pipe_camera;    /* the job's copies of this frame's inputs */
    gi_vpl_inputs pipe_in;
    double pipe_ms;           /* the job's own time (written by the job, read after wait_all) */
    float b;                  /* bounded geometry term (1/m^2), INFINITY when off */
    float alpha;              /* filter threshold in scene units */
    /* paraboloid maps: one slot per VPL index */
    rs_para_context *para;
    gi_ism *ism;              /* --visibility ism (then para is NULL) */
    float bias_scale;         /* map bias x this: 1 for exact maps, the ISM bias scale for ISMs */
    int plane;                /* exact maps with the receiver-plane test (not ISMs, not paraboloid-slope) */
    uint16_t *atlas;          /* exact maps or ISMs, rs_paraboloid layout, R = opt.para_res */
    uint32_t atlas_slots;
    /* static maps (exact maps of a scene whose geometry moves: the maps of
     * what cannot move, slot for slot; rs_para_render_split): malloc'd when
     * the first dynamic range is declared (gi_frame_declare_dynamic), NULL
     * before or when that failed (the maps are then drawn without) */
    uint16_t *static_atlas;
    int static_stale;         /* a range became dynamic: the kept slots' static maps are drawn again */
    rs_para_frame *frames;
    float range;
    uint32_t maps_rendered;   /* this frame */
    /* VPL cycling (opt.cycle): C slices (1: off; opt.vpls is then the whole
     * set, C x the per-frame budget), this frame's slice, and per slot
     * whether its map holds its VPL as it is (cleared when the VPL is new
     * or moved, set when the map is drawn) */
    uint32_t cycle, slice;
    uint8_t *map_ok;
    /* the rotation (gi__cycle_schedule): slices in it (C unless warming up),
     * the one the next frame shades, how often each was shaded, this
     * frame's slice's count (the group rotation), the frame it was chosen
     * for (temporal_frames + 1; 0: none yet), this frame's maps drawn ahead */
    uint32_t cycle_live, cycle_next, cycle_base, cycle_key, maps_ahead;
    int ahead_hold;           /* set by the caller: this frame draws no maps ahead (the viewer, while the view moves) */
    uint32_t cycle_shaded[GI_INDIRECT_MAX_CYCLE];
    /* kept between frames: each slot's tile and the id it had when assigned
     * (a survivor keeps its tile) */
    uint32_t *tile_of, *assigned_id;
    uint32_t assigned_count;  /* slots assigned last time */
    uint32_t assign_kept;     /* survivors that kept their tile this frame */
    /* resolution of the indirect stages (split .. filter): w x h = the frame's
     * size / scale (rounded up), reading the frame's G-buffer, or with
     * scale > 1 `low`, the frame's pixels (scale X, scale Y) */
    uint32_t scale, w, h;
    rs_gbuffer low;
    float *filtered_low;      /* scale > 1: the filter's output, w x h, before gi_stage_upsample */
    /* temporal accumulation (opt.temporal > 0): the group of VPLs tile t
     * shades with this frame is (t + shift) mod T; the history is last
     * frame's output with its G-buffer and camera, double-buffered */
    uint32_t shift, temporal_frames;
    float *hist[2];           /* RGB irradiance, the frame's size */
    uint16_t *hist_n[2];      /* frames in each pixel's history */
    float *hist_p[2][3], *hist_nrm[2][3];
    uint32_t *hist_prim[2];
    pf_camera hist_camera;
    int hist_cur;             /* which of [2] holds last frame's */
    float *comp;              /* opt.compensate: the residual irradiance, w x h RGB */
    float *atrous_scratch;    /* GI_FILTER_ATROUS: gi_atrous_scratch_floats(w, h) */
    /* interleaving */
    uint32_t n, m;
    uint32_t *tile_x0;        /* per tile: offset of the tile in split layout */
    uint32_t *tile_w, *tile_h;
    float *split_px, *split_py, *split_pz, *split_nx, *split_ny, *split_nz;
    uint32_t *split_valid;
    uint32_t *assign;         /* VPL indices grouped by tile */
    uint32_t *assign_start;   /* n m + 1 */
    float *split_e;           /* RGB irradiance in split layout */
    float *combined;          /* RGB irradiance, image layout, w x h */
    float *filtered;          /* RGB irradiance after the filter (and the upsampling), the frame's size */
} gi_indirect;

struct gi_frame;

pf_result gi_indirect_init(struct gi_frame *f, const gi_indirect_options *opt, pf_error *err);
void gi_indirect_free(gi_indirect *ind);

void gi_stage_vpl_update(struct gi_frame *f);
/* Pipelining (no-ops unless opt.pipeline): begin, called at the start of
 * the frame (gbuffer_ready 0) and again after the G-buffer (1), first makes
 * the set finished during the last frame this frame's set, then adds the
 * update job for this frame's inputs once it may start (before the G-buffer
 * only for G-buffer-free methods); end, after pf_jobs_wait_all, records the
 * job's time as the "VPL update" stage. */
void gi_stage_vpl_update_begin(struct gi_frame *f, int gbuffer_ready);
void gi_stage_vpl_update_end(struct gi_frame *f);
void gi_stage_vpl_shadow_maps(struct gi_frame *f);
void gi_stage_split(struct gi_frame *f);
void gi_stage_assign(struct gi_frame *f);
void gi_stage_accumulate(struct gi_frame *f);
void gi_stage_combine(struct gi_frame *f);
void gi_stage_filter(struct gi_frame *f);
/* opt.compensate: adds the screen-space estimate of the clamped-away
 * irradiance to `combined` (between combine and filter). */
void gi_stage_compensate(struct gi_frame *f);
/* scale > 1: filtered_low to the frame's size (a no-op at scale 1). */
void gi_stage_upsample(struct gi_frame *f);
/* opt.temporal > 0: filtered blended with last frame's reprojected output. */
void gi_stage_temporal(struct gi_frame *f);

/* The group of VPLs (an index into assign_start) tile t of T shades with
 * this frame: t itself, or rotated by `shift` (ind->shift: the frame with
 * temporal accumulation, the anti-aliasing sample); with VPL cycling, of
 * this frame's slice, whose groups are slice T .. slice T + T - 1. */
static inline uint32_t gi_tile_group(uint32_t t, uint32_t shift, uint32_t T, uint32_t slice)
{
    return slice * T + (t + shift) % T;
}
static inline uint32_t gi_indirect_tile_group(const gi_indirect *ind, uint32_t t)
{
    return gi_tile_group(t, ind->shift, ind->n * ind->m, ind->slice);
}
/* The weight of a tile pixel's sum: the tiles T times the slices C (each
 * pixel sees 1 / (T C) of the set). */
static inline float gi_indirect_tile_weight(const gi_indirect *ind)
{
    return (float)(ind->n * ind->m) * (float)(ind->cycle ? ind->cycle : 1u);
}

/* Irradiance at (p, n) from one VPL with the bounded geometry term, no
 * visibility (step 7's scalar kernel): I G_b, G_b = min(cos_r cos_v / r^2,
 * b); on a nonzero result *w_out and *r_out get the unit direction to the
 * VPL and its distance, *g_out (may be NULL) G_b, *clamped (may be NULL)
 * whether the bound applied. */
pf_vec3 gi_vpl_irradiance(const gi_vpl *v, pf_vec3 p, pf_vec3 n, float b, pf_vec3 *w_out, float *r_out, float *g_out,
                          int *clamped);

/* The bounded geometry term's bound b = clamp / diagonal^2 (1/m^2) of the
 * scene's bounding box (INFINITY for clamp <= 0): the frame's and the
 * clamped reference's (gi_reference.h). */
float gi_clamp_bound(const pf_scene *scene, float clamp);

/* Frame pixel (x, y) -> the index of the indirect image's pixel (x / scale,
 * y / scale) in the w x h buffers (combined, filtered_low). */
static inline size_t gi_indirect_pixel(const gi_indirect *ind, uint32_t x, uint32_t y)
{
    return (size_t)(y / ind->scale) * ind->w + x / ind->scale;
}

/* Pixel (x, y) of the indirect image (w x h) -> index in the split layout. */
uint32_t gi_split_index(const gi_indirect *ind, uint32_t width, uint32_t x, uint32_t y);

#endif
