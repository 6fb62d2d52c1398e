/* cmd_info.c - mechc info: coordinates, rows, mobility, rank, redundant rows, singularity, integrability. */
#include "cli.h"

#include "../structure/info.h"
#include "../kin/run.h"
#include "../base/arena.h"
#include "state_csv.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* What the command line asked for. */
typedef struct InfoCli {
    mechc_info_options info;    /* libmechc's analysis (mechc.h) */
    mechc_limits limits;
    double t;
    double at;              /* --at T: NAN when absent */
    const char *state;      /* --state FILE.csv, or NULL */
    int linear;             /* --linear, an AnalysisLinear */
    bool json;
} InfoCli;

static const char usage[] =
    "usage: mechc info FILE.mech [--json] [--rank-tol T] [--t T] [--samples N]\n"
    "                  [--linear dense|sparse|auto] [--max-dense N]\n"
    "                  [--at T] [--state STATE.csv]\n"
    "\n"
    "Reports the coordinates, every row with its joint, kind and level, the rows\n"
    "per joint against the textbook table and the mobility count (coordinates -\n"
    "rows, with and without drivers). Then assembles the mechanism at t = 0 by\n"
    "minimum-norm Newton on its holonomic rows (any number of rows), takes the\n"
    "rank of their Jacobian by SVD or sparse QR, names the redundant rows (a row\n"
    "that depends on the rows before it), tells a singular position from a permanent\n"
    "redundancy, and tests every velocity-level row for integrability\n"
    "(holonomic in disguise, with its position law, or nonholonomic).\n"
    "With --at or --state it reports a given state: the rank drop there against\n"
    "the generic rank (at t = 0, or just before T), the rows that became\n"
    "dependent and the directions the rows leave free (null-space vectors by\n"
    "coordinate), with the rank tolerance there: sqrt(eps) * largest singular\n"
    "value, unless --rank-tol.\n"
    "\n";

static const CliOption options[] = {
    {"--json", CLI_FLAG_AT(InfoCli, json),
     .help = "print JSON (keys: coords, rows, nq, nh, nv, dof, rank,\n"
             "redundant, and more)"},
    {"--rank-tol", CLI_REAL_AT(InfoCli, info.rank_tol), CLI_NONNEGATIVE, .what = "a number >= 0",
     .metavar = "T",
     .help = "singular values above T count toward the rank\n"
             "(default max(rows, coords) * eps * largest singular value)"},
    {"--t", CLI_REAL_AT(InfoCli, t), .metavar = "T",
     .help = "analyse at time T instead of 0 (drivers move with t)"},
    {"--samples", CLI_INT_AT(InfoCli, info.samples, 1, 1000), .metavar = "N",
     .help = "random states for the numerical integrability check (default 8)"},
    {"--linear", CLI_CHOICE_AT(InfoCli, linear, analysis_linear_names), .metavar = "L",
     .help = "rank by dense SVD, or by sparse QR (SuiteSparseQR: the rank,\n"
             "the redundant rows and mobility, no condition number), or\n"
             "auto (default: sparse above " ANALYSIS_DENSE_MAX_NQ_TEXT " coordinates)"},
    {"--max-dense", CLI_REAL_AT(InfoCli, info.max_dense), CLI_NONNEGATIVE, .what = "a number >= 0",
     .metavar = "N",
     .help = "rows x coordinates up to which a dense SVD is allowed\n"
             "(default 500000): auto goes sparse beyond it, dense refuses"},
    {"--at", CLI_REAL_AT(InfoCli, at), .metavar = "T",
     .help = "the state the motion reaches at T: assembled at t = 0 from\n"
             "the file's initial values, then followed to T in 100 steps\n"
             "(minimum-norm Newton, through singular positions); reports\n"
             "the rank drop there, the rows that became dependent and the\n"
             "directions the rows leave free (holonomic rows only: with\n"
             "velocity-level rows use --state)"},
    {"--state", CLI_STRING_AT(InfoCli, state), .metavar = "FILE",
     .help = "the same at a state read from a CSV as run writes it (a\n"
             "header naming t and the coordinates; the row at --at T, or\n"
             "the only row), used as it is"},
};

static const char epilogue[] =
    "\n"
    "Exit status: 0 success, 1 the assembly did not converge or --at could not\n"
    "follow the motion (the report is still printed, at the last iterate), 2 bad\n"
    "usage or bad input (a bad --state file, --linear dense beyond --max-dense).\n";

static const char *level_name(const Row *row) { return row->velocity ? "velocity" : "position"; }

static const char *evidence(const Integrability *it)
{
    return !it->decided ? "undecided" : it->symbolic ? "symbolic" : "numeric";
}

/* ---- JSON ---- */

static void json_names(FILE *out, const char *key, const InfoReport *rep, bool velocity)
{
    const Model *m = rep->model;
    fprintf(out, ",\n \"%s\": [", key);
    int n = 0;
    for (int r = velocity ? m->nh : 0; r < (velocity ? m->nr : m->nh); r++)
        if (rep->rows[r].redundant) {
            fprintf(out, n++ ? ", " : "");
            json_string(out, m->rows[r].name);
        }
    fprintf(out, "]");
}

static void json_int_or_null(FILE *out, const char *key, int v)
{
    if (v >= 0)
        fprintf(out, ",\n \"%s\": %d", key, v);
    else
        fprintf(out, ",\n \"%s\": null", key);
}

static void json_num(FILE *out, const char *key, double v)
{
    fprintf(out, ",\n \"%s\": ", key);
    json_number(out, v);
}

/* "rows": every row with its joint, kind, level and verdicts. */
static void json_rows(FILE *out, const InfoReport *rep)
{
    const Model *m = rep->model;
    fprintf(out, ",\n \"rows\": [");
    for (int r = 0; r < m->nr; r++) {
        const Row *row = &m->rows[r];
        const InfoRow *ir = &rep->rows[r];
        fprintf(out, r ? ",\n   {\"name\": " : "{\"name\": ");
        json_string(out, row->name);
        fprintf(out, ", \"kind\": \"%s\", \"level\": \"%s\", \"joint\": ", joint_info[row->kind].keyword,
               level_name(row));
        json_string(out, m->joints[row->joint].name);
        fprintf(out, ", \"driver\": %s, \"redundant\": %s", ir->driver ? "true" : "false",
               ir->redundant ? "true" : "false");
        if (row->velocity) {
            const Integrability *it = &ir->integ;
            fprintf(out, ", \"integrable\": %s", it->integrable ? "true" : "false");
            if (it->integrable) {
                /* "law" is the law itself or absent: never a sentence */
                if (it->law) {
                    fprintf(out, ", \"law\": ");
                    json_string(out, it->law);
                }
                fprintf(out, ", \"law_found\": %s", it->law ? "true" : "false");
            }
            fprintf(out, ", \"evidence\": \"%s\", \"note\": ", evidence(it));
            json_string(out, it->note ? it->note : "");
        }
        fprintf(out, "}");
    }
    fprintf(out, "]");
}

/* "joints": rows of each joint against the textbook table. */
static void json_joints(FILE *out, const Model *m)
{
    fprintf(out, ",\n \"joints\": [");
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        bool vel;
        int table = info_textbook_rows(jt->kind, &vel);
        fprintf(out, j ? ",\n   {\"name\": " : "{\"name\": ");
        json_string(out, jt->name);
        fprintf(out, ", \"kind\": \"%s\", \"rows\": %d, \"table_rows\": %d}", joint_info[jt->kind].keyword,
               jt->nrows, table);
    }
    fprintf(out, "]");
}

/* A direction's components are rates against its free coordinate (which
   is 1): below TOP_ZERO one is rounding, not motion; two within a
   fraction TOP_TIE of each other are equal (both dimensionless). */
#define TOP_ZERO 1e-12
#define TOP_TIE 1e-9

/* The largest components of a null-space direction, up to `most`, by
   decreasing size (equal to TOP_TIE, as rounding leaves them: coordinate
   order); returns how many are kept. */
static int top_components(const double *v, int nq, int most, int *idx)
{
    int n = 0;
    for (int j = 0; j < nq; j++) {
        if (fabs(v[j]) < TOP_ZERO)
            continue;
        int k;
        if (n < most)
            k = n++;
        else if (fabs(v[j]) * (1 - TOP_TIE) > fabs(v[idx[most - 1]]))
            k = most - 1;           /* the smallest kept gives way */
        else
            continue;
        while (k > 0 && fabs(v[idx[k - 1]]) < fabs(v[j]) * (1 - TOP_TIE)) {
            idx[k] = idx[k - 1];
            k--;
        }
        idx[k] = j;
    }
    return n;
}

enum { TOP_COMPONENTS = 6 };

/* --at / --state: "state" with the drop, the rows that became dependent
   and the null-space directions. */
static void json_state(FILE *out, const InfoReport *rep)
{
    const Model *m = rep->model;
    const InfoState *st = &rep->state;
    fprintf(out, ",\n \"state\": {\"source\": \"%s\"", st->given ? "csv" : "followed");
    if (!st->given)
        fprintf(out, ", \"steps\": %d", st->steps);
    json_num(out, "residual", st->residual);
    json_int_or_null(out, "rank", rep->rank);
    json_int_or_null(out, "generic_rank", st->ref_rank);
    json_int_or_null(out, "drop", st->drop);
    json_num(out, "tol", rep->rank_tol);
    fprintf(out, ",\n   \"dependent\": [");
    for (int k = 0; k < st->ndependent; k++) {
        fprintf(out, k ? ", " : "");
        json_string(out, m->rows[st->dependent[k]].name);
    }
    fprintf(out, "]");
    json_int_or_null(out, "null_dim", st->nnull);
    fprintf(out, ",\n   \"directions\": [");
    for (int k = 0; k < st->nshown; k++) {
        const double *v = st->null + (size_t)k * (size_t)m->nq;
        int idx[TOP_COMPONENTS];
        int n = top_components(v, m->nq, TOP_COMPONENTS, idx);
        fprintf(out, k ? ",\n     {\"free\": " : "{\"free\": ");
        json_string(out, m->coord_names[st->free_coord[k]]);
        fprintf(out, ", \"largest\": {");
        for (int i = 0; i < n; i++) {
            fprintf(out, i ? ", " : "");
            json_string(out, m->coord_names[idx[i]]);
            fprintf(out, ": ");
            json_number(out, v[idx[i]]);
        }
        fprintf(out, "}}");
    }
    fprintf(out, "]}");
}

void info_print_json(FILE *out, const InfoReport *rep)
{
    const Model *m = rep->model;
    fprintf(out, "{\"mechanism\": ");
    json_string(out, m->name);
    fprintf(out, ",\n \"coords\": ");
    json_string_list(out, m->coord_names, m->nq);
    json_rows(out, rep);
    json_joints(out, m);
    fprintf(out, ",\n \"nq\": %d, \"nh\": %d, \"nv\": %d, \"nr\": %d", rep->nq, rep->nh, rep->nv, rep->nr);
    fprintf(out, ",\n \"dof\": %d", rep->dof);
    json_int_or_null(out, "rank", rep->rank);
    json_names(out, "redundant", rep, false);
    fprintf(out, ",\n \"drivers\": %d, \"mobility\": %d", rep->nh_drivers + rep->nv_drivers, rep->mobility);
    if (rep->rank_all >= 0) {
        fprintf(out, ",\n \"dof_rank\": %d, \"mobility_rank\": %d", rep->dof_rank, rep->mobility_rank);
    } else {
        fprintf(out, ",\n \"dof_rank\": null, \"mobility_rank\": null");
    }
    json_int_or_null(out, "rank_all", rep->rank_all);
    json_names(out, "redundant_velocity", rep, true);
    json_int_or_null(out, "generic_rank", rep->generic_rank);
    fprintf(out, ",\n \"dense\": %s", rep->dense ? "true" : "false");
    if (rep->rank >= 0) {
        json_num(out, "rank_tol", rep->rank_tol);
        json_num(out, "sigma_max", rep->sigma_max);
        json_num(out, "sigma_min", rep->sigma_min);
        json_num(out, "cond", rep->cond);        /* null when infinite */
    }
    json_num(out, "t", rep->t);
    fprintf(out, ",\n \"assembled\": %s, \"iterations\": %d", rep->assembled ? "true" : "false",
           rep->assembly.iterations);
    json_num(out, "residual", rep->assembly.residual);
    fprintf(out, ",\n \"q\": [");
    for (int i = 0; i < m->nq; i++) {
        fprintf(out, i ? ", " : "");
        json_number(out, rep->q[i]);
    }
    fprintf(out, "],\n \"system_integrable\": %s",
           !rep->system.tested ? "null" : rep->system.involutive ? "true" : "false");
    fprintf(out, ",\n \"system_note\": ");
    json_string(out, rep->system.note ? rep->system.note : "");
    if (rep->state.asked)
        json_state(out, rep);
    fprintf(out, ",\n \"singularity\": \"%s\"", info_singularity_names[rep->singularity]);
    fprintf(out, ",\n \"singular\": ");
    json_string(out, rep->singular);
    fprintf(out, ",\n \"verdict\": ");
    json_string(out, rep->verdict);
    fprintf(out, "}\n");
}

/* ---- text ---- */

static int width(int n, const char *(*name)(const Model *, int), const Model *m, int min)
{
    int w = min;
    for (int i = 0; i < n; i++)
        if ((int)strlen(name(m, i)) > w)
            w = (int)strlen(name(m, i));
    return w;
}

static const char *coord_name(const Model *m, int i) { return m->coord_names[i]; }
static const char *row_name(const Model *m, int i) { return m->rows[i].name; }
static const char *joint_name(const Model *m, int i) { return m->joints[i].name; }

/* Coordinates, rows, joints and the mobility count. */
static void print_structure(const InfoReport *rep)
{
    const Model *m = rep->model;
    printf("mechanism %s: %d coordinate%s, %d row%s (%d holonomic, %d velocity level)\n\n",
           m->name, m->nq, m->nq == 1 ? "" : "s", m->nr, m->nr == 1 ? "" : "s", m->nh, m->nv);

    int cw = width(m->nq, coord_name, m, 5);
    /* a failed assembly shows its best point, never as assembled */
    printf("coordinates (initial value, %s at t = %g):\n",
           rep->assembled ? "assembled" : "best point found, NOT assembled,", rep->t);
    for (int i = 0; i < m->nq; i++)
        printf("  %-*s  %14.8g  %14.8g\n", cw, m->coord_names[i], m->q0[i], rep->q[i]);

    int rw = width(m->nr, row_name, m, 4), jw = width(m->njoints, joint_name, m, 5);
    printf("\nrows:\n  %-*s  %-*s  %-10s  %-8s\n", rw, "row", jw, "joint", "kind", "level");
    for (int r = 0; r < m->nr; r++) {
        const Row *row = &m->rows[r];
        printf("  %-*s  %-*s  %-10s  %-8s%s%s\n", rw, row->name, jw, m->joints[row->joint].name,
               joint_info[row->kind].keyword, level_name(row),
               rep->rows[r].driver ? "  driver" : "", rep->rows[r].redundant ? "  REDUNDANT" : "");
    }

    printf("\njoints (rows here / rows in the textbook table):\n");
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        bool vel;
        int table = info_textbook_rows(jt->kind, &vel);
        printf("  %-*s  %-10s  %d / %d%s\n", jw, jt->name, joint_info[jt->kind].keyword,
               jt->nrows, table, vel || jt->velocity ? "  velocity level" : "");
    }

    int drivers = rep->nh_drivers + rep->nv_drivers;
    printf("\nmobility by the count:\n");
    printf("  %d coordinates - %d holonomic - %d velocity-level rows = %d DOF\n",
           rep->nq, rep->nh, rep->nv, rep->dof);
    printf("  without the %d driver%s: %d DOF\n", drivers, drivers == 1 ? "" : "s", rep->mobility);
}

/* The Newton assembly at t: converged or not, and how far. */
static void print_assembly(const InfoReport *rep)
{
    const Model *m = rep->model;
    printf("\nassembly at t = %g (minimum-norm Newton on the holonomic rows%s):\n  ", rep->t,
           rep->dense ? "" : ", sparse QR");
    if (rep->nh == 0) {
        printf("nothing to assemble (no holonomic rows)\n");
        return;
    }
    if (rep->state.given) {
        printf("the state read from the CSV, used as it is: residual %.3g\n", rep->state.residual);
        return;
    }
    if (rep->constructed > 0)
        printf("%d of %d coordinates placed by construction (drivers, pins, dyads), then\n  ",
               rep->constructed, m->nq);
    if (rep->state.asked) {
        printf("assembled at t = 0, %s to t = %g in %d steps (the last Newton: %d\n"
               "  iteration%s); the state at t = %g: the cubic through the last four, residual %.3g\n",
               rep->assembled ? "the motion followed" : "the motion NOT FOLLOWED", rep->t,
               rep->state.steps, rep->assembly.iterations,
               rep->assembly.iterations == 1 ? "" : "s", rep->t, rep->assembly.residual);
        return;
    }
    printf("%s after %d iteration%s, residual %.3g%s%s\n",
           rep->assembled ? "converged" : "DID NOT CONVERGE", rep->assembly.iterations,
           rep->assembly.iterations == 1 ? "" : "s", rep->assembly.residual,
           rep->assembly.worst_row >= 0 && !rep->assembled ? ", worst row " : "",
           rep->assembly.worst_row >= 0 && !rep->assembled
               ? m->rows[rep->assembly.worst_row].name : "");
}

/* Rank, singular values, the configuration's verdict and the redundant rows. */
static void print_rank(const InfoReport *rep)
{
    const Model *m = rep->model;
    printf("\nrank (%s at the %s):\n", rep->dense ? "SVD" : "sparse QR",
           rep->assembled ? "assembled configuration" : "best point found, not assembled");
    if (rep->rank < 0) {
        printf("  not computed (%s)\n", rep->dense ? "NaN or Inf in the Jacobian"
                                                   : "NaN or Inf, or too much fill in the sparse QR");
    } else {
        printf("  holonomic rows: rank %d of %d (tolerance %.3g)\n", rep->rank, rep->nh, rep->rank_tol);
        if (rep->nv)
            printf("  all rows:       rank %d of %d\n", rep->rank_all, rep->nr);
        if (rep->nh && rep->dense)
            printf("  singular values: largest %.6g, smallest %.6g, condition number %.6g\n",
                   rep->sigma_max, rep->sigma_min, rep->cond);
        else if (rep->nh)
            printf("  sparse QR (%d x %d is beyond the dense-SVD limit): largest singular value "
                   "%.6g,\n  smallest and condition number not computed\n",
                   rep->nr, rep->nq, rep->sigma_max);
        printf("  configuration: %s\n", rep->singular);
        printf("  redundant rows: ");
        int n = 0;
        for (int r = 0; r < m->nr; r++)
            if (rep->rows[r].redundant)
                printf("%s%s (joint %s)", n++ ? ", " : "", m->rows[r].name,
                       m->joints[m->rows[r].joint].name);
        printf("%s\n", n ? "" : "none");
        printf("  DOF by the rank: %d with drivers, %d without\n", rep->dof_rank, rep->mobility_rank);
    }
}

/* Each velocity-level row's verdict, then the system's. */
static void print_integrability(const InfoReport *rep)
{
    const Model *m = rep->model;
    if (!m->nv)
        return;
    int rw = width(m->nr, row_name, m, 4);
    printf("\nintegrability (each velocity-level row on its own, omega = a^T dq + b dt):\n");
    for (int r = m->nh; r < m->nr; r++) {
        const Integrability *it = &rep->rows[r].integ;
        printf("  %-*s  ", rw, m->rows[r].name);
        if (!it->decided)
            printf("undecided\n");
        else if (it->integrable && it->law)
            printf("integrable (holonomic): %s\n", it->law);
        else if (it->integrable)
            printf("integrable (holonomic); law not found in closed form\n");
        else
            printf("not integrable (nonholonomic)\n");
        printf("  %-*s  %s\n", rw, "", it->note);
    }
    printf("  (the verdicts above are per row, on all of (q, t) space)\n");
    printf("\nvelocity-level rows together with the holonomic rows, drivers left out:\n  %s\n",
           rep->system.note ? rep->system.note : "not tested");
}

/* --at / --state: the drop against the generic rank, the rows that
   became dependent, the directions the rows leave free. */
static void print_state(const InfoReport *rep)
{
    const Model *m = rep->model;
    const InfoState *st = &rep->state;
    if (!st->asked)
        return;
    printf("\nat this state (t = %g, %s; residual %.3g):\n", rep->t,
           st->given ? "read from the CSV" : "the motion followed from t = 0", st->residual);
    if (st->drop < 0) {
        printf("  rank drop not computed\n");
        return;
    }
    printf("  rank %d of the holonomic rows (drivers included) against %d generically\n"
           "  (at t = 0%s): a drop of %d (%s above %.3g count)\n", rep->rank,
           st->ref_rank, st->given ? "" : " or just before", st->drop,
           rep->dense ? "singular values" : "sparse QR pivots", rep->rank_tol);
    printf("  rows that became dependent (%d): ", st->ndependent);
    for (int k = 0; k < st->ndependent; k++)
        printf("%s%s", k ? ", " : "", m->rows[st->dependent[k]].name);
    printf("%s\n", st->ndependent ? "" : "none");
    if (st->nnull <= 0) {
        printf("  directions the rows leave free: %s\n", st->nnull ? "not computed" : "none");
        return;
    }
    printf("  directions the rows leave free (%d; each 1 at its coordinate, 0 at the others'%s):\n",
           st->nnull, st->nnull > st->nshown ? ", the first shown" : "");
    for (int k = 0; k < st->nshown; k++) {
        const double *v = st->null + (size_t)k * (size_t)m->nq;
        int idx[TOP_COMPONENTS];
        int n = top_components(v, m->nq, TOP_COMPONENTS, idx);
        printf("    %s:", m->coord_names[st->free_coord[k]]);
        for (int i = 0; i < n; i++)
            printf(" %s %.4g", m->coord_names[idx[i]], v[idx[i]]);
        printf("\n");
    }
}

static void print_text(const InfoReport *rep)
{
    print_structure(rep);
    print_assembly(rep);
    print_rank(rep);
    print_state(rep);
    print_integrability(rep);
    printf("\nverdict: %s\n", rep->verdict);
}

/* --linear into o; false (reported) when dense is refused: the
   Jacobian beyond --max-dense. */
static bool choose_linear(const InfoCli *c, const Model *m, mechc_info_options *o)
{
    o->linear = analysis_linear_names[c->linear];
    if (c->linear == ANALYSIS_LINEAR_DENSE && (double)m->nr * (double)m->nq > o->max_dense) {
        fprintf(stderr, "mechc info: error: --linear dense: the Jacobian is %d x %d, beyond "
                "--max-dense %.0f (a dense SVD of it would take long): use --linear sparse "
                "or raise --max-dense\n", m->nr, m->nq, o->max_dense);
        return false;
    }
    return true;
}

/* --at and --state into o: the motion followed to T, or a state read
   from the CSV into q (nq), o->t the time of the analysis. false on a bad
   --state (reported). */
static bool choose_state(const InfoCli *c, const Model *m, double *q, mechc_info_options *o)
{
    o->t = isnan(c->at) ? c->t : c->at;
    o->follow = !isnan(c->at) && !c->state;
    if (o->follow && m->nv > 0) {
        fprintf(stderr, "mechc info: error: --at follows the holonomic rows only, and %s has "
                "velocity-level rows, whose positions run integrates: write the motion with "
                "`mechc run FILE --t1 T --csv STATE.csv` and give it with "
                "--state STATE.csv --at T\n",
                m->name);
        return false;
    }
    if (!c->state)
        return true;
    Diag diag;
    if (!state_csv_read(c->state, m, c->at, q, &o->t, &diag)) {
        diag_print(&diag, stderr);
        return false;
    }
    o->q = q;
    return true;
}

/* Exit status 1, said on stderr, when the assembly did not converge or
   the motion could not be followed to t. */
static int assembly_status(const Model *m, const InfoReport *rep, double t, bool follow)
{
    if (rep->assembled)
        return EXIT_OK;
    if (rep->state.asked && follow) {
        fprintf(stderr, "mechc info: error: t = %g: the motion from t = 0 could not be followed "
                "to t = %g (residual %.3g)\n", t, t, rep->assembly.residual);
        return EXIT_ANALYSIS;
    }
    fprintf(stderr, "mechc info: error: t = %g: the assembly did not converge (residual %.3g",
            rep->state.asked ? 0.0 : t, rep->assembly.residual);
    if (rep->assembly.worst_row >= 0)
        fprintf(stderr, ", worst row %s", m->rows[rep->assembly.worst_row].name);
    fprintf(stderr, ")");
    if (rep->loop && rep->loop[0])
        fprintf(stderr, ": %s", rep->loop);
    if (rep->violated && rep->violated[0])
        fprintf(stderr, "; rows left unsatisfied at the best point found: %s", rep->violated);
    fprintf(stderr, "\n");
    return EXIT_ANALYSIS;
}

/* The analysis (mechc_info_with) and its report; exit status 1 when the
   assembly did not converge. */
static int info_file(const Args *a, mechc_model *model, void *opts)
{
    const InfoCli *c = opts;
    const Model *m = model->mech->model;
    mechc_info_options o = c->info;
    double *q = xmalloc(((size_t)m->nq + 1) * sizeof *q);
    if (!choose_linear(c, m, &o) || !choose_state(c, m, q, &o)) {
        free(q);
        return EXIT_USAGE;
    }
    mechc_diag d;
    mechc_info_report *r = mechc_info_with(model, &o, &d);
    free(q);
    if (!r) {
        fprintf(stderr, "mechc %s: error: %s\n", a->command, d.message);
        return EXIT_USAGE;
    }
    const InfoReport *rep = lib_info_report(r);
    if (c->json) {
        char *json = mechc_info_report_json(r);
        fputs(json, stdout);
        mechc_free(json);
    } else {
        print_text(rep);
    }
    int status = assembly_status(m, rep, o.t, o.follow);
    mechc_info_report_free(r);
    return status;
}

/* The rank is dense only up to --max-dense (choose_linear), so the model's
   dense-Jacobian limit binds only --linear dense: auto and sparse load
   chains of 60 003 coordinates (their sparse QR forms no dense matrix). */
static bool finish(Args *a, void *opts)
{
    InfoCli *c = opts;
    if (c->linear != ANALYSIS_LINEAR_DENSE)
        c->limits.max_jac_entries = 0;
    return args_need_file(a);
}

static const CliCommand command = {
    .name = "info", .usage = usage, CLI_OPTIONS(options), .column = 17, .epilogue = epilogue,
    .limits_offset = offsetof(InfoCli, limits),
    .finish = finish, .run = info_file,
};

int cmd_info(int argc, char **argv)
{
    InfoCli c = {.info = mechc_info_defaults(), .limits = mechc_default_limits(),
                 .at = NAN};
    return cli_main(&command, argc, argv, &c);
}
