/* diff.c - derivative rules for every graph operation, one memoised recursion for all variables.
 *
 * A "variable" is a code: q_j, qd_j, t, or one of the two whole-expression
 * transforms (total time derivative, velocities set to zero). The leaf
 * rules differ per code; the chain rule is shared. Results are memoised
 * in one table, so a subexpression shared by many rows is differentiated
 * once, and derivative nodes reuse the original nodes (d sqrt(u) =
 * du / (2 sqrt(u)) refers to the sqrt node itself).
 */
#include "diff.h"

#include <math.h>

enum { CODE_T = -1, CODE_TOTAL = -2, CODE_NOVEL = -3 };

/* Variable codes: q_j is j, qd_j is nq + j, design parameter p_j is
   2 nq + j, the rest are negative. */
void differ_init(Differ *differ, Dag *dag, int nq)
{
    differ->dag = dag;
    differ->nq = nq;
    u64map_init(&differ->memo);
}

void differ_free(Differ *differ)
{
    u64map_free(&differ->memo);
}

static uint64_t memo_key(NodeId e, int code)
{
    return (uint64_t)(uint32_t)e << 32 | (uint32_t)code;
}

static NodeId leaf_rule(const Differ *df, const DagNode *n, NodeId e, int code)
{
    Dag *d = df->dag;
    switch ((DagOp)n->op) {
    case OP_CONST:
        return code == CODE_NOVEL ? e : DAG_ZERO;
    case OP_VAR:
        if (code == CODE_TOTAL)
            return dag_vard(d, n->a);
        if (code == CODE_NOVEL)
            return e;
        return code == n->a ? DAG_ONE : DAG_ZERO;
    case OP_VARD:
        if (code == CODE_NOVEL || code == CODE_TOTAL)   /* qd = 0; q'' terms dropped */
            return DAG_ZERO;
        return code == df->nq + n->a ? DAG_ONE : DAG_ZERO;
    case OP_TIME:
        if (code == CODE_NOVEL)
            return e;
        return code == CODE_T || code == CODE_TOTAL ? DAG_ONE : DAG_ZERO;
    case OP_PARAM:      /* constant in time and in every state */
        if (code == CODE_NOVEL)
            return e;
        return code == 2 * df->nq + n->a ? DAG_ONE : DAG_ZERO;
    default:
        return DAG_NONE;
    }
}

static NodeId derive(Differ *df, NodeId e, int code);

/* a'b + ab'. Node ids follow the order nodes are made in and name the
   generated C's temporaries, and C leaves the order of evaluating a call's
   arguments unspecified: where a rule makes two nodes for one call, they
   are made in statements of their own (the right one first, the order gcc
   used), so the output does not depend on the compiler that built mechc. */
static NodeId product_rule(Dag *d, NodeId a, NodeId da, NodeId b, NodeId db)
{
    NodeId adb = dag_mul(d, a, db);
    NodeId dab = dag_mul(d, da, b);
    return dag_add(d, dab, adb);
}

/* The chain rule: d f(a, b) = f_a da + f_b db, written per operation. */
static NodeId chain_rule(Differ *df, NodeId e, int code)
{
    Dag *d = df->dag;
    const DagNode n = *dag_node(d, e);      /* copy: the node array may move */
    DagOp op = (DagOp)n.op;
    NodeId a = n.a, b = n.b;
    NodeId da = derive(df, a, code);
    NodeId db = dag_op_info[op].arity == 2 ? derive(df, b, code) : DAG_ZERO;
    if (da == DAG_ZERO && db == DAG_ZERO)
        return DAG_ZERO;
    switch (op) {
    case OP_NEG: return dag_neg(d, da);
    case OP_ADD: return dag_add(d, da, db);
    case OP_SUB: return dag_sub(d, da, db);
    /* (ab)' = a'b + ab' (ab' made first: see product_rule) */
    case OP_MUL: return product_rule(d, a, da, b, db);
    /* (a/b)' = (a' - (a/b) b') / b */
    case OP_DIV: return dag_div(d, dag_sub(d, da, dag_mul(d, e, db)), b);
    case OP_POW: {
        double c;
        if (dag_is_const(d, b, &c))      /* (a^c)' = c a^(c-1) a' */
            return dag_mul(d, dag_mul(d, b, dag_pow(d, a, dag_const(d, c - 1.0))), da);
        /* (a^b)' = a^b (b' log a + b a'/a) */
        NodeId ratio = dag_div(d, dag_mul(d, b, da), a);
        NodeId logs = dag_mul(d, db, dag_call(d, OP_LOG, a, DAG_NONE));
        return dag_mul(d, e, dag_add(d, logs, ratio));
    }
    case OP_SIN:  return dag_mul(d, dag_call(d, OP_COS, a, DAG_NONE), da);
    case OP_COS:  return dag_neg(d, dag_mul(d, dag_call(d, OP_SIN, a, DAG_NONE), da));
    /* tan' = 1 + tan^2 */
    case OP_TAN:  return dag_mul(d, dag_add(d, DAG_ONE, dag_mul(d, e, e)), da);
    /* asin' = 1/sqrt(1 - a^2), acos' = -asin' */
    case OP_ASIN:
    case OP_ACOS: {
        NodeId r = dag_div(d, da, dag_call(d, OP_SQRT, dag_sub(d, DAG_ONE, dag_mul(d, a, a)), DAG_NONE));
        return op == OP_ASIN ? r : dag_neg(d, r);
    }
    case OP_ATAN: return dag_div(d, da, dag_add(d, DAG_ONE, dag_mul(d, a, a)));
    /* atan2(y, x)' = (x y' - y x') / (x^2 + y^2) */
    case OP_ATAN2: {
        NodeId bb = dag_mul(d, b, b), aa = dag_mul(d, a, a);
        NodeId r2 = dag_add(d, aa, bb);
        NodeId adb = dag_mul(d, a, db), bda = dag_mul(d, b, da);
        return dag_div(d, dag_sub(d, bda, adb), r2);
    }
    /* sqrt' = a' / (2 sqrt a) */
    case OP_SQRT: return dag_div(d, dag_mul(d, dag_const(d, 0.5), da), e);
    case OP_EXP:  return dag_mul(d, e, da);
    case OP_LOG:  return dag_div(d, da, a);
    case OP_SINH: return dag_mul(d, dag_call(d, OP_COSH, a, DAG_NONE), da);
    case OP_COSH: return dag_mul(d, dag_call(d, OP_SINH, a, DAG_NONE), da);
    /* tanh' = 1 - tanh^2 */
    case OP_TANH: return dag_mul(d, dag_sub(d, DAG_ONE, dag_mul(d, e, e)), da);
    case OP_CONST: case OP_VAR: case OP_VARD: case OP_TIME: case OP_PARAM: case OP_COUNT:
        break;
    }
    return DAG_ZERO;
}

/* Rebuilds e with substituted operands (for CODE_NOVEL). */
static NodeId substitute(Differ *df, NodeId e)
{
    Dag *d = df->dag;
    const DagNode n = *dag_node(d, e);
    NodeId a = derive(df, n.a, CODE_NOVEL);
    NodeId b = dag_op_info[n.op].arity == 2 ? derive(df, n.b, CODE_NOVEL) : DAG_NONE;
    if (a == n.a && (b == DAG_NONE || b == n.b))
        return e;
    return dag_apply(d, (DagOp)n.op, a, b);
}

static NodeId derive(Differ *df, NodeId e, int code)
{
    NodeId r = leaf_rule(df, dag_node(df->dag, e), e, code);
    if (r != DAG_NONE)
        return r;
    uint64_t key = memo_key(e, code);
    if (u64map_get(&df->memo, key, &r))
        return r;
    r = code == CODE_NOVEL ? substitute(df, e) : chain_rule(df, e, code);
    u64map_put(&df->memo, key, r);
    return r;
}

NodeId diff_by_q(Differ *df, NodeId e, int j) { return derive(df, e, j); }
NodeId diff_by_qd(Differ *df, NodeId e, int j) { return derive(df, e, df->nq + j); }
NodeId diff_by_p(Differ *df, NodeId e, int j) { return derive(df, e, 2 * df->nq + j); }
NodeId diff_by_t(Differ *df, NodeId e) { return derive(df, e, CODE_T); }
NodeId diff_total(Differ *df, NodeId e) { return derive(df, e, CODE_TOTAL); }
NodeId diff_without_velocities(Differ *df, NodeId e) { return derive(df, e, CODE_NOVEL); }
