/* start.c - a run's start at t0: the assembly with the run's Newton, its failures, the note on how far it moved. */
#include "start.h"

#include "diagnose.h"

#include "../analysis/assemble_t0.h"
#include "../base/arena.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Whether a dense nr x nq Jacobian would be beyond RunOptions.max_dense_entries. */
bool run_dense_too_large(const Model *m, const RunOptions *o)
{
    return o->max_dense_entries > 0 && (long long)m->nr * m->nq > o->max_dense_entries;
}

/* The assembly at t0 (assemble_at_t0) with the run's Newton, from the
   file's values in r->q: the construction, Newton, and where Newton cannot
   start the robust minimum-norm Newton with restarts (dense: not beyond
   RunOptions.max_dense_entries), then Newton again for the velocities and
   accelerations there. With singular, a configuration where the Jacobian
   is nearly singular fails as the toggle it is. res's assembly fields
   filled, *rep Newton's last report; false with the failure in res
   (what: the phase Newton's failure names). */
bool run_assemble(Run *r, AssembleNewtonFn newton, void *ctx, bool singular, MechrtReport *rep,
                  const char *what)
{
    const RunOptions *o = r->o;
    RunResult *res = r->res;
    size_t bytes = (size_t)r->nq * sizeof *r->q;
    AssembleT0Options ao = {.t0 = o->t0, .newton = newton, .newton_ctx = ctx,
                            .robust = !run_dense_too_large(r->m, o), .again = true,
                            .rough = analysis_default_options(), .more_option = "--assembly-iter"};
    ao.rough.tol_phi = o->mechrt.tol_phi;
    ao.rough.tol_dq = o->mechrt.tol_dq;
    ao.rough.max_iter = o->assembly_max_iter;
    double *q0 = xmalloc(bytes + 1);
    memcpy(q0, r->q, bytes);
    AssembleT0Report ar;
    assemble_at_t0(r->m, r->k, NULL, &ao, r->q, &ar);
    *rep = ar.newton;
    res->constructed = ar.constructed;
    res->assembly_iterations = ar.iterations;
    res->assembled_robustly = ar.robust;
    MechrtStatus st = ar.status;
    if (ar.robust && !ar.robust_ok) {
        run_fail_assembly(r, &ar);
    } else if (st != MECHRT_OK && !ao.robust && st != MECHRT_EINVAL && st != MECHRT_EBADLEN) {
        res->status = ANALYSIS_FAILED;     /* the robust assembly works on the dense Jacobian */
        res->cause = MECHRT_EMAXITER;
        res->t_fail = o->t0;
        snprintf(res->message, sizeof res->message, "t = %.10g: Newton found no "
                 "configuration from these initial values, and the robust assembly's dense "
                 "Jacobian would have more than %lld entries (--max-jac-entries)", o->t0,
                 o->max_dense_entries);
    } else {
        if (st == MECHRT_OK && singular && run_nearly_singular(r, o->t0)) {
            st = MECHRT_ESING;
            rep->sing_index = -1;
        }
        if (st != MECHRT_OK)
            run_fail(r, st, o->t0, r->q, rep, what);
        else
            res->assembly_move = assemble_t0_note(o->notes, r->m, &ar, q0, r->q, o->move_note);
    }
    free(q0);
    return st == MECHRT_OK;     /* not after a failed robust assembly: Newton's failure */
}
