/* app_bench_frame: `softgi bench frame` — being written (issue 4). */
#include <stdio.h>

#include "app.h"

int app_bench_frame(const pf_options *opts)
{
    (void)opts;
    fprintf(stderr, "softgi: bench frame: not implemented yet (issue 4)\n");
    return 1;
}
