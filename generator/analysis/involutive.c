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
#include "analysis.h"

#include "../base/arena.h"
#include "../base/strbuf.h"
#include "../diff/diff.h"

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

bool analysis_involutivity(Model *m, const int *rows, int nrows, const double *points,
                           const double *times, int npoints, Involutivity *out, Diag *diag)
{
    memset(out, 0, sizeof *out);
    int nq = m->nq, n = nq + 1;
    Dag *dag = &m->dag;
    Entries *coef = xcalloc(1, sizeof *coef), *part = xcalloc(1, sizeof *part);
    Differ *df = xcalloc(1, sizeof *df);
    SupportScan *scan = xcalloc(1, sizeof *scan);
    int *buf = xmalloc(((size_t)n + 1) * sizeof *buf);
    int *vel = xmalloc(((size_t)nrows + 1) * sizeof *vel);     /* rows[k] for velocity k */
    differ_init(df, dag, nq);
    support_init(scan);
    int nvel = 0;

    Diag *dd = dag->diag;
    jmp_buf escape, *saved = dd->escape;
    dd->escape = &escape;
    bool ok = true;
    if (setjmp(escape) != 0) {
        ok = false;
        if (diag != dd)
            *diag = *dd;
        goto done;
    }
    for (int k = 0; k < nrows; k++) {
        const Row *row = &m->rows[rows[k]];
        if (!row->velocity) {
            int ns = support_collect(scan, dag, row->expr, OP_VAR, buf);
            for (int i = 0; i < ns; i++)
                push(coef, k, buf[i], 0, diff_by_q(df, row->expr, buf[i]));
            push(coef, k, nq, 0, diff_by_t(df, row->expr));
            continue;
        }
        vel[nvel++] = k;
        int first = coef->n;
        int ns = support_collect(scan, dag, row->expr, OP_VARD, buf);
        for (int i = 0; i < ns; i++)
            push(coef, k, buf[i], 0, diff_by_qd(df, row->expr, buf[i]));
        push(coef, k, nq, 0, diff_without_velocities(df, row->expr));
        for (int e = first; e < coef->n; e++) {
            NodeId c = coef->e[e].node;
            int j = coef->e[e].j;
            int nv = support_collect(scan, dag, c, OP_VAR, buf);
            for (int i = 0; i < nv; i++)
                push(part, k, j, buf[i], diff_by_q(df, c, buf[i]));
            if (support_collect(scan, dag, c, OP_TIME, buf) > 0)
                push(part, k, j, nq, diff_by_t(df, c));
        }
    }
    if (nvel == 0) {
        out->note = strdup("no velocity-level rows");
        goto done;
    }
    {
        int nroots = coef->n + part->n;
        NodeId *roots = xmalloc(((size_t)nroots + 1) * sizeof *roots);
        for (int e = 0; e < coef->n; e++)
            roots[e] = coef->e[e].node;
        for (int e = 0; e < part->n; e++)
            roots[coef->n + e] = part->e[e].node;
        NodeValues ev;          /* value e: coef->e[e], value coef->n + e: part->e[e] */
        node_values_init(&ev, dag, roots, nroots);
        free(roots);
        size_t nn = (size_t)n * (size_t)n;
        double *C = xmalloc((size_t)nrows * (size_t)n * sizeof *C);
        double *B = xmalloc((size_t)n * (size_t)n * sizeof *B);
        double *W = xmalloc(nn * sizeof *W), *M = xmalloc(nn * sizeof *M);
        double *scratch = xmalloc(2 * nn * sizeof *scratch);
        MechrtSvd *w = svd_work_new(nrows, n);
        double worst = 0.0;
        int worst_row = -1, worst_point = -1;
        for (int p = 0; p < npoints; p++) {
            node_values_run(&ev, points + (size_t)p * (size_t)nq, NULL, times[p]);
            memset(C, 0, (size_t)nrows * (size_t)n * sizeof *C);
            for (int e = 0; e < coef->n; e++)
                C[(size_t)coef->e[e].k * (size_t)n + (size_t)coef->e[e].j] =
                    node_values_get(&ev, e);
            MechrtSvdResult sv;
            if (!mechrt_svd(w, C, nrows, n, n, -1.0, &sv))
                continue;               /* NaN or Inf here: skip the point */
            int r = sv.rank;
            for (int j = 0; j < n; j++)
                for (int c = 0; c < r; c++)
                    B[j * r + c] = mechrt_svd_row_basis(w, j, c);
            bool finite = true;
            for (int v = 0; v < nvel && finite; v++) {
                memset(W, 0, nn * sizeof *W);
                double scale = 0.0;
                for (int e = 0; e < part->n; e++) {
                    if (part->e[e].k != vel[v])
                        continue;
                    double x = node_values_get(&ev, coef->n + e);   /* d_l a_j */
                    int j = part->e[e].j, l = part->e[e].l;
                    W[l * n + j] += x;
                    W[j * n + l] -= x;
                    finite = finite && isfinite(x);
                }
                for (size_t i = 0; i < nn; i++)
                    scale = fmax(scale, fabs(W[i]));
                if (!finite || scale == 0.0)
                    continue;
                project(n, r, B, W, M, scratch);
                double big = 0.0;
                for (size_t i = 0; i < nn; i++)
                    big = fmax(big, fabs(M[i]));
                if (big / scale > worst) {
                    worst = big / scale;
                    worst_row = rows[vel[v]];
                    worst_point = p;
                }
            }
            if (finite)
                out->points++;
        }
        mechrt_svd_free(w);
        node_values_free(&ev);
        free(C), free(B), free(W), free(M), free(scratch);
        StrBuf sb;
        sb_init(&sb);
        out->tested = out->points > 0;
        if (!out->tested) {
            sb_puts(&sb, "not tested: no configuration could be evaluated");
        } else if (worst > INVOLUTIVE_RTOL) {
            out->involutive = false;
            sb_printf(&sb, "nonholonomic: d omega of row %s does not vanish on the allowed "
                      "velocities (%.3g of its size) at %s configuration",
                      m->rows[worst_row].name, worst, worst_point == 0 ? "the assembled" : "a sampled");
        } else {
            out->involutive = true;
            sb_printf(&sb, "holonomic: the allowed velocities form an involutive distribution at "
                      "%d configuration%s (numerical evidence)", out->points,
                      out->points == 1 ? "" : "s");
        }
        out->note = sb_take(&sb);
    }
done:
    dd->escape = saved;
    free(coef->e), free(coef), free(part->e), free(part);
    support_free(scan), free(scan);
    differ_free(df), free(df);
    free(buf), free(vel);
    return ok;
}
