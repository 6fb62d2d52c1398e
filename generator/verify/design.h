/* design.h - the check of dPhi/dp: finite differences in the design parameters, engines against each other. */
#ifndef MECHC_VERIFY_DESIGN_H
#define MECHC_VERIFY_DESIGN_H

#include "checker.h"

/* At the sample: every open engine's dPhi/dp, the jit's against central
   differences of its Phi in each design parameter (one Richardson step),
   and every pair of engines. */
void check_design(Checker *c);

#endif
