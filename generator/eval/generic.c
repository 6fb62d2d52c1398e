/* generic.c - the generic evaluator's state, its interpreted rows and options, and its entry points.
 *
 * generic_open turns the model's joint list into plans: standard joints
 * keep their attachments and axis for the formulas of generic_joints.c
 * (planar) and generic_spatial.c (spatial, with the local frame of each
 * side's axis, also for `driver D: angle(R) = E` and `slide(T) = E` over
 * R's and T's frames); other `constraint`, `driver` and `velocity` rows
 * (one plan per row: the model's row expression) and non-constant
 * options (length, angle, radius, a driver's E) are compiled to
 * instruction lists (interp.h).
 * A call computes cos and sin of every body angle, and A(p) of every
 * spatial body, the formulas need once, then runs each plan, which writes
 * its own rows. For an interpreted row:
 *
 *   position row Phi:   Jacobian dPhi/dq_j by one dual pass per column in
 *                       the row's support; nu = -dPhi/dt (dual in t);
 *                       gamma = -D(D(Phi)), a second-order jet along
 *                       (q, t) -> (qd, 1), i.e. qdd = 0;
 *   velocity row Psi:   Psi = a(q,t) . qd + b(q,t): a_j = dPsi/dqd_j (dual
 *                       per column), nu = -Psi(qd = 0) = -b,
 *                       gamma = -D(Psi), a first-order jet along (qd, 0, 1).
 */
#include "generic_impl.h"

#include "../base/arena.h"
#include "../base/sincos.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- options ---- */

double option_value(const Call *c, const Option *o)
{
    if (o->constant)
        return o->value;
    return tape_value(&c->g->progs[o->prog], c->q, NULL, c->t, c->g->vreg);
}

double option_dt(const Call *c, const Option *o)
{
    if (o->constant || !c->g->progs[o->prog].has_t)
        return 0.0;
    Seed s = {.q = c->q, .t = c->t, .col_q = -1, .col_qd = -1, .dt = 1.0};
    return tape_jet(&c->g->progs[o->prog], &s, 1, c->g->jreg).d;
}

Jet option_along(const Call *c, const Option *o, int order)
{
    if (o->constant)
        return (Jet){o->value, 0.0, 0.0};
    Seed s = {.q = c->q, .t = c->t, .dq = c->qd, .col_q = -1, .col_qd = -1, .dt = 1.0};
    return tape_jet(&c->g->progs[o->prog], &s, order, c->g->jreg);
}

void option_jac(const Call *c, const Option *o, double coef, double *row)
{
    if (o->constant)
        return;
    const Tape *p = &c->g->progs[o->prog];
    for (int k = 0; k < p->nqcols; k++) {
        Seed s = {.q = c->q, .t = c->t, .col_q = p->qcols[k], .col_qd = -1};
        row[p->qcols[k]] += coef * tape_jet(p, &s, 1, c->g->jreg).d;
    }
}

/* ---- interpreted rows ---- */

/* constraint or driver: Phi(q, t) = lhs - rhs. */
static void position_row(const Call *c, const Tape *p, int r)
{
    Generic *g = c->g;
    if (c->phi)
        c->phi[r] = tape_value(p, c->q, NULL, c->t, g->vreg);
    if (c->jac) {
        double *row = c->jac + (size_t)r * (size_t)g->nq;
        for (int k = 0; k < p->nqcols; k++) {
            Seed s = {.q = c->q, .t = c->t, .col_q = p->qcols[k], .col_qd = -1};
            row[p->qcols[k]] += tape_jet(p, &s, 1, g->jreg).d;
        }
    }
    if (c->nu) {
        Seed s = {.q = c->q, .t = c->t, .col_q = -1, .col_qd = -1, .dt = 1.0};
        c->nu[r] = p->has_t ? -tape_jet(p, &s, 1, g->jreg).d : 0.0;
    }
    if (c->gamma) {
        Seed s = {.q = c->q, .t = c->t, .dq = c->qd, .col_q = -1, .col_qd = -1, .dt = 1.0};
        c->gamma[r] = -tape_jet(p, &s, 2, g->jreg).dd;
    }
}

/* velocity or velocity-level driver: Psi(q, qd, t) = lhs - rhs. */
static void velocity_row(const Call *c, const Tape *p, int r)
{
    Generic *g = c->g;
    if (c->psi)
        c->psi[r - g->nh] = tape_value(p, c->q, c->qd, c->t, g->vreg);
    if (c->jac) {
        double *row = c->jac + (size_t)r * (size_t)g->nq;
        for (int k = 0; k < p->nqdcols; k++) {
            Seed s = {.q = c->q, .t = c->t, .col_q = -1, .col_qd = p->qdcols[k]};
            row[p->qdcols[k]] += tape_jet(p, &s, 1, g->jreg).d;
        }
    }
    if (c->nu)
        c->nu[r] = -tape_value(p, c->q, NULL, c->t, g->vreg);
    if (c->gamma) {
        Seed s = {.q = c->q, .qd = c->qd, .t = c->t, .dq = c->qd, .col_q = -1, .col_qd = -1, .dt = 1.0};
        c->gamma[r] = -tape_jet(p, &s, 1, g->jreg).d;
    }
}

/* ---- a call ---- */

static void run(Call *c)
{
    Generic *g = c->g;
    /* nu of the standard joints never rotates anything, phi only for
       position-level joints */
    int nangles = c->jac || c->gamma || c->psi ? g->nangles : c->phi ? g->nangles_pos : 0;
    for (int k = 0; k < nangles; k++) {
        int i = g->angles[k];
        /* the generated kernels' trigonometry, so that the engines compare
           code generation, not sin and cos */
        mechc_sincos(c->q[i], &g->sinq[i], &g->cosq[i]);
    }
    if (g->nrots && (c->phi || c->jac || c->gamma || c->psi || g->nu_rots))
        generic_spatial_rotations(c);
    if (c->jac)
        memset(c->jac, 0, (size_t)g->nr * (size_t)g->nq * sizeof *c->jac);
    for (int i = 0; i < g->nplans; i++) {
        const Plan *p = &g->plans[i];
        if (p->rows)
            p->rows(c, p);
        else if (p->velocity)
            velocity_row(c, &g->progs[p->prog], p->row);
        else
            position_row(c, &g->progs[p->prog], p->row);
    }
}

void generic_phi(Generic *g, const double *q, double t, double *phi)
{
    run(&(Call){.g = g, .q = q, .t = t, .phi = phi});
}

void generic_jac(Generic *g, const double *q, double t, double *jac)
{
    run(&(Call){.g = g, .q = q, .t = t, .jac = jac});
}

void generic_nu(Generic *g, const double *q, double t, double *nu)
{
    run(&(Call){.g = g, .q = q, .t = t, .nu = nu});
}

void generic_gamma(Generic *g, const double *q, const double *qd, double t, double *gamma)
{
    run(&(Call){.g = g, .q = q, .qd = qd, .t = t, .gamma = gamma});
}

void generic_all(Generic *g, const double *q, const double *qd, double t,
                 double *phi, double *jac, double *nu, double *gamma)
{
    run(&(Call){.g = g, .q = q, .qd = qd, .t = t, .phi = phi, .jac = jac, .nu = nu, .gamma = gamma});
}

void generic_psi(Generic *g, const double *q, const double *qd, double t, double *psi)
{
    run(&(Call){.g = g, .q = q, .qd = qd, .t = t, .psi = psi});
}

/* ---- set-up ---- */

static int add_tape(Generic *g, const Model *m, NodeId root, CompileScratch *cs)
{
    tape_compile(&g->progs[g->nprogs], &m->dag, root, cs);
    return g->nprogs++;
}

/* A joint without formulas: one plan per row, each the row's program
   (the row expression itself, options folded in). p is its first plan. */
static void interpret_rows(Generic *g, Plan *p, CompileScratch *cs)
{
    const Joint *j = p->j;
    for (int k = 0; k < j->nrows; k++) {
        Plan *q = k == 0 ? p : &g->plans[g->nplans++];
        *q = *p;
        q->row = j->first_row + k;
        q->prog = add_tape(g, g->m, g->m->rows[q->row].expr, cs);
    }
}

/* A spatial plan's local frames: h, f, g of A's axis and of B's (the
   builder's, joints_spatial_frame); a kind without an axis has none. */
static void spatial_frame(Generic *g, Plan *p, int joint)
{
    const Joint *j = p->of;
    double (*fr)[3] = g->frames + 6 * joint;
    if (j->ux != 0.0 || j->uy != 0.0 || j->uz != 0.0)
        joints_spatial_frame(j->ux, j->uy, j->uz, fr[0], fr[1], fr[2]);
    if (j->bx != 0.0 || j->by != 0.0 || j->bz != 0.0)
        joints_spatial_frame(j->bx, j->by, j->bz, fr[3], fr[4], fr[5]);
    p->frame = (const double (*)[3])fr;
    if ((j->kind == JOINT_S_CONTACT || p->j->measures > 0) && !p->opt.constant)
        g->nu_rots = true;      /* nu = s R_t, (s S + c C) theta_t need A */
}

/* The spatial bodies whose A(p) the formulas use (need[e0] == NEED_ROT). */
static void collect_rotations(Generic *g, const char *need)
{
    g->rots = xcalloc((size_t)g->nq + 1, sizeof *g->rots);
    g->rot_q = xcalloc((size_t)g->nq + 1, sizeof *g->rot_q);
    g->rot_of = xcalloc((size_t)g->nq + 1, sizeof *g->rot_of);
    for (int k = 3; k < g->nq; k++)
        if (need[k] == NEED_ROT) {
            g->rot_of[k - 3] = g->nrots;
            g->rot_q[g->nrots++] = k - 3;
        }
}

static bool designed(const Joint *j)
{
    return j->a.designed || j->b.designed || j->axis_designed;
}

Generic *generic_open(const Model *m)
{
    Generic *g = xcalloc(1, sizeof *g);
    g->m = m;
    g->nq = m->nq;
    g->nh = m->nh;
    g->nv = m->nv;
    g->nr = m->nr;
    /* at most one plan per row (every joint has a row), and one program
       per row and per joint's option */
    g->plans = xcalloc((size_t)m->nr + 1, sizeof *g->plans);
    g->progs = xcalloc((size_t)m->nr + (size_t)m->njoints + 1, sizeof *g->progs);
    g->cosq = xcalloc((size_t)m->nq, sizeof *g->cosq);
    g->sinq = xcalloc((size_t)m->nq, sizeof *g->sinq);
    g->angles = xcalloc((size_t)m->nq, sizeof *g->angles);
    g->frames = xcalloc((size_t)m->njoints * 6 + 1, sizeof *g->frames);
    char *need = xcalloc((size_t)m->nq, sizeof *need);
    CompileScratch cs;
    compile_scratch_init(&cs, &m->dag);
    for (int i = 0; i < m->njoints; i++) {
        const Joint *j = &m->joints[i];
        Plan *p = &g->plans[g->nplans++];
        *p = (Plan){.j = j, .row = j->first_row, .velocity = j->velocity, .prog = -1,
                    .opt = {.constant = true, .prog = -1}};
        p->of = j;
        /* formulas hold offsets and axes as numbers: a joint whose offsets
           or axis are design parameters' is interpreted from its rows
           (which read p) */
        p->rows = designed(j) ? NULL : generic_joint_formula(j, need);
        if (!p->rows && !designed(j) && j->kind == JOINT_DRIVER && j->measures != 0) {
            p->of = &m->joints[abs(j->measures) - 1];
            p->rows = designed(p->of) ? NULL : generic_measure_rows(j, p->of, need);
        }
        if (!p->rows) {
            interpret_rows(g, p, &cs);
            continue;
        }
        if ((joint_info[j->kind].option != OPTION_NONE || j->measures != 0)
            && !dag_is_const(&m->dag, j->option, &p->opt.value)) {
            p->opt.constant = false;
            p->opt.prog = add_tape(g, m, j->option, &cs);
        }
        if (m->spatial)
            spatial_frame(g, p, i);
    }
    compile_scratch_free(&cs);
    collect_rotations(g, need);
    for (int level = 2; level >= 1; level--) {
        for (int k = 0; k < m->nq; k++)
            if (need[k] == level)
                g->angles[g->nangles++] = k;
        if (level == 2)
            g->nangles_pos = g->nangles;
    }
    free(need);
    int regs = 1;
    for (int k = 0; k < g->nprogs; k++)
        if (g->progs[k].n > regs)
            regs = g->progs[k].n;
    g->jreg = xcalloc((size_t)regs, sizeof *g->jreg);
    g->vreg = xcalloc((size_t)regs, sizeof *g->vreg);
    if (m->nmasses > 0)
        g->dyn = generic_dynamics_open(m);
    return g;
}

int generic_interpreted_rows(const Generic *g)
{
    int n = 0;
    for (int i = 0; i < g->nplans; i++)
        n += g->plans[i].rows == NULL;
    return n;
}

void generic_free(Generic *g)
{
    if (!g)
        return;
    for (int k = 0; k < g->nprogs; k++)
        tape_free(&g->progs[k]);
    free(g->progs);
    free(g->plans);
    free(g->cosq);
    free(g->sinq);
    free(g->angles);
    free(g->frames);
    free(g->rots);
    free(g->rot_q);
    free(g->rot_of);
    free(g->jreg);
    free(g->vreg);
    generic_dynamics_free(g->dyn);
    free(g);
}
