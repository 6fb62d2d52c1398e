/* test_info.c - the analysis behind `mechc info`: SVD, rank and redundant rows,
   minimum-norm assembly, singular positions, integrability and the laws. */
#include "testutil.h"

#include "../generator/structure/info.h"
#include "../generator/engine/mech_eval.h"
#include "../generator/structure/spqr_rank.h"
#include "../generator/analysis/svd.h"
#include "../generator/base/limits.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

/* ---- fixtures ---- */

/* examples/parallelogram_redundant.mech: three equal cranks on one coupler. */
static const char parallelogram[] =
    "body c1      x = 0.25  y = sqrt(3)/4  phi = pi/3\n"
    "body c2      x = 1.25  y = sqrt(3)/4  phi = pi/3\n"
    "body c3      x = 2.25  y = sqrt(3)/4  phi = pi/3\n"
    "body coupler x = 1.5   y = sqrt(3)/2  phi = 0\n"
    "revolute O1: ground(0, 0)  c1(-0.5, 0)\n"
    "revolute A1: c1(0.5, 0)    coupler(-1, 0)\n"
    "revolute O3: ground(2, 0)  c3(-0.5, 0)\n"
    "revolute A3: c3(0.5, 0)    coupler(1, 0)\n"
    "revolute O2: ground(1, 0)  c2(-0.5, 0)\n"
    "revolute A2: c2(0.5, 0)    coupler(0, 0)\n";

/* examples/knife_cart.mech */
static const char knife_cart[] =
    "param v = pi\nparam w = pi\n"
    "body cart x = 1  y = 0  phi = pi/2\n"
    "knife  blade: cart axis(1, 0)\n"
    "driver fwd:   der(cart.x)*cos(cart.phi) + der(cart.y)*sin(cart.phi) = v\n"
    "driver turn:  der(cart.phi) = w\n";

/* examples/rolling_disk_velocity.mech */
static const char rolling_disk[] =
    "param R = 0.5\nparam w = 2*pi\n"
    "body disk x = 1  y = R  phi = 0\n"
    "constraint height: disk.y = R\n"
    "velocity   roll:   der(disk.x) + R*der(disk.phi) = 0\n"
    "driver     spin:   der(disk.phi) = -w\n";

/* examples/rolling_wheel.mech: the `rolling` statement */
static const char rolling_wheel[] =
    "param R = 0.5\nparam w = 2*pi\n"
    "body wheel x = 1  y = R  phi = 0\n"
    "pointline height: ground(0, R) wheel axis(1, 0)\n"
    "rolling   roll:   wheel radius = R\n"
    "driver    spin:   wheel.phi = -w*t\n";

/* A slider-crank with r = l exactly at its toggle: crank straight up, the rod
   folded back onto it, the slider at the crank pivot. */
static const char toggle[] =
    "param r = 0.2\nparam l = 0.2\nparam omega = 2*pi\n"
    "body  crank  x = 0  y = r/2  phi = pi/2\n"
    "body  rod    x = 0  y = r/2  phi = -pi/2\n"
    "body  slider x = 0  y = 0    phi = 0\n"
    "revolute  O: ground(0, 0)  crank(-r/2, 0)\n"
    "revolute  A: crank(r/2, 0) rod(-l/2, 0)\n"
    "revolute  B: rod(l/2, 0)   slider(0, 0)\n"
    "prismatic P: ground(0, 0)  slider(0, 0)  axis(1, 0)\n"
    "driver    D: crank.phi = pi/2 + omega*t\n";

/* examples/slider_crank_toggle.mech: r = l, starting stretched out. */
static const char slider_crank_toggle[] =
    "param r = 0.2\nparam l = 0.2\nparam omega = 2*pi\n"
    "body  crank  x = r/2      y = 0  phi = 0\n"
    "body  rod    x = r + l/2  y = 0  phi = 0\n"
    "body  slider x = r + l    y = 0  phi = 0\n"
    "revolute  O: ground(0, 0)  crank(-r/2, 0)\n"
    "revolute  A: crank(r/2, 0) rod(-l/2, 0)\n"
    "revolute  B: rod(l/2, 0)   slider(0, 0)\n"
    "prismatic P: ground(0, 0)  slider(0, 0)  axis(1, 0)\n"
    "driver    D: crank.phi = omega*t\n";

/* A slider-crank driven by its slider, at the outer dead centre. */
static const char dead_centre[] =
    "param r = 0.1\nparam l = 0.3\n"
    "body  crank  x = r/2      y = 0  phi = 0\n"
    "body  rod    x = r + l/2  y = 0  phi = 0\n"
    "body  slider x = r + l    y = 0  phi = 0\n"
    "revolute  O: ground(0, 0)  crank(-r/2, 0)\n"
    "revolute  A: crank(r/2, 0) rod(-l/2, 0)\n"
    "revolute  B: rod(l/2, 0)   slider(0, 0)\n"
    "prismatic P: ground(0, 0)  slider(0, 0)  axis(1, 0)\n"
    "driver    D: slider.x = r + l - 0.01*t\n";

/* examples/four_bar.mech without its driver, started well off the loop. */
static const char four_bar_free[] =
    "param a = 1\nparam b = 3\nparam c = 2.5\nparam d = 3\n"
    "body crank   x = 0.55  y = 0.05  phi = 0.05\n"
    "body coupler x = 1.8   y = 1.3   phi = 0.9\n"
    "body rocker  x = 2.9   y = 1.2   phi = 1.75\n"
    "revolute O2: ground(0, 0)     crank(-a/2, 0)\n"
    "revolute A:  crank(a/2, 0)    coupler(-b/2, 0)\n"
    "revolute B:  coupler(b/2, 0)  rocker(c/2, 0)\n"
    "revolute O4: ground(d, 0)     rocker(-c/2, 0)\n";

/* examples/elliptical_trammel.mech */
static const char trammel[] =
    "param L = 2\nparam e = 0.5\nparam phi0 = 3*pi/4\nparam omega = 2*pi\n"
    "body  sa   x = 1.4142  y = 0       phi = 0\n"
    "body  sb   x = 0       y = 1.4142  phi = 0\n"
    "body  rod  x = 0.7071  y = 0.7071  phi = phi0\n"
    "point pen  x = 0.3536  y = 1.0607\n"
    "prismatic gx: ground sa axis(1, 0)\n"
    "prismatic gy: ground sb axis(0, 1)\n"
    "revolute  A:  rod(-L/2, 0) sa\n"
    "revolute  B:  rod(L/2, 0)  sb\n"
    "revolute  P:  rod(e, 0)    pen\n"
    "driver turn:  rod.phi = phi0 + omega*t\n";

/* Velocity rows of every kind the integrability test distinguishes. */
static const char velocity_rows[] =
    "coord x = 0.3\ncoord y = 0.7\ncoord z = 0.2\n"
    "velocity exact:    y*der(x) + x*der(y) = 0\n"              /* d(xy) */
    "velocity contact:  der(x) - y*der(z) = 0\n"                /* Heisenberg: nonholonomic */
    "velocity consts:   der(x) + 2*der(y) + 3*der(z) = 0\n"     /* symbolic proof, 3 coords */
    "velocity factor:   exp(x)*(y*der(x) + x*der(y) + der(z)) = 0\n" /* exp(x) d(xy + z) */
    "velocity rotate:   y*der(x) - x*der(y) = 0\n"              /* y^2 d(x/y): law not found */
    "driver   timed:    der(x) = cos(t)\n"                      /* x - sin t */
    "velocity scaled:   t*der(y) = 0\n";                        /* factor 1/t: y = const */

/* A point on two circles that do not meet: no configuration exists. */
static const char impossible[] =
    "point m x = 0.5 y = 0.1\n"
    "distance a: ground(0, 0) m length = 1\n"
    "distance b: ground(5, 0) m length = 1\n";

/* The same velocity row twice. */
static const char twice[] =
    "body disk x = 1  y = 0.5  phi = 0\n"
    "constraint height: disk.y = 0.5\n"
    "velocity roll:  der(disk.x) + 0.5*der(disk.phi) = 0\n"
    "velocity again: 2*der(disk.x) + der(disk.phi) = 0\n";

/* ---- helpers ---- */

typedef struct Loaded {
    Diag diag;
    Mech *mech;
    InfoReport rep;
} Loaded;

static Loaded *load_at(const char *text, double t)
{
    Loaded *l = calloc(1, sizeof *l);
    MechLimits limits = mech_default_limits();
    l->mech = pipeline_load_text(text, "test.mech", &limits, &l->diag);
    if (!l->mech) {
        diag_print(&l->diag, stderr);
        fail_msg("fixture does not load");
    }
    AnalysisOptions o = analysis_default_options();
    if (!info_analyse(l->mech, t, &o, &l->rep, &l->diag))
        fail_msg("info_analyse failed: %s", l->diag.message);
    return l;
}

static Loaded *load(const char *text) { return load_at(text, 0.0); }

static void unload(Loaded *l)
{
    info_report_free(&l->rep);
    pipeline_free(l->mech);
    free(l);
}

static int row_index(const Loaded *l, const char *name)
{
    const Model *m = l->mech->model;
    for (int r = 0; r < m->nr; r++)
        if (strcmp(m->rows[r].name, name) == 0)
            return r;
    fail_msg("no row named %s", name);
    return -1;
}

static const Integrability *integ(const Loaded *l, const char *name)
{
    return &l->rep.rows[row_index(l, name)].integ;
}

#define assert_contains(text, part) do { \
        const char *t_ = (text), *p_ = (part); \
        if (!t_ || !strstr(t_, p_)) \
            fail_msg("'%s' does not contain '%s'", t_ ? t_ : "(null)", p_); \
    } while (0)

/* ---- SVD ---- */

static void test_svd_values_rank_cond(void **state)
{
    (void)state;
    /* A = U diag(3, 2, 1e-20) V^T with a rotation on each side */
    double c = cos(0.3), s = sin(0.3);
    double d[3] = {3, 2, 1e-20};
    double a[9] = {0};
    /* rows rotated in (0,1), columns in (1,2) */
    double u[3][3] = {{c, -s, 0}, {s, c, 0}, {0, 0, 1}}, v[3][3] = {{1, 0, 0}, {0, c, -s}, {0, s, c}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++)
                a[i * 3 + j] += u[i][k] * d[k] * v[j][k];
    MechrtSvd *w = svd_work_new(3, 3);
    MechrtSvdResult r;
    assert_true(mechrt_svd(w, a, 3, 3, 3, -1.0, &r));
    assert_int_equal(r.k, 3);
    assert_near(r.sigma[0], 3.0, 1e-14, 0);
    assert_near(r.sigma[1], 2.0, 1e-14, 0);
    assert_near(r.sigma_max, 3.0, 1e-14, 0);
    assert_true(r.sigma_min < 1e-15);
    assert_int_equal(r.rank, 2);
    assert_true(r.cond > 1e15);
    assert_near(r.tol, 3 * DBL_EPSILON * 3.0, 1e-12, 0);
    /* a user tolerance */
    assert_true(mechrt_svd(w, a, 3, 3, 3, 2.5, &r));
    assert_int_equal(r.rank, 1);
    /* NaN is refused */
    a[4] = NAN;
    assert_false(mechrt_svd(w, a, 3, 3, 3, -1.0, &r));
    assert_int_equal(r.rank, -1);
    mechrt_svd_free(w);
}

static void test_svd_wide_min_norm(void **state)
{
    (void)state;
    /* x + y = 2 and z free: the minimum-norm solution is (1, 1, 0) */
    double a[3] = {1, 1, 0}, b[1] = {2}, x[3];
    MechrtSvd *w = svd_work_new(1, 3);
    MechrtSvdResult r;
    assert_true(mechrt_svd(w, a, 1, 3, 3, -1.0, &r));
    assert_int_equal(r.k, 1);
    assert_int_equal(r.rank, 1);
    assert_near(r.sigma_max, sqrt(2.0), 1e-15, 0);
    mechrt_svd_pinv_solve(w, b, x);
    assert_near(x[0], 1.0, 1e-15, 1e-15);
    assert_near(x[1], 1.0, 1e-15, 1e-15);
    assert_near(x[2], 0.0, 0, 1e-15);
    mechrt_svd_free(w);
}

static void test_svd_tall_least_squares(void **state)
{
    (void)state;
    /* x = 1, x = 3 (inconsistent): least squares gives 2; a zero column stays 0 */
    double a[4] = {1, 0, 1, 0}, b[2] = {1, 3}, x[2];
    MechrtSvd *w = svd_work_new(2, 2);
    MechrtSvdResult r;
    assert_true(mechrt_svd(w, a, 2, 2, 2, -1.0, &r));
    assert_int_equal(r.rank, 1);
    assert_true(isinf(r.cond));
    mechrt_svd_pinv_solve(w, b, x);
    assert_near(x[0], 2.0, 1e-15, 0);
    assert_near(x[1], 0.0, 0, 1e-15);
    mechrt_svd_free(w);
}

static void test_redundant_rows_incremental(void **state)
{
    (void)state;
    /* rows: r0, r1, r0 + r1 (redundant), 0 (redundant), r2, 2 r2 (redundant) */
    double a[6 * 4] = {
        1, 2, 0, 0,
        0, 1, 1, 0,
        1, 3, 1, 0,
        0, 0, 0, 0,
        0, 0, 0, 5,
        0, 0, 0, 10,
    };
    bool red[6];
    MechrtSvd *w = svd_work_new(6, 4);
    MechrtSvdResult r;
    assert_true(mechrt_svd(w, a, 6, 4, 4, -1.0, &r));
    assert_int_equal(r.rank, 3);
    assert_int_equal(svd_redundant_rows(w, a, 6, 4, 4, r.tol, 0, -1, red), 3);
    bool want[6] = {false, false, true, true, false, true};
    for (int i = 0; i < 6; i++)
        if (red[i] != want[i])
            fail_msg("row %d: redundant = %d, expected %d", i, red[i], want[i]);
    /* only rows from 4 on are looked at */
    assert_int_equal(svd_redundant_rows(w, a, 6, 4, 4, r.tol, 4, 3, red), 1);
    assert_false(red[4]);
    assert_true(red[5]);
    mechrt_svd_free(w);
}

/* One program for many roots (what `info` evaluates Phi, the Jacobian and
   its own nodes with): shared nodes, a repeated root and DAG_NONE; each
   root's value equals its own one-root program's. */
static void test_node_values_many_roots(void **state)
{
    (void)state;
    Dag d;
    dag_init(&d, 1000);
    NodeId x = dag_var(&d, 0), y = dag_var(&d, 1), t = dag_time(&d);
    NodeId s = dag_call(&d, OP_SIN, dag_mul(&d, x, y), DAG_NONE);     /* shared */
    NodeId roots[5] = {
        dag_add(&d, s, t),
        dag_div(&d, s, dag_add(&d, y, dag_const(&d, 2.0))),
        DAG_NONE,
        dag_add(&d, s, t),
        dag_mul(&d, dag_vard(&d, 1), x),
    };
    double q[2] = {0.7371, -0.4213}, qd[2] = {0.3, -0.613}, tt = 0.4137;
    NodeValues nv;
    node_values_init(&nv, &d, roots, 5);
    node_values_run(&nv, q, qd, tt);
    double sxy = sin(q[0] * q[1]);
    assert_near(node_values_get(&nv, 0), sxy + tt, 1e-15, 0);
    assert_near(node_values_get(&nv, 1), sxy / (q[1] + 2.0), 1e-15, 0);
    assert_true(isnan(node_values_get(&nv, 2)));
    assert_near(node_values_get(&nv, 3), sxy + tt, 1e-15, 0);
    assert_near(node_values_get(&nv, 4), qd[1] * q[0], 1e-15, 0);
    for (int k = 0; k < 5; k++)
        if (roots[k] != DAG_NONE)
            assert_near(node_value_at(&d, roots[k], q, qd, tt), node_values_get(&nv, k), 0, 0);
    node_values_run(&nv, q, NULL, tt);      /* velocities zero */
    assert_near(node_values_get(&nv, 4), 0.0, 0, 0);
    node_values_free(&nv);
    dag_free(&d);
}

/* ---- rank and redundancy of mechanisms ---- */

static void test_parallelogram_rank_and_redundant_row(void **state)
{
    (void)state;
    Loaded *l = load(parallelogram);
    const InfoReport *rep = &l->rep;
    assert_int_equal(rep->nq, 12);
    assert_int_equal(rep->nh, 12);
    assert_int_equal(rep->dof, 0);
    assert_true(rep->assembled);
    assert_int_equal(rep->rank, 11);
    assert_int_equal(rep->nredundant, 1);
    for (int r = 0; r < rep->nr; r++)
        if (rep->rows[r].redundant != (strcmp(l->mech->model->rows[r].name, "A2.y") == 0))
            fail_msg("row %s: redundant = %d", l->mech->model->rows[r].name, rep->rows[r].redundant);
    assert_int_equal(rep->dof_rank, 1);
    assert_int_equal(rep->mobility_rank, 1);
    assert_true(rep->cond > 1e14);
    assert_int_equal(rep->singularity, SING_PERMANENT);
    assert_int_equal(rep->generic_rank, 11);
    assert_contains(rep->verdict, "the count says 0 DOF");
    assert_contains(rep->verdict, "rank 11 of 12");
    assert_contains(rep->verdict, "moves with 1 DOF");
    assert_contains(rep->verdict, "row A2.y is redundant");
    unload(l);
}

static void test_rank_tolerance_option(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text(parallelogram, "p.mech", &limits, &diag);
    assert_non_null(mech);
    AnalysisOptions o = analysis_default_options();
    o.rank_tol = 1e-30;         /* rounding noise counts as rank */
    InfoReport rep;
    assert_true(info_analyse(mech, 0.0, &o, &rep, &diag));
    assert_int_equal(rep.rank, 12);
    assert_near(rep.rank_tol, 1e-30, 0, 0);
    assert_int_equal(rep.nredundant, 0);
    info_report_free(&rep);
    pipeline_free(mech);
}

static void test_full_rank_trammel(void **state)
{
    (void)state;
    Loaded *l = load(trammel);
    assert_true(l->rep.assembled);
    assert_int_equal(l->rep.rank, 11);
    assert_int_equal(l->rep.nredundant, 0);
    assert_int_equal(l->rep.dof_rank, 0);
    assert_int_equal(l->rep.mobility, 1);
    assert_int_equal(l->rep.mobility_rank, 1);
    assert_int_equal(l->rep.singularity, SING_NONE);
    assert_true(l->rep.cond < 100);
    /* assembly moved the 4-decimal initial values onto the constraints */
    assert_near(l->rep.q[0], 2 * cos(M_PI / 4), 1e-12, 1e-12);
    assert_contains(l->rep.verdict, "full rank 11");
    assert_contains(l->rep.verdict, "fully driven");
    unload(l);
}

static void test_redundant_velocity_row(void **state)
{
    (void)state;
    Loaded *l = load(twice);
    assert_int_equal(l->rep.rank, 1);
    assert_int_equal(l->rep.rank_all, 2);
    assert_int_equal(l->rep.nredundant, 0);
    assert_int_equal(l->rep.nredundant_velocity, 1);
    assert_true(l->rep.rows[row_index(l, "again")].redundant);
    assert_false(l->rep.rows[row_index(l, "roll")].redundant);
    assert_int_equal(l->rep.dof, 0);
    assert_int_equal(l->rep.dof_rank, 1);
    unload(l);
}

/* ---- singular positions ---- */

static void test_toggle_is_singular_position(void **state)
{
    (void)state;
    Loaded *l = load(toggle);
    const InfoReport *rep = &l->rep;
    assert_true(rep->assembled);
    assert_int_equal(rep->rank, 8);
    assert_true(rep->cond > 1e12);
    assert_true(rep->sigma_min < 1e-12);
    assert_int_equal(rep->singularity, SING_POSITION);
    assert_int_equal(rep->rank_undriven_h, 7);
    assert_int_equal(rep->generic_rank, 8);
    assert_contains(rep->singular, "singular position");
    unload(l);
}

static void test_toggle_instant_of_example(void **state)
{
    (void)state;
    /* slider_crank_toggle.mech: regular at t = 0, near-singular at t = 0.25 */
    Loaded *l = load(slider_crank_toggle);
    assert_int_equal(l->rep.rank, 9);
    assert_true(l->rep.cond < 100);
    unload(l);
    l = load_at(slider_crank_toggle, 0.25);
    assert_true(l->rep.assembled);
    assert_true(l->rep.cond > 1e6);
    assert_near(l->rep.q[6], 0.0, 0, 1e-6);         /* slider at the crank pivot */
    assert_contains(l->rep.singular, "singular");
    unload(l);
}

static void test_driver_at_dead_centre(void **state)
{
    (void)state;
    Loaded *l = load(dead_centre);
    assert_int_equal(l->rep.rank, 8);
    assert_true(l->rep.cond > 1e12);
    assert_int_equal(l->rep.singularity, SING_DRIVERS);
    assert_true(l->rep.rows[row_index(l, "D")].redundant);
    assert_contains(l->rep.verdict, "singular position");
    unload(l);
}

/* ---- assembly ---- */

static void test_min_norm_newton_four_bar(void **state)
{
    (void)state;
    Loaded *l = load(four_bar_free);
    const InfoReport *rep = &l->rep;
    const Model *m = l->mech->model;
    assert_int_equal(rep->nh, 8);
    assert_int_equal(rep->dof, 1);
    assert_true(rep->assembled);
    assert_true(rep->assembly.iterations > 0);
    assert_true(rep->assembly.residual <= 1e-10);
    assert_int_equal(rep->rank, 8);
    /* the constraints hold at the returned q */
    MechEval me;
    mech_eval_init(&me, &l->mech->kin);
    double phi[8];
    mech_eval(&me, rep->q, 0.0, phi, NULL);
    for (int i = 0; i < 8; i++)
        assert_near(phi[i], 0.0, 0, 1e-10);
    mech_eval_free(&me);
    /* minimum norm: the nearest configuration, not a far one */
    double dist = 0;
    for (int i = 0; i < m->nq; i++)
        dist += (rep->q[i] - m->q0[i]) * (rep->q[i] - m->q0[i]);
    assert_true(sqrt(dist) < 0.3);
    assert_contains(rep->verdict, "moves with 1 DOF");
    unload(l);
}

static void test_assembly_failure_reported(void **state)
{
    (void)state;
    Loaded *l = load(impossible);
    assert_false(l->rep.assembled);
    assert_false(l->rep.assembly.converged);
    assert_true(l->rep.assembly.residual > 1);
    assert_contains(l->rep.verdict, "assembly failed");
    unload(l);
}

/* ---- the sparse path (beyond the dense limit) ---- */

static Loaded *load_opts(const char *text, const AnalysisOptions *o)
{
    Loaded *l = calloc(1, sizeof *l);
    MechLimits limits = mech_default_limits();
    l->mech = pipeline_load_text(text, "test.mech", &limits, &l->diag);
    if (!l->mech) {
        diag_print(&l->diag, stderr);
        fail_msg("fixture does not load");
    }
    if (!info_analyse(l->mech, 0.0, o, &l->rep, &l->diag))
        fail_msg("info_analyse failed: %s", l->diag.message);
    return l;
}

/* A chain of n unit parallelograms (examples/chain.sh) with a third, middle
   crank in every loop: n redundant rows; rod0 driven. */
static char *ladder(int n, double shift)
{
    size_t cap = 400 + (size_t)n * 400;
    char *t = malloc(cap);
    size_t k = 0;
    for (int i = 0; i <= n; i++)
        k += (size_t)snprintf(t + k, cap - k, "body rod%d x = %g y = 0.5 phi = pi/2\n", i, i + shift);
    for (int i = 0; i < n; i++)
        k += (size_t)snprintf(t + k, cap - k,
                              "body cpl%d x = %g y = 1 phi = 0\nbody mid%d x = %g y = 0.5 phi = pi/2\n",
                              i, i + 0.5 + shift, i, i + 0.5);
    for (int i = 0; i <= n; i++)
        k += (size_t)snprintf(t + k, cap - k, "revolute G%d: ground(%d, 0) rod%d(-0.5, 0)\n", i, i, i);
    for (int i = 0; i < n; i++)
        k += (size_t)snprintf(t + k, cap - k,
                              "revolute L%d: rod%d(0.5, 0) cpl%d(-0.5, 0)\n"
                              "revolute R%d: rod%d(0.5, 0) cpl%d(0.5, 0)\n"
                              "revolute M%d: ground(%g, 0) mid%d(-0.5, 0)\n"
                              "revolute T%d: mid%d(0.5, 0) cpl%d(0, 0)\n",
                              i, i, i, i, i + 1, i, i, i + 0.5, i, i, i, i);
    snprintf(t + k, cap - k, "driver D: rod0.phi = pi/2\n");
    return t;
}

static void test_sparse_path_agrees_with_dense(void **state)
{
    (void)state;
    const char *fixtures[] = {parallelogram, toggle, dead_centre, four_bar_free, trammel, twice,
                              knife_cart, NULL};
    char *lad = ladder(3, 0.0);
    for (int f = 0; f <= 7; f++) {
        const char *text = f < 7 ? fixtures[f] : lad;
        AnalysisOptions o = analysis_default_options();
        Loaded *d = load_opts(text, &o);
        o.max_dense = 0;
        Loaded *s = load_opts(text, &o);
        assert_true(d->rep.dense);
        assert_false(s->rep.dense);
        assert_int_equal(s->rep.assembled, d->rep.assembled);
        assert_int_equal(s->rep.rank, d->rep.rank);
        assert_int_equal(s->rep.rank_all, d->rep.rank_all);
        assert_int_equal(s->rep.rank_undriven, d->rep.rank_undriven);
        for (int r = 0; r < d->rep.nr; r++)
            if (s->rep.rows[r].redundant != d->rep.rows[r].redundant)
                fail_msg("fixture %d row %s: sparse %d, dense %d", f, d->mech->model->rows[r].name,
                         s->rep.rows[r].redundant, d->rep.rows[r].redundant);
        for (int i = 0; i < d->rep.nq; i++)         /* the same minimum-norm configuration */
            assert_near(s->rep.q[i], d->rep.q[i], 1e-9, 1e-9);
        assert_true(isnan(s->rep.cond));
        unload(d);
        unload(s);
    }
    free(lad);
}

static void test_sparse_large_ladder(void **state)
{
    (void)state;
    /* 301 rods, 300 couplers, 300 middle cranks: 2703 coordinates, 3003 rows,
       beyond the dense limit; started 0.01 off so the sparse Newton works too */
    int n = 300;
    char *text = ladder(n, 0.01);
    AnalysisOptions o = analysis_default_options();
    Loaded *l = load_opts(text, &o);
    const InfoReport *rep = &l->rep;
    assert_false(rep->dense);
    assert_int_equal(rep->nq, 9 * n + 3);
    assert_int_equal(rep->nh, 10 * n + 3);
    assert_int_equal(rep->dof, -n);
    assert_true(rep->assembled);
    assert_true(rep->assembly.iterations > 0);
    assert_int_equal(rep->rank, 9 * n + 3);
    assert_int_equal(rep->nredundant, n);
    assert_int_equal(rep->dof_rank, 0);
    for (int r = 0; r < rep->nr; r++)       /* the redundant row of each loop is its middle crank's */
        if (rep->rows[r].redundant && strncmp(l->mech->model->rows[r].name, "T", 1) != 0)
            fail_msg("unexpected redundant row %s", l->mech->model->rows[r].name);
    unload(l);
    free(text);
}

/* ---- SuiteSparseQR: dependent rows and null space (spqr_rank.c) ---- */

/* Rows r0, r1, r0 + r1, r2, 2 r2, r3 of 4 columns (CSR). */
static const int dep_start[] = {0, 2, 4, 7, 9, 11, 12};
static const int dep_cols[] = {0, 1,  1, 2,  0, 1, 2,  2, 3,  2, 3,  0};
static const double dep_vals[] = {1, 2,  3, -1,  1, 5, -1,  0.5, 4,  1, 8,  7};

static void test_spqr_dependent_rows_as_svd(void **state)
{
    (void)state;
    SpqrRows a = {.m = 6, .n = 4, .start = dep_start, .cols = dep_cols, .vals = dep_vals};
    bool dep[6];
    int upto;
    assert_int_equal(spqr_dependent_rows(&a, 1e-12, dep, 3, &upto), 4);
    assert_int_equal(upto, 2);                  /* rows 0..2: r0, r1, r0 + r1 */
    bool want[6] = {false, false, true, false, true, false};
    /* the dense SVD's answer on the same matrix */
    double dense[24] = {0};
    for (int i = 0; i < 6; i++)
        for (int e = dep_start[i]; e < dep_start[i + 1]; e++)
            dense[i * 4 + dep_cols[e]] = dep_vals[e];
    MechrtSvd *w = svd_work_new(6, 4);
    bool red[6];
    assert_int_equal(svd_redundant_rows(w, dense, 6, 4, 4, 1e-12, 0, -1, red), 2);
    mechrt_svd_free(w);
    for (int i = 0; i < 6; i++) {
        assert_int_equal(dep[i], want[i]);
        assert_int_equal(red[i], want[i]);
    }
    /* a tolerance above every remaining norm: only the first row counts */
    assert_int_equal(spqr_dependent_rows(&a, 1e3, dep, 0, NULL), 0);
    double bad[12];
    memcpy(bad, dep_vals, sizeof bad);
    bad[5] = NAN;
    a.vals = bad;
    assert_int_equal(spqr_dependent_rows(&a, 1e-12, dep, 0, NULL), -1);
}

static void test_spqr_null_basis(void **state)
{
    (void)state;
    /* the 6 x 4 matrix above has rank 4: no null space; its first two rows
       (2 x 4, rank 2) leave two directions, free at columns 2 and 3 */
    SpqrRows a = {.m = 6, .n = 4, .start = dep_start, .cols = dep_cols, .vals = dep_vals};
    double basis[16];
    int free_coords[4];
    assert_int_equal(spqr_null_basis(&a, 1e-12, 4, basis, free_coords), 0);
    a.m = 2;
    assert_int_equal(spqr_null_basis(&a, 1e-12, 4, basis, free_coords), 2);
    assert_int_equal(free_coords[0], 2);
    assert_int_equal(free_coords[1], 3);
    for (int k = 0; k < 2; k++) {
        const double *v = basis + 4 * k;
        assert_near(v[free_coords[k]], 1.0, 0, 0);
        assert_near(v[free_coords[1 - k]], 0.0, 0, 0);
        for (int i = 0; i < 2; i++) {           /* A v = 0 */
            double s = 0;
            for (int e = dep_start[i]; e < dep_start[i + 1]; e++)
                s += dep_vals[e] * v[dep_cols[e]];
            assert_near(s, 0.0, 0, 1e-14);
        }
    }
    /* only one vector asked for: the dimension is still 2 */
    assert_int_equal(spqr_null_basis(&a, 1e-12, 1, basis, free_coords), 2);
}

/* ---- info at a state: the A02 chain of n parallelograms driven flat ---- */

/* examples/chain.sh n with rod0.phi = pi/2 - 2 pi t: flat at t = 0.25. */
static char *flat_chain(int n)
{
    size_t cap = 200 + (size_t)n * 300;
    char *t = malloc(cap);
    size_t k = (size_t)snprintf(t, cap, "body rod0 x = 0 y = 0.5 phi = pi/2\n"
                                "revolute g0: ground(0, 0) rod0(-0.5, 0)\n"
                                "driver drive: rod0.phi = pi/2 - 2*pi*t\n");
    for (int i = 0; i < n; i++)
        k += (size_t)snprintf(t + k, cap - k,
                              "body cpl%d x = %g y = 1 phi = 0\n"
                              "body rod%d x = %d y = 0.5 phi = pi/2\n"
                              "revolute g%d: ground(%d, 0) rod%d(-0.5, 0)\n"
                              "revolute a%d: rod%d(0.5, 0) cpl%d(-0.5, 0)\n"
                              "revolute b%d: cpl%d(0.5, 0) rod%d(0.5, 0)\n",
                              i, i + 0.5, i + 1, i + 1, i + 1, i + 1, i + 1, i, i, i, i, i, i + 1);
    return t;
}

static Loaded *load_state(const char *text, double t, const InfoAt *at, const AnalysisOptions *o)
{
    Loaded *l = calloc(1, sizeof *l);
    MechLimits limits = mech_default_limits();
    l->mech = pipeline_load_text(text, "test.mech", &limits, &l->diag);
    if (!l->mech) {
        diag_print(&l->diag, stderr);
        fail_msg("fixture does not load");
    }
    if (!info_analyse_at(l->mech, t, at, o, &l->rep, &l->diag))
        fail_msg("info_analyse_at failed: %s", l->diag.message);
    return l;
}

/* The drop, the rows that became dependent (b0.x .. b{n-1}.x: each loop's
   last pin, in x) and n null directions, each a true null vector. */
static void check_flat(Loaded *l, int n)
{
    const InfoReport *rep = &l->rep;
    const InfoState *st = &rep->state;
    const Model *m = l->mech->model;
    assert_true(st->asked);
    assert_true(rep->assembled);
    assert_true(st->residual < 1e-10);
    assert_int_equal(st->ref_rank, 6 * n + 3);
    assert_int_equal(rep->rank, 5 * n + 3);
    assert_int_equal(st->drop, n);
    assert_int_equal(st->ndependent, n);
    for (int k = 0; k < n; k++) {
        char name[32];
        snprintf(name, sizeof name, "b%d.x", k);
        assert_string_equal(m->rows[st->dependent[k]].name, name);
    }
    assert_int_equal(st->nnull, n);
    assert_int_equal(st->nshown, n);
    double *jac = malloc((size_t)m->nr * (size_t)m->nq * sizeof *jac);
    MechEval me;
    mech_eval_init(&me, &l->mech->kin);
    mech_eval(&me, rep->q, rep->t, NULL, jac);
    for (int k = 0; k < n; k++) {
        const double *v = st->null + (size_t)k * (size_t)m->nq;
        assert_near(v[st->free_coord[k]], 1.0, 0, 0);
        for (int r = 0; r < m->nh; r++) {
            double s = 0;
            for (int j = 0; j < m->nq; j++)
                s += jac[(size_t)r * (size_t)m->nq + (size_t)j] * v[j];
            assert_near(s, 0.0, 0, 1e-9);
        }
    }
    mech_eval_free(&me);
    free(jac);
}

static void test_state_followed_to_flat(void **state)
{
    (void)state;
    char *text = flat_chain(3);
    AnalysisOptions o = analysis_default_options();
    InfoAt at = {.follow = true};
    Loaded *d = load_state(text, 0.25, &at, &o);
    assert_true(d->rep.dense);
    assert_true(d->rep.state.steps > 100);
    assert_true(d->rep.state.reached);
    check_flat(d, 3);
    o.max_dense = -1;                   /* the same by SuiteSparseQR */
    Loaded *s = load_state(text, 0.25, &at, &o);
    assert_false(s->rep.dense);
    check_flat(s, 3);
    for (int i = 0; i < d->rep.nq; i++)
        assert_near(s->rep.q[i], d->rep.q[i], 1e-10, 1e-10);
    /* the same state given coordinate by coordinate */
    InfoAt given = {.q = d->rep.q};
    o = analysis_default_options();
    Loaded *g = load_state(text, 0.25, &given, &o);
    assert_true(g->rep.state.given);
    check_flat(g, 3);
    unload(d), unload(s), unload(g);
    /* at an ordinary time nothing drops and nothing is free */
    Loaded *r = load_state(text, 0.1, &at, &o);
    assert_int_equal(r->rep.state.drop, 0);
    assert_int_equal(r->rep.state.ndependent, 0);
    assert_int_equal(r->rep.state.nnull, 0);
    assert_int_equal(r->rep.rank, 21);
    unload(r);
    free(text);
}

/* Assembled directly at t = 0.25 from the file's initial values (--t),
   the chain lands on a folded branch: one loop folded, not all of them. */
static void test_direct_assembly_is_not_the_motion(void **state)
{
    (void)state;
    char *text = flat_chain(3);
    Loaded *l = load_at(text, 0.25);
    assert_false(l->rep.state.asked);
    assert_true(l->rep.rank > 5 * 3 + 3);
    unload(l);
    free(text);
}

/* ---- integrability ---- */

static void test_knife_is_nonholonomic(void **state)
{
    (void)state;
    Loaded *l = load(knife_cart);
    const Integrability *blade = integ(l, "blade");
    assert_true(blade->decided);
    assert_false(blade->integrable);
    assert_null(blade->law);
    assert_int_equal(blade->ncoords, 3);
    assert_true(blade->samples > 0);
    assert_contains(blade->note, "cart.x, cart.y, cart.phi");
    assert_false(integ(l, "fwd")->integrable);
    /* the turn-rate driver is phi - w t = const */
    const Integrability *turn = integ(l, "turn");
    assert_true(turn->integrable);
    assert_true(turn->symbolic);
    assert_contains(turn->law, "cart.phi - 3.141592653589793*t = const");
    assert_int_equal(l->rep.rank_all, 3);
    unload(l);
}

static void test_rolling_disk_is_integrable(void **state)
{
    (void)state;
    Loaded *l = load(rolling_disk);
    const Integrability *roll = integ(l, "roll");
    assert_true(roll->integrable);
    assert_true(roll->symbolic);
    assert_contains(roll->law, "disk.x + 0.5*disk.phi");
    assert_contains(roll->law, "= const");
    const Integrability *spin = integ(l, "spin");
    assert_true(spin->integrable);
    assert_contains(spin->law, "disk.phi + 6.283185307179586*t = const");
    unload(l);
}

static void test_rolling_statement_is_integrable(void **state)
{
    (void)state;
    Loaded *l = load(rolling_wheel);
    const Integrability *roll = integ(l, "roll");
    assert_true(roll->integrable);
    assert_string_equal(roll->law, "wheel.x + 0.5*wheel.phi = const");
    unload(l);
}

static void test_integrability_cases(void **state)
{
    (void)state;
    Loaded *l = load(velocity_rows);
    const Integrability *it;

    it = integ(l, "exact");
    assert_true(it->integrable);
    assert_string_equal(it->law, "x*y = const");

    it = integ(l, "contact");
    assert_true(it->decided);
    assert_false(it->integrable);
    assert_contains(it->note, "(x, y, z) component is -1");

    it = integ(l, "consts");            /* a symbolic proof over three coordinates */
    assert_true(it->integrable);
    assert_true(it->symbolic);
    assert_int_equal(it->triples, 1);
    assert_string_equal(it->law, "x + 2*y + 3*z = const");

    it = integ(l, "factor");            /* numerical evidence, law through 1/exp(x) */
    assert_true(it->integrable);
    assert_false(it->symbolic);
    assert_true(it->samples > 0);
    assert_contains(it->note, "numerical evidence");
    assert_contains(it->note, "integrating factor 1/(exp(x))");
    /* the order of the terms follows node ids: either spelling is right */
    if (!it->law || (strcmp(it->law, "z + x*y = const") && strcmp(it->law, "x*y + z = const")))
        fail_msg("law %s", it->law ? it->law : "(null)");

    it = integ(l, "rotate");            /* integrable, but no law in the table */
    assert_true(it->integrable);
    assert_null(it->law);
    assert_contains(it->note, "law not found in closed form");

    it = integ(l, "timed");             /* b(t) != 0: omega = dx - cos(t) dt */
    assert_true(it->integrable);
    assert_string_equal(it->law, "x - sin(t) = const");

    it = integ(l, "scaled");            /* t dy: factor 1/t */
    assert_true(it->integrable);
    assert_string_equal(it->law, "y = const");
    unload(l);
}

static void test_system_of_rows(void **state)
{
    (void)state;
    static const char fixed[] =         /* heading held by a holonomic row */
        "body cart x = 1  y = 0  phi = 0.3\n"
        "knife  blade: cart axis(1, 0)\n"
        "constraint head: cart.phi = 0.3\n";
    static const char turning[] =       /* heading turned by a time-dependent row */
        "body cart x = 1  y = 0  phi = 0.3\n"
        "knife  blade: cart axis(1, 0)\n"
        "constraint head: cart.phi = 0.3 + t\n";
    Loaded *l = load(knife_cart);       /* drivers left out: the blade alone */
    assert_true(l->rep.system.tested);
    assert_false(l->rep.system.involutive);
    assert_contains(l->rep.system.note, "row blade");
    unload(l);
    l = load(fixed);
    assert_false(integ(l, "blade")->integrable);     /* alone, on all of (q, t) */
    assert_true(l->rep.system.tested);
    assert_true(l->rep.system.involutive);           /* on the manifold phi = 0.3 */
    assert_true(l->rep.system.points > 1);
    unload(l);
    l = load(turning);
    assert_true(l->rep.system.tested);
    assert_false(l->rep.system.involutive);
    unload(l);
    l = load(rolling_wheel);
    assert_true(l->rep.system.tested);
    assert_true(l->rep.system.involutive);
    unload(l);
    l = load(parallelogram);
    assert_false(l->rep.system.tested);
    unload(l);
}

/* ---- counts ---- */

static void test_textbook_table_and_counts(void **state)
{
    (void)state;
    /* what each joint removes, by the textbook (info_textbook_rows reads joints.def) */
    static const struct { JointKind kind; int rows; bool velocity; } textbook[] = {
        {JOINT_REVOLUTE, 2, false}, {JOINT_PRISMATIC, 2, false}, {JOINT_DISTANCE, 1, false},
        {JOINT_POINTLINE, 1, false}, {JOINT_WELD, 3, false}, {JOINT_CONSTRAINT, 1, false},
        {JOINT_DRIVER, 1, false}, {JOINT_ROLLING, 1, true}, {JOINT_KNIFE, 1, true},
        {JOINT_VELOCITY, 1, true},
    };
    for (size_t k = 0; k < sizeof textbook / sizeof *textbook; k++) {
        bool vel;
        int n = info_textbook_rows(textbook[k].kind, &vel);
        if (n != textbook[k].rows || vel != textbook[k].velocity)
            fail_msg("%s: %d rows (velocity %d), the textbook %d (velocity %d)",
                     joint_info[textbook[k].kind].keyword, n, vel, textbook[k].rows, textbook[k].velocity);
    }
    Loaded *l = load(knife_cart);
    assert_int_equal(l->rep.nq, 3);
    assert_int_equal(l->rep.nh, 0);
    assert_int_equal(l->rep.nv, 3);
    assert_int_equal(l->rep.dof, 0);
    assert_int_equal(l->rep.nv_drivers, 2);
    assert_int_equal(l->rep.mobility, 2);
    assert_int_equal(l->rep.mobility_rank, 2);
    assert_true(l->rep.assembled);
    assert_int_equal(l->rep.rank, 0);
    unload(l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_svd_values_rank_cond),
        cmocka_unit_test(test_svd_wide_min_norm),
        cmocka_unit_test(test_svd_tall_least_squares),
        cmocka_unit_test(test_redundant_rows_incremental),
        cmocka_unit_test(test_node_values_many_roots),
        cmocka_unit_test(test_parallelogram_rank_and_redundant_row),
        cmocka_unit_test(test_rank_tolerance_option),
        cmocka_unit_test(test_full_rank_trammel),
        cmocka_unit_test(test_redundant_velocity_row),
        cmocka_unit_test(test_toggle_is_singular_position),
        cmocka_unit_test(test_toggle_instant_of_example),
        cmocka_unit_test(test_driver_at_dead_centre),
        cmocka_unit_test(test_min_norm_newton_four_bar),
        cmocka_unit_test(test_assembly_failure_reported),
        cmocka_unit_test(test_sparse_path_agrees_with_dense),
        cmocka_unit_test(test_sparse_large_ladder),
        cmocka_unit_test(test_spqr_dependent_rows_as_svd),
        cmocka_unit_test(test_spqr_null_basis),
        cmocka_unit_test(test_state_followed_to_flat),
        cmocka_unit_test(test_direct_assembly_is_not_the_motion),
        cmocka_unit_test(test_knife_is_nonholonomic),
        cmocka_unit_test(test_rolling_disk_is_integrable),
        cmocka_unit_test(test_rolling_statement_is_integrable),
        cmocka_unit_test(test_integrability_cases),
        cmocka_unit_test(test_system_of_rows),
        cmocka_unit_test(test_textbook_table_and_counts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
