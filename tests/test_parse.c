/* test_parse.c - the .mech lexer and parser: AST shapes for every statement form, and bad input. */
#include "testutil.h"

#include "../generator/base/arena.h"
#include "../generator/base/diag.h"
#include "../generator/base/limits.h"
#include "../generator/parse/ast.h"
#include "../generator/parse/parse.h"

#include <stdlib.h>
#include <string.h>

/* One parse: the arena owns the AST, diag the error. */
typedef struct Parsed {
    Arena arena;
    Diag diag;
    Program prog;
    bool ok;
    char sexpr[4096];
} Parsed;

static int setup(void **state)
{
    Parsed *r = calloc(1, sizeof *r);
    arena_init(&r->arena);
    *state = r;
    return 0;
}

static int teardown(void **state)
{
    Parsed *r = *state;
    arena_free(&r->arena);
    free(r);
    return 0;
}

static bool parse_len(Parsed *r, const char *text, int len, const MechLimits *limits)
{
    MechLimits def = mech_default_limits();
    diag_init(&r->diag, "test.mech", text, len);
    r->ok = parse_program(&r->arena, &r->diag, limits ? limits : &def, &r->prog);
    return r->ok;
}

/* Parses text that must be valid; prints the error otherwise. */
static const Program *parse_ok(Parsed *r, const char *text)
{
    if (!parse_len(r, text, (int)strlen(text), NULL)) {
        diag_print(&r->diag, stderr);
        fail_msg("unexpected parse error for: %s", text);
    }
    return &r->prog;
}

static const Stmt *nth_stmt(const Program *prog, int n)
{
    const Stmt *s = prog->first;
    for (int i = 0; i < n && s; i++)
        s = s->next;
    assert_non_null(s);
    return s;
}

/* ---- AST rendering: shapes compared as S-expressions ---- */

static void put(char *buf, size_t size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void put(char *buf, size_t size, const char *fmt, ...)
{
    size_t n = strlen(buf);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + n, size - n, fmt, ap);
    va_end(ap);
}

static void render(const Ast *a, char *buf, size_t size)
{
    switch (a->kind) {
    case AST_NUM:
        put(buf, size, "%.17g", a->num);
        return;
    case AST_NAME:
        put(buf, size, "%s", a->name);
        return;
    case AST_MEMBER:
        put(buf, size, "%s.%s", a->name, a->member);
        return;
    case AST_TIME:
        put(buf, size, "t");
        return;
    case AST_NEG:
        put(buf, size, "(neg ");
        render(a->lhs, buf, size);
        put(buf, size, ")");
        return;
    case AST_BINARY:
    case AST_CALL:
        put(buf, size, "(%s ", dag_op_info[a->op].spelling);
        render(a->lhs, buf, size);
        if (a->rhs) {
            put(buf, size, " ");
            render(a->rhs, buf, size);
        }
        put(buf, size, ")");
        return;
    case AST_SLIDE:
        put(buf, size, "(slide %s)", a->name);
        return;
    case AST_ANGLE:
        put(buf, size, "(angle %s)", a->name);
        return;
    case AST_DER:
        put(buf, size, "(der ");
        render(a->lhs, buf, size);
        put(buf, size, ")");
        return;
    }
    put(buf, size, "?");
}

static const char *show(Parsed *r, const Ast *a)
{
    r->sexpr[0] = '\0';
    render(a, r->sexpr, sizeof r->sexpr);
    return r->sexpr;
}

/* The value of "param p = TEXT" as an S-expression. */
static const char *expr_shape(Parsed *r, const char *text)
{
    char line[1024];
    snprintf(line, sizeof line, "param p = %s\n", text);
    arena_free(&r->arena);
    const Program *prog = parse_ok(r, line);
    return show(r, prog->first->value);
}

static void assert_pos(const Parsed *r, SrcPos pos, int line, int col)
{
    int l, c;
    diag_locate(&r->diag, pos.offset, &l, &c);
    if (l != line || c != col)
        fail_msg("position %d:%d, expected %d:%d", l, c, line, col);
}

/* ---- good input ---- */

static const char slider_crank[] =
    "mechanism slider_crank            # optional; default name = file stem\n"
    "\n"
    "param r     = 0.1                 # constants, folded into the generated code\n"
    "param l     = 0.3\n"
    "param omega = 2*pi\n"
    "\n"
    "body  crank  x = r/2   y = 0  phi = 0      # planar rigid body: coords x, y, phi\n"
    "body  rod    x = 0.25  y = 0  phi = 0      # values are initial guesses (default 0)\n"
    "body  slider x = 0.40  y = 0  phi = 0\n"
    "point m      x = 1.732 y = 1.0             # particle: coords x, y\n"
    "coord theta  = 0.3                         # a free scalar coordinate\n"
    "\n"
    "revolute  O: ground(0, 0)  crank(-r/2, 0)\n"
    "revolute  A: crank(r/2, 0) rod(-l/2, 0)\n"
    "revolute  B: rod(l/2, 0)   slider(0, 0)\n"
    "prismatic P: ground(0, 0)  slider(0, 0)  axis(1, 0)\n"
    "driver    D: crank.phi = omega*t\n";

static void test_spec_example(void **state)
{
    Parsed *r = *state;
    const Program *prog = parse_ok(r, slider_crank);
    assert_int_equal(prog->count, 14);
    assert_int_equal(prog->line_count, 17);

    const Stmt *s = nth_stmt(prog, 0);
    assert_int_equal(s->kind, STMT_MECHANISM);
    assert_string_equal(s->name, "slider_crank");
    assert_pos(r, s->pos, 1, 1);
    assert_pos(r, s->name_pos, 1, 11);

    s = nth_stmt(prog, 3);
    assert_int_equal(s->kind, STMT_PARAM);
    assert_string_equal(s->name, "omega");
    assert_string_equal(show(r, s->value), "(* 2 3.1415926535897931)");
    assert_near(s->value->rhs->num, 3.14159265358979323846, 0, 0);

    s = nth_stmt(prog, 4);
    assert_int_equal(s->kind, STMT_BODY);
    assert_string_equal(s->name, "crank");
    assert_string_equal(show(r, s->init[0]), "(/ r 2)");
    assert_string_equal(show(r, s->init[1]), "0");
    assert_string_equal(show(r, s->init[2]), "0");
    assert_pos(r, s->init_pos[0], 7, 14);
    assert_pos(r, s->init_pos[1], 7, 24);
    assert_pos(r, s->init_pos[2], 7, 31);

    s = nth_stmt(prog, 7);
    assert_int_equal(s->kind, STMT_POINT);
    assert_string_equal(s->name, "m");
    assert_near(s->init[0]->num, 1.732, 0, 0);
    assert_near(s->init[1]->num, 1.0, 0, 0);
    assert_null(s->init[2]);

    s = nth_stmt(prog, 8);
    assert_int_equal(s->kind, STMT_COORD);
    assert_string_equal(s->name, "theta");
    assert_near(s->value->num, 0.3, 0, 0);

    s = nth_stmt(prog, 9);
    assert_int_equal(s->kind, STMT_JOINT);
    assert_int_equal(s->joint, JOINT_REVOLUTE);
    assert_string_equal(s->name, "O");
    assert_pos(r, s->name_pos, 13, 11);
    assert_string_equal(s->attach[0].name, "ground");
    assert_true(s->attach[0].has_offset);
    assert_pos(r, s->attach[0].pos, 13, 14);
    assert_string_equal(s->attach[1].name, "crank");
    assert_pos(r, s->attach[1].pos, 13, 28);
    assert_string_equal(show(r, s->attach[1].sx), "(/ (neg r) 2)");   /* (-r)/2 */
    assert_string_equal(show(r, s->attach[1].sy), "0");
    assert_null(s->option);

    s = nth_stmt(prog, 12);
    assert_int_equal(s->joint, JOINT_PRISMATIC);
    assert_string_equal(s->attach[1].name, "slider");
    assert_string_equal(show(r, s->axis[0]), "1");
    assert_string_equal(show(r, s->axis[1]), "0");
    assert_pos(r, s->axis_pos, 16, 42);
    assert_null(s->option);

    s = nth_stmt(prog, 13);
    assert_int_equal(s->joint, JOINT_DRIVER);
    assert_string_equal(show(r, s->lhs), "crank.phi");
    assert_pos(r, s->lhs->member_pos, 17, 20);
    assert_string_equal(show(r, s->rhs), "(* omega t)");
    assert_pos(r, s->eq_pos, 17, 24);
    assert_null(s->next);
}

static void test_precedence(void **state)
{
    Parsed *r = *state;
    assert_string_equal(expr_shape(r, "-x^2"), "(neg (^ x 2))");
    assert_string_equal(expr_shape(r, "2^3^2"), "(^ 2 (^ 3 2))");
    assert_string_equal(expr_shape(r, "a-b-c"), "(- (- a b) c)");
    assert_string_equal(expr_shape(r, "a/b/c"), "(/ (/ a b) c)");
    assert_string_equal(expr_shape(r, "2*pi"), "(* 2 3.1415926535897931)");
    assert_string_equal(expr_shape(r, "2^-1"), "(^ 2 (neg 1))");
    assert_string_equal(expr_shape(r, "2^-x^2"), "(^ 2 (neg (^ x 2)))");
    assert_string_equal(expr_shape(r, "-a*b"), "(* (neg a) b)");
    assert_string_equal(expr_shape(r, "a+b*c"), "(+ a (* b c))");
    assert_string_equal(expr_shape(r, "a*b+c"), "(+ (* a b) c)");
    assert_string_equal(expr_shape(r, "a*b^c"), "(* a (^ b c))");
    assert_string_equal(expr_shape(r, "(a+b)*c"), "(* (+ a b) c)");
    assert_string_equal(expr_shape(r, "a - -b"), "(- a (neg b))");
    assert_string_equal(expr_shape(r, "+x"), "x");
    assert_string_equal(expr_shape(r, "-+-x"), "(neg (neg x))");
    assert_string_equal(expr_shape(r, "(-x)^2"), "(^ (neg x) 2)");
    assert_string_equal(expr_shape(r, "a^b*c"), "(* (^ a b) c)");
    assert_string_equal(expr_shape(r, "1-2+3"), "(+ (- 1 2) 3)");
}

static void test_primaries(void **state)
{
    Parsed *r = *state;
    assert_string_equal(expr_shape(r, "atan2(y, x)"), "(atan2 y x)");
    assert_string_equal(expr_shape(r, "sin(t)"), "(sin t)");
    assert_string_equal(expr_shape(r, "sqrt(cos(a)^2 + 1)"), "(sqrt (+ (^ (cos a) 2) 1))");
    assert_string_equal(expr_shape(r, "der(crank.phi)"), "(der crank.phi)");
    assert_string_equal(expr_shape(r, "der( theta )*2"), "(* (der theta) 2)");
    assert_string_equal(expr_shape(r, "ground"), "ground");
    assert_string_equal(expr_shape(r, "m.x"), "m.x");
    assert_string_equal(expr_shape(r, "a . b"), "a.b");
    assert_string_equal(expr_shape(r, "exp(log(2))*tanh(sinh(cosh(1)))"),
                        "(* (exp (log 2)) (tanh (sinh (cosh 1))))");
    assert_string_equal(expr_shape(r, "tan(asin(acos(atan(1))))"),
                        "(tan (asin (acos (atan 1))))");
    /* numbers */
    assert_string_equal(expr_shape(r, ".5"), "0.5");
    assert_string_equal(expr_shape(r, "5."), "5");
    assert_string_equal(expr_shape(r, "1e-3"), "0.001");
    assert_string_equal(expr_shape(r, "1E+2"), "100");
    assert_string_equal(expr_shape(r, "2.5e1"), "25");
    assert_string_equal(expr_shape(r, "1e-400"), "0");    /* underflow is fine */
    assert_string_equal(expr_shape(r, "007"), "7");
}

static void test_positions(void **state)
{
    Parsed *r = *state;
    const Program *prog = parse_ok(r, "param p = -a + sin(b.x)*2\n");
    const Ast *e = prog->first->value;
    assert_int_equal(e->kind, AST_BINARY);
    assert_int_equal(e->op, OP_ADD);
    assert_pos(r, e->pos, 1, 14);                   /* the operator */
    assert_int_equal(e->lhs->kind, AST_NEG);
    assert_pos(r, e->lhs->pos, 1, 11);
    assert_pos(r, e->lhs->lhs->pos, 1, 12);
    const Ast *mul = e->rhs;
    assert_pos(r, mul->pos, 1, 24);
    assert_int_equal(mul->lhs->kind, AST_CALL);
    assert_int_equal(mul->lhs->op, OP_SIN);
    assert_pos(r, mul->lhs->pos, 1, 16);
    assert_int_equal(mul->lhs->lhs->kind, AST_MEMBER);
    assert_pos(r, mul->lhs->lhs->pos, 1, 20);
    assert_pos(r, mul->lhs->lhs->member_pos, 1, 22);
    assert_string_equal(ast_describe(e), "a sum");
    assert_string_equal(ast_describe(mul->lhs), "a function call");
}

static void test_body_point_coord(void **state)
{
    Parsed *r = *state;
    const Program *prog = parse_ok(r,
        "body b phi = 1 x = r/2 y = 0\n"
        "body c\n"
        "point m y = 2\n"
        "coord q\n"
        "coord u = -1\n"
        "body body x = 0\n"           /* keywords are not reserved */
        "param axis = 1\n"
        "point length\n");
    assert_int_equal(prog->count, 8);
    const Stmt *s = nth_stmt(prog, 0);
    assert_string_equal(show(r, s->init[0]), "(/ r 2)");
    assert_string_equal(show(r, s->init[1]), "0");
    assert_string_equal(show(r, s->init[2]), "1");
    assert_pos(r, s->init_pos[2], 1, 8);
    assert_pos(r, s->init_pos[0], 1, 16);
    s = nth_stmt(prog, 1);
    assert_null(s->init[0]);
    assert_null(s->init[1]);
    assert_null(s->init[2]);
    s = nth_stmt(prog, 2);
    assert_int_equal(s->kind, STMT_POINT);
    assert_null(s->init[0]);
    assert_string_equal(show(r, s->init[1]), "2");
    s = nth_stmt(prog, 3);
    assert_int_equal(s->kind, STMT_COORD);
    assert_null(s->value);
    s = nth_stmt(prog, 4);
    assert_string_equal(show(r, s->value), "(neg 1)");
    s = nth_stmt(prog, 5);
    assert_int_equal(s->kind, STMT_BODY);
    assert_string_equal(s->name, "body");
    assert_string_equal(nth_stmt(prog, 6)->name, "axis");
    assert_string_equal(nth_stmt(prog, 7)->name, "length");
}

static void test_joints(void **state)
{
    Parsed *r = *state;
    const Program *prog = parse_ok(r,
        "prismatic P: ground a(1, 2) axis(ux, 0) angle = pi/2\n"     /* 0 */
        "distance D: a m length = 0.3 + 0.1*sin(t)\n"              /* 1 */
        "pointline L: ground(0, 1) m axis(1, 1)\n"                 /* 2 */
        "weld W: a b angle = 0.5\n"                                /* 3 */
        "weld W2: a b\n"                                           /* 4 */
        "constraint C: m.x^2 + m.y^2 = 1\n"                        /* 5 */
        "driver V: der(a.phi) = 2\n"                               /* 6 */
        "rolling R: wheel radius = 0.2\n"                          /* 7 */
        "knife K: cart(0.5, 0) axis(1, 0)\n"                       /* 8 */
        "velocity U: der(q) = der(m.x)\n"                          /* 9 */
        "prismatic Q: axis(0, 0) ground axis(1, 0)\n"              /* 10: a body named axis */
        "revolute O: ground crank\n");                             /* 11 */
    assert_int_equal(prog->count, 12);

    const Stmt *s = nth_stmt(prog, 0);
    assert_int_equal(s->joint, JOINT_PRISMATIC);
    assert_string_equal(s->attach[0].name, "ground");
    assert_false(s->attach[0].has_offset);
    assert_null(s->attach[0].sx);
    assert_string_equal(s->attach[1].name, "a");
    assert_true(s->attach[1].has_offset);
    assert_string_equal(show(r, s->axis[0]), "ux");
    assert_string_equal(show(r, s->option), "(/ 3.1415926535897931 2)");
    assert_pos(r, s->option_pos, 1, 41);
    assert_pos(r, s->axis_pos, 1, 29);

    s = nth_stmt(prog, 1);
    assert_int_equal(s->joint, JOINT_DISTANCE);
    assert_string_equal(show(r, s->option), "(+ 0.29999999999999999 (* 0.10000000000000001 (sin t)))");
    assert_pos(r, s->option_pos, 2, 17);

    s = nth_stmt(prog, 2);
    assert_int_equal(s->joint, JOINT_POINTLINE);
    assert_string_equal(show(r, s->attach[0].sy), "1");
    assert_string_equal(s->attach[1].name, "m");
    assert_string_equal(show(r, s->axis[1]), "1");

    s = nth_stmt(prog, 3);
    assert_int_equal(s->joint, JOINT_WELD);
    assert_string_equal(show(r, s->option), "0.5");
    assert_null(nth_stmt(prog, 4)->option);

    s = nth_stmt(prog, 5);
    assert_int_equal(s->joint, JOINT_CONSTRAINT);
    assert_string_equal(show(r, s->lhs), "(+ (^ m.x 2) (^ m.y 2))");
    assert_string_equal(show(r, s->rhs), "1");
    assert_pos(r, s->eq_pos, 6, 29);

    s = nth_stmt(prog, 6);
    assert_int_equal(s->joint, JOINT_DRIVER);
    assert_string_equal(show(r, s->lhs), "(der a.phi)");

    s = nth_stmt(prog, 7);
    assert_int_equal(s->joint, JOINT_ROLLING);
    assert_string_equal(s->attach[0].name, "wheel");
    assert_pos(r, s->attach[0].pos, 8, 12);
    assert_string_equal(show(r, s->option), "0.20000000000000001");
    assert_pos(r, s->option_pos, 8, 18);

    s = nth_stmt(prog, 8);
    assert_int_equal(s->joint, JOINT_KNIFE);
    assert_string_equal(s->attach[0].name, "cart");
    assert_string_equal(show(r, s->attach[0].sx), "0.5");
    assert_string_equal(show(r, s->axis[0]), "1");

    s = nth_stmt(prog, 9);
    assert_int_equal(s->joint, JOINT_VELOCITY);
    assert_string_equal(show(r, s->lhs), "(der q)");
    assert_string_equal(show(r, s->rhs), "(der m.x)");

    s = nth_stmt(prog, 10);
    assert_string_equal(s->attach[0].name, "axis");
    assert_string_equal(s->attach[1].name, "ground");
    assert_string_equal(show(r, s->axis[0]), "1");

    s = nth_stmt(prog, 11);
    assert_string_equal(s->attach[1].name, "crank");
    assert_false(s->attach[1].has_offset);
}

/* Byte-level details: CRLF, BOM, tabs, comments with UTF-8, no final newline. */
static void test_text_details(void **state)
{
    Parsed *r = *state;
    const Program *prog = parse_ok(r,
        "\xEF\xBB\xBF# caf\xC3\xA9 \x01 comment\r\n"
        "param\ta = 1\r\n"
        "\r\n"
        "   # indented comment\n"
        "param b = a # trailing\r\n"
        "param c = 2");
    assert_int_equal(prog->count, 3);
    assert_int_equal(prog->line_count, 6);
    assert_string_equal(nth_stmt(prog, 0)->name, "a");
    assert_string_equal(show(r, nth_stmt(prog, 1)->value), "a");
    assert_pos(r, nth_stmt(prog, 2)->pos, 6, 1);

    arena_free(&r->arena);
    prog = parse_ok(r, "param a = 1\n\n\n");
    assert_int_equal(prog->line_count, 3);
    assert_int_equal(prog->count, 1);
}

/* The token limit counts per statement, and a parse restores diag->escape. */
static void test_limits_per_statement(void **state)
{
    Parsed *r = *state;
    MechLimits lim = mech_default_limits();
    lim.max_expr_tokens = 10;
    const char *text = "param a = 1+1+1+1\nparam b = 1+1+1+1\n";    /* 10 tokens each */
    assert_true(parse_len(r, text, (int)strlen(text), &lim));

    lim = mech_default_limits();
    lim.max_depth = 3;
    text = "param a = (((sin(1))))\n";
    assert_false(parse_len(r, text, (int)strlen(text), &lim));
    text = "param a = (sin(-1))\n";
    assert_true(parse_len(r, text, (int)strlen(text), &lim));

    lim = mech_default_limits();
    lim.max_line_length = 11;               /* a line of exactly the limit passes */
    text = "param a = 1\r\nparam b = 2";
    assert_true(parse_len(r, text, (int)strlen(text), &lim));
    lim.max_file_bytes = (int)strlen(text); /* so does a file of exactly the limit */
    assert_true(parse_len(r, text, (int)strlen(text), &lim));

    /* a literal longer than the scanner's small buffer; and a text that is
       not NUL-terminated right after a number */
    char lit[256];
    snprintf(lit, sizeof lit, "param a = 0.%0150d1e151\n", 0);
    assert_true(parse_len(r, lit, (int)strlen(lit), NULL));
    assert_near(r->prog.first->value->num, 1.0, 1e-15, 0);
    assert_true(parse_len(r, "param a = 12345", 12, NULL));
    assert_near(r->prog.first->value->num, 12.0, 0, 0);

    jmp_buf outer;
    diag_init(&r->diag, "x", "param", 5);
    r->diag.escape = &outer;
    lim = mech_default_limits();
    assert_false(parse_program(&r->arena, &r->diag, &lim, &r->prog));
    assert_ptr_equal(r->diag.escape, &outer);
    assert_null(r->prog.first);
    assert_int_equal(r->prog.count, 0);
}

/* Exactly max_depth levels pass; one more fails. */
static void test_depth_boundary(void **state)
{
    Parsed *r = *state;
    MechLimits lim = mech_default_limits();
    char text[512];
    int n = lim.max_depth;
    snprintf(text, sizeof text, "param a = %.*s1%.*s\n", n,
             "((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((",
             n, "))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))");
    assert_true(parse_len(r, text, (int)strlen(text), &lim));
    snprintf(text, sizeof text, "param a = %.*s1%.*s\n", n + 1,
             "((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((",
             n + 1, "))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))))");
    assert_false(parse_len(r, text, (int)strlen(text), &lim));
    assert_int_equal(r->diag.col, 11 + n);
}

/* ---- bad input ---- */

typedef struct BadCase {
    const char *text;
    int len;                /* 0: strlen(text) */
    int line, col;
    const char *message;    /* a substring of the message */
    MechLimits limits;      /* fields left 0 take the defaults */
} BadCase;

static const BadCase bad_cases[] = {
    /* empty input */
    {"", 0, 1, 1, "the mechanism has no statements", {0}},
    {"# only a comment\n\n   \n", 0, 1, 1, "the mechanism has no statements", {0}},
    {"\xEF\xBB\xBF", 0, 1, 1, "the mechanism has no statements", {0}},
    /* statements */
    {"bdy crank\n", 0, 1, 1, "unknown statement 'bdy': expected mechanism, param", {0}},
    {"param r = 1\nParam s = 2\n", 0, 2, 1, "unknown statement 'Param'", {0}},
    {"= 1\n", 0, 1, 1, "expected a statement keyword at the start of the line, found '='", {0}},
    {"mechanism a\nmechanism b\n", 0, 2, 1, "a second 'mechanism' statement (the first is on line 1)", {0}},
    {"mechanism\n", 0, 1, 10, "expected a name after 'mechanism', found end of line", {0}},
    {"param r 0.1\n", 0, 1, 9, "expected '=' after 'param r', found '0.1'", {0}},
    {"param = 1\n", 0, 1, 7, "expected a name after 'param', found '='", {0}},
    {"param r = 1\nparam s # why\n", 0, 2, 9, "expected '=' after 'param s', found end of line", {0}},
    {"param r = 1 2\n", 0, 1, 13, "unexpected '2' after the end of the statement", {0}},
    {"coord q = 1 = 2\n", 0, 1, 13, "unexpected '=' after the end of the statement", {0}},
    {"coord q 1\n", 0, 1, 9, "unexpected '1' after the end of the statement", {0}},
    /* reserved names */
    {"param pi = 3\n", 0, 1, 7, "'pi' is a reserved name and cannot be declared", {0}},
    {"body t\n", 0, 1, 6, "'t' is a reserved name", {0}},
    {"point ground\n", 0, 1, 7, "'ground' is a reserved name", {0}},
    {"coord der = 1\n", 0, 1, 7, "'der' is a reserved name", {0}},
    {"param sin = 1\n", 0, 1, 7, "'sin' is a reserved name", {0}},
    {"revolute atan2: ground crank\n", 0, 1, 10, "'atan2' is a reserved name", {0}},
    {"mechanism tanh\n", 0, 1, 11, "'tanh' is a reserved name", {0}},
    {"revolute O: sin(0, 0) crank\n", 0, 1, 13, "found the reserved name 'sin'", {0}},
    /* functions */
    {"param r = sin(1, 2)\n", 0, 1, 18, "sin() takes 1 argument, found 2", {0}},
    {"param r = atan2(1)\n", 0, 1, 18, "atan2() takes 2 arguments, found 1", {0}},
    {"param r = atan2(1, 2, 3)\n", 0, 1, 23, "atan2() takes 2 arguments, found 3", {0}},
    {"param r = sqrt()\n", 0, 1, 16, "sqrt() takes 1 argument, found 0", {0}},
    {"param r = sin 1\n", 0, 1, 15, "expected '(' after the function name 'sin', found '1'", {0}},
    {"param r = cos\n", 0, 1, 14, "expected '(' after the function name 'cos', found end of line", {0}},
    {"param r = foo(1)\n", 0, 1, 11, "'foo' is not a function", {0}},
    {"param r = t(1)\n", 0, 1, 11, "'t' is not a function", {0}},
    {"param r = sin(1\n", 0, 1, 16, "expected ')' to close 'sin(' at column 14, found end of line", {0}},
    /* parentheses and operands */
    {"param r = (1 + 2\n", 0, 1, 17, "expected ')' to close the '(' at column 11, found end of line", {0}},
    {"param r = ((1 + 2) * 3\n", 0, 1, 23, "expected ')' to close the '(' at column 11", {0}},
    {"param r = 1 + 2)\n", 0, 1, 16, "unmatched ')'", {0}},
    {"param r = ()\n", 0, 1, 12, "expected an expression, found ')'", {0}},
    {"param r = *2\n", 0, 1, 11, "expected an expression, found '*'", {0}},
    {"param r =\n", 0, 1, 10, "expected an expression, found end of line", {0}},
    {"param r = 2^", 0, 1, 13, "expected an expression, found end of line", {0}},
    {"param r = 2 3\n", 0, 1, 13, "unexpected '3' after the end of the statement", {0}},
    {"param r = 2(3)\n", 0, 1, 12, "unexpected '(' after the end of the statement", {0}},
    {"param r = crank.\n", 0, 1, 17, "expected a member name after 'crank.', found end of line", {0}},
    {"param r = a.5\n", 0, 1, 13, "expected a member name after 'a.', found '5'", {0}},
    {"param r = .\n", 0, 1, 11, "expected an expression, found '.'", {0}},
    {"velocity V: der(2*x) = 0\n", 0, 1, 17, "expected a coordinate name in der(), found '2'", {0}},
    {"velocity V: der(t) = 0\n", 0, 1, 17, "expected a coordinate name in der(), found 't'", {0}},
    {"velocity V: der x = 0\n", 0, 1, 17, "expected '(' after 'der', found 'x'", {0}},
    {"velocity V: der(x + 1) = 0\n", 0, 1, 19, "expected ')' after the coordinate in der(), found '+'", {0}},
    /* numbers */
    {"param r = 1e\n", 0, 1, 11, "malformed number '1e'", {0}},
    {"param r = 1.2.3\n", 0, 1, 11, "malformed number '1.2.3'", {0}},
    {"param r = 12abc\n", 0, 1, 11, "malformed number '12abc'", {0}},
    {"param r = 0x10\n", 0, 1, 11, "malformed number '0x10'", {0}},
    {"param r = 1e+\n", 0, 1, 11, "malformed number '1e+'", {0}},
    {"param r = 2 * 3.5e-2x\n", 0, 1, 15, "malformed number '3.5e-2x'", {0}},
    {"param r = 1e400\n", 0, 1, 11, "number out of range: '1e400'", {0}},
    {"param r = -1e999 + 1\n", 0, 1, 12, "number out of range", {0}},
    /* bytes */
    {"param r = 1\nbody cr\xC3\xA4nk\n", 0, 2, 8, "non-ASCII byte 0xC3 outside a comment", {0}},
    {"param r = 1\n\xEF\xBB\xBFparam s = 2\n", 0, 2, 1, "non-ASCII byte 0xEF outside a comment", {0}},
    {"param r = 1\x07\n", 0, 1, 12, "control byte 0x07 outside a comment", {0}},
    {"param r = 1\x7F\n", 0, 1, 12, "control byte 0x7F outside a comment", {0}},
    {"param r = 1\0\n", 13, 1, 12, "control byte 0x00 outside a comment", {0}},
    {"param r = 1\rparam s = 2\n", 0, 1, 12, "carriage return (0x0D) not followed by a line feed", {0}},
    {"param r = 1 # ok\nparam s = 2 $\n", 0, 2, 13, "unexpected character '$'", {0}},
    {"param r = 1;\n", 0, 1, 12, "unexpected character ';'", {0}},
    /* body and point keys */
    {"body crank x = 1 x = 2\n", 0, 1, 18, "'x' given twice for body 'crank'", {0}},
    {"body crank z = 1\n", 0, 1, 12, "unknown key 'z' for body 'crank': expected x, y or phi", {0}},
    {"point m phi = 0\n", 0, 1, 9, "unknown key 'phi' for point 'm': expected x or y", {0}},
    {"body crank x 1\n", 0, 1, 14, "expected '=' after 'x', found '1'", {0}},
    {"body crank x = r/2 y = \n", 0, 1, 24, "expected an expression, found end of line", {0}},
    {"body crank x = 1, y = 2\n", 0, 1, 17, "unexpected ',' after the end of the statement", {0}},
    {"body = 1\n", 0, 1, 6, "expected a name after 'body', found '='", {0}},
    /* joints */
    {"revolute O ground crank\n", 0, 1, 12, "expected ':' after the joint name 'O', found 'ground'", {0}},
    {"revolute: ground crank\n", 0, 1, 9, "expected a name after 'revolute', found ':'", {0}},
    {"revolute O: ground\n", 0, 1, 19,
     "expected a body, point or ground as the second attachment of revolute 'O', found end of line", {0}},
    {"revolute O: (0, 0) crank\n", 0, 1, 13, "as the first attachment of revolute 'O', found '('", {0}},
    {"revolute O: ground(0 0) crank\n", 0, 1, 22,
     "expected ',' between the two components of the offset of 'ground', found '0'", {0}},
    {"revolute O: ground(0, 0 crank\n", 0, 1, 25,
     "expected ')' after the two components of the offset of 'ground', found 'crank'", {0}},
    {"revolute O: ground(0, 0, 0) crank\n", 0, 1, 24, "expected ')' after the two components", {0}},
    {"revolute O: ground(0, 0) crank axis(1, 0)\n", 0, 1, 32, "revolute joints take no 'axis'", {0}},
    {"revolute O: ground crank angle = 0\n", 0, 1, 26, "revolute joints take no 'angle'", {0}},
    {"revolute O: ground crank extra\n", 0, 1, 26, "unexpected 'extra' after the end of the statement", {0}},
    {"prismatic P: ground slider axis 1 0\n", 0, 1, 33, "expected '(' after the axis, found '1'", {0}},
    {"prismatic P: ground slider axis(1)\n", 0, 1, 34,
     "expected ',' between the two components of the axis, found ')'", {0}},
    {"prismatic P: ground slider axis(1, 0, 0)\n", 0, 1, 37,
     "expected ')' after the two components of the axis, found ','", {0}},
    {"prismatic P: ground slider axis = (1, 0)\n", 0, 1, 33, "expected '(' after the axis, found '='", {0}},
    {"prismatic P: ground slider\n", 0, 1, 27,
     "expected 'axis(ux, uy)' after the attachments of prismatic 'P', found end of line", {0}},
    {"prismatic P: ground axis(1, 0)\n", 0, 1, 31, "is one missing?", {0}},
    {"prismatic P: ground slider axis(1, 0) axis(0, 1)\n", 0, 1, 39, "'axis' given twice for prismatic 'P'", {0}},
    {"prismatic P: ground slider axis(1, 0) angle 0\n", 0, 1, 45, "expected '=' after 'angle', found '0'", {0}},
    {"prismatic P: ground slider axis(1, 0) length = 1\n", 0, 1, 39, "prismatic joints take no 'length'", {0}},
    {"pointline L: ground m\n", 0, 1, 22, "expected 'axis(ux, uy)' after the attachments of pointline 'L'", {0}},
    {"knife K: ground\n", 0, 1, 16, "expected 'axis(ux, uy)' after the attachments of knife 'K'", {0}},
    {"knife K:\n", 0, 1, 9, "expected a body as the attachment of knife 'K', found end of line", {0}},
    {"distance D: ground m\n", 0, 1, 21, "expected 'length = ...' for distance 'D', found end of line", {0}},
    {"distance D: ground m lenght = 1\n", 0, 1, 22, "expected 'length = ...' for distance 'D', found 'lenght'", {0}},
    {"distance D: a b length 2\n", 0, 1, 24, "expected '=' after 'length', found '2'", {0}},
    {"distance D: a b length = 1 length = 2\n", 0, 1, 28, "'length' given twice for distance 'D'", {0}},
    {"rolling W: wheel\n", 0, 1, 17, "expected 'radius = ...' for rolling 'W', found end of line", {0}},
    {"rolling W: wheel(0, 0) radius = 1\n", 0, 1, 17,
     "the body of rolling 'W' takes no offset: write 'wheel' alone", {0}},
    {"rolling W: wheel radius = 1 angle = 0\n", 0, 1, 29, "rolling joints take no 'angle'", {0}},
    {"weld W: a b angle = 0 angle = 1\n", 0, 1, 23, "'angle' given twice for weld 'W'", {0}},
    {"constraint C: x y = 1\n", 0, 1, 17,
     "expected '=' between the two sides of constraint 'C', found 'y'", {0}},
    {"driver D: crank.phi omega*t\n", 0, 1, 21, "expected '=' between the two sides of driver 'D'", {0}},
    {"driver D: crank.phi = omega*t = 1\n", 0, 1, 31, "unexpected '=' after the end of the statement", {0}},
    {"velocity V = der(q)\n", 0, 1, 12, "expected ':' after the joint name 'V', found '='", {0}},
    /* limits */
    {"param r = 1\nparam s = 1 + 2 + 3 + 4 + 5\n", 0, 2, 21, "line longer than the limit of 20 bytes",
     {.max_line_length = 20}},
    {"param r = 1\n# a comment that is far too long\n", 0, 2, 21, "line longer than the limit of 20 bytes",
     {.max_line_length = 20}},
    {"param r = 1 + 2 + 3 + 4 +\r\n", 0, 1, 21, "line longer than the limit of 20 bytes",
     {.max_line_length = 20}},
    {"param r = 1+1+1+1+1+1\n", 0, 1, 18, "statement longer than the limit of 10 tokens",
     {.max_expr_tokens = 10}},
    {"param r = 1\n", 0, 1, 11, "the file is larger than the limit of 10 bytes", {.max_file_bytes = 10}},
    {"param r = 2^2^2^2^2\n", 0, 1, 16, "expression nested deeper than the limit of 2 levels",
     {.max_depth = 2}},
    {"param r = ---1\n", 0, 1, 13, "nested deeper than the limit of 2 levels", {.max_depth = 2}},
    {"param r = sin(cos(tan(1)))\n", 0, 1, 22, "nested deeper than the limit of 2 levels", {.max_depth = 2}},
    {"revolute O: ground((1), (((2)))) crank\n", 0, 1, 27, "nested deeper than the limit of 3 levels",
     {.max_depth = 3}},
};

static MechLimits case_limits(const MechLimits *over)
{
    MechLimits lim = mech_default_limits();
    if (over->max_file_bytes) lim.max_file_bytes = over->max_file_bytes;
    if (over->max_line_length) lim.max_line_length = over->max_line_length;
    if (over->max_depth) lim.max_depth = over->max_depth;
    if (over->max_expr_tokens) lim.max_expr_tokens = over->max_expr_tokens;
    return lim;
}

static void check_bad(Parsed *r, const char *text, int len, const MechLimits *lim,
                      int line, int col, const char *message, const char *what)
{
    arena_free(&r->arena);
    if (parse_len(r, text, len, lim))
        fail_msg("%s: parsed without error", what);
    bool ok = r->diag.failed && r->diag.has_pos && r->diag.line == line
              && r->diag.col == col && strstr(r->diag.message, message) != NULL;
    if (!ok) {
        diag_print(&r->diag, stderr);
        fail_msg("%s: got %d:%d \"%s\", expected %d:%d \"...%s...\"", what, r->diag.line,
                 r->diag.col, r->diag.message, line, col, message);
    }
    /* first letter lowercase, no trailing newline or period */
    size_t n = strlen(r->diag.message);
    assert_true(n > 0);
    if (!(r->diag.message[0] >= 'a' && r->diag.message[0] <= 'z') && r->diag.message[0] != '\'')
        fail_msg("%s: message does not start in lower case: %s", what, r->diag.message);
    assert_true(r->diag.message[n - 1] != '\n' && r->diag.message[n - 1] != '.');
}

static void test_bad_inputs(void **state)
{
    Parsed *r = *state;
    size_t n = sizeof bad_cases / sizeof bad_cases[0];
    for (size_t i = 0; i < n; i++) {
        const BadCase *c = &bad_cases[i];
        MechLimits lim = case_limits(&c->limits);
        char what[64];
        snprintf(what, sizeof what, "bad case %zu", i);
        check_bad(r, c->text, c->len ? c->len : (int)strlen(c->text), &lim, c->line, c->col,
                  c->message, what);
    }
    print_message("%zu bad inputs checked\n", n);
}

/* 100000 '(' : with default limits the line is too long; with the line and
   token limits lifted, the depth limit stops it at the 65th '('. */
static void test_deep_nesting(void **state)
{
    Parsed *r = *state;
    enum { N = 100000 };
    char *text = malloc(N + 64);
    strcpy(text, "param r = ");
    memset(text + 10, '(', N);
    strcpy(text + 10 + N, "1\n");
    int len = (int)strlen(text);

    MechLimits lim = mech_default_limits();
    check_bad(r, text, len, &lim, 1, 4097, "line longer than the limit of 4096 bytes", "deep/default");

    lim.max_line_length = 1 << 20;
    lim.max_expr_tokens = 1 << 20;
    check_bad(r, text, len, &lim, 1, 11 + 64, "expression nested deeper than the limit of 64 levels",
              "deep/parens");

    memset(text + 10, '-', N);
    check_bad(r, text, len, &lim, 1, 11 + 64, "nested deeper", "deep/minus");

    for (int i = 0; i < N; i += 2) {       /* 1^1^1^... */
        text[10 + i] = '1';
        text[11 + i] = '^';
    }
    check_bad(r, text, len, &lim, 1, 11 + 2 * 64 + 1, "nested deeper", "deep/power");

    for (int i = 0; i < N; i += 4)         /* sin(sin(... */
        memcpy(text + 10 + i, "sin(", 4);
    check_bad(r, text, len, &lim, 1, 11 + 4 * 64 + 3, "nested deeper", "deep/calls");

    lim.max_depth = 1 << 20;                /* only the token limit is left */
    lim.max_expr_tokens = 5000;
    memset(text + 10, '(', N);
    check_bad(r, text, len, &lim, 1, 11 + 4997, "statement longer than the limit of 5000 tokens",
              "deep/tokens");
    free(text);
}

/* A long flat sum is not nesting: only the token limit applies. */
static void test_long_flat_expression(void **state)
{
    Parsed *r = *state;
    enum { N = 1500 };
    char *text = malloc(4 * N + 64);
    strcpy(text, "param r = 1");
    for (int i = 0; i < N; i++)
        strcat(text, i % 2 ? "+1" : "*1");
    strcat(text, "\n");
    MechLimits lim = mech_default_limits();
    lim.max_line_length = 1 << 20;
    lim.max_expr_tokens = 1 << 20;
    assert_true(parse_len(r, text, (int)strlen(text), &lim));
    assert_int_equal(r->prog.count, 1);
    free(text);
}

/* A spatial file: the flag, bodies with z and orient, three-component
   offsets, two axes in any order with the option, angle() in expressions. */
static void test_spatial(void **state)
{
    Parsed *r = *state;
    const Program *prog = parse_ok(r,
        "mechanism m\n"
        "spatial\n"                                                      /* 1 */
        "body b x = 1 z = -2 orient = zyx(0.1, 0.2, pi)\n"               /* 2 */
        "point p y = 3 z = 4\n"                                          /* 3 */
        "revolute R: ground(1, 2, 3) b(0, 0, 1) axis(0, 0, 1) axis(1, 0, 0)\n" /* 4 */
        "rolling D: b radius = 0.5 axis(0, 1, 0)\n"                      /* 5 */
        "driver A: angle(R) = 2*t\n");                                   /* 6 */
    assert_true(prog->spatial);
    assert_int_equal(nth_stmt(prog, 1)->kind, STMT_SPATIAL);
    const Stmt *b = nth_stmt(prog, 2);
    assert_string_equal(show(r, b->init[0]), "1");
    assert_null(b->init[1]);
    assert_string_equal(show(r, b->init[2]), "(neg 2)");
    assert_int_equal(b->orient, ORIENT_ZYX);
    assert_string_equal(show(r, b->orient_arg[2]), "3.1415926535897931");
    assert_pos(r, b->orient_pos, 3, 21);
    assert_string_equal(show(r, nth_stmt(prog, 3)->init[2]), "4");
    const Stmt *j = nth_stmt(prog, 4);
    assert_int_equal(j->joint, JOINT_S_REVOLUTE);
    assert_string_equal(show(r, j->attach[0].sz), "3");
    assert_string_equal(show(r, j->attach[1].sz), "1");
    assert_string_equal(show(r, j->axis[2]), "1");
    assert_string_equal(show(r, j->axis_b[0]), "1");
    assert_pos(r, j->axis_b_pos, 5, 54);
    const Stmt *d = nth_stmt(prog, 5);
    assert_int_equal(d->joint, JOINT_S_ROLLING);
    assert_string_equal(show(r, d->option), "0.5");
    assert_string_equal(show(r, d->axis[1]), "1");
    assert_string_equal(show(r, nth_stmt(prog, 6)->lhs), "(angle R)");
    /* without `spatial`, angle(...) is no construct and revolute is planar */
    arena_free(&r->arena);
    prog = parse_ok(r, "revolute R: ground(1, 2) b\n");
    assert_false(prog->spatial);
    assert_int_equal(prog->first->joint, JOINT_REVOLUTE);
}

static void test_joint_table(void **state)
{
    (void)state;
    assert_int_equal(joint_kind_from_keyword("revolute", 8), JOINT_REVOLUTE);
    assert_int_equal(joint_kind_from_keyword("velocity", 8), JOINT_VELOCITY);
    assert_int_equal(joint_kind_from_keyword("revolutex", 8), JOINT_REVOLUTE);  /* length counts */
    assert_int_equal(joint_kind_from_keyword("revolut", 7), -1);
    assert_int_equal(joint_kind_from_keyword("body", 4), -1);
    assert_int_equal(joint_info[JOINT_PRISMATIC].attachments, 2);
    assert_true(joint_info[JOINT_PRISMATIC].axis);
    assert_int_equal(joint_info[JOINT_ROLLING].slot[0], ATTACH_BODY_ONLY);
    assert_int_equal(joint_info[JOINT_WELD].rows, 3);
    assert_string_equal(joint_info[JOINT_WELD].suffix[2], ".phi");
    assert_null(joint_info[JOINT_DISTANCE].suffix[1]);
    assert_int_equal(joint_info[JOINT_DRIVER].level, LEVEL_EITHER);
    for (int k = 0; k < JOINT_KIND_COUNT; k++) {
        const char *kw = joint_info[k].keyword;
        if (joint_info[k].dim == DIM_INTERNAL) {     /* rows the model adds: no statement */
            assert_int_equal(joint_kind_lookup(kw, (int)strlen(kw), false), -1);
            assert_int_equal(joint_kind_lookup(kw, (int)strlen(kw), true), -1);
            continue;
        }
        bool spatial = joint_info[k].dim == DIM_SPATIAL;
        assert_int_equal(joint_kind_lookup(kw, (int)strlen(kw), spatial), k);
        assert_true(joint_info[k].rows <= JOINT_MAX_ROWS);
        assert_non_null(joint_info[k].suffix[joint_info[k].rows - 1]);
    }
    /* one keyword, two kinds: the file's dimension picks */
    assert_int_equal(joint_kind_lookup("revolute", 8, true), JOINT_S_REVOLUTE);
    assert_int_equal(joint_kind_lookup("weld", 4, true), JOINT_S_WELD);
    assert_int_equal(joint_kind_lookup("driver", 6, true), JOINT_DRIVER);
    assert_int_equal(joint_kind_lookup("prismatic", 9, true), -1);
    assert_int_equal(joint_kind_lookup("spherical", 9, false), -1);
    assert_int_equal(joint_info[JOINT_S_REVOLUTE].rows, 5);
    assert_string_equal(joint_info[JOINT_S_WELD].suffix[5], ".zx");
    assert_int_equal(joint_info[JOINT_S_UNIVERSAL].axis, 2);
}

/* Reads a file of the repository (from the root or from tests/) into buf. */
static void read_repo_file(const char *path, char *buf, size_t size)
{
    char alt[256];
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        snprintf(alt, sizeof alt, "../%s", path);
        fp = fopen(alt, "rb");
    }
    if (!fp)
        fail_msg("cannot open %s (run from the repository root)", path);
    size_t n = fread(buf, 1, size - 1, fp);
    fclose(fp);
    if (n == size - 1)
        fail_msg("%s is longer than the test's buffer", path);
    buf[n] = '\0';
}

/* Every joints.def kind is used in all_statements.mech (planar) or
   all_spatial.mech (spatial), the files the jit/generic/aot and
   finite-difference agreement tests compile (and the fuzzer's seeds: make
   fuzz takes every example), so a new kind cannot go untested. Rows the
   model adds itself (DIM_INTERNAL) come with every spatial body and
   rolling disk. */
static void test_all_statements_has_every_kind(void **state)
{
    Parsed *r = *state;
    static const char *const files[] = {"examples/all_statements.mech",
                                        "examples/all_spatial.mech"};
    static char text[1 << 16];
    for (size_t f = 0; f < sizeof files / sizeof *files; f++) {
        read_repo_file(files[f], text, sizeof text);
        const Program *prog = parse_ok(r, text);
        bool seen[JOINT_KIND_COUNT] = {false};
        for (const Stmt *st = prog->first; st; st = st->next)
            if (st->kind == STMT_JOINT)
                seen[st->joint] = true;
        for (int k = 0; k < JOINT_KIND_COUNT; k++)
            if (!seen[k] && joint_kind_in((JointKind)k, prog->spatial))
                fail_msg("%s has no '%s' statement", files[f], joint_info[k].keyword);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_spec_example, setup, teardown),
        cmocka_unit_test_setup_teardown(test_precedence, setup, teardown),
        cmocka_unit_test_setup_teardown(test_primaries, setup, teardown),
        cmocka_unit_test_setup_teardown(test_positions, setup, teardown),
        cmocka_unit_test_setup_teardown(test_body_point_coord, setup, teardown),
        cmocka_unit_test_setup_teardown(test_joints, setup, teardown),
        cmocka_unit_test_setup_teardown(test_text_details, setup, teardown),
        cmocka_unit_test_setup_teardown(test_limits_per_statement, setup, teardown),
        cmocka_unit_test_setup_teardown(test_depth_boundary, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bad_inputs, setup, teardown),
        cmocka_unit_test_setup_teardown(test_deep_nesting, setup, teardown),
        cmocka_unit_test_setup_teardown(test_long_flat_expression, setup, teardown),
        cmocka_unit_test_setup_teardown(test_spatial, setup, teardown),
        cmocka_unit_test(test_joint_table),
        cmocka_unit_test_setup_teardown(test_all_statements_has_every_kind, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
