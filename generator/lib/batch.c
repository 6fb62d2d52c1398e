/* batch.c - libmechc's batch calls: a kernel over n states, each call through one slot of LibBatch.
 *
 * Every slot starts as a loop over the engine's single-state kernel. The
 * generated batch kernels (P_*_batch, issue 29 part 3) plug in at
 * lib_batch_bind: where the compiled unit has one, its slot calls it
 * instead, and the public functions below do not change.
 */
#include "lib.h"

/* t of state i: one time for all (nt == 1) or one each. */
static inline double time_of(const double *t, size_t nt, size_t i) { return t[nt == 1 ? 0 : i]; }

static void loop_phi(mechc_kernels *k, size_t n, const double *q, const double *t, size_t nt,
                     double *out)
{
    const Engine *e = &k->engine;
    size_t nq = (size_t)e->nq, nh = (size_t)e->nh;
    for (size_t i = 0; i < n; i++)
        e->k.phi(e->k.ctx, q + i * nq, time_of(t, nt, i), out + i * nh);
}

static void loop_jac(mechc_kernels *k, size_t n, const double *q, const double *t, size_t nt,
                     double *out)
{
    const Engine *e = &k->engine;
    size_t nq = (size_t)e->nq, size = (size_t)e->nr * nq;
    for (size_t i = 0; i < n; i++)
        e->k.jac(e->k.ctx, q + i * nq, time_of(t, nt, i), out + i * size);
}

static void loop_nu(mechc_kernels *k, size_t n, const double *q, const double *t, size_t nt,
                    double *out)
{
    const Engine *e = &k->engine;
    size_t nq = (size_t)e->nq, nr = (size_t)e->nr;
    for (size_t i = 0; i < n; i++)
        e->k.nu(e->k.ctx, q + i * nq, time_of(t, nt, i), out + i * nr);
}

static void loop_gamma(mechc_kernels *k, size_t n, const double *q, const double *qd,
                       const double *t, size_t nt, double *out)
{
    const Engine *e = &k->engine;
    size_t nq = (size_t)e->nq, nr = (size_t)e->nr;
    for (size_t i = 0; i < n; i++)
        e->k.gamma(e->k.ctx, q + i * nq, qd + i * nq, time_of(t, nt, i), out + i * nr);
}

static void loop_force(mechc_kernels *k, size_t n, const double *q, const double *qd,
                       const double *t, size_t nt, double *out)
{
    const Engine *e = &k->engine;
    size_t nq = (size_t)e->nq;
    for (size_t i = 0; i < n; i++)
        e->k.force(e->k.ctx, q + i * nq, qd + i * nq, time_of(t, nt, i), out + i * nq);
}

static void loop_mass(mechc_kernels *k, size_t n, const double *q, double *M)
{
    const Engine *e = &k->engine;
    size_t nq = (size_t)e->nq;
    for (size_t i = 0; i < n; i++)
        e->k.mass(e->k.ctx, q + i * nq, M + i * nq * nq);
}

/* A NULL output stays NULL for every state (mechc_all skips it). */
static double *at(double *base, size_t i, size_t size) { return base ? base + i * size : NULL; }

static void loop_all(mechc_kernels *k, size_t n, const double *q, const double *qd,
                     const double *t, size_t nt, double *phi, double *jac, double *nu,
                     double *gamma)
{
    size_t nq = (size_t)k->engine.nq, nr = (size_t)k->engine.nr, nh = (size_t)k->engine.nh;
    for (size_t i = 0; i < n; i++)
        mechc_all(k, q + i * nq, qd + i * nq, time_of(t, nt, i), at(phi, i, nh),
                  at(jac, i, nr * nq), at(nu, i, nr), at(gamma, i, nr));
}

void lib_batch_bind(mechc_kernels *k)
{
    k->batch = (LibBatch){.phi = loop_phi, .jac = loop_jac, .nu = loop_nu,
                          .gamma = loop_gamma, .force = loop_force, .all = loop_all,
                          .mass = loop_mass};
}

/* The checks every batch call makes: kernels given, arrays given (n > 0),
   nt 1 or n. */
static mechc_status check(const mechc_kernels *k, size_t n, const double *q, const double *t,
                          size_t nt, const void *out)
{
    if (!k)
        return MECHC_EARG;
    if (n == 0)
        return MECHC_OK;
    if (!q || !out || (t && nt != 1 && nt != n) || (!t && nt != 0))
        return MECHC_EARG;
    return MECHC_OK;
}

/* t NULL (nt 0) means t = 0 for every state. */
static const double zero_time = 0;
#define TIMES(t, nt) ((t) ? (t) : &zero_time), ((t) ? (nt) : 1)

mechc_status mechc_phi_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                             size_t nt, double *phi)
{
    mechc_status st = check(k, n, q, t, nt, phi);
    if (st == MECHC_OK && n > 0)
        k->batch.phi(k, n, q, TIMES(t, nt), phi);
    return st;
}

mechc_status mechc_jacobian_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                                  size_t nt, double *jac)
{
    mechc_status st = check(k, n, q, t, nt, jac);
    if (st == MECHC_OK && !k->engine.k.jac)
        st = MECHC_ENOTAVAIL;
    if (st == MECHC_OK && n > 0)
        k->batch.jac(k, n, q, TIMES(t, nt), jac);
    return st;
}

mechc_status mechc_nu_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                            size_t nt, double *nu)
{
    mechc_status st = check(k, n, q, t, nt, nu);
    if (st == MECHC_OK && n > 0)
        k->batch.nu(k, n, q, TIMES(t, nt), nu);
    return st;
}

mechc_status mechc_gamma_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                               const double *t, size_t nt, double *gamma)
{
    mechc_status st = check(k, n, q, t, nt, gamma);
    if (st == MECHC_OK && n > 0 && !qd)
        st = MECHC_EARG;
    if (st == MECHC_OK && n > 0)
        k->batch.gamma(k, n, q, qd, TIMES(t, nt), gamma);
    return st;
}

mechc_status mechc_all_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                             const double *t, size_t nt, double *phi, double *jac, double *nu,
                             double *gamma)
{
    mechc_status st = check(k, n, q, t, nt, q);
    if (st == MECHC_OK && n > 0 && !qd)
        st = MECHC_EARG;
    if (st == MECHC_OK && !k->engine.k.all)
        st = MECHC_ENOTAVAIL;
    if (st == MECHC_OK && n > 0)
        k->batch.all(k, n, q, qd, TIMES(t, nt), phi, jac, nu, gamma);
    return st;
}

mechc_status mechc_mass_batch(mechc_kernels *k, size_t n, const double *q, double *M)
{
    mechc_status st = check(k, n, q, NULL, 0, M);
    if (st == MECHC_OK && !k->engine.k.mass)
        st = MECHC_ENOTAVAIL;
    if (st == MECHC_OK && n > 0)
        k->batch.mass(k, n, q, M);
    return st;
}

mechc_status mechc_force_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                               const double *t, size_t nt, double *Q)
{
    mechc_status st = check(k, n, q, t, nt, Q);
    if (st == MECHC_OK && n > 0 && !qd)
        st = MECHC_EARG;
    if (st == MECHC_OK && !k->engine.k.force)
        st = MECHC_ENOTAVAIL;
    if (st == MECHC_OK && n > 0)
        k->batch.force(k, n, q, qd, TIMES(t, nt), Q);
    return st;
}

mechc_status mechc_outputs_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                                 const double *qdd, const double *t, size_t nt, double *y,
                                 double *yd, double *ydd)
{
    mechc_status st = check(k, n, q, t, nt, y);
    if (st != MECHC_OK || n == 0)
        return st;
    const double *times = t ? t : &zero_time;
    size_t nq = (size_t)k->engine.nq, no = (size_t)k->outputs.n;
    for (size_t i = 0; i < n && st == MECHC_OK; i++)
        st = mechc_outputs(k, q + i * nq, qd ? qd + i * nq : NULL, qdd ? qdd + i * nq : NULL,
                           time_of(times, t ? nt : 1, i), y + i * no, yd ? yd + i * no : NULL,
                           ydd ? ydd + i * no : NULL);
    return st;
}
