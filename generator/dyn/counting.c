/* counting.c - the simulation's kernels, counted: every call of the simulation goes through them. */
#include "counting.h"

/* Counting wrappers: every kernel call of the simulation goes through these. */
static void c_phi(void *ctx, const double *q, double t, double *out)
{
    Sim *s = ctx;
    s->res->calls.phi++;
    s->inner->phi(s->inner->ctx, q, t, out);
}

static void c_jac(void *ctx, const double *q, double t, double *out)
{
    Sim *s = ctx;
    s->res->calls.jac++;
    s->inner->jac(s->inner->ctx, q, t, out);
}

static void c_nu(void *ctx, const double *q, double t, double *out)
{
    Sim *s = ctx;
    s->res->calls.nu++;
    s->inner->nu(s->inner->ctx, q, t, out);
}

static void c_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
{
    Sim *s = ctx;
    s->res->calls.gamma++;
    s->inner->gamma(s->inner->ctx, q, qd, t, out);
}

static void c_all(void *ctx, const double *q, const double *qd, double t, double *phi,
                  double *jac, double *nu, double *gamma)
{
    Sim *s = ctx;
    s->res->calls.all++;
    s->inner->all(s->inner->ctx, q, qd, t, phi, jac, nu, gamma);
}

static void c_mass(void *ctx, const double *q, double *out)
{
    Sim *s = ctx;
    s->res->calls.mass++;
    s->inner->mass(s->inner->ctx, q, out);
}

static void c_force(void *ctx, const double *q, const double *qd, double t, double *out)
{
    Sim *s = ctx;
    s->res->calls.force++;
    s->inner->force(s->inner->ctx, q, qd, t, out);
}

void sim_counting(Sim *s)
{
    const MechrtKernels *k = s->inner;
    s->kc = (MechrtKernels){k->nq, k->nh, k->nv, s, c_phi, c_jac, c_nu, c_gamma,
                            k->all ? c_all : NULL, c_mass, c_force};
}
