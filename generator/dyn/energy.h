/* energy.h - the energy balance of sim: E = T - W, T from the mass kernel, W the work of the forces. */
#ifndef MECHC_DYN_ENERGY_H
#define MECHC_DYN_ENERGY_H

#include "sim_state.h"

/* 1/2 qd^T Mdot qd by a central difference of M along qd. */
double sim_half_mdot(Sim *s, const double *q, const double *qd);

/* qd^T M x for the n x n row-major M. */
double sim_quad_form(int n, const double *m, const double *qd, const double *x);

/* E = T - W at the state y, and the drift against E(t0) (first: E(t0) itself). */
void sim_watch_energy(Sim *s, const double *y, bool first);

#endif
