/* gi_dump: `--dump-stages DIR` — every named buffer of a frame as an image,
 * with the one-line captions the stepper shows (gi_buffer_caption), so
 * people without a display can step through a frame. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "pf_imageio.h"

/* A data buffer as linear [0,1] RGB -> PNG without tone mapping: the
 * Reinhard/sRGB display transform is inverted so the PNG shows the value. */
static pf_result gi__write_unit(const char *path, const float *rgb01, uint32_t w, uint32_t h, pf_error *err)
{
    size_t n = (size_t)w * h * 3;
    float *lin = malloc(n * sizeof(float));
    if (!lin) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    for (size_t i = 0; i < n; i++) {
        float v = pf_clampf(rgb01[i], 0.0f, 0.999f);
        float l = pf_srgb_to_linear(v);
        lin[i] = l / (1.0f - l); /* Reinhard inverse: display(l / (1 - l)) = l */
    }
    pf_result r = pf_imageio_write_png(path, lin, w, h, 0.0f, err);
    free(lin);
    return r;
}

/* Rearranges a split-layout buffer (3 floats per texel) as a mosaic: tile
 * (i, j) drawn at (i * w0, j * h0), w0 x h0 being tile 0's size. */
static void gi__mosaic(const gi_indirect *ind, const float *split, float *out, uint32_t W, uint32_t H)
{
    memset(out, 0, sizeof(float) * 3 * (size_t)W * H);
    for (uint32_t j = 0; j < ind->m; j++)
        for (uint32_t i = 0; i < ind->n; i++) {
            uint32_t t = j * ind->n + i;
            for (uint32_t b = 0; b < ind->tile_h[t]; b++)
                for (uint32_t a = 0; a < ind->tile_w[t]; a++) {
                    uint32_t x = i * ind->tile_w[0] + a, y = j * ind->tile_h[0] + b;
                    if (x >= W || y >= H) continue;
                    memcpy(out + 3 * ((size_t)y * W + x), split + 3 * (ind->tile_x0[t] + (size_t)b * ind->tile_w[t] + a),
                           3 * sizeof(float));
                }
        }
}

pf_result gi_frame_dump_stages(const gi_frame *f, const char *dir, pf_error *err)
{
    uint32_t W = f->width, H = f->height;
    size_t n = (size_t)W * H;
    float *img = malloc(n * 3 * sizeof(float));
    if (!img) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    char path[4096];
    snprintf(path, sizeof path, "%s/captions.txt", dir);
    pf_result r = pf_imageio_make_parent_dirs(path, err);
    FILE *cap = r == PF_OK ? fopen(path, "w") : NULL;
    if (r == PF_OK && !cap) r = pf_error_set(err, PF_ERR_IO, "%s: cannot write", path);
    const rs_gbuffer *g = &f->gbuf;
    float dmax = 0.0f;
    for (size_t i = 0; i < n; i++)
        if (isfinite(g->depth[i]) && g->depth[i] > dmax) dmax = g->depth[i];
    pf_vec3 lo = f->scene->bounds_min, ext = pf_v3_sub(f->scene->bounds_max, f->scene->bounds_min);
    for (int b = 0; b < GI_BUF_COUNT && r == PF_OK; b++) {
        int unit = 1;
        const float *src = NULL;
        switch (b) {
        case GI_BUF_DEPTH:
            for (size_t i = 0; i < n; i++)
                img[3 * i] = img[3 * i + 1] = img[3 * i + 2] = isfinite(g->depth[i]) ? 1.0f - g->depth[i] / dmax : 0.0f;
            break;
        case GI_BUF_POSITION:
            for (size_t i = 0; i < n; i++) {
                img[3 * i] = (g->pos_x[i] - lo.x) / ext.x;
                img[3 * i + 1] = (g->pos_y[i] - lo.y) / ext.y;
                img[3 * i + 2] = (g->pos_z[i] - lo.z) / ext.z;
            }
            break;
        case GI_BUF_NORMAL:
            for (size_t i = 0; i < n; i++) {
                img[3 * i] = 0.5f + 0.5f * g->nrm_x[i];
                img[3 * i + 1] = 0.5f + 0.5f * g->nrm_y[i];
                img[3 * i + 2] = 0.5f + 0.5f * g->nrm_z[i];
            }
            break;
        case GI_BUF_ALBEDO:
            for (size_t i = 0; i < n; i++) {
                img[3 * i] = pf_linear_to_srgb(g->alb_r[i]);
                img[3 * i + 1] = pf_linear_to_srgb(g->alb_g[i]);
                img[3 * i + 2] = pf_linear_to_srgb(g->alb_b[i]);
            }
            break;
        case GI_BUF_PRIM:
            for (size_t i = 0; i < n; i++) {
                uint32_t h = g->prim[i] * 2654435761u;
                img[3 * i] = g->prim[i] == RS_GBUFFER_EMPTY ? 0.0f : (float)(h & 255) / 255.0f;
                img[3 * i + 1] = g->prim[i] == RS_GBUFFER_EMPTY ? 0.0f : (float)(h >> 8 & 255) / 255.0f;
                img[3 * i + 2] = g->prim[i] == RS_GBUFFER_EMPTY ? 0.0f : (float)(h >> 16 & 255) / 255.0f;
            }
            break;
        case GI_BUF_DIRECT: unit = 0, src = f->direct; break;
        case GI_BUF_VPLS: {
            if (!f->indirect) continue;
            unit = 0;
            memcpy(img, f->final, n * 3 * sizeof(float));
            rs_mat4 vp = rs_mat4_camera(&f->camera, W, H);
            float maxl = 0.0f;
            for (uint32_t k = 0; k < f->ind.vpls.count; k++) maxl = fmaxf(maxl, pf_v3_max_comp(f->ind.vpls.v[k].intensity));
            for (uint32_t k = 0; k < f->ind.vpls.count; k++) {
                const gi_vpl *v = &f->ind.vpls.v[k];
                float c[4];
                rs_mat4_transform(&vp, v->pos, c);
                if (!(c[3] > 0.0f)) continue;
                int px = (int)((c[0] / c[3] * 0.5f + 0.5f) * W), py = (int)((0.5f - c[1] / c[3] * 0.5f) * H);
                float t = pf_v3_max_comp(v->intensity) / (maxl > 0 ? maxl : 1);
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++) {
                        int x = px + dx, y = py + dy;
                        if (x < 0 || y < 0 || x >= (int)W || y >= (int)H) continue;
                        float *o = img + 3 * ((size_t)y * W + (size_t)x);
                        o[0] = 50.0f * t + 0.5f, o[1] = 20.0f * t, o[2] = 50.0f * (1.0f - t); /* hot = bright */
                    }
            }
            break;
        }
        case GI_BUF_SPLIT: {
            if (!f->indirect) continue;
            float *tmp = malloc(n * 3 * sizeof(float));
            if (!tmp) continue;
            for (size_t i = 0; i < n; i++) {
                tmp[3 * i] = 0.5f + 0.5f * f->ind.split_nx[i];
                tmp[3 * i + 1] = 0.5f + 0.5f * f->ind.split_ny[i];
                tmp[3 * i + 2] = 0.5f + 0.5f * f->ind.split_nz[i];
            }
            gi__mosaic(&f->ind, tmp, img, W, H);
            free(tmp);
            break;
        }
        case GI_BUF_ACCUMULATED:
            if (!f->indirect) continue;
            unit = 0;
            gi__mosaic(&f->ind, f->ind.split_e, img, W, H);
            break;
        case GI_BUF_COMBINED:
            if (!f->indirect) continue;
            unit = 0, src = f->ind.combined;
            break;
        case GI_BUF_FILTERED:
            if (!f->indirect) continue;
            unit = 0, src = f->ind.filtered;
            break;
        default: unit = 0, src = f->final; break;
        }
        snprintf(path, sizeof path, "%s/%02d-%s.png", dir, b, gi_buffer_name((gi_buffer_id)b));
        if (unit) r = gi__write_unit(path, img, W, H, err);
        else r = pf_imageio_write_png(path, src ? src : img, W, H, 0.0f, err);
        fprintf(cap, "%02d-%s.png: %s\n", b, gi_buffer_name((gi_buffer_id)b), gi_buffer_caption((gi_buffer_id)b));
    }
    if (cap && fclose(cap) != 0 && r == PF_OK) r = pf_error_set(err, PF_ERR_IO, "%s/captions.txt: write failed", dir);
    free(img);
    return r;
}
