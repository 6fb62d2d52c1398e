/* design.c - the sensitivity functions of each engine: the generated ones (PREFIX_phi_p, PREFIX_sens_v, ...), or the graph interpreted. */
#include "engine.h"

#include "../base/arena.h"
#include "../eval/interp.h"

#include <stdlib.h>

void engine_design_open(Engine *e)
{
    const Kinematics *kin = &e->mech->kin;
    const Model *m = kin->model;
    if (m->np == 0)
        return;
    e->design_values = xcalloc(DESIGN_FN_COUNT, sizeof *e->design_values);
    for (int fn = 0; fn < DESIGN_FN_COUNT; fn++) {
        const NodeId *from[DESIGN_Y_COUNT];
        size_t count[DESIGN_Y_COUNT], total = 0;
        int arrays = design_arrays(kin, (DesignFn)fn, from, count);
        for (int i = 0; i < arrays; i++)
            total += count[i];
        NodeId *roots = xcalloc(total + 1, sizeof *roots), *at = roots;
        for (int i = 0; i < arrays; i++)
            for (size_t k = 0; k < count[i]; k++)
                *at++ = from[i][k];
        node_values_init(&e->design_values[fn], &m->dag, roots, (int)total);
        free(roots);
    }
}

void engine_design_free(Engine *e)
{
    if (!e->design_values)
        return;
    for (int fn = 0; fn < DESIGN_FN_COUNT; fn++)
        node_values_free(&e->design_values[fn]);
    free(e->design_values);
    e->design_values = NULL;
}

/* The compiled unit's function fn. */
static void call_compiled(const Kernels *k, DesignFn fn, const double *q, const double *qd,
                          double t, double *const *o)
{
    switch (fn) {
    case DESIGN_PHI_P:
        k->phi_p(q, t, o[0]);
        return;
    case DESIGN_V:
        k->sens_v(q, qd, t, o[0], o[1]);
        return;
    case DESIGN_G:
        k->sens_g(q, qd, t, o[0], o[1], o[2]);
        return;
    case DESIGN_PHI_P_NZ:
        k->phi_p_nz(q, t, o[0]);
        return;
    case DESIGN_Y:
    case DESIGN_FN_COUNT:
        break;
    }
    k->sens_y(q, qd, t, o[0], o[1], o[2], o[3], o[4], o[5], o[6], o[7]);
}

void engine_design(const Engine *e, DesignFn fn, const double *q, const double *qd, double t,
                   double *const *out)
{
    if (e->compiled) {
        call_compiled(&e->kernels, fn, q, qd, t, out);
        return;
    }
    const NodeId *from[DESIGN_Y_COUNT];
    size_t count[DESIGN_Y_COUNT];
    int arrays = design_arrays(&e->mech->kin, fn, from, count), at = 0;
    NodeValues *nv = &e->design_values[fn];
    node_values_run(nv, q, qd, t);
    for (int i = 0; i < arrays; i++)
        for (size_t k = 0; k < count[i]; k++)
            out[i][k] = node_values_get(nv, at++);
}

void engine_phi_p(const Engine *e, const double *q, double t, double *phi_p)
{
    double *const out[DESIGN_Y_COUNT] = {phi_p};
    engine_design(e, DESIGN_PHI_P, q, NULL, t, out);
}
