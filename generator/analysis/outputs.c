/* outputs.c - the value, velocity and acceleration of each `output` statement at a state of the motion.
 *
 * An output is an expression f(q, t) of the graph (a body point's x or y,
 * a joint's slide(), anything written after `output NAME =`). Along the
 * motion its velocity is the total derivative D f = f_q qd + f_t and its
 * acceleration f_q qdd + D(D f), where D(D f) is the second derivative
 * with qdd = 0. Both come from the interpreter's Taylor jets
 * (eval/interp.h), no derivative nodes are built: one order-2 pass along
 * (qd, 1) gives f, D f and D(D f), one order-1 pass along (qdd, 0) gives
 * f_q qdd.
 */
#include "outputs.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

void outputs_init(OutputEval *oe, const Model *m)
{
    memset(oe, 0, sizeof *oe);
    oe->n = m->nout;
    if (oe->n == 0)
        return;
    oe->tapes = xcalloc((size_t)oe->n, sizeof *oe->tapes);
    CompileScratch cs;
    compile_scratch_init(&cs, &m->dag);
    int longest = 1;
    for (int k = 0; k < oe->n; k++) {
        tape_compile(&oe->tapes[k], &m->dag, m->outputs[k].expr, &cs);
        if (oe->tapes[k].n > longest)
            longest = oe->tapes[k].n;
    }
    compile_scratch_free(&cs);
    oe->reg = xcalloc((size_t)longest, sizeof *oe->reg);
}

void outputs_free(OutputEval *oe)
{
    for (int k = 0; k < oe->n; k++)
        tape_free(&oe->tapes[k]);
    free(oe->tapes);
    free(oe->reg);
    memset(oe, 0, sizeof *oe);
}

void outputs_eval(const OutputEval *oe, const double *q, const double *qd, const double *qdd,
                  double t, double *y, double *yd, double *ydd)
{
    for (int k = 0; k < oe->n; k++) {
        const Tape *p = &oe->tapes[k];
        if (!yd) {
            y[k] = tape_jet(p, &(Seed){.q = q, .t = t, .col_q = -1, .col_qd = -1}, 1, oe->reg).v;
            continue;
        }
        Seed along = {.q = q, .t = t, .dq = qd, .col_q = -1, .col_qd = -1, .dt = 1.0};
        Jet f = tape_jet(p, &along, ydd ? 2 : 1, oe->reg);
        y[k] = f.v;
        yd[k] = f.d;
        if (ydd) {
            Seed accel = {.q = q, .t = t, .dq = qdd, .col_q = -1, .col_qd = -1, .dt = 0.0};
            ydd[k] = f.dd + tape_jet(p, &accel, 1, oe->reg).d;
        }
    }
}
