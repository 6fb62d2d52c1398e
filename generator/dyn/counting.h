/* counting.h - the simulation's kernels, counted: every call of the simulation goes through them. */
#ifndef MECHC_DYN_COUNTING_H
#define MECHC_DYN_COUNTING_H

#include "sim_state.h"

/* s->kc: the caller's kernels s->inner, each call counted in s->res->calls. */
void sim_counting(Sim *s);

#endif
