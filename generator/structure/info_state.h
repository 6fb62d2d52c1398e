/* info_state.h - `info --at` / `--state`: the motion followed to a time, the rank drop there and the directions it frees. */
#ifndef MECHC_INFO_STATE_H
#define MECHC_INFO_STATE_H

#include "../analysis/assemble.h"
#include "info.h"

/* Follows the motion of the holonomic rows (hrows, nh of them) from q,
   assembled at t = 0, to t1: 100 equal steps, each from a secant
   predictor corrected by minimum-norm Newton (dense with w, sparse QR
   without), halved down to 1/64 when Newton fails or corrects much more
   than the predictor moved (a jump to another branch). Minimum-norm
   Newton passes singular positions, where Newton with LU stops. The last
   FOLLOW_ORDER + 1 steps are 16 times shorter and the state at t1 is the
   cubic through them, not Newton's. q is the state at t1 on success (and
   q_near, t_near the last state reached by Newton before it), the last
   state reached otherwise; *steps counts the steps taken. */
bool info_follow(MechEval *me, MechrtSvd *w, const int *hrows, int nh, double t1, double *q,
                 const AnalysisOptions *opt, AssembleResult *res, int *steps, double *q_near,
                 double *t_near);

/* Rank of the holonomic rows (drivers included) at q, t, and which of them
   depend on the rows before them (red, nh): dense SVD with w, else
   SuiteSparseQR; tol < 0: the default relative tolerance. -1 on NaN. */
int info_holonomic_rank(MechEval *me, MechrtSvd *w, const double *q, double t, double tol,
                        bool *red);

/* The rank tolerance at a given state: sqrt(eps) sigma_max of the
   holonomic rows there. A state is known to about that (a singular one
   reached by Newton to sqrt(eps) at best, by extrapolation to a little
   better), and the singular values that vanish at an exactly singular
   state are as small as its distance from it, so the default
   max(m, n) eps sigma_max would count them. */
double info_state_tolerance(MechEval *me, MechrtSvd *w, const double *q, double t);

/* ||Phi||_inf of the holonomic rows at q, t. */
double info_residual(MechEval *me, const double *q, double t);

/* The state's part of the report, once rep holds the ranks at the state:
   the drop against ref_rank (the reference's rank, ref_red its redundant
   rows), the rows that became dependent, and the null-space directions of
   the holonomic rows at the state (SuiteSparseQR, the state's tolerance). */
void info_state_finish(MechEval *me, InfoReport *rep, int ref_rank, const bool *ref_red);

#endif
