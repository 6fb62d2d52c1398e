/* test_design.c - design parameters: parsed and refused where they may not go, emitted as p, evaluated alike by every engine, and the sensitivities against finite differences of whole runs.
 *
 * `design NAME = value` makes NAME the graph leaf p[j]: a derived `param`
 * of it works; a design value of design parameters, an axis that is zero
 * and a mass that is negative at the file's design are errors there
 * (FILE:LINE:COL). The generated C of such a file takes
 * `const PREFIX_real *p`, defines PREFIX_NP and PREFIX_phi_p; a file
 * without design parameters emits what it did before. jit, aot (when a C
 * compiler is there) and generic give the same Phi and Phi_p at a design
 * set by model_set_design after the engines were opened, and Phi_p is the
 * central difference of Phi in p. Finally kin/sens.c's sensitivities of
 * positions, velocities, accelerations and outputs at every state of a run
 * are the central differences of whole runs at p +- h, for a planar
 * four-bar with a point on a rod (designed lengths, pivots, rod length,
 * driver speed, a constraint's and an output's coefficient), a spatial
 * RSSR (designed crank offset, ground pivot and rod length) and the RSSR
 * with both revolute axes designed. Spatial translational, cylindrical
 * and universal joints with designed axes agree between engines. Masses,
 * inertias, centres of mass, gravity and spring constants of design
 * parameters: every engine's M and Q at a design set after opening equal
 * those of the file with the constants written in, and so does a sim;
 * check_mechanism passes on these files. Sensitivities with KLU of Phi_q
 * (the sparse path) are the dense LU's. The aot library cache goes to the run's (testcache.h).
 */
#include "testutil.h"
#include "testcache.h"
#include "testload.h"

#include "../generator/base/arena.h"
#include "../generator/emit/emit.h"
#include "../generator/engine/engine.h"
#include "../generator/jit/jit.h"
#include "../generator/kin/outputs.h"
#include "../generator/kin/run.h"
#include "../generator/kin/sens.h"
#include "../generator/dyn/sim.h"
#include "../generator/verify/check.h"

#include <stdlib.h>
#include <string.h>

static TestCache cache;

static int setup(void **state)
{
    (void)state;
    return testcache_setup(&cache, "design");
}

static int teardown(void **state)
{
    (void)state;
    return testcache_teardown(&cache);
}

/* A four-bar with designed link lengths (b through a derived param),
   ground pivots and driver speed w, and a point m on the line y = e x (a
   `constraint`) at a designed distance L from a coupler point; a coupler
   point and an output of e as outputs. */
static const char planar_text[] =
    "mechanism fbd\n"
    "design a  = 1\n"
    "design b  = 3\n"
    "design c  = 2.5\n"
    "design ax = 0.1\n"
    "design dx = 3\n"
    "design L  = 2.5\n"
    "design w  = 2*pi\n"
    "design e  = 0.1\n"
    "param h = b/2\n"
    "body crank   x = 0.5     y = 0       phi = 0\n"
    "body coupler x = 1.8438  y = 1.2402  phi = 0.9734\n"
    "body rocker  x = 2.8438  y = 1.2402  phi = 1.6961\n"
    "point m x = 3.9 y = 0.39\n"
    "revolute O2: ground(ax, 0)  crank(-a/2, 0)\n"
    "revolute A:  crank(a/2, 0)  coupler(-h, 0)\n"
    "revolute B:  coupler(h, 0)  rocker(c/2, 0)\n"
    "revolute O4: ground(dx, 0)  rocker(-c/2, 0)\n"
    "distance rod: coupler(0, 0.2) m length = L\n"
    "driver drive: crank.phi = w*t\n"
    "constraint slide: m.y - e*m.x = 0\n"
    "output P: coupler(0.5, 0.2)\n"
    "output r = rocker.phi - e*crank.phi\n";

/* examples/rssr.mech with its crank offset a, the rod's length L and the
   rocker's ground pivot gx designed; the rocker's angle and a point of it
   as outputs. */
static const char spatial_text[] =
    "mechanism rssr_design\n"
    "spatial\n"
    "design a  = 1\n"
    "design L  = sqrt(10)\n"
    "design gx = 2\n"
    "param c     = 3\n"
    "param omega = 2*pi\n"
    "body crank  x = 0  y = 0  z = 0\n"
    "body rocker x = 2  y = 0  z = 0  orient = axis(0, 1, 1, pi/2)\n"
    "revolute R1: ground(0, 0, 0)   crank(0, 0, 0)   axis(0, 0, 1)\n"
    "revolute R2: ground(gx, 0, 0)  rocker(0, 0, 0)  axis(0, 1, 1)\n"
    "distance C:  crank(a, 0, 0)    rocker(c, 0, 0)  length = L\n"
    "driver   D:  angle(R1) = omega*t\n"
    "output psi = angle(R2)\n"
    "output Q: rocker(c, 0, 0)\n";

/* The RSSR with its revolutes' axes designed: R1's tilted by ty (the
   crank's offset stays perpendicular to it), R2's (0, ay, az). */
static const char spatial_axis_text[] =
    "mechanism rssr_axes\n"
    "spatial\n"
    "design ty = 0.1\n"
    "design ay = 1\n"
    "design az = 1.2\n"
    "param c     = 3\n"
    "param omega = 2*pi\n"
    "body crank  x = 0  y = 0  z = 0\n"
    "body rocker x = 2  y = 0  z = 0  orient = axis(0, 1, 1, pi/2)\n"
    "revolute R1: ground(0, 0, 0)  crank(0, 0, 0)   axis(0, ty, 1)\n"
    "revolute R2: ground(2, 0, 0)  rocker(0, 0, 0)  axis(0, ay, az)\n"
    "distance C:  crank(1, 0, 0)   rocker(c, 0, 0)  length = sqrt(10)\n"
    "driver   D:  angle(R1) = omega*t\n"
    "output psi = angle(R2)\n"
    "output Q: rocker(c, 0, 0)\n";

/* A translational, a cylindrical and a universal joint (B's axis given)
   with designed axes, driven along the slide. */
static const char spatial_slider_text[] =
    "spatial\n"
    "design tx = 1\n"
    "design ty = 0.2\n"
    "design tz = 0.1\n"
    "design ux = 0.3\n"
    "body s x = 0 y = 0 z = 0\n"
    "body w x = 0 y = 0 z = 0\n"
    "translational T: ground(0, 0, 0) s(0, 0, 0) axis(tx, ty, tz)\n"
    "cylindrical C: s(0, 0, 0) w(0, 0, 0) axis(ux, 1, 0)\n"
    "universal U: ground(0, 0, 0) w(0, 0, 0) axis(ux, 0, 1) axis(0, 1, ux)\n"
    "driver D: slide(T) = t\n";

static bool open_kind(Engine *e, EngineKind kind, const Mech *mech)
{
    return testcache_open_engine(&cache, e, kind, mech);
}

static int row_index(const Model *m, const char *name)
{
    for (int r = 0; r < m->nr; r++)
        if (strcmp(m->rows[r].name, name) == 0)
            return r;
    fail_msg("no row %s", name);
    return -1;
}

/* ---- parsing ------------------------------------------------------------ */

/* design declares p[0] = 2; h = L/2 is a folded param of it: the pin's row
   moves by dh = 1/2 per unit of L; the initial x = 2h is taken at L = 2. */
static void test_parse_design_and_derived_param(void **s)
{
    (void)s;
    Mech *mech = load_text("design L = 2\n"
                           "param h = L/2\n"
                           "body a x = 2*h y = 0 phi = 0\n"
                           "revolute O: ground(0, 0) a(-h, 0)\n"
                           "driver d: a.phi = t\n", "derived.mech");
    Model *m = mech->model;
    assert_int_equal(m->np, 1);
    assert_string_equal(m->design_names[0], "L");
    assert_near(m->design_p0[0], 2.0, 0, 0);
    assert_near(m->dag.param_values[0], 2.0, 0, 0);
    assert_near(m->q0[0], 2.0, 0, 0);   /* initial values at the file's design */
    Engine e;
    assert_true(open_kind(&e, ENGINE_JIT, mech));
    double q[3] = {1, 0, 0}, phi[3], phi3[3], phi_p[3];
    int ox = row_index(m, "O.x");
    engine_phi(&e, q, 0.0, phi);
    engine_phi_p(&e, q, 0.0, phi_p);
    assert_near(phi[ox], 0.0, 0, 1e-15);    /* a(-1, 0) is at the origin */
    assert_near(fabs(phi_p[ox]), 0.5, 0, 1e-15);
    model_set_design(m, (double[]){3.0});
    engine_phi(&e, q, 0.0, phi3);
    assert_near(phi3[ox] - phi[ox], phi_p[ox], 0, 1e-15);
    assert_near(m->design_p0[0], 2.0, 0, 0);    /* the file's design stays */
    model_set_design(m, NULL);
    assert_near(m->dag.param_values[0], 2.0, 0, 0);
    engine_close(&e);
    pipeline_free(mech);
}

/* text does not load: FILE:LINE:COL and the message naming the parameter. */
static void expect_refused(const char *text, const char *where, const char *what)
{
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text(text, "bad.mech", &limits, &diag);
    if (mech)
        fail_msg("%s: loaded", what);
    char out[2048] = "";
    FILE *f = fmemopen(out, sizeof out - 1, "w");
    diag_print(&diag, f);
    fclose(f);
    if (strncmp(out, where, strlen(where)) != 0 || !strstr(out, what))
        fail_msg("expected \"%s ...%s...\", got:\n%s", where, what, out);
}

static void test_parse_refuses_design_in_constants(void **s)
{
    (void)s;
    expect_refused("spatial\ndesign L = 0\nbody a x = 0 y = 0 z = 0\n"
                   "revolute O: ground(0, 0, 0) a(0, 0, 0) axis(L, 0, 2*L)\n",
                   "bad.mech:4:40: error: ", "the axis of revolute 'O' is zero at the file's design");
    expect_refused("design k = 2\nbody rod x = 0.5 y = 0 phi = 0\n"
                   "revolute O: ground(0, 0) rod(-0.5, 0)\nmass rod m = 1 - k J = 1\n",
                   "bad.mech:4:10: error: ", "the mass m of mass 'rod' is negative (-1) at the file's design");
    expect_refused("design m = 2\ndesign n = m\nbody a x = 0 y = 0 phi = 0\n", "bad.mech:2:12: error: ",
                   "the design value cannot depend on design parameter 'm'");
}

/* ---- emission ----------------------------------------------------------- */

static void emit(const Mech *mech, const EmitOptions *opt, EmitResult *res)
{
    Diag diag;
    diag_init(&diag, "test", "", 0);
    if (!emit_mechanism(&mech->kin, opt, res, &diag))
        fail_msg("emit_mechanism: %s", diag.message);
    /* a success records no error (it once did: an aot compiler's failure
       was then reported as "more than N operations") */
    assert_false(diag.failed);
}

/* gen's file: p after q and t in phi, PREFIX_NP, p0, names and phi_p; the
   engines' (with the twins) compiles under libtcc and computes the
   generic engine's Phi at the design it is bound to. */
static void test_emit_design_file(void **s)
{
    (void)s;
    Mech *mech = load_text(planar_text, "fbd.mech");
    EmitOptions opt = emit_default_options();
    EmitResult res;
    emit(mech, &opt, &res);
    const char *sig = strstr(res.c_text, "void fbd_phi(");
    assert_non_null(sig);
    const char *eol = strchr(sig, '\n'), *arg = strstr(sig, "const fbd_real *p");
    assert_true(arg && arg < eol);
    assert_non_null(strstr(res.c_text, "#define FBD_NP   8"));
    assert_non_null(strstr(res.c_text, "void fbd_phi_p(const fbd_real *q, fbd_real t, "
                                       "const fbd_real *p, fbd_real *phi_p)"));
    assert_non_null(strstr(res.c_text, "fbd_p0[FBD_NP]"));
    assert_non_null(strstr(res.c_text, "void fbd_phi_p_nz(const fbd_real *q, fbd_real t, "
                                       "const fbd_real *p, fbd_real *vals)"));
    assert_non_null(strstr(res.c_text, "const int fbd_phi_p_row[FBD_PNNZ] = {"));
    assert_non_null(strstr(res.h_text, "#define FBD_PNNZ 17"));
    assert_non_null(strstr(res.c_text, "fbd_design_names[FBD_NP]"));
    assert_null(strstr(res.c_text, "design_bind"));    /* the engines' twins only */
    emit_result_free(&res);

    /* libtcc has no system headers; its functions are bound through the
       context-free twins, which read p from design_bind's pointer */
    opt.declare_math = true, opt.direct_jac = true, opt.host_design = true;
    emit(mech, &opt, &res);
    assert_non_null(strstr(res.c_text, "void fbd_design_bind(const fbd_real *p)"));
    Diag diag;
    diag_init(&diag, "test", "", 0);
    Jit *jit = jit_compile(res.c_text, res.prefix, &diag);
    if (!jit)
        fail_msg("jit_compile: %s", diag.message);
    const Kernels *k = jit_kernels(jit);
    assert_non_null(k->design_bind);
    assert_non_null(k->phi_p_nz);
    const DesignKin *dk = &mech->kin.design;
    for (int i = 0; i < dk->p_nnz; i++) {
        assert_int_equal(k->phi_p_row[i], dk->p_nz[i].row);
        assert_int_equal(k->phi_p_col[i], dk->p_nz[i].col);
    }
    /* at a design of its own, the unit's phi is the generic engine's */
    const Model *m = mech->model;
    assert_int_equal(m->np, 8);
    assert_int_equal(m->nq, 11);
    double p[8], q[11], t = 0.3, phi[11], want[11];
    for (int j = 0; j < m->np; j++)
        p[j] = m->design_p0[j] * 1.05;
    for (int i = 0; i < m->nq; i++)
        q[i] = m->q0[i] + 0.01 * i;
    k->design_bind(p);
    k->phi(q, t, phi);
    Engine e;
    assert_true(open_kind(&e, ENGINE_GENERIC, mech));
    model_set_design(mech->model, p);
    engine_phi(&e, q, t, want);
    for (int r = 0; r < m->nh; r++)
        assert_near(phi[r], want[r], 0, 1e-12);
    engine_close(&e);
    jit_free(jit);
    emit_result_free(&res);
    pipeline_free(mech);
}

/* A file without design parameters: no p anywhere, and host_design changes
   nothing. */
static void test_emit_file_without_design(void **s)
{
    (void)s;
    Mech *mech = load_example("four_bar.mech");
    EmitOptions opt = emit_default_options();
    EmitResult plain, host;
    emit(mech, &opt, &plain);
    opt.host_design = true;
    emit(mech, &opt, &host);
    assert_null(strstr(plain.c_text, "_design"));
    assert_null(strstr(plain.c_text, "_NP"));
    assert_null(strstr(plain.c_text, "_phi_p"));
    assert_null(strstr(plain.c_text, "_real *p,"));
    assert_string_equal(plain.c_text, host.c_text);
    assert_string_equal(plain.h_text, host.h_text);
    emit_result_free(&plain);
    emit_result_free(&host);
    pipeline_free(mech);
}

/* ---- engines ------------------------------------------------------------ */

/* Engine e's phi_p_nz at (q, t) against the dense dense (nh x np): the
   same values on the pattern, which is row-major, strictly increasing and
   holds every nonzero of dense. */
static void check_phi_p_nz(const Engine *e, const Mech *mech, const double *q, double t,
                           const double *dense)
{
    const Model *m = mech->model;
    const DesignKin *dk = &mech->kin.design;
    double *nz = xcalloc((size_t)dk->p_nnz + 1, sizeof *nz);
    double *const out[DESIGN_Y_COUNT] = {nz};
    engine_design(e, DESIGN_PHI_P_NZ, q, NULL, t, out);
    size_t np = (size_t)m->np, at = 0, nonzero = 0;
    for (int k = 0; k < dk->p_nnz; k++) {
        size_t i = (size_t)dk->p_nz[k].row * np + (size_t)dk->p_nz[k].col;
        assert_true(k == 0 || i > at);
        at = i;
        assert_near(nz[k], dense[i], 0, 1e-12);
    }
    for (size_t i = 0; i < (size_t)m->nh * np; i++)
        nonzero += dense[i] != 0.0;
    assert_true(nonzero <= (size_t)dk->p_nnz);
    assert_true(nonzero > 0);
    free(nz);
}

/* Phi and Phi_p of every engine at a design set after they were opened,
   the same to 1e-12; Phi_p the central difference of Phi (1e-7); the
   nonzeros' phi_p_nz Phi_p's. */
static void check_engines(const char *text, const char *name, const double *dp)
{
    Mech *mech = load_text(text, name);
    Model *m = mech->model;
    int nh = m->nh, np = m->np, nq = m->nq;
    Engine e[ENGINE_KIND_COUNT];
    bool open[ENGINE_KIND_COUNT];
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        open[k] = open_kind(&e[k], (EngineKind)k, mech);
    double *p = xcalloc((size_t)np, sizeof *p), *q = xcalloc((size_t)nq, sizeof *q);
    for (int j = 0; j < np; j++)
        p[j] = m->design_p0[j] + dp[j];
    for (int i = 0; i < nq; i++)
        q[i] = m->q0[i] + 0.05 * (i % 4) - 0.07;
    double t = 0.137;
    model_set_design(m, p);
    size_t nhp = (size_t)nh * (size_t)np;
    double *phi = xcalloc((size_t)nh, sizeof *phi), *phi0 = xcalloc((size_t)nh, sizeof *phi0);
    double *phi_p = xcalloc(nhp, sizeof *phi_p), *ref_p = xcalloc(nhp, sizeof *ref_p);
    double *plus = xcalloc((size_t)nh, sizeof *plus), *minus = xcalloc((size_t)nh, sizeof *minus);
    engine_phi(&e[ENGINE_JIT], q, t, phi0);
    engine_phi_p(&e[ENGINE_JIT], q, t, ref_p);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        if (!open[k])
            continue;
        engine_phi(&e[k], q, t, phi);
        engine_phi_p(&e[k], q, t, phi_p);
        for (int r = 0; r < nh; r++)
            assert_near(phi[r], phi0[r], 0, 1e-12);
        for (size_t i = 0; i < nhp; i++)
            assert_near(phi_p[i], ref_p[i], 0, 1e-12);
        check_phi_p_nz(&e[k], mech, q, t, ref_p);
    }
    for (int j = 0; j < np; j++) {
        double h = 1e-5 * fmax(1.0, fabs(p[j])), pj = p[j];
        m->dag.param_values[j] = pj + h;
        engine_phi(&e[ENGINE_GENERIC], q, t, plus);
        m->dag.param_values[j] = pj - h;
        engine_phi(&e[ENGINE_GENERIC], q, t, minus);
        m->dag.param_values[j] = pj;
        for (int r = 0; r < nh; r++)
            assert_near((plus[r] - minus[r]) / (2 * h), ref_p[(size_t)r * (size_t)np + (size_t)j],
                        0, 1e-7);
    }
    /* the nominal design gives other values: the engines saw p */
    model_set_design(m, NULL);
    engine_phi(&e[ENGINE_JIT], q, t, phi);
    double moved = 0;
    for (int r = 0; r < nh; r++)
        moved = fmax(moved, fabs(phi[r] - phi0[r]));
    assert_true(moved > 1e-3);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (open[k])
            engine_close(&e[k]);
    free(p), free(q), free(phi), free(phi0), free(phi_p), free(ref_p), free(plus), free(minus);
    pipeline_free(mech);
}

static void test_engines_agree_planar(void **s)
{
    (void)s;
    check_engines(planar_text, "fbd.mech", (double[]){0.07, -0.11, 0.05, 0.02, -0.08, 0.13, 0.3, -0.04});
}

static void test_engines_agree_spatial(void **s)
{
    (void)s;
    check_engines(spatial_text, "rssr_design.mech", (double[]){0.1, -0.2, 0.15});
}

static void test_engines_agree_spatial_axes(void **s)
{
    (void)s;
    check_engines(spatial_axis_text, "rssr_axes.mech", (double[]){0.05, -0.2, 0.15});
    check_engines(spatial_slider_text, "slider_axes.mech", (double[]){0.1, -0.05, 0.2, 0.1});
}

/* ---- sensitivities against whole runs ----------------------------------- */

enum { STEPS = 24 };

/* Every state of a run: per state q, y, qd, yd, qdd, ydd (y the outputs),
   and with sens the sensitivity columns (sens_columns' order). */
typedef struct Motion {
    const Model *m;
    OutputEval oe;
    Sens *sens;
    int n, nv, ncol;
    double *x, *cols, *t;
} Motion;

static void on_state(void *ctx, double t, const double *q, const double *qd, const double *qdd)
{
    Motion *mo = ctx;
    int nq = mo->m->nq, nv = mo->nv;
    assert_true(mo->n <= STEPS);
    mo->t[mo->n] = t;
    double *x = mo->x + (size_t)mo->n * 3 * (size_t)nv;
    memcpy(x, q, (size_t)nq * sizeof *x);
    memcpy(x + nv, qd, (size_t)nq * sizeof *x);
    memcpy(x + 2 * nv, qdd, (size_t)nq * sizeof *x);
    outputs_eval(&mo->oe, q, qd, qdd, t, x + nq, x + nv + nq, x + 2 * nv + nq);
    if (mo->sens) {
        assert_int_equal(sens_eval(mo->sens, t, q, qd, qdd), MECHRT_OK);
        sens_columns(mo->sens, mo->cols + (size_t)mo->n * (size_t)mo->ncol);
    }
    mo->n++;
}

/* The run over one period at the model's design, Newton to 1e-12, on the
   dense path; on the sparse one (KLU, the sensitivities' too) with sparse;
   lending its LU to lend when that is not NULL. */
static void run_motion_lending(Mech *mech, const Engine *e, Sens *sens, Motion *mo, bool sparse,
                               RunLu *lend)
{
    const Model *m = mech->model;
    memset(mo, 0, sizeof *mo);
    mo->m = m;
    mo->sens = sens;
    mo->nv = m->nq + m->nout;
    mo->ncol = sens ? sens_column_count(sens) : 0;
    mo->x = xcalloc((size_t)(STEPS + 1) * 3 * (size_t)mo->nv, sizeof *mo->x);
    mo->cols = xcalloc((size_t)(STEPS + 1) * (size_t)mo->ncol + 1, sizeof *mo->cols);
    mo->t = xcalloc(STEPS + 1, sizeof *mo->t);
    outputs_init(&mo->oe, m);
    RunOptions o = run_default_options();
    o.steps = STEPS;
    o.mechrt.tol_phi = o.mechrt.tol_dq = 1e-12;
    o.linear = sparse ? ANALYSIS_LINEAR_SPARSE : ANALYSIS_LINEAR_DENSE;
    if (sparse && sens)
        assert_true(sens_use_sparse(sens, engine_jac_nz(e)));
    o.lend_lu = lend;
    RunResult res;
    if (run_analysis(m, engine_kernels(e), engine_jac_nz(e), &o, on_state, mo, &res) != ANALYSIS_OK)
        fail_msg("run: %s", res.message);
    assert_int_equal(mo->n, STEPS + 1);
    outputs_free(&mo->oe);
}

static void run_motion_on(Mech *mech, const Engine *e, Sens *sens, Motion *mo, bool sparse)
{
    run_motion_lending(mech, e, sens, mo, sparse, NULL);
}

static void run_motion(Mech *mech, const Engine *e, Sens *sens, Motion *mo)
{
    run_motion_on(mech, e, sens, mo, false);
}

static void motion_free(Motion *mo)
{
    free(mo->x), free(mo->cols), free(mo->t);
}

/* sens's columns against (run(p + h e_j) - run(p - h e_j)) / 2h at every
   state, for every design parameter j: positions, velocities,
   accelerations and outputs. */
static void check_sensitivities(const char *text, const char *name)
{
    Mech *mech = load_text(text, name);
    Model *m = mech->model;
    Engine e;
    assert_true(open_kind(&e, ENGINE_JIT, mech));
    Sens sens;
    char why[256];
    if (!sens_init(&sens, m, &mech->kin, &e, why, sizeof why))
        fail_msg("sens_init: %s", why);
    Motion base, plus, minus;
    run_motion(mech, &e, &sens, &base);
    int np = m->np, nv = base.nv;
    assert_int_equal(base.ncol, 3 * nv * np);
    double *p = xcalloc((size_t)np, sizeof *p), worst = 0;
    memcpy(p, m->design_p0, (size_t)np * sizeof *p);
    for (int j = 0; j < np; j++) {
        double h = 1e-6 * fmax(1.0, fabs(p[j]));
        p[j] += h;
        model_set_design(m, p);
        run_motion(mech, &e, NULL, &plus);
        p[j] -= 2 * h;
        model_set_design(m, p);
        run_motion(mech, &e, NULL, &minus);
        p[j] += h;
        model_set_design(m, p);
        for (int k = 0; k <= STEPS; k++)
            for (int i = 0; i < 3 * nv; i++) {
                size_t at = (size_t)k * 3 * (size_t)nv + (size_t)i;
                double fd = (plus.x[at] - minus.x[at]) / (2 * h);
                double got = base.cols[(size_t)k * (size_t)base.ncol + (size_t)i * (size_t)np
                                       + (size_t)j];
                double err = fabs(got - fd) / (1.0 + fabs(fd));
                worst = fmax(worst, err);
                if (!(err <= 1e-6))
                    fail_msg("%s: state %d, value %d, d/d(%s): sensitivity %.12g, "
                             "finite difference %.12g", name, k, i, m->design_names[j], got, fd);
            }
        motion_free(&plus), motion_free(&minus);
    }
    print_message("%s: %d states x %d values x %d parameters, worst relative error %.2g\n", name,
                  STEPS + 1, 3 * nv, np, worst);
    motion_free(&base);
    free(p);
    sens_free(&sens);
    engine_close(&e);
    pipeline_free(mech);
}

static void test_sensitivities_planar(void **s)
{
    (void)s;
    check_sensitivities(planar_text, "fbd.mech");
}

static void test_sensitivities_spatial(void **s)
{
    (void)s;
    check_sensitivities(spatial_text, "rssr_design.mech");
}

static void test_sensitivities_spatial_axes(void **s)
{
    (void)s;
    check_sensitivities(spatial_axis_text, "rssr_axes.mech");
}

/* The sensitivities with KLU of Phi_q are the dense LU's: at the states
   of a dense run to 1e-13 relative, every column; along a run on the
   sparse path (whose states differ from the dense run's by its Newton
   iterations, 1e-12) to 1e-10. */
static void check_sparse_sensitivities(const char *text, const char *name)
{
    Mech *mech = load_text(text, name);
    Model *m = mech->model;
    Engine e;
    assert_true(open_kind(&e, ENGINE_JIT, mech));
    assert_non_null(engine_jac_nz(&e));
    Sens dense, sparse;
    char why[256];
    assert_true(sens_init(&dense, m, &mech->kin, &e, why, sizeof why));
    assert_true(sens_init(&sparse, m, &mech->kin, &e, why, sizeof why));
    Motion a, b;
    run_motion_on(mech, &e, &dense, &a, false);
    run_motion_on(mech, &e, &sparse, &b, true);
    assert_non_null(sparse.klu);
    assert_null(dense.klu);
    int ncol = a.ncol, nv = a.nv;
    double *cols = xcalloc((size_t)ncol, sizeof *cols), same = 0, along = 0;
    for (int k = 0; k <= STEPS; k++) {
        const double *x = a.x + (size_t)k * 3 * (size_t)nv, *ca = a.cols + (size_t)k * (size_t)ncol;
        assert_int_equal(sens_eval(&sparse, a.t[k], x, x + nv, x + 2 * nv), MECHRT_OK);
        sens_columns(&sparse, cols);
        for (int i = 0; i < ncol; i++) {
            same = fmax(same, fabs(cols[i] - ca[i]) / (1.0 + fabs(ca[i])));
            along = fmax(along, fabs(b.cols[(size_t)k * (size_t)ncol + (size_t)i] - ca[i])
                                / (1.0 + fabs(ca[i])));
        }
    }
    print_message("%s: KLU against dense LU sensitivities: %.2g at the same states, %.2g along "
                  "a sparse run\n", name, same, along);
    assert_true(same <= 1e-12);
    assert_true(along <= 1e-10);
    free(cols);
    motion_free(&a), motion_free(&b);
    sens_free(&dense), sens_free(&sparse);
    engine_close(&e);
    pipeline_free(mech);
}

static void test_sensitivities_sparse(void **s)
{
    (void)s;
    check_sparse_sensitivities(planar_text, "fbd.mech");
    check_sparse_sensitivities(spatial_axis_text, "rssr_axes.mech");
}

/* With the run's LU lent (RunOptions.lend_lu, as run --sens does) the
   sensitivities solve with it at every state, and they are those of
   sens's own LU bit for bit: the pattern LU replays lu.c's. */
static void check_borrowed_lu(const char *text, const char *name)
{
    Mech *mech = load_text(text, name);
    Model *m = mech->model;
    Engine e;
    assert_true(open_kind(&e, ENGINE_JIT, mech));
    Sens own, borrowing;
    char why[256];
    assert_true(sens_init(&own, m, &mech->kin, &e, why, sizeof why));
    assert_true(sens_init(&borrowing, m, &mech->kin, &e, why, sizeof why));
    RunLu lent = {0};
    sens_borrow_lu(&borrowing, &lent);
    Motion a, b;
    run_motion(mech, &e, &own, &a);
    run_motion_lending(mech, &e, &borrowing, &b, false, &lent);
    assert_int_equal(own.borrowed_count, 0);
    assert_int_equal(borrowing.borrowed_count, STEPS + 1);
    assert_null(lent.lup);      /* the run took it back */
    assert_memory_equal(a.x, b.x, (size_t)(STEPS + 1) * 3 * (size_t)a.nv * sizeof *a.x);
    for (size_t i = 0; i < (size_t)(STEPS + 1) * (size_t)a.ncol; i++)
        if (!(a.cols[i] == b.cols[i]))
            fail_msg("%s: column value %zu: borrowed %.17g, own %.17g", name, i, b.cols[i],
                     a.cols[i]);
    motion_free(&a), motion_free(&b);
    sens_free(&own), sens_free(&borrowing);
    engine_close(&e);
    pipeline_free(mech);
}

static void test_sensitivities_borrowed_lu(void **s)
{
    (void)s;
    check_borrowed_lu(planar_text, "fbd.mech");
    check_borrowed_lu(spatial_text, "rssr_design.mech");
}

/* The CSV names: d(NAME)/d(P), d(d(NAME))/d(P), d(dd(NAME))/d(P), in
   sens_columns' order. */
static void test_sensitivity_column_names(void **s)
{
    (void)s;
    Mech *mech = load_text(planar_text, "fbd.mech");
    Model *m = mech->model;
    Engine e;
    assert_true(open_kind(&e, ENGINE_GENERIC, mech));
    Sens sens;
    char why[256];
    assert_true(sens_init(&sens, m, &mech->kin, &e, why, sizeof why));
    int nv = m->nq + m->nout, np = m->np;
    const char **names = xcalloc((size_t)nv, sizeof *names);
    for (int i = 0; i < m->nq; i++)
        names[i] = m->coord_names[i];
    for (int k = 0; k < m->nout; k++)
        names[m->nq + k] = m->outputs[k].name;
    assert_int_equal(sens_column_count(&sens), 3 * nv * np);
    static const struct {
        int column;
        const char *name;
    } want[] = {{0, "d(crank.x)/d(a)"}, {7, "d(crank.x)/d(e)"}, {8, "d(crank.y)/d(a)"},
                {11 * 8 + 1, "d(P.x)/d(b)"}, {14 * 8 - 1, "d(r)/d(e)"},
                {14 * 8 + 2, "d(d(crank.x))/d(c)"}, {2 * 14 * 8 + 13 * 8 + 4, "d(dd(r))/d(dx)"}};
    for (size_t i = 0; i < sizeof want / sizeof *want; i++) {
        char *got = sens_column_name(&sens, names, want[i].column);
        assert_string_equal(got, want[i].name);
        free(got);
    }
    free(names);
    sens_free(&sens);
    engine_close(&e);
    pipeline_free(mech);
}

/* ---- dynamics of designed masses ---------------------------------------- */

/* A file of design parameters (keyword "design") or of the same values
   as constants ("param"): first (`spatial` or nothing), the n
   declarations, then body. */
typedef struct DynCase {
    const char *first;
    int n;
    const char *names[6];
    const char *body;
} DynCase;

static char *dyn_text(const DynCase *c, const char *kw, const double *v)
{
    size_t size = strlen(c->body) + 1024;
    char *text = xmalloc(size);
    int at = snprintf(text, size, "%s", c->first);
    for (int i = 0; i < c->n; i++)
        at += snprintf(text + at, size - (size_t)at, "%s %s = %.17g\n", kw, c->names[i], v[i]);
    snprintf(text + at, size - (size_t)at, "%s", c->body);
    return text;
}

/* A double pendulum with a particle on its tip, a spring and a rotational
   spring: its masses, a centre of mass, gravity, the spring's stiffness,
   damping and free length and the rotational spring's stiffness designed. */
static const DynCase pendulum_case = {
    "", 6, {"m1", "m2", "cx", "g", "k", "L0"},
    "param L = 1\n"
    "body rod1 x = L/2      y = 0  phi = 0.3\n"
    "body rod2 x = L + L/2  y = 0  phi = 0.5\n"
    "point tip x = 2 y = 0\n"
    "revolute O: ground(0, 0)  rod1(-L/2, 0)\n"
    "revolute A: rod1(L/2, 0)  rod2(-L/2, 0)\n"
    "revolute B: rod2(L/2, 0)  tip\n"
    "gravity (0, -g)\n"
    "mass rod1 m = m1 J = m1*L^2/12 com(cx, 0)\n"
    "mass rod2 m = m2 J = m2*L^2/12\n"
    "mass tip m = m1/4\n"
    "spring s: ground(0.5, 0.5) rod2(0.2, 0) k = k c = 0.1*k length = L0\n"
    "rspring r: rod1 rod2 k = k/10 angle = 0.1\n",
};

/* examples/heavy_top.mech with its mass, moments of inertia, a product of
   inertia, its centre of mass off the body's origin and gravity designed. */
static const DynCase top_case = {
    "spatial\n", 5, {"m", "J1", "J3", "g", "cz"},
    "param l  = 0.1\n"
    "param th = 0.3\n"
    "body top x = 0  y = -l*sin(th)  z = l*cos(th)  orient = axis(1, 0, 0, th)\n"
    "spherical O: ground(0, 0, 0)  top(0, 0, -l)\n"
    "mass top m = m  J = (J1, J1, J3)  Jxy = 0.1*J1  com(0, 0, cz)\n"
    "gravity (0, 0, -g)\n",
};

typedef struct Last {
    int nq;
    double q[64], qd[64];
} Last;

static void on_sim(void *ctx, double t, const double *q, const double *qd, const double *qdd,
                   const double *lambda)
{
    (void)t, (void)qdd, (void)lambda;
    Last *l = ctx;
    memcpy(l->q, q, (size_t)l->nq * sizeof *q);
    memcpy(l->qd, qd, (size_t)l->nq * sizeof *qd);
}

/* The last state of a sim of m over [0, 0.5]. */
static void sim_last(const Model *m, const Engine *e, Last *last)
{
    SimOptions o = sim_default_options();
    o.t1 = 0.5;
    o.steps = 5;
    o.rtol = o.atol = 1e-11;
    SimResult res;
    last->nq = m->nq;
    assert_true(m->nq <= 64);
    if (sim_run(m, engine_kernels(e), NULL, NULL, &o, on_sim, last, &res) != ANALYSIS_OK)
        fail_msg("sim: %s", res.message);
}

/* The file of design parameters at design `other` (set after the engines
   were opened) against the file with `other` written in as constants:
   every engine's M and Q at a state, to 1e-12, and the state a sim ends
   in, to 1e-9. */
static void check_designed_dynamics(const DynCase *c, const double *nominal, const double *other,
                                    const char *name)
{
    char *dtext = dyn_text(c, "design", nominal), *ctext = dyn_text(c, "param", other);
    Mech *dm = load_text(dtext, name), *cm = load_text(ctext, name);
    Model *m = dm->model;
    int nq = m->nq;
    assert_int_equal(cm->model->nq, nq);
    Engine e[ENGINE_KIND_COUNT], ref;
    bool open[ENGINE_KIND_COUNT];
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        open[k] = open_kind(&e[k], (EngineKind)k, dm);
    assert_true(open_kind(&ref, ENGINE_JIT, cm));
    model_set_design(m, other);
    size_t nn = (size_t)nq * (size_t)nq;
    double *q = xcalloc((size_t)nq, sizeof *q), *qd = xcalloc((size_t)nq, sizeof *qd);
    double *M = xcalloc(nn, sizeof *M), *M0 = xcalloc(nn, sizeof *M0);
    double *Q = xcalloc((size_t)nq, sizeof *Q), *Q0 = xcalloc((size_t)nq, sizeof *Q0);
    for (int i = 0; i < nq; i++) {
        q[i] = cm->model->q0[i] + 0.03 * (i % 3) - 0.02;
        qd[i] = 0.4 - 0.1 * (i % 5);
    }
    const MechrtKernels *kr = engine_kernels(&ref);
    kr->mass(kr->ctx, q, M0);
    kr->force(kr->ctx, q, qd, 0.3, Q0);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        if (!open[k])
            continue;
        const MechrtKernels *kk = engine_kernels(&e[k]);
        kk->mass(kk->ctx, q, M);
        kk->force(kk->ctx, q, qd, 0.3, Q);
        for (size_t i = 0; i < nn; i++)
            assert_near(M[i], M0[i], 0, 1e-12 * (1 + fabs(M0[i])));
        for (int i = 0; i < nq; i++)
            assert_near(Q[i], Q0[i], 0, 1e-12 * (1 + fabs(Q0[i])));
    }
    Last a, b;
    sim_last(m, &e[ENGINE_JIT], &a);
    sim_last(cm->model, &ref, &b);
    for (int i = 0; i < nq; i++) {
        assert_near(a.q[i], b.q[i], 0, 1e-9);
        assert_near(a.qd[i], b.qd[i], 0, 1e-9);
    }
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (open[k])
            engine_close(&e[k]);
    engine_close(&ref);
    free(q), free(qd), free(M), free(M0), free(Q), free(Q0);
    pipeline_free(dm), pipeline_free(cm);
    free(dtext), free(ctext);
}

/* mechc check of text: ok, with every quantity compared between jit and
   generic (and M, Q with masses), Phi_p against finite differences. */
static void expect_check_ok(const char *text, const char *name, bool masses)
{
    Mech *mech = load_text(text, name);
    CheckOptions opt = check_default_options();
    opt.samples = 4;
    opt.use_aot = false;
    CheckReport rep;
    Diag diag;
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    for (int w = 0; w < CHECK_WHAT_COUNT; w++)
        if (rep.items[w].checked && !(rep.items[w].error <= rep.items[w].tol))
            fail_msg("%s: check %s: %g over %g", name, rep.items[w].what, rep.items[w].error,
                     rep.items[w].tol);
    assert_true(rep.ok);
    assert_true(rep.items[CHECK_PHI_P_FD].checked);
    for (int w = CHECK_PAIR_FIRST; w < CHECK_DYN_FIRST + (masses ? 2 : 0); w++)
        if (strstr(rep.items[w].what, "jit/generic"))
            assert_true(rep.items[w].checked);
    pipeline_free(mech);
}

static void test_check_designed(void **s)
{
    (void)s;
    expect_check_ok(spatial_axis_text, "rssr_axes.mech", false);
    expect_check_ok(spatial_slider_text, "slider_axes.mech", false);
    char *pendulum = dyn_text(&pendulum_case, "design", (double[]){1, 1.5, 0.1, 9.81, 20, 0.3});
    char *top = dyn_text(&top_case, "design", (double[]){1, 0.002, 0.004, 9.81, 0.02});
    expect_check_ok(pendulum, "pendulum_masses.mech", true);
    expect_check_ok(top, "top_masses.mech", true);
    free(pendulum), free(top);
}

static void test_designed_masses_planar(void **s)
{
    (void)s;
    check_designed_dynamics(&pendulum_case, (double[]){1, 1.5, 0.1, 9.81, 20, 0.3},
                            (double[]){2, 0.7, -0.05, 3, 35, 0.4}, "pendulum_masses.mech");
}

static void test_designed_masses_spatial(void **s)
{
    (void)s;
    check_designed_dynamics(&top_case, (double[]){1, 0.002, 0.004, 9.81, 0.02},
                            (double[]){2, 0.003, 0.005, 5, 0.01}, "top_masses.mech");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_design_and_derived_param),
        cmocka_unit_test(test_parse_refuses_design_in_constants),
        cmocka_unit_test(test_emit_design_file),
        cmocka_unit_test(test_emit_file_without_design),
        cmocka_unit_test(test_engines_agree_planar),
        cmocka_unit_test(test_engines_agree_spatial),
        cmocka_unit_test(test_sensitivities_planar),
        cmocka_unit_test(test_sensitivities_spatial),
        cmocka_unit_test(test_engines_agree_spatial_axes),
        cmocka_unit_test(test_sensitivities_spatial_axes),
        cmocka_unit_test(test_sensitivity_column_names),
        cmocka_unit_test(test_sensitivities_sparse),
        cmocka_unit_test(test_sensitivities_borrowed_lu),
        cmocka_unit_test(test_designed_masses_planar),
        cmocka_unit_test(test_designed_masses_spatial),
        cmocka_unit_test(test_check_designed),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
