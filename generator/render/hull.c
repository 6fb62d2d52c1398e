/* hull.c - convex hull by Andrew's monotone chain, tolerant of repeated and collinear points.
 *
 * Sort by x then y, build the lower chain left to right and the upper chain
 * right to left, popping while the last turn is not strictly to the left
 * (cross product below tol^2, so nearly collinear points drop out).
 * A. M. Andrew, "Another efficient algorithm for convex hulls in two
 * dimensions", Information Processing Letters 9 (1979) 216-219.
 */
#include "hull.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int cmp_point(const void *pa, const void *pb)
{
    const HullPoint *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    return (a->y > b->y) - (a->y < b->y);
}

static double cross3(HullPoint o, HullPoint a, HullPoint b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

int hull_convex(HullPoint *p, int n, HullPoint *h, double tol)
{
    qsort(p, (size_t)n, sizeof *p, cmp_point);
    int m = 0;
    for (int i = 0; i < n; i++)
        if (m == 0 || fabs(p[i].x - p[m - 1].x) > tol || fabs(p[i].y - p[m - 1].y) > tol)
            p[m++] = p[i];
    if (m <= 2) {
        memcpy(h, p, (size_t)m * sizeof *p);
        return m;
    }
    int k = 0;
    double area_tol = tol * tol;
    for (int i = 0; i < m; i++) {
        while (k >= 2 && cross3(h[k - 2], h[k - 1], p[i]) <= area_tol)
            k--;
        h[k++] = p[i];
    }
    for (int i = m - 2, lo = k + 1; i >= 0; i--) {
        while (k >= lo && cross3(h[k - 2], h[k - 1], p[i]) <= area_tol)
            k--;
        h[k++] = p[i];
    }
    k--;                    /* the first point came round again */
    if (k < 2) {            /* all collinear: the chain collapsed */
        h[0] = p[0];
        h[1] = p[m - 1];
        return 2;
    }
    return k;
}
