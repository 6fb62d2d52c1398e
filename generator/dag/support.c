/* support.c - the leaves an expression depends on, by one marked walk of its subgraph. */
#include "support.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

void support_init(SupportScan *scan)
{
    memset(scan, 0, sizeof *scan);
}

void support_free(SupportScan *scan)
{
    free(scan->mark);
    free(scan->stack);
    memset(scan, 0, sizeof *scan);
}

int support_collect(SupportScan *scan, const Dag *dag, NodeId e, DagOp leaf, int *out)
{
    /* The graph grows while derivatives are built: keep the marks in step. */
    if (scan->cap < dag->count) {
        int cap = dag->count * 2;
        scan->mark = xrealloc(scan->mark, (size_t)cap, sizeof *scan->mark);
        scan->stack = xrealloc(scan->stack, (size_t)cap, sizeof *scan->stack);
        memset(scan->mark + scan->cap, 0, (size_t)(cap - scan->cap) * sizeof *scan->mark);
        scan->cap = cap;
    }
    if (++scan->stamp == 0) {           /* wrapped: clear and restart */
        memset(scan->mark, 0, (size_t)scan->cap * sizeof *scan->mark);
        scan->stamp = 1;
    }
    int top = 0, n = 0;
    scan->mark[e] = scan->stamp;
    scan->stack[top++] = e;
    while (top > 0) {
        const DagNode *node = dag_node(dag, scan->stack[--top]);
        if (node->op == leaf) {
            out[n++] = node->a;
            continue;
        }
        int arity = dag_op_info[node->op].arity;
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < arity; k++) {
            if (scan->mark[kids[k]] != scan->stamp) {
                scan->mark[kids[k]] = scan->stamp;
                scan->stack[top++] = kids[k];
            }
        }
    }
    /* ascending order (insertion sort: a row touches few coordinates) */
    for (int i = 1; i < n; i++)
        for (int k = i; k > 0 && out[k - 1] > out[k]; k--) {
            int t = out[k];
            out[k] = out[k - 1];
            out[k - 1] = t;
        }
    return n;
}
