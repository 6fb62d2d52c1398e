/* check.c - compares the generated derivatives with finite differences and the engines with each other.
 *
 * The engine under test is the JIT (the generated C). At sampled states
 * around the assembled configuration (Newton from the initial values at
 * t = 0 when the holonomic rows are square, the initial values otherwise)
 * it compares, for every row:
 *
 *   jac     position rows: dPhi/dq_j by gsl_deriv_central on Phi;
 *           velocity rows: dPsi/dqd_j on Psi (from the generic evaluator,
 *           the only place Psi exists before it is split into a and b);
 *   nu      position rows: -dPhi/dt (gsl_deriv_central);
 *           velocity rows: -Psi(q, 0, t);
 *   gamma   position rows: -(d/dtau)^2 Phi(q + qd tau, t + tau) at tau = 0,
 *           the second total derivative with qdd = 0, by a central second
 *           difference with one Richardson step (error O(h^4));
 *           velocity rows: -d/dtau Psi(q + qd tau, qd, t + tau) at 0;
 *
 * and every pair of engines (jit, generic, aot) on phi, jac, nu, gamma.
 * Errors are |value - reference| / (1 + |reference|).
 *
 * A finite difference is only as good as its step: a row that varies fast
 * (sin(100 x)) leaves a truncation error at the default step that a fixed
 * tolerance takes for a mistake, and a small step drowns in rounding. So a
 * comparison above tolerance is not judged at the default step h alone
 * (compare_fd): the difference is redone at h/r, h/r^2, ... h/r^8 (r = pi),
 * then r h and r^2 h, until three neighbouring steps agree within tol/2
 * (pairwise), and the value is judged against the middle one, whose step
 * is reported. Truncation error shrinks by r^4 (about 100) a step (both
 * differences are O(h^4)) and rounding error grows by r (first) or r^2
 * (second difference), so in three agreeing steps the middle one is clear
 * of both (its truncation below a hundredth of the first pair's spread,
 * its rounding a third or less of the second pair's) and a correct value
 * passes (two noisy steps alone could agree by chance), and r being
 * irrational, agreeing steps are not an aliasing artefact (see FD_STEPS).
 * So a correct value passes however fast its row varies, as long as some
 * run of steps resolves it, while a mistake stays put at every step and
 * still fails, its diagnosis taken at the settled step. Which steps settle
 * depends only on the finite differences, never on the value under test.
 * When no run of steps agrees, the differences cannot tell: the comparison
 * is counted as unsettled, neither passed nor failed, and reported.
 *
 * Large mechanisms (CheckOptions.linear, auto: above RUN_DENSE_MAX_NQ
 * coordinates) are checked on the Jacobian's nonzeros: the engines' jac_nz
 * (the generic interpreter's Jacobian is dense, so its jac is not
 * compared there), the assembly by KLU's Newton step, and the Jacobian's
 * finite differences taken for groups of columns that share no row
 * (Curtis, Powell and Reid, J. Inst. Maths Applics 13, 1974): one
 * difference of Phi (or Psi) with every column of a group moved at once
 * gives, in each row, the entry of the one column of the group the
 * pattern has there, and zero where it has none, so an entry missing from
 * the pattern shows as a nonzero difference where 0 was expected. The
 * groups (greedy colouring) number a handful for a chain: the work per
 * sample grows as nq, not nq^2. The differences are central with one
 * Richardson step (error O(h^4)), on the same ladder of steps as gamma's.
 *
 * Where the worst error passes its tolerance, the two numbers are examined
 * for the classic textbook slips: a ratio of -1 or 2, a missing term, and for
 * gamma a decomposition of the finite difference into its -(Phi_q qd)_q qd,
 * -2 Phi_qt qd and -Phi_tt parts to name the one that was dropped.
 */
#include "check.h"

#include "../../runtime/mechrt.h"
#include "assemble.h"
#include "construct.h"
#include "../base/arena.h"
#include "../base/rng.h"
#include "../engine/aot.h"
#include "../eval/generic.h"
#include "../../runtime/host/mechrt_host.h"

#include <gsl/gsl_deriv.h>
#include <gsl/gsl_eigen.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

CheckOptions check_default_options(void)
{
    return (CheckOptions){
        .samples = 20, .seed = 1, .tol = 1e-6, .tol_engines = 1e-10,
        .spread_q = 0.05, .spread_qd = 1.0, .fd_step = 1e-4, .fd_step2 = 2e-3,
        .use_aot = true, .fault = {.kind = CHECK_FAULT_NONE},
    };
}

enum { QTY_PHI, QTY_JAC, QTY_NU, QTY_GAMMA, QTY_COUNT = CHECK_QTY_COUNT, PAIR_COUNT = CHECK_PAIR_COUNT };

/* The ladder of finite-difference steps: index i is the step
   h * pi^(FD_COARSE - i), the default h at FD_COARSE, pi^2 h first, h/pi^8
   last. The ratio is irrational so that no step is a whole multiple of
   another: a row oscillating a whole number of times over one step (which
   the difference cannot see) does not do so over the next ones, and
   differences that agree across steps are not an aliasing artefact. With
   a ratio of 4, sin(10^4 x) at a qd that fits 10 periods in the default
   step settled, wrongly, at 16h, 4h and h. */
enum { FD_COARSE = 2, FD_FINE = 8, FD_STEPS = FD_COARSE + 1 + FD_FINE };
#define FD_RATIO 3.14159265358979323846
/* Neighbouring steps settle when they agree within this part of the tolerance. */
#define FD_SETTLE 0.5
/* Points cached per function of one variable: the four of gsl_deriv_central
   at each step of the ladder, shared by the rows of one column, and room
   for its adaptive ones. */
enum { FD_CACHE = 4 * FD_STEPS + 8 };

static const char *const fd_names[3] = {"jac", "nu", "gamma"};
static const char *const pair_names[PAIR_COUNT * QTY_COUNT] = {
    "phi jit/generic", "jac jit/generic", "nu jit/generic", "gamma jit/generic",
    "phi jit/aot",     "jac jit/aot",     "nu jit/aot",     "gamma jit/aot",
    "phi generic/aot", "jac generic/aot", "nu generic/aot", "gamma generic/aot",
};
static const char *const dyn_names[CHECK_WHAT_COUNT - CHECK_DYN_FIRST] = {
    "M jit/generic", "Q jit/generic", "M jit/aot", "Q jit/aot", "M generic/aot", "Q generic/aot",
    "M symmetric", "M semi-definite", "Q velocity fd",
};
static const EngineKind pair_engines[PAIR_COUNT][2] = {
    {ENGINE_JIT, ENGINE_GENERIC}, {ENGINE_JIT, ENGINE_AOT}, {ENGINE_GENERIC, ENGINE_AOT},
};

/* The state of one check run. */
typedef struct Checker {
    const Model *m;
    const CheckOptions *opt;
    CheckReport *rep;
    int nq, nh, nv, nr;
    Engine eng[ENGINE_KIND_COUNT];
    bool open[ENGINE_KIND_COUNT];
    double *out[ENGINE_KIND_COUNT][QTY_COUNT];  /* each engine's results at the sample */
    double *base;                               /* the assembled state */
    double *q, *qd, t;                          /* the sample */
    int sample;
    double *qw, *qdw;                           /* perturbed copies */
    double *gamma0;                             /* fault hook scratch */
    double *save_q[3], *save_qd[3];             /* state of each FD item's worst */
    double *d2[5];                              /* second-difference points */
    double *ladder[FD_STEPS];                   /* gamma's second differences at each step */
    bool ladder_have[FD_STEPS];
    double *vec;                                /* one vector of rows */
    bool dyn;                                   /* the file has masses: */
    double *mass[ENGINE_KIND_COUNT];            /* each engine's M (nq*nq) */
    double *force[ENGINE_KIND_COUNT];           /* and Q (nq) at the sample */
    double *mass_nz[ENGINE_KIND_COUNT];         /* and M's nonzeros (engine_mass_nz) */
    double *mw, *mw2, *qv, *qv_fd;              /* M elsewhere; Q's velocity terms */
    gsl_eigen_symm_workspace *eigen;
    double *scratch;                            /* a VecFn's cache (FD_CACHE vectors) */
    /* the sparse comparisons (CheckOptions.linear) */
    bool sparse;
    const MechrtHostJacNz *jnz[ENGINE_KIND_COUNT];  /* jit's and aot's jac_nz */
    bool has_nz[ENGINE_KIND_COUNT];
    int nnz;
    int ngroups;
    int *group_start, *group_cols;              /* the column groups, CSR */
    int *col_start, *col_ent;                   /* each column's entries */
    int *ent;                                   /* nr: the group's entry in each row, or -1 */
    Arena buffers;                              /* owns every array above */
} Checker;

/* ---- the engine under test, with the optional planted fault ---- */

static void under_test(Checker *c)
{
    const Engine *e = &c->eng[ENGINE_JIT];
    double **o = c->out[ENGINE_JIT];
    engine_phi(e, c->q, c->t, o[QTY_PHI]);
    if (c->sparse)
        c->jnz[ENGINE_JIT]->jac.jac_nz(c->jnz[ENGINE_JIT]->jac.ctx, c->q, c->t, o[QTY_JAC]);
    else
        engine_jac(e, c->q, c->t, o[QTY_JAC]);
    engine_nu(e, c->q, c->t, o[QTY_NU]);
    engine_gamma(e, c->q, c->qd, c->t, o[QTY_GAMMA]);
    if (c->dyn) {
        e->k.mass(e->k.ctx, c->q, c->mass[ENGINE_JIT]);
        e->k.force(e->k.ctx, c->q, c->qd, c->t, c->force[ENGINE_JIT]);
        const MechrtHostMassNz *mnz = engine_mass_nz(e);
        mnz->mass_nz(mnz->ctx, c->q, c->mass_nz[ENGINE_JIT]);
    }
    const CheckFault *f = &c->opt->fault;
    if (f->kind == CHECK_FAULT_MASS_SCALE && c->dyn && f->row >= 0 && f->row < c->nq
        && f->col >= 0 && f->col < c->nq)
        c->mass[ENGINE_JIT][(size_t)f->row * (size_t)c->nq + (size_t)f->col] *= f->factor;
    if (f->kind == CHECK_FAULT_NONE || f->row < 0 || f->row >= c->nr)
        return;
    switch (f->kind) {
    case CHECK_FAULT_NONE:
    case CHECK_FAULT_MASS_SCALE:
        break;
    case CHECK_FAULT_JAC_SCALE:
        for (int k = 0; c->sparse && k < c->nnz; k++)
            if (c->jnz[ENGINE_JIT]->jac.row[k] == f->row && c->jnz[ENGINE_JIT]->jac.col[k] == f->col)
                o[QTY_JAC][k] *= f->factor;
        if (!c->sparse && f->col >= 0 && f->col < c->nq)
            o[QTY_JAC][(size_t)f->row * (size_t)c->nq + (size_t)f->col] *= f->factor;
        break;
    case CHECK_FAULT_NU_SCALE:
        o[QTY_NU][f->row] *= f->factor;
        break;
    case CHECK_FAULT_GAMMA_ZERO:
        o[QTY_GAMMA][f->row] = 0.0;
        break;
    case CHECK_FAULT_GAMMA_DROP_TT:
    case CHECK_FAULT_GAMMA_DROP_QD:
        /* with qd = 0 only -Phi_tt is left of gamma */
        memset(c->qdw, 0, (size_t)c->nq * sizeof *c->qdw);
        engine_gamma(e, c->q, c->qdw, c->t, c->gamma0);
        if (f->kind == CHECK_FAULT_GAMMA_DROP_TT)
            o[QTY_GAMMA][f->row] -= c->gamma0[f->row];
        else
            o[QTY_GAMMA][f->row] = c->gamma0[f->row];
        break;
    }
}

/* ---- recording errors ---- */

static double rel_error(double value, double ref)
{
    if (isnan(value) && isnan(ref))
        return 0.0;
    if (!isfinite(value) || !isfinite(ref))
        return value == ref ? 0.0 : INFINITY;
    return fabs(value - ref) / (1.0 + fabs(ref));
}

/* step: of the reference's finite difference (0: exact, or an engine). */
static void record(Checker *c, int what, int row, int col, double value, double ref, double step)
{
    CheckItem *it = &c->rep->items[what];
    double err = rel_error(value, ref);
    if (it->checked && !(err > it->error))
        return;
    it->checked = true;
    it->error = err;
    it->row = row;
    it->col = col;
    it->value = value;
    it->reference = ref;
    it->sample = c->sample;
    it->t = c->t;
    it->step = step;
    if (what < CHECK_PAIR_FIRST) {
        memcpy(c->save_q[what], c->q, (size_t)c->nq * sizeof *c->q);
        memcpy(c->save_qd[what], c->qd, (size_t)c->nq * sizeof *c->qd);
    }
}

/* ---- finite differences ---- */

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

static double second_step(const Checker *c);

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
    if (rel_error(value, d0) <= tol) {
        record(c, what, row, col, value, d0, h * p->scale);
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
                agree = rel_error(d[j - 1], d[j]) <= FD_SETTLE * tol;
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
    record(c, what, row, col, value, d[r], ladder_step(h, r) * p->scale);
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

static void check_fd(Checker *c, double *scratch, double *vec)
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
            record(c, CHECK_NU_FD, nh + i, -1, u[QTY_NU][nh + i], -vec[i], 0.0);
    }
    /* gamma */
    if (nh > 0) {
        vecfn_init(&f, c, FD_PHI_PATH, -1, true, true, scratch);
        double h = second_step(c);
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

/* ---- engines against each other ---- */

static void eval_engine(Checker *c, EngineKind k)
{
    double **o = c->out[k];
    engine_phi(&c->eng[k], c->q, c->t, o[QTY_PHI]);
    if (!c->sparse)
        engine_jac(&c->eng[k], c->q, c->t, o[QTY_JAC]);
    else if (c->has_nz[k])
        c->jnz[k]->jac.jac_nz(c->jnz[k]->jac.ctx, c->q, c->t, o[QTY_JAC]);
    engine_nu(&c->eng[k], c->q, c->t, o[QTY_NU]);
    engine_gamma(&c->eng[k], c->q, c->qd, c->t, o[QTY_GAMMA]);
    if (c->dyn) {
        const MechrtKernels *mk = &c->eng[k].k;
        mk->mass(mk->ctx, c->q, c->mass[k]);
        mk->force(mk->ctx, c->q, c->qd, c->t, c->force[k]);
        const MechrtHostMassNz *mnz = engine_mass_nz(&c->eng[k]);
        mnz->mass_nz(mnz->ctx, c->q, c->mass_nz[k]);
    }
}

static void compare_pair(Checker *c, int pair)
{
    EngineKind a = pair_engines[pair][0], b = pair_engines[pair][1];
    int nq = c->nq;
    for (int qty = 0; qty < QTY_COUNT; qty++) {
        int what = CHECK_PAIR_FIRST + pair * QTY_COUNT + qty;
        bool nz = c->sparse && qty == QTY_JAC;
        if (nz && !(c->has_nz[a] && c->has_nz[b]))
            continue;   /* the generic interpreter's Jacobian is dense */
        int n = qty == QTY_PHI ? c->nh : nz ? c->nnz : qty == QTY_JAC ? c->nr * nq : c->nr;
        for (int i = 0; i < n; i++) {
            int row = nz ? c->jnz[ENGINE_JIT]->jac.row[i] : qty == QTY_JAC ? i / nq : i;
            int col = nz ? c->jnz[ENGINE_JIT]->jac.col[i] : qty == QTY_JAC ? i % nq : -1;
            record(c, what, row, col, c->out[a][qty][i], c->out[b][qty][i], 0.0);
        }
        if (n == 0)
            c->rep->items[what].checked = true;
    }
    for (int qty = 0; qty < 2 && c->dyn; qty++) {     /* M, then Q: col names the coordinate */
        int what = CHECK_DYN_FIRST + 2 * pair + qty;
        const double *va = qty == 0 ? c->mass[a] : c->force[a], *vb = qty == 0 ? c->mass[b] : c->force[b];
        for (int i = 0; i < (qty == 0 ? nq * nq : nq); i++)
            record(c, what, -1, i % nq, va[i], vb[i], 0.0);
    }
    /* M's nonzeros (what sim's sparse path calls) count under M: every
       engine writes them in the generated kernel's pattern. */
    const MechrtHostMassNz *mnz = c->dyn ? engine_mass_nz(&c->eng[a]) : NULL;
    for (int i = 0; mnz && i < mnz->nnz; i++)
        record(c, CHECK_DYN_FIRST + 2 * pair, -1, mnz->col[i], c->mass_nz[a][i],
               c->mass_nz[b][i], 0.0);
}

/* ---- dynamics: M's symmetry and definiteness, Q's velocity terms ---- */

/* The smallest eigenvalue of the jit's M, made relative: the error is
   max(0, -lambda_min) / (1 + max |lambda|). */
static void check_definite(Checker *c)
{
    size_t nq = (size_t)c->nq;
    memcpy(c->mw, c->mass[ENGINE_JIT], nq * nq * sizeof *c->mw);
    gsl_matrix_view a = gsl_matrix_view_array(c->mw, nq, nq);
    gsl_vector_view ev = gsl_vector_view_array(c->qv, nq);
    gsl_eigen_symm(&a.matrix, &ev.vector, c->eigen);
    double lo = c->qv[0], big = 0.0;
    for (size_t i = 0; i < nq; i++) {
        lo = fmin(lo, c->qv[i]);
        big = fmax(big, fabs(c->qv[i]));
    }
    record(c, CHECK_M_PSD, -1, -1, fmax(0.0, -lo) / (1.0 + big), 0.0, 0.0);
}

/* The jit's M at q + x dir (dir a unit column j >= 0, or qd) into out. */
static void mass_at(Checker *c, int j, double x, double *out)
{
    for (int i = 0; i < c->nq; i++)
        c->qw[i] = c->q[i] + x * (j >= 0 ? (i == j) : c->qd[i]);
    const MechrtKernels *k = &c->eng[ENGINE_JIT].k;
    k->mass(k->ctx, c->qw, out);
}

/* Lagrange: the velocity terms are -(d/dt(M qd) - dT/dq) with qdd = 0,
   -(M_dot qd)_i + 1/2 qd^T M_{q_i} qd, by central differences of the jit's
   M, against the generic evaluator's own velocity terms. */
static void check_velocity_terms(Checker *c)
{
    int nq = c->nq;
    double h = c->opt->fd_step;
    for (int i = 0; i < nq; i++)
        c->qv_fd[i] = 0.0;
    mass_at(c, -1, h, c->mw);
    mass_at(c, -1, -h, c->mw2);
    for (int i = 0; i < nq; i++)
        for (int k = 0; k < nq; k++)
            c->qv_fd[i] -= (c->mw[(size_t)i * nq + k] - c->mw2[(size_t)i * nq + k]) / (2 * h) * c->qd[k];
    for (int j = 0; j < nq; j++) {
        double hj = h * fmax(1.0, fabs(c->q[j]));
        mass_at(c, j, hj, c->mw);
        mass_at(c, j, -hj, c->mw2);
        double quad = 0.0;
        for (int i = 0; i < nq; i++)
            for (int k = 0; k < nq; k++)
                quad += c->qd[i] * (c->mw[(size_t)i * nq + k] - c->mw2[(size_t)i * nq + k]) * c->qd[k];
        c->qv_fd[j] += 0.5 * quad / (2 * hj);
    }
    generic_velocity_terms(c->eng[ENGINE_GENERIC].generic, c->q, c->qd, c->qv);
    for (int i = 0; i < nq; i++)
        record(c, CHECK_QV_FD, -1, i, c->qv[i], c->qv_fd[i], h);
}

static void check_dynamics(Checker *c)
{
    int nq = c->nq;
    const double *m = c->mass[ENGINE_JIT];
    for (int i = 0; i < nq; i++)
        for (int j = 0; j < i; j++)
            record(c, CHECK_M_SYMMETRIC, -1, j, m[(size_t)i * nq + j], m[(size_t)j * nq + i], 0.0);
    if (nq == 1)
        c->rep->items[CHECK_M_SYMMETRIC].checked = true;
    check_definite(c);
    check_velocity_terms(c);
}

/* ---- diagnosis ---- */

static bool near(double a, double b, double tol)
{
    return fabs(a - b) <= tol * (1.0 + fabs(b));
}

/* The ratio patterns between value and reference. */
typedef enum Ratio { RATIO_NONE, RATIO_NEG, RATIO_TWO, RATIO_HALF } Ratio;

static Ratio ratio_of(double v, double r, double tol)
{
    if (r == 0.0)
        return RATIO_NONE;
    if (near(v, -r, 10 * tol))
        return RATIO_NEG;
    if (near(v, 2.0 * r, 10 * tol))
        return RATIO_TWO;
    if (near(v, 0.5 * r, 10 * tol))
        return RATIO_HALF;
    return RATIO_NONE;
}

static void hint_jac(const Checker *c, CheckItem *it)
{
    double tol = c->opt->tol;
    bool velocity = it->row >= c->nh;
    switch (ratio_of(it->value, it->reference, tol)) {
    case RATIO_NEG:
        snprintf(it->hint, sizeof it->hint, "the sign is wrong (value = -reference): e.g. d(P_A - P_B)/dq "
                 "written for P_B - P_A, or B = dA/dphi taken with the wrong sign");
        return;
    case RATIO_TWO:
        snprintf(it->hint, sizeof it->hint, "a factor 2 too many (value = 2 x reference): e.g. a term "
                 "added twice, or d(d.d)/dq taken as 4 d.d_q");
        return;
    case RATIO_HALF:
        snprintf(it->hint, sizeof it->hint, "a factor 2 missing (value = reference / 2): e.g. "
                 "d(d.d)/dq = 2 d.d_q with the 2 dropped");
        return;
    case RATIO_NONE:
        break;
    }
    if (it->value == 0.0)
        snprintf(it->hint, sizeof it->hint, "a Jacobian term is missing%s",
                 velocity ? " (a der() coefficient left out)"
                          : " (e.g. the B s column of a body-fixed point)");
    else if (fabs(it->reference) <= tol)
        snprintf(it->hint, sizeof it->hint,
                 "a spurious entry: the row does not change with this coordinate");
    else
        snprintf(it->hint, sizeof it->hint, "no classic pattern: compare the row's formula term by term");
}

static void hint_nu(const Checker *c, CheckItem *it)
{
    switch (ratio_of(it->value, it->reference, c->opt->tol)) {
    case RATIO_NEG:
        snprintf(it->hint, sizeof it->hint, "the sign is wrong: nu = -Phi_t (Phi_q qd = nu), not +Phi_t");
        return;
    case RATIO_TWO:
        snprintf(it->hint, sizeof it->hint, "a factor 2 too many (value = 2 x reference)");
        return;
    case RATIO_HALF:
        snprintf(it->hint, sizeof it->hint, "a factor 2 missing (value = reference / 2)");
        return;
    case RATIO_NONE:
        break;
    }
    if (it->value == 0.0)
        snprintf(it->hint, sizeof it->hint,
                 "Phi_t is missing: a time-dependent driver, length or angle treated as constant");
    else
        snprintf(it->hint, sizeof it->hint, "no classic pattern: check the row's time dependence");
}

/* The second difference's step: its rounding error grows like
   eps |q| / h^2 (rows are differences of coordinates of size |q|), its
   truncation error like h^4, so the best h grows like |q|^(1/6). */
static double second_step(const Checker *c)
{
    double qmax = 1.0;
    for (int i = 0; i < c->nq; i++)
        qmax = fmax(qmax, fabs(c->q[i]));
    return c->opt->fd_step2 * pow(qmax, 1.0 / 6.0);
}

/* -(d/dtau)^2 of one position row (or -d/dtau of one velocity row) along
   the path with only q moving, or only t, at the step of the reference
   (absolute; both paths are at tau = 0, so no scale applies). */
static double gamma_part(Checker *c, int row, bool path_q, bool path_t, double step, double *scratch,
                         double *vec)
{
    VecFn f;
    if (row < c->nh) {
        vecfn_init(&f, c, FD_PHI_PATH, -1, path_q, path_t, scratch);
        fd_second(&f, c->nh, step > 0.0 ? step : second_step(c), vec);
        return -vec[row];
    }
    vecfn_init(&f, c, FD_PSI_PATH, -1, path_q, path_t, scratch);
    return -fd_first(&f, row - c->nh, 0.0, step > 0.0 ? step : c->opt->fd_step);
}

static void hint_gamma(Checker *c, CheckItem *it, double *scratch, double *vec)
{
    double tol = 10 * c->opt->tol, v = it->value, r = it->reference;
    /* back to the worst state to split the reference into its parts */
    memcpy(c->q, c->save_q[CHECK_GAMMA_FD], (size_t)c->nq * sizeof *c->q);
    memcpy(c->qd, c->save_qd[CHECK_GAMMA_FD], (size_t)c->nq * sizeof *c->qd);
    c->t = it->t;
    double gq = gamma_part(c, it->row, true, false, it->step, scratch, vec);   /* -(Phi_q qd)_q qd */
    double gt = gamma_part(c, it->row, false, true, it->step, scratch, vec);   /* -Phi_tt */
    double gx = r - gq - gt;                                         /* -2 Phi_qt qd */
    bool velocity = it->row >= c->nh;
    struct { double value; const char *text; } cand[] = {
        {-r, velocity ? "the sign is wrong: gamma = -(Psi_q qd + Psi_t)"
                      : "the sign is wrong: Phi_q qdd = gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt"},
        {r - gt, velocity ? "the term -Psi_t is missing (the time derivative of a der() coefficient or right side)"
                          : "the term -Phi_tt is missing (the second time derivative of a driver, length or angle)"},
        {r - gq, velocity ? "the term -Psi_q qd is missing (the coefficients' change along the motion)"
                          : "the quadratic velocity term -(Phi_q qd)_q qd is missing (e.g. A s phi'^2 of a revolute)"},
        {r - gx, "the mixed term -2 Phi_qt qd is missing"},
        {r - 0.5 * gx, "the mixed term is counted once: -Phi_qt qd instead of -2 Phi_qt qd"},
        {r - 2.0 * gq, "the quadratic velocity term has the wrong sign"},
        {2.0 * r, "a factor 2 too many (value = 2 x reference)"},
        {0.5 * r, "a factor 2 missing (value = reference / 2)"},
    };
    for (size_t k = 0; k < sizeof cand / sizeof *cand; k++) {
        if (!near(cand[k].value, r, tol) && near(v, cand[k].value, tol)) {
            snprintf(it->hint, sizeof it->hint, "%s", cand[k].text);
            return;
        }
    }
    if (v == 0.0)
        snprintf(it->hint, sizeof it->hint, "gamma of this row is missing altogether");
    else
        snprintf(it->hint, sizeof it->hint, "no classic pattern: compare the row's gamma term by term");
}

static void hint_pair(const Checker *c, CheckItem *it, int pair, int qty)
{
    int fd = qty == QTY_JAC ? CHECK_JAC_FD : qty == QTY_NU ? CHECK_NU_FD : qty == QTY_GAMMA ? CHECK_GAMMA_FD : -1;
    const CheckItem *f = fd >= 0 ? &c->rep->items[fd] : NULL;
    const char *kind = joint_info[c->m->rows[it->row].kind].keyword;
    if (pair == 1)
        snprintf(it->hint, sizeof it->hint,
                 "the same C differs under libtcc and cc: suspect a compiler or math library difference");
    else if (f && f->checked && !(f->error <= f->tol))
        snprintf(it->hint, sizeof it->hint,
                 "the generated code fails against finite differences too (see above)");
    else if (f)
        snprintf(it->hint, sizeof it->hint, "the generated code agrees with finite differences: "
                 "suspect the generic evaluator's %s formula", kind);
    else
        snprintf(it->hint, sizeof it->hint, "suspect the generic evaluator's %s formula, "
                 "or the row's lowering in generator/model/joints.c", kind);
}

/* ---- the run ---- */

/* The base state: Newton from the initial values at t = 0 when the
   holonomic rows are square (minimum-norm Newton with restarts from rough
   ones), else the initial values. */

/* The sparse path's assembly: the construction, then Newton with KLU (a
   step of length 0 of run's sparse path); no rough-guess fallback (it is
   dense). */
static bool assemble_klu(Checker *c, const MechrtKernels *k, double *q)
{
    size_t nq = (size_t)c->nq;
    MechrtHostSparse *s = mechrt_host_sparse_new(c->nq, c->jnz[ENGINE_JIT]);
    double *work = xcalloc(MECHRT_HOST_SPARSE_WORK_LEN(nq) + 2 * nq, sizeof *work);
    double *qd = work + MECHRT_HOST_SPARSE_WORK_LEN(nq), *qdd = qd + nq;
    construct_with_kernels(c->m, k, 0.0, q);
    bool ok = s && mechrt_host_sparse_step(s, k, NULL, q, qd, qdd, 0.0, 0.0, work,
                                           MECHRT_HOST_SPARSE_WORK_LEN(nq), NULL) == MECHRT_OK;
    mechrt_host_sparse_free(s);
    free(work);
    if (!ok)
        memcpy(q, c->m->q0, nq * sizeof *q);
    return ok;
}

static bool assemble(Checker *c, double *q)
{
    memcpy(q, c->m->q0, (size_t)c->nq * sizeof *q);
    if (c->nh != c->nq)
        return false;
    if (c->sparse) {
        MechrtKernels k = c->eng[ENGINE_JIT].k;
        return assemble_klu(c, &k, q);
    }
    /* Newton on the engine under test's phi and jac, not its fused all */
    MechrtKernels k = c->eng[ENGINE_JIT].k;
    k.all = NULL;
    size_t lwork = mechrt_workspace_size(c->nq, c->nr);
    double *work = xmalloc(lwork * sizeof *work);
    construct_with_kernels(c->m, &k, 0.0, q);
    MechrtStatus st = mechrt_assemble(&k, NULL, q, 0.0, work, lwork, NULL);
    if (st != MECHRT_OK) {
        /* rough initial values: as run assembles them (run.c) */
        AnalysisOptions ao = analysis_default_options();
        ao.stall_iter = ASSEMBLE_ROUGH_STALL;
        AssembleResult ar;
        memcpy(q, c->m->q0, (size_t)c->nq * sizeof *q);
        construct_with_kernels(c->m, &k, 0.0, q);
        if (assemble_restarting(&k, 0.0, q, &ao, &ar)
            && mechrt_assemble(&k, NULL, q, 0.0, work, lwork, NULL) == MECHRT_OK)
            st = MECHRT_OK;
    }
    free(work);
    if (st != MECHRT_OK)
        memcpy(q, c->m->q0, (size_t)c->nq * sizeof *q);
    return st == MECHRT_OK;
}

/* Uniform in [lo, hi) from the shared deterministic generator. */
static double uniform(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * rng_unit(s);
}

/* Item names, tolerances and "nowhere yet". */
static void init_items(CheckReport *rep, const CheckOptions *opt)
{
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        CheckItem *it = &rep->items[w];
        it->what = w < CHECK_PAIR_FIRST ? fd_names[w]
                   : w < CHECK_DYN_FIRST ? pair_names[w - CHECK_PAIR_FIRST]
                   : dyn_names[w - CHECK_DYN_FIRST];
        it->tol = w < CHECK_PAIR_FIRST || w == CHECK_QV_FD ? opt->tol : opt->tol_engines;
        it->row = it->col = -1;
        it->unsettled_row = it->unsettled_col = -1;
    }
}

/* jit and generic always, aot when asked for and a compiler exists (else
   rep->note says why not). False with diag filled when one fails. */
static bool open_engines(Checker *c, const Mech *mech, Diag *diag)
{
    CheckReport *rep = c->rep;
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        if (k == ENGINE_AOT && !c->opt->use_aot) {
            snprintf(rep->note, sizeof rep->note, "aot not compared (not asked for)");
            continue;
        }
        if (k == ENGINE_AOT && !aot_compiler_available()) {
            snprintf(rep->note, sizeof rep->note, "aot not compared: no C compiler found (set CC)");
            continue;
        }
        c->open[k] = engine_open(&c->eng[k], (EngineKind)k, mech, diag);
        rep->engine_used[k] = c->open[k];
        if (!c->open[k])
            return false;
    }
    return true;
}

static void close_engines(Checker *c)
{
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (c->open[k])
            engine_close(&c->eng[k]);
}

static double *take(Checker *c, size_t n)
{
    return arena_alloc_array(&c->buffers, n, sizeof(double));
}

/* Every working array, zero-filled, from c->buffers. */
static void take_buffers(Checker *c)
{
    size_t nq = (size_t)c->nq, nr = (size_t)c->nr, nvec = (size_t)(c->nh > c->nv ? c->nh : c->nv) + 1;
    arena_init(&c->buffers);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        c->out[k][QTY_PHI] = take(c, nvec);
        c->out[k][QTY_JAC] = take(c, c->sparse ? (size_t)c->nnz + 1 : nr * nq);
        c->out[k][QTY_NU] = take(c, nr);
        c->out[k][QTY_GAMMA] = take(c, nr);
    }
    c->base = take(c, nq);
    c->q = take(c, nq);
    c->qd = take(c, nq);
    c->qw = take(c, nq);
    c->qdw = take(c, nq);
    for (int k = 0; k < 3; k++) {
        c->save_q[k] = take(c, nq);
        c->save_qd[k] = take(c, nq);
    }
    c->gamma0 = take(c, nr);
    for (int k = 0; k < 5; k++)
        c->d2[k] = take(c, nvec);
    for (int k = 0; k < FD_STEPS; k++)
        c->ladder[k] = take(c, nvec);
    c->vec = take(c, nvec);
    c->scratch = take(c, FD_CACHE * nvec);
    for (int k = 0; k < ENGINE_KIND_COUNT && c->dyn; k++) {
        c->mass[k] = take(c, nq * nq);
        c->force[k] = take(c, nq);
        c->mass_nz[k] = take(c, (size_t)engine_mass_nz(&c->eng[ENGINE_JIT])->nnz + 1);
    }
    if (c->dyn) {
        c->mw = take(c, nq * nq);
        c->mw2 = take(c, nq * nq);
        c->qv = take(c, nq);
        c->qv_fd = take(c, nq);
        c->eigen = gsl_eigen_symm_alloc(nq);
    }
}

/* Counting sort of the entries by key (n keys): start (n + 1) and the
   entries in key order. */
static void entries_by(Checker *c, const int *key, int n, int **start, int **ent)
{
    *start = arena_alloc_array(&c->buffers, (size_t)n + 1, sizeof **start);
    *ent = arena_alloc_array(&c->buffers, (size_t)c->nnz + 1, sizeof **ent);
    int *next = xcalloc((size_t)n + 1, sizeof *next);
    for (int e = 0; e < c->nnz; e++)
        (*start)[key[e] + 1]++;
    for (int i = 0; i < n; i++)
        next[i] = (*start)[i + 1] += (*start)[i];
    for (int i = 0; i < n; i++)
        next[i] = (*start)[i];
    for (int e = 0; e < c->nnz; e++)
        (*ent)[next[key[e]]++] = e;
    free(next);
}

/* The column groups: greedy colouring in column order, a column taking the
   first group none of whose columns shares a row with it. */
static void group_columns(Checker *c)
{
    const MechrtHostJacNz *j = c->jnz[ENGINE_JIT];
    int *row_start, *row_ent;
    entries_by(c, j->jac.row, c->nr, &row_start, &row_ent);
    entries_by(c, j->jac.col, c->nq, &c->col_start, &c->col_ent);
    int *color = xmalloc(((size_t)c->nq + 1) * sizeof *color);
    int *mark = xmalloc(((size_t)c->nq + 1) * sizeof *mark);
    for (int k = 0; k < c->nq; k++)
        color[k] = mark[k] = -1;
    c->ngroups = 0;
    for (int col = 0; col < c->nq; col++) {
        for (int a = c->col_start[col]; a < c->col_start[col + 1]; a++) {
            int r = j->jac.row[c->col_ent[a]];
            for (int b = row_start[r]; b < row_start[r + 1]; b++) {
                int other = j->jac.col[row_ent[b]];
                if (color[other] >= 0)
                    mark[color[other]] = col;
            }
        }
        int g = 0;
        while (g < c->ngroups && mark[g] == col)
            g++;
        color[col] = g;
        c->ngroups += g == c->ngroups;
    }
    c->group_start = arena_alloc_array(&c->buffers, (size_t)c->ngroups + 1, sizeof *c->group_start);
    c->group_cols = arena_alloc_array(&c->buffers, (size_t)c->nq + 1, sizeof *c->group_cols);
    for (int col = 0; col < c->nq; col++)
        c->group_start[color[col] + 1]++;
    for (int g = 0; g < c->ngroups; g++) {
        c->group_start[g + 1] += c->group_start[g];
        mark[g] = c->group_start[g];
    }
    for (int col = 0; col < c->nq; col++)
        c->group_cols[mark[color[col]]++] = col;
    c->ent = arena_alloc_array(&c->buffers, (size_t)c->nr + 1, sizeof *c->ent);
    for (int r = 0; r < c->nr; r++)
        c->ent[r] = -1;
    free(color), free(mark);
}

/* Sparse or dense (CheckOptions.linear) and, sparse, the engines' jac_nz:
   jit's always, aot's when it has the same pattern. */
static void choose_linear(Checker *c)
{
    RunLinear lin = c->opt->linear;
    c->jnz[ENGINE_JIT] = engine_jac_nz(&c->eng[ENGINE_JIT]);
    c->sparse = (lin == RUN_LINEAR_SPARSE || (lin == RUN_LINEAR_AUTO && c->nq > RUN_DENSE_MAX_NQ))
                && c->jnz[ENGINE_JIT];
    if (!c->sparse)
        return;
    c->has_nz[ENGINE_JIT] = true;
    c->nnz = c->jnz[ENGINE_JIT]->jac.nnz;
    const MechrtHostJacNz *j = c->jnz[ENGINE_JIT];
    const MechrtHostJacNz *a = c->open[ENGINE_AOT] ? engine_jac_nz(&c->eng[ENGINE_AOT]) : NULL;
    c->jnz[ENGINE_AOT] = a;
    c->has_nz[ENGINE_AOT] = a && a->jac.nnz == j->jac.nnz
                            && memcmp(a->jac.row, j->jac.row, (size_t)j->jac.nnz * sizeof *j->jac.row) == 0
                            && memcmp(a->jac.col, j->jac.col, (size_t)j->jac.nnz * sizeof *j->jac.col) == 0;
    c->rep->sparse = true;
    size_t len = strlen(c->rep->note);
    snprintf(c->rep->note + len, sizeof c->rep->note - len, "%ssparse: the Jacobian's %d nonzeros "
             "(finite differences by %s), the generic engine's jac not compared (dense)",
             len ? "; " : "", c->nnz, "column groups");
}

/* Sample s: the assembled state itself at s = 0, then random states
   around it (the draws' order fixes the states for a seed). */
static void draw_sample(Checker *c, int s, uint64_t *rng)
{
    const CheckOptions *opt = c->opt;
    c->sample = s;
    for (int i = 0; i < c->nq; i++) {
        c->q[i] = c->base[i] + (s == 0 ? 0.0 : uniform(rng, -opt->spread_q, opt->spread_q));
        c->qd[i] = uniform(rng, -opt->spread_qd, opt->spread_qd);
    }
    c->t = s == 0 ? 0.0 : uniform(rng, 0.0, 1.0);
}

/* Every comparison at every sample, recorded in the report's items. */
static void sample_loop(Checker *c)
{
    c->rep->assembled = assemble(c, c->base);
    uint64_t rng = (uint64_t)c->opt->seed * 0x2545f4914f6cdd1dull + 1;
    for (int s = 0; s < c->opt->samples; s++) {
        draw_sample(c, s, &rng);
        under_test(c);
        for (int k = 1; k < ENGINE_KIND_COUNT; k++)
            if (c->open[k])
                eval_engine(c, (EngineKind)k);
        for (int pair = 0; pair < PAIR_COUNT; pair++)
            if (c->open[pair_engines[pair][0]] && c->open[pair_engines[pair][1]])
                compare_pair(c, pair);
        check_fd(c, c->scratch, c->vec);
        if (c->dyn)
            check_dynamics(c);
    }
    c->rep->samples = c->opt->samples;
}

/* The verdict, and a hint for every item above its tolerance. */
static void diagnose(Checker *c)
{
    CheckReport *rep = c->rep;
    rep->ok = true;
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        CheckItem *it = &rep->items[w];
        if (!it->checked || it->error <= it->tol)
            continue;
        rep->ok = false;
        if (w == CHECK_JAC_FD)
            hint_jac(c, it);
        else if (w == CHECK_NU_FD)
            hint_nu(c, it);
        else if (w == CHECK_GAMMA_FD)
            hint_gamma(c, it, c->scratch, c->vec);
    }
    for (int w = CHECK_PAIR_FIRST; w < CHECK_DYN_FIRST; w++) {
        CheckItem *it = &rep->items[w];
        if (it->checked && !(it->error <= it->tol))
            hint_pair(c, it, (w - CHECK_PAIR_FIRST) / QTY_COUNT, (w - CHECK_PAIR_FIRST) % QTY_COUNT);
    }
    static const char *const dyn_hints[] = {
        "the generated M or Q and the engine's differ: compare the mass element's or force's "
        "lowering (generator/diff/dynamics.c) with generic_dynamics.c",
        "M is not symmetric: an entry was added to one triangle only",
        "M has a negative eigenvalue: a negative mass or J, or a wrong sign in p_q",
        "the velocity terms disagree with the kinetic energy's: a dropped or doubled "
        "convective term (pdot_q qd)",
    };
    for (int w = CHECK_DYN_FIRST; w < CHECK_WHAT_COUNT; w++) {
        CheckItem *it = &rep->items[w];
        int h = w < CHECK_M_SYMMETRIC ? 0 : 1 + (w - CHECK_M_SYMMETRIC);
        if (it->checked && !(it->error <= it->tol))
            snprintf(it->hint, sizeof it->hint, "%s", dyn_hints[h]);
    }
}

bool check_mechanism(const Mech *mech, const CheckOptions *opt, CheckReport *rep, Diag *diag)
{
    CheckOptions defaults = check_default_options();
    if (!opt)
        opt = &defaults;
    memset(rep, 0, sizeof *rep);
    const Model *m = mech->model;
    Checker c = {.m = m, .opt = opt, .rep = rep, .nq = m->nq, .nh = m->nh, .nv = m->nv, .nr = m->nr,
                 .dyn = m->nmasses > 0};
    init_items(rep, opt);
    bool ok = open_engines(&c, mech, diag);
    if (ok) {
        choose_linear(&c);
        take_buffers(&c);
        if (c.sparse)
            group_columns(&c);
        sample_loop(&c);
        diagnose(&c);
        if (c.eigen)
            gsl_eigen_symm_free(c.eigen);
        arena_free(&c.buffers);
    }
    close_engines(&c);
    return ok;
}
