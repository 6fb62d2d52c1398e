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

#include "../generator/kin/run.h"
#include "../generator/jit/jit.h"
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
    return (MechrtHostJacNz){.jac = {.nnz = 6, .row = p_row, .col = p_col,
                                     .ctx = v, .jac_nz = fill_vals}};
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

/* ---- the augmented matrix [W Phi^T; Phi 0] (sparse_kkt.c) ---------------- */

/* M = [2 .5 0; .5 1 0; 0 0 0] (coordinate 2 without mass: no diagonal
   entry in M's pattern), Phi = [1 0 1; 0 1 1]. */
static const int m_row[] = {0, 0, 1, 1}, m_col[] = {0, 1, 0, 1};
static const double m_val[] = {2, 0.5, 0.5, 1};
static const int j_row[] = {0, 0, 1, 1}, j_col[] = {0, 2, 1, 2};
static const double j_val[] = {1, 1, 1, 1};

static void kkt_no_jac(void *ctx, const double *q, double t, double *vals)
{
    (void)ctx, (void)q, (void)t, (void)vals;
}

static MechrtHostKkt *small_kkt(void)
{
    MechrtHostJacNz j = {.jac = {.nnz = 4, .row = j_row, .col = j_col,
                                 .ctx = NULL, .jac_nz = kkt_no_jac}};
    MechrtHostMassNz m = {4, m_row, m_col, NULL, NULL};
    MechrtHostKkt *s = mechrt_host_kkt_new(3, 2, &j, &m);
    assert_non_null(s);
    memcpy(mechrt_host_kkt_jac(s), j_val, sizeof j_val);
    memcpy(mechrt_host_kkt_mass(s), m_val, sizeof m_val);
    return s;
}

static void test_kkt_identity(void **state)
{
    (void)state;
    MechrtHostKkt *s = small_kkt();
    /* every row: x = Phi^T (Phi Phi^T)^-1 b, y = -(Phi Phi^T)^-1 b; b = (1, 2) */
    assert_int_equal(mechrt_host_kkt_factor(s, MECHRT_KKT_IDENTITY, NULL, 2, 1e-12), MECHRT_OK);
    double x[5] = {0, 0, 0, 1, 2};
    assert_int_equal(mechrt_host_kkt_solve(s, MECHRT_KKT_IDENTITY, x), MECHRT_OK);
    const double want[5] = {0, 1, 1, 0, -1};
    for (int i = 0; i < 5; i++)
        assert_near(x[i], want[i], 0, 1e-14);
    /* row 1 left out: an identity row, its unknown = its right side */
    const unsigned char active[2] = {1, 0};
    assert_int_equal(mechrt_host_kkt_factor(s, MECHRT_KKT_IDENTITY, active, 2, 1e-12), MECHRT_OK);
    double x2[5] = {0, 0, 0, 1, 5};
    assert_int_equal(mechrt_host_kkt_solve(s, MECHRT_KKT_IDENTITY, x2), MECHRT_OK);
    const double want2[5] = {0.5, 0, 0.5, -0.5, 5};
    for (int i = 0; i < 5; i++)
        assert_near(x2[i], want2[i], 0, 1e-14);
    /* rows = 1 leaves row 1 out the same way */
    assert_int_equal(mechrt_host_kkt_factor(s, MECHRT_KKT_IDENTITY, NULL, 1, 1e-12), MECHRT_OK);
    double x3[5] = {0, 0, 0, 1, 5};
    assert_int_equal(mechrt_host_kkt_solve(s, MECHRT_KKT_IDENTITY, x3), MECHRT_OK);
    for (int i = 0; i < 5; i++)
        assert_near(x3[i], want2[i], 0, 1e-14);
    assert_true(mechrt_host_kkt_spread(s, MECHRT_KKT_IDENTITY) >= 1);
    /* the rank screen: every row, fresh pivots; a zero row is a rank drop */
    double spread;
    assert_int_equal(mechrt_host_kkt_screen(s, 2, 1e-12, &spread), MECHRT_OK);
    assert_true(spread >= 1 && spread < 100);
    mechrt_host_kkt_jac(s)[2] = mechrt_host_kkt_jac(s)[3] = 0;
    assert_int_equal(mechrt_host_kkt_screen(s, 2, 1e-12, &spread), MECHRT_ESING);
    assert_int_equal(mechrt_host_kkt_screen(s, 1, 1e-12, &spread), MECHRT_OK);
    mechrt_host_kkt_free(s);
}

static void test_kkt_mass(void **state)
{
    (void)state;
    MechrtHostKkt *s = small_kkt();
    /* M is singular but positive definite on null(Phi) = span (1, 1, -1):
       the augmented matrix is regular; the solution checked by its residual */
    const double a[5][5] = {{2, 0.5, 0, 1, 0}, {0.5, 1, 0, 0, 1}, {0, 0, 0, 1, 1},
                            {1, 0, 1, 0, 0}, {0, 1, 1, 0, 0}};
    const double b[5] = {1, 2, 3, 4, 5};
    double x[5], work[10];
    assert_int_equal(mechrt_host_kkt_factor(s, MECHRT_KKT_MASS, NULL, 2, 1e-12), MECHRT_OK);
    memcpy(x, b, sizeof b);
    assert_int_equal(mechrt_host_kkt_solve_refined(s, MECHRT_KKT_MASS, x, work), MECHRT_OK);
    for (int i = 0; i < 5; i++) {
        double r = -b[i];
        for (int k = 0; k < 5; k++)
            r += a[i][k] * x[k];
        assert_near(r, 0, 0, 1e-13);
    }
    /* without Phi's rows M alone is singular (coordinate 2): refused */
    const unsigned char none[2] = {0, 0};
    assert_int_equal(mechrt_host_kkt_factor(s, MECHRT_KKT_MASS, none, 2, 1e-12), MECHRT_ESING);
    long fresh, re;
    mechrt_host_kkt_counts(s, &fresh, &re);
    assert_true(fresh >= 2);
    mechrt_host_kkt_free(s);
}

/* The projection's minimum-norm step by SuiteSparseQR: Phi_q = [1 0 1; 0 1
   1] and Phi = (-1, -2) give dq = pinv(Phi_q) (1, 2) = (0, 1, 1); a third
   row, the sum of the two with a consistent Phi, is dropped as redundant
   and leaves dq as it was (the dense path's truncated SVD does the same). */
static const int mn_row[] = {0, 0, 1, 1, 2, 2, 2};
static const int mn_col[] = {0, 2, 1, 2, 0, 1, 2};

static void fill_mn(void *ctx, const double *q, double t, double *vals)
{
    (void)ctx, (void)q, (void)t;
    static const double v[7] = {1, 1, 1, 1, 1, 1, 2};
    memcpy(vals, v, sizeof v);
}

static void test_minnorm_step(void **state)
{
    (void)state;
    MechrtHostJacNz j = {.jac = {.nnz = 7, .row = mn_row, .col = mn_col,
                                 .ctx = NULL, .jac_nz = fill_mn}};
    double q[3] = {0, 0, 0}, dq[3];
    for (int nh = 2; nh <= 3; nh++) {
        MechrtHostMinNorm *m = mechrt_host_minnorm_new(nh, 3, &j);
        assert_non_null(m);
        double phi[3] = {-1, -2, -3};
        assert_int_equal(mechrt_host_minnorm_step(m, q, 0, phi, 1e-12, dq), MECHRT_OK);
        assert_near(dq[0], 0, 0, 1e-14);
        assert_near(dq[1], 1, 1e-14, 0);
        assert_near(dq[2], 1, 1e-14, 0);
        mechrt_host_minnorm_free(m);
    }
    assert_null(mechrt_host_minnorm_new(4, 3, &j));     /* more rows than coordinates */
    MechrtHostJacNz no_rows = j, no_cols = j;               /* entries but no pattern */
    no_rows.jac.row = NULL;
    no_cols.jac.col = NULL;
    assert_null(mechrt_host_minnorm_new(2, 3, &no_rows));
    assert_null(mechrt_host_minnorm_new(2, 3, &no_cols));
}

/* Phi = (q0 + q2 - 1, q1 + q2 - 2) at t, Phi_q's nonzeros those of mn_row's
   first two rows (its third row, past nh, is left out as a velocity-level
   row would be): the projector's kernels (only phi is called). */
static void pr_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx, (void)t;
    phi[0] = q[0] + q[2] - 1;
    phi[1] = q[1] + q[2] - 2;
}

/* The projector host (what sim assembles with on its sparse path): two
   rows, three coordinates, which the sparse host refuses; from q = 0 its
   Newton lands on the nearest solution pinv(Phi_q) (1, 2) = (0, 1, 1);
   no velocity solve. */
static void test_projector(void **state)
{
    (void)state;
    MechrtHostJacNz j = {.jac = {.nnz = 7, .row = mn_row, .col = mn_col,
                                 .ctx = NULL, .jac_nz = fill_mn}};
    MechrtKernels k = {3, 2, 0, NULL, pr_phi, NULL, NULL, NULL, NULL, NULL, NULL};
    assert_null(mechrt_host_new_sparse(&k, &j));
    MechrtHost *h = mechrt_host_new_projector(&k, &j);
    assert_non_null(h);
    double q[3] = {0, 0, 0}, qd[3], qdd[3];
    MechrtReport rep;
    assert_int_equal(mechrt_host_project(h, NULL, q, 0, &rep), MECHRT_OK);
    assert_near(q[0], 0, 0, 1e-14);
    assert_near(q[1], 1, 1e-14, 0);
    assert_near(q[2], 1, 1e-14, 0);
    assert_true(rep.iterations >= 1 && rep.residual <= 1e-14);
    assert_int_equal(mechrt_host_velocity_acceleration(h, NULL, q, 0, qd, qdd, &rep),
                     MECHRT_EINVAL);
    mechrt_host_free(h);
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
    MechrtHostJacNz j = {.jac = {.nnz = 4, .row = full_row, .col = full_col,
                                 .ctx = v, .jac_nz = fill_full}};
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
    MechrtHostJacNz j = {.jac = {.nnz = 6, .row = p_row, .col = dup_col,
                                 .ctx = v, .jac_nz = fill_vals}};
    assert_null(mechrt_host_sparse_new(3, &j));
    static const int far_col[] = {0, 3, 0, 1, 1, 2};    /* column 3 of 3 */
    j.jac.col = far_col;
    assert_null(mechrt_host_sparse_new(3, &j));
    j.jac.col = p_col;
    assert_null(mechrt_host_sparse_new(0, &j));
    j.jac.jac_nz = NULL;
    assert_null(mechrt_host_sparse_new(3, &j));
}

/* ---- runs, dense against sparse --------------------------------------- */

typedef struct Collected {
    MechrtTrace trace;
    RunResult res;
    AnalysisStatus status;
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
static void run_linear(Mech *mech, AnalysisLinear lin, RunOptions o, EngineKind kind, Collected *c)
{
    Engine e;
    Diag diag;
    memset(c, 0, sizeof *c);
    mechrt_trace_init(&c->trace, mech->model->nq);
    if (!engine_open(&e, kind, mech, &diag))
        fail_msg("engine: %s", diag.message);
    MechrtKernels k = e.k;
    o.linear = lin;
    c->status = run_analysis(mech->model, &k, engine_jac_nz(&e), &o, collect, c, &c->res);
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
    run_linear(mech, ANALYSIS_LINEAR_DENSE, o, ENGINE_JIT, &d);
    run_linear(mech, ANALYSIS_LINEAR_SPARSE, o, ENGINE_JIT, &s);
    if (d.status != ANALYSIS_OK)
        fail_msg("%s dense: %s", what, d.res.message);
    if (s.status != ANALYSIS_OK)
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
    run_linear(mech, ANALYSIS_LINEAR_AUTO, o, ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_OK);
    assert_true(c.res.sparse);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* The toggle: KLU finds no pivot at t = 0.25, and the dense
   rank-revealing corrector takes the step there (tests/test_qr_rank.c), as
   on the dense path: the same states. A redundant row at t0 still names
   KLU's failing pivot. */
static void test_toggle_sparse(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/slider_crank_toggle.mech");
    Collected c, d;
    run_linear(mech, ANALYSIS_LINEAR_SPARSE, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_OK);
    assert_true(c.res.sparse);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    run_linear(mech, ANALYSIS_LINEAR_DENSE, run_default_options(), ENGINE_JIT, &d);
    assert_int_equal(d.status, ANALYSIS_OK);
    expect_same(&d, &c, "toggle");
    mechrt_trace_free(&c.trace);
    mechrt_trace_free(&d.trace);
    pipeline_free(mech);

    mech = load_file("examples/parallelogram_redundant.mech");
    run_linear(mech, ANALYSIS_LINEAR_SPARSE, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
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
    /* velocity-level rows run sparse (KLU, SuiteSparseQR), as dense */
    static const char *const vel[] = {"examples/knife_cart.mech", "examples/rolling_wheel.mech",
                                      "examples/skate_velocity.mech"};
    Collected c, d;
    for (size_t f = 0; f < sizeof vel / sizeof *vel; f++) {
        Mech *vm = load_file(vel[f]);
        run_linear(vm, ANALYSIS_LINEAR_SPARSE, run_default_options(), ENGINE_JIT, &c);
        assert_int_equal(c.status, ANALYSIS_OK);
        assert_true(c.res.sparse);
        assert_true(c.res.refactorisations + c.res.fresh_factorisations > 0);
        run_linear(vm, ANALYSIS_LINEAR_AUTO, run_default_options(), ENGINE_JIT, &d);
        assert_int_equal(d.status, ANALYSIS_OK);
        assert_false(d.res.sparse);     /* small: dense */
        expect_same(&d, &c, vel[f]);
        mechrt_trace_free(&c.trace);
        mechrt_trace_free(&d.trace);
        pipeline_free(vm);
    }

    Mech *mech = load_file("examples/slider_crank.mech");
    run_linear(mech, ANALYSIS_LINEAR_SPARSE, run_default_options(), ENGINE_GENERIC, &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "generic engine"));
    mechrt_trace_free(&c.trace);
    run_linear(mech, ANALYSIS_LINEAR_AUTO, run_default_options(), ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_OK);
    assert_false(c.res.sparse);     /* small: dense */
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* ---- the fused kernel, all_nz ------------------------------------------ */

/* all_nz of the engine's code against phi, jac_nz, nu and gamma at a state
   off the initial one: the same values (the same expressions, scheduled
   together). */
static void expect_all_nz_agrees(Mech *mech, EngineKind kind)
{
    Engine e;
    Diag diag;
    if (!engine_open(&e, kind, mech, &diag))
        fail_msg("engine: %s", diag.message);
    const Kernels *code = &e.kernels;
    assert_non_null(code->all_nz);
    const Model *m = mech->model;
    size_t nq = (size_t)m->nq, nr = (size_t)m->nr, nnz = (size_t)mech->kin.nnz;
    double *buf = calloc(6 * nr + 2 * nnz + 2 * nq, sizeof *buf);
    double *phi = buf, *nu = buf + nr, *gamma = buf + 2 * nr, *phi2 = buf + 3 * nr;
    double *nu2 = buf + 4 * nr, *gamma2 = buf + 5 * nr, *vals = buf + 6 * nr;
    double *vals2 = vals + nnz, *q = vals2 + nnz, *qd = q + nq;
    for (size_t i = 0; i < nq; i++) {
        q[i] = m->q0[i] + 0.01 * sin((double)i);
        qd[i] = cos(3.0 * (double)i);
    }
    code->all_nz(q, qd, 0.3, phi, vals, nu, gamma);
    code->phi(q, 0.3, phi2);
    code->jac_nz(q, 0.3, vals2);
    code->nu(q, 0.3, nu2);
    code->gamma(q, qd, 0.3, gamma2);
    const double *a[4] = {phi, vals, nu, gamma}, *b[4] = {phi2, vals2, nu2, gamma2};
    size_t n[4] = {(size_t)m->nh, nnz, nr, nr};
    int nonzero = 0;
    for (int k = 0; k < 4; k++)
        for (size_t i = 0; i < n[k]; i++) {
            if (!(fabs(a[k][i] - b[k][i]) <= 1e-12 * fmax(1, fabs(b[k][i]))))
                fail_msg("%s: output %d entry %zu: all_nz %.17g, alone %.17g", m->name, k, i,
                         a[k][i], b[k][i]);
            nonzero += a[k][i] != 0;
        }
    assert_true(nonzero > (int)nnz / 2);   /* a state where the values mean something */
    free(buf);
    engine_close(&e);
}

static void test_all_nz_kernel(void **state)
{
    (void)state;
    Mech *mech = load_chain(50);
    expect_all_nz_agrees(mech, ENGINE_JIT);
    pipeline_free(mech);
    mech = load_file("examples/four_bar.mech");
    expect_all_nz_agrees(mech, ENGINE_JIT);
    expect_all_nz_agrees(mech, ENGINE_AOT);
    pipeline_free(mech);
    /* the KLU module without it: eval_all declines, does nothing */
    double v[6] = {2, 1, 1, 3, 1, 4}, x = 1;
    MechrtHostJacNz j = small_pattern(v);
    MechrtHostSparse *s = mechrt_host_sparse_new(3, &j);
    assert_false(mechrt_host_sparse_eval_all(s, &x, &x, 0, NULL, NULL, NULL));
    mechrt_host_sparse_free(s);
}

/* The sparse path with and without the fused kernel: the same states, the
   same iterations (nu from the last Newton evaluation is the nu kernel's). */
static void test_all_nz_run(void **state)
{
    (void)state;
    Mech *mech = load_chain(20);
    RunOptions o = run_default_options();
    o.steps = 10;
    Collected c[2];
    for (int fused = 0; fused < 2; fused++) {
        Engine e;
        Diag diag;
        MechrtHostJacNz jnz;
        memset(&c[fused], 0, sizeof c[fused]);
        mechrt_trace_init(&c[fused].trace, mech->model->nq);
        assert_true(engine_open(&e, ENGINE_JIT, mech, &diag));
        MechrtKernels k = e.k;
        o.linear = ANALYSIS_LINEAR_SPARSE;
        assert_non_null(engine_jac_nz(&e));
        jnz = *engine_jac_nz(&e);
        assert_non_null(jnz.all_nz);
        if (!fused)
            jnz.all_nz = NULL;
        c[fused].status = run_analysis(mech->model, &k, &jnz, &o, collect, &c[fused], &c[fused].res);
        assert_int_equal(c[fused].status, ANALYSIS_OK);
        engine_close(&e);
    }
    expect_same(&c[0], &c[1], "chain 20, all_nz");
    assert_int_equal(c[0].res.newton_iterations, c[1].res.newton_iterations);
    assert_int_equal(c[0].res.substeps, c[1].res.substeps);
    mechrt_trace_free(&c[0].trace);
    mechrt_trace_free(&c[1].trace);
    pipeline_free(mech);
}

/* RunOptions.max_dense_entries: the sparse path forms no dense Jacobian
   and runs past it; the dense one is refused, saying what would serve. */
static void test_dense_limit(void **state)
{
    (void)state;
    Mech *mech = load_chain(20);    /* 123 coordinates: 15129 dense entries */
    RunOptions o = run_default_options();
    o.steps = 4;
    o.max_dense_entries = 15000;
    Collected c;
    run_linear(mech, ANALYSIS_LINEAR_AUTO, o, ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_OK);
    assert_true(c.res.sparse);
    mechrt_trace_free(&c.trace);
    run_linear(mech, ANALYSIS_LINEAR_DENSE, o, ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "123 rows x 123 coordinates = 15129 entries, more "
                                          "than the limit of 15000 (--max-jac-entries): use "
                                          "--linear sparse"));
    mechrt_trace_free(&c.trace);
    run_linear(mech, ANALYSIS_LINEAR_AUTO, o, ENGINE_GENERIC, &c); /* no jac_nz: dense */
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "the sparse path cannot serve this run"));
    mechrt_trace_free(&c.trace);
    o.max_dense_entries = 15129;    /* at the limit: allowed */
    run_linear(mech, ANALYSIS_LINEAR_DENSE, o, ENGINE_JIT, &c);
    assert_int_equal(c.status, ANALYSIS_OK);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_klu_solve),
        cmocka_unit_test(test_klu_singular_named),
        cmocka_unit_test(test_minnorm_step),
        cmocka_unit_test(test_projector),
        cmocka_unit_test(test_klu_repivots),
        cmocka_unit_test(test_klu_bad_pattern),
        cmocka_unit_test(test_examples_agree),
        cmocka_unit_test(test_chain_agrees),
        cmocka_unit_test(test_toggle_sparse),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_all_nz_kernel),
        cmocka_unit_test(test_all_nz_run),
        cmocka_unit_test(test_dense_limit),
        cmocka_unit_test(test_kkt_identity),
        cmocka_unit_test(test_kkt_mass),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
