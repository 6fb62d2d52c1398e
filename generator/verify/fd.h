/* fd.h - the check's finite differences: Phi, Psi and their paths against the generated jac, nu, gamma. */
#ifndef MECHC_VERIFY_FD_H
#define MECHC_VERIFY_FD_H

#include "checker.h"

/* Every row's jac, nu and gamma of the engine under test at the sample
   against finite differences (see check.c for the ladder of steps). */
void check_fd(Checker *c, double *scratch, double *vec);

/* The second difference's step at the sample. */
double check_second_step(const Checker *c);

/* -(d/dtau)^2 of one position row (or -d/dtau of one velocity row) along
   the path with only q moving, or only t, at the step of the reference
   (absolute; both paths are at tau = 0, so no scale applies). */
double check_gamma_part(Checker *c, int row, bool path_q, bool path_t, double step,
                        double *scratch, double *vec);

#endif
