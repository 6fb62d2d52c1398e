/* realfmt.c - shortest round-trip formatting of doubles, for graph dumps, laws and messages. */
#include "realfmt.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int realfmt_shortest(char *buf, size_t size, double v)
{
    if (isnan(v))
        return snprintf(buf, size, "nan");
    if (isinf(v))
        return snprintf(buf, size, v > 0 ? "inf" : "-inf");
    if (v == 0)
        v = 0;   /* -0 prints as 0: a sign on zero is noise to a reader */
    /* 17 significant digits always round-trip a double; fewer usually do
       and read better (0.3, not 0.29999999999999999) */
    int n = 0;
    for (int d = 15; d <= 17; d++) {
        n = snprintf(buf, size, "%.*g", d, v);
        if (d == 17 || strtod(buf, NULL) == v)
            break;
    }
    return n;
}
