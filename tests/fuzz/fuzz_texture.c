/* fuzz_texture: libFuzzer target for pf_decode (PNG via libspng, JPEG via
 * TurboJPEG), the decoder of texture images from untrusted glTF files.
 *
 * Each input is sniffed, probed and decoded twice: with the default limits
 * and with small ones (64 pixels a side, 1024 pixels). The sanitizers catch
 * memory errors; the invariants below catch wrong answers, with abort():
 *   - success: a non-NULL buffer of w*h*4 readable bytes, 0 < w, h <= the
 *     side limit, w*h <= the pixel limit, a recognised format, and the probe
 *     succeeded with the same w, h;
 *   - failure: *rgba NULL, w = h = 0, a non-empty one-line message, a code
 *     of the table;
 *   - the limits decide alone: an image that fits the small limits decodes
 *     under them to the very same bytes, one that does not is refused with
 *     a message naming the limit.
 * Seeds: tests/fuzz/seeds/texture (small PNGs and JPEGs of every variant). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_decode.h"

#define CHECK(cond)                                                                                                \
    do {                                                                                                           \
        if (!(cond)) {                                                                                             \
            fprintf(stderr, "fuzz_texture: invariant failed: %s (line %d)\n", #cond, __LINE__);                   \
            abort();                                                                                               \
        }                                                                                                          \
    } while (0)

typedef struct outcome {
    pf_result probe, decode;
    pf_image_format format;
    uint32_t pw, ph, w, h;
    uint8_t *rgba;
    pf_error perr, derr;
} outcome;

static void check_error(pf_result r, const pf_error *e)
{
    CHECK(r > PF_OK && r < PF_ERR_COUNT);
    CHECK(e->code == r);
    CHECK(e->message[0] != '\0');
    CHECK(strchr(e->message, '\n') == NULL);
}

static void run(const uint8_t *data, size_t size, const pf_decode_limits *lim, uint32_t max_side, uint64_t max_pixels,
                outcome *o)
{
    memset(o, 0, sizeof *o);
    o->pw = o->ph = o->w = o->h = 12345;
    o->rgba = (uint8_t *)o; /* must be overwritten */
    o->probe = pf_decode_probe(data, size, lim, &o->format, &o->pw, &o->ph, &o->perr);
    o->decode = pf_decode_rgba8(data, size, lim, &o->rgba, &o->w, &o->h, &o->derr);

    CHECK(o->format == pf_decode_format(data, size));
    if (o->probe == PF_OK) {
        CHECK(o->format != PF_IMAGE_UNKNOWN);
        CHECK(o->pw > 0 && o->ph > 0 && o->pw <= max_side && o->ph <= max_side);
        CHECK((uint64_t)o->pw * o->ph <= max_pixels);
    } else {
        check_error(o->probe, &o->perr);
        CHECK(o->pw == 0 && o->ph == 0);
    }

    if (o->decode == PF_OK) {
        CHECK(o->rgba != NULL);
        CHECK(o->probe == PF_OK); /* decoding reads the same header */
        CHECK(o->w == o->pw && o->h == o->ph);
        /* read every byte, so ASan checks the buffer really is w*h*4 */
        const size_t n = (size_t)o->w * o->h * 4;
        unsigned sum = 0;
        for (size_t i = 0; i < n; i++) sum += o->rgba[i];
        if (sum == 0xFFFFFFFFu) fprintf(stderr, " "); /* keep the loop */
    } else {
        check_error(o->decode, &o->derr);
        CHECK(o->rgba == NULL);
        CHECK(o->w == 0 && o->h == 0);
    }
    if (o->format == PF_IMAGE_UNKNOWN) CHECK(o->probe != PF_OK && o->decode != PF_OK);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    outcome big, small;
    run(data, size, NULL, PF_DECODE_MAX_SIDE, PF_DECODE_MAX_PIXELS, &big);

    const pf_decode_limits lim = {.max_side = 64, .max_pixels = 1024};
    run(data, size, &lim, 64, 1024, &small);

    /* the limits decide alone (both decodes saw the same bytes) */
    if (big.decode == PF_OK) {
        const int fits = big.w <= 64 && big.h <= 64 && (uint64_t)big.w * big.h <= 1024;
        if (fits) {
            CHECK(small.decode == PF_OK);
            CHECK(small.w == big.w && small.h == big.h);
            CHECK(memcmp(small.rgba, big.rgba, (size_t)big.w * big.h * 4) == 0);
        } else {
            CHECK(small.decode == PF_ERR_TEXTURE);
            CHECK(strstr(small.derr.message, "limit") != NULL);
        }
    }
    if (big.probe == PF_OK && small.probe != PF_OK) CHECK(strstr(small.perr.message, "limit") != NULL);
    if (small.decode == PF_OK) CHECK(big.decode == PF_OK);

    free(big.rgba);
    free(small.rgba);
    return 0;
}
