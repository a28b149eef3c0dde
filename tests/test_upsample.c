/* test_upsample: the indirect stages at reduced resolution
 * (gi_indirect_options.scale, --indirect-scale; gi_stage_upsample):
 * - on the Cornell box with every VPL at every pixel (1 x 1 tiles), scale 2
 *   stays close to scale 1: the upsampled irradiance's energy within 3% and
 *   its mean relative difference per pixel under 5%;
 * - a frame pixel that is a sample (2X, 2Y) gets its sample's filtered value
 *   exactly; the indirect image is (width / 2) x (height / 2), rounded up;
 * - the same bytes with 1 and 2 threads, and on every SIMD path;
 * - every view renders and the mosaic's pixel mapping round-trips;
 * - a scale out of range is a clear error. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi_frame.h"
#include "gi_view.h"
#include "pf_gltf.h"
#include "pf_isa.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 161 /* odd: the last sample column and row are partial */
#define H 121

static void render_simd(tu_fx *x, uint32_t threads, uint32_t scale, int no_interleave, rs_simd simd)
{
    tu_load(&x->scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 256;
    io.scale = scale;
    io.no_interleave = no_interleave;
    tu_fx_begin(x, threads, simd, W, H, &x->scene.cameras[0], &io, 1);
    gi_frame_render_raster(&x->f);
}

static void render(tu_fx *x, uint32_t threads, uint32_t scale, int no_interleave)
{
    render_simd(x, threads, scale, no_interleave, RS_SIMD_SCALAR);
}

static void test_close_to_full_resolution(void **state)
{
    (void)state;
    tu_fx a, b;
    /* every pixel sees every VPL (1 x 1 tiles): the two differ only by the
     * resolution, not by which VPLs a pixel's tile got */
    render(&a, 2, 1, 1);
    render(&b, 2, 2, 1);
    assert_int_equal(b.f.ind.w, (W + 1) / 2);
    assert_int_equal(b.f.ind.h, (H + 1) / 2);
    double ea = 0, eb = 0, rel = 0;
    uint32_t n = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        if (a.f.gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
        double la = 0, lb = 0;
        for (int c = 0; c < 3; c++) la += a.f.ind.filtered[3 * i + c], lb += b.f.ind.filtered[3 * i + c];
        ea += la, eb += lb;
        if (la > 0) rel += fabs(lb - la) / la, n++;
    }
    rel /= n;
    print_message("scale 2 against 1: energy %.4f, mean relative difference %.4f over %u pixels\n", eb / ea, rel, n);
    assert_true(fabs(eb / ea - 1.0) < 0.03);
    assert_true(rel < 0.05);
    /* sample pixels take their sample's value exactly */
    for (uint32_t Y = 0; Y < b.f.ind.h; Y++)
        for (uint32_t X = 0; X < b.f.ind.w; X++) {
            size_t i = (size_t)(2 * Y) * W + 2 * X, k = (size_t)Y * b.f.ind.w + X;
            if (b.f.gbuf.prim[i] == RS_GBUFFER_EMPTY) continue;
            assert_memory_equal(b.f.ind.filtered + 3 * i, b.f.ind.filtered_low + 3 * k, 3 * sizeof(float));
        }
    tu_fx_end(&a);
    tu_fx_end(&b);
}

static void test_threads(void **state)
{
    (void)state;
    tu_fx a, b;
    render(&a, 1, 2, 0);
    render(&b, 2, 2, 0);
    assert_memory_equal(a.f.final, b.f.final, (size_t)W * H * 3 * sizeof(float));
    assert_memory_equal(a.f.ind.filtered, b.f.ind.filtered, (size_t)W * H * 3 * sizeof(float));
    tu_fx_end(&a);
    tu_fx_end(&b);
}

/* The SIMD paths' upsampling (gi__upsample, runs of 8 or 16 pixels, and
 * the pixel-by-pixel rest of each row) gives the scalar path's bits, at
 * scales 2 and 3 on an odd size. */
static void test_simd_identical(void **state)
{
    (void)state;
    pf_isa isa = pf_isa_detect();
    for (uint32_t scale = 2; scale <= 3; scale++) {
        tu_fx a;
        render_simd(&a, 2, scale, 0, RS_SIMD_SCALAR);
        for (int p = 0; p < 2; p++) {
            rs_simd simd = p ? RS_SIMD_AVX512 : RS_SIMD_AVX2;
            if (isa < (p ? PF_ISA_AVX512 : PF_ISA_AVX2)) continue;
            tu_fx b;
            render_simd(&b, 2, scale, 0, simd);
            assert_memory_equal(a.f.ind.filtered_low, b.f.ind.filtered_low,
                                (size_t)a.f.ind.w * a.f.ind.h * 3 * sizeof(float));
            size_t differ = 0;
            for (size_t i = 0; i < (size_t)W * H * 3; i++)
                differ += memcmp(&a.f.ind.filtered[i], &b.f.ind.filtered[i], sizeof(float)) != 0;
            if (differ) fail_msg("scale %u, %s: %zu upsampled values differ from the scalar path", scale,
                                 rs_simd_name(simd), differ);
            tu_fx_end(&b);
        }
        tu_fx_end(&a);
    }
}

static void test_views(void **state)
{
    (void)state;
    tu_fx x;
    render(&x, 2, 3, 0);
    uint8_t *rgb = malloc((size_t)W * H * 3);
    assert_non_null(rgb);
    for (int v = 0; v < GI_VIEW_COUNT; v++) gi_view_render(&x.f, (gi_view_id)v, NULL, rgb);
    /* frame pixel -> mosaic -> the sample's frame pixel */
    uint32_t mapped = 0;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t xx = 0; xx < W; xx++) {
            uint32_t u, v, fx, fy;
            if (!gi_view_view_pixel(&x.f, GI_VIEW_ACCUMULATED, xx, y, &u, &v)) continue;
            assert_true(gi_view_frame_pixel(&x.f, GI_VIEW_ACCUMULATED, u, v, &fx, &fy));
            assert_int_equal(fx, xx / 3 * 3);
            assert_int_equal(fy, y / 3 * 3);
            mapped++;
        }
    assert_int_equal(mapped, W * H);
    free(rgb);
    tu_fx_end(&x);
}

static void test_bad_scale(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.scale = GI_INDIRECT_MAX_SCALE + 1;
    tu_fx_begin(&x, 1, RS_SIMD_SCALAR, 32, 24, &x.scene.cameras[0], NULL, 0);
    pf_error err;
    assert_int_equal(gi_frame_enable_indirect(&x.f, &io, 0, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "scale"));
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_close_to_full_resolution),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_simd_identical),
        cmocka_unit_test(test_views),
        cmocka_unit_test(test_bad_scale),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
