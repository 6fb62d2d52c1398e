/* limit.h - a motion that ends at a limit position: a driver pushes the mechanism where it cannot go. */
#ifndef MECHC_ANALYSIS_LIMIT_H
#define MECHC_ANALYSIS_LIMIT_H

#include "../../runtime/mechrt.h"
#include "../model/model.h"

#include <stdbool.h>
#include <stddef.h>

/* After a motion failed (run, sim), q the last state reached, at t: when
   the Jacobian there is nearly singular (sigma_min / sigma_max below
   ratio_max: LIMIT_STOPPED where the integration crept up to the limit,
   LIMIT_STEPPED a substep before it) along rows that include a driver,
   rewrites the failure's message (size bytes) to say so first:
   "t = T: the mechanism cannot reach the driven position: driver 'D'
   pushes it past a limit position, where the Jacobian loses rank (...,
   along rows ...); ...; where it stopped: " and the message it had,
   without its "t = T: ". True then; false, the message
   untouched, otherwise. */
bool limit_explain(const Model *m, const MechrtKernels *k, const double *q, double t,
                   double ratio_max, char *message, size_t size);

/* sim's last state, where its steps underflowed, is within about 1e-8 of
   the limit in time; run's last substep start (after its rank-revealing
   corrector, which already found the rank lost, failed) a substep before
   it, where the rank has dropped less. */
#define LIMIT_STOPPED 1e-4
#define LIMIT_STEPPED 0.1

#endif
