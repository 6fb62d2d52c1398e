/* test_redundant.c - more rows than coordinates (generator/analysis/redundant.c): run and sim on the independent rows, every row checked.
 *
 * The planar four-bar written in 3D with four revolutes about z (24 rows,
 * 21 coordinates, three rows redundant) must move as four_bar.mech does;
 * the Bricard linkage with a driver (36 rows, 35 coordinates) runs to its
 * limit position and stops there as a driven mechanism does at a limit;
 * a redundancy that contradicts the other rows fails, naming the rows.
 * Runs from the repository root (examples/ relative), like `make check`.
 */
#include "testutil.h"
#include "testload.h"

#include <stdlib.h>
#include <string.h>

#include "../generator/dyn/sim.h"
#include "../generator/verify/check.h"
#include "../generator/kin/run.h"
#include "../generator/pipeline/pipeline.h"
#include "../runtime/host/mechrt_host.h"

/* Every state of a run or sim, and how it ended. */
typedef struct Collected {
    MechrtTrace trace;
    RunResult res;
    SimResult sres;
    AnalysisStatus status;
    int nr;
    double *lambda;         /* the last state's multipliers (nr) */
    char notes[8192];
} Collected;

static void collect(void *ctx, double t, const double *q, const double *qd, const double *qdd)
{
    Collected *c = ctx;
    assert_true(mechrt_trace_push(&c->trace, t, q, qd, qdd));
}

static void collect_forces(void *ctx, double t, const double *q, const double *qd,
                           const double *qdd, const double *lambda)
{
    Collected *c = ctx;
    collect(ctx, t, q, qd, qdd);
    memcpy(c->lambda, lambda, (size_t)c->nr * sizeof *lambda);
}

static const double *state_at(const Collected *c, size_t i)
{
    return c->trace.data + i * (1 + 3 * (size_t)c->trace.nq);
}

static int coord(const Model *m, const char *name)
{
    for (int i = 0; i < m->nq; i++)
        if (strcmp(m->coord_names[i], name) == 0)
            return i;
    fail_msg("no coordinate %s", name);
    return -1;
}

static int row(const Model *m, const char *name)
{
    for (int i = 0; i < m->nr; i++)
        if (strcmp(m->rows[i].name, name) == 0)
            return i;
    fail_msg("no row %s", name);
    return -1;
}

/* What: 0 run, 1 run --forces, 2 sim; linear: RunOptions.linear. */
enum { RUN, FORCES, SIM };

static void analyse(Mech *mech, int what, AnalysisLinear linear, double t1, int steps,
                    Collected *c)
{
    Engine e;
    Diag diag;
    memset(c, 0, sizeof *c);
    const Model *m = mech->model;
    mechrt_trace_init(&c->trace, m->nq);
    c->nr = m->nr;
    c->lambda = calloc((size_t)m->nr + 1, sizeof *c->lambda);
    if (!engine_open(&e, ENGINE_JIT, mech, &diag))
        fail_msg("jit engine: %s", diag.message);
    FILE *notes = fmemopen(c->notes, sizeof c->notes - 1, "w");
    assert_non_null(notes);
    const MechrtHostJacNz *jnz = engine_jac_nz(&e);
    if (what == SIM) {
        SimOptions o = sim_default_options();
        o.t1 = t1;
        o.steps = steps;
        o.notes = notes;
        o.linear = linear;
        c->status = sim_run(m, &e.k, jnz, engine_mass_nz(&e), &o, collect_forces, c, &c->sres);
    } else {
        RunOptions o = run_default_options();
        o.t1 = t1;
        o.steps = steps;
        o.notes = notes;
        o.linear = linear;
        c->status = what == FORCES
                    ? run_analysis_forces(m, &e.k, jnz, &o, collect_forces, c, &c->res)
                    : run_analysis(m, &e.k, jnz, &o, collect, c, &c->res);
    }
    fclose(notes);
    engine_close(&e);
}

static void collected_free(Collected *c)
{
    mechrt_trace_free(&c->trace);
    free(c->lambda);
}

/* An example's text with lines added at its end (free()). */
static char *example_plus(const char *name, const char *extra)
{
    char path[256];
    snprintf(path, sizeof path, "examples/%s", name);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *text = calloc(1, 65536);
    size_t n = fread(text, 1, 65536 - strlen(extra) - 2, f);
    fclose(f);
    snprintf(text + n, 65536 - n, "\n%s\n", extra);
    return text;
}

/* The rocker's angle of the spatial four-bar, from its Euler parameters
   (a turn about z by theta: e0 = cos(theta/2), e3 = sin(theta/2)),
   brought within pi of the planar angle. */
static double rocker_angle(const double *q, int ie0, int ie3, double planar)
{
    double a = 2 * atan2(q[ie3], q[ie0]);
    return a + 2 * M_PI * round((planar - a) / (2 * M_PI));
}

/* The z-revolute four-bar moves as the planar one: coupler point and
   rocker angle, their rates, over a crank turn, dense and sparse; the
   redundant rows named once. */
static void test_four_bar_equals_planar(void **state)
{
    (void)state;
    const int steps = 100;
    Mech *planar = load_example("four_bar.mech");
    Mech *spatial = load_example("four_bar_spatial_redundant.mech");
    Collected p, s;
    analyse(planar, RUN, ANALYSIS_LINEAR_DENSE, 1, steps, &p);
    assert_int_equal(p.status, ANALYSIS_OK);
    const Model *mp = planar->model, *ms = spatial->model;
    int px = coord(mp, "coupler.x"), py = coord(mp, "coupler.y"), pphi = coord(mp, "rocker.phi");
    int sx = coord(ms, "coupler.x"), sy = coord(ms, "coupler.y");
    int se0 = coord(ms, "rocker.e0"), se3 = coord(ms, "rocker.e3");
    for (int lin = ANALYSIS_LINEAR_DENSE; lin <= ANALYSIS_LINEAR_SPARSE; lin++) {
        analyse(spatial, RUN, (AnalysisLinear)lin, 1, steps, &s);
        if (s.status != ANALYSIS_OK)
            fail_msg("%s", s.res.message);
        assert_int_equal(s.res.sparse, lin == ANALYSIS_LINEAR_SPARSE);
        const char *note = "four_bar_spatial_redundant.mech: note: 24 holonomic rows for 21 "
                           "coordinates: redundant rows: O4.z (joint O4), O4.f (joint O4), "
                           "O4.g (joint O4); solved on the other 21 rows";
        char *at = strstr(s.notes, note);
        assert_non_null(at);
        assert_null(strstr(at + strlen(note), "redundant rows:"));     /* once */
        int nqp = mp->nq, nqs = ms->nq;
        for (int i = 0; i <= steps; i++) {
            const double *a = state_at(&p, (size_t)i), *b = state_at(&s, (size_t)i);
            assert_near(b[0], a[0], 0, 0);
            for (int d = 0; d < 3; d++) {       /* q, qd, qdd */
                const double *qa = a + 1 + d * nqp, *qb = b + 1 + d * nqs;
                double tol = d == 0 ? 1e-10 : d == 1 ? 1e-9 : 1e-8;
                assert_near(qb[sx], qa[px], tol, tol);
                assert_near(qb[sy], qa[py], tol, tol);
                if (d == 0)
                    assert_near(rocker_angle(qb, se0, se3, qa[pphi]), qa[pphi], 1e-10, 1e-10);
            }
        }
        collected_free(&s);
    }
    collected_free(&p);
    pipeline_free(planar);
    pipeline_free(spatial);
}

/* The Bricard linkage driven at J1: one row redundant (J6.g, as info
   says), the motion to the limit position, and there the limit's message. */
static void test_bricard_driven_to_its_limit(void **state)
{
    (void)state;
    char *text = example_plus("bricard.mech", "driver D: angle(J1) = t");
    Mech *mech = load_text(text, "bricard_driven.mech");
    Collected c;
    analyse(mech, RUN, ANALYSIS_LINEAR_DENSE, 3, 30, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_non_null(strstr(c.notes, "redundant row: J6.g (joint J6);"));
    assert_non_null(strstr(c.res.message, "the mechanism cannot reach the driven position: "
                                          "driver 'D' pushes it past a limit position"));
    assert_true(c.res.t_fail > 2.7 && c.res.t_fail < 2.8);
    assert_int_equal(c.res.states, 28);         /* t = 0 .. 2.7 */
    collected_free(&c);
    pipeline_free(mech);
    free(text);
}

/* A redundancy that contradicts: the fourth revolute 1 mm above the plane
   (its O4.z cannot hold), and a second driver of the crank at another
   speed (consistent at t = 0, not in velocity). */
static void test_inconsistent_redundancy(void **state)
{
    (void)state;
    char *text = example_plus("four_bar_spatial_redundant.mech", "");
    char *at = strstr(text, "ground(d, 0, 0)");
    assert_non_null(at);
    memcpy(at, "ground(d, 0, 1e-3)", strlen("ground(d, 0, 1e-3)"));    /* "  rocker" follows */
    assert_int_equal(at[18], ' ');
    Mech *mech = load_text(text, "z.mech");
    Collected c;
    analyse(mech, RUN, ANALYSIS_LINEAR_DENSE, 1, 10, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_int_equal(c.res.states, 0);
    assert_near(c.res.t_fail, 0, 0, 0);
    assert_non_null(strstr(c.res.message, "t = 0: the redundant rows contradict the others: "
                                          "row O4.z (joint O4) is violated at the position level "
                                          "(residual 0.001, tolerance 1e-06)"));
    collected_free(&c);
    pipeline_free(mech);
    free(text);

    text = example_plus("four_bar_spatial_redundant.mech", "driver D2: angle(O2) = 2*omega*t");
    mech = load_text(text, "d2.mech");
    analyse(mech, RUN, ANALYSIS_LINEAR_DENSE, 1, 10, &c);
    assert_int_equal(c.status, ANALYSIS_FAILED);
    assert_non_null(strstr(c.notes, "redundant rows: O4.z (joint O4), O4.f (joint O4), O4.g "
                                    "(joint O4), D2 (joint D2);"));
    assert_non_null(strstr(c.res.message, "t = 0: the redundant rows contradict the others: "
                                          "row D2 (joint D2) is violated at the velocity level"));
    collected_free(&c);
    pipeline_free(mech);
    free(text);
}

/* Masses for the four-bars: slender links (J = m L^2 / 12 about z; in 3D
   about y too, and a little about x), gravity along -y. */
static const char planar_masses[] =
    "mass crank   m = 1    J = 1/12\n"
    "mass coupler m = 3    J = 3*b^2/12\n"
    "mass rocker  m = 2.5  J = 2.5*c^2/12\n"
    "gravity (0, -9.81)";
static const char spatial_masses[] =
    "mass crank   m = 1    J = (0.01, 1/12, 1/12)\n"
    "mass coupler m = 3    J = (0.01, 3*b^2/12, 3*b^2/12)\n"
    "mass rocker  m = 2.5  J = (0.01, 2.5*c^2/12, 2.5*c^2/12)\n"
    "gravity (0, -9.81, 0)";

/* run --forces: the reactions of the rows both files have are the planar
   file's (the basis solution: the redundant rows carry 0), said once. */
static void test_four_bar_forces(void **state)
{
    (void)state;
    char *tp = example_plus("four_bar.mech", planar_masses);
    char *ts = example_plus("four_bar_spatial_redundant.mech", spatial_masses);
    Mech *planar = load_text(tp, "planar.mech"), *spatial = load_text(ts, "spatial.mech");
    Collected p, s;
    analyse(planar, FORCES, ANALYSIS_LINEAR_DENSE, 0.3, 3, &p);
    analyse(spatial, FORCES, ANALYSIS_LINEAR_DENSE, 0.3, 3, &s);
    assert_int_equal(p.status, ANALYSIS_OK);
    if (s.status != ANALYSIS_OK)
        fail_msg("%s", s.res.message);
    assert_non_null(strstr(s.notes, "spatial.mech: note: the reactions of the redundant rows and "
                                    "of the rows they repeat are not unique: reported as the "
                                    "independent rows' (0 on O4.z (joint O4), O4.f (joint O4), "
                                    "O4.g (joint O4))"));
    const Model *mp = planar->model, *ms = spatial->model;
    const char *same[] = {"O2.x", "O2.y", "A.x", "A.y", "B.x", "B.y", "O4.x", "O4.y"};
    for (size_t i = 0; i < sizeof same / sizeof *same; i++)
        assert_near(s.lambda[row(ms, same[i])], p.lambda[row(mp, same[i])], 1e-9, 1e-9);
    assert_near(s.lambda[row(ms, "O4.z")], 0, 0, 0);
    assert_near(s.lambda[row(ms, "O4.f")], 0, 0, 0);
    assert_near(s.lambda[row(ms, "O4.g")], 0, 0, 0);
    collected_free(&p);
    collected_free(&s);
    pipeline_free(planar);
    pipeline_free(spatial);
    free(tp), free(ts);
}

/* text with its line starting with `start` replaced by line (in place:
   text has room). */
static void replace_line(char *text, const char *start, const char *line)
{
    char *at = strstr(text, start);
    assert_non_null(at);
    char *end = strchr(at, '\n');
    assert_non_null(end);
    size_t tail = strlen(end) + 1;
    memmove(at + strlen(line), end, tail);
    memcpy(at, line, strlen(line));
}

/* sim: the z-revolute four-bar without its driver, released under gravity
   from the assembled configuration, moves as the planar one (the rows it
   drops leave the motion alone); dense and sparse. */
static void test_four_bar_sim(void **state)
{
    (void)state;
    char *tp = example_plus("four_bar.mech", planar_masses);
    char *ts = example_plus("four_bar_spatial_redundant.mech", spatial_masses);
    replace_line(tp, "driver drive", "");
    replace_line(ts, "driver drive", "");
    replace_line(tp, "body coupler", "body coupler x = 1.84375  y = 1.2401959270615268  "
                 "phi = 0.9733899101495463");
    replace_line(tp, "body rocker", "body rocker x = 2.84375  y = 1.2401959270615268  "
                 "phi = 1.696124157962962");
    replace_line(ts, "body coupler", "body coupler x = 1.84375  y = 1.2401959270615268  z = 0  "
                 "orient = axis(0, 0, 1, 0.9733899101495463)");
    replace_line(ts, "body rocker", "body rocker x = 2.84375  y = 1.2401959270615268  z = 0  "
                 "orient = axis(0, 0, 1, 1.696124157962962)");
    Mech *planar = load_text(tp, "planar.mech"), *spatial = load_text(ts, "spatial.mech");
    const Model *mp = planar->model, *ms = spatial->model;
    assert_int_equal(ms->nh, 23);
    Collected p, s;
    analyse(planar, SIM, ANALYSIS_LINEAR_DENSE, 1, 20, &p);
    assert_int_equal(p.status, ANALYSIS_OK);
    int px = coord(mp, "coupler.x"), py = coord(mp, "coupler.y"), pphi = coord(mp, "rocker.phi");
    int sx = coord(ms, "coupler.x"), sy = coord(ms, "coupler.y");
    int se0 = coord(ms, "rocker.e0"), se3 = coord(ms, "rocker.e3");
    for (int lin = ANALYSIS_LINEAR_DENSE; lin <= ANALYSIS_LINEAR_SPARSE; lin++) {
        analyse(spatial, SIM, (AnalysisLinear)lin, 1, 20, &s);
        if (s.status != ANALYSIS_OK)
            fail_msg("%s", s.sres.message);
        assert_non_null(strstr(s.notes, "spatial.mech: note: 23 holonomic rows for 21 "
                                        "coordinates: redundant rows: O4.z (joint O4), O4.f "
                                        "(joint O4), O4.g (joint O4); solved on the other 20 rows"));
        assert_non_null(strstr(s.notes, "reactions of the redundant rows"));
        for (int i = 0; i <= 20; i++) {
            const double *a = state_at(&p, (size_t)i), *b = state_at(&s, (size_t)i);
            const double *qa = a + 1, *qb = b + 1;
            assert_near(b[0], a[0], 0, 0);
            assert_near(qb[sx], qa[px], 1e-9, 1e-9);
            assert_near(qb[sy], qa[py], 1e-9, 1e-9);
            assert_near(rocker_angle(qb, se0, se3, qa[pphi]), qa[pphi], 1e-9, 1e-9);
        }
        assert_near(s.lambda[row(ms, "O4.z")], 0, 0, 0);
        assert_near(s.lambda[row(ms, "O4.x")], p.lambda[row(mp, "O4.x")], 1e-6, 1e-6);
        collected_free(&s);
    }
    collected_free(&p);
    pipeline_free(planar);
    pipeline_free(spatial);
    free(tp), free(ts);
}

/* check: the base state assembled on the rows kept (the note once), every
   comparison within tolerance; where the redundant rows contradict, the
   initial values, not assembled. */
static void test_check(void **state)
{
    (void)state;
    const char *names[] = {"four_bar_spatial_redundant.mech", "O4 1 mm above the plane"};
    for (int i = 0; i < 2; i++) {
        char *text = example_plus("four_bar_spatial_redundant.mech", "");
        if (i == 1)
            replace_line(text, "revolute O4", "revolute O4: ground(d, 0, 1e-3) rocker(-c/2, 0, 0) "
                         "axis(0, 0, 1)");
        Mech *mech = load_text(text, "fb.mech");
        CheckOptions opt = check_default_options();
        opt.use_aot = false;
        opt.samples = 3;
        char notes[2048] = "";
        opt.notes = fmemopen(notes, sizeof notes - 1, "w");
        CheckReport rep;
        Diag diag;
        assert_true(check_mechanism(mech, &opt, &rep, &diag));
        fclose(opt.notes);
        if (rep.assembled != (i == 0) || !rep.ok)
            fail_msg("%s: assembled %d, ok %d", names[i], rep.assembled, rep.ok);
        assert_non_null(strstr(notes, "fb.mech: note: 24 holonomic rows for 21 coordinates: "
                                      "redundant rows: O4.z (joint O4), O4.f (joint O4), O4.g "
                                      "(joint O4);"));
        pipeline_free(mech);
        free(text);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_four_bar_equals_planar),
        cmocka_unit_test(test_bricard_driven_to_its_limit),
        cmocka_unit_test(test_inconsistent_redundancy),
        cmocka_unit_test(test_four_bar_forces),
        cmocka_unit_test(test_four_bar_sim),
        cmocka_unit_test(test_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
