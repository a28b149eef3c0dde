/* gi_view_learn: the views of "the frame taken apart"
 * (gi_view.h lists them): the VPL overlays that test each VPL against what
 * the camera sees (an Embree ray from the eye) and colour it by intensity,
 * by light bounce or by "moved this frame"; every VPL's paraboloid map as an
 * atlas; the tile assignment (Laine 2007 Sec. 5.1: which VPLs each
 * interleaved tile shades with); the clamp mask of the bounded geometry
 * term (survey Sec. 5); and the VPL method's own view, drawn by the method
 * through gi_vpl_view_ctx (gi_vpl.h). Each view names the stage it shows in
 * gi_view.c's table; each has a legend (gi_view_legend).
 *
 * Determinism: the pictures depend on the frame alone. Rays go through
 * pf_rt in fixed 8-wide packets (the same bits alone or batched), the clamp
 * mask is one job item per row writing only that row, and every drawing is
 * serial in VPL order. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_probe.h"
#include "gi_view_draw.h"
#include "pf_imageio.h"

/* ------------------------------------------------------------ camera */

int gi_view_draw_project(const gi_frame *f, pf_vec3 p, float *x, float *y)
{
    rs_mat4 vp = rs_mat4_camera(&f->camera, f->width, f->height);
    float c[4];
    rs_mat4_transform(&vp, p, c);
    if (!(c[3] > 0.0f)) return 0;
    float px = (c[0] / c[3] * 0.5f + 0.5f) * (float)f->width, py = (0.5f - c[1] / c[3] * 0.5f) * (float)f->height;
    if (!(fabsf(px) < 1e6f && fabsf(py) < 1e6f)) return 0;
    *x = px, *y = py;
    return 1;
}

void gi_view_draw_visible(const gi_frame *f, const pf_vec3 *p, uint32_t count, uint8_t *visible)
{
    enum { CHUNK = 256 };
    pf_ray rays[CHUNK];
    uint8_t occ[CHUNK];
    for (uint32_t k0 = 0; k0 < count; k0 += CHUNK) {
        uint32_t n = count - k0 < CHUNK ? count - k0 : CHUNK;
        for (uint32_t k = 0; k < n; k++) {
            /* from the eye to 0.999 of the way: the point itself sits just
             * off its surface, so only what lies in front of it occludes */
            rays[k] = (pf_ray){f->camera.eye, 0.0f, pf_v3_sub(p[k0 + k], f->camera.eye), 0.999f};
        }
        pf_rt_occluded(f->rt, rays, occ, n);
        for (uint32_t k = 0; k < n; k++) visible[k0 + k] = !occ[k];
    }
}

/* Per VPL of the frame's set: its pixel (x, y) and whether the camera sees
 * it (in the image, not behind anything, and not an empty slot). */
typedef struct gi__seen {
    uint32_t count, shown, hidden;
    int *x, *y;
    uint8_t *visible;
} gi__seen;

static int gi__seen_make(const gi_frame *f, gi__seen *s)
{
    const gi_vpl_set *set = &f->ind.vpls;
    memset(s, 0, sizeof *s);
    s->count = set->count;
    size_t n = set->count ? set->count : 1;
    s->x = malloc(n * sizeof *s->x), s->y = malloc(n * sizeof *s->y);
    s->visible = malloc(n);
    pf_vec3 *p = malloc(n * sizeof *p);
    if (!s->x || !s->y || !s->visible || !p) {
        free(p);
        return 0;
    }
    for (uint32_t k = 0; k < set->count; k++) p[k] = set->v[k].pos;
    gi_view_draw_visible(f, p, set->count, s->visible);
    free(p);
    for (uint32_t k = 0; k < set->count; k++) {
        float fx, fy;
        int in = pf_luminance(set->v[k].intensity) > 0.0f && gi_view_draw_project(f, set->v[k].pos, &fx, &fy);
        if (in) {
            s->x[k] = (int)floorf(fx), s->y[k] = (int)floorf(fy);
            in = s->x[k] >= 0 && s->y[k] >= 0 && s->x[k] < (int)f->width && s->y[k] < (int)f->height;
        }
        if (!in) {
            s->visible[k] = 0;
            continue;
        }
        s->shown += s->visible[k] != 0;
        s->hidden += s->visible[k] == 0;
    }
    return 1;
}

static void gi__seen_free(gi__seen *s)
{
    free(s->x), free(s->y), free(s->visible);
}

/* ------------------------------------------------------------ VPL overlays */

static const uint8_t gi__white[3] = {255, 255, 255};
static const uint8_t gi__unknown[3] = {150, 150, 150};

/* The bounce colours: 1 .. 4 (4: 4 and more), then "unknown". */
static void gi__bounce_colour(uint32_t b, uint8_t c[3])
{
    static const uint8_t col[4][3] = {{255, 210, 40}, {255, 90, 40}, {200, 40, 220}, {60, 140, 255}};
    if (b == 0) memcpy(c, gi__unknown, 3);
    else memcpy(c, col[(b > 4 ? 4 : b) - 1], 3);
}

static int gi__view_overlay(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb,
                            gi_view_legend *lg)
{
    const uint32_t W = f->width, H = f->height;
    const gi_vpl_set *set = &f->ind.vpls;
    const gi_vpl_method *m = gi_view_method(f);
    const uint32_t B = f->ind.opt.bounces ? f->ind.opt.bounces : 3;
    gi_view_draw_dim_final(f, s->exposure, rgb);
    gi__seen seen;
    if (!gi__seen_make(f, &seen)) {
        gi__seen_free(&seen);
        return 0;
    }
    float lo, hi;
    gi_view_vpl_range(set, &lo, &hi);
    uint32_t moved = 0, kept = 0, per_bounce[5] = {0};
    for (uint32_t k = 0; k < set->count; k++) {
        if (!seen.visible[k]) continue;
        const gi_vpl *v = &set->v[k];
        uint8_t c[3];
        if (id == GI_VIEW_VPL_BOUNCE) {
            uint32_t b = m->bounce ? m->bounce(f->ind.method_state, v, B) : 0;
            gi__bounce_colour(b, c);
            per_bounce[b > 4 ? 4 : b]++;
        } else if (id == GI_VIEW_VPL_MOVED) {
            static const uint8_t mv[3] = {60, 240, 60}, kp[3] = {70, 110, 255};
            memcpy(c, v->moved ? mv : kp, 3);
            moved += v->moved != 0, kept += v->moved == 0;
        } else {
            gi_view_vpl_colour(pf_luminance(v->intensity), lo, hi, c);
        }
        gi_view_fill_rect(rgb, W, H, seen.x[k] - 1, seen.y[k] - 1, 3, 3, c[0], c[1], c[2]);
    }
    if (set->count) {
        uint32_t k = s->vpl % set->count;
        if (seen.visible[k]) gi_view_draw_box(rgb, W, H, seen.x[k], seen.y[k], 4, gi__white);
    }
    char t0[48], t1[48], t2[48], t3[48], t4[48], t5[48];
    if (id == GI_VIEW_VPL_BOUNCE) {
        snprintf(t0, sizeof t0, "bounce 1: %u", per_bounce[1]);
        snprintf(t1, sizeof t1, "bounce 2: %u", per_bounce[2]);
        snprintf(t2, sizeof t2, "bounce 3: %u", per_bounce[3]);
        snprintf(t3, sizeof t3, "bounce 4+: %u", per_bounce[4]);
        snprintf(t4, sizeof t4, "unknown: %u", per_bounce[0]);
        const char *names[5] = {t0, t1, t2, t3, t4};
        uint8_t cols[5][3];
        for (uint32_t b = 0; b < 5; b++) gi__bounce_colour(b < 4 ? b + 1 : 0, cols[b]);
        snprintf(t5, sizeof t5, "VPLs: %u seen, %u hidden", seen.shown, seen.hidden);
        gi_view_draw_legend_key(rgb, W, H, lg, t5, names, (const uint8_t(*)[3])cols, 5);
    } else if (id == GI_VIEW_VPL_MOVED) {
        snprintf(t0, sizeof t0, "moved or new: %u", moved);
        snprintf(t1, sizeof t1, "kept: %u", kept);
        const char *names[2] = {t0, t1};
        const uint8_t cols[2][3] = {{60, 240, 60}, {70, 110, 255}};
        snprintf(t5, sizeof t5, "VPLs: %u seen, %u hidden", seen.shown, seen.hidden);
        gi_view_draw_legend_key(rgb, W, H, lg, t5, names, cols, 2);
    } else {
        snprintf(t5, sizeof t5, "VPL luminance, %u seen, %u hidden", seen.shown, seen.hidden);
        gi_view_draw_legend_bar(rgb, W, H, lg, t5, lo, hi, gi_view_bar_heat_sqrt, NULL);
    }
    gi__seen_free(&seen);
    return 1;
}

/* ------------------------------------------------------------ atlas */

/* Every VPL's map in a grid of cols x rows cells, row by row in VPL order. */
static int gi__view_atlas(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb, gi_view_legend *lg)
{
    const uint32_t W = f->width, H = f->height;
    const gi_indirect *ind = &f->ind;
    memset(rgb, 0, (size_t)W * H * 3);
    uint32_t count = ind->vpls.count < ind->atlas_slots ? ind->vpls.count : ind->atlas_slots;
    const uint32_t R = ind->opt.para_res;
    if (!count || !R) return 0;
    /* the most columns whose square cells still fit every map */
    uint32_t cols = 1, cell = 0;
    for (uint32_t c = 1; c <= count; c++) {
        uint32_t rows = (count + c - 1) / c, side = W / c < H / rows ? W / c : H / rows;
        if (side > cell) cell = side, cols = c;
    }
    if (cell < 2) return 0;
    uint32_t rows = (count + cols - 1) / cols;
    uint32_t ox = (W - cols * cell) / 2, oy = (H - rows * cell) / 2;
    float lo = INFINITY, hi = -INFINITY;
    for (uint32_t k = 0; k < count; k++) {
        float a, b;
        gi_view_para_range(ind->atlas + (size_t)k * R * R, R, ind->range, &a, &b);
        if (a < b || a > 0.0f) lo = fminf(lo, a), hi = fmaxf(hi, b);
    }
    if (!(lo <= hi)) lo = hi = 0.0f;
    uint32_t inner = cell > 4 ? cell - 2 : cell; /* one pixel of frame on each side */
    for (uint32_t k = 0; k < count; k++) {
        const uint16_t *map = ind->atlas + (size_t)k * R * R;
        uint32_t cx = ox + (k % cols) * cell, cy = oy + (k / cols) * cell, o = (cell - inner) / 2;
        for (uint32_t y = 0; y < inner; y++)
            for (uint32_t x = 0; x < inner; x++) {
                uint32_t i = (uint32_t)((uint64_t)x * R / inner), j = (uint32_t)((uint64_t)y * R / inner);
                gi_view_para_texel(map[(size_t)j * R + i], ind->range, lo, hi,
                                   rgb + 3 * ((size_t)(cy + o + y) * W + cx + o + x));
            }
        if (ind->vpls.v[k].moved && cell > 4) {
            static const uint8_t green[3] = {60, 240, 60};
            int l = (int)cx, t = (int)cy, r = (int)(cx + cell - 1), b = (int)(cy + cell - 1);
            gi_view_draw_line(rgb, W, H, l, t, r, t, green);
            gi_view_draw_line(rgb, W, H, l, b, r, b, green);
            gi_view_draw_line(rgb, W, H, l, t, l, b, green);
            gi_view_draw_line(rgb, W, H, r, t, r, b, green);
        }
    }
    uint32_t k = s->vpl % count;
    gi_view_draw_box(rgb, W, H, (int)(ox + (k % cols) * cell + cell / 2), (int)(oy + (k / cols) * cell + cell / 2),
                     (int)cell / 2, gi__white);
    char what[64];
    snprintf(what, sizeof what, "%u maps, distance", count);
    gi_view_draw_legend_bar(rgb, W, H, lg, what, lo, hi, gi_view_bar_grey_rev, NULL);
    return 1;
}

/* ------------------------------------------------------------ tiles */

/* The split mosaic (tile (i, j) at (i w0, j h0), gi_view.c) of the
 * accumulated irradiance, dimmed, with each tile's VPLs drawn where the
 * camera sees them inside that tile's sub-sampled image: tile t shades
 * with group gi_indirect_tile_group(t) of the assignment. */
static int gi__view_tiles(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb, gi_view_legend *lg)
{
    const uint32_t W = f->width, H = f->height;
    const gi_indirect *ind = &f->ind;
    const uint32_t T = ind->n * ind->m;
    float scale = exp2f(s->exposure);
    memset(rgb, 0, (size_t)W * H * 3);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            size_t k = gi_view_mosaic_index(f, x, y);
            if (k == SIZE_MAX) continue;
            uint8_t *o = rgb + 3 * ((size_t)y * W + x);
            for (int c = 0; c < 3; c++) o[c] = (uint8_t)(pf_imageio_display(ind->split_e[3 * k + c], scale) / 3);
        }
    gi__seen seen;
    if (!gi__seen_make(f, &seen)) {
        gi__seen_free(&seen);
        return 0;
    }
    float lo, hi;
    gi_view_vpl_range(&ind->vpls, &lo, &hi);
    uint32_t cmin = UINT32_MAX, cmax = 0;
    const uint32_t w0 = ind->tile_w[0], h0 = ind->tile_h[0], sc = ind->scale ? ind->scale : 1;
    const uint32_t chosen = ind->vpls.count ? s->vpl % ind->vpls.count : UINT32_MAX;
    for (uint32_t t = 0; t < T; t++) {
        uint32_t i = t % ind->n, j = t / ind->n, grp = gi_indirect_tile_group(ind, t);
        uint32_t a0 = ind->assign_start[grp], a1 = ind->assign_start[grp + 1];
        cmin = a1 - a0 < cmin ? a1 - a0 : cmin, cmax = a1 - a0 > cmax ? a1 - a0 : cmax;
        int tx = (int)(i * w0), ty = (int)(j * h0), tw = (int)ind->tile_w[t], th = (int)ind->tile_h[t];
        uint8_t pc[3];
        gi_view_draw_palette(t, pc);
        if (tw > 2 && th > 2) { /* the tile's outline */
            gi_view_draw_line(rgb, W, H, tx, ty, tx + tw - 1, ty, pc);
            gi_view_draw_line(rgb, W, H, tx, ty, tx, ty + th - 1, pc);
        }
        int dot = tw >= 24 && th >= 24 ? 3 : 1;
        for (uint32_t q = a0; q < a1; q++) {
            uint32_t k = ind->assign[q];
            if (k >= seen.count || !seen.visible[k]) continue;
            /* frame pixel -> indirect pixel -> this tile's texel */
            int u = tx + (int)((uint32_t)seen.x[k] / sc / ind->n), v = ty + (int)((uint32_t)seen.y[k] / sc / ind->m);
            uint8_t c[3];
            gi_view_vpl_colour(pf_luminance(ind->vpls.v[k].intensity), lo, hi, c);
            gi_view_fill_rect(rgb, W, H, u - dot / 2, v - dot / 2, dot, dot, c[0], c[1], c[2]);
            if (k == chosen) gi_view_draw_box(rgb, W, H, u, v, 3, gi__white);
        }
        if (tw >= 4 * GI_FONT_CELL_W && th >= 2 * GI_FONT_CELL_H) {
            char label[24];
            snprintf(label, sizeof label, "%u", a1 - a0);
            gi_view_text(rgb, W, H, tx + 2, ty + 1, 1, label, pc[0], pc[1], pc[2]);
        }
    }
    if (cmin == UINT32_MAX) cmin = 0;
    char what[96];
    snprintf(what, sizeof what, "VPL luminance (%u .. %u a tile)", cmin, cmax);
    gi_view_draw_legend_bar(rgb, W, H, lg, what, lo, hi, gi_view_bar_heat_sqrt, NULL);
    gi__seen_free(&seen);
    return 1;
}

/* ------------------------------------------------------------ clamp mask */

typedef struct gi__clamp_ctx {
    const gi_frame *f;
    float *count;
} gi__clamp_ctx;

static void gi__clamp_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__clamp_ctx *c = p;
    gi_probe pr;
    for (uint32_t x = 0; x < c->f->width; x++) {
        gi_probe_pixel(&pr, c->f, x, y); /* the accumulation's own test, VPL by VPL */
        c->count[(size_t)y * c->f->width + x] = (float)pr.clamped;
    }
}

void gi_view_clamp_counts(const gi_frame *f, float *count)
{
    gi__clamp_ctx c = {f, count};
    pf_jobs_parallel_for(f->jobs, gi__clamp_row, &c, f->height, 1);
}

static int gi__view_clamp(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb, gi_view_legend *lg)
{
    const uint32_t W = f->width, H = f->height;
    const size_t n = (size_t)W * H;
    float *count = malloc(n * sizeof *count);
    if (!count) return 0;
    gi_view_clamp_counts(f, count);
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) lo = fminf(lo, count[i]), hi = fmaxf(hi, count[i]);
    /* the final image in grey, dimmed; clamped pixels in heat colours */
    float e = exp2f(s->exposure);
    for (size_t i = 0; i < n; i++) {
        uint8_t *o = rgb + 3 * i;
        if (count[i] > 0.0f) {
            gi_view_draw_heat(hi > lo ? 0.25f + 0.75f * (count[i] - lo) / (hi - lo) : 1.0f, o);
            continue;
        }
        const float *c = f->final + 3 * i;
        o[0] = o[1] = o[2] = (uint8_t)(pf_imageio_display(pf_luminance(pf_v3(c[0], c[1], c[2])), e) / 3);
    }
    char what[96];
    if (isfinite(f->ind.b))
        snprintf(what, sizeof what, "clamped VPLs per pixel (b = %.3g)", (double)f->ind.b);
    else
        snprintf(what, sizeof what, "clamped VPLs per pixel (--clamp 0: none)");
    gi_view_draw_legend_bar(rgb, W, H, lg, what, lo, hi, gi_view_bar_heat, NULL);
    free(count);
    return 1;
}

/* ------------------------------------------------------------ the method's view */

typedef struct gi__canvas {
    const gi_frame *f;
    float exposure;
    gi_view_legend *lg;
} gi__canvas;

static void gi__c_background(const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    const gi__canvas *cv = c->canvas;
    gi_view_draw_dim_final(cv->f, cv->exposure, rgb);
}

static int gi__c_project(const gi_vpl_view_ctx *c, pf_vec3 p, float *x, float *y)
{
    const gi__canvas *cv = c->canvas;
    return gi_view_draw_project(cv->f, p, x, y);
}

static int gi__c_visible(const gi_vpl_view_ctx *c, pf_vec3 p)
{
    const gi__canvas *cv = c->canvas;
    uint8_t v;
    gi_view_draw_visible(cv->f, &p, 1, &v);
    return v;
}

static void gi__c_fill(const gi_vpl_view_ctx *c, uint8_t *rgb, int x, int y, int w, int h, const uint8_t col[3])
{
    gi_view_fill_rect(rgb, c->width, c->height, x, y, w, h, col[0], col[1], col[2]);
}

static void gi__c_line(const gi_vpl_view_ctx *c, uint8_t *rgb, int x0, int y0, int x1, int y1, const uint8_t col[3])
{
    gi_view_draw_line(rgb, c->width, c->height, x0, y0, x1, y1, col);
}

static int gi__c_text(const gi_vpl_view_ctx *c, uint8_t *rgb, int x, int y, const char *s, const uint8_t col[3])
{
    return gi_view_text(rgb, c->width, c->height, x, y, 1, s, col[0], col[1], col[2]);
}

static void gi__c_legend(const gi_vpl_view_ctx *c, uint8_t *rgb, const char *what, float lo, float hi,
                         int sqrt_scale)
{
    const gi__canvas *cv = c->canvas;
    gi_view_draw_legend_bar(rgb, c->width, c->height, cv->lg, what, lo, hi,
                            sqrt_scale ? gi_view_bar_heat_sqrt : gi_view_bar_heat, NULL);
}

static void gi__c_key(const gi_vpl_view_ctx *c, uint8_t *rgb, const char *what, const char *const *names,
                      const uint8_t (*colours)[3], uint32_t n)
{
    const gi__canvas *cv = c->canvas;
    gi_view_draw_legend_key(rgb, c->width, c->height, cv->lg, what, names, colours, n);
}

static int gi__view_method(const gi_frame *f, const gi_view_settings *s, uint8_t *rgb, gi_view_legend *lg)
{
    const gi_vpl_method *m = gi_view_method(f);
    gi_view_legend tmp;
    gi__canvas cv = {f, s->exposure, lg ? lg : &tmp};
    memset(cv.lg, 0, sizeof *cv.lg);
    gi_vpl_view_ctx c;
    memset(&c, 0, sizeof c);
    c.scene = f->scene;
    c.rt = f->rt;
    c.camera = &f->camera;
    c.width = f->width, c.height = f->height;
    c.vpls = &f->ind.vpls;
    c.vpl = f->ind.vpls.count ? s->vpl % f->ind.vpls.count : 0;
    c.bounces = f->ind.opt.bounces ? f->ind.opt.bounces : 3;
    c.canvas = &cv;
    c.background = gi__c_background;
    c.project = gi__c_project;
    c.visible = gi__c_visible;
    c.fill = gi__c_fill;
    c.line = gi__c_line;
    c.text = gi__c_text;
    c.heat = gi_view_draw_heat;
    c.palette = gi_view_draw_palette;
    c.legend = gi__c_legend;
    c.key = gi__c_key;
    memset(rgb, 0, (size_t)f->width * f->height * 3);
    if (m->view && f->ind.method_state && m->view(f->ind.method_state, &c, rgb)) return 1;
    memset(rgb, 0, (size_t)f->width * f->height * 3);
    const char *msg = "the method has nothing to show for this frame";
    int tw = (int)strlen(msg) * GI_FONT_CELL_W;
    gi_view_text(rgb, f->width, f->height, ((int)f->width - tw) / 2, (int)f->height / 2, 1, msg, 200, 200, 200);
    return 0;
}

/* ------------------------------------------------------------ dispatch */

int gi_view_learn_render(const gi_frame *f, gi_view_id id, const gi_view_settings *s, uint8_t *rgb,
                         gi_view_legend *lg)
{
    switch (id) {
    case GI_VIEW_VPLS:
    case GI_VIEW_VPL_BOUNCE:
    case GI_VIEW_VPL_MOVED: return gi__view_overlay(f, id, s, rgb, lg);
    case GI_VIEW_VPL_ATLAS: return gi__view_atlas(f, s, rgb, lg);
    case GI_VIEW_TILES: return gi__view_tiles(f, s, rgb, lg);
    case GI_VIEW_CLAMP: return gi__view_clamp(f, s, rgb, lg);
    case GI_VIEW_METHOD: return gi__view_method(f, s, rgb, lg);
    default: memset(rgb, 0, (size_t)f->width * f->height * 3); return 0;
    }
}
