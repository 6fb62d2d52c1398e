/* test_model.c - the model builder's input errors (names, attachments, joint sanity, row levels), its body table, and option parsing. */
#include "testutil.h"

#include "../generator/kin/outputs.h"
#include "../generator/cli/cli.h"
#include "../generator/model/orient.h"
#include "../generator/pipeline/pipeline.h"

#include <math.h>
#include <string.h>

typedef struct BadInput {
    const char *text;
    int line, col;
    const char *needle;         /* a part of the message */
} BadInput;

static const BadInput bad_inputs[] = {
    /* coordinates in length, angle and radius: the spec allows t only */
    {"body b\nprismatic J: ground b axis(1,0) angle = b.phi\n", 2, 41, "cannot appear in a joint's length, angle or radius"},
    {"point a\ndistance J: a ground length = a.x\n", 2, 31, "cannot appear in a joint's length"},
    {"coord c\nbody b\nrolling R: b radius = 1 + c\n", 3, 27, "only params may appear"},
    {"body b\nrolling R: b radius = der(b.x)\n", 2, 23, "der() cannot appear in a joint's length"},
    /* joints between a frame and itself */
    {"point a\nrevolute RG: ground(1,1) ground(2,2)\n", 2, 26, "joins ground to ground"},
    {"body a\nrevolute R: a(1,0.5) a(-0.3,0.2)\n", 2, 22, "joins 'a' to itself"},
    {"point p\ndistance D: p p length = 1\n", 2, 15, "joins 'p' to itself"},
    /* velocity rows whose der() terms simplify away */
    {"point a\nvelocity J: 0*der(a.x) + a.y = 0\n", 2, 1, "no der() term left"},
    {"point a\nvelocity J: der(a.x) = der(a.x)\n", 2, 1, "no der() term left"},
    /* the attachment kinds each joint takes, named in the message */
    {"coord c\nrolling R: c radius = 1\n", 2, 12, "rolling attaches to a body"},
    {"coord c\nbody b\nprismatic P: c b axis(1,0)\n", 3, 14, "prismatic attaches to bodies or ground"},
    {"param k = 1\nbody b\nrevolute R: k b\n", 3, 13, "revolute attaches to bodies, points or ground"},
    /* spatial files (doc/spatial.md): the `spatial` statement, the dimension of
       every statement, axes and orientations */
    {"body b\nspatial\n", 2, 1, "'spatial' must be the first statement"},
    {"mechanism m\nspatial\nspatial\n", 3, 1, "a second 'spatial' statement (the first is on line 2)"},
    {"body b\nspherical S: ground b\n", 2, 1, "'spherical' is a spatial joint: a spatial mechanism says 'spatial'"},
    {"spatial\nbody b\nprismatic P: ground b axis(1,0)\n", 3, 1, "'prismatic' is a planar joint, and this file is spatial ('spatial' on line 1)"},
    {"spatial\nbody b\nknife K: b axis(1, 0, 0)\n", 3, 1, "'knife' is a planar joint"},
    {"body b z = 1\n", 1, 8, "'z' is for spatial files"},
    {"body b orient = axis(0, 0, 1, 1)\n", 1, 8, "'orient' is for spatial files"},
    {"spatial\nbody b phi = 1\n", 2, 8, "a spatial body has no 'phi'"},
    {"spatial\nbody b orient = axis(0, 0, 0, 1)\n", 2, 8, "cannot be normalised: its axis is zero"},
    {"spatial\nbody b orient = axis(0, 0, 1)\n", 2, 29, "orient = axis(ux, uy, uz, angle) has four components, found three"},
    {"spatial\nbody b orient = abc(0, 0, 1)\n", 2, 17, "axis(ux, uy, uz, angle), xyz(a, b, c) or zyx(a, b, c)"},
    {"spatial\nbody b\nspherical S: ground(1, 2) b\n", 3, 25, "has three components, found two"},
    {"spatial\nbody b\nspherical S: ground(1, 2, 3, 4) b\n", 3, 30, "has three components, found more"},
    {"spatial\nbody b\nrevolute R: ground b axis(0, 0, 0)\n", 3, 22, "the axis of revolute 'R' is zero"},
    {"spatial\nbody b\nrevolute R: ground b axis(1, 0)\n", 3, 31, "has three components, found two"},
    {"spatial\nbody b\nrevolute R: ground b\n", 3, 21, "'axis(ux, uy, uz)' after the attachments of revolute 'R'"},
    {"spatial\nbody b\nuniversal U: ground b axis(1, 0, 0)\n", 3, 36, "B's axis: universal 'U' takes two axes"},
    {"spatial\nbody b\nrevolute R: ground b axis(0, 0, 1) axis(0, 0, 1) axis(1, 0, 0)\n", 3, 50, "at most two axes"},
    {"spatial\nbody b\nspherical S: ground b axis(0, 0, 1)\n", 3, 23, "spherical joints take no 'axis'"},
    {"spatial\nbody b\nspherical S: ground b\ndriver D: angle(S) = t\n", 4, 17, "angle() takes a revolute or cylindrical joint; 'S' is spherical"},
    {"spatial\nbody b\nrevolute R: ground b axis(0, 0, 1)\ndriver D: slide(R) = t\n", 4, 17, "slide() takes a translational or cylindrical joint; 'R' is revolute"},
    {"spatial\nbody b\nconstraint C: b.phi = 0\n", 3, 17, "body 'b' has no coordinate 'phi' (it has x, y, z, e0, e1, e2 and e3)"},
    {"spatial\npoint p\nconstraint C: p.e0 = 0\n", 3, 17, "point 'p' has no coordinate 'e0' (it has x, y and z)"},
    {"spatial\nbody b\nrolling R: b radius = 1\n", 3, 24, "'axis(ux, uy, uz)' after the attachments of rolling 'R'"},
    /* axes that must not be parallel: as written, and once turned by the
       initial orientation (b turned by pi/2 about x takes its y to z) */
    {"spatial\nbody b\nuniversal U: ground b axis(0, 0, 1) axis(0, 0, 2)\n", 3, 37, "the two axes of universal 'U' are parallel in the initial orientations"},
    {"spatial\nbody b orient = axis(1, 0, 0, pi/2)\nperpendicular P: ground b axis(0, 0, 1) axis(0, 1, 0)\n", 3, 41, "the two axes of perpendicular 'P' are parallel"},
    {"spatial\nbody d z = 1\nrolling R: d radius = 1 axis(0, 0, 1)\n", 3, 25, "the disk of rolling 'R' lies flat"},
    /* a disk of no or negative radius (accepted, exit 0: the outside corpus) */
    {"spatial\nbody d z = 1\nrolling R: d radius = 0 axis(0, 1, 0)\n", 3, 14, "the radius of rolling 'R' is 0: a disk's radius must be positive"},
    {"spatial\nbody d z = 1\nrolling R: d radius = 1 - 2 axis(0, 1, 0)\n", 3, 14, "the radius of rolling 'R' is -1: a disk's radius must be positive"},
};

static void test_bad_inputs(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    for (size_t i = 0; i < sizeof bad_inputs / sizeof *bad_inputs; i++) {
        const BadInput *b = &bad_inputs[i];
        Diag diag;
        Mech *mech = pipeline_load_text(b->text, "bad.mech", &limits, &diag);
        if (mech) {
            pipeline_free(mech);
            fail_msg("case %zu accepted: %s", i, b->text);
        }
        if (!diag.has_pos || diag.line != b->line || diag.col != b->col || !strstr(diag.message, b->needle))
            fail_msg("case %zu: error at %d:%d '%s', expected %d:%d containing '%s'", i, diag.line,
                     diag.col, diag.message, b->line, b->col, b->needle);
    }
}

/* text loads and has nr rows. */
static void assert_loads(const char *text, int nr)
{
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text(text, "ok.mech", &limits, &diag);
    if (!mech)
        fail_msg("rejected: %s", diag.message);
    assert_int_equal(mech->model->nr, nr);
    pipeline_free(mech);
}

/* What stays valid: t in options, and joints between different frames. */
static void test_time_in_options_is_fine(void **state)
{
    (void)state;
    assert_loads("body b\ndistance d: ground b length = 1 + t\n"
                 "prismatic p: ground b axis(1,0) angle = 0.1*t\n"
                 "body w\nrolling r: w radius = 0.3 + 0.1*t\n", 4);
}

/* The same local axes are not parallel once B starts turned: accepted
   (b.norm and U's four rows). */
static void test_turned_universal_accepted(void **state)
{
    (void)state;
    assert_loads("spatial\nbody b orient = axis(1, 0, 0, pi/2)\n"
                 "universal U: ground b axis(0, 0, 1) axis(0, 0, 1)\n", 5);
}

/* The body table: bodies and points in declaration order with their first
   coordinate, scalar coords, params and joints left out. */
static void test_body_table(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text("coord c = 1\nbody b x = 0.5\nparam k = 2\npoint p x = 0.5\n"
                                    "coord d\nbody w phi = 0.3\nrevolute R: b p\n"
                                    "distance D: w ground(1, 0) length = k\n",
                                    "bodies.mech", &limits, &diag);
    if (!mech)
        fail_msg("rejected: %s", diag.message);
    const Model *m = mech->model;
    assert_int_equal(m->nq, 10);
    assert_int_equal(m->nbodies, 3);
    static const struct { const char *name; int q, nq; bool has_phi; } want[] = {
        {"b", 1, 3, true}, {"p", 4, 2, false}, {"w", 7, 3, true},
    };
    for (int i = 0; i < 3; i++) {
        const Body *b = &m->bodies[i];
        assert_string_equal(b->name, want[i].name);
        assert_int_equal(b->q, want[i].q);
        assert_int_equal(b->nq, want[i].nq);
        assert_int_equal(b->has_phi, want[i].has_phi);
        /* its coordinates are NAME.x, NAME.y (, NAME.phi) */
        char x[16];
        snprintf(x, sizeof x, "%s.x", b->name);
        assert_string_equal(m->coord_names[b->q], x);
        assert_ptr_equal(model_find_body(m, b->name), b);
    }
    assert_string_equal(m->coord_names[m->bodies[2].q + 2], "w.phi");
    assert_near(m->q0[m->bodies[0].q], 0.5, 0, 0);
    /* the joints' attachments agree with the table */
    assert_int_equal(m->joints[0].a.q, m->bodies[0].q);
    assert_int_equal(m->joints[0].b.q, m->bodies[1].q);
    assert_false(m->joints[0].b.has_phi);
    static const char *const not_bodies[] = {"c", "d", "k", "R", "D", "ground", "b.x", "", "bb"};
    for (size_t i = 0; i < sizeof not_bodies / sizeof *not_bodies; i++)
        if (model_find_body(m, not_bodies[i]))
            fail_msg("'%s' found as a body", not_bodies[i]);
    pipeline_free(mech);
}

/* Runs the option loop the commands use; returns the options seen. */
static int parse(char **argv, int argc, Args *a, const char **seen, const char **values)
{
    args_init(a, "test", argc, argv);
    const char *opt;
    int n = 0;
    while (!a->failed && (opt = args_next(a))) {
        seen[n] = opt;
        values[n++] = strcmp(opt, "--t") == 0 ? args_value(a, opt) : NULL;
    }
    if (!a->failed)
        args_next(a);           /* the loop's last call: an unused --flag=value fails here */
    return n;
}

static void test_options(void **state)
{
    (void)state;
    Args a;
    const char *seen[8], *values[8];
    /* argv strings are writable in C: give them storage */
    char file[] = "f.mech", t_opt[] = "--t=0.5", json[] = "--json", json1[] = "--json=1";
    char dd[] = "--", odd[] = "--odd-name.mech";
    char *ok[] = {file, t_opt, json};
    assert_int_equal(parse(ok, 3, &a, seen, values), 2);
    assert_false(a.failed);
    assert_string_equal(a.file, "f.mech");
    assert_string_equal(values[0], "0.5");

    char *flag_value[] = {file, json1};                /* a flag takes no value */
    parse(flag_value, 2, &a, seen, values);
    assert_true(a.failed);

    char *dashes[] = {dd, odd};                        /* after --, file names only */
    assert_int_equal(parse(dashes, 2, &a, seen, values), 0);
    assert_false(a.failed);
    assert_string_equal(a.file, "--odd-name.mech");

    double v[2];
    assert_false(args_vector("test", "--q", "0x10,1", 2, v));   /* no hexadecimal */
    assert_false(args_vector("test", "--q", "nan,1", 2, v));
    assert_true(args_vector("test", "--q", "1e-3,-2", 2, v));
    assert_near(v[0], 1e-3, 0, 0);
    assert_near(v[1], -2.0, 0, 0);
}

/* A(p) v = (2 e0^2 - 1) v + 2 (e (e.v) + e0 (e x v)), the model's rotation. */
static void rotate_by(const double p[4], const double v[3], double out[3])
{
    const double *e = p + 1;
    double ev = e[0] * v[0] + e[1] * v[1] + e[2] * v[2];
    double exv[3] = {e[1] * v[2] - e[2] * v[1], e[2] * v[0] - e[0] * v[2], e[0] * v[1] - e[1] * v[0]};
    for (int i = 0; i < 3; i++)
        out[i] = (2 * p[0] * p[0] - 1) * v[i] + 2 * (e[i] * ev + p[0] * exv[i]);
}

static void assert_close(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol))
        fail_msg("%.17g != %.17g (tolerance %g)", a, b, tol);
}

/* orient = axis(), xyz(), zyx() as Euler parameters: normalised, and the
   rotation they stand for. */
static void test_orientations(void **state)
{
    (void)state;
    double p[4], v[3];
    const double pi = 3.14159265358979323846;
    assert_true(orient_to_euler(ORIENT_AXIS, (double[4]){0, 0, 2, pi / 2}, p));
    assert_close(p[0], sqrt(0.5), 1e-15), assert_close(p[3], sqrt(0.5), 1e-15);
    assert_close(p[1], 0, 0), assert_close(p[2], 0, 0);
    rotate_by(p, (double[3]){1, 0, 0}, v);          /* x turned a quarter about z: y */
    assert_close(v[0], 0, 1e-15), assert_close(v[1], 1, 1e-15), assert_close(v[2], 0, 1e-15);
    assert_false(orient_to_euler(ORIENT_AXIS, (double[4]){0, 0, 0, 1}, p));
    /* xyz(a, b, c) = Rx(a) Ry(b) Rz(c): z turned by Rz (nothing), then by
       Ry(pi/2) to x, then by Rx(a) (nothing) */
    assert_true(orient_to_euler(ORIENT_XYZ, (double[4]){0.3, pi / 2, 0.7, 0}, p));
    assert_close(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3], 1, 1e-15);
    rotate_by(p, (double[3]){0, 0, 1}, v);
    assert_close(v[0], 1, 1e-15), assert_close(v[1], 0, 1e-15);
    assert_close(v[2], 0, 1e-15);
    /* zyx(a, b, c) = Rz(a) Ry(b) Rx(c): x turned by Rx (nothing), Ry(0),
       then Rz(a): (cos a, sin a, 0) */
    assert_true(orient_to_euler(ORIENT_ZYX, (double[4]){0.4, 0, 1.1, 0}, p));
    rotate_by(p, (double[3]){1, 0, 0}, v);
    assert_close(v[0], cos(0.4), 1e-15), assert_close(v[1], sin(0.4), 1e-15);
    assert_close(v[2], 0, 1e-15);
}

/* A spatial file's body table, coordinates, .norm rows and omega. */
static void test_spatial_bodies(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text("spatial\nbody b x = 1 orient = axis(1, 0, 0, pi)\n"
                                    "point p z = 2\nspherical S: b(0, 0, 1) p\n",
                                    "s.mech", &limits, &diag);
    assert_non_null(mech);
    const Model *m = mech->model;
    assert_true(m->spatial);
    assert_int_equal(m->nq, 10);
    assert_int_equal(m->nbodies, 2);
    assert_int_equal(m->bodies[0].nq, 7);
    assert_true(m->bodies[0].spatial && !m->bodies[0].has_phi);
    assert_int_equal(m->bodies[1].nq, 3);
    assert_string_equal(m->coord_names[6], "b.e3");
    assert_string_equal(m->coord_names[9], "p.z");
    assert_close(m->q0[0], 1, 0);
    assert_close(m->q0[3], 0, 1e-16);       /* e0 = cos(pi/2) */
    assert_close(m->q0[4], 1, 0);           /* e1 = sin(pi/2) */
    assert_int_equal(m->nh, 4);
    assert_string_equal(m->rows[0].name, "b.norm");     /* in statement order */
    assert_int_equal(m->rows[0].kind, JOINT_S_NORM);
    assert_string_equal(m->rows[3].name, "S.z");
    OutputEval oe;
    outputs_init(&oe, m);
    assert_int_equal(oe.nw, 3);
    assert_string_equal(oe.wnames[2], "b.wz");
    /* p = (cos(s/2), sin(s/2), 0, 0) turning at s' = 3 about x: omega = (3, 0, 0) */
    double q[10] = {0, 0, 0, cos(0.2), sin(0.2), 0, 0, 0, 0, 0};
    double qd[10] = {0, 0, 0, -1.5 * sin(0.2), 1.5 * cos(0.2), 0, 0, 0, 0, 0}, w[3];
    outputs_omega(&oe, q, qd, w);
    assert_close(w[0], 3, 1e-15), assert_close(w[1], 0, 0), assert_close(w[2], 0, 0);
    outputs_free(&oe);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_inputs),
        cmocka_unit_test(test_time_in_options_is_fine),
        cmocka_unit_test(test_turned_universal_accepted),
        cmocka_unit_test(test_body_table),
        cmocka_unit_test(test_orientations),
        cmocka_unit_test(test_spatial_bodies),
        cmocka_unit_test(test_options),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
