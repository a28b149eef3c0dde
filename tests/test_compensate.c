/* test_compensate: the screen-space compensation of the clamp's bias
 * (gi_indirect_options.compensate, gi_stage_compensate; the survey's
 * Sec. 5.2 after Novak 2011):
 * - on the Cornell box the clamped image loses indirect energy against the
 *   unclamped one, and the compensated image recovers most of it;
 * - with the clamp off the compensation adds nothing (bit for bit);
 * - the same bytes with 1 and 2 threads;
 * - a tap count out of range is a clear error. */
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
#define W 160
#define H 120

static void render(tu_fx *x, uint32_t threads, float clamp, int compensate)
{
    tu_load(&x->scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 256;
    io.clamp = clamp;
    io.compensate = compensate;
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, W, H, &x->scene.cameras[0], &io, 1);
    gi_frame_render_raster(&x->f);
}

/* The indirect light's energy: luminance of albedo / pi x E summed. */
static double energy(const gi_frame *f)
{
    double e = 0.0;
    for (size_t i = 0; i < (size_t)W * H; i++) e += pf_luminance(pf_v3(f->final[3 * i], f->final[3 * i + 1], f->final[3 * i + 2]));
    return e;
}

static void test_recovers_energy(void **state)
{
    (void)state;
    tu_fx u, c, k;
    render(&u, 2, 0.0f, 0);  /* unclamped */
    render(&c, 2, -1.0f, 0); /* the default clamp */
    render(&k, 2, -1.0f, 1); /* the default clamp, compensated */
    double eu = energy(&u.f), ec = energy(&c.f), ek = energy(&k.f);
    print_message("indirect energy against unclamped: clamped %.4f, compensated %.4f\n", ec / eu, ek / eu);
    assert_true(ec / eu < 0.995);
    assert_true(fabs(ek / eu - 1.0) < fabs(ec / eu - 1.0) / 2.0);
    tu_fx_end(&u);
    tu_fx_end(&c);
    tu_fx_end(&k);
}

static void test_nothing_without_clamp(void **state)
{
    (void)state;
    tu_fx a, b;
    render(&a, 2, 0.0f, 0);
    render(&b, 2, 0.0f, 1);
    assert_memory_equal(a.f.final, b.f.final, (size_t)W * H * 3 * sizeof(float));
    tu_fx_end(&a);
    tu_fx_end(&b);
}

static void test_threads(void **state)
{
    (void)state;
    tu_fx a, b;
    render(&a, 1, -1.0f, 1);
    render(&b, 2, -1.0f, 1);
    assert_memory_equal(a.f.final, b.f.final, (size_t)W * H * 3 * sizeof(float));
    tu_fx_end(&a);
    tu_fx_end(&b);
}

static void test_bad_taps(void **state)
{
    (void)state;
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    tu_fx_begin(&x, 1, RS_SIMD_SCALAR, 32, 24, &x.scene.cameras[0], NULL, 0);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.compensate = 1;
    io.compensate_taps = 5000;
    pf_error err;
    assert_int_equal(gi_frame_enable_indirect(&x.f, &io, 0, &err), PF_ERR_ARGUMENT);
    assert_non_null(strstr(err.message, "taps"));
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_recovers_energy),
        cmocka_unit_test(test_nothing_without_clamp),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_bad_taps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
