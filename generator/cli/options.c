/* options.c - reads a command's options from its option table, and prints its --help from the same table. */
#include "cli.h"

#include <limits.h>
#include <string.h>

/* The --max-... options of every command, into a mechc_limits. */
#define LIMIT_OPTION(field, option, lo, hi) {option, CLI_INT_AT(mechc_limits, field, lo, hi)},
static const CliOption limit_options[] = {MECH_LIMIT_RANGES(LIMIT_OPTION)};
#undef LIMIT_OPTION
enum { LIMIT_COUNT = (int)(sizeof limit_options / sizeof *limit_options) };

static const CliOption *find(const CliOption *table, int count, const char *name)
{
    for (int i = 0; i < count; i++)
        if (strcmp(name, table[i].name) == 0 || (table[i].alias && strcmp(name, table[i].alias) == 0))
            return &table[i];
    return NULL;
}

static void read_real(Args *a, const CliOption *o, const char *name, double *field)
{
    double v;
    if (!args_double(a, name, &v))
        return;
    if (o->what && (v < o->min || (o->above_min && v == o->min) || v > o->max)) {
        if (o->echo)
            fprintf(stderr, "mechc %s: error: %s needs %s, not %g\n", a->command, name, o->what, v);
        else
            fprintf(stderr, "mechc %s: error: %s needs %s\n", a->command, name, o->what);
        a->failed = true;
        return;
    }
    *field = v;
}

static void read_item(Args *a, const CliOption *o, const char *name, CliList *list)
{
    const char *v = args_value(a, name);
    if (v && list->n >= (int)o->max) {
        fprintf(stderr, "mechc %s: error: at most %d %s %s\n", a->command, (int)o->max, name, o->what);
        a->failed = true;
    } else if (v) {
        list->items[list->n++] = v;
    }
}

/* Reads the value of o, given as name, into its field. */
static void read_option(Args *a, const CliOption *o, const char *name, char *base)
{
    void *field = base + o->offset;
    int choice;
    const char *text;
    switch (o->kind) {
    case CLI_FLAG:
    case CLI_CLEAR:
        *(bool *)field = o->kind == CLI_FLAG;
        break;
    case CLI_INT:
        args_int(a, name, (int)o->min, (int)o->max, field);
        break;
    case CLI_REAL:
        read_real(a, o, name, field);
        break;
    case CLI_CHOICE:
        if ((choice = args_choice(a, name, o->choices)) >= 0)
            *(int *)field = choice;
        break;
    case CLI_STRING:
        if ((text = args_value(a, name)))
            *(const char **)field = text;
        break;
    case CLI_LIST:
        read_item(a, o, name, field);
        break;
    }
}

bool cli_parse(Args *a, const CliCommand *cmd, int argc, char **argv, void *opts)
{
    const char *name;
    const CliOption *o;
    args_init(a, cmd->name, argc, argv);
    while (!a->failed && (name = args_next(a))) {
        if (args_is_help(name)) {
            cli_print_help(cmd, stdout);
            return false;
        }
        if (strcmp(name, "--design") == 0) {
            const char *v = args_value(a, name);
            if (v && a->ndesign == (int)(sizeof a->design / sizeof *a->design)) {
                fprintf(stderr, "mechc %s: error: --design given more than %d times\n",
                        a->command, a->ndesign);
                a->failed = true;
            } else if (v) {
                a->design[a->ndesign++] = v;
            }
        } else if ((o = find(limit_options, LIMIT_COUNT, name)))
            read_option(a, o, name, (char *)opts + cmd->limits_offset);
        else if ((o = find(cmd->options, cmd->count, name)))
            read_option(a, o, name, opts);
        else
            args_unknown(a, name);
    }
    return true;
}

/* ---- --help ---- */

/* "--steps N", and ", --t1 T" for each option after o shown on its line. */
static void format_label(const CliOption *o, const CliOption *end, char *buf, size_t size)
{
    size_t n = 0;
    do {
        n += (size_t)snprintf(buf + n, size - n, "%s%s%s%s", n ? ", " : "", o->name,
                              o->metavar ? " " : "", o->metavar ? o->metavar : "");
        if (n >= size)
            return;
    } while (++o < end && !o->help);
}

/* "  LABEL   first line", further lines indented to column. */
static void print_option(FILE *out, const char *label, const char *help, int column)
{
    const char *line = help;
    fprintf(out, "  %-*s ", column - 3, label);
    while (true) {
        size_t len = strcspn(line, "\n");
        fprintf(out, "%.*s\n", (int)len, line);
        if (!line[len])
            break;
        line += len + 1;
        fprintf(out, "%*s", column, "");
    }
}

/* The limits' names, wrapped before column 80. */
static void print_limits(FILE *out)
{
    fputs("limits (defaults in examples/README.md, section Limits; a value N each):\n", out);
    int col = 0;
    for (int i = 0; i < LIMIT_COUNT; i++) {
        int len = (int)strlen(limit_options[i].name);
        if (col > 0 && col + 1 + len >= 80) {
            fputc('\n', out);
            col = 0;
        }
        col += fprintf(out, "%s%s", col ? " " : "  ", limit_options[i].name);
    }
    fputc('\n', out);
}

void cli_print_help(const CliCommand *cmd, FILE *out)
{
    const CliOption *end = cmd->options + cmd->count;
    fputs(cmd->usage, out);
    for (const CliOption *o = cmd->options; o < end; o++) {
        if (!o->help)
            continue;       /* on the line of the option before */
        char label[128];
        format_label(o, end, label, sizeof label);
        print_option(out, label, o->help, cmd->column);
    }
    if (cmd->epilogue)
        fputs(cmd->epilogue, out);
    cli_print_design_help(out);
    print_limits(out);
}
