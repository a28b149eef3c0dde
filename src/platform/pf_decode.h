/* pf_decode: texture images from untrusted files, decoded to RGBA8.
 *
 * glTF 2.0 allows PNG and JPEG images (glTF 2.0 spec, Sec. 3.8.1 "Images").
 * Both come from strangers, so they are decoded by libraries maintained and
 * fuzzed for hostile input: libspng (PNG) and libjpeg-turbo through its
 * TurboJPEG API (JPEG). stb_image is not used for decoding (2.27 writes out of
 * bounds on a JPEG whose Huffman table declares more than 256 symbols).
 *
 * Every call checks the header's dimensions against the limits BEFORE any
 * pixel memory is allocated, so a 40-byte file cannot ask for gigabytes.
 * Any other format (GIF, BMP, WebP, ...) is refused with a clear message. */
#ifndef PF_DECODE_H
#define PF_DECODE_H

#include <stddef.h>
#include <stdint.h>

#include "pf_result.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pf_image_format { PF_IMAGE_UNKNOWN = 0, PF_IMAGE_PNG, PF_IMAGE_JPEG } pf_image_format;

/* Limits on a decoded image; zero fields mean the defaults below. */
typedef struct pf_decode_limits {
    uint32_t max_side;   /* default PF_DECODE_MAX_SIDE */
    uint64_t max_pixels; /* default PF_DECODE_MAX_PIXELS */
} pf_decode_limits;

#define PF_DECODE_MAX_SIDE 32768u
#define PF_DECODE_MAX_PIXELS (UINT64_C(1) << 26) /* 64 Mpixels = 256 MiB of RGBA8 */

/* The format by magic bytes (never by file name). */
pf_image_format pf_decode_format(const void *bytes, size_t size);

/* Reads only the header: format and dimensions, with the limits applied.
 * Used to estimate memory before anything is decoded. */
pf_result pf_decode_probe(const void *bytes, size_t size, const pf_decode_limits *limits, pf_image_format *format,
                          uint32_t *w, uint32_t *h, pf_error *err);

/* Decodes to tightly packed RGBA8, top row first (grey, grey+alpha, palette,
 * 16-bit and CMYK inputs are converted; an image without alpha gets 255).
 * *rgba is malloc'ed; free() it. On failure *rgba is NULL and err says why in
 * one line (no path: the caller adds its own label). */
pf_result pf_decode_rgba8(const void *bytes, size_t size, const pf_decode_limits *limits, uint8_t **rgba,
                          uint32_t *w, uint32_t *h, pf_error *err);

#ifdef __cplusplus
}
#endif

#endif
