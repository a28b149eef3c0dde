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
 *   2. direct light        gi_stage_shadow_maps        (rs_shadow_render: one map or cube per light)
 *                          gi_stage_direct_shadowmap   (16-tap PCF, Laine 2007 Sec. 6)
 *   3. compose             gi_stage_compose            (emission + direct)
 *
 *   gi_frame_render_raytraced (--raytrace, the reference):
 *   1. G-buffer            gi_stage_gbuffer_raytrace   (Embree primary rays)
 *   2. direct light        gi_stage_direct_raytrace
 *   3. compose             gi_stage_compose
 *
 * Later issues add the VPL set, the interleaved split / accumulate /
 * combine and the filter between 2 and 3.
 *
 * Memory: everything a frame writes is allocated once in gi_frame_init
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

typedef enum gi_buffer_id {
    GI_BUF_DEPTH = 0, /* G-buffer planes */
    GI_BUF_POSITION,
    GI_BUF_NORMAL,
    GI_BUF_ALBEDO,
    GI_BUF_PRIM,
    GI_BUF_DIRECT, /* direct radiance (RGB) */
    GI_BUF_FINAL,  /* composed linear radiance (RGB) */
    GI_BUF_COUNT
} gi_buffer_id;

/* Name and one-line caption of a buffer, for dumps and the stepper. */
const char *gi_buffer_name(gi_buffer_id id);
const char *gi_buffer_caption(gi_buffer_id id);

typedef struct gi_frame {
    /* inputs (not owned) */
    const pf_scene *scene;
    const pf_rt *rt;
    pf_jobs *jobs;
    rs_context *raster; /* NULL: only the ray-traced frame is available */
    pf_camera camera;
    uint32_t width, height;
    /* buffers (owned, frame lifetime) */
    rs_gbuffer gbuf;
    rs_shadow_set shadows; /* one map (cube for point lights) per scene light; raster frames only */
    float *direct; /* RGB, width*height*3 */
    float *final;  /* RGB, width*height*3 */
    pf_stage_times times;
} gi_frame;

/* shadow_size: texels per side of each direct-light shadow map (0: 1024). */
pf_result gi_frame_init(gi_frame *f, const pf_scene *scene, const pf_rt *rt, rs_context *raster, pf_jobs *jobs,
                        const pf_camera *camera, uint32_t width, uint32_t height, uint32_t shadow_size, pf_error *err);
void gi_frame_free(gi_frame *f);

/* The primary ray through the centre of pixel (x, y): dir is scaled so that
 * t along it equals view depth. */
pf_ray gi_camera_ray(const pf_camera *cam, uint32_t width, uint32_t height, uint32_t x, uint32_t y);

/* Stages. */
void gi_stage_gbuffer_raytrace(gi_frame *f);
void gi_stage_gbuffer_raster(gi_frame *f);  /* visibility: triangle id + depth per pixel */
void gi_stage_gbuffer_resolve(gi_frame *f); /* attributes from the visibility buffer */
void gi_stage_direct_raytrace(gi_frame *f);
void gi_stage_shadow_maps(gi_frame *f);
void gi_stage_direct_shadowmap(gi_frame *f);
void gi_stage_compose(gi_frame *f);

/* The whole ray-traced frame: G-buffer, direct light, compose (timed). */
void gi_frame_render_raytraced(gi_frame *f);
/* The rasterized frame (needs f->raster). */
void gi_frame_render_raster(gi_frame *f);

#endif
