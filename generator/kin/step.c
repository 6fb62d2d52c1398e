/* step.c - one predictor-corrector step of a run, checked, and redone through singular positions by the rank corrector. */
#include "step.h"

#include "../base/arena.h"

#include <math.h>
#include <string.h>

/* A step whose Jacobian at the end has a condition estimate above this
   (or has no LU at all) is redone by the rank-revealing corrector
   (rank_step): an LU solve there keeps fewer than 16 - 9 digits. */
#define RUN_RANK_COND 1e9
/* The rank corrector's velocity and acceleration must satisfy their
   equations to this share (MechrtReport.inconsistency): otherwise the
   continued motion is none the mechanism can have there. */
#define RUN_BRANCH_TOL 1e-6
/* The rank corrector is dense: two nq x nq matrices and O(nq^3) work per
   call. Above this many coordinates (16 MB) a singular step fails as the
   LU's does. */
#define RUN_RANK_MAX_NQ 1000

/* The check of the converged step of length h that went from (sq, sqd,
   sqdd) to q: see RUN_QUIET_SHARE. NaN fails it. */
static bool step_quiet(const Run *r, double h, const MechrtReport *rep, StepCheck *chk)
{
    const double tol = r->o->mechrt.tol_dq, h2 = 0.5 * h * h;
    double worst = 0;
    int bad = 0;
    /* One Newton iteration (fine steps): the correction was that one step,
       at most tol_dq in every coordinate, so the check holds. */
    if (rep->iterations <= 1)
        return true;
    /* the common case, branch-free */
    for (int i = 0; i < r->nq; i++) {
        double corr = fabs(r->q[i] - (r->sq[i] + h * r->sqd[i] + h2 * r->sqdd[i]));
        double motion = fabs(h * r->sqd[i]) + h2 * fabs(r->sqdd[i]);
        bad |= !(corr <= RUN_QUIET_SHARE * motion + tol);
    }
    if (rep->iterations <= RUN_QUIET_ITER && !bad)
        return true;
    /* not quiet: which coordinate, for a message */
    chk->coord = -1;
    chk->iterations = rep->iterations;
    for (int i = 0; i < r->nq; i++) {
        double corr = fabs(r->q[i] - (r->sq[i] + h * r->sqd[i] + h2 * r->sqdd[i]));
        double motion = fabs(h * r->sqd[i]) + h2 * fabs(r->sqdd[i]);
        double allowed = RUN_QUIET_SHARE * motion + tol;
        if (!(corr <= allowed)) {
            if (!(corr <= worst * allowed)) {
                worst = corr / allowed;
                chk->coord = i;
                chk->correction = corr;
                chk->motion = motion;
            }
        }
    }
    return false;
}

/* The one place the linear algebra differs: the runtime's dense step, or
   the same step on the sparse Jacobian. */
MechrtStatus run_step(Run *r, double t, double h, MechrtReport *rep)
{
    if (r->sp)
        return mechrt_host_sparse_step(r->sp, r->k, &r->o->mechrt, r->q, r->qd, r->qdd, t, h,
                                       r->work, r->lwork, rep);
    if (r->lup) {
        RunLu *lent = r->o->lend_lu;
        if (lent)
            lent->valid = false;
        MechrtStatus st = mechrt_step_lup(r->k, &r->jnz->jac, r->lup, &r->o->mechrt, r->q, r->qd,
                                          r->qdd, t, h, r->work, r->lwork, rep);
        /* the kernels' own P_step leaves no factors in the pattern LU */
        if (lent && lent->lup && st == MECHRT_OK && !(r->lup->gen && r->lup->gen->step)) {
            lent->valid = true;
            lent->t = t + h;
            memcpy(lent->q, r->q, (size_t)r->nq * sizeof *r->q);
        }
        return st;
    }
    return mechrt_step(r->k, &r->o->mechrt, r->q, r->qd, r->qdd, t, h, r->work, r->lwork, rep);
}

/* The state at time t (in sq, sqd, sqdd) was trusted: its acceleration
   joins the predictor's history (the same time again replaces it). */
static void push_history(Run *r, double t)
{
    size_t nq = (size_t)r->nq, bytes = nq * sizeof(double);
    if (r->hist_n > 0 && r->hist_t[0] == t) {
        memcpy(r->hist_qdd, r->sqdd, bytes);
        return;
    }
    memmove(r->hist_qdd + nq, r->hist_qdd, (RUN_HISTORY - 1) * bytes);
    memmove(r->hist_t + 1, r->hist_t, (RUN_HISTORY - 1) * sizeof *r->hist_t);
    memcpy(r->hist_qdd, r->sqdd, bytes);
    r->hist_t[0] = t;
    r->hist_n = r->hist_n < RUN_HISTORY ? r->hist_n + 1 : RUN_HISTORY;
}

/* The prediction at t + h from the state at t (sq, sqd, sqdd) into q, qd,
 * qdd: the acceleration extrapolated by the cubic through it and the
 * history's three before it (fewer when there are fewer, down to Taylor's
 * constant), qd and q its integrals from t. Errors O(h^4) in qdd, O(h^5)
 * in qd, O(h^6) in q, where the LU step's Taylor predictor has O(h^3) in
 * q: along the directions a singular Jacobian loses, the prediction is
 * all there is. History from later times (a subdivision's failed level)
 * or the other direction is left out. */
static void predict(Run *r, double t, double h)
{
    double s[RUN_HISTORY + 1] = {0};
    const double *a[RUN_HISTORY + 1] = {r->sqdd};
    int used = 1;
    for (int e = 0; e < r->hist_n; e++) {
        double se = r->hist_t[e] - t;
        if (se * h < 0 && (used == 1 || fabs(se) > fabs(s[used - 1]))) {
            s[used] = se;
            a[used++] = r->hist_qdd + (size_t)e * (size_t)r->nq;
        }
    }
    double hk[6] = {1, h, h * h, h * h * h, h * h * h * h, h * h * h * h * h};
    for (int i = 0; i < r->nq; i++) {
        /* divided differences, then the Newton form as c0 + c1 s + ... */
        double d[RUN_HISTORY + 1] = {a[0][i]}, c[4] = {0, 0, 0, 0};
        double f[RUN_HISTORY + 1];
        for (int j = 0; j < used; j++)
            f[j] = a[j][i];
        for (int l = 1; l < used; l++) {
            for (int j = used - 1; j >= l; j--)
                f[j] = (f[j] - f[j - 1]) / (s[j] - s[j - l]);
            d[l] = f[l];
        }
        c[0] = d[0];
        if (used > 1)
            c[1] = d[1];
        if (used > 2)
            c[1] -= d[2] * s[1], c[2] = d[2];
        if (used > 3)
            c[1] += d[3] * s[1] * s[2], c[2] -= d[3] * (s[1] + s[2]), c[3] = d[3];
        double qdd = 0, qd = r->sqd[i], q = r->sq[i] + r->sqd[i] * h;
        for (int k = 0; k < 4; k++) {
            qdd += c[k] * hk[k];
            qd += c[k] * hk[k + 1] / (k + 1);
            q += c[k] * hk[k + 2] / ((k + 1) * (k + 2));
        }
        r->qdd[i] = qdd, r->qd[i] = qd, r->q[i] = q;
    }
}

/* The LU step ended without a factorisation (singular), or with one too
   ill-conditioned to trust: the rank-revealing corrector takes over. */
static bool wants_rank(MechrtStatus st, const MechrtReport *rep)
{
    if (st == MECHRT_ESING || st == MECHRT_EMAXITER || st == MECHRT_ENOTFINITE)
        return true;
    return st == MECHRT_OK && rep->cond > RUN_RANK_COND;
}

/* The step from t to t + h again, through a singular position: the
   history's prediction, corrected by mechrt_rank_correct (dense, on both
   paths: KLU has no rank-revealing factorisation). When it fails too, or
   its velocity or acceleration leave a residual (no branch continues the
   motion there), the LU attempt stands: its status st0, its report in
   *rep and its iterate (kept in rq) in q, so that its messages are the
   LU's; the corrector's verdict is kept for the message (rank_note). */
static MechrtStatus rank_step(Run *r, double t, double h, MechrtStatus st0, MechrtReport *rep)
{
    size_t bytes = (size_t)r->nq * sizeof(double);
    if (!r->rk_work) {
        r->rk_lwork = mechrt_rank_workspace_size(r->nq);
        r->rk_work = xcalloc(r->rk_lwork + 1, sizeof *r->rk_work);
    }
    MechrtReport rk;
    memcpy(r->rq, r->q, bytes);
    predict(r, t, h);
    MechrtStatus st = mechrt_rank_correct(r->k, &r->o->mechrt, r->q, r->qd, r->qdd, t + h,
                                          r->rk_work, r->rk_lwork, &rk);
    RunResult *res = r->res;
    res->rank_steps++;
    res->newton_iterations += rk.iterations;
    res->rank_factorisations += rk.factorisations;
    if (st != MECHRT_OK || rk.inconsistency > RUN_BRANCH_TOL) {
        res->rank_failed = true;
        res->rank_t = t + h;
        res->rank_status = st;
        res->rank_inconsistency = rk.inconsistency;
        memcpy(r->q, r->rq, bytes);
        return st0;
    }
    if (rk.rank_deficiency > 0)
        res->rank_deficient_steps++;
    if (rk.rank_deficiency > res->max_rank_deficiency)
        res->max_rank_deficiency = rk.rank_deficiency;
    rk.cond = st0 == MECHRT_OK ? rep->cond : 0;   /* the condition watch: the LU's estimate */
    rk.cond_warning = st0 == MECHRT_OK ? rep->cond_warning : false;
    *rep = rk;
    return MECHRT_OK;
}

/* One predictor-corrector step of the runtime from t to t + h, its start
   kept in sq, sqd, sqdd; *quiet says whether it passed the check. A step
   that meets a singular Jacobian is redone by rank_step. */
MechrtStatus run_checked_step(Run *r, double t, double h, MechrtReport *rep, bool *quiet,
                                 StepCheck *chk)
{
    memcpy(r->sq, r->q, 3 * (size_t)r->nq * sizeof(double));   /* q | qd | qdd */
    MechrtStatus st = run_step(r, t, h, rep);
    r->res->newton_iterations += rep->iterations;
    if (h != 0 && r->nq <= RUN_RANK_MAX_NQ && wants_rank(st, rep))
        st = rank_step(r, t, h, st, rep);
    *quiet = st == MECHRT_OK && step_quiet(r, h, rep, chk);
    if (*quiet)
        push_history(r, t);
    return st;
}

