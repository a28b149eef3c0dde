/* test_embree: the Embree glue (pf_rt).
 * - a ray traced alone gives the same bits as in a packet of 8 (one fixed
 *   query width), on the Cornell box and on Sibenik;
 * - occlusion agrees with closest hits;
 * - BVH builds with 1 and 2 build threads give identical hits;
 * - pinned ISAs (sse2 vs the best) agree on what is hit;
 * - alpha-masked materials are skipped by both query kinds;
 * - hit surfaces (position, normals, albedo) are interpolated correctly. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_rt.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SIBENIK SOFTGI_SHARED_SCENES "/sibenik/sibenik.gltf"

/* Camera rays over the scene's bounds, looking at the centre from a corner. */
static void make_rays(const pf_scene *s, pf_ray *rays, uint32_t w, uint32_t h)
{
    pf_vec3 c = pf_v3_scale(pf_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    pf_vec3 ext = pf_v3_sub(s->bounds_max, s->bounds_min);
    pf_vec3 eye = pf_v3_add(c, pf_v3(0.3f * ext.x, 0.1f * ext.y, 0.35f * ext.z));
    pf_camera cam;
    pf_error err;
    assert_int_equal(pf_camera_look_at(&cam, eye, c, pf_radians(75.0f), &err), PF_OK);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) rays[y * w + x] = gi_camera_ray(&cam, w, h, x, y);
}

static int same_hit(const pf_hit *a, const pf_hit *b)
{
    return memcmp(a, b, sizeof *a) == 0;
}

static void check_single_vs_packet(const char *path)
{
    pf_scene s;
    if (!tu_load_or_skip(&s, path)) return;
    pf_error err;
    pf_rt *rt;
    pf_isa isa = pf_isa_detect();
    assert_int_equal(pf_rt_create(&rt, &s, isa, 1, &err), PF_OK);
    enum { W = 128, H = 96 };
    static pf_ray rays[W * H];
    static pf_hit batch[W * H];
    static uint8_t occ[W * H];
    make_rays(&s, rays, W, H);
    pf_rt_intersect(rt, rays, batch, W * H);
    pf_rt_occluded(rt, rays, occ, W * H);
    uint32_t hits = 0;
    for (uint32_t i = 0; i < W * H; i++) {
        pf_hit one = pf_rt_intersect1(rt, rays[i]);
        if (!same_hit(&one, &batch[i]))
            fail_msg("%s ray %u: alone t=%a prim=%u, in a packet t=%a prim=%u", path, i, (double)one.t, one.prim,
                     (double)batch[i].t, batch[i].prim);
        assert_int_equal(occ[i], batch[i].prim != PF_RT_MISS);
        assert_int_equal(pf_rt_occluded1(rt, rays[i]), occ[i]);
        hits += batch[i].prim != PF_RT_MISS;
    }
    assert_true(hits > W * H / 2);
    /* odd batch sizes (partial packets) give the same answers */
    pf_rt_intersect(rt, rays + 3, batch + 3, 13);
    for (uint32_t i = 3; i < 16; i++) {
        pf_hit one = pf_rt_intersect1(rt, rays[i]);
        assert_true(same_hit(&one, &batch[i]));
    }
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

static void test_single_vs_packet_cornell(void **state)
{
    (void)state;
    check_single_vs_packet(CORNELL);
}

static void test_single_vs_packet_sibenik(void **state)
{
    (void)state;
    check_single_vs_packet(SIBENIK);
}

/* BVH build with 1 vs 2 threads, and sse2 vs the best ISA. */
static void test_build_threads_and_isa(void **state)
{
    (void)state;
    pf_scene s;
    if (!tu_load_or_skip(&s, SIBENIK) && !tu_load_or_skip(&s, CORNELL)) return;
    pf_error err;
    pf_rt *a, *b, *c;
    assert_int_equal(pf_rt_create(&a, &s, pf_isa_detect(), 1, &err), PF_OK);
    assert_int_equal(pf_rt_create(&b, &s, pf_isa_detect(), 2, &err), PF_OK);
    assert_int_equal(pf_rt_create(&c, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    enum { W = 160, H = 120 };
    static pf_ray rays[W * H];
    static pf_hit ha[W * H], hb[W * H], hc[W * H];
    make_rays(&s, rays, W, H);
    pf_rt_intersect(a, rays, ha, W * H);
    pf_rt_intersect(b, rays, hb, W * H);
    pf_rt_intersect(c, rays, hc, W * H);
    uint32_t prim_diff = 0;
    for (uint32_t i = 0; i < W * H; i++) {
        if (!same_hit(&ha[i], &hb[i]))
            fail_msg("ray %u differs between 1 and 2 build threads (prim %u vs %u)", i, ha[i].prim, hb[i].prim);
        if (ha[i].prim != hc[i].prim) prim_diff++;
        else if (ha[i].prim != PF_RT_MISS)
            assert_true(fabsf(ha[i].t - hc[i].t) <= 1e-4f * ha[i].t); /* same surface, nearly same t */
    }
    /* different ISAs may differ in bits, and on exact ties in which triangle */
    assert_true(prim_diff <= W * H / 1000);
    pf_rt_destroy(a);
    pf_rt_destroy(b);
    pf_rt_destroy(c);
    pf_scene_free(&s);
}

/* Two parallel quads; the near one is alpha-masked out (alpha 0.2 < 0.5). */
static void test_alpha_mask(void **state)
{
    (void)state;
    pf_scene s;
    tu_make_alpha_stack(&s, 1.0f);
    pf_error err;
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, PF_ISA_SSE2, 1, &err), PF_OK);
    pf_ray r = {{0.1f, 0.2f, 0}, 0.0f, {0, 0, -1}, INFINITY};
    pf_hit h = pf_rt_intersect1(rt, r);
    assert_int_equal(s.tri_material[h.prim], 1);
    assert_float_equal(h.t, 2.0f, 1e-6f);
    r.tfar = 1.5f; /* only the masked-out quad lies within reach */
    assert_int_equal(pf_rt_occluded1(rt, r), 0);
    r.tfar = 2.5f;
    assert_int_equal(pf_rt_occluded1(rt, r), 1);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

static void test_surface(void **state)
{
    (void)state;
    tu_quad q = {{1, 2, 3}, {2, 0, 0}, {0, 0, -2}, {0.25f, 0.5f, 0.75f, 1}, PF_ALPHA_OPAQUE, 0.5f};
    pf_scene s;
    tu_make_scene(&s, &q, 1);
    pf_error err;
    assert_int_equal(pf_scene_validate(&s, &err), PF_OK);
    pf_rt *rt;
    assert_int_equal(pf_rt_create(&rt, &s, pf_isa_detect(), 1, &err), PF_OK);
    pf_ray r = {{1.5f, 10, 2.5f}, 0.0f, {0, -1, 0}, INFINITY};
    pf_hit h = pf_rt_intersect1(rt, r);
    assert_int_not_equal(h.prim, PF_RT_MISS);
    assert_float_equal(h.t, 8.0f, 1e-5f);
    pf_surface sf;
    pf_rt_surface(rt, &h, 0.0f, &sf);
    assert_float_equal(sf.p.x, 1.5f, 1e-5f);
    assert_float_equal(sf.p.y, 2.0f, 1e-5f);
    assert_float_equal(sf.p.z, 2.5f, 1e-5f);
    assert_float_equal(sf.ng.y, 1.0f, 1e-6f);
    assert_float_equal(sf.ns.y, 1.0f, 1e-6f);
    assert_float_equal(sf.albedo[0], 0.25f, 0.0f);
    assert_float_equal(sf.albedo[2], 0.75f, 0.0f);
    /* uv: quad corners (0,0)..(1,1) over x in [-1,3], z in [5,1] */
    assert_float_equal(sf.uv.x, (1.5f + 1.0f) / 4.0f, 1e-5f);
    assert_float_equal(sf.uv.y, (5.0f - 2.5f) / 4.0f, 1e-5f);
    /* offset origins leave the surface on the requested side */
    pf_vec3 up = pf_rt_offset_origin(sf.p, sf.ng, pf_v3(0, 1, 0));
    pf_vec3 dn = pf_rt_offset_origin(sf.p, sf.ng, pf_v3(0, -1, 0));
    assert_true(up.y > 2.0f && dn.y < 2.0f);
    pf_rt_destroy(rt);
    pf_scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_single_vs_packet_cornell),
        cmocka_unit_test(test_single_vs_packet_sibenik),
        cmocka_unit_test(test_build_threads_and_isa),
        cmocka_unit_test(test_alpha_mask),
        cmocka_unit_test(test_surface),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
