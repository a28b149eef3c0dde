/* pf_window: GLFW window + OpenGL 1.x textured quad (see pf_window.h). */
#if defined(__SANITIZE_ADDRESS__)
#define _GNU_SOURCE /* RTLD_NODELETE */
#include <dlfcn.h>
#endif
#include "pf_window.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <GLFW/glfw3.h> /* includes <GL/gl.h> */

_Static_assert(PF_KEY_ESCAPE == GLFW_KEY_ESCAPE && PF_KEY_F1 == GLFW_KEY_F1 && PF_KEY_LEFT_SHIFT == GLFW_KEY_LEFT_SHIFT &&
                   PF_KEY_UP == GLFW_KEY_UP && PF_KEY_TAB == GLFW_KEY_TAB && PF_MOD_SHIFT == GLFW_MOD_SHIFT,
               "pf_window key codes are GLFW's");

struct pf_window {
    GLFWwindow *glfw;
    GLuint tex;
    uint32_t tex_w, tex_h;
    pf_input pending; /* key, click and wheel events queued by the callbacks */
    double last_x, last_y;
    int have_last;
    /* a button held: where it went down and how far the cursor went since
     * (framebuffer pixels), for telling a click from a drag */
    int held[3];
    double press_x[3], press_y[3], wander[3];
};

static char pf__glfw_error[512];

static void pf__on_error(int code, const char *desc)
{
    snprintf(pf__glfw_error, sizeof pf__glfw_error, "%s (GLFW error 0x%x)", desc ? desc : "?", code);
}

static void pf__on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    pf_window *win = glfwGetWindowUserPointer(w);
    if (!win || (action != GLFW_PRESS && action != GLFW_REPEAT)) return;
    pf_input *in = &win->pending;
    if (in->key_count >= PF_WINDOW_MAX_EVENTS) return;
    in->key[in->key_count] = key;
    in->mods[in->key_count] = mods;
    in->key_count++;
}

/* Screen coordinates (GLFW's cursor) -> framebuffer pixels. */
static void pf__to_framebuffer(GLFWwindow *w, double *x, double *y)
{
    int ww, wh, fw, fh;
    glfwGetWindowSize(w, &ww, &wh);
    glfwGetFramebufferSize(w, &fw, &fh);
    if (ww > 0 && wh > 0) *x *= (double)fw / ww, *y *= (double)fh / wh;
}

static void pf__on_button(GLFWwindow *w, int button, int action, int mods)
{
    (void)mods;
    pf_window *win = glfwGetWindowUserPointer(w);
    int b = button == GLFW_MOUSE_BUTTON_LEFT ? PF_MOUSE_LEFT
            : button == GLFW_MOUSE_BUTTON_RIGHT ? PF_MOUSE_RIGHT
            : button == GLFW_MOUSE_BUTTON_MIDDLE ? PF_MOUSE_MIDDLE
                                                 : -1;
    if (!win || b < 0) return;
    double x, y;
    glfwGetCursorPos(w, &x, &y);
    pf__to_framebuffer(w, &x, &y);
    if (action == GLFW_PRESS) {
        win->held[b] = 1, win->press_x[b] = x, win->press_y[b] = y, win->wander[b] = 0.0;
        return;
    }
    if (action != GLFW_RELEASE || !win->held[b]) return;
    win->held[b] = 0;
    pf_input *in = &win->pending;
    if (win->wander[b] > PF_WINDOW_CLICK_SLOP || in->click_count >= PF_WINDOW_MAX_CLICKS) return;
    in->click_button[in->click_count] = b;
    in->click_x[in->click_count] = win->press_x[b];
    in->click_y[in->click_count] = win->press_y[b];
    in->click_count++;
}

static void pf__on_cursor(GLFWwindow *w, double x, double y)
{
    pf_window *win = glfwGetWindowUserPointer(w);
    if (!win) return;
    pf__to_framebuffer(w, &x, &y);
    for (int b = 0; b < 3; b++)
        if (win->held[b]) {
            double dx = x - win->press_x[b], dy = y - win->press_y[b], d = dx * dx + dy * dy;
            if (d > win->wander[b] * win->wander[b]) win->wander[b] = sqrt(d);
        }
}

static void pf__on_scroll(GLFWwindow *w, double dx, double dy)
{
    (void)dx;
    pf_window *win = glfwGetWindowUserPointer(w);
    if (win) win->pending.scroll += dy;
}

#if defined(__SANITIZE_ADDRESS__)
/* Sanitizer builds only: Mesa keeps some blocks reachable only from its
 * own globals, and libglvnd unloads Mesa's libraries at exit, so
 * LeakSanitizer reports those blocks as leaked from an "<unknown module>"
 * (2 x 56 bytes on Debian 12's llvmpipe). Keeping Mesa's GLX library and
 * software driver loaded (RTLD_NODELETE) lets LeakSanitizer see them; a
 * library that is absent is skipped. Release builds do not do this. */
static void pf__keep_gl_libraries(void)
{
    static const char *const libs[] = {"libGLX_mesa.so.0", "/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so"};
    for (size_t i = 0; i < sizeof libs / sizeof libs[0]; i++) (void)dlopen(libs[i], RTLD_NOW | RTLD_NODELETE);
}
#else
static void pf__keep_gl_libraries(void) {}
#endif

pf_result pf_window_open(pf_window **out, uint32_t width, uint32_t height, const char *title, pf_error *err)
{
    *out = NULL;
    pf__glfw_error[0] = 0;
    glfwSetErrorCallback(pf__on_error);
    pf__keep_gl_libraries();
    if (!glfwInit()) {
        const char *display = getenv("DISPLAY");
        return pf_error_set(err, PF_ERR_IO,
                            "cannot open a window: %s%s; run it under a display or `xvfb-run -a softgi view ...`, or "
                            "step through a frame without one with `softgi render --dump-stages DIR`",
                            pf__glfw_error[0] ? pf__glfw_error : "GLFW could not start",
                            display && display[0] ? "" : " (DISPLAY is not set)");
    }
    pf_window *win = calloc(1, sizeof *win);
    if (!win) {
        glfwTerminate();
        return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    }
    /* legacy (compatibility) context: any version that has glTexImage2D and glBegin */
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    win->glfw = glfwCreateWindow((int)width, (int)height, title, NULL, NULL);
    if (!win->glfw) {
        free(win);
        glfwTerminate();
        return pf_error_set(err, PF_ERR_IO, "cannot open a %ux%u OpenGL window: %s", width, height,
                            pf__glfw_error[0] ? pf__glfw_error : "GLFW could not create it");
    }
    glfwSetWindowUserPointer(win->glfw, win);
    glfwSetKeyCallback(win->glfw, pf__on_key);
    glfwSetMouseButtonCallback(win->glfw, pf__on_button);
    glfwSetCursorPosCallback(win->glfw, pf__on_cursor);
    glfwSetScrollCallback(win->glfw, pf__on_scroll);
    glfwMakeContextCurrent(win->glfw);
    glfwSwapInterval(0); /* the CPU renderer sets the pace, not the display */
    glGenTextures(1, &win->tex);
    glBindTexture(GL_TEXTURE_2D, win->tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    *out = win;
    return PF_OK;
}

void pf_window_close(pf_window *win)
{
    if (!win) return;
    glDeleteTextures(1, &win->tex);
    glfwDestroyWindow(win->glfw);
    glfwTerminate();
    free(win);
}

void pf_window_set_title(pf_window *win, const char *title) { glfwSetWindowTitle(win->glfw, title); }

void pf_window_poll(pf_window *win, pf_input *in, double wait_s)
{
    memset(&win->pending, 0, sizeof win->pending);
    if (wait_s > 0.0) glfwWaitEventsTimeout(wait_s);
    else glfwPollEvents();
    *in = win->pending;
    double x, y;
    glfwGetCursorPos(win->glfw, &x, &y);
    pf__to_framebuffer(win->glfw, &x, &y);
    if (win->have_last) {
        double dx = x - win->last_x, dy = y - win->last_y;
        if (glfwGetMouseButton(win->glfw, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) in->mouse_dx = dx, in->mouse_dy = dy;
        if (glfwGetMouseButton(win->glfw, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
            glfwGetMouseButton(win->glfw, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS)
            in->pan_dx = dx, in->pan_dy = dy;
    }
    win->last_x = x, win->last_y = y, win->have_last = 1;
    in->cursor_x = x, in->cursor_y = y;
    pf_window_framebuffer_size(win, &in->fb_w, &in->fb_h);
    in->close = glfwWindowShouldClose(win->glfw);
}

int pf_window_key_down(const pf_window *win, int key) { return glfwGetKey(win->glfw, key) == GLFW_PRESS; }

void pf_window_framebuffer_size(const pf_window *win, uint32_t *w, uint32_t *h)
{
    int fw, fh;
    glfwGetFramebufferSize(win->glfw, &fw, &fh);
    *w = fw > 0 ? (uint32_t)fw : 0, *h = fh > 0 ? (uint32_t)fh : 0;
}

/* Uploads the image and draws it as a quad at (x, y) of size (qw, qh)
 * window pixels (y down). */
static void pf__draw(pf_window *win, const uint8_t *rgb, uint32_t w, uint32_t h, float x, float y, float qw, float qh)
{
    int fw, fh;
    glfwGetFramebufferSize(win->glfw, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glBindTexture(GL_TEXTURE_2D, win->tex);
    if (w != win->tex_w || h != win->tex_h) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, (GLsizei)w, (GLsizei)h, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb);
        win->tex_w = w, win->tex_h = h;
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGB, GL_UNSIGNED_BYTE, rgb);
    }
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(0.0, fw, fh, 0.0, -1.0, 1.0); /* window pixels, y down: texture row 0 is the image's top row */
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glEnable(GL_TEXTURE_2D);
    glBegin(GL_QUADS);
    glTexCoord2f(0.0f, 0.0f), glVertex2f(x, y);
    glTexCoord2f(1.0f, 0.0f), glVertex2f(x + qw, y);
    glTexCoord2f(1.0f, 1.0f), glVertex2f(x + qw, y + qh);
    glTexCoord2f(0.0f, 1.0f), glVertex2f(x, y + qh);
    glEnd();
    glDisable(GL_TEXTURE_2D);
}

void pf_window_present(pf_window *win, const uint8_t *rgb, uint32_t w, uint32_t h)
{
    int fw, fh;
    glfwGetFramebufferSize(win->glfw, &fw, &fh);
    float s = (float)fw / (float)w < (float)fh / (float)h ? (float)fw / (float)w : (float)fh / (float)h;
    float qw = (float)w * s, qh = (float)h * s;
    pf__draw(win, rgb, w, h, 0.5f * ((float)fw - qw), 0.5f * ((float)fh - qh), qw, qh);
    glfwSwapBuffers(win->glfw);
}

pf_result pf_window_capture(pf_window *win, const uint8_t *rgb, uint32_t w, uint32_t h, uint8_t *out, pf_error *err)
{
    int fw, fh;
    glfwGetFramebufferSize(win->glfw, &fw, &fh);
    if (fw < (int)w || fh < (int)h)
        return pf_error_set(err, PF_ERR_IO, "--screenshot: the window's framebuffer is %dx%d, smaller than the %ux%u image",
                            fw, fh, w, h);
    pf__draw(win, rgb, w, h, 0.0f, 0.0f, (float)w, (float)h);
    glFinish();
    glReadBuffer(GL_BACK);
    /* GL rows run bottom-up: the image's top row is framebuffer row fh - 1 */
    glReadPixels(0, fh - (int)h, (GLsizei)w, (GLsizei)h, GL_RGB, GL_UNSIGNED_BYTE, out);
    size_t row = (size_t)w * 3;
    uint8_t *tmp = malloc(row);
    if (!tmp) return pf_error_set(err, PF_ERR_OUT_OF_MEMORY, "out of memory");
    for (uint32_t y = 0; y < h / 2; y++) {
        memcpy(tmp, out + y * row, row);
        memcpy(out + y * row, out + (h - 1 - y) * row, row);
        memcpy(out + (h - 1 - y) * row, tmp, row);
    }
    free(tmp);
    GLenum e = glGetError();
    glfwSwapBuffers(win->glfw);
    if (e != GL_NO_ERROR) return pf_error_set(err, PF_ERR_IO, "--screenshot: OpenGL error 0x%x reading the window", e);
    return PF_OK;
}
