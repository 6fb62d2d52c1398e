/* lex.h - .mech text to tokens, one at a time, with the input limits checked on the way. */
#ifndef MECHC_LEX_H
#define MECHC_LEX_H

#include "../base/diag.h"
#include "../base/limits.h"

#include <stdbool.h>

/* Single-character tokens are their own character (as in Lua's llex.h), so
   messages can print them directly; the others sit above the byte range. */
typedef enum TokKind {
    TOK_LPAREN = '(',
    TOK_RPAREN = ')',
    TOK_COMMA = ',',
    TOK_COLON = ':',
    TOK_EQ = '=',
    TOK_PLUS = '+',
    TOK_MINUS = '-',
    TOK_STAR = '*',
    TOK_SLASH = '/',
    TOK_CARET = '^',
    TOK_DOT = '.',
    TOK_IDENT = 256,    /* [A-Za-z_][A-Za-z0-9_]* */
    TOK_NUMBER,         /* decimal literal, value in num */
    TOK_NEWLINE,        /* end of a line (comments are skipped) */
    TOK_EOF,
} TokKind;

typedef struct Token {
    TokKind kind;
    SrcPos pos;             /* first byte; NEWLINE: the comment or line end */
    const char *start;      /* into the source text */
    int len;
    double num;             /* TOK_NUMBER */
} Token;

/* The scanner state. It reads diag->text (diag->text_len bytes) and reports
   every error through diag_fail, so the caller must have set diag->escape. */
typedef struct Lexer {
    Diag *diag;
    const MechLimits *limits;
    const char *text;
    int len;
    int cur;                /* next byte to read */
    int line;               /* 1-based line of cur */
    int line_start;         /* offset of the current line's first byte */
    bool line_checked;      /* the current line's length has been checked */
    TokKind prev;           /* last token returned: "a.5" is a member, not 0.5 */
} Lexer;

/* Prepares lx over diag->text; fails when the file exceeds max_file_bytes.
   A UTF-8 byte order mark at the start is skipped. */
void lex_init(Lexer *lx, Diag *diag, const MechLimits *limits);

/* The next token; after the last one, TOK_EOF forever. */
Token lex_next(Lexer *lx);

/* A human description of tok for messages: "'crank'", "'('", or "end of
   line" (also for the end of the file); may use buf. */
enum { LEX_DESCRIBE_MAX = 64 };
const char *lex_describe(const Token *tok, char buf[LEX_DESCRIBE_MAX]);

/* True when tok is the identifier word. */
bool lex_is_word(const Token *tok, const char *word);

#endif
