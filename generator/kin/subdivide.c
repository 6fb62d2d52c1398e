/* subdivide.c - an interval of a run redone in 2, 4, 8 ... substeps when its step looked unreliable. */
#include "subdivide.h"

#include "diagnose.h"

#include <math.h>
#include <string.h>

/* Two subdivision levels agree when their positions at the end of the
   interval differ by at most RUN_AGREE * tol_dq in every coordinate. */
#define RUN_AGREE 10

/* The positions of two levels at the interval's end are the same solution. */
static bool levels_agree(const Run *r, const double *a, const double *b)
{
    double tol = RUN_AGREE * r->o->mechrt.tol_dq;
    for (int i = 0; i < r->nq; i++)
        if (!(fabs(a[i] - b[i]) <= tol))
            return false;
    return true;
}

/* Past the subdivision limit with every level converging: the message. */
static void run_fail_too_fast(Run *r, double t_start, double t_end, double t_bad, long levels,
                          const StepCheck *chk)
{
    RunResult *res = r->res;
    res->status = ANALYSIS_FAILED;
    res->cause = MECHRT_ESTEP;
    res->t_fail = t_bad;
    res->message[0] = '\0';
    msgf(r, "t = %.10g: position analysis failed: the motion is too fast for the step: ", t_bad);
    if (levels > 1)
        msgf(r, "in %ld substeps of the step from t = %.10g to %.10g ", levels, t_start, t_end);
    else
        msgf(r, "in the step from t = %.10g to %.10g (no substeps allowed) ", t_start, t_end);
    if (chk->coord >= 0)
        msgf(r, "Newton %scorrected %s by %.3g where the predictor moved it by %.3g",
             levels > 1 ? "still " : "", r->m->coord_names[chk->coord], chk->correction,
             chk->motion);
    else
        msgf(r, "Newton %sneeded %d iterations", levels > 1 ? "still " : "", chk->iterations);
    msgf(r, ", so the motion may have jumped to another assembly branch or turn; use more "
         "--steps or a larger --max-substeps");
}

/* The step over [t, tn] from (sq, sqd, sqdd) was not quiet (chk0 says
   why), or failed with st0 (report *rep, iterate in q). Redoes the interval
   in 2, 4, 8 ... substeps until a level is quiet throughout, or took few
   iterations throughout and agrees with the previous level: true with the
   state at tn in q, qd, qdd and the last substep's report in *rep. Past
   max_substeps: false, the failure in r->res (the original step's own, at
   tn, when it failed). */
bool run_subdivide(Run *r, double t, double tn, MechrtStatus st0, MechrtReport *rep,
                      const StepCheck *chk0)
{
    const RunOptions *o = r->o;
    size_t bytes = (size_t)r->nq * sizeof(double);
    MechrtReport rep0 = *rep;
    StepCheck chk = *chk0;
    MechrtStatus st = st0;
    double t_bad = tn;
    bool have_last = st0 == MECHRT_OK;
    long levels = 1;

    memcpy(r->iq, r->sq, 3 * bytes);   /* q | qd | qdd */
    memcpy(have_last ? r->lq : r->fq, r->q, bytes);
    r->res->subdivided++;
    for (long s = 2; s <= o->max_substeps; s *= 2) {
        bool all_quiet = true, few_iterations = true;
        double ta = t;
        levels = s;
        memcpy(r->q, r->iq, 3 * bytes);
        st = MECHRT_OK;
        for (long j = 1; j <= s && st == MECHRT_OK; j++) {
            double tb = j == s ? tn : t + (tn - t) * (double)j / (double)s;
            bool quiet;
            StepCheck c = {-1, 0, 0, 0};
            st = run_checked_step(r, ta, tb - ta, rep, &quiet, &c);
            r->res->substeps++;
            if (st != MECHRT_OK || (!quiet && all_quiet)) {
                t_bad = tb;
                if (st == MECHRT_OK)
                    chk = c;
            }
            all_quiet = all_quiet && quiet;
            few_iterations = few_iterations && rep->iterations <= RUN_QUIET_ITER;
            ta = tb;
        }
        if (st == MECHRT_OK
            && (all_quiet || (few_iterations && have_last && levels_agree(r, r->q, r->lq))))
            return true;
        have_last = st == MECHRT_OK;
        if (have_last)
            memcpy(r->lq, r->q, bytes);
    }
    if (st0 != MECHRT_OK) {
        /* subdivision did not help: the step's own failure, as ever, and
           where the substeps stopped */
        memcpy(r->q, r->fq, bytes);
        run_fail_step(r, st0, tn, r->q, &rep0);
        if (levels > 1 && st != MECHRT_OK)
            msgf(r, "; redone in up to %ld substeps, the step from t = %.10g failed again at "
                 "t = %.10g", levels, t, t_bad);
        else if (levels > 1)
            msgf(r, "; redone in up to %ld substeps, the step from t = %.10g still seemed to "
                 "leave its assembly branch: the motion may be too fast for the step (use "
                 "more --steps or a larger --max-substeps)", levels, t);
    } else if (st != MECHRT_OK) {
        run_fail_step(r, st, t_bad, r->q, rep);
        msgf(r, "; or the motion is too fast for the step: the step from t = %.10g to %.10g "
             "seemed to leave its assembly branch and was redone in up to %ld substeps; use "
             "more --steps or a larger --max-substeps", t, tn, levels);
    } else {
        run_fail_too_fast(r, t, tn, t_bad, levels, &chk);
    }
    return false;
}

