/* parse.c - recursive-descent parser for .mech files (spec section 2).

   One statement per line; the first word of a line names the statement.
   This file reads the tokens, the statements and their operands; the
   expressions are expr.c's (precedence climbing, nesting counted against
   limits->max_depth), the dynamics statements dynamics.c's. Tokens per
   statement are counted against max_expr_tokens, so hostile input ends in
   an error, never a stack overflow.

   Errors go through diag_fail to the jmp_buf set by parse_program (style
   R3). The parser checks syntax, reserved words and limits only; names are
   resolved by the model builder from the positions recorded here. */
#include "parser.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ---- tokens and errors ---- */

_Noreturn void parse_expected(Parser *p, const char *fmt, ...)
{
    char what[DIAG_MESSAGE_MAX], buf[LEX_DESCRIBE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    diag_fail(p->diag, p->tok.pos, "expected %s, found %s", what,
              lex_describe(&p->tok, buf));
}

void parse_advance(Parser *p)
{
    if (p->tok.kind == TOK_NEWLINE)
        p->stmt_tokens = 0;     /* a new line starts a new statement */
    p->tok = lex_next(&p->lx);
    if (p->tok.kind != TOK_NEWLINE && p->tok.kind != TOK_EOF
        && ++p->stmt_tokens > p->limits->max_expr_tokens)
        diag_fail(p->diag, p->tok.pos, "statement longer than the limit of %d tokens",
                  p->limits->max_expr_tokens);
}

bool parse_at_end(const Parser *p)
{
    return p->tok.kind == TOK_NEWLINE || p->tok.kind == TOK_EOF;
}

char *parse_token_text(Parser *p, const Token *tok)
{
    return arena_strndup(p->arena, tok->start, (size_t)tok->len);
}

/* The reserved words of spec section 2: never declarable. */
bool parse_is_reserved(const Token *tok)
{
    static const char *const words[] = {"ground", "t", "pi", "der"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
        if (lex_is_word(tok, words[i]))
            return true;
    int op = dag_function_from_name(tok->start, tok->len);
    return op >= 0 && dag_op_is_function((DagOp)op);
}

/* name = IDENT, not reserved; a name being declared by 'after' */
const char *parse_declared_name(Parser *p, const char *after, SrcPos *pos)
{
    if (p->tok.kind != TOK_IDENT)
        parse_expected(p, "a name after '%s'", after);
    if (parse_is_reserved(&p->tok))
        diag_fail(p->diag, p->tok.pos, "'%.*s' is a reserved name and cannot be declared",
                  p->tok.len, p->tok.start);
    /* names become C string literals (row and coordinate names) */
    if (p->tok.len > p->limits->max_name_length)
        diag_fail(p->diag, p->tok.pos, "name longer than the limit of %d characters",
                  p->limits->max_name_length);
    *pos = p->tok.pos;
    const char *name = parse_token_text(p, &p->tok);
    parse_advance(p);
    return name;
}

/* Every statement ends with its line. */
static void expect_end(Parser *p)
{
    char buf[LEX_DESCRIBE_MAX];
    if (parse_at_end(p))
        return;
    if (p->tok.kind == TOK_RPAREN)
        diag_fail(p->diag, p->tok.pos, "unmatched ')'");
    diag_fail(p->diag, p->tok.pos, "unexpected %s after the end of the statement",
              lex_describe(&p->tok, buf));
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
void parse_pair(Parser *p, const char *what, Ast **a, Ast **b)
{
    if (p->tok.kind != TOK_LPAREN)
        parse_expected(p, "'(' after %s", what);
    parse_enter_level(p, p->tok.pos);
    parse_advance(p);
    *a = parse_expr(p);
    if (p->tok.kind != TOK_COMMA)
        parse_expected(p, "',' between the two components of %s", what);
    parse_advance(p);
    *b = parse_expr(p);
    if (p->tok.kind != TOK_RPAREN)
        parse_expected(p, "')' after the two components of %s", what);
    parse_advance(p);
    parse_leave_level(p);
}

/* components = '(' expr {',' expr} ')'   with exactly n expressions: a
   spatial offset, axis or orientation; what names it in messages */
void parse_components(Parser *p, const char *what, int n, Ast **out)
{
    static const char *const count[] = {"no", "one", "two", "three", "four"};
    if (p->tok.kind != TOK_LPAREN)
        parse_expected(p, "'(' after %s", what);
    parse_enter_level(p, p->tok.pos);
    parse_advance(p);
    int i = 0;
    for (;;) {
        SrcPos at = p->tok.pos;
        Ast *e = parse_expr(p);
        if (i == n)
            diag_fail(p->diag, at, "%s has %s components, found more", what, count[n]);
        out[i++] = e;
        if (p->tok.kind != TOK_COMMA)
            break;
        parse_advance(p);
    }
    if (p->tok.kind != TOK_RPAREN)
        parse_expected(p, "',' or ')' in %s", what);
    if (i < n)
        diag_fail(p->diag, p->tok.pos, "%s has %s components, found %s", what, count[n],
                  count[i]);
    parse_advance(p);
    parse_leave_level(p);
}

/* An offset: (sx, sy), or (sx, sy, sz) in a spatial file. */
void parse_offset(Parser *p, const char *what, AstAttach *a)
{
    if (!p->spatial) {
        parse_pair(p, what, &a->sx, &a->sy);
        return;
    }
    Ast *c[3];
    parse_components(p, what, 3, c);
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
        parse_expected(p, "%s as the %sattachment of %s '%s'", attach_noun(rule), nth,
                 info->keyword, s->name);
    if (parse_is_reserved(&p->tok) && !lex_is_word(&p->tok, "ground"))
        diag_fail(p->diag, p->tok.pos,
                  "expected %s as the %sattachment of %s '%s', found the reserved name %s",
                  attach_noun(rule), nth, info->keyword, s->name,
                  lex_describe(&p->tok, buf));
    AstAttach *a = &s->attach[slot];
    a->name = parse_token_text(p, &p->tok);
    a->pos = p->tok.pos;
    parse_advance(p);
    if (p->tok.kind != TOK_LPAREN)
        return;
    if (rule == ATTACH_BODY_ONLY)
        diag_fail(p->diag, p->tok.pos, "the body of %s '%s' takes no offset: write '%s' alone",
                  info->keyword, s->name, a->name);
    char what[DIAG_MESSAGE_MAX];
    snprintf(what, sizeof what, "the offset of '%s'", a->name);
    a->has_offset = true;
    parse_offset(p, what, a);
}

/* axis = 'axis' pair */
static void axis(Parser *p, Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    if (!lex_is_word(&p->tok, "axis")) {
        const AstAttach *last = &s->attach[info->attachments - 1];
        if (parse_at_end(p) && last->has_offset && strcmp(last->name, "axis") == 0)
            diag_fail(p->diag, p->tok.pos, "expected 'axis(ux, uy)' after the attachments "
                      "of %s '%s', found end of line ('axis(...)' was taken as an "
                      "attachment: is one missing?)", info->keyword, s->name);
        parse_expected(p, "'axis(ux, uy)' after the attachments of %s '%s'", info->keyword, s->name);
    }
    s->axis_pos = p->tok.pos;
    parse_advance(p);
    parse_pair(p, "the axis", &s->axis[0], &s->axis[1]);
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
        parse_advance(p);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' after '%s'", word);
        parse_advance(p);
        s->option = parse_expr(p);
    } else if (info->option != OPTION_ANGLE) {
        parse_expected(p, "'%s = ...' for %s '%s'", word, info->keyword, s->name);
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
            parse_advance(p);
            parse_components(p, naxes == 0 ? "the axis (A's)" : "B's axis", 3,
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
        parse_expected(p, "'axis(ux, uy, uz)' after the attachments of %s '%s'", info->keyword,
                 s->name);
    if (info->axis == 2 && naxes == 1)
        parse_expected(p, "B's axis: %s '%s' takes two axes, 'axis(...) axis(...)'", info->keyword,
                 s->name);
    if (word && !s->option && info->option != OPTION_ANGLE)
        parse_expected(p, "'%s = ...' for %s '%s'", word, info->keyword, s->name);
}

/* joint = KIND NAME ':' attachment{n} [axis] [option]   (n = attachments > 0)
         | KIND NAME ':' expr '=' expr                    (n = 0) */
static void joint(Parser *p, Stmt *s)
{
    const JointInfo *info = &joint_info[s->joint];
    s->name = parse_declared_name(p, info->keyword, &s->name_pos);
    if (p->tok.kind != TOK_COLON)
        parse_expected(p, "':' after the joint name '%s'", s->name);
    parse_advance(p);
    if (info->attachments == 0) {
        s->lhs = parse_expr(p);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' between the two sides of %s '%s'", info->keyword, s->name);
        s->eq_pos = p->tok.pos;
        parse_advance(p);
        s->rhs = parse_expr(p);
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
        parse_advance(p);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' after '%s'", keys[i]);
        parse_advance(p);
        s->init[i] = parse_expr(p);
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
        parse_expected(p, "axis(ux, uy, uz, angle), xyz(a, b, c) or zyx(a, b, c) after 'orient ='");
    s->orient = kinds[k];
    parse_advance(p);
    parse_components(p, k == 0 ? "orient = axis(ux, uy, uz, angle)" : k == 1 ? "orient = xyz(a, b, c)"
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
        parse_advance(p);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' after '%s'", orient ? "orient" : keys[i]);
        parse_advance(p);
        if (orient)
            orientation(p, s);
        else
            s->init[i] = parse_expr(p);
    }
}

/* output = 'output' NAME '=' expr                 (a value of q and t)
          | 'output' NAME ':' NAME [pair]           (a point: body, point or ground) */
static void output(Parser *p, Stmt *s)
{
    s->name = parse_declared_name(p, "output", &s->name_pos);
    if (p->tok.kind == TOK_EQ) {
        parse_advance(p);
        s->value = parse_expr(p);
        return;
    }
    if (p->tok.kind != TOK_COLON)
        parse_expected(p, "'=' (a value) or ':' (a point) after 'output %s'", s->name);
    parse_advance(p);
    AstAttach *at = &s->attach[0];
    if (p->tok.kind != TOK_IDENT || (parse_is_reserved(&p->tok) && !lex_is_word(&p->tok, "ground")))
        parse_expected(p, "a body, point or ground after 'output %s:'", s->name);
    at->name = parse_token_text(p, &p->tok);
    at->pos = p->tok.pos;
    parse_advance(p);
    if (p->tok.kind == TOK_LPAREN) {
        at->has_offset = true;
        parse_offset(p, "the point's offset", at);
    }
}

/* Appends the statement keywords of the file's dimension to buf, for the
   unknown-statement message. */
static void list_keywords(char *buf, size_t size, bool spatial)
{
    int n = snprintf(buf, size, "mechanism, %sparam, design, body, point, coord, output",
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
    parse_advance(p);
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
             | 'design' NAME '=' expr
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
        parse_advance(p);
        s->name = parse_declared_name(p, "mechanism", &s->name_pos);
    } else if (lex_is_word(&kw, "param") || lex_is_word(&kw, "design")) {
        s->kind = STMT_PARAM;
        s->design = lex_is_word(&kw, "design");
        const char *word = s->design ? "design" : "param";
        parse_advance(p);
        s->name = parse_declared_name(p, word, &s->name_pos);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' after '%s %s'", word, s->name);
        parse_advance(p);
        s->value = parse_expr(p);
    } else if (lex_is_word(&kw, "body") || lex_is_word(&kw, "point")) {
        bool body = lex_is_word(&kw, "body");
        s->kind = body ? STMT_BODY : STMT_POINT;
        parse_advance(p);
        s->name = parse_declared_name(p, body ? "body" : "point", &s->name_pos);
        if (p->spatial)
            spatial_values(p, s, body);
        else
            initial_values(p, s, body ? 3 : 2);
    } else if (lex_is_word(&kw, "coord")) {
        s->kind = STMT_COORD;
        parse_advance(p);
        s->name = parse_declared_name(p, "coord", &s->name_pos);
        if (p->tok.kind == TOK_EQ) {
            parse_advance(p);
            s->value = parse_expr(p);
        }
    } else if (lex_is_word(&kw, "output")) {
        s->kind = STMT_OUTPUT;
        parse_advance(p);
        output(p, s);
    } else if (lex_is_word(&kw, "mass")) {
        parse_mass(p, s);
    } else if (lex_is_word(&kw, "gravity")) {
        parse_gravity(p, s);
    } else if (force_kind_lookup(kw.start, kw.len) >= 0) {
        parse_force(p, s, (ForceKind)force_kind_lookup(kw.start, kw.len));
    } else if (kind >= 0) {
        s->kind = STMT_JOINT;
        s->joint = (JointKind)kind;
        parse_advance(p);
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
    parse_advance(p);
    for (;;) {
        while (p->tok.kind == TOK_NEWLINE)
            parse_advance(p);
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
