/* run.c - kinematic analysis over time: assembly, predictor-corrector steps, integration.
 *
 * A mechanism with holonomic rows only (nh == nq) is stepped by the
 * freestanding runtime (mechrt_step): second-order Taylor predictor from
 * the last q, qd, qdd, Newton corrector on Phi(q, t) = 0 with one call of
 * the fused `all` kernel per iteration, then velocity and acceleration
 * from one LU of the converged Jacobian (Haug 1989, section 6.1).
 * A mechanism with velocity-level rows (nh + nv == nq, nv > 0) has no
 * position equations for nv of its directions: its positions are
 * integrated (runtime/host: GSL odeiv2, projection onto Phi = 0 after every
 * step) and its velocities and accelerations solved at each output time.
 *
 * A coarse step can leave the branch it should follow: the predictor
 * lands nearer another assembly (the crossed four-bar) or another turn of
 * an angle, and Newton converges there without complaint. So every step is
 * checked (step_quiet): Newton must have needed few iterations and
 * corrected no coordinate by more than a small share of the motion the
 * predictor gave it. An interval whose step fails the check, or fails, is
 * redone from its start in 2, 4, 8 ... substeps (RunOptions.max_substeps at
 * most), each a predictor and a corrector, until every substep of a level
 * passes the check, or a level whose substeps all took few Newton
 * iterations ends where the previous level did (a fully driven mechanism's
 * position at a time depends only on its branch and turns, so two levels
 * that agree followed the same one; this accepts a start from rest, where
 * the predicted motion is nil at any step size). Only the grid's states are
 * reported. Past the limit the run fails: "the motion is too fast for the
 * step", or the error of the finest level. A fine step, one Newton
 * iteration, passes the check for the price of saving the state it started
 * from.
 *
 * The linear algebra is chosen once per run (RunOptions.linear): the
 * runtime's dense LU (mechrt_step), or KLU on the Jacobian's nonzeros
 * (mechrt_host_sparse_step, runtime/host/sparse_step.c: the same predictor,
 * Newton and analysis); run_step is the one place the two differ, so the
 * stepping, its checks and substeps are shared. The sparse path never forms
 * an nr x nq matrix: its diagnostics name the failing pivot's row and
 * coordinate instead of an SVD's, and the nearly singular test at t0 is
 * KLU's condition estimate. With velocity-level rows the sparse path's
 * host (mechrt_host_new_sparse) solves the velocities by KLU and projects
 * by SuiteSparseQR's minimum-norm steps.
 *
 * Failures stop the run and say when, why and where: the time as
 * `t = VALUE`, the runtime's cause, the row with the largest residual or
 * the coordinate where elimination found no pivot, and, from an SVD of the
 * Jacobian at the failing state, the rows and coordinates of the
 * dependency (a toggle, a dead centre, redundant rows). Stretches where the
 * condition estimate exceeds MechrtOptions.cond_warn are warned about once,
 * when they begin, with a note when they end.
 *
 * More holonomic rows than coordinates (a four-bar written in 3D with
 * four revolutes about z): the redundant rows are found once at t0 and
 * the run is the one of the other rows (analysis/redundant.c: their
 * kernels and pattern, a view of the model with their names), with every
 * state checked on the redundant rows too (redundant_at).
 *
 * run_analysis_forces adds inverse dynamics (`run --forces`): at every
 * state, lambda from Phi_q^T lambda = Q - M qdd by the runtime's
 * mechrt_inverse_dynamics, inside the step's timing so that --stats
 * measures what the reactions cost (dyn/inverse.c).
 *
 * The pieces: step.c (the checked step, the rank corrector), subdivide.c,
 * diagnose.c (failures and warnings), start.c (the assembly at t0),
 * kernels.c (timing, the sparse bundle).
 */
#include "run.h"

#include "diagnose.h"
#include "run_state.h"
#include "start.h"
#include "step.h"
#include "subdivide.h"

#include "../analysis/limit.h"
#include "../base/arena.h"
#include "../dyn/blame.h"
#include "../pipeline/pipeline.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

RunOptions run_default_options(void)
{
    RunOptions o;
    o.t0 = 0;
    o.t1 = 1;
    o.steps = 100;
    o.max_substeps = 64;
    o.mechrt = mechrt_default_options();
    o.ode = mechrt_ode_default_options();
    o.move_note = 1e-3;
    o.assembly_max_iter = 100;
    o.notes = NULL;
    o.linear = ANALYSIS_LINEAR_AUTO;
    o.max_dense_entries = 0;
    o.lend_lu = NULL;
    return o;
}

/* A state computed at t (in r->q, r->qd, r->qdd): the condition watch,
   then out to the caller. */
static void put_state(Run *r, double t, const MechrtReport *rep, RunStateFn state, void *ctx)
{
    run_watch_condition(r, t, rep);
    if (r->fstate && r->red)
        r->fstate(ctx, t, r->q, r->qd, r->qdd, redundant_expand(r->red, r->inv.lambda));
    else if (r->fstate)
        r->fstate(ctx, t, r->q, r->qd, r->qdd, r->inv.lambda);
    else
        state(ctx, t, r->q, r->qd, r->qdd);
    r->res->states++;
}

/* The redundant rows left out of the run (r->red) at the state just
   computed: false, with the failure in r->res, when one is violated. */
static bool redundant_at(Run *r, double t)
{
    int row;
    const char *level;
    if (redundant_check(r->red, r->q, r->qd, r->qdd, t, r->o->mechrt.tol_phi, &row,
                        &level) <= 1)
        return true;
    r->res->status = ANALYSIS_FAILED;
    r->res->cause = MECHRT_EMAXITER;
    r->res->t_fail = t;
    redundant_explain(r->red, r->q, r->qd, r->qdd, t, r->o->mechrt.tol_phi, r->res->message,
                      sizeof r->res->message);
    return false;
}

/* Inverse dynamics at the state just computed (t, r->q, r->qd, r->qdd),
   into r->lambda; nothing without run_analysis_forces. False, with the
   failure in r->res, when the solve fails. First, with redundant rows,
   their check. */
static bool inverse_at(Run *r, double t)
{
    if (r->red && !redundant_at(r, t))
        return false;
    if (!r->fstate)
        return true;
    MechrtStatus st = inverse_solve(&r->inv, r->k, r->q, r->qd, r->qdd, t);
    r->res->force_residual = r->inv.residual;
    r->res->force_redundant = r->inv.redundant;
    if (st == MECHRT_OK)
        return true;
    r->res->status = ANALYSIS_FAILED;
    r->res->cause = st;
    r->res->t_fail = t;
    r->res->message[0] = '\0';
    msgf(r, "t = %.10g: inverse dynamics failed: ", t);
    if (st != MECHRT_ENOTFINITE || !blame_force(r->m, r->o->source, t, r->q, r->qd,
                                                r->res->message, sizeof r->res->message))
        msgf(r, "%s", st == MECHRT_ENOTFINITE
                          ? "NaN or infinity in M(q), Q(q, qd, t) or the multipliers"
                          : mechrt_strerror(st));
    return false;
}

/* Newton at t0 for run_assemble: the step of length 0 (q is r->q), which
   also solves the velocities and accelerations there. */
static MechrtStatus step_at_t0(void *ctx, double *q, MechrtReport *rep)
{
    Run *r = ctx;
    (void)q;
    return run_step(r, r->o->t0, 0.0, rep);
}

/* Holonomic rows only: the runtime's predictor-corrector step, checked and
   subdivided when needed (see the top of this file). */
static AnalysisStatus run_holonomic(Run *r, RunStateFn state, void *ctx)
{
    const RunOptions *o = r->o;
    MechrtReport rep;
    AnalysisStatus status = ANALYSIS_OK;
    size_t nq = (size_t)r->nq;
    double *keep = xmalloc((9 + RUN_HISTORY) * nq * sizeof *keep);
    r->sq = keep, r->sqd = keep + nq, r->sqdd = keep + 2 * nq;
    r->iq = keep + 3 * nq, r->lq = keep + 6 * nq, r->fq = keep + 7 * nq, r->rq = keep + 8 * nq;
    r->hist_qdd = keep + 9 * nq;
    r->hist_n = 0;
    if (!run_assemble(r, step_at_t0, r, true, &rep, "assembly from the file's initial values")) {
        status = ANALYSIS_FAILED;
        goto out;
    }
    if (!inverse_at(r, o->t0)) {
        status = ANALYSIS_FAILED;
        goto out;
    }
    put_state(r, o->t0, &rep, state, ctx);

    double t = o->t0;
    for (int i = 1; i <= o->steps; i++) {
        double tn = analysis_time_at(o->t0, o->t1, o->steps, i);
        clock_t cpu0 = clock();     /* before the wall clock: clock() is a system call */
        double c0 = pipeline_now(); /* of about 0.65 us here, not the step's cost */
        bool quiet;
        StepCheck chk = {-1, 0, 0, 0};
        r->res->rank_failed = false;
        MechrtStatus st = run_checked_step(r, t, tn - t, &rep, &quiet, &chk);
        bool ok = quiet || run_subdivide(r, t, tn, st, &rep, &chk);
        if (!ok && r->res->rank_failed) {
            run_note_rank_failure(r);
            /* the start of the step that failed (sq), the last state
               reached: a driver past its reach, said first */
            if (limit_explain(r->m, r->k, r->sq, r->res->rank_t, LIMIT_STEPPED,
                              r->res->message, sizeof r->res->message))
                r->res->t_fail = r->res->rank_t;
        }
        if (ok && !inverse_at(r, tn))
            ok = false;
        r->res->step_seconds += pipeline_now() - c0;
        r->res->step_cpu_seconds += (double)(clock() - cpu0) / CLOCKS_PER_SEC;
        if (!ok) {
            status = ANALYSIS_FAILED;
            goto out;
        }
        r->res->steps_done++;
        t = tn;
        put_state(r, t, &rep, state, ctx);
    }
out:
    free(keep);
    r->sq = r->sqd = r->sqdd = r->iq = r->lq = r->fq = r->rq = r->hist_qdd = NULL;
    free(r->rk_work);
    r->rk_work = NULL;
    return status;
}

/* Newton at t0 for run_assemble with velocity-level rows: the host's
   minimum-norm projection onto the holonomic rows. */
typedef struct ProjectAtT0 {
    MechrtHost *host;
    const MechrtOptions *mechrt;
    double t0;
} ProjectAtT0;

static MechrtStatus project_at_t0(void *ctx, double *q, MechrtReport *rep)
{
    const ProjectAtT0 *p = ctx;
    return mechrt_host_project(p->host, p->mechrt, q, p->t0, rep);
}

/* Velocity-level rows, at t0: the positions projected onto the holonomic
   rows (assembled robustly when that fails), the velocities and
   accelerations solved there, the inverse dynamics asked for. False with
   the failure in r->res. */
static bool integrated_start(Run *r, MechrtHost *host, MechrtReport *rep)
{
    const RunOptions *o = r->o;
    ProjectAtT0 p = {host, &o->mechrt, o->t0};
    if (!run_assemble(r, project_at_t0, &p, false, rep, "assembly (minimum-norm Newton)"))
        return false;
    MechrtStatus st = mechrt_host_velocity_acceleration(host, &o->mechrt, r->q, o->t0, r->qd,
                                                        r->qdd, rep);
    if (st != MECHRT_OK) {
        run_fail(r, st, o->t0, r->q, rep, "velocity and acceleration analysis");
        return false;
    }
    return inverse_at(r, o->t0);
}

/* Velocity-level rows: integrate the positions between output times. */
static AnalysisStatus run_integrated(Run *r, RunStateFn state, void *ctx)
{
    const RunOptions *o = r->o;
    MechrtReport rep;
    AnalysisStatus status = ANALYSIS_OK;
    MechrtHost *host = r->sparse ? mechrt_host_new_sparse(r->k, r->jnz) : mechrt_host_new(r->k);
    r->sp = mechrt_host_sparse_of(host);    /* a failure names its pivot */
    if (!host) {
        snprintf(r->res->message, sizeof r->res->message, "t = %.10g: out of memory", o->t0);
        r->res->status = ANALYSIS_FAILED;
        r->res->cause = MECHRT_EINVAL;
        r->res->t_fail = o->t0;
        return ANALYSIS_FAILED;
    }
    r->res->integrated = true;
    if (!integrated_start(r, host, &rep)) {
        status = ANALYSIS_FAILED;
        goto out;
    }
    put_state(r, o->t0, &rep, state, ctx);

    double t = o->t0, hstep = o->steps > 0 ? (o->t1 - o->t0) / o->steps : 0;
    for (int i = 1; i <= o->steps; i++) {
        double tn = analysis_time_at(o->t0, o->t1, o->steps, i);
        clock_t cpu0 = clock();     /* outside the wall-clock span, as in run_holonomic */
        double c0 = pipeline_now();
        long it0 = mechrt_host_stats(host)->project_iterations;
        MechrtStatus st = mechrt_host_integrate(host, &o->mechrt, &o->ode, r->q, &t, tn, &hstep,
                                                &rep);
        r->res->newton_iterations += mechrt_host_stats(host)->project_iterations - it0;
        if (st != MECHRT_OK) {
            double tf;
            const double *qf = mechrt_host_failure(host, &tf);
            bool proj = st == MECHRT_EMAXITER
                        || (st == MECHRT_ENOTFINITE && rep.worst_row >= 0);
            run_fail(r, st, tf, qf, &rep, proj ? "projection" : "integration (velocity analysis)");
            status = ANALYSIS_FAILED;
            goto out;
        }
        st = mechrt_host_velocity_acceleration(host, &o->mechrt, r->q, tn, r->qd, r->qdd, &rep);
        bool forces_ok = st != MECHRT_OK || inverse_at(r, tn);
        r->res->step_seconds += pipeline_now() - c0;
        r->res->step_cpu_seconds += (double)(clock() - cpu0) / CLOCKS_PER_SEC;
        if (st != MECHRT_OK)
            run_fail(r, st, tn, r->q, &rep, "velocity and acceleration analysis");
        if (st != MECHRT_OK || !forces_ok) {
            status = ANALYSIS_FAILED;
            goto out;
        }
        r->res->steps_done++;
        t = tn;
        put_state(r, t, &rep, state, ctx);
    }
out:
    r->res->host = *mechrt_host_stats(host);
    if (r->sp)
        mechrt_host_sparse_counts(r->sp, &r->res->fresh_factorisations,
                                  &r->res->refactorisations);
    r->sp = NULL;
    mechrt_host_free(host);
    return status;
}

static AnalysisStatus bad_input(RunResult *res, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static AnalysisStatus bad_input(RunResult *res, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(res->message, sizeof res->message, fmt, ap);
    va_end(ap);
    res->status = ANALYSIS_BAD_INPUT;
    res->cause = MECHRT_EINVAL;
    return ANALYSIS_BAD_INPUT;
}


/* Dense or sparse for this run (RunOptions.linear); false with why when
   the choice cannot be honoured. auto takes KLU for redundant rows at any
   size: the rows kept have no unrolled LU of their own, and KLU's kept
   pivot order costs half the dense LU's work there (bench/redundant.sh). */
static bool choose_linear(const Model *m, const MechrtHostJacNz *jnz, const RunOptions *o,
                          bool *sparse, char *why, size_t size)
{
    bool can = jnz != NULL;
    *sparse = o->linear == ANALYSIS_LINEAR_SPARSE
              || (o->linear == ANALYSIS_LINEAR_AUTO && can
                  && (m->nq > ANALYSIS_DENSE_MAX_NQ || redundant_applies(m)));
    if (*sparse && !jnz) {
        snprintf(why, size, "--linear sparse needs the generated kernels' sparse Jacobian, "
                 "which the generic engine does not have: use --engine jit or aot");
        return false;
    }
    if (!*sparse && run_dense_too_large(m, o)) {
        snprintf(why, size, "the dense Jacobian would have %d rows x %d coordinates = %lld "
                 "entries, more than the limit of %lld (--max-jac-entries)%s", m->nr, m->nq,
                 (long long)m->nr * m->nq, o->max_dense_entries,
                 can ? ": use --linear sparse" : "; the sparse path cannot serve this run");
        return false;
    }
    return true;
}

bool run_linear_is_sparse(const Model *m, const MechrtHostJacNz *jnz, const RunOptions *o)
{
    bool sparse;
    char why[8];
    return choose_linear(m, jnz, o, &sparse, why, sizeof why) && sparse;
}

/* The dense path's factorisation: the pattern LU on the kernels' sparse
   Jacobian (same results as lu.c's, replayed over the nonzeros), when
   there is one, the mechanism is stepped (no velocity rows) and its
   worst-case index lists stay small (ANALYSIS_DENSE_MAX_NQ); NULL otherwise.
   One block: the state, then its reals, then its ints. */
static MechrtLup *run_lup_new(const Model *m, const MechrtHostJacNz *jnz)
{
    if (!jnz || m->nv > 0 || m->nq > ANALYSIS_DENSE_MAX_NQ)
        return NULL;
    size_t lw = mechrt_lup_work_size(m->nq), liw = mechrt_lup_iwork_size(m->nq);
    MechrtLup *f = xcalloc(1, sizeof *f + lw * sizeof(double) + liw * sizeof(int));
    double *w = (double *)(f + 1);
    if (mechrt_lup_init(f, m->nq, jnz->jac.nnz, jnz->jac.row, jnz->jac.col, w, lw,
                        (int *)(w + lw), liw) != MECHRT_OK) {
        free(f);
        return NULL;
    }
    if (jnz->lu.factor && jnz->lu.solve)
        mechrt_lup_use(f, &jnz->lu);
    return f;
}

bool run_rows_match(const Model *m, char *why, size_t size)
{
    if (m->nr < m->nq) {
        int dof = m->nq - m->nr;
        snprintf(why, size, "%d degree%s of freedom %s not driven (%d coordinates, %d %s): "
                 "add %s%s", dof, dof == 1 ? "" : "s", dof == 1 ? "is" : "are", m->nq,
                 m->nr, run_plural(m->nr, "row", "rows"), dof == 1 ? "a driver" : "drivers",
                 dof == 1 ? "" : " (one per degree of freedom)");
        return false;
    }
    if (redundant_applies(m))
        return true;    /* the redundant rows are found at t0 (redundant_start) */
    if (m->nr > m->nq) {
        int extra = m->nr - m->nq;
        snprintf(why, size, "the mechanism has %d more %s than coordinates (%d rows, %d "
                 "coordinates): run needs exactly one row per coordinate; remove "
                 "redundant rows or drivers", extra, run_plural(extra, "row", "rows"),
                 m->nr, m->nq);
        return false;
    }
    return true;
}

/* The run of analyse, its input checked; red: the redundant rows left out
   (m, k and jnz are then its kept rows'), or NULL. */
static AnalysisStatus run_on(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                             bool sparse, Redundant *red, const RunOptions *o, RunStateFn state,
                             RunForcesFn fstate, void *state_ctx, RunResult *res)
{
    Run r = {0};
    r.red = red;
    r.m = m;
    r.k = k;
    r.jnz = jnz;
    r.o = o;
    r.res = res;
    r.nq = m->nq;
    r.nr = m->nr;
    size_t nq = (size_t)m->nq;
    /* one block, q | qd | qdd, so that a step's start is saved in one copy */
    r.q = xcalloc(3 * nq, sizeof *r.q);
    r.qd = r.q + nq;
    r.qdd = r.q + 2 * nq;
    r.sparse = sparse;
    if (sparse && m->nv == 0 && !(r.sp = mechrt_host_sparse_new(m->nq, jnz))) {
        free(r.q);
        return bad_input(res, "internal error: the kernels' sparse Jacobian pattern (%d "
                         "entries) is not a valid %d x %d pattern, or out of memory",
                         jnz->jac.nnz, m->nq, m->nq);
    }
    res->sparse = sparse;
    /* without the kernels' unrolled LU (written for all the rows) the
       pattern LU keeps its pivot order for only half the steps of a
       turning crank: lu.c's LU costs less there (bench/redundant.sh) */
    if (!sparse && !red)
        r.lup = run_lup_new(m, jnz);
    RunLu *lent = o->lend_lu;
    if (lent && r.lup)
        *lent = (RunLu){.lup = r.lup, .q = xcalloc(nq, sizeof *lent->q)};
    r.lwork = sparse ? MECHRT_HOST_SPARSE_WORK_LEN(m->nq) : mechrt_workspace_size(m->nq, m->nr);
    r.work = xcalloc(r.lwork, sizeof *r.work);
    memcpy(r.q, m->q0, nq * sizeof *r.q);
    if (fstate) {
        r.fstate = fstate;
        inverse_init(&r.inv, m->nq, m->nr);
        if (red)
            redundant_note_reactions(o->notes, red);
    }

    AnalysisStatus status = m->nv == 0 ? run_holonomic(&r, state, state_ctx)
                                  : run_integrated(&r, state, state_ctx);
    if (r.sp) {
        mechrt_host_sparse_counts(r.sp, &res->fresh_factorisations, &res->refactorisations);
        mechrt_host_sparse_free(r.sp);
    }
    if (lent) {
        free(lent->q);
        *lent = (RunLu){0};
    }
    if (r.lup) {
        res->fresh_factorisations = r.lup->analyses;
        res->refactorisations = r.lup->replays;
        res->generated_factorisations = r.lup->gen_factors;
        free(r.lup);
    }
    if (status == ANALYSIS_OK && r.episode)
        run_notef(&r, "note", "nearly singular from t = %.10g to the end (worst condition estimate "
              "%.3g at t = %.10g)", r.ep_start, r.ep_worst, r.ep_worst_t);
    res->status = status;
    free(r.q), free(r.work);
    inverse_free(&r.inv);
    return status;
}

/* run_analysis and run_analysis_forces: one of state and fstate. */
static AnalysisStatus analyse(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                              const RunOptions *o, RunStateFn state, RunForcesFn fstate,
                              void *state_ctx, RunResult *res)
{
    memset(res, 0, sizeof *res);
    res->t_fail = NAN;
    if (o->steps < 0)
        return bad_input(res, "the number of steps must be at least 0, not %d", o->steps);
    /* steps = 0 is the analysis at one instant, t0: t1 plays no part */
    if (!(isfinite(o->t0) && (o->steps == 0 || isfinite(o->t1)))
        || (o->steps > 0 && o->t0 == o->t1))
        return bad_input(res, "the time interval must be finite and not empty (t0 = %g, t1 = %g)",
                         o->t0, o->t1);
    if (o->max_substeps < 1)
        return bad_input(res, "the number of substeps must be at least 1, not %d",
                         o->max_substeps);
    if (k->nq != m->nq || k->nh != m->nh || k->nv != m->nv)
        return bad_input(res, "internal error: kernels for %d/%d/%d coordinates/rows, "
                         "model with %d/%d/%d", k->nq, k->nh, k->nv, m->nq, m->nh, m->nv);
    char why[sizeof res->message];
    if (!run_rows_match(m, why, sizeof why))
        return bad_input(res, "%s", why);
    bool sparse;
    if (!choose_linear(m, jnz, o, &sparse, why, sizeof why))
        return bad_input(res, "%s", why);
    if (m->nr > m->nq) {
        Redundant red;
        if (!redundant_start(&red, m, k, jnz, o->t0, true, o->notes, why, sizeof why))
            return bad_input(res, "%s", why);
        AnalysisStatus st = run_on(&red.view, &red.k, jnz ? &red.jnz : NULL, sparse, &red, o,
                                   state, fstate, state_ctx, res);
        redundant_close(&red);
        return st;
    }
    return run_on(m, k, jnz, sparse, NULL, o, state, fstate, state_ctx, res);
}

AnalysisStatus run_analysis(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                            const RunOptions *o, RunStateFn state, void *state_ctx,
                            RunResult *res)
{
    return analyse(m, k, jnz, o, state, NULL, state_ctx, res);
}

AnalysisStatus run_analysis_forces(const Model *m, const MechrtKernels *k,
                                   const MechrtHostJacNz *jnz, const RunOptions *o,
                                   RunForcesFn state, void *state_ctx, RunResult *res)
{
    if (!k->mass || !k->force) {
        memset(res, 0, sizeof *res);
        res->t_fail = NAN;
        return bad_input(res, "inverse dynamics needs masses: the mechanism has no `mass` "
                         "statements (run --forces reports the reactions of a file with "
                         "masses)");
    }
    if (o->max_dense_entries > 0 && (long long)m->nq * m->nq > o->max_dense_entries) {
        memset(res, 0, sizeof *res);
        res->t_fail = NAN;
        return bad_input(res, "inverse dynamics is dense (M and Phi_q as %d x %d matrices, "
                         "%lld entries), more than the limit of %lld (--max-jac-entries)",
                         m->nq, m->nq, (long long)m->nq * m->nq, o->max_dense_entries);
    }
    return analyse(m, k, jnz, o, NULL, state, state_ctx, res);
}
