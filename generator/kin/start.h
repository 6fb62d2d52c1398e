/* start.h - a run's start at t0: construction, Newton, the robust assembly, the note on how far it moved. */
#ifndef MECHC_KIN_START_H
#define MECHC_KIN_START_H

#include "run_state.h"

/* The file's values into q0, then r->q as the construction places it, also into start. */
void run_place_at_t0(Run *r, double *q0, double *start);

/* Whether a dense nr x nq Jacobian would be beyond RunOptions.max_dense_entries. */
bool run_dense_too_large(const Model *m, const RunOptions *o);

/* Minimum-norm Newton with restarts from the start in r->q; false with the message. */
bool run_assemble_robustly(Run *r);

/* A note when assembly moved the initial values much. */
void run_note_move(Run *r, const double *q0);

#endif
