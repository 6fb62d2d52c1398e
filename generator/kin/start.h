/* start.h - a run's start at t0: the assembly with the run's Newton, its failures, the note on how far it moved. */
#ifndef MECHC_KIN_START_H
#define MECHC_KIN_START_H

#include "run_state.h"

#include "../analysis/assemble_t0.h"

/* Whether a dense nr x nq Jacobian would be beyond RunOptions.max_dense_entries. */
bool run_dense_too_large(const Model *m, const RunOptions *o);

/* The assembly at t0 from the file's values in r->q with the run's Newton
   (newton, ctx); singular: fail where the Jacobian is nearly singular
   there. *rep: Newton's last report. False with the failure in r->res
   (what: the phase a failed Newton names). */
bool run_assemble(Run *r, AssembleNewtonFn newton, void *ctx, bool singular, MechrtReport *rep,
                  const char *what);

#endif
