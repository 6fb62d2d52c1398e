/* rank.c - the corrector of a kinematic step through a singular position (minimum-change solutions).
 *
 * At a change point (a parallelogram four-bar folding flat: the chain's
 * DOF jumps, every loop may turn into its crossed form) Phi_q loses rank,
 * and Phi(q, t) = 0, Phi_q qd = nu, Phi_q qdd = gamma each have a family
 * of solutions. The motion is the one that goes on smoothly, and the
 * prediction from the previous steps follows it; so each correction here is
 * the least one (minimum norm, from rank-revealing QR, qr.c): Newton's
 * steps move q the least, and the velocity and the acceleration are the
 * solutions nearest their predictions,
 *   qd  = qd_pred  + pinv(Phi_q) (nu    - Phi_q qd_pred),
 *   qdd = qdd_pred + pinv(Phi_q) (gamma - Phi_q qdd_pred).
 * Along the directions the Jacobian does see, that is the exact solution,
 * as mechrt_step's; along the lost ones, the prediction's value. How good
 * the prediction is decides the accuracy there: the caller's job (mechc
 * run extrapolates the acceleration by a cubic through four states).
 * The residual the solves leave (`inconsistency`) says whether the
 * continued velocity was one the mechanism can have: small on a branch,
 * large where the motion cannot go on (or the prediction is far off).
 *
 * Workspace (mechrt_rank_workspace_size(n) reals): jac n*n | rhs n |
 * x n | phi n | dq n | QR mechrt_qr_work_len(n, n).
 */
#include <math.h>

#include "mechrt.h"

typedef struct RankWork {
    mechrt_real *jac, *rhs, *x, *phi, *dq, *qr;
    size_t lqr;
} RankWork;

size_t mechrt_rank_workspace_size(int nq)
{
    size_t n, lqr = mechrt_qr_work_len(nq, nq);

    if (lqr == 0)
        return 0;
    n = (size_t)nq;
    if (lqr > (size_t)-1 - n * n - 4u * n)
        return 0;
    return n * n + 4u * n + lqr;
}

/* max_i |v_i|; NaN propagates (the comparison fails, so it is kept). */
static mechrt_real rk_norm(int n, const mechrt_real *v)
{
    mechrt_real m = 0;
    int i;

    for (i = 0; i < n; i++) {
        mechrt_real a = MECHRT_FABS(v[i]);
        if (!(a <= m))
            m = a;
    }
    return m;
}

/* Phi at q into w->phi: the residual and the worst row into r. */
static MechrtStatus rk_phi(const MechrtKernels *k, const mechrt_real *q, mechrt_real t,
                           RankWork *w, MechrtReport *r)
{
    k->phi(k->ctx, q, t, w->phi);
    return mechrt_residual_inf(w->phi, k->nh, &r->residual, &r->worst_row);
}

/* Phi_q at q, factored by rank-revealing QR. */
static MechrtStatus rk_factor(const MechrtKernels *k, const MechrtOptions *o,
                              const mechrt_real *q, mechrt_real t, RankWork *w, MechrtQr *f,
                              MechrtReport *r)
{
    int n = k->nq;

    k->jac(k->ctx, q, t, w->jac);
    r->factorisations++;
    return mechrt_qr_factor(f, n, n, w->jac, n, o->rank_tol, w->qr, w->lqr);
}

/* Newton with minimum-norm steps on Phi(q, t) = 0 from q. A chord
   iteration on the factors of the predicted q (near a singular point the
   iterate moves by little, so they stay good), refactored when a step
   shrinks by less than half; stops as mechrt_newton_run does. */
static MechrtStatus rk_newton(const MechrtKernels *k, const MechrtOptions *o, mechrt_real *q,
                              mechrt_real t, RankWork *w, MechrtQr *f, MechrtReport *r)
{
    int n = k->nq, i;
    mechrt_real last = -1;
    MechrtStatus st = rk_factor(k, o, q, t, w, f, r);

    if (st == MECHRT_OK)
        st = rk_phi(k, q, t, w, r);
    while (st == MECHRT_OK) {
        mechrt_real step;
        if (r->step >= 0 && r->residual <= o->tol_phi && r->step <= o->tol_dq)
            return MECHRT_OK;
        if (r->iterations >= o->max_iter)
            return MECHRT_EMAXITER;
        if (last >= 0 && !(r->step <= MECHRT_R(0.5) * last)
            && (st = rk_factor(k, o, q, t, w, f, r)) != MECHRT_OK)
            return st;
        for (i = 0; i < n; i++)
            w->rhs[i] = -w->phi[i];
        mechrt_qr_solve(f, w->rhs, w->dq);
        step = rk_norm(n, w->dq);
        if (!isfinite(step))
            return MECHRT_ENOTFINITE;
        for (i = 0; i < n; i++)
            q[i] += w->dq[i];
        last = r->step;
        r->step = step;
        r->iterations++;
        st = rk_phi(k, q, t, w, r);
    }
    return st;
}

/* x <- x + pinv(J0) (rhs - J x), twice: J0 the factored Jacobian, J
   (in w->jac) the one at the solution, which differ by Newton's last
   steps; the second pass takes up what that difference left. Returns the
   residual's share ||rhs - J x|| / (||rhs|| + ||J|| (||x|| + extra)) after
   it (extra: what else the right side scales with, ||qd||^2 for gamma). */
static mechrt_real rk_nearest(int n, RankWork *w, const MechrtQr *f, const mechrt_real *rhs,
                              mechrt_real *x, mechrt_real extra)
{
    mechrt_real res = 0, jnorm = 0;
    int pass, i, j;

    for (pass = 0; pass < 3; pass++) {
        res = jnorm = 0;
        for (i = 0; i < n; i++) {
            const mechrt_real *row = w->jac + (size_t)i * (size_t)n;
            mechrt_real jx = 0, rs = 0;
            for (j = 0; j < n; j++) {
                jx += row[j] * x[j];
                rs += MECHRT_FABS(row[j]);
            }
            w->rhs[i] = rhs[i] - jx;
            if (!(MECHRT_FABS(w->rhs[i]) <= res))
                res = MECHRT_FABS(w->rhs[i]);
            if (rs > jnorm)
                jnorm = rs;
        }
        if (pass == 2)
            break;
        mechrt_qr_solve(f, w->rhs, w->dq);
        for (i = 0; i < n; i++)
            x[i] += w->dq[i];
    }
    extra += rk_norm(n, x);
    extra = rk_norm(n, rhs) + jnorm * extra;
    return extra > 0 ? res / extra : res;
}

MechrtStatus mechrt_rank_correct(const MechrtKernels *k, const MechrtOptions *opts,
                                 mechrt_real *q, mechrt_real *qd, mechrt_real *qdd,
                                 mechrt_real t, mechrt_real *work, size_t lwork,
                                 MechrtReport *report)
{
    MechrtOptions o = opts ? *opts : mechrt_default_options();
    MechrtReport dummy;
    MechrtReport *r = report ? report : &dummy;
    RankWork w;
    MechrtQr f;
    MechrtStatus st;
    size_t need, n;
    mechrt_real a, b;
    int i;

    mechrt_report_clear(r);
    if (!k || k->nq < 1 || !k->phi || !k->jac || !k->nu || !k->gamma || !q || !qd || !qdd
        || !work)
        return MECHRT_EINVAL;
    if (k->nh != k->nq || k->nv != 0)
        return MECHRT_ENOTSQUARE;
    need = mechrt_rank_workspace_size(k->nq);
    if (need == 0)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;
    n = (size_t)k->nq;
    w.jac = work;
    w.rhs = w.jac + n * n;
    w.x = w.rhs + n;
    w.phi = w.x + n;
    w.dq = w.phi + n;
    w.qr = w.dq + n;
    w.lqr = need - (n * n + 4u * n);

    for (i = 0; i < k->nq; i++)
        w.x[i] = q[i];
    st = rk_newton(k, &o, q, t, &w, &f, r);
    if (st != MECHRT_OK)
        return st;
    /* The factors are those of Newton's last factorisation; when Newton
       moved q by little from there (the prediction was good) the passes
       of rk_nearest take up the difference with the Jacobian at the
       solution, which the residuals use; else the solution's own. */
    for (i = 0; i < k->nq; i++)
        w.x[i] -= q[i];
    if (rk_norm(k->nq, w.x) > 100 * o.tol_dq) {
        if ((st = rk_factor(k, &o, q, t, &w, &f, r)) != MECHRT_OK)
            return st;
    } else {
        k->jac(k->ctx, q, t, w.jac);
    }
    r->rank_deficiency = k->nq - f.rank;
    k->nu(k->ctx, q, t, w.x);
    a = rk_nearest(k->nq, &w, &f, w.x, qd, 0);
    k->gamma(k->ctx, q, qd, t, w.x);
    b = rk_nearest(k->nq, &w, &f, w.x, qdd, rk_norm(k->nq, qd) * rk_norm(k->nq, qd));
    r->inconsistency = a > b ? a : b;
    if (!isfinite(rk_norm(k->nq, qd)) || !isfinite(rk_norm(k->nq, qdd)) || !isfinite(a + b))
        return MECHRT_ENOTFINITE;
    return MECHRT_OK;
}
