/* test_learn: "the frame taken apart" (issue 16 item 6; gi_view.h,
 * gi_view_learn.c, gi_vpl_method.view / why / bounce):
 * - every view renders for every VPL method, two frames, and gives the same
 *   bytes and the same legend with 1 and 2 threads; every method draws its
 *   internal view and says why it chooses VPLs as it does;
 * - the stepper's order is a permutation of the views ending at final;
 * - the occlusion-aware overlays do not draw a VPL hidden behind a surface
 *   and do draw one in front of it;
 * - the clamp mask is non-empty where a VPL sits close to a surface (and
 *   equals the probe's count there), and empty with --clamp 0;
 * - the legend's range is the shown buffer's minimum and maximum, and its
 *   text prints them;
 * - the dump's ranges.txt holds every legend as drawn, and 20-clamp.exr the
 *   clamp counts. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gi_dump.h"
#include "gi_frame.h"
#include "gi_probe.h"
#include "gi_view.h"
#include "gi_view_draw.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 200 /* at least GI_VIEW_LEGEND_MIN_W x _H: the legends are drawn */
#define H 150

static void begin(tu_fx *x, uint32_t threads, const gi_vpl_method *m, float clamp, int raytrace, int no_interleave)
{
    tu_load(&x->scene, CORNELL);
    gi_indirect_options io;
    memset(&io, 0, sizeof io);
    io.method = m;
    io.vpls = 64;
    io.clamp = clamp;
    io.visibility_raytrace = raytrace;
    io.no_interleave = no_interleave;
    tu_fx_begin(x, threads, RS_SIMD_SCALAR, W, H, &x->scene.cameras[0], &io, 0);
}

/* ------------------------------------------------------------ every view, every method */

static void render_all(tu_fx *x, uint8_t *rgb, gi_view_legend *lg, int *drawn)
{
    gi_view_settings s = {0.0f, 5u};
    for (int v = 0; v < GI_VIEW_COUNT; v++)
        drawn[v] = gi_view_render_legend(&x->f, (gi_view_id)v, &s, rgb + (size_t)v * W * H * 3, &lg[v]);
}

static void test_every_view_every_method(void **state)
{
    (void)state;
    char names[256];
    snprintf(names, sizeof names, "%s", gi_vpl_method_names());
    const size_t img = (size_t)W * H * 3;
    uint8_t *a = malloc(img * GI_VIEW_COUNT), *b = malloc(img * GI_VIEW_COUNT);
    assert_non_null(a);
    assert_non_null(b);
    int methods = 0;
    for (char *name = strtok(names, ", "); name; name = strtok(NULL, ", ")) {
        const gi_vpl_method *m = gi_vpl_method_find(name);
        assert_non_null(m);
        assert_non_null(m->why); /* every method says why it chooses VPLs as it does */
        assert_true(strstr(m->why, "Sec.") != NULL);
        gi_view_legend la[GI_VIEW_COUNT], lb[GI_VIEW_COUNT];
        int da[GI_VIEW_COUNT], db[GI_VIEW_COUNT];
        tu_fx x1, x2;
        begin(&x1, 1, m, -1.0f, 0, 0);
        begin(&x2, 2, m, -1.0f, 0, 0);
        for (int frame = 0; frame < 2; frame++) {
            if (frame) { /* the light moves: some VPLs move, some are kept */
                x1.scene.lights[0].position.x += 0.05f;
                x2.scene.lights[0].position.x += 0.05f;
            }
            gi_frame_render_raster(&x1.f);
            gi_frame_render_raster(&x2.f);
            render_all(&x1, a, la, da);
            render_all(&x2, b, lb, db);
            for (int v = 0; v < GI_VIEW_COUNT; v++) {
                if (memcmp(a + v * img, b + v * img, img) != 0)
                    fail_msg("method %s, frame %d: view %s differs between 1 and 2 threads", name, frame,
                             gi_view_name((gi_view_id)v));
                assert_int_equal(da[v], db[v]);
                assert_string_equal(la[v].text, lb[v].text);
                assert_int_equal(da[v], gi_view_available(&x1.f, (gi_view_id)v));
                char line[1024];
                assert_true(gi_view_describe_frame(&x1.f, (gi_view_id)v, line, sizeof line) > 0);
                if (gi_view_stage((gi_view_id)v) == GI_STAGE_VPL_UPDATE) assert_non_null(strstr(line, m->why));
                /* every view but the final image has a legend */
                if (da[v] && v != GI_VIEW_FINAL && !la[v].present)
                    fail_msg("method %s: view %s has no legend", name, gi_view_name((gi_view_id)v));
            }
            assert_false(la[GI_VIEW_FINAL].present);
        }
        /* every method draws its own state */
        if (!da[GI_VIEW_METHOD]) fail_msg("method %s: no internal view", name);
        assert_non_null(m->view_caption);
        print_message("%s: %s\n", name, la[GI_VIEW_METHOD].text);
        tu_fx_end(&x1);
        tu_fx_end(&x2);
        methods++;
    }
    assert_int_equal(methods, 7);
    free(a);
    free(b);
}

static void test_order(void **state)
{
    (void)state;
    int seen[GI_VIEW_COUNT] = {0};
    for (uint32_t k = 0; k < GI_VIEW_COUNT; k++) {
        gi_view_id v = gi_view_order(k);
        assert_true((unsigned)v < GI_VIEW_COUNT);
        assert_int_equal(seen[v], 0);
        seen[v] = 1;
        assert_int_equal(gi_view_rank(v), k);
        /* the stages' steps never go backwards */
        if (k)
            assert_true(gi_stage_get(gi_view_stage(v))->step >=
                        gi_stage_get(gi_view_stage(gi_view_order(k - 1)))->step);
    }
    assert_int_equal(gi_view_order(GI_VIEW_COUNT - 1), GI_VIEW_FINAL);
}

/* ------------------------------------------------------------ occlusion */

/* The view's 3x3 block at (px, py) equals the background's. */
static int block_is(const uint8_t *img, const uint8_t *bg, int px, int py)
{
    for (int y = py - 1; y <= py + 1; y++)
        for (int x = px - 1; x <= px + 1; x++)
            if (memcmp(img + 3 * ((size_t)y * W + x), bg + 3 * ((size_t)y * W + x), 3)) return 0;
    return 1;
}

static void test_overlay_hides_occluded_vpls(void **state)
{
    (void)state;
    tu_fx x;
    begin(&x, 2, NULL, -1.0f, 0, 0);
    gi_frame_render_raster(&x.f);
    const rs_gbuffer *g = &x.f.gbuf;
    /* two image points that see a surface; VPL 0 sits just in front of the
     * first, VPL 1 behind the second (further along the camera ray) */
    const uint32_t ax = W / 2, ay = H / 3, bx = W / 3, by = H / 3;
    size_t ia = (size_t)ay * W + ax, ib = (size_t)by * W + bx;
    assert_int_not_equal(g->prim[ia], RS_GBUFFER_EMPTY);
    assert_int_not_equal(g->prim[ib], RS_GBUFFER_EMPTY);
    pf_vec3 pa = pf_v3(g->pos_x[ia], g->pos_y[ia], g->pos_z[ia]), na = pf_v3(g->nrm_x[ia], g->nrm_y[ia], g->nrm_z[ia]);
    pf_vec3 pb = pf_v3(g->pos_x[ib], g->pos_y[ib], g->pos_z[ib]);
    gi_vpl_set *set = &x.f.ind.vpls;
    assert_true(set->cap >= 2);
    set->count = 2;
    set->v[0] = (gi_vpl){pf_v3_add(pa, pf_v3_scale(na, 0.01f)), na, pf_v3(1, 1, 1), 0, 1};
    pf_vec3 d = pf_v3_normalize(pf_v3_sub(pb, x.f.camera.eye));
    set->v[1] = (gi_vpl){pf_v3_add(pb, pf_v3_scale(d, 0.2f)), na, pf_v3(1, 1, 1), 1, 1};
    /* both project where expected */
    float fx, fy;
    assert_true(gi_view_draw_project(&x.f, set->v[1].pos, &fx, &fy));
    int hx = (int)floorf(fx), hy = (int)floorf(fy);
    assert_true(abs(hx - (int)bx) <= 1 && abs(hy - (int)by) <= 1);
    assert_true(gi_view_draw_project(&x.f, set->v[0].pos, &fx, &fy));
    int sx = (int)floorf(fx), sy = (int)floorf(fy);
    uint8_t vis[2];
    gi_view_draw_visible(&x.f, (pf_vec3[]){set->v[0].pos, set->v[1].pos}, 2, vis);
    assert_int_equal(vis[0], 1);
    assert_int_equal(vis[1], 0);
    uint8_t *bg = malloc((size_t)W * H * 3), *img = malloc((size_t)W * H * 3);
    gi_view_draw_dim_final(&x.f, 0.0f, bg);
    gi_view_settings s = {0.0f, 0u};
    static const gi_view_id overlays[3] = {GI_VIEW_VPLS, GI_VIEW_VPL_BOUNCE, GI_VIEW_VPL_MOVED};
    for (int k = 0; k < 3; k++) {
        gi_view_legend lg;
        assert_int_equal(gi_view_render_legend(&x.f, overlays[k], &s, img, &lg), 1);
        if (!block_is(img, bg, hx, hy))
            fail_msg("%s draws the VPL hidden behind the surface", gi_view_name(overlays[k]));
        if (block_is(img, bg, sx, sy)) fail_msg("%s does not draw the VPL in front", gi_view_name(overlays[k]));
        assert_non_null(strstr(lg.text, "1 seen, 1 hidden"));
    }
    free(bg);
    free(img);
    tu_fx_end(&x);
}

/* ------------------------------------------------------------ clamp mask */

/* A frame whose only VPL faces the surface seen at pixel (cx, cy) from
 * 1 mm away, shaded by every pixel (1 x 1 tiles, ray-traced visibility);
 * returns the clamp counts. */
static float *clamp_frame(tu_fx *x, float clamp, uint32_t cx, uint32_t cy, gi_view_legend *lg)
{
    begin(x, 2, NULL, clamp, 1, 1);
    gi_frame_render_raster(&x->f);
    const rs_gbuffer *g = &x->f.gbuf;
    size_t i = (size_t)cy * W + cx;
    assert_int_not_equal(g->prim[i], RS_GBUFFER_EMPTY);
    pf_vec3 p = pf_v3(g->pos_x[i], g->pos_y[i], g->pos_z[i]), n = pf_v3(g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]);
    gi_vpl_set *set = &x->f.ind.vpls;
    set->count = 1;
    set->v[0] = (gi_vpl){pf_v3_add(p, pf_v3_scale(n, 0.001f)), pf_v3_scale(n, -1.0f), pf_v3(0.1f, 0.1f, 0.1f), 7, 1};
    gi_stage_assign(&x->f); /* the one tile's group is the new set */
    float *count = malloc((size_t)W * H * sizeof *count);
    gi_view_clamp_counts(&x->f, count);
    uint8_t *img = malloc((size_t)W * H * 3);
    assert_int_equal(gi_view_render_legend(&x->f, GI_VIEW_CLAMP, NULL, img, lg), 1);
    free(img);
    return count;
}

static void test_clamp_mask(void **state)
{
    (void)state;
    const uint32_t cx = W / 2, cy = H / 3;
    tu_fx x;
    gi_view_legend lg;
    float *count = clamp_frame(&x, -1.0f, cx, cy, &lg); /* the default bound */
    assert_true(count[(size_t)cy * W + cx] == 1.0f);
    /* ray-traced visibility has no paraboloid maps to show */
    assert_false(gi_view_available(&x.f, GI_VIEW_VPL_ATLAS));
    assert_false(gi_view_available(&x.f, GI_VIEW_VPL_MAP));
    gi_probe pr;
    gi_probe_pixel(&pr, &x.f, cx, cy);
    assert_int_equal(pr.clamped, 1);
    size_t marked = 0;
    float hi = 0.0f;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t xx = 0; xx < W; xx++) {
            float c = count[(size_t)y * W + xx];
            marked += c > 0.0f;
            hi = fmaxf(hi, c);
            if (c > 0.0f) { /* only near the VPL: within a few pixels of (cx, cy) */
                if (abs((int)xx - (int)cx) > 40 || abs((int)y - (int)cy) > 40)
                    fail_msg("clamped at (%u, %u), far from the VPL at (%u, %u)", xx, y, cx, cy);
            }
        }
    print_message("clamp mask: %zu pixels clamped around the VPL; legend '%s'\n", marked, lg.text);
    assert_true(marked > 0);
    assert_true(lg.has_range && lg.lo == 0.0f && lg.hi == hi);
    free(count);
    tu_fx_end(&x);
    /* --clamp 0: nothing is clamped */
    count = clamp_frame(&x, 0.0f, cx, cy, &lg);
    assert_false(isfinite(x.f.ind.b));
    for (size_t i = 0; i < (size_t)W * H; i++) assert_true(count[i] == 0.0f);
    assert_true(lg.has_range && lg.lo == 0.0f && lg.hi == 0.0f);
    free(count);
    tu_fx_end(&x);
}

/* ------------------------------------------------------------ legends */

static void expect_range(const gi_view_legend *lg, float lo, float hi, const char *view)
{
    if (!lg->present || !lg->has_range || lg->lo != lo || lg->hi != hi)
        fail_msg("%s: legend %g .. %g, the buffer %g .. %g", view, (double)lg->lo, (double)lg->hi, (double)lo,
                 (double)hi);
    char want[64];
    snprintf(want, sizeof want, "%.4g .. %.4g", (double)lo, (double)hi);
    if (!strstr(lg->text, want)) fail_msg("%s: legend text '%s' does not print '%s'", view, lg->text, want);
}

static void test_legend_ranges(void **state)
{
    (void)state;
    tu_fx x;
    begin(&x, 2, NULL, -1.0f, 0, 0);
    gi_frame_render_raster(&x.f);
    const size_t n = (size_t)W * H;
    uint8_t *img = malloc(n * 3);
    gi_view_legend lg;
    /* depth: the surfaces' view depths */
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++)
        if (x.f.gbuf.prim[i] != RS_GBUFFER_EMPTY) lo = fminf(lo, x.f.gbuf.depth[i]), hi = fmaxf(hi, x.f.gbuf.depth[i]);
    gi_view_render_legend(&x.f, GI_VIEW_DEPTH, NULL, img, &lg);
    expect_range(&lg, lo, hi, "depth");
    /* radiance and irradiance: every component of the buffer */
    const struct {
        gi_view_id id;
        const float *buf;
    } rad[3] = {{GI_VIEW_DIRECT, x.f.direct},
                {GI_VIEW_FILTERED, x.f.ind.filtered},
                {GI_VIEW_COMBINED, x.f.ind.combined}};
    for (int k = 0; k < 3; k++) {
        lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < 3 * n; i++) lo = fminf(lo, rad[k].buf[i]), hi = fmaxf(hi, rad[k].buf[i]);
        gi_view_render_legend(&x.f, rad[k].id, NULL, img, &lg);
        expect_range(&lg, lo, hi, gi_view_name(rad[k].id));
    }
    /* VPLs: the luminance of the non-empty VPLs */
    lo = INFINITY, hi = -INFINITY;
    for (uint32_t k = 0; k < x.f.ind.vpls.count; k++) {
        float l = pf_luminance(x.f.ind.vpls.v[k].intensity);
        if (l > 0.0f) lo = fminf(lo, l), hi = fmaxf(hi, l);
    }
    gi_view_render_legend(&x.f, GI_VIEW_VPL_OVERHEAD, NULL, img, &lg);
    expect_range(&lg, lo, hi, "vpl-overhead");
    /* the legend is drawn: the picture differs from the same view without
     * it in the bottom-right corner only */
    gi_view_render_legend(&x.f, GI_VIEW_DIRECT, NULL, img, &lg);
    uint8_t *plain = malloc(n * 3);
    const float scale = 1.0f;
    for (size_t i = 0; i < 3 * n; i++) plain[i] = pf_imageio_display(x.f.direct[i], scale);
    size_t diff = 0;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t xx = 0; xx < W; xx++)
            if (memcmp(img + 3 * ((size_t)y * W + xx), plain + 3 * ((size_t)y * W + xx), 3)) {
                diff++;
                assert_true(xx >= 10 && y >= H - 40);
            }
    assert_true(diff > 100);
    free(plain);
    free(img);
    tu_fx_end(&x);
}

/* ------------------------------------------------------------ the dump */

/* --dump-stages writes ranges.txt, one line per legend as drawn, and the
 * clamp mask's counts as 20-clamp.exr. */
static void test_dump_ranges(void **state)
{
    (void)state;
    tu_fx x;
    begin(&x, 2, gi_vpl_method_find("iir"), -1.0f, 0, 0);
    gi_frame_render_raster(&x.f);
    char dir[] = "/tmp/softgi-learn-XXXXXX", path[256], line[1024];
    assert_non_null(mkdtemp(dir));
    pf_error err;
    if (gi_dump_stages(&x.f, dir, NULL, GI_DUMP_BOTH, &err) != PF_OK) fail_msg("%s", err.message);
    snprintf(path, sizeof path, "%s/ranges.txt", dir);
    FILE *fp = fopen(path, "r");
    assert_non_null(fp);
    uint8_t *img = malloc((size_t)W * H * 3);
    int lines = 0;
    for (int v = 0; v < GI_VIEW_COUNT; v++) {
        gi_view_legend lg;
        gi_view_render_legend(&x.f, (gi_view_id)v, NULL, img, &lg);
        if (!lg.present) continue;
        char want[512];
        snprintf(want, sizeof want, "%02d-%s.png: %s\n", v, gi_view_name((gi_view_id)v), lg.text);
        if (!fgets(line, sizeof line, fp) || strcmp(line, want))
            fail_msg("ranges.txt: got '%s', want '%s'", line, want);
        lines++;
    }
    assert_null(fgets(line, sizeof line, fp));
    fclose(fp);
    assert_int_equal(lines, GI_VIEW_COUNT - 1); /* every view of this frame but final */
    /* the clamp mask's data */
    float *count = malloc((size_t)W * H * sizeof *count), *exr = NULL;
    gi_view_clamp_counts(&x.f, count);
    uint32_t w, h;
    snprintf(path, sizeof path, "%s/20-clamp.exr", dir);
    if (pf_imageio_read_image(path, PF_IMAGEIO_DATA, &exr, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
    assert_int_equal(w, W);
    assert_int_equal(h, H);
    for (size_t i = 0; i < (size_t)W * H; i++) assert_true(exr[3 * i] == count[i]);
    free(exr);
    free(count);
    free(img);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
    tu_fx_end(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_order),
        cmocka_unit_test(test_legend_ranges),
        cmocka_unit_test(test_overlay_hides_occluded_vpls),
        cmocka_unit_test(test_clamp_mask),
        cmocka_unit_test(test_dump_ranges),
        cmocka_unit_test(test_every_view_every_method),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
