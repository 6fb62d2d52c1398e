/* realfmt.c - shortest round-trip formatting of doubles, for graph dumps, laws and messages. */
#include "realfmt.h"

#include "../../runtime/host/mechrt_host.h"

/* The host runtime's formatter (run's CSV and JSON) defines the text: one
   copy, and its fast path serves the generator too. */
int realfmt_shortest(char *buf, size_t size, double v)
{
    return mechrt_format_real(buf, size, v, 0);
}
