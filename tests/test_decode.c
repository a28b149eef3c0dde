/* test_decode: pf_decode (PNG through libspng, JPEG through TurboJPEG) on
 * images made inside the test, good and hostile.
 *
 * PNGs are written by the tiny independent writer below (zlib "stored"
 * blocks, CRC-32 and Adler-32 by hand, filter 0, Adam7 done here), so the
 * expected RGBA8 values come from the PNG specification, not from libspng:
 *   grey of depth d < 8 -> v * 255 / (2^d - 1) (bit replication),
 *   16-bit             -> v >> 8 (what libspng does, see pf_decode.c),
 *   palette            -> PLTE entry, alpha = tRNS entry or 255,
 *   tRNS key on grey/RGB -> alpha 0 where the raw samples equal the key.
 * One more PNG goes through libspng's own encoder (compressed, all filters)
 * to cover inflate and defiltering. JPEGs are made with tjCompress2.
 *
 * Hostile inputs: the stb_image 2.27 DHT overflow (more than 256 Huffman
 * symbols), truncation at every length, a byte flipped at every offset,
 * 100000x100000 / 65000x65000 headers, a zTXt bomb, tables-only JPEG,
 * other formats. Every failure must give a one-line message, *rgba NULL and
 * (under the ASan build) no sanitizer report. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <spng.h>
#include <turbojpeg.h>

#include "pf_decode.h"

/* ------------------------------------------------------------------ helpers */

typedef struct bytes {
    uint8_t *p;
    size_t n, cap;
} bytes;

static void b_put(bytes *b, const void *d, size_t n)
{
    if (b->n + n > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->n + n) cap *= 2;
        b->p = realloc(b->p, cap);
        assert_non_null(b->p);
        b->cap = cap;
    }
    if (n) memcpy(b->p + b->n, d, n);
    b->n += n;
}

static void b_u8(bytes *b, uint8_t v) { b_put(b, &v, 1); }

static void b_u32be(bytes *b, uint32_t v)
{
    uint8_t t[4] = {(uint8_t)(v >> 24), (uint8_t)(v >> 16), (uint8_t)(v >> 8), (uint8_t)v};
    b_put(b, t, 4);
}

static uint32_t lcg_state;
static uint32_t lcg(void)
{
    lcg_state = lcg_state * 1664525u + 1013904223u;
    return lcg_state >> 8;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int contains(const char *hay, const char *needle) { return strstr(hay, needle) != NULL; }

/* A failing call: the code, a non-empty one-line message containing
 * `needle`, and no output. */
static void check_refused(pf_result got, pf_result want, const pf_error *e, const uint8_t *rgba, const char *needle)
{
    if (got != want)
        fail_msg("result %d (%s), expected %d (%s); message \"%s\"", got, pf_result_name(got), want,
                 pf_result_name(want), e->message);
    assert_int_equal(e->code, want);
    assert_true(e->message[0] != '\0');
    assert_null(strchr(e->message, '\n'));
    assert_null(rgba);
    if (needle && !contains(e->message, needle)) fail_msg("message \"%s\" lacks \"%s\"", e->message, needle);
}

/* Calls pf_decode_rgba8 / pf_decode_probe and checks the refusal. */
static void refuse_decode(const uint8_t *p, size_t n, const pf_decode_limits *lim, pf_result want, const char *needle,
                          pf_error *e)
{
    uint8_t *rgba = (uint8_t *)e; /* must come back NULL */
    uint32_t w = 1, h = 1;
    pf_result r = pf_decode_rgba8(p, n, lim, &rgba, &w, &h, e);
    check_refused(r, want, e, rgba, needle);
    assert_int_equal(w, 0);
    assert_int_equal(h, 0);
}

static pf_image_format refuse_probe(const uint8_t *p, size_t n, const pf_decode_limits *lim, pf_result want,
                                    const char *needle, pf_error *e)
{
    pf_image_format f = (pf_image_format)99;
    uint32_t w = 1, h = 1;
    pf_result r = pf_decode_probe(p, n, lim, &f, &w, &h, e);
    check_refused(r, want, e, NULL, needle);
    assert_int_equal(w, 0);
    assert_int_equal(h, 0);
    return f;
}

/* Probe and decode one buffer; either both fail cleanly or both succeed
 * with the same size. Returns 1 on success. Used by the robustness loops. */
static int decode_any(const uint8_t *p, size_t n, const pf_decode_limits *lim)
{
    pf_error pe = {0}, de = {0};
    pf_image_format f;
    uint32_t pw = 7, ph = 7, w = 7, h = 7;
    uint8_t *rgba = (uint8_t *)&pw; /* must be overwritten */
    pf_result pr = pf_decode_probe(p, n, lim, &f, &pw, &ph, &pe);
    pf_result dr = pf_decode_rgba8(p, n, lim, &rgba, &w, &h, &de);
    if (pr != PF_OK) {
        assert_true(pe.message[0] != '\0');
        assert_null(strchr(pe.message, '\n'));
        assert_int_equal(pw, 0);
    }
    if (dr != PF_OK) {
        assert_true(de.message[0] != '\0');
        assert_null(strchr(de.message, '\n'));
        assert_null(rgba);
        assert_int_equal(w, 0);
        return 0;
    }
    /* decode succeeded: the header was fine, so the probe was too */
    assert_int_equal(pr, PF_OK);
    assert_non_null(rgba);
    assert_int_equal(w, pw);
    assert_int_equal(h, ph);
    assert_true(w > 0 && h > 0);
    free(rgba);
    return 1;
}

/* ------------------------------------------------ an independent PNG writer */

static uint32_t crc32_png(uint32_t crc, const uint8_t *p, size_t n)
{
    crc = ~crc;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

static void png_chunk(bytes *b, const char *type, const uint8_t *data, size_t n)
{
    b_u32be(b, (uint32_t)n);
    size_t at = b->n;
    b_put(b, type, 4);
    b_put(b, data, n);
    b_u32be(b, crc32_png(0, b->p + at, n + 4));
}

/* zlib stream of "stored" (uncompressed) deflate blocks. */
static void zlib_stored(bytes *z, const uint8_t *raw, size_t n)
{
    b_u8(z, 0x78);
    b_u8(z, 0x01);
    size_t at = 0;
    do {
        size_t len = n - at > 65535 ? 65535 : n - at;
        b_u8(z, at + len == n ? 1 : 0);
        uint8_t h[4] = {(uint8_t)len, (uint8_t)(len >> 8), (uint8_t)~len, (uint8_t)(~len >> 8)};
        b_put(z, h, 4);
        b_put(z, raw + at, len);
        at += len;
    } while (at < n);
    uint32_t a = 1, s = 0;
    for (size_t i = 0; i < n; i++) {
        a = (a + raw[i]) % 65521u;
        s = (s + a) % 65521u;
    }
    b_u32be(z, s << 16 | a);
}

typedef struct png_spec {
    uint32_t w, h;
    uint8_t color_type, depth, interlace;
    const uint16_t *samples; /* w*h*channels, row-major */
    const uint8_t *plte;     /* plte_n RGB triplets */
    int plte_n;
    const uint8_t *trns; /* raw tRNS chunk data */
    int trns_n;
} png_spec;

static int png_channels(int ct) { return ct == 0 ? 1 : ct == 2 ? 3 : ct == 3 ? 1 : ct == 4 ? 2 : 4; }

static void png_ihdr(bytes *b, uint32_t w, uint32_t h, uint8_t depth, uint8_t ct, uint8_t interlace)
{
    bytes d = {0};
    b_u32be(&d, w);
    b_u32be(&d, h);
    uint8_t rest[5] = {depth, ct, 0, 0, interlace};
    b_put(&d, rest, 5);
    png_chunk(b, "IHDR", d.p, d.n);
    free(d.p);
}

static const uint8_t png_sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};

/* Adam7 passes: start x, start y, step x, step y (PNG spec Sec. 8.2). */
static const int adam7[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};

static uint8_t *png_encode(const png_spec *s, size_t *size, const char *extra_type, const uint8_t *extra,
                           size_t extra_n)
{
    const int ch = png_channels(s->color_type);
    bytes raw = {0};
    const int passes = s->interlace ? 7 : 1;
    for (int pass = 0; pass < passes; pass++) {
        uint32_t x0 = 0, y0 = 0, dx = 1, dy = 1;
        if (s->interlace) x0 = adam7[pass][0], y0 = adam7[pass][1], dx = adam7[pass][2], dy = adam7[pass][3];
        if (x0 >= s->w || y0 >= s->h) continue; /* empty pass: no filter bytes at all */
        for (uint32_t y = y0; y < s->h; y += dy) {
            b_u8(&raw, 0); /* filter type None */
            uint32_t acc = 0;
            int bits = 0;
            for (uint32_t x = x0; x < s->w; x += dx)
                for (int c = 0; c < ch; c++) {
                    uint16_t v = s->samples[((size_t)y * s->w + x) * ch + c];
                    if (s->depth == 16) {
                        b_u8(&raw, (uint8_t)(v >> 8));
                        b_u8(&raw, (uint8_t)v);
                    } else {
                        acc = acc << s->depth | v;
                        bits += s->depth;
                        if (bits == 8) b_u8(&raw, (uint8_t)acc), acc = 0, bits = 0;
                    }
                }
            if (bits) b_u8(&raw, (uint8_t)(acc << (8 - bits)));
        }
    }
    bytes z = {0}, out = {0};
    zlib_stored(&z, raw.p, raw.n);
    b_put(&out, png_sig, 8);
    png_ihdr(&out, s->w, s->h, s->depth, s->color_type, s->interlace);
    if (extra_type) png_chunk(&out, extra_type, extra, extra_n);
    if (s->plte_n) png_chunk(&out, "PLTE", s->plte, 3 * (size_t)s->plte_n);
    if (s->trns_n) png_chunk(&out, "tRNS", s->trns, (size_t)s->trns_n);
    /* two IDAT chunks, to cover a split stream */
    size_t half = z.n / 2;
    png_chunk(&out, "IDAT", z.p, half);
    png_chunk(&out, "IDAT", z.p + half, z.n - half);
    png_chunk(&out, "IEND", NULL, 0);
    free(raw.p);
    free(z.p);
    *size = out.n;
    return out.p;
}

/* RGBA8 by the PNG specification (and libspng's documented 16 -> 8 bits). */
static uint8_t to8(uint16_t v, int depth)
{
    if (depth == 16) return (uint8_t)(v >> 8);
    return (uint8_t)(v * 255u / ((1u << depth) - 1u));
}

static uint16_t be16(const uint8_t *p) { return (uint16_t)(p[0] << 8 | p[1]); }

static void png_expect(const png_spec *s, uint8_t *out)
{
    const int ch = png_channels(s->color_type);
    for (size_t i = 0; i < (size_t)s->w * s->h; i++, out += 4) {
        const uint16_t *v = &s->samples[i * ch];
        switch (s->color_type) {
        case 0:
            out[0] = out[1] = out[2] = to8(v[0], s->depth);
            out[3] = (s->trns_n == 2 && v[0] == be16(s->trns)) ? 0 : 255;
            break;
        case 2:
            for (int c = 0; c < 3; c++) out[c] = to8(v[c], s->depth);
            out[3] = (s->trns_n == 6 && v[0] == be16(s->trns) && v[1] == be16(s->trns + 2) &&
                      v[2] == be16(s->trns + 4))
                         ? 0
                         : 255;
            break;
        case 3:
            for (int c = 0; c < 3; c++) out[c] = s->plte[3 * v[0] + c];
            out[3] = (int)v[0] < s->trns_n ? s->trns[v[0]] : 255;
            break;
        case 4:
            out[0] = out[1] = out[2] = to8(v[0], s->depth);
            out[3] = to8(v[1], s->depth);
            break;
        default:
            for (int c = 0; c < 4; c++) out[c] = to8(v[c], s->depth);
            break;
        }
    }
}

static void assert_rgba_equal(const uint8_t *got, const uint8_t *want, uint32_t w, uint32_t h, const char *what)
{
    for (size_t i = 0; i < (size_t)w * h * 4; i++)
        if (got[i] != want[i])
            fail_msg("%s: pixel (%zu, %zu) channel %zu is %u, expected %u", what, (i / 4) % w, (i / 4) / w, i % 4,
                     got[i], want[i]);
}

/* Fills a spec with random samples of the right range, a palette and a
 * tRNS that hits at least one pixel. The caller frees spec->samples etc. */
typedef struct png_case {
    png_spec s;
    uint16_t *samples;
    uint8_t plte[768], trns[256];
} png_case;

static void png_case_make(png_case *pc, uint32_t w, uint32_t h, uint8_t ct, uint8_t depth, uint8_t interlace,
                          int with_trns, uint32_t seed)
{
    memset(pc, 0, sizeof *pc);
    lcg_state = seed;
    const int ch = png_channels(ct);
    const size_t n = (size_t)w * h * ch;
    pc->samples = malloc(n * sizeof(uint16_t) + 2);
    assert_non_null(pc->samples);
    int plte_n = 0;
    uint32_t range = depth == 16 ? 65536u : 1u << depth;
    if (ct == 3) {
        plte_n = depth == 8 ? 200 : (int)(1u << depth);
        range = (uint32_t)plte_n;
        for (int i = 0; i < 3 * plte_n; i++) pc->plte[i] = (uint8_t)lcg();
    }
    for (size_t i = 0; i < n; i++) pc->samples[i] = (uint16_t)(lcg() % range);
    /* 16-bit: include values where v >> 8 and round(v / 257) differ */
    if (depth == 16 && n > 2) pc->samples[1] = 0x12FF, pc->samples[2] = 0xFF7F;
    int trns_n = 0;
    if (with_trns) {
        const size_t key = ((size_t)w * h / 2) * ch; /* the middle pixel is the key */
        if (ct == 0) {
            pc->trns[0] = (uint8_t)(pc->samples[key] >> 8), pc->trns[1] = (uint8_t)pc->samples[key];
            trns_n = 2;
        } else if (ct == 2) {
            for (int c = 0; c < 3; c++)
                pc->trns[2 * c] = (uint8_t)(pc->samples[key + c] >> 8), pc->trns[2 * c + 1] = (uint8_t)pc->samples[key + c];
            trns_n = 6;
        } else if (ct == 3) {
            trns_n = plte_n / 2 + 1; /* shorter than the palette: the rest get 255 */
            for (int i = 0; i < trns_n; i++) pc->trns[i] = (uint8_t)lcg();
        }
    }
    pc->s = (png_spec){w, h, ct, depth, interlace, pc->samples, ct == 3 ? pc->plte : NULL, plte_n,
                       trns_n ? pc->trns : NULL, trns_n};
}

/* Encodes and decodes one case and compares every byte. */
static void png_roundtrip(const png_case *pc)
{
    char what[96];
    snprintf(what, sizeof what, "PNG %ux%u type %d depth %d%s%s", pc->s.w, pc->s.h, pc->s.color_type, pc->s.depth,
             pc->s.interlace ? " interlaced" : "", pc->s.trns_n ? " tRNS" : "");
    size_t n;
    uint8_t *png = png_encode(&pc->s, &n, NULL, NULL, 0);
    uint8_t *want = malloc((size_t)pc->s.w * pc->s.h * 4);
    png_expect(&pc->s, want);

    pf_error e = {0};
    pf_image_format f;
    uint32_t w, h;
    assert_int_equal(pf_decode_format(png, n), PF_IMAGE_PNG);
    if (pf_decode_probe(png, n, NULL, &f, &w, &h, &e) != PF_OK) fail_msg("%s: probe: %s", what, e.message);
    assert_int_equal(f, PF_IMAGE_PNG);
    assert_int_equal(w, pc->s.w);
    assert_int_equal(h, pc->s.h);
    uint8_t *rgba = NULL;
    if (pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("%s: decode: %s", what, e.message);
    assert_int_equal(w, pc->s.w);
    assert_int_equal(h, pc->s.h);
    assert_rgba_equal(rgba, want, w, h, what);
    free(rgba);
    free(want);
    free(png);
}

/* A PNG from the helpers above, for the tests that only need "some PNG". */
static uint8_t *small_png(uint32_t w, uint32_t h, uint8_t ct, uint8_t depth, size_t *n)
{
    png_case pc;
    png_case_make(&pc, w, h, ct, depth, 0, 0, 7);
    uint8_t *p = png_encode(&pc.s, n, NULL, NULL, 0);
    free(pc.samples);
    return p;
}

/* ------------------------------------------------------------ JPEG helpers */

static uint8_t *jpeg_encode(const uint8_t *px, int w, int h, int pf, int subsamp, int quality, int flags, size_t *n)
{
    tjhandle tj = tjInitCompress();
    assert_non_null(tj);
    unsigned char *out = NULL;
    unsigned long size = 0;
    if (tjCompress2(tj, px, w, 0, h, pf, &out, &size, subsamp, quality, flags) != 0)
        fail_msg("tjCompress2: %s", tjGetErrorStr2(tj));
    tjDestroy(tj);
    uint8_t *copy = malloc(size);
    memcpy(copy, out, size);
    tjFree(out);
    *n = size;
    return copy;
}

static uint8_t *jpeg_flat(int w, int h, uint8_t r, uint8_t g, uint8_t b, int subsamp, int flags, size_t *n)
{
    uint8_t *px = malloc((size_t)w * h * 3);
    for (int i = 0; i < w * h; i++) px[3 * i] = r, px[3 * i + 1] = g, px[3 * i + 2] = b;
    uint8_t *j = jpeg_encode(px, w, h, TJPF_RGB, subsamp, 95, flags, n);
    free(px);
    return j;
}

/* Offset of the first marker segment of type `marker` before SOS (the
 * offset of its 0xFF), or 0. */
static size_t jpeg_find(const uint8_t *j, size_t n, uint8_t marker)
{
    size_t p = 2;
    while (p + 4 <= n && j[p] == 0xFF) {
        uint8_t m = j[p + 1];
        if (m == marker) return p;
        if (m == 0xDA) break;
        p += 2 + (size_t)(j[p + 2] << 8 | j[p + 3]);
    }
    return 0;
}

static void assert_flat(const uint8_t *rgba, uint32_t w, uint32_t h, int r, int g, int b, int tol, const char *what)
{
    for (size_t i = 0; i < (size_t)w * h; i++) {
        const uint8_t *p = rgba + 4 * i;
        if (abs(p[0] - r) > tol || abs(p[1] - g) > tol || abs(p[2] - b) > tol || p[3] != 255)
            fail_msg("%s: pixel %zu = (%u, %u, %u, %u), expected (%d, %d, %d, 255) +-%d", what, i, p[0], p[1], p[2],
                     p[3], r, g, b, tol);
    }
}

/* =================================================================== tests */

/* Every colour type and bit depth, with and without tRNS, interlaced or not,
 * at sizes that leave Adam7 passes partial or empty and rows with padding
 * bits. */
static void test_png_all_formats_exact(void **state)
{
    (void)state;
    static const struct {
        uint8_t ct, depth;
    } fmts[] = {{0, 1}, {0, 2}, {0, 4}, {0, 8}, {0, 16}, {2, 8}, {2, 16}, {3, 1}, {3, 2},
                {3, 4}, {3, 8}, {4, 8}, {4, 16}, {6, 8}, {6, 16}};
    static const uint32_t sizes[][2] = {{13, 11}, {1, 1}, {3, 2}, {9, 1}, {1, 9}, {33, 17}};
    int cases = 0;
    for (size_t f = 0; f < sizeof fmts / sizeof fmts[0]; f++)
        for (int trns = 0; trns < 2; trns++) {
            if (trns && (fmts[f].ct == 4 || fmts[f].ct == 6)) continue; /* tRNS not allowed with alpha */
            for (int il = 0; il < 2; il++)
                for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
                    png_case pc;
                    png_case_make(&pc, sizes[s][0], sizes[s][1], fmts[f].ct, fmts[f].depth, (uint8_t)il, trns,
                                  (uint32_t)(1000 * f + 100 * trns + 10 * il + s));
                    png_roundtrip(&pc);
                    free(pc.samples);
                    cases++;
                }
        }
    assert_int_equal(cases, (15 + 11) * 2 * 6); /* 11 formats take tRNS */
}

/* The values of the conversions spelled out once, on a known 4x1 image. */
static void test_png_conversion_values(void **state)
{
    (void)state;
    uint8_t *rgba = NULL;
    uint32_t w, h;
    pf_error e = {0};
    size_t n;

    /* 2-bit grey 0,1,2,3 -> 0, 85, 170, 255; tRNS key 2 -> alpha 0 there */
    const uint16_t g2[4] = {0, 1, 2, 3};
    const uint8_t key2[2] = {0, 2};
    png_spec s = {4, 1, 0, 2, 0, g2, NULL, 0, key2, 2};
    uint8_t *png = png_encode(&s, &n, NULL, NULL, 0);
    assert_int_equal(pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e), PF_OK);
    const uint8_t want_g2[16] = {0, 0, 0, 255, 85, 85, 85, 255, 170, 170, 170, 0, 255, 255, 255, 255};
    assert_memory_equal(rgba, want_g2, 16);
    free(rgba);
    free(png);

    /* 16-bit RGB: libspng keeps the high byte (0x12FF -> 0x12 where rounding
     * gives 0x13; 0xFF00 -> 0xFF where rounding gives 0xFE) */
    const uint16_t rgb16[12] = {0x12FF, 0x0080, 0xFFFF, 0x0000, 0x00FF, 0x8000, 0xFF00, 0x7FFF, 0x1234,
                                0xABCD, 0x0101, 0xFEFF};
    png_spec s16 = {4, 1, 2, 16, 0, rgb16, NULL, 0, NULL, 0};
    png = png_encode(&s16, &n, NULL, NULL, 0);
    assert_int_equal(pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e), PF_OK);
    const uint8_t want16[16] = {0x12, 0x00, 0xFF, 255, 0x00, 0x00, 0x80, 255,
                                0xFF, 0x7F, 0x12, 255, 0xAB, 0x01, 0xFE, 255};
    assert_memory_equal(rgba, want16, 16);
    free(rgba);
    free(png);

    /* 1-bit palette with a 1-entry tRNS: index 0 gets alpha 7, index 1 gets 255 */
    const uint16_t idx[4] = {0, 1, 1, 0};
    const uint8_t plte[6] = {10, 20, 30, 200, 150, 100};
    const uint8_t trns[1] = {7};
    png_spec sp = {4, 1, 3, 1, 0, idx, plte, 2, trns, 1};
    png = png_encode(&sp, &n, NULL, NULL, 0);
    assert_int_equal(pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e), PF_OK);
    const uint8_t wantp[16] = {10, 20, 30, 7, 200, 150, 100, 255, 200, 150, 100, 255, 10, 20, 30, 7};
    assert_memory_equal(rgba, wantp, 16);
    free(rgba);
    free(png);
}

/* No gamma correction: a gAMA of 1.0 (and an sRGB chunk) leave bytes as stored. */
static void test_png_no_gamma(void **state)
{
    (void)state;
    png_case pc;
    png_case_make(&pc, 8, 8, 2, 8, 0, 0, 42);
    uint8_t *want = malloc(8 * 8 * 4);
    png_expect(&pc.s, want);
    const uint8_t gama[4] = {0, 1, 0x86, 0xA0}; /* 100000 = gamma 1.0 */
    size_t n;
    uint8_t *png = png_encode(&pc.s, &n, "gAMA", gama, 4);
    uint8_t *rgba = NULL;
    uint32_t w, h;
    pf_error e = {0};
    assert_int_equal(pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e), PF_OK);
    assert_rgba_equal(rgba, want, w, h, "PNG with gAMA 1.0");
    free(rgba);
    free(png);
    free(want);
    free(pc.samples);
}

/* libspng's encoder (deflate, adaptive filters, interlaced or not) -> exact. */
static void test_png_spng_encoder_roundtrip(void **state)
{
    (void)state;
    for (int il = 0; il < 2; il++) {
        const uint32_t W = 37, H = 23;
        uint8_t *img = malloc(W * H * 4);
        lcg_state = 99u + (uint32_t)il;
        for (uint32_t i = 0; i < W * H; i++) {
            /* smooth + noise, so every filter type gets chosen somewhere */
            uint32_t x = i % W, y = i / W;
            img[4 * i] = (uint8_t)(x * 7), img[4 * i + 1] = (uint8_t)(y * 11);
            img[4 * i + 2] = (uint8_t)lcg(), img[4 * i + 3] = (uint8_t)(x * y);
        }
        spng_ctx *enc = spng_ctx_new(SPNG_CTX_ENCODER);
        assert_non_null(enc);
        assert_int_equal(spng_set_option(enc, SPNG_ENCODE_TO_BUFFER, 1), 0);
        assert_int_equal(spng_set_option(enc, SPNG_FILTER_CHOICE, SPNG_FILTER_CHOICE_ALL), 0);
        struct spng_ihdr ihdr = {W, H, 8, SPNG_COLOR_TYPE_TRUECOLOR_ALPHA, 0, 0, (uint8_t)il};
        assert_int_equal(spng_set_ihdr(enc, &ihdr), 0);
        int r = spng_encode_image(enc, img, W * H * 4, SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
        if (r) fail_msg("spng_encode_image: %s", spng_strerror(r));
        size_t n = 0;
        uint8_t *png = spng_get_png_buffer(enc, &n, &r);
        assert_non_null(png);
        spng_ctx_free(enc);

        uint8_t *rgba = NULL;
        uint32_t w, h;
        pf_error e = {0};
        if (pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("%s", e.message);
        assert_int_equal(w, W);
        assert_int_equal(h, H);
        assert_rgba_equal(rgba, img, W, H, il ? "spng-encoded interlaced RGBA8" : "spng-encoded RGBA8");
        free(rgba);
        free(png);
        free(img);
    }
}

static void test_jpeg_flat_colour(void **state)
{
    (void)state;
    static const int subsamps[] = {TJSAMP_444, TJSAMP_422, TJSAMP_420};
    for (size_t s = 0; s < 3; s++)
        for (int prog = 0; prog < 2; prog++) {
            size_t n;
            uint8_t *j = jpeg_flat(16, 16, 200, 100, 50, subsamps[s], prog ? TJFLAG_PROGRESSIVE : 0, &n);
            assert_int_equal(pf_decode_format(j, n), PF_IMAGE_JPEG);
            pf_error e = {0};
            pf_image_format f;
            uint32_t w, h;
            assert_int_equal(pf_decode_probe(j, n, NULL, &f, &w, &h, &e), PF_OK);
            assert_int_equal(f, PF_IMAGE_JPEG);
            assert_int_equal(w, 16);
            assert_int_equal(h, 16);
            uint8_t *rgba = NULL;
            if (pf_decode_rgba8(j, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("%s", e.message);
            assert_int_equal(w, 16);
            assert_int_equal(h, 16);
            assert_flat(rgba, w, h, 200, 100, 50, 2, prog ? "progressive flat JPEG" : "flat JPEG");
            free(rgba);
            free(j);
        }
}

static void test_jpeg_grey(void **state)
{
    (void)state;
    const int W = 24, H = 16;
    uint8_t grey[24 * 16];
    for (int i = 0; i < W * H; i++) grey[i] = (uint8_t)(40 + 4 * (i % W) + (i / W)); /* smooth ramp */
    size_t n;
    uint8_t *j = jpeg_encode(grey, W, H, TJPF_GRAY, TJSAMP_GRAY, 100, 0, &n);
    uint8_t *rgba = NULL;
    uint32_t w, h;
    pf_error e = {0};
    if (pf_decode_rgba8(j, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("%s", e.message);
    assert_int_equal(w, W);
    assert_int_equal(h, H);
    for (int i = 0; i < W * H; i++) {
        const uint8_t *p = rgba + 4 * i;
        if (p[0] != p[1] || p[1] != p[2] || p[3] != 255)
            fail_msg("grey JPEG pixel %d = (%u, %u, %u, %u): not grey", i, p[0], p[1], p[2], p[3]);
        if (abs(p[0] - grey[i]) > 2) fail_msg("grey JPEG pixel %d = %u, encoded %u", i, p[0], grey[i]);
    }
    free(rgba);
    free(j);
}

/* CMYK (written by TurboJPEG as Adobe YCCK) -> R = C*K/255 etc. */
static void test_jpeg_cmyk(void **state)
{
    (void)state;
    const int W = 16, H = 16;
    uint8_t cmyk[16 * 16 * 4];
    for (int i = 0; i < W * H; i++) cmyk[4 * i] = 200, cmyk[4 * i + 1] = 150, cmyk[4 * i + 2] = 100, cmyk[4 * i + 3] = 220;
    size_t n;
    uint8_t *j = jpeg_encode(cmyk, W, H, TJPF_CMYK, TJSAMP_444, 95, 0, &n);
    uint8_t *rgba = NULL;
    uint32_t w, h;
    pf_error e = {0};
    if (pf_decode_rgba8(j, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("%s", e.message);
    /* 200*220/255 = 172.5, 150*220/255 = 129.4, 100*220/255 = 86.3; the
     * tolerance covers the JPEG error of two channels multiplied. */
    assert_flat(rgba, w, h, 173, 129, 86, 3, "CMYK JPEG");
    free(rgba);
    free(j);
}

/* Same bytes, same pixels: the ISLOW IDCT has no machine-dependent path. */
static void test_jpeg_deterministic(void **state)
{
    (void)state;
    const int W = 40, H = 24;
    uint8_t *px = malloc((size_t)W * H * 3);
    lcg_state = 5;
    for (int i = 0; i < W * H * 3; i++) px[i] = (uint8_t)lcg();
    size_t n;
    uint8_t *j = jpeg_encode(px, W, H, TJPF_RGB, TJSAMP_420, 80, 0, &n);
    uint8_t *a = NULL, *b = NULL;
    uint32_t w, h;
    pf_error e = {0};
    assert_int_equal(pf_decode_rgba8(j, n, NULL, &a, &w, &h, &e), PF_OK);
    assert_int_equal(pf_decode_rgba8(j, n, NULL, &b, &w, &h, &e), PF_OK);
    assert_memory_equal(a, b, (size_t)W * H * 4);
    free(a);
    free(b);
    free(j);
    free(px);
}

/* The stb_image 2.27 bug: a DHT whose 16 code-length counts sum to more
 * than 256 made stbi__build_huffman write past its 257-entry arrays. */
static void test_jpeg_dht_over_256_symbols(void **state)
{
    (void)state;
    size_t n;
    uint8_t *j = jpeg_flat(16, 16, 10, 200, 30, TJSAMP_420, 0, &n);
    size_t dht = jpeg_find(j, n, 0xC4);
    assert_true(dht > 0);
    const size_t seg_end = dht + 2 + (size_t)(j[dht + 2] << 8 | j[dht + 3]);

    /* sums 300 and 257 (one past stb's table), with the segment length
     * left as it was or made consistent (2 + 1 + 16 + sum) */
    static const struct {
        int sum, consistent;
    } over[] = {{300, 0}, {300, 1}, {257, 0}, {257, 1}};
    for (size_t v = 0; v < sizeof over / sizeof over[0]; v++) {
        uint8_t counts[16] = {0};
        counts[14] = 200, counts[15] = (uint8_t)(over[v].sum - 200);
        bytes m = {0};
        b_put(&m, j, dht + 5); /* up to and including Tc/Th */
        b_put(&m, counts, 16);
        if (over[v].consistent) {
            const size_t len = 2 + 1 + 16 + (size_t)over[v].sum;
            m.p[dht + 2] = (uint8_t)(len >> 8), m.p[dht + 3] = (uint8_t)len;
            for (int i = 0; i < over[v].sum; i++) b_u8(&m, (uint8_t)i);
            b_put(&m, j + seg_end, n - seg_end);
        } else {
            b_put(&m, j + dht + 21, n - (dht + 21));
        }
        pf_error e = {0};
        refuse_decode(m.p, m.n, NULL, PF_ERR_TEXTURE, "JPEG: Bogus Huffman table definition", &e);
        assert_int_equal(refuse_probe(m.p, m.n, NULL, PF_ERR_TEXTURE, "Huffman", &e), PF_IMAGE_JPEG);
        free(m.p);
    }

    /* <= 256 symbols but no such code (three codes of length 1): the header
     * is well formed, so probe passes; the decoder's table build refuses. */
    bytes m = {0};
    b_put(&m, j, dht + 5);
    m.p[dht + 2] = 0, m.p[dht + 3] = 2 + 1 + 16 + 3;
    const uint8_t bad[16 + 3] = {3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2};
    b_put(&m, bad, sizeof bad);
    b_put(&m, j + seg_end, n - seg_end);
    pf_error e = {0};
    refuse_decode(m.p, m.n, NULL, PF_ERR_TEXTURE, "Huffman", &e);
    free(m.p);
    free(j);
}

static void test_truncated_every_length(void **state)
{
    (void)state;
    size_t np, nj, ns;
    uint8_t *png = small_png(13, 11, 6, 8, &np);
    uint8_t *jpg = jpeg_flat(16, 16, 90, 120, 150, TJSAMP_420, 0, &nj);
    uint8_t *prog = jpeg_flat(16, 16, 90, 120, 150, TJSAMP_420, TJFLAG_PROGRESSIVE, &ns);
    const struct {
        const uint8_t *p;
        size_t n;
    } files[] = {{png, np}, {jpg, nj}, {prog, ns}};
    for (size_t f = 0; f < 3; f++) {
        int ok_full = 0;
        for (size_t len = 0; len <= files[f].n; len++) {
            /* a copy of exactly len bytes, so ASan sees any read past it */
            uint8_t *cut = malloc(len ? len : 1);
            memcpy(cut, files[f].p, len);
            int ok = decode_any(len ? cut : NULL, len, NULL);
            if (len == files[f].n) ok_full = ok;
            /* JPEG: cut before EOI must not decode (stop on warning) */
            if (f > 0 && len + 2 < files[f].n && ok) fail_msg("JPEG %zu cut at %zu of %zu decoded", f, len, files[f].n);
            free(cut);
        }
        assert_true(ok_full);
    }
    free(png);
    free(jpg);
    free(prog);
}

/* One byte changed at every offset (xor 0x55, then set to 0xFF). */
static void test_corrupt_every_byte(void **state)
{
    (void)state;
    size_t np, nj;
    uint8_t *png = small_png(9, 7, 3, 4, &np);
    uint8_t *jpg = jpeg_flat(16, 8, 250, 5, 128, TJSAMP_422, TJFLAG_PROGRESSIVE, &nj);
    const struct {
        uint8_t *p;
        size_t n;
    } files[] = {{png, np}, {jpg, nj}};
    for (size_t f = 0; f < 2; f++)
        for (size_t i = 0; i < files[f].n; i++)
            for (int k = 0; k < 2; k++) {
                uint8_t *c = malloc(files[f].n);
                memcpy(c, files[f].p, files[f].n);
                c[i] = k ? 0xFF : (uint8_t)(c[i] ^ 0x55);
                decode_any(c, files[f].n, NULL);
                free(c);
            }
    free(png);
    free(jpg);
}

/* A PNG CRC error in a critical chunk is fatal; in an ancillary chunk the
 * chunk is dropped and the image decodes. */
static void test_png_crc_policy(void **state)
{
    (void)state;
    png_case pc;
    png_case_make(&pc, 5, 4, 2, 8, 0, 0, 3);
    const char text[] = "Comment\0hello";
    size_t n;
    uint8_t *png = png_encode(&pc.s, &n, "tEXt", (const uint8_t *)text, sizeof text - 1);
    /* tEXt is the chunk after IHDR: its CRC is its last 4 bytes */
    size_t text_crc = 8 + 25 + 8 + (sizeof text - 1);
    uint8_t *rgba = NULL;
    uint32_t w, h;
    pf_error e = {0};
    png[text_crc] ^= 1;
    if (pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("bad tEXt CRC refused: %s", e.message);
    free(rgba);
    png[text_crc] ^= 1;
    /* the first IDAT's CRC: sits right before the second IDAT's length */
    size_t idat = 0;
    for (size_t i = 8; i + 8 < n; i++)
        if (memcmp(png + i + 4, "IDAT", 4) == 0) {
            idat = i;
            break;
        }
    assert_true(idat > 0);
    size_t idat_len = (size_t)png[idat] << 24 | (size_t)png[idat + 1] << 16 | (size_t)png[idat + 2] << 8 | png[idat + 3];
    png[idat + 8 + idat_len] ^= 1;
    refuse_decode(png, n, NULL, PF_ERR_TEXTURE, "PNG: ", &e);
    png[idat + 8 + idat_len] ^= 1;

    /* The last IDAT ends with the zlib Adler-32 and then its CRC, just
     * before IEND (12 bytes). libspng stops at the last image row, so it
     * never checks that CRC (documented in pf_decode.c) but it does check
     * the Adler-32 of the pixel data. */
    png[n - 12 - 1] ^= 1;
    if (pf_decode_rgba8(png, n, NULL, &rgba, &w, &h, &e) != PF_OK) fail_msg("last IDAT CRC: %s", e.message);
    free(rgba);
    png[n - 12 - 1] ^= 1;
    png[n - 12 - 4 - 1] ^= 1;
    refuse_decode(png, n, NULL, PF_ERR_TEXTURE, "PNG: ", &e);
    free(png);
    free(pc.samples);
}

/* A zTXt that inflates to 16 MiB is over the ancillary chunk limits. */
static void test_png_ztxt_bomb(void **state)
{
    (void)state;
    const size_t big = (size_t)16 << 20;
    char *text = malloc(big + 1);
    memset(text, ' ', big);
    text[big] = 0;
    uint8_t px[4 * 4 * 4] = {0};
    spng_ctx *enc = spng_ctx_new(SPNG_CTX_ENCODER);
    assert_int_equal(spng_set_option(enc, SPNG_ENCODE_TO_BUFFER, 1), 0);
    assert_int_equal(spng_set_option(enc, SPNG_TEXT_COMPRESSION_LEVEL, 9), 0);
    struct spng_ihdr ihdr = {4, 4, 8, SPNG_COLOR_TYPE_TRUECOLOR_ALPHA, 0, 0, 0};
    assert_int_equal(spng_set_ihdr(enc, &ihdr), 0);
    struct spng_text t = {.keyword = "Comment", .type = SPNG_ZTXT, .length = big, .text = text};
    int r = spng_set_text(enc, &t, 1);
    if (r) fail_msg("spng_set_text: %s", spng_strerror(r));
    r = spng_encode_image(enc, px, sizeof px, SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
    if (r) fail_msg("spng_encode_image: %s", spng_strerror(r));
    size_t n = 0;
    uint8_t *png = spng_get_png_buffer(enc, &n, &r);
    assert_non_null(png);
    spng_ctx_free(enc);
    free(text);
    assert_true(n < 200000); /* really a bomb: small on disk */

    pf_error e = {0};
    refuse_decode(png, n, NULL, PF_ERR_TEXTURE, "PNG: ", &e);
    assert_true(contains(e.message, "limit"));
    free(png);
}

/* Huge headers: refused by probe and decode, naming the limit, at once. */
static void test_huge_headers(void **state)
{
    (void)state;
    /* PNG, IHDR 100000x100000 RGBA8 (and 30000x30000: within the side limit,
     * over the pixel limit), followed by a tiny IDAT. */
    static const uint32_t sides[2] = {100000, 30000};
    for (int k = 0; k < 2; k++) {
        bytes b = {0};
        b_put(&b, png_sig, 8);
        png_ihdr(&b, sides[k], sides[k], 8, 6, 0);
        const uint8_t row[5] = {0};
        bytes z = {0};
        zlib_stored(&z, row, sizeof row);
        png_chunk(&b, "IDAT", z.p, z.n);
        png_chunk(&b, "IEND", NULL, 0);
        free(z.p);

        double t0 = now_s();
        pf_error e = {0};
        assert_int_equal(refuse_probe(b.p, b.n, NULL, PF_ERR_TEXTURE, "limit", &e), PF_IMAGE_PNG);
        refuse_decode(b.p, b.n, NULL, PF_ERR_TEXTURE, "limit", &e);
        assert_true(contains(e.message, k == 0 ? "100000x100000" : "30000x30000"));
        assert_true(contains(e.message, k == 0 ? "32768 pixels per side" : "67108864 pixels"));
        assert_true(now_s() - t0 < 2.0); /* microseconds in practice */
        free(b.p);
    }

    /* JPEG, SOF rewritten to 65000x65000 (and 9000x9000 = 81 Mpixels). */
    static const uint16_t jsides[2] = {65000, 9000};
    for (int k = 0; k < 2; k++) {
        size_t n;
        uint8_t *j = jpeg_flat(16, 16, 1, 2, 3, TJSAMP_420, 0, &n);
        size_t sof = jpeg_find(j, n, 0xC0);
        assert_true(sof > 0);
        j[sof + 5] = (uint8_t)(jsides[k] >> 8), j[sof + 6] = (uint8_t)jsides[k]; /* height */
        j[sof + 7] = (uint8_t)(jsides[k] >> 8), j[sof + 8] = (uint8_t)jsides[k]; /* width */
        double t0 = now_s();
        pf_error e = {0};
        assert_int_equal(refuse_probe(j, n, NULL, PF_ERR_TEXTURE, "limit", &e), PF_IMAGE_JPEG);
        refuse_decode(j, n, NULL, PF_ERR_TEXTURE, "limit", &e);
        assert_true(contains(e.message, k == 0 ? "65000x65000" : "9000x9000"));
        assert_true(now_s() - t0 < 2.0); /* microseconds in practice */
        free(j);
    }
}

static void test_limits_struct(void **state)
{
    (void)state;
    size_t np, nj;
    uint8_t *png = small_png(16, 16, 2, 8, &np);
    uint8_t *jpg = jpeg_flat(16, 16, 1, 2, 3, TJSAMP_444, 0, &nj);
    const uint8_t *files[2] = {png, jpg};
    const size_t sizes[2] = {np, nj};
    for (int f = 0; f < 2; f++) {
        pf_error e = {0};
        uint8_t *rgba = NULL;
        uint32_t w, h;
        pf_decode_limits side8 = {.max_side = 8};
        refuse_probe(files[f], sizes[f], &side8, PF_ERR_TEXTURE, "16x16 pixels, over the limit of 8 pixels per side", &e);
        refuse_decode(files[f], sizes[f], &side8, PF_ERR_TEXTURE, "over the limit of 8 pixels per side", &e);
        pf_decode_limits px255 = {.max_pixels = 255};
        refuse_probe(files[f], sizes[f], &px255, PF_ERR_TEXTURE, "256 pixels, over the limit of 255 pixels", &e);
        refuse_decode(files[f], sizes[f], &px255, PF_ERR_TEXTURE, "over the limit of 255 pixels", &e);
        /* exactly at the limits: accepted */
        pf_decode_limits exact = {.max_side = 16, .max_pixels = 256};
        assert_int_equal(pf_decode_rgba8(files[f], sizes[f], &exact, &rgba, &w, &h, &e), PF_OK);
        assert_non_null(rgba);
        free(rgba);
        pf_decode_limits zero = {0}; /* zero = defaults */
        assert_int_equal(pf_decode_rgba8(files[f], sizes[f], &zero, &rgba, &w, &h, &e), PF_OK);
        free(rgba);
    }
    free(png);
    free(jpg);
}

/* Probe reads the header only: a PNG cut after IHDR and a JPEG cut after
 * the SOS header probe fine and do not decode. */
static void test_probe_header_only(void **state)
{
    (void)state;
    size_t np, nj;
    uint8_t *png = small_png(6, 5, 0, 8, &np);
    uint8_t *jpg = jpeg_flat(32, 16, 1, 2, 3, TJSAMP_420, 0, &nj);
    size_t sos = 2;
    while (jpg[sos + 1] != 0xDA) sos += 2 + (size_t)(jpg[sos + 2] << 8 | jpg[sos + 3]);
    size_t sos_end = sos + 2 + (size_t)(jpg[sos + 2] << 8 | jpg[sos + 3]);
    const struct {
        const uint8_t *p;
        size_t n;
        uint32_t w, h;
    } cut[2] = {{png, 8 + 25, 6, 5}, {jpg, sos_end, 32, 16}};
    for (int f = 0; f < 2; f++) {
        pf_error e = {0};
        pf_image_format fmt;
        uint32_t w, h;
        if (pf_decode_probe(cut[f].p, cut[f].n, NULL, &fmt, &w, &h, &e) != PF_OK) fail_msg("%s", e.message);
        assert_int_equal(w, cut[f].w);
        assert_int_equal(h, cut[f].h);
        refuse_decode(cut[f].p, cut[f].n, NULL, PF_ERR_TEXTURE, f ? "JPEG: " : "PNG: ", &e);
    }
    free(png);
    free(jpg);
}

/* SOI, the tables, EOI: a valid abbreviated stream without an image. */
static void test_jpeg_tables_only(void **state)
{
    (void)state;
    size_t n;
    uint8_t *j = jpeg_flat(16, 16, 1, 2, 3, TJSAMP_420, 0, &n);
    bytes t = {0};
    b_put(&t, j, 2);
    size_t p = 2;
    while (j[p + 1] != 0xDA) {
        size_t len = 2 + (size_t)(j[p + 2] << 8 | j[p + 3]);
        if (j[p + 1] == 0xDB || j[p + 1] == 0xC4) b_put(&t, j + p, len);
        p += len;
    }
    const uint8_t eoi[2] = {0xFF, 0xD9};
    b_put(&t, eoi, 2);
    pf_error e = {0};
    refuse_probe(t.p, t.n, NULL, PF_ERR_TEXTURE, "JPEG: ", &e);
    refuse_decode(t.p, t.n, NULL, PF_ERR_TEXTURE, "JPEG: ", &e);
    free(t.p);
    free(j);
}

static void test_other_formats_refused(void **state)
{
    (void)state;
    static const uint8_t gif[] = "GIF89a\x01\x00\x01\x00\x80\x00\x00\xff\xff\xff\x00\x00\x00!\xf9\x04\x01";
    static const uint8_t bmp[] = "BM\x3a\x00\x00\x00\x00\x00\x00\x00\x36\x00\x00\x00\x28\x00\x00\x00";
    static const uint8_t webp[] = "RIFF\x1a\x00\x00\x00WEBPVP8L\x0d\x00\x00\x00";
    static const uint8_t ktx2[] = "\xABKTX 20\xBB\r\n\x1A\n\x00\x00\x00\x00";
    static const uint8_t png7[] = "\x89PNG\r\n\x1A"; /* 7 of the 8 signature bytes */
    uint8_t noise[256];
    lcg_state = 11;
    for (int i = 0; i < 256; i++) noise[i] = (uint8_t)lcg();
    noise[0] = 0x00;
    const struct {
        const uint8_t *p;
        size_t n;
        pf_result code;
        const char *name;
    } in[] = {
        {gif, sizeof gif - 1, PF_ERR_UNSUPPORTED, "GIF image"},
        {bmp, sizeof bmp - 1, PF_ERR_UNSUPPORTED, "BMP image"},
        {webp, sizeof webp - 1, PF_ERR_UNSUPPORTED, "WebP image"},
        {ktx2, sizeof ktx2 - 1, PF_ERR_UNSUPPORTED, "KTX2 image"},
        {noise, sizeof noise, PF_ERR_TEXTURE, NULL},
        {png7, sizeof png7 - 1, PF_ERR_TEXTURE, NULL},
        {noise, 0, PF_ERR_TEXTURE, "empty"},
        {NULL, 0, PF_ERR_TEXTURE, "empty"},
    };
    for (size_t i = 0; i < sizeof in / sizeof in[0]; i++) {
        assert_int_equal(pf_decode_format(in[i].p, in[i].n), PF_IMAGE_UNKNOWN);
        pf_error e = {0};
        assert_int_equal(refuse_probe(in[i].p, in[i].n, NULL, in[i].code,
                                      "not a PNG or JPEG image (glTF 2.0 allows only these)", &e),
                         PF_IMAGE_UNKNOWN);
        if (in[i].name) assert_true(contains(e.message, in[i].name));
        refuse_decode(in[i].p, in[i].n, NULL, in[i].code, "not a PNG or JPEG image", &e);
    }
    /* right magic, garbage after it: the library's reason, prefixed */
    uint8_t fake_png[64], fake_jpg[64];
    memcpy(fake_png, png_sig, 8);
    memset(fake_png + 8, 0xA5, 56);
    memcpy(fake_jpg, "\xFF\xD8\xFF", 3);
    memset(fake_jpg + 3, 0xA5, 61);
    pf_error e = {0};
    refuse_decode(fake_png, sizeof fake_png, NULL, PF_ERR_TEXTURE, "PNG: ", &e);
    assert_true(e.message == strstr(e.message, "PNG: "));
    refuse_decode(fake_jpg, sizeof fake_jpg, NULL, PF_ERR_TEXTURE, "JPEG: ", &e);
    assert_true(e.message == strstr(e.message, "JPEG: "));
}

/* Magic bytes only: the PNG signature or FF D8 FF, nothing else. */
static void test_format_magic(void **state)
{
    (void)state;
    assert_int_equal(pf_decode_format(png_sig, 8), PF_IMAGE_PNG);
    assert_int_equal(pf_decode_format(png_sig, 7), PF_IMAGE_UNKNOWN);
    assert_int_equal(pf_decode_format("\xFF\xD8\xFF", 3), PF_IMAGE_JPEG);
    assert_int_equal(pf_decode_format("\xFF\xD8\xFF", 2), PF_IMAGE_UNKNOWN);
    assert_int_equal(pf_decode_format("\xFF\xD8\x00", 3), PF_IMAGE_UNKNOWN);
    assert_int_equal(pf_decode_format(NULL, 100), PF_IMAGE_UNKNOWN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_magic),
        cmocka_unit_test(test_png_all_formats_exact),
        cmocka_unit_test(test_png_conversion_values),
        cmocka_unit_test(test_png_no_gamma),
        cmocka_unit_test(test_png_spng_encoder_roundtrip),
        cmocka_unit_test(test_png_crc_policy),
        cmocka_unit_test(test_png_ztxt_bomb),
        cmocka_unit_test(test_jpeg_flat_colour),
        cmocka_unit_test(test_jpeg_grey),
        cmocka_unit_test(test_jpeg_cmyk),
        cmocka_unit_test(test_jpeg_deterministic),
        cmocka_unit_test(test_jpeg_dht_over_256_symbols),
        cmocka_unit_test(test_jpeg_tables_only),
        cmocka_unit_test(test_truncated_every_length),
        cmocka_unit_test(test_corrupt_every_byte),
        cmocka_unit_test(test_huge_headers),
        cmocka_unit_test(test_limits_struct),
        cmocka_unit_test(test_probe_header_only),
        cmocka_unit_test(test_other_formats_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
