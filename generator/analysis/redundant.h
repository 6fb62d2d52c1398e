/* redundant.h - more holonomic rows than coordinates: the redundant rows found once, the square system of the others, the dropped rows checked. */
#ifndef MECHC_ANALYSIS_REDUNDANT_H
#define MECHC_ANALYSIS_REDUNDANT_H

#include "../../runtime/mechrt.h"
#include "../../runtime/host/mechrt_host.h"
#include "../model/model.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* The state a kernel's values belong to: (q, t), and qd for gamma. */
typedef struct RedundantAt {
    bool valid;
    double t;
    double *q, *qd;             /* nq each */
} RedundantAt;

/* A mechanism with nh > nq holonomic rows (no velocity-level rows) as the
   square system of its independent rows: `view` is the model with those
   rows alone (the same names, joints and positions; everything else
   shared with the model), k and jnz the kernels of those rows, computed
   from the model's kernels (the generated LU, written for the whole
   pattern, is not used). The dropped rows are checked at every state
   (redundant_check): a consistent redundancy keeps them at 0. */
typedef struct Redundant {
    const Model *m;
    const MechrtKernels *full;
    const MechrtHostJacNz *full_jnz;
    int nq, nr, nkeep, ndrop;
    int *keep, *drop;           /* row indices of the model, ascending */
    double *phi, *jac, *nu, *gamma, *vals;     /* the model's rows, scratch */
    /* where each was last evaluated (the kernels below keep them), so
       that redundant_check takes them from the step that just ended */
    RedundantAt at_phi, at_jac, at_vals, at_nu, at_gamma;
    int *nz_keep;               /* jnz entry e: the model's entry nz_keep[e] */
    int *nz_row, *nz_col;
    int ndrop_nz, *nz_drop;     /* the model's entries in the dropped rows */
    double *acc, *at_block;     /* redundant_check's sums (2 nr); the stamps' states */
    Model view;
    MechrtKernels k;
    MechrtHostJacNz jnz;
    double *lambda;             /* nr: redundant_expand's */
} Redundant;

/* Beyond this many Jacobian entries the redundant rows are not looked for
   (the SVD at t0 is dense): info's limit (AnalysisOptions.max_dense). */
#define REDUNDANT_MAX_ENTRIES 5e5

/* m has more holonomic rows than coordinates, no velocity-level rows and
   a Jacobian small enough for the SVD: run, sim and check leave its
   redundant rows out. */
bool redundant_applies(const Model *m);

/* The rows to drop (nr flags into red; their count returned): the model
   assembled at t0 from its file's values on all its rows (minimum-norm
   Newton with restarts; the file's values, constructed, when they do
   not close),
   then `info`'s definition at that configuration: a row is redundant
   when it depends on the rows before it (svd_redundant_rows, the SVD's
   default tolerance). -1 on NaN or Inf. */
int redundant_find(const Model *m, const MechrtKernels *k, double t0, bool *red);

/* Opens r on the rows not flagged in red; jnz may be NULL (then r->jnz is
   not usable). */
void redundant_open(Redundant *r, const Model *m, const MechrtKernels *k,
                    const MechrtHostJacNz *jnz, const bool *red);
void redundant_close(Redundant *r);

/* redundant_find, then redundant_open on the other rows, said once in
   notes (redundant_note); false with why (size bytes) when the Jacobian
   is not finite there or, with driven (run, which needs one row per
   coordinate), the rows kept do not drive every degree of freedom. */
bool redundant_start(Redundant *r, const Model *m, const MechrtKernels *k,
                     const MechrtHostJacNz *jnz, double t0, bool driven, FILE *notes,
                     char *why, size_t size);

/* The rows dropped, "O4.z (joint O4), O4.f (joint O4)" (info's wording),
   appended to msg. */
void redundant_names(const Redundant *r, char *msg, size_t size);

/* The note said once on stderr: "FILE: note: 3 redundant rows: ...; solved
   on the other N rows, the redundant ones checked at every state". */
void redundant_note(FILE *notes, const Redundant *r);

/* The note of inverse and forward dynamics, once: "FILE: note: the
   reactions of the redundant rows and of the rows they repeat are not
   unique: reported as the independent rows' (0 on ...)" - the basis
   solution, the kept rows' multipliers with the dropped rows' at 0. */
void redundant_note_reactions(FILE *notes, const Redundant *r);

/* The dropped rows at the state (q; qd and qdd may be NULL): the largest
   violation relative to its tolerance (at most 1: satisfied), the row in
   *row and the level ("position", "velocity", "acceleration") in *level.
   Position: |Phi_i| against REDUNDANT_PHI_SHARE tol_phi; velocity and
   acceleration: |Phi_q,i x - rhs_i| against REDUNDANT_RATE_SHARE times
   the row's scale sum_j |Phi_q,ij x_j| + |rhs_i| (and 1e-12). */
double redundant_check(Redundant *r, const double *q, const double *qd, const double *qdd,
                       double t, double tol_phi, int *row, const char **level);
#define REDUNDANT_PHI_SHARE 100.0
#define REDUNDANT_RATE_SHARE 1e-6

/* When redundant_check returned above 1: "t = T: the redundant rows are
   not consistent with the others: row NAME (joint J) has residual R at
   the LEVEL level (tolerance TOL), so no configuration satisfies every
   row; the redundant rows: ..." into msg. */
void redundant_explain(Redundant *r, const double *q, const double *qd, const double *qdd,
                       double t, double tol_phi, char *msg, size_t size);

/* The multipliers of the kept rows (nkeep) spread over the model's rows
   (r->lambda, nr, returned): the dropped rows' reactions are 0 (the basis
   solution). */
const double *redundant_expand(Redundant *r, const double *kept);

#endif
