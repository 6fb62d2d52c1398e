/* test_lu_pattern.c - runtime/lu_pattern.c: the pattern LU against lu.c, exactly. */
#include "testrt.h"

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

/* mechrt_lup_solve_many on three right sides (leading dimension 4, the
   fourth column left alone) against mechrt_lup_solve on each, bit for bit. */
static void lup_check_many(const MechrtLup *f, int n, uint64_t *seed)
{
    double b[20 * 4], x[20], work[20 * 3];
    for (int i = 0; i < 4 * n; i++)
        b[i] = rnd(seed);
    double keep[20 * 4];
    memcpy(keep, b, sizeof keep);
    mechrt_lup_solve_many(f, b, 4, 3, work);
    for (int c = 0; c < 3; c++) {
        for (int i = 0; i < n; i++)
            x[i] = keep[4 * i + c];
        mechrt_lup_solve(f, x, x);
        for (int i = 0; i < n; i++)
            if (b[4 * i + c] != x[i])
                fail_msg("n = %d, column %d, x[%d]: many %.17g, one %.17g", n, c, i,
                         b[4 * i + c], x[i]);
    }
    for (int i = 0; i < n; i++)
        assert_true(b[4 * i + 3] == keep[4 * i + 3]);
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
    lup_check_many(f, n, seed);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lup_matches_dense),
        cmocka_unit_test(test_lup_pivot_fallback),
        cmocka_unit_test(test_lup_singular),
        cmocka_unit_test(test_lup_workspace),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
