/* fuzz_pfm: libFuzzer target for the PFM reader (pf_imageio.h), which
 * `softgi compare` and `sequence --reuse-frames` run on files anyone may
 * hand them.
 *
 * Each input goes to pf_imageio_read_pfm_memory (radiance: finite, >= 0)
 * and to pf_imageio_read_pfm_memory_ex with PF_IMAGEIO_DEPTH (+inf
 * allowed). Invariants, checked with abort():
 *   - success: a buffer of w*h*3 floats, 1 <= w, h <= PF_IMAGEIO_MAX_SIDE,
 *     w*h <= PF_IMAGEIO_MAX_PIXELS, the input at least w*h*4 bytes (the data
 *     was there before anything was allocated), every value finite and
 *     >= 0 (radiance) or >= 0 / +inf (depth);
 *   - failure: *rgb NULL, w = h = 0, a one-line message, a known code;
 *   - a radiance success is a depth success with the same bits;
 *   - what was read, written again in softgi's own layout (little-endian,
 *     bottom row first), reads back to the same bits.
 * Seeds: tests/fuzz/seeds/pfm. Build (by hand, or tests/fuzz/CMakeLists.txt):
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -Isrc/platform \
 *     tests/fuzz/fuzz_pfm.c src/platform/pf_imageio.c src/base/pf_result.c \
 *     src/scene/pf_scene.c src/scene/pf_texture.c $(pkg-config --cflags --libs stb) -lm -o fuzz_pfm */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_imageio.h"

#define CHECK(cond)                                                                                                \
    do {                                                                                                           \
        if (!(cond)) {                                                                                             \
            fprintf(stderr, "fuzz_pfm: invariant failed: %s (line %d)\n", #cond, __LINE__);                       \
            abort();                                                                                               \
        }                                                                                                          \
    } while (0)

static void check_failure(pf_result r, const float *rgb, uint32_t w, uint32_t h, const pf_error *e)
{
    CHECK(r != PF_OK && (unsigned)r < PF_ERR_COUNT);
    CHECK(rgb == NULL && w == 0 && h == 0);
    CHECK(e->code == r);
    CHECK(e->message[0] != 0);
    CHECK(memchr(e->message, 0, sizeof e->message) != NULL);
    CHECK(strchr(e->message, '\n') == NULL);
}

static void check_success(const float *rgb, uint32_t w, uint32_t h, size_t size, pf_imageio_range range)
{
    CHECK(rgb != NULL);
    CHECK(w >= 1 && h >= 1 && w <= PF_IMAGEIO_MAX_SIDE && h <= PF_IMAGEIO_MAX_SIDE);
    CHECK((uint64_t)w * h <= PF_IMAGEIO_MAX_PIXELS);
    CHECK((uint64_t)w * h * 4 <= size); /* grey needs 4 bytes a pixel, RGB 12 */
    for (size_t i = 0; i < (size_t)w * h * 3; i++) {
        if (range == PF_IMAGEIO_RADIANCE) CHECK(isfinite(rgb[i]) && rgb[i] >= 0.0f);
        else CHECK(rgb[i] >= 0.0f); /* NaN fails this too */
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    float *rgb = (float *)&size, *depth = (float *)&size; /* must come back NULL on failure */
    uint32_t w = 7, h = 7, dw = 7, dh = 7;
    pf_error err, derr;
    memset(&err, 0, sizeof err);
    memset(&derr, 0, sizeof derr);
    pf_result r = pf_imageio_read_pfm_memory(data, size, &rgb, &w, &h, &err);
    pf_result rd = pf_imageio_read_pfm_memory_ex(data, size, "fuzz.pfm", PF_IMAGEIO_DEPTH, &depth, &dw, &dh, &derr);

    if (rd != PF_OK) check_failure(rd, depth, dw, dh, &derr);
    else check_success(depth, dw, dh, size, PF_IMAGEIO_DEPTH);
    if (r != PF_OK) {
        check_failure(r, rgb, w, h, &err);
        free(depth);
        return 0;
    }
    check_success(rgb, w, h, size, PF_IMAGEIO_RADIANCE);
    /* radiance is a subset of depth */
    CHECK(rd == PF_OK && dw == w && dh == h);
    CHECK(memcmp(rgb, depth, (size_t)w * h * 3 * sizeof(float)) == 0);

    /* softgi's own layout reads back to the same bits */
    char head[64];
    size_t hn = (size_t)snprintf(head, sizeof head, "PF\n%u %u\n-1.0\n", w, h);
    size_t row = (size_t)w * 3 * sizeof(float);
    uint8_t *file = malloc(hn + row * h);
    CHECK(file != NULL);
    memcpy(file, head, hn);
    for (uint32_t y = 0; y < h; y++) memcpy(file + hn + (size_t)y * row, rgb + (size_t)(h - 1 - y) * w * 3, row);
    float *back = NULL;
    uint32_t bw = 0, bh = 0;
    pf_error berr;
    CHECK(pf_imageio_read_pfm_memory(file, hn + row * h, &back, &bw, &bh, &berr) == PF_OK);
    CHECK(bw == w && bh == h && memcmp(back, rgb, row * h) == 0);
    free(back);
    free(file);
    free(rgb);
    free(depth);
    return 0;
}
