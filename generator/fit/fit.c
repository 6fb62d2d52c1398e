/* fit.c - mechc fit as a library: design parameters identified from measurements by nonlinear least squares. */
#include "fit.h"

#include "../base/arena.h"

#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

FitOptions fit_default_options(void)
{
    return (FitOptions){.max_iter = 200, .xtol = 1e-15, .gtol = 1e-15, .ftol = 0.0, .steps = 20,
                        .newton_tol = 1e-12};
}

/* The least-squares problem GSL's callbacks see. */
typedef struct Problem {
    Model *m;
    const FitData *d;
    const FitOptions *o;
    FitSampler smp;
    int n, k;
    int *index;             /* k: design parameter of each unknown */
    size_t *at;             /* n: each residual's entry in the data */
    double *value, *dvalue; /* the last sample's model values and derivatives */
    double *x_done;         /* the unknowns they are for */
    bool have, have_d;
    char why[RUN_MESSAGE_MAX + 64];
} Problem;

static bool bounded(const Problem *pr, int i)
{
    int j = pr->index[i];
    return isfinite(pr->o->lo[j]) && isfinite(pr->o->hi[j]);
}

/* The design parameter of unknown i at u, and its derivative dp/du. */
static double design_of(const Problem *pr, int i, double u, double *dpdu)
{
    int j = pr->index[i];
    if (!bounded(pr, i)) {
        *dpdu = 1.0;
        return u;
    }
    double lo = pr->o->lo[j], hi = pr->o->hi[j];
    *dpdu = 0.5 * (hi - lo) * cos(u);
    return lo + 0.5 * (hi - lo) * (1.0 + sin(u));
}

/* The model values (and derivatives) at the unknowns x, once per x. */
static bool evaluate(Problem *pr, const gsl_vector *x, bool with_d)
{
    bool same = pr->have;
    for (int i = 0; i < pr->k && same; i++)
        same = gsl_vector_get(x, (size_t)i) == pr->x_done[i];
    if (same && (pr->have_d || !with_d))
        return true;
    double *p = pr->m->dag.param_values, dpdu;
    for (int i = 0; i < pr->k; i++) {
        pr->x_done[i] = gsl_vector_get(x, (size_t)i);
        p[pr->index[i]] = design_of(pr, i, pr->x_done[i], &dpdu);
    }
    pr->have = fit_sample(&pr->smp, pr->value, with_d ? pr->dvalue : NULL, pr->why, sizeof pr->why);
    pr->have_d = pr->have && with_d;
    return pr->have;
}

static int residuals(const gsl_vector *x, void *params, gsl_vector *f)
{
    Problem *pr = params;
    if (!evaluate(pr, x, true))     /* GSL asks for J at the same x next */
        return GSL_EDOM;
    for (int i = 0; i < pr->n; i++)
        gsl_vector_set(f, (size_t)i, sqrt(pr->d->weight[pr->at[i]])
                                     * (pr->value[pr->at[i]] - pr->d->value[pr->at[i]]));
    return GSL_SUCCESS;
}

static int jacobian(const gsl_vector *x, void *params, gsl_matrix *J)
{
    Problem *pr = params;
    if (!evaluate(pr, x, true))
        return GSL_EDOM;
    size_t np = (size_t)pr->m->np;
    for (int i = 0; i < pr->n; i++)
        for (int c = 0; c < pr->k; c++) {
            double dpdu;
            design_of(pr, c, pr->x_done[c], &dpdu);
            gsl_matrix_set(J, (size_t)i, (size_t)c, sqrt(pr->d->weight[pr->at[i]]) * dpdu
                           * pr->dvalue[pr->at[i] * np + (size_t)pr->index[c]]);
        }
    return GSL_SUCCESS;
}

/* The weighted Jacobian in the design parameters themselves, at the last x. */
static gsl_matrix *design_jacobian(const Problem *pr)
{
    gsl_matrix *J = gsl_matrix_alloc((size_t)pr->n, (size_t)pr->k);
    size_t np = (size_t)pr->m->np;
    for (int i = 0; i < pr->n; i++)
        for (int c = 0; c < pr->k; c++)
            gsl_matrix_set(J, (size_t)i, (size_t)c, sqrt(pr->d->weight[pr->at[i]])
                           * pr->dvalue[pr->at[i] * np + (size_t)pr->index[c]]);
    return J;
}

/* J's singular values (descending) into s, its right singular vectors into V. */
static void singular_values(const gsl_matrix *J, gsl_vector *s, gsl_matrix *V)
{
    gsl_matrix *A = gsl_matrix_alloc(J->size1, J->size2);
    gsl_matrix_memcpy(A, J);
    gsl_vector *work = gsl_vector_alloc(J->size2);
    gsl_linalg_SV_decomp(A, V, s, work);
    gsl_vector_free(work);
    gsl_matrix_free(A);
}

/* Below this ratio of the least to the largest singular value, the data
   do not tell the parameters of the least one's direction apart. */
#define FIT_RANK_TOL 1e-9

/* The parameters that the least singular direction mixes, into buf. */
static void name_direction(const Problem *pr, const gsl_matrix *V, char *buf, size_t size)
{
    size_t last = V->size2 - 1, n = 0;
    double big = 0;
    for (int c = 0; c < pr->k; c++)
        big = fmax(big, fabs(gsl_matrix_get(V, (size_t)c, last)));
    buf[0] = '\0';
    for (int c = 0; c < pr->k && n < size; c++) {
        double v = gsl_matrix_get(V, (size_t)c, last);
        if (fabs(v) >= 0.1 * big)
            n += (size_t)snprintf(buf + n, size - n, "%s%+.3g %s", n ? " " : "", v,
                                  pr->m->design_names[pr->index[c]]);
    }
}

/* J's condition, and when it is rank-deficient the parameters involved in why. */
static double condition(const Problem *pr, const gsl_matrix *J, char *why, size_t size)
{
    gsl_vector *s = gsl_vector_alloc(J->size2);
    gsl_matrix *V = gsl_matrix_alloc(J->size2, J->size2);
    singular_values(J, s, V);
    /* fabs: a zero singular value can come back as -0 */
    double smax = fabs(gsl_vector_get(s, 0)), smin = fabs(gsl_vector_get(s, J->size2 - 1));
    why[0] = '\0';
    if (!(smax > 0)) {
        size_t n = (size_t)snprintf(why, size, "the measured values do not depend on");
        for (int c = 0; c < pr->k && n < size; c++)
            n += (size_t)snprintf(why + n, size - n, "%s %s", c ? "," : "",
                                  pr->m->design_names[pr->index[c]]);
    } else if (!(smin > FIT_RANK_TOL * smax)) {
        char dir[300];
        name_direction(pr, V, dir, sizeof dir);
        snprintf(why, size, "the measurements do not identify the combination %s (the "
                 "Jacobian's singular values go from %.3g down to %.3g)", dir, smax, smin);
    }
    gsl_vector_free(s);
    gsl_matrix_free(V);
    return smin > 0 ? smax / smin : INFINITY;
}

static FitStatus fail(FitResult *r, FitStatus st, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static FitStatus fail(FitResult *r, FitStatus st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->message, sizeof r->message, fmt, ap);
    va_end(ap);
    return r->status = st;
}

/* The unknowns, the residuals' entries, the starting point; FIT_OK or why not. */
static FitStatus set_up(Problem *pr, FitResult *r, gsl_vector **x0)
{
    const Model *m = pr->m;
    const FitData *d = pr->d;
    pr->index = xcalloc((size_t)m->np, sizeof *pr->index);
    for (int j = 0; j < m->np; j++)
        if (pr->o->vary[j])
            pr->index[pr->k++] = j;
    pr->at = xcalloc((size_t)d->nmeasured + 1, sizeof *pr->at);
    for (size_t i = 0; i < (size_t)d->nsamples * (size_t)d->ncols; i++)
        if (!isnan(d->value[i]))
            pr->at[pr->n++] = i;
    size_t entries = (size_t)d->nsamples * (size_t)d->ncols;
    pr->value = xcalloc(entries, sizeof *pr->value);
    pr->dvalue = xcalloc(entries * (size_t)m->np, sizeof *pr->dvalue);
    pr->x_done = xcalloc((size_t)pr->k + 1, sizeof *pr->x_done);
    r->n = pr->n, r->k = pr->k;
    if (pr->k == 0)
        return fail(r, FIT_BAD_INPUT, "no design parameter to estimate");
    if (pr->n < pr->k)
        return fail(r, FIT_BAD_INPUT, "%d measured value%s cannot determine %d parameters",
                    pr->n, pr->n == 1 ? "" : "s", pr->k);
    *x0 = gsl_vector_alloc((size_t)pr->k);
    for (int i = 0; i < pr->k; i++) {
        int j = pr->index[i];
        double p = m->dag.param_values[j], lo = pr->o->lo[j], hi = pr->o->hi[j];
        if (bounded(pr, i) && !(lo < hi && p >= lo && p <= hi))
            return fail(r, FIT_BAD_INPUT, "design parameter '%s' starts at %.17g, outside its "
                        "bounds [%.17g, %.17g]", m->design_names[j], p, lo, hi);
        gsl_vector_set(*x0, (size_t)i, bounded(pr, i) ? asin(2 * (p - lo) / (hi - lo) - 1) : p);
    }
    return FIT_OK;
}

/* The results at the solver's x: design, costs, errors and correlations;
   false (r->solved too) when the motion cannot be followed there. */
static bool finish(Problem *pr, FitResult *r, gsl_multifit_nlinear_workspace *w)
{
    const Model *m = pr->m;
    if (!evaluate(pr, w->x, true))
        return false;
    r->solved = true;
    memcpy(r->p, m->dag.param_values, (size_t)m->np * sizeof *r->p);
    size_t entries = (size_t)pr->d->nsamples * (size_t)pr->d->ncols;
    memcpy(r->model, pr->value, entries * sizeof *r->model);
    double chi = gsl_blas_dnrm2(w->f);
    r->cost = chi * chi;
    r->iterations = (int)gsl_multifit_nlinear_niter(w);
    r->nevalf = (int)w->fdf->nevalf;
    r->nevaldf = (int)w->fdf->nevaldf;
    gsl_matrix *J = design_jacobian(pr), *covar = gsl_matrix_alloc((size_t)pr->k, (size_t)pr->k);
    r->cond = condition(pr, J, r->warning, sizeof r->warning);
    gsl_multifit_nlinear_covar(J, 0.0, covar);
    double scale = pr->n > pr->k ? r->cost / (pr->n - pr->k) : 0.0;
    for (int a = 0; a < pr->k; a++) {
        r->std_error[a] = sqrt(scale * gsl_matrix_get(covar, (size_t)a, (size_t)a));
        for (int b = 0; b < pr->k; b++) {
            double caa = gsl_matrix_get(covar, (size_t)a, (size_t)a);
            double cbb = gsl_matrix_get(covar, (size_t)b, (size_t)b);
            r->corr[a * pr->k + b] = gsl_matrix_get(covar, (size_t)a, (size_t)b) / sqrt(caa * cbb);
        }
    }
    gsl_matrix_free(J);
    gsl_matrix_free(covar);
    return true;
}

/* The starting point's cost and identifiability; FIT_OK or why not. */
static FitStatus check_start(Problem *pr, FitResult *r, const gsl_vector *x0)
{
    if (!evaluate(pr, x0, true))
        return fail(r, FIT_FAILED, "at the starting design: %s", pr->why);
    r->cost0 = 0;
    for (int i = 0; i < pr->n; i++) {
        double e = pr->value[pr->at[i]] - pr->d->value[pr->at[i]];
        r->cost0 += pr->d->weight[pr->at[i]] * e * e;
    }
    gsl_matrix *J = design_jacobian(pr);
    char why[400];
    condition(pr, J, why, sizeof why);
    gsl_matrix_free(J);
    if (why[0])
        return fail(r, FIT_BAD_INPUT, "%s", why);
    return FIT_OK;
}

static void result_alloc(FitResult *r, const Model *m, const FitData *d)
{
    memset(r, 0, sizeof *r);
    size_t np = (size_t)m->np;
    r->p0 = xcalloc(np, sizeof *r->p0);
    r->p = xcalloc(np, sizeof *r->p);
    r->std_error = xcalloc(np, sizeof *r->std_error);
    r->corr = xcalloc(np * np, sizeof *r->corr);
    r->model = xcalloc((size_t)d->nsamples * (size_t)d->ncols, sizeof *r->model);
    if (np) {   /* none: fit_sampler_init refuses the file */
        memcpy(r->p0, m->dag.param_values, np * sizeof *r->p0);
        memcpy(r->p, r->p0, np * sizeof *r->p);
    }
    r->reason = "";
}

/* GSL's solver from x0 to the end; FIT_OK or why not. */
static FitStatus solve(Problem *pr, FitResult *r, gsl_vector *x0)
{
    gsl_multifit_nlinear_fdf fdf = {.f = residuals, .df = jacobian, .fvv = NULL,
                                    .n = (size_t)pr->n, .p = (size_t)pr->k, .params = pr};
    gsl_multifit_nlinear_parameters params = gsl_multifit_nlinear_default_parameters();
    gsl_multifit_nlinear_workspace *w =
        gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &params, (size_t)pr->n, (size_t)pr->k);
    int info = 0, st = gsl_multifit_nlinear_init(x0, &fdf, w);
    if (st == GSL_SUCCESS)
        st = gsl_multifit_nlinear_driver((size_t)pr->o->max_iter, pr->o->xtol, pr->o->gtol,
                                         pr->o->ftol, NULL, NULL, &info, w);
    r->reason = info == 1 ? "small step" : info == 2 ? "small gradient" : "";
    bool ended = st == GSL_SUCCESS || st == GSL_ENOPROG || st == GSL_EMAXITER;
    if (ended && !finish(pr, r, w)) {
        fail(r, FIT_FAILED, "at the solver's last design: %s", pr->why);
    } else if (st == GSL_SUCCESS || st == GSL_ENOPROG) {   /* no progress at a minimum: done */
        if (st == GSL_ENOPROG)
            r->reason = "no further decrease";
    } else if (st == GSL_EMAXITER) {
        fail(r, FIT_FAILED, "no convergence in %d iterations (cost %.6g from %.6g)",
             pr->o->max_iter, r->cost, r->cost0);
    } else {
        fail(r, FIT_FAILED, "the solver stopped: %s%s%s", gsl_strerror(st),
             pr->why[0] ? ": " : "", pr->why);
    }
    gsl_multifit_nlinear_free(w);
    return r->status;
}

FitStatus fit_run(Model *m, const Kinematics *kin, const Engine *e, const FitData *d,
                  const FitOptions *o, FitResult *r)
{
    clock_t start = clock();
    result_alloc(r, m, d);
    Problem pr = {.m = m, .d = d, .o = o};
    gsl_vector *x0 = NULL;
    char why[300];
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    if (!fit_sampler_init(&pr.smp, m, kin, e, d, o->steps, o->newton_tol, why, sizeof why))
        fail(r, FIT_BAD_INPUT, "%s", why);
    else if (set_up(&pr, r, &x0) == FIT_OK && check_start(&pr, r, x0) == FIT_OK)
        solve(&pr, r, x0);
    gsl_set_error_handler(old);
    r->index = pr.index;
    if (r->status != FIT_OK && r->status != FIT_FAILED)
        model_set_design(m, r->p0);
    if (x0)
        gsl_vector_free(x0);
    fit_sampler_free(&pr.smp);
    free(pr.at), free(pr.value), free(pr.dvalue), free(pr.x_done);
    r->cpu_seconds = (double)(clock() - start) / CLOCKS_PER_SEC;
    return r->status;
}

void fit_result_free(FitResult *r)
{
    free(r->index), free(r->p0), free(r->p), free(r->std_error), free(r->corr), free(r->model);
    memset(r, 0, sizeof *r);
}
