/* fold.h - near a singular position: the accelerations of the rows a step leaves out, held over the step. */
#ifndef MECHC_DYN_FOLD_H
#define MECHC_DYN_FOLD_H

#include "sim_state.h"

/* At the settled state y (t), with the rows of the next step chosen: where
   rows are left out that are not dependent to the runtime's rank_tol (a
   singular position near, not redundant rows), s->fold = qdd with every
   row minus qdd with the step's rows, both solved there, and s->fold_on.
   False with the message set when a solve fails. */
bool sim_fold_prepare(Sim *s, const double *y, double t);

/* qdd += s->fold while it is on (a right side with rows left out). */
void sim_fold_apply(const Sim *s, double *qdd);

#endif
