/* test_shadow: direct-light shadow maps (rs_shadow) against Embree shadow
 * rays, and their determinism.
 *
 * - Agreement: on the Cornell box, the maze and Sibenik, each lit in turn by
 *   a spot (perspective map), a point (cube map) and a directional light
 *   (ortho map), all maps at the default 1024. Samples are the points a
 *   frame shades: Embree primary rays (gi_camera_ray) through every pixel
 *   of a 400x400 view from the scene's camera (Sibenik has none: one view
 *   down the nave, one from outside), kept where the light reaches the side
 *   the camera sees (gi_light_irradiance > 0 with the geometric normal
 *   turned to the camera). The reference is the shadow ray gi_raytrace.c
 *   shoots: from pf_rt_offset_origin(p, ng, wi) towards the light, stopping
 *   just short of it. The map says lit when its visibility is 1 (single
 *   tap) or >= 1/2 (16-tap PCF).
 *   Required: >= 99.9% agreement on the samples farther than 3 shadow-map
 *   texels from a ray-traced shadow boundary (BOUNDARY_TEXELS: how that is
 *   decided, with 8 more shadow rays per sample) for both modes, and >=
 *   98.5% on all samples. The exclusion is needed: within a few texels of
 *   a boundary a shadow map differs from exact rays by construction (edges
 *   snap to texel centres, PCF blurs 2 texels, thin shadows under 2 texels
 *   fade), and on Sibenik, at 3-4 cm texels, 15-18% of the samples lie that
 *   close to one. Every figure is printed.
 * - The maps hold what rays cast from the light through each texel centre
 *   hit, at the same depth (the lookup's axes match the matrices).
 * - Determinism: identical map bytes with 1 and 2 threads and on the scalar,
 *   AVX2 and AVX-512 paths (paths the CPU lacks are skipped).
 * - The 8-wide lookup (rs_shadow_visibility8) gives the scalar lookup's
 *   bits on Cornell (maps of 700) and Sibenik (1024) for spot, cube and
 *   ortho maps with PCF16 and PCF1, and so does the direct-light stage's
 *   8-wide row.
 * - PCF gives fractional values across a shadow edge and exactly 0 or 1
 *   farther than 3 texels from it.
 * - Bias: every floor point a spot, a point light or a low sun reaches
 *   (up to 83 degrees from the normal) is fully lit: no acne.
 * - Receiver-driven tiles: a frame draws the tiles its pixels' lookups
 *   read (checked against the lookup's window worked out here) and reads
 *   no other (undrawn texels poisoned, the direct light unchanged); a light
 *   that stays completes its map once; the direct light equals whole maps'.
 * - Frustum and box edges, cube face selection, bad input.
 * Timing is not a test's job: `softgi bench raster` times the cube map
 * (docs/perf.md). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "gi_light.h"
#include "pf_gltf.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "rs_raster.h"
#include "rs_shadow.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL_PATH SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define MAZE_PATH SOFTGI_SOURCE_DIR "/scenes/maze/maze.gltf"
#define SIBENIK_PATH SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"

#define VIEW 400u
#define MIN_AGREEMENT 0.999     /* away from shadow boundaries */
#define MIN_AGREEMENT_ALL 0.985 /* all samples (a regression guard) */

/* ------------------------------------------------------------------ helpers */

static uint64_t rng_next(uint64_t *s) { return pf_mix64(*s += 0x9e3779b97f4a7c15ull); } /* splitmix64 */
static double rng_unit(uint64_t *s) { return (double)(rng_next(s) >> 11) * (1.0 / 9007199254740992.0); }

static pf_light make_spot(pf_vec3 pos, pf_vec3 target, float inner_deg, float outer_deg)
{
    pf_light L;
    memset(&L, 0, sizeof L);
    snprintf(L.name, sizeof L.name, "test spot");
    L.type = PF_LIGHT_SPOT;
    L.position = pos;
    L.direction = pf_v3_normalize(pf_v3_sub(target, pos));
    L.color = pf_v3(1, 1, 1);
    L.intensity = 10.0f;
    L.inner_cone = pf_radians(inner_deg);
    L.outer_cone = pf_radians(outer_deg);
    return L;
}

static pf_light make_point(pf_vec3 pos)
{
    pf_light L;
    memset(&L, 0, sizeof L);
    snprintf(L.name, sizeof L.name, "test point");
    L.type = PF_LIGHT_POINT;
    L.position = pos;
    L.color = pf_v3(1, 1, 1);
    L.intensity = 10.0f;
    return L;
}

static pf_light make_directional(pf_vec3 dir)
{
    pf_light L;
    memset(&L, 0, sizeof L);
    snprintf(L.name, sizeof L.name, "test sun");
    L.type = PF_LIGHT_DIRECTIONAL;
    L.direction = pf_v3_normalize(dir);
    L.color = pf_v3(1, 1, 1);
    L.intensity = 3.0f;
    return L;
}

/* A scene with its Embree scene, jobs, rasterizer context and shadow maps. */
typedef struct world {
    pf_scene scene;
    pf_rt *rt;
    pf_jobs *jobs;
    rs_context *ctx;
    rs_shadow_set set;
} world;

static void world_lights(world *w, const pf_light *lights, uint32_t count)
{
    pf_error err;
    w->scene.light_count = 0; /* replace the file's lights */
    for (uint32_t i = 0; i < count; i++) assert_int_equal(pf_scene_add_light(&w->scene, &lights[i], &err), PF_OK);
    assert_int_equal(pf_scene_validate(&w->scene, &err), PF_OK);
}

/* Embree, 2 threads, the best SIMD path, maps of `size` for every light. */
static void world_build(world *w, uint32_t size, int with_rt)
{
    pf_error err;
    pf_isa isa = pf_isa_detect();
    w->rt = NULL;
    if (with_rt) assert_int_equal(pf_rt_create(&w->rt, &w->scene, isa, 1, &err), PF_OK);
    w->jobs = pf_jobs_create(2);
    assert_non_null(w->jobs);
    assert_int_equal(rs_context_create(&w->ctx, &w->scene, w->jobs, rs_simd_for_isa(isa), &err), PF_OK);
    rs_shadow_desc desc = {.size = size};
    assert_int_equal(rs_shadow_set_init(&w->set, &w->scene, &desc, &err), PF_OK);
    rs_shadow_set_render(w->ctx, &w->set, NULL);
}

static void world_free(world *w)
{
    rs_shadow_set_free(&w->set);
    rs_context_destroy(w->ctx);
    pf_jobs_destroy(w->jobs);
    if (w->rt) pf_rt_destroy(w->rt);
    pf_scene_free(&w->scene);
}

static int load(world *w, const char *path)
{
    memset(w, 0, sizeof *w);
    if (!tu_file_exists(path)) {
        print_message("SKIP: %s is absent\n", path);
        return 0;
    }
    pf_error err;
    pf_gltf_options opts = {.ignore_textures = 1};
    pf_result r = pf_gltf_load(&w->scene, path, &opts, &err);
    if (r != PF_OK) print_error("%s\n", err.message);
    assert_int_equal(r, PF_OK);
    return 1;
}

/* ---------------------------------------------------------------- agreement */

typedef struct sample {
    pf_vec3 p;      /* visible point */
    pf_vec3 ng;     /* unit geometric normal of the CCW triangle */
    pf_vec3 n_view; /* ng turned to face the camera (the side a frame shades) */
    uint32_t pixel;
} sample;

/* The points a frame shades: Embree primary rays through every pixel centre
 * of a width x height image (gi_camera_ray), those that hit. */
static sample *sample_camera(const world *w, const pf_camera *cam, uint32_t width, uint32_t height, uint32_t *count)
{
    const pf_scene *s = &w->scene;
    sample *out = malloc(sizeof(sample) * width * height);
    assert_non_null(out);
    uint32_t n = 0;
    for (uint32_t y = 0; y < height; y++)
        for (uint32_t x0 = 0; x0 < width; x0 += PF_RT_WIDTH) {
            pf_ray rays[PF_RT_WIDTH];
            pf_hit hits[PF_RT_WIDTH];
            uint32_t k = width - x0 < PF_RT_WIDTH ? width - x0 : PF_RT_WIDTH;
            for (uint32_t i = 0; i < k; i++) rays[i] = gi_camera_ray(cam, width, height, x0 + i, y);
            pf_rt_intersect(w->rt, rays, hits, k);
            for (uint32_t i = 0; i < k; i++) {
                if (hits[i].prim == PF_RT_MISS) continue;
                const uint32_t *t = &s->indices[3 * hits[i].prim];
                pf_vec3 a = s->positions[t[0]], b = s->positions[t[1]], c = s->positions[t[2]];
                float u = hits[i].u, v = hits[i].v;
                sample *o = &out[n++];
                o->pixel = y * width + x0 + i;
                o->p = pf_v3_add(pf_v3_add(pf_v3_scale(a, 1.0f - u - v), pf_v3_scale(b, u)), pf_v3_scale(c, v));
                o->ng = pf_v3_normalize(pf_v3_cross(pf_v3_sub(b, a), pf_v3_sub(c, a)));
                o->n_view = pf_v3_dot(o->ng, rays[i].dir) > 0.0f ? pf_v3_scale(o->ng, -1.0f) : o->ng;
            }
        }
    *count = n;
    return out;
}

/* World size of one shadow-map texel at p (across the light's rays). */
static float texel_world(const rs_shadow_map *m, pf_vec3 p)
{
    if (m->kind == RS_SHADOW_ORTHO) return 2.0f * fmaxf(m->half_w, m->half_h) / (float)m->size;
    uint32_t f = m->kind == RS_SHADOW_CUBE ? rs_shadow_cube_face(m->eye, p) : 0u;
    return 2.0f * m->tan_half * pf_v3_dot(pf_v3_sub(p, m->eye), m->forward[f]) / (float)m->size;
}

/* The shadow ray of gi_raytrace.c from p (geometric normal ng) to the light;
 * returns 0 when the light cannot reach (beyond a point light). */
static int shadow_ray(const pf_light *L, pf_vec3 p, pf_vec3 ng, pf_ray *r)
{
    pf_vec3 wi;
    float dist = INFINITY;
    if (L->type == PF_LIGHT_DIRECTIONAL)
        wi = pf_v3_scale(L->direction, -1.0f);
    else {
        pf_vec3 d = pf_v3_sub(L->position, p);
        dist = pf_v3_length(d);
        if (!(dist > 0.0f)) return 0;
        wi = pf_v3_scale(d, 1.0f / dist);
    }
    r->org = pf_rt_offset_origin(p, ng, wi);
    r->dir = wi;
    r->tnear = 0.0f;
    r->tfar = isinf(dist) ? INFINITY : dist * (1.0f - 1.0e-4f);
    return 1;
}

#define NEIGHBOURS 8
/* A sample is "near a shadow boundary" when the ray-traced answer changes
 * within BOUNDARY_TEXELS shadow-map texels of it, measured across the
 * light's rays (in the map's image plane): 8 more shadow rays start from p
 * moved by that much in 8 directions perpendicular to the light direction
 * (pushed along the light direction back onto p's tangent plane where the
 * move went below it), and any answer differing from p's marks p. 3 texels
 * = the 4x4 kernel's reach (2 per axis) plus the half texel by which the
 * rasterized edge may lie off the true one, rounded up. */
#define BOUNDARY_TEXELS 3.0f

typedef struct agreement {
    uint32_t samples, lit_rt, agree1, agree16, fractional; /* all samples */
    uint32_t away, away_agree1, away_agree16;              /* samples away from shadow boundaries */
} agreement;

static agreement measure(const world *w, uint32_t light, const sample *smp, uint32_t n)
{
    const pf_light *L = &w->scene.lights[light];
    rs_shadow_map m1 = w->set.maps[light], m16 = w->set.maps[light];
    m1.desc.filter = RS_SHADOW_PCF1;
    m16.desc.filter = RS_SHADOW_PCF16;
    const uint32_t per = 1 + NEIGHBOURS;
    pf_ray *rays = malloc(sizeof(pf_ray) * n * per);
    uint8_t *valid = calloc((size_t)n * per, 1), *occ = malloc((size_t)n * per);
    uint32_t *which = malloc(sizeof(uint32_t) * n);
    assert_true(rays && valid && occ && which);
    uint32_t m = 0;
    for (uint32_t k = 0; k < n; k++) {
        gi_light_sample ls;
        if (!gi_light_irradiance(L, smp[k].p, smp[k].n_view, &ls)) continue;
        pf_ray *r = &rays[m * per];
        uint8_t *v = &valid[m * per];
        v[0] = (uint8_t)shadow_ray(L, smp[k].p, smp[k].ng, &r[0]);
        assert_true(v[0]);
        pf_vec3 l = ls.wi, n_l = pf_v3_dot(smp[k].ng, l) < 0.0f ? pf_v3_scale(smp[k].ng, -1.0f) : smp[k].ng;
        pf_vec3 ta, tb;
        pf_v3_basis(l, &ta, &tb);
        float radius = BOUNDARY_TEXELS * texel_world(&w->set.maps[light], smp[k].p);
        for (uint32_t j = 0; j < NEIGHBOURS; j++) {
            float ang = (float)j * (2.0f * PF_PI / NEIGHBOURS);
            pf_vec3 e = pf_v3_add(pf_v3_scale(ta, radius * cosf(ang)), pf_v3_scale(tb, radius * sinf(ang)));
            float below = -pf_v3_dot(e, n_l), cos_l = pf_v3_dot(l, n_l);
            if (below > 0.0f) e = pf_v3_add(e, pf_v3_scale(l, below / cos_l));
            pf_vec3 q = pf_v3_add(smp[k].p, e);
            /* pushed past a point light: nothing can shadow it */
            if (L->type != PF_LIGHT_DIRECTIONAL && pf_v3_dot(pf_v3_sub(L->position, q), l) <= 0.0f) continue;
            v[1 + j] = (uint8_t)shadow_ray(L, q, smp[k].ng, &r[1 + j]);
        }
        which[m++] = k;
    }
    /* compact the valid rays, trace, scatter back */
    pf_ray *packed = malloc(sizeof(pf_ray) * m * per);
    uint8_t *pocc = malloc((size_t)m * per);
    assert_true(packed && pocc);
    uint32_t np = 0;
    for (uint32_t i = 0; i < m * per; i++)
        if (valid[i]) packed[np++] = rays[i];
    pf_rt_occluded(w->rt, packed, pocc, np);
    np = 0;
    for (uint32_t i = 0; i < m * per; i++) occ[i] = valid[i] ? pocc[np++] : 0;
    free(packed);
    free(pocc);

    agreement a;
    memset(&a, 0, sizeof a);
    a.samples = m;
    for (uint32_t i = 0; i < m; i++) {
        const sample *s = &smp[which[i]];
        int lit_rt = !occ[i * per];
        int near = 0;
        for (uint32_t j = 1; j < per; j++) near |= valid[i * per + j] && occ[i * per + j] != occ[i * per];
        float v1 = rs_shadow_visibility(&m1, s->p, s->ng);
        float v16 = rs_shadow_visibility(&m16, s->p, s->ng);
        assert_true(v1 == 0.0f || v1 == 1.0f);
        assert_true(v16 >= 0.0f && v16 <= 1.0f);
        int ok1 = lit_rt == (v1 == 1.0f), ok16 = lit_rt == (v16 >= 0.5f);
        a.lit_rt += (uint32_t)lit_rt;
        a.agree1 += (uint32_t)ok1;
        a.agree16 += (uint32_t)ok16;
        a.fractional += (uint32_t)(v16 > 0.0f && v16 < 1.0f);
        if (!near) {
            a.away++;
            a.away_agree1 += (uint32_t)ok1;
            a.away_agree16 += (uint32_t)ok16;
        }
    }
    free(rays);
    free(valid);
    free(occ);
    free(which);
    return a;
}

typedef struct view {
    pf_vec3 eye, target;
} view;

/* Renders the maps of the three lights (spot, point, directional) at the
 * default 1024 and checks each against the rays at the points seen in
 * VIEW x VIEW images from the scene's camera, if it has one, and from each
 * of `views` (60-degree cameras from eye to target). */

static void check_scene(const char *path, const pf_light lights[3], const view *views, uint32_t view_count)
{
    static const char *const kind_name[] = {"perspective", "cube", "ortho"};
    static const rs_shadow_kind want_kind[3] = {RS_SHADOW_SPOT, RS_SHADOW_CUBE, RS_SHADOW_ORTHO};
    world w;
    if (!load(&w, path)) return;
    world_lights(&w, lights, 3);
    world_build(&w, 0, 1);
    /* the scene's camera, then the given views, one after another */
    sample *smp = malloc(sizeof(sample) * VIEW * VIEW * (1 + view_count));
    assert_non_null(smp);
    uint32_t n = 0, panel = 0;
    for (uint32_t v = 0; v < 1 + view_count; v++) {
        pf_camera cam;
        if (v == 0 && w.scene.camera_count == 0) continue;
        assert_true(panel < 3); /* the debug images hold 3 views */
        if (v == 0)
            cam = w.scene.cameras[0];
        else {
            pf_error err;
            assert_int_equal(pf_camera_look_at(&cam, views[v - 1].eye, views[v - 1].target, pf_radians(60.0f), &err),
                             PF_OK);
        }
        uint32_t k;
        sample *part = sample_camera(&w, &cam, VIEW, VIEW, &k);
        for (uint32_t i = 0; i < k; i++) part[i].pixel += panel * VIEW * VIEW;
        panel++;
        memcpy(smp + n, part, sizeof(sample) * k);
        n += k;
        free(part);
    }
    const char *name = strrchr(path, '/') + 1;
    for (uint32_t l = 0; l < 3; l++) {
        assert_int_equal(w.set.maps[l].kind, want_kind[l]);
        assert_int_equal(w.set.maps[l].size, RS_SHADOW_DEFAULT_SIZE);
        agreement a = measure(&w, l, smp, n);
        double p1 = (double)a.agree1 / a.samples, p16 = (double)a.agree16 / a.samples;
        double q1 = (double)a.away_agree1 / a.away, q16 = (double)a.away_agree16 / a.away;
        print_message("%s %s: %u samples (%.1f%% lit): 1-tap %.3f%%, PCF %.3f%% (%u fractional); "
                      "%.2f%% near a boundary, away from them: 1-tap %.3f%%, PCF %.3f%%\n",
                      name, kind_name[l], a.samples, 100.0 * a.lit_rt / a.samples, 100.0 * p1, 100.0 * p16,
                      a.fractional, 100.0 * (a.samples - a.away) / a.samples, 100.0 * q1, 100.0 * q16);
        /* enough samples in light and in shadow for the figure to mean something */
        assert_true(a.samples >= VIEW * VIEW / 20);
        assert_true(a.lit_rt >= a.samples / 20 && a.lit_rt <= a.samples - a.samples / 20);
        assert_true(a.away >= a.samples / 2);
        assert_true(q1 >= MIN_AGREEMENT);
        assert_true(q16 >= MIN_AGREEMENT);
        assert_true(p1 >= MIN_AGREEMENT_ALL);
        assert_true(p16 >= MIN_AGREEMENT_ALL);
    }
    free(smp);
    world_free(&w);
}

static void test_agreement_cornell(void **state)
{
    (void)state;
    const pf_light lights[3] = {
        make_spot(pf_v3(0.45f, 0.5f, 0.1f), pf_v3(0.25f, 0.0f, 0.35f), 30.0f, 40.0f),
        make_point(pf_v3(0.278f, 0.5388f, 0.2795f)), /* the scene's own light */
        make_directional(pf_v3(-0.3f, -0.6f, 1.0f)), /* in through the open front */
    };
    check_scene(CORNELL_PATH, lights, NULL, 0);
}

static void test_agreement_maze(void **state)
{
    (void)state;
    const pf_light lights[3] = {
        make_spot(pf_v3(3.0f, 4.0f, -3.0f), pf_v3(0.0f, 0.0f, 0.5f), 25.0f, 35.0f),
        make_point(pf_v3(0.5f, 4.0f, 0.5f)), /* the scene's own light */
        make_directional(pf_v3(0.35f, -1.0f, 0.2f)),
    };
    check_scene(MAZE_PATH, lights, NULL, 0);
}

static void test_agreement_sibenik(void **state)
{
    (void)state;
    const pf_light lights[3] = {
        make_spot(pf_v3(12.0f, -4.0f, 2.0f), pf_v3(-5.0f, -15.0f, -2.0f), 25.0f, 35.0f),
        make_point(pf_v3(-2.0f, -6.0f, 0.5f)), /* in the nave, among the columns */
        make_directional(pf_v3(0.5f, -1.0f, 0.3f)),
    };
    /* Sibenik has no camera: one down the nave, one from outside (the sun
     * reaches nothing inside). */
    const view views[2] = {{{-17.0f, -12.0f, 0.0f}, {10.0f, -10.0f, 0.0f}},
                           {{-32.0f, 12.0f, 30.0f}, {0.0f, -6.0f, 0.0f}}};
    check_scene(SIBENIK_PATH, lights, views, 2);
}

/* ------------------------------------------------------------- determinism */

static int isa_has(pf_isa want)
{
    pf_isa best = pf_isa_detect();
    return best >= want;
}

static void render_all(pf_scene *scene, uint32_t threads, rs_simd simd, uint32_t size, float **out, size_t *bytes)
{
    pf_error err;
    pf_jobs *jobs = pf_jobs_create(threads);
    rs_context *ctx;
    assert_int_equal(rs_context_create(&ctx, scene, jobs, simd, &err), PF_OK);
    rs_shadow_set set;
    rs_shadow_desc desc = {.size = size};
    assert_int_equal(rs_shadow_set_init(&set, scene, &desc, &err), PF_OK);
    *bytes = 0;
    for (uint32_t l = 0; l < set.count; l++)
        *bytes += sizeof(float) * set.maps[l].face_count * set.maps[l].size * set.maps[l].size;
    *out = malloc(*bytes);
    assert_non_null(*out);
    size_t off = 0;
    for (uint32_t l = 0; l < set.count; l++) {
        rs_shadow_render(ctx, &set.maps[l], 1, NULL);
        size_t b = sizeof(float) * set.maps[l].face_count * set.maps[l].size * set.maps[l].size;
        memcpy((char *)*out + off, set.maps[l].depth, b);
        off += b;
    }
    rs_shadow_set_free(&set);
    rs_context_destroy(ctx);
    pf_jobs_destroy(jobs);
}

static void test_deterministic(void **state)
{
    (void)state;
    world w;
    const int sibenik = !getenv("SOFTGI_TEST_NO_SHARED") && tu_file_exists(SIBENIK_PATH);
    const char *path = sibenik ? SIBENIK_PATH : MAZE_PATH; /* without the shared scenes: the lights placed in the maze's bounds */
    assert_int_equal(load(&w, path), 1);
    pf_vec3 lo = w.scene.bounds_min, hi = w.scene.bounds_max;
    pf_vec3 c = pf_v3_scale(pf_v3_add(lo, hi), 0.5f), e = pf_v3_sub(hi, lo);
    const pf_light lights[3] = {
        sibenik ? make_spot(pf_v3(12.0f, -4.0f, 2.0f), pf_v3(-5.0f, -15.0f, -2.0f), 25.0f, 35.0f)
                : make_spot(pf_v3(c.x + 0.3f * e.x, hi.y + 0.5f * e.y, c.z), pf_v3(c.x, lo.y, c.z), 25.0f, 35.0f),
        sibenik ? make_point(pf_v3(-2.0f, -6.0f, 0.5f)) : make_point(pf_v3(c.x, lo.y + 0.5f * e.y, c.z)),
        make_directional(pf_v3(0.5f, -1.0f, 0.3f)),
    };
    world_lights(&w, lights, 3);
    const uint32_t size = 512;
    float *ref;
    size_t ref_bytes;
    render_all(&w.scene, 1, RS_SIMD_SCALAR, size, &ref, &ref_bytes);
    /* not trivially empty */
    size_t drawn = 0;
    for (size_t i = 0; i < ref_bytes / sizeof(float); i++) drawn += ref[i] > 0.0f;
    print_message("%s: %.1f%% of the texels drawn\n", sibenik ? "sibenik" : "maze",
                  100.0 * (double)drawn / (double)(ref_bytes / sizeof(float)));
    assert_true(drawn > ref_bytes / sizeof(float) / 4);
    /* 1 vs 2 threads on the scalar path, then each SIMD path against it */
    const struct {
        uint32_t threads;
        rs_simd simd;
        pf_isa needs;
    } runs[] = {{2, RS_SIMD_SCALAR, PF_ISA_SSE2}, {2, RS_SIMD_AVX2, PF_ISA_AVX2}, {2, RS_SIMD_AVX512, PF_ISA_AVX512}};
    for (size_t r = 0; r < sizeof runs / sizeof runs[0]; r++) {
        if (!isa_has(runs[r].needs)) {
            print_message("SKIP: %s path (the CPU lacks %s)\n", rs_simd_name(runs[r].simd), pf_isa_name(runs[r].needs));
            continue;
        }
        float *got;
        size_t bytes;
        render_all(&w.scene, runs[r].threads, runs[r].simd, size, &got, &bytes);
        assert_int_equal(bytes, ref_bytes);
        if (memcmp(got, ref, bytes) != 0)
            fail_msg("%u threads, %s: shadow map bytes differ from 1 thread scalar", runs[r].threads,
                     rs_simd_name(runs[r].simd));
        free(got);
    }
    free(ref);
    world_free(&w);
}

/* ----------------------------------------------------- maps vs ray casting */

/* Every texel of every face, ray-cast from the light through the texel's
 * centre with Embree: the rasterized map must hold a surface exactly where
 * the ray hits one, at the ray's depth. This checks that the axes, fov and
 * box the lookup uses (right/up/forward, tan_half, half_w/half_h, znear,
 * zfar) describe the matrices the maps were rendered with. Texel centres on
 * a silhouette may go either way (the rasterizer snaps vertices to 1/256
 * pixel, Embree does not), so a few mismatches are allowed: 1 in 2000
 * (measured: at most 3 in 65536). */
/* ------------------------------------------------- SIMD lookup == scalar */

/* rs_shadow_visibility8 (AVX2, also taken on AVX-512) against the scalar
 * rs_shadow_visibility, bit for bit, on every lane: the points a camera
 * sees (sample_camera) and points spread over the scene's bounds with
 * random normals (behind lights, outside frusta and boxes, zero normals:
 * every early return), for the spot, cube and ortho maps with PCF16 and
 * PCF1, all lanes on and random lane masks. Then the direct-light stage of
 * a rasterized frame: the 8-wide rows give the scalar rows' bytes. */
static void simd_check_scene(const char *path, const pf_light lights[3], const view *v, uint32_t size)
{
    if (!isa_has(PF_ISA_AVX2)) {
        print_message("SKIP: no AVX2\n");
        return;
    }
    world w;
    if (!load(&w, path)) return;
    world_lights(&w, lights, 3);
    world_build(&w, size, 1); /* 0: the default 1024 */
    pf_camera cam;
    pf_error err;
    if (v)
        assert_int_equal(pf_camera_look_at(&cam, v->eye, v->target, pf_radians(60.0f), &err), PF_OK);
    else
        cam = w.scene.cameras[0];
    uint32_t nc;
    sample *smp = sample_camera(&w, &cam, 200, 200, &nc);
    const uint32_t nr = 8192, n = (nc + nr + 7) / 8 * 8;
    float *pos[3], *ng[3];
    for (int a = 0; a < 3; a++) {
        pos[a] = calloc(n, sizeof(float));
        ng[a] = calloc(n, sizeof(float));
        assert_true(pos[a] && ng[a]);
    }
    for (uint32_t i = 0; i < nc; i++) {
        pos[0][i] = smp[i].p.x, pos[1][i] = smp[i].p.y, pos[2][i] = smp[i].p.z;
        ng[0][i] = smp[i].ng.x, ng[1][i] = smp[i].ng.y, ng[2][i] = smp[i].ng.z;
    }
    uint64_t rng = 12345;
    pf_vec3 lo = w.scene.bounds_min, hi = w.scene.bounds_max;
    for (uint32_t i = nc; i < n; i++) {
        pos[0][i] = lo.x + (hi.x - lo.x) * (float)rng_unit(&rng);
        pos[1][i] = lo.y + (hi.y - lo.y) * (float)rng_unit(&rng);
        pos[2][i] = lo.z + (hi.z - lo.z) * (float)rng_unit(&rng);
        int zero_normal = (i % 61) == 0;
        for (int a = 0; a < 3; a++) ng[a][i] = zero_normal ? 0.0f : (float)(2.0 * rng_unit(&rng) - 1.0);
    }
    for (uint32_t l = 0; l < 3; l++) {
        rs_shadow_map *m = &w.set.maps[l];
        for (int filter = 0; filter < 2; filter++) {
            m->desc.filter = filter ? RS_SHADOW_PCF1 : RS_SHADOW_PCF16;
            uint32_t mismatches = 0, fractional = 0, zeros = 0, ones = 0;
            for (uint32_t i = 0; i < n; i += 8) {
                unsigned mask = (i / 8) % 3 == 2 ? (unsigned)(rng_next(&rng) & 0xffu) : 0xffu;
                float simd[8];
                rs_shadow_visibility8(m, RS_SIMD_AVX2, pos[0] + i, pos[1] + i, pos[2] + i, ng[0] + i, ng[1] + i,
                                      ng[2] + i, mask, simd);
                for (uint32_t k = 0; k < 8; k++) {
                    float ref = (mask >> k) & 1u ? rs_shadow_visibility(m, pf_v3(pos[0][i + k], pos[1][i + k],
                                                                                 pos[2][i + k]),
                                                                        pf_v3(ng[0][i + k], ng[1][i + k], ng[2][i + k]))
                                                 : 0.0f;
                    if (memcmp(&ref, &simd[k], sizeof ref) != 0) {
                        if (mismatches < 5)
                            print_error("map %u filter %d point %u: scalar %a simd %a\n", l, filter, i + k,
                                        (double)ref, (double)simd[k]);
                        mismatches++;
                    }
                    fractional += ref > 0.0f && ref < 1.0f;
                    zeros += ref == 0.0f;
                    ones += ref == 1.0f;
                }
            }
            print_message("%s map %u (%s): %u points, %u lit, %u dark, %u fractional, %u mismatches\n",
                          strrchr(path, '/') + 1, l, filter ? "PCF1" : "PCF16", n, ones, zeros, fractional,
                          mismatches);
            assert_int_equal(mismatches, 0);
            /* the comparison covered light, shadow and (PCF16) penumbrae */
            assert_true(ones > n / 50 && zeros > n / 50);
            if (!filter) assert_true(fractional > 0);
        }
        m->desc.filter = RS_SHADOW_PCF16;
    }

    /* the direct-light stage, scalar rows against 8-wide rows (width 197
     * leaves a partial group of 5 pixels at the end of every row) */
    gi_frame f;
    gi_frame_desc fd = {.scene = &w.scene, .rt = w.rt, .jobs = w.jobs, .raster = w.ctx, .camera = &cam, .width = 197,
                        .height = 120};
    assert_int_equal(gi_frame_create(&f, &fd, &err), PF_OK);
    rs_simd best = rs_context_simd(w.ctx);
    gi_frame_render_raster(&f);
    size_t bytes = (size_t)197 * 120 * 3 * sizeof(float);
    float *simd_rows = malloc(bytes);
    assert_non_null(simd_rows);
    memcpy(simd_rows, f.direct, bytes);
    rs_context_set_simd(w.ctx, RS_SIMD_SCALAR);
    memset(f.direct, 0xff, bytes);
    gi_stage_direct_shadowmap(&f);
    assert_memory_equal(simd_rows, f.direct, bytes);
    uint32_t nonzero = 0;
    for (size_t i = 0; i < (size_t)197 * 120 * 3; i++) nonzero += f.direct[i] > 0.0f;
    assert_true(nonzero > 197 * 120 / 10);
    rs_context_set_simd(w.ctx, best);
    free(simd_rows);
    gi_frame_free(&f);
    for (int a = 0; a < 3; a++) free(pos[a]), free(ng[a]);
    free(smp);
    world_free(&w);
}

static void test_simd_matches_scalar(void **state)
{
    (void)state;
    const pf_light cornell[3] = {
        make_spot(pf_v3(0.45f, 0.5f, 0.1f), pf_v3(0.25f, 0.0f, 0.35f), 30.0f, 40.0f),
        make_point(pf_v3(0.278f, 0.5388f, 0.2795f)),
        make_directional(pf_v3(-0.3f, -0.6f, 1.0f)),
    };
    simd_check_scene(CORNELL_PATH, cornell, NULL, 700); /* a size that is no power of two */
    const pf_light sibenik[3] = {
        make_spot(pf_v3(12.0f, -4.0f, 2.0f), pf_v3(-5.0f, -15.0f, -2.0f), 25.0f, 35.0f),
        make_point(pf_v3(-2.0f, -6.0f, 0.5f)),
        make_directional(pf_v3(0.5f, -1.0f, 0.3f)),
    };
    const view nave = {{-17.0f, -12.0f, 0.0f}, {10.0f, -10.0f, 0.0f}};
    simd_check_scene(SIBENIK_PATH, sibenik, &nave, 0);
}

/* The ray through NDC point (nx, ny) of face f of map m: parallel rays over
 * the box for a directional light (t = depth), else from the eye with
 * |dir . forward| = 1 (t = depth along the face axis). */
static pf_ray texel_ray(const rs_shadow_map *m, uint32_t f, float nx, float ny)
{
    pf_ray r;
    if (m->kind == RS_SHADOW_ORTHO) {
        r.org = pf_v3_add(m->eye,
                          pf_v3_add(pf_v3_scale(m->right[0], nx * m->half_w), pf_v3_scale(m->up[0], ny * m->half_h)));
        r.dir = m->forward[0];
        r.tnear = m->znear;
        r.tfar = m->zfar;
    } else {
        pf_vec3 side = pf_v3_add(pf_v3_scale(m->right[f], nx * m->tan_half), pf_v3_scale(m->up[f], ny * m->tan_half));
        r.org = m->eye;
        r.dir = pf_v3_add(m->forward[f], side);
        r.tnear = m->znear;
        r.tfar = INFINITY;
    }
    return r;
}

/* The PCF window at a face's left and right edges: the SIMD lookup
 * (rs_shadow_lookup.h) clamps each tap's column lane by lane, and any
 * shortcut that reads a row's four taps as consecutive texels must fall
 * back there. Groups of 8 points that all look up within 5 texels of a
 * face's left or right edge, or straddle both, must give the scalar
 * lookup's bits (a trial shortcut that took windows starting up to 9
 * texels left of the edge failed only here, not in
 * test_simd_matches_scalar's camera points). The points are the
 * surfaces seen through texel columns 0..4 and size-5..size-1 of every face
 * (ray cast), moved 2% towards or away from the light, so that both lit and
 * shadowed taps are compared. */
static void test_simd_face_borders(void **state)
{
    (void)state;
    if (!isa_has(PF_ISA_AVX2)) {
        print_message("SKIP: no AVX2\n");
        return;
    }
    world w;
    assert_int_equal(load(&w, CORNELL_PATH), 1);
    const pf_light lights[3] = {
        make_spot(pf_v3(0.45f, 0.5f, 0.1f), pf_v3(0.25f, 0.0f, 0.35f), 30.0f, 40.0f),
        make_point(pf_v3(0.278f, 0.5388f, 0.2795f)),
        make_directional(pf_v3(-0.3f, -0.6f, 1.0f)),
    };
    world_lights(&w, lights, 3);
    world_build(&w, 64, 1);
    uint64_t rng = 777;
    for (uint32_t l = 0; l < 3; l++) {
        const rs_shadow_map *m = &w.set.maps[l];
        uint32_t groups = 0, mismatches = 0, lit = 0, dark = 0;
        for (uint32_t f = 0; f < m->face_count; f++)
            for (uint32_t g = 0; g < 96; g++) {
                float pos[3][8], ng[3][8];
                const int side = g % 3; /* 0: left edge, 1: right edge, 2: both in one group */
                const uint32_t y = (uint32_t)(rng_next(&rng) % m->size);
                for (uint32_t k = 0; k < 8; k++) {
                    uint32_t c = (uint32_t)(rng_next(&rng) % 5);
                    int right = side == 1 || (side == 2 && (k & 1));
                    float x = right ? (float)(m->size - 1 - c) : (float)c;
                    x += (float)rng_unit(&rng);
                    float nx = 2.0f * x / (float)m->size - 1.0f;
                    float ny = 1.0f - 2.0f * ((float)y + 0.5f) / (float)m->size;
                    pf_ray r = texel_ray(m, f, nx, ny);
                    pf_hit h = pf_rt_intersect1(w.rt, r);
                    float t = h.prim != PF_RT_MISS ? h.t : 1.0f;
                    t *= (k >> 1) & 1 ? 1.02f : 0.98f;
                    pf_vec3 p = pf_v3_add(r.org, pf_v3_scale(r.dir, t));
                    pos[0][k] = p.x, pos[1][k] = p.y, pos[2][k] = p.z;
                    for (int a = 0; a < 3; a++) ng[a][k] = (float)(2.0 * rng_unit(&rng) - 1.0);
                }
                const unsigned mask = g % 4 == 3 ? (unsigned)(rng_next(&rng) & 0xffu) | 1u : 0xffu;
                float simd[8];
                rs_shadow_visibility8(m, RS_SIMD_AVX2, pos[0], pos[1], pos[2], ng[0], ng[1], ng[2], mask, simd);
                for (uint32_t k = 0; k < 8; k++) {
                    float ref = (mask >> k) & 1u ? rs_shadow_visibility(m, pf_v3(pos[0][k], pos[1][k], pos[2][k]),
                                                                         pf_v3(ng[0][k], ng[1][k], ng[2][k]))
                                                 : 0.0f;
                    if (memcmp(&ref, &simd[k], sizeof ref) != 0) {
                        if (mismatches < 5)
                            print_error("map %u face %u group %u lane %u: scalar %a simd %a\n", l, f, g, k,
                                        (double)ref, (double)simd[k]);
                        mismatches++;
                    }
                    lit += (mask >> k & 1u) && ref == 1.0f;
                    dark += (mask >> k & 1u) && ref < 1.0f;
                }
                groups++;
            }
        print_message("cornell map %u: %u border groups, %u lit, %u partly or fully shadowed, %u mismatches\n", l,
                      groups, lit, dark, mismatches);
        assert_int_equal(mismatches, 0);
        assert_true(lit > groups && dark > groups / 4); /* both outcomes were compared */
    }
    world_free(&w);
}

static void test_map_matches_rays(void **state)
{
    (void)state;
    world w;
    assert_int_equal(load(&w, MAZE_PATH), 1);
    const pf_light lights[3] = {
        make_spot(pf_v3(3.0f, 4.0f, -3.0f), pf_v3(0.0f, 0.0f, 0.5f), 25.0f, 35.0f),
        make_point(pf_v3(0.5f, 1.0f, 0.5f)), /* below the wall tops: walls on every side face */
        make_directional(pf_v3(0.35f, -1.0f, 0.2f)),
    };
    world_lights(&w, lights, 3);
    world_build(&w, 256, 1);
    for (uint32_t l = 0; l < 3; l++) {
        const rs_shadow_map *m = &w.set.maps[l];
        uint32_t texels = 0, coverage_bad = 0, hits = 0, depth_bad = 0;
        for (uint32_t f = 0; f < m->face_count; f++) {
            const float *plane = rs_shadow_map_face(m, f);
            for (uint32_t y = 0; y < m->size; y++)
                for (uint32_t x = 0; x < m->size; x++) {
                    float nx = 2.0f * ((float)x + 0.5f) / (float)m->size - 1.0f;
                    float ny = 1.0f - 2.0f * ((float)y + 0.5f) / (float)m->size;
                    pf_ray r = texel_ray(m, f, nx, ny);
                    pf_hit h = pf_rt_intersect1(w.rt, r);
                    float zs = plane[(size_t)y * m->size + x];
                    texels++;
                    if ((h.prim != PF_RT_MISS) != (zs > 0.0f)) {
                        coverage_bad++;
                        continue;
                    }
                    if (h.prim == PF_RT_MISS) continue;
                    hits++;
                    double d = m->kind == RS_SHADOW_ORTHO ? m->znear + (1.0 - zs) * (m->zfar - m->znear)
                                                          : m->znear / zs;
                    depth_bad += fabs(d - h.t) > 1e-3 * h.t;
                }
        }
        print_message("light %u: %u texels, %u hit, coverage differs at %u, depth differs by > 0.1%% at %u\n", l,
                      texels, hits, coverage_bad, depth_bad);
        assert_true(hits > texels / 4);
        assert_true(coverage_bad <= texels / 2000);
        assert_true(depth_bad <= texels / 2000);
    }
    world_free(&w);
}

/* ---------------------------------------------------------- PCF and bias */

/* Texel coordinates of p in a single-face map. */
static void texel_of(const rs_shadow_map *m, pf_vec3 p, float *fx, float *fy)
{
    float c[4];
    rs_mat4_transform(&m->view_proj[0], p, c);
    *fx = (0.5f * c[0] / c[3] + 0.5f) * (float)m->size;
    *fy = (0.5f - 0.5f * c[1] / c[3]) * (float)m->size;
}

/* A floor (y = 0) and a blocker (x <= 0 at y = 1) under a directional light
 * straight down (shadow edge: x = 0) and a spot at (2, 3, 0.3) (edge: x =
 * 2 - 2 * 3 / (3 - 1) = -1). Walking across the edge in steps of 1/100
 * texel, PCF must give fractional values near it and exactly 0 (shadow
 * side) or 1 (lit side) farther from it than 3 texels in the map: the 4x4
 * kernel reaches 2 texels, the rasterized edge lies within half a texel of
 * the true one. */
static void test_pcf_edge(void **state)
{
    (void)state;
    world w;
    memset(&w, 0, sizeof w);
    tu_quad quads[2] = {
        {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{-5, 1, 0}, {5, 0, 0}, {0, 0, -10}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    tu_make_scene(&w.scene, quads, 2);
    const pf_light lights[2] = {make_directional(pf_v3(0, -1, 0)),
                                make_spot(pf_v3(2.0f, 3.0f, 0.3f), pf_v3(0, 0, 0), 30.0f, 45.0f)};
    world_lights(&w, lights, 2);
    world_build(&w, 256, 0);
    for (uint32_t l = 0; l < 2; l++) {
        const rs_shadow_map *m = &w.set.maps[l];
        float edge = l == 0 ? 0.0f : -1.0f;
        float ex, ey, fx, fy;
        texel_of(m, pf_v3(edge, 0, 0.3f), &ex, &ey);
        texel_of(m, pf_v3(edge + 0.01f, 0, 0.3f), &fx, &fy);
        float step = 0.01f * 0.01f / hypotf(fx - ex, fy - ey); /* world x per 1/100 texel */
        int fractional = 0, far = 0;
        for (int k = -600; k <= 600; k++) {
            pf_vec3 p = pf_v3(edge + (float)k * step, 0, 0.3f);
            float v = rs_shadow_visibility(m, p, pf_v3(0, 1, 0));
            if (v > 0.0f && v < 1.0f) fractional++;
            texel_of(m, p, &fx, &fy);
            if (hypotf(fx - ex, fy - ey) > 3.0f) {
                far++;
                if (p.x < edge) assert_true(v == 0.0f);
                else assert_true(v == 1.0f);
            }
        }
        print_message("light %u: %d of 1201 positions across the edge fractional, %d beyond 3 texels\n", l,
                      fractional, far);
        assert_true(fractional > 200);
        assert_true(far > 400);
    }
    world_free(&w);
}

/* A lit floor (8 x 8 m sampled) under a wide spot (outer cone 55 degrees,
 * 1.2 m up), a point light 0.7 m up (light arriving at up to 84 degrees from
 * the normal) and a low sun (75 degrees from the normal): every floor point
 * the light reaches is fully lit, with PCF and with one tap. */
static void test_no_acne(void **state)
{
    (void)state;
    world w;
    memset(&w, 0, sizeof w);
    tu_quad floor = {{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f};
    tu_make_scene(&w.scene, &floor, 1);
    const pf_light lights[3] = {make_spot(pf_v3(0.3f, 1.2f, -0.2f), pf_v3(0.4f, 0.0f, -0.1f), 40.0f, 55.0f),
                                make_point(pf_v3(-0.5f, 0.7f, 0.4f)),
                                make_directional(pf_v3(cosf(pf_radians(15.0f)), -sinf(pf_radians(15.0f)), 0.2f))};
    world_lights(&w, lights, 3);
    world_build(&w, 0, 0);
    uint64_t seed = 42;
    for (uint32_t l = 0; l < 3; l++) {
        uint32_t tested = 0;
        for (int k = 0; k < 20000; k++) {
            pf_vec3 p = pf_v3((float)(rng_unit(&seed) * 8.0 - 4.0), 0.0f, (float)(rng_unit(&seed) * 8.0 - 4.0));
            gi_light_sample ls;
            if (!gi_light_irradiance(&w.scene.lights[l], p, pf_v3(0, 1, 0), &ls)) continue;
            rs_shadow_map m = w.set.maps[l];
            float v16 = rs_shadow_visibility(&m, p, pf_v3(0, 1, 0));
            m.desc.filter = RS_SHADOW_PCF1;
            float v1 = rs_shadow_visibility(&m, p, pf_v3(0, 1, 0));
            if (v16 != 1.0f || v1 != 1.0f)
                fail_msg("light %u: floor point (%g, 0, %g) self-shadowed: PCF %g, 1 tap %g", l, p.x, p.z, v16, v1);
            tested++;
        }
        assert_true(tested > 1000);
    }
    world_free(&w);
}

/* Points outside a spot's frustum are unlit; outside the ortho box lit. */
static void test_outside(void **state)
{
    (void)state;
    world w;
    memset(&w, 0, sizeof w);
    tu_quad floor = {{0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f};
    tu_make_scene(&w.scene, &floor, 1);
    const pf_light lights[2] = {make_spot(pf_v3(0, 1, 0), pf_v3(0, 0, 0), 10.0f, 20.0f),
                                make_directional(pf_v3(0, -1, 0))};
    world_lights(&w, lights, 2);
    world_build(&w, 64, 0);
    assert_true(rs_shadow_visibility(&w.set.maps[0], pf_v3(0, 0, 0), pf_v3(0, 1, 0)) == 1.0f);
    assert_true(rs_shadow_visibility(&w.set.maps[0], pf_v3(0.9f, 0, 0), pf_v3(0, 1, 0)) == 0.0f); /* 42 deg */
    assert_true(rs_shadow_visibility(&w.set.maps[0], pf_v3(0, 2, 0), pf_v3(0, 1, 0)) == 0.0f);    /* behind */
    assert_true(rs_shadow_visibility(&w.set.maps[1], pf_v3(0.5f, 0, 0.5f), pf_v3(0, 1, 0)) == 1.0f);
    assert_true(rs_shadow_visibility(&w.set.maps[1], pf_v3(5, 0, 0), pf_v3(0, 1, 0)) == 1.0f);
    assert_true(rs_shadow_visibility(&w.set.maps[1], pf_v3(0, -3, 0), pf_v3(0, 1, 0)) == 1.0f);
    /* a wide spot (outer cone over 60 degrees) gets a cube map */
    pf_light wide = make_spot(pf_v3(0, 1, 0), pf_v3(0, 0, 0), 50.0f, 80.0f);
    rs_shadow_map m;
    pf_error err;
    w.scene.lights[0] = wide;
    assert_int_equal(rs_shadow_map_init(&m, &w.scene, 0, NULL, &err), PF_OK);
    assert_int_equal(m.kind, RS_SHADOW_CUBE);
    assert_int_equal(m.face_count, 6);
    assert_int_equal(m.size, RS_SHADOW_DEFAULT_SIZE);
    rs_shadow_map_free(&m);
    world_free(&w);
}

static void test_cube_faces(void **state)
{
    (void)state;
    pf_vec3 e = pf_v3(1, 2, 3);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(5, 2, 3)), 0);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(-5, 2, 3)), 1);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(1, 9, 3)), 2);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(1, -9, 3)), 3);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(1, 2, 9)), 4);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(1, 2, -9)), 5);
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(2, 3, 3)), 0); /* tie x = y: x */
    assert_int_equal(rs_shadow_cube_face(e, pf_v3(1, 1, 4)), 3); /* tie y = z: y */
}

static void test_bad_input(void **state)
{
    (void)state;
    pf_scene s;
    tu_quad floor = {{0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f};
    tu_make_scene(&s, &floor, 1);
    pf_light L = make_point(pf_v3(0, 1, 0));
    pf_error err;
    assert_int_equal(pf_scene_add_light(&s, &L, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    rs_shadow_map m;
    assert_int_equal(rs_shadow_map_init(&m, &s, 1, NULL, &err), PF_ERR_ARGUMENT);
    rs_shadow_map_free(&m);
    rs_shadow_desc tiny = {.size = 8}, huge = {.size = RS_MAX_SIZE + 1};
    assert_int_equal(rs_shadow_map_init(&m, &s, 0, &tiny, &err), PF_ERR_ARGUMENT);
    rs_shadow_map_free(&m);
    assert_int_equal(rs_shadow_map_init(&m, &s, 0, &huge, &err), PF_ERR_ARGUMENT);
    rs_shadow_map_free(&m);
    s.lights[0].type = PF_LIGHT_DIRECTIONAL;
    s.lights[0].direction = pf_v3(0, 0, 0);
    assert_int_equal(rs_shadow_map_init(&m, &s, 0, NULL, &err), PF_ERR_ARGUMENT);
    rs_shadow_map_free(&m);
    pf_scene_free(&s);
}

/* ---------------------------------------------------- receiver-driven tiles */

/* Every texel outside the maps' valid tiles set to 1 (the nearest depth:
 * a lookup reading one would see a shadow), then the direct light again:
 * the same bytes, so the frame read valid tiles only. Returns the tiles
 * valid over all maps. */
static uint32_t poison_and_compare(gi_frame *f, const char *what)
{
    const size_t n = (size_t)3 * f->width * f->height;
    float *before = malloc(n * sizeof(float));
    assert_non_null(before);
    memcpy(before, f->direct, n * sizeof(float));
    uint32_t valid = 0, lit = 0;
    for (uint32_t l = 0; l < f->shadows.count; l++) {
        rs_shadow_map *m = &f->shadows.maps[l];
        for (uint32_t face = 0; face < m->face_count; face++)
            for (uint32_t y = 0; y < m->size; y++)
                for (uint32_t x = 0; x < m->size; x++) {
                    if (rs_shadow_texel_valid(m, face, x, y)) {
                        valid += x % RS_TILE == 0 && y % RS_TILE == 0;
                        continue;
                    }
                    rs_shadow_map_face(m, face)[(size_t)y * m->size + x] = 1.0f;
                }
    }
    gi_stage_direct_shadowmap(f);
    if (memcmp(before, f->direct, n * sizeof(float))) fail_msg("%s: the direct light read a tile it did not draw", what);
    for (size_t i = 0; i < n; i++) lit += before[i] > 0.0f;
    assert_true(lit > n / 8); /* the lights do reach what the camera sees */
    free(before);
    return valid;
}

/* The tiles each lookup reads, worked out here as rs_shadow_visibility does
 * (the face, the face's matrix, the 4 x 4 window's clamped texels) for every
 * pixel with a surface: each must be in the maps' need, as marked by the
 * frame's last sample (rs_shadow_need_lanes). */
static void need_covers_lookups(const gi_frame *f)
{
    for (uint32_t l = 0; l < f->shadows.count; l++) {
        const rs_shadow_map *m = &f->shadows.maps[l];
        for (uint32_t i = 0; i < f->width * f->height; i++) {
            if (f->gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
            pf_vec3 p = pf_v3(f->gbuf.pos_x[i], f->gbuf.pos_y[i], f->gbuf.pos_z[i]);
            uint32_t face = m->kind == RS_SHADOW_CUBE ? rs_shadow_cube_face(m->eye, p) : 0;
            float c[4];
            rs_mat4_transform(&m->view_proj[face], p, c);
            float x = m->kind == RS_SHADOW_ORTHO ? c[0] : c[0] / c[3], y = m->kind == RS_SHADOW_ORTHO ? c[1] : c[1] / c[3];
            float s = (float)m->size;
            float fx = fminf(fmaxf((0.5f * x + 0.5f) * s, -8.0f), s + 8.0f);
            float fy = fminf(fmaxf((0.5f - 0.5f * y) * s, -8.0f), s + 8.0f);
            int x0 = (int)floorf(fx - 1.5f), y0 = (int)floorf(fy - 1.5f), last = (int)m->size - 1;
            for (int ty = y0; ty < y0 + 4; ty++)
                for (int tx = x0; tx < x0 + 4; tx++) {
                    int cx = tx < 0 ? 0 : (tx > last ? last : tx), cy = ty < 0 ? 0 : (ty > last ? last : ty);
                    uint32_t t = (uint32_t)cy / RS_TILE * m->tiles_side + (uint32_t)cx / RS_TILE;
                    if (!(m->need[(size_t)face * m->tile_words + t / 64] >> (t % 64) & 1u))
                        fail_msg("light %u: pixel %u reads texel (%d, %d) of face %u, a tile not marked needed", l, i,
                                 cx, cy, face);
                }
        }
    }
}

/* Receiver-driven rendering (gi_stage_shadow_maps, rs_shadow_render_needed):
 * on the Cornell box lit by a spot, a point light (cube) and a sun, 1024^2
 * maps (256 tiles a face), a frame draws only the tiles its receivers read
 * and reads no other (need_covers_lookups, poison_and_compare):
 * - the first frame draws fewer tiles than the maps hold;
 * - the camera moved, the lights kept: the maps are completed (a light
 *   that stays costs nothing afterwards), every tile valid;
 * - the lights moved: fresh maps, again only the needed tiles;
 * - that frame's direct light equals the one from maps drawn whole
 *   (rs_shadow_render), bit for bit. */
static void test_needed_tiles(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL_PATH);
    pf_light *lights = realloc(x.scene.lights, 3 * sizeof(pf_light));
    assert_non_null(lights);
    x.scene.lights = lights;
    x.scene.light_count = 3;
    lights[0] = make_spot(pf_v3(0.45f, 0.5f, 0.1f), pf_v3(0.25f, 0.0f, 0.35f), 30.0f, 40.0f);
    lights[1] = make_point(pf_v3(0.278f, 0.5388f, 0.2795f));
    lights[2] = make_directional(pf_v3(-0.3f, -0.6f, 1.0f));
    assert_true(x.scene.camera_count > 0);
    pf_camera cam = x.scene.cameras[0];
    tu_fx_desc d = {.threads = 2, .simd = rs_simd_for_isa(pf_isa_detect()), .w = 160, .h = 120, .cam = &cam,
                    .shadow_size = 1024};
    tu_fx_begin_with(&x, &d);
    const uint32_t all = 256 * (1 + 6 + 1);

    gi_frame_render_raster(&x.f);
    assert_int_equal(x.f.status, PF_OK);
    need_covers_lookups(&x.f);
    uint32_t drawn = x.f.motion_stats.shadow_tiles, valid = poison_and_compare(&x.f, "first frame");
    print_message("receiver-driven shadow maps: first frame %u of %u tiles\n", drawn, all);
    assert_int_equal(drawn, valid);
    assert_true(drawn > 0 && drawn < all);

    x.f.camera.eye = pf_v3_add(x.f.camera.eye, pf_v3_scale(x.f.camera.right, 0.05f)); /* lights kept */
    gi_frame_render_raster(&x.f);
    assert_int_equal(x.f.status, PF_OK);
    drawn = x.f.motion_stats.shadow_tiles;
    assert_int_equal(poison_and_compare(&x.f, "camera moved"), all);
    assert_int_equal(drawn, all - valid);
    gi_frame_render_raster(&x.f); /* and then nothing */
    assert_int_equal(x.f.motion_stats.shadow_tiles, 0);

    for (int l = 0; l < 3; l++) x.scene.lights[l].position = pf_v3_add(x.scene.lights[l].position, pf_v3(0.03f, -0.02f, 0.01f));
    x.scene.lights[2].direction = pf_v3_normalize(pf_v3(-0.25f, -0.6f, 1.0f));
    gi_frame_render_raster(&x.f);
    assert_int_equal(x.f.status, PF_OK);
    drawn = x.f.motion_stats.shadow_tiles;
    need_covers_lookups(&x.f);
    assert_int_equal(poison_and_compare(&x.f, "lights moved"), drawn);
    assert_true(drawn > 0 && drawn < all);
    print_message("receiver-driven shadow maps: moved lights %u of %u tiles\n", drawn, all);

    const size_t n = (size_t)3 * x.f.width * x.f.height;
    float *partial = malloc(n * sizeof(float));
    assert_non_null(partial);
    memcpy(partial, x.f.direct, n * sizeof(float));
    rs_shadow_set_render(x.rs, &x.f.shadows, NULL);
    gi_stage_direct_shadowmap(&x.f);
    if (memcmp(partial, x.f.direct, n * sizeof(float))) fail_msg("the needed tiles' direct light differs from whole maps'");
    free(partial);
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cube_faces),        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_outside),           cmocka_unit_test(test_no_acne),
        cmocka_unit_test(test_pcf_edge),          cmocka_unit_test(test_map_matches_rays),
        cmocka_unit_test(test_deterministic),     cmocka_unit_test(test_simd_matches_scalar),
        cmocka_unit_test(test_simd_face_borders), cmocka_unit_test(test_needed_tiles),
        cmocka_unit_test(test_agreement_cornell), cmocka_unit_test(test_agreement_maze),
        cmocka_unit_test(test_agreement_sibenik),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
