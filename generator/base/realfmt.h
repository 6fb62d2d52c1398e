/* realfmt.h - a double as the shortest text that reads back as the same double. */
#ifndef MECHC_REALFMT_H
#define MECHC_REALFMT_H

#include <stddef.h>

/* The shortest of %.15g, %.16g, %.17g that reads back as v (0.3 stays
   "0.3"); -0 is "0"; NaN and infinities are "nan", "inf", "-inf". Returns
   the length written. It is mechrt_format_real(buf, size, v, 0) of the
   host runtime: runtime/ must not depend on generator/, so the one copy
   lives there. */
int realfmt_shortest(char *buf, size_t size, double v);

#endif
