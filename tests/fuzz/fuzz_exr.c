/* fuzz_exr: libFuzzer target for the OpenEXR reader (pf_exr.h through
 * pf_imageio_read_exr_memory), which `softgi compare` runs on files anyone
 * may hand it. In the fuzz build tinyexr itself is compiled into pf_exr.cpp
 * with the fuzzer's instrumentation (CMakeLists.txt), so the sanitizers and
 * the coverage see inside its header parser and decompressors.
 *
 * Each input is read twice, as radiance (finite, >= 0) and as data (no
 * NaN), with a memory budget of FUZZ_EXR_BUDGET. Invariants, checked with
 * abort():
 *   - failure: *rgb NULL, w = h = 0, a one-line message, a known code;
 *   - success: a buffer of w*h*3 floats, 1 <= w, h <= PF_IMAGEIO_MAX_SIDE,
 *     w*h <= PF_IMAGEIO_MAX_PIXELS, every value within the range asked for;
 *   - a radiance success is a data success with the same bits;
 *   - what was read, encoded again (pf_exr_encode: FLOAT, ZIP), decodes to
 *     the same bits.
 * Inputs: tests/fuzz/regress/exr (valid files from the OpenEXR library and
 * from softgi in every compression softgi reads, files it must refuse:
 * tiled, multi-part, decreasing-y, PIZ, B44/PXR24/DWAA, and the findings of
 * fuzz runs: leak-* and crash-*, each now refused or freed). Run with
 * tools/fuzz.sh SECONDS exr. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_exr.h"
#include "pf_imageio.h"

#define FUZZ_EXR_BUDGET (256ull << 20) /* well under libFuzzer's -rss_limit_mb (tools/fuzz.sh: 4096) */

#define CHECK(cond)                                                                                                \
    do {                                                                                                           \
        if (!(cond)) {                                                                                             \
            fprintf(stderr, "fuzz_exr: invariant failed: %s (line %d)\n", #cond, __LINE__);                       \
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

static void check_success(const float *rgb, uint32_t w, uint32_t h, pf_imageio_range range)
{
    CHECK(rgb != NULL);
    CHECK(w >= 1 && h >= 1 && w <= PF_IMAGEIO_MAX_SIDE && h <= PF_IMAGEIO_MAX_SIDE);
    CHECK((uint64_t)w * h <= PF_IMAGEIO_MAX_PIXELS);
    for (size_t i = 0; i < (size_t)w * h * 3; i++) {
        if (range == PF_IMAGEIO_RADIANCE) CHECK(isfinite(rgb[i]) && rgb[i] >= 0.0f);
        else CHECK(!isnan(rgb[i]));
    }
}

/* The image encoded again and decoded: the same bits. */
static void check_round_trip(const float *rgb, uint32_t w, uint32_t h)
{
    uint8_t *bytes = NULL;
    size_t size = 0;
    pf_error err;
    CHECK(pf_exr_encode(rgb, w, h, 3, "fuzz", &bytes, &size, &err) == PF_OK);
    float *back = NULL;
    uint32_t bw = 0, bh = 0;
    CHECK(pf_imageio_read_exr_memory(bytes, size, "again.exr", PF_IMAGEIO_DATA, FUZZ_EXR_BUDGET, &back, &bw, &bh,
                                     &err) == PF_OK);
    CHECK(bw == w && bh == h && memcmp(back, rgb, (size_t)w * h * 3 * sizeof(float)) == 0);
    free(back);
    pf_exr_free(bytes);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    float *rgb = (float *)&size, *any = (float *)&size; /* must come back NULL on failure */
    uint32_t w = 7, h = 7, aw = 7, ah = 7;
    pf_error err, aerr;
    memset(&err, 0, sizeof err);
    memset(&aerr, 0, sizeof aerr);
    pf_result r = pf_imageio_read_exr_memory(data, size, "fuzz.exr", PF_IMAGEIO_RADIANCE, FUZZ_EXR_BUDGET, &rgb, &w,
                                             &h, &err);
    pf_result ra = pf_imageio_read_exr_memory(data, size, "fuzz.exr", PF_IMAGEIO_DATA, FUZZ_EXR_BUDGET, &any, &aw,
                                              &ah, &aerr);
    if (ra != PF_OK) check_failure(ra, any, aw, ah, &aerr);
    else check_success(any, aw, ah, PF_IMAGEIO_DATA);
    if (r != PF_OK) {
        check_failure(r, rgb, w, h, &err);
        /* refused as radiance: by its values (then data may pass) or like data */
        CHECK(r == PF_ERR_NONFINITE ? 1 : ra == r);
    } else {
        check_success(rgb, w, h, PF_IMAGEIO_RADIANCE);
        CHECK(ra == PF_OK && aw == w && ah == h);
        CHECK(memcmp(rgb, any, (size_t)w * h * 3 * sizeof(float)) == 0);
    }
    if (ra == PF_OK && (uint64_t)aw * ah <= (1u << 20)) check_round_trip(any, aw, ah);
    if (r == PF_OK) free(rgb);
    if (ra == PF_OK) free(any);
    return 0;
}
