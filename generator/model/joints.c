/* joints.c - each joint kind's constraint rows, written as the spec's equations over graph nodes.
 *
 * Planar helpers over node ids (vec_add, rotate, dot, ...) keep every
 * builder a transcription of spec section 2: P = r + A(phi) s,
 * n_A = A(phi_A) (-uy, ux).
 */
#include "model.h"

#include <math.h>

typedef struct Vec {
    NodeId x, y;
} Vec;

static Vec vec_sub(Dag *d, Vec a, Vec b) { return (Vec){dag_sub(d, a.x, b.x), dag_sub(d, a.y, b.y)}; }
static NodeId dot(Dag *d, Vec a, Vec b) { return dag_add(d, dag_mul(d, a.x, b.x), dag_mul(d, a.y, b.y)); }
static Vec vec_const(Dag *d, double x, double y) { return (Vec){dag_const(d, x), dag_const(d, y)}; }

/* A(phi) v = (cos phi vx - sin phi vy, sin phi vx + cos phi vy) */
static Vec rotate(Dag *d, NodeId phi, Vec v)
{
    NodeId c = dag_call(d, OP_COS, phi, DAG_NONE), s = dag_call(d, OP_SIN, phi, DAG_NONE);
    return (Vec){dag_sub(d, dag_mul(d, c, v.x), dag_mul(d, s, v.y)),
                 dag_add(d, dag_mul(d, s, v.x), dag_mul(d, c, v.y))};
}

static NodeId angle_of(Dag *d, Attach at)
{
    return at.has_phi ? dag_var(d, at.q + 2) : DAG_ZERO;
}

/* Global position P = r + A(phi) s of an attachment (ground: s itself). */
static Vec position(Dag *d, Attach at)
{
    if (at.q < 0)
        return vec_const(d, at.sx, at.sy);
    Vec r = {dag_var(d, at.q), dag_var(d, at.q + 1)};
    if (!at.has_phi)
        return r;
    Vec s = rotate(d, angle_of(d, at), vec_const(d, at.sx, at.sy));
    return (Vec){dag_add(d, r.x, s.x), dag_add(d, r.y, s.y)};
}

/* dP/dt = r' + phi' * (-(A s)_y, (A s)_x): the velocity of a body-fixed point. */
static Vec velocity(Dag *d, Attach at)
{
    if (at.q < 0)
        return vec_const(d, 0.0, 0.0);
    Vec v = {dag_vard(d, at.q), dag_vard(d, at.q + 1)};
    if (!at.has_phi)
        return v;
    NodeId w = dag_vard(d, at.q + 2);
    Vec s = rotate(d, angle_of(d, at), vec_const(d, at.sx, at.sy));
    return (Vec){dag_sub(d, v.x, dag_mul(d, w, s.y)), dag_add(d, v.y, dag_mul(d, w, s.x))};
}

/* n_A = A(phi_A) (-uy, ux): the body-fixed normal of the axis. */
static Vec normal(Dag *d, Attach at, double ux, double uy)
{
    Vec n = vec_const(d, -uy, ux);
    return at.has_phi ? rotate(d, angle_of(d, at), n) : n;
}

void joints_lower(Model *model, const Joint *j, NodeId rows[3])
{
    Dag *d = &model->dag;
    switch (j->kind) {
    /* revolute J: J.x, J.y = P_A - P_B */
    case JOINT_REVOLUTE: {
        Vec e = vec_sub(d, position(d, j->a), position(d, j->b));
        rows[0] = e.x;
        rows[1] = e.y;
        return;
    }
    /* prismatic J: J.n = n_A . (P_B - P_A); J.phi = phi_B - phi_A - theta */
    case JOINT_PRISMATIC: {
        Vec e = vec_sub(d, position(d, j->b), position(d, j->a));
        rows[0] = dot(d, normal(d, j->a, j->ux, j->uy), e);
        rows[1] = dag_sub(d, dag_sub(d, angle_of(d, j->b), angle_of(d, j->a)), j->option);
        return;
    }
    /* distance J: (P_B - P_A).(P_B - P_A) - L^2 */
    case JOINT_DISTANCE: {
        Vec e = vec_sub(d, position(d, j->b), position(d, j->a));
        rows[0] = dag_sub(d, dot(d, e, e), dag_mul(d, j->option, j->option));
        return;
    }
    /* pointline J: n_A . (P_B - P_A) */
    case JOINT_POINTLINE: {
        Vec e = vec_sub(d, position(d, j->b), position(d, j->a));
        rows[0] = dot(d, normal(d, j->a, j->ux, j->uy), e);
        return;
    }
    /* weld J: J.x, J.y = P_A - P_B; J.phi = phi_B - phi_A - theta */
    case JOINT_WELD: {
        Vec e = vec_sub(d, position(d, j->a), position(d, j->b));
        rows[0] = e.x;
        rows[1] = e.y;
        rows[2] = dag_sub(d, dag_sub(d, angle_of(d, j->b), angle_of(d, j->a)), j->option);
        return;
    }
    /* constraint, driver, velocity J: lhs - rhs */
    case JOINT_CONSTRAINT:
    case JOINT_DRIVER:
    case JOINT_VELOCITY:
        rows[0] = j->expr;
        return;
    /* rolling J: der(B.x) + R der(B.phi) (no slip on the ground line) */
    case JOINT_ROLLING:
        rows[0] = dag_add(d, dag_vard(d, j->a.q), dag_mul(d, j->option, dag_vard(d, j->a.q + 2)));
        return;
    /* knife J: n_A . d/dt(P_A) (no velocity across the blade) */
    case JOINT_KNIFE: {
        /* v before n, in statements: node ids follow the order nodes are
           made in, which must not be the compiler's order of arguments */
        Vec v = velocity(d, j->a);
        Vec n = normal(d, j->a, j->ux, j->uy);
        rows[0] = dot(d, n, v);
        return;
    }
    case JOINT_KIND_COUNT:
        break;
    }
}

void joints_point(Model *model, Attach at, NodeId xy[2])
{
    Vec p = position(&model->dag, at);
    xy[0] = p.x;
    xy[1] = p.y;
}

/* slide(J) = u_A . (P_B - P_A) / |u|, u_A = A(phi_A) u: how far B's point
   has moved along A's axis, in length units whatever the axis' length. */
NodeId joints_slide(Model *model, const Joint *j)
{
    Dag *d = &model->dag;
    double len = sqrt(j->ux * j->ux + j->uy * j->uy);
    Vec u = vec_const(d, j->ux / len, j->uy / len);
    if (j->a.has_phi)
        u = rotate(d, angle_of(d, j->a), u);
    return dot(d, u, vec_sub(d, position(d, j->b), position(d, j->a)));
}
