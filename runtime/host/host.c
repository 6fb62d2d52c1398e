/* host.c - minimum-norm Gauss-Newton projection and position integration, on GSL.
 *
 * A mechanism with velocity-level rows (rolling, knife edges, velocity
 * drivers) has nh holonomic rows Phi(q, t) = 0 and nv Pfaffian rows
 * A(q, t) qd = b, nh + nv = nq. Its velocities come from the square system
 * [Phi_q; A] qd = nu, its positions only by integrating q' = qd(q, t)
 * (Haug, Computer-Aided Kinematics and Dynamics of Mechanical Systems, 1989,
 * ch. 7; the velocity rows need not be integrable). The integrator keeps
 * Phi constant only to its tolerance, so after every accepted step q is
 * projected back onto Phi = 0 (coordinate projection: Hairer & Wanner,
 * Solving ODEs II, section VII.2; Eich, SIAM J. Numer. Anal. 30, 1993).
 * With nh < nq that projection is underdetermined; each Gauss-Newton step
 * takes the minimum-norm correction, which moves q least (Ben-Israel's
 * Newton method for underdetermined systems).
 *
 * Workspaces are allocated once in mechrt_host_new; the calls per step
 * allocate nothing. mechrt_host_new_sparse keeps no dense matrix: its
 * velocity solves are KLU's (sparse_klu.c) and its projection steps
 * SuiteSparseQR's minimum-norm ones (sparse_qr.c, which allocates its
 * factors per step, as SuiteSparseQR does). GSL's error handler (abort by default) is switched off
 * around every GSL call and restored afterwards: failures come back as
 * statuses, never as an abort.
 */
#include "mechrt_host.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

struct MechrtHost {
    const MechrtKernels *k;
    int nq, nh, nr;
    double *work;               /* the core runtime's workspace */
    size_t lwork;
    double *phi;                /* nh (at least 1) */
    double *jac;                /* nr * nq */
    double *dq, *y;             /* nq each */
    double *qbest;              /* nq: a failed projection's best iterate */
    MechrtSvd *svd;             /* nh x nq (svd.c) */
    /* the sparse host (mechrt_host_new_sparse): no jac, svd or dense work */
    MechrtHostSparse *sp;       /* KLU of [Phi_q; A] (sparse_klu.c) */
    MechrtHostMinNorm *mn;      /* SuiteSparseQR of Phi_q^T (sparse_qr.c) */
    /* integration */
    gsl_odeiv2_step *step;
    MechrtOdeMethod step_method;
    gsl_odeiv2_control *control;
    gsl_odeiv2_evolve *evolve;
    MechrtOptions rhs_opts;     /* the caller's, condition estimate off */
    MechrtStatus fail_status;   /* set by the right-hand side on failure */
    double fail_t;
    double *fail_q;             /* nq */
    MechrtHostStats stats;
};

MechrtOdeOptions mechrt_ode_default_options(void)
{
    MechrtOdeOptions o = {MECHRT_ODE_RK8PD, 1e-10};
    return o;
}

bool mechrt_ode_method_from_name(const char *name, MechrtOdeMethod *out)
{
    if (strcmp(name, "rk8pd") == 0)
        *out = MECHRT_ODE_RK8PD;
    else if (strcmp(name, "rkf45") == 0)
        *out = MECHRT_ODE_RKF45;
    else
        return false;
    return true;
}

static const gsl_odeiv2_step_type *ode_type(MechrtOdeMethod m)
{
    switch (m) {
    case MECHRT_ODE_RK8PD: return gsl_odeiv2_step_rk8pd;
    case MECHRT_ODE_RKF45: return gsl_odeiv2_step_rkf45;
    }
    return gsl_odeiv2_step_rk8pd;
}

void mechrt_host_free(MechrtHost *h)
{
    if (!h)
        return;
    free(h->work);
    free(h->phi);
    free(h->jac);
    free(h->dq);
    free(h->y);
    free(h->qbest);
    free(h->fail_q);
    mechrt_svd_free(h->svd);
    mechrt_host_sparse_free(h->sp);
    mechrt_host_minnorm_free(h->mn);
    if (h->step)
        gsl_odeiv2_step_free(h->step);
    if (h->control)
        gsl_odeiv2_control_free(h->control);
    if (h->evolve)
        gsl_odeiv2_evolve_free(h->evolve);
    free(h);
}

/* The host of k with its dense workspaces (jnz NULL), its sparse
   factorisations, or (project_only, jnz set) only the sparse projection. */
static MechrtHost *host_new(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                            bool project_only)
{
    if (!k || k->nq < 1 || k->nh < 0 || k->nv < 0 || k->nh > k->nq
        || (jnz && !project_only && k->nh + k->nv != k->nq))
        return NULL;
    MechrtHost *h = calloc(1, sizeof *h);
    if (!h)
        return NULL;
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    size_t nq = (size_t)k->nq, nh = (size_t)k->nh;
    h->k = k;
    h->nq = k->nq;
    h->nh = k->nh;
    h->nr = k->nh + k->nv;
    /* sparse: mechrt_host_sparse_velocity's 3 nq */
    h->lwork = project_only ? 0
               : jnz ? 3 * nq : mechrt_workspace_size(k->nq, h->nr > k->nq ? h->nr : k->nq);
    h->work = h->lwork ? malloc(h->lwork * sizeof *h->work) : NULL;
    h->phi = malloc((nh + 1) * sizeof *h->phi);
    h->jac = jnz ? NULL : malloc((size_t)h->nr * nq * sizeof *h->jac + 1);
    h->dq = malloc(nq * sizeof *h->dq);
    h->y = malloc(nq * sizeof *h->y);
    h->qbest = malloc(nq * sizeof *h->qbest);
    h->fail_q = calloc(nq, sizeof *h->fail_q);
    bool ok = (h->work || project_only) && h->phi && (jnz || h->jac) && h->dq && h->y
              && h->qbest && h->fail_q;
    if (ok && jnz) {
        h->sp = project_only ? NULL : mechrt_host_sparse_new(k->nq, jnz);
        h->mn = nh > 0 ? mechrt_host_minnorm_new(k->nh, k->nq, jnz) : NULL;
        ok = (h->sp || project_only) && (nh == 0 || h->mn);
    } else if (ok && nh > 0) {
        h->svd = mechrt_svd_new(k->nh, k->nq);
        ok = h->svd != NULL;
    }
    if (ok) {
        h->evolve = gsl_odeiv2_evolve_alloc(nq);
        h->control = gsl_odeiv2_control_y_new(1e-10, 1e-10);
        ok = h->evolve && h->control;
    }
    gsl_set_error_handler(old);
    if (!ok) {
        mechrt_host_free(h);
        return NULL;
    }
    return h;
}

MechrtHost *mechrt_host_new(const MechrtKernels *k)
{
    return host_new(k, NULL, false);
}

MechrtHost *mechrt_host_new_sparse(const MechrtKernels *k, const MechrtHostJacNz *jnz)
{
    return jnz ? host_new(k, jnz, false) : NULL;
}

MechrtHost *mechrt_host_new_projector(const MechrtKernels *k, const MechrtHostJacNz *jnz)
{
    return jnz ? host_new(k, jnz, true) : NULL;
}

MechrtHostSparse *mechrt_host_sparse_of(MechrtHost *h)
{
    return h ? h->sp : NULL;
}

MechrtStatus mechrt_host_velocity_acceleration(MechrtHost *h, const MechrtOptions *o,
                                               const double *q, double t, double *qd,
                                               double *qdd, MechrtReport *report)
{
    if (!h->work)
        return MECHRT_EINVAL;   /* a projector: no velocity solve */
    if (h->sp)
        return mechrt_host_sparse_velocity(h->sp, h->k, o, q, t, qd, qdd, h->work, report);
    return mechrt_velocity_acceleration(h->k, o, q, t, qd, qdd, h->work, h->lwork, report);
}

const MechrtHostStats *mechrt_host_stats(const MechrtHost *h) { return &h->stats; }

const double *mechrt_host_failure(const MechrtHost *h, double *t)
{
    if (t)
        *t = h->fail_t;
    return h->fail_q;
}

/* ||Phi(q, t)||_inf over the holonomic rows, with the worst row. */
static MechrtStatus eval_phi(MechrtHost *h, const double *q, double t, double *residual,
                             int *worst)
{
    const MechrtKernels *k = h->k;
    k->phi(k->ctx, q, t, h->phi);
    *residual = 0;
    *worst = h->nh > 0 ? 0 : -1;
    for (int i = 0; i < h->nh; i++) {
        double a = fabs(h->phi[i]);
        if (!isfinite(a)) {
            *residual = a;
            *worst = i;
            return MECHRT_ENOTFINITE;
        }
        if (a > *residual) {
            *residual = a;
            *worst = i;
        }
    }
    return MECHRT_OK;
}

/* One minimum-norm Gauss-Newton step for Phi_q dq = -Phi (nh x nq, nh <= nq):
 * dq = -pinv(Phi_q) Phi from the SVD (svd.c), the pseudo-inverse inverting
 * only the singular values above pivot_tol * sigma_max (Golub & Van Loan,
 * 4th ed., section 5.5.4). h->phi holds Phi at q. */
static MechrtStatus min_norm_step(MechrtHost *h, const MechrtOptions *o, const double *q,
                                  double t)
{
    const MechrtKernels *k = h->k;
    MechrtSvdResult sv;
    if (h->mn)
        return mechrt_host_minnorm_step(h->mn, q, t, h->phi, o->pivot_tol, h->dq);
    k->jac(k->ctx, q, t, h->jac);
    if (!mechrt_svd(h->svd, h->jac, h->nh, h->nq, h->nq, -1, &sv))
        return MECHRT_ENOTFINITE;
    if (!(sv.sigma_max > 0))
        return MECHRT_ESING;   /* Phi_q = 0: no direction to move in */
    mechrt_svd_truncate(h->svd, o->pivot_tol * sv.sigma_max);
    mechrt_svd_pinv_solve(h->svd, h->phi, h->dq);
    for (int j = 0; j < h->nq; j++)
        h->dq[j] = -h->dq[j];
    return MECHRT_OK;
}

static MechrtStatus project(MechrtHost *h, const MechrtOptions *o, double *q, double t,
                            MechrtReport *r)
{
    MechrtReport rep = {0, 0, -1, -1, -1, 0, false, 0, 0, 0};
    MechrtStatus st;
    h->stats.projections++;
    if (h->nh == 0) {
        if (r)
            *r = rep;
        return MECHRT_OK;
    }
    MechrtReport best = {0};
    best.residual = INFINITY;
    for (;;) {
        st = eval_phi(h, q, t, &rep.residual, &rep.worst_row);
        if (st != MECHRT_OK)
            break;
        if (rep.residual < best.residual) {
            best = rep;
            memcpy(h->qbest, q, (size_t)h->nq * sizeof *q);
        }
        if (rep.step >= 0 && rep.residual <= o->tol_phi && rep.step <= o->tol_dq)
            break;
        if (rep.iterations >= o->max_iter) {
            st = MECHRT_EMAXITER;
            break;
        }
        st = min_norm_step(h, o, q, t);
        if (st != MECHRT_OK)
            break;
        double step = 0;
        for (int j = 0; j < h->nq; j++) {
            if (!isfinite(h->dq[j])) {
                st = MECHRT_ENOTFINITE;
                break;
            }
            q[j] += h->dq[j];
            if (fabs(h->dq[j]) > step)
                step = fabs(h->dq[j]);
        }
        if (st != MECHRT_OK)
            break;
        rep.step = step;
        rep.iterations++;
        h->stats.project_iterations++;
    }
    /* out of iterations or off to NaN: the iterate with the smallest
       residual, not wherever the full steps had carried Newton */
    if ((st == MECHRT_EMAXITER || st == MECHRT_ENOTFINITE) && !(rep.residual <= best.residual)) {
        memcpy(q, h->qbest, (size_t)h->nq * sizeof *q);
        rep.residual = best.residual;
        rep.worst_row = best.worst_row;
    }
    if (r)
        *r = rep;
    return st;
}

MechrtStatus mechrt_host_project(MechrtHost *h, const MechrtOptions *o, double *q, double t,
                                 MechrtReport *report)
{
    MechrtOptions def = mechrt_default_options();
    if (!h || !q)
        return MECHRT_EINVAL;
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    MechrtStatus st = project(h, o ? o : &def, q, t, report);
    gsl_set_error_handler(old);
    return st;
}

/* q' = qd(q, t) for GSL: the velocity solve of the square system. A failure
   (singular [Phi_q; A], NaN) is kept with its time and state, and reported
   as GSL_EBADFUNC, which stops the integrator at once. */
/* Where and why the integration stopped (mechrt_host_failure). */
static void record_failure(MechrtHost *h, MechrtStatus st, double t, const double *q)
{
    h->fail_status = st;
    h->fail_t = t;
    memcpy(h->fail_q, q, (size_t)h->nq * sizeof *q);
}

static int ode_rhs(double t, const double y[], double dydt[], void *params)
{
    MechrtHost *h = params;
    h->stats.rhs_calls++;
    MechrtReport rep;
    MechrtStatus st = h->sp ? mechrt_host_sparse_velocity(h->sp, h->k, &h->rhs_opts, y, t, dydt,
                                                          NULL, h->work, &rep)
                            : mechrt_velocity(h->k, &h->rhs_opts, y, t, dydt, h->work, h->lwork,
                                              &rep);
    if (st == MECHRT_OK)
        return GSL_SUCCESS;
    if (h->fail_status == MECHRT_OK)
        record_failure(h, st, t, y);
    return GSL_EBADFUNC;
}

/* The stepper of oo's method (a new one when the method changed), the
   control and the evolution reset for a fresh integration. */
static MechrtStatus ode_prepare(MechrtHost *h, const MechrtOdeOptions *oo)
{
    if (!h->step || h->step_method != oo->method) {
        if (h->step)
            gsl_odeiv2_step_free(h->step);
        h->step = gsl_odeiv2_step_alloc(ode_type(oo->method), (size_t)h->nq);
        h->step_method = oo->method;
        if (!h->step)
            return MECHRT_EINVAL;
    }
    gsl_odeiv2_control_init(h->control, oo->tol, oo->tol, 1.0, 0.0);
    gsl_odeiv2_evolve_reset(h->evolve);
    gsl_odeiv2_step_reset(h->step);
    return MECHRT_OK;
}

MechrtStatus mechrt_host_integrate(MechrtHost *h, const MechrtOptions *o,
                                   const MechrtOdeOptions *oo, double *q, double *t,
                                   double t_end, double *hstep, MechrtReport *report)
{
    MechrtOptions def = mechrt_default_options();
    MechrtOdeOptions odef = mechrt_ode_default_options();
    if (!h || !q || !t || !hstep || !isfinite(*t) || !isfinite(t_end))
        return MECHRT_EINVAL;
    if (h->nr != h->nq)
        return MECHRT_ENOTSQUARE;
    if (!h->work)
        return MECHRT_EINVAL;   /* a projector */
    o = o ? o : &def;
    oo = oo ? oo : &odef;
    if (!(oo->tol > 0))
        return MECHRT_EINVAL;
    if (report)
        *report = (MechrtReport){0, 0, -1, -1, -1, 0, false, 0, 0, 0};
    if (*t == t_end)
        return MECHRT_OK;

    gsl_error_handler_t *old = gsl_set_error_handler_off();
    MechrtStatus st = ode_prepare(h, oo);
    h->rhs_opts = *o;
    h->rhs_opts.cond_warn = 0;   /* estimates are for the output times */
    h->fail_status = MECHRT_OK;

    double dir = t_end > *t ? 1.0 : -1.0, hh = *hstep;
    if (!(hh * dir > 0) || !isfinite(hh) || fabs(hh) > fabs(t_end - *t))
        hh = t_end - *t;
    gsl_odeiv2_system sys = {ode_rhs, NULL, (size_t)h->nq, h};
    while (st == MECHRT_OK && *t * dir < t_end * dir) {
        int gs = gsl_odeiv2_evolve_apply(h->evolve, h->control, h->step, &sys, t, t_end, &hh, q);
        if (gs != GSL_SUCCESS) {
            /* not the right-hand side: step size underflow, where the
               integrator gave up */
            if (h->fail_status == MECHRT_OK)
                record_failure(h, MECHRT_ESTEP, *t, q);
            st = h->fail_status;
            break;
        }
        h->stats.ode_steps++;
        MechrtReport pr;
        memcpy(h->y, q, (size_t)h->nq * sizeof *q);
        st = project(h, o, h->y, *t, &pr);
        if (report && pr.iterations > report->iterations)
            *report = pr;   /* the hardest projection of the call */
        if (st != MECHRT_OK) {
            record_failure(h, st, *t, h->y);
            if (report)
                *report = pr;
            break;
        }
        memcpy(q, h->y, (size_t)h->nq * sizeof *q);
    }
    h->stats.ode_rejected += (long)h->evolve->failed_steps;
    *hstep = hh;
    if (st != MECHRT_OK)
        *t = h->fail_t;
    gsl_set_error_handler(old);
    return st;
}
