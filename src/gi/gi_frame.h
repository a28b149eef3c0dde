/* gi_frame: one frame of softgi and the stages that make it.
 *
 * A frame reads like the outline of Laine 2007 Sec. 3: one function calls the
 * stages in order, each a named function, each timed, each writing a named
 * buffer of the frame (gi_buffer_id) so the CLI can dump it and the viewer
 * can show it. Two frames exist today:
 *
 *   gi_frame_render_raster (the default):
 *   1. G-buffer            gi_stage_gbuffer_raster     (rs_render: visibility buffer)
 *                          gi_stage_gbuffer_resolve    (rs_gbuffer_resolve: attributes)
 *   2. direct light        gi_stage_shadow_maps        (rs_shadow_render_needed: one map or cube per
 *                                                       light, the tiles the receivers read)
 *                          gi_stage_area_shadow_maps   (paraboloid maps of K emitter points, once)
 *                          gi_stage_direct_shadowmap   (16-tap PCF, Laine 2007 Sec. 6; area lights
 *                                                       as K fixed cosine emitter points)
 *   3. VPL set             gi_stage_vpl_update         (the VPL method: Instant Radiosity by default)
 *   4. VPL shadow maps     gi_stage_vpl_shadow_maps    (paraboloid maps of new/moved VPLs)
 *   5. split               gi_stage_split              (n x m interleaved tiles)
 *   6. assign              gi_stage_assign             (VPLs to tiles: survivors keep theirs)
 *   7. accumulate          gi_stage_accumulate         (bounded geometry term, map lookups)
 *   8. combine             gi_stage_combine
 *                          gi_stage_compensate         (--compensate only: screen-space estimate of the
 *                                                       clamped-away light, survey Sec. 5.2)
 *   9. filter              gi_stage_filter             (Laine 2007 Fig. 5 box, bilateral or gaussian)
 *                          gi_stage_temporal           (--temporal N only: reprojected history, rotated
 *                                                       VPL groups; at the indirect stages' resolution)
 *                          gi_stage_upsample           (--indirect-scale > 1 only: steps 5-9 ran at
 *                                                       reduced resolution; geometry-aware upsampling)
 *  10. compose             gi_stage_compose            (emission + direct + albedo / pi x indirect)
 *                          gi_stage_aa_resolve         (--aa N > 1 only: the samples' average)
 *                          gi_stage_taa                (--taa N only: temporal anti-aliasing)
 *
 *   gi_frame_render_raytraced (--raytrace, the reference):
 *   1. G-buffer            gi_stage_gbuffer_raytrace   (Embree primary rays)
 *   2. direct light        gi_stage_direct_raytrace    (shadow rays; area lights: stratified samples)
 *   3. compose             gi_stage_compose            (then the two anti-aliasing stages, as above)
 *
 * (steps 3-9 run when gi_frame_enable_indirect was called; the ray-traced
 * frame runs them too, with its G-buffer).
 *
 * Anti-aliasing (gi_aa.h): with --aa N the stages that depend on the camera
 * (the G-buffer, the direct light, split, accumulate .. compose: the table's
 * `per_sample` rows) run once for each of N jittered samples and
 * gi_stage_aa_resolve averages their `final`; the others (shadow maps, area
 * maps, VPL update, VPL maps, assign) run once, with the first sample. With
 * --aa 1 (the default) the frame is the outline above, bit for bit.
 *
 * With gi_indirect_options.pipeline (--pipeline on), step 3 is the update
 * for the next frame, run as a job that overlaps the frame (from before step
 * 1 for methods that never read the G-buffer, else from after step 1) and
 * steps 4-9 use the set made during the previous frame: Laine 2007 Sec. 3
 * and 6, one frame of delay in the VPLs (gi_indirect.h, "Pipelining").
 *
 * Memory: everything a frame writes is allocated once in gi_frame_create
 * (frame lifetime, reused every frame); stages do not allocate. */
#ifndef GI_FRAME_H
#define GI_FRAME_H

#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_scene.h"
#include "pf_timer.h"
#include "rs_gbuffer.h"
#include "rs_raster.h"
#include "rs_shadow.h"
#include "gi_aa.h"
#include "gi_area.h"
#include "gi_indirect.h"
#include "gi_light.h"
#include "gi_motion.h"
#include "rs_paraboloid.h"

/* The frame's named buffers: every intermediate result a stage writes, so
 * the stage table can say what each stage reads and writes (masks of
 * GI_BUFFER_BIT), the viewer can show it and the dump can write it. */
typedef enum gi_buffer_id {
    GI_BUF_VISIBILITY = 0, /* depth and triangle id per pixel (gbuf.depth, gbuf.prim) */
    GI_BUF_GBUFFER,        /* position, normal and albedo planes (gbuf) */
    GI_BUF_SHADOW_MAPS,    /* one map or cube per light (shadows) */
    GI_BUF_AREA_MAPS,      /* the K emitter points' paraboloid maps (area_maps) */
    GI_BUF_DIRECT,         /* direct radiance, RGB (direct) */
    GI_BUF_VPLS,           /* the VPL set (ind.vpls) */
    GI_BUF_VPL_MAPS,       /* the VPLs' paraboloid maps or ISMs (ind.atlas) */
    GI_BUF_SPLIT,          /* the split G-buffer, tile layout (ind.split_*) */
    GI_BUF_ASSIGNMENT,     /* VPLs grouped by tile (ind.assign, ind.tile_of) */
    GI_BUF_ACCUMULATED,    /* per-tile irradiance, tile layout (ind.split_e) */
    GI_BUF_COMBINED,       /* irradiance, image layout (ind.combined) */
    GI_BUF_FILTERED,       /* irradiance after the filter (ind.filtered) */
    GI_BUF_FINAL,          /* composed linear radiance, RGB (final) */
    GI_BUF_COUNT
} gi_buffer_id;
#define GI_BUFFER_BIT(id) (1u << (id))
const char *gi_buffer_name(gi_buffer_id id);

/* The stage table: every stage a frame can run, in the order the frames run
 * them (the outline above). The frame runs and times each stage through it
 * (the timer rows are the table's names), and the dump, the viewer's
 * stepper and HUD, and the benchmarks read names, steps, papers and
 * captions from it, so each exists once. `step` is softgi's own numbering
 * (the outline above); `paper` says where a paper describes the stage
 * (Laine 2007's outline numbers its steps differently: VPL management is
 * its steps 1-4, the G-buffer its step 5). */
typedef enum gi_stage_id {
    GI_STAGE_GBUFFER_RASTER = 0,
    GI_STAGE_GBUFFER_RAYTRACE,
    GI_STAGE_GBUFFER_RESOLVE,
    GI_STAGE_SHADOW_MAPS,
    GI_STAGE_AREA_MAPS,
    GI_STAGE_DIRECT_SHADOWMAP,
    GI_STAGE_DIRECT_RAYTRACE,
    GI_STAGE_VPL_UPDATE,
    GI_STAGE_VPL_MAPS,
    GI_STAGE_SPLIT,
    GI_STAGE_ASSIGN,
    GI_STAGE_ACCUMULATE,
    GI_STAGE_COMBINE,
    GI_STAGE_COMPENSATE,
    GI_STAGE_FILTER,
    GI_STAGE_UPSAMPLE,
    GI_STAGE_TEMPORAL,
    GI_STAGE_COMPOSE,
    GI_STAGE_AA_RESOLVE,
    GI_STAGE_TAA,
    GI_STAGE_COUNT
} gi_stage_id;

struct gi_frame;
typedef struct gi_stage_info {
    const char *name;       /* the timer row ("accumulate") */
    uint32_t step;          /* 1..10: the frame outline's step */
    const char *paper;      /* where the papers describe it */
    const char *caption;    /* what it does, one line */
    uint32_t reads, writes; /* GI_BUFFER_BIT masks */
    void (*run)(struct gi_frame *f);
    int per_sample;         /* runs once per anti-aliasing sample (--aa N, gi_aa.h); else once a frame */
} gi_stage_info;

/* The table entry of a stage (NULL for an id out of range). */
const gi_stage_info *gi_stage_get(gi_stage_id id);

/* Area lights (gi_area.h) in the direct light of a frame.
 *
 * Ray-traced frame: per pixel, S = strata^2 emitter samples, stratified:
 * sample k's triangle-choosing u0 is jittered in stratum k of S, its point
 * (u1, u2) on the triangle is Halton point k (bases 2, 3) under a per-pixel
 * rotation (Cranley-Patterson), so the consecutive k a triangle gets are
 * themselves well spread over it. Deterministic: every random number is a
 * hash of (pixel, sample, dimension). E = 1/S sum Le cos cos' / (r^2 pdf) V (gi_area_sample_irradiance).
 *
 * Rasterized frame: K fixed points on the emitters, chosen once (u0 =
 * (k + 1/2) / K through the power CDF, (u1, u2) = Halton(k + 1) in bases 2
 * and 3), each with weight A_k = 1 / (K pdf_area(p_k)): a point with cosine
 * emission lights a receiver exactly like a VPL of intensity Le A_k,
 *   E = Le A_k cos_r cos_e / r^2 V,
 * with V from a 128 x 128 paraboloid map at the point (rs_paraboloid.h,
 * exact per texel). Emitters do not move, so the maps are rendered at the
 * first frame and kept. This is a fixed K-point quadrature of the emitter
 * integral (deterministic, no noise): accurate where the emitter is small
 * seen from the receiver (tests/test_area.c: 1.6% mean error of the peak
 * under a 1 x 1 emitter at 1 m with K = 32, 0.3% with K = 256), penumbrae
 * made of K hard shadows, and a receiver much closer to an emitter than the
 * points' spacing sees individual points (1/r^2 of each; not clamped). */
#define GI_AREA_DEFAULT_STRATA 4u  /* 16 samples per pixel */
#define GI_AREA_MAX_STRATA 16u
#define GI_AREA_DEFAULT_POINTS 32u /* K */
#define GI_AREA_MAX_POINTS 1024u

typedef struct gi_area_maps {
    uint32_t count;        /* K (0: the scene has no emitters or no raster) */
    rs_para_context *para; /* the scene for the maps */
    uint16_t *atlas;       /* K maps of RS_PARA_DEFAULT_RES^2 codes */
    rs_para_frame *frames; /* point and emitting normal per map */
    pf_vec3 *weight;       /* Le A_k, RGB (W/sr at normal exitance) */
    float range;
    int rendered;          /* maps drawn (at the first frame) */
    int plane;             /* the receiver-plane test (!gi_frame.area_slope, set by the stage) */
} gi_area_maps;

/* Progress of a long stage (the VPLs' maps of a first frame with many
 * VPLs): `done` of `total` units of the stage `what`, called on the thread
 * that renders the frame, between pieces of work; it must not touch the
 * frame. NULL: nobody listens. */
typedef void (*gi_frame_progress_fn)(void *user, const char *what, uint32_t done, uint32_t total);

typedef struct gi_frame {
    /* inputs (not owned) */
    gi_frame_progress_fn progress; /* may be NULL; set after gi_frame_create */
    void *progress_user;
    const pf_scene *scene;
    const pf_rt *rt;
    pf_jobs *jobs;
    rs_context *raster; /* NULL: only the ray-traced frame is available */
    pf_camera camera;
    uint32_t width, height;
    gi_area_lights area;   /* the scene's emissive triangles (built at init) */
    uint32_t area_strata;  /* ray-traced direct light: area_strata^2 samples per pixel */
    gi_area_maps area_maps; /* rasterized direct light: K emitter points */
    /* buffers (owned, frame lifetime) */
    pf_arena mem;          /* direct and final (the indirect part has its own, ind.mem) */
    /* per-frame scratch (the assignment's keys, loads and cursors, the VPL
     * maps' lists): taken with gi_frame_scratch, reset at the start of
     * every gi_frame_render_*, released by gi_frame_free; after the first
     * frame a steady loop takes it without malloc (pf_arena_reset keeps
     * the blocks) */
    pf_arena scratch;
    rs_gbuffer gbuf;
    rs_shadow_set shadows; /* one map (cube for point lights) per scene light; raster frames only */
    gi_light_copy shadow_lights; /* the lights the maps were rendered for (static lights: maps reused) */
    uint32_t shadow_size;
    int shadows_rendered;     /* 0: render at the next gi_stage_shadow_maps */
    gi_indirect ind;       /* many-light state and buffers (when enabled) */
    int indirect;          /* run steps 3-9 */
    int show_direct;       /* compose adds emission + direct (0 for --indirect-only) */
    /* PF_OK, or the first failure of the last frame (a rasterizer pass that
     * ran out of memory drew fewer triangles: rs_context_status; a stage's
     * scratch not had: gi_frame_scratch); the commands check it after every
     * frame and refuse its image */
    pf_result status;
    pf_error error;
    float *direct; /* RGB, width*height*3 */
    float *final;  /* RGB, width*height*3 */
    pf_stage_times times;
    gi_aa aa;      /* anti-aliasing: samples per pixel, the sample being rendered, TAA (gi_aa.h) */
    /* moved geometry (gi_motion.h, gi_frame_geometry_moved): what the
     * stages have yet to catch up with */
    uint32_t area_points;        /* K as set (area_maps.count is 0 without emitters) */
    int area_slope;              /* gi_frame_desc.area_slope */
    gi_motion motion;            /* for the VPL method: cleared after each update */
    gi_moved_box moved_shadows;  /* for gi_stage_shadow_maps */
    gi_moved_box moved_area;     /* for gi_stage_area_shadow_maps */
    gi_moved_box moved_maps;     /* for gi_stage_vpl_shadow_maps */
    pf_vec3 shadow_bounds_lo, shadow_bounds_hi; /* the scene's bounds the directional maps were set up for */
    gi_motion_stats motion_stats; /* what the last frame redid for moved geometry */
} gi_frame;

/* What a frame is set up with (sokol style: zero means the default). */
typedef struct gi_frame_desc {
    const pf_scene *scene;       /* required; validated */
    const pf_rt *rt;             /* Embree's scene of `scene`; NULL: no ray-traced stages (raster only) */
    pf_jobs *jobs;               /* required */
    rs_context *raster;          /* NULL: only the ray-traced frame is available */
    const pf_camera *camera;     /* NULL: the scene's first camera (the scene must have one) */
    uint32_t width, height;      /* required */
    uint32_t shadow_size;        /* texels per side of each direct-light shadow map (0: 1024) */
    uint32_t area_strata;        /* ray-traced area lights: strata per side (0: GI_AREA_DEFAULT_STRATA) */
    uint32_t area_points;        /* rasterized area lights: K points (0: GI_AREA_DEFAULT_POINTS) */
    int area_slope;              /* rasterized area lights: the slope-scaled bias test instead of the
                                    receiver-plane test (--visibility paraboloid-slope; rs_paraboloid.h) */
    const gi_indirect_options *indirect; /* NULL: no indirect light (steps 3-9 off) */
    int indirect_only;           /* with indirect: no emission and direct light in the image */
    uint32_t aa_samples;         /* jittered samples per pixel, 1..GI_AA_MAX_SAMPLES (0: 1, the pixel centres) */
    uint32_t taa_frames;         /* temporal anti-aliasing over up to N frames, 2..GI_AA_MAX_TAA (0: off) */
} gi_frame_desc;

/* Sets up a frame from d: its buffers, the area-light sampling and, with
 * d->indirect, the many-light stages. On failure everything allocated is
 * freed and f is zeroed. */
pf_result gi_frame_create(gi_frame *f, const gi_frame_desc *d, pf_error *err);
void gi_frame_free(gi_frame *f);

/* Bytes a frame will allocate, estimated before anything is (pf_budget.h):
 * the per-pixel planes (G-buffer, split, accumulation, filter, direct,
 * final; GI_FRAME_BYTES_PER_PIXEL each pixel), every light's shadow map
 * (6 faces for point lights and wide spots), the VPLs' paraboloid maps
 * (vpls 0: no indirect light) and the area lights' K emitter maps. */
#define GI_FRAME_BYTES_PER_PIXEL 256u
uint64_t gi_frame_memory_estimate(const pf_scene *scene, uint32_t width, uint32_t height, uint32_t shadow_size,
                                  uint32_t vpls, uint32_t para_res, uint32_t area_points);

/* Turns on the many-light stages (steps 3-9); `indirect_only` drops emission
 * and direct light from the composed image. */
pf_result gi_frame_enable_indirect(gi_frame *f, const gi_indirect_options *opt, int indirect_only, pf_error *err);

/* Sets the area-light sampling of the direct light: strata per side
 * (1..GI_AREA_MAX_STRATA) for the ray-traced frame, K points
 * (1..GI_AREA_MAX_POINTS) for the rasterized one (their maps are redrawn at
 * the next frame). gi_frame_create sets them (the defaults or the description's). */
pf_result gi_frame_set_area_sampling(gi_frame *f, uint32_t strata, uint32_t points, pf_error *err);

/* The primary ray through the centre of pixel (x, y): dir is scaled so that
 * t along it equals view depth. */
pf_ray gi_camera_ray(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y);
/* The same through the image point (x + 1/2 + jx, y + 1/2 + jy): an
 * anti-aliasing sample (gi_aa.h); gi_camera_ray's bits for (0, 0). */
pf_ray gi_camera_ray_at(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y, float jx,
                        float jy);

/* Tells the frame that the scene's geometry moved in place (pf_anim_pose's
 * report: `count` entries, those with `moved` set). The caller has already
 * brought Embree (pf_rt_update) and the rasterizer (rs_context_update) up to
 * date; the frame updates its own paraboloid contexts and ISM points now
 * and marks what its next stages must draw again (gi_motion.h says what and
 * how). Fails on a range outside the scene (nothing changed then) or out of
 * memory (the frame's copies are then part-updated: make the frame again). */
pf_result gi_frame_geometry_moved(gi_frame *f, const pf_anim_moved *moved, uint32_t count, pf_error *err);

/* count * size bytes of this frame's scratch (zeroed, 64-byte aligned; at
 * least one element, so count 0 is not NULL), valid until the next frame
 * starts; NULL when memory is short, the frame's
 * status then PF_ERR_OUT_OF_MEMORY naming `what` (the stage skips its work
 * and the frame's image is refused). Frame thread only. A stage called on
 * its own (tests) takes scratch until the next frame resets it. */
void *gi_frame_scratch(gi_frame *f, size_t count, size_t size, const char *what);

/* Declares the ranges that may move from now on (entries flagged `moved`;
 * gi_frame_geometry_moved declares what it is told moved): the exact VPL
 * maps then keep static maps, the maps of the geometry that cannot move,
 * and a map the moved geometry changes is drawn again from its static map
 * and the dynamic triangles instead of from everything behind them (the
 * same bytes; rs_para_render_box_split). A range new to the set has the
 * kept maps drawn whole, with their static maps, at the next VPL maps stage
 * (once), so a caller that knows what is animated (the scene's dynamic
 * primitives) declares it before the first frame. Fails on a range outside
 * the scene. No-op without exact VPL maps. */
pf_result gi_frame_declare_dynamic(gi_frame *f, const pf_anim_moved *ranges, uint32_t count, pf_error *err);

/* Stages. */
void gi_stage_gbuffer_raytrace(gi_frame *f);
void gi_stage_gbuffer_raster(gi_frame *f);  /* visibility: triangle id + depth per pixel */
void gi_stage_gbuffer_resolve(gi_frame *f); /* attributes from the visibility buffer */
void gi_stage_direct_raytrace(gi_frame *f);
/* Renders the lights' shadow maps, or reuses last frame's when no light
 * changed (a changed light re-creates the maps). */
void gi_stage_shadow_maps(gi_frame *f);
void gi_stage_area_shadow_maps(gi_frame *f); /* the K emitter points' maps, first frame only */
void gi_stage_direct_shadowmap(gi_frame *f);
void gi_stage_compose(gi_frame *f);

/* The whole ray-traced frame: G-buffer, direct light, compose (timed). */
void gi_frame_render_raytraced(gi_frame *f);
/* The rasterized frame (needs f->raster). */
void gi_frame_render_raster(gi_frame *f);

#endif
