/* test_format_real.c - mechrt_format_real (runtime/host/format_real.c) prints what printf and strtod define, byte for byte.
 *
 * The reference is the definition: %.<digits>g, or the first of %.15g,
 * %.16g, %.17g that strtod reads back as v. Compared on random bit
 * patterns over every exponent, on numbers a simulation prints (trig of
 * random angles, tiny residues, decimal fractions), on powers of two and
 * ten and their neighbours (the uneven gap below a power of two), and on
 * exact ties of %.<p>g (2.5, 0.125, 1e23), each at every precision 1..17
 * and the shortest; floats (--real float literals) against the first of
 * %.6g .. %.9g that reads back as the float; then the text of a few
 * values written out.
 */
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../runtime/host/format_real.h"

static int reference(char *buf, size_t size, double v, int digits)
{
    if (v == 0)
        v = 0;
    if (digits > 0)
        return snprintf(buf, size, "%.*g", digits, v);
    int n = 0;
    for (int d = 15; d <= 17; d++) {
        n = snprintf(buf, size, "%.*g", d, v);
        if (d == 17 || strtod(buf, NULL) == v)
            break;
    }
    return n;
}

/* v at the shortest and at digits 1..17 (every one when all, else one picked by i). */
static int compare(double v, unsigned i, bool all)
{
    int bad = 0;
    for (int digits = 0; digits <= 17; digits++) {
        if (!all && digits && (i + (unsigned)digits) % 6 != 0)
            continue;
        char a[40], b[40];
        int na = mechrt_format_real(a, sizeof a, v, digits, false);
        int nb = reference(b, sizeof b, v, digits);
        if (na != nb || strcmp(a, b) != 0) {
            if (bad++ < 5)
                fprintf(stderr, "%a digits %d: got %s, printf %s\n", v, digits, a, b);
        }
    }
    return bad;
}

static uint64_t next64(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static double from_bits(uint64_t b)
{
    double v;
    memcpy(&v, &b, sizeof v);
    return v;
}

static void random_bit_patterns(void **state)
{
    (void)state;
    uint64_t s = 0x9e3779b97f4a7c15u;
    int bad = 0;
    for (unsigned i = 0; i < 300000; i++) {
        double v = from_bits(next64(&s));
        if (isfinite(v))
            bad += compare(v, i, false);
    }
    assert_int_equal(bad, 0);
}

static void simulation_like_numbers(void **state)
{
    (void)state;
    uint64_t s = 12345;
    int bad = 0;
    for (unsigned i = 0; i < 300000; i++) {
        double u = (double)(next64(&s) >> 11) * 0x1p-53;
        double v;
        switch (i % 5) {
        case 0: v = sin(20 * u) * 3; break;
        case 1: v = (u - 0.5) * 1e-16 * pow(10, -(double)(i % 40)); break;   /* residues */
        case 2: v = (double)(i % 100000) / 1000; break;                       /* 12.345 */
        case 3: v = (u - 0.5) * pow(10, (double)(i % 33) - 16); break;
        default: v = 0.1 * (double)(i % 977) + 0.2; break;
        }
        bad += compare(v, i, false);
    }
    assert_int_equal(bad, 0);
}

static void powers_and_neighbours(void **state)
{
    (void)state;
    int bad = 0;
    for (int e = -1074; e <= 1023; e++) {
        double p = ldexp(1, e);
        bad += compare(p, 0, true) + compare(nextafter(p, 0), 0, true) +
               compare(nextafter(p, INFINITY), 0, true) + compare(-p, 0, true);
    }
    for (int e = -320; e <= 308; e++) {
        double p = pow(10, e);
        bad += compare(p, 0, true) + compare(nextafter(p, 0), 0, true) +
               compare(nextafter(p, INFINITY), 0, true);
    }
    assert_int_equal(bad, 0);
}

static void ties_and_edges(void **state)
{
    (void)state;
    static const double v[] = {2.5, 0.125, 0.375, 1e23, 5e-324, 2.2250738585072014e-308,
                               1.7976931348623157e308, 9.5, 99.5, 0.3, 0.1 + 0.2, 1e15,
                               1e16, 1234567890123456.0, 9999999999999998.0, 1e-5, 1e-4,
                               0.00012345, 123456789012345680.0, 4.35, 1.0 / 3, 2.0 / 3};
    int bad = 0;
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        bad += compare(v[i], 0, true) + compare(-v[i], 0, true);
    assert_int_equal(bad, 0);
}

/* The float definition: the first of %.6g .. %.9g of (float)v that reads back as that float. */
static int reference_float(char *buf, size_t size, double v)
{
    float f = (float)v;
    if (f == 0)
        f = 0;
    int n = 0;
    for (int d = 6; d <= 9; d++) {
        n = snprintf(buf, size, "%.*g", d, (double)f);
        if (d == 9 || (float)strtod(buf, NULL) == f)
            break;
    }
    return n;
}

static void floats_shortest(void **state)
{
    (void)state;
    uint64_t s = 0x2545f4914f6cdd1du;
    int bad = 0;
    for (unsigned i = 0; i < 100000; i++) {
        uint32_t bits = (uint32_t)next64(&s);
        float f;
        memcpy(&f, &bits, sizeof f);
        /* random floats, and doubles between floats (rounded first) */
        double v = i % 2 ? (double)f : (double)f * (1 + 0x1p-30);
        if (!isfinite(f))
            continue;
        char a[40], b[40];
        int na = mechrt_format_real(a, sizeof a, v, 0, true), nb = reference_float(b, sizeof b, v);
        if ((na != nb || strcmp(a, b) != 0) && bad++ < 5)
            fprintf(stderr, "%a as float: got %s, printf %s\n", v, a, b);
        if ((float)strtod(a, NULL) != (float)v && bad++ < 5)
            fprintf(stderr, "%a as float: %s does not read back\n", v, a);
    }
    assert_int_equal(bad, 0);
}

static void known_texts(void **state)
{
    (void)state;
    char b[40];
    assert_int_equal(mechrt_format_real(b, sizeof b, 0.3, 0, false), 3);
    assert_string_equal(b, "0.3");
    mechrt_format_real(b, sizeof b, 0.1 + 0.2, 0, false);
    assert_string_equal(b, "0.30000000000000004");
    mechrt_format_real(b, sizeof b, 1e15, 0, false);
    assert_string_equal(b, "1e+15");
    mechrt_format_real(b, sizeof b, 1234567890123456.0, 0, false);
    assert_string_equal(b, "1234567890123456");
    mechrt_format_real(b, sizeof b, -1.5e-7, 0, false);
    assert_string_equal(b, "-1.5e-07");
    mechrt_format_real(b, sizeof b, 0.000123, 0, false);
    assert_string_equal(b, "0.000123");
    mechrt_format_real(b, sizeof b, 2.5, 1, false);
    assert_string_equal(b, "2");
    mechrt_format_real(b, sizeof b, 9.96, 2, false);
    assert_string_equal(b, "10");
    mechrt_format_real(b, sizeof b, -0.0, 0, false);
    assert_string_equal(b, "0");
    mechrt_format_real(b, sizeof b, 0.1, 0, true);
    assert_string_equal(b, "0.1");
    mechrt_format_real(b, sizeof b, 1.0 / 3, 0, true);
    assert_string_equal(b, "0.33333334");
    mechrt_format_real(b, sizeof b, 16777217.0, 0, true);
    assert_string_equal(b, "16777216");
    mechrt_format_real(b, sizeof b, -2.5e-7, 0, true);
    assert_string_equal(b, "-2.5e-07");
    mechrt_format_real(b, sizeof b, 1e39, 0, true);    /* finite only as a double */
    assert_string_equal(b, "inf");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(random_bit_patterns),
        cmocka_unit_test(simulation_like_numbers),
        cmocka_unit_test(powers_and_neighbours),
        cmocka_unit_test(ties_and_edges),
        cmocka_unit_test(floats_shortest),
        cmocka_unit_test(known_texts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
