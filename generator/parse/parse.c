/* parse.c - recursive-descent parser for .mech files (spec section 2).

   One statement per line; the first word of a line names the statement.
   Expressions are parsed by precedence climbing over a priority table, in
   the manner of Lua's lparser.c subexpr: each binary operator has a left and
   a right priority, and an operator is taken while its left priority exceeds
   the caller's limit. Nesting (parentheses, calls, unary operators and the
   right operand of '^', the only unbounded recursions) is counted against
   limits->max_depth, and tokens per statement against max_expr_tokens, so
   hostile input ends in an error, never a stack overflow.

   Errors go through diag_fail to the jmp_buf set by parse_program (style
   R3). The parser checks syntax, reserved words and limits only; names are
   resolved by the model builder from the positions recorded here. */
#include "parse.h"

#include "../lex/lex.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define PARSE_PI 3.14159265358979323846

typedef struct Parser {
    Arena *arena;
    Diag *diag;
    const MechLimits *limits;
    Lexer lx;
    Token tok;              /* the current token */
    int depth;              /* expression nesting */
    int stmt_tokens;        /* tokens read in the current statement */
    int mechanism_line;     /* line of the mechanism statement, 0 if none */
    bool spatial;           /* after a `spatial` statement */
    int spatial_line;       /* its line, 0 if none */
    bool begun;             /* a statement other than `mechanism` was read */
} Parser;

/* ---- tokens and errors ---- */

/* Fails at the current token with "expected WHAT, found TOKEN". */
static _Noreturn void expected(Parser *p, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static _Noreturn void expected(Parser *p, const char *fmt, ...)
{
    char what[DIAG_MESSAGE_MAX], buf[LEX_DESCRIBE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    diag_fail(p->diag, p->tok.pos, "expected %s, found %s", what,
              lex_describe(&p->tok, buf));
}

static void advance(Parser *p)
{
    if (p->tok.kind == TOK_NEWLINE)
        p->stmt_tokens = 0;     /* a new line starts a new statement */
    p->tok = lex_next(&p->lx);
    if (p->tok.kind != TOK_NEWLINE && p->tok.kind != TOK_EOF
        && ++p->stmt_tokens > p->limits->max_expr_tokens)
        diag_fail(p->diag, p->tok.pos, "statement longer than the limit of %d tokens",
                  p->limits->max_expr_tokens);
}

static bool at_end(const Parser *p)
{
    return p->tok.kind == TOK_NEWLINE || p->tok.kind == TOK_EOF;
}

static int column_of(const Parser *p, SrcPos pos)
{
    int line, col;
    diag_locate(p->diag, pos.offset, &line, &col);
    return col;
}

static char *token_text(Parser *p, const Token *tok)
{
    return arena_strndup(p->arena, tok->start, (size_t)tok->len);
}

/* The reserved words of spec section 2: never declarable. */
static bool is_reserved(const Token *tok)
{
    static const char *const words[] = {"ground", "t", "pi", "der"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
        if (lex_is_word(tok, words[i]))
            return true;
    int op = dag_function_from_name(tok->start, tok->len);
    return op >= 0 && dag_op_is_function((DagOp)op);
}

/* name = IDENT, not reserved; a name being declared by 'after' */
static const char *declared_name(Parser *p, const char *after, SrcPos *pos)
{
    if (p->tok.kind != TOK_IDENT)
        expected(p, "a name after '%s'", after);
    if (is_reserved(&p->tok))
        diag_fail(p->diag, p->tok.pos, "'%.*s' is a reserved name and cannot be declared",
                  p->tok.len, p->tok.start);
    /* names become C string literals (row and coordinate names) */
    if (p->tok.len > p->limits->max_name_length)
        diag_fail(p->diag, p->tok.pos, "name longer than the limit of %d characters",
                  p->limits->max_name_length);
    *pos = p->tok.pos;
    const char *name = token_text(p, &p->tok);
    advance(p);
    return name;
}

/* Every statement ends with its line. */
static void expect_end(Parser *p)
{
    char buf[LEX_DESCRIBE_MAX];
    if (at_end(p))
        return;
    if (p->tok.kind == TOK_RPAREN)
        diag_fail(p->diag, p->tok.pos, "unmatched ')'");
    diag_fail(p->diag, p->tok.pos, "unexpected %s after the end of the statement",
              lex_describe(&p->tok, buf));
}

/* ---- expressions ---- */

static Ast *new_ast(Parser *p, AstKind kind, SrcPos pos)
{
    Ast *ast = arena_alloc(p->arena, sizeof *ast);
    ast->kind = kind;
    ast->pos = pos;
    return ast;
}

static void enter_level(Parser *p, SrcPos pos)
{
    if (++p->depth > p->limits->max_depth)
        diag_fail(p->diag, pos, "expression nested deeper than the limit of %d levels",
                  p->limits->max_depth);
}

static void leave_level(Parser *p) { p->depth--; }

static Ast *subexpr(Parser *p, int limit);

/* expr = subexpr(0) */
static Ast *expr(Parser *p) { return subexpr(p, 0); }

/* Binary operators: left and right priority (Lua lparser.c priority[]).
   '^' has right < left, so a chain nests to the right; its left priority is
   above UNARY_PRIORITY, so -x^2 is -(x^2), while -a*b is (-a)*b. */
typedef struct BinaryPriority {
    TokKind tok;
    DagOp op;
    int left, right;
} BinaryPriority;

static const BinaryPriority binary_priority[] = {
    {TOK_PLUS, OP_ADD, 10, 10},
    {TOK_MINUS, OP_SUB, 10, 10},
    {TOK_STAR, OP_MUL, 11, 11},
    {TOK_SLASH, OP_DIV, 11, 11},
    {TOK_CARET, OP_POW, 14, 13},
};

enum { UNARY_PRIORITY = 12 };

static const BinaryPriority *binary_op(TokKind kind)
{
    for (size_t i = 0; i < sizeof binary_priority / sizeof binary_priority[0]; i++)
        if (binary_priority[i].tok == kind)
            return &binary_priority[i];
    return NULL;
}

/* coordinate = NAME ['.' NAME]   (the operand of der) */
static Ast *coordinate(Parser *p)
{
    if (p->tok.kind != TOK_IDENT || is_reserved(&p->tok))
        expected(p, "a coordinate name in der()");
    Token name = p->tok;
    advance(p);
    if (p->tok.kind != TOK_DOT) {
        Ast *ast = new_ast(p, AST_NAME, name.pos);
        ast->name = token_text(p, &name);
        return ast;
    }
    advance(p);
    if (p->tok.kind != TOK_IDENT)
        expected(p, "a coordinate name after '%.*s.'", name.len, name.start);
    Ast *ast = new_ast(p, AST_MEMBER, name.pos);
    ast->name = token_text(p, &name);
    ast->member = token_text(p, &p->tok);
    ast->member_pos = p->tok.pos;
    advance(p);
    return ast;
}


/* slide = 'slide' '(' NAME ')'   (NAME: a prismatic or pointline joint,
   resolved by the model; slide is no reserved word, only this form is);
   angle = 'angle' '(' NAME ')' in a spatial file is read the same way */
static Ast *slide(Parser *p, const Token *word)
{
    Ast *ast = new_ast(p, AST_SLIDE, word->pos);
    advance(p);
    if (p->tok.kind != TOK_IDENT)
        expected(p, "a joint name in %.*s(...)", word->len, word->start);
    ast->name = token_text(p, &p->tok);
    ast->member_pos = p->tok.pos;
    advance(p);
    if (p->tok.kind != TOK_RPAREN)
        expected(p, "')' after the joint name in %.*s(%s", word->len, word->start, ast->name);
    advance(p);
    return ast;
}

/* der = 'der' '(' coordinate ')' */
static Ast *derivative(Parser *p)
{
    Ast *ast = new_ast(p, AST_DER, p->tok.pos);
    advance(p);
    if (p->tok.kind != TOK_LPAREN)
        expected(p, "'(' after 'der'");
    enter_level(p, p->tok.pos);
    advance(p);
    ast->lhs = coordinate(p);
    if (p->tok.kind != TOK_RPAREN)
        expected(p, "')' after the coordinate in der()");
    advance(p);
    leave_level(p);
    return ast;
}

/* call = FUNCTION '(' [expr {',' expr}] ')'   with exactly the function's arity */
static Ast *call(Parser *p, DagOp op)
{
    const DagOpInfo *info = &dag_op_info[op];
    Ast *ast = new_ast(p, AST_CALL, p->tok.pos);
    ast->op = op;
    advance(p);
    if (p->tok.kind != TOK_LPAREN)
        expected(p, "'(' after the function name '%s'", info->spelling);
    SrcPos open = p->tok.pos;
    enter_level(p, open);
    advance(p);
    int n = 0;
    SrcPos excess = {0};
    if (p->tok.kind != TOK_RPAREN) {
        for (;;) {
            SrcPos arg_pos = p->tok.pos;
            Ast *arg = expr(p);
            if (n == 0)
                ast->lhs = arg;
            else if (n == 1)
                ast->rhs = arg;
            if (n == info->arity)
                excess = arg_pos;
            n++;
            if (p->tok.kind != TOK_COMMA)
                break;
            advance(p);
        }
    }
    if (p->tok.kind != TOK_RPAREN)
        expected(p, "')' to close '%s(' at column %d", info->spelling, column_of(p, open));
    SrcPos close = p->tok.pos;
    if (n != info->arity)
        diag_fail(p->diag, n > info->arity ? excess : close,
                  "%s() takes %d argument%s, found %d", info->spelling, info->arity,
                  info->arity == 1 ? "" : "s", n);
    advance(p);
    leave_level(p);
    return ast;
}

/* primary = NUMBER | 'pi' | 't' | NAME ['.' NAME] | call | der | '(' expr ')' */
static Ast *primary(Parser *p)
{
    Token tok = p->tok;
    if (tok.kind == TOK_NUMBER) {
        Ast *ast = new_ast(p, AST_NUM, tok.pos);
        ast->num = tok.num;
        advance(p);
        return ast;
    }
    if (tok.kind == TOK_LPAREN) {
        enter_level(p, tok.pos);
        advance(p);
        Ast *ast = expr(p);
        if (p->tok.kind != TOK_RPAREN)
            expected(p, "')' to close the '(' at column %d", column_of(p, tok.pos));
        advance(p);
        leave_level(p);
        return ast;
    }
    if (tok.kind != TOK_IDENT)
        expected(p, "an expression");
    int op = dag_function_from_name(tok.start, tok.len);
    if (op >= 0 && dag_op_is_function((DagOp)op))
        return call(p, (DagOp)op);
    if (lex_is_word(&tok, "der"))
        return derivative(p);
    advance(p);
    if (p->tok.kind == TOK_LPAREN && lex_is_word(&tok, "slide"))
        return slide(p, &tok);
    if (p->tok.kind == TOK_LPAREN && p->spatial && lex_is_word(&tok, "angle")) {
        Ast *ast = slide(p, &tok);
        ast->kind = AST_ANGLE;
        return ast;
    }
    if (p->tok.kind == TOK_LPAREN)
        diag_fail(p->diag, tok.pos, "'%.*s' is not a function", tok.len, tok.start);
    Ast *ast;
    if (lex_is_word(&tok, "pi")) {
        ast = new_ast(p, AST_NUM, tok.pos);
        ast->num = PARSE_PI;
    } else if (lex_is_word(&tok, "t")) {
        ast = new_ast(p, AST_TIME, tok.pos);
    } else if (p->tok.kind == TOK_DOT) {
        advance(p);
        if (p->tok.kind != TOK_IDENT)
            expected(p, "a member name after '%.*s.'", tok.len, tok.start);
        ast = new_ast(p, AST_MEMBER, tok.pos);
        ast->name = token_text(p, &tok);
        ast->member = token_text(p, &p->tok);
        ast->member_pos = p->tok.pos;
        advance(p);
    } else {
        ast = new_ast(p, AST_NAME, tok.pos);
        ast->name = token_text(p, &tok);
    }
    return ast;
}

/* subexpr = ('-' | '+') subexpr(UNARY_PRIORITY) {binop subexpr(right)}
           | primary {binop subexpr(right)}
   taking each binop only while its left priority exceeds limit. An
   expression ends at the first token that cannot continue it, so
   "x = r/2 y = 0" splits after the 2. */
static Ast *subexpr(Parser *p, int limit)
{
    Ast *ast;
    if (p->tok.kind == TOK_MINUS || p->tok.kind == TOK_PLUS) {
        Token sign = p->tok;
        enter_level(p, sign.pos);
        advance(p);
        Ast *operand = subexpr(p, UNARY_PRIORITY);
        leave_level(p);
        if (sign.kind == TOK_PLUS) {
            ast = operand;      /* unary plus is dropped */
        } else {
            ast = new_ast(p, AST_NEG, sign.pos);
            ast->lhs = operand;
        }
    } else {
        ast = primary(p);
    }
    for (;;) {
        const BinaryPriority *bin = binary_op(p->tok.kind);
        if (!bin || bin->left <= limit)
            return ast;
        Ast *node = new_ast(p, AST_BINARY, p->tok.pos);
        node->op = bin->op;
        node->lhs = ast;
        bool nests = bin->right < bin->left;    /* '^' chains recurse */
        if (nests)
            enter_level(p, p->tok.pos);
        advance(p);
        node->rhs = subexpr(p, bin->right);
        if (nests)
            leave_level(p);
        ast = node;
    }
}

/* ---- statements ---- */

static const char *option_keyword(JointOption opt)
{
    switch (opt) {
    case OPTION_NONE:   return NULL;
    case OPTION_ANGLE:  return "angle";
    case OPTION_LENGTH: return "length";
    case OPTION_RADIUS: return "radius";
    }
    return NULL;
}

static const char *attach_noun(AttachRule rule)
{
    switch (rule) {
    case ATTACH_NONE:      return "nothing";
    case ATTACH_ANY:       return "a body, point or ground";
    case ATTACH_FRAME:     return "a body or ground";
    case ATTACH_BODY:      return "a body";
    case ATTACH_BODY_ONLY: return "a body";
    }
    return "an attachment";
}

/* pair = '(' expr ',' expr ')'   (an offset or an axis; what names it) */
static void pair(Parser *p, const char *what, Ast **a, Ast **b)
{
    if (p->tok.kind != TOK_LPAREN)
        expected(p, "'(' after %s", what);
    enter_level(p, p->tok.pos);
    advance(p);
    *a = expr(p);
    if (p->tok.kind != TOK_COMMA)
        expected(p, "',' between the two components of %s", what);
    advance(p);
    *b = expr(p);
    if (p->tok.kind != TOK_RPAREN)
        expected(p, "')' after the two components of %s", what);
    advance(p);
    leave_level(p);
}

/* components = '(' expr {',' expr} ')'   with exactly n expressions: a
   spatial offset, axis or orientation; what names it in messages */
static void components(Parser *p, const char *what, int n, Ast **out)
{
    static const char *const count[] = {"no", "one", "two", "three", "four"};
    if (p->tok.kind != TOK_LPAREN)
        expected(p, "'(' after %s", what);
    enter_level(p, p->tok.pos);
    advance(p);
    int i = 0;
    for (;;) {
        SrcPos at = p->tok.pos;
        Ast *e = expr(p);
        if (i == n)
            diag_fail(p->diag, at, "%s has %s components, found more", what, count[n]);
        out[i++] = e;
        if (p->tok.kind != TOK_COMMA)
            break;
        advance(p);
    }
    if (p->tok.kind != TOK_RPAREN)
        expected(p, "',' or ')' in %s", what);
    if (i < n)
        diag_fail(p->diag, p->tok.pos, "%s has %s components, found %s", what, count[n],
                  count[i]);
    advance(p);
    leave_level(p);
}

/* An offset: (sx, sy), or (sx, sy, sz) in a spatial file. */
static void offset(Parser *p, const char *what, AstAttach *a)
{
    if (!p->spatial) {
        pair(p, what, &a->sx, &a->sy);
        return;
    }
    Ast *c[3];
    components(p, what, 3, c);
    a->sx = c[0], a->sy = c[1], a->sz = c[2];
}

/* attachment = NAME [pair]   (NAME may be ground; a body-only slot takes no pair) */
static void attachment(Parser *p, Stmt *s, int slot)
{
    const JointInfo *info = &joint_info[s->joint];
    AttachRule rule = info->slot[slot];
    const char *nth = info->attachments == 1 ? "" : slot == 0 ? "first " : "second ";
    char buf[LEX_DESCRIBE_MAX];
    if (p->tok.kind != TOK_IDENT)
        expected(p, "%s as the %sattachment of %s '%s'", attach_noun(rule), nth,
                 info->keyword, s->name);
    if (is_reserved(&p->tok) && !lex_is_word(&p->tok, "ground"))
        diag_fail(p->diag, p->tok.pos,
                  "expected %s as the %sattachment of %s '%s', found the reserved name %s",
                  attach_noun(rule), nth, info->keyword, s->name,
                  lex_describe(&p->tok, buf));
    AstAttach *a = &s->attach[slot];
    a->name = token_text(p, &p->tok);
    a->pos = p->tok.pos;
    advance(p);
    if (p->tok.kind != TOK_LPAREN)
        return;
    if (rule == ATTACH_BODY_ONLY)
        diag_fail(p->diag, p->tok.pos, "the body of %s '%s' takes no offset: write '%s' alone",
                  info->keyword, s->name, a->name);
    char what[DIAG_MESSAGE_MAX];
    snprintf(what, sizeof what, "the offset of '%s'", a->name);
    a->has_offset = true;
    offset(p, what, a);
}

/* axis = 'axis' pair */
static void axis(Parser *p, Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    if (!lex_is_word(&p->tok, "axis")) {
        const AstAttach *last = &s->attach[info->attachments - 1];
        if (at_end(p) && last->has_offset && strcmp(last->name, "axis") == 0)
            diag_fail(p->diag, p->tok.pos, "expected 'axis(ux, uy)' after the attachments "
                      "of %s '%s', found end of line ('axis(...)' was taken as an "
                      "attachment: is one missing?)", info->keyword, s->name);
        expected(p, "'axis(ux, uy)' after the attachments of %s '%s'", info->keyword, s->name);
    }
    s->axis_pos = p->tok.pos;
    advance(p);
    pair(p, "the axis", &s->axis[0], &s->axis[1]);
}

/* option = KEYWORD '=' expr   (length and radius required, angle optional) */
static void option(Parser *p, Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    const char *word = option_keyword(info->option);
    if (!word)
        return;
    if (lex_is_word(&p->tok, word)) {
        s->option_pos = p->tok.pos;
        advance(p);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' after '%s'", word);
        advance(p);
        s->option = expr(p);
    } else if (info->option != OPTION_ANGLE) {
        expected(p, "'%s = ...' for %s '%s'", word, info->keyword, s->name);
    }
}

/* After a joint's operands: a keyword the kind does not take, or takes
   once, gets its own message instead of "unexpected ...". */
static void reject_extra_keyword(Parser *p, const Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    if (p->tok.kind != TOK_IDENT)
        return;
    static const JointOption options[] = {OPTION_ANGLE, OPTION_LENGTH, OPTION_RADIUS};
    bool has;
    if (lex_is_word(&p->tok, "axis")) {
        has = info->axis;
    } else {
        size_t i = 0, n = sizeof options / sizeof options[0];
        while (i < n && !lex_is_word(&p->tok, option_keyword(options[i])))
            i++;
        if (i == n)
            return;
        has = info->option == options[i];
    }
    if (has)
        diag_fail(p->diag, p->tok.pos, "'%.*s' given twice for %s '%s'", p->tok.len,
                  p->tok.start, info->keyword, s->name);
    diag_fail(p->diag, p->tok.pos, "%s joints take no '%.*s'", info->keyword,
              p->tok.len, p->tok.start);
}

/* A spatial joint's keywords after its attachments, in any order:
   axis(ux, uy, uz) for A, a second axis(...) for B (default: the same
   local vector as A's), and the kind's option. */
static void spatial_tail(Parser *p, Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    const char *word = option_keyword(info->option);
    int naxes = 0;
    while (p->tok.kind == TOK_IDENT) {
        if (lex_is_word(&p->tok, "axis") && info->axis && naxes < 2) {
            SrcPos *pos = naxes == 0 ? &s->axis_pos : &s->axis_b_pos;
            *pos = p->tok.pos;
            advance(p);
            components(p, naxes == 0 ? "the axis (A's)" : "B's axis", 3,
                       naxes == 0 ? s->axis : s->axis_b);
            naxes++;
        } else if (word && lex_is_word(&p->tok, word) && !s->option) {
            option(p, s);
        } else if (lex_is_word(&p->tok, "axis") && naxes == 2) {
            diag_fail(p->diag, p->tok.pos, "%s '%s' takes at most two axes (A's, then B's)",
                      info->keyword, s->name);
        } else {
            reject_extra_keyword(p, s);
            break;
        }
    }
    if (info->axis && naxes == 0)
        expected(p, "'axis(ux, uy, uz)' after the attachments of %s '%s'", info->keyword,
                 s->name);
    if (info->axis == 2 && naxes == 1)
        expected(p, "B's axis: %s '%s' takes two axes, 'axis(...) axis(...)'", info->keyword,
                 s->name);
    if (word && !s->option && info->option != OPTION_ANGLE)
        expected(p, "'%s = ...' for %s '%s'", word, info->keyword, s->name);
}

/* joint = KIND NAME ':' attachment{n} [axis] [option]   (n = attachments > 0)
         | KIND NAME ':' expr '=' expr                    (n = 0) */
static void joint(Parser *p, Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    s->name = declared_name(p, info->keyword, &s->name_pos);
    if (p->tok.kind != TOK_COLON)
        expected(p, "':' after the joint name '%s'", s->name);
    advance(p);
    if (info->attachments == 0) {
        s->lhs = expr(p);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' between the two sides of %s '%s'", info->keyword, s->name);
        s->eq_pos = p->tok.pos;
        advance(p);
        s->rhs = expr(p);
        return;
    }
    for (int i = 0; i < info->attachments; i++)
        attachment(p, s, i);
    if (p->spatial) {
        spatial_tail(p, s);
        return;
    }
    if (info->axis)
        axis(p, s);
    option(p, s);
    reject_extra_keyword(p, s);
}

/* body  = 'body' NAME {('x' | 'y' | 'phi') '=' expr}   each key at most once
   point = 'point' NAME {('x' | 'y') '=' expr} */
static void initial_values(Parser *p, Stmt *s, int nkeys)
{
    static const char *const keys[3] = {"x", "y", "phi"};
    const char *what = nkeys == 3 ? "body" : "point";
    char buf[LEX_DESCRIBE_MAX];
    while (p->tok.kind == TOK_IDENT) {
        int i = 0;
        while (i < nkeys && !lex_is_word(&p->tok, keys[i]))
            i++;
        if (i == nkeys && (lex_is_word(&p->tok, "z") || lex_is_word(&p->tok, "orient")))
            diag_fail(p->diag, p->tok.pos, "unknown key %s for %s '%s': expected %s ('%.*s' "
                      "is for spatial files, which say 'spatial' first)",
                      lex_describe(&p->tok, buf), what, s->name,
                      nkeys == 3 ? "x, y or phi" : "x or y", p->tok.len, p->tok.start);
        if (i == nkeys)
            diag_fail(p->diag, p->tok.pos, "unknown key %s for %s '%s': expected %s",
                      lex_describe(&p->tok, buf), what, s->name,
                      nkeys == 3 ? "x, y or phi" : "x or y");
        if (s->init[i])
            diag_fail(p->diag, p->tok.pos, "'%s' given twice for %s '%s'", keys[i], what,
                      s->name);
        s->init_pos[i] = p->tok.pos;
        advance(p);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' after '%s'", keys[i]);
        advance(p);
        s->init[i] = expr(p);
    }
}

/* orientation = 'axis' '(' ux ',' uy ',' uz ',' angle ')'
               | ('xyz' | 'zyx') '(' a ',' b ',' c ')' */
static void orientation(Parser *p, Stmt *s)
{
    static const char *const words[] = {"axis", "xyz", "zyx"};
    static const int kinds[] = {ORIENT_AXIS, ORIENT_XYZ, ORIENT_ZYX};
    int k = 0;
    while (k < 3 && !lex_is_word(&p->tok, words[k]))
        k++;
    if (k == 3)
        expected(p, "axis(ux, uy, uz, angle), xyz(a, b, c) or zyx(a, b, c) after 'orient ='");
    s->orient = kinds[k];
    advance(p);
    components(p, k == 0 ? "orient = axis(ux, uy, uz, angle)" : k == 1 ? "orient = xyz(a, b, c)"
               : "orient = zyx(a, b, c)", k == 0 ? 4 : 3, s->orient_arg);
}

/* spatial body  = 'body' NAME {('x' | 'y' | 'z') '=' expr | 'orient' '=' orientation}
   spatial point = 'point' NAME {('x' | 'y' | 'z') '=' expr}   each key at most once */
static void spatial_values(Parser *p, Stmt *s, bool body)
{
    static const char *const keys[3] = {"x", "y", "z"};
    const char *what = body ? "body" : "point";
    char buf[LEX_DESCRIBE_MAX];
    while (p->tok.kind == TOK_IDENT) {
        int i = 0;
        while (i < 3 && !lex_is_word(&p->tok, keys[i]))
            i++;
        bool orient = i == 3 && body && lex_is_word(&p->tok, "orient");
        if (i == 3 && !orient && body && lex_is_word(&p->tok, "phi"))
            diag_fail(p->diag, p->tok.pos, "a spatial body has no 'phi': write orient = "
                      "axis(ux, uy, uz, angle), xyz(a, b, c) or zyx(a, b, c)");
        if (i == 3 && !orient)
            diag_fail(p->diag, p->tok.pos, "unknown key %s for %s '%s': expected %s",
                      lex_describe(&p->tok, buf), what, s->name,
                      body ? "x, y, z or orient" : "x, y or z");
        if (orient ? s->orient != ORIENT_NONE : s->init[i] != NULL)
            diag_fail(p->diag, p->tok.pos, "'%s' given twice for %s '%s'",
                      orient ? "orient" : keys[i], what, s->name);
        if (!orient)
            s->init_pos[i] = p->tok.pos;
        else
            s->orient_pos = p->tok.pos;
        advance(p);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' after '%s'", orient ? "orient" : keys[i]);
        advance(p);
        if (orient)
            orientation(p, s);
        else
            s->init[i] = expr(p);
    }
}

/* output = 'output' NAME '=' expr                 (a value of q and t)
          | 'output' NAME ':' NAME [pair]           (a point: body, point or ground) */
static void output(Parser *p, Stmt *s)
{
    s->name = declared_name(p, "output", &s->name_pos);
    if (p->tok.kind == TOK_EQ) {
        advance(p);
        s->value = expr(p);
        return;
    }
    if (p->tok.kind != TOK_COLON)
        expected(p, "'=' (a value) or ':' (a point) after 'output %s'", s->name);
    advance(p);
    AstAttach *at = &s->attach[0];
    if (p->tok.kind != TOK_IDENT || (is_reserved(&p->tok) && !lex_is_word(&p->tok, "ground")))
        expected(p, "a body, point or ground after 'output %s:'", s->name);
    at->name = token_text(p, &p->tok);
    at->pos = p->tok.pos;
    advance(p);
    if (p->tok.kind == TOK_LPAREN) {
        at->has_offset = true;
        offset(p, "the point's offset", at);
    }
}

/* ---- dynamics statements (masses and forces: no rows) ---- */

#define KEYBIT(k) (1u << (k))

/* The keys of a mass (a force's are its row's in forces.def). */
static const unsigned mass_keys = KEYBIT(DKEY_M) | KEYBIT(DKEY_J) | KEYBIT(DKEY_ANGLE);

/* A spatial body's own mass: J is the tensor's diagonal, the products
   its off-diagonal entries; a spatial mass element has no angle, no J. */
static const unsigned spatial_body_mass = KEYBIT(DKEY_M) | KEYBIT(DKEY_J) | KEYBIT(DKEY_JXY)
                                          | KEYBIT(DKEY_JXZ) | KEYBIT(DKEY_JYZ);

/* The keys in `allowed`, listed as "m, J or com" for messages. */
static void list_keys(char *buf, size_t size, unsigned allowed, const char *extra)
{
    const char *words[DKEY_COUNT + 1];
    int n = 0;
    for (int k = 0; k < DKEY_COUNT; k++)
        if (allowed & KEYBIT(k))
            words[n++] = dyn_key_names[k];
    if (extra)
        words[n++] = extra;
    size_t len = 0;
    buf[0] = '\0';
    for (int i = 0; i < n && len < size; i++)
        len += (size_t)snprintf(buf + len, size - len, "%s%s", i == 0 ? "" : i == n - 1 ? " or " : ", ",
                                words[i]);
}

/* at(x, y), spatial at(x, y, z): a point given by expressions of the
   coordinates, into a. */
static void at_point(Parser *p, AstAttach *a)
{
    a->at = true;
    a->name = NULL;
    a->pos = p->tok.pos;
    advance(p);
    offset(p, p->spatial ? "at(x, y, z)" : "at(x, y)", a);
}

/* A vector of the file's dimension: (x, y), spatial (x, y, z); what
   names it in messages (its spatial form when the file is spatial). */
static void vector(Parser *p, const char *what, const char *spatial_what, Ast **out)
{
    if (p->spatial)
        components(p, spatial_what, 3, out);
    else
        pair(p, what, &out[0], &out[1]);
}

/* dyn_attachment = 'at' pair | NAME [pair]   (frame_only: a body or ground alone) */
static void dyn_attachment(Parser *p, Stmt *s, int slot, int count, bool frame_only)
{
    AstAttach *a = &s->attach[slot];
    const char *kw = dyn_keyword(s);
    const char *nth = count == 1 ? "" : slot == 0 ? "first " : "second ";
    if (p->tok.kind != TOK_IDENT || (is_reserved(&p->tok) && !lex_is_word(&p->tok, "ground")))
        expected(p, "%s as the %sattachment of %s '%s'",
                 frame_only ? "a body or ground" : "a body, point, ground or at(x, y)", nth, kw,
                 s->name);
    Token name = p->tok;
    Lexer saved = p->lx;
    advance(p);
    if (frame_only && lex_is_word(&name, "at") && p->tok.kind == TOK_LPAREN)
        diag_fail(p->diag, name.pos, "%s '%s' acts on bodies' angles: at(x, y) is a point; "
                  "name a body or ground", kw, s->name);
    if (!frame_only && lex_is_word(&name, "at") && p->tok.kind == TOK_LPAREN) {
        p->lx = saved;      /* back to 'at' for at_point */
        p->tok = name;
        at_point(p, a);
        return;
    }
    a->name = token_text(p, &name);
    a->pos = name.pos;
    if (p->tok.kind != TOK_LPAREN)
        return;
    if (frame_only)
        diag_fail(p->diag, p->tok.pos, "%s '%s' acts on bodies' angles: write '%s' alone, "
                  "without an offset", kw, s->name, a->name);
    char what[DIAG_MESSAGE_MAX];
    snprintf(what, sizeof what, "the offset of '%s'", a->name);
    a->has_offset = true;
    offset(p, what, a);
}

/* keys = {KEY '=' expr | 'com' pair | 'at' pair}, each at most once;
   com and at only where the form takes them (a body's own mass, with
   com, turns with the body: no angle key). */
static void dyn_keys(Parser *p, Stmt *s, bool com, bool at)
{
    bool mass = s->kind == STMT_MASS;
    unsigned allowed = (mass ? mass_keys : force_info[s->force].keys) & (com ? ~KEYBIT(DKEY_ANGLE) : ~0u);
    if (p->spatial && mass)
        allowed = com ? spatial_body_mass : KEYBIT(DKEY_M);
    while (p->tok.kind == TOK_IDENT) {
        bool is_com = com && lex_is_word(&p->tok, "com"), is_at = at && lex_is_word(&p->tok, "at");
        if ((is_com && s->vec[0]) || (is_at && s->attach[0].at))
            diag_fail(p->diag, p->tok.pos, "'%.*s' given twice for %s '%s'", p->tok.len,
                      p->tok.start, dyn_keyword(s), s->name);
        if (is_com) {
            s->vec_pos = p->tok.pos;
            advance(p);
            vector(p, "com(sx, sy)", "com(sx, sy, sz)", s->vec);
            continue;
        }
        if (is_at) {
            at_point(p, &s->attach[0]);
            continue;
        }
        int k = 0;
        while (k < DKEY_COUNT && !lex_is_word(&p->tok, dyn_key_names[k]))
            k++;
        char list[128];
        list_keys(list, sizeof list, allowed, com ? (p->spatial ? "com(sx, sy, sz)" : "com(sx, sy)")
                  : at ? (p->spatial ? "at(x, y, z)" : "at(x, y)") : NULL);
        if (k == DKEY_COUNT || !(allowed & KEYBIT(k)))
            diag_fail(p->diag, p->tok.pos, "unknown key '%.*s' for %s '%s': expected %s",
                      p->tok.len, p->tok.start, dyn_keyword(s), s->name, list);
        if (s->key[k])
            diag_fail(p->diag, p->tok.pos, "'%s' given twice for %s '%s'", dyn_key_names[k],
                      dyn_keyword(s), s->name);
        s->key_pos[k] = p->tok.pos;
        advance(p);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' after '%s'", dyn_key_names[k]);
        advance(p);
        if (p->spatial && k == DKEY_J) {    /* the tensor's diagonal; key[J] marks it given */
            components(p, "J = (Jxx, Jyy, Jzz)", 3, s->inertia);
            s->key[k] = s->inertia[0];
            continue;
        }
        s->key[k] = expr(p);
    }
}

/* mass = 'mass' NAME keys          (a body's or point's own mass; com for a body)
        | 'mass' NAME ':' keys      (a mass element: at(x, y) required) */
static void dyn_mass(Parser *p, Stmt *s)
{
    s->name = declared_name(p, "mass", &s->name_pos);
    if (p->tok.kind == TOK_COLON) {
        s->declares = true;
        advance(p);
        dyn_keys(p, s, false, true);
        if (!s->attach[0].at)
            expected(p, "'%s' for the mass element '%s' (or 'mass BODY m = ...' "
                     "without ':' for a body's own mass)", p->spatial ? "at(x, y, z)" : "at(x, y)",
                     s->name);
    } else {
        dyn_keys(p, s, true, false);
    }
    if (!s->key[DKEY_M])
        expected(p, "'m = ...' for mass '%s'", s->name);
}

/* torque = 'torque' NAME ':' (BODY | 'angle' '(' expr ')') '=' expr */
static void dyn_torque(Parser *p, Stmt *s)
{
    Lexer saved = p->lx;
    Token word = p->tok;
    if (lex_is_word(&word, "angle")) {
        advance(p);
        if (p->tok.kind == TOK_LPAREN) {
            s->eq_pos = word.pos;
            advance(p);
            s->lhs = expr(p);
            if (p->tok.kind != TOK_RPAREN)
                expected(p, "')' after the angle of torque '%s'", s->name);
            advance(p);
        } else {
            p->lx = saved;  /* a body called angle */
            p->tok = word;
        }
    }
    if (!s->lhs)
        dyn_attachment(p, s, 0, 1, true);
    if (p->tok.kind != TOK_EQ)
        expected(p, "'=' and the torque of '%s'", s->name);
    advance(p);
    if (p->spatial && !s->lhs) {    /* a spatial body's torque: global components */
        s->force = FORCE_BODY_TORQUE;
        s->vec_pos = p->tok.pos;
        components(p, "the torque (tx, ty, tz)", 3, s->vec);
        return;
    }
    s->value = expr(p);
}

/* spatial rspring = 'rspring' NAME ':' JOINT keys   (about a revolute's or
   cylindrical's axis: its angle(JOINT)) */
static void dyn_spatial_rspring(Parser *p, Stmt *s)
{
    AstAttach *a = &s->attach[0];
    if (p->tok.kind != TOK_IDENT || is_reserved(&p->tok))
        expected(p, "a revolute or cylindrical joint after 'rspring %s:' (a spatial rspring "
                 "acts about the joint's axis)", s->name);
    a->name = token_text(p, &p->tok);
    a->pos = p->tok.pos;
    advance(p);
    dyn_keys(p, s, false, false);
}

/* gravity = 'gravity' pair */
static void gravity(Parser *p, Stmt *s)
{
    s->kind = STMT_GRAVITY;
    advance(p);
    s->vec_pos = p->tok.pos;
    vector(p, "gravity (gx, gy)", "gravity (gx, gy, gz)", s->vec);
}

/* force = 'force' NAME ':' attachment pair */
static void point_force(Parser *p, Stmt *s)
{
    AstAttach *a = &s->attach[0];
    SrcPos offset_pos = p->tok.pos;
    dyn_attachment(p, s, 0, 1, false);
    if (p->tok.kind != TOK_LPAREN && a->has_offset && !a->at) {
        /* `force F: body (fx, fy)`: the pair was the force, not an offset */
        a->has_offset = false;
        s->vec[0] = a->sx, s->vec[1] = a->sy, s->vec[2] = a->sz;
        a->sx = a->sy = a->sz = NULL;
        s->vec_pos = offset_pos;
        return;
    }
    s->vec_pos = p->tok.pos;
    vector(p, "the force (fx, fy)", "the force (fx, fy, fz)", s->vec);
}

/* force element = KIND NAME ':' operands, by kind (forces.def):
     'force' NAME ':' attachment pair
   | 'torque' NAME ':' (BODY | 'angle' '(' expr ')') '=' expr
   | ('spring' | 'rspring') NAME ':' attachment attachment keys
   | 'gforce' NAME ':' COORDINATE '=' expr */
static void force(Parser *p, Stmt *s, ForceKind kind)
{
    const ForceInfo *info = &force_info[kind];
    s->kind = STMT_FORCE;
    s->force = kind;
    advance(p);
    s->name = declared_name(p, info->keyword, &s->name_pos);
    s->declares = true;
    if (p->tok.kind != TOK_COLON)
        expected(p, "':' after the %s name '%s'", info->keyword, s->name);
    advance(p);
    switch (kind) {
    case FORCE_POINT:
        point_force(p, s);
        return;
    case FORCE_TORQUE: case FORCE_BODY_TORQUE:
        dyn_torque(p, s);
        return;
    case FORCE_SPRING: case FORCE_RSPRING:
        if (p->spatial && kind == FORCE_RSPRING) {
            dyn_spatial_rspring(p, s);
            return;
        }
        for (int i = 0; i < info->attachments; i++)
            dyn_attachment(p, s, i, info->attachments, info->frame);
        dyn_keys(p, s, false, false);
        return;
    case FORCE_GENERAL:
        s->lhs = expr(p);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' after the coordinate of gforce '%s'", s->name);
        s->eq_pos = p->tok.pos;
        advance(p);
        s->value = expr(p);
        return;
    case FORCE_KIND_COUNT:
        break;
    }
}

/* Appends the statement keywords of the file's dimension to buf, for the
   unknown-statement message. */
static void list_keywords(char *buf, size_t size, bool spatial)
{
    int n = snprintf(buf, size, "mechanism, %sparam, body, point, coord, output",
                     spatial ? "spatial, " : "");
    const char *words[JOINT_KIND_COUNT + FORCE_KIND_COUNT + 2];
    int count = 0;
    for (int k = 0; k < JOINT_KIND_COUNT; k++)
        if (joint_kind_in((JointKind)k, spatial))
            words[count++] = joint_info[k].keyword;
    words[count++] = "mass";
    for (int k = 0; k < FORCE_KIND_COUNT; k++)
        if (force_info[k].own)
            words[count++] = force_info[k].keyword;
    words[count++] = "gravity";
    for (int k = 0; k < count && n > 0 && (size_t)n < size; k++)
        n += snprintf(buf + n, size - (size_t)n, "%s %s", k == count - 1 ? " or" : ",", words[k]);
}

/* 'spatial': once, before every statement but `mechanism`. */
static void spatial_statement(Parser *p, Stmt *s)
{
    int line, col;
    diag_locate(p->diag, s->pos.offset, &line, &col);
    if (p->spatial_line)
        diag_fail(p->diag, s->pos, "a second 'spatial' statement (the first is on line %d)",
                  p->spatial_line);
    if (p->begun)
        diag_fail(p->diag, s->pos, "'spatial' must be the first statement (after an "
                  "optional 'mechanism' line): it decides how every body is read");
    p->spatial = true;
    p->spatial_line = line;
    s->kind = STMT_SPATIAL;
    advance(p);
}

/* A joint keyword of the other dimension: say which file it belongs in. */
static _Noreturn void wrong_dimension(Parser *p, const Token *kw)
{
    if (p->spatial)
        diag_fail(p->diag, kw->pos, "'%.*s' is a planar joint, and this file is spatial "
                  "('spatial' on line %d)", kw->len, kw->start, p->spatial_line);
    diag_fail(p->diag, kw->pos, "'%.*s' is a spatial joint: a spatial mechanism says "
              "'spatial' as its first statement", kw->len, kw->start);
}

/* statement = 'mechanism' NAME
             | 'param' NAME '=' expr
             | body | point
             | 'coord' NAME ['=' expr]
             | output
             | joint */
static Stmt *statement(Parser *p)
{
    Token kw = p->tok;
    char buf[LEX_DESCRIBE_MAX];
    if (kw.kind != TOK_IDENT)
        diag_fail(p->diag, kw.pos, "expected a statement keyword at the start of the line, "
                  "found %s", lex_describe(&kw, buf));
    Stmt *s = arena_alloc(p->arena, sizeof *s);
    s->pos = kw.pos;
    int kind = joint_kind_lookup(kw.start, kw.len, p->spatial);
    if (!lex_is_word(&kw, "mechanism") && !lex_is_word(&kw, "spatial"))
        p->begun = true;
    if (lex_is_word(&kw, "spatial")) {
        spatial_statement(p, s);
    } else if (lex_is_word(&kw, "mechanism")) {
        int line, col;
        diag_locate(p->diag, kw.pos.offset, &line, &col);
        if (p->mechanism_line)
            diag_fail(p->diag, kw.pos, "a second 'mechanism' statement (the first is on "
                      "line %d)", p->mechanism_line);
        p->mechanism_line = line;
        s->kind = STMT_MECHANISM;
        advance(p);
        s->name = declared_name(p, "mechanism", &s->name_pos);
    } else if (lex_is_word(&kw, "param")) {
        s->kind = STMT_PARAM;
        advance(p);
        s->name = declared_name(p, "param", &s->name_pos);
        if (p->tok.kind != TOK_EQ)
            expected(p, "'=' after 'param %s'", s->name);
        advance(p);
        s->value = expr(p);
    } else if (lex_is_word(&kw, "body") || lex_is_word(&kw, "point")) {
        bool body = lex_is_word(&kw, "body");
        s->kind = body ? STMT_BODY : STMT_POINT;
        advance(p);
        s->name = declared_name(p, body ? "body" : "point", &s->name_pos);
        if (p->spatial)
            spatial_values(p, s, body);
        else
            initial_values(p, s, body ? 3 : 2);
    } else if (lex_is_word(&kw, "coord")) {
        s->kind = STMT_COORD;
        advance(p);
        s->name = declared_name(p, "coord", &s->name_pos);
        if (p->tok.kind == TOK_EQ) {
            advance(p);
            s->value = expr(p);
        }
    } else if (lex_is_word(&kw, "output")) {
        s->kind = STMT_OUTPUT;
        advance(p);
        output(p, s);
    } else if (lex_is_word(&kw, "mass")) {
        s->kind = STMT_MASS;
        advance(p);
        dyn_mass(p, s);
    } else if (lex_is_word(&kw, "gravity")) {
        gravity(p, s);
    } else if (force_kind_lookup(kw.start, kw.len) >= 0) {
        force(p, s, (ForceKind)force_kind_lookup(kw.start, kw.len));
    } else if (kind >= 0) {
        s->kind = STMT_JOINT;
        s->joint = (JointKind)kind;
        advance(p);
        joint(p, s);
    } else if (joint_kind_lookup(kw.start, kw.len, !p->spatial) >= 0) {
        wrong_dimension(p, &kw);
    } else {
        char list[DIAG_MESSAGE_MAX / 2];
        list_keywords(list, sizeof list, p->spatial);
        diag_fail(p->diag, kw.pos, "unknown statement %s: expected %s",
                  lex_describe(&kw, buf), list);
    }
    expect_end(p);
    return s;
}

/* program = {[statement] NEWLINE} EOF   (at least one statement) */
static void program(Parser *p, Program *out)
{
    Stmt **tail = &out->first;
    advance(p);
    for (;;) {
        while (p->tok.kind == TOK_NEWLINE)
            advance(p);
        if (p->tok.kind == TOK_EOF)
            break;
        Stmt *s = statement(p);
        *tail = s;
        tail = &s->next;
        out->count++;
    }
    /* lines = newlines, plus one for a last line without a newline */
    out->line_count = p->lx.line - 1 + (p->lx.len > p->lx.line_start);
    out->spatial = p->spatial;
    if (out->count == 0)
        diag_fail(p->diag, (SrcPos){0}, "the mechanism has no statements");
}

bool parse_program(Arena *arena, Diag *diag, const MechLimits *limits, Program *out)
{
    jmp_buf escape;
    jmp_buf *saved = diag->escape;
    memset(out, 0, sizeof *out);
    diag->escape = &escape;
    if (setjmp(escape)) {
        diag->escape = saved;
        memset(out, 0, sizeof *out);
        return false;
    }
    Parser p = {.arena = arena, .diag = diag, .limits = limits};
    lex_init(&p.lx, diag, limits);
    program(&p, out);
    diag->escape = saved;
    return true;
}
