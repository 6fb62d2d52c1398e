/* sens.c - the sensitivities of a state of the motion to the design parameters (mechc run --sens).
 *
 * The right-hand sides come from five interpreted programs: V = D(Phi)
 * (Phi_q qd + Phi_t, diff_total), gamma = -D(D(Phi)), and each output f
 * with D f and D(D f). A first-order jet along (q_pj, qd direction, e_j)
 * gives a total derivative in p_j. The acceleration's term
 * d/dp (Phi_q qdd) needs Phi_q qdd as an expression: it is V with qd set
 * to qdd, less V with qd set to 0 (Phi_t), so no new nodes are made for it.
 */
#include "sens.h"

#include "../base/arena.h"
#include "../diff/diff.h"
#include "../eval/interp.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { TAPE_V, TAPE_GAMMA, TAPE_F, TAPE_DF, TAPE_DDF, TAPE_COUNT };

/* The nodes of each program, from the kinematics and new derivatives. */
static void build_roots(Model *m, const Kinematics *kin, NodeId *roots[TAPE_COUNT])
{
    Differ df;
    differ_init(&df, &m->dag, m->nq);
    for (int r = 0; r < m->nh; r++) {
        roots[TAPE_V][r] = diff_total(&df, kin->phi[r]);
        roots[TAPE_GAMMA][r] = kin->gamma[r];
    }
    for (int k = 0; k < m->nout; k++) {
        roots[TAPE_F][k] = m->outputs[k].expr;
        roots[TAPE_DF][k] = diff_total(&df, m->outputs[k].expr);
        roots[TAPE_DDF][k] = diff_total(&df, roots[TAPE_DF][k]);
    }
    differ_free(&df);
}

bool sens_init(Sens *s, Model *m, const Kinematics *kin, const Engine *e, char *why, size_t size)
{
    memset(s, 0, sizeof *s);
    if (m->np == 0)
        snprintf(why, size, "the file has no design parameters (`design NAME = value`)");
    else if (m->nv > 0)
        snprintf(why, size, "sensitivities cover holonomic mechanisms; this one has %d "
                 "velocity-level rows", m->nv);
    else if (m->nh != m->nq)
        snprintf(why, size, "%d rows for %d coordinates", m->nh, m->nq);
    else
        why = NULL;
    if (why)
        return false;
    s->m = m, s->e = e, s->nq = m->nq, s->np = m->np, s->nout = m->nout;
    int nmax = m->nh > m->nout ? m->nh : m->nout;
    NodeId *roots[TAPE_COUNT];
    for (int t = 0; t < TAPE_COUNT; t++)
        roots[t] = xcalloc((size_t)nmax + 1, sizeof *roots[t]);
    build_roots(m, kin, roots);
    s->tapes = xcalloc(TAPE_COUNT, sizeof *s->tapes);
    CompileScratch cs;
    compile_scratch_init(&cs, &m->dag);
    int longest = 1;
    for (int t = 0; t < TAPE_COUNT; t++) {
        tape_compile_roots(&s->tapes[t], &m->dag, roots[t], t <= TAPE_GAMMA ? m->nh : m->nout, &cs);
        if (s->tapes[t].n > longest)
            longest = s->tapes[t].n;
        free(roots[t]);
    }
    compile_scratch_free(&cs);
    s->reg = xcalloc((size_t)longest, sizeof *s->reg);
    size_t nq = (size_t)m->nq, np = (size_t)m->np, ny = (size_t)m->nout * np + 1;
    s->q_p = xcalloc(nq * np, sizeof(double)), s->qd_p = xcalloc(nq * np, sizeof(double));
    s->qdd_p = xcalloc(nq * np, sizeof(double));
    s->y_p = xcalloc(ny, sizeof(double)), s->yd_p = xcalloc(ny, sizeof(double));
    s->ydd_p = xcalloc(ny, sizeof(double));
    s->jac = xcalloc(nq * nq, sizeof(double)), s->piv = xcalloc(nq, sizeof(double));
    s->phi_p = xcalloc(nq * np, sizeof(double)), s->rhs = xcalloc(nq, sizeof(double));
    s->dp = xcalloc(np, sizeof(double)), s->zero = xcalloc(nq, sizeof(double));
    s->col = xcalloc(nq, sizeof(double)), s->cold = xcalloc(nq, sizeof(double));
    s->coldd = xcalloc(nq, sizeof(double));
    return true;
}

void sens_free(Sens *s)
{
    for (int t = 0; s->tapes && t < TAPE_COUNT; t++)
        tape_free(&s->tapes[t]);
    free(s->tapes), free(s->reg);
    free(s->q_p), free(s->qd_p), free(s->qdd_p), free(s->y_p), free(s->yd_p), free(s->ydd_p);
    free(s->jac), free(s->piv), free(s->phi_p), free(s->rhs), free(s->dp), free(s->zero);
    free(s->col), free(s->cold), free(s->coldd);
    memset(s, 0, sizeof *s);
}

/* Root k's derivative along seed in the last jet pass of tape t. */
static double jet_d(const Sens *s, int t, int k)
{
    int r = s->tapes[t].out[k];
    return r >= 0 ? s->reg[r].d : 0.0;
}

/* One first-order pass of tape t at (q, qd, t) along (dq, dqd, e_j). */
static void pass(Sens *s, int tape, const double *q, const double *qd, double t, const double *dq,
                 const double *dqd)
{
    Seed seed = {.q = q, .qd = qd, .t = t, .dq = dq, .col_q = -1, .col_qd = -1, .dqd = dqd,
                 .dp = s->dp};
    tape_jet(&s->tapes[tape], &seed, 1, s->reg);
}

/* Column j of a variable-major nq x np array, from col. */
static void put_column(const Sens *s, double *a, int j, const double *col)
{
    for (int i = 0; i < s->nq; i++)
        a[(size_t)i * (size_t)s->np + (size_t)j] = col[i];
}

/* The outputs' sensitivities to p_j from the coordinates'. */
static void output_column(Sens *s, int j, double t, const double *q, const double *qd,
                          const double *qdd)
{
    size_t np = (size_t)s->np;
    for (int k = 0; k < s->nout; k++)
        s->ydd_p[(size_t)k * np + (size_t)j] = 0.0;
    pass(s, TAPE_F, q, NULL, t, s->col, s->zero);
    for (int k = 0; k < s->nout; k++)
        s->y_p[(size_t)k * np + (size_t)j] = jet_d(s, TAPE_F, k);
    pass(s, TAPE_DF, q, qd, t, s->col, s->cold);
    for (int k = 0; k < s->nout; k++)
        s->yd_p[(size_t)k * np + (size_t)j] = jet_d(s, TAPE_DF, k);
    /* ydd = f_q qdd + D(D f), f_q qdd = Df(qd := qdd) - Df(qd := 0) */
    pass(s, TAPE_DDF, q, qd, t, s->col, s->cold);
    for (int k = 0; k < s->nout; k++)
        s->ydd_p[(size_t)k * np + (size_t)j] += jet_d(s, TAPE_DDF, k);
    pass(s, TAPE_DF, q, qdd, t, s->col, s->coldd);
    for (int k = 0; k < s->nout; k++)
        s->ydd_p[(size_t)k * np + (size_t)j] += jet_d(s, TAPE_DF, k);
    pass(s, TAPE_DF, q, NULL, t, s->col, s->zero);
    for (int k = 0; k < s->nout; k++)
        s->ydd_p[(size_t)k * np + (size_t)j] -= jet_d(s, TAPE_DF, k);
}

/* Column j of q_p, qd_p, qdd_p (and the outputs'), with Phi_q factored. */
static void column(Sens *s, int j, double t, const double *q, const double *qd, const double *qdd)
{
    int n = s->nq;
    for (int i = 0; i < n; i++)
        s->col[i] = -s->phi_p[(size_t)i * (size_t)s->np + (size_t)j];
    mechrt_lu_solve(n, s->jac, n, s->piv, s->col);
    s->dp[j] = 1.0;
    pass(s, TAPE_V, q, qd, t, s->col, s->zero);
    for (int r = 0; r < n; r++)
        s->cold[r] = -jet_d(s, TAPE_V, r);
    mechrt_lu_solve(n, s->jac, n, s->piv, s->cold);
    /* Phi_q qdd_p = d gamma/dp - d(Phi_q qdd)/dp */
    pass(s, TAPE_GAMMA, q, qd, t, s->col, s->cold);
    for (int r = 0; r < n; r++)
        s->coldd[r] = jet_d(s, TAPE_GAMMA, r);
    pass(s, TAPE_V, q, qdd, t, s->col, s->zero);
    for (int r = 0; r < n; r++)
        s->coldd[r] -= jet_d(s, TAPE_V, r);
    pass(s, TAPE_V, q, NULL, t, s->col, s->zero);
    for (int r = 0; r < n; r++)
        s->coldd[r] += jet_d(s, TAPE_V, r);
    mechrt_lu_solve(n, s->jac, n, s->piv, s->coldd);
    put_column(s, s->q_p, j, s->col);
    put_column(s, s->qd_p, j, s->cold);
    put_column(s, s->qdd_p, j, s->coldd);
    if (s->nout)
        output_column(s, j, t, q, qd, qdd);
    s->dp[j] = 0.0;
}

/* Phi_q factored and Phi_p at (q, t). */
static MechrtStatus factor(Sens *s, double t, const double *q)
{
    int n = s->nq;
    engine_jac(s->e, q, t, s->jac);
    engine_phi_p(s->e, q, t, s->phi_p);
    return mechrt_lu_factor(n, s->jac, n, s->piv, mechrt_default_options().pivot_tol, NULL);
}

MechrtStatus sens_eval(Sens *s, double t, const double *q, const double *qd, const double *qdd)
{
    MechrtStatus st = factor(s, t, q);
    for (int j = 0; j < s->np && st == MECHRT_OK; j++)
        column(s, j, t, q, qd, qdd);
    return st;
}

MechrtStatus sens_eval_positions(Sens *s, double t, const double *q)
{
    MechrtStatus st = factor(s, t, q);
    size_t np = (size_t)s->np;
    for (int j = 0; j < s->np && st == MECHRT_OK; j++) {
        for (int i = 0; i < s->nq; i++)
            s->col[i] = -s->phi_p[(size_t)i * np + (size_t)j];
        mechrt_lu_solve(s->nq, s->jac, s->nq, s->piv, s->col);
        put_column(s, s->q_p, j, s->col);
        s->dp[j] = 1.0;
        pass(s, TAPE_F, q, NULL, t, s->col, s->zero);
        s->dp[j] = 0.0;
        for (int k = 0; k < s->nout; k++)
            s->y_p[(size_t)k * np + (size_t)j] = jet_d(s, TAPE_F, k);
    }
    return st;
}

int sens_column_count(const Sens *s)
{
    return 3 * (s->nq + s->nout) * s->np;
}

char *sens_column_name(const Sens *s, const char *const *names, int column)
{
    int nv = s->nq + s->nout, per = nv * s->np;
    int level = column / per, v = column % per / s->np, j = column % s->np;
    static const char *const open[3] = {"", "d(", "dd("}, *const close[3] = {"", ")", ")"};
    size_t len = strlen(names[v]) + strlen(s->m->design_names[j]) + 16;
    char *name = xmalloc(len);
    snprintf(name, len, "d(%s%s%s)/d(%s)", open[level], names[v], close[level],
             s->m->design_names[j]);
    return name;
}

void sens_columns(const Sens *s, double *out)
{
    size_t nqp = (size_t)s->nq * (size_t)s->np, nyp = (size_t)s->nout * (size_t)s->np;
    const double *from[3][2] = {{s->q_p, s->y_p}, {s->qd_p, s->yd_p}, {s->qdd_p, s->ydd_p}};
    for (int level = 0; level < 3; level++) {
        memcpy(out, from[level][0], nqp * sizeof *out);
        memcpy(out + nqp, from[level][1], nyp * sizeof *out);
        out += nqp + nyp;
    }
}
