/* blame.c - which force element makes the right side NaN or infinite at a state, and why.
 *
 * Forward dynamics fails with NaN when Q cannot be evaluated: a spring
 * whose ends meet (l = |B - A| = 0, so the direction of its force,
 * l_q = (B - A)^T (B - A)_q / l, is 0/0), or a force expression outside
 * its domain. The kernels only say that the sum is not finite; here each
 * element's own nodes are evaluated at the failing state, through the
 * graph interpreter, and the first one to blame is named with its place
 * in the file.
 */
#include "blame.h"

#include "../eval/interp.h"

#include <math.h>

/* The element's point, value and angle nodes (DAG_NONE-free: absent ones
   are DAG_ZERO); how many. */
static int force_nodes(const AppliedForce *f, NodeId nodes[9])
{
    NodeId all[9] = {f->ax, f->ay, f->az, f->bx, f->by, f->bz, f->fx, f->fy, f->fz};
    int n = 0;
    for (int i = 0; i < 9; i++)
        if (all[i] != DAG_NONE)
            nodes[n++] = all[i];
    return n;
}

/* "spring 'S' (FILE:LINE:COL)": the element and where the file says it. */
static void name_force(const Model *m, const AppliedForce *f, const Diag *src, char *msg,
                       size_t size)
{
    analysis_msgf(msg, size, "%s '%s'", force_info[f->kind].keyword, f->name);
    if (src && src->text) {
        int line, col;
        diag_locate(src, f->pos.offset, &line, &col);
        analysis_msgf(msg, size, " (%s:%d:%d)", m->file, line, col);
    }
}

bool blame_force(const Model *m, const Diag *src, double t, const double *q,
                     const double *qd, char *msg, size_t size)
{
    const Dag *dag = &m->dag;
    for (int i = 0; i < m->nforces; i++) {
        const AppliedForce *f = &m->forces[i];
        if (f->kind == FORCE_SPRING) {
            double d[3] = {node_value_at(dag, f->bx, q, qd, t) - node_value_at(dag, f->ax, q, qd, t),
                           node_value_at(dag, f->by, q, qd, t) - node_value_at(dag, f->ay, q, qd, t),
                           node_value_at(dag, f->bz, q, qd, t) - node_value_at(dag, f->az, q, qd, t)};
            double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (l == 0) {
                name_force(m, f, src, msg, size);
                analysis_msgf(msg, size, " has length 0 here, its two ends at one point: the "
                              "direction of its force, (B - A)/|B - A|, is undefined (0/0); "
                              "attach its ends where they stay apart");
                return true;
            }
        }
        NodeId nodes[9];
        int n = force_nodes(f, nodes);
        for (int k = 0; k < n; k++)
            if (!isfinite(node_value_at(dag, nodes[k], q, qd, t))) {
                name_force(m, f, src, msg, size);
                analysis_msgf(msg, size, " is NaN or infinite here (an expression evaluated "
                              "outside its domain?)");
                return true;
            }
    }
    return false;
}
