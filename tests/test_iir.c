/* test_iir: Incremental Instant Radiosity (gi_iir, gi_delaunay; Laine 2007
 * Sec. 4).
 * - the largest empty circle on hand-made sets with known answers: a
 *   Voronoi vertex inside the disc, a Voronoi edge meeting the boundary,
 *   the boundary-only case, and on the sphere;
 * - Voronoi areas sum to pi (disc) and 4 pi (sphere), and symmetric sets
 *   give equal analytic areas;
 * - the largest empty circle agrees with a brute-force dispersion, and an
 *   insertion at its centre never increases the dispersion;
 * - the deletion rule removes, of the shortest Delaunay edge's two ends,
 *   the one whose second-closest neighbour is nearer (disc and sphere);
 * - validity: a VPL that falls behind an occluder when the light moves is
 *   invalidated, and every lit VPL is visible from the light;
 * - static light: at most recalcMin VPLs change per frame once converged,
 *   none with recalcMin=0; budget kept; ids and slots stable;
 * - 30 frames of the GI frame with a moving light identical with 1 and 2
 *   threads;
 * - IIR with many VPLs lights the Cornell box like IR (one bounce);
 * - two lights in a closed box: the budget split 3:1 by power and the VPL
 *   fluxes adding up to the lights' powers (gi_ir.c's units);
 * - spot validity: VPLs outside a turned spot's cone are invalidated;
 * - directional lights (the extension): the fluxes estimate E A of a floor;
 * - area lights (the extension): the VPL fluxes add up to the emitter's
 *   power in a closed box;
 * - local vertex deletion gives the same triangulation as a rebuild;
 * - bad --param values are errors.
 * Timing is not a test's job: `softgi bench frame --method iir
 * --moving-light` times the VPL update (docs/perf.md). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_delaunay.h"
#include "gi_frame.h"
#include "gi_light.h"
#include "gi_vpl.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define PI 3.14159265358979323846

static uint64_t rng_state;
static double rnd(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static void rnd_disc(double p[3])
{
    do {
        p[0] = 2.0 * rnd() - 1.0, p[1] = 2.0 * rnd() - 1.0;
    } while (p[0] * p[0] + p[1] * p[1] > 1.0);
    p[2] = 0.0;
}

static void rnd_sphere(double p[3])
{
    double z = 2.0 * rnd() - 1.0, a = 2.0 * PI * rnd(), r = sqrt(1.0 - z * z);
    p[0] = r * cos(a), p[1] = r * sin(a), p[2] = z;
}

static void dt_with(gi_dt *dt, gi_dt_domain dom, const double (*pts)[3], uint32_t n, uint32_t cap)
{
    pf_error err;
    assert_int_equal(gi_dt_init(dt, dom, cap, &err), PF_OK);
    for (uint32_t i = 0; i < n; i++) gi_dt_set_point(dt, i, pts[i]);
    assert_int_equal(gi_dt_rebuild(dt, &err), PF_OK);
    for (uint32_t i = 0; i < n; i++) assert_true(dt->in_dt[i]);
}

/* ------------------------------------------------------------ largest empty circle */

static void test_lec_interior(void **state)
{
    (void)state;
    /* 12 points on a circle of radius 0.95: the empty circle is centred at
     * the origin (a Voronoi vertex), radius 0.95; the boundary gaps between
     * neighbours are only 0.26 wide */
    double pts[12][3];
    for (int k = 0; k < 12; k++) pts[k][0] = 0.95 * cos(k * PI / 6), pts[k][1] = 0.95 * sin(k * PI / 6), pts[k][2] = 0;
    gi_dt dt;
    dt_with(&dt, GI_DT_DISC, (const double(*)[3])pts, 12, 16);
    double c[3];
    int kind;
    double r = gi_dt_largest_empty(&dt, c, &kind);
    print_message("interior: centre (%.3g, %.3g) r %.9f kind %d\n", c[0], c[1], r, kind);
    assert_int_equal(kind, 1);
    assert_true(fabs(r - 0.95) < 1e-6);
    assert_true(fabs(c[0]) < 1e-6 && fabs(c[1]) < 1e-6);
    gi_dt_free(&dt);
}

static void test_lec_voronoi_edge_boundary(void **state)
{
    (void)state;
    /* (-0.5,0), (0.5,0), (0,-0.5): the Voronoi vertex is the origin (r 0.5);
     * the Voronoi edge x = 0 of the first two runs up to (0, 1): r = sqrt(1.25) */
    const double pts[3][3] = {{-0.5, 0, 0}, {0.5, 0, 0}, {0, -0.5, 0}};
    gi_dt dt;
    dt_with(&dt, GI_DT_DISC, pts, 3, 4);
    double c[3];
    int kind;
    double r = gi_dt_largest_empty(&dt, c, &kind);
    print_message("edge/boundary: centre (%.9f, %.9f) r %.9f kind %d\n", c[0], c[1], r, kind);
    assert_int_equal(kind, 2);
    assert_true(fabs(r - sqrt(1.25)) < 1e-9);
    assert_true(fabs(c[0]) < 1e-9 && fabs(c[1] - 1.0) < 1e-9);
    gi_dt_free(&dt);
}

static void test_lec_boundary_only(void **state)
{
    (void)state;
    /* a cluster right of the centre: (0.5,0)'s Voronoi cell contains the
     * whole segment to (-1,0), where the empty circle is (Sec. 4.6's rare
     * case), r = 1.5 */
    const double pts[3][3] = {{0.5, 0, 0}, {0.6, 0.05, 0}, {0.6, -0.05, 0}};
    gi_dt dt;
    dt_with(&dt, GI_DT_DISC, pts, 3, 4);
    double c[3];
    int kind;
    double r = gi_dt_largest_empty(&dt, c, &kind);
    print_message("boundary only: centre (%.9f, %.9f) r %.9f kind %d\n", c[0], c[1], r, kind);
    assert_int_equal(kind, 3);
    assert_true(fabs(r - 1.5) < 1e-9);
    assert_true(fabs(c[0] + 1.0) < 1e-9 && fabs(c[1]) < 1e-9);
    gi_dt_free(&dt);
}

static void test_lec_sphere(void **state)
{
    (void)state;
    /* the octahedron: the empty caps are centred on the 8 face directions
     * (+-1,+-1,+-1)/sqrt(3), chord |(1,1,1)/sqrt(3) - (1,0,0)| */
    const double pts[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    gi_dt dt;
    dt_with(&dt, GI_DT_SPHERE, pts, 6, 8);
    double c[3];
    int kind;
    double r = gi_dt_largest_empty(&dt, c, &kind);
    double want = sqrt(2.0 - 2.0 / sqrt(3.0));
    print_message("sphere: centre (%.6f, %.6f, %.6f) r %.9f (want %.9f)\n", c[0], c[1], c[2], r, want);
    assert_int_equal(kind, 1);
    assert_true(fabs(r - want) < 1e-9);
    for (int k = 0; k < 3; k++) assert_true(fabs(fabs(c[k]) - 1.0 / sqrt(3.0)) < 1e-9);
    /* one more point: a tetrahedron's face centre is opposite a vertex */
    const double tet[4][3] = {{0, 0, 1}, {0.942809, 0, -0.333333}, {-0.471405, 0.816497, -0.333333},
                              {-0.471405, -0.816497, -0.333333}};
    gi_dt dt2;
    dt_with(&dt2, GI_DT_SPHERE, tet, 4, 4);
    r = gi_dt_largest_empty(&dt2, c, &kind);
    /* every face's centre is minus the opposite vertex: chord to the others = |(0,0,-1) - tet[1]| */
    double d = sqrt(0.942809 * 0.942809 + (1 - 0.333333) * (1 - 0.333333));
    assert_true(fabs(r - d) < 1e-5);
    gi_dt_free(&dt);
    gi_dt_free(&dt2);
}

/* ------------------------------------------------------------ Voronoi areas */

static void test_voronoi_areas(void **state)
{
    (void)state;
    rng_state = 7;
    double area[1024];
    for (int trial = 0; trial < 5; trial++) {
        uint32_t n = 50 + 200 * trial;
        gi_dt dd, ds;
        pf_error err;
        assert_int_equal(gi_dt_init(&dd, GI_DT_DISC, n, &err), PF_OK);
        assert_int_equal(gi_dt_init(&ds, GI_DT_SPHERE, n, &err), PF_OK);
        for (uint32_t i = 0; i < n; i++) {
            double p[3];
            rnd_disc(p);
            gi_dt_set_point(&dd, i, p);
            rnd_sphere(p);
            gi_dt_set_point(&ds, i, p);
        }
        assert_int_equal(gi_dt_rebuild(&dd, &err), PF_OK);
        assert_int_equal(gi_dt_rebuild(&ds, &err), PF_OK);
        double sd = 0, ss = 0;
        gi_dt_voronoi_areas(&dd, area);
        for (uint32_t i = 0; i < n; i++) assert_true(area[i] > 0.0), sd += area[i];
        gi_dt_voronoi_areas(&ds, area);
        for (uint32_t i = 0; i < n; i++) assert_true(area[i] > 0.0), ss += area[i];
        print_message("%u points: disc areas sum %.12f (pi %.12f), sphere %.12f (4 pi %.12f)\n", n, sd, PI, ss, 4 * PI);
        assert_true(fabs(sd - PI) < 1e-9);
        assert_true(fabs(ss - 4 * PI) < 1e-9);
        gi_dt_free(&dd);
        gi_dt_free(&ds);
    }
    /* symmetric sets: equal analytic areas */
    const double sq[4][3] = {{0.5, 0, 0}, {0, 0.5, 0}, {-0.5, 0, 0}, {0, -0.5, 0}};
    gi_dt dt;
    dt_with(&dt, GI_DT_DISC, sq, 4, 4);
    gi_dt_voronoi_areas(&dt, area);
    for (int i = 0; i < 4; i++) assert_true(fabs(area[i] - PI / 4) < 1e-12);
    gi_dt_free(&dt);
    const double oct[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    dt_with(&dt, GI_DT_SPHERE, oct, 6, 6);
    gi_dt_voronoi_areas(&dt, area);
    for (int i = 0; i < 6; i++) assert_true(fabs(area[i] - 4 * PI / 6) < 1e-12);
    gi_dt_free(&dt);
}

/* ------------------------------------------------------------ dispersion */

static void dispersion_domain(gi_dt_domain dom)
{
    rng_state = 11 + dom;
    pf_error err;
    for (int trial = 0; trial < 20; trial++) {
        uint32_t n = 5 + 7 * trial;
        gi_dt dt;
        assert_int_equal(gi_dt_init(&dt, dom, n + 8, &err), PF_OK);
        for (uint32_t i = 0; i < n; i++) {
            double p[3];
            if (dom == GI_DT_DISC) rnd_disc(p);
            else rnd_sphere(p);
            gi_dt_set_point(&dt, i, p);
        }
        assert_int_equal(gi_dt_rebuild(&dt, &err), PF_OK);
        double c[3];
        double d0 = gi_dt_largest_empty(&dt, c, NULL);
        /* the exact answer bounds the brute force from above, and the brute
         * force comes within its probe spacing */
        double brute = gi_dt_dispersion_brute(&dt, 200000);
        if (!(brute <= d0 + 1e-7 && d0 <= brute + 0.01))
            fail_msg("trial %d (%u points): dispersion %.6f, brute force %.6f", trial, n, d0, brute);
        /* insertions at the largest empty circle: never an increase */
        for (uint32_t k = 0; k < 8; k++) {
            assert_int_equal(gi_dt_insert(&dt, n + k, c, &err), 1);
            double d1 = gi_dt_largest_empty(&dt, c, NULL);
            if (d1 > d0 + 1e-12) fail_msg("insertion %u increased the dispersion %.9f -> %.9f", k, d0, d1);
            d0 = d1;
        }
        gi_dt_free(&dt);
    }
}

static void test_dispersion_disc(void **state)
{
    (void)state;
    dispersion_domain(GI_DT_DISC);
}

static void test_dispersion_sphere(void **state)
{
    (void)state;
    dispersion_domain(GI_DT_SPHERE);
}

/* ------------------------------------------------------------ deletion rule */

static void test_deletion_rule(void **state)
{
    (void)state;
    /* the shortest edge a-b (0.1); c lies 0.2 beyond one end, so that end's
     * second-closest neighbour (c, 0.2) is nearer than the other's (0.65):
     * that end goes. Mirrored, the other end goes. */
    for (int side = 0; side < 2; side++) {
        double s = side ? -1.0 : 1.0;
        const double pts[8][3] = {{-0.05, 0, 0}, {0.05, 0, 0},   {0.25 * s, 0, 0}, {-0.7, 0, 0},
                                  {0, 0.7, 0},   {0, -0.7, 0},   {0.7, 0.4, 0},    {0.7, -0.4, 0}};
        gi_dt dt;
        dt_with(&dt, GI_DT_DISC, pts, 8, 8);
        uint32_t v = gi_dt_deletion_candidate(&dt);
        assert_int_equal(v, side ? 0u : 1u);
        gi_dt_free(&dt);
    }
    /* the same on the sphere around +z */
    for (int side = 0; side < 2; side++) {
        double s = side ? -1.0 : 1.0;
        double pts[8][3] = {{-0.05, 0, 0}, {0.05, 0, 0}, {0.25 * s, 0, 0}, {-0.7, 0, 0},
                            {0, 0.7, 0},   {0, -0.7, 0}, {0, 0, 0},        {0, 0, 0}};
        for (int k = 0; k < 6; k++) pts[k][2] = sqrt(1.0 - pts[k][0] * pts[k][0] - pts[k][1] * pts[k][1]);
        pts[6][2] = -1.0;                                       /* the south pole */
        pts[7][0] = 0.6, pts[7][1] = 0.6, pts[7][2] = -0.529150262; /* keeps the hull around the origin */
        gi_dt dt;
        dt_with(&dt, GI_DT_SPHERE, (const double(*)[3])pts, 8, 8);
        uint32_t v = gi_dt_deletion_candidate(&dt);
        assert_int_equal(v, side ? 0u : 1u);
        gi_dt_free(&dt);
    }
}

/* Local vertex deletion (ear clipping) gives the triangulation a rebuild
 * gives: the same Delaunay neighbours for every vertex. */
static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static void deletion_matches_rebuild(gi_dt_domain dom)
{
    rng_state = 99 + dom;
    enum { N = 300 };
    pf_error err;
    gi_dt a, b;
    assert_int_equal(gi_dt_init(&a, dom, N, &err), PF_OK);
    assert_int_equal(gi_dt_init(&b, dom, N, &err), PF_OK);
    for (uint32_t i = 0; i < N; i++) {
        double p[3];
        if (dom == GI_DT_DISC) rnd_disc(p);
        else rnd_sphere(p);
        gi_dt_set_point(&a, i, p);
    }
    assert_int_equal(gi_dt_rebuild(&a, &err), PF_OK);
    static uint32_t na[N], nb[N];
    for (int k = 0; k < 120; k++) {
        uint32_t v = (uint32_t)(rnd() * N);
        if (!a.present[v]) continue;
        assert_int_equal(gi_dt_remove(&a, v, &err), PF_OK);
        for (uint32_t i = 0; i < N; i++)
            if (a.present[i]) gi_dt_set_point(&b, i, a.p[i]);
            else b.present[i] = 0;
        assert_int_equal(gi_dt_rebuild(&b, &err), PF_OK);
        for (uint32_t i = 0; i < N; i++) {
            assert_int_equal(a.in_dt[i], b.in_dt[i]);
            if (!a.in_dt[i]) continue;
            uint32_t ca = gi_dt_neighbours(&a, i, na, N), cb = gi_dt_neighbours(&b, i, nb, N);
            qsort(na, ca, 4, cmp_u32), qsort(nb, cb, 4, cmp_u32);
            assert_int_equal(ca, cb);
            assert_memory_equal(na, nb, 4 * ca);
        }
    }
    gi_dt_free(&a);
    gi_dt_free(&b);
}

static void test_local_deletion(void **state)
{
    (void)state;
    deletion_matches_rebuild(GI_DT_DISC);
    deletion_matches_rebuild(GI_DT_SPHERE);
}

/* ------------------------------------------------------------ the method */

static void run_frames(void *st, gi_vpl_inputs *in, gi_vpl_set *out, uint32_t first, uint32_t n)
{
    pf_error err;
    for (uint32_t k = 0; k < n; k++) {
        in->frame = first + k;
        if (gi_method_iir.update(st, in, out, &err) != PF_OK) fail_msg("%s", err.message);
    }
}

static uint32_t lit_count(const gi_vpl_set *v)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < v->count; i++) n += v->v[i].intensity.x + v->v[i].intensity.y + v->v[i].intensity.z > 0.0f;
    return n;
}

static void test_validity_occluder(void **state)
{
    (void)state;
    /* a floor, a 2 x 2 occluder 1 above it, a point light 3 above */
    const tu_quad q[2] = {{{0, 0, 0}, {10, 0, 0}, {0, 0, -10}, {0.8f, 0.8f, 0.8f, 1}, PF_ALPHA_OPAQUE, 0.5f},
                          {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}, {0.5f, 0.5f, 0.5f, 1}, PF_ALPHA_OPAQUE, 0.5f}};
    pf_scene s;
    pf_error err;
    tu_make_scene(&s, q, 2);
    pf_light L = {.type = PF_LIGHT_POINT, .position = {0, 3, 0}, .color = {1, 1, 1}, .intensity = 10};
    assert_int_equal(pf_scene_add_light(&s, &L, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    void *st;
    assert_int_equal(gi_method_iir.create(&st, NULL, &err), PF_OK);
    gi_area_lights area = {0};
    gi_vpl_set a = {0}, b = {0};
    gi_vpl_inputs in = {&s, rt, NULL, NULL, 0, 256, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    run_frames(st, &in, &a, 0, 3);
    print_message("lit VPLs %u of %u slots (half the sphere leaves the scene)\n", lit_count(&a), a.count);
    assert_true(lit_count(&a) > 60);
    /* move the light sideways: floor points now behind the occluder */
    s.lights[0].position = pf_v3(1.6f, 3, 0.3f);
    in.frame = 3;
    assert_int_equal(gi_method_iir.update(st, &in, &b, &err), PF_OK);
    uint32_t shadowed = 0, gone = 0;
    for (uint32_t i = 0; i < a.count; i++) {
        const gi_vpl *v = &a.v[i];
        if (v->id == UINT32_MAX) continue;
        pf_ray r = {s.lights[0].position, 0.0f, pf_v3_sub(v->pos, s.lights[0].position), 0.9999f};
        if (!pf_rt_occluded1(rt, r)) continue;
        shadowed++;
        int alive = 0;
        for (uint32_t j = 0; j < b.count; j++) alive |= b.v[j].id == v->id;
        gone += !alive;
    }
    print_message("%u VPLs fell into the occluder's shadow; %u of them were invalidated\n", shadowed, gone);
    assert_true(shadowed > 0);
    assert_int_equal(gone, shadowed);
    /* every lit VPL is visible from the light; slots of survivors unchanged */
    for (uint32_t j = 0; j < b.count; j++) {
        const gi_vpl *v = &b.v[j];
        if (v->id == UINT32_MAX) continue;
        pf_ray r = {s.lights[0].position, 0.0f, pf_v3_sub(v->pos, s.lights[0].position), 0.9999f};
        assert_false(pf_rt_occluded1(rt, r));
        if (!v->moved) assert_true(j < a.count && a.v[j].id == v->id);
    }
    gi_method_iir.destroy(st);
    gi_vpl_set_free(&a), gi_vpl_set_free(&b);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

static void static_light(uint32_t recalc_min)
{
    pf_scene s;
    pf_error err;
    assert_int_equal(pf_gltf_load(&s, CORNELL, NULL, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    gi_params p = {0};
    char kv[32];
    snprintf(kv, sizeof kv, "recalcMin=%u", recalc_min);
    assert_int_equal(gi_params_add(&p, kv, &err), PF_OK);
    void *st;
    assert_int_equal(gi_method_iir.create(&st, &p, &err), PF_OK);
    gi_area_lights area = {0};
    gi_vpl_set a = {0}, b = {0};
    gi_vpl_inputs in = {&s, rt, NULL, &s.cameras[0], 0, 256, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    run_frames(st, &in, &a, 0, 1);
    uint32_t lit0 = lit_count(&a);
    assert_true(lit0 > 200);
    for (uint32_t f = 1; f < 40; f++) {
        run_frames(st, &in, &b, f, 1);
        uint32_t moved = 0, same_slot = 0;
        for (uint32_t i = 0; i < b.count; i++) {
            moved += b.v[i].moved;
            if (!b.v[i].moved && b.v[i].id != UINT32_MAX) {
                assert_true(i < a.count && a.v[i].id == b.v[i].id); /* a surviving VPL keeps its slot */
                assert_memory_equal(&a.v[i].pos, &b.v[i].pos, sizeof(pf_vec3));
                same_slot++;
            }
        }
        if (moved > recalc_min) fail_msg("frame %u: %u VPLs changed (recalcMin %u)", f, moved, recalc_min);
        assert_true(b.count <= 256);
        assert_int_equal(lit_count(&b) + 0u >= lit0 - recalc_min, 1);
        if (recalc_min == 0 && f >= 2) { /* frozen (frame 1 re-derives the sampling points from the VPLs) */
            assert_int_equal(a.count, b.count);
            assert_int_equal(moved, 0);
            assert_memory_equal(a.v, b.v, sizeof(gi_vpl) * a.count);
        }
        gi_vpl_set t = a;
        a = b, b = t;
    }
    gi_method_iir.destroy(st);
    gi_vpl_set_free(&a), gi_vpl_set_free(&b);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

static void test_static_light_converges(void **state)
{
    (void)state;
    static_light(4);
    static_light(0);
}

/* 30 frames of the GI frame (iir, paraboloid maps) with a light moving
 * along a path: every frame's VPL set and final image hashed, 1 vs 2
 * threads. */
static uint64_t frames_hash(uint32_t threads)
{
    tu_fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = &gi_method_iir;
    io.vpls = 96;
    tu_fx_begin(&x, threads, RS_SIMD_SCALAR, 64, 48, &x.scene.cameras[0], &io, 0);
    gi_frame *f = &x.f;
    uint64_t h = 0;
    pf_vec3 p0 = x.scene.lights[0].position;
    uint32_t maps = 0;
    for (uint32_t k = 0; k < 30; k++) {
        x.scene.lights[0].position = pf_v3(p0.x + 0.15f * sinf(0.2f * k), p0.y - 0.1f, p0.z + 0.1f * cosf(0.3f * k));
        gi_frame_render_raster(f);
        h = h * 31 + pf_imageio_hash((const float *)f->ind.vpls.v, f->ind.vpls.count * (sizeof(gi_vpl) / 4));
        h = h * 31 + pf_imageio_hash(f->final, 3 * 64 * 48);
        if (k > 0) maps += f->ind.maps_rendered;
    }
    print_message("%u threads: hash %016llx, %.1f maps rendered per frame after the first\n", threads,
                  (unsigned long long)h, maps / 29.0);
    assert_true(maps <= 29u * 8u); /* never more than recalcMax new VPLs a frame */
    tu_fx_end(&x);
    return h;
}

static void test_deterministic_threads(void **state)
{
    (void)state;
    uint64_t h1 = frames_hash(1), h2 = frames_hash(2);
    assert_true(h1 == h2);
}

/* IIR against IR (one bounce) in the Cornell box: 4096 VPLs, every pixel
 * sees every VPL through Embree rays, no clamp, no filter, indirect only.
 * The light is moved to the middle of the box as in test_vpl's IR check
 * (under the ceiling the VPLs next to the light make both noisy). */
static void render_indirect(const gi_vpl_method *m, float *out, uint32_t W, uint32_t H, uint32_t vpls, uint32_t frames)
{
    tu_fx x;
    pf_error err;
    assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
    x.scene.lights[0].position = pf_v3(0.278f, 0.35f, 0.28f);
    x.scene.lights[0].intensity = 0.3f;
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = m;
    io.no_interleave = 1;
    io.visibility_raytrace = 1;
    io.vpls = vpls;
    io.bounces = 1;
    io.clamp = 0.0f;
    io.filter = GI_FILTER_NONE;
    tu_fx_begin(&x, 2, RS_SIMD_SCALAR, W, H, &x.scene.cameras[0], &io, 0);
    x.f.show_direct = 0;
    for (uint32_t k = 0; k < frames; k++) gi_frame_render_raster(&x.f);
    memcpy(out, x.f.final, sizeof(float) * 3 * W * H);
    tu_fx_end(&x);
}

static void test_converges_to_ir(void **state)
{
    (void)state;
    enum { W = 48, H = 36 };
    static float a[3 * W * H], b[3 * W * H];
    render_indirect(&gi_method_ir, a, W, H, 4096, 1);
    render_indirect(&gi_method_iir, b, W, H, 4096, 1);
    double sum = 0.0, sa = 0.0, sb = 0.0;
    int n = 0;
    for (int i = 0; i < W * H; i++) {
        double x = 0.2126 * a[3 * i] + 0.7152 * a[3 * i + 1] + 0.0722 * a[3 * i + 2];
        double y = 0.2126 * b[3 * i] + 0.7152 * b[3 * i + 1] + 0.0722 * b[3 * i + 2];
        if (!(x > 1e-5)) continue;
        sum += fabs(y - x) / x;
        sa += x, sb += y;
        n++;
    }
    double mre = sum / n;
    print_message("IIR vs IR (4096 VPLs, one bounce): mean relative error %.4f over %d pixels, ratio of means %.4f\n",
                  mre, n, sb / sa);
    assert_true(n > W * H / 2);
    assert_true(mre < 0.03);
    assert_true(fabs(sb / sa - 1.0) < 0.01);
}

static void closed_box(pf_scene *s, int emitter)
{
    const float al[4] = {0.5f, 0.5f, 0.5f, 1};
    tu_quad q[7] = {
        {{0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0}, PF_ALPHA_OPAQUE, 0.5f},  /* floor, up */
        {{0, 2, 0}, {1, 0, 0}, {0, 0, 1}, {0}, PF_ALPHA_OPAQUE, 0.5f},   /* ceiling, down */
        {{-1, 1, 0}, {0, 0, -1}, {0, 1, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f}, /* walls facing in */
        {{1, 1, 0}, {0, 0, 1}, {0, 1, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 1, -1}, {1, 0, 0}, {0, 1, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 1, 1}, {-1, 0, 0}, {0, 1, 0}, {0}, PF_ALPHA_OPAQUE, 0.5f},
        {{0, 1.9f, 0}, {0.2f, 0, 0}, {0, 0, 0.2f}, {0}, PF_ALPHA_OPAQUE, 0.5f}, /* emitter, down */
    };
    for (int k = 0; k < 7; k++) memcpy(q[k].albedo, al, sizeof al);
    tu_make_scene(s, q, emitter ? 7 : 6);
    if (emitter) s->materials[6].emission[0] = 4.0f, s->materials[6].emission[1] = 2.0f, s->materials[6].emission[2] = 1.0f;
}

/* Several lights in a closed box (every ray hits): one domain each, the
 * budget split by power (3:1 gives 192 + 64 slots), and the VPL fluxes
 * (I pi / albedo) add up to the lights' powers: 4 pi I for the point
 * light, I times the cone factor's integral (gi_ir.c's midpoint rule) for
 * the spot. */
static void test_two_lights_power(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    closed_box(&s, 0);
    pf_light P = {.type = PF_LIGHT_POINT, .position = {-0.5f, 1, 0}, .color = {1, 1, 1}, .intensity = 3};
    pf_light S = {.type = PF_LIGHT_SPOT, .position = {0.5f, 1.5f, 0}, .direction = {0, -1, 0}, .color = {1, 0.5f, 0.25f},
                  .intensity = 1, .inner_cone = 0.3f, .outer_cone = 0.9f};
    /* the spot's power per unit intensity, gi_ir.c's rule */
    double co = cos(0.9), sum = 0.0;
    for (int k = 0; k < 256; k++) sum += gi_light_spot_factor(&S, (float)(co + (1.0 - co) * (k + 0.5) / 256.0));
    double spot_sr = 2.0 * PI * sum * (1.0 - co) / 256.0;
    /* luminance powers 12 pi (point) : 4 pi (spot) */
    S.intensity = (float)(4.0 * PI / spot_sr / (0.2126 + 0.7152 * 0.5 + 0.0722 * 0.25));
    assert_int_equal(pf_scene_add_light(&s, &P, &err), PF_OK);
    assert_int_equal(pf_scene_add_light(&s, &S, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    void *st;
    assert_int_equal(gi_method_iir.create(&st, NULL, &err), PF_OK);
    gi_area_lights area = {0};
    gi_vpl_set v = {0};
    gi_vpl_inputs in = {&s, rt, NULL, NULL, 0, 256, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    run_frames(st, &in, &v, 0, 2);
    double flux[3] = {0, 0, 0};
    uint32_t n = 0, near_spot = 0;
    for (uint32_t i = 0; i < v.count; i++) {
        if (v.v[i].id == UINT32_MAX) continue;
        n++;
        flux[0] += v.v[i].intensity.x * PI / 0.5, flux[1] += v.v[i].intensity.y * PI / 0.5;
        flux[2] += v.v[i].intensity.z * PI / 0.5;
        /* the spot's VPLs are on the floor under it, inside its cone */
        pf_vec3 d = pf_v3_sub(v.v[i].pos, S.position);
        /* (on the cone's edge the cone factor, hence the intensity, is 0) */
        int spot_coloured = v.v[i].intensity.x == 0.0f || v.v[i].intensity.z < 0.5f * v.v[i].intensity.x;
        near_spot += spot_coloured && pf_v3_dot(pf_v3_normalize(d), S.direction) > cosf(0.9f) - 1e-3f;
    }
    double want[3] = {4 * PI * 3 + spot_sr * S.intensity, 4 * PI * 3 + spot_sr * S.intensity * 0.5,
                      4 * PI * 3 + spot_sr * S.intensity * 0.25};
    print_message("%u VPLs (%u of them the spot's), flux (%.5f, %.5f, %.5f), lights' power (%.5f, %.5f, %.5f)\n", n,
                  near_spot, flux[0], flux[1], flux[2], want[0], want[1], want[2]);
    assert_int_equal(n, 256);
    assert_int_equal(near_spot, 64);
    for (int c = 0; c < 3; c++) assert_true(fabs(flux[c] / want[c] - 1.0) < 1e-4);
    gi_method_iir.destroy(st);
    gi_vpl_set_free(&v);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* Spot validity, condition 2 of Sec. 4.4: when the spot turns, VPLs that
 * fall outside its outer cone are invalidated, and every VPL it keeps lies
 * inside the new cone. */
static void test_spot_cone_validity(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    closed_box(&s, 0);
    pf_light S = {.type = PF_LIGHT_SPOT, .position = {0, 1.8f, 0}, .direction = {0, -1, 0}, .color = {1, 1, 1},
                  .intensity = 1, .inner_cone = 0.3f, .outer_cone = 0.6f};
    assert_int_equal(pf_scene_add_light(&s, &S, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    void *st;
    assert_int_equal(gi_method_iir.create(&st, NULL, &err), PF_OK);
    gi_area_lights area = {0};
    gi_vpl_set a = {0}, b = {0};
    gi_vpl_inputs in = {&s, rt, NULL, NULL, 0, 128, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    run_frames(st, &in, &a, 0, 2);
    s.lights[0].direction = pf_v3_normalize(pf_v3(0.25f, -1, 0)); /* turn by 14 degrees */
    run_frames(st, &in, &b, 2, 1);
    uint32_t outside_before = 0, gone = 0, kept = 0;
    float co = cosf(0.6f);
    for (uint32_t i = 0; i < a.count; i++) {
        if (a.v[i].id == UINT32_MAX) continue;
        pf_vec3 w = pf_v3_normalize(pf_v3_sub(a.v[i].pos, S.position));
        if (pf_v3_dot(w, s.lights[0].direction) >= co) continue;
        outside_before++;
        int alive = 0;
        for (uint32_t j = 0; j < b.count; j++) alive |= b.v[j].id == a.v[i].id;
        gone += !alive;
    }
    for (uint32_t j = 0; j < b.count; j++) {
        if (b.v[j].id == UINT32_MAX) continue;
        pf_vec3 w = pf_v3_normalize(pf_v3_sub(b.v[j].pos, S.position));
        assert_true(pf_v3_dot(w, s.lights[0].direction) >= co - 1e-5f);
        kept += !b.v[j].moved;
    }
    print_message("%u VPLs left the turned cone, %u of them invalidated; %u kept\n", outside_before, gone, kept);
    assert_true(outside_before > 5);
    assert_int_equal(gone, outside_before);
    assert_true(kept > 64);
    gi_method_iir.destroy(st);
    gi_vpl_set_free(&a), gi_vpl_set_free(&b);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* Directional lights (the extension): a beam straight down onto a 10 x 10
 * floor; the emission disc has the scene's bounding radius, so the VPLs'
 * fluxes estimate E times the floor's area through their Voronoi areas. */
static void test_directional_power(void **state)
{
    (void)state;
    const tu_quad q = {{0, 0, 0}, {5, 0, 0}, {0, 0, -5}, {0.5f, 0.5f, 0.5f, 1}, PF_ALPHA_OPAQUE, 0.5f};
    pf_scene s;
    pf_error err;
    tu_make_scene(&s, &q, 1);
    pf_light D = {.type = PF_LIGHT_DIRECTIONAL, .direction = {0, -1, 0}, .color = {1, 1, 1}, .intensity = 2};
    assert_int_equal(pf_scene_add_light(&s, &D, &err), PF_OK);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    void *st;
    assert_int_equal(gi_method_iir.create(&st, NULL, &err), PF_OK);
    gi_area_lights area = {0};
    gi_vpl_set v = {0};
    gi_vpl_inputs in = {&s, rt, NULL, NULL, 0, 1024, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    run_frames(st, &in, &v, 0, 2);
    double flux = 0.0;
    uint32_t n = 0;
    for (uint32_t i = 0; i < v.count; i++)
        if (v.v[i].id != UINT32_MAX) flux += v.v[i].intensity.x * PI / 0.5, n++;
    print_message("%u of 1024 samples hit the floor: flux %.4f, E A = %.4f\n", n, flux, 2.0 * 100.0);
    assert_true(fabs(flux / 200.0 - 1.0) < 0.03);
    gi_method_iir.destroy(st);
    gi_vpl_set_free(&v);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

/* Area lights (the extension): a closed 2 x 2 x 2 box of albedo 0.5 with a
 * small emissive quad under its ceiling facing down: every ray hits, so
 * the VPLs' fluxes (I pi / albedo) add up to the emitter's power pi A Le
 * exactly (one emitter of uniform radiance: Le / pdf_area is constant). */
static void test_area_light_power(void **state)
{
    (void)state;
    pf_scene s;
    pf_error err;
    closed_box(&s, 1);
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    gi_area_lights area;
    assert_int_equal(gi_area_lights_build(&area, &s, &err), PF_OK);
    assert_int_equal(area.count, 2);
    void *st;
    assert_int_equal(gi_method_iir.create(&st, NULL, &err), PF_OK);
    gi_vpl_set v = {0};
    gi_vpl_inputs in = {&s, rt, NULL, NULL, 0, 256, 1, NULL, 0, 0, &area, NULL, 0, 0, 0, 0};
    for (uint32_t f = 0; f < 3; f++) {
        run_frames(st, &in, &v, f, 1);
        double sum[3] = {0, 0, 0};
        uint32_t n = 0;
        for (uint32_t i = 0; i < v.count; i++) {
            if (v.v[i].id == UINT32_MAX) continue;
            n++;
            sum[0] += v.v[i].intensity.x * PI / 0.5, sum[1] += v.v[i].intensity.y * PI / 0.5;
            sum[2] += v.v[i].intensity.z * PI / 0.5;
            assert_true(v.v[i].pos.y < 1.9f); /* below the emitter */
        }
        double want[3] = {PI * 0.16 * 4.0, PI * 0.16 * 2.0, PI * 0.16 * 1.0};
        print_message("frame %u: %u VPLs, flux (%.6f, %.6f, %.6f), emitter power (%.6f, %.6f, %.6f)\n", f, n, sum[0],
                      sum[1], sum[2], want[0], want[1], want[2]);
        assert_int_equal(n, 256);
        for (int c = 0; c < 3; c++) assert_true(fabs(sum[c] / want[c] - 1.0) < 1e-4);
    }
    gi_method_iir.destroy(st);
    gi_vpl_set_free(&v);
    gi_area_lights_free(&area);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

static void test_bad_params(void **state)
{
    (void)state;
    pf_error err;
    void *st = NULL;
    const char *bad[] = {"recalcMin=9", "recalcMax=0", "recalcMin=-1", "recalc=3", "albedoLod=99"};
    for (int k = 0; k < 5; k++) {
        gi_params p = {0};
        if (k == 0) assert_int_equal(gi_params_add(&p, "recalcMax=8", &err), PF_OK);
        assert_int_equal(gi_params_add(&p, bad[k], &err), PF_OK);
        assert_int_not_equal(gi_method_iir.create(&st, &p, &err), PF_OK);
        print_message("%s: %s\n", bad[k], err.message);
    }
    /* and through the command line: a clear message, exit status 2 */
    tu_softgi_expect("render " CORNELL " --method iir --param recalcMin=9 --size 32x24 -q -o /tmp/test_iir_bad.png", 2,
                     "recalcMin (9) must not exceed recalcMax (8)");
    tu_softgi_expect("render " CORNELL " --method iir --param recalc=3 --size 32x24 -q -o /tmp/test_iir_bad.png", 2,
                     "no such parameter");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lec_interior),
        cmocka_unit_test(test_lec_voronoi_edge_boundary),
        cmocka_unit_test(test_lec_boundary_only),
        cmocka_unit_test(test_lec_sphere),
        cmocka_unit_test(test_voronoi_areas),
        cmocka_unit_test(test_dispersion_disc),
        cmocka_unit_test(test_dispersion_sphere),
        cmocka_unit_test(test_deletion_rule),
        cmocka_unit_test(test_local_deletion),
        cmocka_unit_test(test_validity_occluder),
        cmocka_unit_test(test_static_light_converges),
        cmocka_unit_test(test_deterministic_threads),
        cmocka_unit_test(test_converges_to_ir),
        cmocka_unit_test(test_two_lights_power),
        cmocka_unit_test(test_spot_cone_validity),
        cmocka_unit_test(test_directional_power),
        cmocka_unit_test(test_area_light_power),
        cmocka_unit_test(test_bad_params),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
