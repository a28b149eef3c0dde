/* test_render: the ray-traced frame end to end on the Cornell box.
 * - determinism: every buffer of the frame is bit-identical with 1, 2 and 7
 *   threads (and with Embree built by 1 or 2 threads);
 * - golden hash: the linear output at --isa sse2 (pinned so it matches on
 *   any x86-64 CPU) equals the recorded value, with its picture in
 *   tests/data/golden/render-cornell.png (tu_golden.h); a change in it is a
 *   change in what softgi renders and must be deliberate (update the
 *   constant and the picture, docs/testing.md, and say why in the commit);
 * - sanity: the walls show their colours (red left, green right). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "gi_frame.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "test_frame_fixture.h"
#include "test_util.h"
#include "tu_golden.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 160
#define H 120

/* Golden: softgi render --isa sse2 --size 160x120 --hash (embedded Cornell box).
 * The same for every --isa and every processor: the rasterizer's SIMD paths
 * give the scalar bits, and pf_rt recomputes Embree's hits exactly. */
#define GOLDEN_CORNELL_SSE2 0xd27a2abb3d83b029ull

static uint64_t frame_hash(const gi_frame *f)
{
    uint64_t n = (uint64_t)f->width * f->height;
    const rs_gbuffer *g = &f->gbuf;
    const float *planes[] = {g->depth, g->pos_x, g->pos_y, g->pos_z, g->nrm_x, g->nrm_y,
                             g->nrm_z, g->alb_r, g->alb_g, g->alb_b, (const float *)g->prim};
    uint64_t h = pf_imageio_hash(f->final, 3 * n) ^ pf_imageio_hash(f->direct, 3 * n) * 3;
    for (size_t i = 0; i < sizeof planes / sizeof planes[0]; i++) h = h * 31 + pf_imageio_hash(planes[i], n);
    return h;
}

/* The ray-traced frame of the Cornell box with Embree at `isa`, built by
 * `build_threads`, rendered by `threads`. */
static uint64_t render(pf_isa isa, uint32_t threads, uint32_t build_threads, uint64_t *final_hash, float *out_final)
{
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    assert_true(x.scene.camera_count >= 1);
    tu_fx_desc d = {.threads = threads, .no_raster = 1, .isa = isa, .build_threads = build_threads, .w = W, .h = H,
                    .shadow_size = 1024};
    tu_fx_begin_with(&x, &d);
    gi_frame_render_raytraced(&x.f);
    uint64_t h = frame_hash(&x.f);
    *final_hash = pf_imageio_hash(x.f.final, 3ull * W * H);
    if (out_final) memcpy(out_final, x.f.final, sizeof(float) * 3 * W * H);
    tu_fx_end(&x);
    return h;
}

static void test_threads_identical(void **state)
{
    (void)state;
    uint64_t f1, f2, f7, fb;
    uint64_t h1 = render(PF_ISA_SSE2, 1, 1, &f1, NULL);
    uint64_t h2 = render(PF_ISA_SSE2, 2, 2, &f2, NULL);
    uint64_t h7 = render(PF_ISA_SSE2, 7, 1, &f7, NULL);
    uint64_t hb = render(pf_isa_detect(), 2, 2, &fb, NULL);
    assert_true(h1 == h2);
    assert_true(h1 == h7);
    assert_true(h1 == hb); /* Embree at the machine's best ISA: same bits (pf_rt's exact hits) */
}

static void test_golden_and_colours(void **state)
{
    (void)state;
    static float img[3 * W * H];
    uint64_t fh;
    render(PF_ISA_SSE2, 2, 2, &fh, img);
    tu_golden_picture pic;
    tu_golden_picture_init(&pic, W, H);
    tu_golden_put_linear(&pic, 0, 0, img, W, H, 0.0f);
    tu_golden_check("render-cornell", fh, GOLDEN_CORNELL_SSE2, &pic);
    tu_golden_picture_free(&pic);
    /* the middle row crosses the red wall on the left and the green one on the right */
    const float *l = &img[3 * ((H / 2) * W + W / 5)], *r = &img[3 * ((H / 2) * W + W - 1 - W / 5)];
    assert_true(l[0] > 2.0f * l[1] && l[0] > 2.0f * l[2]);
    assert_true(r[1] > 1.5f * r[0] && r[1] > 1.5f * r[2]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_identical),
        cmocka_unit_test(test_golden_and_colours),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
