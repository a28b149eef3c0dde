/* pf_window: the one window softgi opens (`softgi view`), through GLFW 3
 * and legacy OpenGL 1.x only: the CPU-rendered RGB8 image is uploaded as a
 * texture (glTexImage2D / glTexSubImage2D) and drawn as one textured quad,
 * so any OpenGL works, Mesa's software llvmpipe included (no GPU needed;
 * under Xvfb too). Nothing of the renderer depends on this module.
 *
 * Key codes are GLFW's (letters and digits are their upper-case ASCII
 * codes); the few special keys the viewer uses are named here.
 *
 * Mouse: a left-button drag is reported as motion (look around), a right-
 * or middle-button drag as pan motion, the wheel as steps, and a button
 * pressed and released within PF_WINDOW_CLICK_SLOP pixels as a click at
 * the press position. Positions are framebuffer pixels, y down (on a HiDPI
 * screen the framebuffer has more pixels than the window has screen
 * coordinates; the viewer draws framebuffer pixels 1:1). */
#ifndef PF_WINDOW_H
#define PF_WINDOW_H

#include <stdint.h>

#include "pf_result.h"

enum {
    PF_KEY_SPACE = 32,
    PF_KEY_MINUS = 45,
    PF_KEY_EQUAL = 61,
    PF_KEY_LEFT_BRACKET = 91,
    PF_KEY_RIGHT_BRACKET = 93,
    PF_KEY_ESCAPE = 256,
    PF_KEY_ENTER = 257,
    PF_KEY_TAB = 258,
    PF_KEY_BACKSPACE = 259,
    PF_KEY_RIGHT = 262,
    PF_KEY_LEFT = 263,
    PF_KEY_DOWN = 264,
    PF_KEY_UP = 265,
    PF_KEY_F1 = 290,
    PF_KEY_LEFT_SHIFT = 340,
    PF_KEY_RIGHT_SHIFT = 344,
};
#define PF_MOD_SHIFT 1

enum { PF_MOUSE_LEFT = 0, PF_MOUSE_RIGHT = 1, PF_MOUSE_MIDDLE = 2 };

#define PF_WINDOW_MAX_EVENTS 64
#define PF_WINDOW_MAX_CLICKS 8
#define PF_WINDOW_CLICK_SLOP 3.0 /* framebuffer pixels a click may wander */

/* What happened since the last poll. */
typedef struct pf_input {
    uint32_t key_count;
    int key[PF_WINDOW_MAX_EVENTS];  /* key presses (and auto-repeats), in order */
    int mods[PF_WINDOW_MAX_EVENTS]; /* PF_MOD_SHIFT, ... */
    double mouse_dx, mouse_dy;      /* cursor motion in pixels while the left button is held */
    double pan_dx, pan_dy;          /* cursor motion while the right or middle button is held */
    double scroll;                  /* wheel steps, away from the user positive */
    double cursor_x, cursor_y;      /* the cursor, framebuffer pixels */
    uint32_t click_count;
    int click_button[PF_WINDOW_MAX_CLICKS]; /* PF_MOUSE_LEFT, ... */
    double click_x[PF_WINDOW_MAX_CLICKS], click_y[PF_WINDOW_MAX_CLICKS]; /* where it was pressed */
    uint32_t fb_w, fb_h;            /* the framebuffer's size now (0 x 0 when minimised) */
    int close;                      /* the window was asked to close */
} pf_input;

typedef struct pf_window pf_window;

/* Opens a width x height window (fails with a clear message when there is
 * no display). */
pf_result pf_window_open(pf_window **out, uint32_t width, uint32_t height, const char *title, pf_error *err);
void pf_window_close(pf_window *win);
/* Collects the events since the last call; wait_s > 0 first sleeps until an
 * event arrives or wait_s seconds pass (an idle, paused viewer). */
void pf_window_poll(pf_window *win, pf_input *in, double wait_s);
int pf_window_key_down(const pf_window *win, int key);
/* The framebuffer's size in pixels (what pf_window_present fills 1:1 when
 * handed an image of this size). */
void pf_window_framebuffer_size(const pf_window *win, uint32_t *w, uint32_t *h);
/* Draws an RGB8 image (top row first) fitted to the window, aspect kept,
 * and shows it. */
void pf_window_present(pf_window *win, const uint8_t *rgb, uint32_t w, uint32_t h);
/* Draws the image 1:1 at the window's top-left corner and reads those
 * pixels back from the window's framebuffer into out (w * h * 3, top row
 * first), then shows the frame. Fails when the framebuffer is smaller than
 * the image. */
pf_result pf_window_capture(pf_window *win, const uint8_t *rgb, uint32_t w, uint32_t h, uint8_t *out, pf_error *err);
void pf_window_set_title(pf_window *win, const char *title);

#endif
