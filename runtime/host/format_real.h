/* format_real.h - a double (or a float) as decimal text: printf's %g, or the shortest that reads back. */
#ifndef MECHRT_FORMAT_REAL_H
#define MECHRT_FORMAT_REAL_H

#include <stdbool.h>
#include <stddef.h>

/* v as text: with digits == 0 the shortest of %.15g, %.16g, %.17g that
   reads back as v (0.3 stays "0.3"), else %.<digits>g. as_float reads v
   as the float (float)v: the shortest of %.6g .. %.9g that reads back as
   that float (how --real float files write constants). -0 is "0"; NaN
   and infinities are "nan", "inf", "-inf". Returns the length written.
   The one formatter of the tool: run's CSV and JSON, the reports' JSON,
   graph dumps and the generated C's literals. */
int mechrt_format_real(char *buf, size_t size, double v, int digits, bool as_float);

#endif
