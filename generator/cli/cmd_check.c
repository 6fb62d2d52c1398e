/* cmd_check.c - mechc check: derivatives against finite differences, engines against each other. */
#include "cli.h"

#include "../eval/check.h"

#include <limits.h>
#include <math.h>
#include <string.h>

static const char usage[] =
    "usage: mechc check FILE.mech [--samples N] [--seed S] [--tol T] [--tol-engines T]\n"
    "                   [--no-aot] [--json]\n"
    "\n"
    "Compares the generated Jacobian, nu and gamma with finite differences of Phi\n"
    "(and of Psi for velocity-level rows), and the engines (jit, generic, aot when a\n"
    "C compiler exists) with each other, at random states around the configuration\n"
    "assembled at t = 0. Prints the worst error of each comparison and the row where\n"
    "it occurs; exit status 1 when one is above its tolerance, with a guess at the\n"
    "textbook mistake it looks like.\n"
    "\n"
    "  --samples N       states to sample (default 20)\n"
    "  --seed S          seed of the random states (default 1)\n"
    "  --tol T           tolerance against finite differences (default 1e-6)\n"
    "  --tol-engines T   tolerance between engines (default 1e-10)\n"
    "  --no-aot          do not build and compare the aot engine\n"
    "  --json            print JSON: ok, samples, worst[{what, error, row, ...}]\n"
    "\n"
    "Errors are |value - reference| / (1 + |reference|).\n";

static const char *row_name(const Model *m, int row)
{
    return row >= 0 && row < m->nr ? m->rows[row].name : "-";
}

static bool item_ok(const CheckItem *it)
{
    return it->error <= it->tol;
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
            json_string(stdout, m->coord_names[it->col]);
        }
        printf(", \"tol\": ");
        json_number(stdout, it->tol);
        printf(", \"ok\": %s, \"value\": ", item_ok(it) ? "true" : "false");
        json_number(stdout, it->value);
        printf(", \"reference\": ");
        json_number(stdout, it->reference);
        printf(", \"t\": ");
        json_number(stdout, it->t);
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
        if (it->col >= 0 && (int)strlen(m->coord_names[it->col]) > cw)
            cw = (int)strlen(m->coord_names[it->col]);
    }
    printf("     %-17s  %11s  %9s  %-*s  %-*s  %s\n", "what", "worst error", "tolerance", rw, "row",
           cw, "col", "t");
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        const CheckItem *it = &rep->items[w];
        if (!it->checked)
            continue;
        if (w == CHECK_PAIR_FIRST)
            printf("\n");
        printf("%-4s %-17s  %11.3g  %9.3g  %-*s  %-*s  %.6g\n", item_ok(it) ? "ok" : "FAIL", it->what,
               it->error, it->tol, rw, row_name(m, it->row), cw,
               it->col >= 0 ? m->coord_names[it->col] : "-", it->t);
        if (!item_ok(it)) {
            printf("       value %.17g, reference %.17g\n", it->value, it->reference);
            if (it->hint[0])
                printf("       looks like: %s\n", it->hint);
        }
    }
    printf("\n%s\n", rep->ok ? "ok: every comparison is within its tolerance"
                             : "FAILED: see the lines marked FAIL");
}

int cmd_check(int argc, char **argv)
{
    Args a;
    args_init(&a, "check", argc, argv);
    MechLimits limits = mech_default_limits();
    CheckOptions opt = check_default_options();
    bool json = false;
    const char *o;
    while (!a.failed && (o = args_next(&a))) {
        if (args_is_help(o)) {
            fputs(usage, stdout);
            fputs(args_limits_usage, stdout);
            return EXIT_OK;
        } else if (args_limit(&a, o, &limits)) {
            continue;
        } else if (strcmp(o, "--samples") == 0) {
            args_int(&a, o, 1, 1000000, &opt.samples);
        } else if (strcmp(o, "--seed") == 0) {
            int seed = 1;
            if (args_int(&a, o, 0, INT_MAX, &seed))
                opt.seed = (unsigned long)seed;
        } else if (strcmp(o, "--tol") == 0 || strcmp(o, "--tol-engines") == 0) {
            double v;
            if (args_double(&a, o, &v)) {
                if (v <= 0.0) {
                    fprintf(stderr, "mechc check: error: %s needs a positive number\n", o);
                    a.failed = true;
                } else if (strcmp(o, "--tol") == 0) {
                    opt.tol = v;
                } else {
                    opt.tol_engines = v;
                }
            }
        } else if (strcmp(o, "--no-aot") == 0) {
            opt.use_aot = false;
        } else if (strcmp(o, "--json") == 0) {
            json = true;
        } else {
            args_unknown(&a, o);
        }
    }
    Diag diag;
    Mech *mech = cli_load(&a, &limits, &diag);
    if (!mech)
        return EXIT_USAGE;
    CheckReport rep;
    int status = EXIT_OK;
    if (!check_mechanism(mech, &opt, &rep, &diag)) {
        cli_error(&a, &diag);
        status = EXIT_USAGE;
    } else {
        if (json)
            print_json(mech->model, &rep);
        else
            print_text(mech->model, &rep);
        if (!rep.ok) {
            status = EXIT_ANALYSIS;
            for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
                const CheckItem *it = &rep.items[w];
                if (it->checked && !item_ok(it)) {
                    fprintf(stderr, "%s: error: %s of row %s%s%s is off by %.3g (tolerance %.3g) at t = %.17g%s%s\n",
                            a.file, it->what, row_name(mech->model, it->row),
                            it->col >= 0 ? ", column " : "", it->col >= 0 ? mech->model->coord_names[it->col] : "",
                            it->error, it->tol, it->t, it->hint[0] ? ": " : "", it->hint);
                    break;
                }
            }
        }
    }
    pipeline_free(mech);
    return status;
}
