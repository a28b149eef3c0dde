/* test_viewer: `softgi view`, the stage views it shares with
 * `softgi render --dump-stages` (gi_view) and its pixel inspector (gi_probe).
 * - the probe of every pixel of small frames (seven settings: paraboloid
 *   maps with the SIMD and the scalar accumulation, no interleaving, ray-
 *   traced and ISM visibility, IIR with the bilateral filter and indirect
 *   light only, direct light only, SMC pipelined) holds the frame's buffers at that pixel
 *   bit for bit, its VPL-by-VPL re-evaluation of the tile irradiance equals
 *   the frame's, the final radiance is its parts composed, the top VPLs are
 *   sorted, and the mosaic mapping is the views' (no window);
 * - zoom and pan: unzoomed the window is the view; zoomed, the pixel drawn
 *   under a point is the pixel a click there picks (no window);
 * - under Xvfb, the probe the viewer takes on a (scripted) click, printed
 *   and written with the frame it dumps (shift+X), equals the dump's float
 *   data (.exr) at that pixel, bit for bit: clicked unzoomed, zoomed in, and
 *   in the accumulated mosaic reached through the view list; X saves the
 *   final view byte-identical to render's PNG;
 * - the HUD at 320x240 and 640x480 never draws past the window's edge,
 *   with the probe, help pages, view list, caption and zoom shown; the
 *   light grabbed with IR runs IIR (far fewer VPL maps a frame while it
 *   moves) until released;
 * - under Xvfb the viewer starts, renders 10 frames, and the window's
 *   framebuffer read back (--screenshot, no HUD) is byte-identical to the
 *   PNG `softgi render` writes for the same camera and settings, with the
 *   viewer on 1 thread and the render on 2 (skipped with a message when
 *   xvfb-run is absent);
 * - the viewer's --dump-stages writes exactly the files and bytes of
 *   render's --dump-stages (one implementation of the views);
 * - --dump-stages writes every stage (file list and captions.txt checked
 *   line by line) for every method of the registry (each must create;
 *   none is skipped); --visibility raytrace and --direct-only drop exactly the views
 *   they have no data for;
 * - without a display (and no Xvfb) the viewer fails with a clear message
 *   and exit status 1, never a crash; bad arguments give status 2. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>

#include "gi_probe.h"
#include "gi_view.h"
#include "gi_vpl.h"
#include "pf_gltf.h"
#include "pf_imageio.h"
#include "test_frame_fixture.h"
#include "test_util.h"

#define CORNELL SOFTGI_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

/* --temporal 0: the viewer without its progressive refinement, the frame
 * `softgi render` makes (harmless to render, whose default it is) */
#define SIZE "--size 160x120 --temporal 0"

static char g_tmp[256];

static int have_xvfb(void) { return system("command -v xvfb-run >/dev/null 2>&1") == 0; }

/* Whole-file byte comparison: 1 if equal (and both readable). */
static int same_file(const char *a, const char *b)
{
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    int same = fa && fb;
    while (same) {
        int ca = fgetc(fa), cb = fgetc(fb);
        if (ca != cb) same = 0;
        if (ca == EOF || cb == EOF) break;
    }
    if (fa) fclose(fa);
    if (fb) fclose(fb);
    return same;
}

/* Runs the viewer under Xvfb; returns its exit status, output in out. */
static int run_view(const char *args, char *out, size_t size)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "xvfb-run -a -s '-screen 0 1280x1024x24' %s view %s", SOFTGI_BINARY, args);
    int st = tu_run(cmd, out, size);
    if (st < 0 || st > 2) fail_msg("'%s' ended abnormally (status %d):\n%s", cmd, st, out);
    return st;
}

static void check_screenshot(const char *tag, const char *settings)
{
    char args[2048], out[16384], shot[512], png[512];
    snprintf(shot, sizeof shot, "%s/%s-view.png", g_tmp, tag);
    snprintf(png, sizeof png, "%s/%s-render.png", g_tmp, tag);
    snprintf(args, sizeof args, "%s %s --threads 1 --frames 10 --screenshot %s", SIZE, settings, shot);
    int st = run_view(args, out, sizeof out);
    if (st != 0) fail_msg("softgi view %s: exit %d:\n%s", args, st, out);
    assert_non_null(strstr(out, "10 frames"));
    snprintf(args, sizeof args, "render %s %s --threads 2 -q -o %s", SIZE, settings, png);
    tu_softgi_expect(args, 0, NULL);
    if (!same_file(shot, png)) fail_msg("%s: the viewer's screenshot %s differs from the render %s", tag, shot, png);
}

/* The optional stages' keys: U and J (half-resolution indirect light, clamp
 * compensation) give render's image with --indirect-scale 2 --compensate
 * on; T twice (temporal accumulation on, then off) leaves the plain image. */
static void test_optional_stage_keys(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    const char *cases[][3] = {{"uj", "U J", "--indirect-scale 2 --compensate on"}, {"tt", "T T", ""}};
    for (int k = 0; k < 2; k++) {
        char shot[512], png[512], cmd[8192], out[16384], args[2048];
        snprintf(shot, sizeof shot, "%s/%s-view.png", g_tmp, cases[k][0]);
        snprintf(png, sizeof png, "%s/%s-render.png", g_tmp, cases[k][0]);
        snprintf(cmd, sizeof cmd,
                 "SOFTGI_VIEW_KEYS='%s' xvfb-run -a -s '-screen 0 1280x1024x24' %s view %s --threads 1 --frames 8 "
                 "--screenshot %s",
                 cases[k][1], SOFTGI_BINARY, SIZE, shot);
        int status = tu_run(cmd, out, sizeof out);
        if (status != 0) fail_msg("%s: exit %d:\n%s", cmd, status, out);
        snprintf(args, sizeof args, "render %s %s --threads 2 -q -o %s", SIZE, cases[k][2], png);
        tu_softgi_expect(args, 0, NULL);
        if (!same_file(shot, png)) fail_msg("keys '%s': the screenshot %s differs from %s", cases[k][1], shot, png);
    }
}

/* The viewer's default is T's progressive refinement (temporal
 * accumulation with VPL cycling and its warm-up, temporal anti-aliasing):
 * the same frames as those options given explicitly, as T pressed on a
 * viewer started with --temporal 0, and as render --frames 12; not the
 * single frame of render. */
static void test_progressive_default(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    const char *runs[][2] = {
        {"", ""},
        {"", "--temporal 32 --vpl-cycle 32 --cycle-maps 32 --taa 16"},
        {"T", "--temporal 0"},
    };
    char shot[3][512], cmd[8192], out[16384], png[512], args[1024];
    for (int k = 0; k < 3; k++) {
        snprintf(shot[k], sizeof shot[k], "%s/progressive-%d.png", g_tmp, k);
        snprintf(cmd, sizeof cmd,
                 "SOFTGI_VIEW_KEYS='%s' xvfb-run -a -s '-screen 0 1280x1024x24' %s view --size 160x120 %s --threads 1 "
                 "--frames 12 --screenshot %s",
                 runs[k][0], SOFTGI_BINARY, runs[k][1], shot[k]);
        int status = tu_run(cmd, out, sizeof out);
        if (status != 0) fail_msg("%s: exit %d:\n%s", cmd, status, out);
    }
    if (!same_file(shot[0], shot[1])) fail_msg("the default viewer %s differs from the explicit options' %s", shot[0], shot[1]);
    if (!same_file(shot[0], shot[2])) fail_msg("the default viewer %s differs from T pressed: %s", shot[0], shot[2]);
    snprintf(png, sizeof png, "%s/progressive-render.png", g_tmp);
    snprintf(args, sizeof args, "render --size 160x120 --threads 2 -q -o %s", png);
    tu_softgi_expect(args, 0, NULL);
    if (same_file(shot[0], png)) fail_msg("the default viewer's frame 12 is render's single frame %s", png);
    /* render --frames 12: the same refinement, the same frame 12 */
    snprintf(png, sizeof png, "%s/progressive-render12.png", g_tmp);
    snprintf(args, sizeof args, "render --size 160x120 --threads 2 --frames 12 -q -o %s", png);
    tu_softgi_expect(args, 0, NULL);
    if (!same_file(shot[0], png)) fail_msg("render --frames 12 %s differs from the viewer's frame 12 %s", png, shot[0]);
    /* the cycled set's maps within the memory budget: 8 MB a slice of 256
     * VPLs, so 100 MB holds 8 slices beside the frame (not 16 or 32) */
    snprintf(cmd, sizeof cmd, "xvfb-run -a -s '-screen 0 1280x1024x24' %s view --size 160x120 --max-memory 100M --frames 2",
             SOFTGI_BINARY);
    int status = tu_run(cmd, out, sizeof out);
    if (status != 0) fail_msg("%s: exit %d:\n%s", cmd, status, out);
    if (!strstr(out, "progressive refinement: 8 slices of VPLs at most, what the memory budget holds (--max-memory)"))
        fail_msg("no budgeted slice count:\n%s", out);
}

static void test_screenshot_equals_render(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent (apt-get install xvfb xauth): the viewer smoke test needs it\n");
        return;
    }
    check_screenshot("default", "");
    check_screenshot("settings", "--vpls 64 --tiles 2x2 --filter bilateral --clamp 100 --exposure 1.5 "
                                 "--camera 0,1,3.5:0,1,0:50");
    /* area-light options reach the viewer's frame as they reach render's */
    const char *mcguire = SOFTGI_SHARED_SCENES "/cornell_box/CornellBox-Original.gltf";
    FILE *f = fopen(mcguire, "rb");
    if (!f) {
        print_message("SKIP: %s is absent: no area-light screenshot\n", mcguire);
        return;
    }
    fclose(f);
    char settings[1024];
    snprintf(settings, sizeof settings, "%s --camera 0,1,3.4:0,1,0:40 --area-points 8 --vpls 32", mcguire);
    check_screenshot("area", settings);
}

/* Keys replayed through SOFTGI_VIEW_KEYS: M and shift+M go to the
 * registry's second method and back (a method that cannot start would be
 * refused with its message, the previous setting staying; today every
 * method starts), O O pass ism and reach raytrace, ] I F C set 512 VPLs, 8x8
 * tiles, the bilateral filter and clamp 1600; P pauses and nine N step to
 * the overhead VPL view (the paraboloid-map view is skipped: raytrace has no
 * maps). The screenshot is then that stage, byte for byte the view render's
 * --dump-stages writes with those settings given on the command line. */
static void test_keys_settings_and_stepper(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    /* which method the first M tries: the registry's second entry */
    char names[256];
    snprintf(names, sizeof names, "%s", gi_vpl_method_names());
    const char *second = strtok(names, ", ");
    second = second ? strtok(NULL, ", ") : NULL;
    assert_non_null(second);
    const gi_vpl_method *m = gi_vpl_method_find(second);
    assert_non_null(m);
    void *st = NULL;
    pf_error err;
    int m_fails = m->create(&st, NULL, &err) != PF_OK;
    if (!m_fails) m->destroy(st);
    char args[2048], out[16384], shot[512], dir[512], want[1024];
    snprintf(shot, sizeof shot, "%s/keys-view.png", g_tmp);
    snprintf(dir, sizeof dir, "%s/keys-dump", g_tmp);
    /* M then shift+M: back on ir whether or not the second method works */
    snprintf(args, sizeof args, "%s --frames 24 --screenshot %s", SIZE, shot);
    char cmd[8192];
    snprintf(cmd, sizeof cmd,
             "SOFTGI_VIEW_KEYS='M shift+M O O ] I F C P N N N N N N N N N' xvfb-run -a -s '-screen 0 1280x1024x24' "
             "%s view %s",
             SOFTGI_BINARY, args);
    int status = tu_run(cmd, out, sizeof out);
    if (status != 0) fail_msg("%s: exit %d:\n%s", cmd, status, out);
    if (m_fails) {
        snprintf(want, sizeof want, "%s: %s", second, err.message);
        if (!strstr(out, want)) fail_msg("the viewer did not report '%s':\n%s", want, out);
    }
    /* if ism visibility cannot start, the viewer must say so and keep paraboloid maps */
    char ism[16384];
    snprintf(args, sizeof args, "render --size 16x16 --visibility ism -q -o %s/ism.png", g_tmp);
    int ism_fails = tu_softgi_run(args, ism, sizeof ism) != 0 && strstr(ism, "not implemented yet");
    if (ism_fails && !strstr(out, "--visibility ism: not implemented yet (kept the previous settings)"))
        fail_msg("the viewer did not report the ism failure:\n%s", out);
    snprintf(args, sizeof args,
             "render %s --visibility raytrace --vpls 512 --tiles 8x8 --filter bilateral --clamp 1600 -q "
             "--dump-stages %s -o %s/keys.png",
             SIZE, dir, g_tmp);
    tu_softgi_expect(args, 0, NULL);
    snprintf(want, sizeof want, "%s/%02d-%s.png", dir, GI_VIEW_VPL_OVERHEAD, gi_view_name(GI_VIEW_VPL_OVERHEAD));
    if (!same_file(shot, want)) fail_msg("the stepper's overhead view %s differs from %s", shot, want);
    /* a bad key name is a usage error */
    snprintf(cmd, sizeof cmd, "SOFTGI_VIEW_KEYS='M nosuchkey' %s view %s --frames 1", SOFTGI_BINARY, SIZE);
    status = tu_run(cmd, out, sizeof out);
    if (status != 2 || !strstr(out, "unknown key 'nosuchkey'")) fail_msg("%s: exit %d:\n%s", cmd, status, out);
}

/* The expected dump: the views available for the given settings; the
 * VPL-update views' captions name the method `m` and say why (m NULL:
 * no indirect light). */
static void check_dump(const char *dir, int indirect, int para_maps, const gi_vpl_method *m)
{
    char path[1024], line[1024], want[1024];
    snprintf(path, sizeof path, "%s/captions.txt", dir);
    FILE *cap = fopen(path, "r");
    if (!cap) fail_msg("%s is missing", path);
    for (int v = 0; v < GI_VIEW_COUNT; v++) {
        int expected = 1;
        if ((v >= GI_VIEW_VPLS && v <= GI_VIEW_FILTERED) || v >= GI_VIEW_VPL_BOUNCE) expected = indirect;
        if (v == GI_VIEW_VPL_MAP || v == GI_VIEW_VPL_ATLAS) expected = indirect && para_maps;
        snprintf(path, sizeof path, "%s/%02d-%s.png", dir, v, gi_view_name((gi_view_id)v));
        if (tu_file_exists(path) != expected)
            fail_msg("%s should %s", path, expected ? "exist" : "not be written (the frame has no such data)");
        if (!expected) continue;
        char what[400];
        gi_view_describe((gi_view_id)v, what, sizeof what);
        /* the description names the view's stage from the stage table */
        const gi_stage_info *st = gi_stage_get(gi_view_stage((gi_view_id)v));
        assert_non_null(strstr(what, st->name));
        snprintf(want, sizeof want, "%02d-%s.png: %s\n", v, gi_view_name((gi_view_id)v), what);
        if (m && gi_view_stage((gi_view_id)v) == GI_STAGE_VPL_UPDATE) {
            /* gi_view_describe_frame: the method's paper and why */
            snprintf(want, sizeof want, "%02d-%s.png: step %u, %s by %s: ", v, gi_view_name((gi_view_id)v), st->step,
                     st->name, m->paper);
            if (!fgets(line, sizeof line, cap) || strncmp(line, want, strlen(want)) != 0 || !strstr(line, m->why))
                fail_msg("%s/captions.txt: got '%s', want '%s...%s'", dir, line, want, m->why);
            continue;
        }
        if (!fgets(line, sizeof line, cap) || strcmp(line, want) != 0)
            fail_msg("%s/captions.txt: got '%s', want '%s'", dir, line, want);
    }
    if (fgets(line, sizeof line, cap)) fail_msg("%s/captions.txt: extra line '%s'", dir, line);
    fclose(cap);
}

static void test_dump_every_method(void **state)
{
    (void)state;
    char names[256], args[2048], dir[512], png[512];
    snprintf(names, sizeof names, "%s", gi_vpl_method_names());
    int ran = 0;
    for (char *name = strtok(names, ", "); name; name = strtok(NULL, ", ")) {
        const gi_vpl_method *m = gi_vpl_method_find(name);
        assert_non_null(m);
        void *st = NULL;
        pf_error err;
        if (m->create(&st, NULL, &err) != PF_OK) fail_msg("method %s: create failed: %s", name, err.message);
        m->destroy(st);
        snprintf(dir, sizeof dir, "%s/dump-%s", g_tmp, name);
        snprintf(png, sizeof png, "%s/render-%s.png", g_tmp, name);
        snprintf(args, sizeof args, "render %s --method %s --vpls 64 -q --dump-stages %s -o %s", SIZE, name, dir, png);
        tu_softgi_expect(args, 0, NULL);
        check_dump(dir, 1, 1, m);
        /* the final view is the PNG render writes */
        snprintf(args, sizeof args, "%s/14-final.png", dir);
        if (!same_file(args, png)) fail_msg("method %s: %s differs from %s", name, args, png);
        ran++;
    }
    assert_int_equal(ran, 7); /* ir, iir, smc, mir, invtm, tcas, ssvp */
    /* the views a frame has no data for are not written */
    snprintf(dir, sizeof dir, "%s/dump-raytrace", g_tmp);
    snprintf(args, sizeof args, "render %s --visibility raytrace -q --dump-stages %s -o %s/rt.png", SIZE, dir, g_tmp);
    tu_softgi_expect(args, 0, NULL);
    check_dump(dir, 1, 0, gi_vpl_method_find("ir"));
    snprintf(dir, sizeof dir, "%s/dump-direct", g_tmp);
    snprintf(args, sizeof args, "render %s --direct-only -q --dump-stages %s -o %s/do.png", SIZE, dir, g_tmp);
    tu_softgi_expect(args, 0, NULL);
    check_dump(dir, 0, 0, NULL);
}

/* The viewer's dump is the render's dump, file for file. */
static void test_viewer_dump_equals_render_dump(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    char args[2048], out[16384], a[512], b[512], fa[1024], fb[1024];
    snprintf(a, sizeof a, "%s/vd-view", g_tmp);
    snprintf(b, sizeof b, "%s/vd-render", g_tmp);
    snprintf(args, sizeof args, "%s --vpls 64 --frames 1 -q --dump-stages %s", SIZE, a);
    int st = run_view(args, out, sizeof out);
    if (st != 0) fail_msg("softgi view %s: exit %d:\n%s", args, st, out);
    snprintf(args, sizeof args, "render %s --vpls 64 -q --dump-stages %s -o %s/vd.png", SIZE, b, g_tmp);
    tu_softgi_expect(args, 0, NULL);
    snprintf(fa, sizeof fa, "%s/captions.txt", a);
    snprintf(fb, sizeof fb, "%s/captions.txt", b);
    assert_true(same_file(fa, fb));
    for (int v = 0; v < GI_VIEW_COUNT; v++) {
        snprintf(fa, sizeof fa, "%s/%02d-%s.png", a, v, gi_view_name((gi_view_id)v));
        snprintf(fb, sizeof fb, "%s/%02d-%s.png", b, v, gi_view_name((gi_view_id)v));
        if (!same_file(fa, fb)) fail_msg("%s differs from %s", fa, fb);
    }
}

static void test_no_display(void **state)
{
    (void)state;
    char cmd[1024], out[16384];
    snprintf(cmd, sizeof cmd, "env -u DISPLAY -u WAYLAND_DISPLAY %s view %s --frames 1", SOFTGI_BINARY, SIZE);
    int st = tu_run(cmd, out, sizeof out);
    if (st != 1 || !strstr(out, "cannot open a window") || !strstr(out, "DISPLAY is not set"))
        fail_msg("%s: exit %d (want 1), output:\n%s", cmd, st, out);
    /* arguments and the scene are checked before any window opens */
    tu_softgi_expect("view --frames 0", 2, "--frames '0'");
    tu_softgi_expect("view /nonexistent/scene.gltf", 1, "no such file");
    tu_softgi_expect("view --method nosuch", 2, "--method 'nosuch'");
}

/* ------------------------------------------------------------ the probe, without a window */

static int same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static void expect_v3(const char *what, uint32_t x, uint32_t y, pf_vec3 got, const float *want)
{
    if (!same_bits(got.x, want[0]) || !same_bits(got.y, want[1]) || !same_bits(got.z, want[2]))
        fail_msg("pixel (%u, %u): probe %s %.9g %.9g %.9g, buffer %.9g %.9g %.9g", x, y, what, (double)got.x,
                 (double)got.y, (double)got.z, (double)want[0], (double)want[1], (double)want[2]);
}

/* Every field of the probe of pixel (x, y) against the frame. */
static void check_probe(const gi_frame *f, uint32_t x, uint32_t y)
{
    gi_probe p;
    gi_probe_pixel(&p, f, x, y);
    const size_t i = (size_t)y * f->width + x;
    const rs_gbuffer *g = &f->gbuf;
    assert_int_equal(p.x, x);
    assert_int_equal(p.prim, g->prim[i]);
    assert_true(same_bits(p.depth, g->depth[i]));
    assert_int_equal(p.surface, g->prim[i] != RS_GBUFFER_EMPTY);
    if (p.surface) {
        const float pos[3] = {g->pos_x[i], g->pos_y[i], g->pos_z[i]}, nrm[3] = {g->nrm_x[i], g->nrm_y[i], g->nrm_z[i]},
                    alb[3] = {g->alb_r[i], g->alb_g[i], g->alb_b[i]};
        expect_v3("position", x, y, p.position, pos);
        expect_v3("normal", x, y, p.normal, nrm);
        expect_v3("albedo", x, y, p.albedo, alb);
    }
    assert_int_equal(p.has_direct, f->show_direct);
    if (f->show_direct) expect_v3("direct", x, y, p.direct, f->direct + 3 * i);
    expect_v3("final", x, y, p.final, f->final + 3 * i);
    /* the final radiance is its parts, composed as gi_stage_compose does */
    const float e[3] = {p.emission.x, p.emission.y, p.emission.z}, d[3] = {p.direct.x, p.direct.y, p.direct.z},
                a[3] = {p.albedo.x, p.albedo.y, p.albedo.z}, fl[3] = {p.filtered.x, p.filtered.y, p.filtered.z};
    float composed[3];
    for (int c = 0; c < 3; c++) {
        float v = e[c] + (f->show_direct ? d[c] : 0.0f);
        if (f->indirect) v += a[c] * PF_INV_PI * fl[c];
        composed[c] = v;
    }
    expect_v3("final (composed from the probe)", x, y, p.final, composed);
    assert_int_equal(p.indirect, f->indirect);
    if (!f->indirect) return;
    const gi_indirect *ind = &f->ind;
    assert_int_equal(p.split, gi_split_index(ind, f->width, x, y));
    assert_int_equal(p.tile, (y % ind->m) * ind->n + x % ind->n);
    expect_v3("tile irradiance", x, y, p.tile_e, ind->split_e + 3 * (size_t)p.split);
    expect_v3("combined", x, y, p.combined, ind->combined + 3 * i);
    expect_v3("filtered", x, y, p.filtered, ind->filtered + 3 * i);
    /* the VPL-by-VPL re-evaluation is the accumulation */
    const float sum[3] = {p.tile_sum.x, p.tile_sum.y, p.tile_sum.z};
    expect_v3("tile irradiance (re-evaluated VPL by VPL)", x, y, p.tile_e, sum);
    assert_int_equal(p.top_count, p.lit < GI_PROBE_TOP ? p.lit : GI_PROBE_TOP);
    assert_true(p.lit + p.occluded <= p.tile_vpls && p.clamped <= p.lit);
    for (uint32_t k = 0; k < p.top_count; k++) {
        const gi_probe_vpl *v = &p.top[k];
        assert_true(v->index < ind->vpls.count);
        assert_int_equal(v->id, ind->vpls.v[v->index].id);
        assert_true(pf_luminance(v->e) > 0.0f || v->e.x + v->e.y + v->e.z > 0.0f);
        if (k) assert_true(pf_luminance(p.top[k - 1].e) >= pf_luminance(v->e));
        assert_true(v->g > 0.0f && (v->g <= ind->b || !isfinite(ind->b)));
    }
    /* the split and accumulated views draw this pixel where the probe says
     * (n w0 x m h0 can exceed the image: the views cut what lies outside) */
    uint32_t u, v, bx, by;
    if (!gi_view_view_pixel(f, GI_VIEW_ACCUMULATED, x, y, &u, &v)) {
        assert_true(p.mosaic_x >= f->width || p.mosaic_y >= f->height);
        return;
    }
    assert_int_equal(u, p.mosaic_x);
    assert_int_equal(v, p.mosaic_y);
    assert_true(gi_view_frame_pixel(f, GI_VIEW_SPLIT, u, v, &bx, &by));
    assert_int_equal(bx, x);
    assert_int_equal(by, y);
}

typedef struct probe_case {
    const char *name;
    const char *method;
    rs_simd simd;
    uint32_t tiles;
    int vis_raytrace, vis_ism, indirect_only, direct_only;
    gi_filter_kind filter;
    int pipeline;
} probe_case;

static void test_probe_equals_buffers(void **state)
{
    (void)state;
    pf_isa isa;
    pf_error err;
    assert_int_equal(pf_isa_resolve(PF_ISA_AUTO, &isa, &err), PF_OK);
    const probe_case cases[] = {
        {"paraboloid, SIMD", "ir", rs_simd_for_isa(isa), 4, 0, 0, 0, 0, GI_FILTER_BOX, 0},
        {"paraboloid, scalar", "ir", RS_SIMD_SCALAR, 2, 0, 0, 0, 0, GI_FILTER_BOX, 0},
        {"no interleaving", "ir", rs_simd_for_isa(isa), 1, 0, 0, 0, 0, GI_FILTER_NONE, 0},
        {"raytraced visibility", "ir", RS_SIMD_SCALAR, 4, 1, 0, 0, 0, GI_FILTER_BOX, 0},
        {"ism", "ir", rs_simd_for_isa(isa), 4, 0, 1, 0, 0, GI_FILTER_BOX, 0},
        {"iir, bilateral, indirect only", "iir", rs_simd_for_isa(isa), 4, 0, 0, 1, 0, GI_FILTER_BILATERAL, 0},
        {"direct only", "ir", rs_simd_for_isa(isa), 4, 0, 0, 0, 1, GI_FILTER_BOX, 0},
        {"smc, pipelined", "smc", rs_simd_for_isa(isa), 4, 0, 0, 0, 0, GI_FILTER_BOX, 1},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const probe_case *pc = &cases[c];
        tu_fx x;
        memset(&x, 0, sizeof x);
        assert_int_equal(pf_gltf_load(&x.scene, CORNELL, NULL, &err), PF_OK);
        gi_indirect_options io;
        memset(&io, 0, sizeof io);
        io.method = gi_vpl_method_find(pc->method);
        io.vpls = 64;
        io.clamp = -1.0f;
        io.para_res = 32;
        io.tiles_n = io.tiles_m = pc->tiles;
        io.no_interleave = pc->tiles == 1;
        io.visibility_raytrace = pc->vis_raytrace;
        io.visibility_ism = pc->vis_ism;
        io.filter = pc->filter;
        io.pipeline = pc->pipeline;
        const uint32_t W = 45, H = 34; /* not a multiple of the tiles: uneven tiles */
        tu_fx_begin(&x, 2, pc->simd, W, H, &x.scene.cameras[0], pc->direct_only ? NULL : &io, pc->indirect_only);
        for (int frame = 0; frame < 2; frame++) { /* the second: IIR's kept VPLs, the pipeline's last set */
            x.scene.lights[0].position.x += 0.01f * (float)frame;
            gi_frame_render_raster(&x.f);
            for (uint32_t py = 0; py < H; py++)
                for (uint32_t px = 0; px < W; px++) check_probe(&x.f, px, py);
        }
        /* the text names the pixel and, with 9 digits, reads back exactly */
        gi_probe p;
        char text[4096], want[64];
        gi_probe_pixel(&p, &x.f, W / 2, H / 2);
        assert_true(gi_probe_text(text, sizeof text, &p, 9, GI_PROBE_TOP) < (int)sizeof text);
        snprintf(want, sizeof want, "pixel %u %u\n", W / 2, H / 2);
        if (strncmp(text, want, strlen(want)) != 0) fail_msg("%s: probe text starts '%.40s'", pc->name, text);
        const char *fin = strstr(text, "\nfinal ");
        assert_non_null(fin);
        float v[3];
        assert_int_equal(sscanf(fin, " final %f %f %f", &v[0], &v[1], &v[2]), 3);
        expect_v3("final (text)", W / 2, H / 2, p.final, v);
        assert_true(gi_probe_text(text, 8, &p, 9, GI_PROBE_TOP) > 8 && strlen(text) == 7); /* truncated, terminated */
        tu_fx_end(&x);
    }
}

/* ------------------------------------------------------------ zoom and pan */

static void test_zoom_and_pan(void **state)
{
    (void)state;
    enum { SW = 40, SH = 30 };
    uint8_t src[SW * SH * 3], dst[2 * SW * 2 * SH * 3];
    for (int i = 0; i < SW * SH; i++) src[3 * i] = (uint8_t)(i % SW), src[3 * i + 1] = (uint8_t)(i / SW), src[3 * i + 2] = 7;
    gi_view_zoom z;
    gi_view_zoom_reset(&z, SW, SH);
    /* unzoomed, the same size: a copy; every pixel's centre picks itself */
    gi_view_blit(dst, SW, SH, src, SW, SH, &z);
    assert_memory_equal(dst, src, sizeof src);
    uint32_t u, v;
    for (uint32_t y = 0; y < SH; y++)
        for (uint32_t x = 0; x < SW; x++) {
            assert_true(gi_view_zoom_to_view(&z, SW, SH, SW, SH, (float)x + 0.5f, (float)y + 0.5f, &u, &v));
            assert_true(u == x && v == y);
        }
    /* a window twice as large (and wider): fitted, centred; zoomed 4x about
     * a point: the point keeps its pixel, and every window pixel shows the
     * view pixel a click there picks */
    const uint32_t DW = 2 * SW, DH = 2 * SH - 6;
    float wx = 31.5f, wy = 17.5f;
    uint32_t u0, v0;
    assert_true(gi_view_zoom_to_view(&z, SW, SH, DW, DH, wx, wy, &u0, &v0));
    gi_view_zoom_at(&z, SW, SH, DW, DH, wx, wy, 4.0f);
    assert_true(z.zoom == 4.0f);
    assert_true(gi_view_zoom_to_view(&z, SW, SH, DW, DH, wx, wy, &u, &v));
    assert_true(u == u0 && v == v0);
    gi_view_blit(dst, DW, DH, src, SW, SH, &z);
    int inside = 0;
    for (uint32_t y = 0; y < DH; y++)
        for (uint32_t x = 0; x < DW; x++) {
            const uint8_t *o = dst + 3 * ((size_t)y * DW + x);
            if (gi_view_zoom_to_view(&z, SW, SH, DW, DH, (float)x + 0.5f, (float)y + 0.5f, &u, &v)) {
                inside++;
                assert_true(o[0] == u && o[1] == v && o[2] == 7);
            } else {
                assert_true(o[0] == 16 && o[2] == 16);
            }
        }
    assert_true(inside > 0);
    /* to_window is the inverse at pixel centres */
    float px, py;
    gi_view_zoom_to_window(&z, SW, SH, DW, DH, (float)u0 + 0.5f, (float)v0 + 0.5f, &px, &py);
    assert_true(gi_view_zoom_to_view(&z, SW, SH, DW, DH, px, py, &u, &v) && u == u0 && v == v0);
    /* pans keep the centre inside the view; zooming out to 1 recentres */
    gi_view_zoom_pan(&z, SW, SH, DW, DH, 1e6f, -1e6f);
    assert_true(z.cx == 0.0f && z.cy == (float)SH);
    gi_view_zoom_at(&z, SW, SH, DW, DH, 3.0f, 3.0f, 1.0f / 64.0f);
    assert_true(z.zoom == 1.0f && z.cx == 0.5f * SW && z.cy == 0.5f * SH);
    gi_view_zoom_at(&z, SW, SH, DW, DH, 3.0f, 3.0f, 1e9f);
    assert_true(z.zoom == GI_VIEW_ZOOM_MAX);
}

/* ------------------------------------------------------------ the probe under Xvfb */

/* "name v0 v1 v2" from probe text: the n numbers after a line that starts
 * with "name ". */
static void probe_values(const char *text, const char *name, float *v, int n)
{
    char key[64];
    snprintf(key, sizeof key, "%s ", name);
    for (const char *l = text; l && *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL) {
        if (strncmp(l, key, strlen(key)) != 0) continue;
        const char *p = l + strlen(key);
        for (int k = 0; k < n; k++) {
            char *end;
            v[k] = strtof(p, &end);
            if (end == p) fail_msg("probe line '%s': cannot read value %d", name, k);
            p = end;
        }
        return;
    }
    fail_msg("no '%s' line in the probe:\n%s", name, text);
}

/* A dumped .exr's pixel (x, y) (RGB; Y files read as R = G = B). */
static void exr_pixel(const char *dir, const char *file, uint32_t x, uint32_t y, float *rgb)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    float *px = NULL;
    uint32_t w, h;
    pf_error err;
    if (pf_imageio_read_image(path, PF_IMAGEIO_DATA, &px, &w, &h, &err) != PF_OK) fail_msg("%s", err.message);
    assert_true(x < w && y < h);
    memcpy(rgb, px + 3 * ((size_t)y * w + x), 3 * sizeof(float));
    free(px);
}

static void expect_dump(const char *dir, const char *file, uint32_t x, uint32_t y, const char *probe, const char *name,
                        int n)
{
    float want[3], got[3] = {0, 0, 0};
    exr_pixel(dir, file, x, y, want);
    probe_values(probe, name, got, n);
    for (int c = 0; c < n; c++)
        if (!same_bits(got[c], want[c]))
            fail_msg("%s pixel (%u, %u): the viewer's probe %s[%d] = %.9g, the dump's %s = %.9g", dir, x, y, name, c,
                     (double)got[c], file, (double)want[c]);
}

/* Runs the viewer in g_tmp/run-TAG with the script; the probe of pixel
 * (x, y) it printed and dumped must equal the dumped float data there. */
static void check_probe_dump(const char *tag, const char *args, const char *script, uint32_t x, uint32_t y)
{
    char cmd[8192], out[65536], dir[1024], path[1200], want[64];
    snprintf(dir, sizeof dir, "%s/run-%s", g_tmp, tag);
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && cd %s && SOFTGI_VIEW_KEYS='%s' xvfb-run -a -s '-screen 0 1280x1024x24' %s view %s %s",
             dir, dir, script, SOFTGI_BINARY, SIZE, args);
    int st = tu_run(cmd, out, sizeof out);
    if (st != 0) fail_msg("%s: exit %d:\n%s", cmd, st, out);
    const char *dumped = strstr(out, "softgi view: dumped frame ");
    unsigned frame = 0;
    if (!dumped || sscanf(dumped, "softgi view: dumped frame %u", &frame) != 1) fail_msg("%s: no dump:\n%s", tag, out);
    snprintf(dir, sizeof dir, "%s/run-%s/out/cornell-box-frame%u", g_tmp, tag, frame);
    snprintf(path, sizeof path, "%s/probe.txt", dir);
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s: no %s:\n%s", tag, path, out);
    static char probe[16384];
    size_t n = fread(probe, 1, sizeof probe - 1, f);
    probe[n] = 0;
    fclose(f);
    snprintf(want, sizeof want, "pixel %u %u\n", x, y);
    if (strncmp(probe, want, strlen(want)) != 0) fail_msg("%s: probed '%.20s', want '%s'", tag, probe, want);
    if (!strstr(out, probe)) fail_msg("%s: the probe printed differs from probe.txt:\n%s\n---\n%s", tag, out, probe);
    expect_dump(dir, "00-depth.exr", x, y, probe, "depth", 1);
    expect_dump(dir, "01-position.exr", x, y, probe, "position", 3);
    expect_dump(dir, "02-normal.exr", x, y, probe, "normal", 3);
    expect_dump(dir, "03-albedo.exr", x, y, probe, "albedo", 3);
    expect_dump(dir, "06-direct.exr", x, y, probe, "direct", 3);
    expect_dump(dir, "12-combined.exr", x, y, probe, "combined", 3);
    expect_dump(dir, "13-filtered.exr", x, y, probe, "filtered", 3);
    expect_dump(dir, "14-final.exr", x, y, probe, "final", 3);
    /* the tile irradiance, where the accumulated mosaic draws the pixel: 4x4 tiles of 40 x 30 */
    expect_dump(dir, "11-accumulated.exr", (x % 4) * 40 + x / 4, (y % 4) * 30 + y / 4, probe, "tile-irradiance", 3);
}

static void test_probe_equals_dump(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    /* a click at 1:1, and X saves the final view: render's PNG */
    check_probe_dump("plain", "--frames 4", "click:37:51 shift+X X", 37, 51);
    char png[1024], shot[1024];
    snprintf(shot, sizeof shot, "%s/run-plain/out/cornell-box-frame1-14-final.png", g_tmp); /* clicked before frame 1 */
    snprintf(png, sizeof png, "%s/probe-render.png", g_tmp);
    char args[2048];
    snprintf(args, sizeof args, "render %s -q -o %s", SIZE, png);
    tu_softgi_expect(args, 0, NULL);
    if (!same_file(shot, png)) fail_msg("X saved %s, which differs from render's %s", shot, png);
    /* zoomed 4x about (100, 60): the pixel there stays; 9 window pixels
     * right and 5 down are 2 and 1 view pixels further (4-pixel texels) */
    check_probe_dump("zoom", "--frames 5 --vpls 64 --filter bilateral", "wheel:100:60:2 click:109:65 P shift+X", 102,
                     61);
    /* paused, the list's accumulated mosaic (V, three up from final,
     * ENTER); a click at mosaic (93, 44) is tile (2, 1), its pixel (13, 14):
     * frame pixel (13 * 4 + 2, 14 * 4 + 1) */
    check_probe_dump("mosaic", "--frames 8", "P V UP UP UP ENTER click:93:44 shift+X", 54, 57);
}

/* ------------------------------------------------------------ the HUD in small windows */

static void check_hud(const char *size, const char *script, const char *expect, const char *expect2)
{
    char cmd[8192], out[65536];
    snprintf(cmd, sizeof cmd,
             "cd %s && SOFTGI_VIEW_KEYS='%s' xvfb-run -a -s '-screen 0 1280x1024x24' %s view --size %s --vpls 64 "
             "--frames 40",
             g_tmp, script, SOFTGI_BINARY, size);
    int st = tu_run(cmd, out, sizeof out);
    if (st != 0) fail_msg("%s: exit %d:\n%s", cmd, st, out);
    char want[128];
    snprintf(want, sizeof want, "HUD in a %s window: ", size);
    const char *hud = strstr(out, want);
    if (!hud) fail_msg("%s: no HUD summary:\n%s", cmd, out);
    unsigned lines = 0, clipped = 1;
    assert_int_equal(sscanf(hud + strlen(want), "%u lines drawn, %u clipped", &lines, &clipped), 2);
    if (clipped != 0 || lines < 100) fail_msg("%s: %u of %u HUD lines cross the window's edge:\n%s", size, clipped, lines, out);
    if (expect && !strstr(out, expect)) fail_msg("%s: no '%s' in:\n%s", size, expect, out);
    if (expect2 && !strstr(out, expect2)) fail_msg("%s: no '%s' in:\n%s", size, expect2, out);
}

static void test_hud_fits(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    /* the probe, every help page, the view list, the caption, the zoom, the
     * grabbed light (ir -> iir and back) */
    const char *script = "click:150:100 H H H H V DOWN DOWN UP ENTER N N N Z Z shift+Z V ESC L W D 0 P L wheel:10:10:3 "
                         "pan:40:-30 K rclick:5:5 M";
    check_hud("320x240", script, "light grabbed: iir while it moves", "light released: back to ir");
    check_hud("640x480", script, NULL, NULL);
    check_hud("200x150", "H V click:50:50 P N", NULL, NULL);
}

/* L with ir: the frame runs iir while the light is grabbed and moved
 * (replayed W D E move it a frame each), rendering far fewer VPL maps a
 * frame than ir's one per VPL, and goes back to ir on release. */
static void test_light_grab_keeps_up(void **state)
{
    (void)state;
    if (!have_xvfb()) {
        print_message("SKIP: xvfb-run is absent: cannot start the viewer\n");
        return;
    }
    char cmd[8192], out[65536];
    snprintf(cmd, sizeof cmd,
             "SOFTGI_VIEW_KEYS='L W W W D D E L' xvfb-run -a -s '-screen 0 1280x1024x24' %s view %s --vpls 64 "
             "--frames 10",
             SOFTGI_BINARY, SIZE);
    int st = tu_run(cmd, out, sizeof out);
    if (st != 0) fail_msg("%s: exit %d:\n%s", cmd, st, out);
    if (!strstr(out, "light grabbed: iir while it moves")) fail_msg("no switch to iir:\n%s", out);
    const char *rel = strstr(out, "light released: back to ir (iir rendered ");
    float maps = 1e9f;
    if (!rel || sscanf(rel, "light released: back to ir (iir rendered %f", &maps) != 1) fail_msg("no release:\n%s", out);
    if (!(maps < 16.0f)) fail_msg("iir rendered %.1f maps a frame of 64 VPLs while the light moved:\n%s", (double)maps, out);
}

static int setup(void **state)
{
    (void)state;
    return tu_tmpdir_create(g_tmp, sizeof g_tmp, "softgi-viewer");
}

static int teardown(void **state)
{
    (void)state;
    return tu_tmpdir_remove(g_tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_screenshot_equals_render),
        cmocka_unit_test(test_progressive_default),
        cmocka_unit_test(test_dump_every_method),
        cmocka_unit_test(test_viewer_dump_equals_render_dump),
        cmocka_unit_test(test_keys_settings_and_stepper),
        cmocka_unit_test(test_optional_stage_keys),
        cmocka_unit_test(test_no_display),
        cmocka_unit_test(test_probe_equals_buffers),
        cmocka_unit_test(test_zoom_and_pan),
        cmocka_unit_test(test_probe_equals_dump),
        cmocka_unit_test(test_hud_fits),
        cmocka_unit_test(test_light_grab_keeps_up),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
