/* cmd_run.c - mechc run (not implemented yet: says so and exits 2). */
#include "cli.h"

int cmd_run(int argc, char **argv)
{
    (void)argc, (void)argv;
    fprintf(stderr, "mechc run: error: this command is not implemented yet in mechc %s\n", MECHC_VERSION);
    return EXIT_USAGE;
}
