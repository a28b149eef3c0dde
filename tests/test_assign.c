/* test_assign: the VPL-to-tile assignment (gi_stage_assign; Laine 2007
 * Sec. 7: VPLs dealt to the interleave tiles in a stable order).
 * - every emitting VPL is in exactly one tile, dark slots in none;
 * - a set with no survivor is dealt by luminance in boustrophedon order:
 *   the brightest T VPLs land one per tile;
 * - survivors keep their tile while every intensity changes; a new VPL goes
 *   to the tile with the least luminance; a slot whose id changed, or that
 *   is marked moved, counts as new; a dark slot revived gets a tile;
 * - assigning the same set twice gives the same tiles (idempotent: frames
 *   rendered twice, and the pipelined frame, see the same assignment);
 * - SMC over 24 frames of a static scene: no survivor ever changes tile,
 *   and the stage counts them (assign_kept). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "gi_frame.h"
#include "test_util.h"
#include "test_frame_fixture.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define T 16u /* the default 4 x 4 tiles */

/* A Cornell-box frame with indirect light on, 4 x 4 tiles, `method`. */
static void fx_begin(tu_fx *x, const char *method, uint32_t vpls)
{
    pf_error err;
    memset(x, 0, sizeof *x);
    if (pf_gltf_load(&x->scene, CORNELL, NULL, &err) != PF_OK) fail_msg("%s", err.message);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = gi_vpl_method_find(method);
    io.vpls = vpls;
    io.visibility_raytrace = 1; /* no maps: these tests look at the assignment */
    tu_fx_begin(x, 1, RS_SIMD_SCALAR, 48, 36, &x->scene.cameras[0], &io, 1);
}

/* Fills the frame's set with n VPLs: slot i has id 100 + i and luminance
 * about (i * 37 % n) + 1 (all distinct), slots in `dark` emit nothing. */
static void set_vpls(gi_frame *f, uint32_t n, uint32_t dark)
{
    pf_error err;
    assert_int_equal(gi_vpl_set_reserve(&f->ind.vpls, n, &err), PF_OK);
    for (uint32_t i = 0; i < n; i++) {
        gi_vpl *v = &f->ind.vpls.v[i];
        memset(v, 0, sizeof *v);
        float l = (float)((i * 37u) % n + 1u);
        v->pos = pf_v3(0.1f * (float)i, 1.0f, 0.0f);
        v->nrm = pf_v3(0, -1, 0);
        v->intensity = i % dark == dark - 1 ? pf_v3(0, 0, 0) : pf_v3(l, l, l);
        v->id = 100 + i;
        v->moved = 1;
    }
    f->ind.vpls.count = n;
}

static void clear_moved(gi_frame *f)
{
    for (uint32_t i = 0; i < f->ind.vpls.count; i++) f->ind.vpls.v[i].moved = 0;
}

static int emits(const gi_vpl *v) { return v->intensity.x > 0 || v->intensity.y > 0 || v->intensity.z > 0; }

/* The tile of each slot (UINT32_MAX: none), read from the stage's output
 * (assign / assign_start), checking that each slot appears at most once. */
static void tiles_of(const gi_indirect *ind, uint32_t *tile)
{
    for (uint32_t i = 0; i < ind->vpls.count; i++) tile[i] = UINT32_MAX;
    for (uint32_t t = 0; t < T; t++)
        for (uint32_t q = ind->assign_start[t]; q < ind->assign_start[t + 1]; q++) {
            uint32_t i = ind->assign[q];
            assert_true(i < ind->vpls.count);
            assert_int_equal(tile[i], UINT32_MAX);
            tile[i] = t;
        }
    for (uint32_t i = 0; i < ind->vpls.count; i++)
        assert_int_equal(tile[i] != UINT32_MAX, emits(&ind->vpls.v[i]));
}

static double tile_lum(const gi_indirect *ind, const uint32_t *tile, uint32_t t)
{
    double s = 0.0;
    for (uint32_t i = 0; i < ind->vpls.count; i++)
        if (tile[i] == t) s += pf_luminance(ind->vpls.v[i].intensity);
    return s;
}

static void test_first_deal(void **state)
{
    (void)state;
    tu_fx x;
    fx_begin(&x, "ir", 64);
    set_vpls(&x.f, 64, 8); /* 8 dark slots */
    gi_stage_assign(&x.f);
    uint32_t tile[64];
    tiles_of(&x.f.ind, tile);
    assert_int_equal(x.f.ind.assign_kept, 0);
    /* the T brightest land one per tile (round 0 of the deal) */
    uint32_t seen[T] = {0};
    for (uint32_t i = 0; i < 64; i++) {
        float l = x.f.ind.vpls.v[i].intensity.x;
        uint32_t brighter = 0;
        for (uint32_t j = 0; j < 64; j++) brighter += x.f.ind.vpls.v[j].intensity.x > l;
        if (emits(&x.f.ind.vpls.v[i]) && brighter < T) seen[tile[i]]++;
    }
    for (uint32_t t = 0; t < T; t++) assert_int_equal(seen[t], 1);
    /* 56 emitting VPLs over 16 tiles: 3 or 4 each */
    for (uint32_t t = 0; t < T; t++) {
        uint32_t c = x.f.ind.assign_start[t + 1] - x.f.ind.assign_start[t];
        assert_true(c == 3 || c == 4);
    }
    tu_fx_end(&x);
}

static void test_survivors_keep_tiles(void **state)
{
    (void)state;
    tu_fx x;
    fx_begin(&x, "ir", 64);
    gi_indirect *ind = &x.f.ind;
    set_vpls(&x.f, 64, 8);
    gi_stage_assign(&x.f);
    uint32_t before[64], after[64];
    tiles_of(ind, before);
    /* next frame: every intensity changes (reversing the order of
     * brightness), slot 5 is replaced (moved), slot 9 gets a new id without
     * the moved flag, dark slot 7 comes alive, slot 12 goes dark */
    clear_moved(&x.f);
    for (uint32_t i = 0; i < 64; i++) {
        gi_vpl *v = &ind->vpls.v[i];
        if (emits(v)) v->intensity = pf_v3_scale(pf_v3(1, 1, 1), 1000.0f / v->intensity.x);
    }
    ind->vpls.v[5].moved = 1, ind->vpls.v[5].id = 900;
    ind->vpls.v[5].intensity = pf_v3(5000, 5000, 5000); /* brighter than any tile's sum */
    ind->vpls.v[9].id = 901;
    ind->vpls.v[7].intensity = pf_v3(3, 3, 3);
    ind->vpls.v[12].intensity = pf_v3(0, 0, 0);
    /* the tile with the least survivor luminance, before the new ones */
    uint32_t surv[64];
    for (uint32_t i = 0; i < 64; i++) surv[i] = (i == 5 || i == 9 || i == 7 || i == 12) ? UINT32_MAX : before[i];
    uint32_t lightest = 0;
    for (uint32_t t = 1; t < T; t++)
        if (tile_lum(ind, surv, t) < tile_lum(ind, surv, lightest)) lightest = t;
    gi_stage_assign(&x.f);
    tiles_of(ind, after);
    uint32_t kept = 0;
    for (uint32_t i = 0; i < 64; i++)
        if (surv[i] != UINT32_MAX && emits(&ind->vpls.v[i])) assert_int_equal(after[i], before[i]), kept++;
    assert_int_equal(ind->assign_kept, kept);
    assert_int_equal(kept, 64 - 8 - 3); /* all but the dark, 5, 9 and 12 (7 was dark) */
    assert_int_equal(after[5], lightest); /* the brightest new one goes first, to the lightest tile */
    assert_int_equal(after[12], UINT32_MAX);
    assert_true(after[7] != UINT32_MAX && after[9] != UINT32_MAX);
    /* idempotent: the same set again gives the same tiles */
    uint32_t again[64];
    gi_stage_assign(&x.f);
    tiles_of(ind, again);
    assert_memory_equal(again, after, sizeof after);
    /* everything moved: dealt anew, exactly as a fresh frame deals it */
    for (uint32_t i = 0; i < 64; i++) ind->vpls.v[i].moved = 1;
    gi_stage_assign(&x.f);
    tiles_of(ind, again);
    assert_int_equal(ind->assign_kept, 0);
    tu_fx y;
    fx_begin(&y, "ir", 64);
    assert_int_equal(gi_vpl_set_reserve(&y.f.ind.vpls, 64, &(pf_error){0}), PF_OK);
    memcpy(y.f.ind.vpls.v, ind->vpls.v, 64 * sizeof(gi_vpl));
    y.f.ind.vpls.count = 64;
    gi_stage_assign(&y.f);
    tiles_of(&y.f.ind, after);
    assert_memory_equal(again, after, sizeof after);
    tu_fx_end(&y);
    tu_fx_end(&x);
}

/* SMC re-estimates every intensity every frame and replaces a few VPLs:
 * with a static camera and light, no survivor may change tile. */
static void test_smc_frames(void **state)
{
    (void)state;
    tu_fx x;
    fx_begin(&x, "smc", 256);
    gi_indirect *ind = &x.f.ind;
    uint32_t prev_tile[256], prev_id[256], tile[256], prev_count = 0, kept_total = 0;
    for (uint32_t n = 0; n < 24; n++) {
        gi_frame_render_raster(&x.f);
        assert_true(ind->vpls.count <= 256);
        tiles_of(ind, tile);
        for (uint32_t i = 0; i < ind->vpls.count && i < prev_count; i++) {
            const gi_vpl *v = &ind->vpls.v[i];
            if (n > 0 && !v->moved && v->id == prev_id[i] && prev_tile[i] != UINT32_MAX && emits(v))
                assert_int_equal(tile[i], prev_tile[i]);
        }
        if (n > 0) kept_total += ind->assign_kept;
        for (uint32_t i = 0; i < ind->vpls.count; i++) prev_tile[i] = tile[i], prev_id[i] = ind->vpls.v[i].id;
        prev_count = ind->vpls.count;
    }
    /* most VPLs survive each frame (M_max = 16 of 256 replaced at most) */
    assert_true(kept_total > 23u * 200u);
    tu_fx_end(&x);
}

/* The assignment's and the VPL maps' scratch comes from the frame's arena,
 * reset every frame: after the first frame no block is added (no malloc),
 * and every frame takes it afresh. */
static void test_frame_scratch(void **state)
{
    (void)state;
    tu_fx x;
    pf_error err;
    memset(&x, 0, sizeof x);
    if (pf_gltf_load(&x.scene, CORNELL, NULL, &err) != PF_OK) fail_msg("%s", err.message);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = gi_vpl_method_find("iir");
    io.vpls = 128;
    io.para_res = 32; /* paraboloid maps: their lists are scratch too */
    tu_fx_begin(&x, 2, RS_SIMD_SCALAR, 48, 36, &x.scene.cameras[0], &io, 1);
    size_t reserved = 0, used = 0;
    for (int n = 0; n < 6; n++) {
        gi_frame_render_raster(&x.f);
        assert_int_equal(x.f.status, PF_OK);
        assert_true(x.f.scratch.used > 0);
        if (n == 0) reserved = x.f.scratch.reserved, used = x.f.scratch.used;
        assert_int_equal(x.f.scratch.reserved, reserved); /* nothing allocated after the first frame */
        assert_true(x.f.scratch.used <= reserved);
        assert_true(x.f.scratch.used == used); /* the same VPL budget: the same scratch each frame */
    }
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_first_deal),
        cmocka_unit_test(test_survivors_keep_tiles),
        cmocka_unit_test(test_smc_frames),
        cmocka_unit_test(test_frame_scratch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
