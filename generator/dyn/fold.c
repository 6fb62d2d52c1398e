/* fold.c - near a singular position: the accelerations of the rows a step leaves out, held over the step.
 *
 * Where Phi_q nearly loses rank (IFToMM A02's flat positions) the rows
 * becoming dependent are left out for the stages of a step (project.c,
 * choose_rows): off the manifold their acceleration equations are
 * inconsistent by the stage's error over a small pivot. But on the
 * parallelogram branch those rows carry a finite generalised force (a
 * multiplier growing as 1 / sigma times a row combination shrinking as
 * sigma) that the mechanism with the rows left out lacks: its
 * accelerations along the fold directions differ from the branch's by
 * O(1) (A02, N = 2: about 1 m/s^2), and a step with the rows left out
 * drifted by that much times its length, 1e-4 in the velocities per flat
 * position, whatever the tolerance. At the settled state, on the manifold
 * to rounding, the solve with every row is accurate (its error is the
 * manifold's residual over sigma, not the stage's), so the difference
 * between the two solves there is held over the step and added to the
 * right side's accelerations: the drift falls to the change of that
 * difference over the step, O(h^2).
 */
#include "fold.h"

#include "kkt.h"

#include <string.h>

/* The rows left out at the runtime's own rank_tol: redundant rows and
   rank drops nearer than it, which the solve with every row leaves out
   too; fewer than the step's means rows left out that still carry force. */
static bool fold_needed(Sim *s, const double *y, double t, int out)
{
    MechrtDynReport rep;
    if (mechrt_dynamics_rows(&s->kc, &s->o->dyn, y, t, s->fold_rows, s->work, s->lwork, &rep)
        != MECHRT_OK)
        return true;    /* the solve below decides or names the cause */
    return rep.redundant < out;
}

/* qdd at y with every row (all) or the step's rows into qdd. */
static MechrtStatus fold_accel(Sim *s, const double *y, double t, bool all, double *qdd)
{
    int n = s->nq;
    if (s->kkt) {
        s->all_active = all;
        s->mq_valid = false;    /* the other rows' factors */
        MechrtStatus st = sim_sparse_accel(s, y, y + n, t, all ? NULL : s->active, qdd, NULL);
        s->all_active = false;
        s->mq_valid = s->mq_valid && !all;
        if (st == MECHRT_OK || !sim_dense_ready(s))
            return st;
    }
    MechrtDynReport rep;
    return mechrt_forward_dynamics(&s->kc, all ? &s->o->dyn : &s->dyn, y, y + n, t, qdd, NULL,
                                   s->work, s->lwork, &rep);
}

bool sim_fold_prepare(Sim *s, const double *y, double t)
{
    int out = 0;
    for (int i = 0; i < s->nr; i++)
        out += !s->active[i];
    /* the same rows out as in the step before: the difference from where
       they went out is held (nearer the rank drop the solve with every row
       has the residuals of the projections over an ever smaller pivot) */
    if (s->fold_on && out > 0 && memcmp(s->active0, s->active, (size_t)s->nr) == 0) {
        s->res->fold_steps++;
        return true;
    }
    s->fold_on = false;
    if (out == 0 || s->o->method == SIM_MSBDF || !sim_dense_ready(s) || !fold_needed(s, y, t, out))
        return true;    /* msbdf: its rows stay from one output time to the next */
    MechrtStatus st = fold_accel(s, y, t, true, s->fold);
    if (st == MECHRT_OK)
        st = fold_accel(s, y, t, false, s->fold2);
    if (st != MECHRT_OK) {
        sim_fail(s, st, t, "forward dynamics");
        msgf(s, "%s", mechrt_strerror(st));
        return false;
    }
    for (int j = 0; j < s->nq; j++)
        s->fold[j] -= s->fold2[j];
    s->fold_on = sim_all_finite(s->nq, s->fold);
    s->res->fold_steps++;
    return true;
}

void sim_fold_apply(const Sim *s, double *qdd)
{
    if (!s->fold_on)
        return;
    for (int j = 0; j < s->nq; j++)
        qdd[j] += s->fold[j];
}
