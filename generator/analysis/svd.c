/* svd.c - redundant rows by incremental rank, on the host runtime's dense SVD.
 *
 * The SVD itself (GSL, rank, pseudo-inverse) is runtime/host/svd.c, shared
 * with `run`; this file adds what only `info` asks of it.
 *
 * Redundant rows use the interlacing of singular values (Golub and Van Loan
 * 8.6.1): appending a row to a matrix never lowers any singular value and
 * raises the count above a fixed tolerance by at most one, so with that
 * tolerance held fixed the deficiency def(k) = k - rank(first k rows) steps
 * up by 0 or 1 per row, and the rows where it steps are found by bisection.
 */
#include "svd.h"

#include "../base/arena.h"

#include <stdio.h>
#include <stdlib.h>

MechrtSvd *svd_work_new(int max_m, int max_n)
{
    MechrtSvd *w = mechrt_svd_new(max_m, max_n);
    if (!w) {
        fprintf(stderr, "mechc: out of memory (SVD workspace %d x %d)\n", max_m, max_n);
        abort();
    }
    return w;
}

/* Deficiency of the first k rows: k - rank, -1 on NaN/Inf. */
static int deficiency(MechrtSvd *w, const double *a, int k, int n, int lda, double tol)
{
    MechrtSvdResult r;
    if (!mechrt_svd(w, a, k, n, lda, tol, &r))
        return -1;
    return k - r.rank;
}

/* Marks the rows in [lo, hi) where the deficiency steps, given def(lo), def(hi). */
static bool bisect(MechrtSvd *w, const double *a, int n, int lda, double tol,
                   int lo, int dlo, int hi, int dhi, bool *redundant)
{
    if (dhi == dlo)
        return true;
    if (hi == lo + 1) {
        redundant[lo] = true;       /* adding row lo (the hi-th row) did not raise the rank */
        return true;
    }
    int mid = lo + (hi - lo) / 2;
    int dmid = deficiency(w, a, mid, n, lda, tol);
    if (dmid < 0)
        return false;
    return bisect(w, a, n, lda, tol, lo, dlo, mid, dmid, redundant)
           && bisect(w, a, n, lda, tol, mid, dmid, hi, dhi, redundant);
}

int svd_redundant_rows(MechrtSvd *w, const double *a, int m, int n, int lda, double tol,
                       int first, int rank, bool *redundant)
{
    for (int i = first; i < m; i++)
        redundant[i] = false;
    if (first >= m)
        return 0;
    int dm = rank >= 0 ? m - rank : deficiency(w, a, m, n, lda, tol);
    if (dm == 0)
        return 0;
    int dfirst = deficiency(w, a, first, n, lda, tol);
    if (dfirst < 0 || dm < 0)
        return -1;
    if (!bisect(w, a, n, lda, tol, first, dfirst, m, dm, redundant))
        return -1;
    int count = 0;
    for (int i = first; i < m; i++)
        count += redundant[i];
    return count;
}
