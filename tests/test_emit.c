/* test_emit.c - the generated C: it compiles cleanly with gcc (a few examples here, every one in
 * tests/firmware_rules.sh), in double and float, with and without a separate header; names from
 * the input cannot break it; the prefix rules; constants as literals; the banner; byte-identical output; the fused
 * kernel's sharing; and the C built by gcc computes what the in-process JIT computes.
 *
 * gcc runs through system() in a mkdtemp directory removed at the end; the
 * compile tests skip (cmocka skip()) when gcc is not installed or under
 * MECHC_SKIP_GCC_ONLY (make check-asan, check-valgrind). Paths
 * are relative to the repository root, where `make check` runs the suites.
 */
#include "testutil.h"

#include "../generator/base/diag.h"
#include "../generator/base/limits.h"
#include "../generator/base/sincos.h"
#include "../generator/emit/emit.h"
#include "../generator/engine/engine.h"
#include "../generator/emit/literal.h"
#include "../generator/pipeline/pipeline.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[256];
static const char *root = ".";     /* the repository root */
static bool have_gcc;

static const char *const CFLAGS = "-std=c99 -Wall -Wextra -Wpedantic -Werror";
static const char *const CFLAGS_FLOAT = "-Wconversion -Wdouble-promotion";

static int group_setup(void **state)
{
    (void)state;
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/mechc_test_emit_XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return -1;
    }
    if (access("examples/four_bar.mech", R_OK) != 0 && access("../examples/four_bar.mech", R_OK) == 0)
        root = "..";
    /* make check-asan and check-valgrind cannot see inside gcc */
    have_gcc = !getenv("MECHC_SKIP_GCC_ONLY") && system("gcc --version > /dev/null 2>&1") == 0;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static void need_gcc(void)
{
    if (!have_gcc) {
        print_message("no gcc, or MECHC_SKIP_GCC_ONLY: skipping the compile checks\n");
        skip();
    }
}

static void write_file(const char *path, const char *text)
{
    FILE *fp = fopen(path, "wb");
    if (!fp)
        fail_msg("cannot write %s", path);
    fputs(text, fp);
    fclose(fp);
}

static char *read_file(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return NULL;
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    size_t got = fread(buf, 1, (size_t)n, fp);
    buf[got] = '\0';
    fclose(fp);
    return buf;
}

/* Compiles dir/file with gcc and extra flags; on failure prints gcc's
   messages and fails the test, naming what was compiled. */
static void gcc_compile(const char *file, const char *flags, const char *what)
{
    char cmd[2048], log[512];
    snprintf(log, sizeof log, "%s/gcc.log", tmpdir);
    snprintf(cmd, sizeof cmd, "cd '%s' && gcc %s %s -c '%s' -o out.o > gcc.log 2>&1",
             tmpdir, CFLAGS, flags, file);
    if (system(cmd) != 0) {
        char *msg = read_file(log);
        fprintf(stderr, "%s\n%.3000s\n", cmd, msg ? msg : "(no log)");
        free(msg);
        fail_msg("generated C for %s does not compile (%s)", what, flags);
    }
}

static Mech *load_path(const char *path, Diag *diag)
{
    MechLimits limits = mech_default_limits();
    Mech *mech = pipeline_load(path, &limits, diag);
    if (!mech) {
        diag_print(diag, stderr);
        fail_msg("%s did not load", path);
    }
    return mech;
}

static Mech *load_text(const char *text, Diag *diag)
{
    MechLimits limits = mech_default_limits();
    Mech *mech = pipeline_load_text(text, "test.mech", &limits, diag);
    if (!mech) {
        diag_print(diag, stderr);
        fail_msg("the test mechanism did not load:\n%s", text);
    }
    return mech;
}

static EmitResult emit(const Mech *mech, const char *prefix, bool real_float, const char *header)
{
    EmitOptions opt = emit_default_options();
    opt.prefix = prefix;
    opt.real_float = real_float;
    opt.header_name = header;
    opt.source_name = mech->model->file;
    EmitResult res;
    Diag diag;
    diag_init(&diag, "emit", NULL, 0);
    if (!emit_mechanism(&mech->kin, &opt, &res, &diag))
        fail_msg("emit_mechanism failed: %s", diag.message);
    assert_non_null(res.c_text);
    assert_non_null(res.h_text);
    return res;
}

/* The four ways a mechanism is written out, each compiled by gcc:
   double and float in one file, double and float as source + header. */
static void compile_all_variants(const Mech *mech, const char *stem)
{
    char c_name[300], h_name[300], path[600];
    for (int fl = 0; fl < 2; fl++) {
        const char *flags = fl ? CFLAGS_FLOAT : "";
        char what[400];
        snprintf(what, sizeof what, "%s (%s)", stem, fl ? "float" : "double");
        /* one file */
        EmitResult res = emit(mech, NULL, fl, NULL);
        snprintf(c_name, sizeof c_name, "%s_%s.c", stem, fl ? "f" : "d");
        snprintf(path, sizeof path, "%s/%s", tmpdir, c_name);
        write_file(path, res.c_text);
        gcc_compile(c_name, flags, what);
        emit_result_free(&res);
        /* source + header: the source includes the header, which it does
           not repeat; a second file can include the header too */
        snprintf(h_name, sizeof h_name, "%s_%s_hdr.h", stem, fl ? "f" : "d");
        res = emit(mech, NULL, fl, h_name);
        snprintf(c_name, sizeof c_name, "%s_%s_hdr.c", stem, fl ? "f" : "d");
        snprintf(path, sizeof path, "%s/%s", tmpdir, c_name);
        write_file(path, res.c_text);
        snprintf(path, sizeof path, "%s/%s", tmpdir, h_name);
        write_file(path, res.h_text);
        char inc[400];
        snprintf(inc, sizeof inc, "#include \"%s\"", h_name);
        if (!strstr(res.c_text, inc))
            fail_msg("%s: the source does not include its header %s", stem, h_name);
        if (strstr(res.c_text, "typedef "))
            fail_msg("%s: the source repeats the interface although it includes the header", stem);
        gcc_compile(c_name, flags, what);
        snprintf(c_name, sizeof c_name, "%s_%s_user.c", stem, fl ? "f" : "d");
        snprintf(path, sizeof path, "%s/%s", tmpdir, c_name);
        char user[1200];
        snprintf(user, sizeof user,
                 "#include \"%s\"\n#include \"%s\"\n"      /* twice: include guard */
                 "int user_count(void);\nint user_count(void) { return (int)sizeof(%s_q0); }\n",
                 h_name, h_name, res.prefix);
        write_file(path, user);
        gcc_compile(c_name, flags, what);
        emit_result_free(&res);
    }
}

/* ---- the four ways compile ---- */

/* On a few examples: every statement, every spatial one, a small planar
   one. tests/firmware_rules.sh compiles every example, with stricter
   flags (source + header, double and float). */
static void test_examples_compile(void **state)
{
    (void)state;
    need_gcc();
    static const char *const stems[] = {"four_bar", "all_statements", "all_spatial"};
    for (size_t i = 0; i < sizeof stems / sizeof *stems; i++) {
        char path[600];
        snprintf(path, sizeof path, "%s/examples/%s.mech", root, stems[i]);
        Diag diag;
        Mech *mech = load_path(path, &diag);
        compile_all_variants(mech, stems[i]);
        pipeline_free(mech);
    }
}

static void test_chain_compiles(void **state)
{
    (void)state;
    need_gcc();
    char cmd[1024], path[600];
    snprintf(path, sizeof path, "%s/chain_20.mech", tmpdir);
    snprintf(cmd, sizeof cmd, "sh '%s/examples/chain.sh' 20 '%s'", root, path);
    assert_int_equal(system(cmd), 0);
    Diag diag;
    Mech *mech = load_path(path, &diag);
    assert_int_equal(mech->model->nq, 123);
    assert_int_equal(mech->model->nr, 123);
    EmitResult res = emit(mech, NULL, false, NULL);
    assert_string_equal(res.prefix, "chain_20");
    assert_true(res.chunks[EMIT_ALL] > 1);      /* long functions were split */
    emit_result_free(&res);
    compile_all_variants(mech, "chain_20");
    pipeline_free(mech);
}

/* ---- the banner ---- */

static void test_banner(void **state)
{
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/examples/four_bar.mech", root);
    Diag diag;
    Mech *mech = load_path(path, &diag);
    EmitResult res = emit(mech, "fb", false, NULL);
    const char *texts[2] = {res.c_text, res.h_text};
    for (int i = 0; i < 2; i++) {
        const char *nl = strchr(texts[i], '\n');
        assert_non_null(nl);
        char first[512];
        snprintf(first, sizeof first, "%.*s", (int)(nl - texts[i]), texts[i]);
        if (strncmp(first, "/*", 2) != 0 || !strstr(first, "DO NOT EDIT")
            || !strstr(first, "four_bar.mech") || strstr(first, "examples/"))
            fail_msg("first line of the %s: '%s'", i ? "header" : "source", first);
    }
    /* the interface of spec section 4 */
    const char *expect[] = {
        "typedef double fb_real;", "#define FB_NQ   9", "#define FB_NH   9", "#define FB_NV   0",
        "#define FB_NR   (FB_NH + FB_NV)", "#define FB_NNZ  25",
        "void fb_phi(const fb_real *q, fb_real t, fb_real *phi);",
        "void fb_gamma(const fb_real *q, const fb_real *qd, fb_real t, fb_real *gamma);",
        "extern const int fb_jac_row[FB_NNZ], fb_jac_col[FB_NNZ];",
        "extern const fb_real fb_q0[FB_NQ];", "#include <math.h>", "\"crank.phi\"", "\"drive\"",
    };
    for (size_t i = 0; i < sizeof expect / sizeof *expect; i++)
        if (!strstr(res.c_text, expect[i]))
            fail_msg("the source lacks '%s'", expect[i]);
    /* no heap, no I/O */
    assert_null(strstr(res.c_text, "malloc"));
    assert_null(strstr(res.c_text, "stdio"));
    emit_result_free(&res);
    /* the JIT's variant declares libm instead of including it */
    EmitOptions opt = emit_default_options();
    opt.prefix = "fb";
    opt.declare_math = true;
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &diag));
    assert_null(strstr(res.c_text, "#include"));
    assert_non_null(strstr(res.c_text, "double sin(double);"));
    emit_result_free(&res);
    /* float: float type, float functions, float literals */
    res = emit(mech, "fb", true, NULL);
    assert_non_null(strstr(res.c_text, "typedef float fb_real;"));
    assert_non_null(strstr(res.c_text, "sinf("));
    assert_null(strstr(res.c_text, " sin("));
    assert_non_null(strstr(res.c_text, "1.8438f"));
    emit_result_free(&res);
    pipeline_free(mech);
}

/* ---- names from the input ---- */

/* Body, point, coord and joint names that are C keywords or the names of
   the generated code's own parameters and temporaries. */
static const char keyword_text[] =
    "mechanism int\n"
    "body qd x = 0.5 y = 0 phi = 0\n"
    "body jac x = 1.5 y = 0 phi = 0\n"
    "point u0 x = 2 y = 0\n"
    "point main x = 2 y = 0\n"
    "coord double = 0.3\n"
    "body gamma x = 1 y = 1 phi = 0\n"
    "body q x = 1 y = 1 phi = 0\n"
    "revolute int: ground qd(-0.5, 0)\n"
    "revolute phi: qd(0.5, 0) jac(-0.5, 0)\n"
    "distance nu: jac(0.5, 0) u0 length = 1\n"
    "revolute vals: u0 main\n"
    "constraint return: double = jac.phi*2\n"
    "weld all: ground gamma angle = 0.5\n"
    "prismatic static: gamma q axis(1, 1)\n"
    "velocity t0: der(double) = 1\n"
    "driver while: der(q.phi) = main.x\n";

static void test_keyword_names(void **state)
{
    (void)state;
    Diag diag;
    Mech *mech = load_text(keyword_text, &diag);
    EmitResult res = emit(mech, NULL, false, NULL);
    /* the mechanism name `int` is not usable as it stands */
    assert_null(emit_check_prefix(res.prefix));
    assert_string_not_equal(res.prefix, "int");
    assert_string_equal(res.prefix, "m_int");
    /* names reach the text only inside string literals */
    assert_non_null(strstr(res.c_text, "\"double\""));
    assert_non_null(strstr(res.c_text, "\"return\""));
    assert_non_null(strstr(res.c_text, "\"qd.phi\""));
    emit_result_free(&res);
    if (have_gcc)
        compile_all_variants(mech, "keywords");
    pipeline_free(mech);
    /* a reserved-looking mechanism name */
    mech = load_text("mechanism __x\npoint m x = 1\nconstraint c: m.x = 1\n", &diag);
    res = emit(mech, NULL, false, NULL);
    assert_null(emit_check_prefix(res.prefix));
    assert_true(strncmp(res.prefix, "__", 2) != 0);
    assert_non_null(strstr(res.prefix, "x"));
    emit_result_free(&res);
    if (have_gcc)
        compile_all_variants(mech, "underscore");
    pipeline_free(mech);
    if (!have_gcc)
        skip();
}

static void test_check_prefix(void **state)
{
    (void)state;
    const char *bad[] = {"1abc", "a-b", "int", "__x", "", "double", "_X", "a b", "a.b", "é",
                         "mechrt", "MECHRT", "mechrtf", "mechrt_x", "Mechrtf_y",
                         "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
        if (emit_check_prefix(bad[i]) == NULL)
            fail_msg("emit_check_prefix accepted '%s'", bad[i]);
    const char *good[] = {"fb", "_x", "four_bar2", "A", "mech_1", "mechrtx", "mechrt2"};
    for (size_t i = 0; i < sizeof good / sizeof *good; i++)
        if (emit_check_prefix(good[i]) != NULL)
            fail_msg("emit_check_prefix rejected '%s': %s", good[i], emit_check_prefix(good[i]));
    assert_non_null(strstr(emit_check_prefix("int"), "keyword"));
    /* emit_mechanism refuses a bad --prefix with a message, and writes nothing */
    Diag diag;
    Mech *mech = load_text("point m x = 1\nconstraint c: m.x = 1\n", &diag);
    EmitOptions opt = emit_default_options();
    opt.prefix = "1bad";
    EmitResult res;
    Diag ed;
    diag_init(&ed, "emit", NULL, 0);
    assert_false(emit_mechanism(&mech->kin, &opt, &res, &ed));
    assert_true(ed.failed);
    assert_non_null(strstr(ed.message, "1bad"));
    assert_null(res.c_text);
    pipeline_free(mech);
}

/* ---- determinism ---- */

static void test_deterministic(void **state)
{
    (void)state;
    const char *files[] = {"four_bar", "all_statements", "knife_cart"};
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
        char path[600];
        snprintf(path, sizeof path, "%s/examples/%s.mech", root, files[i]);
        Diag d1, d2;
        Mech *m1 = load_path(path, &d1);
        Mech *m2 = load_path(path, &d2);
        for (int fl = 0; fl < 2; fl++) {
            EmitResult a = emit(m1, NULL, fl, NULL), b = emit(m2, NULL, fl, NULL);
            EmitResult c = emit(m1, NULL, fl, NULL);    /* the same Mech again */
            assert_string_equal(a.c_text, b.c_text);
            assert_string_equal(a.h_text, b.h_text);
            assert_string_equal(a.c_text, c.c_text);
            assert_memory_equal(a.ops, b.ops, sizeof a.ops);
            emit_result_free(&a);
            emit_result_free(&b);
            emit_result_free(&c);
        }
        pipeline_free(m1);
        pipeline_free(m2);
    }
}

/* ---- the fused kernel shares work ---- */

static void test_op_counts(void **state)
{
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/examples/four_bar.mech", root);
    Diag diag;
    Mech *mech = load_path(path, &diag);
    EmitResult res = emit(mech, NULL, false, NULL);
    int *ops = res.ops;
    int separate = ops[EMIT_PHI] + ops[EMIT_JAC] + ops[EMIT_NU] + ops[EMIT_GAMMA];
    print_message("four_bar ops: phi %d, jac %d, nu %d, gamma %d, all %d\n", ops[EMIT_PHI],
                  ops[EMIT_JAC], ops[EMIT_NU], ops[EMIT_GAMMA], ops[EMIT_ALL]);
    assert_true(ops[EMIT_PHI] > 0 && ops[EMIT_JAC] > 0 && ops[EMIT_GAMMA] > 0);
    assert_true(ops[EMIT_ALL] < separate);
    /* all does at least the work of its largest part */
    assert_true(ops[EMIT_ALL] >= ops[EMIT_PHI] && ops[EMIT_ALL] >= ops[EMIT_GAMMA]);
    assert_int_equal(ops[EMIT_JAC], ops[EMIT_JAC_NZ]);
    emit_result_free(&res);
    pipeline_free(mech);
}

/* ---- gcc's build computes what the JIT computes ---- */

/* A high-entropy state for up to 24 coordinates, shared by the C driver
   (as text) and the test (as numbers). */
#define QV "0.7371, 0.4123, 1.1391, 1.5347, -0.2861, -0.6143, 0.9127, 2.1089, " \
           "-1.3171, 0.3319, 0.5813, -0.2749, 1.0637, -0.8821, 0.1543, 0.6607, " \
           "-0.4411, 1.7213, 0.2297, -1.0913, 0.8389, 0.0731, -0.3467, 1.2953"
#define QDV "0.5813, -0.2749, 1.3171, -0.7433, 0.9127, 2.1089, -0.6607, 0.3319, " \
            "1.0637, -1.2211, 0.4411, 0.8821, -0.1543, 0.7213, -0.9913, 0.2297, " \
            "0.6389, -0.5731, 1.4467, 0.0953, -0.8123, 0.3371, 0.1249, -1.1767"
enum { MAXQ = 24 };

static void parse_list(const char *text, double *out)
{
    char *end;
    for (int i = 0; i < MAXQ; i++) {
        out[i] = strtod(text, &end);
        text = end + 1;     /* past the comma */
    }
}

static const char driver_c[] =
    "#include <stdio.h>\n"
    "#include \"fb.h\"\n"
    "int main(void)\n"
    "{\n"
    "    static const double qv[] = {" QV "};\n"
    "    static const double qdv[] = {" QDV "};\n"
    "    fb_real q[FB_NQ], qd[FB_NQ], phi[FB_NR + 1], jac[FB_NR * FB_NQ], nu[FB_NR], gamma[FB_NR];\n"
    "    fb_real t = (fb_real)0.3217;\n"
    "    for (int i = 0; i < FB_NQ; i++) { q[i] = (fb_real)qv[i]; qd[i] = (fb_real)qdv[i]; }\n"
    "    fb_phi(q, t, phi);\n"
    "    fb_jac(q, t, jac);\n"
    "    fb_nu(q, t, nu);\n"
    "    fb_gamma(q, qd, t, gamma);\n"
    "    for (int i = 0; i < FB_NH; i++) printf(\"%.17g\\n\", (double)phi[i]);\n"
    "    for (int i = 0; i < FB_NR * FB_NQ; i++) printf(\"%.17g\\n\", (double)jac[i]);\n"
    "    for (int i = 0; i < FB_NR; i++) printf(\"%.17g\\n\", (double)nu[i]);\n"
    "    for (int i = 0; i < FB_NR; i++) printf(\"%.17g\\n\", (double)gamma[i]);\n"
    "    /* the fused kernel's Jacobian, zero-filled by itself, equals jac's */\n"
    "    fb_real phi2[FB_NR + 1], jac2[FB_NR * FB_NQ], nu2[FB_NR], gamma2[FB_NR];\n"
    "    for (int i = 0; i < FB_NR * FB_NQ; i++) jac2[i] = (fb_real)7;\n"
    "    fb_all(q, qd, t, phi2, jac2, nu2, gamma2);\n"
    "    for (int i = 0; i < FB_NR * FB_NQ; i++)\n"
    "        if (jac2[i] != jac[i]) { fprintf(stderr, \"fb_all: jac[%d] differs\\n\", i); return 3; }\n"
    "    return 0;\n"
    "}\n";

static void compare_with_jit(const char *stem, bool real_float, int chunk, bool libm_trig)
{
    char path[600];
    snprintf(path, sizeof path, "%s/examples/%s.mech", root, stem);
    Diag diag;
    Mech *mech = load_path(path, &diag);
    const Model *m = mech->model;
    assert_true(m->nq <= MAXQ);
    /* gcc's build */
    EmitOptions opt = emit_default_options();
    opt.prefix = "fb";
    opt.real_float = real_float;
    opt.header_name = "fb.h";
    opt.chunk_nodes = chunk;
    opt.libm_trig = libm_trig;
    EmitResult res;
    Diag ed;
    diag_init(&ed, "emit", NULL, 0);
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &ed));
    char file[700], cmd[2048];
    snprintf(file, sizeof file, "%s/fb.c", tmpdir);
    write_file(file, res.c_text);
    snprintf(file, sizeof file, "%s/fb.h", tmpdir);
    write_file(file, res.h_text);
    snprintf(file, sizeof file, "%s/driver.c", tmpdir);
    write_file(file, driver_c);
    emit_result_free(&res);
    snprintf(cmd, sizeof cmd,
             "cd '%s' && gcc %s -O2 fb.c driver.c -o driver -lm > gcc.log 2>&1 && ./driver > out.txt 2>> gcc.log",
             tmpdir, CFLAGS);
    if (system(cmd) != 0) {
        snprintf(file, sizeof file, "%s/gcc.log", tmpdir);
        char *log = read_file(file);
        fprintf(stderr, "%.3000s\n", log ? log : "");
        free(log);
        fail_msg("%s: the gcc build of the generated C failed, or its fb_all disagreed with fb_jac", stem);
    }
    /* the JIT's values at the same state */
    Jit *jit = engine_jit(mech, &res, NULL, NULL, &diag);
    assert_non_null(jit);
    const Kernels *k = jit_kernels(jit);
    double q[MAXQ], qd[MAXQ];
    parse_list(QV, q);
    parse_list(QDV, qd);
    double t = 0.3217;
    int nq = m->nq, nh = m->nh, nr = m->nr;
    int total = nh + nr * nq + 2 * nr;
    double *want = calloc((size_t)total, sizeof *want);
    k->phi(q, t, want);
    k->jac(q, t, want + nh);
    k->nu(q, t, want + nh + nr * nq);
    k->gamma(q, qd, t, want + nh + nr * nq + nr);
    if (real_float) {   /* the float build sees the state rounded to float */
        for (int i = 0; i < MAXQ; i++) {
            q[i] = (float)q[i];
            qd[i] = (float)qd[i];
        }
    }
    snprintf(file, sizeof file, "%s/out.txt", tmpdir);
    FILE *fp = fopen(file, "r");
    assert_non_null(fp);
    double scale = 0;
    for (int i = 0; i < total; i++)
        scale = fmax(scale, fabs(want[i]));
    for (int i = 0; i < total; i++) {
        double got;
        if (fscanf(fp, "%lf", &got) != 1)
            fail_msg("%s: the gcc build printed %d values, expected %d", stem, i, total);
        double tol = real_float ? 2e-5 * scale : 1e-13 * fmax(1.0, fabs(want[i]));
        if (!(fabs(got - want[i]) <= tol))
            fail_msg("%s (%s): value %d = %.17g from gcc, %.17g from the JIT", stem,
                     real_float ? "float" : "double", i, got, want[i]);
    }
    double extra;
    assert_int_equal(fscanf(fp, "%lf", &extra), EOF);
    fclose(fp);
    free(want);
    jit_free(jit);
    emit_result_free(&res);
    pipeline_free(mech);
}

static void test_gcc_build_matches_jit(void **state)
{
    (void)state;
    need_gcc();
    compare_with_jit("four_bar", false, 0, false);
    compare_with_jit("four_bar", false, 8, false);  /* split into many parts */
    compare_with_jit("four_bar", true, 0, false);
    compare_with_jit("four_bar", false, 0, true);   /* libm's sin and cos */
    compare_with_jit("all_statements", false, 0, false);
    compare_with_jit("skate_velocity", false, 0, false);
    compare_with_jit("all_statements", true, 30, false);
}

/* ---- trigonometry: the file's own sincos, or libm's ---- */

static void test_trig_choices(void **state)
{
    (void)state;
    Diag diag;
    char path[600];
    snprintf(path, sizeof path, "%s/examples/four_bar.mech", root);
    Mech *mech = load_path(path, &diag);
    EmitResult res = emit(mech, "fb", false, NULL);
    assert_non_null(strstr(res.c_text, "static const double fb_sincos_table[320]"));
    assert_non_null(strstr(res.c_text, "FB_TRIG void fb_sincos(double x, double *s, double *c)"));
    /* three angles: a pair through the two-angle function, then the third */
    const char *gamma = strstr(res.c_text, "void fb_gamma(const fb_real *q, const fb_real *qd, "
                                           "fb_real t, fb_real *gamma)\n{");
    assert_non_null(gamma);
    const char *end = strstr(gamma, "\n}\n");
    const char *pair = strstr(gamma, "fb_sincos2(q[2], q[5], &u");
    const char *lone = strstr(gamma, "fb_sincos(q[8], &");
    assert_true(pair && lone && pair < lone && lone < end);
    const char *after = strstr(lone + 1, "fb_sincos");
    assert_true(after == NULL || after > end);
    assert_null(strstr(res.c_text, " sin(q"));
    emit_result_free(&res);

    EmitOptions opt = emit_default_options();
    opt.prefix = "fb";
    opt.declare_math = true;    /* as for the JIT: the tool's own functions */
    Diag ed;
    diag_init(&ed, "emit", NULL, 0);
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &ed));
    assert_non_null(strstr(res.c_text, "mechc_sincos2(q[2], q[5], &"));
    assert_non_null(strstr(res.c_text, "mechc_sincos(q[8], &"));
    emit_result_free(&res);

    opt.declare_math = false;
    opt.libm_trig = true;
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &ed));
    assert_null(strstr(res.c_text, "sincos"));
    assert_non_null(strstr(res.c_text, "= sin(q[2])"));
    assert_non_null(strstr(res.c_text, "= cos(q[2])"));
    emit_result_free(&res);

    res = emit(mech, "fb", true, NULL);      /* float: the C library's sinf, cosf */
    assert_null(strstr(res.c_text, "sincos"));
    assert_non_null(strstr(res.c_text, "sinf(q[2])"));
    emit_result_free(&res);
    pipeline_free(mech);

    /* no angle, no helper (an unused static function would not build with -Werror) */
    mech = load_text("point m x = 3 y = 1\nconstraint line: m.x - 3 = 0\ndriver d: m.y = t\n", &diag);
    res = emit(mech, "pl", false, NULL);
    assert_null(strstr(res.c_text, "sincos"));
    emit_result_free(&res);
    pipeline_free(mech);
}

/* A sin or cos whose partner no code of the function needs: written files
   call the pair through P_sincos_s / P_sincos_c / P_sincos2_some, macros
   that are the pair where optimising (the same bits) and libm's functions
   of the values used elsewhere; the JIT still calls the tool's pair. */
static void test_trig_single(void **state)
{
    (void)state;
    Diag diag;
    Mech *mech = load_text("point m x = 3 y = 1\nconstraint line: m.x - 3 = 0\n"
                           "driver d: m.y = sin(t)\n", &diag);
    EmitResult res = emit(mech, "pl", false, NULL);
    const char *phi = strstr(res.c_text, "void pl_phi(const pl_real *q, pl_real t, "
                                         "pl_real *phi)\n{");
    const char *nu = strstr(res.c_text, "void pl_nu(const pl_real *q, pl_real t, pl_real *nu)\n{");
    assert_true(phi && nu);
    assert_non_null(strstr(phi, "    pl_real u0, w0;\n    pl_sincos_s(t, &u0, &w0);\n"
                                "    phi[0] = q[0] - 3.0;\n    phi[1] = q[1] - u0;\n}\n"));
    assert_non_null(strstr(nu, "    pl_real w0, u0;\n    pl_sincos_c(t, &w0, &u0);\n"));
    assert_non_null(strstr(res.c_text, "pl_sincos(t, &u0, &u1);"));    /* all: both */
    const char *opt = strstr(res.c_text, "#define pl_sincos_s(x, s, c) pl_sincos(x, s, c)\n"
                                         "#define pl_sincos_c(x, s, c) pl_sincos(x, s, c)\n");
    const char *libm = strstr(res.c_text,
                              "#define pl_sincos_s(x, s, c) ((void)(c), (void)(*(s) = sin(x)))\n"
                              "#define pl_sincos_c(x, s, c) ((void)(s), (void)(*(c) = cos(x)))\n");
    assert_true(opt && libm && opt < libm);
    emit_result_free(&res);
    pipeline_free(mech);

    /* two angles in one call: the values used as a mask, 2 cos 2t and 4 sin t */
    mech = load_text("point m x = 3 y = 1\nconstraint line: m.x - 3 = 0\n"
                     "driver d: m.y = sin(t) + cos(2*t)\n", &diag);
    res = emit(mech, "pl", false, NULL);
    phi = strstr(res.c_text, "void pl_phi(const pl_real *q, pl_real t, pl_real *phi)\n{");
    assert_non_null(phi);
    assert_non_null(strstr(phi, "    pl_sincos2_some(2.0 * t, t, &w0, &u0, &u1, &w1, 6);\n"));
    opt = strstr(res.c_text, "#define pl_sincos2_some(x0, x1, s0, c0, s1, c1, used) "
                             "pl_sincos2(x0, x1, s0, c0, s1, c1)\n");
    libm = strstr(res.c_text, "#define pl_sincos2_some(x0, x1, s0, c0, s1, c1, used) \\\n"
                              "    ((void)((used) & 1 ? *(s0) = sin(x0) : 0), \\\n"
                              "     (void)((used) & 2 ? *(c0) = cos(x0) : 0), \\\n"
                              "     (void)((used) & 4 ? *(s1) = sin(x1) : 0), \\\n"
                              "     (void)((used) & 8 ? *(c1) = cos(x1) : 0))\n#endif\n");
    assert_true(opt && libm && opt < libm);
    emit_result_free(&res);

    EmitOptions opt_jit = emit_default_options();
    opt_jit.prefix = "pl";
    opt_jit.declare_math = true;    /* the JIT: the tool's pair, as before */
    Diag ed;
    diag_init(&ed, "emit", NULL, 0);
    assert_true(emit_mechanism(&mech->kin, &opt_jit, &res, &ed));
    assert_non_null(strstr(res.c_text, "mechc_sincos2(2.0 * t, t, &w0, &u0, &u1, &w1);"));
    assert_null(strstr(res.c_text, "_some"));
    emit_result_free(&res);

    /* four-bar: every angle's sin and cos used together, no single form */
    pipeline_free(mech);
    char path[600];
    snprintf(path, sizeof path, "%s/examples/four_bar.mech", root);
    mech = load_path(path, &diag);
    res = emit(mech, "fb", false, NULL);
    assert_null(strstr(res.c_text, "fb_sincos_s"));
    assert_null(strstr(res.c_text, "fb_sincos_c"));
    emit_result_free(&res);
    pipeline_free(mech);
}

/* Error of v against the long double reference, in units in the last place
   of the double nearest the reference. */
static double ulps(double v, long double ref)
{
    double r = fabs((double)ref);
    return (double)fabsl((long double)v - ref) / (nextafter(r, INFINITY) - r);
}

static void test_sincos_accuracy(void **state)
{
    (void)state;
    static const double ranges[] = {1e-6, 0.8, 4, 100, 65536};
    uint64_t rng = 12345;
    for (size_t i = 0; i < sizeof ranges / sizeof *ranges; i++) {
        double worst = 0, at = 0;
        for (int n = 0; n < 200000; n++) {
            rng = rng * 6364136223846793005ull + 1442695040888963407ull;
            double x = ((double)(rng >> 11) * 0x1.0p-53 * 2 - 1) * ranges[i];
            double s, c;
            mechc_sincos(x, &s, &c);
            double e = fmax(ulps(s, sinl(x)), ulps(c, cosl(x)));
            if (e > worst)
                worst = e, at = x;
        }
        if (!(worst <= 2.5))
            fail_msg("|x| <= %g: %.2f ulp at x = %.17g", ranges[i], worst, at);
    }
    /* the exact points of the table and of the reduction */
    double s, c;
    mechc_sincos(0.0, &s, &c);
    assert_true(s == 0.0 && c == 1.0);
    /* next to a zero of sin or cos the error is absolute, about 1e-28 |k| (the
       rounding of k times the second part of pi/128) */
    mechc_sincos(M_PI / 2, &s, &c);
    assert_true(s == 1.0 && fabsl(c - cosl(M_PI / 2)) <= 1e-26L);
    mechc_sincos(M_PI, &s, &c);
    assert_true(c == -1.0 && fabsl(s - sinl(M_PI)) <= 2e-26L);
    mechc_sincos(-1000 * M_PI, &s, &c);
    assert_true(c == 1.0 && fabsl(s - sinl(-1000 * M_PI)) <= 1e-23L);
    /* past 2^16 rad, and what is not a number, the C library answers */
    static const double far[] = {65537.0, -1e5, 1e6, 1e300};
    for (size_t i = 0; i < sizeof far / sizeof *far; i++) {
        mechc_sincos(far[i], &s, &c);
        assert_true(s == sin(far[i]) && c == cos(far[i]));
    }
    mechc_sincos(NAN, &s, &c);
    assert_true(isnan(s) && isnan(c));
    mechc_sincos(INFINITY, &s, &c);
    assert_true(isnan(s) && isnan(c));
}

/* The two-angle function does what two calls of the one-angle function do,
   to the bit, in range and out of it. */
static void test_sincos_pairs(void **state)
{
    (void)state;
    static const double special[] = {0.0, -0.0, 1e-300, M_PI, 65536.0, 65537.0, -1e9, NAN,
                                     INFINITY, -INFINITY};
    const int nspecial = (int)(sizeof special / sizeof *special);
    uint64_t rng = 777;
    for (int n = 0; n < 100000 + nspecial * nspecial; n++) {
        double x[2];
        for (int k = 0; k < 2; k++) {
            rng = rng * 6364136223846793005ull + 1442695040888963407ull;
            x[k] = ((double)(rng >> 11) * 0x1.0p-53 * 2 - 1) * (k ? 7.0 : 300.0);
        }
        if (n >= 100000) {
            x[0] = special[(n - 100000) / nspecial];
            x[1] = special[(n - 100000) % nspecial];
        }
        double s0, c0, s1, c1, e[4];
        mechc_sincos2(x[0], x[1], &s0, &c0, &s1, &c1);
        mechc_sincos(x[0], &e[0], &e[1]);
        mechc_sincos(x[1], &e[2], &e[3]);
        double got[4] = {s0, c0, s1, c1};
        for (int k = 0; k < 4; k++)
            if (memcmp(&got[k], &e[k], sizeof(double)) != 0)
                fail_msg("x = %.17g, %.17g: result %d is %.17g, one by one %.17g", x[0], x[1], k,
                         got[k], e[k]);
    }
}

/* Constants as C literals: the shared formatter's shortest text, a ".0"
   where it would read as an int, negative ones parenthesized, float ones
   suffixed, zero's sign kept, and HUGE_VALF past float's range. */
static void test_literals(void **state)
{
    (void)state;
    static const struct { double v; bool real_float; const char *text; } cases[] = {
        {0.3, false, "0.3"}, {0.1 + 0.2, false, "0.30000000000000004"}, {2, false, "2.0"},
        {-1.5, false, "(-1.5)"}, {1e20, false, "1e+20"}, {0.0, false, "0.0"},
        {-0.0, false, "(-0.0)"}, {0.1, true, "0.1f"}, {2, true, "2.0f"},
        {1.0 / 3, true, "0.33333334f"}, {-0.0, true, "(-0.0f)"}, {1e39, true, "HUGE_VALF"},
        {-1e39, true, "(-HUGE_VALF)"}, {-2.5e-7, true, "(-2.5e-07f)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        StrBuf sb;
        sb_init(&sb);
        emit_put_literal(&sb, cases[i].v, cases[i].real_float);
        assert_string_equal(sb.data, cases[i].text);
        sb_free(&sb);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_check_prefix),
        cmocka_unit_test(test_literals),
        cmocka_unit_test(test_banner),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_op_counts),
        cmocka_unit_test(test_keyword_names),
        cmocka_unit_test(test_examples_compile),
        cmocka_unit_test(test_chain_compiles),
        cmocka_unit_test(test_gcc_build_matches_jit),
        cmocka_unit_test(test_trig_choices),
        cmocka_unit_test(test_trig_single),
        cmocka_unit_test(test_sincos_accuracy),
        cmocka_unit_test(test_sincos_pairs),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
