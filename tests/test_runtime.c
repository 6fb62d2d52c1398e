/* test_runtime.c - the freestanding runtime: LU against GSL, Newton, analysis, float build.
 *
 * The mechanisms are hand-written kernels with the generated code's
 * signatures, their derivatives worked out by hand (comments above each):
 *   slider crank in minimal coordinates (nonlinear, NH == NQ == 3),
 *   a point on a circle driven along x (singular where y = 0),
 *   a knife-edge cart (NH = 1, NV = 2: velocity-level rows).
 * States are "high entropy" (angles like 0.7371), never 0.
 * The end of the file compiles the runtime a second time, as float.
 */
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
static double rnd(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) / 4503599627370496.0 - 1.0;
}

static double *xmalloc(size_t n)
{
    double *p = malloc(n * sizeof *p);
    assert_non_null(p);
    return p;
}

static double inf_norm(int n, const double *v)
{
    double m = 0;
    for (int i = 0; i < n; i++)
        if (fabs(v[i]) > m)
            m = fabs(v[i]);
    return m;
}

/* kappa_1(A) = ||A||_1 ||A^-1||_1 with the inverse from GSL */
static double gsl_cond1(int n, const double *a, int lda)
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

static void sc_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = SC_R * cos(q[0]) + SC_L * cos(q[1]) - q[2];
    phi[1] = SC_R * sin(q[0]) - SC_L * sin(q[1]);
    phi[2] = q[0] - (SC_A + SC_W * t + 0.5 * SC_AL * t * t);
}

static void sc_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    (void)t;
    jac[0] = -SC_R * sin(q[0]); jac[1] = -SC_L * sin(q[1]); jac[2] = -1;
    jac[3] = SC_R * cos(q[0]);  jac[4] = -SC_L * cos(q[1]); jac[5] = 0;
    jac[6] = 1;                 jac[7] = 0;                 jac[8] = 0;
}

static void sc_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    nu[0] = 0;
    nu[1] = 0;
    nu[2] = SC_W + SC_AL * t;
}

static void sc_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    (void)t;
    g[0] = SC_R * cos(q[0]) * qd[0] * qd[0] + SC_L * cos(q[1]) * qd[1] * qd[1];
    g[1] = SC_R * sin(q[0]) * qd[0] * qd[0] - SC_L * sin(q[1]) * qd[1] * qd[1];
    g[2] = SC_AL;
}

static int sc_all_calls;   /* proves mechrt used `all` when offered */

static void sc_all(void *ctx, const double *q, const double *qd, double t,
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
static void scv_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    sc_jac(ctx, q, t, jac);
    jac[9] = 1;
    jac[10] = 0;
    jac[11] = 0;
}

static void scv_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    sc_nu(ctx, q, t, nu);
    nu[3] = SC_W + SC_AL * t;
}

static void scv_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    sc_gamma(ctx, q, qd, t, g);
    g[3] = SC_AL;
}

static const MechrtKernels scv_kernels = {3, 3, 1, NULL, sc_phi, scv_jac, scv_nu, scv_gamma, NULL, NULL, NULL};
static const MechrtKernels sc_kernels_noall = {3, 3, 0, NULL, sc_phi, sc_jac, sc_nu, sc_gamma, NULL, NULL, NULL};

static void sc_exact(double t, double *q, double *qd, double *qdd)
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

static void ci_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = q[0] * q[0] + q[1] * q[1] - CI_R * CI_R;
    phi[1] = q[0] - CI_R * cos(CI_C + CI_W * t);
}

static void ci_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    (void)t;
    jac[0] = 2 * q[0]; jac[1] = 2 * q[1];
    jac[2] = 1;        jac[3] = 0;
}

static void ci_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    nu[0] = 0;
    nu[1] = -CI_R * CI_W * sin(CI_C + CI_W * t);
}

static void ci_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
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

static void kn_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = q[2] - (KN_B + KN_W * t);
}

static void kn_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    double c = cos(q[2]), s = sin(q[2]);
    (void)t;
    jac[0] = 0;  jac[1] = 0; jac[2] = 1;
    jac[3] = -s; jac[4] = c; jac[5] = 0;
    jac[6] = c;  jac[7] = s; jac[8] = 0;
}

static void kn_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    (void)t;
    nu[0] = KN_W;
    nu[1] = 0;
    nu[2] = KN_V;
}

static void kn_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
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
static void nan_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    sc_phi(ctx, q, t, phi);
    phi[1] = NAN;
}

static const MechrtKernels nan_kernels = {3, 3, 0, NULL, nan_phi, sc_jac, sc_nu, sc_gamma, NULL, NULL, NULL};

/* ---- LU ---------------------------------------------------------------- */

/* Factors, solves and the transposed solve agree with GSL on random
   matrices of sizes 1..40 stored with lda > n; the condition estimate is a
   lower bound within a factor 10 of the truth. */
static void test_lu_matches_gsl(void **state)
{
    (void)state;
    uint64_t seed = 0x9E3779B97F4A7C15ULL;

    for (int n = 1; n <= 40; n++) {
        int lda = n + 3;
        double *a = xmalloc((size_t)(n * lda)), *lu = xmalloc((size_t)(n * lda));
        double *piv = xmalloc((size_t)n), *b = xmalloc((size_t)n), *x = xmalloc((size_t)n);
        double *work = xmalloc((size_t)(2 * n));
        gsl_matrix *m = gsl_matrix_alloc((size_t)n, (size_t)n);
        gsl_matrix *mt = gsl_matrix_alloc((size_t)n, (size_t)n);
        gsl_permutation *p = gsl_permutation_alloc((size_t)n);
        gsl_permutation *pt = gsl_permutation_alloc((size_t)n);
        gsl_vector *gb = gsl_vector_alloc((size_t)n), *gx = gsl_vector_alloc((size_t)n);
        int sign, sing = 99;

        for (int i = 0; i < n; i++) {
            for (int j = 0; j < lda; j++) {
                a[i * lda + j] = j < n ? rnd(&seed) : NAN;   /* padding must be ignored */
                lu[i * lda + j] = a[i * lda + j];
            }
            b[i] = x[i] = rnd(&seed);
            gsl_vector_set(gb, (size_t)i, b[i]);
        }
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                gsl_matrix_set(m, (size_t)i, (size_t)j, a[i * lda + j]);
                gsl_matrix_set(mt, (size_t)j, (size_t)i, a[i * lda + j]);
            }

        assert_int_equal(mechrt_lu_factor(n, lu, lda, piv, 1e-12, &sing), MECHRT_OK);
        assert_int_equal(sing, -1);
        gsl_linalg_LU_decomp(m, p, &sign);
        gsl_linalg_LU_decomp(mt, pt, &sign);

        /* same pivots, so the same L and U up to rounding */
        double umax = 0;
        for (int i = 0; i < n * lda; i++)
            if (isfinite(lu[i]) && fabs(lu[i]) > umax)
                umax = fabs(lu[i]);
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++)
                assert_near(lu[i * lda + j], gsl_matrix_get(m, (size_t)i, (size_t)j),
                            1e-12, 1e-12 * umax);

        mechrt_lu_solve(n, lu, lda, piv, x);
        gsl_linalg_LU_solve(m, p, gb, gx);
        double xmax = inf_norm(n, gx->data);
        for (int i = 0; i < n; i++)
            assert_near(x[i], gsl_vector_get(gx, (size_t)i), 1e-12, 1e-12 * xmax);

        for (int i = 0; i < n; i++)
            x[i] = b[i];
        mechrt_lu_solve_t(n, lu, lda, piv, x);
        gsl_linalg_LU_solve(mt, pt, gb, gx);
        xmax = inf_norm(n, gx->data);
        for (int i = 0; i < n; i++)
            assert_near(x[i], gsl_vector_get(gx, (size_t)i), 1e-12, 1e-12 * xmax);

        double est = mechrt_lu_cond1(n, lu, lda, piv, mechrt_norm1(n, a, lda), work);
        double truth = gsl_cond1(n, a, lda);
        if (!(est <= truth * (1 + 1e-10) && est >= truth / 10))
            fail_msg("n = %d: condition estimate %.6g, true %.6g", n, est, truth);

        gsl_vector_free(gx);
        gsl_vector_free(gb);
        gsl_permutation_free(pt);
        gsl_permutation_free(p);
        gsl_matrix_free(mt);
        gsl_matrix_free(m);
        free(work);
        free(x);
        free(b);
        free(piv);
        free(lu);
        free(a);
    }
}

/* Hilbert 8x8 (kappa_1 ~ 3.4e10): backward-stable solve, so a tiny
   residual; the estimate within a factor 10 of the true condition. */
static void test_lu_hilbert(void **state)
{
    (void)state;
    enum { N = 8 };
    double h[N * N], lu[N * N], piv[N], x[N], b[N], work[2 * N];

    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            h[i * N + j] = lu[i * N + j] = 1.0 / (i + j + 1);
    for (int i = 0; i < N; i++) {
        b[i] = 0;
        for (int j = 0; j < N; j++)
            b[i] += h[i * N + j];   /* x = ones */
        x[i] = b[i];
    }
    assert_int_equal(mechrt_lu_factor(N, lu, N, piv, 1e-12, NULL), MECHRT_OK);
    mechrt_lu_solve(N, lu, N, piv, x);

    double rmax = 0;
    for (int i = 0; i < N; i++) {
        double r = -b[i];
        for (int j = 0; j < N; j++)
            r += h[i * N + j] * x[j];
        if (fabs(r) > rmax)
            rmax = fabs(r);
    }
    assert_true(rmax <= 1e-14);
    for (int i = 0; i < N; i++)
        assert_near(x[i], 1.0, 0, 1e-4);   /* forward error ~ kappa eps */

    double est = mechrt_lu_cond1(N, lu, N, piv, mechrt_norm1(N, h, N), work);
    double truth = gsl_cond1(N, h, N);
    assert_true(truth > 1e10);
    if (!(est >= truth / 10 && est <= truth * 10))
        fail_msg("Hilbert 8: condition estimate %.6g, true %.6g", est, truth);
}

/* A rank-deficient matrix is reported singular at the dependent column;
   the zero matrix at column 0; NaN is its own error; bad sizes are EINVAL. */
static void test_lu_singular(void **state)
{
    (void)state;
    enum { N = 5 };
    uint64_t seed = 42;
    double a[N * N], piv[N];
    int sing = 99;

    /* integer entries in [-5, 5], column 3 = column 0 - 2 column 1 */
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            a[i * N + j] = floor(5.5 * rnd(&seed) + 0.5);
    for (int i = 0; i < N; i++)
        a[i * N + 3] = a[i * N + 0] - 2 * a[i * N + 1];
    assert_int_equal(mechrt_lu_factor(N, a, N, piv, 1e-12, &sing), MECHRT_ESING);
    assert_int_equal(sing, 3);

    /* real entries: the dependent column leaves a rounding-level pivot,
       which only the relative threshold catches */
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++)
            a[i * N + j] = rnd(&seed);
        a[i * N + 2] = 0.3 * a[i * N + 0] - 1.7 * a[i * N + 1];
    }
    assert_int_equal(mechrt_lu_factor(N, a, N, piv, 1e-12, &sing), MECHRT_ESING);
    assert_int_equal(sing, 2);

    /* the threshold is relative to the largest entry, whatever the units */
    for (int e = 0; e < 3; e++) {
        double sc = e == 0 ? 1 : e == 1 ? 1e-20 : 1e20;
        double near[4] = {sc, sc, sc, sc * (1 + 1e-14)}, good[4] = {sc, 2 * sc, -sc, sc};
        double m[4];
        for (int i = 0; i < 4; i++)
            m[i] = near[i];
        assert_int_equal(mechrt_lu_factor(2, m, 2, piv, 1e-12, &sing), MECHRT_ESING);
        assert_int_equal(sing, 1);
        for (int i = 0; i < 4; i++)
            m[i] = near[i];
        assert_int_equal(mechrt_lu_factor(2, m, 2, piv, 1e-15, &sing), MECHRT_OK);
        for (int i = 0; i < 4; i++)
            m[i] = good[i];
        assert_int_equal(mechrt_lu_factor(2, m, 2, piv, 1e-12, &sing), MECHRT_OK);
    }

    for (int i = 0; i < N * N; i++)
        a[i] = 0;
    assert_int_equal(mechrt_lu_factor(N, a, N, piv, 1e-12, &sing), MECHRT_ESING);
    assert_int_equal(sing, 0);

    for (int i = 0; i < N * N; i++)
        a[i] = (i % 7) + (i % 3) * 0.25;
    a[7] = INFINITY;
    assert_int_equal(mechrt_lu_factor(N, a, N, piv, 1e-12, &sing), MECHRT_ENOTFINITE);
    a[7] = NAN;
    assert_int_equal(mechrt_lu_factor(N, a, N, piv, 1e-12, &sing), MECHRT_ENOTFINITE);

    assert_int_equal(mechrt_lu_factor(N, a, N - 1, piv, 1e-12, &sing), MECHRT_EINVAL);
    assert_int_equal(mechrt_lu_factor(-1, a, N, piv, 1e-12, &sing), MECHRT_EINVAL);
    assert_int_equal(mechrt_lu_factor(0, NULL, 0, NULL, 1e-12, &sing), MECHRT_OK);
}

/* ---- workspace, options, strings --------------------------------------- */

static void test_workspace_size(void **state)
{
    (void)state;
    assert_int_equal(mechrt_workspace_size(3, 3), 3 * 3 + 3 * 3 + 5 * 3);
    assert_int_equal(mechrt_workspace_size(3, 3), MECHRT_WORKSPACE_LEN(3, 3));
    assert_int_equal(mechrt_workspace_size(7, 5), MECHRT_WORKSPACE_LEN(7, 5));
    assert_int_equal(mechrt_workspace_size(4, 0), MECHRT_WORKSPACE_LEN(4, 0));
    assert_int_equal(mechrt_workspace_size(0, 3), 0);
    assert_int_equal(mechrt_workspace_size(3, -1), 0);
    if (sizeof(size_t) == 4)
        assert_int_equal(mechrt_workspace_size(70000, 70000), 0);
}

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

static void test_options_and_strings(void **state)
{
    (void)state;
    MechrtOptions o = mechrt_default_options();
    assert_true(o.tol_phi > 0 && o.tol_phi < 1e-6);
    assert_true(o.tol_dq > 0 && o.tol_dq < 1e-6);
    assert_true(o.max_iter >= 10);
    assert_true(o.pivot_tol > 0 && o.pivot_tol < 1e-8);
    assert_true(o.cond_warn > 1e6);

    const MechrtStatus all[] = {MECHRT_OK, MECHRT_CONTINUE, MECHRT_ESING, MECHRT_EMAXITER,
                                MECHRT_EBADLEN, MECHRT_ENOTFINITE, MECHRT_ENOTSQUARE,
                                MECHRT_EINVAL, MECHRT_ESTEP};
    const int n = (int)(sizeof all / sizeof all[0]);
    for (int i = 0; i < n; i++) {
        const char *s = mechrt_strerror(all[i]);
        assert_non_null(s);
        assert_true(s[0] != '\0');
        for (int j = 0; j < i; j++)
            assert_string_not_equal(s, mechrt_strerror(all[j]));
    }
    assert_string_equal(mechrt_strerror((MechrtStatus)1000), "unknown status");
    assert_string_equal(mechrt_strerror(MECHRT_ESING), "singular matrix");
}

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

/* mechrt_lu_factor_norm1: the factors of mechrt_lu_factor and the norm of
   mechrt_norm1, bit for bit, and the same errors. */
static void test_lu_factor_norm1(void **state)
{
    (void)state;
    enum { N = 7, LDA = 9 };
    double a[N * LDA], b[N * LDA], pa[N], pb[N], work[N], anorm;
    uint64_t seed = 7;
    int sa, sb;

    for (int i = 0; i < N * LDA; i++)
        a[i] = b[i] = i % 4 == 0 ? 0.0 : rnd(&seed);   /* sparse, like a Jacobian */
    double expect = mechrt_norm1(N, a, LDA);
    assert_int_equal(mechrt_lu_factor(N, a, LDA, pa, 1e-12, &sa), MECHRT_OK);
    assert_int_equal(mechrt_lu_factor_norm1(N, b, LDA, pb, 1e-12, &sb, &anorm, work), MECHRT_OK);
    assert_true(anorm == expect && anorm > 0);
    assert_int_equal(sa, sb);
    assert_memory_equal(a, b, sizeof a);
    assert_memory_equal(pa, pb, sizeof pa);
    b[LDA + 2] = NAN;
    assert_int_equal(mechrt_lu_factor_norm1(N, b, LDA, pb, 1e-12, &sb, &anorm, work),
                     MECHRT_ENOTFINITE);
    b[LDA + 2] = INFINITY;
    assert_int_equal(mechrt_lu_factor_norm1(N, b, LDA, pb, 1e-12, &sb, &anorm, work),
                     MECHRT_ENOTFINITE);
    assert_int_equal(mechrt_lu_factor_norm1(N, b, LDA, pb, 1e-12, &sb, NULL, work),
                     MECHRT_EINVAL);
}

/* The double build's answer, for comparison with the float build below
   (past the float include, mechrt_* names the float functions). */
static MechrtStatus double_lu_solve(int n, double *a, double *piv, double *b)
{
    MechrtStatus st = mechrt_lu_factor(n, a, n, piv, 1e-12, NULL);
    if (st == MECHRT_OK)
        mechrt_lu_solve(n, a, n, piv, b);
    return st;
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

/* ---- kernel wrappers and the context pointer ---------------------------
 * MECHRT_DEFINE_KERNELS is what firmware writes next to `mechc gen` output:
 * here over context-free functions named like generated ones (gc_phi ...,
 * GC_NQ ...), built from the point-on-circle kernels. A host engine passes
 * its state as ctx instead; the runtime must hand it to every kernel.
 */
#define GC_NQ 2
#define GC_NH 2
#define GC_NV 0

static void gc_phi(const double *q, double t, double *phi) { ci_phi(NULL, q, t, phi); }
static void gc_jac(const double *q, double t, double *jac) { ci_jac(NULL, q, t, jac); }
static void gc_nu(const double *q, double t, double *nu) { ci_nu(NULL, q, t, nu); }

static void gc_gamma(const double *q, const double *qd, double t, double *g)
{
    ci_gamma(NULL, q, qd, t, g);
}

static int gc_all_calls;

static void gc_all(const double *q, const double *qd, double t,
                   double *phi, double *jac, double *nu, double *gamma)
{
    gc_all_calls++;
    gc_phi(q, t, phi);
    gc_jac(q, t, jac);
    gc_nu(q, t, nu);
    gc_gamma(q, qd, t, gamma);
}

MECHRT_DEFINE_KERNELS(gc, GC);

typedef struct CountCtx {
    int magic, phi, jac, nu, gamma;
} CountCtx;

static void cc_phi(void *ctx, const double *q, double t, double *phi)
{
    CountCtx *c = ctx;
    assert_int_equal(c->magic, 4242);
    c->phi++;
    ci_phi(NULL, q, t, phi);
}

static void cc_jac(void *ctx, const double *q, double t, double *jac)
{
    CountCtx *c = ctx;
    assert_int_equal(c->magic, 4242);
    c->jac++;
    ci_jac(NULL, q, t, jac);
}

static void cc_nu(void *ctx, const double *q, double t, double *nu)
{
    CountCtx *c = ctx;
    assert_int_equal(c->magic, 4242);
    c->nu++;
    ci_nu(NULL, q, t, nu);
}

static void cc_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    CountCtx *c = ctx;
    assert_int_equal(c->magic, 4242);
    c->gamma++;
    ci_gamma(NULL, q, qd, t, g);
}

static void test_kernel_wrappers(void **state)
{
    (void)state;
    const double t = 0.37, h = 0.01;
    double q[2] = {0.5, 0.6}, qd[2] = {0}, qdd[2] = {0}, q2[2], qd2[2] = {0}, qdd2[2] = {0};
    double work[64];
    MechrtReport rep;
    CountCtx cc = {4242, 0, 0, 0, 0};
    MechrtKernels ck = {2, 2, 0, &cc, cc_phi, cc_jac, cc_nu, cc_gamma, NULL, NULL, NULL};

    assert_int_equal(gc_kernels.nq, 2);
    assert_int_equal(gc_kernels.nh, 2);
    assert_int_equal(gc_kernels.nv, 0);
    assert_null(gc_kernels.ctx);
    q2[0] = q[0];
    q2[1] = q[1];
    gc_all_calls = 0;
    assert_int_equal(mechrt_step(&gc_kernels, NULL, q, qd, qdd, t, 0, work, 64, &rep), MECHRT_OK);
    assert_true(gc_all_calls >= 2);   /* Newton evaluates through `all` */
    assert_int_equal(mechrt_step(&gc_kernels, NULL, q, qd, qdd, t, h, work, 64, &rep), MECHRT_OK);
    /* the context-taking kernels give the same numbers and see their ctx */
    assert_int_equal(mechrt_step(&ck, NULL, q2, qd2, qdd2, t, 0, work, 64, &rep), MECHRT_OK);
    assert_int_equal(mechrt_step(&ck, NULL, q2, qd2, qdd2, t, h, work, 64, &rep), MECHRT_OK);
    assert_true(cc.phi >= 2 && cc.jac >= 2 && cc.nu >= 2 && cc.gamma == 2);
    for (int i = 0; i < 2; i++) {
        assert_near(q2[i], q[i], 0, 1e-14);
        assert_near(qd2[i], qd[i], 1e-13, 1e-14);
        assert_near(qdd2[i], qdd[i], 1e-12, 1e-13);
    }
    assert_near(q[0], CI_R * cos(CI_C + CI_W * (t + h)), 0, 1e-12);
}

/* ---- pattern LU -----------------------------------------------------------
 * mechrt_lup_* against lu.c on the same matrices: by design the same
 * operations in the same order, so the comparisons are exact (==), which
 * is stronger than the 1e-12 first asked of it. */

/* A random n x n pattern (density about d, the diagonal always in) with
   values; row-major entries, as the generated kernels list them. */
typedef struct LupCase {
    int n, nnz;
    int row[400], col[400];
    double val[400];
} LupCase;

static void lup_case(LupCase *c, int n, double d, uint64_t *seed)
{
    c->n = n;
    c->nnz = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            if (i == j || fabs(rnd(seed)) < d) {
                c->row[c->nnz] = i;
                c->col[c->nnz] = j;
                c->val[c->nnz++] = rnd(seed);
            }
}

static void lup_dense_of(const LupCase *c, double *a)
{
    for (int i = 0; i < c->n * c->n; i++)
        a[i] = 0;
    for (int e = 0; e < c->nnz; e++)
        a[c->row[e] * c->n + c->col[e]] = c->val[e];
}

/* Factors c's values both ways and checks statuses, sing_index and, when
   both succeed, the solution of a random right side, bit for bit. */
static MechrtStatus lup_check(MechrtLup *f, const LupCase *c, uint64_t *seed)
{
    int n = c->n, sd, sp;
    double a[400], piv[20], b[20], xd[20], xp[20];

    lup_dense_of(c, a);
    for (int e = 0; e < c->nnz; e++)
        mechrt_lup_values(f)[e] = c->val[e];
    MechrtStatus std = mechrt_lu_factor(n, a, n, piv, 1e-12, &sd);
    MechrtStatus stp = mechrt_lup_factor(f, 1e-12, &sp);
    assert_int_equal(stp, std);
    assert_int_equal(sp, sd);
    if (std != MECHRT_OK)
        return std;
    for (int i = 0; i < n; i++)
        xd[i] = b[i] = rnd(seed);
    mechrt_lu_solve(n, a, n, piv, xd);
    mechrt_lup_solve(f, b, xp);
    for (int i = 0; i < n; i++)
        if (xp[i] != xd[i])
            fail_msg("n = %d, x[%d]: pattern %.17g, dense %.17g", n, i, xp[i], xd[i]);
    assert_true(mechrt_lup_spread(f) >= 1);
    return std;
}

/* Random sparse systems of sizes 1..20, each factored 30 times with
   values drifting (the pivot order mostly kept: replays) and jumping
   (new orders: lu.c finishes and the order is recorded again). */
static void test_lup_matches_dense(void **state)
{
    (void)state;
    static double work[MECHRT_LUP_WORK_LEN(20)];
    static int iwork[MECHRT_LUP_IWORK_LEN(20)];
    uint64_t seed = 17;
    long replays = 0, analyses = 0;

    for (int n = 1; n <= 20; n++) {
        LupCase c;
        MechrtLup f;
        lup_case(&c, n, 0.2, &seed);
        assert_int_equal(mechrt_lup_init(&f, n, c.nnz, c.row, c.col, work, MECHRT_LUP_WORK_LEN(n),
                                         iwork, MECHRT_LUP_IWORK_LEN(n)), MECHRT_OK);
        for (int rep = 0; rep < 30; rep++) {
            double jump = rep % 10 == 9 ? 1.0 : 0.01;
            lup_check(&f, &c, &seed);
            for (int e = 0; e < c.nnz; e++)
                c.val[e] += jump * rnd(&seed);
        }
        replays += f.replays;
        analyses += f.analyses;
    }
    /* most factorisations replay; random values tie often, so orders
       change on drift too, besides the 60 jumps */
    assert_true(replays > 3 * analyses);
    assert_true(analyses > 60);
}

/* The recorded pivot vanishes, or is overtaken (also by a tie that lu.c
   breaks the other way): lu.c finishes the factorisation and the new
   order is recorded; same results. */
static void test_lup_pivot_fallback(void **state)
{
    (void)state;
    /* full 3 x 3: column 0's pivot is row 2 first (|3| largest) */
    LupCase c = {3, 9, {0, 0, 0, 1, 1, 1, 2, 2, 2}, {0, 1, 2, 0, 1, 2, 0, 1, 2},
                 {1, 2, 3, 2, 1, 4, 3, 5, 1}};
    double work[MECHRT_LUP_WORK_LEN(3)];
    int iwork[MECHRT_LUP_IWORK_LEN(3)];
    uint64_t seed = 5;
    MechrtLup f;

    assert_int_equal(mechrt_lup_init(&f, 3, c.nnz, c.row, c.col, work, MECHRT_LUP_WORK_LEN(3),
                                     iwork, MECHRT_LUP_IWORK_LEN(3)), MECHRT_OK);
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    assert_int_equal(f.analyses, 1);
    assert_int_equal(f.replays, 0);
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    assert_int_equal(f.replays, 1);
    c.val[6] = 0;   /* the pivot of column 0 vanishes */
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    assert_int_equal(f.analyses, 2);
    assert_int_equal(f.replays, 1);
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);   /* the new order replays */
    assert_int_equal(f.replays, 2);
    c.val[6] = 2;   /* ties row 1 (before it): lu.c keeps the first, row 1 */
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    c.val[3] = -2;  /* still tied, sign aside */
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    long before = f.analyses;
    c.val[6] = 2.5; /* overtakes */
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    assert_int_equal(f.analyses, before + 1);
}

/* Singular matrices: MECHRT_ESING at lu.c's step, whether the step has
   candidates or not, with or without an order; NaN is ENOTFINITE; a
   regular matrix afterwards factors again. */
static void test_lup_singular(void **state)
{
    (void)state;
    /* 4 x 4, lower bidiagonal plus a corner: column 3 has one entry */
    LupCase c = {4, 7, {0, 1, 1, 2, 2, 3, 3}, {0, 0, 1, 1, 2, 2, 3},
                 {2, 1, 3, 1, 4, 1, 5}};
    double work[MECHRT_LUP_WORK_LEN(4)];
    int iwork[MECHRT_LUP_IWORK_LEN(4)];
    uint64_t seed = 9;
    MechrtLup f;

    assert_int_equal(mechrt_lup_init(&f, 4, c.nnz, c.row, c.col, work, MECHRT_LUP_WORK_LEN(4),
                                     iwork, MECHRT_LUP_IWORK_LEN(4)), MECHRT_OK);
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    c.val[6] = 1e-14;   /* a step without candidates: below 1e-12 * max */
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_ESING);
    c.val[6] = 5;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    c.val[2] = 0;   /* column 1 all zero: singular at step 1 (lu.c decides) */
    c.val[3] = 0;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_ESING);
    c.val[2] = 3;
    c.val[3] = 1;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    c.val[0] = 0;
    c.val[1] = 0;   /* column 0 all zero: the first step */
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_ESING);
    c.val[0] = 2;
    c.val[1] = 1;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    c.val[4] = NAN;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_ENOTFINITE);
    c.val[4] = INFINITY;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_ENOTFINITE);
    c.val[4] = 4;
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    /* replays: the tiny pivot (ESING without lu.c), the two regular
       matrices after it; lu.c finished the two with a zero column and the
       order was recorded anew after each */
    assert_int_equal(f.replays, 2);
    assert_int_equal(f.analyses, 3);
}

/* Sizes, bad patterns and short workspaces; an integer workspace with room
   for no program keeps every factorisation dense, with the same results. */
static void test_lup_workspace(void **state)
{
    (void)state;
    LupCase c;
    uint64_t seed = 3;
    double work[MECHRT_LUP_WORK_LEN(12)];
    int iwork[MECHRT_LUP_IWORK_LEN(12)];
    MechrtLup f;
    int row[2] = {0, 0}, col[2] = {1, 1}, bad[2] = {0, 3};

    assert_int_equal(mechrt_lup_work_size(12), MECHRT_LUP_WORK_LEN(12));
    assert_int_equal(mechrt_lup_iwork_size(12), MECHRT_LUP_IWORK_LEN(12));
    assert_int_equal(mechrt_lup_iwork_size(1), 1 + 14 + 2);
    assert_int_equal(mechrt_lup_work_size(0), 0);
    assert_int_equal(mechrt_lup_iwork_size(MECHRT_LUP_MAX_N + 1), 0);
    assert_int_equal(mechrt_lup_init(&f, 3, 2, row, col, work, 99, iwork, 99), MECHRT_EINVAL);
    assert_int_equal(mechrt_lup_init(&f, 3, 2, bad, col, work, 99, iwork, 99), MECHRT_EINVAL);
    assert_int_equal(mechrt_lup_init(&f, 3, 2, col, bad, work, 99, iwork, 99), MECHRT_EINVAL);
    assert_int_equal(mechrt_lup_init(&f, 3, 1, row, col, work, MECHRT_LUP_WORK_LEN(3) - 1,
                                     iwork, 99), MECHRT_EBADLEN);
    assert_int_equal(mechrt_lup_init(&f, 3, 1, row, col, work, 99, iwork, 9 + 17),
                     MECHRT_EBADLEN);
    assert_int_equal(mechrt_lup_init(NULL, 3, 1, row, col, work, 99, iwork, 99), MECHRT_EINVAL);

    lup_case(&c, 12, 0.3, &seed);
    assert_int_equal(mechrt_lup_init(&f, 12, c.nnz, c.row, c.col, work, MECHRT_LUP_WORK_LEN(12),
                                     iwork, 144 + 72), MECHRT_OK);
    for (int rep = 0; rep < 3; rep++)
        assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    assert_int_equal(f.replays, 0);
    assert_false(f.ordered);
    /* from a dense matrix: the same as from the values */
    double a[144];
    lup_dense_of(&c, a);
    assert_int_equal(mechrt_lup_init(&f, 12, c.nnz, c.row, c.col, work, MECHRT_LUP_WORK_LEN(12),
                                     iwork, MECHRT_LUP_IWORK_LEN(12)), MECHRT_OK);
    assert_int_equal(lup_check(&f, &c, &seed), MECHRT_OK);
    assert_int_equal(mechrt_lup_factor_dense(&f, a, 12, 1e-12, NULL), MECHRT_OK);
    assert_int_equal(f.replays, 1);
    assert_int_equal(mechrt_lup_factor_dense(&f, a, 11, 1e-12, NULL), MECHRT_EINVAL);
}

/* The slider crank's Jacobian has zeros at (1, 2), (2, 1) and (2, 2). */
static const int sc_row[6] = {0, 0, 0, 1, 1, 2}, sc_col[6] = {0, 1, 2, 0, 1, 0};

static void sc_jac_nz(void *ctx, const double *q, double t, double *vals)
{
    double jac[9];
    sc_jac(ctx, q, t, jac);
    for (int e = 0; e < 6; e++)
        vals[e] = jac[sc_row[e] * 3 + sc_col[e]];
}

static const MechrtJacNz sc_jnz = {6, sc_row, sc_col, NULL, sc_jac_nz};

static void report_equal(const MechrtReport *a, const MechrtReport *b)
{
    assert_int_equal(a->iterations, b->iterations);
    assert_true(a->residual == b->residual);
    assert_true(a->step == b->step);
    assert_int_equal(a->worst_row, b->worst_row);
    assert_int_equal(a->sing_index, b->sing_index);
    assert_true(a->cond == b->cond);
    assert_int_equal(a->cond_warning, b->cond_warning);
    assert_int_equal(a->factorisations, b->factorisations);
}

/* mechrt_step_lup against mechrt_step: the same states and reports, bit
   for bit, in coarse and fine steps, with the condition estimate always
   on, through jac_nz, `all` and phi + jac. */
static void test_step_lup(void **state)
{
    (void)state;
    static double lw[MECHRT_LUP_WORK_LEN(3)];
    static int liw[MECHRT_LUP_IWORK_LEN(3)];
    const MechrtJacNz *jn[3] = {&sc_jnz, NULL, NULL};
    const MechrtKernels *ks[3] = {&sc_kernels_noall, &sc_kernels, &sc_kernels_noall};
    MechrtOptions o = mechrt_default_options();
    double work[64], work2[64];

    o.cond_screen = 0;
    for (int v = 0; v < 3; v++) {
        for (int steps = 20; steps <= 2000; steps *= 100) {
            double q[3], qd[3], qdd[3], p[3], pd[3], pdd[3], t = 0, h = 1.0 / steps;
            MechrtReport rd, rp;
            MechrtLup f;
            assert_int_equal(mechrt_lup_init(&f, 3, 6, sc_row, sc_col, lw, MECHRT_LUP_WORK_LEN(3),
                                             liw, MECHRT_LUP_IWORK_LEN(3)), MECHRT_OK);
            sc_exact(0, q, qd, qdd);
            q[0] += 0.1;   /* assembly first: h = 0 */
            memcpy(p, q, sizeof q), memcpy(pd, qd, sizeof qd), memcpy(pdd, qdd, sizeof qdd);
            for (int s = 0; s <= steps; s++) {
                double hh = s == 0 ? 0 : h;
                assert_int_equal(mechrt_step_lup(ks[v], jn[v], &f, &o, p, pd, pdd, t, hh, work2,
                                                 64, &rp),
                                 mechrt_step(ks[v], &o, q, qd, qdd, t, hh, work, 64, &rd));
                report_equal(&rp, &rd);
                assert_true(rp.cond > 1);
                for (int i = 0; i < 3; i++)
                    assert_true(p[i] == q[i] && pd[i] == qd[i] && pdd[i] == qdd[i]);
                t += hh;
            }
            assert_true(f.replays > f.analyses);
        }
    }
    /* arguments */
    MechrtLup f;
    double q[3] = {1, 2, 3}, qd[3] = {0}, qdd[3] = {0};
    MechrtReport r;
    assert_int_equal(mechrt_lup_init(&f, 3, 6, sc_row, sc_col, lw, MECHRT_LUP_WORK_LEN(3), liw,
                                     MECHRT_LUP_IWORK_LEN(3)), MECHRT_OK);
    assert_int_equal(mechrt_step_lup(&sc_kernels, &sc_jnz, &f, NULL, q, qd, qdd, 0, 0, work, 10,
                                     &r), MECHRT_EBADLEN);
    assert_int_equal(mechrt_step_lup(&kn_kernels, NULL, &f, NULL, q, qd, qdd, 0, 0, work, 64, &r),
                     MECHRT_ENOTSQUARE);
    assert_int_equal(mechrt_step_lup(&sc_kernels, &sc_jnz, NULL, NULL, q, qd, qdd, 0, 0, work, 64,
                                     &r), MECHRT_EINVAL);
    assert_int_equal(mechrt_step_lup(&sc_kernels, &sc_jnz, &f, NULL, q, qd, qdd, 0, NAN, work, 64,
                                     &r), MECHRT_EINVAL);
}

/* Through a singular configuration (the circle's dead point at y = 0):
   the same statuses, reports and iterates as mechrt_step. */
static void test_step_lup_singular(void **state)
{
    (void)state;
    static const int row[3] = {0, 0, 1}, col[3] = {0, 1, 0};
    double lw[MECHRT_LUP_WORK_LEN(2)], work[32], work2[32];
    int liw[MECHRT_LUP_IWORK_LEN(2)];
    MechrtLup f;
    /* the dead point at t* = (pi - c) / w, where a step lands */
    double q[2], qd[2] = {0}, qdd[2] = {0}, p[2], pd[2] = {0}, pdd[2] = {0}, t = 0;
    double h = (3.14159265358979323846 - CI_C) / CI_W / 46;
    MechrtReport rd, rp;
    int fails = 0;

    assert_int_equal(mechrt_lup_init(&f, 2, 3, row, col, lw, MECHRT_LUP_WORK_LEN(2), liw,
                                     MECHRT_LUP_IWORK_LEN(2)), MECHRT_OK);
    q[0] = p[0] = CI_R * cos(CI_C);
    q[1] = p[1] = CI_R * sin(CI_C);
    for (int s = 0; s < 60; s++) {
        MechrtStatus sd = mechrt_step(&ci_kernels, NULL, q, qd, qdd, t, h, work, 32, &rd);
        MechrtStatus sp = mechrt_step_lup(&ci_kernels, NULL, &f, NULL, p, pd, pdd, t, h, work2, 32,
                                          &rp);
        assert_int_equal(sp, sd);
        report_equal(&rp, &rd);
        assert_true(p[0] == q[0] && p[1] == q[1]);
        if (sd != MECHRT_OK) {
            fails++;
            break;
        }
        assert_true(pd[0] == qd[0] && pd[1] == qd[1] && pdd[0] == qdd[0] && pdd[1] == qdd[1]);
        t += h;
    }
    assert_int_equal(fails, 1);   /* it does reach the dead point (EMAXITER) */
}

/* ---- the float build ---------------------------------------------------
 * The runtime compiled again in this translation unit with
 * MECHRT_REAL_FLOAT: its external names become mechrtf_*, so it links beside
 * the double library. From here on mechrt_real is float. Kernels are the
 * double ones behind float adapters.
 */
#define MECHRT_REAL_FLOAT
#include "../runtime/lu.c"
#include "../runtime/newton.c"
#include "../runtime/analysis.c"
#include "../runtime/lu_pattern.c"
#include "../runtime/step_lup.c"

static void f2d(int n, const float *f, double *d)
{
    for (int i = 0; i < n; i++)
        d[i] = f[i];
}

static void d2f(int n, const double *d, float *f)
{
    for (int i = 0; i < n; i++)
        f[i] = (float)d[i];
}

static void fsc_phi(void *ctx, const float *q, float t, float *phi)
{
    (void)ctx;
    double dq[3], r[3];
    f2d(3, q, dq);
    sc_phi(ctx, dq, t, r);
    d2f(3, r, phi);
}

static void fsc_jac(void *ctx, const float *q, float t, float *jac)
{
    (void)ctx;
    double dq[3], r[9];
    f2d(3, q, dq);
    sc_jac(ctx, dq, t, r);
    d2f(9, r, jac);
}

static void fsc_nu(void *ctx, const float *q, float t, float *nu)
{
    (void)ctx;
    double dq[3], r[3];
    f2d(3, q, dq);
    sc_nu(ctx, dq, t, r);
    d2f(3, r, nu);
}

static void fsc_gamma(void *ctx, const float *q, const float *qd, float t, float *g)
{
    (void)ctx;
    double dq[3], dqd[3], r[3];
    f2d(3, q, dq);
    f2d(3, qd, dqd);
    sc_gamma(ctx, dq, dqd, t, r);
    d2f(3, r, g);
}

static void test_float_build(void **state)
{
    (void)state;
    /* the float names really are float */
    assert_int_equal(sizeof(mechrt_real), sizeof(float));
    MechrtOptions o = mechrt_default_options();
    assert_true(o.tol_phi >= 1e-6f);

    /* LU: a random 12 x 12 system against the double solve */
    enum { N = 12 };
    uint64_t seed = 7;
    double ad[N * N], bd[N], pd[N];
    float af[N * N], bf[N], pf[N], wf[2 * N];
    for (int i = 0; i < N * N; i++)
        af[i] = (float)(ad[i] = rnd(&seed));
    for (int i = 0; i < N; i++)
        bf[i] = (float)(bd[i] = rnd(&seed));
    assert_int_equal(mechrt_lu_factor(N, af, N, pf, 1e-5f, NULL), MECHRT_OK);
    mechrt_lu_solve(N, af, N, pf, bf);
    assert_int_equal(double_lu_solve(N, ad, pd, bd), MECHRT_OK);
    double bmax = inf_norm(N, bd);
    for (int i = 0; i < N; i++)
        assert_near(bf[i], bd[i], 1e-4, 1e-4 * bmax);
    float cf = mechrt_lu_cond1(N, af, N, pf, 1, wf);
    assert_true(cf > 0);

    /* the pattern LU: lu.c's float factors, bit for bit, replayed */
    {
        static float lw[MECHRT_LUP_WORK_LEN(N)];
        static int liw[MECHRT_LUP_IWORK_LEN(N)];
        int row[N * N], col[N * N], nnz = 0;
        float vals[N * N], a[N * N], x[N], y[N], piv[N];
        MechrtLup f;
        for (int i = 0; i < N; i++)
            for (int j = 0; j < N; j++)
                if (i == j || rnd(&seed) > 0.5) {
                    row[nnz] = i;
                    col[nnz] = j;
                    vals[nnz++] = (float)rnd(&seed);
                }
        assert_int_equal(mechrt_lup_init(&f, N, nnz, row, col, lw, MECHRT_LUP_WORK_LEN(N), liw,
                                         MECHRT_LUP_IWORK_LEN(N)), MECHRT_OK);
        for (int rep = 0; rep < 3; rep++) {
            for (int i = 0; i < N * N; i++)
                a[i] = 0;
            for (int e = 0; e < nnz; e++) {
                a[row[e] * N + col[e]] = vals[e];
                mechrt_lup_values(&f)[e] = vals[e];
            }
            assert_int_equal(mechrt_lu_factor(N, a, N, piv, 1e-5f, NULL), MECHRT_OK);
            assert_int_equal(mechrt_lup_factor(&f, 1e-5f, NULL), MECHRT_OK);
            for (int i = 0; i < N; i++)
                x[i] = y[i] = (float)rnd(&seed);
            mechrt_lu_solve(N, a, N, piv, x);
            mechrt_lup_solve(&f, y, y);
            for (int i = 0; i < N; i++)
                assert_true(x[i] == y[i]);
            for (int e = 0; e < nnz; e++)
                vals[e] += 0.001f * (float)rnd(&seed);
        }
        assert_true(f.replays >= 1);
    }

    /* assembly and a short run of the slider crank */
    MechrtKernels k = {3, 3, 0, NULL, fsc_phi, fsc_jac, fsc_nu, fsc_gamma, NULL, NULL, NULL};
    float q[3], qd[3] = {0}, qdd[3] = {0}, work[64];
    double eq[3], eqd[3], eqdd[3];
    MechrtReport rep;
    float t = 0, h = 0.05f;

    sc_exact(0, eq, eqd, eqdd);
    q[0] = (float)(eq[0] + 0.1);
    q[1] = (float)(eq[1] - 0.1);
    q[2] = (float)(eq[2] + 0.02);
    for (int step = 0; step <= 20; step++) {
        float hh = step == 0 ? 0.0f : h;
        MechrtStatus st = mechrt_step(&k, NULL, q, qd, qdd, t, hh, work, 64, &rep);
        if (st != MECHRT_OK)
            fail_msg("float, t = %g: %s", (double)(t + hh), mechrt_strerror(st));
        t += hh;
        sc_exact(t, eq, eqd, eqdd);
        for (int i = 0; i < 3; i++) {
            assert_near(q[i], eq[i], 1e-4, 1e-4);
            assert_near(qd[i], eqd[i], 1e-4, 1e-4);
            assert_near(qdd[i], eqdd[i], 1e-4, 1e-4);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lu_matches_gsl),
        cmocka_unit_test(test_lu_hilbert),
        cmocka_unit_test(test_lu_singular),
        cmocka_unit_test(test_workspace_size),
        cmocka_unit_test(test_workspace_too_small),
        cmocka_unit_test(test_options_and_strings),
        cmocka_unit_test(test_newton_converges),
        cmocka_unit_test(test_newton_decomposed),
        cmocka_unit_test(test_newton_maxiter),
        cmocka_unit_test(test_newton_singular),
        cmocka_unit_test(test_newton_errors),
        cmocka_unit_test(test_velocity_acceleration),
        cmocka_unit_test(test_velocity_rows),
        cmocka_unit_test(test_condition_warning),
        cmocka_unit_test(test_analysis_not_finite),
        cmocka_unit_test(test_step_run),
        cmocka_unit_test(test_step_predictor),
        cmocka_unit_test(test_step_reference),
        cmocka_unit_test(test_lu_factor_norm1),
        cmocka_unit_test(test_kernel_wrappers),
        cmocka_unit_test(test_lup_matches_dense),
        cmocka_unit_test(test_lup_pivot_fallback),
        cmocka_unit_test(test_lup_singular),
        cmocka_unit_test(test_lup_workspace),
        cmocka_unit_test(test_step_lup),
        cmocka_unit_test(test_step_lup_singular),
        cmocka_unit_test(test_float_build),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
