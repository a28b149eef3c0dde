/* app_sequence: `softgi sequence` — being written (issue 4). */
#include <stdio.h>

#include "app.h"

int app_sequence(const pf_options *opts)
{
    (void)opts;
    fprintf(stderr, "softgi: sequence: not implemented yet (issue 4)\n");
    return 1;
}
