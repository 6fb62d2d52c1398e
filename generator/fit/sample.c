/* sample.c - the motion at the data's times, and its sensitivities to the design parameters. */
#include "sample.h"

#include "../base/arena.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool fit_sampler_init(FitSampler *s, Model *m, const Kinematics *kin, const Engine *e,
                      const FitData *d, int steps, double newton_tol, char *why, size_t size)
{
    memset(s, 0, sizeof *s);
    if (!sens_init(&s->sens, m, kin, e, why, size))
        return false;
    s->m = m, s->e = e, s->d = d;
    outputs_init(&s->outputs, m);
    s->ro = run_default_options();
    /* the residuals are as exact as the positions: Newton converges
       quadratically, so the last iteration costs little */
    s->ro.mechrt.tol_phi = s->ro.mechrt.tol_dq = newton_tol;
    double span = d->t[d->nsamples - 1] - d->t[0];
    s->step = span > 0 ? span / (steps > 0 ? steps : 20) : 1.0;
    s->q = xcalloc((size_t)m->nq, sizeof *s->q);
    s->start = xcalloc((size_t)m->nq, sizeof *s->start);
    s->y = xcalloc((size_t)m->nout + 1, sizeof *s->y);
    return true;
}

void fit_sampler_free(FitSampler *s)
{
    sens_free(&s->sens);
    outputs_free(&s->outputs);
    free(s->q), free(s->start), free(s->y);
    memset(s, 0, sizeof *s);
}

/* run's state callback: the last state is the sample's. */
static void keep_state(void *ctx, double t, const double *q, const double *qd, const double *qdd)
{
    FitSampler *s = ctx;
    (void)t, (void)qd, (void)qdd;
    memcpy(s->q, q, (size_t)s->m->nq * sizeof *q);
}

/* From (t0, s->start) to t1: the state at t1 in s->q. */
static bool follow(FitSampler *s, double t0, double t1, char *why, size_t size)
{
    Model from = *s->m;         /* the same model, starting where the last span ended */
    from.q0 = s->start;
    RunOptions ro = s->ro;
    ro.t0 = t0;
    ro.t1 = t1 != t0 ? t1 : t0 + 1.0;
    ro.steps = t1 != t0 ? (int)ceil(fabs(t1 - t0) / s->step - 1e-9) : 0;
    if (ro.steps < 1 && t1 != t0)
        ro.steps = 1;
    RunResult res;
    if (run_analysis(&from, engine_kernels(s->e), NULL, &ro, keep_state, s, &res) == ANALYSIS_OK)
        return true;
    snprintf(why, size, "%s", res.message);
    return false;
}

/* The model value of measured column c at the current state. */
static double variable(const FitSampler *s, int c)
{
    int v = s->d->var[c];
    return v < s->m->nq ? s->q[v] : s->y[v - s->m->nq];
}

/* Its derivative in design parameter j. */
static double derivative(const FitSampler *s, int c, int j)
{
    int v = s->d->var[c], np = s->m->np;
    return v < s->m->nq ? s->sens.q_p[(size_t)v * (size_t)np + (size_t)j]
                        : s->sens.y_p[(size_t)(v - s->m->nq) * (size_t)np + (size_t)j];
}

bool fit_sample(FitSampler *s, double *value, double *dvalue, char *why, size_t size)
{
    const FitData *d = s->d;
    const Model *m = s->m;
    memcpy(s->start, m->q0, (size_t)m->nq * sizeof *s->start);
    double t_prev = d->t[0];
    for (int k = 0; k < d->nsamples; k++) {
        if (!follow(s, k == 0 ? d->t[0] : t_prev, d->t[k], why, size))
            return false;
        memcpy(s->start, s->q, (size_t)m->nq * sizeof *s->q);
        t_prev = d->t[k];
        outputs_eval(&s->outputs, s->q, NULL, NULL, d->t[k], s->y, NULL, NULL);
        if (dvalue) {
            MechrtStatus st = sens_eval_positions(&s->sens, d->t[k], s->q);
            if (st != MECHRT_OK) {
                snprintf(why, size, "t = %.17g: no sensitivities: %s", d->t[k], mechrt_strerror(st));
                return false;
            }
        }
        for (int c = 0; c < d->ncols; c++) {
            size_t at = (size_t)k * (size_t)d->ncols + (size_t)c;
            value[at] = variable(s, c);
            for (int j = 0; dvalue && j < m->np; j++)
                dvalue[at * (size_t)m->np + (size_t)j] = derivative(s, c, j);
        }
    }
    return true;
}
