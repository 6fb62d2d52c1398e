/* sympy_time.c - times mechc's kernels against SymPy cse's (bench/sympy_kernels.py), both shared objects.
 *
 *   sympy_time REPEAT NQ NR NNZ MECHC.so SYMPY.so     (bench/sympy_time.sh builds and runs it)
 *
 * Loads m_phi, m_jac_nz and m_gamma of both objects (and m_q0 of MECHC.so)
 * and calls them at the file's q0, slightly moved so that no angle is a
 * table point, velocities 0.1 (i mod 7 - 3), t = 0.3. First checks that the
 * two agree to 1e-12 relative to the largest magnitude (exit 1 otherwise:
 * the timings are of the same maths). Then REPEAT rounds, each timing
 * every kernel of both objects once, interleaved so that a change of
 * machine speed touches them alike, one batch of calls lasting about 2 ms,
 * in thread CPU time; each round starts at another slot, after one round to
 * warm up. Also times SYMPY.so's m_trig, sin and cos of every angle (the
 * trig floor both sides share). Prints per kernel the medians in ns per
 * call, their ratio, and the ratio of what lies above the floor:
 *   phi 41.2 52.0 0.79 0.62   (kernel, mechc, SymPy, mechc / SymPy,
 *                              (mechc - trig) / (SymPy - trig))
 *   trig 30.1
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "timing.h"

enum { FN_PHI, FN_JAC_NZ, FN_GAMMA, FN_COUNT, FN_TRIG = FN_COUNT, NLIBS = 2 };
static const char *const fn_names[FN_COUNT] = {"phi", "jac_nz", "gamma"};

typedef void (*QtOut)(const double *, double, double *);
typedef void (*GammaFn)(const double *, const double *, double, double *);

typedef struct Lib {
    const char *path;
    QtOut phi, jac_nz, trig;   /* trig: SYMPY.so's only */
    GammaFn gamma;
} Lib;

/* The state and output buffers every call uses. */
typedef struct Work {
    int nq, nr, nnz;
    double *q, *qd, *out;
    double t;
} Work;

static void *open_lib(Lib *l, const char *path)
{
    void *h = timing_open("sympy_time", path);
    l->path = path;
    *(void **)&l->phi = timing_sym("sympy_time", h, path, "m_phi");
    *(void **)&l->jac_nz = timing_sym("sympy_time", h, path, "m_jac_nz");
    *(void **)&l->gamma = timing_sym("sympy_time", h, path, "m_gamma");
    l->trig = NULL;
    return h;
}

static void call_n(const Lib *l, int fn, long n, Work *w);

/* One function of one library, for timing_batch. */
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

static void call_n(const Lib *l, int fn, long n, Work *w)
{
    for (long i = 0; i < n; i++)
        switch (fn) {
        case FN_PHI: l->phi(w->q, w->t, w->out); break;
        case FN_JAC_NZ: l->jac_nz(w->q, w->t, w->out); break;
        case FN_TRIG: l->trig(w->q, w->t, w->out); break;
        default: l->gamma(w->q, w->qd, w->t, w->out); break;
        }
}

/* Largest difference between the outputs of function fn of a and b,
   relative to the largest magnitude (at least 1); NaN counts as infinite. */
static double compare(const Lib *libs, int fn, Work *w)
{
    int len = fn == FN_JAC_NZ ? w->nnz : w->nr;
    double *out[NLIBS];
    for (int s = 0; s < NLIBS; s++) {
        out[s] = calloc((size_t)len + 1, sizeof(double));
        for (int i = 0; i < len; i++)
            out[s][i] = NAN;    /* an output left unwritten shows */
        double *keep = w->out;
        w->out = out[s];
        call_n(&libs[s], fn, 1, w);
        w->out = keep;
    }
    double worst = 0, scale = 1;
    for (int i = 0; i < len; i++)
        scale = fmax(scale, fabs(out[0][i]));
    for (int i = 0; i < len; i++) {
        double d = fabs(out[0][i] - out[1][i]);
        if (!(d <= worst))
            worst = isnan(d) ? INFINITY : d;
    }
    for (int s = 0; s < NLIBS; s++)
        free(out[s]);
    return worst / scale;
}

int main(int argc, char **argv)
{
    if (argc != 7) {
        fprintf(stderr, "usage: sympy_time REPEAT NQ NR NNZ MECHC.so SYMPY.so\n");
        return 2;
    }
    int repeat = atoi(argv[1]);
    Work w = {.nq = atoi(argv[2]), .nr = atoi(argv[3]), .nnz = atoi(argv[4]), .t = 0.3};
    if (repeat < 1 || w.nq < 1 || w.nr < 1 || w.nnz < 1) {
        fprintf(stderr, "sympy_time: REPEAT, NQ, NR and NNZ must be positive\n");
        return 2;
    }
    Lib libs[NLIBS];
    void *h = open_lib(&libs[0], argv[5]);
    void *hs = open_lib(&libs[1], argv[6]);
    *(void **)&libs[1].trig = timing_sym("sympy_time", hs, argv[6], "m_trig");
    const double *q0 = timing_sym("sympy_time", h, argv[5], "m_q0");
    w.q = calloc((size_t)w.nq, sizeof(double));
    w.qd = calloc((size_t)w.nq, sizeof(double));
    w.out = calloc(2 * (size_t)(w.nq + w.nr + w.nnz) + 16, sizeof(double));
    for (int i = 0; i < w.nq; i++) {
        w.q[i] = q0[i] + 1e-3 * (double)(i % 5);
        w.qd[i] = 0.1 * (double)(i % 7 - 3);
    }
    int status = 0;
    for (int fn = 0; fn < FN_COUNT; fn++) {
        double d = compare(libs, fn, &w);
        if (!(d <= 1e-12)) {
            fprintf(stderr, "sympy_time: %s of %s and %s differ by %g (relative)\n",
                    fn_names[fn], libs[0].path, libs[1].path, d);
            status = 1;
        }
    }
    if (status)
        return status;
    /* slot: kernel * NLIBS + lib; the last, SYMPY.so's trig floor */
    enum { NSLOTS = NLIBS * FN_COUNT + 1 };
    long batch[NSLOTS];
    double *ns = calloc((size_t)NSLOTS * (size_t)repeat, sizeof(double));
    for (int s = 0; s < NSLOTS; s++) {
        Timed c = {&libs[s < NSLOTS - 1 ? s % NLIBS : 1], s / NLIBS, &w};
        batch[s] = timing_batch(call_timed, &c);
    }
    for (int r = -1; r < repeat; r++)       /* round -1 warms up */
        for (int i = 0; i < NSLOTS; i++) {
            int s = (i + (r < 0 ? 0 : r)) % NSLOTS;
            double t0 = timing_now();
            call_n(&libs[s < NSLOTS - 1 ? s % NLIBS : 1], s / NLIBS, batch[s], &w);
            if (r >= 0)
                ns[(size_t)s * (size_t)repeat + (size_t)r] = 1e9 * (timing_now() - t0) / (double)batch[s];
        }
    double med[NSLOTS];
    for (int s = 0; s < NSLOTS; s++) {
        double *v = &ns[(size_t)s * (size_t)repeat];
        qsort(v, (size_t)repeat, sizeof *v, timing_cmp_double);
        med[s] = v[repeat / 2];
    }
    double trig = med[NSLOTS - 1];
    for (int fn = 0; fn < FN_COUNT; fn++) {
        double m = med[fn * NLIBS], s = med[fn * NLIBS + 1];
        printf("%s %.1f %.1f %.2f %.2f\n", fn_names[fn], m, s, m / s,
               s > trig ? (m - trig) / (s - trig) : NAN);
    }
    printf("trig %.1f\n", trig);
    free(ns);
    free(w.q);
    free(w.qd);
    free(w.out);
    return 0;
}
