/* test_run.c - kinematic analysis over time (generator/kin/, runtime/host/).
 *
 * Drives run_analysis on the examples and checks the states it delivers
 * against closed forms: the slider-crank's slider position, velocity and
 * acceleration over a full turn, the four-bar's Freudenstein equation, the
 * knife-edge cart's circle and the rolling wheel's line; then the ways a
 * run must fail (toggle, out of reach, undriven, overdriven) with the time
 * in the message, the warnings of nearly singular stretches, the host's
 * minimum-norm projection and output formats, and finally the firmware
 * path: `gen --real float` kernels built by the system compiler, run by the
 * runtime compiled as float, against the double run.
 * Runs from the repository root (examples/ relative), like `make check`.
 */
#include "testutil.h"
#include "testload.h"

#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../generator/kin/outputs.h"
#include "../generator/kin/run.h"
#include "../generator/base/arena.h"
#include "../generator/pipeline/pipeline.h"
#include "../runtime/host/mechrt_host.h"

/* ---- helpers ----------------------------------------------------------- */

/* Every state of a run, and how it ended. */
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

static int coord_index(const Model *m, const char *name)
{
    for (int i = 0; i < m->nq; i++)
        if (strcmp(m->coord_names[i], name) == 0)
            return i;
    fail_msg("no coordinate %s", name);
    return -1;
}

/* Runs mech with engine kind and options o (notes captured); c must be freed
   with collected_free. Returns false (and leaves c empty) when the engine is
   not available in this build. */
static bool run_with(Mech *mech, EngineKind kind, RunOptions o, Collected *c)
{
    Engine e;
    Diag diag;
    memset(c, 0, sizeof *c);
    mechrt_trace_init(&c->trace, mech->model->nq);
    if (!engine_open(&e, kind, mech, &diag)) {
        if (kind == ENGINE_JIT)
            fail_msg("jit engine: %s", diag.message);
        return false;
    }
    MechrtKernels k = e.k;
    FILE *notes = fmemopen(c->notes, sizeof c->notes - 1, "w");
    assert_non_null(notes);
    o.notes = notes;
    c->status = run_analysis(mech->model, &k, NULL, &o, collect, c, &c->res);
    fclose(notes);
    engine_close(&e);
    assert_int_equal(c->status, c->res.status);
    return true;
}

static void collected_free(Collected *c)
{
    mechrt_trace_free(&c->trace);
}

static void expect_ok(const Collected *c, int steps)
{
    if (c->status != ANALYSIS_OK)
        fail_msg("run failed: %s", c->res.message);
    assert_int_equal((int)c->trace.rows, steps + 1);
    assert_int_equal(c->res.states, steps + 1);
}

/* ---- closed forms ------------------------------------------------------ */

/* slider_crank.mech: r = 0.1, l = 0.3, theta = omega t, omega = 2 pi.
 *   x    = r c + D,                 D = sqrt(l^2 - r^2 s^2)
 *   xd   = -r w s - r^2 w s c / D
 *   xdd  = -r w^2 c - r^2 w^2 (c^2 - s^2) / D - r^4 w^2 s^2 c^2 / D^3
 *   rod.phi = -asin(r s / l)
 */
static void test_slider_crank_closed_form(void **state)
{
    (void)state;
    const double r = 0.1, l = 0.3, w = 2 * M_PI;
    const int steps = 720;
    Mech *mech = load_file("examples/slider_crank.mech");
    RunOptions o = run_default_options();
    o.steps = steps;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, steps);
    const Model *m = mech->model;
    int ix = coord_index(m, "slider.x"), iphi = coord_index(m, "rod.phi");
    int iy = coord_index(m, "slider.y"), nq = m->nq;
    for (int i = 0; i <= steps; i++) {
        const double *st = state_at(&c, (size_t)i);
        double t = st[0], th = w * t, s = sin(th), co = cos(th);
        double D = sqrt(l * l - r * r * s * s);
        double x = r * co + D;
        double xd = -r * w * s - r * r * w * s * co / D;
        double xdd = -r * w * w * co - r * r * w * w * (co * co - s * s) / D
                     - r * r * r * r * w * w * s * s * co * co / (D * D * D);
        assert_near(t, (double)i / steps, 0, 1e-15);
        assert_near(st[1 + ix], x, 1e-9, 1e-9);
        assert_near(st[1 + nq + ix], xd, 1e-9, 1e-9);
        assert_near(st[1 + 2 * nq + ix], xdd, 1e-9, 1e-9);
        assert_near(st[1 + iphi], -asin(r * s / l), 1e-9, 1e-9);
        assert_near(st[1 + iy], 0, 0, 1e-12);
    }
    assert_near(state_at(&c, (size_t)steps)[0], 1.0, 0, 0);   /* t1 exactly */
    /* the predictor keeps Newton to about one iteration per step, and no
       step needs the branch check's substeps */
    assert_true(c.res.newton_iterations <= 2 * steps);
    assert_int_equal(c.res.subdivided, 0);
    assert_int_equal(c.res.substeps, 0);
    assert_int_equal(c.res.warnings, 0);
    collected_free(&c);
    pipeline_free(mech);
}

/* four_bar.mech: Freudenstein's equation between the crank angle theta2
 * and the rocker angle theta4, a = 1, b = 3, c = 2.5, d = 3:
 *   K1 cos(theta4) - K2 cos(theta2) + K3 = cos(theta2 - theta4)
 *   K1 = d/a, K2 = d/c, K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c)
 * and its time derivative for the rocker's angular velocity:
 *   (K1 sin th4 + sin(th2 - th4)) th4' = (K2 sin th2 + sin(th2 - th4)) th2'
 */
static void test_four_bar_freudenstein(void **state)
{
    (void)state;
    const double a = 1, b = 3, cc = 2.5, d = 3, w = 2 * M_PI;
    const double K1 = d / a, K2 = d / cc, K3 = (a * a - b * b + cc * cc + d * d) / (2 * a * cc);
    const int steps = 400;
    Mech *mech = load_file("examples/four_bar.mech");
    RunOptions o = run_default_options();
    o.steps = steps;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, steps);
    const Model *m = mech->model;
    int i2 = coord_index(m, "crank.phi"), i4 = coord_index(m, "rocker.phi"), nq = m->nq;
    double lo = 10, hi = -10;
    for (int i = 0; i <= steps; i++) {
        const double *st = state_at(&c, (size_t)i);
        double th2 = st[1 + i2], th4 = st[1 + i4];
        double w2 = st[1 + nq + i2], w4 = st[1 + nq + i4];
        assert_near(th2, w * st[0], 1e-12, 1e-12);
        assert_near(K1 * cos(th4) - K2 * cos(th2) + K3, cos(th2 - th4), 0, 1e-9);
        assert_near((K1 * sin(th4) + sin(th2 - th4)) * w4, (K2 * sin(th2) + sin(th2 - th4)) * w2,
                    0, 1e-8);
        lo = fmin(lo, th4);
        hi = fmax(hi, th4);
        if (i == steps / 4)
            assert_near(th4, 1.725386, 0, 1e-6);   /* the file's header */
    }
    assert_near(lo, 1.5208, 0, 2e-4);   /* the rocker's swing, from the header */
    assert_near(hi, 2.4189, 0, 2e-4);
    collected_free(&c);
    pipeline_free(mech);
}

/* knife_cart.mech: v = w = pi from (1, 0, pi/2): the circle of radius v/w = 1
   about the origin, cart.x = cos(w t), cart.y = sin(w t), phi = pi/2 + w t,
   centripetal acceleration v w = pi^2. */
static void test_knife_cart_circle(void **state)
{
    (void)state;
    const double v = M_PI, w = M_PI, x0 = 1, y0 = 0, phi0 = M_PI / 2;
    const double R = v / w, cx = x0 - R * sin(phi0), cy = y0 + R * cos(phi0);
    const int steps = 50;
    Mech *mech = load_file("examples/knife_cart.mech");
    RunOptions o = run_default_options();
    o.steps = steps;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, steps);
    assert_true(c.res.integrated);
    for (int i = 0; i <= steps; i++) {
        const double *st = state_at(&c, (size_t)i);
        double t = st[0], x = st[1], y = st[2], phi = st[3];
        assert_near(hypot(x - cx, y - cy), R, 0, 1e-8);
        assert_near(x, cx + R * sin(phi0 + w * t), 0, 1e-8);
        assert_near(y, cy - R * cos(phi0 + w * t), 0, 1e-8);
        assert_near(phi, phi0 + w * t, 0, 1e-8);
        assert_near(hypot(st[4], st[5]), v, 1e-12, 0);
        assert_near(st[6], w, 1e-12, 0);
        assert_near(hypot(st[7], st[8]), v * w, 1e-9, 0);
    }
    /* the same cart written by hand (skate_velocity.mech) runs the same */
    Mech *skate = load_file("examples/skate_velocity.mech");
    Collected c2;
    run_with(skate, ENGINE_JIT, o, &c2);
    expect_ok(&c2, steps);
    for (size_t i = 0; i < c.trace.rows * (1 + 9); i++)
        assert_near(c2.trace.data[i], c.trace.data[i], 1e-8, 1e-8);
    collected_free(&c2);
    pipeline_free(skate);
    /* rkf45 and a looser tolerance: still on the circle, to that tolerance */
    o.ode.method = MECHRT_ODE_RKF45;
    o.ode.tol = 1e-8;
    Collected c3;
    run_with(mech, ENGINE_JIT, o, &c3);
    expect_ok(&c3, steps);
    for (int i = 0; i <= steps; i++) {
        const double *st = state_at(&c3, (size_t)i);
        assert_near(hypot(st[1] - cx, st[2] - cy), R, 0, 1e-6);
    }
    collected_free(&c3);
    collected_free(&c);
    pipeline_free(mech);
}

/* rolling_wheel.mech: x = 1 + pi t, y = 0.5, phi = -2 pi t; the holonomic
   rows (height, spin) are kept by projection while x is integrated. The
   hand-written rolling_disk_velocity.mech gives the same motion. */
static void test_rolling_wheel(void **state)
{
    (void)state;
    const char *files[2] = {"examples/rolling_wheel.mech", "examples/rolling_disk_velocity.mech"};
    for (int f = 0; f < 2; f++) {
        Mech *mech = load_file(files[f]);
        RunOptions o = run_default_options();
        o.steps = 20;
        Collected c;
        run_with(mech, ENGINE_JIT, o, &c);
        expect_ok(&c, 20);
        for (int i = 0; i <= 20; i++) {
            const double *st = state_at(&c, (size_t)i);
            double t = st[0];
            assert_near(st[1], 1 + M_PI * t, 0, 1e-9);
            assert_near(st[2], 0.5, 0, 1e-12);
            assert_near(st[3], -2 * M_PI * t, 0, 1e-9);
            assert_near(st[4], M_PI, 1e-12, 1e-12);
            assert_near(st[6], -2 * M_PI, 1e-12, 1e-12);
            for (int j = 7; j < 10; j++)
                assert_near(st[j], 0, 0, 1e-9);
        }
        collected_free(&c);
        pipeline_free(mech);
    }
}

/* Every other runnable example runs to the end. */
static void test_examples_run(void **state)
{
    (void)state;
    const char *files[] = {"examples/five_bar.mech", "examples/elliptical_trammel.mech",
                           "examples/pendulum_driven.mech", "examples/point_on_line.mech",
                           "examples/all_statements.mech"};
    for (size_t f = 0; f < sizeof files / sizeof *files; f++) {
        Mech *mech = load_file(files[f]);
        Collected c;
        run_with(mech, ENGINE_JIT, run_default_options(), &c);
        if (c.status != ANALYSIS_OK)
            fail_msg("%s: %s", files[f], c.res.message);
        expect_ok(&c, 100);
        collected_free(&c);
        pipeline_free(mech);
    }
    /* pendulum_driven.mech's closed form at t = 1: m = (2, 0), m.yd = pi,
       m.xdd = -L omega^2 = -pi^2/2 */
    Mech *mech = load_file("examples/pendulum_driven.mech");
    Collected c;
    run_with(mech, ENGINE_JIT, run_default_options(), &c);
    const double *st = state_at(&c, 100);
    int ix = coord_index(mech->model, "m.x"), iy = coord_index(mech->model, "m.y");
    int nq = mech->model->nq;
    assert_near(st[1 + ix], 2, 0, 1e-12);
    assert_near(st[1 + iy], 0, 0, 1e-12);
    assert_near(st[1 + nq + iy], M_PI, 1e-12, 1e-12);
    assert_near(st[1 + 2 * nq + ix], -M_PI * M_PI / 2, 1e-12, 1e-12);
    collected_free(&c);
    pipeline_free(mech);
}

/* ---- coarse steps -------------------------------------------------------- */

/* Every state of c equals the state of ref at the same time (ref's grid
   must contain c's), positions, velocities and accelerations to 1e-8. */
static void expect_same_states(const Collected *c, const Collected *ref, const char *what)
{
    size_t w = 1 + 3 * (size_t)c->trace.nq, j = 0;
    for (size_t i = 0; i < c->trace.rows; i++) {
        const double *st = state_at(c, i);
        while (j < ref->trace.rows && state_at(ref, j)[0] != st[0])
            j++;
        if (j == ref->trace.rows)
            fail_msg("%s: t = %.17g is not on the reference grid", what, st[0]);
        const double *rs = state_at(ref, j);
        for (size_t k = 1; k < w; k++)
            if (!(fabs(st[k] - rs[k]) <= 1e-8 * (1 + fabs(rs[k]))))
                fail_msg("%s: t = %g: value %zu is %.17g, the reference %.17g", what, st[0], k,
                         st[k], rs[k]);
    }
}

/* With one, two or three steps per crank turn the predictor lands nearer
   the crossed assembly (or another turn of the coupler's angle) than the
   right one, and Newton would converge there: the four-bar at t = 0.5 came
   out with coupler.y = -0.936 instead of +0.936. The branch check redoes
   such steps in substeps, and the grid states equal those of a fine run
   (1200 steps: every point of the 1-, 2- and 3-step grids is on it). */
static void test_coarse_steps_keep_branch(void **state)
{
    (void)state;
    const char *files[] = {"examples/four_bar.mech", "examples/five_bar.mech",
                           "examples/slider_crank.mech"};
    for (size_t f = 0; f < sizeof files / sizeof *files; f++) {
        Mech *mech = load_file(files[f]);
        RunOptions o = run_default_options();
        o.steps = 1200;
        Collected ref;
        run_with(mech, ENGINE_JIT, o, &ref);
        expect_ok(&ref, 1200);
        for (int steps = 1; steps <= 3; steps++) {
            char what[96];
            snprintf(what, sizeof what, "%s, %d %s", files[f], steps, steps == 1 ? "step" : "steps");
            Collected c;
            o.steps = steps;
            run_with(mech, ENGINE_JIT, o, &c);
            if (c.status != ANALYSIS_OK)
                fail_msg("%s: %s", what, c.res.message);
            expect_ok(&c, steps);
            expect_same_states(&c, &ref, what);
            /* only the grid's states are delivered; the substeps are counted */
            assert_true(c.res.subdivided >= 1);
            assert_true(c.res.substeps >= 2 * c.res.subdivided);
            assert_int_equal(c.res.steps_done, steps);
            collected_free(&c);
        }
        collected_free(&ref);
        pipeline_free(mech);
    }
}

/* A crank started from rest (crank.phi = omega t^3): the first step's
   predicted motion is nil at any step size, so only the agreement of two
   subdivision levels can accept it; coarse runs still match the fine one. */
static void test_coarse_steps_from_rest(void **state)
{
    (void)state;
    FILE *f = fopen("examples/four_bar.mech", "r");
    assert_non_null(f);
    static char text[8192];
    size_t n = fread(text, 1, sizeof text - 16, f);
    fclose(f);
    text[n] = '\0';
    char *drive = strstr(text, "omega*t\n");
    assert_non_null(drive);
    memmove(drive + 9, drive + 7, strlen(drive + 7) + 1);
    memcpy(drive + 7, "^3", 2);
    assert_non_null(strstr(text, "crank.phi = omega*t^3\n"));
    Mech *mech = load_text(text, "four_bar_from_rest.mech");
    RunOptions o = run_default_options();
    o.steps = 1200;
    Collected ref;
    run_with(mech, ENGINE_JIT, o, &ref);
    expect_ok(&ref, 1200);
    for (int steps = 1; steps <= 4; steps++) {
        Collected c;
        o.steps = steps;
        run_with(mech, ENGINE_JIT, o, &c);
        if (c.status != ANALYSIS_OK)
            fail_msg("%d steps: %s", steps, c.res.message);
        expect_ok(&c, steps);
        expect_same_states(&c, &ref, "four-bar from rest");
        collected_free(&c);
    }
    collected_free(&ref);
    pipeline_free(mech);
}

/* Past max_substeps the run fails, exit status 1, naming the time and the
   cause; it never goes on with a state it could not check. */
static void test_substep_limit(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/four_bar.mech");
    RunOptions o = run_default_options();
    o.steps = 2;
    o.max_substeps = 2;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.cause, MECHRT_ESTEP);
    assert_int_equal(c.res.states, 1);   /* t = 0 only */
    assert_int_equal((int)c.trace.rows, 1);
    /* the first substep of the finest level (2 of 0 .. 0.5) still jumped */
    assert_near(c.res.t_fail, 0.25, 0, 1e-15);
    assert_non_null(strstr(c.res.message, "t = 0.25: position analysis failed: the motion is "
                                          "too fast for the step: in 2 substeps of the step "
                                          "from t = 0 to 0.5 "));
    assert_non_null(strstr(c.res.message, "--max-substeps"));
    collected_free(&c);

    /* no subdivision at all: the unchecked step itself fails */
    o.max_substeps = 1;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.cause, MECHRT_ESTEP);
    assert_near(c.res.t_fail, 0.5, 0, 0);
    assert_int_equal(c.res.states, 1);
    assert_non_null(strstr(c.res.message, "t = 0.5: position analysis failed: the motion is too "
                                          "fast for the step: in the step from t = 0 to 0.5 "
                                          "(no substeps allowed)"));
    assert_int_equal(c.res.substeps, 0);
    collected_free(&c);

    /* ten crank turns in one step are too many for the default 64 substeps */
    o = run_default_options();
    o.t1 = 10;
    o.steps = 1;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.states, 1);
    assert_true(c.res.t_fail > 0 && c.res.t_fail <= 10);
    assert_non_null(strstr(c.res.message, "the motion is too fast for the step"));
    assert_non_null(strstr(c.res.message, "in 64 substeps"));
    collected_free(&c);
    /* ... and enough with a higher limit, where the grid point matches a
       fine run */
    o.max_substeps = 1024;
    run_with(mech, ENGINE_JIT, o, &c);
    if (c.status != ANALYSIS_OK)
        fail_msg("10 turns, 1 step, 1024 substeps: %s", c.res.message);
    expect_ok(&c, 1);
    Collected ref;
    o.steps = 1000;
    run_with(mech, ENGINE_JIT, o, &ref);
    expect_ok(&ref, 1000);
    expect_same_states(&c, &ref, "10 turns in 1 step");
    collected_free(&ref);
    collected_free(&c);

    /* (a step that fails outright and that substeps cannot rescue keeps its
       own message and time: test_toggle, test_out_of_reach) */

    /* no substeps at all is bad input */
    o = run_default_options();
    o.max_substeps = 0;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    collected_free(&c);
    pipeline_free(mech);
}

/* ---- failures ---------------------------------------------------------- */

/* slider_crank_toggle.mech (r = l) reaches its toggle at t = 0.25, where
   two branches cross: the run goes on along the smooth one it came on
   (tests/test_qr_rank.c checks it against the closed form). */
static void test_toggle(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/slider_crank_toggle.mech");
    Collected c;
    run_with(mech, ENGINE_JIT, run_default_options(), &c);
    expect_ok(&c, 100);
    assert_int_equal(c.res.rank_deficient_steps, 2);
    collected_free(&c);

    /* clear of the toggle, it runs */
    RunOptions o = run_default_options();
    o.t1 = 0.2;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, 100);
    collected_free(&c);
    pipeline_free(mech);
}

/* A point on the unit circle pulled along x past the circle: from t = 0.45
   there is no solution; the step to the first sample beyond, t = 0.5,
   fails, and its 64 substeps stop at t = 0.45 + 0.1/64, where the failure
   is dated and put down to the driver (the Jacobian loses rank). */
static const char reach_text[] =
    "point p x = 0.55 y = 0.8\n"
    "constraint circle: p.x^2 + p.y^2 = 1\n"
    "driver pull: p.x = 0.55 + t\n";

static void test_out_of_reach(void **state)
{
    (void)state;
    Mech *mech = load_text(reach_text, "reach.mech");
    RunOptions o = run_default_options();
    o.steps = 10;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_near(c.res.t_fail, 0.45 + 0.1 / 64, 0, 1e-12);
    assert_int_equal(c.res.states, 5);
    assert_non_null(strstr(c.res.message, "t = 0.4515625: the mechanism cannot reach the driven "
                                          "position: driver 'pull' pushes it past a limit "
                                          "position"));
    assert_non_null(strstr(c.res.message, "along rows pull and circle"));
    assert_int_equal(c.res.cause, MECHRT_EMAXITER);
    assert_non_null(strstr(c.res.message, "no convergence"));
    assert_non_null(strstr(c.res.message, "row circle"));
    /* the initial y was rough: assembly moved it and said so */
    assert_non_null(strstr(c.notes, "note: assembly at t = 0 moved"));
    assert_non_null(strstr(c.notes, "p.y"));
    assert_near(c.res.assembly_move, sqrt(1 - 0.55 * 0.55) - 0.8, 1e-9, 0);
    collected_free(&c);
    pipeline_free(mech);
}

/* Assembly that cannot succeed names t0; a NaN names its row. */
static void test_assembly_and_nan(void **state)
{
    (void)state;
    Mech *mech = load_text("point p x = 3 y = 0\n"
                           "constraint circle: p.x^2 + p.y^2 = 1\n"
                           "driver pull: p.x = 2 + t\n", "far.mech");
    RunOptions o = run_default_options();
    o.t0 = 0.125;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.states, 0);
    assert_non_null(strstr(c.res.message, "t = 0.125: could not assemble"));
    collected_free(&c);
    pipeline_free(mech);

    /* sqrt of a negative number after t = 0.5 */
    mech = load_text("point p x = 1 y = 0\n"
                     "constraint c: p.y = 0\n"
                     "driver d: p.x = sqrt(0.5 - t)\n", "nan.mech");
    o = run_default_options();
    o.steps = 4;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    /* at t = 0.5 the position is still defined, its time derivative not */
    assert_near(c.res.t_fail, 0.5, 0, 0);
    assert_int_equal(c.res.cause, MECHRT_ENOTFINITE);
    assert_non_null(strstr(c.res.message, "t = 0.5:"));
    assert_non_null(strstr(c.res.message, "nu of row d"));
    collected_free(&c);
    pipeline_free(mech);
}

/* ---- assembly from rough guesses, one instant, outputs, units ---------- */

/* A four-bar a, b, c, d (crank, coupler, rocker, ground) with the crank
   held at th2, every initial value left at its default 0 unless
   positions_given (then the link centres are given, every angle 0). */
static Mech *four_bar_text(double a, double b, double c, double d, double th2,
                           bool positions_given)
{
    char text[1024];
    snprintf(text, sizeof text,
             "param a = %.17g\nparam b = %.17g\nparam c = %.17g\nparam d = %.17g\n"
             "body crank %s\nbody coupler %s\nbody rocker %s\n"
             "revolute O2: ground(0, 0) crank(-a/2, 0)\n"
             "revolute A: crank(a/2, 0) coupler(-b/2, 0)\n"
             "revolute B: coupler(b/2, 0) rocker(c/2, 0)\n"
             "revolute O4: ground(d, 0) rocker(-c/2, 0)\n"
             "driver drive: crank.phi = %.17g\n", a, b, c, d,
             positions_given ? "x = 0.5 y = 0" : "", positions_given ? "x = 1.5 y = 1" : "",
             positions_given ? "x = 3 y = 1" : "", th2);
    return load_text(text, "four_bar_guess.mech");
}

/* Every four-bar configuration that exists assembles from all-zero guesses
   (angles only, or everything), on a sweep of geometries and crank
   angles, and satisfies Freudenstein's equation; one that does not exist
   fails with "could not assemble", never "toggle". */
static void test_assembly_from_zero_guesses(void **state)
{
    (void)state;
    static const double shapes[][4] = {
        {1, 3, 2.5, 3},     /* the example's crank-rocker */
        {1, 2, 2, 2},       /* a parallelogram-like Grashof linkage */
        {2, 3, 3.5, 4},     /* non-Grashof triple rocker */
        {1.5, 1, 2, 2.5},   /* coupler shortest */
    };
    RunOptions o = run_default_options();
    o.steps = 0;
    int assembled = 0, refused = 0, worst_iterations = 0;
    for (size_t g = 0; g < sizeof shapes / sizeof *shapes; g++) {
        double a = shapes[g][0], b = shapes[g][1], c = shapes[g][2], d = shapes[g][3];
        for (int k = 0; k < 12; k++) {
            double th2 = 2 * M_PI * k / 12 + 0.1;
            double e = hypot(d - a * cos(th2), a * sin(th2));   /* A to O4 */
            bool exists = fabs(b - c) < e - 1e-3 && e < b + c - 1e-3;
            bool near_limit = fabs(e - fabs(b - c)) < 1e-3 || fabs(e - (b + c)) < 1e-3;
            if (near_limit)
                continue;
            for (int given = 0; given < 2; given++) {
                Mech *mech = four_bar_text(a, b, c, d, th2, given);
                Collected col;
                run_with(mech, ENGINE_JIT, o, &col);
                if (!exists) {
                    assert_int_equal(col.status, ANALYSIS_FAILED);
                    assert_non_null(strstr(col.res.message, "could not assemble"));
                    assert_null(strstr(col.res.message, "toggle"));
                    refused++;
                } else {
                    if (col.status != ANALYSIS_OK)
                        fail_msg("shape %zu, th2 = %g, positions %d: %s", g, th2, given,
                                 col.res.message);
                    assert_int_equal(col.res.states, 1);
                    const Model *m = mech->model;
                    const double *st = state_at(&col, 0);
                    double t2 = st[1 + coord_index(m, "crank.phi")];
                    double t4 = st[1 + coord_index(m, "rocker.phi")];
                    double K1 = d / a, K2 = d / c, K3 = (a * a - b * b + c * c + d * d) / (2 * a * c);
                    assert_near(K1 * cos(t4) - K2 * cos(t2) + K3, cos(t2 - t4), 0, 1e-9);
                    if (col.res.assembly_iterations > worst_iterations)
                        worst_iterations = col.res.assembly_iterations;
                    assembled++;
                }
                collected_free(&col);
                pipeline_free(mech);
            }
        }
    }
    assert_true(assembled >= 60);
    assert_true(refused >= 4);
    /* the target: at most twice the 2 iterations of the example's
       own guesses (the answer to four decimals) */
    print_message("worst assembly: %d Newton iterations\n", worst_iterations);
    assert_true(worst_iterations <= 4);
}

/* The slider-crank and every example that runs assemble with every angle
   guess 0, to the same configuration family (slider-crank: the closed form). */
static void test_assembly_examples_zero_angles(void **state)
{
    (void)state;
    Mech *mech = load_text("param r = 0.1\nparam l = 0.3\n"
                           "body crank\nbody rod\nbody slider\n"
                           "revolute O: ground(0, 0) crank(-r/2, 0)\n"
                           "revolute A: crank(r/2, 0) rod(-l/2, 0)\n"
                           "revolute B: rod(l/2, 0) slider(0, 0)\n"
                           "prismatic P: ground(0, 0) slider(0, 0) axis(1, 0)\n"
                           "driver D: crank.phi = 30*deg + 1500*rpm*t\n", "sc0.mech");
    RunOptions o = run_default_options();
    o.steps = 0;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, 0);
    const Model *m = mech->model;
    const double *st = state_at(&c, 0);
    int nq = m->nq, ix = coord_index(m, "slider.x");
    double r = 0.1, l = 0.3, th = M_PI / 6, w = 1500 * 2 * M_PI / 60;
    double sn = sin(th), cs = cos(th), D = sqrt(l * l - r * r * sn * sn);
    /* the closure nearer the guesses: the rod's angle 0 puts the slider
       beyond the crank pin (x = r c + D, not r c - D) */
    double x = st[1 + ix];
    double sign = 1;
    assert_near(x, r * cs + sign * D, 1e-12, 1e-12);
    assert_near(st[1 + nq + ix], -r * w * sn - sign * r * r * w * sn * cs / D, 1e-9, 1e-9);
    assert_true(c.res.assembly_iterations <= 2);     /* twice the file's 1 */
    assert_int_equal(c.res.constructed, 9);
    collected_free(&c);
    pipeline_free(mech);
}

/* Offset slider-cranks of several proportions at 12 crank angles, every
   guess 0: the slider where the closed form puts it (ahead of the crank
   pin: the closure nearer the rod's guessed angle 0), in at most twice the
   1 iteration of exact guesses. */
static void test_slider_crank_sweep_zero_guesses(void **state)
{
    (void)state;
    static const double shapes[][3] = {{0.1, 0.3, 0}, {0.1, 0.3, 0.05}, {0.2, 0.5, -0.1}, {1, 4, 0.5}};
    RunOptions o = run_default_options();
    o.steps = 0;
    for (size_t g = 0; g < sizeof shapes / sizeof *shapes; g++) {
        double r = shapes[g][0], l = shapes[g][1], e = shapes[g][2];
        for (int k = 0; k < 12; k++) {
            double th = 2 * M_PI * k / 12 + 0.05;
            char text[512];
            snprintf(text, sizeof text, "body crank\nbody rod\nbody slider\n"
                     "revolute O: ground(0, 0) crank(-%.17g, 0)\n"
                     "revolute A: crank(%.17g, 0) rod(-%.17g, 0)\n"
                     "revolute B: rod(%.17g, 0) slider(0, 0)\n"
                     "prismatic P: ground(0, %.17g) slider(0, 0) axis(1, 0)\n"
                     "driver D: crank.phi = %.17g\n", r / 2, r / 2, l / 2, l / 2, e, th);
            Mech *mech = load_text(text, "sc_sweep.mech");
            Collected c;
            run_with(mech, ENGINE_JIT, o, &c);
            expect_ok(&c, 0);
            const Model *m = mech->model;
            const double *st = state_at(&c, 0);
            double h = e - r * sin(th);
            assert_near(st[1 + coord_index(m, "slider.x")], r * cos(th) + sqrt(l * l - h * h), 1e-12,
                        1e-12);
            assert_near(st[1 + coord_index(m, "slider.y")], e, 1e-12, 1e-12);
            assert_true(c.res.assembly_iterations <= 2);
            collected_free(&c);
            pipeline_free(mech);
        }
    }
}

/* The four-bar from rough guesses: the construction closes the dyad on the
   side of the guesses (the rocker's angle below the ground line gives the
   crossed branch), and with every guess 0 on the left of the line from the
   crank pin to the rocker pivot (the coupler above the ground). */
static void test_construction_picks_branch(void **state)
{
    (void)state;
    static const struct {
        const char *guesses;
        double sign;        /* of the coupler's y */
    } cases[] = {
        {"body crank\nbody coupler\nbody rocker\n", 1},
        {"body crank\nbody coupler phi = -1\nbody rocker phi = -1.7\n", -1},
        {"body crank\nbody coupler y = -1\nbody rocker\n", -1},
    };
    RunOptions o = run_default_options();
    o.steps = 0;
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char text[512];
        snprintf(text, sizeof text, "%srevolute O2: ground(0, 0) crank(-0.5, 0)\n"
                 "revolute A: crank(0.5, 0) coupler(-1.5, 0)\n"
                 "revolute B: coupler(1.5, 0) rocker(1.25, 0)\n"
                 "revolute O4: ground(3, 0) rocker(-1.25, 0)\n"
                 "driver d: crank.phi = 0\n", cases[i].guesses);
        Mech *mech = load_text(text, "branch.mech");
        Collected c;
        run_with(mech, ENGINE_JIT, o, &c);
        expect_ok(&c, 0);
        const Model *m = mech->model;
        const double *st = state_at(&c, 0);
        /* crank pin (1, 0), rocker pivot (3, 0): the coupler's end B is
           where circles of radius 3 and 2.5 meet, at x = 2.6875 */
        double bx = st[1 + coord_index(m, "coupler.x")] + 1.5 * cos(st[1 + coord_index(m, "coupler.phi")]);
        double by = st[1 + coord_index(m, "coupler.y")] + 1.5 * sin(st[1 + coord_index(m, "coupler.phi")]);
        assert_near(bx, 2.6875, 1e-12, 1e-12);
        assert_near(by, cases[i].sign * sqrt(9 - 1.6875 * 1.6875), 1e-12, 1e-12);
        assert_int_equal(c.res.constructed, 9);
        assert_true(c.res.assembly_iterations <= 2);
        collected_free(&c);
        pipeline_free(mech);
    }
}

/* steps = 0: one state at t0, t1 ignored; a negative count is refused. */
static void test_one_instant(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/four_bar.mech");
    RunOptions o = run_default_options();
    o.steps = 0;
    o.t0 = 0.25;
    o.t1 = 0.25;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, 0);
    assert_near(state_at(&c, 0)[0], 0.25, 0, 0);
    assert_near(state_at(&c, 0)[1 + coord_index(mech->model, "rocker.phi")], 1.725386, 0, 1e-6);
    assert_int_equal(c.res.steps_done, 0);
    collected_free(&c);
    o.steps = -1;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "at least 0"));
    collected_free(&c);
    pipeline_free(mech);
}

/* Output statements: a body point, a slide() and a plain value, with their
   velocities and accelerations, against the slider-crank's closed form. */
static void test_outputs_slider_crank(void **state)
{
    (void)state;
    Mech *mech = load_text("param r = 0.1\nparam l = 0.3\nparam omega = 2*pi\n"
                           "body crank x = r/2\nbody rod x = r + l/2\nbody slider x = r + l\n"
                           "revolute O: ground(0, 0) crank(-r/2, 0)\n"
                           "revolute A: crank(r/2, 0) rod(-l/2, 0)\n"
                           "revolute B: rod(l/2, 0) slider(0, 0)\n"
                           "prismatic P: ground(0.05, 0) slider(0, 0) axis(2, 0)\n"
                           "driver D: crank.phi = omega*t\n"
                           "output pin: rod(l/2, 0)\n"
                           "output s = slide(P)\n"
                           "output rod_deg = rod.phi/deg\n", "outputs.mech");
    const Model *m = mech->model;
    assert_int_equal(m->nout, 4);
    assert_string_equal(m->outputs[0].name, "pin.x");
    assert_string_equal(m->outputs[1].name, "pin.y");
    assert_string_equal(m->outputs[2].name, "s");
    assert_string_equal(m->outputs[3].name, "rod_deg");
    RunOptions o = run_default_options();
    o.steps = 16;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, 16);
    OutputEval oe;
    outputs_init(&oe, m);
    const double r = 0.1, l = 0.3, w = 2 * M_PI;
    int nq = m->nq;
    for (int i = 0; i <= 16; i++) {
        const double *st = state_at(&c, (size_t)i);
        double y[4], yd[4], ydd[4];
        outputs_eval(&oe, st + 1, st + 1 + nq, st + 1 + 2 * nq, st[0], y, yd, ydd);
        double th = w * st[0], sn = sin(th), cs = cos(th), D = sqrt(l * l - r * r * sn * sn);
        double x = r * cs + D, xd = -r * w * sn - r * r * w * sn * cs / D;
        double xdd = -r * w * w * cs - r * r * w * w * (cs * cs - sn * sn) / D
                     - r * r * r * r * w * w * sn * sn * cs * cs / (D * D * D);
        assert_near(y[0], x, 1e-9, 1e-9);
        assert_near(yd[0], xd, 1e-8, 1e-8);
        assert_near(ydd[0], xdd, 1e-7, 1e-7);
        assert_near(y[1], 0, 0, 1e-12);
        assert_near(y[2], x - 0.05, 1e-9, 1e-9);   /* along the axis, from (0.05, 0) */
        assert_near(yd[2], xd, 1e-8, 1e-8);
        assert_near(ydd[2], xdd, 1e-7, 1e-7);
        assert_near(y[3], -asin(r * sn / l) * 180 / M_PI, 1e-9, 1e-9);
    }
    outputs_free(&oe);
    collected_free(&c);
    pipeline_free(mech);
}

/* Restarts from jittered guesses leave alone the coordinates no holonomic
   row depends on: under velocity-level rows they are the integrator's
   initial values, not guesses. (The loop is closed by constraint rows,
   which the construction leaves to Newton, so the restarts run.) */
static void test_rough_assembly_keeps_free_coordinates(void **state)
{
    (void)state;
    Mech *mech = load_text("param a = 1\nbody crank\nbody coupler\nbody rocker\n"
                           "body cart x = 5 y = 0 phi = 0\n"
                           "revolute O2: ground(0, 0) crank(-0.5, 0)\n"
                           "revolute A: crank(0.5, 0) coupler(-1.5, 0)\n"
                           "constraint Bx: coupler.x + 1.5*cos(coupler.phi) = "
                           "rocker.x + 1.25*cos(rocker.phi)\n"
                           "constraint By: coupler.y + 1.5*sin(coupler.phi) = "
                           "rocker.y + 1.25*sin(rocker.phi)\n"
                           "revolute O4: ground(3, 0) rocker(-1.25, 0)\n"
                           "driver d: crank.phi = 0\n"
                           "knife blade: cart axis(1, 0)\n"
                           "driver fwd: der(cart.x)*cos(cart.phi) + der(cart.y)*sin(cart.phi) = 1\n"
                           "driver turn: der(cart.phi) = 0\n", "mix.mech");
    RunOptions o = run_default_options();
    o.steps = 0;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, 0);
    const Model *m = mech->model;
    const double *st = state_at(&c, 0);
    assert_near(st[1 + coord_index(m, "cart.x")], 5, 0, 0);
    assert_near(st[1 + coord_index(m, "cart.y")], 0, 0, 0);
    assert_near(st[1 + coord_index(m, "cart.phi")], 0, 0, 0);
    assert_true(c.res.assembled_robustly);
    collected_free(&c);
    pipeline_free(mech);
}

/* A mechanism that cannot close: the message says so and names rows. */
static void test_cannot_assemble(void **state)
{
    (void)state;
    Mech *mech = four_bar_text(1, 1, 1, 5, 0.3, true);   /* b + c < the gap */
    RunOptions o = run_default_options();
    o.steps = 4;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.states, 0);
    assert_non_null(strstr(c.res.message, "t = 0: could not assemble from these initial values"));
    assert_non_null(strstr(c.res.message, "largest residual"));
    assert_null(strstr(c.res.message, "toggle"));
    collected_free(&c);
    pipeline_free(mech);
}

/* Not as many rows as coordinates: ANALYSIS_BAD_INPUT, nothing run, the count
   in plain words. */
static void test_row_count(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/pendulum_distance.mech");
    Collected c;
    run_with(mech, ENGINE_JIT, run_default_options(), &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    assert_int_equal(c.res.states, 0);
    assert_string_equal(c.res.message, "1 degree of freedom is not driven (2 coordinates, 1 row): "
                                       "add a driver");
    collected_free(&c);
    pipeline_free(mech);

    mech = load_text("body b x = 0 y = 0 phi = 0\nconstraint c: b.x = 0\n", "free.mech");
    run_with(mech, ENGINE_JIT, run_default_options(), &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    assert_non_null(strstr(c.res.message, "2 degrees of freedom are not driven"));
    collected_free(&c);
    pipeline_free(mech);

    mech = load_text("point p x = 0 y = 0\nconstraint a: p.x = 0\nconstraint b: p.y = 0\n"
                     "driver c: p.x = t\ndriver d: p.y = t\n", "over.mech");
    run_with(mech, ENGINE_JIT, run_default_options(), &c);
    /* rows c and d repeat a and b (redundant, test_redundant.c) but
       contradict them: a failure at t0, at the velocity level */
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.states, 0);
    assert_non_null(strstr(c.res.message, "t = 0: the redundant rows contradict the others"));
    collected_free(&c);

    /* bad options are bad input too */
    RunOptions o = run_default_options();
    o.steps = -1;
    run_with(mech, ENGINE_JIT, o, &c);
    assert_int_equal(c.status, ANALYSIS_BAD_INPUT);
    collected_free(&c);
    pipeline_free(mech);
}

/* Near a singular position: one warning per stretch, with its time. The
   toggle mechanism with 50 steps passes t = 0.25 and 0.75 between samples;
   with a low threshold both neighbourhoods warn once each. */
static void test_condition_episodes(void **state)
{
    (void)state;
    Mech *mech = load_file("examples/slider_crank_toggle.mech");
    RunOptions o = run_default_options();
    o.steps = 50;
    o.mechrt.cond_warn = 100;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, 50);
    assert_int_equal(c.res.warnings, 2);
    assert_non_null(strstr(c.notes, "warning: t = 0.2"));
    assert_non_null(strstr(c.notes, "warning: t = 0.7"));
    assert_non_null(strstr(c.notes, "note: nearly singular from t = "));
    /* one warning line per stretch, not one per step */
    int lines = 0;
    for (const char *p = c.notes; (p = strstr(p, ": warning: ")); p++)
        lines++;
    assert_int_equal(lines, 2);
    collected_free(&c);
    pipeline_free(mech);
}

/* The generic engine (when this build has it) runs the same trajectory. */
static void test_engines_agree(void **state)
{
    (void)state;
    const char *files[2] = {"examples/four_bar.mech", "examples/all_statements.mech"};
    for (int f = 0; f < 2; f++) {
        Mech *mech = load_file(files[f]);
        RunOptions o = run_default_options();
        o.steps = 40;
        Collected a, b;
        run_with(mech, ENGINE_JIT, o, &a);
        expect_ok(&a, 40);
        if (!run_with(mech, ENGINE_GENERIC, o, &b)) {
            collected_free(&a);
            collected_free(&b);
            pipeline_free(mech);
            skip();
        }
        expect_ok(&b, 40);
        for (size_t i = 0; i < a.trace.rows * (1 + 3 * (size_t)a.trace.nq); i++)
            assert_near(b.trace.data[i], a.trace.data[i], 1e-9, 1e-9);
        collected_free(&a);
        collected_free(&b);
        pipeline_free(mech);
    }
}

/* ---- host pieces ------------------------------------------------------- */

/* mechrt_host_project with fewer rows than coordinates moves q the least:
   onto x + y = 1 from (1, 1) the minimum-norm move is to (0.5, 0.5). */
static void lin_phi(void *ctx, const double *q, double t, double *phi)
{
    (void)ctx;
    (void)t;
    phi[0] = q[0] + q[1] - 1;
}

static void lin_jac(void *ctx, const double *q, double t, double *jac)
{
    (void)ctx;
    (void)q;
    (void)t;
    jac[0] = 1;   /* Phi = x + y - 1 */
    jac[1] = 1;
    jac[2] = 1;   /* a velocity row: xd - yd = 2 */
    jac[3] = -1;
}

static void lin_nu(void *ctx, const double *q, double t, double *nu)
{
    (void)ctx;
    (void)q;
    (void)t;
    nu[0] = 0;
    nu[1] = 2;
}

static void lin_gamma(void *ctx, const double *q, const double *qd, double t, double *g)
{
    (void)ctx;
    (void)q;
    (void)qd;
    (void)t;
    g[0] = g[1] = 0;
}

static void test_host_projection(void **state)
{
    (void)state;
    MechrtKernels k = {2, 1, 1, NULL, lin_phi, lin_jac, lin_nu, lin_gamma, NULL, NULL, NULL};
    MechrtHost *h = mechrt_host_new(&k);
    assert_non_null(h);
    double q[2] = {1, 1};
    MechrtReport rep;
    assert_int_equal(mechrt_host_project(h, NULL, q, 0, &rep), MECHRT_OK);
    assert_near(q[0], 0.5, 0, 1e-15);
    assert_near(q[1], 0.5, 0, 1e-15);
    assert_int_equal(rep.iterations, 2);   /* the second step confirms: |dq| ~ 0 */
    /* integrate: xd - yd = 2 with xd + yd = 0: (1, -1) per unit time */
    double t = 0, hs = 0.1;
    assert_int_equal(mechrt_host_integrate(h, NULL, NULL, q, &t, 0.5, &hs, &rep), MECHRT_OK);
    assert_near(t, 0.5, 0, 0);
    assert_near(q[0], 1.0, 0, 1e-12);
    assert_near(q[1], 0.0, 0, 1e-12);
    assert_true(mechrt_host_stats(h)->ode_steps >= 1);
    mechrt_host_free(h);

    /* singular directions: rows 0 and 2 of this matrix are equal */
    const double a[9] = {1, 2, 0, 0, 1, 1, 1, 2, 0};
    double rw[3], cw[3];
    double ratio = mechrt_host_singular_direction(3, 3, a, rw, cw);
    assert_true(ratio >= 0 && ratio < 1e-15);
    assert_near(rw[0], sqrt(0.5), 0, 1e-12);
    assert_near(rw[1], 0, 0, 1e-12);
    assert_near(rw[2], sqrt(0.5), 0, 1e-12);
    /* a wide matrix (fewer rows than columns) works through its transpose */
    const double b[6] = {1, 0, 0, 2, 0, 0};
    ratio = mechrt_host_singular_direction(2, 3, b, rw, cw);
    assert_true(ratio >= 0 && ratio < 1e-15);
    assert_near(rw[0] * sqrt(5), 2, 0, 1e-12);
    assert_near(rw[1] * sqrt(5), 1, 0, 1e-12);
}

static void test_output_formats(void **state)
{
    (void)state;
    char buf[64];
    mechrt_format_real(buf, sizeof buf, 0.3, 0, false);
    assert_string_equal(buf, "0.3");
    mechrt_format_real(buf, sizeof buf, 0.1 + 0.2, 0, false);
    assert_string_equal(buf, "0.30000000000000004");
    mechrt_format_real(buf, sizeof buf, M_PI, 6, false);
    assert_string_equal(buf, "3.14159");
    mechrt_format_real(buf, sizeof buf, -0.0, 0, false);
    assert_string_equal(buf, "0");
    mechrt_format_real(buf, sizeof buf, -INFINITY, 0, false);
    assert_string_equal(buf, "-inf");

    char text[1024];
    FILE *f = fmemopen(text, sizeof text, "w");
    const char *names[2] = {"p.x", "theta"};
    double q[2] = {1, 0.5}, qd[2] = {-2, 0}, qdd[2] = {0.25, NAN};
    mechrt_csv_header(f, 2, names);
    mechrt_csv_row(f, 2, 0.1, q, qd, qdd, 0);
    MechrtTrace tr;
    mechrt_trace_init(&tr, 2);
    assert_true(mechrt_trace_push(&tr, 0.1, q, qd, qdd));
    mechrt_json_write(f, &tr, names, 0, "t = 0.2: \"bad\"", 0.2);
    mechrt_trace_free(&tr);
    fclose(f);
    assert_string_equal(text,
        "t,p.x,theta,d(p.x),d(theta),dd(p.x),dd(theta)\n"
        "0.1,1,0.5,-2,0,0.25,nan\n"
        "{\"coords\": [\"p.x\", \"theta\"],\n"
        " \"t\": [0.1],\n"
        " \"q\": [[1, 0.5]],\n"
        " \"qd\": [[-2, 0]],\n"
        " \"qdd\": [[0.25, null]],\n"
        " \"ok\": false,\n"
        " \"error\": {\"t\": 0.2, \"message\": \"t = 0.2: \\\"bad\\\"\"}}\n");
}

/* ---- the firmware path: float kernels and the float runtime ------------ */

/* The runtime compiled again as float (its names become mechrtf_*), as
   firmware built with -DMECHRT_REAL_FLOAT would have it. */
#define MECHRT_REAL_FLOAT
#include "../runtime/lu.c"
#include "../runtime/newton.c"
#include "../runtime/analysis.c"

typedef struct FloatLib {
    void (*phi)(const float *, float, float *);
    void (*jac)(const float *, float, float *);
    void (*nu)(const float *, float, float *);
    void (*gamma)(const float *, const float *, float, float *);
    void (*all)(const float *, const float *, float, float *, float *, float *, float *);
} FloatLib;

static void fl_phi(void *ctx, const float *q, float t, float *o)
{
    ((FloatLib *)ctx)->phi(q, t, o);
}

static void fl_jac(void *ctx, const float *q, float t, float *o)
{
    ((FloatLib *)ctx)->jac(q, t, o);
}

static void fl_nu(void *ctx, const float *q, float t, float *o)
{
    ((FloatLib *)ctx)->nu(q, t, o);
}

static void fl_gamma(void *ctx, const float *q, const float *qd, float t, float *o)
{
    ((FloatLib *)ctx)->gamma(q, qd, t, o);
}

static void fl_all(void *ctx, const float *q, const float *qd, float t, float *phi, float *jac,
                   float *nu, float *gamma)
{
    ((FloatLib *)ctx)->all(q, qd, t, phi, jac, nu, gamma);
}

static void test_float_kernels(void **state)
{
    (void)state;
    if (system("cc --version >/dev/null 2>&1") != 0)
        skip();
    Mech *mech = load_file("examples/slider_crank.mech");
    const Model *m = mech->model;
    EmitOptions eo = emit_default_options();
    eo.real_float = true;
    eo.prefix = "fsc";
    EmitResult er;
    Diag diag;
    if (!emit_mechanism(&mech->kin, &eo, &er, &diag))
        fail_msg("emit: %s", diag.message);

    char dir[] = "/tmp/mechc-test-run-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char src[256], lib[256], cmd[1024];
    snprintf(src, sizeof src, "%s/fsc.c", dir);
    snprintf(lib, sizeof lib, "%s/fsc.so", dir);
    FILE *f = fopen(src, "w");
    assert_non_null(f);
    fputs(er.c_text, f);
    fclose(f);
    emit_result_free(&er);
    snprintf(cmd, sizeof cmd, "cc -std=c99 -pedantic -Wall -Wextra -Werror -O2 -fPIC -shared "
             "-o %s %s -lm", lib, src);
    assert_int_equal(system(cmd), 0);
    void *h = dlopen(lib, RTLD_NOW | RTLD_LOCAL);
    if (!h)
        fail_msg("dlopen: %s", dlerror());
    FloatLib fl;
    *(void **)&fl.phi = dlsym(h, "fsc_phi");
    *(void **)&fl.jac = dlsym(h, "fsc_jac");
    *(void **)&fl.nu = dlsym(h, "fsc_nu");
    *(void **)&fl.gamma = dlsym(h, "fsc_gamma");
    *(void **)&fl.all = dlsym(h, "fsc_all");
    assert_true(fl.phi && fl.jac && fl.nu && fl.gamma && fl.all);

    /* the double run through run_analysis */
    const int steps = 100;
    RunOptions o = run_default_options();
    o.steps = steps;
    Collected c;
    run_with(mech, ENGINE_JIT, o, &c);
    expect_ok(&c, steps);

    /* the float run, stepped like firmware would step it */
    enum { NQ = 9 };
    assert_int_equal(m->nq, NQ);
    MechrtKernels k = {NQ, NQ, 0, &fl, fl_phi, fl_jac, fl_nu, fl_gamma, fl_all, NULL, NULL};
    float q[NQ], qd[NQ] = {0}, qdd[NQ] = {0}, work[MECHRT_WORKSPACE_LEN(NQ, NQ)];
    for (int i = 0; i < NQ; i++)
        q[i] = (float)m->q0[i];
    MechrtReport rep;
    float t = 0;
    double worst = 0;
    for (int s = 0; s <= steps; s++) {
        float tn = (float)s / (float)steps;
        MechrtStatus st = mechrt_step(&k, NULL, q, qd, qdd, t, s == 0 ? 0.0f : tn - t, work,
                                      sizeof work / sizeof *work, &rep);
        if (st != MECHRT_OK)
            fail_msg("float run, t = %g: %s", (double)tn, mechrt_strerror(st));
        t = tn;
        const double *ds = state_at(&c, (size_t)s);
        for (int i = 0; i < NQ; i++) {
            /* positions and velocities to 1e-4; accelerations (up to 40
               m/s^2 and rad/s^2 here) to 1e-4 relative */
            assert_near(q[i], ds[1 + i], 0, 1e-4);
            assert_near(qd[i], ds[1 + NQ + i], 1e-4, 1e-4);
            assert_near(qdd[i], ds[1 + 2 * NQ + i], 1e-4, 1e-4);
            worst = fmax(worst, fabs(q[i] - ds[1 + i]));
        }
    }
    print_message("float kernels + float runtime vs double: worst |dq| %.3g\n", worst);
    collected_free(&c);
    dlclose(h);
    unlink(src);
    unlink(lib);
    rmdir(dir);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slider_crank_closed_form),
        cmocka_unit_test(test_four_bar_freudenstein),
        cmocka_unit_test(test_knife_cart_circle),
        cmocka_unit_test(test_rolling_wheel),
        cmocka_unit_test(test_examples_run),
        cmocka_unit_test(test_coarse_steps_keep_branch),
        cmocka_unit_test(test_coarse_steps_from_rest),
        cmocka_unit_test(test_substep_limit),
        cmocka_unit_test(test_toggle),
        cmocka_unit_test(test_out_of_reach),
        cmocka_unit_test(test_assembly_and_nan),
        cmocka_unit_test(test_assembly_from_zero_guesses),
        cmocka_unit_test(test_assembly_examples_zero_angles),
        cmocka_unit_test(test_construction_picks_branch),
        cmocka_unit_test(test_slider_crank_sweep_zero_guesses),
        cmocka_unit_test(test_one_instant),
        cmocka_unit_test(test_outputs_slider_crank),
        cmocka_unit_test(test_rough_assembly_keeps_free_coordinates),
        cmocka_unit_test(test_cannot_assemble),
        cmocka_unit_test(test_row_count),
        cmocka_unit_test(test_condition_episodes),
        cmocka_unit_test(test_engines_agree),
        cmocka_unit_test(test_host_projection),
        cmocka_unit_test(test_output_formats),
        cmocka_unit_test(test_float_kernels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
