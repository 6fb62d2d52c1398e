/* cmd_pending.c - the commands whose issues are still open: each says so and exits 2. */
#include "cli.h"

static int not_yet(const char *name)
{
    fprintf(stderr, "mechc %s: error: this command is not implemented yet in mechc %s\n", name, MECHC_VERSION);
    return EXIT_USAGE;
}

int cmd_run(int argc, char **argv) { (void)argc, (void)argv; return not_yet("run"); }
int cmd_check(int argc, char **argv) { (void)argc, (void)argv; return not_yet("check"); }
int cmd_info(int argc, char **argv) { (void)argc, (void)argv; return not_yet("info"); }
int cmd_bench(int argc, char **argv) { (void)argc, (void)argv; return not_yet("bench"); }
