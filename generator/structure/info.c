/* info.c - the `info` report: counts, assembly, ranks, redundant rows, singularity, integrability.
 *
 * Mobility by the count (Gruebler-Kutzbach in coordinate form) is
 * nq - nh - nv; the truth is nq - rank(Phi_q), the rank taken by SVD at the
 * assembled configuration (Nikravesh, Computer-Aided Analysis of Mechanical
 * Systems, 1988, 3.4 and 4.6; Haug, Computer-Aided Kinematics and Dynamics,
 * 1989, 3.3). Where they differ some rows are redundant: row i is redundant
 * when it depends on rows 0..i-1 (svd_redundant_rows), so the first rows of
 * a file are the ones kept and the report names the late duplicate.
 *
 * A rank deficiency can be permanent (a redundant link, like the third crank
 * of a parallelogram) or belong to the configuration (a dead-centre or
 * toggle position). To tell them apart the rows without drivers are
 * assembled again from a few random perturbations of the configuration
 * (minimum-norm Newton lands on nearby generic configurations) and their
 * rank there, the generic rank, is compared with the rank here.
 *
 * Beyond the dense limit (`--linear sparse`, or auto above 100
 * coordinates) the ranks and redundant rows come from SuiteSparseQR
 * (spqr_rank.c) with the same definition. `--at` and `--state` take all of
 * this at a given state (info_state.c).
 */
#include "info.h"

#include "../base/arena.h"
#include "../base/rng.h"
#include "../base/strbuf.h"
#include "../analysis/assemble_t0.h"
#include "info_state.h"
#include "../analysis/sparse.h"
#include "spqr_rank.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A condition number above this is reported as near-singular. */
static const double NEAR_SINGULAR_COND = 1e8;

const char *const info_singularity_names[] = {"none", "position", "drivers", "permanent", "unknown"};

/* What each kind removes is its joints.def row count (revolute 2, prismatic
   2, weld 3, the others 1: the textbook table, which test_info checks), so
   a new kind needs no case here. */
int info_textbook_rows(JointKind kind, bool *velocity)
{
    *velocity = joint_info[kind].level == LEVEL_VELOCITY;
    return joint_info[kind].rows;
}

/* Copies the listed rows of jac (nq columns) into out. */
static void pick_rows(const double *jac, int nq, const int *rows, int n, double *out)
{
    for (int i = 0; i < n; i++)
        memcpy(out + (size_t)i * (size_t)nq, jac + (size_t)rows[i] * (size_t)nq,
               (size_t)nq * sizeof *out);
}

static int rank_of(MechrtSvd *w, const double *a, int m, int nq, double tol)
{
    MechrtSvdResult r;
    return mechrt_svd(w, a, m, nq, nq, tol, &r) ? r.rank : -1;
}

/* A random configuration near q: each coordinate moved by up to 20 % of its
   size (at least 2 % of the largest), so angles and lengths both move. */
static void perturb(const double *q, int nq, uint64_t *state, double *qs)
{
    double size = 0.0;
    for (int i = 0; i < nq; i++)
        size = fmax(size, fabs(q[i]));
    if (size == 0.0)
        size = 1.0;
    for (int i = 0; i < nq; i++) {
        double u = rng_symmetric(state);
        qs[i] = q[i] + 0.2 * u * fmax(fabs(q[i]), 0.1 * size);
    }
}

/* Rank of the undriven holonomic rows at configurations assembled from random
   perturbations of q; -1 when none assembled. */
static int generic_rank(MechEval *me, const int *rows, int nrows, const double *q, double t,
                        const AnalysisOptions *opt, MechrtSvd *w)
{
    int nq = me->nq, best = -1;
    double *qs = xmalloc((size_t)nq * sizeof *qs);
    double *jac = xmalloc((size_t)me->nr * (size_t)nq * sizeof *jac + 1);
    double *sub = xmalloc((size_t)nrows * (size_t)nq * sizeof *sub + 1);
    uint64_t state = opt->seed * 2654435761u + 1;
    for (int s = 0; s < opt->generic_samples; s++) {
        perturb(q, nq, &state, qs);
        AssembleResult ar;
        MechrtKernels k = mech_eval_kernels(me);
        if (!assemble_min_norm(&k, rows, nrows, t, qs, opt, w, &ar))
            continue;
        mech_eval(me, qs, t, NULL, jac);
        pick_rows(jac, nq, rows, nrows, sub);
        int r = rank_of(w, sub, nrows, nq, opt->rank_tol);
        if (r > best)
            best = r;
    }
    free(qs), free(jac), free(sub);
    return best;
}

/* The velocity rows without drivers, together with the holonomic rows
   without drivers, at the configuration and at a few others assembled on
   those holonomic rows at nearby times. */
static bool system_test(Model *m, MechEval *me, InfoReport *rep, const int *undriven, int nu,
                        int nuh, const AnalysisOptions *opt, MechrtSvd *w, Diag *diag)
{
    int nq = m->nq;
    if (nu == nuh) {
        rep->system.note = strdup(m->nv ? "every velocity-level row is a driver" : "no velocity-level rows");
        return true;
    }
    int cap = 1 + opt->generic_samples, np = 0;
    double *points = xmalloc((size_t)cap * (size_t)nq * sizeof *points);
    double *times = xmalloc((size_t)cap * sizeof *times);
    if (rep->assembled) {
        memcpy(points, rep->q, (size_t)nq * sizeof *points);
        times[np++] = rep->t;
    }
    uint64_t state = opt->seed * 40503u + 3;
    for (int s = 0; w && s < opt->generic_samples; s++) {
        double *qs = points + (size_t)np * (size_t)nq;
        perturb(rep->q, nq, &state, qs);
        double ts = rep->t + 0.5 * rng_symmetric(&state);
        AssembleResult ar;
        MechrtKernels k = mech_eval_kernels(me);
        if (assemble_min_norm(&k, undriven, nuh, ts, qs, opt, w, &ar))
            times[np++] = ts;
    }
    bool ok = involutivity_analyse(m, undriven, nu, points, times, np, &rep->system, diag);
    free(points), free(times);
    return ok;
}

static void list_rows(StrBuf *sb, const InfoReport *rep, bool redundant_only)
{
    int n = 0;
    for (int r = 0; r < rep->nr; r++)
        if (!redundant_only || rep->rows[r].redundant)
            sb_printf(sb, "%s%s", n++ ? ", " : "", rep->model->rows[r].name);
}

static const char *plural(int n, const char *one, const char *many)
{
    return n == 1 ? one : many;
}

static char *make_verdict(const InfoReport *rep)
{
    StrBuf sb;
    sb_init(&sb);
    int drivers = rep->nh_drivers + rep->nv_drivers;
    if (!rep->assembled)
        sb_printf(&sb, "assembly failed (residual %.3g): ranks are those of the best point found; ",
                  rep->assembly.residual);
    sb_printf(&sb, "the count says %d DOF", rep->dof);
    if (rep->nv > 0)
        sb_printf(&sb, " (%d coordinates - %d holonomic - %d velocity-level rows)",
                  rep->nq, rep->nh, rep->nv);
    if (rep->rank < 0) {
        sb_puts(&sb, "; the rank was not computed");
        return sb_take(&sb);
    }
    const char *what = rep->nv > 0 ? "the holonomic rows of the Jacobian have" : "the Jacobian has";
    if (rep->nh == 0)
        sb_puts(&sb, "; no holonomic rows");
    else if (rep->rank == rep->nh)
        sb_printf(&sb, "; %s full rank %d", what, rep->rank);
    else
        sb_printf(&sb, "; %s rank %d of %d", what, rep->rank, rep->nh);
    if (rep->nv > 0)
        sb_printf(&sb, "%s all %d rows rank %d", rep->nh ? " and" : ",", rep->nr, rep->rank_all);
    if (rep->singularity == SING_POSITION || rep->singularity == SING_DRIVERS)
        sb_printf(&sb, ": at this singular position it moves, to first order, with %d DOF",
                  rep->dof_rank);
    else
        sb_printf(&sb, ": the mechanism moves with %d DOF", rep->dof_rank);
    if (rep->dof_rank == 0)
        sb_puts(&sb, drivers ? " (fully driven)" : " (a structure)");
    int nred = rep->nredundant + rep->nredundant_velocity;
    if (nred > 0) {
        sb_printf(&sb, ", %s ", plural(nred, "row", "rows"));
        list_rows(&sb, rep, true);
        sb_printf(&sb, " %s redundant", plural(nred, "is", "are"));
    }
    if (drivers)
        sb_printf(&sb, "; without its %d %s: %d DOF by the count, %d by the rank", drivers,
                  plural(drivers, "driver", "drivers"), rep->mobility, rep->mobility_rank);
    return sb_take(&sb);
}

static char *make_singular(const InfoReport *rep, int nuh)
{
    StrBuf sb;
    sb_init(&sb);
    if (rep->rank < 0) {
        sb_puts(&sb, "not computed");
        return sb_take(&sb);
    }
    if (rep->nh == 0) {
        sb_puts(&sb, "no holonomic rows: nothing to be singular");
        return sb_take(&sb);
    }
    if (rep->rank == rep->nh && !rep->dense) {
        sb_puts(&sb, "full row rank (the condition number is not computed beyond the dense limit)");
        return sb_take(&sb);
    }
    if (rep->rank == rep->nh) {
        if (rep->cond > NEAR_SINGULAR_COND)
            sb_printf(&sb, "near-singular (condition number %.3g: close to a dead-centre, toggle "
                      "or branch point)", rep->cond);
        else
            sb_puts(&sb, "regular");
        return sb_take(&sb);
    }
    sb_printf(&sb, "singular: rank-deficient by %d", rep->nh - rep->rank);
    if (rep->singularity == SING_POSITION && rep->generic_rank < 0)
        sb_printf(&sb, "; a singular position: the rows have rank %d here but %d at t = 0 or "
                  "just before (a dead-centre, toggle or branch point)", rep->rank,
                  rep->state.ref_rank);
    else if (rep->singularity == SING_POSITION)
        sb_printf(&sb, "; a singular position: without drivers the rows have rank %d here but %d "
                  "at nearby assembled configurations (a dead-centre, toggle or branch point)",
                  rep->rank_undriven_h, rep->generic_rank);
    else if (rep->singularity == SING_DRIVERS)
        sb_puts(&sb, "; the rows without drivers are independent, so the drivers depend on them "
                "here (an input at its dead centre, or drivers that fight each other)");
    else if (rep->singularity == SING_PERMANENT)
        sb_printf(&sb, "; a permanent redundancy: without drivers the rows have rank %d of %d at "
                  "nearby assembled configurations too", rep->generic_rank, nuh);
    return sb_take(&sb);
}

/* The listed rows of the Jacobian's nonzeros as a CSR matrix (start:
   n + 1 entries, cols and vals: the rows' nonzeros). */
static SpqrRows pick_sparse(const Kinematics *kin, const int *cols, const double *vals,
                            const int *rows, int n, int *start, int *scols, double *svals)
{
    int k = 0;
    for (int i = 0; i < n; i++) {
        start[i] = k;
        for (int e = kin->row_start[rows[i]]; e < kin->row_start[rows[i] + 1]; e++) {
            scols[k] = cols[e];
            svals[k++] = vals[e];
        }
    }
    start[n] = k;
    return (SpqrRows){.m = n, .n = kin->model->nq, .start = start, .cols = scols, .vals = svals};
}

/* Beyond the dense limit: ranks and redundant rows by SuiteSparseQR of
   Phi_q^T (spqr_rank.c), one tolerance for all rows (from sigma_max of all
   rows); no smallest singular value. */
static void sparse_ranks(const Kinematics *kin, MechEval *me, InfoReport *rep, const int *undriven,
                         int nu, int nuh, const AnalysisOptions *opt, bool *red)
{
    int nq = rep->nq, nh = rep->nh, nr = rep->nr;
    size_t nnz = (size_t)kin->nnz + 1;
    double *vals = xmalloc(nnz * sizeof *vals), *svals = xmalloc(nnz * sizeof *svals);
    int *cols = xmalloc(nnz * sizeof *cols), *scols = xmalloc(nnz * sizeof *scols);
    int *all = xmalloc(((size_t)nr + 1) * sizeof *all), *start = xmalloc(((size_t)nr + 1) * sizeof *start);
    bool *dep = xcalloc((size_t)nr + 1, sizeof *dep);
    for (int e = 0; e < kin->nnz; e++)
        cols[e] = kin->jac[e].col;
    for (int r = 0; r < nr; r++)
        all[r] = r;
    mech_eval_nz(me, rep->q, rep->t, NULL, vals);
    double smax = sparse_rank_sigma_max(kin, vals, all, nr, opt->seed);
    double tol = opt->rank_tol >= 0 ? opt->rank_tol : mechrt_svd_default_tol(nr, nq, smax);
    rep->sigma_max = smax;
    rep->sigma_min = rep->cond = NAN;
    rep->rank_tol = tol;
    SpqrRows a = pick_sparse(kin, cols, vals, all, nr, start, scols, svals);
    rep->rank_all = spqr_dependent_rows(&a, tol, red, nh, &rep->rank);
    if (rep->rank_all >= 0) {
        for (int r = 0; r < nr; r++)
            *(r < nh ? &rep->nredundant : &rep->nredundant_velocity) += red[r];
        if (rep->rank_all == nr) {          /* independent rows: so is every subset */
            rep->rank_undriven_h = nuh;
            rep->rank_undriven = nu;
        } else {
            SpqrRows u = pick_sparse(kin, cols, vals, undriven, nu, start, scols, svals);
            rep->rank_undriven = spqr_dependent_rows(&u, tol, dep, nuh, &rep->rank_undriven_h);
        }
    } else {
        rep->rank = -1;
    }
    free(vals), free(svals), free(cols), free(scols), free(all), free(start), free(dep);
}

/* Ranks of the dense Jacobian jac (nr x nq, evaluated) by SVD: of the
   holonomic rows, of all rows, and of both without drivers; marks the
   redundant rows in red. sub: nr x nq scratch. Leaves a rank at -1 when
   the SVD fails (NaN or Inf). */
static void dense_ranks(MechrtSvd *w, double *jac, double *sub, const Model *m, InfoReport *rep,
                        const int *undriven, int nu, int nuh, const AnalysisOptions *opt,
                        bool *red)
{
    int nq = m->nq, nh = m->nh, nr = m->nr;
    MechrtSvdResult sv;
    if (!mechrt_svd(w, jac, nh, nq, nq, opt->rank_tol, &sv))
        return;
    rep->rank = sv.rank;
    rep->rank_tol = sv.tol;
    rep->sigma_max = sv.sigma_max;
    rep->sigma_min = sv.sigma_min;
    rep->cond = nh ? sv.cond : 0.0;
    rep->nredundant = svd_redundant_rows(w, jac, nh, nq, nq, sv.tol, 0, sv.rank, red);
    /* all rows, velocity level included (the same matrix when nv == 0) */
    MechrtSvdResult sa = sv;
    if (m->nv > 0 && !mechrt_svd(w, jac, nr, nq, nq, opt->rank_tol, &sa))
        return;
    rep->rank_all = sa.rank;
    rep->nredundant_velocity = svd_redundant_rows(w, jac, nr, nq, nq, sa.tol, nh, sa.rank, red);
    if (sa.rank == nr) {        /* independent rows: so is every subset */
        rep->rank_undriven_h = nuh;
        rep->rank_undriven = nu;
    } else {
        pick_rows(jac, nq, undriven, nu, sub);
        rep->rank_undriven_h = rank_of(w, sub, nuh, nq, sv.tol);
        rep->rank_undriven = rank_of(w, sub, nu, nq, sa.tol);
    }
}

/* Why the holonomic rows lose rank, from the ranks with and without
   drivers and the generic rank (rank_undriven_h < nuh: the mechanism
   itself is singular there). */
static Singularity classify_singularity(const InfoReport *rep, int nuh)
{
    if (rep->rank < 0)
        return SING_UNKNOWN;
    if (rep->rank == rep->nh)
        return SING_NONE;
    if (rep->generic_rank >= 0 && rep->rank_undriven_h < rep->generic_rank)
        return SING_POSITION;
    if (rep->rank_undriven_h == nuh)
        return SING_DRIVERS;
    if (rep->generic_rank < 0 && rep->state.drop > 0)
        return SING_POSITION;       /* --at, --state: more rank at the reference */
    if (rep->generic_rank >= 0 && rep->generic_rank == rep->rank_undriven_h)
        return SING_PERMANENT;
    return SING_UNKNOWN;
}

/* Marks the drivers and counts them. undriven[] lists the rows without
   drivers (holonomic rows first, *nuh of them), hrows[] every holonomic
   row; returns how many rows undriven[] holds. */
static int count_rows(const Model *m, InfoReport *rep, int *undriven, int *hrows, int *nuh)
{
    int nu = 0, nh = m->nh;
    *nuh = 0;
    for (int r = 0; r < m->nr; r++) {
        bool driver = m->rows[r].kind == JOINT_DRIVER;
        rep->rows[r].driver = driver;
        if (driver)
            *(r < nh ? &rep->nh_drivers : &rep->nv_drivers) += 1;
        else {
            undriven[nu++] = r;
            *nuh += r < nh;
        }
        if (r < nh)
            hrows[r] = r;
    }
    rep->dof = m->nq - nh - m->nv;
    rep->mobility = m->nq - nu;
    return nu;
}

/* info's Newton for assemble_at_t0: minimum-norm Newton on the holonomic
   rows (dense SVD), or beyond the dense limit (w NULL) by sparse QR; its
   AssembleResult kept for the report. */
typedef struct InfoNewton {
    MechEval *me;
    MechrtKernels k;
    MechrtSvd *w;
    const int *hrows;
    int nh;
    double t;
    const AnalysisOptions *opt;
    AssembleResult res;
} InfoNewton;

static MechrtStatus info_newton(void *ctx, double *q, MechrtReport *rep)
{
    InfoNewton *n = ctx;
    bool ok = n->w ? assemble_min_norm(&n->k, n->hrows, n->nh, n->t, q, n->opt, n->w, &n->res)
                   : assemble_sparse(n->me, n->nh, n->t, q, n->opt, &n->res);
    *rep = (MechrtReport){.iterations = n->res.iterations, .residual = n->res.residual,
                          .step = n->res.step, .worst_row = n->res.worst_row, .sing_index = -1};
    return ok ? MECHRT_OK : MECHRT_EMAXITER;
}

/* Assembly at t from the file's initial values, as run, sim and check
   assemble (assemble_at_t0): construction, then minimum-norm Newton, and
   where it stalls the restarts from jittered guesses (dense only: beyond
   the dense limit, w NULL, Newton is the sparse QR's and restarts would
   need the dense SVD). */
static void assemble_at(Mech *mech, MechEval *me, MechrtSvd *w, InfoReport *rep,
                        const int *hrows, double t, const AnalysisOptions *opt)
{
    const Model *m = mech->model;
    memcpy(rep->q, m->q0, (size_t)m->nq * sizeof *rep->q);
    if (m->nh == 0) {
        rep->assembled = true;
        rep->assembly = (AssembleResult){.converged = true, .step = -1, .worst_row = -1, .rank = -1};
        return;
    }
    InfoNewton n = {me, mech_eval_kernels(me), w, hrows, m->nh, t, opt, {0}};
    AssembleT0Options ao = {.t0 = t, .no_construction = w == NULL, .newton = info_newton,
                            .newton_ctx = &n, .robust = w != NULL, .rough = *opt};
    AssembleT0Report t0rep;
    rep->assembled = assemble_at_t0(m, &n.k, NULL, &ao, rep->q, &t0rep);
    rep->constructed = t0rep.constructed;
    rep->assembly = t0rep.robust ? t0rep.rough : n.res;
    if (!rep->assembled) {      /* rep->q: the best point found */
        AssembleViolated v;
        rep->violated = xcalloc(ASSEMBLE_VIOLATED_SIZE, 1);
        rep->loop = xcalloc(ASSEMBLE_VIOLATED_SIZE, 1);
        if (assemble_t0_violated(m, &n.k, t, opt->tol_phi, rep->q, &v, rep->violated,
                                 ASSEMBLE_VIOLATED_SIZE))
            assemble_t0_loop(m, &n.k, t, opt->tol_phi, rep->q, rep->loop,
                             ASSEMBLE_VIOLATED_SIZE);
    }
}

/* The ranks at rep->q, the redundant rows and, where rows are lost, the
   generic rank. w is NULL beyond the dense limit (sparse QR instead of
   SVD). */
static void rank_here(Mech *mech, MechEval *me, MechrtSvd *w, InfoReport *rep,
                      const int *undriven, int nu, int nuh, const AnalysisOptions *opt)
{
    const Model *m = mech->model;
    int nq = m->nq, nh = m->nh, nr = m->nr;
    double t = rep->t;
    size_t dense_len = w ? (size_t)nr * (size_t)nq : 0;
    double *jac = xcalloc(dense_len + 1, sizeof *jac);
    double *sub = xcalloc(dense_len + 1, sizeof *sub);
    bool *red = xcalloc((size_t)nr + 1, sizeof *red);
    if (w) {
        mech_eval(me, rep->q, t, NULL, jac);
        dense_ranks(w, jac, sub, m, rep, undriven, nu, nuh, opt, red);
    } else {
        sparse_ranks(&mech->kin, me, rep, undriven, nu, nuh, opt, red);
    }
    if (rep->rank < 0 || rep->rank_all < 0) {       /* NaN or Inf in the Jacobian */
        rep->rank = rep->rank_all = rep->rank_undriven = rep->rank_undriven_h = -1;
        rep->nredundant = rep->nredundant_velocity = 0;
        memset(red, 0, (size_t)nr * sizeof *red);
    }
    for (int r = 0; r < nr; r++)
        rep->rows[r].redundant = red[r];
    if (w) {
        if (rep->rank >= 0 && rep->rank_undriven_h >= 0 && opt->generic_samples > 0
            && (rep->rank < nh || rep->rank_undriven_h < nuh))
            rep->generic_rank = generic_rank(me, undriven, nuh, rep->q, t, opt, w);
    }
    if (rep->rank_all >= 0) {
        rep->dof_rank = nq - rep->rank_all;
        rep->mobility_rank = nq - rep->rank_undriven;
    }
    free(jac), free(sub), free(red);
}

/* --at / --state: the reference at t = 0 (its rank and redundant rows into
   *ref_rank, ref_red), then the state: the motion followed to rep->t, or
   at->q as given. */
static void reach_state(Mech *mech, MechEval *me, MechrtSvd *w, InfoReport *rep, const int *hrows,
                        const InfoAt *at, const AnalysisOptions *opt, int *ref_rank, bool *ref_red)
{
    int nq = rep->nq, nh = rep->nh;
    InfoState *st = &rep->state;
    st->asked = true;
    assemble_at(mech, me, w, rep, hrows, 0.0, opt);
    *ref_rank = rep->assembled ? info_holonomic_rank(me, w, rep->q, 0.0, opt->rank_tol, ref_red) : -1;
    if (at->q) {
        st->given = true;
        memcpy(rep->q, at->q, (size_t)nq * sizeof *rep->q);
        rep->assembled = true;
        rep->constructed = 0;
        rep->assembly = (AssembleResult){.converged = true, .step = -1, .worst_row = -1, .rank = -1};
    } else if (rep->assembled && nh > 0 && rep->t != 0.0) {
        double *near = xmalloc(((size_t)nq + 1) * sizeof *near), t_near;
        bool *near_red = xcalloc((size_t)nh + 1, sizeof *near_red);
        st->reached = info_follow(me, w, hrows, nh, rep->t, rep->q, opt, &rep->assembly, &st->steps,
                                  near, &t_near);
        rep->assembled = st->reached;
        /* the regular state just before t, with the state's tolerance: the
           reference when its rank is the larger (t = 0 may be singular) */
        int near_rank = !st->reached ? -1
            : info_holonomic_rank(me, w, near, t_near, info_state_tolerance(me, w, near, t_near),
                                  near_red);
        if (near_rank > *ref_rank) {
            *ref_rank = near_rank;
            memcpy(ref_red, near_red, (size_t)nh * sizeof *ref_red);
        }
        free(near), free(near_red);
    } else {
        st->reached = rep->assembled;
    }
    rep->assembly.residual = st->residual = info_residual(me, rep->q, rep->t);
}

bool info_analyse(Mech *mech, double t, const AnalysisOptions *opt, InfoReport *rep, Diag *diag)
{
    return info_analyse_at(mech, t, NULL, opt, rep, diag);
}

bool info_analyse_at(Mech *mech, double t, const InfoAt *at, const AnalysisOptions *opt,
                     InfoReport *rep, Diag *diag)
{
    Model *m = mech->model;
    int nq = m->nq, nh = m->nh, nr = m->nr;
    memset(rep, 0, sizeof *rep);
    rep->model = m;
    rep->t = t;
    rep->nq = nq, rep->nh = nh, rep->nv = m->nv, rep->nr = nr;
    rep->rows = xcalloc((size_t)nr + 1, sizeof *rep->rows);
    int *undriven = xmalloc(((size_t)nr + 1) * sizeof *undriven);
    int *hrows = xmalloc(((size_t)nh + 1) * sizeof *hrows);
    int nuh;
    int nu = count_rows(m, rep, undriven, hrows, &nuh);
    rep->rank = rep->rank_all = rep->rank_undriven = rep->rank_undriven_h = -1;
    rep->generic_rank = -1;
    rep->q = xmalloc((size_t)nq * sizeof *rep->q + 1);
    rep->dense = (double)nr * (double)nq <= opt->max_dense;

    MechEval me;
    mech_eval_init(&me, &mech->kin);
    MechrtSvd *w = rep->dense ? svd_work_new(nr, nq) : NULL;
    int ref_rank = -1;
    bool *ref_red = xcalloc((size_t)nh + 1, sizeof *ref_red);
    AnalysisOptions so = *opt;      /* at a state: its own tolerance */
    if (at) {
        reach_state(mech, &me, w, rep, hrows, at, opt, &ref_rank, ref_red);
        if (so.rank_tol < 0)
            so.rank_tol = info_state_tolerance(&me, w, rep->q, t);
    } else {
        assemble_at(mech, &me, w, rep, hrows, t, opt);
    }
    rank_here(mech, &me, w, rep, undriven, nu, nuh, &so);
    if (at)
        info_state_finish(&me, rep, ref_rank, ref_red);
    free(ref_red);
    rep->singularity = classify_singularity(rep, nuh);
    rep->verdict = make_verdict(rep);
    rep->singular = make_singular(rep, nuh);

    /* integrability of every velocity-level row, around the configuration,
       then of the rows without drivers together */
    bool ok = true;
    for (int r = nh; r < nr && ok; r++)
        ok = integrability_analyse(m, r, rep->q, opt, &rep->rows[r].integ, diag);
    if (ok)
        ok = system_test(m, &me, rep, undriven, nu, nuh, opt, w, diag);

    mech_eval_free(&me);
    mechrt_svd_free(w);
    free(undriven), free(hrows);
    if (!ok)
        info_report_free(rep);
    return ok;
}

void info_report_free(InfoReport *rep)
{
    if (rep->rows)
        for (int r = 0; r < rep->nr; r++)
            integrability_free(&rep->rows[r].integ);
    free(rep->rows);
    involutivity_free(&rep->system);
    free(rep->q);
    free(rep->verdict);
    free(rep->violated);
    free(rep->loop);
    free(rep->singular);
    free(rep->state.dependent);
    free(rep->state.null);
    free(rep->state.free_coord);
    memset(rep, 0, sizeof *rep);
}
