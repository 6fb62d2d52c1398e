/* assemble.h - minimum-norm Newton assembly on any set of holonomic rows, dense or sparse. */
#ifndef MECHC_ASSEMBLE_H
#define MECHC_ASSEMBLE_H

#include "../engine/mech_eval.h"
#include "options.h"
#include "svd.h"

#include <stdbool.h>

typedef struct AssembleResult {
    bool converged;
    int iterations;
    double residual;        /* ||Phi_rows||_inf at the returned q */
    double step;            /* ||dq||_inf of the last step, -1 if none */
    int worst_row;          /* model row with the largest |Phi|, -1 if none */
    int rank;               /* rank of the rows' Jacobian at the last step, -1 if none */
} AssembleResult;

/* Minimum-norm Newton on the holonomic rows of kernels k listed in rows[]
   (row indices < k->nh; NULL: the first nrows), at time t, from q
   (updated in place): dq = -pinv(Phi_q) Phi, with step halving when the
   residual grows. Works for fewer rows than coordinates (the step nearest
   to q) and for redundant rows (singular values at or below the rank
   tolerance are dropped). k: an engine's (run, sim, check) or the
   graph's (info, mech_eval_kernels); needs phi and jac. w must hold
   nrows x nq; NULL: one of its own. res->worst_row is a kernel row. */
bool assemble_min_norm(const MechrtKernels *k, const int *rows, int nrows, double t, double *q,
                       const AnalysisOptions *opt, MechrtSvd *w, AssembleResult *res);

/* The same beyond the dense limit, on the first nrows holonomic rows, with
   the sparse QR of Phi_q^T (sparse.c): dq = Phi_q^T y, Phi_q Phi_q^T y = -Phi
   by the seminormal equations; rows that depend on earlier ones are left
   out of the step. */
bool assemble_sparse(MechEval *me, int nrows, double t, double *q,
                     const AnalysisOptions *opt, AssembleResult *res);

/* Iterations without 1 % progress after which an assembly from rough
   initial values gives up an attempt and restarts (AnalysisOptions.stall_iter
   for run, check and info). */
#define ASSEMBLE_ROUGH_STALL 8

/* assemble_min_norm on all of k's holonomic rows from q, restarted from
   jittered guesses (a fixed seed) while it stalls (give opt->stall_iter >
   0): what assembles a mechanism from rough initial values, all angles 0
   included. Coordinates the rows
   do not depend on keep their values. res->iterations counts every
   attempt's; on failure q is the attempt with the smallest residual. */
bool assemble_restarting(const MechrtKernels *k, double t, double *q,
                         const AnalysisOptions *opt, AssembleResult *res);

#endif
