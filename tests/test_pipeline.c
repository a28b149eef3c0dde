/* test_pipeline: frame pipelining (issue 7 part 2; Laine 2007 Sec. 3 and 6,
 * the one-frame delay in VPL positions and intensities) and the options of
 * `softgi bench frame`.
 * - the exact lag: with a light that moves every frame (Instant Radiosity,
 *   which then regenerates every VPL), pipelined frame 0 equals the
 *   unpipelined frame 0, and pipelined frame N >= 1 equals, bit for bit,
 *   the unpipelined frame N rendered with the unpipelined frame N-1's VPL
 *   set (frame N's G-buffer, lights and shadow maps, no update); the VPL
 *   sets themselves match; and the lag is real (frame N differs from the
 *   unpipelined frame N). Both with paraboloid maps and with Embree rays,
 *   and with a test method that reads the G-buffer (so the pipelined
 *   update starts after the G-buffer and must see frame N's), the camera
 *   moving too.
 * - pipelined output is identical with 1 and 2 threads (frame by frame, and
 *   a `softgi sequence --pipeline on` run, raster and ray-traced);
 * - bench frame's new options parse, and bad values are errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "gi_frame.h"
#include "pf_gltf.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 64
#define H 48
#define FRAMES 5

/* A method that reads the G-buffer: Instant Radiosity whose intensities are
 * scaled by a factor from the depth at the image centre, so its output
 * depends on which frame's G-buffer it saw. Not G-buffer-free, so the
 * pipelined frame starts it after the G-buffer. */
static pf_result probe_update(void *state, const gi_vpl_inputs *in, gi_vpl_set *out, pf_error *err)
{
    if (!in->gbuf) return pf_error_set(err, PF_ERR_ARGUMENT, "probe: no G-buffer");
    pf_result r = gi_method_ir.update(state, in, out, err);
    if (r != PF_OK) return r;
    float d = in->gbuf->depth[(size_t)(in->height / 2) * in->width + in->width / 2];
    float k = 1.0f + 0.5f * (isfinite(d) ? d : 0.0f);
    for (uint32_t i = 0; i < out->count; i++) out->v[i].intensity = pf_v3_scale(out->v[i].intensity, k);
    return PF_OK;
}
static const gi_vpl_method k_probe = {.name = "probe", .paper = "test", .update = probe_update};

/* The fixture (test_frame_fixture.h) and the light's first position. */
typedef struct fx {
    tu_fx t;
    pf_vec3 light0;
} fx;

static void fx_begin(fx *x, uint32_t threads, int pipeline, int raytrace_vis, int probe)
{
    tu_load(&x->t.scene, CORNELL);
    assert_true(x->t.scene.light_count >= 1 && x->t.scene.camera_count >= 1);
    x->light0 = x->t.scene.lights[0].position;
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.vpls = 48;
    io.clamp = -1.0f;
    io.para_res = 32;
    io.pipeline = pipeline;
    io.visibility_raytrace = raytrace_vis;
    if (probe) {
        static gi_vpl_method m;
        m = k_probe;
        m.create = gi_method_ir.create;
        m.destroy = gi_method_ir.destroy;
        io.method = &m;
        assert_false(m.gbuffer_free);
    }
    tu_fx_begin(&x->t, threads, RS_SIMD_SCALAR, W, H, &x->t.scene.cameras[0], &io, 0);
}

static void fx_end(fx *x) { tu_fx_end(&x->t); }

/* The light of frame n: a small circle under the ceiling light's spot; the
 * camera steps sideways. */
static void fx_set_frame(fx *x, uint32_t n)
{
    float a = 0.9f * (float)n;
    x->t.scene.lights[0].position = pf_v3_add(x->light0, pf_v3(0.06f * cosf(a), -0.02f * (float)n, 0.06f * sinf(a)));
    x->t.f.camera = x->t.scene.cameras[0];
    x->t.f.camera.eye = pf_v3_add(x->t.f.camera.eye, pf_v3_scale(x->t.f.camera.right, 0.03f * (float)n));
}

/* gi_frame_render_raster without step 3: the frame shades with whatever
 * set the frame holds (the unpipelined frame N with frame N-1's set). */
static void render_without_update(gi_frame *f)
{
    gi_stage_gbuffer_raster(f);
    gi_stage_gbuffer_resolve(f);
    gi_stage_shadow_maps(f);
    gi_stage_direct_shadowmap(f);
    gi_stage_vpl_shadow_maps(f);
    gi_stage_split(f);
    gi_stage_assign(f);
    gi_stage_accumulate(f);
    gi_stage_combine(f);
    gi_stage_filter(f);
    gi_stage_compose(f);
    pf_jobs_wait_all(f->jobs);
}

/* Equal VPL sets: positions, normals, intensities and ids bit for bit;
 * moved flags too unless `skip_moved`. */
#define assert_sets_equal(a, b, what, n, skip_moved) sets_equal_at(a, b, what, n, skip_moved, __LINE__)
static void sets_equal_at(const gi_vpl_set *a, const gi_vpl_set *b, const char *what, uint32_t n, int skip_moved,
                          int line)
{
    if (a->count != b->count || !a->count)
        fail_msg("line %d, frame %u: VPL sets differ: %s (%u vs %u VPLs)", line, n, what, a->count, b->count);
    for (uint32_t i = 0; i < a->count; i++) {
        gi_vpl x = a->v[i], y = b->v[i];
        if (skip_moved) x.moved = y.moved = 0;
        if (memcmp(&x, &y, sizeof x)) fail_msg("line %d, frame %u: VPL %u differs: %s", line, n, i, what);
    }
}

static int images_equal(const float *a, const float *b) { return !memcmp(a, b, sizeof(float) * 3 * W * H); }

static void lag_case(int raytrace_vis, int probe)
{
    const size_t px = (size_t)W * H * 3;
    float *piped[FRAMES];
    gi_vpl_set sets[FRAMES]; /* the pipelined frames' shading sets */
    memset(sets, 0, sizeof sets);
    pf_error err;

    /* pipelined, 2 threads: every frame's image and shading set */
    fx p;
    fx_begin(&p, 2, 1, raytrace_vis, probe);
    for (uint32_t n = 0; n < FRAMES; n++) {
        fx_set_frame(&p, n);
        gi_frame_render_raster(&p.t.f);
        piped[n] = malloc(sizeof(float) * px);
        assert_non_null(piped[n]);
        memcpy(piped[n], p.t.f.final, sizeof(float) * px);
        assert_int_equal(gi_vpl_set_reserve(&sets[n], p.t.f.ind.vpls.count, &err), PF_OK);
        memcpy(sets[n].v, p.t.f.ind.vpls.v, sizeof(gi_vpl) * p.t.f.ind.vpls.count);
        sets[n].count = p.t.f.ind.vpls.count;
        /* the update is recorded as its own stage in both modes */
        int found = 0;
        for (uint32_t s = 0; s < p.t.f.times.count; s++) found |= !strcmp(p.t.f.times.name[s], "VPL update");
        assert_true(found);
    }
    fx_end(&p);

    /* pipelined, 1 thread: the same frames, bit for bit */
    fx q;
    fx_begin(&q, 1, 1, raytrace_vis, probe);
    for (uint32_t n = 0; n < FRAMES; n++) {
        fx_set_frame(&q, n);
        gi_frame_render_raster(&q.t.f);
        if (!images_equal(q.t.f.final, piped[n])) fail_msg("pipelined frame %u differs between 1 and 2 threads", n);
        assert_sets_equal(&q.t.f.ind.vpls, &sets[n], "pipelined, 1 vs 2 threads", n, 0);
    }
    fx_end(&q);

    /* unpipelined, 1 thread: frame N with frame N-1's set equals pipelined
     * frame N; the normal unpipelined frame N does not (the lag is real) */
    fx u;
    fx_begin(&u, 1, 0, raytrace_vis, probe);
    gi_vpl_set prev = {0, 0, NULL};
    for (uint32_t n = 0; n < FRAMES; n++) {
        fx_set_frame(&u, n);
        if (n > 0) {
            render_without_update(&u.t.f); /* frame N's inputs, frame N-1's set */
            if (!images_equal(u.t.f.final, piped[n]))
                fail_msg("pipelined frame %u != unpipelined frame %u with frame %u's VPLs", n, n, n - 1);
            /* frame 1 shades with frame 0's set a second time: nothing in it moved */
            assert_sets_equal(&sets[n], &prev, "pipelined frame N vs unpipelined frame N-1", n, n == 1);
            if (n == 1)
                for (uint32_t i = 0; i < sets[1].count; i++) assert_int_equal(sets[1].v[i].moved, 0);
        }
        gi_frame_render_raster(&u.t.f);
        if (n == 0) {
            if (!images_equal(u.t.f.final, piped[0])) fail_msg("pipelined frame 0 != unpipelined frame 0");
            assert_sets_equal(&u.t.f.ind.vpls, &sets[0], "frame 0, pipelined vs not", n, 0);
        } else if (images_equal(u.t.f.final, piped[n])) {
            fail_msg("frame %u: pipelined equals unpipelined although the light moved (no lag?)", n);
        }
        assert_int_equal(gi_vpl_set_reserve(&prev, u.t.f.ind.vpls.count, &err), PF_OK);
        memcpy(prev.v, u.t.f.ind.vpls.v, sizeof(gi_vpl) * u.t.f.ind.vpls.count);
        prev.count = u.t.f.ind.vpls.count;
    }
    fx_end(&u);
    gi_vpl_set_free(&prev);
    for (uint32_t n = 0; n < FRAMES; n++) {
        free(piped[n]);
        gi_vpl_set_free(&sets[n]);
    }
}

static void test_lag_paraboloid(void **state)
{
    (void)state;
    lag_case(0, 0);
}

static void test_lag_raytrace(void **state)
{
    (void)state;
    lag_case(1, 0);
}

static void test_lag_gbuffer_method(void **state)
{
    (void)state;
    lag_case(0, 1);
}

/* Pipelined frame 1 shades with frame 0's set again: its paraboloid maps
 * are reused, not rendered twice; later frames render the moved ones. */
static void test_maps_reused(void **state)
{
    (void)state;
    fx p;
    fx_begin(&p, 2, 1, 0, 0);
    uint32_t maps[3];
    for (uint32_t n = 0; n < 3; n++) {
        fx_set_frame(&p, n);
        gi_frame_render_raster(&p.t.f);
        maps[n] = p.t.f.ind.maps_rendered;
    }
    assert_int_equal(maps[0], p.t.f.ind.vpls.count);
    assert_int_equal(maps[1], 0);
    assert_true(maps[2] > 0); /* frame 1's set: the light moved, IR regenerated it */
    fx_end(&p);
    /* a static light: after frame 0 nothing moves and no map is rendered */
    fx_begin(&p, 2, 1, 0, 0);
    for (uint32_t n = 0; n < 4; n++) {
        gi_frame_render_raster(&p.t.f);
        uint32_t moved = 0;
        for (uint32_t i = 0; i < p.t.f.ind.vpls.count; i++) moved += p.t.f.ind.vpls.v[i].moved != 0;
        assert_int_equal(moved, n ? 0 : p.t.f.ind.vpls.count);
        assert_int_equal(p.t.f.ind.maps_rendered, n ? 0 : p.t.f.ind.vpls.count);
    }
    fx_end(&p);
}

/* ------------------------------------------------------------ the CLI */

static char g_tmp[512];

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-pipeline");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

static const char *k_light_seq =
    "{\"scene\": \"embedded:cornell-box\", \"frames\": 4, \"size\": [48, 36],\n"
    " \"lights\": [{\"light\": 0, \"keys\": [{\"frame\": 0, \"position\": [0.278, 0.5388, 0.2795]},\n"
    "                                   {\"frame\": 3, \"position\": [0.15, 0.45, 0.2]}]}]}\n";

static void seq_hash(const char *seq, const char *extra, char hash[17])
{
    char args[2048], out[32768];
    snprintf(args, sizeof args, "sequence '%s' -o '%s/out' --vpls 32 --shadow-size 128 --isa sse2 --hash %s", seq,
             g_tmp, extra);
    int st = tu_softgi_run(args, out, sizeof out);
    if (st != 0) fail_msg("softgi %s: exit %d\n%s", args, st, out);
    const char *h = strstr(out, "hash ");
    if (!h || sscanf(h, "hash %16s", hash) != 1) fail_msg("no hash in:\n%s", out);
    if (strstr(extra, "--pipeline on") && !strstr(out, "pipeline on")) fail_msg("pipeline not reported:\n%s", out);
}

static void test_sequence_cli(void **state)
{
    (void)state;
    char seq[600];
    snprintf(seq, sizeof seq, "%s/light.seq.json", g_tmp);
    FILE *fp = fopen(seq, "w");
    assert_non_null(fp);
    fputs(k_light_seq, fp);
    fclose(fp);
    char off1[17], on1[17], on2[17], rt1[17], rt2[17], def[17];
    seq_hash(seq, "--threads 1 --pipeline off", off1);
    seq_hash(seq, "--threads 1", def); /* default: off */
    assert_string_equal(off1, def);
    seq_hash(seq, "--threads 1 --pipeline on", on1);
    seq_hash(seq, "--threads 2 --pipeline on", on2);
    assert_string_equal(on1, on2);
    assert_string_not_equal(on1, off1); /* the light moves: the lag shows */
    seq_hash(seq, "--threads 1 --pipeline on --raytrace", rt1);
    seq_hash(seq, "--threads 2 --pipeline on --raytrace", rt2);
    assert_string_equal(rt1, rt2);
    assert_string_not_equal(rt1, on1);
    tu_softgi_expect("render --pipeline sometimes", 2, "--pipeline 'sometimes': expected on or off");
    /* one frame renders the same with pipelining on and off (frame 0 runs the update in place) */
    char hr[2][17];
    for (int k = 0; k < 2; k++) {
        char args[1024], out[16384];
        snprintf(args, sizeof args, "render --size 48x36 --vpls 32 --shadow-size 128 --isa sse2 -q --hash -o '%s/r%d.png' "
                 "--pipeline %s", g_tmp, k, k ? "on" : "off");
        if (tu_softgi_run(args, out, sizeof out) != 0) fail_msg("softgi %s:\n%s", args, out);
        const char *h = strstr(out, "hash ");
        if (!h || sscanf(h, "hash %16s", hr[k]) != 1) fail_msg("no hash in:\n%s", out);
    }
    assert_string_equal(hr[0], hr[1]);
}

static void test_bench_frame_options(void **state)
{
    (void)state;
    /* bad values: errors before any scene is loaded */
    tu_softgi_expect("bench frame --pipeline 1", 2, "--pipeline '1': expected on or off");
    tu_softgi_expect("bench frame --method nope", 2, "--method 'nope': softgi knows");
    tu_softgi_expect("bench frame --param foo=1", 2, "--param foo: method ir has no such parameter");
    tu_softgi_expect("bench frame --param foo", 2, "--param 'foo': expected KEY=VALUE");
    tu_softgi_expect("bench frame --visibility sideways", 2, "--visibility 'sideways'");
    tu_softgi_expect("bench frame --visibility ism --visibility raytrace", 2, "--visibility: give one of");
    tu_softgi_expect("render --moving-light", 2, "--moving-light: only bench frame takes it");
    tu_softgi_expect("bench raster --moving-light", 2, "--moving-light: only bench frame takes it");
    tu_softgi_expect("bench frame --size 64x48", 2, "--size does not apply");
    /* good values parse: the run gets as far as loading the scenes */
    char args[1024];
    snprintf(args, sizeof args,
             "bench frame --method ir --visibility raytrace --pipeline on --moving-light --threads 1 --vpls 8 "
             "--frames 1 --scenes '%s/none'",
             g_tmp);
    tu_softgi_expect(args, 1, "give the folder with --scenes");
    tu_softgi_expect("bench frame --pipeline off --visibility paraboloid --scenes /nonexistent", 1,
                     "give the folder with --scenes");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lag_paraboloid), cmocka_unit_test(test_lag_raytrace),
        cmocka_unit_test(test_lag_gbuffer_method),
        cmocka_unit_test(test_maps_reused),    cmocka_unit_test(test_sequence_cli),
        cmocka_unit_test(test_bench_frame_options),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
