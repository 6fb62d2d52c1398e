/* generic.h - the generic evaluator: Phi, Phi_q, nu and gamma from the joint list, without generated code.
 *
 * Standard joints use the textbook body-coordinate formulas (generic_joints.c;
 * spatial joints, and spatial angle() and slide() drivers, over Euler
 * parameters: generic_spatial.c); other `constraint`, `driver` and
 * `velocity` rows and joint options are interpreted (interp.h). Nothing here uses the symbolic derivatives, so
 * the generic evaluator and the generated code check each other.
 *
 * Everything is allocated by generic_open; the evaluation calls allocate
 * nothing. A Generic holds scratch memory: one Generic serves one thread
 * at a time.
 */
#ifndef MECHC_GENERIC_H
#define MECHC_GENERIC_H

#include "../model/model.h"

typedef struct Generic Generic;

/* Prepares the evaluator for model (which must outlive it). */
Generic *generic_open(const Model *model);
void generic_free(Generic *g);

/* The generated kernels' interface (spec section 4). */
void generic_phi(Generic *g, const double *q, double t, double *phi);        /* nh */
void generic_jac(Generic *g, const double *q, double t, double *jac);        /* nr*nq, row-major */
void generic_nu(Generic *g, const double *q, double t, double *nu);          /* nr */
void generic_gamma(Generic *g, const double *q, const double *qd, double t, double *gamma); /* nr */
void generic_all(Generic *g, const double *q, const double *qd, double t,
                 double *phi, double *jac, double *nu, double *gamma);

/* Psi(q, qd, t) of the velocity-level rows (nv values): what the rows say
   before they are split into Jacobian and nu; for finite differences. */
void generic_psi(Generic *g, const double *q, const double *qd, double t, double *psi);

/* Dynamics, for a model with masses (generic_dynamics.c): M (nq*nq,
   row-major) and Q (nq) from the mass elements and forces by forward-mode
   derivatives of their expressions, not from the symbolic ones. */
void generic_mass(Generic *g, const double *q, double *M);
void generic_force(Generic *g, const double *q, const double *qd, double t, double *Q);
/* M's nonzeros in a given pattern (row-major, rows then columns
   ascending: the generated PREFIX_mass_nz's, generator/diff/dynamics.c),
   which generic_mass_pattern takes once (it keeps no pointer to it);
   a product outside the pattern is left out (check compares M too). */
void generic_mass_pattern(Generic *g, const int *row, const int *col, int nnz);
void generic_mass_nz(Generic *g, const double *q, double *vals);
/* Q's velocity terms alone, -m p_q^T D(D(p)) - J theta_q^T D(D(theta)). */
void generic_velocity_terms(Generic *g, const double *q, const double *qd, double *Qv);

/* How many rows the interpreter runs (constraint, driver and velocity
   rows); every other row is a joint's formula. */
int generic_interpreted_rows(const Generic *g);

#endif
