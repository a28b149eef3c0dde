/* pf_imageio: writing and reading the images softgi produces.
 *
 * - PNG (8-bit sRGB) through stb_image_write (libstb-dev): linear RGB is
 *   multiplied by 2^exposure, tone mapped per channel with Reinhard's
 *   x / (1 + x), then sRGB-encoded. This is the display output.
 * - PFM (Portable Float Map, "PF", little-endian, bottom row first): the
 *   linear HDR output, bit-exact floats, readable by every HDR tool.
 * - pf_imageio_hash: FNV-1a 64 over the float bits of a linear buffer; what
 *   `--hash` prints and the golden tests compare.
 *
 * Buffers are row-major from the top row, 3 floats per pixel (RGB). */
#ifndef PF_IMAGEIO_H
#define PF_IMAGEIO_H

#include <stdint.h>

#include "pf_result.h"

pf_result pf_imageio_write_png(const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure,
                               pf_error *err);
pf_result pf_imageio_write_pfm(const char *path, const float *rgb, uint32_t w, uint32_t h, pf_error *err);
/* Reads a 3-channel PFM written by any tool (either endianness); *rgb is
 * malloc'ed top row first. */
pf_result pf_imageio_read_pfm(const char *path, float **rgb, uint32_t *w, uint32_t *h, pf_error *err);
uint64_t pf_imageio_hash(const float *data, uint64_t count);
/* The display transform of one linear value (shared with the viewer). */
uint8_t pf_imageio_display(float linear, float exposure_scale);
/* Creates the parent directories of `path` (like mkdir -p of dirname). */
pf_result pf_imageio_make_parent_dirs(const char *path, pf_error *err);

#endif
