/* diagnose.c - what a run says when it fails or nears a singular position: when, why, which rows and coordinates. */
#include "diagnose.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A singular value ratio below this names the dependency in a failure message. */
#define RUN_NEAR_SINGULAR 1e-7
/* Above this many coordinates the dense SVD of a failure message (O(n^3))
   would take longer than the user should wait for an error: left out. */
#define RUN_SVD_MAX_NQ 400

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
        analysis_name_list(r->res->message, sizeof r->res->message, row_names, roww, rows);
        msgf(r, " and coordinates ");
        analysis_name_list(r->res->message, sizeof r->res->message, r->m->coord_names, colw, r->nq);
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
bool run_nearly_singular(Run *r, double t)
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

/* Names the first row whose Phi, Phi_q or nu is NaN or infinite at (q, t);
   false when all are finite (then the solve overflowed). */
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

/* Fills res with ANALYSIS_FAILED and the message for status st at time t, the
 * state q the runtime stopped at and its report. what: the phase. */
void run_fail(Run *r, MechrtStatus st, double t, const double *q, const MechrtReport *rep,
                 const char *what)
{
    RunResult *res = r->res;
    const Model *m = r->m;
    res->status = ANALYSIS_FAILED;
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
             run_plural(rep ? rep->iterations : 2, "iteration", "iterations"));
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

/* A failed mechrt_step ending at t with iterate q: Newton's failure or the
   velocity and acceleration analysis' after it. */
void run_fail_step(Run *r, MechrtStatus st, double t, const double *q,
                      const MechrtReport *rep)
{
    const MechrtOptions *mo = &r->o->mechrt;
    bool newton = rep->step < 0 || st == MECHRT_EMAXITER || rep->residual > mo->tol_phi
                  || rep->step > mo->tol_dq;
    run_fail(r, st, t, q, rep, newton ? "position analysis (Newton)"
                                  : "velocity and acceleration analysis");
}

/* The message of an assembly that found no configuration: the rows left
   unsatisfied at the attempt that came closest (assemble_t0_describe). */
void run_fail_assembly(Run *r, const AssembleT0Report *ar)
{
    RunResult *res = r->res;
    res->status = ANALYSIS_FAILED;
    res->cause = MECHRT_EMAXITER;
    res->t_fail = ar->t0;
    assemble_t0_describe(r->m, r->k, ar, r->q, res->message, sizeof res->message);
}

/* A failed step after which the rank-revealing corrector could not go on
   either: what it found, after the LU's message. */
void run_note_rank_failure(Run *r)
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

/* Nearly singular stretches: a warning when one begins, a note when it ends. */
void run_watch_condition(Run *r, double t, const MechrtReport *rep)
{
    if (rep->cond > r->res->max_cond)
        r->res->max_cond = rep->cond;
    if (rep->cond_warning) {
        if (!r->episode) {
            r->episode = true;
            r->ep_start = t;
            r->ep_worst = 0;
            r->res->warnings++;
            run_notef(r, "warning", "t = %.10g: the Jacobian is nearly singular (condition "
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
            run_notef(r, "note", "nearly singular from t = %.10g to t = %.10g (worst condition "
                  "estimate %.3g at t = %.10g)", r->ep_start, r->ep_end, r->ep_worst,
                  r->ep_worst_t);
        r->episode = false;
    }
}

