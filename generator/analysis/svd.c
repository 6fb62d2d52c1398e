/* svd.c - singular values, numerical rank and pseudo-inverse of a dense matrix, with GSL.
 *
 * A (m x n, row-major) is copied into a tall GSL matrix, A itself when
 * m >= n, A^T otherwise, and factored by gsl_linalg_SV_decomp (one-sided
 * Householder bidiagonalisation, then implicit-shift QR: Golub and Reinsch
 * 1970, Golub and Van Loan, Matrix Computations, 4th ed., 8.6):
 *     tall = U S V^T,  U: p x k,  S = diag(sigma_1 >= ... >= sigma_k >= 0),
 *     V: k x k,  k = min(m, n), p = max(m, n).
 * The numerical rank is the number of sigma_i above a tolerance, by default
 * max(m, n) eps sigma_1 (LAPACK's xGELSS and Matlab's rank use the same rule).
 * The pseudo-inverse keeps the same singular values, so a Newton step through
 * it ignores the directions the rows do not determine.
 *
 * Redundant rows use the interlacing of singular values (Golub and Van Loan
 * 8.6.1): appending a row to a matrix never lowers any singular value and
 * raises the count above a fixed tolerance by at most one, so with that
 * tolerance held fixed the deficiency def(k) = k - rank(first k rows) steps
 * up by 0 or 1 per row, and the rows where it steps are found by bisection.
 */
#include "analysis.h"

#include "../base/arena.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct SvdWork {
    int max_m, max_n;
    gsl_matrix *a;          /* p x k tall copy; U after the decomposition */
    gsl_matrix *v;          /* k x k */
    gsl_vector *s, *work;   /* k */
    double *tmp;            /* k: S^+ U^T b */
    /* the last decomposition */
    int m, n, k, rank;
    bool transposed;        /* a holds A^T */
    double tol;
};

SvdWork *svd_work_new(int max_m, int max_n)
{
    SvdWork *w = xcalloc(1, sizeof *w);
    w->max_m = max_m;
    w->max_n = max_n;
    size_t p = (size_t)(max_m > max_n ? max_m : max_n);
    size_t k = (size_t)(max_m < max_n ? max_m : max_n);
    if (p == 0)
        p = 1;
    if (k == 0)
        k = 1;
    w->a = gsl_matrix_alloc(p, k);
    w->v = gsl_matrix_alloc(k, k);
    w->s = gsl_vector_alloc(k);
    w->work = gsl_vector_alloc(k);
    w->tmp = xcalloc(k, sizeof *w->tmp);
    if (!w->a || !w->v || !w->s || !w->work) {
        fprintf(stderr, "mechc: out of memory (SVD workspace %zu x %zu)\n", p, k);
        abort();
    }
    return w;
}

void svd_work_free(SvdWork *w)
{
    if (!w)
        return;
    gsl_matrix_free(w->a);
    gsl_matrix_free(w->v);
    gsl_vector_free(w->s);
    gsl_vector_free(w->work);
    free(w->tmp);
    free(w);
}

double svd_default_tol(int m, int n, double sigma_max)
{
    return (double)(m > n ? m : n) * DBL_EPSILON * sigma_max;
}

bool analysis_svd(SvdWork *w, const double *a, int m, int n, int lda, double tol,
                  SvdResult *out)
{
    memset(out, 0, sizeof *out);
    out->m = m;
    out->n = n;
    out->rank = -1;
    w->m = m;
    w->n = n;
    w->k = 0;
    w->rank = 0;
    if (m < 0 || n < 0 || m > w->max_m || n > w->max_n)
        return false;
    for (int i = 0; i < m; i++)
        for (int j = 0; j < n; j++)
            if (!isfinite(a[(size_t)i * (size_t)lda + (size_t)j]))
                return false;
    int k = m < n ? m : n, p = m < n ? n : m;
    out->k = k;
    out->rank = 0;
    out->cond = k ? INFINITY : 0.0;
    out->sigma = w->s->data;
    if (k == 0) {
        w->tol = out->tol = tol < 0 ? 0.0 : tol;
        return true;
    }
    w->transposed = m < n;
    gsl_matrix_view tall = gsl_matrix_submatrix(w->a, 0, 0, (size_t)p, (size_t)k);
    gsl_matrix_view v = gsl_matrix_submatrix(w->v, 0, 0, (size_t)k, (size_t)k);
    gsl_vector_view s = gsl_vector_subvector(w->s, 0, (size_t)k);
    gsl_vector_view work = gsl_vector_subvector(w->work, 0, (size_t)k);
    for (int i = 0; i < m; i++)
        for (int j = 0; j < n; j++) {
            double x = a[(size_t)i * (size_t)lda + (size_t)j];
            if (w->transposed)
                gsl_matrix_set(&tall.matrix, (size_t)j, (size_t)i, x);
            else
                gsl_matrix_set(&tall.matrix, (size_t)i, (size_t)j, x);
        }
    /* GSL's default handler aborts; a failure here (no convergence, which
       finite input does not produce in practice) becomes a false return. */
    gsl_error_handler_t *saved = gsl_set_error_handler_off();
    int status = gsl_linalg_SV_decomp(&tall.matrix, &v.matrix, &s.vector, &work.vector);
    gsl_set_error_handler(saved);
    if (status != GSL_SUCCESS) {
        out->rank = -1;
        return false;
    }
    const double *sigma = w->s->data;
    out->sigma_max = sigma[0];
    out->sigma_min = sigma[k - 1];
    out->cond = out->sigma_min > 0 ? out->sigma_max / out->sigma_min : INFINITY;
    out->tol = tol < 0 ? svd_default_tol(m, n, out->sigma_max) : tol;
    int rank = 0;
    while (rank < k && sigma[rank] > out->tol)
        rank++;
    out->rank = rank;
    w->k = k;
    w->rank = rank;
    w->tol = out->tol;
    return true;
}

/* Not transposed: A = U S V^T, x = V S^+ U^T b.
   Transposed:     A = V S U^T, x = U S^+ V^T b.
   "left" is the factor b is multiplied with, "right" the one x is built from. */
void svd_pinv_solve(const SvdWork *w, const double *b, double *x)
{
    int r = w->rank;
    const gsl_matrix *left = w->transposed ? w->v : w->a;
    const gsl_matrix *right = w->transposed ? w->a : w->v;
    int m = w->m, n = w->n;
    for (int l = 0; l < r; l++) {
        double sum = 0.0;
        for (int i = 0; i < m; i++)
            sum += gsl_matrix_get(left, (size_t)i, (size_t)l) * b[i];
        w->tmp[l] = sum / gsl_vector_get(w->s, (size_t)l);
    }
    for (int j = 0; j < n; j++) {
        double sum = 0.0;
        for (int l = 0; l < r; l++)
            sum += gsl_matrix_get(right, (size_t)j, (size_t)l) * w->tmp[l];
        x[j] = sum;
    }
}

double svd_row_basis(const SvdWork *w, int j, int l)
{
    /* not transposed: A = U S V^T, the row space is V's columns;
       transposed: A = V S U^T (U in w->a), the row space is U's columns */
    return gsl_matrix_get(w->transposed ? w->a : w->v, (size_t)j, (size_t)l);
}

/* Deficiency of the first k rows: k - rank, -1 on NaN/Inf. */
static int deficiency(SvdWork *w, const double *a, int k, int n, int lda, double tol)
{
    SvdResult r;
    if (!analysis_svd(w, a, k, n, lda, tol, &r))
        return -1;
    return k - r.rank;
}

/* Marks the rows in [lo, hi) where the deficiency steps, given def(lo), def(hi). */
static bool bisect(SvdWork *w, const double *a, int n, int lda, double tol,
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

int svd_redundant_rows(SvdWork *w, const double *a, int m, int n, int lda, double tol,
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
