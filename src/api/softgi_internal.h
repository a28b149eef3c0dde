/* softgi_internal: what the softgi program reads of a softgi_context and a
 * library user does not need (src/app/app_render.c includes it; it is not
 * installed). Not in softgi.h because it exposes internal types (the
 * automatic camera's reasons are a pf_default_camera) or program behaviour
 * (a warning on stderr, which the library otherwise never prints).
 *
 * - softgi_internal_notes: why the automatic camera and light are what they
 *   are, and their --camera / --light text, for the program's
 *   "softgi: note:" lines (the values in them, copied onto the command
 *   line, give the same image).
 * - softgi_internal_set_scene_lights: softgi_set_lights with the lights
 *   as pf_cli_parse_light made them (--light), bit for bit: converting
 *   them to softgi_light and back (cone angles in degrees, directions
 *   normalised again) could change their last bits.
 * - softgi_internal_warn: with on = 1, the budget check of the first
 *   frame prints the program's warning when the run would take most of the
 *   machine's memory (pf_budget_warn). */
#ifndef SOFTGI_INTERNAL_H
#define SOFTGI_INTERNAL_H

#include "softgi/softgi.h"
#include "pf_defaults.h"
#include "pf_scene.h"

typedef struct softgi_internal_notes {
    int auto_camera;          /* the camera is the automatic one (as softgi_info) */
    pf_default_camera camera; /* its reasons: interior, rays, axis, open end */
    char camera_spec[256];    /* its --camera value */
    int auto_light;           /* the light is the automatic one, at the current camera */
    float light_median;       /* the median distance its intensity was scaled for */
    char light_spec[256];     /* its --light value */
} softgi_internal_notes;

/* NULL without a loaded scene. Valid until the next call on the context. */
const softgi_internal_notes *softgi_internal_notes_get(const softgi_context *ctx);

softgi_result softgi_internal_set_scene_lights(softgi_context *ctx, const pf_light *lights, uint32_t count,
                                               softgi_error *err);

void softgi_internal_warn(softgi_context *ctx, int on);

/* The progressive refinement of a still view (the viewer's default, and
 * `softgi render --frames N`; docs/view.md): api_refine_fit on the
 * context's options and scene (--temporal 32 --taa 16 and, for slices >= 2,
 * VPL cycling over the most slices the memory budget holds). Only after
 * softgi_load_scene and before the first softgi_render; *cycle gets the
 * slices (0: none). */
softgi_result softgi_internal_refine(softgi_context *ctx, uint32_t slices, uint32_t *cycle, softgi_error *err);

#endif
