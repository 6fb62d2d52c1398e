/* engine.c - dispatches evaluation to the JIT kernels, an AOT library or the generic evaluator.
 *
 * jit:     generated C (libm declared, not included) compiled in memory by libtcc.
 * aot:     the same C with <math.h>, built by the system compiler into a
 *          cached shared library and loaded with dlopen (generator/engine/aot.c).
 * generic: no code generation; formulas and an interpreter over the joint
 *          list (generator/eval/generic.c).
 * All three fill one MechrtKernels (and where they have them the Jacobian's
 * and M's nonzeros): jit and aot through thunks whose ctx is the compiled
 * unit's Kernels, generic through wrappers whose ctx is its state. These
 * are the only kernel adapters; everything downstream (check, run, sim)
 * asks engine_kernels, engine_jac_nz and engine_mass_nz.
 */
#include "engine.h"

#include "../base/arena.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const engine_names[ENGINE_KIND_COUNT + 1] = {
#define X(E, name) [ENGINE_##E] = name,
    ENGINE_KINDS(X)
#undef X
};

EngineOptions engine_default_options(void)
{
    return (EngineOptions){.aot_fresh = false};
}

/* ---- jit and aot: ctx is the compiled unit's context-free Kernels ---- */

static void code_phi(void *ctx, const double *q, double t, double *out)
{
    ((const Kernels *)ctx)->phi(q, t, out);
}

static void code_jac(void *ctx, const double *q, double t, double *out)
{
    ((const Kernels *)ctx)->jac(q, t, out);
}

static void code_nu(void *ctx, const double *q, double t, double *out)
{
    ((const Kernels *)ctx)->nu(q, t, out);
}

static void code_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
{
    ((const Kernels *)ctx)->gamma(q, qd, t, out);
}

static void code_all(void *ctx, const double *q, const double *qd, double t,
                     double *phi, double *jac, double *nu, double *gamma)
{
    ((const Kernels *)ctx)->all(q, qd, t, phi, jac, nu, gamma);
}

static void code_mass(void *ctx, const double *q, double *M)
{
    ((const Kernels *)ctx)->mass(q, M);
}

static void code_force(void *ctx, const double *q, const double *qd, double t, double *Q)
{
    ((const Kernels *)ctx)->force(q, qd, t, Q);
}

static void code_mass_nz(void *ctx, const double *q, double *vals)
{
    ((const Kernels *)ctx)->mass_nz(q, vals);
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
    return ((const Kernels *)ctx)->step(q, qd, qdd, t, h, tol, max_iter, out, iout);
}

/* ---- generic: ctx is the evaluator's state ---- */

static void gen_phi(void *ctx, const double *q, double t, double *out)
{
    generic_phi(ctx, q, t, out);
}

static void gen_jac(void *ctx, const double *q, double t, double *out)
{
    generic_jac(ctx, q, t, out);
}

static void gen_nu(void *ctx, const double *q, double t, double *out)
{
    generic_nu(ctx, q, t, out);
}

static void gen_gamma(void *ctx, const double *q, const double *qd, double t, double *out)
{
    generic_gamma(ctx, q, qd, t, out);
}

static void gen_all(void *ctx, const double *q, const double *qd, double t,
                    double *phi, double *jac, double *nu, double *gamma)
{
    generic_all(ctx, q, qd, t, phi, jac, nu, gamma);
}

static void gen_mass(void *ctx, const double *q, double *M)
{
    generic_mass(ctx, q, M);
}

static void gen_force(void *ctx, const double *q, const double *qd, double t, double *Q)
{
    generic_force(ctx, q, qd, t, Q);
}

static void gen_mass_nz(void *ctx, const double *q, double *vals)
{
    generic_mass_nz(ctx, q, vals);
}

/* e->k, e->jac_nz and e->mass_nz for compiled code (jit, aot) whose
   functions code holds. */
static void bind_code(Engine *e, const Kernels *code)
{
    void *ctx = (void *)code;
    if (code->design_bind)  /* the unit reads the model's design (model_set_design) */
        code->design_bind(e->mech->model->dag.param_values);
    e->compiled = true;
    e->kernels = *code;
    e->k = (MechrtKernels){.nq = e->nq, .nh = e->nh, .nv = e->nv, .ctx = ctx,
                           .phi = code_phi, .jac = code->jac ? code_jac : NULL,
                           .nu = code_nu, .gamma = code_gamma,
                           .all = code->all ? code_all : NULL};   /* NULL: sparse-only */
    e->jac_nz = (MechrtHostJacNz){
        .jac = {e->mech->kin.nnz, code->jac_row, code->jac_col, ctx, code_jac_nz},
        .all_nz = code->all_nz ? code_all_nz : NULL};
    if (code->lu_factor)    /* the LU's family, all or none (kernels_bind) */
        e->jac_nz.lu = (MechrtLuGen){e->nq * e->nq, ctx, code_lu_factor, code_lu_solve,
                                     code_lu_step};
    if (code->mass) {       /* the file has masses */
        e->k.mass = code_mass;
        e->k.force = code_force;
        e->mass_nz = (MechrtHostMassNz){e->mech->kin.dyn.nnz, code->mass_row, code->mass_col,
                                        ctx, code_mass_nz};
    }
}

/* The generic engine's mass_nz in the generated kernel's pattern: only
   the positions of M's structural nonzeros, not their symbolic values. */
static void bind_generic_pattern(Engine *e, const Dynamics *dyn)
{
    int n = dyn->nnz;
    e->pattern = xcalloc(2 * (size_t)n + 1, sizeof *e->pattern);
    for (int k = 0; k < n; k++) {
        e->pattern[k] = dyn->mass[k].row;
        e->pattern[n + k] = dyn->mass[k].col;
    }
    e->mass_nz = (MechrtHostMassNz){n, e->pattern, e->pattern + n, e->generic, gen_mass_nz};
    generic_mass_pattern(e->generic, e->mass_nz.row, e->mass_nz.col, n);
}

static bool open_aot(Engine *e, const Mech *mech, const EngineOptions *opt, Diag *diag)
{
    EmitOptions eo = engine_emit_options(mech, ENGINE_AOT);
    eo.batch = opt->batch;
    double t0 = pipeline_now();
    if (!emit_mechanism(&mech->kin, &eo, &e->emitted, diag))
        return false;
    e->gen_seconds = pipeline_now() - t0;
    AotResult res;
    e->aot = aot_load_with(e->emitted.c_text, e->emitted.prefix, opt->aot_fresh, opt->batch, &res,
                           diag);
    if (!e->aot)
        return false;
    bind_code(e, aot_kernels(e->aot));
    e->compile_seconds = res.seconds;
    e->aot_cached = res.cached;
    return true;
}

bool engine_open_with(Engine *e, EngineKind kind, const Mech *mech, const EngineOptions *opt, Diag *diag)
{
    EngineOptions defaults = engine_default_options();
    if (!opt)
        opt = &defaults;
    memset(e, 0, sizeof *e);
    e->kind = kind;
    e->mech = mech;
    e->nq = mech->model->nq;
    e->nh = mech->model->nh;
    e->nv = mech->model->nv;
    e->nr = mech->model->nr;
    switch (kind) {
    case ENGINE_JIT: {
        EmitOptions eo = engine_emit_options(mech, ENGINE_JIT);
        eo.batch = opt->batch;
        e->jit = engine_jit_compile(mech, &eo, &e->emitted, &e->gen_seconds,
                                    &e->compile_seconds, diag);
        if (!e->jit) {
            emit_result_free(&e->emitted);
            return false;
        }
        bind_code(e, jit_kernels(e->jit));
        return true;
    }
    case ENGINE_GENERIC: {
        double t0 = pipeline_now();
        e->generic = generic_open(mech->model);
        e->gen_seconds = pipeline_now() - t0;
        e->k = (MechrtKernels){.nq = e->nq, .nh = e->nh, .nv = e->nv, .ctx = e->generic,
                               .phi = gen_phi, .jac = gen_jac, .nu = gen_nu,
                               .gamma = gen_gamma, .all = gen_all};
        engine_design_open(e);
        if (mech->model->nmasses > 0) {
            e->k.mass = gen_mass;
            e->k.force = gen_force;
            bind_generic_pattern(e, &mech->kin.dyn);
        }
        return true;
    }
    case ENGINE_AOT:
        if (!open_aot(e, mech, opt, diag)) {
            emit_result_free(&e->emitted);
            return false;
        }
        return true;
    case ENGINE_KIND_COUNT:
        break;
    }
    diag_error_nopos(diag, "unknown engine");
    return false;
}

bool engine_open(Engine *e, EngineKind kind, const Mech *mech, Diag *diag)
{
    return engine_open_with(e, kind, mech, NULL, diag);
}

MechrtKernels engine_newton_kernels(const Engine *e)
{
    MechrtKernels k = e->k;
    const int *ops = e->emitted.ops;
    if (e->compiled && k.phi && k.jac
        && ops[EMIT_GAMMA] >= ops[EMIT_PHI] + ops[EMIT_JAC])
        k.all = NULL;
    return k;
}

void engine_close(Engine *e)
{
    jit_free(e->jit);
    aot_unload(e->aot);
    generic_free(e->generic);
    engine_design_free(e);
    free(e->pattern);
    emit_result_free(&e->emitted);
    memset(e, 0, sizeof *e);
}
