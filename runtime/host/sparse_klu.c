/* sparse_klu.c - the square Jacobian as a compressed sparse matrix, factored and solved by SuiteSparse's KLU.
 *
 * The pattern is the generated code's (PREFIX_jac_row, PREFIX_jac_col), fixed
 * for a run: mechrt_host_sparse_new lays it out by columns (CSC, what KLU
 * takes) with a map from the kernel's entry order to the CSC slots, and does
 * KLU's symbolic analysis (BTF, then AMD within the blocks) once. Every
 * factorisation scatters the nnz values jac_nz wrote (no dense matrix, no
 * zero fill: every slot has exactly one entry) and refactors with the pivot
 * order of the last fresh factorisation (klu_refactor: no pivot search, no
 * allocation); a fresh klu_factor is done first, after a singular result,
 * and whenever the refactored pivots fail the pivot test or their spread
 * grows SPARSE_REFRESH times past the fresh one's, so a stale pivot order
 * never costs accuracy or reports a false singularity.
 *
 * Pivoting is strict partial pivoting (Common.tol = 1) without row scaling,
 * like the dense LU of runtime/lu.c, and the singularity test is the dense
 * one: |u_kk| <= pivot_tol * max|a_ij|. The failing pivot is named by its
 * original row and column (KLU's final permutations Pnum and Q).
 * Davis and Palamadai Natarajan, "Algorithm 907: KLU, a direct sparse solver
 * for circuit simulation problems", ACM TOMS 37(3), 2010.
 */
#include "mechrt_host.h"

#include <klu.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>

/* Refactor with the old pivot order while the pivot spread stays within this
   factor of the fresh factorisation's; beyond it, pivot afresh. */
#define SPARSE_REFRESH 1e3

struct MechrtHostSparse {
    int n, nnz;
    MechrtHostJacNz jnz;
    int *ap, *ai;           /* CSC pattern: n + 1 column starts, nnz row indices */
    int *map;               /* kernel entry e -> CSC slot */
    double *vals;           /* nnz values in the kernel's order (jac_nz writes here) */
    double *ax;             /* nnz values in CSC order */
    klu_common common;
    klu_symbolic *symbolic;
    klu_numeric *numeric;   /* NULL: the next factorisation is fresh */
    double spread_fresh;    /* pivot spread of the last fresh factorisation */
    double spread_last;     /* ... of the current factors (one pass with the pivot test) */
    int sing_row, sing_col; /* the failing pivot of the last ESING, else -1 */
    long fresh, refactored; /* factorisations of each kind */
};

/* The CSC layout of the pattern and the map to it; false on a bad index or
   a duplicate entry. */
static bool sparse_layout(MechrtHostSparse *s)
{
    const MechrtHostJacNz *j = &s->jnz;
    int *next = calloc((size_t)s->n + 1, sizeof *next);
    int *seen = malloc(((size_t)s->n + 1) * sizeof *seen);
    bool ok = next && seen;
    for (int e = 0; ok && e < s->nnz; e++) {
        ok = j->jac.row[e] >= 0 && j->jac.row[e] < s->n && j->jac.col[e] >= 0 && j->jac.col[e] < s->n;
        if (ok)
            s->ap[j->jac.col[e] + 1]++;
    }
    for (int c = 0; ok && c < s->n; c++) {
        s->ap[c + 1] += s->ap[c];
        next[c] = s->ap[c];
        seen[c] = -1;
    }
    for (int e = 0; ok && e < s->nnz; e++) {
        int slot = next[j->jac.col[e]]++;
        s->ai[slot] = j->jac.row[e];
        s->map[e] = slot;
    }
    /* duplicates: a row met twice in one column */
    for (int c = 0; ok && c < s->n; c++)
        for (int p = s->ap[c]; ok && p < s->ap[c + 1]; p++) {
            ok = seen[s->ai[p]] != c;
            seen[s->ai[p]] = c;
        }
    free(next);
    free(seen);
    return ok;
}

MechrtHostSparse *mechrt_host_sparse_new(int n, const MechrtHostJacNz *jnz)
{
    if (n < 1 || !jnz || jnz->jac.nnz < 0 || !jnz->jac.jac_nz
        || (jnz->jac.nnz > 0 && (!jnz->jac.row || !jnz->jac.col)))
        return NULL;
    MechrtHostSparse *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    size_t nnz = (size_t)jnz->jac.nnz + 1;
    s->n = n;
    s->nnz = jnz->jac.nnz;
    s->jnz = *jnz;
    s->sing_row = s->sing_col = -1;
    s->ap = calloc((size_t)n + 1, sizeof *s->ap);
    s->ai = malloc(nnz * sizeof *s->ai);
    s->map = malloc(nnz * sizeof *s->map);
    s->vals = calloc(nnz, sizeof *s->vals);
    s->ax = calloc(nnz, sizeof *s->ax);
    if (!s->ap || !s->ai || !s->map || !s->vals || !s->ax || !sparse_layout(s)) {
        mechrt_host_sparse_free(s);
        return NULL;
    }
    klu_defaults(&s->common);
    s->common.tol = 1.0;                /* strict partial pivoting, as the dense LU */
    s->common.scale = -1;               /* no row scaling, so the dense pivot test applies;
                                           -1 also skips re-checking the pattern each call */
    s->common.halt_if_singular = 0;     /* keep the factors, to name the failing pivot */
    s->symbolic = klu_analyze(n, s->ap, s->ai, &s->common);
    if (!s->symbolic) {
        mechrt_host_sparse_free(s);
        return NULL;
    }
    return s;
}

void mechrt_host_sparse_free(MechrtHostSparse *s)
{
    if (!s)
        return;
    if (s->numeric)
        klu_free_numeric(&s->numeric, &s->common);
    if (s->symbolic)
        klu_free_symbolic(&s->symbolic, &s->common);
    free(s->ap), free(s->ai), free(s->map), free(s->vals), free(s->ax);
    free(s);
}

int mechrt_host_sparse_nnz(const MechrtHostSparse *s)
{
    return s->nnz;
}

double *mechrt_host_sparse_values(MechrtHostSparse *s)
{
    return s->vals;
}

void mechrt_host_sparse_eval(MechrtHostSparse *s, const double *q, double t)
{
    s->jnz.jac.jac_nz(s->jnz.jac.ctx, q, t, s->vals);
}

bool mechrt_host_sparse_eval_all(MechrtHostSparse *s, const double *q, const double *qd,
                                 double t, double *phi, double *nu, double *gamma)
{
    if (!s->jnz.all_nz)
        return false;
    s->jnz.all_nz(s->jnz.jac.ctx, q, qd, t, phi, s->vals, nu, gamma);
    return true;
}

/* The first pivot at or below thresh (NaN included), named by its original
   row and column; false when there is none, and then spread_last set in
   the same pass (sparse_spread's value: every pivot is nonzero). */
static bool sparse_bad_pivot(MechrtHostSparse *s, double thresh)
{
    const double *u = s->numeric->Udiag;
    double lo = INFINITY, hi = 0;
    for (int k = 0; k < s->n; k++) {
        double a = fabs(u[k]);
        if (!(a > thresh)) {
            s->sing_row = s->numeric->Pnum[k];
            s->sing_col = s->symbolic->Q[k];
            return true;
        }
        lo = a < lo ? a : lo;
        hi = a > hi ? a : hi;
    }
    s->spread_last = hi / lo;
    return false;
}

MechrtStatus mechrt_host_sparse_factor(MechrtHostSparse *s, double pivot_tol)
{
    double amax = 0;
    for (int e = 0; e < s->nnz; e++) {
        double a = fabs(s->vals[e]);
        if (!(a <= DBL_MAX)) {      /* NaN too */
            s->sing_row = s->jnz.jac.row[e];
            s->sing_col = -1;
            return MECHRT_ENOTFINITE;
        }
        amax = a > amax ? a : amax;
    }
    return mechrt_host_sparse_factor_known(s, pivot_tol, amax);
}

MechrtStatus mechrt_host_sparse_factor_known(MechrtHostSparse *s, double pivot_tol, double amax)
{
    s->sing_row = s->sing_col = -1;
    const double *vals = s->vals;
    const int *map = s->map;
    double *ax = s->ax;
    for (int e = 0; e < s->nnz; e++)
        ax[map[e]] = vals[e];
    double thresh = pivot_tol * amax;
    if (s->numeric) {
        if (klu_refactor(s->ap, s->ai, s->ax, s->symbolic, s->numeric, &s->common)
            && !sparse_bad_pivot(s, thresh)
            && s->spread_last <= SPARSE_REFRESH * s->spread_fresh) {
            s->refactored++;
            return MECHRT_OK;
        }
        klu_free_numeric(&s->numeric, &s->common);
    }
    s->fresh++;
    s->sing_row = s->sing_col = -1;
    s->numeric = klu_factor(s->ap, s->ai, s->ax, s->symbolic, &s->common);
    if (!s->numeric)
        return MECHRT_EINVAL;   /* out of memory (KLU's only failure here) */
    if (sparse_bad_pivot(s, thresh)) {
        klu_free_numeric(&s->numeric, &s->common);
        return MECHRT_ESING;
    }
    s->spread_fresh = s->spread_last;
    return MECHRT_OK;
}

static bool sparse_finite(int n, const double *v)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

MechrtStatus mechrt_host_sparse_solve(MechrtHostSparse *s, double *b)
{
    if (!s->numeric)
        return MECHRT_EINVAL;
    if (!sparse_finite(s->n, b))
        return MECHRT_ENOTFINITE;
    klu_solve(s->symbolic, s->numeric, s->n, 1, b, &s->common);
    return sparse_finite(s->n, b) ? MECHRT_OK : MECHRT_ENOTFINITE;
}

double mechrt_host_sparse_spread(const MechrtHostSparse *s)
{
    return s->numeric ? s->spread_last : INFINITY;
}

double mechrt_host_sparse_condest(MechrtHostSparse *s)
{
    if (!s->numeric || !klu_condest(s->ap, s->ax, s->symbolic, s->numeric, &s->common))
        return INFINITY;
    return s->common.condest;
}

void mechrt_host_sparse_singular(const MechrtHostSparse *s, int *row, int *col)
{
    *row = s->sing_row;
    *col = s->sing_col;
}

void mechrt_host_sparse_refresh(MechrtHostSparse *s)
{
    if (s->numeric)
        klu_free_numeric(&s->numeric, &s->common);
}

void mechrt_host_sparse_counts(const MechrtHostSparse *s, long *fresh, long *refactored)
{
    *fresh = s->fresh;
    *refactored = s->refactored;
}
