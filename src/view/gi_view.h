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
 * irradiance (Sec. 5) and the final image. The learner's views ("the frame
 * taken apart", gi_view_learn.c) adds the VPLs coloured by light bounce and
 * by "moved this frame", the VPL method's own view (gi_vpl_method.view: IR's
 * light paths, IIR's Delaunay/Voronoi domain, SMC's candidates and kNN
 * radii, MIR's candidates by image contribution, InvTM's and TCAS's
 * importance map with the samples and chains, SSVP's clusters), every VPL's
 * paraboloid map as an atlas, the tile assignment and the clamp mask of the
 * bounded geometry term. The VPL overlays are occlusion-aware: a VPL the
 * camera does not see (an Embree ray from the eye) is not drawn. Every view
 * is an RGB8 image of the frame's size (maps are fitted into it, centred on
 * black) with a legend in its bottom-right corner (gi_view_legend: what the
 * colours stand for and the smallest and largest value they span; not on
 * the final image, which is the render's PNG byte for byte), and a
 * one-line caption (gi_view_caption, gi_view_describe_frame) saying what
 * the stage does, which paper section it implements and, for the VPL
 * views, why the frame's method chooses VPLs as it does.
 *
 * For the viewer's inspector, gi_view_frame_pixel / gi_view_view_pixel map
 * a view's pixels to the frame's and back (the identity for views in image
 * layout, the tile mosaic for split and accumulated), and gi_view_zoom
 * fits, zooms and pans a view into a window (nearest neighbour) with the
 * inverse a click needs.
 *
 * Display transforms: radiance and irradiance views go through the PNG
 * writer's transform (pf_imageio_display: 2^exposure, Reinhard, sRGB), so
 * the final view is byte for byte the PNG `softgi render` writes; data views
 * are mapped to [0, 1] from their legend's range (depth: nearest white,
 * farthest black; positions: each axis from its smallest to its largest
 * value; normals: -1 .. 1) and quantised as round(255 v) with no tone
 * mapping.
 *
 * Numbers: a view's gi_view_id is its file number in the dumps
 * (NN-name.png); the learner's views were appended (15..20), and
 * gi_view_order gives the order the frame computes them, which the stepper
 * and the viewer's list follow. */
#ifndef GI_VIEW_H
#define GI_VIEW_H

#include <stddef.h>
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
    /* "the frame taken apart" (appended: the numbers of the
     * views above are kept; gi_view_order gives the stepper's order, by
     * stage) */
    GI_VIEW_VPL_BOUNCE,   /* the VPLs the camera sees, coloured by light bounce */
    GI_VIEW_VPL_MOVED,    /* the VPLs the camera sees: moved this frame (new map) or kept */
    GI_VIEW_METHOD,       /* the VPL method's own state (gi_vpl_method.view) */
    GI_VIEW_VPL_ATLAS,    /* every VPL's paraboloid map, tiled */
    GI_VIEW_TILES,        /* the tile assignment: each tile's VPLs over its mosaic tile */
    GI_VIEW_CLAMP,        /* the clamp mask: how many of a pixel's VPLs the bound clamped */
    GI_VIEW_COUNT
} gi_view_id;

/* The views in the order the frame computes them (the stepper's N / B and
 * the viewer's list): k = 0 .. GI_VIEW_COUNT-1 -> a view; gi_view_rank is
 * the inverse. */
gi_view_id gi_view_order(uint32_t k);
uint32_t gi_view_rank(gi_view_id id);

/* A view's legend: what its colours mean and the range of values they span
 * (`lo`, `hi`: the shown buffer's minimum and maximum, over the pixels or
 * items it shows), drawn into the picture's bottom-right corner as a colour
 * bar or a key when the picture is large enough (GI_VIEW_LEGEND_MIN_W x
 * _H) and recorded here either way. The final view has none: it is the
 * render's PNG, byte for byte. */
#define GI_VIEW_LEGEND_MIN_W 200u
#define GI_VIEW_LEGEND_MIN_H 120u
typedef struct gi_view_legend {
    int present;   /* 0: the view has no legend */
    int has_range; /* 1: lo and hi hold a numeric range (else a key only) */
    float lo, hi;
    char what[64];  /* what the colours stand for ("view depth") */
    char text[160]; /* the legend's text as drawn: "view depth: 0.512 .. 3.27" or the key */
} gi_view_legend;

/* What a view depends on beyond the frame. Zero-initialised = defaults. */
typedef struct gi_view_settings {
    float exposure;   /* stops, as --exposure */
    uint32_t vpl;     /* the chosen VPL (index into the frame's set, taken modulo the count) */
} gi_view_settings;

/* File-name part ("depth", "shadow-map", ...) and what the picture shows. */
const char *gi_view_name(gi_view_id id);
const char *gi_view_caption(gi_view_id id);
/* The stage whose output the view shows (gi_frame.h's stage table). */
gi_stage_id gi_view_stage(gi_view_id id);
/* The view's one-line description from the stage table and the view:
 * "step 7, accumulate (Laine 2007 Sec. 3 step 7, ...): each tile's ...".
 * The dump's captions.txt and the stepper's HUD show it. Returns what
 * snprintf returns. */
int gi_view_describe(gi_view_id id, char *buf, size_t n);
/* 1 if the frame has what the view shows (the VPL views need the indirect
 * stages; the paraboloid-map views exact paraboloid maps; the method view a
 * method with a view; the shadow-map view a rasterized frame with direct
 * light). */
int gi_view_available(const gi_frame *f, gi_view_id id);

/* Draws view `id` of the frame's last render into rgb (width * height * 3
 * bytes, top row first). Returns 0 (and draws a black image saying why) when
 * the view is not available. Uses the frame's job system (the overhead
 * view's rays, the clamp mask) and Embree (the overlays' visibility);
 * deterministic for any thread count. */
int gi_view_render(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb);
/* The same, also giving the legend (may be NULL). */
int gi_view_render_legend(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb,
                          gi_view_legend *legend);
/* The description for this frame: gi_view_describe, and for the views of
 * the VPL update (vpls, vpl-overhead, vpl-bounce, vpl-moved, method) the
 * frame's method with its paper and why it chooses VPLs as it does
 * (gi_vpl_method.why). The dump's captions.txt, the EXR comments and the
 * stepper's HUD show it. */
int gi_view_describe_frame(const gi_frame *f, gi_view_id id, char *buf, size_t n);
/* The frame's VPL method (Instant Radiosity when none was given). */
const gi_vpl_method *gi_view_method(const gi_frame *f);

/* Which frame pixel (x, y) view `id` draws at its pixel (u, v): the same
 * pixel for the views in image layout, the mosaic's inverse for the split
 * and accumulated views (tile (i, j) drawn at (i w0, j h0)). Returns 0 for
 * the views that are maps or drawings (shadow map, overhead, paraboloid
 * map), outside the view, and on a mosaic pixel no tile covers. */
/* The index into gi_indirect's split-layout buffers that pixel (u, v) of
 * the split and accumulated views' mosaic shows (tile (i, j) drawn at
 * (i w0, j h0), w0 x h0 being tile 0's size); SIZE_MAX where no tile
 * covers the pixel. */
size_t gi_view_mosaic_index(const gi_frame *f, uint32_t u, uint32_t v);
int gi_view_frame_pixel(const gi_frame *f, gi_view_id id, uint32_t u, uint32_t v, uint32_t *x, uint32_t *y);
/* The inverse: where view `id` draws frame pixel (x, y); 0 where it does
 * not draw it. */
int gi_view_view_pixel(const gi_frame *f, gi_view_id id, uint32_t x, uint32_t y, uint32_t *u, uint32_t *v);

/* Writes an RGB8 image (top row first) as a PNG, creating parent folders;
 * the same encoder and settings as pf_imageio_write_png. */
pf_result gi_view_write_png(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h, pf_error *err);

/* Zoom and pan: a view of sw x sh pixels shown in a window of dw x dh
 * pixels, fitted (aspect kept, centred) and then magnified `zoom` times
 * about the view point (cx, cy), which appears at the window's centre.
 * Nearest neighbour: zoomed in, every view pixel is a visible block, so a
 * learner can see (and click) single texels. Window coordinates are
 * continuous, y down: pixel (X, Y) covers [X, X+1) x [Y, Y+1). */
typedef struct gi_view_zoom {
    float zoom;   /* 1 (fitted) .. GI_VIEW_ZOOM_MAX */
    float cx, cy; /* view coordinates at the window's centre */
} gi_view_zoom;
#define GI_VIEW_ZOOM_MAX 64.0f

/* Fitted and centred. */
void gi_view_zoom_reset(gi_view_zoom *z, uint32_t sw, uint32_t sh);
/* Window pixels per view pixel. */
float gi_view_zoom_scale(const gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh);
/* Window point (wx, wy) -> the view pixel under it; 0 outside the view. */
int gi_view_zoom_to_view(const gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float wx, float wy,
                         uint32_t *u, uint32_t *v);
/* View point (u, v) (continuous) -> window point. */
void gi_view_zoom_to_window(const gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float u, float v,
                            float *wx, float *wy);
/* Zooms by `factor` (clamped to 1 .. GI_VIEW_ZOOM_MAX) keeping the view
 * point under window point (wx, wy) where it is. */
void gi_view_zoom_at(gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float wx, float wy,
                     float factor);
/* Moves the view with the cursor by (dx, dy) window pixels; its centre
 * stays inside the view. */
void gi_view_zoom_pan(gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float dx, float dy);
/* Draws the RGB8 view src (sw x sh) into dst (dw x dh) through the zoom;
 * window pixels outside the view are dark grey. Unzoomed, with dw = sw and
 * dh = sh, dst is a copy of src. */
void gi_view_blit(uint8_t *dst, uint32_t dw, uint32_t dh, const uint8_t *src, uint32_t sw, uint32_t sh,
                  const gi_view_zoom *z);

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
