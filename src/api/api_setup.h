/* api_setup: what a frame needs before it renders, in one place for the
 * library (softgi_api.c) and the program's commands (src/app/app_scene.c:
 * render through the library, and view, sequence, evaluate, reference and
 * the benchmarks, which build their frames on the modules):
 *
 *   api_scene_read        the .gltf / .glb file, or the built-in Cornell box,
 *                         under the memory budget, with its animations
 *   api_scene_pose        the scene posed at a time (--time, --animation)
 *   api_geometry_moved    Embree, the rasterizer and a frame updated for it
 *   api_declare_dynamic   the scene's animated primitives told to a frame
 *   api_default_camera    pf_defaults_camera as the program prints it (its
 *                         --camera text) and parses it back
 *   api_default_light     pf_defaults_light likewise (its --light text)
 *   api_budget_check      the scene plus the frame (or the path tracer's
 *                         image) against the budget, before allocating
 *   api_refine_fit        the progressive refinement's slices that fit it
 *   api_indirect_options  the many-light options of a softgi_desc
 *   api_frame_create      gi_frame_create with every option of a softgi_desc
 *
 * The frame's options are the public softgi_desc (include/softgi/softgi.h):
 * the program maps its pf_options to one (app_desc, app_scene.c), so each
 * option means the same to the library and to every command.
 *
 * The automatic camera and light go through their text because the
 * program prints them as a --camera / --light value to copy: the copied
 * line must give the same image bit for bit, so the image is rendered with
 * the rounded numbers (5 significant digits, or 9 when 5 merge eye and
 * target or move the light by more than 1% of the median distance; the
 * fovy with %g, the intensity with %.3g; strtof, as pf_cli parses them).
 *
 * Nothing here prints, except api_budget_check's warning when asked
 * (the program's; pf_budget_warn). */
#ifndef API_SETUP_H
#define API_SETUP_H

#include <stddef.h>
#include <stdint.h>

#include "softgi/softgi.h"
#include "pf_defaults.h"
#include "pf_result.h"
#include "pf_scene.h"

struct gi_frame;
struct gi_indirect_options;
struct pf_anim;
struct pf_anim_moved;
struct pf_jobs;
struct pf_rt;
struct rs_context;

/* 640 x 480, the size of a desc with width = height = 0. */
#define API_DEFAULT_WIDTH 640u
#define API_DEFAULT_HEIGHT 480u

/* Whether any triangle's material emits (an area light, gi_area.h). */
int api_scene_has_emitters(const pf_scene *scene);

/* Reads `path` (NULL: the built-in Cornell box, scenes/cornell-box) into
 * `scene` with the memory budget max_memory (0: half the machine's); with
 * `anim` not NULL, what posing it needs into *anim (pf_gltf_options.anim:
 * empty for a file without animations). */
pf_result api_scene_read(pf_scene *scene, struct pf_anim *anim, const char *path, uint64_t max_memory,
                         pf_error *err);

/* The animation an --animation value names ("NAME", or an index when it is
 * all digits: "0", "2"; NULL: every animation of the file together, in file
 * order) into *clip (pf_anim.h). PF_ERR_ARGUMENT naming the scene and
 * listing its animations otherwise ("NAME: no animation named 'walk' (the
 * file has 2: 0 'run', 1 'jump')", "NAME: the scene has no animations"). */
pf_result api_anim_clip(const struct pf_anim *anim, const char *scene_name, const char *animation, int32_t *clip,
                        pf_error *err);

/* --time / softgi_set_time: `scene` posed at `seconds` of `animation`
 * (api_anim_clip) with pf_anim_pose; *moved (may be NULL) gets how many
 * instanced primitives moved, report (NULL, or anim->prim_count entries)
 * pose's report of what moved (for pf_rt_update). Errors name the scene.
 * The automatic camera and light are not touched: they are chosen on the
 * static pose, so an animation is framed alike at every time. */
pf_result api_scene_pose(pf_scene *scene, struct pf_anim *anim, const char *scene_name, double seconds,
                         const char *animation, uint32_t *moved, struct pf_anim_moved *report, pf_error *err);

/* The renderer brought up to date in place after a pose moved geometry
 * (docs/architecture.md "Moving geometry"): Embree
 * (pf_rt_update, REBUILD: the moved primitives' BVHs built afresh, a fresh
 * build's bytes, so nothing depends on the poses before), the rasterizer
 * (rs_context_update; raster may be NULL) and the frame (gi_frame_geometry_moved:
 * maps redrawn only where the moved bounds reach them, the VPL method told;
 * frame may be NULL). `moved` is pose's report, count entries. A failure
 * leaves them part-updated: the caller makes them again or stops. */
pf_result api_geometry_moved(struct pf_rt *rt, struct rs_context *raster, struct gi_frame *frame,
                             const struct pf_anim_moved *moved, uint32_t count, pf_error *err);

/* Declares the scene's dynamic primitives (anim->prims[k].dynamic) to the
 * frame (gi_frame_declare_dynamic), so its first frame draws the static
 * VPL maps with the maps; a static file declares nothing. */
pf_result api_declare_dynamic(struct gi_frame *frame, const struct pf_anim *anim, pf_error *err);

/* The automatic camera of a validated scene without one: pf_defaults_camera
 * (its reasons into *dc when not NULL), rounded through the --camera value
 * written into spec (ex,ey,ez:tx,ty,tz:fovy). Named "default". */
pf_result api_default_camera(const pf_scene *scene, pf_camera *camera, pf_default_camera *dc, char *spec,
                             size_t spec_size, pf_error *err);

/* The automatic light of a scene that nothing lights, at `camera`, for a
 * width x height image: pf_defaults_light rounded through the --light value
 * written into spec (point:x,y,z:1,1,1:I); *median (may be NULL) gets the
 * median distance it was scaled for. Named "default"; not added. */
pf_result api_default_light(const pf_scene *scene, const pf_camera *camera, uint32_t width, uint32_t height,
                            pf_light *out, float *median, char *spec, size_t spec_size, pf_error *err);

/* The memory budget (d->max_memory, pf_budget.h) against the scene as
 * loaded plus what will be allocated: with `frame`, a frame of d's size
 * (gi_frame_memory_estimate: planes, shadow maps, VPL maps, with `indirect`
 * and not SOFTGI_DIRECT_ONLY the VPLs d asks for); without, the path
 * tracer's image. Refused with one line naming what helps; with `warn`,
 * a run that takes most of the machine's memory prints the program's
 * warning on stderr. */
pf_result api_budget_check(const softgi_desc *d, const pf_scene *scene, int frame, int indirect, int warn,
                           pf_error *err);

/* The progressive refinement of a still view (softgi view's default and
 * render --frames N, docs/view.md): temporal accumulation and temporal
 * anti-aliasing over these many frames, VPL cycling over at most
 * API_REFINE_SLICES slices with API_REFINE_MAPS maps a frame drawn ahead. */
#define API_REFINE_TEMPORAL 32u
#define API_REFINE_TAA 16u
#define API_REFINE_SLICES 32u
#define API_REFINE_MAPS 32u
/* Sets d's temporal options to the refinement's, with the largest of
 * slices, slices / 2, ... (at least 2) whose frame passes the budget
 * (api_budget_check of d with `indirect`), else no cycling; returns the
 * slices chosen (0: none). */
uint32_t api_refine_fit(softgi_desc *d, const pf_scene *scene, int indirect, uint32_t slices);

/* The many-light options of d: the method (NULL: ir), its parameters
 * (pointers into d->params, which must outlive the frame), VPLs, bounces,
 * tiles, clamp, filter, visibility and the ISM settings, pipelining,
 * compensation, temporal accumulation, the indirect scale. Errors use the
 * program's option names ("--ism-res ... need --visibility ism"). */
pf_result api_indirect_options(const softgi_desc *d, struct gi_indirect_options *io, pf_error *err);

/* The frame d describes, on a loaded scene: the budget check (warn as
 * above), then gi_frame_create with the shadow-map size, the area-light
 * sampling, anti-aliasing and, unless SOFTGI_DIRECT_ONLY or `indirect` is
 * 0 (sequence --reference), the many-light stages. On failure nothing is
 * left to free. */
pf_result api_frame_create(struct gi_frame *f, const softgi_desc *d, const pf_scene *scene, const struct pf_rt *rt,
                           struct rs_context *raster, struct pf_jobs *jobs, const pf_camera *camera, int indirect,
                           int warn, pf_error *err);

#endif
