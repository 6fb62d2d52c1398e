/* reactions.h - the forces planar joints apply to their second bodies, from the multipliers of inverse dynamics (run --forces pictures). */
#ifndef MECHC_REACTIONS_H
#define MECHC_REACTIONS_H

#include "../model/model.h"
#include "svg_anim.h"

/* For every planar revolute, weld, prismatic, pointline and distance
   joint (at most max): the global force its rows' multipliers apply to its
   second body, at its second attachment, at each of the n frames
   q[k*nq ...], lambda[k*nr ...] (signed as in M qdd + Phi_q^T lambda = Q):
     revolute, weld      (lambda(J.x), lambda(J.y))
     prismatic, pointline -lambda(J.n) n_A, n_A = A(phi_A) (-uy, ux)
     distance            -2 lambda(J) (P_B - P_A)
   out[i].f points into *values (allocated here, n*2*count; the caller
   frees it), stride 2*count. Returns the count. */
int reactions_compute(const Model *m, const double *q, const double *lambda, int n,
                      SvgForce *out, int max, double **values);

#endif
