/* testcache.h - the AOT cache of a test suite (XDG_CACHE_HOME): tests/run_all's, shared by the run, or a private one removed afterwards; engines opened with it. */
#ifndef MECHC_TESTCACHE_H
#define MECHC_TESTCACHE_H

#include "../generator/engine/aot.h"
#include "../generator/engine/engine.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Points XDG_CACHE_HOME at the run's cache, $MECHC_TEST_CACHE, which
   tests/run_all sets for all its suites (the keys hash source, compiler
   and flags: the suites build each library once between them); run alone,
   at a new TMPDIR/mechc-test-SUITE-XXXXXX. dir (size n) gets the folder,
   so the suite never touches the user's cache. */
static inline bool testcache_make(char *dir, size_t n, const char *suite)
{
    const char *shared = getenv("MECHC_TEST_CACHE");
    if (shared && shared[0] == '/' && strlen(shared) < n) {
        snprintf(dir, n, "%s", shared);
        setenv("XDG_CACHE_HOME", dir, 1);
        return true;
    }
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, n, "%s/mechc-test-%s-XXXXXX", tmp && *tmp ? tmp : "/tmp", suite);
    if (!mkdtemp(dir))
        return false;
    setenv("XDG_CACHE_HOME", dir, 1);
    return true;
}

/* Removes dir and what it holds, depth levels of folders below it. */
static inline void testcache_remove(const char *dir, int depth)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    char path[900];
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        int len = snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (len < 0 || (size_t)len >= sizeof path)
            continue;
        if (unlink(path) != 0 && depth > 0)
            testcache_remove(path, depth - 1);
    }
    closedir(d);
    rmdir(dir);
}

/* Removes the suite's cache unless it is the run's. */
static inline void testcache_release(const char *dir)
{
    const char *shared = getenv("MECHC_TEST_CACHE");
    if (!shared || strcmp(shared, dir) != 0)
        testcache_remove(dir, 2);
}

/* A suite's cache and whether a C compiler is there (the aot engine's
   tests run only then), for its cmocka setup and teardown. */
typedef struct TestCache {
    char dir[256];
    bool have_cc;
} TestCache;

static inline int testcache_setup(TestCache *c, const char *suite)
{
    if (!testcache_make(c->dir, sizeof c->dir, suite))
        return -1;
    c->have_cc = aot_compiler_available();
    return 0;
}

static inline int testcache_teardown(TestCache *c)
{
    testcache_release(c->dir);
    return 0;
}

/* Opens an engine of kind for mech, failing the test when it cannot;
   false (nothing opened) for aot without a C compiler. */
static inline bool testcache_open_engine(const TestCache *c, Engine *e, EngineKind kind,
                                         const Mech *mech)
{
    if (kind == ENGINE_AOT && !c->have_cc)
        return false;
    Diag diag;
    if (!engine_open(e, kind, mech, &diag))
        fail_msg("%s: %s", engine_names[kind], diag.message);
    return true;
}

#endif
