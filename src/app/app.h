/* app: the softgi program's commands. main.c parses the command line and
 * dispatches; each command lives in its own app_*.c. */
#ifndef APP_H
#define APP_H

#include "pf_cli.h"

/* `softgi render`: load, override, build, render, write. Returns the exit status. */
int app_render(const pf_options *opts);

/* `softgi bench raster`: per-stage medians of the rasterizer passes against
 * Embree, as a table and one JSON line. Returns the exit status. */
int app_bench_raster(const pf_options *opts);

#endif
