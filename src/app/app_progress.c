/* app_progress: the progress bar of the long commands (app_progress.h). */
#include "app_progress.h"

#include <stdio.h>
#include <unistd.h>

#include "pf_timer.h"

#define APP__PROGRESS_DELAY 1.0   /* s before the first draw */
#define APP__PROGRESS_PERIOD 0.1  /* s between draws */
#define APP__PROGRESS_BAR 30

void app_progress_begin(app_progress *p, const char *label, int quiet)
{
    p->on = !quiet && isatty(STDERR_FILENO);
    p->drawn = 0;
    p->label = label;
    p->start = pf_time_now();
    p->last_draw = 0.0;
}

/* "1 h 02 min", "3 min 05 s", "9.6 s" */
static void app__duration(char *buf, size_t size, double s)
{
    if (s >= 3600.0) snprintf(buf, size, "%d h %02d min", (int)(s / 3600.0), (int)(s / 60.0) % 60);
    else if (s >= 60.0) snprintf(buf, size, "%d min %02d s", (int)(s / 60.0), (int)s % 60);
    else snprintf(buf, size, "%.1f s", s);
}

void app_progress_update(app_progress *p, double done, double total, const char *what)
{
    if (!p->on) return;
    double now = pf_time_now(), elapsed = now - p->start;
    if (elapsed < APP__PROGRESS_DELAY || (p->drawn && now - p->last_draw < APP__PROGRESS_PERIOD)) return;
    p->last_draw = now;
    if (total <= 0.0) { /* no measure of the whole: the time and the step only */
        char el[32];
        app__duration(el, sizeof el, elapsed);
        fflush(stdout);
        fprintf(stderr, "\r\033[K%s  %s%s%s", p->label, el, what ? "  " : "", what ? what : "");
        fflush(stderr);
        p->drawn = 1;
        return;
    }
    double frac = done / total;
    if (frac < 0.0) frac = 0.0;
    if (frac > 1.0) frac = 1.0;
    char bar[APP__PROGRESS_BAR + 1];
    int fill = (int)(frac * APP__PROGRESS_BAR);
    for (int i = 0; i < APP__PROGRESS_BAR; i++) bar[i] = i < fill ? '=' : i == fill ? '>' : ' ';
    bar[APP__PROGRESS_BAR] = 0;
    char el[32], left[48] = "";
    app__duration(el, sizeof el, elapsed);
    if (frac > 0.0 && frac < 1.0) {
        char t[24];
        app__duration(t, sizeof t, elapsed * (1.0 - frac) / frac);
        snprintf(left, sizeof left, ", about %s left", t);
    }
    fflush(stdout);
    fprintf(stderr, "\r\033[K%s [%s] %3.0f%%  %s%s%s%s", p->label, bar, 100.0 * frac, el, left, what ? "  " : "",
            what ? what : "");
    fflush(stderr);
    p->drawn = 1;
}

void app_progress_clear(app_progress *p)
{
    if (!p->on || !p->drawn) return;
    fflush(stdout);
    fputs("\r\033[K", stderr);
    fflush(stderr);
    p->drawn = 0;
}

void app_progress_end(app_progress *p)
{
    app_progress_clear(p);
}
