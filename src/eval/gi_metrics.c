/* gi_metrics: image and sequence metrics (gi_metrics.h).
 *
 * This work is based on Hedman et al. 2017 (Table 1, Eq. 10, Fig. 7) and
 * Barak et al. 2013 (Sec. 6.2, TID); see the header for the definitions.
 *
 * Why the tone map acts on luminance. Hedman et al. write "we perform all
 * measurements after applying the Reinhard tone mapping operator [38]" and
 * "we track the luminance of 8 pixels". Reinhard 2002 states its global
 * operator (Eq. 3) on world luminance, L_d = L / (1 + L), so the measured
 * quantity is that display luminance. Applying the curve per channel first
 * (as pf_imageio_display does for the PNG) and then taking luminance would
 * also be defensible; the two agree on grey pixels and differ only by the
 * desaturation of bright colours. The operator is bounded in [0, 1), so one
 * fire-fly pixel cannot dominate |E| -- which is what "agree better with
 * perceived quality" asks for. No sRGB encoding: Hedman names only Reinhard.
 *
 * All sums are accumulated in double in a fixed order, so the metrics are
 * deterministic and independent of image size up to rounding. */
#include "gi_metrics.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pf_imageio.h"

/* ---------------------------------------------------------------- pixels */

float gi_metrics_luminance(const float *rgb)
{
    return pf_luminance(pf_v3(rgb[0], rgb[1], rgb[2]));
}

float gi_metrics_reinhard(float x)
{
    if (!(x > 0.0f)) return 0.0f; /* also NaN */
    if (isinf(x)) return 1.0f;
    return x / (1.0f + x);
}

float gi_metrics_display_luminance(const float *rgb, float exposure_scale)
{
    return gi_metrics_reinhard(exposure_scale * gi_metrics_luminance(rgb));
}

/* ---------------------------------------------------------------- images */

double gi_metrics_rmse(const float *rgb, const float *ref, size_t pixel_count)
{
    if (pixel_count == 0) return 0.0;
    double s = 0.0;
    for (size_t i = 0; i < 3 * pixel_count; i++) {
        double d = (double)rgb[i] - (double)ref[i];
        s += d * d;
    }
    return sqrt(s / (3.0 * (double)pixel_count));
}

double gi_metrics_mae(const float *rgb, const float *ref, size_t pixel_count)
{
    if (pixel_count == 0) return 0.0;
    double s = 0.0;
    for (size_t i = 0; i < 3 * pixel_count; i++) s += fabs((double)rgb[i] - (double)ref[i]);
    return s / (3.0 * (double)pixel_count);
}

double gi_metrics_mean_relative_error(const float *rgb, const float *ref, size_t pixel_count, float floor,
                                      size_t *counted)
{
    double s = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < pixel_count; i++) {
        double yr = gi_metrics_luminance(ref + 3 * i), y = gi_metrics_luminance(rgb + 3 * i);
        if (!(yr > floor)) continue;
        s += fabs(y - yr) / yr;
        n++;
    }
    if (counted) *counted = n;
    return n ? s / (double)n : 0.0;
}

double gi_metrics_energy_ratio(const float *rgb, const float *ref, size_t pixel_count)
{
    double a = 0.0, b = 0.0;
    for (size_t i = 0; i < pixel_count; i++) a += gi_metrics_luminance(rgb + 3 * i), b += gi_metrics_luminance(ref + 3 * i);
    return b > 0.0 ? a / b : NAN;
}

double gi_metrics_abs_error_image(const float *rgb, const float *ref, size_t pixel_count, float exposure_scale)
{
    if (pixel_count == 0) return 0.0;
    double s = 0.0;
    for (size_t i = 0; i < pixel_count; i++)
        s += fabs((double)gi_metrics_display_luminance(rgb + 3 * i, exposure_scale) -
                  (double)gi_metrics_display_luminance(ref + 3 * i, exposure_scale));
    return s / (double)pixel_count;
}

/* ---------------------------------------------------------------- tracked pixels */

uint32_t gi_metrics_track_grid(gi_metrics_pixel *dst, uint32_t count, uint32_t width, uint32_t height)
{
    if (count == 0 || width == 0 || height == 0) return 0;
    if ((uint64_t)count > (uint64_t)width * height) count = width * height;
    /* cols / rows ~ W / H so the cells are roughly square. */
    uint32_t cols = (uint32_t)ceil(sqrt((double)count * width / height));
    if (cols < 1) cols = 1;
    if (cols > width) cols = width;
    if (cols > count) cols = count;
    uint32_t rows = (count + cols - 1) / cols;
    if (rows > height) { /* only when cols == width: the whole image */
        rows = height;
        count = cols * rows;
    }
    uint32_t n = 0;
    for (uint32_t r = 0; r < rows && n < count; r++)
        for (uint32_t c = 0; c < cols && n < count; c++) {
            /* Cell centre; cols <= W keeps the columns distinct (and rows <= H the rows). */
            dst[n].x = (uint32_t)(((uint64_t)(2 * c + 1) * width) / (2 * (uint64_t)cols));
            dst[n].y = (uint32_t)(((uint64_t)(2 * r + 1) * height) / (2 * (uint64_t)rows));
            n++;
        }
    return n;
}

void gi_metrics_track_sample(float *dst, const float *rgb, uint32_t width, uint32_t height,
                             const gi_metrics_pixel *px, uint32_t count, float exposure_scale)
{
    for (uint32_t k = 0; k < count; k++) {
        assert(px[k].x < width && px[k].y < height);
        (void)height;
        dst[k] = gi_metrics_display_luminance(rgb + 3 * ((size_t)px[k].y * width + px[k].x), exposure_scale);
    }
}

double gi_metrics_abs_error(const float *method, const float *ref, uint32_t frames, uint32_t count)
{
    size_t n = (size_t)frames * count;
    if (n == 0) return NAN;
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += fabs((double)method[i] - (double)ref[i]);
    return s / (double)n;
}

double gi_metrics_abs_error_rate(const float *method, const float *ref, uint32_t frames, uint32_t count)
{
    if (frames < 2 || count == 0) return NAN;
    /* Eq. 10 with dt = one frame: E'_t = E_t - E_{t-1}, E_t = method_t - ref_t. */
    double s = 0.0;
    for (uint32_t t = 1; t < frames; t++)
        for (uint32_t k = 0; k < count; k++) {
            size_t i = (size_t)t * count + k, j = i - count;
            double e1 = (double)method[i] - (double)ref[i];
            double e0 = (double)method[j] - (double)ref[j];
            s += fabs(e1 - e0);
        }
    return s / ((double)(frames - 1) * count);
}

/* ---------------------------------------------------------------- views */

void gi_metrics_view_from_camera(gi_metrics_view *view, const pf_camera *cam, uint32_t width, uint32_t height)
{
    view->eye = cam->eye;
    view->forward = cam->forward;
    view->up = cam->up;
    view->right = cam->right;
    view->yfov = cam->yfov;
    view->width = width;
    view->height = height;
}

/* pf_imageio_write_text's printer: 0 on success. */
static int gi__view_print(FILE *f, void *user)
{
    const gi_metrics_view *v = user;
    /* %.9g: every float survives the text round trip bit for bit. */
    return fprintf(f,
                   "softgi-view 1\nwidth %u\nheight %u\neye %.9g %.9g %.9g\nforward %.9g %.9g %.9g\n"
                   "up %.9g %.9g %.9g\nright %.9g %.9g %.9g\nyfov %.9g\n",
                   v->width, v->height, (double)v->eye.x, (double)v->eye.y, (double)v->eye.z, (double)v->forward.x,
                   (double)v->forward.y, (double)v->forward.z, (double)v->up.x, (double)v->up.y, (double)v->up.z,
                   (double)v->right.x, (double)v->right.y, (double)v->right.z, (double)v->yfov) > 0
               ? 0
               : -1;
}

/* Written to a temporary file and renamed (pf_imageio_write_text). */
pf_result gi_metrics_view_write(const char *path, const gi_metrics_view *v, pf_error *err)
{
    pf_result r = pf_imageio_make_parent_dirs(path, err);
    if (r != PF_OK) return r;
    return pf_imageio_write_text(path, gi__view_print, (void *)v, err);
}

/* Reads "key X Y Z" (n floats) from f. */
static int gi__read_floats(FILE *f, const char *key, float *out, int n)
{
    char word[32];
    if (fscanf(f, "%31s", word) != 1 || strcmp(word, key) != 0) return 0;
    for (int i = 0; i < n; i++)
        if (fscanf(f, "%f", &out[i]) != 1 || !isfinite(out[i])) return 0;
    return 1;
}

pf_result gi_metrics_view_read(const char *path, gi_metrics_view *v, pf_error *err)
{
    memset(v, 0, sizeof *v);
    FILE *f = fopen(path, "r");
    if (!f) return pf_error_set(err, PF_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    char magic[32];
    int version = 0;
    unsigned w = 0, h = 0;
    float eye[3], fwd[3], up[3], right[3], yfov = 0.0f;
    int ok = fscanf(f, "%31s %d", magic, &version) == 2 && !strcmp(magic, "softgi-view") && version == 1 &&
             fscanf(f, " width %u height %u", &w, &h) == 2 && w > 0 && h > 0 && w <= 65536 && h <= 65536 &&
             gi__read_floats(f, "eye", eye, 3) && gi__read_floats(f, "forward", fwd, 3) &&
             gi__read_floats(f, "up", up, 3) && gi__read_floats(f, "right", right, 3) &&
             gi__read_floats(f, "yfov", &yfov, 1);
    fclose(f);
    if (!ok) return pf_error_set(err, PF_ERR_PARSE, "%s: not a softgi-view 1 file", path);
    v->eye = pf_v3(eye[0], eye[1], eye[2]);
    v->forward = pf_v3(fwd[0], fwd[1], fwd[2]);
    v->up = pf_v3(up[0], up[1], up[2]);
    v->right = pf_v3(right[0], right[1], right[2]);
    v->yfov = yfov;
    v->width = w;
    v->height = h;
    if (!(yfov > 0.0f && yfov < PF_PI)) return pf_error_set(err, PF_ERR_PARSE, "%s: yfov %g out of (0, pi)", path, (double)yfov);
    /* The reprojection divides by these axes' lengths implicitly (it assumes
     * an orthonormal basis); reject files that are not one. */
    const float tol = 1e-3f;
    if (fabsf(pf_v3_length(v->forward) - 1.0f) > tol || fabsf(pf_v3_length(v->up) - 1.0f) > tol ||
        fabsf(pf_v3_length(v->right) - 1.0f) > tol || fabsf(pf_v3_dot(v->forward, v->up)) > tol ||
        fabsf(pf_v3_dot(v->forward, v->right)) > tol || fabsf(pf_v3_dot(v->up, v->right)) > tol)
        return pf_error_set(err, PF_ERR_PARSE, "%s: forward/up/right are not orthonormal", path);
    return PF_OK;
}

pf_result gi_metrics_depth_write(const char *path, const float *depth, uint32_t width, uint32_t height,
                                 pf_error *err)
{
    size_t n = (size_t)width * height;
    float *rgb = calloc(3 * n, sizeof(float));
    if (!rgb) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory writing %s", path);
    for (size_t i = 0; i < n; i++) rgb[3 * i] = depth[i];
    pf_result r = pf_imageio_write_pfm_range(path, rgb, width, height, PF_IMAGEIO_DEPTH, err);
    free(rgb);
    return r;
}

pf_result gi_metrics_depth_read(const char *path, float **depth, uint32_t *width, uint32_t *height, pf_error *err)
{
    float *rgb = NULL;
    *depth = NULL;
    pf_result r = pf_imageio_read_pfm_range(path, &rgb, width, height, PF_IMAGEIO_DEPTH, err);
    if (r != PF_OK) return r;
    size_t n = (size_t)*width * *height;
    /* Compact R in place: element i is read (at 3i >= i) before it is overwritten. */
    for (size_t i = 0; i < n; i++) rgb[i] = rgb[3 * i];
    float *d = realloc(rgb, n * sizeof(float));
    *depth = d ? d : rgb;
    return PF_OK;
}

/* ---------------------------------------------------------------- TID */

static float gi__intensity(const float *rgb, const gi_metrics_tid_desc *d)
{
    if (d->tonemapped) return gi_metrics_display_luminance(rgb, d->exposure_scale);
    return gi_metrics_luminance(rgb);
}

void gi_metrics_tid_pair(gi_metrics_tid_sum *acc, const gi_metrics_frame *prev, const gi_metrics_frame *cur,
                         const gi_metrics_tid_desc *desc)
{
    gi_metrics_tid_desc d = {0};
    if (desc) d = *desc;
    if (!(d.depth_tolerance > 0.0f)) d.depth_tolerance = GI_METRICS_DEFAULT_DEPTH_TOLERANCE;
    if (!(d.exposure_scale > 0.0f)) d.exposure_scale = 1.0f;

    const gi_metrics_view *vc = cur->view, *vp = prev->view;
    const uint32_t wc = vc->width, hc = vc->height, wp = vp->width, hp = vp->height;
    /* Camera t-1's projection: a point at view offset (x_r, y_u, z) lands at
     * sx = x_r / (z tan(yfov/2) aspect), sy = y_u / (z tan(yfov/2)) in
     * [-1, 1], i.e. the inverse of pf_camera_ray_dir. Done in double: the
     * test scenes place pixel centres exactly, and float round-off near a
     * pixel edge must not flip the nearest pixel. */
    const double thp = tan(0.5 * (double)vp->yfov), aspp = (double)wp / (double)hp;
    /* Camera t's rays come from pf_camera_ray_dir itself, so the world points
     * are the ones the renderer shaded. */
    pf_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.eye = vc->eye;
    cam.forward = vc->forward;
    cam.up = vc->up;
    cam.right = vc->right;
    cam.yfov = vc->yfov;
    double sum = 0.0;
    uint64_t matched = 0;
    for (uint32_t y = 0; y < hc; y++)
        for (uint32_t x = 0; x < wc; x++) {
            size_t ic = (size_t)y * wc + x;
            float z = cur->depth[ic];
            if (!(z > 0.0f) || !isfinite(z)) continue; /* sky */
            /* World point: eye + depth * ray_dir (the ray's forward component is 1). */
            pf_vec3 dir = pf_camera_ray_dir(&cam, wc, hc, (float)x + 0.5f, (float)y + 0.5f);
            double px = (double)vc->eye.x + (double)z * dir.x;
            double py = (double)vc->eye.y + (double)z * dir.y;
            double pz = (double)vc->eye.z + (double)z * dir.z;
            double ox = px - vp->eye.x, oy = py - vp->eye.y, oz = pz - vp->eye.z;
            double zp = ox * vp->forward.x + oy * vp->forward.y + oz * vp->forward.z;
            if (!(zp > 0.0)) continue; /* behind camera t-1 */
            double xr = ox * vp->right.x + oy * vp->right.y + oz * vp->right.z;
            double yu = ox * vp->up.x + oy * vp->up.y + oz * vp->up.z;
            double u = (xr / (zp * thp * aspp) + 1.0) * 0.5 * wp; /* pixel coordinates, y down */
            double v = (1.0 - yu / (zp * thp)) * 0.5 * hp;
            if (!(u >= 0.0 && u < (double)wp && v >= 0.0 && v < (double)hp)) continue; /* off screen */
            size_t ip = (size_t)(uint32_t)v * wp + (uint32_t)u;
            double zprev = prev->depth[ip];
            if (!isfinite(zprev)) continue;
            /* Disocclusion: the nearest pixel of t-1 shows another surface. */
            if (fabs(zp - zprev) > (double)d.depth_tolerance * fmax(zp, zprev)) continue;
            double diff = (double)gi__intensity(cur->rgb + 3 * ic, &d) - (double)gi__intensity(prev->rgb + 3 * ip, &d);
            sum += diff * diff;
            matched++;
        }
    acc->sum_sq += sum;
    acc->count += matched;
}

double gi_metrics_tid_value(const gi_metrics_tid_sum *acc)
{
    if (acc->count == 0) return NAN;
    return sqrt(acc->sum_sq / (double)acc->count);
}
