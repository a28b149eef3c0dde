/* test_temporal: temporal accumulation with reprojection and rotated VPL
 * groups (gi_indirect_options.temporal, gi_stage_temporal):
 * - static camera and light, no filter: after T frames (T = n m tiles, the
 *   history as long) every pixel has averaged every tile's group of VPLs,
 *   so the irradiance equals the one without interleaving (every pixel
 *   every VPL) up to float rounding;
 * - a small camera move keeps most pixels' history (reprojection), a turn
 *   to look the other way restarts it everywhere;
 * - the same at half resolution (--indirect-scale 2: the stage runs on the
 *   reduced image before the upsampling): converged to every-VPL shading,
 *   and a small step keeps most reduced pixels' history;
 * - the same bytes with 1 and 2 threads over a moving camera;
 * - a history of 1 frame is refused with a clear message. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "pf_gltf.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 96
#define H 72

static void begin_scaled(tu_fx *x, uint32_t threads, uint32_t temporal, int no_interleave, uint32_t scale)
{
    tu_load(&x->scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 64;
    io.filter = GI_FILTER_NONE;
    io.temporal = temporal;
    io.no_interleave = no_interleave;
    io.scale = scale;
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, W, H, &x->scene.cameras[0], &io, 1);
}

static void begin(tu_fx *x, uint32_t threads, uint32_t temporal, int no_interleave)
{
    begin_scaled(x, threads, temporal, no_interleave, 1);
}

static void converges(uint32_t scale)
{
    tu_fx all, t;
    begin_scaled(&all, 2, 0, 1, scale);
    gi_frame_render_raster(&all.f);
    begin_scaled(&t, 2, 16, 0, scale);
    assert_int_equal(t.f.ind.scale, scale);
    double first = 0.0;
    for (int k = 0; k < 16; k++) {
        gi_frame_render_raster(&t.f);
        if (k == 0 || k == 15) {
            double rel = tu_mean_rel_green(all.f.ind.filtered, t.f.ind.filtered, (size_t)W * H);
            print_message("scale %u, after %d frame(s): mean relative difference to every-VPL shading %.6f\n", scale,
                          k + 1, rel);
            if (k == 0) first = rel;
            else {
                assert_true(rel < 1e-4);
                assert_true(first > 0.05); /* one interleaved frame is far from it */
            }
        }
    }
    tu_fx_end(&all);
    tu_fx_end(&t);
}

static void test_converges_to_every_vpl(void **state)
{
    (void)state;
    converges(1);
    converges(2); /* the upsampling is linear in the irradiance: it keeps the equality */
}

/* Pixels (of the indirect image) whose history survived the last frame. */
static uint32_t kept(const gi_frame *f)
{
    const uint16_t *n = f->ind.hist_n[f->ind.hist_cur];
    uint32_t c = 0;
    for (size_t i = 0; i < (size_t)f->ind.w * f->ind.h; i++) c += n[i] > 1;
    return c;
}

static void reprojection(uint32_t scale)
{
    tu_fx t;
    begin_scaled(&t, 2, 8, 0, scale);
    gi_frame_render_raster(&t.f);
    const rs_gbuffer *g = scale > 1 ? &t.f.ind.low : &t.f.gbuf;
    uint32_t surfaces = 0;
    for (size_t i = 0; i < (size_t)t.f.ind.w * t.f.ind.h; i++) surfaces += g->prim[i] != RS_GBUFFER_EMPTY;
    /* a small sideways step */
    t.f.camera.eye = pf_v3_add(t.f.camera.eye, pf_v3_scale(t.f.camera.right, 0.02f));
    gi_frame_render_raster(&t.f);
    print_message("after a small step: %u of %u pixels keep their history\n", kept(&t.f), surfaces);
    assert_true(kept(&t.f) > surfaces * 8 / 10);
    /* look the other way: nothing seen now was seen last frame where it is now */
    t.f.camera.forward = pf_v3_scale(t.f.camera.forward, -1.0f);
    t.f.camera.right = pf_v3_scale(t.f.camera.right, -1.0f);
    gi_frame_render_raster(&t.f);
    print_message("after turning around: %u pixels keep their history\n", kept(&t.f));
    assert_true(kept(&t.f) < surfaces / 50);
    tu_fx_end(&t);
}

static void test_reprojection(void **state)
{
    (void)state;
    reprojection(1);
    reprojection(2);
}

static void test_threads(void **state)
{
    (void)state;
    tu_fx a, b;
    begin(&a, 1, 8, 0);
    begin(&b, 2, 8, 0);
    for (int k = 0; k < 5; k++) {
        pf_vec3 step = pf_v3_scale(a.f.camera.right, 0.01f * (float)k);
        a.f.camera.eye = pf_v3_add(a.f.camera.eye, step);
        b.f.camera.eye = pf_v3_add(b.f.camera.eye, step);
        gi_frame_render_raster(&a.f);
        gi_frame_render_raster(&b.f);
        assert_memory_equal(a.f.final, b.f.final, (size_t)W * H * 3 * sizeof(float));
    }
    tu_fx_end(&a);
    tu_fx_end(&b);
}

static void test_bad_length(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    tu_fx_begin(&x, 1, RS_SIMD_SCALAR, 32, 24, &x.scene.cameras[0], NULL, 0);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.temporal = 1;
    pf_error err;
    assert_int_equal(gi_frame_enable_indirect(&x.f, &io, 0, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "temporal"));
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_converges_to_every_vpl),
        cmocka_unit_test(test_reprojection),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_bad_length),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
