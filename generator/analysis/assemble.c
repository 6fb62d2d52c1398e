/* assemble.c - graph interpreter and minimum-norm Newton assembly on any set of holonomic rows.
 *
 * The interpreter marks the nodes reachable from its roots once, then each
 * run is one loop over them in id order (operands have smaller ids), using
 * dag_op_eval, the single definition of every operation. It needs no code
 * generation, so `info` also evaluates nodes it builds itself (the
 * integrability test).
 *
 * Minimum-norm Newton (Gauss-Newton through the pseudo-inverse; Ben-Israel
 * 1966, Deuflhard, Newton Methods for Nonlinear Problems, 4.4):
 *     dq = -pinv(Phi_q(q)) Phi(q),   q <- q + alpha dq
 * pinv from the SVD with singular values at or below the rank tolerance
 * dropped. With fewer rows than coordinates this is the shortest step that
 * zeroes the linearised rows, so the iteration settles on the configuration
 * nearest the start; with redundant rows the dropped singular values are
 * the dependent directions. alpha is halved (at most 12 times) until the
 * residual's 2-norm decreases.
 */
#include "analysis.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

AnalysisOptions analysis_default_options(void)
{
    return (AnalysisOptions){
        .tol_phi = 1e-10,
        .tol_dq = 1e-10,
        .max_iter = 60,
        .rank_tol = -1.0,
        .samples = 8,
        .seed = 20240605u,
        .generic_samples = 3,
        .max_dense = 5e5,
    };
}

/* ---- graph interpreter ---- */

struct NodeEval {
    const Dag *dag;
    NodeId *order;      /* reachable nodes, ascending ids */
    int count;
    double *value;      /* indexed by node id (size dag->count at creation) */
    int32_t known;      /* dag->count at creation */
};

NodeEval *node_eval_new(const Dag *dag, const NodeId *roots, int nroots)
{
    NodeEval *ev = xcalloc(1, sizeof *ev);
    ev->dag = dag;
    ev->known = dag->count;
    size_t n = (size_t)dag->count;
    uint32_t *mark = xcalloc(n, sizeof *mark);
    NodeId *stack = xmalloc(n * sizeof *stack);
    ev->count = dag_mark_reachable(dag, roots, nroots, mark, 1, stack);
    ev->order = xmalloc(((size_t)ev->count + 1) * sizeof *ev->order);
    int k = 0;
    for (int32_t id = 0; id < dag->count; id++)
        if (mark[id] == 1)
            ev->order[k++] = id;
    ev->count = k;
    ev->value = xcalloc(n + 1, sizeof *ev->value);
    free(mark);
    free(stack);
    return ev;
}

void node_eval_free(NodeEval *ev)
{
    if (!ev)
        return;
    free(ev->order);
    free(ev->value);
    free(ev);
}

void node_eval_run(NodeEval *ev, const double *q, const double *qd, double t)
{
    const DagNode *nodes = ev->dag->nodes;
    double *v = ev->value;
    for (int k = 0; k < ev->count; k++) {
        NodeId id = ev->order[k];
        const DagNode *n = &nodes[id];
        switch ((DagOp)n->op) {
        case OP_CONST: v[id] = n->value; break;
        case OP_VAR:   v[id] = q[n->a]; break;
        case OP_VARD:  v[id] = qd ? qd[n->a] : 0.0; break;
        case OP_TIME:  v[id] = t; break;
        default:
            v[id] = dag_op_eval((DagOp)n->op, v[n->a],
                                dag_op_info[n->op].arity == 2 ? v[n->b] : 0.0);
            break;
        }
    }
}

double node_eval_value(const NodeEval *ev, NodeId id)
{
    return id >= 0 && id < ev->known ? ev->value[id] : NAN;
}

/* ---- Phi and Phi_q of a mechanism ---- */

void mech_eval_init(MechEval *me, const Kinematics *kin)
{
    const Model *m = kin->model;
    me->kin = kin;
    me->nq = m->nq;
    me->nh = m->nh;
    me->nr = m->nr;
    int nroots = m->nh + kin->nnz;
    NodeId *roots = xmalloc(((size_t)nroots + 1) * sizeof *roots);
    for (int i = 0; i < m->nh; i++)
        roots[i] = kin->phi[i];
    for (int e = 0; e < kin->nnz; e++)
        roots[m->nh + e] = kin->jac[e].value;
    me->ev = node_eval_new(&m->dag, roots, nroots);
    free(roots);
}

void mech_eval_free(MechEval *me)
{
    node_eval_free(me->ev);
    memset(me, 0, sizeof *me);
}

void mech_eval(MechEval *me, const double *q, double t, double *phi, double *jac)
{
    const Kinematics *kin = me->kin;
    node_eval_run(me->ev, q, NULL, t);
    if (phi)
        for (int i = 0; i < me->nh; i++)
            phi[i] = node_eval_value(me->ev, kin->phi[i]);
    if (jac) {
        memset(jac, 0, (size_t)me->nr * (size_t)me->nq * sizeof *jac);
        for (int e = 0; e < kin->nnz; e++)
            jac[(size_t)kin->jac[e].row * (size_t)me->nq + (size_t)kin->jac[e].col] =
                node_eval_value(me->ev, kin->jac[e].value);
    }
}

void mech_eval_nz(MechEval *me, const double *q, double t, double *phi, double *vals)
{
    const Kinematics *kin = me->kin;
    node_eval_run(me->ev, q, NULL, t);
    if (phi)
        for (int i = 0; i < me->nh; i++)
            phi[i] = node_eval_value(me->ev, kin->phi[i]);
    if (vals)
        for (int e = 0; e < kin->nnz; e++)
            vals[e] = node_eval_value(me->ev, kin->jac[e].value);
}

/* ---- minimum-norm Newton ---- */

/* Phi and Phi_q of the selected rows at q; returns ||f||_2 (NaN if not finite). */
static double rows_eval(MechEval *me, const int *rows, int nrows, const double *q, double t,
                        double *phi_all, double *jac_all, double *f, double *jac,
                        double *inf_norm, int *worst)
{
    mech_eval(me, q, t, phi_all, jac_all ? jac : NULL);
    double sum = 0.0, inf = 0.0;
    int nq = me->nq;
    *worst = -1;
    for (int i = 0; i < nrows; i++) {
        f[i] = phi_all[rows[i]];
        if (jac_all)
            memcpy(jac_all + (size_t)i * (size_t)nq, jac + (size_t)rows[i] * (size_t)nq,
                   (size_t)nq * sizeof *jac);
        if (!isfinite(f[i]))
            return NAN;
        sum += f[i] * f[i];
        if (fabs(f[i]) > inf || *worst < 0) {
            inf = fabs(f[i]);
            *worst = rows[i];
        }
    }
    *inf_norm = inf;
    return sqrt(sum);
}

bool analysis_assemble(MechEval *me, const int *rows, int nrows, double t, double *q,
                       const AnalysisOptions *opt, SvdWork *w, AssembleResult *res)
{
    int nq = me->nq;
    memset(res, 0, sizeof *res);
    res->step = -1.0;
    res->worst_row = -1;
    res->rank = -1;
    if (nrows == 0) {
        res->converged = true;
        return true;
    }
    double *phi_all = xcalloc((size_t)me->nh + 1, sizeof *phi_all);
    double *jac = xcalloc((size_t)me->nr * (size_t)nq + 1, sizeof *jac);
    double *J = xcalloc((size_t)nrows * (size_t)nq, sizeof *J);
    double *f = xcalloc((size_t)nrows, sizeof *f);
    double *ftrial = xcalloc((size_t)nrows, sizeof *ftrial);
    double *dq = xcalloc((size_t)nq, sizeof *dq);
    double *trial = xcalloc((size_t)nq, sizeof *trial);
    double inf = 0.0;
    int worst = -1;
    double norm = rows_eval(me, rows, nrows, q, t, phi_all, J, f, jac, &inf, &worst);
    res->residual = inf;
    res->worst_row = worst;
    bool ok = false;
    for (int iter = 0; isfinite(norm); iter++) {
        if (inf <= opt->tol_phi && (res->step < 0 || res->step <= opt->tol_dq)) {
            ok = true;
            break;
        }
        if (iter >= opt->max_iter)
            break;
        SvdResult sv;
        if (!analysis_svd(w, J, nrows, nq, nq, opt->rank_tol, &sv))
            break;
        res->rank = sv.rank;
        svd_pinv_solve(w, f, dq);
        double step = 0.0;
        for (int j = 0; j < nq; j++) {
            dq[j] = -dq[j];
            step = fmax(step, fabs(dq[j]));
        }
        /* step halving until the residual decreases (or is already small) */
        double alpha = 1.0, tnorm = NAN, tinf = 0.0;
        int tworst = -1;
        for (int h = 0; h <= 12; h++) {
            for (int j = 0; j < nq; j++)
                trial[j] = q[j] + alpha * dq[j];
            tnorm = rows_eval(me, rows, nrows, trial, t, phi_all, NULL, ftrial, jac, &tinf, &tworst);
            if (isfinite(tnorm) && (tnorm < norm || tinf <= opt->tol_phi))
                break;
            alpha *= 0.5;
        }
        if (!isfinite(tnorm) || !(tnorm < norm || tinf <= opt->tol_phi)) {
            /* no descent along the Newton direction: take the full step */
            alpha = 1.0;
            for (int j = 0; j < nq; j++)
                trial[j] = q[j] + dq[j];
        }
        memcpy(q, trial, (size_t)nq * sizeof *q);
        res->iterations = iter + 1;
        res->step = alpha * step;
        norm = rows_eval(me, rows, nrows, q, t, phi_all, J, f, jac, &inf, &worst);
        res->residual = isfinite(norm) ? inf : NAN;
        res->worst_row = worst;
    }
    res->converged = ok;
    free(phi_all), free(jac), free(J), free(f), free(ftrial), free(dq), free(trial);
    return ok;
}
