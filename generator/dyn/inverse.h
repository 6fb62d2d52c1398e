/* inverse.h - inverse dynamics at a state of a run: the multipliers of Phi_q^T lambda = Q - M qdd. */
#ifndef MECHC_DYN_INVERSE_H
#define MECHC_DYN_INVERSE_H

#include <stdbool.h>
#include <stddef.h>

#include "../../runtime/mechrt.h"

/* The workspace and results of inverse dynamics over a run (`run --forces`). */
typedef struct Inverse {
    int nq, nr;
    double *work;           /* mechrt_dynamics_workspace_size(nq, nr) */
    size_t lwork;
    double rank_tol;        /* mechrt_dyn_default_options()' */
    double *lambda;         /* nr: the multipliers of the last state */
    /* over the rank-revealing solves: the largest part of Q - M qdd the
       rows could not carry (above round-off only where the Jacobian lost
       rank), and the most rows found dependent */
    double residual;
    int redundant;
} Inverse;

/* Allocates the workspace for nq coordinates and nr rows (nr == nq for a run). */
void inverse_init(Inverse *inv, int nq, int nr);
void inverse_free(Inverse *inv);

/* lambda at (q, qd, qdd, t) into inv->lambda: the square LU where Phi_q is
   regular, else the rank-revealing mechrt_inverse_dynamics (minimum-norm
   where rows are dependent). Its status (MECHRT_ENOTFINITE: NaN in M or Q). */
MechrtStatus inverse_solve(Inverse *inv, const MechrtKernels *k, const double *q, const double *qd,
                           const double *qdd, double t);

#endif
