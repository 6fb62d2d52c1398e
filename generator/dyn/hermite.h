/* hermite.h - sim's output between steps: the Hermite interpolant of q, qd, qdd at the last steps' ends. */
#ifndef MECHC_DYN_HERMITE_H
#define MECHC_DYN_HERMITE_H

#include "sim_state.h"

/* yi at t from the nk (2 or 3) nodes tk[k], yk[k], fk[k] (f = (qd, qdd, ...)). */
void sim_hermite(const Sim *s, int nk, const double *tk, double t, double *const *yk,
                 double *const *fk, double *yi);

#endif
