/* cmd_gen.c - mechc gen: writes the generated C (and optionally its header). */
#include "cli.h"

#include "../base/strbuf.h"
#include "../pipeline/pipeline.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

/* What the command line asked for. */
typedef struct GenCli {
    EmitOptions emit;
    mechc_limits limits;
    const char *out_path, *header_path;
    int real, trig, jac, dump;      /* indices into the choices below */
    int roll;                       /* rolls[]: EmitRoll's order */
    bool stats;
    int dense_limit;                /* --max-jac-entries, kept here with
                                       --sparse-only (the model then skips it) */
} GenCli;

static const char usage[] =
    "usage: mechc gen FILE.mech [-o OUT.c] [--header OUT.h] [--prefix NAME]\n"
    "                 [--real double|float] [--trig own|libm] [--jac auto|spread|direct]\n"
    "                 [--sparse | --sparse-only] [--roll auto|never|always] [--lu]\n"
    "                 [--batch] [--chunk N] [--stats]\n"
    "\n"
    "Writes straight-line C99 for Phi, Phi_q (dense and sparse), nu, gamma and the\n"
    "fused _all of the mechanism (loops for joints of one shape, --roll): needs\n"
    "only <math.h>, no heap, no I/O.\n"
    "\n";

static const char *const reals[] = {"double", "float", NULL};
static const char *const trigs[] = {"own", "libm", NULL};
static const char *const jacs[] = {"auto", "spread", "direct", NULL};
static const char *const dumps[] = {"rows", NULL};
static const char *const rolls[] = {"auto", "never", "always", NULL};

static const CliOption options[] = {
    {"-o", CLI_STRING_AT(GenCli, out_path), .alias = "--output", .metavar = "OUT.c",
     .help = "write the source to OUT.c (default: standard output)"},
    {"--header", CLI_STRING_AT(GenCli, header_path), .metavar = "OUT.h",
     .help = "also write the interface to OUT.h; the source includes it"},
    {"--prefix", CLI_STRING_AT(GenCli, emit.prefix), .metavar = "NAME",
     .help = "symbol prefix (default: the mechanism name); macros use\n"
             "its upper case"},
    {"--real", CLI_CHOICE_AT(GenCli, real, reals), .metavar = "TYPE",
     .help = "double (default) or float (float literals, sinf, ...)"},
    {"--trig", CLI_CHOICE_AT(GenCli, trig, trigs), .metavar = "own|libm",
     .help = "double kernels: sin and cos of each angle in one call of\n"
             "the file's own PREFIX_sincos (own, the default; a table\n"
             "and short series, within 2.5 ulp, libm past 2^16 rad)\n"
             "or sin and cos of <math.h> as written (libm); float\n"
             "kernels always call sinf and cosf"},
    {"--jac", CLI_CHOICE_AT(GenCli, jac, jacs), .metavar = "HOW",
     .help = "the dense PREFIX_jac: direct stores every entry in place\n"
             "after one zero fill: a second copy of the Jacobian's\n"
             "expressions, the faster dense Jacobian (what jit and aot\n"
             "use); spread fills it from PREFIX_jac_nz, one copy, and\n"
             "moves the values into place; auto (default) is direct\n"
             "unless the copy is large (over 4000 nonzeros, not rolled)"},
    {"--sparse", CLI_FLAG_AT(GenCli, emit.all_nz),
     .help = "also write PREFIX_all_nz: Phi, the Jacobian's nonzeros, nu\n"
             "and gamma in one call (the sparse counterpart of _all,\n"
             "what run's sparse path calls)"},
    {"--sparse-only", CLI_FLAG_AT(GenCli, emit.sparse_only),
     .help = "PREFIX_all_nz, and no dense PREFIX_jac or PREFIX_all\n"
             "(NR*NQ entries): for mechanisms past --max-jac-entries,\n"
             "which binds only dense files; the header defines\n"
             "PREFIX_SPARSE_ONLY 1"},
    {"--roll", CLI_CHOICE_AT(GenCli, roll, rolls), .metavar = "WHEN",
     .help = "joints' rows of one shape (a chain's links) written once,\n"
             "as a loop over tables of their constants and indices:\n"
             "auto (default) for 500 rows or more, groups of 8 joints\n"
             "or more; always (groups of 2 or more); never. The same\n"
             "results to the bit; code size and compile time nearly\n"
             "independent of the number of links"},
    {"--lu", CLI_FLAG_AT(GenCli, emit.lu),
     .help = "also write PREFIX_lu_factor and PREFIX_lu_solve: the\n"
             "Jacobian's LU unrolled for its pattern, constants folded,\n"
             "with run-time pivot checks (square mechanisms without\n"
             "velocity rows, up to 100 coordinates; what run calls;\n"
             "otherwise a note on stderr says why none was written)"},
    {"--batch", CLI_FLAG_AT(GenCli, emit.batch),
     .help = "also write PREFIX_NAME_batch for phi, jac, jac_nz, nu,\n"
             "gamma, all (all_nz): n states a call, PREFIX_LANES at a\n"
             "time in lock-step so that compilers vectorise across\n"
             "the states; the same bits as n single calls"},
    {"--chunk", CLI_INT_AT(GenCli, emit.chunk_nodes, 50, 1000000), .metavar = "N",
     .help = "most operations per C function before it is split into\n"
             "static parts, counting operations and stores (default 150;\n"
             "keeps optimizing compilers fast)"},
    {"--stats", CLI_FLAG_AT(GenCli, stats),
     .help = "print to stderr the operation count of each function and\n"
             "the time of each stage, including an in-process libtcc\n"
             "compile of the kernels (what eval and run do)"},
    {"--dump", CLI_CHOICE_AT(GenCli, dump, dumps), .metavar = "rows",
     .help = "print each row as an expression of q[i], qd[i] and t\n"
             "(Phi, or Psi for velocity rows) instead of C"},
};

/* One row per line: "name level expression"; the input for outside tools
   (bench/sympy_ops.py) that compare against other derivations. */
static void dump_rows(const Mech *mech)
{
    const Model *m = mech->model;
    StrBuf sb;
    sb_init(&sb);
    for (int r = 0; r < m->nr; r++) {
        sb_clear(&sb);
        dag_format(&m->dag, m->rows[r].expr, NULL, &sb);
        printf("%s %s %s\n", m->rows[r].name, m->rows[r].velocity ? "velocity" : "position", sb.data);
    }
    sb_free(&sb);
}

static bool write_file(const char *path, const char *text)
{
    FILE *f = cli_open_output("gen", path);
    if (!f)
        return false;
    fputs(text, f);
    bool ok = fclose(f) == 0;
    if (!ok)
        fprintf(stderr, "mechc gen: error: cannot write '%s'\n", path);
    return ok;
}

/* A user's value inside a one-line message: control bytes shown as '?'. */
static const char *shown(const char *value, char *buf, size_t size)
{
    size_t n = 0;
    for (; value[n] && n + 1 < size; n++)
        buf[n] = (unsigned char)value[n] < 0x20 || value[n] == 0x7f ? '?' : value[n];
    buf[n] = '\0';
    return buf;
}

/* The choices into EmitOptions; the names that reach the C text checked
   before any work: false (reported) when one cannot be used. */
static bool finish(Args *a, void *opts)
{
    GenCli *c = opts;
    (void)a;
    c->emit.real_float = c->real == 1;
    c->emit.libm_trig = c->trig == 1;
    c->emit.direct_jac = c->jac == 2;     /* auto: gen_file, once the size is known */
    c->emit.roll = c->roll;     /* rolls[] is in EmitRoll's order */
    c->emit.max_ops = c->limits.max_code_ops;
    /* The dense Jacobian's size is checked in gen_file, on the whole
       model: past the limit the file is written sparse-only by itself. */
    c->dense_limit = c->limits.max_jac_entries;
    c->limits.max_jac_entries = 0;
    const char *why;
    char buf[256];
    if (c->emit.prefix && (why = emit_check_prefix(c->emit.prefix))) {
        fprintf(stderr, "mechc gen: error: --prefix '%s' cannot be used: %s\n",
                shown(c->emit.prefix, buf, sizeof buf), why);
        return false;
    }
    if (c->header_path) {
        const char *base = strrchr(c->header_path, '/');
        c->emit.header_name = base ? base + 1 : c->header_path;
        if ((why = emit_check_header_name(c->emit.header_name))) {
            fprintf(stderr, "mechc gen: error: --header '%s' cannot be used: %s\n",
                    shown(c->header_path, buf, sizeof buf), why);
            return false;
        }
    }
    return true;
}

/* --stats: sizes, operation counts, stage times, and an in-process compile. */
static void print_stats(Mech *mech, const GenCli *c, const EmitResult *res, double emit_seconds,
                        Diag *diag)
{
    fprintf(stderr, "mechc gen: %s: %d coordinates, %d rows (%d holonomic, %d velocity level), "
            "%d Jacobian nonzeros\n", mech->model->name, mech->model->nq, mech->model->nr,
            mech->model->nh, mech->model->nv, mech->kin.nnz);
    fprintf(stderr, "mechc gen: operations after sharing:");
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
        if (emit_function_present(&mech->kin, (EmitFunction)f)
            && emit_function_written(&c->emit, (EmitFunction)f))
            fprintf(stderr, "%s %s %d", f ? "," : "", emit_function_names[f], res->ops[f]);
    fputc('\n', stderr);
    fprintf(stderr, "mechc gen: graph %d nodes; load %.3f s, derivatives %.3f s, emission %.3f s\n",
            (int)mech->model->dag.count, mech->load_seconds, mech->diff_seconds, emit_seconds);
    EmitResult jit_src;
    double jit_emit = 0, jit_tcc = 0;
    EmitOptions eo = engine_emit_options(mech, ENGINE_JIT);
    eo.roll = c->emit.roll;
    eo.sparse_only = eo.sparse_only || c->emit.sparse_only;
    Jit *jit = engine_jit_compile(mech, &eo, &jit_src, &jit_emit, &jit_tcc, diag);
    if (jit)
        fprintf(stderr, "mechc gen: in-process: emission %.3f s + libtcc %.3f s; from the "
                "file to machine code %.3f s\n", jit_emit, jit_tcc,
                mech->load_seconds + mech->diff_seconds + jit_emit + jit_tcc);
    else
        fprintf(stderr, "mechc gen: %s\n", diag->message);
    jit_free(jit);
    emit_result_free(&jit_src);
}

/* The header, then the source (to stdout without -o); false (reported) on a write error. */
static bool write_outputs(const GenCli *c, const EmitResult *res)
{
    bool ok = true;
    if (c->header_path)
        ok = write_file(c->header_path, res->h_text);
    if (ok && c->out_path)
        ok = write_file(c->out_path, res->c_text);
    else if (ok)
        fputs(res->c_text, stdout);
    return ok;
}

/* --sparse-only on a file with masses: its mass and eom stay dense (M,
   and eom's Jacobian), so the dense limit still binds; false (diag
   filled) past it. */
static bool dynamics_fit(const Mech *mech, int limit, bool sparse_only, Diag *diag)
{
    const Model *m = mech->model;
    long long jac = (long long)m->nr * m->nq, mass = (long long)m->nq * m->nq;
    long long most = jac > mass ? jac : mass;
    if (!mech->kin.dyn.present || limit <= 0 || most <= limit)
        return true;
    diag_error_nopos(diag, "the file has masses, and its _mass and _eom stay dense%s: the "
                     "dense %s would have %d rows x %d coordinates = %lld entries, more than "
                     "the limit of %d (--max-jac-entries)",
                     sparse_only ? " with --sparse-only" : " (also with --sparse-only)",
                     jac >= mass ? "Jacobian" : "mass matrix", jac >= mass ? m->nr : m->nq,
                     m->nq, most, limit);
    return false;
}

/* --real float: false (diag filled) when a constant the functions use
   overflows a float or vanishes in one. */
static bool constants_fit_float(const Mech *mech, Diag *diag)
{
    const Kinematics *kin = &mech->kin;
    const Model *m = mech->model;
    int n = 0, cap = m->nh + 2 * m->nr + kin->nnz + kin->dyn.nnz + m->nq;
    NodeId *roots = xmalloc((size_t)(cap ? cap : 1) * sizeof *roots);
    for (int r = 0; r < m->nh; r++)
        roots[n++] = kin->phi[r];
    for (int r = 0; r < m->nr; r++)
        roots[n++] = kin->nu[r], roots[n++] = kin->gamma[r];
    for (int k = 0; k < kin->nnz; k++)
        roots[n++] = kin->jac[k].value;
    for (int k = 0; kin->dyn.present && k < kin->dyn.nnz; k++)
        roots[n++] = kin->dyn.mass[k].value;
    for (int j = 0; kin->dyn.present && j < m->nq; j++)
        roots[n++] = kin->dyn.force[j];
    bool ok = dag_check_float(&m->dag, roots, n, diag);
    free(roots);
    return ok;
}

/* The generated C (or the rows) for the file. */
static int gen_file(const Args *a, mechc_model *model, void *opts)
{
    Mech *mech = model->mech;
    Diag *diag = &model->diag;     /* the file's: its text for positions */
    GenCli *c = opts;
    if (c->dump == 0) {
        dump_rows(mech);
        return EXIT_OK;
    }
    c->emit.source_name = a->file;
    const Model *m = mech->model;
    bool asked = c->emit.sparse_only;
    if (!c->emit.sparse_only && c->dense_limit > 0
        && (long long)m->nr * m->nq > c->dense_limit && !mech->kin.dyn.present) {
        c->emit.sparse_only = true;
        fprintf(stderr, "%s: note: the dense Jacobian would have %d rows x %d coordinates = "
                "%lld entries, more than the limit of %d (--max-jac-entries): written "
                "--sparse-only (PREFIX_all_nz and the Jacobian's nonzeros, no PREFIX_jac or "
                "PREFIX_all)\n", a->file, m->nr, m->nq, (long long)m->nr * m->nq,
                c->dense_limit);
    }
    if (!dynamics_fit(mech, c->dense_limit, asked, diag)
        || (c->emit.real_float && !constants_fit_float(mech, diag))) {
        diag_print(diag, stderr);
        return EXIT_USAGE;
    }
    if (c->jac == 0)
        c->emit.direct_jac = emit_direct_jac_default(&mech->kin, c->emit.roll);
    EmitResult res;
    double t0 = pipeline_now();
    if (!emit_mechanism(&mech->kin, &c->emit, &res, diag)) {     /* about the file: "FILE: error: ..." */
        diag_print(diag, stderr);
        return EXIT_USAGE;
    }
    double emit_seconds = pipeline_now() - t0;
    if (res.lu_skipped[0])  /* the file is whole without it; a caller of P_lu_factor is not */
        fprintf(stderr, "mechc gen: note: --lu not written: %s\n", res.lu_skipped);
    bool ok = write_outputs(c, &res);
    if (c->stats)
        print_stats(mech, c, &res, emit_seconds, diag);
    emit_result_free(&res);
    return ok ? EXIT_OK : EXIT_USAGE;
}

static const CliCommand command = {
    .name = "gen", .usage = usage, CLI_OPTIONS(options), .column = 20,
    .limits_offset = offsetof(GenCli, limits),
    .finish = finish, .run = gen_file,
};

int cmd_gen(int argc, char **argv)
{
    GenCli c = {.emit = emit_default_options(), .limits = mechc_default_limits(), .dump = -1};
    c.limits.jac_advice = "write the file --sparse-only, without the dense Jacobian";
    return cli_main(&command, argc, argv, &c);
}
