/* run.h - kinematic analysis over time, the machinery of `mechc run`, as a library.
 *
 * run_analysis assembles a mechanism at t0 from its file's initial values
 * and walks it over `steps` equal intervals to t1, handing every state
 * (t, q, qd, qdd) to a callback as soon as it is known. It never prints
 * an error and never exits: a failure is an AnalysisStatus with a one-line
 * message naming `t = VALUE`, the cause and the rows and coordinates
 * involved; notes and warnings (assembly moved q, nearly singular
 * stretches) go to RunOptions.notes when that is not NULL.
 */
#ifndef MECHC_RUN_H
#define MECHC_RUN_H

#include <stdio.h>

#include "../../runtime/mechrt.h"
#include "../../runtime/host/mechrt_host.h"
#include "../engine/engine.h"
#include "../model/model.h"
#include "../analysis/common.h"

/* The dense path's LU of Phi_q, lent to a caller that solves with the
   same matrix at the states handed out (run --sens). After a step that
   ended with the run's pattern LU factored at its converged state, `valid`
   is true and (t, q) is that state: then lup holds Phi_q(q, t) (solve with
   mechrt_lup_solve) until the next step. lup is NULL when the run has no
   pattern LU (sparse path, redundant rows, velocity-level rows). The run
   owns q (nq values) and clears the whole when it returns. */
typedef struct RunLu {
    const MechrtLup *lup;
    bool valid;
    double t;
    double *q;
} RunLu;

/* What a run does; fill with run_default_options(), then change fields. */
typedef struct RunOptions {
    double t0, t1;           /* time interval, t1 != t0 (t1 < t0 runs backwards); 0, 1 */
    int steps;               /* equal intervals, >= 0: steps + 1 states (0: the
                                analysis at t0 alone, t1 unused); 100 */
    /* Holonomic stepping: an interval whose step looks as if it left its
       assembly branch (see run.c) is redone internally in 2, 4, 8 ...
       predictor-corrector substeps, at most this many, >= 1 (1: never
       subdivide, such a step fails); only grid states are reported. 64 */
    int max_substeps;
    MechrtOptions mechrt;    /* Newton tolerances and cap, pivot and condition
                                thresholds: mechrt_default_options() */
    MechrtOdeOptions ode;    /* integrator for velocity-level rows: rk8pd, 1e-10 */
    /* a note when assembly moves q by more than move_note * ||q0||_inf
       (dimensionless); default 1e-3 */
    double move_note;
    /* iterations of the minimum-norm Newton that assembles at t0 when
       Newton from the initial values fails (a singular Jacobian at the
       guess, no convergence); default 100 */
    int assembly_max_iter;
    FILE *notes;             /* notes and warnings, "FILE: warning: ..."; NULL: none */
    /* the file's text, for the line and column of a force element that
       inverse dynamics finds NaN (dyn/blame.c); NULL: its name alone */
    const Diag *source;
    AnalysisLinear linear;   /* ANALYSIS_LINEAR_AUTO */
    /* most rows x coordinates of a dense Jacobian, checked when the run
       would form one (dense linear algebra, the robust assembly at t0);
       0: no limit (default; mechc run passes --max-jac-entries here when
       the sparse path may serve, instead of the model builder) */
    long long max_dense_entries;
    RunLu *lend_lu;          /* where the run lends its LU; NULL (default): nowhere */
} RunOptions;

RunOptions run_default_options(void);

enum { RUN_MESSAGE_MAX = 1024 };

typedef struct RunResult {
    AnalysisStatus status;
    MechrtStatus cause;          /* the runtime's status behind ANALYSIS_FAILED;
                                    MECHRT_ESTEP also when an interval still
                                    looked unreliable with max_substeps substeps */
    double t_fail;               /* when ANALYSIS_FAILED: the time that failed */
    char message[RUN_MESSAGE_MAX]; /* ANALYSIS_FAILED, ANALYSIS_BAD_INPUT: "t = 0.25: ..." */
    int states;                  /* states handed to the callback */
    int warnings;                /* nearly singular episodes warned about */
    double assembly_move;        /* ||q(t0) - q0||_inf */
    int assembly_iterations;     /* Newton (or Gauss-Newton) iterations at t0 */
    int constructed;             /* coordinates placed by construction at t0
                                    (construct.h), before Newton */
    bool assembled_robustly;     /* Newton from the initial values failed and
                                    minimum-norm Newton assembled instead */
    /* per-step statistics, over the steps after t0 */
    int steps_done;
    long newton_iterations;      /* Newton iterations (velocity rows: projection
                                    iterations) */
    double step_seconds;         /* wall time inside the analysis of those steps */
    double step_cpu_seconds;     /* the process's CPU time in the same (clock()) */
    int subdivided;              /* intervals redone in substeps */
    long substeps;               /* predictor-corrector substeps taken in them
                                    (every level tried; their Newton iterations
                                    are in newton_iterations) */
    double max_cond;             /* largest condition estimate seen (0: off) */
    bool integrated;             /* positions came from the integrator */
    bool sparse;                 /* the sparse path (KLU) was used */
    long fresh_factorisations;   /* sparse: KLU factorisations with pivoting
                                    (dense: the pattern LU's finished by lu.c)... */
    long refactorisations;       /* ... and with the pivot order kept (replayed) */
    long generated_factorisations;   /* dense: by the kernels' unrolled LU
                                        (PREFIX_lu_factor), not counted above */
    MechrtHostStats host;        /* integrator counters when integrated */
    /* through singular positions (holonomic runs): steps redone by the
       rank-revealing corrector (mechrt_rank_correct) because the LU found
       the Jacobian singular or too ill-conditioned, those of them where it
       was rank-deficient, the largest deficiency, and its QR
       factorisations (dense, also on the sparse path) */
    int rank_steps;
    int rank_deficient_steps;
    int max_rank_deficiency;
    long rank_factorisations;
    /* the last time the corrector could not continue the motion: when,
       its status (MECHRT_OK: it converged, but no velocity or acceleration
       near the continued one satisfies their equations), and the residual
       share it left */
    bool rank_failed;
    double rank_t;
    MechrtStatus rank_status;
    double rank_inconsistency;
    /* run_analysis_forces: the largest part of Q - M qdd the rows could
       not carry (mechrt_inverse_dynamics' residual; above round-off only
       where the Jacobian lost rank) and the most rows found dependent */
    double force_residual;
    int force_redundant;
} RunResult;

/* Receives each state as soon as it is computed. */
typedef void (*RunStateFn)(void *ctx, double t, const double *q, const double *qd,
                           const double *qdd);

/* The same with the multipliers of inverse dynamics (nr values, signed as
   in M qdd + Phi_q^T lambda = Q): run_analysis_forces' states, and the
   shape of sim's (SimStateFn). */
typedef void (*RunForcesFn)(void *ctx, double t, const double *q, const double *qd,
                            const double *qdd, const double *lambda);

/* True when m has one row per coordinate, as a run needs, or more
   holonomic rows and no velocity-level ones (the redundant rows are left
   out at t0, redundant.h); otherwise false with why (size bytes) saying
   how many degrees of freedom are not driven or how many rows are too
   many. */
bool run_rows_match(const Model *m, char *why, size_t size);

/* Whether a run of m with options o takes the sparse path (jnz: the
   engine's sparse Jacobian, or NULL). */
bool run_linear_is_sparse(const Model *m, const MechrtHostJacNz *jnz, const RunOptions *o);

/* The run. m gives sizes, names and initial values; k evaluates m's rows;
   jnz is their sparse Jacobian (engine_jac_nz), or NULL: dense only.
   Needs k->nh + k->nv == k->nq, otherwise ANALYSIS_BAD_INPUT saying how many
   degrees of freedom are not driven (or how many rows are too many); or
   more holonomic rows than coordinates (k->nv == 0): the redundant rows
   found at t0 (a note), the run on the others, every state checked on
   the redundant ones (ANALYSIS_FAILED where they contradict the others),
   and ANALYSIS_BAD_INPUT when the others drive too few coordinates. */
AnalysisStatus run_analysis(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                            const RunOptions *o, RunStateFn state, void *state_ctx,
                            RunResult *res);

/* run_analysis with inverse dynamics at every state: lambda from
   Phi_q^T lambda = Q(q, qd, t) - M(q) qdd (mechrt_inverse_dynamics,
   minimum-norm where rows are dependent), computed inside each step's
   timing, handed to state with the state (with redundant rows: the rows
   kept carry the reactions, the redundant rows' lambda is 0, a note says
   they are not unique). Needs k->mass and k->force (a
   file with masses): ANALYSIS_BAD_INPUT otherwise. A failed solve (NaN in M or
   Q) fails the run at that time. */
AnalysisStatus run_analysis_forces(const Model *m, const MechrtKernels *k,
                                   const MechrtHostJacNz *jnz, const RunOptions *o,
                                   RunForcesFn state, void *state_ctx, RunResult *res);

#endif
