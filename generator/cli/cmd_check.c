/* cmd_check.c - mechc check (not implemented yet: says so and exits 2). */
#include "cli.h"

int cmd_check(int argc, char **argv)
{
    (void)argc, (void)argv;
    fprintf(stderr, "mechc check: error: this command is not implemented yet in mechc %s\n", MECHC_VERSION);
    return EXIT_USAGE;
}
