/* parser.h - what the parser's files share (parse.c, expr.c, dynamics.c): its state, tokens and common operands. */
#ifndef MECHC_PARSER_H
#define MECHC_PARSER_H

#include "parse.h"

#include "../lex/lex.h"

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

/* ---- tokens and errors (parse.c) ---- */

/* Fails at the current token with "expected WHAT, found TOKEN". */
_Noreturn void parse_expected(Parser *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void parse_advance(Parser *p);
/* At the end of the statement's line. */
bool parse_at_end(const Parser *p);
char *parse_token_text(Parser *p, const Token *tok);
/* One of the reserved words of spec section 2: never declarable. */
bool parse_is_reserved(const Token *tok);
/* The name a statement 'after' declares, or fails. */
const char *parse_declared_name(Parser *p, const char *after, SrcPos *pos);

/* ---- operands (parse.c) ---- */

/* '(' expr ',' expr ')': what names it in messages */
void parse_pair(Parser *p, const char *what, Ast **a, Ast **b);
/* '(' expr {',' expr} ')' with exactly n expressions */
void parse_components(Parser *p, const char *what, int n, Ast **out);
/* An offset of the file's dimension, into a. */
void parse_offset(Parser *p, const char *what, AstAttach *a);

/* ---- expressions (expr.c) ---- */

Ast *parse_expr(Parser *p);
/* Nesting, counted against limits->max_depth. */
void parse_enter_level(Parser *p, SrcPos pos);
void parse_leave_level(Parser *p);

/* ---- dynamics statements (dynamics.c) ---- */

void parse_mass(Parser *p, Stmt *s);
void parse_gravity(Parser *p, Stmt *s);
void parse_force(Parser *p, Stmt *s, ForceKind kind);

#endif
