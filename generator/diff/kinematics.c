/* kinematics.c - the constraint Jacobian, nu and gamma of every row, by symbolic differentiation.
 *
 * Position row Phi:  jac = dPhi/dq (only the coordinates it depends on),
 *                    nu = -dPhi/dt, gamma = -D(D(Phi)) (see diff_total).
 * Velocity row Psi = a(q,t)^T qd + b(q,t):
 *                    jac = a = dPsi/dqd, nu = -b = -Psi(qd = 0),
 *                    gamma = -(dPsi/dq qd + dPsi/dt) = -D(Psi).
 * Work is proportional to the size of each row's expression times the
 * coordinates it touches, so it stays linear in the mechanism's size.
 */
#include "kinematics.h"

#include "../base/strbuf.h"
#include "../dag/support.h"
#include "diff.h"

#include <stdlib.h>
#include <string.h>

/* Scratch of one pass over the rows. */
typedef struct Work {
    Differ df;
    SupportScan scan;
    int *cols, *inner;      /* nq each */
    JacEntry *jac;          /* grows; copied into the arena at the end */
    int cap;
} Work;

static void push_entry(Work *w, Kinematics *kin, JacEntry entry)
{
    if (kin->nnz == w->cap) {
        w->cap *= 2;
        w->jac = xrealloc(w->jac, (size_t)w->cap, sizeof *w->jac);
    }
    w->jac[kin->nnz++] = entry;
}

static void not_affine(const Model *m, const Row *row, int col, NodeId coef, Diag *diag)
{
    StrBuf sb;
    sb_init(&sb);
    dag_format(&m->dag, coef, m->coord_names, &sb);
    diag_error(diag, row->pos,
               "velocity row '%s' is not affine in der(): its coefficient of "
               "der(%s) is %s, which still contains der()",
               row->name, m->coord_names[col], sb.data);
    sb_free(&sb);
}

/* Row r's nu, gamma and Jacobian entries (and Phi for a position row).
   False with diag filled when a velocity row constrains no velocity or is
   not affine in der(). Past the node limit it stops early and returns
   true: the caller reports the limit. */
static bool build_row(Model *m, Kinematics *kin, Work *w, int r, Diag *diag)
{
    Dag *dag = &m->dag;
    const Row *row = &m->rows[r];
    int ncols = support_collect(&w->scan, dag, row->expr, row->velocity ? OP_VARD : OP_VAR, w->cols);
    if (!row->velocity) {
        kin->phi[r] = row->expr;
        kin->nu[r] = dag_neg(dag, diff_by_t(&w->df, row->expr));
        kin->gamma[r] = dag_neg(dag, diff_total(&w->df, diff_total(&w->df, row->expr)));
    } else if (ncols == 0) {
        diag_error(diag, row->pos,
                   "velocity row '%s' has no der() term left once simplified: it "
                   "constrains no velocity (write a position row as a 'constraint')", row->name);
        return false;
    } else {
        kin->nu[r] = dag_neg(dag, diff_without_velocities(&w->df, row->expr));
        kin->gamma[r] = dag_neg(dag, diff_total(&w->df, row->expr));
    }
    for (int k = 0; k < ncols; k++) {
        NodeId v = row->velocity ? diff_by_qd(&w->df, row->expr, w->cols[k])
                                 : diff_by_q(&w->df, row->expr, w->cols[k]);
        if (dag->overflow)
            return true;
        if (dag_is_zero(dag, v))
            continue;
        if (row->velocity && support_collect(&w->scan, dag, v, OP_VARD, w->inner) > 0) {
            not_affine(m, row, w->cols[k], v, diag);
            return false;
        }
        push_entry(w, kin, (JacEntry){.row = r, .col = w->cols[k], .value = v});
    }
    return true;
}

bool kinematics_build(Model *m, Kinematics *kin, Diag *diag)
{
    Dag *dag = &m->dag;
    memset(kin, 0, sizeof *kin);
    kin->model = m;
    kin->phi = arena_alloc_array(&m->arena, (size_t)m->nh + 1, sizeof *kin->phi);
    kin->nu = arena_alloc_array(&m->arena, (size_t)m->nr, sizeof *kin->nu);
    kin->gamma = arena_alloc_array(&m->arena, (size_t)m->nr, sizeof *kin->gamma);
    kin->row_start = arena_alloc_array(&m->arena, (size_t)m->nr + 1, sizeof *kin->row_start);

    Work w = {.cap = 16};
    differ_init(&w.df, dag, m->nq);
    support_init(&w.scan);
    w.cols = xmalloc((size_t)m->nq * sizeof *w.cols);
    w.inner = xmalloc((size_t)m->nq * sizeof *w.inner);
    w.jac = xmalloc((size_t)w.cap * sizeof *w.jac);
    bool ok = true;
    for (int r = 0; r < m->nr && ok && !dag->overflow; r++) {
        dag->where = m->rows[r].pos.offset;     /* a node-limit error names the row */
        kin->row_start[r] = kin->nnz;
        ok = build_row(m, kin, &w, r, diag);
    }
    ok = ok && dag_check_limit(dag, diag);
    dag->where = -1;
    if (ok) {
        kin->row_start[m->nr] = kin->nnz;
        kin->jac = arena_alloc_array(&m->arena, (size_t)kin->nnz + 1, sizeof *kin->jac);
        memcpy(kin->jac, w.jac, (size_t)kin->nnz * sizeof *w.jac);
    }
    if (ok && m->nmasses > 0)
        ok = dynamics_build(m, &kin->dyn, diag);
    if (ok && m->np > 0)        /* after everything else: files without design keep their ids */
        ok = design_build(m, kin, diag);
    ok = ok && dag_check_finite(dag, diag);     /* the model's constants, and M's and Q's */
    free(w.jac);
    free(w.cols);
    free(w.inner);
    support_free(&w.scan);
    differ_free(&w.df);
    return ok;
}
