/* cmd_sim.c - mechc sim: forward dynamics over time of a mechanism with masses.
 *
 * Parses the options, loads the mechanism, opens the engine and hands the
 * rest to sim_run (generator/analysis/sim.c). The states go out as run's
 * do: the same CSV columns and JSON keys (runtime/host/output.c), the
 * file's outputs beside the coordinates, the same animation and chart
 * writers; JSON adds the multipliers ("rows", "lambda"). On a failure the
 * states computed before it are still written, and the message goes to
 * stderr.
 */
#include "cli.h"

#include "../analysis/outputs.h"
#include "../analysis/sim.h"
#include "../base/arena.h"
#include "../render/progress.h"
#include "../render/svg_anim.h"
#include "../render/svg_plot.h"
#include "../../runtime/host/mechrt_host.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_TRACES = CLI_LIST_MAX, MAX_PLOT_VARS = 64 };

/* What the command line asked for. */
typedef struct SimCli {
    SimOptions so;
    MechLimits limits;
    const char *csv_path, *svg_path, *plot_path, *plot_list, *qd_text, *baumgarte;
    CliList traces;
    int engine, method, digits;
    bool json, stats;
    bool pictures, csv_stdout;      /* worked out from the above */
} SimCli;

static const char usage[] =
    "usage: mechc sim FILE.mech [--t0 T] [--t1 T] [--steps N] [--engine jit|generic|aot]\n"
    "                 [--csv OUT.csv] [--json] [options]\n"
    "\n"
    "Forward dynamics of a mechanism with masses (`mass`, `gravity`, forces and\n"
    "springs in the file): assembles it at t0 from the file's initial values as\n"
    "run does, makes the initial velocities consistent (zero unless --qd; a\n"
    "driver gives its rate), then integrates M qdd + Phi_q^T lambda = Q,\n"
    "Phi_q qdd = gamma (GSL, adaptive step; redundant rows allowed), projecting\n"
    "positions onto Phi = 0 and velocities onto Phi_q qd = nu after every step.\n"
    "Writes the state at N equal intervals up to t1: N + 1 states.\n"
    "\n";

#define POSITIVE CLI_POSITIVE, .what = "a positive number", .echo = true
#define NONNEGATIVE CLI_NONNEGATIVE, .what = "a non-negative number", .echo = true

static const CliOption options[] = {
    {"--t0", CLI_REAL_AT(SimCli, so.t0), .metavar = "T", .help = "time interval (default 0 and 1)"},
    {"--t1", CLI_REAL_AT(SimCli, so.t1), .metavar = "T"},
    {"--steps", CLI_INT_AT(SimCli, so.steps, 1, 100000000), .metavar = "N",
     .help = "output intervals (default 100); the integrator chooses\n"
             "its own steps in between"},
    {"--engine", CLI_CHOICE_AT(SimCli, engine, cli_engine_choices), .metavar = "E",
     .help = "jit (default), generic or aot, as for eval"},
    {"--method", CLI_CHOICE_AT(SimCli, method, sim_method_names), .metavar = "M",
     .help = "integrator: rk8pd (default), rkf45 (explicit Runge-Kutta\n"
             "pairs), rk4imp or msbdf (implicit, for stiff springs and\n"
             "dampers; finite-difference Jacobian)"},
    {"--rtol", CLI_REAL_AT(SimCli, so.rtol), NONNEGATIVE, .metavar = "X",
     .help = "relative error per step (default 1e-10)"},
    {"--atol", CLI_REAL_AT(SimCli, so.atol), NONNEGATIVE, .metavar = "X",
     .help = "absolute error per step, coordinate units (default 1e-10)"},
    {"--qd", CLI_STRING_AT(SimCli, qd_text), .metavar = "V1,V2,...",
     .help = "initial velocities, one per coordinate (default 0);\n"
             "projected onto the velocity equations"},
    {"--baumgarte", CLI_STRING_AT(SimCli, baumgarte), .metavar = "A,B",
     .help = "Baumgarte stabilisation gamma - 2A Phi' - B^2 Phi\n"
             "(1/s; default off: projection alone)"},
    {"--csv", CLI_STRING_AT(SimCli, csv_path), .metavar = "FILE",
     .help = "write the CSV to FILE ('-': stdout; the default when\n"
             "there is no --json); run's columns"},
    {"--json", CLI_FLAG_AT(SimCli, json),
     .help = "print run's JSON keys and \"rows\", \"lambda\" (the\n"
             "multipliers of every row at every state)"},
    {"--digits", CLI_INT_AT(SimCli, digits, 1, 17), .metavar = "N",
     .help = "significant digits of numbers (default: the fewest that\n"
             "read back exactly, at most 17)"},
    {"--stats", CLI_FLAG_AT(SimCli, stats),
     .help = "print integrator steps, rejections, projections, kernel\n"
             "calls and the energy balance"},
    {"--svg", CLI_STRING_AT(SimCli, svg_path), .metavar = "FILE",
     .help = "write an animated SVG of the motion"},
    {"--trace", CLI_LIST_AT(SimCli, traces, MAX_TRACES), .what = "points", .metavar = "B(sx,sy)",
     .help = "draw the path of a body point in the animation, as run"},
    {"--plot", CLI_STRING_AT(SimCli, plot_path), .metavar = "FILE",
     .help = "write an SVG chart of variables against time"},
    {"--plot-vars", CLI_STRING_AT(SimCli, plot_list), .metavar = "LIST",
     .help = "what --plot shows, as for run (default: every\n"
             "coordinate and output)"},
};

static const char epilogue[] =
    "\n"
    "CSV columns as run's: t, every coordinate and output, d(NAME) velocities,\n"
    "dd(NAME) accelerations. lambda follows M qdd + Phi_q^T lambda = Q.\n"
    "Needs masses in the file. Exit status: 0 done; 1 the simulation failed (the\n"
    "message names t = VALUE and the cause; the states before it are written);\n"
    "2 bad usage or input, or a file without masses.\n";

/* Where the states go; the same shapes as run's. */
typedef struct Output {
    FILE *csv;
    MechrtTrace trace;      /* rows for JSON and pictures */
    double *lambda;         /* nr per kept row, for JSON */
    size_t lcap;
    int nq, nv, nr;         /* coordinates; variables (coordinates, outputs); rows */
    OutputEval outputs;
    double *v;              /* v | vd | vdd, 3 nv */
    const char **names;
    double *w;              /* spatial angular velocities */
    bool keep, full;
    int digits;
    Progress progress;
    double t0, t1;
} Output;

static void output_open(Output *out, const Model *m)
{
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
    mechrt_trace_set_omega(&out->trace, out->outputs.nw, (const char *const *)out->outputs.wnames);
}

static void output_close(Output *out)
{
    outputs_free(&out->outputs);
    free(out->v), free(out->w), free(out->names), free(out->lambda);
    mechrt_trace_free(&out->trace);
}

/* Keeps a state's multipliers; false when out of memory. */
static bool keep_lambda(Output *out, const double *lambda)
{
    size_t nr = (size_t)out->nr, row = out->trace.rows;
    if ((row + 1) * nr > out->lcap) {
        size_t cap = out->lcap ? 2 * out->lcap : 64 * (nr + 1);
        double *p = realloc(out->lambda, cap * sizeof *p);
        if (!p)
            return false;
        out->lambda = p, out->lcap = cap;
    }
    memcpy(out->lambda + row * nr, lambda, nr * sizeof *lambda);
    return true;
}

static void on_state(void *ctx, double t, const double *q, const double *qd, const double *qdd,
                     const double *lambda)
{
    Output *out = ctx;
    size_t nq = (size_t)out->nq, nv = (size_t)out->nv;
    const double *src[3] = {q, qd, qdd};
    for (size_t k = 0; k < 3; k++)
        memcpy(out->v + k * nv, src[k], nq * sizeof *out->v);
    outputs_eval(&out->outputs, q, qd, qdd, t, out->v + nq, out->v + nv + nq,
                 out->v + 2 * nv + nq);
    outputs_omega(&out->outputs, q, qd, out->w);
    if (out->csv)
        mechrt_csv_row_omega(out->csv, out->nv, t, out->v, out->v + nv, out->v + 2 * nv,
                             out->outputs.nw, out->w, out->digits);
    if (out->keep && (!keep_lambda(out, lambda)
                      || !mechrt_trace_push_omega(&out->trace, t, out->v, out->v + nv,
                                                  out->v + 2 * nv, out->w)))
        out->full = true;
    progress_update(&out->progress, (long)(1000.0 * (t - out->t0) / (out->t1 - out->t0)));
}

/* run's JSON, then "rows" and "lambda" before its closing brace. */
static bool write_json(const Model *m, const Output *out, int digits, const SimResult *res)
{
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    if (!mem)
        return false;
    mechrt_json_write_outputs(mem, &out->trace, m->nq, out->names, digits,
                              res->status == SIM_FAILED ? res->message : NULL, res->t_fail);
    if (fclose(mem) != 0 || len < 2) {
        free(text);
        return false;
    }
    fwrite(text, 1, len - 2, stdout);          /* without "}\n" */
    free(text);
    fputs(",\n \"rows\": [", stdout);
    for (int i = 0; i < m->nr; i++) {
        fputs(i ? ", " : "", stdout);
        mechrt_json_string(stdout, m->rows[i].name);
    }
    fputs("],\n \"lambda\": [", stdout);
    for (size_t r = 0; r < out->trace.rows; r++) {
        fputs(r ? ",\n   [" : "[", stdout);
        for (int i = 0; i < m->nr; i++) {
            char buf[40];
            double v = out->lambda[r * (size_t)m->nr + (size_t)i];
            if (isfinite(v))
                mechrt_format_real(buf, sizeof buf, v, digits);
            fprintf(stdout, "%s%s", i ? ", " : "", isfinite(v) ? buf : "null");
        }
        fputs("]", stdout);
    }
    fputs("]}\n", stdout);
    return true;
}

/* The --trace points and --plot variables, resolved against the model. */
typedef struct Pictures {
    SvgTrace traces[MAX_TRACES];
    int ntraces;
    SvgPlotVar vars[MAX_PLOT_VARS];
    int nvars;
} Pictures;

static bool resolve_pictures(const Model *m, const SimCli *c, Pictures *p)
{
    char err[256];
    p->ntraces = p->nvars = 0;
    for (int i = 0; i < c->traces.n; i++)
        if (!svg_parse_trace(m, c->traces.items[i], &p->traces[p->ntraces++], err, sizeof err)) {
            fprintf(stderr, "mechc sim: error: %s\n", err);
            return false;
        }
    for (int k = 0; k < m->nout && p->ntraces < MAX_TRACES; k++) {
        const ModelOutput *o = &m->outputs[k];
        if (o->point && o->at.q >= 0)
            p->traces[p->ntraces++] = (SvgTrace){o->at.q, o->at.has_phi || o->at.has_p,
                                                 o->at.sx, o->at.sy, o->point, o->at.spatial,
                                                 o->at.sz};
    }
    if (c->plot_path && c->plot_list) {
        p->nvars = svg_plot_resolve(m, c->plot_list, p->vars, MAX_PLOT_VARS, err, sizeof err);
        if (p->nvars <= 0) {
            fprintf(stderr, "mechc sim: error: %s\n", err);
            return false;
        }
    } else if (c->plot_path) {
        for (int i = 0; i < m->nq + m->nout && p->nvars < MAX_PLOT_VARS; i++)
            p->vars[p->nvars++] = (SvgPlotVar){i, 0};
    }
    return true;
}

/* One picture file: the animation (which 0) or the chart (1). */
static bool write_picture(const Model *m, const MechrtTrace *tr, const Pictures *p,
                          const char *path, int which, const double *t, const double *q)
{
    size_t n = tr->rows, nv = (size_t)tr->nq, w = 1 + 3 * nv;
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "mechc sim: error: cannot write '%s': %s\n", path, strerror(errno));
        return false;
    }
    bool wrote;
    if (which == 0) {
        wrote = svg_write_animation_opt(f, m, t, q, (int)n, p->traces, p->ntraces, m->name, NULL);
    } else {
        SvgSeries series[MAX_PLOT_VARS];
        char names[MAX_PLOT_VARS][96];
        for (int i = 0; i < p->nvars; i++) {
            svg_plot_var_name(m, p->vars[i], names[i], sizeof names[i]);
            series[i] = (SvgSeries){names[i], tr->data + 1 + (size_t)p->vars[i].order * nv
                                              + (size_t)p->vars[i].coord, (int)w};
        }
        wrote = svg_write_plot(f, m->name, t, (int)n, series, p->nvars);
    }
    if (fclose(f) != 0 || !wrote) {
        fprintf(stderr, "mechc sim: error: writing '%s' failed\n", path);
        return false;
    }
    return true;
}

static bool write_pictures(const Model *m, const SimCli *c, const MechrtTrace *tr,
                           const Pictures *p)
{
    size_t n = tr->rows, nq = (size_t)m->nq, w = 1 + 3 * (size_t)tr->nq;
    bool ok = true;
    if (n == 0)
        return true;
    double *t = xcalloc(n, sizeof *t), *q = xcalloc(n * nq, sizeof *q);
    for (size_t k = 0; k < n; k++) {
        t[k] = tr->data[k * w];
        memcpy(q + k * nq, tr->data + k * w + 1, nq * sizeof *q);
    }
    if (c->svg_path)
        ok = write_picture(m, tr, p, c->svg_path, 0, t, q) && ok;
    if (c->plot_path)
        ok = write_picture(m, tr, p, c->plot_path, 1, t, q) && ok;
    free(t), free(q);
    return ok;
}

static void print_stats(const SimResult *r, int nr)
{
    const SimKernelCalls *k = &r->calls;
    fprintf(stderr, "mechc sim: stats: %ld integrator steps, %ld rejected, %ld right-hand "
            "sides (forward-dynamics solves), %ld finite-difference Jacobians\n", r->steps,
            r->rejected, r->rhs_calls, r->jacobian_calls);
    fprintf(stderr, "mechc sim: stats: %ld projections (%ld Newton iterations)\n",
            r->projections, r->projection_iterations);
    fprintf(stderr, "mechc sim: stats: kernel calls: mass %ld, force %ld, all %ld, jac %ld, "
            "gamma %ld, phi %ld, nu %ld\n", k->mass, k->force, k->all, k->jac, k->gamma,
            k->phi, k->nu);
    if (r->energy_scale > 0)
        fprintf(stderr, "mechc sim: stats: energy balance T - W drifted by %.3g (%.3g of the "
                "largest kinetic energy or work, %.3g); for a conservative mechanism (no "
                "dampers, no drivers) this is the energy drift\n", r->energy_drift,
                r->energy_drift / r->energy_scale, r->energy_scale);
    if (nr > 0)
        fprintf(stderr, "mechc sim: stats: up to %d dependent %s; smallest pivot ratio of "
                "Phi_q %.3g (near 0: a singular position)\n", r->max_redundant,
                r->max_redundant == 1 ? "row" : "rows", r->min_pivot_ratio);
    fprintf(stderr, "mechc sim: stats: %.6g ms of integration (%.6g ms CPU)\n",
            1e3 * r->seconds, 1e3 * r->cpu_seconds);
}

static bool finish(Args *a, void *opts)
{
    SimCli *c = opts;
    if (!args_need_file(a))
        return false;
    if (c->method >= 0)
        c->so.method = (SimMethod)c->method;
    if (c->so.t0 == c->so.t1) {
        fprintf(stderr, "mechc sim: error: --t0 and --t1 are both %g: nothing to simulate\n",
                c->so.t0);
        return false;
    }
    if (c->so.rtol == 0 && c->so.atol == 0) {
        fprintf(stderr, "mechc sim: error: --rtol and --atol cannot both be 0\n");
        return false;
    }
    double ab[2];
    if (c->baumgarte) {
        if (!args_vector("sim", "--baumgarte", c->baumgarte, 2, ab))
            return false;
        c->so.dyn.baumgarte_alpha = ab[0];
        c->so.dyn.baumgarte_beta = ab[1];
    }
    if ((c->traces.n > 0 && !c->svg_path) || (c->plot_list && !c->plot_path)) {
        fprintf(stderr, "mechc sim: error: %s goes with %s\n",
                c->traces.n ? "--trace" : "--plot-vars", c->traces.n ? "--svg FILE" : "--plot FILE");
        return false;
    }
    c->pictures = c->svg_path || c->plot_path;
    c->csv_stdout = c->csv_path ? strcmp(c->csv_path, "-") == 0 : !c->json && !c->pictures;
    if (c->csv_stdout && c->json) {
        fprintf(stderr, "mechc sim: error: --csv - and --json would both write to stdout\n");
        return false;
    }
    return true;
}

/* After the simulation: pictures, JSON, the failure, --stats; the exit status. */
static int report(const SimCli *c, const Model *m, const Output *out, const Pictures *p,
                  SimStatus st, const SimResult *res)
{
    int status = EXIT_OK;
    if (st == SIM_BAD_INPUT) {
        fprintf(stderr, "%s: error: %s\n", m->file, res->message);
        return EXIT_USAGE;
    }
    if (c->pictures && !write_pictures(m, c, &out->trace, p))
        status = EXIT_USAGE;
    if (c->json && !write_json(m, out, c->digits, res))
        status = EXIT_ANALYSIS;
    if (st == SIM_FAILED) {
        fprintf(stderr, "%s: error: %s\n", m->file, res->message);
        if (res->states > 0)
            fprintf(stderr, "%s: note: the %d %s before t = %.10g %s written\n", m->file,
                    res->states, res->states == 1 ? "state" : "states", res->t_fail,
                    res->states == 1 ? "is" : "are");
        status = EXIT_ANALYSIS;
    }
    if (out->full) {
        fprintf(stderr, "mechc sim: error: out of memory keeping the states for JSON\n");
        status = EXIT_ANALYSIS;
    }
    if (c->stats)
        print_stats(res, m->nr);
    return status;
}

/* The simulation with the open engine, the states going where c says. */
static int simulate(SimCli *c, const Model *m, const Engine *e, const Pictures *p)
{
    Output out = {.keep = c->json || c->pictures, .digits = c->digits, .t0 = c->so.t0,
                  .t1 = c->so.t1};
    if (c->csv_stdout)
        out.csv = stdout;
    else if (c->csv_path && !(out.csv = fopen(c->csv_path, "w"))) {
        fprintf(stderr, "mechc sim: error: cannot write '%s': %s\n", c->csv_path, strerror(errno));
        return EXIT_USAGE;
    }
    output_open(&out, m);
    if (out.csv)
        mechrt_csv_header_omega(out.csv, out.nv, out.names, out.outputs.nw,
                                (const char *const *)out.outputs.wnames);
    c->so.notes = stderr;
    SimResult res;
    progress_start(&out.progress, "sim", 1000);
    SimStatus st = sim_run(m, &e->k, &c->so, on_state, &out, &res);
    progress_finish(&out.progress);
    int status = report(c, m, &out, p, st, &res);
    if (out.csv && out.csv != stdout && fclose(out.csv) != 0) {
        fprintf(stderr, "mechc sim: error: writing '%s': %s\n", c->csv_path, strerror(errno));
        status = status == EXIT_OK ? EXIT_USAGE : status;
    } else if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "mechc sim: error: writing the output: %s\n", strerror(errno));
        status = status == EXIT_OK ? EXIT_USAGE : status;
    }
    output_close(&out);
    return status;
}

/* Masses, velocities and pictures checked, the engine opened, then the simulation. */
static int sim_file(const Args *a, Mech *mech, Diag *diag, void *opts)
{
    SimCli *c = opts;
    const Model *m = mech->model;
    Pictures pics;
    Engine e;
    double *qd0 = xcalloc((size_t)m->nq, sizeof *qd0);
    int status = EXIT_USAGE;
    if ((c->qd_text && !args_vector("sim", "--qd", c->qd_text, m->nq, qd0))
        || !resolve_pictures(m, c, &pics)) {
        free(qd0);
        return EXIT_USAGE;
    }
    c->so.qd0 = qd0;
    if (!cli_engine_open(a, &e, (EngineKind)c->engine, mech, NULL, diag)) {
        free(qd0);
        return EXIT_USAGE;
    }
    if (!sim_has_masses(&e.k)) {
        diag_error(diag, m->last_pos, "the mechanism has no masses: `mechc sim` needs `mass` "
                   "statements (with `gravity`, forces or springs) to simulate its dynamics");
        diag_print(diag, stderr);
    } else {
        status = simulate(c, m, &e, &pics);
    }
    engine_close(&e);
    free(qd0);
    return status;
}

static const CliCommand command = {
    .name = "sim", .usage = usage, CLI_OPTIONS(options), .column = 19, .epilogue = epilogue,
    .limits_offset = offsetof(SimCli, limits),
    .finish = finish, .run = sim_file,
};

int cmd_sim(int argc, char **argv)
{
    SimCli c = {.so = sim_default_options(), .limits = mech_default_limits(),
                .engine = ENGINE_JIT, .method = -1};
    return cli_main(&command, argc, argv, &c);
}
