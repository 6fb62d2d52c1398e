/* cmd_run.c - mechc run: assembly, then position, velocity and acceleration analysis over time.
 *
 * Parses the options, loads the mechanism, opens the engine and hands the
 * rest to run_analysis (generator/analysis/run.c), whose states stream to
 * the CSV writer or are collected for JSON (runtime/host/output.c). On a
 * failure the states computed before it are still written, JSON included
 * ("ok": false and the error), and the message goes to stderr.
 */
#include "cli.h"

#include "../analysis/outputs.h"
#include "../analysis/run.h"
#include "../base/arena.h"
#include "../render/progress.h"
#include "../render/svg_anim.h"
#include "../render/svg_plot.h"
#include "run_table.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_TRACES = CLI_LIST_MAX, MAX_PLOT_VARS = 64 };

/* What the command line asked for. */
typedef struct RunCli {
    RunOptions ro;
    MechLimits limits;
    const char *csv_path, *svg_path, *plot_path, *plot_list;
    CliList traces;         /* --trace texts */
    double tol;             /* --tol: both Newton tolerances of ro.mechrt; 0: not given */
    double at;              /* --at: one instant, t0 = at and no steps; NaN: not given */
    int engine, ode, digits;
    int view;               /* --view: an SvgView; -1: not given (iso) */
    int linear;             /* --linear, a RunLinear */
    bool json, stats;
    bool pictures, csv_stdout, table;   /* worked out from the above */
} RunCli;

static const char usage[] =
    "usage: mechc run FILE.mech [--t0 T] [--t1 T] [--steps N] [--engine jit|generic|aot]\n"
    "                 [--csv OUT.csv] [--json] [options]\n"
    "\n"
    "Assembles the mechanism at t0 (Newton from the file's initial values; from\n"
    "rough ones, minimum-norm Newton), then does position, velocity and\n"
    "acceleration analysis on N equal intervals up to t1: N + 1 states. With\n"
    "--steps 0 (or --at T) it analyses the one instant t0 and prints a table.\n"
    "Mechanisms with velocity-level rows (rolling, knife, velocity drivers) have\n"
    "their positions integrated (GSL, adaptive step) and projected back onto the\n"
    "holonomic rows after every step. Needs as many rows as coordinates. The\n"
    "file's `output` statements are reported beside the coordinates.\n"
    "Where the Jacobian loses rank (a parallelogram folding flat, coupled wheels\n"
    "at a dead centre, a toggle) a step is redone by a rank-revealing corrector:\n"
    "each correction the least one from the motion the previous steps predict,\n"
    "so the run keeps to the branch it is on; where no motion continues it (a\n"
    "driver pushing past a dead centre) the run stops with exit 1 and says so.\n"
    "\n";

static const char *const ode_methods[] = {"rk8pd", "rkf45", NULL};

#define POSITIVE CLI_POSITIVE, .what = "a positive number", .echo = true
#define NONNEGATIVE CLI_NONNEGATIVE, .what = "a non-negative number", .echo = true

static const CliOption options[] = {
    {"--t0", CLI_REAL_AT(RunCli, ro.t0), .metavar = "T", .help = "time interval (default 0 and 1)"},
    {"--t1", CLI_REAL_AT(RunCli, ro.t1), .metavar = "T"},
    {"--steps", CLI_INT_AT(RunCli, ro.steps, 0, 100000000), .metavar = "N",
     .help = "intervals (default 100); 0: the instant t0 alone, printed\n"
             "as a table unless --csv or --json is given"},
    {"--at", CLI_REAL_AT(RunCli, at), .metavar = "T",
     .help = "the instant T alone: --t0 T --steps 0"},
    {"--engine", CLI_CHOICE_AT(RunCli, engine, cli_engine_choices), .metavar = "E",
     .help = "jit (default), generic or aot, as for eval"},
    {"--linear", CLI_CHOICE_AT(RunCli, linear, run_linear_names), .metavar = "L",
     .help = "linear algebra: dense (LU), sparse (KLU on the Jacobian's\n"
             "nonzeros; jit and aot, holonomic rows only) or auto\n"
             "(default: sparse above " RUN_DENSE_MAX_NQ_TEXT " coordinates when it can)"},
    {"--csv", CLI_STRING_AT(RunCli, csv_path), .metavar = "FILE",
     .help = "write the CSV to FILE ('-': stdout; the default when\n"
             "there is no --json)"},
    {"--json", CLI_FLAG_AT(RunCli, json),
     .help = "print {\"coords\", \"t\", \"q\", \"qd\", \"qdd\", \"ok\"[, \"error\"]}\n"
             "(with output statements also \"outputs\", \"y\", \"yd\", \"ydd\")"},
    {"--digits", CLI_INT_AT(RunCli, digits, 1, 17), .metavar = "N",
     .help = "significant digits of numbers (default: the fewest that\n"
             "read back exactly, at most 17)"},
    {"--tol", CLI_REAL_AT(RunCli, tol), POSITIVE, .metavar = "X",
     .help = "Newton: converged when max |Phi_i| <= X and the last\n"
             "step max |dq_j| <= X (default 1e-8)"},
    {"--max-iter", CLI_INT_AT(RunCli, ro.mechrt.max_iter, 1, 10000), .metavar = "N",
     .help = "Newton iterations per time step (default 25)"},
    {"--assembly-iter", CLI_INT_AT(RunCli, ro.assembly_max_iter, 1, 100000), .metavar = "N",
     .help = "minimum-norm Newton iterations per attempt when Newton\n"
             "cannot start from the initial values (default 100)"},
    {"--max-substeps", CLI_INT_AT(RunCli, ro.max_substeps, 1, 1 << 20), .metavar = "N",
     .help = "a step that seems to leave its assembly branch (Newton\n"
             "corrects far more than the predicted motion) is redone\n"
             "in 2, 4, 8 ... substeps, at most N (default 64), and\n"
             "the run fails past that; substeps are not output"},
    {"--pivot-tol", CLI_REAL_AT(RunCli, ro.mechrt.pivot_tol), NONNEGATIVE, .metavar = "X",
     .help = "singular when an LU pivot <= X times the largest\n"
             "Jacobian entry (default 1e-12)"},
    {"--cond-warn", CLI_REAL_AT(RunCli, ro.mechrt.cond_warn), NONNEGATIVE, .metavar = "X",
     .help = "warn where the Jacobian's condition estimate exceeds X\n"
             "(default 1e10; 0: no estimate)"},
    {"--ode", CLI_CHOICE_AT(RunCli, ode, ode_methods), .metavar = "M",
     .help = "integrator for velocity-level rows: rk8pd (default) or rkf45"},
    {"--ode-tol", CLI_REAL_AT(RunCli, ro.ode.tol), POSITIVE, .metavar = "X",
     .help = "its error per step, absolute and relative (default 1e-10)"},
    {"--stats", CLI_FLAG_AT(RunCli, stats),
     .help = "print time per step, Newton iterations per step, the\n"
             "step's cost in evaluations of the fused `all` kernel and\n"
             "the steps through singular positions (dense QR, also on\n"
             "the sparse path)"},
    {"--svg", CLI_STRING_AT(RunCli, svg_path), .metavar = "FILE",
     .help = "write an animated SVG of the motion (plays in any browser)"},
    {"--trace", CLI_LIST_AT(RunCli, traces, MAX_TRACES), .what = "points", .metavar = "B(sx,sy)",
     .help = "draw the path of the point (sx, sy) of body B in the\n"
             "animation (repeatable; a point particle: --trace m;\n"
             "spatial: B(sx,sy,sz))"},
    {"--view", CLI_CHOICE_AT(RunCli, view, svg_view_names), .metavar = "V",
     .help = "the animation of a spatial mechanism seen from the\n"
             "front (x right, z up), top (x right, y up), side\n"
             "(y right, z up) or iso (default; isometric, from\n"
             "(1, -1, 1)): orthographic"},
    {"--plot", CLI_STRING_AT(RunCli, plot_path), .metavar = "FILE",
     .help = "write an SVG chart of variables against time"},
    {"--plot-vars", CLI_STRING_AT(RunCli, plot_list), .metavar = "LIST",
     .help = "what --plot shows: coordinate or output names, d(NAME)\n"
             "for a velocity, dd(NAME) for an acceleration (default:\n"
             "every coordinate and output)"},
};

static const char epilogue[] =
    "\n"
    "CSV columns: t, then every coordinate by name (crank.x, ...) and every\n"
    "output, then the velocities d(crank.x), ..., then the accelerations\n"
    "dd(crank.x), ...\n"
    "Exit status: 0 done; 1 the analysis failed (the message names t = VALUE,\n"
    "the cause and the rows and coordinates involved; the states before the\n"
    "failure are written); 2 bad usage or input, or not as many rows as\n"
    "coordinates.\n";

/* Where the states go. */
typedef struct Output {
    FILE *csv;              /* NULL: no CSV */
    MechrtTrace trace;      /* kept rows, for JSON and pictures */
    bool json, trace_full;
    Progress progress;
    double t0, t1;
    int digits;
    int nq;                 /* coordinates */
    int nv;                 /* reported variables: the coordinates, then the outputs */
    OutputEval outputs;
    double *v;              /* a state's variables: v | vd | vdd, 3 nv */
    const char **names;     /* the variables' names, nv */
    double *w;              /* a spatial state's angular velocities, outputs.nw */
    const char *file;       /* for warnings */
    bool warned;            /* an output was not finite (said once) */
} Output;

/* Sets up out for m's coordinates and outputs; output_close frees it. */
static void output_open(Output *out, const Model *m)
{
    out->nq = m->nq;
    out->nv = m->nq + m->nout;
    outputs_init(&out->outputs, m);
    out->v = xcalloc(3 * (size_t)out->nv, sizeof *out->v);
    out->names = xcalloc((size_t)out->nv, sizeof *out->names);
    for (int i = 0; i < out->nv; i++)
        out->names[i] = i < m->nq ? m->coord_names[i] : m->outputs[i - m->nq].name;
    mechrt_trace_init(&out->trace, out->nv);
    out->w = xcalloc((size_t)out->outputs.nw + 1, sizeof *out->w);
    mechrt_trace_set_omega(&out->trace, out->outputs.nw,
                           (const char *const *)out->outputs.wnames);
}

static void output_close(Output *out)
{
    outputs_free(&out->outputs);
    free(out->v);
    free(out->w);
    free(out->names);
    mechrt_trace_free(&out->trace);
}

/* --steps 0 without --csv or --json: the one state as a table. */
static void print_table(const Model *m, const Output *out, const RunResult *res, int digits)
{
    const double *row = out->trace.data;
    size_t nv = (size_t)out->nv, nq = (size_t)out->nq;
    bool outputs = nv > nq;
    RunInstant s = {
        .t = row[0], .q = row + 1, .qd = row + 1 + nv, .qdd = row + 1 + 2 * nv,
        .y = outputs ? row + 1 + nq : NULL, .yd = outputs ? row + 1 + nv + nq : NULL,
        .ydd = outputs ? row + 1 + 2 * nv + nq : NULL,
        .ynames = out->names + nq,
        .assembly_iterations = res->assembly_iterations,
        .assembled_robustly = res->assembled_robustly,
        .constructed = res->constructed,
    };
    /* alpha = 2 E(p) p'' (the term 2 E' p' vanishes: E' p' = 0) */
    size_t nw = (size_t)out->outputs.nw;
    double *w = xcalloc(2 * nw + 1, sizeof *w);
    outputs_omega(&out->outputs, s.q, s.qd, w);
    outputs_omega(&out->outputs, s.q, s.qdd, w + nw);
    s.nw = (int)nw, s.w = w, s.wd = w + nw;
    s.wnames = (const char *const *)out->outputs.wnames;
    run_table_print(stdout, m, &s, digits);
    free(w);
}

/* The state's coordinates followed by the outputs' values, in out->v. */
static void fill_variables(Output *out, double t, const double *q, const double *qd,
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
static void warn_nonfinite(Output *out, double t)
{
    for (int k = 0; k < 3 && !out->warned; k++)
        for (int i = out->nq; i < out->nv && !out->warned; i++)
            if (!isfinite(out->v[k * out->nv + i])) {
                fprintf(stderr, "%s: warning: output '%s' is not finite at t = %.10g (later "
                        "ones are not reported)\n", out->file, out->names[i], t);
                out->warned = true;
            }
}

static void on_state(void *ctx, double t, const double *q, const double *qd, const double *qdd)
{
    Output *out = ctx;
    outputs_omega(&out->outputs, q, qd, out->w);
    if (out->nv > out->nq) {
        fill_variables(out, t, q, qd, qdd);
        q = out->v, qd = out->v + out->nv, qdd = out->v + 2 * out->nv;
        warn_nonfinite(out, t);
    }
    if (out->csv)
        mechrt_csv_row_omega(out->csv, out->nv, t, q, qd, qdd, out->outputs.nw, out->w,
                             out->digits);
    if (out->json && !mechrt_trace_push_omega(&out->trace, t, q, qd, qdd, out->w))
        out->trace_full = true;
    if (out->t1 != out->t0)
        progress_update(&out->progress, (long)(1000.0 * (t - out->t0) / (out->t1 - out->t0)));
}

/* The animation and the chart, from the kept rows [t, q, qd, qdd]. */
static bool write_pictures(const Model *m, const MechrtTrace *tr, const char *svg_path,
                           const SvgTrace *traces, int ntraces, int view, const char *plot_path,
                           const SvgPlotVar *vars, int nvars)
{
    SvgAnimOptions ao = svg_anim_default_options();
    if (view >= 0)
        ao.view = (SvgView)view;
    size_t n = tr->rows, nq = (size_t)m->nq, nv = (size_t)tr->nq, w = 1 + 3 * nv;
    bool ok = true;
    if (n == 0)
        return true;
    double *t = xcalloc(n, sizeof *t), *q = xcalloc(n * nq, sizeof *q);
    for (size_t k = 0; k < n; k++) {
        t[k] = tr->data[k * w];
        memcpy(q + k * nq, tr->data + k * w + 1, nq * sizeof *q);
    }
    const char *paths[2] = {svg_path, plot_path};
    for (int which = 0; which < 2; which++) {
        if (!paths[which])
            continue;
        FILE *f = fopen(paths[which], "w");
        if (!f) {
            fprintf(stderr, "mechc run: error: cannot write '%s': %s\n", paths[which], strerror(errno));
            ok = false;
            continue;
        }
        bool wrote;
        if (which == 0) {
            wrote = svg_write_animation_opt(f, m, t, q, (int)n, traces, ntraces, m->name, &ao);
        } else {
            SvgSeries series[MAX_PLOT_VARS];
            char names[MAX_PLOT_VARS][96];
            for (int i = 0; i < nvars; i++) {
                svg_plot_var_name(m, vars[i], names[i], sizeof names[i]);
                series[i] = (SvgSeries){names[i], tr->data + 1 + (size_t)vars[i].order * nv
                                                  + (size_t)vars[i].coord, (int)w};
            }
            wrote = svg_write_plot(f, m->name, t, (int)n, series, nvars);
        }
        if (fclose(f) != 0 || !wrote) {
            fprintf(stderr, "mechc run: error: writing '%s' failed\n", paths[which]);
            ok = false;
        }
    }
    free(t);
    free(q);
    return ok;
}

static void print_stats(const RunResult *res, const MechrtKernels *k,
                        const MechrtHostJacNz *jnz, const double *q, const double *qd, double t)
{
    int n = res->steps_done;
    if (n == 0) {           /* one instant: only the assembly */
        fprintf(stderr, "mechc run: stats: assembly at t0 in %d Newton %s%s\n",
                res->assembly_iterations, res->assembly_iterations == 1 ? "iteration" : "iterations",
                res->assembled_robustly ? " (from rough initial values)" : "");
        if (res->constructed > 0)
            fprintf(stderr, "mechc run: stats: %d %s placed by construction before Newton\n",
                    res->constructed, res->constructed == 1 ? "coordinate" : "coordinates");
        return;
    }
    double ns_step = n > 0 ? 1e9 * res->step_seconds / n : 0;
    fprintf(stderr, "mechc run: stats: %d %s after assembly (%d Newton %s at t0), %.6g ms "
            "of analysis: %.0f ns per step\n", n, n == 1 ? "step" : "steps",
            res->assembly_iterations, res->assembly_iterations == 1 ? "iteration" : "iterations",
            1e3 * res->step_seconds, ns_step);
    if (res->integrated) {
        const MechrtHostStats *h = &res->host;
        fprintf(stderr, "mechc run: stats: integrator: %ld accepted steps (%.3g per output "
                "step), %ld rejected, %ld velocity solves; %.3g projection iterations per "
                "integrator step\n", h->ode_steps, n > 0 ? (double)h->ode_steps / n : 0,
                h->ode_rejected, h->rhs_calls,
                h->ode_steps > 0 ? (double)h->project_iterations / (double)h->ode_steps : 0);
    } else {
        fprintf(stderr, "mechc run: stats: %.3g Newton iterations per step (%ld in all)\n",
                n > 0 ? (double)res->newton_iterations / n : 0, res->newton_iterations);
        if (res->subdivided > 0)
            fprintf(stderr, "mechc run: stats: %d %s redone in substeps (%ld substeps)\n",
                    res->subdivided, res->subdivided == 1 ? "step" : "steps", res->substeps);
        if (res->rank_steps > 0)
            fprintf(stderr, "mechc run: stats: %d %s through singular positions by the "
                    "rank-revealing corrector (dense QR%s: %ld factorisations), %d of them "
                    "rank-deficient (by up to %d)\n", res->rank_steps,
                    res->rank_steps == 1 ? "step" : "steps",
                    res->sparse ? ", where KLU found the Jacobian singular or too "
                    "ill-conditioned" : "", res->rank_factorisations,
                    res->rank_deficient_steps, res->max_rank_deficiency);
    }
    fprintf(stderr, "mechc run: stats: %.6g ms of CPU time in the steps: %.0f ns per step\n",
            1e3 * res->step_cpu_seconds, 1e9 * res->step_cpu_seconds / n);
    if (res->sparse)
        fprintf(stderr, "mechc run: stats: sparse LU (KLU): %ld factorisations with pivoting, "
                "%ld refactorisations\n", res->fresh_factorisations, res->refactorisations);
    else if (res->fresh_factorisations > 0)   /* the dense path's pattern LU */
        fprintf(stderr, "mechc run: stats: pattern LU: %ld of %ld factorisations finished by "
                "the dense LU (a new pivot order), the others replayed\n",
                res->fresh_factorisations, res->fresh_factorisations + res->refactorisations);
    double ns_all = run_time_all(k, res->sparse ? jnz : NULL, q, qd, t, 0.05);
    fprintf(stderr, "mechc run: stats: one %s call (Phi, Phi_q, nu, gamma) takes "
            "%.1f ns: a step costs %.2f of them\n",
            !res->sparse ? "`all` kernel" : jnz->all_nz ? "`all_nz` kernel"
                                                        : "phi + jac_nz + nu + gamma kernel", ns_all,
            ns_all > 0 ? ns_step / ns_all : 0);
    if (res->max_cond > 0)
        fprintf(stderr, "mechc run: stats: largest condition estimate %.3g\n", res->max_cond);
}

/* The last state seen, for --stats' kernel timing. */
typedef struct LastState {
    Output *out;
    double t;
    double *q, *qd;
} LastState;

static void on_state_keep(void *ctx, double t, const double *q, const double *qd,
                          const double *qdd)
{
    LastState *ls = ctx;
    on_state(ls->out, t, q, qd, qdd);
    ls->t = t;
    memcpy(ls->q, q, (size_t)ls->out->nq * sizeof *q);
    memcpy(ls->qd, qd, (size_t)ls->out->nq * sizeof *qd);
}

/* Checks the options together and fills what they imply; false when
   they cannot be used (reported). */
static bool finish(Args *a, void *opts)
{
    RunCli *c = opts;
    if (!args_need_file(a))
        return false;
    if (c->tol > 0)
        c->ro.mechrt.tol_phi = c->ro.mechrt.tol_dq = c->tol;
    if (c->ode >= 0)
        mechrt_ode_method_from_name(ode_methods[c->ode], &c->ro.ode.method);
    if (!isnan(c->at)) {
        RunOptions d = run_default_options();
        if (c->ro.t0 != d.t0 || c->ro.t1 != d.t1 || c->ro.steps != d.steps) {
            fprintf(stderr, "mechc run: error: --at T is --t0 T --steps 0: give it alone, "
                    "without --t0, --t1 or --steps\n");
            return false;
        }
        c->ro.t0 = c->at;
        c->ro.steps = 0;
    }
    if (c->linear != RUN_LINEAR_DENSE) {    /* checked by the run, where a dense one is formed */
        c->ro.max_dense_entries = c->limits.max_jac_entries;
        c->limits.max_jac_entries = 0;
    }
    if (c->ro.steps > 0 && c->ro.t0 == c->ro.t1) {
        fprintf(stderr, "mechc run: error: --t0 and --t1 are both %g: nothing to run\n", c->ro.t0);
        return false;
    }
    if ((c->traces.n > 0 && !c->svg_path) || (c->plot_list && !c->plot_path)) {
        fprintf(stderr, "mechc run: error: %s goes with %s\n",
                c->traces.n ? "--trace" : "--plot-vars", c->traces.n ? "--svg FILE" : "--plot FILE");
        return false;
    }
    if (c->view >= 0 && !c->svg_path) {
        fprintf(stderr, "mechc run: error: --view goes with --svg FILE\n");
        return false;
    }
    c->pictures = c->svg_path || c->plot_path;
    if (c->pictures && c->ro.steps == 0) {
        fprintf(stderr, "mechc run: error: %s needs a motion: one instant (--steps 0 or --at) "
                "has nothing to draw\n", c->svg_path ? "--svg" : "--plot");
        return false;
    }
    c->table = c->ro.steps == 0 && !c->csv_path && !c->json && !c->pictures;
    c->csv_stdout = c->csv_path ? strcmp(c->csv_path, "-") == 0
                                : !c->json && !c->pictures && !c->table;
    if (c->csv_stdout && c->json) {
        fprintf(stderr, "mechc run: error: --csv - and --json would both write to stdout\n");
        return false;
    }
    return true;
}

/* The --trace points and --plot variables by name; false (reported) when
   one is unknown. */
static bool resolve_pictures(const Model *m, const RunCli *c, SvgTrace *traces, int *ntraces,
                             SvgPlotVar *vars, int *nvars)
{
    char err[256];
    *nvars = 0;
    if (!m->spatial && c->view >= 0) {
        fprintf(stderr, "%s: error: --view chooses how a spatial mechanism is seen, and this "
                "one is planar (drawn as it is, x right, y up)\n", m->file);
        return false;
    }
    for (int i = 0; i < c->traces.n; i++) {
        if (!svg_parse_trace(m, c->traces.items[i], &traces[i], err, sizeof err)) {
            fprintf(stderr, "mechc run: error: %s\n", err);
            return false;
        }
    }
    *ntraces = c->traces.n;
    int dropped = 0;
    for (int k = 0; k < m->nout; k++) {
        const ModelOutput *o = &m->outputs[k];
        if (!o->point || o->at.q < 0)    /* a point output's path; ground's stays put */
            continue;
        if (*ntraces < MAX_TRACES)
            traces[(*ntraces)++] = (SvgTrace){o->at.q, o->at.has_phi || o->at.has_p, o->at.sx,
                                              o->at.sy, o->point, o->at.spatial, o->at.sz};
        else
            dropped++;
    }
    if (dropped > 0 && c->svg_path)
        fprintf(stderr, "%s: note: the paths of %d point output%s are not drawn (at most %d "
                "paths)\n", m->file, dropped, dropped == 1 ? "" : "s", MAX_TRACES);
    if (c->plot_path && c->plot_list) {
        *nvars = svg_plot_resolve(m, c->plot_list, vars, MAX_PLOT_VARS, err, sizeof err);
        if (*nvars <= 0) {
            fprintf(stderr, "mechc run: error: %s\n", err);
            return false;
        }
    } else if (c->plot_path) {
        for (int i = 0; i < m->nq + m->nout && *nvars < MAX_PLOT_VARS; i++)
            vars[(*nvars)++] = (SvgPlotVar){i, 0};
        if (m->nq + m->nout > MAX_PLOT_VARS)
            fprintf(stderr, "%s: note: --plot shows the first %d of %d variables; choose "
                    "them with --plot-vars\n", m->file, MAX_PLOT_VARS, m->nq + m->nout);
    }
    return true;
}

/* The --trace points and --plot variables, resolved. */
typedef struct Pictures {
    SvgTrace traces[MAX_TRACES];
    int ntraces;            /* --trace points, then point outputs */
    SvgPlotVar vars[MAX_PLOT_VARS];
    int nvars;
} Pictures;

/* Before any state: rows against coordinates (before the engine's
   compile), the pictures' names, the engine. false when one fails
   (reported). */
static bool prepare(const Args *a, const RunCli *c, const Mech *mech, Pictures *pics, Engine *e,
                    Diag *diag)
{
    const Model *m = mech->model;
    char why[300];
    if (!run_rows_match(m, why, sizeof why)) {
        diag_error(diag, m->last_pos, "%s", why);
        diag_print(diag, stderr);
        return false;
    }
    return resolve_pictures(m, c, pics->traces, &pics->ntraces, pics->vars, &pics->nvars)
           && cli_engine_open(a, e, (EngineKind)c->engine, mech, NULL, diag);
}

/* After the analysis: pictures, JSON, the failure, --stats; the exit status. */
static int report(const RunCli *c, const Model *m, const Output *out, const Pictures *pics,
                  RunStatus rs, const RunResult *res, const MechrtKernels *k,
                  const MechrtHostJacNz *jnz, const LastState *last)
{
    int status = EXIT_OK;
    if (rs == RUN_BAD_INPUT) {
        fprintf(stderr, "%s: error: %s\n", m->file, res->message);
        return EXIT_USAGE;
    }
    if (c->pictures && !write_pictures(m, &out->trace, c->svg_path, pics->traces, pics->ntraces,
                                       c->view, c->plot_path, pics->vars, pics->nvars))
        status = EXIT_USAGE;
    if (c->json)
        mechrt_json_write_outputs(stdout, &out->trace, m->nq, out->names, c->digits,
                                  rs == RUN_FAILED ? res->message : NULL, res->t_fail);
    if (c->table && rs == RUN_OK && out->trace.rows == 1)
        print_table(m, out, res, c->digits);
    if (rs == RUN_FAILED) {
        fprintf(stderr, "%s: error: %s\n", m->file, res->message);
        if (res->states > 0)
            fprintf(stderr, "%s: note: the %d %s before t = %.10g %s written\n", m->file,
                    res->states, res->states == 1 ? "state" : "states", res->t_fail,
                    res->states == 1 ? "is" : "are");
        status = EXIT_ANALYSIS;
    }
    if (out->trace_full) {
        fprintf(stderr, "mechc run: error: out of memory keeping the states for JSON\n");
        status = EXIT_ANALYSIS;
    }
    if (c->stats)
        print_stats(res, k, jnz, last->q, last->qd, last->t);
    return status;
}

/* Closes the CSV file or flushes stdout; status made EXIT_USAGE by a
   write error, unless already a failure. */
static int finish_output(const RunCli *c, FILE *csv, int status)
{
    if (csv && csv != stdout) {
        if (fclose(csv) != 0) {
            fprintf(stderr, "mechc run: error: writing '%s': %s\n", c->csv_path, strerror(errno));
            status = status == EXIT_OK ? EXIT_USAGE : status;
        }
    } else if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "mechc run: error: writing the output: %s\n", strerror(errno));
        status = status == EXIT_OK ? EXIT_USAGE : status;
    }
    return status;
}

/* Runs the analysis with the open engine, the states going where c says. */
static int analyse(RunCli *c, const Model *m, const Engine *e, const Pictures *pics)
{
    Output out = {.csv = NULL, .json = c->json || c->pictures || c->table, .digits = c->digits,
                  .t0 = c->ro.t0, .t1 = c->ro.t1, .file = m->file};
    if (c->csv_stdout) {
        out.csv = stdout;
    } else if (c->csv_path && !(out.csv = fopen(c->csv_path, "w"))) {
        fprintf(stderr, "mechc run: error: cannot write '%s': %s\n", c->csv_path, strerror(errno));
        return EXIT_USAGE;
    }
    output_open(&out, m);
    MechrtKernels k = e->k;
    MechrtHostJacNz jnz;
    RunResult res;
    c->ro.notes = stderr;
    c->ro.linear = (RunLinear)c->linear;
    c->ro.jac_nz = run_jac_nz_of(e, &jnz) ? &jnz : NULL;
    if (out.csv)
        mechrt_csv_header_omega(out.csv, out.nv, out.names, out.outputs.nw,
                                (const char *const *)out.outputs.wnames);
    LastState last = {&out, c->ro.t0, xcalloc((size_t)m->nq, sizeof(double)),
                      xcalloc((size_t)m->nq, sizeof(double))};
    memcpy(last.q, m->q0, (size_t)m->nq * sizeof(double));
    progress_start(&out.progress, "run", 1000);
    MechrtKernels newton = engine_newton_kernels(e);
    RunStatus rs = run_analysis(m, &newton, &c->ro, on_state_keep, &last, &res);
    progress_finish(&out.progress);
    int status = report(c, m, &out, pics, rs, &res, &k, &jnz, &last);
    status = finish_output(c, out.csv, status);
    free(last.q), free(last.qd);
    output_close(&out);
    return status;
}

/* Rows, pictures and engine ready, then the analysis. */
static int run_file(const Args *a, Mech *mech, Diag *diag, void *opts)
{
    RunCli *c = opts;
    Pictures pics;
    Engine e;
    if (!prepare(a, c, mech, &pics, &e, diag))
        return EXIT_USAGE;
    if (c->stats)   /* what it took to have the kernels (wall time) */
        fprintf(stderr, "mechc run: stats: set-up: load %.3f s, derivatives %.3f s, emission "
                "%.3f s, compilation %.3f s\n", mech->load_seconds, mech->diff_seconds,
                e.gen_seconds, e.compile_seconds);
    int status = analyse(c, mech->model, &e, &pics);
    engine_close(&e);
    return status;
}

static const CliCommand command = {
    .name = "run", .usage = usage, CLI_OPTIONS(options), .column = 19, .epilogue = epilogue,
    .limits_offset = offsetof(RunCli, limits),
    .finish = finish, .run = run_file,
};

int cmd_run(int argc, char **argv)
{
    RunCli c = {.ro = run_default_options(), .limits = mech_default_limits(),
                .engine = ENGINE_JIT, .ode = -1, .view = -1, .at = NAN};
    return cli_main(&command, argc, argv, &c);
}
