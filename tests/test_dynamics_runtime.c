/* test_dynamics_runtime.c - forward and inverse dynamics (runtime/dynamics.c), hand-written kernels. */
#include "testutil.h"

#include "../generator/dyn/sim.h"
#include "../runtime/mechrt.h"

#include <gsl/gsl_linalg.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "testplanar.h"

/* (a) The pendulum: (J + m l^2) phi'' = -m g l cos(phi), and the pin force. */
static void test_pendulum_forward(void **state)
{
    (void)state;
    double m = 2.0, J = 0.05, l = 0.7, phi = 0.4, w = 1.3;
    TMech tm = pendulum(m, J, l);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[3], qd[3], qdd[3], lam[2];
    pendulum_state(l, phi, w, q, qd);
    MechrtDynReport rep;
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, lam, work, lw, &rep),
                     MECHRT_OK);
    double a = -m * tm.g * l * cos(phi) / (J + m * l * l);
    double xdd = -l * sin(phi) * a - l * cos(phi) * w * w;
    double ydd = l * cos(phi) * a - l * sin(phi) * w * w;
    assert_near(qdd[2], a, 1e-13, 1e-14);
    assert_near(qdd[0], xdd, 1e-13, 1e-14);
    assert_near(qdd[1], ydd, 1e-13, 1e-14);
    /* m xdd + lambda_1 = 0, m ydd + lambda_2 = -m g */
    assert_near(lam[0], -m * xdd, 1e-12, 1e-13);
    assert_near(lam[1], -m * tm.g - m * ydd, 1e-12, 1e-13);
    assert_int_equal(rep.rank, 2);
    assert_int_equal(rep.redundant, 0);
    free(work);
}

/* The double pendulum's accelerations from Lagrange's equations in the
   two angles (centres of mass at a1 and a2 from the pins, body 1 of
   length L1). */
static void double_pendulum_closed(const TMech *tm, double a1, double L1, double a2,
                                   const double *q, const double *qd, double *expect)
{
    double m1 = tm->m[0], m2 = tm->m[1], J1 = tm->J[0], J2 = tm->J[1], g = tm->g;
    double p1 = q[2], p2 = q[5], w1 = qd[2], w2 = qd[5], s12 = sin(p1 - p2);
    double A11 = m1 * a1 * a1 + J1 + m2 * L1 * L1, A22 = m2 * a2 * a2 + J2;
    double A12 = m2 * L1 * a2 * cos(p1 - p2);
    double b1 = -m2 * L1 * a2 * s12 * w2 * w2 - (m1 * a1 + m2 * L1) * g * cos(p1);
    double b2 = m2 * L1 * a2 * s12 * w1 * w1 - m2 * g * a2 * cos(p2);
    double det = A11 * A22 - A12 * A12;
    double e1 = (A22 * b1 - A12 * b2) / det, e2 = (A11 * b2 - A12 * b1) / det;
    /* r1 = a1 e(p1), r2 = L1 e(p1) + a2 e(p2): r'' = e'(p) p'' - e(p) p'^2 */
    expect[0] = a1 * (-sin(p1) * e1 - cos(p1) * w1 * w1);
    expect[1] = a1 * (cos(p1) * e1 - sin(p1) * w1 * w1);
    expect[2] = e1;
    expect[3] = L1 * (-sin(p1) * e1 - cos(p1) * w1 * w1) + a2 * (-sin(p2) * e2 - cos(p2) * w2 * w2);
    expect[4] = L1 * (cos(p1) * e1 - sin(p1) * w1 * w1) + a2 * (cos(p2) * e2 - sin(p2) * w2 * w2);
    expect[5] = e2;
}

static void test_double_pendulum_forward(void **state)
{
    (void)state;
    double a1 = 0.3, b1 = 0.25, a2 = 0.4, L1 = a1 + b1;
    TMech tm = double_pendulum(a1, b1, a2);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[6], qd[6], qdd[6], expect[6];
    double angles[3][2] = {{-1.2, 0.4}, {0.3, 2.9}, {-2.0, -0.1}}, rates[3][2] = {{0, 0}, {1.5, -2.0}, {-3, 4}};
    for (int c = 0; c < 3; c++) {
        double_state(a1, L1, a2, angles[c], rates[c], q, qd);
        assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw, NULL),
                         MECHRT_OK);
        double_pendulum_closed(&tm, a1, L1, a2, q, qd, expect);
        for (int i = 0; i < 6; i++)
            assert_near(qdd[i], expect[i], 1e-11, 1e-12);
    }
    free(work);
}

/* A free body (no rows): qdd = M^-1 Q. */
static void test_free_body(void **state)
{
    (void)state;
    TMech tm = {.nb = 1, .npin = 0, .m = {3}, .J = {0.4}, .c = {0.2}, .driver = -1, .g = 9.81};
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[3] = {0.1, 0.2, 0.3}, qd[3] = {0, 0, 2}, qdd[3];
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw, NULL),
                     MECHRT_OK);
    /* the centre of mass falls freely, the body spins on (no torque about it) */
    double p = q[2], w = qd[2], c = 0.2;
    double ang = 0;                            /* J phi'' = 0 about the centre of mass */
    double comx = qdd[0] - c * sin(p) * qdd[2] - c * cos(p) * w * w;
    double comy = qdd[1] + c * cos(p) * qdd[2] - c * sin(p) * w * w;
    assert_near(qdd[2], ang, 0, 1e-12);
    assert_near(comx, 0, 0, 1e-12);
    assert_near(comy, -9.81, 1e-13, 1e-12);
    free(work);
}

/* lambda_pinv = pinv(Phi_q^T) r by GSL's SVD: the minimum-norm solution. */
static void pinv_transpose_solve(const double *jac, int m, int n, const double *r, double *lam)
{
    gsl_matrix *a = gsl_matrix_alloc((size_t)n, (size_t)m), *v = gsl_matrix_alloc((size_t)m, (size_t)m);
    gsl_vector *s = gsl_vector_alloc((size_t)m), *work = gsl_vector_alloc((size_t)m);
    for (int i = 0; i < m; i++)
        for (int j = 0; j < n; j++)
            gsl_matrix_set(a, (size_t)j, (size_t)i, jac[i * n + j]);
    gsl_linalg_SV_decomp(a, v, s, work);      /* Phi_q^T = U S V^T */
    double smax = gsl_vector_get(s, 0);
    for (int i = 0; i < m; i++)
        lam[i] = 0;
    for (int c = 0; c < m; c++) {
        double sc = gsl_vector_get(s, (size_t)c);
        if (sc <= 1e-10 * smax)
            continue;
        double ur = 0;
        for (int j = 0; j < n; j++)
            ur += gsl_matrix_get(a, (size_t)j, (size_t)c) * r[j];
        for (int i = 0; i < m; i++)
            lam[i] += gsl_matrix_get(v, (size_t)i, (size_t)c) * ur / sc;
    }
    gsl_matrix_free(a), gsl_matrix_free(v), gsl_vector_free(s), gsl_vector_free(work);
}

static void test_redundant_parallelogram(void **state)
{
    (void)state;
    double L = 0.4, d = 0.5, th = 0.7, w = -1.1;
    TMech tm = parallelogram(L, d);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[12], qd[12], qdd[12], lam[12], expect[12], expect_qd[12];
    parallelogram_state(L, d, th, w, q, qd);
    MechrtDynReport rep;
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, lam, work, lw, &rep),
                     MECHRT_OK);
    assert_int_equal(rep.rank, 11);
    assert_int_equal(rep.redundant, 1);
    assert_true(rep.residual < 1e-12);
    /* one coordinate theta: I theta'' = -(3 m_k L/2 + m_c L) g cos(theta) */
    double mk = tm.m[0], mc = tm.m[3], Jk = tm.J[0];
    double inertia = 3 * (Jk + mk * L * L / 4) + mc * L * L;
    double a = -(3 * mk * L / 2 + mc * L) * tm.g * cos(th) / inertia;
    parallelogram_state(L, d, th, w, expect, expect_qd);
    for (int kk = 0; kk < 3; kk++) {
        expect[3 * kk] = -L / 2 * (sin(th) * a + cos(th) * w * w);
        expect[3 * kk + 1] = L / 2 * (cos(th) * a - sin(th) * w * w);
        expect[3 * kk + 2] = a;
    }
    expect[9] = -L * (sin(th) * a + cos(th) * w * w);
    expect[10] = L * (cos(th) * a - sin(th) * w * w);
    expect[11] = 0;
    for (int i = 0; i < 12; i++)
        assert_near(qdd[i], expect[i], 1e-11, 1e-12);
    /* lambda: Phi_q^T lambda = Q - M qdd, and the minimum-norm one */
    double jac[144], M[144], Q[12], r[12], lpinv[12];
    t_jac(&tm, q, 0, jac);
    t_mass(&tm, q, M);
    t_force(&tm, q, qd, 0, Q);
    for (int j = 0; j < 12; j++) {
        r[j] = Q[j];
        for (int i = 0; i < 12; i++)
            r[j] -= M[j * 12 + i] * qdd[i];
    }
    for (int j = 0; j < 12; j++) {
        double s = 0;
        for (int i = 0; i < 12; i++)
            s += jac[i * 12 + j] * lam[i];
        assert_near(s, r[j], 1e-10, 1e-11);
    }
    pinv_transpose_solve(jac, 12, 12, r, lpinv);
    for (int i = 0; i < 12; i++)
        assert_near(lam[i], lpinv[i], 1e-8, 1e-9);
    free(work);
}

/* The rank drop is found slightly off the constraint manifold too (the
   positions between two projections): qdd within the drift of the exact one. */
static void test_redundant_off_manifold(void **state)
{
    (void)state;
    double L = 0.4, d = 0.5, th = 0.7, w = 0.5;
    TMech tm = parallelogram(L, d);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[12], qd[12], qdd[12], qdd0[12];
    parallelogram_state(L, d, th, w, q, qd);
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd0, NULL, work, lw, NULL),
                     MECHRT_OK);
    q[4] += 1e-10;                  /* crank 2 nudged off its pins */
    MechrtDynReport rep;
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw, &rep),
                     MECHRT_OK);
    assert_int_equal(rep.redundant, 1);
    for (int i = 0; i < 12; i++)
        assert_near(qdd[i], qdd0[i], 1e-6, 1e-6);
    free(work);
}

/* (d) The driven pendulum, phi = d0 + d1 t + d2 t^2/2: the motor's torque
   -lambda_driver = (J + m l^2) phi'' + m g l cos(phi). */
static void test_inverse_driven_pendulum(void **state)
{
    (void)state;
    double m = 1.2, J = 0.03, l = 0.5;
    TMech tm = pendulum(m, J, l);
    tm.driver = 0;
    tm.d[0] = 0.2, tm.d[1] = 2.0, tm.d[2] = -1.5;
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[3], qd[3], qdd[3], lam[3];
    double kwork[MECHRT_WORKSPACE_LEN(3, 3)];
    for (double t = 0; t <= 1.0; t += 0.25) {
        double phi = tm.d[0] + tm.d[1] * t + 0.5 * tm.d[2] * t * t, w = tm.d[1] + tm.d[2] * t;
        pendulum_state(l, phi, w, q, qd);
        assert_int_equal(mechrt_acceleration(&k, NULL, q, qd, t, qdd, kwork,
                                             sizeof kwork / sizeof *kwork, NULL), MECHRT_OK);
        MechrtDynReport rep;
        assert_int_equal(mechrt_inverse_dynamics(&k, NULL, q, qd, qdd, t, lam, work, lw, &rep),
                         MECHRT_OK);
        double torque = (J + m * l * l) * tm.d[2] + m * tm.g * l * cos(phi);
        assert_near(-lam[2], torque, 1e-12, 1e-12);
        assert_near(lam[0], -m * qdd[0], 1e-12, 1e-12);
        assert_near(lam[1], -m * tm.g - m * qdd[1], 1e-12, 1e-12);
        assert_true(rep.residual < 1e-12);
        /* forward dynamics along the same motion gives the same qdd and lambda */
        double qdd2[3], lam2[3];
        assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, t, qdd2, lam2, work, lw, NULL),
                         MECHRT_OK);
        for (int i = 0; i < 3; i++) {
            assert_near(qdd2[i], qdd[i], 1e-12, 1e-12);
            assert_near(lam2[i], lam[i], 1e-11, 1e-12);
        }
    }
    free(work);
}

/* Inverse dynamics of a motion the rows do not drive: the residual says so. */
static void test_inverse_undriven_residual(void **state)
{
    (void)state;
    TMech tm = pendulum(1, 0.1, 0.5);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[3], qd[3], qdd[3] = {0, 0, 0}, lam[2];
    pendulum_state(0.5, 0.3, 0, q, qd);
    MechrtDynReport rep;
    assert_int_equal(mechrt_inverse_dynamics(&k, NULL, q, qd, qdd, 0, lam, work, lw, &rep),
                     MECHRT_OK);
    /* held still against gravity: the torque m g l cos(phi) has no row to carry it */
    assert_near(rep.residual, 9.81 * 0.5 * cos(0.3), 1e-12, 1e-12);
    free(work);
}

/* A massless direction the joints leave free: singular; bad arguments. */
static void test_errors(void **state)
{
    (void)state;
    TMech tm = pendulum(1, 0, 0.5);
    tm.m[0] = 0;
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[3], qd[3], qdd[3];
    pendulum_state(0.5, 0.3, 0, q, qd);
    MechrtDynReport rep;
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw, &rep),
                     MECHRT_ESING);
    assert_int_equal(rep.sing_index, 0);
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw - 1, NULL),
                     MECHRT_EBADLEN);
    k.mass = NULL;
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw, NULL),
                     MECHRT_EINVAL);
    assert_false(sim_has_masses(&k));
    assert_int_equal(mechrt_dynamics_workspace_size(0, 1), 0);
    assert_int_equal(mechrt_dynamics_workspace_size(INT_MAX, INT_MAX), 0);
    free(work);
}

/* Baumgarte: the accelerations meet gamma - 2 alpha (Phi_q qd - nu) - beta^2 Phi
   off the manifold. */
static void test_baumgarte(void **state)
{
    (void)state;
    TMech tm = pendulum(1.0, 0.05, 0.5);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw), q[3], qd[3], qdd[3], jac[6], phi[2], gam[2];
    pendulum_state(0.5, 0.4, 1.0, q, qd);
    q[0] += 1e-3, qd[1] += 2e-3;                  /* off the rows */
    MechrtDynOptions o = mechrt_dyn_default_options();
    o.baumgarte_alpha = 5, o.baumgarte_beta = 7;
    assert_int_equal(mechrt_forward_dynamics(&k, &o, q, qd, 0, qdd, NULL, work, lw, NULL),
                     MECHRT_OK);
    t_jac(&tm, q, 0, jac);
    t_phi(&tm, q, 0, phi);
    t_gamma(&tm, q, qd, 0, gam);
    for (int i = 0; i < 2; i++) {
        double acc = 0, vel = 0;
        for (int j = 0; j < 3; j++)
            acc += jac[i * 3 + j] * qdd[j], vel += jac[i * 3 + j] * qd[j];
        assert_near(acc, gam[i] - 2 * 5 * vel - 49 * phi[i], 1e-12, 1e-12);
    }
    free(work);
}

/* The rows to keep at a state: the parallelogram's one dependent row left
   out, and the accelerations the same with it out. */
static void test_dynamics_rows(void **state)
{
    (void)state;
    double L = 0.4, d = 0.5, q[12], qd[12], qdd[12], qdd2[12], lam[12];
    TMech tm = parallelogram(L, d);
    MechrtKernels k = t_kernels(&tm);
    size_t lw;
    double *work = t_work(&k, &lw);
    unsigned char active[12];
    parallelogram_state(L, d, 0.9, 0.7, q, qd);
    MechrtDynReport rep;
    assert_int_equal(mechrt_dynamics_rows(&k, NULL, q, 0, active, work, lw, &rep), MECHRT_OK);
    int kept = 0;
    for (int i = 0; i < 12; i++)
        kept += active[i];
    assert_int_equal(kept, 11);
    assert_int_equal(rep.redundant, 1);
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, NULL, work, lw, NULL),
                     MECHRT_OK);
    MechrtDynOptions o = mechrt_dyn_default_options();
    o.active = active;
    assert_int_equal(mechrt_forward_dynamics(&k, &o, q, qd, 0, qdd2, lam, work, lw, &rep),
                     MECHRT_OK);
    for (int i = 0; i < 12; i++) {
        assert_near(qdd2[i], qdd[i], 1e-12, 1e-12);
        if (!active[i])
            assert_true(lam[i] == 0);
    }
    free(work);
}

/* A velocity-level row (nv = 1): a knife edge (x, y, phi) that cannot slide
   sideways, -sin(phi) x' + cos(phi) y' = 0, pushed by a force F along its
   heading and a torque tau: v' = F / m, phi'' = tau / J. */
static void k_jac(void *ctx, const double *q, double t, double *out)
{
    (void)ctx, (void)t;
    out[0] = -sin(q[2]), out[1] = cos(q[2]), out[2] = 0;
}

static void k_nu(void *ctx, const double *q, double t, double *out)
{
    (void)ctx, (void)q, (void)t;
    out[0] = 0;
}

static void k_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
{
    (void)ctx, (void)t;
    out[0] = qd[2] * (cos(q[2]) * qd[0] + sin(q[2]) * qd[1]);
}

static void k_phi(void *ctx, const double *q, double t, double *out)
{
    (void)ctx, (void)q, (void)t, (void)out;
}

static void k_mass(void *ctx, const double *q, double *M)
{
    (void)ctx, (void)q;
    memset(M, 0, 9 * sizeof *M);
    M[0] = M[4] = 2.0, M[8] = 0.1;
}

static void k_force(void *ctx, const double *q, const double *qd, double t, double *Q)
{
    (void)ctx, (void)qd, (void)t;
    Q[0] = 3.0 * cos(q[2]), Q[1] = 3.0 * sin(q[2]), Q[2] = 0.5;
}

static void test_knife_edge_forward(void **state)
{
    (void)state;
    MechrtKernels k = {3, 0, 1, NULL, k_phi, k_jac, k_nu, k_gamma, NULL, k_mass, k_force};
    size_t lw;
    double *work = t_work(&k, &lw), phi = 0.6, v = 1.5, w = -0.8;
    double q[3] = {0.1, 0.2, phi}, qd[3] = {v * cos(phi), v * sin(phi), w}, qdd[3], lam[1];
    assert_int_equal(mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, lam, work, lw, NULL),
                     MECHRT_OK);
    double vd = 3.0 / 2.0;
    assert_near(qdd[0], vd * cos(phi) - v * sin(phi) * w, 1e-13, 1e-14);
    assert_near(qdd[1], vd * sin(phi) + v * cos(phi) * w, 1e-13, 1e-14);
    assert_near(qdd[2], 0.5 / 0.1, 1e-13, 1e-14);
    /* the sideways force the blade takes: m v w = -lambda */
    assert_near(-lam[0], 2.0 * v * w, 1e-12, 1e-13);
    free(work);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pendulum_forward),
        cmocka_unit_test(test_double_pendulum_forward),
        cmocka_unit_test(test_free_body),
        cmocka_unit_test(test_redundant_parallelogram),
        cmocka_unit_test(test_redundant_off_manifold),
        cmocka_unit_test(test_inverse_driven_pendulum),
        cmocka_unit_test(test_inverse_undriven_residual),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_baumgarte),
        cmocka_unit_test(test_dynamics_rows),
        cmocka_unit_test(test_knife_edge_forward),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
