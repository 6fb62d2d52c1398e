/* testcache.h - a private AOT cache directory for one test suite (XDG_CACHE_HOME), removed afterwards. */
#ifndef MECHC_TESTCACHE_H
#define MECHC_TESTCACHE_H

#include "../generator/engine/aot.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* Makes TMPDIR/mechc-test-SUITE-XXXXXX into dir (size n) and points
   XDG_CACHE_HOME at it, so the suite never touches the user's cache. */
static inline bool testcache_make(char *dir, size_t n, const char *suite)
{
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
    testcache_remove(c->dir, 2);
    return 0;
}

#endif
