/* dynamics.c - the mass matrix M(q) and the force vector Q(q, qd, t) as graph nodes, by symbolic differentiation.
 *
 * Every mass statement is a mass element: mass m at p(q), moment of inertia
 * J about it for the angle theta(q) (doc/dynamics.md). With T = 1/2 m |p_q qd|^2 +
 * 1/2 J (theta_q qd)^2, Lagrange's equations give
 *
 *   M += m p_q^T p_q + J theta_q^T theta_q
 *   Q += -m p_q^T (pdot_q qd) - J theta_q^T (thetadot_q qd)      velocity terms
 *   Q += m p_q^T g                                               gravity
 *
 * where pdot_q qd = D(D(p)), the total time derivative twice with qdd = 0:
 * the convective term gamma is made of (p never depends on t). Applied
 * forces enter by virtual work, Q += (d position / dq)^T force, each kind
 * by its add_KIND (generator/parse/forces.def). M is accumulated entry by entry over the coordinates each
 * element touches, so a body in body coordinates with its centre of mass
 * at its origin adds the constants m, m, J on the diagonal and nothing else.
 *
 * Node ids name the generated C's temporaries: every node is made in a
 * statement of its own (see joints.c), so the output does not depend on
 * the compiler that built mechc.
 */
#include "kinematics.h"

#include "../base/arena.h"
#include "../base/hashmap.h"
#include "../dag/support.h"
#include "diff.h"

#include <stdlib.h>
#include <string.h>

/* What the constants a mass adds are, named when one is out of range. */
#define DYN_WEIGHT "its weight m g"
#define DYN_INERTIA_AT_BODY "its moment of inertia about the body's reference point, J + m |com|^2"

/* Scratch of one build. */
typedef struct DynWork {
    Model *m;
    Dag *dag;
    Differ df;
    SupportScan scan;
    int *cols, *tmp;        /* nq each */
    char *seen;             /* nq */
    NodeId *velocity, *applied;     /* nq */
    U64Map where;           /* (row, col), row <= col -> index into entries */
    JacEntry *entries;      /* upper triangle, in the order first met */
    int n, cap;
} DynWork;

/* The coordinates any of the n expressions depends on, ascending, into w->cols. */
static int support_of(DynWork *w, const NodeId *e, int n)
{
    memset(w->seen, 0, (size_t)w->m->nq);
    for (int k = 0; k < n; k++) {
        int c = support_collect(&w->scan, w->dag, e[k], OP_VAR, w->tmp);
        for (int i = 0; i < c; i++)
            w->seen[w->tmp[i]] = 1;
    }
    int count = 0;
    for (int j = 0; j < w->m->nq; j++)
        if (w->seen[j])
            w->cols[count++] = j;
    return count;
}

/* M(i, j) += v for i <= j. */
static void add_mass(DynWork *w, int i, int j, NodeId v)
{
    if (dag_is_zero(w->dag, v))
        return;
    uint64_t key = (uint64_t)(uint32_t)i << 32 | (uint32_t)j;
    int32_t at;
    if (u64map_get(&w->where, key, &at)) {
        w->entries[at].value = dag_add(w->dag, w->entries[at].value, v);
        return;
    }
    if (w->n == w->cap) {
        w->cap = w->cap ? 2 * w->cap : 16;
        w->entries = xrealloc(w->entries, (size_t)w->cap, sizeof *w->entries);
    }
    w->entries[w->n] = (JacEntry){.row = i, .col = j, .value = v};
    u64map_put(&w->where, key, w->n++);
}

/* acc[j] += v */
static void accumulate(DynWork *w, NodeId *acc, int j, NodeId v)
{
    acc[j] = dag_add(w->dag, acc[j], v);
}

/* A mass's or force's constant as a node: the number, made as before
   design parameters could set it (a file without them gets the same
   nodes), or its expression of design parameters. */
static NodeId dyn_node(Dag *d, double value, NodeId node)
{
    return dag_is_const(d, node, NULL) ? dag_const(d, value) : node;
}

/* sign m g_c of an element: one named constant, or a product of nodes. */
static NodeId weight(DynWork *w, const MassElement *e, int c, double sign)
{
    Dag *d = w->dag;
    NodeId g = w->m->gravity_node[c];
    if (dag_is_const(d, e->m_node, NULL) && dag_is_const(d, g, NULL))
        return dag_const_named(d, sign * e->m * w->m->gravity[c], DYN_WEIGHT);
    NodeId mg = dag_mul(d, e->m_node, g);
    return sign < 0 ? dag_neg(d, mg) : mg;
}

/* J + m s.s of a planar body: one named constant, or nodes. */
static NodeId inertia_at_body(Dag *d, const MassElement *e)
{
    const NodeId parts[4] = {e->J_node, e->m_node, e->s_node[0], e->s_node[1]};
    bool constant = true;
    for (int i = 0; i < 4; i++)
        constant = constant && dag_is_const(d, parts[i], NULL);
    if (constant)
        return dag_const_named(d, e->J + e->m * (e->sx * e->sx + e->sy * e->sy),
                               DYN_INERTIA_AT_BODY);
    NodeId xx = dag_mul(d, e->s_node[0], e->s_node[0]);
    NodeId yy = dag_mul(d, e->s_node[1], e->s_node[1]);
    NodeId ss = dag_add(d, xx, yy);
    NodeId mss = dag_mul(d, e->m_node, ss);
    return dag_add(d, e->J_node, mss);
}

/* a * b + c * d, each product in a statement of its own */
static NodeId dot2(Dag *d, NodeId a, NodeId b, NodeId c, NodeId e)
{
    NodeId ab = dag_mul(d, a, b);
    NodeId ce = dag_mul(d, c, e);
    return dag_add(d, ab, ce);
}

/* A planar body's own mass, the formula worked out (doc/dynamics.md's with
   p = r + A(phi) s, u = A(phi) s, p_phi = B s = (-u_y, u_x), w = phi'):
   M(x, x) = M(y, y) = m, M(x, phi) = -m u_y, M(y, phi) = m u_x,
   M(phi, phi) = J + m s.s; velocity terms m u w^2 on (x, y), none on phi
   (B s is normal to u); weight m g on (x, y), m (B s).g on phi. The
   symbolic route gives the same numbers with sin^2 + cos^2 left unfolded. */
static void add_body(DynWork *w, const MassElement *e)
{
    Dag *d = w->dag;
    int x = e->body, y = x + 1, phi = x + 2;
    NodeId c = dag_call(d, OP_COS, e->theta, DAG_NONE);     /* as joints.c's rotate */
    NodeId sn = dag_call(d, OP_SIN, e->theta, DAG_NONE);
    NodeId vx = dyn_node(d, e->sx, e->s_node[0]);
    NodeId vy = dyn_node(d, e->sy, e->s_node[1]);
    NodeId sy = dag_mul(d, sn, vy), cx = dag_mul(d, c, vx);
    NodeId ux = dag_sub(d, cx, sy);
    NodeId cy = dag_mul(d, c, vy), sx = dag_mul(d, sn, vx);
    NodeId uy = dag_add(d, sx, cy);
    NodeId m = dyn_node(d, e->m, e->m_node);
    add_mass(w, x, x, m);
    add_mass(w, y, y, m);
    NodeId muy = dag_mul(d, m, uy);
    add_mass(w, x, phi, dag_neg(d, muy));
    add_mass(w, y, phi, dag_mul(d, m, ux));
    add_mass(w, phi, phi, inertia_at_body(d, e));
    NodeId rate = dag_vard(d, phi);
    NodeId w2 = dag_mul(d, rate, rate);
    NodeId mw2 = dag_mul(d, m, w2);
    accumulate(w, w->velocity, x, dag_mul(d, mw2, ux));
    accumulate(w, w->velocity, y, dag_mul(d, mw2, uy));
    accumulate(w, w->applied, x, weight(w, e, 0, 1.0));
    accumulate(w, w->applied, y, weight(w, e, 1, 1.0));
    NodeId mgx = weight(w, e, 0, -1.0);
    NodeId mgy = weight(w, e, 1, 1.0);
    accumulate(w, w->applied, phi, dot2(d, uy, mgx, ux, mgy));
}

/* ---- spatial: Euler-parameter bodies ---- */

/* G(e) and E(e) of the Euler parameters e = (e0, e1, e2, e3) (Nikravesh,
   Computer-Aided Analysis of Mechanical Systems, ch. 6 and 11): body-axes
   and global angular velocity w' = 2 G ed, w = 2 E ed. Entry (i, k) is
   sign * e[index]. */
typedef struct EulerEntry {
    signed char sign, index;
} EulerEntry;

static const EulerEntry euler_G[3][4] = {
    {{-1, 1}, {1, 0}, {1, 3}, {-1, 2}},
    {{-1, 2}, {-1, 3}, {1, 0}, {1, 1}},
    {{-1, 3}, {1, 2}, {-1, 1}, {1, 0}},
};
static const EulerEntry euler_E[3][4] = {
    {{-1, 1}, {1, 0}, {-1, 3}, {1, 2}},
    {{-1, 2}, {1, 3}, {1, 0}, {-1, 1}},
    {{-1, 3}, {-1, 2}, {1, 1}, {1, 0}},
};

/* The 3 x 4 matrix table(v) over four nodes v (the parameters or their rates). */
static void euler_matrix(Dag *d, const EulerEntry table[3][4], const NodeId v[4], NodeId out[3][4])
{
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 4; k++) {
            NodeId x = v[table[i][k].index];
            out[i][k] = table[i][k].sign < 0 ? dag_neg(d, x) : x;
        }
}

/* The index of J' (i, j) in (xx, yy, zz, xy, xz, yz). */
static int tensor_index(int i, int j)
{
    static const int at[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
    return at[i][j];
}

/* sum_j c[j] v[j] over three coefficients (numbers c, nodes cn) and
   nodes v; constant zeros left out */
static NodeId weighted3(Dag *d, const double c[3], const NodeId cn[3], NodeId const v[3])
{
    NodeId sum = DAG_ZERO;
    for (int j = 0; j < 3; j++) {
        if (dag_is_const(d, cn[j], NULL) && c[j] == 0)
            continue;
        NodeId term = dag_mul(d, dyn_node(d, c[j], cn[j]), v[j]);
        sum = dag_add(d, sum, term);
    }
    return sum;
}

/* A spatial body's rotation: T = 1/2 w'^T J' w', w' = 2 G ed, linear in
   ed with G linear in e. Lagrange's equations with G(a) b = -G(b) a (so
   Gd ed = 0 and d(G ed)/de = -Gd, Gd = G(ed)) give
     M_ee += 4 G^T J' G,   Q_e += -4 Gd^T J' w' = 8 Gd^T J' Gd e
   (Nikravesh eq. 11.27's velocity term). G e = 0, so M has e in its null
   space; the row e.e - 1 makes the augmented matrix regular. */
static void add_rotation(DynWork *w, const MassElement *e)
{
    Dag *d = w->dag;
    NodeId p[4], pd[4], G[3][4], Gd[3][4];
    for (int k = 0; k < 4; k++) {
        p[k] = dag_var(d, e->euler + k);
        pd[k] = dag_vard(d, e->euler + k);
    }
    euler_matrix(d, euler_G, p, G);
    euler_matrix(d, euler_G, pd, Gd);
    double J[3][3];
    NodeId Jn[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            J[i][j] = e->inertia[tensor_index(i, j)];
            Jn[i][j] = e->inertia_node[tensor_index(i, j)];
        }
    for (int b = 0; b < 4 && !d->overflow; b++) {
        NodeId col[3] = {G[0][b], G[1][b], G[2][b]}, jg[3];
        for (int i = 0; i < 3; i++)
            jg[i] = weighted3(d, J[i], Jn[i], col);     /* (J' G)(i, b) */
        for (int a = 0; a <= b; a++) {
            NodeId ga[3] = {G[0][a], G[1][a], G[2][a]};
            NodeId sum = DAG_ZERO;
            for (int i = 0; i < 3; i++) {
                NodeId term = dag_mul(d, ga[i], jg[i]);
                sum = dag_add(d, sum, term);
            }
            add_mass(w, e->euler + a, e->euler + b, dag_mul(d, dag_const(d, 4.0), sum));
        }
    }
    NodeId omega[3], jw[3];
    for (int i = 0; i < 3; i++) {
        NodeId sum = DAG_ZERO;
        for (int k = 0; k < 4; k++) {
            NodeId term = dag_mul(d, G[i][k], pd[k]);
            sum = dag_add(d, sum, term);
        }
        omega[i] = dag_mul(d, dag_const(d, 2.0), sum);
    }
    for (int i = 0; i < 3; i++)
        jw[i] = weighted3(d, J[i], Jn[i], omega);
    for (int a = 0; a < 4 && !d->overflow; a++) {
        NodeId sum = DAG_ZERO;
        for (int i = 0; i < 3; i++) {
            NodeId term = dag_mul(d, Gd[i][a], jw[i]);
            sum = dag_add(d, sum, term);
        }
        accumulate(w, w->velocity, e->euler + a, dag_mul(d, dag_const(d, -4.0), sum));
    }
}

/* A spatial mass element: m at p = (px, py, pz) as add_element's
   translation (T = 1/2 m |p_q qd|^2, any p(q)), then a body's rotation. */
static void add_spatial_element(DynWork *w, const MassElement *e)
{
    Dag *d = w->dag;
    NodeId parts[3] = {e->px, e->py, e->pz};
    int n = support_of(w, parts, 3);
    NodeId *dp = xmalloc((size_t)(3 * n + 1) * sizeof *dp);
    for (int k = 0; k < n; k++)
        for (int c = 0; c < 3; c++)
            dp[3 * k + c] = diff_by_q(&w->df, parts[c], w->cols[k]);
    NodeId m = dyn_node(d, e->m, e->m_node);
    for (int a = 0; a < n && !d->overflow; a++)
        for (int b = a; b < n; b++) {
            NodeId pp = dot2(d, dp[3 * a], dp[3 * b], dp[3 * a + 1], dp[3 * b + 1]);
            NodeId zz = dag_mul(d, dp[3 * a + 2], dp[3 * b + 2]);
            NodeId sum = dag_add(d, pp, zz);
            add_mass(w, w->cols[a], w->cols[b], dag_mul(d, m, sum));
        }
    NodeId acc[3];
    for (int c = 0; c < 3; c++) {
        NodeId v = diff_total(&w->df, parts[c]);
        acc[c] = diff_total(&w->df, v);
    }
    NodeId g[3];
    for (int c = 0; c < 3; c++)
        g[c] = weight(w, e, c, 1.0);
    for (int k = 0; k < n && !d->overflow; k++) {
        int j = w->cols[k];
        const NodeId *u = dp + 3 * k;
        NodeId pa = dot2(d, u[0], acc[0], u[1], acc[1]);
        NodeId za = dag_mul(d, u[2], acc[2]);
        NodeId sum = dag_add(d, pa, za);
        w->velocity[j] = dag_sub(d, w->velocity[j], dag_mul(d, m, sum));
        NodeId pg = dot2(d, u[0], g[0], u[1], g[1]);
        NodeId zg = dag_mul(d, u[2], g[2]);
        accumulate(w, w->applied, j, dag_add(d, pg, zg));
    }
    free(dp);
    if (e->euler >= 0)
        add_rotation(w, e);
}

/* A torque tau in global axes on a spatial body: its virtual work
   tau . w, w = 2 E ed, so Q_e += 2 E^T tau. */
static void add_BODY_TORQUE(DynWork *w, const AppliedForce *f)
{
    Dag *d = w->dag;
    NodeId p[4], E[3][4], tau[3] = {f->fx, f->fy, f->fz};
    for (int k = 0; k < 4; k++)
        p[k] = dag_var(d, f->coord + k);
    euler_matrix(d, euler_E, p, E);
    for (int a = 0; a < 4; a++) {
        NodeId sum = DAG_ZERO;
        for (int i = 0; i < 3; i++) {
            NodeId term = dag_mul(d, E[i][a], tau[i]);
            sum = dag_add(d, sum, term);
        }
        accumulate(w, w->applied, f->coord + a, dag_mul(d, dag_const(d, 2.0), sum));
    }
}

/* One mass element's share of M, its velocity terms and its weight. */
static void add_element(DynWork *w, const MassElement *e)
{
    Dag *d = w->dag;
    if (e->spatial) {
        add_spatial_element(w, e);
        return;
    }
    if (e->body >= 0) {
        add_body(w, e);
        return;
    }
    NodeId parts[3] = {e->px, e->py, e->theta};
    int n = support_of(w, parts, 3);
    NodeId *dx = xmalloc((size_t)(3 * n + 1) * sizeof *dx), *dy = dx + n, *dth = dy + n;
    for (int k = 0; k < n; k++) {
        dx[k] = diff_by_q(&w->df, e->px, w->cols[k]);
        dy[k] = diff_by_q(&w->df, e->py, w->cols[k]);
        dth[k] = diff_by_q(&w->df, e->theta, w->cols[k]);
    }
    NodeId m = dyn_node(d, e->m, e->m_node);
    NodeId J = dyn_node(d, e->J, e->J_node);
    for (int a = 0; a < n && !d->overflow; a++)
        for (int b = a; b < n; b++) {
            NodeId pp = dot2(d, dx[a], dx[b], dy[a], dy[b]);
            NodeId mpp = dag_mul(d, m, pp);
            NodeId tt = dag_mul(d, dth[a], dth[b]);
            NodeId jtt = dag_mul(d, J, tt);
            add_mass(w, w->cols[a], w->cols[b], dag_add(d, mpp, jtt));
        }
    /* pdot_q qd = D(D(p)) (p has no t and no qd) */
    NodeId vx = diff_total(&w->df, e->px);
    NodeId ax = diff_total(&w->df, vx);
    NodeId vy = diff_total(&w->df, e->py);
    NodeId ay = diff_total(&w->df, vy);
    NodeId vth = diff_total(&w->df, e->theta);
    NodeId ath = diff_total(&w->df, vth);
    NodeId gx = weight(w, e, 0, 1.0);
    NodeId gy = weight(w, e, 1, 1.0);
    for (int k = 0; k < n && !d->overflow; k++) {
        int j = w->cols[k];
        NodeId pa = dot2(d, dx[k], ax, dy[k], ay);
        NodeId mpa = dag_mul(d, m, pa);
        NodeId ta = dag_mul(d, dth[k], ath);
        NodeId jta = dag_mul(d, J, ta);
        NodeId sum = dag_add(d, mpa, jta);
        w->velocity[j] = dag_sub(d, w->velocity[j], sum);
        accumulate(w, w->applied, j, dot2(d, dx[k], gx, dy[k], gy));
    }
    free(dx);
}

/* Q += coef * d(e)/dq over e's coordinates (coef: a force along e). */
static void add_along(DynWork *w, NodeId e, NodeId coef)
{
    int n = support_of(w, &e, 1);
    for (int k = 0; k < n && !w->dag->overflow; k++) {
        NodeId de = diff_by_q(&w->df, e, w->cols[k]);
        accumulate(w, w->applied, w->cols[k], dag_mul(w->dag, de, coef));
    }
}

/* -(k (s - s0) + c D(s) + act): a spring's pull along its length or angle s */
static NodeId spring_force(DynWork *w, const AppliedForce *f, NodeId s)
{
    Dag *d = w->dag;
    NodeId stretch = dag_sub(d, s, dyn_node(d, f->free, f->free_node));
    NodeId ks = dag_mul(d, dyn_node(d, f->k, f->k_node), stretch);
    NodeId rate = diff_total(&w->df, s);
    NodeId cr = dag_mul(d, dyn_node(d, f->c, f->c_node), rate);
    NodeId sum = dag_add(d, ks, cr);
    NodeId total = dag_add(d, sum, f->fx);
    return dag_neg(d, total);
}

/* force: Q += p_q^T (fx, fy, fz) */
static void add_POINT(DynWork *w, const AppliedForce *f)
{
    add_along(w, f->ax, f->fx);
    add_along(w, f->ay, f->fy);
    if (w->m->spatial)
        add_along(w, f->az, f->fz);
}

/* torque: Q += theta_q^T tau */
static void add_TORQUE(DynWork *w, const AppliedForce *f)
{
    add_along(w, f->ax, f->fx);
}

/* spring: l = |B - A|, Q += -(k (l - L0) + c ldot + F) l_q */
static void add_SPRING(DynWork *w, const AppliedForce *f)
{
    Dag *d = w->dag;
    NodeId ex = dag_sub(d, f->bx, f->ax);
    NodeId ey = dag_sub(d, f->by, f->ay);
    NodeId l2 = dot2(d, ex, ex, ey, ey);
    if (w->m->spatial) {
        NodeId ez = dag_sub(d, f->bz, f->az);
        l2 = dag_add(d, l2, dag_mul(d, ez, ez));
    }
    NodeId l = dag_call(d, OP_SQRT, l2, DAG_NONE);
    add_along(w, l, spring_force(w, f, l));
}

/* rspring: a = theta_B - theta_A, Q += -(k (a - a0) + c adot + T) a_q */
static void add_RSPRING(DynWork *w, const AppliedForce *f)
{
    NodeId a = dag_sub(w->dag, f->bx, f->ax);
    add_along(w, a, spring_force(w, f, a));
}

/* gforce: Q[coord] += fx */
static void add_GENERAL(DynWork *w, const AppliedForce *f)
{
    accumulate(w, w->applied, f->coord, f->fx);
}

typedef void ForceMaths(DynWork *w, const AppliedForce *f);

/* Every force kind's share of Q, by kind: a row of forces.def without its
   add_KIND is an undeclared identifier, so the build names it. */
static ForceMaths *const force_maths[FORCE_KIND_COUNT] = {
#define X(e, ...) [FORCE_##e] = add_##e,
#include "../parse/forces.def"
#undef X
};

static int compare_entries(const void *x, const void *y)
{
    const JacEntry *a = x, *b = y;
    if (a->row != b->row)
        return (a->row > b->row) - (a->row < b->row);
    return (a->col > b->col) - (a->col < b->col);
}

/* The upper triangle mirrored into both triangles, row-major, in the arena. */
static void finish_mass(DynWork *w, Dynamics *dyn)
{
    int n = 0;
    for (int k = 0; k < w->n; k++)
        n += w->entries[k].row == w->entries[k].col ? 1 : 2;
    dyn->mass = arena_alloc_array(&w->m->arena, (size_t)n + 1, sizeof *dyn->mass);
    for (int k = 0; k < w->n; k++) {
        JacEntry e = w->entries[k];
        dyn->mass[dyn->nnz++] = e;
        if (e.row != e.col)
            dyn->mass[dyn->nnz++] = (JacEntry){.row = e.col, .col = e.row, .value = e.value};
    }
    qsort(dyn->mass, (size_t)dyn->nnz, sizeof *dyn->mass, compare_entries);
}

bool dynamics_build(Model *m, Dynamics *dyn, Diag *diag)
{
    memset(dyn, 0, sizeof *dyn);
    dyn->present = true;
    DynWork w = {.m = m, .dag = &m->dag};
    size_t nq = (size_t)m->nq;
    differ_init(&w.df, w.dag, m->nq);
    support_init(&w.scan);
    u64map_init(&w.where);
    w.cols = xmalloc(nq * sizeof *w.cols);
    w.tmp = xmalloc(nq * sizeof *w.tmp);
    w.seen = xmalloc(nq);
    dyn->force = arena_alloc_array(&m->arena, nq, sizeof *dyn->force);
    dyn->velocity = arena_alloc_array(&m->arena, nq, sizeof *dyn->velocity);
    w.velocity = dyn->velocity;
    w.applied = xcalloc(nq, sizeof *w.applied);     /* DAG_ZERO is 0 */
    for (int i = 0; i < m->nmasses && !w.dag->overflow; i++) {
        w.dag->where = m->masses[i].pos.offset;
        add_element(&w, &m->masses[i]);
    }
    for (int i = 0; i < m->nforces && !w.dag->overflow; i++) {
        w.dag->where = m->forces[i].pos.offset;
        force_maths[m->forces[i].kind](&w, &m->forces[i]);
    }
    for (int j = 0; j < m->nq; j++)
        dyn->force[j] = dag_add(w.dag, dyn->velocity[j], w.applied[j]);
    bool ok = dag_check_limit(w.dag, diag);
    w.dag->where = -1;
    if (ok)
        finish_mass(&w, dyn);
    free(w.entries);
    free(w.applied);
    free(w.cols);
    free(w.tmp);
    free(w.seen);
    u64map_free(&w.where);
    support_free(&w.scan);
    differ_free(&w.df);
    return ok;
}
