/* batch_time.c - times a written file's batch kernels (mechc gen --batch --prefix m) against single calls.
 *
 *   batch_time REPEAT STATES NQ NR NNZ LIB      (bench/batch.sh builds and runs it)
 *
 * Loads LIB (the written file compiled with -shared) and evaluates m_gamma,
 * the fused m_all and, where LIB has it (gen --sparse), m_all_nz at STATES
 * states (q0 moved by up to 0.3 in every
 * coordinate, velocities in [-2, 2], t in [0, 1)), 10^6 evaluations of
 * each per timing: 10^6 / STATES rounds over the states, as STATES calls
 * of m_NAME on rows, one m_NAME_batch(STATES, ...) call on the same rows,
 * or one m_NAME_batch_soa call on the states by coordinate (the same
 * values transposed). The three alternate REPEAT times (the same machine
 * speed for all); the minimum and the median of the CPU time of this
 * thread, in ns per evaluation, and the ratios single / batch (by minima)
 * are printed for each kernel. Exits 1 unless both batches' outputs equal
 * the single calls' to the bit.
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

enum { KERNEL_GAMMA, KERNEL_ALL, KERNEL_ALL_NZ, KERNEL_COUNT };
static const char *const kernel_names[KERNEL_COUNT] = {"gamma", "all", "all_nz"};
/* how the states go in: single calls on rows, a batch on rows, a batch by coordinate */
enum { WAY_SINGLE, WAY_ROWS, WAY_SOA, WAY_COUNT };

typedef struct Bench {
    int n, nq, nr, nnz;
    GammaFn gamma;
    AllFn all[KERNEL_COUNT];                    /* [KERNEL_ALL], [KERNEL_ALL_NZ] */
    GammaBatchFn gamma_batch[WAY_COUNT];        /* [WAY_ROWS], [WAY_SOA] */
    AllBatchFn all_batch[KERNEL_COUNT][WAY_COUNT];
    double *q, *qd, *t, *q_soa, *qd_soa;
    double *out[WAY_COUNT][4];  /* [way][phi, jac, nu, gamma] */
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

/* 10^6 evaluations of kernel one of the ways; its seconds. */
static double run(Bench *b, int kernel, int way)
{
    size_t nq = (size_t)b->nq, nr = (size_t)b->nr;
    size_t jac = kernel == KERNEL_ALL ? nr * nq : (size_t)b->nnz;
    double **o = b->out[way];
    const double *q = way == WAY_SOA ? b->q_soa : b->q, *qd = way == WAY_SOA ? b->qd_soa : b->qd;
    double t0 = timing_now();
    for (int round = 0; round < EVALUATIONS / b->n; round++) {
        if (way != WAY_SINGLE && kernel != KERNEL_GAMMA)
            b->all_batch[kernel][way](b->n, q, qd, b->t, o[0], o[1], o[2], o[3]);
        else if (way != WAY_SINGLE)
            b->gamma_batch[way](b->n, q, qd, b->t, o[3]);
        for (size_t i = 0; way == WAY_SINGLE && i < (size_t)b->n; i++) {
            if (kernel != KERNEL_GAMMA)
                b->all[kernel](q + i * nq, qd + i * nq, b->t[i], o[0] + i * nr, o[1] + i * jac,
                               o[2] + i * nr, o[3] + i * nr);
            else
                b->gamma(q + i * nq, qd + i * nq, b->t[i], o[3] + i * nr);
        }
    }
    return timing_now() - t0;
}

/* Whether way's outputs equal the single calls' to the bit (by
   coordinate: transposed). */
static int same(const Bench *b, int kernel, int way)
{
    size_t n = (size_t)b->n, nr = (size_t)b->nr;
    size_t sizes[4] = {nr, kernel == KERNEL_ALL_NZ ? (size_t)b->nnz : nr * (size_t)b->nq, nr, nr};
    for (int k = kernel == KERNEL_GAMMA ? 3 : 0; k < 4; k++)
        for (size_t i = 0; i < n; i++)
            for (size_t j = 0; j < sizes[k]; j++) {
                double x = b->out[WAY_SINGLE][k][i * sizes[k] + j];
                double y = b->out[way][k][way == WAY_SOA ? j * n + i : i * sizes[k] + j];
                if (memcmp(&x, &y, sizeof x) != 0)
                    return 0;
            }
    return 1;
}

static void *symbol(void *h, const char *path, const char *name, const char *suffix)
{
    char full[64];
    snprintf(full, sizeof full, "m_%s%s", name, suffix);
    return timing_sym("batch_time", h, path, full);
}

static void open_bench(Bench *b, const char *path)
{
    void *h = timing_open("batch_time", path);
    *(void **)&b->gamma = symbol(h, path, "gamma", "");
    *(void **)&b->gamma_batch[WAY_ROWS] = symbol(h, path, "gamma", "_batch");
    *(void **)&b->gamma_batch[WAY_SOA] = symbol(h, path, "gamma", "_batch_soa");
    for (int k = KERNEL_ALL; k < KERNEL_COUNT; k++) {
        if (k == KERNEL_ALL_NZ && !dlsym(h, "m_all_nz"))      /* without gen --sparse */
            continue;
        *(void **)&b->all[k] = symbol(h, path, kernel_names[k], "");
        *(void **)&b->all_batch[k][WAY_ROWS] = symbol(h, path, kernel_names[k], "_batch");
        *(void **)&b->all_batch[k][WAY_SOA] = symbol(h, path, kernel_names[k], "_batch_soa");
    }
    const double *q0 = timing_sym("batch_time", h, path, "m_q0");
    size_t n = (size_t)b->n, nq = (size_t)b->nq, nr = (size_t)b->nr;
    b->q = array(n * nq);
    b->qd = array(n * nq);
    b->q_soa = array(n * nq);
    b->qd_soa = array(n * nq);
    b->t = array(n);
    unsigned long long seed = 29;
    for (size_t i = 0; i < n * nq; i++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        double u = (double)(seed >> 11) * 0x1.0p-53;
        b->q[i] = q0[i % nq] + 0.6 * (u - 0.5);
        b->qd[i] = 4.0 * (u - 0.5) * (i % 2 ? 1 : -1);
        b->q_soa[(i % nq) * n + i / nq] = b->q[i];
        b->qd_soa[(i % nq) * n + i / nq] = b->qd[i];
    }
    for (size_t i = 0; i < n; i++)
        b->t[i] = (double)i / (double)n;
    for (int w = 0; w < WAY_COUNT; w++) {
        b->out[w][0] = array(n * nr);
        b->out[w][1] = array(n * nr * nq);
        b->out[w][2] = array(n * nr);
        b->out[w][3] = array(n * nr);
    }
}

/* Times kernel REPEAT times each way, the ways in turn; prints the line. */
static int time_kernel(Bench *b, int kernel, int repeat)
{
    double t[WAY_COUNT][MAX_REPEAT], best[WAY_COUNT], median[WAY_COUNT];
    for (int w = 0; w < WAY_COUNT; w++)
        run(b, kernel, w);      /* warm up */
    for (int r = 0; r < repeat; r++)
        for (int i = 0; i < WAY_COUNT; i++) {
            int w = (i + r) % WAY_COUNT;
            t[w][r] = run(b, kernel, w);
        }
    for (int w = 0; w < WAY_COUNT; w++) {
        qsort(t[w], (size_t)repeat, sizeof(double), timing_cmp_double);
        best[w] = t[w][0] * 1e9 / EVALUATIONS;
        median[w] = t[w][repeat / 2] * 1e9 / EVALUATIONS;
    }
    int ok = same(b, kernel, WAY_ROWS) && same(b, kernel, WAY_SOA);
    printf("%-6s single %7.2f (%7.2f)  rows %7.2f (%7.2f) x%.2f  soa %7.2f (%7.2f) x%.2f%s\n",
           kernel_names[kernel], best[WAY_SINGLE], median[WAY_SINGLE], best[WAY_ROWS],
           median[WAY_ROWS], best[WAY_SINGLE] / best[WAY_ROWS], best[WAY_SOA], median[WAY_SOA],
           best[WAY_SINGLE] / best[WAY_SOA], ok ? "" : "  DIFFERENT OUTPUTS");
    return ok;
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
    printf("ns per evaluation, minimum (median); ratios single / batch by minima\n");
    int status = 0;
    for (int kernel = 0; kernel < KERNEL_COUNT; kernel++)
        if (kernel == KERNEL_GAMMA || b.all[kernel])
            status |= !time_kernel(&b, kernel, repeat);
    return status;
}
