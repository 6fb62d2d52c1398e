/* fuzz_frontend.c - libFuzzer harness over the whole front end.
 *
 * One input is one .mech file. It goes through every stage mechc runs on a
 * file: read limits, lex, parse, resolve, differentiate, emit (the JIT's
 * double C and gen's float C with a header), compile with libtcc, and one
 * evaluation of each generated kernel at the file's initial values: the
 * kinematic ones (phi, jac, jac_nz, nu, gamma, all, all_nz) and, for a
 * file with masses, the dynamics ones (mass, mass_nz, force, eom); then
 * the generic evaluator's (generator/eval) at the same point. Bad input
 * must end in a diagnostic; good input must give C that compiles and
 * kernels that write exactly their outputs.
 *
 * The generated code is not instrumented by the sanitizers (libtcc writes
 * it), so every output array is surrounded by guard words and prefilled
 * with a marker: a write outside the array, or an entry left unwritten, is
 * caught here and reported with abort(). The fused _all, _all_nz and _eom
 * must agree bit for bit with the single kernels, the dense Jacobian and
 * M with their nonzeros, and M must be symmetric. Dense arrays past
 * DENSE_MAX entries are not evaluated, so that one input stays fast.
 *
 * Built with -fsanitize=fuzzer by `make fuzz`; tests/test_fuzz_replay.c
 * includes this file (without libFuzzer) and replays the corpus through
 * fuzz_frontend(), so `make check` runs every saved input.
 */
#include "../../generator/base/arena.h"
#include "../../generator/base/strbuf.h"
#include "../../generator/engine/engine.h"
#include "../../generator/eval/generic.h"
#include "../../generator/pipeline/pipeline.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fuzz_frontend(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The limits the harness runs with: the defaults, with the graph and the
   generated code capped lower so one input stays well under a second
   under the sanitizers (the default caps are tested in test_security.c). */
static MechLimits fuzz_limits(void)
{
    MechLimits limits = mech_default_limits();
    limits.max_nodes = 200000;
    limits.max_code_ops = 200000;
    return limits;
}

static void fuzz_fail(const char *what)
{
    fprintf(stderr, "fuzz_frontend: invariant broken: %s\n", what);
    abort();
}

/* ---- guarded output arrays ---- */

enum { GUARD = 8 };
static const uint64_t guard_bits = 0x7ff4dead0000beefull;   /* a signalling-NaN pattern */
static const uint64_t unset_bits = 0x7ff4cafe0000f00dull;

typedef struct Guarded {
    double *base;           /* GUARD words, n values, GUARD words */
    double *v;
    size_t n;
} Guarded;

static void put_bits(double *d, uint64_t bits) { memcpy(d, &bits, sizeof bits); }
static bool has_bits(const double *d, uint64_t bits) { return memcmp(d, &bits, sizeof bits) == 0; }

static Guarded guarded_new(size_t n)
{
    Guarded g = {.n = n};
    g.base = xmalloc((n + 2 * GUARD) * sizeof *g.base);
    g.v = g.base + GUARD;
    for (size_t i = 0; i < n + 2 * GUARD; i++)
        put_bits(&g.base[i], i < GUARD || i >= GUARD + n ? guard_bits : unset_bits);
    return g;
}

/* Every entry written, nothing written outside. */
static void guarded_check(const Guarded *g, const char *what)
{
    for (size_t i = 0; i < GUARD; i++)
        if (!has_bits(&g->base[i], guard_bits) || !has_bits(&g->v[g->n + i], guard_bits))
            fuzz_fail(what);
    for (size_t i = 0; i < g->n; i++)
        if (has_bits(&g->v[i], unset_bits))
            fuzz_fail(what);
}

static bool same_value(double a, double b)
{
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

/* ---- the stages after a successful load ---- */

/* gen --dump rows: every row printed as an expression. */
static void dump_rows(const Model *m)
{
    StrBuf sb;
    sb_init(&sb);
    for (int r = 0; r < m->nr; r++) {
        sb_clear(&sb);
        dag_format(&m->dag, m->rows[r].expr, m->coord_names, &sb);
    }
    sb_free(&sb);
}

/* gen --real float --header: text only (libtcc gets the double kernels).
   The banner must be one closed comment on the first line. */
static void emit_float(const Mech *mech)
{
    EmitOptions opt = emit_default_options();
    opt.real_float = true;
    opt.header_name = "fuzz.h";
    opt.chunk_nodes = 50;
    opt.source_name = "dir*/x\"y\n.mech";
    opt.max_ops = mech->limits.max_code_ops;
    EmitResult res;
    Diag diag;
    diag_init(&diag, "fuzz.mech", NULL, 0);
    if (!emit_mechanism(&mech->kin, &opt, &res, &diag)) {
        if (!diag.failed)
            fuzz_fail("emission failed without a message");
        return;
    }
    const char *nl = strchr(res.c_text, '\n');
    const char *close = strstr(res.c_text, "*/");
    if (strncmp(res.c_text, "/* ", 3) != 0 || !nl || !close || close + 2 != nl)
        fuzz_fail("the banner is not one comment on the first line");
    emit_result_free(&res);
}

/* Bit for bit the same values (the fused kernels against the single ones). */
static void same_arrays(const Guarded *a, const Guarded *b, const char *what)
{
    for (size_t i = 0; i < a->n; i++)
        if (!same_value(a->v[i], b->v[i]))
            fuzz_fail(what);
}

static void free_guarded(Guarded *const *all, size_t n)
{
    for (size_t i = 0; i < n; i++)
        free(all[i]->base);
}

/* Where one evaluation happens: the file's initial values, made-up speeds. */
typedef struct Point {
    const double *q;
    double *qd;
    double t;
} Point;

/* A dense array with the count entries of a sparse pattern (from the
   model) and zeros elsewhere: checks it against the pattern's values (vals
   has one placeholder entry more when count is 0). */
static void check_spread(const Guarded *dense, size_t cols, const JacEntry *pattern, size_t count,
                         const int *row, const int *col, const Guarded *vals, const char *what)
{
    bool *in = xcalloc(dense->n ? dense->n : 1, sizeof *in);
    for (size_t e = 0; e < count; e++) {
        if (row[e] != pattern[e].row || col[e] != pattern[e].col)
            fuzz_fail(what);
        size_t at = (size_t)row[e] * cols + (size_t)col[e];
        if (!same_value(dense->v[at], vals->v[e]))
            fuzz_fail(what);
        in[at] = true;
    }
    for (size_t i = 0; i < dense->n; i++)
        if (!in[i] && dense->v[i] != 0.0)
            fuzz_fail(what);
    free(in);
}

/* jac, all and eom are dense: an array beyond this many entries is not
   evaluated (a big file from the seeds' generators), to stay fast. */
enum { DENSE_MAX = 1 << 18 };

/* jac (as jac_nz spread out) and _all (as the single kernels). */
static void check_dense(const Mech *mech, const Kernels *k, const Point *at,
                        Guarded *const single[4])
{
    const Model *m = mech->model;
    size_t nq = (size_t)m->nq, nh = (size_t)m->nh, nr = (size_t)m->nr;
    Guarded jac = guarded_new(nr * nq);
    k->jac(at->q, at->t, jac.v);
    guarded_check(&jac, "jac");
    check_spread(&jac, nq, mech->kin.jac, (size_t)mech->kin.nnz, k->jac_row, k->jac_col, single[3],
                 "jac and jac_nz disagree");
    Guarded phi2 = guarded_new(nh), jac2 = guarded_new(nr * nq), nu2 = guarded_new(nr);
    Guarded gamma2 = guarded_new(nr);
    k->all(at->q, at->qd, at->t, phi2.v, jac2.v, nu2.v, gamma2.v);
    Guarded *fused[] = {&phi2, &nu2, &gamma2, &jac2};
    const char *names[] = {"all: phi", "all: nu", "all: gamma", "all: jac"};
    for (int a = 0; a < 4; a++)
        guarded_check(fused[a], names[a]);
    for (int a = 0; a < 3; a++)
        same_arrays(single[a], fused[a], "_all differs from the single kernels");
    same_arrays(&jac, &jac2, "_all differs from the single kernels");
    Guarded *all[] = {&jac, &phi2, &jac2, &nu2, &gamma2};
    free_guarded(all, sizeof all / sizeof *all);
}

/* _all_nz as phi, jac_nz, nu and gamma. */
static void check_all_nz(const Kernels *k, const Point *at, Guarded *const single[4])
{
    Guarded fused[4];       /* phi, nu, gamma, the Jacobian's values (or the placeholder) */
    for (int a = 0; a < 4; a++)
        fused[a] = guarded_new(single[a]->n);
    k->all_nz(at->q, at->qd, at->t, fused[0].v, fused[3].v, fused[1].v, fused[2].v);
    for (int a = 0; a < 4; a++) {
        guarded_check(&fused[a], "all_nz");
        same_arrays(single[a], &fused[a], "_all_nz differs from the single kernels");
        free(fused[a].base);
    }
}

/* mass (as mass_nz spread out, symmetric), force, and _eom as those with
   jac and gamma. */
static void check_dynamics(const Mech *mech, const Kernels *k, const Point *at,
                           const Guarded *gamma)
{
    const Model *m = mech->model;
    const Dynamics *dyn = &mech->kin.dyn;
    size_t nq = (size_t)m->nq, nr = (size_t)m->nr;
    if (!k->mass != !dyn->present)
        fuzz_fail("dynamics kernels without masses, or masses without them");
    if (!k->mass || nq * nq > DENSE_MAX || nr * nq > DENSE_MAX)
        return;
    Guarded mass = guarded_new(nq * nq), vals = guarded_new(dyn->nnz ? (size_t)dyn->nnz : 1);
    Guarded force = guarded_new(nq);
    k->mass(at->q, mass.v);
    guarded_check(&mass, "mass");
    k->mass_nz(at->q, vals.v);
    guarded_check(&vals, "mass_nz");
    check_spread(&mass, nq, dyn->mass, (size_t)dyn->nnz, k->mass_row, k->mass_col, &vals,
                 "mass and mass_nz disagree");
    for (size_t i = 0; i < nq; i++)
        for (size_t j = 0; j < i; j++)
            if (!same_value(mass.v[i * nq + j], mass.v[j * nq + i]))
                fuzz_fail("M is not symmetric");
    k->force(at->q, at->qd, at->t, force.v);
    guarded_check(&force, "force");

    Guarded mass2 = guarded_new(nq * nq), force2 = guarded_new(nq);
    Guarded jac2 = guarded_new(nr * nq), gamma2 = guarded_new(nr), jac = guarded_new(nr * nq);
    k->eom(at->q, at->qd, at->t, mass2.v, force2.v, jac2.v, gamma2.v);
    guarded_check(&mass2, "eom: M");
    guarded_check(&force2, "eom: Q");
    guarded_check(&jac2, "eom: jac");
    guarded_check(&gamma2, "eom: gamma");
    same_arrays(&mass, &mass2, "_eom differs from mass");
    same_arrays(&force, &force2, "_eom differs from force");
    same_arrays(gamma, &gamma2, "_eom differs from gamma");
    if (k->jac) {
        k->jac(at->q, at->t, jac.v);
        same_arrays(&jac, &jac2, "_eom differs from jac");
    }
    Guarded *all[] = {&mass, &vals, &force, &mass2, &force2, &jac2, &gamma2, &jac};
    free_guarded(all, sizeof all / sizeof *all);
}

/* The generic evaluator (instrumented C, unlike the JIT's code) at the
   same point: every entry written, nothing outside. Its values are not
   compared: fuzzed constants make any tolerance meaningless. */
static void run_generic(const Mech *mech, const Point *at)
{
    const Model *m = mech->model;
    const Dynamics *dyn = &mech->kin.dyn;
    size_t nq = (size_t)m->nq, nh = (size_t)m->nh, nr = (size_t)m->nr;
    if (nr * nq > DENSE_MAX || nq * nq > DENSE_MAX)
        return;
    Generic *g = generic_open(m);
    Guarded phi = guarded_new(nh), jac = guarded_new(nr * nq), nu = guarded_new(nr);
    Guarded gamma = guarded_new(nr), mass = guarded_new(nq * nq), force = guarded_new(nq);
    Guarded vals = guarded_new((size_t)dyn->nnz);
    generic_all(g, at->q, at->qd, at->t, phi.v, jac.v, nu.v, gamma.v);
    guarded_check(&phi, "generic: phi");
    guarded_check(&jac, "generic: jac");
    guarded_check(&nu, "generic: nu");
    guarded_check(&gamma, "generic: gamma");
    if (dyn->present) {
        generic_mass(g, at->q, mass.v);
        guarded_check(&mass, "generic: mass");
        generic_force(g, at->q, at->qd, at->t, force.v);
        guarded_check(&force, "generic: force");
        int *row = xmalloc((size_t)(dyn->nnz + 1) * sizeof *row);
        int *col = xmalloc((size_t)(dyn->nnz + 1) * sizeof *col);
        for (int e = 0; e < dyn->nnz; e++)
            row[e] = dyn->mass[e].row, col[e] = dyn->mass[e].col;
        generic_mass_pattern(g, row, col, dyn->nnz);
        generic_mass_nz(g, at->q, vals.v);
        guarded_check(&vals, "generic: mass_nz");
        free(row);
        free(col);
    }
    Guarded *all[] = {&phi, &jac, &nu, &gamma, &mass, &force, &vals};
    free_guarded(all, sizeof all / sizeof *all);
    generic_free(g);
}

static void run_kernels(const Mech *mech, const Kernels *k)
{
    const Model *m = mech->model;
    size_t nq = (size_t)m->nq, nh = (size_t)m->nh, nr = (size_t)m->nr;
    size_t nnz = (size_t)mech->kin.nnz;
    double *qd = xmalloc((nq ? nq : 1) * sizeof *qd);
    for (size_t i = 0; i < nq; i++)
        qd[i] = 0.5 - 0.125 * (double)(i % 7);
    Point at = {m->q0, qd, 0.25};
    Guarded phi = guarded_new(nh), nu = guarded_new(nr), gamma = guarded_new(nr);
    Guarded vals = guarded_new(nnz ? nnz : 1);
    k->phi(at.q, at.t, phi.v);
    guarded_check(&phi, "phi");
    k->jac_nz(at.q, at.t, vals.v);
    guarded_check(&vals, "jac_nz");
    k->nu(at.q, at.t, nu.v);
    guarded_check(&nu, "nu");
    k->gamma(at.q, at.qd, at.t, gamma.v);
    guarded_check(&gamma, "gamma");
    Guarded *single[4] = {&phi, &nu, &gamma, &vals};
    if (k->jac && nr * nq <= DENSE_MAX)
        check_dense(mech, k, &at, single);
    else if (k->jac_row)
        for (size_t e = 0; e < nnz; e++)
            if (k->jac_row[e] != mech->kin.jac[e].row || k->jac_col[e] != mech->kin.jac[e].col)
                fuzz_fail("jac_row/jac_col differ from the model");
    if (k->all_nz)
        check_all_nz(k, &at, single);
    check_dynamics(mech, k, &at, &gamma);
    run_generic(mech, &at);
    free_guarded(single, 4);
    free(qd);
}

int fuzz_frontend(const uint8_t *data, size_t size)
{
    static FILE *sink;
    if (!sink)
        sink = fopen("/dev/null", "w");
    MechLimits limits = fuzz_limits();
    Diag diag;
    Mech *mech = pipeline_load_bytes((const char *)data, size, "fuzz.mech", &limits, &diag);
    if (!mech) {
        if (!diag.failed || !diag.message[0])
            fuzz_fail("bad input without a message");
        if (sink)
            diag_print(&diag, sink);
        return 0;
    }
    dump_rows(mech->model);
    emit_float(mech);
    EmitResult emitted;
    Jit *jit = engine_jit(mech, &emitted, NULL, NULL, &diag);
    if (jit) {
        const Kernels *k = jit_kernels(jit);
        if (k->design_bind)     /* a design file's kernels read the model's design */
            k->design_bind(mech->model->dag.param_values);
        run_kernels(mech, k);
        jit_free(jit);
    } else if (strstr(diag.message, "did not compile")) {
        fputs(diag.message, stderr);
        fuzz_fail("the generated C did not compile");
    } else if (!diag.failed) {
        fuzz_fail("the JIT failed without a message");
    }
    emit_result_free(&emitted);
    pipeline_free(mech);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_frontend(data, size);
}
