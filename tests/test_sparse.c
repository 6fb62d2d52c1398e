/* test_sparse.c - the sparse path of run: KLU on the Jacobian's nonzeros (runtime/host/sparse_*.c) against the dense LU.
 *
 * First the KLU module alone on small matrices with known answers (solve,
 * refactorisation with new values, the failing pivot named by its row and
 * column, NaN, bad patterns); then run_analysis with --linear dense and
 * sparse on the slider-crank, four-bar and five-bar (fine and coarse steps,
 * so the predictor, the substeps and the branch check are exercised) and a
 * chain of 50 four-bar loops: the same states to 1e-10, the same Newton
 * iteration and substep counts; the toggle failing at t = 0.25 with its row
 * and coordinate named; what sparse refuses. Runs from the repository root.
 */
#include "testutil.h"
#include "testload.h"

#include <stdlib.h>
#include <string.h>

#include "../generator/analysis/run.h"
#include "../generator/pipeline/pipeline.h"
#include "../runtime/host/mechrt_host.h"

/* ---- the KLU module ---------------------------------------------------- */

/* A 3 x 3 pattern, row-major as generated code lists it:
 *   [ a 0 b ]
 *   [ c d 0 ]
 *   [ 0 e f ]                                                             */
static const int p_row[] = {0, 0, 1, 1, 2, 2};
static const int p_col[] = {0, 2, 0, 1, 1, 2};

static void fill_vals(void *ctx, const double *q, double t, double *vals)
{
    (void)t;
    const double *v = ctx;
    for (int e = 0; e < 6; e++)
        vals[e] = v[e] * q[0];
}

static MechrtHostJacNz small_pattern(double *v)
{
    return (MechrtHostJacNz){6, p_row, p_col, v, fill_vals};
}

static void test_klu_solve(void **state)
{
    (void)state;
    double v[6] = {2, 1, 1, 3, 1, 4};    /* a b c d e f */
    MechrtHostJacNz j = small_pattern(v);
    MechrtHostSparse *s = mechrt_host_sparse_new(3, &j);
    assert_non_null(s);
    assert_int_equal(mechrt_host_sparse_nnz(s), 6);
    double one = 1;
    mechrt_host_sparse_eval(s, &one, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_OK);
    /* x = (1, 2, 3): b = (2 + 3, 1 + 6, 2 + 12) */
    double b[3] = {5, 7, 14};
    assert_int_equal(mechrt_host_sparse_solve(s, b), MECHRT_OK);
    assert_near(b[0], 1, 1e-14, 0);
    assert_near(b[1], 2, 1e-14, 0);
    assert_near(b[2], 3, 1e-14, 0);
    /* new values, same pattern: twice the matrix (the refactorisation path) */
    double two = 2;
    mechrt_host_sparse_eval(s, &two, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_OK);
    double b2[3] = {5, 7, 14};
    assert_int_equal(mechrt_host_sparse_solve(s, b2), MECHRT_OK);
    assert_near(b2[0], 0.5, 1e-14, 0);
    assert_near(b2[2], 1.5, 1e-14, 0);
    long fresh, re;
    mechrt_host_sparse_counts(s, &fresh, &re);
    assert_int_equal(fresh, 1);
    assert_int_equal(re, 1);
    /* the 1-norm condition estimate of a 3 x 3 is exact: ||A||_1 ||A^-1||_1 */
    double c = mechrt_host_sparse_condest(s);
    assert_true(c >= 1 && c < 100);
    mechrt_host_sparse_free(s);
}

static void test_klu_singular_named(void **state)
{
    (void)state;
    /* [1 0 1; 1 1 0; 0 1 -1]: det = a d f + b c e = -1 + 1 = 0 */
    double v[6] = {1, 1, 1, 1, 1, -1};
    MechrtHostJacNz j = small_pattern(v);
    MechrtHostSparse *s = mechrt_host_sparse_new(3, &j);
    assert_non_null(s);
    double one = 1;
    mechrt_host_sparse_eval(s, &one, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_ESING);
    int row, col;
    mechrt_host_sparse_singular(s, &row, &col);
    assert_true(row >= 0 && row < 3);
    assert_true(col >= 0 && col < 3);
    double b[3] = {1, 1, 1};
    assert_int_equal(mechrt_host_sparse_solve(s, b), MECHRT_EINVAL);   /* no factors kept */
    /* regular again: a fresh factorisation */
    v[5] = 4;
    mechrt_host_sparse_eval(s, &one, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_OK);
    mechrt_host_sparse_singular(s, &row, &col);
    assert_int_equal(row, -1);
    assert_int_equal(col, -1);
    /* NaN: its row named */
    v[3] = NAN;
    mechrt_host_sparse_eval(s, &one, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_ENOTFINITE);
    mechrt_host_sparse_singular(s, &row, &col);
    assert_int_equal(row, 1);
    mechrt_host_sparse_free(s);
}

/* A refactorisation whose kept pivot order has gone bad pivots afresh:
   [a b; c d] first pivots on a, then a becomes tiny. */
static const int full_row[] = {0, 0, 1, 1};
static const int full_col[] = {0, 1, 0, 1};

static void fill_full(void *ctx, const double *q, double t, double *vals)
{
    (void)q, (void)t;
    memcpy(vals, ctx, 4 * sizeof *vals);
}

static void test_klu_repivots(void **state)
{
    (void)state;
    double v[4] = {1, 1, 1e-3, 2};
    MechrtHostJacNz j = {4, full_row, full_col, v, fill_full};
    MechrtHostSparse *s = mechrt_host_sparse_new(2, &j);
    assert_non_null(s);
    mechrt_host_sparse_eval(s, NULL, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_OK);
    v[0] = 1e-9;
    v[2] = 1;
    mechrt_host_sparse_eval(s, NULL, 0);
    assert_int_equal(mechrt_host_sparse_factor(s, 1e-12), MECHRT_OK);
    long fresh, re;
    mechrt_host_sparse_counts(s, &fresh, &re);
    assert_int_equal(fresh, 2);
    assert_int_equal(re, 0);
    /* x = (1, 1): b = (1e-9 + 1, 1 + 2), to full accuracy */
    double b[2] = {1 + 1e-9, 3};
    assert_int_equal(mechrt_host_sparse_solve(s, b), MECHRT_OK);
    assert_near(b[0], 1, 1e-15, 0);
    assert_near(b[1], 1, 1e-15, 0);
    mechrt_host_sparse_free(s);
}

static void test_klu_bad_pattern(void **state)
{
    (void)state;
    double v[6] = {1, 1, 1, 1, 1, 1};
    static const int dup_col[] = {0, 0, 0, 1, 1, 2};    /* (0, 0) twice */
    MechrtHostJacNz j = {6, p_row, dup_col, v, fill_vals};
    assert_null(mechrt_host_sparse_new(3, &j));
    static const int far_col[] = {0, 3, 0, 1, 1, 2};    /* column 3 of 3 */
    j.col = far_col;
    assert_null(mechrt_host_sparse_new(3, &j));
    j.col = p_col;
    assert_null(mechrt_host_sparse_new(0, &j));
    j.jac_nz = NULL;
    assert_null(mechrt_host_sparse_new(3, &j));
}

/* ---- runs, dense against sparse --------------------------------------- */

typedef struct Collected {
    MechrtTrace trace;
    RunResult res;
    RunStatus status;
} Collected;

static void collect(void *ctx, double t, const double *q, const double *qd, const double *qdd)
{
    Collected *c = ctx;
    assert_true(mechrt_trace_push(&c->trace, t, q, qd, qdd));
}

/* examples/chain.sh N, loaded. */
static Mech *load_chain(int n)
{
    char cmd[64], name[32];
    snprintf(cmd, sizeof cmd, "sh examples/chain.sh %d", n);
    snprintf(name, sizeof name, "chain_%d.mech", n);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 1 << 16, len = 0;
    char *text = malloc(cap);
    size_t got;
    while ((got = fread(text + len, 1, cap - len - 1, p)) > 0) {
        len += got;
        if (cap - len < 4096)
            text = realloc(text, cap *= 2);
    }
    assert_int_equal(pclose(p), 0);
    text[len] = '\0';
    Mech *m = load_text(text, name);
    free(text);
    return m;
}

/* Runs mech with the jit engine and linear algebra lin. */
static void run_linear(Mech *mech, RunLinear lin, RunOptions o, EngineKind kind, Collected *c)
{
    Engine e;
    Diag diag;
    MechrtHostJacNz jnz;
    memset(c, 0, sizeof *c);
    mechrt_trace_init(&c->trace, mech->model->nq);
    if (!engine_open(&e, kind, mech, &diag))
        fail_msg("engine: %s", diag.message);
    MechrtKernels k = e.k;
    o.linear = lin;
    o.jac_nz = run_jac_nz_of(&e, &jnz) ? &jnz : NULL;
    c->status = run_analysis(mech->model, &k, &o, collect, c, &c->res);
    engine_close(&e);
}

/* Every state of a and b within 1e-10 * max(1, |value|). */
static void expect_same(const Collected *a, const Collected *b, const char *what)
{
    assert_int_equal(a->trace.rows, b->trace.rows);
    size_t n = a->trace.rows * (1 + 3 * (size_t)a->trace.nq);
    for (size_t i = 0; i < n; i++) {
        double x = a->trace.data[i], y = b->trace.data[i];
        if (!(fabs(x - y) <= 1e-10 * fmax(1, fabs(x))))
            fail_msg("%s: value %zu: dense %.17g, sparse %.17g", what, i, x, y);
    }
}

/* Dense and sparse runs of mech with o: same states, statuses and
   stepping (Newton iterations, subdivisions, substeps). */
static void compare(Mech *mech, RunOptions o, const char *what)
{
    Collected d, s;
    run_linear(mech, RUN_LINEAR_DENSE, o, ENGINE_JIT, &d);
    run_linear(mech, RUN_LINEAR_SPARSE, o, ENGINE_JIT, &s);
    if (d.status != RUN_OK)
        fail_msg("%s dense: %s", what, d.res.message);
    if (s.status != RUN_OK)
        fail_msg("%s sparse: %s", what, s.res.message);
    assert_false(d.res.sparse);
    assert_true(s.res.sparse);
    expect_same(&d, &s, what);
    assert_int_equal(d.res.newton_iterations, s.res.newton_iterations);
    assert_int_equal(d.res.assembly_iterations, s.res.assembly_iterations);
    assert_int_equal(d.res.subdivided, s.res.subdivided);
    assert_int_equal(d.res.substeps, s.res.substeps);
    /* one refactorisation per factorisation after the first, normally */
    assert_true(s.res.fresh_factorisations >= 1);
    assert_true(s.res.refactorisations > s.res.fresh_factorisations);
    mechrt_trace_free(&d.trace);
    mechrt_trace_free(&s.trace);
}

static void test_examples_agree(void **state)
{
    (void)state;
    const char *files[] = {"examples/slider_crank.mech", "examples/four_bar.mech",
                           "examples/five_bar.mech"};
    for (size_t f = 0; f < sizeof files / sizeof *files; f++) {
        Mech *mech = load_file(files[f]);
        RunOptions o = run_default_options();
        compare(mech, o, files[f]);
        /* coarse steps: the predictor, the branch check and the substeps */
        o.steps = 3;
        compare(mech, o, files[f]);
        pipeline_free(mech);
    }
}

static void test_chain_agrees(void **state)
{
    (void)state;
    Mech *mech = load_chain(50);
    assert_int_equal(mech->model->nq, 303);
    RunOptions o = run_default_options();
    o.steps = 40;
    compare(mech, o, "chain 50");
    /* auto goes sparse at this size */
    Collected c;
    run_linear(mech, RUN_LINEAR_AUTO, o, ENGINE_JIT, &c);
    assert_int_equal(c.status, RUN_OK);
    assert_true(c.res.sparse);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* The toggle: KLU finds no pivot at t = 0.25, and the dense
   rank-revealing corrector takes the step there (tests/test_branch.c), as
   on the dense path: the same states. A redundant row at t0 still names
   KLU's failing pivot. */
static void test_toggle_sparse(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/slider_crank_toggle.mech");
    Collected c, d;
    run_linear(mech, RUN_LINEAR_SPARSE, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, RUN_OK);
    assert_true(c.res.sparse);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    run_linear(mech, RUN_LINEAR_DENSE, run_default_options(), ENGINE_JIT, &d);
    assert_int_equal(d.status, RUN_OK);
    expect_same(&d, &c, "toggle");
    mechrt_trace_free(&c.trace);
    mechrt_trace_free(&d.trace);
    pipeline_free(mech);

    mech = load_file("examples/parallelogram_redundant.mech");
    run_linear(mech, RUN_LINEAR_SPARSE, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, RUN_FAILED);
    assert_int_equal(c.res.cause, MECHRT_ESING);
    assert_near(c.res.t_fail, 0, 0, 0);
    assert_non_null(strstr(c.res.message, "t = 0: assembly from the file's initial values "
                                          "failed: singular Jacobian"));
    const char *named = strstr(c.res.message, "the sparse LU found no pivot for ");
    assert_non_null(named);
    assert_non_null(strstr(named, " in row "));
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

static void test_refusals(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/knife_cart.mech");
    Collected c;
    run_linear(mech, RUN_LINEAR_SPARSE, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, RUN_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "velocity-level rows"));
    mechrt_trace_free(&c.trace);
    run_linear(mech, RUN_LINEAR_AUTO, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, RUN_OK);
    assert_false(c.res.sparse);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);

    mech = load_file("examples/slider_crank.mech");
    run_linear(mech, RUN_LINEAR_SPARSE, run_default_options(), ENGINE_GENERIC, &c);
    assert_int_equal(c.status, RUN_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "generic engine"));
    mechrt_trace_free(&c.trace);
    run_linear(mech, RUN_LINEAR_AUTO, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, RUN_OK);
    assert_false(c.res.sparse);     /* small: dense */
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_klu_solve),
        cmocka_unit_test(test_klu_singular_named),
        cmocka_unit_test(test_klu_repivots),
        cmocka_unit_test(test_klu_bad_pattern),
        cmocka_unit_test(test_examples_agree),
        cmocka_unit_test(test_chain_agrees),
        cmocka_unit_test(test_toggle_sparse),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
