/* orient.c - a spatial body's initial orientation, as written, to normalised Euler parameters. */
#include "orient.h"

#include <math.h>

/* (a0, a) (b0, b) = (a0 b0 - a.b, a0 b + b0 a + a x b): the rotation a after b */
static void product(const double a[4], const double b[4], double out[4])
{
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + b[0] * a[1] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] + b[0] * a[2] + a[3] * b[1] - a[1] * b[3];
    r[3] = a[0] * b[3] + b[0] * a[3] + a[1] * b[2] - a[2] * b[1];
    for (int i = 0; i < 4; i++)
        out[i] = r[i];
}

/* The rotation by angle about coordinate axis k (0 x, 1 y, 2 z). */
static void about(int k, double angle, double out[4])
{
    out[0] = cos(angle / 2);
    out[1] = out[2] = out[3] = 0;
    out[1 + k] = sin(angle / 2);
}

bool orient_to_euler(int kind, const double arg[4], double p[4])
{
    p[0] = 1, p[1] = p[2] = p[3] = 0;
    if (kind == ORIENT_AXIS) {
        double n = sqrt(arg[0] * arg[0] + arg[1] * arg[1] + arg[2] * arg[2]);
        if (!(n > 0) || !isfinite(n))
            return false;
        double s = sin(arg[3] / 2);
        p[0] = cos(arg[3] / 2);
        for (int i = 0; i < 3; i++)
            p[1 + i] = s * arg[i] / n;
    } else if (kind == ORIENT_XYZ || kind == ORIENT_ZYX) {
        /* xyz(a, b, c) = Rx(a) Ry(b) Rz(c); zyx(a, b, c) = Rz(a) Ry(b) Rx(c) */
        static const int axes[2][3] = {{0, 1, 2}, {2, 1, 0}};
        const int *ax = axes[kind == ORIENT_ZYX];
        for (int i = 0; i < 3; i++) {
            double r[4];
            about(ax[i], arg[i], r);
            product(p, r, p);
        }
    }
    double n = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]);
    if (!(n > 0) || !isfinite(n))
        return false;
    for (int i = 0; i < 4; i++)
        p[i] /= n;
    return true;
}

void orient_rotate(const double p[4], const double u[3], double out[3])
{
    const double *e = p + 1;
    double c = 2 * p[0] * p[0] - 1;
    double eu = e[0] * u[0] + e[1] * u[1] + e[2] * u[2];
    double exu[3] = {e[1] * u[2] - e[2] * u[1], e[2] * u[0] - e[0] * u[2], e[0] * u[1] - e[1] * u[0]};
    for (int i = 0; i < 3; i++)
        out[i] = c * u[i] + 2 * (e[i] * eu + p[0] * exu[i]);
}
