/* sim.h - forward dynamics over time, the machinery of `mechc sim`, as a library.
 *
 * sim_run assembles a mechanism with masses at t0 from its file's initial
 * values (as run does), makes the initial velocities consistent, then
 * integrates M qdd + Phi_q^T lambda = Q, Phi_q qdd = gamma with GSL's
 * odeiv2 (state (q, qd), accelerations from mechrt_forward_dynamics),
 * projecting positions and velocities back onto the constraints, and hands
 * the state at `steps` equal intervals to a callback. Like run.h: no
 * printing, no exit; a failure is an AnalysisStatus with a one-line message
 * naming `t = VALUE` and the cause.
 */
#ifndef MECHC_SIM_H
#define MECHC_SIM_H

#include <stdbool.h>
#include <stdio.h>

#include "../../runtime/mechrt.h"
#include "../../runtime/host/mechrt_host.h"
#include "../engine/engine.h"
#include "../model/model.h"
#include "../analysis/common.h"
#include "../analysis/redundant.h"

/* The integrators: explicit embedded Runge-Kutta pairs, and two implicit
   methods for stiff mechanisms (stiff springs, large damping) that take
   a finite-difference Jacobian of the right side. */
typedef enum SimMethod { SIM_RK8PD, SIM_RKF45, SIM_RK4IMP, SIM_MSBDF } SimMethod;

/* "rk8pd", "rkf45", "rk4imp", "msbdf", NULL: the --method names, in order. */
extern const char *const sim_method_names[];

/* What a simulation does; fill with sim_default_options(). */
typedef struct SimOptions {
    double t0, t1;          /* time interval, t1 != t0; 0, 1 */
    int steps;              /* output intervals, >= 1: steps + 1 states; 100 */
    SimMethod method;       /* SIM_RK8PD */
    /* local error per step |err_i| <= atol + rtol |y_i| on every position
       and velocity; 5e-11, 5e-11 */
    double rtol, atol;
    MechrtDynOptions dyn;   /* rank tolerance, Baumgarte (off) */
    /* the projections' Newton: tol_phi, tol_dq, max_iter; and assembly's */
    MechrtOptions mechrt;
    bool project;           /* coordinate projection; true */
    /* Steps across the output times instead of ending a step at each one;
       the state at an output time is the degree-8 Hermite interpolant of
       q, qd, qdd at the ends of the enclosing step and the one before
       (quintic, on the enclosing step's ends alone, in the first), its
       accelerations and multipliers solved there (not projected: Phi = 0
       holds to the interpolation error). false: every output time is a step's end */
    bool interpolate;
    /* At the start of every step (on the manifold), rows whose pivot in
       the rank-revealing elimination is <= row_tol * max|Phi_q_ij| are left
       out for the step's stages: redundant rows, and near a singular
       position the row that becomes dependent there (off the manifold, at
       the stages, its acceleration equation is inconsistent by the step's
       error divided by the pivot); the projection restores it. 1e-4 */
    double row_tol;
    /* integrate the work of the forces for the energy balance (3 more
       mass-kernel calls per right-hand side); true */
    bool energy;
    const double *qd0;      /* initial velocities (nq), NULL: zero; projected
                               onto Phi_q qd = nu either way */
    int assembly_max_iter;  /* minimum-norm Newton at t0 when projection fails; 100 */
    long max_steps;         /* integrator steps allowed in all; 10 000 000 */
    FILE *notes;            /* notes ("FILE: note: ..."); NULL: none */
    const char *const *row_names; /* nr names for failures; NULL: unnamed (sim_run: the file's) */
    /* called after every accepted step with its end (progress); NULL: none */
    void (*on_step)(void *ctx, double t);
    void *on_step_ctx;
    AnalysisLinear linear;  /* ANALYSIS_LINEAR_AUTO */
    /* the model whose force element a NaN right side is blamed on
       (blame.c; sim_run: its own), and the file's text for its line and
       column; NULL: no element named, its name alone */
    const Model *model;
    const Diag *source;
    /* sim_run with more holonomic rows than coordinates: the redundant
       rows it leaves out (the kernels are the other rows'), checked at
       every output state, their multipliers reported as 0; NULL: none */
    Redundant *redundant;
} SimOptions;

SimOptions sim_default_options(void);

enum { SIM_MESSAGE_MAX = 1024 };

/* Kernel calls by kind, through the counting wrapper (engine_counting). */
typedef EngineCalls SimKernelCalls;

typedef struct SimResult {
    AnalysisStatus status;
    MechrtStatus cause;          /* behind ANALYSIS_FAILED */
    double t_fail;
    char message[SIM_MESSAGE_MAX];
    int states;                  /* states handed to the callback */
    int constructed;             /* coordinates placed by construction at t0 */
    bool assembled_robustly;     /* minimum-norm Newton with restarts at t0 */
    double assembly_move;        /* ||q(t0) - q0||_inf */
    long steps, rejected;        /* accepted and rejected integrator steps */
    long rhs_calls;              /* forward-dynamics solves for the integrator */
    long jacobian_calls;         /* finite-difference Jacobians (implicit methods) */
    long projections;            /* position + velocity projections */
    long qr_solves;              /* dense projection solves by QR */
    long svd_solves;             /* dense projection solves by the SVD (near a rank drop) */
    /* the sparse path: whether it ran; KLU factorisations of the augmented
       matrix with pivot search and without; projection solves on it; row
       choices by the augmented matrix's pivots alone and by the dense
       rank-revealing elimination (near a rank drop); right sides and
       projection solves that fell back to the dense methods */
    bool sparse;
    long kkt_fresh, kkt_refactored, kkt_solves;
    long kkt_reused;             /* M's factors reused at the same state */
    long rows_sparse, rows_dense, dense_fallbacks;
    double max_screen_spread;    /* largest pivot spread of [I Phi_q^T; Phi_q 0] with
                                    every row, where it factored (sparse path) */
    long projection_iterations;  /* Newton iterations in the position ones */
    long fold_steps;             /* steps near a rank drop that left rows out with their
                                    accelerations held (fold.c) */
    SimKernelCalls calls;
    int max_redundant;           /* most rows found dependent at once */
    double min_pivot_ratio;      /* nearest approach to a rank drop (1: none) */
    /* energy balance E = T - W, T = 1/2 qd^T M qd, W the work of the applied
       and constraint forces: max |E - E(t0)| over the accepted steps, and
       the largest of T and |W| met (the scale it is relative to) */
    double energy_drift, energy_scale;
    double seconds, cpu_seconds; /* wall and CPU time of the integration */
} SimResult;

/* Receives each output state; lambda holds nr multipliers. */
typedef void (*SimStateFn)(void *ctx, double t, const double *q, const double *qd,
                           const double *qdd, const double *lambda);

/* The kernels have the dynamics slots (a file with masses). */
bool sim_has_masses(const MechrtKernels *k);

/* From the file's initial values: construction and assembly at t0 (as
   run), then sim_integrate. More holonomic rows than coordinates (no
   velocity-level rows): the redundant rows found at t0 and left out
   (SimOptions.redundant, notes on the rows and on their reactions), the
   states checked on them and their lambda reported as 0. */
AnalysisStatus sim_run(const Model *m, const MechrtKernels *k, const MechrtHostJacNz *jnz,
                       const MechrtHostMassNz *mnz, const SimOptions *o, SimStateFn state,
                       void *state_ctx, SimResult *res);

/* From positions q0 (nq; projected onto Phi = 0 first) and o->qd0, with
   kernels k and, for the sparse path, their nonzeros jnz and mnz
   (engine_jac_nz, engine_mass_nz; NULL without: the sparse path needs
   both and jnz->all_nz). */
AnalysisStatus sim_integrate(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                             const MechrtHostMassNz *mnz, const SimOptions *o, const double *q0,
                             SimStateFn state, void *state_ctx, SimResult *res);

#endif
