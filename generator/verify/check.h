/* check.h - mechc check as a library: derivatives against finite differences, engines against each other. */
#ifndef MECHC_CHECK_H
#define MECHC_CHECK_H

#include "../engine/engine.h"
#include "../kin/run.h"

/* A deliberate mistake planted in the engine under test (the JIT kernels),
   so tests can prove that check catches what it is meant to catch. */
typedef enum CheckFaultKind {
    CHECK_FAULT_NONE,
    CHECK_FAULT_JAC_SCALE,      /* Phi_q[row][col] *= factor (-1: sign, 2: factor 2) */
    CHECK_FAULT_NU_SCALE,       /* nu[row] *= factor */
    CHECK_FAULT_GAMMA_ZERO,     /* gamma[row] = 0 */
    CHECK_FAULT_GAMMA_DROP_TT,  /* gamma[row] loses its -Phi_tt term */
    CHECK_FAULT_GAMMA_DROP_QD,  /* gamma[row] keeps only -Phi_tt (the qd terms dropped) */
    CHECK_FAULT_MASS_SCALE,     /* M[row][col] *= factor (row: a coordinate here) */
} CheckFaultKind;

typedef struct CheckFault {
    CheckFaultKind kind;
    int row, col;
    double factor;
} CheckFault;

/* Defaults from check_default_options(). */
typedef struct CheckOptions {
    int samples;            /* states sampled (default 20) */
    unsigned long seed;     /* random states are a function of it (default 1) */
    /* error = |value - reference| / (1 + |reference|), dimensionless */
    double tol;             /* against finite differences (default 1e-6) */
    double tol_engines;     /* between engines (default 1e-10) */
    double spread_q;        /* q = q_assembled + U(-s, s), coordinate units (default 0.05) */
    double spread_qd;       /* qd = U(-s, s) (default 1) */
    /* The finite differences start at these steps. A comparison above
       tolerance is not judged at the default step alone: the difference is
       redone at h/pi, h/pi^2, ... (then pi h, pi^2 h) until three
       neighbouring steps agree, and the value is judged against that
       settled difference; see check.c. */
    double fd_step;         /* first step of gsl_deriv_central, times max(1, |x|) (default 1e-4) */
    double fd_step2;        /* step of the second difference for gamma, times
                               max(1, |q|)^(1/6) (default 2e-3) */
    bool use_aot;           /* compare the aot engine too when a compiler exists (default true) */
    /* dense (nr x nq Jacobians), or sparse: the Jacobian's nonzeros
       (jac_nz), assembly by KLU, the Jacobian's finite differences by
       groups of columns that share no row; auto: sparse above
       ANALYSIS_DENSE_MAX_NQ coordinates (default auto) */
    AnalysisLinear linear;
    CheckFault fault;       /* tests only (default none) */
    /* notes ("FILE: note: ...": the redundant rows of a mechanism with
       more holonomic rows than coordinates, said once); NULL: none
       (default) */
    FILE *notes;
} CheckOptions;

CheckOptions check_default_options(void);

/* The checks, in report order. FD: the engine under test (jit) against
   finite differences; then every pair of engines on every quantity; then,
   for a file with masses only, every pair on M and Q, M's symmetry and
   positive semi-definiteness, and Q's velocity terms against finite
   differences of the kinetic energy (M from the jit). */
enum {
    CHECK_PAIR_COUNT = ENGINE_KIND_COUNT * (ENGINE_KIND_COUNT - 1) / 2,   /* pairs of engines */
    CHECK_QTY_COUNT = 4,                                                /* phi, jac, nu, gamma */
};

typedef enum CheckWhat {
    CHECK_JAC_FD, CHECK_NU_FD, CHECK_GAMMA_FD,
    CHECK_PAIR_FIRST,
    CHECK_DYN_FIRST = CHECK_PAIR_FIRST + CHECK_QTY_COUNT * CHECK_PAIR_COUNT, /* M, Q of each pair */
    CHECK_M_SYMMETRIC = CHECK_DYN_FIRST + 2 * CHECK_PAIR_COUNT,
    CHECK_M_PSD,
    CHECK_QV_FD,
    /* a file with design parameters: the jit's dPhi/dp against finite
       differences in p, then every pair of engines on it (col: the
       design parameter) */
    CHECK_PHI_P_FD,
    CHECK_PHI_P_PAIR_FIRST,
    /* and every pair on the other sensitivity functions (sens_v, sens_g,
       sens_y: row and col -1) */
    CHECK_SENS_PAIR_FIRST = CHECK_PHI_P_PAIR_FIRST + CHECK_PAIR_COUNT,
    CHECK_WHAT_COUNT = CHECK_SENS_PAIR_FIRST + CHECK_PAIR_COUNT
} CheckWhat;

typedef struct CheckItem {
    const char *what;       /* "jac", "nu", "gamma", "phi jit/generic", ... */
    bool checked;           /* something was compared */
    double error;           /* worst error seen (+inf for a NaN on one side) */
    double tol;
    int row, col;           /* where (col: Jacobian column, else -1) */
    double value, reference;/* the two numbers at the worst place */
    int sample;
    double t;               /* time of the worst sample */
    /* finite-difference items only */
    double step;            /* the step of the worst comparison's finite difference
                               (absolute; 0: the reference is exact, no difference) */
    int refined;            /* comparisons judged at another step than the default,
                               because the default disagreed (a fast-varying row) */
    int unsettled;          /* comparisons the finite differences could not settle (no
                               three neighbouring steps agreed): neither passed nor
                               failed, as the differences cannot tell */
    int unsettled_row, unsettled_col; /* the first of them */
    bool design_col;        /* col is a design parameter, not a coordinate */
    char hint[240];         /* when above tolerance: what mistake it looks like */
} CheckItem;

typedef struct CheckReport {
    bool ok;
    int samples;
    bool assembled;         /* the base state came from Newton (else initial values) */
    bool engine_used[ENGINE_KIND_COUNT];
    char note[300];         /* e.g. why aot was not compared */
    bool sparse;            /* the sparse comparisons were made (CheckOptions.linear) */
    CheckItem items[CHECK_WHAT_COUNT];
} CheckReport;

/* Runs the checks. Returns false with diag filled when it cannot run (an
   engine failed to build); otherwise rep->ok tells the verdict. */
bool check_mechanism(const Mech *mech, const CheckOptions *opt, CheckReport *rep, Diag *diag);

#endif
