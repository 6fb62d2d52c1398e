/* cmd_eval.c - mechc eval: Phi, Phi_q, nu and gamma at exactly one given state. */
#include "cli.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

/* What the command line asked for. */
typedef struct EvalCli {
    mechc_limits limits;
    const char *q_text, *qd_text;
    double t;
    int engine;
    bool json;
} EvalCli;

static const char usage[] =
    "usage: mechc eval FILE.mech [--q v,v,...] [--qd v,v,...] [--t T]\n"
    "                  [--engine jit|generic|aot] [--json]\n"
    "\n"
    "Evaluates Phi, Phi_q, nu and gamma at exactly the given state (no assembly);\n"
    "with masses also M and Q (M(q) qdd + Phi_q^T lambda = Q(q, qd, t)); with\n"
    "design parameters also Phi_p (dPhi/dp).\n"
    "\n";

static const CliOption options[] = {
    {"--q", CLI_STRING_AT(EvalCli, q_text), .metavar = "LIST",
     .help = "coordinates, comma-separated in declaration order\n"
             "(default: the file's initial values)"},
    {"--qd", CLI_STRING_AT(EvalCli, qd_text), .metavar = "LIST", .help = "velocities (default: zeros)"},
    {"--t", CLI_REAL_AT(EvalCli, t), .metavar = "T", .help = "time (default 0)"},
    {"--engine", CLI_CHOICE_AT(EvalCli, engine, engine_names), .metavar = "E",
     .help = "jit (default: generated C compiled in memory), generic\n"
             "(no code generation) or aot (system compiler)"},
    {"--json", CLI_FLAG_AT(EvalCli, json), .help = "print JSON: coords, rows, phi, jac, nu, gamma\n(and M, Q with masses)"},
};

static const char *row_level(const Row *row) { return row->velocity ? "velocity" : "position"; }

/* ,\n "KEY": [v0, v1, ...] */
static void json_vector(const char *key, const double *v, int n)
{
    printf(",\n \"%s\": [", key);
    for (int i = 0; i < n; i++) {
        printf(i ? ", " : "");
        json_number(stdout, v[i]);
    }
    printf("]");
}

/* ,\n "KEY": [[row 0], then each row on a line of its own under the first] */
static void json_matrix(const char *key, const double *a, int rows, int cols)
{
    int indent = (int)strlen(key) + 6;     /* under the first row's '[' */
    printf(",\n \"%s\": [", key);
    for (int r = 0; r < rows; r++) {
        printf(r ? ",\n%*s[" : "[", r ? indent : 0, "");
        for (int c = 0; c < cols; c++) {
            printf(c ? ", " : "");
            json_number(stdout, a[(size_t)r * (size_t)cols + (size_t)c]);
        }
        printf("]");
    }
    printf("]");
}

/* "M" and "Q" (a file with masses): after the spec's keys. */
static void print_json_dynamics(const Model *m, const double *M, const double *Q)
{
    json_matrix("M", M, m->nq, m->nq);
    json_vector("Q", Q, m->nq);
}

/* Phi_p of a file with design parameters: dense, and on its structural
   nonzeros (PREFIX_phi_p_nz: values and pattern, nnz of them). */
typedef struct EvalDesign {
    double *phi_p, *nz;
    const JacEntry *pattern;
    int nnz;
} EvalDesign;

/* "design", "p", "phi_p" and "phi_p_nz" {"row", "col", "values"}: after the others. */
static void print_json_design(const Model *m, const EvalDesign *d)
{
    printf(",\n \"design\": ");
    json_string_list(stdout, m->design_names, m->np);
    json_vector("p", m->dag.param_values, m->np);
    json_matrix("phi_p", d->phi_p, m->nh, m->np);
    printf(",\n \"phi_p_nz\": {\"row\": [");
    for (int e = 0; e < d->nnz; e++)
        printf("%s%d", e ? ", " : "", d->pattern[e].row);
    printf("], \"col\": [");
    for (int e = 0; e < d->nnz; e++)
        printf("%s%d", e ? ", " : "", d->pattern[e].col);
    printf("],\n              \"values\": [");
    for (int e = 0; e < d->nnz; e++) {
        printf(e ? ", " : "");
        json_number(stdout, d->nz[e]);
    }
    printf("]}");
}

/* The design and dPhi/dp's nonzero entries row by row. */
static void print_text_design(const Model *m, const double *phi_p)
{
    printf("\nDesign parameters:");
    for (int j = 0; j < m->np; j++)
        printf("%s %s = %.17g", j ? "," : "", m->design_names[j], m->dag.param_values[j]);
    printf("\n\nSensitivity Phi_p (nonzero entries, row by row):\n");
    for (int r = 0; r < m->nh; r++) {
        printf("  %s:", m->rows[r].name);
        int shown = 0;
        for (int j = 0; j < m->np; j++) {
            double v = phi_p[(size_t)r * (size_t)m->np + (size_t)j];
            if (v != 0.0)
                printf("%s d/d%s = %.17g", shown++ ? "," : "", m->design_names[j], v);
        }
        printf("%s\n", shown ? "" : " (all zero)");
    }
}

static void print_json(const Model *m, double t, const double *q, const double *qd, const double *phi,
                       const double *jac, const double *nu, const double *gamma, const double *M,
                       const double *Q, const EvalDesign *design)
{
    printf("{\"coords\": ");
    json_string_list(stdout, m->coord_names, m->nq);
    printf(",\n \"rows\": [");
    for (int r = 0; r < m->nr; r++) {
        printf(r ? ",\n          " : "");
        printf("{\"name\": ");
        json_string(stdout, m->rows[r].name);
        printf(", \"kind\": \"%s\", \"level\": \"%s\", \"joint\": ",
               joint_info[m->rows[r].kind].keyword, row_level(&m->rows[r]));
        json_string(stdout, m->joints[m->rows[r].joint].name);
        printf("}");
    }
    printf("],\n \"t\": ");
    json_number(stdout, t);
    json_vector("q", q, m->nq);
    json_vector("qd", qd, m->nq);
    json_vector("phi", phi, m->nh);
    json_vector("nu", nu, m->nr);
    json_vector("gamma", gamma, m->nr);
    json_matrix("jac", jac, m->nr, m->nq);
    if (M)
        print_json_dynamics(m, M, Q);
    if (design->phi_p)
        print_json_design(m, design);
    printf("}\n");
}

static int name_width(const char *const *names, int n, int min)
{
    int w = min;
    for (int i = 0; i < n; i++)
        if ((int)strlen(names[i]) > w)
            w = (int)strlen(names[i]);
    return w;
}

/* -0 and 0 are the same answer; print one of them. */
static double tidy(double v) { return v == 0.0 ? 0.0 : v; }

/* M's nonzero entries row by row, then Q (a file with masses). */
static void print_text_dynamics(const Model *m, const double *M, const double *Q)
{
    int cw = name_width(m->coord_names, m->nq, 5);
    printf("\nMass matrix M (nonzero entries, row by row):\n");
    for (int r = 0; r < m->nq; r++) {
        printf("  %-*s", cw, m->coord_names[r]);
        int shown = 0;
        for (int c = 0; c < m->nq; c++) {
            double v = M[(size_t)r * (size_t)m->nq + (size_t)c];
            if (v != 0.0) {
                printf("%s %s = %.17g", shown ? "," : "", m->coord_names[c], v);
                shown++;
            }
        }
        printf("%s\n", shown ? "" : " (all zero)");
    }
    printf("\n%-*s  %24s\n", cw, "coord", "Q");
    for (int i = 0; i < m->nq; i++)
        printf("%-*s  %24.17g\n", cw, m->coord_names[i], tidy(Q[i]));
}

static void print_text(const Model *m, double t, const double *q, const double *qd, const double *phi,
                       const double *jac, const double *nu, const double *gamma)
{
    printf("mechanism %s: %d coordinate%s, %d row%s (%d holonomic, %d velocity level)\n",
           m->name, m->nq, m->nq == 1 ? "" : "s", m->nr, m->nr == 1 ? "" : "s", m->nh, m->nv);
    printf("t = %.17g\n\n", t);
    int cw = name_width(m->coord_names, m->nq, 5);
    printf("%-*s  %24s  %24s\n", cw, "coord", "q", "qd");
    for (int i = 0; i < m->nq; i++)
        printf("%-*s  %24.17g  %24.17g\n", cw, m->coord_names[i], tidy(q[i]), tidy(qd[i]));
    int rw = 5;
    for (int r = 0; r < m->nr; r++)
        if ((int)strlen(m->rows[r].name) > rw)
            rw = (int)strlen(m->rows[r].name);
    printf("\n%-*s  %-10s %-8s  %24s  %24s  %24s\n", rw, "row", "kind", "level", "phi", "nu", "gamma");
    for (int r = 0; r < m->nr; r++) {
        char phibuf[32] = "-";
        if (r < m->nh)
            snprintf(phibuf, sizeof phibuf, "%.17g", tidy(phi[r]));
        printf("%-*s  %-10s %-8s  %24s  %24.17g  %24.17g\n", rw, m->rows[r].name,
               joint_info[m->rows[r].kind].keyword, row_level(&m->rows[r]), phibuf, tidy(nu[r]), tidy(gamma[r]));
    }
    printf("\nJacobian Phi_q (nonzero entries, row by row):\n");
    for (int r = 0; r < m->nr; r++) {
        printf("  %-*s", rw, m->rows[r].name);
        int shown = 0;
        for (int c = 0; c < m->nq; c++) {
            double v = jac[(size_t)r * (size_t)m->nq + (size_t)c];
            if (v != 0.0) {
                printf("%s d/d%s = %.17g", shown ? "," : "", m->coord_names[c], v);
                shown++;
            }
        }
        printf("%s\n", shown ? "" : " (all zero)");
    }
}

/* Evaluates every kernel at (q, qd, t) with the engine asked for
   (libmechc's calls) and prints the report; false (reported) when the
   engine does not compile. */
static bool evaluate(const Args *a, const EvalCli *c, mechc_model *model, const double *q,
                     const double *qd)
{
    const Model *m = model->mech->model;
    size_t nq = (size_t)m->nq, nr = (size_t)m->nr;
    mechc_kernels *k = cli_compile(a, model, (EngineKind)c->engine, NULL);
    if (!k)
        return false;
    double *phi = xcalloc((size_t)m->nh + 1, sizeof *phi), *nu = xcalloc(nr, sizeof *nu);
    double *gamma = xcalloc(nr, sizeof *gamma), *jac = xcalloc(nr * nq, sizeof *jac);
    mechc_phi(k, q, c->t, phi);
    mechc_jacobian(k, q, c->t, jac);
    mechc_nu(k, q, c->t, nu);
    mechc_gamma(k, q, qd, c->t, gamma);
    double *M = NULL, *Q = NULL;
    if (mechc_has_dynamics(model)) {
        M = xcalloc(nq * nq, sizeof *M);
        Q = xcalloc(nq, sizeof *Q);
        mechc_mass(k, q, M);
        mechc_force(k, q, qd, c->t, Q);
    }
    EvalDesign design = {0};
    if (mechc_np(model) > 0) {
        const DesignKin *dk = &model->mech->kin.design;
        design.phi_p = xcalloc((size_t)m->nh * (size_t)m->np + 1, sizeof *design.phi_p);
        design.nz = xcalloc((size_t)dk->p_nnz + 1, sizeof *design.nz);
        design.pattern = dk->p_nz, design.nnz = dk->p_nnz;
        mechc_phi_p(k, q, c->t, design.phi_p);
        mechc_phi_p_values(k, q, c->t, design.nz);
    }
    mechc_kernels_free(k);
    if (c->json) {
        print_json(m, c->t, q, qd, phi, jac, nu, gamma, M, Q, &design);
    } else {
        print_text(m, c->t, q, qd, phi, jac, nu, gamma);
        if (M)
            print_text_dynamics(m, M, Q);
        if (design.phi_p)
            print_text_design(m, design.phi_p);
    }
    free(phi), free(nu), free(gamma), free(jac), free(M), free(Q);
    free(design.phi_p), free(design.nz);
    return true;
}

/* The state from --q and --qd (default: the file's q0 and zeros), evaluated. */
static int eval_file(const Args *a, mechc_model *model, void *opts)
{
    const EvalCli *c = opts;
    int nq = mechc_nq(model);
    double *q = xcalloc((size_t)nq, sizeof *q), *qd = xcalloc((size_t)nq, sizeof *qd);
    memcpy(q, mechc_q0(model), (size_t)nq * sizeof *q);
    mechc_qd0(model, qd);
    int status = EXIT_OK;
    if ((c->q_text && !args_vector("eval", "--q", c->q_text, nq, q))
        || (c->qd_text && !args_vector("eval", "--qd", c->qd_text, nq, qd))
        || !evaluate(a, c, model, q, qd))
        status = EXIT_USAGE;
    free(q), free(qd);
    return status;
}

static const CliCommand command = {
    .name = "eval", .usage = usage, CLI_OPTIONS(options), .column = 17,
    .limits_offset = offsetof(EvalCli, limits),
    .run = eval_file,
};

int cmd_eval(int argc, char **argv)
{
    EvalCli c = {.limits = mechc_default_limits(), .engine = ENGINE_JIT};
    return cli_main(&command, argc, argv, &c);
}
