/* test_security.c - input text never becomes code, and no input exhausts mechc.
 *
 * Code injection: names from the .mech file (C keywords, libc and compiler
 * names, the generated code's own parameters and locals, 4000-character
 * names), mechanism names, file paths with comment ends, quotes and
 * newlines, and --prefix / --header values. Each generated file is written
 * to a mkdtemp directory and checked by gcc -std=c99 -pedantic -Wall
 * -Wextra -Werror (double and float; -fsyntax-only, which gives what a
 * build at -O0 warns of), built with tcc (gcc without it) and linked with a
 * small main that prints the name tables, and its text is scanned: every occurrence of a marker
 * chosen by the test must lie inside a string literal (or, for a file path,
 * inside the banner comment).
 *
 * Limits: each documented limit ends in a clear error, also at the default
 * values with inputs built to blow up (a 2000-token product differentiated
 * twice, code that shares work across many outputs, a huge dense Jacobian),
 * within bounded time. Numbers: params that are not finite are refused;
 * sqrt(-1) and log(0) reached at run time give IEEE results.
 *
 * The compile checks skip when gcc is missing or under MECHC_SKIP_GCC_ONLY
 * (make check-asan and check-valgrind). Under valgrind (tests/
 * run_valgrind sets MECHC_UNDER_VALGRIND) the stress inputs run with
 * smaller limits, as they would take minutes there.
 */
#include "testutil.h"

#include "../generator/base/arena.h"
#include "../generator/base/diag.h"
#include "../generator/base/limits.h"
#include "../generator/structure/info.h"
#include "../generator/base/strbuf.h"
#include "../generator/emit/emit.h"
#include "../generator/engine/engine.h"
#include "../generator/pipeline/pipeline.h"

#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static char tmpdir[256];
static bool have_gcc;
static const char *builder = "gcc";     /* tcc when there: builds in a tenth of the time */
static bool under_valgrind;

static const char *const CFLAGS = "-std=c99 -pedantic -Wall -Wextra -Werror";

static int group_setup(void **state)
{
    (void)state;
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/mechc_test_security_XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return -1;
    }
    /* make check-asan and check-valgrind cannot see inside gcc */
    have_gcc = !getenv("MECHC_SKIP_GCC_ONLY") && system("gcc --version > /dev/null 2>&1") == 0;
    under_valgrind = getenv("MECHC_UNDER_VALGRIND") != NULL;
    if (system("tcc -v > /dev/null 2>&1") == 0)
        builder = "tcc";
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- loading and emitting ---- */

static Mech *load(const char *text, const char *file, const MechLimits *limits, Diag *diag)
{
    MechLimits def = mech_default_limits();
    return pipeline_load_text(text, file, limits ? limits : &def, diag);
}

static Mech *load_ok(const char *text, const char *file, const MechLimits *limits, Diag *diag)
{
    Mech *mech = load(text, file, limits, diag);
    if (!mech) {
        diag_print(diag, stderr);
        fail_msg("%s: unexpected error", file);
    }
    return mech;
}

/* Loading must fail with a message containing want, at a position when
   the error belongs to a statement. */
static void load_fails(const char *text, const MechLimits *limits, const char *want, bool positioned)
{
    Diag diag;
    Mech *mech = load(text, "bad.mech", limits, &diag);
    if (mech) {
        pipeline_free(mech);
        fail_msg("loaded without error, expected \"%s\"", want);
    }
    if (!strstr(diag.message, want) || (positioned && !diag.has_pos)) {
        diag_print(&diag, stderr);
        fail_msg("expected \"%s\"%s", want, positioned ? " with a position" : "");
    }
}

/* ---- scanning the C text ---- */

typedef enum Where { IN_CODE, IN_STRING, IN_CHAR, IN_LINE_COMMENT, IN_BLOCK_COMMENT } Where;

/* Calls back with the lexical context of every occurrence of marker. A
   small C tokenizer: strings and character constants with escapes,
   both comment forms; enough for what mechc writes. */
static void scan(const char *text, const char *marker, void (*seen)(Where, size_t, void *), void *ctx)
{
    size_t mlen = strlen(marker);
    Where w = IN_CODE;
    for (size_t i = 0; text[i]; i++) {
        if (strncmp(text + i, marker, mlen) == 0)
            seen(w, i, ctx);
        char c = text[i], d = text[i + 1];
        switch (w) {
        case IN_CODE:
            if (c == '"') w = IN_STRING;
            else if (c == '\'') w = IN_CHAR;
            else if (c == '/' && d == '/') w = IN_LINE_COMMENT, i++;
            else if (c == '/' && d == '*') w = IN_BLOCK_COMMENT, i++;
            break;
        case IN_STRING:
        case IN_CHAR:
            if (c == '\\' && d)
                i++;
            else if (c == (w == IN_STRING ? '"' : '\''))
                w = IN_CODE;
            else if (c == '\n')
                fail_msg("a newline inside a string or character literal at offset %zu", i);
            break;
        case IN_LINE_COMMENT:
            if (c == '\n') w = IN_CODE;
            break;
        case IN_BLOCK_COMMENT:
            if (c == '*' && d == '/') w = IN_CODE, i++;
            break;
        }
    }
    assert_int_equal(w, IN_CODE);      /* nothing left open */
}

typedef struct MarkerCount {
    const char *text;
    int strings, banner, elsewhere;
    size_t first_bad;
} MarkerCount;

static void count_marker(Where w, size_t at, void *ctx)
{
    MarkerCount *m = ctx;
    size_t line_end = strcspn(m->text, "\n");
    if (w == IN_STRING)
        m->strings++;
    else if (w == IN_BLOCK_COMMENT && at < line_end)
        m->banner++;
    else if (m->elsewhere++ == 0)
        m->first_bad = at;
}

/* Occurrences of marker in text: each must be in a string literal, or in
   the banner comment when banner_ok; returns how many strings held it. */
static int marker_in_strings_only(const char *text, const char *marker, bool banner_ok)
{
    MarkerCount m = {.text = text};
    scan(text, marker, count_marker, &m);
    if (m.elsewhere || (!banner_ok && m.banner)) {
        size_t at = m.elsewhere ? m.first_bad : 0;
        fail_msg("'%s' appears outside a string literal: ...%.80s...", marker,
                 text + (at > 40 ? at - 40 : 0));
    }
    return m.strings;
}

/* ---- compiling ---- */

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return NULL;
    StrBuf sb;
    sb_init(&sb);
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0)
        sb_putn(&sb, buf, n);
    fclose(f);
    return sb_take(&sb);
}

/* A main that calls P_all and prints the name tables, one per line. */
static void write_main(const char *path, const char *prefix, const char *header)
{
    char upper[128];
    size_t i = 0;
    for (; prefix[i] && i + 1 < sizeof upper; i++)
        upper[i] = (char)(prefix[i] >= 'a' && prefix[i] <= 'z' ? prefix[i] - 32 : prefix[i]);
    upper[i] = '\0';
    StrBuf sb;
    sb_init(&sb);
    sb_printf(&sb,
              "#include <stdio.h>\n#include \"%s\"\n"
              "int main(void)\n{\n"
              "    static %s_real phi[%s_NH + 1], jac[%s_NR * %s_NQ], nu[%s_NR], gamma[%s_NR], qd[%s_NQ];\n"
              "    %s_all(%s_q0, qd, 0, phi, jac, nu, gamma);\n"
              "    for (int i = 0; i < %s_NQ; i++) puts(%s_coord_names[i]);\n"
              "    for (int i = 0; i < %s_NR; i++) puts(%s_row_names[i]);\n"
              "    return 0;\n}\n",
              header, prefix, upper, upper, upper, upper, upper, upper, prefix, prefix, upper,
              prefix, upper, prefix);
    write_text(path, sb.data);
    sb_free(&sb);
}

/* Emits mech with opt (header "mech.h" added), checks the marker, builds
   and runs the program; the printed names must be the model's. */
/* Emits mech with opt (header "mech.h" added) into res and checks the
   marker when given. */
static void emit_scanned(const Mech *mech, EmitOptions opt, const char *marker, bool banner_ok,
                         const char *tag, EmitResult *res)
{
    opt.header_name = "mech.h";
    Diag diag;
    diag_init(&diag, "test", NULL, 0);
    if (!emit_mechanism(&mech->kin, &opt, res, &diag))
        fail_msg("%s: emission failed: %s", tag, diag.message);
    if (marker) {
        marker_in_strings_only(res->c_text, marker, banner_ok);
        marker_in_strings_only(res->h_text, marker, banner_ok);
    }
}

static void build_and_run(const Mech *mech, EmitOptions opt, const char *marker, bool banner_ok,
                          const char *tag)
{
    EmitResult res;
    emit_scanned(mech, opt, marker, banner_ok, tag, &res);
    if (!have_gcc) {
        emit_result_free(&res);
        return;
    }
    char c_path[512], h_path[512], main_path[512], both_path[512], exe[512], out[512], cmd[4096];
    snprintf(c_path, sizeof c_path, "%s/mech.c", tmpdir);
    snprintf(h_path, sizeof h_path, "%s/mech.h", tmpdir);
    snprintf(main_path, sizeof main_path, "%s/main.c", tmpdir);
    snprintf(both_path, sizeof both_path, "%s/both.c", tmpdir);
    snprintf(exe, sizeof exe, "%s/prog", tmpdir);
    snprintf(out, sizeof out, "%s/out.txt", tmpdir);
    write_text(c_path, res.c_text);
    write_text(h_path, res.h_text);
    write_main(main_path, res.prefix, "mech.h");
    /* gcc reads both in one unit, mech.c first (its own includes alone
       before it), main.c's use of the header after: the same diagnostics
       as two units, one compiler start instead of two. The build links
       them as two units, so the names main.c uses are exported. */
    write_text(both_path, "#include \"mech.c\"\n#include \"main.c\"\n");
    snprintf(cmd, sizeof cmd, "gcc %s -fsyntax-only %s && %s %s %s -o %s -lm && %s > %s", CFLAGS,
             both_path, builder, c_path, main_path, exe, exe, out);
    if (system(cmd) != 0)
        fail_msg("%s (prefix %s, %s): the generated C failed gcc %s, or did not build or run with %s",
                 tag, res.prefix, opt.real_float ? "float" : "double", CFLAGS, builder);
    char *printed = read_text(out);
    assert_non_null(printed);
    StrBuf want;
    sb_init(&want);
    sb_puts(&want, "");
    const Model *m = mech->model;
    for (int i = 0; i < m->nq; i++)
        sb_printf(&want, "%s\n", m->coord_names[i]);
    for (int r = 0; r < m->nr; r++)
        sb_printf(&want, "%s\n", m->rows[r].name);
    if (strcmp(printed, want.data) != 0)
        fail_msg("%s: the name tables do not print the input's names", tag);
    free(printed);
    sb_free(&want);
    emit_result_free(&res);
}

static void build_both(const Mech *mech, const char *prefix, const char *marker, bool banner_ok,
                       const char *tag)
{
    EmitOptions opt = emit_default_options();
    opt.prefix = prefix;
    opt.source_name = mech->model->file;
    build_and_run(mech, opt, marker, banner_ok, tag);
    opt.real_float = true;
    build_and_run(mech, opt, marker, banner_ok, tag);
}

/* ---- names from the input ---- */

/* Names that are C keywords, libc and compiler names, and the names the
   generated code uses for its own parameters and locals. */
static const char *const hostile_names[] = {
    "int", "return", "static", "sizeof", "void", "asm", "typedef", "main", "malloc", "free",
    "exit", "_Exit", "__asm__", "__attribute__", "NULL", "errno", "printf", "q", "qd", "jac",
    "gamma", "phi", "nu", "vals", "u0", "u1", "i", "k", "at", "next", "v", "mechc_jit_phi",
    "M_PI", "HUGE_VAL", "INFINITY", "NAN", "_Pragma", "__LINE__", "double", "float",
};
enum { NHOSTILE = sizeof hostile_names / sizeof *hostile_names };

/* The statements using name for a body, a point, a coord and joints. */
static void hostile_statements(StrBuf *sb, const char *name)
{
    sb_printf(sb,
              "body %s x = 0.5 y = 0.25 phi = 0.7\n"
              "point %s_p x = 1 y = 2\n"
              "coord %s_c = 0.3\n"
              "revolute %s_j: ground %s(-0.5, 0)\n"
              "distance %s_d: %s %s_p length = 2\n"
              "constraint %s_k: %s_c = sin(%s.phi)\n"
              "velocity %s_v: der(%s_c) = 1\n",
              name, name, name, name, name, name, name, name, name, name, name, name, name);
}

/* A mechanism using name everywhere, plus marker-named statements. */
static char *hostile_text(const char *name, const char *mech_name)
{
    StrBuf sb;
    sb_init(&sb);
    if (mech_name)
        sb_printf(&sb, "mechanism %s\n", mech_name);
    hostile_statements(&sb, name);
    hostile_statements(&sb, "zqxMARK");
    return sb_take(&sb);
}

/* Every hostile name in one mechanism; the marker's names may appear only
   in the name tables. */
static void test_hostile_names(void **state)
{
    (void)state;
    StrBuf sb;
    sb_init(&sb);
    for (int i = 0; i < NHOSTILE; i++)
        hostile_statements(&sb, hostile_names[i]);
    hostile_statements(&sb, "zqxMARK");
    Diag diag;
    Mech *mech = load_ok(sb.data, "hostile.mech", NULL, &diag);
    assert_int_equal(mech->model->nq, 6 * (NHOSTILE + 1));
    build_both(mech, NULL, "zqxMARK", false, "hostile names");
    pipeline_free(mech);
    sb_free(&sb);
}

/* The same names as mechanism names: the default prefix is made a safe
   identifier (or the name is usable as it stands). */
static void test_hostile_mechanism_names(void **state)
{
    (void)state;
    for (int i = 0; i < NHOSTILE; i++) {
        char *text = hostile_text("b", hostile_names[i]);
        Diag diag;
        Mech *mech = load_ok(text, "hostile.mech", NULL, &diag);
        EmitOptions opt = emit_default_options();
        opt.source_name = mech->model->file;
        build_and_run(mech, opt, "zqxMARK", false, hostile_names[i]);
        pipeline_free(mech);
        free(text);
    }
}

/* --prefix values that are identifiers, including the generated code's
   own local names: all compile. */
static void test_prefix_accepted(void **state)
{
    (void)state;
    static const char *const prefixes[] = {"q", "qd", "t", "jac", "gamma", "phi", "nu", "vals", "u0",
                                           "i", "k", "at", "next", "v", "main", "NULL", "errno",
                                           "sin", "mech", "x_", "a1"};
    char *text = hostile_text("b", NULL);
    Diag diag;
    Mech *mech = load_ok(text, "prefix.mech", NULL, &diag);
    for (size_t i = 0; i < sizeof prefixes / sizeof *prefixes; i++) {
        assert_null(emit_check_prefix(prefixes[i]));
        EmitOptions opt = emit_default_options();
        opt.prefix = prefixes[i];
        build_and_run(mech, opt, "zqxMARK", false, prefixes[i]);
    }
    pipeline_free(mech);
    free(text);
}

/* --prefix values that are not identifiers are refused by the emitter
   itself, with the reason, and nothing is written. */
static void test_prefix_refused(void **state)
{
    (void)state;
    char long_prefix[80];
    memset(long_prefix, 'a', sizeof long_prefix - 1);
    long_prefix[sizeof long_prefix - 1] = '\0';
    static const char *const bad[] = {"", "1a", "a-b", "a b", "a\"b", "a\nb", "a*/b", "int", "for",
                                      "__x", "_X", "a;b", "a(b)", "\xc3\xa9", "a.b", "a/b"};
    char *text = hostile_text("b", NULL);
    Diag diag;
    Mech *mech = load_ok(text, "prefix.mech", NULL, &diag);
    for (size_t i = 0; i <= sizeof bad / sizeof *bad; i++) {
        const char *p = i < sizeof bad / sizeof *bad ? bad[i] : long_prefix;
        if (!emit_check_prefix(p))
            fail_msg("--prefix '%s' was accepted", p);
        EmitOptions opt = emit_default_options();
        opt.prefix = p;
        EmitResult res;
        Diag d;
        diag_init(&d, "test", NULL, 0);
        assert_false(emit_mechanism(&mech->kin, &opt, &res, &d));
        assert_non_null(strstr(d.message, "--prefix"));
        assert_null(res.c_text);
    }
    pipeline_free(mech);
    free(text);
}

/* #include "..." takes no escapes: header names are plain file names. */
static void test_header_names(void **state)
{
    (void)state;
    static const char *const bad[] = {"", "a\"b.h", "a\\b.h", "a?" "?/b.h", "a b.h", "a'b.h", "a\nb.h",
                                      "a*/b.h", "a>b.h"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
        if (!emit_check_header_name(bad[i]))
            fail_msg("header name '%s' was accepted", bad[i]);
    assert_null(emit_check_header_name("mech.h"));
    assert_null(emit_check_header_name("my-mech_1.2+x.h"));
    char *text = hostile_text("b", NULL);
    Diag diag;
    Mech *mech = load_ok(text, "header.mech", NULL, &diag);
    EmitOptions opt = emit_default_options();
    opt.header_name = "x\"y.h";
    EmitResult res;
    diag_init(&diag, "test", NULL, 0);
    assert_false(emit_mechanism(&mech->kin, &opt, &res, &diag));
    assert_non_null(strstr(diag.message, "header"));
    pipeline_free(mech);
    free(text);
}

/* A 4000-character name: refused at the default limit; with the limit
   raised it compiles, C99's 4095-character string literals included. */
static void test_long_names(void **state)
{
    (void)state;
    enum { LEN = 4000 };
    char *name = malloc(LEN + 1);
    memset(name, 'n', LEN);
    memcpy(name, "zqxMARK", 7);
    name[LEN] = '\0';
    char *text = hostile_text(name, name);
    load_fails(text, NULL, "name longer than the limit of 255 characters", true);
    free(text);
    /* the longest --max-name-length (4000) leaves row names such as
       NAME.phi within the 4095 characters of a C99 string literal */
    name[LEN - 10] = '\0';
    text = hostile_text(name, name);
    MechLimits limits = mech_default_limits();
    limits.max_name_length = 4000;
    limits.max_line_length = 20000;
    Diag diag;
    Mech *mech = load_ok(text, "long.mech", &limits, &diag);
    /* the marker starts the long names and the mechanism name: the
       prefix is it, cut to 64 characters */
    EmitOptions opt = emit_default_options();
    EmitResult res;
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &diag));
    assert_int_equal(strlen(res.prefix), 64);
    emit_result_free(&res);
    build_both(mech, "lng", "zqxMARK", false, "long names");
    pipeline_free(mech);
    free(text);
    free(name);
}

/* File paths with comment ends, quotes, newlines, backslashes and
   trigraphs: the banner stays one comment, the default prefix (from the
   file stem) an identifier. */
static void test_hostile_paths(void **state)
{
    (void)state;
    static const char *const paths[] = {
        "dir*/zqxMARK*/x.mech", "zqxMARK\"q\".mech", "zqxMARK\nint main(void){}\n.mech",
        "zqxMARK\\\\x.mech", "zqxMARK?" "?/.mech", "/*zqxMARK*/.mech", "zqxMARK'.mech",
        "zqxMARK#include <stdio.h>.mech", "zqxMARK\xc3\xa9.mech", ".mech", "zqxMARK",
    };
    const char *text = "body b x = 1\ndistance d: ground b length = 1\n";
    for (size_t i = 0; i < sizeof paths / sizeof *paths; i++) {
        Diag diag;
        Mech *mech = load_ok(text, paths[i], NULL, &diag);
        /* the marker may be in the banner comment, nowhere else (prefix
           p, so that no name holds it); the builds below, at the default
           prefix, compile and run the same banner */
        for (int fl = 0; fl < 2; fl++) {
            EmitOptions opt = emit_default_options();
            opt.prefix = "p";
            opt.source_name = mech->model->file;
            opt.real_float = fl;
            EmitResult res;
            emit_scanned(mech, opt, "zqxMARK", true, paths[i], &res);
            emit_result_free(&res);
        }
        /* the default prefix, from the stem, is an identifier */
        EmitOptions opt = emit_default_options();
        opt.source_name = paths[i];
        EmitResult res;
        assert_true(emit_mechanism(&mech->kin, &opt, &res, &diag));
        assert_null(emit_check_prefix(res.prefix));
        const char *nl = strchr(res.c_text, '\n');
        const char *end = strstr(res.c_text, "*/");
        assert_true(strncmp(res.c_text, "/* Code generated by mechc", 26) == 0);
        assert_true(end && end + 2 == nl);
        emit_result_free(&res);
        build_both(mech, NULL, NULL, true, paths[i]);
        pipeline_free(mech);
    }
}

/* ---- numbers ---- */

static void test_non_finite_constants(void **state)
{
    (void)state;
    load_fails("param a = 1e308*10\npoint m\ndistance d: ground m length = a\n", NULL,
               "the param value is not a finite number", true);
    load_fails("param a = 0/0\npoint m\ndistance d: ground m length = 1\n", NULL,
               "not a finite number", true);
    load_fails("param a = log(0)\npoint m\ndistance d: ground m length = 1\n", NULL,
               "not a finite number", true);
    load_fails("param a = sqrt(-1)\npoint m\ndistance d: ground m length = 1\n", NULL,
               "not a finite number", true);
    load_fails("param a = 1e999\n", NULL, "number out of range", true);
    load_fails("point m x = 1e308*1e308\ndistance d: ground m length = 1\n", NULL,
               "the initial x is not a finite number", true);
    load_fails("body b\npointline p: ground b axis(1e308*10, 0)\n", NULL,
               "the axis component ux is not a finite number", true);
    load_fails("body b\nrevolute r: ground(exp(1000), 0) b\n", NULL,
               "an attachment offset is not a finite number", true);
}

/* sqrt(-1), log(0), 1/0 and overflow reached at run time: IEEE results,
   no trap, no fold into the code. */
static void test_ieee_at_run_time(void **state)
{
    (void)state;
    const char *text = "point m x = -1 y = 0\n"
                       "constraint s: sqrt(m.x) = 0\n"
                       "constraint l: log(m.y) = 0\n"
                       "constraint d: 1/m.y = 0\n"
                       "constraint e: exp(1000*(m.x + 2)) = 0\n";
    Diag diag;
    Mech *mech = load_ok(text, "ieee.mech", NULL, &diag);
    EmitResult res;
    Jit *jit = engine_jit(mech, &res, NULL, NULL, &diag);
    if (!jit)
        fail_msg("jit: %s", diag.message);
    double q[2] = {-1, 0}, qd[2] = {0.5, -0.25}, phi[4], jac[8], nu[4], gamma[4];
    const Kernels *k = jit_kernels(jit);
    k->all(q, qd, 0.0, phi, jac, nu, gamma);
    assert_true(isnan(phi[0]));
    assert_true(isinf(phi[1]) && phi[1] < 0);
    assert_true(isinf(phi[2]));
    assert_true(isinf(phi[3]) && phi[3] > 0);
    assert_true(isnan(jac[0]));                 /* d sqrt(x)/dx at -1 */
    /* no NaN or infinity literal in the generated C */
    assert_null(strstr(res.c_text, "inf"));
    assert_null(strstr(res.c_text, "nan"));
    jit_free(jit);
    emit_result_free(&res);
    pipeline_free(mech);
}

/* ---- limits ---- */

static long max_rss_kb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

/* Every limit of limits.h, one at a time, with a tiny value. */
static void test_each_limit(void **state)
{
    (void)state;
    MechLimits l = mech_default_limits();
    l.max_file_bytes = 10;
    load_fails("body b x = 1\ndistance d: ground b length = 1\n", &l, "larger than the limit of 10 bytes",
               false);
    l = mech_default_limits();
    l.max_line_length = 12;
    load_fails("body b x = 1\ndistance d: ground b length = 1\n", &l, "line longer than the limit of 12",
               true);
    l = mech_default_limits();
    l.max_name_length = 3;
    load_fails("body abcd\n", &l, "name longer than the limit of 3 characters", true);
    l = mech_default_limits();
    l.max_depth = 3;
    load_fails("param a = ((((1))))\n", &l, "nested deeper than the limit of 3 levels", true);
    l = mech_default_limits();
    l.max_expr_tokens = 5;
    load_fails("param a = 1 + 2 + 3 + 4\n", &l, "statement longer than the limit of 5 tokens", true);
    l = mech_default_limits();
    l.max_coords = 4;
    load_fails("body a\nbody b\n", &l, "too many coordinates (the limit is 4)", true);
    l = mech_default_limits();
    l.max_rows = 2;
    load_fails("body a\nweld w: ground a\n", &l, "too many rows (the limit is 2)", true);
    l = mech_default_limits();
    l.max_jac_entries = 8;
    load_fails("body a\nweld w: ground a\n", &l, "the dense Jacobian would have 3 rows x 3 coordinates",
               true);
    l = mech_default_limits();
    l.max_nodes = 40;
    load_fails("body a\nbody b\nrevolute r: a(1, 2) b(3, 4)\nweld w: ground a\n", &l,
               "the expression graph passed its limit of 40 nodes at this statement", true);

    /* the generated code's size */
    Diag diag;
    Mech *mech = load_ok("body a\nbody b\nrevolute r: a(1, 2) b(3, 4)\n", "ops.mech", NULL, &diag);
    EmitOptions opt = emit_default_options();
    opt.max_ops = 10;
    EmitResult res;
    assert_false(emit_mechanism(&mech->kin, &opt, &res, &diag));
    assert_non_null(strstr(diag.message, "more than 10 operations"));
    pipeline_free(mech);
}

/* n coordinates c0.. and rows of products of all of them: 2n tokens per
   row, derivatives quadratic in n per row and, with the rows different,
   nothing shared between rows. */
static const char *short_name(int i, char buf[8])
{
    /* A..Z, then AA..ZZ, then AAA..: capitals avoid every reserved word */
    int len = 1, span = 26;
    while (i >= span)
        i -= span, span *= 26, len++;
    buf[len] = '\0';
    for (int k = len - 1; k >= 0; k--, i /= 26)
        buf[k] = (char)('A' + i % 26);
    return buf;
}

static char *product_rows(int n, int rows)
{
    StrBuf sb;
    sb_init(&sb);
    char name[8];
    for (int i = 0; i < n; i++)
        sb_printf(&sb, "coord %s = 0.%d\n", short_name(i, name), i % 9 + 1);
    for (int r = 0; r < rows; r++) {
        sb_printf(&sb, "constraint k%d: (A + %d)", r, r);
        for (int i = 1; i < n; i++)
            sb_printf(&sb, "*%s", short_name(i, name));
        sb_puts(&sb, " = 1\n");
    }
    return sb_take(&sb);
}

/* A limit must trip (message contains want) or the whole pipeline run,
   within seconds; returns whether it tripped. */
static bool pipeline_bounded(const char *text, const MechLimits *limits, const char *want,
                             double seconds, const char *what)
{
    double t0 = now();
    Diag diag;
    bool tripped = false;
    Mech *mech = load(text, "stress.mech", limits, &diag);
    if (mech) {
        EmitResult res;
        Jit *jit = engine_jit(mech, &res, NULL, NULL, &diag);
        if (jit)
            jit_free(jit);
        else if (!strstr(diag.message, want))
            fail_msg("%s: unexpected error: %s", what, diag.message);
        else
            tripped = true;
        emit_result_free(&res);
        pipeline_free(mech);
    } else if (!strstr(diag.message, want)) {
        diag_print(&diag, stderr);
        fail_msg("%s: unexpected error", what);
    } else {
        tripped = true;
    }
    double t = now() - t0;
    print_message("%s: %s in %.2f s, max RSS %ld MB\n", what, tripped ? diag.message : "compiled", t,
                  max_rss_kb() / 1024);
    if (!under_valgrind && t > seconds)
        fail_msg("%s took %.1f s (more than %.0f s)", what, t, seconds);
    return tripped;
}

/* One 2000-token statement, differentiated twice: fine or a clear error. */
static void test_one_huge_statement(void **state)
{
    (void)state;
    MechLimits l = mech_default_limits();
    if (under_valgrind)
        l.max_nodes = 100000, l.max_code_ops = 100000;
    /* 995 factors: with "constraint k0: (A + 0) ... = 1", 2000 tokens */
    char *text = product_rows(under_valgrind ? 100 : 995, 1);
    pipeline_bounded(text, &l, "limit", 60, "one row, product of 995 coordinates (100 under valgrind)");
    free(text);
    /* sin(sin(...)) nested past the depth limit */
    StrBuf sb;
    sb_init(&sb);
    sb_puts(&sb, "coord c = 1\nconstraint k: ");
    for (int i = 0; i < 500; i++)
        sb_puts(&sb, "sin(");
    sb_puts(&sb, "c");
    for (int i = 0; i < 500; i++)
        sb_puts(&sb, ")");
    sb_puts(&sb, " = 0\n");
    load_fails(sb.data, NULL, "nested deeper than the limit of 64 levels", true);
    sb_free(&sb);
    /* x*x*x*...: 1000 factors of one coordinate */
    sb_init(&sb);
    sb_puts(&sb, "coord x = 0.9\nconstraint k: x");
    for (int i = 1; i < 997; i++)
        sb_puts(&sb, "*x");
    sb_puts(&sb, " = 0\n");
    pipeline_bounded(sb.data, NULL, "limit", 20, "x*x*...*x, 997 factors");
    sb_free(&sb);
    /* left-nested sums: deep graphs without parentheses, at the token limit */
    sb_init(&sb);
    sb_puts(&sb, "coord x = 0.9\ncoord y = 0.1\nconstraint k: sin(x)");
    for (int i = 1; i < 497; i++)
        sb_printf(&sb, "%cx*y", i % 2 ? '+' : '-');
    sb_puts(&sb, " = 0\n");
    pipeline_bounded(sb.data, NULL, "limit", 20, "x*y +- x*y ..., 2000 tokens");
    sb_free(&sb);
}

/* Many such statements: the node limit trips with the statement's position. */
static void test_node_limit_trips(void **state)
{
    (void)state;
    MechLimits l = mech_default_limits();
    if (under_valgrind)
        l.max_nodes = 200000;
    char *text = product_rows(600, 200);
    /* one load: it trips within the time (so the pipeline does), the
       limit's message at the statement's position */
    double t0 = now();
    Diag diag;
    Mech *mech = load(text, "stress.mech", &l, &diag);
    double t = now() - t0;
    if (mech) {
        pipeline_free(mech);
        fail_msg("200 rows, products of 600 coordinates: loaded without error");
    }
    print_message("200 rows, products of 600 coordinates: %s in %.2f s\n", diag.message, t);
    if (!strstr(diag.message, "the expression graph passed its limit") ||
        !strstr(diag.message, "at this statement") || !diag.has_pos)
        fail_msg("expected the node limit at a statement's position");
    if (!under_valgrind && t > 60)
        fail_msg("200 rows, products of 600 coordinates took %.1f s (more than 60 s)", t);
    free(text);
}

/* ---- the node limit in each phase that builds nodes ---- */

/* The graph's size once the model is built (before any derivative). */
static int nodes_after_model(const char *text)
{
    MechLimits l = mech_default_limits();
    Diag diag;
    diag_init(&diag, "m.mech", NULL, 0);
    Model *m = model_load(text, (int)strlen(text), "m.mech", "m", &l, &diag);
    assert_non_null(m);
    int count = m->dag.count;
    model_free(m);
    return count;
}

static const char *const two_rows =
    "body a x = 1  y = 2  phi = 0.5\n"
    "distance d: ground(0, 0) a(0.5, 0) length = 2\n"
    "revolute r: ground(1, 2) a(0, 0.25)\n";

/* Differentiation past the limit: the model builds within it, then the
   first row whose derivatives need a node is named, as before. */
static void test_node_limit_in_differentiation(void **state)
{
    (void)state;
    MechLimits l = mech_default_limits();
    l.max_nodes = nodes_after_model(two_rows);
    Diag diag;
    Mech *mech = load(two_rows, "d.mech", &l, &diag);
    if (mech)
        pipeline_free(mech);
    assert_null(mech);
    assert_true(diag.has_pos);
    assert_int_equal(diag.line, 2);             /* the distance row, the first one */
    assert_int_equal(diag.col, 1);
    char want[160];
    snprintf(want, sizeof want, "the expression graph passed its limit of %d nodes at this statement "
             "(its rows or their derivatives are too large; see --max-nodes)", l.max_nodes);
    assert_string_equal(diag.message, want);
    /* one node fewer: the model builder trips, at the last statement */
    l.max_nodes--;
    assert_null(load(two_rows, "d.mech", &l, &diag));
    assert_int_equal(diag.line, 3);
    snprintf(want, sizeof want, "limit of %d nodes at this statement", l.max_nodes);
    assert_non_null(strstr(diag.message, want));
}

/* A statement that passes the limit and has an input error after that
   point: the node limit is the error, as when the graph jumped out at once
   (the builder checks before each operand and after each expression). */
static void test_node_limit_is_the_first_error(void **state)
{
    (void)state;
    MechLimits l = mech_default_limits();
    l.max_nodes = 3;        /* 0, 1 and x: sin(x) is refused, then 'nosuch' is looked up */
    load_fails("coord x = 1\nconstraint k: atan2(sin(x), nosuch) = 0\n", &l,
               "limit of 3 nodes at this statement", true);
    l.max_nodes = 2;        /* cos(1) is refused: the axis would read as zero */
    load_fails("param a = 1\nbody b\nprismatic p: ground b axis(cos(a), 0)\n", &l,
               "limit of 2 nodes at this statement", true);
    load_fails("param a = 1\nbody b\nweld w: nosuch(1, cos(a)) b\n", &l,     /* then the lookup */
               "limit of 2 nodes at this statement", true);
}

/* Past the limit, differentiation stops at the row where it happened
   instead of running on over the remaining rows with refused nodes. */
static void test_node_limit_stops_differentiation(void **state)
{
    (void)state;
    enum { N = 1000 };      /* coords, and N - 1 small rows of about 20 new nodes each */
    StrBuf sb;
    sb_init(&sb);
    char a[8], b[8];
    for (int i = 0; i < N; i++)
        sb_printf(&sb, "coord %s = 0.%d\n", short_name(i, a), i % 9 + 1);
    for (int r = 0; r + 1 < N; r++)
        sb_printf(&sb, "constraint k%d: %s*%s + sin(%s) = %d\n", r, short_name(r, a),
                  short_name(r + 1, b), a, r);
    MechLimits l = mech_default_limits();
    Diag diag;
    diag_init(&diag, "c.mech", NULL, 0);
    Model *m = model_load(sb.data, (int)sb.len, "c.mech", "c", &l, &diag);
    assert_non_null(m);
    m->dag.max_nodes = m->dag.count + 1000;     /* passed after some rows, long before the last */
    Kinematics kin;
    assert_false(kinematics_build(m, &kin, &diag));
    assert_int_equal(m->dag.count, m->dag.max_nodes);
    assert_non_null(strstr(diag.message, "at this statement"));
    assert_true(diag.line > N + 1 && diag.line < N + N / 2);
    assert_true(kin.nnz > 0);                   /* the rows before the limit */
    assert_int_equal(kin.row_start[m->nr - 1], 0);     /* the last rows never started */
    model_free(m);
    sb_free(&sb);
}

static const char *const knife =
    "body cart x = 1  y = 0  phi = 0.7\n"
    "knife blade: cart axis(1, 0)\n"
    "velocity roll: der(cart.x)*cart.y - der(cart.y)*cart.x = sin(cart.phi)*t\n";

/* The integrability test and the involutivity test of `info` past the
   limit: the message has no statement (the mechanism as a whole). */
static void test_node_limit_in_info(void **state)
{
    (void)state;
    MechLimits l = mech_default_limits();
    Diag diag;
    Mech *mech = load_ok(knife, "k.mech", &l, &diag);
    Model *m = mech->model;
    m->dag.max_nodes = m->dag.count;            /* nothing new from here on */
    char want[160];
    snprintf(want, sizeof want, "the expression graph passed its limit of %d nodes "
             "(the mechanism is too large; see --max-nodes)", m->dag.count);
    AnalysisOptions opt = analysis_default_options();
    Integrability it;
    assert_false(integrability_analyse(m, m->nh + 1, m->q0, &opt, &it, &diag));
    assert_false(diag.has_pos);
    assert_string_equal(diag.message, want);
    assert_null(it.note);                       /* no verdict on refused nodes */
    integrability_free(&it);

    diag_init(&diag, "k.mech", NULL, 0);
    int rows[3] = {0, 1, 2};
    double t = 0.0;
    Involutivity inv;
    assert_false(involutivity_analyse(m, rows, m->nr, m->q0, &t, 1, &inv, &diag));
    assert_string_equal(diag.message, want);
    involutivity_free(&inv);

    diag_init(&diag, "k.mech", NULL, 0);
    InfoReport rep;
    assert_false(info_analyse(mech, 0.0, &opt, &rep, &diag));
    assert_string_equal(diag.message, want);
    /* with room, the same mechanism analyses */
    m->dag.max_nodes = 1000000;
    m->dag.overflow = false;
    diag_init(&diag, "k.mech", NULL, 0);
    assert_true(info_analyse(mech, 0.0, &opt, &rep, &diag));
    assert_false(rep.system.involutive);
    info_report_free(&rep);
    pipeline_free(mech);
}

/* Outputs sharing long chains: few graph nodes. Each node is computed by
   one part of a function and imported by the later ones, so the code stays
   the size of the graph and compiles at the defaults; a limit below that
   size still trips. */
static void test_code_limit_trips(void **state)
{
    (void)state;
    StrBuf sb;
    sb_init(&sb);
    int n = under_valgrind ? 300 : 600;
    char name[8];
    for (int i = 0; i < n; i++)
        sb_printf(&sb, "coord %s = 0.5\n", short_name(i, name));
    for (int r = 0; r < 60; r++) {
        sb_printf(&sb, "constraint k%d: A", r);
        for (int i = 1; i < n; i++)
            sb_printf(&sb, "*%s", short_name(i, name));
        sb_printf(&sb, " = %d\n", r);
    }
    MechLimits l = mech_default_limits();
    if (under_valgrind)
        l.max_code_ops = 200000;
    assert_false(pipeline_bounded(sb.data, &l, "operations, the limit", 20, "60 rows sharing a product"));
    l.max_code_ops = 5000;
    assert_true(pipeline_bounded(sb.data, &l, "operations, the limit", 20, "60 rows sharing a product"));
    sb_free(&sb);
}

/* Rows x coordinates past the dense limit, at the defaults. */
static void test_dense_limit_trips(void **state)
{
    (void)state;
    StrBuf sb;
    sb_init(&sb);
    for (int i = 0; i < 7100; i++)
        sb_printf(&sb, "coord c%d\nconstraint k%d: c%d = %d\n", i, i, i, i);
    load_fails(sb.data, NULL, "entries, more than the limit of 50000000", true);
    sb_free(&sb);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hostile_names),
        cmocka_unit_test(test_hostile_mechanism_names),
        cmocka_unit_test(test_prefix_accepted),
        cmocka_unit_test(test_prefix_refused),
        cmocka_unit_test(test_header_names),
        cmocka_unit_test(test_long_names),
        cmocka_unit_test(test_hostile_paths),
        cmocka_unit_test(test_non_finite_constants),
        cmocka_unit_test(test_ieee_at_run_time),
        cmocka_unit_test(test_each_limit),
        cmocka_unit_test(test_one_huge_statement),
        cmocka_unit_test(test_node_limit_trips),
        cmocka_unit_test(test_node_limit_in_differentiation),
        cmocka_unit_test(test_node_limit_is_the_first_error),
        cmocka_unit_test(test_node_limit_stops_differentiation),
        cmocka_unit_test(test_node_limit_in_info),
        cmocka_unit_test(test_code_limit_trips),
        cmocka_unit_test(test_dense_limit_trips),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
