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

/* Rows whose residual at the failed assembly's best point is below this
   fraction of the largest are rounding, not violated (and never below the
   tolerance). */
#define ASSEMBLE_T0_NOISE 1e-6

/* A failed assembly looks for the loop that cannot close (describe_loop)
   in mechanisms of at most this many statements (and the dense limit's
   coordinates). */
#define ASSEMBLE_T0_LOOP_JOINTS 64
/* Iterations of each of its probes: the rows without a statement of the
   loop close from the file's values in a few; the others only stall. */
#define ASSEMBLE_T0_LOOP_ITER 20

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
    *rep = (AssembleT0Report){.t0 = o->t0, .more_option = o->more_option,
                              .tol_phi = o->mechrt ? o->mechrt->tol_phi : o->rough.tol_phi};
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

/* What a violated normalisation row of a spatial body means, and the
   length of its Euler parameters there: the row is |p|^2 - 1 (phi signed,
   violated where |phi| >= floor). */
static void describe_norms(const Model *m, const double *phi, double floor, char *msg,
                           size_t size)
{
    for (int i = 0; i < m->nh; i++)
        if (m->rows[i].kind == JOINT_S_NORM && fabs(phi[i]) >= floor)
            analysis_msgf(msg, size, "; %s is the normalisation of %s's Euler parameters "
                          "(e0^2 + e1^2 + e2^2 + e3^2 = 1), and there |p| = %.6g",
                          m->rows[i].name, m->joints[m->rows[i].joint].name,
                          sqrt(fmax(0.0, 1.0 + phi[i])));
}

/* One dense minimum-norm Newton per statement, from the file's values
   then from q, on the other rows: those without which the rest closes. */
int assemble_t0_loop(const Model *m, const MechrtKernels *k, double t, double tol_phi,
                     const double *q, char *msg, size_t size)
{
    int nq = k->nq, nh = k->nh, nj = m->njoints, found = 0;
    if (nq > ANALYSIS_DENSE_MAX_NQ || nj > ASSEMBLE_T0_LOOP_JOINTS)
        return 0;
    int *rows = xcalloc((size_t)nh + 1, sizeof *rows);
    double *trial = xcalloc((size_t)nq + 1, sizeof *trial);
    double *in_loop = xcalloc((size_t)nj + 1, sizeof *in_loop);
    const char **names = xcalloc((size_t)nj + 1, sizeof *names);
    AnalysisOptions opt = analysis_default_options();
    opt.tol_phi = tol_phi;
    opt.stall_iter = ASSEMBLE_ROUGH_STALL;
    opt.max_iter = ASSEMBLE_T0_LOOP_ITER;
    MechrtSvd *w = mechrt_svd_new(nh, nq);
    for (int j = 0; j < nj && w; j++) {
        names[j] = m->joints[j].name;
        int n = 0;
        for (int i = 0; i < nh; i++)
            if (m->rows[i].joint != j)
                rows[n++] = i;
        if (n == nh || m->joints[j].kind == JOINT_S_NORM)
            continue;   /* no holonomic rows; a body's normalisation is no suspect */
        /* from the file's values, then from the best point */
        AssembleResult res;
        bool closes = false;
        for (int from = 0; from < 2 && !closes; from++) {
            memcpy(trial, from ? q : m->q0, (size_t)nq * sizeof *trial);
            closes = assemble_min_norm(k, rows, n, t, trial, &opt, w, &res);
        }
        if (closes) {
            in_loop[j] = 1;
            found++;
        }
    }
    if (found > 1) {
        analysis_msgf(msg, size, "the loop of ");
        analysis_name_above(msg, size, names, in_loop, nj, 1);
        analysis_msgf(msg, size, " cannot close (without any one of them the other rows "
                      "assemble: a length, a pivot, a rail or a driven position out of reach)");
    } else if (found == 1) {
        analysis_name_above(msg, size, names, in_loop, nj, 1);
        analysis_msgf(msg, size, " cannot be met (without it the other rows assemble)");
    }
    mechrt_svd_free(w);
    free(rows), free(trial), free(in_loop), free(names);
    return found;
}

bool assemble_t0_violated(const Model *m, const MechrtKernels *k, double t, double tol_phi,
                          const double *q, AssembleViolated *v, char *msg, size_t size)
{
    size_t nh = (size_t)k->nh;
    double *phi = xcalloc(nh + 1, sizeof *phi), *size_of = xcalloc(nh + 1, sizeof *size_of);
    const char **names = xcalloc(nh + 1, sizeof *names);
    k->phi(k->ctx, q, t, phi);
    bool finite = true;
    *v = (AssembleViolated){0, -1};
    for (size_t i = 0; i < nh; i++) {
        finite = finite && isfinite(phi[i]);
        size_of[i] = fabs(phi[i]);
        if (size_of[i] > v->largest) {
            v->largest = size_of[i];
            v->worst = (int)i;
        }
        names[i] = m->rows[i].name;
    }
    if (finite) {
        /* every row violated there, not only those near the largest */
        double floor = fmax(tol_phi, ASSEMBLE_T0_NOISE * v->largest);
        analysis_name_above(msg, size, names, size_of, (int)nh, floor);
        describe_norms(m, phi, floor, msg, size);
    }
    free(phi), free(size_of), free(names);
    return finite;
}

/* Appends the rows that are NaN or infinite at the file's initial values
   (an expression not defined there: no iterate can help); how many. */
static int nonfinite_at_q0(const Model *m, const MechrtKernels *k, double t, char *msg,
                           size_t size)
{
    size_t nh = (size_t)k->nh;
    double *phi = xcalloc(nh + 1, sizeof *phi), *bad = xcalloc(nh + 1, sizeof *bad);
    const char **names = xcalloc(nh + 1, sizeof *names);
    k->phi(k->ctx, m->q0, t, phi);
    for (size_t i = 0; i < nh; i++) {
        bad[i] = isfinite(phi[i]) ? 0 : 1;
        names[i] = m->rows[i].name;
    }
    int n = analysis_name_above(msg, size, names, bad, (int)nh, 1);
    free(phi), free(bad), free(names);
    return n;
}

void assemble_t0_describe(const Model *m, const MechrtKernels *k, const AssembleT0Report *rep,
                          const double *q, char *msg, size_t size)
{
    int iterations = rep->robust ? rep->rough.iterations : rep->newton.iterations;
    const char *its = iterations == 1 ? "iteration" : "iterations";
    char rows[ASSEMBLE_VIOLATED_SIZE] = "", loop[ASSEMBLE_VIOLATED_SIZE] = "";
    AssembleViolated v;
    msg[0] = '\0';
    analysis_msgf(msg, size, "t = %.10g: could not assemble from these initial values: ", rep->t0);
    if (nonfinite_at_q0(m, k, rep->t0, rows, sizeof rows) > 0) {
        analysis_msgf(msg, size, "rows not a finite number at the file's initial values: %s "
                      "(an expression not defined there: the square root or log of a negative "
                      "number, 0/0, asin or acos past 1, an overflow?); give initial values and "
                      "t0 where every row is defined", rows);
        return;
    }
    bool finite = assemble_t0_violated(m, k, rep->t0, rep->tol_phi, q, &v, rows, sizeof rows);
    if (finite && assemble_t0_loop(m, k, rep->t0, rep->tol_phi, q, loop, sizeof loop) > 0)
        analysis_msgf(msg, size, "%s; ", loop);     /* the cause first */
    if (!finite)
        analysis_msgf(msg, size, "minimum-norm Newton reached NaN or infinity after %d %s",
                      iterations, its);
    else    /* q: the iterate with the smallest residual (min_norm_newton, project) */
        analysis_msgf(msg, size, "after %d %s of minimum-norm Newton the largest residual at "
                      "the best point found is %.3g in row %s; rows left unsatisfied there: %s",
                      iterations, its, v.largest, v.worst >= 0 ? m->rows[v.worst].name : "?",
                      rows);
    analysis_msgf(msg, size, " (the mechanism may not close with these lengths, or the guess is "
                  "nearer a configuration that does not exist; try other initial values%s%s)",
                  rep->more_option ? ", or more " : "", rep->more_option ? rep->more_option : "");
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
