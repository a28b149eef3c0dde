/* pf_decode: PNG and JPEG texture images from untrusted files to RGBA8.
 *
 * What it implements: the image half of glTF 2.0 Sec. 3.8.1 "Images" (PNG and
 * JPEG only), as a format sniffer, a header-only probe and a decoder to tightly
 * packed RGBA8, top row first.
 *
 * Why these libraries: texture files come from strangers. stb_image 2.27 has
 * an out-of-bounds write in stbi__build_huffman when a JPEG's DHT segment
 * declares more than 256 symbols, so it is not used for decoding. Instead:
 *   - libspng (PNG): written for hostile input, continuously fuzzed (OSS-Fuzz),
 *     with explicit image-size, chunk-size and chunk-cache limits;
 *   - libjpeg-turbo through its TurboJPEG API (JPEG): the reference decoder
 *     most of the world runs, fuzzed by OSS-Fuzz, which checks DHT counts
 *     ("Bogus Huffman table definition") and can stop at the first warning and
 *     after 500 progressive scans.
 *
 * Order of work in every call (the point of this module):
 *   1. sniff the magic bytes (never the file name);
 *   2. read the header only, and check width/height against pf_decode_limits;
 *   3. only then allocate w*h*4 bytes (all sizes in uint64 with checks) and
 *      decode into them.
 * So a 40-byte file cannot ask for gigabytes, and a failed call leaves nothing
 * behind (no output buffer, no library context).
 *
 * Conversions to RGBA8 (alpha 255 where the file has none):
 *   - PNG, all colour types and bit depths, interlaced or not, by libspng with
 *     SPNG_FMT_RGBA8 | SPNG_DECODE_TRNS:
 *       grey 1/2/4 bits  -> left bit replication (v * 255 / (2^d - 1), exact);
 *       16-bit samples   -> the high byte, v >> 8 (libspng truncates, like
 *                           libpng's png_set_strip_16): with v = 256a + b it
 *                           is a, while the exact value is v / 257 =
 *                           a + (b - a) / 257, so the error is below one
 *                           8-bit step but can differ from round(v / 257) by
 *                           one either way (0x12FF -> 0x12, not 0x13;
 *                           0xFF00 -> 0xFF, not 0xFE);
 *       palette          -> PLTE colour, alpha from tRNS (255 past its end);
 *       tRNS on grey/RGB -> alpha 0 where the raw sample equals the key.
 *     No gamma correction: gAMA/sRGB/iCCP are ignored and the bytes are used as
 *     stored (the renderer applies the sRGB transfer function itself).
 *   - JPEG by TurboJPEG with TJFLAG_ACCURATEDCT (the ISLOW IDCT; libjpeg-turbo's
 *     SIMD ISLOW is bit-exact with its C code, so output does not depend on the
 *     machine):
 *       YCbCr/RGB/grey   -> TJPF_RGBA (grey gives R = G = B);
 *       CMYK/YCCK        -> TJPF_CMYK, then R = C*K/255, G = M*K/255,
 *                           B = Y*K/255 (rounded) on the values as stored,
 *                           which Adobe writers store inverted (255 = no ink).
 *                           Naive, without colour management, the same
 *                           conversion stb_image made; libjpeg-turbo itself
 *                           has no CMYK -> RGB path.
 *
 * Messages are one line, "PNG: " / "JPEG: " + the library's own reason
 * (spng_strerror, tjGetErrorStr2), never printed, only stored in pf_error.
 * Note: TurboJPEG 2.1 formats library messages into one process-wide buffer,
 * so two threads failing at the same moment may see each other's message text
 * (the result code is always right). */
#include "pf_decode.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include <spng.h>
#include <turbojpeg.h>

/* Ancillary PNG chunks (text, EXIF, ICC profiles, unknown chunks) are never
 * used, but libspng parses and stores them. Without limits a few bytes of
 * eXIf chunk header may ask for a 2 GiB buffer, and a zTXt may inflate
 * without bound. One chunk
 * may take at most 4 MiB after inflation and all of them together 8 MiB;
 * real ICC profiles and XMP packets are far smaller. A file over these limits
 * is refused (libspng 0.7 has no "skip if too big"). */
#define PF__PNG_CHUNK_MAX ((size_t)4 << 20)
#define PF__PNG_CHUNK_CACHE ((size_t)8 << 20)

static const uint8_t pf__png_magic[8] = {0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A};
static const uint8_t pf__jpeg_magic[3] = {0xFF, 0xD8, 0xFF};

#define PF__NOT_PNG_JPEG "not a PNG or JPEG image (glTF 2.0 allows only these)"

/* ----------------------------------------------------------------- helpers */

typedef struct pf__limits {
    uint32_t max_side;
    uint64_t max_pixels;
} pf__limits;

static pf__limits pf__limits_resolve(const pf_decode_limits *l)
{
    pf__limits r = {PF_DECODE_MAX_SIDE, PF_DECODE_MAX_PIXELS};
    if (l && l->max_side) r.max_side = l->max_side;
    if (l && l->max_pixels) r.max_pixels = l->max_pixels;
    return r;
}

/* Stores "<prefix><reason>" as the one-line message (library strings are
 * one line already; control characters are blanked to be sure). */
static pf_result pf__fail(pf_error *err, pf_result code, const char *prefix, const char *reason)
{
    if (!err) return code;
    pf_error_set(err, code, "%s%s", prefix, (reason && reason[0]) ? reason : "unknown error");
    for (char *p = err->message; *p; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7F) *p = ' ';
    return code;
}

/* Checks a header's size against the limits; the product is taken in uint64
 * (w, h < 2^32, so w*h < 2^64 cannot wrap) and must leave room for 4 bytes
 * per pixel in size_t. Called before any pixel memory exists. */
static pf_result pf__check_size(const char *prefix, uint64_t w, uint64_t h, pf__limits lim, pf_error *err)
{
    if (w == 0 || h == 0)
        return pf_error_set(err, PF_ERR_TEXTURE, "%simage has zero width or height (%llux%llu)", prefix,
                            (unsigned long long)w, (unsigned long long)h);
    if (w > lim.max_side || h > lim.max_side)
        return pf_error_set(err, PF_ERR_TEXTURE, "%simage is %llux%llu pixels, over the limit of %u pixels per side",
                            prefix, (unsigned long long)w, (unsigned long long)h, lim.max_side);
    uint64_t pixels = w * h;
    if (pixels > lim.max_pixels)
        return pf_error_set(err, PF_ERR_TEXTURE,
                            "%simage is %llux%llu = %llu pixels, over the limit of %llu pixels", prefix,
                            (unsigned long long)w, (unsigned long long)h, (unsigned long long)pixels,
                            (unsigned long long)lim.max_pixels);
    if (pixels > (uint64_t)SIZE_MAX / 4u)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%simage is %llux%llu pixels, too big for this machine", prefix,
                            (unsigned long long)w, (unsigned long long)h);
    return PF_OK;
}

/* Names a few formats that are recognisable but not allowed, so the message
 * can say what the file is. NULL for anything else. */
static const char *pf__other_format_name(const uint8_t *b, size_t n)
{
    if (n >= 6 && (memcmp(b, "GIF87a", 6) == 0 || memcmp(b, "GIF89a", 6) == 0)) return "GIF";
    if (n >= 2 && memcmp(b, "BM", 2) == 0) return "BMP";
    if (n >= 12 && memcmp(b, "RIFF", 4) == 0 && memcmp(b + 8, "WEBP", 4) == 0) return "WebP";
    if (n >= 12 && memcmp(b, "\xABKTX 20\xBB\r\n\x1A\n", 12) == 0) return "KTX2";
    if (n >= 12 && memcmp(b, "\xABKTX 11\xBB\r\n\x1A\n", 12) == 0) return "KTX";
    if (n >= 4 && memcmp(b, "DDS ", 4) == 0) return "DDS";
    if (n >= 4 && (memcmp(b, "II*\0", 4) == 0 || memcmp(b, "MM\0*", 4) == 0)) return "TIFF";
    if (n >= 4 && memcmp(b, "qoif", 4) == 0) return "QOI";
    if (n >= 12 && memcmp(b + 4, "ftypavif", 8) == 0) return "AVIF";
    return NULL;
}

static pf_result pf__refuse_format(const uint8_t *b, size_t n, pf_error *err)
{
    if (n == 0) return pf_error_set(err, PF_ERR_TEXTURE, "empty image data: " PF__NOT_PNG_JPEG);
    const char *name = pf__other_format_name(b, n);
    if (name) return pf_error_set(err, PF_ERR_UNSUPPORTED, "%s image: " PF__NOT_PNG_JPEG, name);
    return pf_error_set(err, PF_ERR_TEXTURE, PF__NOT_PNG_JPEG);
}

/* --------------------------------------------------------------------- PNG */

/* Opens a libspng decoder on the buffer with every limit set and reads the
 * IHDR only. On success *out owns a context the caller frees. */
static pf_result pf__png_open(const uint8_t *b, size_t n, pf__limits lim, spng_ctx **out, struct spng_ihdr *ihdr,
                              pf_error *err)
{
    *out = NULL;
    spng_ctx *ctx = spng_ctx_new(0);
    if (!ctx) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "PNG: out of memory creating the decoder");

    /* libspng takes limits up to 2^31 - 1 (the PNG maximum). */
    uint32_t side = lim.max_side > (uint32_t)INT32_MAX ? (uint32_t)INT32_MAX : lim.max_side;
    int r = spng_set_png_buffer(ctx, b, n);
    if (!r) r = spng_set_image_limits(ctx, side, side);
    if (!r) r = spng_set_chunk_limits(ctx, PF__PNG_CHUNK_MAX, PF__PNG_CHUNK_CACHE);
    /* A bad CRC on IHDR/PLTE/IDAT is an error; a damaged ancillary chunk is
     * dropped (it is never used). These are libspng's defaults, set here so
     * the policy is visible. libspng checks a CRC when it reaches the end of
     * a chunk and stops reading at the last image row, so a bad CRC on the
     * final IDAT goes unseen (PngSuite xcsn0g01 decodes); the zlib Adler-32
     * of the pixel data is still checked, so damaged pixels are refused. */
    if (!r) r = spng_set_crc_action(ctx, SPNG_CRC_ERROR, SPNG_CRC_DISCARD);
    if (r) {
        spng_ctx_free(ctx);
        return pf__fail(err, PF_ERR_TEXTURE, "PNG: ", spng_strerror(r));
    }

    r = spng_get_ihdr(ctx, ihdr);
    if (r == SPNG_EUSER_WIDTH || r == SPNG_EUSER_HEIGHT) {
        /* libspng refused the size against our limit; say which size, read
         * from the IHDR it has just parsed (bytes 16..23, big-endian). */
        spng_ctx_free(ctx);
        if (n >= 24) {
            uint32_t w = (uint32_t)b[16] << 24 | (uint32_t)b[17] << 16 | (uint32_t)b[18] << 8 | b[19];
            uint32_t h = (uint32_t)b[20] << 24 | (uint32_t)b[21] << 16 | (uint32_t)b[22] << 8 | b[23];
            pf_result c = pf__check_size("PNG: ", w, h, lim, err);
            if (c != PF_OK) return c;
        }
        return pf__fail(err, PF_ERR_TEXTURE, "PNG: ", spng_strerror(r));
    }
    if (r) {
        spng_ctx_free(ctx);
        return pf__fail(err, PF_ERR_TEXTURE, "PNG: ", spng_strerror(r));
    }

    pf_result c = pf__check_size("PNG: ", ihdr->width, ihdr->height, lim, err);
    if (c != PF_OK) {
        spng_ctx_free(ctx);
        return c;
    }
    *out = ctx;
    return PF_OK;
}

static pf_result pf__png_probe(const uint8_t *b, size_t n, pf__limits lim, uint32_t *w, uint32_t *h, pf_error *err)
{
    spng_ctx *ctx;
    struct spng_ihdr ihdr;
    pf_result c = pf__png_open(b, n, lim, &ctx, &ihdr, err);
    if (c != PF_OK) return c;
    spng_ctx_free(ctx);
    *w = ihdr.width;
    *h = ihdr.height;
    return PF_OK;
}

static pf_result pf__png_decode(const uint8_t *b, size_t n, pf__limits lim, uint8_t **rgba, uint32_t *w, uint32_t *h,
                                pf_error *err)
{
    spng_ctx *ctx;
    struct spng_ihdr ihdr;
    pf_result c = pf__png_open(b, n, lim, &ctx, &ihdr, err);
    if (c != PF_OK) return c;

    /* pf__check_size has bounded w*h*4 by SIZE_MAX; libspng's own figure
     * (which also checks for overflow) must agree with it. */
    uint64_t want = (uint64_t)ihdr.width * ihdr.height * 4u;
    size_t len = 0;
    int r = spng_decoded_image_size(ctx, SPNG_FMT_RGBA8, &len);
    if (r || (uint64_t)len != want) {
        spng_ctx_free(ctx);
        if (r) return pf__fail(err, PF_ERR_TEXTURE, "PNG: ", spng_strerror(r));
        return pf_error_set(err, PF_ERR_TEXTURE, "PNG: decoded size %zu does not match %ux%u RGBA8", len, ihdr.width,
                            ihdr.height);
    }

    uint8_t *px = malloc(len);
    if (!px) {
        spng_ctx_free(ctx);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "PNG: out of memory for %ux%u RGBA8 (%zu bytes)", ihdr.width,
                            ihdr.height, len);
    }
    /* SPNG_DECODE_TRNS applies tRNS; no SPNG_DECODE_GAMMA (bytes as stored). */
    r = spng_decode_image(ctx, px, len, SPNG_FMT_RGBA8, SPNG_DECODE_TRNS);
    spng_ctx_free(ctx);
    if (r) {
        free(px);
        return pf__fail(err, PF_ERR_TEXTURE, "PNG: ", spng_strerror(r));
    }
    *rgba = px;
    *w = ihdr.width;
    *h = ihdr.height;
    return PF_OK;
}

/* -------------------------------------------------------------------- JPEG */

/* tjDecompressHeader3 on an open handle: size, and whether the image is CMYK
 * (CMYK or YCCK colour space). Reads markers up to the first SOS only. */
static pf_result pf__jpeg_header(tjhandle tj, const uint8_t *b, size_t n, pf__limits lim, uint32_t *w, uint32_t *h,
                                 int *cmyk, pf_error *err)
{
    if ((uint64_t)n > (uint64_t)ULONG_MAX) return pf_error_set(err, PF_ERR_TEXTURE, "JPEG: file too large");
    int iw = 0, ih = 0, subsamp = -1, colorspace = -1;
    if (tjDecompressHeader3(tj, b, (unsigned long)n, &iw, &ih, &subsamp, &colorspace) != 0)
        return pf__fail(err, PF_ERR_TEXTURE, "JPEG: ", tjGetErrorStr2(tj));
    /* A tables-only stream (no frame) returns success without a size. */
    if (iw <= 0 || ih <= 0) return pf_error_set(err, PF_ERR_TEXTURE, "JPEG: no image in the data (tables only)");
    pf_result c = pf__check_size("JPEG: ", (uint64_t)iw, (uint64_t)ih, lim, err);
    if (c != PF_OK) return c;
    *w = (uint32_t)iw;
    *h = (uint32_t)ih;
    *cmyk = colorspace == TJCS_CMYK || colorspace == TJCS_YCCK;
    return PF_OK;
}

static pf_result pf__jpeg_probe(const uint8_t *b, size_t n, pf__limits lim, uint32_t *w, uint32_t *h, pf_error *err)
{
    tjhandle tj = tjInitDecompress();
    if (!tj) return pf__fail(err, PF_ERR_OUT_OF_MEMORY, "JPEG: ", tjGetErrorStr2(NULL));
    int cmyk;
    pf_result c = pf__jpeg_header(tj, b, n, lim, w, h, &cmyk, err);
    tjDestroy(tj);
    return c;
}

/* In place: Adobe-style CMYK as stored (255 = no ink) to RGBA, x*k/255
 * rounded: (x*k + 127) / 255 with x*k <= 65025, exact since 255 is odd. */
static void pf__cmyk_to_rgba(uint8_t *px, uint64_t pixels)
{
    for (uint64_t i = 0; i < pixels; i++, px += 4) {
        unsigned k = px[3];
        px[0] = (uint8_t)((px[0] * k + 127u) / 255u);
        px[1] = (uint8_t)((px[1] * k + 127u) / 255u);
        px[2] = (uint8_t)((px[2] * k + 127u) / 255u);
        px[3] = 255;
    }
}

static pf_result pf__jpeg_decode(const uint8_t *b, size_t n, pf__limits lim, uint8_t **rgba, uint32_t *w, uint32_t *h,
                                 pf_error *err)
{
    tjhandle tj = tjInitDecompress();
    if (!tj) return pf__fail(err, PF_ERR_OUT_OF_MEMORY, "JPEG: ", tjGetErrorStr2(NULL));
    uint32_t iw, ih;
    int cmyk;
    pf_result c = pf__jpeg_header(tj, b, n, lim, &iw, &ih, &cmyk, err);
    if (c != PF_OK) {
        tjDestroy(tj);
        return c;
    }

    /* pf__check_size bounded w*h*4 by SIZE_MAX; the pitch must fit an int
     * (JPEG sides are <= 65535, so 4*w always does). */
    uint64_t pitch = (uint64_t)iw * 4u;
    uint64_t bytes = pitch * ih;
    if (pitch > (uint64_t)INT_MAX || ih > (uint32_t)INT_MAX) {
        tjDestroy(tj);
        return pf_error_set(err, PF_ERR_TEXTURE, "JPEG: image is %ux%u pixels, too wide to decode", iw, ih);
    }
    uint8_t *px = malloc((size_t)bytes);
    if (!px) {
        tjDestroy(tj);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "JPEG: out of memory for %ux%u RGBA8 (%llu bytes)", iw, ih,
                            (unsigned long long)bytes);
    }
    /* The same width/height as the header, so TurboJPEG does not scale;
     * CMYK is 4 bytes a pixel too and is converted in place below. */
    const int flags = TJFLAG_ACCURATEDCT | TJFLAG_LIMITSCANS | TJFLAG_STOPONWARNING;
    int r = tjDecompress2(tj, b, (unsigned long)n, px, (int)iw, (int)pitch, (int)ih, cmyk ? TJPF_CMYK : TJPF_RGBA,
                          flags);
    if (r != 0) {
        pf__fail(err, PF_ERR_TEXTURE, "JPEG: ", tjGetErrorStr2(tj));
        tjDestroy(tj);
        free(px);
        return PF_ERR_TEXTURE;
    }
    tjDestroy(tj);
    if (cmyk) pf__cmyk_to_rgba(px, (uint64_t)iw * ih);
    *rgba = px;
    *w = iw;
    *h = ih;
    return PF_OK;
}

/* ------------------------------------------------------------------ public */

pf_image_format pf_decode_format(const void *bytes, size_t size)
{
    const uint8_t *b = bytes;
    if (!b) return PF_IMAGE_UNKNOWN;
    if (size >= sizeof pf__png_magic && memcmp(b, pf__png_magic, sizeof pf__png_magic) == 0) return PF_IMAGE_PNG;
    if (size >= sizeof pf__jpeg_magic && memcmp(b, pf__jpeg_magic, sizeof pf__jpeg_magic) == 0) return PF_IMAGE_JPEG;
    return PF_IMAGE_UNKNOWN;
}

pf_result pf_decode_probe(const void *bytes, size_t size, const pf_decode_limits *limits, pf_image_format *format,
                          uint32_t *w, uint32_t *h, pf_error *err)
{
    const uint8_t *b = bytes;
    if (!b) size = 0;
    pf_image_format f = pf_decode_format(b, size);
    uint32_t iw = 0, ih = 0;
    pf_result c;
    if (format) *format = f;
    if (w) *w = 0;
    if (h) *h = 0;

    pf__limits lim = pf__limits_resolve(limits);
    switch (f) {
    case PF_IMAGE_PNG: c = pf__png_probe(b, size, lim, &iw, &ih, err); break;
    case PF_IMAGE_JPEG: c = pf__jpeg_probe(b, size, lim, &iw, &ih, err); break;
    default: c = pf__refuse_format(b, size, err); break;
    }
    if (c != PF_OK) return c;
    if (w) *w = iw;
    if (h) *h = ih;
    return PF_OK;
}

pf_result pf_decode_rgba8(const void *bytes, size_t size, const pf_decode_limits *limits, uint8_t **rgba,
                          uint32_t *w, uint32_t *h, pf_error *err)
{
    const uint8_t *b = bytes;
    if (!b) size = 0;
    uint8_t *px = NULL;
    uint32_t iw = 0, ih = 0;
    pf_result c;
    *rgba = NULL;
    if (w) *w = 0;
    if (h) *h = 0;

    pf__limits lim = pf__limits_resolve(limits);
    switch (pf_decode_format(b, size)) {
    case PF_IMAGE_PNG: c = pf__png_decode(b, size, lim, &px, &iw, &ih, err); break;
    case PF_IMAGE_JPEG: c = pf__jpeg_decode(b, size, lim, &px, &iw, &ih, err); break;
    default: c = pf__refuse_format(b, size, err); break;
    }
    if (c != PF_OK) return c;
    *rgba = px;
    if (w) *w = iw;
    if (h) *h = ih;
    return PF_OK;
}
