/* trig.h - sin and cos in the generated code: pairs in one call, calls placed first, the math preamble. */
#ifndef MECHC_TRIG_H
#define MECHC_TRIG_H

#include "../base/strbuf.h"
#include "../dag/dag.h"
#include "../sched/sched.h"
#include "options.h"

#include <stdbool.h>

/* How a file computes its sines and cosines, and what it called. Double
   kernels compute sin and cos together, of two angles at once where they
   can: the JIT calls the tool's mechc_sincos and mechc_sincos2 (or the C
   library's sincos with libm_trig), file output its own P_sincos and
   P_sincos2 (templates/sincos*.tmpl) or, with libm_trig, sin and cos as
   written (sincos is not C99; gcc merges the pairs itself). */
typedef struct EmitTrig {
    const char *sincos_name;    /* NULL: sin and cos of <math.h> as written */
    const char *sincos2_name;   /* two angles in one call; NULL: no such function */
    const char *sin_name;       /* the pair where only its sin is used (a macro:
                                   libm's sin alone where not optimising);
                                   NULL: sincos_name */
    const char *cos_name;       /* the pair where only its cos is used */
    const char *sincos2_some_name;  /* sincos2 where some values go unused */
    bool sincos_used;           /* some function called sincos_name */
    bool sincos2_used;          /* some function called sincos2_name */
    bool single_used;           /* some function called one of the three */
    bool calls;                 /* sin and cos are calls, not inlined (calls_first) */
    bool place_as_calls;        /* this function, if split into parts,
                                   places its inline pairs as calls where
                                   they cannot all go first */
    bool pair_out_of_line;      /* the file calls one noinline copy of its pair */
    bool hoisting;              /* in trig_put_first */
    bool *written;              /* per node: its sincos call was already written
                                   (paired with an earlier one) in this chunk */
    int *call_rank;             /* per node: its call's number among the chunk's
                                   sin/cos that may go first (rank_calls) */
    int hoist;                  /* how many of those go first */
    const char *lane_name;      /* a batch lane's pair (the file's own trig only;
                                   NULL: the functions above) */
    bool lane_used;             /* some batch function called lane_name */
    char names[6][160];         /* the file's own names, P_sincos ... */
} EmitTrig;

/* Calls of the written file's own sin/cos functions. Inlined at every
   call (gcc splits the pair function at its rare-case test and calls the
   rest out of line, through memory, unless forced), the pair takes gcc
   -O2 several times as long as libm calls would: files with more calls
   than TRIG_INLINE_MAX call one copy. */
enum { TRIG_INLINE_MAX = 64 };

/* The names and mode of a file with this prefix and these options, with
   per-node state for a graph of nnodes nodes (trig_free frees it; the
   names stay). */
void trig_init(EmitTrig *t, const EmitOptions *opt, const char *prefix, int nnodes);
/* Fresh per-node state for another graph of nnodes nodes (a loop body's):
   the names and mode stay. */
void trig_graph(EmitTrig *t, int nnodes);
void trig_free(EmitTrig *t);

/* Whether the file's calls of its own pair are inlined: only then does
   their number matter (TRIG_INLINE_MAX). */
bool trig_pair_inline(const EmitTrig *t);
/* The pair becomes one out-of-line copy: every call a real call, placed
   as libm's are (calls_first), nothing yet called. */
void trig_pair_out_of_line(EmitTrig *t);

/* Fewest calls of the file's own sin/cos functions the functions whose
   outputs are outs[f] (n[f] of them; NULL: not written) can make: each
   evaluates every angle it uses, two at most a call. */
long trig_least_calls(const Dag *dag, SchedOutput *const *outs, const int *n, int nfunctions);
/* Calls of the file's own sin/cos functions in the written functions. */
long trig_pair_calls(const EmitTrig *t, const StrBuf *parts, const StrBuf *bodies, int nfunctions);

struct Emitter;
/* Writes the sin/cos calls that go to the top of chunk c of fn. */
void trig_put_first(struct Emitter *e, StrBuf *sb, const SchedFunction *fn, const SchedChunk *c);
/* The statement that gives node id (at position at of chunk c) its
   temporary: an import's load, a sincos call for a group's leader (none
   for its partner), or an assignment (then its export). */
void trig_put_temporary(struct Emitter *e, StrBuf *sb, const SchedChunk *c, int at, NodeId id);

/* What the kernels call for math (the MATH placeholder): libm declared
   (JIT) or included, and the sincos functions the file used, for written
   files chosen by the compiler (templates/trig.tmpl). */
void trig_put_math(StrBuf *math, const EmitTrig *t, const EmitOptions *opt, const char *prefix,
                   const char *upper);

#endif
