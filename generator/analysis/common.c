/* common.c - what the analyses over time (run, sim, check) share: the linear-algebra choice, the status, the failure message. */
#include "common.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const char *const analysis_linear_names[] = {"auto", "dense", "sparse", NULL};

void analysis_msgf(char *msg, size_t size, const char *fmt, ...)
{
    size_t len = strlen(msg);
    if (len + 1 >= size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg + len, size - len, fmt, ap);
    va_end(ap);
}
