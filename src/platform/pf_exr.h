/* pf_exr: OpenEXR images through tinyexr (Debian's libtinyexr-dev 1.0.1),
 * behind a plain C API. pf_exr.cpp is the only C++ of softgi's image
 * files; pf_imageio.h is what the rest of softgi calls (it writes these
 * bytes atomically and applies the value rules).
 *
 * Writing: pf_exr_encode turns a w x h image of 1 (Y), 3 (RGB) or 4 (RGBA)
 * interleaved floats a pixel, top row first, into the bytes of a single-part
 * scanline OpenEXR file: channels A, B, G, R / Y in the file's alphabetical
 * order, 32-bit FLOAT samples, ZIP compression (zlib, 16 scanlines a block,
 * lossless), increasing-y line order, data and display window (0, 0) to
 * (w - 1, h - 1), and `comment` (if any) in the standard "comments" string
 * attribute.
 *   Why FLOAT, not HALF: the linear output is bit-exact (--hash and the
 *   golden images hash its floats) and must read back bit for bit, as the
 *   PFM does; HALF keeps 11 significant bits and overflows above 65504,
 *   while a light may reach PF_MAX_RADIANCE (1e10). The price is files about
 *   twice as large as HALF before compression.
 *   Why ZIP: lossless, deterministic (the same bytes for the same floats),
 *   and read by every OpenEXR reader (tev, OpenImageIO, Blender, pbrt's imgtool).
 *
 * Reading is untrusted input (`softgi compare IMAGE.exr REFERENCE.exr` reads
 * whatever it is handed). pf_exr_decode accepts single-part scanline images
 * (tiled, deep and multi-part files are refused), line order increasing y
 * (tinyexr 1.0.1 turns decreasing-y files upside down), compression NONE,
 * RLE, ZIPS or ZIP (PIZ is refused: tinyexr 1.0.1's PIZ decoder reads out
 * of bounds on crafted blocks), channels R, G and B (HALF, FLOAT
 * or UINT samples; other channels ignored) or Y alone (grey, read as
 * R = G = B), no subsampling. Before anything is decoded:
 *   - the header is parsed and the data window checked: 1..desc->max_side a
 *     side, at most desc->max_pixels pixels;
 *   - the memory the decode takes (4 bytes a sample for every channel of the
 *     file, plus the 12-byte RGB result a pixel) must fit desc->max_bytes;
 *   - a "type" attribute, if any, must say "scanlineimage" (tinyexr 1.0.1
 *     aborts the program on one that contradicts the version field);
 *   - the offset table is checked: one entry per block of scanlines, each
 *     pointing inside the file at a block whose first scanline is its own
 *     (min_y + k * lines per block), whose size fits the file and is at
 *     most its scanlines' uncompressed size (exactly that without
 *     compression). So every scanline of the image is decoded (tinyexr
 *     leaves lines no block covers uninitialised) and no block is read past
 *     its end.
 * Each of these closes a hole fuzz_exr found in tinyexr 1.0.1 (pf_exr.cpp
 * names them; the inputs are in tests/fuzz/regress/exr).
 * The values are returned as stored (NaN, infinities and negatives
 * included): pf_imageio applies its rules. The result is top row first,
 * 3 floats a pixel (the data window; the display window is ignored).
 * Every failure is one line naming `desc->name`, with tinyexr's own reason
 * where it gives one. */
#ifndef PF_EXR_H
#define PF_EXR_H

#include <stddef.h>
#include <stdint.h>

#include "pf_result.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The 4 bytes every OpenEXR file starts with. */
#define PF_EXR_MAGIC "\x76\x2f\x31\x01"

/* Encodes w x h pixels of `channels` (1, 3 or 4) interleaved floats, top row
 * first. On success *bytes (free with pf_exr_free) holds *size bytes. */
pf_result pf_exr_encode(const float *px, uint32_t w, uint32_t h, uint32_t channels, const char *comment,
                        uint8_t **bytes, size_t *size, pf_error *err);
void pf_exr_free(void *bytes);

/* What a read may take. Every field must be set. */
typedef struct pf_exr_read_desc {
    const char *name;    /* the file, for messages */
    uint32_t max_side;   /* width and height 1..max_side */
    uint64_t max_pixels; /* width x height */
    uint64_t max_bytes;  /* memory the decode may allocate */
} pf_exr_read_desc;

/* Decodes an OpenEXR file in memory into *rgb (malloc'ed, free() it; 3
 * floats a pixel, top row first). On failure *rgb is NULL and *w = *h = 0. */
pf_result pf_exr_decode(const void *data, size_t size, const pf_exr_read_desc *desc, float **rgb, uint32_t *w,
                        uint32_t *h, pf_error *err);

/* 1 when `data` starts with the OpenEXR magic number. */
int pf_exr_is_exr(const void *data, size_t size);

#ifdef __cplusplus
}
#endif

#endif
