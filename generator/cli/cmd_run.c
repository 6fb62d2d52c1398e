/* cmd_run.c - mechc run: assembly, then position, velocity and acceleration analysis over time.
 *
 * Parses the options, loads the mechanism, opens the engine and hands the
 * rest to run_analysis (generator/kin/run.c), whose states stream to
 * the CSV writer or are collected for JSON (runtime/host/output.c). On a
 * failure the states computed before it are still written, JSON included
 * ("ok": false and the error), and the message goes to stderr.
 */
#include "cli.h"

#include "../kin/outputs.h"
#include "../kin/run.h"
#include "../kin/sens.h"
#include "../base/arena.h"
#include "run_output.h"
#include "run_table.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { MAX_TRACES = RUN_OUTPUT_MAX_TRACES };

/* What the command line asked for. */
typedef struct RunCli {
    mechc_run_options ro;   /* libmechc's run (mechc.h) ... */
    mechc_run_tuning tune;  /* ... with the command's tuning */
    mechc_limits limits;
    const char *csv_path, *svg_path, *plot_path, *plot_list;
    CliList traces;         /* --trace texts */
    double tol;             /* --tol: ro.tol, both Newton tolerances; 0: not given */
    double at;              /* --at: one instant, t0 = at and no steps; NaN: not given */
    int engine, ode, digits;   /* ode: an index of ode_methods, -1 not given */
    int view;               /* --view: an SvgView; -1: not given (iso) */
    int linear;             /* --linear, an AnalysisLinear */
    bool json, stats, forces, sens;
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
    {"--engine", CLI_CHOICE_AT(RunCli, engine, engine_names), .metavar = "E",
     .help = "jit (default), generic or aot, as for eval"},
    {"--linear", CLI_CHOICE_AT(RunCli, linear, analysis_linear_names), .metavar = "L",
     .help = "linear algebra: dense (LU), sparse (KLU on the Jacobian's\n"
             "nonzeros; jit and aot; velocity-level rows integrated,\n"
             "KLU for the velocities) or auto\n"
             "(default: sparse above " ANALYSIS_DENSE_MAX_NQ_TEXT " coordinates when it can)"},
    {"--csv", CLI_STRING_AT(RunCli, csv_path), .metavar = "FILE",
     .help = "write the CSV to FILE ('-': stdout; the default when\n"
             "there is no --json)"},
    {"--json", CLI_FLAG_AT(RunCli, json),
     .help = "print {\"coords\", \"t\", \"q\", \"qd\", \"qdd\", \"ok\"[, \"error\"]}\n"
             "(with output statements also \"outputs\", \"y\", \"yd\", \"ydd\")"},
    {"--forces", CLI_FLAG_AT(RunCli, forces),
     .help = "inverse dynamics along the motion (a file with masses):\n"
             "the multipliers lambda(ROW) of every row and the effort(D)\n"
             "= -lambda(D) of every driver, as CSV columns after the\n"
             "others and JSON \"rows\", \"lambda\", \"drivers\", \"efforts\";\n"
             "--svg draws the joints' reaction forces as arrows"},
    {"--sens", CLI_FLAG_AT(RunCli, sens),
     .help = "sensitivities to the design parameters (a file with\n"
             "`design` statements, holonomic): CSV columns d(NAME)/d(P),\n"
             "d(d(NAME))/d(P) and d(dd(NAME))/d(P) after the others for\n"
             "every coordinate and output NAME and design parameter P;\n"
             "JSON \"sens_columns\" (those names) and \"sens\" (a row each)"},
    {"--digits", CLI_INT_AT(RunCli, digits, 1, 17), .metavar = "N",
     .help = "significant digits of numbers (default: the fewest that\n"
             "read back exactly, at most 17)"},
    {"--tol", CLI_REAL_AT(RunCli, tol), POSITIVE, .metavar = "X",
     .help = "Newton: converged when max |Phi_i| <= X and the last\n"
             "step max |dq_j| <= X (default 1e-8)"},
    {"--max-iter", CLI_INT_AT(RunCli, ro.max_iter, 1, 10000), .metavar = "N",
     .help = "Newton iterations per time step (default 25)"},
    {"--assembly-iter", CLI_INT_AT(RunCli, tune.assembly_max_iter, 1, 100000), .metavar = "N",
     .help = "minimum-norm Newton iterations per attempt when Newton\n"
             "cannot start from the initial values (default 100)"},
    {"--max-substeps", CLI_INT_AT(RunCli, tune.max_substeps, 1, 1 << 20), .metavar = "N",
     .help = "a step that seems to leave its assembly branch (Newton\n"
             "corrects far more than the predicted motion) is redone\n"
             "in 2, 4, 8 ... substeps, at most N (default 64), and\n"
             "the run fails past that; substeps are not output"},
    {"--pivot-tol", CLI_REAL_AT(RunCli, tune.pivot_tol), NONNEGATIVE, .metavar = "X",
     .help = "singular when an LU pivot <= X times the largest\n"
             "Jacobian entry (default 1e-12)"},
    {"--cond-warn", CLI_REAL_AT(RunCli, tune.cond_warn), NONNEGATIVE, .metavar = "X",
     .help = "warn where the Jacobian's condition estimate exceeds X\n"
             "(default 1e10; 0: no estimate)"},
    {"--ode", CLI_CHOICE_AT(RunCli, ode, ode_methods), .metavar = "M",
     .help = "integrator for velocity-level rows: rk8pd (default) or rkf45"},
    {"--ode-tol", CLI_REAL_AT(RunCli, tune.ode_tol), POSITIVE, .metavar = "X",
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
             "for a velocity, dd(NAME) for an acceleration, with\n"
             "--forces lambda(ROW) and effort(DRIVER), with --sens\n"
             "its columns d(NAME)/d(P) (default: every coordinate and\n"
             "output)"},
};

static const char epilogue[] =
    "\n"
    "CSV columns: t, then every coordinate by name (crank.x, ...) and every\n"
    "output, then the velocities d(crank.x), ..., then the accelerations\n"
    "dd(crank.x), ...; with --forces then lambda(ROW) for every row and\n"
    "effort(D) for every driver (the force or torque it applies along its\n"
    "coordinate: the motor torque of `driver D: crank.phi = ...`).\n"
    "Exit status: 0 done; 1 the analysis failed (the message names t = VALUE,\n"
    "the cause and the rows and coordinates involved; the states before the\n"
    "failure are written); 2 bad usage or input, or not as many rows as\n"
    "coordinates.\n";

/* --forces at one instant: every row's multiplier, every driver's effort. */
static void print_forces(const Model *m, const RunOutput *out, int digits)
{
    int dg = digits > 0 ? digits : 10, width = 10;
    for (int i = 0; i < m->nr; i++)
        if ((int)strlen(m->rows[i].name) > width)
            width = (int)strlen(m->rows[i].name);
    printf("\nrow%*s  %17s\n", width - 3, "", "lambda");
    for (int i = 0; i < m->nr; i++)
        printf("%-*s  %17.*g\n", width, m->rows[i].name, dg, out->lambda[i]);
    if (out->nd > 0)
        printf("\ndriver%*s  %17s\n", width - 6, "", "effort");
    for (int i = 0; i < out->nd; i++)
        printf("%-*s  %17.*g\n", width, out->dnames[i], dg, out->efforts[i]);
    printf("\nlambda as in M qdd + Phi_q^T lambda = Q; a driver's effort is -lambda (the force\n"
           "or torque it applies along its coordinate); a revolute's (lambda(J.x), lambda(J.y))\n"
           "is the force on its second body: examples/README.md, Reactions\n");
}

/* --steps 0 without --csv or --json: the one state as a table. */
static void print_table(const Model *m, const RunOutput *out, const RunResult *res, int digits)
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
    if (out->lambda_use == RUN_OUTPUT_FORCES)
        print_forces(m, out, digits);
}

static void print_stats(const RunResult *res, const MechrtKernels *k,
                        const MechrtHostJacNz *jnz, const double *q, const double *qd, double t,
                        bool forces)
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
    if (res->generated_factorisations > 0)
        fprintf(stderr, "mechc run: stats: unrolled LU (the kernels' lu_factor): %ld "
                "factorisations; its pivot checks sent the others to the pattern LU\n",
                res->generated_factorisations);
    double ns_all = engine_time_all(k, res->sparse ? jnz : NULL, q, qd, t, 0.05);
    fprintf(stderr, "mechc run: stats: one %s call (Phi, Phi_q, nu, gamma) takes "
            "%.1f ns: a step costs %.2f of them\n",
            !res->sparse ? "`all` kernel" : jnz->all_nz ? "`all_nz` kernel"
                                                        : "phi + jac_nz + nu + gamma kernel", ns_all,
            ns_all > 0 ? ns_step / ns_all : 0);
    if (res->max_cond > 0)
        fprintf(stderr, "mechc run: stats: largest condition estimate %.3g\n", res->max_cond);
    if (forces)
        fprintf(stderr, "mechc run: stats: inverse dynamics at every state (in the steps' "
                "time): up to %d dependent %s, largest part of Q - M qdd the rows could not "
                "carry %.3g\n", res->force_redundant, res->force_redundant == 1 ? "row" : "rows",
                res->force_residual);
}

/* The last state seen, for --stats' kernel timing. */
typedef struct LastState {
    RunOutput *out;
    double t;
    double *q, *qd;
} LastState;

static void on_state_keep(void *ctx, double t, const double *q, const double *qd,
                          const double *qdd, const double *lambda)
{
    LastState *ls = ctx;
    run_output_state(ls->out, t, q, qd, qdd, lambda);
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
        c->ro.tol = c->tol;
    if (c->ode >= 0)
        c->tune.ode = ode_methods[c->ode];
    c->tune.linear = analysis_linear_names[c->linear];
    if (!isnan(c->at)) {
        mechc_run_options d = mechc_run_defaults();
        if (c->ro.t0 != d.t0 || c->ro.t1 != d.t1 || c->ro.steps != d.steps) {
            fprintf(stderr, "mechc run: error: --at T is --t0 T --steps 0: give it alone, "
                    "without --t0, --t1 or --steps\n");
            return false;
        }
        c->ro.t0 = c->at;
        c->ro.steps = 0;
    }
    if (c->linear != ANALYSIS_LINEAR_DENSE) { /* checked by the run, where a dense one is formed */
        c->tune.max_dense_entries = c->limits.max_jac_entries;
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
    if (c->sens && c->forces) {
        fprintf(stderr, "mechc run: error: --sens and --forces each add columns: give one\n");
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
static bool resolve_pictures(const Model *m, const RunCli *c, RunPictures *p)
{
    p->svg_path = c->svg_path;
    p->plot_path = c->plot_path;
    p->view = c->view;
    p->sens = c->sens;
    return run_output_resolve_pictures("run", m, &c->traces, c->plot_list, c->forces, p);
}

/* Before any state: rows against coordinates (before the engine's
   compile), the pictures' names, the kernels, and the masses --forces
   needs. NULL when one fails (reported). */
static mechc_kernels *prepare(const Args *a, const RunCli *c, mechc_model *model,
                              RunPictures *pics)
{
    const Model *m = model->mech->model;
    Diag *diag = &model->diag;
    char why[300];
    if (!run_rows_match(m, why, sizeof why)) {
        diag_error(diag, m->last_pos, "%s", why);
        diag_print(diag, stderr);
        return NULL;
    }
    mechc_kernels *k = resolve_pictures(m, c, pics)
                           ? cli_compile(a, model, (EngineKind)c->engine, NULL) : NULL;
    if (!k)
        return NULL;
    if (c->forces && !mechc_has_dynamics(model)) {
        diag_error(diag, m->last_pos, "the mechanism has no masses: `run --forces` needs `mass` "
                   "statements (with `gravity`, forces or springs) for its inverse dynamics");
        diag_print(diag, stderr);
        mechc_kernels_free(k);
        return NULL;
    }
    return k;
}

/* After the analysis (r, or NULL and d when it could not start):
   pictures, JSON, the failure, --stats; the exit status. */
static int report(const RunCli *c, const Model *m, const RunOutput *out, const RunPictures *pics,
                  const mechc_result *r, const mechc_diag *d, const Engine *e,
                  const LastState *last)
{
    if (!r) {
        fprintf(stderr, "%s: error: %s\n", m->file, d->message);
        return EXIT_USAGE;
    }
    const char *failure = mechc_result_status(r) == MECHC_EANALYSIS ? mechc_result_message(r)
                                                                     : NULL;
    const RunResult *res = lib_result_run(r);  /* the statistics */
    int status = EXIT_OK;
    if (c->pictures && !run_output_pictures(out, pics))
        status = EXIT_USAGE;
    if (c->json)
        run_output_json(stdout, out, failure, mechc_result_t_fail(r));
    if (c->table && !failure && out->trace.rows == 1)
        print_table(m, out, res, c->digits);
    if (run_output_report_failure(out, m, failure, mechc_result_states(r), mechc_result_t_fail(r)))
        status = EXIT_ANALYSIS;
    if (c->stats)
        print_stats(res, engine_kernels(e), engine_jac_nz(e), last->q, last->qd, last->t,
                    c->forces);
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

/* --sens: the sensitivities at each state into the extra columns x; a
   state where they cannot be had (Phi_q singular) gets NaN, said once. */
typedef struct SensColumns {
    Sens sens;
    bool warned, timed;     /* timed: --stats */
    long states;
    /* for --stats: the CPU and wall time in sens_eval, and the run's CPU
       time per step (its "of CPU time in the steps" line) */
    double cpu_seconds, wall_seconds, step_cpu_ns;
} SensColumns;

static void fill_sens(void *ctx, double t, const double *q, const double *qd, const double *qdd,
                      double *x)
{
    SensColumns *sc = ctx;
    /* a clock() reading is a system call (1.6 us of CPU time on a loaded
       virtual machine, more than the sensitivities of a four-bar): made
       only for --stats, around a span shaped like the step's (run.c),
       with two wall-clock readings in it, so that one calibration serves */
    clock_t start = sc->timed ? clock() : 0;
    double wall = sc->timed ? pipeline_now() : 0;
    MechrtStatus st = sens_eval(&sc->sens, t, q, qd, qdd);
    if (sc->timed) {
        sc->wall_seconds += pipeline_now() - wall;
        sc->cpu_seconds += (double)(clock() - start) / CLOCKS_PER_SEC;
    }
    sc->states++;
    if (st == MECHRT_OK) {
        sens_columns(&sc->sens, x);
        return;
    }
    for (int i = 0; i < sens_column_count(&sc->sens); i++)
        x[i] = NAN;
    if (!sc->warned)
        fprintf(stderr, "%s: warning: no sensitivities at t = %.10g: %s (NaN there; later "
                "ones are not reported)\n", sc->sens.m->file, t, mechrt_strerror(st));
    sc->warned = true;
}

/* The extra columns of --sens on out. */
static void open_sens(RunOutput *out, SensColumns *sc)
{
    int n = sens_column_count(&sc->sens);
    char **names = xcalloc((size_t)n + 1, sizeof *names);
    for (int i = 0; i < n; i++)
        names[i] = sens_column_name(&sc->sens, out->names, i);
    run_output_set_extra(out, n, names, fill_sens, sc);
}

/* The run (mechc_run_with) with the compiled kernels, the states going
   where c says: streamed, not kept by the library. */
static int analyse(RunCli *c, const Model *m, mechc_kernels *k, const RunPictures *pics,
                   SensColumns *sc)
{
    RunOutput out = {.cmd = "run", .keep = c->json || c->pictures || c->table,
                     .lambda_use = c->forces ? RUN_OUTPUT_FORCES : RUN_OUTPUT_NO_LAMBDA,
                     .digits = c->digits, .t0 = c->ro.t0, .t1 = c->ro.t1};
    if (c->csv_stdout) {
        out.csv = stdout;
    } else if (c->csv_path && !(out.csv = cli_open_output("run", c->csv_path))) {
        return EXIT_USAGE;
    }
    run_output_open(&out, m);
    if (sc)
        open_sens(&out, sc);
    LastState last = {&out, c->ro.t0, xcalloc((size_t)m->nq, sizeof(double)),
                      xcalloc((size_t)m->nq, sizeof(double))};
    memcpy(last.q, m->q0, (size_t)m->nq * sizeof(double));
    mechc_run_options ro = c->ro;
    ro.forces = c->forces;
    ro.on_state = on_state_keep;
    ro.ctx = &last;
    mechc_run_tuning tune = c->tune;
    tune.notes = stderr;
    tune.keep_states = 0;
    RunOptions full;
    const MechrtHostJacNz *jnz = engine_jac_nz(&k->engine);
    RunLu lent = {0};
    RunLu *lend = NULL;
    if (sc && lib_run_options(&ro, &tune, &full) && run_linear_is_sparse(m, jnz, &full)) {
        sens_use_sparse(&sc->sens, jnz);    /* KLU as the run; else ... */
    } else if (sc) {
        lend = &lent;                       /* ... the run's own LU, where it has one */
        sens_borrow_lu(&sc->sens, &lent);
    }
    progress_start(&out.progress, "run", 1000);
    mechc_diag d;
    mechc_result *r = lib_run_lending(k, &ro, &tune, lend, &d);
    progress_finish(&out.progress);
    int status = report(c, m, &out, pics, r, &d, &k->engine, &last);
    const RunResult *res = r ? lib_result_run(r) : NULL;
    if (sc && res && res->steps_done > 0)
        sc->step_cpu_ns = 1e9 * res->step_cpu_seconds / res->steps_done;
    status = finish_output(c, out.csv, status);
    mechc_result_free(r);
    free(last.q), free(last.qd);
    run_output_close(&out);
    return status;
}

/* The CPU time an empty span between two clock() readings reads, with
   the two wall-clock readings the spans of the steps and sensitivities
   have inside (run.c, fill_sens): mean of n. */
static double clock_span_ns(int n)
{
    double sum = 0;
    for (int i = 0; i < n; i++) {
        clock_t c0 = clock();
        sum -= pipeline_now() - pipeline_now();
        sum += (double)(clock() - c0) / CLOCKS_PER_SEC;
    }
    return 1e9 * sum / n;
}

/* --stats of --sens: its cost per state beside the step's, in CPU time
   less what the clock() readings around every span take themselves (a
   system call: 1.6 us on a loaded virtual machine, twice a four-bar's
   step), measured here after the run. */
static void print_sens_stats(const SensColumns *sc)
{
    double cpu = 1e9 * sc->cpu_seconds / (double)sc->states;
    fprintf(stderr, "mechc run: stats: sensitivities to %d design parameters%s: %.6g ms of "
            "CPU time, %.0f ns per state (wall time %.0f ns); the run's LU of Phi_q reused "
            "at %ld of %ld\n", sc->sens.np, sc->sens.klu ? " (KLU of Phi_q)" : "",
            1e3 * sc->cpu_seconds, cpu, 1e9 * sc->wall_seconds / (double)sc->states,
            sc->sens.borrowed_count, sc->states);
    if (!(sc->step_cpu_ns > 0))
        return;
    double span = clock_span_ns(4000), sens = cpu - span, step = sc->step_cpu_ns - span;
    fprintf(stderr, "mechc run: stats: less the %.0f ns an empty clock() span reads: "
            "sensitivities %.0f ns per state, steps %.0f ns: run --sens costs %.3g times "
            "the run\n", span, sens, step, 1 + sens / step);
}

/* Rows, pictures and engine ready, then the analysis. */
static int run_file(const Args *a, mechc_model *model, void *opts)
{
    Mech *mech = model->mech;
    Diag *diag = &model->diag;     /* the file's: its text for positions */
    RunCli *c = opts;
    RunPictures pics;
    mechc_kernels *k = prepare(a, c, model, &pics);
    if (!k)
        return EXIT_USAGE;
    const Engine *e = &k->engine;
    if (c->stats)   /* what it took to have the kernels (wall time) */
        fprintf(stderr, "mechc run: stats: set-up: load %.3f s, derivatives %.3f s, emission "
                "%.3f s, compilation %.3f s\n", mech->load_seconds, mech->diff_seconds,
                e->gen_seconds, e->compile_seconds);
    SensColumns sc = {.timed = c->stats};
    char why[200];
    if (c->sens && !sens_init(&sc.sens, mech->model, &mech->kin, e, why, sizeof why)) {
        diag_error(diag, mech->model->last_pos, "run --sens: %s", why);
        diag_print(diag, stderr);
        mechc_kernels_free(k);
        return EXIT_USAGE;
    }
    int status = analyse(c, mech->model, k, &pics, c->sens ? &sc : NULL);
    if (c->sens && c->stats && sc.states > 0)
        print_sens_stats(&sc);
    if (c->sens)
        sens_free(&sc.sens);
    mechc_kernels_free(k);
    return status;
}

static const CliCommand command = {
    .name = "run", .usage = usage, CLI_OPTIONS(options), .column = 19, .epilogue = epilogue,
    .limits_offset = offsetof(RunCli, limits),
    .finish = finish, .run = run_file,
};

int cmd_run(int argc, char **argv)
{
    RunCli c = {.ro = mechc_run_defaults(), .tune = mechc_run_tuning_defaults(), .limits = mechc_default_limits(),
                .engine = ENGINE_JIT, .ode = -1, .view = -1, .at = NAN};
    return cli_main(&command, argc, argv, &c);
}
