/* joints.c - each joint kind's constraint rows, written as the spec's equations over graph nodes.
 *
 * Planar helpers over node ids (vec_add, rotate, dot, ...) keep every
 * builder a transcription of spec section 2: P = r + A(phi) s,
 * n_A = A(phi_A) (-uy, ux).
 *
 * Node ids follow the order nodes are made in, and they name the
 * temporaries of the generated C; C leaves the order of evaluating a
 * call's arguments unspecified, so every node here is made in a statement
 * of its own (in the order gcc used to pick: a call's arguments right to
 * left), and the output is the same whichever compiler built mechc.
 */
#include "model.h"

#include "joint_builders.h"

#include <math.h>

typedef struct Vec {
    NodeId x, y;
} Vec;

static Vec vec_sub(Dag *d, Vec a, Vec b)
{
    NodeId x = dag_sub(d, a.x, b.x);
    NodeId y = dag_sub(d, a.y, b.y);
    return (Vec){x, y};
}

static NodeId dot(Dag *d, Vec a, Vec b)
{
    NodeId yy = dag_mul(d, a.y, b.y);
    NodeId xx = dag_mul(d, a.x, b.x);
    return dag_add(d, xx, yy);
}

static Vec vec_const(Dag *d, double x, double y)
{
    NodeId cx = dag_const(d, x);
    NodeId cy = dag_const(d, y);
    return (Vec){cx, cy};
}

/* A(phi) v = (cos phi vx - sin phi vy, sin phi vx + cos phi vy) */
static Vec rotate(Dag *d, NodeId phi, Vec v)
{
    NodeId c = dag_call(d, OP_COS, phi, DAG_NONE);
    NodeId s = dag_call(d, OP_SIN, phi, DAG_NONE);
    NodeId sy = dag_mul(d, s, v.y), cx = dag_mul(d, c, v.x);
    NodeId x = dag_sub(d, cx, sy);
    NodeId cy = dag_mul(d, c, v.y), sx = dag_mul(d, s, v.x);
    NodeId y = dag_add(d, sx, cy);
    return (Vec){x, y};
}

/* An attachment's offset s: its design's nodes, or constants. */
static Vec offset_of(Dag *d, Attach at)
{
    return at.designed ? (Vec){at.s_node[0], at.s_node[1]} : vec_const(d, at.sx, at.sy);
}

static NodeId angle_of(Dag *d, Attach at)
{
    return at.has_phi ? dag_var(d, at.q + 2) : DAG_ZERO;
}

/* Global position P = r + A(phi) s of an attachment (ground: s itself). */
static Vec position(Dag *d, Attach at)
{
    if (at.q < 0)
        return offset_of(d, at);
    NodeId rx = dag_var(d, at.q);
    NodeId ry = dag_var(d, at.q + 1);
    if (!at.has_phi)
        return (Vec){rx, ry};
    Vec local = offset_of(d, at);
    Vec s = rotate(d, angle_of(d, at), local);
    NodeId x = dag_add(d, rx, s.x);
    NodeId y = dag_add(d, ry, s.y);
    return (Vec){x, y};
}

/* dP/dt = r' + phi' * (-(A s)_y, (A s)_x): the velocity of a body-fixed point. */
static Vec velocity(Dag *d, Attach at)
{
    if (at.q < 0)
        return vec_const(d, 0.0, 0.0);
    NodeId vx = dag_vard(d, at.q);
    NodeId vy = dag_vard(d, at.q + 1);
    if (!at.has_phi)
        return (Vec){vx, vy};
    NodeId w = dag_vard(d, at.q + 2);
    Vec local = offset_of(d, at);
    Vec s = rotate(d, angle_of(d, at), local);
    NodeId wy = dag_mul(d, w, s.y);
    NodeId x = dag_sub(d, vx, wy);
    NodeId wx = dag_mul(d, w, s.x);
    NodeId y = dag_add(d, vy, wx);
    return (Vec){x, y};
}

/* n_A = A(phi_A) (-uy, ux): the body-fixed normal of j's axis. */
static Vec normal(Dag *d, const Joint *j)
{
    Vec n = !j->axis_designed ? vec_const(d, -j->uy, j->ux)
                              : (Vec){dag_neg(d, j->u_node[1]), j->u_node[0]};
    return j->a.has_phi ? rotate(d, angle_of(d, j->a), n) : n;
}

/* j's unit axis u / |u| (in A's frame). */
static Vec unit_axis(Dag *d, const Joint *j)
{
    if (!j->axis_designed) {
        double len = sqrt(j->ux * j->ux + j->uy * j->uy);
        return vec_const(d, j->ux / len, j->uy / len);
    }
    Vec u = {j->u_node[0], j->u_node[1]};
    NodeId len = dag_call(d, OP_SQRT, dot(d, u, u), DAG_NONE);
    NodeId x = dag_div(d, u.x, len);
    return (Vec){x, dag_div(d, u.y, len)};
}

/* P_p - P_q (P_q's nodes made first) */
static Vec difference(Dag *d, Attach p, Attach q)
{
    Vec pq = position(d, q);
    Vec pp = position(d, p);
    return vec_sub(d, pp, pq);
}

/* phi_b - phi_a - theta */
static NodeId relative_angle(Dag *d, Attach b, Attach a, NodeId theta)
{
    NodeId pa = angle_of(d, a);
    NodeId pb = angle_of(d, b);
    return dag_sub(d, dag_sub(d, pb, pa), theta);
}

/* revolute J: J.x, J.y = P_A - P_B */
static void lower_REVOLUTE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Vec e = difference(d, j->a, j->b);
    rows[0] = e.x;
    rows[1] = e.y;
}

/* prismatic J: J.n = n_A . (P_B - P_A); J.phi = phi_B - phi_A - theta */
static void lower_PRISMATIC(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Vec e = difference(d, j->b, j->a);
    rows[0] = dot(d, normal(d, j), e);
    rows[1] = relative_angle(d, j->b, j->a, j->option);
}

/* distance J: (P_B - P_A).(P_B - P_A) - L^2 */
static void lower_DISTANCE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Vec e = difference(d, j->b, j->a);
    NodeId l2 = dag_mul(d, j->option, j->option);
    rows[0] = dag_sub(d, dot(d, e, e), l2);
}

/* pointline J: n_A . (P_B - P_A) */
static void lower_POINTLINE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Vec e = difference(d, j->b, j->a);
    rows[0] = dot(d, normal(d, j), e);
}

/* weld J: J.x, J.y = P_A - P_B; J.phi = phi_B - phi_A - theta */
static void lower_WELD(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    lower_REVOLUTE(d, j, rows);
    rows[2] = relative_angle(d, j->b, j->a, j->option);
}

/* constraint, driver, velocity J: lhs - rhs, which model.c lowered */
static void lower_statement(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    (void)d;
    rows[0] = j->expr;
}
#define lower_CONSTRAINT lower_statement
#define lower_DRIVER lower_statement
#define lower_VELOCITY lower_statement

/* rolling J: der(B.x) + R der(B.phi) (no slip on the ground line) */
static void lower_ROLLING(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    NodeId roll = dag_mul(d, j->option, dag_vard(d, j->a.q + 2));
    rows[0] = dag_add(d, dag_vard(d, j->a.q), roll);
}

/* knife J: n_A . d/dt(P_A) (no velocity across the blade) */
static void lower_KNIFE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Vec v = velocity(d, j->a);
    Vec n = normal(d, j);
    rows[0] = dot(d, n, v);
}

/* Every kind's builder, by kind: a row of joints.def without its
   lower_KIND (here, or the spatial family's in joint_builders.h) is an
   undeclared identifier, so the build names it. */
static JointBuilder *const builders[JOINT_KIND_COUNT] = {
#define X(e, ...) [JOINT_##e] = lower_##e,
#include "../parse/joints.def"
#undef X
};

void joints_lower(Model *model, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    builders[j->kind](&model->dag, j, rows);
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
    Vec u = unit_axis(d, j);
    if (j->a.has_phi)
        u = rotate(d, angle_of(d, j->a), u);
    Vec e = difference(d, j->b, j->a);
    return dot(d, u, e);
}
