/* pf_defaults: the automatic camera, light and exposure (pf_defaults.h). */
#include "pf_defaults.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define APP__ENCLOSURE_RAYS 26 /* the directions {-1,0,1}^3 without 0 */
#define APP__GRID 7            /* pf_defaults_light: 7 x 7 camera rays */

/* t[i] = distance along unit dir[i] from org[i] to the closest triangle
 * (either side), INFINITY for a miss. Moeller & Trumbore 1997, in double so
 * that file coordinates up to PF_SCENE_MAX_COORD neither overflow nor lose
 * the hit; triangles outside, rays inside, so each triangle is read once. */
static void app__cast(const pf_scene *s, const pf_vec3 *org, const pf_vec3 *dir, float *t, uint32_t n)
{
    double best[64];
    for (uint32_t i = 0; i < n; i++) best[i] = INFINITY;
    for (uint32_t k = 0; k < s->tri_count; k++) {
        const uint32_t *ix = s->indices + 3 * (size_t)k;
        pf_vec3 a = s->positions[ix[0]], b = s->positions[ix[1]], c = s->positions[ix[2]];
        double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
        double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
        for (uint32_t i = 0; i < n; i++) {
            double d[3] = {dir[i].x, dir[i].y, dir[i].z};
            double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
            double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
            if (fabs(det) < 1e-300) continue; /* parallel */
            double inv = 1.0 / det;
            double o[3] = {(double)org[i].x - a.x, (double)org[i].y - a.y, (double)org[i].z - a.z};
            double u = (o[0] * p[0] + o[1] * p[1] + o[2] * p[2]) * inv;
            if (u < 0.0 || u > 1.0) continue;
            double q[3] = {o[1] * e1[2] - o[2] * e1[1], o[2] * e1[0] - o[0] * e1[2], o[0] * e1[1] - o[1] * e1[0]};
            double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
            if (v < 0.0 || u + v > 1.0) continue;
            double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
            if (tt > 0.0 && tt < best[i]) best[i] = tt;
        }
    }
    for (uint32_t i = 0; i < n; i++) t[i] = (float)best[i];
}

static float app__clamp_coord(float x) { return pf_clampf(x, -PF_SCENE_MAX_COORD, PF_SCENE_MAX_COORD); }

void pf_defaults_camera(pf_default_camera *out, const pf_scene *s)
{
    memset(out, 0, sizeof *out);
    out->fovy_deg = APP_DEFAULT_FOVY_DEG;
    pf_vec3 lo = s->bounds_min, hi = s->bounds_max;
    pf_vec3 c = pf_v3_scale(pf_v3_add(lo, hi), 0.5f), ext = pf_v3_sub(hi, lo);
    float radius = 0.5f * pf_v3_length(ext); /* > 0: a validated scene has a triangle of non-zero area */

    /* Is the centre enclosed? Most of 26 rays from it hit geometry. */
    pf_vec3 org[APP__ENCLOSURE_RAYS], dir[APP__ENCLOSURE_RAYS];
    float t[APP__ENCLOSURE_RAYS];
    uint32_t n = 0, plus = 0, minus = 0;
    const int horizontal_x = ext.x >= ext.z;
    for (int i = -1; i <= 1; i++)
        for (int j = -1; j <= 1; j++)
            for (int k = -1; k <= 1; k++) {
                if (!i && !j && !k) continue;
                if (!j && (horizontal_x ? !k && i == 1 : !i && k == 1)) plus = n;
                if (!j && (horizontal_x ? !k && i == -1 : !i && k == -1)) minus = n;
                org[n] = c;
                dir[n++] = pf_v3_normalize(pf_v3((float)i, (float)j, (float)k));
            }
    app__cast(s, org, dir, t, n);
    for (uint32_t i = 0; i < n; i++) out->hits += isfinite(t[i]) != 0;
    out->rays = n;
    out->interior = 2 * out->hits > n;

    if (out->interior) {
        /* Inside: near the more open end of the longer horizontal axis (+Y
         * is up: a view down the vertical would show only floor or roof),
         * 10% of the length from it, but never past 80% of the way to the
         * geometry that way; looking back down the axis. An end open to
         * the outside (a box with no front wall, the ray misses) is looked
         * through instead: the eye stands out in front of it, far enough
         * that the opening's cross-section fills 90% of the vertical view. */
        out->axis = horizontal_x ? 'x' : 'z';
        float len = horizontal_x ? ext.x : ext.z;
        uint32_t end = t[plus] >= t[minus] ? plus : minus; /* the farther hit (or a miss): more room */
        float step;
        if (isfinite(t[end])) {
            step = fminf(0.4f * len, 0.8f * t[end]);
            step = fmaxf(step, 0.05f * len); /* the centre on a surface: still step off it */
        } else {
            out->open_end = 1;
            float half = 0.5f * fmaxf(ext.y, horizontal_x ? ext.z : ext.x);
            step = 0.5f * len + half / (0.9f * tanf(pf_radians(0.5f * APP_DEFAULT_FOVY_DEG)));
        }
        out->eye = pf_v3_add(c, pf_v3_scale(dir[end], step));
        out->target = pf_v3_sub(out->eye, pf_v3_scale(dir[end], len));
    } else {
        /* Outside: the bounding sphere fills 80% of the vertical field,
         * seen from the front (+Z) and 17 degrees above. */
        float d = radius / sinf(pf_radians(0.8f * 0.5f * APP_DEFAULT_FOVY_DEG));
        out->eye = pf_v3_add(c, pf_v3_scale(pf_v3_normalize(pf_v3(0.0f, 0.3f, 1.0f)), d));
        out->target = c;
    }
    out->eye = pf_v3(app__clamp_coord(out->eye.x), app__clamp_coord(out->eye.y), app__clamp_coord(out->eye.z));
    out->target =
        pf_v3(app__clamp_coord(out->target.x), app__clamp_coord(out->target.y), app__clamp_coord(out->target.z));
}

static int app__float_cmp(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

void pf_defaults_light(pf_light *out, float *median, const pf_scene *s, const pf_camera *cam, uint32_t width,
                        uint32_t height)
{
    /* 7 x 7 rays through the image and one straight up from the eye */
    pf_vec3 org[APP__GRID * APP__GRID + 1], dir[APP__GRID * APP__GRID + 1];
    float t[APP__GRID * APP__GRID + 1];
    uint32_t n = 0;
    for (uint32_t y = 0; y < APP__GRID; y++)
        for (uint32_t x = 0; x < APP__GRID; x++) {
            org[n] = cam->eye;
            dir[n++] = pf_v3_normalize(pf_camera_ray_dir(cam, width, height, ((float)x + 0.5f) * (float)width / APP__GRID,
                                                         ((float)y + 0.5f) * (float)height / APP__GRID));
        }
    org[n] = cam->eye;
    dir[n++] = pf_v3(0.0f, 1.0f, 0.0f);
    app__cast(s, org, dir, t, n);
    const float up = t[n - 1];

    /* The median of the hits (misses sort last as INFINITY; only hits count) */
    qsort(t, n - 1, sizeof *t, app__float_cmp);
    uint32_t hits = 0;
    while (hits < n - 1 && isfinite(t[hits])) hits++;
    float radius = 0.5f * pf_v3_length(pf_v3_sub(s->bounds_max, s->bounds_min));
    float d = hits ? t[hits / 2] : radius;
    d = fmaxf(d, 1e-3f * radius); /* the eye on a surface */

    memset(out, 0, sizeof *out);
    snprintf(out->name, sizeof out->name, "default");
    out->type = PF_LIGHT_POINT;
    out->color = pf_v3(1.0f, 1.0f, 1.0f);
    out->intensity = pf_clampf(APP_DEFAULT_IRRADIANCE * d * d, 1e-30f, PF_MAX_RADIANCE);
    /* Just above the eye, so shadows show a little, but below a ceiling */
    float lift = fminf(0.05f * d, 0.5f * up);
    out->position = pf_v3(cam->eye.x, app__clamp_coord(cam->eye.y + lift), cam->eye.z);
    *median = d;
}

float pf_defaults_exposure(const float *rgb, uint32_t width, uint32_t height, double *log_average)
{
    /* Reinhard et al. 2002, Eq. 1: exp(mean(log L)) over the lit pixels
     * (black background and unlit pixels would drag the mean to -inf) */
    double sum = 0.0;
    uint64_t lit = 0, count = (uint64_t)width * height;
    for (uint64_t i = 0; i < count; i++) {
        float y = pf_luminance(pf_v3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]));
        if (y > 0.0f && isfinite(y)) {
            sum += log((double)y);
            lit++;
        }
    }
    if (log_average) *log_average = lit ? exp(sum / (double)lit) : 0.0;
    if (!lit) return 0.0f;
    /* x / (1 + x) = g  <=>  x = g / (1 - g); 2^stops * average = x */
    const double x = APP_DEFAULT_GREY / (1.0 - APP_DEFAULT_GREY);
    double stops = log2(x) - sum / (double)lit / log(2.0);
    return (float)fmin(fmax(stops, -64.0), 64.0);
}

int pf_defaults_nearly_black(const float *rgb, uint32_t width, uint32_t height, float exposure)
{
    const float scale = exp2f(exposure);
    uint64_t bright = 0, count = (uint64_t)width * height;
    for (uint64_t i = 0; i < count; i++)
        bright += pf_luminance(pf_v3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2])) * scale >= APP_DARK_LUMINANCE;
    return bright * 100 < count;
}
