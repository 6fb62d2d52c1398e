/* spill.c - counts the temporaries of a prepared chunk that would live across a call, for a choice of where its calls go.
 *
 * On x86-64 (and most ABIs) a call clobbers every floating-point
 * register, so a value computed before a call and used after it is
 * spilled: a store and a load at least (libm's sincos, which returns
 * through memory, makes gcc copy each result it keeps out of the shared
 * result slots). Which order spills less depends on the code: hoisting a
 * chunk's calls to its top keeps the arithmetic between them short but
 * carries every sin and cos across the later calls; leaving each call at
 * its first use carries instead what rows computed before it and reuse
 * after it. The emitter counts both and takes the smaller.
 */
#include "sched.h"

#include "../base/arena.h"

#include <stdlib.h>

/* Calls a compiler makes out of line (sqrt is an instruction with a cold
   errno path, left out). */
static bool is_call(const Dag *dag, NodeId id)
{
    DagOp op = dag_op(dag, id);
    return op == OP_POW || (dag_op_is_function(op) && op != OP_SQRT);
}

/* The cos of a sin node (or the reverse) when both are computed here:
   one call computes the pair. DAG_NONE otherwise. */
static NodeId pair_of(const Scheduler *s, NodeId id, int chunk)
{
    DagOp op = dag_op(s->dag, id);
    if (op != OP_SIN && op != OP_COS)
        return DAG_NONE;
    NodeId other = dag_find(s->dag, op == OP_SIN ? OP_COS : OP_SIN, dag_node(s->dag, id)->a, -1);
    return other != DAG_NONE && s->temp[other] >= 0 && !sched_is_import(s, other, chunk)
           ? other : DAG_NONE;
}

int sched_values_across_calls(const Scheduler *s, const SchedFunction *fn, int chunk,
                              bool (*at_top)(const void *ctx, NodeId id), const void *ctx)
{
    const Dag *dag = s->dag;
    const SchedChunk *c = &fn->chunks[chunk];
    int n = c->nnodes;
    if (n == 0)
        return 0;
    /* Times: the nodes hoisted to the top at 0 .. 2n (in their order),
       node i in place at 2n + 2i + 1, the store after ends[k] at
       2n + 2 ends[k]. */
    int span = 4 * n + 2;
    int *time = xmalloc((size_t)n * sizeof *time);
    int *last = xmalloc((size_t)n * sizeof *last);
    int *calls = xcalloc((size_t)span + 1, sizeof *calls);     /* calls at times < t */
    for (int i = 0; i < n; i++) {
        NodeId id = c->nodes[i];
        bool import = sched_is_import(s, id, chunk);
        time[i] = !import && at_top && is_call(dag, id) && at_top(ctx, id) ? 2 * i : 2 * n + 2 * i + 1;
        last[i] = -1;
    }
    for (int i = 0; i < n; i++) {       /* a pair is made by the call of its first */
        NodeId partner = pair_of(s, c->nodes[i], chunk);
        if (partner != DAG_NONE && s->pos[partner] < i)
            time[i] = time[s->pos[partner]];
    }
    for (int i = 0; i < n; i++) {
        NodeId id = c->nodes[i];
        if (sched_is_import(s, id, chunk))
            continue;
        if (is_call(dag, id) && (pair_of(s, id, chunk) == DAG_NONE || s->pos[pair_of(s, id, chunk)] > i))
            calls[time[i] + 1]++;
        const DagNode *node = dag_node(dag, id);
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < dag_op_info[node->op].arity; k++)
            if (!dag_is_leaf(dag, kids[k]) && last[s->pos[kids[k]]] < time[i])
                last[s->pos[kids[k]]] = time[i];
    }
    for (int k = 0; k < c->count; k++) {
        NodeId v = fn->outputs[c->first + k].value;
        if (!dag_is_leaf(dag, v) && last[s->pos[v]] < 2 * n + 2 * c->ends[k])
            last[s->pos[v]] = 2 * n + 2 * c->ends[k];
    }
    for (int t = 1; t <= span; t++)
        calls[t] += calls[t - 1];
    int across = 0;
    for (int i = 0; i < n; i++)     /* a call strictly after the value, before its last use */
        if (s->temp[c->nodes[i]] >= 0 && last[i] > time[i] && calls[last[i]] - calls[time[i] + 1] > 0)
            across++;
    free(time);
    free(last);
    free(calls);
    return across;
}

/* The node t (a sin or cos) times x, or x times t, as one of the chunk's
   products with x not a leaf. */
static bool times(const Dag *dag, NodeId id, NodeId t, NodeId *x)
{
    const DagNode *node = dag_node(dag, id);
    if (node->op != OP_MUL || (node->a != t && node->b != t))
        return false;
    *x = node->a == t ? node->b : node->a;
    return !dag_is_leaf(dag, *x);
}

bool sched_pair_shares_factor(const Scheduler *s, const SchedFunction *fn, int chunk, NodeId id)
{
    NodeId partner = pair_of(s, id, chunk);
    if (partner == DAG_NONE || sched_is_import(s, id, chunk))
        return false;
    const SchedChunk *c = &fn->chunks[chunk];
    for (int i = 0; i < c->nnodes; i++) {
        NodeId x, y;
        if (sched_is_import(s, c->nodes[i], chunk) || !times(s->dag, c->nodes[i], id, &x))
            continue;
        for (int j = 0; j < c->nnodes; j++)
            if (!sched_is_import(s, c->nodes[j], chunk) && times(s->dag, c->nodes[j], partner, &y)
                && y == x)
                return true;
    }
    return false;
}
