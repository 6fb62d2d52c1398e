/* involutive.h - are the velocity-level rows, with the holonomic rows, integrable together? */
#ifndef MECHC_INVOLUTIVE_H
#define MECHC_INVOLUTIVE_H

#include "../model/model.h"

#include <stdbool.h>

/* The distribution D on (q, t) space annihilated by the rows' forms
   (velocity rows a^T dq + b dt, holonomic rows dPhi = Phi_q dq + Phi_t dt)
   is integrable iff it is involutive, i.e. d omega_k(X, Y) = 0 for X, Y in
   D and every velocity row k (Frobenius; the holonomic forms are exact).
   Tested numerically at the given points (configurations on the holonomic
   rows) by projecting each d omega_k onto D. */
typedef struct Involutivity {
    bool tested;            /* false: no velocity rows, or no point evaluated */
    bool involutive;
    int points;             /* points evaluated */
    char *note;             /* malloc'd */
} Involutivity;

/* rows: model rows to include (holonomic first, then velocity-level);
   points: npoints configurations (npoints x nq) with their times. Adds
   nodes to the model's graph. Returns false with diag filled only when the
   graph's node limit is passed. */
bool involutivity_analyse(Model *m, const int *rows, int nrows, const double *points,
                          const double *times, int npoints, Involutivity *out, Diag *diag);
void involutivity_free(Involutivity *inv);

#endif
