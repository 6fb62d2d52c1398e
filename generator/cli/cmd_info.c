/* cmd_info.c - mechc info (not implemented yet: says so and exits 2). */
#include "cli.h"

int cmd_info(int argc, char **argv)
{
    (void)argc, (void)argv;
    fprintf(stderr, "mechc info: error: this command is not implemented yet in mechc %s\n", MECHC_VERSION);
    return EXIT_USAGE;
}
