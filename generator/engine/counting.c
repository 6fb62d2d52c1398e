/* counting.c - kernels that count their calls: one wrapper any driver can put around an engine's. */
#include "engine.h"

static void c_phi(void *ctx, const double *q, double t, double *out)
{
    EngineCounter *c = ctx;
    c->calls->phi++;
    c->inner.phi(c->inner.ctx, q, t, out);
}

static void c_jac(void *ctx, const double *q, double t, double *out)
{
    EngineCounter *c = ctx;
    c->calls->jac++;
    c->inner.jac(c->inner.ctx, q, t, out);
}

static void c_nu(void *ctx, const double *q, double t, double *out)
{
    EngineCounter *c = ctx;
    c->calls->nu++;
    c->inner.nu(c->inner.ctx, q, t, out);
}

static void c_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
{
    EngineCounter *c = ctx;
    c->calls->gamma++;
    c->inner.gamma(c->inner.ctx, q, qd, t, out);
}

static void c_all(void *ctx, const double *q, const double *qd, double t, double *phi,
                  double *jac, double *nu, double *gamma)
{
    EngineCounter *c = ctx;
    c->calls->all++;
    c->inner.all(c->inner.ctx, q, qd, t, phi, jac, nu, gamma);
}

static void c_mass(void *ctx, const double *q, double *out)
{
    EngineCounter *c = ctx;
    c->calls->mass++;
    c->inner.mass(c->inner.ctx, q, out);
}

static void c_force(void *ctx, const double *q, const double *qd, double t, double *out)
{
    EngineCounter *c = ctx;
    c->calls->force++;
    c->inner.force(c->inner.ctx, q, qd, t, out);
}

MechrtKernels engine_counting(EngineCounter *counter, const MechrtKernels *k, EngineCalls *calls)
{
    counter->inner = *k;
    counter->calls = calls;
    return (MechrtKernels){k->nq, k->nh, k->nv, counter, k->phi ? c_phi : NULL,
                           k->jac ? c_jac : NULL, k->nu ? c_nu : NULL,
                           k->gamma ? c_gamma : NULL, k->all ? c_all : NULL,
                           k->mass ? c_mass : NULL, k->force ? c_force : NULL};
}
