/* test_viewer: `softgi view` and the stage views it shares with
 * `softgi render --dump-stages` (gi_view).
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

#include "gi_view.h"
#include "gi_vpl.h"
#include "test_util.h"

#define SIZE "--size 160x120"

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

/* Keys replayed through SOFTGI_VIEW_KEYS: a method that is not implemented
 * yet and ism visibility are refused with their message (the previous
 * setting stays), the next O reaches raytrace, ] I F C set 512 VPLs, 8x8
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
    /* while ism is a placeholder, the viewer must say so and keep paraboloid maps */
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

/* The expected dump: the views available for the given settings. */
static void check_dump(const char *dir, int indirect, int para_maps)
{
    char path[1024], line[1024], want[1024];
    snprintf(path, sizeof path, "%s/captions.txt", dir);
    FILE *cap = fopen(path, "r");
    if (!cap) fail_msg("%s is missing", path);
    for (int v = 0; v < GI_VIEW_COUNT; v++) {
        int expected = 1;
        if (v >= GI_VIEW_VPLS && v <= GI_VIEW_FILTERED) expected = indirect;
        if (v == GI_VIEW_VPL_MAP) expected = indirect && para_maps;
        snprintf(path, sizeof path, "%s/%02d-%s.png", dir, v, gi_view_name((gi_view_id)v));
        if (tu_file_exists(path) != expected)
            fail_msg("%s should %s", path, expected ? "exist" : "not be written (the frame has no such data)");
        if (!expected) continue;
        snprintf(want, sizeof want, "%02d-%s.png: %s\n", v, gi_view_name((gi_view_id)v),
                 gi_view_caption((gi_view_id)v));
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
        check_dump(dir, 1, 1);
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
    check_dump(dir, 1, 0);
    snprintf(dir, sizeof dir, "%s/dump-direct", g_tmp);
    snprintf(args, sizeof args, "render %s --direct-only -q --dump-stages %s -o %s/do.png", SIZE, dir, g_tmp);
    tu_softgi_expect(args, 0, NULL);
    check_dump(dir, 0, 0);
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
        cmocka_unit_test(test_dump_every_method),
        cmocka_unit_test(test_viewer_dump_equals_render_dump),
        cmocka_unit_test(test_keys_settings_and_stepper),
        cmocka_unit_test(test_no_display),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
