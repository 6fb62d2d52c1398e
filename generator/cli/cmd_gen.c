/* cmd_gen.c - mechc gen: writes the generated C (and optionally its header). */
#include "cli.h"

#include "../base/strbuf.h"
#include "../pipeline/pipeline.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: mechc gen FILE.mech [-o OUT.c] [--header OUT.h] [--prefix NAME]\n"
    "                 [--real double|float] [--trig own|libm] [--jac spread|direct]\n"
    "                 [--chunk N] [--stats]\n"
    "\n"
    "Writes straight-line C99 for Phi, Phi_q (dense and sparse), nu, gamma and the\n"
    "fused _all of the mechanism: needs only <math.h>, no heap, no I/O.\n"
    "\n"
    "  -o OUT.c          write the source to OUT.c (default: standard output)\n"
    "  --header OUT.h    also write the interface to OUT.h; the source includes it\n"
    "  --prefix NAME     symbol prefix (default: the mechanism name); macros use\n"
    "                    its upper case\n"
    "  --real TYPE       double (default) or float (float literals, sinf, ...)\n"
    "  --trig own|libm   double kernels: sin and cos of each angle in one call of\n"
    "                    the file's own PREFIX_sincos (own, the default; a table\n"
    "                    and short series, within 2.5 ulp, libm past 2^16 rad)\n"
    "                    or sin and cos of <math.h> as written (libm); float\n"
    "                    kernels always call sinf and cosf\n"
    "  --jac HOW         the dense PREFIX_jac: spread (default) fills it from\n"
    "                    PREFIX_jac_nz, one copy of the Jacobian's expressions;\n"
    "                    direct stores every entry itself, zeros included: more\n"
    "                    code, a faster dense Jacobian (what jit and aot use)\n"
    "  --chunk N         most operations per C function before it is split into\n"
    "                    static parts, counting operations and stores (default 150;\n"
    "                    keeps optimizing compilers fast)\n"
    "  --stats           print to stderr the operation count of each function and\n"
    "                    the time of each stage, including an in-process libtcc\n"
    "                    compile of the kernels (what eval and run do)\n"
    "  --dump rows       print each row as an expression of q[i], qd[i] and t\n"
    "                    (Phi, or Psi for velocity rows) instead of C\n";

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
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "mechc gen: error: cannot write '%s': %s\n", path, strerror(errno));
        return false;
    }
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

int cmd_gen(int argc, char **argv)
{
    Args a;
    args_init(&a, "gen", argc, argv);
    const char *out_path = NULL, *header_path = NULL, *opt_name;
    bool stats = false, dump = false;
    EmitOptions opt = emit_default_options();
    MechLimits limits = mech_default_limits();
    while (!a.failed && (opt_name = args_next(&a))) {
        if (args_is_help(opt_name)) {
            fputs(usage, stdout);
            fputs(args_limits_usage, stdout);
            return EXIT_OK;
        } else if (args_limit(&a, opt_name, &limits)) {
            continue;
        } else if (strcmp(opt_name, "-o") == 0 || strcmp(opt_name, "--output") == 0) {
            out_path = args_value(&a, opt_name);
        } else if (strcmp(opt_name, "--header") == 0) {
            header_path = args_value(&a, opt_name);
        } else if (strcmp(opt_name, "--prefix") == 0) {
            opt.prefix = args_value(&a, opt_name);
        } else if (strcmp(opt_name, "--real") == 0) {
            static const char *const reals[] = {"double", "float", NULL};
            opt.real_float = args_choice(&a, opt_name, reals) == 1;
        } else if (strcmp(opt_name, "--trig") == 0) {
            static const char *const trigs[] = {"own", "libm", NULL};
            opt.libm_trig = args_choice(&a, opt_name, trigs) == 1;
        } else if (strcmp(opt_name, "--jac") == 0) {
            static const char *const jacs[] = {"spread", "direct", NULL};
            opt.direct_jac = args_choice(&a, opt_name, jacs) == 1;
        } else if (strcmp(opt_name, "--chunk") == 0) {
            args_int(&a, opt_name, 50, 1000000, &opt.chunk_nodes);
        } else if (strcmp(opt_name, "--dump") == 0) {
            static const char *const dumps[] = {"rows", NULL};
            dump = args_choice(&a, opt_name, dumps) == 0;
        } else if (strcmp(opt_name, "--stats") == 0) {
            stats = true;
        } else {
            args_unknown(&a, opt_name);
        }
    }
    /* Names that reach the C text are checked before any work. */
    const char *why;
    char buf[256];
    if (opt.prefix && (why = emit_check_prefix(opt.prefix))) {
        fprintf(stderr, "mechc gen: error: --prefix '%s' cannot be used: %s\n",
                shown(opt.prefix, buf, sizeof buf), why);
        return EXIT_USAGE;
    }
    if (header_path) {
        const char *base = strrchr(header_path, '/');
        opt.header_name = base ? base + 1 : header_path;
        if ((why = emit_check_header_name(opt.header_name))) {
            fprintf(stderr, "mechc gen: error: --header '%s' cannot be used: %s\n",
                    shown(header_path, buf, sizeof buf), why);
            return EXIT_USAGE;
        }
    }
    opt.max_ops = limits.max_code_ops;

    Diag diag;
    Mech *mech = cli_load(&a, &limits, &diag);
    if (!mech)
        return EXIT_USAGE;
    if (dump) {
        dump_rows(mech);
        pipeline_free(mech);
        return EXIT_OK;
    }
    opt.source_name = a.file;
    EmitResult res;
    double t0 = pipeline_now();
    if (!emit_mechanism(&mech->kin, &opt, &res, &diag)) {     /* about the file: "FILE: error: ..." */
        diag_print(&diag, stderr);
        pipeline_free(mech);
        return EXIT_USAGE;
    }
    double emit_seconds = pipeline_now() - t0;
    bool ok = true;
    if (header_path)
        ok = write_file(header_path, res.h_text);
    if (ok && out_path)
        ok = write_file(out_path, res.c_text);
    else if (ok)
        fputs(res.c_text, stdout);
    if (stats) {
        fprintf(stderr, "mechc gen: %s: %d coordinates, %d rows (%d holonomic, %d velocity level), "
                "%d Jacobian nonzeros\n", mech->model->name, mech->model->nq, mech->model->nr,
                mech->model->nh, mech->model->nv, mech->kin.nnz);
        fprintf(stderr, "mechc gen: operations after sharing:");
        for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
            fprintf(stderr, " %s %d%s", emit_function_names[f], res.ops[f], f + 1 < EMIT_FUNCTION_COUNT ? "," : "\n");
        fprintf(stderr, "mechc gen: graph %d nodes; load %.3f s, derivatives %.3f s, emission %.3f s\n",
                (int)mech->model->dag.count, mech->load_seconds, mech->diff_seconds, emit_seconds);
        EmitResult jit_src;
        double jit_emit = 0, jit_tcc = 0;
        Jit *jit = pipeline_jit(mech, &jit_src, &jit_emit, &jit_tcc, &diag);
        if (jit)
            fprintf(stderr, "mechc gen: in-process: emission %.3f s + libtcc %.3f s; from the "
                    "file to machine code %.3f s\n", jit_emit, jit_tcc,
                    mech->load_seconds + mech->diff_seconds + jit_emit + jit_tcc);
        else
            fprintf(stderr, "mechc gen: %s\n", diag.message);
        jit_free(jit);
        emit_result_free(&jit_src);
    }
    emit_result_free(&res);
    pipeline_free(mech);
    return ok ? EXIT_OK : EXIT_USAGE;
}
