/* format_real.c - doubles as text (run's CSV and JSON, reports, generated C), mostly without printf or strtod.
 *
 * The text is defined by printf: "%.<P>g" with P = digits, or with the
 * shortest P of 15, 16, 17 whose text reads back as v. glibc computes
 * those digits with multiple-precision arithmetic and strtod reads them
 * back the same way: about 1.5 us a number, most of a large run's time
 * (18 million numbers for 1000 steps of a 6003-coordinate chain).
 *
 * The fast path computes X = |v| 10^s (17 or 18 digits before the point)
 * to 64 bits after the point from a 128-bit 5^s, rounds it to P digits,
 * and decides the read-back from the distance to the candidate against
 * half an ulp (strtod rounds to nearest: it reads back exactly when the
 * candidate is nearer to v than half the gap to v's neighbours). Every
 * quantity is known to within 2 units of 2^-64; a decision that close to
 * its boundary (a tie, say) is left to printf and strtod, as are
 * subnormals, |v| >= 1e16, floats and compilers without a 128-bit
 * integer. So the text is byte for byte printf's (tests/test_format_real.c
 * compares them).
 */
#include "format_real.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* printf and strtod: the definition, and the path for what the fast one leaves. */
static int format_slow(char *buf, size_t size, double v, int digits, bool as_float)
{
    if (digits > 0)
        return snprintf(buf, size, "%.*g", digits, v);
    /* 17 significant digits always round-trip a double (9 a float); fewer
       usually do and read better (0.3, not 0.29999999999999999) */
    int least = as_float ? 6 : 15, most = as_float ? 9 : 17, n = 0;
    for (int d = least; d <= most; d++) {
        n = snprintf(buf, size, "%.*g", d, v);
        double back = strtod(buf, NULL);
        if (d == most || (as_float ? (float)back == (float)v : back == v))
            break;
    }
    return n;
}

#ifdef __SIZEOF_INT128__
__extension__ typedef unsigned __int128 fr_u128;

static const uint64_t fr_p10[19] = {
    1u, 10u, 100u, 1000u, 10000u, 100000u, 1000000u, 10000000u, 100000000u,
    1000000000u, 10000000000u, 100000000000u, 1000000000000u, 10000000000000u,
    100000000000000u, 1000000000000000u, 10000000000000000u, 100000000000000000u,
    1000000000000000000u};

/* 5^(27 i) ~= F 2^g, F the top 128 bits (truncated), i = 0..12 (5^0 .. 5^324). */
static const uint64_t fr_pow5_hi[13] = {
    0x8000000000000000u, 0xcecb8f27f4200f3au, 0xa70c3c40a64e6c51u, 0x86f0ac99b4e8dafdu,
    0xda01ee641a708de9u, 0xb01ae745b101e9e4u, 0x8e41ade9fbebc27du, 0xe5d3ef282a242e81u,
    0xb9a74a0637ce2ee1u, 0x95f83d0a1fb69cd9u, 0xf24a01a73cf2dccfu, 0xc3b8358109e84f07u,
    0x9e19db92b4e31ba9u};
static const uint64_t fr_pow5_lo[13] = {
    0x0u, 0x0u, 0x999090b65f67d924u, 0x69a028bb3ded71a3u,
    0xe80e6f4820cc9495u, 0x5ec05dcff72e7f8fu, 0x14588f13be847307u, 0x8f1668c8a86da5fau,
    0x6d953e2bd7173692u, 0x4abdaf101564f98eu, 0xbc633b39673c8cecu, 0x0a862f80ec4700c8u,
    0x6c07a2c26a8346d1u};
static const int fr_pow5_exp[13] = {-127, -65, -2, 61, 123, 186, 249, 311, 374, 437, 499, 562, 625};

static int fr_clz128(fr_u128 x)
{
    uint64_t hi = (uint64_t)(x >> 64);
    return hi ? __builtin_clzll(hi) : 64 + __builtin_clzll((uint64_t)x);
}

/* 5^s ~= F 2^*g with F in [2^127, 2^128), F <= 5^s 2^-g < F (1 + 2^-126); s in [0, 350]. */
static fr_u128 fr_pow5(int s, int *g)
{
    static const uint64_t pow5_small[27] = {
        1u, 5u, 25u, 125u, 625u, 3125u, 15625u, 78125u, 390625u, 1953125u, 9765625u,
        48828125u, 244140625u, 1220703125u, 6103515625u, 30517578125u, 152587890625u,
        762939453125u, 3814697265625u, 19073486328125u, 95367431640625u, 476837158203125u,
        2384185791015625u, 11920928955078125u, 59604644775390625u, 298023223876953125u,
        1490116119384765625u};
    int i = s / 27;
    uint64_t b = pow5_small[s % 27];
    fr_u128 lo = (fr_u128)fr_pow5_lo[i] * b;
    fr_u128 hi = (fr_u128)fr_pow5_hi[i] * b + (lo >> 64);   /* the product: hi 2^64 + lo */
    int z = fr_clz128(hi);                                   /* 0 .. 64: hi >= 2^63 */
    *g = fr_pow5_exp[i] + 64 - z;
    return (hi << z) | (z ? (fr_u128)((uint64_t)lo >> (64 - z)) : 0);
}

/* |v| as X = |v| 10^s in units of 2^-64, and half its ulp in the same units. */
typedef struct {
    fr_u128 xa;     /* X 2^64 within [xa, xa + 2) */
    fr_u128 ha;     /* half an ulp of v, times 10^s 2^64, within [ha, ha + 2) */
    uint64_t d;     /* floor(xa 2^-64): 17 or 18 digits */
    int nd;         /* its digit count */
    int exp10;      /* the decimal exponent of its first digit in v */
    bool low_gap;   /* v a power of two: the gap below is half the gap above */
} FrScaled;

static bool fr_scale(double v, FrScaled *sc)
{
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    int be = (int)(bits >> 52 & 0x7ff);
    if (be == 0 || be == 0x7ff)
        return false;
    uint64_t m = (bits & ((1ull << 52) - 1)) | 1ull << 52;
    int e = be - 1075, x = e + 52;
    /* floor(x log10 2), exact for |x| <= 1650 (Ryu's log10Pow2) */
    int e0 = x >= 0 ? (int)(((uint32_t)x * 78913u) >> 18) : -(int)((((uint32_t)-x * 78913u) >> 18) + 1);
    int s = 16 - e0, g;
    if (s < 0 || s > 350)
        return false;
    fr_u128 f = fr_pow5(s, &g);
    fr_u128 lo = (fr_u128)m * (uint64_t)f;
    fr_u128 hi = (fr_u128)m * (uint64_t)(f >> 64) + (lo >> 64);   /* m f = hi 2^64 + lo */
    int sh = -(g + e + s + 64);                                    /* X 2^64 = m f 2^-sh */
    if (sh < 1 || sh > 127 + 64 || (sh < 64 && hi >> (64 + sh)))
        return false;
    sc->xa = sh >= 64 ? hi >> (sh - 64) : hi << (64 - sh) | (fr_u128)((uint64_t)lo >> sh);
    sc->ha = sh + 1 < 128 ? f >> (sh + 1) : 0;
    sc->d = (uint64_t)(sc->xa >> 64);
    if (sc->d < fr_p10[16] || sc->d >= fr_p10[18] || sc->ha < 8)
        return false;
    sc->nd = sc->d >= fr_p10[17] ? 18 : 17;
    sc->exp10 = sc->nd - 1 - s;
    sc->low_gap = m == 1ull << 52 && be > 1;
    return true;
}

/* d / 10^k: the shortest path drops 0 to 3 digits, by constants (a
   multiplication) rather than a division instruction. */
static uint64_t fr_div_p10(uint64_t d, int k)
{
    switch (k) {
    case 0: return d;
    case 1: return d / 10u;
    case 2: return d / 100u;
    case 3: return d / 1000u;
    default: return d / fr_p10[k];
    }
}

/* X rounded to p digits, as an integer q (p digits, or 10^p after a carry)
   and the candidate cx = q 10^(nd - p) in X's units. False: too near a tie. */
static bool fr_round(const FrScaled *sc, int p, uint64_t *q, uint64_t *cx)
{
    int k = sc->nd - p;
    *q = fr_div_p10(sc->d, k);
    uint64_t r = sc->d - *q * fr_p10[k];
    fr_u128 dropped = (fr_u128)r << 64 | (uint64_t)sc->xa;
    fr_u128 half = k ? (fr_u128)(fr_p10[k] / 2) << 64 : (fr_u128)1 << 63;
    if (dropped > half)
        ++*q;
    else if (dropped + 2 > half)
        return false;
    *cx = *q * fr_p10[k];
    return true;
}

/* Whether the candidate cx reads back as v: 1 yes, 0 no, -1 too near to
   tell (a tie of strtod's, say). X 2^64 is in [lo, hi), half an ulp in
   [ha, ha + 2); the gap below a power of two is half as wide. */
static int fr_reads_back(const FrScaled *sc, uint64_t cx)
{
    fr_u128 c = (fr_u128)cx << 64, lo = sc->xa, hi = sc->xa + 2;
    fr_u128 above_most = c > lo ? c - lo : 0, below_most = hi > c ? hi - c : 0;
    fr_u128 dmax = above_most > below_most ? above_most : below_most;
    fr_u128 dmin = c >= hi ? c - hi : c >= lo ? 0 : lo - c;
    bool maybe_below = c < hi, surely_below = c < lo;
    if ((sc->low_gap && maybe_below ? 2 * dmax : dmax) < sc->ha)
        return 1;
    if ((sc->low_gap && surely_below ? 2 * dmin : dmin) > sc->ha + 2)
        return 0;
    return -1;
}

/* Bytes of buffer the fast path needs (fr_put_g's fixed copies). */
#define FR_ROOM 36

static const char fr_pairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* The 4 digits of v < 10^4 at d. */
static void fr_put4(char *d, uint32_t v)
{
    memcpy(d, fr_pairs + 2 * (v / 100), 2);
    memcpy(d + 2, fr_pairs + 2 * (v % 100), 2);
}

/* The 18 digits of q < 10^18 at d (leading zeros included): three
   independent chains of 32-bit divisions by constants, not 9 dependent
   64-bit ones. */
static void fr_put18(char *d, uint64_t q)
{
    uint32_t lo = (uint32_t)(q % 100000000u);
    uint64_t rest = q / 100000000u;
    uint32_t mid = (uint32_t)(rest % 100000000u), hi = (uint32_t)(rest / 100000000u);
    memcpy(d, fr_pairs + 2 * hi, 2);
    fr_put4(d + 2, mid / 10000);
    fr_put4(d + 6, mid % 10000);
    fr_put4(d + 10, lo / 10000);
    fr_put4(d + 14, lo % 10000);
}

/* printf's %.<p>g of the p digits q (value q 10^(exp10 - p + 1)). buf has
   room for FR_ROOM bytes: the digits go by fixed-size copies (a copy of a
   variable length is a library call), the length counted apart; the
   copies reach at most buf + 35. */
static int fr_put_g(char *buf, bool neg, uint64_t q, int p, int exp10)
{
    char all[40];   /* 18 digits; the fixed copies read up to all + 34 */
    fr_put18(all, q);
    const char *dig = all + 18 - p;
    int len = p, n = 0;
    while (len > 1 && dig[len - 1] == '0')
        len--;
    if (neg)
        buf[n++] = '-';
    if (exp10 < -4 || exp10 >= p) {
        buf[n++] = dig[0];
        if (len > 1) {
            buf[n++] = '.';
            memcpy(buf + n, dig + 1, 16);
            n += len - 1;
        }
        int a = exp10 < 0 ? -exp10 : exp10;
        buf[n++] = 'e';
        buf[n++] = exp10 < 0 ? '-' : '+';
        if (a >= 100)
            buf[n++] = (char)('0' + a / 100);
        buf[n++] = (char)('0' + a / 10 % 10);
        buf[n++] = (char)('0' + a % 10);
    } else if (exp10 >= 0) {
        memcpy(buf + n, dig, 17);
        n += exp10 + 1;
        if (len > exp10 + 1) {
            buf[n++] = '.';
            memcpy(buf + n, dig + exp10 + 1, 16);
            n += len - exp10 - 1;
        }
    } else {
        memcpy(buf + n, "0.0000", 6);
        n += 1 - exp10;
        memcpy(buf + n, dig, 17);
        n += len;
    }
    buf[n] = '\0';
    return n;
}

/* The text of X rounded to q at precision p; true, for the callers' && chains. */
static bool fr_emit(char *buf, const FrScaled *sc, bool neg, int p, uint64_t q, int *n)
{
    int exp10 = sc->exp10;
    if (q == fr_p10[p]) {   /* 9.99.. rounded up to 10.0.. */
        q = fr_p10[p - 1];
        exp10++;
    }
    *n = fr_put_g(buf, neg, q, p, exp10);
    return true;
}

/* The fast path; false when it cannot decide (then printf does). */
static bool format_fast(char *buf, size_t size, double v, int digits, int *n)
{
    FrScaled sc;
    if (size < FR_ROOM || digits > 17 || !fr_scale(v, &sc))
        return false;
    bool neg = v < 0;
    uint64_t q, cx;
    if (digits > 0)
        return fr_round(&sc, digits, &q, &cx) && fr_emit(buf, &sc, neg, digits, q, n);
    for (int p = 15; p <= 16; p++) {
        if (!fr_round(&sc, p, &q, &cx))
            return false;
        int rb = fr_reads_back(&sc, cx);
        if (rb < 0)
            return false;
        if (rb)
            return fr_emit(buf, &sc, neg, p, q, n);
    }
    return fr_round(&sc, 17, &q, &cx) && fr_emit(buf, &sc, neg, 17, q, n);
}
#else
static bool format_fast(char *buf, size_t size, double v, int digits, int *n)
{
    (void)buf, (void)size, (void)v, (void)digits, (void)n;
    return false;
}
#endif

int mechrt_format_real(char *buf, size_t size, double v, int digits, bool as_float)
{
    if (as_float)
        v = (float)v;   /* then v is exactly the float, reads back or not */
    if (isnan(v))
        return snprintf(buf, size, "nan");
    if (isinf(v))
        return snprintf(buf, size, v > 0 ? "inf" : "-inf");
    if (v == 0)
        v = 0;   /* -0 prints as 0: a sign on zero is noise to a reader */
    int n;
    /* floats are written once each, into generated files: printf serves */
    if (v != 0 && !as_float && format_fast(buf, size, v, digits, &n))
        return n;
    return format_slow(buf, size, v, digits, as_float);
}
