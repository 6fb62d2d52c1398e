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
 *
 * A spatial body's angular velocity is not a function of q and t but of
 * its Euler parameters and their rates: omega = 2 E(p) p' (Haug 1989,
 * eq. 6.3.18), computed here directly, three values per body.
 */
#include "outputs.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The spatial bodies' angular velocity columns and their names. */
static void omega_init(OutputEval *oe, const Model *m)
{
    int n = 0;
    for (int b = 0; b < m->nbodies; b++)
        n += m->bodies[b].spatial && m->bodies[b].nq == 7;
    if (n == 0)
        return;
    oe->nw = 3 * n;
    oe->wq = xcalloc((size_t)n, sizeof *oe->wq);
    oe->wnames = xcalloc((size_t)oe->nw, sizeof *oe->wnames);
    static const char *const suffix[3] = {".wx", ".wy", ".wz"};
    n = 0;
    for (int b = 0; b < m->nbodies; b++) {
        const Body *body = &m->bodies[b];
        if (!body->spatial || body->nq != 7)
            continue;
        for (int k = 0; k < 3; k++) {
            char *name = xmalloc(strlen(body->name) + 4);
            strcpy(name, body->name);
            strcat(name, suffix[k]);
            oe->wnames[3 * n + k] = name;
        }
        oe->wq[n++] = body->q;
    }
}

void outputs_omega(const OutputEval *oe, const double *q, const double *qd, double *w)
{
    for (int i = 0; i < oe->nw / 3; i++) {
        const double *p = q + oe->wq[i] + 3, *v = qd + oe->wq[i] + 3;
        w[3 * i] = 2 * (-p[1] * v[0] + p[0] * v[1] - p[3] * v[2] + p[2] * v[3]);
        w[3 * i + 1] = 2 * (-p[2] * v[0] + p[3] * v[1] + p[0] * v[2] - p[1] * v[3]);
        w[3 * i + 2] = 2 * (-p[3] * v[0] - p[2] * v[1] + p[1] * v[2] + p[0] * v[3]);
    }
}

void outputs_euler_rates(const double *e, const double *w, double *ed)
{
    double n = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3]);
    double p[4] = {e[0] / n, e[1] / n, e[2] / n, e[3] / n};
    /* E's rows (-e1, e0, -e3, e2), (-e2, e3, e0, -e1), (-e3, -e2, e1, e0), as above */
    ed[0] = 0.5 * (-p[1] * w[0] - p[2] * w[1] - p[3] * w[2]);
    ed[1] = 0.5 * (p[0] * w[0] + p[3] * w[1] - p[2] * w[2]);
    ed[2] = 0.5 * (-p[3] * w[0] + p[0] * w[1] + p[1] * w[2]);
    ed[3] = 0.5 * (p[2] * w[0] - p[1] * w[1] + p[0] * w[2]);
}

void outputs_init(OutputEval *oe, const Model *m)
{
    memset(oe, 0, sizeof *oe);
    omega_init(oe, m);
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
    for (int k = 0; k < oe->nw; k++)
        free(oe->wnames[k]);
    free(oe->wnames);
    free(oe->wq);
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
