/* outputs.h - the value, velocity and acceleration of each `output` statement at a state of the motion. */
#ifndef MECHC_OUTPUTS_H
#define MECHC_OUTPUTS_H

#include "../eval/interp.h"
#include "../model/model.h"

/* One program per output value, compiled once from the model's graph. */
typedef struct OutputEval {
    int n;                  /* the model's nout */
    Tape *tapes;
    Jet *reg;               /* registers for the longest program */
} OutputEval;

void outputs_init(OutputEval *oe, const Model *m);
void outputs_free(OutputEval *oe);

/* y = f(q, t), yd = f_q qd + f_t, ydd = f_q qdd + D(D f) for every output f
   (n values each; yd, ydd may be NULL, and qd, qdd then too). */
void outputs_eval(const OutputEval *oe, const double *q, const double *qd, const double *qdd,
                  double t, double *y, double *yd, double *ydd);

#endif
