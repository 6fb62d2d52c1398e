/* sim.c - forward dynamics over time on GSL's odeiv2, with coordinate projection.
 *
 * The state is y = (q, qd[, W]): q' = qd, qd' = qdd(q, qd, t) from the
 * runtime's null-space solve of the augmented system (runtime/dynamics.c,
 * which survives redundant rows), and W' the power of the forces for the
 * energy balance. GSL steps it with an embedded Runge-Kutta pair (rk8pd by
 * default, rkf45), or for stiff mechanisms the implicit Gauss-Legendre
 * rk4imp or the variable-order BDF msbdf, both on a forward-difference
 * Jacobian of the right side (2 nq + 2 right sides each).
 *
 * Drift: the integrator keeps Phi = 0 and Phi_q qd = nu only to its error,
 * and the error grows (index reduction). So the state is projected back:
 * positions by minimum-norm Newton onto Phi(q, t) = 0, then velocities by
 * the minimum-norm correction onto Phi_q qd = nu (every row, velocity-level
 * ones too) (Hairer & Wanner, Solving ODEs II, VII.2): pseudo-inverse
 * solves, by rank-revealing QR away from a rank drop and by the truncated
 * SVD near one (min_norm_solve; redundant rows harmless).
 * One-step methods project after every accepted integrator step; msbdf,
 * whose history a change of the state would invalidate, projects at the
 * output times only and restarts there. Baumgarte's stabilisation
 * (SimOptions.dyn) may be added on top.
 *
 * Redundant rows and singular positions: after each projection, on the
 * manifold, the rows the rank-revealing elimination keeps (pivots above
 * SimOptions.row_tol) are chosen for the next step (mechrt_dynamics_rows)
 * and the others left out at its stages, which lie off the manifold by the
 * step's error: there a redundant row is independent to that error, and
 * near a singular position (a parallelogram's cranks in line with its
 * coupler) the row becoming dependent has an acceleration equation
 * inconsistent by the error over its small pivot. The projection restores
 * the rows left out.
 *
 * Large mechanisms (SimOptions.linear; auto above SIM_DENSE_MAX_NQ
 * coordinates) take the sparse path instead: the generated kernels'
 * nonzeros (all_nz, jac_nz, mass_nz) into the augmented matrix [W Phi_A^T;
 * Phi_A 0] on KLU (runtime/host/sparse_kkt.c), W = M for the right side
 * (one refactorisation per call, a refined solve near a rank drop, the
 * rows of the step as identity rows), W = I for the minimum-norm position
 * Newton and W = M for the mass-orthogonal velocity projection
 * (sparse_project_velocities says why), no nr x nq or nq x nq array
 * touched per call. The rows: where [I Phi_q^T; Phi_q 0] with every row,
 * factored with a fresh pivot search, has a pivot spread below
 * SIM_KKT_SPREAD_MAX, every row is kept (no rank drop near, the dense
 * elimination would keep them all); only otherwise does the dense
 * rank-revealing elimination decide, which on IFToMM A02 is a few steps
 * around each flat position. Positions are projected with the rows of the
 * step before, velocities with the rows just chosen. Where a sparse
 * factorisation fails, that call falls back to the dense method, which
 * decides or names the cause.
 *
 * Energy: E = T - W with T = 1/2 qd^T M qd and W' = qd^T M qdd +
 * 1/2 qd^T Mdot qd = qd.(Q - Phi_q^T lambda) + 1/2 qd^T Mdot qd, the power of
 * the applied forces (Q without its velocity terms, which the Mdot term
 * cancels) and of the constraint forces; Mdot qd by a central difference of
 * the mass kernel along qd. The identity holds for any mechanism, so the
 * drift of E measures the integration and projection error; for a
 * conservative one (gravity and springs, no dampers, no drivers) W = -(V -
 * V0) and E is the energy, T + V - V0. W rides in the state, so the
 * integrator is its quadrature; its own error does not steer the step size.
 */
#include "sim.h"

#include "../base/arena.h"
#include "../pipeline/pipeline.h"
#include "../../runtime/host/mechrt_host.h"
#include "assemble.h"
#include "options.h"
#include "construct.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

/* Relative displacement of the central difference for Mdot qd. */
#define SIM_MDOT_STEP 1e-5
/* QR stands in for the projections' SVD where every pivot ratio exceeds
   this many times their truncation tolerance (see min_norm_solve). */
#define SIM_QR_MARGIN 100.0
/* The step size is said to underflow below this share of |t1 - t0|. */
#define SIM_HMIN_SHARE 1e-14
/* Sparse path: the pivot test of its factorisations (relative to the
   largest entry, as the dense LU's), and the pivot spread of [I Phi_q^T;
   Phi_q 0] with every row above which the rows are chosen by the dense
   rank-revealing elimination. Its small eigenvalues are -sigma_i^2 of
   Phi_q, so 1e6 is a singular value ratio near 1e-3, ten times above
   row_tol's 1e-4 (pivots in the elimination track the singular values
   within modest factors): far from a rank drop every row is kept without
   the dense elimination, near one it decides. */
#define SIM_KKT_PIVOT_TOL 1e-12
#define SIM_KKT_SPREAD_MAX 1e6
/* The right side's solve is refined once (mechrt_host_kkt_solve_refined)
   where [M Phi_A^T; Phi_A 0]'s pivot spread exceeds this: near a rank
   drop, where the multipliers dwarf the accelerations. Elsewhere (A02:
   spreads of 40 to 2000) one solve is as accurate. */
#define SIM_KKT_REFINE_SPREAD 1e4

const char *const sim_method_names[] = {"rk8pd", "rkf45", "rk4imp", "msbdf", NULL};
const char *const sim_linear_names[] = {"auto", "dense", "sparse", NULL};

SimOptions sim_default_options(void)
{
    SimOptions o;
    memset(&o, 0, sizeof o);
    o.t0 = 0;
    o.t1 = 1;
    o.steps = 100;
    o.method = SIM_RK8PD;
    o.rtol = 1e-10;
    o.atol = 1e-10;
    o.dyn = mechrt_dyn_default_options();
    o.mechrt = mechrt_default_options();
    o.project = true;
    o.row_tol = 1e-4;
    o.energy = true;
    o.qd0 = NULL;
    o.assembly_max_iter = 100;
    o.max_steps = 10000000;
    o.notes = NULL;
    o.linear = SIM_LINEAR_AUTO;
    return o;
}

bool sim_has_masses(const MechrtKernels *k)
{
    return k && k->mass && k->force;
}

/* ---- the state of one simulation ---------------------------------------- */

typedef struct Sim {
    const MechrtKernels *inner;  /* the caller's kernels */
    EngineCounter counter;
    MechrtKernels kc;            /* the same, counted (engine_counting) */
    const SimOptions *o;
    SimResult *res;
    int nq, nr, dim;             /* dim: 2 nq (+1 with energy) */
    double *work;                /* mechrt_forward_dynamics' workspace */
    size_t lwork;
    double *qrw;                 /* the projections' QR workspace (nr x nq) */
    size_t lqrw;
    MechrtSvd *svd;              /* the same near a rank drop */
    double *jac, *nu, *resid, *dqd, *lambda, *mass, *mass2, *qs, *f0, *f1, *y;
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *drv;
    MechrtStatus fail_status;    /* set by the right-hand side */
    double fail_t;
    MechrtDynReport fail_rep;
    double e0;                   /* E at t0 */
    MechrtDynOptions dyn;        /* the caller's, with the rows of this step */
    unsigned char *active;       /* nr: the rows kept during this step */
    /* the sparse path (kkt NULL: dense) */
    MechrtHostKkt *kkt;
    const MechrtHostJacNz *jnz;
    const MechrtHostMassNz *mnz;
    double *sx, *sw, *sphi, *sg, *sforce, *smass;  /* nq + nr; 2 (nq + nr); nr; nr; nq; mass nnz */
    bool all_active;             /* every row kept in this step */
    double *mq, mq_t;            /* (q, t) of the factors of M's augmented matrix */
    bool mq_valid;               /* ... with this step's rows */
    bool vel_ready;              /* Phi_q's nonzeros and nu at the state, for the
                                    velocity projection */
    /* the last right side, (t, y) -> f, valid while the rows stay: GSL
       evaluates f at a step's start, where an output state or the
       interpolant's end has just solved it */
    double *cy, *cf, ct;
    bool cache_ok;
    double *yc, *fc, *ya, *fa;   /* --interpolate: the last two steps' starts, f there */
    double *fb, *yi;             /* f at the step's end, the output state */
} Sim;

static void msgf(Sim *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Appends to res->message, truncating quietly. */
static void msgf(Sim *s, const char *fmt, ...)
{
    char *msg = s->res->message;
    size_t len = strlen(msg);
    if (len + 1 >= sizeof s->res->message)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg + len, sizeof s->res->message - len, fmt, ap);
    va_end(ap);
}

/* The failure at t: status, cause and message start "t = T: WHAT: ". */
static void fail(Sim *s, MechrtStatus st, double t, const char *what)
{
    SimResult *res = s->res;
    res->status = SIM_FAILED;
    res->cause = st;
    res->t_fail = t;
    res->message[0] = '\0';
    msgf(s, "t = %.10g: %s failed: ", t, what);
}

/* Why mechrt_forward_dynamics failed, after fail(). */
static void explain_dynamics(Sim *s, MechrtStatus st, const MechrtDynReport *rep)
{
    switch (st) {
    case MECHRT_ESING:
        msgf(s, "the augmented matrix is singular: the mass matrix is singular on the motions "
             "the joints allow (reduced mass matrix, direction %d of %d): a body or coordinate "
             "free to move without mass or inertia?", rep->sing_index + 1,
             s->nq - rep->rank);
        break;
    case MECHRT_ENOTFINITE:
        msgf(s, "NaN or infinity in the mass matrix, the forces, the Jacobian, gamma or the "
             "solution (a function evaluated outside its domain, or the motion blew up)");
        break;
    default:
        msgf(s, "%s (an internal error)", mechrt_strerror(st));
        break;
    }
}

/* ---- the sparse path: the augmented matrix on KLU --------------------------- */

/* y = Phi_q x over the Jacobian's nonzeros (nr rows). */
static void sparse_jac_times(const Sim *s, const double *x, double *y)
{
    const double *v = mechrt_host_kkt_jac(s->kkt);
    memset(y, 0, (size_t)s->nr * sizeof *y);
    for (int e = 0; e < s->jnz->jac.nnz; e++)
        y[s->jnz->jac.row[e]] += v[e] * x[s->jnz->jac.col[e]];
}

/* qd^T M x over M's nonzeros vals. */
static double sparse_mass_form(const Sim *s, const double *vals, const double *qd,
                               const double *x)
{
    double sum = 0;
    for (int e = 0; e < s->mnz->nnz; e++)
        sum += qd[s->mnz->row[e]] * vals[e] * x[s->mnz->col[e]];
    return sum;
}

/* M's nonzeros at q into vals (counted). */
static void sparse_mass(Sim *s, const double *q, double *vals)
{
    s->res->calls.mass_nz++;
    s->mnz->mass_nz(s->mnz->ctx, q, vals);
}

static bool all_finite(int n, const double *v)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

/* Phi, Phi_q's nonzeros, nu and gamma at the state (one all_nz call), and
   with dynamics M's nonzeros and Q. */
static MechrtStatus sparse_eval(Sim *s, const double *q, const double *qd, double t,
                                bool dynamics)
{
    double *jac = mechrt_host_kkt_jac(s->kkt);
    s->res->calls.all_nz++;
    s->jnz->all_nz(s->jnz->jac.ctx, q, qd, t, s->sphi, jac, s->nu, s->sg);
    if (!all_finite(s->jnz->jac.nnz, jac) || !all_finite(s->nr, s->nu) || !all_finite(s->nr, s->sg))
        return MECHRT_ENOTFINITE;
    if (!dynamics)
        return MECHRT_OK;
    double *mass = mechrt_host_kkt_mass(s->kkt);
    sparse_mass(s, q, mass);
    s->kc.force(s->kc.ctx, q, qd, t, s->sforce);
    return all_finite(s->mnz->nnz, mass) && all_finite(s->nq, s->sforce) ? MECHRT_OK
                                                                        : MECHRT_ENOTFINITE;
}

/* [M Phi_A^T; Phi_A 0] factored at (q, t) with the step's rows, M's and
   Phi_q's nonzeros at q in the buffers; skipped where the factors are
   already at the same q and t with these rows (the matrix depends on
   nothing else): the velocity projection's serve the step's first stage,
   its retries after a rejection, and the output state's solve. */
static MechrtStatus sparse_mass_factor(Sim *s, const double *q, double t)
{
    size_t bytes = (size_t)s->nq * sizeof *q;
    if (s->mq_valid && t == s->mq_t && memcmp(q, s->mq, bytes) == 0) {
        s->res->kkt_reused++;
        return MECHRT_OK;
    }
    s->mq_valid = false;
    MechrtStatus st = mechrt_host_kkt_factor(s->kkt, MECHRT_KKT_MASS,
                                             s->all_active ? NULL : s->active, s->nr,
                                             s->o->dyn.pivot_tol);
    if (st == MECHRT_OK) {
        memcpy(s->mq, q, bytes);
        s->mq_t = t;
        s->mq_valid = true;
    }
    return st;
}

/* qdd (and lambda, nr, when not NULL) from [M Phi_A^T; Phi_A 0] with the
   rows of active (NULL: all), gamma stabilised as dyn_eval does. */
static MechrtStatus sparse_accel(Sim *s, const double *q, const double *qd, double t,
                                 const unsigned char *active, double *qdd, double *lambda)
{
    int n = s->nq, m = s->nr;
    const MechrtDynOptions *o = &s->o->dyn;
    MechrtStatus st = sparse_eval(s, q, qd, t, true);
    if (st != MECHRT_OK)
        return st;
    if (o->baumgarte_alpha != 0 || o->baumgarte_beta != 0) {
        sparse_jac_times(s, qd, s->resid);
        for (int i = 0; i < m; i++)
            s->sg[i] -= 2 * o->baumgarte_alpha * (s->resid[i] - s->nu[i])
                      + (i < s->inner->nh ? o->baumgarte_beta * o->baumgarte_beta * s->sphi[i] : 0);
    }
    st = sparse_mass_factor(s, q, t);     /* active is the step's rows, or all of them */
    if (st != MECHRT_OK)
        return st;
    memcpy(s->sx, s->sforce, (size_t)n * sizeof *s->sx);
    for (int i = 0; i < m; i++)
        s->sx[n + i] = !active || active[i] ? s->sg[i] : 0;
    st = mechrt_host_kkt_spread(s->kkt, MECHRT_KKT_MASS) > SIM_KKT_REFINE_SPREAD
             ? mechrt_host_kkt_solve_refined(s->kkt, MECHRT_KKT_MASS, s->sx, s->sw)
             : mechrt_host_kkt_solve(s->kkt, MECHRT_KKT_MASS, s->sx);
    if (st != MECHRT_OK)
        return st;
    memcpy(qdd, s->sx, (size_t)n * sizeof *qdd);
    if (lambda)
        memcpy(lambda, s->sx + n, (size_t)m * sizeof *lambda);
    return MECHRT_OK;
}

/* The dense method's arrays (nr x nq, nq x nq, the SVD): at the start on
   the dense path, at the first dense fallback on the sparse one, which
   otherwise never reads them (at 10 000 coordinates they are gigabytes).
   False when out of memory. */
static bool dense_ready(Sim *s)
{
    if (s->work)
        return s->nr == 0 || s->svd;
    size_t n = (size_t)s->nq, m = (size_t)s->nr;
    s->lwork = mechrt_dynamics_workspace_size(s->nq, s->nr);
    s->work = xcalloc(s->lwork, sizeof *s->work);
    s->jac = xcalloc(m * n + 1, sizeof *s->jac);
    s->mass = xcalloc(n * n, sizeof *s->mass);
    s->mass2 = xcalloc(n * n, sizeof *s->mass2);
    s->lqrw = m > 0 ? mechrt_qr_work_len(s->nr, s->nq) : 0;
    s->qrw = xcalloc(s->lqrw + 1, sizeof *s->qrw);
    s->svd = m > 0 ? mechrt_svd_new(s->nr, s->nq) : NULL;
    return m == 0 || s->svd;
}

/* ---- energy --------------------------------------------------------------- */

/* 1/2 qd^T Mdot qd by a central difference of M along qd (qs scratch; M
   into mass2, or its nonzeros into smass on the sparse path). */
static double half_mdot(Sim *s, const double *q, const double *qd)
{
    int n = s->nq;
    double vmax = 0, qmax = 1;
    for (int i = 0; i < n; i++) {
        vmax = fmax(vmax, fabs(qd[i]));
        qmax = fmax(qmax, fabs(q[i]));
    }
    if (vmax == 0)
        return 0;
    double eps = SIM_MDOT_STEP * qmax / vmax, sum = 0;
    for (int sign = -1; sign <= 1; sign += 2) {
        for (int i = 0; i < n; i++)
            s->qs[i] = q[i] + sign * eps * qd[i];
        double quad = 0;
        if (s->kkt) {
            sparse_mass(s, s->qs, s->smass);
            quad = sparse_mass_form(s, s->smass, qd, qd);
        } else {
            s->kc.mass(s->kc.ctx, s->qs, s->mass2);
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++)
                    quad += qd[i] * s->mass2[(size_t)i * (size_t)n + (size_t)j] * qd[j];
        }
        sum += sign * quad;
    }
    return 0.25 * sum / eps;    /* 1/2 * (quad+ - quad-) / (2 eps) */
}

/* qd^T M x for the n x n row-major M. */
static double quad_form(int n, const double *m, const double *qd, const double *x)
{
    double sum = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            sum += qd[i] * m[(size_t)i * (size_t)n + (size_t)j] * x[j];
    return sum;
}

/* qd^T M x with M at q (one mass call). */
static double mass_form(Sim *s, const double *q, const double *qd, const double *x)
{
    s->kc.mass(s->kc.ctx, q, s->mass);
    return quad_form(s->nq, s->mass, qd, x);
}

/* E = T - W at the state y, and the drift against E(t0). */
static void watch_energy(Sim *s, const double *y, bool first)
{
    if (!s->o->energy)
        return;
    const double *q = y, *qd = y + s->nq;
    double tk, w = y[2 * s->nq];
    if (s->kkt) {
        sparse_mass(s, q, s->smass);
        tk = 0.5 * sparse_mass_form(s, s->smass, qd, qd);
    } else {
        tk = 0.5 * mass_form(s, q, qd, qd);
    }
    double e = tk - w;
    if (first)
        s->e0 = e;
    s->res->energy_scale = fmax(s->res->energy_scale, fmax(tk, fabs(w)));
    s->res->energy_drift = fmax(s->res->energy_drift, fabs(e - s->e0));
}

/* ---- right-hand side -------------------------------------------------------- */

/* M at the state of the last mechrt_forward_dynamics: its workspace holds
   it after Phi_q (runtime/dynamics.c: "a nr*nq | mass nq*nq | ..."),
   which saves the energy balance a mass call per right-hand side. */
static const double *dyn_mass(const Sim *s)
{
    return s->work + (size_t)s->nr * (size_t)s->nq;
}

static int sim_rhs_solve(Sim *s, double t, const double y[], double f[]);

/* f = (qd, qdd, dE/dt) at (t, y) kept for a repeated evaluation. */
static void cache_store(Sim *s, double t, const double *y, const double *f)
{
    memcpy(s->cy, y, 2 * (size_t)s->nq * sizeof *y);
    memcpy(s->cf, f, (size_t)s->dim * sizeof *f);
    s->ct = t;
    s->cache_ok = true;
}

/* The cache holds f at (t, y). */
static bool cache_has(const Sim *s, double t, const double *y)
{
    return s->cache_ok && t == s->ct && memcmp(y, s->cy, 2 * (size_t)s->nq * sizeof *y) == 0;
}

static int sim_rhs(double t, const double y[], double f[], void *params)
{
    Sim *s = params;
    if (cache_has(s, t, y)) {
        memcpy(f, s->cf, (size_t)s->dim * sizeof *f);
        return GSL_SUCCESS;
    }
    int st0 = sim_rhs_solve(s, t, y, f);
    if (st0 == GSL_SUCCESS)
        cache_store(s, t, y, f);
    return st0;
}

static int sim_rhs_solve(Sim *s, double t, const double y[], double f[])
{
    int n = s->nq;
    const double *q = y, *qd = y + n;
    MechrtDynReport rep;
    s->res->rhs_calls++;
    if (s->kkt) {
        /* the rows left out are known: no rank decision here */
        if (sparse_accel(s, q, qd, t, s->all_active ? NULL : s->active, f + n, NULL)
            == MECHRT_OK) {
            memcpy(f, qd, (size_t)n * sizeof *f);
            if (s->o->energy)
                f[2 * n] = sparse_mass_form(s, mechrt_host_kkt_mass(s->kkt), qd, f + n)
                           + half_mdot(s, q, qd);
            return GSL_SUCCESS;
        }
        s->res->dense_fallbacks++;     /* the dense method decides, or names the cause */
        if (!dense_ready(s)) {
            s->fail_status = MECHRT_EINVAL;
            s->fail_t = t;
            return GSL_EBADFUNC;
        }
    }
    MechrtStatus st = mechrt_forward_dynamics(&s->kc, &s->dyn, q, qd, t, f + n, NULL,
                                              s->work, s->lwork, &rep);
    if (st == MECHRT_OK) {
        memcpy(f, qd, (size_t)n * sizeof *f);
        if (rep.redundant > s->res->max_redundant)
            s->res->max_redundant = rep.redundant;
        if (s->nr > 0 && rep.pivot_ratio < s->res->min_pivot_ratio)
            s->res->min_pivot_ratio = rep.pivot_ratio;
        if (s->o->energy)
            f[2 * n] = quad_form(n, dyn_mass(s), qd, f + n) + half_mdot(s, q, qd);
        return GSL_SUCCESS;
    }
    if (s->fail_status == MECHRT_OK) {
        s->fail_status = st;
        s->fail_t = t;
        s->fail_rep = rep;
    }
    return GSL_EBADFUNC;
}

/* Forward differences of the right side for the implicit methods. */
static int sim_jacobian(double t, const double y[], double *dfdy, double dfdt[], void *params)
{
    Sim *s = params;
    int dim = s->dim;
    s->res->jacobian_calls++;
    int gs = sim_rhs(t, y, s->f0, s);
    memcpy(s->y, y, (size_t)dim * sizeof *y);
    for (int j = 0; j < dim && gs == GSL_SUCCESS; j++) {
        double h = 1.4901161193847656e-08 * fmax(fabs(y[j]), 1.0);   /* sqrt(eps) */
        s->y[j] = y[j] + h;
        gs = sim_rhs(t, s->y, s->f1, s);
        for (int i = 0; i < dim; i++)
            dfdy[(size_t)i * (size_t)dim + (size_t)j] = (s->f1[i] - s->f0[i]) / h;
        s->y[j] = y[j];
    }
    if (gs == GSL_SUCCESS) {
        double ht = 1.4901161193847656e-08 * fmax(fabs(t), 1.0);
        gs = sim_rhs(t + ht, y, s->f1, s);
        for (int i = 0; i < dim; i++)
            dfdt[i] = (s->f1[i] - s->f0[i]) / ht;
    }
    return gs;
}

/* ---- projection ------------------------------------------------------------- */

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

/* qd <- qd - pinv(Phi_q) (Phi_q qd - nu): the nearest velocities the rows allow. */
static MechrtStatus project_velocities(Sim *s, const double *q, double *qd, double t)
{
    int n = s->nq, m = s->nr;
    bool zero;
    if (m == 0)
        return MECHRT_OK;
    if (!dense_ready(s))
        return MECHRT_EINVAL;
    s->kc.jac(s->kc.ctx, q, t, s->jac);
    s->kc.nu(s->kc.ctx, q, t, s->nu);
    for (int i = 0; i < m; i++) {
        double a = -s->nu[i];
        for (int j = 0; j < n; j++)
            a += s->jac[(size_t)i * (size_t)n + (size_t)j] * qd[j];
        s->resid[i] = a;
    }
    MechrtStatus st = min_norm_solve(s, m, project_tol(s), s->resid, s->dqd, &zero);
    if (st != MECHRT_OK || zero)
        return st;   /* Phi_q = 0: nothing constrains the velocities */
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
        if (!dense_ready(s))
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
        fail(s, st, t, "position projection");
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
    sparse_mass(s, q, mechrt_host_kkt_mass(s->kkt));
    if (sparse_mass_factor(s, q, t) != MECHRT_OK) {
        w = MECHRT_KKT_IDENTITY;
        MechrtStatus st = mechrt_host_kkt_factor(s->kkt, w, s->active, s->nr,
                                                 SIM_KKT_PIVOT_TOL);
        if (st != MECHRT_OK)
            return st;
    }
    sparse_jac_times(s, qd, s->resid);
    memset(s->sx, 0, (size_t)n * sizeof *s->sx);
    for (int i = 0; i < s->nr; i++)
        s->sx[n + i] = s->active[i] ? s->resid[i] - s->nu[i] : 0;
    MechrtStatus st = mechrt_host_kkt_solve_refined(s->kkt, w, s->sx, s->sw);
    if (st != MECHRT_OK)
        return st;
    s->res->kkt_solves++;
    for (int j = 0; j < n; j++)
        qd[j] -= s->sx[j];
    return all_finite(n, qd) ? MECHRT_OK : MECHRT_ENOTFINITE;
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
        fail(s, st, t, "velocity projection");
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
    MechrtStatus st = !dense_ready(s) ? MECHRT_EINVAL
                      : mechrt_dynamics_rows(&s->kc, &ro, y, t, s->active, s->work,
                                             s->lwork, &rep);
    if (st != MECHRT_OK) {
        fail(s, st, t, "the rank of the Jacobian");
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
    bool evaluated = sparse_eval(s, y, y + s->nq, t, false) == MECHRT_OK;
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

/* After a step (or at the start): projection when on, then the rows; the
   sparse path chooses the rows before the velocity projection, which
   uses them. */
static bool settle(Sim *s, double *y, double t, bool project)
{
    s->cache_ok = false;    /* y and the rows change */
    if (!s->kkt)
        return (!project || (settle_positions(s, y, t) && settle_velocities(s, y, t)))
               && choose_rows(s, y, t, NULL);
    return (!project || settle_positions(s, y, t)) && sparse_rows(s, y, t)
           && (!project || settle_velocities(s, y, t));
}

/* ---- set-up ------------------------------------------------------------------ */

static const gsl_odeiv2_step_type *step_type(SimMethod m)
{
    switch (m) {
    case SIM_RK8PD: return gsl_odeiv2_step_rk8pd;
    case SIM_RKF45: return gsl_odeiv2_step_rkf45;
    case SIM_RK4IMP: return gsl_odeiv2_step_rk4imp;
    case SIM_MSBDF: return gsl_odeiv2_step_msbdf;
    }
    return gsl_odeiv2_step_rk8pd;
}

/* The sparse path's kernels are there (and rows to constrain). */
static bool sim_sparse_can(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                           const MechrtHostMassNz *mnz)
{
    return k->nh + k->nv > 0 && jnz && jnz->all_nz && jnz->jac.jac_nz && mnz && mnz->mass_nz;
}

/* The sparse path is taken: asked for, or auto on a large mechanism. */
static bool sim_sparse_wanted(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                              const MechrtHostMassNz *mnz, const SimOptions *o)
{
    return sim_sparse_can(k, jnz, mnz)
           && (o->linear == SIM_LINEAR_SPARSE
               || (o->linear == SIM_LINEAR_AUTO && k->nq > SIM_DENSE_MAX_NQ));
}

/* Buffers, projection objects and the GSL driver; false when out of memory. */
static bool sim_open(Sim *s, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                     const MechrtHostMassNz *mnz, const SimOptions *o, SimResult *res)
{
    size_t n = (size_t)k->nq, m = (size_t)(k->nh + k->nv);
    s->inner = k;
    s->o = o;
    s->res = res;
    s->nq = k->nq;
    s->nr = (int)m;
    s->dim = 2 * k->nq + (o->energy ? 1 : 0);
    s->kc = engine_counting(&s->counter, k, &res->calls);
    s->nu = xcalloc(m + 1, sizeof *s->nu);
    s->resid = xcalloc(m + 1, sizeof *s->resid);
    s->lambda = xcalloc(m + 1, sizeof *s->lambda);
    s->dqd = xcalloc(n, sizeof *s->dqd);
    s->qs = xcalloc(n, sizeof *s->qs);
    s->f0 = xcalloc((size_t)s->dim, sizeof *s->f0);
    s->f1 = xcalloc((size_t)s->dim, sizeof *s->f1);
    s->y = xcalloc((size_t)s->dim, sizeof *s->y);
    s->cy = xcalloc((size_t)s->dim, sizeof *s->cy);
    s->cf = xcalloc((size_t)s->dim, sizeof *s->cf);
    s->ya = xcalloc((size_t)s->dim, sizeof *s->ya);
    s->yc = xcalloc((size_t)s->dim, sizeof *s->yc);
    s->fc = xcalloc((size_t)s->dim, sizeof *s->fc);
    s->fa = xcalloc((size_t)s->dim, sizeof *s->fa);
    s->yi = xcalloc((size_t)s->dim, sizeof *s->yi);
    s->fb = xcalloc((size_t)s->dim, sizeof *s->fb);
    s->active = xcalloc(m + 1, sizeof *s->active);
    memset(s->active, 1, m + 1);
    s->dyn = o->dyn;
    s->dyn.active = s->active;
    if (sim_sparse_wanted(k, jnz, mnz, o)) {
        s->jnz = jnz;
        s->mnz = mnz;
        s->kkt = mechrt_host_kkt_new(k->nq, (int)m, jnz, mnz);
        if (!s->kkt)
            return false;
        s->res->sparse = true;
        s->sx = xcalloc(n + m, sizeof *s->sx);
        s->mq = xcalloc(n, sizeof *s->mq);
        s->sw = xcalloc(2 * (n + m), sizeof *s->sw);
        s->sphi = xcalloc(m, sizeof *s->sphi);
        s->sg = xcalloc(m, sizeof *s->sg);
        s->sforce = xcalloc(n, sizeof *s->sforce);
        s->smass = xcalloc((size_t)mnz->nnz + 1, sizeof *s->smass);
    }
    if (!s->kkt && !dense_ready(s))
        return false;
    /* W's error must not steer the step: its absolute scale is huge */
    double *scale = xcalloc((size_t)s->dim, sizeof *scale);
    for (int i = 0; i < s->dim; i++)
        scale[i] = i < 2 * s->nq ? 1.0 : 1e300;
    double span = fabs(o->t1 - o->t0), h0 = span / o->steps / 16;
    s->sys = (gsl_odeiv2_system){sim_rhs, sim_jacobian, (size_t)s->dim, s};
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    s->drv = gsl_odeiv2_driver_alloc_scaled_new(&s->sys, step_type(o->method),
                                                o->t1 > o->t0 ? h0 : -h0, o->atol, o->rtol,
                                                1.0, 0.0, scale);
    gsl_set_error_handler(old);
    free(scale);
    return s->drv != NULL;
}

static void sim_close(Sim *s)
{
    free(s->work), free(s->jac), free(s->nu), free(s->resid), free(s->lambda);
    free(s->dqd), free(s->mass), free(s->mass2), free(s->qs), free(s->f0), free(s->f1);
    free(s->y), free(s->active);
    free(s->cy), free(s->cf), free(s->ya), free(s->fa), free(s->fb), free(s->yi), free(s->yc), free(s->fc);
    free(s->qrw);
    mechrt_svd_free(s->svd);
    if (s->kkt)
        mechrt_host_kkt_counts(s->kkt, &s->res->kkt_fresh, &s->res->kkt_refactored);
    mechrt_host_kkt_free(s->kkt);
    free(s->sx), free(s->mq), free(s->sw), free(s->sphi), free(s->sg), free(s->sforce), free(s->smass);
    if (s->drv)
        gsl_odeiv2_driver_free(s->drv);
}

/* ---- the integration ---------------------------------------------------------- */

static double time_at(const SimOptions *o, int i)
{
    if (i == o->steps)
        return o->t1;
    return o->t0 + (o->t1 - o->t0) * (double)i / (double)o->steps;
}

/* The state y at t out: its accelerations and multipliers, then the
   callback; with cache, the right side there is kept for the next step. */
static bool put_state(Sim *s, const double *y, double t, SimStateFn state, void *ctx,
                      bool cache)
{
    int n = s->nq;
    MechrtDynReport rep;
    /* every row kept: the multipliers are unique and the sparse solve gives
       them; near a rank drop the dense method's minimum-norm ones */
    if (s->kkt && s->all_active
        && sparse_accel(s, y, y + n, t, NULL, s->f0, s->lambda) == MECHRT_OK) {
        if (cache) {    /* the right side the next step starts from, as sim_rhs solves it */
            memcpy(s->f1, y + n, (size_t)n * sizeof *s->f1);
            memcpy(s->f1 + n, s->f0, (size_t)n * sizeof *s->f1);
            if (s->o->energy)
                s->f1[2 * n] = sparse_mass_form(s, mechrt_host_kkt_mass(s->kkt), y + n, s->f0)
                               + half_mdot(s, y, y + n);
            cache_store(s, t, y, s->f1);
        }
        state(ctx, t, y, y + n, s->f0, s->lambda);
        s->res->states++;
        return true;
    }
    MechrtStatus st = !dense_ready(s) ? MECHRT_EINVAL
                      : mechrt_forward_dynamics(&s->kc, &s->o->dyn, y, y + n, t, s->f0,
                                                s->lambda, s->work, s->lwork, &rep);
    if (st != MECHRT_OK) {
        fail(s, st, t, "forward dynamics");
        explain_dynamics(s, st, &rep);
        return false;
    }
    state(ctx, t, y, y + n, s->f0, s->lambda);
    s->res->states++;
    return true;
}

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
static bool one_step(Sim *s, double *y, double *t, double tn, double *h)
{
    gsl_odeiv2_driver *d = s->drv;
    double hmin = SIM_HMIN_SHARE * fabs(s->o->t1 - s->o->t0), t_before = *t;
    unsigned long failed0 = d->e->failed_steps;
    /* GSL's evolve starts a step from the last one's dydt_out, f at the
       unprojected end with the old rows; where f at the projected state
       is at hand (an output state or the interpolant's end solved it
       there), count = 0 makes it evaluate f there instead, which the
       cache answers */
    if (cache_has(s, *t, y))
        d->e->count = 0;
    bool explicit_rk = s->o->method == SIM_RK8PD || s->o->method == SIM_RKF45;
    int gs = s->o->interpolate && explicit_rk ? step_without_end_f(s, t, tn, h, y)
                                              : gsl_odeiv2_evolve_apply(d->e, d->c, d->s,
                                                                        &s->sys, t, tn, h, y);
    s->res->rejected += (long)(d->e->failed_steps - failed0);
    if (gs != GSL_SUCCESS) {
        if (s->fail_status != MECHRT_OK) {
            fail(s, s->fail_status, s->fail_t, "forward dynamics");
            explain_dynamics(s, s->fail_status, &s->fail_rep);
        } else {
            fail(s, MECHRT_ESTEP, *t, "integration");
            msgf(s, "the integrator (%s) gave up (GSL: %s)", sim_method_names[s->o->method],
                 gsl_strerror(gs));
        }
        return false;
    }
    s->res->steps++;
    if ((fabs(*t - t_before) < hmin && *t != tn) || s->res->steps > s->o->max_steps) {
        fail(s, MECHRT_ESTEP, *t, "integration");
        if (s->res->steps > s->o->max_steps)
            msgf(s, "more than %ld integrator steps: the motion is stiff or too fast for "
                 "--rtol/--atol (an implicit --method may help)", s->o->max_steps);
        else
            msgf(s, "step size underflow (%.3g) before --rtol/--atol were met: a singular "
                 "position, an impact or a stiff force? (an implicit --method may help)",
                 fabs(*t - t_before));
        return false;
    }
    return true;
}

/* f at the settled state y (t) into f, kept for the next step's first
   stage; false with the message set. */
static bool end_rhs(Sim *s, const double *y, double t, double *f)
{
    if (sim_rhs(t, y, f, s) == GSL_SUCCESS)
        return true;
    if (s->fail_status == MECHRT_OK) {     /* sim_rhs records every failure; defensive */
        fail(s, MECHRT_ENOTFINITE, t, "forward dynamics");
        msgf(s, "%s", mechrt_strerror(MECHRT_ENOTFINITE));
        return false;
    }
    fail(s, s->fail_status, s->fail_t, "forward dynamics");
    explain_dynamics(s, s->fail_status, &s->fail_rep);
    return false;
}

/* The weights at t of the Hermite interpolant through nk (2 or 3) nodes
   tk (the last the newest) with value, first and second derivative at
   each, for the value (w) and its derivative (wd): 3 nk each, in the
   order (value, derivative, second derivative) per node. In the
   variable x = (t - t_last) / hs, hs the last interval, the monomial
   basis' confluent Vandermonde A gives P = phi(x)^T A^-1 d, so w solves
   A^T w = phi(x); Gaussian elimination with partial pivoting (9 x 9). */
static void hermite_weights(int nk, const double *tk, double t, double *w, double *wd)
{
    enum { NMAX = 9 };
    int nn = 3 * nk;
    double hs = tk[nk - 1] - tk[nk - 2], at[NMAX][NMAX + 2];
    for (int k = 0; k < nk; k++) {
        double xk = (tk[k] - tk[nk - 1]) / hs, pw[NMAX + 1];
        pw[0] = 1;
        for (int m = 1; m <= nn; m++)
            pw[m] = pw[m - 1] * xk;
        for (int m = 0; m < nn; m++) {      /* column 3k + i of A is row 3k + i of A^T */
            at[m][3 * k] = pw[m];
            at[m][3 * k + 1] = m >= 1 ? m * pw[m - 1] / hs : 0;          /* d/dt = d/dx / hs */
            at[m][3 * k + 2] = m >= 2 ? m * (m - 1) * pw[m - 2] / (hs * hs) : 0;
        }
    }
    double x = (t - tk[nk - 1]) / hs, pw = 1;
    for (int m = 0; m < nn; m++) {
        at[m][nn] = pw;                                     /* phi(x) */
        at[m][nn + 1] = m >= 1 ? m * (pw / (x != 0 ? x : 1)) : 0;
        pw *= x;
    }
    if (x == 0)     /* phi'(0) = (0, 1, 0, ...) */
        for (int m = 0; m < nn; m++)
            at[m][nn + 1] = m == 1;
    for (int m = 0; m < nn; m++)
        at[m][nn + 1] /= hs;
    for (int c = 0; c < nn; c++) {
        int p = c;
        for (int r = c + 1; r < nn; r++)
            if (fabs(at[r][c]) > fabs(at[p][c]))
                p = r;
        for (int j = 0; j < nn + 2; j++) {
            double tmp = at[c][j];
            at[c][j] = at[p][j];
            at[p][j] = tmp;
        }
        for (int r = c + 1; r < nn; r++) {
            double f = at[r][c] / at[c][c];
            for (int j = c; j < nn + 2; j++)
                at[r][j] -= f * at[c][j];
        }
    }
    for (int c = nn - 1; c >= 0; c--) {
        double v = at[c][nn], vd = at[c][nn + 1];
        for (int j = c + 1; j < nn; j++)
            v -= at[c][j] * w[j], vd -= at[c][j] * wd[j];
        w[c] = v / at[c][c];
        wd[c] = vd / at[c][c];
    }
}

/* yi at t: per coordinate the Hermite interpolant of q, qd, qdd at the
   nk nodes (tk[k], yk[k], fk[k]; f = (qd, qdd, ...)): quintic on one
   step, degree 8 on the last two (errors O(h^9) and O(h^8) in q and qd
   against the quintic's O(h^6) and O(h^5): at rk8pd's own steps on A02
   the quintic's velocities were off by 5e-4). The energy slot is linear
   on the last step. */
static void hermite(const Sim *s, int nk, const double *tk, double t, double *const *yk,
                    double *const *fk, double *yi)
{
    int n = s->nq;
    double w[9], wd[9];
    hermite_weights(nk, tk, t, w, wd);
    for (int j = 0; j < n; j++) {
        double q = 0, qd = 0;
        for (int k = 0; k < nk; k++) {
            double p = yk[k][j], v = fk[k][j], a = fk[k][n + j];
            q += w[3 * k] * p + w[3 * k + 1] * v + w[3 * k + 2] * a;
            qd += wd[3 * k] * p + wd[3 * k + 1] * v + wd[3 * k + 2] * a;
        }
        yi[j] = q;
        yi[n + j] = qd;
    }
    if (s->dim > 2 * n) {
        const double *ya = yk[nk - 2], *yb = yk[nk - 1];
        double u = (t - tk[nk - 2]) / (tk[nk - 1] - tk[nk - 2]);
        yi[2 * n] = ya[2 * n] + u * (yb[2 * n] - ya[2 * n]);
    }
}

/* --interpolate: steps towards t1 across the output times, settling
   after each; the output states in a step from hermite(). */
static SimStatus integrate_interpolated(Sim *s, double *y, SimStateFn state, void *ctx)
{
    const SimOptions *o = s->o;
    size_t bytes = (size_t)s->dim * sizeof *y;
    double t = o->t0, h = s->drv->h, dir = o->t1 > o->t0 ? 1 : -1;
    /* the nodes, oldest first: two steps back, one step back, the end */
    double tk[3] = {0, t, 0}, *yk[3] = {s->yc, s->ya, y}, *fk[3] = {s->fc, s->fa, s->fb};
    int nk = 1;
    watch_energy(s, y, true);
    if (!put_state(s, y, t, state, ctx, false) || !end_rhs(s, y, t, s->fa))
        return SIM_FAILED;
    memcpy(s->ya, y, bytes);
    for (int i = 1; i <= o->steps;) {
        if (!one_step(s, y, &t, o->t1, &h) || !settle(s, y, t, o->project)
            || !end_rhs(s, y, t, s->fb))
            return SIM_FAILED;
        watch_energy(s, y, false);
        tk[2] = t;
        nk = nk < 3 ? nk + 1 : 3;
        for (; i <= o->steps && dir * (time_at(o, i) - t) <= 0; i++) {
            double tn = time_at(o, i);
            if (tn == t)
                memcpy(s->yi, y, bytes);
            else
                hermite(s, nk, tk + 3 - nk, tn, yk + 3 - nk, fk + 3 - nk, s->yi);
            if (!put_state(s, s->yi, tn, state, ctx, false))
                return SIM_FAILED;
        }
        /* shift the nodes: c <- a, a <- the end */
        double *ty = s->yc, *tf = s->fc;
        s->yc = s->ya, s->fc = s->fa;
        s->ya = ty, s->fa = tf;
        memcpy(s->ya, y, bytes);
        memcpy(s->fa, s->fb, bytes);
        yk[0] = s->yc, fk[0] = s->fc, yk[1] = s->ya, fk[1] = s->fa;
        tk[0] = tk[1], tk[1] = t;
    }
    return SIM_OK;
}

/* From the consistent state in y: the output times, stepping and projecting. */
static SimStatus integrate(Sim *s, double *y, SimStateFn state, void *ctx)
{
    const SimOptions *o = s->o;
    if (o->interpolate && o->method != SIM_MSBDF)
        return integrate_interpolated(s, y, state, ctx);
    bool per_step = o->project && o->method != SIM_MSBDF;
    double t = o->t0, h = s->drv->h;
    watch_energy(s, y, true);
    if (!put_state(s, y, t, state, ctx, true))
        return SIM_FAILED;
    for (int i = 1; i <= o->steps; i++) {
        double tn = time_at(o, i);
        while (t != tn) {
            if (!one_step(s, y, &t, tn, &h) || (per_step && !settle(s, y, t, true)))
                return SIM_FAILED;
            watch_energy(s, y, false);
        }
        if (!per_step) {
            if (!settle(s, y, t, o->project))
                return SIM_FAILED;
            if (o->project)
                gsl_odeiv2_driver_reset(s->drv);    /* the multistep history is stale */
            watch_energy(s, y, false);
        }
        if (!put_state(s, y, t, state, ctx, true))
            return SIM_FAILED;
    }
    return SIM_OK;
}

static SimStatus bad_input(SimResult *res, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static SimStatus bad_input(SimResult *res, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(res->message, sizeof res->message, fmt, ap);
    va_end(ap);
    res->status = SIM_BAD_INPUT;
    res->cause = MECHRT_EINVAL;
    return SIM_BAD_INPUT;
}

/* Options and kernels usable; SIM_OK or SIM_BAD_INPUT with the message. */
static SimStatus check_input(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                             const MechrtHostMassNz *mnz, const SimOptions *o, SimResult *res)
{
    if (!sim_has_masses(k))
        return bad_input(res, "the mechanism has no masses: forward dynamics needs `mass` "
                         "statements (and gravity or forces) in the file");
    if (o->steps < 1)
        return bad_input(res, "the number of steps must be at least 1, not %d", o->steps);
    if (!isfinite(o->t0) || !isfinite(o->t1) || o->t0 == o->t1)
        return bad_input(res, "the time interval must be finite and not empty (t0 = %g, "
                         "t1 = %g)", o->t0, o->t1);
    if (!(o->rtol >= 0) || !(o->atol >= 0) || (o->rtol == 0 && o->atol == 0))
        return bad_input(res, "--rtol and --atol must be non-negative and not both 0");
    if (k->nh > k->nq)
        return bad_input(res, "%d holonomic rows for %d coordinates: the position "
                         "projection needs at most one row per coordinate", k->nh, k->nq);
    if (o->linear == SIM_LINEAR_SPARSE && !sim_sparse_can(k, jnz, mnz))
        return bad_input(res, "--linear sparse needs the generated kernels' nonzeros (--engine "
                         "jit or aot) and at least one constraint row");
    return SIM_OK;
}

SimStatus sim_integrate(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                        const MechrtHostMassNz *mnz, const SimOptions *o, const double *q0,
                        SimStateFn state, void *state_ctx, SimResult *res)
{
    memset(res, 0, sizeof *res);
    res->t_fail = NAN;
    res->min_pivot_ratio = 1;
    if (check_input(k, jnz, mnz, o, res) != SIM_OK)
        return SIM_BAD_INPUT;
    Sim s;
    memset(&s, 0, sizeof s);
    SimStatus status = SIM_FAILED;
    if (!sim_open(&s, k, jnz, mnz, o, res)) {
        snprintf(res->message, sizeof res->message, "t = %.10g: out of memory", o->t0);
        res->status = SIM_FAILED;
        res->cause = MECHRT_EINVAL;
        res->t_fail = o->t0;
        sim_close(&s);
        return SIM_FAILED;
    }
    double *y = xcalloc((size_t)s.dim, sizeof *y);
    memcpy(y, q0, (size_t)s.nq * sizeof *y);
    if (o->qd0)
        memcpy(y + s.nq, o->qd0, (size_t)s.nq * sizeof *y);
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    double c0 = pipeline_now();
    clock_t cpu0 = clock();
    if (settle(&s, y, o->t0, true))
        status = integrate(&s, y, state, state_ctx);
    res->seconds = pipeline_now() - c0;
    res->cpu_seconds = (double)(clock() - cpu0) / CLOCKS_PER_SEC;
    gsl_set_error_handler(old);
    res->status = status;
    free(y);
    sim_close(&s);
    return status;
}

/* Construction, then Newton onto the rows from the file's values (as run
   does at t0); q holds the result. False with the message set. */
static bool assemble_at_t0(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                           const MechrtHostMassNz *mnz, const SimOptions *o, double *q,
                           SimResult *res)
{
    bool sparse = sim_sparse_wanted(k, jnz, mnz, o);
    res->constructed = construct_with_kernels(m, k, o->t0, q);
    /* the sparse path's Newton by SuiteSparseQR: the dense SVD is O(nq^3) */
    MechrtHost *host = sparse ? mechrt_host_new_projector(k, jnz) : mechrt_host_new(k);
    if (!host) {
        snprintf(res->message, sizeof res->message, "t = %.10g: out of memory", o->t0);
        return false;
    }
    double *start = xmalloc((size_t)m->nq * sizeof *start);
    memcpy(start, q, (size_t)m->nq * sizeof *q);
    MechrtReport rep;
    MechrtStatus st = mechrt_host_project(host, &o->mechrt, q, o->t0, &rep);
    mechrt_host_free(host);
    bool ok = st == MECHRT_OK;
    if (!ok && sparse && m->nq > SIM_DENSE_MAX_NQ) {
        /* the restarts' dense SVDs would take hours here: the sparse
           Newton's own failure, in the same words */
        snprintf(res->message, sizeof res->message, "t = %.10g: could not assemble from "
                 "these initial values: after %d iterations of minimum-norm Newton the "
                 "largest residual is %.3g in row %s (%s)", o->t0, rep.iterations,
                 rep.residual, rep.worst_row >= 0 ? m->rows[rep.worst_row].name : "?",
                 mechrt_strerror(st));
    } else if (!ok) {
        AnalysisOptions ao = analysis_default_options();
        AssembleResult ar;
        ao.tol_phi = o->mechrt.tol_phi;
        ao.tol_dq = o->mechrt.tol_dq;
        ao.max_iter = o->assembly_max_iter;
        ao.stall_iter = ASSEMBLE_ROUGH_STALL;
        memcpy(q, start, (size_t)m->nq * sizeof *q);
        ok = assemble_restarting(k, o->t0, q, &ao, &ar);
        res->assembled_robustly = true;
        if (!ok)
            snprintf(res->message, sizeof res->message, "t = %.10g: could not assemble from "
                     "these initial values: after %d iterations of minimum-norm Newton the "
                     "largest residual is %.3g in row %s", o->t0, ar.iterations, ar.residual,
                     ar.worst_row >= 0 ? m->rows[ar.worst_row].name : "?");
    }
    free(start);
    return ok;
}

SimStatus sim_run(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                  const MechrtHostMassNz *mnz, const SimOptions *o, SimStateFn state,
                  void *state_ctx, SimResult *res)
{
    memset(res, 0, sizeof *res);
    res->t_fail = NAN;
    if (k->nq != m->nq || k->nh != m->nh || k->nv != m->nv)
        return bad_input(res, "internal error: kernels for %d/%d/%d coordinates/rows, "
                         "model with %d/%d/%d", k->nq, k->nh, k->nv, m->nq, m->nh, m->nv);
    if (check_input(k, jnz, mnz, o, res) != SIM_OK)
        return SIM_BAD_INPUT;
    double *q = xmalloc((size_t)m->nq * sizeof *q);
    memcpy(q, m->q0, (size_t)m->nq * sizeof *q);
    SimResult pre = {0};
    if (!assemble_at_t0(m, k, jnz, mnz, o, q, &pre)) {
        *res = pre;
        res->status = SIM_FAILED;
        res->cause = MECHRT_EMAXITER;
        res->t_fail = o->t0;
        free(q);
        return SIM_FAILED;
    }
    double move = 0;
    for (int i = 0; i < m->nq; i++)
        move = fmax(move, fabs(q[i] - m->q0[i]));
    if (pre.assembled_robustly && o->notes)
        fprintf(o->notes, "%s: note: Newton could not start from the file's initial values; "
                "minimum-norm Newton assembled the mechanism at t = %.10g\n", m->file, o->t0);
    SimStatus st = sim_integrate(k, jnz, mnz, o, q, state, state_ctx, res);
    res->constructed = pre.constructed;
    res->assembled_robustly = pre.assembled_robustly;
    res->assembly_move = move;
    free(q);
    return st;
}
