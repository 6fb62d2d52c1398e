/* sched.h - straight-line code: which outputs go in which chunk, in what order nodes are computed, which get a temporary. */
#ifndef MECHC_SCHED_H
#define MECHC_SCHED_H

#include "../dag/dag.h"

/* One store of a generated function: array[index] = value. */
typedef struct SchedOutput {
    const char *array;      /* "phi", "jac", "vals", "nu", "gamma" */
    int index;
    NodeId value;
} SchedOutput;

/* A run of outputs computed by one C function body. Long functions are
   cut into chunks so an optimising compiler sees pieces of bounded size
   (its passes are superlinear in function length). A node is computed by
   one chunk of a function only: a later chunk that needs it imports it
   through the function's workspace (a slot the computing chunk stores
   into), so nothing, least of all a sin or cos, is computed twice. */
typedef struct SchedChunk {
    int first, count;       /* outputs[first .. first + count) */
    NodeId *nodes;          /* computed and imported nodes, in evaluation
                               order: each output's new nodes in post-order,
                               just before its store */
    int nnodes;
    int *ends;              /* per output: nodes[0 .. ends[i]) come before
                               the store of outputs[first + i] */
} SchedChunk;

typedef struct SchedFunction {
    SchedOutput *outputs;
    int noutputs;
    SchedChunk *chunks;
    int nchunks;
    int ops;                /* arithmetic operations and calls, all chunks */
    int nslots;             /* workspace slots (values crossing chunks) */
} SchedFunction;

/* Scratch state reused across functions; per-node arrays sized to the
   graph. owner and slot describe the function scheduled last, and stay
   valid until the next sched_function. */
typedef struct Scheduler {
    const Dag *dag;
    int chunk_nodes;        /* most operations plus stores per chunk */
    long max_ops;           /* most operations over all functions; 0: no limit */
    long total_ops;         /* operations of the functions scheduled so far */
    uint32_t *mark;         /* == stamp: in the chunk being collected */
    uint32_t stamp;
    uint32_t *owned;        /* == fn_stamp: owner[] and slot[] are set */
    uint32_t fn_stamp;
    int32_t *owner;         /* the chunk that computes the node */
    int32_t *slot;          /* its workspace slot, or -1 */
    int32_t *pos;           /* position in the prepared chunk */
    int32_t *uses;          /* uses within the current chunk */
    int32_t *temp;          /* temporary number within the current chunk, or -1 */
    uint8_t *depth;         /* inlined expression depth */
    NodeId *stack;          /* 2 * count + 1 entries */
} Scheduler;

void sched_init(Scheduler *s, const Dag *dag, int chunk_nodes);
void sched_free(Scheduler *s);

/* Partitions outputs into chunks (takes ownership of outputs). Returns
   false, as soon as it is known, when the operations of this and the
   functions before would pass max_ops; fn is then empty but must still
   be freed. */
bool sched_function(Scheduler *s, SchedOutput *outputs, int noutputs, SchedFunction *fn);
void sched_function_free(SchedFunction *fn);

/* True when chunk imports id (a node of the function scheduled last that
   an earlier chunk computes) rather than computing it. */
static inline bool sched_is_import(const Scheduler *s, NodeId id, int chunk)
{
    return s->owned[id] == s->fn_stamp && s->owner[id] != chunk;
}

/* The workspace slot of a node that crosses chunks, or -1. */
static inline int sched_slot(const Scheduler *s, NodeId id)
{
    return s->owned[id] == s->fn_stamp ? s->slot[id] : -1;
}

/* Prepares one chunk for emission: positions, use counts and
   temporaries (a node used twice or more, a function call, an import, a
   node stored to the workspace, or an expression that would nest too
   deeply gets one; the rest are written inline). Valid until the next
   call. Returns how many negations the chunk writes fused into their
   product (sched_fused_negation): operations it does not perform. */
int sched_prepare_chunk(Scheduler *s, const SchedFunction *fn, int chunk);

/* In the prepared chunk: id is -(c*y) and c*y has no temporary, so the
   pair is written as the one product (-c)*y (the same number: IEEE
   multiplication is symmetric in sign). */
bool sched_fused_negation(const Scheduler *s, NodeId id);

/* In the prepared chunk: how many temporaries would be computed before a
   call and used after it (so spilled across it), the calls written where
   the chunk's order puts them, except those at_top(ctx, id) says go to the
   chunk's top (at_top NULL: none). A sin and cos of one angle are one call
   (spill.c). */
int sched_values_across_calls(const Scheduler *s, const SchedFunction *fn, int chunk,
                              bool (*at_top)(const void *ctx, NodeId id), const void *ctx);

/* In the prepared chunk: the sin or cos id and its partner (both
   computed here) are multiplied by one and the same computed factor, as
   in γ's 0.5 qd² (cos, sin): gcc's SLP vectorizer then multiplies them as
   one vector, loaded in one piece from the two results sincos stored
   just before, a store-forwarding stall of a dozen cycles where they are
   used next to the call; a copy out of the result slots (the pair
   hoisted above a later call) avoids it (spill.c). */
bool sched_pair_shares_factor(const Scheduler *s, const SchedFunction *fn, int chunk, NodeId id);

#endif
