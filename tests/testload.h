/* testload.h - a mechanism from a file or from text for a test, failing the test with the diagnostic when it does not load. */
#ifndef MECHC_TESTLOAD_H
#define MECHC_TESTLOAD_H

#include "../generator/pipeline/pipeline.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

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

/* A mechanism written by one of the examples' shell scripts (script N FILE). */
static inline Mech *load_script(const char *script, int n)
{
    char path[256], cmd[600];
    const char *dir = getenv("MECHC_EXAMPLES");
    snprintf(path, sizeof path, "%s/mechc_test_script_%d_%d.mech",
             getenv("TMPDIR") && *getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (int)getpid(), n);
    snprintf(cmd, sizeof cmd, "sh '%s/%s' %d '%s'", dir ? dir : "examples", script, n, path);
    if (system(cmd) != 0)
        fail_msg("%s failed", cmd);
    Mech *mech = load_file(path);
    unlink(path);
    return mech;
}

#endif
