/* args.c - option parsing shared by every subcommand; usage errors exit 2 through the caller. */
#include "cli.h"

#include "../base/strbuf.h"
#include "../../runtime/host/mechrt_host.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

void args_init(Args *a, const char *command, int argc, char **argv)
{
    *a = (Args){.argc = argc, .argv = argv, .i = 0, .command = command};
}

const char *args_next(Args *a)
{
    char *name = a->name;
    if (a->pending) {           /* --flag=value on an option that takes none */
        fprintf(stderr, "mechc %s: error: %s takes no value (given '%s')\n", a->command,
                a->name, a->pending);
        a->failed = true;
        return NULL;
    }
    while (a->i < a->argc) {
        char *arg = a->argv[a->i++];
        if (strcmp(arg, "--") == 0 && !a->options_done) {
            a->options_done = true;     /* the rest are file names */
            continue;
        }
        if (arg[0] == '-' && arg[1] == '-' && arg[2] && !a->options_done) {
            const char *eq = strchr(arg, '=');
            if (eq) {
                size_t n = (size_t)(eq - arg) < sizeof a->name - 1 ? (size_t)(eq - arg) : sizeof a->name - 1;
                memcpy(name, arg, n);
                name[n] = '\0';
                a->pending = eq + 1;
                return name;
            }
            return arg;
        }
        if (arg[0] == '-' && arg[1] && arg[1] != '-' && !a->options_done)
            return arg;         /* -o, -h */
        if (a->file) {
            fprintf(stderr, "mechc %s: error: more than one input file ('%s' and '%s')\n",
                    a->command, a->file, arg);
            a->failed = true;
            return NULL;
        }
        a->file = arg;
    }
    return NULL;
}

const char *args_value(Args *a, const char *option)
{
    if (a->pending) {
        const char *v = a->pending;
        a->pending = NULL;
        return v;
    }
    if (a->i >= a->argc) {
        fprintf(stderr, "mechc %s: error: %s needs a value\n", a->command, option);
        a->failed = true;
        return NULL;
    }
    return a->argv[a->i++];
}

static bool parse_double(const char *text, double *out)
{
    if (strpbrk(text, "xXpP"))     /* strtod would read hexadecimal floats */
        return false;
    char *end;
    errno = 0;
    *out = strtod(text, &end);
    while (*end == ' ')
        end++;
    return end != text && *end == '\0';
}

bool args_double(Args *a, const char *option, double *out)
{
    const char *v = args_value(a, option);
    if (!v)
        return false;
    if (!parse_double(v, out) || !isfinite(*out)) {
        fprintf(stderr, "mechc %s: error: %s needs a finite number, not '%s'\n", a->command, option, v);
        a->failed = true;
        return false;
    }
    return true;
}

bool args_int(Args *a, const char *option, int min, int max, int *out)
{
    const char *v = args_value(a, option);
    if (!v)
        return false;
    char *end;
    errno = 0;
    long n = strtol(v, &end, 10);
    if (end == v || *end || errno || n < min || n > max) {
        fprintf(stderr, "mechc %s: error: %s needs a whole number from %d to %d, not '%s'\n",
                a->command, option, min, max, v);
        a->failed = true;
        return false;
    }
    *out = (int)n;
    return true;
}

/* Each limit's option and the range it accepts. The upper bounds keep what
   the limits protect: the parser's and differentiator's recursion stays
   far from the stack's end, and int indices (file offsets, the dense
   Jacobian of the generated C) cannot overflow. */
static const struct LimitOption {
    const char *option;
    size_t offset;
    int min, max;
} limit_options[] = {
    {"--max-file-bytes", offsetof(MechLimits, max_file_bytes), 1, INT_MAX - 1},
    {"--max-line-length", offsetof(MechLimits, max_line_length), 1, INT_MAX - 1},
    {"--max-name-length", offsetof(MechLimits, max_name_length), 1, 4000},
    {"--max-depth", offsetof(MechLimits, max_depth), 1, 1000},
    {"--max-expr-tokens", offsetof(MechLimits, max_expr_tokens), 1, 20000},
    {"--max-coords", offsetof(MechLimits, max_coords), 1, 10000000},
    {"--max-rows", offsetof(MechLimits, max_rows), 1, 10000000},
    {"--max-jac-entries", offsetof(MechLimits, max_jac_entries), 1, INT_MAX},
    {"--max-nodes", offsetof(MechLimits, max_nodes), 16, INT_MAX - 1},
    {"--max-code-ops", offsetof(MechLimits, max_code_ops), 1, INT_MAX},
};

const char args_limits_usage[] =
    "limits (defaults in examples/README.md, section Limits; a value N each):\n"
    "  --max-file-bytes --max-line-length --max-name-length --max-depth\n"
    "  --max-expr-tokens --max-coords --max-rows --max-jac-entries --max-nodes\n"
    "  --max-code-ops\n";

bool args_limit(Args *a, const char *option, MechLimits *limits)
{
    for (size_t i = 0; i < sizeof limit_options / sizeof *limit_options; i++) {
        const struct LimitOption *l = &limit_options[i];
        if (strcmp(option, l->option) != 0)
            continue;
        int value;
        if (args_int(a, option, l->min, l->max, &value))
            memcpy((char *)limits + l->offset, &value, sizeof value);
        return true;
    }
    return false;
}

bool args_engine(Args *a, const char *option, int *engine)
{
    if (strcmp(option, "--engine") != 0)
        return false;
    const char *v = args_value(a, option);
    if (v && (*engine = engine_from_name(v)) < 0) {
        fprintf(stderr, "mechc %s: error: --engine takes jit, generic or aot, not '%s'\n", a->command, v);
        a->failed = true;
    }
    return true;
}

int args_choice(Args *a, const char *option, const char *const *choices)
{
    const char *v = args_value(a, option);
    if (!v)
        return -1;
    int n = 0;
    for (; choices[n]; n++)
        if (strcmp(v, choices[n]) == 0)
            return n;
    fprintf(stderr, "mechc %s: error: %s takes ", a->command, option);
    for (int i = 0; i < n; i++)
        fprintf(stderr, "%s%s", i == 0 ? "" : i == n - 1 ? " or " : ", ", choices[i]);
    fputs(", not '", stderr);
    for (const char *c = v; *c; c++)    /* control bytes shown as '?' */
        fputc((unsigned char)*c < 0x20 || *c == 0x7f ? '?' : *c, stderr);
    fputs("'\n", stderr);
    a->failed = true;
    return -1;
}

bool args_vector(const char *command, const char *option, const char *text, int n, double *out)
{
    int count = 0;
    const char *p = text;
    char item[128];
    while (true) {
        size_t len = strcspn(p, ",");
        if (len >= sizeof item) {
            fprintf(stderr, "mechc %s: error: %s: value %d is too long\n", command, option, count + 1);
            return false;
        }
        memcpy(item, p, len);
        item[len] = '\0';
        double v;
        if (!parse_double(item, &v)) {
            fprintf(stderr, "mechc %s: error: %s: '%s' is not a number\n", command, option, item);
            return false;
        }
        /* NaN and infinities (also 1e999, which overflows) are refused, as
           for --t: the kernels would only pass them on. */
        if (!isfinite(v)) {
            fprintf(stderr, "mechc %s: error: %s: value %d, '%s', is not a finite number\n",
                    command, option, count + 1, item);
            return false;
        }
        if (count < n)
            out[count] = v;
        count++;
        p += len;
        if (!*p)
            break;
        p++;
    }
    if (count != n) {
        fprintf(stderr, "mechc %s: error: %s needs %d comma-separated values (one per coordinate), got %d\n",
                command, option, n, count);
        return false;
    }
    return true;
}

void args_unknown(Args *a, const char *option)
{
    fprintf(stderr, "mechc %s: error: unknown option '%s' (see 'mechc %s --help')\n",
            a->command, option, a->command);
    a->failed = true;
}

bool args_need_file(Args *a)
{
    if (a->failed)
        return false;
    if (!a->file) {
        fprintf(stderr, "mechc %s: error: no input file (see 'mechc %s --help')\n", a->command, a->command);
        a->failed = true;
        return false;
    }
    return true;
}

bool args_is_help(const char *option)
{
    return strcmp(option, "--help") == 0 || strcmp(option, "-h") == 0;
}

void json_number(FILE *out, double v)
{
    char buf[40];
    if (!isfinite(v)) {
        fputs("null", out);
        return;
    }
    mechrt_format_real(buf, sizeof buf, v, 0);  /* as run's JSON: 0.3, not 0.29999999999999999 */
    fputs(buf, out);
}

void json_string(FILE *out, const char *s)
{
    StrBuf sb;
    sb_init(&sb);
    sb_put_json_string(&sb, s);
    fputs(sb.data, out);
    sb_free(&sb);
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
