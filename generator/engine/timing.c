/* timing.c - how long a kernel call takes: run --stats's figure for the step's evaluation. */
#include "engine.h"

#include "../base/arena.h"

#include <stdlib.h>

double engine_time_all(const MechrtKernels *k, const MechrtHostJacNz *jnz, const double *q,
                       const double *qd, double t, double min_seconds)
{
    size_t nq = (size_t)k->nq, nr = (size_t)(k->nh + k->nv);
    size_t njac = jnz ? (size_t)jnz->jac.nnz : nr * nq;
    double *phi = xcalloc(nr + 1, sizeof *phi), *jac = xcalloc(njac + 1, sizeof *jac);
    double *nu = xcalloc(nr + 1, sizeof *nu), *gamma = xcalloc(nr + 1, sizeof *gamma);
    long calls = 0, batch = 64;
    double t0 = pipeline_now(), elapsed;
    do {
        for (long i = 0; i < batch; i++) {
            if (jnz && jnz->all_nz) {
                jnz->all_nz(jnz->jac.ctx, q, qd, t, phi, jac, nu, gamma);
            } else if (jnz) {
                k->phi(k->ctx, q, t, phi);
                jnz->jac.jac_nz(jnz->jac.ctx, q, t, jac);
                k->nu(k->ctx, q, t, nu);
                k->gamma(k->ctx, q, qd, t, gamma);
            } else if (k->all) {
                k->all(k->ctx, q, qd, t, phi, jac, nu, gamma);
            } else {
                k->phi(k->ctx, q, t, phi);
                k->jac(k->ctx, q, t, jac);
                k->nu(k->ctx, q, t, nu);
                k->gamma(k->ctx, q, qd, t, gamma);
            }
        }
        calls += batch;
        batch *= 2;
        elapsed = pipeline_now() - t0;
    } while (elapsed < min_seconds);
    free(phi), free(jac), free(nu), free(gamma);
    return 1e9 * elapsed / (double)calls;
}
