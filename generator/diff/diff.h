/* diff.h - symbolic derivatives over the expression graph, memoised per (node, variable). */
#ifndef MECHC_DIFF_H
#define MECHC_DIFF_H

#include "../base/hashmap.h"
#include "../dag/dag.h"

typedef struct Differ {
    Dag *dag;
    int nq;
    U64Map memo;        /* (node, variable code) -> derivative node */
} Differ;

void differ_init(Differ *differ, Dag *dag, int nq);
void differ_free(Differ *differ);

NodeId diff_by_q(Differ *differ, NodeId e, int j);     /* de/dq_j */
NodeId diff_by_qd(Differ *differ, NodeId e, int j);    /* de/dqd_j */
NodeId diff_by_p(Differ *differ, NodeId e, int j);     /* de/dp_j (design parameter j) */
NodeId diff_by_t(Differ *differ, NodeId e);            /* partial de/dt */

/* Total time derivative along the motion with the accelerations left out:
   D(q_j) = qd_j, D(t) = 1, D(qd_j) = 0. For a position row, D(D(Phi)) =
   (Phi_q qd)_q qd + 2 Phi_qt qd + Phi_tt, so gamma = -D(D(Phi)); for a
   velocity row Psi, gamma = -D(Psi). One linear pass per expression. */
NodeId diff_total(Differ *differ, NodeId e);

/* e with every qd_j set to 0 (b of Psi = a^T qd + b). */
NodeId diff_without_velocities(Differ *differ, NodeId e);

#endif
