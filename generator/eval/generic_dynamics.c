/* generic_dynamics.c - the generic evaluator's M and Q: the mass elements and forces by forward-mode derivatives, no symbolic ones.
 *
 * Each mass element and each force is one program of its expressions
 * (interp.h): position, angle, components. Their derivatives come from
 * jets while the program runs, not from generator/diff/, so M and Q here
 * check the generated kernels:
 *
 *   mass element:  p_q by one first-order pass per coordinate it reads;
 *                  pdot_q qd = D(D(p)), a second-order jet along (qd, 0, 0);
 *                  M += m p_q^T p_q + J theta_q^T theta_q,
 *                  Q += -m p_q^T D(D(p)) - J theta_q^T D(D(theta)) + m p_q^T g
 *   point force:   Q += p_q^T F;  torque: Q += theta_q^T tau
 *   spring:        l = |P_B - P_A|, l_q and ldot from the points' jets,
 *                  Q -= (k (l - L0) + c ldot + F) l_q
 *   rspring:       a = theta_B - theta_A, Q -= (k (a - a0) + c adot + T) a_q
 *   gforce:        Q[coord] += value
 *
 * In a spatial file the elements' points have z (the third root is pz,
 * no angle), and a spatial body's rotation, T = 1/2 w'^T J' w' with
 * w' = W ed, W = 2 G(e), enters by Lagrange's equations written out for
 * a velocity linear in ed, without the Euler-parameter identities the
 * generated code's closed form uses (generator/diff/dynamics.c):
 *   M_ee += W^T J' W,
 *   Q_e  += -(d/dt W)^T J' w' - W^T J' (d/dt W) ed + (d(W ed)/de)^T J' w',
 * so the two agree only if those identities hold: check compares them.
 * A body torque tau (global axes): Q_e += 2 E^T tau.
 *
 * Masses, inertias, gravity and spring constants of design parameters are
 * the values of their nodes at the model's design, evaluated at each call
 * into copies of the elements and forces (design_refresh).
 */
#include "generic_impl.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One program per mass element (px, py, theta; spatial px, py, pz) and
   per force (its expressions: ax ay bx by fx fy, then az bz fz). */
struct GenericDyn {
    const Model *m;
    Tape *mass_tapes, *force_tapes;
    Jet *jreg;
    double *vreg;
    double *dp;         /* 3 nq: one element's (px, py, theta)_q */
    /* mass_nz: per mass element, where each of its (qcols[a], qcols[b])
       products lands in the pattern (nqcols^2 slots, then 16 for the
       Euler block of a spatial body), slot_at[i] its first; -1: outside
       the pattern. NULL until generic_mass_pattern. */
    int *slot, *slot_at;
    int nnz;
    /* The elements, forces and gravity the formulas read: the model's,
       with their constants at the design now when the file has design
       parameters (consts: their nodes, NCONST per element, then gravity,
       then per force) */
    MassElement *masses;
    AppliedForce *forces;
    double gravity[3];
    NodeValues consts;
    bool designed;
};

enum { MASS_CONSTS = 8, FORCE_CONSTS = 3 };

enum { FORCE_ROOTS = 9 };

/* planar: the first six; spatial: az, bz, fz after them */
static void force_roots(const AppliedForce *f, NodeId roots[FORCE_ROOTS])
{
    NodeId r[FORCE_ROOTS] = {f->ax, f->ay, f->bx, f->by, f->fx, f->fy, f->az, f->bz, f->fz};
    memcpy(roots, r, sizeof r);
}

/* ---- spatial rotation ---- */

/* The cross-product matrix of v: tilde(v) x = v x x. */
static void tilde(const double v[3], double t[3][3])
{
    double m[3][3] = {{0, -v[2], v[1]}, {v[2], 0, -v[0]}, {-v[1], v[0], 0}};
    memcpy(t, m, sizeof m);
}

/* G(e) = [-e_v, -tilde(e_v) + e0 I] (body axes) or E(e) = [-e_v, tilde(e_v) + e0 I]
   (global axes), 3 x 4, e = (e0, e_v). */
static void euler_matrix(const double e[4], bool global, double out[3][4])
{
    double t[3][3];
    tilde(e + 1, t);
    for (int i = 0; i < 3; i++) {
        out[i][0] = -e[1 + i];
        for (int j = 0; j < 3; j++)
            out[i][1 + j] = (global ? t[i][j] : -t[i][j]) + (i == j ? e[0] : 0.0);
    }
}

static double tensor_at(const double t[6], int i, int j)
{
    static const int at[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
    return t[at[i][j]];
}

/* W^T J' W, W = 2 G(e): the Euler block M_ee of one body. */
static void rotation_mass(const MassElement *e, const double *q, double blk[4][4])
{
    double W[3][4];
    euler_matrix(q + e->euler, false, W);
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++) {
            double sum = 0;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    sum += 4 * W[i][a] * tensor_at(e->inertia, i, j) * W[j][b];
            blk[a][b] = sum;
        }
}

/* Q_e += -Wd^T J' w' - W^T J' Wd ed + (d(W ed)/de)^T J' w', Wd = 2 G(ed):
   Lagrange's equations of T = 1/2 (W ed)^T J' (W ed) with W linear in e. */
static void add_rotation_velocity(const MassElement *e, const double *q, const double *qd, double *Q)
{
    const double *p = q + e->euler, *pd = qd + e->euler;
    double G[3][4], Gd[3][4], w[3] = {0, 0, 0}, wd[3] = {0, 0, 0}, jw[3], jwd[3];
    euler_matrix(p, false, G);
    euler_matrix(pd, false, Gd);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 4; k++) {
            w[i] += 2 * G[i][k] * pd[k];    /* w' */
            wd[i] += 2 * Gd[i][k] * pd[k];  /* Wd ed */
        }
    for (int i = 0; i < 3; i++) {
        jw[i] = jwd[i] = 0;
        for (int j = 0; j < 3; j++) {
            jw[i] += tensor_at(e->inertia, i, j) * w[j];
            jwd[i] += tensor_at(e->inertia, i, j) * wd[j];
        }
    }
    for (int a = 0; a < 4; a++) {
        double unit[4] = {0, 0, 0, 0}, Ga[3][4], dw[3] = {0, 0, 0};
        unit[a] = 1;
        euler_matrix(unit, false, Ga);      /* d(W ed)/de_a = 2 G(unit_a) ed */
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 4; k++)
                dw[i] += 2 * Ga[i][k] * pd[k];
        double sum = 0;
        for (int i = 0; i < 3; i++)
            sum += -2 * Gd[i][a] * jw[i] - 2 * G[i][a] * jwd[i] + dw[i] * jw[i];
        Q[e->euler + a] += sum;
    }
}

/* The nodes of every element's m, J and tensor, gravity, and every
   force's k, c and free length: design_refresh's roots, in its order. */
static void design_open(GenericDyn *d)
{
    const Model *m = d->m;
    size_t n = (size_t)m->nmasses * MASS_CONSTS + 3 + (size_t)m->nforces * FORCE_CONSTS, k = 0;
    NodeId *roots = xmalloc(n * sizeof *roots);
    for (int i = 0; i < m->nmasses; i++) {
        const MassElement *e = &m->masses[i];
        roots[k++] = e->m_node;
        roots[k++] = e->J_node;
        for (int j = 0; j < 6; j++)
            roots[k++] = e->inertia_node[j];
    }
    for (int c = 0; c < 3; c++)
        roots[k++] = m->gravity_node[c];
    for (int i = 0; i < m->nforces; i++) {
        const AppliedForce *f = &m->forces[i];
        roots[k++] = f->k_node;
        roots[k++] = f->c_node;
        roots[k++] = f->free_node;
    }
    node_values_init(&d->consts, &m->dag, roots, (int)n);
    free(roots);
    d->designed = true;
}

/* The constants at the model's design now (model_set_design's). */
static void design_refresh(GenericDyn *d)
{
    if (!d->designed)
        return;
    const Model *m = d->m;
    node_values_run(&d->consts, NULL, NULL, 0.0);
    int k = 0;
    for (int i = 0; i < m->nmasses; i++) {
        MassElement *e = &d->masses[i];
        e->m = node_values_get(&d->consts, k++);
        e->J = node_values_get(&d->consts, k++);
        for (int j = 0; j < 6; j++)
            e->inertia[j] = node_values_get(&d->consts, k++);
    }
    for (int c = 0; c < 3; c++)
        d->gravity[c] = node_values_get(&d->consts, k++);
    for (int i = 0; i < m->nforces; i++) {
        AppliedForce *f = &d->forces[i];
        f->k = node_values_get(&d->consts, k++);
        f->c = node_values_get(&d->consts, k++);
        f->free = node_values_get(&d->consts, k++);
    }
}

GenericDyn *generic_dynamics_open(const Model *m)
{
    GenericDyn *d = xcalloc(1, sizeof *d);
    d->m = m;
    d->masses = xcalloc((size_t)m->nmasses + 1, sizeof *d->masses);
    d->forces = xcalloc((size_t)m->nforces + 1, sizeof *d->forces);
    if (m->nmasses > 0)
        memcpy(d->masses, m->masses, (size_t)m->nmasses * sizeof *d->masses);
    if (m->nforces > 0)
        memcpy(d->forces, m->forces, (size_t)m->nforces * sizeof *d->forces);
    memcpy(d->gravity, m->gravity, sizeof d->gravity);
    if (m->np > 0)
        design_open(d);
    d->mass_tapes = xcalloc((size_t)m->nmasses + 1, sizeof *d->mass_tapes);
    d->force_tapes = xcalloc((size_t)m->nforces + 1, sizeof *d->force_tapes);
    CompileScratch cs;
    compile_scratch_init(&cs, &m->dag);
    int regs = 1;
    for (int i = 0; i < m->nmasses; i++) {
        const MassElement *e = &m->masses[i];
        NodeId roots[3] = {e->px, e->py, e->spatial ? e->pz : e->theta};
        tape_compile_roots(&d->mass_tapes[i], &m->dag, roots, 3, &cs);
        regs = d->mass_tapes[i].n > regs ? d->mass_tapes[i].n : regs;
    }
    for (int i = 0; i < m->nforces; i++) {
        NodeId roots[FORCE_ROOTS];
        force_roots(&m->forces[i], roots);
        tape_compile_roots(&d->force_tapes[i], &m->dag, roots, FORCE_ROOTS, &cs);
        regs = d->force_tapes[i].n > regs ? d->force_tapes[i].n : regs;
    }
    compile_scratch_free(&cs);
    d->jreg = xcalloc((size_t)regs, sizeof *d->jreg);
    d->vreg = xcalloc((size_t)regs, sizeof *d->vreg);
    d->dp = xcalloc(3 * (size_t)m->nq + 1, sizeof *d->dp);
    return d;
}

void generic_dynamics_free(GenericDyn *d)
{
    if (!d)
        return;
    for (int i = 0; i < d->m->nmasses; i++)
        tape_free(&d->mass_tapes[i]);
    for (int i = 0; i < d->m->nforces; i++)
        tape_free(&d->force_tapes[i]);
    free(d->mass_tapes);
    free(d->force_tapes);
    free(d->jreg);
    free(d->vreg);
    free(d->dp);
    free(d->slot);
    free(d->slot_at);
    free(d->masses);
    free(d->forces);
    if (d->designed)
        node_values_free(&d->consts);
    free(d);
}

/* The jet of root k after a tape_jet pass. */
static Jet root_jet(const GenericDyn *d, const Tape *p, int k)
{
    return d->jreg[p->out[k]];
}

/* d(roots)/dq_j for every coordinate j the program reads: dp[3 k + r] for
   the k-th of p->qcols (the first nr roots). */
static void root_gradients(GenericDyn *d, const Tape *p, const double *q, const double *qd,
                           double t, int nr, double *dp)
{
    for (int k = 0; k < p->nqcols; k++) {
        Seed s = {.q = q, .qd = qd, .t = t, .col_q = p->qcols[k], .col_qd = -1};
        tape_jet(p, &s, 1, d->jreg);
        for (int r = 0; r < nr; r++)
            dp[3 * k + r] = root_jet(d, p, r).d;
    }
}

/* M's contributions, dense (slot NULL: M nq*nq row-major) or into the
   pattern's slots (vals, generic_mass_pattern's). */
static void add_mass(GenericDyn *d, const double *q, const int *slot, double *out)
{
    const Model *m = d->m;
    size_t nq = (size_t)m->nq;
    for (int i = 0; i < m->nmasses; i++) {
        const MassElement *e = &d->masses[i];
        const Tape *p = &d->mass_tapes[i];
        const int *at = slot ? slot + d->slot_at[i] : NULL;
        int n = p->nqcols;
        root_gradients(d, p, q, NULL, 0.0, 3, d->dp);
        double mz = e->spatial ? e->m : e->J;   /* the third root: pz, or theta */
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++) {
                const double *u = d->dp + 3 * a, *v = d->dp + 3 * b;
                long k = at ? at[a * n + b] : (long)((size_t)p->qcols[a] * nq + (size_t)p->qcols[b]);
                if (k >= 0)
                    out[k] += e->m * (u[0] * v[0] + u[1] * v[1]) + mz * u[2] * v[2];
            }
        if (e->euler < 0)
            continue;
        double blk[4][4];
        rotation_mass(e, q, blk);
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++) {
                long k = at ? at[n * n + 4 * a + b]
                            : (long)((size_t)(e->euler + a) * nq + (size_t)(e->euler + b));
                if (k >= 0)
                    out[k] += blk[a][b];
            }
    }
}

void generic_mass(Generic *g, const double *q, double *M)
{
    size_t nq = (size_t)g->dyn->m->nq;
    memset(M, 0, nq * nq * sizeof *M);
    design_refresh(g->dyn);
    add_mass(g->dyn, q, NULL, M);
}

/* The index of (r, c) in a row-major pattern, -1 when absent. */
static int pattern_find(const int *row, const int *col, int nnz, int r, int c)
{
    int lo = 0, hi = nnz - 1;
    while (lo <= hi) {
        int mid = lo + (hi - lo) / 2;
        int cmp = row[mid] != r ? (row[mid] > r) - (row[mid] < r) : (col[mid] > c) - (col[mid] < c);
        if (cmp == 0)
            return mid;
        if (cmp < 0)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

void generic_mass_pattern(Generic *g, const int *row, const int *col, int nnz)
{
    GenericDyn *d = g->dyn;
    const Model *m = d->m;
    free(d->slot);
    free(d->slot_at);
    d->slot_at = xcalloc((size_t)m->nmasses + 1, sizeof *d->slot_at);
    size_t total = 0;
    for (int i = 0; i < m->nmasses; i++) {
        size_t n = (size_t)d->mass_tapes[i].nqcols;
        d->slot_at[i] = (int)total;
        total += n * n + (m->masses[i].euler >= 0 ? 16 : 0);
    }
    d->slot = xcalloc(total + 1, sizeof *d->slot);
    for (int i = 0; i < m->nmasses; i++) {
        const Tape *p = &d->mass_tapes[i];
        const MassElement *e = &m->masses[i];
        int *at = d->slot + d->slot_at[i], n = p->nqcols;
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++)
                at[a * n + b] = pattern_find(row, col, nnz, p->qcols[a], p->qcols[b]);
        for (int k = 0; e->euler >= 0 && k < 16; k++)
            at[n * n + k] = pattern_find(row, col, nnz, e->euler + k / 4, e->euler + k % 4);
    }
    d->nnz = nnz;
}

void generic_mass_nz(Generic *g, const double *q, double *vals)
{
    GenericDyn *d = g->dyn;
    memset(vals, 0, (size_t)d->nnz * sizeof *vals);
    design_refresh(d);
    add_mass(d, q, d->slot, vals);
}

/* Q's velocity terms (with_gravity: and the weights) of every mass element. */
static void add_inertia(GenericDyn *d, const double *q, const double *qd, bool with_gravity,
                        double *Q)
{
    const Model *m = d->m;
    for (int i = 0; i < m->nmasses; i++) {
        const MassElement *e = &d->masses[i];
        const Tape *p = &d->mass_tapes[i];
        root_gradients(d, p, q, NULL, 0.0, 3, d->dp);
        Seed s = {.q = q, .dq = qd, .col_q = -1, .col_qd = -1};
        tape_jet(p, &s, 2, d->jreg);
        double ax = root_jet(d, p, 0).dd, ay = root_jet(d, p, 1).dd, ath = root_jet(d, p, 2).dd;
        double gx = with_gravity ? d->gravity[0] : 0.0, gy = with_gravity ? d->gravity[1] : 0.0;
        double gz = with_gravity ? d->gravity[2] : 0.0;
        for (int k = 0; k < p->nqcols; k++) {
            const double *u = d->dp + 3 * k;
            if (e->spatial)     /* the third root is pz */
                Q[p->qcols[k]] += -e->m * (u[0] * ax + u[1] * ay + u[2] * ath)
                                  + e->m * (u[0] * gx + u[1] * gy + u[2] * gz);
            else
                Q[p->qcols[k]] += -e->m * (u[0] * ax + u[1] * ay) - e->J * u[2] * ath
                                  + e->m * (u[0] * gx + u[1] * gy);
        }
        if (e->euler >= 0)
            add_rotation_velocity(e, q, qd, Q);
    }
}

/* Q += coef * (root a - root b)_q over the program's coordinates (b < 0: none). */
static void add_gradient(GenericDyn *d, const Tape *p, const double *q, const double *qd, double t,
                         int a, int b, double coef, double *Q)
{
    for (int k = 0; k < p->nqcols; k++) {
        Seed s = {.q = q, .qd = qd, .t = t, .col_q = p->qcols[k], .col_qd = -1};
        tape_jet(p, &s, 1, d->jreg);
        double v = root_jet(d, p, a).d - (b >= 0 ? root_jet(d, p, b).d : 0.0);
        Q[p->qcols[k]] += coef * v;
    }
}

/* A spring's length l (or an rspring's angle), its rate along the motion
   and the pull -(k (l - L0) + c ldot + F) along it. */
static double spring_pull(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                          const double *qd, double t, double *len)
{
    Seed s = {.q = q, .qd = qd, .t = t, .dq = qd, .col_q = -1, .col_qd = -1, .dt = 1.0};
    tape_jet(p, &s, 1, d->jreg);
    Jet ax = root_jet(d, p, 0), ay = root_jet(d, p, 1), bx = root_jet(d, p, 2), by = root_jet(d, p, 3);
    Jet az = root_jet(d, p, 6), bz = root_jet(d, p, 7);     /* 0 in a planar file */
    double act = root_jet(d, p, 4).v, l, rate;
    if (f->kind == FORCE_RSPRING) {
        l = bx.v - ax.v;
        rate = bx.d - ax.d;
    } else if (d->m->spatial) {
        double ex = bx.v - ax.v, ey = by.v - ay.v, ez = bz.v - az.v;
        l = sqrt(ex * ex + ey * ey + ez * ez);
        rate = (ex * (bx.d - ax.d) + ey * (by.d - ay.d) + ez * (bz.d - az.d)) / l;
    } else {
        double ex = bx.v - ax.v, ey = by.v - ay.v;
        l = sqrt(ex * ex + ey * ey);
        rate = (ex * (bx.d - ax.d) + ey * (by.d - ay.d)) / l;
    }
    *len = l;
    return -(f->k * (l - f->free) + f->c * rate + act);
}

/* l_q of a spring: (e . (P_B - P_A)_q) / l. */
static void add_spring(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                       const double *qd, double t, double *Q)
{
    double l, pull = spring_pull(d, f, p, q, qd, t, &l);
    if (f->kind == FORCE_RSPRING) {
        add_gradient(d, p, q, qd, t, 2, 0, pull, Q);
        return;
    }
    tape_run(p, q, qd, t, d->vreg);
    double ex = d->vreg[p->out[2]] - d->vreg[p->out[0]], ey = d->vreg[p->out[3]] - d->vreg[p->out[1]];
    add_gradient(d, p, q, qd, t, 2, 0, pull * ex / l, Q);
    add_gradient(d, p, q, qd, t, 3, 1, pull * ey / l, Q);
    if (d->m->spatial) {
        double ez = d->vreg[p->out[7]] - d->vreg[p->out[6]];
        add_gradient(d, p, q, qd, t, 7, 6, pull * ez / l, Q);
    }
}

/* Q_e += 2 E(e)^T tau: a torque in global axes on a spatial body. */
static void add_body_torque(const AppliedForce *f, const double *q, const double tau[3], double *Q)
{
    double E[3][4];
    euler_matrix(q + f->coord, true, E);
    for (int a = 0; a < 4; a++)
        Q[f->coord + a] += 2 * (E[0][a] * tau[0] + E[1][a] * tau[1] + E[2][a] * tau[2]);
}

/* force: Q += p_q^T (fx, fy, fz) */
static void apply_POINT(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                        const double *qd, double t, double *Q)
{
    (void)f;
    double fx = d->vreg[p->out[4]], fy = d->vreg[p->out[5]], fz = d->vreg[p->out[8]];
    add_gradient(d, p, q, qd, t, 0, -1, fx, Q);
    add_gradient(d, p, q, qd, t, 1, -1, fy, Q);
    if (d->m->spatial)
        add_gradient(d, p, q, qd, t, 6, -1, fz, Q);
}

/* torque: Q += theta_q^T tau */
static void apply_TORQUE(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                         const double *qd, double t, double *Q)
{
    (void)f;
    add_gradient(d, p, q, qd, t, 0, -1, d->vreg[p->out[4]], Q);
}

/* spring and rspring: the pull along the length or the angle (add_spring) */
#define apply_SPRING add_spring
#define apply_RSPRING add_spring

/* gforce: Q[coord] += fx */
static void apply_GENERAL(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                          const double *qd, double t, double *Q)
{
    (void)q, (void)qd, (void)t;
    Q[f->coord] += d->vreg[p->out[4]];
}

/* a spatial body torque: Q_e += 2 E(e)^T tau */
static void apply_BODY_TORQUE(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                              const double *qd, double t, double *Q)
{
    (void)qd, (void)t;
    double tau[3] = {d->vreg[p->out[4]], d->vreg[p->out[5]], d->vreg[p->out[8]]};
    add_body_torque(f, q, tau, Q);
}

typedef void ForceApply(GenericDyn *d, const AppliedForce *f, const Tape *p, const double *q,
                        const double *qd, double t, double *Q);

/* Every force kind's share of Q, by kind: a row of forces.def without its
   apply_KIND is an undeclared identifier, so the build names it. */
static ForceApply *const force_apply[FORCE_KIND_COUNT] = {
#define X(e, ...) [FORCE_##e] = apply_##e,
#include "../parse/forces.def"
#undef X
};

/* Each force's program runs once (apply_KIND reads its values in vreg),
   then its kind adds its share. */
static void add_applied(GenericDyn *d, const double *q, const double *qd, double t, double *Q)
{
    const Model *m = d->m;
    for (int i = 0; i < m->nforces; i++) {
        const AppliedForce *f = &d->forces[i];
        const Tape *p = &d->force_tapes[i];
        tape_run(p, q, qd, t, d->vreg);
        force_apply[f->kind](d, f, p, q, qd, t, Q);
    }
}

void generic_force(Generic *g, const double *q, const double *qd, double t, double *Q)
{
    memset(Q, 0, (size_t)g->nq * sizeof *Q);
    design_refresh(g->dyn);
    add_inertia(g->dyn, q, qd, true, Q);
    add_applied(g->dyn, q, qd, t, Q);
}

void generic_velocity_terms(Generic *g, const double *q, const double *qd, double *Qv)
{
    memset(Qv, 0, (size_t)g->nq * sizeof *Qv);
    design_refresh(g->dyn);
    add_inertia(g->dyn, q, qd, false, Qv);
}
