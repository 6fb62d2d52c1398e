/* dag.h - the expression graph: hash-consed nodes with integer ids, simplified at construction. */
#ifndef MECHC_DAG_H
#define MECHC_DAG_H

#include "../base/diag.h"
#include "dag_ops.h"

#include <stdbool.h>
#include <stdint.h>

/* Nodes are referred to by index. A node's operands always have smaller
   ids, so id order is a topological order: every pass is a loop over ids,
   and identical input yields identical ids and byte-identical output. */
typedef int32_t NodeId;

enum { DAG_ZERO = 0, DAG_ONE = 1, DAG_NONE = -1 };

typedef struct DagNode {
    uint8_t op;         /* DagOp */
    int32_t a, b;       /* operands; VAR/VARD: coordinate index in a */
    double value;       /* CONST */
} DagNode;

typedef struct Dag {
    DagNode *nodes;
    int32_t count, cap;
    int32_t *table;         /* open addressing: node id or -1 */
    uint32_t table_cap;     /* power of two */
    int32_t max_nodes;      /* limit on count */
    int32_t where;          /* offset of the statement being built, for the
                               limit's error; -1: none */
    int32_t where_expr;     /* offset of the sub-expression being lowered (a
                               number, an operator, a call), where a constant
                               out of range is reported; -1: at where */
    const char *what;       /* what a builder is combining ("the weight m g"),
                               named with a constant out of range; NULL: none */
    /* Sticky, like ferror: set when a node past max_nodes is asked for.
       From then on every new node comes back as DAG_ZERO (existing ones are
       still found), which every rule folds away: a phase goes on to its end
       on harmless nodes (long loops test the flag to stop early) and checks
       once with dag_check_limit. No dag_* call ever jumps out. */
    bool overflow;
    int32_t overflow_where; /* where at the first overflow */
    /* Sticky too: set when a constant that is not finite is asked for
       (the numbers a builder combines itself past the range of a double:
       an offset turned by an orientation, an axis normalised, m |com|^2,
       m g; it would print as inf or nan, which C does not read), or when
       constant operands fold to one (0/0 or 1e308*10 in a force: folding
       keeps only finite results, so the C would compute it at every
       call). dag_check_finite reports it once, at its statement. */
    bool nonfinite;
    int32_t nonfinite_where; /* where_expr, else where, at the first one */
    bool nonfinite_expr;     /* ... and it was where_expr */
    const char *nonfinite_what; /* what at the first one */
    double nonfinite_value;
    /* The finite constants a float cannot hold (HUGE_VALF or 0 as a
       float), with where they were made: gen --real float refuses the
       ones its functions use (dag_check_float). */
    struct DagWide *wide;
    int32_t nwide, wide_cap;
    /* Design parameters (`design NAME = value`): OP_PARAM leaf a reads
       param_values[a], the design every evaluation on the host sees (the
       interpreter, the compiled units through engine.c); the model owns
       both arrays. np 0: a file without design parameters. */
    int np;
    double *param_values;
    const char *const *param_names;
} Dag;

typedef struct DagWide {
    NodeId id;
    int32_t where;
    bool expr;              /* where is a sub-expression's (where_expr) */
    const char *what;       /* Dag.what when it was made */
} DagWide;

void dag_init(Dag *dag, int32_t max_nodes);
void dag_free(Dag *dag);

/* True when no node was refused. Otherwise records the node-limit error in
   diag (at the statement that was being built, if any) and returns false. */
bool dag_check_limit(const Dag *dag, Diag *diag);
/* Constants out of range (range.c). dag_check_finite: true when every
   constant asked for was finite; otherwise records in diag which (inf or
   NaN) and why, at the statement it came from. dag_check_float: true when
   no constant the roots reach overflows a float or vanishes in one;
   otherwise the same about the first one. dag_range_note: dag_const's
   record of a new constant node; dag_range_note_nonfinite: of a value
   that constant operands fold to but no node can hold (0/0, 1e308*10 in
   a force: left unfolded, the C would compute it at every call). */
bool dag_check_finite(const Dag *dag, Diag *diag);
bool dag_check_float(const Dag *dag, const NodeId *roots, int nroots, Diag *diag);
void dag_range_note(Dag *dag, NodeId id);
void dag_range_note_nonfinite(Dag *dag, double v);
/* dag_const of a value a builder combined, named (what: "the weight m g")
   if it is out of range. */
NodeId dag_const_named(Dag *dag, double value, const char *what);

static inline const DagNode *dag_node(const Dag *dag, NodeId id) { return &dag->nodes[id]; }
static inline DagOp dag_op(const Dag *dag, NodeId id) { return (DagOp)dag->nodes[id].op; }
/* A constant, coordinate, velocity or time: nothing to compute. */
static inline bool dag_is_leaf(const Dag *dag, NodeId id)
{
    DagOp op = dag_op(dag, id);
    return op == OP_CONST || op == OP_VAR || op == OP_VARD || op == OP_TIME || op == OP_PARAM;
}
bool dag_is_const(const Dag *dag, NodeId id, double *value);
bool dag_is_zero(const Dag *dag, NodeId id);

/* Leaves. */
NodeId dag_const(Dag *dag, double value);
NodeId dag_var(Dag *dag, int index);     /* q[index] */
NodeId dag_vard(Dag *dag, int index);    /* qd[index] */
NodeId dag_time(Dag *dag);
NodeId dag_param(Dag *dag, int index);   /* design parameter p[index] */

/* Operators, simplified as they are built: constants folded when the
   result is finite, 0/1 identities, x - x, double negation, numeric
   coefficients merged (2*(3*x) = 6*x, x + x = 2*x, 3*x - x = 2*x),
   operands of + and * put in canonical order, coefficients positive
   ((-c)*x is built as -(c*x), so c*x is one node for both signs and the
   sign goes into the parent's + or -). */
NodeId dag_neg(Dag *dag, NodeId a);
NodeId dag_add(Dag *dag, NodeId a, NodeId b);
NodeId dag_sub(Dag *dag, NodeId a, NodeId b);
NodeId dag_mul(Dag *dag, NodeId a, NodeId b);
NodeId dag_div(Dag *dag, NodeId a, NodeId b);
NodeId dag_pow(Dag *dag, NodeId a, NodeId b);   /* small integer powers become products */
NodeId dag_call(Dag *dag, DagOp fn, NodeId a, NodeId b);  /* b = DAG_NONE for unary */
/* The node (op, a, b) when it exists, else DAG_NONE; never creates one. */
NodeId dag_find(const Dag *dag, DagOp op, NodeId a, NodeId b);

/* Any operator or function by op (what the AST lowering uses). */
NodeId dag_apply(Dag *dag, DagOp op, NodeId a, NodeId b);

/* Evaluates one operator on numbers: the single definition of what every
   op means, shared by constant folding and the interpreters. */
double dag_op_eval(DagOp op, double a, double b);

/* Marks in mark[] (size dag->count, caller-owned, set to stamp) every node
   reachable from the roots; returns how many were newly marked. Iterative:
   deep graphs do not recurse. stack must hold dag->count ids. */
int dag_mark_reachable(const Dag *dag, const NodeId *roots, int nroots,
                       uint32_t *mark, uint32_t stamp, NodeId *stack);

/* Prints a node as an infix expression (for dumps, messages and the
   integrability law); coord_names may be NULL (prints q[i]). */
struct StrBuf;
void dag_format(const Dag *dag, NodeId id, const char *const *coord_names, struct StrBuf *out);
/* The same as a malloc'd string (numbers print as the shortest text that
   reads back: 0.3, not 0.29999999999999999). */
char *dag_format_string(const Dag *dag, NodeId id, const char *const *coord_names);

#endif
