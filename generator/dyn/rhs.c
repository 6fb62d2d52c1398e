/* rhs.c - the right-hand side of sim for GSL: f = (qd, qdd, dW/dt), dense or sparse, cached, and its Jacobian. */
#include "rhs.h"

#include "energy.h"
#include "fold.h"
#include "kkt.h"

#include <math.h>
#include <string.h>

#include <gsl/gsl_errno.h>

/* M at the state of the last mechrt_forward_dynamics: its workspace holds
   it after Phi_q (runtime/dynamics.c: "a nr*nq | mass nq*nq | ..."),
   which saves the energy balance a mass call per right-hand side. */
static const double *dyn_mass(const Sim *s)
{
    return s->work + (size_t)s->nr * (size_t)s->nq;
}

static int sim_rhs_solve(Sim *s, double t, const double y[], double f[]);

/* f = (qd, qdd, dE/dt) at (t, y) kept for a repeated evaluation. */
void sim_cache_store(Sim *s, double t, const double *y, const double *f)
{
    memcpy(s->cy, y, 2 * (size_t)s->nq * sizeof *y);
    memcpy(s->cf, f, (size_t)s->dim * sizeof *f);
    s->ct = t;
    s->cache_ok = true;
}

/* The cache holds f at (t, y). */
bool sim_cache_has(const Sim *s, double t, const double *y)
{
    return s->cache_ok && t == s->ct && memcmp(y, s->cy, 2 * (size_t)s->nq * sizeof *y) == 0;
}

int sim_rhs(double t, const double y[], double f[], void *params)
{
    Sim *s = params;
    if (sim_cache_has(s, t, y)) {
        memcpy(f, s->cf, (size_t)s->dim * sizeof *f);
        return GSL_SUCCESS;
    }
    int st0 = sim_rhs_solve(s, t, y, f);
    if (st0 == GSL_SUCCESS)
        sim_cache_store(s, t, y, f);
    return st0;
}

static int sim_rhs_solve(Sim *s, double t, const double y[], double f[])
{
    int n = s->nq;
    const double *q = y, *qd = y + n;
    MechrtDynReport rep;
    s->res->rhs_calls++;
    if (s->kkt) {
        /* the rows left out are known: no rank decision here */
        if (sim_sparse_accel(s, q, qd, t, s->all_active ? NULL : s->active, f + n, NULL)
            == MECHRT_OK) {
            memcpy(f, qd, (size_t)n * sizeof *f);
            sim_fold_apply(s, f + n);
            if (s->o->energy)
                f[2 * n] = sim_sparse_mass_form(s, mechrt_host_kkt_mass(s->kkt), qd, f + n)
                           + sim_half_mdot(s, q, qd);
            return GSL_SUCCESS;
        }
        s->res->dense_fallbacks++;     /* the dense method decides, or names the cause */
        if (!sim_dense_ready(s)) {
            s->fail_status = MECHRT_EINVAL;
            s->fail_t = t;
            return GSL_EBADFUNC;
        }
    }
    MechrtStatus st = mechrt_forward_dynamics(&s->kc, &s->dyn, q, qd, t, f + n, NULL,
                                              s->work, s->lwork, &rep);
    if (st == MECHRT_OK) {
        memcpy(f, qd, (size_t)n * sizeof *f);
        sim_fold_apply(s, f + n);
        if (rep.redundant > s->res->max_redundant)
            s->res->max_redundant = rep.redundant;
        if (s->nr > 0 && rep.pivot_ratio < s->res->min_pivot_ratio)
            s->res->min_pivot_ratio = rep.pivot_ratio;
        if (s->o->energy)
            f[2 * n] = sim_quad_form(n, dyn_mass(s), qd, f + n) + sim_half_mdot(s, q, qd);
        return GSL_SUCCESS;
    }
    if (s->fail_status == MECHRT_OK) {
        s->fail_status = st;
        s->fail_t = t;
        s->fail_rep = rep;
        memcpy(s->fail_y, y, 2 * (size_t)n * sizeof *y);
    }
    return GSL_EBADFUNC;
}

/* Forward differences of the right side for the implicit methods. */
int sim_jacobian(double t, const double y[], double *dfdy, double dfdt[], void *params)
{
    Sim *s = params;
    int dim = s->dim;
    s->res->jacobian_calls++;
    int gs = sim_rhs(t, y, s->f0, s);
    memcpy(s->y, y, (size_t)dim * sizeof *y);
    for (int j = 0; j < dim && gs == GSL_SUCCESS; j++) {
        double h = 1.4901161193847656e-08 * fmax(fabs(y[j]), 1.0);   /* sqrt(eps) */
        s->y[j] = y[j] + h;
        gs = sim_rhs(t, s->y, s->f1, s);
        for (int i = 0; i < dim; i++)
            dfdy[(size_t)i * (size_t)dim + (size_t)j] = (s->f1[i] - s->f0[i]) / h;
        s->y[j] = y[j];
    }
    if (gs == GSL_SUCCESS) {
        double ht = 1.4901161193847656e-08 * fmax(fabs(t), 1.0);
        gs = sim_rhs(t + ht, y, s->f1, s);
        for (int i = 0; i < dim; i++)
            dfdt[i] = (s->f1[i] - s->f0[i]) / ht;
    }
    return gs;
}

