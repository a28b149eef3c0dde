/* test_rt_update: Embree's scene kept up to date for moved geometry
 * (pf_rt_create_dynamic, pf_rt_update; pf_rt.h "Moving geometry").
 *
 * - REBUILD: scenes/anim-box posed at several times (and back, and twice at
 *   the same time) and updated gives, for a fixed set of 20480 rays (camera
 *   rays, random rays in the room, rays aimed at the animated primitives'
 *   vertices and edge midpoints, where BVHs can differ), the
 *   closest hits and the occlusion of a fresh pf_rt_create_dynamic of the
 *   posed scene bit for bit, with 2 build threads updating and 1 building
 *   afresh;
 * - REFIT: the same closest hits and occlusion except for rays that meet
 *   triangles only at their edges or vertices (checked against every
 *   triangle in double precision) or two triangles at the same distance,
 *   which are counted; a REBUILD afterwards (even with nothing moved)
 *   gives the fresh bytes again;
 * - static scenes: no animation, an empty one, or a file without animations
 *   build the one geometry (pf_rt_dynamic_count 0) with pf_rt_create's
 *   bytes; a pf_rt of one geometry updated for a pose equals a fresh
 *   pf_rt_create of it; the split differs from one geometry only in the
 *   same edge cases as REFIT;
 * - the split maps Embree's ids back to the scene's triangles, for
 *   alpha-masked dynamic primitives too, and for a scene that is all
 *   dynamic;
 * - bad input: moved ranges outside the scene (overflowing too), a static
 *   or partial range moved, a NULL report, a bad mode, and animation data
 *   whose ranges lie outside the scene, overlap or share vertices with
 *   static triangles: errors with a message, the pf_rt unchanged. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "pf_anim.h"
#include "pf_gltf.h"
#include "pf_rt.h"
#include "test_util.h"

#define ANIM_BOX SOFTGI_SOURCE_DIR "/scenes/anim-box/anim-box.gltf"
#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

enum { CAM_W = 128, CAM_H = 96, N_RANDOM = 4096, N_AIMED = 4096, N_RAYS = CAM_W * CAM_H + N_RANDOM + N_AIMED };

typedef struct world {
    pf_scene scene;
    pf_anim anim;
    pf_anim_moved *moved; /* anim.prim_count */
    uint32_t moved_count;
} world;

static void world_load(world *w, const char *path)
{
    memset(w, 0, sizeof *w);
    pf_gltf_options o = {.anim = &w->anim};
    pf_error e;
    if (pf_gltf_load(&w->scene, path, &o, &e) != PF_OK) fail_msg("%s: %s", path, e.message);
    assert_int_equal(pf_scene_validate(&w->scene, &e), PF_OK);
    w->moved = calloc(w->anim.prim_count ? w->anim.prim_count : 1, sizeof *w->moved);
    assert_non_null(w->moved);
}

static void world_free(world *w)
{
    free(w->moved);
    pf_anim_free(&w->anim);
    pf_scene_free(&w->scene);
}

static void world_pose(world *w, double t)
{
    pf_error e;
    if (pf_anim_pose(&w->scene, w->moved, &w->moved_count, &w->anim, PF_ANIM_ALL, t, &e) != PF_OK)
        fail_msg("pose at %g: %s", t, e.message);
}

static uint32_t rng_u32(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (uint32_t)(*s >> 32);
}
static float rng_unit(uint64_t *s) { return (float)(rng_u32(s) >> 8) * (1.0f / 16777216.0f); }

/* The fixed rays (made on the scene as it is now): camera rays over the
 * scene's bounds, random rays from inside the bounds, and rays from inside
 * aimed at the dynamic primitives' vertices and edge midpoints (half of
 * them with tfar just short of the target: occlusion decided near it). */
static void make_rays(const world *w, pf_ray *rays)
{
    const pf_scene *s = &w->scene;
    pf_vec3 lo = s->bounds_min, ext = pf_v3_sub(s->bounds_max, s->bounds_min);
    pf_vec3 c = pf_v3_add(lo, pf_v3_scale(ext, 0.5f));
    pf_camera cam;
    pf_error e;
    if (s->camera_count) cam = s->cameras[0];
    else
        assert_int_equal(
            pf_camera_look_at(&cam, pf_v3_add(c, pf_v3(0.3f * ext.x, 0.1f * ext.y, 0.45f * ext.z)), c, 1.2f, &e),
            PF_OK);
    uint32_t k = 0;
    for (uint32_t y = 0; y < CAM_H; y++)
        for (uint32_t x = 0; x < CAM_W; x++) rays[k++] = gi_camera_ray(&cam, CAM_W, CAM_H, x, y);
    uint64_t st = 0x5eed;
    for (uint32_t i = 0; i < N_RANDOM + N_AIMED; i++) {
        pf_vec3 o = pf_v3(lo.x + ext.x * (0.05f + 0.9f * rng_unit(&st)), lo.y + ext.y * (0.05f + 0.9f * rng_unit(&st)),
                          lo.z + ext.z * (0.05f + 0.9f * rng_unit(&st)));
        pf_vec3 d;
        float tfar = INFINITY;
        if (i < N_RANDOM || !w->anim.dynamic_count) {
            float z = 2.0f * rng_unit(&st) - 1.0f, ph = 6.2831853f * rng_unit(&st), r = sqrtf(fmaxf(0.0f, 1 - z * z));
            d = pf_v3(r * cosf(ph), z, r * sinf(ph));
        } else {
            /* a dynamic primitive's triangle, a corner or an edge midpoint */
            uint32_t p;
            do p = rng_u32(&st) % w->anim.prim_count;
            while (!w->anim.prims[p].dynamic || !w->anim.prims[p].tri_count);
            const pf_anim_prim *ap = &w->anim.prims[p];
            uint32_t t = ap->tri_first + rng_u32(&st) % ap->tri_count, corner = rng_u32(&st) % 6;
            const uint32_t *tri = &s->indices[3 * (size_t)t];
            pf_vec3 a = s->positions[tri[corner % 3]], b = s->positions[tri[(corner + 1) % 3]];
            pf_vec3 target = corner < 3 ? a : pf_v3_scale(pf_v3_add(a, b), 0.5f);
            d = pf_v3_sub(target, o);
            if (i & 1) tfar = 0.999f; /* |d| units: just short of the target */
        }
        rays[k++] = (pf_ray){o, 0.0f, d, tfar};
    }
    assert_int_equal(k, N_RAYS);
}

/* Where the ray meets triangle `prim`, in double precision: *t, and *edge
 * the smallest barycentric (negative outside the triangle, about 0 on an
 * edge or at a vertex). 0 where the ray is parallel to it. */
static int meet(const pf_scene *s, uint32_t prim, const pf_ray *r, double *t, double *edge)
{
    const uint32_t *tri = &s->indices[3 * (size_t)prim];
    pf_vec3 A = s->positions[tri[0]], B = s->positions[tri[1]], C = s->positions[tri[2]];
    double e1[3] = {(double)B.x - A.x, (double)B.y - A.y, (double)B.z - A.z};
    double e2[3] = {(double)C.x - A.x, (double)C.y - A.y, (double)C.z - A.z};
    double d[3] = {r->dir.x, r->dir.y, r->dir.z};
    double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0.0) return 0;
    double tv[3] = {(double)r->org.x - A.x, (double)r->org.y - A.y, (double)r->org.z - A.z};
    double q[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]};
    double u = (tv[0] * p[0] + tv[1] * p[1] + tv[2] * p[2]) / det;
    double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
    *t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    *edge = fmin(fmin(u, v), 1.0 - u - v);
    return 1;
}

#define EDGE_TOL 1e-5 /* barycentric: "on an edge or vertex", beyond float rounding at these sizes */

/* Whether some triangle is hit inside, away from its edges, at t in
 * (lo, hi] (relative slack 1e-6): a hit no BVH may miss. */
static int interior_hit(const pf_scene *s, const pf_ray *r, double lo, double hi)
{
    for (uint32_t k = 0; k < s->tri_count; k++) {
        double t, edge;
        if (meet(s, k, r, &t, &edge) && edge > EDGE_TOL && t > lo * (1 + 1e-6) + 1e-9 && t <= hi * (1 - 1e-6))
            return 1;
    }
    return 0;
}

typedef struct results {
    pf_hit hits[N_RAYS];
    uint8_t occ[N_RAYS];
} results;

/* How many rays of `got` differ from `want`, failing unless every
 * difference is what two different BVHs may give (pf_rt.h): a ray that
 * meets triangles only at their edges or vertices up to the farther of the
 * two answers (within EDGE_TOL), there hitting one of them, another, or
 * passing between them; or a tie (two triangles hit at the same t). */
static uint32_t count_edge_cases(const results *got, const results *want, const pf_ray *rays, const pf_scene *s,
                                 const char *what, double t)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < N_RAYS; i++) {
        const pf_ray *r = &rays[i];
        const pf_hit *a = &got->hits[i], *b = &want->hits[i];
        int hits_differ = memcmp(a, b, sizeof *a) != 0;
        if (got->occ[i] != want->occ[i] && interior_hit(s, r, r->tnear, r->tfar))
            fail_msg("%s at t = %g: ray %u: occluded %d, fresh %d, with a triangle hit inside", what, t, i, got->occ[i],
                     want->occ[i]);
        if (hits_differ) {
            double ta = a->prim == PF_RT_MISS ? INFINITY : a->t, tb = b->prim == PF_RT_MISS ? INFINITY : b->t;
            int tie = isfinite(ta) && isfinite(tb) && fabs(ta - tb) <= 1e-6 * fmax(fabs(ta), 1.0);
            if (!tie && interior_hit(s, r, r->tnear, fmax(ta, tb)))
                fail_msg("%s at t = %g: ray %u: prim %u t %.9g, fresh prim %u t %.9g, with a triangle hit inside "
                         "before the farther",
                         what, t, i, a->prim, ta, b->prim, tb);
        }
        n += hits_differ || got->occ[i] != want->occ[i];
    }
    return n;
}

static void trace(const pf_rt *rt, const pf_ray *rays, results *out)
{
    pf_rt_intersect(rt, rays, out->hits, N_RAYS);
    pf_rt_occluded(rt, rays, out->occ, N_RAYS);
}

static void expect_same(const results *a, const results *b, const char *what, double t)
{
    for (uint32_t i = 0; i < N_RAYS; i++) {
        if (memcmp(&a->hits[i], &b->hits[i], sizeof a->hits[i]))
            fail_msg("%s at t = %g: ray %u: prim %u t %a, fresh prim %u t %a", what, t, i, a->hits[i].prim,
                     (double)a->hits[i].t, b->hits[i].prim, (double)b->hits[i].t);
        if (a->occ[i] != b->occ[i]) fail_msg("%s at t = %g: ray %u: occluded %d, fresh %d", what, t, i, a->occ[i], b->occ[i]);
    }
}

static pf_rt *fresh(const world *w, uint32_t threads)
{
    pf_rt *rt;
    pf_error e;
    if (pf_rt_create_dynamic(&rt, &w->scene, &w->anim, pf_isa_detect(), threads, &e) != PF_OK) fail_msg("%s", e.message);
    return rt;
}

static void update(pf_rt *rt, const world *w, pf_rt_update_mode mode)
{
    pf_error e;
    if (pf_rt_update(rt, w->moved, w->anim.prim_count, mode, &e) != PF_OK) fail_msg("pf_rt_update: %s", e.message);
}

/* Whether triangle t belongs to a dynamic primitive. */
static int is_dynamic(const world *w, uint32_t t)
{
    for (uint32_t p = 0; p < w->anim.prim_count; p++) {
        const pf_anim_prim *ap = &w->anim.prims[p];
        if (ap->dynamic && t >= ap->tri_first && t - ap->tri_first < ap->tri_count) return 1;
    }
    return 0;
}

static const double times[] = {0.5, 1.25, 2.0, 2.0, 3.3, 0.0, 4.5, 1.7};

/* ------------------------------------------------------------------ REBUILD */

static void test_rebuild_equals_fresh(void **state)
{
    (void)state;
    static world w;
    world_load(&w, ANIM_BOX);
    static pf_ray rays[N_RAYS];
    make_rays(&w, rays);
    pf_rt *rt = fresh(&w, 2);
    assert_int_equal(pf_rt_dynamic_count(rt), 3); /* the box, the column, the dome */
    static results got, want;
    for (size_t k = 0; k < sizeof times / sizeof times[0]; k++) {
        world_pose(&w, times[k]);
        if (k != 3) assert_true(w.moved_count > 0);
        else assert_int_equal(w.moved_count, 0); /* the same time again: nothing moved */
        update(rt, &w, PF_RT_REBUILD);
        pf_rt *f = fresh(&w, 1);
        trace(rt, rays, &got);
        trace(f, rays, &want);
        expect_same(&got, &want, "REBUILD", times[k]);
        uint32_t on_dynamic = 0, occluded = 0;
        for (uint32_t i = 0; i < N_RAYS; i++) {
            on_dynamic += got.hits[i].prim != PF_RT_MISS && is_dynamic(&w, got.hits[i].prim);
            occluded += got.occ[i];
        }
        assert_true(on_dynamic > N_RAYS / 20); /* the rays reach what moved */
        assert_true(occluded > N_RAYS / 4 && occluded < N_RAYS);
        pf_rt_destroy(f);
    }
    pf_rt_destroy(rt);
    world_free(&w);
}

/* ------------------------------------------------------------------ REFIT */

static void test_refit(void **state)
{
    (void)state;
    static world w;
    world_load(&w, ANIM_BOX);
    static pf_ray rays[N_RAYS];
    make_rays(&w, rays);
    pf_rt *rt = fresh(&w, 2);
    static results got, want;
    uint32_t edge_cases = 0, compared = 0;
    for (size_t k = 0; k < sizeof times / sizeof times[0]; k++) {
        world_pose(&w, times[k]);
        update(rt, &w, PF_RT_REFIT);
        pf_rt *f = fresh(&w, 1);
        trace(rt, rays, &got);
        trace(f, rays, &want);
        edge_cases += count_edge_cases(&got, &want, rays, &w.scene, "REFIT", times[k]); /* the documented exception */
        compared += N_RAYS;
        pf_rt_destroy(f);
    }
    print_message("REFIT: %u of %u rays differ from a fresh build, every one meeting triangles at their edges\n",
                  edge_cases, compared);
    assert_true(edge_cases > 0 && edge_cases <= compared / 100);
    /* at t = 4.5 a REFIT decides some edge cases otherwise (the dome's
     * patch lies flat on the floor); a REBUILD with nothing moved rebuilds
     * what was refitted: the fresh bytes */
    world_pose(&w, 4.5);
    update(rt, &w, PF_RT_REFIT);
    pf_rt *f = fresh(&w, 1);
    trace(rt, rays, &got);
    trace(f, rays, &want);
    assert_memory_not_equal(got.hits, want.hits, sizeof got.hits);
    for (uint32_t p = 0; p < w.anim.prim_count; p++) w.moved[p].moved = 0;
    update(rt, &w, PF_RT_REBUILD);
    trace(rt, rays, &got);
    expect_same(&got, &want, "REBUILD after REFIT", 4.5);
    /* and REFIT, REBUILD, REFIT again in turn */
    world_pose(&w, 2.6);
    update(rt, &w, PF_RT_REFIT);
    world_pose(&w, 3.0);
    update(rt, &w, PF_RT_REBUILD);
    pf_rt_destroy(f);
    f = fresh(&w, 1);
    trace(rt, rays, &got);
    trace(f, rays, &want);
    expect_same(&got, &want, "REBUILD after REFIT", 3.0);
    pf_rt_destroy(f);
    pf_rt_destroy(rt);
    world_free(&w);
}

/* ------------------------------------------------------------------ static scenes */

static void test_static_unchanged(void **state)
{
    (void)state;
    static world w;
    world_load(&w, CORNELL); /* a file without animations: anim empty */
    assert_int_equal(w.anim.prim_count, 0);
    static pf_ray rays[N_RAYS];
    make_rays(&w, rays);
    pf_rt *a, *b, *c;
    pf_error e;
    pf_anim none;
    memset(&none, 0, sizeof none);
    assert_int_equal(pf_rt_create(&a, &w.scene, pf_isa_detect(), 1, &e), PF_OK);
    assert_int_equal(pf_rt_create_dynamic(&b, &w.scene, NULL, pf_isa_detect(), 1, &e), PF_OK);
    assert_int_equal(pf_rt_create_dynamic(&c, &w.scene, &w.anim, pf_isa_detect(), 1, &e), PF_OK);
    assert_int_equal(pf_rt_dynamic_count(a), 0);
    assert_int_equal(pf_rt_dynamic_count(b), 0);
    assert_int_equal(pf_rt_dynamic_count(c), 0);
    static results ra, rb, rc;
    trace(a, rays, &ra);
    trace(b, rays, &rb);
    trace(c, rays, &rc);
    expect_same(&rb, &ra, "anim NULL", 0.0);
    expect_same(&rc, &ra, "no animations", 0.0);
    /* an empty report and one with nothing moved change nothing */
    assert_int_equal(pf_rt_update(a, NULL, 0, PF_RT_REBUILD, &e), PF_OK);
    pf_anim_moved still = {.tri_first = 0, .tri_count = w.scene.tri_count, .vertex_count = w.scene.vertex_count};
    assert_int_equal(pf_rt_update(a, &still, 1, PF_RT_REFIT, &e), PF_OK);
    trace(a, rays, &rb);
    expect_same(&rb, &ra, "nothing moved", 0.0);
    pf_rt_destroy(a);
    pf_rt_destroy(b);
    pf_rt_destroy(c);
    world_free(&w);
}

/* One geometry (pf_rt_create) on an animated scene: an update rebuilds it
 * (REBUILD = a fresh pf_rt_create of the pose; REFIT up to edge cases). */
static void test_single_geometry_update(void **state)
{
    (void)state;
    static world w;
    world_load(&w, ANIM_BOX);
    static pf_ray rays[N_RAYS];
    make_rays(&w, rays);
    pf_rt *rt, *f;
    pf_error e;
    assert_int_equal(pf_rt_create(&rt, &w.scene, pf_isa_detect(), 2, &e), PF_OK);
    static results got, want;
    for (size_t k = 0; k < 3; k++) {
        world_pose(&w, times[k]);
        update(rt, &w, PF_RT_REBUILD);
        assert_int_equal(pf_rt_create(&f, &w.scene, pf_isa_detect(), 1, &e), PF_OK);
        trace(rt, rays, &got);
        trace(f, rays, &want);
        expect_same(&got, &want, "one geometry, REBUILD", times[k]);
        pf_rt_destroy(f);
    }
    world_pose(&w, 3.3);
    update(rt, &w, PF_RT_REFIT);
    assert_int_equal(pf_rt_create(&f, &w.scene, pf_isa_detect(), 1, &e), PF_OK);
    trace(rt, rays, &got);
    trace(f, rays, &want);
    count_edge_cases(&got, &want, rays, &w.scene, "one geometry, REFIT", 3.3);
    pf_rt_destroy(f);
    /* the split and one geometry see the same surfaces, edge cases aside
     * (at t = 0 and 4 the dome lies flat on the floor: coplanar ties) */
    static results split;
    const double at[] = {0.0, 1.0, 3.3, 4.0};
    for (size_t k = 0; k < sizeof at / sizeof at[0]; k++) {
        world_pose(&w, at[k]);
        assert_int_equal(pf_rt_create(&f, &w.scene, pf_isa_detect(), 1, &e), PF_OK);
        trace(f, rays, &want);
        pf_rt_destroy(f);
        f = fresh(&w, 1);
        trace(f, rays, &split);
        uint32_t n = count_edge_cases(&split, &want, rays, &w.scene, "the split against one geometry", at[k]);
        print_message("t = %g: the split and one geometry differ in %u of %u rays, every one an edge case\n", at[k],
                      n, N_RAYS);
        pf_rt_destroy(f);
    }
    pf_rt_destroy(rt);
    world_free(&w);
}

/* ------------------------------------------------------------------ the split's ids */

/* Quads made dynamic by a hand-made anim: `dyn` flags per quad. */
static void fake_anim(pf_anim *a, const int *dyn, uint32_t quads)
{
    memset(a, 0, sizeof *a);
    a->prim_count = quads;
    a->prims = calloc(quads, sizeof *a->prims);
    assert_non_null(a->prims);
    for (uint32_t q = 0; q < quads; q++) {
        a->prims[q] = (pf_anim_prim){.vertex_first = 4 * q, .vertex_count = 4, .tri_first = 2 * q, .tri_count = 2,
                                     .dynamic = dyn[q]};
        a->dynamic_count += dyn[q] != 0;
    }
}

static void moved_quad(pf_anim_moved *m, uint32_t q)
{
    *m = (pf_anim_moved){.vertex_first = 4 * q, .vertex_count = 4, .tri_first = 2 * q, .tri_count = 2, .moved = 1};
}

/* Alpha-masked and opaque quads, some dynamic: hits name the scene's
 * triangles and materials through the split, before and after a move. */
static void test_split_ids_and_alpha(void **state)
{
    (void)state;
    tu_quad q[4] = {
        {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 0.2f}, PF_ALPHA_MASK, 0.5f}, /* a hole: dynamic */
        {{0, 0, -2}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 0.8f}, PF_ALPHA_MASK, 0.5f}, /* kept: static */
        {{0, 0, -3}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1.0f}, PF_ALPHA_OPAQUE, 0.5f}, /* dynamic */
        {{5, 0, -3}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1.0f}, PF_ALPHA_OPAQUE, 0.5f}, /* static */
    };
    const int dyn[4] = {1, 0, 1, 0};
    pf_scene s;
    tu_make_scene(&s, q, 4);
    pf_error e;
    assert_int_equal(pf_scene_validate(&s, &e), PF_OK);
    pf_anim a;
    fake_anim(&a, dyn, 4);
    pf_rt *rt;
    assert_int_equal(pf_rt_create_dynamic(&rt, &s, &a, PF_ISA_SSE2, 1, &e), PF_OK);
    assert_int_equal(pf_rt_dynamic_count(rt), 2);
    pf_ray r = {{0.1f, 0.2f, 0}, 0.0f, {0, 0, -1}, INFINITY};
    pf_hit h = pf_rt_intersect1(rt, r);
    assert_int_equal(s.tri_material[h.prim], 1); /* through the dynamic hole onto the static quad */
    assert_float_equal(h.t, 2.0f, 1e-6f);
    r.tfar = 1.5f;
    assert_int_equal(pf_rt_occluded1(rt, r), 0);
    pf_ray r5 = {{5.1f, 0.2f, 0}, 0.0f, {0, 0, -1}, INFINITY};
    h = pf_rt_intersect1(rt, r5);
    assert_int_equal(s.tri_material[h.prim], 3);
    assert_true(h.prim == 6 || h.prim == 7);
    /* the hole moves in front of quad 3 and the opaque dynamic quad 2 in
     * front of everything at x = 0: two moved entries */
    for (int k = 0; k < 4; k++) {
        s.positions[k].x += 5.0f;
        s.positions[8 + k].z = -0.5f;
    }
    pf_anim_moved m[4];
    for (uint32_t k = 0; k < 4; k++) {
        moved_quad(&m[k], k);
        m[k].moved = dyn[k];
    }
    assert_int_equal(pf_rt_update(rt, m, 4, PF_RT_REBUILD, &e), PF_OK);
    r.tfar = INFINITY;
    h = pf_rt_intersect1(rt, r);
    assert_int_equal(s.tri_material[h.prim], 2);
    assert_float_equal(h.t, 0.5f, 1e-6f);
    h = pf_rt_intersect1(rt, r5); /* through the moved hole onto quad 3 */
    assert_int_equal(s.tri_material[h.prim], 3);
    assert_float_equal(h.t, 3.0f, 1e-6f);
    r5.tfar = 2.5f;
    assert_int_equal(pf_rt_occluded1(rt, r5), 0);
    pf_rt_destroy(rt);
    pf_anim_free(&a);
    pf_scene_free(&s);
}

/* Every triangle dynamic: no static child. */
static void test_all_dynamic(void **state)
{
    (void)state;
    tu_quad q[2] = {
        {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 0, -2}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    const int dyn[2] = {1, 1};
    pf_scene s;
    tu_make_scene(&s, q, 2);
    pf_error e;
    assert_int_equal(pf_scene_validate(&s, &e), PF_OK);
    pf_anim a;
    fake_anim(&a, dyn, 2);
    pf_rt *rt;
    assert_int_equal(pf_rt_create_dynamic(&rt, &s, &a, pf_isa_detect(), 1, &e), PF_OK);
    pf_ray r = {{0.1f, 0.2f, 0}, 0.0f, {0, 0, -1}, INFINITY};
    assert_int_equal(s.tri_material[pf_rt_intersect1(rt, r).prim], 0);
    for (int k = 0; k < 4; k++) s.positions[k].y += 10.0f; /* quad 0 out of the way */
    pf_anim_moved m;
    moved_quad(&m, 0);
    assert_int_equal(pf_rt_update(rt, &m, 1, PF_RT_REFIT, &e), PF_OK);
    pf_hit h = pf_rt_intersect1(rt, r);
    assert_int_equal(s.tri_material[h.prim], 1);
    assert_float_equal(h.t, 2.0f, 1e-6f);
    pf_rt_destroy(rt);
    pf_anim_free(&a);
    pf_scene_free(&s);
}

/* ------------------------------------------------------------------ bad input */

static void expect_fail(pf_result got, pf_result want, const pf_error *e, const char *needle)
{
    assert_int_equal(got, want);
    if (!strstr(e->message, needle)) fail_msg("message '%s' lacks '%s'", e->message, needle);
}

static void test_bad_input(void **state)
{
    (void)state;
    static world w;
    world_load(&w, ANIM_BOX);
    static pf_ray rays[N_RAYS];
    make_rays(&w, rays);
    pf_rt *rt = fresh(&w, 1);
    static results before, after;
    trace(rt, rays, &before);
    const uint32_t T = w.scene.tri_count, V = w.scene.vertex_count;
    uint32_t dp = 0; /* a dynamic primitive */
    while (!w.anim.prims[dp].dynamic) dp++;
    const pf_anim_prim *ap = &w.anim.prims[dp];
    pf_anim_moved good = {.vertex_first = ap->vertex_first, .vertex_count = ap->vertex_count,
                          .tri_first = ap->tri_first, .tri_count = ap->tri_count, .moved = 1};
    pf_error e;
    pf_anim_moved m = good;
    m.tri_first = T;
    expect_fail(pf_rt_update(rt, &m, 1, PF_RT_REBUILD, &e), PF_ERR_INDEX_RANGE, &e, "outside the scene");
    m = good;
    m.tri_first = UINT32_MAX - 1; /* tri_first + tri_count overflows 32 bits */
    m.moved = 0;                  /* checked even when not moved */
    expect_fail(pf_rt_update(rt, &m, 1, PF_RT_REBUILD, &e), PF_ERR_INDEX_RANGE, &e, "outside the scene");
    m = good;
    m.vertex_count = V;
    expect_fail(pf_rt_update(rt, &m, 1, PF_RT_REFIT, &e), PF_ERR_INDEX_RANGE, &e, "outside the scene");
    m = good;
    m.tri_count--; /* part of a primitive */
    expect_fail(pf_rt_update(rt, &m, 1, PF_RT_REBUILD, &e), PF_ERR_ARGUMENT, &e, "built static");
    m = (pf_anim_moved){.tri_first = 0, .tri_count = 2, .vertex_first = 0, .vertex_count = 4, .moved = 1};
    assert_false(ap->tri_first == 0);
    expect_fail(pf_rt_update(rt, &m, 1, PF_RT_REBUILD, &e), PF_ERR_ARGUMENT, &e, "built static");
    /* a good entry before a bad one: nothing is touched */
    pf_anim_moved two[2] = {good, good};
    two[1].tri_first = T + 5;
    expect_fail(pf_rt_update(rt, two, 2, PF_RT_REBUILD, &e), PF_ERR_INDEX_RANGE, &e, "entry 1");
    expect_fail(pf_rt_update(rt, NULL, 3, PF_RT_REBUILD, &e), PF_ERR_ARGUMENT, &e, "NULL");
    expect_fail(pf_rt_update(rt, &good, 1, (pf_rt_update_mode)7, &e), PF_ERR_ARGUMENT, &e, "mode");
    trace(rt, rays, &after);
    expect_same(&after, &before, "after refused updates", 0.0);
    /* the good entry itself is accepted */
    assert_int_equal(pf_rt_update(rt, &good, 1, PF_RT_REBUILD, &e), PF_OK);
    pf_rt_destroy(rt);

    /* animation data that does not fit the scene */
    static char sentinel;
    pf_rt *bad = (pf_rt *)&sentinel; /* must come back NULL */
    pf_anim_prim saved = w.anim.prims[dp];
    w.anim.prims[dp].tri_count = T; /* past the end */
    expect_fail(pf_rt_create_dynamic(&bad, &w.scene, &w.anim, pf_isa_detect(), 1, &e), PF_ERR_INDEX_RANGE, &e,
                "lies outside");
    assert_null(bad);
    w.anim.prims[dp] = saved;
    w.anim.prims[dp].vertex_first = UINT32_MAX - 2;
    expect_fail(pf_rt_create_dynamic(&bad, &w.scene, &w.anim, pf_isa_detect(), 1, &e), PF_ERR_INDEX_RANGE, &e,
                "lies outside");
    w.anim.prims[dp] = saved;
    world_free(&w);

    tu_quad q[3] = {
        {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 0, -2}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 0, -3}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1, 1}, PF_ALPHA_OPAQUE, 0.5f},
    };
    const int dyn[3] = {0, 1, 1};
    pf_scene s;
    tu_make_scene(&s, q, 3);
    assert_int_equal(pf_scene_validate(&s, &e), PF_OK);
    pf_anim a;
    fake_anim(&a, dyn, 3);
    a.prims[2].tri_first = 3; /* overlaps primitive 1 */
    expect_fail(pf_rt_create_dynamic(&bad, &s, &a, pf_isa_detect(), 1, &e), PF_ERR_INDEX_RANGE, &e, "overlaps");
    a.prims[2].tri_first = 4;
    s.indices[0] = 5; /* a static triangle using a vertex of primitive 1 */
    expect_fail(pf_rt_create_dynamic(&bad, &s, &a, pf_isa_detect(), 1, &e), PF_ERR_INDEX_RANGE, &e,
                "would not move");
    s.indices[0] = 0;
    s.indices[6] = 9; /* a triangle of primitive 1 using a vertex of primitive 2 */
    expect_fail(pf_rt_create_dynamic(&bad, &s, &a, pf_isa_detect(), 1, &e), PF_ERR_INDEX_RANGE, &e,
                "another animated primitive");
    s.indices[6] = 4;
    assert_int_equal(pf_rt_create_dynamic(&bad, &s, &a, pf_isa_detect(), 1, &e), PF_OK);
    pf_rt_destroy(bad);
    pf_anim_free(&a);
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rebuild_equals_fresh),
        cmocka_unit_test(test_refit),
        cmocka_unit_test(test_static_unchanged),
        cmocka_unit_test(test_single_geometry_update),
        cmocka_unit_test(test_split_ids_and_alpha),
        cmocka_unit_test(test_all_dynamic),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
