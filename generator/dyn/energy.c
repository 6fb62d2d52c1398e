/* energy.c - the energy balance of sim: E = T - W, T from the mass kernel, W the work of the forces. */
#include "energy.h"

#include "kkt.h"

#include <math.h>

/* Relative displacement of the central difference for Mdot qd. */
#define SIM_MDOT_STEP 1e-5

/* 1/2 qd^T Mdot qd by a central difference of M along qd (qs scratch; M
   into mass2, or its nonzeros into smass on the sparse path). */
double sim_half_mdot(Sim *s, const double *q, const double *qd)
{
    int n = s->nq;
    double vmax = 0, qmax = 1;
    for (int i = 0; i < n; i++) {
        vmax = fmax(vmax, fabs(qd[i]));
        qmax = fmax(qmax, fabs(q[i]));
    }
    if (vmax == 0)
        return 0;
    double eps = SIM_MDOT_STEP * qmax / vmax, sum = 0;
    for (int sign = -1; sign <= 1; sign += 2) {
        for (int i = 0; i < n; i++)
            s->qs[i] = q[i] + sign * eps * qd[i];
        double quad = 0;
        if (s->kkt) {
            sim_sparse_mass(s, s->qs, s->smass);
            quad = sim_sparse_mass_form(s, s->smass, qd, qd);
        } else {
            s->kc.mass(s->kc.ctx, s->qs, s->mass2);
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++)
                    quad += qd[i] * s->mass2[(size_t)i * (size_t)n + (size_t)j] * qd[j];
        }
        sum += sign * quad;
    }
    return 0.25 * sum / eps;    /* 1/2 * (quad+ - quad-) / (2 eps) */
}

/* qd^T M x for the n x n row-major M. */
double sim_quad_form(int n, const double *m, const double *qd, const double *x)
{
    double sum = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            sum += qd[i] * m[(size_t)i * (size_t)n + (size_t)j] * x[j];
    return sum;
}

/* qd^T M x with M at q (one mass call). */
static double mass_form(Sim *s, const double *q, const double *qd, const double *x)
{
    s->kc.mass(s->kc.ctx, q, s->mass);
    return sim_quad_form(s->nq, s->mass, qd, x);
}

/* E = T - W at the state y, and the drift against E(t0). */
void sim_watch_energy(Sim *s, const double *y, bool first)
{
    if (!s->o->energy)
        return;
    const double *q = y, *qd = y + s->nq;
    double tk, w = y[2 * s->nq];
    if (s->kkt) {
        sim_sparse_mass(s, q, s->smass);
        tk = 0.5 * sim_sparse_mass_form(s, s->smass, qd, qd);
    } else {
        tk = 0.5 * mass_form(s, q, qd, qd);
    }
    double e = tk - w;
    if (first)
        s->e0 = e;
    s->res->energy_scale = fmax(s->res->energy_scale, fmax(tk, fabs(w)));
    s->res->energy_drift = fmax(s->res->energy_drift, fabs(e - s->e0));
}

