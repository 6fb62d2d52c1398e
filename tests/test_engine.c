/* test_engine.c - every engine kind is one MechrtKernels: same sizes, same values, valid wherever the Engine goes.
 *
 * engine_open fills Engine.k for jit, aot and generic; check, run and the
 * runtime call nothing else. These tests hold k to that: its sizes are the
 * model's, calling it gives exactly what the kind's own functions give,
 * its fused `all` agrees with the four separate kernels, the runtime's
 * Newton assembles through it, and a copy of k keeps working after the
 * Engine itself is moved (k.ctx is memory the engine owns, never the
 * Engine struct). The aot library cache goes to a private folder.
 */
#include "testutil.h"
#include "testcache.h"
#include "testload.h"
#include "testout.h"

#include "../generator/base/arena.h"
#include "../generator/engine/aot.h"
#include "../generator/engine/engine.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static TestCache cache;

static int setup(void **state)
{
    (void)state;
    return testcache_setup(&cache, "engine");
}

static int teardown(void **state)
{
    (void)state;
    return testcache_teardown(&cache);
}

static void evaluate(const MechrtKernels *k, const double *q, const double *qd, double t, Out *o)
{
    k->phi(k->ctx, q, t, o->phi);
    k->jac(k->ctx, q, t, o->jac);
    k->nu(k->ctx, q, t, o->nu);
    k->gamma(k->ctx, q, qd, t, o->gamma);
}

/* The kind's own functions, bypassing k. */
static void evaluate_directly(const Engine *e, const double *q, const double *qd, double t, Out *o)
{
    if (e->kind == ENGINE_GENERIC) {
        generic_phi(e->generic, q, t, o->phi);
        generic_jac(e->generic, q, t, o->jac);
        generic_nu(e->generic, q, t, o->nu);
        generic_gamma(e->generic, q, qd, t, o->gamma);
        return;
    }
    e->kernels.phi(q, t, o->phi);
    e->kernels.jac(q, t, o->jac);
    e->kernels.nu(q, t, o->nu);
    e->kernels.gamma(q, qd, t, o->gamma);
}

static void assert_same(const char *what, const double *got, const double *want, int n, double rtol)
{
    for (int i = 0; i < n; i++)
        if (!(fabs(got[i] - want[i]) <= rtol * (1.0 + fabs(want[i]))))
            fail_msg("%s[%d] = %.17g, expected %.17g", what, i, got[i], want[i]);
}

static void assert_outs(const char *ctx, const Model *m, const Out *got, const Out *want, double rtol)
{
    char what[120];
    snprintf(what, sizeof what, "%s phi", ctx);
    assert_same(what, got->phi, want->phi, m->nh, rtol);
    snprintf(what, sizeof what, "%s jac", ctx);
    assert_same(what, got->jac, want->jac, m->nr * m->nq, rtol);
    snprintf(what, sizeof what, "%s nu", ctx);
    assert_same(what, got->nu, want->nu, m->nr, rtol);
    snprintf(what, sizeof what, "%s gamma", ctx);
    assert_same(what, got->gamma, want->gamma, m->nr, rtol);
}

/* A high-entropy state near the initial values. */
static void state(const Model *m, double *q, double *qd, double *t)
{
    for (int i = 0; i < m->nq; i++) {
        q[i] = m->q0[i] + 0.0731 * (i % 5) - 0.113;
        qd[i] = 0.7371 - 0.291 * (i % 3);
    }
    *t = 0.4137;
}

static bool open_kind(Engine *e, EngineKind kind, const Mech *mech)
{
    if (kind == ENGINE_AOT && !cache.have_cc)
        return false;
    Diag diag;
    if (!engine_open(e, kind, mech, &diag))
        fail_msg("%s: %s", engine_names[kind], diag.message);
    return true;
}

/* k's sizes are the model's, all five kernels are there, and k gives
   bit for bit what the kind's own functions give. */
static void check_kernels(const char *file)
{
    Mech *mech = load_example(file);
    const Model *m = mech->model;
    double *q = xcalloc((size_t)m->nq, sizeof *q), *qd = xcalloc((size_t)m->nq, sizeof *qd), t;
    state(m, q, qd, &t);
    Out via_k, direct, all;
    out_alloc(&via_k, m), out_alloc(&direct, m), out_alloc(&all, m);
    for (int kind = 0; kind < ENGINE_KIND_COUNT; kind++) {
        Engine e;
        if (!open_kind(&e, (EngineKind)kind, mech))
            continue;
        const MechrtKernels *k = &e.k;
        assert_int_equal(k->nq, m->nq);
        assert_int_equal(k->nh, m->nh);
        assert_int_equal(k->nv, m->nv);
        assert_non_null(k->ctx);
        assert_true(k->phi && k->jac && k->nu && k->gamma && k->all);
        evaluate(k, q, qd, t, &via_k);
        evaluate_directly(&e, q, qd, t, &direct);
        assert_outs(engine_names[kind], m, &via_k, &direct, 0.0);
        k->all(k->ctx, q, qd, t, all.phi, all.jac, all.nu, all.gamma);
        assert_outs(engine_names[kind], m, &all, &via_k, 1e-13);
        engine_close(&e);
    }
    out_free(&via_k), out_free(&direct), out_free(&all);
    free(q), free(qd);
    pipeline_free(mech);
}

static void test_kernels_position_rows(void **s)
{
    (void)s;
    check_kernels("four_bar.mech");
}

static void test_kernels_velocity_rows(void **s)
{
    (void)s;
    check_kernels("all_statements.mech");
}

/* Every spatial kind, the rows of bodies and rolling disks the model adds,
   and both levels: generic (spatial formulas), jit and aot agree. */
static void test_kernels_spatial_rows(void **s)
{
    (void)s;
    check_kernels("all_spatial.mech");
}

/* Every spatial kind with each side a body, a point or ground, general
   axes (B's its own where allowed), lengths and radii of t, and angle()
   and slide() drivers of t, of q and constant: the generic engine's
   formulas must meet each variant. */
static const char every_spatial_text[] =
    "spatial\n"
    "body a x = 0.1 y = 0.2 z = 0.3 orient = axis(1, 2, 3, 0.7)\n"
    "body b x = 1 y = 0.5 z = -0.2 orient = xyz(0.3, -0.2, 0.5)\n"
    "body c x = -0.5 y = 1 z = 0.4 orient = zyx(0.1, 0.4, -0.3)\n"
    "body d x = 2 y = 0 z = 0.5\n"
    "point m x = 0.3 y = -0.4 z = 0.8\n"
    "point n x = 1.3 y = 0.4 z = -0.8\n"
    "spherical S1: a(0.1, -0.2, 0.3) b(-0.4, 0.2, 0.1)\n"
    "spherical S2: m ground(1, 2, 3)\n"
    "spherical S3: ground(0.5, 0, 0) c(0.2, 0.3, -0.1)\n"
    "universal U: a(0.3, 0.1, -0.2) ground(0.4, 0.4, 0.1) axis(1, 1, 0) axis(0, 1, 2)\n"
    "revolute R: b(0.2, -0.1, 0.3) c(-0.3, 0.2, 0.1) axis(0.3, -1, 0.2)\n"
    "revolute R0: ground(0, 0, 1) a(0, 0, 0) axis(1, 0, 0)\n"
    "cylindrical C: c(0.1, 0.2, 0.3) b(0, 0, 0) axis(1, 2, -0.5) axis(0.2, 0.1, 1)\n"
    "translational T: a(0.2, 0.1, 0) ground(1, -1, 0.5) axis(-0.4, 0.3, 0.9)\n"
    "weld W: c(0.3, -0.3, 0.2) b(-0.1, 0.4, 0.2)\n"
    "weld W0: ground(0.2, 0.3, 0.4) a(0.1, 0, 0)\n"
    "distance D1: m a(0.1, 0.2, 0.3) length = 1.2 + 0.1*sin(t)\n"
    "distance D2: b ground(1, 1, 1) length = 2\n"
    "distance D3: b(0.2, 0.1, -0.3) n length = 0.7*t\n"
    "pointplane PP: b(0.1, 0.2, 0.3) n axis(0.5, -1, 2)\n"
    "pointplane PP0: ground(0, 0, 1) c(0.2, 0.1, 0) axis(0, 0, 1)\n"
    "parallel Pl: a c axis(1, 1, 1) axis(0.2, -1, 0.3)\n"
    "perpendicular Pp: b a axis(0.1, 0.9, -0.2) axis(1, 0, 0.3)\n"
    "rolling roll: d radius = 0.5 + 0.1*t + 0.02*sin(2*t) axis(0.1, 1, 0.2)\n"
    "rolling roll2: c radius = 0.3 axis(0, 0, 1)\n"
    "driver Da: angle(R) = t\n"
    "driver Ds: slide(T) = 0.1*t\n"
    "driver Dc: angle(C) = 0.3*t^2 + sin(t)\n"
    "driver Dcs: slide(C) = 0.2*cos(t) + 0.1*m.y\n"
    "driver Dk: angle(R0) = 0.4\n"
    "driver Dq: angle(R) = t + 0.3*b.z*m.x\n"
    "velocity V: der(d.e3) + d.e1*der(m.x) = 0.1*t\n";

/* xorshift64*: deterministic numbers in [-1, 1) */
static double rnd(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) / 4503599627370496.0 - 1.0;
}

/* generic (hand formulas; interpreted: the rows a `constraint`, `driver`
   or `velocity` statement writes, except angle() and slide() drivers,
   `interpreted` of them) against jit at 16 states whose Euler parameters
   are off the unit sphere, to 1e-12. */
static void check_spatial(Mech *mech, const char *name, int interpreted)
{
    const Model *m = mech->model;
    assert_true(m->spatial);
    Engine gen, jit;
    assert_true(open_kind(&gen, ENGINE_GENERIC, mech));
    assert_true(open_kind(&jit, ENGINE_JIT, mech));
    if (generic_interpreted_rows(gen.generic) != interpreted)
        fail_msg("%s: %d interpreted rows, expected %d", name,
                 generic_interpreted_rows(gen.generic), interpreted);
    double *q = xcalloc((size_t)m->nq, sizeof *q), *qd = xcalloc((size_t)m->nq, sizeof *qd);
    Out og, oj;
    out_alloc(&og, m), out_alloc(&oj, m);
    uint64_t s = 0x2545f4914f6cdd1dull;
    char ctx[160];
    for (int k = 0; k < 16; k++) {
        for (int i = 0; i < m->nq; i++) {
            q[i] = m->q0[i] + 0.3 * rnd(&s);
            qd[i] = 1.5 * rnd(&s);
        }
        double t = 0.1 + 0.37 * k;
        evaluate(&gen.k, q, qd, t, &og);
        evaluate(&jit.k, q, qd, t, &oj);
        snprintf(ctx, sizeof ctx, "%s state %d: generic", name, k);
        assert_outs(ctx, m, &og, &oj, 1e-12);
    }
    out_free(&og), out_free(&oj);
    free(q), free(qd);
    engine_close(&gen);
    engine_close(&jit);
}

static void test_generic_spatial_formulas(void **s)
{
    (void)s;
    static const struct {
        const char *file;
        int interpreted;
    } files[] = {
        {"all_spatial.mech", 10},   /* Th Cx Cy Cz Up Head, Du Dv Push, Vp */
        {"rssr.mech", 0},           /* its angle(R1) driver has a formula */
        {"bricard.mech", 0},
        {"rolling_disk.mech", 3},   /* three velocity-level drivers */
        {"slider_crank_spatial.mech", 0},
    };
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
        Mech *mech = load_example(files[i].file);
        check_spatial(mech, files[i].file, files[i].interpreted);
        pipeline_free(mech);
    }
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text(every_spatial_text, "every_spatial.mech", &limits, &diag);
    if (!mech)
        fail_msg("every_spatial.mech: %s", diag.message);
    check_spatial(mech, "every_spatial.mech", 1);     /* V */
    pipeline_free(mech);
}

/* A copy of k, taken before the Engine is moved and the old place
   poisoned, still evaluates, and gives what it gave before. */
static void test_kernels_survive_a_moved_engine(void **s)
{
    (void)s;
    Mech *mech = load_example("four_bar.mech");
    const Model *m = mech->model;
    double *q = xcalloc((size_t)m->nq, sizeof *q), *qd = xcalloc((size_t)m->nq, sizeof *qd), t;
    state(m, q, qd, &t);
    Out before, after;
    out_alloc(&before, m), out_alloc(&after, m);
    for (int kind = 0; kind < ENGINE_KIND_COUNT; kind++) {
        Engine *first = xcalloc(1, sizeof *first);
        if (!open_kind(first, (EngineKind)kind, mech)) {
            free(first);
            continue;
        }
        MechrtKernels k = first->k;
        evaluate(&k, q, qd, t, &before);
        Engine moved = *first;
        memset(first, 0xa5, sizeof *first);     /* poison the old place */
        evaluate(&k, q, qd, t, &after);
        free(first);    /* only now: the compiler drops a memset just before free */
        assert_outs(engine_names[kind], m, &after, &before, 0.0);
        evaluate(&moved.k, q, qd, t, &after);
        assert_outs(engine_names[kind], m, &after, &before, 0.0);
        engine_close(&moved);
    }
    out_free(&before), out_free(&after);
    free(q), free(qd);
    pipeline_free(mech);
}

/* Newton's kernels: the fused `all` where gamma is the smaller part of it
   (planar linkages), phi then jac where gamma outweighs phi and jac (the
   Stewart platform); the generic engine keeps its own. */
static void test_newton_kernels(void **s)
{
    (void)s;
    static const struct {
        const char *file;
        bool all;
    } cases[] = {{"slider_crank.mech", true}, {"four_bar.mech", true}, {"stewart.mech", false}};
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        Mech *mech = load_example(cases[i].file);
        Engine e;
        assert_true(open_kind(&e, ENGINE_JIT, mech));
        MechrtKernels k = engine_newton_kernels(&e);
        assert_true((k.all != NULL) == cases[i].all);
        assert_ptr_equal(k.phi, e.k.phi);
        assert_ptr_equal(k.jac, e.k.jac);
        engine_close(&e);
        if (open_kind(&e, ENGINE_GENERIC, mech)) {
            k = engine_newton_kernels(&e);
            assert_ptr_equal(k.all, e.k.all);
            engine_close(&e);
        }
        pipeline_free(mech);
    }
}

/* The runtime takes an engine's k as it is: Newton assembles the four-bar
   through every kind to the same configuration. */
static void test_runtime_assembles_through_k(void **s)
{
    (void)s;
    Mech *mech = load_example("four_bar.mech");
    const Model *m = mech->model;
    size_t nq = (size_t)m->nq, lwork = mechrt_workspace_size(m->nq, m->nr);
    double *work = xcalloc(lwork, sizeof *work), *q = xcalloc(nq, sizeof *q);
    double *first = xcalloc(nq, sizeof *first);
    bool have_first = false;
    for (int kind = 0; kind < ENGINE_KIND_COUNT; kind++) {
        Engine e;
        if (!open_kind(&e, (EngineKind)kind, mech))
            continue;
        memcpy(q, m->q0, nq * sizeof *q);
        MechrtReport rep;
        assert_int_equal(mechrt_assemble(&e.k, NULL, q, 0.0, work, lwork, &rep), MECHRT_OK);
        assert_true(rep.residual <= 1e-8);
        double *phi = xcalloc((size_t)m->nh + 1, sizeof *phi);
        engine_phi(&e, q, 0.0, phi);
        for (int i = 0; i < m->nh; i++)
            assert_near(phi[i], 0.0, 0.0, 1e-8);
        free(phi);
        if (!have_first)
            memcpy(first, q, nq * sizeof *q);
        assert_same(engine_names[kind], q, first, m->nq, 1e-9);
        have_first = true;
        engine_close(&e);
    }
    assert_true(have_first);
    free(work), free(q), free(first);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kernels_position_rows),
        cmocka_unit_test(test_kernels_velocity_rows),
        cmocka_unit_test(test_kernels_spatial_rows),
        cmocka_unit_test(test_generic_spatial_formulas),
        cmocka_unit_test(test_kernels_survive_a_moved_engine),
        cmocka_unit_test(test_runtime_assembles_through_k),
        cmocka_unit_test(test_newton_kernels),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
