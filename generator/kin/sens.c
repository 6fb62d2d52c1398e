/* sens.c - the sensitivities of a state of the motion to the design parameters (mechc run --sens).
 *
 * Every partial derivative comes from the engine's sensitivity functions
 * (the generated PREFIX_phi_p, _sens_v, _sens_g, _sens_y, or the graph
 * interpreted by the generic engine), and the sensitivities of all design
 * parameters at once are products and solves with one LU of Phi_q (dense,
 * or KLU on the sparse path, where Phi_p comes on its nonzeros,
 * PREFIX_phi_p_nz; the dense path solves with the run's own LU of Phi_q
 * wherever the run lends it, sens_borrow_lu):
 *
 *   Q_p   = -Phi_q^-1 Phi_p
 *   Qd_p  = -Phi_q^-1 (V_q Q_p + V_p)                          V at qd
 *   Qdd_p =  Phi_q^-1 (G_q Q_p + G_qd Qd_p + G_p - (Phi_q qdd)_q Q_p - (Phi_q qdd)_p)
 *
 * where Phi_q qdd = V(qd := qdd) - V(qd := 0), and V being affine in qd,
 * its partials are V's at qd + qdd less V's at qd; an output f gives
 * f_q Q_p + f_p, D f the same with its qd partials on Qd_p, and
 * D(D f) + f_q qdd likewise. The n x n partials V_q, G_q and G_qd are
 * multiplied over their structural nonzeros (the graph's entries other
 * than DAG_ZERO, a subset of Phi_q's pattern), in the dense walk's order,
 * so both give the same sums.
 */
#include "sens.h"

#include "../base/arena.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Where the engine's functions write, per velocity they are taken at:
   qd, and qd + qdd. V and D f are affine in qd, so the partials of
   Phi_q qdd = V(qdd) - V(0) are V's at qd + qdd less V's at qd. */
enum { AT_QD, AT_QD_QDD, AT_COUNT };

/* The structural nonzeros of V_q, G_q and G_qd (kin's nodes), by rows. */
static void collect_nonzeros(Sens *s, const Kinematics *kin)
{
    const NodeId *of[3] = {kin->design.v_q, kin->design.g_q, kin->design.g_qd};
    size_t nq = (size_t)s->nq, nn = nq * nq, n = 0;
    for (int k = 0; k < 3; k++)
        for (size_t i = 0; i < nn; i++)
            n += of[k][i] != DAG_ZERO;
    s->nz_col = xcalloc(n + 1, sizeof *s->nz_col);
    s->nz_ptr = xcalloc(3 * (nq + 1), sizeof *s->nz_ptr);
    int at = 0;
    for (int k = 0; k < 3; k++) {
        int *ptr = s->nz_ptr + (size_t)k * (nq + 1);
        for (size_t r = 0; r < nq; r++) {
            ptr[r] = at;
            for (size_t c = 0; c < nq; c++)
                if (of[k][r * nq + c] != DAG_ZERO)
                    s->nz_col[at++] = (int)c;
        }
        ptr[nq] = at;
    }
}

bool sens_init(Sens *s, Model *m, const Kinematics *kin, const Engine *e, char *why, size_t size)
{
    memset(s, 0, sizeof *s);
    if (m->np == 0)
        snprintf(why, size, "the file has no design parameters (`design NAME = value`)");
    else if (m->nv > 0)
        snprintf(why, size, "sensitivities cover holonomic mechanisms; this one has %d "
                 "velocity-level row%s", m->nv, m->nv == 1 ? "" : "s");
    else if (m->nh != m->nq)
        snprintf(why, size, "%d rows for %d coordinates", m->nh, m->nq);
    else
        why = NULL;
    if (why)
        return false;
    s->m = m, s->e = e, s->nq = m->nq, s->np = m->np, s->nout = m->nout;
    size_t nq = (size_t)m->nq, np = (size_t)m->np, ny = (size_t)m->nout;
    size_t qq = nq * nq, qp = nq * np, yq = ny * nq + 1, yp = ny * np + 1;
    s->q_p = xcalloc(qp, sizeof(double)), s->qd_p = xcalloc(qp, sizeof(double));
    s->qdd_p = xcalloc(qp, sizeof(double));
    s->y_p = xcalloc(yp, sizeof(double)), s->yd_p = xcalloc(yp, sizeof(double));
    s->ydd_p = xcalloc(yp, sizeof(double));
    s->jac = xcalloc(qq, sizeof(double)), s->piv = xcalloc(nq, sizeof(double));
    s->phi_p = xcalloc(qp, sizeof(double)), s->col = xcalloc(nq, sizeof(double));
    for (int a = 0; a < AT_COUNT; a++) {
        s->v[a][0] = xcalloc(qq, sizeof(double)), s->v[a][1] = xcalloc(qp, sizeof(double));
        for (int k = 0; k < DESIGN_Y_COUNT; k++)
            s->y[a][k] = xcalloc(design_y_by_p(k) ? yp : yq, sizeof(double));
    }
    for (int k = 0; k < 3; k++)
        s->g[k] = xcalloc(k == 2 ? qp : qq, sizeof(double));
    s->work = xcalloc(qp + yp, sizeof(double));
    collect_nonzeros(s, kin);
    s->p_nz = kin->design.p_nz, s->p_nnz = kin->design.p_nnz;
    return true;
}

bool sens_use_sparse(Sens *s, const MechrtHostJacNz *jnz)
{
    s->klu = jnz ? mechrt_host_sparse_new(s->nq, jnz) : NULL;
    if (!s->klu)
        return false;
    /* nq x nq and nh x np: not needed; Phi_p comes on its nonzeros */
    free(s->jac), free(s->piv), free(s->phi_p);
    s->jac = s->piv = NULL;
    s->phi_p = xcalloc((size_t)(s->p_nnz > 0 ? s->p_nnz : 1), sizeof *s->phi_p);
    return true;
}

void sens_borrow_lu(Sens *s, const RunLu *lent)
{
    s->lent = lent;
    if (!s->solve_work)
        s->solve_work = xcalloc((size_t)s->nq * (size_t)s->np, sizeof *s->solve_work);
}

void sens_free(Sens *s)
{
    free(s->q_p), free(s->qd_p), free(s->qdd_p), free(s->y_p), free(s->yd_p), free(s->ydd_p);
    free(s->jac), free(s->piv), free(s->phi_p), free(s->col), free(s->work), free(s->solve_work);
    for (int a = 0; a < AT_COUNT; a++) {
        free(s->v[a][0]), free(s->v[a][1]);
        for (int k = 0; k < DESIGN_Y_COUNT; k++)
            free(s->y[a][k]);
    }
    for (int k = 0; k < 3; k++)
        free(s->g[k]);
    free(s->nz_col), free(s->nz_ptr);
    if (s->klu)
        mechrt_host_sparse_free(s->klu);
    memset(s, 0, sizeof *s);
}

/* Columns j .. j + w - 1 (w <= 4) of one row of a product: cr[j + l] +=
   sign * a_k b[k][j + l] for the k in cols (count of them; NULL: 0 ..
   count - 1) in that order, terms whose factor sign * a_k is zero left
   out; the w sums held in registers. */
static inline void add_block(double *restrict cr, double sign, const double *ar, const int *cols,
                             int count, const double *restrict b, size_t ld, int j, int w)
{
    double c[4];
    for (int l = 0; l < w; l++)
        c[l] = cr[j + l];
    for (int i = 0; i < count; i++) {
        int k = cols ? cols[i] : i;
        double f = sign * ar[k];
        if (f == 0.0)
            continue;
        const double *bk = b + (size_t)k * ld + (size_t)j;
        for (int l = 0; l < w; l++)
            c[l] += f * bk[l];
    }
    for (int l = 0; l < w; l++)
        cr[j + l] = c[l];
}

/* One row of a product, every cr[j] with the operations of the loop over
   k outside and j inside, in that order: add_block four columns at a time. */
static void add_row(double *cr, double sign, const double *ar, const int *cols, int count,
                    const double *b, int np)
{
    int j = 0;
    for (; j + 4 <= np; j += 4)
        add_block(cr, sign, ar, cols, count, b, (size_t)np, j, 4);
    switch (np - j) {     /* w a constant in each call: the sums stay in registers */
    case 3:
        add_block(cr, sign, ar, cols, count, b, (size_t)np, j, 3);
        break;
    case 2:
        add_block(cr, sign, ar, cols, count, b, (size_t)np, j, 2);
        break;
    case 1:
        add_block(cr, sign, ar, cols, count, b, (size_t)np, j, 1);
        break;
    default:
        break;
    }
}

/* c (n x np) += sign * a (n x nq) b (nq x np), all row-major. */
static void add_product(double *c, double sign, const double *a, const double *b, int n, int nq,
                        int np)
{
    for (int r = 0; r < n; r++)
        add_row(c + (size_t)r * (size_t)np, sign, a + (size_t)r * (size_t)nq, NULL, nq, b, np);
}

/* c (nq x np) += sign * a (nq x nq) b (nq x np) over a's structural
   nonzeros (the k-th list of collect_nonzeros): add_product's sums. */
static void add_product_nz(const Sens *s, int k, double *c, double sign, const double *a,
                           const double *b)
{
    size_t nq = (size_t)s->nq, np = (size_t)s->np;
    const int *ptr = s->nz_ptr + (size_t)k * (nq + 1);
    for (size_t r = 0; r < nq; r++)
        add_row(c + r * np, sign, a + r * nq, s->nz_col + ptr[r], ptr[r + 1] - ptr[r], b, s->np);
}

enum { NZ_V, NZ_GQ, NZ_GQD };

/* c (n x np) = sign * a, element by element. */
static void set_scaled(double *c, double sign, const double *a, size_t n)
{
    for (size_t i = 0; i < n; i++)
        c[i] = sign * a[i];
}

/* x (nq x np) = Phi_q^-1 x: every column at once with the dense LU
   (mechrt_lu_solve_many: the same bits as one column at a time), column by
   column with KLU. */
static void solve_columns(Sens *s, double *x)
{
    size_t np = (size_t)s->np;
    if (s->borrowed) {
        mechrt_lup_solve_many(s->lent->lup, x, s->np, s->np, s->solve_work);
        return;
    }
    if (!s->klu) {
        mechrt_lu_solve_many(s->nq, s->jac, s->nq, s->piv, x, s->np, s->np);
        return;
    }
    for (int j = 0; j < s->np; j++) {
        for (int i = 0; i < s->nq; i++)
            s->col[i] = x[(size_t)i * np + (size_t)j];
        mechrt_host_sparse_solve(s->klu, s->col);   /* as lu_solve: NaN stays NaN */
        for (int i = 0; i < s->nq; i++)
            x[(size_t)i * np + (size_t)j] = s->col[i];
    }
}

/* Whether the run's LU is Phi_q at (q, t). */
static bool lent_at(const Sens *s, double t, const double *q)
{
    const RunLu *l = s->lent;
    return l && l->lup && l->valid && l->t == t
           && memcmp(l->q, q, (size_t)s->nq * sizeof *q) == 0;
}

/* Phi_q factored (or the run's LU at (q, t) borrowed) and Phi_p at (q, t). */
static MechrtStatus factor(Sens *s, double t, const double *q)
{
    int n = s->nq;
    double tol = mechrt_default_options().pivot_tol;
    s->borrowed = !s->klu && lent_at(s, t, q);
    if (s->borrowed) {
        s->borrowed_count++;
        engine_phi_p(s->e, q, t, s->phi_p);
        return MECHRT_OK;
    }
    if (s->klu) {
        double *const nz[DESIGN_Y_COUNT] = {s->phi_p};
        engine_design(s->e, DESIGN_PHI_P_NZ, q, NULL, t, nz);
        mechrt_host_sparse_eval(s->klu, q, t);
        return mechrt_host_sparse_factor(s->klu, tol);
    }
    engine_jac(s->e, q, t, s->jac);
    engine_phi_p(s->e, q, t, s->phi_p);
    return mechrt_lu_factor(n, s->jac, n, s->piv, tol, NULL);
}

/* q_p = -Phi_p: from the dense Phi_p, or on the sparse path from its
   nonzeros (the zeros then +0, not -0). */
static void positions_rhs(Sens *s)
{
    size_t len = (size_t)s->nq * (size_t)s->np;
    if (!s->klu) {
        set_scaled(s->q_p, -1.0, s->phi_p, len);
        return;
    }
    memset(s->q_p, 0, len * sizeof *s->q_p);
    for (int e = 0; e < s->p_nnz; e++)
        s->q_p[(size_t)s->p_nz[e].row * (size_t)s->np + (size_t)s->p_nz[e].col] = -s->phi_p[e];
}

/* The outputs' sensitivities from the coordinates' (y partials taken). */
static void outputs(Sens *s)
{
    int n = s->nout, nq = s->nq, np = s->np;
    double *const *y = s->y[AT_QD], *const *y2 = s->y[AT_QD_QDD], *const *y0 = s->y[AT_QD];
    size_t len = (size_t)n * (size_t)np;
    set_scaled(s->y_p, 1.0, y[1], len);                 /* f_q Q_p + f_p */
    add_product(s->y_p, 1.0, y[0], s->q_p, n, nq, np);
    set_scaled(s->yd_p, 1.0, y[4], len);                /* Df_q Q_p + Df_qd Qd_p + Df_p */
    add_product(s->yd_p, 1.0, y[2], s->q_p, n, nq, np);
    add_product(s->yd_p, 1.0, y[3], s->qd_p, n, nq, np);
    set_scaled(s->ydd_p, 1.0, y[7], len);               /* D(D f) by q, qd, p ... */
    add_product(s->ydd_p, 1.0, y[5], s->q_p, n, nq, np);
    add_product(s->ydd_p, 1.0, y[6], s->qd_p, n, nq, np);
    add_product(s->ydd_p, 1.0, y2[2], s->q_p, n, nq, np);   /* ... f_q qdd by q and p ... */
    add_product(s->ydd_p, -1.0, y0[2], s->q_p, n, nq, np);
    for (size_t i = 0; i < len; i++)
        s->ydd_p[i] += y2[4][i] - y0[4][i];
    add_product(s->ydd_p, 1.0, y[0], s->qdd_p, n, nq, np);  /* ... and f_q Qdd_p */
}

/* The engine's V and outputs' partials at the velocity v (slot a). */
static void partials_at(Sens *s, int a, const double *q, const double *v, double t)
{
    engine_design(s->e, DESIGN_V, q, v, t, s->v[a]);
    if (s->nout)
        engine_design(s->e, DESIGN_Y, q, v, t, s->y[a]);
}

MechrtStatus sens_eval(Sens *s, double t, const double *q, const double *qd, const double *qdd)
{
    MechrtStatus st = factor(s, t, q);
    if (st != MECHRT_OK)
        return st;
    int n = s->nq, np = s->np;
    size_t len = (size_t)n * (size_t)np;
    double *both = s->work;     /* qd + qdd */
    for (int i = 0; i < n; i++)
        both[i] = qd[i] + qdd[i];
    partials_at(s, AT_QD, q, qd, t);
    partials_at(s, AT_QD_QDD, q, both, t);
    engine_design(s->e, DESIGN_G, q, qd, t, s->g);
    positions_rhs(s);
    solve_columns(s, s->q_p);
    set_scaled(s->qd_p, -1.0, s->v[AT_QD][1], len);
    add_product_nz(s, NZ_V, s->qd_p, -1.0, s->v[AT_QD][0], s->q_p);
    solve_columns(s, s->qd_p);
    set_scaled(s->qdd_p, 1.0, s->g[2], len);
    add_product_nz(s, NZ_GQ, s->qdd_p, 1.0, s->g[0], s->q_p);
    add_product_nz(s, NZ_GQD, s->qdd_p, 1.0, s->g[1], s->qd_p);
    add_product_nz(s, NZ_V, s->qdd_p, -1.0, s->v[AT_QD_QDD][0], s->q_p);
    add_product_nz(s, NZ_V, s->qdd_p, 1.0, s->v[AT_QD][0], s->q_p);
    for (size_t i = 0; i < len; i++)
        s->qdd_p[i] -= s->v[AT_QD_QDD][1][i] - s->v[AT_QD][1][i];
    solve_columns(s, s->qdd_p);
    if (s->nout)
        outputs(s);
    return MECHRT_OK;
}

MechrtStatus sens_eval_positions(Sens *s, double t, const double *q)
{
    MechrtStatus st = factor(s, t, q);
    if (st != MECHRT_OK)
        return st;
    positions_rhs(s);
    solve_columns(s, s->q_p);
    if (s->nout) {
        memset(s->work, 0, (size_t)s->nq * sizeof *s->work);
        engine_design(s->e, DESIGN_Y, q, s->work, t, s->y[AT_QD]);
        set_scaled(s->y_p, 1.0, s->y[AT_QD][1], (size_t)s->nout * (size_t)s->np);
        add_product(s->y_p, 1.0, s->y[AT_QD][0], s->q_p, s->nout, s->nq, s->np);
    }
    return MECHRT_OK;
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
