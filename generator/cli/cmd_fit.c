/* cmd_fit.c - mechc fit: design parameters identified from measured motion (generator/fit/). */
#include "cli.h"

#include "../base/arena.h"
#include "../fit/fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct FitCli {
    mechc_limits limits;
    const char *data_path, *vary_list;
    CliList bounds;         /* NAME=LO:HI */
    FitOptions fo;
    double tol;             /* --tol: xtol and gtol; 0: not given */
    int engine, worst;
    bool json;
} FitCli;

static const char usage[] =
    "usage: mechc fit FILE.mech --data MEASURED.csv [--vary LIST] [--bound NAME=LO:HI]\n"
    "                 [--json] [options]\n"
    "\n"
    "Identifies design parameters (`design NAME = value`) from measurements:\n"
    "nonlinear least squares (GSL's trust region, Levenberg-Marquardt) on the\n"
    "measured coordinates and outputs, its Jacobian from the sensitivities\n"
    "Phi_q q_p = -Phi_p (no finite differences). The motion is followed through\n"
    "the samples in time order from the file's initial values (the assembly\n"
    "branch they choose), as `run` does. Reports the estimates, their standard\n"
    "errors and correlations (from the Jacobian at the solution, scaled by the\n"
    "residual variance), the residual of every measured column and the samples\n"
    "that fit worst. Start from other values with --design.\n"
    "\n";

static const CliOption options[] = {
    {"--data", CLI_STRING_AT(FitCli, data_path), .metavar = "FILE",
     .help = "the measurements: a CSV whose header names t, then\n"
             "coordinates or outputs measured (crank.phi, P.x), and\n"
             "optional weights w(NAME) (inverse variances; default 1);\n"
             "one sample per row, times in order, empty = not measured"},
    {"--vary", CLI_STRING_AT(FitCli, vary_list), .metavar = "LIST",
     .help = "the design parameters to estimate, comma-separated\n"
             "(default: all; the others keep their values)"},
    {"--bound", CLI_LIST_AT(FitCli, bounds, CLI_LIST_MAX), .what = "bounds", .metavar = "P=LO:HI",
     .help = "keep parameter P in [LO, HI] (repeatable)"},
    {"--steps", CLI_INT_AT(FitCli, fo.steps, 1, 100000000), .metavar = "N",
     .help = "intervals over the data's time span when following the\n"
             "motion between samples (default 20; steps that would\n"
             "leave the assembly branch are subdivided, as in run)"},
    {"--max-iter", CLI_INT_AT(FitCli, fo.max_iter, 1, 100000), .metavar = "N",
     .help = "solver iterations (default 200)"},
    {"--tol", CLI_REAL_AT(FitCli, tol), CLI_POSITIVE, .what = "a positive number", .echo = true,
     .metavar = "X", .help = "converged when a step changes no parameter by more than\n"
                             "X relative, or the gradient is below X (default 1e-15)"},
    {"--newton-tol", CLI_REAL_AT(FitCli, fo.newton_tol), CLI_POSITIVE, .what = "a positive number",
     .echo = true, .metavar = "X",
     .help = "the positions' Newton tolerance, max |Phi_i| and the last\n"
             "step's max |dq_j| (default 1e-12)"},
    {"--worst", CLI_INT_AT(FitCli, worst, 0, 1000), .metavar = "N",
     .help = "how many of the worst-fitting values to list (default 5)"},
    {"--engine", CLI_CHOICE_AT(FitCli, engine, engine_names), .metavar = "E",
     .help = "jit (default), generic or aot, as for eval"},
    {"--json", CLI_FLAG_AT(FitCli, json),
     .help = "print JSON: \"ok\", \"parameters\" (name, start, estimate,\n"
             "std_error), \"correlation\", \"cost0\", \"cost\", \"iterations\",\n"
             "\"residuals\", \"worst\", \"design\" (a fit that could not\n"
             "start or go on: \"ok\": false and \"error\" alone)"},
};

static const char epilogue[] =
    "\n"
    "Exit status: 0 converged; 1 no convergence, or the motion cannot be followed\n"
    "at some design; 2 bad usage or input: a bad CSV (FILE:LINE:COL), fewer\n"
    "measured values than parameters, parameters the data cannot tell apart\n"
    "(named), a file without design parameters.\n";

static int design_index(const Model *m, const char *s, size_t len)
{
    for (int j = 0; j < m->np; j++)
        if (strlen(m->design_names[j]) == len && strncmp(m->design_names[j], s, len) == 0)
            return j;
    return -1;
}

/* --vary and --bound into o (arrays np long); false (reported) on a bad one. */
static bool read_choices(const FitCli *c, const Model *m, FitOptions *o)
{
    for (int j = 0; j < m->np; j++)
        o->vary[j] = c->vary_list == NULL, o->lo[j] = -INFINITY, o->hi[j] = INFINITY;
    for (const char *s = c->vary_list; s && *s;) {
        size_t len = strcspn(s, ",");
        int j = design_index(m, s, len);
        if (j < 0) {
            fprintf(stderr, "mechc fit: error: --vary: '%.*s' is not a design parameter of %s\n",
                    (int)len, s, m->file);
            return false;
        }
        o->vary[j] = true;
        s += len + (s[len] == ',');
    }
    for (int i = 0; i < c->bounds.n; i++) {
        const char *b = c->bounds.items[i], *eq = strchr(b, '=');
        int j = eq ? design_index(m, b, (size_t)(eq - b)) : -1;
        char *colon = NULL, *end = NULL;
        double lo = eq ? strtod(eq + 1, &colon) : NAN, hi = NAN;
        if (colon && colon != eq + 1 && *colon == ':')     /* LO not empty */
            hi = strtod(colon + 1, &end);
        if (end == colon + 1)       /* HI empty */
            end = NULL;
        if (j < 0 || !end || *end || !isfinite(lo) || !isfinite(hi) || !(lo < hi)) {
            fprintf(stderr, "mechc fit: error: --bound takes P=LO:HI with P a design parameter "
                    "and LO < HI, not '%s'\n", b);
            return false;
        }
        o->lo[j] = lo, o->hi[j] = hi;
    }
    return true;
}

/* The measured entries in order of |sqrt(w) (model - measured)|, largest first. */
typedef struct Entry {
    size_t at;
    double r;
} Entry;

static int by_residual(const void *a, const void *b)
{
    double ra = ((const Entry *)a)->r, rb = ((const Entry *)b)->r;
    return ra < rb ? 1 : ra > rb ? -1 : 0;
}

static Entry *rank_entries(const FitData *d, const FitResult *r, int *n)
{
    Entry *e = xcalloc((size_t)d->nmeasured + 1, sizeof *e);
    *n = 0;
    for (size_t i = 0; i < (size_t)d->nsamples * (size_t)d->ncols; i++)
        if (!isnan(d->value[i]))
            e[(*n)++] = (Entry){i, sqrt(d->weight[i]) * fabs(r->model[i] - d->value[i])};
    qsort(e, (size_t)*n, sizeof *e, by_residual);
    return e;
}

/* rms and largest |model - measured| of column c. */
static void column_stats(const FitData *d, const FitResult *r, int c, double *rms, double *max)
{
    double sum = 0;
    int n = 0;
    *max = 0;
    for (int s = 0; s < d->nsamples; s++) {
        size_t i = (size_t)s * (size_t)d->ncols + (size_t)c;
        if (isnan(d->value[i]))
            continue;
        double e = r->model[i] - d->value[i];
        sum += e * e, n++;
        *max = fmax(*max, fabs(e));
    }
    *rms = n ? sqrt(sum / n) : 0;
}

static void print_text(const Model *m, const FitData *d, const FitResult *r, const char *path,
                       int worst)
{
    printf("fit %s: %d parameter%s from %d measured value%s at %d sample%s (%s)\n", m->name, r->k,
           r->k == 1 ? "" : "s", r->n, r->n == 1 ? "" : "s", d->nsamples,
           d->nsamples == 1 ? "" : "s", path);
    printf("%s: %s after %d iterations (%d evaluations of the motion, %d of its sensitivities, "
           "%.3g ms of CPU); cost %.6g -> %.6g\n\n",
           r->status == FIT_OK ? "converged" : "not converged", r->reason[0] ? r->reason : "stopped",
           r->iterations, r->nevalf, r->nevaldf, 1e3 * r->cpu_seconds, r->cost0, r->cost);
    printf("%-14s %24s %24s %12s\n", "parameter", "start", "estimate", "std error");
    for (int a = 0; a < r->k; a++) {
        int j = r->index[a];
        char se[32] = "-";      /* as many values as parameters: no residual variance */
        if (r->n > r->k)
            snprintf(se, sizeof se, "%.4g", r->std_error[a]);
        printf("%-14s %24.17g %24.17g %12s\n", m->design_names[j], r->p0[j], r->p[j], se);
    }
    printf("\ncorrelation:\n%-14s", "");
    for (int b = 0; b < r->k; b++)
        printf(" %8.8s", m->design_names[r->index[b]]);
    for (int a = 0; a < r->k; a++) {
        printf("\n%-14s", m->design_names[r->index[a]]);
        for (int b = 0; b < r->k; b++)
            printf(" %8.4f", r->corr[a * r->k + b]);
    }
    printf("\n\nresiduals (model - measured), condition of the Jacobian %.3g:\n%-14s %12s %12s\n",
           r->cond, "column", "rms", "max");
    for (int c = 0; c < d->ncols; c++) {
        double rms, max;
        column_stats(d, r, c, &rms, &max);
        printf("%-14s %12.4g %12.4g\n", d->names[c], rms, max);
    }
    int n;
    Entry *e = rank_entries(d, r, &n);
    if (worst > 0 && n > 0)
        printf("\nworst-fitting values:\n%6s %14s %-14s %20s %20s %12s\n", "line", "t", "column",
               "measured", "model", "residual");
    for (int i = 0; i < worst && i < n; i++) {
        size_t s = e[i].at / (size_t)d->ncols, c = e[i].at % (size_t)d->ncols;
        printf("%6d %14.8g %-14s %20.12g %20.12g %12.4g\n", d->line[s], d->t[s], d->names[c],
               d->value[e[i].at], r->model[e[i].at], r->model[e[i].at] - d->value[e[i].at]);
    }
    free(e);
    printf("\ndesign:");
    for (int j = 0; j < m->np; j++)
        printf("%s%s=%.17g", j ? "," : " --design ", m->design_names[j], r->p[j]);
    printf("\n");
}

static void print_json(const Model *m, const FitData *d, const FitResult *r, int worst)
{
    printf("{\"ok\": %s, \"iterations\": %d, \"evaluations\": %d, \"reason\": ",
           r->status == FIT_OK ? "true" : "false", r->iterations, r->nevalf);
    json_string(stdout, r->reason);
    printf(",\n \"cost0\": ");
    json_number(stdout, r->cost0);
    printf(", \"cost\": ");
    json_number(stdout, r->cost);
    printf(", \"condition\": ");
    json_number(stdout, r->cond);
    printf(", \"cpu_seconds\": ");
    json_number(stdout, r->cpu_seconds);
    if (r->status != FIT_OK) {
        printf(", \"error\": ");
        json_string(stdout, r->message);
    }
    if (r->warning[0]) {
        printf(", \"warning\": ");
        json_string(stdout, r->warning);
    }
    printf(",\n \"parameters\": [");
    for (int a = 0; a < r->k; a++) {
        int j = r->index[a];
        printf("%s{\"name\": ", a ? ",\n                " : "");
        json_string(stdout, m->design_names[j]);
        printf(", \"start\": ");
        json_number(stdout, r->p0[j]);
        printf(", \"estimate\": ");
        json_number(stdout, r->p[j]);
        printf(", \"std_error\": ");
        json_number(stdout, r->n > r->k ? r->std_error[a] : NAN);
        printf("}");
    }
    printf("],\n \"correlation\": [");
    for (int a = 0; a < r->k; a++) {
        printf(a ? ", [" : "[");
        for (int b = 0; b < r->k; b++) {
            printf(b ? ", " : "");
            json_number(stdout, r->corr[a * r->k + b]);
        }
        printf("]");
    }
    printf("],\n \"residuals\": [");
    for (int c = 0; c < d->ncols; c++) {
        double rms, max;
        column_stats(d, r, c, &rms, &max);
        printf("%s{\"name\": ", c ? ", " : "");
        json_string(stdout, d->names[c]);
        printf(", \"rms\": ");
        json_number(stdout, rms);
        printf(", \"max\": ");
        json_number(stdout, max);
        printf("}");
    }
    printf("],\n \"worst\": [");
    int n;
    Entry *e = rank_entries(d, r, &n);
    for (int i = 0; i < worst && i < n; i++) {
        size_t s = e[i].at / (size_t)d->ncols, c = e[i].at % (size_t)d->ncols;
        printf("%s{\"line\": %d, \"t\": ", i ? ", " : "", d->line[s]);
        json_number(stdout, d->t[s]);
        printf(", \"name\": ");
        json_string(stdout, d->names[c]);
        printf(", \"measured\": ");
        json_number(stdout, d->value[e[i].at]);
        printf(", \"model\": ");
        json_number(stdout, r->model[e[i].at]);
        printf("}");
    }
    free(e);
    printf("],\n \"design\": {");
    for (int j = 0; j < m->np; j++) {
        printf(j ? ", " : "");
        json_string(stdout, m->design_names[j]);
        printf(": ");
        json_number(stdout, r->p[j]);
    }
    printf("}}\n");
}

static int fit_file(const Args *a, mechc_model *model, void *opts)
{
    Mech *mech = model->mech;
    Diag *diag = &model->diag;     /* the file's: its text for positions */
    FitCli *c = opts;
    Model *m = mech->model;
    if (m->np == 0) {
        diag_error(diag, m->last_pos, "fit: the file has no design parameters: declare what "
                   "to identify with `design NAME = value`");
        diag_print(diag, stderr);
        return EXIT_USAGE;
    }
    FitOptions o = c->fo;
    o.vary = xcalloc((size_t)m->np, sizeof *o.vary);
    o.lo = xcalloc((size_t)m->np, sizeof *o.lo);
    o.hi = xcalloc((size_t)m->np, sizeof *o.hi);
    if (c->tol > 0)
        o.xtol = o.gtol = c->tol;
    FitData d = {0};
    Diag data_diag = {0};     /* failed stays false unless the CSV was read */
    mechc_kernels *k = NULL;
    int status = EXIT_USAGE;
    bool data = read_choices(c, m, &o) && fit_data_read(c->data_path, m, &d, &data_diag);
    if (!data && data_diag.failed)
        diag_print(&data_diag, stderr);
    if (data && (k = cli_compile(a, model, (EngineKind)c->engine, NULL))) {
        FitResult r;
        FitStatus st = fit_run(m, &mech->kin, &k->engine, &d, &o, &r);
        if (st == FIT_BAD_INPUT) {
            fprintf(stderr, "mechc fit: error: %s: %s\n", m->file, r.message);
        } else if (!r.solved) {     /* no estimates to show */
            if (c->json) {
                printf("{\"ok\": false, \"error\": ");
                json_string(stdout, r.message);
                printf("}\n");
            }
            fprintf(stderr, "%s: error: fit: %s\n", m->file, r.message);
            status = EXIT_ANALYSIS;
        } else {
            if (c->json)
                print_json(m, &d, &r, c->worst);
            else
                print_text(m, &d, &r, c->data_path, c->worst);
            if (r.warning[0])
                fprintf(stderr, "%s: warning: at the solution %s\n", m->file, r.warning);
            if (st == FIT_FAILED)
                fprintf(stderr, "%s: error: fit: %s\n", m->file, r.message);
            status = st == FIT_OK ? EXIT_OK : EXIT_ANALYSIS;
        }
        fit_result_free(&r);
        mechc_kernels_free(k);
    }
    fit_data_free(&d);
    free(o.vary), free(o.lo), free(o.hi);
    return status;
}

static bool finish(Args *a, void *opts)
{
    FitCli *c = opts;
    if (!args_need_file(a))
        return false;
    if (!c->data_path) {
        fprintf(stderr, "mechc fit: error: --data FILE.csv is required (the measurements)\n");
        return false;
    }
    return true;
}

static const CliCommand command = {
    .name = "fit", .usage = usage, CLI_OPTIONS(options), .column = 19, .epilogue = epilogue,
    .limits_offset = offsetof(FitCli, limits), .finish = finish, .run = fit_file,
};

int cmd_fit(int argc, char **argv)
{
    FitCli c = {.limits = mechc_default_limits(), .fo = fit_default_options(),
                .engine = ENGINE_JIT, .worst = 5};
    return cli_main(&command, argc, argv, &c);
}
