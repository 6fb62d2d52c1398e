/* dag_ops.h - the operation enum and its table, generated from ops.def. */
#ifndef MECHC_DAG_OPS_H
#define MECHC_DAG_OPS_H

#include <stdbool.h>

typedef enum DagOp {
#define X(e, spell, arity, cd, cf) OP_##e,
#include "ops.def"
#undef X
    OP_COUNT
} DagOp;

typedef struct DagOpInfo {
    const char *spelling;
    int arity;
    const char *c_double, *c_float;
} DagOpInfo;

extern const DagOpInfo dag_op_info[OP_COUNT];

static inline bool dag_op_is_function(DagOp op) { return op >= OP_SIN; }

/* Function lookup by its .mech spelling: the op, or -1. */
int dag_function_from_name(const char *word, int len);

#endif
