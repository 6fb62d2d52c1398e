/* sched.c - cuts a function's outputs into chunks and decides temporaries for straight-line code.
 *
 * Node ids are a topological order, so a chunk's nodes sorted by id are a
 * valid evaluation order: no other scheduling is needed. A node is
 * computed once per chunk; hash-consing already made every shared
 * subexpression (sin(phi) of a body, a product used by two rows) one node.
 */
#include "sched.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

enum { MAX_INLINE_DEPTH = 6 };

void sched_init(Scheduler *s, const Dag *dag, int chunk_nodes)
{
    memset(s, 0, sizeof *s);
    s->dag = dag;
    s->chunk_nodes = chunk_nodes;
    size_t n = (size_t)dag->count;
    s->mark = xcalloc(n, sizeof *s->mark);
    s->uses = xcalloc(n, sizeof *s->uses);
    s->temp = xmalloc((n ? n : 1) * sizeof *s->temp);
    memset(s->temp, 0xff, n * sizeof *s->temp);     /* -1: leaves never get one */
    s->depth = xcalloc(n, sizeof *s->depth);
    s->stack = xcalloc(n, sizeof *s->stack);
}

void sched_free(Scheduler *s)
{
    free(s->mark);
    free(s->uses);
    free(s->temp);
    free(s->depth);
    free(s->stack);
    memset(s, 0, sizeof *s);
}

/* Marks the operation nodes reachable from root; appends new ones to list. */
static void collect(Scheduler *s, NodeId root, NodeId **list, int *n, int *cap)
{
    const Dag *dag = s->dag;
    if (s->mark[root] == s->stamp || dag_is_leaf(dag, root))
        return;
    int top = 0;
    s->mark[root] = s->stamp;
    s->stack[top++] = root;
    while (top > 0) {
        NodeId id = s->stack[--top];
        if (*n == *cap) {
            *cap = *cap ? *cap * 2 : 64;
            *list = xrealloc(*list, (size_t)*cap, sizeof **list);
        }
        (*list)[(*n)++] = id;
        const DagNode *node = dag_node(dag, id);
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < dag_op_info[node->op].arity; k++) {
            if (s->mark[kids[k]] != s->stamp && !dag_is_leaf(dag, kids[k])) {
                s->mark[kids[k]] = s->stamp;
                s->stack[top++] = kids[k];
            }
        }
    }
}

static int compare_ids(const void *a, const void *b)
{
    NodeId x = *(const NodeId *)a, y = *(const NodeId *)b;
    return (x > y) - (x < y);
}

static void close_chunk(SchedFunction *fn, int first, int count, NodeId *nodes, int nnodes)
{
    if (nnodes > 1)     /* an empty chunk may have nodes == NULL, which qsort must not get */
        qsort(nodes, (size_t)nnodes, sizeof *nodes, compare_ids);
    fn->chunks = xrealloc(fn->chunks, (size_t)fn->nchunks + 1, sizeof *fn->chunks);
    fn->chunks[fn->nchunks++] = (SchedChunk){first, count, nodes, nnodes};
    fn->ops += nnodes;
}

bool sched_function(Scheduler *s, SchedOutput *outputs, int noutputs, SchedFunction *fn)
{
    memset(fn, 0, sizeof *fn);
    fn->outputs = outputs;
    fn->noutputs = noutputs;
    NodeId *nodes = NULL;
    int n = 0, cap = 0, first = 0;
    s->stamp++;
    for (int i = 0; i < noutputs; i++) {
        int before = n;
        collect(s, outputs[i].value, &nodes, &n, &cap);
        /* Stores count too: gcc's store passes are quadratic per block. */
        if (n + (i - first + 1) > s->chunk_nodes && i > first) {
            /* Cut before output i; it starts the next chunk afresh. */
            n = before;
            close_chunk(fn, first, i - first, nodes, n);
            nodes = NULL;
            n = cap = 0;
            first = i;
            s->stamp++;
            collect(s, outputs[i].value, &nodes, &n, &cap);
        }
        if (s->max_ops > 0 && s->total_ops + fn->ops + n > s->max_ops) {
            free(nodes);
            return false;
        }
    }
    if (noutputs > first || fn->nchunks == 0)
        close_chunk(fn, first, noutputs - first, nodes, n);
    else
        free(nodes);
    s->total_ops += fn->ops;
    return true;
}

void sched_function_free(SchedFunction *fn)
{
    for (int i = 0; i < fn->nchunks; i++)
        free(fn->chunks[i].nodes);
    free(fn->chunks);
    free(fn->outputs);
    memset(fn, 0, sizeof *fn);
}

void sched_prepare_chunk(Scheduler *s, const SchedFunction *fn, int index)
{
    const Dag *dag = s->dag;
    const SchedChunk *c = &fn->chunks[index];
    for (int i = 0; i < c->nnodes; i++) {
        s->uses[c->nodes[i]] = 0;
        s->temp[c->nodes[i]] = -1;
    }
    for (int i = 0; i < c->nnodes; i++) {
        const DagNode *node = dag_node(dag, c->nodes[i]);
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < dag_op_info[node->op].arity; k++)
            if (!dag_is_leaf(dag, kids[k]))
                s->uses[kids[k]]++;
    }
    for (int i = c->first; i < c->first + c->count; i++)
        if (!dag_is_leaf(dag, fn->outputs[i].value))
            s->uses[fn->outputs[i].value]++;
    int ntemps = 0;
    for (int i = 0; i < c->nnodes; i++) {
        NodeId id = c->nodes[i];
        const DagNode *node = dag_node(dag, id);
        int depth = 0;
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < dag_op_info[node->op].arity; k++)
            if (!dag_is_leaf(dag, kids[k]) && s->temp[kids[k]] < 0 && s->depth[kids[k]] > depth)
                depth = s->depth[kids[k]];
        s->depth[id] = (uint8_t)(depth + 1);
        bool shared = s->uses[id] > 1;
        bool call = dag_op_is_function((DagOp)node->op) || node->op == OP_POW;
        if (shared || call || depth + 1 > MAX_INLINE_DEPTH) {
            s->temp[id] = ntemps++;
            s->depth[id] = 0;
        }
    }
}
