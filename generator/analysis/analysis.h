/* analysis.h - what `mechc info` computes: singular values and rank, redundant
   rows, minimum-norm assembly, integrability of velocity rows, mobility.

   Host-side only (GSL). Layers, usable separately:
     svd.c           redundant rows by incremental rank, on the dense SVD of
                     runtime/host/svd.c (singular values, numerical rank,
                     condition number, pseudo-inverse solve), which `run`
                     shares for its projection and its failure messages.
     assemble.c      Phi and Phi_q through the graph interpreter (eval/interp.h)
                     and minimum-norm Newton on any subset of the holonomic rows.
     integrability.c Frobenius test of one velocity-level row and the search
                     for its position law.
     involutive.c    the velocity rows together with the holonomic rows.
     sparse.c        rank, redundant rows and the assembly step beyond the
                     dense limit (row-wise Givens QR).
     mobility.c      the whole `info` report for a loaded mechanism.
*/
#ifndef MECHC_ANALYSIS_H
#define MECHC_ANALYSIS_H

#include "../../runtime/host/mechrt_host.h"
#include "../eval/interp.h"
#include "../pipeline/pipeline.h"

#include <stdbool.h>

/* ---- options --------------------------------------------------------- */

/* Tunable constants of the analysis; fill with analysis_default_options(). */
typedef struct AnalysisOptions {
    /* Assembly converged when ||Phi||_inf <= tol_phi (row units) and the last
       step ||dq||_inf <= tol_dq (coordinate units). default 1e-10, 1e-10 */
    double tol_phi, tol_dq;
    /* Newton iterations allowed; a singular root converges only linearly,
       so this is generous. default 60 */
    int max_iter;
    /* Give up early when the residual's 2-norm has not fallen by 1 % in
       this many iterations (a stationary point that is no solution, e.g.
       a guess symmetric about a line the mechanism cannot lie on); 0:
       never. default 0 */
    int stall_iter;
    /* Absolute tolerance on singular values: sigma > rank_tol counts toward
       the rank. Negative: the default max(m, n) * eps * sigma_max (the rule
       of LAPACK's and Matlab's rank). default -1 */
    double rank_tol;
    /* Random states for the numerical integrability check and the law
       verification. default 8 */
    int samples;
    /* Seed of the (deterministic) sample generator. default 20240605 */
    unsigned seed;
    /* Assembled configurations sampled to find the generic rank of the
       undriven mechanism (telling a singular position from a permanent
       redundancy); 0 skips. default 3 */
    int generic_samples;
    /* Dense SVD limit: rank and condition are computed only when
       rows * coordinates <= max_dense (the cost is cubic: about 1 s for
       600 x 600, 20 s for 1200 x 1200 with GSL). default 5e5 */
    double max_dense;
} AnalysisOptions;

AnalysisOptions analysis_default_options(void);

/* ---- dense SVD (runtime/host/svd.c, and svd.c here) ----------------------- */

/* The dense SVD is the host runtime's (MechrtSvd, mechrt_svd,
   mechrt_svd_pinv_solve, mechrt_svd_row_basis: runtime/host/mechrt_host.h),
   the same one `run` projects with. svd_work_new allocates its workspace
   and aborts when memory runs out, like xmalloc. */
MechrtSvd *svd_work_new(int max_m, int max_n);

/* Redundant rows: row i (i >= first) is redundant when the rank of rows
   0..i equals the rank of rows 0..i-1, every rank taken with the absolute
   tolerance tol (singular values only grow when rows are added, so the
   deficiency k - rank(k) is monotone and its steps are found by bisection,
   O(d log m) decompositions for d redundant rows). rank: the rank of all m
   rows with tol when already known (saves one decomposition), else -1.
   Sets redundant[i] for i in [first, m); returns their count, -1 on NaN or
   Inf. Uses (and clobbers) the workspace. */
int svd_redundant_rows(MechrtSvd *w, const double *a, int m, int n, int lda, double tol,
                       int first, int rank, bool *redundant);

/* ---- large sparse Jacobians (sparse.c) ------------------------------------ */

/* Rank and redundant rows beyond the dense limit: rows are added one at a
   time to a row-wise Givens QR; a row eliminated down to entries at or
   below tol is redundant. fill_max bounds the stored R entries. */
typedef struct SparseRank SparseRank;

SparseRank *sparse_rank_new(int nq, double tol, size_t fill_max);
void sparse_rank_free(SparseRank *s);
/* Adds a row given by its nonzeros: 1 it raised the rank, 0 it is
   redundant, -1 NaN or Inf, -2 the fill limit was reached. */
int sparse_rank_add(SparseRank *s, const int *cols, const double *vals, int n);
int sparse_rank_of(const SparseRank *s);
/* Solves R^T R y = b in place with the factor of the rows added so far
   (m of them; a redundant row gets y = 0): the seminormal equations of the
   sparse minimum-norm step. */
void sparse_rank_seminormal_solve(const SparseRank *s, int m, double *b);
/* Largest singular value of the listed rows (power iteration);
   vals[e] is the value of kin->jac[e]. */
double sparse_sigma_max(const Kinematics *kin, const double *vals, const int *rows, int nrows,
                        unsigned seed);

/* ---- evaluation and assembly (assemble.c) ------------------------------ */

/* Phi and the Jacobian of a loaded mechanism, interpreted from its graph
   (generator/eval/interp.h: one program for every row and entry). */
typedef struct MechEval {
    const Kinematics *kin;
    NodeValues values;      /* roots: Phi (nh), then the Jacobian's nonzeros (kin->nnz) */
    int nq, nh, nr;
} MechEval;

void mech_eval_init(MechEval *me, const Kinematics *kin);
void mech_eval_free(MechEval *me);
/* phi: nh values (may be NULL); jac: nr x nq row-major (may be NULL). */
void mech_eval(MechEval *me, const double *q, double t, double *phi, double *jac);
/* The same with the Jacobian as its structural nonzeros: vals[e] is entry
   kin->jac[e] (row-major, kin->row_start per row). */
void mech_eval_nz(MechEval *me, const double *q, double t, double *phi, double *vals);

typedef struct AssembleResult {
    bool converged;
    int iterations;
    double residual;        /* ||Phi_rows||_inf at the returned q */
    double step;            /* ||dq||_inf of the last step, -1 if none */
    int worst_row;          /* model row with the largest |Phi|, -1 if none */
    int rank;               /* rank of the rows' Jacobian at the last step, -1 if none */
} AssembleResult;

/* Minimum-norm Newton on the holonomic rows listed in rows[] (model row
   indices < nh), at time t, from q (updated in place):
   dq = -pinv(Phi_q) Phi, with step halving when the residual grows. Works
   for fewer rows than coordinates (the step nearest to q) and for
   redundant rows (singular values at or below the rank tolerance are
   dropped). w must hold nrows x nq. */
bool analysis_assemble(MechEval *me, const int *rows, int nrows, double t, double *q,
                       const AnalysisOptions *opt, MechrtSvd *w, AssembleResult *res);

/* The same beyond the dense limit, on the first nrows holonomic rows, with
   the sparse QR of Phi_q^T (sparse.c): dq = Phi_q^T y, Phi_q Phi_q^T y = -Phi
   by the seminormal equations; rows that depend on earlier ones are left
   out of the step. */
bool analysis_assemble_sparse(MechEval *me, int nrows, double t, double *q,
                              const AnalysisOptions *opt, AssembleResult *res);

/* The same on the holonomic rows of compiled (or generic) kernels, dense:
   what run and check assemble with. res->worst_row is a kernel row. */
bool analysis_assemble_kernels(const MechrtKernels *k, double t, double *q,
                               const AnalysisOptions *opt, AssembleResult *res);

/* ---- integrability (integrability.c) ------------------------------------ */

typedef struct Integrability {
    bool integrable;        /* the verdict */
    bool symbolic;          /* proved by simplification, not by sampling */
    bool decided;           /* false: no sample state could be evaluated */
    int ncoords;            /* coordinates (t included) the form involves */
    int triples;            /* components of omega ^ d omega tested */
    int samples;            /* sample states evaluated */
    char *law;              /* "h(q, t) = const", or NULL (malloc'd) */
    char *note;             /* how the verdict was reached (malloc'd) */
} Integrability;

/* Tests the velocity-level row `row` of the model: Psi = a(q,t)^T qd + b(q,t),
   omega = a^T dq + b dt on (q, t) space, integrable iff omega ^ d omega = 0,
   i.e. for every triple i < j < k of (q, t) coordinates
     a_i (d_j a_k - d_k a_j) + a_j (d_k a_i - d_i a_k) + a_k (d_i a_j - d_j a_i) = 0.
   Symbolic first (every triple simplifies to 0: proof); otherwise sampled
   at opt->samples random states around q_center. When integrable, looks
   for h with mu omega = dh (mu = 1, then 1/a_p) by symbolic integration.
   Adds nodes to the model's graph. Returns false with diag filled only when
   the graph's node limit is passed. */
bool analysis_integrability(Model *m, int row, const double *q_center,
                            const AnalysisOptions *opt, Integrability *out, Diag *diag);
void integrability_free(Integrability *it);

/* The velocity-level rows together: the distribution D on (q, t) space
   annihilated by the rows' forms (velocity rows a^T dq + b dt, holonomic
   rows dPhi = Phi_q dq + Phi_t dt) is integrable iff it is involutive,
   i.e. d omega_k(X, Y) = 0 for X, Y in D and every velocity row k (Frobenius;
   the holonomic forms are exact). Tested numerically at the given points
   (configurations on the holonomic rows) by projecting each d omega_k onto D. */
typedef struct Involutivity {
    bool tested;            /* false: no velocity rows, or no point evaluated */
    bool involutive;
    int points;             /* points evaluated */
    char *note;             /* malloc'd */
} Involutivity;

/* rows: model rows to include (holonomic first, then velocity-level);
   points: npoints configurations (npoints x nq) with their times. */
bool analysis_involutivity(Model *m, const int *rows, int nrows, const double *points,
                           const double *times, int npoints, Involutivity *out, Diag *diag);
void involutivity_free(Involutivity *inv);

/* Formats a node as infix text with the shortest round-trip numbers
   (0.3, not 0.29999999999999999), for laws and messages. malloc'd. */
char *analysis_format(const Dag *dag, NodeId id, const char *const *coord_names);

/* ---- the info report (mobility.c) ----------------------------------------- */

typedef struct InfoRow {
    bool driver;            /* a driver row */
    bool redundant;         /* depends on the rows before it */
    Integrability integ;    /* velocity rows only */
} InfoRow;

/* What a rank deficiency of the holonomic rows at the configuration means. */
typedef enum Singularity {
    SING_NONE,          /* full row rank */
    SING_POSITION,      /* the undriven rows lose rank here only: dead-centre, toggle, branch point */
    SING_DRIVERS,       /* the undriven rows are independent, the drivers depend on them here */
    SING_PERMANENT,     /* the undriven rows have the same deficiency at nearby configurations */
    SING_UNKNOWN,       /* not classified (sampling failed, or not computed) */
} Singularity;

extern const char *const singularity_names[];   /* "none", "position", ... */

typedef struct InfoReport {
    const Model *model;
    double t;               /* the time of the analysis (0) */
    /* counts */
    int nq, nh, nv, nr;
    int nh_drivers, nv_drivers;
    int dof;                /* nq - nh - nv */
    int mobility;           /* nq - rows without drivers */
    /* assembly */
    double *q;              /* the assembled configuration (nq, malloc'd) */
    AssembleResult assembly;
    bool assembled;         /* converged, or nothing to assemble */
    /* rank of the holonomic rows at q */
    bool dense;             /* rank computed (size within max_dense) */
    double rank_tol;
    int rank;               /* holonomic rows; -1 when not computed */
    double sigma_max, sigma_min, cond;
    int nredundant;
    /* all rows (velocity rows included): instantaneous mobility */
    int rank_all;
    int nredundant_velocity;
    /* drivers removed */
    int rank_undriven;      /* rank of the non-driver rows (all levels) */
    int generic_rank;       /* max rank of the undriven holonomic rows over sampled
                               assembled configurations; -1 if not sampled */
    int rank_undriven_h;    /* rank of the undriven holonomic rows at q */
    int dof_rank;           /* nq - rank - nv: DOF with the drivers, by rank */
    int mobility_rank;      /* nq - rank_undriven: DOF without drivers, by rank */
    Singularity singularity;
    InfoRow *rows;          /* nr */
    Involutivity system;    /* the velocity rows without drivers, with the holonomic ones */
    char *verdict;          /* plain words (malloc'd) */
    char *singular;         /* about the configuration's singularity (malloc'd) */
} InfoReport;

/* Analyses a loaded mechanism at time t. Returns false with diag filled only
   on an internal limit (graph size); an assembly that does not converge is
   reported in rep->assembled. */
bool info_analyse(Mech *mech, double t, const AnalysisOptions *opt, InfoReport *rep, Diag *diag);
void info_report_free(InfoReport *rep);

/* The textbook's row count for a joint kind (what each joint removes:
   revolute 2, prismatic 2, distance 1, pointline 1, weld 3, rolling 1,
   knife 1, constraint, driver and velocity 1), independent of joints.def. */
int info_textbook_rows(JointKind kind, bool *velocity);

#endif
