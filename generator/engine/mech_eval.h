/* mech_eval.h - Phi and the Jacobian of a loaded mechanism, interpreted from its graph (the evaluator of info). */
#ifndef MECHC_MECH_EVAL_H
#define MECHC_MECH_EVAL_H

#include "../../runtime/mechrt.h"
#include "../diff/kinematics.h"
#include "../eval/interp.h"

/* One program of the graph interpreter (generator/eval/interp.h) for every
   row and entry: no code generation. */
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

/* me as kernels with phi and jac (nu, gamma, all, mass and force NULL):
   what assembly and construction take from any evaluator. ctx is me. */
MechrtKernels mech_eval_kernels(MechEval *me);

#endif
