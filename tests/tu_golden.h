/* tu_golden: golden hashes with a reference picture beside them.
 *
 * A golden test hashes what it rendered (pf_imageio_hash or its own FNV-1a)
 * and compares the hash with a constant in the test: any change of a single
 * bit fails. The hash alone leaves nothing to look at, so each golden also
 * makes a picture of what the hash covers (an RGB8 image: the tone-mapped
 * image, the G-buffer planes side by side, the maps, the VPLs from above)
 * and keeps it as tests/data/golden/NAME.png.
 *
 * tu_golden_check(name, hash, expected, picture):
 *   - hash == expected: passes when the reference picture exists and equals
 *     the picture (a stale or missing picture fails, naming the update mode);
 *   - hash != expected: writes NAME-actual.png, NAME-expected.png (the
 *     reference) and NAME-diff.png to SOFTGI_GOLDEN_FAILURES (the build
 *     folder's golden-failures/), prints their paths, how many pixels differ,
 *     the largest difference and where, then fails. The diff picture shows
 *     unchanged pixels as the reference in dim grey and changed ones from red
 *     (a difference of 1/255 in some channel) to yellow (32/255 or more).
 *     A change below the picture's 8-bit precision (the hash covers floats)
 *     shows as "0 pixels differ".
 *   - SOFTGI_GOLDEN_UPDATE=1 in the environment (update mode): where the hash
 *     equals the expected one, the picture is written as the reference
 *     instead of compared. A deliberate change of a golden is therefore two
 *     steps: put the new hash (printed by the failure) into the test, then
 *     run the test once with SOFTGI_GOLDEN_UPDATE=1 (docs/testing.md).
 *
 * Pictures are built from panels: tu_golden_picture_init makes a black w x h
 * RGB8 image; the put functions draw one panel at (x0, y0). */
#ifndef TU_GOLDEN_H
#define TU_GOLDEN_H

#include <stddef.h>
#include <stdint.h>

typedef struct tu_golden_picture {
    uint8_t *rgb; /* w * h * 3, top row first */
    uint32_t w, h;
} tu_golden_picture;

/* What tu_golden_diff found. */
typedef struct tu_golden_diff_stats {
    uint64_t pixels;  /* pixels differing in any channel */
    uint32_t max;     /* largest channel difference (0..255) */
    uint32_t max_x, max_y;        /* where it is */
    uint32_t x0, y0, x1, y1;      /* bounding box of the differing pixels (inclusive) */
} tu_golden_diff_stats;

void tu_golden_picture_init(tu_golden_picture *p, uint32_t w, uint32_t h);
void tu_golden_picture_free(tu_golden_picture *p);
/* A PNG file (e.g. one `softgi render` wrote) as the picture; fails the
 * test when it cannot be read. */
void tu_golden_picture_load(tu_golden_picture *p, const char *path);

/* An RGB8 image of w x h pixels. */
void tu_golden_put_rgb8(tu_golden_picture *p, uint32_t x0, uint32_t y0, const uint8_t *rgb, uint32_t w, uint32_t h);
/* Linear RGB (3 floats a pixel) through the PNG writer's display transform
 * (pf_imageio_display at 2^exposure), as `softgi render` writes it. */
void tu_golden_put_linear(tu_golden_picture *p, uint32_t x0, uint32_t y0, const float *rgb, uint32_t w, uint32_t h,
                          float exposure);
/* One plane of `stride` floats a pixel (channel at offset 0) as grey, lo..hi
 * to 0..255 (clamped); NaN and infinities blue. */
void tu_golden_put_plane(tu_golden_picture *p, uint32_t x0, uint32_t y0, const float *v, size_t stride, uint32_t w,
                         uint32_t h, float lo, float hi);
/* Three planes (r, g, b: `stride` floats a pixel each, e.g. the G-buffer's
 * normals or albedo) as colours, lo..hi to 0..255 (clamped; NaN 0). */
void tu_golden_put_planes3(tu_golden_picture *p, uint32_t x0, uint32_t y0, const float *r, const float *g,
                           const float *b, size_t stride, uint32_t w, uint32_t h, float lo, float hi);
/* 32-bit ids (triangle ids) as one arbitrary colour each; `empty` black. */
void tu_golden_put_ids(tu_golden_picture *p, uint32_t x0, uint32_t y0, const uint32_t *id, uint32_t w, uint32_t h,
                       uint32_t empty);
/* Points seen along an axis: point i is (xyz[i * stride + ax], xyz[i * stride
 * + ay]), lo..hi mapped to the w x h panel (y up), drawn white on dark grey. */
void tu_golden_put_points(tu_golden_picture *p, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h, const float *xyz,
                          size_t stride, uint32_t count, int ax, int ay, const float lo[3], const float hi[3]);

/* Compares two RGB8 images of w x h pixels; diff (may be NULL) gets the
 * difference picture described above. Returns the number of differing
 * pixels. */
uint64_t tu_golden_diff(const uint8_t *actual, const uint8_t *expected, uint32_t w, uint32_t h, uint8_t *diff,
                        tu_golden_diff_stats *stats);

/* The check, with the reference folder and the failure folder given:
 * returns 0 when it passes, else writes the failure pictures and a message
 * (several lines) into msg. tu_golden_check calls it with
 * SOFTGI_GOLDEN_DIR and SOFTGI_GOLDEN_FAILURES and fails the test on 1. */
int tu_golden_verify(const char *ref_dir, const char *fail_dir, const char *name, uint64_t hash, uint64_t expected,
                     const tu_golden_picture *pic, char *msg, size_t msg_size);
void tu_golden_check_at(const char *name, uint64_t hash, uint64_t expected, const tu_golden_picture *pic,
                        const char *file, int line);
#define tu_golden_check(name, hash, expected, pic) \
    tu_golden_check_at(name, hash, expected, pic, __FILE__, __LINE__)

#endif
