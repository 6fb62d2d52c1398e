/* diag.h - compiler-style diagnostics: FILE:LINE:COL: error: message, line, caret. */
#ifndef MECHC_DIAG_H
#define MECHC_DIAG_H

#include <setjmp.h>
#include <stdbool.h>
#include <stdio.h>

/* A position in the source: byte offset into the whole-file buffer. Line
   and column (1-based) are derived on demand from the offset. */
typedef struct SrcPos {
    int offset;
} SrcPos;

/* DIAG_LINE_MAX holds the longest line the default limits accept. */
enum { DIAG_MESSAGE_MAX = 512, DIAG_LINE_MAX = 4100 };

/* The outcome of a front-end or back-end stage. Library code never exits:
   it records the first error here and returns (or longjmps to the one
   handler of its stage, see diag_fail). */
typedef struct Diag {
    const char *file;           /* name to print, as the user gave it */
    const char *text;           /* the whole input (NUL-terminated) */
    int text_len;
    bool failed;
    bool has_pos;               /* false: a message without a location */
    int line, col;              /* 1-based, valid when has_pos */
    char message[DIAG_MESSAGE_MAX];
    char source_line[DIAG_LINE_MAX];  /* the offending line, for the caret */
    jmp_buf *escape;            /* set by the stage entry point */
} Diag;

void diag_init(Diag *diag, const char *file, const char *text, int text_len);

/* Records an error at pos and longjmps to diag->escape (which must be set). */
_Noreturn void diag_fail(Diag *diag, SrcPos pos, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Longjmps to diag->escape with the error already recorded (diag_error). */
_Noreturn void diag_throw(Diag *diag);

/* Records an error without longjmp (first error wins). */
void diag_error(Diag *diag, SrcPos pos, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void diag_error_nopos(Diag *diag, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Prints "FILE:LINE:COL: error: message", then the line and a caret. */
void diag_print(const Diag *diag, FILE *out);

/* Line and column of a byte offset. */
void diag_locate(const Diag *diag, int offset, int *line, int *col);

#endif
