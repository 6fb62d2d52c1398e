/* newton.c - Newton-Raphson assembly: solve the holonomic rows Phi(q, t) = 0.
 *
 * Decomposed like GSL's multiroot solvers (multiroots/newton.c): init binds
 * the state to the caller's q and workspace and evaluates Phi and Phi_q;
 * iterate takes one step; test checks convergence; run and mechrt_assemble
 * are the convenience loops on top. A caller that wants an iteration log
 * (mechc run reports the failing time and history) drives the three itself.
 *
 * Only the square case is handled: nh == nq. Velocity-level rows, if any,
 * come after the holonomic ones and play no part in assembly; the top nq x nq
 * block of the nr x nq Jacobian is the Newton matrix. With nh < nq Newton is
 * underdetermined and the host does minimum-norm Newton (SVD) instead.
 *
 * Workspace layout (mechrt_real elements, see MECHRT_WORKSPACE_LEN):
 * jac nr*nq | phi nr | nu nr | gamma nr | dq nq | qd0 nq | piv nq | cwork 2nq.
 */
#include <math.h>

#include "mechrt.h"

MechrtStatus mechrt_residual_inf(const mechrt_real *phi, int nh, mechrt_real *residual,
                                 int *worst_row)
{
    int i;

    *residual = 0;
    *worst_row = nh > 0 ? 0 : -1;
    for (i = 0; i < nh; i++) {
        /* only magnitudes are compared: the one-instruction |x| will do */
        mechrt_real a = MECHRT_LUP_ABS(phi[i]);
        if (!isfinite(a)) {
            *residual = a;
            *worst_row = i;
            return MECHRT_ENOTFINITE;
        }
        if (a > *residual) {
            *residual = a;
            *worst_row = i;
        }
    }
    return MECHRT_OK;
}

/* Phi and Phi_q at s->q: the `all` kernel when there is one (it shares sin,
   cos and products between them; nu comes for free), else phi then jac.
   Sets the residual norm and the worst row; NaN/Inf in Phi is an error. */
static MechrtStatus newton_eval(MechrtNewton *s)
{
    const MechrtKernels *k = s->k;
    if (k->all) {
        k->all(k->ctx, s->q, s->qd0, s->t, s->phi, s->jac, s->nu, s->gamma);
        s->have_nu = true;
    } else {
        k->phi(k->ctx, s->q, s->t, s->phi);
        k->jac(k->ctx, s->q, s->t, s->jac);
        s->have_nu = false;
    }
    return mechrt_residual_inf(s->phi, k->nh, &s->residual, &s->worst_row);
}

MechrtStatus mechrt_newton_init(MechrtNewton *s, const MechrtKernels *k,
                                const MechrtOptions *opts, mechrt_real *q, mechrt_real t,
                                mechrt_real *work, size_t lwork)
{
    size_t need, nq, nr;
    int i;

    if (!s)
        return MECHRT_EINVAL;
    s->k = k;
    s->opts = opts ? *opts : mechrt_default_options();
    s->q = q;
    s->t = t;
    s->phi = s->jac = s->nu = s->gamma = s->dq = s->qd0 = s->piv = s->cwork = NULL;
    s->have_nu = false;
    s->iter = 0;
    s->residual = 0;
    s->step = -1;
    s->worst_row = -1;
    s->sing_index = -1;
    s->factorisations = 0;

    if (!k || !q || !work || k->nq < 1 || k->nh < 0 || k->nv < 0
        || (!k->all && (!k->phi || !k->jac)))
        return MECHRT_EINVAL;
    if (k->nh != k->nq)
        return MECHRT_ENOTSQUARE;
    need = mechrt_workspace_size(k->nq, k->nh + k->nv);
    if (need == 0)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;

    nq = (size_t)k->nq;
    nr = (size_t)(k->nh + k->nv);
    s->jac = work;
    s->phi = s->jac + nr * nq;
    s->nu = s->phi + nr;
    s->gamma = s->nu + nr;
    s->dq = s->gamma + nr;
    s->qd0 = s->dq + nq;
    s->piv = s->qd0 + nq;
    s->cwork = s->piv + nq;
    for (i = 0; i < k->nq; i++)
        s->qd0[i] = 0;
    return newton_eval(s);
}

/* One Newton step on the square holonomic system:
 *   Phi_q(q_k) dq = -Phi(q_k),  q_{k+1} = q_k + dq,
 * with Phi_q factored in place by mechrt_lu_factor (partial pivoting), then
 * Phi and Phi_q evaluated at q_{k+1} for the test and the next step.
 * Quadratic convergence near a regular solution: Kelley, Iterative Methods
 * for Linear and Nonlinear Equations, SIAM 1995, ch. 5; in kinematics,
 * Haug, Computer-Aided Kinematics and Dynamics of Mechanical Systems, 1989,
 * section 4.4.
 */
MechrtStatus mechrt_newton_iterate(MechrtNewton *s)
{
    int n, i;
    mechrt_real step = 0;
    MechrtStatus st;

    if (!s || !s->jac)
        return MECHRT_EINVAL;
    n = s->k->nq;
    st = mechrt_lu_factor(n, s->jac, n, s->piv, s->opts.pivot_tol, &s->sing_index);
    s->factorisations++;
    if (st != MECHRT_OK)
        return st;
    for (i = 0; i < n; i++)
        s->dq[i] = -s->phi[i];
    mechrt_lu_solve(n, s->jac, n, s->piv, s->dq);
    for (i = 0; i < n; i++) {
        mechrt_real a = MECHRT_FABS(s->dq[i]);
        if (!isfinite(a))   /* overflow in a nearly singular solve */
            return MECHRT_ENOTFINITE;
        if (a > step)
            step = a;
    }
    for (i = 0; i < n; i++)
        s->q[i] += s->dq[i];
    s->step = step;
    s->iter++;
    return newton_eval(s);
}

/* Both norms must be small: the residual alone could stop early where
   Phi_q is ill-conditioned, the step alone says nothing before one is taken. */
MechrtStatus mechrt_newton_test(const MechrtNewton *s)
{
    if (!s)
        return MECHRT_EINVAL;
    if (s->step < 0)
        return MECHRT_CONTINUE;
    if (s->residual <= s->opts.tol_phi && s->step <= s->opts.tol_dq)
        return MECHRT_OK;
    return MECHRT_CONTINUE;
}

static void newton_report(const MechrtNewton *s, MechrtReport *report)
{
    if (!report)
        return;
    report->iterations = s->iter;
    report->residual = s->residual;
    report->step = s->step;
    report->worst_row = s->worst_row;
    report->sing_index = s->sing_index;
    report->cond = 0;
    report->cond_warning = false;
    report->factorisations = s->factorisations;
}

MechrtStatus mechrt_newton_run(MechrtNewton *s, MechrtReport *report)
{
    MechrtStatus st;

    if (!s || !s->jac)
        return MECHRT_EINVAL;
    for (;;) {
        st = mechrt_newton_test(s);
        if (st != MECHRT_CONTINUE)
            break;
        if (s->iter >= s->opts.max_iter) {
            st = MECHRT_EMAXITER;
            break;
        }
        st = mechrt_newton_iterate(s);
        if (st != MECHRT_OK)
            break;
    }
    newton_report(s, report);
    return st;
}

MechrtStatus mechrt_assemble(const MechrtKernels *k, const MechrtOptions *opts,
                             mechrt_real *q, mechrt_real t,
                             mechrt_real *work, size_t lwork, MechrtReport *report)
{
    MechrtNewton s;
    MechrtStatus st = mechrt_newton_init(&s, k, opts, q, t, work, lwork);

    if (st != MECHRT_OK) {
        newton_report(&s, report);
        return st;
    }
    return mechrt_newton_run(&s, report);
}
