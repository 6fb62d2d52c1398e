/* timing.h - what the bench drivers share: thread CPU time, symbols that must exist, batch sizing, sorting for medians. */
#ifndef MECHC_BENCH_TIMING_H
#define MECHC_BENCH_TIMING_H

#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double timing_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);   /* time descheduled does not count */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* dlopen, or exit 2 naming the program and dlerror's reason. */
static void *timing_open(const char *prog, const char *path)
{
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        fprintf(stderr, "%s: %s\n", prog, dlerror());
        exit(2);
    }
    return h;
}

/* dlsym, or exit 2 naming the program, the library and the symbol. */
static void *timing_sym(const char *prog, void *h, const char *path, const char *name)
{
    void *p = dlsym(h, name);
    if (!p) {
        fprintf(stderr, "%s: %s has no %s\n", prog, path, name);
        exit(2);
    }
    return p;
}

/* Calls per batch so that one batch lasts about 2 ms; after one call, so
   that page faults and cold caches do not count. call(ctx, n) makes n calls. */
static long timing_batch(void (*call)(void *ctx, long n), void *ctx)
{
    long n = 1;
    call(ctx, 1);
    for (;;) {
        double t0 = timing_now();
        call(ctx, n);
        double dt = timing_now() - t0;
        if (dt > 2e-3 || n > (1L << 30))
            return n;
        n = dt < 1e-5 ? n * 16 : (long)((double)n * 2.2e-3 / dt) + 1;
    }
}

static int timing_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

#endif
