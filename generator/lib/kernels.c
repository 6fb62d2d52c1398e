/* kernels.c - libmechc's compiled kernels: an engine per handle, every kernel at one state. */
#include "lib.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

#include <pthread.h>

/* libtcc 0.9.27 keeps its compiler state in globals: one jit compile at a
   time in the process, whatever handles the threads hold. */
static pthread_mutex_t jit_lock = PTHREAD_MUTEX_INITIALIZER;

static bool open_engine(Engine *e, EngineKind kind, const Mech *mech, const EngineOptions *o,
                        Diag *diag)
{
    if (kind != ENGINE_JIT)
        return engine_open_with(e, kind, mech, o, diag);
    pthread_mutex_lock(&jit_lock);
    bool ok = engine_open_with(e, kind, mech, o, diag);
    pthread_mutex_unlock(&jit_lock);
    return ok;
}

mechc_compile_options mechc_compile_defaults(void)
{
    return (mechc_compile_options){.aot_fresh = engine_default_options().aot_fresh, .batch = 1};
}

mechc_kernels *mechc_compile(mechc_model *m, const char *engine, mechc_diag *d)
{
    return mechc_compile_with(m, engine, NULL, d);
}

mechc_kernels *mechc_compile_with(mechc_model *m, const char *engine,
                                  const mechc_compile_options *o, mechc_diag *d)
{
    const char *name = engine ? engine : "jit";
    int kind = lib_name_index(engine_names, name, -1);
    if (!m || kind < 0) {
        lib_fail(d, MECHC_EARG, m ? "unknown engine '%s': jit, aot or generic" : "no model",
                 name);
        return NULL;
    }
    mechc_kernels *k = xcalloc(1, sizeof *k);
    k->model = m;
    EngineOptions eo = engine_default_options();
    mechc_compile_options co = o ? *o : mechc_compile_defaults();
    eo.aot_fresh = co.aot_fresh != 0;
    /* cc vectorises the batch kernels (batch.c calls them); libtcc does
       not, so the jit's would only lengthen its compile. */
    eo.batch = kind == ENGINE_AOT && co.batch != 0;
    Diag diag;
    diag_init(&diag, m->name, NULL, 0);
    if (!open_engine(&k->engine, (EngineKind)kind, m->mech, &eo, &diag)) {
        lib_fail_diag(d, MECHC_ECOMPILE, &diag);
        free(k);
        return NULL;
    }
    outputs_init(&k->outputs, m->mech->model);
    lib_batch_bind(k);
    lib_ok(d);
    return k;
}

void mechc_kernels_free(mechc_kernels *k)
{
    if (!k)
        return;
    if (k->sens_state > 0)
        sens_free(&k->sens);
    engine_close(&k->engine);
    outputs_free(&k->outputs);
    free(k->scratch);
    free(k);
}

const char *mechc_kernels_engine(const mechc_kernels *k)
{
    return k ? engine_names[k->engine.kind] : NULL;
}

double mechc_kernels_compile_seconds(const mechc_kernels *k)
{
    return k ? k->engine.gen_seconds + k->engine.compile_seconds : 0;
}

mechc_model *mechc_kernels_model(const mechc_kernels *k) { return k ? k->model : NULL; }

const char *mechc_kernels_source(const mechc_kernels *k)
{
    return k && k->engine.compiled ? k->engine.emitted.c_text : NULL;
}

/* Room for what a call skips (NULL outputs) or gathers from: nr x nq +
   nh + 2 nr, made at the first such call (a run of a sparse model of
   60 000 coordinates never makes its dense Jacobian). */
static double *scratch(mechc_kernels *k)
{
    if (!k->scratch) {
        size_t nq = (size_t)k->engine.nq, nr = (size_t)k->engine.nr;
        k->scratch = xcalloc(nr * nq + (size_t)k->engine.nh + 2 * nr + 1, sizeof(double));
    }
    return k->scratch;
}

mechc_status mechc_phi(mechc_kernels *k, const double *q, double t, double *phi)
{
    if (!k || !q || !phi)
        return MECHC_EARG;
    engine_phi(&k->engine, q, t, phi);
    return MECHC_OK;
}

mechc_status mechc_jacobian(mechc_kernels *k, const double *q, double t, double *jac)
{
    if (!k || !q || !jac)
        return MECHC_EARG;
    if (!k->engine.k.jac)
        return MECHC_ENOTAVAIL;     /* sparse-only kernels */
    engine_jac(&k->engine, q, t, jac);
    return MECHC_OK;
}

int mechc_jacobian_nz(const mechc_kernels *k) { return k ? k->model->mech->kin.nnz : 0; }

mechc_status mechc_jacobian_pattern(const mechc_kernels *k, int *rows, int *cols)
{
    if (!k || !rows || !cols)
        return MECHC_EARG;
    const MechrtHostJacNz *jnz = engine_jac_nz(&k->engine);
    const Kinematics *kin = &k->model->mech->kin;
    for (int i = 0; i < kin->nnz; i++) {
        rows[i] = jnz ? jnz->jac.row[i] : kin->jac[i].row;
        cols[i] = jnz ? jnz->jac.col[i] : kin->jac[i].col;
    }
    return MECHC_OK;
}

mechc_status mechc_jacobian_values(mechc_kernels *k, const double *q, double t, double *vals)
{
    if (!k || !q || !vals)
        return MECHC_EARG;
    const MechrtHostJacNz *jnz = engine_jac_nz(&k->engine);
    if (jnz) {
        jnz->jac.jac_nz(jnz->jac.ctx, q, t, vals);
        return MECHC_OK;
    }
    /* generic: the dense Jacobian, gathered */
    const Kinematics *kin = &k->model->mech->kin;
    int nq = k->engine.nq;
    double *jac = scratch(k);
    engine_jac(&k->engine, q, t, jac);
    for (int i = 0; i < kin->nnz; i++)
        vals[i] = jac[(size_t)kin->jac[i].row * (size_t)nq + (size_t)kin->jac[i].col];
    return MECHC_OK;
}

mechc_status mechc_nu(mechc_kernels *k, const double *q, double t, double *nu)
{
    if (!k || !q || !nu)
        return MECHC_EARG;
    engine_nu(&k->engine, q, t, nu);
    return MECHC_OK;
}

mechc_status mechc_gamma(mechc_kernels *k, const double *q, const double *qd, double t,
                         double *gamma)
{
    if (!k || !q || !qd || !gamma)
        return MECHC_EARG;
    engine_gamma(&k->engine, q, qd, t, gamma);
    return MECHC_OK;
}

mechc_status mechc_all(mechc_kernels *k, const double *q, const double *qd, double t,
                       double *phi, double *jac, double *nu, double *gamma)
{
    if (!k || !q || !qd)
        return MECHC_EARG;
    if (!k->engine.k.all)
        return MECHC_ENOTAVAIL;
    size_t nq = (size_t)k->engine.nq, nr = (size_t)k->engine.nr;
    double *s = scratch(k);     /* the outputs the caller does not want */
    engine_all(&k->engine, q, qd, t, phi ? phi : s + nr * nq, jac ? jac : s,
               nu ? nu : s + nr * nq + (size_t)k->engine.nh,
               gamma ? gamma : s + nr * nq + (size_t)k->engine.nh + nr);
    return MECHC_OK;
}

mechc_status mechc_mass(mechc_kernels *k, const double *q, double *M)
{
    if (!k || !q || !M)
        return MECHC_EARG;
    if (!k->engine.k.mass)
        return MECHC_ENOTAVAIL;
    k->engine.k.mass(k->engine.k.ctx, q, M);
    return MECHC_OK;
}

mechc_status mechc_force(mechc_kernels *k, const double *q, const double *qd, double t,
                         double *Q)
{
    if (!k || !q || !qd || !Q)
        return MECHC_EARG;
    if (!k->engine.k.force)
        return MECHC_ENOTAVAIL;
    k->engine.k.force(k->engine.k.ctx, q, qd, t, Q);
    return MECHC_OK;
}

mechc_status mechc_eom(mechc_kernels *k, const double *q, const double *qd, double t,
                       double *M, double *Q, double *jac, double *gamma)
{
    if (!k || !q || !qd)
        return MECHC_EARG;
    if (!k->engine.k.mass)
        return MECHC_ENOTAVAIL;
    if (jac && !k->engine.k.jac)
        return MECHC_ENOTAVAIL;
    const MechrtKernels *kk = &k->engine.k;
    if (M)
        kk->mass(kk->ctx, q, M);
    if (Q)
        kk->force(kk->ctx, q, qd, t, Q);
    if (jac)
        kk->jac(kk->ctx, q, t, jac);
    if (gamma)
        kk->gamma(kk->ctx, q, qd, t, gamma);
    return MECHC_OK;
}

mechc_status mechc_phi_p(mechc_kernels *k, const double *q, double t, double *phi_p)
{
    if (!k || !q || !phi_p)
        return MECHC_EARG;
    if (k->model->mech->model->np == 0)
        return MECHC_ENOTAVAIL;
    engine_phi_p(&k->engine, q, t, phi_p);
    return MECHC_OK;
}

int mechc_phi_p_nz(const mechc_kernels *k) { return k ? k->model->mech->kin.design.p_nnz : 0; }

mechc_status mechc_phi_p_pattern(const mechc_kernels *k, int *rows, int *params)
{
    if (!k || !rows || !params)
        return MECHC_EARG;
    const DesignKin *dk = &k->model->mech->kin.design;
    for (int i = 0; i < dk->p_nnz; i++)
        rows[i] = dk->p_nz[i].row, params[i] = dk->p_nz[i].col;
    return MECHC_OK;
}

mechc_status mechc_phi_p_values(mechc_kernels *k, const double *q, double t, double *vals)
{
    if (!k || !q || !vals)
        return MECHC_EARG;
    if (k->model->mech->model->np == 0)
        return MECHC_ENOTAVAIL;
    double *const out[DESIGN_Y_COUNT] = {vals};
    engine_design(&k->engine, DESIGN_PHI_P_NZ, q, NULL, t, out);
    return MECHC_OK;
}

mechc_status mechc_outputs(mechc_kernels *k, const double *q, const double *qd,
                           const double *qdd, double t, double *y, double *yd, double *ydd)
{
    if (!k || !q || !y || (yd && !qd) || (ydd && (!qd || !qdd || !yd)))
        return MECHC_EARG;
    outputs_eval(&k->outputs, q, yd ? qd : NULL, ydd ? qdd : NULL, t, y, yd, ydd);
    return MECHC_OK;
}
