/* analysis.c - libmechc's run and sim: the command's drivers, their states kept in a result handle. */
#include "lib.h"

#include "../base/arena.h"
#include "../dyn/sim.h"
#include "../kin/run.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Every state of a run or a simulation, grown as they come. */
struct mechc_result {
    mechc_kernels *k;
    int nq, nr, nout;
    int states, cap;
    double *t, *q, *qd, *qdd, *y, *yd, *ydd, *lambda;
    bool with_lambda;
    mechc_status status;
    char message[RUN_MESSAGE_MAX];
    double t_fail;
    mechc_state_fn on_state;
    void *ctx;
};

static void grow(double **a, size_t per_state, int cap)
{
    if (per_state > 0)
        *a = xrealloc(*a, (size_t)cap * per_state, sizeof **a);
}

static void keep_state(void *ctx, double t, const double *q, const double *qd,
                       const double *qdd, const double *lambda)
{
    mechc_result *r = ctx;
    size_t nq = (size_t)r->nq, nr = (size_t)r->nr, no = (size_t)r->nout, i = (size_t)r->states;
    if (r->states == r->cap) {
        r->cap = r->cap ? 2 * r->cap : 64;
        grow(&r->t, 1, r->cap);
        grow(&r->q, nq, r->cap), grow(&r->qd, nq, r->cap), grow(&r->qdd, nq, r->cap);
        grow(&r->y, no, r->cap), grow(&r->yd, no, r->cap), grow(&r->ydd, no, r->cap);
        if (r->with_lambda)
            grow(&r->lambda, nr, r->cap);
    }
    r->t[i] = t;
    memcpy(r->q + i * nq, q, nq * sizeof *q);
    memcpy(r->qd + i * nq, qd, nq * sizeof *q);
    memcpy(r->qdd + i * nq, qdd, nq * sizeof *q);
    if (no > 0)
        outputs_eval(&r->k->outputs, q, qd, qdd, t, r->y + i * no, r->yd + i * no,
                     r->ydd + i * no);
    if (r->with_lambda && lambda)
        memcpy(r->lambda + i * nr, lambda, nr * sizeof *lambda);
    r->states++;
    if (r->on_state)
        r->on_state(r->ctx, t, q, qd, qdd, r->with_lambda ? lambda : NULL);
}

static void keep_kinematic(void *ctx, double t, const double *q, const double *qd,
                           const double *qdd)
{
    keep_state(ctx, t, q, qd, qdd, NULL);
}

static mechc_result *result_new(mechc_kernels *k, bool with_lambda, mechc_state_fn fn, void *ctx)
{
    const Model *m = k->model->mech->model;
    mechc_result *r = xcalloc(1, sizeof *r);
    *r = (mechc_result){.k = k, .nq = m->nq, .nr = m->nr, .nout = m->nout,
                        .with_lambda = with_lambda, .on_state = fn, .ctx = ctx, .t_fail = NAN};
    return r;
}

/* The driver's outcome into r; NULL (r freed, d filled) when it could not start. */
static mechc_result *finish(mechc_result *r, AnalysisStatus st, const char *message,
                            double t_fail, mechc_diag *d)
{
    if (st == ANALYSIS_BAD_INPUT) {
        lib_fail(d, MECHC_ENOTRUNNABLE, "%s", message);
        mechc_result_free(r);
        return NULL;
    }
    if (st == ANALYSIS_FAILED) {
        r->status = MECHC_EANALYSIS;
        r->t_fail = t_fail;
        snprintf(r->message, sizeof r->message, "%s", message);
        lib_fail(d, MECHC_EANALYSIS, "%s", message);
    } else {
        lib_ok(d);
    }
    return r;
}

mechc_run_options mechc_run_defaults(void)
{
    RunOptions ro = run_default_options();
    return (mechc_run_options){.t0 = ro.t0, .t1 = ro.t1, .steps = ro.steps,
                               .tol = ro.mechrt.tol_phi, .max_iter = ro.mechrt.max_iter};
}

/* The options as run_analysis takes them; false when one is out of range. */
static bool run_options(const mechc_run_options *o, RunOptions *ro)
{
    *ro = run_default_options();
    if (o->steps < 0 || (o->steps > 0 && o->t0 == o->t1) || !isfinite(o->t0)
        || !isfinite(o->t1) || !(o->tol > 0) || o->max_iter < 1)
        return false;
    ro->t0 = o->t0;
    ro->t1 = o->t1;
    ro->steps = o->steps;
    ro->mechrt.tol_phi = ro->mechrt.tol_dq = o->tol;
    ro->mechrt.max_iter = o->max_iter;
    return true;
}

mechc_result *mechc_run(mechc_kernels *k, const mechc_run_options *o, mechc_diag *d)
{
    mechc_run_options defaults = mechc_run_defaults();
    if (!o)
        o = &defaults;
    RunOptions ro;
    if (!k || !run_options(o, &ro)) {
        lib_fail(d, MECHC_EARG, "mechc_run: steps < 0, t0 == t1, a tolerance <= 0 or "
                 "max_iter < 1");
        return NULL;
    }
    const Model *m = k->model->mech->model;
    char why[300];
    if (!run_rows_match(m, why, sizeof why)) {
        lib_fail(d, MECHC_ENOTRUNNABLE, "%s", why);
        return NULL;
    }
    if (o->forces && !k->engine.k.mass) {
        lib_fail(d, MECHC_ENOTRUNNABLE, "the mechanism has no masses: forces need `mass` "
                 "statements");
        return NULL;
    }
    ro.source = &k->model->diag;
    mechc_result *r = result_new(k, o->forces, o->on_state, o->ctx);
    MechrtKernels newton = engine_newton_kernels(&k->engine);
    const MechrtHostJacNz *jnz = engine_jac_nz(&k->engine);
    RunResult res;
    AnalysisStatus st = o->forces
                            ? run_analysis_forces(m, &newton, jnz, &ro, keep_state, r, &res)
                            : run_analysis(m, &newton, jnz, &ro, keep_kinematic, r, &res);
    return finish(r, st, res.message, res.t_fail, d);
}

mechc_sim_options mechc_sim_defaults(void)
{
    SimOptions so = sim_default_options();
    return (mechc_sim_options){.t0 = so.t0, .t1 = so.t1, .steps = so.steps, .rtol = so.rtol,
                               .atol = so.atol};
}

/* The options as sim_run takes them; false when one is out of range. */
static bool sim_options(const mechc_sim_options *o, SimOptions *so)
{
    *so = sim_default_options();
    int method = 0;
    if (o->method) {
        method = -1;
        for (int i = 0; sim_method_names[i]; i++)
            if (strcmp(sim_method_names[i], o->method) == 0)
                method = i;
    }
    if (method < 0 || o->steps < 1 || o->t0 == o->t1 || !isfinite(o->t0) || !isfinite(o->t1)
        || !(o->rtol >= 0) || !(o->atol >= 0) || !isfinite(o->rtol) || !isfinite(o->atol)
        || (o->rtol == 0 && o->atol == 0))
        return false;
    so->t0 = o->t0;
    so->t1 = o->t1;
    so->steps = o->steps;
    so->rtol = o->rtol;
    so->atol = o->atol;
    so->method = (SimMethod)method;
    so->qd0 = o->qd0;
    return true;
}

mechc_result *mechc_sim(mechc_kernels *k, const mechc_sim_options *o, mechc_diag *d)
{
    mechc_sim_options defaults = mechc_sim_defaults();
    if (!o)
        o = &defaults;
    SimOptions so;
    if (!k || !sim_options(o, &so)) {
        lib_fail(d, MECHC_EARG, "mechc_sim: steps < 1, t0 == t1, a tolerance < 0 or not "
                 "finite, rtol and atol both 0, or an unknown method (rk8pd, rkf45, rk4imp, "
                 "msbdf)");
        return NULL;
    }
    const Model *m = k->model->mech->model;
    for (int j = 0; o->qd0 && j < m->nq; j++)
        if (!isfinite(o->qd0[j])) {
            lib_fail(d, MECHC_EARG, "mechc_sim: qd0[%d] (%s) is not a finite number", j,
                     m->coord_names[j]);
            return NULL;
        }
    if (!sim_has_masses(&k->engine.k)) {
        lib_fail(d, MECHC_ENOTRUNNABLE, "the mechanism has no masses: sim needs `mass` "
                 "statements (with `gravity`, forces or springs)");
        return NULL;
    }
    if (m->nh > m->nq) {
        lib_fail(d, MECHC_ENOTRUNNABLE, "%d holonomic rows for %d coordinates: sim's position "
                 "projection needs at most one row per coordinate", m->nh, m->nq);
        return NULL;
    }
    so.source = &k->model->diag;
    mechc_result *r = result_new(k, true, o->on_state, o->ctx);
    SimResult res;
    AnalysisStatus st = sim_run(m, engine_kernels(&k->engine), engine_jac_nz(&k->engine),
                                engine_mass_nz(&k->engine), &so, keep_state, r, &res);
    return finish(r, st, res.message, res.t_fail, d);
}

/* A NULL result (a run that could not start) reads as empty. */
int mechc_result_states(const mechc_result *r) { return r ? r->states : 0; }
const double *mechc_result_time(const mechc_result *r) { return r ? r->t : NULL; }
const double *mechc_result_q(const mechc_result *r) { return r ? r->q : NULL; }
const double *mechc_result_qd(const mechc_result *r) { return r ? r->qd : NULL; }
const double *mechc_result_qdd(const mechc_result *r) { return r ? r->qdd : NULL; }
const double *mechc_result_y(const mechc_result *r) { return r && r->nout ? r->y : NULL; }
const double *mechc_result_yd(const mechc_result *r) { return r && r->nout ? r->yd : NULL; }
const double *mechc_result_ydd(const mechc_result *r) { return r && r->nout ? r->ydd : NULL; }
const double *mechc_result_lambda(const mechc_result *r)
{
    return r && r->with_lambda ? r->lambda : NULL;
}
mechc_status mechc_result_status(const mechc_result *r) { return r ? r->status : MECHC_EARG; }
const char *mechc_result_message(const mechc_result *r) { return r ? r->message : ""; }
double mechc_result_t_fail(const mechc_result *r) { return r ? r->t_fail : NAN; }

void mechc_result_free(mechc_result *r)
{
    if (!r)
        return;
    free(r->t), free(r->q), free(r->qd), free(r->qdd);
    free(r->y), free(r->yd), free(r->ydd), free(r->lambda);
    free(r);
}
