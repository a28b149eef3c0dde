/* gi_aa: the jitter pattern, supersampling (--aa N) and temporal
 * anti-aliasing (--taa N) of a frame (see gi_aa.h: Halton 1960 with a
 * Cranley-Patterson rotation, pbrt 3rd ed. Sec. 7.4 and 7.8; Yang et al.
 * 2009; Karis 2014). */
#include "gi_aa.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"

/* ---------------------------------------------------------------- the pattern */

/* frac(h + 1/2) - 1/2 as a float in [-1/2, 1/2): h in [0, 1), computed in
 * double (exact for base 2); the float rounding could reach 1/2 for an h a
 * hair below 1/2 (base 3, index 3^15 and up), hence the clamp. */
static float gi__centred(double h)
{
    double v = h + 0.5;
    if (v >= 1.0) v -= 1.0;
    float r = (float)(v - 0.5);
    return r < 0.5f ? r : 0x1.fffffep-2f;
}

void gi_aa_jitter(uint32_t index, float *jx, float *jy)
{
    *jx = gi__centred(gi_halton(index, 2));
    *jy = gi__centred(gi_halton(index, 3));
}

rs_mat4 gi_aa_view_proj(const pf_camera *cam, uint32_t width, uint32_t height, float jx, float jy)
{
    rs_mat4 m = rs_mat4_camera(cam, width, height);
    if (jx == 0.0f && jy == 0.0f) return m; /* the unjittered matrix, bit for bit */
    /* x_ndc' = x_ndc - 2 jx / W and y_ndc' = y_ndc + 2 jy / H (NDC y is up,
     * the image's y down): the point at image position (x + 1/2 + jx,
     * y + 1/2 + jy) moves to the pixel centre (x + 1/2, y + 1/2). In clip
     * space that is row 0 += ax row 3, row 1 += ay row 3 (row 3 gives
     * w_clip); column-major, so row r of column c is m[4 c + r]. */
    const float ax = -2.0f * jx / (float)width, ay = 2.0f * jy / (float)height;
    for (int c = 0; c < 4; c++) {
        m.m[4 * c + 0] += ax * m.m[4 * c + 3];
        m.m[4 * c + 1] += ay * m.m[4 * c + 3];
    }
    return m;
}

pf_camera gi_aa_resolve_camera(const pf_camera *cam, uint32_t width, uint32_t height, float jx, float jy)
{
    pf_camera c = *cam;
    if (jx == 0.0f && jy == 0.0f) return c;
    /* pf_camera_ray_dir: dir = forward + right sx(x) + up sy(y) with
     * sx(x) = (2 x / W - 1) tan(fov/2) aspect, sy(y) = (1 - 2 y / H) tan(fov/2),
     * both affine: sx(x + jx) = sx(x) + 2 jx / W tan aspect, sy(y + jy) =
     * sy(y) - 2 jy / H tan; the offsets go into the forward axis */
    const float th = tanf(0.5f * cam->yfov), aspect = (float)width / (float)height;
    const float ox = 2.0f * jx / (float)width * th * aspect, oy = -2.0f * jy / (float)height * th;
    c.forward = pf_v3_add(cam->forward, pf_v3_add(pf_v3_scale(cam->right, ox), pf_v3_scale(cam->up, oy)));
    return c;
}

/* ---------------------------------------------------------------- set-up */

void gi_aa_free(gi_aa *aa)
{
    free(aa->sum);
    for (int b = 0; b < 2; b++) {
        free(aa->taa.hist[b]);
        free(aa->taa.count[b]);
    }
    for (uint32_t k = 0; aa->taa.scratch && k < aa->taa.workers; k++) {
        free(aa->taa.scratch[k].lo);
        free(aa->taa.scratch[k].hi);
        free(aa->taa.scratch[k].nd);
        free(aa->taa.scratch[k].near);
    }
    free(aa->taa.scratch);
    free(aa->taa.lights);
    memset(aa, 0, sizeof *aa);
    aa->samples = 1;
}

pf_result gi_frame_set_aa(gi_frame *f, uint32_t samples, uint32_t taa_frames, pf_error *err)
{
    if (samples < 1 || samples > GI_AA_MAX_SAMPLES)
        return pf_error_set(err, PF_ERR_ARGUMENT, "anti-aliasing with %u samples per pixel: expected 1..%u", samples,
                            GI_AA_MAX_SAMPLES);
    if (taa_frames == 1 || taa_frames > GI_AA_MAX_TAA)
        return pf_error_set(err, PF_ERR_ARGUMENT,
                            "temporal anti-aliasing over %u frames: expected 0 (off) or 2..%u", taa_frames,
                            GI_AA_MAX_TAA);
    gi_aa *aa = &f->aa;
    gi_aa_free(aa);
    const size_t n = (size_t)f->width * f->height;
    aa->samples = samples;
    int ok = 1;
    if (samples > 1) ok = (aa->sum = malloc(3 * n * sizeof(float))) != NULL;
    if (ok && taa_frames) {
        aa->taa.frames = taa_frames;
        for (int b = 0; b < 2 && ok; b++) {
            aa->taa.hist[b] = calloc(3 * n, sizeof(float));
            aa->taa.count[b] = calloc(n, sizeof(uint16_t));
            ok = aa->taa.hist[b] && aa->taa.count[b];
        }
        /* one row of column minima, maxima and nearest surfaces per worker */
        const uint32_t workers = pf_jobs_thread_count(f->jobs), W = f->width;
        aa->taa.workers = workers;
        ok = ok && (aa->taa.scratch = calloc(workers, sizeof *aa->taa.scratch)) != NULL;
        for (uint32_t k = 0; ok && k < workers; k++) {
            gi__taa_scratch *s = &aa->taa.scratch[k];
            s->lo = malloc(3 * (size_t)W * sizeof(float));
            s->hi = malloc(3 * (size_t)W * sizeof(float));
            s->nd = malloc((size_t)W * sizeof(float));
            s->near = malloc((size_t)W * sizeof(size_t));
            ok = s->lo && s->hi && s->nd && s->near;
        }
    }
    if (!ok) {
        gi_aa_free(aa);
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory for anti-aliasing (%u samples, %u frames)",
                            samples, taa_frames);
    }
    return PF_OK;
}

void gi_aa_sample_begin(gi_frame *f, uint32_t k)
{
    gi_aa *aa = &f->aa;
    aa->sample = (k + 1) % aa->samples; /* 1, 2, ..., N-1, then the centre */
    uint32_t base = aa->taa.frames ? (aa->taa.frame % aa->taa.frames) * aa->samples : 0;
    aa->index = base + aa->sample;
    gi_aa_jitter(aa->index, &aa->jx, &aa->jy);
}

/* ---------------------------------------------------------------- supersampling */

/* The average's inputs and outputs, explicitly (the stage table's reads
 * and writes: FINAL; the running sum). */
typedef struct gi__resolve_ctx {
    float *final;    /* FINAL: this sample's, then the mean after the last */
    float *sum;      /* the running sum of the samples */
    uint32_t width;
    float samples;   /* N */
    int first, last; /* the frame's first and last sample */
} gi__resolve_ctx;

static void gi__resolve_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__resolve_ctx *c = p;
    const size_t row = (size_t)y * c->width * 3, n = (size_t)c->width * 3;
    float *fin = c->final + row, *sum = c->sum + row;
    if (c->first) memcpy(sum, fin, n * sizeof(float));
    else
        for (size_t i = 0; i < n; i++) sum[i] += fin[i]; /* in sample order: the same bits for any thread count */
    if (c->last) {
        const float N = c->samples;
        for (size_t i = 0; i < n; i++) fin[i] = sum[i] / N;
    }
}

void gi_stage_aa_resolve(gi_frame *f)
{
    if (f->aa.samples <= 1) return;
    /* the k-th sample rendered is sample (k + 1) mod N: sample 1 is the
     * first, sample 0 (the centre) the last */
    const gi__resolve_ctx c = {f->final, f->aa.sum, f->width, (float)f->aa.samples, f->aa.sample == 1 % f->aa.samples,
                               f->aa.sample == 0};
    pf_jobs_parallel_for(f->jobs, gi__resolve_row, (void *)&c, f->height, 8);
}

/* ---------------------------------------------------------------- temporal anti-aliasing */

static int gi__camera_same(const pf_camera *a, const pf_camera *b)
{
    return a->eye.x == b->eye.x && a->eye.y == b->eye.y && a->eye.z == b->eye.z && a->forward.x == b->forward.x &&
           a->forward.y == b->forward.y && a->forward.z == b->forward.z && a->up.x == b->up.x && a->up.y == b->up.y &&
           a->up.z == b->up.z && a->right.x == b->right.x && a->right.y == b->right.y && a->right.z == b->right.z &&
           a->yfov == b->yfov && a->znear == b->znear && a->zfar == b->zfar && a->aspect == b->aspect;
}

static int gi__v3_same(pf_vec3 a, pf_vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* What shading reads of a light (not its name). */
static int gi__light_same(const pf_light *a, const pf_light *b)
{
    return a->type == b->type && gi__v3_same(a->position, b->position) && gi__v3_same(a->direction, b->direction) &&
           gi__v3_same(a->color, b->color) && a->intensity == b->intensity && a->inner_cone == b->inner_cone &&
           a->outer_cone == b->outer_cone;
}

/* A camera's projection onto a W x H image: pf_camera_ray_dir inverted,
 * px = W/2 (1 + (d.right / z) / (tan(fov/2) aspect)) and
 * py = H/2 (1 - (d.up / z) / tan(fov/2)) with z = d.forward. */
typedef struct gi__proj {
    const pf_camera *c;
    float kx, ky, hw, hh; /* W / (2 tan aspect), H / (2 tan), W / 2, H / 2 */
} gi__proj;

static gi__proj gi__proj_make(const pf_camera *c, uint32_t W, uint32_t H)
{
    const float th = tanf(0.5f * c->yfov), ta = th * (float)W / (float)H;
    return (gi__proj){c, 0.5f * (float)W / ta, 0.5f * (float)H / th, 0.5f * (float)W, 0.5f * (float)H};
}

/* The image position (pixels, continuous, y down) of point p (point 1) or
 * of direction p (point 0); 0 when it lies behind the camera. */
static int gi__project(const gi__proj *pr, pf_vec3 p, int point, float *px, float *py)
{
    const pf_camera *c = pr->c;
    pf_vec3 d = point ? pf_v3_sub(p, c->eye) : p;
    float z = pf_v3_dot(d, c->forward);
    if (!(z > 0.0f)) return 0;
    const float inv = 1.0f / z;
    *px = pr->hw + pf_v3_dot(d, c->right) * inv * pr->kx;
    *py = pr->hh - pf_v3_dot(d, c->up) * inv * pr->ky;
    return 1;
}

/* The temporal anti-aliasing's inputs and outputs, explicitly (the stage
 * table's reads: VISIBILITY, GBUFFER, FINAL; writes: FINAL, through this
 * frame's history). */
typedef struct gi__taa_ctx {
    const rs_gbuffer *gbuf;     /* VISIBILITY (prim, depth) and GBUFFER (position) */
    float *final;               /* FINAL: this frame's sample in, the blend out (after every row is read) */
    const pf_camera *camera;    /* this frame's (unjittered) camera */
    float jx, jy;               /* this frame's jitter */
    uint32_t W, H, N;           /* size; --taa N */
    gi__taa_scratch *scratch;   /* per worker */
    const float *h;     /* last frame's history */
    const uint16_t *hn;
    float *o;           /* this frame's */
    uint16_t *on;
    int have;           /* a history exists */
    int moved;          /* the camera differs from last frame's */
    int changed;        /* the camera or a light differs: clamp the history */
    gi__proj cur, prev;    /* this and last frame's (unjittered) camera */
} gi__taa_ctx;

/* The history at image position (hx, hy) (texel centres at i + 1/2),
 * filtered with the Catmull-Rom spline over the 4 x 4 texels around it
 * (Karis 2014: a bilinear fetch blurs the history a little more every frame
 * the camera moves; the cubic keeps it sharp), the taps clamped to the
 * image; *n gets the count of the nearest texel. The spline overshoots near
 * edges, so the caller clamps the result to the current neighbourhood
 * (every frame that fetches here is a moved, hence changed, frame). */
static void gi__taa_fetch(const gi__taa_ctx *c, float hx, float hy, float out[3], uint32_t *n)
{
    const uint32_t W = c->W, H = c->H;
    float u = hx - 0.5f, v = hy - 0.5f; /* >= -1/2 */
    int x0 = (int)u, y0 = (int)v;       /* floor, without a libm call */
    x0 -= (float)x0 > u, y0 -= (float)y0 > v;
    const float tx = u - (float)x0, ty = v - (float)y0;
    /* Catmull-Rom weights of texels i-1, i, i+1, i+2 at fraction t */
    const float wx[4] = {tx * (-0.5f + tx * (1.0f - 0.5f * tx)), 1.0f + tx * tx * (-2.5f + 1.5f * tx),
                         tx * (0.5f + tx * (2.0f - 1.5f * tx)), tx * tx * (-0.5f + 0.5f * tx)};
    const float wy[4] = {ty * (-0.5f + ty * (1.0f - 0.5f * ty)), 1.0f + ty * ty * (-2.5f + 1.5f * ty),
                         ty * (0.5f + ty * (2.0f - 1.5f * ty)), ty * ty * (-0.5f + 0.5f * ty)};
    size_t xs[4], ys[4];
    for (int k = 0; k < 4; k++) {
        int X = x0 - 1 + k, Y = y0 - 1 + k;
        xs[k] = (size_t)(X < 0 ? 0 : X > (int)W - 1 ? (int)W - 1 : X);
        ys[k] = (size_t)(Y < 0 ? 0 : Y > (int)H - 1 ? (int)H - 1 : Y) * W;
    }
    out[0] = out[1] = out[2] = 0.0f;
    for (int j = 0; j < 4; j++) {
        float row[3] = {0.0f, 0.0f, 0.0f};
        for (int k = 0; k < 4; k++) {
            const float *h = c->h + 3 * (ys[j] + xs[k]);
            for (int ch = 0; ch < 3; ch++) row[ch] += wx[k] * h[ch];
        }
        for (int ch = 0; ch < 3; ch++) out[ch] += wy[j] * row[ch];
    }
    uint32_t nx = (uint32_t)hx, ny = (uint32_t)hy; /* hx, hy in [0, W) x [0, H) */
    *n = c->hn[(size_t)ny * W + nx];
}

/* The 3 x 3 neighbourhood's searches, separably: over the three rows
 * y - 1 .. y + 1 per column first (into the worker's scratch), then over
 * three columns per pixel. lo, hi: `final`'s minimum and maximum per
 * channel (changed frames); near, nd: the nearest surface's pixel and view
 * depth (moved cameras; SIZE_MAX and +inf for none). Ties keep the first in
 * the order of the scan (rows, then columns), so the result is a function
 * of the image alone. */
static void gi__taa_columns(const gi__taa_ctx *c, uint32_t y, gi__taa_scratch *s)
{
    const rs_gbuffer *g = c->gbuf;
    const uint32_t W = c->W, H = c->H;
    const uint32_t y0 = y > 0 ? y - 1 : 0, y1 = y + 1 < H ? y + 1 : H - 1;
    for (uint32_t x = 0; x < W; x++) {
        if (c->changed) {
            const float *a = c->final + 3 * ((size_t)y0 * W + x);
            float lo[3] = {a[0], a[1], a[2]}, hi[3] = {a[0], a[1], a[2]};
            for (uint32_t Y = y0 + 1; Y <= y1; Y++) {
                const float *b = c->final + 3 * ((size_t)Y * W + x);
                for (int ch = 0; ch < 3; ch++) { /* (fminf and fmaxf are libm calls here) */
                    lo[ch] = b[ch] < lo[ch] ? b[ch] : lo[ch];
                    hi[ch] = b[ch] > hi[ch] ? b[ch] : hi[ch];
                }
            }
            memcpy(s->lo + 3 * x, lo, sizeof lo);
            memcpy(s->hi + 3 * x, hi, sizeof hi);
        }
        if (c->moved) {
            size_t near = SIZE_MAX;
            float nd = INFINITY;
            for (uint32_t Y = y0; Y <= y1; Y++) {
                const size_t k = (size_t)Y * W + x;
                if (g->prim[k] != RS_GBUFFER_EMPTY && g->depth[k] < nd) nd = g->depth[k], near = k;
            }
            s->near[x] = near;
            s->nd[x] = nd;
        }
    }
}

static void gi__taa_row(void *p, uint32_t y, uint32_t worker)
{
    const gi__taa_ctx *c = p;
    const rs_gbuffer *g = c->gbuf;
    const uint32_t W = c->W, H = c->H, N = c->N;
    gi__taa_scratch *s = &c->scratch[worker];
    if (c->have && (c->changed || c->moved)) gi__taa_columns(c, y, s);
    for (uint32_t x = 0; x < W; x++) {
        const size_t i = (size_t)y * W + x;
        const float *cur = c->final + 3 * i;
        const uint32_t x0 = x > 0 ? x - 1 : 0, x1 = x + 1 < W ? x + 1 : W - 1;
        float h[3];
        uint32_t n = 0;
        if (c->have) {
            /* reprojection: the pixel's centre plus the motion of what its
             * sample saw, from last frame's camera to this one's */
            float hx = (float)x + 0.5f, hy = (float)y + 0.5f;
            int ok = 1;
            if (c->moved) {
                /* the nearest surface of the 3 x 3 neighbourhood gives the
                 * motion (Karis 2014), so an edge pixel whose sample missed
                 * a foreground object moves with it; none: the sample's
                 * direction (the background at infinity) */
                size_t near = SIZE_MAX;
                float nd = INFINITY;
                for (uint32_t X = x0; X <= x1; X++)
                    if (s->nd[X] < nd) nd = s->nd[X], near = s->near[X];
                int point = near != SIZE_MAX;
                pf_vec3 q = point ? pf_v3(g->pos_x[near], g->pos_y[near], g->pos_z[near])
                                  : pf_camera_ray_dir(c->camera, W, H, (float)x + 0.5f + c->jx,
                                                      (float)y + 0.5f + c->jy);
                float px, py, cx, cy;
                ok = gi__project(&c->prev, q, point, &px, &py) && gi__project(&c->cur, q, point, &cx, &cy);
                if (ok) hx += px - cx, hy += py - cy;
                /* off the screen (or NaN): disoccluded, restart */
                ok = ok && hx >= 0.0f && hy >= 0.0f && hx < (float)W && hy < (float)H;
            }
            if (ok && !c->moved) { /* the fetch's weights would be 1, 0, 0, 0: the same bits */
                memcpy(h, c->h + 3 * i, sizeof h);
                n = c->hn[i];
            } else if (ok)
                gi__taa_fetch(c, hx, hy, h, &n);
        }
        if (n && c->changed) {
            /* Karis 2014: the history clamped to the current 3 x 3
             * neighbourhood's range, per channel */
            for (int ch = 0; ch < 3; ch++) {
                float lo = s->lo[3 * x0 + ch], hi = s->hi[3 * x0 + ch];
                for (uint32_t X = x0 + 1; X <= x1; X++) {
                    lo = s->lo[3 * X + ch] < lo ? s->lo[3 * X + ch] : lo;
                    hi = s->hi[3 * X + ch] > hi ? s->hi[3 * X + ch] : hi;
                }
                h[ch] = pf_clampf(h[ch], lo, hi);
            }
        }
        /* a moved frame weighs the history as GI_TAA_MOVING_FRAMES frames at most */
        const uint32_t cap = c->moved && N > GI_TAA_MOVING_FRAMES ? GI_TAA_MOVING_FRAMES : N;
        const uint32_t m = n + 1 < cap ? n + 1 : cap;
        float *o = c->o + 3 * i;
        if (n == 0) memcpy(o, cur, 3 * sizeof(float));
        else {
            const float inv = 1.0f / (float)m;
            for (int ch = 0; ch < 3; ch++) o[ch] = h[ch] + (cur[ch] - h[ch]) * inv;
        }
        c->on[i] = (uint16_t)m;
    }
}

/* Row y of the blended image (this frame's history, c->o) into `final`. */
static void gi__taa_copy_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__taa_ctx *c = p;
    const size_t n = (size_t)c->W * 3, row = (size_t)y * n;
    memcpy(c->final + row, c->o + row, n * sizeof(float));
}

void gi_stage_taa(gi_frame *f)
{
    gi_taa *t = &f->aa.taa;
    if (!t->frames) return;
    const int prev = t->cur, next = 1 - prev;
    gi__taa_ctx c;
    memset(&c, 0, sizeof c);
    c.gbuf = &f->gbuf, c.final = f->final, c.camera = &f->camera, c.jx = f->aa.jx, c.jy = f->aa.jy;
    c.W = f->width, c.H = f->height, c.N = t->frames, c.scratch = t->scratch;
    c.h = t->hist[prev], c.hn = t->count[prev];
    c.o = t->hist[next], c.on = t->count[next];
    c.have = t->frame > 0;
    const pf_scene *s = f->scene;
    c.moved = c.have && !gi__camera_same(&t->camera, &f->camera);
    int lights_changed = t->light_count != s->light_count;
    for (uint32_t l = 0; l < s->light_count && !lights_changed; l++)
        lights_changed = !gi__light_same(&t->lights[l], &s->lights[l]);
    c.changed = c.moved || lights_changed;
    c.cur = gi__proj_make(&f->camera, f->width, f->height);
    c.prev = gi__proj_make(&t->camera, f->width, f->height);
    pf_jobs_parallel_for(f->jobs, gi__taa_row, &c, f->height, 8);
    pf_jobs_parallel_for(f->jobs, gi__taa_copy_row, &c, f->height, 16); /* the blend read `final`'s neighbours */
    /* this frame becomes the history */
    t->cur = next;
    t->camera = f->camera;
    if (s->light_count > t->light_cap) {
        pf_light *grown = realloc(t->lights, s->light_count * sizeof *grown);
        if (grown) t->lights = grown, t->light_cap = s->light_count;
    }
    /* out of memory for the copy: the next frame counts as changed */
    t->light_count = s->light_count <= t->light_cap ? s->light_count : UINT32_MAX;
    if (t->light_count != UINT32_MAX && s->light_count) memcpy(t->lights, s->lights, s->light_count * sizeof *t->lights);
    t->frame++;
}

/* ---------------------------------------------------------------- the resolve's depth */

/* The view depth along the true axis: GBUFFER's positions in, VISIBILITY's
 * depth out. */
typedef struct gi__depth_ctx {
    rs_gbuffer *gbuf;
    const pf_camera *cam;
    uint32_t width;
} gi__depth_ctx;

static void gi__depth_row(void *p, uint32_t y, uint32_t worker)
{
    (void)worker;
    const gi__depth_ctx *c = p;
    rs_gbuffer *g = c->gbuf;
    const pf_camera *cam = c->cam;
    for (uint32_t x = 0; x < c->width; x++) {
        size_t i = (size_t)y * c->width + x;
        if (g->prim[i] == RS_GBUFFER_EMPTY) continue;
        pf_vec3 d = pf_v3_sub(pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]), cam->eye);
        g->depth[i] = pf_v3_dot(d, cam->forward);
    }
}

void gi_aa_resolve_depth(gi_frame *f)
{
    if (f->aa.jx == 0.0f && f->aa.jy == 0.0f) return;
    const gi__depth_ctx c = {&f->gbuf, &f->camera, f->width};
    pf_jobs_parallel_for(f->jobs, gi__depth_row, (void *)&c, f->height, 8);
}
