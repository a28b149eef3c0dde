/* app_view: `softgi view [SCENE]`, the interactive viewer, frame-stage
 * stepper and pixel inspector.
 *
 * Every frame is the CPU frame of `softgi render` (gi_frame_render_raster,
 * or the ray-traced one with --raytrace) with the same options, shown in a
 * GLFW window (pf_window: OpenGL 1.x textured quad, works on Mesa's
 * software llvmpipe and under Xvfb). The view (the final image or a stage)
 * is drawn at the frame's size, then fitted, zoomed and panned into the
 * window's framebuffer (gi_view_blit, nearest neighbour) and the HUD is
 * drawn over it at the framebuffer's own resolution with gi_view's bitmap
 * font, laid out for the window: lines wrap, the HUD goes compact below
 * 560 x 400 pixels, a block that does not fit is left out, and the help
 * and the view list are paged (nothing is drawn past the window's edge).
 *
 * HUD: frame time, the method and settings, a graph of the last 120 frame
 * times, the per-stage times as a bar with a legend, the last message, and
 * the probe. Keys: H.
 *
 * Teaching mode (the stepper): P pauses on the current frame and N / B
 * step through its stages in the order they run (gi_view_order: G-buffer
 * channels, shadow map, direct light, VPLs over the image, from above, by
 * bounce and by "moved", the method's own view, one VPL's paraboloid map and
 * the atlas of all, split, tile assignment, clamp mask, accumulated,
 * combined, filtered, final), each with its legend and its one-line
 * caption naming the paper section it implements (for the VPL views, the
 * method and why it chooses VPLs so: gi_view_describe_frame); V lists the
 * views to jump to, in the same order. `--dump-stages DIR` writes the same
 * pictures (gi_dump_stages).
 *
 * Inspector: a left click probes the pixel under the cursor (gi_probe.h:
 * its G-buffer values, direct light, tile and filtered irradiance, final
 * radiance and the VPLs that contribute most); in the split and accumulated
 * mosaics the click finds the frame pixel the mosaic shows there. The probe
 * stays on that pixel, re-read after every frame, and is printed to stdout
 * when taken. The wheel (or Z) zooms, a right or middle drag pans. X saves
 * the view shown to out/ as a PNG; shift+X pauses and dumps the frame to
 * out/STEM-frameN/ (gi_dump_stages: pictures and float .exr data, with the
 * probe as probe.txt).
 *
 * Settings changed by keys (method, VPL count, tiles, filter, visibility,
 * clamp) rebuild the frame's indirect state and apply from the next frame
 * on; a setting the frame cannot take (too many VPLs for the maps, a method
 * that fails to start) leaves the previous one in place and shows the error
 * in the HUD. Grabbing the light (L) with Instant Radiosity, which
 * re-renders every VPL's map whenever the light moves, switches to
 * Incremental Instant Radiosity (Laine 2007: only new VPLs get maps) until
 * the light is released, and the HUD says so.
 *
 * Headless: `--frames N` shows N frames and exits 0; with `--screenshot
 * FILE` the window's framebuffer (the displayed view without the HUD or
 * zoom: the final image unless the stepper shows a stage) is read back after
 * frame N and written as a PNG, byte-identical to `softgi render`'s PNG of
 * the same camera and options (tests/test_viewer.c). The environment
 * variable SOFTGI_VIEW_KEYS replays key presses, clicks, wheel steps and
 * pans, one per frame shown, so the tests drive the viewer without a
 * keyboard or mouse. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_setup.h"
#include "app.h"
#include "gi_dump.h"
#include "gi_frame.h"
#include "gi_probe.h"
#include "gi_view.h"
#include "pf_imageio.h"
#include "pf_jobs.h"
#include "pf_rt.h"
#include "pf_timer.h"
#include "pf_window.h"

#define VIEW_MAX_METHODS 16
#define VIEW_HISTORY 120 /* frame times in the graph */
#define VIEW_LINE 256    /* HUD line buffer (characters) */
#define VIEW_MAX_LINES 96
#define VIEW_MAX_SCRIPT 256

/* One replayed input event (SOFTGI_VIEW_KEYS). */
typedef enum view_event_kind { VIEW_EV_KEY, VIEW_EV_CLICK, VIEW_EV_WHEEL, VIEW_EV_PAN } view_event_kind;
typedef struct view_event {
    view_event_kind kind;
    int key, mods;  /* VIEW_EV_KEY; VIEW_EV_CLICK: key = PF_MOUSE_* */
    float x, y, n;  /* click and wheel: framebuffer pixel; wheel: n steps; pan: (x, y) pixels */
} view_event;

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
    int progressive;          /* T: temporal accumulation with VPL cycling and the progressive warm-up */
    uint32_t cycle_cap;       /* T's slices at most: what --max-memory (or the machine) holds */
    int moving;               /* the camera or the grabbed light moved since the last frame */
    uint32_t method_count, method_cursor;
    uint32_t vis_cursor; /* 0 paraboloid, 1 ism, 2 raytrace */
    const gi_vpl_method *methods[VIEW_MAX_METHODS];
    float exposure;
    /* fly camera and light */
    float yaw, pitch, speed;
    int light_grab;
    /* the light grabbed with a method that cannot keep up: the method and
     * parameters to go back to on release */
    int grab_swapped;
    const gi_vpl_method *grab_method;
    gi_params grab_params;
    uint32_t grab_frames, grab_maps; /* frames rendered swapped, maps rendered after the first */
    /* stepper and view list */
    int paused, stage; /* stage: a gi_view_id while paused */
    uint32_t vpl_pick;
    int list_open, list_cursor;
    int list_x, list_y0, list_w, list_row0, list_rows; /* where the list was drawn (for clicks) */
    int show_help, help_page, help_pages, show_hud;
    /* inspector */
    int probe_on, probe_print;
    uint32_t probe_x, probe_y;
    gi_probe probe;
    gi_view_zoom zoom;
    /* what happened */
    int frame_needed, image_dirty;
    uint32_t frames_done;  /* frames rendered */
    uint32_t frames_shown; /* loop iterations (a paused viewer shows frames without rendering) */
    view_event script[VIEW_MAX_SCRIPT];
    uint32_t script_count, script_next;
    int script_hold; /* a replayed W A S D Q E: held for one frame */
    double frame_ms, total_ms;
    double loop_start;     /* when the first frame began (for the whole-loop rate) */
    float history[VIEW_HISTORY]; /* frame times, ring buffer */
    uint32_t history_count, history_head;
    uint32_t vpls_moved;
    char message[1024];
    double message_until;
    /* HUD accounting: lines drawn, lines that would cross the window's edge
     * (0 by construction; the tests check it), blocks left out for room */
    uint32_t hud_lines, hud_clipped, hud_omitted;
    /* images: the view without HUD (frame size), and what goes to the window (framebuffer size) */
    uint8_t *image, *display;
    uint32_t disp_w, disp_h;
    size_t display_cap;
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

/* ------------------------------------------------------------ scripted input */

/* "12:34" or "12:34:-1": exactly `count` numbers separated by ':'. */
static int view_parse_numbers(const char *s, float *v, int count)
{
    for (int k = 0; k < count; k++) {
        char *end;
        v[k] = strtof(s, &end);
        if (end == s || !isfinite(v[k])) return 0;
        s = end;
        if (k + 1 < count && *s++ != ':') return 0;
    }
    return *s == 0;
}

/* A mouse token: click:X:Y, rclick:X:Y, wheel:X:Y:STEPS, pan:DX:DY. */
static int view_parse_mouse(const char *tok, view_event *e)
{
    float v[3];
    if (!strncmp(tok, "click:", 6) || !strncmp(tok, "rclick:", 7)) {
        int right = tok[0] == 'r';
        if (!view_parse_numbers(tok + (right ? 7 : 6), v, 2)) return 0;
        e->kind = VIEW_EV_CLICK, e->key = right ? PF_MOUSE_RIGHT : PF_MOUSE_LEFT, e->x = v[0], e->y = v[1];
        return 1;
    }
    if (!strncmp(tok, "wheel:", 6) && view_parse_numbers(tok + 6, v, 3)) {
        e->kind = VIEW_EV_WHEEL, e->x = v[0], e->y = v[1], e->n = v[2];
        return 1;
    }
    if (!strncmp(tok, "pan:", 4) && view_parse_numbers(tok + 4, v, 2)) {
        e->kind = VIEW_EV_PAN, e->x = v[0], e->y = v[1];
        return 1;
    }
    return 0;
}

/* A key token: a letter or digit or a name, optionally after "shift+". */
static int view_parse_key(const char *tok, view_event *e)
{
    static const struct {
        const char *name;
        int key;
    } named[] = {{"SPACE", PF_KEY_SPACE}, {"TAB", PF_KEY_TAB},     {"ESC", PF_KEY_ESCAPE}, {"ENTER", PF_KEY_ENTER},
                 {"F1", PF_KEY_F1},       {"LEFT", PF_KEY_LEFT},   {"RIGHT", PF_KEY_RIGHT}, {"UP", PF_KEY_UP},
                 {"DOWN", PF_KEY_DOWN},   {"[", PF_KEY_LEFT_BRACKET}, {"]", PF_KEY_RIGHT_BRACKET},
                 {"-", PF_KEY_MINUS},     {"=", PF_KEY_EQUAL}};
    int mods = 0, key = -1;
    if (!strncmp(tok, "shift+", 6)) mods = PF_MOD_SHIFT, tok += 6;
    if (strlen(tok) == 1 && ((tok[0] >= 'A' && tok[0] <= 'Z') || (tok[0] >= '0' && tok[0] <= '9'))) key = tok[0];
    if (strlen(tok) == 1 && tok[0] >= 'a' && tok[0] <= 'z') key = tok[0] - 'a' + 'A';
    for (size_t k = 0; key < 0 && k < sizeof named / sizeof named[0]; k++)
        if (!strcmp(tok, named[k].name)) key = named[k].key;
    if (key < 0) return 0;
    e->kind = VIEW_EV_KEY, e->key = key, e->mods = mods;
    return 1;
}

/* SOFTGI_VIEW_KEYS="M O O ] P N N click:40:30 shift+X": events replayed one
 * per shown frame before the window's own events, so tests (and demos) can
 * drive the viewer headless. Keys: a letter or digit, [ ] - =, SPACE TAB
 * ESC ENTER F1 LEFT RIGHT UP DOWN, each optionally prefixed with "shift+";
 * mouse: click:X:Y and rclick:X:Y (framebuffer pixel X, Y), wheel:X:Y:STEPS,
 * pan:DX:DY. */
static pf_result view_parse_script(view_app *a, const char *text, pf_error *err)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", text);
    for (char *tok = strtok(buf, " ,"); tok; tok = strtok(NULL, " ,")) {
        if (a->script_count >= VIEW_MAX_SCRIPT)
            return pf_error_set(err, PF_ERR_ARGUMENT, "SOFTGI_VIEW_KEYS: at most %d events", VIEW_MAX_SCRIPT);
        view_event e;
        memset(&e, 0, sizeof e);
        if (!view_parse_key(tok, &e) && !view_parse_mouse(tok, &e))
            return pf_error_set(err, PF_ERR_ARGUMENT,
                                "SOFTGI_VIEW_KEYS: unknown key '%s' (a letter or digit, [ ] - =, SPACE TAB ESC ENTER F1 "
                                "LEFT RIGHT UP DOWN, optionally shift+; or click:X:Y rclick:X:Y wheel:X:Y:STEPS "
                                "pan:DX:DY)",
                                tok);
        a->script[a->script_count++] = e;
    }
    return PF_OK;
}

/* ------------------------------------------------------------ setup */

/* The options the frame's indirect state was made with, as
 * gi_frame_enable_indirect takes them (ind.opt.vpls counts the whole
 * cycled set, the options the VPLs of one frame). */
static gi_indirect_options view_options_of(const gi_frame *f)
{
    gi_indirect_options o = f->ind.opt;
    if (f->ind.cycle > 1) o.vpls /= f->ind.cycle;
    return o;
}

/* T's VPL cycling (docs/frame.md "VPL cycling"): app_refine_slices for
 * the method, visibility and VPL count, at most `cap` (view_cycle_cap). */
static uint32_t view_cycle_for(const gi_indirect_options *o, uint32_t cap)
{
    uint32_t c = app_refine_slices(o->method ? o->method->name : NULL, o->visibility_ism, o->visibility_raytrace,
                                   o->vpls, o->para_res);
    c = c < cap ? c : cap;
    return c >= 2 ? c : 0;
}

/* T's slices at most: what the memory budget holds (--max-memory, else the
 * machine's; api_refine_fit), 0 when not even two slices fit. */
static uint32_t view_cycle_cap(const view_app *a)
{
    softgi_desc d;
    pf_error err;
    if (app_desc(a->opt, a->width, a->height, &d, &err) != PF_OK) return 0;
    return api_refine_fit(&d, &a->scene, a->frame.indirect, API_REFINE_SLICES);
}

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
static void view_toggle_temporal(view_app *a);

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
        a->io = view_options_of(&a->frame); /* as the command line gave it, with the defaults filled in */
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
    gi_view_zoom_reset(&a->zoom, a->width, a->height);
    a->image = calloc((size_t)a->width * a->height * 3, 1);
    if (!a->image) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    /* progressive refinement from the start (T's setting: a still view
     * converges), unless the command line set the temporal options
     * (--temporal 0 turns it off) */
    a->cycle_cap = view_cycle_cap(a);
    if (a->cycle_cap < API_REFINE_SLICES && a->frame.indirect && !o->refine_set)
        view_message(a, "progressive refinement: %u slices of VPLs at most, what the memory budget holds%s",
                     a->cycle_cap, o->max_memory ? " (--max-memory)" : "");
    if (!o->refine_set) view_toggle_temporal(a);
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

/* The display buffer follows the framebuffer (a resized window); grows
 * only when the window does. Returns 0 when out of memory (then nothing is
 * drawn until the next size). */
static int view_size_display(view_app *a, uint32_t w, uint32_t h)
{
    size_t bytes = (size_t)w * h * 3;
    if (bytes > a->display_cap) {
        uint8_t *p = realloc(a->display, bytes);
        if (!p) {
            a->disp_w = a->disp_h = 0;
            return 0;
        }
        a->display = p, a->display_cap = bytes;
    }
    a->disp_w = w, a->disp_h = h;
    return 1;
}

/* ------------------------------------------------------------ state changes */

/* Temporal anti-aliasing over `frames` (0: off; gi_aa.h), the frame's
 * --aa samples kept; restarts its history. */
static void view_set_taa(view_app *a, uint32_t frames)
{
    pf_error err;
    if (gi_frame_set_aa(&a->frame, a->frame.aa.samples, frames, &err) != PF_OK)
        view_message(a, "temporal anti-aliasing: %s", err.message);
}

/* Rebuilds the frame's indirect state with a->want; on failure shows why
 * and goes back to the previous settings. */
static void view_apply_indirect(view_app *a)
{
    a->indirect_dirty = 0;
    if (!a->frame.indirect) return;
    pf_error err;
    gi_indirect_free(&a->frame.ind);
    a->frame.indirect = 0;
    if (a->progressive) { /* for this method, visibility and VPL count */
        a->want.cycle = view_cycle_for(&a->want, a->cycle_cap);
        a->want.cycle_maps = a->want.cycle > 1 ? API_REFINE_MAPS : 0;
    }
    if (gi_frame_enable_indirect(&a->frame, &a->want, a->opt->indirect_only, &err) == PF_OK) {
        a->io = view_options_of(&a->frame);
        a->want = a->io;
        if (a->frame.aa.taa.frames) view_set_taa(a, a->frame.aa.taa.frames); /* a new image: a new history */
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
 * succeeds; a method that fails is named in the HUD and the current one
 * stays. --param values belong to the first method and are dropped on a
 * switch. A method chosen while the light is grabbed stays on release. */
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
    a->grab_swapped = 0;
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
    a->want.filter = a->want.filter == GI_FILTER_BOX         ? GI_FILTER_BILATERAL
                     : a->want.filter == GI_FILTER_BILATERAL ? GI_FILTER_NONE
                     : a->want.filter == GI_FILTER_NONE      ? GI_FILTER_ATROUS
                                                             : GI_FILTER_BOX;
    a->indirect_dirty = 1;
}

/* The three optional stages (docs/frame.md): temporal accumulation, the
 * indirect light at half resolution, the clamp compensation. T turns on and
 * off together the temporal accumulation of the indirect light over 32
 * frames with VPL cycling (view_cycle_for: 32 x --vpls VPLs, one slice a
 * frame) and its progressive warm-up (API_REFINE_MAPS maps a frame drawn
 * ahead, only while the view is still), and the temporal anti-aliasing
 * over 16 frames (docs/aa.md: the samples jittered from frame to frame):
 * a still camera then converges to an anti-aliased image of the whole
 * cycled set. */
static void view_toggle_temporal(view_app *a)
{
    int on = !(a->want.temporal || a->frame.aa.taa.frames);
    a->progressive = on;
    if (a->frame.indirect) {
        a->want.temporal = on ? API_REFINE_TEMPORAL : 0;
        a->want.cycle = a->want.cycle_maps = 0; /* view_apply_indirect: view_cycle_for when on */
        a->indirect_dirty = 1;
    }
    view_set_taa(a, on ? API_REFINE_TAA : 0);
}

static void view_toggle_scale(view_app *a)
{
    a->want.scale = a->want.scale > 1 ? 1 : 2;
    a->indirect_dirty = 1;
}

static void view_toggle_compensate(view_app *a)
{
    a->want.compensate = !a->want.compensate;
    a->indirect_dirty = 1;
}

/* paraboloid -> ism -> raytrace: the cursor moves on even when a choice
 * fails, so every press tries the next. */
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

/* L: grab or release light 0. Instant Radiosity traces new VPL paths from
 * the light every frame, so a moving light re-renders every VPL's map
 * (256 maps: about 1 s a frame on Sibenik); Incremental Instant Radiosity
 * (Laine 2007 Sec. 4) keeps the VPLs that stay valid and renders maps only
 * for new ones, so while the light is grabbed the viewer renders with IIR
 * and goes back to IR (with its --param values) on release. */
static void view_toggle_grab(view_app *a)
{
    if (a->scene.light_count == 0) {
        view_message(a, "the scene has no light to grab");
        return;
    }
    a->light_grab = !a->light_grab;
    const gi_vpl_method *fast = gi_vpl_method_find("iir");
    if (a->light_grab && a->frame.indirect && a->want.method && !strcmp(a->want.method->name, "ir") && fast) {
        a->grab_swapped = 1, a->grab_frames = a->grab_maps = 0;
        a->grab_method = a->want.method;
        a->grab_params = a->want.params;
        a->want.method = fast;
        memset(&a->want.params, 0, sizeof a->want.params);
        a->indirect_dirty = 1;
        view_message(a, "light grabbed: iir while it moves (ir re-renders every VPL map when the light moves); L "
                        "releases it and goes back to ir");
    } else if (a->light_grab) {
        view_message(a, "light grabbed: W A S D Q E move it, L releases it");
    } else if (a->grab_swapped) {
        a->grab_swapped = 0;
        a->want.method = a->grab_method;
        a->want.params = a->grab_params;
        a->indirect_dirty = 1;
        if (a->grab_frames > 0)
            view_message(a, "light released: back to %s (iir rendered %.1f VPL maps a frame while the light was grabbed; "
                            "%s renders one per VPL when the light moves)",
                         a->grab_method->name, (double)a->grab_maps / a->grab_frames, a->grab_method->name);
        else view_message(a, "light released: back to %s", a->grab_method->name);
    }
}

/* ------------------------------------------------------------ views shown */

/* The view on screen: the stepper's stage while paused, else the final image. */
static gi_view_id view_shown(const view_app *a) { return a->paused ? (gi_view_id)a->stage : GI_VIEW_FINAL; }

/* Next (+1) or previous (-1) stage view the frame has, from `from`, in
 * the order the frame computes them (gi_view_order). */
static int view_next_stage(const view_app *a, int from, int step)
{
    int s = (int)gi_view_rank((gi_view_id)from);
    for (int k = 0; k < GI_VIEW_COUNT; k++) {
        s = (s + step + GI_VIEW_COUNT) % GI_VIEW_COUNT;
        if (gi_view_available(&a->frame, gi_view_order((uint32_t)s))) return (int)gi_view_order((uint32_t)s);
    }
    return GI_VIEW_FINAL;
}

/* Pauses (if running) and shows view `id`. */
static void view_jump(view_app *a, int id)
{
    a->paused = 1;
    a->stage = id;
    a->image_dirty = 1;
    a->list_open = 0;
}

/* ------------------------------------------------------------ the inspector */

/* Prints the probe to stdout (9 digits: every float exactly). */
static void view_print_probe(const view_app *a)
{
    char text[4096];
    gi_probe_text(text, sizeof text, &a->probe, 9, GI_PROBE_TOP);
    printf("softgi view: probe of frame %u:\n%s", a->frames_done, text);
    fflush(stdout);
}

/* Re-reads the probed pixel from the frame just rendered (or shown). */
static void view_update_probe(view_app *a)
{
    if (!a->probe_on || a->frames_done == 0) return;
    gi_probe_pixel(&a->probe, &a->frame, a->probe_x, a->probe_y);
    if (a->probe_print && !a->opt->quiet) view_print_probe(a);
    a->probe_print = 0;
}

/* A left click at framebuffer point (wx, wy): the view list's row there,
 * else the probe of the frame pixel the view shows there. */
static void view_click(view_app *a, float wx, float wy)
{
    if (a->list_open) {
        int row = (int)floorf((wy - (float)a->list_y0) / (float)(GI_FONT_CELL_H + 1));
        if (wx >= (float)a->list_x && wx < (float)(a->list_x + a->list_w) && row >= 0 && row < a->list_rows) {
            int rank = a->list_row0 + row, id = (int)gi_view_order((uint32_t)rank);
            if (rank < GI_VIEW_COUNT && gi_view_available(&a->frame, (gi_view_id)id)) view_jump(a, id);
            return;
        }
    }
    uint32_t u, v, x, y;
    gi_view_id id = view_shown(a);
    if (!gi_view_zoom_to_view(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, wx, wy, &u, &v)) return;
    if (!gi_view_frame_pixel(&a->frame, id, u, v, &x, &y)) {
        view_message(a, "the %s view is a map, not the image: probe in an image view", gi_view_name(id));
        return;
    }
    a->probe_on = 1, a->probe_x = x, a->probe_y = y, a->probe_print = 1;
    view_update_probe(a);
}

static void view_button(view_app *a, int button, float wx, float wy)
{
    if (button == PF_MOUSE_LEFT) view_click(a, wx, wy);
    else if (button == PF_MOUSE_RIGHT && a->probe_on) a->probe_on = 0, view_message(a, "probe off");
}

/* Z / shift+Z: zoom about the probed pixel when the view shows it, else
 * about the window's centre. */
static void view_zoom_key(view_app *a, float factor)
{
    float wx = 0.5f * (float)a->disp_w, wy = 0.5f * (float)a->disp_h;
    uint32_t u, v;
    if (a->probe_on && gi_view_view_pixel(&a->frame, view_shown(a), a->probe_x, a->probe_y, &u, &v)) {
        gi_view_zoom_to_window(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, (float)u + 0.5f, (float)v + 0.5f,
                               &wx, &wy);
        wx = pf_clampf(wx, 0.0f, (float)a->disp_w), wy = pf_clampf(wy, 0.0f, (float)a->disp_h);
    }
    gi_view_zoom_at(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, wx, wy, factor);
}

/* X: the view shown (frame size, no HUD, no zoom) as out/STEM-frameN-NN-name.png. */
static void view_save_view(view_app *a)
{
    if (a->frames_done == 0) return;
    if (a->image_dirty) { /* a key earlier in this poll changed the view */
        gi_view_settings s = {a->exposure, a->vpl_pick};
        gi_view_render(&a->frame, view_shown(a), &s, a->image);
    }
    char path[512];
    gi_view_id id = view_shown(a);
    snprintf(path, sizeof path, "out/%s-frame%u-%02d-%s.png", a->stem, a->frames_done, (int)id, gi_view_name(id));
    pf_error err;
    if (gi_view_write_png(path, a->image, a->width, a->height, &err) != PF_OK) view_message(a, "%s", err.message);
    else view_message(a, "wrote %s", path);
}

static int view_print_probe_file(FILE *out, void *user)
{
    const gi_probe *p = user;
    char text[4096];
    gi_probe_text(text, sizeof text, p, 9, GI_PROBE_TOP);
    return fputs(text, out) < 0;
}

/* shift+X: pauses and writes the frame's stages to out/STEM-frameN/: the
 * pictures, the float data (.exr) and captions.txt (gi_dump_stages), and
 * the probe as probe.txt. */
static void view_dump_frame(view_app *a)
{
    if (a->frames_done == 0) return;
    if (!a->paused) a->paused = 1, a->stage = GI_VIEW_FINAL, a->image_dirty = 1;
    char dir[512], path[600];
    snprintf(dir, sizeof dir, "out/%s-frame%u", a->stem, a->frames_done);
    gi_view_settings s = {a->exposure, a->vpl_pick};
    pf_error err;
    pf_result r = gi_dump_stages(&a->frame, dir, &s, GI_DUMP_BOTH, &err);
    snprintf(path, sizeof path, "%s/probe.txt", dir);
    if (r == PF_OK && a->probe_on) r = pf_imageio_write_text(path, view_print_probe_file, &a->probe, &err);
    if (r != PF_OK) view_message(a, "%s", err.message);
    else view_message(a, "dumped frame %u to %s/ (pictures, float .exr, captions.txt%s)", a->frames_done, dir,
                      a->probe_on ? ", probe.txt" : "");
}

/* ------------------------------------------------------------ input */

/* The key help: keys, then what they do. */
static const char *const view_help[][2] = {
    {"left drag", "look around (paused: pan)"},
    {"left click", "probe the pixel: G-buffer, light, irradiance, VPLs"},
    {"right click", "probe off"},
    {"wheel, Z, shift+Z", "zoom in / out (texels stay sharp); 0: fit"},
    {"right/middle drag", "pan"},
    {"W A S D / Q E", "fly / down, up (shift: faster)"},
    {"L", "grab light 0: W A S D Q E move it (ir runs as iir meanwhile)"},
    {"R", "camera back to the start"},
    {"M / shift+M", "next / previous VPL method"},
    {"[ / ]", "half / double the VPLs"},
    {"I", "interleave 4x4, 8x8, off, 2x2"},
    {"F", "filter box, bilateral, none, atrous"},
    {"O", "visibility paraboloid, ism, raytrace"},
    {"C", "clamp 400, 1600, 6400, off, 25, 100"},
    {"J", "clamp compensation on / off"},
    {"T", "temporal accumulation (VPL cycling) and anti-aliasing on / off"},
    {"U", "indirect light at half resolution on / off"},
    {"- / =", "exposure -/+ 0.5 stop"},
    {"P / space", "pause: the stage stepper"},
    {"N / B (arrows)", "next / previous stage"},
    {"V", "list of views: UP DOWN, ENTER or click jumps"},
    {"K / shift+K", "next / previous VPL (paraboloid map)"},
    {"X", "save the view shown to out/ (PNG)"},
    {"shift+X", "dump the paused frame to out/ (PNG + EXR)"},
    {"TAB", "HUD on / off"},
    {"H / F1", "this help (again: next page)"},
    {"ESC", "quit (closes the view list first)"},
};
#define VIEW_HELP_COUNT ((int)(sizeof view_help / sizeof view_help[0]))

/* Moves the list's cursor to the next available view in direction step. */
static void view_list_move(view_app *a, int step)
{
    a->list_cursor = view_next_stage(a, a->list_cursor, step);
}

/* Keys of the stepper and the view list; returns 1 when the key was one. */
static int view_key_views(view_app *a, int key, int shift)
{
    switch (key) {
    case 'P':
    case PF_KEY_SPACE:
        a->paused = !a->paused;
        a->stage = GI_VIEW_FINAL;
        a->image_dirty = 1;
        return 1;
    case 'N':
    case PF_KEY_RIGHT:
    case 'B':
    case PF_KEY_LEFT:
        if (!a->paused) a->paused = 1, a->stage = GI_VIEW_FINAL;
        a->stage = view_next_stage(a, a->stage, key == 'N' || key == PF_KEY_RIGHT ? 1 : -1);
        a->image_dirty = 1;
        return 1;
    case 'V':
        a->list_open = !a->list_open;
        a->list_cursor = (int)view_shown(a);
        return 1;
    case PF_KEY_UP:
    case PF_KEY_DOWN:
        if (a->list_open) view_list_move(a, key == PF_KEY_DOWN ? 1 : -1);
        return 1;
    case PF_KEY_ENTER:
        if (a->list_open) view_jump(a, a->list_cursor);
        return 1;
    case 'K':
        a->vpl_pick += shift ? (uint32_t)-1 : 1u;
        if (a->frame.indirect && a->frame.ind.vpls.count) a->vpl_pick %= a->frame.ind.vpls.count;
        a->image_dirty = 1;
        return 1;
    default: return 0;
    }
}

/* Keys of the display: HUD, help, zoom, saving. Returns 1 when handled. */
static int view_key_display(view_app *a, int key, int shift)
{
    switch (key) {
    case 'H':
    case PF_KEY_F1:
        if (!a->show_help) a->show_help = 1, a->help_page = 0;
        else if (a->help_page + 1 < a->help_pages) a->help_page++;
        else a->show_help = 0;
        return 1;
    case PF_KEY_TAB: a->show_hud = !a->show_hud; return 1;
    case 'Z': view_zoom_key(a, shift ? 0.5f : 2.0f); return 1;
    case '0': gi_view_zoom_reset(&a->zoom, a->width, a->height); return 1;
    case 'X':
        if (shift) view_dump_frame(a);
        else view_save_view(a);
        return 1;
    case PF_KEY_MINUS:
    case PF_KEY_EQUAL:
        a->exposure = pf_clampf(a->exposure + (key == PF_KEY_EQUAL ? 0.5f : -0.5f), -64.0f, 64.0f);
        a->image_dirty = 1;
        return 1;
    default: return 0;
    }
}

/* Keys that change the frame's settings. */
static void view_key_settings(view_app *a, int key, int shift)
{
    switch (key) {
    case 'L': view_toggle_grab(a); break;
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
    case 'J': view_toggle_compensate(a); break;
    case 'T': view_toggle_temporal(a); break;
    case 'U': view_toggle_scale(a); break;
    default: break;
    }
}

/* One key press: state changes only (the frame is rendered later).
 * Returns 1 to quit. */
static int view_handle_key(view_app *a, int key, int mods)
{
    int shift = (mods & PF_MOD_SHIFT) != 0;
    if (key == PF_KEY_ESCAPE) {
        if (!a->list_open) return 1;
        a->list_open = 0;
        return 0;
    }
    if (!view_key_views(a, key, shift) && !view_key_display(a, key, shift)) view_key_settings(a, key, shift);
    if (a->indirect_dirty && !a->frame.indirect) {
        a->indirect_dirty = 0;
        view_message(a, "indirect light is off (--direct-only)");
    }
    if (a->indirect_dirty) a->frame_needed = 1;
    return 0;
}

/* A motion key held now (or replayed this frame). */
static int view_key_down(const view_app *a, int key) { return pf_window_key_down(a->win, key) || a->script_hold == key; }

/* Mouse-look (or, paused, pan) and WASD/QE motion of the camera, or of
 * light 0 while grabbed; dt: seconds since the last frame. */
static void view_handle_motion(view_app *a, const pf_input *in, double dt)
{
    if ((in->mouse_dx != 0.0 || in->mouse_dy != 0.0) && a->paused) {
        gi_view_zoom_pan(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, (float)in->mouse_dx,
                         (float)in->mouse_dy);
    } else if (in->mouse_dx != 0.0 || in->mouse_dy != 0.0) {
        a->yaw -= (float)in->mouse_dx * 0.004f;
        a->pitch = pf_clampf(a->pitch - (float)in->mouse_dy * 0.004f, -1.55f, 1.55f);
        pf_vec3 f = pf_v3(cosf(a->pitch) * sinf(a->yaw), sinf(a->pitch), cosf(a->pitch) * cosf(a->yaw));
        a->camera.forward = f;
        a->camera.right = pf_v3_normalize(pf_v3_cross(f, pf_v3(0, 1, 0)));
        a->camera.up = pf_v3_cross(a->camera.right, f);
        a->frame_needed = 1;
        a->moving = 1;
    }
    pf_vec3 move = pf_v3(0, 0, 0);
    if (view_key_down(a, 'W')) move = pf_v3_add(move, a->camera.forward);
    if (view_key_down(a, 'S')) move = pf_v3_sub(move, a->camera.forward);
    if (view_key_down(a, 'D')) move = pf_v3_add(move, a->camera.right);
    if (view_key_down(a, 'A')) move = pf_v3_sub(move, a->camera.right);
    if (view_key_down(a, 'E')) move = pf_v3_add(move, pf_v3(0, 1, 0));
    if (view_key_down(a, 'Q')) move = pf_v3_sub(move, pf_v3(0, 1, 0));
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
    a->moving = 1;
}

/* One scripted event, through the same paths as the window's. */
static int view_replay(view_app *a, const view_event *e)
{
    switch (e->kind) {
    case VIEW_EV_KEY:
        if (e->key > 0 && e->key < 128 && strchr("WASDQE", e->key)) a->script_hold = e->key; /* fly a frame */
        return view_handle_key(a, e->key, e->mods);
    case VIEW_EV_CLICK: view_button(a, e->key, e->x + 0.5f, e->y + 0.5f); break; /* the pixel's centre */
    case VIEW_EV_WHEEL:
        gi_view_zoom_at(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, e->x + 0.5f, e->y + 0.5f, exp2f(e->n));
        break;
    case VIEW_EV_PAN: gi_view_zoom_pan(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, e->x, e->y); break;
    }
    return 0;
}

/* Polls the window; returns 1 to quit. */
static int view_handle_input(view_app *a, double dt)
{
    pf_input in;
    int idle = a->paused && !a->frame_needed && !a->image_dirty && a->script_next >= a->script_count;
    pf_window_poll(a->win, &in, idle ? 0.05 : 0.0);
    if (in.close) return 1;
    if (in.fb_w != a->disp_w || in.fb_h != a->disp_h) view_size_display(a, in.fb_w, in.fb_h);
    a->script_hold = 0;
    if (a->script_next < a->script_count && view_replay(a, &a->script[a->script_next++])) return 1;
    for (uint32_t i = 0; i < in.key_count; i++)
        if (view_handle_key(a, in.key[i], in.mods[i])) return 1;
    for (uint32_t i = 0; i < in.click_count; i++)
        view_button(a, in.click_button[i], (float)in.click_x[i], (float)in.click_y[i]);
    if (in.scroll != 0.0 && a->disp_w)
        gi_view_zoom_at(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, (float)in.cursor_x, (float)in.cursor_y,
                        exp2f((float)in.scroll));
    if ((in.pan_dx != 0.0 || in.pan_dy != 0.0) && a->disp_w)
        gi_view_zoom_pan(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, (float)in.pan_dx, (float)in.pan_dy);
    view_handle_motion(a, &in, dt);
    return 0;
}

/* ------------------------------------------------------------ frame */

static void view_render_frame(view_app *a)
{
    int rebuilt = a->indirect_dirty;
    if (a->indirect_dirty) view_apply_indirect(a);
    if (a->grab_swapped && (!a->frame.indirect || strcmp(a->io.method->name, "iir") != 0))
        a->grab_swapped = 0; /* iir could not start: the frame kept ir */
    a->frame.camera = a->camera;
    a->frame.ind.ahead_hold = a->moving; /* the warm-up's maps wait for a still view */
    a->moving = 0;
    double t0 = pf_time_now();
    if (a->opt->raytrace) gi_frame_render_raytraced(&a->frame);
    else gi_frame_render_raster(&a->frame);
    a->frame_ms = (pf_time_now() - t0) * 1e3;
    a->total_ms += a->frame_ms;
    a->history[a->history_head] = (float)a->frame_ms;
    a->history_head = (a->history_head + 1) % VIEW_HISTORY;
    if (a->history_count < VIEW_HISTORY) a->history_count++;
    a->vpls_moved = 0;
    if (a->frame.indirect)
        for (uint32_t i = 0; i < a->frame.ind.vpls.count; i++) a->vpls_moved += a->frame.ind.vpls.v[i].moved != 0;
    if (a->grab_swapped && !rebuilt) /* a rebuilt state renders every map once: not counted */
        a->grab_frames++, a->grab_maps += a->frame.ind.maps_rendered;
    if (a->frames_done == 0 && a->opt->exposure_auto) /* once, from the first frame; - and = adjust from there */
        a->exposure = app_exposure(a->opt, a->frame.final, a->width, a->height);
    a->frames_done++;
    a->frame_needed = 0;
    a->image_dirty = 1;
    view_update_probe(a);
}

/* The view without HUD: the final image, or the stepper's stage. */
static void view_draw_image(view_app *a)
{
    gi_view_settings s = {a->exposure, a->vpl_pick};
    if (!gi_view_available(&a->frame, view_shown(a))) a->stage = GI_VIEW_FINAL;
    gi_view_render(&a->frame, view_shown(a), &s, a->image);
    a->image_dirty = 0;
}

/* ------------------------------------------------------------ HUD: text layout */

/* A column of the HUD: x, width and the next free y, down to `bottom`. */
typedef struct view_col {
    int x, w, y, bottom;
} view_col;

#define VIEW_ROW (GI_FONT_CELL_H + 1)

/* Word-wraps text ('\n' ends a line) to `cols` characters a line; a long
 * word is cut; continuation lines are indented by two spaces. Returns the
 * line count (at most max). */
static int view_wrap(const char *text, int cols, char out[][VIEW_LINE], int max)
{
    int count = 0;
    if (cols > VIEW_LINE - 1) cols = VIEW_LINE - 1;
    if (cols < 4) return 0;
    for (const char *p = text; *p && count < max;) {
        size_t para = strcspn(p, "\n");
        int first = 1;
        for (size_t at = 0; (at < para || first) && count < max;) {
            int indent = first ? 0 : 2, room = cols - indent;
            size_t n = para - at;
            if ((int)n > room) {
                n = (size_t)room;
                for (size_t k = n; k > (size_t)room / 2; k--) /* break at the last space */
                    if (p[at + k] == ' ') {
                        n = k;
                        break;
                    }
            }
            snprintf(out[count++], VIEW_LINE, "%*s%.*s", indent, "", (int)n, p + at);
            at += n;
            while (at < para && p[at] == ' ') at++;
            first = 0;
        }
        p += para;
        if (*p == '\n') p++;
    }
    return count;
}

/* One line of text on a darkened background at (x, y). Counts it, and
 * counts it as clipped if any of it would fall outside the window. */
static void view_text_line(view_app *a, int x, int y, const char *t, const uint8_t rgb[3])
{
    int w = (int)strlen(t) * GI_FONT_CELL_W + 4;
    a->hud_lines++;
    if (x - 2 < 0 || y < 0 || x - 2 + w > (int)a->disp_w || y + VIEW_ROW > (int)a->disp_h) a->hud_clipped++;
    gi_view_shade_rect(a->display, a->disp_w, a->disp_h, x - 2, y, w, VIEW_ROW);
    gi_view_text(a->display, a->disp_w, a->disp_h, x, y, 1, t, rgb[0], rgb[1], rgb[2]);
}

/* A block of text wrapped to the column, drawn only if all of it fits
 * (else counted as left out and the column ends there). With `partial`,
 * the lines that fit are drawn and the last says there is more. Returns 1
 * if all of it was drawn. */
static int view_block(view_app *a, view_col *c, const char *text, const uint8_t rgb[3], int partial)
{
    char lines[VIEW_MAX_LINES][VIEW_LINE];
    int n = view_wrap(text, (c->w - 4) / GI_FONT_CELL_W, lines, VIEW_MAX_LINES);
    if (n == 0) return 0;
    int room = (c->bottom - c->y) / VIEW_ROW, all = n <= room;
    if (!all) {
        a->hud_omitted++;
        n = partial && room >= 2 ? room - 1 : 0;
    }
    for (int i = 0; i < n; i++, c->y += VIEW_ROW) view_text_line(a, c->x, c->y, lines[i], rgb);
    if (!all && n > 0) {
        view_text_line(a, c->x, c->y, (c->w - 4) / GI_FONT_CELL_W >= 24 ? "... (all of it: stdout)" : "...", rgb);
        c->y += VIEW_ROW;
    }
    if (!all) c->bottom = c->y; /* what comes below would be out of order: the column ends */
    return all;
}

static const uint8_t view_white[3] = {255, 255, 255}, view_yellow[3] = {255, 210, 60}, view_cream[3] = {255, 240, 160},
                     view_grey[3] = {120, 120, 120}, view_cyan[3] = {140, 230, 255};

/* The HUD is compact in small windows: short lines, no stage legend. */
static int view_compact(const view_app *a) { return a->disp_w < 560 || a->disp_h < 400; }

/* ------------------------------------------------------------ HUD: blocks */

static const char *view_filter_name(gi_filter_kind k)
{
    return k == GI_FILTER_BOX         ? "box"
           : k == GI_FILTER_BILATERAL ? "bilateral"
           : k == GI_FILTER_NONE      ? "none"
           : k == GI_FILTER_ATROUS    ? "atrous"
                                      : "gaussian";
}

/* The first lines: frame time, state, method and settings. */
static void view_draw_status(view_app *a, view_col *c)
{
    char line[1024], zoom[32] = "", grab[96] = "";
    const gi_frame *f = &a->frame;
    int compact = view_compact(a);
    if (a->zoom.zoom != 1.0f) snprintf(zoom, sizeof zoom, "  zoom %gx", (double)a->zoom.zoom);
    if (a->light_grab)
        snprintf(grab, sizeof grab, "  LIGHT GRABBED%s", a->grab_swapped ? " (ir -> iir until released)" : "");
    if (compact)
        snprintf(line, sizeof line, "%.1f ms %.1f fps%s%s%s", a->frame_ms, a->frame_ms > 0 ? 1e3 / a->frame_ms : 0.0,
                 a->paused ? "  PAUSED" : "", zoom, grab);
    else
        snprintf(line, sizeof line, "%s %ux%u  frame %.1f ms (%.1f fps)%s%s%s", a->stem, a->width, a->height,
                 a->frame_ms, a->frame_ms > 0 ? 1e3 / a->frame_ms : 0.0, a->paused ? "  PAUSED" : "", zoom, grab);
    view_block(a, c, line, view_white, 0);
    if (!f->indirect) {
        snprintf(line, sizeof line, "direct light only  exposure %+.1f  H: help", (double)a->exposure);
        view_block(a, c, line, view_white, 0);
        return;
    }
    const gi_indirect_options *o = &f->ind.opt;
    const char *vis = o->visibility_raytrace ? "raytrace"
                      : o->visibility_ism    ? "ism"
                      : o->para_slope        ? "paraboloid-slope"
                                             : "paraboloid";
    char clamp[32];
    if (o->clamp > 0.0f) snprintf(clamp, sizeof clamp, "%g", (double)o->clamp);
    else snprintf(clamp, sizeof clamp, "off");
    if (compact) {
        snprintf(line, sizeof line, "%s %u VPLs %ux%u %s %s  H: help", o->method->name, f->ind.vpls.count, f->ind.n,
                 f->ind.m, view_filter_name(o->filter), vis);
        view_block(a, c, line, view_white, 0);
        return;
    }
    snprintf(line, sizeof line, "method %s  VPLs %u (budget %u, moved %u, maps %u)  tiles %ux%u  filter %s",
             o->method->name, f->ind.vpls.count, o->vpls, a->vpls_moved, f->ind.maps_rendered, f->ind.n, f->ind.m,
             view_filter_name(o->filter));
    view_block(a, c, line, view_white, 0);
    char cyc[32] = "";
    if (f->ind.cycle > 1) snprintf(cyc, sizeof cyc, " cycle %u/%u", f->ind.cycle_live, f->ind.cycle);
    snprintf(line, sizeof line, "visibility %s  clamp %s%s  scale %u  temporal %u%s  aa %u  taa %u  exposure %+.1f   H: help",
             vis, clamp, o->compensate ? " +comp" : "", f->ind.scale, o->temporal, cyc, f->aa.samples,
             f->aa.taa.frames, (double)a->exposure);
    view_block(a, c, line, view_white, 0);
}

/* Rounds up to 1, 2 or 5 times a power of ten (the graph's scale). */
static double view_nice(double v)
{
    double p = pow(10.0, floor(log10(v > 1e-3 ? v : 1e-3)));
    return v <= p ? p : v <= 2 * p ? 2 * p : v <= 5 * p ? 5 * p : 10 * p;
}

/* The last VIEW_HISTORY frame times as bars, oldest left, with the scale
 * and the last, mean and largest time. */
static void view_draw_graph(view_app *a, view_col *c)
{
    if (a->history_count == 0) return;
    int compact = view_compact(a), gh = compact ? 16 : 32;
    int bar = c->w - 8 >= 2 * VIEW_HISTORY ? 2 : 1, gw = bar * VIEW_HISTORY;
    if (gw > c->w - 8 || c->y + VIEW_ROW + gh + 4 > c->bottom) {
        a->hud_omitted++;
        return;
    }
    double max = 0.0, sum = 0.0;
    for (uint32_t i = 0; i < a->history_count; i++) max = fmax(max, a->history[i]), sum += a->history[i];
    double scale = view_nice(max);
    char line[160];
    if (compact) snprintf(line, sizeof line, "frame ms (0-%g): mean %.1f max %.1f", scale, sum / a->history_count, max);
    else
        snprintf(line, sizeof line, "frame ms, last %u (scale 0-%g): mean %.1f max %.1f", a->history_count, scale,
                 sum / a->history_count, max);
    if (!view_block(a, c, line, view_cyan, 0) || c->y + gh + 4 > c->bottom) return;
    int x0 = c->x, y0 = c->y;
    gi_view_shade_rect(a->display, a->disp_w, a->disp_h, x0 - 2, y0, gw + 4, gh + 4);
    for (uint32_t k = 0; k < a->history_count; k++) {
        uint32_t i = (a->history_head + VIEW_HISTORY - a->history_count + k) % VIEW_HISTORY;
        int h = (int)(a->history[i] / scale * gh + 0.5);
        h = h < 1 ? 1 : h > gh ? gh : h;
        int x = x0 + (int)(VIEW_HISTORY - a->history_count + k) * bar;
        gi_view_fill_rect(a->display, a->disp_w, a->disp_h, x, y0 + 2 + gh - h, bar, h, 90, 200, 240);
    }
    c->y += gh + 4 + 1;
}

static const uint8_t view_palette[10][3] = {{230, 80, 80},  {240, 160, 60}, {230, 220, 70},  {120, 210, 80},
                                            {70, 200, 190}, {80, 140, 240}, {150, 100, 240}, {230, 100, 200},
                                            {180, 180, 180}, {140, 90, 60}};

/* The stage times as a stacked bar (one colour per stage) and, with
 * `legend` in full HUDs, a line per stage. */
static void view_draw_stages(view_app *a, view_col *c, int legend)
{
    const pf_stage_times *t = &a->frame.times;
    double total = 0.0;
    for (uint32_t i = 0; i < t->count; i++) total += t->ms[i];
    int bar_w = c->w - 8 < 400 ? c->w - 8 : 400, x = c->x;
    if (c->y + 10 > c->bottom || bar_w < 8) {
        a->hud_omitted++;
        return;
    }
    gi_view_shade_rect(a->display, a->disp_w, a->disp_h, c->x - 2, c->y, bar_w + 4, 10);
    for (uint32_t i = 0; i < t->count && total > 0.0; i++) {
        int w = (int)(t->ms[i] / total * bar_w + 0.5);
        if (x + w > c->x + bar_w) w = c->x + bar_w - x;
        gi_view_fill_rect(a->display, a->disp_w, a->disp_h, x, c->y + 2, w, 6, view_palette[i % 10][0],
                          view_palette[i % 10][1], view_palette[i % 10][2]);
        x += w;
    }
    c->y += 11;
    if (!legend || view_compact(a)) return;
    char line[160];
    for (uint32_t i = 0; i < t->count; i++) {
        snprintf(line, sizeof line, "%-28s %7.2f ms", t->name[i], t->ms[i]);
        if (!view_block(a, c, line, view_palette[i % 10], 0)) return;
    }
}

/* The probe: compact windows get fewer digits and VPLs. */
static void view_draw_probe(view_app *a, view_col *c)
{
    if (!a->probe_on || a->frames_done == 0) return;
    char text[4096];
    int compact = view_compact(a);
    gi_probe_text(text, sizeof text, &a->probe, compact ? 3 : 4, compact ? 2 : 5);
    view_block(a, c, text, view_cream, 1);
}

/* A small box around the probed pixel where the view shows it. */
static void view_draw_probe_marker(view_app *a)
{
    uint32_t u, v;
    if (!a->probe_on || !gi_view_view_pixel(&a->frame, view_shown(a), a->probe_x, a->probe_y, &u, &v)) return;
    float x0, y0, x1, y1;
    gi_view_zoom_to_window(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, (float)u, (float)v, &x0, &y0);
    gi_view_zoom_to_window(&a->zoom, a->width, a->height, a->disp_w, a->disp_h, (float)u + 1.0f, (float)v + 1.0f,
                           &x1, &y1);
    int l = (int)floorf(x0) - 2, t = (int)floorf(y0) - 2, r = (int)ceilf(x1) + 1, b = (int)ceilf(y1) + 1;
    uint8_t *d = a->display;
    gi_view_fill_rect(d, a->disp_w, a->disp_h, l, t, r - l + 1, 1, 255, 0, 255);
    gi_view_fill_rect(d, a->disp_w, a->disp_h, l, b, r - l + 1, 1, 255, 0, 255);
    gi_view_fill_rect(d, a->disp_w, a->disp_h, l, t, 1, b - t + 1, 255, 0, 255);
    gi_view_fill_rect(d, a->disp_w, a->disp_h, r, t, 1, b - t + 1, 255, 0, 255);
}

/* The stepper's caption at the bottom, word-wrapped to the window; returns
 * the y above it. */
static int view_draw_caption(view_app *a)
{
    char text[1536];
    int shown = 0, total = 0;
    for (uint32_t k = 0; k < GI_VIEW_COUNT; k++)
        if (gi_view_available(&a->frame, gi_view_order(k))) {
            total++;
            if (k <= gi_view_rank((gi_view_id)a->stage)) shown++;
        }
    char what[1024];
    gi_view_describe_frame(&a->frame, (gi_view_id)a->stage, what, sizeof what);
    snprintf(text, sizeof text, "[%d/%d %s] %s", shown, total, gi_view_name((gi_view_id)a->stage), what);
    if (a->stage == GI_VIEW_VPL_MAP || a->stage == GI_VIEW_VPLS || a->stage == GI_VIEW_VPL_OVERHEAD ||
        a->stage == GI_VIEW_VPL_BOUNCE || a->stage == GI_VIEW_VPL_MOVED || a->stage == GI_VIEW_VPL_ATLAS ||
        a->stage == GI_VIEW_TILES || a->stage == GI_VIEW_METHOD) {
        char more[96];
        uint32_t n = a->frame.ind.vpls.count;
        snprintf(more, sizeof more, "  [VPL %u of %u, K: next]", n ? a->vpl_pick % n : 0, n);
        strncat(text, more, sizeof text - strlen(text) - 1);
    }
    char lines[16][VIEW_LINE];
    int n = view_wrap(text, ((int)a->disp_w - 8) / GI_FONT_CELL_W, lines, 16);
    int room = ((int)a->disp_h - 4) / VIEW_ROW / 2; /* at most half the window */
    if (n > room) n = room, a->hud_omitted++;
    int y = (int)a->disp_h - n * VIEW_ROW - 2;
    for (int i = 0; i < n; i++) view_text_line(a, 4, y + i * VIEW_ROW, lines[i], view_cream);
    return y - 2;
}

/* ------------------------------------------------------------ HUD: overlays */

/* Rows of `count` entries of `lines` rows each, split into pages of at most
 * `rows` rows without splitting an entry; returns the page count and the
 * first entry of page `page` in *first (and the end in *end). */
static int view_pages(const int *lines, int count, int rows, int page, int *first, int *end)
{
    int pages = 0, used = 0;
    *first = 0, *end = count;
    for (int i = 0; i < count; i++) {
        if (used > 0 && used + lines[i] > rows) {
            if (pages == page) *end = i;
            pages++, used = 0;
            if (pages == page) *first = i;
        }
        used += lines[i];
    }
    return pages + 1;
}

/* One help entry as lines: "KEY  what it does" with the description
 * wrapped in its own column, or (stacked) the key on a line of its own and
 * the description indented below it. Returns the line count. */
static int view_help_entry(int i, int cols, int keyw, int stacked, char out[][VIEW_LINE], int max)
{
    char desc[16][VIEW_LINE];
    int indent = stacked ? 2 : keyw + 2, count = 0;
    int n = view_wrap(view_help[i][1], cols - indent, desc, 16);
    if (stacked && count < max) snprintf(out[count++], VIEW_LINE, "%s", view_help[i][0]);
    for (int k = 0; k < n && count < max; k++)
        snprintf(out[count++], VIEW_LINE, "%-*s%s", indent, k == 0 && !stacked ? view_help[i][0] : "", desc[k]);
    return count;
}

/* The key help, paged to fit the window (H: the next page). */
static void view_draw_help(view_app *a, int bottom)
{
    int cols = ((int)a->disp_w - 16) / GI_FONT_CELL_W, keyw = 0;
    for (int i = 0; i < VIEW_HELP_COUNT; i++) keyw = (int)strlen(view_help[i][0]) > keyw ? (int)strlen(view_help[i][0]) : keyw;
    int stacked = cols < keyw + 2 + 24; /* too narrow for two columns */
    int rows = (bottom - 12) / VIEW_ROW - 2, lines[VIEW_HELP_COUNT], first, end;
    if (rows < 3 || cols < 16) {
        a->hud_omitted++;
        return;
    }
    char wrapped[VIEW_MAX_LINES][VIEW_LINE];
    for (int i = 0; i < VIEW_HELP_COUNT; i++) lines[i] = view_help_entry(i, cols, keyw, stacked, wrapped, VIEW_MAX_LINES);
    a->help_pages = view_pages(lines, VIEW_HELP_COUNT, rows, 0, &first, &end);
    if (a->help_page >= a->help_pages) a->help_page = a->help_pages - 1; /* the window grew */
    view_pages(lines, VIEW_HELP_COUNT, rows, a->help_page, &first, &end);
    int used = 0, width = 0;
    for (int i = first; i < end; i++) {
        used += view_help_entry(i, cols, keyw, stacked, wrapped, VIEW_MAX_LINES);
        for (int k = 0; k < lines[i]; k++) width = (int)strlen(wrapped[k]) > width ? (int)strlen(wrapped[k]) : width;
    }
    width *= GI_FONT_CELL_W;
    int x = ((int)a->disp_w - width) / 2, y = (bottom - (used + 2) * VIEW_ROW) / 2;
    x = x < 6 ? 6 : x, y = y < 4 ? 4 : y;
    char title[96];
    snprintf(title, sizeof title, a->help_pages > 1 ? "keys %d/%d (H: more)" : "softgi view: keys", a->help_page + 1,
             a->help_pages);
    gi_view_shade_rect(a->display, a->disp_w, a->disp_h, x - 4, y - 4, width + 8, (used + 2) * VIEW_ROW + 8);
    view_text_line(a, x, y, title, view_yellow);
    y += 2 * VIEW_ROW;
    for (int i = first; i < end; i++) {
        int n = view_help_entry(i, cols, keyw, stacked, wrapped, VIEW_MAX_LINES);
        for (int k = 0; k < n; k++, y += VIEW_ROW) view_text_line(a, x, y, wrapped[k], view_white);
    }
}

/* The list of views to jump to, in the order the frame computes them
 * (gi_view_order), paged around the cursor: "> NN name" for the one shown
 * (NN: the dump's file number), the cursor in yellow, views without data
 * grey. */
static void view_draw_list(view_app *a, int bottom)
{
    int rows = (bottom - 8) / VIEW_ROW - 1;
    if (rows < 1 || a->disp_w < 20 * GI_FONT_CELL_W) {
        a->hud_omitted++;
        return;
    }
    int row0 = (int)gi_view_rank((gi_view_id)a->list_cursor) / rows * rows;
    int count = GI_VIEW_COUNT - row0 < rows ? GI_VIEW_COUNT - row0 : rows;
    a->list_x = 4, a->list_w = 18 * GI_FONT_CELL_W, a->list_rows = count, a->list_row0 = row0;
    view_text_line(a, 4, 4, "views (V closes)", view_yellow);
    a->list_y0 = 4 + VIEW_ROW;
    char line[64];
    for (int k = 0; k < count; k++) {
        int v = (int)gi_view_order((uint32_t)(row0 + k));
        snprintf(line, sizeof line, "%s %02d %-13s", v == (int)view_shown(a) ? ">" : " ", v, gi_view_name((gi_view_id)v));
        const uint8_t *rgb = !gi_view_available(&a->frame, (gi_view_id)v) ? view_grey
                             : v == a->list_cursor                         ? view_yellow
                                                                           : view_white;
        view_text_line(a, 4, a->list_y0 + k * VIEW_ROW, line, rgb);
    }
}

/* The displayed image: the view zoomed into the window, the probe's mark,
 * and the HUD with the caption; the help or the view list, when open,
 * take the HUD's place. */
static void view_draw_hud(view_app *a)
{
    gi_view_blit(a->display, a->disp_w, a->disp_h, a->image, a->width, a->height, &a->zoom);
    view_draw_probe_marker(a);
    a->list_rows = 0; /* no list on screen to click until it is drawn */
    if (!a->show_hud) return;
    if (a->show_help) {
        view_draw_help(a, (int)a->disp_h);
        return;
    }
    int bottom = a->paused ? view_draw_caption(a) : (int)a->disp_h - 2;
    if (a->list_open) {
        view_draw_list(a, bottom);
        return;
    }
    int probe_right = a->probe_on && a->disp_w >= 800;
    int probe_w = probe_right ? ((int)a->disp_w / 2 < 420 ? (int)a->disp_w / 2 : 420) : 0;
    view_col c = {4, (int)a->disp_w - 4 - probe_w, 4, bottom};
    view_draw_status(a, &c);
    if (a->message[0] && pf_time_now() < a->message_until) view_block(a, &c, a->message, view_yellow, 0);
    if (probe_right) { /* a wide window: the probe in its own column */
        view_col p = {(int)a->disp_w - probe_w + 2, probe_w - 4, 4, bottom};
        view_draw_probe(a, &p);
    } else { /* else before the graph: the user asked for it */
        view_draw_probe(a, &c);
    }
    view_draw_graph(a, &c);
    view_draw_stages(a, &c, !a->probe_on || probe_right); /* the probe in this column replaces the legend */
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
        r = gi_dump_stages(&a->frame, o->dump_dir, &s, GI_DUMP_PNG, &err);
    }
    if (r != PF_OK) return app_fail(&err);
    if (!o->quiet) {
        printf("softgi view: %s, %ux%u, %u frames, %u rendered, mean frame %.2f ms, mean loop %.2f ms (frame + HUD + "
               "window)\n",
               a->stem, a->width, a->height, a->frames_shown, a->frames_done,
               a->frames_done ? a->total_ms / a->frames_done : 0.0,
               a->frames_shown ? (pf_time_now() - a->loop_start) * 1e3 / a->frames_shown : 0.0);
        printf("softgi view: HUD in a %ux%u window: %u lines drawn, %u clipped, %u blocks left out for room\n",
               a->disp_w, a->disp_h, a->hud_lines, a->hud_clipped, a->hud_omitted);
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
        if (a->disp_w == 0 || a->disp_h == 0) continue; /* minimised */
        view_draw_hud(a);
        pf_window_present(a->win, a->display, a->disp_w, a->disp_h);
    }
    view_teardown(a);
    free(a);
    return status;
}
