/* app_view: `softgi view [SCENE]`, the interactive viewer and frame-stage
 * stepper (issue 7).
 *
 * Every frame is the CPU frame of `softgi render` (gi_frame_render_raster,
 * or the ray-traced one with --raytrace) with the same options, shown in a
 * GLFW window (pf_window: OpenGL 1.x textured quad, works on Mesa's
 * software llvmpipe and under Xvfb). On top, a HUD drawn on the CPU with
 * gi_view's bitmap font: frame time, the per-stage times as a bar, VPL
 * count, VPLs moved this frame, the method, and the key help (H).
 *
 * Teaching mode (the stepper): P pauses on the current frame and N / B
 * step through its stages in the order they run (gi_view.h: G-buffer
 * channels, shadow map, direct light, VPLs over the image and from above,
 * one VPL's paraboloid map, split, accumulated, combined, filtered, final),
 * each with its one-line caption naming the paper section it implements.
 * `--dump-stages DIR` writes the same pictures (gi_view_dump).
 *
 * Settings changed by keys (method, VPL count, tiles, filter, visibility,
 * clamp) rebuild the frame's indirect state and apply from the next frame
 * on; a setting the frame cannot take (a method that is "not implemented
 * yet", too many VPLs for the maps) leaves the previous one in place and
 * shows the error in the HUD.
 *
 * Headless: `--frames N` shows N frames and exits 0; with `--screenshot
 * FILE` the window's framebuffer (the displayed view without the HUD: the
 * final image unless the stepper shows a stage) is read back after frame N
 * and written as a PNG, byte-identical to `softgi render`'s PNG of the same
 * camera and options (tests/test_viewer.c). The environment variable
 * SOFTGI_VIEW_KEYS replays key presses, one per frame shown, so the tests
 * drive the settings and the stepper without a keyboard. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "gi_frame.h"
#include "gi_view.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"
#include "pf_window.h"

#define VIEW_MAX_METHODS 16

typedef struct view_app {
    const pf_options *opt;
    char stem[256];
    uint32_t width, height;
    /* the renderer (as app_render sets it up) */
    pf_scene scene;
    pf_camera camera, camera_start;
    pf_rt *rt;
    pf_jobs *jobs;
    rs_context *raster;
    gi_frame frame;
    int frame_ready;
    /* settings applied from the next frame on */
    gi_indirect_options io;   /* the indirect state the frame was built with */
    gi_indirect_options want; /* what the keys asked for */
    int indirect_dirty;
    uint32_t method_count, method_cursor;
    uint32_t vis_cursor; /* 0 paraboloid, 1 ism, 2 raytrace */
    const gi_vpl_method *methods[VIEW_MAX_METHODS];
    float exposure;
    /* fly camera and light */
    float yaw, pitch, speed;
    int light_grab;
    /* stepper */
    int paused, stage; /* stage: a gi_view_id while paused */
    uint32_t vpl_pick;
    int show_help, show_hud;
    /* what happened */
    int frame_needed, image_dirty;
    uint32_t frames_done;  /* frames rendered */
    uint32_t frames_shown; /* loop iterations (a paused viewer shows frames without rendering) */
    /* SOFTGI_VIEW_KEYS: key presses replayed one per shown frame */
    uint32_t script_count, script_next;
    int script_key[256], script_mods[256];
    double frame_ms, total_ms;
    double loop_start;     /* when the first frame began (for the whole-loop rate) */
    uint32_t vpls_moved;
    char message[1024];
    double message_until;
    /* images: the view without HUD, and what goes to the window */
    uint8_t *image, *display;
    pf_window *win;
} view_app;

/* ------------------------------------------------------------ messages */

__attribute__((format(printf, 2, 3))) static void view_message(view_app *a, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(a->message, sizeof a->message, fmt, ap);
    va_end(ap);
    a->message_until = pf_time_now() + 6.0;
    if (!a->opt->quiet) fprintf(stderr, "softgi view: %s\n", a->message);
}

/* ------------------------------------------------------------ scripted keys */

/* SOFTGI_VIEW_KEYS="M O O ] P N N": key presses replayed one per shown
 * frame before the window's own events, so tests (and demos) can drive the
 * viewer headless. Names: a letter or digit, [ ] - =, SPACE TAB ESC F1 LEFT
 * RIGHT UP DOWN, each optionally prefixed with "shift+". */
static pf_result view_parse_script(view_app *a, const char *text, pf_error *err)
{
    static const struct {
        const char *name;
        int key;
    } named[] = {{"SPACE", PF_KEY_SPACE}, {"TAB", PF_KEY_TAB},   {"ESC", PF_KEY_ESCAPE}, {"F1", PF_KEY_F1},
                 {"LEFT", PF_KEY_LEFT},   {"RIGHT", PF_KEY_RIGHT}, {"UP", PF_KEY_UP},   {"DOWN", PF_KEY_DOWN},
                 {"[", PF_KEY_LEFT_BRACKET}, {"]", PF_KEY_RIGHT_BRACKET}, {"-", PF_KEY_MINUS}, {"=", PF_KEY_EQUAL}};
    char buf[2048];
    snprintf(buf, sizeof buf, "%s", text);
    for (char *tok = strtok(buf, " ,"); tok; tok = strtok(NULL, " ,")) {
        if (a->script_count >= sizeof a->script_key / sizeof a->script_key[0])
            return pf_error_set(err, PF_ERR_ARGUMENT, "SOFTGI_VIEW_KEYS: at most 256 keys");
        int mods = 0, key = -1;
        if (!strncmp(tok, "shift+", 6)) mods = PF_MOD_SHIFT, tok += 6;
        if (strlen(tok) == 1 && ((tok[0] >= 'A' && tok[0] <= 'Z') || (tok[0] >= '0' && tok[0] <= '9'))) key = tok[0];
        if (strlen(tok) == 1 && tok[0] >= 'a' && tok[0] <= 'z') key = tok[0] - 'a' + 'A';
        for (size_t k = 0; key < 0 && k < sizeof named / sizeof named[0]; k++)
            if (!strcmp(tok, named[k].name)) key = named[k].key;
        if (key < 0)
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "SOFTGI_VIEW_KEYS: unknown key '%s' (a letter or digit, [ ] - =, SPACE TAB ESC F1 LEFT "
                                "RIGHT UP DOWN, optionally shift+)",
                                tok);
        a->script_key[a->script_count] = key;
        a->script_mods[a->script_count] = mods;
        a->script_count++;
    }
    return PF_OK;
}

/* ------------------------------------------------------------ setup */

/* The method registry, in its order (gi_vpl_method_names). */
static void view_list_methods(view_app *a)
{
    char names[256];
    snprintf(names, sizeof names, "%s", gi_vpl_method_names());
    a->method_count = 0;
    for (char *tok = strtok(names, ", "); tok && a->method_count < VIEW_MAX_METHODS; tok = strtok(NULL, ", ")) {
        const gi_vpl_method *m = gi_vpl_method_find(tok);
        if (m) a->methods[a->method_count++] = m;
    }
    for (uint32_t i = 0; i < a->method_count; i++)
        if (a->methods[i] == a->io.method) a->method_cursor = i;
}

static void view_camera_angles(view_app *a)
{
    pf_vec3 f = a->camera.forward;
    a->yaw = atan2f(f.x, f.z);
    a->pitch = asinf(pf_clampf(f.y, -1.0f, 1.0f));
}

/* Scene, Embree, jobs, raster context and frame, as app_render. */
static pf_result view_setup(view_app *a, pf_error *err)
{
    const pf_options *o = a->opt;
    a->width = o->width ? o->width : 640;
    a->height = o->height ? o->height : 480;
    uint32_t threads = o->threads ? o->threads : pf_jobs_core_count();
    pf_isa isa;
    pf_result r = pf_isa_resolve(o->isa, &isa, err);
    if (r != PF_OK) return r;
    const char *script = getenv("SOFTGI_VIEW_KEYS");
    if (script && (r = view_parse_script(a, script, err)) != PF_OK) return r;
    if ((r = app_scene_load(o, &a->scene, &a->camera, a->stem, sizeof a->stem, err)) != PF_OK) return r;
    a->camera_start = a->camera;
    if ((r = pf_rt_create(&a->rt, &a->scene, isa, threads, err)) != PF_OK) return r;
    a->jobs = pf_jobs_create(threads);
    if (!a->jobs) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "cannot start %u threads", threads);
    if (!o->raytrace && (r = rs_context_create(&a->raster, &a->scene, a->jobs, rs_simd_for_isa(isa), err)) != PF_OK)
        return r;
    r = app_frame_init(o, &a->frame, &a->scene, a->rt, a->raster, a->jobs, &a->camera, a->width, a->height, 1, err);
    if (r != PF_OK) return r;
    a->frame_ready = 1;
    if (a->frame.indirect) {
        a->io = a->frame.ind.opt; /* as the command line gave it, with the defaults filled in */
        a->want = a->io;
        a->vis_cursor = a->io.visibility_ism ? 1 : a->io.visibility_raytrace ? 2 : 0;
    }
    view_list_methods(a);
    a->exposure = o->exposure;
    view_camera_angles(a);
    float diag = pf_v3_length(pf_v3_sub(a->scene.bounds_max, a->scene.bounds_min));
    a->speed = 0.25f * diag; /* scene units per second */
    a->show_hud = 1;
    a->frame_needed = 1;
    size_t bytes = (size_t)a->width * a->height * 3;
    a->image = calloc(bytes, 1);
    a->display = calloc(bytes, 1);
    if (!a->image || !a->display) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    return PF_OK;
}

static void view_teardown(view_app *a)
{
    pf_window_close(a->win);
    free(a->image);
    free(a->display);
    if (a->frame_ready) gi_frame_free(&a->frame);
    rs_context_destroy(a->raster);
    if (a->jobs) pf_jobs_destroy(a->jobs);
    if (a->rt) pf_rt_destroy(a->rt);
    if (a->scene.positions) pf_scene_free(&a->scene);
}

/* ------------------------------------------------------------ state changes */

/* Rebuilds the frame's indirect state with a->want; on failure shows why
 * and goes back to the previous settings. */
static void view_apply_indirect(view_app *a)
{
    a->indirect_dirty = 0;
    if (!a->frame.indirect) return;
    pf_error err;
    gi_indirect_free(&a->frame.ind);
    a->frame.indirect = 0;
    if (gi_frame_enable_indirect(&a->frame, &a->want, a->opt->indirect_only, &err) == PF_OK) {
        a->io = a->frame.ind.opt;
        a->want = a->io;
        return;
    }
    view_message(a, "%s (kept the previous settings)", err.message);
    gi_indirect_free(&a->frame.ind);
    if (gi_frame_enable_indirect(&a->frame, &a->io, a->opt->indirect_only, &err) != PF_OK) {
        gi_indirect_free(&a->frame.ind); /* cannot happen: these settings worked; render direct light only */
        view_message(a, "indirect light off: %s", err.message);
    }
    a->want = a->io;
}

/* The next (step = +1) or previous method of the registry whose create
 * succeeds; a method that fails ("not implemented yet") is named in the HUD
 * and the current one stays. --param values belong to the first method and
 * are dropped on a switch. */
static void view_switch_method(view_app *a, int step)
{
    if (!a->frame.indirect || a->method_count == 0) return;
    a->method_cursor = (a->method_cursor + a->method_count + (uint32_t)(step > 0 ? 1 : -1)) % a->method_count;
    const gi_vpl_method *m = a->methods[a->method_cursor];
    void *state = NULL;
    pf_error err;
    if (m->create(&state, NULL, &err) != PF_OK) {
        view_message(a, "%s: %s", m->name, err.message);
        return;
    }
    m->destroy(state);
    a->want.method = m;
    memset(&a->want.params, 0, sizeof a->want.params);
    a->indirect_dirty = 1;
    view_message(a, "method %s: %s", m->name, m->paper);
}

static void view_cycle_tiles(view_app *a)
{
    static const uint32_t n[] = {4, 8, 1, 2};
    uint32_t k = 0;
    while (k < 4 && n[k] != a->want.tiles_n) k++;
    uint32_t next = n[(k + 1) % 4];
    a->want.tiles_n = a->want.tiles_m = next;
    a->want.no_interleave = next == 1;
    a->indirect_dirty = 1;
}

static void view_cycle_filter(view_app *a)
{
    a->want.filter = a->want.filter == GI_FILTER_BOX ? GI_FILTER_BILATERAL
                     : a->want.filter == GI_FILTER_BILATERAL ? GI_FILTER_NONE
                                                             : GI_FILTER_BOX;
    a->indirect_dirty = 1;
}

/* paraboloid -> ism -> raytrace: the cursor moves on even when a choice
 * fails (ism while it is not implemented), so every press tries the next. */
static void view_cycle_visibility(view_app *a)
{
    a->vis_cursor = (a->vis_cursor + 1) % 3;
    a->want.visibility_ism = a->vis_cursor == 1;
    a->want.visibility_raytrace = a->vis_cursor == 2;
    a->indirect_dirty = 1;
}

static void view_cycle_clamp(view_app *a)
{
    static const float c[] = {400.0f, 1600.0f, 6400.0f, 0.0f, 25.0f, 100.0f};
    uint32_t k = 0;
    while (k < 6 && c[k] != a->want.clamp) k++;
    a->want.clamp = c[(k + 1) % 6];
    a->indirect_dirty = 1;
}

static void view_scale_vpls(view_app *a, int up)
{
    uint32_t v = a->want.vpls;
    v = up ? (v < (1u << 16) ? v * 2 : v) : (v > 1 ? v / 2 : 1);
    a->want.vpls = v;
    a->indirect_dirty = 1;
}

/* ------------------------------------------------------------ input */

static const char *const view_help[] = {
    "mouse drag (left)   look around",
    "W A S D / Q E       fly / down, up (shift: faster)",
    "L                   grab light 0: W A S D Q E move it",
    "R                   camera back to the start",
    "M / shift+M         next / previous VPL method",
    "[ / ]               half / double the VPLs",
    "I                   interleave 4x4, 8x8, off, 2x2",
    "F                   filter box, bilateral, none",
    "O                   visibility paraboloid, ism, raytrace",
    "C                   clamp 400, 1600, 6400, off, 25, 100",
    "- / =               exposure -/+ 0.5 stop",
    "P / space           pause: the stage stepper",
    "N / B (arrows)      next / previous stage",
    "K / shift+K         next / previous VPL (paraboloid map)",
    "TAB                 HUD on / off",
    "H / F1              this help       ESC  quit",
};

/* Next (+1) or previous (-1) stage view the frame has, from `from`. */
static int view_next_stage(const view_app *a, int from, int step)
{
    int s = from;
    for (int k = 0; k < GI_VIEW_COUNT; k++) {
        s = (s + step + GI_VIEW_COUNT) % GI_VIEW_COUNT;
        if (gi_view_available(&a->frame, (gi_view_id)s)) return s;
    }
    return GI_VIEW_FINAL;
}

/* One key press: state changes only (the frame is rendered later). */
static int view_handle_key(view_app *a, int key, int mods)
{
    int shift = (mods & PF_MOD_SHIFT) != 0;
    switch (key) {
    case PF_KEY_ESCAPE: return 1;
    case 'H':
    case PF_KEY_F1: a->show_help = !a->show_help; break;
    case PF_KEY_TAB: a->show_hud = !a->show_hud; break;
    case 'P':
    case PF_KEY_SPACE:
        a->paused = !a->paused;
        a->stage = GI_VIEW_FINAL;
        a->image_dirty = 1;
        break;
    case 'N':
    case PF_KEY_RIGHT:
    case 'B':
    case PF_KEY_LEFT:
        if (!a->paused) a->paused = 1, a->stage = GI_VIEW_FINAL;
        a->stage = view_next_stage(a, a->stage, key == 'N' || key == PF_KEY_RIGHT ? 1 : -1);
        a->image_dirty = 1;
        break;
    case 'K':
        a->vpl_pick += shift ? (uint32_t)-1 : 1u;
        if (a->frame.indirect && a->frame.ind.vpls.count) a->vpl_pick %= a->frame.ind.vpls.count;
        a->image_dirty = 1;
        break;
    case 'L':
        if (a->scene.light_count == 0) view_message(a, "the scene has no light to grab");
        else a->light_grab = !a->light_grab;
        break;
    case 'R':
        a->camera = a->camera_start;
        view_camera_angles(a);
        a->frame_needed = 1;
        break;
    case 'M': view_switch_method(a, shift ? -1 : 1); break;
    case PF_KEY_LEFT_BRACKET: view_scale_vpls(a, 0); break;
    case PF_KEY_RIGHT_BRACKET: view_scale_vpls(a, 1); break;
    case 'I': view_cycle_tiles(a); break;
    case 'F': view_cycle_filter(a); break;
    case 'O': view_cycle_visibility(a); break;
    case 'C': view_cycle_clamp(a); break;
    case PF_KEY_MINUS:
    case PF_KEY_EQUAL:
        a->exposure = pf_clampf(a->exposure + (key == PF_KEY_EQUAL ? 0.5f : -0.5f), -64.0f, 64.0f);
        a->image_dirty = 1;
        break;
    default: break;
    }
    if (a->indirect_dirty && !a->frame.indirect) {
        a->indirect_dirty = 0;
        view_message(a, "indirect light is off (--direct-only)");
    }
    if (a->indirect_dirty) a->frame_needed = 1;
    return 0;
}

/* Mouse-look and WASD/QE motion of the camera, or of light 0 while
 * grabbed; dt: seconds since the last frame. */
static void view_handle_motion(view_app *a, const pf_input *in, double dt)
{
    if (in->mouse_dx != 0.0 || in->mouse_dy != 0.0) {
        a->yaw -= (float)in->mouse_dx * 0.004f;
        a->pitch = pf_clampf(a->pitch - (float)in->mouse_dy * 0.004f, -1.55f, 1.55f);
        pf_vec3 f = pf_v3(cosf(a->pitch) * sinf(a->yaw), sinf(a->pitch), cosf(a->pitch) * cosf(a->yaw));
        a->camera.forward = f;
        a->camera.right = pf_v3_normalize(pf_v3_cross(f, pf_v3(0, 1, 0)));
        a->camera.up = pf_v3_cross(a->camera.right, f);
        a->frame_needed = 1;
    }
    pf_vec3 move = pf_v3(0, 0, 0);
    if (pf_window_key_down(a->win, 'W')) move = pf_v3_add(move, a->camera.forward);
    if (pf_window_key_down(a->win, 'S')) move = pf_v3_sub(move, a->camera.forward);
    if (pf_window_key_down(a->win, 'D')) move = pf_v3_add(move, a->camera.right);
    if (pf_window_key_down(a->win, 'A')) move = pf_v3_sub(move, a->camera.right);
    if (pf_window_key_down(a->win, 'E')) move = pf_v3_add(move, pf_v3(0, 1, 0));
    if (pf_window_key_down(a->win, 'Q')) move = pf_v3_sub(move, pf_v3(0, 1, 0));
    if (move.x == 0.0f && move.y == 0.0f && move.z == 0.0f) return;
    int fast = pf_window_key_down(a->win, PF_KEY_LEFT_SHIFT) || pf_window_key_down(a->win, PF_KEY_RIGHT_SHIFT);
    float step = a->speed * (float)(dt < 0.1 ? dt : 0.1) * (fast ? 4.0f : 1.0f);
    move = pf_v3_scale(pf_v3_normalize(move), step);
    if (a->light_grab && a->scene.light_count > 0) {
        pf_light *L = &a->scene.lights[0];
        if (L->type == PF_LIGHT_DIRECTIONAL) /* a directional light has no position: tilt it */
            L->direction = pf_v3_normalize(pf_v3_add(L->direction, pf_v3_scale(move, 1.0f / a->speed)));
        else
            L->position = pf_v3_add(L->position, move);
    } else {
        a->camera.eye = pf_v3_add(a->camera.eye, move);
    }
    a->frame_needed = 1;
}

/* Polls the window; returns 1 to quit. */
static int view_handle_input(view_app *a, double dt)
{
    pf_input in;
    int idle = a->paused && !a->frame_needed && !a->image_dirty && a->script_next >= a->script_count;
    pf_window_poll(a->win, &in, idle ? 0.05 : 0.0);
    if (in.close) return 1;
    if (a->script_next < a->script_count) {
        uint32_t k = a->script_next++;
        if (view_handle_key(a, a->script_key[k], a->script_mods[k])) return 1;
    }
    for (uint32_t i = 0; i < in.key_count; i++)
        if (view_handle_key(a, in.key[i], in.mods[i])) return 1;
    view_handle_motion(a, &in, dt);
    return 0;
}

/* ------------------------------------------------------------ frame */

static void view_render_frame(view_app *a)
{
    if (a->indirect_dirty) view_apply_indirect(a);
    a->frame.camera = a->camera;
    double t0 = pf_time_now();
    if (a->opt->raytrace) gi_frame_render_raytraced(&a->frame);
    else gi_frame_render_raster(&a->frame);
    a->frame_ms = (pf_time_now() - t0) * 1e3;
    a->total_ms += a->frame_ms;
    a->vpls_moved = 0;
    if (a->frame.indirect)
        for (uint32_t i = 0; i < a->frame.ind.vpls.count; i++) a->vpls_moved += a->frame.ind.vpls.v[i].moved != 0;
    a->frames_done++;
    a->frame_needed = 0;
    a->image_dirty = 1;
}

/* The view without HUD: the final image, or the stepper's stage. */
static void view_draw_image(view_app *a)
{
    gi_view_settings s = {a->exposure, a->vpl_pick};
    gi_view_id id = a->paused ? (gi_view_id)a->stage : GI_VIEW_FINAL;
    if (!gi_view_available(&a->frame, id)) id = GI_VIEW_FINAL, a->stage = GI_VIEW_FINAL;
    gi_view_render(&a->frame, id, &s, a->image);
    a->image_dirty = 0;
}

/* ------------------------------------------------------------ HUD */

static void view_text(view_app *a, int x, int y, const char *t, uint8_t r, uint8_t g, uint8_t b)
{
    gi_view_text(a->display, a->width, a->height, x, y, 1, t, r, g, b);
}

/* Text lines on a darkened background, starting at (x, y); returns the y
 * below them. */
static int view_text_line(view_app *a, int x, int y, const char *t, uint8_t r, uint8_t g, uint8_t b)
{
    int w = (int)strlen(t) * GI_FONT_CELL_W + 4;
    gi_view_shade_rect(a->display, a->width, a->height, x - 2, y, w, GI_FONT_CELL_H + 1);
    view_text(a, x, y, t, r, g, b);
    return y + GI_FONT_CELL_H + 1;
}

/* Frame time, settings, VPL counts and the stage times as a stacked bar with
 * a legend. */
static int view_draw_stats(view_app *a, int y)
{
    char line[512];
    const gi_frame *f = &a->frame;
    snprintf(line, sizeof line, "%s %ux%u  frame %.1f ms (%.1f fps)%s%s", a->stem, a->width, a->height, a->frame_ms,
             a->frame_ms > 0 ? 1e3 / a->frame_ms : 0.0, a->paused ? "  PAUSED" : "",
             a->light_grab ? "  LIGHT GRABBED" : "");
    y = view_text_line(a, 4, y, line, 255, 255, 255);
    if (f->indirect) {
        const gi_indirect_options *o = &f->ind.opt;
        char clamp[32];
        if (o->clamp > 0.0f) snprintf(clamp, sizeof clamp, "%g", (double)o->clamp);
        else snprintf(clamp, sizeof clamp, "off");
        snprintf(line, sizeof line, "method %s  VPLs %u (budget %u, moved %u, maps %u)  tiles %ux%u  filter %s", o->method->name,
                 f->ind.vpls.count, o->vpls, a->vpls_moved, f->ind.maps_rendered, f->ind.n, f->ind.m,
                 o->filter == GI_FILTER_BOX ? "box" : o->filter == GI_FILTER_BILATERAL ? "bilateral" : "none");
        y = view_text_line(a, 4, y, line, 255, 255, 255);
        snprintf(line, sizeof line, "visibility %s  clamp %s  exposure %+.1f   H: help",
                 o->visibility_raytrace ? "raytrace" : o->visibility_ism ? "ism" : "paraboloid", clamp,
                 (double)a->exposure);
    } else {
        snprintf(line, sizeof line, "direct light only  exposure %+.1f   H: help", (double)a->exposure);
    }
    y = view_text_line(a, 4, y, line, 255, 255, 255);
    /* stage bar: one colour per stage, width proportional to its time */
    static const uint8_t pal[10][3] = {{230, 80, 80},  {240, 160, 60}, {230, 220, 70}, {120, 210, 80},
                                       {70, 200, 190}, {80, 140, 240}, {150, 100, 240}, {230, 100, 200},
                                       {180, 180, 180}, {140, 90, 60}};
    double total = 0.0;
    for (uint32_t i = 0; i < f->times.count; i++) total += f->times.ms[i];
    int bar_w = (int)a->width - 8 < 400 ? (int)a->width - 8 : 400, x = 4;
    gi_view_shade_rect(a->display, a->width, a->height, 2, y, bar_w + 4, 10);
    for (uint32_t i = 0; i < f->times.count && total > 0.0; i++) {
        int w = (int)(f->times.ms[i] / total * bar_w + 0.5);
        gi_view_fill_rect(a->display, a->width, a->height, x, y + 2, w, 6, pal[i % 10][0], pal[i % 10][1],
                          pal[i % 10][2]);
        x += w;
    }
    y += 11;
    for (uint32_t i = 0; i < f->times.count; i++) {
        snprintf(line, sizeof line, "%-28s %7.2f ms", f->times.name[i], f->times.ms[i]);
        y = view_text_line(a, 4, y, line, pal[i % 10][0], pal[i % 10][1], pal[i % 10][2]);
    }
    return y;
}

/* The stepper's caption at the bottom, word-wrapped to the window. */
static void view_draw_caption(view_app *a)
{
    char text[640];
    int shown = 0, total = 0;
    for (int v = 0; v < GI_VIEW_COUNT; v++)
        if (gi_view_available(&a->frame, (gi_view_id)v)) {
            total++;
            if (v <= a->stage) shown++;
        }
    snprintf(text, sizeof text, "[%d/%d %s] %s", shown, total, gi_view_name((gi_view_id)a->stage),
             gi_view_caption((gi_view_id)a->stage));
    if (a->stage == GI_VIEW_VPL_MAP || a->stage == GI_VIEW_VPLS || a->stage == GI_VIEW_VPL_OVERHEAD) {
        char more[96];
        uint32_t n = a->frame.ind.vpls.count;
        snprintf(more, sizeof more, "  [VPL %u of %u, K: next]", n ? a->vpl_pick % n : 0, n);
        strncat(text, more, sizeof text - strlen(text) - 1);
    }
    int per_line = ((int)a->width - 8) / GI_FONT_CELL_W, len = (int)strlen(text);
    if (per_line < 8) return;
    char lines[8][256];
    int count = 0;
    for (int start = 0; start < len && count < 8;) {
        int end = start + per_line < len ? start + per_line : len;
        if (end < len)
            for (int k = end; k > start + per_line / 2; k--)
                if (text[k] == ' ') {
                    end = k;
                    break;
                }
        snprintf(lines[count++], sizeof lines[0], "%.*s", end - start < 255 ? end - start : 255, text + start);
        start = end;
        while (start < len && text[start] == ' ') start++;
    }
    int y = (int)a->height - count * (GI_FONT_CELL_H + 1) - 2;
    for (int i = 0; i < count; i++) y = view_text_line(a, 4, y, lines[i], 255, 240, 160);
}

static void view_draw_help(view_app *a)
{
    int n = (int)(sizeof view_help / sizeof view_help[0]), chars = 0;
    for (int i = 0; i < n; i++) chars = (int)strlen(view_help[i]) > chars ? (int)strlen(view_help[i]) : chars;
    int w = chars * GI_FONT_CELL_W, h = (n + 2) * (GI_FONT_CELL_H + 1);
    int x = ((int)a->width - w) / 2, y = ((int)a->height - h) / 2;
    if (x < 4) x = 4; /* small windows: keep the start of each line */
    if (y < 4) y = 4;
    gi_view_shade_rect(a->display, a->width, a->height, x - 4, y - 4, w + 8, h + 8);
    view_text(a, x, y, "softgi view: keys", 255, 220, 120);
    for (int i = 0; i < n; i++) view_text(a, x, y + (i + 2) * (GI_FONT_CELL_H + 1), view_help[i], 255, 255, 255);
}

/* The displayed image: the view plus the HUD, the caption and the help. */
static void view_draw_hud(view_app *a)
{
    memcpy(a->display, a->image, (size_t)a->width * a->height * 3);
    if (!a->show_hud) return;
    int y = view_draw_stats(a, 4);
    if (a->message[0] && pf_time_now() < a->message_until) view_text_line(a, 4, y + 2, a->message, 255, 210, 60);
    if (a->paused) view_draw_caption(a);
    if (a->show_help) view_draw_help(a);
}

/* ------------------------------------------------------------ headless end */

/* --screenshot: the window's framebuffer without the HUD, read back. */
static pf_result view_screenshot(view_app *a, const char *path, pf_error *err)
{
    uint8_t *px = malloc((size_t)a->width * a->height * 3);
    if (!px) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    pf_result r = pf_window_capture(a->win, a->image, a->width, a->height, px, err);
    if (r == PF_OK) r = gi_view_write_png(path, px, a->width, a->height, err);
    free(px);
    return r;
}

static int view_finish(view_app *a)
{
    const pf_options *o = a->opt;
    pf_error err;
    pf_result r = PF_OK;
    if (o->screenshot_path) r = view_screenshot(a, o->screenshot_path, &err);
    if (r == PF_OK && o->dump_dir) {
        gi_view_settings s = {a->exposure, a->vpl_pick};
        r = gi_view_dump(&a->frame, o->dump_dir, &s, &err);
    }
    if (r != PF_OK) return app_fail(&err);
    if (!o->quiet) {
        printf("softgi view: %s, %ux%u, %u frames, %u rendered, mean frame %.2f ms, mean loop %.2f ms (frame + HUD + "
               "window)\n",
               a->stem, a->width, a->height, a->frames_shown, a->frames_done,
               a->frames_done ? a->total_ms / a->frames_done : 0.0,
               a->frames_shown ? (pf_time_now() - a->loop_start) * 1e3 / a->frames_shown : 0.0);
        if (o->screenshot_path) printf("wrote %s (the window without the HUD)\n", o->screenshot_path);
    }
    return 0;
}

/* ------------------------------------------------------------ main loop */

int app_view(const pf_options *opts)
{
    view_app *a = calloc(1, sizeof *a);
    if (!a) {
        fprintf(stderr, "softgi: out of memory\n");
        return 1;
    }
    a->opt = opts;
    a->stage = GI_VIEW_FINAL;
    pf_error err;
    pf_result r = view_setup(a, &err);
    char title[320];
    snprintf(title, sizeof title, "softgi view - %s", a->stem);
    if (r == PF_OK) r = pf_window_open(&a->win, a->width, a->height, title, &err);
    if (r != PF_OK) {
        view_teardown(a);
        free(a);
        return app_fail(&err);
    }
    /* --frames N: N frames shown, then exit (with --screenshot: 1 when not
     * given); unpaused, every frame shown is a frame rendered */
    uint32_t max_frames = opts->frames ? opts->frames : opts->screenshot_path ? 1 : 0;
    int status = 0;
    double last = pf_time_now();
    a->loop_start = last;
    for (;;) {
        double now = pf_time_now(), dt = now - last;
        last = now;
        if (view_handle_input(a, dt)) break;
        if (!a->paused || a->frame_needed) view_render_frame(a);
        if (a->image_dirty) view_draw_image(a);
        a->frames_shown++;
        if (max_frames && a->frames_shown >= max_frames) {
            status = view_finish(a);
            break;
        }
        view_draw_hud(a);
        pf_window_present(a->win, a->display, a->width, a->height);
    }
    view_teardown(a);
    free(a);
    return status;
}
