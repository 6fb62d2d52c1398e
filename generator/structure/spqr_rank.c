/* spqr_rank.c - rank, dependent rows and a null-space basis of a sparse Jacobian, by SuiteSparseQR.
 *
 * `info` at scale (beyond --linear auto's 100 coordinates, or --linear
 * sparse) factors the Jacobian with SuiteSparseQR, the multifrontal sparse
 * QR (Davis, ACM TOMS 38(1), 2011). Its rank detection is Heath's (1982):
 * while a column is eliminated, if what is left of it has 2-norm at or
 * below tol it is "dead", gets no pivot row, and R comes out "squeezed"
 * (upper trapezoidal with steps). With the column order fixed
 * (SPQR_ORDERING_FIXED, no fill-reducing permutation) a dead column is one
 * that lies within tol of the span of the columns before it, which is how
 * `info` defines a redundant row when the columns are the Jacobian's rows
 * (a QR of Phi_q^T): the first rows of a file are the ones kept, as with
 * the dense SVD. Declaration order keeps chains and loops banded, so the
 * fixed order costs little fill.
 *
 * The null space comes from a QR of Phi_q itself: a dead column j (a
 * coordinate the ones before it already determine to first order) gives
 * the vector x_j = 1, x_dead = 0 elsewhere, R11 x_live = -R(:, j).
 */
#include "spqr_rank.h"

#include "../base/arena.h"

#include <SuiteSparseQR_C.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef SuiteSparse_long Long;

/* A^T as a CHOLMOD matrix: A's rows are its columns (CSR of A is CSC of
   A^T); NULL on NaN or Inf. */
static cholmod_sparse *transpose_of(const SpqrRows *a, cholmod_common *cc)
{
    size_t nnz = (size_t)a->start[a->m];
    cholmod_sparse *t = cholmod_l_allocate_sparse((size_t)a->n, (size_t)a->m, nnz + 1, 1, 1, 0,
                                                  CHOLMOD_REAL, cc);
    if (!t)
        return NULL;
    Long *p = t->p, *ix = t->i;
    double *x = t->x;
    for (int i = 0; i <= a->m; i++)
        p[i] = a->start[i];
    for (size_t e = 0; e < nnz; e++) {
        if (!isfinite(a->vals[e])) {
            cholmod_l_free_sparse(&t, cc);
            return NULL;
        }
        ix[e] = a->cols[e];
        x[e] = a->vals[e];
    }
    return t;
}

/* SPQR in the given column order: R squeezed and rank-sized (econ = 0). */
static Long factor_fixed(cholmod_sparse *a, double tol, cholmod_sparse **r, Long **e,
                         cholmod_common *cc)
{
    return SuiteSparseQR_C(SPQR_ORDERING_FIXED, tol, 0, 0, a, NULL, NULL, NULL, NULL, r, e, NULL,
                           NULL, NULL, cc);
}

/* For each column c of the squeezed R (rank rows), its pivot row, or -1
   when dead: a live column has an entry in the row after the pivots of the
   live columns before it. */
static void pivots_of(const cholmod_sparse *r, Long *pivot)
{
    const Long *p = r->p, *ix = r->i;
    Long k = 0;
    for (size_t c = 0; c < r->ncol; c++) {
        pivot[c] = -1;
        for (Long q = p[c]; q < p[c + 1]; q++)
            if (ix[q] == k && k < (Long)r->nrow) {
                pivot[c] = k++;
                break;
            }
    }
}

static void start_common(cholmod_common *cc)
{
    cholmod_l_start(cc);
    cc->print = 0;
    cc->error_handler = NULL;
}

int spqr_dependent_rows(const SpqrRows *a, double tol, bool *dependent, int upto, int *rank_upto)
{
    cholmod_common cc;
    start_common(&cc);
    cholmod_sparse *t = transpose_of(a, &cc), *r = NULL;
    Long *e = NULL;
    int rank = -1;
    if (t && a->m == 0) {
        rank = 0;
    } else if (t && factor_fixed(t, tol, &r, &e, &cc) >= 0 && r) {
        Long *pivot = xmalloc(((size_t)a->m + 1) * sizeof *pivot);
        pivots_of(r, pivot);
        rank = 0;
        for (int c = 0; c < a->m; c++) {
            int row = e ? (int)e[c] : c;
            dependent[row] = pivot[c] < 0;
            rank += pivot[c] >= 0;
        }
        free(pivot);
    }
    if (rank_upto) {
        *rank_upto = rank < 0 ? -1 : 0;
        for (int i = 0; rank >= 0 && i < upto; i++)
            *rank_upto += !dependent[i];
    }
    cholmod_l_free_sparse(&t, &cc);
    cholmod_l_free_sparse(&r, &cc);
    if (e)
        cholmod_l_free((size_t)a->m, sizeof *e, e, &cc);
    cholmod_l_finish(&cc);
    return rank;
}

/* x (n, R's column order) = the null vector of dead column c: R11 x_live
   = -R(:, c) by back substitution over the live columns (livecol[k]: the
   column with pivot row k). b: rank scratch. */
static void null_vector(const cholmod_sparse *r, const Long *livecol, Long rank, size_t c,
                        double *b, double *x)
{
    const Long *p = r->p, *ix = r->i;
    const double *rx = r->x;
    memset(b, 0, (size_t)rank * sizeof *b);
    for (Long q = p[c]; q < p[c + 1]; q++)
        b[ix[q]] = -rx[q];
    memset(x, 0, r->ncol * sizeof *x);
    x[c] = 1.0;
    for (Long k = rank - 1; k >= 0; k--) {
        Long col = livecol[k];
        double diag = 0.0;
        for (Long q = p[col]; q < p[col + 1]; q++)
            if (ix[q] == k)
                diag = rx[q];
        double v = diag != 0.0 ? b[k] / diag : 0.0;
        x[col] = v;
        for (Long q = p[col]; q < p[col + 1]; q++)
            if (ix[q] < k)
                b[ix[q]] -= rx[q] * v;
    }
}

int spqr_null_basis(const SpqrRows *a, double tol, int max_vectors, double *basis, int *free_coords)
{
    cholmod_common cc;
    start_common(&cc);
    cholmod_sparse *t = transpose_of(a, &cc), *at = NULL, *r = NULL;
    Long *e = NULL;
    int nnull = -1;
    if (t)
        at = cholmod_l_transpose(t, 1, &cc);
    if (at && factor_fixed(at, tol, &r, &e, &cc) >= 0 && r) {
        size_t n = (size_t)a->n;
        Long *pivot = xmalloc((n + 1) * sizeof *pivot), *livecol = xmalloc((n + 1) * sizeof *livecol);
        double *b = xmalloc((n + 1) * sizeof *b), *x = xmalloc((n + 1) * sizeof *x);
        pivots_of(r, pivot);
        Long rank = 0;
        for (size_t c = 0; c < n; c++)
            if (pivot[c] >= 0)
                livecol[rank++] = (Long)c;
        nnull = 0;
        for (size_t c = 0; c < n; c++) {
            if (pivot[c] >= 0)
                continue;
            if (nnull < max_vectors) {
                null_vector(r, livecol, rank, c, b, x);
                double *out = basis + (size_t)nnull * n;
                for (size_t j = 0; j < n; j++)
                    out[e ? e[j] : (Long)j] = x[j];
                free_coords[nnull] = (int)(e ? e[c] : (Long)c);
            }
            nnull++;
        }
        free(pivot), free(livecol), free(b), free(x);
    }
    cholmod_l_free_sparse(&t, &cc);
    cholmod_l_free_sparse(&at, &cc);
    cholmod_l_free_sparse(&r, &cc);
    if (e)
        cholmod_l_free((size_t)a->n, sizeof *e, e, &cc);
    cholmod_l_finish(&cc);
    return nnull;
}
