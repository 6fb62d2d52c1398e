/* test_render_spatial.c - the animated SVG of a spatial mechanism: the views' projections, Euler-parameter vertices, first-frame pixels and depth order.
 *
 * The fixture is examples/rssr.mech's mechanism with frames made by hand:
 * the crank turned by theta about z, the rocker by psi about (0, 1, 1)/sqrt 2
 * (any psi: the picture does not check the rows). Its joint points have
 * closed forms (Rodrigues' formula for the rocker tip), which the drawing's
 * first frame must show, projected by the chosen view, at one scale with y
 * up. The depth order is checked where the views disagree on it.
 */
#include "testutil.h"

#include "../generator/pipeline/pipeline.h"
#include "../generator/render/scene.h"
#include "../generator/render/svg_anim.h"
#include "../generator/render/view.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static const char rssr[] =
    "mechanism rssr\n"
    "spatial\n"
    "param a = 1\n"
    "param c = 3\n"
    "param L = sqrt(10)\n"
    "param omega = 2*pi\n"
    "body crank  x = 0  y = 0  z = 0\n"
    "body rocker x = 2  y = 0  z = 0  orient = axis(0, 1, 1, pi/2)\n"
    "revolute R1: ground(0, 0, 0)  crank(0, 0, 0)   axis(0, 0, 1)\n"
    "revolute R2: ground(2, 0, 0)  rocker(0, 0, 0)  axis(0, 1, 1)\n"
    "distance C:  crank(a, 0, 0)   rocker(c, 0, 0)  length = L\n"
    "driver   D:  angle(R1) = omega*t\n";

enum { NF = 41 };

typedef struct Fixture {
    Mech *mech;
    Diag diag;
    double t[NF], q[NF * 14];
} Fixture;

static double theta_at(int k) { return 0.5 * k / (NF - 1); }
static double psi_at(int k) { return M_PI / 2 + 0.3 * sin(theta_at(k)); }

/* The four joint points at frame k: O, A (crank tip), B0, B (rocker tip). */
static void joint_points(int k, double P[4][3])
{
    double th = theta_at(k), ps = psi_at(k), r = sqrt(0.5);
    double pts[4][3] = {{0, 0, 0}, {cos(th), sin(th), 0}, {2, 0, 0},
                        {2 + 3 * cos(ps), 3 * r * sin(ps), -3 * r * sin(ps)}};
    memcpy(P, pts, sizeof pts);
}

static int setup(void **state)
{
    Fixture *fx = calloc(1, sizeof *fx);
    MechLimits limits = mech_default_limits();
    fx->mech = pipeline_load_text(rssr, "rssr.mech", &limits, &fx->diag);
    if (!fx->mech) {
        diag_print(&fx->diag, stderr);
        return -1;
    }
    for (int k = 0; k < NF; k++) {
        double *q = fx->q + 14 * k, th = theta_at(k), ps = psi_at(k), r = sqrt(0.5);
        fx->t[k] = 0.01 * k;
        double qk[14] = {0, 0, 0, cos(th / 2), 0, 0, sin(th / 2),
                         2, 0, 0, cos(ps / 2), 0, r * sin(ps / 2), r * sin(ps / 2)};
        memcpy(q, qk, sizeof qk);
    }
    *state = fx;
    return 0;
}

static int teardown(void **state)
{
    Fixture *fx = *state;
    pipeline_free(fx->mech);
    free(fx);
    return 0;
}

static char *animate(const Fixture *fx, SvgView view, const SvgTrace *tr, int ntr)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    SvgAnimOptions o = svg_anim_default_options();
    o.view = view;
    assert_true(svg_write_animation_opt(f, fx->mech->model, fx->t, fx->q, NF, tr, ntr, NULL, &o));
    fclose(f);
    return buf;
}

/* ---- the views ---- */

static void test_project_known_point(void **state)
{
    (void)state;
    const double P[3] = {1, 2, 3};
    struct { SvgView v; double x, y, depth; } cases[] = {
        {SVG_VIEW_FRONT, 1, 3, -2},     /* x right, z up, the viewer at -y */
        {SVG_VIEW_TOP, 1, 2, 3},        /* x right, y up, the viewer above */
        {SVG_VIEW_SIDE, 2, 3, 1},       /* y right, z up, the viewer at +x */
        {SVG_VIEW_ISO, 3 / sqrt(2), 7 / sqrt(6), 2 / sqrt(3)},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        double x, y;
        svg_view_project(cases[i].v, P, &x, &y);
        assert_near(x, cases[i].x, 0, 1e-15);
        assert_near(y, cases[i].y, 0, 1e-15);
        assert_near(svg_view_depth(cases[i].v, P), cases[i].depth, 0, 1e-15);
    }
    assert_string_equal(svg_view_names[SVG_VIEW_FRONT], "front");
    assert_string_equal(svg_view_names[SVG_VIEW_ISO], "iso");
    assert_null(svg_view_names[SVG_VIEW_ISO + 1]);
}

/* Every view is a rotation (lengths kept, right-handed: right x up = toward
   the viewer), and iso shows x 30 degrees below the horizontal, y 30 above,
   z straight up, each foreshortened to sqrt(2/3). */
static void test_views_are_rotations(void **state)
{
    (void)state;
    const double E[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int v = SVG_VIEW_FRONT; v <= SVG_VIEW_ISO; v++) {
        double col[3][3];       /* per axis: right, up, toward */
        for (int i = 0; i < 3; i++) {
            svg_view_project((SvgView)v, E[i], &col[i][0], &col[i][1]);
            col[i][2] = svg_view_depth((SvgView)v, E[i]);
        }
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double d = col[0][i] * col[0][j] + col[1][i] * col[1][j] + col[2][i] * col[2][j];
                assert_near(d, i == j, 0, 1e-15);
            }
        /* the rows' triple product (right x up) . toward = det = +1 */
        double det = col[0][0] * (col[1][1] * col[2][2] - col[2][1] * col[1][2])
                   - col[1][0] * (col[0][1] * col[2][2] - col[2][1] * col[0][2])
                   + col[2][0] * (col[0][1] * col[1][2] - col[1][1] * col[0][2]);
        assert_near(det, 1, 0, 1e-15);
    }
    double x, y;
    svg_view_project(SVG_VIEW_ISO, E[0], &x, &y);
    assert_near(atan2(y, x) * 180 / M_PI, -30, 0, 1e-12);
    assert_near(hypot(x, y), sqrt(2.0 / 3), 0, 1e-15);
    svg_view_project(SVG_VIEW_ISO, E[1], &x, &y);
    assert_near(atan2(y, x) * 180 / M_PI, 30, 0, 1e-12);
    svg_view_project(SVG_VIEW_ISO, E[2], &x, &y);
    assert_near(x, 0, 0, 1e-15);
    assert_near(y, sqrt(2.0 / 3), 0, 1e-15);
}

/* P = r + A(p) s with Euler parameters, against Rodrigues' formula. */
static void test_vertex_euler(void **state)
{
    Fixture *fx = *state;
    for (int k = 0; k < NF; k += 10) {
        double P[4][3], got[3];
        joint_points(k, P);
        Vtx tip = {.q = 7, .fq = -1, .spatial = true, .has_p = true, .sx = 3};
        scene_vtx_point(&tip, fx->q + 14 * k, got);
        for (int i = 0; i < 3; i++)
            assert_near(got[i], P[3][i], 0, 1e-14);
        Vtx a = {.q = 0, .fq = -1, .spatial = true, .has_p = true, .sx = 1};
        scene_vtx_point(&a, fx->q + 14 * k, got);
        for (int i = 0; i < 3; i++)
            assert_near(got[i], P[1][i], 0, 1e-14);
        /* an offset turned with another body: the crank tip's (0, 0, 1)
           turned with the rocker */
        Vtx off = {.q = 0, .fq = 7, .spatial = true, .has_p = true, .sx = 1, .oz = 1};
        scene_vtx_point(&off, fx->q + 14 * k, got);
        double ps = psi_at(k), r = sqrt(0.5);
        /* Rodrigues: (0,0,1) about k = (0,1,1)/sqrt 2 */
        double w[3] = {r * sin(ps), 0.5 * (1 - cos(ps)), cos(ps) + 0.5 * (1 - cos(ps))};
        for (int i = 0; i < 3; i++)
            assert_near(got[i], P[1][i] + w[i], 0, 1e-14);
    }
}

/* ---- the drawing ---- */

/* The first "X,Y X,Y" pairs of the polyline of class cls titled name
   (its static points: the first frame); returns how many were read. */
static int polyline_points(const char *s, const char *cls, const char *name, double xy[][2],
                           int max)
{
    char open[64], title[64];
    snprintf(open, sizeof open, "<polyline class=\"%s\" ", cls);
    snprintf(title, sizeof title, "<title>%s</title>", name);
    for (const char *p = strstr(s, open); p; p = strstr(p + 1, open)) {
        const char *end = strstr(p, "</polyline>"), *t = strstr(p, title);
        if (!end || !t || t > end)
            continue;
        const char *v = strstr(p, "points=\"") + 8;
        int n = 0;
        char *e;
        while (n < max && *v != '"') {
            xy[n][0] = strtod(v, &e);
            assert_true(*e == ',');
            xy[n][1] = strtod(e + 1, &e);
            n++;
            v = *e == ' ' ? e + 1 : e;
        }
        return n;
    }
    return 0;
}

/* The pixels px of world points P (n of them) are their projections at one
   scale s > 0, y up: X = ox + s x, Y = oy - s y, to the 0.1 px printed. */
static void assert_projected(SvgView view, double P[][3], double px[][2], int n)
{
    double x[8], y[8];
    int bi = 0, bj = 1;
    double best = -1;
    for (int i = 0; i < n; i++)
        svg_view_project(view, P[i], &x[i], &y[i]);
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            if (hypot(x[i] - x[j], y[i] - y[j]) > best)
                best = hypot(x[i] - x[j], y[i] - y[j]), bi = i, bj = j;
    double s = hypot(px[bi][0] - px[bj][0], px[bi][1] - px[bj][1]) / best;
    assert_true(s > 10);
    double ox = px[bi][0] - s * x[bi], oy = px[bi][1] + s * y[bi];
    for (int i = 0; i < n; i++) {
        assert_near(px[i][0], ox + s * x[i], 0, 0.15);
        assert_near(px[i][1], oy - s * y[i], 0, 0.15);
    }
}

static void test_first_frame_is_projected(void **state)
{
    Fixture *fx = *state;
    SvgTrace tr;
    char err[200];
    assert_true(svg_parse_trace(fx->mech->model, "rocker(3, 0, 0)", &tr, err, sizeof err));
    for (int v = SVG_VIEW_FRONT; v <= SVG_VIEW_ISO; v++) {
        char *s = animate(fx, (SvgView)v, &tr, 1);
        double px[5][2], crank[2][2], rocker[2][2], path[1][2], P[5][3];
        assert_int_equal(polyline_points(s, "link", "crank", crank, 2), 2);
        assert_int_equal(polyline_points(s, "link", "rocker", rocker, 2), 2);
        assert_int_equal(polyline_points(s, "trace", "rocker(3, 0, 0)", path, 1), 1);
        joint_points(0, P);
        memcpy(P[4], P[3], sizeof P[3]);    /* the trace starts at the rocker tip */
        memcpy(px[0], crank[0], sizeof crank[0]);
        memcpy(px[1], crank[1], sizeof crank[1]);
        memcpy(px[2], rocker[0], sizeof rocker[0]);
        memcpy(px[3], rocker[1], sizeof rocker[1]);
        memcpy(px[4], path[0], sizeof path[0]);
        assert_projected((SvgView)v, P, px, 5);
        char desc[64];
        snprintf(desc, sizeof desc, "(the %s view, orthographic", svg_view_names[v]);
        assert_non_null(strstr(s, desc));
        assert_int_equal(strstr(s, "class=\"pivot\"") != NULL, 1);
        free(s);
    }
}

static int count(const char *s, const char *what)
{
    int n = 0;
    for (const char *p = strstr(s, what); p; p = strstr(p + 1, what))
        n++;
    return n;
}

/* What is drawn: two links, pins at the two revolutes over ground pivots,
   their axes, the coupler as a dashed distance line with a pin at each end;
   the crank (driven) in red; every link moves. */
static void test_spatial_structure(void **state)
{
    Fixture *fx = *state;
    char *s = animate(fx, SVG_VIEW_ISO, NULL, 0);
    assert_int_equal(count(s, "class=\"link\""), 2);
    assert_int_equal(count(s, "class=\"pivot\""), 2);
    assert_int_equal(count(s, "class=\"pin\""), 4);
    assert_int_equal(count(s, "class=\"axis\""), 2);
    assert_int_equal(count(s, "class=\"distance\""), 1);
    assert_int_equal(count(s, "class=\"drive\""), 0);
    assert_non_null(strstr(s, "style=\"stroke:" SCENE_DRIVE_COLOUR ";fill:none\"><title>crank"));
    /* links and the coupler move; the axes are on ground here */
    assert_int_equal(count(s, "<animate attributeName=\"points\""), 2 + 1);
    assert_non_null(strstr(s, "driver D: crank.e0, crank.e1, crank.e2, crank.e3"));
    assert_null(strstr(s, "nan"));
    free(s);
}

/* Links farthest first at the first frame: the rocker is behind the crank
   in the iso view (mean depth (x - y + z)/sqrt 3: -0.12/sqrt 3 against
   0.5/sqrt 3), in front of it in the side view (mean x: 2 against 0.5). */
static void test_depth_order(void **state)
{
    Fixture *fx = *state;
    SvgView views[2] = {SVG_VIEW_ISO, SVG_VIEW_SIDE};
    for (int i = 0; i < 2; i++) {
        char *s = animate(fx, views[i], NULL, 0);
        const char *c = strstr(s, "<title>crank</title>"), *r = strstr(s, "<title>rocker</title>");
        assert_non_null(c);
        assert_non_null(r);
        assert_int_equal(r < c, views[i] == SVG_VIEW_ISO);
        free(s);
    }
}

static void test_trace_parse_spatial(void **state)
{
    Fixture *fx = *state;
    const Model *m = fx->mech->model;
    SvgTrace tr;
    char err[200];
    assert_true(svg_parse_trace(m, " rocker ( 3 , -0.5 , 2e-1 ) ", &tr, err, sizeof err));
    assert_int_equal(tr.q, 7);
    assert_true(tr.has_phi && tr.spatial);
    assert_near(tr.sx, 3, 0, 0);
    assert_near(tr.sy, -0.5, 0, 0);
    assert_near(tr.sz, 0.2, 0, 0);
    assert_true(svg_parse_trace(m, "crank", &tr, err, sizeof err));
    assert_true(tr.spatial && tr.has_phi && tr.sz == 0);
    assert_false(svg_parse_trace(m, "rocker(3, 0)", &tr, err, sizeof err));
    assert_string_equal(err, "--trace 'rocker(3, 0)': expected ',' between sy and sz");
    assert_false(svg_parse_trace(m, "rocker(3, 0, 0, 1)", &tr, err, sizeof err));
    assert_string_equal(err, "--trace 'rocker(3, 0, 0, 1)': expected ')' after sz");
}

/* A view outside the four, or a planar trace on a spatial model, is refused. */
static void test_bad_input(void **state)
{
    Fixture *fx = *state;
    SvgAnimOptions o = svg_anim_default_options();
    assert_int_equal(o.view, SVG_VIEW_ISO);
    o.view = (SvgView)4;
    FILE *f = tmpfile();
    assert_non_null(f);
    errno = 0;
    assert_false(svg_write_animation_opt(f, fx->mech->model, fx->t, fx->q, NF, NULL, 0, NULL, &o));
    assert_int_equal(errno, EINVAL);
    SvgTrace planar = {.q = 7, .has_phi = true, .sx = 3, .label = "p"};
    assert_false(svg_write_animation(f, fx->mech->model, fx->t, fx->q, NF, &planar, 1, NULL));
    assert_int_equal(ftell(f), 0);
    fclose(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_project_known_point),
        cmocka_unit_test(test_views_are_rotations),
        cmocka_unit_test_setup_teardown(test_vertex_euler, setup, teardown),
        cmocka_unit_test_setup_teardown(test_first_frame_is_projected, setup, teardown),
        cmocka_unit_test_setup_teardown(test_spatial_structure, setup, teardown),
        cmocka_unit_test_setup_teardown(test_depth_order, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trace_parse_spatial, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bad_input, setup, teardown),
    };
    return cmocka_run_group_tests_name("render_spatial", tests, NULL, NULL);
}
