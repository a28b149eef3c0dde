/* app_view: `softgi view`, the interactive viewer (issue 7).
 * NOT IMPLEMENTED YET: says so and fails. */
#include <stdio.h>

#include "app.h"

int app_view(const pf_options *opts)
{
    (void)opts;
    fprintf(stderr, "softgi: view: not implemented yet\n");
    return 1;
}
