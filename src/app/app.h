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

/* `softgi reference`: the path-traced reference (gi_reference). */
int app_reference(const pf_options *opts);

/* `softgi compare`: metrics between renders and references, with a plot.
 * Parses its own arguments (argv[1] == "compare"). */
int app_compare(int argc, char **argv);

#endif
