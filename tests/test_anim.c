/* test_anim: glTF animation, skins and morph targets (pf_anim.h) through the
 * loader (pf_gltf.h) on the authored files of tools/make_anim_gltf.py
 * (tests/data/gltf/anim/; the expected poses are derived there, next to
 * each file, and repeated here).
 *
 * - sampling: LINEAR, STEP and CUBICSPLINE for translation, rotation (the
 *   shortest path), scale and morph weights, against hand-computed poses;
 *   clamping before the first and after the last key;
 * - a two-joint skin bend over two JOINTS/WEIGHTS sets (u8, u16, normalized
 *   u8 and float), the skinned mesh node's own transform ignored; morph
 *   targets with mesh, node and animated weights; a hierarchy of animated
 *   nodes with a flat-shaded primitive;
 * - the pose contract: the same vertex and triangle counts and triangle
 *   order at every time, the same bytes for the same t whatever came
 *   before, the static pose giving back the loaded bytes, the moved report
 *   and its bounds, a failed pose leaving the scene as it was;
 * - hostile files (bad_*.gltf): the exact pf_result, a message naming the
 *   file and the object, an empty scene and anim, never a crash. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "pf_anim.h"
#include "pf_gltf.h"

#define ANIM_DIR SOFTGI_TEST_DATA "/gltf/anim"
#define DATA(name) ANIM_DIR "/" name
#define EPS 2e-6f

static const float R2 = 0.70710678118654752f; /* sqrt(1/2) */

/* ------------------------------------------------------------------ helpers */

typedef struct loaded {
    pf_scene scene;
    pf_anim anim;
} loaded;

static void load_(loaded *l, const char *path, const char *file, int line)
{
    pf_gltf_options o = {.anim = &l->anim};
    pf_error e = {0};
    if (pf_gltf_load(&l->scene, path, &o, &e) != PF_OK) {
        fprintf(stderr, "%s:%d: loading %s: %s\n", file, line, path, e.message);
        _fail(file, line);
    }
}
#define load(l, path) load_((l), (path), __FILE__, __LINE__)

static void unload(loaded *l)
{
    pf_anim_free(&l->anim);
    pf_scene_free(&l->scene);
}

static void pose_(loaded *l, int32_t clip, double t, pf_anim_moved *moved, const char *file, int line)
{
    pf_error e = {0};
    if (pf_anim_pose(&l->scene, moved, NULL, &l->anim, clip, t, &e) != PF_OK) {
        fprintf(stderr, "%s:%d: pose clip %d at %g: %s\n", file, line, clip, t, e.message);
        _fail(file, line);
    }
}
#define pose(l, clip, t) pose_((l), (clip), (t), NULL, __FILE__, __LINE__)

static int near3(pf_vec3 a, pf_vec3 b, float eps)
{
    return fabsf(a.x - b.x) <= eps && fabsf(a.y - b.y) <= eps && fabsf(a.z - b.z) <= eps;
}

#define assert_vec3_near(v, X, Y, Z)                                                                                \
    do {                                                                                                            \
        pf_vec3 v_ = (v);                                                                                           \
        if (!near3(v_, pf_v3((float)(X), (float)(Y), (float)(Z)), EPS))                                             \
            fail_msg("%s = (%.9g, %.9g, %.9g), expected (%.9g, %.9g, %.9g)", #v, (double)v_.x, (double)v_.y,        \
                     (double)v_.z, (double)(X), (double)(Y), (double)(Z));                                          \
    } while (0)

/* Instanced primitive i's scene vertex k (its k-th vertex in the scene). */
static pf_vec3 vpos(const loaded *l, uint32_t prim, uint32_t k)
{
    assert_true(prim < l->anim.prim_count);
    assert_true(k < l->anim.prims[prim].vertex_count);
    return l->scene.positions[l->anim.prims[prim].vertex_first + k];
}
static pf_vec3 vnrm(const loaded *l, uint32_t prim, uint32_t k)
{
    return l->scene.normals[l->anim.prims[prim].vertex_first + k];
}

/* The position of file vertex `local` of a welded primitive. */
#define P(l, prim, local) vpos((l), (prim), (local))

/* A byte snapshot of the scene's geometry. */
typedef struct snapshot {
    uint32_t vertex_count, tri_count;
    pf_vec3 *pos, *nrm;
    uint32_t *idx;
    pf_vec3 lo, hi;
} snapshot;

static void snap(snapshot *s, const pf_scene *sc)
{
    s->vertex_count = sc->vertex_count;
    s->tri_count = sc->tri_count;
    s->pos = malloc(sizeof(pf_vec3) * sc->vertex_count);
    s->nrm = malloc(sizeof(pf_vec3) * sc->vertex_count);
    s->idx = malloc(sizeof(uint32_t) * 3 * sc->tri_count);
    assert_non_null(s->pos);
    assert_non_null(s->nrm);
    assert_non_null(s->idx);
    memcpy(s->pos, sc->positions, sizeof(pf_vec3) * sc->vertex_count);
    memcpy(s->nrm, sc->normals, sizeof(pf_vec3) * sc->vertex_count);
    memcpy(s->idx, sc->indices, sizeof(uint32_t) * 3 * sc->tri_count);
    s->lo = sc->bounds_min;
    s->hi = sc->bounds_max;
}

static int snap_equal(const snapshot *s, const pf_scene *sc)
{
    return s->vertex_count == sc->vertex_count && s->tri_count == sc->tri_count &&
           !memcmp(s->pos, sc->positions, sizeof(pf_vec3) * sc->vertex_count) &&
           !memcmp(s->nrm, sc->normals, sizeof(pf_vec3) * sc->vertex_count) &&
           !memcmp(s->idx, sc->indices, sizeof(uint32_t) * 3 * sc->tri_count) &&
           !memcmp(&s->lo, &sc->bounds_min, sizeof s->lo) && !memcmp(&s->hi, &sc->bounds_max, sizeof s->hi);
}

static void unsnap(snapshot *s)
{
    free(s->pos);
    free(s->nrm);
    free(s->idx);
}

static int32_t find(const loaded *l, const char *name)
{
    int32_t clip = -99;
    pf_error e;
    assert_int_equal(pf_anim_find(&l->anim, name, 0, &clip, &e), PF_OK);
    return clip;
}

/* ------------------------------------------------------------------ static files */

/* A file without animations keeps nothing and loads exactly as before. */
static void test_static_file(void **state)
{
    (void)state;
    loaded l;
    load(&l, SOFTGI_TEST_DATA "/gltf/hierarchy_trs.gltf");
    assert_int_equal(l.anim.clip_count, 0);
    assert_int_equal(l.anim.prim_count, 0);
    assert_null(l.anim.nodes);
    pf_scene plain;
    pf_error e;
    assert_int_equal(pf_gltf_load(&plain, SOFTGI_TEST_DATA "/gltf/hierarchy_trs.gltf", NULL, &e), PF_OK);
    snapshot s;
    snap(&s, &plain);
    assert_true(snap_equal(&s, &l.scene));
    assert_int_equal(plain.memory_bytes, l.scene.memory_bytes);
    /* posing such a scene is a no-op with a clear message for a clip */
    int32_t clip;
    assert_int_equal(pf_anim_find(&l.anim, "walk", 0, &clip, &e), PF_ERR_ARGUMENT);
    assert_non_null(strstr(e.message, "no animations"));
    pose(&l, PF_ANIM_ALL, 1.0);
    assert_true(snap_equal(&s, &l.scene));
    unsnap(&s);
    pf_scene_free(&plain);
    unload(&l);
}

/* ------------------------------------------------------------------ sampling */

static void test_linear(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_linear.gltf"));
    assert_int_equal(l.anim.clip_count, 4);
    assert_string_equal(l.anim.clips[1].name, "spin");
    assert_int_equal(l.anim.prim_count, 2);
    assert_int_equal(l.anim.dynamic_count, 2);
    assert_true(fabs(pf_anim_end(&l.anim, PF_ANIM_ALL) - 3.0) == 0.0);
    assert_true(fabs(pf_anim_end(&l.anim, 0) - 2.0) == 0.0);
    /* the static pose: TRI */
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);
    assert_vec3_near(P(&l, 1, 2), 0, 1, 5);

    /* "slide" (clip 0): translation LINEAR (0,0,0) (2,0,0) (2,4,0) at t = 0, 1, 2 */
    const int32_t slide = find(&l, "slide");
    assert_int_equal(slide, 0); /* the first of the two named "slide" */
    pose(&l, slide, 0.5);
    assert_vec3_near(P(&l, 0, 0), 1, 0, 0);
    assert_vec3_near(P(&l, 0, 1), 2, 0, 0);
    pose(&l, slide, 1.5);
    assert_vec3_near(P(&l, 0, 2), 2, 3, 0);
    pose(&l, slide, 1.0); /* exactly at a key */
    assert_vec3_near(P(&l, 0, 0), 2, 0, 0);
    /* clamped: after the last key the last value, at 0 the first */
    pose(&l, slide, 100.0);
    assert_vec3_near(P(&l, 0, 0), 2, 4, 0);
    pose(&l, slide, 0.0);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);

    /* "spin" (clip 1): t = 1, 3, identity -> 90 degrees about +Z written as
     * (0,0,-S,-S): the shortest path is +45 degrees at t = 2 */
    const int32_t spin = find(&l, "spin");
    pose(&l, spin, 2.0);
    assert_vec3_near(P(&l, 0, 1), R2, R2, 0);
    assert_vec3_near(vnrm(&l, 0, 1), 0, 0, 1);
    pose(&l, spin, 0.5); /* before the first key: identity */
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);
    pose(&l, spin, 10.0); /* after the last: 90 degrees */
    assert_vec3_near(P(&l, 0, 1), 0, 1, 0);
    assert_vec3_near(P(&l, 0, 2), -1, 0, 0);
    pose(&l, spin, 1.5); /* 22.5 degrees */
    assert_vec3_near(P(&l, 0, 1), cos(M_PI / 8), sin(M_PI / 8), 0);

    /* "grow" (clip 2): scale STEP 1 until t = 1, then 2 */
    const int32_t grow = find(&l, "grow");
    pose(&l, grow, 0.999);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);
    pose(&l, grow, 1.0);
    assert_vec3_near(P(&l, 0, 1), 2, 0, 0);

    /* all together at t = 2: T (2,4,0), R 45 degrees, S 2: (1,0,0) -> (2 + sqrt2, 4 + sqrt2, 0);
     * node 1 by clip 3 at (0,8,0) */
    pose(&l, PF_ANIM_ALL, 2.0);
    assert_vec3_near(P(&l, 0, 0), 2, 4, 0);
    assert_vec3_near(P(&l, 0, 1), 2 + 2 * R2, 4 + 2 * R2, 0);
    assert_vec3_near(P(&l, 0, 2), 2 - 2 * R2, 4 + 2 * R2, 0);
    assert_vec3_near(P(&l, 1, 0), 0, 8, 5);
    assert_vec3_near(vnrm(&l, 0, 0), 0, 0, 1);
    unload(&l);
}

static void test_cubic(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_cubic.gltf"));
    /* t = 1: translation (2.25,0,0), rotation 45 degrees about +Z */
    pose(&l, 0, 1.0);
    assert_vec3_near(P(&l, 0, 0), 2.25, 0, 0);
    assert_vec3_near(P(&l, 0, 1), 2.25 + R2, R2, 0);
    /* t = 0.5 (s = 1/4): x = 1.09375; rotation h00 id + h01 q90 normalised,
     * h00 = 27/32, h01 = 5/32 */
    pose(&l, 0, 0.5);
    assert_vec3_near(P(&l, 0, 0), 1.09375, 0, 0);
    const double z = 5.0 / 32 * R2, w = 27.0 / 32 + 5.0 / 32 * R2, len = sqrt(z * z + w * w);
    const double a = 2 * atan2(z / len, w / len);
    assert_vec3_near(P(&l, 0, 1), 1.09375 + cos(a), sin(a), 0);
    /* the ends: the values, not the tangents */
    pose(&l, 0, 0.0);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);
    pose(&l, 0, 7.0);
    assert_vec3_near(P(&l, 0, 0), 4, 0, 0);
    assert_vec3_near(P(&l, 0, 1), 4, 1, 0);
    unload(&l);
}

/* ------------------------------------------------------------------ skins and morphs */

/* The strip's vertex (x, y) is file vertex 2y + x (welded: scene order). */
static void test_skin(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_skin.gltf"));
    assert_int_equal(l.anim.prim_count, 1);
    assert_int_equal(l.anim.prims[0].skin, 0);
    assert_int_equal(l.anim.prims[0].joint_sets, 2);
    assert_true(l.anim.prims[0].dynamic);
    /* the static pose: the strip, without its node's T(100,0,0) */
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 2; x++) assert_vec3_near(P(&l, 0, (uint32_t)(2 * y + x)), x, y, 0);
    /* t = 1: the elbow at 90 degrees */
    pose(&l, 0, 1.0);
    assert_vec3_near(P(&l, 0, 0), 0, 0, 0);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);
    assert_vec3_near(P(&l, 0, 2), 0, 1, 0);
    assert_vec3_near(P(&l, 0, 3), 0.5, 1.5, 0);
    assert_vec3_near(P(&l, 0, 4), -1, 1, 0);
    assert_vec3_near(P(&l, 0, 5), -1, 2, 0);
    for (uint32_t k = 0; k < 6; k++) assert_vec3_near(vnrm(&l, 0, k), 0, 0, 1);
    /* t = 0.5: 45 degrees: (x, 2) -> (x c - s, 1 + x s + c); (x, 1) -> mean of (x, 1) and (x c, 1 + x s) */
    pose(&l, 0, 0.5);
    const double c = R2, s = R2;
    assert_vec3_near(P(&l, 0, 4), -s, 1 + c, 0);
    assert_vec3_near(P(&l, 0, 5), c - s, 1 + s + c, 0);
    assert_vec3_near(P(&l, 0, 3), 0.5 * (1 + c), 0.5 * (1 + 1 + s), 0);
    unload(&l);
}

static void test_morph(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_morph.gltf"));
    assert_int_equal(l.anim.prim_count, 2);
    assert_true(l.anim.prims[0].dynamic);
    assert_false(l.anim.prims[1].dynamic); /* node weights, never animated */
    /* static: mesh weights [0.5, 0] on node 0, node weights [0, 1] on node 1 */
    assert_vec3_near(P(&l, 0, 0), 0, 0, 0.5);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0.5);
    assert_vec3_near(P(&l, 1, 1), 2, 0, 5);
    assert_vec3_near(vnrm(&l, 1, 1), R2, 0, R2);
    assert_vec3_near(vnrm(&l, 1, 0), 0, 0, 1);
    /* "blend" at 0.5: weights (0.5, 0.5) */
    pf_anim_moved moved[2];
    uint32_t count = 99;
    pf_error e;
    assert_int_equal(pf_anim_pose(&l.scene, moved, &count, &l.anim, find(&l, "blend"), 0.5, &e), PF_OK);
    assert_int_equal(count, 1);
    assert_true(moved[0].moved);
    assert_false(moved[1].moved);
    assert_vec3_near(P(&l, 0, 0), 0, 0, 0.5);
    assert_vec3_near(P(&l, 0, 1), 1.5, 0, 0.5);
    assert_vec3_near(P(&l, 0, 2), 0, 1, 0.5);
    assert_vec3_near(vnrm(&l, 0, 1), 1 / sqrt(5.0), 0, 2 / sqrt(5.0));
    assert_vec3_near(vnrm(&l, 0, 2), 0, 0, 1);
    assert_vec3_near(P(&l, 1, 1), 2, 0, 5); /* node 1 untouched */
    /* "snap": STEP [0,0] until t = 1, then [1,0] */
    const int32_t snapc = find(&l, "snap");
    pose(&l, snapc, 0.999);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 0);
    pose(&l, snapc, 1.0);
    assert_vec3_near(P(&l, 0, 1), 1, 0, 1);
    unload(&l);
}

static void test_hierarchy(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_hierarchy.gltf"));
    assert_int_equal(l.anim.prim_count, 3);
    assert_true(l.anim.prims[0].dynamic);
    assert_true(l.anim.prims[1].dynamic);
    assert_true(l.anim.prims[1].flat);
    assert_false(l.anim.prims[2].dynamic);
    pf_anim_moved moved[3];
    uint32_t count = 0;
    pf_error e;
    assert_int_equal(pf_anim_pose(&l.scene, moved, &count, &l.anim, 0, 1.0, &e), PF_OK);
    assert_int_equal(count, 2);
    /* t = 1: R90 T(2,0,0): TRI -> (0,2,0) (0,3,0) (-1,2,0) */
    assert_vec3_near(P(&l, 0, 0), 0, 2, 0);
    assert_vec3_near(P(&l, 0, 1), 0, 3, 0);
    assert_vec3_near(P(&l, 0, 2), -1, 2, 0);
    /* the flat copy at z = 1: three corners, face normal +Z from the posed corners */
    assert_int_equal(l.anim.prims[1].vertex_count, 3);
    assert_vec3_near(vpos(&l, 1, 0), 0, 2, 1);
    assert_vec3_near(vpos(&l, 1, 1), 0, 3, 1);
    assert_vec3_near(vpos(&l, 1, 2), -1, 2, 1);
    for (uint32_t k = 0; k < 3; k++) assert_vec3_near(vnrm(&l, 1, k), 0, 0, 1);
    /* the report: the bounds before (static: hand at (1,0,0)) and after */
    assert_true(moved[0].moved && moved[1].moved && !moved[2].moved);
    assert_vec3_near(moved[0].before_min, 1, 0, 0);
    assert_vec3_near(moved[0].before_max, 2, 1, 0);
    assert_vec3_near(moved[0].after_min, -1, 2, 0);
    assert_vec3_near(moved[0].after_max, 0, 3, 0);
    assert_vec3_near(moved[2].before_min, 0, 0, -1);
    assert_vec3_near(moved[2].after_max, 1, 1, -1);
    assert_int_equal(moved[1].tri_first, l.anim.prims[1].tri_first);
    assert_int_equal(moved[1].tri_count, 1);
    /* the scene's bounds follow */
    assert_vec3_near(l.scene.bounds_min, -1, 0, -1);
    assert_vec3_near(l.scene.bounds_max, 1, 3, 1);
    /* t = 0.5: 45 degrees, the hand at 1.5 */
    pose(&l, 0, 0.5);
    assert_vec3_near(P(&l, 0, 0), 1.5 * R2, 1.5 * R2, 0);
    /* the same pose again moves nothing */
    assert_int_equal(pf_anim_pose(&l.scene, moved, &count, &l.anim, 0, 0.5, &e), PF_OK);
    assert_int_equal(count, 0);
    assert_true(!memcmp(&moved[0].before_min, &moved[0].after_min, sizeof(pf_vec3)));
    unload(&l);
}

/* ------------------------------------------------------------------ the pose contract */

static const char *const k_good[] = {"anim_linear.gltf", "anim_cubic.gltf", "anim_skin.gltf", "anim_morph.gltf",
                                     "anim_hierarchy.gltf"};

/* Counts and triangle order never change; the same t gives the same bytes
 * whatever was posed before; the static pose gives back the loaded bytes. */
static void test_determinism(void **state)
{
    (void)state;
    for (size_t f = 0; f < sizeof k_good / sizeof k_good[0]; f++) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", ANIM_DIR, k_good[f]);
        loaded l, m;
        load(&l, path);
        load(&m, path);
        snapshot loaded_bytes, at;
        snap(&loaded_bytes, &l.scene);
        const double t = 0.3; /* within every file's keys */
        pose(&l, PF_ANIM_ALL, t);
        snap(&at, &l.scene);
        assert_int_equal(at.vertex_count, loaded_bytes.vertex_count);
        assert_int_equal(at.tri_count, loaded_bytes.tri_count);
        assert_true(!memcmp(at.idx, loaded_bytes.idx, sizeof(uint32_t) * 3 * at.tri_count));
        pose(&l, PF_ANIM_ALL, 1.7);
        pose(&l, PF_ANIM_ALL, 0.05);
        pose(&l, PF_ANIM_ALL, t);
        assert_true(snap_equal(&at, &l.scene));
        pose(&m, PF_ANIM_ALL, t); /* another load, posed once */
        assert_true(snap_equal(&at, &m.scene));
        pose(&l, PF_ANIM_STATIC, 0.0);
        if (!snap_equal(&loaded_bytes, &l.scene)) fail_msg("%s: the static pose differs from the load", k_good[f]);
        pf_error e;
        assert_int_equal(pf_scene_validate(&l.scene, &e), PF_OK); /* the bounds validate computes */
        assert_true(snap_equal(&loaded_bytes, &l.scene));
        unsnap(&at);
        unsnap(&loaded_bytes);
        unload(&m);
        unload(&l);
    }
}

/* A pose beyond PF_SCENE_MAX_COORD is refused and the scene stays as it was. */
static void test_failed_pose(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_far.gltf"));
    pose(&l, 0, 1e-25); /* 1e5 units: fine */
    snapshot before;
    snap(&before, &l.scene);
    pf_error e = {0};
    assert_int_equal(pf_anim_pose(&l.scene, NULL, NULL, &l.anim, 0, 1.0, &e), PF_ERR_NONFINITE);
    assert_non_null(strstr(e.message, "animation 0 'away'"));
    assert_non_null(strstr(e.message, "mesh 0 primitive 0"));
    assert_non_null(strstr(e.message, "beyond"));
    assert_true(snap_equal(&before, &l.scene));
    assert_int_equal(l.anim.pose_clip, 0);
    assert_true(l.anim.pose_time == 1e-25);
    /* bad arguments: the time, the clip */
    const double bad_t[] = {NAN, -1.0, INFINITY, 2e6};
    for (size_t i = 0; i < sizeof bad_t / sizeof bad_t[0]; i++) {
        assert_int_equal(pf_anim_pose(&l.scene, NULL, NULL, &l.anim, 0, bad_t[i], &e), PF_ERR_ARGUMENT);
        assert_non_null(strstr(e.message, "time"));
    }
    assert_int_equal(pf_anim_pose(&l.scene, NULL, NULL, &l.anim, 1, 0.5, &e), PF_ERR_ARGUMENT);
    assert_int_equal(pf_anim_pose(&l.scene, NULL, NULL, &l.anim, -7, 0.5, &e), PF_ERR_ARGUMENT);
    assert_true(snap_equal(&before, &l.scene));
    unsnap(&before);
    unload(&l);
}

static void test_find(void **state)
{
    (void)state;
    loaded l;
    load(&l, DATA("anim_linear.gltf"));
    int32_t clip = -5;
    pf_error e;
    assert_int_equal(pf_anim_find(&l.anim, NULL, 3, &clip, &e), PF_OK);
    assert_int_equal(clip, 3);
    assert_int_equal(pf_anim_find(&l.anim, "grow", 0, &clip, &e), PF_OK);
    assert_int_equal(clip, 2);
    assert_int_equal(pf_anim_find(&l.anim, "walk", 0, &clip, &e), PF_ERR_ARGUMENT);
    assert_non_null(strstr(e.message, "'walk'"));
    assert_non_null(strstr(e.message, "1 'spin'")); /* the file's animations listed */
    assert_int_equal(pf_anim_find(&l.anim, NULL, 4, &clip, &e), PF_ERR_ARGUMENT);
    assert_int_equal(pf_anim_find(&l.anim, NULL, -1, &clip, &e), PF_ERR_ARGUMENT);
    unload(&l);
}

/* ------------------------------------------------------------------ hostile files */

typedef struct bad_case {
    const char *file;
    pf_result code;
    const char *what; /* in the message */
} bad_case;

static const bad_case k_bad[] = {
    {"bad_anim_node_index.gltf", PF_ERR_INDEX_RANGE, "animation 0 channel 0 targets node 9"},
    {"bad_anim_sampler_index.gltf", PF_ERR_INDEX_RANGE, "uses sampler 5"},
    {"bad_anim_accessor_index.gltf", PF_ERR_INDEX_RANGE, "accessor 99"},
    {"bad_anim_times_order.gltf", PF_ERR_PARSE, "increase strictly"},
    {"bad_anim_interp.gltf", PF_ERR_PARSE, "SMOOTH"},
    {"bad_anim_path.gltf", PF_ERR_PARSE, "colour"},
    {"bad_anim_twice.gltf", PF_ERR_PARSE, "animated twice"},
    {"bad_anim_matrix.gltf", PF_ERR_PARSE, "has a matrix"},
    {"bad_anim_times_nan.gltf", PF_ERR_NONFINITE, "input time 1"},
    {"bad_anim_times_negative.gltf", PF_ERR_NONFINITE, "input time 0 is -1"},
    {"bad_anim_times_huge.gltf", PF_ERR_NONFINITE, "input time 2"},
    {"bad_anim_key_nan.gltf", PF_ERR_NONFINITE, "output value 3"},
    {"bad_anim_key_inf.gltf", PF_ERR_NONFINITE, "output value 2"},
    {"bad_anim_rot_zero.gltf", PF_ERR_NONFINITE, "zero quaternion"},
    {"bad_anim_count.gltf", PF_ERR_ACCESSOR, "3 keys need 9"},
    {"bad_anim_cubic_count.gltf", PF_ERR_ACCESSOR, "in-tangent, value and out-tangent"},
    {"bad_anim_type.gltf", PF_ERR_ACCESSOR, "3 components"},
    {"bad_anim_huge_keys.gltf", PF_ERR_ACCESSOR, "no bufferView"},
    {"bad_anim_limit_keys.gltf", PF_ERR_ACCESSOR, "softgi's limit"},
    {"bad_skin_joint_range.gltf", PF_ERR_INDEX_RANGE, "names joint 5, but skin 0 has 2 joints"},
    {"bad_skin_node_index.gltf", PF_ERR_INDEX_RANGE, "joint 1 is node 42"},
    {"bad_skin_index.gltf", PF_ERR_INDEX_RANGE, "uses skin 3"},
    {"bad_skin_ibm_index.gltf", PF_ERR_INDEX_RANGE, "accessor 77"},
    {"bad_skin_no_joints.gltf", PF_ERR_ACCESSOR, "no JOINTS_0"},
    {"bad_skin_no_weights.gltf", PF_ERR_ACCESSOR, "JOINTS_1 without WEIGHTS_1"},
    {"bad_skin_ibm_count.gltf", PF_ERR_ACCESSOR, "1 matrices for 2 joints"},
    {"bad_skin_joints_normalized.gltf", PF_ERR_ACCESSOR, "JOINTS_0"},
    {"bad_skin_ibm_nan.gltf", PF_ERR_NONFINITE, "inverse bind matrix 0"},
    {"bad_skin_weight_nan.gltf", PF_ERR_NONFINITE, "WEIGHTS_1 of vertex 0"},
    {"bad_skin_joint_outside.gltf", PF_ERR_PARSE, "not in the scene"},
    {"bad_skin_empty.gltf", PF_ERR_PARSE, "no joints"},
    {"bad_morph_node_weights.gltf", PF_ERR_PARSE, "node 1: weights has 3 numbers"},
    {"bad_morph_mesh_weights.gltf", PF_ERR_PARSE, "mesh 0: weights has 1 numbers"},
    {"bad_morph_mismatch.gltf", PF_ERR_PARSE, "primitive 1 has 1 morph targets"},
    {"bad_morph_no_targets.gltf", PF_ERR_PARSE, "no morph targets"},
    {"bad_morph_channel_count.gltf", PF_ERR_ACCESSOR, "2 weights each"},
    {"bad_morph_delta_nan.gltf", PF_ERR_NONFINITE, "target 0 POSITION 0"},
    {"bad_morph_weight_nan.gltf", PF_ERR_NONFINITE, "output value 2"},
    {"bad_morph_accessor.gltf", PF_ERR_INDEX_RANGE, "accessor 55"},
};

static void test_bad_files(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof k_bad / sizeof k_bad[0]; i++) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", ANIM_DIR, k_bad[i].file);
        pf_scene s;
        pf_anim a;
        memset(&a, 0x5a, sizeof a); /* the loader zeroes it first */
        pf_gltf_options o = {.anim = &a};
        pf_error e = {0};
        pf_result r = pf_gltf_load(&s, path, &o, &e);
        if (r != k_bad[i].code || !strstr(e.message, k_bad[i].what) || !strstr(e.message, k_bad[i].file))
            fail_msg("%s: got %d '%s', expected %d with '%s'", k_bad[i].file, (int)r, e.message, (int)k_bad[i].code,
                     k_bad[i].what);
        assert_int_equal(s.tri_count, 0);
        assert_null(s.positions);
        assert_int_equal(a.clip_count, 0);
        assert_null(a.nodes);
        assert_null(a.prims);
        /* one line */
        assert_null(strchr(e.message, '\n'));
        /* the plain loader refuses it too (animations are checked without pf_gltf_options.anim) */
        assert_int_equal(pf_gltf_load(&s, path, NULL, &e), k_bad[i].code);
        pf_anim_free(&a);
    }
}

/* Huge key counts are taken from the memory budget before anything is read. */
static void test_key_budget(void **state)
{
    (void)state;
    pf_scene s;
    pf_anim a;
    pf_gltf_options o = {.anim = &a, .max_memory = 64ull << 20};
    pf_error e = {0};
    assert_int_equal(pf_gltf_load(&s, DATA("bad_anim_huge_keys.gltf"), &o, &e), PF_ERR_OUT_OF_MEMORY);
    assert_non_null(strstr(e.message, "animation 0 sampler 0"));
    assert_non_null(strstr(e.message, "67108864 keys"));
    assert_int_equal(a.clip_count, 0);
}

/* scenes/anim-box (tools/make_anim_scene.py): three animations, the box, the
 * skinned column and the morphed dome dynamic, the room static; every
 * frame time of its sequence poses within range, the box's rotation
 * reaching 180 degrees at t = 4. */
static void test_anim_box_scene(void **state)
{
    (void)state;
    loaded l;
    load(&l, SOFTGI_SOURCE_DIR "/scenes/anim-box/anim-box.gltf");
    assert_int_equal(l.anim.clip_count, 3);
    assert_string_equal(l.anim.clips[0].name, "move");
    assert_string_equal(l.anim.clips[1].name, "sway");
    assert_string_equal(l.anim.clips[2].name, "breathe");
    assert_int_equal(l.anim.prim_count, 8);
    assert_int_equal(l.anim.dynamic_count, 3);
    assert_true(l.scene.tri_count < 4000);
    assert_true(pf_anim_end(&l.anim, PF_ANIM_ALL) == 4.0);
    for (int f = 0; f < 48; f++) pose(&l, PF_ANIM_ALL, 4.0 * f / 47.0);
    /* t = 2: the box at x = 3, turned 90 degrees; the dome's top 0.35 m up; the column straight */
    pf_anim_moved moved[8];
    pose_(&l, PF_ANIM_ALL, 2.0, moved, __FILE__, __LINE__);
    assert_vec3_near(moved[5].after_min, 2.7, 0.0, 1.9);
    assert_vec3_near(moved[5].after_max, 3.3, 0.6, 2.5);
    assert_true(fabsf(moved[7].after_max.y - 0.35f) < 1e-5f);
    assert_true(fabsf(moved[6].after_max.y - 2.0f) < 1e-5f);
    unload(&l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_static_file), cmocka_unit_test(test_linear),      cmocka_unit_test(test_cubic),
        cmocka_unit_test(test_skin),        cmocka_unit_test(test_morph),       cmocka_unit_test(test_hierarchy),
        cmocka_unit_test(test_determinism), cmocka_unit_test(test_failed_pose), cmocka_unit_test(test_find),
        cmocka_unit_test(test_bad_files),   cmocka_unit_test(test_key_budget),  cmocka_unit_test(test_anim_box_scene),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
