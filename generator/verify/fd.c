/* fd.c - the check's finite differences: Phi, Psi and their paths against the generated jac, nu, gamma.
 *
 * Every difference is taken on a ladder of steps (FD_STEPS) and judged at
 * the first run of three neighbouring steps that agree (compare_fd); see
 * check.c for why. The sparse Jacobian is differenced by column groups
 * (groups.c).
 */
#include "fd.h"

#include <gsl/gsl_deriv.h>
#include <math.h>
#include <string.h>

/* A vector function of one scalar x, its values cached for the few x
   gsl_deriv_central asks for, so the rows of one column share them. */
typedef enum FdKind {
    FD_PHI_Q,       /* Phi(q with q_col = x, t) */
    FD_PHI_PATH,    /* Phi(q + qd x [path_q], t + x [path_t]) */
    FD_PSI_QD,      /* Psi(q, qd with qd_col = x, t) */
    FD_PSI_PATH,    /* Psi(q + qd x [path_q], qd, t + x [path_t]) */
    FD_PHI_GROUP,   /* Phi(q + x on the group's columns, t) */
    FD_PSI_GROUP,   /* Psi(q, qd + x on the group's columns, t) */
} FdKind;

typedef struct VecFn {
    Checker *c;
    FdKind kind;
    int col;
    bool path_q, path_t;
    int comp;               /* the component gsl asks about */
    const int *gcols;       /* FD_*_GROUP: the group's columns */
    int gn;
    double x[FD_CACHE];
    double *val[FD_CACHE];
    int count, next;
} VecFn;

static void vecfn_eval(VecFn *f, double x, double *out)
{
    Checker *c = f->c;
    int nq = c->nq;
    switch (f->kind) {
    case FD_PHI_Q:
        memcpy(c->qw, c->q, (size_t)nq * sizeof *c->qw);
        c->qw[f->col] = x;
        engine_phi(&c->eng[ENGINE_JIT], c->qw, c->t, out);
        return;
    case FD_PHI_PATH:
        for (int i = 0; i < nq; i++)
            c->qw[i] = c->q[i] + (f->path_q ? c->qd[i] * x : 0.0);
        engine_phi(&c->eng[ENGINE_JIT], c->qw, c->t + (f->path_t ? x : 0.0), out);
        return;
    case FD_PSI_QD:
        memcpy(c->qdw, c->qd, (size_t)nq * sizeof *c->qdw);
        c->qdw[f->col] = x;
        generic_psi(c->eng[ENGINE_GENERIC].generic, c->q, c->qdw, c->t, out);
        return;
    case FD_PSI_PATH:
        for (int i = 0; i < nq; i++)
            c->qw[i] = c->q[i] + (f->path_q ? c->qd[i] * x : 0.0);
        generic_psi(c->eng[ENGINE_GENERIC].generic, c->qw, c->qd, c->t + (f->path_t ? x : 0.0), out);
        return;
    case FD_PHI_GROUP:
        memcpy(c->qw, c->q, (size_t)nq * sizeof *c->qw);
        for (int k = 0; k < f->gn; k++)
            c->qw[f->gcols[k]] += x;
        engine_phi(&c->eng[ENGINE_JIT], c->qw, c->t, out);
        return;
    case FD_PSI_GROUP:
        memcpy(c->qdw, c->qd, (size_t)nq * sizeof *c->qdw);
        for (int k = 0; k < f->gn; k++)
            c->qdw[f->gcols[k]] += x;
        generic_psi(c->eng[ENGINE_GENERIC].generic, c->q, c->qdw, c->t, out);
        return;
    }
}

static void vecfn_init(VecFn *f, Checker *c, FdKind kind, int col, bool path_q, bool path_t, double *store)
{
    *f = (VecFn){.c = c, .kind = kind, .col = col, .path_q = path_q, .path_t = path_t};
    int n = (c->nh > c->nv ? c->nh : c->nv) + 1;
    for (int k = 0; k < FD_CACHE; k++)
        f->val[k] = store + (size_t)k * (size_t)n;
}

static double vecfn_component(double x, void *params)
{
    VecFn *f = params;
    for (int k = 0; k < f->count; k++)
        if (f->x[k] == x)
            return f->val[k][f->comp];
    int slot = f->next;
    f->next = (f->next + 1) % FD_CACHE;
    if (f->count < FD_CACHE)
        f->count++;
    f->x[slot] = x;
    vecfn_eval(f, x, f->val[slot]);
    return f->val[slot][f->comp];
}

/* d f_comp / dx at x0 by GSL's adaptive five-point central difference. */
static double fd_first(VecFn *f, int comp, double x0, double h)
{
    gsl_function fn = {vecfn_component, f};
    double result, abserr;
    f->comp = comp;
    gsl_deriv_central(&fn, x0, h * fmax(1.0, fabs(x0)), &result, &abserr);
    return result;
}

/* d2 f/dx2 at 0 for every component into out: central second differences
   D(h) = (f(h) - 2 f(0) + f(-h))/h^2 at h and h/2, then Richardson
   (4 D(h/2) - D(h))/3, which cancels the h^2 error term. */
static void fd_second(VecFn *f, int n, double h, double *out)
{
    Checker *c = f->c;
    const double xs[5] = {-h, -0.5 * h, 0.0, 0.5 * h, h};
    for (int k = 0; k < 5; k++)
        vecfn_eval(f, xs[k], c->d2[k]);
    for (int i = 0; i < n; i++) {
        double f0 = c->d2[2][i];
        double dh = (c->d2[4][i] - 2.0 * f0 + c->d2[0][i]) / (h * h);
        double dh2 = (c->d2[3][i] - 2.0 * f0 + c->d2[1][i]) / (0.25 * h * h);
        out[i] = (4.0 * dh2 - dh) / 3.0;
    }
}

/* df/dx at 0 for every component into out: central differences
   D(h) = (f(h) - f(-h))/2h at h and h/2, then Richardson (4 D(h/2) -
   D(h))/3, error O(h^4) (the sparse Jacobian's column groups). */
static void fd_first_vec(VecFn *f, int n, double h, double *out)
{
    Checker *c = f->c;
    const double xs[4] = {-h, -0.5 * h, 0.5 * h, h};
    for (int k = 0; k < 4; k++)
        vecfn_eval(f, xs[k], c->d2[k]);
    for (int i = 0; i < n; i++) {
        double dh = (c->d2[3][i] - c->d2[0][i]) / (2.0 * h);
        double dh2 = (c->d2[2][i] - c->d2[1][i]) / h;
        out[i] = (4.0 * dh2 - dh) / 3.0;
    }
}

/* The second difference's step: its rounding error grows like
   eps |q| / h^2 (rows are differences of coordinates of size |q|), its
   truncation error like h^4, so the best h grows like |q|^(1/6). */
double check_second_step(const Checker *c)
{
    double qmax = 1.0;
    for (int i = 0; i < c->nq; i++)
        qmax = fmax(qmax, fabs(c->q[i]));
    return c->opt->fd_step2 * pow(qmax, 1.0 / 6.0);
}

/* One finite difference a value is compared with, as a function of the
   step: sign times a component of gsl_deriv_central at x0 (step relative,
   times scale = max(1, |x0|)), or of the second difference along a path
   at 0 (absolute step; every component computed at once, kept per ladder
   step so that the rows share them). */
typedef struct FdProbe {
    VecFn *f;
    int comp;
    double sign;
    bool second;
    bool vector;        /* fd_first_vec's, kept per ladder step like the second's */
    double x0, scale;
    int n;
    Checker *c;
} FdProbe;

static double ladder_step(double h, int i)
{
    return h * pow(FD_RATIO, FD_COARSE - i);
}

static double probe_at(FdProbe *p, int i, double h)
{
    double step = ladder_step(h, i);
    if (!p->second && !p->vector)
        return p->sign * fd_first(p->f, p->comp, p->x0, step);
    Checker *c = p->c;
    if (!c->ladder_have[i]) {
        if (p->vector)
            fd_first_vec(p->f, p->n, step, c->ladder[i]);
        else
            fd_second(p->f, p->n, step, c->ladder[i]);
        c->ladder_have[i] = true;
    }
    return p->sign * c->ladder[i][p->comp];
}

/* Judges value against the finite difference d0 taken at the default step
   h; when they disagree, against the first run of three neighbouring steps
   whose differences settle (see the top of the file). */
static void compare_fd(Checker *c, int what, int row, int col, double value, double d0, FdProbe *p, double h)
{
    double tol = c->opt->tol;
    if (check_rel_error(value, d0) <= tol) {
        check_record(c, what, row, col, value, d0, h * p->scale);
        return;
    }
    double d[FD_STEPS];
    bool have[FD_STEPS] = {false};
    d[FD_COARSE] = d0;
    have[FD_COARSE] = true;
    int bottom = FD_STEPS - 1, settled = -1;
    /* the runs (i, i + 1, i + 2), with r = pi: (h, h/r, h/r^2), (h/r, h/r^2,
       h/r^3), ..., then (r h, h, h/r), (r^2 h, r h, h) */
    for (int k = 0; k < FD_STEPS - 2 && settled < 0; k++) {
        int i = k < FD_FINE - 1 ? FD_COARSE + k : FD_COARSE - 1 - (k - (FD_FINE - 1));
        bool agree = true;
        for (int j = i; j <= i + 2 && agree; j++) {
            if (j > bottom) {
                agree = false;
                break;
            }
            if (!have[j]) {
                d[j] = probe_at(p, j, h);
                have[j] = true;
            }
            if (j > FD_COARSE && d[j] == 0.0 && d[j - 1] != 0.0) {
                bottom = j - 1;     /* the step is below what the row resolves */
                agree = false;
            } else if (j > i) {
                agree = check_rel_error(d[j - 1], d[j]) <= FD_SETTLE * tol;
            }
        }
        if (agree)
            settled = i;
    }
    CheckItem *it = &c->rep->items[what];
    if (settled < 0) {
        /* no run of steps agrees: the differences cannot tell */
        if (it->unsettled++ == 0) {
            it->unsettled_row = row;
            it->unsettled_col = col;
        }
        it->checked = true;
        return;
    }
    /* the reference: the default's difference when the run confirms it, else the run's middle */
    int r = settled <= FD_COARSE && FD_COARSE <= settled + 2 ? FD_COARSE : settled + 1;
    if (r != FD_COARSE)
        it->refined++;
    check_record(c, what, row, col, value, d[r], ladder_step(h, r) * p->scale);
}

/* value against sign * d f_comp/dx at x0. */
static void compare_first(Checker *c, int what, int row, int col, double value, VecFn *f, int comp,
                          double x0, double sign)
{
    double h = c->opt->fd_step;
    FdProbe p = {.f = f, .comp = comp, .sign = sign, .x0 = x0, .scale = fmax(1.0, fabs(x0)), .c = c};
    compare_fd(c, what, row, col, value, sign * fd_first(f, comp, x0, h), &p, h);
}

/* The rows of one column group against one vector difference (rows first
   .. first + n - 1, component i of the difference for row first + i):
   each row's entry of the group, or 0 where the pattern has none. */
static void compare_group(Checker *c, VecFn *f, int first, int n)
{
    double h = c->opt->fd_step;
    memset(c->ladder_have, 0, sizeof c->ladder_have);
    fd_first_vec(f, n, h, c->ladder[FD_COARSE]);
    c->ladder_have[FD_COARSE] = true;
    FdProbe p = {.f = f, .sign = 1.0, .vector = true, .scale = 1.0, .n = n, .c = c};
    const double *vals = c->out[ENGINE_JIT][QTY_JAC];
    for (int i = 0; i < n; i++) {
        int e = c->ent[first + i];
        p.comp = i;
        compare_fd(c, CHECK_JAC_FD, first + i, e >= 0 ? c->jnz[ENGINE_JIT]->jac.col[e] : -1,
                   e >= 0 ? vals[e] : 0.0, c->ladder[FD_COARSE][i], &p, h);
    }
}

/* The Jacobian's nonzeros against differences of Phi (position rows) and
   Psi (velocity rows) along each column group. */
static void check_fd_groups(Checker *c, double *scratch)
{
    const int *row = c->jnz[ENGINE_JIT]->jac.row;
    VecFn f;
    for (int g = 0; g < c->ngroups; g++) {
        const int *cols = c->group_cols + c->group_start[g];
        int gn = c->group_start[g + 1] - c->group_start[g];
        for (int k = 0; k < gn; k++)
            for (int a = c->col_start[cols[k]]; a < c->col_start[cols[k] + 1]; a++)
                c->ent[row[c->col_ent[a]]] = c->col_ent[a];
        for (int v = 0; v < 2; v++) {
            int first = v ? c->nh : 0, n = v ? c->nv : c->nh;
            if (n == 0)
                continue;
            vecfn_init(&f, c, v ? FD_PSI_GROUP : FD_PHI_GROUP, -1, false, false, scratch);
            f.gcols = cols;
            f.gn = gn;
            compare_group(c, &f, first, n);
        }
        for (int k = 0; k < gn; k++)
            for (int a = c->col_start[cols[k]]; a < c->col_start[cols[k] + 1]; a++)
                c->ent[row[c->col_ent[a]]] = -1;
    }
}

void check_fd(Checker *c, double *scratch, double *vec)
{
    double **u = c->out[ENGINE_JIT];
    int nq = c->nq, nh = c->nh, nv = c->nv;
    VecFn f;
    /* jac */
    if (c->sparse)
        check_fd_groups(c, scratch);
    for (int j = 0; j < nq && !c->sparse; j++) {
        if (nh > 0) {
            vecfn_init(&f, c, FD_PHI_Q, j, false, false, scratch);
            for (int i = 0; i < nh; i++)
                compare_first(c, CHECK_JAC_FD, i, j, u[QTY_JAC][(size_t)i * nq + j], &f, i, c->q[j], 1.0);
        }
        if (nv > 0) {
            vecfn_init(&f, c, FD_PSI_QD, j, false, false, scratch);
            for (int i = 0; i < nv; i++)
                compare_first(c, CHECK_JAC_FD, nh + i, j, u[QTY_JAC][(size_t)(nh + i) * nq + j], &f, i,
                              c->qd[j], 1.0);
        }
    }
    /* nu */
    if (nh > 0) {
        vecfn_init(&f, c, FD_PHI_PATH, -1, false, true, scratch);
        for (int i = 0; i < nh; i++)
            compare_first(c, CHECK_NU_FD, i, -1, u[QTY_NU][i], &f, i, 0.0, -1.0);
    }
    if (nv > 0) {
        memset(c->qdw, 0, (size_t)nq * sizeof *c->qdw);
        generic_psi(c->eng[ENGINE_GENERIC].generic, c->q, c->qdw, c->t, vec);
        for (int i = 0; i < nv; i++)
            check_record(c, CHECK_NU_FD, nh + i, -1, u[QTY_NU][nh + i], -vec[i], 0.0);
    }
    /* gamma */
    if (nh > 0) {
        vecfn_init(&f, c, FD_PHI_PATH, -1, true, true, scratch);
        double h = check_second_step(c);
        memset(c->ladder_have, 0, sizeof c->ladder_have);
        fd_second(&f, nh, h, c->ladder[FD_COARSE]);
        c->ladder_have[FD_COARSE] = true;
        FdProbe p = {.f = &f, .sign = -1.0, .second = true, .scale = 1.0, .n = nh, .c = c};
        for (int i = 0; i < nh; i++) {
            p.comp = i;
            compare_fd(c, CHECK_GAMMA_FD, i, -1, u[QTY_GAMMA][i], -c->ladder[FD_COARSE][i], &p, h);
        }
    }
    if (nv > 0) {
        vecfn_init(&f, c, FD_PSI_PATH, -1, true, true, scratch);
        for (int i = 0; i < nv; i++)
            compare_first(c, CHECK_GAMMA_FD, nh + i, -1, u[QTY_GAMMA][nh + i], &f, i, 0.0, -1.0);
    }
}

double check_gamma_part(Checker *c, int row, bool path_q, bool path_t, double step,
                  double *scratch, double *vec)
{
    VecFn f;
    if (row < c->nh) {
        vecfn_init(&f, c, FD_PHI_PATH, -1, path_q, path_t, scratch);
        fd_second(&f, c->nh, step > 0.0 ? step : check_second_step(c), vec);
        return -vec[row];
    }
    vecfn_init(&f, c, FD_PSI_PATH, -1, path_q, path_t, scratch);
    return -fd_first(&f, row - c->nh, 0.0, step > 0.0 ? step : c->opt->fd_step);
}
