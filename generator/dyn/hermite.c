/* hermite.c - sim's output between steps: the Hermite interpolant of q, qd, qdd at the last steps' ends. */
#include "hermite.h"

#include <math.h>

/* The weights at t of the Hermite interpolant through nk (2 or 3) nodes
   tk (the last the newest) with value, first and second derivative at
   each, for the value (w) and its derivative (wd): 3 nk each, in the
   order (value, derivative, second derivative) per node. In the
   variable x = (t - t_last) / hs, hs the last interval, the monomial
   basis' confluent Vandermonde A gives P = phi(x)^T A^-1 d, so w solves
   A^T w = phi(x); Gaussian elimination with partial pivoting (9 x 9). */
static void hermite_weights(int nk, const double *tk, double t, double *w, double *wd)
{
    enum { NMAX = 9 };
    int nn = 3 * nk;
    double hs = tk[nk - 1] - tk[nk - 2], at[NMAX][NMAX + 2];
    for (int k = 0; k < nk; k++) {
        double xk = (tk[k] - tk[nk - 1]) / hs, pw[NMAX + 1];
        pw[0] = 1;
        for (int m = 1; m <= nn; m++)
            pw[m] = pw[m - 1] * xk;
        for (int m = 0; m < nn; m++) {      /* column 3k + i of A is row 3k + i of A^T */
            at[m][3 * k] = pw[m];
            at[m][3 * k + 1] = m >= 1 ? m * pw[m - 1] / hs : 0;          /* d/dt = d/dx / hs */
            at[m][3 * k + 2] = m >= 2 ? m * (m - 1) * pw[m - 2] / (hs * hs) : 0;
        }
    }
    double x = (t - tk[nk - 1]) / hs, pw = 1;
    for (int m = 0; m < nn; m++) {
        at[m][nn] = pw;                                     /* phi(x) */
        at[m][nn + 1] = m >= 1 ? m * (pw / (x != 0 ? x : 1)) : 0;
        pw *= x;
    }
    if (x == 0)     /* phi'(0) = (0, 1, 0, ...) */
        for (int m = 0; m < nn; m++)
            at[m][nn + 1] = m == 1;
    for (int m = 0; m < nn; m++)
        at[m][nn + 1] /= hs;
    for (int c = 0; c < nn; c++) {
        int p = c;
        for (int r = c + 1; r < nn; r++)
            if (fabs(at[r][c]) > fabs(at[p][c]))
                p = r;
        for (int j = 0; j < nn + 2; j++) {
            double tmp = at[c][j];
            at[c][j] = at[p][j];
            at[p][j] = tmp;
        }
        for (int r = c + 1; r < nn; r++) {
            double f = at[r][c] / at[c][c];
            for (int j = c; j < nn + 2; j++)
                at[r][j] -= f * at[c][j];
        }
    }
    for (int c = nn - 1; c >= 0; c--) {
        double v = at[c][nn], vd = at[c][nn + 1];
        for (int j = c + 1; j < nn; j++)
            v -= at[c][j] * w[j], vd -= at[c][j] * wd[j];
        w[c] = v / at[c][c];
        wd[c] = vd / at[c][c];
    }
}

/* yi at t: per coordinate the Hermite interpolant of q, qd, qdd at the
   nk nodes (tk[k], yk[k], fk[k]; f = (qd, qdd, ...)): quintic on one
   step, degree 8 on the last two (errors O(h^9) and O(h^8) in q and qd
   against the quintic's O(h^6) and O(h^5): at rk8pd's own steps on A02
   the quintic's velocities were off by 5e-4). The energy slot is linear
   on the last step. */
void sim_hermite(const Sim *s, int nk, const double *tk, double t, double *const *yk,
                    double *const *fk, double *yi)
{
    int n = s->nq;
    double w[9], wd[9];
    hermite_weights(nk, tk, t, w, wd);
    for (int j = 0; j < n; j++) {
        double q = 0, qd = 0;
        for (int k = 0; k < nk; k++) {
            double p = yk[k][j], v = fk[k][j], a = fk[k][n + j];
            q += w[3 * k] * p + w[3 * k + 1] * v + w[3 * k + 2] * a;
            qd += wd[3 * k] * p + wd[3 * k + 1] * v + wd[3 * k + 2] * a;
        }
        yi[j] = q;
        yi[n + j] = qd;
    }
    if (s->dim > 2 * n) {
        const double *ya = yk[nk - 2], *yb = yk[nk - 1];
        double u = (t - tk[nk - 2]) / (tk[nk - 1] - tk[nk - 2]);
        yi[2 * n] = ya[2 * n] + u * (yb[2 * n] - ya[2 * n]);
    }
}

