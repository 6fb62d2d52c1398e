/* lu_pattern.c - LU of matrices with one sparsity pattern: the dense LU's pivots, replayed over index lists.
 *
 * A kinematic step factors Jacobians of one pattern again and again, and
 * the order partial pivoting picks rarely changes from one to the next. So
 * the first factorisation is the dense one (lu.c); its pivot order and the
 * fill it causes are recorded once as index lists ("symbolic analysis", on
 * the caller's integer workspace), and later factorisations replay that
 * elimination over the structural nonzeros and the fill only: no scan of
 * n^2 entries, no pivot search, no row swaps.
 *
 * Replaying keeps the dense LU's results bit for bit. At step k the replay
 * first checks that the recorded pivot is still the one partial pivoting
 * would take: larger in magnitude than every candidate that comes before
 * it in the dense LU's row arrangement, and no smaller than those after
 * it (lu.c keeps the first largest), and above the singularity threshold.
 * Entries outside the pattern are exact zeros in the dense LU too, and
 * x - l*0 == x, so the replay performs the same operations in the same
 * order on every entry that matters. When a check fails at step k, the
 * slots hold exactly what the dense LU holds after k steps: they are
 * spread into lu.c's layout and lu.c finishes the elimination from step k
 * (mechrt_lu_resume), pivot search and singularity test included, and the
 * order it found is recorded for next time. Robustness is the dense LU's.
 * KLU's refactorisation (Davis & Palamadai Natarajan, ACM TOMS 37, 2010)
 * is the model; its pivot check is made exact here.
 *
 * Storage: slot e < nnz holds pattern entry e (the order of row[] and
 * col[]), fill entries follow. The replay is right-looking like lu.c. The
 * lists are three flat programs of ints, read front to back:
 *   factor: the count of steps with candidates, then per such step k: k,
 *     its pivot's slot, the strict count ns, the candidate count nc, the
 *     U count nu, U's slots, then per candidate its slot and the nu update
 *     targets (the candidates of column k: the first ns sit before the
 *     pivot in lu.c's arrangement and must stay strictly smaller); then
 *     the count of steps without candidates and those steps, whose pivots
 *     are only tested (lone pivots);
 *   forward, column by column: (row i of the arrangement, slot of l_ij,
 *     column j) triples;
 *   backward, per row i from the last: the slot of u_ii, the count of U
 *     entries, then (slot, column) pairs, columns ascending.
 * After a fallback the factors of that factorisation are lu.c's (the
 * `dense` scratch and piv) and the solves use lu.c.
 */
#include <math.h>

#include "mechrt.h"

/* Row-major index of entry (r, j) in the n*n map. */
#define LUP_AT(f, r, j) ((size_t)(r) * (size_t)(f)->n + (size_t)(j))

/* The fixed part of the integer workspace: the map (n*n), then prow,
   pslot, pos and three n-int scratch lists of the analysis. */
#define LUP_IFIXED(n) ((size_t)(n) * (size_t)(n) + 6u * (size_t)(n))

size_t mechrt_lup_work_size(int n)
{
    size_t m;

    if (n < 1 || n > MECHRT_LUP_MAX_N)
        return 0;
    m = (size_t)n;
    if (m > ((size_t)-1 / 4) / m)   /* 2n^2 + 4n on a 32-bit size_t */
        return 0;
    return MECHRT_LUP_WORK_LEN(m);
}

size_t mechrt_lup_iwork_size(int n)
{
    size_t m;

    if (n < 1 || n > MECHRT_LUP_MAX_N)
        return 0;
    m = (size_t)n;
    if (m > ((size_t)-1 / 4) / (m * m))   /* the cubic term on a 32-bit size_t */
        return 0;
    return MECHRT_LUP_IWORK_LEN(m);
}

/* The pattern's own entries in the map; no fill. */
static void lup_reset_map(MechrtLup *f)
{
    size_t i, nn = (size_t)f->n * (size_t)f->n;
    int e;

    for (i = 0; i < nn; i++)
        f->map[i] = -1;
    for (e = 0; e < f->nnz; e++)
        f->map[LUP_AT(f, f->row[e], f->col[e])] = e;
}

MechrtStatus mechrt_lup_init(MechrtLup *f, int n, int nnz, const int *row, const int *col,
                             mechrt_real *work, size_t lwork, int *iwork, size_t liwork)
{
    size_t nn;
    int e;

    if (!f)
        return MECHRT_EINVAL;
    f->n = 0;
    if (n < 1 || n > MECHRT_LUP_MAX_N || nnz < 0 || (size_t)nnz > (size_t)n * (size_t)n
        || (nnz > 0 && (!row || !col)) || !work || !iwork)
        return MECHRT_EINVAL;
    nn = (size_t)n;
    if (mechrt_lup_work_size(n) == 0)
        return MECHRT_EINVAL;
    if (lwork < MECHRT_LUP_WORK_LEN(nn) || liwork < LUP_IFIXED(nn))
        return MECHRT_EBADLEN;
    for (e = 0; e < nnz; e++)
        if (row[e] < 0 || row[e] >= n || col[e] < 0 || col[e] >= n)
            return MECHRT_EINVAL;
    f->n = n;
    f->nnz = nnz;
    f->row = row;
    f->col = col;
    f->lu = work;
    f->dense = work + nn * nn;
    f->piv = f->dense + nn * nn;
    f->tmp = f->piv + nn;
    f->cwork = f->tmp + nn;
    f->liw = liwork;
    f->map = iwork;
    f->prow = iwork + nn * nn;
    f->pslot = f->prow + nn;
    f->pos = f->pslot + nn;
    f->scratch = f->pos + nn;
    f->fprog = f->fwd = f->bwd = f->scratch + 3 * nn;
    f->nslots = nnz;
    f->nfwd = 0;
    f->ordered = false;
    f->dense_now = false;
    f->analyses = 0;
    f->replays = 0;
    f->gen = NULL;
    f->gen_now = false;
    f->gen_spread = 0;
    f->gen_factors = 0;
    lup_reset_map(f);
    for (e = 0; e < nnz; e++)
        if (f->map[LUP_AT(f, row[e], col[e])] != e) {   /* repeated */
            f->n = 0;
            return MECHRT_EINVAL;
        }
    return MECHRT_OK;
}

MechrtStatus mechrt_lup_use(MechrtLup *f, const MechrtLuGen *gen)
{
    if (!f || f->n < 1 || (gen && (!gen->factor || !gen->solve || gen->nslots < 1
                                   || (size_t)gen->nslots > (size_t)f->n * (size_t)f->n)))
        return MECHRT_EINVAL;
    f->gen = gen;
    f->gen_now = false;
    return MECHRT_OK;
}

mechrt_real *mechrt_lup_values(MechrtLup *f)
{
    return f->lu;
}

/* pos[i] = the row at position i of lu.c's arrangement after the
   interchanges piv[0 .. k-1]. */
static void lup_arrange(const MechrtLup *f, int *pos, int k)
{
    int i;

    for (i = 0; i < f->n; i++)
        pos[i] = i;
    for (i = 0; i < k; i++) {
        int p = (int)f->piv[i], t = pos[i];
        pos[i] = pos[p];
        pos[p] = t;
    }
}

/* Symbolic elimination in the order of piv: marks the fill in the map,
   sizes the three programs and counts the steps without candidates (lone
   pivots). False if a pivot falls outside the pattern
   (an entry the pattern calls zero was not). */
static bool lup_fill(MechrtLup *f, size_t *len, int *lone)
{
    int n = f->n, *pos = f->pos, i, j, k;

    lup_arrange(f, pos, 0);
    *lone = 0;
    len[0] = 2;
    len[1] = 0;
    len[2] = 2 * (size_t)n;
    for (k = 0; k < n; k++) {
        int p = (int)f->piv[k], rk, nu = 0, nc = 0, t = pos[k];
        pos[k] = pos[p];
        pos[p] = t;
        rk = pos[k];
        if (f->map[LUP_AT(f, rk, k)] < 0)
            return false;
        for (j = k + 1; j < n; j++)
            nu += f->map[LUP_AT(f, rk, j)] >= 0;
        for (i = k + 1; i < n; i++) {
            int r = pos[i];
            if (f->map[LUP_AT(f, r, k)] < 0)
                continue;
            nc++;
            for (j = k + 1; j < n; j++)
                if (f->map[LUP_AT(f, rk, j)] >= 0 && f->map[LUP_AT(f, r, j)] < 0)
                    f->map[LUP_AT(f, r, j)] = f->nslots++;
        }
        if (nc > 0)
            len[0] += 5 + (size_t)nu + (size_t)nc * (1 + (size_t)nu);
        else
            ++*lone;
        len[1] += 3 * (size_t)nc;   /* a candidate is an L entry of a later row */
        len[2] += 2 * (size_t)nu;
    }
    len[0] += (size_t)*lone;   /* the list of lone pivots closes the program */
    return true;
}

/* Writes to slots the slots of column k's candidates at positions k..n-1
   of the arrangement before step k's interchange with position p: the
   strict ones (before p) when strict, the others otherwise; their rows
   into rows. Returns the count. */
static int lup_candidates(const MechrtLup *f, const int *pos, int k, int p, bool strict,
                          int *slots, int *rows)
{
    int i, c = 0;

    for (i = k; i < f->n; i++) {
        int s = f->map[LUP_AT(f, pos[i], k)];
        if (i != p && s >= 0 && (i < p) == strict) {
            slots[c] = s;
            rows[c++] = pos[i];
        }
    }
    return c;
}

/* Step k of the analysis: its pivot, and its part of the factor program
   at w when it has candidates (pos: the arrangement before step k,
   advanced past it). Returns the program's end. */
static int *lup_prog_step(MechrtLup *f, int *w, int k)
{
    int n = f->n, *pos = f->pos, p = (int)f->piv[k], rk, ns, nc, nu = 0, c, j, t;
    int *cand = f->scratch, *crow = cand + n, *ucol = crow + n;

    ns = lup_candidates(f, pos, k, p, true, cand, crow);
    nc = ns + lup_candidates(f, pos, k, p, false, cand + ns, crow + ns);
    t = pos[k];
    pos[k] = pos[p];
    pos[p] = t;
    rk = pos[k];
    f->prow[k] = rk;
    f->pslot[k] = f->map[LUP_AT(f, rk, k)];
    if (nc == 0)
        return w;
    for (j = k + 1; j < n; j++)
        if (f->map[LUP_AT(f, rk, j)] >= 0)
            ucol[nu++] = j;
    *w++ = k;
    *w++ = f->pslot[k];
    *w++ = ns;
    *w++ = nc;
    *w++ = nu;
    for (j = 0; j < nu; j++)
        *w++ = f->map[LUP_AT(f, rk, ucol[j])];
    for (c = 0; c < nc; c++) {
        *w++ = cand[c];
        for (j = 0; j < nu; j++)
            *w++ = f->map[LUP_AT(f, crow[c], ucol[j])];
    }
    return w;
}

/* The solve programs from the map and prow: forward, column by column,
   the triples (row i, slot of l_ij, column j); backward, row by row from
   the last, the slot of u_ii, the count, then (slot, column) pairs. */
static void lup_prog_solve(MechrtLup *f)
{
    int n = f->n, i, j, *w = f->fwd;

    for (j = 0; j < n; j++)
        for (i = j + 1; i < n; i++) {
            int s = f->map[LUP_AT(f, f->prow[i], j)];
            if (s >= 0) {
                *w++ = i;
                *w++ = s;
                *w++ = j;
            }
        }
    f->nfwd = (int)((w - f->fwd) / 3);
    w = f->bwd;
    for (i = n - 1; i >= 0; i--) {
        const int *m = f->map + LUP_AT(f, f->prow[i], 0);
        int *count;
        *w++ = m[i];
        count = w++;
        *count = 0;
        for (j = i + 1; j < n; j++)
            if (m[j] >= 0) {
                *w++ = m[j];
                *w++ = j;
                ++*count;
            }
    }
}

/* Records the order of f->piv (a successful dense factorisation): fill
   and programs. When they do not fit the integer workspace, or the
   pattern missed an entry, nothing is recorded and the factorisations
   stay dense. */
static void lup_analyse(MechrtLup *f)
{
    size_t len[3], room = f->liw - LUP_IFIXED(f->n);
    int *w, k, lone = 0;

    f->analyses++;
    f->ordered = false;
    f->nslots = f->nnz;
    lup_reset_map(f);
    if (!lup_fill(f, len, &lone) || len[0] > room || len[1] > room - len[0]
        || len[2] > room - len[0] - len[1]) {
        f->nslots = f->nnz;
        return;
    }
    f->fwd = f->fprog + len[0];
    f->bwd = f->fwd + len[1];
    f->lone = f->fwd - 1 - lone;   /* the end of the factor program */
    f->lone[0] = lone;
    f->fprog[0] = 0;   /* the count of steps with candidates */
    lone = 0;
    lup_arrange(f, f->pos, 0);
    w = f->fprog + 1;
    for (k = 0; k < f->n; k++) {
        int *end = lup_prog_step(f, w, k);
        f->fprog[0] += end != w;
        if (end == w)
            f->lone[1 + lone++] = k;
        w = end;
    }
    lup_prog_solve(f);
    f->ordered = true;
}

/* max|a_ij| over the slots of the pattern (the scale of the pivot test),
   MECHRT_ENOTFINITE on NaN or Inf as lu.c's scan; zeros the fill. x - x
   is 0 for every finite x and NaN otherwise, so one sum checks them all. */
static MechrtStatus lup_scan(MechrtLup *f, mechrt_real *amax_out)
{
    mechrt_real *lu = f->lu, a0 = 0, a1 = 0, c0 = 0, c1 = 0;
    int e, nnz = f->nnz;

    for (e = 0; e + 1 < nnz; e += 2) {   /* two chains: half the loop control */
        mechrt_real x = lu[e], y = lu[e + 1], u = MECHRT_LUP_ABS(x), v = MECHRT_LUP_ABS(y);
        c0 += x - x;
        c1 += y - y;
        a0 = u > a0 ? u : a0;
        a1 = v > a1 ? v : a1;
    }
    if (e < nnz) {
        mechrt_real x = lu[e], u = MECHRT_LUP_ABS(x);
        c0 += x - x;
        a0 = u > a0 ? u : a0;
    }
    if (c0 + c1 != 0)
        return MECHRT_ENOTFINITE;
    for (e = nnz; e < f->nslots; e++)
        lu[e] = 0;
    *amax_out = a1 > a0 ? a1 : a0;
    return MECHRT_OK;
}

/* The recorded elimination on the slots, over the steps that have
   candidates. Returns n when done, or the first step k whose pivot is not
   the one partial pivoting takes or is at the threshold: the slots then
   hold lu.c's matrix after k steps. The operations are lu_eliminate's. */
static int lup_replay(MechrtLup *f, mechrt_real thresh)
{
    mechrt_real *lu = f->lu;
    const int *p = f->fprog + 1;
    int steps = f->fprog[0];

    for (; steps > 0; steps--) {
        mechrt_real pivot = lu[p[1]], ap = MECHRT_LUP_ABS(pivot);
        int ns = p[2], nc = p[3], nu = p[4], stride = 1 + nu, c, m;
        const int *us = p + 5, *cand = us + nu, *q = cand;

        if (!(ap > thresh))
            return p[0];
        for (c = 0; c < ns; c++, q += stride)
            if (!(MECHRT_LUP_ABS(lu[*q]) < ap))
                return p[0];
        for (; c < nc; c++, q += stride)
            if (!(MECHRT_LUP_ABS(lu[*q]) <= ap))
                return p[0];
        for (q = cand; q < cand + nc * stride; q += stride) {
            mechrt_real l = lu[*q] / pivot;
            lu[*q] = l;
            if (l != 0)
                for (m = 0; m < nu; m++)
                    lu[q[1 + m]] -= l * lu[us[m]];
        }
        p = q;
    }
    return f->n;
}

/* The pivots of the steps before k that have no candidates, against the
   threshold: the replay tested the others. Such a pivot is final once the
   steps before it are done, and where it fails lu.c stops with
   MECHRT_ESING (its column has no other nonzero). Returns the first such
   step, or -1. */
static int lup_lone_pivots(const MechrtLup *f, int k, mechrt_real thresh)
{
    const int *p = f->lone + 1, *end = p + f->lone[0];

    for (; p < end && *p < k; p++)
        if (!(MECHRT_LUP_ABS(f->lu[f->pslot[*p]]) > thresh))
            return *p;
    return -1;
}

/* lu.c's layout of the slots after k steps of the recorded order. */
static void lup_to_dense(MechrtLup *f, int k)
{
    size_t n = (size_t)f->n, i, j;

    lup_arrange(f, f->pos, k);
    for (i = 0; i < n; i++) {
        const int *m = f->map + LUP_AT(f, f->pos[i], 0);
        for (j = 0; j < n; j++)
            f->dense[i * n + j] = m[j] >= 0 ? f->lu[m[j]] : 0;
    }
}

/* lu.c finishes what the replay began at step k (k = 0 without an order:
   the whole dense LU of the slots); its order is recorded on success. */
static MechrtStatus lup_fallback(MechrtLup *f, int k, mechrt_real pivot_tol, mechrt_real thresh,
                                 int *sing_index)
{
    MechrtStatus st;

    if (f->ordered) {
        lup_to_dense(f, k);
        st = mechrt_lu_resume(f->n, f->dense, f->n, f->piv, k, thresh, sing_index);
    } else {
        size_t i, nn = (size_t)f->n * (size_t)f->n;
        int e;
        for (i = 0; i < nn; i++)
            f->dense[i] = 0;
        for (e = 0; e < f->nnz; e++)
            f->dense[LUP_AT(f, f->row[e], f->col[e])] = f->lu[e];
        st = mechrt_lu_factor(f->n, f->dense, f->n, f->piv, pivot_tol, sing_index);
    }
    f->ordered = false;   /* piv no longer matches the programs */
    f->dense_now = st == MECHRT_OK;
    if (st == MECHRT_OK)
        lup_analyse(f);
    return st;
}

/* The pattern LU's factorisation (mechrt_lup_factor without gen); kept
   out of line, so that gen's path does not pay for its frame. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static MechrtStatus lup_factor_pivoting(MechrtLup *f, mechrt_real pivot_tol, int *sing_index)
{
    mechrt_real amax, thresh;
    MechrtStatus st;
    int k, sing;

    if (!f->ordered)
        return lup_fallback(f, 0, pivot_tol, 0, sing_index);
    st = lup_scan(f, &amax);
    if (st != MECHRT_OK)
        return st;
    /* lu.c's test |u_kk| <= thresh || u_kk == 0 as one comparison */
    thresh = pivot_tol * amax > 0 ? pivot_tol * amax : 0;
    k = lup_replay(f, thresh);
    sing = lup_lone_pivots(f, k, thresh);
    if (sing >= 0) {
        if (sing_index)
            *sing_index = sing;
        return MECHRT_ESING;
    }
    if (k < f->n)
        return lup_fallback(f, k, pivot_tol, thresh, sing_index);
    f->replays++;
    return MECHRT_OK;
}

MechrtStatus mechrt_lup_factor(MechrtLup *f, mechrt_real pivot_tol, int *sing_index)
{
    if (sing_index)
        *sing_index = -1;
    if (!f || f->n < 1)
        return MECHRT_EINVAL;
    f->dense_now = false;
    f->gen_now = false;
    /* the unrolled LU reads the values and leaves them: where it declines,
       the pattern LU factors the same matrix; its factors go to dense,
       which only the pattern LU's fallback and estimate use */
    if (f->gen && f->gen->factor(f->gen->ctx, f->lu, f->dense, pivot_tol, &f->gen_spread) == 0
        && f->gen_spread <= MECHRT_R(MECHRT_LUP_GEN_SPREAD)) {
        f->gen_now = true;
        f->gen_factors++;
        return MECHRT_OK;
    }
    return lup_factor_pivoting(f, pivot_tol, sing_index);
}

MechrtStatus mechrt_lup_factor_dense(MechrtLup *f, const mechrt_real *a, int lda,
                                     mechrt_real pivot_tol, int *sing_index)
{
    size_t ld = (size_t)lda;
    int e;

    if (!f || f->n < 1 || !a || lda < f->n) {
        if (sing_index)
            *sing_index = -1;
        return MECHRT_EINVAL;
    }
    for (e = 0; e < f->nnz; e++)
        f->lu[e] = a[(size_t)f->row[e] * ld + (size_t)f->col[e]];
    return mechrt_lup_factor(f, pivot_tol, sing_index);
}

/* lu.c's solve over the nonzeros: b in the row order into tmp, the forward
   substitution column by column (each y_i still receives its terms with
   columns ascending, as lu.c's row-oriented loop gives them), then the
   back substitution row by row into x; the same operations in the same
   order on every nonzero term. x may be b. */
void mechrt_lup_solve(const MechrtLup *f, const mechrt_real *b, mechrt_real *x)
{
    const mechrt_real *lu = f->lu;
    mechrt_real *y = f->tmp;
    const int *p, *end;
    int n = f->n, i;

    if (f->gen_now) {
        f->gen->solve(f->gen->ctx, f->dense, b, x);
        return;
    }
    if (f->dense_now) {
        if (x != b)
            for (i = 0; i < n; i++)
                x[i] = b[i];
        mechrt_lu_solve(n, f->dense, n, f->piv, x);
        return;
    }
    for (i = 0; i < n; i++)
        y[i] = b[f->prow[i]];
    for (p = f->fwd, end = p + 3 * f->nfwd; p < end; p += 3)
        y[p[0]] -= lu[p[1]] * y[p[2]];
    for (i = n - 1, p = f->bwd; i >= 0; i--) {
        mechrt_real s = y[i], u = lu[p[0]];
        int c = p[1];
        for (p += 2; c > 0; c--, p += 2)
            s -= lu[p[0]] * x[p[1]];
        x[i] = s / u;
    }
}

/* mechrt_lup_solve on every column of b, the columns innermost: each
   column's operations and their order are mechrt_lup_solve's, and the
   columns' chains (a division per row in the back substitution) overlap
   instead of following one another. */
void mechrt_lup_solve_many(const MechrtLup *f, mechrt_real *b, int ldb, int nrhs,
                           mechrt_real *work)
{
    const mechrt_real *lu = f->lu;
    const int *p, *end;
    size_t lb = (size_t)ldb, m = (size_t)nrhs;
    int n = f->n, i, c;

    if (f->dense_now) {
        mechrt_lu_solve_many(n, f->dense, n, f->piv, b, ldb, nrhs);
        return;
    }
    if (f->gen_now) {
        for (c = 0; c < nrhs; c++) {
            for (i = 0; i < n; i++)
                work[i] = b[(size_t)i * lb + (size_t)c];
            f->gen->solve(f->gen->ctx, f->dense, work, work);
            for (i = 0; i < n; i++)
                b[(size_t)i * lb + (size_t)c] = work[i];
        }
        return;
    }
    for (i = 0; i < n; i++)
        for (c = 0; c < nrhs; c++)
            work[(size_t)i * m + (size_t)c] = b[(size_t)f->prow[i] * lb + (size_t)c];
    for (p = f->fwd, end = p + 3 * f->nfwd; p < end; p += 3) {
        mechrt_real l = lu[p[1]], *yi = work + (size_t)p[0] * m;
        const mechrt_real *yj = work + (size_t)p[2] * m;
        for (c = 0; c < nrhs; c++)
            yi[c] -= l * yj[c];
    }
    for (i = n - 1, p = f->bwd; i >= 0; i--) {
        mechrt_real u = lu[p[0]], *xi = b + (size_t)i * lb, *yi = work + (size_t)i * m;
        int cnt = p[1];
        const int *q = p + 2;
        for (c = 0; c < nrhs; c++) {
            mechrt_real s = yi[c];
            int k;
            for (k = 0; k < cnt; k++)
                s -= lu[q[2 * k]] * b[(size_t)q[2 * k + 1] * lb + (size_t)c];
            xi[c] = s / u;
        }
        p = q + 2 * cnt;
    }
}

/* analysis.c's an_pivot_spread, over the pivots in step order. */
mechrt_real mechrt_lup_spread(const MechrtLup *f)
{
    size_t n = (size_t)f->n, k;
    mechrt_real lo, hi;

    if (f->gen_now)
        return f->gen_spread;
    if (f->dense_now) {
        lo = hi = MECHRT_LUP_ABS(f->dense[0]);
        for (k = 1; k < n; k++) {
            mechrt_real u = MECHRT_LUP_ABS(f->dense[k * n + k]);
            lo = u < lo ? u : lo;
            hi = u > hi ? u : hi;
        }
    } else {
        lo = hi = MECHRT_LUP_ABS(f->lu[f->pslot[0]]);
        for (k = 1; k < n; k++) {
            mechrt_real u = MECHRT_LUP_ABS(f->lu[f->pslot[k]]);
            lo = u < lo ? u : lo;
            hi = u > hi ? u : hi;
        }
    }
    return hi / lo;
}

mechrt_real mechrt_lup_norm1(MechrtLup *f, const mechrt_real *vals)
{
    size_t i, nn = (size_t)f->n * (size_t)f->n;
    int e;

    for (i = 0; i < nn; i++)
        f->dense[i] = 0;
    for (e = 0; e < f->nnz; e++)
        f->dense[LUP_AT(f, f->row[e], f->col[e])] = vals[e];
    return mechrt_norm1(f->n, f->dense, f->n);
}

/* lu.c's estimate on the factors in lu.c's layout (the same numbers). */
mechrt_real mechrt_lup_cond1(MechrtLup *f, mechrt_real anorm)
{
    if (!f->dense_now) {
        lup_to_dense(f, f->n);
        f->dense_now = true;
    }
    return mechrt_lu_cond1(f->n, f->dense, f->n, f->piv, anorm, f->cwork);
}
