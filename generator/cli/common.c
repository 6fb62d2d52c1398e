/* common.c - what the commands do alike once their options are read: load the file, open an engine, report a failure. */
#include "cli.h"

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
