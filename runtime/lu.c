/* lu.c - dense LU with partial pivoting, its solves and a condition estimate.
 *
 * Also home to the runtime's shared definitions (status strings, default
 * options, workspace size), since every runtime build links this file.
 *
 * Storage: an n x n matrix is row-major with leading dimension lda >= n,
 * entry (i, j) at a[i*lda + j]. After mechrt_lu_factor the strictly lower
 * triangle holds L (unit diagonal, not stored) and the upper triangle U, of
 * PA = LU. The permutation is kept LAPACK-style as n interchanges: at step k
 * row k was swapped with row piv[k] >= k. The interchanges are stored as
 * mechrt_real (exact integers below 2^24 even in float) so that a caller's
 * workspace is a single array of a single type, which C's effective-type
 * rules require of a static array.
 */
#include <math.h>

#include "mechrt.h"

const char *mechrt_strerror(MechrtStatus status)
{
    switch (status) {
    case MECHRT_OK:         return "success";
    case MECHRT_CONTINUE:   return "iteration has not converged yet";
    case MECHRT_ESING:      return "singular matrix";
    case MECHRT_EMAXITER:   return "no convergence within the iteration limit";
    case MECHRT_EBADLEN:    return "workspace too small";
    case MECHRT_ENOTFINITE: return "NaN or infinity met";
    case MECHRT_ENOTSQUARE: return "system is not square";
    case MECHRT_EINVAL:     return "invalid argument";
    case MECHRT_ESTEP:      return "integration step size became too small";
    }
    return "unknown status";
}

MechrtOptions mechrt_default_options(void)
{
    MechrtOptions o;
#ifdef MECHRT_REAL_FLOAT
    /* float: epsilon 1.2e-7, so tolerances sit a few hundred epsilons up */
    o.tol_phi = MECHRT_R(1e-4);
    o.tol_dq = MECHRT_R(1e-3);
    o.pivot_tol = MECHRT_R(1e-5);
    o.cond_warn = MECHRT_R(1e5);
    o.cond_screen = MECHRT_R(1e-2);
    o.rank_tol = MECHRT_R(1e-3);
#else
    o.tol_phi = 1e-8;
    o.tol_dq = 1e-8;
    o.pivot_tol = 1e-12;
    o.cond_warn = 1e10;
    o.cond_screen = 1e-4;
    o.rank_tol = 1e-5;
#endif
    o.max_iter = 25;
    return o;
}

size_t mechrt_workspace_size(int nq, int nr)
{
    size_t q, r, max = (size_t)-1;

    if (nq < 1 || nr < 0)
        return 0;
    q = (size_t)nq;
    r = (size_t)nr;
    /* the same sum as MECHRT_WORKSPACE_LEN, checked term by term:
       r*q + 3r + 5q = r*(q + 3) + 5q */
    if (q > max - 3 || (r != 0 && q + 3 > max / r))
        return 0;
    if (q > (max - r * (q + 3)) / 5)
        return 0;
    return MECHRT_WORKSPACE_LEN(nq, nr);
}

mechrt_real mechrt_norm1(int n, const mechrt_real *a, int lda)
{
    mechrt_real best = 0;
    int i, j;

    for (j = 0; j < n; j++) {
        mechrt_real s = 0;
        for (i = 0; i < n; i++)
            s += MECHRT_FABS(a[(size_t)i * (size_t)lda + (size_t)j]);
        if (s > best || s != s)   /* s != s: let NaN through, not hide it */
            best = s;
    }
    return best;
}

/* The scan that precedes the elimination: every entry finite and the
 * largest |a_ij| (the scale of the pivot test); when colsum is not NULL,
 * also the column sums of |a_ij|, added in the order mechrt_norm1 adds them
 * (so the condition estimate's norm costs no separate call and has the
 * same bits). The branch on v > amax is predictable; NaN fails both tests. */
static MechrtStatus lu_scan(int n, const mechrt_real *a, size_t ld, mechrt_real *amax_out,
                            mechrt_real *colsum)
{
    mechrt_real amax = 0;
    int i, j;

    for (i = 0; i < n; i++) {
        const mechrt_real *ri = a + (size_t)i * ld;
        for (j = 0; j < n; j++) {
            mechrt_real v = MECHRT_FABS(ri[j]);
            if (v > amax)
                amax = v;
            else if (!(v <= amax))
                return MECHRT_ENOTFINITE;
        }
    }
    if (!isfinite(amax))
        return MECHRT_ENOTFINITE;
    if (colsum) {
        for (j = 0; j < n; j++)
            colsum[j] = MECHRT_FABS(a[j]);
        for (i = 1; i < n; i++) {
            const mechrt_real *ri = a + (size_t)i * ld;
            for (j = 0; j < n; j++)
                colsum[j] += MECHRT_FABS(ri[j]);
        }
    }
    *amax_out = amax;
    return MECHRT_OK;
}

/* Gaussian elimination with partial pivoting, right-looking (kij) form:
 * at step k choose the row p >= k with the largest |a_pk|, swap rows k and p,
 * store the multipliers l_ik = a_ik / a_kk below the diagonal and update the
 * trailing block a_ij -= l_ik a_kj; the inner loop runs along a row, which is
 * contiguous in row-major storage. Golub & Van Loan, Matrix Computations,
 * 4th ed., Algorithm 3.4.1 (outer-product LU with partial pivoting).
 *
 * Singularity: a pivot |u_kk| <= pivot_tol * max_ij |a_ij| (the scale of the
 * original matrix) stops the factorisation at step k; column k is then,
 * to that tolerance, a combination of columns 0..k-1.
 */
static MechrtStatus lu_eliminate(int n, mechrt_real *a, size_t ld, mechrt_real *piv,
                                 int k0, mechrt_real thresh, int *sing_index)
{
    int i, j, k;

    for (k = k0; k < n; k++) {
        mechrt_real *rk = a + (size_t)k * ld;
        mechrt_real pmax = MECHRT_FABS(rk[k]), pivot;
        int p = k;

        for (i = k + 1; i < n; i++) {
            mechrt_real v = MECHRT_FABS(a[(size_t)i * ld + (size_t)k]);
            if (v > pmax) {
                pmax = v;
                p = i;
            }
        }
        piv[k] = (mechrt_real)p;
        /* amax == 0 means the zero matrix: singular at the first column */
        if (pmax <= thresh || pmax == 0) {
            if (sing_index)
                *sing_index = k;
            return MECHRT_ESING;
        }
        if (p != k) {
            mechrt_real *rp = a + (size_t)p * ld;
            for (j = 0; j < n; j++) {
                mechrt_real tmp = rk[j];
                rk[j] = rp[j];
                rp[j] = tmp;
            }
        }
        pivot = rk[k];
        for (i = k + 1; i < n; i++) {
            mechrt_real *ri = a + (size_t)i * ld;
            mechrt_real l = ri[k] / pivot;
            ri[k] = l;
            if (l != 0)
                for (j = k + 1; j < n; j++)
                    ri[j] -= l * rk[j];
        }
    }
    return MECHRT_OK;
}

static MechrtStatus lu_factor(int n, mechrt_real *a, int lda, mechrt_real *piv,
                              mechrt_real pivot_tol, int *sing_index, mechrt_real *colsum)
{
    mechrt_real amax;
    MechrtStatus st;

    if (sing_index)
        *sing_index = -1;
    if (n < 0 || lda < n || (n > 0 && (!a || !piv)))
        return MECHRT_EINVAL;
#ifdef MECHRT_REAL_FLOAT
    if ((long)n > 16777216L)   /* 2^24: beyond it float cannot hold piv exactly */
        return MECHRT_EINVAL;
#endif
    st = lu_scan(n, a, (size_t)lda, &amax, colsum);
    if (st != MECHRT_OK)
        return st;
    return lu_eliminate(n, a, (size_t)lda, piv, 0, pivot_tol * amax, sing_index);
}

MechrtStatus mechrt_lu_resume(int n, mechrt_real *a, int lda, mechrt_real *piv, int k0,
                              mechrt_real thresh, int *sing_index)
{
    if (sing_index)
        *sing_index = -1;
    if (n < 0 || lda < n || k0 < 0 || k0 > n || (n > 0 && (!a || !piv)))
        return MECHRT_EINVAL;
    return lu_eliminate(n, a, (size_t)lda, piv, k0, thresh, sing_index);
}

MechrtStatus mechrt_lu_factor(int n, mechrt_real *a, int lda, mechrt_real *piv,
                              mechrt_real pivot_tol, int *sing_index)
{
    return lu_factor(n, a, lda, piv, pivot_tol, sing_index, NULL);
}

MechrtStatus mechrt_lu_factor_norm1(int n, mechrt_real *a, int lda, mechrt_real *piv,
                                    mechrt_real pivot_tol, int *sing_index,
                                    mechrt_real *anorm, mechrt_real *work)
{
    MechrtStatus st;
    int j;

    if (!anorm || (n > 0 && !work))
        return MECHRT_EINVAL;
    *anorm = 0;
    st = lu_factor(n, a, lda, piv, pivot_tol, sing_index, work);
    if (st == MECHRT_EINVAL || st == MECHRT_ENOTFINITE)
        return st;
    for (j = 0; j < n; j++)   /* the max as mechrt_norm1 takes it */
        if (work[j] > *anorm || work[j] != work[j])
            *anorm = work[j];
    return st;
}

/* Solve A x = b from PA = LU: b <- Pb, then L y = b by forward substitution
 * (row-oriented: inner products along contiguous rows of L), then U x = y by
 * back substitution. Golub & Van Loan, 4th ed., Algorithms 3.1.1 and 3.1.2.
 */
void mechrt_lu_solve(int n, const mechrt_real *lu, int lda, const mechrt_real *piv,
                     mechrt_real *b)
{
    size_t ld = (size_t)lda;
    int i, j, k;

    for (k = 0; k < n; k++) {
        int p = (int)piv[k];
        if (p != k) {
            mechrt_real tmp = b[k];
            b[k] = b[p];
            b[p] = tmp;
        }
    }
    for (i = 1; i < n; i++) {
        const mechrt_real *ri = lu + (size_t)i * ld;
        mechrt_real s = b[i];
        for (j = 0; j < i; j++)
            s -= ri[j] * b[j];
        b[i] = s;
    }
    for (i = n - 1; i >= 0; i--) {
        const mechrt_real *ri = lu + (size_t)i * ld;
        mechrt_real s = b[i];
        for (j = i + 1; j < n; j++)
            s -= ri[j] * b[j];
        b[i] = s / ri[i];
    }
}

void mechrt_lu_solve_many(int n, const mechrt_real *lu, int lda, const mechrt_real *piv,
                          mechrt_real *b, int ldb, int nrhs)
{
    size_t ld = (size_t)lda, lb = (size_t)ldb;
    int i, j, k, c;

    for (k = 0; k < n; k++) {
        int p = (int)piv[k];
        if (p != k)
            for (c = 0; c < nrhs; c++) {
                mechrt_real tmp = b[(size_t)k * lb + (size_t)c];
                b[(size_t)k * lb + (size_t)c] = b[(size_t)p * lb + (size_t)c];
                b[(size_t)p * lb + (size_t)c] = tmp;
            }
    }
    for (i = 1; i < n; i++) {
        const mechrt_real *ri = lu + (size_t)i * ld;
        for (c = 0; c < nrhs; c++) {
            mechrt_real s = b[(size_t)i * lb + (size_t)c];
            for (j = 0; j < i; j++)
                s -= ri[j] * b[(size_t)j * lb + (size_t)c];
            b[(size_t)i * lb + (size_t)c] = s;
        }
    }
    for (i = n - 1; i >= 0; i--) {
        const mechrt_real *ri = lu + (size_t)i * ld;
        for (c = 0; c < nrhs; c++) {
            mechrt_real s = b[(size_t)i * lb + (size_t)c];
            for (j = i + 1; j < n; j++)
                s -= ri[j] * b[(size_t)j * lb + (size_t)c];
            b[(size_t)i * lb + (size_t)c] = s / ri[i];
        }
    }
}

/* Solve A^T x = b from PA = LU, i.e. U^T L^T (P x) = b: U^T y = b forward,
 * L^T w = y backward, both column-oriented (saxpy with row j of the factors,
 * which is contiguous), then x = P^T w by undoing the interchanges in
 * reverse order. Golub & Van Loan, 4th ed., section 3.1 (column versions).
 */
void mechrt_lu_solve_t(int n, const mechrt_real *lu, int lda, const mechrt_real *piv,
                       mechrt_real *b)
{
    size_t ld = (size_t)lda;
    int i, j, k;

    for (j = 0; j < n; j++) {
        const mechrt_real *rj = lu + (size_t)j * ld;
        mechrt_real y = b[j] / rj[j];
        b[j] = y;
        if (y != 0)
            for (i = j + 1; i < n; i++)
                b[i] -= rj[i] * y;
    }
    for (j = n - 1; j > 0; j--) {
        const mechrt_real *rj = lu + (size_t)j * ld;
        mechrt_real w = b[j];
        if (w != 0)
            for (i = 0; i < j; i++)
                b[i] -= rj[i] * w;
    }
    for (k = n - 1; k >= 0; k--) {
        int p = (int)piv[k];
        if (p != k) {
            mechrt_real tmp = b[k];
            b[k] = b[p];
            b[p] = tmp;
        }
    }
}

/* Condition estimate kappa_1 = ||A||_1 ||A^-1||_1 without forming A^-1.
 * Hager's method (W. W. Hager, "Condition estimates", SIAM J. Sci. Stat.
 * Comput. 5, 1984) maximises ||A^-1 x||_1 over the unit 1-norm ball by a
 * gradient ascent that needs one solve with A and one with A^T per step;
 * with N. J. Higham's refinements ("FORTRAN codes for estimating the one-norm
 * of a real or complex matrix", ACM TOMS 14, 1988, Algorithm 4.1): at most 5
 * steps, stop when the estimate stops growing, and a second estimate from
 * the alternating vector x_i = (-1)^i (1 + i/(n-1)) that catches the
 * matrices fooling the ascent. This is what LAPACK's dgecon does (dlacn2).
 * Cost: O(n^2) per solve, about ten solves.
 */
mechrt_real mechrt_lu_cond1(int n, const mechrt_real *lu, int lda, const mechrt_real *piv,
                            mechrt_real anorm, mechrt_real *work)
{
    mechrt_real *v = work, *z = work + n;
    mechrt_real est = 0, alt;
    int i, it, j = 0;

    if (n < 1)
        return 0;
    if (n == 1)   /* exact, and the alternating vector divides by n-1 */
        return anorm / MECHRT_FABS(lu[0]);

    for (i = 0; i < n; i++)
        v[i] = MECHRT_R(1.0) / (mechrt_real)n;
    for (it = 0; it < 5; it++) {
        mechrt_real e = 0, zmax;
        int jmax = 0;

        mechrt_lu_solve(n, lu, lda, piv, v);                    /* v = A^-1 x */
        for (i = 0; i < n; i++)
            e += MECHRT_FABS(v[i]);
        if (it > 0 && e <= est)
            break;                                              /* no progress */
        est = e;
        for (i = 0; i < n; i++)
            z[i] = v[i] >= 0 ? MECHRT_R(1.0) : MECHRT_R(-1.0);  /* sign(v) */
        mechrt_lu_solve_t(n, lu, lda, piv, z);                  /* gradient */
        zmax = MECHRT_FABS(z[0]);
        for (i = 1; i < n; i++) {
            if (MECHRT_FABS(z[i]) > zmax) {
                zmax = MECHRT_FABS(z[i]);
                jmax = i;
            }
        }
        /* Hager's optimality test: max_i |z_i| <= z^T x, with x = e_j */
        if (it > 0 && zmax <= z[j])
            break;
        j = jmax;
        for (i = 0; i < n; i++)
            v[i] = 0;
        v[j] = 1;
    }

    for (i = 0; i < n; i++) {
        mechrt_real m = MECHRT_R(1.0) + (mechrt_real)i / (mechrt_real)(n - 1);
        v[i] = (i % 2) ? -m : m;
    }
    mechrt_lu_solve(n, lu, lda, piv, v);
    alt = 0;
    for (i = 0; i < n; i++)
        alt += MECHRT_FABS(v[i]);
    alt = MECHRT_R(2.0) * alt / (MECHRT_R(3.0) * (mechrt_real)n);
    if (alt > est)
        est = alt;
    return anorm * est;
}
