/* pf_imageio: checked, atomic output files; PNG/PFM/OpenEXR output, PFM and
 * OpenEXR input and the output hash (pf_imageio.h). */
#define _DEFAULT_SOURCE /* mkstemp, fsync, open_memstream, realpath, openat, mkdirat */
#include "pf_imageio.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <stb_image_write.h>

#include "pf_budget.h"
#include "pf_exr.h"
#include "pf_scene.h" /* pf_linear_to_srgb */

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "pf_imageio writes little-endian PFM from host floats: a big-endian host needs a byte swap here"
#endif

uint8_t pf_imageio_display(float linear, float exposure_scale)
{
    float x = linear * exposure_scale;
    if (!(x > 0.0f)) return 0; /* also maps NaN to black */
    float tm = x / (1.0f + x);  /* Reinhard 2002, Eq. 3, per channel */
    if (!(tm < 1.0f)) tm = 1.0f; /* x = inf */
    float s = pf_linear_to_srgb(tm) * 255.0f + 0.5f;
    return (uint8_t)(s >= 255.0f ? 255 : (int)s);
}

/* ---------------------------------------------------------------- folders */

pf_result pf_imageio_make_parent_dirs(const char *path, pf_error *err)
{
    char buf[PF_IMAGEIO_PATH_MAX];
    size_t n = strlen(path);
    if (n >= sizeof buf) return pf_error_set(err, PF_ERR_IO, "%.200s...: path too long", path);
    memcpy(buf, path, n + 1);
    for (char *p = buf + 1; *p; p++) {
        if (*p != '/') continue;
        *p = 0;
        if (mkdir(buf, 0777) != 0 && errno != EEXIST)
            return pf_error_set(err, PF_ERR_IO, "%s: cannot create directory %s: %s", path, buf, strerror(errno));
        *p = '/';
    }
    return PF_OK;
}

/* "dir/name" -> "dir" ("." for a bare name, "/" for "/name"); 0 if too long. */
static int pf__dirname(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    int n = !slash ? snprintf(dir, size, ".") : slash == path ? snprintf(dir, size, "/")
                                                              : snprintf(dir, size, "%.*s", (int)(slash - path), path);
    return n >= 0 && (size_t)n < size;
}

static const char *pf__basename(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* Appends the components of `rest` to the absolute path `abs` (size
 * bytes), resolving "." and ".." lexically. */
static void pf__append_lexical(char *abs, size_t size, const char *rest)
{
    while (*rest) {
        while (*rest == '/') rest++;
        size_t n = strcspn(rest, "/");
        if (n == 0) break;
        if (n == 1 && rest[0] == '.') {
        } else if (n == 2 && rest[0] == '.' && rest[1] == '.') {
            char *s = strrchr(abs, '/');
            if (s && s != abs) *s = 0;
            else snprintf(abs, size, "/");
        } else {
            size_t l = strlen(abs);
            if (l + 1 + n < size) {
                if (l == 0 || abs[l - 1] != '/') abs[l++] = '/';
                memcpy(abs + l, rest, n);
                abs[l + n] = 0;
            }
        }
        rest += n;
    }
}

/* The folder of `path` as the kernel would find it (realpath of the longest
 * existing prefix, the rest appended lexically: it does not exist, so it
 * holds no links), then "/" and the file name. */
static void pf__canonical(const char *path, char *out, size_t size)
{
    char dir[PF_IMAGEIO_PATH_MAX], probe[PF_IMAGEIO_PATH_MAX], real[PATH_MAX];
    if (!pf__dirname(path, dir, sizeof dir)) {
        snprintf(out, size, "%s", path);
        return;
    }
    /* try dir, then ever shorter prefixes of it */
    snprintf(probe, sizeof probe, "%s", dir);
    const char *rest = NULL;
    for (;;) {
        if (realpath(probe, real)) break;
        char *s = strrchr(probe, '/');
        if (!s) {
            if (!getcwd(real, sizeof real)) snprintf(real, sizeof real, ".");
            rest = dir;
            break;
        }
        if (s == probe) {
            snprintf(real, sizeof real, "/");
            rest = dir + 1;
            break;
        }
        *s = 0;
        rest = dir + (s - probe) + 1;
    }
    snprintf(out, size, "%s", real);
    if (rest) pf__append_lexical(out, size, rest);
    size_t l = strlen(out);
    if (l + 1 < size && (l == 0 || out[l - 1] != '/')) out[l++] = '/', out[l] = 0;
    strncat(out, pf__basename(path), size - strlen(out) - 1);
}

int pf_imageio_same_output(const char *a, const char *b)
{
    char ca[PF_IMAGEIO_PATH_MAX + PATH_MAX], cb[PF_IMAGEIO_PATH_MAX + PATH_MAX];
    pf__canonical(a, ca, sizeof ca);
    pf__canonical(b, cb, sizeof cb);
    return strcmp(ca, cb) == 0;
}

pf_result pf_imageio_make_dir_inside(const char *base, const char *rel, char *out, size_t out_size, pf_error *err)
{
    /* rel: relative, no ".." component */
    if (!rel[0] || rel[0] == '/')
        return pf_error_set(err, PF_ERR_ARGUMENT, "'%s': must be a relative folder inside %s/", rel, base);
    for (const char *p = rel; *p;) {
        size_t n = strcspn(p, "/");
        if (n == 2 && p[0] == '.' && p[1] == '.')
            return pf_error_set(err, PF_ERR_ARGUMENT, "'%s': must not contain '..' (it must stay inside %s/)", rel,
                                base);
        p += n;
        while (*p == '/') p++;
    }
    int n = snprintf(out, out_size, "%s/%s", base, rel);
    if (n < 0 || (size_t)n >= out_size) return pf_error_set(err, PF_ERR_ARGUMENT, "'%s': path too long", rel);
    while (n > 1 && out[n - 1] == '/') out[--n] = 0;

    /* the base: the user's folder (it may itself be a link) */
    char probe[PF_IMAGEIO_PATH_MAX + 2];
    snprintf(probe, sizeof probe, "%s/x", base);
    pf_result r = pf_imageio_make_parent_dirs(probe, err);
    if (r != PF_OK) return r;
    char real_base[PATH_MAX], real_out[PATH_MAX];
    if (!realpath(base, real_base)) return pf_error_set(err, PF_ERR_IO, "%s: %s", base, strerror(errno));
    int fd = open(base, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return pf_error_set(err, PF_ERR_IO, "%s: cannot open the folder: %s", base, strerror(errno));
    /* each component created or opened without following links */
    for (const char *p = rel; *p && r == PF_OK;) {
        size_t len = strcspn(p, "/");
        char comp[NAME_MAX + 1];
        if (len > NAME_MAX) {
            r = pf_error_set(err, PF_ERR_ARGUMENT, "'%s': a folder name is too long", rel);
            break;
        }
        memcpy(comp, p, len);
        comp[len] = 0;
        p += len;
        while (*p == '/') p++;
        if (!strcmp(comp, ".")) continue;
        if (mkdirat(fd, comp, 0777) != 0 && errno != EEXIST) {
            r = pf_error_set(err, PF_ERR_IO, "%s: cannot create folder '%s': %s", out, comp, strerror(errno));
            break;
        }
        int next = openat(fd, comp, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        if (next < 0) {
            int e = errno;
            r = e == ELOOP || e == ENOTDIR
                    ? pf_error_set(err, PF_ERR_IO,
                                   "%s: '%s' is a symbolic link or not a folder; the output must be a folder inside %s/",
                                   out, comp, base)
                    : pf_error_set(err, PF_ERR_IO, "%s: cannot open folder '%s': %s", out, comp, strerror(e));
            break;
        }
        close(fd);
        fd = next;
    }
    close(fd);
    if (r != PF_OK) return r;
    /* belt and braces: the folder made must resolve inside the base */
    if (!realpath(out, real_out)) return pf_error_set(err, PF_ERR_IO, "%s: %s", out, strerror(errno));
    size_t bl = strlen(real_base);
    if (strncmp(real_out, real_base, bl) != 0 || (real_out[bl] != '/' && real_out[bl] != 0 && bl > 1))
        return pf_error_set(err, PF_ERR_IO, "%s resolves to %s, outside %s/", out, real_out, base);
    return PF_OK;
}

/* ---------------------------------------------------------------- files */

/* The mode fopen(path, "w") would create a file with. umask() can only be
 * read by setting it; softgi creates files from the main thread only, so
 * the brief change is not observed by anyone. */
static mode_t pf__file_mode(void)
{
    mode_t m = umask(0);
    umask(m);
    return 0666 & ~m;
}

void pf_file_abort(pf_file *f)
{
    if (f->open) close(f->fd);
    if (!f->direct && f->tmp[0]) unlink(f->tmp);
    f->open = 0;
    f->fd = -1;
    f->tmp[0] = 0;
}

static pf_result pf__file_fail(pf_file *f, pf_error *err, const char *what, int e)
{
    pf_error_set(err, PF_ERR_IO, "%s: %s: %s", f->path, what, strerror(e));
    pf_file_abort(f);
    return PF_ERR_IO;
}

pf_result pf_file_begin(pf_file *f, const char *path, pf_error *err)
{
    memset(f, 0, sizeof *f);
    f->fd = -1;
    size_t n = strlen(path);
    if (n == 0) return pf_error_set(err, PF_ERR_ARGUMENT, "empty output file name");
    if (n >= sizeof f->path) return pf_error_set(err, PF_ERR_IO, "%.200s...: path too long", path);
    memcpy(f->path, path, n + 1);
    const char *base = pf__basename(path);
    if (!base[0] || !strcmp(base, ".") || !strcmp(base, ".."))
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s: names a folder, not a file", path);
    pf_result r = pf_imageio_make_parent_dirs(path, err);
    if (r != PF_OK) return r;

    struct stat st, lst;
    if (stat(path, &st) == 0) {
        if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
            /* a device or pipe: nothing to replace; write it in place */
            f->fd = open(path, O_WRONLY | O_CLOEXEC);
            if (f->fd < 0) return pf_error_set(err, PF_ERR_IO, "%s: cannot open for writing: %s", path, strerror(errno));
            f->open = f->direct = 1;
            return PF_OK;
        }
        if (S_ISDIR(st.st_mode)) return pf_error_set(err, PF_ERR_IO, "%s: is a folder, not a file", path);
        if (!S_ISREG(st.st_mode))
            return pf_error_set(err, PF_ERR_IO, "%s: not a regular file, character device or FIFO; not replacing it",
                                path);
        /* a read-only file stays as fopen would leave it (a link is replaced, not written through) */
        if (lstat(path, &lst) == 0 && S_ISREG(lst.st_mode) && access(path, W_OK) != 0 && errno == EACCES)
            return pf_error_set(err, PF_ERR_IO, "%s: cannot write: %s", path, strerror(EACCES));
    } else if (errno != ENOENT) {
        return pf_error_set(err, PF_ERR_IO, "%s: %s", path, strerror(errno));
    }

    char dir[PF_IMAGEIO_PATH_MAX];
    if (!pf__dirname(path, dir, sizeof dir)) return pf_error_set(err, PF_ERR_IO, "%s: path too long", path);
    int k = snprintf(f->tmp, sizeof f->tmp, "%s/.%.200s.tmp-XXXXXX", dir, base);
    if (k < 0 || (size_t)k >= sizeof f->tmp) {
        f->tmp[0] = 0;
        return pf_error_set(err, PF_ERR_IO, "%s: path too long", path);
    }
    f->fd = mkstemp(f->tmp);
    if (f->fd < 0) {
        int e = errno;
        f->tmp[0] = 0;
        return pf_error_set(err, PF_ERR_IO, "%s: cannot create a temporary file in %s: %s", path, dir, strerror(e));
    }
    f->open = 1;
    (void)fcntl(f->fd, F_SETFD, FD_CLOEXEC);
    if (fchmod(f->fd, pf__file_mode()) != 0) return pf__file_fail(f, err, "cannot set the file mode", errno);
    return PF_OK;
}

pf_result pf_file_write(pf_file *f, const void *data, size_t size, pf_error *err)
{
    if (!f->open) return pf_error_set(err, PF_ERR_IO, "%s: write to a closed file", f->path);
    const char *p = data;
    while (size > 0) {
        ssize_t w = write(f->fd, p, size > (1u << 30) ? (1u << 30) : size);
        if (w < 0) {
            if (errno == EINTR) continue;
            return pf__file_fail(f, err, "write failed", errno);
        }
        if (w == 0) return pf__file_fail(f, err, "write failed", EIO);
        p += w;
        size -= (size_t)w;
    }
    return PF_OK;
}

pf_result pf_file_commit(pf_file *f, pf_error *err)
{
    if (!f->open) return pf_error_set(err, PF_ERR_IO, "%s: commit of a closed file", f->path);
    if (!f->direct && fsync(f->fd) != 0) return pf__file_fail(f, err, "write failed (fsync)", errno);
    int fd = f->fd;
    f->open = 0;
    f->fd = -1;
    if (close(fd) != 0 && errno != EINTR) return pf__file_fail(f, err, "write failed (close)", errno);
    if (f->direct) return PF_OK;
    if (rename(f->tmp, f->path) != 0) {
        int e = errno;
        char msg[PF_IMAGEIO_PATH_MAX + 64];
        snprintf(msg, sizeof msg, "cannot rename %s over it", f->tmp);
        return pf__file_fail(f, err, msg, e);
    }
    f->tmp[0] = 0;
    return PF_OK;
}

pf_result pf_imageio_write_file(const char *path, const void *data, size_t size, pf_error *err)
{
    pf_file f;
    pf_result r = pf_file_begin(&f, path, err);
    if (r == PF_OK) r = pf_file_write(&f, data, size, err);
    if (r == PF_OK) r = pf_file_commit(&f, err);
    return r;
}

pf_result pf_imageio_write_text(const char *path, int (*print)(FILE *f, void *user), void *user, pf_error *err)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    int bad = print(m, user) != 0;
    bad |= ferror(m) != 0;
    bad |= fclose(m) != 0;
    pf_result r = bad ? pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory formatting the text", path)
                      : pf_imageio_write_file(path, buf, len, err);
    free(buf);
    return r;
}

/* ---------------------------------------------------------------- checks */

static int pf__bad_value(float v, pf_imageio_range range)
{
    if (range == PF_IMAGEIO_DATA) return isnan(v);
    if (range == PF_IMAGEIO_DEPTH) return !(v >= 0.0f); /* NaN, negative, -inf; +inf is "no surface" */
    return !(v >= 0.0f) || isinf(v);
}

/* The message of pf_imageio_check for `channels` floats a pixel (1: Y,
 * 3: RGB, 4: RGBA), with `tail` appended. */
static pf_result pf__check_n(const char *name, const float *px, uint32_t w, uint32_t h, uint32_t channels,
                             pf_imageio_range range, const char *tail, pf_error *err)
{
    size_t bad = 0, first = 0;
    uint32_t first_c = 0;
    for (size_t i = 0, n = (size_t)w * h; i < n; i++) {
        int b = 0;
        for (uint32_t c = 0; c < channels; c++)
            if (pf__bad_value(px[channels * i + c], range) && !b++ && !bad) first = i, first_c = c;
        bad += b != 0;
    }
    if (!bad) return PF_OK;
    const char *what = range == PF_IMAGEIO_DEPTH  ? "NaN or negative depth"
                       : range == PF_IMAGEIO_DATA ? "NaN"
                                                  : "NaN, infinite or negative";
    return pf_error_set(err, PF_ERR_NONFINITE, "%s: %zu pixel%s %s (first: pixel (%u, %u) channel %c = %g)%s", name,
                        bad, bad == 1 ? " is" : "s are", what, (unsigned)(first % w), (unsigned)(first / w),
                        (channels == 1 ? "Y" : "RGBA")[first_c], (double)px[channels * first + first_c], tail);
}

static pf_result pf__check(const char *name, const float *rgb, uint32_t w, uint32_t h, pf_imageio_range range,
                           const char *tail, pf_error *err)
{
    return pf__check_n(name, rgb, w, h, 3, range, tail, err);
}

pf_result pf_imageio_check(const char *name, const float *rgb, uint32_t w, uint32_t h, pf_imageio_range range,
                           pf_error *err)
{
    return pf__check(name, rgb, w, h, range, "", err);
}

static pf_result pf__check_size(const char *path, uint32_t w, uint32_t h, pf_error *err)
{
    if (w == 0 || h == 0 || w > PF_IMAGEIO_MAX_SIDE || h > PF_IMAGEIO_MAX_SIDE ||
        (uint64_t)w * h > PF_IMAGEIO_MAX_PIXELS)
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s: cannot write a %ux%u image (1 to %u a side, %u pixels at most)",
                            path, w, h, PF_IMAGEIO_MAX_SIDE, PF_IMAGEIO_MAX_PIXELS);
    return PF_OK;
}

/* ---------------------------------------------------------------- output names */

/* 1 when the file name of `path` is something + ext (case-insensitive) */
static int pf__has_ext(const char *path, const char *ext)
{
    const char *base = pf__basename(path);
    size_t n = strlen(base), e = strlen(ext);
    return n > e && strcasecmp(base + n - e, ext) == 0;
}

pf_imageio_format pf_imageio_format_of(const char *path)
{
    return pf__has_ext(path, ".png")   ? PF_IMAGEIO_PNG
           : pf__has_ext(path, ".pfm") ? PF_IMAGEIO_PFM
           : pf__has_ext(path, ".exr") ? PF_IMAGEIO_EXR
                                       : PF_IMAGEIO_UNKNOWN;
}

/* "'.jpg'" or "(no extension)" for messages */
static void pf__ext_words(const char *path, char *buf, size_t size)
{
    const char *base = pf__basename(path), *dot = strrchr(base, '.');
    if (dot && dot != base) snprintf(buf, size, "'%.32s'", dot);
    else snprintf(buf, size, "(no extension)");
}

pf_result pf_imageio_outputs_resolve(pf_imageio_outputs *o, const char *output, const char *hdr,
                                     const char *default_png, pf_error *err)
{
    o->png[0] = o->linear[0] = 0;
    const char *out = output ? output : default_png;
    const char *opt = output ? "-o" : "the default output";
    char ext[48];
    if (strlen(out) >= PF_IMAGEIO_PATH_MAX - 8 || (hdr && strlen(hdr) >= PF_IMAGEIO_PATH_MAX))
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s: path too long", opt);
    pf_imageio_format hf = hdr ? pf_imageio_format_of(hdr) : PF_IMAGEIO_UNKNOWN;
    if (hdr && hf != PF_IMAGEIO_PFM && hf != PF_IMAGEIO_EXR) {
        pf__ext_words(hdr, ext, sizeof ext);
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "--hdr '%s': unsupported linear format %s (supported: .exr and .pfm)", hdr, ext);
    }
    switch (pf_imageio_format_of(out)) {
    case PF_IMAGEIO_PNG:
        snprintf(o->png, PF_IMAGEIO_PATH_MAX, "%s", out);
        if (hdr) snprintf(o->linear, PF_IMAGEIO_PATH_MAX, "%s", hdr);
        else snprintf(o->linear, PF_IMAGEIO_PATH_MAX, "%.*s.pfm", (int)(strlen(out) - 4), out);
        if (pf_imageio_same_output(o->png, o->linear))
            return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s' and --hdr '%s' name the same file", opt, o->png,
                                o->linear);
        return PF_OK;
    case PF_IMAGEIO_PFM:
    case PF_IMAGEIO_EXR:
        if (hdr)
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "--hdr '%s': -o '%s' already writes the linear image (--hdr goes with -o NAME.png)",
                                hdr, out);
        snprintf(o->linear, PF_IMAGEIO_PATH_MAX, "%s", out);
        return PF_OK;
    default:
        pf__ext_words(out, ext, sizeof ext);
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s '%s': unsupported output format %s (supported: %s)", opt, out,
                            ext, PF_IMAGEIO_OUTPUT_HELP);
    }
}

pf_result pf_imageio_outputs_write(const pf_imageio_outputs *o, const float *rgb, uint32_t w, uint32_t h,
                                   float exposure, pf_error *err)
{
    pf_file fpng, flin;
    memset(&fpng, 0, sizeof fpng);
    memset(&flin, 0, sizeof flin);
    pf_result r = PF_OK;
    if (o->png[0]) r = pf_imageio_stage_png(&fpng, o->png, rgb, w, h, exposure, err);
    if (r == PF_OK) r = pf_imageio_stage_linear(&flin, o->linear, rgb, w, h, err);
    if (r == PF_OK && o->png[0]) r = pf_file_commit(&fpng, err);
    if (r == PF_OK) r = pf_file_commit(&flin, err);
    pf_file_abort(&fpng); /* no-ops after a commit or a failure */
    pf_file_abort(&flin);
    return r;
}

/* ---------------------------------------------------------------- PNG */

typedef struct pf__png_sink {
    pf_file *f;
    pf_error *err;
    pf_result r;
} pf__png_sink;

static void pf__png_write(void *user, void *data, int size)
{
    pf__png_sink *s = user;
    if (s->r == PF_OK && size > 0) s->r = pf_file_write(s->f, data, (size_t)size, s->err);
}

static pf_result pf__stage_png_rgb8(pf_file *f, const char *path, const uint8_t *px, uint32_t w, uint32_t h,
                                    pf_error *err)
{
    pf_result r = pf__check_size(path, w, h, err);
    if (r == PF_OK) r = pf_file_begin(f, path, err);
    if (r != PF_OK) return r;
    /* stbi_write_png_to_func encodes in memory, then hands over the bytes:
     * the same encoder and settings as stbi_write_png, so the same bytes. */
    pf__png_sink sink = {f, err, PF_OK};
    int ok = stbi_write_png_to_func(pf__png_write, &sink, (int)w, (int)h, 3, px, (int)(w * 3));
    if (sink.r != PF_OK) return sink.r; /* f aborted by pf_file_write */
    if (!ok) {
        pf_file_abort(f);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory encoding the PNG", path);
    }
    return PF_OK;
}

pf_result pf_imageio_stage_png(pf_file *f, const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure,
                               pf_error *err)
{
    memset(f, 0, sizeof *f);
    pf_result r = pf__check_size(path, w, h, err);
    if (r == PF_OK) r = pf__check(path, rgb, w, h, PF_IMAGEIO_RADIANCE, "; nothing written", err);
    if (r != PF_OK) return r;
    uint8_t *px = malloc((size_t)w * h * 3);
    if (!px) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory writing %s", path);
    float scale = exp2f(exposure);
    for (size_t i = 0; i < (size_t)w * h * 3; i++) px[i] = pf_imageio_display(rgb[i], scale);
    r = pf__stage_png_rgb8(f, path, px, w, h, err);
    free(px);
    return r;
}

pf_result pf_imageio_write_png(const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure,
                               pf_error *err)
{
    pf_file f;
    pf_result r = pf_imageio_stage_png(&f, path, rgb, w, h, exposure, err);
    return r == PF_OK ? pf_file_commit(&f, err) : r;
}

pf_result pf_imageio_write_png_rgb8(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h, pf_error *err)
{
    pf_file f;
    pf_result r = pf__stage_png_rgb8(&f, path, rgb, w, h, err);
    return r == PF_OK ? pf_file_commit(&f, err) : r;
}

/* ---------------------------------------------------------------- PFM output */

pf_result pf_imageio_stage_pfm(pf_file *f, const char *path, const float *rgb, uint32_t w, uint32_t h,
                               pf_imageio_range range, pf_error *err)
{
    memset(f, 0, sizeof *f);
    pf_result r = pf__check_size(path, w, h, err);
    if (r == PF_OK) r = pf__check(path, rgb, w, h, range, "; nothing written", err);
    if (r == PF_OK) r = pf_file_begin(f, path, err);
    if (r != PF_OK) return r;
    /* Scale -1: little-endian floats. PFM stores the bottom row first. */
    char head[64];
    int hn = snprintf(head, sizeof head, "PF\n%u %u\n-1.0\n", w, h);
    r = pf_file_write(f, head, (size_t)hn, err);
    /* rows gathered into ~1 MiB writes */
    const size_t row = (size_t)w * 3 * sizeof(float);
    uint32_t per = (uint32_t)((1u << 20) / row);
    if (per < 1) per = 1;
    if (per > h) per = h;
    float *buf = malloc(row * per);
    if (r == PF_OK && !buf) {
        pf_file_abort(f);
        r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory writing %s", path);
    }
    for (uint32_t y = h; r == PF_OK && y > 0;) {
        uint32_t k = 0;
        for (; k < per && y > 0; k++) memcpy((char *)buf + k * row, rgb + (size_t)--y * w * 3, row);
        r = pf_file_write(f, buf, k * row, err);
    }
    free(buf);
    return r;
}

pf_result pf_imageio_write_pfm_range(const char *path, const float *rgb, uint32_t w, uint32_t h,
                                     pf_imageio_range range, pf_error *err)
{
    pf_file f;
    pf_result r = pf_imageio_stage_pfm(&f, path, rgb, w, h, range, err);
    return r == PF_OK ? pf_file_commit(&f, err) : r;
}

pf_result pf_imageio_write_pfm(const char *path, const float *rgb, uint32_t w, uint32_t h, pf_error *err)
{
    return pf_imageio_write_pfm_range(path, rgb, w, h, PF_IMAGEIO_RADIANCE, err);
}

/* ---------------------------------------------------------------- OpenEXR output */

pf_result pf_imageio_stage_exr(pf_file *f, const char *path, const float *px, uint32_t w, uint32_t h,
                               uint32_t channels, pf_imageio_range range, const char *comment, pf_error *err)
{
    memset(f, 0, sizeof *f);
    pf_result r = pf__check_size(path, w, h, err);
    if (r == PF_OK) r = pf__check_n(path, px, w, h, channels, range, "; nothing written", err);
    if (r != PF_OK) return r;
    /* encoded in memory (pf_exr.h), then written like every other file */
    uint8_t *bytes = NULL;
    size_t size = 0;
    pf_error e;
    if ((r = pf_exr_encode(px, w, h, channels, comment, &bytes, &size, &e)) != PF_OK)
        return pf_error_set(err, r, "%s: %s", path, e.message);
    r = pf_file_begin(f, path, err);
    if (r == PF_OK) r = pf_file_write(f, bytes, size, err);
    pf_exr_free(bytes);
    return r;
}

pf_result pf_imageio_write_exr(const char *path, const float *px, uint32_t w, uint32_t h, uint32_t channels,
                               pf_imageio_range range, const char *comment, pf_error *err)
{
    pf_file f;
    pf_result r = pf_imageio_stage_exr(&f, path, px, w, h, channels, range, comment, err);
    return r == PF_OK ? pf_file_commit(&f, err) : r;
}

pf_result pf_imageio_stage_linear(pf_file *f, const char *path, const float *rgb, uint32_t w, uint32_t h,
                                  pf_error *err)
{
    memset(f, 0, sizeof *f);
    switch (pf_imageio_format_of(path)) {
    case PF_IMAGEIO_EXR: return pf_imageio_stage_exr(f, path, rgb, w, h, 3, PF_IMAGEIO_RADIANCE, NULL, err);
    case PF_IMAGEIO_PFM: return pf_imageio_stage_pfm(f, path, rgb, w, h, PF_IMAGEIO_RADIANCE, err);
    default:
        return pf_error_set(err, PF_ERR_ARGUMENT, "%s: the linear image is written as .exr or .pfm", path);
    }
}

/* ---------------------------------------------------------------- PFM input */

static int pf__space(uint8_t c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

/* Skips at least one whitespace byte; 0 when there is none. */
static int pf__skip_space(const uint8_t *p, size_t size, size_t *i)
{
    size_t s = *i;
    while (*i < size && pf__space(p[*i])) (*i)++;
    return *i > s;
}

/* A decimal size token, 1..limit; 0 when it is not one. */
static int pf__size_token(const uint8_t *p, size_t size, size_t *i, uint32_t limit, uint32_t *out)
{
    uint64_t v = 0;
    size_t s = *i;
    while (*i < size && p[*i] >= '0' && p[*i] <= '9') {
        v = v * 10 + (uint64_t)(p[*i] - '0');
        if (v > limit) return 0;
        (*i)++;
    }
    if (*i == s || v == 0) return 0;
    *out = (uint32_t)v;
    return 1;
}

pf_result pf_imageio_read_pfm_memory_ex(const void *data, size_t size, const char *name, pf_imageio_range range,
                                        float **out, uint32_t *w_out, uint32_t *h_out, pf_error *err)
{
    *out = NULL;
    *w_out = *h_out = 0;
    const uint8_t *p = data;
    if (!name) name = "PFM data";
    if (size < 2 || p[0] != 'P' || (p[1] != 'F' && p[1] != 'f'))
        return pf_error_set(err, PF_ERR_PARSE, "%s: not a 3-channel PFM file (it must start with PF; grey Pf is read as R = G = B)",
                            name);
    const uint32_t channels = p[1] == 'F' ? 3 : 1;
    size_t i = 2;
    uint32_t w = 0, h = 0;
    if (!pf__skip_space(p, size, &i) || !pf__size_token(p, size, &i, PF_IMAGEIO_MAX_SIDE, &w) ||
        !pf__skip_space(p, size, &i) || !pf__size_token(p, size, &i, PF_IMAGEIO_MAX_SIDE, &h) ||
        !pf__skip_space(p, size, &i))
        return pf_error_set(err, PF_ERR_PARSE, "%s: bad PFM header (width and height must be 1 to %u)", name,
                            PF_IMAGEIO_MAX_SIDE);
    if ((uint64_t)w * h > PF_IMAGEIO_MAX_PIXELS)
        return pf_error_set(err, PF_ERR_PARSE, "%s: %ux%u is more than %u pixels", name, w, h, PF_IMAGEIO_MAX_PIXELS);
    /* the scale: a number token of at most 63 bytes, finite, non-zero */
    char tok[64];
    size_t n = 0;
    while (i < size && !pf__space(p[i]) && n < sizeof tok - 1) tok[n++] = (char)p[i++];
    tok[n] = 0;
    char *end = NULL;
    double scale = n ? strtod(tok, &end) : 0.0;
    const int nul = memchr(tok, 0, n) != NULL; /* strtod would stop there */
    for (size_t k = 0; k < n; k++) /* printable in the message */
        if (tok[k] < 0x20 || tok[k] > 0x7e) tok[k] = '?';
    if (!n || *end || nul || (i < size && !pf__space(p[i])) || !isfinite(scale) || scale == 0.0)
        return pf_error_set(err, PF_ERR_PARSE, "%s: bad PFM scale '%s' (a finite non-zero number)", name, tok);
    if (i >= size) return pf_error_set(err, PF_ERR_PARSE, "%s: PFM header without pixel data", name);
    const uint64_t need = (uint64_t)w * h * channels * sizeof(float);
    i++; /* the one whitespace byte that ends the header */
    if (p[i - 1] == '\r' && i < size && p[i] == '\n' && size - i - 1 == need) i++; /* "\r\n" */
    if (size - i != need)
        return pf_error_set(err, PF_ERR_PARSE, "%s: %zu bytes of pixel data, a %ux%u %s PFM has %llu (%s)", name,
                            size - i, w, h, channels == 3 ? "RGB" : "grey", (unsigned long long)need,
                            size - i < need ? "truncated" : "trailing bytes");
    float *rgb = malloc((size_t)w * h * 3 * sizeof(float));
    if (!rgb) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory for %ux%u pixels", name, w, h);
    const int swap = scale > 0.0; /* positive scale: big-endian data */
    const uint8_t *src = p + i;
    for (uint32_t y = 0; y < h; y++) { /* file rows bottom first */
        float *dst = rgb + (size_t)(h - 1 - y) * w * 3;
        for (uint32_t x = 0; x < w; x++)
            for (uint32_t c = 0; c < 3; c++) {
                uint32_t b;
                memcpy(&b, src + 4 * ((size_t)y * w * channels + (size_t)x * channels + (channels == 3 ? c : 0)), 4);
                if (swap) b = __builtin_bswap32(b);
                memcpy(&dst[3 * x + c], &b, 4);
            }
    }
    pf_result r = pf__check(name, rgb, w, h, range, "", err);
    if (r != PF_OK) {
        free(rgb);
        return r;
    }
    *out = rgb;
    *w_out = w;
    *h_out = h;
    return PF_OK;
}

pf_result pf_imageio_read_pfm_memory(const void *data, size_t size, float **rgb, uint32_t *w, uint32_t *h,
                                     pf_error *err)
{
    return pf_imageio_read_pfm_memory_ex(data, size, NULL, PF_IMAGEIO_RADIANCE, rgb, w, h, err);
}

pf_result pf_imageio_read_file(const char *path, uint64_t limit, const char *what, char **data, size_t *size,
                               pf_error *err)
{
    *data = NULL;
    *size = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return pf_error_set(err, PF_ERR_IO, "%s: cannot open the %s: %s", path, what, strerror(errno));
    /* a regular file's size is known: refused before reading, read in one
     * allocation (+1: EOF is seen without a regrow); a pipe grows by doubling */
    struct stat st;
    size_t cap = 1 << 12;
    if (fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode)) {
        if ((uint64_t)st.st_size > limit) {
            fclose(f);
            return pf_error_set(err, PF_ERR_PARSE, "%s: %lld bytes is larger than any %s softgi reads", path,
                                (long long)st.st_size, what);
        }
        cap = (size_t)st.st_size + 1;
    }
    char *buf = malloc(cap);
    size_t n = 0;
    pf_result r = buf ? PF_OK : pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    while (r == PF_OK) {
        if (n == cap) {
            if (cap > limit) {
                r = pf_error_set(err, PF_ERR_PARSE, "%s: larger than any %s softgi reads", path, what);
                break;
            }
            size_t nc = cap * 2 > limit + 1 ? (size_t)limit + 1 : cap * 2;
            char *nb = realloc(buf, nc);
            if (!nb) {
                r = pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
                break;
            }
            buf = nb, cap = nc;
        }
        size_t k = fread(buf + n, 1, cap - n, f);
        n += k;
        if (k == 0) {
            if (ferror(f)) r = pf_error_set(err, PF_ERR_IO, "%s: read error", path);
            break;
        }
    }
    fclose(f);
    if (r != PF_OK) {
        free(buf);
        return r;
    }
    *data = buf;
    *size = n;
    return PF_OK;
}

pf_result pf_imageio_read_pfm_range(const char *path, float **out, uint32_t *w, uint32_t *h, pf_imageio_range range,
                                    pf_error *err)
{
    *out = NULL;
    *w = *h = 0;
    /* the largest PFM we read: a short header and 2^28 RGB pixels */
    char *buf;
    size_t n;
    pf_result r = pf_imageio_read_file(path, 256 + (uint64_t)PF_IMAGEIO_MAX_PIXELS * 12, "PFM image", &buf, &n, err);
    if (r == PF_OK) r = pf_imageio_read_pfm_memory_ex(buf, n, path, range, out, w, h, err);
    free(buf);
    return r;
}

pf_result pf_imageio_read_pfm(const char *path, float **out, uint32_t *w, uint32_t *h, pf_error *err)
{
    return pf_imageio_read_pfm_range(path, out, w, h, PF_IMAGEIO_RADIANCE, err);
}

/* ---------------------------------------------------------------- OpenEXR input, any image */

pf_result pf_imageio_read_exr_memory(const void *data, size_t size, const char *name, pf_imageio_range range,
                                     uint64_t max_bytes, float **rgb, uint32_t *w, uint32_t *h, pf_error *err)
{
    pf_exr_read_desc desc = {name ? name : "OpenEXR data", PF_IMAGEIO_MAX_SIDE, PF_IMAGEIO_MAX_PIXELS, max_bytes};
    pf_result r = pf_exr_decode(data, size, &desc, rgb, w, h, err);
    if (r == PF_OK && (r = pf__check(desc.name, *rgb, *w, *h, range, "", err)) != PF_OK) {
        free(*rgb);
        *rgb = NULL;
        *w = *h = 0;
    }
    return r;
}

pf_result pf_imageio_read_image(const char *path, pf_imageio_range range, float **rgb, uint32_t *w, uint32_t *h,
                                pf_error *err)
{
    *rgb = NULL;
    *w = *h = 0;
    /* the file and its decoding come out of one budget (pf_budget.h) */
    pf_budget b;
    pf_budget_init(&b, 0);
    char *buf;
    size_t n;
    pf_result r = pf_imageio_read_file(path, b.limit, "image", &buf, &n, err);
    if (r != PF_OK) return r;
    if (pf_exr_is_exr(buf, n))
        r = pf_imageio_read_exr_memory(buf, n, path, range, b.limit - n, rgb, w, h, err);
    else if (n >= 2 && buf[0] == 'P' && (buf[1] == 'F' || buf[1] == 'f'))
        r = pf_imageio_read_pfm_memory_ex(buf, n, path, range, rgb, w, h, err);
    else
        r = pf_error_set(err, PF_ERR_PARSE,
                         "%s: not a 3-channel PFM file or an OpenEXR file (they start with PF or Pf, and with the "
                         "bytes 76 2f 31 01)",
                         path);
    free(buf);
    return r;
}

uint64_t pf_imageio_hash(const float *data, uint64_t count)
{
    uint64_t hsh = 0xcbf29ce484222325ull; /* FNV-1a 64 offset basis */
    const uint8_t *b = (const uint8_t *)data;
    for (uint64_t i = 0; i < count * sizeof(float); i++) {
        hsh ^= b[i];
        hsh *= 0x100000001b3ull;
    }
    return hsh;
}
