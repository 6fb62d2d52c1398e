/* test_cli.c - the CLI's option tables: cli_parse into a struct, the --help printer, mechc's one JSON string escaper. */
#include "testutil.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../generator/cli/cli.h"
#include "../runtime/host/mechrt_host.h"

/* ---- a command with one option of each kind ---- */

typedef struct Opts {
    MechLimits limits;
    bool flag, on;
    int n, pick;
    double x, pos;
    const char *text;
    CliList items;
} Opts;

static const char *const picks[] = {"one", "two", "three", NULL};

static const CliOption options[] = {
    {"--flag", CLI_FLAG_AT(Opts, flag), .help = "a flag"},
    {"--no-on", CLI_CLEAR_AT(Opts, on), .help = "clears on"},
    {"--n", CLI_INT_AT(Opts, n, 1, 10), .metavar = "N", .help = "a count\nover two lines"},
    {"--x0", CLI_REAL_AT(Opts, x), .metavar = "X", .help = "any number"},
    {"--x1", CLI_REAL_AT(Opts, x), .metavar = "X"},
    {"--pos", CLI_REAL_AT(Opts, pos), CLI_POSITIVE, .what = "a positive number", .echo = true,
     .metavar = "P", .help = "positive"},
    {"--unit", CLI_REAL_AT(Opts, pos), .min = 0, .above_min = true, .max = 1,
     .what = "a number in (0, 1]", .metavar = "U", .help = "in (0, 1]"},
    {"--pick", CLI_CHOICE_AT(Opts, pick, picks), .metavar = "P", .help = "one, two or three"},
    {"-o", CLI_STRING_AT(Opts, text), .alias = "--output", .metavar = "F", .help = "a file"},
    {"--item", CLI_LIST_AT(Opts, items, 2), .what = "items", .metavar = "I", .help = "repeatable"},
};

static const CliCommand command = {
    .name = "demo", .usage = "usage: mechc demo FILE\n\n", CLI_OPTIONS(options), .column = 12,
    .epilogue = "\nthe end\n", .limits_offset = offsetof(Opts, limits),
};

/* What a stream writes, caught in a temporary file (the messages go
   straight to stderr, --help to stdout). */
typedef struct Capture {
    FILE *stream, *tmp;
    int saved;
} Capture;

static void capture_start(Capture *c, FILE *stream)
{
    fflush(stream);
    c->stream = stream;
    c->tmp = tmpfile();
    assert_non_null(c->tmp);
    c->saved = dup(fileno(stream));
    dup2(fileno(c->tmp), fileno(stream));
}

static void capture_end(Capture *c, char *text, size_t size)
{
    fflush(c->stream);
    dup2(c->saved, fileno(c->stream));
    close(c->saved);
    rewind(c->tmp);
    size_t n = fread(text, 1, size - 1, c->tmp);
    text[n] = '\0';
    fclose(c->tmp);
}

/* cli_parse on the NULL-terminated words, its stderr kept in err. */
static bool parse(Opts *o, Args *a, char *err, size_t size, ...)
{
    char *argv[32];
    int argc = 0;
    va_list ap;
    va_start(ap, size);
    for (char *w; (w = va_arg(ap, char *)) && argc < 32;)
        argv[argc++] = w;
    va_end(ap);
    *o = (Opts){.limits = mech_default_limits(), .on = true, .n = 5, .pick = -1};
    Capture c;
    capture_start(&c, stderr);
    bool go_on = cli_parse(a, &command, argc, argv, o);
    capture_end(&c, err, size);
    return go_on;
}

static void test_parse_every_kind(void **state)
{
    (void)state;
    Opts o;
    Args a;
    char err[512];
    assert_true(parse(&o, &a, err, sizeof err, "--flag", "--no-on", "--n", "7", "--x0=-2.5", "f.mech",
                      "--pos", "1e-3", "--pick", "three", "--output", "out.c", "--item", "a",
                      "--item=b", "--max-depth", "12", NULL));
    assert_false(a.failed);
    assert_string_equal(err, "");
    assert_string_equal(a.file, "f.mech");
    assert_true(o.flag);
    assert_false(o.on);
    assert_int_equal(o.n, 7);
    assert_near(o.x, -2.5, 0, 0);
    assert_near(o.pos, 1e-3, 0, 0);
    assert_int_equal(o.pick, 2);
    assert_string_equal(o.text, "out.c");
    assert_int_equal(o.items.n, 2);
    assert_string_equal(o.items.items[0], "a");
    assert_string_equal(o.items.items[1], "b");
    assert_int_equal(o.limits.max_depth, 12);
    assert_int_equal(o.limits.max_nodes, mech_default_limits().max_nodes);

    /* -- ends the options: what follows is the file */
    assert_true(parse(&o, &a, err, sizeof err, "-o", "x.c", "--", "--flag", NULL));
    assert_false(a.failed);
    assert_string_equal(a.file, "--flag");
    assert_string_equal(o.text, "x.c");
    assert_false(o.flag);
}

static void test_parse_errors(void **state)
{
    (void)state;
    Opts o;
    Args a;
    char err[512];
    static const struct {
        const char *w[4];
        const char *message;
    } cases[] = {
        {{"--n", "11"}, "mechc demo: error: --n needs a whole number from 1 to 10, not '11'\n"},
        {{"--n", "0x5"}, "mechc demo: error: --n needs a whole number from 1 to 10, not '0x5'\n"},
        {{"--n"}, "mechc demo: error: --n needs a value\n"},
        {{"--x0", "0x1p3"}, "mechc demo: error: --x0 needs a finite number, not '0x1p3'\n"},
        {{"--x1", "inf"}, "mechc demo: error: --x1 needs a finite number, not 'inf'\n"},
        {{"--pos", "0"}, "mechc demo: error: --pos needs a positive number, not 0\n"},
        {{"--unit", "0"}, "mechc demo: error: --unit needs a number in (0, 1]\n"},
        {{"--unit", "1.5"}, "mechc demo: error: --unit needs a number in (0, 1]\n"},
        {{"--pick", "four"}, "mechc demo: error: --pick takes one, two or three, not 'four'\n"},
        {{"--flag=yes"}, "mechc demo: error: --flag takes no value (given 'yes')\n"},
        {{"--item", "a", "--item", "b"}, NULL},     /* the third one is too many */
        {{"--bogus"}, "mechc demo: error: unknown option '--bogus' (see 'mechc demo --help')\n"},
        {{"--max-nodes", "15"}, "mechc demo: error: --max-nodes needs a whole number from 16 to 2147483646, not '15'\n"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        const char *const *w = cases[i].w;
        if (cases[i].message)
            parse(&o, &a, err, sizeof err, w[0], w[1], w[2], w[3], NULL);
        else
            parse(&o, &a, err, sizeof err, w[0], w[1], w[2], w[3], "--item", "c", NULL);
        assert_true(a.failed);
        assert_string_equal(err, cases[i].message ? cases[i].message
                                                  : "mechc demo: error: at most 2 --item items\n");
    }
    /* a value out of range leaves the field as it was */
    parse(&o, &a, err, sizeof err, "--n", "11", NULL);
    assert_int_equal(o.n, 5);
    parse(&o, &a, err, sizeof err, "--unit", "2", NULL);
    assert_near(o.pos, 0, 0, 0);
    /* parsing stops at the first error */
    parse(&o, &a, err, sizeof err, "--n", "0", "--flag", "--bogus", NULL);
    assert_false(o.flag);
    assert_null(strstr(err, "--bogus"));
}

static void test_help(void **state)
{
    (void)state;
    Opts o;
    Args a;
    char err[64];
    char text[2048];
    Capture c;
    capture_start(&c, stdout);
    cli_print_help(&command, stdout);
    capture_end(&c, text, sizeof text);
    assert_string_equal(text,
        "usage: mechc demo FILE\n"
        "\n"
        "  --flag    a flag\n"
        "  --no-on   clears on\n"
        "  --n N     a count\n"
        "            over two lines\n"
        "  --x0 X, --x1 X any number\n"
        "  --pos P   positive\n"
        "  --unit U  in (0, 1]\n"
        "  --pick P  one, two or three\n"
        "  -o F      a file\n"
        "  --item I  repeatable\n"
        "\n"
        "the end\n"
        "design parameters (`design NAME = value` in the file):\n"
        "  --design NAME=VALUE[,NAME=VALUE...]  evaluate at these values instead of\n"
        "                 the file's (repeatable; gen writes them as PREFIX_p0)\n"
        "limits (defaults in examples/README.md, section Limits; a value N each):\n"
        "  --max-file-bytes --max-line-length --max-name-length --max-depth\n"
        "  --max-expr-tokens --max-coords --max-rows --max-jac-entries --max-nodes\n"
        "  --max-code-ops\n");
    /* --help and -h stop the parse before anything else is read */
    capture_start(&c, stdout);
    bool go_on = parse(&o, &a, err, sizeof err, "--flag", "-h", "--bogus", NULL);
    capture_end(&c, text, sizeof text);
    assert_non_null(strstr(text, "  --n N     a count\n"));
    assert_false(go_on);
    assert_false(a.failed);
    assert_string_equal(err, "");
}

static void test_engine_choices(void **state)
{
    (void)state;
    /* --engine's choices are engine_names: EngineKind's order, NULL-ended */
    assert_string_equal(engine_names[ENGINE_JIT], "jit");
    assert_string_equal(engine_names[ENGINE_GENERIC], "generic");
    assert_string_equal(engine_names[ENGINE_AOT], "aot");
    assert_null(engine_names[ENGINE_KIND_COUNT]);
}

static void test_json_string(void **state)
{
    (void)state;
    char text[128];
    Capture c;
    capture_start(&c, stdout);
    mechrt_json_string(stdout, "a\"b\\c\nd\te\x7f\x01 \xc3\xa9/");
    capture_end(&c, text, sizeof text);
    assert_string_equal(text, "\"a\\\"b\\\\c\\u000ad\\u0009e\\u007f\\u0001 \xc3\xa9/\"");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_every_kind),
        cmocka_unit_test(test_parse_errors),
        cmocka_unit_test(test_help),
        cmocka_unit_test(test_engine_choices),
        cmocka_unit_test(test_json_string),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
