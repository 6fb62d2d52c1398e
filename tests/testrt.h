/* testrt.h - hand-written kernels and helpers for the runtime's suites (test_lu.c ...). */
/*
 * The mechanisms are hand-written kernels with the generated code's
 * signatures, their derivatives worked out by hand (comments above each):
 *   slider crank in minimal coordinates (nonlinear, NH == NQ == 3),
 *   a point on a circle driven along x (singular where y = 0),
 *   a knife-edge cart (NH = 1, NV = 2: velocity-level rows).
 * States are "high entropy" (angles like 0.7371), never 0.
 */
#ifndef MECHC_TESTRT_H
#define MECHC_TESTRT_H

#include "testutil.h"

#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_permutation.h>
#include <gsl/gsl_vector.h>
#include "../runtime/mechrt.h"

/* ---- helpers ----------------------------------------------------------- */

/* xorshift64*: deterministic numbers in [-1, 1), same on every machine */
static inline double rnd(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) / 4503599627370496.0 - 1.0;
}

static inline double *xmalloc(size_t n)
{
    double *p = malloc(n * sizeof *p);
    assert_non_null(p);
    return p;
}

static inline double inf_norm(int n, const double *v)
{
    double m = 0;
    for (int i = 0; i < n; i++)
        if (fabs(v[i]) > m)
            m = fabs(v[i]);
    return m;
}

/* kappa_1(A) = ||A||_1 ||A^-1||_1 with the inverse from GSL */
static inline double gsl_cond1(int n, const double *a, int lda)
{
    gsl_matrix *m = gsl_matrix_alloc((size_t)n, (size_t)n);
    gsl_matrix *inv = gsl_matrix_alloc((size_t)n, (size_t)n);
    gsl_permutation *p = gsl_permutation_alloc((size_t)n);
    int sign;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            gsl_matrix_set(m, (size_t)i, (size_t)j, a[i * lda + j]);
    gsl_linalg_LU_decomp(m, p, &sign);
    gsl_linalg_LU_invert(m, p, inv);
    double ninv = mechrt_norm1(n, inv->data, (int)inv->tda);
    gsl_permutation_free(p);
    gsl_matrix_free(inv);
    gsl_matrix_free(m);
    return mechrt_norm1(n, a, lda) * ninv;
}

/* ---- mechanism 1: slider crank in minimal coordinates ------------------
 * q = (th, be, s): crank angle, rod angle, slider position; crank r, rod l.
 *   Phi1 = r cos th + l cos be - s
 *   Phi2 = r sin th - l sin be
 *   Phi3 = th - (a + w t + al t^2/2)                  (driver)
 * Phi_q = [[-r sin th, -l sin be, -1], [r cos th, -l cos be, 0], [1, 0, 0]]
 * nu    = (0, 0, w + al t)
 * gamma = (r cos th thd^2 + l cos be bed^2, r sin th thd^2 - l sin be bed^2, al)
 * Exact: th(t) as driven, sin be = r sin th / l (cos be > 0 since r < l),
 * s = r cos th + l cos be; velocities and accelerations by differentiating.
 */
#define SC_R  0.12
#define SC_L  0.35
#define SC_A  0.7371
#define SC_W  2.3
#define SC_AL 0.9

static inline void sc_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = SC_R * cos(q[0]) + SC_L * cos(q[1]) - q[2];
    phi[1] = SC_R * sin(q[0]) - SC_L * sin(q[1]);
    phi[2] = q[0] - (SC_A + SC_W * t + 0.5 * SC_AL * t * t);
}

static inline void sc_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    (void)t;
    jac[0] = -SC_R * sin(q[0]); jac[1] = -SC_L * sin(q[1]); jac[2] = -1;
    jac[3] = SC_R * cos(q[0]);  jac[4] = -SC_L * cos(q[1]); jac[5] = 0;
    jac[6] = 1;                 jac[7] = 0;                 jac[8] = 0;
}

static inline void sc_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    nu[0] = 0;
    nu[1] = 0;
    nu[2] = SC_W + SC_AL * t;
}

static inline void sc_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    (void)t;
    g[0] = SC_R * cos(q[0]) * qd[0] * qd[0] + SC_L * cos(q[1]) * qd[1] * qd[1];
    g[1] = SC_R * sin(q[0]) * qd[0] * qd[0] - SC_L * sin(q[1]) * qd[1] * qd[1];
    g[2] = SC_AL;
}

static int sc_all_calls;   /* proves mechrt used `all` when offered */

static inline void sc_all(void *ctx, const double *q, const double *qd, double t,
                   double *phi, double *jac, double *nu, double *gamma)
{
    (void)ctx;
    sc_all_calls++;
    sc_phi(ctx, q, t, phi);
    sc_jac(ctx, q, t, jac);
    sc_nu(ctx, q, t, nu);
    sc_gamma(ctx, q, qd, t, gamma);
}

static const MechrtKernels sc_kernels = {3, 3, 0, NULL, sc_phi, sc_jac, sc_nu, sc_gamma, sc_all, NULL, NULL};

/* The slider crank with one redundant velocity-level row appended,
   Psi = thd - (w + al t): NH == NQ, NR = 4. Newton uses the top 3 rows. */
static inline void scv_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    sc_jac(ctx, q, t, jac);
    jac[9] = 1;
    jac[10] = 0;
    jac[11] = 0;
}

static inline void scv_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    sc_nu(ctx, q, t, nu);
    nu[3] = SC_W + SC_AL * t;
}

static inline void scv_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    sc_gamma(ctx, q, qd, t, g);
    g[3] = SC_AL;
}

static const MechrtKernels scv_kernels = {3, 3, 1, NULL, sc_phi, scv_jac, scv_nu, scv_gamma, NULL, NULL, NULL};
static const MechrtKernels sc_kernels_noall = {3, 3, 0, NULL, sc_phi, sc_jac, sc_nu, sc_gamma, NULL, NULL, NULL};

static inline void sc_exact(double t, double *q, double *qd, double *qdd)
{
    double th = SC_A + SC_W * t + 0.5 * SC_AL * t * t, thd = SC_W + SC_AL * t, thdd = SC_AL;
    double be = asin(SC_R * sin(th) / SC_L);
    double cth = cos(th), sth = sin(th), cbe = cos(be), sbe = sin(be);
    double bed = SC_R * cth * thd / (SC_L * cbe);
    double bedd = (SC_R * cth * thdd - SC_R * sth * thd * thd + SC_L * sbe * bed * bed)
                  / (SC_L * cbe);
    q[0] = th;   q[1] = be;   q[2] = SC_R * cth + SC_L * cbe;
    qd[0] = thd; qd[1] = bed; qd[2] = -SC_R * sth * thd - SC_L * sbe * bed;
    qdd[0] = thdd;
    qdd[1] = bedd;
    qdd[2] = -SC_R * cth * thd * thd - SC_R * sth * thdd - SC_L * cbe * bed * bed
             - SC_L * sbe * bedd;
}

/* ---- mechanism 2: point on a circle, driven along x --------------------
 * q = (x, y). Phi = (x^2 + y^2 - R^2, x - d), d = R cos(c + w t).
 * Phi_q = [[2x, 2y], [1, 0]]: singular on y = 0 (the dead point).
 */
#define CI_R 0.8
#define CI_C 0.6
#define CI_W 1.1

static inline void ci_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = q[0] * q[0] + q[1] * q[1] - CI_R * CI_R;
    phi[1] = q[0] - CI_R * cos(CI_C + CI_W * t);
}

static inline void ci_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    (void)t;
    jac[0] = 2 * q[0]; jac[1] = 2 * q[1];
    jac[2] = 1;        jac[3] = 0;
}

static inline void ci_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    nu[0] = 0;
    nu[1] = -CI_R * CI_W * sin(CI_C + CI_W * t);
}

static inline void ci_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    (void)q;
    g[0] = -2 * (qd[0] * qd[0] + qd[1] * qd[1]);
    g[1] = -CI_R * CI_W * CI_W * cos(CI_C + CI_W * t);
}

static const MechrtKernels ci_kernels = {2, 2, 0, NULL, ci_phi, ci_jac, ci_nu, ci_gamma, NULL, NULL, NULL};

/* ---- mechanism 3: knife-edge cart driven by heading and speed ----------
 * q = (x, y, th). One holonomic row, two velocity-level rows:
 *   Phi  = th - (b + w t)                            (driver)
 *   Psi1 = -sin th xd + cos th yd                    (knife: no side slip)
 *   Psi2 =  cos th xd + sin th yd - v                (speed driver)
 * Phi_q = [[0, 0, 1], [-sin th, cos th, 0], [cos th, sin th, 0]]
 * nu    = (w, 0, v)
 * gamma = -(dPsi/dq qd + dPsi/dt):
 *       = (0, (cos th xd + sin th yd) thd, (sin th xd - cos th yd) thd)
 * Solution: thd = w, (xd, yd) = v (cos th, sin th),
 * (xdd, ydd) = v w (-sin th, cos th): the centripetal acceleration.
 */
#define KN_B 0.7371
#define KN_W 0.45
#define KN_V 1.9

static inline void kn_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = q[2] - (KN_B + KN_W * t);
}

static inline void kn_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    double c = cos(q[2]), s = sin(q[2]);
    (void)t;
    jac[0] = 0;  jac[1] = 0; jac[2] = 1;
    jac[3] = -s; jac[4] = c; jac[5] = 0;
    jac[6] = c;  jac[7] = s; jac[8] = 0;
}

static inline void kn_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    (void)t;
    nu[0] = KN_W;
    nu[1] = 0;
    nu[2] = KN_V;
}

static inline void kn_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    double c = cos(q[2]), s = sin(q[2]);
    (void)t;
    g[0] = 0;
    g[1] = (c * qd[0] + s * qd[1]) * qd[2];
    g[2] = (s * qd[0] - c * qd[1]) * qd[2];
}

static const MechrtKernels kn_kernels = {3, 1, 2, NULL, kn_phi, kn_jac, kn_nu, kn_gamma, NULL, NULL, NULL};

/* A kernel set whose second row is NaN: the runtime must say so. */
static inline void nan_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    sc_phi(ctx, q, t, phi);
    phi[1] = NAN;
}

static const MechrtKernels nan_kernels = {3, 3, 0, NULL, nan_phi, sc_jac, sc_nu, sc_gamma, NULL, NULL, NULL};

#endif
