/* literal.h - constants as C literals of the generated code. */
#ifndef MECHC_LITERAL_H
#define MECHC_LITERAL_H

#include "../base/strbuf.h"

#include <stdbool.h>

/* The shortest decimal of v that reads back exactly (as a float with
   real_float, with an f suffix), negative ones parenthesized: how
   constants are written. A double finite only as a double is
   HUGE_VALF in a float file. */
void emit_put_literal(StrBuf *sb, double v, bool real_float);

#endif
