/* common.c - what the analyses over time (run, sim, check) share: the linear-algebra choice, the status, the failure message and the names in it. */
#include "common.h"

#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

/* Components of a vector at least this fraction of its largest are named, at most NAMED_MAX. */
#define NAMED_SHARE 0.2
#define NAMED_MAX 6

const char *const analysis_linear_names[] = {"auto", "dense", "sparse", NULL};

double analysis_time_at(double t0, double t1, int steps, int i)
{
    if (i == steps)
        return t1;
    return t0 + (t1 - t0) * (double)i / (double)steps;
}

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

/* The names of the components of w at or above floor, largest first (at
   most NAMED_MAX); how many were named. */
static int name_picked(char *msg, size_t size, const char *const *names, const double *w, int n,
                       double floor)
{
    int picked[NAMED_MAX], count = 0;
    while (count < NAMED_MAX) {
        int best = -1;
        for (int i = 0; i < n; i++) {
            bool taken = false;
            for (int c = 0; c < count; c++)
                taken = taken || picked[c] == i;
            if (!taken && w[i] >= floor && (best < 0 || w[i] > w[best]))
                best = i;
        }
        if (best < 0)
            break;
        picked[count++] = best;
    }
    for (int c = 0; c < count; c++)
        analysis_msgf(msg, size, "%s%s", c == 0 ? "" : c + 1 == count ? " and " : ", ",
                      names[picked[c]]);
    return count;
}

void analysis_name_list(char *msg, size_t size, const char *const *names, const double *w,
                        int n)
{
    double wmax = 0;
    for (int i = 0; i < n; i++)
        if (w[i] > wmax)
            wmax = w[i];
    name_picked(msg, size, names, w, n, NAMED_SHARE * wmax);
}

int analysis_name_above(char *msg, size_t size, const char *const *names, const double *w,
                        int n, double floor)
{
    int above = 0;
    for (int i = 0; i < n; i++)
        above += w[i] >= floor;
    int count = name_picked(msg, size, names, w, n, floor);
    if (above > count)
        analysis_msgf(msg, size, ", and %d more", above - count);
    return count;
}
