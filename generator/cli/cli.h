/* cli.h - the subcommands and the small helpers they share (args.c, options.c, common.c, json.c). */
#ifndef MECHC_CLI_H
#define MECHC_CLI_H

#include "../base/limits.h"
#include "../engine/engine.h"
#include "../lib/lib.h"         /* the commands are clients of libmechc (mechc.h) */

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* Exit statuses of spec section 3. */
enum { EXIT_OK = 0, EXIT_ANALYSIS = 1, EXIT_USAGE = 2 };

/* Walks argv: positional FILE and --options (as "--opt value" or "--opt=value"). */
typedef struct Args {
    int argc, i;
    char **argv;
    const char *command;
    const char *file;       /* the one positional argument */
    const char *pending;    /* value given as --opt=value, until consumed */
    bool options_done;      /* after "--": every argument is a file name */
    char name[64];          /* the option name split off --opt=value */
    bool failed;
    /* --design NAME=VALUE[,NAME=VALUE ...], every command's (design.c) */
    const char *design[16];
    int ndesign;
} Args;

void args_init(Args *a, const char *command, int argc, char **argv);
/* Next option name (without its value), or NULL at the end. Positional
   arguments are consumed into a->file along the way. */
const char *args_next(Args *a);
/* The value of the option just returned. */
const char *args_value(Args *a, const char *option);
bool args_double(Args *a, const char *option, double *out);
bool args_int(Args *a, const char *option, int min, int max, int *out);
/* The value of option as an index into choices (NULL-terminated), or -1
   with a->failed set and a message naming the choices ("--real takes
   double or float, not 'long'"); -1 also when the value is missing. */
int args_choice(Args *a, const char *option, const char *const *choices);
/* A comma-separated list of exactly n finite numbers. */
bool args_vector(const char *command, const char *option, const char *text, int n, double *out);
void args_unknown(Args *a, const char *option);
bool args_need_file(Args *a);
bool args_is_help(const char *option);

/* ---- option tables (options.c) ---- */

/* What an option's value is, and the type of the field it is stored in. */
typedef enum CliKind {
    CLI_FLAG,       /* no value: sets a bool */
    CLI_CLEAR,      /* no value: clears a bool (--no-aot) */
    CLI_INT,        /* a whole number in [min, max], decimal: int */
    CLI_REAL,       /* a finite number, in range (see CliOption.what): double */
    CLI_CHOICE,     /* one of choices: its index, int */
    CLI_STRING,     /* any text: const char *, pointing into argv */
    CLI_LIST        /* repeatable text, at most max of them: CliList */
} CliKind;

enum { CLI_LIST_MAX = 16 };
typedef struct CliList {
    int n;
    const char *items[CLI_LIST_MAX];
} CliList;

/* One option of a command: how to read it, where its value goes, how
   --help shows it. Adding an option is one entry and one field. */
typedef struct CliOption {
    const char *name;           /* "--steps" */
    CliKind kind;
    size_t offset;              /* of its field in the command's options struct */
    double min, max;            /* CLI_INT, CLI_REAL: the values accepted; CLI_LIST: most items */
    bool above_min;             /* CLI_REAL: min itself is refused */
    /* CLI_REAL: the values accepted in words, for "OPTION needs WHAT" (NULL:
       any finite number, min and max unused); CLI_LIST: the items, for "at
       most N OPTION WHAT" */
    const char *what;
    bool echo;                  /* CLI_REAL: the range error ends ", not VALUE" */
    const char *const *choices; /* CLI_CHOICE: NULL-terminated */
    const char *alias;          /* a second name, not shown by --help */
    const char *metavar;        /* --help shows "--steps N" */
    /* --help text, lines split by '\n'; NULL: shown on the line of the
       option before ("--t0 T, --t1 T") */
    const char *help;
} CliOption;

/* offsetof(T, field); the compiler warns ("incompatible pointer type")
   when field is not of type type, so a kind cannot meet a wrong field. */
#define CLI_AT(T, field, type) (offsetof(T, field) + 0 * sizeof((type *){0} = &((T *)0)->field))
/* An entry's kind and field: {"--steps", CLI_INT_AT(RunCli, ro.steps, 1, 1000), ...}. */
#define CLI_FLAG_AT(T, f)           .kind = CLI_FLAG, .offset = CLI_AT(T, f, bool)
#define CLI_CLEAR_AT(T, f)          .kind = CLI_CLEAR, .offset = CLI_AT(T, f, bool)
#define CLI_INT_AT(T, f, lo, hi)    .kind = CLI_INT, .offset = CLI_AT(T, f, int), .min = (lo), .max = (hi)
#define CLI_REAL_AT(T, f)           .kind = CLI_REAL, .offset = CLI_AT(T, f, double)
#define CLI_CHOICE_AT(T, f, list)   .kind = CLI_CHOICE, .offset = CLI_AT(T, f, int), .choices = (list)
#define CLI_STRING_AT(T, f)         .kind = CLI_STRING, .offset = CLI_AT(T, f, const char *)
#define CLI_LIST_AT(T, f, most)     .kind = CLI_LIST, .offset = CLI_AT(T, f, CliList), .max = (most)
/* CLI_REAL ranges, for entries that also set .what. */
#define CLI_POSITIVE                .min = 0, .above_min = true, .max = HUGE_VAL
#define CLI_NONNEGATIVE             .min = 0, .max = HUGE_VAL

/* A command's options and --help. Every command also takes the --max-...
   limits (examples/README.md, Limits) into the mechc_limits at limits_offset. */
typedef struct CliCommand {
    const char *name;           /* "run" */
    const char *usage;          /* --help before the options: synopsis, description */
    const CliOption *options;
    int count;
    int column;                 /* where --help starts an option's text */
    const char *epilogue;       /* --help after the options, or NULL */
    size_t limits_offset;
    /* After the options, before the file is loaded (NULL: nothing): checks
       them together and fills what they imply; false when they cannot be
       used (reported). Called also when one option was wrong. */
    bool (*finish)(Args *a, void *opts);
    /* The command's work on the loaded mechanism (model->mech, its
       diagnostics' source &model->diag); returns the exit status. */
    int (*run)(const Args *a, mechc_model *model, void *opts);
} CliCommand;

#define CLI_OPTIONS(table) .options = (table), .count = (int)(sizeof(table) / sizeof *(table))

/* Starts a on argv and reads its options into opts (the command's options
   struct, holding the defaults). false after printing --help (exit status
   0); else true, with a->failed set when an option was wrong (reported). */
bool cli_parse(Args *a, const CliCommand *cmd, int argc, char **argv, void *opts);
void cli_print_help(const CliCommand *cmd, FILE *out);

/* ---- after the options (common.c) ---- */

/* A whole command: reads the options into opts (holding the defaults),
   then cmd->finish, loads the file with the limits read, runs cmd->run and
   frees the model. Returns the exit status. */
int cli_main(const CliCommand *cmd, int argc, char **argv, void *opts);
/* mechc_load_file_with of a->file (no file: the usage error of
   args_need_file) with limits (NULL: the defaults). On bad input prints
   the diagnostic (FILE:LINE:COL, the line, a caret) and returns NULL:
   exit status 2. */
mechc_model *cli_load(Args *a, const mechc_limits *limits);
/* --design's values into m's design (design.c): the design the command
   evaluates and gen writes as P_p0. false (reported, exit status 2) for an
   unknown name, a value that is not a finite number, or a file without
   design parameters. */
bool cli_apply_design(const Args *a, Model *m);
/* --design's line of --help. */
void cli_print_design_help(FILE *out);
/* PATH opened for writing (created or truncated), or NULL after
   "mechc COMMAND: error: cannot write ..." on stderr; never blocks on a
   named pipe that no process reads. */
FILE *cli_open_output(const char *command, const char *path);
/* "mechc COMMAND: error: MESSAGE" for a failure reported in diag. */
void cli_error(const Args *a, const Diag *diag);
/* mechc_compile_with the engine of kind (o NULL: the defaults), the
   failure reported as cli_error does; NULL then. */
mechc_kernels *cli_compile(const Args *a, mechc_model *model, EngineKind kind,
                           const mechc_compile_options *o);

int cmd_gen(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_sim(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_fit(int argc, char **argv);

/* What `info --json` prints (cmd_info.c), to out; libmechc's mechc_info_json too. */
struct InfoReport;
void info_print_json(FILE *out, const struct InfoReport *rep);

/* ---- JSON (json.c) ---- */

/* JSON number: %.17g, or null for NaN and infinities (JSON has neither). */
void json_number(FILE *out, double v);
void json_string(FILE *out, const char *s);
/* ["s0", "s1", ...] */
void json_string_list(FILE *out, const char *const *s, int n);

#endif
