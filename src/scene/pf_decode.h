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

/* The format by magic bytes (never by file name): the PNG signature
 * 89 50 4E 47 0D 0A 1A 0A, or FF D8 FF for JPEG. bytes may be NULL. */
pf_image_format pf_decode_format(const void *bytes, size_t size);

/* Reads only the header: format and dimensions, with the limits applied.
 * Used to estimate memory before anything is decoded; allocates only the
 * library's small context. format, w, h may be NULL; on failure *w = *h = 0
 * and *format is what the magic bytes said.
 * Errors: PF_ERR_UNSUPPORTED for a recognised other format (GIF, BMP, WebP,
 * KTX2, ...), PF_ERR_TEXTURE for anything else undecodable or over the
 * limits; the message says "not a PNG or JPEG image (glTF 2.0 allows only
 * these)" for a wrong format, names the limit for a too-large header, and
 * otherwise is "PNG: " / "JPEG: " + the library's reason. */
pf_result pf_decode_probe(const void *bytes, size_t size, const pf_decode_limits *limits, pf_image_format *format,
                          uint32_t *w, uint32_t *h, pf_error *err);

/* Decodes to tightly packed RGBA8, top row first (grey, grey+alpha, palette,
 * 16-bit and CMYK inputs are converted; an image without alpha gets 255;
 * no gamma correction: bytes as stored. pf_decode.c lists the conversions).
 * The header is checked against the limits before the w*h*4 bytes exist.
 * *rgba is malloc'ed; free() it. On failure *rgba is NULL, *w = *h = 0, and
 * err says why in one line as for pf_decode_probe (no path: the caller adds
 * its own label). w, h may be NULL; err may be NULL. Nothing is printed. */
pf_result pf_decode_rgba8(const void *bytes, size_t size, const pf_decode_limits *limits, uint8_t **rgba,
                          uint32_t *w, uint32_t *h, pf_error *err);

#ifdef __cplusplus
}
#endif

#endif
