/* step.c - one accepted step of sim's integrator, GSL's evolve or the same without f at the step's end. */
#include "step.h"

#include "rhs.h"
#include "watch.h"

#include <math.h>
#include <string.h>

#include <gsl/gsl_errno.h>

/* The step size is said to underflow below this share of |t1 - t0|. */
#define SIM_HMIN_SHARE 1e-14

/* One accepted step from *t towards t1 with GSL's stepper and control,
   retried with the control's smaller h (or half h on a stepper failure)
   as gsl_odeiv2_evolve_apply does, but asking the stepper for no f at
   the step's unprojected end (dydt_out NULL: rk8pd and rkf45 then skip
   that evaluation, one in 13 and in 6): --interpolate solves f at the
   projected end anyway, for the interpolant and the next step's start.
   The control's derivative weight is 0 (sim_open), so dydt_in stands in
   for the dydt it is given. GSL's status. */
static int step_without_end_f(Sim *s, double *t, double t1, double *h, double *y)
{
    gsl_odeiv2_driver *d = s->drv;
    gsl_odeiv2_evolve *e = d->e;
    size_t bytes = (size_t)s->dim * sizeof *y;
    double t0 = *t, span = t1 - t0;
    int st = sim_rhs(t0, y, e->dydt_in, s);
    if (st != GSL_SUCCESS)
        return st;
    memcpy(e->y0, y, bytes);
    for (;;) {
        double hs = *h;
        bool last = span >= 0 ? hs > span : hs < span;
        if (last)
            hs = span;
        st = gsl_odeiv2_step_apply(d->s, t0, hs, y, e->yerr, e->dydt_in, NULL, &s->sys);
        if (st == GSL_EFAULT || st == GSL_EBADFUNC)
            return st;
        double hn = hs;
        bool again = st != GSL_SUCCESS;
        if (again)
            hn = 0.5 * hs;
        else
            again = gsl_odeiv2_control_hadjust(d->c, d->s, y, e->yerr, e->dydt_in, &hn)
                    == GSL_ODEIV_HADJ_DEC;
        if (again) {
            memcpy(y, e->y0, bytes);
            *h = hn;
            if (!(fabs(hn) < fabs(hs)) || t0 + hn == t0)
                return st != GSL_SUCCESS ? st : GSL_FAILURE;
            e->failed_steps++;
            continue;
        }
        e->count++;
        e->last_step = hs;
        *t = last ? t1 : t0 + hs;
        if (!last)
            *h = hn;
        return GSL_SUCCESS;
    }
}

/* One accepted integrator step from *t towards tn; false with the message set. */
bool sim_one_step(Sim *s, double *y, double *t, double tn, double *h)
{
    gsl_odeiv2_driver *d = s->drv;
    double hmin = SIM_HMIN_SHARE * fabs(s->o->t1 - s->o->t0), t_before = *t;
    unsigned long failed0 = d->e->failed_steps;
    /* GSL's evolve starts a step from the last one's dydt_out, f at the
       unprojected end with the old rows; where f at the projected state
       is at hand (an output state or the interpolant's end solved it
       there), count = 0 makes it evaluate f there instead, which the
       cache answers; so too where the projection moved the state beyond
       the tolerance's scale or changed the rows (fresh_f): the stale f
       was taken elsewhere, and the pair's error estimate would see the
       difference as error (near a flat position of IFToMM A02 a velocity
       correction of 1e-4 made rk8pd cut its step to 5e-9 s) */
    if (sim_cache_has(s, *t, y) || s->fresh_f)
        d->e->count = 0;
    s->fresh_f = false;
    bool explicit_rk = s->o->method == SIM_RK8PD || s->o->method == SIM_RKF45;
    int gs = s->o->interpolate && explicit_rk ? step_without_end_f(s, t, tn, h, y)
                                              : gsl_odeiv2_evolve_apply(d->e, d->c, d->s,
                                                                        &s->sys, t, tn, h, y);
    bool retried = d->e->failed_steps > failed0;
    s->res->rejected += (long)(d->e->failed_steps - failed0);
    /* no growth right after a rejection (Hairer, Norsett and Wanner,
       Solving ODEs I, II.4, as DOPRI5 does): approaching a flat position
       of IFToMM A02 the error per step grows along the path, and GSL's
       evolve, growing h after the retried step was accepted, had the next
       one rejected too, step after step (a third of A02's steps at 1e-10) */
    if (gs == GSL_SUCCESS && retried && fabs(*h) > fabs(*t - t_before))
        *h = copysign(fabs(*t - t_before), *h);
    if (gs != GSL_SUCCESS) {
        if (s->fail_status != MECHRT_OK) {
            sim_fail(s, s->fail_status, s->fail_t, "forward dynamics");
            sim_explain_dynamics(s, s->fail_status, &s->fail_rep, s->fail_y);
        } else {
            sim_fail(s, MECHRT_ESTEP, *t, "integration");
            msgf(s, "the integrator (%s) gave up (GSL: %s)", sim_method_names[s->o->method],
                 gsl_strerror(gs));
        }
        return false;
    }
    s->res->steps++;
    if (fabs(*t - t_before) < hmin && *t != tn) {
        sim_fail(s, MECHRT_ESTEP, *t, "integration");
        msgf(s, "step size underflow (%.3g) before --rtol/--atol were met: a singular "
             "position, an impact or a stiff force? (an implicit --method may help)",
             fabs(*t - t_before));
        return false;
    }
    if (!sim_watch_step(s, y, *t, t_before))
        return false;
    if (s->o->on_step)
        s->o->on_step(s->o->on_step_ctx, *t);
    return true;
}

/* f at the settled state y (t) into f, kept for the next step's first
   stage; false with the message set. */
bool sim_end_rhs(Sim *s, const double *y, double t, double *f)
{
    if (sim_rhs(t, y, f, s) == GSL_SUCCESS)
        return true;
    if (s->fail_status == MECHRT_OK) {     /* sim_rhs records every failure; defensive */
        sim_fail(s, MECHRT_ENOTFINITE, t, "forward dynamics");
        msgf(s, "%s", mechrt_strerror(MECHRT_ENOTFINITE));
        return false;
    }
    sim_fail(s, s->fail_status, s->fail_t, "forward dynamics");
    sim_explain_dynamics(s, s->fail_status, &s->fail_rep, s->fail_y);
    return false;
}

