/* written_time.c - times the kernels of written files (mechc gen --prefix m) built as shared objects.
 *
 *   written_time REPEAT NQ NR NNZ LIB...      (bench/written.sh builds and runs it)
 *
 * Loads every LIB (a written file compiled with -shared, under any
 * compiler), then times m_phi, m_jac, m_jac_nz, m_nu, m_gamma and m_all of
 * each at the file's q0 (slightly moved, so no angle is a table point),
 * velocities 0.1 (i mod 7 - 3), t = 0.3: REPEAT rounds, each timing every
 * function of every LIB once (interleaved, so a change of machine speed
 * touches them alike), one batch of calls lasting about 2 ms; the median
 * per function (each round starts at another function, after one round
 * to warm up). Also times the floor of the dense Jacobian: one memset of
 * NR*NQ reals and NNZ stores at their places, built with this driver's
 * flags (gcc -O2). Prints one line per LIB: its name, then ns per call of
 * phi jac jac_nz nu gamma all; then a line "floor" with the fill and
 * stores. Exits 1 when two LIBs disagree by more than 1e-9 (relative to
 * the largest magnitude) on any output: the timings are of the same maths.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "timing.h"

enum { FN_PHI, FN_JAC, FN_JAC_NZ, FN_NU, FN_GAMMA, FN_ALL, FN_COUNT, MAX_LIBS = 16 };
static const char *const fn_names[FN_COUNT] = {"phi", "jac", "jac_nz", "nu", "gamma", "all"};

typedef void (*QtOut)(const double *, double, double *);
typedef void (*GammaFn)(const double *, const double *, double, double *);
typedef void (*AllFn)(const double *, const double *, double, double *, double *, double *,
                      double *);

typedef struct Lib {
    const char *path;
    QtOut phi, jac, jac_nz, nu;
    GammaFn gamma;
    AllFn all;
    const double *q0;
    const int *row, *col;
} Lib;

/* The state and output buffers every call uses. */
typedef struct Work {
    int nq, nr, nnz;
    double *q, *qd, *phi, *jac, *vals, *nu, *gamma;
    double t;
} Work;

static void open_lib(Lib *l, const char *path)
{
    void *h = timing_open("written_time", path);
    l->path = path;
    *(void **)&l->phi = timing_sym("written_time", h, path, "m_phi");
    *(void **)&l->jac = timing_sym("written_time", h, path, "m_jac");
    *(void **)&l->jac_nz = timing_sym("written_time", h, path, "m_jac_nz");
    *(void **)&l->nu = timing_sym("written_time", h, path, "m_nu");
    *(void **)&l->gamma = timing_sym("written_time", h, path, "m_gamma");
    *(void **)&l->all = timing_sym("written_time", h, path, "m_all");
    l->q0 = timing_sym("written_time", h, path, "m_q0");
    l->row = timing_sym("written_time", h, path, "m_jac_row");
    l->col = timing_sym("written_time", h, path, "m_jac_col");
}

static void call_n(const Lib *l, int fn, long n, Work *w, const Lib *shape);

/* One function of one library (or the floor), for timing_batch. */
typedef struct Timed {
    const Lib *l, *shape;
    int fn;
    Work *w;
} Timed;

static void call_timed(void *ctx, long n)
{
    Timed *c = ctx;
    call_n(c->l, c->fn, n, c->w, c->shape);
}

/* Calls function fn of l n times; the floor (l NULL) is memset and stores. */
static void call_n(const Lib *l, int fn, long n, Work *w, const Lib *shape)
{
    for (long i = 0; i < n; i++) {
        if (!l) {
            memset(w->jac, 0, sizeof(double) * (size_t)w->nr * (size_t)w->nq);
            for (int k = 0; k < w->nnz; k++)
                w->jac[shape->row[k] * w->nq + shape->col[k]] = w->vals[k];
            continue;
        }
        switch (fn) {
        case FN_PHI: l->phi(w->q, w->t, w->phi); break;
        case FN_JAC: l->jac(w->q, w->t, w->jac); break;
        case FN_JAC_NZ: l->jac_nz(w->q, w->t, w->vals); break;
        case FN_NU: l->nu(w->q, w->t, w->nu); break;
        case FN_GAMMA: l->gamma(w->q, w->qd, w->t, w->gamma); break;
        default: l->all(w->q, w->qd, w->t, w->phi, w->jac, w->nu, w->gamma); break;
        }
    }
}

/* Largest difference between the outputs of a and b, relative to the
   largest magnitude; jac is filled with NaN first, so an entry left
   unwritten shows. */
static double compare(const Lib *a, const Lib *b, Work *w)
{
    size_t nd = (size_t)w->nr * (size_t)w->nq;
    double *out[2][5];
    const Lib *libs[2] = {a, b};
    for (int s = 0; s < 2; s++) {
        for (int k = 0; k < 5; k++)
            out[s][k] = calloc(nd + (size_t)w->nnz + 3 * (size_t)w->nr + 1, sizeof(double));
        for (size_t i = 0; i < nd; i++)
            out[s][1][i] = out[s][4][i] = NAN;
        libs[s]->phi(w->q, w->t, out[s][0]);
        libs[s]->jac(w->q, w->t, out[s][1]);
        libs[s]->jac_nz(w->q, w->t, out[s][2]);
        libs[s]->gamma(w->q, w->qd, w->t, out[s][3]);
        libs[s]->all(w->q, w->qd, w->t, out[s][3] + w->nr, out[s][4], out[s][0] + w->nr,
                     out[s][3] + 2 * w->nr);
    }
    size_t len[5] = {(size_t)(2 * w->nr), nd, (size_t)w->nnz, (size_t)(3 * w->nr), nd};
    double worst = 0, scale = 1;
    for (int k = 0; k < 5; k++)
        for (size_t i = 0; i < len[k]; i++)
            scale = fmax(scale, fabs(out[0][k][i]));
    for (int k = 0; k < 5; k++)
        for (size_t i = 0; i < len[k]; i++) {
            double d = fabs(out[0][k][i] - out[1][k][i]);
            if (!(d <= worst))      /* NaN included */
                worst = isnan(d) ? INFINITY : d;
        }
    for (int s = 0; s < 2; s++)
        for (int k = 0; k < 5; k++)
            free(out[s][k]);
    return worst / scale;
}

int main(int argc, char **argv)
{
    if (argc < 6 || argc - 5 > MAX_LIBS) {
        fprintf(stderr, "usage: written_time REPEAT NQ NR NNZ LIB... (at most %d)\n", MAX_LIBS);
        return 2;
    }
    int repeat = atoi(argv[1]), nlibs = argc - 5;
    Work w = {.nq = atoi(argv[2]), .nr = atoi(argv[3]), .nnz = atoi(argv[4]), .t = 0.3};
    Lib libs[MAX_LIBS];
    for (int i = 0; i < nlibs; i++)
        open_lib(&libs[i], argv[5 + i]);
    size_t nd = (size_t)w.nr * (size_t)w.nq;
    w.q = calloc((size_t)w.nq, sizeof(double));
    w.qd = calloc((size_t)w.nq, sizeof(double));
    w.phi = calloc((size_t)w.nr + 1, sizeof(double));
    w.jac = calloc(nd + 1, sizeof(double));
    w.vals = calloc((size_t)w.nnz + 1, sizeof(double));
    w.nu = calloc((size_t)w.nr + 1, sizeof(double));
    w.gamma = calloc((size_t)w.nr + 1, sizeof(double));
    for (int i = 0; i < w.nq; i++) {
        w.q[i] = libs[0].q0[i] + 1e-3 * (double)(i % 5);
        w.qd[i] = 0.1 * (double)(i % 7 - 3);
    }
    int status = 0;
    for (int i = 1; i < nlibs; i++) {
        double d = compare(&libs[0], &libs[i], &w);
        if (!(d <= 1e-9)) {
            fprintf(stderr, "written_time: %s and %s differ by %g (relative)\n", libs[0].path,
                    libs[i].path, d);
            status = 1;
        }
    }
    /* slot nlibs * FN_COUNT is the floor */
    int nslots = nlibs * FN_COUNT + 1;
    long *batch = calloc((size_t)nslots, sizeof(long));
    double *ns = calloc((size_t)nslots * (size_t)repeat, sizeof(double));
    for (int s = 0; s < nslots; s++) {
        Timed c = {s < nslots - 1 ? &libs[s / FN_COUNT] : NULL, &libs[0], s % FN_COUNT, &w};
        batch[s] = timing_batch(call_timed, &c);
    }
    /* round -1 warms up; each round starts at another slot, so that no
       LIB always follows the floor (whose memset evicts the Jacobian) */
    for (int r = -1; r < repeat; r++)
        for (int i = 0; i < nslots; i++) {
            int s = (i + (r < 0 ? 0 : r) * (FN_COUNT + 1)) % nslots;
            const Lib *l = s < nslots - 1 ? &libs[s / FN_COUNT] : NULL;
            double t0 = timing_now();
            call_n(l, s % FN_COUNT, batch[s], &w, &libs[0]);
            if (r >= 0)
                ns[(size_t)s * (size_t)repeat + (size_t)r] = 1e9 * (timing_now() - t0) / (double)batch[s];
        }
    for (int s = 0; s < nslots; s++) {
        double *v = &ns[(size_t)s * (size_t)repeat];
        qsort(v, (size_t)repeat, sizeof *v, timing_cmp_double);
        if (s % FN_COUNT == 0 || s == nslots - 1)
            printf("%s", s < nslots - 1 ? libs[s / FN_COUNT].path : "floor");
        printf(" %.1f", v[repeat / 2]);
        if (s % FN_COUNT == FN_COUNT - 1 || s == nslots - 1)
            printf("\n");
    }
    printf("# columns: %s %s %s %s %s %s (ns per call, median of %d); floor: memset + %d stores\n",
           fn_names[0], fn_names[1], fn_names[2], fn_names[3], fn_names[4], fn_names[5], repeat,
           w.nnz);
    free(batch);
    free(ns);
    return status;
}
