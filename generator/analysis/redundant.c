/* redundant.c - more holonomic rows than coordinates: the redundant rows found once, the square system of the others, the dropped rows checked.
 *
 * Models written joint by joint are overconstrained as a rule (a planar
 * four-bar with four revolutes about z repeats three rows; the Bricard
 * linkage with a driver has 36 rows for 35 coordinates). The rows that
 * depend on the rows before them are found once, at the configuration
 * assembled at t0 on all rows, by `info`'s own definition and SVD
 * (svd_redundant_rows), so that run, sim and check name the rows info
 * names. The analyses then work on the square system of the other rows
 * (the kernels below pick them out of the model's kernels), which is what
 * ADAMS does when it removes redundant constraints; and because a
 * redundancy can be inconsistent (a dimension that makes the loop close
 * only by least squares), every state is checked on the dropped rows too.
 * Along a motion whose redundancy is permanent (the joints' structure,
 * not the position) the kept rows stay independent; where they lose rank
 * the analyses meet a singular position as they would without the
 * redundancy (the Bricard's limit position).
 */
#include "redundant.h"

#include "assemble.h"
#include "common.h"
#include "construct.h"
#include "svd.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The kept rows of a full vector, in order. */
static void gather(const Redundant *r, const double *full, double *out)
{
    for (int i = 0; i < r->nkeep; i++)
        out[i] = full[r->keep[i]];
}

static void gather_jac(const Redundant *r, const double *full, double *out)
{
    size_t nq = (size_t)r->nq;
    for (int i = 0; i < r->nkeep; i++)
        memcpy(out + (size_t)i * nq, full + (size_t)r->keep[i] * nq, nq * sizeof *out);
}

/* The model's kernels into the scratch arrays, each stamped with the
   state it was evaluated at. */
static void stamp(const Redundant *r, RedundantAt *at, const double *q, const double *qd,
                  double t)
{
    size_t bytes = (size_t)r->nq * sizeof *q;
    memcpy(at->q, q, bytes);
    if (qd)
        memcpy(at->qd, qd, bytes);
    at->t = t;
    at->valid = true;
}

static bool fresh(const Redundant *r, const RedundantAt *at, const double *q, const double *qd,
                  double t)
{
    size_t bytes = (size_t)r->nq * sizeof *q;
    return at->valid && at->t == t && memcmp(at->q, q, bytes) == 0
           && (!qd || memcmp(at->qd, qd, bytes) == 0);
}

static void eval_phi(Redundant *r, const double *q, double t)
{
    r->full->phi(r->full->ctx, q, t, r->phi);
    stamp(r, &r->at_phi, q, NULL, t);
}

static void eval_jac(Redundant *r, const double *q, double t)
{
    r->full->jac(r->full->ctx, q, t, r->jac);
    stamp(r, &r->at_jac, q, NULL, t);
}

static void eval_jac_nz(Redundant *r, const double *q, double t)
{
    r->full_jnz->jac.jac_nz(r->full_jnz->jac.ctx, q, t, r->vals);
    stamp(r, &r->at_vals, q, NULL, t);
}

static void eval_nu(Redundant *r, const double *q, double t)
{
    r->full->nu(r->full->ctx, q, t, r->nu);
    stamp(r, &r->at_nu, q, NULL, t);
}

static void eval_gamma(Redundant *r, const double *q, const double *qd, double t)
{
    r->full->gamma(r->full->ctx, q, qd, t, r->gamma);
    stamp(r, &r->at_gamma, q, qd, t);
}

static void red_phi(void *ctx, const double *q, double t, double *phi)
{
    Redundant *r = ctx;
    eval_phi(r, q, t);
    gather(r, r->phi, phi);
}

static void red_jac(void *ctx, const double *q, double t, double *jac)
{
    Redundant *r = ctx;
    eval_jac(r, q, t);
    gather_jac(r, r->jac, jac);
}

static void red_nu(void *ctx, const double *q, double t, double *nu)
{
    Redundant *r = ctx;
    eval_nu(r, q, t);
    gather(r, r->nu, nu);
}

static void red_gamma(void *ctx, const double *q, const double *qd, double t, double *gamma)
{
    Redundant *r = ctx;
    eval_gamma(r, q, qd, t);
    gather(r, r->gamma, gamma);
}

static void red_all(void *ctx, const double *q, const double *qd, double t, double *phi,
                    double *jac, double *nu, double *gamma)
{
    Redundant *r = ctx;
    r->full->all(r->full->ctx, q, qd, t, r->phi, r->jac, r->nu, r->gamma);
    stamp(r, &r->at_phi, q, NULL, t);
    stamp(r, &r->at_jac, q, NULL, t);
    stamp(r, &r->at_nu, q, NULL, t);
    stamp(r, &r->at_gamma, q, qd, t);
    gather(r, r->phi, phi);
    gather_jac(r, r->jac, jac);
    gather(r, r->nu, nu);
    gather(r, r->gamma, gamma);
}

static void red_mass(void *ctx, const double *q, double *M)
{
    Redundant *r = ctx;
    r->full->mass(r->full->ctx, q, M);
}

static void red_force(void *ctx, const double *q, const double *qd, double t, double *Q)
{
    Redundant *r = ctx;
    r->full->force(r->full->ctx, q, qd, t, Q);
}

static void red_jac_nz(void *ctx, const double *q, double t, double *vals)
{
    Redundant *r = ctx;
    eval_jac_nz(r, q, t);
    for (int e = 0; e < r->jnz.jac.nnz; e++)
        vals[e] = r->vals[r->nz_keep[e]];
}

static void red_all_nz(void *ctx, const double *q, const double *qd, double t, double *phi,
                       double *vals, double *nu, double *gamma)
{
    Redundant *r = ctx;
    r->full_jnz->all_nz(r->full_jnz->jac.ctx, q, qd, t, r->phi, r->vals, r->nu, r->gamma);
    stamp(r, &r->at_phi, q, NULL, t);
    stamp(r, &r->at_vals, q, NULL, t);
    stamp(r, &r->at_nu, q, NULL, t);
    stamp(r, &r->at_gamma, q, qd, t);
    for (int e = 0; e < r->jnz.jac.nnz; e++)
        vals[e] = r->vals[r->nz_keep[e]];
    gather(r, r->phi, phi);
    gather(r, r->nu, nu);
    gather(r, r->gamma, gamma);
}

bool redundant_applies(const Model *m)
{
    return m->nh > m->nq && m->nv == 0 && (double)m->nr * m->nq <= REDUNDANT_MAX_ENTRIES;
}

int redundant_find(const Model *m, const MechrtKernels *k, double t0, bool *red)
{
    int nq = m->nq, nr = m->nr;
    double *q = xmalloc((size_t)nq * sizeof *q);
    double *jac = xmalloc((size_t)nr * (size_t)nq * sizeof *jac);
    memcpy(q, m->q0, (size_t)nq * sizeof *q);
    construct_with_kernels(m, k, t0, q);
    AnalysisOptions opt = analysis_default_options();
    opt.stall_iter = ASSEMBLE_ROUGH_STALL;
    AssembleResult ar;
    double *start = xmalloc((size_t)nq * sizeof *start);
    memcpy(start, q, (size_t)nq * sizeof *q);
    /* Where the rows do not close (an inconsistent redundancy), the least
       squares point tilts the mechanism to share the error, and a
       structural redundancy (a fourth revolute about z) no longer shows:
       the file's values, where the user put the mechanism, tell it. */
    if (!assemble_restarting(k, t0, q, &opt, &ar))
        memcpy(q, start, (size_t)nq * sizeof *q);
    free(start);
    k->jac(k->ctx, q, t0, jac);
    MechrtSvd *w = svd_work_new(nr, nq);
    MechrtSvdResult sv;
    int n = -1;
    if (mechrt_svd(w, jac, nr, nq, nq, opt.rank_tol, &sv))
        n = svd_redundant_rows(w, jac, nr, nq, nq, sv.tol, 0, sv.rank, red);
    mechrt_svd_free(w);
    free(q), free(jac);
    return n;
}

/* The kept rows' entries of the model's pattern, renumbered. */
static void open_pattern(Redundant *r, const MechrtHostJacNz *jnz)
{
    int *newrow = xmalloc(((size_t)r->nr + 1) * sizeof *newrow);
    for (int i = 0; i < r->nr; i++)
        newrow[i] = -1;
    for (int i = 0; i < r->nkeep; i++)
        newrow[r->keep[i]] = i;
    size_t nnz = (size_t)jnz->jac.nnz + 1;
    r->nz_keep = xmalloc(nnz * sizeof *r->nz_keep);
    r->nz_row = xmalloc(nnz * sizeof *r->nz_row);
    r->nz_col = xmalloc(nnz * sizeof *r->nz_col);
    r->nz_drop = xmalloc(nnz * sizeof *r->nz_drop);
    r->vals = xmalloc(nnz * sizeof *r->vals);
    int n = 0;
    for (int e = 0; e < jnz->jac.nnz; e++)
        if (newrow[jnz->jac.row[e]] >= 0) {
            r->nz_keep[n] = e;
            r->nz_row[n] = newrow[jnz->jac.row[e]];
            r->nz_col[n++] = jnz->jac.col[e];
        } else {
            r->nz_drop[r->ndrop_nz++] = e;
        }
    free(newrow);
    r->jnz = (MechrtHostJacNz){.jac = {.nnz = n, .row = r->nz_row, .col = r->nz_col, .ctx = r,
                                       .jac_nz = red_jac_nz},
                               .all_nz = jnz->all_nz ? red_all_nz : NULL};
}

void redundant_open(Redundant *r, const Model *m, const MechrtKernels *k,
                    const MechrtHostJacNz *jnz, const bool *red)
{
    memset(r, 0, sizeof *r);
    r->m = m;
    r->full = k;
    r->full_jnz = jnz;
    r->nq = m->nq;
    r->nr = m->nr;
    size_t nr = (size_t)m->nr + 1, nq = (size_t)m->nq;
    r->keep = xmalloc(nr * sizeof *r->keep);
    r->drop = xmalloc(nr * sizeof *r->drop);
    for (int i = 0; i < m->nr; i++) {
        if (red[i])
            r->drop[r->ndrop++] = i;
        else
            r->keep[r->nkeep++] = i;
    }
    r->phi = xmalloc(nr * sizeof *r->phi);
    r->nu = xmalloc(nr * sizeof *r->nu);
    r->gamma = xmalloc(nr * sizeof *r->gamma);
    r->lambda = xcalloc(nr, sizeof *r->lambda);
    r->acc = xmalloc(2 * nr * sizeof *r->acc);
    RedundantAt *at[] = {&r->at_phi, &r->at_jac, &r->at_vals, &r->at_nu, &r->at_gamma};
    r->at_block = xmalloc(2 * nq * (sizeof at / sizeof *at) * sizeof *r->at_block + 1);
    for (size_t i = 0; i < sizeof at / sizeof *at; i++) {
        at[i]->q = r->at_block + 2 * nq * i;
        at[i]->qd = at[i]->q + nq;
    }
    r->jac = xmalloc(nr * nq * sizeof *r->jac);
    Row *rows = xmalloc(nr * sizeof *rows);
    for (int i = 0; i < r->nkeep; i++)
        rows[i] = m->rows[r->keep[i]];
    r->view = *m;       /* shares the model's arena and graph: never freed through it */
    r->view.rows = rows;
    r->view.nh = r->view.nr = r->nkeep;
    r->view.nv = 0;
    r->k = *k;
    r->k.nh = r->nkeep;
    r->k.nv = 0;
    r->k.ctx = r;
    r->k.phi = red_phi;
    r->k.jac = red_jac;
    r->k.nu = red_nu;
    r->k.gamma = red_gamma;
    r->k.all = k->all ? red_all : NULL;
    r->k.mass = k->mass ? red_mass : NULL;      /* the model's, with its ctx */
    r->k.force = k->force ? red_force : NULL;
    if (jnz)
        open_pattern(r, jnz);
}

bool redundant_start(Redundant *r, const Model *m, const MechrtKernels *k,
                     const MechrtHostJacNz *jnz, double t0, bool driven, FILE *notes,
                     char *why, size_t size)
{
    bool *drop = xcalloc((size_t)m->nr + 1, sizeof *drop);
    int n = redundant_find(m, k, t0, drop);
    if (n >= 0)
        redundant_open(r, m, k, jnz, drop);
    free(drop);
    if (n < 0) {
        snprintf(why, size, "t = %.10g: NaN or Inf in the Jacobian where the redundant rows "
                 "are looked for (the configuration assembled on all rows)", t0);
        return false;
    }
    if (driven && r->nkeep < m->nq) {
        int dof = m->nq - r->nkeep;
        snprintf(why, size, "%d degree%s of freedom %s not driven (%d coordinates, %d rows of "
                 "which %d %s redundant: ", dof, dof == 1 ? "" : "s", dof == 1 ? "is" : "are",
                 m->nq, m->nr, r->ndrop, r->ndrop == 1 ? "is" : "are");
        redundant_names(r, why, size);
        analysis_msgf(why, size, "): add %s", dof == 1 ? "a driver" : "drivers");
        redundant_close(r);
        return false;
    }
    redundant_note(notes, r);
    return true;
}

void redundant_close(Redundant *r)
{
    free(r->keep), free(r->drop);
    free(r->phi), free(r->nu), free(r->gamma), free(r->jac), free(r->lambda);
    free(r->acc), free(r->at_block);
    free(r->nz_keep), free(r->nz_row), free(r->nz_col), free(r->nz_drop), free(r->vals);
    free(r->view.rows);
    memset(r, 0, sizeof *r);
}

void redundant_names(const Redundant *r, char *msg, size_t size)
{
    for (int i = 0; i < r->ndrop; i++) {
        const Row *row = &r->m->rows[r->drop[i]];
        analysis_msgf(msg, size, "%s%s (joint %s)", i ? ", " : "", row->name,
                      r->m->joints[row->joint].name);
    }
}

void redundant_note(FILE *notes, const Redundant *r)
{
    if (!notes)
        return;
    char names[1024] = "";
    redundant_names(r, names, sizeof names);
    fprintf(notes, "%s: note: %d holonomic rows for %d coordinates: redundant %s: %s; solved on "
            "the other %d rows, the redundant ones checked at every state\n", r->m->file, r->nr,
            r->nq, r->ndrop == 1 ? "row" : "rows", names, r->nkeep);
}

void redundant_note_reactions(FILE *notes, const Redundant *r)
{
    if (!notes)
        return;
    char names[1024] = "";
    redundant_names(r, names, sizeof names);
    fprintf(notes, "%s: note: the reactions of the redundant rows and of the rows they repeat are "
            "not unique: reported as the independent rows' (0 on %s)\n", r->m->file, names);
}

/* The dropped rows' residuals of Phi_q x = rhs relative to their
   tolerance, from the dense Jacobian (r->jac) or the model's nonzeros
   (r->vals, sparse); the worst into *worst (its row in *row) when it is
   larger. */
static void check_rate(Redundant *r, bool sparse, const double *x, const double *rhs,
                       double *worst, int *row, bool *this_level)
{
    double *ax = r->acc, *scale = r->acc + r->nr;
    for (int d = 0; d < r->ndrop; d++) {
        int i = r->drop[d];
        ax[i] = 0;
        scale[i] = fabs(rhs[i]);
        if (sparse)
            continue;
        const double *a = r->jac + (size_t)i * (size_t)r->nq;
        for (int j = 0; j < r->nq; j++) {
            ax[i] += a[j] * x[j];
            scale[i] += fabs(a[j] * x[j]);
        }
    }
    for (int n = 0; sparse && n < r->ndrop_nz; n++) {
        int e = r->nz_drop[n], i = r->full_jnz->jac.row[e];
        double v = r->vals[e] * x[r->full_jnz->jac.col[e]];
        ax[i] += v;
        scale[i] += fabs(v);
    }
    for (int d = 0; d < r->ndrop; d++) {
        int i = r->drop[d];
        double v = fabs(ax[i] - rhs[i]) / (REDUNDANT_RATE_SHARE * scale[i] + 1e-12);
        if (!(v <= *worst)) {
            *worst = v;
            *row = i;
            *this_level = true;
        }
    }
}

/* The dropped rows' Jacobian at (q, t), from the step that ended there
   when it left one; true when it is the nonzeros (r->vals). */
static bool jac_at(Redundant *r, const double *q, double t)
{
    if (r->full_jnz && fresh(r, &r->at_vals, q, NULL, t))
        return true;
    if (fresh(r, &r->at_jac, q, NULL, t))
        return false;
    if (r->full_jnz)
        eval_jac_nz(r, q, t);
    else
        eval_jac(r, q, t);
    return r->full_jnz != NULL;
}

double redundant_check(Redundant *r, const double *q, const double *qd, const double *qdd,
                       double t, double tol_phi, int *row, const char **level)
{
    double worst = 0;
    *row = -1;
    *level = "position";
    if (!fresh(r, &r->at_phi, q, NULL, t))
        eval_phi(r, q, t);
    for (int d = 0; d < r->ndrop; d++) {
        double v = fabs(r->phi[r->drop[d]]) / (REDUNDANT_PHI_SHARE * tol_phi);
        if (!(v <= worst))
            worst = v, *row = r->drop[d];
    }
    if (!qd)
        return worst;
    bool sparse = jac_at(r, q, t), at = false;
    if (!fresh(r, &r->at_nu, q, NULL, t))
        eval_nu(r, q, t);
    check_rate(r, sparse, qd, r->nu, &worst, row, &at);
    if (at)
        *level = "velocity";
    if (!qdd)
        return worst;
    if (!fresh(r, &r->at_gamma, q, qd, t))
        eval_gamma(r, q, qd, t);
    at = false;
    check_rate(r, sparse, qdd, r->gamma, &worst, row, &at);
    if (at)
        *level = "acceleration";
    return worst;
}

void redundant_explain(Redundant *r, const double *q, const double *qd, const double *qdd,
                       double t, double tol_phi, char *msg, size_t size)
{
    int row;
    const char *level;
    double v = redundant_check(r, q, qd, qdd, t, tol_phi, &row, &level);
    if (row < 0)
        return;
    const Row *rw = &r->m->rows[row];
    snprintf(msg, size, "t = %.10g: the redundant rows contradict the others: row %s (joint %s) "
             "is violated at the %s level", t, rw->name, r->m->joints[rw->joint].name, level);
    if (strcmp(level, "position") == 0)
        analysis_msgf(msg, size, " (residual %.3g, tolerance %.3g)", r->phi[row],
                      REDUNDANT_PHI_SHARE * tol_phi);
    else
        analysis_msgf(msg, size, " (residual %.3g times the tolerance, %.3g of its terms)", v,
                      REDUNDANT_RATE_SHARE);
    analysis_msgf(msg, size, ", so no motion satisfies every row; redundant rows: ");
    redundant_names(r, msg, size);
}

const double *redundant_expand(Redundant *r, const double *kept)
{
    for (int i = 0; i < r->ndrop; i++)
        r->lambda[r->drop[i]] = 0;
    for (int i = 0; i < r->nkeep; i++)
        r->lambda[r->keep[i]] = kept[i];
    return r->lambda;
}
