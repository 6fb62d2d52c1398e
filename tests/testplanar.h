/* testplanar.h - hand-written planar kernels with masses and pins, for the dynamics suites. */
#ifndef MECHC_TESTPLANAR_H
#define MECHC_TESTPLANAR_H

#include "testutil.h"

#include "../runtime/mechrt.h"

#include <math.h>
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

static inline int t_nh(const TMech *tm) { return 2 * tm->npin + (tm->driver >= 0); }

/* The global point of body b's local point s (b = -1: s itself), and A(phi) s. */
static inline void t_point(const double *q, int b, const double *s, double p[2], double as[2])
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

static inline void t_phi(void *ctx, const double *q, double t, double *out)
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
static inline void t_jac(void *ctx, const double *q, double t, double *out)
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

static inline void t_nu(void *ctx, const double *q, double t, double *out)
{
    const TMech *tm = ctx;
    (void)q;
    memset(out, 0, (size_t)t_nh(tm) * sizeof *out);
    if (tm->driver >= 0)
        out[2 * tm->npin] = tm->d[1] + tm->d[2] * t;
}

/* gamma of a pin: A_i s_i phi_i'^2 - A_j s_j phi_j'^2; of the driver: d2 */
static inline void t_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
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
static inline void t_mass(void *ctx, const double *q, double *M)
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
static inline void t_force(void *ctx, const double *q, const double *qd, double t, double *Q)
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

static inline MechrtKernels t_kernels(TMech *tm)
{
    return (MechrtKernels){3 * tm->nb, t_nh(tm), 0, tm, t_phi, t_jac, t_nu, t_gamma,
                           NULL, t_mass, t_force};
}

static inline double *t_work(const MechrtKernels *k, size_t *lwork)
{
    *lwork = mechrt_dynamics_workspace_size(k->nq, k->nh + k->nv);
    assert_true(*lwork == MECHRT_DYN_WORKSPACE_LEN(k->nq, k->nh + k->nv));
    return calloc(*lwork, sizeof(double));
}

/* A pendulum: its centre of mass at distance l from the pin at the origin,
   angle phi from the x axis. */
static inline TMech pendulum(double m, double J, double l)
{
    TMech tm = {.nb = 1, .npin = 1, .m = {m}, .J = {J}, .driver = -1, .g = 9.81};
    tm.pins[0] = (Pin){0, -1, {-l, 0}, {0, 0}};
    return tm;
}

static inline void pendulum_state(double l, double phi, double w, double *q, double *qd)
{
    q[0] = l * cos(phi), q[1] = l * sin(phi), q[2] = phi;
    qd[0] = -l * sin(phi) * w, qd[1] = l * cos(phi) * w, qd[2] = w;
}

static inline TMech double_pendulum(double a1, double b1, double a2)
{
    TMech tm = {.nb = 2, .npin = 2, .m = {1.5, 0.8}, .J = {0.02, 0.01}, .driver = -1, .g = 9.81};
    tm.pins[0] = (Pin){0, -1, {-a1, 0}, {0, 0}};
    tm.pins[1] = (Pin){0, 1, {b1, 0}, {-a2, 0}};
    return tm;
}

/* Positions and velocities of the double pendulum from its angles and rates. */
static inline void double_state(double a1, double L1, double a2, const double ang[2],
                                const double w[2], double *q, double *qd)
{
    double c1 = cos(ang[0]), s1 = sin(ang[0]), c2 = cos(ang[1]), s2 = sin(ang[1]);
    q[0] = a1 * c1, q[1] = a1 * s1, q[2] = ang[0];
    q[3] = L1 * c1 + a2 * c2, q[4] = L1 * s1 + a2 * s2, q[5] = ang[1];
    qd[0] = -a1 * s1 * w[0], qd[1] = a1 * c1 * w[0], qd[2] = w[0];
    qd[3] = -L1 * s1 * w[0] - a2 * s2 * w[1], qd[4] = L1 * c1 * w[0] + a2 * c2 * w[1];
    qd[5] = w[1];
}

/* (c) A parallelogram with a redundant third crank: cranks of length L
   (centre of mass mid-way) pinned to ground at x = -d, 0, d and to the
   coupler (centre of mass at its middle pin). 12 rows, rank 11, 1 DOF. */
static inline TMech parallelogram(double L, double d)
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

static inline void parallelogram_state(double L, double d, double th, double w, double *q,
                                       double *qd)
{
    for (int k = 0; k < 3; k++) {
        q[3 * k] = (k - 1) * d + L / 2 * cos(th), q[3 * k + 1] = L / 2 * sin(th);
        q[3 * k + 2] = th;
        qd[3 * k] = -L / 2 * sin(th) * w, qd[3 * k + 1] = L / 2 * cos(th) * w, qd[3 * k + 2] = w;
    }
    q[9] = L * cos(th), q[10] = L * sin(th), q[11] = 0;
    qd[9] = -L * sin(th) * w, qd[10] = L * cos(th) * w, qd[11] = 0;
}

#endif
