/* gi_view_draw: the drawing helpers the view files share (gi_view.c, the
 * stage pictures; gi_view_learn.c, the views of "the frame
 * taken apart"). Private to src/view: RGB8 images, top row first, every
 * helper clipped to the image and deterministic. */
#ifndef GI_VIEW_DRAW_H
#define GI_VIEW_DRAW_H

#include <stdint.h>

#include "gi_frame.h"
#include "gi_view.h"

/* round(255 v) for v in [0, 1], clamped (NaN -> 0). */
uint8_t gi_view_draw_unit(float v);
void gi_view_draw_put(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, const uint8_t c[3]);
void gi_view_draw_line(uint8_t *rgb, uint32_t w, uint32_t h, int x0, int y0, int x1, int y1, const uint8_t c[3]);
void gi_view_draw_box(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rad, const uint8_t c[3]);
/* Heat colour map for t in [0, 1]: dark blue -> red -> yellow -> white. */
void gi_view_draw_heat(float t, uint8_t c[3]);
/* Categorical colours (clusters, tiles, bounces): 12 distinct hues, cycled. */
void gi_view_draw_palette(uint32_t k, uint8_t c[3]);

/* The luminance range of a VPL set's non-empty VPLs, and a VPL's heat
 * colour in it (square-root scaled so that dim VPLs stay visible). */
void gi_view_vpl_range(const gi_vpl_set *set, float *lo, float *hi);
void gi_view_vpl_colour(float lum, float lo, float hi, uint8_t c[3]);
/* A paraboloid map's distance range (texels that hit something) and one
 * texel's colour: near white, far black, nothing hit dark blue, outside
 * the disc black. */
void gi_view_para_range(const uint16_t *map, uint32_t R, float range, float *lo, float *hi);
void gi_view_para_texel(uint16_t code, float range, float lo, float hi, uint8_t o[3]);

/* World point -> continuous pixel position with the frame's camera; 0
 * behind the camera or far outside. */
int gi_view_draw_project(const gi_frame *f, pf_vec3 p, float *x, float *y);
/* Whether the camera sees world point p: an Embree ray from the eye
 * towards p finds nothing before 0.999 of the way (the VPLs sit just off
 * their surface, gi_vpl.h). visible[k] for the `count` points p[k], in
 * 8-wide packets (the same bits alone or batched: pf_rt.h). */
void gi_view_draw_visible(const gi_frame *f, const pf_vec3 *p, uint32_t count, uint8_t *visible);
/* The final image through the display transform, each byte halved: the
 * background of the overlays. */
void gi_view_draw_dim_final(const gi_frame *f, float exposure, uint8_t *rgb);

/* A legend's colour bar: colour at position t in [0, 1] along the bar. */
typedef void (*gi_view_bar_fn)(float t, const void *user, uint8_t c[3]);
/* Fills *lg with a numeric range legend and, if the image is large enough,
 * draws it in the bottom-right corner: the label with the range on top,
 * the bar below (lo left, hi right). */
void gi_view_draw_legend_bar(uint8_t *rgb, uint32_t w, uint32_t h, gi_view_legend *lg, const char *what, float lo,
                             float hi, gi_view_bar_fn bar, const void *user);
/* A key: n coloured swatches with their names, and an optional title. */
void gi_view_draw_legend_key(uint8_t *rgb, uint32_t w, uint32_t h, gi_view_legend *lg, const char *what,
                             const char *const *names, const uint8_t (*colours)[3], uint32_t n);
/* Bars: grey (black at lo to white at hi), reversed grey (white at lo),
 * heat, heat of sqrt(t), and the display transform of lo + t (hi - lo)
 * (user: a float[3] of lo, hi and the exposure scale). */
void gi_view_bar_grey(float t, const void *user, uint8_t c[3]);
void gi_view_bar_grey_rev(float t, const void *user, uint8_t c[3]);
void gi_view_bar_heat(float t, const void *user, uint8_t c[3]);
void gi_view_bar_heat_sqrt(float t, const void *user, uint8_t c[3]);
void gi_view_bar_display(float t, const void *user, uint8_t c[3]);

/* The views of gi_view_learn.c (vpls, vpl-overhead's VPL colours aside):
 * the occlusion-aware overlays, the atlas, the tiles, the clamp mask and
 * the method's own view. Return 0 when there is nothing to draw. */
int gi_view_learn_render(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb,
                         gi_view_legend *lg);
/* The clamp mask's data: per frame pixel, how many of its tile's VPLs
 * light it with the bounded geometry term clamped (gi_probe's `clamped`),
 * into count (width * height floats). Uses the frame's job system. */
void gi_view_clamp_counts(const gi_frame *f, float *count);

#endif
