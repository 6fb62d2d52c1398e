/* reactions.c - the forces planar joints apply to their second bodies, from the multipliers of inverse dynamics.
 *
 * Row i's generalised reaction on the coordinates is -Phi_q(i,:)^T lambda_i
 * (M qdd + Phi_q^T lambda = Q). For a row that is a function of the
 * second attachment's position P_B, that is the force -(dPhi_i/dP_B)^T
 * lambda_i applied at P_B: for a revolute's rows P_A - P_B, +lambda; for
 * a prismatic's or pointline's n_A^T (P_B - P_A), -lambda n_A; for a
 * distance's |P_B - P_A|^2 - L^2, -2 lambda (P_B - P_A). The first body
 * gets the opposite force (and, off P_B, a moment).
 */
#include "reactions.h"

#include "../base/arena.h"

#include <math.h>

/* The global position of attachment a at coordinates qk (planar). */
static void attach_point(Attach a, const double *qk, double *x, double *y)
{
    if (a.q < 0) {
        *x = a.sx, *y = a.sy;
        return;
    }
    double c = a.has_phi ? cos(qk[a.q + 2]) : 1, s = a.has_phi ? sin(qk[a.q + 2]) : 0;
    *x = qk[a.q] + c * a.sx - s * a.sy;
    *y = qk[a.q + 1] + s * a.sx + c * a.sy;
}

/* Whether joint kind k has a drawn reaction. */
static bool drawn(JointKind k)
{
    return k == JOINT_REVOLUTE || k == JOINT_WELD || k == JOINT_PRISMATIC
           || k == JOINT_POINTLINE || k == JOINT_DISTANCE;
}

/* Joint jt's force on its second body at one frame. */
static void joint_force(const Joint *jt, const double *qk, const double *lk, double *f)
{
    const double *l = lk + jt->first_row;
    if (jt->kind == JOINT_REVOLUTE || jt->kind == JOINT_WELD) {
        f[0] = l[0], f[1] = l[1];
    } else if (jt->kind == JOINT_DISTANCE) {
        double ax, ay, bx, by;
        attach_point(jt->a, qk, &ax, &ay);
        attach_point(jt->b, qk, &bx, &by);
        f[0] = -2 * l[0] * (bx - ax), f[1] = -2 * l[0] * (by - ay);
    } else {            /* prismatic, pointline: the normal n_A = A(phi_A) (-uy, ux) */
        double phi = jt->a.q >= 0 && jt->a.has_phi ? qk[jt->a.q + 2] : 0;
        double c = cos(phi), s = sin(phi), nx = -jt->uy, ny = jt->ux;
        f[0] = -l[0] * (c * nx - s * ny), f[1] = -l[0] * (s * nx + c * ny);
    }
}

int reactions_compute(const Model *m, const double *q, const double *lambda, int n,
                      SvgForce *out, int max, double **values)
{
    int count = 0;
    *values = NULL;
    if (m->spatial)
        return 0;
    for (int j = 0; j < m->njoints && count < max; j++)
        if (drawn(m->joints[j].kind))
            out[count++] = (SvgForce){m->joints[j].b, NULL, 0, m->joints[j].name};
    if (count == 0)
        return 0;
    double *v = xcalloc((size_t)n * 2 * (size_t)count, sizeof *v);
    int i = 0;
    for (int j = 0; j < m->njoints && i < count; j++) {
        const Joint *jt = &m->joints[j];
        if (!drawn(jt->kind))
            continue;
        for (int k = 0; k < n; k++)
            joint_force(jt, q + (size_t)k * (size_t)m->nq, lambda + (size_t)k * (size_t)m->nr,
                        v + ((size_t)k * (size_t)count + (size_t)i) * 2);
        out[i].f = v + 2 * i;
        out[i].stride = 2 * count;
        i++;
    }
    *values = v;
    return count;
}
