/* watch.h - sim's watch over its steps: a step size that collapses, rows that turn abruptly, the step budget. */
#ifndef MECHC_DYN_WATCH_H
#define MECHC_DYN_WATCH_H

#include "sim_state.h"

/* After the accepted step from t_before to t (y there, before any
   projection); false with the message set when the motion cannot go on:
   more than SimOptions.max_steps steps, the step size collapsed (a
   window of steps far below those taken before, most of their attempts
   rejected), or a row's gradient turned abruptly within one step (rows
   not smooth or not defined there: a rolling disk lying flat). */
bool sim_watch_step(Sim *s, const double *y, double t, double t_before);

#endif
