/* gi_ir: Instant Radiosity (Keller 1997), the baseline VPL method, as the
 * survey's Sec. 4.1 describes it: random walks from the lights with a VPL
 * at every diffuse bounce, "flux" by Eq. 6, Russian roulette by albedo.
 *
 * Sampling: the Halton sequence with a fixed start, one index per light
 * path, so a static scene keeps a static VPL set; when anything changes (a
 * light moves), the whole set is regenerated from the same indices, which is
 * the flickering baseline the later methods beat. With --param reseed=1
 * every frame takes the next stretch of the sequence instead (frame f
 * starts at index f * 64 * budget + 1, past any path the previous frame
 * could start), so the set is new every frame even under a static light:
 * the IR that the papers compare with (Hedman 2017 Table 1, Laine 2007
 * Sec. 8), which flickers under a static light too. Dimensions of path i:
 * 2 light choice, 3/5 emission (area lights: also 7/11), then per bounce k (0-based) a pair of
 * primes for the cosine-weighted direction and one for Russian roulette.
 *
 * Path construction (gi_lightpath.h, shared with `mir`): a light chosen by
 * power, Phi by Eq. 6 for its kind (point, spot, directional, area lights:
 * the scene's emissive triangles, one more entry of the light CDF; a path
 * that picks them reuses the light choice's number, rescaled to [0, 1)
 * inside the entry, to pick an emitter triangle, dims 3/5 for the point on
 * it and 7/11 for its cosine-weighted direction, so the bounce dimensions
 * below shift by 2), a VPL at every hit, Russian roulette by albedo, up
 * to `bounces` VPLs per path. Paths are started until the VPL budget is
 * filled, and every intensity is divided by the number of paths started
 * (survey Sec. 4.1, last step). VPL ids are path * bounces + k.
 *
 * Without reseed, when nothing the paths depend on changed since the last
 * update (the scene and its Embree scene, the lights field for field, no
 * geometry moved: gi_motion's epoch, budget and bounces) the update returns
 * the last set with every moved flag cleared instead of tracing it again:
 * the same bytes the paths would give (they are a function of exactly
 * those inputs), for the cost of a copy. It matters with VPL cycling
 * (gi_indirect.h), whose set is 16 times the per-frame budget: 2-3 ms of
 * paths a frame at 4,096 VPLs on Sibenik. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_area.h"
#include "gi_light.h"
#include "gi_lightpath.h"
#include "gi_vpl.h"


typedef struct gi__ir_state {
    gi_vpl_set prev; /* last frame's set, for the moved flags */
    uint32_t reseed; /* --param reseed=1: a new stretch of the sequence every frame */
    /* what `prev` was traced from (have_key: once a set was traced) */
    int have_key;
    const pf_scene *scene;
    const pf_rt *rt;
    uint32_t budget, bounces, epoch;
    gi_light_copy lights;
} gi__ir_state;

/* 1 when this update's paths would be the last update's: same inputs, no
 * geometry moved since (the set is then prev, unmoved). */
static int gi__ir_same_inputs(const gi__ir_state *st, const gi_vpl_inputs *in)
{
    const pf_scene *s = in->scene;
    const gi_motion *m = in->motion;
    return st->have_key && !st->reseed && st->scene == s && st->rt == in->rt && st->budget == in->budget &&
           st->bounces == in->bounces && st->epoch == (m ? m->epoch : 0u) && !(m && (m->moved || m->emitters)) &&
           gi_light_copy_all_same(&st->lights, s);
}

/* Records what this update traced from (a failed allocation only means
 * the next update traces again). */
static void gi__ir_keep_inputs(gi__ir_state *st, const gi_vpl_inputs *in)
{
    st->have_key = gi_light_copy_take(&st->lights, in->scene);
    st->scene = in->scene, st->rt = in->rt, st->budget = in->budget, st->bounces = in->bounces;
    st->epoch = in->motion ? in->motion->epoch : 0u;
}

static pf_result gi__ir_create(void **state, const gi_params *params, pf_error *err)
{
    static const char *const known[] = {"reseed", NULL};
    uint32_t reseed = 0;
    pf_result r = gi_params_check(params, "ir", known, err);
    if (r == PF_OK) r = gi_param_u32(params, "reseed", 0, 1, &reseed, err);
    if (r != PF_OK) return r;
    gi__ir_state *s = calloc(1, sizeof *s);
    if (!s) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    s->reseed = reseed;
    *state = s;
    return PF_OK;
}

static void gi__ir_destroy(void *state)
{
    gi__ir_state *s = state;
    if (!s) return;
    gi_vpl_set_free(&s->prev);
    gi_light_copy_free(&s->lights);
    free(s);
}

static pf_result gi__ir_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    gi__ir_state *st = state;
    const pf_scene *s = in->scene;
    out->count = 0;
    uint32_t budget = in->budget, B = in->bounces ? in->bounces : 3;
    pf_result r = gi_vpl_set_reserve(out, budget, err);
    if (r != PF_OK) return r;
    if (gi__ir_same_inputs(st, in)) { /* the paths would trace the last set again */
        memcpy(out->v, st->prev.v, sizeof(gi_vpl) * st->prev.count);
        out->count = st->prev.count;
        for (uint32_t i = 0; i < out->count; i++) out->v[i].moved = 0;
        return PF_OK;
    }
    gi_lightpath_lights c;
    gi_lightpath_lights_init(&c, s, in->area);
    if (c.nl == 0 || !(c.total > 0.0)) return PF_OK; /* nothing emits: no VPLs */
    uint32_t paths = 0, max_paths = budget * 64u;
    /* the frame's first Halton index (0 maps every dimension to 0); wraps
     * after 2^31 indices, some 130,000 frames at the default budget, and
     * start + path stays below 2^32 */
    uint32_t start = st->reseed ? (uint32_t)(((uint64_t)in->frame * max_paths) % 0x7fffffffu) + 1u : 1u;
    for (uint32_t path = 0; out->count < budget && path < max_paths; path++) {
        paths++;
        uint32_t hi = start + path;
        uint32_t got = gi_lightpath_trace_halton(&c, in->rt, hi, B, budget - out->count, &out->v[out->count]);
        for (uint32_t k = 0; k < got; k++) {
            out->v[out->count + k].id = path * B + k;
            out->v[out->count + k].moved = 1;
        }
        out->count += got;
    }
    float inv = 1.0f / (float)paths;
    for (uint32_t i = 0; i < out->count; i++) out->v[i].intensity = pf_v3_scale(out->v[i].intensity, inv);
    /* moved flags against the previous frame (same id at the same slot) */
    for (uint32_t i = 0; i < out->count; i++) {
        gi_vpl *v = &out->v[i];
        if (i < st->prev.count && st->prev.v[i].id == v->id && !memcmp(&st->prev.v[i].pos, &v->pos, sizeof v->pos) &&
            !memcmp(&st->prev.v[i].nrm, &v->nrm, sizeof v->nrm) &&
            !memcmp(&st->prev.v[i].intensity, &v->intensity, sizeof v->intensity))
            v->moved = 0;
    }
    r = gi_vpl_set_reserve(&st->prev, out->count ? out->count : 1, err);
    if (r != PF_OK) return r;
    memcpy(st->prev.v, out->v, sizeof(gi_vpl) * out->count);
    st->prev.count = out->count;
    gi__ir_keep_inputs(st, in);
    return PF_OK;
}

/* The light paths over the image (the learner's view): each VPL the camera
 * sees as a dot in its bounce's colour, and every path segment between two
 * VPLs of one path (ids path * B + k and + k + 1, consecutive in the set)
 * as a line, so the random walks of Keller 1997 can be followed; segments
 * with an end behind the camera are left out. */
static int gi__ir_view(const void *state, const gi_vpl_view_ctx *c, uint8_t *rgb)
{
    (void)state;
    const gi_vpl_set *set = c->vpls;
    const uint32_t B = c->bounces ? c->bounces : 3;
    if (!set->count) return 0;
    c->background(c, rgb);
    uint32_t paths = 0, seen = 0;
    for (uint32_t i = 0; i < set->count; i++) {
        const gi_vpl *v = &set->v[i];
        float x0, y0, x1, y1;
        uint8_t col[3];
        paths += v->id % B == 0;
        if (i > 0 && v->id % B != 0 && set->v[i - 1].id + 1 == v->id && c->project(c, set->v[i - 1].pos, &x0, &y0) &&
            c->project(c, v->pos, &x1, &y1)) {
            c->palette(v->id % B, col);
            col[0] = (uint8_t)(col[0] / 2), col[1] = (uint8_t)(col[1] / 2), col[2] = (uint8_t)(col[2] / 2);
            c->line(c, rgb, (int)floorf(x0), (int)floorf(y0), (int)floorf(x1), (int)floorf(y1), col);
        }
    }
    for (uint32_t i = 0; i < set->count; i++) {
        const gi_vpl *v = &set->v[i];
        float x, y;
        uint8_t col[3];
        if (!c->project(c, v->pos, &x, &y) || !c->visible(c, v->pos)) continue;
        c->palette(v->id % B, col);
        c->fill(c, rgb, (int)floorf(x) - 1, (int)floorf(y) - 1, 3, 3, col);
        seen++;
    }
    char text[128];
    static const uint8_t white[3] = {255, 255, 255};
    snprintf(text, sizeof text, "%u VPLs on %u light paths (%u seen); lines: the walks, colour: bounce", set->count,
             paths, seen);
    c->text(c, rgb, 4, 2, text, white);
    char names[4][24];
    const char *np[4];
    uint8_t cols[4][3];
    uint32_t nk = B < 4 ? B : 4;
    for (uint32_t k = 0; k < nk; k++) {
        snprintf(names[k], sizeof names[k], k + 1 < nk || nk == B ? "bounce %u" : "bounce %u+", k + 1);
        np[k] = names[k];
        c->palette(k, cols[k]);
    }
    c->key(c, rgb, "light bounce", np, (const uint8_t(*)[3])cols, nk);
    return 1;
}

/* VPL ids are path * bounces + k, k = 0 for the first hit (the learner's
 * bounce overlay). */
static uint32_t gi__ir_bounce(const void *state, const gi_vpl *v, uint32_t bounces)
{
    (void)state;
    return v->id % (bounces ? bounces : 3) + 1;
}

const gi_vpl_method gi_method_ir = {
    .name = "ir",
    .paper = "Instant Radiosity (Keller 1997; survey Sec. 4.1)",
    .create = gi__ir_create,
    .update = gi__ir_update,
    .destroy = gi__ir_destroy,
    .parts = NULL,
    .gbuffer_free = 1,
    .why = "the light's paths are the simplest unbiased way to spread flux over the scene: a VPL at every bounce "
           "of a random walk from the lights, so the indirect light converges as VPLs are added (Keller 1997; "
           "survey Sec. 4.1)",
    .view_caption = "the light paths: each VPL the camera sees in its bounce's colour, the walks between the VPLs "
                    "of one path as lines",
    .view = gi__ir_view,
    .bounce = gi__ir_bounce,
};
