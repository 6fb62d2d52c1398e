/* qr.c - rank-revealing QR (Householder, column pivoting) and minimum-norm solves, for singular Jacobians.
 *
 * Where the Jacobian loses rank (a parallelogram folding flat, a dead
 * centre) LU has no pivot, yet Phi_q x = b may still have solutions: a
 * family of them. The one wanted is the smallest correction, so this file
 * gives x = the minimum-norm solution of the rows that carry the rank.
 *
 * Method: Householder QR with column pivoting (Businger and Golub 1965;
 * Golub and Van Loan, Matrix Computations, 4th ed., section 5.4.2) of A^T,
 * so the pivoting picks rows of A:  A^T P = Q R,  R upper trapezoidal,
 * numerical rank r = the steps whose pivot column norm exceeds rtol times
 * the first. Then  P^T A x = R^T Q^T x,  and with y = Q^T x the first r
 * equations R11^T y1 = (P^T b)_1 are triangular; y2 = 0 gives the x = Q y
 * of least norm that satisfies them. For a consistent system (b in the
 * range of A) that is the minimum-norm solution, pinv(A) b; otherwise the
 * r chosen rows hold exactly and the others are left with the residual.
 *
 * Storage: the working copy holds A^T column-major, which is A row-major:
 * column j of A^T (row j of A) is contiguous, so every Householder dot
 * product runs over contiguous memory. Workspace layout, n columns and m
 * rows of A (mechrt_qr_work_len(m, n) reals): W m*n | tau m | rdiag m |
 * perm m | cn m | cn_ref m | lo m | hi m. The columns stay in place (perm
 * says which one step k chose), each with the extent [lo, hi] of its
 * nonzeros, so that reflections skip what they cannot touch. No heap, no libm: the square root is Newton's.
 */
#include "mechrt.h"

/* sqrt(x) for x >= 0 without libm: scale into [0.25, 1) by powers of 4,
   Newton from a linear guess (six steps are enough for double). */
static mechrt_real qr_sqrt(mechrt_real x)
{
    mechrt_real s = 1, y;
    int i;

    if (!(x > 0))
        return 0;
    if (x - x != 0)     /* inf stays inf */
        return x;
    while (x >= 1) {
        x *= MECHRT_R(0.25);
        s *= 2;
    }
    while (x < MECHRT_R(0.25)) {
        x *= 4;
        s *= MECHRT_R(0.5);
    }
    y = MECHRT_R(0.5) + MECHRT_R(0.5) * x;
    for (i = 0; i < 6; i++)
        y = MECHRT_R(0.5) * (y + x / y);
    return y * s;
}

/* sum a_i b_i in four partial sums: independent chains the processor
   overlaps (the compiler may not reorder a floating-point sum itself) */
static mechrt_real qr_dot(int n, const mechrt_real *a, const mechrt_real *b)
{
    mechrt_real s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    int i = 0;

    for (; i + 4 <= n; i += 4) {
        s0 += a[i] * b[i];
        s1 += a[i + 1] * b[i + 1];
        s2 += a[i + 2] * b[i + 2];
        s3 += a[i + 3] * b[i + 3];
    }
    for (; i < n; i++)
        s0 += a[i] * b[i];
    return (s0 + s1) + (s2 + s3);
}

/* c -= s v, for distinct arrays (restrict lets the compiler use vector
   instructions without a run-time overlap test) */
static void qr_axpy(int n, mechrt_real s, const mechrt_real *restrict v, mechrt_real *restrict c)
{
    int i;

    for (i = 0; i < n; i++)
        c[i] -= s * v[i];
}

size_t mechrt_qr_work_len(int m, int n)
{
    size_t mm, nn;

    if (m < 1 || n < 1)
        return 0;
    mm = (size_t)m;
    nn = (size_t)n;
    if (mm > ((size_t)-1 / 16u) / nn)
        return 0;
    return mm * nn + 8u * mm;
}

/* The pivot of step k: of the rows of A not chosen yet (columns of A^T),
   the first in their order whose remaining norm is at least QR_THRESHOLD
   times the largest. Threshold pivoting: the plain rule (the largest)
   reveals the rank as well where the norms part by orders of magnitude,
   as at a singular position, and keeping to the order keeps a banded
   Jacobian's reflections short (see qr_reflect). Returns the column, its
   remaining norm^2 in *norm2 and the largest in *max2. */
#define QR_THRESHOLD2 MECHRT_R(0.01)    /* 0.1 squared */

static int qr_pivot(MechrtQr *f, int k, mechrt_real *norm2, mechrt_real *max2)
{
    int n = f->n, m = f->m, j, p = -1;
    mechrt_real best = 0;

    for (j = 0; j < m; j++) {
        mechrt_real c = f->cn[j];
        if (c < 0 && f->cn_ref[j] < 0)  /* chosen already */
            continue;
        /* the downdated norm lost its digits: recompute it */
        if (c < MECHRT_R(1e-3) * f->cn_ref[j] || c < 0) {
            mechrt_real *wj = f->w + (size_t)j * (size_t)n;
            int lo = (int)f->lo[j] > k ? (int)f->lo[j] : k, hi = (int)f->hi[j];
            c = hi >= lo ? qr_dot(hi - lo + 1, wj + lo, wj + lo) : 0;
            f->cn[j] = f->cn_ref[j] = c;
        }
        if (c > best)
            best = c;
    }
    *max2 = best;
    for (j = 0; j < m && p < 0; j++)
        if (!(f->cn[j] < 0 && f->cn_ref[j] < 0) && f->cn[j] >= QR_THRESHOLD2 * best)
            p = j;
    *norm2 = p >= 0 ? f->cn[p] : 0;
    (void)n;
    return p;
}

/* Householder step k on column p: reflects its positions k.. onto alpha
   e_k (v kept in its place, v_k = x_k - alpha, nonzero on [k, hi_p]) and
   applies the reflection to the columns not chosen yet. A column whose
   nonzeros [lo, hi] miss [k, hi_p] is left alone: on a banded Jacobian
   that is nearly all of them, and the work is O(n b^2) instead of
   O(n^3). */
static void qr_reflect(MechrtQr *f, int k, int p)
{
    int n = f->n, m = f->m, j, hv = (int)f->hi[p];
    mechrt_real *v = f->w + (size_t)p * (size_t)n + k;
    mechrt_real alpha, tau, norm;
    int len;

    if (hv < k)
        hv = k;
    len = hv - k + 1;
    norm = qr_sqrt(qr_dot(len, v, v));  /* the vector's own, not the downdated one */
    alpha = v[0] > 0 ? -norm : norm;
    v[0] -= alpha;
    f->rdiag[k] = alpha;
    tau = -MECHRT_R(1) / (alpha * v[0]);   /* 2 / v^T v */
    f->tau[k] = tau;
    f->perm[k] = (mechrt_real)p;
    f->hi[p] = (mechrt_real)hv;
    f->cn[p] = f->cn_ref[p] = -1;        /* chosen */
    for (j = 0; j < m; j++) {
        mechrt_real *c;
        int lo, hi;
        if (f->cn[j] < 0 && f->cn_ref[j] < 0)
            continue;
        lo = (int)f->lo[j] > k ? (int)f->lo[j] : k;
        hi = (int)f->hi[j] < hv ? (int)f->hi[j] : hv;
        if (hi < lo)
            continue;
        c = f->w + (size_t)j * (size_t)n + k;
        qr_axpy(len, tau * qr_dot(hi - lo + 1, v + (lo - k), c + (lo - k)), v, c);
        if ((int)f->lo[j] > k)
            f->lo[j] = (mechrt_real)k;
        if ((int)f->hi[j] < hv)
            f->hi[j] = (mechrt_real)hv;
        f->cn[j] -= c[0] * c[0];
    }
}

/* Copies A into the working columns, with each row's nonzero extent and
   norm; MECHRT_ENOTFINITE for NaN or Inf. */
static MechrtStatus qr_load(MechrtQr *f, const mechrt_real *a, int lda)
{
    int n = f->n, m = f->m, i, j;

    for (j = 0; j < m; j++) {
        mechrt_real *wj = f->w + (size_t)j * (size_t)n;
        const mechrt_real *aj = a + (size_t)j * (size_t)lda;
        int lo = n, hi = -1;
        for (i = 0; i < n; i++) {
            if (!(aj[i] - aj[i] == 0))
                return MECHRT_ENOTFINITE;
            wj[i] = aj[i];
            if (aj[i] != 0) {
                if (lo == n)
                    lo = i;
                hi = i;
            }
        }
        f->lo[j] = (mechrt_real)lo;
        f->hi[j] = (mechrt_real)hi;
        f->perm[j] = (mechrt_real)j;
        f->cn[j] = f->cn_ref[j] = hi >= lo ? qr_dot(hi - lo + 1, wj + lo, wj + lo) : 0;
    }
    return MECHRT_OK;
}

MechrtStatus mechrt_qr_factor(MechrtQr *f, int m, int n, const mechrt_real *a, int lda,
                              mechrt_real rtol, mechrt_real *work, size_t lwork)
{
    size_t need = mechrt_qr_work_len(m, n);
    int k, kmax;
    mechrt_real first = 0;
    MechrtStatus st;

    if (!f || !a || !work || need == 0 || lda < n)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;
    f->m = m;
    f->n = n;
    f->w = work;
    f->tau = work + (size_t)m * (size_t)n;
    f->rdiag = f->tau + m;
    f->perm = f->rdiag + m;
    f->cn = f->perm + m;
    f->cn_ref = f->cn + m;
    f->lo = f->cn_ref + m;
    f->hi = f->lo + m;
    f->rank = 0;
    if ((st = qr_load(f, a, lda)) != MECHRT_OK)
        return st;
    kmax = m < n ? m : n;
    for (k = 0; k < kmax; k++) {
        mechrt_real c, cmax;
        int p = qr_pivot(f, k, &c, &cmax);
        (void)c;
        if (k == 0)
            first = qr_sqrt(cmax);
        if (p < 0 || !(qr_sqrt(cmax) > rtol * first) || cmax == 0)
            break;
        qr_reflect(f, k, p);
        f->rank = k + 1;
    }
    return MECHRT_OK;
}

void mechrt_qr_solve(const MechrtQr *f, const mechrt_real *b, mechrt_real *x)
{
    int n = f->n, r = f->rank, i, k;

    for (i = 0; i < r; i++) {
        /* R(j, i) for j < i sits above position i in the column of step i */
        int p = (int)f->perm[i], lo = (int)f->lo[p];
        const mechrt_real *col = f->w + (size_t)p * (size_t)n;
        mechrt_real s = b[p] - (lo < i ? qr_dot(i - lo, col + lo, x + lo) : 0);
        x[i] = s / f->rdiag[i];
    }
    for (i = r; i < n; i++)
        x[i] = 0;
    for (k = r - 1; k >= 0; k--) {
        int p = (int)f->perm[k], len = (int)f->hi[p] - k + 1;
        const mechrt_real *v = f->w + (size_t)p * (size_t)n + k;
        qr_axpy(len, f->tau[k] * qr_dot(len, v, x + k), v, x + k);
    }
}

/* The row of A chosen at step i < rank (the rows that carry the rank, in
   pivot order), or -1. */
int mechrt_qr_row(const MechrtQr *f, int i)
{
    return (i >= 0 && i < f->rank) ? (int)f->perm[i] : -1;
}
