/* pf_exr: OpenEXR encode and decode through tinyexr, behind the C API of
 * pf_exr.h (formats, limits and why FLOAT samples: see there).
 *
 * tinyexr is C++ and reports failure by return code plus a message it
 * allocates; it may also throw std::bad_alloc from its std::vectors. Both
 * stop here: every entry point catches, frees what tinyexr allocated
 * (pf__exr_owner) and returns one pf_error line. */
#include "pf_exr.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#include <tinyexr.h>

namespace {

/* The header and image tinyexr filled in, freed on every path out. */
struct pf__exr_owner {
    EXRHeader header;
    EXRImage image;
    bool header_parsed = false, image_loaded = false;
    pf__exr_owner()
    {
        InitEXRHeader(&header);
        InitEXRImage(&image);
    }
    ~pf__exr_owner()
    {
        if (image_loaded) FreeEXRImage(&image);
        if (header_parsed) FreeEXRHeader(&header);
    }
    pf__exr_owner(const pf__exr_owner &) = delete;
    pf__exr_owner &operator=(const pf__exr_owner &) = delete;
};

/* tinyexr's message as one printable line (it may end in "\n" or hold
 * several), then freed. */
void pf__exr_reason(const char *msg, char *out, size_t size)
{
    size_t n = 0;
    if (msg) {
        for (const char *p = msg; *p && n + 1 < size; p++) {
            unsigned char c = (unsigned char)*p;
            out[n++] = c < 0x20 || c > 0x7e ? ' ' : (char)c;
        }
        FreeEXRErrorMessage(msg);
    }
    while (n > 0 && out[n - 1] == ' ') n--;
    out[n] = 0;
    if (n == 0) snprintf(out, size, "no reason given");
}

/* At most n bytes of a name from the file, printable ('?' for the rest), for
 * messages: a message is one line whatever the file holds. */
void pf__printable(const char *s, size_t n, char *out, size_t size)
{
    size_t k = 0;
    for (; k < n && s[k] && k + 1 < size; k++) out[k] = s[k] >= 0x20 && s[k] < 0x7f ? s[k] : '?';
    out[k] = 0;
}

uint64_t pf__le(const uint8_t *p, int bytes)
{
    uint64_t v = 0;
    for (int i = bytes - 1; i >= 0; i--) v = v << 8 | p[i];
    return v;
}

/* Scanlines per block of each compression softgi lets tinyexr decode; 0
 * for the others. PIZ is among the others: tinyexr 1.0.1's PIZ decoder
 * reads past the end of a block whose bitmap range or Huffman length lies
 * (found by fuzz_exr: tests/fuzz/regress/exr/crash-piz-bitmap-overread);
 * PXR24, B44, B44A, DWAA and DWAB tinyexr does not decode at all. */
int pf__lines_per_block(int compression)
{
    switch (compression) {
    case TINYEXR_COMPRESSIONTYPE_NONE:
    case TINYEXR_COMPRESSIONTYPE_RLE:
    case TINYEXR_COMPRESSIONTYPE_ZIPS: return 1;
    case TINYEXR_COMPRESSIONTYPE_ZIP: return 16;
    default: return 0;
    }
}

const char *pf__compression_name(int compression)
{
    static const char *const names[] = {"NONE", "RLE", "ZIPS", "ZIP", "PIZ", "PXR24", "B44", "B44A", "DWAA", "DWAB"};
    return compression >= 0 && compression < 10 ? names[compression] : "unknown";
}

/* tinyexr 1.0.1 asserts (aborts the program, also in Debian's build) when a
 * "type" attribute is not the kind of part the version field announced (found
 * by fuzz_exr: tests/fuzz/regress/exr/crash-type-attribute-assert). softgi
 * reads single-part scanline files, so a "type", if any, must say
 * "scanlineimage". The walk reads the attributes exactly as tinyexr's
 * ReadAttribute does (name, type, 32-bit size, value; a zero size only for a
 * string), so it sees every attribute tinyexr will; where tinyexr's own
 * parse fails cleanly it stops and lets tinyexr say why. */
pf_result pf__exr_check_type(const uint8_t *p, size_t size, const char *name, pf_error *err)
{
    size_t i = 8; /* after the magic number and the version field */
    for (int n = 0; n < TINYEXR_MAX_HEADER_ATTRIBUTES && i < size && p[i] != 0; n++) {
        const char *attr = (const char *)p + i;
        size_t nl = strnlen(attr, size - i), j = i + nl + 1; /* j: the attribute's type */
        if (nl == size - i || j >= size) return PF_OK;
        const char *type = (const char *)p + j;
        size_t tl = strnlen(type, size - j);
        if (tl == size - j) return PF_OK;
        j += tl + 1; /* the value's size */
        if (size - j < 4) return PF_OK;
        uint64_t len = pf__le(p + j, 4);
        j += 4;
        if ((len == 0 && strcmp(type, "string") != 0) || len > size - j) return PF_OK;
        if (!strcmp(attr, "type") && len > 0 && p[j] != 0) {
            size_t vl = strnlen((const char *)p + j, (size_t)len);
            if (vl != 13 || memcmp(p + j, "scanlineimage", 13) != 0) {
                char shown[40];
                pf__printable((const char *)p + j, vl, shown, sizeof shown);
                return pf_error_set(err, PF_ERR_UNSUPPORTED,
                                    "%s: OpenEXR part type '%s' is not supported (softgi reads scanline images)", name,
                                    shown);
            }
        }
        i = j + (size_t)len;
    }
    return PF_OK;
}

/* Where R, G, B (or Y, in all three) are among the file's channels. */
struct pf__exr_channels {
    int src[3];
};

pf_result pf__exr_pick_channels(const EXRHeader *hd, const char *name, pf__exr_channels *pick, pf_error *err)
{
    int r = -1, g = -1, b = -1, y = -1;
    if (hd->num_channels < 1) return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR file without channels", name);
    for (int c = 0; c < hd->num_channels; c++) {
        const EXRChannelInfo *ch = &hd->channels[c];
        char shown[64];
        pf__printable(ch->name, sizeof ch->name, shown, sizeof shown);
        if (ch->x_sampling != 1 || ch->y_sampling != 1)
            return pf_error_set(err, PF_ERR_UNSUPPORTED, "%s: channel '%s' is subsampled (%dx%d); softgi reads "
                                "only full-resolution channels", name, shown, ch->x_sampling, ch->y_sampling);
        if (hd->pixel_types[c] < TINYEXR_PIXELTYPE_UINT || hd->pixel_types[c] > TINYEXR_PIXELTYPE_FLOAT)
            return pf_error_set(err, PF_ERR_PARSE, "%s: channel '%s' has an unknown sample type %d", name, shown,
                                hd->pixel_types[c]);
        if (!strcmp(ch->name, "R")) r = c;
        else if (!strcmp(ch->name, "G")) g = c;
        else if (!strcmp(ch->name, "B")) b = c;
        else if (!strcmp(ch->name, "Y")) y = c;
    }
    if (r >= 0 && g >= 0 && b >= 0) pick->src[0] = r, pick->src[1] = g, pick->src[2] = b;
    else if (y >= 0) pick->src[0] = pick->src[1] = pick->src[2] = y;
    else
        return pf_error_set(err, PF_ERR_UNSUPPORTED,
                            "%s: OpenEXR file without R, G and B channels or a Y channel (softgi reads RGB or grey "
                            "images, not layers)",
                            name);
    return PF_OK;
}

/* The header against pf_exr.h's rules and desc's limits; *lines gets the
 * scanlines per block. */
pf_result pf__exr_check_header(const EXRHeader *hd, const pf_exr_read_desc *desc, int *lines, uint32_t *w,
                               uint32_t *h, pf_error *err)
{
    const char *name = desc->name;
    if (hd->tiled) return pf_error_set(err, PF_ERR_UNSUPPORTED, "%s: tiled OpenEXR files are not supported", name);
    if (hd->line_order != 0)
        return pf_error_set(err, PF_ERR_UNSUPPORTED,
                            "%s: OpenEXR line order %d is not supported (softgi reads increasing-y files)", name,
                            hd->line_order);
    *lines = pf__lines_per_block(hd->compression_type);
    if (*lines == 0)
        return pf_error_set(err, PF_ERR_UNSUPPORTED,
                            "%s: OpenEXR compression %s (%d) is not supported (softgi reads NONE, RLE, ZIPS and ZIP)",
                            name, pf__compression_name(hd->compression_type), hd->compression_type);
    const EXRBox2i *dw = &hd->data_window;
    int64_t ww = (int64_t)dw->max_x - dw->min_x + 1, hh = (int64_t)dw->max_y - dw->min_y + 1;
    if (ww < 1 || hh < 1 || ww > desc->max_side || hh > desc->max_side || (uint64_t)(ww * hh) > desc->max_pixels)
        return pf_error_set(err, PF_ERR_PARSE,
                            "%s: OpenEXR data window (%d, %d)-(%d, %d) is not an image of 1 to %u pixels a side and "
                            "at most %llu pixels",
                            name, dw->min_x, dw->min_y, dw->max_x, dw->max_y, desc->max_side,
                            (unsigned long long)desc->max_pixels);
    /* tinyexr's planes (4 bytes a sample once HALF is widened), one block's
     * decompression buffers, the RGB result */
    uint64_t bytes = (uint64_t)(ww * hh) * (4u * (uint64_t)hd->num_channels + 12u) +
                     2u * (uint64_t)ww * (uint64_t)*lines * 4u * (uint64_t)hd->num_channels;
    if (bytes > desc->max_bytes)
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY,
                            "%s: decoding this %lldx%lld OpenEXR image of %d channels needs %llu MiB, more than the "
                            "%llu MiB allowed",
                            name, (long long)ww, (long long)hh, hd->num_channels, (unsigned long long)(bytes >> 20),
                            (unsigned long long)(desc->max_bytes >> 20));
    *w = (uint32_t)ww;
    *h = (uint32_t)hh;
    return PF_OK;
}

/* Bytes of one uncompressed row: every channel's samples (HALF 2 bytes,
 * FLOAT and UINT 4). */
uint64_t pf__exr_row_bytes(const EXRHeader *hd, uint32_t w)
{
    uint64_t b = 0;
    for (int c = 0; c < hd->num_channels; c++) b += hd->pixel_types[c] == TINYEXR_PIXELTYPE_HALF ? 2u : 4u;
    return b * w;
}

/* Every block of scanlines present, in its own place, and no larger than
 * its scanlines uncompressed (exactly that size without compression):
 * tinyexr 1.0.1 reads a UINT sample of an uncompressed block that ends
 * early up to 3 bytes past the block (found by fuzz_exr:
 * tests/fuzz/regress/exr/crash-none-uint-overread). */
pf_result pf__exr_check_offsets(const EXRHeader *hd, const uint8_t *p, size_t size, int lines, uint32_t w, uint32_t h,
                                const char *name, pf_error *err)
{
    const uint64_t row = pf__exr_row_bytes(hd, w);
    const uint64_t blocks = (h + (uint64_t)lines - 1) / (uint64_t)lines;
    if (hd->chunk_count != 0 && (uint64_t)hd->chunk_count != blocks)
        return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR chunkCount %d, the image has %llu blocks", name,
                            hd->chunk_count, (unsigned long long)blocks);
    const uint64_t table = 8u + (uint64_t)hd->header_len, first = table + 8u * blocks;
    if (first + 8u > size)
        return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR offset table of %llu blocks is cut off", name,
                            (unsigned long long)blocks);
    for (uint64_t k = 0; k < blocks; k++) {
        uint64_t off = pf__le(p + table + 8u * k, 8);
        if (off < first || off > size - 8u)
            return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR block %llu: offset %llu lies outside the data", name,
                                (unsigned long long)k, (unsigned long long)off);
        int64_t line = (int32_t)(uint32_t)pf__le(p + off, 4);
        int64_t want = (int64_t)hd->data_window.min_y + (int64_t)k * lines;
        int64_t len = (int32_t)(uint32_t)pf__le(p + off + 4u, 4);
        if (line != want)
            return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR block %llu starts at scanline %lld, expected %lld",
                                name, (unsigned long long)k, (long long)line, (long long)want);
        if (len <= 0 || (uint64_t)len > size - off - 8u)
            return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR block %llu: %lld bytes of data do not fit the file",
                                name, (unsigned long long)k, (long long)len);
        const uint64_t rows = (uint64_t)h - k * (uint64_t)lines < (uint64_t)lines ? h - k * lines : (uint64_t)lines;
        const uint64_t raw = rows * row;
        if ((uint64_t)len > raw || (hd->compression_type == TINYEXR_COMPRESSIONTYPE_NONE && (uint64_t)len != raw))
            return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR block %llu holds %lld bytes, %s the %llu of its %llu "
                                "scanlines uncompressed", name, (unsigned long long)k, (long long)len,
                                (uint64_t)len > raw ? "more than" : "not", (unsigned long long)raw,
                                (unsigned long long)rows);
    }
    return PF_OK;
}

/* One sample of channel c at pixel i as a float (HALF was widened to FLOAT
 * by tinyexr; UINT is converted here, exact below 2^24). */
float pf__exr_sample(const EXRHeader *hd, const EXRImage *im, int c, size_t i)
{
    if (hd->requested_pixel_types[c] == TINYEXR_PIXELTYPE_UINT) {
        uint32_t u;
        memcpy(&u, im->images[c] + 4 * i, 4);
        return (float)u;
    }
    float f;
    memcpy(&f, im->images[c] + 4 * i, 4);
    return f;
}

pf_result pf__exr_decode(const uint8_t *p, size_t size, const pf_exr_read_desc *desc, float **rgb, uint32_t *w_out,
                         uint32_t *h_out, pf_error *err)
{
    const char *name = desc->name ? desc->name : "OpenEXR data";
    char reason[256];
    if (!pf_exr_is_exr(p, size))
        return pf_error_set(err, PF_ERR_PARSE, "%s: not an OpenEXR file (it must start with 76 2f 31 01)", name);
    EXRVersion ver;
    if (ParseEXRVersionFromMemory(&ver, p, size) != TINYEXR_SUCCESS)
        return pf_error_set(err, PF_ERR_PARSE, "%s: bad OpenEXR version field", name);
    if (ver.multipart || ver.non_image)
        return pf_error_set(err, PF_ERR_UNSUPPORTED, "%s: multi-part and deep OpenEXR files are not supported", name);
    if (ver.tiled) return pf_error_set(err, PF_ERR_UNSUPPORTED, "%s: tiled OpenEXR files are not supported", name);
    pf_result r = pf__exr_check_type(p, size, name, err);
    if (r != PF_OK) return r;
    pf__exr_owner o;
    const char *msg = NULL;
    int rc = ParseEXRHeaderFromMemory(&o.header, &ver, p, size, &msg);
    o.header_parsed = true; /* FreeEXRHeader is safe on a partly filled header */
    if (rc != TINYEXR_SUCCESS) {
        pf__exr_reason(msg, reason, sizeof reason);
        return pf_error_set(err, PF_ERR_PARSE, "%s: bad OpenEXR header: %s", name, reason);
    }
    int lines = 0;
    uint32_t w = 0, h = 0;
    pf__exr_channels pick = {{0, 0, 0}};
    r = pf__exr_check_header(&o.header, desc, &lines, &w, &h, err);
    if (r == PF_OK) r = pf__exr_pick_channels(&o.header, name, &pick, err);
    if (r == PF_OK) r = pf__exr_check_offsets(&o.header, p, size, lines, w, h, name, err);
    if (r != PF_OK) return r;
    for (int c = 0; c < o.header.num_channels; c++)
        if (o.header.pixel_types[c] == TINYEXR_PIXELTYPE_HALF)
            o.header.requested_pixel_types[c] = TINYEXR_PIXELTYPE_FLOAT;
    /* tinyexr 1.0.1 frees a failed decode with FreeEXRImage, which frees one
     * plane per image.num_channels, a field it sets only on success: set
     * here, the planes of a file that fails half-way are not leaked (found by
     * fuzz_exr; tests/fuzz/regress/exr/leak-*) */
    o.image.num_channels = o.header.num_channels;
    msg = NULL;
    rc = LoadEXRImageFromMemory(&o.image, &o.header, p, size, &msg);
    if (rc != TINYEXR_SUCCESS) { /* tinyexr freed the image itself (its pointers dangle: not freed again) */
        pf__exr_reason(msg, reason, sizeof reason);
        return pf_error_set(err, PF_ERR_PARSE, "%s: bad OpenEXR data: %s", name, reason);
    }
    o.image_loaded = true;
    if (!o.image.images || (uint32_t)o.image.width != w || (uint32_t)o.image.height != h)
        return pf_error_set(err, PF_ERR_PARSE, "%s: OpenEXR decoder returned no image of %ux%u", name, w, h);
    float *out = (float *)malloc((size_t)w * h * 3 * sizeof(float));
    if (!out) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory for %ux%u pixels", name, w, h);
    for (size_t i = 0; i < (size_t)w * h; i++)
        for (int k = 0; k < 3; k++) out[3 * i + k] = pf__exr_sample(&o.header, &o.image, pick.src[k], i);
    *rgb = out;
    *w_out = w;
    *h_out = h;
    return PF_OK;
}

pf_result pf__exr_encode(const float *px, uint32_t w, uint32_t h, uint32_t channels, const char *comment,
                         uint8_t **bytes, size_t *size, pf_error *err)
{
    /* the file lists channels alphabetically: A B G R (src: index in a pixel) */
    static const char *const names[4][4] = {{"Y"}, {0}, {"B", "G", "R"}, {"A", "B", "G", "R"}};
    static const int src[4][4] = {{0}, {0}, {2, 1, 0}, {3, 2, 1, 0}};
    if (!(channels == 1 || channels == 3 || channels == 4) || w == 0 || h == 0 || w > 1u << 24 || h > 1u << 24)
        return pf_error_set(err, PF_ERR_ARGUMENT, "OpenEXR: cannot encode %ux%u pixels of %u channels", w, h,
                            channels);
    const size_t n = (size_t)w * h;
    float *planes = (float *)malloc(n * channels * sizeof(float));
    if (!planes) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "OpenEXR: out of memory for %ux%u pixels", w, h);
    unsigned char *plane_ptr[4];
    EXRChannelInfo info[4];
    int types[4], requested[4];
    memset(info, 0, sizeof info);
    for (uint32_t c = 0; c < channels; c++) {
        float *dst = planes + c * n;
        for (size_t i = 0; i < n; i++) dst[i] = px[i * channels + (size_t)src[channels - 1][c]];
        plane_ptr[c] = (unsigned char *)dst;
        snprintf(info[c].name, sizeof info[c].name, "%s", names[channels - 1][c]);
        types[c] = requested[c] = TINYEXR_PIXELTYPE_FLOAT;
    }
    EXRHeader hd;
    EXRImage im;
    InitEXRHeader(&hd);
    InitEXRImage(&im);
    hd.num_channels = (int)channels;
    hd.channels = info;
    hd.pixel_types = types;
    hd.requested_pixel_types = requested;
    hd.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;
    EXRAttribute note;
    memset(&note, 0, sizeof note);
    if (comment && comment[0]) {
        snprintf(note.name, sizeof note.name, "comments");
        snprintf(note.type, sizeof note.type, "string");
        note.value = (unsigned char *)comment;
        note.size = (int)strnlen(comment, 4096);
        hd.num_custom_attributes = 1;
        hd.custom_attributes = &note;
    }
    im.images = plane_ptr;
    im.width = (int)w;
    im.height = (int)h;
    im.num_channels = (int)channels;
    unsigned char *mem = NULL;
    const char *msg = NULL;
    size_t got = SaveEXRImageToMemory(&im, &hd, &mem, &msg); /* hd and im are ours: not freed by tinyexr calls */
    free(planes);
    if (got == 0 || !mem) {
        char reason[256];
        pf__exr_reason(msg, reason, sizeof reason);
        free(mem);
        return pf_error_set(err, PF_ERR_IO, "OpenEXR: encoding %ux%u pixels failed: %s", w, h, reason);
    }
    *bytes = mem;
    *size = got;
    return PF_OK;
}

} // namespace

extern "C" {

int pf_exr_is_exr(const void *data, size_t size)
{
    return size >= 4 && memcmp(data, PF_EXR_MAGIC, 4) == 0;
}

void pf_exr_free(void *bytes) { free(bytes); }

pf_result pf_exr_encode(const float *px, uint32_t w, uint32_t h, uint32_t channels, const char *comment,
                        uint8_t **bytes, size_t *size, pf_error *err)
{
    *bytes = NULL;
    *size = 0;
    try {
        return pf__exr_encode(px, w, h, channels, comment, bytes, size, err);
    } catch (const std::bad_alloc &) {
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "OpenEXR: out of memory encoding %ux%u pixels", w, h);
    } catch (...) {
        return pf_error_set(err, PF_ERR_IO, "OpenEXR: encoding %ux%u pixels failed", w, h);
    }
}

pf_result pf_exr_decode(const void *data, size_t size, const pf_exr_read_desc *desc, float **rgb, uint32_t *w,
                        uint32_t *h, pf_error *err)
{
    *rgb = NULL;
    *w = *h = 0;
    const char *name = desc->name ? desc->name : "OpenEXR data";
    try {
        return pf__exr_decode((const uint8_t *)data, size, desc, rgb, w, h, err);
    } catch (const std::bad_alloc &) {
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory decoding the OpenEXR image", name);
    } catch (...) {
        return pf_error_set(err, PF_ERR_PARSE, "%s: the OpenEXR decoder failed", name);
    }
}

} // extern "C"
