/* test_dynamics.c - masses and forces: M and Q against closed forms, the engines against each other, the generated code, bad input.
 *
 * The compound pendulum (examples/pendulum_dynamics.mech, body
 * coordinates, centre of mass off the origin) and a double pendulum in
 * its own angles (mass elements given by expressions, a torque on an
 * expression angle, a generalised force with der()) are compared with
 * their hand-written M(q) and Q(q, qd, t) at random states, in every
 * engine; a file with every force kind has its engines agree to 1e-12
 * and its springs' Q equal -dV/dq of their potential; the fused eom
 * kernel equals the separate ones, and the generic engine's mass_nz the
 * jit's on every example with masses; a body with its centre of mass at its
 * origin costs M no operation; bad input fails at its line and column.
 */
#include "testutil.h"
#define TESTDYN_SUITE "dynamics"
#include "testdyn.h"
#include "testload.h"

#include "../generator/verify/check.h"
#include "../generator/base/arena.h"
#include "../generator/base/rng.h"
#include "../generator/engine/aot.h"
#include "../generator/engine/engine.h"
#include "../generator/eval/generic.h"

#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A random state: q = base + U(-1, 1), qd = U(-2, 2), t = U(0, 1). */
static void random_state(uint64_t *rng, int nq, const double *base, double *q, double *qd, double *t)
{
    for (int i = 0; i < nq; i++) {
        q[i] = (base ? base[i] : 0.0) + rng_symmetric(rng);
        qd[i] = 2.0 * rng_symmetric(rng);
    }
    *t = rng_unit(rng);
}

static void assert_matrix(const char *what, const double *got, const double *want, int n)
{
    for (int i = 0; i < n; i++)
        if (!(fabs(got[i] - want[i]) <= 1e-12 * (1.0 + fabs(want[i]))))
            fail_msg("%s[%d] = %.17g, expected %.17g", what, i, got[i], want[i]);
}

/* M and Q of a 3-coordinate file, written by hand. */
typedef void ClosedForm(const double *q, const double *qd, double t, double *M, double *Q);

/* Every engine's M and Q at 25 random states against the closed form. */
static void assert_closed_form(const Mech *mech, uint64_t rng, ClosedForm *closed)
{
    for (int k = 0; k < engine_count(); k++) {
        Engine e;
        open_engine(&e, (EngineKind)k, mech);
        for (int s = 0; s < 25; s++) {
            double q[3], qd[3], t, M[9], Q[3], Mw[9], Qw[3];
            random_state(&rng, 3, NULL, q, qd, &t);
            e.k.mass(e.k.ctx, q, M);
            e.k.force(e.k.ctx, q, qd, t, Q);
            closed(q, qd, t, Mw, Qw);
            assert_matrix(engine_names[k], M, Mw, 9);
            assert_matrix(engine_names[k], Q, Qw, 3);
        }
        engine_close(&e);
    }
}

/* ---- the compound pendulum: one body, centre of mass at (a, 0) ---- */

/* pendulum_dynamics.mech's closed forms (its header): L = 1, m = 2, g = 9.81. */
static void pendulum_closed(const double *q, const double *qd, double t, double *M, double *Q)
{
    (void)t;
    const double L = 1, m = 2, g = 9.81, a = L / 2, J = m * L * L / 12;
    double s = sin(q[2]), c = cos(q[2]), w = qd[2];
    double Mw[9] = {m, 0, -m * a * s, 0, m, m * a * c, -m * a * s, m * a * c, J + m * a * a};
    double Qw[3] = {m * a * c * w * w, m * a * s * w * w - m * g, -m * g * a * c};
    memcpy(M, Mw, sizeof Mw);
    memcpy(Q, Qw, sizeof Qw);
}

static void test_compound_pendulum(void **state)
{
    (void)state;
    Mech *mech = load_example("pendulum_dynamics.mech");
    assert_int_equal(mech->model->nmasses, 1);
    assert_true(mech->kin.dyn.present);
    assert_closed_form(mech, 7, pendulum_closed);
    pipeline_free(mech);
}

/* ---- a double pendulum in its own angles ---- */

/* th1, th2 from the downward vertical; a particle m1 at the end of the
   first rod (l1), a second rod of mass m2 and inertia J2 about its centre
   of mass, a2 from the joint; gravity; a motor torque tau t on th1, a
   viscous generalised force -b th2' on th2. z is a held coordinate (the
   file needs a row): its row and column of M and its Q are zero. */
static const char double_pendulum[] =
    "param l1 = 0.7\nparam a2 = 0.4\nparam m1 = 1.3\nparam m2 = 0.8\nparam J2 = 0.05\n"
    "coord th1 = 0.3\ncoord th2 = -0.2\ncoord z\n"
    "constraint hold: z = 0\n"
    "mass p1: at(l1*sin(th1), -l1*cos(th1)) m = m1\n"
    "mass rod2: m = m2 J = J2 at(l1*sin(th1) + a2*sin(th2), -l1*cos(th1) - a2*cos(th2)) angle = th2\n"
    "gravity (0, -9.81)\n"
    "torque motor: angle(th1) = 2.5*t\n"
    "gforce damp: th2 = -0.3*der(th2)\n";

static void double_closed(const double *q, const double *qd, double t, double *M, double *Q)
{
    const double l1 = 0.7, a2 = 0.4, m1 = 1.3, m2 = 0.8, J2 = 0.05, g = 9.81;
    double d = q[0] - q[1], c12 = cos(d), s12 = sin(d);
    memset(M, 0, 9 * sizeof *M);
    M[0] = (m1 + m2) * l1 * l1;
    M[1] = M[3] = m2 * l1 * a2 * c12;
    M[4] = m2 * a2 * a2 + J2;
    Q[0] = -m2 * l1 * a2 * s12 * qd[1] * qd[1] - (m1 + m2) * g * l1 * sin(q[0]) + 2.5 * t;
    Q[1] = m2 * l1 * a2 * s12 * qd[0] * qd[0] - m2 * g * a2 * sin(q[1]) - 0.3 * qd[1];
    Q[2] = 0.0;
}

static void test_double_pendulum(void **state)
{
    (void)state;
    Mech *mech = load_text(double_pendulum, "double_pendulum.mech");
    assert_int_equal(mech->model->nmasses, 2);
    assert_int_equal(mech->model->nforces, 2);
    assert_closed_form(mech, 11, double_closed);
    pipeline_free(mech);
}

/* ---- every force kind ---- */

static const char every_force[] =
    "param k = 40\n"
    "body a x = 0.2 y = 0.1 phi = 0.3\nbody b x = 1.1 y = -0.2 phi = -0.4\npoint p x = 0.5 y = 0.9\n"
    "coord s = 0.1\n"
    "revolute O: ground(0, 0) a(-0.2, 0)\n"
    "distance D: b(0.3, 0.1) p length = 0.8\n"
    "constraint C: s = 0.1*sin(t)\n"
    "mass a m = 1.2 J = 0.03 com(0.1, -0.05)\n"
    "mass b m = 0.7 J = 0.02\nmass p m = 0.3\n"
    "mass e: at(a.x + s*cos(a.phi), a.y + s*sin(a.phi)) m = 0.4 J = 0.01 angle = a.phi + s\n"
    "gravity (0.5, -9.81)\n"
    "force F: b(0.2, -0.1) (3*cos(t), der(b.x) - 2)\n"
    "force G: at(s, a.y) (1, 2*s)\n"
    "torque T: b = -0.5*der(b.phi)\n"
    "spring S1: a(0.1, 0.2) b(-0.1, 0) k = k c = 0.7 length = 0.4 force = 3*t\n"
    "spring S2: ground(2, 1) p k = 10 length = 0.1\n"
    "rspring R: a b k = 5 c = 0.2 angle = 0.1 torque = 1.5\n"
    "gforce H: s = -2*s - 0.1*der(s)^3\n";

/* every spatial force kind (spatial bodies: Euler parameters) */
static const char every_spatial_force[] =
    "spatial\n"
    "param k = 40\n"
    "body a x = 0.2 y = 0.1 z = 0.05 orient = axis(0, 0, 1, 0.3)\n"
    "body b x = 1.1 y = -0.2 z = 0.4 orient = xyz(0.1, -0.2, 0.3)\n"
    "point p x = 0.5 y = 0.9 z = -0.3\n"
    "coord s = 0.1\n"
    "revolute O: ground(0, 0, 0) a(-0.2, 0, 0) axis(0, 0, 1)\n"
    "revolute R: a(0.2, 0, 0) b(-0.3, 0.1, 0) axis(0, 1, 1)\n"
    "distance D: b(0.3, 0.1, 0) p length = 0.8\n"
    "constraint C: s = 0.1*sin(t)\n"
    "mass a m = 1.2 J = (0.01, 0.03, 0.03) com(0.1, -0.05, 0.02)\n"
    "mass b m = 0.7 J = (0.02, 0.02, 0.01) Jxy = 0.001 Jyz = -0.002\n"
    "mass p m = 0.3\n"
    "mass e: at(a.x + s, a.y*s, a.z - s^2) m = 0.4\n"
    "gravity (0.5, -9.81, 1)\n"
    "force F: b(0.2, -0.1, 0.3) (3*cos(t), der(b.x) - 2, b.e2)\n"
    "force G: at(s, a.y, b.z) (1, 2*s, -1)\n"
    "torque T: b = (-0.5*der(b.e1), 0.2, t)\n"
    "torque M: angle(R) = 1.5 - 0.1*t\n"
    "spring S1: a(0.1, 0.2, 0) b(-0.1, 0, 0.1) k = k c = 0.7 length = 0.4 force = 3*t\n"
    "spring S2: ground(2, 1, 0) p k = 10 length = 0.1\n"
    "rspring RS: R k = 5 c = 0.2 angle = 0.1 torque = 1.5\n"
    "gforce H: s = -2*s - 0.1*der(s)^3\n";

/* The engines agree on M and Q (to 1e-12), and the jit's eom equals its
   separate kernels, at random states. */
static void test_engines_agree(void **state)
{
    (void)state;
    const char *names[] = {"every_force", "pendulum_dynamics.mech", "slider_crank_dynamics.mech",
                           "every_spatial_force", "heavy_top.mech"};
    uint64_t rng = 3;
    for (int f = 0; f < 5; f++) {
        Mech *mech = f == 0 ? load_text(every_force, "every_force.mech")
                     : f == 3 ? load_text(every_spatial_force, "every_spatial_force.mech")
                     : load_example(names[f]);
        const Model *m = mech->model;
        size_t nq = (size_t)m->nq, nr = (size_t)m->nr;
        Engine e[ENGINE_KIND_COUNT];
        for (int k = 0; k < engine_count(); k++)
            open_engine(&e[k], (EngineKind)k, mech);
        double *q = xcalloc(nq, 8), *qd = xcalloc(nq, 8), t, *M = xcalloc(nq * nq, 8);
        double *M0 = xcalloc(nq * nq, 8), *Q = xcalloc(nq, 8), *Q0 = xcalloc(nq, 8);
        double *jac = xcalloc(nr * nq, 8), *jac0 = xcalloc(nr * nq, 8);
        double *gam = xcalloc(nr, 8), *gam0 = xcalloc(nr, 8);
        for (int s = 0; s < 10; s++) {
            random_state(&rng, (int)nq, m->q0, q, qd, &t);
            e[0].k.mass(e[0].k.ctx, q, M0);
            e[0].k.force(e[0].k.ctx, q, qd, t, Q0);
            for (int k = 1; k < engine_count(); k++) {
                e[k].k.mass(e[k].k.ctx, q, M);
                e[k].k.force(e[k].k.ctx, q, qd, t, Q);
                assert_matrix(names[f], M, M0, (int)(nq * nq));
                assert_matrix(names[f], Q, Q0, (int)nq);
            }
            const Kernels *code = &e[ENGINE_JIT].kernels;
            code->eom(q, qd, t, M, Q, jac, gam);
            code->jac(q, t, jac0);
            code->gamma(q, qd, t, gam0);
            assert_matrix("eom M", M, M0, (int)(nq * nq));
            assert_matrix("eom Q", Q, Q0, (int)nq);
            assert_matrix("eom jac", jac, jac0, (int)(nr * nq));
            assert_matrix("eom gamma", gam, gam0, (int)nr);
            /* mass_nz with its pattern gives M */
            double *vals = xcalloc((size_t)mech->kin.dyn.nnz + 1, 8);
            code->mass_nz(q, vals);
            memset(M, 0, nq * nq * 8);
            for (int k = 0; k < mech->kin.dyn.nnz; k++)
                M[code->mass_row[k] * (int)nq + code->mass_col[k]] = vals[k];
            assert_matrix("mass_nz", M, M0, (int)(nq * nq));
            free(vals);
        }
        for (int k = 0; k < engine_count(); k++)
            engine_close(&e[k]);
        free(q), free(qd), free(M), free(M0), free(Q), free(Q0), free(jac), free(jac0), free(gam), free(gam0);
        pipeline_free(mech);
    }
}

/* The generic engine's mass_nz, from its jets, equals the jit's (to
   1e-12) in the generated kernel's pattern, and scattered gives its own
   dense M (no product falls outside the pattern), at random states. */
static void assert_mass_nz_agree(const char *name, const Mech *mech)
{
    const Model *m = mech->model;
    size_t nq = (size_t)m->nq;
    Engine gen, jit;
    open_engine(&gen, ENGINE_GENERIC, mech);
    open_engine(&jit, ENGINE_JIT, mech);
    int nnz = mech->kin.dyn.nnz;
    assert_true(nnz > 0);
    const MechrtHostMassNz *gm = engine_mass_nz(&gen), *jm = engine_mass_nz(&jit);
    assert_non_null(gm);
    assert_non_null(jm);
    assert_int_equal(gm->nnz, nnz);
    assert_int_equal(jm->nnz, nnz);
    for (int k = 0; k < nnz; k++) {
        assert_int_equal(gm->row[k], jm->row[k]);
        assert_int_equal(gm->col[k], jm->col[k]);
    }
    double *q = xcalloc(nq, 8), *qd = xcalloc(nq, 8), t, *M = xcalloc(nq * nq, 8);
    double *M0 = xcalloc(nq * nq, 8), *vals = xcalloc((size_t)nnz, 8), *want = xcalloc((size_t)nnz, 8);
    uint64_t rng = 11;
    for (int s = 0; s < 10; s++) {
        random_state(&rng, (int)nq, m->q0, q, qd, &t);
        for (int k = 0; k < nnz; k++)
            vals[k] = NAN;  /* every slot must be written */
        gm->mass_nz(gm->ctx, q, vals);
        jm->mass_nz(jm->ctx, q, want);
        assert_matrix(name, vals, want, nnz);
        gen.k.mass(gen.k.ctx, q, M0);
        memset(M, 0, nq * nq * 8);
        for (int k = 0; k < nnz; k++)
            M[(size_t)gm->row[k] * nq + (size_t)gm->col[k]] = vals[k];
        assert_matrix(name, M, M0, (int)(nq * nq));
    }
    engine_close(&gen);
    engine_close(&jit);
    free(q), free(qd), free(M), free(M0), free(vals), free(want);
}

static void test_generic_mass_nz(void **state)
{
    (void)state;
    const char *dir = getenv("MECHC_EXAMPLES") ? getenv("MECHC_EXAMPLES") : "examples";
    DIR *d = opendir(dir);
    assert_non_null(d);
    int checked = 0;
    bool top = false;
    for (struct dirent *ent; (ent = readdir(d));) {
        size_t len = strlen(ent->d_name);
        if (len < 5 || strcmp(ent->d_name + len - 5, ".mech") != 0)
            continue;
        Mech *mech = load_example(ent->d_name);
        if (mech->model->nmasses > 0) {
            assert_mass_nz_agree(ent->d_name, mech);
            checked++;
            top |= strcmp(ent->d_name, "heavy_top.mech") == 0;
        }
        pipeline_free(mech);
    }
    closedir(d);
    assert_true(checked >= 9);
    assert_true(top);       /* a spatial one: the Euler block */
    Mech *mech = load_script("a02_four_bar.sh", 4);
    assert_mass_nz_agree("a02 N = 4", mech);
    pipeline_free(mech);
    mech = load_text(every_force, "every_force.mech");
    assert_mass_nz_agree("every_force", mech);
    pipeline_free(mech);
    mech = load_text(every_spatial_force, "every_spatial_force.mech");
    assert_mass_nz_agree("every_spatial_force", mech);
    pipeline_free(mech);
}

/* A spring without damping or actuator is conservative: its Q is -dV/dq,
   V = k/2 (l - L0)^2, by central differences. */
static void test_spring_potential(void **state)
{
    (void)state;
    Mech *mech = load_text("body a x = 0.3 y = 0.2 phi = 0.4\npoint p x = 1 y = 1\n"
                           "weld W: ground a\nconstraint C: p.x = 1\n"
                           "mass p m = 1\n"
                           "spring S: a(0.2, -0.1) p k = 30 length = 0.5\n", "spring.mech");
    Engine e;
    open_engine(&e, ENGINE_JIT, mech);
    uint64_t rng = 5;
    for (int s = 0; s < 10; s++) {
        double q[5], qd[5] = {0}, t, Q[5];
        random_state(&rng, 5, mech->model->q0, q, qd, &t);
        memset(qd, 0, sizeof qd);
        e.k.force(e.k.ctx, q, qd, t, Q);
        for (int j = 0; j < 5; j++) {
            double v[2];
            for (int side = 0; side < 2; side++) {
                double w[5];
                memcpy(w, q, sizeof w);
                w[j] += side ? -1e-6 : 1e-6;
                double c = cos(w[2]), sn = sin(w[2]);
                double ax = w[0] + 0.2 * c + 0.1 * sn, ay = w[1] + 0.2 * sn - 0.1 * c;
                double l = hypot(w[3] - ax, w[4] - ay);
                v[side] = 15 * (l - 0.5) * (l - 0.5);
            }
            assert_near(Q[j], -(v[0] - v[1]) / 2e-6, 1e-6, 1e-6);
        }
    }
    engine_close(&e);
    pipeline_free(mech);
}

/* Bodies with their centres of mass at their origins: M is constant, the
   generated mass function does no arithmetic, and Q only the weights and
   the spring. Without masses nothing of it is generated. */
static void test_constant_mass_costs_nothing(void **state)
{
    (void)state;
    Mech *mech = load_example("slider_crank_dynamics.mech");
    EmitOptions opt = emit_default_options();
    EmitResult res;
    Diag diag;
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &diag));
    assert_int_equal(res.ops[EMIT_MASS], 0);
    assert_int_equal(res.ops[EMIT_MASS_NZ], 0);
    assert_int_equal(mech->kin.dyn.nnz, 9);
    assert_non_null(strstr(res.h_text, "#define SLIDER_CRANK_DYNAMICS_HAS_DYNAMICS 1"));
    assert_non_null(strstr(res.c_text, "M[40] = 1.5;"));
    emit_result_free(&res);
    pipeline_free(mech);

    mech = load_example("slider_crank.mech");
    assert_false(mech->kin.dyn.present);
    assert_true(emit_mechanism(&mech->kin, &opt, &res, &diag));
    assert_null(strstr(res.c_text, "_mass"));
    assert_null(strstr(res.h_text, "HAS_DYNAMICS"));
    Engine e;
    assert_true(engine_open(&e, ENGINE_GENERIC, mech, &diag));
    assert_null(e.k.mass);
    assert_null(e.k.force);
    engine_close(&e);
    emit_result_free(&res);
    pipeline_free(mech);
}

/* check passes the examples with masses, and catches a wrong entry of M
   (planted in the jit's): the engines disagree, and M is not symmetric. */
static void test_check_catches_mass_mistakes(void **state)
{
    (void)state;
    Mech *mech = load_example("pendulum_dynamics.mech");
    CheckOptions opt = check_default_options();
    opt.samples = 4;
    opt.use_aot = false;
    CheckReport rep;
    Diag diag;
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    assert_true(rep.ok);
    for (int w = CHECK_DYN_FIRST; w < CHECK_PHI_P_FD; w++)     /* the dynamics items */
        assert_int_equal(rep.items[w].checked, strstr(rep.items[w].what, "aot") == NULL);
    opt.fault = (CheckFault){.kind = CHECK_FAULT_MASS_SCALE, .row = 0, .col = 2, .factor = -1.0};
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    assert_false(rep.ok);
    assert_true(rep.items[CHECK_DYN_FIRST].error > 0.1);            /* M jit/generic */
    assert_true(rep.items[CHECK_M_SYMMETRIC].error > 0.1);
    assert_non_null(strstr(rep.items[CHECK_M_SYMMETRIC].hint, "one triangle"));
    assert_true(rep.items[CHECK_DYN_FIRST + 1].error <= 1e-12);     /* Q untouched */
    pipeline_free(mech);
}

/* ---- bad input ---- */

typedef struct BadCase {
    const char *text;
    int line, col;
    const char *message;
} BadCase;

#define PRE "body a x = 1\npoint p\ncoord s\nrevolute O: ground a\n"

static const BadCase bad_cases[] = {
    {PRE "mass a m = -1\n", 5, 8, "the mass m of mass 'a' is negative"},
    {PRE "mass a m = 1 J = -0.1\n", 5, 14, "the moment of inertia J of mass 'a' is negative"},
    {PRE "mass b m = 1\n", 5, 6, "unknown name 'b'"},
    {PRE "mass s m = 1\n", 5, 6, "'s' is a coord"},
    {PRE "mass p m = 1 J = 2\n", 5, 14, "'p' is a point (a particle): it has no angle"},
    {PRE "mass a J = 1\n", 5, 13, "expected 'm = ...' for mass 'a'"},
    {PRE "mass a m = 1\nmass a m = 2\n", 6, 6, "'a' already has a mass (line 5)"},
    {PRE "mass e: m = 1\n", 5, 14, "expected 'at(x, y)' for the mass element 'e'"},
    {PRE "mass e: at(a.x, t) m = 1\n", 5, 17, "'t' cannot appear in a mass element's position"},
    {PRE "mass e: at(a.x, 0) m = 1 J = 2\n", 5, 26, "has J but no 'angle = ...'"},
    {PRE "mass a m = 1 spin = 2\n", 5, 14, "unknown key 'spin' for mass 'a': expected m, J or com(sx, sy)"},
    {PRE "mass a m = 1\nspring S: a p k = 1 length = -0.5\n", 6, 21, "the free length of spring 'S' is negative"},
    {PRE "mass a m = 1\ntorque T: p = 1\n", 6, 11, "'p' is a point (it has no angle)"},
    {PRE "mass a m = 1\nforce F: q (1, 0)\n", 6, 10, "unknown name 'q'"},
    {PRE "mass a m = 1\nforce F: ground (1, 0)\n", 6, 10, "acts on ground only: it does no work"},
    {PRE "mass a m = 1\nrspring R: a p(1, 0) k = 1\n", 6, 15, "acts on bodies' angles"},
    {PRE "mass a m = 1\nrspring R: at(1, 2) ground k = 1\n", 6, 12, "at(x, y) is a point; name a body or ground"},
    {PRE "mass a m = 1\ntorque T: at(1, 2) = 1\n", 6, 11, "at(x, y) is a point; name a body or ground"},
    {PRE "mass a m = 1\nforce F: at(1, 2) (1, 0)\n", 6, 10, "force 'F' is applied at a fixed point"},
    {PRE "mass a m = 1\nforce F: at(2 * t, 1) (1, 0)\n", 6, 10, "it does no work"},
    {PRE "mass a m = 1\ntorque T: angle(t) = 1\n", 6, 17, "torque 'T' acts on an angle that depends on no coordinate"},
    {PRE "mass a m = 1\nspring S: a a k = 1\n", 6, 13, "spring 'S' joins a point to itself"},
    {PRE "mass a m = 1\nspring S: p at(p.x, p.y) k = 1\n", 6, 13, "spring 'S' joins a point to itself"},
    {PRE "mass a m = 1\nspring S: ground at(1, 0) k = 1\n", 6, 11, "spring 'S' joins two fixed points"},
    {PRE "mass a m = 1\ngforce G: a = 1\n", 6, 11, "'a' is a body: write a.x, a.y or a.phi"},
    {PRE "mass a m = 1\ngravity (0, -9.81)\ngravity (0, 1)\n", 7, 1, "a second gravity statement"},
    {PRE "gravity (0, -9.81)\n", 5, 1, "gravity without masses"},
    {PRE "force F: a (1, 0)\n", 5, 1, "a force without masses"},
#define SPRE "spatial\nbody a z = -1\npoint p\nspherical O: ground a\n"
    {SPRE "mass a m = -1\n", 5, 8, "the mass m of mass 'a' is negative"},
    {SPRE "mass a m = 1 J = (-1, 1, 1)\n", 5, 19, "the moment of inertia Jxx of mass 'a' is negative"},
    {SPRE "mass a m = 1 J = (1, 1, 1) Jxy = 2\n", 5, 14,
     "the inertia tensor of 'a' is not positive definite: its principal moments are -1, 1, 3"},
    {SPRE "mass a m = 1 J = (1, 1, 0)\n", 5, 14, "the inertia tensor of 'a' is not positive definite"},
    /* a diagonal tensor's moments exactly (not -1.1e-16); entries near 1e200 scaled first */
    {SPRE "mass a m = 1 J = (0, 1, 1)\n", 5, 14, "its principal moments are 0, 1, 1"},
    {SPRE "mass a m = 1 J = (1e200, 1e200, 1e200) Jxy = 1e200\n", 5, 14, ", 1e+200, 2e+200"},
    {SPRE "mass a m = 1 J = (1, 1, 3)\n", 5, 14, "1 + 1 < 3 break the triangle inequality"},
    {SPRE "mass a m = 1 Jxy = 0.1\n", 5, 14, "'Jxy' without J = (Jxx, Jyy, Jzz)"},
    {SPRE "mass a m = 1 J = 2\n", 5, 18, "expected '(' after J = (Jxx, Jyy, Jzz)"},
    {SPRE "mass p m = 1 J = (1, 1, 1)\n", 5, 14, "'p' is a point (a particle)"},
    {SPRE "mass a m = 1 angle = 2\n", 5, 14, "unknown key 'angle' for mass 'a': expected m, J, Jxy, "
     "Jxz, Jyz or com(sx, sy, sz)"},
    {SPRE "mass e: at(1, 2) m = 1\n", 5, 16, "at(x, y, z) has three components, found two"},
    {SPRE "mass a m = 1\ngravity (0, -9.81)\n", 6, 18, "gravity (gx, gy, gz) has three components"},
    {SPRE "mass a m = 1\ntorque T: a = 1\n", 6, 15, "expected '(' after the torque (tx, ty, tz)"},
    {SPRE "mass a m = 1\nrspring R: O k = 1\n", 6, 12, "a spatial rspring acts about a revolute's "
     "or cylindrical's axis; 'O' is spherical"},
    {SPRE "mass a m = 1\ntorque T: angle(O) = 1\n", 6, 17, "angle(O) takes a revolute or cylindrical"},
    {SPRE "mass a m = 1\nspring S: a a k = 1\n", 6, 13, "spring 'S' joins a point to itself"},
    {SPRE "mass a m = 1\nforce F: ground(1, 2, 3) (1, 0, 0)\n", 6, 10, "acts on ground only"},
#undef SPRE
};

static void test_bad_input(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof bad_cases / sizeof *bad_cases; i++) {
        const BadCase *b = &bad_cases[i];
        MechLimits limits = mech_default_limits();
        Diag diag;
        Mech *mech = pipeline_load_text(b->text, "bad.mech", &limits, &diag);
        if (mech)
            fail_msg("case %zu loaded: %s", i, b->text);
        if (!strstr(diag.message, b->message) || diag.line != b->line || diag.col != b->col)
            fail_msg("case %zu: %d:%d: %s\nexpected %d:%d: %s", i, diag.line, diag.col,
                     diag.message, b->line, b->col, b->message);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compound_pendulum),
        cmocka_unit_test(test_double_pendulum),
        cmocka_unit_test(test_engines_agree),
        cmocka_unit_test(test_generic_mass_nz),
        cmocka_unit_test(test_spring_potential),
        cmocka_unit_test(test_constant_mass_costs_nothing),
        cmocka_unit_test(test_check_catches_mass_mistakes),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
