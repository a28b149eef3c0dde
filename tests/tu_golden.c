/* tu_golden: golden hashes with a reference picture beside them
 * (tu_golden.h). */
#include "tu_golden.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>

#include "pf_decode.h"
#include "pf_imageio.h"

#ifndef SOFTGI_GOLDEN_DIR
#error "SOFTGI_GOLDEN_DIR (tests/data/golden) must be defined by the build"
#endif
#ifndef SOFTGI_GOLDEN_FAILURES
#error "SOFTGI_GOLDEN_FAILURES (the build folder's golden-failures/) must be defined by the build"
#endif

void tu_golden_picture_init(tu_golden_picture *p, uint32_t w, uint32_t h)
{
    p->w = w;
    p->h = h;
    p->rgb = calloc((size_t)w * h * 3, 1);
    assert_non_null(p->rgb);
}

void tu_golden_picture_free(tu_golden_picture *p)
{
    free(p->rgb);
    memset(p, 0, sizeof *p);
}

/* The picture's pixel for panel pixel (x, y) at (x0, y0); NULL outside. */
static uint8_t *tu__px(tu_golden_picture *p, uint32_t x0, uint32_t y0, uint32_t x, uint32_t y)
{
    if (x0 + x >= p->w || y0 + y >= p->h) return NULL;
    return p->rgb + 3 * ((size_t)(y0 + y) * p->w + x0 + x);
}

void tu_golden_put_rgb8(tu_golden_picture *p, uint32_t x0, uint32_t y0, const uint8_t *rgb, uint32_t w, uint32_t h)
{
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *o = tu__px(p, x0, y0, x, y);
            if (o) memcpy(o, rgb + 3 * ((size_t)y * w + x), 3);
        }
}

void tu_golden_put_linear(tu_golden_picture *p, uint32_t x0, uint32_t y0, const float *rgb, uint32_t w, uint32_t h,
                          float exposure)
{
    float scale = exp2f(exposure);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *o = tu__px(p, x0, y0, x, y);
            if (!o) continue;
            for (int c = 0; c < 3; c++) o[c] = pf_imageio_display(rgb[3 * ((size_t)y * w + x) + c], scale);
        }
}

static uint8_t tu__unit(float v)
{
    if (!(v > 0.0f)) return 0;
    if (!(v < 1.0f)) return 255;
    return (uint8_t)(v * 255.0f + 0.5f);
}

void tu_golden_put_plane(tu_golden_picture *p, uint32_t x0, uint32_t y0, const float *v, size_t stride, uint32_t w,
                         uint32_t h, float lo, float hi)
{
    float inv = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *o = tu__px(p, x0, y0, x, y);
            if (!o) continue;
            float f = v[((size_t)y * w + x) * stride];
            if (!isfinite(f)) {
                o[0] = o[1] = 0;
                o[2] = 255;
            } else {
                o[0] = o[1] = o[2] = tu__unit((f - lo) * inv);
            }
        }
}

void tu_golden_put_planes3(tu_golden_picture *p, uint32_t x0, uint32_t y0, const float *r, const float *g,
                           const float *b, size_t stride, uint32_t w, uint32_t h, float lo, float hi)
{
    float inv = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    const float *planes[3] = {r, g, b};
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *o = tu__px(p, x0, y0, x, y);
            if (!o) continue;
            for (int c = 0; c < 3; c++) o[c] = tu__unit((planes[c][((size_t)y * w + x) * stride] - lo) * inv);
        }
}

void tu_golden_put_ids(tu_golden_picture *p, uint32_t x0, uint32_t y0, const uint32_t *id, uint32_t w, uint32_t h,
                       uint32_t empty)
{
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *o = tu__px(p, x0, y0, x, y);
            if (!o) continue;
            uint32_t v = id[(size_t)y * w + x];
            if (v == empty) {
                o[0] = o[1] = o[2] = 0;
                continue;
            }
            uint32_t c = v * 2654435761u; /* Knuth's multiplicative hash: neighbours far apart */
            c ^= c >> 15;
            o[0] = (uint8_t)(64 + (c & 191));
            o[1] = (uint8_t)(64 + ((c >> 8) & 191));
            o[2] = (uint8_t)(64 + ((c >> 16) & 191));
        }
}

void tu_golden_put_points(tu_golden_picture *p, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h, const float *xyz,
                          size_t stride, uint32_t count, int ax, int ay, const float lo[3], const float hi[3])
{
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *o = tu__px(p, x0, y0, x, y);
            if (o) o[0] = o[1] = o[2] = 40;
        }
    for (uint32_t i = 0; i < count; i++) {
        float u = (xyz[i * stride + ax] - lo[ax]) / (hi[ax] - lo[ax]);
        float v = (xyz[i * stride + ay] - lo[ay]) / (hi[ay] - lo[ay]);
        if (!(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f)) continue;
        uint32_t px = (uint32_t)(u * (float)(w - 1) + 0.5f), py = (uint32_t)((1.0f - v) * (float)(h - 1) + 0.5f);
        uint8_t *o = tu__px(p, x0, y0, px, py);
        if (o) o[0] = o[1] = o[2] = 255;
    }
}

uint64_t tu_golden_diff(const uint8_t *actual, const uint8_t *expected, uint32_t w, uint32_t h, uint8_t *diff,
                        tu_golden_diff_stats *stats)
{
    tu_golden_diff_stats st;
    memset(&st, 0, sizeof st);
    st.x0 = w;
    st.y0 = h;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            size_t k = 3 * ((size_t)y * w + x);
            uint32_t d = 0;
            for (int c = 0; c < 3; c++) {
                int e = abs((int)actual[k + c] - (int)expected[k + c]);
                if ((uint32_t)e > d) d = (uint32_t)e;
            }
            if (d) {
                st.pixels++;
                if (d > st.max) st.max = d, st.max_x = x, st.max_y = y;
                if (x < st.x0) st.x0 = x;
                if (y < st.y0) st.y0 = y;
                if (x > st.x1) st.x1 = x;
                if (y > st.y1) st.y1 = y;
            }
            if (!diff) continue;
            if (d) { /* red (1/255) to yellow (32/255 and more) */
                diff[k] = 255;
                diff[k + 1] = (uint8_t)(d >= 32 ? 255 : 8 * d - 1);
                diff[k + 2] = 0;
            } else { /* the reference, grey and dimmed to a quarter */
                uint32_t l = (77u * expected[k] + 150u * expected[k + 1] + 29u * expected[k + 2]) >> 8;
                diff[k] = diff[k + 1] = diff[k + 2] = (uint8_t)(l / 4);
            }
        }
    if (stats) *stats = st;
    return st.pixels;
}

/* Reads a reference PNG as RGB8 (*rgb malloc'ed); 0 when it is absent or
 * unreadable (why in `why`). */
static int tu__read_png(const char *path, uint8_t **rgb, uint32_t *w, uint32_t *h, char *why, size_t why_size)
{
    char *bytes;
    size_t size;
    pf_error err;
    *rgb = NULL;
    if (pf_imageio_read_file(path, 64u << 20, "reference picture", &bytes, &size, &err) != PF_OK) {
        snprintf(why, why_size, "%s", err.message);
        return 0;
    }
    uint8_t *rgba;
    pf_result r = pf_decode_rgba8(bytes, size, NULL, &rgba, w, h, &err);
    free(bytes);
    if (r != PF_OK) {
        snprintf(why, why_size, "%s: %s", path, err.message);
        return 0;
    }
    size_t n = (size_t)*w * *h;
    *rgb = malloc(3 * n);
    assert_non_null(*rgb);
    for (size_t i = 0; i < n; i++) memcpy(*rgb + 3 * i, rgba + 4 * i, 3);
    free(rgba);
    return 1;
}

void tu_golden_picture_load(tu_golden_picture *p, const char *path)
{
    char why[1024];
    if (!tu__read_png(path, &p->rgb, &p->w, &p->h, why, sizeof why)) fail_msg("%s", why);
}

/* Removes NAME-{actual,expected,diff}.png from the failure folder. */
static void tu__remove_failure(const char *fail_dir, const char *name)
{
    static const char *const kinds[3] = {"actual", "expected", "diff"};
    for (int k = 0; k < 3; k++) {
        char path[PF_IMAGEIO_PATH_MAX];
        snprintf(path, sizeof path, "%s/%s-%s.png", fail_dir, name, kinds[k]);
        remove(path);
    }
}

static int tu__update_mode(void)
{
    const char *e = getenv("SOFTGI_GOLDEN_UPDATE");
    return e && strcmp(e, "1") == 0;
}

int tu_golden_verify(const char *ref_dir, const char *fail_dir, const char *name, uint64_t hash, uint64_t expected,
                     const tu_golden_picture *pic, char *msg, size_t msg_size)
{
    char ref[PF_IMAGEIO_PATH_MAX], why[1024] = "";
    pf_error err;
    snprintf(ref, sizeof ref, "%s/%s.png", ref_dir, name);
    msg[0] = 0;
    if (hash == expected && tu__update_mode()) {
        if (pf_imageio_write_png_rgb8(ref, pic->rgb, pic->w, pic->h, &err) != PF_OK) {
            snprintf(msg, msg_size, "golden %s: cannot write the reference: %s", name, err.message);
            return 1;
        }
        print_message("golden %s: reference picture written to %s\n", name, ref);
        return 0;
    }
    uint8_t *exp_rgb = NULL;
    uint32_t ew = 0, eh = 0;
    int have = tu__read_png(ref, &exp_rgb, &ew, &eh, why, sizeof why);
    int same_size = have && ew == pic->w && eh == pic->h;
    if (hash == expected) {
        int ok = same_size && tu_golden_diff(pic->rgb, exp_rgb, pic->w, pic->h, NULL, NULL) == 0;
        free(exp_rgb);
        if (ok) {
            tu__remove_failure(fail_dir, name); /* an earlier failure's pictures would mislead */
            return 0;
        }
        snprintf(msg, msg_size,
                 "golden %s: the hash %016llx matches, but the reference picture %s %s; rewrite it with "
                 "SOFTGI_GOLDEN_UPDATE=1 (docs/testing.md)",
                 name, (unsigned long long)hash, ref,
                 !have ? "is missing or unreadable" : !same_size ? "has another size" : "is stale (differs)");
        if (!have && why[0]) snprintf(msg + strlen(msg), msg_size - strlen(msg), "\n  (%s)", why);
        return 1;
    }

    /* A failing golden: the actual, expected and difference pictures. */
    char actual[PF_IMAGEIO_PATH_MAX], expected_out[PF_IMAGEIO_PATH_MAX], diff[PF_IMAGEIO_PATH_MAX];
    snprintf(actual, sizeof actual, "%s/%s-actual.png", fail_dir, name);
    snprintf(expected_out, sizeof expected_out, "%s/%s-expected.png", fail_dir, name);
    snprintf(diff, sizeof diff, "%s/%s-diff.png", fail_dir, name);
    size_t len = 0;
#define TU__MSG(...) (len += (size_t)snprintf(msg + len, len < msg_size ? msg_size - len : 0, __VA_ARGS__))
    TU__MSG("golden %s: hash %016llx, expected %016llx", name, (unsigned long long)hash,
            (unsigned long long)expected);
    if (tu__update_mode()) TU__MSG(" (update mode writes the reference only once the test expects the new hash)");
    if (pf_imageio_write_png_rgb8(actual, pic->rgb, pic->w, pic->h, &err) == PF_OK) TU__MSG("\n  actual:   %s", actual);
    else TU__MSG("\n  cannot write %s: %s", actual, err.message);
    if (!have) {
        TU__MSG("\n  no reference picture to compare with (%s)", why);
    } else if (!same_size) {
        TU__MSG("\n  the reference %s is %ux%u, the picture %ux%u: no difference picture", ref, ew, eh, pic->w, pic->h);
    } else {
        uint8_t *d = malloc((size_t)pic->w * pic->h * 3);
        assert_non_null(d);
        tu_golden_diff_stats st;
        tu_golden_diff(pic->rgb, exp_rgb, pic->w, pic->h, d, &st);
        if (pf_imageio_write_png_rgb8(expected_out, exp_rgb, ew, eh, &err) == PF_OK)
            TU__MSG("\n  expected: %s", expected_out);
        if (pf_imageio_write_png_rgb8(diff, d, pic->w, pic->h, &err) == PF_OK) TU__MSG("\n  diff:     %s", diff);
        else TU__MSG("\n  cannot write %s: %s", diff, err.message);
        if (st.pixels)
            TU__MSG("\n  %llu of %u pixels differ (in x %u..%u, y %u..%u); largest difference %u/255 at (%u, %u)",
                    (unsigned long long)st.pixels, pic->w * pic->h, st.x0, st.x1, st.y0, st.y1, st.max, st.max_x,
                    st.max_y);
        else
            TU__MSG("\n  0 pixels differ: the change is below the picture's 8-bit precision");
        free(d);
    }
#undef TU__MSG
    free(exp_rgb);
    return 1;
}

void tu_golden_check_at(const char *name, uint64_t hash, uint64_t expected, const tu_golden_picture *pic,
                        const char *file, int line)
{
    static char msg[8192];
    if (tu_golden_verify(SOFTGI_GOLDEN_DIR, SOFTGI_GOLDEN_FAILURES, name, hash, expected, pic, msg, sizeof msg)) {
        print_error("%s\n", msg);
        _fail(file, line); /* cmocka's fail(), at the test's line */
    }
}
