/* design.c - dPhi/dp of each engine: the generated PREFIX_phi_p, or the graph interpreted. */
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
    e->phi_p_values = xmalloc(sizeof *e->phi_p_values);
    node_values_init(e->phi_p_values, &m->dag, kin->phi_p, m->nh * m->np);
}

void engine_design_free(Engine *e)
{
    if (!e->phi_p_values)
        return;
    node_values_free(e->phi_p_values);
    free(e->phi_p_values);
    e->phi_p_values = NULL;
}

void engine_phi_p(const Engine *e, const double *q, double t, double *phi_p)
{
    int n = e->mech->model->nh * e->mech->model->np;
    if (e->compiled) {
        e->kernels.phi_p(q, t, phi_p);
        return;
    }
    node_values_run(e->phi_p_values, q, NULL, t);
    for (int k = 0; k < n; k++)
        phi_p[k] = node_values_get(e->phi_p_values, k);
}
