/* generic_joints.c - the standard joints' rows, Jacobian, nu and gamma, by the textbook formulas.
 *
 * Body coordinates (x, y, phi); an attachment's global position is
 * P = r + A(phi) s with A the rotation by phi, and
 *
 *   dP/dr = I,   dP/dphi = B s = perp(A s),   B = dA/dphi,  perp(v) = (-v_y, v_x),
 *   dP/dt = r' + perp(A s) phi',
 *   d2P/dt2 = r'' + perp(A s) phi'' - A s phi'^2.
 *
 * gamma is the part of d2(row)/dt2 without qdd (so qdd = 0 below), with
 * the sign of Phi_q qdd = gamma: gamma = -(d2 row/dt2)|qdd=0. For
 * revolute P_A - P_B it is A_A s_A phi_A'^2 - A_B s_B phi_B'^2 (Haug,
 * Computer-Aided Kinematics and Dynamics of Mechanical Systems, 1989,
 * ch. 3; Nikravesh, Computer-Aided Analysis of Mechanical Systems, 1988,
 * ch. 3 and 4). Every formula here was derived by hand, independently of
 * the symbolic differentiator (generator/diff/).
 *
 * Ground is an attachment without coordinates (P = s); a point has
 * P = r and no angle. Jacobian entries are added (+=), so a joint whose
 * two attachments share a body gets the sum of both contributions.
 */
#include "generic_impl.h"

/* An attachment at the current state. */
typedef struct Pt {
    double x, y;        /* P */
    double ax, ay;      /* A(phi) s (zero for ground and points) */
    double vx, vy;      /* dP/dt (when qd is given) */
    double w;           /* phi' (zero without an angle) */
} Pt;

static Pt point_at(const Call *c, const Attach *at)
{
    Pt p = {0};
    if (at->q < 0) {
        p.x = at->sx;
        p.y = at->sy;
        return p;
    }
    const double *q = c->q;
    p.x = q[at->q];
    p.y = q[at->q + 1];
    if (at->has_phi && (at->sx != 0.0 || at->sy != 0.0)) {
        double cs = c->g->cosq[at->q + 2], sn = c->g->sinq[at->q + 2];
        p.ax = cs * at->sx - sn * at->sy;
        p.ay = sn * at->sx + cs * at->sy;
        p.x += p.ax;
        p.y += p.ay;
    }
    if (c->qd) {
        p.vx = c->qd[at->q];
        p.vy = c->qd[at->q + 1];
        if (at->has_phi) {
            p.w = c->qd[at->q + 2];
            p.vx -= p.ay * p.w;
            p.vy += p.ax * p.w;
        }
    }
    return p;
}

/* row += d(e . P)/dq = e on (x, y), e . perp(A s) on phi. */
static void jac_point(double *row, const Attach *at, const Pt *p, double ex, double ey)
{
    if (at->q < 0)
        return;
    row[at->q] += ex;
    row[at->q + 1] += ey;
    if (at->has_phi)
        row[at->q + 2] += -ex * p->ay + ey * p->ax;
}

static double angle_of(const Call *c, const Attach *at)
{
    return at->has_phi ? c->q[at->q + 2] : 0.0;
}

/* n_A = A(phi_A) (-uy, ux): the body-fixed normal of the axis. */
static void normal_of(const Call *c, const Attach *at, double ux, double uy, double *nx, double *ny)
{
    if (!at->has_phi) {
        *nx = -uy;
        *ny = ux;
        return;
    }
    double cs = c->g->cosq[at->q + 2], sn = c->g->sinq[at->q + 2];
    *nx = -cs * uy - sn * ux;
    *ny = -sn * uy + cs * ux;
}

static double *jac_row(const Call *c, int r)
{
    return c->jac + (size_t)r * (size_t)c->g->nq;
}

/* revolute (and weld) rows r, r+1: P_A - P_B.
   Jacobian blocks [I, B_A s_A] and [-I, -B_B s_B]; nu = 0;
   gamma = A_A s_A phi_A'^2 - A_B s_B phi_B'^2. */
static void revolute_rows(const Call *c, const Joint *j, int r)
{
    Pt a = point_at(c, &j->a), b = point_at(c, &j->b);
    if (c->phi) {
        c->phi[r] = a.x - b.x;
        c->phi[r + 1] = a.y - b.y;
    }
    if (c->jac) {
        double *rx = jac_row(c, r), *ry = jac_row(c, r + 1);
        jac_point(rx, &j->a, &a, 1.0, 0.0);
        jac_point(ry, &j->a, &a, 0.0, 1.0);
        jac_point(rx, &j->b, &b, -1.0, 0.0);
        jac_point(ry, &j->b, &b, 0.0, -1.0);
    }
    if (c->nu)
        c->nu[r] = c->nu[r + 1] = 0.0;
    if (c->gamma) {
        double wa2 = a.w * a.w, wb2 = b.w * b.w;
        c->gamma[r] = a.ax * wa2 - b.ax * wb2;
        c->gamma[r + 1] = a.ay * wa2 - b.ay * wb2;
    }
}

/* prismatic (row n) and pointline: f = n_A . d, d = P_B - P_A.
   df/dr_A = -n, df/dphi_A = perp(n) . d - n . perp(A_A s_A),
   df/dr_B = n,  df/dphi_B = n . perp(A_B s_B); nu = 0;
   D2 f = n'' . d + 2 n' . d' + n . d'' with n' = perp(n) phi_A',
   n'' = -n phi_A'^2, d'' = -A_B s_B phi_B'^2 + A_A s_A phi_A'^2; gamma = -D2 f. */
static void normal_row(const Call *c, const Joint *j, int r)
{
    Pt a = point_at(c, &j->a), b = point_at(c, &j->b);
    double nx, ny;
    normal_of(c, &j->a, j->ux, j->uy, &nx, &ny);
    double dx = b.x - a.x, dy = b.y - a.y;
    if (c->phi)
        c->phi[r] = nx * dx + ny * dy;
    if (c->jac) {
        double *row = jac_row(c, r);
        jac_point(row, &j->b, &b, nx, ny);
        jac_point(row, &j->a, &a, -nx, -ny);
        if (j->a.has_phi)
            row[j->a.q + 2] += -ny * dx + nx * dy;
    }
    if (c->nu)
        c->nu[r] = 0.0;
    if (c->gamma) {
        double w = a.w;     /* the normal turns with A */
        double ndx = -ny * w, ndy = nx * w, nddx = -nx * w * w, nddy = -ny * w * w;
        double ddx = b.vx - a.vx, ddy = b.vy - a.vy;
        double dddx = -b.ax * b.w * b.w + a.ax * a.w * a.w;
        double dddy = -b.ay * b.w * b.w + a.ay * a.w * a.w;
        c->gamma[r] = -(nddx * dx + nddy * dy + 2.0 * (ndx * ddx + ndy * ddy) + nx * dddx + ny * dddy);
    }
}

/* prismatic and weld row phi: phi_B - phi_A - theta(q, t).
   Jacobian +1 on phi_B, -1 on phi_A, -theta_q; nu = theta_t; gamma = D2 theta. */
static void angle_row(const Call *c, const Plan *p, int r)
{
    const Joint *j = p->j;
    double theta = option_value(c, &p->opt);
    if (c->phi)
        c->phi[r] = angle_of(c, &j->b) - angle_of(c, &j->a) - theta;
    if (c->jac) {
        double *row = jac_row(c, r);
        if (j->b.has_phi)
            row[j->b.q + 2] += 1.0;
        if (j->a.has_phi)
            row[j->a.q + 2] -= 1.0;
        option_jac(c, &p->opt, -1.0, row);
    }
    if (c->nu)
        c->nu[r] = option_dt(c, &p->opt);
    if (c->gamma)
        c->gamma[r] = option_along(c, &p->opt, 2).dd;
}

/* distance: f = d . d - L^2, d = P_B - P_A.
   df/dr_B = 2d, df/dphi_B = 2 d . perp(A_B s_B), the negatives for A,
   -2 L L_q; nu = 2 L L_t;
   D2 f = 2 d'.d' + 2 d.d'' - 2 (DL)^2 - 2 L D2L; gamma = -D2 f. */
static void distance_row(const Call *c, const Plan *p)
{
    int r = p->row;
    const Joint *j = p->j;
    Pt a = point_at(c, &j->a), b = point_at(c, &j->b);
    double dx = b.x - a.x, dy = b.y - a.y;
    double len = option_value(c, &p->opt);
    if (c->phi)
        c->phi[r] = dx * dx + dy * dy - len * len;
    if (c->jac) {
        double *row = jac_row(c, r);
        jac_point(row, &j->b, &b, 2.0 * dx, 2.0 * dy);
        jac_point(row, &j->a, &a, -2.0 * dx, -2.0 * dy);
        option_jac(c, &p->opt, -2.0 * len, row);
    }
    if (c->nu)
        c->nu[r] = 2.0 * len * option_dt(c, &p->opt);
    if (c->gamma) {
        double ddx = b.vx - a.vx, ddy = b.vy - a.vy;
        double dddx = -b.ax * b.w * b.w + a.ax * a.w * a.w;
        double dddy = -b.ay * b.w * b.w + a.ay * a.w * a.w;
        Jet l = option_along(c, &p->opt, 2);
        c->gamma[r] = -(2.0 * (ddx * ddx + ddy * ddy) + 2.0 * (dx * dddx + dy * dddy)
                        - 2.0 * l.d * l.d - 2.0 * l.v * l.dd);
    }
}

/* rolling (velocity level): Psi = x_B' + R phi_B'.
   a = (1 on x, R on phi); nu = -Psi(qd = 0) = 0; gamma = -(DR) phi_B'. */
static void rolling_row(const Call *c, const Plan *p)
{
    int r = p->row;
    const Attach *at = &p->j->a;
    double radius = option_value(c, &p->opt);
    if (c->psi)
        c->psi[r - c->g->nh] = c->qd[at->q] + radius * c->qd[at->q + 2];
    if (c->jac) {
        double *row = jac_row(c, r);
        row[at->q] += 1.0;
        row[at->q + 2] += radius;
        /* R's dependence on q is not part of a = dPsi/dqd */
    }
    if (c->nu)
        c->nu[r] = 0.0;
    if (c->gamma)
        c->gamma[r] = p->opt.constant ? 0.0 : -option_along(c, &p->opt, 1).d * c->qd[at->q + 2];
}

/* knife (velocity level): Psi = n_A . dP_A/dt.
   a = (n on x, y; n . perp(A s) on phi); nu = 0;
   gamma = -(perp(n) phi' . P' + n . P'') with P'' = -A s phi'^2. */
static void knife_row(const Call *c, const Plan *p)
{
    int r = p->row;
    const Joint *j = p->j;
    Pt a = point_at(c, &j->a);
    double nx, ny;
    normal_of(c, &j->a, j->ux, j->uy, &nx, &ny);
    if (c->psi)
        c->psi[r - c->g->nh] = nx * a.vx + ny * a.vy;
    if (c->jac)
        jac_point(jac_row(c, r), &j->a, &a, nx, ny);
    if (c->nu)
        c->nu[r] = 0.0;
    if (c->gamma) {
        double w = a.w;
        c->gamma[r] = -(w * (-ny * a.vx + nx * a.vy) - w * w * (nx * a.ax + ny * a.ay));
    }
}

static void revolute_joint(const Call *c, const Plan *p)
{
    revolute_rows(c, p->j, p->row);
}

static void prismatic_joint(const Call *c, const Plan *p)
{
    normal_row(c, p->j, p->row);
    angle_row(c, p, p->row + 1);
}

static void pointline_joint(const Call *c, const Plan *p)
{
    normal_row(c, p->j, p->row);
}

static void weld_joint(const Call *c, const Plan *p)
{
    revolute_rows(c, p->j, p->row);
    angle_row(c, p, p->row + 2);
}

/* The planar family's formulas and what each rotates. */
static const Formula formula_REVOLUTE = {revolute_joint, TURN_SA | TURN_SB};
static const Formula formula_PRISMATIC = {prismatic_joint, TURN_SA | TURN_SB | TURN_AXIS};
static const Formula formula_DISTANCE = {distance_row, TURN_SA | TURN_SB};
static const Formula formula_POINTLINE = {pointline_joint, TURN_SA | TURN_SB | TURN_AXIS};
static const Formula formula_WELD = {weld_joint, TURN_SA | TURN_SB};
static const Formula formula_ROLLING = {rolling_row, 0};    /* phi' only, no rotation */
static const Formula formula_KNIFE = {knife_row, TURN_SA | TURN_AXIS};
/* constraint, driver, velocity: the row is interpreted (generic.c) */
static const Formula formula_CONSTRAINT = {NULL, 0};
#define formula_DRIVER formula_CONSTRAINT
#define formula_VELOCITY formula_CONSTRAINT

/* Every kind's formulas, by kind: a row of joints.def without its
   formula_KIND (above, or the spatial family's in generic_impl.h) is an
   undeclared identifier, so the build names it. */
static const Formula *const formulas[JOINT_KIND_COUNT] = {
#define X(e, ...) [JOINT_##e] = &formula_##e,
#include "../parse/joints.def"
#undef X
};

/* need[phi] = 1 for velocity-level joints, 2 for position-level ones;
   an attachment without an angle, or an offset of zero, rotates nothing. */
static void need_angle(char *need, const Attach *at, bool axis, bool offset, bool velocity)
{
    if (at->q >= 0 && at->has_phi && (axis || (offset && (at->sx != 0.0 || at->sy != 0.0)))) {
        char level = velocity ? 1 : 2;
        if (need[at->q + 2] < level)
            need[at->q + 2] = level;
    }
}

GenericRows *generic_joint_formula(const Joint *j, char *need)
{
    Formula f = *formulas[j->kind];
    if (f.rows && (f.turns & TURN_P)) {
        if (j->a.has_p)
            need[j->a.q + 3] = NEED_ROT;
        if (j->b.has_p)
            need[j->b.q + 3] = NEED_ROT;
    } else if (f.rows) {
        need_angle(need, &j->a, f.turns & TURN_AXIS, f.turns & TURN_SA, j->velocity);
        need_angle(need, &j->b, false, f.turns & TURN_SB, j->velocity);
    }
    return f.rows;
}
