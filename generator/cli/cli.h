/* cli.h - the subcommands and the small helpers they share (args.c, common.c). */
#ifndef MECHC_CLI_H
#define MECHC_CLI_H

#include "../base/limits.h"
#include "../engine/engine.h"

#include <stdbool.h>
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
} Args;

void args_init(Args *a, const char *command, int argc, char **argv);
/* Next option name (without its value), or NULL at the end. Positional
   arguments are consumed into a->file along the way. */
const char *args_next(Args *a);
/* The value of the option just returned. */
const char *args_value(Args *a, const char *option);
bool args_double(Args *a, const char *option, double *out);
bool args_int(Args *a, const char *option, int min, int max, int *out);
/* The --max-... options every command takes (examples/README.md, Limits):
   true when option is one of them, its value then parsed into limits
   (a->failed set on a bad value). args_limits_usage is their --help text. */
bool args_limit(Args *a, const char *option, MechLimits *limits);
extern const char args_limits_usage[];
/* --engine jit|generic|aot: true when option is --engine, its value then
   parsed into *engine (a->failed set on a bad value). */
bool args_engine(Args *a, const char *option, int *engine);
/* The value of option as an index into choices (NULL-terminated), or -1
   with a->failed set and a message naming the choices ("--real takes
   double or float, not 'long'"); -1 also when the value is missing. */
int args_choice(Args *a, const char *option, const char *const *choices);
/* A comma-separated list of exactly n finite numbers. */
bool args_vector(const char *command, const char *option, const char *text, int n, double *out);
void args_unknown(Args *a, const char *option);
bool args_need_file(Args *a);
bool args_is_help(const char *option);

/* ---- after the options (common.c) ---- */

/* Loads a->file (no file: the usage error of args_need_file) with limits
   (NULL: the defaults). On bad input prints the diagnostic and returns
   NULL: exit status 2. diag must outlive the Mech (pipeline_load). */
Mech *cli_load(Args *a, const MechLimits *limits, Diag *diag);
/* "mechc COMMAND: error: MESSAGE" for a failure reported in diag. */
void cli_error(const Args *a, const Diag *diag);
/* engine_open_with (options NULL: the defaults), the failure reported by
   cli_error. */
bool cli_engine_open(const Args *a, Engine *e, EngineKind kind, const Mech *mech,
                     const EngineOptions *options, Diag *diag);

int cmd_gen(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_bench(int argc, char **argv);

/* JSON number: %.17g, or null for NaN and infinities (JSON has neither). */
void json_number(FILE *out, double v);
void json_string(FILE *out, const char *s);
/* ["s0", "s1", ...] */
void json_string_list(FILE *out, const char *const *s, int n);

#endif
