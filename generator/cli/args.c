/* args.c - walks argv and reads option values (numbers, choices, lists); usage errors exit 2 through the caller. */
#include "cli.h"

#include <errno.h>
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
