/* engine.c - dispatches evaluation to the JIT kernels, an AOT library or the generic evaluator.
 *
 * jit:     generated C (libm declared, not included) compiled in memory by libtcc.
 * aot:     the same C with <math.h>, built by the system compiler into a
 *          cached shared library and loaded with dlopen (generator/engine/aot.c).
 * generic: no code generation; formulas and an interpreter over the joint
 *          list (generator/eval/generic.c).
 * jit and aot end up as the same Kernels; generic is called through its state.
 */
#include "engine.h"

#include "aot.h"
#include "../eval/generic.h"

#include <stdio.h>
#include <string.h>

const char *const engine_names[ENGINE_KIND_COUNT] = {"jit", "generic", "aot"};

int engine_from_name(const char *name)
{
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (strcmp(name, engine_names[k]) == 0)
            return k;
    return -1;
}

EngineOptions engine_default_options(void)
{
    return (EngineOptions){.aot_fresh = false};
}

static bool open_aot(Engine *e, const Mech *mech, const EngineOptions *opt, Diag *diag)
{
    EmitOptions eo = emit_default_options();
    eo.declare_math = false;
    eo.real_float = false;
    eo.prefix = "mechc_aot";
    /* Stores in place are faster than the spread from jac_nz; only large
       mechanisms keep the compact form, for the compiler's sake. */
    eo.direct_jac = mech->kin.nnz <= 4000;
    eo.source_name = mech->model->file;
    double t0 = pipeline_now();
    if (!emit_mechanism(&mech->kin, &eo, &e->emitted, diag))
        return false;
    e->gen_seconds = pipeline_now() - t0;
    AotResult res;
    if (!aot_load(e->emitted.c_text, e->emitted.prefix, opt->aot_fresh, &e->kernels, &res, diag))
        return false;
    e->library = res.handle;
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
    case ENGINE_JIT:
        e->jit = pipeline_jit(mech, &e->emitted, &e->gen_seconds, &e->compile_seconds, diag);
        if (!e->jit) {
            emit_result_free(&e->emitted);
            return false;
        }
        e->kernels = *jit_kernels(e->jit);
        return true;
    case ENGINE_GENERIC: {
        double t0 = pipeline_now();
        e->generic = generic_open(mech->model);
        e->gen_seconds = pipeline_now() - t0;
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

void engine_close(Engine *e)
{
    jit_free(e->jit);
    aot_unload(e->library);
    generic_free(e->generic);
    emit_result_free(&e->emitted);
    memset(e, 0, sizeof *e);
}

void engine_phi(const Engine *e, const double *q, double t, double *phi)
{
    if (e->generic)
        generic_phi(e->generic, q, t, phi);
    else
        e->kernels.phi(q, t, phi);
}

void engine_jac(const Engine *e, const double *q, double t, double *jac)
{
    if (e->generic)
        generic_jac(e->generic, q, t, jac);
    else
        e->kernels.jac(q, t, jac);
}

void engine_nu(const Engine *e, const double *q, double t, double *nu)
{
    if (e->generic)
        generic_nu(e->generic, q, t, nu);
    else
        e->kernels.nu(q, t, nu);
}

void engine_gamma(const Engine *e, const double *q, const double *qd, double t, double *gamma)
{
    if (e->generic)
        generic_gamma(e->generic, q, qd, t, gamma);
    else
        e->kernels.gamma(q, qd, t, gamma);
}

void engine_all(const Engine *e, const double *q, const double *qd, double t,
                double *phi, double *jac, double *nu, double *gamma)
{
    if (e->generic)
        generic_all(e->generic, q, qd, t, phi, jac, nu, gamma);
    else
        e->kernels.all(q, qd, t, phi, jac, nu, gamma);
}
