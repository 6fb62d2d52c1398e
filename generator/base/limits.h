/* limits.h - the documented input limits; every one gives a clear error when passed. */
#ifndef MECHC_LIMITS_H
#define MECHC_LIMITS_H

typedef struct MechLimits {
    int max_file_bytes;     /* whole input file (default 4 MiB) */
    int max_line_length;    /* bytes per line, newline excluded (default 4096) */
    int max_depth;          /* expression nesting: parentheses, calls, unary ops (default 64) */
    int max_expr_tokens;    /* tokens in one statement (default 2000) */
    int max_coords;         /* coordinates (default 200000) */
    int max_rows;           /* constraint rows (default 200000) */
    int max_nodes;          /* expression-graph nodes incl. derivatives (default 20000000) */
} MechLimits;

static inline MechLimits mech_default_limits(void)
{
    MechLimits l = {
        .max_file_bytes = 4 << 20,
        .max_line_length = 4096,
        .max_depth = 64,
        .max_expr_tokens = 2000,
        .max_coords = 200000,
        .max_rows = 200000,
        .max_nodes = 20000000,
    };
    return l;
}

#endif
