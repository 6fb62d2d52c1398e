/* svd.c - singular values, numerical rank, pseudo-inverse and singular directions of a dense matrix, with GSL.
 *
 * The one SVD of mechc: `run` projects onto Phi = 0 with its minimum-norm
 * steps and names the rows and coordinates of a singular Jacobian with its
 * smallest singular vectors; `info` takes ranks, redundant rows, minimum-
 * norm assembly steps and row-space bases from it (generator/analysis).
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
 * it is the minimum-norm least-squares step and ignores the directions the
 * rows do not determine (Golub and Van Loan 5.5.4; Ben-Israel's Newton
 * method for underdetermined systems).
 *
 * The workspace is allocated once for the largest matrix; a decomposition
 * allocates nothing. GSL's error handler (abort by default) is switched off
 * around every GSL call: failures come back as false or NULL.
 */
#include "mechrt_host.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_vector.h>

struct MechrtSvd {
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

MechrtSvd *mechrt_svd_new(int max_m, int max_n)
{
    if (max_m < 0 || max_n < 0)
        return NULL;
    MechrtSvd *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    w->max_m = max_m;
    w->max_n = max_n;
    size_t p = (size_t)(max_m > max_n ? max_m : max_n);
    size_t k = (size_t)(max_m < max_n ? max_m : max_n);
    if (p == 0)
        p = 1;
    if (k == 0)
        k = 1;
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    w->a = gsl_matrix_alloc(p, k);
    w->v = gsl_matrix_alloc(k, k);
    w->s = gsl_vector_alloc(k);
    w->work = gsl_vector_alloc(k);
    gsl_set_error_handler(old);
    w->tmp = calloc(k, sizeof *w->tmp);
    if (!w->a || !w->v || !w->s || !w->work || !w->tmp) {
        mechrt_svd_free(w);
        return NULL;
    }
    return w;
}

void mechrt_svd_free(MechrtSvd *w)
{
    if (!w)
        return;
    if (w->a)
        gsl_matrix_free(w->a);
    if (w->v)
        gsl_matrix_free(w->v);
    if (w->s)
        gsl_vector_free(w->s);
    if (w->work)
        gsl_vector_free(w->work);
    free(w->tmp);
    free(w);
}

double mechrt_svd_default_tol(int m, int n, double sigma_max)
{
    return (double)(m > n ? m : n) * DBL_EPSILON * sigma_max;
}

bool mechrt_svd(MechrtSvd *w, const double *a, int m, int n, int lda, double tol,
                MechrtSvdResult *out)
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
    /* a failure here (no convergence, which finite input does not produce
       in practice) becomes a false return */
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
    w->k = k;
    out->tol = tol < 0 ? mechrt_svd_default_tol(m, n, out->sigma_max) : tol;
    out->rank = mechrt_svd_truncate(w, out->tol);
    return true;
}

int mechrt_svd_truncate(MechrtSvd *w, double tol)
{
    const double *sigma = w->s->data;
    int rank = 0;
    while (rank < w->k && sigma[rank] > tol)
        rank++;
    w->rank = rank;
    w->tol = tol;
    return rank;
}

/* Not transposed: A = U S V^T, x = V S^+ U^T b.
   Transposed:     A = V S U^T, x = U S^+ V^T b.
   "left" is the factor b is multiplied with (its rows are A's rows),
   "right" the one x is built from (its rows are A's columns). */
static const gsl_matrix *left_factor(const MechrtSvd *w) { return w->transposed ? w->v : w->a; }
static const gsl_matrix *right_factor(const MechrtSvd *w) { return w->transposed ? w->a : w->v; }

void mechrt_svd_pinv_solve(const MechrtSvd *w, const double *b, double *x)
{
    int r = w->rank;
    const gsl_matrix *left = left_factor(w), *right = right_factor(w);
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

double mechrt_svd_row_basis(const MechrtSvd *w, int j, int l)
{
    /* the row space is spanned by the right singular vectors of A */
    return gsl_matrix_get(right_factor(w), (size_t)j, (size_t)l);
}

void mechrt_svd_smallest(const MechrtSvd *w, double *row_w, double *col_w)
{
    if (w->k == 0)
        return;
    size_t c = (size_t)w->k - 1;
    const gsl_matrix *left = left_factor(w), *right = right_factor(w);
    for (int i = 0; i < w->m; i++)
        row_w[i] = fabs(gsl_matrix_get(left, (size_t)i, c));
    for (int j = 0; j < w->n; j++)
        col_w[j] = fabs(gsl_matrix_get(right, (size_t)j, c));
}

double mechrt_host_singular_direction(int m, int n, const double *a, double *row_w,
                                      double *col_w)
{
    if (m < 1 || n < 1 || !a)
        return -1;
    MechrtSvd *w = mechrt_svd_new(m, n);
    if (!w)
        return -1;
    MechrtSvdResult r;
    double ratio = -1;
    if (mechrt_svd(w, a, m, n, n, -1, &r)) {
        ratio = r.sigma_max > 0 ? r.sigma_min / r.sigma_max : 0;
        mechrt_svd_smallest(w, row_w, col_w);
    }
    mechrt_svd_free(w);
    return ratio;
}
