/* test_runtime.c - the runtime as firmware uses it: mechrt.h's kernel wrappers, the float build. */
#include "testrt.h"

/* The double build's answer, for comparison with the float build below
   (past the float include, mechrt_* names the float functions). */
static MechrtStatus double_lu_solve(int n, double *a, double *piv, double *b)
{
    MechrtStatus st = mechrt_lu_factor(n, a, n, piv, 1e-12, NULL);
    if (st == MECHRT_OK)
        mechrt_lu_solve(n, a, n, piv, b);
    return st;
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
        cmocka_unit_test(test_kernel_wrappers),
        cmocka_unit_test(test_float_build),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
