/* mechrt_host.h - host-side companions of the runtime: GSL numerics and output formats.
 *
 * What a firmware build does not need and a host tool does: minimum-norm
 * Gauss-Newton projection onto Phi = 0 when there are fewer holonomic rows
 * than coordinates, adaptive integration of the positions of mechanisms with
 * velocity-level rows (GSL's odeiv2), the dense SVD behind both the
 * projection and `info` (ranks, pseudo-inverse, the singular direction of a
 * Jacobian for error messages), the sparse LU of large Jacobians (KLU), and
 * the CSV and JSON writers of `mechc run`.
 * Compiled into the tool only (double reals, C11, links GSL and KLU); the
 * freestanding core in runtime/ stays free of all of it.
 *
 * Ownership follows the core: a MechrtHost holds every workspace for one
 * mechanism size, allocated once by mechrt_host_new, so the per-step calls
 * allocate nothing (GSL's SVD and odeiv2 steppers work in place).
 */
#ifndef MECHRT_HOST_H
#define MECHRT_HOST_H

#include <stdbool.h>
#include <stdio.h>

#include "../mechrt.h"
#include "format_real.h"

/* ---- Integrator options ------------------------------------------------ */

typedef enum MechrtOdeMethod {
    MECHRT_ODE_RK8PD,   /* Runge-Kutta Prince-Dormand (8, 9): few steps at tight tolerances */
    MECHRT_ODE_RKF45    /* Runge-Kutta-Fehlberg (4, 5): cheaper steps, more of them */
} MechrtOdeMethod;

typedef struct MechrtOdeOptions {
    MechrtOdeMethod method;  /* default MECHRT_ODE_RK8PD */
    /* Local error allowed per step, absolute and relative at once:
       |err_i| <= tol (1 + |q_i|) (coordinate units). default 1e-10 */
    double tol;
} MechrtOdeOptions;

MechrtOdeOptions mechrt_ode_default_options(void);
/* "rk8pd" / "rkf45"; NULL for an unknown name */
/* Parses a method name; false when unknown. */
bool mechrt_ode_method_from_name(const char *name, MechrtOdeMethod *out);

/* Counters of the host-side work, accumulated over calls. */
typedef struct MechrtHostStats {
    long ode_steps;          /* accepted integrator steps */
    long ode_rejected;       /* integrator steps retried with a smaller h */
    long rhs_calls;          /* velocity solves for the integrator */
    long projections;        /* calls of mechrt_host_project */
    long project_iterations; /* Gauss-Newton iterations in them */
} MechrtHostStats;

/* ---- The host object (host.c) ------------------------------------------ */

typedef struct MechrtHost MechrtHost;
/* Defined below (the sparse Jacobian). */
typedef struct MechrtHostJacNz MechrtHostJacNz;
typedef struct MechrtHostSparse MechrtHostSparse;

/* Workspaces for the mechanism of k (which must outlive the host).
   NULL when out of memory or k is malformed. */
MechrtHost *mechrt_host_new(const MechrtKernels *k);
void mechrt_host_free(MechrtHost *h);
/* The same on the sparse Jacobian of pattern jnz (whose arrays must outlive
   the host): velocity solves by KLU, the projection's minimum-norm steps
   by SuiteSparseQR; nothing of size nr x nq or nq x nq is allocated.
   Needs nh + nv == nq. */
MechrtHost *mechrt_host_new_sparse(const MechrtKernels *k, const MechrtHostJacNz *jnz);
/* Only mechrt_host_project on the sparse Jacobian of pattern jnz
   (SuiteSparseQR's minimum-norm steps, nh <= nq rows, any nv): for
   assembling a mechanism with free degrees of freedom, which the sparse
   host's square velocity solve cannot take. Velocity calls and
   mechrt_host_integrate return MECHRT_EINVAL or MECHRT_ENOTSQUARE. */
MechrtHost *mechrt_host_new_projector(const MechrtKernels *k, const MechrtHostJacNz *jnz);
/* Velocity and acceleration at (q, t) (mechrt_velocity_acceleration, dense
   or on the sparse host's KLU). */
MechrtStatus mechrt_host_velocity_acceleration(MechrtHost *h, const MechrtOptions *o,
                                               const double *q, double t, double *qd,
                                               double *qdd, MechrtReport *report);
/* The sparse host's factorisation (NULL for a dense host): the failing
   pivot of its last ESING, its counts. */
MechrtHostSparse *mechrt_host_sparse_of(MechrtHost *h);

const MechrtHostStats *mechrt_host_stats(const MechrtHost *h);

/* Gauss-Newton on the nh holonomic rows, any nh <= nq (nh == 0: nothing
 * to do), each step the minimum-norm solution of Phi_q dq = -Phi from the SVD
 * of Phi_q (singular values below pivot_tol * sigma_max dropped, so
 * consistent redundant rows are harmless). Stops like Newton (newton.c):
 * ||Phi||_inf <= tol_phi and ||dq||_inf <= tol_dq, at most max_iter
 * iterations. q is updated in place; report (may be NULL) gets iterations,
 * residual, step and worst_row. MECHRT_EMAXITER, MECHRT_ENOTFINITE: q and
 * the residual are those of the iterate with the smallest residual. */
MechrtStatus mechrt_host_project(MechrtHost *h, const MechrtOptions *o, double *q, double t,
                                 MechrtReport *report);

/* Integrates the positions of a mechanism with velocity-level rows,
 *   q' = qd(q, t),  [Phi_q; A](q, t) qd = nu(q, t)   (square: nh + nv == nq),
 * from *t to t_end with GSL's adaptive embedded Runge-Kutta pair (odeiv2
 * evolve + standard step control), projecting q back onto Phi = 0 with
 * mechrt_host_project after every accepted step (the drift of the holonomic
 * rows, which the velocity equations alone only keep constant).
 * *hstep is the step size to try first and, on return, the one to use next.
 * On success *t == t_end exactly. On failure *t is the time of the failing
 * velocity solve or projection, and mechrt_host_failure() gives the state;
 * q holds the last accepted state. */
MechrtStatus mechrt_host_integrate(MechrtHost *h, const MechrtOptions *o,
                                   const MechrtOdeOptions *oo, double *q, double *t,
                                   double t_end, double *hstep, MechrtReport *report);

/* After a failed mechrt_host_integrate: the state and time where it failed. */
const double *mechrt_host_failure(const MechrtHost *h, double *t);

/* ---- Dense SVD and pseudo-inverse (svd.c) ------------------------------ */

/* Workspace for matrices up to max_m x max_n, allocated once (GSL's rule:
   no allocation per call). */
typedef struct MechrtSvd MechrtSvd;

/* NULL when out of memory. */
MechrtSvd *mechrt_svd_new(int max_m, int max_n);
void mechrt_svd_free(MechrtSvd *w);

/* Outcome of one decomposition. sigma points into the workspace and stays
   valid until its next use. */
typedef struct MechrtSvdResult {
    int m, n;               /* the matrix decomposed */
    int k;                  /* min(m, n): number of singular values */
    const double *sigma;    /* k singular values, descending */
    double sigma_max;       /* sigma[0], 0 when k == 0 */
    double sigma_min;       /* sigma[k-1], 0 when k == 0 */
    double cond;            /* sigma_max / sigma_min; INFINITY when sigma_min == 0 */
    double tol;             /* the rank tolerance used */
    int rank;               /* singular values > tol */
} MechrtSvdResult;

/* The default rank tolerance max(m, n) * DBL_EPSILON * sigma_max. */
double mechrt_svd_default_tol(int m, int n, double sigma_max);

/* Singular values of the m x n row-major matrix a (leading dimension lda)
   by GSL's Golub-Reinsch SVD (of a^T when m < n), and the rank: singular
   values above the absolute tolerance tol (tol < 0: the default). Returns
   false (out->rank = -1) when a holds NaN or Inf, is larger than the
   workspace or the decomposition fails. a is not modified. */
bool mechrt_svd(MechrtSvd *w, const double *a, int m, int n, int lda, double tol,
                MechrtSvdResult *out);

/* Sets the tolerance of the last decomposition (the singular values
   mechrt_svd_pinv_solve keeps: those above tol); returns the rank. */
int mechrt_svd_truncate(MechrtSvd *w, double tol);

/* x = pinv(A) b with the factors of the last decomposition, singular values
   at or below its tolerance dropped: the minimum-norm least-squares
   solution. b has m entries, x has n. */
void mechrt_svd_pinv_solve(const MechrtSvd *w, const double *b, double *x);

/* Component j (< n) of the l-th (< rank) orthonormal basis vector of the
   row space of the last matrix decomposed (its right singular vectors). */
double mechrt_svd_row_basis(const MechrtSvd *w, int j, int l);

/* The direction in which the last matrix decomposed is closest to
   singular: row_w[m] and col_w[n] receive |u_i| and |v_j| of the singular
   vectors of the smallest singular value (the rows and the coordinates of
   the dependency, each of unit 2-norm). Nothing when k == 0. */
void mechrt_svd_smallest(const MechrtSvd *w, double *row_w, double *col_w);

/* The same for one matrix, without a workspace: mechrt_svd_smallest of the
 * m x n row-major matrix a. Returns sigma_min / sigma_max (0 for an exactly
 * singular or zero matrix), or -1 when m or n is < 1, a holds NaN or Inf,
 * or memory runs out. Allocates: for error paths. */
double mechrt_host_singular_direction(int m, int n, const double *a, double *row_w,
                                      double *col_w);

/* ---- Sparse Jacobian (sparse_klu.c: KLU; sparse_step.c: a time step) ---
   For large mechanisms: the Jacobian's structural nonzeros only, factored
   by SuiteSparse's KLU (symbolic analysis once, numeric refactorisation
   per call). Nothing of size nr x nq is allocated. */

/* The Jacobian's nonzeros as generated code gives them (spec section 4:
   PREFIX_jac_nz with its fixed pattern PREFIX_jac_row, PREFIX_jac_col),
   the runtime's MechrtJacNz: entry e sits at (jac.row[e], jac.col[e]);
   jac.jac_nz writes the jac.nnz values in that order. The arrays must
   outlive every user. With what the host adds: */
struct MechrtHostJacNz {
    MechrtJacNz jac;
    /* Phi, the nnz values, nu and gamma in one call, sharing their work
       (PREFIX_all_nz), passed jac.ctx; may be NULL */
    void (*all_nz)(void *ctx, const double *q, const double *qd, double t, double *phi,
                   double *vals, double *nu, double *gamma);
    /* The pattern's unrolled LU (PREFIX_lu_factor, PREFIX_lu_solve,
       PREFIX_step: factors in at most nq*nq reals); lu.factor and
       lu.solve NULL without */
    MechrtLuGen lu;
};

/* The n x n matrix of pattern jnz (copied; its arrays are kept by
   pointer), analysed once. NULL when out of memory, or an index is out of
   range or repeated. */
MechrtHostSparse *mechrt_host_sparse_new(int n, const MechrtHostJacNz *jnz);
void mechrt_host_sparse_free(MechrtHostSparse *s);
int mechrt_host_sparse_nnz(const MechrtHostSparse *s);
/* The nnz values, in the pattern's order, that the next factorisation
   takes: jac_nz's output; mechrt_host_sparse_eval fills them at (q, t). */
double *mechrt_host_sparse_values(MechrtHostSparse *s);
void mechrt_host_sparse_eval(MechrtHostSparse *s, const double *q, double t);
/* The same values with Phi, nu and gamma (at qd) from one all_nz call;
   false, and nothing done, when the pattern came without all_nz. */
bool mechrt_host_sparse_eval_all(MechrtHostSparse *s, const double *q, const double *qd,
                                 double t, double *phi, double *nu, double *gamma);
/* LU of the values with partial pivoting. MECHRT_ESING when a pivot
   |u_kk| <= pivot_tol * max|a_ij| (the dense test of lu.c), naming it in
   mechrt_host_sparse_singular; MECHRT_ENOTFINITE for NaN or Inf (its row
   named); MECHRT_EINVAL when out of memory. */
MechrtStatus mechrt_host_sparse_factor(MechrtHostSparse *s, double pivot_tol);
/* The same for values the caller knows finite, amax their largest
   magnitude: no pass over them but the copy (the augmented matrix holds
   Phi_q twice, and its caller checked the kernels' output already). */
MechrtStatus mechrt_host_sparse_factor_known(MechrtHostSparse *s, double pivot_tol, double amax);
/* b = A^-1 b with the last factorisation; MECHRT_ENOTFINITE when b or the
   solution is not finite, MECHRT_EINVAL without a factorisation. */
MechrtStatus mechrt_host_sparse_solve(MechrtHostSparse *s, double *b);
/* max|u_kk| / min|u_kk| of the last factorisation (the condition screen). */
double mechrt_host_sparse_spread(const MechrtHostSparse *s);
/* 1-norm condition estimate of the matrix factored last (KLU's Hager-Higham
   estimate, as lu.c's); INFINITY without a factorisation. */
double mechrt_host_sparse_condest(MechrtHostSparse *s);
/* After MECHRT_ESING: the original row and column (coordinate) of the
   failing pivot; after MECHRT_ENOTFINITE: the row, column -1; else -1. */
void mechrt_host_sparse_singular(const MechrtHostSparse *s, int *row, int *col);
/* Fresh factorisations (with pivot search) and refactorisations done. */
void mechrt_host_sparse_counts(const MechrtHostSparse *s, long *fresh, long *refactored);
/* Drops the factors: the next factorisation searches its pivots afresh. */
void mechrt_host_sparse_refresh(MechrtHostSparse *s);

/* ---- Sparse augmented matrix (sparse_kkt.c) -------------------------------
   [W Phi_A^T; Phi_A 0] for forward dynamics (W = M) and minimum-norm
   projections (W = I) of large mechanisms: M's and Phi_q's nonzeros, the
   rows left out as identity rows (their unknown y_i = b_i), KLU. */

/* M's nonzeros as generated code gives them (PREFIX_mass_nz with its
   pattern PREFIX_mass_row, PREFIX_mass_col; both triangles). */
typedef struct MechrtHostMassNz {
    int nnz;
    const int *row, *col;
    void *ctx;
    void (*mass_nz)(void *ctx, const double *q, double *vals);
} MechrtHostMassNz;

typedef enum MechrtKktWeight { MECHRT_KKT_MASS, MECHRT_KKT_IDENTITY } MechrtKktWeight;

typedef struct MechrtHostKkt MechrtHostKkt;

/* For nq coordinates and nr rows with the two patterns (kept by pointer
   only while this call runs); NULL when out of memory or a pattern is bad. */
MechrtHostKkt *mechrt_host_kkt_new(int nq, int nr, const MechrtHostJacNz *jnz,
                                   const MechrtHostMassNz *mnz);
void mechrt_host_kkt_free(MechrtHostKkt *s);
/* Where the caller writes Phi_q's nonzeros (jac_nz, all_nz) and M's
   (mass_nz) for the next factorisation. */
double *mechrt_host_kkt_jac(MechrtHostKkt *s);
double *mechrt_host_kkt_mass(MechrtHostKkt *s);
/* Factors the matrix of weight w keeping row r where r < rows and
   active[r] (active NULL: every one of the first rows); the statuses of
   mechrt_host_sparse_factor. */
MechrtStatus mechrt_host_kkt_factor(MechrtHostKkt *s, MechrtKktWeight w,
                                    const unsigned char *active, int rows, double pivot_tol);
/* The rank screen: [I Phi_q^T; Phi_q 0] with the first `rows` rows
   factored with a fresh pivot search, into factors of its own. Partial
   pivoting shows a rank drop near as a small pivot; a refactorisation's
   old order need not (a drop of many ranks can spread over many moderate
   pivots). *spread = max|u_kk| / min|u_kk|; the statuses of
   mechrt_host_kkt_factor. */
MechrtStatus mechrt_host_kkt_screen(MechrtHostKkt *s, int rows, double pivot_tol,
                                    double *spread);
/* x (nq + nr) <- the solution for right side x, with the last factors of w. */
MechrtStatus mechrt_host_kkt_solve(MechrtHostKkt *s, MechrtKktWeight w, double *x);
/* The same with one step of iterative refinement (a residual over the
   nonzeros and a second solve); work: 2 (nq + nr) doubles. */
MechrtStatus mechrt_host_kkt_solve_refined(MechrtHostKkt *s, MechrtKktWeight w, double *x,
                                           double *work);
/* max|u_kk| / min|u_kk| of w's last factors (INFINITY without). */
double mechrt_host_kkt_spread(const MechrtHostKkt *s, MechrtKktWeight w);
/* Factorisations with pivot search and refactorisations, both weights and
   the screen. */
void mechrt_host_kkt_counts(const MechrtHostKkt *s, long *fresh, long *refactored);

/* Workspace length, in doubles, of mechrt_host_sparse_step. */
#define MECHRT_HOST_SPARSE_WORK_LEN(nq) (4u * (size_t)(nq))

/* mechrt_step (runtime/analysis.c) on the sparse Jacobian s of k's
   mechanism: predictor, Newton with one factorisation per iteration, then
   velocity and acceleration from one factorisation at the converged q.
   Same statuses and report; report->sing_index is the failing pivot's
   column (its row: mechrt_host_sparse_singular). */
MechrtStatus mechrt_host_sparse_step(MechrtHostSparse *s, const MechrtKernels *k,
                                     const MechrtOptions *opts, double *q, double *qd,
                                     double *qdd, double t, double h, double *work, size_t lwork,
                                     MechrtReport *report);

/* mechrt_velocity_acceleration (runtime/analysis.c) on the sparse
   Jacobian s: one evaluation at (q, t), one factorisation with the same
   pivot test and condition screen, qd from nu and, when qdd is not NULL,
   qdd from gamma at the new qd (qdd NULL: mechrt_velocity). work: 3 nq
   doubles. */
MechrtStatus mechrt_host_sparse_velocity(MechrtHostSparse *s, const MechrtKernels *k,
                                         const MechrtOptions *opts, const double *q, double t,
                                         double *qd, double *qdd, double *work,
                                         MechrtReport *report);

/* The minimum-norm Gauss-Newton step of the projection over the nh
   holonomic rows of pattern jnz (sparse_qr.c: SuiteSparseQR of Phi_q^T;
   its velocity-level rows, row >= nh, are left out). NULL when out of
   memory or an index is out of range. */
typedef struct MechrtHostMinNorm MechrtHostMinNorm;
MechrtHostMinNorm *mechrt_host_minnorm_new(int nh, int nq, const MechrtHostJacNz *jnz);
void mechrt_host_minnorm_free(MechrtHostMinNorm *m);
/* dq = -pinv(Phi_q) phi at (q, t), the rows whose remaining norm is at most
   pivot_tol times the largest row norm dropped (redundant rows).
   MECHRT_ESING when Phi_q = 0, MECHRT_ENOTFINITE for NaN or Inf,
   MECHRT_EINVAL when out of memory. */
MechrtStatus mechrt_host_minnorm_step(MechrtHostMinNorm *m, const double *q, double t,
                                      const double *phi, double pivot_tol, double *dq);

/* ---- Output (output.c; numbers: format_real.c) ---------------------------- */


/* CSV (RFC 4180, no quoting needed: coordinate names are identifiers with
   dots). Header: t, the coordinate names, d(NAME) for each velocity,
   dd(NAME) for each acceleration; one row per time, 1 + 3 nq columns. */
void mechrt_csv_header(FILE *out, int nq, const char *const *names);
void mechrt_csv_row(FILE *out, int nq, double t, const double *q, const double *qd,
                    const double *qdd, int digits);
/* The same with nw velocity-only columns (a spatial body's angular
   velocity NAME.wx NAME.wy NAME.wz) after the d(NAME) columns. */
void mechrt_csv_header_omega(FILE *out, int nq, const char *const *names, int nw,
                             const char *const *wnames);
void mechrt_csv_row_omega(FILE *out, int nq, double t, const double *q, const double *qd,
                          const double *qdd, int nw, const double *w, int digits);
/* The same with nx further columns at the end of each row (run --forces:
   lambda(ROW) and effort(DRIVER)); nx = 0 is the _omega form. */
void mechrt_csv_header_extra(FILE *out, int nq, const char *const *names, int nw,
                             const char *const *wnames, int nx, const char *const *xnames);
void mechrt_csv_row_extra(FILE *out, int nq, double t, const double *q, const double *qd,
                          const double *qdd, int nw, const double *w, int nx, const double *x,
                          int digits);

/* The rows of a run kept for JSON (which cannot be streamed key by key):
   each row is t, q[nq], qd[nq], qdd[nq]. */
typedef struct MechrtTrace {
    int nq;
    size_t rows, cap;
    double *data;
    int nw;                     /* velocity-only columns per row (0: none) */
    const char *const *wnames;  /* their names (not owned) */
    double *wdata;              /* rows x nw */
} MechrtTrace;

void mechrt_trace_init(MechrtTrace *tr, int nq);
/* false when out of memory (the row is not kept) */
bool mechrt_trace_push(MechrtTrace *tr, double t, const double *q, const double *qd,
                       const double *qdd);
void mechrt_trace_free(MechrtTrace *tr);
/* Keeps nw velocity-only values per row too (before the first push);
   JSON writes them as "omega_names" and "omega", after the outputs. */
void mechrt_trace_set_omega(MechrtTrace *tr, int nw, const char *const *wnames);
bool mechrt_trace_push_omega(MechrtTrace *tr, double t, const double *q, const double *qd,
                             const double *qdd, const double *w);

/* A JSON string literal, quotes included (RFC 8259 section 7): a quote
   or backslash gets a backslash before it, a control byte or DEL is
   written as \u00XX (so none reaches a terminal), every other byte (UTF-8)
   passes through. mechc's one JSON escaper: the CLI's JSON uses it too. */
void mechrt_json_string(FILE *out, const char *s);

/* {"coords": [...], "t": [...], "q": [[...]...], "qd": [...], "qdd": [...],
    "ok": true|false, "error": {"t": T, "message": "..."}} - error only when
   error_message is not NULL. Non-finite numbers are null. */
void mechrt_json_write(FILE *out, const MechrtTrace *tr, const char *const *names, int digits,
                       const char *error_message, double error_t);

/* The same for a trace whose first ncoords columns are coordinates and the
   rest reported values (mechc's `output` statements): those go under
   "outputs" (their names), "y", "yd" and "ydd", after "qdd". */
void mechrt_json_write_outputs(FILE *out, const MechrtTrace *tr, int ncoords,
                               const char *const *names, int digits,
                               const char *error_message, double error_t);

/* The multipliers of dynamics kept beside a trace, one set per trace row:
   lambda (rows x nr, the rows named rows) and, when nd > 0, the efforts
   of the nd drivers (rows x nd, named drivers); and when nx > 0 other
   columns (rows x nx, named xnames) under the keys xnames_key and x_key
   (mechc run --sens: "sens_columns", "sens"). */
typedef struct MechrtJsonLambda {
    int nr;
    const char *const *rows;
    const double *lambda;
    int nd;
    const char *const *drivers;
    const double *efforts;
    int nx;
    const char *const *xnames;
    const double *x;
    const char *xnames_key, *x_key;
} MechrtJsonLambda;

/* mechrt_json_write_outputs, then (lam not NULL) "rows" and "lambda" (when
   nr > 0) and, with drivers, "drivers" and "efforts", and the other
   columns, after "ok" and "error". */
void mechrt_json_write_lambda(FILE *out, const MechrtTrace *tr, int ncoords,
                              const char *const *names, int digits, const char *error_message,
                              double error_t, const MechrtJsonLambda *lam);

#endif
