/* main.c - mechc's command line: picks the subcommand, nothing else. */
#include "cli.h"

#include <string.h>

static const char usage[] =
    "usage: mechc COMMAND FILE.mech [options]\n"
    "\n"
    "mechc compiles a planar or spatial mechanism, written as a joint list, into C\n"
    "for its constraints Phi, Jacobian Phi_q and the velocity and acceleration right\n"
    "sides nu and gamma (with masses also M(q) and Q(q, qd, t)), and runs kinematics\n"
    "and dynamics, forward and inverse, with it.\n"
    "\n"
    "commands:\n"
    "  gen     write the generated C (and header)\n"
    "  eval    evaluate Phi, Phi_q, nu, gamma at one state\n"
    "  run     assemble, then position, velocity and acceleration analysis over time\n"
    "  sim     forward dynamics over time (a file with masses)\n"
    "  check   compare symbolic derivatives with finite differences, engines with each other\n"
    "  info    coordinates, rows, mobility, rank, redundant rows, integrability\n"
    "  bench   time the evaluation engines side by side\n"
    "\n"
    "'mechc COMMAND --help' describes each command. Exit status: 0 success,\n"
    "1 the analysis failed, 2 bad usage or bad input.\n";

int main(int argc, char **argv)
{
    if (argc < 2) {
        fputs(usage, stderr);
        return EXIT_USAGE;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        fputs(usage, stdout);
        return EXIT_OK;
    }
    if (strcmp(cmd, "--version") == 0) {
        printf("mechc %s\n", MECHC_VERSION);
        return EXIT_OK;
    }
    static const struct { const char *name; int (*fn)(int, char **); } commands[] = {
        {"gen", cmd_gen}, {"eval", cmd_eval}, {"run", cmd_run}, {"sim", cmd_sim},
        {"check", cmd_check}, {"info", cmd_info}, {"bench", cmd_bench}, {"fit", cmd_fit},
    };
    for (size_t i = 0; i < sizeof commands / sizeof *commands; i++)
        if (strcmp(cmd, commands[i].name) == 0)
            return commands[i].fn(argc - 2, argv + 2);
    fprintf(stderr, "mechc: error: unknown command '%s'\n\n%s", cmd, usage);
    return EXIT_USAGE;
}
