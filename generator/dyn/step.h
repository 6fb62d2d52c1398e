/* step.h - one accepted step of sim's integrator, GSL's evolve or the same without f at the step's end. */
#ifndef MECHC_DYN_STEP_H
#define MECHC_DYN_STEP_H

#include "sim_state.h"

/* One accepted integrator step from *t towards tn; false with the message set. */
bool sim_one_step(Sim *s, double *y, double *t, double tn, double *h);

/* f at the settled state y (t) into f, kept for the next step's first
   stage; false with the message set. */
bool sim_end_rhs(Sim *s, const double *y, double t, double *f);

#endif
