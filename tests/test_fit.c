/* test_fit.c - mechc fit as a library: Freudenstein's three precision positions, the three examples against references of their own, the CSV's errors with their line and column, and the inputs fit_run refuses.
 *
 * Freudenstein: the rocker angle psi of a four-bar of ground link d at
 * crank angles theta satisfies K1 cos psi - K2 cos theta + K3 =
 * cos(theta - psi), K1 = d/a, K2 = d/c, K3 = (a^2 - b^2 + c^2 + d^2)/(2ac),
 * linear in the K's: three (theta, psi) pairs give a, b, c in closed form.
 * The pairs come from a closed-form position solution of the "true"
 * linkage (1.2, 2.8, 2.3); fit_run from (1, 3, 2.5) must land on the
 * closed form's a, b, c to 1e-12; so must the fit of
 * examples/freudenstein.mech to its data. examples/coupler_synthesis.csv's
 * points lie on the coupler curve (closed form) of the linkage its header
 * names, which fit finds. The Stewart platform's 36 joint centres come
 * back to 1e-9 from leg lengths computed here (|r + A(e) p_i - b_i|) for
 * a geometry up to 5 mm off nominal, and the example's own lengths are
 * those of the geometry fit finds from them. The CSVs are written into a
 * folder of the suite's own, removed at the end.
 */
#include "testutil.h"
#include "testload.h"

#include "../generator/base/arena.h"
#include "../generator/engine/engine.h"
#include "../generator/fit/data.h"
#include "../generator/fit/fit.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[256];

static int setup(void **state)
{
    (void)state;
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/mechc_test_fit_XXXXXX", base && *base ? base : "/tmp");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

/* Ground link d = 3 from O2 to O4, crank a, coupler b, rocker c, all
   along their bodies' x axes: theta = crank.phi = t, psi = rocker.phi. */
static const char four_bar_text[] =
    "mechanism freudenstein\n"
    "design a = 1\n"
    "design b = 3\n"
    "design c = 2.5\n"
    "param d = 3\n"
    "body crank   x = 0.44  y = 0.24  phi = 0.5\n"
    "body coupler x = 1.9   y = 1.4   phi = 0.9\n"
    "body rocker  x = 2.8   y = 1.24  phi = 1.7\n"
    "revolute O2: ground(0, 0)     crank(-a/2, 0)\n"
    "revolute A:  crank(a/2, 0)    coupler(-b/2, 0)\n"
    "revolute B:  coupler(b/2, 0)  rocker(c/2, 0)\n"
    "revolute O4: ground(d, 0)     rocker(-c/2, 0)\n"
    "driver input: crank.phi = t\n";

static const double D = 3.0;

/* psi at theta for links a, b, c: A cos psi + B sin psi = C from
   Freudenstein's equation, on the branch with the coupler above the
   ground link (the file's initial values). */
static double rocker_angle(double a, double b, double c, double theta)
{
    double k1 = D / a, k2 = D / c, k3 = (a * a - b * b + c * c + D * D) / (2 * a * c);
    double A = k1 - cos(theta), B = -sin(theta), C = k2 * cos(theta) - k3;
    return atan2(B, A) + acos(C / hypot(A, B));
}

/* The 3x3 system M k = r by Cramer's rule. */
static void solve3(const double M[3][3], const double r[3], double k[3])
{
    double det = M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
               - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
               + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
    for (int c = 0; c < 3; c++) {
        double A[3][3];
        memcpy(A, M, sizeof A);
        for (int i = 0; i < 3; i++)
            A[i][c] = r[i];
        k[c] = (A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1])
                - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0])
                + A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0])) / det;
    }
}

static const char *write_csv(const char *name, const char *text)
{
    static char path[400];
    snprintf(path, sizeof path, "%s/%s", tmpdir, name);
    FILE *f = fopen(path, "w");
    if (!f)
        fail_msg("cannot write %s", path);
    fputs(text, f);
    fclose(f);
    return path;
}

/* fit_run's inputs for mech: every parameter varied, no bounds. */
enum { MAX_P = 64 };
typedef struct Fit {
    Mech *mech;
    Engine e;
    FitData data;
    FitOptions o;
    FitResult r;
    bool vary[MAX_P];
    double lo[MAX_P], hi[MAX_P];
} Fit;

static void fit_open_mech(Fit *f, Mech *mech, const char *csv_path)
{
    memset(f, 0, sizeof *f);
    f->mech = mech;
    assert_true(mech->model->np <= MAX_P);
    Diag diag;
    if (!engine_open(&f->e, ENGINE_JIT, f->mech, &diag))
        fail_msg("jit: %s", diag.message);
    if (!fit_data_read(csv_path, f->mech->model, &f->data, &diag))
        fail_msg("%s: %d:%d: %s", csv_path, diag.line, diag.col, diag.message);
    f->o = fit_default_options();
    f->o.vary = f->vary, f->o.lo = f->lo, f->o.hi = f->hi;
    for (int j = 0; j < MAX_P; j++)
        f->vary[j] = true, f->lo[j] = -INFINITY, f->hi[j] = INFINITY;
}

static void fit_open(Fit *f, const char *text, const char *csv_name, const char *csv)
{
    fit_open_mech(f, load_text(text, "freudenstein.mech"), write_csv(csv_name, csv));
}

/* examples/NAME.mech with its data examples/NAME.csv ($MECHC_EXAMPLES/...). */
static void fit_open_example(Fit *f, const char *name)
{
    const char *dir = getenv("MECHC_EXAMPLES");
    char mech[300], csv[300];
    snprintf(mech, sizeof mech, "%s.mech", name);
    snprintf(csv, sizeof csv, "%s/%s.csv", dir ? dir : "examples", name);
    fit_open_mech(f, load_example(mech), csv);
}

static FitStatus fit_go(Fit *f)
{
    Model *m = f->mech->model;
    return fit_run(m, &f->mech->kin, &f->e, &f->data, &f->o, &f->r);
}

static void fit_close(Fit *f)
{
    fit_result_free(&f->r);
    fit_data_free(&f->data);
    engine_close(&f->e);
    pipeline_free(f->mech);
}

/* The data of the true linkage at theta = 0.5, 1, 1.5, as a CSV. */
static void freudenstein_csv(char *csv, size_t size, double psi[3])
{
    static const double theta[3] = {0.5, 1.0, 1.5};
    int n = snprintf(csv, size, "t,rocker.phi\n");
    for (int i = 0; i < 3; i++) {
        psi[i] = rocker_angle(1.2, 2.8, 2.3, theta[i]);
        n += snprintf(csv + n, size - (size_t)n, "%.17g,%.17g\n", theta[i], psi[i]);
    }
}

/* fit_open on that CSV (csv_name); psi gets the angles. */
static void fit_open_freudenstein(Fit *f, const char *csv_name, double psi[3])
{
    char csv[512];
    freudenstein_csv(csv, sizeof csv, psi);
    fit_open(f, four_bar_text, csv_name, csv);
}

/* a, b, c from three (theta, psi) pairs: Freudenstein's equations, linear
   in K1, K2, K3. */
static void freudenstein_solve(const double theta[3], const double psi[3], double abc[3])
{
    double M[3][3], r[3], k[3];
    for (int i = 0; i < 3; i++) {
        M[i][0] = cos(psi[i]), M[i][1] = -cos(theta[i]), M[i][2] = 1.0;
        r[i] = cos(theta[i] - psi[i]);
    }
    solve3(M, r, k);
    double a = D / k[0], c = D / k[1];
    abc[0] = a, abc[1] = sqrt(a * a + c * c + D * D - 2 * a * c * k[2]), abc[2] = c;
}

static void test_freudenstein_three_positions(void **s)
{
    (void)s;
    static const double theta[3] = {0.5, 1.0, 1.5};
    double psi[3], abc[3];
    Fit f;
    fit_open_freudenstein(&f, "freudenstein.csv", psi);
    freudenstein_solve(theta, psi, abc);
    double a = abc[0], b = abc[1], c = abc[2];
    assert_near(a, 1.2, 0, 1e-12);      /* the closed form recovers the truth */
    assert_near(b, 2.8, 0, 1e-12);
    assert_near(c, 2.3, 0, 1e-12);

    assert_int_equal(f.data.nsamples, 3);
    assert_int_equal(f.data.nmeasured, 3);
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    assert_true(f.r.solved);
    assert_int_equal(f.r.n, 3);
    assert_int_equal(f.r.k, 3);
    assert_near(f.r.p0[0], 1.0, 0, 0);
    assert_near(f.r.p[0], a, 0, 1e-12);
    assert_near(f.r.p[1], b, 0, 1e-12);
    assert_near(f.r.p[2], c, 0, 1e-12);
    assert_true(f.r.cost0 > 1e-3);
    assert_true(f.r.cost < 1e-24);
    for (int i = 0; i < 3; i++)
        assert_near(f.r.model[i], psi[i], 0, 1e-12);
    assert_true(f.r.cond > 1 && isfinite(f.r.cond));
    assert_string_equal(f.r.warning, "");
    for (int j = 0; j < 3; j++)     /* the design found is left set */
        assert_near(f.mech->model->dag.param_values[j], f.r.p[j], 0, 0);
    for (int a1 = 0; a1 < 3; a1++) {
        assert_near(f.r.corr[a1 * 3 + a1], 1.0, 0, 1e-12);
        for (int b1 = 0; b1 < 3; b1++)
            assert_near(f.r.corr[a1 * 3 + b1], f.r.corr[b1 * 3 + a1], 0, 1e-12);
    }
    fit_close(&f);
}

/* Outputs measured: a coupler point at seven times, generated by the
   sampler itself at a true design (1.1, 2.9, 2.4), weighted; the fit from
   the file's design finds the truth. */
static void test_fit_coupler_point(void **s)
{
    (void)s;
    char text[1024], csv[2048];
    snprintf(text, sizeof text, "%soutput P: coupler(0.5, 0.2)\n", four_bar_text);
    Fit f;
    fit_open(&f, text, "grid.csv", "t,P.x,P.y\n0.2,0,0\n0.4,0,0\n0.6,0,0\n0.8,0,0\n1,0,0\n"
                                   "1.2,0,0\n1.4,0,0\n");
    Model *m = f.mech->model;
    static const double truth[3] = {1.1, 2.9, 2.4};
    model_set_design(m, truth);
    FitSampler smp;
    char why[300];
    assert_true(fit_sampler_init(&smp, m, &f.mech->kin, &f.e, &f.data, 100, 1e-13, why, sizeof why));
    double value[14];
    if (!fit_sample(&smp, value, NULL, why, sizeof why))
        fail_msg("fit_sample: %s", why);
    fit_sampler_free(&smp);
    model_set_design(m, NULL);
    int n = snprintf(csv, sizeof csv, "t,P.x,w(P.x),P.y\n");
    for (int k = 0; k < 7; k++)
        n += snprintf(csv + n, sizeof csv - (size_t)n, "%.17g,%.17g,4,%.17g\n", f.data.t[k],
                      value[2 * k], value[2 * k + 1]);
    fit_data_free(&f.data);
    Diag diag;
    assert_true(fit_data_read(write_csv("coupler.csv", csv), m, &f.data, &diag));
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    assert_int_equal(f.r.n, 14);
    for (int j = 0; j < 3; j++)
        assert_near(f.r.p[j], truth[j], 0, 1e-10);
    assert_true(f.r.cost < 1e-20);
    fit_close(&f);
}

/* ---- the examples ------------------------------------------------------ */

/* examples/freudenstein.mech with its three pairs: fit equals the closed
   form of Freudenstein's equations through them. */
static void test_freudenstein_example(void **s)
{
    (void)s;
    Fit f;
    fit_open_example(&f, "freudenstein");
    assert_int_equal(f.data.nsamples, 3);
    assert_int_equal(f.data.ncols, 1);
    assert_string_equal(f.data.names[0], "rocker.phi");
    double abc[3];
    freudenstein_solve(f.data.t, f.data.value, abc);
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    for (int j = 0; j < 3; j++)
        assert_near(f.r.p[j], abc[j], 0, 1e-12);
    fit_close(&f);
}

/* The coupler point of the four-bar the example's header names (pivots
   (0, 0) and (4, 0.5), links 1.2, 3.5, 3, P = (1.5, 1) in the coupler's
   frame) at crank angle theta, on the branch nearer (x, y). */
static void coupler_point(double theta, double x, double y, double P[2])
{
    const double a = 1.2, b = 3.5, c = 3, dx = 4, dy = 0.5, px = 1.5, py = 1;
    double ax = a * cos(theta), ay = a * sin(theta);
    double ex = dx - ax, ey = dy - ay, d = hypot(ex, ey);
    double along = (b * b - c * c + d * d) / (2 * d), off = sqrt(b * b - along * along);
    double best = INFINITY;
    for (int side = -1; side <= 1; side += 2) {
        double bx = ax + (along * ex - side * off * ey) / d, by = ay + (along * ey + side * off * ex) / d;
        double ux = (bx - ax) / b, uy = (by - ay) / b;
        double qx = ax + px * ux - py * uy, qy = ay + px * uy + py * ux;
        if (hypot(qx - x, qy - y) < best)
            best = hypot(qx - x, qy - y), P[0] = qx, P[1] = qy;
    }
}

/* examples/coupler_synthesis.mech: its five points lie on the coupler
   curve of the linkage its header names, and fit finds that linkage with
   zero residual from the file's design. */
static void test_coupler_synthesis_example(void **s)
{
    (void)s;
    Fit f;
    fit_open_example(&f, "coupler_synthesis");
    assert_int_equal(f.data.nsamples, 5);
    assert_string_equal(f.data.names[0], "P.x");
    assert_string_equal(f.data.names[1], "P.y");
    for (int k = 0; k < 5; k++) {
        double P[2], *v = f.data.value + 2 * k;
        coupler_point(f.data.t[k], v[0], v[1], P);
        assert_near(v[0], P[0], 0, 1e-12);
        assert_near(v[1], P[1], 0, 1e-12);
    }
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    static const char *const names[9] = {"xa", "ya", "xd", "yd", "a", "b", "c", "px", "py"};
    static const double linkage[9] = {0, 0, 4, 0.5, 1.2, 3.5, 3, 1.5, 1};
    for (int j = 0; j < 9; j++) {
        assert_string_equal(f.mech->model->design_names[j], names[j]);
        assert_near(f.r.p[j], linkage[j], 0, 1e-9);
    }
    assert_true(f.r.cost < 1e-24);
    fit_close(&f);
}

/* The leg lengths |r + A(e) p_i - b_i| of examples/stewart_calibration.mech
   at t (its drivers' pose, e0 from the norm), for a design p of six
   (b_i, p_i) in the file's order. */
static void stewart_legs(const double *p, double t, double L[6])
{
    const double w = 2 * M_PI;
    double r[3] = {0.1 * sin(w * t), 0.08 * sin(2 * w * t), 1 + 0.1 * (1 - cos(w * t))};
    double e1 = 0.1 * sin(w * t), e2 = 0.08 * sin(2 * w * t + 1), e3 = 0.12 * cos(3 * w * t);
    double e0 = sqrt(1 - e1 * e1 - e2 * e2 - e3 * e3);
    double A[3][3] = {
        {e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)},
        {2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1)},
        {2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3}};
    for (int i = 0; i < 6; i++) {
        const double *b = p + 6 * i, *q = p + 6 * i + 3;
        double sq = 0;
        for (int k = 0; k < 3; k++) {
            double d = r[k] + A[k][0] * q[0] + A[k][1] * q[1] + A[k][2] * q[2] - b[k];
            sq += d * d;
        }
        L[i] = sqrt(sq);
    }
}

/* The 36 joint centres of the Stewart platform from 32 poses: exact leg
   lengths of a geometry up to 5 mm off nominal (computed here) give it
   back to 1e-9 from the nominal start; the example's own data are the
   lengths of the geometry fit finds there, to 1e-12. */
static void test_stewart_calibration(void **s)
{
    (void)s;
    Fit f;
    fit_open_example(&f, "stewart_calibration");
    const Model *m = f.mech->model;
    assert_int_equal(m->np, 36);
    assert_string_equal(m->design_names[0], "b1x");
    assert_string_equal(m->design_names[3], "p1x");
    assert_string_equal(m->design_names[35], "p6z");
    assert_int_equal(f.data.nsamples, 32);
    assert_int_equal(f.data.ncols, 6);
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    for (int k = 0; k < 32; k++) {
        double L[6];
        stewart_legs(f.r.p, f.data.t[k], L);
        for (int i = 0; i < 6; i++)
            assert_near(f.data.value[6 * k + i], L[i], 0, 1e-12);
    }
    for (int j = 0; j < 36; j++)
        assert_true(fabs(f.r.p[j] - m->design_p0[j]) <= 0.0055);
    double truth[36];
    for (int j = 0; j < 36; j++)
        truth[j] = m->design_p0[j] + 0.005 * sin(2.3 * j + 0.7);
    fit_close(&f);

    char *csv = xmalloc(32 * 200);
    int n = snprintf(csv, 32 * 200, "t,L1,L2,L3,L4,L5,L6\n");
    for (int k = 0; k < 32; k++) {
        double L[6];
        stewart_legs(truth, k / 32.0, L);
        n += snprintf(csv + n, 32 * 200 - (size_t)n, "%.17g", k / 32.0);
        for (int i = 0; i < 6; i++)
            n += snprintf(csv + n, 32 * 200 - (size_t)n, ",%.17g", L[i]);
        n += snprintf(csv + n, 32 * 200 - (size_t)n, "\n");
    }
    fit_open_mech(&f, load_example("stewart_calibration.mech"), write_csv("stewart.csv", csv));
    free(csv);
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    double worst = 0;
    for (int j = 0; j < 36; j++) {
        assert_near(f.r.p[j], truth[j], 0, 1e-9);
        worst = fmax(worst, fabs(f.r.p[j] - truth[j]));
    }
    print_message("stewart: 36 joint centres recovered to %.2g in %d iterations\n", worst,
                  f.r.iterations);
    assert_true(f.r.cost < 1e-24);
    fit_close(&f);
}

/* ---- the CSV ------------------------------------------------------------ */

/* A good file: comments, blank and CRLF lines, spaces around fields, an
   empty field (not measured), weights defaulting to 1. */
static void test_data_read(void **s)
{
    (void)s;
    Mech *mech = load_text(four_bar_text, "freudenstein.mech");
    FitData d;
    Diag diag;
    const char *path = write_csv("good.csv", "# measured\r\n"
                                             " t , rocker.phi , w(rocker.phi), crank.x\r\n"
                                             "\n"
                                             "0.5, 1.45, 4, \r\n"
                                             "  # a comment\n"
                                             "1, , , 0.3\n"
                                             "1, 1.5, , 0.2\n");
    if (!fit_data_read(path, mech->model, &d, &diag))
        fail_msg("%d:%d: %s", diag.line, diag.col, diag.message);
    assert_int_equal(d.nsamples, 3);
    assert_int_equal(d.ncols, 2);
    assert_int_equal(d.nmeasured, 4);
    assert_string_equal(d.names[0], "rocker.phi");
    assert_string_equal(d.names[1], "crank.x");
    assert_int_equal(d.var[0], 8);
    assert_int_equal(d.var[1], 0);
    static const int lines[3] = {4, 6, 7};
    static const double t[3] = {0.5, 1, 1};
    for (int k = 0; k < 3; k++) {
        assert_int_equal(d.line[k], lines[k]);
        assert_near(d.t[k], t[k], 0, 0);
    }
    assert_near(d.value[0], 1.45, 0, 0);
    assert_true(isnan(d.value[1]) && isnan(d.value[2]));
    assert_near(d.value[3], 0.3, 0, 0);
    assert_near(d.weight[0], 4, 0, 0);
    assert_near(d.weight[1], 1, 0, 0);
    assert_near(d.weight[4], 1, 0, 0);
    fit_data_free(&d);
    pipeline_free(mech);
}

static void test_data_errors(void **s)
{
    (void)s;
    Mech *mech = load_text(four_bar_text, "freudenstein.mech");
    static const struct {
        const char *csv;
        int line, col;
        const char *message;
    } cases[] = {
        {"crank.phi,rocker.phi\n0.5,1\n", 1, 1, "the header has no column t"},
        {"t,rocker.psi\n0.5,1\n", 1, 3, "'rocker.psi' is neither t, a coordinate, an output"},
        {"t,rocker.phi\n0.5,1.4x\n", 2, 5, "'1.4x' is not a finite number"},
        {"t,rocker.phi\n0.5,nan\n", 2, 5, "'nan' is not a finite number"},
        {"t,rocker.phi\n0.5,1e999\n", 2, 5, "'1e999' is not a finite number"},
        {"t,rocker.phi\n1,1.4\n0.5,1.5\n", 3, 1, "t = 0.5 comes after t = 1"},
        {"t,rocker.phi\n0.5,1.4,2\n", 2, 9, "3 fields where the header has 2"},
        {"t,rocker.phi,crank.x\n0.5,1.4\n", 2, 5, "2 fields where the header has 3"},
        {"t,rocker.phi,w(crank.phi)\n0.5,1.4,1\n", 1, 14, "the weight 'w(crank.phi)' has no measured column"},
        {"t,rocker.phi,w(rocker.phi)\n0.5,1.4,-1\n", 2, 9, "a weight must be positive, not -1"},
        {"t,rocker.phi,w(rocker.phi)\n0.5,1.4,0\n", 2, 9, "a weight must be positive, not 0"},
        {"t,rocker.phi,rocker.phi\n", 1, 14, "'rocker.phi' is measured in two columns"},
        {"t,rocker.phi,t\n", 1, 14, "a second column t"},
        {"t\n0.5\n", 1, 1, "the header names no measured coordinate or output"},
        {"t,rocker.phi\n,1.4\n", 2, 1, "the sample has no time t"},
        {"t,rocker.phi\n0.5,\n1,\n", 3, 3, "no measured value"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        FitData d;
        Diag diag;
        char name[32];
        snprintf(name, sizeof name, "bad%zu.csv", i);
        const char *path = write_csv(name, cases[i].csv);
        bool ok = fit_data_read(path, mech->model, &d, &diag);
        if (ok || !diag.has_pos || diag.line != cases[i].line || diag.col != cases[i].col
            || !strstr(diag.message, cases[i].message) || strcmp(diag.file, path) != 0)
            fail_msg("case %zu: got %s %d:%d \"%s\", expected %d:%d \"...%s...\"", i,
                     ok ? "success" : "error", diag.line, diag.col, diag.message, cases[i].line,
                     cases[i].col, cases[i].message);
        fit_data_free(&d);
    }
    FitData d;
    Diag diag;
    char missing[400];
    snprintf(missing, sizeof missing, "%s/none.csv", tmpdir);
    assert_false(fit_data_read(missing, mech->model, &d, &diag));
    assert_non_null(strstr(diag.message, "none.csv"));
    fit_data_free(&d);
    pipeline_free(mech);
}

/* ---- what fit_run refuses ----------------------------------------------- */

static void test_too_few_values(void **s)
{
    (void)s;
    Fit f;
    fit_open(&f, four_bar_text, "two.csv", "t,rocker.phi\n0.5,1.45\n1,1.51\n");
    assert_int_equal(fit_go(&f), FIT_BAD_INPUT);
    assert_non_null(strstr(f.r.message, "2 measured values cannot determine 3 parameters"));
    for (int j = 0; j < 3; j++)     /* the model keeps its design */
        assert_near(f.mech->model->dag.param_values[j], f.mech->model->design_p0[j], 0, 0);
    fit_close(&f);
    /* with one parameter varied, two values are enough */
    fit_open(&f, four_bar_text, "two.csv", "t,rocker.phi\n0.5,1.45\n1,1.51\n");
    f.vary[0] = f.vary[1] = false;
    assert_int_equal(fit_go(&f), FIT_OK);
    assert_int_equal(f.r.k, 1);
    assert_int_equal(f.r.index[0], 2);
    assert_near(f.r.p[0], 1.0, 0, 0);
    assert_near(f.r.p[1], 3.0, 0, 0);
    assert_true(f.r.p[2] != 2.5);
    fit_close(&f);
    fit_open(&f, four_bar_text, "two.csv", "t,rocker.phi\n0.5,1.45\n1,1.51\n");
    f.vary[0] = f.vary[1] = f.vary[2] = false;
    assert_int_equal(fit_go(&f), FIT_BAD_INPUT);
    assert_non_null(strstr(f.r.message, "no design parameter to estimate"));
    fit_close(&f);
}

/* crank.x = (a/2) cos(theta) depends on a alone: b cannot be told. */
static void test_unidentifiable(void **s)
{
    (void)s;
    Fit f;
    fit_open(&f, four_bar_text, "crank.csv", "t,crank.x\n0.5,0.5\n1,0.3\n1.5,0.05\n");
    f.vary[2] = false;
    assert_int_equal(fit_go(&f), FIT_BAD_INPUT);
    if (!strstr(f.r.message, "do not identify the combination +1 b"))
        fail_msg("message: %s", f.r.message);
    assert_null(strstr(f.r.message, " a "));
    assert_non_null(strstr(f.r.message, "down to 0)"));     /* not -0 */
    fit_close(&f);
    /* b and c alone: the data depend on neither */
    fit_open(&f, four_bar_text, "crank.csv", "t,crank.x\n0.5,0.5\n1,0.3\n1.5,0.05\n");
    f.vary[0] = false;
    assert_int_equal(fit_go(&f), FIT_BAD_INPUT);
    if (!strstr(f.r.message, "the measured values do not depend on b, c"))
        fail_msg("message: %s", f.r.message);
    fit_close(&f);
    /* a alone is identified by it: a = 2 x / cos(theta) */
    fit_open(&f, four_bar_text, "crank.csv", "t,crank.x\n0.5,0.5\n1,0.3\n1.5,0.05\n");
    f.vary[1] = f.vary[2] = false;
    assert_int_equal(fit_go(&f), FIT_OK);
    double want = 2 * (0.5 * cos(0.5) + 0.3 * cos(1.0) + 0.05 * cos(1.5))
                / (cos(0.5) * cos(0.5) + cos(1.0) * cos(1.0) + cos(1.5) * cos(1.5));
    assert_near(f.r.p[0], want, 0, 1e-12);   /* linear least squares in a */
    /* its cost and standard error: s^2 = cost / (n - 1), se^2 = s^2 / sum (cos/2)^2 */
    static const double th[3] = {0.5, 1.0, 1.5}, x[3] = {0.5, 0.3, 0.05};
    double cost = 0, sxx = 0;
    for (int i = 0; i < 3; i++) {
        double e = want / 2 * cos(th[i]) - x[i];
        cost += e * e;
        sxx += cos(th[i]) * cos(th[i]) / 4;
    }
    assert_near(f.r.cost, cost, 1e-9, 0);
    assert_near(f.r.std_error[0], sqrt(cost / 2 / sxx), 1e-9, 0);
    assert_near(f.r.corr[0], 1.0, 0, 1e-15);
    fit_close(&f);
}

/* The truth a = 1.2 lies outside [0.9, 1.1]: the fit stops on the bound;
   a start outside its bounds is refused. */
static void test_bounds(void **s)
{
    (void)s;
    double psi[3];
    Fit f;
    fit_open_freudenstein(&f, "bounded.csv", psi);
    f.lo[0] = 0.9, f.hi[0] = 1.1;
    f.lo[2] = 2.0, f.hi[2] = 2.6;
    if (fit_go(&f) != FIT_OK)
        fail_msg("fit: %s", f.r.message);
    assert_true(f.r.p[0] >= 0.9 && f.r.p[0] <= 1.1);
    assert_near(f.r.p[0], 1.1, 0, 1e-9);
    assert_true(f.r.p[2] >= 2.0 && f.r.p[2] <= 2.6);
    assert_true(f.r.cost < f.r.cost0);
    fit_close(&f);
    fit_open_freudenstein(&f, "bounded.csv", psi);
    f.lo[1] = 3.5, f.hi[1] = 4;
    assert_int_equal(fit_go(&f), FIT_BAD_INPUT);
    assert_non_null(strstr(f.r.message, "design parameter 'b' starts at 3, outside its bounds"));
    fit_close(&f);
}

/* A start where the linkage does not close (b = 0.1): FIT_FAILED with the
   time and the cause, and no estimates (solved false). */
static void test_start_cannot_assemble(void **s)
{
    (void)s;
    double psi[3];
    Fit f;
    fit_open_freudenstein(&f, "apart.csv", psi);
    model_set_design(f.mech->model, (double[]){1, 0.1, 2.5});
    assert_int_equal(fit_go(&f), FIT_FAILED);
    assert_false(f.r.solved);
    if (!strstr(f.r.message, "at the starting design: t = 0.5: could not assemble"))
        fail_msg("message: %s", f.r.message);
    assert_near(f.r.p[1], 0.1, 0, 0);
    fit_close(&f);
}

/* A file without design parameters has nothing to fit. */
static void test_no_design(void **s)
{
    (void)s;
    Fit f;
    fit_open(&f, "body a x = 1 y = 0 phi = 0\nrevolute O: ground(0, 0) a(-1, 0)\n"
                 "driver d: a.phi = t\n", "plain.csv", "t,a.x\n0,1\n");
    assert_int_equal(fit_go(&f), FIT_BAD_INPUT);
    assert_non_null(strstr(f.r.message, "no design parameters"));
    fit_close(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_freudenstein_three_positions),
        cmocka_unit_test(test_fit_coupler_point),
        cmocka_unit_test(test_freudenstein_example),
        cmocka_unit_test(test_coupler_synthesis_example),
        cmocka_unit_test(test_stewart_calibration),
        cmocka_unit_test(test_data_read),
        cmocka_unit_test(test_data_errors),
        cmocka_unit_test(test_too_few_values),
        cmocka_unit_test(test_unidentifiable),
        cmocka_unit_test(test_bounds),
        cmocka_unit_test(test_start_cannot_assemble),
        cmocka_unit_test(test_no_design),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
