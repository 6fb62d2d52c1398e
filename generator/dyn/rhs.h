/* rhs.h - the right-hand side of sim for GSL: f = (qd, qdd, dW/dt), dense or sparse, cached, and its Jacobian. */
#ifndef MECHC_DYN_RHS_H
#define MECHC_DYN_RHS_H

#include "sim_state.h"

/* f = (qd, qdd, dE/dt) at (t, y): GSL's gsl_odeiv2_system function (params: the Sim). */
int sim_rhs(double t, const double y[], double f[], void *params);

/* Forward differences of the right side for the implicit methods. */
int sim_jacobian(double t, const double y[], double *dfdy, double dfdt[], void *params);

/* f at (t, y) kept for a repeated evaluation. */
void sim_cache_store(Sim *s, double t, const double *y, const double *f);

/* The cache holds f at (t, y). */
bool sim_cache_has(const Sim *s, double t, const double *y);

#endif
