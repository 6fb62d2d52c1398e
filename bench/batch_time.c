/* batch_time.c - times a written file's batch kernels (mechc gen --batch --prefix m) against single calls.
 *
 *   batch_time REPEAT STATES NQ NR NNZ LIB      (bench/batch.sh builds and runs it)
 *
 * Loads LIB (the written file compiled with -shared) and evaluates m_gamma,
 * the fused m_all and, where LIB has it (gen --sparse), m_all_nz at STATES
 * states (q0 moved by up to 0.3 in every
 * coordinate, velocities in [-2, 2], t in [0, 1)), 10^6 evaluations of
 * each per timing: 10^6 / STATES rounds over the states, either as one
 * m_NAME_batch(STATES, ...) call or as STATES calls of m_NAME. Single and
 * batch alternate REPEAT times (the same machine speed for both); the
 * medians of the CPU time of this thread, in ns per evaluation, and the
 * ratio single / batch are printed for each kernel. Exits 1 unless the
 * batch's outputs equal the single calls' to the bit.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "timing.h"

#include <dlfcn.h>

enum { EVALUATIONS = 1000000, MAX_REPEAT = 101 };

typedef void (*GammaFn)(const double *, const double *, double, double *);
typedef void (*AllFn)(const double *, const double *, double, double *, double *, double *,
                      double *);
typedef void (*GammaBatchFn)(int, const double *, const double *, const double *, double *);
typedef void (*AllBatchFn)(int, const double *, const double *, const double *, double *,
                           double *, double *, double *);

typedef struct Bench {
    int n, nq, nr, nnz;
    GammaFn gamma;
    AllFn all;
    GammaBatchFn gamma_batch;
    AllBatchFn all_batch;
    AllFn all_nz;           /* NULL without gen --sparse */
    AllBatchFn all_nz_batch;
    double *q, *qd, *t;
    double *out[2][4];      /* [single, batch][phi, jac, nu, gamma] */
} Bench;

static double *array(size_t n)
{
    double *a = calloc(n + 1, sizeof *a);
    if (!a) {
        fprintf(stderr, "batch_time: out of memory\n");
        exit(2);
    }
    return a;
}

enum { KERNEL_GAMMA, KERNEL_ALL, KERNEL_ALL_NZ, KERNEL_COUNT };
static const char *const kernel_names[KERNEL_COUNT] = {"gamma", "all", "all_nz"};

/* 10^6 evaluations of kernel as single calls or batches; its seconds. */
static double run(Bench *b, int kernel, int batch)
{
    size_t nq = (size_t)b->nq, nr = (size_t)b->nr, nnz = (size_t)b->nnz;
    double **o = b->out[batch];
    AllFn all = kernel == KERNEL_ALL ? b->all : b->all_nz;
    AllBatchFn all_batch = kernel == KERNEL_ALL ? b->all_batch : b->all_nz_batch;
    size_t jac = kernel == KERNEL_ALL ? nr * nq : nnz;
    double t0 = timing_now();
    for (int round = 0; round < EVALUATIONS / b->n; round++) {
        if (batch && kernel != KERNEL_GAMMA)
            all_batch(b->n, b->q, b->qd, b->t, o[0], o[1], o[2], o[3]);
        else if (batch)
            b->gamma_batch(b->n, b->q, b->qd, b->t, o[3]);
        for (size_t i = 0; !batch && i < (size_t)b->n; i++) {
            if (kernel != KERNEL_GAMMA)
                all(b->q + i * nq, b->qd + i * nq, b->t[i], o[0] + i * nr, o[1] + i * jac,
                    o[2] + i * nr, o[3] + i * nr);
            else
                b->gamma(b->q + i * nq, b->qd + i * nq, b->t[i], o[3] + i * nr);
        }
    }
    return timing_now() - t0;
}

static int same(const Bench *b, int sparse)
{
    size_t n = (size_t)b->n, nr = (size_t)b->nr;
    size_t sizes[4] = {n * nr, n * (sparse ? (size_t)b->nnz : nr * (size_t)b->nq), n * nr, n * nr};
    for (int k = 0; k < 4; k++)
        if (memcmp(b->out[0][k], b->out[1][k], sizes[k] * sizeof(double)) != 0)
            return 0;
    return 1;
}

static void open_bench(Bench *b, const char *path)
{
    void *h = timing_open("batch_time", path);
    *(void **)&b->gamma = timing_sym("batch_time", h, path, "m_gamma");
    *(void **)&b->all = timing_sym("batch_time", h, path, "m_all");
    *(void **)&b->gamma_batch = timing_sym("batch_time", h, path, "m_gamma_batch");
    *(void **)&b->all_batch = timing_sym("batch_time", h, path, "m_all_batch");
    *(void **)&b->all_nz = dlsym(h, "m_all_nz");
    *(void **)&b->all_nz_batch = dlsym(h, "m_all_nz_batch");
    const double *q0 = timing_sym("batch_time", h, path, "m_q0");
    size_t n = (size_t)b->n, nq = (size_t)b->nq, nr = (size_t)b->nr;
    b->q = array(n * nq);
    b->qd = array(n * nq);
    b->t = array(n);
    unsigned long long seed = 29;
    for (size_t i = 0; i < n * nq; i++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        double u = (double)(seed >> 11) * 0x1.0p-53;
        b->q[i] = q0[i % nq] + 0.6 * (u - 0.5);
        b->qd[i] = 4.0 * (u - 0.5) * (i % 2 ? 1 : -1);
    }
    for (size_t i = 0; i < n; i++)
        b->t[i] = (double)i / (double)n;
    for (int s = 0; s < 2; s++) {
        b->out[s][0] = array(n * nr);
        b->out[s][1] = array(n * nr * nq);
        b->out[s][2] = array(n * nr);
        b->out[s][3] = array(n * nr);
    }
}

int main(int argc, char **argv)
{
    if (argc != 7) {
        fprintf(stderr, "usage: batch_time REPEAT STATES NQ NR NNZ LIB\n");
        return 2;
    }
    int repeat = atoi(argv[1]);
    Bench b = {.n = atoi(argv[2]), .nq = atoi(argv[3]), .nr = atoi(argv[4]),
               .nnz = atoi(argv[5])};
    if (repeat < 1 || repeat > MAX_REPEAT || b.n < 1 || b.n > EVALUATIONS || b.nq < 1 || b.nr < 1) {
        fprintf(stderr, "batch_time: bad arguments\n");
        return 2;
    }
    open_bench(&b, argv[6]);
    int status = 0;
    for (int kernel = 0; kernel < KERNEL_COUNT; kernel++) {
        if (kernel == KERNEL_ALL_NZ && !(b.all_nz && b.all_nz_batch))
            continue;
        double t[2][MAX_REPEAT];
        run(&b, kernel, 0);     /* warm up */
        run(&b, kernel, 1);
        for (int r = 0; r < repeat; r++)
            for (int batch = 0; batch < 2; batch++)
                t[batch][r] = run(&b, kernel, (batch + r) % 2);
        for (int r = 0; r < repeat; r++)      /* undo the alternation */
            if (r % 2) {
                double x = t[0][r];
                t[0][r] = t[1][r];
                t[1][r] = x;
            }
        qsort(t[0], (size_t)repeat, sizeof(double), timing_cmp_double);
        qsort(t[1], (size_t)repeat, sizeof(double), timing_cmp_double);
        double single = t[0][repeat / 2] * 1e9 / EVALUATIONS, batch = t[1][repeat / 2] * 1e9 / EVALUATIONS;
        int ok = same(&b, kernel == KERNEL_ALL_NZ);
        printf("%-6s single %8.2f ns  batch %8.2f ns  x%.2f%s\n", kernel_names[kernel], single, batch,
               single / batch, ok ? "" : "  DIFFERENT OUTPUTS");
        status |= !ok;
    }
    return status;
}
