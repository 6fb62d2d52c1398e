/* common.c - what the commands do alike: the order of their steps, loading the file, opening an engine, reporting a failure. */
#include "cli.h"

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
