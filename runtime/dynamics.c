/* dynamics.c - forward and inverse dynamics of a constrained mechanism (null-space method).
 *
 * Forward dynamics solves the index-1 augmented system
 *     [M  Phi_q^T] [qdd   ]   [Q    ]
 *     [Phi_q   0 ] [lambda] = [gamma]
 * without forming it, by a null-space method that survives redundant rows
 * (Phi_q of rank r < nr: a parallelogram's third bar, or a singular
 * position where the rank drops):
 *  1. Phi_q = P^T L U Qc^T by Gaussian elimination with complete pivoting,
 *     stopped when the largest remaining entry is <= rank_tol * max|Phi_q|:
 *     rank-revealing in practice (Golub & Van Loan, 4th ed., 3.4.8), and the
 *     r pivot columns are the best-conditioned greedy choice of dependent
 *     coordinates (Wehage & Haug's generalized coordinate partitioning,
 *     1982, done by an LU). The rows eliminated last are the dependent ones.
 *  2. A particular solution qp of Phi_q qdd = gamma (free coordinates 0) and
 *     a null-space basis Z = Qc [-U11^-1 U12; I]. Complete pivoting keeps
 *     |U11^-1 U12| moderate even when the last pivot is small, so Z stays
 *     well conditioned near a rank drop.
 *  3. qdd = qp + Z x with (Z^T M Z) x = Z^T (Q - M qp): unique when M is
 *     positive definite on the null space of Phi_q, whatever lambda does.
 *  4. lambda from Phi_q^T lambda = Q - M qdd (consistent by step 3): a basic
 *     solution through U11^T and L11^T, then, with d = nr - r dependent
 *     rows, the component along the null space of Phi_q^T, [-K; I] with
 *     K = L11^-T L21^T, removed by a d x d normal-equation solve
 *     (K^T K + I, eigenvalues >= 1): the minimum-norm lambda.
 * Inverse dynamics is step 1 and 4 with the given qdd.
 *
 * The rank decision is made wherever the call is; an integrator's stages
 * lie off the constraint manifold by the step's error, where a redundant
 * row is independent to that error and a fresh decision would lock the
 * mechanism (a rank tolerance below the error) or drop a genuine row
 * (above it). So mechrt_dynamics_rows tells which rows the elimination
 * keeps at a state on the manifold, and MechrtDynOptions.active leaves the
 * others out (as zero rows, never pivoted on) for the stages of the step.
 *
 * Cost: the elimination visits the pivot row's nonzeros and keeps each
 * row's largest entry (a sparse Phi_q: about O(nr nq) per call, O(nr nq r)
 * dense); Z^T M Z over M's nonzeros, O(nnz(M) (nq - r) + nq (nq - r)^2). No square root is
 * needed (no library call: the runtime's rule).
 *
 * Workspace (MECHRT_DYN_WORKSPACE_LEN): a nr*nq | mass nq*nq | z nq*nq |
 * h nq*nq | kb nr*nr | gm nr*nr | force, cpiv, hpiv, v1, v2, v3 nq each |
 * g, phi, nu, rpiv, y, ypiv nr each.
 */
#include <math.h>

#include "mechrt.h"

typedef struct DynWork {
    int n, m;                   /* nq, nr */
    mechrt_real *a;             /* Phi_q, then its complete-pivoting LU */
    mechrt_real *mass, *z, *h;  /* M; null-space basis (rows); Z^T M Z */
    mechrt_real *kb, *gm;       /* K (r x d); K^T K + I (d x d) */
    mechrt_real *force, *cpiv, *hpiv, *v1, *v2, *v3;
    mechrt_real *g, *phi, *nu, *rpiv, *y, *ypiv;
    long mnz;                   /* M's nonzeros packed in kb.., -1: use M dense */
} DynWork;

/* Entry (i, j) of a row-major matrix with leading dimension ld. */
#define AT(p, i, j, ld) ((p)[(size_t)(i) * (size_t)(ld) + (size_t)(j)])

MechrtDynOptions mechrt_dyn_default_options(void)
{
    MechrtDynOptions o;
#ifdef MECHRT_REAL_FLOAT
    o.rank_tol = MECHRT_R(1e-4);
    o.pivot_tol = MECHRT_R(1e-5);
#else
    o.rank_tol = 1e-8;
    o.pivot_tol = 1e-12;
#endif
    o.baumgarte_alpha = 0;
    o.baumgarte_beta = 0;
    o.active = NULL;
    return o;
}

size_t mechrt_dynamics_workspace_size(int nq, int nr)
{
    size_t q, r, max = (size_t)-1, sum, part;

    if (nq < 1 || nr < 0)
        return 0;
    q = (size_t)nq;
    r = (size_t)nr;
    /* every product and sum of MECHRT_DYN_WORKSPACE_LEN, checked */
    if (q > max / 4 / q || (r != 0 && r > max / 4 / r) || (r != 0 && q > max / 4 / r))
        return 0;
    sum = r * q;
    part = 3u * q * q;
    if (part > max - sum)
        return 0;
    sum += part;
    part = 2u * r * r;
    if (part > max - sum)
        return 0;
    sum += part;
    if (q > (max - sum) / 12 || r > (max - sum - 6u * q) / 6)
        return 0;
    return MECHRT_DYN_WORKSPACE_LEN(nq, nr);
}

static bool dyn_finite(size_t n, const mechrt_real *v)
{
    size_t i;

    for (i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

/* Checks the arguments and carves the workspace. */
static MechrtStatus dyn_setup(const MechrtKernels *k, mechrt_real *work, size_t lwork,
                              DynWork *w)
{
    size_t n, m, need;

    if (!k || k->nq < 1 || k->nh < 0 || k->nv < 0 || !k->jac || !k->gamma || !k->mass
        || !k->force || !work)
        return MECHRT_EINVAL;
    need = mechrt_dynamics_workspace_size(k->nq, k->nh + k->nv);
    if (need == 0)
        return MECHRT_EINVAL;
    if (lwork < need)
        return MECHRT_EBADLEN;
    w->n = k->nq;
    w->m = k->nh + k->nv;
    n = (size_t)w->n;
    m = (size_t)w->m;
    w->a = work;
    w->mass = w->a + m * n;
    w->z = w->mass + n * n;
    w->h = w->z + n * n;
    w->kb = w->h + n * n;
    w->gm = w->kb + m * m;
    w->force = w->gm + m * m;
    w->cpiv = w->force + n;
    w->hpiv = w->cpiv + n;
    w->v1 = w->hpiv + n;
    w->v2 = w->v1 + n;
    w->v3 = w->v2 + n;
    w->g = w->v3 + n;
    w->phi = w->g + m;
    w->nu = w->phi + m;
    w->rpiv = w->nu + m;
    w->y = w->rpiv + m;
    w->ypiv = w->y + m;
    w->mnz = -1;
    return MECHRT_OK;
}

static void dyn_swap(mechrt_real *a, mechrt_real *b)
{
    mechrt_real t = *a;
    *a = *b;
    *b = t;
}

/* max |a_ij| over j >= k of row i (-1 without columns): the pivot
   search's row maxima, kept up to date instead of a full scan per step. */
static mechrt_real dyn_row_max(const DynWork *w, int i, int k)
{
    mechrt_real best = -1;
    int j;

    for (j = k; j < w->n; j++)
        if (MECHRT_FABS(AT(w->a, i, j, w->n)) > best)
            best = MECHRT_FABS(AT(w->a, i, j, w->n));
    return best;
}

/* Step k of the complete-pivoting elimination: the largest |a_ij|, i, j >= k,
   into (*p, *c), its magnitude returned; the first in row-major order, as a
   full scan would find it, from the row maxima rmax. */
static mechrt_real dyn_pivot_search(const DynWork *w, const mechrt_real *rmax, int k, int *p,
                                    int *c)
{
    mechrt_real best = -1;
    int i, j;

    *p = k;
    *c = k;
    for (i = k; i < w->m; i++)
        if (rmax[i] > best) {
            best = rmax[i];
            *p = i;
        }
    for (j = k; j < w->n; j++)
        if (MECHRT_FABS(AT(w->a, *p, j, w->n)) == best) {
            *c = j;
            break;
        }
    return best;
}

/* Rows k+1.. minus their multiple of pivot row k, over the pivot row's
   nonzeros only (listed in nz: Jacobians are sparse); rows touched get
   their maxima over the columns after k again. */
static void dyn_eliminate(DynWork *w, int k, mechrt_real *rmax, mechrt_real *nz)
{
    int m = w->m, n = w->n, i, j, len = 0, t;
    mechrt_real pivot = AT(w->a, k, k, n);

    for (j = k + 1; j < n; j++)
        if (AT(w->a, k, j, n) != 0)
            nz[len++] = (mechrt_real)j;
    for (i = k + 1; i < m; i++) {
        mechrt_real aik = AT(w->a, i, k, n), l = aik / pivot;
        AT(w->a, i, k, n) = l;
        if (l != 0)
            for (t = 0; t < len; t++) {
                j = (int)nz[t];
                AT(w->a, i, j, n) -= l * AT(w->a, k, j, n);
            }
        if (aik != 0)
            rmax[i] = dyn_row_max(w, i, k + 1);
    }
}

/* P Phi_q Qc = L U in place (LAPACK-style interchanges: at step k row k
   with rpiv[k], column k with cpiv[k]), stopped at the first pivot
   <= rank_tol * max|a_ij|. Returns the rank r; *ratio = smallest pivot /
   max|a_ij| (1 without rows or with a zero matrix). Scratch: kb holds the
   row maxima (m), h the pivot row's nonzero columns (n); both are free
   until the null-space steps. */
static int dyn_factor(DynWork *w, mechrt_real rank_tol, mechrt_real *ratio)
{
    int m = w->m, n = w->n, kmax = m < n ? m : n, i, j, k, p, c;
    mechrt_real amax = 0, thresh, *rmax = w->kb;

    for (i = 0; i < m; i++) {
        rmax[i] = dyn_row_max(w, i, 0);
        if (rmax[i] > amax)
            amax = rmax[i];
    }
    *ratio = 1;
    thresh = rank_tol * amax;
    for (k = 0; k < kmax; k++) {
        mechrt_real best = dyn_pivot_search(w, rmax, k, &p, &c);
        if (!(best > thresh) || best == 0)
            break;
        if (best / amax < *ratio)
            *ratio = best / amax;
        w->rpiv[k] = (mechrt_real)p;
        w->cpiv[k] = (mechrt_real)c;
        if (p != k) {
            for (j = 0; j < n; j++)
                dyn_swap(&AT(w->a, k, j, n), &AT(w->a, p, j, n));
            dyn_swap(&rmax[k], &rmax[p]);
        }
        if (c != k)
            for (i = 0; i < m; i++)
                dyn_swap(&AT(w->a, i, k, n), &AT(w->a, i, c, n));
        dyn_eliminate(w, k, rmax, w->h);
    }
    return k;
}

/* x (n, permuted order) back into coordinate order: x <- Qc x. */
static void dyn_unpermute_cols(const DynWork *w, int r, mechrt_real *x)
{
    int k;

    for (k = r - 1; k >= 0; k--)
        if ((int)w->cpiv[k] != k)
            dyn_swap(&x[k], &x[(int)w->cpiv[k]]);
}

/* x[0..r) <- U11^-1 x[0..r) (back substitution). */
static void dyn_solve_u(const DynWork *w, int r, mechrt_real *x)
{
    int i, j;

    for (i = r - 1; i >= 0; i--) {
        mechrt_real s = x[i];
        for (j = i + 1; j < r; j++)
            s -= AT(w->a, i, j, w->n) * x[j];
        x[i] = s / AT(w->a, i, i, w->n);
    }
}

/* g <- L^-1 P g (all m rows; L unit lower with r nontrivial columns).
   Returns max |g_i| over the dependent rows i >= r. */
static mechrt_real dyn_solve_l(const DynWork *w, int r, mechrt_real *g)
{
    mechrt_real worst = 0;
    int i, j, k;

    for (k = 0; k < r; k++)
        if ((int)w->rpiv[k] != k)
            dyn_swap(&g[k], &g[(int)w->rpiv[k]]);
    for (i = 1; i < w->m; i++) {
        mechrt_real s = g[i];
        for (j = 0; j < i && j < r; j++)
            s -= AT(w->a, i, j, w->n) * g[j];
        g[i] = s;
        if (i >= r && MECHRT_FABS(s) > worst)
            worst = MECHRT_FABS(s);
    }
    if (r == 0)
        for (i = 0; i < w->m; i++)
            if (MECHRT_FABS(g[i]) > worst)
                worst = MECHRT_FABS(g[i]);
    return worst;
}

/* The null-space basis: row f - r of w->z is Qc [-U11^-1 U12 e_f; e_f]
   for each free column f >= r. */
static void dyn_null_basis(const DynWork *w, int r)
{
    int n = w->n, f, i;

    for (f = r; f < n; f++) {
        mechrt_real *zf = w->z + (size_t)(f - r) * (size_t)n;
        for (i = 0; i < n; i++)
            zf[i] = 0;
        for (i = 0; i < r; i++)
            zf[i] = -AT(w->a, i, f, n);
        dyn_solve_u(w, r, zf);
        zf[f] = 1;
        dyn_unpermute_cols(w, r, zf);
    }
}

/* M's nonzeros, row by row, as (i n + j, m_ij) pairs into kb and gm (2 m^2
   reals, free from the end of dyn_factor until dyn_min_norm) when they fit:
   a mass matrix is mostly zeros (diagonal for planar bodies about their
   centres), and dyn_reduced multiplies by it n - r times. */
static void dyn_mass_pack(DynWork *w)
{
    size_t n = (size_t)w->n, cap = 2u * (size_t)w->m * (size_t)w->m, cnt = 0, i;

    w->mnz = -1;
    for (i = 0; i < n * n; i++)
        if (w->mass[i] != 0)
            cnt++;
    if (2u * cnt > cap || (size_t)(mechrt_real)(n * n) != n * n)
        return;     /* no room, or an index a float cannot hold */
    cnt = 0;
    for (i = 0; i < n * n; i++)
        if (w->mass[i] != 0) {
            w->kb[2u * cnt] = (mechrt_real)i;
            w->kb[2u * cnt + 1u] = w->mass[i];
            cnt++;
        }
    w->mnz = (long)cnt;
}

/* y = M x (n): from the packed nonzeros when there are, summed in the same
   order as the dense rows (the zeros add nothing). */
static void dyn_mass_times(const DynWork *w, const mechrt_real *x, mechrt_real *y)
{
    int i, j;
    long t;

    if (w->mnz >= 0) {
        for (i = 0; i < w->n; i++)
            y[i] = 0;
        for (t = 0; t < w->mnz; t++) {
            long ij = (long)w->kb[2 * t];
            y[ij / w->n] += w->kb[2 * t + 1] * x[ij % w->n];
        }
        return;
    }
    for (i = 0; i < w->n; i++) {
        mechrt_real s = 0;
        for (j = 0; j < w->n; j++)
            s += AT(w->mass, i, j, w->n) * x[j];
        y[i] = s;
    }
}

static mechrt_real dyn_dot(int n, const mechrt_real *x, const mechrt_real *y)
{
    mechrt_real s = 0;
    int i;

    for (i = 0; i < n; i++)
        s += x[i] * y[i];
    return s;
}

/* qdd = qp + Z x, (Z^T M Z) x = Z^T (Q - M qp); qp in qdd on entry. */
static MechrtStatus dyn_reduced(const DynWork *w, int r, mechrt_real pivot_tol,
                                mechrt_real *qdd, int *sing_index)
{
    int n = w->n, d = n - r, a, b, i;
    MechrtStatus st;

    if (d == 0)
        return MECHRT_OK;
    dyn_mass_times(w, qdd, w->v1);
    for (i = 0; i < n; i++)
        w->v1[i] = w->force[i] - w->v1[i];                  /* Q - M qp */
    for (b = 0; b < d; b++) {
        const mechrt_real *zb = w->z + (size_t)b * (size_t)n;
        dyn_mass_times(w, zb, w->v2);
        for (a = 0; a < d; a++)
            AT(w->h, a, b, d) = dyn_dot(n, w->z + (size_t)a * (size_t)n, w->v2);
        w->v3[b] = dyn_dot(n, zb, w->v1);
    }
    st = mechrt_lu_factor(d, w->h, d, w->hpiv, pivot_tol, sing_index);
    if (st != MECHRT_OK)
        return st;
    mechrt_lu_solve(d, w->h, d, w->hpiv, w->v3);
    for (b = 0; b < d; b++)
        for (i = 0; i < n; i++)
            qdd[i] += w->v3[b] * AT(w->z, b, i, n);
    return MECHRT_OK;
}

/* Removes from the basic solution y (y[r..m) = 0 on entry) its component
   along the null space of Phi_q^T, [-K; I] (permuted rows), K = L11^-T L21^T:
   y <- [y_B - K c; c] with (K^T K + I) c = K^T y_B. */
static MechrtStatus dyn_min_norm(const DynWork *w, int r)
{
    int m = w->m, n = w->n, d = m - r, i, j, c;
    MechrtStatus st;

    if (d == 0)
        return MECHRT_OK;
    for (c = 0; c < d; c++)        /* column c of K: L11^T k = L21(c, :)^T */
        for (j = r - 1; j >= 0; j--) {
            mechrt_real s = AT(w->a, r + c, j, n);
            for (i = j + 1; i < r; i++)
                s -= AT(w->a, i, j, n) * AT(w->kb, i, c, d);
            AT(w->kb, j, c, d) = s;
        }
    for (i = 0; i < d; i++) {
        mechrt_real s = 0;
        for (j = 0; j < d; j++) {
            mechrt_real e = i == j ? MECHRT_R(1.0) : MECHRT_R(0.0);
            for (c = 0; c < r; c++)
                e += AT(w->kb, c, i, d) * AT(w->kb, c, j, d);
            AT(w->gm, i, j, d) = e;
        }
        for (c = 0; c < r; c++)
            s += AT(w->kb, c, i, d) * w->y[c];
        w->y[r + i] = s;
    }
    st = mechrt_lu_factor(d, w->gm, d, w->ypiv, MECHRT_R(0.0), NULL);
    if (st != MECHRT_OK)
        return st;
    mechrt_lu_solve(d, w->gm, d, w->ypiv, w->y + r);
    for (c = 0; c < r; c++)
        for (i = 0; i < d; i++)
            w->y[c] -= AT(w->kb, c, i, d) * w->y[r + i];
    return MECHRT_OK;
}

/* lambda from Phi_q^T lambda = Q - M qdd with the factors in w (rank r),
   minimum-norm; *residual = max |Phi_q^T lambda - (Q - M qdd)| over the
   free columns (the part no lambda carries). */
static MechrtStatus dyn_lambda(const DynWork *w, int r, const mechrt_real *qdd,
                               mechrt_real *lambda, mechrt_real *residual)
{
    int n = w->n, m = w->m, i, j, k;
    mechrt_real *s = w->v2;
    MechrtStatus st;

    dyn_mass_times(w, qdd, w->v1);
    for (i = 0; i < n; i++)
        s[i] = w->force[i] - w->v1[i];
    for (k = 0; k < r; k++)                 /* s <- Qc^T s */
        if ((int)w->cpiv[k] != k)
            dyn_swap(&s[k], &s[(int)w->cpiv[k]]);
    for (j = 0; j < r; j++) {               /* U11^T w = s_B, w in s[0..r) */
        mechrt_real v = s[j];
        for (i = 0; i < j; i++)
            v -= AT(w->a, i, j, n) * s[i];
        s[j] = v / AT(w->a, j, j, n);
    }
    *residual = 0;
    for (j = r; j < n; j++) {               /* U12^T w - s_N: 0 when consistent */
        mechrt_real v = s[j];
        for (i = 0; i < r; i++)
            v -= AT(w->a, i, j, n) * s[i];
        if (MECHRT_FABS(v) > *residual || v != v)
            *residual = MECHRT_FABS(v);
    }
    for (j = r - 1; j >= 0; j--) {          /* L11^T y_B = w */
        mechrt_real v = s[j];
        for (i = j + 1; i < r; i++)
            v -= AT(w->a, i, j, n) * w->y[i];
        w->y[j] = v;
    }
    for (i = r; i < m; i++)
        w->y[i] = 0;
    st = dyn_min_norm(w, r);
    if (st != MECHRT_OK)
        return st;
    for (k = r - 1; k >= 0; k--)            /* lambda = P^T y */
        if ((int)w->rpiv[k] != k)
            dyn_swap(&w->y[k], &w->y[(int)w->rpiv[k]]);
    for (i = 0; i < m; i++)
        lambda[i] = w->y[i];
    return dyn_finite((size_t)m, lambda) ? MECHRT_OK : MECHRT_ENOTFINITE;
}

/* Rows left out (opts->active) become zero rows, which the elimination
   never pivots on: dropped, with lambda 0. */
static void dyn_drop_rows(const MechrtDynOptions *o, const DynWork *w, bool gamma)
{
    int i, j;

    if (!o->active)
        return;
    for (i = 0; i < w->m; i++)
        if (!o->active[i]) {
            for (j = 0; j < w->n; j++)
                AT(w->a, i, j, w->n) = 0;
            if (gamma)
                w->g[i] = 0;
        }
}

/* M, Q and Phi_q at the state, checked finite; gamma too when want_gamma
   (stabilised when Baumgarte is on). */
static MechrtStatus dyn_eval(const MechrtKernels *k, const MechrtDynOptions *o, const DynWork *w,
                             const mechrt_real *q, const mechrt_real *qd, mechrt_real t,
                             bool want_gamma)
{
    size_t n = (size_t)w->n, m = (size_t)w->m;
    bool stab = want_gamma && (o->baumgarte_alpha != 0 || o->baumgarte_beta != 0);
    int i;

    k->mass(k->ctx, q, w->mass);
    k->force(k->ctx, q, qd, t, w->force);
    if (m > 0 && want_gamma && k->all) {
        k->all(k->ctx, q, qd, t, w->phi, w->a, w->nu, w->g);
    } else if (m > 0) {
        k->jac(k->ctx, q, t, w->a);
        if (want_gamma)
            k->gamma(k->ctx, q, qd, t, w->g);
        if (stab && k->nh > 0 && k->phi)
            k->phi(k->ctx, q, t, w->phi);
        if (stab && k->nu)
            k->nu(k->ctx, q, t, w->nu);
        if (stab && (!k->nu || (k->nh > 0 && !k->phi)))
            return MECHRT_EINVAL;
    }
    if (!dyn_finite(n * n, w->mass) || !dyn_finite(n, w->force) || !dyn_finite(m * n, w->a)
        || (want_gamma && !dyn_finite(m, w->g)))
        return MECHRT_ENOTFINITE;
    if (stab) {
        mechrt_real two_a = MECHRT_R(2.0) * o->baumgarte_alpha;
        mechrt_real b2 = o->baumgarte_beta * o->baumgarte_beta;
        for (i = 0; i < w->m; i++) {
            mechrt_real drift = dyn_dot(w->n, w->a + (size_t)i * n, qd) - w->nu[i];
            w->g[i] -= two_a * drift + (i < k->nh ? b2 * w->phi[i] : MECHRT_R(0.0));
        }
        if (!dyn_finite(m, w->g))
            return MECHRT_ENOTFINITE;
    }
    dyn_drop_rows(o, w, want_gamma);
    return MECHRT_OK;
}

static void dyn_report_clear(MechrtDynReport *r)
{
    if (!r)
        return;
    r->rank = 0;
    r->redundant = 0;
    r->pivot_ratio = 1;
    r->residual = 0;
    r->sing_index = -1;
}

MechrtStatus mechrt_forward_dynamics(const MechrtKernels *k, const MechrtDynOptions *opts,
                                     const mechrt_real *q, const mechrt_real *qd,
                                     mechrt_real t, mechrt_real *qdd, mechrt_real *lambda,
                                     mechrt_real *work, size_t lwork, MechrtDynReport *report)
{
    MechrtDynOptions o = opts ? *opts : mechrt_dyn_default_options();
    MechrtStatus st;
    DynWork w;
    mechrt_real ratio, inconsistency, residual;
    int r, i, sing = -1;

    dyn_report_clear(report);
    if (!q || !qd || !qdd)
        return MECHRT_EINVAL;
    st = dyn_setup(k, work, lwork, &w);
    if (st != MECHRT_OK)
        return st;
    st = dyn_eval(k, &o, &w, q, qd, t, true);
    if (st != MECHRT_OK)
        return st;
    r = dyn_factor(&w, o.rank_tol, &ratio);
    dyn_mass_pack(&w);      /* until dyn_lambda's dyn_min_norm */
    inconsistency = dyn_solve_l(&w, r, w.g);
    for (i = 0; i < w.n; i++)
        qdd[i] = i < r ? w.g[i] : MECHRT_R(0.0);
    dyn_solve_u(&w, r, qdd);
    dyn_unpermute_cols(&w, r, qdd);        /* qp */
    dyn_null_basis(&w, r);
    st = dyn_reduced(&w, r, o.pivot_tol, qdd, &sing);
    if (report) {
        report->rank = r;
        report->redundant = w.m - r;
        report->pivot_ratio = ratio;
        report->residual = inconsistency;
        report->sing_index = sing;
    }
    if (st != MECHRT_OK)
        return st;
    if (!dyn_finite((size_t)w.n, qdd))
        return MECHRT_ENOTFINITE;
    if (!lambda)
        return MECHRT_OK;
    return dyn_lambda(&w, r, qdd, lambda, &residual);
}

MechrtStatus mechrt_inverse_dynamics(const MechrtKernels *k, const MechrtDynOptions *opts,
                                     const mechrt_real *q, const mechrt_real *qd,
                                     const mechrt_real *qdd, mechrt_real t, mechrt_real *lambda,
                                     mechrt_real *work, size_t lwork, MechrtDynReport *report)
{
    MechrtDynOptions o = opts ? *opts : mechrt_dyn_default_options();
    MechrtStatus st;
    DynWork w;
    mechrt_real ratio, residual = 0;
    int r;

    dyn_report_clear(report);
    if (!q || !qd || !qdd || !lambda)
        return MECHRT_EINVAL;
    st = dyn_setup(k, work, lwork, &w);
    if (st != MECHRT_OK)
        return st;
    if (!dyn_finite((size_t)w.n, qdd))
        return MECHRT_ENOTFINITE;
    st = dyn_eval(k, &o, &w, q, qd, t, false);
    if (st != MECHRT_OK)
        return st;
    r = dyn_factor(&w, o.rank_tol, &ratio);
    st = dyn_lambda(&w, r, qdd, lambda, &residual);
    if (report) {
        report->rank = r;
        report->redundant = w.m - r;
        report->pivot_ratio = ratio;
        report->residual = residual;
    }
    return st;
}

MechrtStatus mechrt_dynamics_rows(const MechrtKernels *k, const MechrtDynOptions *opts,
                                  const mechrt_real *q, mechrt_real t, unsigned char *active,
                                  mechrt_real *work, size_t lwork, MechrtDynReport *report)
{
    MechrtDynOptions o = opts ? *opts : mechrt_dyn_default_options();
    MechrtStatus st;
    DynWork w;
    mechrt_real ratio;
    int r, i, kk;

    dyn_report_clear(report);
    if (!q || !active)
        return MECHRT_EINVAL;
    st = dyn_setup(k, work, lwork, &w);
    if (st != MECHRT_OK)
        return st;
    if (w.m > 0)
        k->jac(k->ctx, q, t, w.a);
    if (!dyn_finite((size_t)w.m * (size_t)w.n, w.a))
        return MECHRT_ENOTFINITE;
    r = dyn_factor(&w, o.rank_tol, &ratio);
    /* row i of P Phi_q is original row perm[i]: the interchanges replayed */
    for (i = 0; i < w.m; i++)
        w.y[i] = (mechrt_real)i;
    for (kk = 0; kk < r; kk++)
        if ((int)w.rpiv[kk] != kk)
            dyn_swap(&w.y[kk], &w.y[(int)w.rpiv[kk]]);
    for (i = 0; i < w.m; i++)
        active[(int)w.y[i]] = (unsigned char)(i < r);
    if (report) {
        report->rank = r;
        report->redundant = w.m - r;
        report->pivot_ratio = ratio;
    }
    return MECHRT_OK;
}
