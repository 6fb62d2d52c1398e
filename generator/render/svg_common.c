/* svg_common.c - escaping, compact number formatting and tick steps for the SVG writers.
 *
 * SVG files stay small and byte-for-byte reproducible when numbers are
 * printed with a fixed, small precision and no redundant zeros: the writers
 * round pixel coordinates to 0.1 px, which is below what any screen shows.
 */
#include "svg_common.h"

#include <math.h>
#include <string.h>

/* Tableau-10 like colours, distinguishable and printable. */
const char *const svg_palette[SVG_PALETTE_SIZE] = {
    "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#17becf",
    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#d62728",
};

void svg_put_escaped(FILE *out, const char *s)
{
    for (; s && *s; s++) {
        unsigned char c = (unsigned char)*s;
        switch (c) {
        case '&': fputs("&amp;", out); break;
        case '<': fputs("&lt;", out); break;
        case '>': fputs("&gt;", out); break;
        case '"': fputs("&quot;", out); break;
        case '\'': fputs("&#39;", out); break;
        default:
            fputc(c < 0x20 && c != '\t' && c != '\n' ? '?' : (int)c, out);
        }
    }
}

/* Removes trailing zeros after a decimal point, then the point itself. */
static void trim_zeros(char *buf)
{
    char *dot = strchr(buf, '.');
    if (!dot)
        return;
    char *end = buf + strlen(buf);
    while (end > dot + 1 && end[-1] == '0')
        *--end = '\0';
    if (end == dot + 1)
        *dot = '\0';
}

char *svg_fmt_fixed(char *buf, double v, int decimals)
{
    if (!isfinite(v))
        v = 0;
    if (v > 1e15)
        v = 1e15;
    if (v < -1e15)
        v = -1e15;
    snprintf(buf, SVG_NUM_MAX, "%.*f", decimals, v);
    trim_zeros(buf);
    if (strcmp(buf, "-0") == 0)
        strcpy(buf, "0");
    return buf;
}

char *svg_fmt_sig(char *buf, double v, int sig)
{
    if (sig < 1)
        sig = 1;
    if (sig > 15)
        sig = 15;
    if (!isfinite(v) || v == 0) {
        strcpy(buf, isfinite(v) ? "0" : (isnan(v) ? "nan" : v > 0 ? "inf" : "-inf"));
        return buf;
    }
    double a = fabs(v);
    if (a < 1e-6 || a >= 1e15) {
        snprintf(buf, SVG_NUM_MAX, "%.*g", sig, v);
        return buf;
    }
    int mag = (int)floor(log10(a));       /* a = d.ddd * 10^mag */
    int decimals = sig - 1 - mag;
    if (decimals < 0)
        decimals = 0;
    return svg_fmt_fixed(buf, v, decimals);
}

double svg_nice_step(double span, int target)
{
    if (!(span > 0) || !isfinite(span))
        return 1;
    if (target < 1)
        target = 1;
    double raw = span / target;
    double p = pow(10, floor(log10(raw)));
    double f = raw / p;
    double nice = f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10;
    return nice * p;
}
