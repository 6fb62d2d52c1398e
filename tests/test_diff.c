/* test_diff.c - symbolic derivatives: every rule of ops.def against finite differences.
 *
 * Each case builds an expression in x = q[0], y = q[1] (and t, qd where it
 * matters) whose top operation is the rule under test, with operands that
 * depend on both coordinates so the chain-rule factor is exercised too.
 * Derivative graphs are evaluated by a small recursive interpreter over
 * DagNode written here (VAR -> q[a], VARD -> qd[a], TIME -> t, CONST ->
 * value, anything else -> dag_op_eval of its operands) and compared with a
 * fourth-order central difference of the original expression at a
 * high-entropy state (x = 0.7371, y = 0.4123, t = 0.3217: no 0, 1 or pi/2
 * to hide a missing term).
 */
#include "testutil.h"

#include "../generator/dag/dag.h"
#include "../generator/diff/diff.h"

#include <stdlib.h>
#include <string.h>

enum { NQ = 2 };

typedef struct State {
    double q[NQ], qd[NQ], t;
} State;

static const State base_state = {{0.7371, 0.4123}, {0.5813, -0.2749}, 0.3217};

/* ---- the test's own evaluator ---- */

static double eval(const Dag *d, NodeId id, const State *s)
{
    const DagNode *n = dag_node(d, id);
    switch ((DagOp)n->op) {
    case OP_CONST: return n->value;
    case OP_VAR:   return s->q[n->a];
    case OP_VARD:  return s->qd[n->a];
    case OP_TIME:  return s->t;
    default: break;
    }
    double a = eval(d, n->a, s);
    double b = dag_op_info[n->op].arity == 2 ? eval(d, n->b, s) : 0.0;
    return dag_op_eval((DagOp)n->op, a, b);
}

/* Which variable a finite difference moves. */
typedef enum Var { VAR_Q, VAR_QD, VAR_T, VAR_PATH } Var;

/* The state moved by h along one variable; VAR_PATH moves along the motion
   q + h qd, t + h with qd fixed (the path the total derivative follows). */
static State moved(const State *s, Var var, int j, double h)
{
    State m = *s;
    switch (var) {
    case VAR_Q:  m.q[j] += h; break;
    case VAR_QD: m.qd[j] += h; break;
    case VAR_T:  m.t += h; break;
    case VAR_PATH:
        for (int i = 0; i < NQ; i++)
            m.q[i] += h * s->qd[i];
        m.t += h;
        break;
    }
    return m;
}

/* Fourth-order central difference: error h^4 f^(5) / 30, about 1e-13 here. */
static double fd(const Dag *d, NodeId e, const State *s, Var var, int j)
{
    const double h = 1e-3;
    State p1 = moved(s, var, j, h), m1 = moved(s, var, j, -h);
    State p2 = moved(s, var, j, 2 * h), m2 = moved(s, var, j, -2 * h);
    return (8.0 * (eval(d, e, &p1) - eval(d, e, &m1)) - (eval(d, e, &p2) - eval(d, e, &m2)))
           / (12.0 * h);
}

/* Second derivative along the path, also fourth order. */
static double fd2_path(const Dag *d, NodeId e, const State *s)
{
    const double h = 1e-2;
    State p1 = moved(s, VAR_PATH, 0, h), m1 = moved(s, VAR_PATH, 0, -h);
    State p2 = moved(s, VAR_PATH, 0, 2 * h), m2 = moved(s, VAR_PATH, 0, -2 * h);
    return (-eval(d, e, &p2) + 16.0 * eval(d, e, &p1) - 30.0 * eval(d, e, s)
            + 16.0 * eval(d, e, &m1) - eval(d, e, &m2)) / (12.0 * h * h);
}

/* ---- fixture ---- */

typedef struct Fixture {
    Dag dag;
    Differ df;
    NodeId x, y, t, xd, yd;
} Fixture;

static int setup(void **state)
{
    Fixture *f = calloc(1, sizeof *f);
    dag_init(&f->dag, 1000000);
    differ_init(&f->df, &f->dag, NQ);
    f->x = dag_var(&f->dag, 0);
    f->y = dag_var(&f->dag, 1);
    f->t = dag_time(&f->dag);
    f->xd = dag_vard(&f->dag, 0);
    f->yd = dag_vard(&f->dag, 1);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    Fixture *f = *state;
    differ_free(&f->df);
    dag_free(&f->dag);
    free(f);
    return 0;
}

static NodeId K(Fixture *f, double v) { return dag_const(&f->dag, v); }
static NodeId add(Fixture *f, NodeId a, NodeId b) { return dag_add(&f->dag, a, b); }
static NodeId sub(Fixture *f, NodeId a, NodeId b) { return dag_sub(&f->dag, a, b); }
static NodeId mul(Fixture *f, NodeId a, NodeId b) { return dag_mul(&f->dag, a, b); }
static NodeId dvd(Fixture *f, NodeId a, NodeId b) { return dag_div(&f->dag, a, b); }
static NodeId pw(Fixture *f, NodeId a, NodeId b) { return dag_pow(&f->dag, a, b); }
static NodeId fn1(Fixture *f, DagOp op, NodeId a) { return dag_call(&f->dag, op, a, DAG_NONE); }

/* u = 0.6 x + 0.2 y (0.525 here: inside asin's and log's domains),
   v = 0.3 x + 0.9 y: two different inner functions of both coordinates. */
static NodeId inner_u(Fixture *f) { return add(f, mul(f, K(f, 0.6), f->x), mul(f, K(f, 0.2), f->y)); }
static NodeId inner_v(Fixture *f) { return add(f, mul(f, K(f, 0.3), f->x), mul(f, K(f, 0.9), f->y)); }

/* Checks de/dq_j for both coordinates, and de/dt, against finite differences. */
static void check_partials(Fixture *f, NodeId e, const char *what)
{
    const Dag *d = &f->dag;
    const State *s = &base_state;
    double value = eval(d, e, s);
    if (!isfinite(value))
        fail_msg("%s: not finite at the test state", what);
    for (int j = 0; j < NQ; j++) {
        NodeId de = diff_by_q(&f->df, e, j);
        double got = eval(d, de, s), want = fd(d, e, s, VAR_Q, j);
        if (!(fabs(got - want) <= 1e-9 * fabs(want) + 1e-10))
            fail_msg("%s: d/dq%d = %.17g, finite difference %.17g", what, j, got, want);
    }
    NodeId dt = diff_by_t(&f->df, e);
    double got = eval(d, dt, s), want = fd(d, e, s, VAR_T, 0);
    if (!(fabs(got - want) <= 1e-9 * fabs(want) + 1e-10))
        fail_msg("%s: d/dt = %.17g, finite difference %.17g", what, got, want);
}

/* ---- one test per group of rules ---- */

static void test_arithmetic(void **state)
{
    Fixture *f = *state;
    NodeId x = f->x, y = f->y, u = inner_u(f), v = inner_v(f);
    NodeId sx = fn1(f, OP_SIN, x), ey = fn1(f, OP_EXP, y);
    check_partials(f, add(f, sx, mul(f, y, y)), "sin x + y y");
    check_partials(f, sub(f, sx, mul(f, x, ey)), "sin x - x exp y");
    check_partials(f, mul(f, x, y), "x y");
    check_partials(f, mul(f, sx, ey), "sin x exp y");
    check_partials(f, mul(f, u, v), "u v");
    check_partials(f, dvd(f, x, y), "x / y");
    check_partials(f, dvd(f, sx, add(f, DAG_ONE, mul(f, y, y))), "sin x / (1 + y^2)");
    check_partials(f, dvd(f, u, v), "u / v");
    check_partials(f, dvd(f, K(f, 2.5), mul(f, x, v)), "2.5 / (x v)");
    check_partials(f, dvd(f, x, K(f, 3.0)), "x / 3");
    NodeId n = dag_neg(&f->dag, mul(f, x, ey));
    assert_int_equal(dag_op(&f->dag, n), OP_NEG);
    check_partials(f, n, "-(x exp y)");
    n = dag_neg(&f->dag, fn1(f, OP_COS, dvd(f, u, v)));
    assert_int_equal(dag_op(&f->dag, n), OP_NEG);
    check_partials(f, n, "-cos(u / v)");
}

static void test_powers(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, y = f->y, u = inner_u(f), v = inner_v(f);
    /* constant exponents: the general rule (2.5, -1.5, 1.7) and the ones
       the graph turns into products, quotients or sqrt (3, -2, 0.5) */
    NodeId e = pw(f, u, K(f, 2.5));
    assert_int_equal(dag_op(d, e), OP_POW);
    check_partials(f, e, "u^2.5");
    check_partials(f, pw(f, v, K(f, -1.5)), "v^-1.5");
    check_partials(f, pw(f, add(f, x, y), K(f, 1.7)), "(x + y)^1.7");
    check_partials(f, pw(f, u, K(f, 3.0)), "u^3");
    check_partials(f, pw(f, v, K(f, -2.0)), "v^-2");
    check_partials(f, pw(f, u, K(f, 0.5)), "u^0.5");
    /* variable exponents: a^b (b' log a + b a'/a) */
    e = pw(f, x, y);
    assert_int_equal(dag_op(d, e), OP_POW);
    check_partials(f, e, "x^y");
    check_partials(f, pw(f, y, x), "y^x");
    check_partials(f, pw(f, u, mul(f, x, v)), "u^(x v)");
    check_partials(f, pw(f, K(f, 2.0), mul(f, x, y)), "2^(x y)");
    check_partials(f, pw(f, x, f->t), "x^t");
}

static void test_functions(void **state)
{
    Fixture *f = *state;
    NodeId u = inner_u(f), v = inner_v(f);
    for (int op = OP_SIN; op < OP_COUNT; op++) {
        char what[64];
        NodeId e;
        if (op == OP_ATAN2)
            e = dag_call(&f->dag, (DagOp)op, u, v);
        else
            e = fn1(f, (DagOp)op, u);
        assert_int_equal(dag_op(&f->dag, e), op);
        snprintf(what, sizeof what, "%s(u)", dag_op_info[op].spelling);
        check_partials(f, e, what);
        /* the function of a product: a chain factor that differs per coordinate */
        if (op == OP_ATAN2)
            e = dag_call(&f->dag, (DagOp)op, mul(f, f->x, f->y), sub(f, f->x, v));
        else
            e = fn1(f, (DagOp)op, mul(f, u, f->y));
        snprintf(what, sizeof what, "%s(u y)", dag_op_info[op].spelling);
        check_partials(f, e, what);
    }
    /* atan2 in every quadrant of (y, x) */
    NodeId nx = dag_neg(&f->dag, v);
    NodeId nu = dag_neg(&f->dag, u);
    check_partials(f, dag_call(&f->dag, OP_ATAN2, u, nx), "atan2(u, -v)");
    check_partials(f, dag_call(&f->dag, OP_ATAN2, nu, nx), "atan2(-u, -v)");
    check_partials(f, dag_call(&f->dag, OP_ATAN2, nu, v), "atan2(-u, v)");
}

static void test_time(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, y = f->y, t = f->t;
    /* a driver-like row with time-dependent coefficients */
    NodeId e = sub(f, mul(f, x, add(f, DAG_ONE, mul(f, K(f, 0.5), t))),
                   fn1(f, OP_SIN, mul(f, K(f, 2.0), t)));
    check_partials(f, e, "x (1 + 0.5 t) - sin 2t");
    check_partials(f, sub(f, mul(f, mul(f, t, t), y), DAG_ONE), "t^2 y - 1");
    check_partials(f, dvd(f, mul(f, t, x), add(f, DAG_ONE, t)), "t x / (1 + t)");
    check_partials(f, fn1(f, OP_EXP, mul(f, t, y)), "exp(t y)");
    /* leaf rules */
    assert_int_equal(diff_by_t(&f->df, t), DAG_ONE);
    assert_int_equal(diff_by_q(&f->df, t, 0), DAG_ZERO);
    assert_int_equal(diff_by_t(&f->df, x), DAG_ZERO);
    assert_int_equal(diff_by_t(&f->df, f->xd), DAG_ZERO);
    /* d/dt (x (1 + 0.5 t)) = 0.5 x exactly */
    NodeId g = mul(f, x, add(f, DAG_ONE, mul(f, K(f, 0.5), t)));
    assert_near(eval(d, diff_by_t(&f->df, g), &base_state), 0.5 * base_state.q[0], 1e-15, 0);
}

static void test_leaves_and_memo(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    assert_int_equal(diff_by_q(&f->df, f->x, 0), DAG_ONE);
    assert_int_equal(diff_by_q(&f->df, f->x, 1), DAG_ZERO);
    assert_int_equal(diff_by_q(&f->df, f->y, 1), DAG_ONE);
    assert_int_equal(diff_by_q(&f->df, K(f, 0.7371), 0), DAG_ZERO);
    assert_int_equal(diff_by_q(&f->df, f->xd, 0), DAG_ZERO);   /* qd is not q */
    assert_int_equal(diff_by_qd(&f->df, f->xd, 0), DAG_ONE);
    assert_int_equal(diff_by_qd(&f->df, f->xd, 1), DAG_ZERO);
    assert_int_equal(diff_by_qd(&f->df, f->x, 0), DAG_ZERO);
    /* an expression free of q_1 has the exact zero as derivative */
    NodeId e = fn1(f, OP_SIN, mul(f, f->x, f->t));
    assert_int_equal(diff_by_q(&f->df, e, 1), DAG_ZERO);
    /* memoised: asking again builds nothing and returns the same node */
    NodeId de = diff_by_q(&f->df, e, 0);
    int32_t count = d->count;
    assert_int_equal(diff_by_q(&f->df, e, 0), de);
    assert_int_equal(d->count, count);
    /* d sin(x t)/dx = t cos(x t): the cos node is shared with a direct build */
    NodeId c = fn1(f, OP_COS, mul(f, f->x, f->t));
    assert_int_equal(d->count, count);
    assert_int_equal(de, mul(f, c, f->t));
    /* d (x^2)/dx = 2 x, as a node */
    assert_int_equal(diff_by_q(&f->df, mul(f, f->x, f->x), 0), mul(f, K(f, 2.0), f->x));
}

static void test_velocity_partials(void **state)
{
    Fixture *f = *state;
    const Dag *d = &f->dag;
    NodeId x = f->x, y = f->y;
    /* a velocity-level row: cos(y) xd + x y yd + t x, and a non-affine one */
    NodeId psi = add(f, add(f, mul(f, fn1(f, OP_COS, y), f->xd), mul(f, mul(f, x, y), f->yd)),
                     mul(f, f->t, x));
    NodeId sq = mul(f, mul(f, f->xd, f->xd), fn1(f, OP_SIN, mul(f, x, f->yd)));
    NodeId exprs[2] = {psi, sq};
    for (int k = 0; k < 2; k++) {
        for (int j = 0; j < NQ; j++) {
            double got = eval(d, diff_by_qd(&f->df, exprs[k], j), &base_state);
            double want = fd(d, exprs[k], &base_state, VAR_QD, j);
            assert_near(got, want, 1e-9, 1e-10);
            got = eval(d, diff_by_q(&f->df, exprs[k], j), &base_state);
            want = fd(d, exprs[k], &base_state, VAR_Q, j);
            assert_near(got, want, 1e-9, 1e-10);
        }
    }
    /* the coefficient of der(x) in an affine row is free of qd */
    assert_near(eval(d, diff_by_qd(&f->df, psi, 0), &base_state), cos(base_state.q[1]), 1e-15, 0);
}

/* ---- the total time derivative ---- */

static void test_total_leaves(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    assert_int_equal(diff_total(&f->df, f->x), dag_vard(d, 0));   /* D(q) = qd */
    assert_int_equal(diff_total(&f->df, f->y), dag_vard(d, 1));
    assert_int_equal(diff_total(&f->df, f->t), DAG_ONE);           /* D(t) = 1 */
    assert_int_equal(diff_total(&f->df, f->xd), DAG_ZERO);         /* D(qd) = 0: qdd left out */
    assert_int_equal(diff_total(&f->df, K(f, 0.7371)), DAG_ZERO);
    /* D(x y) = xd y + x yd */
    NodeId xy = mul(f, f->x, f->y);
    NodeId want = add(f, mul(f, f->xd, f->y), mul(f, f->x, f->yd));
    assert_near(eval(d, diff_total(&f->df, xy), &base_state), eval(d, want, &base_state), 1e-15, 0);
    /* D(D(x)) = 0: no acceleration term */
    assert_int_equal(diff_total(&f->df, diff_total(&f->df, f->x)), DAG_ZERO);
}

static void test_total_along_path(void **state)
{
    Fixture *f = *state;
    const Dag *d = &f->dag;
    NodeId x = f->x, y = f->y, t = f->t, u = inner_u(f);
    NodeId exprs[] = {
        /* distance-like, revolute-like and driver-like position rows */
        sub(f, add(f, mul(f, x, x), mul(f, y, y)), K(f, 4.0)),
        sub(f, add(f, x, mul(f, K(f, 0.5), fn1(f, OP_COS, y))), mul(f, K(f, 0.3), fn1(f, OP_SIN, t))),
        sub(f, mul(f, y, add(f, DAG_ONE, mul(f, K(f, 0.5), t))), fn1(f, OP_SIN, mul(f, K(f, 2.0), t))),
        mul(f, dag_call(&f->dag, OP_ATAN2, u, y), fn1(f, OP_EXP, mul(f, t, x))),
        pw(f, u, add(f, x, t)),
    };
    for (size_t k = 0; k < sizeof exprs / sizeof *exprs; k++) {
        NodeId e = exprs[k];
        NodeId de = diff_total(&f->df, e), dde = diff_total(&f->df, de);
        /* D(Phi) = Phi_q qd + Phi_t = d/ds Phi(q + s qd, t + s) */
        assert_near(eval(d, de, &base_state), fd(d, e, &base_state, VAR_PATH, 0), 1e-9, 1e-10);
        /* D(D(Phi)) = d^2/ds^2 Phi(q + s qd, t + s): the straight path has no qdd */
        assert_near(eval(d, dde, &base_state), fd(d, de, &base_state, VAR_PATH, 0), 1e-9, 1e-10);
        assert_near(eval(d, dde, &base_state), fd2_path(d, e, &base_state), 1e-7, 1e-8);
        /* and by the formula (Phi_q qd)_q qd + 2 Phi_qt qd + Phi_tt, each
           part from the partial derivatives */
        double sum = eval(d, diff_by_t(&f->df, diff_by_t(&f->df, e)), &base_state);
        for (int i = 0; i < NQ; i++) {
            NodeId di = diff_by_q(&f->df, e, i);
            sum += 2.0 * eval(d, diff_by_t(&f->df, di), &base_state) * base_state.qd[i];
            for (int j = 0; j < NQ; j++)
                sum += eval(d, diff_by_q(&f->df, di, j), &base_state) * base_state.qd[i]
                       * base_state.qd[j];
        }
        assert_near(eval(d, dde, &base_state), sum, 1e-12, 1e-13);
    }
}

static void test_total_velocity_row(void **state)
{
    Fixture *f = *state;
    const Dag *d = &f->dag;
    NodeId x = f->x, y = f->y, t = f->t;
    /* Psi = a(q, t)^T qd + b(q, t); D(Psi) = Psi_q qd + Psi_t (qdd dropped) */
    NodeId a0 = fn1(f, OP_COS, y), a1 = mul(f, x, add(f, DAG_ONE, t));
    NodeId b = sub(f, mul(f, K(f, 0.5), mul(f, t, t)), fn1(f, OP_SIN, x));
    NodeId psi = add(f, add(f, mul(f, a0, f->xd), mul(f, a1, f->yd)), b);
    NodeId dpsi = diff_total(&f->df, psi);
    /* with qd held fixed, moving along q + s qd, t + s */
    assert_near(eval(d, dpsi, &base_state), fd(d, psi, &base_state, VAR_PATH, 0), 1e-9, 1e-10);
    /* by hand: -sin(y) yd xd + (1 + t) xd yd + x yd + t - cos(x) xd */
    const State *s = &base_state;
    double xv = s->q[0], yv = s->q[1], xd = s->qd[0], yd = s->qd[1], tv = s->t;
    double want = -sin(yv) * yd * xd + (1 + tv) * xd * yd + xv * yd + tv - cos(xv) * xd;
    assert_near(eval(d, dpsi, s), want, 1e-13, 1e-15);
}

static void test_without_velocities(void **state)
{
    Fixture *f = *state;
    Dag *d = &f->dag;
    NodeId x = f->x, y = f->y, t = f->t;
    NodeId a0 = fn1(f, OP_COS, y), a1 = mul(f, x, t);
    NodeId b = sub(f, mul(f, K(f, 0.5), t), fn1(f, OP_SIN, x));
    NodeId psi = add(f, add(f, mul(f, a0, f->xd), mul(f, a1, f->yd)), b);
    NodeId r = diff_without_velocities(&f->df, psi);
    /* the same function as b whatever qd is */
    State s = base_state;
    assert_near(eval(d, r, &s), eval(d, b, &s), 1e-15, 1e-16);
    s.qd[0] = 17.3;
    s.qd[1] = -4.1;
    assert_near(eval(d, r, &s), eval(d, b, &s), 1e-15, 1e-16);
    assert_near(eval(d, r, &s), 0.5 * s.t - sin(s.q[0]), 1e-15, 1e-16);
    /* an expression without velocities comes back as the same node */
    NodeId e = fn1(f, OP_EXP, mul(f, x, t));
    assert_int_equal(diff_without_velocities(&f->df, e), e);
    /* pure velocity terms vanish */
    assert_int_equal(diff_without_velocities(&f->df, mul(f, f->xd, f->yd)), DAG_ZERO);
    assert_int_equal(diff_without_velocities(&f->df, f->xd), DAG_ZERO);
    /* der(x) - 1: b is the constant -1 */
    double c;
    assert_true(dag_is_const(d, diff_without_velocities(&f->df, sub(f, f->xd, DAG_ONE)), &c));
    assert_near(c, -1.0, 0, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_arithmetic, setup, teardown),
        cmocka_unit_test_setup_teardown(test_powers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_functions, setup, teardown),
        cmocka_unit_test_setup_teardown(test_time, setup, teardown),
        cmocka_unit_test_setup_teardown(test_leaves_and_memo, setup, teardown),
        cmocka_unit_test_setup_teardown(test_velocity_partials, setup, teardown),
        cmocka_unit_test_setup_teardown(test_total_leaves, setup, teardown),
        cmocka_unit_test_setup_teardown(test_total_along_path, setup, teardown),
        cmocka_unit_test_setup_teardown(test_total_velocity_row, setup, teardown),
        cmocka_unit_test_setup_teardown(test_without_velocities, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
