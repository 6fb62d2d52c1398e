/* svg_common.h - what the SVG writers share: escaping, compact numbers, colours, tick steps. */
#ifndef MECHC_SVG_COMMON_H
#define MECHC_SVG_COMMON_H

#include <stdio.h>

/* Writes s with & < > " ' escaped, so text from file names or the command
   line can go into element content and attribute values alike. Bytes below
   0x20 other than tab and newline (not allowed in XML 1.0) become '?'. */
void svg_put_escaped(FILE *out, const char *s);

/* Formats v rounded to `decimals` digits after the point, trailing zeros
   and a trailing point removed, never an exponent and never "-0". buf must
   hold SVG_NUM_MAX bytes; returns buf. Values beyond +-1e15 are clamped. */
enum { SVG_NUM_MAX = 40 };
char *svg_fmt_fixed(char *buf, double v, int decimals);

/* Formats v with `sig` significant digits (1..15), without an exponent
   for 1e-6 <= |v| < 1e15, trailing zeros removed. For labels. */
char *svg_fmt_sig(char *buf, double v, int sig);

/* A 1-2-5 tick step: the nicest step giving about `target` intervals over
   span (> 0). */
double svg_nice_step(double span, int target);

/* Colours for series and bodies, cycled. */
enum { SVG_PALETTE_SIZE = 10 };
extern const char *const svg_palette[SVG_PALETTE_SIZE];

#endif
