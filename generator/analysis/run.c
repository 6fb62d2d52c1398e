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
 * run_analysis_forces adds inverse dynamics (`run --forces`): at every
 * state, lambda from Phi_q^T lambda = Q - M qdd by the runtime's
 * mechrt_inverse_dynamics, inside the step's timing so that --stats
 * measures what the reactions cost.
 */
#include "run.h"

#include "../base/arena.h"
#include "assemble.h"
#include "construct.h"
#include "../pipeline/pipeline.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* A singular value ratio below this names the dependency in a failure message. */
#define RUN_NEAR_SINGULAR 1e-7
/* Components of a singular vector at least this fraction of its largest are named. */
#define RUN_NAME_SHARE 0.2
#define RUN_NAME_MAX 6
/* Above this many coordinates the dense SVD of a failure message (O(n^3))
   would take longer than the user should wait for an error: left out. */
#define RUN_SVD_MAX_NQ 400
/* A holonomic step is quiet (trusted) when Newton took at most
   RUN_QUIET_ITER iterations and moved every coordinate away from the
   prediction by at most RUN_QUIET_SHARE times the motion the predictor gave
   it, |h qd| + h^2/2 |qdd|, plus tol_dq. On the branch the correction is the
   predictor's O(h^3) error, a small share of the O(h) motion; a jump to
   another branch or turn corrects by a link length or a radian. */
#define RUN_QUIET_ITER 3
#define RUN_QUIET_SHARE 0.05
/* Two subdivision levels agree when their positions at the end of the
   interval differ by at most RUN_AGREE * tol_dq in every coordinate. */
#define RUN_AGREE 10
/* A step whose Jacobian at the end has a condition estimate above this
   (or has no LU at all) is redone by the rank-revealing corrector
   (rank_step): an LU solve there keeps fewer than 16 - 9 digits. */
#define RUN_RANK_COND 1e9
/* The rank corrector's velocity and acceleration must satisfy their
   equations to this share (MechrtReport.inconsistency): otherwise the
   continued motion is none the mechanism can have there. */
#define RUN_BRANCH_TOL 1e-6
/* States before the current one that the rank corrector's predictor
   extrapolates the acceleration from (a cubic through four). */
#define RUN_HISTORY 3
/* The rank corrector is dense: two nq x nq matrices and O(nq^3) work per
   call. Above this many coordinates (16 MB) a singular step fails as the
   LU's does. */
#define RUN_RANK_MAX_NQ 1000

const char *const run_linear_names[] = {"auto", "dense", "sparse", NULL};

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
    o.linear = RUN_LINEAR_AUTO;
    o.max_dense_entries = 0;
    return o;
}

/* ---- the state of one run ---------------------------------------------- */

typedef struct Run {
    const Model *m;
    const MechrtKernels *k;
    const MechrtHostJacNz *jnz;  /* the kernels' sparse Jacobian, or NULL */
    const RunOptions *o;
    RunResult *res;
    int nq, nr;
    double *q, *qd, *qdd;    /* one block of 3 nq: qd == q + nq, qdd == q + 2 nq */
    double *work;
    size_t lwork;
    MechrtHostSparse *sp;    /* the sparse path's factorisation; NULL: dense (with
                                velocity-level rows: the sparse host's) */
    bool sparse;             /* the sparse path (RunOptions.linear) */
    MechrtLup *lup;          /* the dense path's pattern LU (run_lup_new); NULL: lu.c's */
    /* holonomic stepping: the start of the last step (sq | sqd | sqdd, laid
       out like q | qd | qdd), the start of the interval being subdivided
       (iq, the same layout), the end of the previous subdivision level (lq)
       and a failed step's iterate (fq) */
    double *sq, *sqd, *sqdd, *iq, *lq, *fq, *rq;
    /* through singular positions (rank_step): the QR corrector's workspace
       (allocated at the first use), and the accelerations of the last RUN_HISTORY
       trusted states before the current one, for the predictor */
    double *rk_work;
    size_t rk_lwork;
    int hist_n;
    double hist_t[RUN_HISTORY];
    double *hist_qdd;       /* RUN_HISTORY nq: entry 0 the latest */
    /* run_analysis_forces: the state callback with lambda, the dynamics
       workspace and the multipliers of the last state (nr) */
    RunForcesFn fstate;
    double *dyn_work, *lambda;
    size_t dyn_lwork;
    double dyn_rank_tol;     /* mechrt_dyn_default_options()' */
    /* a nearly singular stretch in progress */
    bool episode;
    double ep_start, ep_end, ep_worst, ep_worst_t;
} Run;

static void notef(const Run *r, const char *kind, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void notef(const Run *r, const char *kind, const char *fmt, ...)
{
    if (!r->o->notes)
        return;
    va_list ap;
    va_start(ap, fmt);
    fprintf(r->o->notes, "%s: %s: ", r->m->file, kind);
    vfprintf(r->o->notes, fmt, ap);
    fputc('\n', r->o->notes);
    va_end(ap);
}

/* Appends to res->message, truncating quietly at its size. */
static void msgf(Run *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void msgf(Run *r, const char *fmt, ...)
{
    char *msg = r->res->message;
    size_t len = strlen(msg);
    if (len + 1 >= sizeof r->res->message)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg + len, sizeof r->res->message - len, fmt, ap);
    va_end(ap);
}

/* " and " / ", " separated names of the largest components of w, largest first. */
static void name_list(Run *r, const char *const *names, const double *w, int n)
{
    int picked[RUN_NAME_MAX], count = 0;
    double wmax = 0;
    for (int i = 0; i < n; i++)
        if (w[i] > wmax)
            wmax = w[i];
    while (count < RUN_NAME_MAX) {
        int best = -1;
        for (int i = 0; i < n; i++) {
            bool taken = false;
            for (int c = 0; c < count; c++)
                taken = taken || picked[c] == i;
            if (!taken && w[i] >= RUN_NAME_SHARE * wmax && (best < 0 || w[i] > w[best]))
                best = i;
        }
        if (best < 0)
            break;
        picked[count++] = best;
    }
    for (int c = 0; c < count; c++)
        msgf(r, "%s%s", c == 0 ? "" : c + 1 == count ? " and " : ", ", names[picked[c]]);
}

/* The sparse path's account of a singular factorisation: the row and the
   coordinate of the pivot that failed (KLU's permutations undone). */
static double describe_pivot(Run *r)
{
    int row, col;
    mechrt_host_sparse_singular(r->sp, &row, &col);
    if (row >= 0 && col >= 0)
        msgf(r, "; the sparse LU found no pivot for %s in row %s (or after it)",
             r->m->coord_names[col], r->m->rows[row].name);
    return -1;
}

/* describe_dependency's dense part: the smallest singular direction of the
   dense Jacobian (at most RUN_SVD_MAX_NQ coordinates). */
static double describe_dense_dependency(Run *r, const double *q, double t, int rows,
                                        bool always)
{
    if (r->nq > RUN_SVD_MAX_NQ)
        return -1;
    size_t nq = (size_t)r->nq;
    double *jac = xcalloc((size_t)r->nr * nq + 1, sizeof *jac);
    double *roww = xcalloc((size_t)r->nr + 1, sizeof *roww);
    double *colw = xcalloc(nq, sizeof *colw);
    const char **row_names = xcalloc((size_t)r->nr + 1, sizeof *row_names);
    for (int i = 0; i < r->nr; i++)
        row_names[i] = r->m->rows[i].name;
    r->k->jac(r->k->ctx, q, t, jac);
    double ratio = mechrt_host_singular_direction(rows, r->nq, jac, roww, colw);
    if (ratio >= 0 && (always || ratio < RUN_NEAR_SINGULAR)) {
        msgf(r, "; the Jacobian there is %s along rows ", always ? "singular" : "nearly singular");
        name_list(r, row_names, roww, rows);
        msgf(r, " and coordinates ");
        name_list(r, r->m->coord_names, colw, r->nq);
        msgf(r, " (smallest singular value %.2g of the largest)", ratio);
    }
    free(jac), free(roww), free(colw), free(row_names);
    return ratio;
}

/* The rows and coordinates of the Jacobian's (near) dependency at (q, t),
   over the first `rows` rows; nothing when the Jacobian is well conditioned.
   Returns sigma_min / sigma_max, or -1 when it could not be computed. */
static double describe_dependency(Run *r, const double *q, double t, int rows, bool always)
{
    if (r->sp)
        return describe_pivot(r);
    return describe_dense_dependency(r, q, t, rows, always);
}

/* After the assembly at t0: a configuration reached only approximately
   because the Jacobian is singular there (a driven position on a toggle,
   which the construction or Newton approaches only linearly) passes the
   LU's pivot test; it must fail as the toggle it is, rather than give the
   huge velocities of a Jacobian singular to 1e-9. True when
   sigma_min / sigma_max < RUN_NEAR_SINGULAR. */
static bool nearly_singular(Run *r, double t)
{
    if (r->sp)      /* its last factorisation is at q: the velocity analysis' */
        return !(mechrt_host_sparse_condest(r->sp) * RUN_NEAR_SINGULAR <= 1);
    if (r->nq > RUN_SVD_MAX_NQ)
        return false;
    size_t nq = (size_t)r->nq, nr = (size_t)r->nr;
    double *jac = xcalloc(nr * nq + 1, sizeof *jac);
    double *roww = xcalloc(nr + 1, sizeof *roww), *colw = xcalloc(nq, sizeof *colw);
    r->k->jac(r->k->ctx, r->q, t, jac);
    double ratio = mechrt_host_singular_direction(r->nr, r->nq, jac, roww, colw);
    free(jac), free(roww), free(colw);
    return ratio >= 0 && ratio < RUN_NEAR_SINGULAR;
}

/* Names the first row whose Phi, Phi_q or nu is NaN or infinite at (q, t);
   false when all are finite (then the solve overflowed). */
/* The first row with a NaN or infinite Jacobian entry at (q, t), or -1:
   the dense kernel's, or the sparse path's nonzeros. */
static int nonfinite_jac_row(Run *r, const double *q, double t)
{
    int row = -1;
    if (r->sp) {
        const MechrtHostJacNz *j = r->jnz;
        double *vals = mechrt_host_sparse_values(r->sp);
        mechrt_host_sparse_eval(r->sp, q, t);
        for (int e = 0; e < j->jac.nnz && row < 0; e++)
            if (!isfinite(vals[e]))
                row = j->jac.row[e];
        return row;
    }
    size_t nq = (size_t)r->nq, nr = (size_t)r->nr;
    double *jac = xcalloc(nr * nq + 1, sizeof *jac);
    r->k->jac(r->k->ctx, q, t, jac);
    for (size_t i = 0; i < nr * nq && row < 0; i++)
        if (!isfinite(jac[i]))
            row = (int)(i / nq);
    free(jac);
    return row;
}

static bool find_nonfinite(Run *r, const double *q, double t)
{
    const MechrtKernels *k = r->k;
    size_t nr = (size_t)r->nr;
    double *phi = xcalloc(nr + 1, sizeof *phi), *nu = xcalloc(nr + 1, sizeof *nu);
    const char *what = NULL;
    int row = -1;
    k->phi(k->ctx, q, t, phi);
    k->nu(k->ctx, q, t, nu);
    for (int i = 0; i < k->nh && !what; i++)
        if (!isfinite(phi[i]))
            what = "Phi", row = i;
    if (!what && (row = nonfinite_jac_row(r, q, t)) >= 0)
        what = "Phi_q";
    for (int i = 0; i < r->nr && !what; i++)
        if (!isfinite(nu[i]))
            what = "nu", row = i;
    if (what)
        msgf(r, "NaN or infinity in %s of row %s", what, r->m->rows[row].name);
    free(phi), free(nu);
    return what != NULL;
}

static const char *plural(int n, const char *one, const char *many) { return n == 1 ? one : many; }

/* Fills res with RUN_FAILED and the message for status st at time t, the
 * state q the runtime stopped at and its report. what: the phase. */
static void fail(Run *r, MechrtStatus st, double t, const double *q, const MechrtReport *rep,
                 const char *what)
{
    RunResult *res = r->res;
    const Model *m = r->m;
    res->status = RUN_FAILED;
    res->cause = st;
    res->t_fail = t;
    res->message[0] = '\0';
    msgf(r, "t = %.10g: %s failed: ", t, what);
    int rows = r->nr;
    switch (st) {
    case MECHRT_ESING:
        msgf(r, "singular Jacobian");
        if (rep && rep->sing_index >= 0 && rep->sing_index < r->nq)
            msgf(r, " (no pivot for coordinate %s)", m->coord_names[rep->sing_index]);
        msgf(r, ": a toggle or dead-centre position, or rows that depend on each other");
        break;
    case MECHRT_EMAXITER:
        msgf(r, "no convergence in %d %s", rep ? rep->iterations : r->o->mechrt.max_iter,
             plural(rep ? rep->iterations : 2, "iteration", "iterations"));
        if (rep && rep->worst_row >= 0 && rep->worst_row < m->nr)
            msgf(r, " (largest residual %.3g in row %s)", rep->residual,
                 m->rows[rep->worst_row].name);
        msgf(r, ": the driven position may be out of reach, or the motion passes a toggle");
        break;
    case MECHRT_ENOTFINITE:
        if (q && find_nonfinite(r, q, t))
            msgf(r, " (a function evaluated at or beyond the edge of its domain?)");
        else
            msgf(r, "NaN or infinity in the solution (a nearly singular Jacobian?)");
        rows = 0;
        break;
    case MECHRT_ESTEP:
        msgf(r, "the integrator's step size became too small to meet --ode-tol %.3g",
             r->o->ode.tol);
        break;
    case MECHRT_OK:
    case MECHRT_CONTINUE:
    case MECHRT_EBADLEN:
    case MECHRT_ENOTSQUARE:
    case MECHRT_EINVAL:
        msgf(r, "%s (an internal error)", mechrt_strerror(st));
        rows = 0;
        break;
    }
    if (q && rows > 0) {
        /* projection works on the holonomic rows alone */
        if (strcmp(what, "projection") == 0 || strcmp(what, "assembly (minimum-norm Newton)") == 0)
            rows = r->k->nh;
        if (rows > 0)
            describe_dependency(r, q, t, rows, st == MECHRT_ESING);
    }
}

static void fail_assembly(Run *r, const AssembleResult *ar);

/* The start of the assembly at t0: the file's values into q0 (the note on
   how far assembly moved them compares with these), then r->q as the
   construction places it (construct.h), also into start, where a robust
   assembly begins again when Newton cannot start. q0, start: nq each. */
static void place_at_t0(Run *r, double *q0, double *start)
{
    size_t nq = (size_t)r->nq;
    memcpy(q0, r->q, nq * sizeof *q0);
    r->res->constructed = construct_with_kernels(r->m, r->k, r->o->t0, r->q);
    memcpy(start, r->q, nq * sizeof *start);
}

/* Whether a dense nr x nq Jacobian would be beyond RunOptions.max_dense_entries. */
static bool run_dense_too_large(const Model *m, const RunOptions *o)
{
    return o->max_dense_entries > 0 && (long long)m->nr * m->nq > o->max_dense_entries;
}

/* Minimum-norm Newton with step halving over the holonomic rows, from the
 * start in r->q (assemble_kernels, what `info` uses):
 * unlike Newton with LU it starts from any guess, including one where the
 * Jacobian is singular because two links are merely parallel (all angles
 * 0). False, with the message filled, when even it finds no configuration
 * near the initial values: the rows it could not satisfy are named. */
static bool assemble_robustly(Run *r)
{
    const RunOptions *o = r->o;
    AnalysisOptions ao = analysis_default_options();
    ao.tol_phi = o->mechrt.tol_phi;
    ao.tol_dq = o->mechrt.tol_dq;
    ao.max_iter = o->assembly_max_iter;
    ao.stall_iter = ASSEMBLE_ROUGH_STALL;
    AssembleResult ar;
    if (run_dense_too_large(r->m, o)) {     /* it works on the dense Jacobian */
        r->res->status = RUN_FAILED;
        r->res->cause = MECHRT_EMAXITER;
        r->res->t_fail = o->t0;
        snprintf(r->res->message, sizeof r->res->message, "t = %.10g: Newton found no "
                 "configuration from these initial values, and the robust assembly's dense "
                 "Jacobian would have more than %lld entries (--max-jac-entries)", o->t0,
                 o->max_dense_entries);
        return false;
    }
    bool ok = assemble_restarting(r->k, o->t0, r->q, &ao, &ar);
    r->res->assembly_iterations += ar.iterations;
    r->res->assembled_robustly = true;
    if (!ok)
        fail_assembly(r, &ar);
    return ok;
}

/* The message of an assembly that found no configuration: the rows left
   unsatisfied at the attempt that came closest. */
static void fail_assembly(Run *r, const AssembleResult *ar)
{
    const RunOptions *o = r->o;
    RunResult *res = r->res;
    res->status = RUN_FAILED;
    res->cause = MECHRT_EMAXITER;
    res->t_fail = o->t0;
    res->message[0] = '\0';
    msgf(r, "t = %.10g: could not assemble from these initial values: ", o->t0);
    size_t nh = (size_t)r->k->nh;
    double *phi = xcalloc(nh + 1, sizeof *phi);
    const char **names = xcalloc(nh + 1, sizeof *names);
    r->k->phi(r->k->ctx, r->q, o->t0, phi);
    bool finite = true;
    for (size_t i = 0; i < nh; i++) {
        finite = finite && isfinite(phi[i]);
        phi[i] = fabs(phi[i]);
        names[i] = r->m->rows[i].name;
    }
    if (!finite) {
        msgf(r, "minimum-norm Newton reached NaN or infinity after %d %s", ar->iterations,
             plural(ar->iterations, "iteration", "iterations"));
    } else {
        msgf(r, "after %d %s of minimum-norm Newton the largest residual is %.3g in row %s; "
             "rows left unsatisfied: ", ar->iterations,
             plural(ar->iterations, "iteration", "iterations"), ar->residual,
             ar->worst_row >= 0 ? names[ar->worst_row] : "?");
        name_list(r, names, phi, (int)nh);
    }
    msgf(r, " (the mechanism may not close with these lengths, or the guess is nearer "
         "a configuration that does not exist; try other initial values, or more --assembly-iter)");
    free(phi), free(names);
}

/* A note when assembly moved the initial values much. */
static void note_move(Run *r, const double *q0)
{
    double moved = 0, scale = 0;
    int at = 0;
    for (int i = 0; i < r->nq; i++) {
        double d = fabs(r->q[i] - q0[i]);
        if (d > moved) {
            moved = d;
            at = i;
        }
        if (fabs(q0[i]) > scale)
            scale = fabs(q0[i]);
    }
    r->res->assembly_move = moved;
    int it = r->res->assembly_iterations;
    const char *its = it == 1 ? "iteration" : "iterations";
    if (r->res->assembled_robustly && r->res->constructed > 0)
        notef(r, "note", "Newton could not start from the file's initial values; %d of the %d "
              "coordinates were placed by construction (drivers, pins, dyads: of two closures "
              "the one nearer the initial values), then Newton assembled the mechanism at "
              "t = %.10g in %d %s", r->res->constructed, r->nq, r->o->t0, it, its);
    else if (r->res->assembled_robustly)
        notef(r, "note", "Newton could not start from the file's initial values; minimum-norm "
              "Newton assembled the mechanism at t = %.10g in %d %s (initial values "
              "near the configuration you mean choose its assembly branch)", r->o->t0, it, its);
    else if (moved > r->o->move_note * (scale > 0 ? scale : 1) && r->res->constructed > 0)
        notef(r, "note", "assembly at t = %.10g moved the initial values by up to %.6g "
              "(%s: %.6g -> %.6g): %d of the %d coordinates were placed by construction "
              "(drivers, pins, dyads: of two closures the one nearer the initial values), "
              "then Newton took %d %s", r->o->t0, moved, r->m->coord_names[at], q0[at], r->q[at],
              r->res->constructed, r->nq, it, its);
    else if (moved > r->o->move_note * (scale > 0 ? scale : 1))
        notef(r, "note", "assembly at t = %.10g moved the initial values by up to %.6g "
              "(%s: %.6g -> %.6g); the file's values are only Newton's starting point",
              r->o->t0, moved, r->m->coord_names[at], q0[at], r->q[at]);
}

/* Nearly singular stretches: a warning when one begins, a note when it ends. */
static void watch_condition(Run *r, double t, const MechrtReport *rep)
{
    if (rep->cond > r->res->max_cond)
        r->res->max_cond = rep->cond;
    if (rep->cond_warning) {
        if (!r->episode) {
            r->episode = true;
            r->ep_start = t;
            r->ep_worst = 0;
            r->res->warnings++;
            notef(r, "warning", "t = %.10g: the Jacobian is nearly singular (condition "
                  "estimate %.3g > %.3g): close to a toggle or dead-centre position; "
                  "velocities and accelerations lose accuracy", t, rep->cond,
                  r->o->mechrt.cond_warn);
        }
        r->ep_end = t;
        if (!(rep->cond <= r->ep_worst)) {
            r->ep_worst = rep->cond;
            r->ep_worst_t = t;
        }
    } else {
        if (r->episode)
            notef(r, "note", "nearly singular from t = %.10g to t = %.10g (worst condition "
                  "estimate %.3g at t = %.10g)", r->ep_start, r->ep_end, r->ep_worst,
                  r->ep_worst_t);
        r->episode = false;
    }
}

/* A state computed at t (in r->q, r->qd, r->qdd): the condition watch,
   then out to the caller. */
static void put_state(Run *r, double t, const MechrtReport *rep, RunStateFn state, void *ctx)
{
    watch_condition(r, t, rep);
    if (r->fstate)
        r->fstate(ctx, t, r->q, r->qd, r->qdd, r->lambda);
    else
        state(ctx, t, r->q, r->qd, r->qdd);
    r->res->states++;
}

/* A run has one row per coordinate, so where Phi_q is regular lambda is
   the solution of the square system Phi_q^T lambda = Q - M qdd: one LU
   with partial pivoting (lu.c) and a transposed solve, a third of the
   complete-pivoting elimination's work. False when a pivot is below the
   dynamics' rank tolerance (a singular position, where this would give
   lambda to few digits) or a value is not finite: then the
   rank-revealing mechrt_inverse_dynamics decides. Workspace: dyn_work's first
   nq*nq + nq*nq + 2 nq entries (M, the LU, the pivots, Q). */
static bool inverse_square(Run *r, double t)
{
    const MechrtKernels *k = r->k;
    size_t n = (size_t)r->nq;
    double *mass = r->dyn_work, *lu = mass + n * n, *piv = lu + n * n, *rhs = piv + n;
    k->mass(k->ctx, r->q, mass);
    k->force(k->ctx, r->q, r->qd, t, rhs);
    k->jac(k->ctx, r->q, t, lu);
    if (mechrt_lu_factor(r->nq, lu, r->nq, piv, r->dyn_rank_tol, NULL) != MECHRT_OK)
        return false;
    for (size_t i = 0; i < n; i++) {
        double s = rhs[i];
        const double *mi = mass + i * n;
        for (size_t j = 0; j < n; j++)
            s -= mi[j] * r->qdd[j];
        rhs[i] = s;
    }
    mechrt_lu_solve_t(r->nq, lu, r->nq, piv, rhs);
    bool finite = true;
    for (size_t i = 0; i < n; i++)
        finite = finite && isfinite(rhs[i]);
    if (finite)
        memcpy(r->lambda, rhs, n * sizeof *rhs);
    return finite;
}

/* Inverse dynamics at the state just computed (t, r->q, r->qd, r->qdd),
   into r->lambda; nothing without run_analysis_forces. False, with the
   failure in r->res, when the solve fails. */
static bool inverse_at(Run *r, double t)
{
    if (!r->fstate || inverse_square(r, t))
        return true;
    MechrtDynReport rep;
    MechrtStatus st = mechrt_inverse_dynamics(r->k, NULL, r->q, r->qd, r->qdd, t, r->lambda,
                                              r->dyn_work, r->dyn_lwork, &rep);
    if (rep.residual > r->res->force_residual)
        r->res->force_residual = rep.residual;
    if (rep.redundant > r->res->force_redundant)
        r->res->force_redundant = rep.redundant;
    if (st == MECHRT_OK)
        return true;
    r->res->status = RUN_FAILED;
    r->res->cause = st;
    r->res->t_fail = t;
    r->res->message[0] = '\0';
    msgf(r, "t = %.10g: inverse dynamics failed: %s", t,
         st == MECHRT_ENOTFINITE ? "NaN or infinity in M(q), Q(q, qd, t) or the multipliers"
                                 : mechrt_strerror(st));
    return false;
}

static double time_at(const RunOptions *o, int i)
{
    if (i == o->steps)
        return o->t1;
    return o->t0 + (o->t1 - o->t0) * (double)i / (double)o->steps;
}

/* A failed mechrt_step ending at t with iterate q: Newton's failure or the
   velocity and acceleration analysis' after it. */
static void fail_step(Run *r, MechrtStatus st, double t, const double *q,
                      const MechrtReport *rep)
{
    const MechrtOptions *mo = &r->o->mechrt;
    bool newton = rep->step < 0 || st == MECHRT_EMAXITER || rep->residual > mo->tol_phi
                  || rep->step > mo->tol_dq;
    fail(r, st, t, q, rep, newton ? "position analysis (Newton)"
                                  : "velocity and acceleration analysis");
}

/* Why a step was not quiet: the coordinate corrected most beyond its share
   (-1: none, too many iterations only). */
typedef struct StepCheck {
    int coord;
    double correction, motion;
    int iterations;
} StepCheck;

/* The check of the converged step of length h that went from (sq, sqd,
   sqdd) to q: see RUN_QUIET_SHARE. NaN fails it. */
static bool step_quiet(const Run *r, double h, const MechrtReport *rep, StepCheck *chk)
{
    const double tol = r->o->mechrt.tol_dq, h2 = 0.5 * h * h;
    double worst = 0;
    int bad = 0;
    /* One Newton iteration (fine steps): the correction was that one step,
       at most tol_dq in every coordinate, so the check holds. */
    if (rep->iterations <= 1)
        return true;
    /* the common case, branch-free */
    for (int i = 0; i < r->nq; i++) {
        double corr = fabs(r->q[i] - (r->sq[i] + h * r->sqd[i] + h2 * r->sqdd[i]));
        double motion = fabs(h * r->sqd[i]) + h2 * fabs(r->sqdd[i]);
        bad |= !(corr <= RUN_QUIET_SHARE * motion + tol);
    }
    if (rep->iterations <= RUN_QUIET_ITER && !bad)
        return true;
    /* not quiet: which coordinate, for a message */
    chk->coord = -1;
    chk->iterations = rep->iterations;
    for (int i = 0; i < r->nq; i++) {
        double corr = fabs(r->q[i] - (r->sq[i] + h * r->sqd[i] + h2 * r->sqdd[i]));
        double motion = fabs(h * r->sqd[i]) + h2 * fabs(r->sqdd[i]);
        double allowed = RUN_QUIET_SHARE * motion + tol;
        if (!(corr <= allowed)) {
            if (!(corr <= worst * allowed)) {
                worst = corr / allowed;
                chk->coord = i;
                chk->correction = corr;
                chk->motion = motion;
            }
        }
    }
    return false;
}

/* The one place the linear algebra differs: the runtime's dense step, or
   the same step on the sparse Jacobian. */
static MechrtStatus run_step(Run *r, double t, double h, MechrtReport *rep)
{
    if (r->sp)
        return mechrt_host_sparse_step(r->sp, r->k, &r->o->mechrt, r->q, r->qd, r->qdd, t, h,
                                       r->work, r->lwork, rep);
    if (r->lup)
        return mechrt_step_lup(r->k, &r->jnz->jac, r->lup, &r->o->mechrt, r->q, r->qd, r->qdd,
                               t, h, r->work, r->lwork, rep);
    return mechrt_step(r->k, &r->o->mechrt, r->q, r->qd, r->qdd, t, h, r->work, r->lwork, rep);
}

/* The state at time t (in sq, sqd, sqdd) was trusted: its acceleration
   joins the predictor's history (the same time again replaces it). */
static void push_history(Run *r, double t)
{
    size_t nq = (size_t)r->nq, bytes = nq * sizeof(double);
    if (r->hist_n > 0 && r->hist_t[0] == t) {
        memcpy(r->hist_qdd, r->sqdd, bytes);
        return;
    }
    memmove(r->hist_qdd + nq, r->hist_qdd, (RUN_HISTORY - 1) * bytes);
    memmove(r->hist_t + 1, r->hist_t, (RUN_HISTORY - 1) * sizeof *r->hist_t);
    memcpy(r->hist_qdd, r->sqdd, bytes);
    r->hist_t[0] = t;
    r->hist_n = r->hist_n < RUN_HISTORY ? r->hist_n + 1 : RUN_HISTORY;
}

/* The prediction at t + h from the state at t (sq, sqd, sqdd) into q, qd,
 * qdd: the acceleration extrapolated by the cubic through it and the
 * history's three before it (fewer when there are fewer, down to Taylor's
 * constant), qd and q its integrals from t. Errors O(h^4) in qdd, O(h^5)
 * in qd, O(h^6) in q, where the LU step's Taylor predictor has O(h^3) in
 * q: along the directions a singular Jacobian loses, the prediction is
 * all there is. History from later times (a subdivision's failed level)
 * or the other direction is left out. */
static void predict(Run *r, double t, double h)
{
    double s[RUN_HISTORY + 1] = {0};
    const double *a[RUN_HISTORY + 1] = {r->sqdd};
    int used = 1;
    for (int e = 0; e < r->hist_n; e++) {
        double se = r->hist_t[e] - t;
        if (se * h < 0 && (used == 1 || fabs(se) > fabs(s[used - 1]))) {
            s[used] = se;
            a[used++] = r->hist_qdd + (size_t)e * (size_t)r->nq;
        }
    }
    double hk[6] = {1, h, h * h, h * h * h, h * h * h * h, h * h * h * h * h};
    for (int i = 0; i < r->nq; i++) {
        /* divided differences, then the Newton form as c0 + c1 s + ... */
        double d[RUN_HISTORY + 1] = {a[0][i]}, c[4] = {0, 0, 0, 0};
        double f[RUN_HISTORY + 1];
        for (int j = 0; j < used; j++)
            f[j] = a[j][i];
        for (int l = 1; l < used; l++) {
            for (int j = used - 1; j >= l; j--)
                f[j] = (f[j] - f[j - 1]) / (s[j] - s[j - l]);
            d[l] = f[l];
        }
        c[0] = d[0];
        if (used > 1)
            c[1] = d[1];
        if (used > 2)
            c[1] -= d[2] * s[1], c[2] = d[2];
        if (used > 3)
            c[1] += d[3] * s[1] * s[2], c[2] -= d[3] * (s[1] + s[2]), c[3] = d[3];
        double qdd = 0, qd = r->sqd[i], q = r->sq[i] + r->sqd[i] * h;
        for (int k = 0; k < 4; k++) {
            qdd += c[k] * hk[k];
            qd += c[k] * hk[k + 1] / (k + 1);
            q += c[k] * hk[k + 2] / ((k + 1) * (k + 2));
        }
        r->qdd[i] = qdd, r->qd[i] = qd, r->q[i] = q;
    }
}

/* The LU step ended without a factorisation (singular), or with one too
   ill-conditioned to trust: the rank-revealing corrector takes over. */
static bool wants_rank(MechrtStatus st, const MechrtReport *rep)
{
    if (st == MECHRT_ESING || st == MECHRT_EMAXITER || st == MECHRT_ENOTFINITE)
        return true;
    return st == MECHRT_OK && rep->cond > RUN_RANK_COND;
}

/* The step from t to t + h again, through a singular position: the
   history's prediction, corrected by mechrt_rank_correct (dense, on both
   paths: KLU has no rank-revealing factorisation). When it fails too, or
   its velocity or acceleration leave a residual (no branch continues the
   motion there), the LU attempt stands: its status st0, its report in
   *rep and its iterate (kept in rq) in q, so that its messages are the
   LU's; the corrector's verdict is kept for the message (rank_note). */
static MechrtStatus rank_step(Run *r, double t, double h, MechrtStatus st0, MechrtReport *rep)
{
    size_t bytes = (size_t)r->nq * sizeof(double);
    if (!r->rk_work) {
        r->rk_lwork = mechrt_rank_workspace_size(r->nq);
        r->rk_work = xcalloc(r->rk_lwork + 1, sizeof *r->rk_work);
    }
    MechrtReport rk;
    memcpy(r->rq, r->q, bytes);
    predict(r, t, h);
    MechrtStatus st = mechrt_rank_correct(r->k, &r->o->mechrt, r->q, r->qd, r->qdd, t + h,
                                          r->rk_work, r->rk_lwork, &rk);
    RunResult *res = r->res;
    res->rank_steps++;
    res->newton_iterations += rk.iterations;
    res->rank_factorisations += rk.factorisations;
    if (st != MECHRT_OK || rk.inconsistency > RUN_BRANCH_TOL) {
        res->rank_failed = true;
        res->rank_t = t + h;
        res->rank_status = st;
        res->rank_inconsistency = rk.inconsistency;
        memcpy(r->q, r->rq, bytes);
        return st0;
    }
    if (rk.rank_deficiency > 0)
        res->rank_deficient_steps++;
    if (rk.rank_deficiency > res->max_rank_deficiency)
        res->max_rank_deficiency = rk.rank_deficiency;
    rk.cond = st0 == MECHRT_OK ? rep->cond : 0;   /* the condition watch: the LU's estimate */
    rk.cond_warning = st0 == MECHRT_OK ? rep->cond_warning : false;
    *rep = rk;
    return MECHRT_OK;
}

/* One predictor-corrector step of the runtime from t to t + h, its start
   kept in sq, sqd, sqdd; *quiet says whether it passed the check. A step
   that meets a singular Jacobian is redone by rank_step. */
static MechrtStatus checked_step(Run *r, double t, double h, MechrtReport *rep, bool *quiet,
                                 StepCheck *chk)
{
    memcpy(r->sq, r->q, 3 * (size_t)r->nq * sizeof(double));   /* q | qd | qdd */
    MechrtStatus st = run_step(r, t, h, rep);
    r->res->newton_iterations += rep->iterations;
    if (h != 0 && r->nq <= RUN_RANK_MAX_NQ && wants_rank(st, rep))
        st = rank_step(r, t, h, st, rep);
    *quiet = st == MECHRT_OK && step_quiet(r, h, rep, chk);
    if (*quiet)
        push_history(r, t);
    return st;
}

/* The positions of two levels at the interval's end are the same solution. */
static bool levels_agree(const Run *r, const double *a, const double *b)
{
    double tol = RUN_AGREE * r->o->mechrt.tol_dq;
    for (int i = 0; i < r->nq; i++)
        if (!(fabs(a[i] - b[i]) <= tol))
            return false;
    return true;
}

/* Past the subdivision limit with every level converging: the message. */
static void fail_too_fast(Run *r, double t_start, double t_end, double t_bad, long levels,
                          const StepCheck *chk)
{
    RunResult *res = r->res;
    res->status = RUN_FAILED;
    res->cause = MECHRT_ESTEP;
    res->t_fail = t_bad;
    res->message[0] = '\0';
    msgf(r, "t = %.10g: position analysis failed: the motion is too fast for the step: ", t_bad);
    if (levels > 1)
        msgf(r, "in %ld substeps of the step from t = %.10g to %.10g ", levels, t_start, t_end);
    else
        msgf(r, "in the step from t = %.10g to %.10g (no substeps allowed) ", t_start, t_end);
    if (chk->coord >= 0)
        msgf(r, "Newton %scorrected %s by %.3g where the predictor moved it by %.3g",
             levels > 1 ? "still " : "", r->m->coord_names[chk->coord], chk->correction,
             chk->motion);
    else
        msgf(r, "Newton %sneeded %d iterations", levels > 1 ? "still " : "", chk->iterations);
    msgf(r, ", so the motion may have jumped to another assembly branch or turn; use more "
         "--steps or a larger --max-substeps");
}

/* The step over [t, tn] from (sq, sqd, sqdd) was not quiet (chk0 says
   why), or failed with st0 (report *rep, iterate in q). Redoes the interval
   in 2, 4, 8 ... substeps until a level is quiet throughout, or took few
   iterations throughout and agrees with the previous level: true with the
   state at tn in q, qd, qdd and the last substep's report in *rep. Past
   max_substeps: false, the failure in r->res (the original step's own, at
   tn, when it failed). */
static bool subdivide(Run *r, double t, double tn, MechrtStatus st0, MechrtReport *rep,
                      const StepCheck *chk0)
{
    const RunOptions *o = r->o;
    size_t bytes = (size_t)r->nq * sizeof(double);
    MechrtReport rep0 = *rep;
    StepCheck chk = *chk0;
    MechrtStatus st = st0;
    double t_bad = tn;
    bool have_last = st0 == MECHRT_OK;
    long levels = 1;

    memcpy(r->iq, r->sq, 3 * bytes);   /* q | qd | qdd */
    memcpy(have_last ? r->lq : r->fq, r->q, bytes);
    r->res->subdivided++;
    for (long s = 2; s <= o->max_substeps; s *= 2) {
        bool all_quiet = true, few_iterations = true;
        double ta = t;
        levels = s;
        memcpy(r->q, r->iq, 3 * bytes);
        st = MECHRT_OK;
        for (long j = 1; j <= s && st == MECHRT_OK; j++) {
            double tb = j == s ? tn : t + (tn - t) * (double)j / (double)s;
            bool quiet;
            StepCheck c = {-1, 0, 0, 0};
            st = checked_step(r, ta, tb - ta, rep, &quiet, &c);
            r->res->substeps++;
            if (st != MECHRT_OK || (!quiet && all_quiet)) {
                t_bad = tb;
                if (st == MECHRT_OK)
                    chk = c;
            }
            all_quiet = all_quiet && quiet;
            few_iterations = few_iterations && rep->iterations <= RUN_QUIET_ITER;
            ta = tb;
        }
        if (st == MECHRT_OK
            && (all_quiet || (few_iterations && have_last && levels_agree(r, r->q, r->lq))))
            return true;
        have_last = st == MECHRT_OK;
        if (have_last)
            memcpy(r->lq, r->q, bytes);
    }
    if (st0 != MECHRT_OK) {
        /* subdivision did not help: the step's own failure, as ever, and
           where the substeps stopped */
        memcpy(r->q, r->fq, bytes);
        fail_step(r, st0, tn, r->q, &rep0);
        if (levels > 1 && st != MECHRT_OK)
            msgf(r, "; redone in up to %ld substeps, the step from t = %.10g failed again at "
                 "t = %.10g", levels, t, t_bad);
        else if (levels > 1)
            msgf(r, "; redone in up to %ld substeps, the step from t = %.10g still seemed to "
                 "leave its assembly branch: the motion may be too fast for the step (use "
                 "more --steps or a larger --max-substeps)", levels, t);
    } else if (st != MECHRT_OK) {
        fail_step(r, st, t_bad, r->q, rep);
        msgf(r, "; or the motion is too fast for the step: the step from t = %.10g to %.10g "
             "seemed to leave its assembly branch and was redone in up to %ld substeps; use "
             "more --steps or a larger --max-substeps", t, tn, levels);
    } else {
        fail_too_fast(r, t, tn, t_bad, levels, &chk);
    }
    return false;
}

/* A failed step after which the rank-revealing corrector could not go on
   either: what it found, after the LU's message. */
static void note_rank_failure(Run *r)
{
    const RunResult *res = r->res;
    msgf(r, "; the rank-revealing corrector found no motion that continues the branch "
         "either (at t = %.10g: ", res->rank_t);
    if (res->rank_status == MECHRT_OK)
        msgf(r, "no velocity or acceleration near the continued ones satisfies their "
             "equations, %.2g of them is left", res->rank_inconsistency);
    else
        msgf(r, "%s", mechrt_strerror(res->rank_status));
    msgf(r, ")");
    if (r->sp)      /* the LU's message named a pivot only: the dependency, densely */
        describe_dense_dependency(r, r->q, res->rank_t, r->nr, true);
    msgf(r, ": where the Jacobian loses rank the motion cannot go on (a limit position "
         "that the driver pushes past), or branches meet that the motion so far cannot "
         "tell apart (a bifurcation); drive another coordinate, or end the run there and "
         "start another on the branch you want");
}

/* Holonomic rows only: the runtime's predictor-corrector step, checked and
   subdivided when needed (see the top of this file). */
static RunStatus run_holonomic(Run *r, RunStateFn state, void *ctx)
{
    const RunOptions *o = r->o;
    MechrtReport rep;
    RunStatus status = RUN_OK;
    size_t nq = (size_t)r->nq;
    double *q0 = xmalloc(2 * nq * sizeof *q0), *start = q0 + nq;
    double *keep = xmalloc((9 + RUN_HISTORY) * nq * sizeof *keep);
    r->sq = keep, r->sqd = keep + nq, r->sqdd = keep + 2 * nq;
    r->iq = keep + 3 * nq, r->lq = keep + 6 * nq, r->fq = keep + 7 * nq, r->rq = keep + 8 * nq;
    r->hist_qdd = keep + 9 * nq;
    r->hist_n = 0;
    place_at_t0(r, q0, start);
    MechrtStatus st = run_step(r, o->t0, 0.0, &rep);
    r->res->assembly_iterations = rep.iterations;
    if (st != MECHRT_OK && st != MECHRT_EINVAL && st != MECHRT_EBADLEN) {
        /* a guess Newton cannot start from: assemble robustly, then
           Newton again for the velocities and accelerations there */
        memcpy(r->q, start, nq * sizeof *start);
        if (!assemble_robustly(r)) {
            status = RUN_FAILED;
            goto out;
        }
        st = run_step(r, o->t0, 0.0, &rep);
        r->res->assembly_iterations += rep.iterations;
    }
    if (st == MECHRT_OK && nearly_singular(r, o->t0)) {
        st = MECHRT_ESING;
        rep.sing_index = -1;
    }
    if (st != MECHRT_OK) {
        fail(r, st, o->t0, r->q, &rep, "assembly from the file's initial values");
        status = RUN_FAILED;
        goto out;
    }
    note_move(r, q0);
    if (!inverse_at(r, o->t0)) {
        status = RUN_FAILED;
        goto out;
    }
    put_state(r, o->t0, &rep, state, ctx);

    double t = o->t0;
    for (int i = 1; i <= o->steps; i++) {
        double tn = time_at(o, i);
        clock_t cpu0 = clock();     /* before the wall clock: clock() is a system call */
        double c0 = pipeline_now(); /* of about 0.65 us here, not the step's cost */
        bool quiet;
        StepCheck chk = {-1, 0, 0, 0};
        r->res->rank_failed = false;
        st = checked_step(r, t, tn - t, &rep, &quiet, &chk);
        bool ok = quiet || subdivide(r, t, tn, st, &rep, &chk);
        if (!ok && r->res->rank_failed)
            note_rank_failure(r);
        if (ok && !inverse_at(r, tn))
            ok = false;
        r->res->step_seconds += pipeline_now() - c0;
        r->res->step_cpu_seconds += (double)(clock() - cpu0) / CLOCKS_PER_SEC;
        if (!ok) {
            status = RUN_FAILED;
            goto out;
        }
        r->res->steps_done++;
        t = tn;
        put_state(r, t, &rep, state, ctx);
    }
out:
    free(q0);
    free(keep);
    r->sq = r->sqd = r->sqdd = r->iq = r->lq = r->fq = r->rq = r->hist_qdd = NULL;
    free(r->rk_work);
    r->rk_work = NULL;
    return status;
}

/* Velocity-level rows, at t0: the positions projected onto the holonomic
   rows (assembled robustly when that fails), the velocities and
   accelerations solved there, the inverse dynamics asked for. False with
   the failure in r->res. */
static bool integrated_start(Run *r, MechrtHost *host, MechrtReport *rep)
{
    const RunOptions *o = r->o;
    double *q0 = xmalloc(2 * (size_t)r->nq * sizeof *q0), *start = q0 + r->nq;
    bool ok = false;
    place_at_t0(r, q0, start);
    MechrtStatus st = mechrt_host_project(host, &o->mechrt, r->q, o->t0, rep);
    r->res->assembly_iterations = rep->iterations;
    if (st != MECHRT_OK && st != MECHRT_EINVAL) {
        memcpy(r->q, start, (size_t)r->nq * sizeof *start);
        if (!assemble_robustly(r))
            goto out;
        st = mechrt_host_project(host, &o->mechrt, r->q, o->t0, rep);
        r->res->assembly_iterations += rep->iterations;
    }
    if (st != MECHRT_OK) {
        fail(r, st, o->t0, r->q, rep, "assembly (minimum-norm Newton)");
        goto out;
    }
    note_move(r, q0);
    st = mechrt_host_velocity_acceleration(host, &o->mechrt, r->q, o->t0, r->qd, r->qdd, rep);
    if (st != MECHRT_OK) {
        fail(r, st, o->t0, r->q, rep, "velocity and acceleration analysis");
        goto out;
    }
    ok = inverse_at(r, o->t0);
out:
    free(q0);
    return ok;
}

/* Velocity-level rows: integrate the positions between output times. */
static RunStatus run_integrated(Run *r, RunStateFn state, void *ctx)
{
    const RunOptions *o = r->o;
    MechrtReport rep;
    RunStatus status = RUN_OK;
    MechrtHost *host = r->sparse ? mechrt_host_new_sparse(r->k, r->jnz) : mechrt_host_new(r->k);
    r->sp = mechrt_host_sparse_of(host);    /* a failure names its pivot */
    if (!host) {
        snprintf(r->res->message, sizeof r->res->message, "t = %.10g: out of memory", o->t0);
        r->res->status = RUN_FAILED;
        r->res->cause = MECHRT_EINVAL;
        r->res->t_fail = o->t0;
        return RUN_FAILED;
    }
    r->res->integrated = true;
    if (!integrated_start(r, host, &rep)) {
        status = RUN_FAILED;
        goto out;
    }
    put_state(r, o->t0, &rep, state, ctx);

    double t = o->t0, hstep = o->steps > 0 ? (o->t1 - o->t0) / o->steps : 0;
    for (int i = 1; i <= o->steps; i++) {
        double tn = time_at(o, i);
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
            fail(r, st, tf, qf, &rep, proj ? "projection" : "integration (velocity analysis)");
            status = RUN_FAILED;
            goto out;
        }
        st = mechrt_host_velocity_acceleration(host, &o->mechrt, r->q, tn, r->qd, r->qdd, &rep);
        bool forces_ok = st != MECHRT_OK || inverse_at(r, tn);
        r->res->step_seconds += pipeline_now() - c0;
        r->res->step_cpu_seconds += (double)(clock() - cpu0) / CLOCKS_PER_SEC;
        if (st != MECHRT_OK)
            fail(r, st, tn, r->q, &rep, "velocity and acceleration analysis");
        if (st != MECHRT_OK || !forces_ok) {
            status = RUN_FAILED;
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

static RunStatus bad_input(RunResult *res, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static RunStatus bad_input(RunResult *res, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(res->message, sizeof res->message, fmt, ap);
    va_end(ap);
    res->status = RUN_BAD_INPUT;
    res->cause = MECHRT_EINVAL;
    return RUN_BAD_INPUT;
}

/* Dense or sparse for this run (RunOptions.linear); false with why when
   the choice cannot be honoured. */
static bool choose_linear(const Model *m, const MechrtHostJacNz *jnz, const RunOptions *o,
                          bool *sparse, char *why, size_t size)
{
    bool can = jnz != NULL;
    *sparse = o->linear == RUN_LINEAR_SPARSE
              || (o->linear == RUN_LINEAR_AUTO && can && m->nq > RUN_DENSE_MAX_NQ);
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

/* The dense path's factorisation: the pattern LU on the kernels' sparse
   Jacobian jnz (same results as lu.c's, replayed over the nonzeros), with
   jnz's unrolled LU when it has one, when the mechanism is stepped (no
   velocity rows) and its worst-case index lists stay small
   (RUN_DENSE_MAX_NQ); NULL otherwise. One block: the state, then its
   reals, then its ints. */
static MechrtLup *run_lup_new(const Model *m, const MechrtHostJacNz *jnz)
{
    if (!jnz || m->nv > 0 || m->nq > RUN_DENSE_MAX_NQ)
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
                 m->nr, plural(m->nr, "row", "rows"), dof == 1 ? "a driver" : "drivers",
                 dof == 1 ? "" : " (one per degree of freedom)");
        return false;
    }
    if (m->nr > m->nq) {
        int extra = m->nr - m->nq;
        snprintf(why, size, "the mechanism has %d more %s than coordinates (%d rows, %d "
                 "coordinates): run needs exactly one row per coordinate; remove "
                 "redundant rows or drivers", extra, plural(extra, "row", "rows"),
                 m->nr, m->nq);
        return false;
    }
    return true;
}

/* run_analysis and run_analysis_forces: one of state and fstate. */
static RunStatus analyse(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
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

    Run r = {0};
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
    if (!sparse)
        r.lup = run_lup_new(m, jnz);
    r.lwork = sparse ? MECHRT_HOST_SPARSE_WORK_LEN(m->nq) : mechrt_workspace_size(m->nq, m->nr);
    r.work = xcalloc(r.lwork, sizeof *r.work);
    memcpy(r.q, m->q0, nq * sizeof *r.q);
    if (fstate) {
        r.fstate = fstate;
        r.dyn_rank_tol = mechrt_dyn_default_options().rank_tol;
        r.dyn_lwork = mechrt_dynamics_workspace_size(m->nq, m->nr);
        r.dyn_work = xcalloc(r.dyn_lwork + 1, sizeof *r.dyn_work);
        r.lambda = xcalloc((size_t)m->nr + 1, sizeof *r.lambda);
    }

    RunStatus status = m->nv == 0 ? run_holonomic(&r, state, state_ctx)
                                  : run_integrated(&r, state, state_ctx);
    if (r.sp) {
        mechrt_host_sparse_counts(r.sp, &res->fresh_factorisations, &res->refactorisations);
        mechrt_host_sparse_free(r.sp);
    }
    if (r.lup) {
        res->fresh_factorisations = r.lup->analyses;
        res->refactorisations = r.lup->replays;
        res->generated_factorisations = r.lup->gen_factors;
        free(r.lup);
    }
    if (status == RUN_OK && r.episode)
        notef(&r, "note", "nearly singular from t = %.10g to the end (worst condition estimate "
              "%.3g at t = %.10g)", r.ep_start, r.ep_worst, r.ep_worst_t);
    res->status = status;
    free(r.q), free(r.work), free(r.dyn_work), free(r.lambda);
    return status;
}

RunStatus run_analysis(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                       const RunOptions *o, RunStateFn state, void *state_ctx, RunResult *res)
{
    return analyse(m, k, jnz, o, state, NULL, state_ctx, res);
}

RunStatus run_analysis_forces(const Model *m, const MechrtKernels *k,
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
