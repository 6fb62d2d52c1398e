/* roll_time.c - times the sparse kernels of written files side by side: straight-line against loop-rolled (mechc gen --roll).
 *
 *   roll_time REPEAT NQ NR NNZ LIB...      (bench/roll.sh builds and runs it)
 *
 * Loads every LIB (a written file with --sparse --prefix m, built with
 * -shared by any compiler), checks that all compute the same bytes for
 * m_phi, m_jac_nz, m_nu, m_gamma and m_all_nz (exit 1 otherwise: rolled
 * and straight-line code must agree to the bit), then times each of them,
 * REPEAT rounds interleaved over the LIBs (one round to warm up, batches
 * of about 2 ms), at q0 slightly moved, velocities 0.1 (i mod 7 - 3),
 * t = 0.3. Prints one line per LIB: its name and the median ns per call of
 * phi jac_nz nu gamma all_nz.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "timing.h"

enum { FN_PHI, FN_JAC_NZ, FN_NU, FN_GAMMA, FN_ALL_NZ, FN_COUNT, MAX_LIBS = 8 };
static const char *const fn_names[FN_COUNT] = {"phi", "jac_nz", "nu", "gamma", "all_nz"};

typedef void (*QtOut)(const double *, double, double *);
typedef void (*GammaFn)(const double *, const double *, double, double *);
typedef void (*AllFn)(const double *, const double *, double, double *, double *, double *,
                      double *);

/* A library's kernels, m_NAME for each of fn_names, and its q0. */
typedef struct Lib {
    const char *path;
    void *fn[FN_COUNT];
    const double *q0;
} Lib;

/* The state and the outputs every call uses. */
typedef struct Work {
    int nq, nr, nnz;
    double *q, *qd, *phi, *vals, *nu, *gamma;
    double t;
} Work;

static void open_lib(Lib *l, const char *path)
{
    void *h = timing_open("roll_time", path);
    l->path = path;
    for (int f = 0; f < FN_COUNT; f++) {
        char name[32];
        snprintf(name, sizeof name, "m_%s", fn_names[f]);
        l->fn[f] = timing_sym("roll_time", h, path, name);
    }
    l->q0 = timing_sym("roll_time", h, path, "m_q0");
}

/* n calls of kernel f of l; the casts from the symbols' void pointers. */
static void call_n(const Lib *l, int f, long n, Work *w)
{
    QtOut qt = (QtOut)(uintptr_t)l->fn[f];
    GammaFn gamma = (GammaFn)(uintptr_t)l->fn[f];
    AllFn all = (AllFn)(uintptr_t)l->fn[f];
    double *out = f == FN_PHI ? w->phi : f == FN_JAC_NZ ? w->vals : w->nu;
    for (long i = 0; i < n; i++)
        if (f == FN_GAMMA)
            gamma(w->q, w->qd, w->t, w->gamma);
        else if (f == FN_ALL_NZ)
            all(w->q, w->qd, w->t, w->phi, w->vals, w->nu, w->gamma);
        else
            qt(w->q, w->t, out);
}

typedef struct Timed {
    const Lib *l;
    int fn;
    Work *w;
} Timed;

static void call_timed(void *ctx, long n)
{
    Timed *c = ctx;
    call_n(c->l, c->fn, n, c->w);
}

/* Every output of l, one after the other, into out (4 nr + nnz reals). */
static void outputs(const Lib *l, Work w_, double *out)
{
    Work *w = &w_;
    memset(out, 0x5a, (4 * (size_t)w->nr + (size_t)w->nnz) * sizeof *out);
    call_n(l, FN_ALL_NZ, 1, w);
    memcpy(out, w->phi, (size_t)w->nr * sizeof *out);
    memcpy(out + w->nr, w->vals, (size_t)w->nnz * sizeof *out);
    double *tail = out + w->nr + w->nnz;    /* phi, nu, gamma, one call each */
    w->phi = tail;
    call_n(l, FN_PHI, 1, w);
    w->nu = tail + w->nr;
    call_n(l, FN_NU, 1, w);
    double *gamma = w->gamma;
    w->gamma = tail + 2 * w->nr;
    call_n(l, FN_GAMMA, 1, w);
    for (int i = 0; i < w->nr; i++)
        if (memcmp(&gamma[i], &w->gamma[i], sizeof(double))) {
            fprintf(stderr, "roll_time: %s: all_nz and gamma differ at row %d\n", l->path, i);
            exit(1);
        }
}

int main(int argc, char **argv)
{
    if (argc < 6 || argc - 5 > MAX_LIBS) {
        fprintf(stderr, "usage: roll_time REPEAT NQ NR NNZ LIB... (at most %d)\n", MAX_LIBS);
        return 2;
    }
    int repeat = atoi(argv[1]), nlibs = argc - 5;
    Work w = {.nq = atoi(argv[2]), .nr = atoi(argv[3]), .nnz = atoi(argv[4]), .t = 0.3};
    Lib libs[MAX_LIBS];
    for (int i = 0; i < nlibs; i++)
        open_lib(&libs[i], argv[5 + i]);
    w.q = calloc((size_t)w.nq, sizeof(double));
    w.qd = calloc((size_t)w.nq, sizeof(double));
    w.phi = calloc((size_t)w.nr + 1, sizeof(double));
    w.vals = calloc((size_t)w.nnz + 1, sizeof(double));
    w.nu = calloc((size_t)w.nr + 1, sizeof(double));
    w.gamma = calloc((size_t)w.nr + 1, sizeof(double));
    for (int i = 0; i < w.nq; i++) {
        w.q[i] = libs[0].q0[i] + 1e-3 * (double)(i % 5);
        w.qd[i] = 0.1 * (double)(i % 7 - 3);
    }
    size_t nout = 4 * (size_t)w.nr + (size_t)w.nnz;
    double *first = malloc(nout * sizeof *first), *other = malloc(nout * sizeof *other);
    outputs(&libs[0], w, first);
    for (int i = 1; i < nlibs; i++) {
        outputs(&libs[i], w, other);
        if (memcmp(first, other, nout * sizeof *first)) {
            fprintf(stderr, "roll_time: %s and %s differ\n", libs[0].path, libs[i].path);
            return 1;
        }
    }
    int nslots = nlibs * FN_COUNT;
    long *batch = calloc((size_t)nslots, sizeof(long));
    double *ns = calloc((size_t)nslots * (size_t)repeat, sizeof(double));
    for (int s = 0; s < nslots; s++) {
        Timed c = {&libs[s / FN_COUNT], s % FN_COUNT, &w};
        batch[s] = timing_batch(call_timed, &c);
    }
    for (int r = -1; r < repeat; r++)
        for (int i = 0; i < nslots; i++) {
            int s = (i + (r < 0 ? 0 : r)) % nslots;
            double t0 = timing_now();
            call_n(&libs[s / FN_COUNT], s % FN_COUNT, batch[s], &w);
            if (r >= 0)
                ns[(size_t)s * (size_t)repeat + (size_t)r] = 1e9 * (timing_now() - t0) / (double)batch[s];
        }
    printf("%-28s", "ns per call");
    for (int f = 0; f < FN_COUNT; f++)
        printf(" %10s", fn_names[f]);
    printf("\n");
    for (int s = 0; s < nslots; s++) {
        double *v = &ns[(size_t)s * (size_t)repeat];
        qsort(v, (size_t)repeat, sizeof *v, timing_cmp_double);
        if (s % FN_COUNT == 0) {
            const char *base = strrchr(libs[s / FN_COUNT].path, '/');
            printf("%-28s", base ? base + 1 : libs[s / FN_COUNT].path);
        }
        printf(" %10.0f", v[repeat / 2]);
        if (s % FN_COUNT == FN_COUNT - 1)
            printf("\n");
    }
    free(first);
    free(other);
    return 0;
}
