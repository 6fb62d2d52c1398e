/* dynamics.h - the check of M and Q: symmetry, definiteness, velocity terms against the kinetic energy. */
#ifndef MECHC_VERIFY_DYNAMICS_H
#define MECHC_VERIFY_DYNAMICS_H

#include "checker.h"

/* At the sample: the jit's M symmetric and positive semi-definite, its
   velocity terms against differences of the kinetic energy. */
void check_dynamics(Checker *c);

#endif
