/* assemble_t0.c - the assembly at t0 of run, sim and check: construction, Newton, the robust restarts, one wording of its failure.
 *
 * Every analysis over time starts where the file's initial values are
 * only a guess: the construction places what it can (drivers, pins,
 * dyads: construct.c), Newton converges from there, and where Newton
 * cannot start (a singular Jacobian at the guess, all angles 0, no
 * convergence) the minimum-norm Newton restarted from jittered guesses
 * (assemble_restarting) finds a configuration near the guess, after which
 * the caller's Newton may run once more (run needs its velocities and
 * accelerations there). Which Newton is the caller's: run steps with its
 * own LU or KLU, check with the engine under test; sim projects (the
 * default here).
 */
#include "assemble_t0.h"

#include "common.h"
#include "construct.h"

#include "../base/arena.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The default Newton: minimum-norm projection onto the holonomic rows, by
   SuiteSparseQR on the sparse bundle (the dense SVD is O(nq^3)), else
   dense. */
static MechrtStatus project(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                            const AssembleT0Options *o, double *q, AssembleT0Report *rep)
{
    MechrtHost *host = jnz ? mechrt_host_new_projector(k, jnz) : mechrt_host_new(k);
    if (!host) {
        rep->out_of_memory = true;
        return MECHRT_EINVAL;
    }
    MechrtStatus st = mechrt_host_project(host, o->mechrt, q, o->t0, &rep->newton);
    mechrt_host_free(host);
    return st;
}

/* The caller's Newton, or the default projection; its iterations counted. */
static MechrtStatus newton(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                           const AssembleT0Options *o, double *q, AssembleT0Report *rep)
{
    MechrtStatus st = o->newton ? o->newton(o->newton_ctx, q, &rep->newton)
                                : project(k, jnz, o, q, rep);
    rep->iterations += rep->newton.iterations;
    return st;
}

bool assemble_at_t0(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                    const AssembleT0Options *o, double *q, AssembleT0Report *rep)
{
    size_t bytes = (size_t)m->nq * sizeof *q;
    *rep = (AssembleT0Report){.t0 = o->t0, .more_option = o->more_option};
    if (!o->no_construction)
        rep->constructed = construct_with_kernels(m, k, o->t0, q);
    double *start = xmalloc(bytes + 1);
    memcpy(start, q, bytes);
    rep->status = newton(k, jnz, o, q, rep);
    if (rep->status != MECHRT_OK && rep->status != MECHRT_EINVAL
        && rep->status != MECHRT_EBADLEN && o->robust) {
        AnalysisOptions ao = o->rough;
        ao.stall_iter = ASSEMBLE_ROUGH_STALL;
        memcpy(q, start, bytes);
        rep->robust = true;
        rep->robust_ok = assemble_restarting(k, o->t0, q, &ao, &rep->rough);
        rep->iterations += rep->rough.iterations;
        if (rep->robust_ok)
            rep->status = o->again ? newton(k, jnz, o, q, rep) : MECHRT_OK;
    }
    free(start);
    return rep->status == MECHRT_OK;
}

void assemble_t0_describe(const Model *m, const MechrtKernels *k, const AssembleT0Report *rep,
                          const double *q, char *msg, size_t size)
{
    int iterations = rep->robust ? rep->rough.iterations : rep->newton.iterations;
    double residual = rep->robust ? rep->rough.residual : rep->newton.residual;
    int worst = rep->robust ? rep->rough.worst_row : rep->newton.worst_row;
    const char *its = iterations == 1 ? "iteration" : "iterations";
    msg[0] = '\0';
    analysis_msgf(msg, size, "t = %.10g: could not assemble from these initial values: ", rep->t0);
    size_t nh = (size_t)k->nh;
    double *phi = xcalloc(nh + 1, sizeof *phi);
    const char **names = xcalloc(nh + 1, sizeof *names);
    k->phi(k->ctx, q, rep->t0, phi);
    bool finite = true;
    for (size_t i = 0; i < nh; i++) {
        finite = finite && isfinite(phi[i]);
        phi[i] = fabs(phi[i]);
        names[i] = m->rows[i].name;
    }
    if (!finite) {
        analysis_msgf(msg, size, "minimum-norm Newton reached NaN or infinity after %d %s",
                      iterations, its);
    } else {
        analysis_msgf(msg, size, "after %d %s of minimum-norm Newton the largest residual is "
                      "%.3g in row %s; rows left unsatisfied: ", iterations, its, residual,
                      worst >= 0 && worst < (int)nh ? names[worst] : "?");
        analysis_name_list(msg, size, names, phi, (int)nh);
    }
    analysis_msgf(msg, size, " (the mechanism may not close with these lengths, or the guess is "
                  "nearer a configuration that does not exist; try other initial values%s%s)",
                  rep->more_option ? ", or more " : "", rep->more_option ? rep->more_option : "");
    free(phi), free(names);
}

/* The note after a successful assembly: how Newton started, or how far it
   moved the file's values when that is beyond move_note * max|q0|; the
   move (max |q - q0|). run and sim print the same words. */
double assemble_t0_note(FILE *notes, const Model *m, const AssembleT0Report *rep,
                        const double *q0, const double *q, double move_note)
{
    double moved = 0, scale = 0;
    int at = 0, it = rep->iterations;
    for (int i = 0; i < m->nq; i++) {
        double d = fabs(q[i] - q0[i]);
        if (d > moved) {
            moved = d;
            at = i;
        }
        scale = fmax(scale, fabs(q0[i]));
    }
    bool far = moved > move_note * (scale > 0 ? scale : 1);
    if (!notes || (!rep->robust && !far))
        return moved;
    const char *its = it == 1 ? "iteration" : "iterations";
    fprintf(notes, "%s: note: ", m->file);
    if (rep->robust && rep->constructed > 0)
        fprintf(notes, "Newton could not start from the file's initial values; %d of the %d "
                "coordinates were placed by construction (drivers, pins, dyads: of two closures "
                "the one nearer the initial values), then Newton assembled the mechanism at "
                "t = %.10g in %d %s", rep->constructed, m->nq, rep->t0, it, its);
    else if (rep->robust)
        fprintf(notes, "Newton could not start from the file's initial values; minimum-norm "
                "Newton assembled the mechanism at t = %.10g in %d %s (initial values "
                "near the configuration you mean choose its assembly branch)", rep->t0, it, its);
    else if (rep->constructed > 0)
        fprintf(notes, "assembly at t = %.10g moved the initial values by up to %.6g "
                "(%s: %.6g -> %.6g): %d of the %d coordinates were placed by construction "
                "(drivers, pins, dyads: of two closures the one nearer the initial values), "
                "then Newton took %d %s", rep->t0, moved, m->coord_names[at], q0[at], q[at],
                rep->constructed, m->nq, it, its);
    else
        fprintf(notes, "assembly at t = %.10g moved the initial values by up to %.6g "
                "(%s: %.6g -> %.6g); the file's values are only Newton's starting point",
                rep->t0, moved, m->coord_names[at], q0[at], q[at]);
    fputc('\n', notes);
    return moved;
}
