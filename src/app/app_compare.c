/* app_compare: `softgi compare`, the evaluation's metrics (gi_metrics.h).
 *
 *   softgi compare IMAGE REFERENCE
 *     RMSE and MAE over linear RGB, and |E| over all pixels; each image a
 *     PFM or an OpenEXR file (pf_imageio_read_image: told apart by their
 *     first bytes; untrusted input, read within size limits and the memory
 *     budget).
 *   softgi compare --reference REFDIR --name NAME:DIR [--name NAME:DIR ...]
 *     A Markdown table of |E| and |E'| (Hedman 2017 Table 1, Eq. 10) over the
 *     tracked pixels, TID (Barak 2013 Sec. 6.2) and the mean RMSE per method,
 *     and an SVG plot of the tracked pixels' luminance over time, one panel
 *     per pixel, like Hedman 2017 Fig. 7.
 *
 * A sequence folder holds frame_NNNN.pfm from 0000 on, and for TID
 * frame_NNNN.view and frame_NNNN.depth.pfm (format in gi_metrics.h); a
 * method folder without views borrows the reference folder's (same camera
 * path). When the folder has the manifest frames.txt (pf_sequence.h) that
 * `softgi sequence` writes, exactly its frames are read (frame files of an
 * older, longer run beside them are ignored) and a folder whose run has not
 * finished is refused; without one, frames are read up to the first
 * missing frame_NNNN.pfm. Images must be finite and >= 0 (pf_imageio
 * refuses others, naming the file and the first bad pixel), so no metric is
 * ever NaN; depth files may hold +inf (no surface). --table and --plot are
 * written atomically (pf_imageio.h) and must name different files. Errors
 * are one line on stderr: exit 2 for bad usage, 1 for missing, mismatched
 * or bad files. */
#include <errno.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app.h"
#include "gi_metrics.h"
#include "pf_imageio.h"
#include "pf_sequence.h"

#define CMP_MAX_SERIES 16
#define CMP_MAX_TRACK 64

typedef struct cmp__series {
    const char *name;
    const char *dir;
    const char *view_dir; /* where frame_NNNN.view/.depth.pfm are read; NULL: no TID */
    uint32_t frames;
    float *lum;           /* [frames * track_count] tracked display luminance */
    double e, e_rate, tid, rmse;
} cmp__series;

typedef struct cmp__args {
    const char *positional[2];
    int positional_count;
    const char *reference;
    const char *plot, *table;
    float exposure_scale;
    gi_metrics_tid_desc tid;
    uint32_t track_count; /* grid size when no --track is given */
    gi_metrics_pixel track[CMP_MAX_TRACK];
    uint32_t track_given;
    cmp__series series[CMP_MAX_SERIES + 1]; /* [0] = the reference */
    uint32_t series_count;
} cmp__args;

static void cmp__usage(FILE *f)
{
    fputs("usage: softgi compare IMAGE REFERENCE [--exposure EV]      (each .pfm or .exr)\n"
          "       softgi compare --reference REFDIR --name NAME:DIR [--name NAME:DIR ...]\n"
          "                      [--track X,Y ...] [--tracked K] [--plot OUT.svg] [--table OUT.md]\n"
          "                      [--exposure EV] [--depth-tolerance F] [--tid-tonemapped]\n"
          "\n"
          "Two images: RMSE and MAE over linear RGB; |E|, the mean absolute difference of\n"
          "Reinhard-tone-mapped luminance Y/(1+Y) (Rec. 709 Y) over all pixels.\n"
          "\n"
          "Sequences: folders of frame_0000.pfm, frame_0001.pfm, ... For each method, against\n"
          "the reference, over the tracked pixels (Hedman et al. 2017, Table 1):\n"
          "  |E|   mean |T(Y) - T(Y_ref)|, T(Y) = Y / (1 + Y)\n"
          "  |E'|  mean |E_t - E_t-1|, the frame-to-frame change of the error (Eq. 10)\n"
          "  TID   RMS difference of the linear luminance of reprojected pixels between\n"
          "        consecutive frames (Barak et al. 2013, Sec. 6.2); needs frame_NNNN.view and\n"
          "        frame_NNNN.depth.pfm in the method's folder or the reference folder\n"
          "  RMSE  mean over frames of the linear RGB RMSE against the reference frame\n"
          "The table is printed as Markdown (and written to --table); --plot writes an SVG of\n"
          "the tracked pixels' tone-mapped luminance over time, one panel per pixel.\n"
          "\n"
          "  --track X,Y          track pixel (X, Y) (x right, y down from the top-left);\n"
          "                       repeatable; default: a grid of --tracked pixels\n"
          "  --tracked K          number of grid pixels (default 8, as Hedman et al.)\n"
          "  --exposure EV        scale linear values by 2^EV before the tone map (default 0)\n"
          "  --depth-tolerance F  relative depth agreement for a TID match (default 0.01)\n"
          "  --tid-tonemapped     TID on T(Y) instead of linear Y\n",
          f);
}

/* Prints "softgi compare: MESSAGE" on stderr; returns status. */
static int cmp__fail(int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static int cmp__fail(int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("softgi compare: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    return status;
}

static int cmp__parse_float(const char *s, float *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v)) return 0;
    *out = (float)v;
    return 1;
}

static int cmp__parse_uint(const char *s, const char **end_out, uint32_t *out)
{
    char *end;
    if (*s < '0' || *s > '9') return 0;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || v > 0xffffffffu) return 0;
    *out = (uint32_t)v;
    *end_out = end;
    return 1;
}

/* Returns 0 on success, else the exit status (message printed). */
static int cmp__parse(cmp__args *a, int argc, char **argv, int *help)
{
    memset(a, 0, sizeof *a);
    a->exposure_scale = 1.0f;
    a->track_count = GI_METRICS_DEFAULT_TRACKED;
    a->series_count = 1;
    a->series[0].name = "reference";
    for (int i = 2; i < argc; i++) {
        const char *o = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--help") || !strcmp(o, "-h")) {
            *help = 1;
            return 0;
        }
        if (o[0] != '-' || !o[1]) {
            if (a->positional_count == 2) return cmp__fail(2, "unexpected argument '%s'", o);
            a->positional[a->positional_count++] = o;
            continue;
        }
        int takes_value = !strcmp(o, "--reference") || !strcmp(o, "--name") || !strcmp(o, "--track") ||
                          !strcmp(o, "--tracked") || !strcmp(o, "--plot") || !strcmp(o, "--table") ||
                          !strcmp(o, "--exposure") || !strcmp(o, "--depth-tolerance");
        if (!strcmp(o, "--tid-tonemapped")) {
            a->tid.tonemapped = 1;
            continue;
        }
        if (!takes_value) return cmp__fail(2, "unknown option '%s' (see softgi compare --help)", o);
        if (!v) return cmp__fail(2, "%s needs a value", o);
        i++;
        if (!strcmp(o, "--reference")) {
            a->reference = v;
        } else if (!strcmp(o, "--plot")) {
            size_t n = strlen(v);
            if (n < 4 || strcmp(v + n - 4, ".svg") != 0)
                return cmp__fail(2, "--plot '%s': the plot is SVG; name it *.svg", v);
            a->plot = v;
        } else if (!strcmp(o, "--table")) {
            a->table = v;
        } else if (!strcmp(o, "--exposure")) {
            float ev;
            if (!cmp__parse_float(v, &ev) || fabsf(ev) > 64.0f)
                return cmp__fail(2, "--exposure '%s': expected a number of stops in [-64, 64]", v);
            a->exposure_scale = exp2f(ev);
        } else if (!strcmp(o, "--depth-tolerance")) {
            float t;
            if (!cmp__parse_float(v, &t) || !(t > 0.0f))
                return cmp__fail(2, "--depth-tolerance '%s': expected a positive number", v);
            a->tid.depth_tolerance = t;
        } else if (!strcmp(o, "--tracked")) {
            const char *end;
            uint32_t k;
            if (!cmp__parse_uint(v, &end, &k) || *end || k == 0 || k > CMP_MAX_TRACK)
                return cmp__fail(2, "--tracked '%s': expected 1 to 64 pixels", v);
            a->track_count = k;
        } else if (!strcmp(o, "--track")) {
            const char *end;
            gi_metrics_pixel p;
            if (!cmp__parse_uint(v, &end, &p.x) || *end != ',' || !cmp__parse_uint(end + 1, &end, &p.y) || *end)
                return cmp__fail(2, "--track '%s': expected X,Y (pixel coordinates)", v);
            if (a->track_given == CMP_MAX_TRACK) return cmp__fail(2, "too many --track pixels (at most 64)");
            a->track[a->track_given++] = p;
        } else { /* --name */
            const char *colon = strchr(v, ':');
            if (!colon || colon == v || !colon[1])
                return cmp__fail(2, "--name '%s': expected NAME:DIR", v);
            if (a->series_count == CMP_MAX_SERIES + 1)
                return cmp__fail(2, "too many --name methods (at most 16)");
            /* Split in place: argv strings are writable (C17 5.1.2.2.1). */
            char *c = (char *)colon;
            *c = 0;
            a->series[a->series_count].name = v;
            a->series[a->series_count].dir = c + 1;
            a->series_count++;
        }
    }
    if (a->positional_count > 0 && (a->reference || a->series_count > 1))
        return cmp__fail(2, "give either IMAGE REFERENCE or --reference/--name, not both");
    if (a->positional_count == 1)
        return cmp__fail(2, "missing REFERENCE.pfm or .exr (usage: softgi compare IMAGE REFERENCE)");
    if (a->positional_count == 0) {
        if (!a->reference && a->series_count == 1)
            return cmp__fail(2, "nothing to compare (see softgi compare --help)");
        if (!a->reference) return cmp__fail(2, "--name needs --reference REFDIR");
        if (a->series_count == 1) return cmp__fail(2, "--reference needs at least one --name NAME:DIR");
        a->series[0].dir = a->reference;
    } else if (a->plot || a->table || a->track_given) {
        return cmp__fail(2, "--plot, --table and --track apply to sequences (--reference/--name)");
    }
    if (a->plot && a->table && pf_imageio_same_output(a->plot, a->table))
        return cmp__fail(2, "--table '%s' and --plot '%s' name the same file", a->table, a->plot);
    return 0;
}

/* ---------------------------------------------------------------- two images */

static int cmp__images(const cmp__args *a)
{
    pf_error err;
    float *img = NULL, *ref = NULL;
    uint32_t w, h, rw, rh;
    int status = 1;
    if (pf_imageio_read_image(a->positional[0], PF_IMAGEIO_RADIANCE, &img, &w, &h, &err) != PF_OK ||
        pf_imageio_read_image(a->positional[1], PF_IMAGEIO_RADIANCE, &ref, &rw, &rh, &err) != PF_OK) {
        fprintf(stderr, "softgi compare: %s\n", err.message);
        goto done;
    }
    if (w != rw || h != rh) {
        fprintf(stderr, "softgi compare: size mismatch: %s is %ux%u, %s is %ux%u\n", a->positional[0], w, h,
                a->positional[1], rw, rh);
        goto done;
    }
    size_t n = (size_t)w * h;
    printf("image      %s\nreference  %s\nsize       %ux%u\n", a->positional[0], a->positional[1], w, h);
    printf("RMSE       %.6g\n", gi_metrics_rmse(img, ref, n));
    printf("MAE        %.6g\n", gi_metrics_mae(img, ref, n));
    printf("|E|        %.6g   (mean |T(Y) - T(Y_ref)| over all %zu pixels, T(Y) = Y/(1+Y))\n",
           gi_metrics_abs_error_image(img, ref, n, a->exposure_scale), n);
    size_t counted = 0;
    double mre = gi_metrics_mean_relative_error(img, ref, n, GI_METRICS_MRE_FLOOR, &counted);
    printf("MRE        %.6g   (mean |Y - Y_ref| / Y_ref over the %zu pixels with Y_ref > %g)\n", mre, counted,
           (double)GI_METRICS_MRE_FLOOR);
    printf("energy     %.6g   (sum of Y over sum of Y_ref)\n", gi_metrics_energy_ratio(img, ref, n));
    status = 0;
done:
    free(img);
    free(ref);
    return status;
}

/* ---------------------------------------------------------------- sequences */

static void cmp__frame_path(char *buf, size_t size, const char *dir, uint32_t t, const char *ext)
{
    snprintf(buf, size, "%s/frame_%04u%s", dir, t, ext);
}

static int cmp__exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* The folder's frames: those its manifest lists (all must exist), else
 * frame_0000.pfm, frame_0001.pfm, ... up to the first gap. */
static int cmp__count_frames(const char *dir, uint32_t *frames)
{
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
        return cmp__fail(1, "%s: no such directory", dir);
    char path[4096];
    pf_sequence_manifest m;
    int present = 0;
    pf_error err;
    if (pf_sequence_manifest_read(dir, &m, &present, &err) != PF_OK) return cmp__fail(1, "%s", err.message);
    if (present) {
        if (!m.complete)
            return cmp__fail(1, "%s: %s says the run writing it has not finished (or failed); run softgi sequence "
                                "again",
                             dir, PF_SEQUENCE_MANIFEST);
        for (uint32_t t = 0; t < m.frames; t++) {
            cmp__frame_path(path, sizeof path, dir, t, ".pfm");
            if (!cmp__exists(path))
                return cmp__fail(1, "%s: missing (%s/%s lists %u frames)", path, dir, PF_SEQUENCE_MANIFEST, m.frames);
        }
        *frames = m.frames;
        return 0;
    }
    uint32_t n = 0;
    for (;; n++) {
        cmp__frame_path(path, sizeof path, dir, n, ".pfm");
        if (!cmp__exists(path)) break;
    }
    if (n == 0) return cmp__fail(1, "%s: empty sequence (no frame_0000.pfm)", dir);
    *frames = n;
    return 0;
}

/* Loads frame t of a folder, checking its size. */
static int cmp__load_frame(const char *dir, uint32_t t, uint32_t w, uint32_t h, float **rgb)
{
    char path[4096];
    pf_error err;
    uint32_t fw, fh;
    cmp__frame_path(path, sizeof path, dir, t, ".pfm");
    if (pf_imageio_read_pfm(path, rgb, &fw, &fh, &err) != PF_OK) return cmp__fail(1, "%s", err.message);
    if (fw != w || fh != h) {
        fprintf(stderr, "softgi compare: size mismatch: %s is %ux%u, the reference frames are %ux%u\n", path, fw, fh,
                w, h);
        return 1;
    }
    return 0;
}

typedef struct cmp__view_frame {
    gi_metrics_view view;
    float *rgb, *depth;
} cmp__view_frame;

static int cmp__load_view(const char *dir, uint32_t t, uint32_t w, uint32_t h, cmp__view_frame *f)
{
    char path[4096];
    pf_error err;
    uint32_t dw, dh;
    cmp__frame_path(path, sizeof path, dir, t, ".view");
    if (gi_metrics_view_read(path, &f->view, &err) != PF_OK) return cmp__fail(1, "%s", err.message);
    if (f->view.width != w || f->view.height != h) {
        fprintf(stderr, "softgi compare: size mismatch: %s is for %ux%u, the frames are %ux%u\n", path,
                f->view.width, f->view.height, w, h);
        return 1;
    }
    cmp__frame_path(path, sizeof path, dir, t, ".depth.pfm");
    if (gi_metrics_depth_read(path, &f->depth, &dw, &dh, &err) != PF_OK) return cmp__fail(1, "%s", err.message);
    if (dw != w || dh != h) {
        fprintf(stderr, "softgi compare: size mismatch: %s is %ux%u, the frames are %ux%u\n", path, dw, dh, w, h);
        return 1;
    }
    return 0;
}

/* Runs one series over its frames: tracked luminance, TID, and RMSE against
 * the reference (series other than [0]). */
static int cmp__run_series(const cmp__args *a, cmp__series *s, uint32_t frames, uint32_t w, uint32_t h,
                           const gi_metrics_pixel *track, uint32_t track_count)
{
    int status = 1;
    float *ref = NULL;
    cmp__view_frame fr[2];
    memset(fr, 0, sizeof fr);
    gi_metrics_tid_sum tid = {0};
    double rmse = 0.0;
    const int is_ref = s == &a->series[0];
    s->lum = malloc((size_t)frames * track_count * sizeof(float));
    if (!s->lum) return cmp__fail(1, "out of memory");
    for (uint32_t t = 0; t < frames; t++) {
        cmp__view_frame *cur = &fr[t & 1], *prev = &fr[(t + 1) & 1];
        free(cur->rgb);
        free(cur->depth);
        cur->rgb = cur->depth = NULL;
        if (cmp__load_frame(s->dir, t, w, h, &cur->rgb)) goto done;
        gi_metrics_track_sample(s->lum + (size_t)t * track_count, cur->rgb, w, h, track, track_count,
                                a->exposure_scale);
        if (!is_ref) {
            free(ref);
            ref = NULL;
            if (cmp__load_frame(a->series[0].dir, t, w, h, &ref)) goto done;
            rmse += gi_metrics_rmse(cur->rgb, ref, (size_t)w * h);
        }
        if (s->view_dir) {
            if (cmp__load_view(s->view_dir, t, w, h, cur)) goto done;
            if (t > 0) {
                gi_metrics_frame f0 = {prev->rgb, prev->depth, &prev->view};
                gi_metrics_frame f1 = {cur->rgb, cur->depth, &cur->view};
                gi_metrics_tid_pair(&tid, &f0, &f1, &a->tid);
            }
        }
    }
    s->tid = s->view_dir && frames > 1 ? gi_metrics_tid_value(&tid) : NAN;
    s->rmse = is_ref ? NAN : rmse / frames;
    status = 0;
done:
    free(ref);
    for (int i = 0; i < 2; i++) {
        free(fr[i].rgb);
        free(fr[i].depth);
    }
    return status;
}

static void cmp__md_escaped(FILE *f, const char *s)
{
    for (; *s; s++) {
        if (*s == '|' || *s == '\\') fputc('\\', f);
        fputc(*s, f);
    }
}

static void cmp__md_number(FILE *f, double v)
{
    if (isnan(v))
        fputs(" - |", f);
    else
        fprintf(f, " %.6g |", v);
}

static void cmp__write_table(FILE *f, const cmp__args *a, uint32_t frames, uint32_t w, uint32_t h,
                             const gi_metrics_pixel *track, uint32_t track_count)
{
    fprintf(f, "Reference `%s`: %u frames, %ux%u. Tracked pixels (%u):", a->series[0].dir, frames, w, h,
            track_count);
    for (uint32_t k = 0; k < track_count; k++) fprintf(f, " (%u,%u)", track[k].x, track[k].y);
    fprintf(f, ".\nMetrics: |E| and |E'| on tone-mapped luminance Y/(1+Y) (Hedman 2017, Table 1, Eq. 10); TID: RMS "
               "of %s differences of reprojected pixels, depth tolerance %g (Barak 2013, Sec. 6.2).\n\n",
            a->tid.tonemapped ? "tone-mapped luminance" : "linear luminance",
            (double)(a->tid.depth_tolerance > 0.0f ? a->tid.depth_tolerance : GI_METRICS_DEFAULT_DEPTH_TOLERANCE));
    fputs("| method | frames | mean \\|E\\| | mean \\|E'\\| | TID | RMSE |\n", f);
    fputs("|---|---:|---:|---:|---:|---:|\n", f);
    for (uint32_t i = 0; i < a->series_count; i++) {
        const cmp__series *s = &a->series[i];
        fputs("| ", f);
        cmp__md_escaped(f, s->name);
        fprintf(f, " | %u |", frames);
        cmp__md_number(f, i ? s->e : NAN);
        cmp__md_number(f, i ? s->e_rate : NAN);
        cmp__md_number(f, s->tid);
        cmp__md_number(f, i ? s->rmse : NAN);
        fputc('\n', f);
    }
}

static void cmp__xml_escaped(FILE *f, const char *s)
{
    for (; *s; s++) switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&apos;", f); break;
        default: fputc(*s, f);
        }
}

/* What the table and the plot are printed from. */
typedef struct cmp__print {
    const cmp__args *a;
    uint32_t frames, w, h;
    const gi_metrics_pixel *track;
    uint32_t track_count;
} cmp__print;

static int cmp__print_table(FILE *f, void *user)
{
    const cmp__print *p = user;
    cmp__write_table(f, p->a, p->frames, p->w, p->h, p->track, p->track_count);
    return 0;
}

/* Hedman 2017 Fig. 7 as small multiples: one panel per tracked pixel, the
 * reference in black and one coloured polyline per method. */
static int cmp__print_plot(FILE *f, void *user)
{
    const cmp__print *p = user;
    const cmp__args *a = p->a;
    const uint32_t frames = p->frames, track_count = p->track_count;
    const gi_metrics_pixel *track = p->track;
    static const char *const colors[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd",
                                         "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"};
    const int ncolors = (int)(sizeof colors / sizeof colors[0]);
    const uint32_t cols = track_count < 2 ? 1 : 2, rows = (track_count + cols - 1) / cols;
    const double pw = 300, ph = 170;           /* plot area of a panel */
    const double ml = 60, mr = 20, mt = 30, mb = 40; /* panel margins */
    const double legend_h = 30 + 18.0 * ((a->series_count + 3) / 4);
    const double W = cols * (ml + pw + mr), H = legend_h + rows * (mt + ph + mb);
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
            "font-family=\"sans-serif\" font-size=\"11\">\n"
            "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
            "<text x=\"10\" y=\"18\" font-size=\"13\">Tracked-pixel luminance Y/(1+Y) over time "
            "(Hedman et al. 2017, Fig. 7)</text>\n",
            W, H, W, H);
    for (uint32_t i = 0; i < a->series_count; i++) { /* legend */
        double lx = 10 + 180.0 * (i % 4), ly = 36 + 18.0 * (i / 4);
        const char *c = i ? colors[(i - 1) % ncolors] : "black";
        fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"2\"/>\n", lx,
                ly - 4, lx + 24, ly - 4, c);
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\">", lx + 30, ly);
        cmp__xml_escaped(f, a->series[i].name);
        fputs("</text>\n", f);
    }
    for (uint32_t k = 0; k < track_count; k++) {
        const double x0 = (k % cols) * (ml + pw + mr) + ml, y0 = legend_h + (k / cols) * (mt + ph + mb) + mt;
        double lo = INFINITY, hi = -INFINITY;
        for (uint32_t i = 0; i < a->series_count; i++)
            for (uint32_t t = 0; t < frames; t++) {
                double v = a->series[i].lum[(size_t)t * track_count + k];
                lo = fmin(lo, v);
                hi = fmax(hi, v);
            }
        double pad = 0.05 * (hi - lo);
        if (!(pad > 1e-4)) pad = 1e-4 + 0.01 * fabs(hi); /* flat series: a visible band around it */
        lo = lo >= 0.0 && lo - pad < 0.0 ? 0.0 : lo - pad; /* T(Y) >= 0: no negative axis */
        hi += pad;
        fprintf(f, "<g>\n<text x=\"%.1f\" y=\"%.1f\">pixel (%u, %u)</text>\n", x0, y0 - 8, track[k].x, track[k].y);
        fprintf(f, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#999\"/>\n", x0,
                y0, pw, ph);
        for (int j = 0; j <= 2; j++) { /* y ticks: lo, middle, hi */
            double v = lo + (hi - lo) * j / 2.0, y = y0 + ph - ph * j / 2.0;
            fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%.4g</text>\n", x0 - 4, y + 4, v);
        }
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\">0</text>\n", x0, y0 + ph + 14);
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%u</text>\n", x0 + pw, y0 + ph + 14,
                frames - 1);
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">frame</text>\n", x0 + pw / 2, y0 + ph + 28);
        for (uint32_t i = 0; i < a->series_count; i++) {
            const char *c = i ? colors[(i - 1) % ncolors] : "black";
            fprintf(f, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"%s\" points=\"", c, i ? "1.5" : "2");
            for (uint32_t t = 0; t < frames; t++) {
                double v = a->series[i].lum[(size_t)t * track_count + k];
                double x = x0 + (frames > 1 ? pw * t / (frames - 1) : pw / 2);
                double y = y0 + ph - ph * (v - lo) / (hi - lo);
                fprintf(f, "%s%.2f,%.2f", t ? " " : "", x, y);
            }
            fputs("\"/>\n", f);
        }
        fputs("</g>\n", f);
    }
    fputs("</svg>\n", f);
    return 0;
}

static int cmp__sequences(cmp__args *a)
{
    int status = 1;
    float *first = NULL;
    uint32_t frames = 0;
    for (uint32_t i = 0; i < a->series_count; i++) {
        uint32_t n = 0;
        if ((status = cmp__count_frames(a->series[i].dir, &n))) return status;
        a->series[i].frames = n;
    }
    /* Methods are compared over the frames every folder has. */
    frames = a->series[0].frames;
    for (uint32_t i = 1; i < a->series_count; i++)
        if (a->series[i].frames < frames) frames = a->series[i].frames;
    for (uint32_t i = 0; i < a->series_count; i++)
        if (a->series[i].frames != frames)
            fprintf(stderr, "softgi compare: warning: %s has %u frames; comparing the first %u\n", a->series[i].dir,
                    a->series[i].frames, frames);

    /* The image size comes from the reference's first frame. */
    char path[4096];
    pf_error err;
    uint32_t w, h;
    status = 1;
    cmp__frame_path(path, sizeof path, a->series[0].dir, 0, ".pfm");
    if (pf_imageio_read_pfm(path, &first, &w, &h, &err) != PF_OK) return cmp__fail(1, "%s", err.message);
    free(first);

    gi_metrics_pixel track[CMP_MAX_TRACK];
    uint32_t track_count;
    if (a->track_given) {
        for (uint32_t k = 0; k < a->track_given; k++)
            if (a->track[k].x >= w || a->track[k].y >= h) {
                fprintf(stderr, "softgi compare: --track %u,%u is outside the %ux%u frames\n", a->track[k].x,
                        a->track[k].y, w, h);
                return 2;
            }
        memcpy(track, a->track, a->track_given * sizeof track[0]);
        track_count = a->track_given;
    } else {
        track_count = gi_metrics_track_grid(track, a->track_count, w, h);
    }

    /* TID views: the series' own folder, else the reference's (same camera path). */
    cmp__frame_path(path, sizeof path, a->series[0].dir, 0, ".view");
    const int ref_views = cmp__exists(path);
    for (uint32_t i = 0; i < a->series_count; i++) {
        cmp__frame_path(path, sizeof path, a->series[i].dir, 0, ".view");
        a->series[i].view_dir = cmp__exists(path) ? a->series[i].dir : ref_views ? a->series[0].dir : NULL;
        if (!a->series[i].view_dir)
            fprintf(stderr, "softgi compare: warning: no frame_0000.view in %s or %s: no TID for '%s'\n",
                    a->series[i].dir, a->series[0].dir, a->series[i].name);
    }

    for (uint32_t i = 0; i < a->series_count; i++)
        if ((status = cmp__run_series(a, &a->series[i], frames, w, h, track, track_count))) goto done;
    for (uint32_t i = 1; i < a->series_count; i++) {
        a->series[i].e = gi_metrics_abs_error(a->series[i].lum, a->series[0].lum, frames, track_count);
        a->series[i].e_rate = gi_metrics_abs_error_rate(a->series[i].lum, a->series[0].lum, frames, track_count);
    }

    cmp__write_table(stdout, a, frames, w, h, track, track_count);
    status = 1;
    cmp__print pr = {a, frames, w, h, track, track_count};
    if (a->table && pf_imageio_write_text(a->table, cmp__print_table, &pr, &err) != PF_OK) {
        fprintf(stderr, "softgi compare: %s\n", err.message);
        goto done;
    }
    if (a->plot && pf_imageio_write_text(a->plot, cmp__print_plot, &pr, &err) != PF_OK) {
        fprintf(stderr, "softgi compare: %s\n", err.message);
        goto done;
    }
    status = 0;
done:
    for (uint32_t i = 0; i < a->series_count; i++) {
        free(a->series[i].lum);
        a->series[i].lum = NULL;
    }
    return status;
}

int app_compare(int argc, char **argv)
{
    cmp__args a;
    int help = 0;
    int status = cmp__parse(&a, argc, argv, &help);
    if (status) return status;
    if (help) {
        cmp__usage(stdout);
        return 0;
    }
    return a.positional_count ? cmp__images(&a) : cmp__sequences(&a);
}
