/* kkt.h - the sparse path of sim: accelerations from the augmented matrix [M Phi_A^T; Phi_A 0] on KLU. */
#ifndef MECHC_DYN_KKT_H
#define MECHC_DYN_KKT_H

#include "sim_state.h"

/* y = Phi_q x over the Jacobian's nonzeros (nr rows). */
void sim_sparse_jac_times(const Sim *s, const double *x, double *y);

/* qd^T M x over M's nonzeros vals. */
double sim_sparse_mass_form(const Sim *s, const double *vals, const double *qd, const double *x);

/* M's nonzeros at q into vals (counted). */
void sim_sparse_mass(Sim *s, const double *q, double *vals);

/* Every one of the n values is finite. */
bool sim_all_finite(int n, const double *v);

/* Phi, Phi_q's nonzeros, nu and gamma at the state (one all_nz call), and
   with dynamics M's nonzeros and Q. */
MechrtStatus sim_sparse_eval(Sim *s, const double *q, const double *qd, double t, bool dynamics);

/* [M Phi_A^T; Phi_A 0] factored at (q, t) with the step's rows, reused
   where the factors are already there. */
MechrtStatus sim_sparse_mass_factor(Sim *s, const double *q, double t);

/* qdd (and lambda, nr, when not NULL) from [M Phi_A^T; Phi_A 0] with the
   rows of active (NULL: all). */
MechrtStatus sim_sparse_accel(Sim *s, const double *q, const double *qd, double t,
                              const unsigned char *active, double *qdd, double *lambda);

#endif
