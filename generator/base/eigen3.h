/* eigen3.h - the eigenvalues of a symmetric 3 x 3 matrix, in closed form. */
#ifndef MECHC_EIGEN3_H
#define MECHC_EIGEN3_H

/* The eigenvalues of the symmetric t (xx, yy, zz, xy, xz, yz), ascending,
   into ev: a diagonal t gives its sorted diagonal exactly. */
void eigen3_symmetric(const double t[6], double ev[3]);

#endif
