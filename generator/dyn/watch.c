/* watch.c - sim's watch over its steps: a step size that collapses, rows that turn abruptly, the step budget.
 *
 * Where rows are not smooth (a rolling disk lying flat: its contact's
 * normal, the unit horizontal part of the axle, is 0/0 there) the right
 * side jumps, and an error-controlled step cannot cross: the one-step
 * methods take steps ever smaller, most attempts rejected, and never get
 * past (on a falling disk rk8pd crept on at 5e-10 s a step for minutes);
 * msbdf, which projects only at the output times, steps across and goes
 * on through states where the rows mean nothing. So every accepted step
 * is watched: over a window of SIM_STALL_STEPS steps, a mean step below
 * SIM_STALL_SHARE of the largest taken before with most attempts
 * rejected, or below SIM_STALL_FLOOR max(1, |t|), is a collapse; and
 * each row's gradient (dense, or the sparse path's nonzeros) at the
 * step's end is compared with the one at its start: a change larger than
 * the gradient itself (a turn beyond 60 degrees) in one accepted step far
 * shorter than those before names the rows. Both end the simulation with
 * exit 1, the time and the rows.
 *
 * The step budget (--max-steps) is checked as it is spent, and forecast:
 * once a hundredth of it is spent, a rate of progress that would need
 * more than SIM_BUDGET_FORECAST times the budget for the whole interval
 * (sim --t1 1e9 on a pendulum: 2e10 steps) ends the run there, in a
 * second, instead of at the budget's end a minute later with the same
 * message.
 */
#include "watch.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Accepted steps per window of the collapse test. */
#define SIM_STALL_STEPS 1000
/* The window's mean step against the largest step before it. */
#define SIM_STALL_SHARE 1e-6
/* ... or against max(1, |t|), rejections or not. */
#define SIM_STALL_FLOOR 1e-12
/* A row's gradient changing by more than this share of its size in one
   step, a step below SIM_TURN_STEP of the largest before (a smooth row
   turns that far only in a long step: a fast spin at loose tolerances). */
#define SIM_TURN_SHARE 1.0
#define SIM_TURN_STEP 1e-3
/* The step budget's forecast: past SIM_BUDGET_FORECAST times the budget. */
#define SIM_BUDGET_FORECAST 10.0

/* The gradients are watched: rows and their Jacobian, dense or the
   sparse path's nonzeros. */
static bool watch_rows(const Sim *s)
{
    return s->nr > 0 && (s->kkt ? s->jnz->jac.jac_nz != NULL : s->inner->jac != NULL);
}

/* Entries of the Jacobian watched: nr x nq, or the nonzeros. */
static size_t watch_len(const Sim *s)
{
    return s->kkt ? (size_t)s->jnz->jac.nnz : (size_t)s->nr * (size_t)s->nq;
}

/* Per row, |J_i(now) - J_i(before)| / max(|J_i(now)|, |J_i(before)|)
   into w (nr; wnow, wold: nr of room each); the largest. */
static double row_turns(const Sim *s, double *w)
{
    double *na = s->wturn + s->nr, *nb = na + s->nr;
    memset(w, 0, (size_t)s->nr * sizeof *w);
    memset(na, 0, 2 * (size_t)s->nr * sizeof *na);
    for (size_t k = 0, n = watch_len(s); k < n; k++) {
        int i = s->kkt ? s->jnz->jac.row[k] : (int)(k / (size_t)s->nq);
        double a = s->wjac[k], b = s->wjac0[k];
        w[i] += (a - b) * (a - b);
        na[i] += a * a;
        nb[i] += b * b;
    }
    double worst = 0;
    for (int i = 0; i < s->nr; i++) {
        double n = sqrt(fmax(na[i], nb[i]));
        w[i] = n > 0 ? sqrt(w[i]) / n : 0;
        if (!isfinite(w[i]))
            w[i] = INFINITY;
        worst = fmax(worst, w[i]);
    }
    return worst;
}

/* lead and the rows that turned most in the last step (wturn), or nothing. */
static void name_rows(Sim *s, const char *lead)
{
    if (!watch_rows(s) || !s->o->row_names || !s->wvalid || row_turns(s, s->wturn) <= 0)
        return;
    msgf(s, "%s", lead);
    analysis_name_list(s->res->message, sizeof s->res->message, s->o->row_names, s->wturn,
                       s->nr);
}

/* The Jacobian at y into wjac, the one before kept in wjac0. */
static void take_gradients(Sim *s, const double *y, double t)
{
    double *tmp = s->wjac0;
    s->wjac0 = s->wjac;
    s->wjac = tmp;
    if (s->kkt)
        s->jnz->jac.jac_nz(s->jnz->jac.ctx, y, t, s->wjac);
    else
        s->inner->jac(s->inner->ctx, y, t, s->wjac);
    s->wvalid = s->whave;
    s->whave = true;
}

static bool collapsed(Sim *s, double t)
{
    double mean = (t - s->wt0) / SIM_STALL_STEPS;
    long rejected = s->res->rejected - s->wrejected0;
    return fabs(mean) < SIM_STALL_FLOOR * fmax(1, fabs(t))
           || (fabs(mean) < SIM_STALL_SHARE * s->hmax && rejected >= SIM_STALL_STEPS / 2);
}

/* More steps than --max-steps, taken or (at this rate) needed: false
   with the message set. */
static bool over_budget(Sim *s, double t)
{
    long steps = s->res->steps, budget = s->o->max_steps;
    double done = (t - s->o->t0) / (s->o->t1 - s->o->t0);
    double needed = steps / fmax(done, 1e-300);
    if (steps > budget) {
        sim_fail(s, MECHRT_ESTEP, t, "integration");
        msgf(s, "more than %ld integrator steps (--max-steps)", budget);
    } else if (steps >= SIM_STALL_STEPS && steps >= budget / 100
               && needed > SIM_BUDGET_FORECAST * (double)budget) {
        sim_fail(s, MECHRT_ESTEP, t, "integration");
        msgf(s, "%ld integrator steps so far, at this rate about %.2g for the whole interval: "
             "more than %ld (--max-steps)", steps, needed, budget);
    } else {
        return true;
    }
    msgf(s, " at %.3g%% of the interval from t = %.10g to %.10g: the motion is stiff or too "
         "fast for --rtol/--atol (an implicit --method may help), or the interval too long",
         100 * done, s->o->t0, s->o->t1);
    return false;
}

bool sim_watch_step(Sim *s, const double *y, double t, double t_before)
{
    if (!over_budget(s, t))
        return false;
    if (s->wsteps == 0) {
        s->wt0 = t_before;
        s->wrejected0 = s->res->rejected;
    }
    double h = fabs(t - t_before);
    if (watch_rows(s)) {
        take_gradients(s, y, t);
        if (s->wvalid && h < SIM_TURN_STEP * s->hmax
            && row_turns(s, s->wturn) > SIM_TURN_SHARE) {
            sim_fail(s, MECHRT_ESING, t, "integration");
            msgf(s, "in the last step (of %.3g) the gradient of a row turned abruptly", h);
            name_rows(s, " (");
            msgf(s, "%s: the rows are not smooth or not defined there (a contact whose normal "
                 "is lost, a rolling disk lying flat?)", s->o->row_names ? ")" : "");
            return false;
        }
    }
    if (++s->wsteps < SIM_STALL_STEPS) {
        s->hmax = fmax(s->hmax, h);
        return true;
    }
    if (collapsed(s, t)) {
        sim_fail(s, MECHRT_ESTEP, t, "integration");
        msgf(s, "the step size collapsed (%d steps of %.3g on average, %ld attempts rejected; "
             "steps of %.3g before): the motion reached a state the integrator cannot cross, "
             "where rows are not smooth or not defined (a rolling disk lying flat?), an impact "
             "or a singular position", SIM_STALL_STEPS, fabs(t - s->wt0) / SIM_STALL_STEPS,
             s->res->rejected - s->wrejected0, s->hmax);
        name_rows(s, "; the rows whose gradients change most there: ");
        return false;
    }
    s->wsteps = 0;
    s->hmax = fmax(s->hmax, h);
    return true;
}
