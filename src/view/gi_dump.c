/* gi_dump: `--dump-stages DIR` — every stage of a frame as an image, with
 * the one-line captions the stepper of `softgi view` shows, so people
 * without a display can step through a frame; with --dump-format exr or
 * both, also each stage's float data as OpenEXR (gi_dump.h lists the files).
 * The pictures are gi_view's (one implementation for the dump and the
 * viewer); the float files are the frame's own buffers, copied out. */
#include "gi_dump.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_view_draw.h"
#include "pf_imageio.h"

int gi_dump_has_exr(gi_view_id id)
{
    switch (id) {
    case GI_VIEW_DEPTH:
    case GI_VIEW_POSITION:
    case GI_VIEW_NORMAL:
    case GI_VIEW_ALBEDO:
    case GI_VIEW_DIRECT:
    case GI_VIEW_SPLIT:
    case GI_VIEW_ACCUMULATED:
    case GI_VIEW_COMBINED:
    case GI_VIEW_FILTERED:
    case GI_VIEW_FINAL:
    case GI_VIEW_CLAMP: return 1;
    default: return 0;
    }
}

/* ---------------------------------------------------------------- float data */

/* A G-buffer view: three planes and A = 1 where a surface was hit. */
static void gi__dump_planes(const gi_frame *f, const float *x, const float *y, const float *z, float *px)
{
    for (size_t i = 0, n = (size_t)f->width * f->height; i < n; i++) {
        int hit = f->gbuf.prim[i] != RS_GBUFFER_EMPTY;
        px[4 * i + 0] = hit ? x[i] : 0.0f;
        px[4 * i + 1] = hit ? y[i] : 0.0f;
        px[4 * i + 2] = hit ? z[i] : 0.0f;
        px[4 * i + 3] = hit ? 1.0f : 0.0f;
    }
}

/* A split-layout buffer as the picture's mosaic (gi_view_mosaic_index);
 * uncovered pixels 0. normals: RGBA from the split normals, A = valid; else
 * RGB irradiance. */
static void gi__dump_mosaic(const gi_frame *f, int normals, float *px)
{
    const gi_indirect *ind = &f->ind;
    const uint32_t W = f->width, H = f->height, C = normals ? 4 : 3;
    memset(px, 0, (size_t)W * H * C * sizeof(float));
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            size_t k = gi_view_mosaic_index(f, x, y);
            if (k == SIZE_MAX) continue;
            float *o = px + C * ((size_t)y * W + x);
            if (normals) {
                int valid = ind->split_valid[k] != 0;
                o[0] = valid ? ind->split_nx[k] : 0.0f;
                o[1] = valid ? ind->split_ny[k] : 0.0f;
                o[2] = valid ? ind->split_nz[k] : 0.0f;
                o[3] = valid ? 1.0f : 0.0f;
            } else {
                memcpy(o, ind->split_e + 3 * k, 3 * sizeof(float));
            }
        }
}

/* View `id`'s float data into px (room for 4 floats a pixel); returns the
 * channels a pixel (1, 3 or 4). Only for gi_dump_has_exr views. */
static uint32_t gi__dump_float(const gi_frame *f, gi_view_id id, float *px)
{
    const size_t n = (size_t)f->width * f->height;
    const rs_gbuffer *g = &f->gbuf;
    const float *rgb = NULL;
    switch (id) {
    case GI_VIEW_DEPTH: memcpy(px, g->depth, n * sizeof(float)); return 1;
    case GI_VIEW_CLAMP: gi_view_clamp_counts(f, px); return 1;
    case GI_VIEW_POSITION: gi__dump_planes(f, g->pos_x, g->pos_y, g->pos_z, px); return 4;
    case GI_VIEW_NORMAL: gi__dump_planes(f, g->nrm_x, g->nrm_y, g->nrm_z, px); return 4;
    case GI_VIEW_ALBEDO: gi__dump_planes(f, g->alb_r, g->alb_g, g->alb_b, px); return 4;
    case GI_VIEW_SPLIT: gi__dump_mosaic(f, 1, px); return 4;
    case GI_VIEW_ACCUMULATED: gi__dump_mosaic(f, 0, px); return 3;
    case GI_VIEW_DIRECT: rgb = f->direct; break;
    case GI_VIEW_COMBINED:
        /* the indirect image's buffer, each pixel as a scale x scale block */
        for (uint32_t y = 0; y < f->height; y++)
            for (uint32_t x = 0; x < f->width; x++)
                memcpy(px + 3 * ((size_t)y * f->width + x), f->ind.combined + 3 * gi_indirect_pixel(&f->ind, x, y),
                       3 * sizeof(float));
        return 3;
    case GI_VIEW_FILTERED: rgb = f->ind.filtered; break;
    default: rgb = f->final; break;
    }
    memcpy(px, rgb, n * 3 * sizeof(float));
    return 3;
}

static pf_result gi__dump_exr(const gi_frame *f, gi_view_id v, const char *path, float *px, pf_error *err)
{
    char comment[1200], text[1024];
    gi_view_describe_frame(f, v, text, sizeof text);
    snprintf(comment, sizeof comment, "softgi stage %02d-%s: %s", (int)v, gi_view_name(v), text);
    uint32_t channels = gi__dump_float(f, v, px);
    return pf_imageio_write_exr(path, px, f->width, f->height, channels, PF_IMAGEIO_DATA, comment, err);
}

/* ---------------------------------------------------------------- captions */

typedef struct gi__dump_captions {
    const gi_frame *f;
    gi_dump_format format;
    const gi_view_legend *legend; /* per view, GI_VIEW_COUNT (PNG dumps) */
} gi__dump_captions;

/* ranges.txt: "NN-name.png: legend" for every picture with a legend (the
 * value range its colours span, as drawn). */
static int gi__print_ranges(FILE *out, void *user)
{
    const gi__dump_captions *c = user;
    for (int v = 0; v < GI_VIEW_COUNT; v++) {
        gi_view_id id = (gi_view_id)v;
        if (!gi_view_available(c->f, id) || !c->legend[v].present) continue;
        if (fprintf(out, "%02d-%s.png: %s\n", v, gi_view_name(id), c->legend[v].text) < 0) return 1;
    }
    return 0;
}

static int gi__print_captions(FILE *out, void *user)
{
    const gi__dump_captions *c = user;
    char text[1024];
    for (int v = 0; v < GI_VIEW_COUNT; v++) {
        gi_view_id id = (gi_view_id)v;
        if (!gi_view_available(c->f, id)) continue;
        gi_view_describe_frame(c->f, id, text, sizeof text);
        if ((c->format & GI_DUMP_PNG) && fprintf(out, "%02d-%s.png: %s\n", v, gi_view_name(id), text) < 0) return 1;
        if ((c->format & GI_DUMP_EXR) && gi_dump_has_exr(id) &&
            fprintf(out, "%02d-%s.exr: %s\n", v, gi_view_name(id), text) < 0)
            return 1;
    }
    return 0;
}

/* ---------------------------------------------------------------- the dump */

pf_result gi_dump_stages(const gi_frame *f, const char *dir, const gi_view_settings *s, gi_dump_format format,
                         pf_error *err)
{
    const size_t n = (size_t)f->width * f->height;
    uint8_t *rgb8 = (format & GI_DUMP_PNG) ? malloc(n * 3) : NULL;
    float *px = (format & GI_DUMP_EXR) ? malloc(n * 4 * sizeof(float)) : NULL;
    if (((format & GI_DUMP_EXR) && !px) || ((format & GI_DUMP_PNG) && !rgb8)) {
        free(rgb8);
        free(px);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory dumping the stages of a %ux%u frame",
                            f->width, f->height);
    }
    char path[4200];
    pf_result r = PF_OK;
    gi_view_legend legend[GI_VIEW_COUNT];
    memset(legend, 0, sizeof legend);
    for (int v = 0; v < GI_VIEW_COUNT && r == PF_OK; v++) {
        gi_view_id id = (gi_view_id)v;
        if (!gi_view_available(f, id)) continue;
        if (format & GI_DUMP_PNG) {
            gi_view_render_legend(f, id, s, rgb8, &legend[v]);
            snprintf(path, sizeof path, "%s/%02d-%s.png", dir, v, gi_view_name(id));
            r = gi_view_write_png(path, rgb8, f->width, f->height, err);
        }
        if (r == PF_OK && (format & GI_DUMP_EXR) && gi_dump_has_exr(id)) {
            snprintf(path, sizeof path, "%s/%02d-%s.exr", dir, v, gi_view_name(id));
            r = gi__dump_exr(f, id, path, px, err);
        }
    }
    free(rgb8);
    free(px);
    /* captions.txt last: one line per file written */
    gi__dump_captions c = {f, format, legend};
    snprintf(path, sizeof path, "%s/captions.txt", dir);
    if (r == PF_OK) r = pf_imageio_write_text(path, gi__print_captions, &c, err);
    snprintf(path, sizeof path, "%s/ranges.txt", dir);
    if (r == PF_OK && (format & GI_DUMP_PNG)) r = pf_imageio_write_text(path, gi__print_ranges, &c, err);
    return r;
}
