/* test_model.c - the model builder's input errors (names, attachments, joint sanity, row levels), its body table, and option parsing. */
#include "testutil.h"

#include "../generator/cli/cli.h"
#include "../generator/pipeline/pipeline.h"

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
    /* spatial files (issue 14): the `spatial` statement, the dimension of
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

/* What stays valid: t in options, and joints between different frames. */
static void test_time_in_options_is_fine(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text("body b\ndistance d: ground b length = 1 + t\n"
                                    "prismatic p: ground b axis(1,0) angle = 0.1*t\n"
                                    "body w\nrolling r: w radius = 0.3 + 0.1*t\n",
                                    "ok.mech", &limits, &diag);
    if (!mech)
        fail_msg("rejected: %s", diag.message);
    assert_int_equal(mech->model->nr, 4);
    pipeline_free(mech);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_inputs),
        cmocka_unit_test(test_time_in_options_is_fine),
        cmocka_unit_test(test_body_table),
        cmocka_unit_test(test_options),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
