/* strbuf.h - growable text buffer used to build generated C and reports. */
#ifndef MECHC_STRBUF_H
#define MECHC_STRBUF_H

#include <stdarg.h>
#include <stddef.h>

typedef struct StrBuf {
    char *data;         /* always NUL-terminated once anything was added */
    size_t len, cap;
} StrBuf;

void sb_init(StrBuf *sb);
void sb_free(StrBuf *sb);
void sb_clear(StrBuf *sb);
void sb_putc(StrBuf *sb, char c);
void sb_puts(StrBuf *sb, const char *s);
void sb_putn(StrBuf *sb, const char *s, size_t n);
void sb_printf(StrBuf *sb, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
void sb_vprintf(StrBuf *sb, const char *fmt, va_list ap);
/* Hands the buffer to the caller (free with free()); sb is left empty. */
char *sb_take(StrBuf *sb);
/* A C string literal body for s: quotes, backslashes and every byte outside
   printable ASCII escaped, so no input text can leave the literal. */
void sb_put_c_string(StrBuf *sb, const char *s);

#endif
