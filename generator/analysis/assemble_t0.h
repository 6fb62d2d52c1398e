/* assemble_t0.h - the assembly at t0 of run, sim and check: construction, Newton, the robust restarts, one wording of its failure. */
#ifndef MECHC_ASSEMBLE_T0_H
#define MECHC_ASSEMBLE_T0_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "../../runtime/mechrt.h"
#include "../../runtime/host/mechrt_host.h"
#include "../model/model.h"
#include "assemble.h"

/* A caller's Newton from q at t0, in place, with its report: run's step of
   length 0 (which also solves qd and qdd there), check's dense Newton or
   KLU step. */
typedef MechrtStatus (*AssembleNewtonFn)(void *ctx, double *q, MechrtReport *rep);

/* How to assemble; the fields the caller does not set are 0. */
typedef struct AssembleT0Options {
    double t0;
    bool no_construction;   /* Newton from q as given (info beyond the dense
                               limit keeps the file's values as they are) */
    /* Newton from the construction's q; NULL: minimum-norm projection onto
       the holonomic rows (mechrt_host_project) with mechrt's tolerances,
       on the sparse bundle's projector (SuiteSparseQR) when one is given */
    AssembleNewtonFn newton;
    void *newton_ctx;
    const MechrtOptions *mechrt;
    /* When Newton fails (other than MECHRT_EINVAL, MECHRT_EBADLEN: bad
       input), the restarting minimum-norm Newton from the construction's q
       (assemble_restarting: dense, any guess, all angles 0 included) with
       these tolerances and cap (stall_iter is ASSEMBLE_ROUGH_STALL) */
    bool robust;
    AnalysisOptions rough;
    bool again;             /* Newton once more where the robust assembly succeeded */
    /* the option that allows more robust iterations, named in the failure
       ("--assembly-iter"); NULL: none */
    const char *more_option;
} AssembleT0Options;

typedef struct AssembleT0Report {
    double t0;
    int constructed;        /* coordinates placed by construction (construct.h) */
    MechrtStatus status;    /* the last Newton's; MECHRT_OK: assembled */
    MechrtReport newton;    /* its report */
    int iterations;         /* every Newton's and the robust attempts' */
    bool robust;            /* the robust assembly ran ... */
    bool robust_ok;         /* ... and found a configuration */
    AssembleResult rough;   /* its result */
    bool out_of_memory;     /* the default Newton's projector could not be made */
    const char *more_option;
    double tol_phi;         /* the residual below which a row counts as satisfied */
} AssembleT0Report;

/* Assembles at o->t0 from the file's values in q (nq, updated in place):
   the construction, Newton, and where it fails the robust restarts (then
   Newton again if o->again). jnz: the kernels' sparse Jacobian, or NULL.
   True when assembled (rep->status MECHRT_OK); otherwise q is the last
   attempt and rep says what failed: Newton (rep->status, rep->newton) or,
   with rep->robust and !rep->robust_ok, the robust assembly too. */
bool assemble_at_t0(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                    const AssembleT0Options *o, double *q, AssembleT0Report *rep);

/* The one wording of an assembly that found no configuration, into msg
   (size bytes): "t = T: could not assemble from these initial values:
   after N iterations of minimum-norm Newton the largest residual at the
   best point found is R in row NAME; rows left unsatisfied there: ..."
   (every row above the tolerance; what a violated spatial .norm row
   means), the residuals taken at q: the best point of the robust attempt
   that came closest, else Newton's (each attempt ends at its iterate
   with the smallest residual). */
void assemble_t0_describe(const Model *m, const MechrtKernels *k, const AssembleT0Report *rep,
                          const double *q, char *msg, size_t size);

/* The largest residual of a failed assembly and its row (-1: none). */
typedef struct AssembleViolated {
    double largest;
    int worst;
} AssembleViolated;

/* Room for assemble_t0_violated's text. */
#define ASSEMBLE_VIOLATED_SIZE 1024

/* Appends to msg (size bytes) the holonomic rows violated at q and t
   (above tol_phi and rounding, largest first: "C and rocker.norm") and
   what a violated spatial .norm row means there; *v the largest. False,
   nothing appended, when a residual is NaN or infinite. */
bool assemble_t0_violated(const Model *m, const MechrtKernels *k, double t, double tol_phi,
                          const double *q, AssembleViolated *v, char *msg, size_t size);

/* The statements without any one of which the other holonomic rows
   assemble at t (from the file's values or from q, the best point found):
   the loop that cannot close, each of its joints as much a suspect as the
   rows left unsatisfied at q (a rail out of reach keeps its own rows and
   breaks the joints next to it). Appends to msg "the loop of O, A, B and P
   cannot close (...)", or for one statement "C cannot be met (...)";
   returns how many. Small mechanisms only (one dense assembly each): 0
   beyond ANALYSIS_DENSE_MAX_NQ coordinates or 64 statements. */
int assemble_t0_loop(const Model *m, const MechrtKernels *k, double t, double tol_phi,
                     const double *q, char *msg, size_t size);

/* After a successful assembly, the note ("FILE: note: ...") on notes
   (NULL: none) when Newton could not start from the file's values q0 or
   moved them by more than move_note * max|q0_i| (1 if all 0) to q; the
   move max|q_i - q0_i|. run and sim say the same. */
double assemble_t0_note(FILE *notes, const Model *m, const AssembleT0Report *rep,
                        const double *q0, const double *q, double move_note);

#endif
