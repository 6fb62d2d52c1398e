/* lex.c - the .mech scanner: bytes to tokens, one call per token.

   Modelled on Lua's llex.c: a switch on the current byte, numbers read
   greedily and then validated, errors raised on the spot through diag_fail.
   The scanner also enforces the byte-level rules of the format: a file and
   line size limit, ASCII outside comments, no control bytes except tab and
   CR before LF. Every line is measured when the scanner first enters it, so
   a too-long line is reported before anything on it. */
#include "lex.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static SrcPos at(int offset)
{
    SrcPos pos = {offset};
    return pos;
}

static bool is_digit(int c) { return c >= '0' && c <= '9'; }

static bool is_ident_start(int c)
{
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
}

static bool is_ident_char(int c) { return is_ident_start(c) || is_digit(c); }

void lex_init(Lexer *lx, Diag *diag, const MechLimits *limits)
{
    memset(lx, 0, sizeof *lx);
    lx->diag = diag;
    lx->limits = limits;
    lx->text = diag->text;
    lx->len = diag->text_len;
    lx->line = 1;
    lx->prev = TOK_NEWLINE;
    if (lx->len > limits->max_file_bytes)
        diag_fail(diag, at(limits->max_file_bytes),
                  "the file is larger than the limit of %d bytes",
                  limits->max_file_bytes);
    if (lx->len >= 3 && memcmp(lx->text, "\xEF\xBB\xBF", 3) == 0)
        lx->cur = 3;
}

/* Fails at the first byte past the limit when the current line is too long
   (newline and a CR before it excluded). */
static void check_line(Lexer *lx)
{
    const char *nl = memchr(lx->text + lx->line_start, '\n',
                            (size_t)(lx->len - lx->line_start));
    int end = nl ? (int)(nl - lx->text) : lx->len;
    if (end > lx->line_start && lx->text[end - 1] == '\r')
        end--;
    int max = lx->limits->max_line_length;
    if (end - lx->line_start > max)
        diag_fail(lx->diag, at(lx->line_start + max),
                  "line longer than the limit of %d bytes", max);
    lx->line_checked = true;
}

static Token make(TokKind kind, const char *text, int start, int len)
{
    Token tok = {.kind = kind, .pos = at(start), .start = text + start, .len = len};
    return tok;
}

/* number = digits ['.' digits*] [('e'|'E') ['+'|'-'] digits] | '.' digits ...
   The span is read greedily over letters, digits, dots and exponent signs
   (so "12abc", "1.2.3" and "0x10" are one bad token, not two good ones),
   then checked against the decimal grammar before strtod sees it. strtod
   relies on the "C" locale, which mechc never changes. */
static Token read_number(Lexer *lx, int start)
{
    const char *s = lx->text;
    int end = start;
    while (end < lx->len) {
        char c = s[end];
        if (is_ident_char(c) || c == '.')
            end++;
        else if ((c == '+' || c == '-') && (s[end - 1] == 'e' || s[end - 1] == 'E'))
            end++;
        else
            break;
    }
    int j = start, digits = 0;
    bool ok = true;
    while (j < end && is_digit(s[j]))
        j++, digits++;
    if (j < end && s[j] == '.') {
        j++;
        while (j < end && is_digit(s[j]))
            j++, digits++;
    }
    if (digits > 0 && j < end && (s[j] == 'e' || s[j] == 'E')) {
        j++;
        if (j < end && (s[j] == '+' || s[j] == '-'))
            j++;
        int exp_digits = 0;
        while (j < end && is_digit(s[j]))
            j++, exp_digits++;
        ok = exp_digits > 0;
    }
    int len = end - start;
    if (!ok || digits == 0 || j != end)
        diag_fail(lx->diag, at(start), "malformed number '%.*s'",
                  len > 40 ? 40 : len, s + start);
    /* strtod gets a NUL-terminated copy: the text need not end after it */
    char small[64];
    char *copy = len < (int)sizeof small ? small : xmalloc((size_t)len + 1);
    memcpy(copy, s + start, (size_t)len);
    copy[len] = '\0';
    double value = strtod(copy, NULL);
    if (copy != small)
        free(copy);
    if (isinf(value))
        diag_fail(lx->diag, at(start), "number out of range: '%.*s'",
                  len > 40 ? 40 : len, s + start);
    lx->cur = end;
    Token tok = make(TOK_NUMBER, s, start, len);
    tok.num = value;
    return tok;
}

static Token scan(Lexer *lx)
{
    const char *s = lx->text;
    int comment = -1;       /* a line's end is reported at its comment */
    for (;;) {
        if (!lx->line_checked)
            check_line(lx);
        int start = lx->cur;
        if (start >= lx->len)
            return make(TOK_EOF, s, comment >= 0 ? comment : lx->len, 0);
        unsigned char c = (unsigned char)s[start];
        switch (c) {
        case '\n': {
            int pos = comment >= 0 ? comment
                    : start > lx->line_start && s[start - 1] == '\r' ? start - 1
                    : start;
            lx->cur++;
            lx->line++;
            lx->line_start = lx->cur;
            lx->line_checked = false;
            return make(TOK_NEWLINE, s, pos, 1);
        }
        case ' ':
        case '\t':
            lx->cur++;
            continue;
        case '\r':
            if (start + 1 < lx->len && s[start + 1] == '\n') {
                lx->cur++;
                continue;
            }
            diag_fail(lx->diag, at(start),
                      "carriage return (0x0D) not followed by a line feed");
        case '#':
            comment = start;
            while (lx->cur < lx->len && s[lx->cur] != '\n')
                lx->cur++;
            continue;
        case '.':
            /* ".5" is a number, but in "a.5" the dot is a member access */
            if (start + 1 < lx->len && is_digit(s[start + 1]) && lx->prev != TOK_IDENT)
                return read_number(lx, start);
            /* fall through */
        case '(': case ')': case ',': case ':': case '=':
        case '+': case '-': case '*': case '/': case '^':
            lx->cur++;
            return make((TokKind)c, s, start, 1);
        default:
            break;
        }
        if (is_digit(c))
            return read_number(lx, start);
        if (is_ident_start(c)) {
            int end = start;
            while (end < lx->len && is_ident_char(s[end]))
                end++;
            lx->cur = end;
            return make(TOK_IDENT, s, start, end - start);
        }
        if (c >= 0x80)
            diag_fail(lx->diag, at(start), "non-ASCII byte 0x%02X outside a comment", c);
        if (c < 0x20 || c == 0x7F)
            diag_fail(lx->diag, at(start), "control byte 0x%02X outside a comment", c);
        diag_fail(lx->diag, at(start), "unexpected character '%c'", c);
    }
}

Token lex_next(Lexer *lx)
{
    Token tok = scan(lx);
    lx->prev = tok.kind;
    return tok;
}

const char *lex_describe(const Token *tok, char buf[LEX_DESCRIBE_MAX])
{
    /* statements are single lines, so the end of the file ends a line too */
    if (tok->kind == TOK_NEWLINE || tok->kind == TOK_EOF)
        return "end of line";
    if (tok->kind == TOK_IDENT || tok->kind == TOK_NUMBER) {
        enum { SHOWN = 40 };
        bool cut = tok->len > SHOWN;
        snprintf(buf, LEX_DESCRIBE_MAX, "'%.*s%s'", cut ? SHOWN : tok->len,
                 tok->start, cut ? "..." : "");
        return buf;
    }
    snprintf(buf, LEX_DESCRIBE_MAX, "'%c'", (char)tok->kind);
    return buf;
}

bool lex_is_word(const Token *tok, const char *word)
{
    size_t n = strlen(word);
    return tok->kind == TOK_IDENT && (size_t)tok->len == n
        && memcmp(tok->start, word, n) == 0;
}
