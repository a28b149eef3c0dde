/* gi_view: a frame's stages as RGB8 pictures with captions, shared by the
 * stepper of `softgi view` and `--dump-stages` (see gi_view.h for the list,
 * the papers and the display transforms). */
#include "gi_view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_probe.h"
#include "gi_view_draw.h"
#include "pf_imageio.h"

/* The views: file-name part, the stage whose output each shows (its step,
 * name and paper come from the stage table, gi_frame.h) and what the
 * picture shows. */
typedef struct gi__view_info {
    const char *name;
    gi_stage_id stage;
    const char *caption;
} gi__view_info;

static const gi__view_info gi__views[GI_VIEW_COUNT] = {
    [GI_VIEW_DEPTH] = {"depth", GI_STAGE_GBUFFER_RASTER,
                       "view-space distance of the visible surface, near = bright; every later stage reads these "
                       "planes, so shading costs per pixel, not per triangle"},
    [GI_VIEW_POSITION] = {"position", GI_STAGE_GBUFFER_RESOLVE, "world position of the visible surface"},
    [GI_VIEW_NORMAL] = {"normal", GI_STAGE_GBUFFER_RESOLVE, "shading normal, turned to face the camera"},
    [GI_VIEW_ALBEDO] = {"albedo", GI_STAGE_GBUFFER_RESOLVE, "filtered baseColor, linear RGB"},
    [GI_VIEW_PRIM] = {"prim", GI_STAGE_GBUFFER_RASTER, "primitive id: which triangle each pixel sees"},
    [GI_VIEW_SHADOW_MAP] = {"shadow-map", GI_STAGE_SHADOW_MAPS,
                            "light 0's map, near = bright (cube: +x -x +y / -y +z -z), read with 16-tap PCF; blue checker: tiles no visible receiver reads, not drawn"},
    [GI_VIEW_DIRECT] = {"direct", GI_STAGE_DIRECT_SHADOWMAP, "every light with its shadow test, albedo E / pi"},
    [GI_VIEW_VPLS] = {"vpls", GI_STAGE_VPL_UPDATE,
                      "the VPLs the camera sees, coloured by intensity (hidden ones are not drawn); each re-emits the "
                      "light it received, standing in for the indirect light"},
    [GI_VIEW_VPL_OVERHEAD] = {"vpl-overhead", GI_STAGE_VPL_UPDATE,
                              "VPLs from above (cut at eye height), coloured by intensity; lights yellow, camera and "
                              "frustum green (Hedman 2017 Fig. 3)"},
    [GI_VIEW_VPL_MAP] = {"vpl-map", GI_STAGE_VPL_MAPS,
                         "the chosen VPL's paraboloid map (white box), near = bright: what the VPL sees, so its light "
                         "casts shadows"},
    [GI_VIEW_SPLIT] = {"split", GI_STAGE_SPLIT,
                       "the split G-buffer's normals: n x m tiles, each the image sub-sampled with its own offset, so "
                       "each tile can shade with its own share of the VPLs"},
    [GI_VIEW_ACCUMULATED] = {"accumulated", GI_STAGE_ACCUMULATE,
                             "each tile's irradiance from its share of the VPLs, in tile layout"},
    [GI_VIEW_COMBINED] = {"combined", GI_STAGE_COMBINE,
                          "the tiles back in image layout; the n x m structured noise is visible (Laine 2007 Fig. 4a)"},
    [GI_VIEW_FILTERED] = {"filtered", GI_STAGE_FILTER,
                          "the filtered irradiance (default: Laine 2007 Fig. 5's geometry-aware box): averaging n x m "
                          "neighbours gives each pixel every tile's VPLs back"},
    [GI_VIEW_FINAL] = {"final", GI_STAGE_COMPOSE, "emission + direct + albedo / pi x filtered indirect, linear RGB"},
    [GI_VIEW_VPL_BOUNCE] = {"vpl-bounce", GI_STAGE_VPL_UPDATE,
                            "the VPLs the camera sees, by light bounce (1 = lit by a light; grey: the method does not "
                            "say); hidden ones are not drawn"},
    [GI_VIEW_VPL_MOVED] = {"vpl-moved", GI_STAGE_VPL_UPDATE,
                           "the VPLs the camera sees: green moved or new this frame (its map is re-rendered), blue "
                           "kept (its map is reused: why incremental methods are fast)"},
    [GI_VIEW_METHOD] = {"method", GI_STAGE_VPL_UPDATE, "the VPL method's own state"},
    [GI_VIEW_VPL_ATLAS] = {"vpl-atlas", GI_STAGE_VPL_MAPS,
                           "every VPL's paraboloid map, near = bright (green frame: re-rendered this frame, white: the "
                           "chosen VPL); one map per VPL is the cost incremental methods save"},
    [GI_VIEW_TILES] = {"tiles", GI_STAGE_ASSIGN,
                       "the tile assignment: each tile of the split mosaic with the VPLs it shades with; each pixel "
                       "pays for 1 / (n m) of the VPLs and the filter averages the n x m neighbours back"},
    [GI_VIEW_CLAMP] = {"clamp", GI_STAGE_ACCUMULATE,
                       "the clamp mask: how many of a pixel's VPLs the bounded geometry term min(G, b) clamped; it "
                       "trades the 1 / r^2 spikes near a VPL for missing energy in corners (survey Sec. 5)"},
};

/* The stepper's order: the outline's steps (gi_frame.h), each view after
 * the views of the same or earlier steps (the clamp mask, step 7, before
 * the accumulated tiles it explains). */
static const gi_view_id gi__order[GI_VIEW_COUNT] = {
    GI_VIEW_DEPTH,       GI_VIEW_POSITION,   GI_VIEW_NORMAL,      GI_VIEW_ALBEDO,       GI_VIEW_PRIM,
    GI_VIEW_SHADOW_MAP,  GI_VIEW_DIRECT,     GI_VIEW_VPLS,        GI_VIEW_VPL_OVERHEAD, GI_VIEW_VPL_BOUNCE,
    GI_VIEW_VPL_MOVED,   GI_VIEW_METHOD,     GI_VIEW_VPL_MAP,     GI_VIEW_VPL_ATLAS,    GI_VIEW_SPLIT,
    GI_VIEW_TILES,       GI_VIEW_CLAMP,      GI_VIEW_ACCUMULATED, GI_VIEW_COMBINED,     GI_VIEW_FILTERED,
    GI_VIEW_FINAL,
};

gi_view_id gi_view_order(uint32_t k) { return k < GI_VIEW_COUNT ? gi__order[k] : GI_VIEW_FINAL; }

uint32_t gi_view_rank(gi_view_id id)
{
    for (uint32_t k = 0; k < GI_VIEW_COUNT; k++)
        if (gi__order[k] == id) return k;
    return GI_VIEW_COUNT - 1;
}

const gi_vpl_method *gi_view_method(const gi_frame *f)
{
    return f->indirect && f->ind.opt.method ? f->ind.opt.method : &gi_method_ir;
}

const char *gi_view_name(gi_view_id id) { return (unsigned)id < GI_VIEW_COUNT ? gi__views[id].name : "?"; }

const char *gi_view_caption(gi_view_id id) { return (unsigned)id < GI_VIEW_COUNT ? gi__views[id].caption : "?"; }

gi_stage_id gi_view_stage(gi_view_id id)
{
    return (unsigned)id < GI_VIEW_COUNT ? gi__views[id].stage : GI_STAGE_COMPOSE;
}

int gi_view_describe(gi_view_id id, char *buf, size_t n)
{
    const gi_stage_info *st = gi_stage_get(gi_view_stage(id));
    return snprintf(buf, n, "step %u, %s (%s): %s", st->step, st->name, st->paper, gi_view_caption(id));
}

int gi_view_describe_frame(const gi_frame *f, gi_view_id id, char *buf, size_t n)
{
    if (!f->indirect || gi_view_stage(id) != GI_STAGE_VPL_UPDATE) return gi_view_describe(id, buf, n);
    const gi_stage_info *st = gi_stage_get(GI_STAGE_VPL_UPDATE);
    const gi_vpl_method *m = gi_view_method(f);
    const char *what = id == GI_VIEW_METHOD && m->view_caption ? m->view_caption : gi_view_caption(id);
    return snprintf(buf, n, "step %u, %s by %s: %s. Why: %s", st->step, st->name, m->paper, what,
                    m->why ? m->why : "-");
}

int gi_view_available(const gi_frame *f, gi_view_id id)
{
    switch (id) {
    case GI_VIEW_SHADOW_MAP:
        return f->raster && f->show_direct && f->shadows_rendered && f->shadows.count > 0 && f->shadows.maps[0].depth;
    case GI_VIEW_DIRECT: return f->show_direct;
    case GI_VIEW_VPL_ATLAS:
    case GI_VIEW_VPL_MAP: return f->indirect && f->ind.para && f->ind.vpls.count > 0 && f->ind.atlas_slots > 0;
    case GI_VIEW_METHOD: return f->indirect && f->ind.method_state && gi_view_method(f)->view;
    case GI_VIEW_VPLS:
    case GI_VIEW_VPL_BOUNCE:
    case GI_VIEW_VPL_MOVED:
    case GI_VIEW_TILES:
    case GI_VIEW_CLAMP:
    case GI_VIEW_VPL_OVERHEAD:
    case GI_VIEW_SPLIT:
    case GI_VIEW_ACCUMULATED:
    case GI_VIEW_COMBINED:
    case GI_VIEW_FILTERED: return f->indirect;
    default: return (unsigned)id < GI_VIEW_COUNT;
    }
}

/* ------------------------------------------------------------ pixels */

uint8_t gi_view_draw_unit(float v)
{
    if (!(v > 0.0f)) return 0;
    if (!(v < 1.0f)) return 255;
    return (uint8_t)(v * 255.0f + 0.5f);
}

static void gi__put(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, uint8_t r, uint8_t g, uint8_t b)
{
    if (x < 0 || y < 0 || x >= (int)w || y >= (int)h) return;
    uint8_t *p = rgb + 3 * ((size_t)y * w + (size_t)x);
    p[0] = r, p[1] = g, p[2] = b;
}

void gi_view_fill_rect(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rw, int rh, uint8_t r, uint8_t g,
                       uint8_t b)
{
    for (int j = y; j < y + rh; j++)
        for (int i = x; i < x + rw; i++) gi__put(rgb, w, h, i, j, r, g, b);
}

void gi_view_shade_rect(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rw, int rh)
{
    for (int j = y < 0 ? 0 : y; j < y + rh && j < (int)h; j++)
        for (int i = x < 0 ? 0 : x; i < x + rw && i < (int)w; i++) {
            uint8_t *p = rgb + 3 * ((size_t)j * w + (size_t)i);
            p[0] = (uint8_t)(p[0] / 4), p[1] = (uint8_t)(p[1] / 4), p[2] = (uint8_t)(p[2] / 4);
        }
}

/* Bresenham line. */
static void gi__line(uint8_t *rgb, uint32_t w, uint32_t h, int x0, int y0, int x1, int y1, uint8_t r, uint8_t g,
                     uint8_t b)
{
    int dx = abs(x1 - x0), dy = -abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1, e = dx + dy;
    for (int guard = 0; guard < 1 << 16; guard++) {
        gi__put(rgb, w, h, x0, y0, r, g, b);
        if (x0 == x1 && y0 == y1) break;
        int e2 = 2 * e;
        if (e2 >= dy) e += dy, x0 += sx;
        if (e2 <= dx) e += dx, y0 += sy;
    }
}

static void gi__box(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rad, uint8_t r, uint8_t g, uint8_t b)
{
    gi__line(rgb, w, h, x - rad, y - rad, x + rad, y - rad, r, g, b);
    gi__line(rgb, w, h, x + rad, y - rad, x + rad, y + rad, r, g, b);
    gi__line(rgb, w, h, x + rad, y + rad, x - rad, y + rad, r, g, b);
    gi__line(rgb, w, h, x - rad, y + rad, x - rad, y - rad, r, g, b);
}

void gi_view_draw_put(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, const uint8_t c[3])
{
    gi__put(rgb, w, h, x, y, c[0], c[1], c[2]);
}

void gi_view_draw_line(uint8_t *rgb, uint32_t w, uint32_t h, int x0, int y0, int x1, int y1, const uint8_t c[3])
{
    gi__line(rgb, w, h, x0, y0, x1, y1, c[0], c[1], c[2]);
}

void gi_view_draw_box(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int rad, const uint8_t c[3])
{
    gi__box(rgb, w, h, x, y, rad, c[0], c[1], c[2]);
}

/* Heat colour map for t in [0, 1]: dark blue -> red -> yellow -> white. */
void gi_view_draw_heat(float t, uint8_t c[3])
{
    t = pf_clampf(t, 0.0f, 1.0f);
    c[0] = gi_view_draw_unit(3.0f * t);
    c[1] = gi_view_draw_unit(3.0f * t - 1.0f);
    c[2] = gi_view_draw_unit(t < 1.0f / 3.0f ? 0.4f + 0.6f * (1.0f - 3.0f * t) * 0.5f : 3.0f * t - 2.0f);
}

void gi_view_draw_palette(uint32_t k, uint8_t c[3])
{
    static const uint8_t pal[12][3] = {{230, 25, 75},   {60, 180, 75},  {255, 225, 25}, {67, 99, 216},
                                       {245, 130, 49},  {145, 30, 180}, {66, 212, 244}, {240, 50, 230},
                                       {191, 239, 69},  {250, 190, 212}, {70, 153, 144}, {220, 190, 255}};
    memcpy(c, pal[k % 12], 3);
}


void gi_view_vpl_range(const gi_vpl_set *set, float *lo, float *hi)
{
    *lo = INFINITY, *hi = -INFINITY;
    for (uint32_t k = 0; k < set->count; k++) {
        float l = pf_luminance(set->v[k].intensity);
        if (!(l > 0.0f)) continue; /* an empty slot */
        *lo = fminf(*lo, l), *hi = fmaxf(*hi, l);
    }
    if (!(*lo <= *hi)) *lo = *hi = 0.0f;
}

/* VPL colour: its luminance from the set's smallest (lo) to its largest
 * (hi), square-root scaled so that dim VPLs stay visible. */
void gi_view_vpl_colour(float lum, float lo, float hi, uint8_t c[3])
{
    float t = hi > lo ? (lum - lo) / (hi - lo) : 1.0f;
    gi_view_draw_heat(sqrtf(pf_clampf(t, 0.0f, 1.0f)), c);
}

/* ------------------------------------------------------------ font */

/* 5x7 glyphs for ASCII 32..95 and 123..126, drawn here ('#' = ink; cell row 0
 * is blank, rows 1..7 hold the glyph, row 8 the lower-case descenders). */
static const char *const gi__glyphs[][7] = {
    {".....", ".....", ".....", ".....", ".....", ".....", "....."}, /* space */
    {"..#..", "..#..", "..#..", "..#..", "..#..", ".....", "..#.."}, /* ! */
    {".#.#.", ".#.#.", ".....", ".....", ".....", ".....", "....."}, /* " */
    {".#.#.", ".#.#.", "#####", ".#.#.", "#####", ".#.#.", ".#.#."}, /* # */
    {"..#..", ".####", "#.#..", ".###.", "..#.#", "####.", "..#.."}, /* $ */
    {"##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"}, /* % */
    {".##..", "#..#.", "#.#..", ".#...", "#.#.#", "#..#.", ".##.#"}, /* & */
    {"..#..", "..#..", ".....", ".....", ".....", ".....", "....."}, /* ' */
    {"...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."}, /* ( */
    {".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."}, /* ) */
    {".....", "..#..", "#.#.#", ".###.", "#.#.#", "..#..", "....."}, /* * */
    {".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."}, /* + */
    {".....", ".....", ".....", ".....", "..##.", "..#..", ".#..."}, /* , */
    {".....", ".....", ".....", "#####", ".....", ".....", "....."}, /* - */
    {".....", ".....", ".....", ".....", ".....", ".##..", ".##.."}, /* . */
    {".....", "....#", "...#.", "..#..", ".#...", "#....", "....."}, /* / */
    {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}, /* 0 */
    {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}, /* 1 */
    {".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"}, /* 2 */
    {"#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."}, /* 3 */
    {"...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."}, /* 4 */
    {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}, /* 5 */
    {"..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."}, /* 6 */
    {"#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."}, /* 7 */
    {".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."}, /* 8 */
    {".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."}, /* 9 */
    {".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."}, /* : */
    {".....", ".##..", ".##..", ".....", ".##..", "..#..", ".#..."}, /* ; */
    {"...#.", "..#..", ".#...", "#....", ".#...", "..#..", "...#."}, /* < */
    {".....", ".....", "#####", ".....", "#####", ".....", "....."}, /* = */
    {".#...", "..#..", "...#.", "....#", "...#.", "..#..", ".#..."}, /* > */
    {".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."}, /* ? */
    {".###.", "#...#", "....#", ".##.#", "#.#.#", "#.#.#", ".###."}, /* @ */
    {".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}, /* A */
    {"####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."}, /* B */
    {".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."}, /* C */
    {"###..", "#..#.", "#...#", "#...#", "#...#", "#..#.", "###.."}, /* D */
    {"#####", "#....", "#....", "####.", "#....", "#....", "#####"}, /* E */
    {"#####", "#....", "#....", "####.", "#....", "#....", "#...."}, /* F */
    {".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"}, /* G */
    {"#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}, /* H */
    {".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}, /* I */
    {"..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."}, /* J */
    {"#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"}, /* K */
    {"#....", "#....", "#....", "#....", "#....", "#....", "#####"}, /* L */
    {"#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"}, /* M */
    {"#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#"}, /* N */
    {".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}, /* O */
    {"####.", "#...#", "#...#", "####.", "#....", "#....", "#...."}, /* P */
    {".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"}, /* Q */
    {"####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"}, /* R */
    {".####", "#....", "#....", ".###.", "....#", "....#", "####."}, /* S */
    {"#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}, /* T */
    {"#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}, /* U */
    {"#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."}, /* V */
    {"#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#."}, /* W */
    {"#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"}, /* X */
    {"#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."}, /* Y */
    {"#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"}, /* Z */
    {".###.", ".#...", ".#...", ".#...", ".#...", ".#...", ".###."}, /* [ */
    {".....", "#....", ".#...", "..#..", "...#.", "....#", "....."}, /* backslash */
    {".###.", "...#.", "...#.", "...#.", "...#.", "...#.", ".###."}, /* ] */
    {"..#..", ".#.#.", "#...#", ".....", ".....", ".....", "....."}, /* ^ */
    {".....", ".....", ".....", ".....", ".....", ".....", "#####"}, /* _ */
    {"...#.", "..#..", "..#..", ".#...", "..#..", "..#..", "...#."}, /* { */
    {"..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}, /* | */
    {".#...", "..#..", "..#..", "...#.", "..#..", "..#..", ".#..."}, /* } */
    {".....", ".....", ".#...", "#.#.#", "...#.", ".....", "....."}, /* ~ */
};


/* Lower case a..z: 8 rows, the last one for descenders (g j p q y). */
static const char *const gi__lower[26][8] = {
    {".....", ".....", ".###.", "....#", ".####", "#...#", ".####", "....."}, /* a */
    {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "####.", "....."}, /* b */
    {".....", ".....", ".###.", "#....", "#....", "#...#", ".###.", "....."}, /* c */
    {"....#", "....#", ".##.#", "#..##", "#...#", "#...#", ".####", "....."}, /* d */
    {".....", ".....", ".###.", "#...#", "#####", "#....", ".###.", "....."}, /* e */
    {"..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#...", "....."}, /* f */
    {".....", ".....", ".####", "#...#", "#...#", ".####", "....#", ".###."}, /* g */
    {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "#...#", "....."}, /* h */
    {"..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###.", "....."}, /* i */
    {"...#.", ".....", "..##.", "...#.", "...#.", "...#.", "#..#.", ".##.."}, /* j */
    {"#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "....."}, /* k */
    {".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.", "....."}, /* l */
    {".....", ".....", "##.#.", "#.#.#", "#.#.#", "#...#", "#...#", "....."}, /* m */
    {".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#", "....."}, /* n */
    {".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###.", "....."}, /* o */
    {".....", ".....", "####.", "#...#", "#...#", "####.", "#....", "#...."}, /* p */
    {".....", ".....", ".####", "#...#", "#...#", ".####", "....#", "....#"}, /* q */
    {".....", ".....", "#.##.", "##..#", "#....", "#....", "#....", "....."}, /* r */
    {".....", ".....", ".####", "#....", ".###.", "....#", "####.", "....."}, /* s */
    {".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##.", "....."}, /* t */
    {".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#", "....."}, /* u */
    {".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#..", "....."}, /* v */
    {".....", ".....", "#...#", "#...#", "#.#.#", "#.#.#", ".#.#.", "....."}, /* w */
    {".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "....."}, /* x */
    {".....", ".....", "#...#", "#...#", "#...#", ".####", "....#", ".###."}, /* y */
    {".....", ".....", "#####", "...#.", "..#..", ".#...", "#####", "....."}, /* z */
};

/* The upper-case and symbol glyph of c (7 rows); '?' for what the font lacks. */
static const char *const *gi__glyph(int c)
{
    if (c >= 32 && c <= 95) return gi__glyphs[c - 32];
    if (c >= 123 && c <= 126) return gi__glyphs[64 + c - 123];
    if (c == 96) return gi__glyphs['\'' - 32];
    return gi__glyphs['?' - 32];
}

int gi_view_text(uint8_t *rgb, uint32_t w, uint32_t h, int x, int y, int scale, const char *text, uint8_t r,
                 uint8_t g, uint8_t b)
{
    if (scale < 1) scale = 1;
    int x0 = x;
    for (const char *p = text; *p; p++) {
        int c = (unsigned char)*p, lower = c >= 'a' && c <= 'z';
        const char *const *gl = lower ? gi__lower[c - 'a'] : gi__glyph(c);
        for (int row = 0; row < (lower ? 8 : 7); row++)
            for (int col = 0; col < 5; col++)
                if (gl[row][col] == '#')
                    gi_view_fill_rect(rgb, w, h, x + (col + 0) * scale, y + (row + 1) * scale, scale, scale, r, g, b);
        x += GI_FONT_CELL_W * scale;
    }
    return x - x0;
}

/* A black image with a centred message (a view the frame does not have). */
static void gi__unavailable(uint8_t *rgb, uint32_t w, uint32_t h, const char *msg)
{
    memset(rgb, 0, (size_t)w * h * 3);
    int tw = (int)strlen(msg) * GI_FONT_CELL_W;
    gi_view_text(rgb, w, h, ((int)w - tw) / 2, (int)h / 2 - GI_FONT_CELL_H / 2, 1, msg, 200, 200, 200);
}

/* ------------------------------------------------------------ legends */

void gi_view_bar_grey(float t, const void *user, uint8_t c[3])
{
    (void)user;
    c[0] = c[1] = c[2] = gi_view_draw_unit(t);
}

void gi_view_bar_grey_rev(float t, const void *user, uint8_t c[3])
{
    (void)user;
    c[0] = c[1] = c[2] = gi_view_draw_unit(1.0f - t);
}

void gi_view_bar_heat(float t, const void *user, uint8_t c[3])
{
    (void)user;
    gi_view_draw_heat(t, c);
}

void gi_view_bar_heat_sqrt(float t, const void *user, uint8_t c[3])
{
    (void)user;
    gi_view_draw_heat(sqrtf(pf_clampf(t, 0.0f, 1.0f)), c);
}

void gi_view_bar_display(float t, const void *user, uint8_t c[3])
{
    const float *u = user; /* lo, hi, exposure scale */
    c[0] = c[1] = c[2] = pf_imageio_display(u[0] + t * (u[1] - u[0]), u[2]);
}

/* sRGB-encoded grey from lo to hi (user: float[2]), as the albedo view. */
static void gi__bar_srgb(float t, const void *user, uint8_t c[3])
{
    const float *u = user;
    c[0] = c[1] = c[2] = gi_view_draw_unit(pf_linear_to_srgb(u[0] + t * (u[1] - u[0])));
}

static int gi__legend_fits(uint32_t w, uint32_t h) { return w >= GI_VIEW_LEGEND_MIN_W && h >= GI_VIEW_LEGEND_MIN_H; }

#define GI__BAR_W 100
#define GI__BAR_H 8

void gi_view_draw_legend_bar(uint8_t *rgb, uint32_t w, uint32_t h, gi_view_legend *lg, const char *what, float lo,
                             float hi, gi_view_bar_fn bar, const void *user)
{
    gi_view_legend tmp;
    if (!lg) lg = &tmp;
    memset(lg, 0, sizeof *lg);
    lg->present = 1, lg->has_range = 1, lg->lo = lo, lg->hi = hi;
    snprintf(lg->what, sizeof lg->what, "%s", what);
    snprintf(lg->text, sizeof lg->text, "%s: %.4g .. %.4g", what, (double)lo, (double)hi);
    if (!gi__legend_fits(w, h)) return;
    const char *text = lg->text;
    char shortc[64];
    if ((int)strlen(text) * GI_FONT_CELL_W > (int)w - 16) { /* too wide: the range alone */
        snprintf(shortc, sizeof shortc, "%.4g .. %.4g", (double)lo, (double)hi);
        text = shortc;
    }
    int tw = (int)strlen(text) * GI_FONT_CELL_W, bw = tw > GI__BAR_W ? tw : GI__BAR_W;
    int bh = GI_FONT_CELL_H + GI__BAR_H + 8;
    int x0 = (int)w - bw - 8, y0 = (int)h - bh - 4;
    gi_view_shade_rect(rgb, w, h, x0 - 3, y0 - 2, bw + 6, bh + 2);
    gi_view_text(rgb, w, h, x0, y0, 1, text, 230, 230, 230);
    int by = y0 + GI_FONT_CELL_H + 3, bx = x0 + bw - GI__BAR_W;
    for (int i = 0; i < GI__BAR_W; i++) {
        uint8_t c[3];
        bar((float)i / (float)(GI__BAR_W - 1), user, c);
        for (int j = 0; j < GI__BAR_H; j++) gi__put(rgb, w, h, bx + i, by + j, c[0], c[1], c[2]);
    }
}

void gi_view_draw_legend_key(uint8_t *rgb, uint32_t w, uint32_t h, gi_view_legend *lg, const char *what,
                             const char *const *names, const uint8_t (*colours)[3], uint32_t n)
{
    gi_view_legend tmp;
    if (!lg) lg = &tmp;
    memset(lg, 0, sizeof *lg);
    lg->present = 1;
    snprintf(lg->what, sizeof lg->what, "%s", what);
    size_t len = (size_t)snprintf(lg->text, sizeof lg->text, "%s", what);
    for (uint32_t k = 0; k < n && len < sizeof lg->text; k++)
        len += (size_t)snprintf(lg->text + len, sizeof lg->text - len, "%s%s", k ? ", " : ": ", names[k]);
    if (!gi__legend_fits(w, h)) return;
    int bw = (int)strlen(what) * GI_FONT_CELL_W;
    for (uint32_t k = 0; k < n; k++) {
        int ew = 12 + (int)strlen(names[k]) * GI_FONT_CELL_W;
        if (ew > bw) bw = ew;
    }
    int rows = (what[0] ? 1 : 0) + (int)n, bh = rows * (GI_FONT_CELL_H + 1) + 2;
    int x0 = (int)w - bw - 8, y0 = (int)h - bh - 4, y = y0;
    gi_view_shade_rect(rgb, w, h, x0 - 3, y0 - 2, bw + 6, bh + 2);
    if (what[0]) {
        gi_view_text(rgb, w, h, x0, y, 1, what, 230, 230, 230);
        y += GI_FONT_CELL_H + 1;
    }
    for (uint32_t k = 0; k < n; k++, y += GI_FONT_CELL_H + 1) {
        gi_view_fill_rect(rgb, w, h, x0, y + 2, 8, 7, colours[k][0], colours[k][1], colours[k][2]);
        gi_view_text(rgb, w, h, x0 + 12, y, 1, names[k], 230, 230, 230);
    }
}

/* ------------------------------------------------------------ views */

/* The G-buffer channels. Depth: near (the smallest view depth) white, the
 * farthest black; positions: each axis from its smallest to its largest
 * value in the image; normals: -1 .. 1; albedo: sRGB-encoded. Pixels
 * without a surface are black. */
static void gi__view_gbuffer(const gi_frame *f, gi_view_id id, uint8_t *rgb, gi_view_legend *lg)
{
    const rs_gbuffer *g = &f->gbuf;
    const uint32_t W = f->width, H = f->height;
    size_t n = (size_t)W * H;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    uint32_t plo = UINT32_MAX, phi = 0, seen = 0;
    const float *pl[3] = {g->pos_x, g->pos_y, g->pos_z};
    if (id == GI_VIEW_ALBEDO) pl[0] = g->alb_r, pl[1] = g->alb_g, pl[2] = g->alb_b;
    for (size_t i = 0; i < n; i++) {
        if (g->prim[i] == RS_GBUFFER_EMPTY) continue;
        seen++;
        if (g->prim[i] < plo) plo = g->prim[i];
        if (g->prim[i] > phi) phi = g->prim[i];
        if (id == GI_VIEW_DEPTH) {
            if (isfinite(g->depth[i])) lo[0] = fminf(lo[0], g->depth[i]), hi[0] = fmaxf(hi[0], g->depth[i]);
        } else if (id == GI_VIEW_POSITION || id == GI_VIEW_ALBEDO)
            for (int c = 0; c < 3; c++) lo[c] = fminf(lo[c], pl[c][i]), hi[c] = fmaxf(hi[c], pl[c][i]);
    }
    if (!seen) lo[0] = lo[1] = lo[2] = hi[0] = hi[1] = hi[2] = 0.0f;
    if (id == GI_VIEW_DEPTH && !(lo[0] <= hi[0])) lo[0] = hi[0] = 0.0f; /* no finite depth */
    float alo = fminf(lo[0], fminf(lo[1], lo[2])), ahi = fmaxf(hi[0], fmaxf(hi[1], hi[2]));
    for (size_t i = 0; i < n; i++) {
        uint8_t *o = rgb + 3 * i;
        int empty = g->prim[i] == RS_GBUFFER_EMPTY;
        switch (id) {
        case GI_VIEW_DEPTH: {
            float t = hi[0] > lo[0] ? 1.0f - (g->depth[i] - lo[0]) / (hi[0] - lo[0]) : 1.0f; /* nearest white */
            o[0] = o[1] = o[2] = !empty && isfinite(g->depth[i]) ? gi_view_draw_unit(t) : 0;
            break;
        }
        case GI_VIEW_POSITION:
            for (int c = 0; c < 3; c++)
                o[c] = empty ? 0 : gi_view_draw_unit(hi[c] > lo[c] ? (pl[c][i] - lo[c]) / (hi[c] - lo[c]) : 0.5f);
            break;
        case GI_VIEW_NORMAL:
            o[0] = empty ? 0 : gi_view_draw_unit(0.5f + 0.5f * g->nrm_x[i]);
            o[1] = empty ? 0 : gi_view_draw_unit(0.5f + 0.5f * g->nrm_y[i]);
            o[2] = empty ? 0 : gi_view_draw_unit(0.5f + 0.5f * g->nrm_z[i]);
            break;
        case GI_VIEW_ALBEDO:
            o[0] = empty ? 0 : gi_view_draw_unit(pf_linear_to_srgb(g->alb_r[i]));
            o[1] = empty ? 0 : gi_view_draw_unit(pf_linear_to_srgb(g->alb_g[i]));
            o[2] = empty ? 0 : gi_view_draw_unit(pf_linear_to_srgb(g->alb_b[i]));
            break;
        default: { /* primitive id: a hash colour per triangle */
            uint32_t hsh = g->prim[i] * 2654435761u;
            o[0] = empty ? 0 : (uint8_t)(hsh & 255);
            o[1] = empty ? 0 : (uint8_t)(hsh >> 8 & 255);
            o[2] = empty ? 0 : (uint8_t)(hsh >> 16 & 255);
        }
        }
    }
    char what[64];
    switch (id) {
    case GI_VIEW_DEPTH:
        gi_view_draw_legend_bar(rgb, W, H, lg, "view depth", lo[0], hi[0], gi_view_bar_grey_rev, NULL);
        break;
    case GI_VIEW_POSITION: {
        char nx[48], ny[48], nz[48];
        snprintf(nx, sizeof nx, "R = x %.4g .. %.4g", (double)lo[0], (double)hi[0]);
        snprintf(ny, sizeof ny, "G = y %.4g .. %.4g", (double)lo[1], (double)hi[1]);
        snprintf(nz, sizeof nz, "B = z %.4g .. %.4g", (double)lo[2], (double)hi[2]);
        const char *names[3] = {nx, ny, nz};
        const uint8_t cols[3][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
        gi_view_draw_legend_key(rgb, W, H, lg, "world position", names, cols, 3);
        if (lg) lg->has_range = 1, lg->lo = alo, lg->hi = ahi;
        break;
    }
    case GI_VIEW_NORMAL: {
        const char *names[3] = {"R = x", "G = y", "B = z"};
        const uint8_t cols[3][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
        gi_view_draw_legend_key(rgb, W, H, lg, "unit normal, -1 .. 1", names, cols, 3);
        break;
    }
    case GI_VIEW_ALBEDO: {
        const float u[2] = {alo, ahi};
        gi_view_draw_legend_bar(rgb, W, H, lg, "linear albedo", alo, ahi, gi__bar_srgb, u);
        break;
    }
    default:
        snprintf(what, sizeof what, "%u pixels see triangles %u .. %u", seen, seen ? plo : 0, seen ? phi : 0);
        gi_view_draw_legend_key(rgb, W, H, lg, what, NULL, NULL, 0);
        if (lg) lg->has_range = 1, lg->lo = (float)(seen ? plo : 0), lg->hi = (float)(seen ? phi : 0);
        break;
    }
}

/* Radiance or irradiance through the PNG writer's display transform, one
 * job item per row (the transform is per value: any thread count gives the
 * same bytes). */
typedef struct gi__display_ctx {
    const float *src;
    uint8_t *rgb;
    size_t row; /* values per row */
    float scale;
} gi__display_ctx;

static void gi__display_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__display_ctx *c = p;
    size_t o = (size_t)y * c->row;
    for (size_t i = o; i < o + c->row; i++) c->rgb[i] = pf_imageio_display(c->src[i], c->scale);
}

static void gi__view_radiance(const gi_frame *f, const float *src, float exposure, uint8_t *rgb)
{
    gi__display_ctx c = {src, rgb, (size_t)f->width * 3, exp2f(exposure)};
    pf_jobs_parallel_for(f->jobs, gi__display_row, &c, f->height, 8);
}

void gi_view_draw_dim_final(const gi_frame *f, float exposure, uint8_t *rgb)
{
    gi__view_radiance(f, f->final, exposure, rgb);
    for (size_t i = 0; i < (size_t)f->width * f->height * 3; i++) rgb[i] = (uint8_t)(rgb[i] / 2);
}

/* The legend of a radiance or irradiance buffer of `count` RGB values:
 * their smallest and largest component, through the display transform. */
static void gi__radiance_legend(const gi_frame *f, const float *src, size_t count, float exposure, uint8_t *rgb,
                                gi_view_legend *lg, const char *what)
{
    float u[3] = {INFINITY, -INFINITY, exp2f(exposure)};
    for (size_t i = 0; i < 3 * count; i++) u[0] = fminf(u[0], src[i]), u[1] = fmaxf(u[1], src[i]);
    if (!(u[0] <= u[1])) u[0] = u[1] = 0.0f;
    gi_view_draw_legend_bar(rgb, f->width, f->height, lg, what, u[0], u[1], gi_view_bar_display, u);
}

/* A buffer of the indirect image (w x h; the frame's size unless
 * --indirect-scale > 1, then each of its pixels drawn as a scale x scale
 * block: frame pixel (x, y) shows gi_indirect_pixel). */
static void gi__view_indirect_image(const gi_frame *f, const float *src, float exposure, uint8_t *rgb)
{
    const gi_indirect *ind = &f->ind;
    if (ind->scale <= 1) {
        gi__view_radiance(f, src, exposure, rgb);
        return;
    }
    float scale = exp2f(exposure);
    for (uint32_t y = 0; y < f->height; y++)
        for (uint32_t x = 0; x < f->width; x++) {
            const float *e = src + 3 * gi_indirect_pixel(ind, x, y);
            uint8_t *o = rgb + 3 * ((size_t)y * f->width + x);
            for (int c = 0; c < 3; c++) o[c] = pf_imageio_display(e[c], scale);
        }
}

/* Light 0's shadow map: one face fitted in the image, or a cube's six faces
 * as a 3 x 2 grid (+x -x +y on top, -y +z -z below); the tiles the frame
 * did not draw (no visible receiver reads them, gi_stage_shadow_maps) as a
 * dark blue checker. */
static void gi__view_shadow_map(const gi_frame *f, uint8_t *rgb, gi_view_legend *lg)
{
    uint32_t W = f->width, H = f->height;
    memset(rgb, 0, (size_t)W * H * 3);
    const rs_shadow_map *m = &f->shadows.maps[0];
    uint32_t cols = m->face_count == 6 ? 3 : 1, rows = m->face_count == 6 ? 2 : 1;
    uint32_t cell = W / cols < H / rows ? W / cols : H / rows;
    if (cell == 0) return;
    uint32_t ox = (W - cell * cols) / 2, oy = (H - cell * rows) / 2;
    /* one scale for every face: 0 (nothing, or the far end) .. the largest
     * stored value (reversed depth: near = large = bright) */
    size_t texels = (size_t)m->size * m->size;
    float zmax = 0.0f;
    for (uint32_t face = 0; face < m->face_count && face < 6; face++) {
        const float *d = rs_shadow_map_face(m, face);
        for (size_t i = 0; i < texels; i++)
            if (rs_shadow_texel_valid(m, face, (uint32_t)(i % m->size), (uint32_t)(i / m->size))) zmax = fmaxf(zmax, d[i]);
    }
    for (uint32_t face = 0; face < m->face_count && face < 6; face++) {
        const float *d = rs_shadow_map_face(m, face);
        uint32_t cx = ox + (face % cols) * cell, cy = oy + (face / cols) * cell;
        for (uint32_t y = 0; y < cell; y++)
            for (uint32_t x = 0; x < cell; x++) {
                uint32_t tx = (uint32_t)((uint64_t)x * m->size / cell), ty = (uint32_t)((uint64_t)y * m->size / cell);
                uint8_t *o = rgb + 3 * ((size_t)(cy + y) * W + cx + x);
                if (!rs_shadow_texel_valid(m, face, tx, ty)) { /* not drawn: no visible receiver reads it */
                    o[0] = o[1] = o[2] = (uint8_t)(((tx / 8 + ty / 8) & 1u) ? 40 : 24);
                    o[2] = (uint8_t)(o[2] + 24);
                    continue;
                }
                float v = zmax > 0.0f ? d[(size_t)ty * m->size + tx] / zmax : 0.0f; /* reversed depth: near = 1 */
                o[0] = o[1] = o[2] = gi_view_draw_unit(v);
            }
        if (m->face_count == 6) gi__box(rgb, W, H, (int)(cx + cell / 2), (int)(cy + cell / 2), (int)cell / 2, 90, 90, 160);
    }
    gi_view_draw_legend_bar(rgb, W, H, lg, "reversed depth (near = 1)", 0.0f, zmax, gi_view_bar_grey, NULL);
}

/* Overhead view: the scene seen straight down (+x right, +z down),
 * fitted to the image, with everything above the camera's eye height cut
 * away so interiors show their floor plan. */
typedef struct gi__overhead {
    const gi_frame *f;
    uint8_t *rgb;
    float cx, cz, scale, y0;
    int frustum;                  /* 1: tint the camera's horizontal frustum */
    float ex, ez, lx, lz, rx, rz; /* eye and the left / right edge directions, x-z plane */
} gi__overhead;

static float gi__cross2(float ax, float az, float bx, float bz) { return ax * bz - az * bx; }

/* 1 if the x-z point (x, z) lies in the wedge between the frustum's edges. */
static int gi__in_frustum(const gi__overhead *o, float x, float z)
{
    float dx = x - o->ex, dz = z - o->ez, s = gi__cross2(o->lx, o->lz, o->rx, o->rz);
    return s * gi__cross2(o->lx, o->lz, dx, dz) >= 0.0f && s * gi__cross2(dx, dz, o->rx, o->rz) >= 0.0f &&
           o->lx * dx + o->lz * dz + o->rx * dx + o->rz * dz > 0.0f;
}

static void gi__overhead_row(void *ctx, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__overhead *o = ctx;
    const gi_frame *f = o->f;
    uint32_t W = f->width;
    pf_ray rays[PF_RT_WIDTH];
    pf_hit hits[PF_RT_WIDTH];
    for (uint32_t x0 = 0; x0 < W; x0 += PF_RT_WIDTH) {
        uint32_t n = W - x0 < PF_RT_WIDTH ? W - x0 : PF_RT_WIDTH;
        for (uint32_t k = 0; k < n; k++) {
            float wx = o->cx + ((float)(x0 + k) + 0.5f - 0.5f * (float)W) / o->scale;
            float wz = o->cz + ((float)y + 0.5f - 0.5f * (float)f->height) / o->scale;
            rays[k].org = pf_v3(wx, o->y0, wz);
            rays[k].dir = pf_v3(0.0f, -1.0f, 0.0f);
            rays[k].tnear = 0.0f;
            rays[k].tfar = INFINITY;
        }
        pf_rt_intersect(f->rt, rays, hits, n);
        for (uint32_t k = 0; k < n; k++) {
            uint8_t *p = o->rgb + 3 * ((size_t)y * W + x0 + k);
            if (hits[k].prim == PF_RT_MISS) {
                p[0] = p[1] = p[2] = 24;
                continue;
            }
            pf_surface sf;
            pf_rt_surface(f->rt, &hits[k], 0.0f, &sf);
            float shade = 0.25f + 0.75f * fabsf(sf.ng.y); /* floors bright, walls seen edge-on dark */
            for (int c = 0; c < 3; c++) p[c] = gi_view_draw_unit(pf_linear_to_srgb(sf.albedo[c] * shade) * 0.8f);
        }
        for (uint32_t k = 0; k < n && o->frustum; k++) /* the frustum as a green region (Hedman 2017 Fig. 3) */
            if (gi__in_frustum(o, rays[k].org.x, rays[k].org.z)) {
                uint8_t *p = o->rgb + 3 * ((size_t)y * W + x0 + k);
                p[0] = (uint8_t)(p[0] * 3 / 4), p[1] = (uint8_t)(p[1] * 3 / 4 + 50), p[2] = (uint8_t)(p[2] * 3 / 4);
            }
    }
}

static void gi__overhead_point(const gi__overhead *o, pf_vec3 p, int *px, int *py)
{
    float x = (p.x - o->cx) * o->scale + 0.5f * (float)o->f->width;
    float y = (p.z - o->cz) * o->scale + 0.5f * (float)o->f->height;
    *px = (int)floorf(pf_clampf(x, -1e6f, 1e6f)), *py = (int)floorf(pf_clampf(y, -1e6f, 1e6f));
}

static void gi__view_overhead(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb, gi_view_legend *lg)
{
    uint32_t W = f->width, H = f->height;
    const pf_scene *sc = f->scene;
    pf_vec3 ext = pf_v3_sub(sc->bounds_max, sc->bounds_min);
    gi__overhead o;
    o.f = f;
    o.rgb = rgb;
    /* the region shown: the scene's bounds, the camera and the lights */
    float x0 = sc->bounds_min.x, x1 = sc->bounds_max.x, z0 = sc->bounds_min.z, z1 = sc->bounds_max.z;
    for (uint32_t l = 0; l <= sc->light_count; l++) {
        pf_vec3 p = l < sc->light_count ? sc->lights[l].position : f->camera.eye;
        if (l < sc->light_count && sc->lights[l].type == PF_LIGHT_DIRECTIONAL) continue;
        x0 = fminf(x0, p.x), x1 = fmaxf(x1, p.x), z0 = fminf(z0, p.z), z1 = fmaxf(z1, p.z);
    }
    o.cx = 0.5f * (x0 + x1);
    o.cz = 0.5f * (z0 + z1);
    float sx = 0.92f * (float)W / fmaxf(x1 - x0, 1e-6f), sz = 0.92f * (float)H / fmaxf(z1 - z0, 1e-6f);
    o.scale = fminf(sx, sz);
    float diag = pf_v3_length(ext);
    o.y0 = fminf(sc->bounds_max.y + 1e-3f * diag, fmaxf(sc->bounds_min.y, f->camera.eye.y));
    pf_vec3 dl = pf_camera_ray_dir(&f->camera, W, H, 0.0f, 0.5f * (float)H);
    pf_vec3 dr = pf_camera_ray_dir(&f->camera, W, H, (float)W, 0.5f * (float)H);
    o.ex = f->camera.eye.x, o.ez = f->camera.eye.z, o.lx = dl.x, o.lz = dl.z, o.rx = dr.x, o.rz = dr.z;
    /* a camera looking (almost) straight down or up has no horizontal wedge */
    o.frustum = fabsf(gi__cross2(o.lx, o.lz, o.rx, o.rz)) > 1e-6f;
    pf_jobs_parallel_for(f->jobs, gi__overhead_row, &o, H, 4);
    /* camera: eye and the frustum's left/right edges through the image centre row */
    int ex, ey, ax, ay;
    gi__overhead_point(&o, f->camera.eye, &ex, &ey);
    float len = 0.6f * diag;
    const float edge_x[3] = {0.0f, 0.5f * (float)W, (float)W};
    for (int k = 0; k < 3; k++) {
        pf_vec3 d = pf_camera_ray_dir(&f->camera, W, H, edge_x[k], 0.5f * (float)H);
        d.y = 0.0f;
        if (!(pf_v3_length(d) > 0.0f)) continue;
        d = pf_v3_scale(pf_v3_normalize(d), k == 1 ? 0.15f * diag : len);
        gi__overhead_point(&o, pf_v3_add(f->camera.eye, d), &ax, &ay);
        gi__line(rgb, W, H, ex, ey, ax, ay, 40, 220, 40);
    }
    gi_view_fill_rect(rgb, W, H, ex - 2, ey - 2, 5, 5, 40, 255, 40);
    /* VPLs */
    const gi_vpl_set *set = &f->ind.vpls;
    float lo, hi;
    gi_view_vpl_range(set, &lo, &hi);
    for (uint32_t k = 0; k < set->count; k++) {
        int px, py;
        uint8_t c[3];
        float l = pf_luminance(set->v[k].intensity);
        if (!(l > 0.0f)) continue; /* an empty slot */
        gi__overhead_point(&o, set->v[k].pos, &px, &py);
        gi_view_vpl_colour(l, lo, hi, c);
        gi_view_fill_rect(rgb, W, H, px - 1, py - 1, 3, 3, c[0], c[1], c[2]);
    }
    if (set->count) {
        int px, py;
        gi__overhead_point(&o, set->v[s->vpl % set->count].pos, &px, &py);
        gi__box(rgb, W, H, px, py, 4, 255, 255, 255);
    }
    /* lights: a yellow cross; spots also show their direction */
    for (uint32_t l = 0; l < sc->light_count; l++) {
        const pf_light *L = &sc->lights[l];
        if (L->type == PF_LIGHT_DIRECTIONAL) continue;
        int px, py;
        gi__overhead_point(&o, L->position, &px, &py);
        gi__line(rgb, W, H, px - 5, py, px + 5, py, 255, 230, 0);
        gi__line(rgb, W, H, px, py - 5, px, py + 5, 255, 230, 0);
        if (L->type == PF_LIGHT_SPOT) {
            gi__overhead_point(&o, pf_v3_add(L->position, pf_v3_scale(L->direction, 0.1f * diag)), &ax, &ay);
            gi__line(rgb, W, H, px, py, ax, ay, 255, 230, 0);
        }
    }
    gi_view_draw_legend_bar(rgb, W, H, lg, "VPL luminance (W/sr)", lo, hi, gi_view_bar_heat_sqrt, NULL);
}

/* The chosen VPL's paraboloid map (R x R codes) fitted in the image:
 * near = bright, nothing hit = dark blue, outside the disc = black. */
static void gi__view_vpl_map(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb, gi_view_legend *lg)
{
    uint32_t W = f->width, H = f->height;
    memset(rgb, 0, (size_t)W * H * 3);
    const gi_indirect *ind = &f->ind;
    uint32_t count = ind->vpls.count < ind->atlas_slots ? ind->vpls.count : ind->atlas_slots;
    uint32_t R = ind->opt.para_res, k = s->vpl % count;
    const uint16_t *map = ind->atlas + (size_t)k * R * R;
    uint32_t side = W < H ? W : H;
    uint32_t ox = (W - side) / 2, oy = (H - side) / 2;
    float lo, hi;
    gi_view_para_range(map, R, ind->range, &lo, &hi);
    for (uint32_t y = 0; y < side; y++)
        for (uint32_t x = 0; x < side; x++) {
            uint32_t i = (uint32_t)((uint64_t)x * R / side), j = (uint32_t)((uint64_t)y * R / side);
            uint8_t *o = rgb + 3 * ((size_t)(oy + y) * W + ox + x);
            gi_view_para_texel(map[(size_t)j * R + i], ind->range, lo, hi, o);
        }
    gi__box(rgb, W, H, (int)(ox + side / 2), (int)(oy + side / 2), (int)side / 2, 255, 255, 255);
    gi_view_draw_legend_bar(rgb, W, H, lg, "distance from the VPL", lo, hi, gi_view_bar_grey_rev, NULL);
}

void gi_view_para_range(const uint16_t *map, uint32_t R, float range, float *lo, float *hi)
{
    *lo = INFINITY, *hi = -INFINITY;
    for (size_t i = 0; i < (size_t)R * R; i++) {
        if (map[i] == RS_PARA_OUTSIDE || map[i] == RS_PARA_EMPTY) continue;
        float d = rs_para_decode(map[i], range);
        *lo = fminf(*lo, d), *hi = fmaxf(*hi, d);
    }
    if (!(*lo <= *hi)) *lo = *hi = 0.0f;
}

void gi_view_para_texel(uint16_t code, float range, float lo, float hi, uint8_t o[3])
{
    if (code == RS_PARA_OUTSIDE) {
        o[0] = o[1] = o[2] = 0;
        return;
    }
    if (code == RS_PARA_EMPTY) {
        o[0] = 20, o[1] = 20, o[2] = 80;
        return;
    }
    float d = rs_para_decode(code, range);
    o[0] = o[1] = o[2] = gi_view_draw_unit(hi > lo ? 1.0f - (d - lo) / (hi - lo) : 1.0f);
}

/* The mosaic's layout: tile (i, j) drawn at (i w0, j h0), w0 x h0 being
 * tile 0's size (the largest). Pixel (u, v) shows tile t's texel (a, b), or
 * (return 0) no tile covers it. */
static int gi__mosaic_tile(const gi_indirect *ind, uint32_t u, uint32_t v, uint32_t *t, uint32_t *a, uint32_t *b)
{
    uint32_t i = u / ind->tile_w[0], j = v / ind->tile_h[0];
    *a = u % ind->tile_w[0], *b = v % ind->tile_h[0];
    if (i >= ind->n || j >= ind->m) return 0;
    *t = j * ind->n + i;
    return *a < ind->tile_w[*t] && *b < ind->tile_h[*t];
}

size_t gi_view_mosaic_index(const gi_frame *f, uint32_t u, uint32_t v)
{
    const gi_indirect *ind = &f->ind;
    uint32_t t, a, b;
    if (!gi__mosaic_tile(ind, u, v, &t, &a, &b)) return SIZE_MAX;
    return ind->tile_x0[t] + (size_t)b * ind->tile_w[t] + a;
}

/* A split-layout buffer (3 floats a texel) as the n x m mosaic of tiles
 * (gi_view_mosaic_index). Unit data (normals) is remapped from [-1, 1];
 * irradiance goes through the display transform. */
static void gi__view_mosaic(const gi_frame *f, int normals, float exposure, uint8_t *rgb, gi_view_legend *lg)
{
    const gi_indirect *ind = &f->ind;
    uint32_t W = f->width, H = f->height;
    float scale = exp2f(exposure);
    memset(rgb, 0, (size_t)W * H * 3);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            size_t k = gi_view_mosaic_index(f, x, y);
            if (k == SIZE_MAX) continue;
            uint8_t *o = rgb + 3 * ((size_t)y * W + x);
            if (normals) {
                int valid = ind->split_valid[k] != 0;
                o[0] = valid ? gi_view_draw_unit(0.5f + 0.5f * ind->split_nx[k]) : 0;
                o[1] = valid ? gi_view_draw_unit(0.5f + 0.5f * ind->split_ny[k]) : 0;
                o[2] = valid ? gi_view_draw_unit(0.5f + 0.5f * ind->split_nz[k]) : 0;
            } else {
                for (int c = 0; c < 3; c++) o[c] = pf_imageio_display(ind->split_e[3 * k + c], scale);
            }
        }
    if (normals) {
        const char *names[3] = {"R = x", "G = y", "B = z"};
        const uint8_t cols[3][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
        gi_view_draw_legend_key(rgb, W, H, lg, "split normal, -1 .. 1", names, cols, 3);
    } else {
        gi__radiance_legend(f, ind->split_e, (size_t)ind->w * ind->h, exposure, rgb, lg, "tile irradiance (W/m2)");
    }
}

int gi_view_render(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb)
{
    return gi_view_render_legend(f, id, s, rgb, NULL);
}

int gi_view_render_legend(const gi_frame *f, gi_view_id id, const gi_view_settings *s_in, uint8_t *rgb,
                          gi_view_legend *lg)
{
    gi_view_settings s;
    memset(&s, 0, sizeof s);
    if (s_in) s = *s_in;
    if (lg) memset(lg, 0, sizeof *lg);
    uint32_t W = f->width, H = f->height;
    if (!gi_view_available(f, id)) {
        gi__unavailable(rgb, W, H,
                        id == GI_VIEW_SHADOW_MAP ? "no shadow map (ray-traced frame, no lights or --indirect-only)"
                        : id == GI_VIEW_DIRECT   ? "no direct light (--indirect-only)"
                        : id == GI_VIEW_VPL_MAP || id == GI_VIEW_VPL_ATLAS
                            ? "no paraboloid maps (--visibility raytrace, no VPLs or --direct-only)"
                        : id == GI_VIEW_METHOD ? "this VPL method has no view of its own"
                                               : "no indirect light (--direct-only)");
        return 0;
    }
    switch (id) {
    case GI_VIEW_DEPTH:
    case GI_VIEW_POSITION:
    case GI_VIEW_NORMAL:
    case GI_VIEW_ALBEDO:
    case GI_VIEW_PRIM: gi__view_gbuffer(f, id, rgb, lg); break;
    case GI_VIEW_SHADOW_MAP: gi__view_shadow_map(f, rgb, lg); break;
    case GI_VIEW_DIRECT:
        gi__view_radiance(f, f->direct, s.exposure, rgb);
        gi__radiance_legend(f, f->direct, (size_t)W * H, s.exposure, rgb, lg, "direct radiance");
        break;
    case GI_VIEW_VPL_OVERHEAD: gi__view_overhead(f, &s, rgb, lg); break;
    case GI_VIEW_VPL_MAP: gi__view_vpl_map(f, &s, rgb, lg); break;
    case GI_VIEW_SPLIT: gi__view_mosaic(f, 1, s.exposure, rgb, lg); break;
    case GI_VIEW_ACCUMULATED: gi__view_mosaic(f, 0, s.exposure, rgb, lg); break;
    case GI_VIEW_COMBINED:
        gi__view_indirect_image(f, f->ind.combined, s.exposure, rgb);
        gi__radiance_legend(f, f->ind.combined, (size_t)f->ind.w * f->ind.h, s.exposure, rgb, lg,
                            "irradiance (W/m2)");
        break;
    case GI_VIEW_FILTERED:
        gi__view_radiance(f, f->ind.filtered, s.exposure, rgb);
        gi__radiance_legend(f, f->ind.filtered, (size_t)W * H, s.exposure, rgb, lg, "filtered irradiance (W/m2)");
        break;
    case GI_VIEW_FINAL: gi__view_radiance(f, f->final, s.exposure, rgb); break; /* the render's PNG: no legend */
    default: return gi_view_learn_render(f, id, &s, rgb, lg);
    }
    return 1;
}

/* ------------------------------------------------------------ pixels of a view */

static int gi__mosaic_view(gi_view_id id)
{
    return id == GI_VIEW_SPLIT || id == GI_VIEW_ACCUMULATED || id == GI_VIEW_TILES;
}

static int gi__image_layout_view(gi_view_id id)
{
    return id != GI_VIEW_SHADOW_MAP && id != GI_VIEW_VPL_OVERHEAD && id != GI_VIEW_VPL_MAP && !gi__mosaic_view(id) &&
           id != GI_VIEW_METHOD && id != GI_VIEW_VPL_ATLAS && (unsigned)id < GI_VIEW_COUNT;
}

int gi_view_frame_pixel(const gi_frame *f, gi_view_id id, uint32_t u, uint32_t v, uint32_t *x, uint32_t *y)
{
    if (u >= f->width || v >= f->height || !gi_view_available(f, id)) return 0;
    if (gi__image_layout_view(id)) {
        *x = u, *y = v;
        return 1;
    }
    if (!gi__mosaic_view(id)) return 0;
    /* tile t = (i, j)'s texel (a, b) is pixel (a n + i, b m + j) of the
     * indirect image, frame pixel scale x that */
    const gi_indirect *ind = &f->ind;
    uint32_t t, a, b;
    if (!gi__mosaic_tile(ind, u, v, &t, &a, &b)) return 0;
    *x = (a * ind->n + t % ind->n) * ind->scale, *y = (b * ind->m + t / ind->n) * ind->scale;
    return *x < f->width && *y < f->height;
}

int gi_view_view_pixel(const gi_frame *f, gi_view_id id, uint32_t x, uint32_t y, uint32_t *u, uint32_t *v)
{
    if (x >= f->width || y >= f->height || !gi_view_available(f, id)) return 0;
    if (gi__image_layout_view(id)) {
        *u = x, *v = y;
        return 1;
    }
    if (!gi__mosaic_view(id)) return 0;
    const gi_indirect *ind = &f->ind;
    x /= ind->scale, y /= ind->scale; /* the indirect image's pixel */
    *u = (x % ind->n) * ind->tile_w[0] + x / ind->n;
    *v = (y % ind->m) * ind->tile_h[0] + y / ind->m;
    return *u < f->width && *v < f->height;
}

/* ------------------------------------------------------------ zoom and pan */

void gi_view_zoom_reset(gi_view_zoom *z, uint32_t sw, uint32_t sh)
{
    z->zoom = 1.0f;
    z->cx = 0.5f * (float)sw, z->cy = 0.5f * (float)sh;
}

float gi_view_zoom_scale(const gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh)
{
    float fx = (float)dw / (float)sw, fy = (float)dh / (float)sh;
    return (fx < fy ? fx : fy) * z->zoom;
}

int gi_view_zoom_to_view(const gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float wx, float wy,
                         uint32_t *u, uint32_t *v)
{
    float s = gi_view_zoom_scale(z, sw, sh, dw, dh);
    float fu = floorf(z->cx + (wx - 0.5f * (float)dw) / s), fv = floorf(z->cy + (wy - 0.5f * (float)dh) / s);
    if (!(fu >= 0.0f && fu < (float)sw && fv >= 0.0f && fv < (float)sh)) return 0;
    *u = (uint32_t)fu, *v = (uint32_t)fv;
    return 1;
}

void gi_view_zoom_to_window(const gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float u, float v,
                            float *wx, float *wy)
{
    float s = gi_view_zoom_scale(z, sw, sh, dw, dh);
    *wx = 0.5f * (float)dw + (u - z->cx) * s;
    *wy = 0.5f * (float)dh + (v - z->cy) * s;
}

static void gi__zoom_clamp_centre(gi_view_zoom *z, uint32_t sw, uint32_t sh)
{
    z->cx = pf_clampf(z->cx, 0.0f, (float)sw);
    z->cy = pf_clampf(z->cy, 0.0f, (float)sh);
}

void gi_view_zoom_at(gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float wx, float wy,
                     float factor)
{
    if (dw == 0 || dh == 0) return; /* a minimised window */
    /* the view point under the cursor, before and after, stays the same:
     * c' = p - (w - d/2) / s' with p = c + (w - d/2) / s */
    float s0 = gi_view_zoom_scale(z, sw, sh, dw, dh);
    float px = z->cx + (wx - 0.5f * (float)dw) / s0, py = z->cy + (wy - 0.5f * (float)dh) / s0;
    z->zoom = pf_clampf(z->zoom * factor, 1.0f, GI_VIEW_ZOOM_MAX);
    float s1 = gi_view_zoom_scale(z, sw, sh, dw, dh);
    z->cx = px - (wx - 0.5f * (float)dw) / s1;
    z->cy = py - (wy - 0.5f * (float)dh) / s1;
    if (z->zoom == 1.0f) gi_view_zoom_reset(z, sw, sh); /* fitted is centred */
    gi__zoom_clamp_centre(z, sw, sh);
}

void gi_view_zoom_pan(gi_view_zoom *z, uint32_t sw, uint32_t sh, uint32_t dw, uint32_t dh, float dx, float dy)
{
    if (dw == 0 || dh == 0) return;
    float s = gi_view_zoom_scale(z, sw, sh, dw, dh);
    z->cx -= dx / s, z->cy -= dy / s;
    gi__zoom_clamp_centre(z, sw, sh);
}

void gi_view_blit(uint8_t *dst, uint32_t dw, uint32_t dh, const uint8_t *src, uint32_t sw, uint32_t sh,
                  const gi_view_zoom *z)
{
    /* the same expression as gi_view_zoom_to_view at the pixel centres, so
     * a click picks exactly the view pixel drawn under the cursor */
    float s = gi_view_zoom_scale(z, sw, sh, dw, dh);
    for (uint32_t Y = 0; Y < dh; Y++) {
        float fv = floorf(z->cy + ((float)Y + 0.5f - 0.5f * (float)dh) / s);
        uint8_t *o = dst + (size_t)Y * dw * 3;
        int row_in = fv >= 0.0f && fv < (float)sh;
        const uint8_t *row = row_in ? src + (size_t)fv * sw * 3 : NULL;
        for (uint32_t X = 0; X < dw; X++, o += 3) {
            float fu = floorf(z->cx + ((float)X + 0.5f - 0.5f * (float)dw) / s);
            if (!row_in || !(fu >= 0.0f && fu < (float)sw)) {
                o[0] = o[1] = o[2] = 16;
                continue;
            }
            const uint8_t *p = row + (size_t)fu * 3;
            o[0] = p[0], o[1] = p[1], o[2] = p[2];
        }
    }
}

pf_result gi_view_write_png(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h, pf_error *err)
{
    return pf_imageio_write_png_rgb8(path, rgb, w, h, err); /* temporary file + rename (pf_imageio.h) */
}
