/* test_vpl_cycle: VPL cycling (gi_indirect_options.cycle, gi_indirect.h):
 * a set of C x vpls VPLs, one slice of vpls shaded a frame, averaged by the
 * temporal history.
 * - static camera and light, no filter: after T C frames (T = n m tiles,
 *   the history as long) every pixel has seen every group of every slice
 *   once, so the irradiance equals the one of the whole set without
 *   interleaving (every pixel every one of the C x vpls VPLs) up to float
 *   rounding; one cycled frame is far from it;
 * - every map is drawn once: vpls a frame in the first C frames, none
 *   after (a static scene); the same with pipelining;
 * - the same bytes with 1 and 2 threads, and on the SIMD path as on the
 *   scalar one, over frames with a moving light (moved VPLs' maps drawn
 *   when their slice comes);
 * - the progressive warm-up (cycle_maps B): slice 0's maps in frame 0,
 *   then B maps a frame drawn ahead, a slice joining the rotation once its
 *   maps are there, only slices in the rotation shaded, every map drawn
 *   once, and the history still converging to the whole set; the same
 *   bytes with 1 and 2 threads and on the SIMD path;
 * - SMC's chains (gi_smc.c "VPL cycling") follow the frames' slices: with
 *   the progressive warm-up, pipelined or not, a frame's set differs from
 *   the last one only in the slice it shades and in chains made for the
 *   first time, slices past the rotation (and the one drawn ahead, and
 *   pipelined one more) stay empty, and the shaded slice's chain changes;
 * - cycling without --temporal, with imperfect shadow maps, or over too
 *   many slices, and the warm-up without cycling, are refused with a clear
 *   message. */
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
#include "pf_isa.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 96
#define H 72
#define VPLS 32u
#define CYCLE 4u

static void begin_method(tu_fx *x, uint32_t threads, rs_simd simd, uint32_t vpls, uint32_t cycle, uint32_t temporal,
                         int no_interleave, int pipeline, uint32_t cycle_maps, const char *method,
                         const char *const *params)
{
    tu_load(&x->scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    pf_error err;
    if (method) io.method = gi_vpl_method_find(method);
    for (const char *const *p = params; p && *p; p++) assert_int_equal(gi_params_add(&io.params, *p, &err), PF_OK);
    io.vpls = vpls;
    io.filter = GI_FILTER_NONE;
    io.temporal = temporal;
    io.cycle = cycle;
    io.no_interleave = no_interleave;
    io.pipeline = pipeline;
    io.cycle_maps = cycle_maps;
    tu_fx_begin(x, threads, simd, W, H, &x->scene.cameras[0], &io, 1);
}

static void begin_warm(tu_fx *x, uint32_t threads, rs_simd simd, uint32_t vpls, uint32_t cycle, uint32_t temporal,
                       int no_interleave, int pipeline, uint32_t cycle_maps)
{
    begin_method(x, threads, simd, vpls, cycle, temporal, no_interleave, pipeline, cycle_maps, NULL, NULL);
}

static void begin_piped(tu_fx *x, uint32_t threads, rs_simd simd, uint32_t vpls, uint32_t cycle, uint32_t temporal,
                        int no_interleave, int pipeline)
{
    begin_warm(x, threads, simd, vpls, cycle, temporal, no_interleave, pipeline, 0);
}

static void begin(tu_fx *x, uint32_t threads, rs_simd simd, uint32_t vpls, uint32_t cycle, uint32_t temporal,
                  int no_interleave)
{
    begin_piped(x, threads, simd, vpls, cycle, temporal, no_interleave, 0);
}

static double mean_rel(const float *a, const float *b) { return tu_mean_rel_green(a, b, (size_t)W * H); }

static void converges(int pipeline)
{
    tu_fx all, t;
    begin(&all, 2, RS_SIMD_SCALAR, VPLS * CYCLE, 0, 0, 1); /* the whole set, every VPL at every pixel */
    gi_frame_render_raster(&all.f);
    const uint32_t frames = 16u * CYCLE; /* 4 x 4 tiles */
    begin_piped(&t, 2, RS_SIMD_SCALAR, VPLS, CYCLE, frames, 0, pipeline);
    uint32_t maps = 0;
    for (uint32_t k = 0; k < frames; k++) {
        gi_frame_render_raster(&t.f);
        assert_int_equal(t.f.ind.vpls.count, all.f.ind.vpls.count); /* the method made the whole set */
        uint32_t drawn = t.f.ind.maps_rendered;
        maps += drawn;
        if (k < CYCLE) assert_int_equal(drawn, (t.f.ind.vpls.count - k + CYCLE - 1) / CYCLE); /* slice k's */
        else assert_int_equal(drawn, 0);
        if (k == 0 || k == frames - 1) {
            double rel = mean_rel(all.f.ind.filtered, t.f.ind.filtered);
            print_message("pipeline %d, after %u frame(s): mean relative difference to the whole set at every "
                          "pixel %.6f\n",
                          pipeline, k + 1, rel);
            if (k == 0) assert_true(rel > 0.05); /* one slice of one group is far from it */
            else assert_true(rel < 2e-4);
        }
    }
    assert_int_equal(maps, all.f.ind.vpls.count); /* each map drawn once */
    tu_fx_end(&all);
    tu_fx_end(&t);
}

/* Unpipelined, and pipelined (frame N shades the set made during frame
 * N - 1, gi_indirect.h: a static light's set is the same, and each slice's
 * maps must still be drawn when its turn comes). */
static void test_converges_to_the_whole_set(void **state)
{
    (void)state;
    converges(0);
    converges(1);
}

/* Without cycling the history of T frames converges to the per-frame set,
 * not to the whole one: the cycled frames' extra VPLs are what brings it
 * there (the test above could otherwise pass with the cycling ignored). */
static void test_without_cycling_it_stays_apart(void **state)
{
    (void)state;
    tu_fx all, t;
    begin(&all, 2, RS_SIMD_SCALAR, VPLS * CYCLE, 0, 0, 1);
    gi_frame_render_raster(&all.f);
    begin(&t, 2, RS_SIMD_SCALAR, VPLS, 0, 16, 0);
    for (int k = 0; k < 16; k++) gi_frame_render_raster(&t.f);
    double rel = mean_rel(all.f.ind.filtered, t.f.ind.filtered);
    print_message("%u VPLs over 16 frames against %u at every pixel: %.4f\n", VPLS, VPLS * CYCLE, rel);
    assert_true(rel > 0.02);
    tu_fx_end(&all);
    tu_fx_end(&t);
}

/* The progressive warm-up with B maps a frame ahead: the maps each frame
 * draws, the rotation growing by a slice once its maps are all there, only
 * slices in it shaded, each map drawn once; and each frame's accumulated
 * irradiance, before the filter and the history, equals bit for bit the
 * frame without the warm-up that shades the same slice for the same time
 * (frame a C + s shades slice s for the a-th time, the groups rotated by
 * a + s): so a warm-up frame reads no map before it is drawn, weights its
 * slice as the plain cycle does, and the history converges to the whole
 * set as test_converges_to_the_whole_set shows for those frames. */
static void test_progressive_warmup(void **state)
{
    (void)state;
    enum { B = 5, ROUNDS = 4 };
    const size_t px3 = (size_t)W * H * 3;
    tu_fx plain, t;
    begin(&plain, 2, RS_SIMD_SCALAR, VPLS, CYCLE, 16, 0);
    float *want = malloc(ROUNDS * CYCLE * px3 * sizeof(float));
    assert_non_null(want);
    for (uint32_t k = 0; k < ROUNDS * CYCLE; k++) {
        gi_frame_render_raster(&plain.f);
        memcpy(want + k * px3, plain.f.ind.combined, px3 * sizeof(float));
    }
    const uint32_t N = plain.f.ind.vpls.count;
    tu_fx_end(&plain);
    begin_warm(&t, 2, RS_SIMD_SCALAR, VPLS, CYCLE, 16, 0, 0, B);
    /* slice s holds the slots s, s + C, ...: (N - s + C - 1) / C of them */
    uint32_t maps = 0, want_live = 1, left = (N - 1 + CYCLE - 1) / CYCLE, shaded[CYCLE] = {0}, compared = 0;
    for (uint32_t k = 0; k < 60; k++) {
        const uint32_t live = t.f.ind.cycle_live;
        assert_int_equal(live, want_live);
        gi_frame_render_raster(&t.f);
        const uint32_t drawn = t.f.ind.maps_rendered, s = t.f.ind.slice;
        assert_int_equal(t.f.ind.vpls.count, N);
        assert_true(s < live); /* only slices in the rotation */
        assert_int_equal(t.f.ind.cycle_base, shaded[s]);
        /* frame 0: slice 0's maps; every frame: B of slice `live` ahead,
         * which joins the rotation once all its maps are there */
        uint32_t ahead = live < CYCLE ? (left < B ? left : B) : 0;
        assert_int_equal(drawn, (k == 0 ? (N + CYCLE - 1) / CYCLE : 0) + ahead);
        assert_int_equal(t.f.ind.maps_ahead, ahead);
        maps += drawn;
        left -= ahead;
        if (live < CYCLE && !left) {
            want_live = live + 1;
            if (want_live < CYCLE) left = (N - want_live + CYCLE - 1) / CYCLE;
        }
        if (shaded[s] < ROUNDS) {
            assert_memory_equal(t.f.ind.combined, want + (shaded[s] * CYCLE + s) * px3, px3 * sizeof(float));
            compared++;
        }
        shaded[s]++;
    }
    assert_int_equal(want_live, CYCLE);
    assert_int_equal(maps, N); /* each map drawn once */
    assert_int_equal(compared, ROUNDS * CYCLE); /* every slice shaded at least ROUNDS times */
    print_message("warm-up of %u maps a frame: slices shaded %u %u %u %u times in 60 frames, %u frames equal to the "
                  "plain cycle's\n",
                  (unsigned)B, shaded[0], shaded[1], shaded[2], shaded[3], compared);
    free(want);
    tu_fx_end(&t);
}

static void chains_follow(int pipeline)
{
    static const char *const params[] = {"spp=4", "chain_warmup=2", NULL};
    tu_fx t;
    begin_method(&t, 2, RS_SIMD_SCALAR, VPLS, CYCLE, 16, 0, pipeline, 8, "smc", params);
    const uint32_t N = VPLS * CYCLE;
    gi_vpl *prev = calloc(N, sizeof *prev);
    assert_non_null(prev);
    uint32_t changed_frames = 0, made = 0;
    for (uint32_t k = 0; k < 40; k++) {
        const uint32_t live = t.f.ind.cycle_live;
        gi_frame_render_raster(&t.f);
        const gi_vpl *v = t.f.ind.vpls.v;
        const uint32_t s = t.f.ind.slice;
        assert_int_equal(t.f.ind.vpls.count, N);
        uint32_t in_slice = 0;
        for (uint32_t i = 0; i < N; i++) {
            const uint32_t c = i % CYCLE;
            if (c >= live + 1u + (pipeline ? 1u : 0u)) assert_int_equal(v[i].id, 0xffffffffu); /* not made yet */
            gi_vpl a = v[i], b = prev[i];
            a.moved = b.moved = 0; /* cleared in the slots an update leaves */
            if (k == 0 || !memcmp(&a, &b, sizeof a)) continue;
            if (c == s) {
                in_slice++;
                continue;
            }
            /* another slice changes only when its chain is made */
            assert_int_equal(prev[i].id, 0xffffffffu);
            made++;
        }
        changed_frames += in_slice > 0;
        memcpy(prev, v, N * sizeof *v);
    }
    print_message("smc chains%s: the shaded slice changed in %u of 39 frames, %u slots of new chains\n",
                  pipeline ? ", pipelined" : "", changed_frames, made);
    assert_true(changed_frames >= 30);
    assert_true(made >= VPLS); /* at least one chain made after frame 0 */
    assert_int_equal(t.f.ind.cycle_live, CYCLE);
    free(prev);
    tu_fx_end(&t);
}

static void test_smc_chains_follow_the_slice(void **state)
{
    (void)state;
    chains_follow(0);
    chains_follow(1);
}

/* The light moves every frame: every VPL moves, and each slice's maps are
 * drawn when its turn comes; 1 and 2 threads, scalar and SIMD, same bytes;
 * with and without the progressive warm-up. */
static void threads_and_simd(uint32_t cycle_maps)
{
    tu_fx a, b, c;
    begin_warm(&a, 1, RS_SIMD_SCALAR, VPLS, CYCLE, 8, 0, 0, cycle_maps);
    begin_warm(&b, 2, RS_SIMD_SCALAR, VPLS, CYCLE, 8, 0, 0, cycle_maps);
    pf_isa isa = pf_isa_detect();
    rs_simd best = isa >= PF_ISA_AVX512 ? RS_SIMD_AVX512 : isa >= PF_ISA_AVX2 ? RS_SIMD_AVX2 : RS_SIMD_SCALAR;
    begin_warm(&c, 2, best, VPLS, CYCLE, 8, 0, 0, cycle_maps);
    for (int k = 0; k < 6; k++) {
        tu_fx *x[3] = {&a, &b, &c};
        for (int j = 0; j < 3; j++) {
            if (k >= 3) x[j]->scene.lights[0].position.x += 0.02f; /* moves from frame 3 on */
            gi_frame_render_raster(&x[j]->f);
        }
        assert_memory_equal(a.f.final, b.f.final, (size_t)W * H * 3 * sizeof(float));
        assert_memory_equal(a.f.final, c.f.final, (size_t)W * H * 3 * sizeof(float));
        if (k >= 3) assert_true(a.f.ind.maps_rendered > 0); /* the moved slice's maps */
    }
    tu_fx_end(&a);
    tu_fx_end(&b);
    tu_fx_end(&c);
}

static void test_threads_and_simd(void **state)
{
    (void)state;
    threads_and_simd(0);
    threads_and_simd(3);
}

static void refused(const gi_indirect_options *io, const char *says)
{
    tu_fx x;
    tu_load(&x.scene, CORNELL);
    tu_fx_begin(&x, 1, RS_SIMD_SCALAR, 32, 24, &x.scene.cameras[0], NULL, 0);
    pf_error err;
    assert_int_equal(gi_frame_enable_indirect(&x.f, io, 0, &err), PF_ERR_ARGUMENT);
    print_message("refused: %s\n", err.message);
    assert_non_null(strstr(err.message, says));
    tu_fx_end(&x);
}

static void test_bad_options(void **state)
{
    (void)state;
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.cycle = 4;
    refused(&io, "--temporal");
    io.temporal = 8;
    io.visibility_ism = 1;
    refused(&io, "imperfect shadow maps");
    io.visibility_ism = 0;
    io.cycle = GI_INDIRECT_MAX_CYCLE + 1;
    refused(&io, "slices");
    io.cycle = GI_INDIRECT_MAX_CYCLE;
    io.vpls = GI_INDIRECT_MAX_SET / 8;
    refused(&io, "set of more than");
    memset(&io, 0, sizeof io);
    io.temporal = 8;
    io.cycle_maps = 16;
    refused(&io, "needs --vpl-cycle");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_converges_to_the_whole_set),
        cmocka_unit_test(test_without_cycling_it_stays_apart),
        cmocka_unit_test(test_progressive_warmup),
        cmocka_unit_test(test_threads_and_simd),
        cmocka_unit_test(test_smc_chains_follow_the_slice),
        cmocka_unit_test(test_bad_options),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
