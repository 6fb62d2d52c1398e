/* analysis.c - velocity and acceleration analysis, and one kinematic time step.
 *
 * Differentiating Phi(q, t) = 0 once and twice in time gives two linear
 * systems with the same matrix (Haug, Computer-Aided Kinematics and Dynamics
 * of Mechanical Systems, 1989, sections 3.3 and 6.1):
 *   Phi_q qd  = nu    = -Phi_t,
 *   Phi_q qdd = gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt.
 * Velocity-level rows (rolling, knife edges) contribute rows of the same
 * form, so the matrix is the full nr x nq Jacobian, square when nr == nq.
 * One LU factorisation serves both solves. A mechanism without velocity
 * rows is stepped in time here (mechrt_step); with velocity rows the host
 * integrates q' = qd(q, t) and calls mechrt_velocity from its ODE right side.
 *
 * Workspace of the analysis-only calls, in mechrt_real elements (a prefix of
 * MECHRT_WORKSPACE_LEN(n, n)): jac n*n | rhs n | piv n | cwork 2n.
 * mechrt_step uses the Newton state's layout instead (newton.c).
 */
#include <math.h>

#include "mechrt.h"

typedef struct AnWork {
    mechrt_real *jac, *rhs, *piv, *cwork;
} AnWork;

void mechrt_report_clear(MechrtReport *r)
{
    if (!r)
        return;
    r->iterations = 0;
    r->residual = 0;
    r->step = -1;
    r->worst_row = -1;
    r->sing_index = -1;
    r->cond = 0;
    r->cond_warning = false;
    r->factorisations = 0;
    r->rank_deficiency = 0;
    r->inconsistency = 0;
}

static bool an_kernels_ok(const MechrtKernels *k)
{
    return k && k->nq >= 1 && k->nh >= 0 && k->nv >= 0 && k->jac && k->nu && k->gamma;
}

static bool an_all_finite(int n, const mechrt_real *v)
{
    int i;

    for (i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

/* Checks the kernels and the workspace and carves the workspace. */
static MechrtStatus an_setup(const MechrtKernels *k, mechrt_real *work, size_t lwork,
                             AnWork *w)
{
    size_t n, need;

    if (!an_kernels_ok(k) || !work)
        return MECHRT_EINVAL;
    if (k->nh + k->nv != k->nq)
        return MECHRT_ENOTSQUARE;
    need = mechrt_workspace_size(k->nq, k->nq);
    if (need == 0)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;
    n = (size_t)k->nq;
    w->jac = work;
    w->rhs = w->jac + n * n;
    w->piv = w->rhs + n;
    w->cwork = w->piv + n;
    return MECHRT_OK;
}

/* max|u_kk| / min|u_kk| over the diagonal of the LU factors (U has no zero
   pivot after a successful factorisation). Cheap: the screen of an_factor. */
static mechrt_real an_pivot_spread(int n, const mechrt_real *lu)
{
    mechrt_real lo = MECHRT_FABS(lu[0]), hi = lo;
    int k;

    for (k = 1; k < n; k++) {
        mechrt_real u = MECHRT_FABS(lu[(size_t)k * (size_t)n + (size_t)k]);
        if (u < lo)
            lo = u;
        if (u > hi)
            hi = u;
    }
    return hi / lo;
}

/* Factors the n x n Jacobian in place. When a report is wanted and
   cond_warn > 0, also estimates its 1-norm condition number if the pivot
   spread passes the screen (the norm must be taken before the factorisation
   overwrites the matrix). */
static MechrtStatus an_factor(int n, const MechrtOptions *o, mechrt_real *jac,
                              mechrt_real *piv, mechrt_real *cwork, MechrtReport *r)
{
    bool want_cond = r && o->cond_warn > 0;
    mechrt_real anorm = 0;
    int sing;
    MechrtStatus st = want_cond
        ? mechrt_lu_factor_norm1(n, jac, n, piv, o->pivot_tol, &sing, &anorm, cwork)
        : mechrt_lu_factor(n, jac, n, piv, o->pivot_tol, &sing);

    if (r) {
        r->sing_index = sing;
        r->factorisations++;
    }
    if (st != MECHRT_OK)
        return st;
    if (want_cond && o->cond_screen > 0
        && an_pivot_spread(n, jac) <= o->cond_screen * o->cond_warn)
        want_cond = false;
    if (want_cond) {
        r->cond = mechrt_lu_cond1(n, jac, n, piv, anorm, cwork);
        r->cond_warning = !(r->cond <= o->cond_warn);   /* NaN warns too */
    }
    return MECHRT_OK;
}

/* x = A^-1 b with A factored; b must be finite and x comes out finite. */
static MechrtStatus an_solve(int n, const mechrt_real *lu, const mechrt_real *piv,
                             const mechrt_real *b, mechrt_real *x)
{
    int i;

    if (!an_all_finite(n, b))
        return MECHRT_ENOTFINITE;
    for (i = 0; i < n; i++)
        x[i] = b[i];
    mechrt_lu_solve(n, lu, n, piv, x);
    return an_all_finite(n, x) ? MECHRT_OK : MECHRT_ENOTFINITE;
}

/* The start of every analysis-only call: checks the kernels and the
   workspace, evaluates the Jacobian and the right side at (q, t) (nu, or
   gamma when qd is given) and factors the Jacobian. */
static MechrtStatus an_prepare(const MechrtKernels *k, const MechrtOptions *o,
                               const mechrt_real *q, const mechrt_real *qd, mechrt_real t,
                               mechrt_real *work, size_t lwork, AnWork *w,
                               MechrtReport *report)
{
    MechrtStatus st = an_setup(k, work, lwork, w);

    if (st != MECHRT_OK)
        return st;
    k->jac(k->ctx, q, t, w->jac);
    if (qd)
        k->gamma(k->ctx, q, qd, t, w->rhs);
    else
        k->nu(k->ctx, q, t, w->rhs);
    return an_factor(k->nq, o, w->jac, w->piv, w->cwork, report);
}

MechrtStatus mechrt_velocity(const MechrtKernels *k, const MechrtOptions *opts,
                             const mechrt_real *q, mechrt_real t, mechrt_real *qd_out,
                             mechrt_real *work, size_t lwork, MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    AnWork w;
    MechrtStatus st;

    mechrt_report_clear(report);
    if (!q || !qd_out)
        return MECHRT_EINVAL;
    st = an_prepare(k, &o, q, NULL, t, work, lwork, &w, report);
    if (st != MECHRT_OK)
        return st;
    return an_solve(k->nq, w.jac, w.piv, w.rhs, qd_out);
}

MechrtStatus mechrt_acceleration(const MechrtKernels *k, const MechrtOptions *opts,
                                 const mechrt_real *q, const mechrt_real *qd, mechrt_real t,
                                 mechrt_real *qdd_out,
                                 mechrt_real *work, size_t lwork, MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    AnWork w;
    MechrtStatus st;

    mechrt_report_clear(report);
    if (!q || !qd || !qdd_out)
        return MECHRT_EINVAL;
    st = an_prepare(k, &o, q, qd, t, work, lwork, &w, report);
    if (st != MECHRT_OK)
        return st;
    return an_solve(k->nq, w.jac, w.piv, w.rhs, qdd_out);
}

MechrtStatus mechrt_velocity_acceleration(const MechrtKernels *k, const MechrtOptions *opts,
                                          const mechrt_real *q, mechrt_real t,
                                          mechrt_real *qd_out, mechrt_real *qdd_out,
                                          mechrt_real *work, size_t lwork,
                                          MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    AnWork w;
    MechrtStatus st;

    mechrt_report_clear(report);
    if (!q || !qd_out || !qdd_out)
        return MECHRT_EINVAL;
    st = an_prepare(k, &o, q, NULL, t, work, lwork, &w, report);
    if (st != MECHRT_OK)
        return st;
    st = an_solve(k->nq, w.jac, w.piv, w.rhs, qd_out);
    if (st != MECHRT_OK)
        return st;
    k->gamma(k->ctx, q, qd_out, t, w.rhs);   /* gamma needs the velocities just found */
    return an_solve(k->nq, w.jac, w.piv, w.rhs, qdd_out);
}

/* One step of kinematic analysis from t to t + h (Haug 1989, section 6.1):
 *   predictor  q <- q + h qd + h^2/2 qdd   (second-order Taylor; error O(h^3)
 *                                          keeps Newton to one or two steps),
 *   corrector  Newton on Phi(q, t + h) = 0,
 *   velocity   Phi_q qd = nu      } one LU of the Jacobian at the converged q,
 *   accel.     Phi_q qdd = gamma  } which Newton has just evaluated.
 */
MechrtStatus mechrt_step(const MechrtKernels *k, const MechrtOptions *opts,
                         mechrt_real *q, mechrt_real *qd, mechrt_real *qdd,
                         mechrt_real t, mechrt_real h,
                         mechrt_real *work, size_t lwork, MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    MechrtNewton s;
    MechrtStatus st;
    mechrt_real tn;
    size_t need;
    int i, n;

    mechrt_report_clear(report);
    if (!an_kernels_ok(k) || !q || !qd || !qdd || !work || !isfinite(h))
        return MECHRT_EINVAL;
    if (k->nh != k->nq || k->nv != 0)
        return MECHRT_ENOTSQUARE;
    n = k->nq;
    /* checked here too, before the predictor touches q */
    need = mechrt_workspace_size(n, n);
    if (need == 0)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;
    if (h != 0)
        for (i = 0; i < n; i++)
            q[i] += h * qd[i] + MECHRT_R(0.5) * h * h * qdd[i];
    tn = t + h;

    st = mechrt_newton_init(&s, k, &o, q, tn, work, lwork);
    if (st != MECHRT_OK) {
        if (report) {
            report->residual = s.residual;
            report->worst_row = s.worst_row;
        }
        return st;
    }
    st = mechrt_newton_run(&s, report);
    if (st != MECHRT_OK)
        return st;

    if (!s.have_nu)
        k->nu(k->ctx, q, tn, s.nu);
    st = an_factor(n, &o, s.jac, s.piv, s.cwork, report);
    if (st != MECHRT_OK)
        return st;
    st = an_solve(n, s.jac, s.piv, s.nu, qd);
    if (st != MECHRT_OK)
        return st;
    k->gamma(k->ctx, q, qd, tn, s.gamma);
    return an_solve(n, s.jac, s.piv, s.gamma, qdd);
}
