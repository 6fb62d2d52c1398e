/* fuzz_frontend.c - libFuzzer harness over the whole front end.
 *
 * One input is one .mech file. It goes through every stage mechc runs on a
 * file: read limits, lex, parse, resolve, differentiate, emit (the JIT's
 * double C and gen's float C with a header), compile with libtcc, and one
 * evaluation of each generated kernel at the file's initial values. Bad
 * input must end in a diagnostic; good input must give C that compiles and
 * kernels that write exactly their outputs.
 *
 * The generated code is not instrumented by the sanitizers (libtcc writes
 * it), so every output array is surrounded by guard words and prefilled
 * with a marker: a write outside the array, or an entry left unwritten, is
 * caught here and reported with abort(). The fused _all must agree bit for
 * bit with the single kernels, and the dense Jacobian with the sparse one.
 *
 * Built with -fsanitize=fuzzer by `make fuzz`; tests/test_fuzz_replay.c
 * includes this file (without libFuzzer) and replays the corpus through
 * fuzz_frontend(), so `make check` runs every saved input.
 */
#include "../../generator/base/arena.h"
#include "../../generator/base/strbuf.h"
#include "../../generator/engine/engine.h"
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

static void run_kernels(const Mech *mech, const Kernels *k)
{
    const Model *m = mech->model;
    size_t nq = (size_t)m->nq, nh = (size_t)m->nh, nr = (size_t)m->nr;
    size_t nnz = (size_t)mech->kin.nnz;
    double t = 0.25;
    double *q = xmalloc(nq * sizeof *q), *qd = xmalloc(nq * sizeof *qd);
    memcpy(q, m->q0, nq * sizeof *q);
    for (size_t i = 0; i < nq; i++)
        qd[i] = 0.5 - 0.125 * (double)(i % 7);
    Guarded phi = guarded_new(nh), jac = guarded_new(nr * nq), nu = guarded_new(nr);
    Guarded gamma = guarded_new(nr), vals = guarded_new(nnz ? nnz : 1);
    k->phi(q, t, phi.v);
    guarded_check(&phi, "phi");
    k->jac(q, t, jac.v);
    guarded_check(&jac, "jac");
    k->jac_nz(q, t, vals.v);
    guarded_check(&vals, "jac_nz");
    k->nu(q, t, nu.v);
    guarded_check(&nu, "nu");
    k->gamma(q, qd, t, gamma.v);
    guarded_check(&gamma, "gamma");

    /* the dense Jacobian is the sparse one spread out, zeros elsewhere */
    for (size_t e = 0; e < nnz; e++) {
        if (k->jac_row[e] != mech->kin.jac[e].row || k->jac_col[e] != mech->kin.jac[e].col)
            fuzz_fail("jac_row/jac_col differ from the model");
        size_t at = (size_t)k->jac_row[e] * nq + (size_t)k->jac_col[e];
        if (!same_value(jac.v[at], vals.v[e]))
            fuzz_fail("jac and jac_nz disagree");
        put_bits(&jac.v[at], unset_bits);
    }
    for (size_t i = 0; i < nr * nq; i++)
        if (!has_bits(&jac.v[i], unset_bits) && jac.v[i] != 0.0)
            fuzz_fail("jac has a nonzero outside the structure");

    /* _all gives the same bits as the four kernels */
    Guarded phi2 = guarded_new(nh), jac2 = guarded_new(nr * nq), nu2 = guarded_new(nr);
    Guarded gamma2 = guarded_new(nr);
    k->jac(q, t, jac.v);
    k->all(q, qd, t, phi2.v, jac2.v, nu2.v, gamma2.v);
    guarded_check(&phi2, "all: phi");
    guarded_check(&jac2, "all: jac");
    guarded_check(&nu2, "all: nu");
    guarded_check(&gamma2, "all: gamma");
    const Guarded *single[] = {&phi, &jac, &nu, &gamma}, *fused[] = {&phi2, &jac2, &nu2, &gamma2};
    for (int a = 0; a < 4; a++)
        for (size_t i = 0; i < single[a]->n; i++)
            if (!same_value(single[a]->v[i], fused[a]->v[i]))
                fuzz_fail("_all differs from the single kernels");

    Guarded *all[] = {&phi, &jac, &nu, &gamma, &vals, &phi2, &jac2, &nu2, &gamma2};
    for (size_t a = 0; a < sizeof all / sizeof *all; a++)
        free(all[a]->base);
    free(q);
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
        run_kernels(mech, jit_kernels(jit));
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
