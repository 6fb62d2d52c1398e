/* roll.h - loop-rolled emission: rows of one shape written once, as a loop over tables of constants and indices. */
#ifndef MECHC_ROLL_H
#define MECHC_ROLL_H

#include "../base/strbuf.h"
#include "../diff/kinematics.h"
#include "../sched/sched.h"

#include <stdbool.h>

/* How a loop body's graph is printed: its leaves other than constants and
   t are OP_VAR nodes whose a is a slot (a coordinate, a velocity, a sin or
   cos of an angle, a constant that differs between the rows), and each
   store's index is a slot too; the hooks print them for the loop's row i. */
typedef struct RollHooks {
    void (*leaf)(void *ctx, StrBuf *sb, int slot);
    void (*store)(void *ctx, StrBuf *sb, const SchedOutput *o);     /* "array[...] = " */
    void *ctx;
} RollHooks;

/* Writes a loop body's statements with the emitter's scheduler and
   printer (emit.c, expr.c); takes outs and returns the body's operations. */
typedef int (*RollBodyWriter)(void *emitter, const Dag *body, SchedOutput *outs, int n,
                              const RollHooks *hooks, StrBuf *sb);

typedef struct RollContext {
    const Kinematics *kin;
    const char *prefix;         /* P: the tables are P_FUNCTION_r... */
    const char *function;       /* "phi", "jac_nz", ... */
    bool real_float;
    /* The emitter's trigonometry (trig.c): the pair function (NULL: sin
       and cos as written), and the names for an angle of which only the
       sin or only the cos is used (NULL: the pair). */
    const char *sincos_name, *sin_name, *cos_name;
    const char *sincos2_name;   /* two angles a call (trig.c), or NULL */
    int min_members;            /* fewest rows of one shape worth a loop */
    RollBodyWriter write_body;
    void *emitter;
    bool *sincos_used, *single_used, *sincos2_used;     /* set when the loops call them */
} RollContext;

/* Rolls, among the n outputs of one function (row by row, as the emitter
   collects them), each group of at least min_members joints' rows of the
   same shape: its tables go to parts, its loop to body, after one loop
   that computes the sin and cos of every angle the loops read. Returns
   how many outputs were rolled; *rest (malloc'ed) gets the others in
   their order, for straight-line code, and *ops the rolled operations
   per call. With none rolled, *rest is NULL and nothing is written. */
int roll_function(const RollContext *c, const SchedOutput *outs, int n, StrBuf *parts,
                  StrBuf *body, SchedOutput **rest, int *nrest, long *ops);

#endif
