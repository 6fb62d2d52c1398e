/* common.c - what the commands do alike: the order of their steps, loading the file, opening an engine, reporting a failure. */
#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <unistd.h>

int cli_main(const CliCommand *cmd, int argc, char **argv, void *opts)
{
    Args a;
    if (!cli_parse(&a, cmd, argc, argv, opts))
        return EXIT_OK;         /* --help */
    if (cmd->finish && !cmd->finish(&a, opts))
        return EXIT_USAGE;
    Diag diag;      /* outlives the Mech, as cli_load wants */
    Mech *mech = cli_load(&a, (const MechLimits *)((const char *)opts + cmd->limits_offset), &diag);
    if (!mech)
        return EXIT_USAGE;
    if (!cli_apply_design(&a, mech->model)) {
        pipeline_free(mech);
        return EXIT_USAGE;
    }
    int status = cmd->run(&a, mech, &diag, opts);
    pipeline_free(mech);
    return status;
}

Mech *cli_load(Args *a, const MechLimits *limits, Diag *diag)
{
    if (!args_need_file(a))
        return NULL;
    MechLimits defaults = mech_default_limits();
    Mech *mech = pipeline_load(a->file, limits ? limits : &defaults, diag);
    if (!mech)
        diag_print(diag, stderr);
    return mech;
}

void cli_error(const Args *a, const Diag *diag)
{
    fprintf(stderr, "mechc %s: error: %s\n", a->command, diag->message);
}

bool cli_engine_open(const Args *a, Engine *e, EngineKind kind, const Mech *mech,
                     const EngineOptions *options, Diag *diag)
{
    if (engine_open_with(e, kind, mech, options, diag))
        return true;
    cli_error(a, diag);
    return false;
}

FILE *cli_open_output(const char *command, const char *path)
{
    /* O_NONBLOCK: a named pipe with no reader fails (ENXIO) at once
       instead of blocking the open forever; one with a reader (a shell's
       process substitution) is written as usual, blocking again. */
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK | O_CLOEXEC, 0666);
    if (fd < 0) {
        fprintf(stderr, "mechc %s: error: cannot write '%s': %s\n", command, path,
                errno == ENXIO ? "a named pipe that no process reads" : strerror(errno));
        return NULL;
    }
    int flags = fcntl(fd, F_GETFL);
    FILE *f = flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) < 0 ? NULL : fdopen(fd, "w");
    if (!f) {
        fprintf(stderr, "mechc %s: error: cannot write '%s': %s\n", command, path,
                strerror(errno));
        close(fd);
    }
    return f;
}
