/* test_analysis.c - runtime/analysis.c: velocity, acceleration and steps, hand-written kernels. */
#include "testrt.h"

/* One element short is MECHRT_EBADLEN everywhere, and nothing is touched. */
static void test_workspace_too_small(void **state)
{
    (void)state;
    size_t need = mechrt_workspace_size(3, 3);
    double *work = xmalloc(need), q[3] = {0.8, 0.1, 0.4}, qd[3] = {0}, qdd[3] = {0};
    MechrtReport rep;

    assert_int_equal(mechrt_assemble(&sc_kernels, NULL, q, 0.3, work, need - 1, &rep),
                     MECHRT_EBADLEN);
    assert_int_equal(rep.iterations, 0);
    assert_near(q[0], 0.8, 0, 0);
    assert_int_equal(mechrt_velocity(&sc_kernels, NULL, q, 0.3, qd, work, need - 1, NULL),
                     MECHRT_EBADLEN);
    assert_int_equal(mechrt_acceleration(&sc_kernels, NULL, q, qd, 0.3, qdd, work, need - 1,
                                         NULL),
                     MECHRT_EBADLEN);
    qd[0] = 1;
    assert_int_equal(mechrt_step(&sc_kernels, NULL, q, qd, qdd, 0.3, 0.01, work, need - 1,
                                 &rep),
                     MECHRT_EBADLEN);
    assert_near(q[0], 0.8, 0, 0);   /* the predictor did not run */
    free(work);
}

/* ---- analysis ---------------------------------------------------------- */

/* Velocity and acceleration of the slider crank at its exact configuration
   against the hand-derived values; separately and with one factorisation. */
static void test_velocity_acceleration(void **state)
{
    (void)state;
    const double t = 0.83;
    double q[3], qd[3], qdd[3], v[3], a[3], v2[3], a2[3], work[64];
    MechrtReport rep;
    MechrtOptions always = mechrt_default_options();

    always.cond_screen = 0;   /* estimate even when the pivots say it is not needed */
    sc_exact(t, q, qd, qdd);
    assert_int_equal(mechrt_velocity(&sc_kernels, &always, q, t, v, work, 64, &rep), MECHRT_OK);
    assert_true(rep.cond >= 1 && !rep.cond_warning);
    /* by default the pivots' spread screens the well-conditioned matrix out */
    assert_int_equal(mechrt_velocity(&sc_kernels, NULL, q, t, v, work, 64, &rep), MECHRT_OK);
    assert_true(rep.cond == 0 && !rep.cond_warning);
    assert_int_equal(mechrt_acceleration(&sc_kernels, NULL, q, qd, t, a, work, 64, NULL),
                     MECHRT_OK);
    assert_int_equal(mechrt_velocity_acceleration(&sc_kernels, NULL, q, t, v2, a2, work, 64,
                                                  NULL),
                     MECHRT_OK);
    for (int i = 0; i < 3; i++) {
        assert_near(v[i], qd[i], 1e-12, 1e-14);
        assert_near(a[i], qdd[i], 1e-12, 1e-14);
        assert_near(v2[i], qd[i], 1e-12, 1e-14);
        assert_near(a2[i], qdd[i], 1e-12, 1e-14);
    }
}

/* The knife-edge cart: Jacobian with velocity-level rows, NR == NQ. */
static void test_velocity_rows(void **state)
{
    (void)state;
    const double t = 0.6, th = KN_B + KN_W * t;
    double q[3] = {0.3, -0.2, th}, qd[3], qdd[3], work[64];
    MechrtReport rep;
    MechrtOptions always = mechrt_default_options();

    always.cond_screen = 0;
    assert_int_equal(mechrt_velocity_acceleration(&kn_kernels, &always, q, t, qd, qdd, work, 64,
                                                  &rep),
                     MECHRT_OK);
    assert_near(qd[0], KN_V * cos(th), 1e-13, 1e-15);
    assert_near(qd[1], KN_V * sin(th), 1e-13, 1e-15);
    assert_near(qd[2], KN_W, 1e-13, 1e-15);
    assert_near(qdd[0], -KN_V * KN_W * sin(th), 1e-13, 1e-15);
    assert_near(qdd[1], KN_V * KN_W * cos(th), 1e-13, 1e-15);
    assert_near(qdd[2], 0.0, 0, 1e-15);
    assert_true(rep.cond >= 1 && rep.cond < 10);   /* orthogonal rows */

    /* positions come from the host's integrator: no stepping here */
    assert_int_equal(mechrt_step(&kn_kernels, NULL, q, qd, qdd, t, 0.01, work, 64, NULL),
                     MECHRT_ENOTSQUARE);
}

/* Near the dead point the solve works but the estimate warns. */
static void test_condition_warning(void **state)
{
    (void)state;
    const double eps = 1e-7;
    double q[2] = {CI_R * cos(eps), CI_R * sin(eps)}, qd[2], work[64];
    MechrtOptions o = mechrt_default_options();
    MechrtReport rep;

    o.cond_warn = 1e5;
    assert_int_equal(mechrt_velocity(&ci_kernels, &o, q, 0.0, qd, work, 64, &rep), MECHRT_OK);
    assert_true(rep.cond > 1e6);
    assert_true(rep.cond_warning);
    o.cond_warn = 0;   /* estimate off */
    assert_int_equal(mechrt_velocity(&ci_kernels, &o, q, 0.0, qd, work, 64, &rep), MECHRT_OK);
    assert_near(rep.cond, 0.0, 0, 0);
    assert_false(rep.cond_warning);
    /* with the defaults the pivot screen opens and the estimate warns
       (cond ~ 2.6 / (1.6 * 0.8 * eps'), about 5e10) */
    q[0] = CI_R * cos(5e-11);
    q[1] = CI_R * sin(5e-11);
    assert_int_equal(mechrt_velocity(&ci_kernels, NULL, q, 0.0, qd, work, 64, &rep), MECHRT_OK);
    assert_true(rep.cond > 1e10);
    assert_true(rep.cond_warning);
    /* exactly on it: singular, column 1 */
    q[0] = CI_R;
    q[1] = 0;
    assert_int_equal(mechrt_velocity(&ci_kernels, NULL, q, 0.0, qd, work, 64, &rep),
                     MECHRT_ESING);
    assert_int_equal(rep.sing_index, 1);
    /* not square */
    MechrtKernels two = ci_kernels;
    two.nh = 1;
    assert_int_equal(mechrt_velocity(&two, NULL, q, 0.0, qd, work, 64, &rep),
                     MECHRT_ENOTSQUARE);
}

static void huge_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    (void)q;
    (void)qd;
    (void)t;
    g[0] = 1e305;
    g[1] = -1e305;
}

static void nan_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    ci_nu(ctx, q, t, nu);
    nu[0] = NAN;
}

/* NaN from a kernel, or an overflowing solve, is MECHRT_ENOTFINITE. */
static void test_analysis_not_finite(void **state)
{
    (void)state;
    double q[2] = {CI_R * cos(1e-7), CI_R * sin(1e-7)}, qd[2] = {0.1, 0.2}, x[2], work[64];
    MechrtKernels k = ci_kernels;

    k.gamma = huge_gamma;
    assert_int_equal(mechrt_acceleration(&k, NULL, q, qd, 0.0, x, work, 64, NULL),
                     MECHRT_ENOTFINITE);
    k = ci_kernels;
    k.nu = nan_nu;
    assert_int_equal(mechrt_velocity(&k, NULL, q, 0.0, x, work, 64, NULL), MECHRT_ENOTFINITE);
}

/* A run: assemble at t0 with h = 0 from the rough initial values, then 40
   steps; every state exact to 1e-12, the predictor keeping Newton short. */
static void test_step_run(void **state)
{
    (void)state;
    const double h = 0.05;
    double q[3], qd[3], qdd[3], eq[3], eqd[3], eqdd[3];
    double work[64];
    MechrtReport rep;
    const MechrtKernels *ks[2] = {&sc_kernels, &sc_kernels_noall};
    MechrtOptions always = mechrt_default_options();

    always.cond_screen = 0;
    for (int v = 0; v < 2; v++) {
        double t = 0;
        sc_exact(0, eq, eqd, eqdd);
        q[0] = eq[0] + 0.1;   /* the mechanism file's rough initial values */
        q[1] = eq[1] - 0.1;
        q[2] = eq[2] + 0.02;
        for (int i = 0; i < 3; i++)
            qd[i] = qdd[i] = 0;
        for (int step = 0; step <= 40; step++) {
            double hh = step == 0 ? 0 : h;
            MechrtStatus st = mechrt_step(ks[v], &always, q, qd, qdd, t, hh, work, 64, &rep);
            if (st != MECHRT_OK)
                fail_msg("t = %g: %s", t + hh, mechrt_strerror(st));
            t += hh;
            sc_exact(t, eq, eqd, eqdd);
            for (int i = 0; i < 3; i++) {
                assert_near(q[i], eq[i], 0, 1e-12);
                assert_near(qd[i], eqd[i], 1e-11, 1e-12);
                assert_near(qdd[i], eqdd[i], 1e-11, 1e-12);
            }
            if (step > 0)
                assert_true(rep.iterations <= 3);
            assert_true(rep.cond >= 1 && !rep.cond_warning);
        }
    }
}

/* GSL's LU solve of the n x n row-major a against b (a is left alone). */
static void ref_solve(int n, const double *a, const double *b, double *x)
{
    gsl_matrix *m = gsl_matrix_alloc((size_t)n, (size_t)n);
    gsl_permutation *p = gsl_permutation_alloc((size_t)n);
    gsl_vector_const_view bv = gsl_vector_const_view_array(b, (size_t)n);
    gsl_vector_view xv = gsl_vector_view_array(x, (size_t)n);
    int sign;

    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            gsl_matrix_set(m, (size_t)i, (size_t)j, a[i * n + j]);
    gsl_linalg_LU_decomp(m, p, &sign);
    gsl_linalg_LU_solve(m, p, &bv.vector, &xv.vector);
    gsl_permutation_free(p);
    gsl_matrix_free(m);
}

/* The step written out plainly, with GSL's LU: Taylor predictor, Newton
   until the runtime's test passes (fresh Jacobian every iteration), then
   velocity and acceleration at the converged q. Returns the iterations. */
static int ref_step(double *q, double *qd, double *qdd, double t, double h,
                    const MechrtOptions *o)
{
    double phi[3], jac[9], nu[3], g[3], dq[3], mphi[3], step = -1, res;
    int it = 0;

    for (int i = 0; i < 3; i++)
        q[i] += h * qd[i] + 0.5 * h * h * qdd[i];
    for (;;) {
        sc_phi(NULL, q, t + h, phi);
        res = 0;
        for (int i = 0; i < 3; i++)
            res = fmax(res, fabs(phi[i]));
        if (step >= 0 && res <= o->tol_phi && step <= o->tol_dq)
            break;
        sc_jac(NULL, q, t + h, jac);
        for (int i = 0; i < 3; i++)
            mphi[i] = -phi[i];
        ref_solve(3, jac, mphi, dq);
        step = 0;
        for (int i = 0; i < 3; i++) {
            q[i] += dq[i];
            step = fmax(step, fabs(dq[i]));
        }
        it++;
    }
    sc_jac(NULL, q, t + h, jac);
    sc_nu(NULL, q, t + h, nu);
    ref_solve(3, jac, nu, qd);
    sc_gamma(NULL, q, qd, t + h, g);
    ref_solve(3, jac, g, qdd);
    return it;
}

/* mechrt_step against the plain reference, value by value to 1e-12
   relative, over a revolution in coarse (several Newton iterations) and
   fine (one) steps; and its cost: one factorisation per Newton iteration
   and one for velocity and acceleration together, so two per fine step. */
static void test_step_reference(void **state)
{
    (void)state;
    const int steps[2] = {20, 2000};
    double work[64];
    MechrtOptions o = mechrt_default_options();

    for (int v = 0; v < 2; v++) {
        double q[3], qd[3], qdd[3], rq[3], rqd[3], rqdd[3], t = 0, h = 1.0 / steps[v];
        MechrtReport rep;
        int one_iteration = 0;

        sc_exact(0, q, qd, qdd);
        for (int i = 0; i < 3; i++)
            rq[i] = q[i], rqd[i] = qd[i], rqdd[i] = qdd[i];
        for (int s = 0; s < steps[v]; s++, t += h) {
            assert_int_equal(mechrt_step(&sc_kernels, &o, q, qd, qdd, t, h, work, 64, &rep),
                             MECHRT_OK);
            int it = ref_step(rq, rqd, rqdd, t, h, &o);
            assert_int_equal(rep.iterations, it);
            assert_int_equal(rep.factorisations, it + 1);
            one_iteration += it == 1;
            for (int i = 0; i < 3; i++) {
                assert_near(q[i], rq[i], 1e-12, 1e-15);
                assert_near(qd[i], rqd[i], 1e-12, 1e-15);
                assert_near(qdd[i], rqdd[i], 1e-12, 1e-15);
            }
        }
        if (v == 1)
            assert_int_equal(one_iteration, steps[v]);   /* fine steps: 2 factorisations */
        else
            assert_true(one_iteration < steps[v]);       /* coarse: the test can fail */
    }
}

/* The predictor is second order: from an exact state its error is O(h^3),
   so one Newton correction of that size meets a 5e-4 step tolerance. A
   first-order predictor (error h^2/2 |qdd| ~ 3e-3 here) would not. */
static void test_step_predictor(void **state)
{
    (void)state;
    const double t = 0.4, h = 0.05;
    double q[3], qd[3], qdd[3], eq[3], eqd[3], eqdd[3], work[64];
    MechrtOptions o = mechrt_default_options();
    MechrtReport rep;

    o.max_iter = 1;
    o.tol_dq = 5e-4;
    o.tol_phi = 1e-6;
    sc_exact(t, q, qd, qdd);
    assert_int_equal(mechrt_step(&sc_kernels, &o, q, qd, qdd, t, h, work, 64, &rep),
                     MECHRT_OK);
    assert_int_equal(rep.iterations, 1);
    assert_true(rep.step > 0 && rep.step < 2e-4);
    sc_exact(t + h, eq, eqd, eqdd);
    for (int i = 0; i < 3; i++)
        assert_near(q[i], eq[i], 0, 1e-7);   /* one step: error ~ step^2 */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_workspace_too_small),
        cmocka_unit_test(test_velocity_acceleration),
        cmocka_unit_test(test_velocity_rows),
        cmocka_unit_test(test_condition_warning),
        cmocka_unit_test(test_analysis_not_finite),
        cmocka_unit_test(test_step_run),
        cmocka_unit_test(test_step_predictor),
        cmocka_unit_test(test_step_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
