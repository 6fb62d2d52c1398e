/* start.c - a run's start at t0: construction, Newton, the robust assembly, the note on how far it moved. */
#include "start.h"

#include "diagnose.h"

#include "../analysis/assemble.h"
#include "../analysis/construct.h"

#include <math.h>
#include <string.h>

/* The start of the assembly at t0: the file's values into q0 (the note on
   how far assembly moved them compares with these), then r->q as the
   construction places it (construct.h), also into start, where a robust
   assembly begins again when Newton cannot start. q0, start: nq each. */
void run_place_at_t0(Run *r, double *q0, double *start)
{
    size_t nq = (size_t)r->nq;
    memcpy(q0, r->q, nq * sizeof *q0);
    r->res->constructed = construct_with_kernels(r->m, r->k, r->o->t0, r->q);
    memcpy(start, r->q, nq * sizeof *start);
}

/* Whether a dense nr x nq Jacobian would be beyond RunOptions.max_dense_entries. */
bool run_dense_too_large(const Model *m, const RunOptions *o)
{
    return o->max_dense_entries > 0 && (long long)m->nr * m->nq > o->max_dense_entries;
}

/* Minimum-norm Newton with step halving over the holonomic rows, from the
 * start in r->q (assemble_kernels, what `info` uses):
 * unlike Newton with LU it starts from any guess, including one where the
 * Jacobian is singular because two links are merely parallel (all angles
 * 0). False, with the message filled, when even it finds no configuration
 * near the initial values: the rows it could not satisfy are named. */
bool run_assemble_robustly(Run *r)
{
    const RunOptions *o = r->o;
    AnalysisOptions ao = analysis_default_options();
    ao.tol_phi = o->mechrt.tol_phi;
    ao.tol_dq = o->mechrt.tol_dq;
    ao.max_iter = o->assembly_max_iter;
    ao.stall_iter = ASSEMBLE_ROUGH_STALL;
    AssembleResult ar;
    if (run_dense_too_large(r->m, o)) {     /* it works on the dense Jacobian */
        r->res->status = ANALYSIS_FAILED;
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
        run_fail_assembly(r, &ar);
    return ok;
}

/* A note when assembly moved the initial values much. */
void run_note_move(Run *r, const double *q0)
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
        run_notef(r, "note", "Newton could not start from the file's initial values; %d of the %d "
              "coordinates were placed by construction (drivers, pins, dyads: of two closures "
              "the one nearer the initial values), then Newton assembled the mechanism at "
              "t = %.10g in %d %s", r->res->constructed, r->nq, r->o->t0, it, its);
    else if (r->res->assembled_robustly)
        run_notef(r, "note", "Newton could not start from the file's initial values; minimum-norm "
              "Newton assembled the mechanism at t = %.10g in %d %s (initial values "
              "near the configuration you mean choose its assembly branch)", r->o->t0, it, its);
    else if (moved > r->o->move_note * (scale > 0 ? scale : 1) && r->res->constructed > 0)
        run_notef(r, "note", "assembly at t = %.10g moved the initial values by up to %.6g "
              "(%s: %.6g -> %.6g): %d of the %d coordinates were placed by construction "
              "(drivers, pins, dyads: of two closures the one nearer the initial values), "
              "then Newton took %d %s", r->o->t0, moved, r->m->coord_names[at], q0[at], r->q[at],
              r->res->constructed, r->nq, it, its);
    else if (moved > r->o->move_note * (scale > 0 ? scale : 1))
        run_notef(r, "note", "assembly at t = %.10g moved the initial values by up to %.6g "
              "(%s: %.6g -> %.6g); the file's values are only Newton's starting point",
              r->o->t0, moved, r->m->coord_names[at], q0[at], r->q[at]);
}

