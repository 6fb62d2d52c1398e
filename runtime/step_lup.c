/* step_lup.c - one kinematic time step (predictor, Newton, velocity, acceleration) on the pattern LU.
 *
 * mechrt_step of analysis.c with the dense LU replaced by the pattern LU
 * (lu_pattern.c), which gives the same factors: the same predictor, Newton
 * iteration, convergence test, analysis at the converged q with its
 * condition screen and estimate, and the same report, so a caller may
 * switch between the two without a bit of its output changing. With the
 * kernels' sparse Jacobian the Newton evaluations are phi and jac_nz (no
 * zero fill of an n x n matrix, no gather) and nu is called once at the
 * converged q; without it, `all` or phi and jac as in newton.c.
 *
 * Workspace: mechrt_workspace_size(nq, nq) reals, laid out as newton.c's:
 * jac n*n (the dense Jacobian; with jac_nz, whose values go straight into
 * the pattern LU, only the condition estimate's copy) | phi | nu | gamma |
 * dq | qd0 (n each) | the rest unused.
 */
#include <math.h>

#include "mechrt.h"

typedef struct Ls {
    const MechrtKernels *k;
    const MechrtJacNz *jnz;
    MechrtLup *f;
    const MechrtOptions *o;
    mechrt_real *q, t;
    mechrt_real *jac, *phi, *nu, *gamma, *dq, *qd0;
    bool have_nu;
    MechrtReport *r;
} Ls;

/* Phi and the Jacobian at s->q, the residual norm and worst row into the
   report (newton.c's newton_eval). */
static MechrtStatus ls_eval(Ls *s)
{
    const MechrtKernels *k = s->k;
    MechrtReport *r = s->r;
    if (s->jnz) {
        k->phi(k->ctx, s->q, s->t, s->phi);
        s->jnz->jac_nz(s->jnz->ctx, s->q, s->t, mechrt_lup_values(s->f));
        s->have_nu = false;
    } else if (k->all) {
        k->all(k->ctx, s->q, s->qd0, s->t, s->phi, s->jac, s->nu, s->gamma);
        s->have_nu = true;
    } else {
        k->phi(k->ctx, s->q, s->t, s->phi);
        k->jac(k->ctx, s->q, s->t, s->jac);
        s->have_nu = false;
    }
    return mechrt_residual_inf(s->phi, k->nh, &r->residual, &r->worst_row);
}

/* The Jacobian last evaluated, factored; counted in the report. */
static MechrtStatus ls_factor(Ls *s)
{
    MechrtStatus st = s->jnz
        ? mechrt_lup_factor(s->f, s->o->pivot_tol, &s->r->sing_index)
        : mechrt_lup_factor_dense(s->f, s->jac, s->k->nq, s->o->pivot_tol, &s->r->sing_index);
    s->r->factorisations++;
    return st;
}

/* Newton from s->q (mechrt_newton_run's loop and test). The solve gives
   x = Phi_q^-1 Phi = -dq exactly (a solve commutes with negation), and
   q - x is q + dq. */
static MechrtStatus ls_newton(Ls *s)
{
    MechrtReport *r = s->r;
    mechrt_real *x = s->dq, *q = s->q;
    int n = s->k->nq, i;
    MechrtStatus st = ls_eval(s);

    if (st != MECHRT_OK)
        return st;
    for (;;) {
        mechrt_real step = 0, chk = 0;
        if (r->step >= 0 && r->residual <= s->o->tol_phi && r->step <= s->o->tol_dq)
            return MECHRT_OK;
        if (r->iterations >= s->o->max_iter)
            return MECHRT_EMAXITER;
        if ((st = ls_factor(s)) != MECHRT_OK)
            return st;
        mechrt_lup_solve(s->f, s->phi, x);
        for (i = 0; i < n; i++) {
            mechrt_real a = MECHRT_LUP_ABS(x[i]);
            chk += x[i] - x[i];   /* NaN unless every x[i] is finite */
            step = a > step ? a : step;
        }
        if (chk != 0)   /* overflow in a nearly singular solve */
            return MECHRT_ENOTFINITE;
        for (i = 0; i < n; i++)
            q[i] -= x[i];
        r->step = step;
        r->iterations++;
        if ((st = ls_eval(s)) != MECHRT_OK)
            return st;
    }
}

/* x = A^-1 b with A factored (analysis.c's an_solve); x finite. A NaN or
   Inf in b makes its own x_i non-finite, so checking x is enough. */
static MechrtStatus ls_solve(const Ls *s, const mechrt_real *b, mechrt_real *x)
{
    mechrt_real chk = 0;
    int n = s->k->nq, i;

    mechrt_lup_solve(s->f, b, x);
    for (i = 0; i < n; i++)
        chk += x[i] - x[i];
    return chk == 0 ? MECHRT_OK : MECHRT_ENOTFINITE;
}

/* The factorisation of the analysis, with analysis.c's screened condition
   estimate (only when the caller wants a report). */
static MechrtStatus ls_factor_cond(Ls *s, bool want_cond)
{
    const MechrtOptions *o = s->o;
    MechrtStatus st = ls_factor(s);
    mechrt_real anorm;

    if (st != MECHRT_OK || !want_cond || !(o->cond_warn > 0))
        return st;
    if (o->cond_screen > 0 && mechrt_lup_spread(s->f) <= o->cond_screen * o->cond_warn)
        return MECHRT_OK;
    if (s->f->gen_now) {
        /* the estimate reads the pattern LU's factors: that LU on the same
           values (the unrolled one leaves them), screened by its pivots */
        const MechrtLuGen *g = s->f->gen;
        s->f->gen = NULL;
        st = ls_factor(s);
        s->f->gen = g;
        if (st != MECHRT_OK)
            return st;
        if (o->cond_screen > 0 && mechrt_lup_spread(s->f) <= o->cond_screen * o->cond_warn)
            return MECHRT_OK;
    }
    if (s->jnz) {   /* the factorisation consumed the values: evaluate them again */
        s->jnz->jac_nz(s->jnz->ctx, s->q, s->t, s->jac);
        anorm = mechrt_lup_norm1(s->f, s->jac);
    } else {
        anorm = mechrt_norm1(s->k->nq, s->jac, s->k->nq);
    }
    s->r->cond = mechrt_lup_cond1(s->f, anorm);
    s->r->cond_warning = !(s->r->cond <= o->cond_warn);   /* NaN warns too */
    return MECHRT_OK;
}

/* Carves the workspace; checks what mechrt_step checks, and the pattern. */
static MechrtStatus ls_setup(Ls *s, mechrt_real *work, size_t lwork)
{
    const MechrtKernels *k = s->k;
    size_t n, need;
    int i;

    if (!k || k->nq < 1 || k->nh < 0 || k->nv < 0 || !k->jac || !k->nu || !k->gamma
        || ((s->jnz || !k->all) && !k->phi) || !work || !s->f || s->f->n != k->nq
        || (s->jnz && (!s->jnz->jac_nz || s->jnz->nnz != s->f->nnz)))
        return MECHRT_EINVAL;
    if (k->nh != k->nq || k->nv != 0)
        return MECHRT_ENOTSQUARE;
    need = mechrt_workspace_size(k->nq, k->nq);
    if (need == 0)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;
    n = (size_t)k->nq;
    s->jac = work;
    s->phi = work + n * n;
    s->nu = s->phi + n;
    s->gamma = s->nu + n;
    s->dq = s->gamma + n;
    s->qd0 = s->dq + n;
    if (!s->jnz && k->all)
        for (i = 0; i < k->nq; i++)
            s->qd0[i] = 0;
    return MECHRT_OK;
}

/* The step by the kernels' own P_step (the same operations as below,
   its calls direct): true when it took it, the report then filled as
   this file would fill it; false, the state untouched, otherwise. Its
   largest pivot spread: the unrolled LU's limit, and where a condition
   estimate is wanted the screen's, so that a step it takes needs none. */
static bool ls_gen_step(Ls *s, mechrt_real *q, mechrt_real *qd, mechrt_real *qdd,
                        mechrt_real t, mechrt_real h, bool want_cond)
{
    const MechrtOptions *o = s->o;
    mechrt_real tol[4], out[2];
    int iout[2];

    tol[0] = o->tol_phi;
    tol[1] = o->tol_dq;
    tol[2] = o->pivot_tol;
    tol[3] = MECHRT_R(MECHRT_LUP_GEN_SPREAD);
    if (want_cond && o->cond_warn > 0) {
        mechrt_real screen = o->cond_screen > 0 ? o->cond_screen * o->cond_warn : 0;
        tol[3] = screen < tol[3] ? screen : tol[3];
    }
    if (s->f->gen->step(s->f->gen->ctx, q, qd, qdd, t, h, tol, o->max_iter, out, iout) != 0)
        return false;
    s->r->iterations = iout[0];
    s->r->residual = out[0];
    s->r->step = out[1];
    s->r->worst_row = iout[1];
    s->r->factorisations = iout[0] + 1;
    s->f->gen_factors += iout[0] + 1;
    s->f->gen_now = s->f->dense_now = false;
    return true;
}

MechrtStatus mechrt_step_lup(const MechrtKernels *k, const MechrtJacNz *jnz, MechrtLup *f,
                             const MechrtOptions *opts,
                             mechrt_real *q, mechrt_real *qd, mechrt_real *qdd,
                             mechrt_real t, mechrt_real h,
                             mechrt_real *work, size_t lwork, MechrtReport *report)
{
    MechrtOptions dflt;
    MechrtReport dummy;
    Ls s;
    MechrtStatus st;
    int i;

    s.k = k;
    s.jnz = jnz;
    s.f = f;
    if (!opts) {
        dflt = mechrt_default_options();
        opts = &dflt;
    }
    s.o = opts;
    s.r = report ? report : &dummy;
    mechrt_report_clear(s.r);
    if (!q || !qd || !qdd || !isfinite(h))
        return MECHRT_EINVAL;
    /* the kernels' own step calls its own kernels: k and the workspace
       are checked (and carved) when the runtime steps */
    if (f && f->gen && f->gen->step && k && f->n == k->nq && work
        && ls_gen_step(&s, q, qd, qdd, t, h, report != NULL))
        return MECHRT_OK;
    if ((st = ls_setup(&s, work, lwork)) != MECHRT_OK)
        return st;
    if (h != 0) {
        /* 0.5 h h qdd[i] is ((0.5 h) h) qdd[i]: the factor hoisted, the
           same numbers (P_step's) */
        mechrt_real hh = MECHRT_R(0.5) * h * h;
        int n = k->nq;
        for (i = 0; i < n; i++)
            q[i] += h * qd[i] + hh * qdd[i];
    }
    s.q = q;
    s.t = t + h;
    if ((st = ls_newton(&s)) != MECHRT_OK)
        return st;

    if (!s.have_nu)
        k->nu(k->ctx, q, s.t, s.nu);
    if ((st = ls_factor_cond(&s, report != NULL)) != MECHRT_OK)
        return st;
    if ((st = ls_solve(&s, s.nu, qd)) != MECHRT_OK)
        return st;
    k->gamma(k->ctx, q, qd, s.t, s.gamma);   /* gamma needs the velocities just found */
    return ls_solve(&s, s.gamma, qdd);
}
