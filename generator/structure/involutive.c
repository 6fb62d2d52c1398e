/* involutive.c - are the velocity-level rows, taken together with the holonomic rows, integrable?
 *
 * The rows are 1-forms on (q, t) space (n = nq + 1 variables):
 *     holonomic row   dPhi  = Phi_q dq + Phi_t dt   (exact: d(dPhi) = 0),
 *     velocity row    omega = a^T dq + b dt.
 * The motions are the curves tangent to the distribution D = ker of all of
 * them. By Frobenius (the form version: e.g. Bryant et al., Exterior
 * Differential Systems, 1991, II.1), D is integrable, so the velocity rows
 * are holonomic in disguise once the holonomic rows hold, iff for every
 * velocity row k and all X, Y in D
 *     d omega_k (X, Y) = X^T W_k Y = 0,   (W_k)_jl = d_j a_l - d_l a_j.
 * With B an orthonormal basis of the rows' span (right singular vectors of
 * the rows' coefficient matrix C) and P = I - B B^T the projector onto D,
 * that is P W_k P = 0. It is checked numerically at a few configurations
 * that satisfy the holonomic rows: a nonzero value anywhere proves the
 * system nonholonomic; zero everywhere is evidence that it is holonomic.
 * This catches what the per-row test cannot: a knife edge whose heading is
 * fixed by a holonomic row is integrable on that row's manifold.
 */
#include "involutive.h"

#include "../base/arena.h"
#include "../base/strbuf.h"
#include "../dag/support.h"
#include "../diff/diff.h"
#include "../eval/interp.h"
#include "../analysis/svd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* |P W P| below this fraction of |W| counts as zero. */
static const double INVOLUTIVE_RTOL = 1e-8;

typedef struct Entry {
    int k, j, l;        /* C: row k, column j (l unused); part: d a_kj / d x_l */
    NodeId node;
} Entry;

typedef struct Entries {
    Entry *e;
    int n, cap;
} Entries;

static void push(Entries *v, int k, int j, int l, NodeId node)
{
    if (v->n == v->cap) {
        v->cap = v->cap ? 2 * v->cap : 64;
        v->e = xrealloc(v->e, (size_t)v->cap, sizeof *v->e);
    }
    v->e[v->n++] = (Entry){k, j, l, node};
}

void involutivity_free(Involutivity *inv)
{
    free(inv->note);
    memset(inv, 0, sizeof *inv);
}

/* out = P W P, P = I - B B^T, all n x n (B: n x r); scratch holds n * r + n * n. */
static void project(int n, int r, const double *B, const double *W, double *out, double *scratch)
{
    double *WB = scratch, *WP = scratch + (size_t)n * (size_t)r;
    for (int i = 0; i < n; i++)
        for (int c = 0; c < r; c++) {
            double s = 0.0;
            for (int j = 0; j < n; j++)
                s += W[i * n + j] * B[j * r + c];
            WB[i * r + c] = s;
        }
    for (int i = 0; i < n; i++)             /* WP = W - (W B) B^T */
        for (int j = 0; j < n; j++) {
            double s = W[i * n + j];
            for (int c = 0; c < r; c++)
                s -= WB[i * r + c] * B[j * r + c];
            WP[i * n + j] = s;
        }
    for (int c = 0; c < r; c++)             /* reuse WB as B^T WP (r x n) */
        for (int j = 0; j < n; j++) {
            double s = 0.0;
            for (int i = 0; i < n; i++)
                s += B[i * r + c] * WP[i * n + j];
            WB[c * n + j] = s;
        }
    for (int i = 0; i < n; i++)             /* P W P = WP - B (B^T WP) */
        for (int j = 0; j < n; j++) {
            double s = WP[i * n + j];
            for (int c = 0; c < r; c++)
                s -= B[i * r + c] * WB[c * n + j];
            out[i * n + j] = s;
        }
}

/* The rows' forms as graph nodes: coef holds the coefficients of every
   row (C: row k, column j; t is column nq), part the partials d a_kj / d x_l
   of the velocity rows' coefficients. */
typedef struct Forms {
    Entries coef, part;
    int *vel;           /* index k into rows[] of each velocity row */
    int nvel;
} Forms;

static void forms_free(Forms *f)
{
    free(f->coef.e), free(f->part.e), free(f->vel);
    memset(f, 0, sizeof *f);
}

/* The symbolic part: every node the numeric test evaluates. Stops early
   past the node limit (the caller reports it). */
static void collect_forms(Model *m, const int *rows, int nrows, Forms *f)
{
    Dag *dag = &m->dag;
    int nq = m->nq;
    Differ df;
    SupportScan scan;
    differ_init(&df, dag, nq);
    support_init(&scan);
    int *buf = xmalloc(((size_t)nq + 2) * sizeof *buf);
    f->vel = xmalloc(((size_t)nrows + 1) * sizeof *f->vel);
    for (int k = 0; k < nrows && !dag->overflow; k++) {
        const Row *row = &m->rows[rows[k]];
        if (!row->velocity) {
            int ns = support_collect(&scan, dag, row->expr, OP_VAR, buf);
            for (int i = 0; i < ns; i++)
                push(&f->coef, k, buf[i], 0, diff_by_q(&df, row->expr, buf[i]));
            push(&f->coef, k, nq, 0, diff_by_t(&df, row->expr));
            continue;
        }
        f->vel[f->nvel++] = k;
        int first = f->coef.n;
        int ns = support_collect(&scan, dag, row->expr, OP_VARD, buf);
        for (int i = 0; i < ns; i++)
            push(&f->coef, k, buf[i], 0, diff_by_qd(&df, row->expr, buf[i]));
        push(&f->coef, k, nq, 0, diff_without_velocities(&df, row->expr));
        for (int e = first; e < f->coef.n; e++) {
            NodeId c = f->coef.e[e].node;
            int j = f->coef.e[e].j;
            int nv = support_collect(&scan, dag, c, OP_VAR, buf);
            for (int i = 0; i < nv; i++)
                push(&f->part, k, j, buf[i], diff_by_q(&df, c, buf[i]));
            if (support_collect(&scan, dag, c, OP_TIME, buf) > 0)
                push(&f->part, k, j, nq, diff_by_t(&df, c));
        }
    }
    free(buf);
    support_free(&scan);
    differ_free(&df);
}

/* The numeric part's program and workspaces, sized once for all points. */
typedef struct Curvature {
    int n, nrows;       /* n = nq + 1 */
    NodeValues ev;      /* value e: coef.e[e]; value coef.n + e: part.e[e] */
    double *C, *B, *W, *M, *scratch;
    MechrtSvd *svd;
} Curvature;

static void curvature_init(Curvature *c, const Dag *dag, const Forms *f, int nrows, int n)
{
    c->n = n;
    c->nrows = nrows;
    int nroots = f->coef.n + f->part.n;
    NodeId *roots = xmalloc(((size_t)nroots + 1) * sizeof *roots);
    for (int e = 0; e < f->coef.n; e++)
        roots[e] = f->coef.e[e].node;
    for (int e = 0; e < f->part.n; e++)
        roots[f->coef.n + e] = f->part.e[e].node;
    node_values_init(&c->ev, dag, roots, nroots);
    free(roots);
    size_t nn = (size_t)n * (size_t)n;
    c->C = xmalloc((size_t)nrows * (size_t)n * sizeof *c->C);
    c->B = xmalloc(nn * sizeof *c->B);
    c->W = xmalloc(nn * sizeof *c->W);
    c->M = xmalloc(nn * sizeof *c->M);
    c->scratch = xmalloc(2 * nn * sizeof *c->scratch);
    c->svd = svd_work_new(nrows, n);
}

static void curvature_free(Curvature *c)
{
    mechrt_svd_free(c->svd);
    node_values_free(&c->ev);
    free(c->C), free(c->B), free(c->W), free(c->M), free(c->scratch);
}

/* W_k of the velocity row k at the evaluated point, (W_k)_jl = d_j a_l -
   d_l a_j; *scale = max |W_k|. False when a partial is not finite. */
static bool curl(Curvature *c, const Forms *f, int k, double *scale)
{
    int n = c->n;
    size_t nn = (size_t)n * (size_t)n;
    bool finite = true;
    memset(c->W, 0, nn * sizeof *c->W);
    for (int e = 0; e < f->part.n; e++) {
        if (f->part.e[e].k != k)
            continue;
        double x = node_values_get(&c->ev, f->coef.n + e);     /* d_l a_j */
        int j = f->part.e[e].j, l = f->part.e[e].l;
        c->W[l * n + j] += x;
        c->W[j * n + l] -= x;
        finite = finite && isfinite(x);
    }
    *scale = 0.0;
    for (size_t i = 0; i < nn; i++)
        *scale = fmax(*scale, fabs(c->W[i]));
    return finite;
}

/* The worst |P W_k P| / |W_k| seen so far, with its model row and point. */
typedef struct Worst {
    double ratio;
    int row, point;
} Worst;

/* Point p, configuration q at time t: updates *worst for each velocity row
   in turn. False when the point does not count (NaN or Inf met). */
static bool worst_curvature(Curvature *c, const Forms *f, const int *rows, const double *q,
                            double t, int p, Worst *worst)
{
    int n = c->n;
    size_t nn = (size_t)n * (size_t)n;
    node_values_run(&c->ev, q, NULL, t);
    memset(c->C, 0, (size_t)c->nrows * (size_t)n * sizeof *c->C);
    for (int e = 0; e < f->coef.n; e++)
        c->C[(size_t)f->coef.e[e].k * (size_t)n + (size_t)f->coef.e[e].j] = node_values_get(&c->ev, e);
    MechrtSvdResult sv;
    if (!mechrt_svd(c->svd, c->C, c->nrows, n, n, -1.0, &sv))
        return false;
    int r = sv.rank;
    for (int j = 0; j < n; j++)
        for (int col = 0; col < r; col++)
            c->B[j * r + col] = mechrt_svd_row_basis(c->svd, j, col);
    for (int v = 0; v < f->nvel; v++) {
        double scale;
        if (!curl(c, f, f->vel[v], &scale))
            return false;
        if (scale == 0.0)
            continue;
        project(n, r, c->B, c->W, c->M, c->scratch);
        double big = 0.0;
        for (size_t i = 0; i < nn; i++)
            big = fmax(big, fabs(c->M[i]));
        if (big / scale > worst->ratio)
            *worst = (Worst){big / scale, rows[f->vel[v]], p};
    }
    return true;
}

/* The verdict in words, from the worst ratio over the points. */
static void involutive_note(const Model *m, const Worst *worst, Involutivity *out)
{
    StrBuf sb;
    sb_init(&sb);
    out->tested = out->points > 0;
    if (!out->tested) {
        sb_puts(&sb, "not tested: no configuration could be evaluated");
    } else if (worst->ratio > INVOLUTIVE_RTOL) {
        out->involutive = false;
        sb_printf(&sb, "nonholonomic: d omega of row %s does not vanish on the allowed "
                  "velocities (%.3g of its size) at %s configuration", m->rows[worst->row].name,
                  worst->ratio, worst->point == 0 ? "the assembled" : "a sampled");
    } else {
        out->involutive = true;
        sb_printf(&sb, "holonomic: the allowed velocities form an involutive distribution at "
                  "%d configuration%s (numerical evidence)", out->points, out->points == 1 ? "" : "s");
    }
    out->note = sb_take(&sb);
}

bool involutivity_analyse(Model *m, const int *rows, int nrows, const double *points,
                          const double *times, int npoints, Involutivity *out, Diag *diag)
{
    memset(out, 0, sizeof *out);
    Forms f = {0};
    collect_forms(m, rows, nrows, &f);
    bool ok = dag_check_limit(&m->dag, diag);   /* the node limit, once for the symbolic part */
    if (ok && f.nvel == 0) {
        out->note = strdup("no velocity-level rows");
    } else if (ok) {
        Curvature c;
        curvature_init(&c, &m->dag, &f, nrows, m->nq + 1);
        Worst worst = {0.0, -1, -1};
        for (int p = 0; p < npoints; p++)
            if (worst_curvature(&c, &f, rows, points + (size_t)p * (size_t)m->nq, times[p], p, &worst))
                out->points++;
        curvature_free(&c);
        involutive_note(m, &worst, out);
    }
    forms_free(&f);
    return ok;
}
