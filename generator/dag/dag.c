/* dag.c - hash-consed expression graph with construction-time simplification.
 *
 * Every node is unique: building (op, a, b) twice returns the same id, so a
 * subexpression shared by several rows, or by a row and its derivatives,
 * exists once and is computed once in the generated code. Simplifications
 * are local rewrites applied before the lookup; each is exact in real
 * arithmetic and folding happens only when the IEEE result is finite, so
 * no NaN or infinity is baked into the generated code.
 */
#include "dag.h"

#include "../base/arena.h"
#include "../base/strbuf.h"
#include "../../runtime/host/format_real.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const DagOpInfo dag_op_info[OP_COUNT] = {
#define X(e, spell, arity, cd, cf) {spell, arity, cd, cf},
#include "ops.def"
#undef X
};

int dag_function_from_name(const char *word, int len)
{
    for (int op = OP_SIN; op < OP_COUNT; op++) {
        const char *s = dag_op_info[op].spelling;
        if ((int)strlen(s) == len && memcmp(s, word, (size_t)len) == 0)
            return op;
    }
    return -1;
}

/* ---- table ---- */

static uint32_t hash_key(DagOp op, int32_t a, int32_t b, double value)
{
    uint64_t bits;
    memcpy(&bits, &value, sizeof bits);
    uint64_t h = 1469598103934665603ull;
    uint64_t parts[4] = {(uint64_t)op, (uint64_t)(uint32_t)a, (uint64_t)(uint32_t)b, bits};
    for (int i = 0; i < 4; i++) {
        h ^= parts[i];
        h *= 1099511628211ull;
        h ^= h >> 29;
    }
    return (uint32_t)(h ^ (h >> 32));
}

static bool same_key(const DagNode *n, DagOp op, int32_t a, int32_t b, double value)
{
    return n->op == op && n->a == a && n->b == b
           && memcmp(&n->value, &value, sizeof value) == 0;
}

static void table_grow(Dag *dag)
{
    uint32_t cap = dag->table_cap ? dag->table_cap * 2 : 1024;
    free(dag->table);
    dag->table = xmalloc(cap * sizeof *dag->table);
    memset(dag->table, 0xff, cap * sizeof *dag->table);
    dag->table_cap = cap;
    for (int32_t id = 0; id < dag->count; id++) {
        const DagNode *n = &dag->nodes[id];
        uint32_t h = hash_key((DagOp)n->op, n->a, n->b, n->value) & (cap - 1);
        while (dag->table[h] >= 0)
            h = (h + 1) & (cap - 1);
        dag->table[h] = id;
    }
}

/* The one place nodes are created: look (op, a, b, value) up, else append
   (past the limit: DAG_ZERO and the sticky overflow flag). */
static NodeId intern(Dag *dag, DagOp op, int32_t a, int32_t b, double value)
{
    if ((uint32_t)dag->count * 2 >= dag->table_cap)
        table_grow(dag);
    uint32_t mask = dag->table_cap - 1;
    uint32_t h = hash_key(op, a, b, value) & mask;
    for (; dag->table[h] >= 0; h = (h + 1) & mask) {
        if (same_key(&dag->nodes[dag->table[h]], op, a, b, value))
            return dag->table[h];
    }
    if (dag->count >= dag->max_nodes) {
        if (!dag->overflow)
            dag->overflow_where = dag->where;
        dag->overflow = true;
        return DAG_ZERO;        /* harmless: every rule folds it away */
    }
    if (dag->count == dag->cap) {
        dag->cap = dag->cap ? dag->cap * 2 : 1024;
        dag->nodes = xrealloc(dag->nodes, (size_t)dag->cap, sizeof *dag->nodes);
    }
    NodeId id = dag->count++;
    dag->nodes[id] = (DagNode){.op = (uint8_t)op, .a = a, .b = b, .value = value};
    dag->table[h] = id;
    return id;
}

NodeId dag_find(const Dag *dag, DagOp op, NodeId a, NodeId b)
{
    if (!dag->table_cap)
        return DAG_NONE;
    uint32_t mask = dag->table_cap - 1;
    for (uint32_t h = hash_key(op, a, b, 0.0) & mask; dag->table[h] >= 0; h = (h + 1) & mask)
        if (same_key(&dag->nodes[dag->table[h]], op, a, b, 0.0))
            return dag->table[h];
    return DAG_NONE;
}

void dag_init(Dag *dag, int32_t max_nodes)
{
    memset(dag, 0, sizeof *dag);
    dag->max_nodes = max_nodes > 2 ? max_nodes : 2;
    dag->where = -1;
    dag->where_expr = -1;
    dag->overflow_where = -1;
    dag->nonfinite_where = -1;
    NodeId zero = dag_const(dag, 0.0), one = dag_const(dag, 1.0);
    (void)zero, (void)one;      /* DAG_ZERO and DAG_ONE by construction */
}

bool dag_check_limit(const Dag *dag, Diag *diag)
{
    if (!dag->overflow)
        return true;
    if (dag->overflow_where >= 0)
        diag_error(diag, (SrcPos){dag->overflow_where},
                   "the expression graph passed its limit of %d nodes at this statement "
                   "(its rows or their derivatives are too large; see --max-nodes)",
                   (int)dag->max_nodes);
    else
        diag_error_nopos(diag, "the expression graph passed its limit of %d nodes "
                         "(the mechanism is too large; see --max-nodes)", (int)dag->max_nodes);
    return false;
}

void dag_free(Dag *dag)
{
    free(dag->nodes);
    free(dag->table);
    free(dag->wide);
    memset(dag, 0, sizeof *dag);
}

/* ---- leaves and queries ---- */

NodeId dag_const(Dag *dag, double value)
{
    int32_t before = dag->count;
    NodeId id = intern(dag, OP_CONST, -1, -1, value);
    if (dag->count > before)
        dag_range_note(dag, id);        /* range.c: inf, NaN, past a float's range */
    return id;
}
NodeId dag_var(Dag *dag, int index)      { return intern(dag, OP_VAR, index, -1, 0.0); }
NodeId dag_vard(Dag *dag, int index)     { return intern(dag, OP_VARD, index, -1, 0.0); }
NodeId dag_time(Dag *dag)                { return intern(dag, OP_TIME, -1, -1, 0.0); }
NodeId dag_param(Dag *dag, int index)    { return intern(dag, OP_PARAM, index, -1, 0.0); }

bool dag_is_const(const Dag *dag, NodeId id, double *value)
{
    if (dag->nodes[id].op != OP_CONST)
        return false;
    if (value)
        *value = dag->nodes[id].value;
    return true;
}

bool dag_is_zero(const Dag *dag, NodeId id)
{
    double v;
    return dag_is_const(dag, id, &v) && v == 0.0;
}

static bool is_value(const Dag *dag, NodeId id, double want)
{
    double v;
    return dag_is_const(dag, id, &v) && v == want;
}

double dag_op_eval(DagOp op, double a, double b)
{
    switch (op) {
    case OP_CONST: case OP_VAR: case OP_VARD: case OP_TIME: case OP_PARAM: return NAN;
    case OP_NEG:   return -a;
    case OP_ADD:   return a + b;
    case OP_SUB:   return a - b;
    case OP_MUL:   return a * b;
    case OP_DIV:   return a / b;
    case OP_POW:   return pow(a, b);
    case OP_SIN:   return sin(a);
    case OP_COS:   return cos(a);
    case OP_TAN:   return tan(a);
    case OP_ASIN:  return asin(a);
    case OP_ACOS:  return acos(a);
    case OP_ATAN:  return atan(a);
    case OP_ATAN2: return atan2(a, b);
    case OP_SQRT:  return sqrt(a);
    case OP_EXP:   return exp(a);
    case OP_LOG:   return log(a);
    case OP_SINH:  return sinh(a);
    case OP_COSH:  return cosh(a);
    case OP_TANH:  return tanh(a);
    case OP_COUNT: break;
    }
    return NAN;
}

/* Folds op over constant operands when the result is finite; one that is
   not is noted (range.c) and reported once the graph is complete. */
static bool try_fold(Dag *dag, DagOp op, NodeId a, NodeId b, NodeId *out)
{
    double va, vb = 0.0;
    if (!dag_is_const(dag, a, &va))
        return false;
    if (b != DAG_NONE && !dag_is_const(dag, b, &vb))
        return false;
    double r = dag_op_eval(op, va, vb);
    if (!isfinite(r)) {
        dag_range_note_nonfinite(dag, r);
        return false;
    }
    *out = r == 0.0 ? DAG_ZERO : dag_const(dag, r);     /* one zero: no -0 node */
    return true;
}

/* Splits e into coefficient * term (term = DAG_NONE for a pure constant). */
static double split_coefficient(const Dag *dag, NodeId e, NodeId *term)
{
    const DagNode *n = &dag->nodes[e];
    double c;
    if (n->op == OP_CONST) {
        *term = DAG_NONE;
        return n->value;
    }
    if (n->op == OP_MUL && dag_is_const(dag, n->a, &c)) {
        *term = n->b;
        return c;
    }
    if (n->op == OP_NEG) {      /* -(c y): coefficients are kept positive */
        const DagNode *m = &dag->nodes[n->a];
        if (m->op == OP_MUL && dag_is_const(dag, m->a, &c)) {
            *term = m->b;
            return -c;
        }
        *term = n->a;
        return -1.0;
    }
    *term = e;
    return 1.0;
}

static NodeId scale(Dag *dag, double c, NodeId term)
{
    return dag_mul(dag, dag_const(dag, c), term);
}

/* ---- operators ---- */

NodeId dag_neg(Dag *dag, NodeId a)
{
    NodeId r;
    if (dag_is_zero(dag, a))        /* -0 would be a distinct node printing as -0 */
        return DAG_ZERO;
    if (try_fold(dag, OP_NEG, a, DAG_NONE, &r))
        return r;
    const DagNode n = dag->nodes[a];     /* a copy: the array may move below */
    double c;
    if (n.op == OP_NEG)
        return n.a;
    if (n.op == OP_SUB)
        return dag_sub(dag, n.b, n.a);
    if (n.op == OP_MUL && dag_is_const(dag, n.a, &c) && c < 0.0)
        return scale(dag, -c, n.b);
    return intern(dag, OP_NEG, a, -1, 0.0);
}

/* Constants first, then the smaller id: one spelling per commutative pair. */
static void order_commutative(const Dag *dag, NodeId *a, NodeId *b)
{
    bool ca = dag->nodes[*a].op == OP_CONST, cb = dag->nodes[*b].op == OP_CONST;
    if ((cb && !ca) || (ca == cb && *b < *a)) {
        NodeId t = *a;
        *a = *b;
        *b = t;
    }
}

static bool is_power_of_two(const Dag *dag, NodeId id);

/* c x + sign c y = c (x + sign y) for the same power of two c: exact
   (scaling by 2^k commutes with rounding), one product instead of two;
   the Euler-parameter rows' 2 e0 e0' + 2 e1 e1' + ... become 2 (...). */
static bool factor_power_of_two(Dag *dag, NodeId a, NodeId b, double sign, NodeId *out)
{
    const DagNode na = dag->nodes[a], nb = dag->nodes[b];   /* copies: the array may move */
    if (na.op != OP_MUL || nb.op != OP_MUL || na.a != nb.a || !is_power_of_two(dag, na.a)
        || dag_is_const(dag, na.b, NULL) || dag_is_const(dag, nb.b, NULL))
        return false;
    NodeId inner = sign > 0 ? dag_add(dag, na.b, nb.b) : dag_sub(dag, na.b, nb.b);
    *out = dag_mul(dag, na.a, inner);
    return true;
}

/* a + sign*b when both are multiples of the same term: (ca + sign*cb) term. */
static bool merge_terms(Dag *dag, NodeId a, NodeId b, double sign, NodeId *out)
{
    NodeId ta, tb;
    double ca = split_coefficient(dag, a, &ta);
    double cb = split_coefficient(dag, b, &tb);
    if (ta == DAG_NONE || ta != tb)
        return false;
    double c = ca + sign * cb;
    if (!isfinite(c))           /* 1e308 x + 1e308 x stays a sum */
        return false;
    *out = c == 0.0 ? DAG_ZERO : scale(dag, c, ta);
    return true;
}

NodeId dag_add(Dag *dag, NodeId a, NodeId b)
{
    NodeId r;
    if (try_fold(dag, OP_ADD, a, b, &r))
        return r;
    if (dag_is_zero(dag, a))
        return b;
    if (dag_is_zero(dag, b))
        return a;
    if (dag->nodes[b].op == OP_NEG)
        return dag_sub(dag, a, dag->nodes[b].a);
    if (dag->nodes[a].op == OP_NEG)
        return dag_sub(dag, b, dag->nodes[a].a);
    if (merge_terms(dag, a, b, 1.0, &r) || factor_power_of_two(dag, a, b, 1.0, &r))
        return r;
    /* a + (-c) y = a - c y: positive coefficients, so c y is shared with
       the rows that add it. */
    NodeId term;
    double coef = split_coefficient(dag, b, &term);
    if (term != DAG_NONE && term != b && coef < 0.0)
        return dag_sub(dag, a, scale(dag, -coef, term));
    coef = split_coefficient(dag, a, &term);
    if (term != DAG_NONE && term != a && coef < 0.0)
        return dag_sub(dag, b, scale(dag, -coef, term));
    order_commutative(dag, &a, &b);
    /* c1 + (c2 + y) = (c1 + c2) + y: keeps constants together. */
    double c1, c2;
    const DagNode nb = dag->nodes[b];    /* a copy: the array may move below */
    if (dag_is_const(dag, a, &c1) && nb.op == OP_ADD && dag_is_const(dag, nb.a, &c2)
        && isfinite(c1 + c2))
        return dag_add(dag, dag_const(dag, c1 + c2), nb.b);
    return intern(dag, OP_ADD, a, b, 0.0);
}

NodeId dag_sub(Dag *dag, NodeId a, NodeId b)
{
    NodeId r;
    if (try_fold(dag, OP_SUB, a, b, &r))
        return r;
    if (a == b)
        return DAG_ZERO;
    if (dag_is_zero(dag, b))
        return a;
    if (dag_is_zero(dag, a))
        return dag_neg(dag, b);
    if (dag->nodes[b].op == OP_NEG)
        return dag_add(dag, a, dag->nodes[b].a);
    if (dag->nodes[a].op == OP_NEG)     /* -x - b = -(x + b) */
        return dag_neg(dag, dag_add(dag, dag->nodes[a].a, b));
    if (merge_terms(dag, a, b, -1.0, &r) || factor_power_of_two(dag, a, b, -1.0, &r))
        return r;
    NodeId term;
    double coef = split_coefficient(dag, b, &term);
    if (term != DAG_NONE && term != b && coef < 0.0)      /* a - (-c) y = a + c y */
        return dag_add(dag, a, scale(dag, -coef, term));
    return intern(dag, OP_SUB, a, b, 0.0);
}

static bool is_trig(const Dag *dag, NodeId id)
{
    DagOp op = dag_op(dag, id);
    return op == OP_SIN || op == OP_COS;
}

/* c a moderate power of two: c (x y) and x (c y) are the same number
   (scaling by 2^k is exact away from overflow and subnormals), so either
   grouping may be chosen without changing a bit of any result. */
static bool is_power_of_two(const Dag *dag, NodeId id)
{
    double c;
    int e;
    return dag_is_const(dag, id, &c) && c > 0.0 && frexp(c, &e) == 0.5 && e > -64 && e < 64;
}

/* t (c y), t a sin or cos, c a power of two and y neither a constant nor a
   sin or cos: the one form of the product c t y, so that the sin and the
   cos of an angle share c y (0.5 phid^2 in gamma). */
static bool trig_times_scaled(const Dag *dag, NodeId t, NodeId scaled)
{
    const DagNode *n = &dag->nodes[scaled];
    return is_trig(dag, t) && n->op == OP_MUL && is_power_of_two(dag, n->a)
           && !is_trig(dag, n->b) && !dag_is_const(dag, n->b, NULL);
}

NodeId dag_mul(Dag *dag, NodeId a, NodeId b)
{
    NodeId r;
    if (try_fold(dag, OP_MUL, a, b, &r))
        return r;
    if (dag_is_zero(dag, a) || dag_is_zero(dag, b))
        return DAG_ZERO;
    order_commutative(dag, &a, &b);
    if (is_value(dag, a, 1.0))
        return b;
    if (is_value(dag, a, -1.0))
        return dag_neg(dag, b);
    /* copies: nested calls may grow (move) the node array */
    const DagNode na = dag->nodes[a], nb = dag->nodes[b];
    if (na.op == OP_NEG)
        return dag_neg(dag, dag_mul(dag, na.a, b));
    if (nb.op == OP_NEG)
        return dag_neg(dag, dag_mul(dag, a, nb.a));
    double c1, c2;
    bool a_const = dag_is_const(dag, a, &c1);
    /* (-c) y = -(c y): one product for c y and -c y, the sign folded
       into the parent's + or - (or a negation at the top). */
    if (a_const && c1 < 0.0) {
        NodeId positive = dag_const(dag, -c1);
        return dag_neg(dag, dag_mul(dag, positive, b));
    }
    if (trig_times_scaled(dag, a, b) || trig_times_scaled(dag, b, a))
        return intern(dag, OP_MUL, a, b, 0.0);
    /* c (t y) = t (c y) */
    if (a_const && is_power_of_two(dag, a) && nb.op == OP_MUL && !dag_is_const(dag, nb.a, NULL)
        && is_trig(dag, nb.a) != is_trig(dag, nb.b)) {
        NodeId t = is_trig(dag, nb.a) ? nb.a : nb.b;
        NodeId scaled = dag_mul(dag, a, t == nb.a ? nb.b : nb.a);
        return dag_mul(dag, t, scaled);
    }
    if (nb.op == OP_MUL && dag_is_const(dag, nb.a, &c2)) {
        if (a_const && isfinite(c1 * c2))       /* c1 (c2 y) = (c1 c2) y */
            return dag_mul(dag, dag_const(dag, c1 * c2), nb.b);
        if (!a_const)                           /* x (c y) = c (x y) */
            return dag_mul(dag, nb.a, dag_mul(dag, a, nb.b));
    }
    if (!a_const && na.op == OP_MUL && dag_is_const(dag, na.a, &c1))
        return dag_mul(dag, na.a, dag_mul(dag, na.b, b));
    /* (x y) y = x (y y): squares of velocities become one shared node
       (the chain rule builds (cos(phi) phid) phid). Not for a constant y:
       c (c x) with c c overflowing would turn back into c (c x) forever. */
    if (!a_const && nb.op == OP_MUL && nb.a != nb.b && (nb.a == a || nb.b == a))
        return dag_mul(dag, nb.a == a ? nb.b : nb.a, dag_mul(dag, a, a));
    if (!a_const && na.op == OP_MUL && na.a != na.b && (na.a == b || na.b == b))
        return dag_mul(dag, na.a == b ? na.b : na.a, dag_mul(dag, b, b));
    return intern(dag, OP_MUL, a, b, 0.0);
}

NodeId dag_div(Dag *dag, NodeId a, NodeId b)
{
    NodeId r;
    double c;
    if (try_fold(dag, OP_DIV, a, b, &r))
        return r;
    if (dag_is_const(dag, b, &c) && c == 0.0)
        return intern(dag, OP_DIV, a, b, 0.0);    /* leave x/0 to IEEE at run time */
    if (is_value(dag, b, 1.0))
        return a;
    if (dag_is_zero(dag, a))
        return DAG_ZERO;
    if (a == b)
        return DAG_ONE;
    /* copies: nested calls may grow (move) the node array */
    const DagNode na = dag->nodes[a], nb = dag->nodes[b];
    if (na.op == OP_NEG)
        return dag_neg(dag, dag_div(dag, na.a, b));
    if (nb.op == OP_NEG)
        return dag_neg(dag, dag_div(dag, a, nb.a));
    /* Division by a power of two is an exact multiplication. */
    int e;
    if (dag_is_const(dag, b, &c) && isfinite(c) && frexp(c, &e) == 0.5 * copysign(1.0, c)
        && isfinite(1.0 / c))   /* 1/2^-1074 overflows */
        return dag_mul(dag, dag_const(dag, 1.0 / c), a);
    double ca;
    if (na.op == OP_MUL && dag_is_const(dag, na.a, &ca))  /* (c x)/y = c (x/y) */
        return dag_mul(dag, na.a, dag_div(dag, na.b, b));
    return intern(dag, OP_DIV, a, b, 0.0);
}

NodeId dag_pow(Dag *dag, NodeId a, NodeId b)
{
    NodeId r;
    if (try_fold(dag, OP_POW, a, b, &r))
        return r;
    double c;
    if (dag_is_const(dag, b, &c)) {
        if (c == 0.0)
            return DAG_ONE;
        if (c == 1.0)
            return a;
        if (c == 2.0)
            return dag_mul(dag, a, a);
        if (c == 3.0)
            return dag_mul(dag, dag_mul(dag, a, a), a);
        if (c == 4.0) {
            NodeId sq = dag_mul(dag, a, a);
            return dag_mul(dag, sq, sq);
        }
        if (c == -1.0)
            return dag_div(dag, DAG_ONE, a);
        if (c == -2.0)
            return dag_div(dag, DAG_ONE, dag_mul(dag, a, a));
        if (c == 0.5)
            return dag_call(dag, OP_SQRT, a, DAG_NONE);
    }
    return intern(dag, OP_POW, a, b, 0.0);
}

NodeId dag_call(Dag *dag, DagOp fn, NodeId a, NodeId b)
{
    NodeId r;
    if (try_fold(dag, fn, a, b, &r))
        return r;
    /* Even and odd functions of -x: share the node of x. */
    if (dag->nodes[a].op == OP_NEG && b == DAG_NONE) {
        NodeId x = dag->nodes[a].a;
        switch (fn) {
        case OP_COS: case OP_COSH:
            return dag_call(dag, fn, x, DAG_NONE);
        case OP_SIN: case OP_TAN: case OP_ASIN: case OP_ATAN: case OP_SINH: case OP_TANH:
            return dag_neg(dag, dag_call(dag, fn, x, DAG_NONE));
        default:
            break;
        }
    }
    return intern(dag, fn, a, b == DAG_NONE ? -1 : b, 0.0);
}

NodeId dag_apply(Dag *dag, DagOp op, NodeId a, NodeId b)
{
    switch (op) {
    case OP_NEG: return dag_neg(dag, a);
    case OP_ADD: return dag_add(dag, a, b);
    case OP_SUB: return dag_sub(dag, a, b);
    case OP_MUL: return dag_mul(dag, a, b);
    case OP_DIV: return dag_div(dag, a, b);
    case OP_POW: return dag_pow(dag, a, b);
    default:     return dag_call(dag, op, a, b);
    }
}

/* ---- traversal and printing ---- */

int dag_mark_reachable(const Dag *dag, const NodeId *roots, int nroots,
                       uint32_t *mark, uint32_t stamp, NodeId *stack)
{
    int top = 0, marked = 0;
    for (int i = 0; i < nroots; i++) {
        if (roots[i] >= 0 && mark[roots[i]] != stamp) {
            mark[roots[i]] = stamp;
            stack[top++] = roots[i];
        }
    }
    while (top > 0) {
        NodeId id = stack[--top];
        marked++;
        const DagNode *n = &dag->nodes[id];
        int arity = dag_op_info[n->op].arity;
        NodeId kids[2] = {n->a, n->b};
        for (int k = 0; k < arity; k++) {
            if (mark[kids[k]] != stamp) {
                mark[kids[k]] = stamp;
                stack[top++] = kids[k];
            }
        }
    }
    return marked;
}

static int precedence(DagOp op)
{
    switch (op) {
    case OP_ADD: case OP_SUB: return 1;
    case OP_MUL: case OP_DIV: return 2;
    case OP_NEG: return 3;
    case OP_POW: return 4;
    default: return 5;
    }
}

static void format_node(const Dag *dag, NodeId id, const char *const *names,
                        StrBuf *out, int depth)
{
    const DagNode *n = &dag->nodes[id];
    DagOp op = (DagOp)n->op;
    if (depth > 200) {
        sb_puts(out, "...");
        return;
    }
    switch (op) {
    case OP_CONST: {
        char buf[40];
        mechrt_format_real(buf, sizeof buf, n->value, 0, false);    /* reads back exactly */
        sb_printf(out, n->value < 0 ? "(%s)" : "%s", buf);
        return;
    }
    case OP_VAR:
        if (names)
            sb_puts(out, names[n->a]);
        else
            sb_printf(out, "q[%d]", n->a);
        return;
    case OP_VARD:
        if (names)
            sb_printf(out, "der(%s)", names[n->a]);
        else
            sb_printf(out, "qd[%d]", n->a);
        return;
    case OP_TIME:
        sb_puts(out, "t");
        return;
    case OP_PARAM:
        if (dag->param_names)
            sb_puts(out, dag->param_names[n->a]);
        else
            sb_printf(out, "p[%d]", n->a);
        return;
    case OP_NEG:
        sb_putc(out, '-');
        if (precedence((DagOp)dag->nodes[n->a].op) <= precedence(op)) {
            sb_putc(out, '(');
            format_node(dag, n->a, names, out, depth + 1);
            sb_putc(out, ')');
        } else {
            format_node(dag, n->a, names, out, depth + 1);
        }
        return;
    case OP_ADD: case OP_SUB: case OP_MUL: case OP_DIV: case OP_POW: {
        int p = precedence(op);
        int pl = precedence((DagOp)dag->nodes[n->a].op);
        int pr = precedence((DagOp)dag->nodes[n->b].op);
        bool paren_l = op == OP_POW ? pl <= p : pl < p;
        bool paren_r = op == OP_POW ? pr < p : (op == OP_SUB || op == OP_DIV) ? pr <= p : pr < p;
        if (paren_l) sb_putc(out, '(');
        format_node(dag, n->a, names, out, depth + 1);
        if (paren_l) sb_putc(out, ')');
        /* x*y and x/y tight, x + y spaced: reads like the .mech file */
        sb_printf(out, op == OP_ADD || op == OP_SUB ? " %s " : "%s", dag_op_info[op].spelling);
        if (paren_r) sb_putc(out, '(');
        format_node(dag, n->b, names, out, depth + 1);
        if (paren_r) sb_putc(out, ')');
        return;
    }
    default:
        sb_printf(out, "%s(", dag_op_info[op].spelling);
        format_node(dag, n->a, names, out, depth + 1);
        if (dag_op_info[op].arity == 2) {
            sb_puts(out, ", ");
            format_node(dag, n->b, names, out, depth + 1);
        }
        sb_putc(out, ')');
        return;
    }
}

void dag_format(const Dag *dag, NodeId id, const char *const *coord_names, StrBuf *out)
{
    format_node(dag, id, coord_names, out, 0);
}

char *dag_format_string(const Dag *dag, NodeId id, const char *const *coord_names)
{
    StrBuf sb;
    sb_init(&sb);
    format_node(dag, id, coord_names, &sb, 0);
    return sb_take(&sb);
}
