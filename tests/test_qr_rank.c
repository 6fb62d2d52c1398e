/* test_qr_rank.c - kinematic analysis through change points and dead centres (runtime/rank.c, runtime/qr.c, generator/kin/).
 *
 * The rank-revealing QR against known minimum-norm solutions, and the
 * corrector on a hand-written parallelogram at its fold (double and, at
 * the end of the file, float); then `run` through singular positions, every state against the
 * closed form, the folded states on the grid included: the IFToMM A02
 * chain of 40 parallelograms (sparse path), the same chain of 5 on the
 * dense path, a locomotive's coupled wheels and a parallelogram four-bar;
 * the toggle slider-crank continuing on its smooth branch; a slider
 * pushed past its dead centre failing with the corrector's verdict; and
 * every other example never taking the rank-revealing path.
 * Runs from the repository root (examples/ relative), like `make check`.
 */
#include "testutil.h"
#include "testload.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>

#include "../generator/kin/run.h"
#include "../generator/base/arena.h"
#include "../generator/pipeline/pipeline.h"
#include "../runtime/host/mechrt_host.h"

/* ---- the QR ------------------------------------------------------------ */

/* A 4 x 3 matrix of rank 2 (row 3 = row 1 + row 2, row 4 = 2 row 1) and a
   consistent right side: the solution must be pinv(A) b, orthogonal to the
   null space (1, -1, 1) / sqrt(3), and satisfy every row. */
static void test_qr_min_norm(void **state)
{
    (void)state;
    const double a[12] = {1, 2, 1, 0, 1, 1, 1, 3, 2, 2, 4, 2};
    const double x0[3] = {0.3, -0.7, 1.1};  /* any solution */
    double b[4], x[3], work[64];
    for (int i = 0; i < 4; i++)
        b[i] = a[3 * i] * x0[0] + a[3 * i + 1] * x0[1] + a[3 * i + 2] * x0[2];
    MechrtQr f;
    assert_true(mechrt_qr_work_len(4, 3) <= 64);
    assert_int_equal(mechrt_qr_factor(&f, 4, 3, a, 3, 1e-10, work, 64), MECHRT_OK);
    assert_int_equal(f.rank, 2);
    mechrt_qr_solve(&f, b, x);
    /* x0 minus its null-space part: (0.3 + 0.7 + 1.1) / 3 = 0.7 */
    assert_near(x[0], 0.3 - 0.7, 0, 1e-14);
    assert_near(x[1], -0.7 + 0.7, 0, 1e-14);
    assert_near(x[2], 1.1 - 0.7, 0, 1e-14);
    for (int i = 0; i < 4; i++)
        assert_near(a[3 * i] * x[0] + a[3 * i + 1] * x[1] + a[3 * i + 2] * x[2], b[i], 0, 1e-14);
    /* the rows that carry the rank come first in the pivot order */
    assert_in_range(mechrt_qr_row(&f, 0), 0, 3);
    assert_int_equal(mechrt_qr_row(&f, 2), -1);
    /* a regular matrix: the plain solution; a short workspace, NaN */
    const double r[4] = {2, 1, 1, 3}, rb[2] = {3, 5};
    assert_int_equal(mechrt_qr_factor(&f, 2, 2, r, 2, 1e-10, work, 64), MECHRT_OK);
    assert_int_equal(f.rank, 2);
    mechrt_qr_solve(&f, rb, x);
    assert_near(x[0], 0.8, 0, 1e-15);
    assert_near(x[1], 1.4, 0, 1e-15);
    assert_int_equal(mechrt_qr_factor(&f, 2, 2, r, 2, 1e-10, work, 3), MECHRT_EBADLEN);
    const double bad[4] = {1, NAN, 0, 1};
    assert_int_equal(mechrt_qr_factor(&f, 2, 2, bad, 2, 1e-10, work, 64), MECHRT_ENOTFINITE);
}

/* A banded 30 x 30 matrix (tridiagonal with two rows made dependent): the
   threshold pivoting and the skipped reflections must give the same
   minimum-norm solution as a dense check, J x = b on every row and x
   orthogonal to the null space found by J's structure. */
static void test_qr_banded(void **state)
{
    (void)state;
    enum { N = 30 };
    static double a[N * N], work[N * N + 8 * N];
    double b[N], x[N], x0[N];
    for (int i = 0; i < N; i++) {
        a[i * N + i] = 2 + 0.1 * i;
        if (i > 0)
            a[i * N + i - 1] = -1;
        if (i + 1 < N)
            a[i * N + i + 1] = -0.5;
        x0[i] = 0.01 * (i * 7 % 11) - 0.05;
    }
    /* rows 10 and 20 copies of rows 9 and 19: rank N - 2 */
    memcpy(a + 10 * N, a + 9 * N, N * sizeof *a);
    memcpy(a + 20 * N, a + 19 * N, N * sizeof *a);
    for (int i = 0; i < N; i++) {
        b[i] = 0;
        for (int j = 0; j < N; j++)
            b[i] += a[i * N + j] * x0[j];
    }
    MechrtQr f;
    assert_int_equal(mechrt_qr_factor(&f, N, N, a, N, 1e-10, work, sizeof work / sizeof *work),
                     MECHRT_OK);
    assert_int_equal(f.rank, N - 2);
    mechrt_qr_solve(&f, b, x);
    for (int i = 0; i < N; i++) {
        double s = 0;
        for (int j = 0; j < N; j++)
            s += a[i * N + j] * x[j];
        assert_near(s, b[i], 0, 1e-13);
    }
    /* minimum norm: x is in the row space, so x . z = 0 for every null
       vector z; solving for z with the rows, x must be no longer than x0
       and differ from it by a null vector (A (x - x0) = 0, checked above) */
    double nx = 0, nx0 = 0;
    for (int i = 0; i < N; i++)
        nx += x[i] * x[i], nx0 += x0[i] * x0[i];
    assert_true(nx <= nx0 + 1e-15);
    /* and x is unchanged by solving again from its own right side */
    double y[N];
    for (int i = 0; i < N; i++) {
        b[i] = 0;
        for (int j = 0; j < N; j++)
            b[i] += a[i * N + j] * x[j];
    }
    mechrt_qr_solve(&f, b, y);
    for (int i = 0; i < N; i++)
        assert_near(y[i], x[i], 0, 1e-13);
}

/* ---- the corrector on hand-written kernels -------------------------------
 * A parallelogram in two angles: crank theta = omega t (row 0), rocker psi
 * with the coupler's length 2 (row 1); ground 2, cranks 1:
 *   Phi1 = 4 (cos psi - cos theta) + 2 - 2 cos(psi - theta) = 0,
 *   J1 = [4 sin theta - 2 sin d, -4 sin psi + 2 sin d], d = psi - theta,
 *   gamma1 = 4 cos psi psi'^2 - 4 cos theta theta'^2 - 2 cos d d'^2.
 * Branches psi = theta and the crossed one meet at theta = 0, pi, where
 * J1 = 0: rank 1 of 2. */
#define PG_OMEGA 6.283185307179586

static void pg_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    phi[0] = q[0] - PG_OMEGA * t;
    phi[1] = 4 * (cos(q[1]) - cos(q[0])) + 2 - 2 * cos(q[1] - q[0]);
}

static void pg_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx, (void)t;
    double sd = sin(q[1] - q[0]);
    jac[0] = 1, jac[1] = 0;
    jac[2] = 4 * sin(q[0]) - 2 * sd, jac[3] = -4 * sin(q[1]) + 2 * sd;
}

static void pg_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx, (void)q, (void)t;
    nu[0] = PG_OMEGA, nu[1] = 0;
}

static void pg_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx, (void)t;
    double dd = qd[1] - qd[0];
    g[0] = 0;
    g[1] = 4 * cos(q[1]) * qd[1] * qd[1] - 4 * cos(q[0]) * qd[0] * qd[0]
           - 2 * cos(q[1] - q[0]) * dd * dd;
}

/* From the exact state h before the fold (theta = pi), Taylor's
   prediction, then the corrector: on the branch psi = theta, with the
   rocker's rate omega; regular Jacobians give mechrt_step's answer. */
static void test_rank_correct_fold(void **state)
{
    (void)state;
    const MechrtKernels k = {2, 2, 0, NULL, pg_phi, pg_jac, pg_nu, pg_gamma, NULL, NULL, NULL};
    double work[64];
    assert_true(mechrt_rank_workspace_size(2) <= 64);
    double h = 0.0025, t1 = 0.5, th = PG_OMEGA * (t1 - h);
    double q[2] = {th + PG_OMEGA * h, th + PG_OMEGA * h};  /* Taylor: qdd = 0 */
    double qd[2] = {PG_OMEGA, PG_OMEGA}, qdd[2] = {0, 0};
    q[1] += 1e-7;       /* a prediction a little off along the lost direction */
    MechrtReport rep;
    assert_int_equal(mechrt_rank_correct(&k, NULL, q, qd, qdd, t1, work, 64, &rep), MECHRT_OK);
    assert_near(q[0], M_PI, 0, 1e-15);
    /* the Jacobian's second singular value there, about 6e-7, is under
       rank_tol (1e-5): that direction is the prediction's, in q as in qd */
    assert_near(q[1], M_PI + 1e-7, 0, 1e-12);
    assert_near(qd[1], PG_OMEGA, 0, 1e-6);
    assert_near(qdd[1], 0, 0, 1e-4);
    assert_int_equal(rep.rank_deficiency, 1);
    assert_true(rep.inconsistency < 1e-6);
    assert_true(rep.factorisations >= 1);
    /* away from the fold: full rank, the plain solution */
    double q2[2] = {1.0, 1.0 + 1e-3}, qd2[2] = {0, 0}, qdd2[2] = {0, 0};
    assert_int_equal(mechrt_rank_correct(&k, NULL, q2, qd2, qdd2, 1.0 / PG_OMEGA, work, 64, &rep),
                     MECHRT_OK);
    assert_int_equal(rep.rank_deficiency, 0);
    assert_near(q2[1], 1.0, 0, 1e-12);
    assert_near(qd2[1], PG_OMEGA, 0, 1e-9);
    assert_near(qdd2[1], 0, 0, 1e-7);
    /* a short workspace, a non-square system */
    assert_int_equal(mechrt_rank_correct(&k, NULL, q2, qd2, qdd2, 0, work, 8, &rep),
                     MECHRT_EBADLEN);
    const MechrtKernels k1 = {2, 1, 0, NULL, pg_phi, pg_jac, pg_nu, pg_gamma, NULL, NULL, NULL};
    assert_int_equal(mechrt_rank_correct(&k1, NULL, q2, qd2, qdd2, 0, work, 64, &rep),
                     MECHRT_ENOTSQUARE);
}

/* ---- runs through singular positions ------------------------------------ */

typedef struct Collected {
    MechrtTrace trace;
    RunResult res;
    AnalysisStatus status;
    char notes[8192];
} Collected;

static void collect(void *ctx, double t, const double *q, const double *qd, const double *qdd)
{
    Collected *c = ctx;
    assert_true(mechrt_trace_push(&c->trace, t, q, qd, qdd));
}

static const double *state_at(const Collected *c, size_t i)
{
    return c->trace.data + i * (1 + 3 * (size_t)c->trace.nq);
}

/* Runs mech on the jit engine with o (the sparse Jacobian handed over, so
   that --linear auto may pick it); c must be freed with mechrt_trace_free. */
static void run_with(Mech *mech, RunOptions o, Collected *c)
{
    Engine e;
    Diag diag;
    memset(c, 0, sizeof *c);
    mechrt_trace_init(&c->trace, mech->model->nq);
    if (!engine_open(&e, ENGINE_JIT, mech, &diag))
        fail_msg("jit engine: %s", diag.message);
    FILE *notes = fmemopen(c->notes, sizeof c->notes - 1, "w");
    assert_non_null(notes);
    o.notes = notes;
    c->status = run_analysis(mech->model, &e.k, engine_jac_nz(&e), &o, collect, c, &c->res);
    fclose(notes);
    engine_close(&e);
}

/* One link of a mechanism whose every link moves with one driven angle
   theta = theta0 + w t: centre (x0 + ax cos theta, ay sin theta), angle
   theta when it turns, 0 when it translates. */
typedef struct Link {
    double x0, ax, ay;
    bool turns;
} Link;

typedef bool (*LinkOf)(const char *body, Link *out);

/* Every state of c against the closed form of link_of, to tol_q, tol_qd,
   tol_qdd (absolute). */
static void check_closed_form(const Mech *mech, const Collected *c, LinkOf link_of,
                              double theta0, double w, double tol_q, double tol_qd,
                              double tol_qdd)
{
    const Model *m = mech->model;
    int nq = m->nq;
    for (size_t k = 0; k < c->trace.rows; k++) {
        const double *s = state_at(c, k);
        double t = s[0], th = theta0 + w * t, cs = cos(th), sn = sin(th);
        for (int i = 0; i < nq; i++) {
            char body[64];
            const char *dot = strrchr(m->coord_names[i], '.');
            assert_non_null(dot);
            snprintf(body, sizeof body, "%.*s", (int)(dot - m->coord_names[i]),
                     m->coord_names[i]);
            Link l;
            if (!link_of(body, &l))
                fail_msg("no closed form for %s", body);
            double e[3];
            if (strcmp(dot, ".x") == 0)
                e[0] = l.x0 + l.ax * cs, e[1] = -l.ax * sn * w, e[2] = -l.ax * cs * w * w;
            else if (strcmp(dot, ".y") == 0)
                e[0] = l.ay * sn, e[1] = l.ay * cs * w, e[2] = -l.ay * sn * w * w;
            else
                e[0] = l.turns ? th : 0, e[1] = l.turns ? w : 0, e[2] = 0;
            double got[3] = {s[1 + i], s[1 + nq + i], s[1 + 2 * nq + i]};
            double tol[3] = {tol_q, tol_qd, tol_qdd};
            for (int d = 0; d < 3; d++)
                if (!(fabs(got[d] - e[d]) <= tol[d]))
                    fail_msg("t = %.17g: %s%s = %.17g, closed form %.17g (off by %.3g)", t,
                             d == 0 ? "" : d == 1 ? "d/dt " : "d2/dt2 ", m->coord_names[i],
                             got[d], e[d], fabs(got[d] - e[d]));
        }
    }
}

/* chain.sh's rods and couplers: rod i at (i, 0), coupler i over rod i + 1. */
static bool chain_link(const char *body, Link *out)
{
    int i;
    if (sscanf(body, "rod%d", &i) == 1)
        *out = (Link){i, 0.5, 0.5, true};
    else if (sscanf(body, "cpl%d", &i) == 1)
        *out = (Link){i + 0.5, 1, 1, false};
    else
        return false;
    return true;
}

/* locomotive.mech: d = 1.6, r = 0.4 */
static bool loco_link(const char *body, Link *out)
{
    int i;
    if (sscanf(body, "wheel%d", &i) == 1)
        *out = (Link){(i - 1) * 1.6, 0, 0, true};
    else if (sscanf(body, "rod%d", &i) == 1)
        *out = (Link){(i - 0.5) * 1.6, 0.4, 0.4, false};
    else
        return false;
    return true;
}

static bool pfb_link(const char *body, Link *out)
{
    if (strcmp(body, "crank") == 0)
        *out = (Link){0, 0.5, 0.5, true};
    else if (strcmp(body, "coupler") == 0)
        *out = (Link){1, 1, 1, false};
    else if (strcmp(body, "rocker") == 0)
        *out = (Link){2, 0.5, 0.5, true};
    else
        return false;
    return true;
}

static void expect_ok(const Collected *c, int steps)
{
    if (c->status != ANALYSIS_OK)
        fail_msg("run failed: %s", c->res.message);
    assert_int_equal((int)c->trace.rows, steps + 1);
}

/* The targets (doc/singular.md): angles 1e-8, rates 1e-6, accelerations 1e-4
   at every one of 400 steps, t = 0.25 and 0.75 (flat) on the grid; the
   two flat states by the corrector, rank-deficient by N = 40. */
static void test_a02_chain(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/a02_chain.mech");
    assert_int_equal(mech->model->nq, 243);
    RunOptions o = run_default_options();
    o.steps = 400;
    Collected c;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    assert_true(c.res.sparse);
    assert_near(state_at(&c, 100)[0], 0.25, 0, 0);
    assert_near(state_at(&c, 300)[0], 0.75, 0, 0);
    check_closed_form(mech, &c, chain_link, M_PI / 2, -2 * M_PI, 1e-8, 1e-6, 1e-4);
    assert_int_equal(c.res.rank_steps, 2);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    assert_int_equal(c.res.max_rank_deficiency, 40);
    assert_int_equal(c.res.subdivided, 0);
    mechrt_trace_free(&c.trace);

    /* two full turns in 400 steps: four flat states on the grid */
    o.t1 = 2;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    check_closed_form(mech, &c, chain_link, M_PI / 2, -2 * M_PI, 1e-8, 1e-6, 1e-4);
    assert_int_equal(c.res.rank_deficient_steps, 4);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* The same chain, N = 5, on the dense path (the runtime's LU, then QR),
   with a grid that misses the flat states by 1e-9 of a turn: near, not
   at, the corrector must still keep the branch. */
static void test_chain_dense_near(void **state)
{
    (void)state;
    char text[4096] = "param omega = 2*pi\n"
                      "body rod0 x = 0 y = 0.5 phi = pi/2\n"
                      "revolute g0: ground(0, 0) rod0(-0.5, 0)\n"
                      "driver drive: rod0.phi = pi/2 - omega*t\n";
    for (int i = 0; i < 5; i++) {
        char more[512];
        snprintf(more, sizeof more,
                 "body cpl%d x = %d.5 y = 1 phi = 0\nbody rod%d x = %d y = 0.5 phi = pi/2\n"
                 "revolute g%d: ground(%d, 0) rod%d(-0.5, 0)\n"
                 "revolute a%d: rod%d(0.5, 0) cpl%d(-0.5, 0)\n"
                 "revolute b%d: cpl%d(0.5, 0) rod%d(0.5, 0)\n",
                 i, i, i + 1, i + 1, i + 1, i + 1, i + 1, i, i, i, i, i, i + 1);
        strcat(text, more);
    }
    Mech *mech = load_text(text, "chain5.mech");
    RunOptions o = run_default_options();
    o.steps = 400;
    o.linear = ANALYSIS_LINEAR_DENSE;
    Collected c;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    assert_false(c.res.sparse);
    check_closed_form(mech, &c, chain_link, M_PI / 2, -2 * M_PI, 1e-8, 1e-6, 1e-4);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    assert_int_equal(c.res.max_rank_deficiency, 5);
    mechrt_trace_free(&c.trace);

    o.t0 = 1e-9;
    o.t1 = 1 + 1e-9;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    check_closed_form(mech, &c, chain_link, M_PI / 2, -2 * M_PI, 1e-8, 1e-6, 1e-4);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

static void test_locomotive(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/locomotive.mech");
    RunOptions o = run_default_options();
    o.steps = 400;
    Collected c;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    check_closed_form(mech, &c, loco_link, M_PI / 2, 2 * M_PI, 1e-8, 1e-6, 1e-4);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    assert_int_equal(c.res.max_rank_deficiency, 2);
    mechrt_trace_free(&c.trace);
    /* coarse: 8 steps a turn, still on the grid at the dead centres */
    o.steps = 8;
    run_with(mech, o, &c);
    expect_ok(&c, 8);
    check_closed_form(mech, &c, loco_link, M_PI / 2, 2 * M_PI, 1e-8, 1e-6, 1e-4);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

static void test_parallelogram_four_bar(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/parallelogram_four_bar.mech");
    RunOptions o = run_default_options();
    o.steps = 400;
    o.t1 = 3;       /* three turns: six folds, all on the grid */
    o.steps = 1200;
    Collected c;
    run_with(mech, o, &c);
    expect_ok(&c, 1200);
    check_closed_form(mech, &c, pfb_link, M_PI / 2, 2 * M_PI, 1e-8, 1e-6, 1e-4);
    assert_int_equal(c.res.rank_deficient_steps, 6);
    assert_int_equal(c.res.max_rank_deficiency, 1);
    mechrt_trace_free(&c.trace);
    /* backwards in time, through the folds at t = -0.25 and -0.75 */
    o.t0 = 0;
    o.t1 = -1;
    o.steps = 400;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    check_closed_form(mech, &c, pfb_link, M_PI / 2, 2 * M_PI, 1e-8, 1e-6, 1e-4);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* slider_crank_toggle.mech (r = l = 0.2): of the two branches that cross
   at t = 0.25, x = 2 r cos(theta) and x = 0, the run keeps the smooth one
   it came on, with the rod mirroring the crank. */
static void test_toggle_continues(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/slider_crank_toggle.mech");
    const Model *m = mech->model;
    int xs = -1, rp = -1;
    for (int i = 0; i < m->nq; i++) {
        if (strcmp(m->coord_names[i], "slider.x") == 0)
            xs = i;
        if (strcmp(m->coord_names[i], "rod.phi") == 0)
            rp = i;
    }
    assert_true(xs >= 0 && rp >= 0);
    RunOptions o = run_default_options();
    o.steps = 400;
    Collected c;
    run_with(mech, o, &c);
    expect_ok(&c, 400);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    double w = 2 * M_PI, r = 0.2;
    for (size_t k = 0; k < c.trace.rows; k++) {
        const double *s = state_at(&c, k);
        double th = w * s[0];
        assert_near(s[1 + xs], 2 * r * cos(th), 0, 1e-9);
        assert_near(s[1 + m->nq + xs], -2 * r * w * sin(th), 0, 1e-6);
        assert_near(s[1 + 2 * m->nq + xs], -2 * r * w * w * cos(th), 0, 1e-4);
        assert_near(s[1 + rp], -th, 0, 1e-8);
    }
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* A slider pushed to its dead centre (crank 0.1, rod 0.3: x <= 0.4, reached
   at t = 1) and past it: no motion continues, and the message says so
   after the LU's account, with the time. */
static const char limit_text[] =
    "param r = 0.1\nparam l = 0.3\n"
    "body crank x = 0.05 y = 0 phi = 0\nbody rod x = 0.25 y = 0 phi = 0\n"
    "body slider x = 0.4 y = 0 phi = 0\n"
    "revolute O: ground(0, 0) crank(-r/2, 0)\nrevolute A: crank(r/2, 0) rod(-l/2, 0)\n"
    "revolute B: rod(l/2, 0) slider(0, 0)\n"
    "prismatic P: ground(0, 0) slider(0, 0) axis(1, 0)\n"
    "driver D: slider.x = 0.3 + 0.1*t\n";

static void test_dead_centre_passed(void **state)
{
    (void)state;
    Mech *mech = load_text(limit_text, "limit.mech");
    RunOptions o = run_default_options();
    o.t1 = 2;
    o.steps = 20;
    Collected c;
    run_with(mech, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_near(c.res.t_fail, 1, 0, 1e-15);
    assert_int_equal((int)c.trace.rows, 10);
    assert_non_null(strstr(c.res.message, "t = 1:"));
    assert_non_null(strstr(c.res.message, "rank-revealing corrector found no motion"));
    assert_non_null(strstr(c.res.message, "(at t = 1: "));
    assert_non_null(strstr(c.res.message, "crank.phi"));
    assert_true(c.res.rank_failed);
    mechrt_trace_free(&c.trace);
    pipeline_free(mech);
}

/* Every other example that runs: never the corrector. */
static void test_examples_never_switch(void **state)
{
    (void)state;
    DIR *d = opendir("examples");
    assert_non_null(d);
    struct dirent *e;
    int ran = 0;
    while ((e = readdir(d))) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".mech") != 0)
            continue;
        if (strcmp(e->d_name, "a02_chain.mech") == 0 || strcmp(e->d_name, "locomotive.mech") == 0
            || strcmp(e->d_name, "parallelogram_four_bar.mech") == 0
            || strcmp(e->d_name, "slider_crank_toggle.mech") == 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "examples/%s", e->d_name);
        Mech *mech = load_file(path);
        char why[256];
        if (mech->model->nv == 0 && run_rows_match(mech->model, why, sizeof why)) {
            Collected c;
            run_with(mech, run_default_options(), &c);
            if (c.res.rank_steps != 0)
                fail_msg("%s: %d steps by the rank corrector", path, c.res.rank_steps);
            ran += c.status == ANALYSIS_OK;
            mechrt_trace_free(&c.trace);
        }
        pipeline_free(mech);
    }
    closedir(d);
    assert_true(ran >= 12);
}

/* ---- the float build ------------------------------------------------------
 * The runtime compiled a second time with MECHRT_REAL_FLOAT: its external
 * names become mechrtf_*, so it links beside the double library; past
 * this point mechrt_* names the float functions. */
#define MECHRT_REAL_FLOAT
#include "../runtime/lu.c"
#include "../runtime/newton.c"
#include "../runtime/analysis.c"
#include "../runtime/qr.c"
#include "../runtime/rank.c"

static void fpg_phi(void *ctx, const float *q, float t, float *phi)
{
    (void)ctx;
    phi[0] = q[0] - (float)PG_OMEGA * t;
    phi[1] = 4 * (cosf(q[1]) - cosf(q[0])) + 2 - 2 * cosf(q[1] - q[0]);
}

static void fpg_jac(void *ctx, const float *q, float t, float *jac)
{
    (void)ctx, (void)t;
    float sd = sinf(q[1] - q[0]);
    jac[0] = 1, jac[1] = 0;
    jac[2] = 4 * sinf(q[0]) - 2 * sd, jac[3] = -4 * sinf(q[1]) + 2 * sd;
}

static void fpg_nu(void *ctx, const float *q, float t, float *nu)
{
    (void)ctx, (void)q, (void)t;
    nu[0] = (float)PG_OMEGA, nu[1] = 0;
}

static void fpg_gamma(void *ctx, const float *q, const float *qd, float t, float *g)
{
    (void)ctx, (void)t;
    float dd = qd[1] - qd[0];
    g[0] = 0;
    g[1] = 4 * cosf(q[1]) * qd[1] * qd[1] - 4 * cosf(q[0]) * qd[0] * qd[0]
           - 2 * cosf(q[1] - q[0]) * dd * dd;
}

/* The QR and the corrector in float: the same answers to float's digits. */
static void test_float_build(void **state)
{
    (void)state;
    assert_int_equal(sizeof(mechrt_real), sizeof(float));
    const float a[12] = {1, 2, 1, 0, 1, 1, 1, 3, 2, 2, 4, 2};
    const float b[4] = {0.3f - 1.4f + 1.1f, -0.7f + 1.1f, 0.3f - 2.1f + 2.2f,
                        0.6f - 2.8f + 2.2f};
    float x[3], work[64];
    MechrtQr f;
    assert_int_equal(mechrt_qr_factor(&f, 4, 3, a, 3, 1e-4f, work, 64), MECHRT_OK);
    assert_int_equal(f.rank, 2);
    mechrt_qr_solve(&f, b, x);
    assert_near(x[0], -0.4, 0, 1e-5);
    assert_near(x[1], 0, 0, 1e-5);
    assert_near(x[2], 0.4, 0, 1e-5);

    const MechrtfKernels k = {2, 2, 0, NULL, fpg_phi, fpg_jac, fpg_nu, fpg_gamma, NULL, NULL,
                              NULL};
    float q[2] = {(float)M_PI, (float)M_PI}, qd[2] = {(float)PG_OMEGA, (float)PG_OMEGA};
    float qdd[2] = {0, 0};
    MechrtfReport rep;
    assert_int_equal(mechrt_rank_correct(&k, NULL, q, qd, qdd, 0.5f, work, 64, &rep), MECHRT_OK);
    assert_int_equal(rep.rank_deficiency, 1);
    assert_near(q[1], M_PI, 0, 1e-5);
    assert_near(qd[1], PG_OMEGA, 0, 1e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_qr_min_norm),
        cmocka_unit_test(test_qr_banded),
        cmocka_unit_test(test_rank_correct_fold),
        cmocka_unit_test(test_float_build),
        cmocka_unit_test(test_a02_chain),
        cmocka_unit_test(test_chain_dense_near),
        cmocka_unit_test(test_locomotive),
        cmocka_unit_test(test_parallelogram_four_bar),
        cmocka_unit_test(test_toggle_continues),
        cmocka_unit_test(test_dead_centre_passed),
        cmocka_unit_test(test_examples_never_switch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
