/* sparse_step.c - one kinematic time step (predictor, Newton, velocity, acceleration) on the sparse Jacobian.
 *
 * mechrt_step of runtime/analysis.c with its dense LU replaced by KLU
 * (sparse_klu.c): the same predictor, the same Newton iteration and
 * convergence test (one factorisation per iteration: the refactorisation
 * is cheap, and a chord iteration that kept an old one would change the
 * iteration counts that run's branch check relies on, so the two paths
 * step alike), then one factorisation at the converged q for the velocity
 * and the acceleration, with the same condition screen and estimate -
 * unless Newton's last correction was below SPARSE_REUSE_STEP, where the
 * last iteration's factorisation serves (at N = 1000, 2.8 factorisations
 * a step become 1.8). Phi
 * and the Jacobian's nonzeros come from one all_nz call where the kernels
 * have it (nu comes with them: the last one, at the converged q, serves;
 * gamma needs the new velocities and is called after), else from the phi
 * and jac_nz kernels: nothing of size nr x nq is ever formed.
 */
#include "mechrt_host.h"

#include <math.h>
#include <string.h>

/* Newton's last correction at most this (in every coordinate): the
   factorisation of its iteration, at a q this near the converged one,
   serves the velocity and the acceleration (their relative change is of
   the order of the correction times the condition number: 1e-14 where
   the correction is 1e-14, as the second of two iterations' usually is),
   instead of a refactorisation at the converged q. */
#define SPARSE_REUSE_STEP 1e-12
/* ... while the pivots' spread max|u_kk| / min|u_kk| (a lower bound of the
   condition number) stays below this. */
#define SPARSE_REUSE_SPREAD 1e3

/* Where the fused kernel writes what a Newton evaluation does not need:
   nu (kept: the last one is at the converged q) and gamma (at the old qd). */
typedef struct SpExtra {
    const double *qd;
    double *nu, *gamma;
    bool have_nu;
} SpExtra;

/* Phi and the Jacobian's nonzeros at q; the residual norm and worst row
   into r. NaN or Inf in Phi is an error. */
static MechrtStatus sp_eval(MechrtHostSparse *s, const MechrtKernels *k, const double *q,
                            double t, double *phi, SpExtra *x, MechrtReport *r)
{
    x->have_nu = mechrt_host_sparse_eval_all(s, q, x->qd, t, phi, x->nu, x->gamma);
    if (!x->have_nu) {
        k->phi(k->ctx, q, t, phi);
        mechrt_host_sparse_eval(s, q, t);
    }
    return mechrt_residual_inf(phi, k->nh, &r->residual, &r->worst_row);
}

/* A factorisation counted in r; a failing pivot's column in sing_index. */
static MechrtStatus sp_factor(MechrtHostSparse *s, const MechrtOptions *o, MechrtReport *r)
{
    int row, col;
    MechrtStatus st = mechrt_host_sparse_factor(s, o->pivot_tol);
    r->factorisations++;
    mechrt_host_sparse_singular(s, &row, &col);
    r->sing_index = col;
    return st;
}

/* Newton on Phi(q, t) = 0 from q (updated in place), stopping as
   mechrt_newton_run does. */
static MechrtStatus sp_newton(MechrtHostSparse *s, const MechrtKernels *k, const MechrtOptions *o,
                              double *q, double t, double *phi, double *dq, SpExtra *x,
                              MechrtReport *r)
{
    int n = k->nq;
    MechrtStatus st = sp_eval(s, k, q, t, phi, x, r);
    if (st != MECHRT_OK)
        return st;
    for (;;) {
        if (r->step >= 0 && r->residual <= o->tol_phi && r->step <= o->tol_dq)
            return MECHRT_OK;
        if (r->iterations >= o->max_iter)
            return MECHRT_EMAXITER;
        if ((st = sp_factor(s, o, r)) != MECHRT_OK)
            return st;
        for (int i = 0; i < n; i++)
            dq[i] = -phi[i];
        if (mechrt_host_sparse_solve(s, dq) != MECHRT_OK)
            return MECHRT_ENOTFINITE;   /* overflow in a nearly singular solve */
        double step = 0;
        for (int i = 0; i < n; i++) {
            q[i] += dq[i];
            step = fabs(dq[i]) > step ? fabs(dq[i]) : step;
        }
        r->step = step;
        r->iterations++;
        if ((st = sp_eval(s, k, q, t, phi, x, r)) != MECHRT_OK)
            return st;
    }
}

/* Factors the Jacobian last evaluated (reuse: keeps the last
   factorisation), with the condition estimate of an_factor
   (runtime/analysis.c): screened by the pivot spread. */
static MechrtStatus sp_factor_cond(MechrtHostSparse *s, const MechrtOptions *o, MechrtReport *r,
                                   bool reuse)
{
    MechrtStatus st = reuse ? MECHRT_OK : sp_factor(s, o, r);
    if (st != MECHRT_OK || !(o->cond_warn > 0))
        return st;
    if (o->cond_screen > 0 && mechrt_host_sparse_spread(s) <= o->cond_screen * o->cond_warn)
        return MECHRT_OK;
    r->cond = mechrt_host_sparse_condest(s);
    r->cond_warning = !(r->cond <= o->cond_warn);   /* NaN warns too */
    return MECHRT_OK;
}

MechrtStatus mechrt_host_sparse_step(MechrtHostSparse *s, const MechrtKernels *k,
                                     const MechrtOptions *opts, double *q, double *qd,
                                     double *qdd, double t, double h, double *work, size_t lwork,
                                     MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    MechrtReport dummy;
    MechrtReport *r = report ? report : &dummy;
    mechrt_report_clear(r);
    if (!s || !k || !k->phi || !k->nu || !k->gamma || !q || !qd || !qdd || !work || !isfinite(h))
        return MECHRT_EINVAL;
    if (k->nh != k->nq || k->nv != 0)
        return MECHRT_ENOTSQUARE;
    int n = k->nq;
    if (lwork < MECHRT_HOST_SPARSE_WORK_LEN(n))
        return MECHRT_EBADLEN;
    double *phi = work, *rhs = work + n;
    SpExtra x = {qd, work + 2 * n, work + 3 * n, false};
    if (h != 0)
        for (int i = 0; i < n; i++)
            q[i] += h * qd[i] + 0.5 * h * h * qdd[i];
    double tn = t + h;
    MechrtStatus st = sp_newton(s, k, &o, q, tn, phi, rhs, &x, r);
    if (st != MECHRT_OK)
        return st;
    /* near a singular position (the pivots spread past the condition
       screen) the change would be large: factor at the converged q */
    bool reuse = r->iterations > 0 && r->step <= SPARSE_REUSE_STEP
                 && mechrt_host_sparse_spread(s) <= SPARSE_REUSE_SPREAD;
    if ((st = sp_factor_cond(s, &o, r, reuse)) != MECHRT_OK)
        return st;
    if (x.have_nu)
        memcpy(qd, x.nu, (size_t)n * sizeof *qd);
    else
        k->nu(k->ctx, q, tn, qd);
    if ((st = mechrt_host_sparse_solve(s, qd)) != MECHRT_OK)
        return st;
    k->gamma(k->ctx, q, qd, tn, qdd);   /* gamma needs the velocities just found */
    return mechrt_host_sparse_solve(s, qdd);
}

MechrtStatus mechrt_host_sparse_velocity(MechrtHostSparse *s, const MechrtKernels *k,
                                         const MechrtOptions *opts, const double *q, double t,
                                         double *qd, double *qdd, double *work,
                                         MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    MechrtReport dummy;
    MechrtReport *r = report ? report : &dummy;
    mechrt_report_clear(r);
    if (!s || !k || !k->nu || !k->gamma || !q || !qd || !work)
        return MECHRT_EINVAL;
    int n = k->nq;
    double *zero = work, *phi = work + n, *gamma = work + 2 * n;
    memset(zero, 0, (size_t)n * sizeof *zero);
    /* the fused kernel's gamma (at qd = 0) is not used: gamma needs the
       velocities solved for */
    if (!mechrt_host_sparse_eval_all(s, q, zero, t, phi, qd, gamma)) {
        mechrt_host_sparse_eval(s, q, t);
        k->nu(k->ctx, q, t, qd);
    }
    MechrtStatus st = sp_factor_cond(s, &o, r, false);
    if (st != MECHRT_OK || (st = mechrt_host_sparse_solve(s, qd)) != MECHRT_OK || !qdd)
        return st;
    k->gamma(k->ctx, q, qd, t, qdd);
    return mechrt_host_sparse_solve(s, qdd);
}
