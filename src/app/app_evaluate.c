/* app_evaluate: `softgi evaluate`, the method evaluation (issue 5).
 * NOT IMPLEMENTED YET: says so and fails. */
#include <stdio.h>

#include "app.h"

int app_evaluate(int argc, char **argv)
{
    (void)argc, (void)argv;
    fprintf(stderr, "softgi: evaluate: not implemented yet\n");
    return 1;
}
