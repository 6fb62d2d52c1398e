/* joints_spatial.c - the spatial joints' constraint rows over Euler parameters, as equations over graph nodes.
 *
 * A spatial body owns r = (x, y, z) and p = (e0, e1, e2, e3), e = (e1, e2, e3);
 * a body-fixed vector s is a_i = A(p) s globally, and a body-fixed point is
 * P = r + A(p) s, with
 *
 *     A(p) = (2 e0^2 - 1) I + 2 (e e^T + e0 e~),   e~ v = e x v
 *
 * (Haug, Computer-Aided Kinematics and Dynamics of Mechanical Systems,
 * 1989, ch. 6 and 9; Nikravesh, Computer-Aided Analysis of Mechanical
 * Systems, 1988, ch. 6 and 7). Every joint is built from three blocks:
 *
 *     dot-1      a_i^T a_j = 0            (two body-fixed vectors stay perpendicular)
 *     dot-2      a_i^T d_ij = 0,  d_ij = P_j - P_i
 *     spherical  P_i - P_j = 0            (three rows)
 *
 * An axis h is given in A's frame, and in B's (the same local vector
 * unless a second axis(...) gives B's). From a unit axis h the builders
 * take the perpendicular f = unit(e_k - h_k h), e_k the coordinate axis
 * with the smallest |h_k| (the first of equals), and g = h x f: for
 * h = z, f = x and g = y. A(p_A) f_A, A(p_A) g_A, A(p_B) h_B, ... are
 * written fA, gA, hB below.
 *
 * As in joints.c, every node is made in a statement of its own, so the
 * node ids (the generated C's temporaries) do not depend on the order a
 * compiler evaluates a call's arguments in.
 */
#include "joint_builders.h"

#include <math.h>

typedef struct Vec3 {
    NodeId x, y, z;
} Vec3;

/* A body-fixed vector s of a joint side, not yet turned: A(p) s is built
   only where a product needs it (see axis_dot). A vector of an axis of
   design parameters is the nodes v instead. */
typedef struct Axis3 {
    Attach at;
    double s[3];
    bool designed;
    Vec3 v;
} Axis3;

/* A joint side's axis and two perpendiculars, body-fixed. */
typedef struct Frame3 {
    Axis3 h, f, g;
} Frame3;

static Vec3 v3_const(Dag *d, const double v[3])
{
    NodeId x = dag_const(d, v[0]);
    NodeId y = dag_const(d, v[1]);
    NodeId z = dag_const(d, v[2]);
    return (Vec3){x, y, z};
}

static Vec3 v3_sub(Dag *d, Vec3 a, Vec3 b)
{
    NodeId x = dag_sub(d, a.x, b.x);
    NodeId y = dag_sub(d, a.y, b.y);
    NodeId z = dag_sub(d, a.z, b.z);
    return (Vec3){x, y, z};
}

static Vec3 v3_add(Dag *d, Vec3 a, Vec3 b)
{
    NodeId x = dag_add(d, a.x, b.x);
    NodeId y = dag_add(d, a.y, b.y);
    NodeId z = dag_add(d, a.z, b.z);
    return (Vec3){x, y, z};
}

static Vec3 v3_scale(Dag *d, NodeId k, Vec3 a)
{
    NodeId x = dag_mul(d, k, a.x);
    NodeId y = dag_mul(d, k, a.y);
    NodeId z = dag_mul(d, k, a.z);
    return (Vec3){x, y, z};
}

/* a^T b */
static NodeId v3_dot(Dag *d, Vec3 a, Vec3 b)
{
    NodeId xx = dag_mul(d, a.x, b.x);
    NodeId yy = dag_mul(d, a.y, b.y);
    NodeId zz = dag_mul(d, a.z, b.z);
    NodeId xy = dag_add(d, xx, yy);
    return dag_add(d, xy, zz);
}

/* a x b */
static Vec3 v3_cross(Dag *d, Vec3 a, Vec3 b)
{
    NodeId yz = dag_mul(d, a.y, b.z), zy = dag_mul(d, a.z, b.y);
    NodeId x = dag_sub(d, yz, zy);
    NodeId zx = dag_mul(d, a.z, b.x), xz = dag_mul(d, a.x, b.z);
    NodeId y = dag_sub(d, zx, xz);
    NodeId xy = dag_mul(d, a.x, b.y), yx = dag_mul(d, a.y, b.x);
    NodeId z = dag_sub(d, xy, yx);
    return (Vec3){x, y, z};
}

/* e = (e1, e2, e3) of a spatial body whose x is q[at.q] */
static Vec3 euler_vector(Dag *d, Attach at)
{
    NodeId e1 = dag_var(d, at.q + 4);
    NodeId e2 = dag_var(d, at.q + 5);
    NodeId e3 = dag_var(d, at.q + 6);
    return (Vec3){e1, e2, e3};
}

/* A(p) s = (2 e0^2 - 1) s + e (e^T 2s) + e0 (e x 2s): the factor 2 in
   the constant vector, where it folds into s's components; ground and
   points do not turn: s itself. */
static Vec3 rotate3_nodes(Dag *d, Attach at, Vec3 s, Vec3 s2);

static Vec3 rotate3(Dag *d, Attach at, const double local[3])
{
    Vec3 s = v3_const(d, local);
    if (!at.has_p)
        return s;
    double twice[3] = {2 * local[0], 2 * local[1], 2 * local[2]};
    const char *outer = d->what;
    d->what = "an attachment's offset s, doubled in A(p) s";
    Vec3 s2 = v3_const(d, twice);
    d->what = outer;
    return rotate3_nodes(d, at, s, s2);
}

/* The same with s and 2 s given as nodes (an offset of design parameters). */
static Vec3 rotate3_nodes(Dag *d, Attach at, Vec3 s, Vec3 s2)
{
    NodeId two = dag_const(d, 2.0);
    NodeId e0 = dag_var(d, at.q + 3);
    Vec3 e = euler_vector(d, at);
    NodeId e00 = dag_mul(d, e0, e0);
    NodeId c2 = dag_mul(d, two, e00);
    NodeId c = dag_sub(d, c2, DAG_ONE);
    Vec3 cs = v3_scale(d, c, s);
    NodeId es = v3_dot(d, e, s2);
    Vec3 ees = v3_scale(d, es, e);
    Vec3 exs = v3_cross(d, e, s2);
    Vec3 e0exs = v3_scale(d, e0, exs);
    Vec3 sum = v3_add(d, ees, e0exs);
    return v3_add(d, cs, sum);
}

/* position3 of an attachment whose offset depends on design parameters. */
static Vec3 designed_position3(Dag *d, Attach at)
{
    Vec3 s = {at.s_node[0], at.s_node[1], at.s_node[2]};
    if (at.q < 0)
        return s;
    Vec3 r = {dag_var(d, at.q), dag_var(d, at.q + 1), dag_var(d, at.q + 2)};
    if (!at.has_p)
        return r;
    NodeId two = dag_const(d, 2.0);
    Vec3 s2 = v3_scale(d, two, s);
    return v3_add(d, r, rotate3_nodes(d, at, s, s2));
}

/* P = r + A(p) s (ground: s, the global point; a point: r). */
static Vec3 position3(Dag *d, Attach at)
{
    if (at.designed)
        return designed_position3(d, at);
    double s[3] = {at.sx, at.sy, at.sz};
    if (at.q < 0)
        return v3_const(d, s);
    NodeId x = dag_var(d, at.q);
    NodeId y = dag_var(d, at.q + 1);
    NodeId z = dag_var(d, at.q + 2);
    Vec3 r = {x, y, z};
    if (!at.has_p || (s[0] == 0.0 && s[1] == 0.0 && s[2] == 0.0))
        return r;
    Vec3 as = rotate3(d, at, s);
    return v3_add(d, r, as);
}

/* P_p - P_q (P_q's nodes made first) */
static Vec3 difference3(Dag *d, Attach p, Attach q)
{
    Vec3 pq = position3(d, q);
    Vec3 pp = position3(d, p);
    return v3_sub(d, pp, pq);
}

/* The coordinate axis e_k f starts from: the smallest |h_k|, the first of equals. */
static int frame_start(const double h[3])
{
    int k = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(h[i]) < fabs(h[k]))
            k = i;
    return k;
}

/* The unit axis h and its perpendiculars f, g (see the header), local. */
void joints_spatial_frame(double ux, double uy, double uz, double h[3], double f[3], double g[3])
{
    double n = sqrt(ux * ux + uy * uy + uz * uz);
    h[0] = ux / n, h[1] = uy / n, h[2] = uz / n;
    int k = frame_start(h);
    double len = 0;
    for (int i = 0; i < 3; i++) {
        f[i] = (i == k) - h[k] * h[i];
        len += f[i] * f[i];
    }
    len = sqrt(len);
    for (int i = 0; i < 3; i++)
        f[i] /= len;
    g[0] = h[1] * f[2] - h[2] * f[1];
    g[1] = h[2] * f[0] - h[0] * f[2];
    g[2] = h[0] * f[1] - h[1] * f[0];
}

/* The frame of an axis u of design parameters, as nodes: h = u / |u|,
   f = (e_k - h_k h) / sqrt(1 - h_k^2), g = h x f, with k the one of the
   file's design (fr's numbers), so that the rows are smooth in p about it. */
static void designed_frame3(Dag *d, Frame3 *fr, const NodeId u[3])
{
    int k = frame_start(fr->h.s);
    Vec3 uv = {u[0], u[1], u[2]};
    NodeId uu = v3_dot(d, uv, uv);
    NodeId n = dag_call(d, OP_SQRT, uu, DAG_NONE);
    NodeId inv = dag_div(d, DAG_ONE, n);
    Vec3 h = v3_scale(d, inv, uv);
    NodeId hk = k == 0 ? h.x : k == 1 ? h.y : h.z;
    Vec3 khh = v3_scale(d, hk, h);
    Vec3 ek = {k == 0 ? DAG_ONE : DAG_ZERO, k == 1 ? DAG_ONE : DAG_ZERO, k == 2 ? DAG_ONE : DAG_ZERO};
    Vec3 f0 = v3_sub(d, ek, khh);
    NodeId hk2 = dag_mul(d, hk, hk);
    NodeId rest = dag_sub(d, DAG_ONE, hk2);
    NodeId len = dag_call(d, OP_SQRT, rest, DAG_NONE);
    NodeId il = dag_div(d, DAG_ONE, len);
    Vec3 f = v3_scale(d, il, f0);
    Vec3 g = v3_cross(d, h, f);
    fr->h.v = h, fr->f.v = f, fr->g.v = g;
    fr->h.designed = fr->f.designed = fr->g.designed = true;
}

static bool nodes_constant(const Dag *d, const NodeId u[3])
{
    return dag_is_const(d, u[0], NULL) && dag_is_const(d, u[1], NULL) && dag_is_const(d, u[2], NULL);
}

/* The h, f, g of side A (b false: the axis (ux, uy, uz)) or B. */
static Frame3 frame3(Dag *d, const Joint *j, bool b)
{
    Frame3 fr = {0};
    if (b)
        joints_spatial_frame(j->bx, j->by, j->bz, fr.h.s, fr.f.s, fr.g.s);
    else
        joints_spatial_frame(j->ux, j->uy, j->uz, fr.h.s, fr.f.s, fr.g.s);
    fr.h.at = fr.f.at = fr.g.at = b ? j->b : j->a;
    const NodeId *u = b ? j->b_node : j->u_node;
    if (j->axis_designed && !nodes_constant(d, u))
        designed_frame3(d, &fr, u);
    return fr;
}

static Vec3 axis_global(Dag *d, Axis3 v)
{
    if (!v.designed)
        return rotate3(d, v.at, v.s);
    if (!v.at.has_p)
        return v.v;
    NodeId two = dag_const(d, 2.0);
    Vec3 s2 = v3_scale(d, two, v.v);
    return rotate3_nodes(d, v.at, v.v, s2);
}

/* c^T A(p) s for a constant c, written so each factor is linear in p:
     (2 e0^2 - 1) c^T s + (c^T e)(2s^T e) + e0 e^T (2s x c)
   (c^T (e x s) = e^T (s x c)). The same polynomial as c^T (A(p) s), in
   fewer operations, and its derivatives stay products of linear forms
   (a joint to ground or a driver against ground). */
static NodeId fixed_dot(Dag *d, const double c[3], Axis3 v)
{
    const double *s = v.s;
    double s2[3] = {2 * s[0], 2 * s[1], 2 * s[2]};
    double sc2[3] = {s2[1] * c[2] - s2[2] * c[1], s2[2] * c[0] - s2[0] * c[2], s2[0] * c[1] - s2[1] * c[0]};
    double cs = c[0] * s[0] + c[1] * s[1] + c[2] * s[2];
    NodeId e0 = dag_var(d, v.at.q + 3);
    Vec3 e = euler_vector(d, v.at);
    NodeId sum = DAG_ZERO;
    if (cs != 0.0) {
        NodeId two = dag_const(d, 2.0);
        NodeId e00 = dag_mul(d, e0, e0);
        NodeId c2 = dag_mul(d, two, e00);
        NodeId cc = dag_sub(d, c2, DAG_ONE);
        NodeId k = dag_const(d, cs);
        sum = dag_mul(d, k, cc);
    }
    Vec3 cv = v3_const(d, c);
    Vec3 s2v = v3_const(d, s2);
    NodeId ce = v3_dot(d, cv, e);
    NodeId se = v3_dot(d, s2v, e);
    NodeId quad = dag_mul(d, ce, se);
    sum = dag_add(d, sum, quad);
    Vec3 scv = v3_const(d, sc2);
    NodeId esc = v3_dot(d, e, scv);
    NodeId lin = dag_mul(d, e0, esc);
    return dag_add(d, sum, lin);
}

/* (A(p_a) a)^T (A(p_b) b); one side fixed (ground or a point): fixed_dot. */
static NodeId axis_dot(Dag *d, Axis3 a, Axis3 b)
{
    if (a.designed || b.designed) {
        Vec3 ga = axis_global(d, a);
        Vec3 gb = axis_global(d, b);
        return v3_dot(d, ga, gb);
    }
    if (!a.at.has_p && b.at.has_p)
        return fixed_dot(d, a.s, b);
    if (a.at.has_p && !b.at.has_p)
        return fixed_dot(d, b.s, a);
    Vec3 ga = axis_global(d, a);
    Vec3 gb = axis_global(d, b);
    return v3_dot(d, ga, gb);
}

/* spherical: P_A - P_B = 0 (rows[0..2]) */
static void spherical(Dag *d, const Joint *j, NodeId rows[3])
{
    Vec3 e = difference3(d, j->a, j->b);
    rows[0] = e.x;
    rows[1] = e.y;
    rows[2] = e.z;
}

/* .f, .g: dot-1 fA^T hB = 0, gA^T hB = 0 (the axes stay parallel) */
static void parallel(Dag *d, const Frame3 *a, const Frame3 *b, NodeId rows[2])
{
    rows[0] = axis_dot(d, a->f, b->h);
    rows[1] = axis_dot(d, a->g, b->h);
}

/* cylindrical: .f, .g parallel axes; .df, .dg dot-2 fA^T d = 0, gA^T d = 0,
   d = P_B - P_A (B's point stays on A's axis line) */
static void cylindrical(Dag *d, const Joint *j, const Frame3 *a, const Frame3 *b, NodeId rows[4])
{
    parallel(d, a, b, rows);
    Vec3 e = difference3(d, j->b, j->a);
    Vec3 fa = axis_global(d, a->f), ga = axis_global(d, a->g);
    rows[2] = v3_dot(d, fa, e);
    rows[3] = v3_dot(d, ga, e);
}

void lower_S_SPHERICAL(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    spherical(d, j, rows);
}

/* universal: spherical; .dot dot-1 hA^T hB = 0 */
void lower_S_UNIVERSAL(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false), b = frame3(d, j, true);
    spherical(d, j, rows);
    rows[3] = axis_dot(d, a.h, b.h);
}

/* revolute: spherical; .f, .g parallel axes */
void lower_S_REVOLUTE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false), b = frame3(d, j, true);
    spherical(d, j, rows);
    parallel(d, &a, &b, rows + 3);
}

void lower_S_CYLINDRICAL(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false), b = frame3(d, j, true);
    cylindrical(d, j, &a, &b, rows);
}

/* translational: cylindrical; .rot dot-1 gA^T fB = 0 (no turning about h) */
void lower_S_TRANSLATIONAL(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false), b = frame3(d, j, true);
    cylindrical(d, j, &a, &b, rows);
    rows[4] = axis_dot(d, a.g, b.f);
}

/* weld: .x .y .z spherical; .xy, .yz, .zx dot-1 xA^T yB, yA^T zB, zA^T xB
   (B's axes stay those of A: the relative orientation is the identity) */
void lower_S_WELD(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    spherical(d, j, rows);
    Axis3 xa = {.at = j->a, .s = {1, 0, 0}}, ya = {.at = j->a, .s = {0, 1, 0}};
    Axis3 za = {.at = j->a, .s = {0, 0, 1}}, xb = {.at = j->b, .s = {1, 0, 0}};
    Axis3 yb = {.at = j->b, .s = {0, 1, 0}}, zb = {.at = j->b, .s = {0, 0, 1}};
    rows[3] = axis_dot(d, xa, yb);
    rows[4] = axis_dot(d, ya, zb);
    rows[5] = axis_dot(d, za, xb);
}

/* distance: d^T d - L^2 = 0, d = P_B - P_A; a length written as sqrt(u)
   gives L^2 = u, without the square root and the divisions its
   derivatives would bring into nu and gamma (a leg length from
   closed-form inverse kinematics is one). */
void lower_S_DISTANCE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Vec3 e = difference3(d, j->b, j->a);
    const DagNode *len = dag_node(d, j->option);
    NodeId l2 = len->op == OP_SQRT ? len->a : dag_mul(d, j->option, j->option);
    NodeId ee = v3_dot(d, e, e);
    rows[0] = dag_sub(d, ee, l2);
}

/* pointplane: dot-2 hA^T (P_B - P_A) = 0 */
void lower_S_POINTPLANE(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false);
    Vec3 e = difference3(d, j->b, j->a);
    Vec3 ha = axis_global(d, a.h);
    rows[0] = v3_dot(d, ha, e);
}

void lower_S_PARALLEL(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false), b = frame3(d, j, true);
    parallel(d, &a, &b, rows);
}

/* perpendicular: dot-1 hA^T hB = 0 */
void lower_S_PERPENDICULAR(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    Frame3 a = frame3(d, j, false), b = frame3(d, j, true);
    rows[0] = axis_dot(d, a.h, b.h);
}

/* omega = 2 E(p) p', E = [-e, e~ + e0 I]: a spatial body's angular velocity, global */
static Vec3 omega3(Dag *d, Attach at)
{
    NodeId p[4], v[4];
    for (int i = 0; i < 4; i++) {
        p[i] = dag_var(d, at.q + 3 + i);
        v[i] = dag_vard(d, at.q + 3 + i);
    }
    /* rows of E: (-e1, e0, -e3, e2), (-e2, e3, e0, -e1), (-e3, -e2, e1, e0) */
    static const int idx[3][4] = {{1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
    static const double sgn[3][4] = {{-2, 2, -2, 2}, {-2, 2, 2, -2}, {-2, -2, 2, 2}};
    NodeId w[3];
    for (int r = 0; r < 3; r++) {
        w[r] = DAG_ZERO;
        for (int c = 0; c < 4; c++) {
            NodeId k = dag_const(d, sgn[r][c]);
            NodeId kp = dag_mul(d, k, p[idx[r][c]]);
            NodeId term = dag_mul(d, kp, v[c]);
            w[r] = dag_add(d, w[r], term);
        }
    }
    return (Vec3){w[0], w[1], w[2]};
}

/* The disk's lowest rim point, relative to its centre, times s:
   a = A(p) u the unit axle, s = sqrt(a_x^2 + a_y^2),
   k s = (a_x a_z, a_y a_z, -s^2), k = unit(a a_z - e_z). */
static Vec3 contact_offset(Dag *d, const Joint *j, NodeId *s_out)
{
    double u[3] = {j->ux, j->uy, j->uz};
    double n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; i++)
        u[i] /= n;
    Vec3 a = j->axis_designed ? axis_global(d, frame3(d, j, false).h) : rotate3(d, j->a, u);
    NodeId xx = dag_mul(d, a.x, a.x);
    NodeId yy = dag_mul(d, a.y, a.y);
    NodeId s2 = dag_add(d, xx, yy);
    *s_out = dag_call(d, OP_SQRT, s2, DAG_NONE);
    NodeId kx = dag_mul(d, a.x, a.z);
    NodeId ky = dag_mul(d, a.y, a.z);
    NodeId kz = dag_neg(d, s2);
    return (Vec3){kx, ky, kz};
}

/* rolling (no slip on the plane z = 0), velocity level: the disk's material
   point at the contact, r' + omega x (R k), has no x and no y velocity:
   .x: x' + R (omega x k)_x = 0,  .y: y' + R (omega x k)_y = 0 */
void lower_S_ROLLING(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    NodeId s;
    Vec3 ks = contact_offset(d, j, &s);
    NodeId rs = dag_div(d, j->option, s);
    Vec3 k = v3_scale(d, rs, ks);
    Vec3 w = omega3(d, j->a);
    Vec3 wk = v3_cross(d, w, k);
    NodeId vx = dag_vard(d, j->a.q);
    rows[0] = dag_add(d, vx, wk.x);
    NodeId vy = dag_vard(d, j->a.q + 1);
    rows[1] = dag_add(d, vy, wk.y);
}

/* contact (the rolling disk's holonomic row) .h: the lowest rim point is on
   the plane, z + R k_z = z - R s = 0 */
void lower_S_CONTACT(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    NodeId s;
    contact_offset(d, j, &s);
    NodeId z = dag_var(d, j->a.q + 2);
    NodeId rs = dag_mul(d, j->option, s);
    rows[0] = dag_sub(d, z, rs);
}

/* body B .norm: e0^2 + e1^2 + e2^2 + e3^2 - 1 = 0 */
void lower_S_NORM(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS])
{
    NodeId sum = DAG_ZERO;
    for (int i = 0; i < 4; i++) {
        NodeId e = dag_var(d, j->a.q + 3 + i);
        NodeId ee = dag_mul(d, e, e);
        sum = dag_add(d, sum, ee);
    }
    rows[0] = dag_sub(d, sum, DAG_ONE);
}

void joints_spatial_point(Model *model, Attach at, NodeId xyz[3])
{
    Vec3 p = position3(&model->dag, at);
    xyz[0] = p.x;
    xyz[1] = p.y;
    xyz[2] = p.z;
}

/* slide(T) = hA^T (P_B - P_A), |h| = 1 */
NodeId joints_spatial_slide(Model *model, const Joint *j)
{
    Dag *d = &model->dag;
    Frame3 a = frame3(d, j, false);
    Vec3 e = difference3(d, j->b, j->a);
    Vec3 ha = axis_global(d, a.h);
    return v3_dot(d, ha, e);
}

/* With fB = cos(angle) fA + sin(angle) gA about the common axis:
   gA^T fB = sin(angle), fA^T fB = cos(angle). */
NodeId joints_spatial_angle(Model *model, const Joint *j)
{
    Dag *d = &model->dag;
    Frame3 a = frame3(d, j, false);
    Frame3 b = frame3(d, j, true);
    NodeId c = axis_dot(d, a.f, b.f);
    NodeId s = axis_dot(d, a.g, b.f);
    return dag_call(d, OP_ATAN2, s, c);
}

/* cos(theta) gA^T fB - sin(theta) fA^T fB = sin(angle - theta): no branch
   cut, so a drive may turn any number of times */
NodeId joints_spatial_angle_row(Model *model, const Joint *j, NodeId theta)
{
    Dag *d = &model->dag;
    Frame3 a = frame3(d, j, false);
    Frame3 b = frame3(d, j, true);
    NodeId c = axis_dot(d, a.f, b.f);
    NodeId s = axis_dot(d, a.g, b.f);
    NodeId ct = dag_call(d, OP_COS, theta, DAG_NONE);
    NodeId st = dag_call(d, OP_SIN, theta, DAG_NONE);
    NodeId left = dag_mul(d, ct, s);
    NodeId right = dag_mul(d, st, c);
    return dag_sub(d, left, right);
}
