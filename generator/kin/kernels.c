/* kernels.c - a run's view of compiled kernels: the fused kernel timed, the sparse Jacobian bundle. */
#include "run.h"

#include "../base/arena.h"
#include "../pipeline/pipeline.h"

#include <stdlib.h>

double run_time_all(const MechrtKernels *k, const MechrtHostJacNz *jnz, const double *q,
                    const double *qd, double t, double min_seconds)
{
    size_t nq = (size_t)k->nq, nr = (size_t)(k->nh + k->nv);
    size_t njac = jnz ? (size_t)jnz->nnz : nr * nq;
    double *phi = xcalloc(nr + 1, sizeof *phi), *jac = xcalloc(njac + 1, sizeof *jac);
    double *nu = xcalloc(nr + 1, sizeof *nu), *gamma = xcalloc(nr + 1, sizeof *gamma);
    long calls = 0, batch = 64;
    double t0 = pipeline_now(), elapsed;
    do {
        for (long i = 0; i < batch; i++) {
            if (jnz && jnz->all_nz) {
                jnz->all_nz(jnz->ctx, q, qd, t, phi, jac, nu, gamma);
            } else if (jnz) {
                k->phi(k->ctx, q, t, phi);
                jnz->jac_nz(jnz->ctx, q, t, jac);
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

static void code_jac_nz(void *ctx, const double *q, double t, double *vals)
{
    ((const Kernels *)ctx)->jac_nz(q, t, vals);
}

static void code_all_nz(void *ctx, const double *q, const double *qd, double t, double *phi,
                        double *vals, double *nu, double *gamma)
{
    ((const Kernels *)ctx)->all_nz(q, qd, t, phi, vals, nu, gamma);
}

static int code_lu_factor(void *ctx, const double *a, double *lu, double pivot_tol,
                          double *spread)
{
    return ((const Kernels *)ctx)->lu_factor(a, lu, pivot_tol, spread);
}

static void code_lu_solve(void *ctx, const double *lu, const double *b, double *x)
{
    ((const Kernels *)ctx)->lu_solve(lu, b, x);
}

static int code_lu_step(void *ctx, double *q, double *qd, double *qdd, double t, double h,
                        const double *tol, int max_iter, double *out, int *iout)
{
    return ((const Kernels *)ctx)->lu_step(q, qd, qdd, t, h, tol, max_iter, out, iout);
}

bool run_jac_nz_of(const Engine *e, MechrtHostJacNz *out)
{
    const Kernels *code = e->k.ctx;
    if ((e->kind != ENGINE_JIT && e->kind != ENGINE_AOT) || !code || !code->jac_nz
        || !code->jac_row || !code->jac_col)
        return false;
    *out = (MechrtHostJacNz){e->mech->kin.nnz, code->jac_row, code->jac_col, (void *)code,
                             code_jac_nz, code->all_nz ? code_all_nz : NULL,
                             code->lu_factor ? code_lu_factor : NULL,
                             code->lu_factor ? code_lu_solve : NULL,
                             code->lu_step ? code_lu_step : NULL};
    return true;
}
