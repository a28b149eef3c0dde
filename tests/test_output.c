/* test_output: outputs that are never partial, never misplaced, never wrong
 * (pf_imageio.h "Outputs are never partial", pf_sequence.h "Where frames
 * go" and the frames' folder manifest).
 *
 * - a full device (/dev/full, also behind a link named x.png) and a folder
 *   nobody may create files in give exit 1 and one line naming the file and
 *   the reason; nothing is left behind, and an old file stays as it was when
 *   the other file of the pair fails;
 * - a successful render, dump and sequence leave no temporary file;
 * - -o NAME.pfm writes exactly that PFM and leaves NAME.png alone; other
 *   extensions, --hdr without .pfm or .exr and two outputs naming one file
 *   are refused with exit 2 before anything is rendered;
 * - every format written is read back and compared with the rendered
 *   floats: .pfm and .exr (through tinyexr, pf_exr.h) bit for bit against
 *   the --hash of the render, the PNG byte for byte against the display
 *   transform of those floats; the float stage dumps (--dump-format exr and
 *   both), and compare reading .exr (and refusing broken ones);
 * - the writers refuse NaN, infinite and negative values (count and first
 *   pixel in the message, no file); depth planes may hold +inf;
 * - compare refuses a PFM with NaN instead of printing "RMSE nan"; the PFM
 *   parser's header, size and data checks (the fuzz target's contract);
 * - a sequence file's "output" cannot be absolute, hold "..", or escape
 *   out/ through a link; softgi sequence deletes nothing (an unrelated
 *   frame_0099.png, older frames and track.txt stay), and compare reads only
 *   the frames the manifest lists, refusing an unfinished run.
 * Every render is 32x24, direct light only, with small shadow maps. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <unistd.h>

#include "pf_decode.h"
#include "pf_imageio.h"
#include "pf_sequence.h"
#include "test_util.h"

#define FAST "--size 32x24 --direct-only --shadow-size 64 --threads 1 -q"
/* reference draws no shadow maps: it refuses --shadow-size (pf_cli.h) */
#define FAST_REF "--size 32x24 --direct-only --threads 1 -q"

static char g_tmp[256];

/* ---------------------------------------------------------------- helpers */

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

static void write_text(const char *path, const char *text) { write_bytes(path, text, strlen(text)); }

/* The whole file into buf (NUL-terminated); its size, or -1. */
static long read_text(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    size_t n = fread(buf, 1, size - 1, f);
    buf[n] = 0;
    fclose(f);
    return (long)n;
}

static void make_dir(const char *fmt, const char *a, char *out, size_t size)
{
    snprintf(out, size, fmt, g_tmp, a);
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", out);
    assert_int_equal(system(cmd), 0);
}

/* Number of entries of dir (not . and ..), and of temporary files
 * (".NAME.tmp-XXXXXX") among them. */
static int count_entries(const char *dir, int *temps)
{
    DIR *d = opendir(dir);
    if (!d) fail_msg("cannot open %s", dir);
    int n = 0;
    *temps = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        n++;
        if (e->d_name[0] == '.' && strstr(e->d_name, ".tmp-")) ++*temps;
    }
    closedir(d);
    return n;
}

static void expect_no_temps(const char *dir)
{
    int temps;
    count_entries(dir, &temps);
    if (temps) fail_msg("%s holds %d temporary file(s)", dir, temps);
}

/* A 2-frame sequence folder made by hand: frame_0000.pfm, frame_0001.pfm. */
static void make_frames(const char *dir, uint32_t frames)
{
    float px[4 * 3];
    for (int i = 0; i < 12; i++) px[i] = 0.25f * (float)(i % 4);
    pf_error err;
    for (uint32_t t = 0; t < frames; t++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/frame_%04u.pfm", dir, t);
        if (pf_imageio_write_pfm(path, px, 2, 2, &err) != PF_OK) fail_msg("%s", err.message);
    }
}

/* ---------------------------------------------------------------- full and read-only targets */

static void test_full_device(void **state)
{
    (void)state;
    char dir[512], link[600], args[2048], out[16384], pfm[600];
    make_dir("%s/full%s", "", dir, sizeof dir);
    /* the path names no supported format: refused as usage before any render */
    tu_softgi_expect("render " FAST " -o /dev/full", 2, "-o '/dev/full': unsupported output format (no extension)");
    /* a link named like a PNG: the bytes go to the device, the error is reported */
    snprintf(link, sizeof link, "%s/x.png", dir);
    assert_int_equal(symlink("/dev/full", link), 0);
    snprintf(args, sizeof args, "render " FAST " -o '%s'", link);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 1 || !strstr(out, "x.png: write failed: No space left on device"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);
    snprintf(pfm, sizeof pfm, "%s/x.pfm", dir);
    assert_false(tu_file_exists(pfm)); /* the PNG failed: the PFM is not written either */
    expect_no_temps(dir);
    /* --hdr to the device too (PNG first, then the PFM fails): neither is replaced */
    char png[600];
    snprintf(png, sizeof png, "%s/keep.png", dir);
    write_text(png, "old");
    snprintf(link, sizeof link, "%s/dev.pfm", dir);
    assert_int_equal(symlink("/dev/full", link), 0);
    snprintf(args, sizeof args, "render " FAST " -o '%s' --hdr '%s'", png, link);
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 1 || !strstr(out, "dev.pfm: write failed: No space left on device"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);
    char buf[64];
    assert_int_equal(read_text(png, buf, sizeof buf), 3);
    assert_string_equal(buf, "old");
    expect_no_temps(dir);

    /* the API: a direct write to the device, every call checked */
    pf_error err;
    float px[3] = {1, 1, 1};
    assert_int_equal(pf_imageio_write_pfm("/dev/full", px, 1, 1, &err), PF_ERR_IO);
    assert_non_null(strstr(err.message, "/dev/full: write failed: No space left on device"));
    assert_int_equal(pf_imageio_write_png("/dev/full", px, 1, 1, 0.0f, &err), PF_ERR_IO);
    assert_int_equal(pf_imageio_write_pfm("/dev/null", px, 1, 1, &err), PF_OK);
    assert_true(tu_file_exists("/dev/null"));

    /* compare's table (any name) straight to /dev/full */
    char seq[600];
    make_dir("%s/full%s", "/seq", seq, sizeof seq);
    make_frames(seq, 2);
    snprintf(args, sizeof args, "compare --reference '%s' --name a:'%s' --table /dev/full", seq, seq);
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 1 || !strstr(out, "softgi compare: /dev/full: write failed: No space left on device"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);
}

static void test_readonly_folder(void **state)
{
    (void)state;
    char args[2048], out[16384];
    /* root ignores folder permissions; nobody, root included, creates files in /proc/self */
    int st;
    if (geteuid() != 0) {
        char ro[512];
        make_dir("%s/ro%s", "", ro, sizeof ro);
        assert_int_equal(chmod(ro, 0555), 0);
        snprintf(args, sizeof args, "render " FAST " -o '%s/x.png'", ro);
        st = tu_softgi_run(args, out, sizeof out);
        chmod(ro, 0755);
        if (st != 1 || !strstr(out, "x.png: cannot create a temporary file in") || !strstr(out, "Permission denied"))
            fail_msg("softgi %s: exit %d\n%s", args, st, out);
        int temps;
        assert_int_equal(count_entries(ro, &temps), 0);
    } else {
        print_message("note: running as root, so a chmod 0555 folder does not stop writes; using /proc/self\n");
    }
    st = tu_softgi_run("render " FAST " -o /proc/self/softgi-test.png", out, sizeof out);
    if (st != 1 || !strstr(out, "softgi: /proc/self/softgi-test.png: cannot create a temporary file in /proc/self"))
        fail_msg("render -o /proc/self/softgi-test.png: exit %d\n%s", st, out);

    /* the PFM's folder cannot be made (a file is in the way): the PNG, staged
     * first, is not committed, so the old PNG stays */
    char dir[512], png[600], blocker[600];
    make_dir("%s/pair%s", "", dir, sizeof dir);
    snprintf(png, sizeof png, "%s/x.png", dir);
    snprintf(blocker, sizeof blocker, "%s/file", dir);
    write_text(png, "old png");
    write_text(blocker, "a file, not a folder");
    snprintf(args, sizeof args, "render " FAST " -o '%s' --hdr '%s/sub/x.pfm'", png, blocker);
    st = tu_softgi_run(args, out, sizeof out);
    if (st != 1 || !strstr(out, "sub/x.pfm"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);
    char buf[64];
    read_text(png, buf, sizeof buf);
    assert_string_equal(buf, "old png");
    expect_no_temps(dir);
    /* a folder where the file should be */
    snprintf(args, sizeof args, "render " FAST " -o '%s/x.png' --hdr '%s/x.png.d.pfm'", dir, dir);
    char sub[700];
    snprintf(sub, sizeof sub, "%s/x.png.d.pfm", dir);
    assert_int_equal(mkdir(sub, 0755), 0);
    tu_softgi_expect(args, 1, "x.png.d.pfm: is a folder, not a file");
}

/* ---------------------------------------------------------------- success, names */

static void test_success_leaves_no_temps(void **state)
{
    (void)state;
    char dir[512], args[2048];
    make_dir("%s/ok%s", "", dir, sizeof dir);
    snprintf(args, sizeof args, "render " FAST " -o '%s/a.png' --dump-stages '%s/dump'", dir, dir);
    tu_softgi_expect(args, 0, NULL);
    int temps;
    assert_int_equal(count_entries(dir, &temps), 3); /* a.png, a.pfm, dump */
    assert_int_equal(temps, 0);
    char dump[600];
    snprintf(dump, sizeof dump, "%s/dump", dir);
    expect_no_temps(dump);
    snprintf(dump, sizeof dump, "%s/dump/captions.txt", dir);
    assert_true(tu_file_exists(dump));
    /* the PFM holds the image; the file mode is fopen's (0666 & ~umask) */
    float *rgb = NULL;
    uint32_t w, h;
    pf_error err;
    char p[600];
    snprintf(p, sizeof p, "%s/a.pfm", dir);
    if (pf_imageio_read_pfm(p, &rgb, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
    assert_int_equal(w, 32);
    assert_int_equal(h, 24);
    free(rgb);
    struct stat st;
    assert_int_equal(stat(p, &st), 0);
    mode_t um = umask(0);
    umask(um);
    assert_int_equal(st.st_mode & 0777, 0666 & ~um);

    /* a sequence run: frames, track.txt, frames.txt and nothing else */
    char seq[600], sdir[600];
    snprintf(seq, sizeof seq, "%s/two.seq.json", g_tmp);
    write_text(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 2, \"size\": [32, 24]}");
    snprintf(sdir, sizeof sdir, "%s/seq", dir);
    snprintf(args, sizeof args, "sequence '%s' -o '%s' --direct-only --shadow-size 64 --threads 1 -q", seq, sdir);
    tu_softgi_expect(args, 0, NULL);
    assert_int_equal(count_entries(sdir, &temps), 2 * 4 + 2);
    assert_int_equal(temps, 0);
}

static void test_pfm_output_keeps_png(void **state)
{
    (void)state;
    char dir[512], png[600], pfm[600], args[2048];
    make_dir("%s/pfmonly%s", "", dir, sizeof dir);
    snprintf(png, sizeof png, "%s/x.png", dir);
    snprintf(pfm, sizeof pfm, "%s/x.pfm", dir);
    write_text(png, "my own PNG");
    /* one file written, once (before, the PNG went to x.pfm and the PFM over it: "wrote x.pfm and x.pfm") */
    snprintf(args, sizeof args, "render --size 32x24 --direct-only --shadow-size 64 --threads 1 -o '%s'", pfm);
    char out[16384], want[700];
    int st = tu_softgi_run(args, out, sizeof out);
    snprintf(want, sizeof want, "wrote %s\n", pfm);
    if (st != 0 || !strstr(out, want)) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    char buf[64];
    read_text(png, buf, sizeof buf);
    assert_string_equal(buf, "my own PNG");
    float *rgb = NULL;
    uint32_t w, h;
    pf_error err;
    if (pf_imageio_read_pfm(pfm, &rgb, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
    assert_int_equal(w * h, 32 * 24);
    free(rgb);
    /* the same for reference, and an upper-case .PNG is a PNG */
    snprintf(args, sizeof args, "reference " FAST_REF " --spp 1 --bounces 1 -o '%s/r.pfm'", dir);
    tu_softgi_expect(args, 0, NULL);
    snprintf(args, sizeof args, "render " FAST " -o '%s/U.PNG'", dir);
    tu_softgi_expect(args, 0, NULL);
    snprintf(pfm, sizeof pfm, "%s/U.pfm", dir);
    assert_true(tu_file_exists(pfm));
    int temps;
    assert_int_equal(count_entries(dir, &temps), 5); /* x.png x.pfm r.pfm U.PNG U.pfm */
    assert_int_equal(temps, 0);
}

static void test_unsupported_names(void **state)
{
    (void)state;
    char dir[512], args[4096];
    make_dir("%s/names%s", "", dir, sizeof dir);
    static const struct {
        const char *opts, *needle;
    } bad[] = {
        {"-o '%s/x.tif'", "unsupported output format '.tif' (supported: .png (with the linear .pfm beside it, or "
                          "--hdr NAME.exr|NAME.pfm), .exr or .pfm)"},
        {"-o '%s/x.jpg'", "unsupported output format '.jpg'"},
        {"-o '%s/x.exr.gz'", "unsupported output format '.gz'"},
        {"-o '%s/x'", "unsupported output format (no extension)"},
        {"-o '%s/'", "unsupported output format (no extension)"},
        {"-o '%s/.png'", "unsupported output format"},
        {"-o '%s/x.png' --hdr '%s/x.tif'", "unsupported linear format '.tif' (supported: .exr and .pfm)"},
        {"-o '%s/x.png' --hdr '%s/x.png'", "unsupported linear format '.png'"},
        {"-o '%s/x.pfm' --hdr '%s/y.pfm'", "already writes the linear image"},
        {"-o '%s/x.exr' --hdr '%s/y.exr'", "already writes the linear image"},
        {"-o '%s/d/14-final.png' --dump-stages '%s/d'", "is also a --dump-stages file"},
        {"-o '%s/d/14-final.exr' --dump-stages '%s/d' --dump-format exr", "is also a --dump-stages file"},
        {"-o '%s/d/06-direct.png' --dump-stages '%s/d' --dump-format both", "is also a --dump-stages file"},
        {"-o '%s/d/x.png' --hdr '%s/d/00-depth.exr' --dump-stages '%s/d' --dump-format both",
         "is also a --dump-stages file"},
        {"-o '%s/a.png' --hdr '%s/./e/../a.pfm' --dump-stages '%s'", NULL}, /* distinct: accepted */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char opts[1600];
        snprintf(opts, sizeof opts, bad[i].opts, dir, dir, dir);
        for (int cmd = 0; cmd < 2; cmd++) {
            if (cmd == 1 && strstr(opts, "dump")) continue; /* reference has no --dump-stages */
            snprintf(args, sizeof args, "%s %s %s", cmd ? "reference " FAST_REF " --spp 1" : "render " FAST, opts, "");
            tu_softgi_expect(args, bad[i].needle ? 2 : 0, bad[i].needle);
        }
    }
    /* nothing was written by the refused ones */
    char p[600];
    snprintf(p, sizeof p, "%s/x.pfm", dir);
    assert_false(tu_file_exists(p));
    snprintf(p, sizeof p, "%s/d", dir);
    assert_false(tu_file_exists(p));
    /* a --hdr that is the same file as the PNG's folder entry through a link to its folder */
    char link[600];
    snprintf(link, sizeof link, "%s/alias", dir);
    assert_int_equal(symlink(dir, link), 0);
    char a[600], b[600];
    snprintf(a, sizeof a, "%s/s.pfm", dir);
    snprintf(b, sizeof b, "%s/alias/s.pfm", dir);
    assert_true(pf_imageio_same_output(a, b));
    snprintf(b, sizeof b, "%s/alias/../names/s.pfm", dir); /* ".." after a link: the link's parent */
    assert_true(pf_imageio_same_output(a, b));
    snprintf(b, sizeof b, "%s/new/../s.pfm", dir); /* a folder that does not exist yet */
    assert_true(pf_imageio_same_output(a, b));
    assert_false(pf_imageio_same_output(a, "s.pfm"));
    /* compare: --table and --plot naming one file */
    snprintf(args, sizeof args, "compare --reference '%s' --name a:'%s' --table '%s/t.svg' --plot '%s/alias/t.svg'",
             dir, dir, dir, dir);
    tu_softgi_expect(args, 2, "name the same file");
}

/* ---------------------------------------------------------------- formats read back */

/* The whole file, malloc'ed (NUL-terminated beyond *size). */
static char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    buf[n] = 0;
    fclose(f);
    *size = (size_t)n;
    return buf;
}

/* The first `needle` (n bytes) in data[0..size), or NULL (memmem is a GNU extension). */
static const char *find_bytes(const char *data, size_t size, const char *needle, size_t n)
{
    for (size_t i = 0; i + n <= size; i++)
        if (!memcmp(data + i, needle, n)) return data + i;
    return NULL;
}

/* The hash line `softgi ... --hash` printed, as a number. */
static uint64_t printed_hash(const char *out)
{
    const char *h = strstr(out, "hash ");
    if (!h) fail_msg("no hash in:\n%s", out);
    return strtoull(h + 5, NULL, 16);
}

/* A linear file (.pfm or .exr) read back: exactly the floats whose hash the render printed; *rgb keeps them. */
static void expect_linear(const char *path, uint64_t hash, uint32_t w, uint32_t h, float **rgb)
{
    uint32_t fw, fh;
    pf_error err;
    if (pf_imageio_read_image(path, PF_IMAGEIO_RADIANCE, rgb, &fw, &fh, &err) != PF_OK) fail_msg("%s", err.message);
    assert_int_equal(fw, w);
    assert_int_equal(fh, h);
    if (pf_imageio_hash(*rgb, 3ull * w * h) != hash) fail_msg("%s does not hold the rendered floats", path);
}

/* A PNG read back (libspng, pf_decode): byte for byte the display transform of the floats. */
static void expect_png(const char *path, const float *rgb, uint32_t w, uint32_t h, float exposure)
{
    size_t n;
    char *png = read_all(path, &n);
    uint8_t *px = NULL;
    uint32_t pw, ph;
    pf_error err;
    if (pf_decode_rgba8(png, n, NULL, &px, &pw, &ph, &err) != PF_OK) fail_msg("%s: %s", path, err.message);
    assert_int_equal(pw, w);
    assert_int_equal(ph, h);
    for (size_t i = 0; i < (size_t)w * h; i++)
        for (int c = 0; c < 3; c++)
            if (px[4 * i + c] != pf_imageio_display(rgb[3 * i + c], exp2f(exposure)))
                fail_msg("%s: pixel %zu channel %d is %u, not the display transform of %g", path, i, c, px[4 * i + c],
                         (double)rgb[3 * i + c]);
    free(px);
    free(png);
}

/* 1 when the file is an OpenEXR file of 32-bit float channels and ZIP compression, as pf_exr.h promises. */
static int exr_is_float_zip(const char *path)
{
    size_t n;
    char *d = read_all(path, &n);
    int ok = n > 8 && !memcmp(d, "\x76\x2f\x31\x01", 4);
    /* chlist entries: name \0, pixel type (2 = FLOAT) as a 4-byte int; compression 3 = ZIP */
    const char *ch = find_bytes(d, n, "chlist", 7);
    ok = ok && ch && ch[7 + 4 + 2] == 2;
    const char *cp = find_bytes(d, n, "compression\0compression", 24);
    ok = ok && cp && cp[24 + 4] == 3;
    free(d);
    return ok;
}

static void test_formats_read_back(void **state)
{
    (void)state;
    char dir[512], args[2048], out[16384], p[700], q[700];
    make_dir("%s/formats%s", "", dir, sizeof dir);
    static const struct {
        const char *cmd, *opts, *png, *linear;
    } runs[] = {
        {"render " FAST " --exposure 1.5", "-o '%s/a.png'", "a.png", "a.pfm"},
        {"render " FAST " --exposure 1.5", "-o '%s/b.png' --hdr '%s/b.exr'", "b.png", "b.exr"},
        {"render " FAST " --exposure 1.5", "-o '%s/c.exr'", NULL, "c.exr"},
        {"render " FAST " --exposure 1.5", "-o '%s/d.pfm'", NULL, "d.pfm"},
        {"render " FAST " --exposure 1.5", "-o '%s/E.EXR'", NULL, "E.EXR"},
        {"reference " FAST_REF " --spp 2 --bounces 1 --exposure 1.5", "-o '%s/r.png' --hdr '%s/r.exr'", "r.png", "r.exr"},
        {"reference " FAST_REF " --spp 2 --bounces 1 --exposure 1.5", "-o '%s/s.exr'", NULL, "s.exr"},
    };
    uint64_t render_hash = 0;
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        char opts[1600];
        snprintf(opts, sizeof opts, runs[i].opts, dir, dir);
        snprintf(args, sizeof args, "%s --hash %s", runs[i].cmd, opts);
        int st = tu_softgi_run(args, out, sizeof out);
        if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
        uint64_t hash = printed_hash(out);
        if (!strncmp(runs[i].cmd, "render", 6)) { /* the same render each time, whatever the format */
            if (render_hash && hash != render_hash) fail_msg("softgi %s: another hash", args);
            render_hash = hash;
        }
        float *rgb = NULL;
        snprintf(p, sizeof p, "%s/%s", dir, runs[i].linear);
        expect_linear(p, hash, 32, 24, &rgb);
        if (strstr(runs[i].linear, "xr") || strstr(runs[i].linear, "XR")) assert_true(exr_is_float_zip(p));
        if (runs[i].png) {
            snprintf(q, sizeof q, "%s/%s", dir, runs[i].png);
            expect_png(q, rgb, 32, 24, 1.5f);
        }
        free(rgb);
    }
    expect_no_temps(dir);
    /* -o NAME.exr writes only the EXR; NAME.png stays absent */
    snprintf(p, sizeof p, "%s/c.png", dir);
    assert_false(tu_file_exists(p));
    /* one render's files agree across formats: compare reads both */
    snprintf(args, sizeof args, "compare '%s/c.exr' '%s/a.pfm'", dir, dir);
    tu_softgi_expect(args, 0, "RMSE       0\n");

    /* a full device behind a link named .exr: the error names it, nothing is left */
    snprintf(p, sizeof p, "%s/full.exr", dir);
    assert_int_equal(symlink("/dev/full", p), 0);
    snprintf(args, sizeof args, "render " FAST " -o '%s'", p);
    tu_softgi_expect(args, 1, "full.exr: write failed: No space left on device");
    expect_no_temps(dir);
}

static void test_exr_stage_dumps(void **state)
{
    (void)state;
    char dir[512], args[2048], out[16384], p[800];
    make_dir("%s/dumps%s", "", dir, sizeof dir);
    static const char *const formats[3] = {"", "--dump-format both", "--dump-format exr"};
    static const char *const exrs[] = {"00-depth", "01-position", "02-normal", "03-albedo", "06-direct",
                                       "10-split", "11-accumulated", "12-combined", "13-filtered", "20-clamp",
                                       "14-final"};
    const int nexr = (int)(sizeof exrs / sizeof exrs[0]);
    uint64_t hash = 0;
    for (int k = 0; k < 3; k++) {
        snprintf(args, sizeof args,
                 "render --size 32x24 --vpls 16 --shadow-size 64 --threads 1 -q --hash -o '%s/f%d.png' "
                 "--dump-stages '%s/d%d' %s",
                 dir, k, dir, k, formats[k]);
        int st = tu_softgi_run(args, out, sizeof out);
        if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
        hash = printed_hash(out);
        snprintf(p, sizeof p, "%s/d%d", dir, k);
        int temps, files = count_entries(p, &temps);
        assert_int_equal(temps, 0);
        /* 21 pictures (png) and ranges.txt, 11 float files (exr), captions.txt */
        assert_int_equal(files, (k < 2 ? 21 + 1 : 0) + (k > 0 ? nexr : 0) + 1);
        size_t n;
        snprintf(p, sizeof p, "%s/d%d/captions.txt", dir, k);
        char *captions = read_all(p, &n);
        assert_int_equal(strstr(captions, ".exr: ") != NULL, k > 0);
        assert_int_equal(strstr(captions, ".png: ") != NULL, k < 2);
        free(captions);
        for (int e = 0; k > 0 && e < nexr; e++) {
            snprintf(p, sizeof p, "%s/d%d/%s.exr", dir, k, exrs[e]);
            assert_true(exr_is_float_zip(p));
            float *rgb = NULL;
            uint32_t w, h;
            pf_error err;
            if (pf_imageio_read_image(p, PF_IMAGEIO_DATA, &rgb, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
            assert_int_equal(w, 32);
            assert_int_equal(h, 24);
            if (e == 0) /* depth: one channel Y, read as R = G = B; +inf where no surface */
                for (size_t i = 0; i < 32 * 24; i++) assert_true(rgb[3 * i] == rgb[3 * i + 1] && rgb[3 * i] >= 0.0f);
            if (e == nexr - 1 && pf_imageio_hash(rgb, 3ull * w * h) != hash)
                fail_msg("%s is not the rendered image", p);
            free(rgb);
        }
    }
    /* the pictures are the same bytes with or without the float files */
    size_t n0, n1;
    snprintf(p, sizeof p, "%s/d0/14-final.png", dir);
    char *a = read_all(p, &n0);
    snprintf(p, sizeof p, "%s/d1/14-final.png", dir);
    char *b = read_all(p, &n1);
    assert_true(n0 == n1 && !memcmp(a, b, n0));
    free(a);
    free(b);
}

static void test_exr_input(void **state)
{
    (void)state;
    char dir[512], p[700], args[2048];
    make_dir("%s/exrin%s", "", dir, sizeof dir);
    pf_error err;
    float *back = NULL;
    uint32_t w, h;
    /* 1 (Y), 3 (RGB) and 4 (RGBA) channels written and read back (Y as grey, A dropped) */
    enum { W = 5, H = 3 };
    float px[W * H * 4];
    for (int i = 0; i < W * H * 4; i++) px[i] = 0.125f * (float)i;
    for (uint32_t c = 1; c <= 4; c++) {
        if (c == 2) continue;
        snprintf(p, sizeof p, "%s/c%u.exr", dir, c);
        /* c3.exr without a comment: its offset table follows screenWindowWidth (below) */
        assert_int_equal(pf_imageio_write_exr(p, px, W, H, c, PF_IMAGEIO_RADIANCE, c == 3 ? NULL : "a note", &err),
                         PF_OK);
        if (pf_imageio_read_image(p, PF_IMAGEIO_RADIANCE, &back, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
        assert_int_equal(w * h, W * H);
        for (int i = 0; i < W * H; i++)
            for (int k = 0; k < 3; k++) assert_true(back[3 * i + k] == px[c * i + (c == 1 ? 0 : k)]);
        free(back);
    }
    /* the writers' value rules: NaN refused (no file), signed data and inf only where allowed */
    px[7] = NAN;
    snprintf(p, sizeof p, "%s/nan.exr", dir);
    assert_int_equal(pf_imageio_write_exr(p, px, W, H, 3, PF_IMAGEIO_DATA, NULL, &err), PF_ERR_NONFINITE);
    assert_non_null(strstr(err.message, "nan.exr: 1 pixel is NaN (first: pixel (2, 0) channel G = nan); nothing written"));
    assert_false(tu_file_exists(p));
    px[7] = -INFINITY;
    assert_int_equal(pf_imageio_write_exr(p, px, W, H, 3, PF_IMAGEIO_RADIANCE, NULL, &err), PF_ERR_NONFINITE);
    assert_int_equal(pf_imageio_write_exr(p, px, W, H, 3, PF_IMAGEIO_DATA, NULL, &err), PF_OK);
    assert_int_equal(pf_imageio_read_image(p, PF_IMAGEIO_RADIANCE, &back, &w, &h, &err), PF_ERR_NONFINITE);
    assert_null(back);
    assert_non_null(strstr(err.message, "nan.exr: 1 pixel is NaN, infinite or negative"));
    /* compare reads what it is handed, and refuses broken files with one line */
    size_t n;
    snprintf(p, sizeof p, "%s/c3.exr", dir);
    char *good = read_all(p, &n);
    snprintf(p, sizeof p, "%s/cut.exr", dir);
    write_bytes(p, good, n / 2);
    snprintf(args, sizeof args, "compare '%s' '%s/c3.exr'", p, dir);
    tu_softgi_expect(args, 1, "cut.exr: ");
    snprintf(p, sizeof p, "%s/magic.exr", dir);
    write_bytes(p, good, 40);
    snprintf(args, sizeof args, "compare '%s/c3.exr' '%s'", dir, p);
    tu_softgi_expect(args, 1, "magic.exr: bad OpenEXR");
    snprintf(p, sizeof p, "%s/text.exr", dir);
    write_text(p, "not an image at all");
    snprintf(args, sizeof args, "compare '%s' '%s/c3.exr'", p, dir);
    tu_softgi_expect(args, 1, "text.exr: not a 3-channel PFM file or an OpenEXR file");
    /* a block that does not hold its own scanline (tinyexr would leave lines unset): refused */
    const char *sw = find_bytes(good, n, "screenWindowWidth", 18);
    assert_non_null(sw);
    size_t table = (size_t)(sw - good) + 18 + 6 + 4 + 4 + 1; /* name, "float", size, value, end of header */
    uint64_t off;
    memcpy(&off, good + table, 8);
    assert_true(off + 8 <= n);
    good[off] = 1; /* scanline 1 in block 0 */
    assert_int_equal(pf_imageio_read_exr_memory(good, n, "moved.exr", PF_IMAGEIO_DATA, 1u << 30, &back, &w, &h, &err),
                     PF_ERR_PARSE);
    assert_non_null(strstr(err.message, "moved.exr: OpenEXR block 0 starts at scanline 1, expected 0"));
    good[off] = 0;
    /* the memory budget is asked before anything is decoded */
    assert_int_equal(pf_imageio_read_exr_memory(good, n, "big.exr", PF_IMAGEIO_DATA, 100, &back, &w, &h, &err),
                     PF_ERR_OUT_OF_MEMORY);
    assert_non_null(strstr(err.message, "big.exr: decoding this 5x3 OpenEXR image of 3 channels needs"));
    assert_int_equal(pf_imageio_read_exr_memory(good, n, "ok.exr", PF_IMAGEIO_DATA, 1u << 30, &back, &w, &h, &err),
                     PF_OK);
    free(back);
    free(good);
    /* files from the OpenEXR library: every compression softgi reads, and those it refuses */
    static const struct {
        const char *file, *needle;
    } lib[] = {
        {"openexr-zip-half.exr", NULL},
        {"openexr-piz-float.exr", "OpenEXR compression PIZ (4) is not supported"},
        {"openexr-rle-float.exr", NULL},
        {"openexr-tiled.exr", "tiled OpenEXR files are not supported"},
        {"openexr-multipart.exr", "multi-part and deep OpenEXR files are not supported"},
        {"openexr-zip-float-decy.exr", "line order 1 is not supported"},
        {"openexr-b44-half.exr", "bad OpenEXR header"},
    };
    for (size_t i = 0; i < sizeof lib / sizeof lib[0]; i++) {
        snprintf(args, sizeof args, "compare '%s/tests/fuzz/regress/exr/%s' '%s/tests/fuzz/regress/exr/%s'",
                 SOFTGI_SOURCE_DIR, lib[i].file, SOFTGI_SOURCE_DIR, lib[i].file);
        tu_softgi_expect(args, lib[i].needle ? 1 : 0, lib[i].needle ? lib[i].needle : "RMSE       0\n");
    }
}

/* ---------------------------------------------------------------- values */

static void test_writers_refuse_bad_values(void **state)
{
    (void)state;
    char dir[512], path[600];
    make_dir("%s/values%s", "", dir, sizeof dir);
    enum { W = 4, H = 3 };
    float img[W * H * 3];
    for (int i = 0; i < W * H * 3; i++) img[i] = 0.5f;
    img[3 * (1 * W + 2) + 1] = NAN;  /* pixel (2, 1), G */
    img[3 * (2 * W + 0) + 0] = -1.0f; /* pixel (0, 2) */
    img[3 * (2 * W + 3) + 2] = INFINITY;
    pf_error err;
    snprintf(path, sizeof path, "%s/bad.pfm", dir);
    write_text(path, "previous");
    assert_int_equal(pf_imageio_write_pfm(path, img, W, H, &err), PF_ERR_NONFINITE);
    assert_non_null(strstr(err.message, "bad.pfm: 3 pixels are NaN, infinite or negative (first: pixel (2, 1) channel G = nan)"));
    char buf[64];
    read_text(path, buf, sizeof buf);
    assert_string_equal(buf, "previous"); /* untouched */
    snprintf(path, sizeof path, "%s/bad.png", dir);
    assert_int_equal(pf_imageio_write_png(path, img, W, H, 0.0f, &err), PF_ERR_NONFINITE);
    assert_non_null(strstr(err.message, "3 pixels are"));
    assert_false(tu_file_exists(path));
    /* one negative value alone, and +inf alone */
    for (int i = 0; i < W * H * 3; i++) img[i] = 0.5f;
    img[3 * (2 * W + 1)] = -0.25f;
    assert_int_equal(pf_imageio_write_png(path, img, W, H, 0.0f, &err), PF_ERR_NONFINITE);
    assert_non_null(strstr(err.message, "1 pixel is NaN, infinite or negative (first: pixel (1, 2) channel R = -0.25)"));
    img[3 * (2 * W + 1)] = INFINITY;
    assert_int_equal(pf_imageio_check("x", img, W, H, PF_IMAGEIO_RADIANCE, &err), PF_ERR_NONFINITE);
    /* a depth plane may hold +inf (no surface), not NaN or negatives */
    assert_int_equal(pf_imageio_check("x", img, W, H, PF_IMAGEIO_DEPTH, &err), PF_OK);
    snprintf(path, sizeof path, "%s/depth.pfm", dir);
    assert_int_equal(pf_imageio_write_pfm_range(path, img, W, H, PF_IMAGEIO_DEPTH, &err), PF_OK);
    float *back = NULL;
    uint32_t w, h;
    assert_int_equal(pf_imageio_read_pfm(path, &back, &w, &h, &err), PF_ERR_NONFINITE); /* not an image */
    assert_null(back);
    assert_int_equal(pf_imageio_read_pfm_range(path, &back, &w, &h, PF_IMAGEIO_DEPTH, &err), PF_OK);
    assert_true(isinf(back[3 * (2 * W + 1)]));
    free(back);
    img[0] = NAN;
    assert_int_equal(pf_imageio_check("x", img, W, H, PF_IMAGEIO_DEPTH, &err), PF_ERR_NONFINITE);
    /* -0 is not negative */
    for (int i = 0; i < W * H * 3; i++) img[i] = -0.0f;
    assert_int_equal(pf_imageio_check("x", img, W, H, PF_IMAGEIO_RADIANCE, &err), PF_OK);
    expect_no_temps(dir);
}

/* A PFM by hand: header + floats, little-endian, any values. */
static void write_raw_pfm(const char *path, const float *v, uint32_t w, uint32_t h)
{
    char head[64];
    int n = snprintf(head, sizeof head, "PF\n%u %u\n-1.0\n", w, h);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(head, 1, (size_t)n, f), (size_t)n);
    assert_int_equal(fwrite(v, sizeof(float) * 3, (size_t)w * h, f), (size_t)w * h);
    assert_int_equal(fclose(f), 0);
}

static void test_compare_refuses_nan(void **state)
{
    (void)state;
    char dir[512], a[600], b[600], args[2048], out[16384];
    make_dir("%s/cmp%s", "", dir, sizeof dir);
    float v[2 * 2 * 3] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    snprintf(a, sizeof a, "%s/a.pfm", dir);
    write_raw_pfm(a, v, 2, 2);
    v[3 * 3 + 2] = NAN; /* file row 1 = top row: pixel (1, 0) */
    snprintf(b, sizeof b, "%s/nan.pfm", dir);
    write_raw_pfm(b, v, 2, 2);
    snprintf(args, sizeof args, "compare '%s' '%s'", a, b);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 1 || strstr(out, "nan\n") || strstr(out, "RMSE") ||
        !strstr(out, "nan.pfm: 1 pixel is NaN, infinite or negative (first: pixel (1, 0) channel B = nan)"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);
    v[3 * 3 + 2] = INFINITY;
    write_raw_pfm(b, v, 2, 2);
    snprintf(args, sizeof args, "compare '%s' '%s'", b, a);
    tu_softgi_expect(args, 1, "nan.pfm: 1 pixel is NaN, infinite or negative");
    /* in a sequence folder too */
    char s1[600], f1[700];
    make_dir("%s/cmp%s", "/seq", s1, sizeof s1);
    make_frames(s1, 2);
    snprintf(f1, sizeof f1, "%s/frame_0001.pfm", s1);
    write_raw_pfm(f1, v, 2, 2);
    snprintf(args, sizeof args, "compare --reference '%s' --name x:'%s'", s1, s1);
    tu_softgi_expect(args, 1, "frame_0001.pfm: 1 pixel is NaN, infinite or negative");
}

static void test_pfm_parser(void **state)
{
    (void)state;
    float *rgb = NULL;
    uint32_t w = 7, h = 7;
    pf_error err;
    const float one = 1.0f, two = 2.0f, three = 3.0f;
    uint8_t buf[256];
    /* a 1x2 little-endian RGB PFM: bottom row (1,2,3), top row (2,2,2) */
    size_t n = (size_t)snprintf((char *)buf, sizeof buf, "PF\n1 2\n-1\n");
    const float rows[6] = {one, two, three, two, two, two};
    memcpy(buf + n, rows, sizeof rows);
    assert_int_equal(pf_imageio_read_pfm_memory(buf, n + sizeof rows, &rgb, &w, &h, &err), PF_OK);
    assert_int_equal(w, 1);
    assert_int_equal(h, 2);
    assert_true(rgb[0] == 2.0f && rgb[3] == 1.0f && rgb[5] == 3.0f); /* top row first */
    free(rgb);
    /* big-endian grey, "\r\n" after the scale */
    n = (size_t)snprintf((char *)buf, sizeof buf, "Pf 2 1 1.0\r\n");
    const uint8_t be[8] = {0x3f, 0x80, 0, 0, 0x40, 0, 0, 0}; /* 1.0f, 2.0f */
    memcpy(buf + n, be, 8);
    assert_int_equal(pf_imageio_read_pfm_memory(buf, n + 8, &rgb, &w, &h, &err), PF_OK);
    assert_true(w == 2 && h == 1 && rgb[0] == 1.0f && rgb[2] == 1.0f && rgb[3] == 2.0f && rgb[5] == 2.0f);
    free(rgb);

    static const struct {
        const char *head;
        size_t data; /* bytes of 0.5f-ish data after the header */
        const char *needle;
    } bad[] = {
        {"", 0, "not a 3-channel PFM"},
        {"P6\n1 1\n255\n", 3, "not a 3-channel PFM"},
        {"PF", 0, "bad PFM header"},
        {"PF\n0 1\n-1\n", 0, "bad PFM header"},
        {"PF\n-1 1\n-1\n", 12, "bad PFM header"},
        {"PF\n32769 1\n-1\n", 12, "bad PFM header"},
        {"PF\n99999999999999999999999 1\n-1\n", 12, "bad PFM header"},
        {"PF\n32768 32768\n-1\n", 12, "more than 268435456 pixels"},
        {"PF\n16384 16384\n-1\n", 12, "bytes of pixel data, a 16384x16384 RGB PFM has 3221225472 (truncated)"},
        {"PF\n1 1\n-1\n", 11, "(truncated)"},
        {"PF\n1 1\n-1\n", 13, "(trailing bytes)"},
        {"PF\n1 1\n-1", 0, "PFM header without pixel data"},
        {"PF\n1 1\n0\n", 12, "bad PFM scale '0'"},
        {"PF\n1 1\nnan\n", 12, "bad PFM scale 'nan'"},
        {"PF\n1 1\n-inf\n", 12, "bad PFM scale"},
        {"PF\n1 1\n1e999\n", 12, "bad PFM scale"},
        {"PF\n1 1\n-1x\n", 12, "bad PFM scale '-1x'"},
        {"PF\n1 1\n\n", 12, "bad PFM scale"},
        {"PF1 1 -1\n", 12, "bad PFM header"},
        {"PF\n1x1\n-1\n", 12, "bad PFM header"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        n = strlen(bad[i].head);
        memcpy(buf, bad[i].head, n);
        for (size_t k = 0; k < bad[i].data; k++) buf[n + k] = k % 4 == 3 ? 0x3f : 0; /* 0.5f little-endian */
        rgb = (float *)buf;
        memset(&err, 0, sizeof err);
        pf_result r = pf_imageio_read_pfm_memory(buf, n + bad[i].data, &rgb, &w, &h, &err);
        if (r == PF_OK || rgb || !strstr(err.message, bad[i].needle))
            fail_msg("case %zu: got %d '%s', want '%s'", i, (int)r, err.message, bad[i].needle);
    }
    /* values: NaN and negatives refused with their first pixel */
    n = (size_t)snprintf((char *)buf, sizeof buf, "PF\n2 1\n-1\n");
    const float vals[6] = {0.5f, 0.5f, 0.5f, 0.5f, -2.0f, 0.5f};
    memcpy(buf + n, vals, sizeof vals);
    assert_int_equal(pf_imageio_read_pfm_memory(buf, n + sizeof vals, &rgb, &w, &h, &err), PF_ERR_NONFINITE);
    assert_non_null(strstr(err.message, "PFM data: 1 pixel is NaN, infinite or negative (first: pixel (1, 0) channel G = -2)"));
    assert_null(rgb);
}

/* ---------------------------------------------------------------- sequences */

/* Runs `softgi ARGS` in `cwd` (the sequence's out/ is relative to it). */
static int run_in(const char *cwd, const char *args, char *out, size_t size)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "cd '%s' && %s %s", cwd, SOFTGI_BINARY, args);
    int st = tu_run(cmd, out, size);
    if (st < 0 || st > 2) fail_msg("'%s' ended abnormally (status %d):\n%s", cmd, st, out);
    return st;
}

static void test_sequence_output_confined(void **state)
{
    (void)state;
    char work[512], elsewhere[512], seq[600], args[2048], out[16384], p[800];
    make_dir("%s/confined%s", "/work", work, sizeof work);
    make_dir("%s/confined%s", "/elsewhere", elsewhere, sizeof elsewhere);
    snprintf(seq, sizeof seq, "%s/s.seq.json", work);
    snprintf(args, sizeof args, "sequence s.seq.json --direct-only --shadow-size 64 --threads 1 -q");
    char abs_out[600], abs_needle[700];
    snprintf(abs_out, sizeof abs_out, "%s/confined/escape-abs", g_tmp);
    snprintf(abs_needle, sizeof abs_needle, "output: '%s': must be a relative folder", abs_out);
    const struct {
        const char *output, *needle;
    } bad[] = {
        {abs_out, abs_needle},
        {"../escape", "output: '../escape': must not contain '..'"},
        {"a/../../escape", "must not contain '..'"},
    };
    char json[2048];
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(json, sizeof json,
                 "{\"scene\": \"embedded:cornell-box\", \"frames\": 1, \"size\": [32, 24], \"output\": \"%s\"}",
                 bad[i].output);
        write_text(seq, json);
        int st = run_in(work, args, out, sizeof out);
        if (st != 1 || !strstr(out, bad[i].needle)) fail_msg("output %s: exit %d\n%s", bad[i].output, st, out);
    }
    assert_false(tu_file_exists(abs_out));
    snprintf(p, sizeof p, "%s/confined/escape", g_tmp);
    assert_false(tu_file_exists(p));
    /* a link inside out/ pointing elsewhere: refused, nothing created there */
    char outdir[600];
    snprintf(outdir, sizeof outdir, "%s/out", work);
    assert_int_equal(mkdir(outdir, 0755), 0);
    snprintf(p, sizeof p, "%s/out/link", work);
    assert_int_equal(symlink(elsewhere, p), 0);
    write_text(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 1, \"size\": [32, 24], \"output\": \"link/x\"}");
    int st = run_in(work, args, out, sizeof out);
    if (st != 1 || !strstr(out, "s.seq.json: output folder out/link/x: 'link' is a symbolic link or not a folder"))
        fail_msg("link: exit %d\n%s", st, out);
    int temps;
    assert_int_equal(count_entries(elsewhere, &temps), 0);
    /* the name chooses out/NAME: ".." is refused there too */
    write_text(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 1, \"name\": \"..\"}");
    st = run_in(work, args, out, sizeof out);
    if (st != 1 || !strstr(out, "name: expected 1 to")) fail_msg("name ..: exit %d\n%s", st, out);
    /* a good relative output lands under out/ */
    write_text(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 1, \"size\": [32, 24], \"output\": \"a/./b\"}");
    st = run_in(work, args, out, sizeof out);
    if (st != 0) fail_msg("a/./b: exit %d\n%s", st, out);
    snprintf(p, sizeof p, "%s/out/a/b/frame_0000.pfm", work);
    assert_true(tu_file_exists(p));
    /* -o is the user's choice: anywhere */
    snprintf(args, sizeof args, "sequence s.seq.json -o '%s/mine' --direct-only --shadow-size 64 --threads 1 -q",
             elsewhere);
    st = run_in(work, args, out, sizeof out);
    if (st != 0) fail_msg("-o: exit %d\n%s", st, out);
    snprintf(p, sizeof p, "%s/mine/frame_0000.png", elsewhere);
    assert_true(tu_file_exists(p));
}

static void test_sequence_deletes_nothing(void **state)
{
    (void)state;
    char dir[512], seq[600], args[2048], out[32768], p[1024], buf[128];
    make_dir("%s/keep%s", "", dir, sizeof dir);
    /* another run's longer sequence and someone's own files */
    make_frames(dir, 5);
    snprintf(p, sizeof p, "%s/frame_0099.png", dir);
    write_text(p, "not softgi's");
    snprintf(p, sizeof p, "%s/frame_0003.png", dir);
    write_text(p, "older run");
    snprintf(p, sizeof p, "%s/track.txt", dir);
    write_text(p, "1,1\n");
    snprintf(seq, sizeof seq, "%s/two.seq.json", g_tmp);
    write_text(seq, "{\"scene\": \"embedded:cornell-box\", \"frames\": 2, \"size\": [32, 24]}");
    snprintf(args, sizeof args, "sequence '%s' -o '%s' --direct-only --shadow-size 64 --threads 1 -q", seq, dir);
    tu_softgi_expect(args, 0, NULL);
    snprintf(p, sizeof p, "%s/frame_0099.png", dir);
    read_text(p, buf, sizeof buf);
    assert_string_equal(buf, "not softgi's");
    snprintf(p, sizeof p, "%s/frame_0003.png", dir);
    read_text(p, buf, sizeof buf);
    assert_string_equal(buf, "older run");
    for (int t = 2; t < 5; t++) {
        snprintf(p, sizeof p, "%s/frame_%04d.pfm", dir, t);
        assert_true(tu_file_exists(p));
    }
    /* track.txt is this run's now (no "track": empty, compare's default grid) */
    snprintf(p, sizeof p, "%s/track.txt", dir);
    assert_int_equal(read_text(p, buf, sizeof buf), 0);
    snprintf(p, sizeof p, "%s/frames.txt", dir);
    read_text(p, buf, sizeof buf);
    assert_string_equal(buf, "softgi-frames 1\nframes 2\nstate complete\n");
    /* compare reads this run's 2 frames, not the 5 + 1 files in the folder */
    snprintf(args, sizeof args, "compare --reference '%s' --name me:'%s'", dir, dir);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 0 || !strstr(out, "2 frames, 32x24") || !strstr(out, "| me | 2 |"))
        fail_msg("softgi %s: exit %d\n%s", args, st, out);

    /* a run that fails at frame 1 (a folder where frame_0001.png goes)
     * leaves the manifest "running": compare refuses the folder */
    char d2[600];
    make_dir("%s/keep%s", "/failed", d2, sizeof d2);
    snprintf(p, sizeof p, "%s/frame_0001.png", d2);
    assert_int_equal(mkdir(p, 0755), 0);
    snprintf(args, sizeof args, "sequence '%s' -o '%s' --direct-only --shadow-size 64 --threads 1 -q", seq, d2);
    tu_softgi_expect(args, 1, "frame_0001.png: is a folder, not a file");
    snprintf(p, sizeof p, "%s/frames.txt", d2);
    read_text(p, buf, sizeof buf);
    assert_string_equal(buf, "softgi-frames 1\nframes 2\nstate running\n");
    snprintf(args, sizeof args, "compare --reference '%s' --name me:'%s'", dir, d2);
    tu_softgi_expect(args, 1, "frames.txt says the run writing it has not finished");
    expect_no_temps(d2);
    /* a manifest listing a frame that is missing, and a malformed one */
    snprintf(p, sizeof p, "%s/frames.txt", d2);
    write_text(p, "softgi-frames 1\nframes 3\nstate complete\n");
    tu_softgi_expect(args, 1, "frame_0002.pfm: missing");
    write_text(p, "softgi-frames 1\nframes -3\nstate complete\n");
    tu_softgi_expect(args, 1, "not a softgi-frames 1 manifest");
    /* --reuse-frames refuses a folder whose manifest is of another run */
    write_text(p, "softgi-frames 1\nframes 7\nstate complete\n");
    snprintf(args, sizeof args, "sequence '%s' -o '%s' --reference --spp 1 --track-spp 2 --reuse-frames " FAST, seq,
             d2);
    tu_softgi_expect(args, 2, "--reuse-frames:");
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-test-output");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_device),
        cmocka_unit_test(test_readonly_folder),
        cmocka_unit_test(test_success_leaves_no_temps),
        cmocka_unit_test(test_pfm_output_keeps_png),
        cmocka_unit_test(test_unsupported_names),
        cmocka_unit_test(test_formats_read_back),
        cmocka_unit_test(test_exr_stage_dumps),
        cmocka_unit_test(test_exr_input),
        cmocka_unit_test(test_writers_refuse_bad_values),
        cmocka_unit_test(test_compare_refuses_nan),
        cmocka_unit_test(test_pfm_parser),
        cmocka_unit_test(test_sequence_output_confined),
        cmocka_unit_test(test_sequence_deletes_nothing),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
