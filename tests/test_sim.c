/* test_sim.c - the simulation (generator/dyn/) on hand-written kernels (testplanar.h). */
#include "testutil.h"

#include "../generator/dyn/sim.h"
#include "testplanar.h"

#include <string.h>

/* ---- the simulation ---------------------------------------------------------- */

typedef struct Collect {
    const TMech *tm;
    int n;
    double t[2001];
    double e[2001];          /* T + V */
    double phi_res;          /* largest |Phi| seen */
    double qd_first[12];     /* the velocities at t0 */
    double q_last[12];       /* the positions at the last state */
} Collect;

static double t_energy(const TMech *tm, const double *q, const double *qd)
{
    double M[144], e = 0;
    int n = 3 * tm->nb;
    t_mass((void *)tm, q, M);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            e += 0.5 * qd[i] * M[i * n + j] * qd[j];
    for (int b = 0; b < tm->nb; b++)     /* V = m g y_com */
        e += tm->m[b] * tm->g * (q[3 * b + 1] + tm->c[b] * sin(q[3 * b + 2]));
    return e;
}

static void on_state(void *ctx, double t, const double *q, const double *qd, const double *qdd,
                     const double *lambda)
{
    Collect *c = ctx;
    double phi[12];
    int n = 3 * c->tm->nb;
    (void)qdd, (void)lambda;
    if (c->n == 0)
        memcpy(c->qd_first, qd, (size_t)n * sizeof *qd);
    memcpy(c->q_last, q, (size_t)n * sizeof *q);
    c->t[c->n] = t;
    c->e[c->n] = t_energy(c->tm, q, qd);
    t_phi((void *)c->tm, q, t, phi);
    for (int i = 0; i < t_nh(c->tm); i++)
        c->phi_res = fmax(c->phi_res, fabs(phi[i]));
    c->n++;
}

static double max_energy_change(const Collect *c)
{
    double worst = 0;
    for (int i = 0; i < c->n; i++)
        worst = fmax(worst, fabs(c->e[i] - c->e[0]));
    return worst;
}

/* (b) The free double pendulum over 10 s, released from rest: chaotic, and
   its energy kept to 1e-8 of the energy exchanged (rk8pd, tolerances 1e-12,
   projection after every step). */
/* The energy tests' double pendulum, released at rest from angles 0.2
   and 1.0: its kernels on tm, q and qd, sim's defaults with qd0 = qd. */
static SimOptions double_pendulum_release(TMech *tm, MechrtKernels *k, double *q, double *qd)
{
    double a1 = 0.3, b1 = 0.25, a2 = 0.4;
    *tm = double_pendulum(a1, b1, a2);
    *k = t_kernels(tm);
    double ang[2] = {0.2, 1.0}, w[2] = {0, 0};
    double_state(a1, a1 + b1, a2, ang, w, q, qd);
    SimOptions o = sim_default_options();
    o.qd0 = qd;
    return o;
}

static void test_double_pendulum_energy(void **state)
{
    (void)state;
    TMech tm;
    MechrtKernels k;
    double q[6], qd[6];
    SimOptions o = double_pendulum_release(&tm, &k, q, qd);
    o.t1 = 10;
    o.steps = 1000;
    o.rtol = o.atol = 1e-12;
    Collect *c = calloc(1, sizeof *c);
    c->tm = &tm;
    SimResult res;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, c, &res), ANALYSIS_OK);
    assert_int_equal(c->n, 1001);
    assert_near(c->t[1000], 10, 0, 0);
    /* the energy exchanged: the largest kinetic energy is about the potential drop */
    double scale = res.energy_scale;
    assert_true(scale > 1);
    double drift = max_energy_change(c);
    assert_true(drift <= 1e-8 * scale);
    /* sim's own balance agrees that the energy was kept */
    assert_true(res.energy_drift <= 1e-8 * scale);
    assert_true(c->phi_res < 1e-10);
    assert_true(res.steps > 100);
    assert_true(res.projections >= res.steps);
    /* full rank far from any singular position: every projection solve
       (each Newton iteration, each velocity correction) by QR, no SVD */
    assert_int_equal(res.qr_solves, res.projections + res.projection_iterations);
    assert_true(res.calls.mass > 0 && res.calls.force == res.rhs_calls + c->n);
    free(c);
}

/* The same with interpolation over 2 s: fewer steps than outputs, the
   end on the stepped run's motion, the interpolated states' energy and
   constraints within the interpolant's error (measured 2.5e-9 of the
   scale and 4e-11). */
static void test_double_pendulum_interpolated(void **state)
{
    (void)state;
    TMech tm;
    MechrtKernels k;
    double q[6], qd[6];
    SimOptions o = double_pendulum_release(&tm, &k, q, qd);
    o.t1 = 2;
    o.steps = 400;
    Collect *ref = calloc(1, sizeof *ref), *c = calloc(1, sizeof *c);
    ref->tm = c->tm = &tm;
    SimResult rres, res;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, ref, &rres), ANALYSIS_OK);
    o.interpolate = true;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, c, &res), ANALYSIS_OK);
    assert_int_equal(c->n, 401);
    assert_near(c->t[200], 1, 0, 1e-15);
    assert_true(res.steps < o.steps / 2 && res.steps < rres.steps / 2);
    for (int i = 0; i < 6; i++)
        assert_near(c->q_last[i], ref->q_last[i], 0, 1e-8);
    double scale = res.energy_scale;
    assert_true(max_energy_change(c) <= 1e-8 * scale);
    assert_true(c->phi_res < 1e-8);
    free(ref);
    free(c);
}

/* A pendulum with its centre of mass off the pin (M depends on phi, Q has
   velocity terms): the period of small swings, and the energy balance with
   the Mdot term. */
static void test_offset_pendulum(void **state)
{
    (void)state;
    double m = 1.0, J = 0.02, c = 0.3;
    TMech tm = {.nb = 1, .npin = 1, .m = {m}, .J = {J}, .c = {c}, .driver = -1, .g = 9.81};
    tm.pins[0] = (Pin){0, -1, {0, 0}, {0, 0}};
    MechrtKernels k = t_kernels(&tm);
    double q[3] = {0, 0, -M_PI / 2 + 0.01}, qd[3] = {0, 0, 0};
    double period = 2 * M_PI * sqrt((J + m * c * c) / (m * tm.g * c));
    SimOptions o = sim_default_options();
    o.t1 = period;
    o.steps = 2;
    o.qd0 = qd;
    Collect *col = calloc(1, sizeof *col);
    col->tm = &tm;
    SimResult res;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, col, &res), ANALYSIS_OK);
    /* a small swing returns after one period (to O(amplitude^3)) */
    assert_near(col->q_last[2], q[2], 0, 1e-5);
    assert_true(max_energy_change(col) < 1e-10);
    assert_true(res.energy_drift < 1e-9 * fmax(res.energy_scale, 1e-3));
    free(col);
    /* a large swing: the balance (with 1/2 qd^T Mdot qd) still closes */
    q[2] = 0.5;
    col = calloc(1, sizeof *col);
    col->tm = &tm;
    o.t1 = 3;
    o.steps = 30;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, col, &res), ANALYSIS_OK);
    assert_true(res.energy_scale > 1);
    assert_true(res.energy_drift < 1e-8 * res.energy_scale);
    assert_true(max_energy_change(col) < 1e-8 * res.energy_scale);
    free(col);
}

/* The redundant parallelogram simulated by every method, released at
   theta = 0.3: it falls through its change point theta = 0 (cranks and
   coupler in line, where the rank drops by one more: a singular position
   as in IFToMM's A02) and stays a parallelogram, its energy kept. */
static void test_redundant_simulation(void **state)
{
    (void)state;
    double L = 0.4, d = 0.5, q[12], qd[12];
    TMech tm = parallelogram(L, d);
    MechrtKernels k = t_kernels(&tm);
    parallelogram_state(L, d, 0.3, 0, q, qd);
    for (int method = SIM_RK8PD; method <= SIM_MSBDF; method++) {
        SimOptions o = sim_default_options();
        o.t1 = 1;
        o.steps = 10;
        o.method = (SimMethod)method;
        o.rtol = o.atol = method >= SIM_RK4IMP ? 1e-9 : 1e-11;
        Collect *c = calloc(1, sizeof *c);
        c->tm = &tm;
        SimResult res;
        AnalysisStatus st = sim_integrate(&k, NULL, NULL, &o, q, on_state, c, &res);
        if (st != ANALYSIS_OK)
            fail_msg("%s: %s", sim_method_names[method], res.message);
        assert_int_equal(c->n, 11);
        /* one row always, two at the change point theta = 0 (t = 0.153) */
        assert_true(res.max_redundant >= 1);
        assert_near(c->q_last[11], 0, 0, 1e-7);       /* still a parallelogram */
        assert_true(max_energy_change(c) < (method >= SIM_RK4IMP ? 1e-5 : 1e-8));
        assert_true(c->phi_res < 1e-8);
        if (method >= SIM_RK4IMP)
            assert_true(res.jacobian_calls > 0);
        /* a redundant row always: the projections' truncated SVD, never QR */
        assert_true(res.projections > 0);
        assert_int_equal(res.qr_solves, 0);
        free(c);
    }
}

/* A failure names the time and the cause: the massless pendulum. */
static void test_sim_failure(void **state)
{
    (void)state;
    TMech tm = pendulum(1, 0, 0.5);
    tm.m[0] = 0;
    MechrtKernels k = t_kernels(&tm);
    double q[3], qd[3];
    pendulum_state(0.5, 0.3, 0, q, qd);
    SimOptions o = sim_default_options();
    Collect *c = calloc(1, sizeof *c);
    c->tm = &tm;
    SimResult res;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, c, &res), ANALYSIS_FAILED);
    assert_int_equal(res.cause, MECHRT_ESING);
    assert_non_null(strstr(res.message, "t = 0: "));
    assert_non_null(strstr(res.message, "singular"));
    k.mass = NULL;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, c, &res), ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(res.message, "no masses"));
    free(c);
}

/* Initial velocities that break the rows are projected: a driver's rate
   prescribed, the rest minimum-norm. */
static void test_initial_velocity_projection(void **state)
{
    (void)state;
    TMech tm = pendulum(1, 0.1, 0.5);
    tm.driver = 0;
    tm.d[0] = 0.3, tm.d[1] = 2.0, tm.d[2] = 0;
    MechrtKernels k = t_kernels(&tm);
    double q[3], qd[3];
    pendulum_state(0.5, 0.3, 0, q, qd);
    SimOptions o = sim_default_options();
    o.steps = 1;
    o.t1 = 0.1;
    Collect *c = calloc(1, sizeof *c);
    c->tm = &tm;
    SimResult res;
    assert_int_equal(sim_integrate(&k, NULL, NULL, &o, q, on_state, c, &res), ANALYSIS_OK);
    /* zero given: the driver's rate, and the pin's velocities that follow */
    assert_near(c->qd_first[2], 2.0, 1e-14, 0);
    assert_near(c->qd_first[0], -0.5 * sin(0.3) * 2.0, 1e-12, 1e-14);
    assert_near(c->qd_first[1], 0.5 * cos(0.3) * 2.0, 1e-12, 1e-14);
    assert_true(c->phi_res < 1e-9);
    free(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_double_pendulum_energy),
        cmocka_unit_test(test_double_pendulum_interpolated),
        cmocka_unit_test(test_offset_pendulum),
        cmocka_unit_test(test_redundant_simulation),
        cmocka_unit_test(test_sim_failure),
        cmocka_unit_test(test_initial_velocity_projection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
