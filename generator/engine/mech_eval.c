/* mech_eval.c - Phi and the Jacobian's nonzeros of a mechanism as one interpreted program of its graph.
 *
 * Phi and the Jacobian's nonzeros are the roots of one program of the graph
 * interpreter (generator/eval/interp.h), compiled once: each evaluation is
 * one loop over the reachable nodes in id order. It needs no code
 * generation and works on the same graph as the rest of `info`.
 */
#include "mech_eval.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

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
    node_values_init(&me->values, &m->dag, roots, nroots);
    free(roots);
}

void mech_eval_free(MechEval *me)
{
    node_values_free(&me->values);
    memset(me, 0, sizeof *me);
}

/* Runs the program at (q, t) and copies Phi out (phi may be NULL). */
static void eval_phi(MechEval *me, const double *q, double t, double *phi)
{
    node_values_run(&me->values, q, NULL, t);
    if (phi)
        for (int i = 0; i < me->nh; i++)
            phi[i] = node_values_get(&me->values, i);
}

void mech_eval(MechEval *me, const double *q, double t, double *phi, double *jac)
{
    const Kinematics *kin = me->kin;
    eval_phi(me, q, t, phi);
    if (jac) {
        memset(jac, 0, (size_t)me->nr * (size_t)me->nq * sizeof *jac);
        for (int e = 0; e < kin->nnz; e++)
            jac[(size_t)kin->jac[e].row * (size_t)me->nq + (size_t)kin->jac[e].col] =
                node_values_get(&me->values, me->nh + e);
    }
}

void mech_eval_nz(MechEval *me, const double *q, double t, double *phi, double *vals)
{
    eval_phi(me, q, t, phi);
    if (vals)
        for (int e = 0; e < me->kin->nnz; e++)
            vals[e] = node_values_get(&me->values, me->nh + e);
}

static void kernel_phi(void *ctx, const double *q, double t, double *phi)
{
    mech_eval(ctx, q, t, phi, NULL);
}

static void kernel_jac(void *ctx, const double *q, double t, double *jac)
{
    mech_eval(ctx, q, t, NULL, jac);
}

MechrtKernels mech_eval_kernels(MechEval *me)
{
    return (MechrtKernels){.nq = me->nq, .nh = me->nh, .nv = me->nr - me->nh, .ctx = me,
                           .phi = kernel_phi, .jac = kernel_jac};
}
