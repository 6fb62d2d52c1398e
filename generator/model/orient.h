/* orient.h - a spatial body's initial orientation (axis and angle, or a rotation sequence) to Euler parameters. */
#ifndef MECHC_ORIENT_H
#define MECHC_ORIENT_H

#include "../parse/ast.h"

#include <stdbool.h>

/* p = (e0, e1, e2, e3), normalised, of the rotation that kind (ORIENT_*)
   and arg describe:
     ORIENT_NONE  the identity;
     ORIENT_AXIS  by arg[3] radians about (arg[0], arg[1], arg[2]);
     ORIENT_XYZ   Rx(a) Ry(b) Rz(c): about x, then the new y, then the new z;
     ORIENT_ZYX   Rz(a) Ry(b) Rx(c): yaw, pitch, roll.
   False (p the identity) for a zero or non-finite axis. */
bool orient_to_euler(int kind, const double arg[4], double p[4]);

/* out = A(p) u, A(p) = (2 e0^2 - 1) I + 2 (e e^T + e0 e~): the body-fixed
   vector u in the global frame (out may not be u). */
void orient_rotate(const double p[4], const double u[3], double out[3]);

#endif
