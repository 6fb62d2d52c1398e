/* project.h - the projections of sim: positions onto Phi = 0, velocities onto Phi_q qd = nu, the rows of the next step. */
#ifndef MECHC_DYN_PROJECT_H
#define MECHC_DYN_PROJECT_H

#include "sim_state.h"

/* After a step (or at the start): projection when on, then the rows the
   next step keeps; false with the message set. */
bool sim_settle(Sim *s, double *y, double t, bool project);

#endif
