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
 * Large mechanisms (CheckOptions.linear, auto: above ANALYSIS_DENSE_MAX_NQ
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
 * The pieces: checker.c (the state), engines.c, fd.c, groups.c,
 * dynamics.c (M and Q), design.c (dPhi/dp), hints.c (the verdict and its hints).
 */
#include "check.h"

#include "checker.h"
#include "design.h"
#include "dynamics.h"
#include "engines.h"
#include "fd.h"
#include "groups.h"
#include "hints.h"

#include "../../runtime/mechrt.h"
#include "../analysis/assemble_t0.h"
#include "../analysis/redundant.h"
#include "../base/arena.h"
#include "../base/rng.h"
#include "../kin/run.h"

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

static const char *const fd_names[3] = {"jac", "nu", "gamma"};
static const char *const pair_names[PAIR_COUNT * QTY_COUNT] = {
    "phi jit/generic", "jac jit/generic", "nu jit/generic", "gamma jit/generic",
    "phi jit/aot",     "jac jit/aot",     "nu jit/aot",     "gamma jit/aot",
    "phi generic/aot", "jac generic/aot", "nu generic/aot", "gamma generic/aot",
};
static const char *const dyn_names[CHECK_WHAT_COUNT - CHECK_DYN_FIRST] = {
    "M jit/generic", "Q jit/generic", "M jit/aot", "Q jit/aot", "M generic/aot", "Q generic/aot",
    "M symmetric", "M semi-definite", "Q velocity fd",
    "phi_p", "phi_p jit/generic", "phi_p jit/aot", "phi_p generic/aot",
    "sens jit/generic", "sens jit/aot", "sens generic/aot",
};

/* The base state's Newton (assemble_at_t0's, on the engine under test's
   phi and jac, not its fused all): the runtime's dense Newton, or on the
   sparse path a step of length 0 of run's sparse path (KLU). */
typedef struct BaseNewton {
    Checker *c;
    const MechrtKernels *k;
    const MechrtHostJacNz *jnz;     /* the sparse path's pattern */
} BaseNewton;

static MechrtStatus base_newton(void *ctx, double *q, MechrtReport *rep)
{
    const BaseNewton *b = ctx;
    size_t nq = (size_t)b->c->nq;
    if (!b->c->sparse) {
        size_t lwork = mechrt_workspace_size(b->c->nq, b->k->nh + b->k->nv);
        double *work = xmalloc(lwork * sizeof *work);
        MechrtStatus st = mechrt_assemble(b->k, NULL, q, 0.0, work, lwork, rep);
        free(work);
        return st;
    }
    MechrtHostSparse *s = mechrt_host_sparse_new(b->c->nq, b->jnz);
    double *work = xcalloc(MECHRT_HOST_SPARSE_WORK_LEN(nq) + 2 * nq, sizeof *work);
    double *qd = work + MECHRT_HOST_SPARSE_WORK_LEN(nq), *qdd = qd + nq;
    MechrtStatus st = !s ? MECHRT_EINVAL
                         : mechrt_host_sparse_step(s, b->k, NULL, q, qd, qdd, 0.0, 0.0, work,
                                                   MECHRT_HOST_SPARSE_WORK_LEN(nq), rep);
    mechrt_host_sparse_free(s);
    free(work);
    return st;
}

/* assemble's Newton on the holonomic rows of m, square, with kernels k0
   and pattern jnz. */
static bool assemble_square(Checker *c, const Model *m, const MechrtKernels *k0,
                            const MechrtHostJacNz *jnz, double *q)
{
    MechrtKernels k = *k0;
    if (!c->sparse)
        k.all = NULL;
    BaseNewton b = {c, &k, jnz};
    AssembleT0Options ao = {.t0 = 0.0, .newton = base_newton, .newton_ctx = &b,
                            .robust = !c->sparse, .again = true,
                            .rough = analysis_default_options()};
    AssembleT0Report rep;
    return assemble_at_t0(m, &k, NULL, &ao, q, &rep);
}

/* More holonomic rows than coordinates: assembled on the rows that are
   not redundant (redundant.c, as run), which must drive every coordinate,
   and only where the redundant rows hold there too. */
static bool assemble_redundant(Checker *c, double *q)
{
    Redundant red;
    char why[300];
    const MechrtHostJacNz *jnz = c->jnz[ENGINE_JIT];
    if (!redundant_start(&red, c->m, &c->eng[ENGINE_JIT].k, jnz, 0.0, true, c->opt->notes, why,
                         sizeof why))
        return false;
    int row;
    const char *level;
    bool ok = assemble_square(c, &red.view, &red.k, jnz ? &red.jnz : NULL, q)
              && redundant_check(&red, q, NULL, NULL, 0.0, mechrt_default_options().tol_phi,
                                 &row, &level) <= 1;
    redundant_close(&red);
    return ok;
}

/* The base state: assembled at t = 0 from the initial values when the
   holonomic rows are square (dense: with the robust restarts from rough
   initial values, as run; sparse: none, they are dense) or redundant rows
   make them so, else the initial values. */
static bool assemble(Checker *c, double *q)
{
    memcpy(q, c->m->q0, (size_t)c->nq * sizeof *q);
    bool ok = redundant_applies(c->m) ? assemble_redundant(c, q)
              : c->nh == c->nq && assemble_square(c, c->m, &c->eng[ENGINE_JIT].k,
                                                   c->jnz[ENGINE_JIT], q);
    if (!ok)
        memcpy(q, c->m->q0, (size_t)c->nq * sizeof *q);
    return ok;
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
        it->tol = w < CHECK_PAIR_FIRST || w == CHECK_QV_FD || w == CHECK_PHI_P_FD
                  ? opt->tol : opt->tol_engines;
        it->design_col = w >= CHECK_PHI_P_FD;
        it->row = it->col = -1;
        it->unsettled_row = it->unsettled_col = -1;
    }
}

/* Sparse or dense (CheckOptions.linear) and, sparse, the engines' jac_nz:
   jit's always, aot's when it has the same pattern. */
static void choose_linear(Checker *c)
{
    AnalysisLinear lin = c->opt->linear;
    c->jnz[ENGINE_JIT] = engine_jac_nz(&c->eng[ENGINE_JIT]);
    c->sparse = (lin == ANALYSIS_LINEAR_SPARSE
                 || (lin == ANALYSIS_LINEAR_AUTO && c->nq > ANALYSIS_DENSE_MAX_NQ))
                && c->jnz[ENGINE_JIT];
    if (!c->sparse)
        return;
    c->has_nz[ENGINE_JIT] = true;
    c->nnz = c->jnz[ENGINE_JIT]->jac.nnz;
    const MechrtHostJacNz *j = c->jnz[ENGINE_JIT];
    const MechrtHostJacNz *a = c->open[ENGINE_AOT] ? engine_jac_nz(&c->eng[ENGINE_AOT]) : NULL;
    c->jnz[ENGINE_AOT] = a;
    size_t len_pat = (size_t)j->jac.nnz * sizeof *j->jac.row;
    c->has_nz[ENGINE_AOT] = a && a->jac.nnz == j->jac.nnz
                            && memcmp(a->jac.row, j->jac.row, len_pat) == 0
                            && memcmp(a->jac.col, j->jac.col, len_pat) == 0;
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
        check_under_test(c);
        for (int k = 1; k < ENGINE_KIND_COUNT; k++)
            if (c->open[k])
                check_eval_engine(c, (EngineKind)k);
        for (int pair = 0; pair < PAIR_COUNT; pair++)
            if (c->open[check_pair_engines[pair][0]] && c->open[check_pair_engines[pair][1]])
                check_compare_pair(c, pair);
        check_fd(c, c->scratch, c->vec);
        if (c->dyn)
            check_dynamics(c);
        if (c->m->np > 0)
            check_design(c);
    }
    c->rep->samples = c->opt->samples;
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
    bool ok = check_open_engines(&c, mech, diag);
    if (ok) {
        choose_linear(&c);
        check_take_buffers(&c);
        if (c.sparse)
            check_group_columns(&c);
        sample_loop(&c);
        check_diagnose(&c);
        if (c.eigen)
            gsl_eigen_symm_free(c.eigen);
        arena_free(&c.buffers);
    }
    check_close_engines(&c);
    return ok;
}
