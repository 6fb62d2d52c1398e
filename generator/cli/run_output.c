/* run_output.c - where the states of `mechc run` and `mechc sim` go: CSV, JSON, the kept rows, pictures.
 *
 * Both commands stream their states here as they are computed: the CSV
 * row (runtime/host/output.c), the kept row for JSON and pictures, the
 * progress line. The file's `output` statements are evaluated beside the
 * coordinates, a spatial body's angular velocity beside the velocities.
 * Multipliers (sim's, and run --forces') are kept per row for JSON; with
 * --forces they are also CSV columns lambda(ROW) and effort(DRIVER) =
 * -lambda(DRIVER), plottable, and drawn as arrows at the joints.
 */
#include "run_output.h"

#include "../base/arena.h"
#include "../render/reactions.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The drivers' rows and names, and the extra CSV columns' names. */
static void open_forces(RunOutput *out, const Model *m)
{
    out->drivers = xcalloc((size_t)m->nr + 1, sizeof *out->drivers);
    out->dnames = xcalloc((size_t)m->nr + 1, sizeof *out->dnames);
    for (int i = 0; i < m->nr; i++)
        if (m->rows[i].kind == JOINT_DRIVER) {
            out->dnames[out->nd] = m->rows[i].name;
            out->drivers[out->nd++] = i;
        }
    out->nx = m->nr + out->nd;
    out->xnames = xcalloc((size_t)out->nx + 1, sizeof *out->xnames);
    out->x = xcalloc((size_t)out->nx + 1, sizeof *out->x);
    for (int i = 0; i < out->nx; i++) {
        const char *name = i < m->nr ? m->rows[i].name : out->dnames[i - m->nr];
        size_t len = strlen(name) + 16;
        out->xnames[i] = xmalloc(len);
        snprintf(out->xnames[i], len, "%s(%s)", i < m->nr ? "lambda" : "effort", name);
    }
}

void run_output_open(RunOutput *out, const Model *m)
{
    out->m = m;
    out->nq = m->nq;
    out->nv = m->nq + m->nout;
    out->nr = m->nr;
    outputs_init(&out->outputs, m);
    out->v = xcalloc(3 * (size_t)out->nv, sizeof *out->v);
    out->names = xcalloc((size_t)out->nv, sizeof *out->names);
    for (int i = 0; i < out->nv; i++)
        out->names[i] = i < m->nq ? m->coord_names[i] : m->outputs[i - m->nq].name;
    mechrt_trace_init(&out->trace, out->nv);
    out->w = xcalloc((size_t)out->outputs.nw + 1, sizeof *out->w);
    mechrt_trace_set_omega(&out->trace, out->outputs.nw,
                           (const char *const *)out->outputs.wnames);
    if (out->lambda_use == RUN_OUTPUT_FORCES)
        open_forces(out, m);
}

void run_output_set_extra(RunOutput *out, int n, char **names,
                          void (*fill)(void *ctx, double t, const double *q, const double *qd,
                                       const double *qdd, double *x), void *ctx)
{
    out->nx = n;
    out->xnames = names;
    out->x = xcalloc((size_t)n + 1, sizeof *out->x);
    out->extra = fill;
    out->extra_ctx = ctx;
}

void run_output_close(RunOutput *out)
{
    outputs_free(&out->outputs);
    free(out->v), free(out->w), free(out->names);
    free(out->lambda), free(out->efforts), free(out->drivers), free(out->dnames);
    for (int i = 0; i < out->nx; i++)
        free(out->xnames[i]);
    free(out->xnames), free(out->x), free(out->xkept);
    mechrt_trace_free(&out->trace);
}

/* The state's coordinates followed by the outputs' values, in out->v. */
static void fill_variables(RunOutput *out, double t, const double *q, const double *qd,
                           const double *qdd)
{
    size_t nq = (size_t)out->nq, nv = (size_t)out->nv;
    const double *src[3] = {q, qd, qdd};
    for (size_t k = 0; k < 3; k++)
        memcpy(out->v + k * nv, src[k], nq * sizeof *out->v);
    outputs_eval(&out->outputs, q, qd, qdd, t, out->v + nq, out->v + nv + nq,
                 out->v + 2 * nv + nq);
}

/* An output that is NaN or infinite (sqrt of a negative, ...) is written
   as such; the first one is said on stderr, with its time. */
static void warn_nonfinite(RunOutput *out, double t)
{
    for (int k = 0; k < 3 && !out->warned; k++)
        for (int i = out->nq; i < out->nv && !out->warned; i++)
            if (!isfinite(out->v[k * out->nv + i])) {
                fprintf(stderr, "%s: warning: output '%s' is not finite at t = %.10g (later "
                        "ones are not reported)\n", out->m->file, out->names[i], t);
                out->warned = true;
            }
}

/* Keeps a state's multipliers (and efforts) for the kept row about to be
   pushed; false when out of memory. */
static bool keep_lambda(RunOutput *out, const double *lambda)
{
    size_t nr = (size_t)out->nr, nd = (size_t)out->nd, row = out->trace.rows;
    if (row + 1 > out->lcap) {
        size_t cap = out->lcap ? 2 * out->lcap : 64;
        double *p = realloc(out->lambda, cap * (nr + 1) * sizeof *p);
        if (!p)
            return false;
        out->lambda = p;
        p = realloc(out->efforts, cap * (nd + 1) * sizeof *p);
        if (!p)
            return false;
        out->efforts = p;
        out->lcap = cap;
    }
    memcpy(out->lambda + row * nr, lambda, nr * sizeof *lambda);
    for (size_t i = 0; i < nd; i++)
        out->efforts[row * nd + i] = -lambda[out->drivers[i]];
    return true;
}

/* Keeps a state's extra columns for the kept row about to be pushed;
   false when out of memory. */
static bool keep_extra(RunOutput *out)
{
    size_t nx = (size_t)out->nx, row = out->trace.rows;
    if (row + 1 > out->xcap) {
        size_t cap = out->xcap ? 2 * out->xcap : 64;
        double *p = realloc(out->xkept, cap * (nx + 1) * sizeof *p);
        if (!p)
            return false;
        out->xkept = p;
        out->xcap = cap;
    }
    memcpy(out->xkept + row * nx, out->x, nx * sizeof *out->x);
    return true;
}

void run_output_state(void *ctx, double t, const double *q, const double *qd,
                      const double *qdd, const double *lambda)
{
    RunOutput *out = ctx;
    outputs_omega(&out->outputs, q, qd, out->w);
    if (out->extra)     /* before q becomes the variables (outputs appended) */
        out->extra(out->extra_ctx, t, q, qd, qdd, out->x);
    if (out->nv > out->nq) {
        fill_variables(out, t, q, qd, qdd);
        q = out->v, qd = out->v + out->nv, qdd = out->v + 2 * out->nv;
        warn_nonfinite(out, t);
    }
    if (out->lambda_use == RUN_OUTPUT_FORCES) {
        memcpy(out->x, lambda, (size_t)out->nr * sizeof *lambda);
        for (int i = 0; i < out->nd; i++)
            out->x[out->nr + i] = -lambda[out->drivers[i]];
    }
    if (out->csv && !out->headed) {
        mechrt_csv_header_extra(out->csv, out->nv, out->names, out->outputs.nw,
                                (const char *const *)out->outputs.wnames, out->nx,
                                (const char *const *)out->xnames);
        out->headed = true;
    }
    if (out->csv)
        mechrt_csv_row_extra(out->csv, out->nv, t, q, qd, qdd, out->outputs.nw, out->w,
                             out->nx, out->x, out->digits);
    if (out->keep && ((lambda && out->lambda_use != RUN_OUTPUT_NO_LAMBDA
                       && !keep_lambda(out, lambda))
                      || (out->extra && !keep_extra(out))
                      || !mechrt_trace_push_omega(&out->trace, t, q, qd, qdd, out->w)))
        out->full = true;
    if (out->t1 != out->t0)
        progress_update(&out->progress, (long)(1000.0 * (t - out->t0) / (out->t1 - out->t0)));
}

void run_output_kinematic_state(void *ctx, double t, const double *q, const double *qd,
                                const double *qdd)
{
    run_output_state(ctx, t, q, qd, qdd, NULL);
}

void run_output_json(FILE *f, const RunOutput *out, const char *error_message, double error_t)
{
    const Model *m = out->m;
    if (out->extra) {       /* run --sens: its columns, no multipliers */
        MechrtJsonLambda lam = {.nx = out->nx, .xnames = (const char *const *)out->xnames,
                                .x = out->xkept, .xnames_key = "sens_columns", .x_key = "sens"};
        mechrt_json_write_lambda(f, &out->trace, m->nq, out->names, out->digits, error_message,
                                 error_t, &lam);
        return;
    }
    if (out->lambda_use == RUN_OUTPUT_NO_LAMBDA) {
        mechrt_json_write_outputs(f, &out->trace, m->nq, out->names, out->digits, error_message,
                                  error_t);
        return;
    }
    const char **rows = xcalloc((size_t)m->nr + 1, sizeof *rows);
    for (int i = 0; i < m->nr; i++)
        rows[i] = m->rows[i].name;
    MechrtJsonLambda lam = {.nr = m->nr, .rows = rows, .lambda = out->lambda};
    if (out->lambda_use == RUN_OUTPUT_FORCES)
        lam.nd = out->nd, lam.drivers = out->dnames, lam.efforts = out->efforts;
    mechrt_json_write_lambda(f, &out->trace, m->nq, out->names, out->digits, error_message,
                             error_t, &lam);
    free(rows);
}

/* The point outputs' paths after the --trace points; a note when some
   do not fit. */
static void add_point_outputs(const Model *m, RunPictures *p, bool svg)
{
    int dropped = 0;
    for (int k = 0; k < m->nout; k++) {
        const ModelOutput *o = &m->outputs[k];
        if (!o->point || o->at.q < 0)    /* a point output's path; ground's stays put */
            continue;
        if (p->ntraces < RUN_OUTPUT_MAX_TRACES)
            p->traces[p->ntraces++] = (SvgTrace){o->at.q, o->at.has_phi || o->at.has_p,
                                                 o->at.sx, o->at.sy, o->point, o->at.spatial,
                                                 o->at.sz};
        else
            dropped++;
    }
    if (dropped > 0 && svg)
        fprintf(stderr, "%s: note: the paths of %d point output%s are not drawn (at most %d "
                "paths)\n", m->file, dropped, dropped == 1 ? "" : "s", RUN_OUTPUT_MAX_TRACES);
}

bool run_output_resolve_pictures(const char *cmd, const Model *m, const CliList *traces,
                                 const char *plot_list, bool forces, RunPictures *p)
{
    char err[256];
    if (!m->spatial && p->view >= 0) {
        fprintf(stderr, "%s: error: --view chooses how a spatial mechanism is seen, and this "
                "one is planar (drawn as it is, x right, y up)\n", m->file);
        return false;
    }
    p->ntraces = p->nvars = 0;
    for (int i = 0; i < traces->n; i++) {
        if (!svg_parse_trace(m, traces->items[i], &p->traces[p->ntraces++], err, sizeof err)) {
            fprintf(stderr, "mechc %s: error: %s\n", cmd, err);
            return false;
        }
    }
    add_point_outputs(m, p, p->svg_path != NULL);
    if (p->plot_path && plot_list) {
        size_t size = svg_plot_err_size(m) + strlen(plot_list);
        char *why = xmalloc(size);
        p->nvars = svg_plot_resolve_columns(m, plot_list, forces, p->sens, p->vars,
                                            RUN_OUTPUT_MAX_PLOT_VARS, why, size);
        if (p->nvars <= 0)
            fprintf(stderr, "mechc %s: error: %s\n", cmd, why);
        free(why);
        if (p->nvars <= 0)
            return false;
    } else if (p->plot_path) {
        for (int i = 0; i < m->nq + m->nout && p->nvars < RUN_OUTPUT_MAX_PLOT_VARS; i++)
            p->vars[p->nvars++] = (SvgPlotVar){i, 0};
        if (m->nq + m->nout > RUN_OUTPUT_MAX_PLOT_VARS)
            fprintf(stderr, "%s: note: --plot shows the first %d of %d variables; choose "
                    "them with --plot-vars\n", m->file, RUN_OUTPUT_MAX_PLOT_VARS,
                    m->nq + m->nout);
    }
    return true;
}

/* Variable v's values over the kept rows: the first and the stride. */
static SvgSeries plot_series(const RunOutput *out, SvgPlotVar v, const char *name)
{
    size_t nv = (size_t)out->trace.nq, w = 1 + 3 * nv;
    if (v.order == SVG_PLOT_LAMBDA)
        return (SvgSeries){name, out->lambda + v.coord, out->nr};
    if (v.order == SVG_PLOT_SENS)
        return (SvgSeries){name, out->xkept + v.coord, out->nx};
    if (v.order == SVG_PLOT_EFFORT) {
        int d = 0;
        while (d + 1 < out->nd && out->drivers[d] != v.coord)
            d++;
        return (SvgSeries){name, out->efforts + d, out->nd};
    }
    return (SvgSeries){name, out->trace.data + 1 + (size_t)v.order * nv + (size_t)v.coord, (int)w};
}

/* One picture file: the animation (which 0) or the chart (1). */
static bool write_picture(const RunOutput *out, const RunPictures *p, int which,
                          const double *t, const double *q)
{
    const Model *m = out->m;
    const char *path = which == 0 ? p->svg_path : p->plot_path;
    int n = (int)out->trace.rows;
    FILE *f = cli_open_output(out->cmd, path);
    if (!f)
        return false;
    bool wrote;
    if (which == 0) {
        SvgAnimOptions ao = svg_anim_default_options();
        SvgForce forces[RUN_OUTPUT_MAX_FORCES];
        double *fvals = NULL;
        if (p->view >= 0)
            ao.view = (SvgView)p->view;
        if (out->lambda_use == RUN_OUTPUT_FORCES && out->lambda) {
            ao.nforces = reactions_compute(m, q, out->lambda, n, forces, RUN_OUTPUT_MAX_FORCES,
                                           &fvals);
            ao.forces = forces;
        }
        wrote = svg_write_animation_opt(f, m, t, q, n, p->traces, p->ntraces, m->name, &ao);
        free(fvals);
    } else {
        SvgSeries series[RUN_OUTPUT_MAX_PLOT_VARS];
        char names[RUN_OUTPUT_MAX_PLOT_VARS][96];
        for (int i = 0; i < p->nvars; i++) {
            svg_plot_var_name(m, p->vars[i], names[i], sizeof names[i]);
            series[i] = plot_series(out, p->vars[i], names[i]);
        }
        wrote = svg_write_plot(f, m->name, t, n, series, p->nvars);
    }
    if (fclose(f) != 0 || !wrote) {
        fprintf(stderr, "mechc %s: error: writing '%s' failed\n", out->cmd, path);
        return false;
    }
    return true;
}

bool run_output_pictures(const RunOutput *out, const RunPictures *p)
{
    const MechrtTrace *tr = &out->trace;
    size_t n = tr->rows, nq = (size_t)out->nq, w = 1 + 3 * (size_t)tr->nq;
    bool ok = true;
    if (n == 0)
        return true;
    double *t = xcalloc(n, sizeof *t), *q = xcalloc(n * nq, sizeof *q);
    for (size_t k = 0; k < n; k++) {
        t[k] = tr->data[k * w];
        memcpy(q + k * nq, tr->data + k * w + 1, nq * sizeof *q);
    }
    for (int which = 0; which < 2; which++)
        if (which == 0 ? p->svg_path != NULL : p->plot_path != NULL)
            ok = write_picture(out, p, which, t, q) && ok;
    free(t), free(q);
    return ok;
}

bool run_output_report_failure(const RunOutput *out, const Model *m, const char *message,
                               int states, double t_fail)
{
    if (message) {
        fprintf(stderr, "%s: error: %s\n", m->file, message);
        if (states > 0)
            fprintf(stderr, "%s: note: the %d %s before t = %.10g %s written\n", m->file, states,
                    states == 1 ? "state" : "states", t_fail, states == 1 ? "is" : "are");
    }
    if (out->full)
        fprintf(stderr, "mechc %s: error: out of memory keeping the states for JSON\n", out->cmd);
    return message || out->full;
}
