/* hull.h - the convex hull of a few planar points (a body's outline). */
#ifndef MECHC_HULL_H
#define MECHC_HULL_H

typedef struct HullPoint { double x, y; } HullPoint;

/* Sorts p (deduplicated within tol) and writes its hull, counter-clockwise,
   into h (room for n + 1); returns the hull size: 1, 2 (collinear: the two
   extremes) or more. */
int hull_convex(HullPoint *p, int n, HullPoint *h, double tol);

#endif
