/* template.c - placeholder substitution: @NAME@ (upper case, digits, _) becomes its value. */
#include "template.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int placeholder_length(const char *p)
{
    int n = 0;
    while ((p[n] >= 'A' && p[n] <= 'Z') || (p[n] >= '0' && p[n] <= '9') || p[n] == '_')
        n++;
    return n > 0 && p[n] == '@' ? n : 0;
}

const char *template_render(StrBuf *out, const char *tmpl, const TemplateVar *vars, int nvars)
{
    const char *p = tmpl;
    /* a first line "@@ ..." says what the template is for: not output */
    if (p[0] == '@' && p[1] == '@') {
        const char *nl = strchr(p, '\n');
        p = nl ? nl + 1 : p + strlen(p);
    }
    while (*p) {
        const char *at = strchr(p, '@');
        if (!at) {
            sb_puts(out, p);
            break;
        }
        sb_putn(out, p, (size_t)(at - p));
        int n = placeholder_length(at + 1);
        if (n == 0) {
            sb_putc(out, '@');
            p = at + 1;
            continue;
        }
        int i = 0;
        while (i < nvars && !(strlen(vars[i].name) == (size_t)n
                              && memcmp(vars[i].name, at + 1, (size_t)n) == 0))
            i++;
        if (i == nvars)
            return at + 1;
        sb_puts(out, vars[i].value);
        p = at + n + 2;
    }
    return NULL;
}

void template_set(TemplateVar *vars, int nvars, const char *name, const char *value)
{
    for (int i = 0; i < nvars; i++)
        if (strcmp(vars[i].name, name) == 0) {
            vars[i].value = value;
            return;
        }
    fprintf(stderr, "mechc: internal error: no template variable '%s'\n", name);
    abort();
}

_Noreturn void template_placeholder_bug(const char *name)
{
    fprintf(stderr, "mechc: internal error: template placeholder '%.20s' has no value\n", name);
    abort();
}
