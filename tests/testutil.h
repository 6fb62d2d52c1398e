/* testutil.h - cmocka prelude and a tolerance assertion that prints both values. */
#ifndef MECHC_TESTUTIL_H
#define MECHC_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

/* |actual - expected| <= atol + rtol * |expected|; NaN never passes.
   cmocka 1.1.5 has no double assertion (assert_float_equal rounds to float). */
#define assert_near(actual, expected, rtol, atol) \
    assert_near_at((actual), (expected), (rtol), (atol), #actual, __FILE__, __LINE__)

static inline void assert_near_at(double actual, double expected, double rtol,
                                  double atol, const char *what,
                                  const char *file, int line)
{
    double tol = atol + rtol * fabs(expected);
    if (!(fabs(actual - expected) <= tol)) {
        fail_msg("%s:%d: %s = %.17g, expected %.17g (tolerance %.3g)",
                 file, line, what, actual, expected, tol);
    }
}

#endif
