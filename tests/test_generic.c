/* test_generic.c - the engines agree: generic evaluator, JIT and AOT on every example.
 *
 * The generic evaluator (hand-derived joint formulas, interpreted
 * expression rows) and the generated code (symbolic derivatives) are
 * written independently, so their agreement to 1e-12 at high-entropy
 * states (angles like 0.7371, velocities like -0.613, t = 0.4137) checks
 * both. AOT is compared when a C compiler exists; its cache goes to a
 * private folder ($XDG_CACHE_HOME is pointed at it).
 */
#include "testutil.h"
#include "testcache.h"
#include "testout.h"

#include "../generator/base/arena.h"
#include "../generator/engine/aot.h"
#include "../generator/engine/engine.h"
#include "../generator/eval/generic.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Every joint kind, offsets on both sides, options that depend on t and on
   q, every function and operator in expression rows, velocity rows with
   coefficients that depend on q and t, a body jointed to itself. */
static const char funcs_mech[] =
    "mechanism funcs\n"
    "param L0 = 1.2\n"
    "body a x = 0.3 y = 0.4 phi = 0.5\n"
    "body b x = 1.1 y = 0.2 phi = 0.7\n"
    "point p x = 0.5 y = 0.9\n"
    "coord th = 0.3\n"
    "distance d1: a(0.1, 0.2) p length = L0 + 0.1*sin(t) + 0.05*t*t\n"
    "prismatic pr: a(0.2,0.1) b(0.3,-0.1) axis(0.6, 0.8) angle = 0.1*t^2 + 0.2*sin(t)\n"
    "weld w: ground(1, 2) b(0.1, 0.1) angle = atan2(t, 2)\n"
    "weld w2: a b(0.2, 0)\n"
    "prismatic pg: ground(0.5, 0.5) a axis(1, 1)\n"
    "pointline pl: b(0.2, 0.3) p axis(1, 2)\n"
    "pointline pl2: ground(0, 1) b(0.4, 0.1) axis(2, -1)\n"
    "distance d2: p b length = 2\n"
    "revolute rv: a(0.1, 0.3) b(-0.2, 0.1)\n"
    "revolute rp: p b(0.1, 0.1)\n"
    "constraint c1: tan(th) + asin(0.3*a.x) + acos(0.2*a.y) + atan(p.x) + sqrt(p.y + 2)"
    " + exp(0.1*a.phi) + log(b.x + 3) + sinh(th) + cosh(0.5*t) + tanh(p.x*p.y) + (a.x+2)^1.7"
    " + (b.y+2)^(0.3*t+th) + atan2(p.y, p.x) + a.x/(b.x+2) - t^3/(1+t) - -p.x = 0\n"
    "driver dr: th = sin(3*t)*cos(t) + t/(2 + t)\n"
    "rolling r: a radius = 0.3 + 0.1*t + 0.05*t*t\n"
    "rolling r2: b radius = 0.4\n"
    "knife k: b(0.1, -0.2) axis(0.3, 1)\n"
    "knife k2: a axis(1, 0.5)\n"
    "velocity v: der(th)*cos(a.phi) + t*der(p.x)*p.y + sin(t)*b.x = 0\n"
    "driver dv: der(b.phi)*exp(t) = 2*t\n";

static char cache_dir[256];
static bool have_cc;

static int setup(void **state)
{
    (void)state;
    if (!testcache_make(cache_dir, sizeof cache_dir, "generic"))
        return -1;
    have_cc = aot_compiler_available();
    if (!have_cc)
        fprintf(stderr, "test_generic: no C compiler: the aot engine is not compared\n");
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    testcache_release(cache_dir);
    return 0;
}

/* xorshift64*: deterministic numbers in [-1, 1) */
static double rnd(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) / 4503599627370496.0 - 1.0;
}

static void evaluate(const Engine *e, const double *q, const double *qd, double t, Out *o)
{
    engine_phi(e, q, t, o->phi);
    engine_jac(e, q, t, o->jac);
    engine_nu(e, q, t, o->nu);
    engine_gamma(e, q, qd, t, o->gamma);
}

static void assert_same(const char *file, const char *what, const char *engine, const Model *m,
                        const double *got, const double *want, int n)
{
    for (int i = 0; i < n; i++) {
        double tol = 1e-12 * (1.0 + fabs(want[i]));
        if (!(fabs(got[i] - want[i]) <= tol)) {
            int row = strcmp(what, "jac") == 0 ? i / m->nq : i;
            fail_msg("%s: %s[%d] (row %s) %s = %.17g, jit = %.17g", file, what, i,
                     row < m->nr ? m->rows[row].name : "?", engine, got[i], want[i]);
        }
    }
}

/* jit against generic (and aot) at four high-entropy states. */
static void compare_engines(Mech *mech, const char *file)
{
    const Model *m = mech->model;
    Diag diag;
    Engine jit, gen, aot;
    assert_true(engine_open(&jit, ENGINE_JIT, mech, &diag));
    assert_true(engine_open(&gen, ENGINE_GENERIC, mech, &diag));
    bool use_aot = have_cc;
    if (use_aot && !engine_open(&aot, ENGINE_AOT, mech, &diag))
        fail_msg("%s: aot: %s", file, diag.message);
    Out oj, og, oa, all;
    out_alloc(&oj, m), out_alloc(&og, m), out_alloc(&oa, m), out_alloc(&all, m);
    double *q = xcalloc((size_t)m->nq, sizeof *q), *qd = xcalloc((size_t)m->nq, sizeof *qd);
    uint64_t s = 0x9e3779b97f4a7c15ull;
    for (int k = 0; k < 4; k++) {
        for (int i = 0; i < m->nq; i++) {
            q[i] = m->q0[i] + 0.2 * rnd(&s);
            qd[i] = 1.3 * rnd(&s);
        }
        double t = 0.4137 + 0.3 * k;
        evaluate(&jit, q, qd, t, &oj);
        evaluate(&gen, q, qd, t, &og);
        const char *names[] = {"phi", "jac", "nu", "gamma"};
        double *want[] = {oj.phi, oj.jac, oj.nu, oj.gamma}, *got[] = {og.phi, og.jac, og.nu, og.gamma};
        int n[] = {m->nh, m->nr * m->nq, m->nr, m->nr};
        for (int w = 0; w < 4; w++)
            assert_same(file, names[w], "generic", m, got[w], want[w], n[w]);
        /* generic's all = its four separate calls */
        engine_all(&gen, q, qd, t, all.phi, all.jac, all.nu, all.gamma);
        double *together[] = {all.phi, all.jac, all.nu, all.gamma};
        for (int w = 0; w < 4; w++)
            assert_same(file, names[w], "generic all", m, together[w], got[w], n[w]);
        if (use_aot) {
            evaluate(&aot, q, qd, t, &oa);
            double *ga[] = {oa.phi, oa.jac, oa.nu, oa.gamma};
            for (int w = 0; w < 4; w++)
                assert_same(file, names[w], "aot", m, ga[w], want[w], n[w]);
        }
    }
    free(q), free(qd);
    out_free(&oj), out_free(&og), out_free(&oa), out_free(&all);
    engine_close(&jit);
    engine_close(&gen);
    if (use_aot)
        engine_close(&aot);
}

static void test_examples_agree(void **state)
{
    (void)state;
    const char *dir = getenv("MECHC_EXAMPLES");
    if (!dir)
        dir = "examples";
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    int count = 0;
    MechLimits limits = mech_default_limits();
    while ((e = readdir(d))) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".mech") != 0)
            continue;
        char path[600];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        Diag diag;
        Mech *mech = pipeline_load(path, &limits, &diag);
        if (!mech)
            continue;       /* examples of bad input */
        compare_engines(mech, path);
        pipeline_free(mech);
        count++;
    }
    closedir(d);
    assert_true(count >= 10);
}

static void test_every_joint_and_function(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text(funcs_mech, "funcs.mech", &limits, &diag);
    if (!mech)
        fail_msg("funcs.mech: %s", diag.message);
    compare_engines(mech, "funcs.mech");
    pipeline_free(mech);
}

/* A revolute by hand: rows, Jacobian blocks [I, B s] and gamma A s phi'^2. */
static void test_revolute_by_hand(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text("body b x = 0.2 y = -0.3 phi = 0.7371\n"
                                    "revolute O: b(0.5, 0.25) ground(1, 2)\n",
                                    "rev.mech", &limits, &diag);
    assert_non_null(mech);
    Generic *g = generic_open(mech->model);
    double q[3] = {0.2, -0.3, 0.7371}, qd[3] = {0.1, -0.2, 1.7}, phi[2], jac[6], gamma[2], nu[2];
    generic_phi(g, q, 0.0, phi);
    generic_jac(g, q, 0.0, jac);
    generic_nu(g, q, 0.0, nu);
    generic_gamma(g, q, qd, 0.0, gamma);
    double c = cos(q[2]), s = sin(q[2]), ax = c * 0.5 - s * 0.25, ay = s * 0.5 + c * 0.25;
    assert_near(phi[0], q[0] + ax - 1.0, 0, 1e-15);
    assert_near(phi[1], q[1] + ay - 2.0, 0, 1e-15);
    const double want[6] = {1, 0, -ay, 0, 1, ax};
    for (int i = 0; i < 6; i++)
        assert_near(jac[i], want[i], 0, 1e-15);
    assert_near(nu[0], 0.0, 0, 0);
    assert_near(gamma[0], ax * qd[2] * qd[2], 1e-15, 1e-15);
    assert_near(gamma[1], ay * qd[2] * qd[2], 1e-15, 1e-15);
    generic_free(g);
    pipeline_free(mech);
}

/* No compiler: a clear message, not a crash; then the cache is used. */
static void test_aot_compiler_and_cache(void **state)
{
    (void)state;
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text("point m x = 1.732 y = 1\ndistance rod: ground m length = 2\n",
                                    "pend.mech", &limits, &diag);
    assert_non_null(mech);
    const char *old = getenv("CC");
    char *saved = old ? strdup(old) : NULL;
    setenv("CC", "/nonexistent/mechc-test-cc", 1);
    Engine e;
    assert_false(engine_open(&e, ENGINE_AOT, mech, &diag));
    assert_non_null(strstr(diag.message, "needs a C compiler"));
    if (saved) {
        setenv("CC", saved, 1);
        free(saved);
    } else {
        unsetenv("CC");
    }
    if (have_cc) {
        EngineOptions fresh = engine_default_options();
        fresh.aot_fresh = true;
        assert_true(engine_open_with(&e, ENGINE_AOT, mech, &fresh, &diag));
        assert_false(e.aot_cached);
        engine_close(&e);
        assert_true(engine_open(&e, ENGINE_AOT, mech, &diag));
        assert_true(e.aot_cached);
        double q[2] = {1.1, 0.7}, phi[1];
        engine_phi(&e, q, 0.0, phi);
        assert_near(phi[0], 1.1 * 1.1 + 0.7 * 0.7 - 4.0, 1e-15, 1e-15);
        engine_close(&e);
    }
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_revolute_by_hand),
        cmocka_unit_test(test_every_joint_and_function),
        cmocka_unit_test(test_examples_agree),
        cmocka_unit_test(test_aot_compiler_and_cache),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
