/* pf_imageio: PNG/PFM output, PFM input and the output hash (pf_imageio.h). */
#include "pf_imageio.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <stb_image_write.h>

#include "pf_scene.h" /* pf_linear_to_srgb */

uint8_t pf_imageio_display(float linear, float exposure_scale)
{
    float x = linear * exposure_scale;
    if (!(x > 0.0f)) return 0; /* also maps NaN to black */
    float tm = x / (1.0f + x);  /* Reinhard 2002, Eq. 3, per channel */
    if (!(tm < 1.0f)) tm = 1.0f; /* x = inf */
    float s = pf_linear_to_srgb(tm) * 255.0f + 0.5f;
    return (uint8_t)(s >= 255.0f ? 255 : (int)s);
}

pf_result pf_imageio_make_parent_dirs(const char *path, pf_error *err)
{
    char buf[4096];
    size_t n = strlen(path);
    if (n >= sizeof buf) return pf_error_set(err, PF_ERR_IO, "%s: path too long", path);
    memcpy(buf, path, n + 1);
    for (char *p = buf + 1; *p; p++) {
        if (*p != '/') continue;
        *p = 0;
        if (mkdir(buf, 0777) != 0 && errno != EEXIST)
            return pf_error_set(err, PF_ERR_IO, "%s: cannot create directory: %s", buf, strerror(errno));
        *p = '/';
    }
    return PF_OK;
}

pf_result pf_imageio_write_png(const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure,
                               pf_error *err)
{
    pf_result r = pf_imageio_make_parent_dirs(path, err);
    if (r != PF_OK) return r;
    uint8_t *px = malloc((size_t)w * h * 3);
    if (!px) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory writing %s", path);
    float scale = exp2f(exposure);
    for (size_t i = 0; i < (size_t)w * h * 3; i++) px[i] = pf_imageio_display(rgb[i], scale);
    int ok = stbi_write_png(path, (int)w, (int)h, 3, px, (int)(w * 3));
    free(px);
    if (!ok) return pf_error_set(err, PF_ERR_IO, "%s: cannot write PNG", path);
    return PF_OK;
}

pf_result pf_imageio_write_pfm(const char *path, const float *rgb, uint32_t w, uint32_t h, pf_error *err)
{
    pf_result r = pf_imageio_make_parent_dirs(path, err);
    if (r != PF_OK) return r;
    FILE *f = fopen(path, "wb");
    if (!f) return pf_error_set(err, PF_ERR_IO, "%s: cannot open for writing: %s", path, strerror(errno));
    /* Scale -1: little-endian floats. PFM stores the bottom row first. */
    int ok = fprintf(f, "PF\n%u %u\n-1.0\n", w, h) > 0;
    for (uint32_t y = h; ok && y-- > 0;) ok = fwrite(rgb + (size_t)y * w * 3, sizeof(float) * 3, w, f) == w;
    ok = (fclose(f) == 0) && ok;
    if (!ok) return pf_error_set(err, PF_ERR_IO, "%s: write failed", path);
    return PF_OK;
}

pf_result pf_imageio_read_pfm(const char *path, float **out, uint32_t *w_out, uint32_t *h_out, pf_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return pf_error_set(err, PF_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    char magic[3] = {0};
    unsigned w = 0, h = 0;
    double scale = 0.0;
    if (fscanf(f, "%2s %u %u %lf", magic, &w, &h, &scale) != 4 || strcmp(magic, "PF") != 0 || w == 0 || h == 0 ||
        w > 65536 || h > 65536 || scale == 0.0 || fgetc(f) == EOF) {
        fclose(f);
        return pf_error_set(err, PF_ERR_PARSE, "%s: not a 3-channel PFM file", path);
    }
    size_t n = (size_t)w * h * 3;
    float *rgb = malloc(n * sizeof(float));
    if (!rgb) {
        fclose(f);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    int ok = 1;
    for (uint32_t y = h; ok && y-- > 0;) ok = fread(rgb + (size_t)y * w * 3, sizeof(float) * 3, w, f) == w;
    fclose(f);
    if (!ok) {
        free(rgb);
        return pf_error_set(err, PF_ERR_PARSE, "%s: truncated PFM data", path);
    }
    if (scale > 0.0) /* big-endian file */
        for (size_t i = 0; i < n; i++) {
            uint32_t b;
            memcpy(&b, &rgb[i], 4);
            b = __builtin_bswap32(b);
            memcpy(&rgb[i], &b, 4);
        }
    *out = rgb;
    *w_out = w;
    *h_out = h;
    return PF_OK;
}

uint64_t pf_imageio_hash(const float *data, uint64_t count)
{
    uint64_t hsh = 0xcbf29ce484222325ull; /* FNV-1a 64 offset basis */
    const uint8_t *b = (const uint8_t *)data;
    for (uint64_t i = 0; i < count * sizeof(float); i++) {
        hsh ^= b[i];
        hsh *= 0x100000001b3ull;
    }
    return hsh;
}
