/* test_sim.c - forward and inverse dynamics (runtime/dynamics.c) and the simulation (sim.c) on hand-written kernels. */
#include "testutil.h"

#include "../generator/analysis/sim.h"
#include "../runtime/mechrt.h"

#include <gsl/gsl_linalg.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

/* ---- planar bodies in body coordinates (x, y, phi), pins, one driver ------
   Body b: mass m at the body point (c, 0) (its centre of mass), inertia J
   about it; gravity -g along y. Pin p: body bi's point si on body bj's
   point sj (bj = -1: the ground point sj). Driver: phi of body `driver`
   equals d0 + d1 t + d2 t^2 / 2. */

enum { MAXB = 4, MAXP = 6 };

typedef struct Pin {
    int bi, bj;
    double si[2], sj[2];
} Pin;

typedef struct TMech {
    int nb, npin;
    double m[MAXB], J[MAXB], c[MAXB];
    Pin pins[MAXP];
    int driver;
    double d[3];
    double g;
} TMech;

static int t_nh(const TMech *tm) { return 2 * tm->npin + (tm->driver >= 0); }

/* The global point of body b's local point s (b = -1: s itself), and A(phi) s. */
static void t_point(const double *q, int b, const double *s, double p[2], double as[2])
{
    if (b < 0) {
        p[0] = s[0], p[1] = s[1], as[0] = as[1] = 0;
        return;
    }
    double cs = cos(q[3 * b + 2]), sn = sin(q[3 * b + 2]);
    as[0] = cs * s[0] - sn * s[1];
    as[1] = sn * s[0] + cs * s[1];
    p[0] = q[3 * b] + as[0];
    p[1] = q[3 * b + 1] + as[1];
}

static void t_phi(void *ctx, const double *q, double t, double *out)
{
    const TMech *tm = ctx;
    for (int k = 0; k < tm->npin; k++) {
        const Pin *p = &tm->pins[k];
        double pi[2], pj[2], a[2];
        t_point(q, p->bi, p->si, pi, a);
        t_point(q, p->bj, p->sj, pj, a);
        out[2 * k] = pi[0] - pj[0];
        out[2 * k + 1] = pi[1] - pj[1];
    }
    if (tm->driver >= 0)
        out[2 * tm->npin] = q[3 * tm->driver + 2] - (tm->d[0] + tm->d[1] * t + 0.5 * tm->d[2] * t * t);
}

/* d(A s)/dphi = (-as_y, as_x) */
static void t_jac(void *ctx, const double *q, double t, double *out)
{
    const TMech *tm = ctx;
    int n = 3 * tm->nb;
    (void)t;
    memset(out, 0, (size_t)t_nh(tm) * (size_t)n * sizeof *out);
    for (int k = 0; k < tm->npin; k++) {
        const Pin *p = &tm->pins[k];
        double pt[2], a[2];
        double *r0 = out + (size_t)(2 * k) * (size_t)n, *r1 = r0 + n;
        if (p->bi >= 0) {
            t_point(q, p->bi, p->si, pt, a);
            r0[3 * p->bi] += 1, r1[3 * p->bi + 1] += 1;
            r0[3 * p->bi + 2] += -a[1], r1[3 * p->bi + 2] += a[0];
        }
        if (p->bj >= 0) {
            t_point(q, p->bj, p->sj, pt, a);
            r0[3 * p->bj] -= 1, r1[3 * p->bj + 1] -= 1;
            r0[3 * p->bj + 2] -= -a[1], r1[3 * p->bj + 2] -= a[0];
        }
    }
    if (tm->driver >= 0)
        out[(size_t)(2 * tm->npin) * (size_t)n + (size_t)(3 * tm->driver + 2)] = 1;
}

static void t_nu(void *ctx, const double *q, double t, double *out)
{
    const TMech *tm = ctx;
    (void)q;
    memset(out, 0, (size_t)t_nh(tm) * sizeof *out);
    if (tm->driver >= 0)
        out[2 * tm->npin] = tm->d[1] + tm->d[2] * t;
}

/* gamma of a pin: A_i s_i phi_i'^2 - A_j s_j phi_j'^2; of the driver: d2 */
static void t_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
{
    const TMech *tm = ctx;
    (void)t;
    for (int k = 0; k < tm->npin; k++) {
        const Pin *p = &tm->pins[k];
        double pt[2], a[2];
        out[2 * k] = out[2 * k + 1] = 0;
        if (p->bi >= 0) {
            double w = qd[3 * p->bi + 2];
            t_point(q, p->bi, p->si, pt, a);
            out[2 * k] += a[0] * w * w, out[2 * k + 1] += a[1] * w * w;
        }
        if (p->bj >= 0) {
            double w = qd[3 * p->bj + 2];
            t_point(q, p->bj, p->sj, pt, a);
            out[2 * k] -= a[0] * w * w, out[2 * k + 1] -= a[1] * w * w;
        }
    }
    if (tm->driver >= 0)
        out[2 * tm->npin] = tm->d[2];
}

/* M of a mass m at the body point (c, 0): p_q = [I, B(phi) (c, 0)]. */
static void t_mass(void *ctx, const double *q, double *M)
{
    const TMech *tm = ctx;
    int n = 3 * tm->nb;
    memset(M, 0, (size_t)n * (size_t)n * sizeof *M);
    for (int b = 0; b < tm->nb; b++) {
        double m = tm->m[b], c = tm->c[b], sn = sin(q[3 * b + 2]), cs = cos(q[3 * b + 2]);
        double *r = M + (size_t)(3 * b) * (size_t)n + 3 * b;
        r[0] = m, r[2] = -m * c * sn;
        r[n + 1] = m, r[n + 2] = m * c * cs;
        r[2 * n] = -m * c * sn, r[2 * n + 1] = m * c * cs, r[2 * n + 2] = tm->J[b] + m * c * c;
    }
}

/* Q: gravity m p_q^T (0, -g) and the velocity terms m c phi'^2 (cos, sin, 0). */
static void t_force(void *ctx, const double *q, const double *qd, double t, double *Q)
{
    const TMech *tm = ctx;
    (void)t;
    for (int b = 0; b < tm->nb; b++) {
        double m = tm->m[b], c = tm->c[b], w = qd[3 * b + 2];
        double sn = sin(q[3 * b + 2]), cs = cos(q[3 * b + 2]);
        Q[3 * b] = m * c * w * w * cs;
        Q[3 * b + 1] = m * c * w * w * sn - m * tm->g;
        Q[3 * b + 2] = -m * tm->g * c * cs;
    }
}

static MechrtKernels t_kernels(TMech *tm)
{
    return (MechrtKernels){3 * tm->nb, t_nh(tm), 0, tm, t_phi, t_jac, t_nu, t_gamma,
                           NULL, t_mass, t_force};
}

static double *t_work(const MechrtKernels *k, size_t *lwork)
{
    *lwork = mechrt_dynamics_workspace_size(k->nq, k->nh + k->nv);
    assert_true(*lwork == MECHRT_DYN_WORKSPACE_LEN(k->nq, k->nh + k->nv));
    return calloc(*lwork, sizeof(double));
}

/* A pendulum: its centre of mass at distance l from the pin at the origin,
   angle phi from the x axis. */
static TMech pendulum(double m, double J, double l)
{
    TMech tm = {.nb = 1, .npin = 1, .m = {m}, .J = {J}, .driver = -1, .g = 9.81};
    tm.pins[0] = (Pin){0, -1, {-l, 0}, {0, 0}};
    return tm;
}

static void pendulum_state(double l, double phi, double w, double *q, double *qd)
{
    q[0] = l * cos(phi), q[1] = l * sin(phi), q[2] = phi;
    qd[0] = -l * sin(phi) * w, qd[1] = l * cos(phi) * w, qd[2] = w;
}

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

static TMech double_pendulum(double a1, double b1, double a2)
{
    TMech tm = {.nb = 2, .npin = 2, .m = {1.5, 0.8}, .J = {0.02, 0.01}, .driver = -1, .g = 9.81};
    tm.pins[0] = (Pin){0, -1, {-a1, 0}, {0, 0}};
    tm.pins[1] = (Pin){0, 1, {b1, 0}, {-a2, 0}};
    return tm;
}

/* Positions and velocities of the double pendulum from its angles and rates. */
static void double_state(double a1, double L1, double a2, const double ang[2], const double w[2],
                         double *q, double *qd)
{
    double c1 = cos(ang[0]), s1 = sin(ang[0]), c2 = cos(ang[1]), s2 = sin(ang[1]);
    q[0] = a1 * c1, q[1] = a1 * s1, q[2] = ang[0];
    q[3] = L1 * c1 + a2 * c2, q[4] = L1 * s1 + a2 * s2, q[5] = ang[1];
    qd[0] = -a1 * s1 * w[0], qd[1] = a1 * c1 * w[0], qd[2] = w[0];
    qd[3] = -L1 * s1 * w[0] - a2 * s2 * w[1], qd[4] = L1 * c1 * w[0] + a2 * c2 * w[1];
    qd[5] = w[1];
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

/* (c) A parallelogram with a redundant third crank: cranks of length L
   (centre of mass mid-way) pinned to ground at x = -d, 0, d and to the
   coupler (centre of mass at its middle pin). 12 rows, rank 11, 1 DOF. */
static TMech parallelogram(double L, double d)
{
    TMech tm = {.nb = 4, .npin = 6, .m = {0.5, 0.5, 0.5, 2.0}, .J = {0.01, 0.01, 0.01, 0.3},
                .driver = -1, .g = 9.81};
    for (int k = 0; k < 3; k++) {
        double xk = (k - 1) * d;
        tm.pins[2 * k] = (Pin){k, -1, {-L / 2, 0}, {xk, 0}};
        tm.pins[2 * k + 1] = (Pin){k, 3, {L / 2, 0}, {xk, 0}};
    }
    return tm;
}

static void parallelogram_state(double L, double d, double th, double w, double *q, double *qd)
{
    for (int k = 0; k < 3; k++) {
        q[3 * k] = (k - 1) * d + L / 2 * cos(th), q[3 * k + 1] = L / 2 * sin(th);
        q[3 * k + 2] = th;
        qd[3 * k] = -L / 2 * sin(th) * w, qd[3 * k + 1] = L / 2 * cos(th) * w, qd[3 * k + 2] = w;
    }
    q[9] = L * cos(th), q[10] = L * sin(th), q[11] = 0;
    qd[9] = -L * sin(th) * w, qd[10] = L * cos(th) * w, qd[11] = 0;
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
    assert_int_equal(sim_integrate(&k, &o, q, on_state, c, &res), SIM_OK);
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
    assert_int_equal(sim_integrate(&k, &o, q, on_state, ref, &rres), SIM_OK);
    o.interpolate = true;
    assert_int_equal(sim_integrate(&k, &o, q, on_state, c, &res), SIM_OK);
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
    assert_int_equal(sim_integrate(&k, &o, q, on_state, col, &res), SIM_OK);
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
    assert_int_equal(sim_integrate(&k, &o, q, on_state, col, &res), SIM_OK);
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
        SimStatus st = sim_integrate(&k, &o, q, on_state, c, &res);
        if (st != SIM_OK)
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
    assert_int_equal(sim_integrate(&k, &o, q, on_state, c, &res), SIM_FAILED);
    assert_int_equal(res.cause, MECHRT_ESING);
    assert_non_null(strstr(res.message, "t = 0: "));
    assert_non_null(strstr(res.message, "singular"));
    k.mass = NULL;
    assert_int_equal(sim_integrate(&k, &o, q, on_state, c, &res), SIM_BAD_INPUT);
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
    assert_int_equal(sim_integrate(&k, &o, q, on_state, c, &res), SIM_OK);
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
        cmocka_unit_test(test_double_pendulum_energy),
        cmocka_unit_test(test_double_pendulum_interpolated),
        cmocka_unit_test(test_offset_pendulum),
        cmocka_unit_test(test_redundant_simulation),
        cmocka_unit_test(test_sim_failure),
        cmocka_unit_test(test_initial_velocity_projection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
