/* kinematics.h - per row: Phi, the sparse Jacobian row, nu and gamma, as graph nodes. */
#ifndef MECHC_KINEMATICS_H
#define MECHC_KINEMATICS_H

#include "../model/model.h"

typedef struct JacEntry {
    int row, col;
    NodeId value;
} JacEntry;

/* The equations of motion M(q) qdd + Phi_q^T lambda = Q(q, qd, t) of a
   model with masses (generator/diff/dynamics.c, doc/dynamics.md). */
typedef struct Dynamics {
    bool present;       /* the model has masses; nothing below otherwise */
    JacEntry *mass;     /* M's structural nonzeros, row-major, both triangles
                           (M is symmetric: (i, j) and (j, i) share a node) */
    int nnz;
    NodeId *force;      /* Q: nq values */
    NodeId *velocity;   /* Q's velocity terms alone, -sum m p_q^T (pdot_q qd)
                           - J theta_q^T (thetadot_q qd): nq values (check) */
} Dynamics;

/* Everything the emitter and the interpreters need, row by row. */
typedef struct Kinematics {
    const Model *model;
    NodeId *phi;        /* nh: holonomic residuals */
    NodeId *nu;         /* nr */
    NodeId *gamma;      /* nr */
    JacEntry *jac;      /* nnz structural nonzeros, row-major, columns ascending */
    int nnz;
    int *row_start;     /* nr + 1: row r's entries are jac[row_start[r] .. row_start[r+1]) */
    Dynamics dyn;       /* M and Q, when the model has masses */
    NodeId *phi_p;      /* nh x np, row-major: dPhi/dp, the design
                           parameters' columns (NULL without them) */
} Kinematics;

/* Differentiates every row of the model. Returns false with diag filled
   when a velocity row is not affine in der() or has no der() term left,
   or when the graph passes its node limit. Arrays live in the model's
   arena; the derivative nodes in its graph. */
bool kinematics_build(Model *model, Kinematics *kin, Diag *diag);

/* M and Q of a model with masses, by the mass-element formulas (every
   derivative symbolic). False with diag filled past the node limit. */
bool dynamics_build(Model *model, Dynamics *dyn, Diag *diag);

#endif
