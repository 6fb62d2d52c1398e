/* inverse.c - inverse dynamics at a state of a run: the multipliers of Phi_q^T lambda = Q - M qdd.
 *
 * At every state of `run --forces`, lambda from Phi_q^T lambda = Q(q, qd, t)
 * - M(q) qdd: the square LU first (a run has one row per coordinate), the
 * runtime's rank-revealing mechrt_inverse_dynamics where that LU finds the
 * Jacobian singular.
 */
#include "inverse.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void inverse_init(Inverse *inv, int nq, int nr)
{
    *inv = (Inverse){.nq = nq, .nr = nr};
    inv->rank_tol = mechrt_dyn_default_options().rank_tol;
    inv->lwork = mechrt_dynamics_workspace_size(nq, nr);
    inv->work = xcalloc(inv->lwork + 1, sizeof *inv->work);
    inv->lambda = xcalloc((size_t)nr + 1, sizeof *inv->lambda);
}

void inverse_free(Inverse *inv)
{
    free(inv->work), free(inv->lambda);
    inv->work = inv->lambda = NULL;
}

/* A run has one row per coordinate, so where Phi_q is regular lambda is
   the solution of the square system Phi_q^T lambda = Q - M qdd: one LU
   with partial pivoting (lu.c) and a transposed solve, a third of the
   complete-pivoting elimination's work. False when a pivot is below the
   dynamics' rank tolerance (a singular position, where this would give
   lambda to few digits) or a value is not finite: then the
   rank-revealing mechrt_inverse_dynamics decides. Workspace: work's first
   nq*nq + nq*nq + 2 nq entries (M, the LU, the pivots, Q). */
static bool inverse_square(Inverse *inv, const MechrtKernels *k, const double *q,
                           const double *qd, const double *qdd, double t)
{
    size_t n = (size_t)inv->nq;
    double *mass = inv->work, *lu = mass + n * n, *piv = lu + n * n, *rhs = piv + n;
    k->mass(k->ctx, q, mass);
    k->force(k->ctx, q, qd, t, rhs);
    k->jac(k->ctx, q, t, lu);
    if (mechrt_lu_factor(inv->nq, lu, inv->nq, piv, inv->rank_tol, NULL) != MECHRT_OK)
        return false;
    for (size_t i = 0; i < n; i++) {
        double s = rhs[i];
        const double *mi = mass + i * n;
        for (size_t j = 0; j < n; j++)
            s -= mi[j] * qdd[j];
        rhs[i] = s;
    }
    mechrt_lu_solve_t(inv->nq, lu, inv->nq, piv, rhs);
    bool finite = true;
    for (size_t i = 0; i < n; i++)
        finite = finite && isfinite(rhs[i]);
    if (finite)
        memcpy(inv->lambda, rhs, n * sizeof *rhs);
    return finite;
}

MechrtStatus inverse_solve(Inverse *inv, const MechrtKernels *k, const double *q, const double *qd,
                           const double *qdd, double t)
{
    if (inverse_square(inv, k, q, qd, qdd, t))
        return MECHRT_OK;
    MechrtDynReport rep;
    MechrtStatus st = mechrt_inverse_dynamics(k, NULL, q, qd, qdd, t, inv->lambda, inv->work,
                                              inv->lwork, &rep);
    if (rep.residual > inv->residual)
        inv->residual = rep.residual;
    if (rep.redundant > inv->redundant)
        inv->redundant = rep.redundant;
    return st;
}
