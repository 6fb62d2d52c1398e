/* test_newton.c - runtime/newton.c: assembly by Newton's method on hand-written kernels. */
#include "testrt.h"

/* ---- Newton ------------------------------------------------------------ */

/* From a guess 0.3 rad and 3 cm off, assembly converges in a few
   iterations to the exact configuration, with and without `all`. */
static void test_newton_converges(void **state)
{
    (void)state;
    const double t = 0.37;
    double exact[3], qd[3], qdd[3], work[64];
    MechrtReport rep;
    const MechrtKernels *ks[2] = {&sc_kernels, &sc_kernels_noall};

    sc_exact(t, exact, qd, qdd);
    for (int v = 0; v < 2; v++) {
        double q[3] = {exact[0] + 0.3, exact[1] - 0.25, exact[2] + 0.03};
        sc_all_calls = 0;
        assert_int_equal(mechrt_assemble(ks[v], NULL, q, t, work, 64, &rep), MECHRT_OK);
        assert_true(rep.iterations >= 2 && rep.iterations <= 6);
        assert_true(rep.residual <= 1e-14);
        assert_true(rep.step >= 0 && rep.step <= 1e-8);
        assert_int_equal(rep.sing_index, -1);
        assert_true(rep.worst_row >= 0 && rep.worst_row < 3);
        assert_int_equal(sc_all_calls, v == 0 ? rep.iterations + 1 : 0);
        for (int i = 0; i < 3; i++)
            assert_near(q[i], exact[i], 0, 1e-12);
    }
}

/* The decomposed interface: residuals fall quadratically, test says
   CONTINUE until both norms are small. */
static void test_newton_decomposed(void **state)
{
    (void)state;
    const double t = 1.234;
    double exact[3], qd[3], qdd[3], work[64], res[16];
    double q[3];
    MechrtNewton s;
    int k = 0;

    sc_exact(t, exact, qd, qdd);
    q[0] = exact[0] - 0.2;
    q[1] = exact[1] + 0.15;
    q[2] = exact[2] - 0.05;
    assert_int_equal(mechrt_newton_init(&s, &sc_kernels, NULL, q, t, work, 64), MECHRT_OK);
    assert_int_equal(mechrt_newton_test(&s), MECHRT_CONTINUE);   /* no step yet */
    res[k++] = s.residual;
    while (mechrt_newton_test(&s) == MECHRT_CONTINUE) {
        assert_true(k < 16);
        assert_int_equal(mechrt_newton_iterate(&s), MECHRT_OK);
        res[k++] = s.residual;
    }
    assert_int_equal(s.iter, k - 1);
    /* quadratic: once below 1e-2, each residual is below 10 x the square
       of the one before (or at rounding level) */
    for (int i = 1; i < k; i++)
        if (res[i - 1] < 1e-2)
            assert_true(res[i] <= 10 * res[i - 1] * res[i - 1] + 1e-15);
    for (int i = 0; i < 3; i++)
        assert_near(q[i], exact[i], 0, 1e-12);
}

/* max_iter = 1 from a far start: one iteration, then MECHRT_EMAXITER. */
static void test_newton_maxiter(void **state)
{
    (void)state;
    double q[3] = {5.0, -3.0, 2.5}, work[64];
    MechrtOptions o = mechrt_default_options();
    MechrtReport rep;

    o.max_iter = 1;
    assert_int_equal(mechrt_assemble(&sc_kernels, &o, q, 0.37, work, 64, &rep),
                     MECHRT_EMAXITER);
    assert_int_equal(rep.iterations, 1);
    assert_true(rep.residual > o.tol_phi);
    assert_true(rep.step > o.tol_dq);
    assert_true(rep.worst_row >= 0 && rep.worst_row < 3);
}

/* Starting on the dead point y = 0: Phi_q = [[2x, 0], [1, 0]] has a zero
   second column, so the first factorisation fails at column 1. */
static void test_newton_singular(void **state)
{
    (void)state;
    double q[2] = {CI_R, 0.0}, work[64];
    MechrtReport rep;

    assert_int_equal(mechrt_assemble(&ci_kernels, NULL, q, 0.0, work, 64, &rep),
                     MECHRT_ESING);
    assert_int_equal(rep.sing_index, 1);
    assert_int_equal(rep.iterations, 0);
    assert_near(q[0], CI_R, 0, 0);   /* q left where the failure happened */
    assert_near(q[1], 0.0, 0, 0);
    assert_int_equal(rep.worst_row, 1);
}

static void test_newton_errors(void **state)
{
    (void)state;
    double q[3] = {0.8, 0.1, 0.4}, work[64];
    MechrtReport rep;
    MechrtKernels bad = sc_kernels;

    /* NH < NQ: the host's minimum-norm Newton, not ours */
    assert_int_equal(mechrt_assemble(&kn_kernels, NULL, q, 0.0, work, 64, &rep),
                     MECHRT_ENOTSQUARE);
    /* NH == NQ with a velocity row after: Newton on the holonomic block */
    double exact[3], qd[3], qdd[3];
    sc_exact(0.0, exact, qd, qdd);
    assert_int_equal(mechrt_assemble(&scv_kernels, NULL, q, 0.0, work, 64, &rep), MECHRT_OK);
    for (int i = 0; i < 3; i++)
        assert_near(q[i], exact[i], 0, 1e-12);
    assert_int_equal(mechrt_step(&scv_kernels, NULL, q, qd, qdd, 0.0, 0.0, work, 64, &rep),
                     MECHRT_ENOTSQUARE);
    assert_int_equal(mechrt_velocity(&scv_kernels, NULL, q, 0.0, qd, work, 64, &rep),
                     MECHRT_ENOTSQUARE);
    assert_int_equal(mechrt_assemble(&scv_kernels, NULL, q, 0.0, work,
                                     mechrt_workspace_size(3, 3), &rep),
                     MECHRT_EBADLEN);   /* sized for NR = 4, not 3 */

    assert_int_equal(mechrt_assemble(&nan_kernels, NULL, q, 0.0, work, 64, &rep),
                     MECHRT_ENOTFINITE);
    assert_int_equal(rep.worst_row, 1);
    assert_int_equal(mechrt_assemble(NULL, NULL, q, 0.0, work, 64, &rep), MECHRT_EINVAL);
    assert_int_equal(mechrt_assemble(&sc_kernels, NULL, NULL, 0.0, work, 64, &rep),
                     MECHRT_EINVAL);
    bad.all = NULL;
    bad.jac = NULL;
    assert_int_equal(mechrt_assemble(&bad, NULL, q, 0.0, work, 64, &rep), MECHRT_EINVAL);
    bad = sc_kernels;
    bad.nq = 0;
    assert_int_equal(mechrt_assemble(&bad, NULL, q, 0.0, work, 64, &rep), MECHRT_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_newton_converges),
        cmocka_unit_test(test_newton_decomposed),
        cmocka_unit_test(test_newton_maxiter),
        cmocka_unit_test(test_newton_singular),
        cmocka_unit_test(test_newton_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
