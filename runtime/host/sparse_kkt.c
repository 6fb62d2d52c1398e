/* sparse_kkt.c - the augmented matrix [W Phi_q^T; Phi_q 0] of a mechanism with masses, sparse, factored by KLU.
 *
 * Forward dynamics and the projections of `mechc sim` on large mechanisms
 * solve one kind of system, the augmented (KKT) matrix
 *     [W      Phi_A^T] [x]   [a]
 *     [Phi_A  0      ] [y] = [b]
 * with W = M (accelerations and multipliers) or W = I (minimum-norm
 * corrections of positions and velocities), Phi_A the Jacobian's rows
 * that are kept. Its pattern is fixed: M's nonzeros (PREFIX_mass_nz) and
 * the diagonal, Phi_q's nonzeros (PREFIX_jac_nz) twice, and one diagonal
 * slot per row, 0 for a row kept and 1 for a row left out (whose entries
 * are zeroed: y_i = b_i, with b_i = 0 the multiplier is 0). So a change
 * of the rows kept is a change of values, and KLU's symbolic analysis
 * (runtime/host/sparse_klu.c: BTF, AMD) is done once per weight; each
 * weight has its own numeric factors, so that alternating between them
 * keeps the refactorisations' pivot orders.
 *
 * Nothing of size nr x nq or nq x nq is formed: for IFToMM A02 (243
 * coordinates) the matrix has 485 rows and about 3 400 nonzeros.
 * mechrt_host_kkt_solve_refined adds one step of iterative refinement:
 * a refactorisation keeps a pivot order whose growth may reach 1e3 times
 * a fresh one's (sparse_klu.c), and near a rank drop the multipliers
 * dwarf the accelerations, whose error a backward-stable solve bounds
 * only relative to the whole solution.
 */
#include "mechrt_host.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct MechrtHostKkt {
    int nq, nr, mnz, jnz, nxd;      /* sizes; nxd: diagonal slots M's pattern lacks */
    int *xdiag;                     /* their coordinates */
    unsigned char *mdiag;           /* M's entry e is on the diagonal */
    int *row, *col;                 /* the pattern, entries in the order of fill() */
    double *jac, *mass;             /* the caller's values: jnz, mnz */
    MechrtHostSparse *lu[3];        /* per MechrtKktWeight; [2] the rank screen's */
};

/* A pattern without a callback: values are written, not evaluated. */
static void kkt_no_eval(void *ctx, const double *q, double t, double *vals)
{
    (void)ctx, (void)q, (void)t, (void)vals;
}

/* Entries: M's (mnz), the diagonal slots M lacks (nxd), Phi_q (jnz) at
   (nq + r, c), Phi_q^T at (c, nq + r), the rows' diagonal (nr). */
static bool kkt_pattern(MechrtHostKkt *s, const MechrtHostJacNz *jnz, const MechrtHostMassNz *mnz)
{
    unsigned char *has = calloc((size_t)s->nq, 1);
    if (!has)
        return false;
    for (int e = 0; e < s->mnz; e++)
        if (mnz->row[e] == mnz->col[e] && mnz->row[e] >= 0 && mnz->row[e] < s->nq)
            has[mnz->row[e]] = s->mdiag[e] = 1;
    for (int i = 0; i < s->nq; i++)
        if (!has[i])
            s->xdiag[s->nxd++] = i;
    free(has);
    int e = 0;
    for (int k = 0; k < s->mnz; k++, e++)
        s->row[e] = mnz->row[k], s->col[e] = mnz->col[k];
    for (int k = 0; k < s->nxd; k++, e++)
        s->row[e] = s->col[e] = s->xdiag[k];
    for (int k = 0; k < s->jnz; k++, e++)
        s->row[e] = s->nq + jnz->jac.row[k], s->col[e] = jnz->jac.col[k];
    for (int k = 0; k < s->jnz; k++, e++)
        s->row[e] = jnz->jac.col[k], s->col[e] = s->nq + jnz->jac.row[k];
    for (int k = 0; k < s->nr; k++, e++)
        s->row[e] = s->col[e] = s->nq + k;
    return true;
}

MechrtHostKkt *mechrt_host_kkt_new(int nq, int nr, const MechrtHostJacNz *jnz,
                                   const MechrtHostMassNz *mnz)
{
    if (nq < 1 || nr < 0 || !jnz || !mnz || jnz->jac.nnz < 0 || mnz->nnz < 0
        || (jnz->jac.nnz > 0 && (!jnz->jac.row || !jnz->jac.col))
        || (mnz->nnz > 0 && (!mnz->row || !mnz->col)))
        return NULL;
    MechrtHostKkt *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->nq = nq;
    s->nr = nr;
    s->mnz = mnz->nnz;
    s->jnz = jnz->jac.nnz;
    size_t total = (size_t)s->mnz + (size_t)nq + 2u * (size_t)s->jnz + (size_t)nr + 1u;
    s->xdiag = malloc((size_t)nq * sizeof *s->xdiag);
    s->mdiag = calloc((size_t)s->mnz + 1u, 1);
    s->row = malloc(total * sizeof *s->row);
    s->col = malloc(total * sizeof *s->col);
    s->jac = calloc((size_t)s->jnz + 1u, sizeof *s->jac);
    s->mass = calloc((size_t)s->mnz + 1u, sizeof *s->mass);
    if (!s->xdiag || !s->mdiag || !s->row || !s->col || !s->jac || !s->mass
        || !kkt_pattern(s, jnz, mnz)) {
        mechrt_host_kkt_free(s);
        return NULL;
    }
    MechrtHostJacNz pat = {.jac = {.nnz = s->mnz + s->nxd + 2 * s->jnz + nr, .row = s->row,
                                   .col = s->col, .jac_nz = kkt_no_eval}};
    for (int w = 0; w < 3; w++) {
        s->lu[w] = mechrt_host_sparse_new(nq + nr, &pat);
        if (!s->lu[w]) {
            mechrt_host_kkt_free(s);
            return NULL;
        }
    }
    return s;
}

void mechrt_host_kkt_free(MechrtHostKkt *s)
{
    if (!s)
        return;
    for (int w = 0; w < 3; w++)
        mechrt_host_sparse_free(s->lu[w]);
    free(s->xdiag), free(s->mdiag), free(s->row), free(s->col), free(s->jac), free(s->mass);
    free(s);
}

double *mechrt_host_kkt_jac(MechrtHostKkt *s)
{
    return s->jac;
}

double *mechrt_host_kkt_mass(MechrtHostKkt *s)
{
    return s->mass;
}

/* Row r (< nr) kept: among the first `rows` and marked in active (NULL: all). */
static bool kkt_kept(const unsigned char *active, int rows, int r)
{
    return r < rows && (!active || active[r]);
}

/* The values of weight w with the rows kept, in the pattern's order. */
static void kkt_fill(const MechrtHostKkt *s, MechrtKktWeight w, const unsigned char *active,
                     int rows, double *v)
{
    int e = 0;
    if (w == MECHRT_KKT_MASS)
        memcpy(v, s->mass, (size_t)s->mnz * sizeof *v), e = s->mnz;
    else
        for (int k = 0; k < s->mnz; k++, e++)
            v[e] = s->mdiag[k] ? 1.0 : 0.0;
    for (int k = 0; k < s->nxd; k++, e++)
        v[e] = w == MECHRT_KKT_MASS ? 0.0 : 1.0;
    const int *jrow = s->row + s->mnz + s->nxd;     /* nq + r */
    if (!active && rows >= s->nr)   /* every row kept: the values as they are */
        memcpy(v + e, s->jac, (size_t)s->jnz * sizeof *v);
    else
        for (int k = 0; k < s->jnz; k++)
            v[e + k] = kkt_kept(active, rows, jrow[k] - s->nq) ? s->jac[k] : 0.0;
    memcpy(v + e + s->jnz, v + e, (size_t)s->jnz * sizeof *v);
    e += 2 * s->jnz;
    for (int r = 0; r < s->nr; r++, e++)
        v[e] = kkt_kept(active, rows, r) ? 0.0 : 1.0;
}

/* max |v_e| over the values kkt_fill wrote, Phi_q's once (its transpose
   holds the same); false for a value not finite. */
static bool kkt_amax(const MechrtHostKkt *s, const double *v, double *amax)
{
    int head = s->mnz + s->nxd + s->jnz, tail = head + s->jnz, end = tail + s->nr;
    double m = 0;
    bool finite = true;
    for (int e = 0; e < head; e++) {
        double a = fabs(v[e]);
        m = a > m ? a : m;
        finite &= a <= DBL_MAX;     /* false for NaN too */
    }
    for (int e = tail; e < end; e++)
        m = v[e] > m ? v[e] : m;    /* the rows' diagonal: 0 or 1 */
    *amax = m;
    return finite;
}

MechrtStatus mechrt_host_kkt_factor(MechrtHostKkt *s, MechrtKktWeight w,
                                    const unsigned char *active, int rows, double pivot_tol)
{
    MechrtHostSparse *lu = s->lu[w == MECHRT_KKT_MASS ? 0 : 1];
    double *v = mechrt_host_sparse_values(lu), amax;
    kkt_fill(s, w, active, rows, v);
    if (!kkt_amax(s, v, &amax))
        return mechrt_host_sparse_factor(lu, pivot_tol);    /* names the entry */
    return mechrt_host_sparse_factor_known(lu, pivot_tol, amax);
}

MechrtStatus mechrt_host_kkt_screen(MechrtHostKkt *s, int rows, double pivot_tol,
                                    double *spread)
{
    MechrtHostSparse *lu = s->lu[2];
    double *v = mechrt_host_sparse_values(lu), amax;
    kkt_fill(s, MECHRT_KKT_IDENTITY, NULL, rows, v);
    mechrt_host_sparse_refresh(lu);
    MechrtStatus st = kkt_amax(s, v, &amax) ? mechrt_host_sparse_factor_known(lu, pivot_tol, amax)
                                            : mechrt_host_sparse_factor(lu, pivot_tol);
    *spread = mechrt_host_sparse_spread(lu);
    return st;
}

MechrtStatus mechrt_host_kkt_solve(MechrtHostKkt *s, MechrtKktWeight w, double *x)
{
    return mechrt_host_sparse_solve(s->lu[w == MECHRT_KKT_MASS ? 0 : 1], x);
}

MechrtStatus mechrt_host_kkt_solve_refined(MechrtHostKkt *s, MechrtKktWeight w, double *x,
                                           double *work)
{
    MechrtHostSparse *lu = s->lu[w == MECHRT_KKT_MASS ? 0 : 1];
    int n = s->nq + s->nr, nnz = mechrt_host_sparse_nnz(lu);
    const double *v = mechrt_host_sparse_values(lu);
    double *b = work, *r = work + n;
    for (int i = 0; i < n; i++)
        b[i] = x[i];
    MechrtStatus st = mechrt_host_sparse_solve(lu, x);
    if (st != MECHRT_OK)
        return st;
    for (int i = 0; i < n; i++)
        r[i] = b[i];
    for (int e = 0; e < nnz; e++)
        r[s->row[e]] -= v[e] * x[s->col[e]];
    st = mechrt_host_sparse_solve(lu, r);
    if (st != MECHRT_OK)
        return st;
    for (int i = 0; i < n; i++)
        x[i] += r[i];
    return MECHRT_OK;
}

double mechrt_host_kkt_spread(const MechrtHostKkt *s, MechrtKktWeight w)
{
    return mechrt_host_sparse_spread(s->lu[w == MECHRT_KKT_MASS ? 0 : 1]);
}

void mechrt_host_kkt_counts(const MechrtHostKkt *s, long *fresh, long *refactored)
{
    *fresh = *refactored = 0;
    for (int w = 0; w < 3; w++) {
        long f, r;
        mechrt_host_sparse_counts(s->lu[w], &f, &r);
        *fresh += f;
        *refactored += r;
    }
}
