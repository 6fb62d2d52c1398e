/* test_inverse.c - inverse dynamics along a driven run (run_analysis_forces, `run --forces`) against closed forms.
 *
 * The slider-crank with uniform links turned at constant speed
 * (examples/slider_crank_torque.mech): the driver's effort -lambda(D) is
 * the crank torque of the reference table in the file's header (derived
 * by Lagrange's equation and checked by Newton-Euler, /work/wt/dref
 * REFS.md section 3), at theta = 0, 30, ..., 330 degrees, with and without
 * gravity, and at 100 steps against the formula coded here; the jit and
 * generic engines both. The compound pendulum driven with an angular
 * acceleration: the motor torque (J + m a^2) phi'' + m g a cos(phi) and
 * the revolute's reaction on the rod, m a_G - m g, against their closed
 * forms. The slider-crank's reactions balance the weights; run's square
 * solve equals the runtime's rank-revealing one; through the flat
 * positions of a parallelogram the runtime's minimum-norm lambda takes
 * over. The arrows' forces (render/reactions.c) of a revolute, a
 * prismatic and a distance from given multipliers. A file without masses
 * is refused.
 */
#include "testutil.h"
#include "testload.h"

#include <stdlib.h>
#include <string.h>

#include "../generator/kin/run.h"
#include "../generator/base/arena.h"
#include "../generator/engine/engine.h"
#include "../generator/render/reactions.h"

/* Every state and its multipliers. */
typedef struct Kept {
    int nq, nr, n;
    double t[256], q[256][16], qd[256][16], qdd[256][16], lambda[256][16];
} Kept;

static void keep(void *ctx, double t, const double *q, const double *qd, const double *qdd,
                 const double *lambda)
{
    Kept *k = ctx;
    assert_true(k->n < 256);
    memcpy(k->qd[k->n], qd, (size_t)k->nq * sizeof *qd);
    k->t[k->n] = t;
    memcpy(k->q[k->n], q, (size_t)k->nq * sizeof *q);
    memcpy(k->qdd[k->n], qdd, (size_t)k->nq * sizeof *qdd);
    memcpy(k->lambda[k->n], lambda, (size_t)k->nr * sizeof *lambda);
    k->n++;
}

static int row_of(const Model *m, const char *name)
{
    for (int i = 0; i < m->nr; i++)
        if (strcmp(m->rows[i].name, name) == 0)
            return i;
    fail_msg("no row %s", name);
    return -1;
}

static int coord_of(const Model *m, const char *name)
{
    for (int i = 0; i < m->nq; i++)
        if (strcmp(m->coord_names[i], name) == 0)
            return i;
    fail_msg("no coordinate %s", name);
    return -1;
}

/* run_analysis_forces over [0, t1] in steps intervals with engine kind. */
static void run_forces(const Mech *mech, EngineKind kind, double t1, int steps, Kept *k)
{
    Engine e;
    Diag diag;
    if (!engine_open(&e, kind, mech, &diag))
        fail_msg("%s: %s", engine_names[kind], diag.message);
    RunOptions o = run_default_options();
    o.t1 = t1;
    o.steps = steps;
    RunResult res;
    memset(k, 0, sizeof *k);
    k->nq = mech->model->nq;
    k->nr = mech->model->nr;
    assert_true(k->nq <= 16 && k->nr <= 16);
    AnalysisStatus st = run_analysis_forces(mech->model, &e.k, NULL, &o, keep, k, &res);
    if (st != ANALYSIS_OK)
        fail_msg("%s: %s", engine_names[kind], res.message);
    assert_int_equal(k->n, steps + 1);
    assert_true(res.force_residual < 1e-9);
    assert_int_equal(res.force_redundant, 0);
    engine_close(&e);
}

/* ---- the slider-crank's crank torque ---- */

/* The reference table (REFS.md section 3.3): theta = 30 k degrees. */
static const double tau_g0[12] = {
    0, 0.718528783342604, 0.395289642412457, -0.348943209981944, -0.530553173931687,
    -0.294312157323148, 0, 0.294312157323148, 0.530553173931687, 0.348943209981944,
    -0.395289642412457, -0.718528783342604};
static const double tau_g[12] = {
    1.4715, 1.99288516501141, 1.13103964241246, -0.348943209981944, -1.26630317393169,
    -1.56866853899195, -1.4715, -0.980044224345654, -0.205196826068313, 0.348943209981944,
    0.340460357587543, 0.555827598326197};

/* The closed form: Lagrange's equation with the kinematic coefficients. */
static double crank_torque(double th, double g)
{
    const double r = 0.1, l = 0.3, w = 2 * M_PI, m1 = 1, m2 = 2, m3 = 1.5, J2 = m2 * l * l / 12;
    double phi = asin(-r / l * sin(th)), sp = sin(phi), cp = cos(phi);
    double p1 = -r * cos(th) / (l * cp), p2 = (r * sin(th) + l * sp * p1 * p1) / (l * cp);
    double xb1 = -r * sin(th) - l * sp * p1, xb2 = -r * cos(th) - l * cp * p1 * p1 - l * sp * p2;
    double xg1 = -r * sin(th) - l / 2 * sp * p1;
    double xg2 = -r * cos(th) - l / 2 * (cp * p1 * p1 + sp * p2);
    double yg1 = r / 2 * cos(th), yg2 = -r / 2 * sin(th);
    return w * w * (m2 * (xg1 * xg2 + yg1 * yg2) + J2 * p1 * p2 + m3 * xb1 * xb2)
           + g * (m1 * r / 2 + m2 * r / 2) * cos(th);
}

/* The example's text with g replaced (g = 0: no gravity). */
static Mech *load_torque_example(double g)
{
    const char *dir = getenv("MECHC_EXAMPLES");
    char path[600], line[256];
    snprintf(path, sizeof path, "%s/slider_crank_torque.mech", dir ? dir : "examples");
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t cap = 1 << 16, len = 0;
    char *text = xcalloc(cap, 1);
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "param g ", 8) == 0)
            snprintf(line, sizeof line, "param g = %.17g\n", g);
        size_t n = strlen(line);
        assert_true(len + n < cap);
        memcpy(text + len, line, n + 1);
        len += n;
    }
    fclose(f);
    Mech *m = load_text(text, "slider_crank_torque.mech");
    free(text);
    return m;
}

static void test_crank_torque_table(void **state)
{
    (void)state;
    for (int grav = 0; grav < 2; grav++) {
        Mech *mech = load_torque_example(grav ? 9.81 : 0);
        int d = row_of(mech->model, "D");
        for (int kind = 0; kind < 2; kind++) {     /* jit, generic */
            Kept k;
            run_forces(mech, kind == 0 ? ENGINE_JIT : ENGINE_GENERIC, 1, 12, &k);
            for (int i = 0; i < 12; i++) {
                double want = grav ? tau_g[i] : tau_g0[i];
                assert_near(-k.lambda[i][d], want, 1e-9, 1e-12);
            }
            assert_near(-k.lambda[12][d], grav ? tau_g[0] : tau_g0[0], 1e-9, 1e-12);
        }
        pipeline_free(mech);
    }
}

static void test_crank_torque_formula(void **state)
{
    (void)state;
    Mech *mech = load_torque_example(9.81);
    const Model *m = mech->model;
    int d = row_of(m, "D"), phi = coord_of(m, "crank.phi");
    Kept k;
    run_forces(mech, ENGINE_JIT, 1, 100, &k);
    for (int i = 0; i <= 100; i++)
        assert_near(-k.lambda[i][d], crank_torque(k.q[i][phi], 9.81), 1e-9, 1e-12);
    pipeline_free(mech);
}

/* The reactions balance the weights and the inertia: the force of O on
   the crank, (lambda(O.x), lambda(O.y)), and of the guide on the slider,
   (0, -lambda(P.n)), equal sum m a_G - sum m g. */
static void test_slider_crank_balance(void **state)
{
    (void)state;
    Mech *mech = load_torque_example(9.81);
    const Model *m = mech->model;
    int ox = row_of(m, "O.x"), oy = row_of(m, "O.y"), pn = row_of(m, "P.n");
    const double mass[3] = {1, 2, 1.5}, g = 9.81;
    const char *body[3] = {"crank", "rod", "slider"};
    Kept k;
    run_forces(mech, ENGINE_JIT, 1, 24, &k);
    for (int i = 0; i <= 24; i++) {
        double fx = 0, fy = 0;
        for (int b = 0; b < 3; b++) {
            char name[32];
            snprintf(name, sizeof name, "%s.x", body[b]);
            fx += mass[b] * k.qdd[i][coord_of(m, name)];
            snprintf(name, sizeof name, "%s.y", body[b]);
            fy += mass[b] * (k.qdd[i][coord_of(m, name)] + g);
        }
        assert_near(k.lambda[i][ox], fx, 1e-9, 1e-9);
        assert_near(k.lambda[i][oy] - k.lambda[i][pn], fy, 1e-9, 1e-9);
    }
    pipeline_free(mech);
}

/* ---- the compound pendulum, driven ---- */

/* A uniform rod (L = 1.2, m = 2, centre of mass a = L/2 from the pin at
   the origin), turned by phi = -pi/2 + w t + alpha t^2 / 2. */
static const char driven_pendulum[] =
    "param L = 1.2\nparam m = 2\nparam w = 3\nparam alpha = 1.5\n"
    "body rod phi = -pi/2\n"
    "revolute O: ground rod\n"
    "driver D: rod.phi = -pi/2 + w*t + alpha*t^2/2\n"
    "mass rod m = m J = m*L^2/12 com(L/2, 0)\n"
    "gravity (0, -9.81)\n";

static void test_driven_pendulum(void **state)
{
    (void)state;
    const double L = 1.2, m = 2, w = 3, alpha = 1.5, g = 9.81, a = L / 2, J = m * L * L / 12;
    Mech *mech = load_text(driven_pendulum, "driven_pendulum.mech");
    const Model *mo = mech->model;
    int d = row_of(mo, "D"), ox = row_of(mo, "O.x"), oy = row_of(mo, "O.y");
    for (int kind = 0; kind < 2; kind++) {
        Kept k;
        run_forces(mech, kind == 0 ? ENGINE_JIT : ENGINE_GENERIC, 2, 40, &k);
        for (int i = 0; i <= 40; i++) {
            double t = k.t[i], phi = -M_PI / 2 + w * t + alpha * t * t / 2, pd = w + alpha * t;
            double c = cos(phi), s = sin(phi);
            /* the motor torque: (J + m a^2) phi'' + m g a cos(phi) */
            assert_near(-k.lambda[i][d], (J + m * a * a) * alpha + m * g * a * c, 1e-9, 1e-12);
            /* the pin's force on the rod (its second body): m a_G - m g */
            double agx = a * (-s * alpha - c * pd * pd), agy = a * (c * alpha - s * pd * pd);
            assert_near(k.lambda[i][ox], m * agx, 1e-9, 1e-12);
            assert_near(k.lambda[i][oy], m * agy + m * g, 1e-9, 1e-12);
        }
    }
    pipeline_free(mech);
}

/* run's square solve (one LU of Phi_q, a transposed solve) against the
   runtime's rank-revealing mechrt_inverse_dynamics at every state. */
static void test_same_as_runtime(void **state)
{
    (void)state;
    Mech *mech = load_torque_example(9.81);
    const Model *m = mech->model;
    Kept k;
    run_forces(mech, ENGINE_JIT, 1, 36, &k);
    Engine e;
    Diag diag;
    assert_true(engine_open(&e, ENGINE_JIT, mech, &diag));
    size_t lw = mechrt_dynamics_workspace_size(m->nq, m->nr);
    double *work = xcalloc(lw, sizeof *work), lambda[16];
    for (int i = 0; i <= 36; i++) {
        MechrtDynReport dr;
        assert_int_equal(mechrt_inverse_dynamics(&e.k, NULL, k.q[i], k.qd[i], k.qdd[i], k.t[i],
                                                 lambda, work, lw, &dr), MECHRT_OK);
        assert_int_equal(dr.rank, m->nr);
        for (int r = 0; r < m->nr; r++)
            assert_near(k.lambda[i][r], lambda[r], 1e-10, 1e-10);
    }
    free(work);
    engine_close(&e);
    pipeline_free(mech);
}

/* The parallelogram four-bar folds flat at t = 0.25 and 0.75 (run passes
   there by the rank-revealing corrector): with masses, lambda there is
   the runtime's minimum-norm one, one row found dependent, finite. */
static const char parallelogram_masses[] =
    "param omega = 2*pi\n"
    "body crank   x = 0  y = 0.5  phi = pi/2\n"
    "body coupler x = 1  y = 1    phi = 0\n"
    "body rocker  x = 2  y = 0.5  phi = pi/2\n"
    "revolute O1: ground(0, 0)    crank(-0.5, 0)\n"
    "revolute A:  crank(0.5, 0)   coupler(-1, 0)\n"
    "revolute B:  coupler(1, 0)   rocker(0.5, 0)\n"
    "revolute O2: ground(2, 0)    rocker(-0.5, 0)\n"
    "driver drive: crank.phi = pi/2 + omega*t\n"
    "mass crank m = 1 J = 1/12\nmass coupler m = 2 J = 2*4/12\nmass rocker m = 1 J = 1/12\n"
    "gravity (0, -9.81)\n";

static void test_through_singular(void **state)
{
    (void)state;
    Mech *mech = load_text(parallelogram_masses, "parallelogram_masses.mech");
    Engine e;
    Diag diag;
    assert_true(engine_open(&e, ENGINE_JIT, mech, &diag));
    RunOptions o = run_default_options();
    o.steps = 100;
    RunResult res;
    Kept k;
    memset(&k, 0, sizeof k);
    k.nq = mech->model->nq, k.nr = mech->model->nr;
    assert_int_equal(run_analysis_forces(mech->model, &e.k, NULL, &o, keep, &k, &res), ANALYSIS_OK);
    assert_int_equal(k.n, 101);
    assert_int_equal(res.force_redundant, 1);
    for (int i = 0; i <= 100; i++)
        for (int r = 0; r < k.nr; r++)
            assert_true(isfinite(k.lambda[i][r]));
    /* away from the flat positions the driver holds the weights: the
       effort is odd about t = 0.5 (the crank at pi/2 + pi) */
    int d = row_of(mech->model, "drive");
    assert_near(-k.lambda[10][d], k.lambda[90][d], 1e-9, 1e-9);
    engine_close(&e);
    pipeline_free(mech);
}

/* The arrows' forces (render/reactions.c) from given states and
   multipliers: a revolute's +lambda, a prismatic's -lambda n_A with A's
   normal turned by phi_A, a distance's -2 lambda (P_B - P_A). */
static void test_reaction_forces(void **state)
{
    (void)state;
    Mech *mech = load_text("body a phi = 0.3\nbody b x = 1\npoint p x = 3 y = 4\n"
                           "revolute R: ground a\nprismatic P: a(0.5, 0) b axis(2, 0)\n"
                           "distance D: ground(1, 1) p length = 2\n"
                           "driver d1: a.phi = 0.3\ndriver d2: b.x = 1\ndriver d3: p.x = 3\n",
                           "reactions.mech");
    const Model *m = mech->model;
    double q[2][8] = {{0, 0, 0.3, 1, 0, 0.3, 3, 4}, {0, 0, -0.7, 2, 1, -0.7, -1, 2}};
    double lambda[2][8] = {{1, 2, 3, 4, 0.5, 0, 0, 0}, {-1, 5, -2, 0, -0.25, 0, 0, 0}};
    assert_int_equal(m->nq, 8);
    assert_int_equal(m->nr, 8);
    SvgForce f[8];
    double *vals;
    int n = reactions_compute(m, &q[0][0], &lambda[0][0], 2, f, 8, &vals);
    assert_int_equal(n, 3);
    assert_string_equal(f[0].name, "R");
    assert_string_equal(f[1].name, "P");
    assert_string_equal(f[2].name, "D");
    for (int k = 0; k < 2; k++) {
        const double *r = f[0].f + k * f[0].stride, *p = f[1].f + k * f[1].stride;
        const double *d = f[2].f + k * f[2].stride, *l = lambda[k];
        assert_near(r[0], l[0], 0, 1e-15);
        assert_near(r[1], l[1], 0, 1e-15);
        /* n_A = A(phi_a) (0, 2) */
        double phi = q[k][2];
        assert_near(p[0], -l[2] * (-2 * sin(phi)), 1e-15, 1e-15);
        assert_near(p[1], -l[2] * (2 * cos(phi)), 1e-15, 1e-15);
        assert_near(d[0], -2 * l[4] * (q[k][6] - 1), 1e-15, 1e-15);
        assert_near(d[1], -2 * l[4] * (q[k][7] - 1), 1e-15, 1e-15);
    }
    free(vals);
    pipeline_free(mech);
}

static void test_no_masses_refused(void **state)
{
    (void)state;
    const char *dir = getenv("MECHC_EXAMPLES");
    char path[600];
    snprintf(path, sizeof path, "%s/slider_crank.mech", dir ? dir : "examples");
    Mech *mech = load_file(path);
    Engine e;
    Diag diag;
    assert_true(engine_open(&e, ENGINE_JIT, mech, &diag));
    RunOptions o = run_default_options();
    RunResult res;
    Kept k = {.nq = mech->model->nq, .nr = mech->model->nr};
    assert_int_equal(run_analysis_forces(mech->model, &e.k, NULL, &o, keep, &k, &res), ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(res.message, "needs masses"));
    assert_int_equal(k.n, 0);
    engine_close(&e);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crank_torque_table),
        cmocka_unit_test(test_crank_torque_formula),
        cmocka_unit_test(test_slider_crank_balance),
        cmocka_unit_test(test_driven_pendulum),
        cmocka_unit_test(test_same_as_runtime),
        cmocka_unit_test(test_through_singular),
        cmocka_unit_test(test_reaction_forces),
        cmocka_unit_test(test_no_masses_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
