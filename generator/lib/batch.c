/* batch.c - libmechc's batch calls: a kernel over n states, each call through one slot of LibBatch.
 *
 * Every slot starts as a loop over the engine's single-state kernel. The
 * generated batch kernels (P_*_batch, generator/emit/batch.c) plug in at
 * lib_batch_bind: where the compiled unit has them (the aot engine's,
 * kernels.c), phi, jac, nu, gamma and all call them instead, in runs of
 * at most BATCH_RUN states (their n is an int; one time for all states
 * goes in as BATCH_RUN copies), and the public functions below do not
 * change. The batch kernels give the single kernels' bits.
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

enum { BATCH_RUN = 256 };

/* The times of the run of m states from state i: t's own, or copies of
   its one value (filled once, by fill_copies). */
static const double *run_times(const double *t, size_t nt, size_t i, const double *copies)
{
    return nt == 1 ? copies : t + i;
}

static void fill_copies(const double *t, size_t nt, double copies[BATCH_RUN])
{
    for (size_t j = 0; nt == 1 && j < BATCH_RUN; j++)
        copies[j] = t[0];
}

static size_t run_length(size_t n, size_t i) { return n - i < BATCH_RUN ? n - i : BATCH_RUN; }

/* phi, jac or nu (size per state) through the unit's batch kernel f. */
static void kernel_phi_like(KernelPhiBatch f, size_t size, mechc_kernels *k, size_t n,
                            const double *q, const double *t, size_t nt, double *out)
{
    size_t nq = (size_t)k->engine.nq;
    double copies[BATCH_RUN];
    fill_copies(t, nt, copies);
    for (size_t i = 0; i < n; i += BATCH_RUN)
        f((int)run_length(n, i), q + i * nq, run_times(t, nt, i, copies), out + i * size);
}

static void kernel_phi(mechc_kernels *k, size_t n, const double *q, const double *t, size_t nt,
                       double *out)
{
    kernel_phi_like(engine_batch(&k->engine)->phi, (size_t)k->engine.nh, k, n, q, t, nt, out);
}

static void kernel_jac(mechc_kernels *k, size_t n, const double *q, const double *t, size_t nt,
                       double *out)
{
    size_t size = (size_t)k->engine.nr * (size_t)k->engine.nq;
    kernel_phi_like(engine_batch(&k->engine)->jac, size, k, n, q, t, nt, out);
}

static void kernel_nu(mechc_kernels *k, size_t n, const double *q, const double *t, size_t nt,
                      double *out)
{
    kernel_phi_like(engine_batch(&k->engine)->nu, (size_t)k->engine.nr, k, n, q, t, nt, out);
}

static void kernel_gamma(mechc_kernels *k, size_t n, const double *q, const double *qd,
                         const double *t, size_t nt, double *out)
{
    const BatchKernels *b = engine_batch(&k->engine);
    size_t nq = (size_t)k->engine.nq, nr = (size_t)k->engine.nr;
    double copies[BATCH_RUN];
    fill_copies(t, nt, copies);
    for (size_t i = 0; i < n; i += BATCH_RUN)
        b->gamma((int)run_length(n, i), q + i * nq, qd + i * nq, run_times(t, nt, i, copies),
                 out + i * nr);
}

/* all with every output given; a NULL one (skipped) goes state by state. */
static void kernel_all(mechc_kernels *k, size_t n, const double *q, const double *qd,
                       const double *t, size_t nt, double *phi, double *jac, double *nu,
                       double *gamma)
{
    if (!phi || !jac || !nu || !gamma) {
        loop_all(k, n, q, qd, t, nt, phi, jac, nu, gamma);
        return;
    }
    const BatchKernels *b = engine_batch(&k->engine);
    size_t nq = (size_t)k->engine.nq, nr = (size_t)k->engine.nr, nh = (size_t)k->engine.nh;
    double copies[BATCH_RUN];
    fill_copies(t, nt, copies);
    for (size_t i = 0; i < n; i += BATCH_RUN)
        b->all((int)run_length(n, i), q + i * nq, qd + i * nq, run_times(t, nt, i, copies),
               phi + i * nh, jac + i * nr * nq, nu + i * nr, gamma + i * nr);
}

void lib_batch_bind(mechc_kernels *k)
{
    k->batch = (LibBatch){.phi = loop_phi, .jac = loop_jac, .nu = loop_nu,
                          .gamma = loop_gamma, .force = loop_force, .all = loop_all,
                          .mass = loop_mass};
    const BatchKernels *b = engine_batch(&k->engine);
    if (!b)
        return;
    k->batch.phi = kernel_phi;
    k->batch.nu = kernel_nu;
    k->batch.gamma = kernel_gamma;
    if (b->jac)
        k->batch.jac = kernel_jac;
    if (b->all)
        k->batch.all = kernel_all;
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
