/* test_eigen3.c - base/eigen3.c: the symmetric 3 x 3 eigenvalues against hand-computed spectra. */
#include "testutil.h"
#include "../generator/base/eigen3.h"

/* A diagonal matrix: its diagonal sorted, exactly (the closed form would
   leave a rounding error, and 0 would read -1.1e-16). */
static void test_diagonal_is_exact(void **state)
{
    (void)state;
    double t[6] = {1, 0, 1, 0, 0, 0}, ev[3];
    eigen3_symmetric(t, ev);
    assert_true(ev[0] == 0.0 && ev[1] == 1.0 && ev[2] == 1.0);
    double u[6] = {3, -2, 5, 0, 0, 0};
    eigen3_symmetric(u, ev);
    assert_true(ev[0] == -2.0 && ev[1] == 3.0 && ev[2] == 5.0);
}

/* [[2 1 0] [1 2 0] [0 0 3]]: 1, 3, 3; [[2 -1 0] [-1 2 -1] [0 -1 2]]:
   2 - sqrt 2, 2, 2 + sqrt 2. */
static void test_known_spectra(void **state)
{
    (void)state;
    double a[6] = {2, 2, 3, 1, 0, 0}, ev[3];
    eigen3_symmetric(a, ev);
    assert_near(ev[0], 1.0, 1e-14, 1e-14);
    assert_near(ev[1], 3.0, 1e-14, 1e-14);
    assert_near(ev[2], 3.0, 1e-14, 1e-14);
    double b[6] = {2, 2, 2, -1, 0, -1};
    eigen3_symmetric(b, ev);
    assert_near(ev[0], 2.0 - sqrt(2.0), 1e-14, 1e-14);
    assert_near(ev[1], 2.0, 1e-14, 1e-14);
    assert_near(ev[2], 2.0 + sqrt(2.0), 1e-14, 1e-14);
}

/* Entries near 1e200, whose squares overflow: the same spectrum, scaled. */
static void test_huge_entries(void **state)
{
    (void)state;
    double b[6] = {2e200, 2e200, 2e200, -1e200, 0, -1e200}, ev[3];
    eigen3_symmetric(b, ev);
    assert_near(ev[0], (2.0 - sqrt(2.0)) * 1e200, 1e-13, 0);
    assert_near(ev[1], 2e200, 1e-13, 0);
    assert_near(ev[2], (2.0 + sqrt(2.0)) * 1e200, 1e-13, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_diagonal_is_exact),
        cmocka_unit_test(test_known_spectra),
        cmocka_unit_test(test_huge_entries),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
