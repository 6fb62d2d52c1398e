/* subdivide.h - an interval of a run redone in 2, 4, 8 ... substeps when its step looked unreliable. */
#ifndef MECHC_KIN_SUBDIVIDE_H
#define MECHC_KIN_SUBDIVIDE_H

#include "step.h"

/* The step over [t, tn] was not quiet (chk0 says why), or failed with st0:
   redone in substeps; true with the state at tn, false with the failure. */
bool run_subdivide(Run *r, double t, double tn, MechrtStatus st0, MechrtReport *rep,
                   const StepCheck *chk0);

#endif
