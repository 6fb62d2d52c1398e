/* run_state.c - the state of one run: its notes and warnings. */
#include "run_state.h"

#include <stdarg.h>

void run_notef(const Run *r, const char *kind, const char *fmt, ...)
{
    if (!r->o->notes)
        return;
    va_list ap;
    va_start(ap, fmt);
    fprintf(r->o->notes, "%s: %s: ", r->m->file, kind);
    vfprintf(r->o->notes, fmt, ap);
    fputc('\n', r->o->notes);
    va_end(ap);
}

const char *run_plural(int n, const char *one, const char *many)
{
    return n == 1 ? one : many;
}
