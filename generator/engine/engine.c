/* engine.c - dispatches evaluation to the JIT kernels, an AOT library or the generic evaluator. */
#include "engine.h"

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

bool engine_open(Engine *e, EngineKind kind, const Mech *mech, Diag *diag)
{
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
    case ENGINE_GENERIC:
    case ENGINE_AOT:
    case ENGINE_KIND_COUNT:
        break;
    }
    diag_error_nopos(diag, "the %s engine is not available in this build",
                     kind < ENGINE_KIND_COUNT ? engine_names[kind] : "requested");
    return false;
}

void engine_close(Engine *e)
{
    jit_free(e->jit);
    emit_result_free(&e->emitted);
    memset(e, 0, sizeof *e);
}

void engine_phi(const Engine *e, const double *q, double t, double *phi)
{
    e->kernels.phi(q, t, phi);
}

void engine_jac(const Engine *e, const double *q, double t, double *jac)
{
    e->kernels.jac(q, t, jac);
}

void engine_nu(const Engine *e, const double *q, double t, double *nu)
{
    e->kernels.nu(q, t, nu);
}

void engine_gamma(const Engine *e, const double *q, const double *qd, double t, double *gamma)
{
    e->kernels.gamma(q, qd, t, gamma);
}

void engine_all(const Engine *e, const double *q, const double *qd, double t,
                double *phi, double *jac, double *nu, double *gamma)
{
    e->kernels.all(q, qd, t, phi, jac, nu, gamma);
}
