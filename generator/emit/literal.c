/* literal.c - constants as C literals: the shared formatter's text, made a C constant. */
#include "literal.h"

#include "../../runtime/host/format_real.h"

#include <math.h>
#include <string.h>

void emit_put_literal(StrBuf *sb, double v, bool real_float)
{
    if (real_float && isinf((float)v)) {    /* finite as double, not as float */
        sb_puts(sb, v > 0 ? "HUGE_VALF" : "(-HUGE_VALF)");
        return;
    }
    char buf[64];
    if (v == 0 && signbit(v))   /* the formatter drops zero's sign; C keeps it */
        strcpy(buf, "-0");
    else
        mechrt_format_real(buf, sizeof buf, v, 0, real_float);
    if (!strpbrk(buf, ".eEn"))
        strcat(buf, ".0");
    bool negative = buf[0] == '-';
    if (negative)
        sb_putc(sb, '(');
    sb_puts(sb, buf);
    if (real_float)
        sb_putc(sb, 'f');
    if (negative)
        sb_putc(sb, ')');
}
