/* mechc.h - libmechc, the mechanism compiler as a library: load, compile, evaluate, analyse.
 *
 * Usage (doc/library.md has a worked example):
 *
 *     mechc_diag d;
 *     mechc_model *m = mechc_load_file("four_bar.mech", &d);
 *     if (!m) { fprintf(stderr, "%s:%d:%d: %s\n", d.file, d.line, d.column, d.message); ... }
 *     mechc_kernels *k = mechc_compile(m, "jit", &d);
 *     double phi[8];                       // mechc_nh(m) values
 *     mechc_phi(k, mechc_q0(m), 0.0, phi);
 *     mechc_kernels_free(k);
 *     mechc_model_free(m);
 *
 * Handles are opaque. There are no global variables: calls on distinct
 * models (and the kernels and results made from them) may run in
 * different threads at the same time. One model, and the kernels compiled
 * from it, serve one thread at a time (the generic engine and the outputs
 * keep scratch memory in the handle). A kernels handle keeps a pointer to
 * its model: free the kernels first.
 *
 * The first load turns GSL's error handler off (gsl_set_error_handler_off:
 * its default aborts; the library checks every status), for good.
 *
 * The library never prints (unless given a stream for the notes of a run
 * or a simulation: mechc_run_tuning, mechc_sim_tuning) and never exits on
 * bad input or a failed analysis: every failure is a status
 * (mechc_status) and, where a mechc_diag pointer is taken (it may be
 * NULL), a message. Out of memory aborts the process, as the mechc
 * command does. A NULL handle gives MECHC_EARG (or NULL), and 0, -1 or
 * NULL from the accessors.
 *
 * Arrays: every matrix is row-major (C order), its size given below as
 * ROWS x COLS; the caller allocates every output array. Sizes:
 *   nq   coordinates                 mechc_nq
 *   nh   holonomic rows (Phi)        mechc_nh
 *   nv   velocity-level rows         mechc_nv
 *   nr   all rows, nh + nv           mechc_nr     (rows 0..nh-1 holonomic)
 *   nout output values               mechc_nout
 *   np   design parameters           mechc_np
 *   nnz  the Jacobian's nonzeros     mechc_jacobian_nz
 */
#ifndef MECHC_H
#define MECHC_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MECHC_API_VERSION 1

/* What a call returns. 0 is success; the others name the kind of failure. */
typedef enum mechc_status {
    MECHC_OK = 0,
    MECHC_EINPUT = 1,       /* the mechanism file or text is wrong (line, column set) */
    MECHC_EARG = 2,         /* a bad argument: an unknown name or engine, an index or
                               size out of range, a NULL array, options out of range */
    MECHC_ENOTAVAIL = 3,    /* the model has no such thing: dynamics without masses,
                               design sensitivities without design parameters, a
                               dense Jacobian of a sparse-only (very large) model */
    MECHC_ECOMPILE = 4,     /* the engine could not compile (no compiler for aot) */
    MECHC_EANALYSIS = 5,    /* an analysis failed: no convergence, a singular
                               Jacobian, a step too small; states before it are kept */
    MECHC_ENOTRUNNABLE = 6  /* not runnable as it is: run needs as many rows as
                               coordinates, sim needs masses */
} mechc_status;

enum { MECHC_DIAG_FILE_MAX = 256, MECHC_DIAG_MESSAGE_MAX = 1024 };

/* A failure as a value. line and column are 1-based, 0 when the failure
   has no place in the file. message has no "file:line:col: error:" prefix. */
typedef struct mechc_diag {
    mechc_status status;
    char file[MECHC_DIAG_FILE_MAX];
    int line, column;
    char message[MECHC_DIAG_MESSAGE_MAX];
} mechc_diag;

typedef struct mechc_model mechc_model;
typedef struct mechc_kernels mechc_kernels;
typedef struct mechc_result mechc_result;

/* "0.1.0": the version of the mechc the library was built with. */
const char *mechc_version(void);
/* A short text for a status ("singular Jacobian"... ); never NULL. */
const char *mechc_status_text(mechc_status status);
/* Frees what the library hands out with "free with mechc_free" (strings). */
void mechc_free(void *p);

/* ---- loading ---- */

/* Reads, parses, resolves and differentiates a .mech file ("-": stdin).
   NULL with diag filled (MECHC_EINPUT, file, line, column) on bad input. */
mechc_model *mechc_load_file(const char *path, mechc_diag *diag);
/* The same from text in memory; name is what diagnostics call the file and
   gives the mechanism's default name (its stem), NULL: "<string>". */
mechc_model *mechc_load_string(const char *text, const char *name, mechc_diag *diag);
void mechc_model_free(mechc_model *m);

/* The limits on one input (examples/README.md, section Limits; what the
   command's --max-... options set): each bounds the work or memory a file
   can cause, and loading fails with MECHC_EINPUT, naming the limit, past it. */
typedef struct mechc_limits {
    int max_file_bytes;     /* the whole file; 4 MiB */
    int max_line_length;    /* bytes per line; 4096 */
    int max_name_length;    /* characters per name; 255 */
    int max_depth;          /* expression nesting; 64 */
    int max_expr_tokens;    /* tokens in one statement; 2000 */
    int max_coords;         /* coordinates; 200000 */
    int max_rows;           /* constraint rows; 200000 */
    int max_jac_entries;    /* rows x coordinates of the dense Jacobian; 50000000
                               (0: not checked while loading) */
    int max_nodes;          /* expression-graph nodes, derivatives included; 2000000 */
    int max_code_ops;       /* operations in the generated C; 4000000 */
    const char *jac_advice; /* NULL, or what ends max_jac_entries' message: how
                               the caller can do without the dense Jacobian */
} mechc_limits;

mechc_limits mechc_default_limits(void);

/* The longest source line a diagnostic quotes, its NUL included. */
enum { MECHC_DIAG_LINE_MAX = 4100 };

/* mechc_load_file with limits (NULL: the defaults). On bad input
   source_line (NULL, or MECHC_DIAG_LINE_MAX chars) receives the line the
   diagnostic points into, for a caret under diag->column ("" when the
   failure has no line): what the command prints under its message. */
mechc_model *mechc_load_file_with(const char *path, const mechc_limits *limits,
                                  mechc_diag *diag, char *source_line);

/* ---- sizes and names (the model's; valid as long as it lives) ---- */

int mechc_nq(const mechc_model *m);
int mechc_nh(const mechc_model *m);
int mechc_nv(const mechc_model *m);
int mechc_nr(const mechc_model *m);
int mechc_nout(const mechc_model *m);
int mechc_nbodies(const mechc_model *m);
int mechc_np(const mechc_model *m);
/* 1 when the file has masses (mass, force, eom and sim are available). */
int mechc_has_dynamics(const mechc_model *m);
/* 1 for a `spatial` file. */
int mechc_is_spatial(const mechc_model *m);
/* The mechanism's name (its `mechanism` statement or the file's stem). */
const char *mechc_model_name(const mechc_model *m);

/* Names by index; NULL when i is out of range. */
const char *mechc_coord_name(const mechc_model *m, int i);     /* "crank.phi", i < nq */
const char *mechc_row_name(const mechc_model *m, int i);       /* "A.x", i < nr */
const char *mechc_output_name(const mechc_model *m, int i);    /* i < nout */
const char *mechc_body_name(const mechc_model *m, int i);      /* bodies and points, i < nbodies */
const char *mechc_design_name(const mechc_model *m, int i);    /* i < np */
/* Index of a name, -1 when there is none. */
int mechc_coord_index(const mechc_model *m, const char *name);
/* A body's first coordinate and its count (3 planar body, 2 point, 7
   spatial body, 3 spatial point); MECHC_EARG when i is out of range. */
mechc_status mechc_body_coords(const mechc_model *m, int i, int *first, int *count);

/* The file's initial values: q0 (nq values; the pointer lives as long as m). */
const double *mechc_q0(const mechc_model *m);
/* The initial velocities sim starts from by default: zero (nq values);
   for symmetry with q0 and a future `qd0` in files. */
mechc_status mechc_qd0(const mechc_model *m, double *qd0);

/* ---- design parameters (`design NAME = value` statements) ---- */

/* The design evaluated now (np values). */
mechc_status mechc_design(const mechc_model *m, double *p);
/* Sets one design parameter (what `--design NAME=VALUE` does): every
   kernel compiled from m, the run, sim and info see the new value at once,
   without recompiling. MECHC_EARG for an unknown name or a value that is
   not finite; MECHC_ENOTAVAIL when the file has no design parameters. */
mechc_status mechc_set_design(mechc_model *m, const char *name, double value);
/* All np at once; p NULL: back to the file's values. */
mechc_status mechc_set_design_vector(mechc_model *m, const double *p);

/* ---- compiling ---- */

/* Compiles m's kernels with an engine: "jit" (default when NULL: generated
   C compiled in memory by libtcc, about 2 ms for a four-bar; one jit
   compile at a time in the process), "aot" (generated C built by $CC,
   default cc, -O2, cached in $XDG_CACHE_HOME/mechc or ~/.cache/mechc) or
   "generic" (formulas interpreted, nothing compiled). NULL with diag filled:
   MECHC_EARG for an unknown engine, MECHC_ECOMPILE when it cannot compile. */
mechc_kernels *mechc_compile(mechc_model *m, const char *engine, mechc_diag *diag);
void mechc_kernels_free(mechc_kernels *k);

/* What mechc_compile_with can change; mechc_compile_defaults() gives
   mechc_compile's. */
typedef struct mechc_compile_options {
    int aot_fresh;          /* aot: compile even when the cache holds the library
                               (to time the compiler, as `mechc bench` does); 0 */
    int batch;              /* aot: the unit also holds the batch kernels (gen
                               --batch, built with the machine's vector
                               extensions), which the *_batch calls use; 1 */
} mechc_compile_options;

mechc_compile_options mechc_compile_defaults(void);
/* mechc_compile with options (NULL: the defaults). */
mechc_kernels *mechc_compile_with(mechc_model *m, const char *engine,
                                  const mechc_compile_options *o, mechc_diag *diag);
/* "jit", "aot" or "generic". */
const char *mechc_kernels_engine(const mechc_kernels *k);
/* Wall time of the emission plus the compilation (generic: its set-up), s. */
double mechc_kernels_compile_seconds(const mechc_kernels *k);
/* The model the kernels were compiled from. */
mechc_model *mechc_kernels_model(const mechc_kernels *k);
/* The generated C source (jit, aot; NULL for generic), alive with k. */
const char *mechc_kernels_source(const mechc_kernels *k);

/* ---- kernels at one state: q (nq), qd (nq), t ----
   Each returns MECHC_OK, or MECHC_EARG for a NULL array, MECHC_ENOTAVAIL
   for what the model lacks. */

mechc_status mechc_phi(mechc_kernels *k, const double *q, double t, double *phi /* nh */);
/* Phi_q of every row (velocity-level rows: their coefficients A), dense. */
mechc_status mechc_jacobian(mechc_kernels *k, const double *q, double t,
                            double *jac /* nr x nq */);
/* The Jacobian's nonzeros: their count, their pattern (row and column
   indices, nnz each, the order of mechc_jacobian_values), their values. */
int mechc_jacobian_nz(const mechc_kernels *k);
mechc_status mechc_jacobian_pattern(const mechc_kernels *k, int *rows /* nnz */,
                                    int *cols /* nnz */);
mechc_status mechc_jacobian_values(mechc_kernels *k, const double *q, double t,
                                   double *vals /* nnz */);
/* Right side of Phi_q qd = nu. */
mechc_status mechc_nu(mechc_kernels *k, const double *q, double t, double *nu /* nr */);
/* Right side of Phi_q qdd = gamma. */
mechc_status mechc_gamma(mechc_kernels *k, const double *q, const double *qd, double t,
                         double *gamma /* nr */);
/* phi, jac, nu and gamma in one call (a NULL output is skipped). */
mechc_status mechc_all(mechc_kernels *k, const double *q, const double *qd, double t,
                       double *phi /* nh */, double *jac /* nr x nq */, double *nu /* nr */,
                       double *gamma /* nr */);
/* Dynamics, M(q) qdd + Phi_q^T lambda = Q(q, qd, t): MECHC_ENOTAVAIL without masses. */
mechc_status mechc_mass(mechc_kernels *k, const double *q, double *M /* nq x nq */);
mechc_status mechc_force(mechc_kernels *k, const double *q, const double *qd, double t,
                         double *Q /* nq */);
/* M, Q, Phi_q and gamma at once (a NULL output is skipped). */
mechc_status mechc_eom(mechc_kernels *k, const double *q, const double *qd, double t,
                       double *M /* nq x nq */, double *Q /* nq */, double *jac /* nr x nq */,
                       double *gamma /* nr */);
/* dPhi/dp at the current design: MECHC_ENOTAVAIL when np == 0. */
mechc_status mechc_phi_p(mechc_kernels *k, const double *q, double t,
                         double *phi_p /* nh x np */);
/* dPhi/dp's structural nonzeros, as the Jacobian's: their count (0 when
   np == 0), pattern (rows and parameter indices) and values. */
int mechc_phi_p_nz(const mechc_kernels *k);
mechc_status mechc_phi_p_pattern(const mechc_kernels *k, int *rows /* pnnz */,
                                 int *params /* pnnz */);
mechc_status mechc_phi_p_values(mechc_kernels *k, const double *q, double t,
                                double *vals /* pnnz */);
/* The sensitivities of a state of the motion (q, qd, qdd at t, as a run
   gives them) to the design parameters, what `run --sens` writes:
   variable-major, [i * np + j] = d(variable i)/d(p_j); q_p, qd_p, qdd_p
   nq x np, y_p, yd_p, ydd_p (the outputs'; may be NULL) nout x np.
   MECHC_ENOTAVAIL without design parameters, with velocity-level rows or
   without as many rows as coordinates; MECHC_EANALYSIS where Phi_q is
   singular. */
mechc_status mechc_sensitivities(mechc_kernels *k, const double *q, const double *qd,
                                 const double *qdd, double t, double *q_p, double *qd_p,
                                 double *qdd_p, double *y_p, double *yd_p, double *ydd_p);
/* The `output` statements' values, velocities and accelerations; yd, ydd
   (and qd, qdd with them) may be NULL. */
mechc_status mechc_outputs(mechc_kernels *k, const double *q, const double *qd,
                           const double *qdd, double t, double *y /* nout */,
                           double *yd /* nout */, double *ydd /* nout */);

/* ---- kernels over n states at once ----
   q and qd are n x nq (state i in row i), the outputs n times the single
   call's size, state i's block at i * size. t holds nt values: nt == 1,
   one time for every state, or nt == n, one each (MECHC_EARG otherwise);
   t NULL with nt 0: t = 0 for every state. n == 0 does nothing. The
   results are those of the single calls, state by state. */

mechc_status mechc_phi_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                             size_t nt, double *phi /* n x nh */);
mechc_status mechc_jacobian_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                                  size_t nt, double *jac /* n x nr x nq */);
mechc_status mechc_nu_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                            size_t nt, double *nu /* n x nr */);
mechc_status mechc_gamma_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                               const double *t, size_t nt, double *gamma /* n x nr */);
/* A NULL output is skipped, as in mechc_all. */
mechc_status mechc_all_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                             const double *t, size_t nt, double *phi /* n x nh */,
                             double *jac /* n x nr x nq */, double *nu /* n x nr */,
                             double *gamma /* n x nr */);
mechc_status mechc_mass_batch(mechc_kernels *k, size_t n, const double *q,
                              double *M /* n x nq x nq */);
mechc_status mechc_force_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                               const double *t, size_t nt, double *Q /* n x nq */);
/* The outputs' values at n states (qd, qdd, yd, ydd may be NULL as in
   mechc_outputs). */
mechc_status mechc_outputs_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                                 const double *qdd, const double *t, size_t nt,
                                 double *y /* n x nout */, double *yd /* n x nout */,
                                 double *ydd /* n x nout */);

/* ---- analyses ----
   A run or a simulation returns a result handle holding every state
   (mechc_result_*; the arrays live as long as the result), or NULL with
   diag filled when it could not start (MECHC_ENOTRUNNABLE, MECHC_EARG).
   When it fails part-way the result is returned all the same, with the
   states before the failure, mechc_result_status MECHC_EANALYSIS and the
   message (also copied into diag). A callback, when given, sees each
   state as soon as it is computed as well. */

/* One state: q, qd, qdd (nq each), lambda (nr; NULL for a kinematic run). */
typedef void (*mechc_state_fn)(void *ctx, double t, const double *q, const double *qd,
                               const double *qdd, const double *lambda);

/* Kinematic analysis (mechc run): assembly at t0 from the file's initial
   values, then steps equal intervals to t1 (steps + 1 states; steps 0:
   t0 alone). The defaults are the command's. */
typedef struct mechc_run_options {
    double t0, t1;          /* 0, 1 */
    int steps;              /* >= 0; 100 */
    double tol;             /* Newton's tolerance on |Phi| and |dq|; 1e-8 */
    int max_iter;           /* Newton iterations per step; 25 */
    int forces;             /* 1: inverse dynamics too (lambda; needs masses); 0 */
    mechc_state_fn on_state;/* NULL: none */
    void *ctx;              /* passed to on_state */
} mechc_run_options;

mechc_run_options mechc_run_defaults(void);
mechc_result *mechc_run(mechc_kernels *k, const mechc_run_options *o, mechc_diag *diag);

/* What `mechc run`'s options tune beyond mechc_run_options (mechc_run_with);
   mechc_run_tuning_defaults() gives the command's defaults. */
typedef struct mechc_run_tuning {
    const char *linear;     /* "auto" (NULL), "dense" or "sparse" (KLU; jit and aot) */
    int max_substeps;       /* a step that seems to leave its branch is redone in
                               2, 4, 8 ... substeps, at most this many; 64 */
    int assembly_max_iter;  /* minimum-norm Newton iterations per attempt at t0
                               when Newton cannot start from q0; 100 */
    double pivot_tol;       /* singular when an LU pivot <= this times the
                               largest Jacobian entry; 1e-12 */
    double cond_warn;       /* a note where the condition estimate exceeds it;
                               1e10 (0: no estimate) */
    const char *ode;        /* velocity-level rows' integrator: "rk8pd" (NULL) or "rkf45" */
    double ode_tol;         /* its error per step; 1e-10 */
    long long max_dense_entries; /* most rows x coordinates of a dense Jacobian the
                               run forms; 0 (default): no limit */
    int keep_states;        /* 1 (default): the result keeps every state; 0: only
                               on_state sees them (mechc_result_states counts
                               them, the arrays are NULL): a run of any length */
    FILE *notes;            /* NULL (default): no notes; else where the run's
                               notes and warnings go, "FILE: warning: ..." lines
                               (the only printing the library does) */
} mechc_run_tuning;

mechc_run_tuning mechc_run_tuning_defaults(void);
/* mechc_run with tuning (NULL: the defaults, mechc_run itself). */
mechc_result *mechc_run_with(mechc_kernels *k, const mechc_run_options *o,
                             const mechc_run_tuning *tuning, mechc_diag *diag);

/* Forward dynamics (mechc sim) of a file with masses. */
typedef struct mechc_sim_options {
    double t0, t1;          /* 0, 1 */
    int steps;              /* output intervals, >= 1; 100 */
    double rtol, atol;      /* error per step; 5e-11, 5e-11 */
    const char *method;     /* "rk8pd" (NULL), "rkf45", "rk4imp", "msbdf" */
    const double *qd0;      /* initial velocities (nq), NULL: zero */
    mechc_state_fn on_state;
    void *ctx;
} mechc_sim_options;

mechc_sim_options mechc_sim_defaults(void);
mechc_result *mechc_sim(mechc_kernels *k, const mechc_sim_options *o, mechc_diag *diag);

/* What `mechc sim`'s options tune beyond mechc_sim_options (mechc_sim_with);
   mechc_sim_tuning_defaults() gives the command's defaults. */
typedef struct mechc_sim_tuning {
    const char *linear;     /* "auto" (NULL: sparse above 100 coordinates), "dense"
                               or "sparse" (KLU; jit and aot) */
    long max_steps;         /* integrator steps allowed in all; 10000000 */
    int interpolate;        /* 1: step across the output times, the states there
                               interpolated (degree 8 Hermite); 0 (default): a
                               step ends at each */
    double baumgarte_alpha, baumgarte_beta; /* gamma - 2 alpha Phi' - beta^2 Phi,
                               1/s, >= 0; 0, 0: off (projection alone) */
    int keep_states;        /* 1 (default) or 0, as mechc_run_tuning's */
    FILE *notes;            /* NULL (default), or where the simulation's notes go */
    void (*on_step)(void *ctx, double t);   /* after every accepted integrator
                               step, with its end (progress); NULL: none */
    void *step_ctx;         /* passed to on_step */
} mechc_sim_tuning;

mechc_sim_tuning mechc_sim_tuning_defaults(void);
/* mechc_sim with tuning (NULL: the defaults, mechc_sim itself). */
mechc_result *mechc_sim_with(mechc_kernels *k, const mechc_sim_options *o,
                             const mechc_sim_tuning *tuning, mechc_diag *diag);

/* What a result holds. states: how many; time (states values); q, qd, qdd
   (states x nq each); y, yd, ydd, the outputs (states x nout each; NULL
   when nout == 0); lambda (states x nr; NULL for a run without forces). */
int mechc_result_states(const mechc_result *r);
const double *mechc_result_time(const mechc_result *r);
const double *mechc_result_q(const mechc_result *r);
const double *mechc_result_qd(const mechc_result *r);
const double *mechc_result_qdd(const mechc_result *r);
const double *mechc_result_y(const mechc_result *r);
const double *mechc_result_yd(const mechc_result *r);
const double *mechc_result_ydd(const mechc_result *r);
const double *mechc_result_lambda(const mechc_result *r);
/* MECHC_OK, or MECHC_EANALYSIS with the message ("t = 0.25: ..."). */
mechc_status mechc_result_status(const mechc_result *r);
const char *mechc_result_message(const mechc_result *r);
/* The time that failed (MECHC_EANALYSIS), NaN otherwise. */
double mechc_result_t_fail(const mechc_result *r);
void mechc_result_free(mechc_result *r);

/* Structure at t (mechc info's analysis): counts and ranks as a struct. */
typedef struct mechc_info {
    int nq, nh, nv, nr;
    int dof;                /* nq - nh - nv */
    int mobility;           /* nq - rows without drivers */
    int assembled;          /* 1: Newton converged at t (or nothing to assemble) */
    int rank;               /* rank of the holonomic rows at the assembled q; -1 not computed */
    int nredundant;         /* holonomic rows depending on the rows before them */
    int rank_all;           /* rank of every row (velocity rows included) */
    int dof_rank;           /* nq - rank - nv: degrees of freedom by rank */
    int mobility_rank;      /* nq - rank of the rows without drivers */
    int generic_rank;       /* largest rank of the undriven rows over samples; -1 */
    double sigma_max, sigma_min, cond;
    char singularity[16];   /* "none", "position", "drivers", "permanent", "unknown" */
} mechc_info;

/* Fills info; redundant (nr values, may be NULL) gets 1 for a redundant
   row, 0 otherwise; q (nq, may be NULL) the assembled configuration.
   MECHC_OK also when assembly failed (info->assembled 0). */
mechc_status mechc_info_at(mechc_model *m, double t, mechc_info *info, int *redundant,
                           double *q, mechc_diag *diag);
/* What `mechc info --json` prints, as a string to free with mechc_free;
   NULL with diag filled on failure. */
char *mechc_info_json(mechc_model *m, mechc_diag *diag);

/* What `mechc info`'s options set (mechc_info_with); mechc_info_defaults()
   gives the command's defaults. */
typedef struct mechc_info_options {
    double t;               /* the time of the analysis; 0 */
    double rank_tol;        /* singular values above it count toward the rank;
                               negative (default): max(rows, coords) eps sigma_max */
    int samples;            /* random states of the integrability check, >= 1; 8 */
    const char *linear;     /* "auto" (NULL: sparse QR above 100 coordinates),
                               "dense" (SVD) or "sparse" (SuiteSparseQR) */
    double max_dense;       /* rows x coordinates up to which a dense SVD is
                               allowed; 500000 ("dense" beyond it: MECHC_EARG) */
    int follow;             /* 1: at the state the motion reaches at t, assembled at
                               t = 0 and followed (holonomic rows only) */
    const double *q;        /* NULL, or a state (nq) analysed as it is, at t */
} mechc_info_options;

/* The whole structure report (mechc info's), kept in a handle. */
typedef struct mechc_info_report mechc_info_report;

mechc_info_options mechc_info_defaults(void);
/* The analysis with options (NULL: the defaults); NULL with diag filled
   (MECHC_EARG) when the options cannot be used. A report whose assembly
   did not converge is returned: its summary says assembled 0. */
mechc_info_report *mechc_info_with(mechc_model *m, const mechc_info_options *o,
                                   mechc_diag *diag);
/* The report's counts and ranks, as mechc_info_at gives them (redundant
   and q may be NULL). */
mechc_status mechc_info_report_summary(const mechc_info_report *r, mechc_info *info,
                                       int *redundant, double *q);
/* The report as `mechc info --json` prints it; free with mechc_free. */
char *mechc_info_report_json(const mechc_info_report *r);
void mechc_info_report_free(mechc_info_report *r);

#ifdef __cplusplus
}
#endif

#endif
