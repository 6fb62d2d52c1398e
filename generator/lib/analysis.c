/* analysis.c - libmechc's run and sim: the command's drivers, their states kept in a result handle. */
#include "lib.h"

#include "../base/arena.h"
#include "../analysis/redundant.h"
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
    bool keep;              /* false: states counted and passed on, not kept */
    RunResult run;          /* a run's statistics (lib_result_run) */
    SimResult sim;          /* a simulation's (lib_result_sim) */
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

/* State number r->states into the arrays, grown as needed. */
static void store_state(mechc_result *r, double t, const double *q, const double *qd,
                        const double *qdd, const double *lambda)
{
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
}

static void keep_state(void *ctx, double t, const double *q, const double *qd,
                       const double *qdd, const double *lambda)
{
    mechc_result *r = ctx;
    if (r->keep)
        store_state(r, t, q, qd, qdd, lambda);
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
    *r = (mechc_result){.k = k, .nq = m->nq, .nr = m->nr, .nout = m->nout, .keep = true,
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

mechc_run_tuning mechc_run_tuning_defaults(void)
{
    RunOptions ro = run_default_options();
    return (mechc_run_tuning){
        .max_substeps = ro.max_substeps, .assembly_max_iter = ro.assembly_max_iter,
        .pivot_tol = ro.mechrt.pivot_tol, .cond_warn = ro.mechrt.cond_warn,
        .ode_tol = ro.ode.tol, .max_dense_entries = ro.max_dense_entries, .keep_states = 1};
}

/* tuning's part of ro; false when a value is out of range. */
static bool run_tuning(const mechc_run_tuning *x, RunOptions *ro)
{
    static const char *const odes[] = {"rk8pd", "rkf45", NULL};
    int linear = lib_name_index(analysis_linear_names, x->linear, ANALYSIS_LINEAR_AUTO);
    int ode = lib_name_index(odes, x->ode, 0);
    if (linear < 0 || ode < 0 || x->max_substeps < 1 || x->assembly_max_iter < 1
        || !(x->pivot_tol >= 0) || !(x->cond_warn >= 0) || !(x->ode_tol > 0)
        || x->max_dense_entries < 0)
        return false;
    ro->linear = (AnalysisLinear)linear;
    if (x->ode)
        mechrt_ode_method_from_name(odes[ode], &ro->ode.method);
    ro->max_substeps = x->max_substeps;
    ro->assembly_max_iter = x->assembly_max_iter;
    ro->mechrt.pivot_tol = x->pivot_tol;
    ro->mechrt.cond_warn = x->cond_warn;
    ro->ode.tol = x->ode_tol;
    ro->max_dense_entries = x->max_dense_entries;
    ro->notes = x->notes;
    return true;
}

bool lib_run_options(const mechc_run_options *o, const mechc_run_tuning *x, RunOptions *ro)
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
    return !x || run_tuning(x, ro);
}

mechc_result *mechc_run(mechc_kernels *k, const mechc_run_options *o, mechc_diag *d)
{
    return mechc_run_with(k, o, NULL, d);
}

mechc_result *mechc_run_with(mechc_kernels *k, const mechc_run_options *o,
                             const mechc_run_tuning *x, mechc_diag *d)
{
    return lib_run_lending(k, o, x, NULL, d);
}

mechc_result *lib_run_lending(mechc_kernels *k, const mechc_run_options *o,
                              const mechc_run_tuning *x, RunLu *lend, mechc_diag *d)
{
    mechc_run_options defaults = mechc_run_defaults();
    if (!o)
        o = &defaults;
    RunOptions ro;
    if (!k || !lib_run_options(o, x, &ro)) {
        lib_fail(d, MECHC_EARG, "mechc_run: steps < 0, t0 == t1, a tolerance <= 0, "
                 "max_iter < 1 or a tuning value out of range");
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
    ro.lend_lu = lend;
    mechc_result *r = result_new(k, o->forces, o->on_state, o->ctx);
    r->keep = !x || x->keep_states;
    MechrtKernels newton = engine_newton_kernels(&k->engine);
    const MechrtHostJacNz *jnz = engine_jac_nz(&k->engine);
    RunResult *res = &r->run;
    AnalysisStatus st = o->forces
                            ? run_analysis_forces(m, &newton, jnz, &ro, keep_state, r, res)
                            : run_analysis(m, &newton, jnz, &ro, keep_kinematic, r, res);
    return finish(r, st, res->message, res->t_fail, d);
}

const RunResult *lib_result_run(const mechc_result *r) { return &r->run; }

mechc_sim_options mechc_sim_defaults(void)
{
    SimOptions so = sim_default_options();
    return (mechc_sim_options){.t0 = so.t0, .t1 = so.t1, .steps = so.steps, .rtol = so.rtol,
                               .atol = so.atol};
}

mechc_sim_tuning mechc_sim_tuning_defaults(void)
{
    SimOptions so = sim_default_options();
    return (mechc_sim_tuning){.max_steps = so.max_steps, .interpolate = so.interpolate,
                              .baumgarte_alpha = so.dyn.baumgarte_alpha,
                              .baumgarte_beta = so.dyn.baumgarte_beta, .keep_states = 1};
}

/* tuning's part of so; false when a value is out of range. */
static bool sim_tuning(const mechc_sim_tuning *x, SimOptions *so)
{
    int linear = lib_name_index(analysis_linear_names, x->linear, ANALYSIS_LINEAR_AUTO);
    if (linear < 0 || x->max_steps < 1 || !(x->baumgarte_alpha >= 0)
        || !(x->baumgarte_beta >= 0) || !isfinite(x->baumgarte_alpha)
        || !isfinite(x->baumgarte_beta))
        return false;
    so->linear = (AnalysisLinear)linear;
    so->max_steps = x->max_steps;
    so->interpolate = x->interpolate != 0;
    so->dyn.baumgarte_alpha = x->baumgarte_alpha;
    so->dyn.baumgarte_beta = x->baumgarte_beta;
    so->notes = x->notes;
    so->on_step = x->on_step;
    so->on_step_ctx = x->step_ctx;
    return true;
}

/* The options as sim_run takes them; false when one is out of range. */
static bool sim_options(const mechc_sim_options *o, const mechc_sim_tuning *x, SimOptions *so)
{
    *so = sim_default_options();
    int method = lib_name_index(sim_method_names, o->method, SIM_RK8PD);
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
    return !x || sim_tuning(x, so);
}

mechc_result *mechc_sim(mechc_kernels *k, const mechc_sim_options *o, mechc_diag *d)
{
    return mechc_sim_with(k, o, NULL, d);
}

mechc_result *mechc_sim_with(mechc_kernels *k, const mechc_sim_options *o,
                             const mechc_sim_tuning *x, mechc_diag *d)
{
    mechc_sim_options defaults = mechc_sim_defaults();
    if (!o)
        o = &defaults;
    SimOptions so;
    if (!k || !sim_options(o, x, &so)) {
        lib_fail(d, MECHC_EARG, "mechc_sim: steps < 1, t0 == t1, a tolerance < 0 or not "
                 "finite, rtol and atol both 0, an unknown method (rk8pd, rkf45, rk4imp, "
                 "msbdf) or a tuning value out of range");
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
    if (m->nh > m->nq && !redundant_applies(m)) {
        lib_fail(d, MECHC_ENOTRUNNABLE, "%d holonomic rows for %d coordinates: sim's position "
                 "projection needs at most one row per coordinate", m->nh, m->nq);
        return NULL;
    }
    so.source = &k->model->diag;
    mechc_result *r = result_new(k, true, o->on_state, o->ctx);
    r->keep = !x || x->keep_states;
    SimResult *res = &r->sim;
    AnalysisStatus st = sim_run(m, engine_kernels(&k->engine), engine_jac_nz(&k->engine),
                                engine_mass_nz(&k->engine), &so, keep_state, r, res);
    return finish(r, st, res->message, res->t_fail, d);
}

const SimResult *lib_result_sim(const mechc_result *r) { return &r->sim; }

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
