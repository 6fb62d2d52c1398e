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
    int nw;                 /* angular velocities: 3 per spatial body */
    int *wq;                /* their bodies' x coordinates, nw / 3 */
    char **wnames;          /* NAME.wx NAME.wy NAME.wz, nw */
} OutputEval;

void outputs_init(OutputEval *oe, const Model *m);
void outputs_free(OutputEval *oe);

/* y = f(q, t), yd = f_q qd + f_t, ydd = f_q qdd + D(D f) for every output f
   (n values each; yd, ydd may be NULL, and qd, qdd then too). */
void outputs_eval(const OutputEval *oe, const double *q, const double *qd, const double *qdd,
                  double t, double *y, double *yd, double *ydd);

/* The angular velocity omega = 2 E(p) p' (global frame), E = [-e, e~ + e0 I],
   of every spatial body: w[3 i .. 3 i + 2] for the i-th, oe->nw values. */
void outputs_omega(const OutputEval *oe, const double *q, const double *qd, double *w);
/* The other way: the Euler-parameter rates ed (4) of a body whose Euler
   parameters are e (4; normalised here) turning at w (3, global frame):
   ed = 1/2 E(e)^T w, so that 2 E ed = w and e . ed = 0. */
void outputs_euler_rates(const double *e, const double *w, double *ed);

#endif
