/* kinematics.h - per row: Phi, the sparse Jacobian row, nu and gamma, as graph nodes. */
#ifndef MECHC_KINEMATICS_H
#define MECHC_KINEMATICS_H

#include "../model/model.h"

typedef struct JacEntry {
    int row, col;
    NodeId value;
} JacEntry;

/* Everything the emitter and the interpreters need, row by row. */
typedef struct Kinematics {
    const Model *model;
    NodeId *phi;        /* nh: holonomic residuals */
    NodeId *nu;         /* nr */
    NodeId *gamma;      /* nr */
    JacEntry *jac;      /* nnz structural nonzeros, row-major, columns ascending */
    int nnz;
    int *row_start;     /* nr + 1: row r's entries are jac[row_start[r] .. row_start[r+1]) */
} Kinematics;

/* Differentiates every row of the model. Returns false with diag filled
   when a velocity row is not affine in der() or has no der() term left,
   or when the graph passes its node limit. Arrays live in the model's
   arena; the derivative nodes in its graph. */
bool kinematics_build(Model *model, Kinematics *kin, Diag *diag);

#endif
