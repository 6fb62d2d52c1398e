/* svd.h - the dense SVD's workspace for `info`, and redundant rows by incremental rank. */
#ifndef MECHC_ANALYSIS_SVD_H
#define MECHC_ANALYSIS_SVD_H

#include "../../runtime/host/mechrt_host.h"

#include <stdbool.h>

/* The dense SVD is the host runtime's (MechrtSvd, mechrt_svd,
   mechrt_svd_pinv_solve, mechrt_svd_row_basis: runtime/host/mechrt_host.h),
   the same one `run` projects with. svd_work_new allocates its workspace
   and aborts when memory runs out, like xmalloc. */
MechrtSvd *svd_work_new(int max_m, int max_n);

/* Redundant rows: row i (i >= first) is redundant when the rank of rows
   0..i equals the rank of rows 0..i-1, every rank taken with the absolute
   tolerance tol (singular values only grow when rows are added, so the
   deficiency k - rank(k) is monotone and its steps are found by bisection,
   O(d log m) decompositions for d redundant rows). rank: the rank of all m
   rows with tol when already known (saves one decomposition), else -1.
   Sets redundant[i] for i in [first, m); returns their count, -1 on NaN or
   Inf. Uses (and clobbers) the workspace. */
int svd_redundant_rows(MechrtSvd *w, const double *a, int m, int n, int lda, double tol,
                       int first, int rank, bool *redundant);

#endif
