/* sparse.c - numerical rank and redundant rows of a large sparse Jacobian, row by row with Givens rotations.
 *
 * Beyond the dense-SVD limit `info` factors Phi_q = Q R one row at a time
 * (row-wise sparse orthogonal factorisation: George and Heath 1980, Linear
 * Algebra Appl. 34; Bjoerck, Numerical Methods for Least Squares Problems,
 * 1996, 6.6). R is kept as one dense segment per pivot column (an envelope:
 * fill stays inside the span of the rows that meet there, which the
 * declaration order keeps narrow for chains and loops). An incoming row w
 * is rotated against R row j for each of its nonzero columns j in turn; if a
 * column has no R row yet, w becomes that R row (the row raised the rank),
 * unless the entry is at or below the tolerance, in which case it is
 * rounding and dropped. A row that is eliminated entirely lies within the
 * span of the rows before it: it is redundant, which is the definition of
 * the dense path, decided by distance instead of by singular values.
 */
#include "sparse.h"

#include "../base/rng.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct SparseRank {
    int nq;
    double tol;
    int rank;
    double **seg;       /* per pivot column j: R row j on columns j .. j + len[j] - 1, or NULL */
    int *len;
    double *w;          /* the incoming row, dense, zero outside [lo, hi) */
    size_t fill, fill_max;
};

SparseRank *sparse_rank_new(int nq, double tol, size_t fill_max)
{
    SparseRank *s = xcalloc(1, sizeof *s);
    s->nq = nq;
    s->tol = tol;
    s->fill_max = fill_max;
    s->seg = xcalloc((size_t)nq + 1, sizeof *s->seg);
    s->len = xcalloc((size_t)nq + 1, sizeof *s->len);
    s->w = xcalloc((size_t)nq + 1, sizeof *s->w);
    return s;
}

void sparse_rank_free(SparseRank *s)
{
    if (!s)
        return;
    for (int j = 0; j < s->nq; j++)
        free(s->seg[j]);
    free(s->seg), free(s->len), free(s->w);
    free(s);
}

int sparse_rank_of(const SparseRank *s) { return s->rank; }

int sparse_rank_add(SparseRank *s, const int *cols, const double *vals, int n)
{
    double *w = s->w;
    int lo = s->nq, hi = 0;
    for (int k = 0; k < n; k++) {
        if (vals[k] == 0.0)
            continue;
        if (!isfinite(vals[k]))
            return -1;
        w[cols[k]] = vals[k];
        if (cols[k] < lo) lo = cols[k];
        if (cols[k] + 1 > hi) hi = cols[k] + 1;
    }
    int result = 0;
    for (int j = lo; j < hi; j++) {
        double x = w[j];
        if (x == 0.0)
            continue;
        double *r = s->seg[j];
        if (!r) {
            if (fabs(x) <= s->tol) {
                w[j] = 0.0;         /* rounding left by earlier rotations */
                continue;
            }
            int len = hi - j;
            if (s->fill + (size_t)len > s->fill_max) {
                result = -2;
                break;
            }
            s->seg[j] = xmalloc((size_t)len * sizeof *r);
            memcpy(s->seg[j], w + j, (size_t)len * sizeof *r);
            s->len[j] = len;
            s->fill += (size_t)len;
            s->rank++;
            result = 1;
            break;
        }
        int end = j + s->len[j];
        if (end < hi) {             /* the R row grows to cover w */
            int len = hi - j;
            if (s->fill + (size_t)(hi - end) > s->fill_max) {
                result = -2;
                break;
            }
            r = s->seg[j] = xrealloc(r, (size_t)len, sizeof *r);
            memset(r + s->len[j], 0, (size_t)(hi - end) * sizeof *r);
            s->fill += (size_t)(hi - end);
            s->len[j] = len;
            end = hi;
        } else {
            hi = end;               /* w fills in up to the R row's end */
        }
        /* rotate [r; w] so that w[j] becomes 0 */
        double a = r[0], h = hypot(a, x), c = a / h, sn = x / h;
        for (int k = j; k < end; k++) {
            double rk = r[k - j], wk = w[k];
            r[k - j] = c * rk + sn * wk;
            w[k] = -sn * rk + c * wk;
        }
        w[j] = 0.0;
    }
    for (int k = lo; k < hi && k < s->nq; k++)
        w[k] = 0.0;
    return result;
}

/* sigma_max of the sparse rows by power iteration on J^T J (a lower bound,
   within a few per cent after 50 steps for the matrices met here). */
double sparse_rank_sigma_max(const Kinematics *kin, const double *vals, const int *rows,
                             int nrows, unsigned seed)
{
    int nq = kin->model->nq;
    double *x = xmalloc((size_t)nq * sizeof *x), *y = xcalloc((size_t)nq, sizeof *y);
    uint64_t st = seed * 2654435761u + 7;
    for (int i = 0; i < nq; i++) {
        x[i] = rng_unit(&st) + 0.5;
    }
    double sigma = 0.0;
    for (int it = 0; it < 50; it++) {
        double nx = 0.0;
        for (int i = 0; i < nq; i++)
            nx += x[i] * x[i];
        nx = sqrt(nx);
        if (nx == 0.0)
            break;
        for (int i = 0; i < nq; i++) {
            x[i] /= nx;
            y[i] = 0.0;
        }
        double ny = 0.0;
        for (int k = 0; k < nrows; k++) {      /* y = J^T (J x), ||J x||^2 */
            int r = rows[k];
            double jx = 0.0;
            for (int e = kin->row_start[r]; e < kin->row_start[r + 1]; e++)
                jx += vals[e] * x[kin->jac[e].col];
            ny += jx * jx;
            for (int e = kin->row_start[r]; e < kin->row_start[r + 1]; e++)
                y[kin->jac[e].col] += vals[e] * jx;
        }
        sigma = sqrt(ny);
        double *t = x;
        x = y;
        y = t;
    }
    free(x), free(y);
    return sigma;
}

/* Solves R^T R y = b in place (b becomes y): the seminormal equations of
   the minimum-norm step (assemble.c). A row of J that depends on the rows
   before it has no pivot: it is left out (y_j = 0), which is the factor of
   J without that row. */
void sparse_rank_seminormal_solve(const SparseRank *s, int m, double *b)
{
    for (int j = 0; j < m; j++) {           /* R^T z = b, forward */
        const double *r = s->seg[j];
        if (!r) {
            b[j] = 0.0;
            continue;
        }
        b[j] /= r[0];
        for (int k = 1; k < s->len[j]; k++)
            b[j + k] -= r[k] * b[j];
    }
    for (int j = m - 1; j >= 0; j--) {      /* R y = z, backward */
        const double *r = s->seg[j];
        if (!r)
            continue;
        double sum = b[j];
        for (int k = 1; k < s->len[j]; k++)
            sum -= r[k] * b[j + k];
        b[j] = sum / r[0];
    }
}
