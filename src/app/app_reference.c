/* app_reference: `softgi reference` — being written (issue 4). */
#include <stdio.h>

#include "app.h"

int app_reference(const pf_options *opts)
{
    (void)opts;
    fprintf(stderr, "softgi: reference: not implemented yet (issue 4)\n");
    return 1;
}
