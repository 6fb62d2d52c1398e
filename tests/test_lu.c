/* test_lu.c - runtime/lu.c: LU against GSL, many right-hand sides, the condition estimate, workspaces, options, strings. */
#include "testrt.h"

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

/* Many right-hand sides at once give, column by column, the bits of one
   solve each (the sensitivities' solves rely on it). */
static void test_lu_solve_many(void **state)
{
    (void)state;
    uint64_t seed = 0x2545F4914F6CDD1DULL;
    enum { N = 12, LDA = 14, NRHS = 5, LDB = 7 };
    double a[N * LDA], piv[N], b[N * LDB], col[N];
    for (int i = 0; i < N * LDA; i++)
        a[i] = rnd(&seed);
    for (int i = 0; i < N * LDB; i++)
        b[i] = rnd(&seed);
    assert_int_equal(mechrt_lu_factor(N, a, LDA, piv, 1e-12, NULL), MECHRT_OK);
    double x[N * LDB];
    memcpy(x, b, sizeof x);
    mechrt_lu_solve_many(N, a, LDA, piv, x, LDB, NRHS);
    for (int c = 0; c < LDB; c++) {
        for (int i = 0; i < N; i++)
            col[i] = b[i * LDB + c];
        if (c < NRHS)
            mechrt_lu_solve(N, a, LDA, piv, col);
        for (int i = 0; i < N; i++)     /* solved columns equal, the rest untouched */
            assert_memory_equal(&x[i * LDB + c], &col[i], sizeof(double));
    }
}

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lu_matches_gsl),
        cmocka_unit_test(test_lu_hilbert),
        cmocka_unit_test(test_lu_singular),
        cmocka_unit_test(test_lu_solve_many),
        cmocka_unit_test(test_workspace_size),
        cmocka_unit_test(test_options_and_strings),
        cmocka_unit_test(test_lu_factor_norm1),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
