/* json.c - the small JSON writers of the reports (check, info, eval, bench); strings escaped by the host runtime's escaper. */
#include "cli.h"

#include "../../runtime/host/mechrt_host.h"

#include <math.h>

void json_number(FILE *out, double v)
{
    char buf[40];
    if (!isfinite(v)) {
        fputs("null", out);
        return;
    }
    mechrt_format_real(buf, sizeof buf, v, 0, false);  /* as run's JSON: 0.3, not 0.29999999999999999 */
    fputs(buf, out);
}

void json_string(FILE *out, const char *s)
{
    mechrt_json_string(out, s);
}

void json_string_list(FILE *out, const char *const *s, int n)
{
    fputc('[', out);
    for (int i = 0; i < n; i++) {
        fputs(i ? ", " : "", out);
        json_string(out, s[i]);
    }
    fputc(']', out);
}
