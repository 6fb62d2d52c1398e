/* testload.h - a mechanism from a file or from text for a test, failing the test with the diagnostic when it does not load. */
#ifndef MECHC_TESTLOAD_H
#define MECHC_TESTLOAD_H

#include "../generator/pipeline/pipeline.h"

#include <stdio.h>
#include <stdlib.h>

static inline Mech *load_file(const char *path)
{
    static Diag diag;   /* must outlive the Mech on failure paths only */
    MechLimits limits = mech_default_limits();
    Mech *m = pipeline_load(path, &limits, &diag);
    if (!m)
        fail_msg("%s: %s", path, diag.message);
    return m;
}

/* examples/NAME, or $MECHC_EXAMPLES/NAME when the suite runs elsewhere. */
static inline Mech *load_example(const char *name)
{
    const char *dir = getenv("MECHC_EXAMPLES");
    char path[600];
    snprintf(path, sizeof path, "%s/%s", dir ? dir : "examples", name);
    return load_file(path);
}

static inline Mech *load_text(const char *text, const char *name)
{
    static Diag diag;
    MechLimits limits = mech_default_limits();
    Mech *m = pipeline_load_text(text, name, &limits, &diag);
    if (!m)
        fail_msg("%s: %s", name, diag.message);
    return m;
}

#endif
