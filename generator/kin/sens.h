/* sens.h - the sensitivities of a state of the motion to the design parameters (mechc run --sens).
 *
 * Along a motion Phi(q, p, t) = 0 of a holonomic mechanism with as many
 * rows as coordinates, each design parameter p_j moves the state:
 *
 *   Phi_q q_pj   = -Phi_pj                                   (positions)
 *   Phi_q qd_pj  = -(V_q q_pj + V_pj),       V = Phi_q qd + Phi_t
 *   Phi_q qdd_pj = -(W_q q_pj + W_qd qd_pj + W_pj),  W = Phi_q qdd - gamma
 *
 * one LU of Phi_q per state serving every right-hand side: dense, or on
 * the sparse path KLU on the Jacobian's nonzeros (sens_use_sparse). The
 * partial derivatives come from the engine's sensitivity functions
 * (generated: PREFIX_phi_p, _sens_v, _sens_g, _sens_y; generic:
 * interpreted), and all design parameters are handled at once by products
 * over the partials' structural nonzeros (sens.c).
 */
#ifndef MECHC_SENS_H
#define MECHC_SENS_H

#include "../engine/engine.h"
#include "run.h"

typedef struct Sens {
    const Model *m;
    const Engine *e;
    int nq, np, nout;
    /* the results at the last sens_eval, variable-major: [i * np + j] is
       d(variable i)/d(p_j) */
    double *q_p, *qd_p, *qdd_p;     /* nq x np */
    double *y_p, *yd_p, *ydd_p;     /* nout x np: the outputs' */
    /* the rest is sens.c's: Phi_q's LU, Phi_p, the engine's partials at
       qd and qd + qdd (V's and the outputs'), gamma's, scratch */
    double *jac, *piv, *phi_p, *col, *work;    /* phi_p: on its nonzeros with klu */
    const JacEntry *p_nz;       /* Phi_p's pattern (p_nnz entries) */
    int p_nnz;
    double *v[2][2];
    double *y[2][DESIGN_Y_COUNT];
    double *g[3];
    /* the structural nonzeros of V_q, G_q and G_qd by rows: the columns
       of row r of the k-th are nz_col[p[r]] .. nz_col[p[r + 1] - 1], p =
       nz_ptr + k (nq + 1) */
    int *nz_col, *nz_ptr;
    MechrtHostSparse *klu;      /* the sparse path's factorisation, or NULL */
    const RunLu *lent;          /* the run's LU (sens_borrow_lu), or NULL ... */
    double *solve_work;         /* ... and its solves' nq x np scratch */
    bool borrowed;              /* the last factor() found it at its state */
    long borrowed_count;        /* states solved with it */
} Sens;

/* Prepares s for the motion of m through e (np > 0, no velocity-level
   rows, as many rows as coordinates; kin: m's). false with why (size
   bytes) when m is not such a mechanism. */
bool sens_init(Sens *s, Model *m, const Kinematics *kin, const Engine *e, char *why, size_t size);
void sens_free(Sens *s);
/* Factors Phi_q by KLU on the Jacobian's nonzeros jnz (the engine's)
   instead of the dense LU: the run's sparse path. false, the dense LU
   kept, when the pattern cannot be analysed. */
bool sens_use_sparse(Sens *s, const MechrtHostJacNz *jnz);
/* Solves with the run's own factorisation of Phi_q (RunOptions.lend_lu)
   at the states where it holds one: no Jacobian, no LU of sens's own
   there (the pattern LU gives lu.c's factors bit for bit). */
void sens_borrow_lu(Sens *s, const RunLu *lent);

/* The sensitivities at the state (t, q, qd, qdd) of the motion, at the
   model's design. MECHRT_OK, or the LU's status when Phi_q is singular
   there. */
MechrtStatus sens_eval(Sens *s, double t, const double *q, const double *qd, const double *qdd);
/* The same for positions alone: q_p and y_p (what fitting positions needs). */
MechrtStatus sens_eval_positions(Sens *s, double t, const double *q);

/* The CSV names of sens's columns, in sens_columns' order: d(NAME)/d(P)
   for every coordinate and output and design parameter, then
   d(d(NAME))/d(P) (velocities), then d(dd(NAME))/d(P); count:
   3 (nq + nout) np. Strings malloc'ed, freed by the caller. */
int sens_column_count(const Sens *s);
char *sens_column_name(const Sens *s, const char *const *names, int column);
/* The last sens_eval's values in that order, into out. */
void sens_columns(const Sens *s, double *out);

#endif
