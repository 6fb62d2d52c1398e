/* sparse_qr.c - the minimum-norm Gauss-Newton step of the projection onto Phi = 0, by SuiteSparseQR.
 *
 * The sparse counterpart of host.c's min_norm_step (a truncated SVD of the
 * dense nh x nq Jacobian): with nh < nq holonomic rows the correction
 * Phi_q dq = -Phi is underdetermined, and the projection takes the
 * minimum-norm dq. As SuiteSparseQR_min2norm does (Davis, ACM TOMS 38(1),
 * 2011): a QR of Phi_q^T E = Q R, then dq = Q (R^T \ (E^T (-Phi))), the
 * entries of R^T \ .. beyond the rank zero. Rank: Heath's rule, a column
 * of Phi_q^T (a row of Phi_q) whose remaining 2-norm is at most
 * pivot_tol * (the largest row 2-norm, a lower bound of sigma_max) is
 * dropped, so consistent redundant rows are harmless, as the dense path's
 * truncated singular values are.
 *
 * The pattern is the kernels' (rows < nh of PREFIX_jac_row/col, the
 * velocity-level rows left out); Phi_q^T is laid out once as CSC (column i
 * is row i of Phi_q) with a map from the kernel's entries to its slots, and
 * the symbolic analysis (fill-reducing column order) is done once; each
 * step scatters the values and refactors numerically. SuiteSparseQR
 * allocates its factors per factorisation (its own rule; the sizes are
 * fixed by the symbolic analysis).
 */
#include "mechrt_host.h"

#include <SuiteSparseQR_C.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef SuiteSparse_long Long;

struct MechrtHostMinNorm {
    int nh, nq, nnz;            /* nnz: the kernel's entries, all rows */
    MechrtHostJacNz jnz;
    double *vals;               /* the kernel's nnz values */
    int *map;                   /* entry e -> slot in at, -1 for a velocity-level row */
    cholmod_common cc;
    cholmod_sparse *at;         /* Phi_q^T: nq x nh, CSC */
    cholmod_dense *b;           /* nh x 1 */
    SuiteSparseQR_C_factorization *qr;
};

void mechrt_host_minnorm_free(MechrtHostMinNorm *m)
{
    if (!m)
        return;
    if (m->qr)
        SuiteSparseQR_C_free(&m->qr, &m->cc);
    cholmod_l_free_sparse(&m->at, &m->cc);
    cholmod_l_free_dense(&m->b, &m->cc);
    cholmod_l_finish(&m->cc);
    free(m->vals), free(m->map);
    free(m);
}

/* Phi_q^T's CSC pattern and the map; false on a bad index or out of
   memory. The entries are taken in coordinate order (a counting sort), so
   row indices ascend within each column of Phi_q^T, as CHOLMOD wants. */
static bool minnorm_layout(MechrtHostMinNorm *m)
{
    const MechrtHostJacNz *j = &m->jnz;
    Long *p = m->at->p, *ix = m->at->i;
    int *cstart = calloc((size_t)m->nq + 2, sizeof *cstart);
    int *order = malloc(((size_t)m->nnz + 1) * sizeof *order);
    Long *next = malloc(((size_t)m->nh + 1) * sizeof *next);
    bool ok = cstart && order && next;
    for (int e = 0; ok && e < m->nnz; e++) {
        ok = j->jac.row[e] >= 0 && j->jac.col[e] >= 0 && j->jac.col[e] < m->nq;
        if (ok && j->jac.row[e] < m->nh)
            p[j->jac.row[e] + 1]++;
        if (ok)
            cstart[j->jac.col[e] + 2]++;
    }
    for (int c = 0; ok && c < m->nq; c++)
        cstart[c + 2] += cstart[c + 1];
    for (int e = 0; ok && e < m->nnz; e++)
        order[cstart[j->jac.col[e] + 1]++] = e;
    for (int i = 0; ok && i < m->nh; i++) {
        p[i + 1] += p[i];
        next[i] = p[i];
    }
    for (int k = 0; ok && k < m->nnz; k++) {
        int e = order[k];
        m->map[e] = -1;
        if (j->jac.row[e] >= m->nh)
            continue;
        Long slot = next[j->jac.row[e]]++;
        ix[slot] = j->jac.col[e];
        m->map[e] = (int)slot;
    }
    free(cstart), free(order), free(next);
    return ok;
}

MechrtHostMinNorm *mechrt_host_minnorm_new(int nh, int nq, const MechrtHostJacNz *jnz)
{
    if (nh < 1 || nq < nh || !jnz || jnz->jac.nnz < 0 || !jnz->jac.jac_nz
        || (jnz->jac.nnz > 0 && (!jnz->jac.row || !jnz->jac.col)))
        return NULL;
    MechrtHostMinNorm *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->nh = nh;
    m->nq = nq;
    m->nnz = jnz->jac.nnz;
    m->jnz = *jnz;
    cholmod_l_start(&m->cc);
    m->cc.print = 0;
    m->cc.error_handler = NULL;
    m->vals = calloc((size_t)jnz->jac.nnz + 1, sizeof *m->vals);
    m->map = malloc(((size_t)jnz->jac.nnz + 1) * sizeof *m->map);
    m->at = cholmod_l_allocate_sparse((size_t)nq, (size_t)nh, (size_t)jnz->jac.nnz + 1, 1, 1, 0,
                                      CHOLMOD_REAL, &m->cc);
    m->b = cholmod_l_allocate_dense((size_t)nh, 1, (size_t)nh, CHOLMOD_REAL, &m->cc);
    if (!m->vals || !m->map || !m->at || !m->b || !minnorm_layout(m)) {
        mechrt_host_minnorm_free(m);
        return NULL;
    }
    m->qr = SuiteSparseQR_C_symbolic(SPQR_ORDERING_DEFAULT, 1, m->at, &m->cc);
    if (!m->qr) {
        mechrt_host_minnorm_free(m);
        return NULL;
    }
    return m;
}

MechrtStatus mechrt_host_minnorm_step(MechrtHostMinNorm *m, const double *q, double t,
                                      const double *phi, double pivot_tol, double *dq)
{
    m->jnz.jac.jac_nz(m->jnz.jac.ctx, q, t, m->vals);
    double *x = m->at->x, *rownorm2 = m->b->x, big = 0;
    memset(rownorm2, 0, (size_t)m->nh * sizeof *rownorm2);
    for (int e = 0; e < m->nnz; e++) {
        if (m->map[e] < 0)
            continue;
        double v = m->vals[e];
        if (!isfinite(v))
            return MECHRT_ENOTFINITE;
        x[m->map[e]] = v;
        rownorm2[m->jnz.jac.row[e]] += v * v;
    }
    for (int i = 0; i < m->nh; i++)
        big = rownorm2[i] > big ? rownorm2[i] : big;
    if (!(big > 0))
        return MECHRT_ESING;    /* Phi_q = 0: no direction to move in */
    if (!SuiteSparseQR_C_numeric(pivot_tol * sqrt(big), m->at, m->qr, &m->cc))
        return MECHRT_EINVAL;   /* out of memory */
    double *b = m->b->x;
    for (int i = 0; i < m->nh; i++)
        b[i] = -phi[i];
    cholmod_dense *w = SuiteSparseQR_C_solve(SPQR_RTX_EQUALS_ETB, m->qr, m->b, &m->cc);
    cholmod_dense *y = w ? SuiteSparseQR_C_qmult(SPQR_QX, m->qr, w, &m->cc) : NULL;
    MechrtStatus st = y ? MECHRT_OK : MECHRT_EINVAL;
    if (y) {
        const double *yx = y->x;
        for (int j = 0; j < m->nq; j++) {
            dq[j] = yx[j];
            if (!isfinite(dq[j]))
                st = MECHRT_ENOTFINITE;
        }
    }
    cholmod_l_free_dense(&w, &m->cc);
    cholmod_l_free_dense(&y, &m->cc);
    return st;
}
