/* pf_imageio: writing and reading the files softgi produces.
 *
 * - PNG (8-bit sRGB) through stb_image_write (libstb-dev): linear RGB is
 *   multiplied by 2^exposure, tone mapped per channel with Reinhard's
 *   x / (1 + x), then sRGB-encoded. This is the display output.
 * - PFM (Portable Float Map, "PF", little-endian, bottom row first): the
 *   linear HDR output, bit-exact floats, readable by every HDR tool.
 * - pf_imageio_hash: FNV-1a 64 over the float bits of a linear buffer; what
 *   `--hash` prints and the golden tests compare.
 *
 * Buffers are row-major from the top row, 3 floats per pixel (RGB).
 *
 * Outputs are never partial, never misplaced, never wrong
 * ------------------------------------------------------
 * Every file softgi writes (images, stage dumps, sequence frames, manifests,
 * tables, plots) goes through pf_file:
 *   1. pf_file_begin creates the parent folders, then a temporary file
 *      beside the target (mkstemp of "DIR/.NAME.tmp-XXXXXX", so the rename
 *      below stays within one file system), with the mode fopen would give
 *      (0666 & ~umask);
 *   2. pf_file_write writes all of its bytes (short writes and EINTR
 *      retried); every write, fsync and close is checked;
 *   3. pf_file_commit fsyncs the temporary file (so a power cut after the
 *      rename cannot leave an empty or partial file where the old one was;
 *      0.4 ms a file on the CI VM's ext4), closes it and rename()s it over
 *      the target. The folder itself is not fsynced: after a power cut the
 *      rename may be lost, and then the old file is still whole.
 * Any failure removes the temporary file, leaves the target untouched and
 * fills the pf_error with one line naming the target and the reason
 * (strerror), e.g. "out/a.png: write failed: No space left on device"; the
 * pf_file is then closed (pf_file_abort is harmless after it).
 * Targets:
 *   - missing or a regular file: replaced as above. An existing read-only
 *     file is refused (EACCES), as fopen would. A symbolic link at the
 *     target is replaced by the new file, never written through (a link
 *     planted in a shared folder cannot redirect the write).
 *   - an existing character device or FIFO (/dev/null, /dev/full, a pipe;
 *     also through a symbolic link): there is nothing to replace, and a
 *     rename over /dev/full would replace the device node. The bytes are
 *     written to it directly, every write and the close checked
 *     ("/dev/full: write failed: No space left on device"); fsync is skipped.
 *   - anything else (a folder, a block device, a socket) is refused.
 *
 * What the writers accept (PF_ERR_NONFINITE otherwise, nothing written):
 * radiance images must be finite and >= 0 in every channel; the message
 * counts the bad pixels and names the first one, e.g.
 *   "out/a.pfm: 3 pixels are NaN, infinite or negative (first: pixel (4, 7)
 *    channel G = nan); nothing written".
 * Depth planes (gi_metrics.h) use PF_IMAGEIO_DEPTH: >= 0 or +inf (no
 * surface). Readers apply the same rules to what they read.
 *
 * - OpenEXR (pf_exr.h: tinyexr; single-part scanline, 32-bit FLOAT
 *   channels, ZIP): the linear HDR output like the PFM, bit-exact floats,
 *   read back bit for bit; also the float stage dumps (RGB, RGBA or Y).
 *
 * Output names: the format is the file's extension (case-insensitive),
 * PF_IMAGEIO_OUTPUT_HELP lists them: -o NAME.png writes the PNG and the
 * linear image beside it (NAME.pfm, or --hdr NAME.exr / NAME.pfm); -o
 * NAME.exr and -o NAME.pfm write only that linear image; any other name is
 * refused with the list (pf_imageio_outputs_resolve).
 *
 * Input (`softgi compare IMAGE REFERENCE`): pf_imageio_read_image
 * reads a PFM or an OpenEXR file, told apart by their first bytes, within
 * the same size limits and the memory budget (pf_budget.h).
 *
 * PFM input limits: "PF" (RGB) or "Pf" (grey, read into R = G = B); width
 * and height 1..PF_IMAGEIO_MAX_SIDE, at most PF_IMAGEIO_MAX_PIXELS pixels;
 * the scale a finite non-zero number (its sign is the byte order, its
 * magnitude is ignored, as by most tools); the header is the four tokens
 * separated by whitespace, then one whitespace byte ("\r\n" is taken as
 * one); the data exactly width x height x channels floats. Sizes are checked
 * against the bytes present before anything is allocated. */
#ifndef PF_IMAGEIO_H
#define PF_IMAGEIO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "pf_result.h"

#define PF_IMAGEIO_MAX_SIDE 32768u
#define PF_IMAGEIO_MAX_PIXELS (1u << 28)
#define PF_IMAGEIO_PATH_MAX 4096

/* What values a buffer may hold. */
typedef enum pf_imageio_range {
    PF_IMAGEIO_RADIANCE = 0, /* finite and >= 0: every image (the default of the plain functions) */
    PF_IMAGEIO_DEPTH,        /* >= 0 or +inf (no surface): view-depth planes */
    PF_IMAGEIO_DATA,         /* anything but NaN: stage dumps (positions, normals, depth with +inf) */
} pf_imageio_range;

/* Image file formats, by extension (pf_imageio_format_of). */
typedef enum pf_imageio_format {
    PF_IMAGEIO_UNKNOWN = 0,
    PF_IMAGEIO_PNG, /* 8-bit sRGB, tone mapped */
    PF_IMAGEIO_PFM, /* linear float */
    PF_IMAGEIO_EXR, /* linear float, OpenEXR */
} pf_imageio_format;

/* The accepted output names, for help texts and messages. */
#define PF_IMAGEIO_OUTPUT_HELP \
    ".png (with the linear .pfm beside it, or --hdr NAME.exr|NAME.pfm), .exr or .pfm"

/* The format the name of `path` asks for (case-insensitive extension). */
pf_imageio_format pf_imageio_format_of(const char *path);

/* ---------------------------------------------------------------- files */

/* One output file being written (see "Outputs are never partial" above).
 * Zero-initialised or aborted: closed. */
typedef struct pf_file {
    int fd;                          /* valid while `open` */
    int open;
    int direct;                      /* writing a character device / FIFO in place */
    char path[PF_IMAGEIO_PATH_MAX];  /* the target */
    char tmp[PF_IMAGEIO_PATH_MAX];   /* the temporary file ("" when direct) */
} pf_file;

pf_result pf_file_begin(pf_file *f, const char *path, pf_error *err);
/* All `size` bytes or an error (then the file is aborted). */
pf_result pf_file_write(pf_file *f, const void *data, size_t size, pf_error *err);
/* fsync, close, rename over the target (or close a direct target). */
pf_result pf_file_commit(pf_file *f, pf_error *err);
/* Closes and removes the temporary file; the target is untouched. */
void pf_file_abort(pf_file *f);

/* `size` bytes as the whole file `path` (begin, write, commit). */
pf_result pf_imageio_write_file(const char *path, const void *data, size_t size, pf_error *err);
/* A text file: `print` writes it to a memory stream (returns 0 on success);
 * the text is then written as one file. */
pf_result pf_imageio_write_text(const char *path, int (*print)(FILE *f, void *user), void *user, pf_error *err);

/* Reads the whole file `path` (at most `limit` bytes; a regular file's size
 * is checked before anything is read) into *data (malloc'ed, free() it).
 * `what` names the kind of file in messages ("PFM image", "sequence file"). */
pf_result pf_imageio_read_file(const char *path, uint64_t limit, const char *what, char **data, size_t *size,
                               pf_error *err);

/* Creates the parent directories of `path` (like mkdir -p of dirname). */
pf_result pf_imageio_make_parent_dirs(const char *path, pf_error *err);
/* Creates base/rel as a folder inside `base` for input from strangers (a
 * sequence file's "output"): rel must be relative without ".." components;
 * `base` is created if missing; every component of rel is created or opened
 * without following symbolic links, and the realpath of the result must lie
 * inside the realpath of base. The path "base/rel" goes to out. */
pf_result pf_imageio_make_dir_inside(const char *base, const char *rel, char *out, size_t out_size, pf_error *err);
/* 1 when the two paths name the same file for a writer: the same folder
 * (after symbolic links and "..", where it exists) and the same name. */
int pf_imageio_same_output(const char *a, const char *b);

/* ---------------------------------------------------------------- images */

/* The image files of one render. */
typedef struct pf_imageio_outputs {
    char png[PF_IMAGEIO_PATH_MAX];    /* the display PNG; "" when none */
    char linear[PF_IMAGEIO_PATH_MAX]; /* the linear image: a .pfm or an .exr */
} pf_imageio_outputs;

/* The files of -o/--output and --hdr (`output` NULL: default_png),
 * extensions case-insensitive:
 *   NAME.png            -> png = NAME.png, linear = --hdr or NAME.pfm
 *   NAME.exr, NAME.pfm  -> only that linear image (png = ""); --hdr refused
 *   other               -> PF_ERR_ARGUMENT naming PF_IMAGEIO_OUTPUT_HELP
 * --hdr must end in .exr or .pfm; two outputs naming the same file are
 * refused. */
pf_result pf_imageio_outputs_resolve(pf_imageio_outputs *out, const char *output, const char *hdr,
                                     const char *default_png, pf_error *err);
/* Writes the files of `out` (rgb: w x h linear RGB): every one to its
 * temporary file first, then all renamed, so either all are replaced or
 * none. */
pf_result pf_imageio_outputs_write(const pf_imageio_outputs *out, const float *rgb, uint32_t w, uint32_t h,
                                   float exposure, pf_error *err);
/* PF_OK when every value of the w x h x 3 buffer is within `range`; else
 * PF_ERR_NONFINITE with "<name>: N pixels are ... (first: pixel (x, y) ...)". */
pf_result pf_imageio_check(const char *name, const float *rgb, uint32_t w, uint32_t h, pf_imageio_range range,
                           pf_error *err);

pf_result pf_imageio_write_png(const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure,
                               pf_error *err);
/* An already display-encoded 8-bit RGB image (the viewer's stage views),
 * with the same encoder and settings as pf_imageio_write_png. */
pf_result pf_imageio_write_png_rgb8(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h, pf_error *err);
pf_result pf_imageio_write_pfm(const char *path, const float *rgb, uint32_t w, uint32_t h, pf_error *err);
pf_result pf_imageio_write_pfm_range(const char *path, const float *rgb, uint32_t w, uint32_t h,
                                     pf_imageio_range range, pf_error *err);
/* The same, left in their temporary files (f begun, not committed), so a
 * command can commit several files only once all are written. On failure
 * f is aborted. */
pf_result pf_imageio_stage_png(pf_file *f, const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure,
                               pf_error *err);
pf_result pf_imageio_stage_pfm(pf_file *f, const char *path, const float *rgb, uint32_t w, uint32_t h,
                               pf_imageio_range range, pf_error *err);

/* OpenEXR (pf_exr.h): w x h pixels of `channels` (1: Y, 3: RGB, 4: RGBA)
 * interleaved floats, top row first, as 32-bit FLOAT channels; the values
 * must be within `range` (every channel). `comment` (may be NULL) goes into
 * the file's "comments" attribute. */
pf_result pf_imageio_stage_exr(pf_file *f, const char *path, const float *px, uint32_t w, uint32_t h,
                               uint32_t channels, pf_imageio_range range, const char *comment, pf_error *err);
pf_result pf_imageio_write_exr(const char *path, const float *px, uint32_t w, uint32_t h, uint32_t channels,
                               pf_imageio_range range, const char *comment, pf_error *err);
/* A linear RGB radiance image as its extension says: .exr or .pfm (anything
 * else: PF_ERR_ARGUMENT). */
pf_result pf_imageio_stage_linear(pf_file *f, const char *path, const float *rgb, uint32_t w, uint32_t h,
                                  pf_error *err);

/* Reads a PFM written by any tool (either endianness, "PF" or "Pf"); *rgb
 * is malloc'ed, 3 floats a pixel, top row first. Values must be within
 * `range` (the plain functions: PF_IMAGEIO_RADIANCE). On failure *rgb is
 * NULL and err names the file (`name` for the memory version) and reason. */
pf_result pf_imageio_read_pfm(const char *path, float **rgb, uint32_t *w, uint32_t *h, pf_error *err);
pf_result pf_imageio_read_pfm_range(const char *path, float **rgb, uint32_t *w, uint32_t *h, pf_imageio_range range,
                                    pf_error *err);
pf_result pf_imageio_read_pfm_memory(const void *data, size_t size, float **rgb, uint32_t *w, uint32_t *h,
                                     pf_error *err);
pf_result pf_imageio_read_pfm_memory_ex(const void *data, size_t size, const char *name, pf_imageio_range range,
                                        float **rgb, uint32_t *w, uint32_t *h, pf_error *err);

/* Reads an OpenEXR file (pf_exr.h's rules) into *rgb as pf_imageio_read_pfm
 * does; `max_bytes` bounds the decoder's memory. */
pf_result pf_imageio_read_exr_memory(const void *data, size_t size, const char *name, pf_imageio_range range,
                                     uint64_t max_bytes, float **rgb, uint32_t *w, uint32_t *h, pf_error *err);
/* A PFM or an OpenEXR file, told apart by its first bytes, within the size
 * limits above and the default memory budget (pf_budget.h). */
pf_result pf_imageio_read_image(const char *path, pf_imageio_range range, float **rgb, uint32_t *w, uint32_t *h,
                                pf_error *err);

uint64_t pf_imageio_hash(const float *data, uint64_t count);
/* The display transform of one linear value (shared with the viewer). */
uint8_t pf_imageio_display(float linear, float exposure_scale);

#endif
