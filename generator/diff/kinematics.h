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

/* The partial derivatives the sensitivities of a motion to the design
   parameters are made of (generator/diff/design.c, kin/sens.h), dense and
   row-major, for a file with design parameters: V = D(Phi) = Phi_q qd +
   Phi_t and gamma by q, qd and p (nh rows), and each output f, D f and
   D(D f) by q, qd and p (nout rows). */
enum { DESIGN_Y_COUNT = 8 };
typedef struct DesignKin {
    NodeId *v_q, *v_p;              /* nh x nq, nh x np */
    NodeId *g_q, *g_qd, *g_p;       /* nh x nq, nh x nq, nh x np */
    /* f_q, f_p, Df_q, Df_qd, Df_p, DDf_q, DDf_qd, DDf_p: nout x (nq or np) */
    NodeId *y[DESIGN_Y_COUNT];
    /* Phi_p's structural nonzeros (nodes other than DAG_ZERO), row-major,
       columns ascending: PREFIX_phi_p_nz's pattern */
    JacEntry *p_nz;
    NodeId *p_nz_values;    /* their nodes, at least one (DAG_ZERO when none) */
    int p_nnz;
} DesignKin;

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
    DesignKin design;   /* what sensitivities need, with design parameters */
} Kinematics;

/* Differentiates every row of the model. Returns false with diag filled
   when a velocity row is not affine in der() or has no der() term left,
   or when the graph passes its node limit. Arrays live in the model's
   arena; the derivative nodes in its graph. */
bool kinematics_build(Model *model, Kinematics *kin, Diag *diag);

/* M and Q of a model with masses, by the mass-element formulas (every
   derivative symbolic). False with diag filled past the node limit. */
bool dynamics_build(Model *model, Dynamics *dyn, Diag *diag);

/* Phi_p and kin->design for a model with design parameters (design.c).
   False with diag filled past the node limit. */
bool design_build(Model *model, Kinematics *kin, Diag *diag);
/* Whether entry k of y[] is by p (np columns), else by q or qd (nq). */
static inline bool design_y_by_p(int k) { return k == 1 || k == 4 || k == 7; }

/* The generated functions of a design file (functions.def's EMIT_DESIGN
   rows, in order) and the arrays each writes: from[i] holds count[i] nodes
   (phi_p; v_q, v_p; g_q, g_qd, g_p; y[0 .. 7]; Phi_p's nonzeros, at
   least one slot). Returns how many. */
typedef enum DesignFn {
    DESIGN_PHI_P, DESIGN_V, DESIGN_G, DESIGN_Y, DESIGN_PHI_P_NZ, DESIGN_FN_COUNT
} DesignFn;
int design_arrays(const Kinematics *kin, DesignFn fn, const NodeId *from[DESIGN_Y_COUNT],
                  size_t count[DESIGN_Y_COUNT]);

#endif
