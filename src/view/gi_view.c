/* gi_view: a frame's stages as RGB8 pictures with captions, shared by the
 * stepper of `softgi view` and `--dump-stages` (see gi_view.h for the list,
 * the papers and the display transforms). */
#include "gi_view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    [GI_VIEW_DEPTH] = {"depth", GI_STAGE_GBUFFER_RASTER, "view-space distance of the visible surface, near = bright"},
    [GI_VIEW_POSITION] = {"position", GI_STAGE_GBUFFER_RESOLVE, "world position of the visible surface"},
    [GI_VIEW_NORMAL] = {"normal", GI_STAGE_GBUFFER_RESOLVE, "shading normal, turned to face the camera"},
    [GI_VIEW_ALBEDO] = {"albedo", GI_STAGE_GBUFFER_RESOLVE, "filtered baseColor, linear RGB"},
    [GI_VIEW_PRIM] = {"prim", GI_STAGE_GBUFFER_RASTER, "primitive id: which triangle each pixel sees"},
    [GI_VIEW_SHADOW_MAP] = {"shadow-map", GI_STAGE_SHADOW_MAPS,
                            "light 0's map, near = bright (cube: +x -x +y / -y +z -z), read with 16-tap PCF"},
    [GI_VIEW_DIRECT] = {"direct", GI_STAGE_DIRECT_SHADOWMAP, "every light with its shadow test, albedo E / pi"},
    [GI_VIEW_VPLS] = {"vpls", GI_STAGE_VPL_UPDATE, "each VPL drawn where it projects, coloured by its intensity"},
    [GI_VIEW_VPL_OVERHEAD] = {"vpl-overhead", GI_STAGE_VPL_UPDATE,
                              "VPLs from above (cut at eye height), coloured by intensity; lights yellow, camera and "
                              "frustum green (Hedman 2017 Fig. 3)"},
    [GI_VIEW_VPL_MAP] = {"vpl-map", GI_STAGE_VPL_MAPS, "the chosen VPL's paraboloid map (white box), near = bright"},
    [GI_VIEW_SPLIT] = {"split", GI_STAGE_SPLIT, "the split G-buffer's normals: n x m tiles, each the image "
                                                "sub-sampled with its own offset"},
    [GI_VIEW_ACCUMULATED] = {"accumulated", GI_STAGE_ACCUMULATE,
                             "each tile's irradiance from its share of the VPLs, in tile layout"},
    [GI_VIEW_COMBINED] = {"combined", GI_STAGE_COMBINE,
                          "the tiles back in image layout; the n x m structured noise is visible (Laine 2007 Fig. 4a)"},
    [GI_VIEW_FILTERED] = {"filtered", GI_STAGE_FILTER,
                          "the filtered irradiance (default: Laine 2007 Fig. 5's geometry-aware box)"},
    [GI_VIEW_FINAL] = {"final", GI_STAGE_COMPOSE, "emission + direct + albedo / pi x filtered indirect, linear RGB"},
};

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

int gi_view_available(const gi_frame *f, gi_view_id id)
{
    switch (id) {
    case GI_VIEW_SHADOW_MAP:
        return f->raster && f->show_direct && f->shadows_rendered && f->shadows.count > 0 && f->shadows.maps[0].depth;
    case GI_VIEW_DIRECT: return f->show_direct;
    case GI_VIEW_VPL_MAP: return f->indirect && f->ind.para && f->ind.vpls.count > 0 && f->ind.atlas_slots > 0;
    case GI_VIEW_VPLS:
    case GI_VIEW_VPL_OVERHEAD:
    case GI_VIEW_SPLIT:
    case GI_VIEW_ACCUMULATED:
    case GI_VIEW_COMBINED:
    case GI_VIEW_FILTERED: return f->indirect;
    default: return (unsigned)id < GI_VIEW_COUNT;
    }
}

/* ------------------------------------------------------------ pixels */

static uint8_t gi__unit(float v)
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

/* Heat colour map for t in [0, 1]: dark blue -> red -> yellow -> white. */
static void gi__heat(float t, uint8_t c[3])
{
    t = pf_clampf(t, 0.0f, 1.0f);
    c[0] = gi__unit(3.0f * t);
    c[1] = gi__unit(3.0f * t - 1.0f);
    c[2] = gi__unit(t < 1.0f / 3.0f ? 0.4f + 0.6f * (1.0f - 3.0f * t) * 0.5f : 3.0f * t - 2.0f);
}


/* VPL k's colour: its luminance relative to the brightest VPL, square-root
 * scaled so that dim VPLs stay visible. */
static void gi__vpl_colour(const gi_vpl_set *set, float max_lum, uint32_t k, uint8_t c[3])
{
    float t = max_lum > 0.0f ? pf_luminance(set->v[k].intensity) / max_lum : 0.0f;
    gi__heat(sqrtf(pf_clampf(t, 0.0f, 1.0f)), c);
}

static float gi__max_lum(const gi_vpl_set *set)
{
    float m = 0.0f;
    for (uint32_t k = 0; k < set->count; k++) m = fmaxf(m, pf_luminance(set->v[k].intensity));
    return m;
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

/* ------------------------------------------------------------ views */

static void gi__view_gbuffer(const gi_frame *f, gi_view_id id, uint8_t *rgb)
{
    const rs_gbuffer *g = &f->gbuf;
    size_t n = (size_t)f->width * f->height;
    float dmax = 0.0f;
    if (id == GI_VIEW_DEPTH)
        for (size_t i = 0; i < n; i++)
            if (isfinite(g->depth[i]) && g->depth[i] > dmax) dmax = g->depth[i];
    pf_vec3 lo = f->scene->bounds_min, ext = pf_v3_sub(f->scene->bounds_max, f->scene->bounds_min);
    for (size_t i = 0; i < n; i++) {
        uint8_t *o = rgb + 3 * i;
        int empty = g->prim[i] == RS_GBUFFER_EMPTY;
        switch (id) {
        case GI_VIEW_DEPTH:
            o[0] = o[1] = o[2] = isfinite(g->depth[i]) && dmax > 0.0f ? gi__unit(1.0f - g->depth[i] / dmax) : 0;
            break;
        case GI_VIEW_POSITION:
            o[0] = empty ? 0 : gi__unit((g->pos_x[i] - lo.x) / ext.x);
            o[1] = empty ? 0 : gi__unit((g->pos_y[i] - lo.y) / ext.y);
            o[2] = empty ? 0 : gi__unit((g->pos_z[i] - lo.z) / ext.z);
            break;
        case GI_VIEW_NORMAL:
            o[0] = empty ? 0 : gi__unit(0.5f + 0.5f * g->nrm_x[i]);
            o[1] = empty ? 0 : gi__unit(0.5f + 0.5f * g->nrm_y[i]);
            o[2] = empty ? 0 : gi__unit(0.5f + 0.5f * g->nrm_z[i]);
            break;
        case GI_VIEW_ALBEDO:
            o[0] = empty ? 0 : gi__unit(pf_linear_to_srgb(g->alb_r[i]));
            o[1] = empty ? 0 : gi__unit(pf_linear_to_srgb(g->alb_g[i]));
            o[2] = empty ? 0 : gi__unit(pf_linear_to_srgb(g->alb_b[i]));
            break;
        default: { /* primitive id: a hash colour per triangle */
            uint32_t hsh = g->prim[i] * 2654435761u;
            o[0] = empty ? 0 : (uint8_t)(hsh & 255);
            o[1] = empty ? 0 : (uint8_t)(hsh >> 8 & 255);
            o[2] = empty ? 0 : (uint8_t)(hsh >> 16 & 255);
        }
        }
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
 * as a 3 x 2 grid (+x -x +y on top, -y +z -z below). */
static void gi__view_shadow_map(const gi_frame *f, uint8_t *rgb)
{
    uint32_t W = f->width, H = f->height;
    memset(rgb, 0, (size_t)W * H * 3);
    const rs_shadow_map *m = &f->shadows.maps[0];
    uint32_t cols = m->face_count == 6 ? 3 : 1, rows = m->face_count == 6 ? 2 : 1;
    uint32_t cell = W / cols < H / rows ? W / cols : H / rows;
    if (cell == 0) return;
    uint32_t ox = (W - cell * cols) / 2, oy = (H - cell * rows) / 2;
    for (uint32_t face = 0; face < m->face_count && face < 6; face++) {
        const float *d = rs_shadow_map_face(m, face);
        size_t texels = (size_t)m->size * m->size;
        float zmax = 0.0f;
        for (size_t i = 0; i < texels; i++) zmax = fmaxf(zmax, d[i]);
        uint32_t cx = ox + (face % cols) * cell, cy = oy + (face / cols) * cell;
        for (uint32_t y = 0; y < cell; y++)
            for (uint32_t x = 0; x < cell; x++) {
                uint32_t tx = (uint32_t)((uint64_t)x * m->size / cell), ty = (uint32_t)((uint64_t)y * m->size / cell);
                float v = zmax > 0.0f ? d[(size_t)ty * m->size + tx] / zmax : 0.0f; /* reversed depth: near = 1 */
                uint8_t *o = rgb + 3 * ((size_t)(cy + y) * W + cx + x);
                o[0] = o[1] = o[2] = gi__unit(v);
            }
        if (m->face_count == 6) gi__box(rgb, W, H, (int)(cx + cell / 2), (int)(cy + cell / 2), (int)cell / 2, 90, 90, 160);
    }
}

/* Projects world point p with the frame's camera; 0 if behind it. */
static int gi__project(const gi_frame *f, const rs_mat4 *vp, pf_vec3 p, int *px, int *py)
{
    float c[4];
    rs_mat4_transform(vp, p, c);
    if (!(c[3] > 0.0f)) return 0;
    float x = (c[0] / c[3] * 0.5f + 0.5f) * (float)f->width, y = (0.5f - c[1] / c[3] * 0.5f) * (float)f->height;
    if (!(fabsf(x) < 1e6f && fabsf(y) < 1e6f)) return 0;
    *px = (int)floorf(x), *py = (int)floorf(y);
    return 1;
}

/* The VPLs as 3x3 points over the final image, coloured by intensity; the
 * chosen VPL in a white box. */
static void gi__view_vpls(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb)
{
    uint32_t W = f->width, H = f->height;
    gi__view_radiance(f, f->final, s->exposure, rgb);
    for (size_t i = 0; i < (size_t)W * H * 3; i++) rgb[i] = (uint8_t)(rgb[i] / 2); /* dim the image under the dots */
    rs_mat4 vp = rs_mat4_camera(&f->camera, W, H);
    const gi_vpl_set *set = &f->ind.vpls;
    float maxl = gi__max_lum(set);
    for (uint32_t k = 0; k < set->count; k++) {
        int px, py;
        if (!gi__project(f, &vp, set->v[k].pos, &px, &py)) continue;
        uint8_t c[3];
        gi__vpl_colour(set, maxl, k, c);
        gi_view_fill_rect(rgb, W, H, px - 1, py - 1, 3, 3, c[0], c[1], c[2]);
    }
    int px, py;
    if (set->count && gi__project(f, &vp, set->v[s->vpl % set->count].pos, &px, &py))
        gi__box(rgb, W, H, px, py, 4, 255, 255, 255);
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
            for (int c = 0; c < 3; c++) p[c] = gi__unit(pf_linear_to_srgb(sf.albedo[c] * shade) * 0.8f);
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

static void gi__view_overhead(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb)
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
    float maxl = gi__max_lum(set);
    for (uint32_t k = 0; k < set->count; k++) {
        int px, py;
        uint8_t c[3];
        gi__overhead_point(&o, set->v[k].pos, &px, &py);
        gi__vpl_colour(set, maxl, k, c);
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
}

/* The chosen VPL's paraboloid map (R x R codes) fitted in the image:
 * near = bright, nothing hit = dark blue, outside the disc = black. */
static void gi__view_vpl_map(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb)
{
    uint32_t W = f->width, H = f->height;
    memset(rgb, 0, (size_t)W * H * 3);
    const gi_indirect *ind = &f->ind;
    uint32_t count = ind->vpls.count < ind->atlas_slots ? ind->vpls.count : ind->atlas_slots;
    uint32_t R = ind->opt.para_res, k = s->vpl % count;
    const uint16_t *map = ind->atlas + (size_t)k * R * R;
    uint32_t side = W < H ? W : H;
    uint32_t ox = (W - side) / 2, oy = (H - side) / 2;
    for (uint32_t y = 0; y < side; y++)
        for (uint32_t x = 0; x < side; x++) {
            uint32_t i = (uint32_t)((uint64_t)x * R / side), j = (uint32_t)((uint64_t)y * R / side);
            uint16_t code = map[(size_t)j * R + i];
            uint8_t *o = rgb + 3 * ((size_t)(oy + y) * W + ox + x);
            if (code == RS_PARA_OUTSIDE) continue;
            if (code == RS_PARA_EMPTY) {
                o[0] = 20, o[1] = 20, o[2] = 80;
                continue;
            }
            float d = rs_para_decode(code, ind->range);
            o[0] = o[1] = o[2] = gi__unit(1.0f - d / ind->range);
        }
    gi__box(rgb, W, H, (int)(ox + side / 2), (int)(oy + side / 2), (int)side / 2, 255, 255, 255);
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
static void gi__view_mosaic(const gi_frame *f, int normals, float exposure, uint8_t *rgb)
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
                o[0] = valid ? gi__unit(0.5f + 0.5f * ind->split_nx[k]) : 0;
                o[1] = valid ? gi__unit(0.5f + 0.5f * ind->split_ny[k]) : 0;
                o[2] = valid ? gi__unit(0.5f + 0.5f * ind->split_nz[k]) : 0;
            } else {
                for (int c = 0; c < 3; c++) o[c] = pf_imageio_display(ind->split_e[3 * k + c], scale);
            }
        }
}

int gi_view_render(const gi_frame *f, gi_view_id id, const gi_view_settings *s_in, uint8_t *rgb)
{
    gi_view_settings s;
    memset(&s, 0, sizeof s);
    if (s_in) s = *s_in;
    uint32_t W = f->width, H = f->height;
    if (!gi_view_available(f, id)) {
        gi__unavailable(rgb, W, H,
                        id == GI_VIEW_SHADOW_MAP ? "no shadow map (ray-traced frame, no lights or --indirect-only)"
                        : id == GI_VIEW_DIRECT   ? "no direct light (--indirect-only)"
                        : id == GI_VIEW_VPL_MAP  ? "no paraboloid maps (--visibility raytrace, no VPLs or --direct-only)"
                                                 : "no indirect light (--direct-only)");
        return 0;
    }
    switch (id) {
    case GI_VIEW_DEPTH:
    case GI_VIEW_POSITION:
    case GI_VIEW_NORMAL:
    case GI_VIEW_ALBEDO:
    case GI_VIEW_PRIM: gi__view_gbuffer(f, id, rgb); break;
    case GI_VIEW_SHADOW_MAP: gi__view_shadow_map(f, rgb); break;
    case GI_VIEW_DIRECT: gi__view_radiance(f, f->direct, s.exposure, rgb); break;
    case GI_VIEW_VPLS: gi__view_vpls(f, &s, rgb); break;
    case GI_VIEW_VPL_OVERHEAD: gi__view_overhead(f, &s, rgb); break;
    case GI_VIEW_VPL_MAP: gi__view_vpl_map(f, &s, rgb); break;
    case GI_VIEW_SPLIT: gi__view_mosaic(f, 1, s.exposure, rgb); break;
    case GI_VIEW_ACCUMULATED: gi__view_mosaic(f, 0, s.exposure, rgb); break;
    case GI_VIEW_COMBINED: gi__view_indirect_image(f, f->ind.combined, s.exposure, rgb); break;
    case GI_VIEW_FILTERED: gi__view_radiance(f, f->ind.filtered, s.exposure, rgb); break;
    default: gi__view_radiance(f, f->final, s.exposure, rgb); break;
    }
    return 1;
}

/* ------------------------------------------------------------ pixels of a view */

static int gi__mosaic_view(gi_view_id id) { return id == GI_VIEW_SPLIT || id == GI_VIEW_ACCUMULATED; }

static int gi__image_layout_view(gi_view_id id)
{
    return id != GI_VIEW_SHADOW_MAP && id != GI_VIEW_VPL_OVERHEAD && id != GI_VIEW_VPL_MAP && !gi__mosaic_view(id) &&
           (unsigned)id < GI_VIEW_COUNT;
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
