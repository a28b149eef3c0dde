/* softgi: the command-line entry point. Parses options (pf_cli) and runs the
 * command; every failure is one line on stderr and a non-zero exit status
 * (2 for bad usage, 1 for bad input or a failed write). `softgi --help`
 * lists the commands, `softgi COMMAND --help` the options of one command
 * (pf_cli.h: one table gives both the help and which command takes which
 * option). */
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "pf_fpenv.h"

int main(int argc, char **argv)
{
    pf_fpenv_set();
    if (argc > 1 && !strcmp(argv[1], "compare")) return app_compare(argc, argv);
    if (argc > 1 && !strcmp(argv[1], "evaluate")) return app_evaluate(argc, argv);
    pf_options opts;
    pf_error err;
    pf_result r = pf_cli_parse(&opts, argc, argv, &err);
    if (r == PF_OK && opts.version) {
        printf("softgi %s\n", SOFTGI_VERSION);
        return 0;
    }
    if (r == PF_OK && opts.help) r = pf_cli_usage_command(stdout, opts.command, opts.scene_path, &err);
    if (r != PF_OK) {
        fprintf(stderr, "softgi: %s\n", err.message);
        return pf_result_exit_code(r);
    }
    if (opts.help) return 0;
    if (!strcmp(opts.command, "bench"))
        return !strcmp(opts.scene_path, "frame") ? app_bench_frame(&opts) : app_bench_raster(&opts);
    if (!strcmp(opts.command, "sequence")) return app_sequence(&opts);
    if (!strcmp(opts.command, "reference")) return app_reference(&opts);
    if (!strcmp(opts.command, "view")) return app_view(&opts);
    return app_render(&opts);
}
