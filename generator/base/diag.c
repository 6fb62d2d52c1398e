/* diag.c - records the first error with its location and prints it like a compiler. */
#include "diag.h"

#include <stdarg.h>
#include <string.h>

void diag_init(Diag *diag, const char *file, const char *text, int text_len)
{
    memset(diag, 0, sizeof *diag);
    diag->file = file;
    diag->text = text;
    diag->text_len = text_len;
}

void diag_locate(const Diag *diag, int offset, int *line, int *col)
{
    int l = 1, c = 1, i = 0;
    if (offset > diag->text_len)
        offset = diag->text_len;
    /* A UTF-8 byte-order mark takes no column. */
    if (diag->text_len >= 3 && memcmp(diag->text, "\xEF\xBB\xBF", 3) == 0 && offset >= 3)
        i = 3;
    for (; i < offset; i++) {
        if (diag->text[i] == '\n')
            l++, c = 1;
        else
            c++;
    }
    *line = l;
    *col = c;
}

static void record(Diag *diag, const SrcPos *pos, const char *fmt, va_list ap)
{
    if (diag->failed)
        return;
    diag->failed = true;
    vsnprintf(diag->message, sizeof diag->message, fmt, ap);
    diag->has_pos = pos != NULL && diag->text != NULL;
    if (!diag->has_pos)
        return;
    diag_locate(diag, pos->offset, &diag->line, &diag->col);
    int start = pos->offset < diag->text_len ? pos->offset : diag->text_len;
    while (start > 0 && diag->text[start - 1] != '\n')
        start--;
    if (start == 0 && diag->text_len >= 3 && memcmp(diag->text, "\xEF\xBB\xBF", 3) == 0)
        start = 3;
    int n = 0;
    while (start + n < diag->text_len && diag->text[start + n] != '\n'
           && n < DIAG_LINE_MAX - 1)
        n++;
    if (n > 0 && diag->text[start + n - 1] == '\r')     /* CRLF files */
        n--;
    memcpy(diag->source_line, diag->text + start, (size_t)n);
    diag->source_line[n] = '\0';
}

void diag_fail(Diag *diag, SrcPos pos, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    record(diag, &pos, fmt, ap);
    va_end(ap);
    diag_throw(diag);
}

void diag_throw(Diag *diag)
{
    longjmp(*diag->escape, 1);
}

void diag_error(Diag *diag, SrcPos pos, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    record(diag, &pos, fmt, ap);
    va_end(ap);
}

void diag_error_nopos(Diag *diag, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    record(diag, NULL, fmt, ap);
    va_end(ap);
}

void diag_print(const Diag *diag, FILE *out)
{
    if (!diag->has_pos) {
        fprintf(out, "%s: error: %s\n", diag->file ? diag->file : "mechc",
                diag->message);
        return;
    }
    fprintf(out, "%s:%d:%d: error: %s\n", diag->file, diag->line, diag->col,
            diag->message);
    /* Control bytes in the echoed line would garble the terminal. */
    fputs("    ", out);
    for (const char *p = diag->source_line; *p; p++)
        fputc((unsigned char)*p < 0x20 && *p != '\t' ? '?' : *p, out);
    fputs("\n    ", out);
    for (int i = 1; i < diag->col && diag->source_line[i - 1]; i++)
        fputc(diag->source_line[i - 1] == '\t' ? '\t' : ' ', out);
    fputs("^\n", out);
}
