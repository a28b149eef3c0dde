/* gi_view: the stages of one frame as pictures, for the stepper of
 * `softgi view` and for `softgi render --dump-stages DIR` (one
 * implementation: both call gi_view_render, so a dumped PNG holds exactly
 * the bytes the viewer shows for that stage, HUD aside).
 *
 * A frame is shown in the order it is computed (Laine 2007 Sec. 3's outline,
 * gi_frame.h): the G-buffer channels (step 1), the direct light's shadow map
 * and the direct light (step 5 with Sec. 6's shadow maps), the VPL set over
 * the image and from above with the camera frustum (Hedman 2017 Fig. 3's
 * overhead view), one VPL's paraboloid shadow map (Sec. 4.6, Brabec 2002),
 * the split tiles, the per-tile accumulation, the combined and the filtered
 * irradiance (Sec. 5) and the final image. Every view is an RGB8 image of
 * the frame's size (maps are fitted into it, centred on black), with a
 * one-line caption (gi_view_caption) saying what the stage does and which
 * paper section it implements.
 *
 * Display transforms: radiance and irradiance views go through the PNG
 * writer's transform (pf_imageio_display: 2^exposure, Reinhard, sRGB), so
 * the final view is byte for byte the PNG `softgi render` writes; data views
 * (depth, positions, normals, ...) are mapped to [0, 1] and quantised as
 * round(255 v) with no tone mapping. */
#ifndef GI_VIEW_H
#define GI_VIEW_H

#include <stdint.h>

#include "gi_frame.h"

typedef enum gi_view_id {
    GI_VIEW_DEPTH = 0,
    GI_VIEW_POSITION,
    GI_VIEW_NORMAL,
    GI_VIEW_ALBEDO,
    GI_VIEW_PRIM,
    GI_VIEW_SHADOW_MAP,   /* the first light's shadow map (cube: six faces) */
    GI_VIEW_DIRECT,
    GI_VIEW_VPLS,         /* VPLs as points over the final image */
    GI_VIEW_VPL_OVERHEAD, /* VPLs, lights and the camera frustum seen from above */
    GI_VIEW_VPL_MAP,      /* the chosen VPL's paraboloid map */
    GI_VIEW_SPLIT,
    GI_VIEW_ACCUMULATED,
    GI_VIEW_COMBINED,
    GI_VIEW_FILTERED,
    GI_VIEW_FINAL,
    GI_VIEW_COUNT
} gi_view_id;

/* What a view depends on beyond the frame. Zero-initialised = defaults. */
typedef struct gi_view_settings {
    float exposure;   /* stops, as --exposure */
    uint32_t vpl;     /* the chosen VPL (index into the frame's set, taken modulo the count) */
} gi_view_settings;

/* File-name part ("depth", "shadow-map", ...) and one-line caption. */
const char *gi_view_name(gi_view_id id);
const char *gi_view_caption(gi_view_id id);
/* 1 if the frame has what the view shows (the VPL views need the indirect
 * stages; the shadow-map view a rasterized frame with direct light). */
int gi_view_available(const gi_frame *f, gi_view_id id);

/* Draws view `id` of the frame's last render into rgb (width * height * 3
 * bytes, top row first). Returns 0 (and draws a black image saying why) when
 * the view is not available. Uses the frame's job system for the overhead
 * view's rays; deterministic for any thread count. */
int gi_view_render(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb);

/* Every available view as `DIR/NN-name.png` (NN = the view id) plus
 * `DIR/captions.txt`, one "NN-name.png: caption" line per image. */
pf_result gi_view_dump(const gi_frame *f, const char *dir, const gi_view_settings *s, pf_error *err);

/* Writes an RGB8 image (top row first) as a PNG, creating parent folders;
 * the same encoder and settings as pf_imageio_write_png. */
pf_result gi_view_write_png(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h, pf_error *err);

/* Built-in 5x7 bitmap font (ASCII 32..126; lower case with one descender
 * row), each glyph cell 6 x 9 pixels times `scale`. Draws `text` with its top-left
 * corner at (x, y), clipped to the image; returns the width drawn. */
#define GI_FONT_CELL_W 6
#define GI_FONT_CELL_H 9
int gi_view_text(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int scale, const char *text, uint8_t r,
                 uint8_t g, uint8_t b);
/* Darkens the rectangle [x, x+rw) x [y, y+rh) (for text backgrounds). */
void gi_view_shade_rect(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rw, int rh);
/* Fills a rectangle with a colour. */
void gi_view_fill_rect(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rw, int rh, uint8_t r, uint8_t g,
                       uint8_t b);

#endif
