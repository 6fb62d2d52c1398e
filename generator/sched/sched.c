/* sched.c - cuts a function's outputs into chunks, orders each chunk's nodes and decides temporaries.
 *
 * Each output's nodes are collected in post-order just before its store,
 * so a value (a sin/cos pair above all) is computed next to its first use
 * and dies soon after, rather than every chunk computing everything at its
 * top and spilling it across the calls. Hash-consing already made every
 * shared subexpression one node; a node is computed once per function:
 * the first chunk that needs it owns it, later chunks import it through a
 * workspace slot. The sin and cos of one angle share their owner (one
 * sincos call computes both), so an angle costs one trig evaluation per
 * function however the function is cut.
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
    s->owned = xcalloc(n, sizeof *s->owned);
    s->owner = xcalloc(n, sizeof *s->owner);
    s->slot = xcalloc(n, sizeof *s->slot);
    s->pos = xcalloc(n, sizeof *s->pos);
    s->uses = xcalloc(n, sizeof *s->uses);
    s->temp = xmalloc((n ? n : 1) * sizeof *s->temp);
    memset(s->temp, 0xff, n * sizeof *s->temp);     /* -1: leaves never get one */
    s->depth = xcalloc(n, sizeof *s->depth);
    s->stack = xcalloc(2 * n + 1, sizeof *s->stack);
}

void sched_free(Scheduler *s)
{
    free(s->mark);
    free(s->owned);
    free(s->owner);
    free(s->slot);
    free(s->pos);
    free(s->uses);
    free(s->temp);
    free(s->depth);
    free(s->stack);
    memset(s, 0, sizeof *s);
}

/* A growing array of ints (node ids or ends). */
typedef struct List {
    int32_t *items;
    int n, cap;
} List;

static void list_push(List *l, int32_t v)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? l->cap * 2 : 64;
        l->items = xrealloc(l->items, (size_t)l->cap, sizeof *l->items);
    }
    l->items[l->n++] = v;
}

/* Puts node x into the closed chunk c right after its trig partner. */
static void insert_after_partner(SchedChunk *c, NodeId partner, NodeId x)
{
    int at = 0;
    while (c->nodes[at] != partner)
        at++;
    c->nodes = xrealloc(c->nodes, (size_t)c->nnodes + 1, sizeof *c->nodes);
    memmove(c->nodes + at + 2, c->nodes + at + 1, (size_t)(c->nnodes - at - 1) * sizeof *c->nodes);
    c->nodes[at + 1] = x;
    c->nnodes++;
    for (int i = 0; i < c->count; i++)
        if (c->ends[i] > at)
            c->ends[i]++;
}

/* A sin or cos whose partner (cos or sin of the same angle) an earlier
   chunk computes is computed there too, with it, and imported here:
   true when e was so given to an earlier chunk. */
static bool adopt_by_partner(Scheduler *s, SchedFunction *fn, int chunk, NodeId e)
{
    DagOp op = dag_op(s->dag, e);
    if (op != OP_SIN && op != OP_COS)
        return false;
    NodeId partner = dag_find(s->dag, op == OP_SIN ? OP_COS : OP_SIN, dag_node(s->dag, e)->a, -1);
    if (partner == DAG_NONE || s->owned[partner] != s->fn_stamp || s->owner[partner] >= chunk)
        return false;
    int j = s->owner[partner];
    insert_after_partner(&fn->chunks[j], partner, e);
    s->owned[e] = s->fn_stamp;
    s->owner[e] = j;
    s->slot[e] = -1;
    fn->ops++;
    return true;
}

/* Appends the operation nodes root needs and the chunk does not have yet
   to list, in post-order (operands first, left to right); nodes that an
   earlier chunk computes are appended as imports and not entered. Returns
   how many nodes this chunk now computes in addition. */
static int collect(Scheduler *s, SchedFunction *fn, int chunk, NodeId root, List *list)
{
    const Dag *dag = s->dag;
    int top = 0, computed = 0;
    s->stack[top++] = root;
    while (top > 0) {
        NodeId e = s->stack[top - 1];
        if (e < 0) {                    /* ~id: its operands are in; now itself */
            top--;
            list_push(list, ~e);
            continue;
        }
        if (dag_is_leaf(dag, e) || s->mark[e] == s->stamp) {
            top--;
            continue;
        }
        s->mark[e] = s->stamp;
        if (s->owned[e] == s->fn_stamp || adopt_by_partner(s, fn, chunk, e)) {
            top--;
            if (s->slot[e] < 0)
                s->slot[e] = fn->nslots++;
            list_push(list, e);
            continue;
        }
        s->owned[e] = s->fn_stamp;
        s->owner[e] = chunk;
        s->slot[e] = -1;
        computed++;
        s->stack[top - 1] = ~e;
        const DagNode *node = dag_node(dag, e);
        if (dag_op_info[node->op].arity == 2)
            s->stack[top++] = node->b;
        s->stack[top++] = node->a;
    }
    return computed;
}

/* Reorders one output's new nodes items[before ..) so that its calls
   (with the nodes their arguments need) come first, then the arithmetic
   that combines them: a call clobbers every floating-point register, so
   arithmetic between two calls would be spilled across the second. uses
   and pos serve as scratch (prepare sets them afresh). */
static void hoist_calls(Scheduler *s, List *list, int before, int chunk)
{
    const Dag *dag = s->dag;
    int n = list->n - before, hoisted = 0;
    if (n == 0)
        return;                         /* items may still be NULL */
    NodeId *seg = list->items + before;
    for (int j = 0; j < n; j++)
        s->uses[seg[j]] = 0;
    for (int j = n - 1; j >= 0; j--) {      /* operands come before their users */
        const DagNode *node = dag_node(dag, seg[j]);
        if (dag_op_is_function((DagOp)node->op))
            s->uses[seg[j]] = 1;
        if (s->uses[seg[j]] != 1 || s->owner[seg[j]] != chunk)   /* an import's operands are not here */
            continue;
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < dag_op_info[node->op].arity; k++)
            s->uses[kids[k]] = 1;       /* only seg's nodes are read back */
    }
    for (int j = 0; j < n; j++)
        hoisted += s->uses[seg[j]] == 1;
    if (hoisted == 0 || hoisted == n)
        return;
    NodeId *copy = xmalloc((size_t)n * sizeof *copy);
    memcpy(copy, seg, (size_t)n * sizeof *copy);
    int a = 0, b = hoisted;
    for (int j = 0; j < n; j++)
        seg[s->uses[copy[j]] == 1 ? a++ : b++] = copy[j];
    free(copy);
}

/* Closes the chunk of outputs first .. first+count-1 (their ends are
   ends->items[first ..]): it takes nodes' array and leaves nodes empty. */
static void close_chunk(SchedFunction *fn, int first, int count, List *nodes, const List *ends)
{
    fn->chunks = xrealloc(fn->chunks, (size_t)fn->nchunks + 1, sizeof *fn->chunks);
    int *own_ends = xmalloc((size_t)(count ? count : 1) * sizeof *own_ends);
    if (count)      /* ends->items is NULL when there are no outputs */
        memcpy(own_ends, ends->items + first, (size_t)count * sizeof *own_ends);
    fn->chunks[fn->nchunks++] = (SchedChunk){first, count, nodes->items, nodes->n, own_ends};
    *nodes = (List){0};
}

/* Forgets output i's nodes when it moves to the next chunk: the ones this
   chunk would have computed are owned by nobody again (its imports keep
   their slots: the next chunk imports them too). */
static void roll_back(Scheduler *s, List *nodes, int before, int chunk)
{
    for (int j = before; j < nodes->n; j++)
        if (s->owner[nodes->items[j]] == chunk)
            s->owned[nodes->items[j]] = 0;
    nodes->n = before;
}

bool sched_function(Scheduler *s, SchedOutput *outputs, int noutputs, SchedFunction *fn)
{
    memset(fn, 0, sizeof *fn);
    fn->outputs = outputs;
    fn->noutputs = noutputs;
    List nodes = {0}, ends = {0};
    int first = 0, computed = 0;
    s->stamp++;
    s->fn_stamp++;
    for (int i = 0; i < noutputs; i++) {
        int before = nodes.n;
        int more = collect(s, fn, fn->nchunks, outputs[i].value, &nodes);
        /* Stores count too: gcc's store passes are quadratic per block. */
        if (nodes.n + (i - first + 1) > s->chunk_nodes && i > first) {
            /* Cut before output i; it starts the next chunk afresh. */
            roll_back(s, &nodes, before, fn->nchunks);
            fn->ops += computed;
            close_chunk(fn, first, i - first, &nodes, &ends);
            first = i;
            s->stamp++;
            more = collect(s, fn, fn->nchunks, outputs[i].value, &nodes);
            computed = 0;
            before = 0;
        }
        hoist_calls(s, &nodes, before, fn->nchunks);
        computed += more;
        list_push(&ends, nodes.n);
        if (s->max_ops > 0 && s->total_ops + fn->ops + computed > s->max_ops) {
            free(nodes.items);
            free(ends.items);
            return false;
        }
    }
    fn->ops += computed;
    close_chunk(fn, first, noutputs - first, &nodes, &ends);
    free(ends.items);
    s->total_ops += fn->ops;
    return true;
}

void sched_function_free(SchedFunction *fn)
{
    for (int i = 0; i < fn->nchunks; i++) {
        free(fn->chunks[i].nodes);
        free(fn->chunks[i].ends);
    }
    free(fn->chunks);
    free(fn->outputs);
    memset(fn, 0, sizeof *fn);
}

/* Uses of each node within the chunk: by the nodes it computes and by
   its stores (an import's operands are not used here). */
static void count_uses(Scheduler *s, const SchedFunction *fn, int index)
{
    const Dag *dag = s->dag;
    const SchedChunk *c = &fn->chunks[index];
    for (int i = 0; i < c->nnodes; i++) {
        s->uses[c->nodes[i]] = 0;
        s->temp[c->nodes[i]] = -1;
        s->pos[c->nodes[i]] = i;
    }
    for (int i = 0; i < c->nnodes; i++) {
        if (sched_is_import(s, c->nodes[i], index))
            continue;
        const DagNode *node = dag_node(dag, c->nodes[i]);
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < dag_op_info[node->op].arity; k++)
            if (!dag_is_leaf(dag, kids[k]))
                s->uses[kids[k]]++;
    }
    for (int i = c->first; i < c->first + c->count; i++)
        if (!dag_is_leaf(dag, fn->outputs[i].value))
            s->uses[fn->outputs[i].value]++;
}

/* -(c*y) with c*y used by nothing else: written (-c)*y, one operation. */
bool sched_fused_negation(const Scheduler *s, NodeId id)
{
    const DagNode *node = dag_node(s->dag, id);
    return node->op == OP_NEG && dag_op(s->dag, node->a) == OP_MUL
           && dag_op(s->dag, dag_node(s->dag, node->a)->a) == OP_CONST && s->temp[node->a] < 0;
}

int sched_prepare_chunk(Scheduler *s, const SchedFunction *fn, int index)
{
    const Dag *dag = s->dag;
    const SchedChunk *c = &fn->chunks[index];
    count_uses(s, fn, index);
    int ntemps = 0, fused = 0;
    for (int i = 0; i < c->nnodes; i++) {
        NodeId id = c->nodes[i];
        const DagNode *node = dag_node(dag, id);
        bool import = sched_is_import(s, id, index);
        int depth = 0;
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; !import && k < dag_op_info[node->op].arity; k++)
            if (!dag_is_leaf(dag, kids[k]) && s->temp[kids[k]] < 0 && s->depth[kids[k]] > depth)
                depth = s->depth[kids[k]];
        s->depth[id] = (uint8_t)(depth + 1);
        bool shared = s->uses[id] > 1;
        bool call = dag_op_is_function((DagOp)node->op) || node->op == OP_POW;
        if (shared || call || import || sched_slot(s, id) >= 0 || depth + 1 > MAX_INLINE_DEPTH) {
            s->temp[id] = ntemps++;
            s->depth[id] = 0;
        }
        if (!import && sched_fused_negation(s, id))
            fused++;
    }
    return fused;
}
