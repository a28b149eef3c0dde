/* app_progress: the one progress bar of the long commands:
 * `softgi reference` (rows of the path tracer), `softgi sequence`
 * (frames, and the stages of the frame being rendered), `softgi evaluate`
 * (references and method runs) and `softgi render` (the stages of a frame
 * that takes long, e.g. with --vpls 100000).
 *
 *   reference [==========>         ]  52%  10.4 s, about 9.6 s left
 *
 * One line on stderr, redrawn in place at most 10 times a second, and only
 * when stderr is a terminal and the command is not -q: logs, pipes and
 * tests see nothing. Nothing is drawn before the first second, so short
 * runs stay quiet. The time left assumes the rest costs what the part done
 * cost on average; it is left out until a step has finished.
 *
 * Text the command prints meanwhile goes through app_progress_clear first
 * (stdout is flushed and the bar's line erased, since the two streams share
 * the terminal); the next update draws the bar again. */
#ifndef APP_PROGRESS_H
#define APP_PROGRESS_H

#include <stdint.h>

typedef struct app_progress {
    int on;          /* stderr is a terminal and not quiet */
    int drawn;       /* the bar is on the screen now */
    const char *label;
    double start, last_draw;
} app_progress;

/* Starts the clock; `label` (a static string) heads the line. */
void app_progress_begin(app_progress *p, const char *label, int quiet);
/* done of total (any unit; fractions allowed), with `what` (may be NULL)
 * after the times, e.g. "frame 12/48: accumulate". total <= 0: no bar and
 * no time left, only the time so far and `what` (work whose size is not
 * known, e.g. the stages of one frame, most of whose time one stage may
 * take). */
void app_progress_update(app_progress *p, double done, double total, const char *what);
/* Erases the bar's line (if drawn) before other output. */
void app_progress_clear(app_progress *p);
/* Erases the bar: the command prints its own summary. */
void app_progress_end(app_progress *p);

#endif
