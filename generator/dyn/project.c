/* project.c - the projections of sim: positions onto Phi = 0, velocities onto Phi_q qd = nu, the rows of the next step. */
#include "project.h"

#include "fold.h"
#include "kkt.h"

#include <math.h>
#include <string.h>

/* QR stands in for the projections' SVD where every pivot ratio exceeds
   this many times their truncation tolerance (see min_norm_solve). */
#define SIM_QR_MARGIN 100.0
/* Sparse path: the pivot test of its factorisations (relative to the
   largest entry, as the dense LU's), and the pivot spread of [I Phi_q^T;
   Phi_q 0] with every row above which the rows are chosen by the dense
   rank-revealing elimination. Its small eigenvalues are -sigma_i^2 of
   Phi_q, so 1e4 is a singular value ratio near 1e-2, a hundred times
   above row_tol's 1e-4: far from a rank drop every row is kept without
   the dense elimination, near one it decides. (At 1e6 the rows near a
   flat position of A02, N = 2, stayed until 4e-6 rad from it, where the
   elimination's pivots, 30 times below the singular values, had dropped
   them at 7e-5 on the dense path: the stages' error over the small
   singular value went into the velocities, 6e-5 of error at rtol 1e-10.) */
#define SIM_KKT_PIVOT_TOL 1e-12
#define SIM_KKT_SPREAD_MAX 1e4
/* A projection that moves a coordinate or rate by more than this share
   of its tolerance (atol + rtol |y|) has the next step take f afresh. */
#define SIM_FRESH_F_SHARE 0.1

/* The rows' tolerance of both projections (row_tol): redundant rows, and
   near a rank drop the row becoming dependent, are left alone; a small
   pivot there would turn the integration's error into a large change of
   position or speed (energy). */
static double project_tol(const Sim *s)
{
    return fmax(s->o->dyn.rank_tol, s->o->row_tol);
}

/* x = the minimum-norm solution of A x = b, A the first m rows of s->jac,
   with singular values below tol * sigma_max left alone (the projections'
   semantics). Far from a rank drop nothing is truncated and the
   rank-revealing QR (runtime/qr.c) gives the same x at a fraction of the
   cost: taken when every row's pivot exceeds SIM_QR_MARGIN * tol times the
   first (the pivots bound the singular values within modest factors);
   otherwise the SVD. *zero: A = 0 (x untouched). */
static MechrtStatus min_norm_solve(Sim *s, int m, double tol, const double *b, double *x,
                                   bool *zero)
{
    int n = s->nq;
    MechrtQr f;
    MechrtSvdResult sv;
    *zero = false;
    MechrtStatus st = mechrt_qr_factor(&f, m, n, s->jac, n, fmin(0.5, SIM_QR_MARGIN * tol),
                                       s->qrw, s->lqrw);
    if (st != MECHRT_OK)
        return st;
    if (f.rank == m) {
        s->res->qr_solves++;
        mechrt_qr_solve(&f, b, x);
        return MECHRT_OK;
    }
    s->res->svd_solves++;
    if (!mechrt_svd(s->svd, s->jac, m, n, n, -1, &sv))
        return MECHRT_ENOTFINITE;
    if (!(sv.sigma_max > 0)) {
        *zero = true;
        return MECHRT_OK;
    }
    mechrt_svd_truncate(s->svd, tol * sv.sigma_max);
    mechrt_svd_pinv_solve(s->svd, b, x);
    return MECHRT_OK;
}

/* M = L L^T in place in the n x n array a (lower triangle; the upper
   left as it was); false where M is not positive definite (a coordinate
   without mass or inertia, Euler parameters' singular M). */
static bool cholesky(int n, double *a)
{
    for (int j = 0; j < n; j++) {
        double *rj = a + (size_t)j * (size_t)n;
        double d = rj[j];
        for (int k = 0; k < j; k++)
            d -= rj[k] * rj[k];
        if (!(d > 0))
            return false;
        rj[j] = sqrt(d);
        for (int i = j + 1; i < n; i++) {
            double *ri = a + (size_t)i * (size_t)n, v = ri[j];
            for (int k = 0; k < j; k++)
                v -= ri[k] * rj[k];
            ri[j] = v / rj[j];
        }
    }
    return true;
}

/* x <- L^-1 x (trans false) or L^-T x (true), L the lower triangle of l. */
static void tri_solve(int n, const double *l, double *x, bool trans)
{
    if (!trans) {
        for (int i = 0; i < n; i++) {
            const double *ri = l + (size_t)i * (size_t)n;
            double v = x[i];
            for (int k = 0; k < i; k++)
                v -= ri[k] * x[k];
            x[i] = v / ri[i];
        }
        return;
    }
    for (int i = n - 1; i >= 0; i--) {
        double v = x[i];
        for (int k = i + 1; k < n; k++)
            v -= l[(size_t)k * (size_t)n + (size_t)i] * x[k];
        x[i] = v / l[(size_t)i * (size_t)n + (size_t)i];
    }
}

/* qd <- qd - dqd with Phi_q dqd = Phi_q qd - nu and the least dqd^T M dqd
   (mass-orthogonal, as the sparse path's: see sparse_project_velocities),
   singular values of Phi_q L^-T below the projections' tolerance left
   alone, M = L L^T; at t0 (the given rates) and with M not positive
   definite the least |dqd|. */
static MechrtStatus project_velocities(Sim *s, const double *q, double *qd, double t)
{
    int n = s->nq, m = s->nr;
    bool zero;
    if (m == 0)
        return MECHRT_OK;
    if (!sim_dense_ready(s))
        return MECHRT_EINVAL;
    s->kc.jac(s->kc.ctx, q, t, s->jac);
    s->kc.nu(s->kc.ctx, q, t, s->nu);
    for (int i = 0; i < m; i++) {
        double a = -s->nu[i];
        for (int j = 0; j < n; j++)
            a += s->jac[(size_t)i * (size_t)n + (size_t)j] * qd[j];
        s->resid[i] = a;
    }
    bool weighted = false;
    if (s->res->steps > 0) {   /* at t0 the file's or --qd's rates: the nearest, as ever */
        s->kc.mass(s->kc.ctx, q, s->mass);
        weighted = sim_all_finite(n * n, s->mass) && cholesky(n, s->mass);
    }
    if (weighted)   /* rows of Phi_q L^-T: L^-1 times each row */
        for (int i = 0; i < m; i++)
            tri_solve(n, s->mass, s->jac + (size_t)i * (size_t)n, false);
    MechrtStatus st = min_norm_solve(s, m, project_tol(s), s->resid, s->dqd, &zero);
    if (st != MECHRT_OK || zero)
        return st;   /* Phi_q = 0: nothing constrains the velocities */
    if (weighted)
        tri_solve(n, s->mass, s->dqd, true);
    for (int j = 0; j < n; j++) {
        qd[j] -= s->dqd[j];
        if (!isfinite(qd[j]))
            return MECHRT_ENOTFINITE;
    }
    return MECHRT_OK;
}

/* ||Phi(q, t)||_inf over the holonomic rows into rep (Phi in s->resid). */
static MechrtStatus eval_phi(Sim *s, const double *q, double t, MechrtReport *rep)
{
    s->kc.phi(s->kc.ctx, q, t, s->resid);
    rep->residual = 0;
    rep->worst_row = 0;
    for (int i = 0; i < s->inner->nh; i++) {
        double a = fabs(s->resid[i]);
        if (!isfinite(a)) {
            rep->residual = a;
            rep->worst_row = i;
            return MECHRT_ENOTFINITE;
        }
        if (a > rep->residual) {
            rep->residual = a;
            rep->worst_row = i;
        }
    }
    return MECHRT_OK;
}

/* The minimum-norm correction dq (s->dqd) of the holonomic rows' residual
   s->resid at q: on the sparse path from [I Phi_A^T; Phi_A 0] with the
   rows of this step (min |dq| with Phi_A dq = Phi_A), where it factors;
   else, and on the dense path, min_norm_solve. *zero: Phi_q = 0. */
static MechrtStatus position_correction(Sim *s, const MechrtOptions *o, const double *q,
                                        double t, bool *zero)
{
    int n = s->nq, nh = s->inner->nh;
    *zero = false;
    if (s->kkt) {
        s->res->calls.jac_nz++;
        s->jnz->jac.jac_nz(s->jnz->jac.ctx, q, t, mechrt_host_kkt_jac(s->kkt));
        if (mechrt_host_kkt_factor(s->kkt, MECHRT_KKT_IDENTITY, s->active, nh,
                                   SIM_KKT_PIVOT_TOL) == MECHRT_OK) {
            memset(s->sx, 0, (size_t)n * sizeof *s->sx);
            for (int i = 0; i < s->nr; i++)
                s->sx[n + i] = i < nh && s->active[i] ? s->resid[i] : 0;
            if (mechrt_host_kkt_solve(s->kkt, MECHRT_KKT_IDENTITY, s->sx) == MECHRT_OK) {
                memcpy(s->dqd, s->sx, (size_t)n * sizeof *s->dqd);
                s->res->kkt_solves++;
                return MECHRT_OK;
            }
        }
        s->res->dense_fallbacks++;
        if (!sim_dense_ready(s))
            return MECHRT_EINVAL;
    }
    s->kc.jac(s->kc.ctx, q, t, s->jac);
    return min_norm_solve(s, nh, o->pivot_tol, s->resid, s->dqd, zero);
}

/* Minimum-norm Newton onto Phi(q, t) = 0 (as mechrt_host_project, without
   its SVD per step where QR does): dq = -pinv(Phi_q) Phi truncated at
   pivot_tol, at least one step, until |Phi| <= tol_phi and |dq| <= tol_dq. */
static MechrtStatus project_positions(Sim *s, const MechrtOptions *o, double *q, double t,
                                      MechrtReport *rep)
{
    int n = s->nq, nh = s->inner->nh;
    memset(rep, 0, sizeof *rep);
    rep->step = -1;
    rep->worst_row = -1;
    rep->sing_index = -1;
    if (nh == 0)
        return MECHRT_OK;
    for (;;) {
        MechrtStatus st = eval_phi(s, q, t, rep);
        if (st != MECHRT_OK)
            return st;
        if (rep->step >= 0 && rep->residual <= o->tol_phi && rep->step <= o->tol_dq)
            return MECHRT_OK;
        if (rep->iterations >= o->max_iter)
            return MECHRT_EMAXITER;
        bool zero;
        st = position_correction(s, o, q, t, &zero);
        if (st != MECHRT_OK)
            return st;
        if (zero)
            return MECHRT_ESING;   /* Phi_q = 0: no direction to move in */
        double step = 0;
        for (int j = 0; j < n; j++) {
            if (!isfinite(s->dqd[j]))
                return MECHRT_ENOTFINITE;
            q[j] -= s->dqd[j];
            step = fmax(step, fabs(s->dqd[j]));
        }
        rep->step = step;
        rep->iterations++;
    }
}

/* Positions onto Phi = 0; fails with the message set. */
static bool settle_positions(Sim *s, double *y, double t)
{
    MechrtOptions po = s->o->mechrt;
    MechrtReport rep;
    po.pivot_tol = project_tol(s);
    s->res->projections++;
    MechrtStatus st = project_positions(s, &po, y, t, &rep);
    s->res->projection_iterations += rep.iterations;
    if (st != MECHRT_OK) {
        sim_fail(s, st, t, "position projection");
        if (st == MECHRT_EMAXITER)
            msgf(s, "minimum-norm Newton did not bring the rows back within %d iterations "
                 "(largest residual %.3g); the step may be too long for the motion: "
                 "tighten --rtol/--atol", po.max_iter, rep.residual);
        else
            msgf(s, "%s", mechrt_strerror(st));
        return false;
    }
    return true;
}

/* qd <- qd - dqd, the correction onto the kept rows of Phi_q qd = nu
   nearest in kinetic energy (mass-orthogonal: least dqd^T M dqd) from
   [M Phi_A^T; Phi_A 0] at q, Phi_q there from sparse_rows; the minimum-
   norm one where M is singular on the rows' null space. Mass-orthogonal
   (Bayo and Ledesma's projections) because it changes T only by
   -1/2 dqd^T M dqd, second order in the correction: the correction is
   largest where rows come back after a rank drop (the velocities that
   moved freely along the fold directions while they were left out), and
   the minimum-norm one there changed T at first order: on IFToMM A02,
   3e-4 J at one flat position, then a phase error growing with time. */
static MechrtStatus sparse_project_velocities(Sim *s, const double *q, double t, double *qd)
{
    int n = s->nq;
    MechrtKktWeight w = MECHRT_KKT_MASS;
    sim_sparse_mass(s, q, mechrt_host_kkt_mass(s->kkt));
    if (sim_sparse_mass_factor(s, q, t) != MECHRT_OK) {
        w = MECHRT_KKT_IDENTITY;
        MechrtStatus st = mechrt_host_kkt_factor(s->kkt, w, s->active, s->nr,
                                                 SIM_KKT_PIVOT_TOL);
        if (st != MECHRT_OK)
            return st;
    }
    sim_sparse_jac_times(s, qd, s->resid);
    memset(s->sx, 0, (size_t)n * sizeof *s->sx);
    for (int i = 0; i < s->nr; i++)
        s->sx[n + i] = s->active[i] ? s->resid[i] - s->nu[i] : 0;
    MechrtStatus st = mechrt_host_kkt_solve_refined(s->kkt, w, s->sx, s->sw);
    if (st != MECHRT_OK)
        return st;
    s->res->kkt_solves++;
    for (int j = 0; j < n; j++)
        qd[j] -= s->sx[j];
    return sim_all_finite(n, qd) ? MECHRT_OK : MECHRT_ENOTFINITE;
}

/* Velocities onto Phi_q qd = nu; fails with the message set. */
static bool settle_velocities(Sim *s, double *y, double t)
{
    MechrtStatus st = MECHRT_EINVAL;
    if (s->kkt && s->vel_ready)
        st = sparse_project_velocities(s, y, t, y + s->nq);
    if (st != MECHRT_OK) {
        if (s->kkt)
            s->res->dense_fallbacks++;
        st = project_velocities(s, y, y + s->nq, t);
    }
    if (st != MECHRT_OK) {
        sim_fail(s, st, t, "velocity projection");
        msgf(s, "%s", mechrt_strerror(st));
        return false;
    }
    return true;
}

/* The rows the next step keeps, decided at y (on the manifold after a
   projection): redundant ones out, for every stage of the step. */
static bool choose_rows(Sim *s, const double *y, double t, MechrtDynReport *out)
{
    MechrtDynReport rep;
    MechrtDynOptions ro = s->o->dyn;
    ro.rank_tol = fmax(ro.rank_tol, s->o->row_tol);
    MechrtStatus st = !sim_dense_ready(s) ? MECHRT_EINVAL
                      : mechrt_dynamics_rows(&s->kc, &ro, y, t, s->active, s->work,
                                             s->lwork, &rep);
    if (st != MECHRT_OK) {
        sim_fail(s, st, t, "the rank of the Jacobian");
        msgf(s, "%s", mechrt_strerror(st));
        return false;
    }
    if (out)
        *out = rep;
    return true;
}

/* The sparse path's choice: every row where [I Phi_q^T; Phi_q 0] factors
   with a fresh pivot search and a modest pivot spread (no rank drop near:
   mechrt_host_kkt_screen), else choose_rows. */
static bool sparse_rows(Sim *s, const double *y, double t)
{
    int m = s->nr;
    s->vel_ready = false;
    s->mq_valid = false;    /* the rows may change */
    bool evaluated = sim_sparse_eval(s, y, y + s->nq, t, false) == MECHRT_OK;
    double spread = INFINITY;
    bool factored = evaluated
                    && mechrt_host_kkt_screen(s->kkt, m, SIM_KKT_PIVOT_TOL, &spread) == MECHRT_OK;
    if (factored)
        s->res->max_screen_spread = fmax(s->res->max_screen_spread, spread);
    if (spread <= SIM_KKT_SPREAD_MAX) {
        memset(s->active, 1, (size_t)m);
        s->all_active = s->vel_ready = true;
        s->res->rows_sparse++;
        return true;
    }
    MechrtDynReport rep;
    s->res->rows_dense++;
    if (!choose_rows(s, y, t, &rep))
        return false;
    s->all_active = rep.redundant == 0;
    if (rep.redundant > s->res->max_redundant)
        s->res->max_redundant = rep.redundant;
    if (rep.pivot_ratio < s->res->min_pivot_ratio)
        s->res->min_pivot_ratio = rep.pivot_ratio;
    s->vel_ready = evaluated;
    return true;
}

/* Rows the step before left out are back (s->active0: its rows). */
static bool rows_returned(const Sim *s)
{
    for (int i = 0; i < s->nr; i++)
        if (!s->active0[i] && s->active[i])
            return true;
    return false;
}

/* After a step (or at the start): projection when on, then the rows; the
   sparse path chooses the rows before the velocity projection, which
   uses them, and projects the positions with the rows of the step before
   (its factors), again with the new ones where rows came back (the
   velocities of rows that were out, projected at positions off them,
   took their residual over a small pivot). */
static bool settle(Sim *s, double *y, double t, bool project)
{
    if (!s->kkt)
        return (!project || (settle_positions(s, y, t) && settle_velocities(s, y, t)))
               && choose_rows(s, y, t, NULL);
    if ((project && !settle_positions(s, y, t)) || !sparse_rows(s, y, t))
        return false;
    if (project && rows_returned(s)) {
        if (!settle_positions(s, y, t))
            return false;
        s->vel_ready = s->vel_ready && sim_sparse_eval(s, y, y + s->nq, t, false) == MECHRT_OK;
    }
    return !project || settle_velocities(s, y, t);
}

/* The settled state differs from s->ys (before) by more than
   SIM_FRESH_F_SHARE of the error allowed per step, or the rows changed. */
static bool settle_moved(const Sim *s, const double *y)
{
    const SimOptions *o = s->o;
    if (memcmp(s->active0, s->active, (size_t)s->nr) != 0)
        return true;
    for (int i = 0; i < 2 * s->nq; i++)
        if (fabs(y[i] - s->ys[i]) > SIM_FRESH_F_SHARE * (o->atol + o->rtol * fabs(y[i])))
            return true;
    return false;
}

bool sim_settle(Sim *s, double *y, double t, bool project)
{
    s->cache_ok = false;    /* y and the rows change */
    memcpy(s->ys, y, 2 * (size_t)s->nq * sizeof *y);
    memcpy(s->active0, s->active, (size_t)s->nr);
    if (!settle(s, y, t, project))
        return false;
    s->fresh_f = settle_moved(s, y);
    return !project || sim_fold_prepare(s, y, t);
}

