/* generic_spatial.c - the spatial joints' rows, Jacobian, nu and gamma over Euler parameters, by hand-derived formulas.
 *
 * A spatial body has r = (x, y, z) and p = (e0, e), e = (e1, e2, e3); a
 * body-fixed vector s is a = A(p) s globally, a body-fixed point
 * P = r + A(p) s, with the builder's A (generator/model/joints_spatial.c)
 *
 *     A(p) = (2 e0^2 - 1) I + 2 (e e^T + e0 e~),   e~ v = e x v.
 *
 * The rows are the builder's, derived here by hand (Nikravesh,
 * Computational Methods in Spatial Dynamics of Multibody Systems, and
 * Computer-Aided Analysis of Mechanical Systems, 1988, ch. 6 and 7; Haug,
 * 1989, ch. 9), not by generator/diff/. A is not made orthogonal by
 * p^T p = 1 here: the rows hold at any p (Newton's iterates leave the
 * unit sphere), so every derivative is of the expression above as it
 * stands, not of Nikravesh's E G^T form, which agrees only on the sphere:
 *
 *     B(p, s) = d(A s)/dp:  d/de0 = 4 e0 s + 2 e x s,
 *                           d/de_k = 2 (e.s) u_k + 2 e s_k + 2 e0 u_k x s
 *                           (u_k the unit vector k), so for a row w^T (A s)
 *     w^T B = (4 e0 (w.s) + 2 w.(e x s),  2 (e.s) w + 2 (w.e) s + 2 e0 s x w);
 *     d(A s)/dt = Ad s,    Ad = 4 e0 e0' I + 2 (e e'^T + e' e^T) + 2 (e0' e + e0 e')~;
 *     d2(A s)/dt2 = B(p, s) p'' + H s,   H = 4 e0'^2 I + 4 e' e'^T + 4 e0' e'~,
 *
 * H s = B(p', s) p' being the part without p'' (H depends on p' only).
 * A call computes A, and with qd also Ad and H, of every spatial body the
 * formulas turn, once (generic_spatial_rotations); each vector is then one
 * matrix product. The blocks, with gamma = -(d2 row/dt2) at qdd = 0:
 *
 *     dot-1      a_i^T a_j:  Jacobian a_j^T B_i + a_i^T B_j;
 *                gamma = -(a_i''.a_j + 2 a_i'.a_j' + a_i.a_j'')
 *     dot-2      a^T d, d = P_B - P_A:  Jacobian d^T B_a + a^T (dP_B/dq - dP_A/dq);
 *                gamma = -(a''.d + 2 a'.d' + a.d'')
 *     spherical  P_A - P_B:  Jacobian [I, B_A] and [-I, -B_B];  gamma = -(H_A s_A - H_B s_B)
 *
 * where a'' and d'' are the qdd-free parts (H s). nu is 0 unless an option
 * (a distance's length, a disk's radius, a driver's angle or slide)
 * depends on t. The norm row, the rolling disk's contact and no-slip rows
 * and the angle() and slide() drivers have formulas of their own below.
 */
#include "generic_impl.h"

#include "../base/sincos.h"

#include <math.h>

/* A vector or point of one side: value, d/dt and d2/dt2 at qdd = 0 (the
   last two only when qd is given). */
typedef struct V3 {
    double v[3], d[3], dd[3];
} V3;

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void mat_vec(const double m[9], const double s[3], double out[3])
{
    out[0] = m[0] * s[0] + m[1] * s[1] + m[2] * s[2];
    out[1] = m[3] * s[0] + m[4] * s[1] + m[5] * s[2];
    out[2] = m[6] * s[0] + m[7] * s[1] + m[8] * s[2];
}

/* m = diag I + x y^T + y x^T + k~ : A, Ad and H have this form. */
static void sym_skew(double m[9], double diag, const double x[3], const double y[3], const double k[3])
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            m[3 * r + c] = x[r] * y[c] + y[r] * x[c] + (r == c ? diag : 0.0);
    m[1] -= k[2], m[2] += k[1];
    m[3] += k[2], m[5] -= k[0];
    m[6] -= k[1], m[7] += k[0];
}

void generic_spatial_rotations(const Call *c)
{
    Generic *g = c->g;
    for (int i = 0; i < g->nrots; i++) {
        Rot *R = &g->rots[i];
        const double *p = c->q + g->rot_q[i] + 3;
        const double e0 = p[0], e[3] = {p[1], p[2], p[3]};
        /* x = y = e: 2 e e^T */
        double k[3] = {2.0 * e0 * e[0], 2.0 * e0 * e[1], 2.0 * e0 * e[2]};
        sym_skew(R->a, 2.0 * e0 * e0 - 1.0, e, e, k);
        if (!c->qd)
            continue;
        const double *pd = c->qd + g->rot_q[i] + 3;
        const double w0 = pd[0], w[3] = {pd[1], pd[2], pd[3]};
        const double w2[3] = {2.0 * w[0], 2.0 * w[1], 2.0 * w[2]};
        for (int j = 0; j < 3; j++)
            k[j] = 2.0 * w0 * e[j] + 2.0 * e0 * w[j];
        sym_skew(R->ad, 4.0 * e0 * w0, e, w2, k);
        for (int j = 0; j < 3; j++)
            k[j] = 4.0 * w0 * w[j];
        sym_skew(R->h, 4.0 * w0 * w0, w, w2, k);
    }
}

static const Rot *rot_of(const Call *c, const Attach *at)
{
    return &c->g->rots[c->g->rot_of[at->q]];
}

/* a = A s of a side's body-fixed vector (ground: s itself, fixed). */
static V3 turned(const Call *c, const Attach *at, const double s[3])
{
    V3 a = {{s[0], s[1], s[2]}, {0}, {0}};
    if (!at->has_p)
        return a;
    const Rot *R = rot_of(c, at);
    mat_vec(R->a, s, a.v);
    if (c->qd) {
        mat_vec(R->ad, s, a.d);
        mat_vec(R->h, s, a.dd);
    }
    return a;
}

static bool offset_of(const Attach *at, double s[3])
{
    s[0] = at->sx, s[1] = at->sy, s[2] = at->sz;
    return s[0] != 0.0 || s[1] != 0.0 || s[2] != 0.0;
}

/* P = r + A s (ground: s, the global point; a point: r). */
static V3 placed(const Call *c, const Attach *at)
{
    double s[3];
    bool offset = offset_of(at, s);
    if (at->q < 0)
        return (V3){{s[0], s[1], s[2]}, {0}, {0}};
    V3 P = {{0}, {0}, {0}};
    if (at->has_p && offset)
        P = turned(c, at, s);
    for (int i = 0; i < 3; i++) {
        P.v[i] += c->q[at->q + i];
        if (c->qd)
            P.d[i] += c->qd[at->q + i];
    }
    return P;
}

/* b - a, each part */
static V3 minus(const V3 *b, const V3 *a)
{
    V3 d;
    for (int i = 0; i < 3; i++) {
        d.v[i] = b->v[i] - a->v[i];
        d.d[i] = b->d[i] - a->d[i];
        d.dd[i] = b->dd[i] - a->dd[i];
    }
    return d;
}

static double *jac_row(const Call *c, int r)
{
    return c->jac + (size_t)r * (size_t)c->g->nq;
}

/* row += k w^T B(p, s) on the side's Euler parameters (see the header). */
static void jac_turned(const Call *c, double *row, const Attach *at, const double s[3],
                       const double w[3], double k)
{
    if (!at->has_p)
        return;
    const double *p = c->q + at->q + 3;
    const double e0 = p[0], e[3] = {p[1], p[2], p[3]};
    double ws = dot3(w, s), es = dot3(e, s), we = dot3(w, e);
    double exs[3] = {e[1] * s[2] - e[2] * s[1], e[2] * s[0] - e[0] * s[2], e[0] * s[1] - e[1] * s[0]};
    double sxw[3] = {s[1] * w[2] - s[2] * w[1], s[2] * w[0] - s[0] * w[2], s[0] * w[1] - s[1] * w[0]};
    row[at->q + 3] += k * (4.0 * e0 * ws + 2.0 * dot3(w, exs));
    for (int i = 0; i < 3; i++)
        row[at->q + 4 + i] += k * 2.0 * (es * w[i] + we * s[i] + e0 * sxw[i]);
}

/* row += k w^T dP/dq: w on r, w^T B(p, s) on p. */
static void jac_placed(const Call *c, double *row, const Attach *at, const double w[3], double k)
{
    if (at->q < 0)
        return;
    for (int i = 0; i < 3; i++)
        row[at->q + i] += k * w[i];
    double s[3];
    if (offset_of(at, s))
        jac_turned(c, row, at, s, w, k);
}

/* Only nu asked for: rows whose nu is 0 write it and stop (the
   rotations are not computed for such a call). */
static bool nu_only(const Call *c, int r, int n)
{
    if (c->nu)
        for (int i = 0; i < n; i++)
            c->nu[r + i] = 0.0;
    return !c->phi && !c->jac && !c->gamma;
}

/* ---- the blocks ---- */

/* dot-1 row r: a^T b, a = A_i s_i on side ai, b = A_j s_j on side bj. */
static void dot1(const Call *c, int r, const Attach *ai, const double si[3], const Attach *bj,
                 const double sj[3])
{
    V3 a = turned(c, ai, si), b = turned(c, bj, sj);
    if (c->phi)
        c->phi[r] = dot3(a.v, b.v);
    if (c->jac) {
        double *row = jac_row(c, r);
        jac_turned(c, row, ai, si, b.v, 1.0);
        jac_turned(c, row, bj, sj, a.v, 1.0);
    }
    if (c->gamma)
        c->gamma[r] = -(dot3(a.dd, b.v) + 2.0 * dot3(a.d, b.d) + dot3(a.v, b.dd));
}

/* dot-2 row r: a^T d, a = A_A s on side A, d = P_B - P_A. */
static void dot2(const Call *c, int r, const Joint *j, const double s[3], const V3 *d)
{
    V3 a = turned(c, &j->a, s);
    if (c->phi)
        c->phi[r] = dot3(a.v, d->v);
    if (c->jac) {
        double *row = jac_row(c, r);
        jac_turned(c, row, &j->a, s, d->v, 1.0);
        jac_placed(c, row, &j->b, a.v, 1.0);
        jac_placed(c, row, &j->a, a.v, -1.0);
    }
    if (c->gamma)
        c->gamma[r] = -(dot3(a.dd, d->v) + 2.0 * dot3(a.d, d->d) + dot3(a.v, d->dd));
}

/* spherical rows r .. r+2: P_A - P_B. */
static void spherical_rows(const Call *c, const Joint *j, int r)
{
    V3 pa = placed(c, &j->a), pb = placed(c, &j->b);
    for (int k = 0; k < 3; k++) {
        if (c->phi)
            c->phi[r + k] = pa.v[k] - pb.v[k];
        if (c->jac) {
            double *row = jac_row(c, r + k);
            double unit[3] = {k == 0, k == 1, k == 2};
            jac_placed(c, row, &j->a, unit, 1.0);
            jac_placed(c, row, &j->b, unit, -1.0);
        }
        if (c->gamma)
            c->gamma[r + k] = -(pa.dd[k] - pb.dd[k]);
    }
}

/* The local frame of a plan: h, f, g of side A, then of side B (generic.c
   fills it with the builder's joints_spatial_frame). */
enum { HA, FA, GA, HB, FB, GB };

/* .f, .g: fA^T hB, gA^T hB (the axes stay parallel) */
static void parallel_rows(const Call *c, const Plan *p, int r)
{
    const Joint *j = p->j;
    dot1(c, r, &j->a, p->frame[FA], &j->b, p->frame[HB]);
    dot1(c, r + 1, &j->a, p->frame[GA], &j->b, p->frame[HB]);
}

/* cylindrical: .f, .g parallel; .df, .dg dot-2 fA^T d, gA^T d */
static void cylindrical_rows(const Call *c, const Plan *p)
{
    const Joint *j = p->j;
    parallel_rows(c, p, p->row);
    V3 pa = placed(c, &j->a), pb = placed(c, &j->b);
    V3 d = minus(&pb, &pa);
    dot2(c, p->row + 2, j, p->frame[FA], &d);
    dot2(c, p->row + 3, j, p->frame[GA], &d);
}

/* ---- the kinds ---- */

static void spherical_joint(const Call *c, const Plan *p)
{
    if (!nu_only(c, p->row, 3))
        spherical_rows(c, p->j, p->row);
}

/* universal: spherical; .dot hA^T hB */
static void universal_joint(const Call *c, const Plan *p)
{
    if (nu_only(c, p->row, 4))
        return;
    spherical_rows(c, p->j, p->row);
    dot1(c, p->row + 3, &p->j->a, p->frame[HA], &p->j->b, p->frame[HB]);
}

/* revolute: spherical; .f, .g parallel */
static void revolute_joint(const Call *c, const Plan *p)
{
    if (nu_only(c, p->row, 5))
        return;
    spherical_rows(c, p->j, p->row);
    parallel_rows(c, p, p->row + 3);
}

static void cylindrical_joint(const Call *c, const Plan *p)
{
    if (!nu_only(c, p->row, 4))
        cylindrical_rows(c, p);
}

/* translational: cylindrical; .rot gA^T fB */
static void translational_joint(const Call *c, const Plan *p)
{
    if (nu_only(c, p->row, 5))
        return;
    cylindrical_rows(c, p);
    dot1(c, p->row + 4, &p->j->a, p->frame[GA], &p->j->b, p->frame[FB]);
}

/* weld: spherical; .xy, .yz, .zx: xA^T yB, yA^T zB, zA^T xB */
static void weld_joint(const Call *c, const Plan *p)
{
    static const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    const Joint *j = p->j;
    if (nu_only(c, p->row, 6))
        return;
    spherical_rows(c, j, p->row);
    dot1(c, p->row + 3, &j->a, ex, &j->b, ey);
    dot1(c, p->row + 4, &j->a, ey, &j->b, ez);
    dot1(c, p->row + 5, &j->a, ez, &j->b, ex);
}

/* pointplane: dot-2 hA^T (P_B - P_A) */
static void pointplane_joint(const Call *c, const Plan *p)
{
    if (nu_only(c, p->row, 1))
        return;
    V3 pa = placed(c, &p->j->a), pb = placed(c, &p->j->b);
    V3 d = minus(&pb, &pa);
    dot2(c, p->row, p->j, p->frame[HA], &d);
}

static void parallel_joint(const Call *c, const Plan *p)
{
    if (!nu_only(c, p->row, 2))
        parallel_rows(c, p, p->row);
}

/* perpendicular: dot-1 hA^T hB */
static void perpendicular_joint(const Call *c, const Plan *p)
{
    if (!nu_only(c, p->row, 1))
        dot1(c, p->row, &p->j->a, p->frame[HA], &p->j->b, p->frame[HB]);
}

/* distance: f = d^T d - L^2, d = P_B - P_A.
   Jacobian 2 d^T (dP_B/dq - dP_A/dq) - 2 L L_q; nu = 2 L L_t;
   gamma = -(2 d'.d' + 2 d.d'' - 2 (DL)^2 - 2 L D2L). */
static void distance_joint(const Call *c, const Plan *p)
{
    int r = p->row;
    double len = option_value(c, &p->opt);
    if (c->nu)
        c->nu[r] = 2.0 * len * option_dt(c, &p->opt);
    if (!c->phi && !c->jac && !c->gamma)
        return;
    V3 pa = placed(c, &p->j->a), pb = placed(c, &p->j->b);
    V3 d = minus(&pb, &pa);
    if (c->phi)
        c->phi[r] = dot3(d.v, d.v) - len * len;
    if (c->jac) {
        double *row = jac_row(c, r);
        jac_placed(c, row, &p->j->b, d.v, 2.0);
        jac_placed(c, row, &p->j->a, d.v, -2.0);
        option_jac(c, &p->opt, -2.0 * len, row);
    }
    if (c->gamma) {
        Jet l = option_along(c, &p->opt, 2);
        c->gamma[r] = -(2.0 * dot3(d.d, d.d) + 2.0 * dot3(d.v, d.dd) - 2.0 * l.d * l.d - 2.0 * l.v * l.dd);
    }
}

/* body .norm: p^T p - 1.  Jacobian 2 p^T; nu 0; gamma = -2 p'^T p'. */
static void norm_joint(const Call *c, const Plan *p)
{
    int r = p->row, q = p->j->a.q + 3;
    if (c->phi)
        c->phi[r] = c->q[q] * c->q[q] + c->q[q + 1] * c->q[q + 1]
                    + c->q[q + 2] * c->q[q + 2] + c->q[q + 3] * c->q[q + 3] - 1.0;
    if (c->jac) {
        double *row = jac_row(c, r);
        for (int i = 0; i < 4; i++)
            row[q + i] += 2.0 * c->q[q + i];
    }
    if (c->nu)
        c->nu[r] = 0.0;
    if (c->gamma) {
        const double *v = c->qd + q;
        c->gamma[r] = -2.0 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
    }
}

/* contact .h: z - R s, s = |(a_x, a_y)|, a = A u the unit axle.
   Jacobian 1 on z, -R (a_x, a_y, 0)^T B(p, u) / s, -s R_q; nu = s R_t;
   gamma = D2(R s) = s D2R + 2 DR Ds + R D2s with Ds = (a_x a_x' + a_y a_y') / s,
   D2s = (a_x'^2 + a_y'^2 + a_x a_x'' + a_y a_y'' - Ds^2) / s. */
static void contact_joint(const Call *c, const Plan *p)
{
    int r = p->row;
    const Attach *at = &p->j->a;
    if (!c->phi && !c->jac && !c->gamma && p->opt.constant) {
        if (c->nu)
            c->nu[r] = 0.0;
        return;     /* generic.c turns A for a nu-only call only when R has t */
    }
    V3 a = turned(c, at, p->frame[HA]);
    double s = sqrt(a.v[0] * a.v[0] + a.v[1] * a.v[1]);
    double radius = option_value(c, &p->opt);
    if (c->phi)
        c->phi[r] = c->q[at->q + 2] - radius * s;
    if (c->jac) {
        double *row = jac_row(c, r);
        double w[3] = {a.v[0] / s, a.v[1] / s, 0.0};
        row[at->q + 2] += 1.0;
        jac_turned(c, row, at, p->frame[HA], w, -radius);
        option_jac(c, &p->opt, -s, row);
    }
    if (c->nu)
        c->nu[r] = s * option_dt(c, &p->opt);
    if (c->gamma) {
        double ds = (a.v[0] * a.d[0] + a.v[1] * a.d[1]) / s;
        double dds = (a.d[0] * a.d[0] + a.d[1] * a.d[1] + a.v[0] * a.dd[0] + a.v[1] * a.dd[1] - ds * ds) / s;
        Jet l = option_along(c, &p->opt, 2);
        c->gamma[r] = s * l.dd + 2.0 * l.d * ds + l.v * dds;
    }
}

/* rows of 2 E(p) (omega = 2 E p', global), as the builder's omega3 */
static void twice_e(const double *p, double E[3][4])
{
    double rows[3][4] = {{-p[1], p[0], -p[3], p[2]}, {-p[2], p[3], p[0], -p[1]}, {-p[3], -p[2], p[1], p[0]}};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 4; k++)
            E[i][k] = 2.0 * rows[i][k];
}

/* rolling (velocity level) .x, .y: r' + omega x K, K = (R / s) k,
   k = (a_x a_z, a_y a_z, -s^2), a = A u, s = |(a_x, a_y)|, omega = 2 E p'.
   a (the Jacobian) = dPsi/dqd: 1 on x' (y'), and omega x K = -K~ 2 E p'
   gives (2E_y K_z - 2E_z K_y) on p' (.x), (2E_z K_x - 2E_x K_z) (.y);
   nu = -Psi(qd = 0) = 0; gamma = -D Psi = -(omega x DK) since
   D omega = 2 E(p') p' = 0, with DK = (DR / s - R Ds / s^2) k + (R / s) Dk,
   Dk = (a_x' a_z + a_x a_z', a_y' a_z + a_y a_z', -2 (a_x a_x' + a_y a_y')). */
static void rolling_joint(const Call *c, const Plan *p)
{
    int r = p->row;
    const Attach *at = &p->j->a;
    if (c->nu)
        c->nu[r] = c->nu[r + 1] = 0.0;
    if (!c->psi && !c->jac && !c->gamma)
        return;
    V3 a = turned(c, at, p->frame[HA]);
    double s2 = a.v[0] * a.v[0] + a.v[1] * a.v[1], s = sqrt(s2);
    double radius = option_value(c, &p->opt), rs = radius / s;
    double k[3] = {a.v[0] * a.v[2], a.v[1] * a.v[2], -s2};
    double K[3] = {rs * k[0], rs * k[1], rs * k[2]};
    double E[3][4];
    twice_e(c->q + at->q + 3, E);
    double w[3] = {0, 0, 0};
    if (c->qd)
        for (int i = 0; i < 3; i++)
            for (int m = 0; m < 4; m++)
                w[i] += E[i][m] * c->qd[at->q + 3 + m];
    if (c->psi) {
        c->psi[r - c->g->nh] = c->qd[at->q] + w[1] * K[2] - w[2] * K[1];
        c->psi[r + 1 - c->g->nh] = c->qd[at->q + 1] + w[2] * K[0] - w[0] * K[2];
    }
    if (c->jac) {
        double *rx = jac_row(c, r), *ry = jac_row(c, r + 1);
        rx[at->q] += 1.0;
        ry[at->q + 1] += 1.0;
        for (int m = 0; m < 4; m++) {
            rx[at->q + 3 + m] += E[1][m] * K[2] - E[2][m] * K[1];
            ry[at->q + 3 + m] += E[2][m] * K[0] - E[0][m] * K[2];
        }
    }
    if (c->gamma) {
        double dl = p->opt.constant ? 0.0 : option_along(c, &p->opt, 1).d;
        double dsx = a.v[0] * a.d[0] + a.v[1] * a.d[1];    /* s Ds */
        double coef = dl / s - radius * dsx / (s2 * s);
        double dk[3] = {a.d[0] * a.v[2] + a.v[0] * a.d[2], a.d[1] * a.v[2] + a.v[1] * a.d[2], -2.0 * dsx};
        double dK[3];
        for (int i = 0; i < 3; i++)
            dK[i] = coef * k[i] + rs * dk[i];
        c->gamma[r] = -(w[1] * dK[2] - w[2] * dK[1]);
        c->gamma[r + 1] = -(w[2] * dK[0] - w[0] * dK[2]);
    }
}

/* driver angle(R) = theta (model.c records R and theta): the builder's
   branch-free row phi = c S - s C, c = cos theta, s = sin theta,
   S = gA^T fB, C = fA^T fB (two dot-1 of R's frames):
   Jacobian c S_q - s C_q - (s S + c C) theta_q;  nu = (s S + c C) theta_t;
   with w = D theta, gamma = -(D2(c S) - D2(s C)),
   D2(c S) = c D2S - 2 s w DS - (c w^2 + s D2theta) S,
   D2(s C) = s D2C + 2 c w DC + (c D2theta - s w^2) C. */
static void angle_driver(const Call *c, const Plan *p)
{
    int r = p->row;
    const Joint *j = p->of;
    if (!c->phi && !c->jac && !c->gamma && (!c->nu || p->opt.constant)) {
        if (c->nu)
            c->nu[r] = 0.0;
        return;     /* a nu-only call with theta(t) has A: generic.c's nu_rots */
    }
    double theta = option_value(c, &p->opt), sn, cs;
    mechc_sincos(theta, &sn, &cs);
    V3 fa = turned(c, &j->a, p->frame[FA]), ga = turned(c, &j->a, p->frame[GA]);
    V3 fb = turned(c, &j->b, p->frame[FB]);
    double S = dot3(ga.v, fb.v), C = dot3(fa.v, fb.v), k = sn * S + cs * C;
    if (c->phi)
        c->phi[r] = cs * S - sn * C;
    if (c->jac) {
        double *row = jac_row(c, r), w[3];
        jac_turned(c, row, &j->a, p->frame[GA], fb.v, cs);
        jac_turned(c, row, &j->a, p->frame[FA], fb.v, -sn);
        for (int i = 0; i < 3; i++)
            w[i] = cs * ga.v[i] - sn * fa.v[i];
        jac_turned(c, row, &j->b, p->frame[FB], w, 1.0);
        option_jac(c, &p->opt, -k, row);
    }
    if (c->nu)
        c->nu[r] = k * option_dt(c, &p->opt);
    if (c->gamma) {
        Jet th = option_along(c, &p->opt, 2);
        double w = th.d;
        double dS = dot3(ga.d, fb.v) + dot3(ga.v, fb.d), dC = dot3(fa.d, fb.v) + dot3(fa.v, fb.d);
        double ddS = dot3(ga.dd, fb.v) + 2.0 * dot3(ga.d, fb.d) + dot3(ga.v, fb.dd);
        double ddC = dot3(fa.dd, fb.v) + 2.0 * dot3(fa.d, fb.d) + dot3(fa.v, fb.dd);
        double cS = cs * ddS - 2.0 * sn * w * dS - (cs * w * w + sn * th.dd) * S;
        double sC = sn * ddC + 2.0 * cs * w * dC + (cs * th.dd - sn * w * w) * C;
        c->gamma[r] = -(cS - sC);
    }
}

/* driver slide(T) = E: hA^T (P_B - P_A) - E over T's frame, a dot-2 row;
   Jacobian - E_q, nu = E_t, gamma + D2E. */
static void slide_driver(const Call *c, const Plan *p)
{
    int r = p->row;
    const Joint *j = p->of;
    if (c->nu)
        c->nu[r] = option_dt(c, &p->opt);
    if (!c->phi && !c->jac && !c->gamma)
        return;
    V3 pa = placed(c, &j->a), pb = placed(c, &j->b);
    V3 d = minus(&pb, &pa);
    dot2(c, r, j, p->frame[HA], &d);
    if (c->phi)
        c->phi[r] -= option_value(c, &p->opt);
    if (c->jac)
        option_jac(c, &p->opt, -1.0, jac_row(c, r));
    if (c->gamma)
        c->gamma[r] += option_along(c, &p->opt, 2).dd;
}

GenericRows *generic_measure_rows(const Joint *driver, const Joint *of, char *need)
{
    if (driver->kind != JOINT_DRIVER || driver->velocity || driver->measures == 0)
        return NULL;
    if (of->a.has_p)
        need[of->a.q + 3] = NEED_ROT;
    if (of->b.has_p)
        need[of->b.q + 3] = NEED_ROT;
    return driver->measures > 0 ? angle_driver : slide_driver;
}

/* Dot-1, dot-2 and spherical over Euler parameters turn both sides' A(p);
   the body row .norm turns nothing. */
const Formula formula_S_SPHERICAL = {spherical_joint, TURN_P};
const Formula formula_S_UNIVERSAL = {universal_joint, TURN_P};
const Formula formula_S_REVOLUTE = {revolute_joint, TURN_P};
const Formula formula_S_CYLINDRICAL = {cylindrical_joint, TURN_P};
const Formula formula_S_TRANSLATIONAL = {translational_joint, TURN_P};
const Formula formula_S_WELD = {weld_joint, TURN_P};
const Formula formula_S_DISTANCE = {distance_joint, TURN_P};
const Formula formula_S_POINTPLANE = {pointplane_joint, TURN_P};
const Formula formula_S_PARALLEL = {parallel_joint, TURN_P};
const Formula formula_S_PERPENDICULAR = {perpendicular_joint, TURN_P};
const Formula formula_S_NORM = {norm_joint, 0};
const Formula formula_S_CONTACT = {contact_joint, TURN_P};
const Formula formula_S_ROLLING = {rolling_joint, TURN_P};
