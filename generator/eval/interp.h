/* interp.h - expressions of the graph compiled to an instruction list, run with forward-mode derivatives.
 *
 * The one interpreter of the expression graph. The generic evaluator
 * runs its `constraint`, `driver` and `velocity` rows and joint options
 * (length, angle, radius) with it: it never builds derivative nodes, it
 * carries derivatives along while it runs (dual numbers, and second-order
 * jets for gamma). `info` evaluates Phi, the Jacobian's entries and the
 * nodes it builds itself (integrability) with it, many roots in one
 * program (NodeValues).
 */
#ifndef MECHC_INTERP_H
#define MECHC_INTERP_H

#include "../dag/dag.h"

#include <stdbool.h>
#include <stdint.h>

/* One instruction: register k (its index in the program) = op(reg a, reg b).
   Leaves: VAR / VARD read q[a] / qd[a], TIME reads t, CONST holds value. */
typedef struct Instr {
    uint8_t op;         /* DagOp */
    int32_t a, b;       /* operand registers (unary: b = a); leaves: coordinate index */
    double value;       /* CONST */
} Instr;

/* The nodes reachable from one or more roots, in topological (node id)
   order. With one root the last instruction is the root. */
typedef struct Tape {
    Instr *code;
    int n;
    int *out;           /* register of each root (-1: the root was DAG_NONE) */
    int nout;
    int *qcols;         /* coordinates it reads (OP_VAR), ascending */
    int nqcols;
    int *qdcols;        /* velocities it reads (OP_VARD), ascending */
    int nqdcols;
    bool has_t;         /* reads t */
    const double *params;   /* OP_PARAM reads params[a]: the graph's design
                               (Dag.param_values) as it is when run */
} Tape;

/* A truncated Taylor expansion along one direction s of (q, qd, t):
   v = f, d = df/ds, dd = d2f/ds2. With the direction (qd, 0, 1) these are
   f, its total time derivative D f and D(D f) with qdd = 0. */
typedef struct Jet {
    double v, d, dd;
} Jet;

/* Where a jet pass starts: the point and the direction of each leaf. */
typedef struct Seed {
    const double *q, *qd;   /* the point; qd NULL: all velocities zero */
    double t;
    const double *dq;       /* direction of q; NULL: unit vector col_q (or none) */
    int col_q;              /* -1: none */
    int col_qd;             /* direction of qd: unit vector col_qd, -1: none */
    double dt;              /* direction of t */
    const double *dqd;      /* direction of qd as a vector (then col_qd unused); NULL: col_qd */
    const double *dp;       /* direction of the design parameters; NULL: none */
} Seed;

/* Scratch for compiling: marks the nodes of one root at a time. Sized for
   the graph as it is when interp_scratch_init is called. */
typedef struct CompileScratch {
    uint32_t *mark;
    uint32_t stamp;
    NodeId *stack, *nodes;
    int32_t *slot;
    int cap;
} CompileScratch;

void compile_scratch_init(CompileScratch *cs, const Dag *dag);
void compile_scratch_free(CompileScratch *cs);

/* Compiles the expression rooted at root into p (malloc'ed arrays). */
void tape_compile(Tape *p, const Dag *dag, NodeId root, CompileScratch *cs);
/* The same for several roots at once: one program over the union of
   their nodes (a shared node is computed once); p->out[k] is roots[k]'s
   register. */
void tape_compile_roots(Tape *p, const Dag *dag, const NodeId *roots, int nroots,
                        CompileScratch *cs);
void tape_free(Tape *p);

/* Values only: every register of reg (p->n doubles) is set; qd NULL:
   velocities zero. */
void tape_run(const Tape *p, const double *q, const double *qd, double t, double *reg);
/* The value of a one-root program. */
double tape_value(const Tape *p, const double *q, const double *qd, double t, double *reg);

/* Value and first derivative along the seed's direction (order 1), or
   also the second (order 2). reg holds p->n jets. */
Jet tape_jet(const Tape *p, const Seed *seed, int order, Jet *reg);

/* The values of chosen nodes (roots) at many states: one program, compiled
   once for the graph as it is at node_values_init, and its registers. */
typedef struct NodeValues {
    Tape tape;
    double *reg;
} NodeValues;

void node_values_init(NodeValues *nv, const Dag *dag, const NodeId *roots, int nroots);
void node_values_free(NodeValues *nv);
/* Evaluates every root at (q, qd, t); qd NULL: velocities zero. */
void node_values_run(NodeValues *nv, const double *q, const double *qd, double t);
/* The value of roots[k] at the last run (NaN for a DAG_NONE root). */
double node_values_get(const NodeValues *nv, int k);
/* One node at one state (allocates: for one-off values). */
double node_value_at(const Dag *dag, NodeId id, const double *q, const double *qd, double t);

#endif
