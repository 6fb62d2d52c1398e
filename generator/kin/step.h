/* step.h - one predictor-corrector step of a run, checked, and redone through singular positions by the rank corrector. */
#ifndef MECHC_KIN_STEP_H
#define MECHC_KIN_STEP_H

#include "run_state.h"

/* A holonomic step is quiet (trusted) when Newton took at most
   RUN_QUIET_ITER iterations and moved every coordinate away from the
   prediction by at most RUN_QUIET_SHARE times the motion the predictor gave
   it, |h qd| + h^2/2 |qdd|, plus tol_dq. On the branch the correction is the
   predictor's O(h^3) error, a small share of the O(h) motion; a jump to
   another branch or turn corrects by a link length or a radian. */
#define RUN_QUIET_ITER 3
#define RUN_QUIET_SHARE 0.05

/* Why a step was not quiet: the coordinate corrected most beyond its share
   (-1: none, too many iterations only). */
typedef struct StepCheck {
    int coord;
    double correction, motion;
    int iterations;
} StepCheck;

/* The runtime's step from t to t + h on the run's linear algebra. */
MechrtStatus run_step(Run *r, double t, double h, MechrtReport *rep);

/* One predictor-corrector step from t to t + h, its start kept in sq,
   sqd, sqdd; *quiet says whether it passed the check. */
MechrtStatus run_checked_step(Run *r, double t, double h, MechrtReport *rep, bool *quiet,
                              StepCheck *chk);

#endif
