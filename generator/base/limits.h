/* limits.h - the documented input limits; every one gives a clear error when passed.
 *
 * Each limit bounds the work or memory one input can cause, so hostile or
 * mistaken input ends in a diagnostic instead of exhausting the machine.
 * examples/README.md documents them; every command takes --max-... options
 * that change them (generator/cli/args.c, args_limit).
 */
#ifndef MECHC_LIMITS_H
#define MECHC_LIMITS_H

#include <limits.h>

typedef struct MechLimits {
    int max_file_bytes;     /* whole input file (default 4 MiB) */
    int max_line_length;    /* bytes per line, newline excluded (default 4096) */
    int max_name_length;    /* characters per name (default 255; row and coordinate
                               names become C string literals, which C99 bounds at 4095) */
    int max_depth;          /* expression nesting: parentheses, calls, unary ops (default 64) */
    int max_expr_tokens;    /* tokens in one statement (default 2000) */
    int max_coords;         /* coordinates (default 200000) */
    int max_rows;           /* constraint rows (default 200000) */
    int max_jac_entries;    /* rows x coordinates of the dense Jacobian (default 50000000:
                               400 MB of doubles), checked as the model is built; 0:
                               not checked there (run's sparse path forms no dense
                               Jacobian and checks only where it would, RunOptions) */
    int max_nodes;          /* expression-graph nodes incl. derivatives (default 2000000) */
    int max_code_ops;       /* operations in the generated C, all functions (default 4000000) */
    const char *jac_advice; /* ends max_jac_entries' error: how the command can do
                               without the dense Jacobian (gen: --sparse-only);
                               NULL: nothing */
} MechLimits;

/* Each limit's field, its option and the values the option accepts:
   X(field, option, min, max). The upper bounds keep what the limits
   protect: the parser's and differentiator's recursion stays far from the
   stack's end, and int indices (file offsets, the dense Jacobian of the
   generated C) cannot overflow. */
#define MECH_LIMIT_RANGES(X) \
    X(max_file_bytes, "--max-file-bytes", 1, INT_MAX - 1) \
    X(max_line_length, "--max-line-length", 1, INT_MAX - 1) \
    X(max_name_length, "--max-name-length", 1, 4000) \
    X(max_depth, "--max-depth", 1, 1000) \
    X(max_expr_tokens, "--max-expr-tokens", 1, 20000) \
    X(max_coords, "--max-coords", 1, 10000000) \
    X(max_rows, "--max-rows", 1, 10000000) \
    X(max_jac_entries, "--max-jac-entries", 1, INT_MAX) \
    X(max_nodes, "--max-nodes", 16, INT_MAX - 1) \
    X(max_code_ops, "--max-code-ops", 1, INT_MAX)

static inline MechLimits mech_default_limits(void)
{
    MechLimits l = {
        .max_file_bytes = 4 << 20,
        .max_line_length = 4096,
        .max_name_length = 255,
        .max_depth = 64,
        .max_expr_tokens = 2000,
        .max_coords = 200000,
        .max_rows = 200000,
        .max_jac_entries = 50000000,
        .max_nodes = 2000000,
        .max_code_ops = 4000000,
    };
    return l;
}

#endif
