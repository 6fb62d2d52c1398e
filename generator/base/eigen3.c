/* eigen3.c - the eigenvalues of a symmetric 3 x 3 matrix, in closed form. */
#include "eigen3.h"

#include <math.h>

/* The eigenvalues of the symmetric 3 x 3 matrix t (xx, yy, zz, xy, xz,
   yz), ascending, by the trigonometric closed form (Smith 1961) on t
   divided by its largest entry (squares of entries near 1e200 would
   overflow); a diagonal t gives its sorted diagonal exactly (the closed
   form leaves a rounding error there: (0, 1, 1) would read -1.1e-16). */
void eigen3_symmetric(const double t[6], double ev[3])
{
    if (t[3] == 0 && t[4] == 0 && t[5] == 0) {
        double a = t[0], b = t[1], c = t[2], x;
        if (a > b)
            x = a, a = b, b = x;
        if (b > c)
            x = b, b = c, c = x;
        if (a > b)
            x = a, a = b, b = x;
        ev[0] = a, ev[1] = b, ev[2] = c;
        return;
    }
    double scale = 0;
    for (int i = 0; i < 6; i++)
        scale = fmax(scale, fabs(t[i]));
    double u[6];
    for (int i = 0; i < 6; i++)
        u[i] = t[i] / scale;
    double p1 = u[3] * u[3] + u[4] * u[4] + u[5] * u[5];
    double q = (u[0] + u[1] + u[2]) / 3;
    double p2 = (u[0] - q) * (u[0] - q) + (u[1] - q) * (u[1] - q) + (u[2] - q) * (u[2] - q) + 2 * p1;
    double p = sqrt(p2 / 6);
    double b[6];
    for (int i = 0; i < 6; i++)
        b[i] = (u[i] - (i < 3 ? q : 0)) / p;
    double det = b[0] * (b[1] * b[2] - b[5] * b[5]) - b[3] * (b[3] * b[2] - b[5] * b[4])
                 + b[4] * (b[3] * b[5] - b[1] * b[4]);
    double r = fmax(-1.0, fmin(1.0, det / 2));
    double phi = acos(r) / 3;
    ev[2] = q + 2 * p * cos(phi);
    ev[0] = q + 2 * p * cos(phi + 2 * 3.14159265358979323846 / 3);
    ev[1] = 3 * q - ev[0] - ev[2];
    for (int i = 0; i < 3; i++)
        ev[i] *= scale;
}
