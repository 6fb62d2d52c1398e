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
 * Large mechanisms (SimOptions.linear; auto above ANALYSIS_DENSE_MAX_NQ
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
 *
 * The pieces: sim_state.c (set-up, failures), counting.c, rhs.c (the right
 * side), kkt.c (its sparse path), project.c, energy.c, step.c, watch.c
 * (a collapsing step size, rows that turn abruptly, --max-steps) and
 * hermite.c (output between steps); this file drives them.
 */
#include "sim.h"

#include "energy.h"
#include "hermite.h"
#include "kkt.h"
#include "project.h"
#include "rhs.h"
#include "sim_state.h"
#include "step.h"

#include "../analysis/assemble_t0.h"
#include "../analysis/limit.h"
#include "../base/arena.h"
#include "../pipeline/pipeline.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_errno.h>

/* The note on how far assembly moved the file's values: beyond this
   share of their size, as run's RunOptions.move_note. */
#define SIM_MOVE_NOTE 1e-3

const char *const sim_method_names[] = {"rk8pd", "rkf45", "rk4imp", "msbdf", NULL};

SimOptions sim_default_options(void)
{
    SimOptions o;
    memset(&o, 0, sizeof o);
    o.t0 = 0;
    o.t1 = 1;
    o.steps = 100;
    o.method = SIM_RK8PD;
    o.rtol = 5e-11;     /* IFToMM A01: 1e-10 ended 1.06e-5 away, 5e-11 5.2e-6 */
    o.atol = 5e-11;
    o.dyn = mechrt_dyn_default_options();
    o.mechrt = mechrt_default_options();
    o.project = true;
    o.row_tol = 1e-4;
    o.energy = true;
    o.qd0 = NULL;
    o.assembly_max_iter = 100;
    o.max_steps = 10000000;
    o.notes = NULL;
    o.linear = ANALYSIS_LINEAR_AUTO;
    return o;
}

bool sim_has_masses(const MechrtKernels *k)
{
    return k && k->mass && k->force;
}

/* The callback with the state y at t, its accelerations in s->f0 and
   multipliers in s->lambda; with redundant rows left out, first their
   check (false, the failure in s->res, when one is violated), and the
   multipliers spread over every row. */
static bool deliver(Sim *s, const double *y, double t, SimStateFn state, void *ctx)
{
    Redundant *red = s->o->redundant;
    int n = s->nq;
    if (!red) {
        state(ctx, t, y, y + n, s->f0, s->lambda);
        s->res->states++;
        return true;
    }
    int row;
    const char *level;
    double tol = s->o->mechrt.tol_phi;
    if (redundant_check(red, y, y + n, s->f0, t, tol, &row, &level) > 1) {
        sim_fail(s, MECHRT_EMAXITER, t, "the check of the redundant rows");
        redundant_explain(red, y, y + n, s->f0, t, tol, s->res->message,
                          sizeof s->res->message);
        return false;
    }
    state(ctx, t, y, y + n, s->f0, redundant_expand(red, s->lambda));
    s->res->states++;
    return true;
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
        && sim_sparse_accel(s, y, y + n, t, NULL, s->f0, s->lambda) == MECHRT_OK) {
        if (cache) {    /* the right side the next step starts from, as sim_rhs solves it */
            memcpy(s->f1, y + n, (size_t)n * sizeof *s->f1);
            memcpy(s->f1 + n, s->f0, (size_t)n * sizeof *s->f1);
            if (s->o->energy)
                s->f1[2 * n] = sim_sparse_mass_form(s, mechrt_host_kkt_mass(s->kkt), y + n, s->f0)
                               + sim_half_mdot(s, y, y + n);
            sim_cache_store(s, t, y, s->f1);
        }
        return deliver(s, y, t, state, ctx);
    }
    MechrtStatus st = !sim_dense_ready(s) ? MECHRT_EINVAL
                      : mechrt_forward_dynamics(&s->kc, &s->o->dyn, y, y + n, t, s->f0,
                                                s->lambda, s->work, s->lwork, &rep);
    if (st != MECHRT_OK) {
        sim_fail(s, st, t, "forward dynamics");
        sim_explain_dynamics(s, st, &rep, y);
        return false;
    }
    return deliver(s, y, t, state, ctx);
}

/* --interpolate: steps towards t1 across the output times, settling
   after each; the output states in a step from sim_hermite(). */
static AnalysisStatus integrate_interpolated(Sim *s, double *y, SimStateFn state, void *ctx)
{
    const SimOptions *o = s->o;
    size_t bytes = (size_t)s->dim * sizeof *y;
    double t = o->t0, h = s->drv->h, dir = o->t1 > o->t0 ? 1 : -1;
    /* the nodes, oldest first: two steps back, one step back, the end */
    double tk[3] = {0, t, 0}, *yk[3] = {s->yc, s->ya, y}, *fk[3] = {s->fc, s->fa, s->fb};
    int nk = 1;
    sim_watch_energy(s, y, true);
    if (!put_state(s, y, t, state, ctx, false) || !sim_end_rhs(s, y, t, s->fa))
        return ANALYSIS_FAILED;
    memcpy(s->ya, y, bytes);
    for (int i = 1; i <= o->steps;) {
        if (!sim_one_step(s, y, &t, o->t1, &h) || !sim_settle(s, y, t, o->project)
            || !sim_end_rhs(s, y, t, s->fb))
            return ANALYSIS_FAILED;
        sim_watch_energy(s, y, false);
        tk[2] = t;
        nk = nk < 3 ? nk + 1 : 3;
        for (; i <= o->steps; i++) {
            double tn = analysis_time_at(o->t0, o->t1, o->steps, i);
            if (!(dir * (tn - t) <= 0))
                break;      /* beyond this step: the next one's */
            if (tn == t)
                memcpy(s->yi, y, bytes);
            else
                sim_hermite(s, nk, tk + 3 - nk, tn, yk + 3 - nk, fk + 3 - nk, s->yi);
            if (!put_state(s, s->yi, tn, state, ctx, false))
                return ANALYSIS_FAILED;
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
    return ANALYSIS_OK;
}

/* From the consistent state in y: the output times, stepping and projecting. */
static AnalysisStatus integrate(Sim *s, double *y, SimStateFn state, void *ctx)
{
    const SimOptions *o = s->o;
    if (o->interpolate && o->method != SIM_MSBDF)
        return integrate_interpolated(s, y, state, ctx);
    bool per_step = o->project && o->method != SIM_MSBDF;
    double t = o->t0, h = s->drv->h;
    sim_watch_energy(s, y, true);
    if (!put_state(s, y, t, state, ctx, true))
        return ANALYSIS_FAILED;
    for (int i = 1; i <= o->steps; i++) {
        double tn = analysis_time_at(o->t0, o->t1, o->steps, i);
        while (t != tn) {
            if (!sim_one_step(s, y, &t, tn, &h) || (per_step && !sim_settle(s, y, t, true)))
                return ANALYSIS_FAILED;
            sim_watch_energy(s, y, false);
        }
        if (!per_step) {
            if (!sim_settle(s, y, t, o->project))
                return ANALYSIS_FAILED;
            if (o->project)
                gsl_odeiv2_driver_reset(s->drv);    /* the multistep history is stale */
            sim_watch_energy(s, y, false);
        }
        if (!put_state(s, y, t, state, ctx, true))
            return ANALYSIS_FAILED;
    }
    return ANALYSIS_OK;
}

static AnalysisStatus bad_input(SimResult *res, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static AnalysisStatus bad_input(SimResult *res, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(res->message, sizeof res->message, fmt, ap);
    va_end(ap);
    res->status = ANALYSIS_BAD_INPUT;
    res->cause = MECHRT_EINVAL;
    return ANALYSIS_BAD_INPUT;
}

/* Options and kernels usable; ANALYSIS_OK or ANALYSIS_BAD_INPUT with the message. */
static AnalysisStatus check_input(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                                  const MechrtHostMassNz *mnz, const SimOptions *o,
                                  SimResult *res)
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
    if (o->linear == ANALYSIS_LINEAR_SPARSE && !sim_sparse_can(k, jnz, mnz))
        return bad_input(res, "--linear sparse needs the generated kernels' nonzeros (--engine "
                         "jit or aot) and at least one constraint row");
    return ANALYSIS_OK;
}

AnalysisStatus sim_integrate(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                             const MechrtHostMassNz *mnz, const SimOptions *o, const double *q0,
                             SimStateFn state, void *state_ctx, SimResult *res)
{
    memset(res, 0, sizeof *res);
    res->t_fail = NAN;
    res->min_pivot_ratio = 1;
    if (check_input(k, jnz, mnz, o, res) != ANALYSIS_OK)
        return ANALYSIS_BAD_INPUT;
    Sim s;
    memset(&s, 0, sizeof s);
    AnalysisStatus status = ANALYSIS_FAILED;
    if (!sim_open(&s, k, jnz, mnz, o, res)) {
        snprintf(res->message, sizeof res->message, "t = %.10g: out of memory", o->t0);
        res->status = ANALYSIS_FAILED;
        res->cause = MECHRT_EINVAL;
        res->t_fail = o->t0;
        sim_close(&s);
        return ANALYSIS_FAILED;
    }
    double *y = xcalloc((size_t)s.dim, sizeof *y);
    memcpy(y, q0, (size_t)s.nq * sizeof *y);
    if (o->qd0)
        memcpy(y + s.nq, o->qd0, (size_t)s.nq * sizeof *y);
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    double c0 = pipeline_now();
    clock_t cpu0 = clock();
    if (sim_settle(&s, y, o->t0, true))
        status = integrate(&s, y, state, state_ctx);
    if (status == ANALYSIS_FAILED && res->states > 0 && o->model && isfinite(res->t_fail)
        && limit_explain(o->model, k, y, res->t_fail, LIMIT_STOPPED, res->message, sizeof res->message))
        res->cause = MECHRT_ESING;      /* a limit position, said first */
    res->seconds = pipeline_now() - c0;
    res->cpu_seconds = (double)(clock() - cpu0) / CLOCKS_PER_SEC;
    gsl_set_error_handler(old);
    res->status = status;
    free(y);
    sim_close(&s);
    return status;
}

/* Construction, then Newton onto the rows from the file's values (as run
   does at t0: assemble_at_t0, its default projection, run's note); q
   holds the result. False with the message set. */
static bool start_at_t0(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                        const MechrtHostMassNz *mnz, const SimOptions *o, double *q,
                        SimResult *res)
{
    bool sparse = sim_sparse_wanted(k, jnz, mnz, o);
    /* the robust restarts' dense SVDs would take hours on a large sparse mechanism */
    AssembleT0Options ao = {.t0 = o->t0, .mechrt = &o->mechrt,
                            .robust = !(sparse && m->nq > ANALYSIS_DENSE_MAX_NQ),
                            .rough = analysis_default_options()};
    ao.rough.tol_phi = o->mechrt.tol_phi;
    ao.rough.tol_dq = o->mechrt.tol_dq;
    ao.rough.max_iter = o->assembly_max_iter;
    AssembleT0Report rep;
    bool ok = assemble_at_t0(m, k, sparse ? jnz : NULL, &ao, q, &rep);
    res->constructed = rep.constructed;
    res->assembled_robustly = rep.robust;
    if (rep.out_of_memory)
        snprintf(res->message, sizeof res->message, "t = %.10g: out of memory", o->t0);
    else if (!ok)
        assemble_t0_describe(m, k, &rep, q, res->message, sizeof res->message);
    else
        res->assembly_move = assemble_t0_note(o->notes, m, &rep, m->q0, q, SIM_MOVE_NOTE);
    return ok;
}

/* sim_run on m and its kernels, input checked: o->redundant set when m
   and k are the rows kept of a model with redundant rows. */
static AnalysisStatus run_on(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                             const MechrtHostMassNz *mnz, const SimOptions *o, SimStateFn state,
                             void *state_ctx, SimResult *res)
{
    double *q = xmalloc((size_t)m->nq * sizeof *q);
    memcpy(q, m->q0, (size_t)m->nq * sizeof *q);
    SimResult pre = {0};
    if (!start_at_t0(m, k, jnz, mnz, o, q, &pre)) {
        *res = pre;
        res->status = ANALYSIS_FAILED;
        res->cause = MECHRT_EMAXITER;
        res->t_fail = o->t0;
        free(q);
        return ANALYSIS_FAILED;
    }
    double move = pre.assembly_move;
    const char **names = xcalloc((size_t)m->nr + 1, sizeof *names);
    for (int i = 0; i < m->nr; i++)
        names[i] = m->rows[i].name;
    SimOptions named = *o;
    named.row_names = names;
    named.model = m;
    AnalysisStatus st = sim_integrate(k, jnz, mnz, &named, q, state, state_ctx, res);
    free(names);
    res->constructed = pre.constructed;
    res->assembled_robustly = pre.assembled_robustly;
    res->assembly_move = move;
    free(q);
    return st;
}

AnalysisStatus sim_run(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                       const MechrtHostMassNz *mnz, const SimOptions *o, SimStateFn state,
                       void *state_ctx, SimResult *res)
{
    memset(res, 0, sizeof *res);
    res->t_fail = NAN;
    if (k->nq != m->nq || k->nh != m->nh || k->nv != m->nv)
        return bad_input(res, "internal error: kernels for %d/%d/%d coordinates/rows, "
                         "model with %d/%d/%d", k->nq, k->nh, k->nv, m->nq, m->nh, m->nv);
    if (!redundant_applies(m)) {
        if (check_input(k, jnz, mnz, o, res) != ANALYSIS_OK)
            return ANALYSIS_BAD_INPUT;
        return run_on(m, k, jnz, mnz, o, state, state_ctx, res);
    }
    Redundant red;
    char why[SIM_MESSAGE_MAX];
    if (!redundant_start(&red, m, k, jnz, o->t0, false, o->notes, why, sizeof why))
        return bad_input(res, "%s", why);
    SimOptions ro = *o;
    ro.redundant = &red;
    AnalysisStatus st = check_input(&red.k, jnz ? &red.jnz : NULL, mnz, &ro, res);
    if (st == ANALYSIS_OK) {
        redundant_note_reactions(o->notes, &red);
        st = run_on(&red.view, &red.k, jnz ? &red.jnz : NULL, mnz, &ro, state, state_ctx, res);
    }
    redundant_close(&red);
    return st;
}
