/* info_state.c - `info --at` / `--state`: the motion followed to a time, the rank drop there and the directions it frees.
 *
 * A mechanism meets its singular states by moving into them: the A02
 * chain of parallelograms, driven flat, has every loop fold at once, and
 * assembling directly at that time from the file's initial values lands on
 * some folded branch instead. So `--at T` assembles at t = 0, as run does,
 * and follows the motion to T with a secant predictor and minimum-norm
 * Newton (Deuflhard, Newton Methods for Nonlinear Problems, 2004, 5.1:
 * continuation with a step-size control), which goes through the singular
 * state where Newton with LU stops. There the rank of the holonomic rows is
 * compared with a reference, the rank at t = 0 or at nearby states, and the
 * rows that turned dependent are named. The directions the rows leave free
 * are a basis of the null space from a QR that keeps the coordinates in
 * order, one vector per coordinate the others no longer fix.
 */
#include "info_state.h"

#include "../base/arena.h"
#include "spqr_rank.h"
#include "../analysis/sparse.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Equal steps from t = 0 to t1, each halved at most 6 times; the last
   steps before t1 are FOLLOW_FINE times shorter. */
enum { FOLLOW_STEPS = 100, FOLLOW_HALVINGS = 6, FOLLOW_FINE = 16 };

/* The tolerances of the path followed. A coordinate's scale is 1 + the
   largest |q| of the state stepped from (metres, radians: whatever the
   file uses), so a mechanism drawn in mm or in km is judged alike. */
/* the first step's correction (no prediction yet), in scales */
#define FOLLOW_FIRST_JUMP 0.1
/* a later step's correction: half the predicted motion plus this, in
   scales (Newton leaves about tol_phi; this is well above it) */
#define FOLLOW_SLACK 1e-6
/* the end time is reached within this times max(1, |t_end|) (seconds) */
#define FOLLOW_T_EPS 1e-12
/* a step "equal" to h0 or to the rest within this fraction of itself */
#define FOLLOW_H_EPS 1e-9

static double dist_inf(const double *a, const double *b, int n)
{
    double d = 0.0;
    for (int i = 0; i < n; i++)
        d = fmax(d, fabs(a[i] - b[i]));
    return d;
}

/* The states reached so far, the last FOLLOW_ORDER + 1 of them, for the
   predictor: the polynomial through them, evaluated at the next time. */
enum { FOLLOW_ORDER = 3 };
typedef struct History {
    int n;                          /* states held, <= FOLLOW_ORDER + 1 */
    double t[FOLLOW_ORDER + 1];     /* newest last */
    double *q[FOLLOW_ORDER + 1];
} History;

static void history_push(History *h, double t, const double *q, int nq)
{
    if (h->n == FOLLOW_ORDER + 1) {
        double *oldest = h->q[0];
        memmove(h->q, h->q + 1, FOLLOW_ORDER * sizeof *h->q);
        memmove(h->t, h->t + 1, FOLLOW_ORDER * sizeof *h->t);
        h->q[FOLLOW_ORDER] = oldest;
        h->n--;
    }
    memcpy(h->q[h->n], q, (size_t)nq * sizeof *q);
    h->t[h->n++] = t;
}

/* pred = the Lagrange polynomial through the history at t: a cubic once
   four states are known, so the prediction errs by O(h^4) and the
   corrector lands within that of the state followed even where other
   branches cross it (a bifurcation), which minimum-norm Newton cannot
   tell apart. */
static void predict(const History *h, double t, int nq, double *pred)
{
    memset(pred, 0, (size_t)nq * sizeof *pred);
    for (int k = 0; k < h->n; k++) {
        double l = 1.0;
        for (int j = 0; j < h->n; j++)
            if (j != k)
                l *= (t - h->t[j]) / (h->t[k] - h->t[j]);
        for (int i = 0; i < nq; i++)
            pred[i] += l * h->q[k][i];
    }
}

/* One step to t from the newest state into trial; accepted when Newton
   converged and corrected the prediction by at most half the predicted
   motion (more looks like a jump to another branch). */
static bool follow_step(MechEval *me, MechrtSvd *w, const int *hrows, int nh, double t,
                        const History *hist, double *trial, double *pred,
                        const AnalysisOptions *opt, AssembleResult *res)
{
    int nq = me->nq;
    const double *q = hist->q[hist->n - 1];
    predict(hist, t, nq, pred);
    memcpy(trial, pred, (size_t)nq * sizeof *trial);
    MechrtKernels k = mech_eval_kernels(me);
    bool ok = w ? assemble_min_norm(&k, hrows, nh, t, trial, opt, w, res)
                : assemble_sparse(me, nh, t, trial, opt, res);
    if (!ok)
        return false;
    double corr = dist_inf(trial, pred, nq), moved = dist_inf(pred, q, nq), size = 0.0;
    for (int i = 0; i < nq; i++)
        size = fmax(size, fabs(q[i]));
    if (hist->n == 1)               /* the first step: no prediction to judge by */
        return corr <= FOLLOW_FIRST_JUMP * (1.0 + size);
    return corr <= 0.5 * moved + FOLLOW_SLACK * (1.0 + size);
}

/* Steps from the newest state of hist to t_end, h at a time (halved
   where refused, then grown back to h); false when a step stays refused. */
static bool follow_to(MechEval *me, MechrtSvd *w, const int *hrows, int nh, double t_end,
                      double h0, History *hist, double *trial, double *pred,
                      const AnalysisOptions *opt, AssembleResult *res, int *steps)
{
    int nq = me->nq;
    double h = h0, t = hist->t[hist->n - 1];
    while (fabs(t_end - t) > FOLLOW_T_EPS * fmax(1.0, fabs(t_end))) {
        double tn = fabs(t_end - t) <= fabs(h) * (1 + FOLLOW_H_EPS) ? t_end : t + h;
        if (follow_step(me, w, hrows, nh, tn, hist, trial, pred, opt, res)) {
            history_push(hist, tn, trial, nq);
            t = tn;
            ++*steps;
            if (fabs(h) < fabs(h0))
                h *= 2;             /* back towards the equal steps */
        } else if (fabs(h) > fabs(h0) / (1 << FOLLOW_HALVINGS) * (1 + FOLLOW_H_EPS)) {
            h /= 2;
        } else {
            return false;
        }
    }
    return true;
}

bool info_follow(MechEval *me, MechrtSvd *w, const int *hrows, int nh, double t1, double *q,
                 const AnalysisOptions *opt, AssembleResult *res, int *steps, double *q_near,
                 double *t_near)
{
    int nq = me->nq;
    History hist = {0};
    for (int k = 0; k <= FOLLOW_ORDER; k++)
        hist.q[k] = xmalloc(((size_t)nq + 1) * sizeof *hist.q[k]);
    double *trial = xmalloc(((size_t)nq + 1) * sizeof *trial);
    double *pred = xmalloc(((size_t)nq + 1) * sizeof *pred);
    history_push(&hist, 0.0, q, nq);
    /* equal steps to just before t1, then FOLLOW_ORDER + 1 short ones, and
       the state at t1 is their cubic's value there: Newton at a singular
       state would wander along the directions it frees by sqrt(eps)
       (rounding over a vanishing singular value), the extrapolation from
       regular states does not */
    double h0 = t1 / FOLLOW_STEPS, hf = h0 / FOLLOW_FINE;
    *steps = 0;
    bool ok = follow_to(me, w, hrows, nh, t1 - (FOLLOW_ORDER + 1) * hf, h0, &hist, trial, pred,
                        opt, res, steps)
              && follow_to(me, w, hrows, nh, t1 - hf, hf, &hist, trial, pred, opt, res, steps);
    if (ok) {
        memcpy(q_near, hist.q[hist.n - 1], (size_t)nq * sizeof *q_near);
        *t_near = hist.t[hist.n - 1];
        predict(&hist, t1, nq, q);
        ++*steps;
    } else {
        memcpy(q, hist.q[hist.n - 1], (size_t)nq * sizeof *q);
    }
    for (int k = 0; k <= FOLLOW_ORDER; k++)
        free(hist.q[k]);
    free(trial), free(pred);
    return ok;
}

/* The holonomic rows' nonzeros at q as a CSR matrix (buffers malloc'd). */
static SpqrRows holonomic_nz(MechEval *me, const double *q, double t, int **start, int **cols,
                             double **vals)
{
    const Kinematics *kin = me->kin;
    int nh = me->nh, nnz = kin->row_start[nh];
    double *all = xmalloc(((size_t)kin->nnz + 1) * sizeof *all);
    mech_eval_nz(me, q, t, NULL, all);
    *start = xmalloc(((size_t)nh + 1) * sizeof **start);
    *cols = xmalloc(((size_t)nnz + 1) * sizeof **cols);
    *vals = xmalloc(((size_t)nnz + 1) * sizeof **vals);
    memcpy(*start, kin->row_start, ((size_t)nh + 1) * sizeof **start);
    for (int e = 0; e < nnz; e++) {
        (*cols)[e] = kin->jac[e].col;
        (*vals)[e] = all[e];
    }
    free(all);
    return (SpqrRows){.m = nh, .n = me->nq, .start = *start, .cols = *cols, .vals = *vals};
}

int info_holonomic_rank(MechEval *me, MechrtSvd *w, const double *q, double t, double tol,
                        bool *red)
{
    int nq = me->nq, nh = me->nh, rank = -1;
    if (w) {
        double *jac = xmalloc(((size_t)me->nr * (size_t)nq + 1) * sizeof *jac);
        mech_eval(me, q, t, NULL, jac);
        MechrtSvdResult sv;
        if (mechrt_svd(w, jac, nh, nq, nq, tol, &sv)
            && svd_redundant_rows(w, jac, nh, nq, nq, sv.tol, 0, sv.rank, red) >= 0)
            rank = sv.rank;
        free(jac);
        return rank;
    }
    int *start, *cols;
    double *vals;
    SpqrRows a = holonomic_nz(me, q, t, &start, &cols, &vals);
    if (tol < 0) {
        int *rows = xmalloc(((size_t)nh + 1) * sizeof *rows);
        for (int r = 0; r < nh; r++)
            rows[r] = r;
        double *all = xmalloc(((size_t)me->kin->nnz + 1) * sizeof *all);
        mech_eval_nz(me, q, t, NULL, all);
        tol = mechrt_svd_default_tol(nh, nq, sparse_rank_sigma_max(me->kin, all, rows, nh, 1));
        free(rows), free(all);
    }
    rank = spqr_dependent_rows(&a, tol, red, 0, NULL);
    free(start), free(cols), free(vals);
    return rank;
}

double info_residual(MechEval *me, const double *q, double t)
{
    double *phi = xmalloc(((size_t)me->nh + 1) * sizeof *phi), r = 0.0;
    mech_eval(me, q, t, phi, NULL);
    for (int i = 0; i < me->nh; i++)
        r = fmax(r, fabs(phi[i]));
    free(phi);
    return r;
}

void info_state_finish(MechEval *me, InfoReport *rep, int ref_rank, const bool *ref_red)
{
    InfoState *st = &rep->state;
    int nh = rep->nh, nq = rep->nq;
    st->ref_rank = ref_rank > rep->rank ? ref_rank : rep->rank;
    st->drop = rep->rank >= 0 && ref_rank >= 0 ? st->ref_rank - rep->rank : -1;
    st->dependent = xmalloc(((size_t)nh + 1) * sizeof *st->dependent);
    for (int r = 0; r < nh && rep->rank >= 0; r++)
        if (rep->rows[r].redundant && !(ref_red && ref_red[r]))
            st->dependent[st->ndependent++] = r;
    st->null = xmalloc(((size_t)INFO_MAX_DIRECTIONS * (size_t)nq + 1) * sizeof *st->null);
    st->free_coord = xmalloc((INFO_MAX_DIRECTIONS + 1) * sizeof *st->free_coord);
    st->nnull = -1;
    if (rep->rank < 0)
        return;
    int *start, *cols;
    double *vals;
    SpqrRows a = holonomic_nz(me, rep->q, rep->t, &start, &cols, &vals);
    st->nnull = spqr_null_basis(&a, rep->rank_tol, INFO_MAX_DIRECTIONS, st->null, st->free_coord);
    st->nshown = st->nnull < INFO_MAX_DIRECTIONS ? st->nnull : INFO_MAX_DIRECTIONS;
    if (st->nshown < 0)
        st->nshown = 0;
    free(start), free(cols), free(vals);
}

double info_state_tolerance(MechEval *me, MechrtSvd *w, const double *q, double t)
{
    int nq = me->nq, nh = me->nh;
    double smax = 0.0;
    if (w) {
        double *jac = xmalloc(((size_t)me->nr * (size_t)nq + 1) * sizeof *jac);
        mech_eval(me, q, t, NULL, jac);
        MechrtSvdResult sv;
        if (mechrt_svd(w, jac, nh, nq, nq, -1, &sv))
            smax = sv.sigma_max;
        free(jac);
    } else {
        int *rows = xmalloc(((size_t)nh + 1) * sizeof *rows);
        double *all = xmalloc(((size_t)me->kin->nnz + 1) * sizeof *all);
        for (int r = 0; r < nh; r++)
            rows[r] = r;
        mech_eval_nz(me, q, t, NULL, all);
        smax = sparse_rank_sigma_max(me->kin, all, rows, nh, 1);
        free(rows), free(all);
    }
    return sqrt(DBL_EPSILON) * smax;
}
