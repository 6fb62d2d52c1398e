/* design.c - --design NAME=VALUE: the design a command evaluates, without compiling again. */
#include "cli.h"

#include "../base/arena.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

void cli_print_design_help(FILE *out)
{
    fputs("design parameters (`design NAME = value` in the file):\n"
          "  --design NAME=VALUE[,NAME=VALUE...]  evaluate at these values instead of\n"
          "                 the file's (repeatable; gen writes them as PREFIX_p0)\n", out);
}

/* The index of the design parameter called name (len bytes), or -1. */
static int find_design(const Model *m, const char *name, size_t len)
{
    for (int j = 0; j < m->np; j++)
        if (strlen(m->design_names[j]) == len && strncmp(m->design_names[j], name, len) == 0)
            return j;
    return -1;
}

/* One NAME=VALUE of item at *s; false (reported) when it cannot be used
   or names a parameter already given (seen: one flag per parameter). */
static bool apply_one(const Args *a, Model *m, const char *item, size_t len, bool *seen)
{
    const char *eq = memchr(item, '=', len);
    if (!eq) {
        fprintf(stderr, "mechc %s: error: --design takes NAME=VALUE, not '%.*s'\n",
                a->command, (int)len, item);
        return false;
    }
    int j = find_design(m, item, (size_t)(eq - item));
    if (j < 0) {
        fprintf(stderr, "mechc %s: error: --design: '%.*s' is not a design parameter of %s "
                "(it has:", a->command, (int)(eq - item), item, m->file);
        for (int k = 0; k < m->np; k++)
            fprintf(stderr, " %s", m->design_names[k]);
        fputs(")\n", stderr);
        return false;
    }
    if (seen[j]) {
        fprintf(stderr, "mechc %s: error: --design: '%s' is given more than once\n",
                a->command, m->design_names[j]);
        return false;
    }
    seen[j] = true;
    char buf[64];
    size_t vlen = len - (size_t)(eq + 1 - item);
    char *end = NULL;
    double v = 0;
    if (vlen > 0 && vlen < sizeof buf) {
        memcpy(buf, eq + 1, vlen);
        buf[vlen] = '\0';
        errno = 0;
        v = strtod(buf, &end);
    }
    if (!end || *end || end == buf || errno == ERANGE || !isfinite(v)) {
        fprintf(stderr, "mechc %s: error: --design: the value of '%s' must be a finite "
                "number, not '%.*s'\n", a->command, m->design_names[j], (int)vlen, eq + 1);
        return false;
    }
    m->design_p0[j] = v;
    return true;
}

bool cli_apply_design(const Args *a, Model *m)
{
    if (a->ndesign == 0)
        return true;
    if (m->np == 0) {
        fprintf(stderr, "mechc %s: error: --design: %s has no design parameters (declare "
                "them with `design NAME = value`)\n", a->command, m->file);
        return false;
    }
    bool *seen = xcalloc((size_t)m->np, sizeof *seen);
    bool ok = true;
    for (int i = 0; i < a->ndesign && ok; i++)
        for (const char *s = a->design[i]; *s && ok;) {
            size_t len = strcspn(s, ",");
            ok = apply_one(a, m, s, len, seen);
            s += len + (s[len] == ',');
        }
    free(seen);
    if (ok)
        model_set_design(m, NULL);
    return ok;
}
