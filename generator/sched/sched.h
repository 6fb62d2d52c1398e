/* sched.h - straight-line code: which outputs go in which chunk, which nodes get a temporary. */
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
   (its passes are superlinear in function length); nodes shared across
   a cut are recomputed in each chunk that needs them. */
typedef struct SchedChunk {
    int first, count;       /* outputs[first .. first + count) */
    NodeId *nodes;          /* the chunk's operation nodes, ascending id */
    int nnodes;
} SchedChunk;

typedef struct SchedFunction {
    SchedOutput *outputs;
    int noutputs;
    SchedChunk *chunks;
    int nchunks;
    int ops;                /* arithmetic operations and calls, all chunks */
} SchedFunction;

/* Scratch state reused across functions; per-node arrays sized to the graph. */
typedef struct Scheduler {
    const Dag *dag;
    int chunk_nodes;        /* most operations plus stores per chunk */
    long max_ops;           /* most operations over all functions; 0: no limit */
    long total_ops;         /* operations of the functions scheduled so far */
    uint32_t *mark;
    uint32_t stamp;
    int32_t *uses;          /* uses within the current chunk */
    int32_t *temp;          /* temporary number within the current chunk, or -1 */
    uint8_t *depth;         /* inlined expression depth */
    NodeId *stack;
} Scheduler;

void sched_init(Scheduler *s, const Dag *dag, int chunk_nodes);
void sched_free(Scheduler *s);

/* Partitions outputs into chunks (takes ownership of outputs). Returns
   false, as soon as it is known, when the operations of this and the
   functions before would pass max_ops (nodes shared across chunks are
   recomputed in each, so the code can be much larger than the graph);
   fn is then empty but must still be freed. */
bool sched_function(Scheduler *s, SchedOutput *outputs, int noutputs, SchedFunction *fn);
void sched_function_free(SchedFunction *fn);

/* Prepares one chunk for emission: counts uses and decides temporaries
   (a node used twice or more, a function call, or an expression that
   would nest too deeply gets one; the rest are written inline). Valid
   until the next call. */
void sched_prepare_chunk(Scheduler *s, const SchedFunction *fn, int chunk);

#endif
