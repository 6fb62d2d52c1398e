/* testdyn.h - what the dynamics suites share: the engine cache, opening an engine with masses, comparing arrays. */
#ifndef MECHC_TESTDYN_H
#define MECHC_TESTDYN_H

#include "testutil.h"
#include "testcache.h"

#include "../generator/engine/engine.h"

static TestCache cache;

/* The suite's fixtures: testcache_setup(&cache, TESTDYN_SUITE). */
static int setup(void **state)
{
    (void)state;
    return testcache_setup(&cache, TESTDYN_SUITE);
}

static int teardown(void **state)
{
    (void)state;
    return testcache_teardown(&cache);
}

/* The engines a test runs: jit, generic, and aot with a compiler. */
static int engine_count(void) { return cache.have_cc ? ENGINE_KIND_COUNT : 2; }

/* Opens an engine of a file with masses: its mass and force kernels exist. */
static void open_engine(Engine *e, EngineKind kind, const Mech *mech)
{
    Diag diag;
    if (!engine_open(e, kind, mech, &diag))
        fail_msg("%s: %s", engine_names[kind], diag.message);
    assert_non_null(e->k.mass);
    assert_non_null(e->k.force);
}

#endif
