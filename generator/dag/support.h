/* support.h - which coordinates, velocities or time an expression depends on (a scan of the graph). */
#ifndef MECHC_SUPPORT_H
#define MECHC_SUPPORT_H

#include "dag.h"

/* The scan's marks and stack, reusable across calls: the graph may grow
   between them (they are resized to keep in step). */
typedef struct SupportScan {
    uint32_t *mark;     /* per node: stamp of the last scan that reached it */
    NodeId *stack;
    int cap;
    uint32_t stamp;
} SupportScan;

void support_init(SupportScan *scan);
void support_free(SupportScan *scan);
/* Indices of the leaves of kind leaf (OP_VAR: coordinates, OP_VARD:
   velocities, OP_TIME: t, index -1) that e depends on, ascending, into out
   (room for nq). */
int support_collect(SupportScan *scan, const Dag *dag, NodeId e, DagOp leaf, int *out);

#endif
