/* app_compare: `softgi compare` — being written (issue 4). */
#include <stdio.h>

#include "app.h"

int app_compare(int argc, char **argv)
{
    (void)argc, (void)argv;
    fprintf(stderr, "softgi: compare: not implemented yet (issue 4)\n");
    return 1;
}
