/* cmd_sim.c - mechc sim: forward dynamics over time of a mechanism with masses.
 *
 * Parses the options, loads the mechanism, opens the engine and hands the
 * rest to sim_run (generator/dyn/sim.c). The states go out as run's
 * do, through run's output module (run_output.c): the same CSV columns and
 * JSON keys, the file's outputs beside the coordinates, the same animation
 * and chart writers; JSON adds the multipliers ("rows", "lambda"). On a
 * failure the states computed before it are still written, and the
 * message goes to stderr.
 */
#include "cli.h"

#include "../kin/outputs.h"

#include "../kin/run.h"
#include "../dyn/sim.h"
#include "../base/arena.h"
#include "run_output.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_TRACES = RUN_OUTPUT_MAX_TRACES };

/* What the command line asked for. */
typedef struct SimCli {
    mechc_sim_options so;   /* libmechc's simulation (mechc.h) ... */
    mechc_sim_tuning tune;  /* ... with the command's tuning */
    mechc_limits limits;
    const char *csv_path, *svg_path, *plot_path, *plot_list, *qd_text, *baumgarte;
    CliList omegas;         /* --w BODY=wx,wy,wz */
    CliList traces;
    int engine, method, digits, view, linear, max_steps;
    bool json, stats, interpolate;
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
    {"--max-steps", CLI_INT_AT(SimCli, max_steps, 1, INT_MAX), .metavar = "N",
     .help = "integrator steps allowed in all (default 10000000): a\n"
             "longer run stops with exit 1 and the time reached"},
    {"--engine", CLI_CHOICE_AT(SimCli, engine, engine_names), .metavar = "E",
     .help = "jit (default), generic or aot, as for eval"},
    {"--method", CLI_CHOICE_AT(SimCli, method, sim_method_names), .metavar = "M",
     .help = "integrator: rk8pd (default), rkf45 (explicit Runge-Kutta\n"
             "pairs), rk4imp or msbdf (implicit, for stiff springs and\n"
             "dampers; finite-difference Jacobian)"},
    {"--linear", CLI_CHOICE_AT(SimCli, linear, analysis_linear_names), .metavar = "L",
     .help = "linear algebra: dense (null-space method, QR/SVD\n"
             "projections) or sparse (KLU on the augmented matrix from\n"
             "the generated kernels' nonzeros; jit, aot); default auto:\n"
             "sparse above 100 coordinates"},
    {"--rtol", CLI_REAL_AT(SimCli, so.rtol), NONNEGATIVE, .metavar = "X",
     .help = "relative error per step, as GSL's and SUNDIALS' rtol:\n"
             "|err_i| <= atol + rtol |y_i| on every position and rate\n"
             "(default 5e-11: the errors of the steps add up, and\n"
             "IFToMM A01's 2000 s need it to stay within 1e-5)"},
    {"--atol", CLI_REAL_AT(SimCli, so.atol), NONNEGATIVE, .metavar = "X",
     .help = "absolute error per step, coordinate units (default 5e-11)"},
    {"--qd", CLI_STRING_AT(SimCli, qd_text), .metavar = "V1,V2,...",
     .help = "initial velocities, one per coordinate (default 0);\n"
             "projected onto the velocity equations"},
    {"--w", CLI_LIST_AT(SimCli, omegas, CLI_LIST_MAX), .what = "bodies", .metavar = "B=WX,WY,WZ",
     .help = "initial angular velocity of spatial body B, global frame\n"
             "(rad/s; repeatable): its Euler-parameter rates, after --qd"},
    {"--interpolate", CLI_FLAG_AT(SimCli, interpolate),
     .help = "step across the output times: states there from the\n"
             "Hermite interpolant of q, qd, qdd at the ends of the\n"
             "last two steps, degree 8 (quintic within the first step;\n"
             "fewer steps when outputs are dense; default: a step\n"
             "ends at each)"},
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
    {"--view", CLI_CHOICE_AT(SimCli, view, svg_view_names), .metavar = "V",
     .help = "a spatial mechanism's animation seen from the front,\n"
             "top, side or iso (default), as for run"},
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

/* The --trace points and --plot variables, resolved against the model. */
static bool resolve_pictures(const Model *m, const SimCli *c, RunPictures *p)
{
    p->svg_path = c->svg_path;
    p->plot_path = c->plot_path;
    p->view = c->view;
    return run_output_resolve_pictures("sim", m, &c->traces, c->plot_list, false, p);
}

static void print_stats(const SimResult *r, int nr)
{
    const SimKernelCalls *k = &r->calls;
    fprintf(stderr, "mechc sim: stats: %ld integrator steps, %ld rejected, %ld right-hand "
            "sides (forward-dynamics solves), %ld finite-difference Jacobians\n", r->steps,
            r->rejected, r->rhs_calls, r->jacobian_calls);
    fprintf(stderr, "mechc sim: stats: %ld projections (%ld Newton iterations); dense "
            "projection solves: %ld by QR, %ld by the SVD (near a rank drop)\n",
            r->projections, r->projection_iterations, r->qr_solves, r->svd_solves);
    if (r->sparse)
        fprintf(stderr, "mechc sim: stats: sparse augmented matrix (KLU): %ld factorisations "
                "with pivoting, %ld refactorisations, %ld reused at the same state, %ld "
                "projection solves; rows chosen by its pivots %ld times, by the dense "
                "elimination %ld times (near a rank drop); %ld dense fallbacks\n",
                r->kkt_fresh, r->kkt_refactored, r->kkt_reused, r->kkt_solves, r->rows_sparse,
                r->rows_dense, r->dense_fallbacks);
    fprintf(stderr, "mechc sim: stats: kernel calls: mass %ld, force %ld, all %ld, jac %ld, "
            "gamma %ld, phi %ld, nu %ld", k->mass, k->force, k->all, k->jac, k->gamma,
            k->phi, k->nu);
    if (r->sparse)
        fprintf(stderr, ", all_nz %ld, jac_nz %ld, mass_nz %ld", k->all_nz, k->jac_nz,
                k->mass_nz);
    fputc('\n', stderr);
    if (r->energy_scale > 0)
        fprintf(stderr, "mechc sim: stats: energy balance T - W drifted by %.3g (%.3g of the "
                "largest kinetic energy or work, %.3g); for a conservative mechanism (no "
                "dampers, no drivers) this is the energy drift\n", r->energy_drift,
                r->energy_drift / r->energy_scale, r->energy_scale);
    if (nr > 0 && r->sparse)
        fprintf(stderr, "mechc sim: stats: up to %d dependent %s; largest pivot spread of "
                "[I Phi_q^T; Phi_q 0] with every row %.3g (about (sigma_max / sigma_min)^2 of "
                "Phi_q; above 1e4 the dense elimination chose the rows)\n", r->max_redundant,
                r->max_redundant == 1 ? "row" : "rows", r->max_screen_spread);
    else if (nr > 0)
        fprintf(stderr, "mechc sim: stats: up to %d dependent %s; smallest pivot ratio of "
                "Phi_q %.3g (near 0: a singular position)\n", r->max_redundant,
                r->max_redundant == 1 ? "row" : "rows", r->min_pivot_ratio);
    if (r->fold_steps > 0)
        fprintf(stderr, "mechc sim: stats: %ld steps near a rank drop left rows out, with the "
                "accelerations those rows impose held from where they went out\n",
                r->fold_steps);
    fprintf(stderr, "mechc sim: stats: %.6g ms of integration (%.6g ms CPU)\n",
            1e3 * r->seconds, 1e3 * r->cpu_seconds);
}

static bool finish(Args *a, void *opts)
{
    SimCli *c = opts;
    if (!args_need_file(a))
        return false;
    if (c->method >= 0)
        c->so.method = sim_method_names[c->method];
    c->tune.linear = analysis_linear_names[c->linear];
    if (c->so.t0 == c->so.t1) {
        fprintf(stderr, "mechc sim: error: --t0 and --t1 are both %g: nothing to simulate\n",
                c->so.t0);
        return false;
    }
    c->tune.max_steps = c->max_steps;
    c->tune.interpolate = c->interpolate;
    if (c->so.steps > c->max_steps && !c->interpolate) {
        fprintf(stderr, "mechc sim: error: --steps %d output states need at least as many "
                "integrator steps, more than --max-steps %d (raise it, or --interpolate)\n",
                c->so.steps, c->max_steps);
        return false;
    }
    if (c->so.rtol >= 1) {      /* a relative error of 100 % or more: a misplaced exponent */
        fprintf(stderr, "mechc sim: error: --rtol %g is not below 1 (e.g. 1e-8)\n", c->so.rtol);
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
        if (!(ab[0] >= 0) || !(ab[1] >= 0)) {
            fprintf(stderr, "mechc sim: error: --baumgarte gains must not be negative (a negative "
                    "one makes the drift grow), got %g,%g\n", ab[0], ab[1]);
            return false;
        }
        c->tune.baumgarte_alpha = ab[0];
        c->tune.baumgarte_beta = ab[1];
    }
    if ((c->traces.n > 0 && !c->svg_path) || (c->plot_list && !c->plot_path)) {
        fprintf(stderr, "mechc sim: error: %s goes with %s\n",
                c->traces.n ? "--trace" : "--plot-vars", c->traces.n ? "--svg FILE" : "--plot FILE");
        return false;
    }
    if (c->view >= 0 && !c->svg_path) {
        fprintf(stderr, "mechc sim: error: --view goes with --svg FILE\n");
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

/* After the simulation (r, or NULL and d when it could not start):
   pictures, JSON, the failure, --stats; the exit status. */
static int report(const SimCli *c, const Model *m, const RunOutput *out, const RunPictures *p,
                  const mechc_result *r, const mechc_diag *d)
{
    if (!r) {
        fprintf(stderr, "%s: error: %s\n", m->file, d->message);
        return EXIT_USAGE;
    }
    const char *failure = mechc_result_status(r) == MECHC_EANALYSIS ? mechc_result_message(r)
                                                                     : NULL;
    int status = EXIT_OK;
    if (c->pictures && !run_output_pictures(out, p))
        status = EXIT_USAGE;        /* as run: a file that cannot be written */
    if (c->json)
        run_output_json(stdout, out, failure, mechc_result_t_fail(r));
    if (run_output_report_failure(out, m, failure, mechc_result_states(r), mechc_result_t_fail(r)))
        status = EXIT_ANALYSIS;
    if (c->stats)
        print_stats(lib_result_sim(r), m->nr);
    return status;
}

/* After each accepted integrator step: the progress bar by simulated time. */
static void step_progress(void *ctx, double t)
{
    RunOutput *out = ctx;
    progress_update(&out->progress, (long)(1000.0 * (t - out->t0) / (out->t1 - out->t0)));
}

/* The simulation (mechc_sim_with) with the compiled kernels, the states
   going where c says: streamed, not kept by the library. */
static int simulate(SimCli *c, const Model *m, mechc_kernels *k, const RunPictures *p)
{
    RunOutput out = {.cmd = "sim", .keep = c->json || c->pictures,
                     .lambda_use = RUN_OUTPUT_LAMBDA_JSON, .digits = c->digits, .t0 = c->so.t0,
                     .t1 = c->so.t1};
    if (c->csv_stdout)
        out.csv = stdout;
    else if (c->csv_path && !(out.csv = cli_open_output("sim", c->csv_path)))
        return EXIT_USAGE;
    run_output_open(&out, m);
    mechc_sim_options so = c->so;
    so.on_state = run_output_state;
    so.ctx = &out;
    mechc_sim_tuning tune = c->tune;
    tune.notes = stderr;
    tune.keep_states = 0;
    tune.on_step = step_progress;
    tune.step_ctx = &out;
    progress_start(&out.progress, "sim", 1000);
    mechc_diag d;
    mechc_result *r = mechc_sim_with(k, &so, &tune, &d);
    progress_finish(&out.progress);
    int status = report(c, m, &out, p, r, &d);
    mechc_result_free(r);
    if (out.csv && out.csv != stdout && fclose(out.csv) != 0) {
        fprintf(stderr, "mechc sim: error: writing '%s': %s\n", c->csv_path, strerror(errno));
        status = status == EXIT_OK ? EXIT_USAGE : status;
    } else if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "mechc sim: error: writing the output: %s\n", strerror(errno));
        status = status == EXIT_OK ? EXIT_USAGE : status;
    }
    run_output_close(&out);
    return status;
}

/* --w B=wx,wy,wz into qd0: B's Euler-parameter rates at the file's
   orientation; false (reported) for a name that is no spatial body, a
   value that is not three numbers, or a body given twice. */
static bool read_omegas(const SimCli *c, const Model *m, double *qd0)
{
    for (int i = 0; i < c->omegas.n; i++) {
        size_t len_i = strcspn(c->omegas.items[i], "=");
        for (int k = 0; k < i; k++)
            if (strncmp(c->omegas.items[k], c->omegas.items[i], len_i + 1) == 0) {
                fprintf(stderr, "mechc sim: error: --w: body '%.*s' is given more than once\n",
                        (int)len_i, c->omegas.items[i]);
                return false;
            }
        const char *item = c->omegas.items[i], *eq = strchr(item, '=');
        char name[256];
        size_t len = eq ? (size_t)(eq - item) : 0;
        snprintf(name, sizeof name, "%.*s", (int)(len < sizeof name ? len : sizeof name - 1), item);
        const Body *b = eq ? model_find_body(m, name) : NULL;
        if (!b || b->nq != 7) {
            fprintf(stderr, "mechc sim: error: --w takes B=WX,WY,WZ with B a spatial body, "
                    "not '%s'\n", item);
            return false;
        }
        double w[3];
        if (!args_vector("sim", "--w", eq + 1, 3, w))
            return false;
        outputs_euler_rates(m->q0 + b->q + 3, w, qd0 + b->q + 3);
    }
    return true;
}

/* Masses, velocities and pictures checked, the kernels compiled, then the simulation. */
static int sim_file(const Args *a, mechc_model *model, void *opts)
{
    Mech *mech = model->mech;
    Diag *diag = &model->diag;     /* the file's: its text for positions */
    SimCli *c = opts;
    const Model *m = mech->model;
    RunPictures pics;
    double *qd0 = xcalloc((size_t)m->nq, sizeof *qd0);
    int status = EXIT_USAGE;
    if ((c->qd_text && !args_vector("sim", "--qd", c->qd_text, m->nq, qd0))
        || !read_omegas(c, m, qd0) || !resolve_pictures(m, c, &pics)) {
        free(qd0);
        return EXIT_USAGE;
    }
    c->so.qd0 = qd0;
    mechc_kernels *k = cli_compile(a, model, (EngineKind)c->engine, NULL);
    if (!k) {
        free(qd0);
        return EXIT_USAGE;
    }
    if (!mechc_has_dynamics(model)) {
        diag_error(diag, m->last_pos, "the mechanism has no masses: `mechc sim` needs `mass` "
                   "statements (with `gravity`, forces or springs) to simulate its dynamics");
        diag_print(diag, stderr);
    } else if (m->nh > m->nq && !redundant_applies(m)) {   /* before any output: sim_run
                                                              would refuse it later */
        diag_error(diag, m->last_pos, "%d holonomic rows for %d coordinates: sim's position "
                   "projection needs at most one row per coordinate", m->nh, m->nq);
        diag_print(diag, stderr);
    } else {
        status = simulate(c, m, k, &pics);
    }
    mechc_kernels_free(k);
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
    SimCli c = {.so = mechc_sim_defaults(), .tune = mechc_sim_tuning_defaults(),
                .limits = mechc_default_limits(), .engine = ENGINE_JIT, .method = -1, .view = -1};
    c.max_steps = (int)c.tune.max_steps;
    return cli_main(&command, argc, argv, &c);
}
