/* cmd_check.c - mechc check: derivatives against finite differences, engines against each other. */
#include "cli.h"

#include "../verify/check.h"

#include <limits.h>
#include <math.h>
#include <string.h>

/* What the command line asked for. */
typedef struct CheckCli {
    CheckOptions opt;
    mechc_limits limits;
    int seed;               /* opt.seed, read as an int */
    int linear;             /* --linear, an AnalysisLinear */
    bool json;
    long long max_dense;    /* limits.max_jac_entries, checked by check_file */
} CheckCli;

static const char usage[] =
    "usage: mechc check FILE.mech [--samples N] [--seed S] [--tol T] [--tol-engines T]\n"
    "                   [--fd-step H] [--fd-step2 H] [--spread-q S] [--spread-qd S]\n"
    "                   [--no-aot] [--linear dense|sparse|auto] [--json]\n"
    "\n"
    "Compares the generated Jacobian, nu and gamma with finite differences of Phi\n"
    "(and of Psi for velocity-level rows), and the engines (jit, generic, aot when a\n"
    "C compiler exists) with each other, at random states around the configuration\n"
    "assembled at t = 0. Prints the worst error of each comparison and the row where\n"
    "it occurs; exit status 1 when one is above its tolerance, with a guess at the\n"
    "textbook mistake it looks like.\n"
    "\n";

#define UNIT .min = 0, .above_min = true, .max = 1, .what = "a number in (0, 1]"

static const CliOption options[] = {
    {"--samples", CLI_INT_AT(CheckCli, opt.samples, 1, 1000000), .metavar = "N",
     .help = "states to sample (default 20)"},
    {"--seed", CLI_INT_AT(CheckCli, seed, 0, INT_MAX), .metavar = "S",
     .help = "seed of the random states (default 1)"},
    {"--tol", CLI_REAL_AT(CheckCli, opt.tol), CLI_POSITIVE, .what = "a positive number",
     .metavar = "T", .help = "tolerance against finite differences (default 1e-6)"},
    {"--tol-engines", CLI_REAL_AT(CheckCli, opt.tol_engines), CLI_POSITIVE,
     .what = "a positive number", .metavar = "T", .help = "tolerance between engines (default 1e-10)"},
    {"--fd-step", CLI_REAL_AT(CheckCli, opt.fd_step), UNIT, .metavar = "H",
     .help = "first step of the first derivatives' finite differences\n"
             "(jac, nu; gamma of velocity rows), times max(1, |x|)\n"
             "(default 1e-4)"},
    {"--fd-step2", CLI_REAL_AT(CheckCli, opt.fd_step2), UNIT, .metavar = "H",
     .help = "step of gamma's second differences, times max(1, |q|)^(1/6)\n"
             "(default 2e-3)"},
    {"--spread-q", CLI_REAL_AT(CheckCli, opt.spread_q), CLI_NONNEGATIVE, .what = "a number >= 0",
     .metavar = "S", .help = "sampled q = assembled q + uniform(-S, S) (default 0.05)"},
    {"--spread-qd", CLI_REAL_AT(CheckCli, opt.spread_qd), CLI_NONNEGATIVE, .what = "a number >= 0",
     .metavar = "S", .help = "sampled qd = uniform(-S, S) (default 1)"},
    {"--no-aot", CLI_CLEAR_AT(CheckCli, opt.use_aot), .help = "do not build and compare the aot engine"},
    {"--linear", CLI_CHOICE_AT(CheckCli, linear, analysis_linear_names), .metavar = "L",
     .help = "dense Jacobians, or sparse: the Jacobian's nonzeros,\n"
             "assembly by KLU, finite differences by column groups;\n"
             "auto (default: sparse above " ANALYSIS_DENSE_MAX_NQ_TEXT " coordinates)"},
    {"--json", CLI_FLAG_AT(CheckCli, json),
     .help = "print JSON: ok, samples, worst[{what, error, row, ...}]"},
};

static const char epilogue[] =
    "\n"
    "Errors are |value - reference| / (1 + |reference|). A value that disagrees with\n"
    "its finite difference at the default step H is not failed yet: the difference\n"
    "is redone at H/pi, H/pi^2, ... H/pi^8, then pi H and pi^2 H, until three\n"
    "neighbouring steps agree within tol/2, and the value is judged against that\n"
    "settled difference (truncation error shrinks with the step, a mistake does not).\n"
    "The \"fd step\" column is the step of the worst comparison's difference\n"
    "(\"exact\": none was needed); \"refined\" counts the comparisons judged at\n"
    "another step than H. A comparison that no run of steps settles is reported as\n"
    "unsettled, with a warning: the differences cannot tell, so it neither passes\n"
    "nor fails.\n";

static const char *row_name(const Model *m, int row)
{
    return row >= 0 && row < m->nr ? m->rows[row].name : "-";
}

static bool item_ok(const CheckItem *it)
{
    return it->error <= it->tol;
}

static bool item_fd(const CheckItem *it, const CheckReport *rep)
{
    return it >= rep->items && it < rep->items + CHECK_PAIR_FIRST;
}

static const char *col_name(const Model *m, int col)
{
    return col >= 0 && col < m->nq ? m->coord_names[col] : "-";
}

/* An item's column: a coordinate, or a design parameter (dPhi/dp's items). */
static const char *item_col(const Model *m, const CheckItem *it)
{
    if (it->design_col)
        return it->col >= 0 && it->col < m->np ? m->design_names[it->col] : "-";
    return col_name(m, it->col);
}

static void print_json(const Model *m, const CheckReport *rep)
{
    printf("{\"ok\": %s, \"samples\": %d, \"assembled\": %s, \"engines\": [",
           rep->ok ? "true" : "false", rep->samples, rep->assembled ? "true" : "false");
    bool first = true;
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (rep->engine_used[k]) {
            printf("%s\"%s\"", first ? "" : ", ", engine_names[k]);
            first = false;
        }
    printf("],\n \"worst\": [");
    first = true;
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        const CheckItem *it = &rep->items[w];
        if (!it->checked)
            continue;
        printf("%s{\"what\": \"%s\", \"error\": ", first ? "" : ",\n           ", it->what);
        first = false;
        json_number(stdout, it->error);
        printf(", \"row\": ");
        if (it->row >= 0)
            json_string(stdout, row_name(m, it->row));
        else
            printf("null");
        if (it->col >= 0) {
            printf(", \"col\": ");
            json_string(stdout, item_col(m, it));
        }
        printf(", \"tol\": ");
        json_number(stdout, it->tol);
        printf(", \"ok\": %s, \"value\": ", item_ok(it) ? "true" : "false");
        json_number(stdout, it->value);
        printf(", \"reference\": ");
        json_number(stdout, it->reference);
        printf(", \"t\": ");
        json_number(stdout, it->t);
        if (item_fd(it, rep)) {
            printf(", \"step\": ");
            if (it->step > 0.0)
                json_number(stdout, it->step);
            else
                printf("null");
            printf(", \"refined\": %d, \"unsettled\": %d", it->refined, it->unsettled);
            if (it->unsettled > 0) {
                printf(", \"unsettled_row\": ");
                json_string(stdout, row_name(m, it->unsettled_row));
                if (it->unsettled_col >= 0) {
                    printf(", \"unsettled_col\": ");
                    json_string(stdout, col_name(m, it->unsettled_col));
                }
            }
        }
        if (it->hint[0]) {
            printf(", \"hint\": ");
            json_string(stdout, it->hint);
        }
        printf("}");
    }
    printf("]");
    if (rep->note[0]) {
        printf(",\n \"note\": ");
        json_string(stdout, rep->note);
    }
    printf("}\n");
}

static void print_text(const Model *m, const CheckReport *rep)
{
    printf("check %s: %d samples around the %s\n", m->name, rep->samples,
           rep->assembled ? "configuration assembled at t = 0" : "initial values (not assembled)");
    printf("engines:");
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (rep->engine_used[k])
            printf(" %s%s", engine_names[k], k == ENGINE_JIT ? " (under test)" : "");
    printf("%s%s\n\n", rep->note[0] ? "; " : "", rep->note);
    int rw = 3, cw = 3;
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        const CheckItem *it = &rep->items[w];
        if (!it->checked)
            continue;
        if ((int)strlen(row_name(m, it->row)) > rw)
            rw = (int)strlen(row_name(m, it->row));
        if (it->col >= 0 && (int)strlen(item_col(m, it)) > cw)
            cw = (int)strlen(item_col(m, it));
    }
    printf("     %-17s  %11s  %9s  %-*s  %-*s  %-10s  %s\n", "what", "worst error", "tolerance", rw, "row",
           cw, "col", "t", "fd step");
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        const CheckItem *it = &rep->items[w];
        if (!it->checked)
            continue;
        if (w == CHECK_PAIR_FIRST || w == CHECK_DYN_FIRST || w == CHECK_PHI_P_FD)
            printf("\n");
        char step[40] = "";
        if (item_fd(it, rep)) {
            if (it->step > 0.0)
                snprintf(step, sizeof step, "%.3g", it->step);
            else
                snprintf(step, sizeof step, "exact");
        }
        printf("%-4s %-17s  %11.3g  %9.3g  %-*s  %-*s  %-*.6g%s%s\n", item_ok(it) ? "ok" : "FAIL", it->what,
               it->error, it->tol, rw, row_name(m, it->row), cw, item_col(m, it), step[0] ? 10 : 0, it->t,
               step[0] ? "  " : "", step);
        if (item_fd(it, rep) && it->refined > 0)
            printf("       refined: %d comparison%s judged at another step than the default (a fast-varying row)\n",
                   it->refined, it->refined == 1 ? "" : "s");
        if (item_fd(it, rep) && it->unsettled > 0)
            printf("       unsettled: %d comparison%s not judged, the finite differences agreeing at no run of\n"
                   "       steps (first at row %s%s%s); try other --fd-step/--fd-step2\n",
                   it->unsettled, it->unsettled == 1 ? "" : "s", row_name(m, it->unsettled_row),
                   it->unsettled_col >= 0 ? ", column " : "", it->unsettled_col >= 0 ? col_name(m, it->unsettled_col) : "");
        if (!item_ok(it)) {
            printf("       value %.17g, reference %.17g\n", it->value, it->reference);
            if (it->hint[0])
                printf("       looks like: %s\n", it->hint);
        }
    }
    printf("\n%s\n", rep->ok ? "ok: every comparison is within its tolerance"
                             : "FAILED: see the lines marked FAIL");
}

/* On stderr: the first failed comparison, and every unsettled one. */
static void report_failures(const char *file, const Model *m, const CheckReport *rep)
{
    for (int w = 0; w < CHECK_WHAT_COUNT && !rep->ok; w++) {
        const CheckItem *it = &rep->items[w];
        if (it->checked && !item_ok(it)) {
            fprintf(stderr, "%s: error: %s of row %s%s%s is off by %.3g (tolerance %.3g) at t = %.17g%s%s\n",
                    file, it->what, row_name(m, it->row),
                    it->col >= 0 ? ", column " : "", it->col >= 0 ? item_col(m, it) : "",
                    it->error, it->tol, it->t, it->hint[0] ? ": " : "", it->hint);
            break;
        }
    }
    for (int w = 0; w < CHECK_PAIR_FIRST; w++) {
        const CheckItem *it = &rep->items[w];
        if (it->unsettled > 0)
            fprintf(stderr, "%s: warning: %d %s comparison%s unsettled (first at row %s%s%s): the finite "
                    "differences agree at no run of steps; not judged\n", file, it->unsettled, it->what,
                    it->unsettled == 1 ? "" : "s", row_name(m, it->unsettled_row),
                    it->unsettled_col >= 0 ? ", column " : "",
                    it->unsettled_col >= 0 ? col_name(m, it->unsettled_col) : "");
    }
}

/* The comparisons, their report on stdout and the failures on stderr. */
static int check_file(const Args *a, mechc_model *model, void *opts)
{
    Mech *mech = model->mech;
    Diag *diag = &model->diag;     /* the file's: its text for positions */
    CheckCli *c = opts;
    CheckReport rep;
    c->opt.seed = (unsigned long)c->seed;
    c->opt.linear = (AnalysisLinear)c->linear;
    const Model *m = mech->model;
    bool sparse = c->linear == ANALYSIS_LINEAR_SPARSE
                  || (c->linear == ANALYSIS_LINEAR_AUTO && m->nq > ANALYSIS_DENSE_MAX_NQ);
    long long dense = (long long)m->nr * m->nq, mass = m->nmasses > 0 ? (long long)m->nq * m->nq : 0;
    if ((!sparse && dense > c->max_dense) || mass > c->max_dense) {
        fprintf(stderr, "mechc check: error: %s: the dense %s would have %lld entries, more than "
                "the limit of %lld (--max-jac-entries)%s\n", a->file,
                mass > c->max_dense ? "mass matrix" : "Jacobian", mass > c->max_dense ? mass : dense,
                c->max_dense, mass > c->max_dense ? "" : ": use --linear sparse");
        return EXIT_USAGE;
    }
    if (!check_mechanism(mech, &c->opt, &rep, diag)) {
        cli_error(a, diag);
        return EXIT_USAGE;
    }
    if (c->json)
        print_json(mech->model, &rep);
    else
        print_text(mech->model, &rep);
    report_failures(a->file, mech->model, &rep);
    return rep.ok ? EXIT_OK : EXIT_ANALYSIS;
}

/* The dense-Jacobian limit is checked here, after loading, where the
   comparisons would form dense matrices: the sparse ones form none. */
static bool finish(Args *a, void *opts)
{
    CheckCli *c = opts;
    c->max_dense = c->limits.max_jac_entries;
    c->limits.max_jac_entries = 0;
    return args_need_file(a);
}

static const CliCommand command = {
    .name = "check", .usage = usage, CLI_OPTIONS(options), .column = 20, .epilogue = epilogue,
    .limits_offset = offsetof(CheckCli, limits),
    .finish = finish, .run = check_file,
};

int cmd_check(int argc, char **argv)
{
    CheckCli c = {.opt = check_default_options(), .limits = mechc_default_limits()};
    c.opt.notes = stderr;
    c.seed = (int)c.opt.seed;
    return cli_main(&command, argc, argv, &c);
}
