/* pf_window: the one window softgi opens (`softgi view`), through GLFW 3
 * and legacy OpenGL 1.x only: the CPU-rendered RGB8 image is uploaded as a
 * texture (glTexImage2D / glTexSubImage2D) and drawn as one textured quad,
 * so any OpenGL works, Mesa's software llvmpipe included (no GPU needed;
 * under Xvfb too). Nothing of the renderer depends on this module.
 *
 * Key codes are GLFW's (letters and digits are their upper-case ASCII
 * codes); the few special keys the viewer uses are named here. */
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

#define PF_WINDOW_MAX_EVENTS 64

/* What happened since the last poll. */
typedef struct pf_input {
    uint32_t key_count;
    int key[PF_WINDOW_MAX_EVENTS];  /* key presses (and auto-repeats), in order */
    int mods[PF_WINDOW_MAX_EVENTS]; /* PF_MOD_SHIFT, ... */
    double mouse_dx, mouse_dy;      /* cursor motion in pixels while the left button is held */
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
