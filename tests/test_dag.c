/* test_dag.c - the expression graph: hash-consing, every construction-time
 * simplification, canonical operand order, the node limit, and dag_op_eval
 * for every operation of ops.def.
 *
 * Each test builds a fresh graph (setup/teardown per test) with two
 * coordinate leaves x = q[0], y = q[1]; simplifications are checked both by
 * node identity (the rewritten form must be the very node the simple form
 * builds) and, where a value is folded, by the exact double.
 */
#include "testutil.h"

#include "../generator/base/diag.h"
#include "../generator/base/strbuf.h"
#include "../generator/dag/dag.h"

#include <math.h>

#include <stdlib.h>
#include <string.h>

typedef struct Fixture {
    Dag dag;
    NodeId x, y;
} Fixture;

static int setup(void **state)
{
    Fixture *f = calloc(1, sizeof *f);
    dag_init(&f->dag, 1000000);
    f->x = dag_var(&f->dag, 0);
    f->y = dag_var(&f->dag, 1);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    Fixture *f = *state;
    dag_free(&f->dag);
    free(f);
    return 0;
}

static NodeId K(Fixture *f, double v) { return dag_const(&f->dag, v); }

/* The node must be a constant with exactly this value (bitwise for 0). */
static void assert_const(const Dag *d, NodeId id, double want)
{
    double v = NAN;
    if (!dag_is_const(d, id, &v))
        fail_msg("node %d is op %d, expected the constant %.17g", (int)id,
                 (int)dag_op(d, id), want);
    if (!(v == want))
        fail_msg("node %d = %.17g, expected %.17g", (int)id, v, want);
}

/* The node must be (op a b) with exactly these operands. */
static void assert_node(const Dag *d, NodeId id, DagOp op, NodeId a, NodeId b)
{
    const DagNode *n = dag_node(d, id);
    if (n->op != op || n->a != a || (dag_op_info[op].arity == 2 && n->b != b))
        fail_msg("node %d = (op %d, %d, %d), expected (op %d, %d, %d)", (int)id,
                 (int)n->op, (int)n->a, (int)n->b, (int)op, (int)a, (int)b);
}

/* ---- hash-consing ---- */

static void test_leaves_unique(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    assert_int_equal(dag_const(d, 0.0), DAG_ZERO);
    assert_int_equal(dag_const(d, 1.0), DAG_ONE);
    assert_const(d, DAG_ZERO, 0.0);
    assert_const(d, DAG_ONE, 1.0);
    assert_int_equal(dag_var(d, 0), f->x);
    assert_int_equal(dag_var(d, 1), f->y);
    assert_int_not_equal(f->x, f->y);
    NodeId v0 = dag_vard(d, 0);
    assert_int_not_equal(v0, f->x);             /* qd[0] is not q[0] */
    assert_int_equal(dag_vard(d, 0), v0);
    assert_int_equal(dag_time(d), dag_time(d));
    NodeId c = K(f, 0.7371);
    assert_int_equal(K(f, 0.7371), c);
    assert_int_not_equal(K(f, 0.7372), c);
    assert_node(d, v0, OP_VARD, 0, -1);
    assert_node(d, dag_time(d), OP_TIME, -1, -1);
}

static void test_same_expression_same_id(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    /* sin(x*y + 0.3) / (y - x), built twice from scratch */
    NodeId e1 = dag_div(d, dag_call(d, OP_SIN, dag_add(d, dag_mul(d, f->x, f->y), K(f, 0.3)), DAG_NONE),
                        dag_sub(d, f->y, f->x));
    int32_t count = d->count;
    NodeId e2 = dag_div(d, dag_call(d, OP_SIN, dag_add(d, dag_mul(d, f->x, f->y), K(f, 0.3)), DAG_NONE),
                        dag_sub(d, f->y, f->x));
    assert_int_equal(e1, e2);
    assert_int_equal(d->count, count);          /* nothing new was created */
    assert_int_equal(dag_op(d, e1), OP_DIV);
    /* a different expression is a different node */
    NodeId e3 = dag_div(d, dag_call(d, OP_COS, dag_add(d, dag_mul(d, f->x, f->y), K(f, 0.3)), DAG_NONE),
                        dag_sub(d, f->y, f->x));
    assert_int_not_equal(e3, e1);
    /* two-argument functions are keyed on both operands, in order */
    NodeId a1 = dag_call(d, OP_ATAN2, f->x, f->y), a2 = dag_call(d, OP_ATAN2, f->y, f->x);
    assert_int_not_equal(a1, a2);
    assert_int_equal(dag_call(d, OP_ATAN2, f->x, f->y), a1);
}

static void test_table_growth_keeps_identity(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    /* enough nodes to grow the table several times */
    NodeId ids[5000];
    for (int i = 0; i < 5000; i++)
        ids[i] = dag_add(d, dag_var(d, i + 2), K(f, 0.5 + i));
    for (int i = 0; i < 5000; i++)
        assert_int_equal(dag_add(d, dag_var(d, i + 2), K(f, 0.5 + i)), ids[i]);
    /* operands always have smaller ids: id order is topological */
    for (int32_t id = 0; id < d->count; id++) {
        const DagNode *n = dag_node(d, id);
        int arity = dag_op_info[n->op].arity;
        if (arity >= 1)
            assert_true(n->a >= 0 && n->a < id);
        if (arity == 2)
            assert_true(n->b >= 0 && n->b < id);
    }
}

/* ---- constant folding ---- */

/* The expected values below come from libm at run time (volatile inputs):
   a compiler folding sin(0.7371) itself may round differently from libm. */
static volatile double va = 0.7371, vb = 0.4123;

static void test_constant_folding(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    double a = va, b = vb;
    NodeId ka = K(f, a), kb = K(f, b);
    assert_const(d, dag_add(d, ka, kb), a + b);
    assert_const(d, dag_sub(d, ka, kb), a - b);
    assert_const(d, dag_mul(d, ka, kb), a * b);
    assert_const(d, dag_div(d, ka, kb), a / b);
    assert_const(d, dag_pow(d, ka, kb), pow(a, b));
    assert_const(d, dag_neg(d, ka), -a);
    assert_const(d, dag_call(d, OP_SIN, ka, DAG_NONE), sin(a));
    assert_const(d, dag_call(d, OP_COS, ka, DAG_NONE), cos(a));
    assert_const(d, dag_call(d, OP_TAN, ka, DAG_NONE), tan(a));
    assert_const(d, dag_call(d, OP_ASIN, ka, DAG_NONE), asin(a));
    assert_const(d, dag_call(d, OP_ACOS, ka, DAG_NONE), acos(a));
    assert_const(d, dag_call(d, OP_ATAN, ka, DAG_NONE), atan(a));
    assert_const(d, dag_call(d, OP_ATAN2, ka, kb), atan2(a, b));
    assert_const(d, dag_call(d, OP_SQRT, ka, DAG_NONE), sqrt(a));
    assert_const(d, dag_call(d, OP_EXP, ka, DAG_NONE), exp(a));
    assert_const(d, dag_call(d, OP_LOG, ka, DAG_NONE), log(a));
    assert_const(d, dag_call(d, OP_SINH, ka, DAG_NONE), sinh(a));
    assert_const(d, dag_call(d, OP_COSH, ka, DAG_NONE), cosh(a));
    assert_const(d, dag_call(d, OP_TANH, ka, DAG_NONE), tanh(a));
    /* nested: (2 + 3) * 4 - 1 = 19 */
    assert_const(d, dag_sub(d, dag_mul(d, dag_add(d, K(f, 2), K(f, 3)), K(f, 4)), DAG_ONE), 19.0);
    /* through dag_apply, the lowering's entry point */
    assert_const(d, dag_apply(d, OP_MUL, K(f, 6), K(f, 7)), 42.0);
    assert_const(d, dag_apply(d, OP_NEG, K(f, 6), DAG_NONE), -6.0);
    assert_const(d, dag_apply(d, OP_COSH, K(f, 0.0), DAG_NONE), 1.0);
    /* -0 is never made: neg(0) is the zero node */
    assert_int_equal(dag_neg(d, DAG_ZERO), DAG_ZERO);
}

static void test_no_fold_to_nan_or_inf(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId one = DAG_ONE, zero = DAG_ZERO, m1 = K(f, -1.0), two = K(f, 2.0);
    NodeId e;
    e = dag_div(d, one, zero);                  /* 1/0 = inf */
    assert_node(d, e, OP_DIV, one, zero);
    e = dag_div(d, zero, zero);                 /* 0/0 = nan */
    assert_node(d, e, OP_DIV, zero, zero);
    e = dag_call(d, OP_LOG, m1, DAG_NONE);      /* log(-1) = nan */
    assert_node(d, e, OP_LOG, m1, -1);
    e = dag_call(d, OP_LOG, zero, DAG_NONE);    /* log(0) = -inf */
    assert_node(d, e, OP_LOG, zero, -1);
    e = dag_call(d, OP_SQRT, m1, DAG_NONE);     /* sqrt(-1) = nan */
    assert_node(d, e, OP_SQRT, m1, -1);
    e = dag_call(d, OP_ASIN, two, DAG_NONE);    /* asin(2) = nan */
    assert_node(d, e, OP_ASIN, two, -1);
    e = dag_call(d, OP_ACOS, two, DAG_NONE);
    assert_node(d, e, OP_ACOS, two, -1);
    NodeId big = K(f, 1000.0);
    e = dag_call(d, OP_EXP, big, DAG_NONE);     /* exp(1000) overflows */
    assert_node(d, e, OP_EXP, big, -1);
    e = dag_call(d, OP_COSH, big, DAG_NONE);
    assert_node(d, e, OP_COSH, big, -1);
    NodeId huge = K(f, 1e300);
    e = dag_mul(d, huge, huge);                 /* 1e600 overflows */
    assert_node(d, e, OP_MUL, huge, huge);
    e = dag_pow(d, K(f, -8.0), K(f, 1.0 / 3.0));   /* pow(-8, 1/3) = nan */
    assert_int_equal(dag_op(d, e), OP_POW);
    e = dag_pow(d, zero, K(f, -1.0));           /* 0^-1 = 1/0, still not folded */
    assert_int_equal(dag_op(d, e), OP_DIV);
    /* the unfolded node is still hash-consed */
    assert_int_equal(dag_div(d, one, zero), dag_div(d, one, zero));
    /* an unfolded constant subtree does not poison a finite neighbour */
    assert_const(d, dag_add(d, two, two), 4.0);
}

/* ---- identities ---- */

static void test_identities(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, y = f->y;
    /* x + 0, 0 + x */
    assert_int_equal(dag_add(d, x, DAG_ZERO), x);
    assert_int_equal(dag_add(d, DAG_ZERO, x), x);
    /* x - 0; 0 - x = -x */
    assert_int_equal(dag_sub(d, x, DAG_ZERO), x);
    assert_node(d, dag_sub(d, DAG_ZERO, x), OP_NEG, x, -1);
    /* x * 1, 1 * x */
    assert_int_equal(dag_mul(d, x, DAG_ONE), x);
    assert_int_equal(dag_mul(d, DAG_ONE, x), x);
    /* x * 0, 0 * x: even with a non-constant x */
    assert_int_equal(dag_mul(d, x, DAG_ZERO), DAG_ZERO);
    assert_int_equal(dag_mul(d, DAG_ZERO, dag_call(d, OP_SIN, x, DAG_NONE)), DAG_ZERO);
    /* x * -1 = -x */
    assert_node(d, dag_mul(d, x, K(f, -1.0)), OP_NEG, x, -1);
    /* x / 1, 0 / x, x / x */
    assert_int_equal(dag_div(d, x, DAG_ONE), x);
    assert_int_equal(dag_div(d, DAG_ZERO, x), DAG_ZERO);
    NodeId s = dag_add(d, x, y);
    assert_int_equal(dag_div(d, s, s), DAG_ONE);
    /* x - x = 0, also for a compound x */
    assert_int_equal(dag_sub(d, x, x), DAG_ZERO);
    assert_int_equal(dag_sub(d, s, dag_add(d, y, x)), DAG_ZERO);
    /* -(-x) = x */
    NodeId nx = dag_neg(d, x);
    assert_node(d, nx, OP_NEG, x, -1);
    assert_int_equal(dag_neg(d, nx), x);
    /* -(a - b) = b - a */
    assert_int_equal(dag_neg(d, dag_sub(d, x, y)), dag_sub(d, y, x));
    /* x + (-y) = x - y, (-x) + y = y - x, x - (-y) = x + y */
    assert_int_equal(dag_add(d, x, dag_neg(d, y)), dag_sub(d, x, y));
    assert_int_equal(dag_add(d, dag_neg(d, x), y), dag_sub(d, y, x));
    assert_int_equal(dag_sub(d, x, dag_neg(d, y)), dag_add(d, x, y));
    /* (-x) - y = -(x + y) */
    assert_int_equal(dag_sub(d, dag_neg(d, x), y), dag_neg(d, dag_add(d, x, y)));
    /* (-x) * y = -(x y), x * (-y) = -(x y); (-x) / y = -(x / y) */
    NodeId xy = dag_mul(d, x, y);
    assert_node(d, dag_mul(d, dag_neg(d, x), y), OP_NEG, xy, -1);
    assert_node(d, dag_mul(d, x, dag_neg(d, y)), OP_NEG, xy, -1);
    NodeId xdy = dag_div(d, x, y);
    assert_node(d, xdy, OP_DIV, x, y);
    assert_node(d, dag_div(d, dag_neg(d, x), y), OP_NEG, xdy, -1);
    assert_node(d, dag_div(d, x, dag_neg(d, y)), OP_NEG, xdy, -1);
}

static void test_coefficients_merge(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, y = f->y;
    NodeId six_x = dag_mul(d, K(f, 6.0), x);
    assert_node(d, six_x, OP_MUL, K(f, 6.0), x);
    /* 2*(3*x) = 6*x, either operand order */
    assert_int_equal(dag_mul(d, K(f, 2.0), dag_mul(d, K(f, 3.0), x)), six_x);
    assert_int_equal(dag_mul(d, dag_mul(d, x, K(f, 3.0)), K(f, 2.0)), six_x);
    /* x + x = 2*x */
    NodeId two_x = dag_mul(d, K(f, 2.0), x);
    assert_int_equal(dag_add(d, x, x), two_x);
    assert_node(d, dag_add(d, x, x), OP_MUL, K(f, 2.0), x);
    /* 3*x - x = 2*x, x - 3*x = -2*x, 3*x + 4*x = 7*x, 3*x - 3*x = 0 */
    NodeId three_x = dag_mul(d, K(f, 3.0), x);
    assert_int_equal(dag_sub(d, three_x, x), two_x);
    assert_node(d, dag_sub(d, x, three_x), OP_NEG, two_x, -1);      /* -(2*x) */
    assert_node(d, dag_add(d, three_x, dag_mul(d, K(f, 4.0), x)), OP_MUL, K(f, 7.0), x);
    assert_int_equal(dag_sub(d, three_x, three_x), DAG_ZERO);
    assert_int_equal(dag_add(d, three_x, dag_mul(d, K(f, -3.0), x)), DAG_ZERO);
    /* -(3*x) stays a negation of 3*x, and (-3)*x is the same node: c*x and
       -c*x share one product, the sign goes to the parent */
    NodeId minus_three_x = dag_neg(d, three_x);
    assert_node(d, minus_three_x, OP_NEG, three_x, -1);
    assert_int_equal(dag_mul(d, K(f, -3.0), x), minus_three_x);
    assert_int_equal(dag_mul(d, x, K(f, -3.0)), minus_three_x);
    assert_int_equal(dag_mul(d, K(f, -1.5), dag_mul(d, K(f, 2.0), x)), minus_three_x);
    assert_int_equal(dag_neg(d, minus_three_x), three_x);
    /* y + (-3)*x = y - 3*x; y - (-3)*x = y + 3*x; 4*x + (-3)*x = x */
    assert_node(d, dag_add(d, y, dag_mul(d, K(f, -3.0), x)), OP_SUB, y, three_x);
    assert_int_equal(dag_sub(d, y, dag_mul(d, K(f, -3.0), x)), dag_add(d, y, three_x));
    assert_int_equal(dag_add(d, dag_mul(d, K(f, 4.0), x), minus_three_x), x);
    /* merging applies to compound terms: sin(y) + sin(y) = 2 sin(y) */
    NodeId sy = dag_call(d, OP_SIN, y, DAG_NONE);
    assert_node(d, dag_add(d, sy, sy), OP_MUL, K(f, 2.0), sy);
    /* different terms do not merge */
    NodeId e = dag_add(d, three_x, y);
    assert_int_equal(dag_op(d, e), OP_ADD);
    /* x * (3*y) = 3*(x*y), (3*x) * y = 3*(x*y) */
    NodeId xy = dag_mul(d, x, y);
    NodeId three_xy = dag_mul(d, K(f, 3.0), xy);
    assert_node(d, three_xy, OP_MUL, K(f, 3.0), xy);
    assert_int_equal(dag_mul(d, x, dag_mul(d, K(f, 3.0), y)), three_xy);
    assert_int_equal(dag_mul(d, three_x, y), three_xy);
    /* (3*x)/y = 3*(x/y) */
    assert_node(d, dag_div(d, three_x, y), OP_MUL, K(f, 3.0), dag_div(d, x, y));
    /* c1 + (c2 + x) = (c1 + c2) + x */
    NodeId e5 = dag_add(d, K(f, 5.0), x);
    assert_node(d, e5, OP_ADD, K(f, 5.0), x);
    assert_int_equal(dag_add(d, K(f, 2.0), dag_add(d, K(f, 3.0), x)), e5);
    assert_int_equal(dag_add(d, dag_add(d, x, K(f, 3.0)), K(f, 2.0)), e5);
    /* division by a power of two is a product; by 3 it is not */
    assert_node(d, dag_div(d, x, K(f, 4.0)), OP_MUL, K(f, 0.25), x);
    assert_node(d, dag_div(d, x, K(f, -0.5)), OP_NEG, dag_mul(d, K(f, 2.0), x), -1);
    assert_node(d, dag_div(d, x, K(f, 3.0)), OP_DIV, x, K(f, 3.0));
}

/* c t y with c a power of two and t a sin or cos is t (c y): the sin and
   cos of an angle share c y. Other constants keep c (t y), so no result
   changes a bit. */
static void test_trig_products(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, y = f->y;
    NodeId s = dag_call(d, OP_SIN, x, DAG_NONE), c = dag_call(d, OP_COS, x, DAG_NONE);
    NodeId half_y = dag_mul(d, K(f, 0.5), y);
    NodeId cy = dag_mul(d, c, half_y);
    assert_node(d, cy, OP_MUL, c < half_y ? c : half_y, c < half_y ? half_y : c);
    assert_int_equal(dag_mul(d, K(f, 0.5), dag_mul(d, c, y)), cy);
    assert_int_equal(dag_mul(d, dag_mul(d, y, K(f, 0.5)), c), cy);
    assert_int_equal(dag_mul(d, y, dag_mul(d, K(f, 0.5), c)), cy);
    NodeId sy = dag_mul(d, K(f, 0.5), dag_mul(d, s, y));
    const DagNode *n = dag_node(d, sy);
    assert_true(n->a == half_y || n->b == half_y);        /* 0.5 y shared */
    /* -0.5 (cos x) y = -(cos x (0.5 y)) */
    assert_node(d, dag_mul(d, K(f, -0.5), dag_mul(d, c, y)), OP_NEG, cy, -1);
    /* 1.5 is not a power of two: 1.5 (cos x y) as before */
    NodeId cxy = dag_mul(d, c, y);
    assert_node(d, dag_mul(d, K(f, 1.5), cxy), OP_MUL, K(f, 1.5), cxy);
    /* sin x cos x: both trig, no rewrite */
    NodeId sc = dag_mul(d, s, c);
    assert_node(d, dag_mul(d, K(f, 0.5), sc), OP_MUL, K(f, 0.5), sc);
}

static void test_powers(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x;
    NodeId xx = dag_mul(d, x, x);
    assert_int_equal(dag_pow(d, x, DAG_ZERO), DAG_ONE);
    assert_int_equal(dag_pow(d, x, DAG_ONE), x);
    assert_int_equal(dag_pow(d, x, K(f, 2.0)), xx);
    assert_int_equal(dag_pow(d, x, K(f, 3.0)), dag_mul(d, xx, x));
    assert_node(d, dag_pow(d, x, K(f, 3.0)), OP_MUL, x, xx);    /* smaller id first */
    assert_node(d, dag_pow(d, x, K(f, 4.0)), OP_MUL, xx, xx);
    assert_node(d, dag_pow(d, x, K(f, -1.0)), OP_DIV, DAG_ONE, x);
    assert_node(d, dag_pow(d, x, K(f, -2.0)), OP_DIV, DAG_ONE, xx);
    assert_node(d, dag_pow(d, x, K(f, 0.5)), OP_SQRT, x, -1);
    NodeId k = K(f, 2.5);
    assert_node(d, dag_pow(d, x, k), OP_POW, x, k);
    assert_node(d, dag_pow(d, x, f->y), OP_POW, x, f->y);
    assert_node(d, dag_apply(d, OP_POW, x, K(f, 2.0)), OP_MUL, x, x);
}

static void test_even_odd_functions(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, nx = dag_neg(d, x);
    const DagOp even[] = {OP_COS, OP_COSH};
    const DagOp odd[] = {OP_SIN, OP_TAN, OP_ASIN, OP_ATAN, OP_SINH, OP_TANH};
    for (size_t i = 0; i < sizeof even / sizeof *even; i++)
        assert_int_equal(dag_call(d, even[i], nx, DAG_NONE), dag_call(d, even[i], x, DAG_NONE));
    for (size_t i = 0; i < sizeof odd / sizeof *odd; i++) {
        NodeId fx = dag_call(d, odd[i], x, DAG_NONE);
        assert_node(d, dag_call(d, odd[i], nx, DAG_NONE), OP_NEG, fx, -1);
    }
    /* neither even nor odd: kept as written */
    assert_node(d, dag_call(d, OP_EXP, nx, DAG_NONE), OP_EXP, nx, -1);
    assert_node(d, dag_call(d, OP_ACOS, nx, DAG_NONE), OP_ACOS, nx, -1);
}

/* ---- canonical order ---- */

static void test_canonical_order(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId a = dag_call(d, OP_SIN, f->x, DAG_NONE), b = dag_call(d, OP_COS, f->y, DAG_NONE);
    NodeId ab = dag_add(d, a, b);
    assert_int_equal(dag_add(d, b, a), ab);
    assert_node(d, ab, OP_ADD, a < b ? a : b, a < b ? b : a);
    NodeId m = dag_mul(d, a, b);
    assert_int_equal(dag_mul(d, b, a), m);
    assert_node(d, m, OP_MUL, a < b ? a : b, a < b ? b : a);
    /* constants come first whatever their id */
    NodeId c = K(f, 0.4123);
    assert_true(c > f->x);
    assert_node(d, dag_mul(d, f->x, c), OP_MUL, c, f->x);
    assert_node(d, dag_add(d, f->x, c), OP_ADD, c, f->x);
    /* non-commutative operators keep their order */
    assert_int_not_equal(dag_sub(d, a, b), dag_sub(d, b, a));
    assert_int_not_equal(dag_div(d, a, b), dag_div(d, b, a));
    assert_int_not_equal(dag_pow(d, a, b), dag_pow(d, b, a));
    /* so x*y - y*x cancels */
    assert_int_equal(dag_sub(d, dag_mul(d, f->x, f->y), dag_mul(d, f->y, f->x)), DAG_ZERO);
}

/* ---- dag_op_eval: the one meaning of every op ---- */

static void test_op_eval_every_op(void **state)
{
    (void)state;
    double a = va, b = vb;
    struct { DagOp op; double want; } cases[] = {
        {OP_NEG, -a}, {OP_ADD, a + b}, {OP_SUB, a - b}, {OP_MUL, a * b},
        {OP_DIV, a / b}, {OP_POW, pow(a, b)}, {OP_SIN, sin(a)}, {OP_COS, cos(a)},
        {OP_TAN, tan(a)}, {OP_ASIN, asin(a)}, {OP_ACOS, acos(a)}, {OP_ATAN, atan(a)},
        {OP_ATAN2, atan2(a, b)}, {OP_SQRT, sqrt(a)}, {OP_EXP, exp(a)}, {OP_LOG, log(a)},
        {OP_SINH, sinh(a)}, {OP_COSH, cosh(a)}, {OP_TANH, tanh(a)},
    };
    int n = (int)(sizeof cases / sizeof *cases);
    assert_int_equal(n, OP_COUNT - 5);          /* every non-leaf op is listed */
    for (int i = 0; i < n; i++) {
        double got = dag_op_eval(cases[i].op, a, b);
        if (!(got == cases[i].want))
            fail_msg("dag_op_eval(%s) = %.17g, expected %.17g",
                     dag_op_info[cases[i].op].spelling, got, cases[i].want);
    }
    /* known values, independent of libm's spelling above */
    assert_near(dag_op_eval(OP_ATAN2, 1.0, -1.0), 3.0 * M_PI / 4.0, 1e-15, 0);
    assert_near(dag_op_eval(OP_POW, 2.0, 10.0), 1024.0, 0, 0);
    assert_near(dag_op_eval(OP_SQRT, 6.25, 0), 2.5, 0, 0);
    assert_near(dag_op_eval(OP_SUB, 3.0, 5.0), -2.0, 0, 0);
    assert_near(dag_op_eval(OP_DIV, 3.0, 4.0), 0.75, 0, 0);
    /* leaves have no operator meaning */
    assert_true(isnan(dag_op_eval(OP_CONST, a, b)));
    assert_true(isnan(dag_op_eval(OP_VAR, a, b)));
    assert_true(isnan(dag_op_eval(OP_VARD, a, b)));
    assert_true(isnan(dag_op_eval(OP_TIME, a, b)));
}

static void test_op_table(void **state)
{
    (void)state;
    assert_int_equal(dag_function_from_name("sin", 3), OP_SIN);
    assert_int_equal(dag_function_from_name("atan2", 5), OP_ATAN2);
    assert_int_equal(dag_function_from_name("tanh", 4), OP_TANH);
    assert_int_equal(dag_function_from_name("sinh", 3), OP_SIN);    /* length counts */
    assert_int_equal(dag_function_from_name("foo", 3), -1);
    assert_int_equal(dag_function_from_name("q", 1), -1);           /* leaves are not functions */
    assert_int_equal(dag_function_from_name("pow", 3), -1);         /* ^ is the operator */
    for (int op = 0; op < OP_COUNT; op++) {
        bool fn = dag_op_is_function((DagOp)op);
        assert_true(fn == (op >= OP_SIN));
        if (fn) {
            assert_non_null(dag_op_info[op].c_double);
            assert_non_null(dag_op_info[op].c_float);
            assert_int_equal(dag_op_info[op].arity, op == OP_ATAN2 ? 2 : 1);
        }
    }
    assert_int_equal(dag_op_info[OP_CONST].arity, 0);
    assert_int_equal(dag_op_info[OP_NEG].arity, 1);
    assert_int_equal(dag_op_info[OP_POW].arity, 2);
}

/* ---- traversal, printing, the node limit ---- */

static void test_mark_reachable(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId s = dag_call(d, OP_SIN, f->x, DAG_NONE);
    NodeId e = dag_add(d, dag_mul(d, s, f->y), s);  /* nodes: e, s*y, s, x, y */
    NodeId unrelated = dag_call(d, OP_EXP, f->y, DAG_NONE);
    uint32_t *mark = calloc((size_t)d->count, sizeof *mark);
    NodeId *stack = calloc((size_t)d->count, sizeof *stack);
    NodeId roots[2] = {e, DAG_NONE};
    assert_int_equal(dag_mark_reachable(d, roots, 2, mark, 7, stack), 5);
    assert_int_equal(mark[f->x], 7);
    assert_int_equal(mark[s], 7);
    assert_int_not_equal(mark[unrelated], 7);
    /* a second pass with the same stamp marks nothing new */
    assert_int_equal(dag_mark_reachable(d, roots, 1, mark, 7, stack), 0);
    roots[0] = unrelated;
    assert_int_equal(dag_mark_reachable(d, roots, 1, mark, 7, stack), 1);
    free(mark);
    free(stack);
}

static void test_format(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    const char *names[] = {"m.x", "m.y"};
    StrBuf sb;
    sb_init(&sb);
    NodeId xx = dag_mul(d, f->x, f->x);        /* built in order: ids decide the operand order */
    NodeId yy = dag_mul(d, f->y, f->y);
    NodeId e = dag_sub(d, dag_add(d, yy, xx), K(f, 4.0));
    dag_format(d, e, names, &sb);
    assert_string_equal(sb.data, "m.x*m.x + m.y*m.y - 4");
    sb_clear(&sb);
    dag_format(d, dag_sub(d, f->x, dag_sub(d, f->y, dag_time(d))), NULL, &sb);
    assert_string_equal(sb.data, "q[0] - (q[1] - t)");
    sb_clear(&sb);
    NodeId at = dag_call(d, OP_ATAN2, f->y, f->x);     /* built first: the smaller id */
    NodeId yd = dag_vard(d, 1);
    dag_format(d, dag_mul(d, yd, at), names, &sb);
    assert_string_equal(sb.data, "atan2(m.y, m.x)*der(m.y)");
    sb_clear(&sb);
    dag_format(d, dag_neg(d, dag_pow(d, f->x, K(f, 2.5))), names, &sb);
    assert_string_equal(sb.data, "-m.x^2.5");
    sb_free(&sb);
}

/* Numbers print as the shortest text that reads back; a malloc'd string. */
static void test_format_shortest_numbers(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    const char *names[] = {"a.x", "a.phi"};
    NodeId e = dag_add(d, f->x, dag_mul(d, dag_const(d, 0.3), f->y));
    char *s = dag_format_string(d, e, names);
    assert_string_equal(s, "a.x + 0.3*a.phi");
    free(s);
    e = dag_sub(d, f->x, dag_mul(d, dag_const(d, -2.5), dag_time(d)));
    s = dag_format_string(d, e, names);
    assert_string_equal(s, "a.x + 2.5*t");
    free(s);
    s = dag_format_string(d, dag_const(d, 0.1 + 0.2), NULL);
    assert_string_equal(s, "0.30000000000000004");
    free(s);
}

/* Past the limit the graph makes no node: a new one comes back as
   DAG_ZERO and sets the sticky overflow flag, existing ones are still
   found, and dag_check_limit reports it (the ferror idiom). */
static void test_node_limit(void **state)
{
    (void)state;
    Dag d;
    dag_init(&d, 10);
    Diag diag;
    diag_init(&diag, "test", "", 0);
    assert_true(dag_check_limit(&d, &diag));
    assert_false(diag.failed);
    NodeId v[100];
    for (int i = 0; i < 100; i++)
        v[i] = dag_var(&d, i);
    assert_int_equal(d.count, 10);
    assert_true(d.overflow);
    for (int i = 0; i < 8; i++)                 /* 0 and 1 are the first two */
        assert_int_equal(v[i], i + 2);
    for (int i = 8; i < 100; i++)
        assert_int_equal(v[i], DAG_ZERO);
    assert_int_equal(dag_var(&d, 3), v[3]);
    /* the zero folds away in every rule: no node, no x/0 left behind */
    assert_int_equal(dag_div(&d, v[0], dag_const(&d, 7.0)), DAG_ZERO);
    assert_int_equal(dag_add(&d, v[0], dag_call(&d, OP_SIN, v[1], DAG_NONE)), v[0]);
    assert_int_equal(dag_mul(&d, v[0], v[1]), DAG_ZERO);
    assert_int_equal(d.count, 10);
    assert_false(dag_check_limit(&d, &diag));
    assert_true(diag.failed);
    assert_false(diag.has_pos);
    assert_string_equal(diag.message, "the expression graph passed its limit of 10 nodes "
                                      "(the mechanism is too large; see --max-nodes)");
    dag_free(&d);
}

/* With a statement being built, the error points at the statement where
   the limit was first passed, not where the phase noticed it. */
static void test_node_limit_names_statement(void **state)
{
    (void)state;
    const char *text = "first\nsecond\nthird\n";
    Dag d;
    dag_init(&d, 4);
    d.where = 0;
    dag_var(&d, 0);
    dag_var(&d, 1);
    d.where = 6;                                /* "second" */
    assert_int_equal(dag_var(&d, 2), DAG_ZERO);
    d.where = 13;                               /* later work does not move it */
    assert_int_equal(dag_var(&d, 3), DAG_ZERO);
    Diag diag;
    diag_init(&diag, "x.mech", text, (int)strlen(text));
    assert_false(dag_check_limit(&d, &diag));
    assert_true(diag.has_pos);
    assert_int_equal(diag.line, 2);
    assert_int_equal(diag.col, 1);
    assert_string_equal(diag.message, "the expression graph passed its limit of 4 nodes at this "
                                      "statement (its rows or their derivatives are too large; "
                                      "see --max-nodes)");
    dag_free(&d);
}

/* A constant that is not finite is noted at the statement that asked for
   it (the first one only) and reported by dag_check_finite. */
static void test_nonfinite_constant_names_statement(void **state)
{
    (void)state;
    const char *text = "first\nsecond\nthird\n";
    Dag d;
    dag_init(&d, 100);
    Diag diag;
    diag_init(&diag, "x.mech", text, (int)strlen(text));
    d.where = 0;
    dag_const(&d, 1e308);
    assert_true(dag_check_finite(&d, &diag));
    d.where = 6;                                /* "second" */
    dag_const(&d, 1e308 * 10);
    d.where = 13;
    dag_const(&d, NAN);
    assert_false(dag_check_finite(&d, &diag));
    assert_int_equal(diag.line, 2);
    assert_int_equal(diag.col, 1);
    assert_string_equal(diag.message, "a constant mechc computes from this statement's numbers "
                                      "is +inf: it overflows past the largest double (about "
                                      "1.8e308); write the numbers in other units, or nearer 1");
    dag_free(&d);
}

/* Made while a sub-expression is lowered (where_expr), a constant out of
   range is reported at that sub-expression, as "this constant". */
static void test_nonfinite_constant_names_expression(void **state)
{
    (void)state;
    const char *text = "first\nsecond x = 1e200\n";
    Dag d;
    dag_init(&d, 100);
    Diag diag;
    diag_init(&diag, "x.mech", text, (int)strlen(text));
    d.where = 6;                                /* "second" */
    d.where_expr = 17;                          /* "1e200" */
    dag_const(&d, -INFINITY);
    d.where_expr = -1;
    assert_false(dag_check_finite(&d, &diag));
    assert_int_equal(diag.line, 2);
    assert_int_equal(diag.col, 12);
    assert_string_equal(diag.message, "this constant is -inf: it overflows past the largest "
                                      "double (about -1.8e308); write the numbers in other "
                                      "units, or nearer 1");
    dag_free(&d);
}

/* dag_check_float names the first constant a float cannot hold among those
   the roots reach: one folded away does not count. */
static void test_float_range_only_reachable(void **state)
{
    (void)state;
    const char *text = "first\nsecond\n";
    Dag d;
    dag_init(&d, 100);
    Diag diag;
    diag_init(&diag, "x.mech", text, (int)strlen(text));
    d.where = 0;
    NodeId x = dag_var(&d, 0);
    NodeId folded = dag_div(&d, dag_const(&d, 1e200), dag_const(&d, 1e199));   /* 10 */
    NodeId small = dag_mul(&d, folded, x);
    assert_true(dag_check_float(&d, &small, 1, &diag));
    d.where = 6;
    NodeId tiny = dag_mul(&d, dag_const(&d, 1e-50), x);
    NodeId roots[2] = {small, tiny};
    assert_false(dag_check_float(&d, roots, 2, &diag));
    assert_int_equal(diag.line, 2);
    assert_non_null(strstr(diag.message, "is 1e-50, which a float (--real float) cannot hold: "
                                         "it would become 0"));
    dag_free(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_leaves_unique, setup, teardown),
        cmocka_unit_test_setup_teardown(test_same_expression_same_id, setup, teardown),
        cmocka_unit_test_setup_teardown(test_table_growth_keeps_identity, setup, teardown),
        cmocka_unit_test_setup_teardown(test_constant_folding, setup, teardown),
        cmocka_unit_test_setup_teardown(test_no_fold_to_nan_or_inf, setup, teardown),
        cmocka_unit_test_setup_teardown(test_identities, setup, teardown),
        cmocka_unit_test_setup_teardown(test_coefficients_merge, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trig_products, setup, teardown),
        cmocka_unit_test_setup_teardown(test_powers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_even_odd_functions, setup, teardown),
        cmocka_unit_test_setup_teardown(test_canonical_order, setup, teardown),
        cmocka_unit_test(test_op_eval_every_op),
        cmocka_unit_test(test_op_table),
        cmocka_unit_test_setup_teardown(test_mark_reachable, setup, teardown),
        cmocka_unit_test_setup_teardown(test_format, setup, teardown),
        cmocka_unit_test_setup_teardown(test_format_shortest_numbers, setup, teardown),
        cmocka_unit_test(test_node_limit),
        cmocka_unit_test(test_node_limit_names_statement),
        cmocka_unit_test(test_nonfinite_constant_names_statement),
        cmocka_unit_test(test_nonfinite_constant_names_expression),
        cmocka_unit_test(test_float_range_only_reachable),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
