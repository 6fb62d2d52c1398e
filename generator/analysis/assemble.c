/* assemble.c - minimum-norm Newton assembly on any set of holonomic rows.
 *
 * Phi and Phi_q come from kernels: an engine's, or the graph interpreter's
 * (mech_eval.c); the sparse path reads the graph's pattern.
 *
 * Minimum-norm Newton (Gauss-Newton through the pseudo-inverse; Ben-Israel
 * 1966, Deuflhard, Newton Methods for Nonlinear Problems, 4.4):
 *     dq = -pinv(Phi_q(q)) Phi(q),   q <- q + alpha dq
 * pinv from the SVD (runtime/host/svd.c) with singular values at or below
 * the rank tolerance dropped, or beyond the dense limit from the sparse QR
 * of Phi_q^T (sparse.c); one iteration serves both. With fewer rows than
 * coordinates this is the shortest step that zeroes the linearised rows, so
 * the iteration settles on the configuration nearest the start; with
 * redundant rows the dropped singular values are the dependent directions.
 * alpha is halved (at most 12 times) until the residual's 2-norm decreases.
 */
#include "assemble.h"

#include "../base/arena.h"
#include "../base/rng.h"
#include "sparse.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- minimum-norm Newton ---- */

/* Where the Newton direction comes from: the residual of the rows at a
   point and dq = -pinv(Phi_q) Phi at the last iterate. */
typedef struct NewtonPath {
    /* Phi of the rows at q: returns ||Phi||_2 (NaN or Inf if not finite),
       sets ||Phi||_inf and the model row where it is largest. iterate: q is
       the new iterate, whose Jacobian the next direction uses; else a
       trial point of the step halving. */
    double (*eval)(void *ctx, const double *q, bool iterate, double *inf, int *worst);
    /* The step at the last iterate into dq (nq); false when there is none.
       *rank: the rank of the rows' Jacobian seen by the solve. */
    bool (*direction)(void *ctx, double *dq, int *rank);
    void *ctx;
} NewtonPath;

/* The iterate with the smallest ||Phi||_2 so far: its norms and worst row.
   A failure ends there, not at the last iterate: a full step that found no
   descent may have carried Newton far off (Euler parameters grown without
   bound), and what is violated there says nothing about the mechanism. */
typedef struct BestIterate {
    double norm, inf;
    int worst;
} BestIterate;

static bool min_norm_newton(const NewtonPath *p, int nrows, int nq, double *q,
                            const AnalysisOptions *opt, AssembleResult *res)
{
    memset(res, 0, sizeof *res);
    res->step = -1.0;
    res->worst_row = -1;
    res->rank = -1;
    if (nrows == 0) {
        res->converged = true;
        return true;
    }
    double *dq = xcalloc((size_t)nq, sizeof *dq);
    double *trial = xcalloc((size_t)nq, sizeof *trial);
    double *bestq = xmalloc((size_t)nq * sizeof *bestq);
    memcpy(bestq, q, (size_t)nq * sizeof *bestq);
    double inf = 0.0;
    int worst = -1;
    double norm = p->eval(p->ctx, q, true, &inf, &worst);
    res->residual = inf;
    res->worst_row = worst;
    bool ok = false;
    double best = norm;
    BestIterate least = {norm, inf, worst};
    int improved = 0;       /* the iteration that last cut the best norm by 1 % */
    for (int iter = 0; isfinite(norm); iter++) {
        /* at least one step: a start that satisfies the rows only to
           tol_phi (placed by construction on a toggle, where rows vary
           quadratically) is polished until the step is small too */
        if (inf <= opt->tol_phi && res->step >= 0 && res->step <= opt->tol_dq) {
            ok = true;
            break;
        }
        if (norm < 0.99 * best) {
            best = norm;
            improved = iter;
        }
        if (opt->stall_iter > 0 && iter - improved >= opt->stall_iter)
            break;
        if (iter >= opt->max_iter || !p->direction(p->ctx, dq, &res->rank))
            break;
        double step = 0.0;
        for (int j = 0; j < nq; j++)
            step = fmax(step, fabs(dq[j]));
        /* step halving until the residual decreases (or is already small) */
        double alpha = 1.0, tnorm = NAN, tinf = 0.0;
        int tworst = -1;
        for (int h = 0; h <= 12; h++) {
            for (int j = 0; j < nq; j++)
                trial[j] = q[j] + alpha * dq[j];
            tnorm = p->eval(p->ctx, trial, false, &tinf, &tworst);
            if (isfinite(tnorm) && (tnorm < norm || tinf <= opt->tol_phi))
                break;
            alpha *= 0.5;
        }
        if (!isfinite(tnorm) || !(tnorm < norm || tinf <= opt->tol_phi))
            alpha = 1.0;    /* no descent along the Newton direction: take the full step */
        for (int j = 0; j < nq; j++)
            q[j] += alpha * dq[j];
        res->iterations = iter + 1;
        res->step = alpha * step;
        norm = p->eval(p->ctx, q, true, &inf, &worst);
        res->residual = isfinite(norm) ? inf : NAN;
        res->worst_row = worst;
        if (norm < least.norm || !isfinite(least.norm)) {
            least = (BestIterate){norm, inf, worst};
            memcpy(bestq, q, (size_t)nq * sizeof *bestq);
        }
    }
    if (!ok && isfinite(least.norm) && !(norm <= least.norm)) {
        memcpy(q, bestq, (size_t)nq * sizeof *bestq);
        res->residual = least.inf;
        res->worst_row = least.worst;
    }
    res->converged = ok;
    free(dq), free(trial), free(bestq);
    return ok;
}

/* ---- the dense direction: SVD of the selected rows ----
 *
 * The rows of any kernels: an engine's (run, sim and check assemble with
 * jit, aot or generic) or the graph's (info, mech_eval_kernels).
 */

typedef struct DenseRows {
    const MechrtKernels *k;
    const int *rows;        /* kernel rows; NULL: the first nrows */
    int nrows;
    double t, rank_tol;
    MechrtSvd *w;
    double *phi_all;        /* nh */
    double *jac;            /* nr x nq */
    double *J, *f;          /* the rows' Jacobian (nrows x nq) and Phi at the iterate */
    double *ftrial;         /* Phi at a trial point */
} DenseRows;

static int dense_row(const DenseRows *d, int i)
{
    return d->rows ? d->rows[i] : i;
}

static double dense_eval(void *ctx, const double *q, bool iterate, double *inf, int *worst)
{
    DenseRows *d = ctx;
    const MechrtKernels *k = d->k;
    size_t nq = (size_t)k->nq;
    double *f = iterate ? d->f : d->ftrial;
    k->phi(k->ctx, q, d->t, d->phi_all);
    if (iterate)
        k->jac(k->ctx, q, d->t, d->jac);
    double sum = 0.0;
    *inf = 0.0;
    *worst = -1;
    for (int i = 0; i < d->nrows; i++) {
        int r = dense_row(d, i);
        f[i] = d->phi_all[r];
        if (iterate)
            memcpy(d->J + (size_t)i * nq, d->jac + (size_t)r * nq, nq * sizeof *d->J);
        if (!isfinite(f[i])) {
            *worst = r;
            return NAN;
        }
        sum += f[i] * f[i];
        if (fabs(f[i]) > *inf || *worst < 0) {
            *inf = fabs(f[i]);
            *worst = r;
        }
    }
    return sqrt(sum);
}

static bool dense_direction(void *ctx, double *dq, int *rank)
{
    DenseRows *d = ctx;
    int nq = d->k->nq;
    MechrtSvdResult sv;
    if (!mechrt_svd(d->w, d->J, d->nrows, nq, nq, d->rank_tol, &sv))
        return false;
    *rank = sv.rank;
    mechrt_svd_pinv_solve(d->w, d->f, dq);
    for (int j = 0; j < nq; j++)
        dq[j] = -dq[j];
    return true;
}

bool assemble_min_norm(const MechrtKernels *k, const int *rows, int nrows, double t, double *q,
                       const AnalysisOptions *opt, MechrtSvd *w, AssembleResult *res)
{
    size_t nq = (size_t)k->nq, nr = (size_t)(k->nh + k->nv);
    MechrtSvd *own = !w && nrows > 0 ? mechrt_svd_new(nrows, k->nq) : NULL;
    DenseRows d = {
        .k = k, .rows = rows, .nrows = nrows, .t = t, .rank_tol = opt->rank_tol,
        .w = w ? w : own,
        .phi_all = xcalloc((size_t)k->nh + 1, sizeof *d.phi_all),
        .jac = xcalloc(nr * nq + 1, sizeof *d.jac),
        .J = xcalloc((size_t)nrows * nq + 1, sizeof *d.J),
        .f = xcalloc((size_t)nrows + 1, sizeof *d.f),
        .ftrial = xcalloc((size_t)nrows + 1, sizeof *d.ftrial),
    };
    NewtonPath path = {dense_eval, dense_direction, &d};
    bool ok = (nrows == 0 || d.w) && min_norm_newton(&path, nrows, k->nq, q, opt, res);
    mechrt_svd_free(own);
    free(d.phi_all), free(d.jac), free(d.J), free(d.f), free(d.ftrial);
    return ok;
}

/* ---- the sparse direction: QR of Phi_q^T ----
 *
 * With J^T = Q R (R: m x m upper triangular, from the row-wise QR of J^T,
 * whose rows are the columns of J), J = R^T Q^T and Q = J^T R^-1, so the
 * minimum-norm solution of J dq = -f is
 *     dq = Q R^-T (-f) = J^T y,   R^T R y = -f
 * (the seminormal equations; Bjoerck 1996, 6.6.5: accurate enough for a
 * Newton direction, and every iterate's residual is checked anyway).
 * Rows that depend on the ones before them (entries at or below the rank
 * tolerance where a pivot would be) are left out of the step.
 */

typedef struct SparseRows {
    MechEval *me;
    int nrows;              /* the first nrows holonomic rows */
    double t;
    const AnalysisOptions *opt;
    int *cstart, *crow, *cidx;  /* the rows' Jacobian by columns (CSC); cidx: entry of kin->jac */
    double *vals, *cval;    /* every nonzero at the last evaluation; one column's */
    double *phi, *y;
    int *all;               /* 0 .. nrows-1 */
} SparseRows;

static double sparse_eval(void *ctx, const double *q, bool iterate, double *inf, int *worst)
{
    SparseRows *s = ctx;
    (void)iterate;          /* one pass gives Phi and the nonzeros together */
    mech_eval_nz(s->me, q, s->t, s->phi, s->vals);
    double sum = 0.0;
    *inf = 0.0;
    *worst = -1;
    for (int i = 0; i < s->nrows; i++) {
        sum += s->phi[i] * s->phi[i];
        if (fabs(s->phi[i]) > *inf || *worst < 0) {
            *inf = fabs(s->phi[i]);
            *worst = i;
        }
    }
    return sqrt(sum);
}

static bool sparse_direction(void *ctx, double *dq, int *rank)
{
    SparseRows *s = ctx;
    const Kinematics *kin = s->me->kin;
    const AnalysisOptions *opt = s->opt;
    int nq = s->me->nq, nrows = s->nrows;
    const size_t fill_max = 50u * 1000u * 1000u;
    /* factor J^T row by row (its rows are J's columns) */
    double tol = opt->rank_tol >= 0
                     ? opt->rank_tol
                     : mechrt_svd_default_tol(nrows, nq, sparse_rank_sigma_max(kin, s->vals, s->all,
                                                                               nrows, opt->seed));
    SparseRank *qr = sparse_rank_new(nrows, tol, fill_max);
    bool good = true;
    for (int i = 0; i < nq && good; i++) {
        int k0 = s->cstart[i], k1 = s->cstart[i + 1];
        for (int k = k0; k < k1; k++)
            s->cval[k] = s->vals[s->cidx[k]];
        good = sparse_rank_add(qr, s->crow + k0, s->cval + k0, k1 - k0) >= 0;
    }
    *rank = sparse_rank_of(qr);
    for (int i = 0; i < nrows; i++)
        s->y[i] = -s->phi[i];
    if (good)
        sparse_rank_seminormal_solve(qr, nrows, s->y);
    sparse_rank_free(qr);
    if (!good)
        return false;
    for (int i = 0; i < nq; i++) {          /* dq = J^T y */
        double sum = 0.0;
        for (int k = s->cstart[i]; k < s->cstart[i + 1]; k++)
            sum += s->vals[s->cidx[k]] * s->y[s->crow[k]];
        dq[i] = sum;
    }
    return true;
}

bool assemble_sparse(MechEval *me, int nrows, double t, double *q,
                     const AnalysisOptions *opt, AssembleResult *res)
{
    const Kinematics *kin = me->kin;
    int nq = me->nq;
    /* the columns of the first nrows rows of J (CSC), fixed structure */
    int nnz = kin->row_start[nrows];
    SparseRows s = {
        .me = me, .nrows = nrows, .t = t, .opt = opt,
        .cstart = xcalloc((size_t)nq + 2, sizeof *s.cstart),
        .crow = xmalloc(((size_t)nnz + 1) * sizeof *s.crow),
        .cidx = xmalloc(((size_t)nnz + 1) * sizeof *s.cidx),
        .vals = xmalloc(((size_t)kin->nnz + 1) * sizeof *s.vals),
        .cval = xmalloc(((size_t)nnz + 1) * sizeof *s.cval),
        .phi = xmalloc(((size_t)me->nh + 1) * sizeof *s.phi),
        .y = xmalloc(((size_t)nrows + 1) * sizeof *s.y),
        .all = xmalloc(((size_t)nrows + 1) * sizeof *s.all),
    };
    for (int e = 0; e < nnz; e++)
        s.cstart[kin->jac[e].col + 2]++;
    for (int i = 0; i < nq; i++)
        s.cstart[i + 2] += s.cstart[i + 1];
    for (int e = 0; e < nnz; e++) {         /* rows ascending within each column */
        int k = s.cstart[kin->jac[e].col + 1]++;
        s.crow[k] = kin->jac[e].row;
        s.cidx[k] = e;
    }
    for (int i = 0; i < nrows; i++)
        s.all[i] = i;
    NewtonPath path = {sparse_eval, sparse_direction, &s};
    bool ok = min_norm_newton(&path, nrows, nq, q, opt, res);
    free(s.cstart), free(s.crow), free(s.cidx), free(s.vals), free(s.cval), free(s.phi),
        free(s.y), free(s.all);
    return ok;
}

/* ---- restarts from jittered guesses ----
 *
 * A stall (opt->stall_iter) is a stationary point of ||Phi|| that is no
 * solution, most often a guess symmetric about a line the mechanism cannot
 * lie on (every link on the x axis): the Gauss-Newton step keeps the
 * symmetry. Restarting from the guess jittered by 5 %, 10 %, 20 % ... of
 * its scale (its largest residual or value: one scale for lengths and
 * angles, which is enough to break a symmetry) breaks it; the jitter comes
 * from a fixed seed, so that every run repeats exactly. Only coordinates
 * the rows depend on are jittered: the others (a cart's position under
 * velocity-level rows alone) are initial values, not guesses, and the
 * minimum-norm step would never move them back.
 */
#define ASSEMBLE_RESTARTS 6
#define ASSEMBLE_SEED 20261125u

/* The rows being assembled, seen by the restarts. */
typedef struct RoughRows {
    int nq, nrows;
    /* Phi (nrows) and the rows' Jacobian (nrows x nq) at q */
    void (*eval)(void *ctx, const double *q, double *phi, double *jac);
    /* one minimum-norm Newton attempt from q */
    bool (*attempt)(void *ctx, double *q, AssembleResult *res);
    void *ctx;
} RoughRows;

/* The scale of the jitter, and which coordinates the rows depend on (a
   nonzero Jacobian column at q0 or at a probe point near it). */
static double rough_scale(const RoughRows *rr, const double *q0, bool *touched)
{
    size_t nq = (size_t)rr->nq, nrows = (size_t)rr->nrows;
    double *phi = xcalloc(nrows + 1, sizeof *phi), *jac = xcalloc(nrows * nq + 1, sizeof *jac);
    double *probe = xmalloc(nq * sizeof *probe);
    double scale = 1e-3;
    rr->eval(rr->ctx, q0, phi, jac);
    for (size_t i = 0; i < nrows; i++)
        if (isfinite(phi[i]))
            scale = fmax(scale, fabs(phi[i]));
    for (size_t j = 0; j < nq; j++)
        scale = fmax(scale, fabs(q0[j]));
    uint64_t seed = ~(uint64_t)ASSEMBLE_SEED;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < nrows; i++)
            for (size_t j = 0; j < nq; j++)
                touched[j] = touched[j] || jac[i * nq + j] != 0;
        for (size_t j = 0; j < nq; j++)
            probe[j] = q0[j] + 0.1 * scale * rng_symmetric(&seed);
        rr->eval(rr->ctx, probe, phi, jac);
    }
    free(phi), free(jac), free(probe);
    return scale;
}

static bool restart_loop(const RoughRows *rr, double *q, AssembleResult *res)
{
    size_t nq = (size_t)rr->nq;
    double *q0 = xmalloc(nq * sizeof *q0), *best = xmalloc(nq * sizeof *best);
    bool *touched = xcalloc(nq, sizeof *touched);
    memcpy(q0, q, nq * sizeof *q0);
    double scale = rough_scale(rr, q0, touched);
    uint64_t seed = ASSEMBLE_SEED;
    AssembleResult ar, best_ar = {0};
    int iterations = 0;
    bool ok = false;
    for (int attempt = 0; attempt <= ASSEMBLE_RESTARTS && !ok; attempt++) {
        double jitter = attempt == 0 ? 0 : 0.05 * scale * (double)(1 << (attempt - 1));
        for (size_t j = 0; j < nq; j++) {
            double u = rng_symmetric(&seed);
            q[j] = touched[j] ? q0[j] + jitter * u : q0[j];
        }
        ok = rr->attempt(rr->ctx, q, &ar);
        iterations += ar.iterations;
        if (ok || attempt == 0 || !(ar.residual >= best_ar.residual)) {
            best_ar = ar;
            memcpy(best, q, nq * sizeof *best);
        }
    }
    memcpy(q, best, nq * sizeof *best);
    *res = best_ar;
    res->iterations = iterations;
    free(q0), free(best), free(touched);
    return ok;
}

/* The kernels' holonomic rows (the first nh rows of their Jacobian). */
typedef struct KernelAttempt {
    const MechrtKernels *k;
    double t;
    const AnalysisOptions *opt;
    double *jac;            /* nr x nq */
} KernelAttempt;

static void kernel_rough_eval(void *ctx, const double *q, double *phi, double *jac)
{
    KernelAttempt *ka = ctx;
    ka->k->phi(ka->k->ctx, q, ka->t, phi);
    ka->k->jac(ka->k->ctx, q, ka->t, ka->jac);
    memcpy(jac, ka->jac, (size_t)ka->k->nh * (size_t)ka->k->nq * sizeof *jac);
}

static bool kernel_attempt(void *ctx, double *q, AssembleResult *res)
{
    KernelAttempt *ka = ctx;
    return assemble_min_norm(ka->k, NULL, ka->k->nh, ka->t, q, ka->opt, NULL, res);
}

bool assemble_restarting(const MechrtKernels *k, double t, double *q,
                         const AnalysisOptions *opt, AssembleResult *res)
{
    size_t nr = (size_t)(k->nh + k->nv);
    KernelAttempt ka = {k, t, opt, xcalloc(nr * (size_t)k->nq + 1, sizeof *ka.jac)};
    RoughRows rr = {k->nq, k->nh, kernel_rough_eval, kernel_attempt, &ka};
    bool ok = restart_loop(&rr, q, res);
    free(ka.jac);
    return ok;
}
