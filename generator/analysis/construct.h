/* construct.h - assembly by construction: what ground, drivers and dyads of revolute joints fix, placed in closed form before Newton. */
#ifndef MECHC_CONSTRUCT_H
#define MECHC_CONSTRUCT_H

#include "../../runtime/mechrt.h"
#include "../model/model.h"

/* Places what the mechanism fixes without a guess, from the holonomic rows
 * of kernels k at t (an engine's for run, sim and check; the graph's,
 * mech_eval_kernels, for info), the way a textbook
 * solves a linkage at one instant: a row in which a single coordinate is
 * still unknown is solved for it (a driver gives its angle, a pin to ground
 * the position of the link, one scalar Newton per row); a body pinned at
 * two placed points is placed; an RRR dyad (two links pinned to each other
 * and each to a placed point) is closed by intersecting two circles, an
 * RRP dyad (the second link slides on a placed line) by a circle and a
 * line. Of the two closures the one nearer the initial values in q (angles
 * in radians, positions relative to the dyad's size) is
 * taken (the left one, seen from the first pin to the second, when both
 * are as near: all angles 0). Rounds repeat until nothing more is placed.
 * q is updated in place; coordinates nothing fixes keep their values.
 * Returns how many coordinates were placed. The rows themselves are not
 * trusted to be satisfied: Newton follows. */
int construct_with_kernels(const Model *m, const MechrtKernels *k, double t, double *q);

#endif
