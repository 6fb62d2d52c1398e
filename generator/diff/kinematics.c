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
#include "diff.h"

#include <stdlib.h>
#include <string.h>

void support_init(SupportScan *scan)
{
    memset(scan, 0, sizeof *scan);
}

void support_free(SupportScan *scan)
{
    free(scan->mark);
    free(scan->stack);
    memset(scan, 0, sizeof *scan);
}

int support_collect(SupportScan *scan, const Dag *dag, NodeId e, DagOp leaf, int *out)
{
    /* The graph grows while derivatives are built: keep the marks in step. */
    if (scan->cap < dag->count) {
        int cap = dag->count * 2;
        scan->mark = xrealloc(scan->mark, (size_t)cap, sizeof *scan->mark);
        scan->stack = xrealloc(scan->stack, (size_t)cap, sizeof *scan->stack);
        memset(scan->mark + scan->cap, 0, (size_t)(cap - scan->cap) * sizeof *scan->mark);
        scan->cap = cap;
    }
    if (++scan->stamp == 0) {           /* wrapped: clear and restart */
        memset(scan->mark, 0, (size_t)scan->cap * sizeof *scan->mark);
        scan->stamp = 1;
    }
    int top = 0, n = 0;
    scan->mark[e] = scan->stamp;
    scan->stack[top++] = e;
    while (top > 0) {
        const DagNode *node = dag_node(dag, scan->stack[--top]);
        if (node->op == leaf) {
            out[n++] = node->a;
            continue;
        }
        int arity = dag_op_info[node->op].arity;
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < arity; k++) {
            if (scan->mark[kids[k]] != scan->stamp) {
                scan->mark[kids[k]] = scan->stamp;
                scan->stack[top++] = kids[k];
            }
        }
    }
    /* ascending order (insertion sort: a row touches few coordinates) */
    for (int i = 1; i < n; i++)
        for (int k = i; k > 0 && out[k - 1] > out[k]; k--) {
            int t = out[k];
            out[k] = out[k - 1];
            out[k - 1] = t;
        }
    return n;
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

    jmp_buf escape, *saved = diag->escape;
    diag->escape = &escape;         /* the graph's node limit lands here */
    Differ df;
    differ_init(&df, dag, m->nq);
    SupportScan scan;
    support_init(&scan);
    int *cols = xmalloc((size_t)m->nq * sizeof *cols);
    int *inner = xmalloc((size_t)m->nq * sizeof *inner);
    int cap = 16;
    /* volatile: reallocated between setjmp and a possible longjmp, after
       which a register copy would be stale (C11 7.13.2.1) */
    JacEntry *volatile jac = xmalloc((size_t)cap * sizeof *jac);
    bool ok = true;
    if (setjmp(escape) != 0) {
        ok = false;
        goto done;
    }
    for (int r = 0; r < m->nr; r++) {
        const Row *row = &m->rows[r];
        dag->where = row->pos.offset;       /* a node-limit error names the row */
        kin->row_start[r] = kin->nnz;
        int ncols;
        if (!row->velocity) {
            kin->phi[r] = row->expr;
            ncols = support_collect(&scan, dag, row->expr, OP_VAR, cols);
            kin->nu[r] = dag_neg(dag, diff_by_t(&df, row->expr));
            kin->gamma[r] = dag_neg(dag, diff_total(&df, diff_total(&df, row->expr)));
        } else {
            ncols = support_collect(&scan, dag, row->expr, OP_VARD, cols);
            if (ncols == 0) {
                diag_error(diag, row->pos,
                           "velocity row '%s' has no der() term left once simplified: it "
                           "constrains no velocity (write a position row as a 'constraint')",
                           row->name);
                ok = false;
                goto done;
            }
            kin->nu[r] = dag_neg(dag, diff_without_velocities(&df, row->expr));
            kin->gamma[r] = dag_neg(dag, diff_total(&df, row->expr));
        }
        for (int k = 0; k < ncols; k++) {
            NodeId v = row->velocity ? diff_by_qd(&df, row->expr, cols[k])
                                     : diff_by_q(&df, row->expr, cols[k]);
            if (dag_is_zero(dag, v))
                continue;
            if (row->velocity && support_collect(&scan, dag, v, OP_VARD, inner) > 0) {
                StrBuf sb;
                sb_init(&sb);
                dag_format(dag, v, m->coord_names, &sb);
                diag_error(diag, row->pos,
                           "velocity row '%s' is not affine in der(): its coefficient of "
                           "der(%s) is %s, which still contains der()",
                           row->name, m->coord_names[cols[k]], sb.data);
                sb_free(&sb);
                ok = false;
                goto done;
            }
            if (kin->nnz == cap) {
                cap *= 2;
                jac = xrealloc(jac, (size_t)cap, sizeof *jac);
            }
            jac[kin->nnz++] = (JacEntry){.row = r, .col = cols[k], .value = v};
        }
    }
    kin->row_start[m->nr] = kin->nnz;
    kin->jac = arena_alloc_array(&m->arena, (size_t)kin->nnz + 1, sizeof *kin->jac);
    memcpy(kin->jac, jac, (size_t)kin->nnz * sizeof *jac);
done:
    dag->where = -1;
    diag->escape = saved;
    free(jac);
    free(cols);
    free(inner);
    support_free(&scan);
    differ_free(&df);
    return ok;
}
