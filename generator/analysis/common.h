/* common.h - what the analyses over time (run, sim, check) share: the linear-algebra choice, the status, the failure message. */
#ifndef MECHC_ANALYSIS_COMMON_H
#define MECHC_ANALYSIS_COMMON_H

#include <stddef.h>

/* The linear algebra of an analysis: dense (the freestanding runtime's LU,
   the dense null-space method, QR and SVD), or sparse on the generated
   kernels' nonzeros (KLU: runtime/host/sparse_klu.c for run,
   sparse_kkt.c's augmented matrix for sim; check differences the
   Jacobian by column groups), or whichever suits the size
   (ANALYSIS_DENSE_MAX_NQ). */
typedef enum AnalysisLinear {
    ANALYSIS_LINEAR_AUTO, ANALYSIS_LINEAR_DENSE, ANALYSIS_LINEAR_SPARSE
} AnalysisLinear;

/* "auto", "dense", "sparse", NULL: the --linear names, in AnalysisLinear order. */
extern const char *const analysis_linear_names[];

/* auto stays dense up to this many coordinates, sparse above: near the
   crossover measured on examples/chain.sh chains (doc/figures.md, "Size: dense against sparse"),
   where the dense LU's O(n^3) starts to cost more than KLU's overhead. */
#define ANALYSIS_DENSE_MAX_NQ 100
#define ANALYSIS_DENSE_MAX_NQ_TEXT "100" /* the same, for --help */

/* How an analysis ended; the values double as mechc's exit codes (spec section 3). */
typedef enum AnalysisStatus {
    ANALYSIS_OK = 0,       /* every state computed */
    ANALYSIS_FAILED = 1,   /* the analysis failed at a time: exit 1 */
    ANALYSIS_BAD_INPUT = 2 /* not runnable as given (row count, options): exit 2 */
} AnalysisStatus;

/* Output time i of steps equal intervals from t0 to t1: t1 itself at i = steps. */
double analysis_time_at(double t0, double t1, int steps, int i);

/* Appends printf-style text to the message msg (size bytes, NUL-terminated),
   truncating quietly at its size: a failure's message is built in parts. */
void analysis_msgf(char *msg, size_t size, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Appends to msg the names of the largest components of w (n >= 0, at
   least a fifth of the largest, six at most), largest first, separated by
   ", " and " and ". */
void analysis_name_list(char *msg, size_t size, const char *const *names, const double *w,
                        int n);

/* Appends to msg the names of the components of w at or above floor,
   largest first (six at most, then ", and N more"); returns how many were
   named. */
int analysis_name_above(char *msg, size_t size, const char *const *names, const double *w,
                        int n, double floor);

#endif
