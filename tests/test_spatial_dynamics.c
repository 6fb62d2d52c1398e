/* test_spatial_dynamics.c - M and Q of spatial (Euler-parameter) bodies: Nikravesh's closed form, Euler's equations, Lagrange from M, every engine.
 *
 * A free body's M and Q against Nikravesh's equations written here by
 * hand (M_ee = 4 G^T J' G, Q_e = 8 Gd^T J' Gd e + 2 E^T tau); the motion
 * they give against Euler's equations J' w'd + w' x J' w' = n' (no
 * Euler parameters in the reference); the velocity terms against
 * Lagrange's equations of T = 1/2 qd^T M qd by central differences of M.
 * Every spatial force kind in every engine: test_dynamics.c.
 */
#include "testutil.h"
#define TESTDYN_SUITE "spatial_dynamics"
#include "testdyn.h"
#include "testload.h"

#include "../generator/base/arena.h"
#include "../generator/base/rng.h"
#include "../generator/engine/aot.h"
#include "../generator/engine/engine.h"

#include <gsl/gsl_linalg.h>
#include <stdlib.h>
#include <string.h>

static void assert_close(const char *what, const double *got, const double *want, int n, double tol)
{
    for (int i = 0; i < n; i++)
        if (!(fabs(got[i] - want[i]) <= tol * (1.0 + fabs(want[i]))))
            fail_msg("%s[%d] = %.17g, expected %.17g", what, i, got[i], want[i]);
}

/* ---- a free body: Nikravesh's equations by hand ---- */

/* m = 1.7 at the body origin, J' with products, gravity, a global torque. */
static const char free_body[] =
    "spatial\n"
    "body b x = 0.1 y = -0.2 z = 0.3 orient = axis(1, 2, 3, 0.7)\n"
    "mass b m = 1.7 J = (0.03, 0.05, 0.06) Jxy = 0.004 Jxz = -0.002 Jyz = 0.003\n"
    "gravity (0.5, -1, -9.81)\n"
    "torque T: b = (0.2 + b.x, -0.3*t, 0.1*der(b.e1))\n";

static const double fb_m = 1.7, fb_g[3] = {0.5, -1, -9.81};
static const double fb_J[3][3] = {{0.03, 0.004, -0.002}, {0.004, 0.05, 0.003}, {-0.002, 0.003, 0.06}};

/* Nikravesh (6.x): G = [-e, -tilde(e) + e0 I], E = [-e, tilde(e) + e0 I]. */
static void nik_G(const double *p, double G[3][4], bool global)
{
    double s = global ? 1 : -1;
    double e0 = p[0], e1 = p[1], e2 = p[2], e3 = p[3];
    double out[3][4] = {
        {-e1, e0, -s * e3, s * e2},
        {-e2, s * e3, e0, -s * e1},
        {-e3, -s * e2, s * e1, e0},
    };
    memcpy(G, out, sizeof out);
}

static void free_body_closed(const double *q, const double *qd, double t, double *M, double *Q)
{
    const double *p = q + 3, *pd = qd + 3;
    memset(M, 0, 49 * sizeof *M);
    for (int i = 0; i < 3; i++) {
        M[i * 7 + i] = fb_m;
        Q[i] = fb_m * fb_g[i];
    }
    double G[3][4], Gd[3][4], E[3][4];
    nik_G(p, G, false);
    nik_G(pd, Gd, false);
    nik_G(p, E, true);
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++) {
            double s = 0;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    s += 4 * G[i][a] * fb_J[i][j] * G[j][b];
            M[(3 + a) * 7 + 3 + b] = s;
        }
    double Gdp[3] = {0, 0, 0}, tau[3] = {0.2 + q[0], -0.3 * t, 0.1 * qd[4]};
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < 4; k++)
            Gdp[j] += Gd[j][k] * p[k];
    for (int a = 0; a < 4; a++) {
        double s = 0;
        for (int i = 0; i < 3; i++) {
            double jg = 0;
            for (int j = 0; j < 3; j++)
                jg += fb_J[i][j] * Gdp[j];
            s += 8 * Gd[i][a] * jg + 2 * E[i][a] * tau[i];
        }
        Q[3 + a] = s;
    }
}

/* Every engine's M and Q at random states (off the unit sphere too: the
   formulas are polynomials) against Nikravesh's, written above. */
static void test_free_body_nikravesh(void **state)
{
    (void)state;
    Mech *mech = load_text(free_body, "free_body.mech");
    assert_int_equal(mech->model->nq, 7);
    uint64_t rng = 11;
    for (int k = 0; k < engine_count(); k++) {
        Engine e;
        open_engine(&e, (EngineKind)k, mech);
        for (int s = 0; s < 20; s++) {
            double q[7], qd[7], t = rng_unit(&rng), M[49], Q[7], Mw[49], Qw[7];
            for (int i = 0; i < 7; i++) {
                q[i] = rng_symmetric(&rng);
                qd[i] = 2 * rng_symmetric(&rng);
            }
            e.k.mass(e.k.ctx, q, M);
            e.k.force(e.k.ctx, q, qd, t, Q);
            free_body_closed(q, qd, t, Mw, Qw);
            assert_close(engine_names[k], M, Mw, 49, 1e-12);
            assert_close(engine_names[k], Q, Qw, 7, 1e-12);
        }
        engine_close(&e);
    }
    pipeline_free(mech);
}

/* ---- the motion: Euler's equations ---- */

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* At unit e and ed . e = 0, the free body's qdd from [M 2e; 2e^T 0]
   [qdd; lambda] = [Q; -2 ed.ed] (the norm row's gamma) satisfies
   J' w'd + w' x J' w' = A^T tau and m rdd = m g: Newton and Euler, with
   w' = 2 G ed, w'd = 2 G edd (G(ed) ed = 0). */
static void test_free_body_euler(void **state)
{
    (void)state;
    Mech *mech = load_text(free_body, "free_body.mech");
    Engine e;
    open_engine(&e, ENGINE_JIT, mech);
    uint64_t rng = 17;
    for (int s = 0; s < 20; s++) {
        double q[7], qd[7], t = rng_unit(&rng), M[49], Q[7];
        for (int i = 0; i < 7; i++) {
            q[i] = rng_symmetric(&rng);
            qd[i] = 2 * rng_symmetric(&rng);
        }
        double *p = q + 3, *pd = qd + 3, n = 0, d = 0;
        for (int k = 0; k < 4; k++)
            n += p[k] * p[k];
        for (int k = 0; k < 4; k++)
            p[k] /= sqrt(n);
        for (int k = 0; k < 4; k++)
            d += pd[k] * p[k];
        for (int k = 0; k < 4; k++)
            pd[k] -= d * p[k];
        e.k.mass(e.k.ctx, q, M);
        e.k.force(e.k.ctx, q, qd, t, Q);
        double aug[64] = {0}, rhs[8], x[8];
        for (int i = 0; i < 7; i++) {
            for (int j = 0; j < 7; j++)
                aug[i * 8 + j] = M[i * 7 + j];
            rhs[i] = Q[i];
        }
        double pdpd = 0;
        for (int k = 0; k < 4; k++) {
            aug[(3 + k) * 8 + 7] = aug[7 * 8 + 3 + k] = 2 * p[k];
            pdpd += pd[k] * pd[k];
        }
        rhs[7] = -2 * pdpd;
        gsl_matrix_view A = gsl_matrix_view_array(aug, 8, 8);
        gsl_vector_view b = gsl_vector_view_array(rhs, 8), xv = gsl_vector_view_array(x, 8);
        gsl_permutation *perm = gsl_permutation_alloc(8);
        int sign;
        gsl_linalg_LU_decomp(&A.matrix, perm, &sign);
        gsl_linalg_LU_solve(&A.matrix, perm, &b.vector, &xv.vector);
        gsl_permutation_free(perm);
        for (int i = 0; i < 3; i++)
            assert_near(x[i], fb_g[i], 1e-12, 1e-12);
        double G[3][4], E[3][4], w[3] = {0, 0, 0}, wd[3] = {0, 0, 0}, jw[3], jwd[3], gyro[3];
        nik_G(p, G, false);
        nik_G(p, E, true);
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 4; k++) {
                w[i] += 2 * G[i][k] * pd[k];
                wd[i] += 2 * G[i][k] * x[3 + k];
            }
        for (int i = 0; i < 3; i++) {
            jw[i] = jwd[i] = 0;
            for (int j = 0; j < 3; j++) {
                jw[i] += fb_J[i][j] * w[j];
                jwd[i] += fb_J[i][j] * wd[j];
            }
        }
        cross(w, jw, gyro);
        /* n' = A^T tau, A = E G^T */
        double tau[3] = {0.2 + q[0], -0.3 * t, 0.1 * qd[4]}, nb[3];
        for (int i = 0; i < 3; i++) {
            nb[i] = 0;
            for (int j = 0; j < 3; j++) {
                double a = 0;
                for (int k = 0; k < 4; k++)
                    a += E[j][k] * G[i][k];     /* A(j, i) */
                nb[i] += a * tau[j];
            }
        }
        for (int i = 0; i < 3; i++)
            assert_near(jwd[i] + gyro[i], nb[i], 1e-11, 1e-11);
    }
    engine_close(&e);
    pipeline_free(mech);
}

/* The velocity terms are Lagrange's of T = 1/2 qd^T M(q) qd:
   Q(q, qd) - Q(q, 0) = -(Mdot qd - 1/2 d(qd^T M qd)/dq) with Mdot and
   dM/dq by central differences of the generated M (the file's forces do
   not depend on qd). Bodies with their centres of mass off their origins,
   so the translation couples to the Euler parameters. */
static void test_velocity_terms_from_energy(void **state)
{
    (void)state;
    Mech *mech = load_text("spatial\n"
                           "body a x = 0.2 y = 0.1 z = 0.05 orient = axis(1, 1, 0, 0.3)\n"
                           "body b x = 1.1 y = -0.2 z = 0.4\n"
                           "spherical O: ground(0, 0, 0) a(-0.2, 0, 0)\n"
                           "mass a m = 1.2 J = (0.01, 0.03, 0.035) Jxz = 0.002 com(0.1, -0.05, 0.02)\n"
                           "mass b m = 0.7 J = (0.02, 0.025, 0.01) com(0, 0.3, -0.1)\n"
                           "gravity (0, 0, -9.81)\n", "lagrange.mech");
    int nq = mech->model->nq;
    Engine e;
    open_engine(&e, ENGINE_JIT, mech);
    double *q = xcalloc((size_t)nq, 8), *qd = xcalloc((size_t)nq, 8), *zero = xcalloc((size_t)nq, 8);
    double *Q = xcalloc((size_t)nq, 8), *Q0 = xcalloc((size_t)nq, 8), *w = xcalloc((size_t)nq, 8);
    double *Mp = xcalloc((size_t)nq * nq, 8), *Mm = xcalloc((size_t)nq * nq, 8);
    double *lag = xcalloc((size_t)nq, 8);
    uint64_t rng = 29;
    const double h = 1e-6;
    for (int s = 0; s < 5; s++) {
        for (int i = 0; i < nq; i++) {
            q[i] = mech->model->q0[i] + 0.5 * rng_symmetric(&rng);
            qd[i] = 2 * rng_symmetric(&rng);
        }
        e.k.force(e.k.ctx, q, qd, 0.0, Q);
        e.k.force(e.k.ctx, q, zero, 0.0, Q0);
        memset(lag, 0, (size_t)nq * 8);
        /* Mdot qd = (M(q + h qd) - M(q - h qd)) qd / 2h */
        for (int i = 0; i < nq; i++)
            w[i] = q[i] + h * qd[i];
        e.k.mass(e.k.ctx, w, Mp);
        for (int i = 0; i < nq; i++)
            w[i] = q[i] - h * qd[i];
        e.k.mass(e.k.ctx, w, Mm);
        for (int i = 0; i < nq; i++)
            for (int j = 0; j < nq; j++)
                lag[i] -= (Mp[i * nq + j] - Mm[i * nq + j]) / (2 * h) * qd[j];
        /* + 1/2 d(qd^T M qd)/dq_k */
        for (int k = 0; k < nq; k++) {
            memcpy(w, q, (size_t)nq * 8);
            w[k] += h;
            e.k.mass(e.k.ctx, w, Mp);
            w[k] -= 2 * h;
            e.k.mass(e.k.ctx, w, Mm);
            double d = 0;
            for (int i = 0; i < nq; i++)
                for (int j = 0; j < nq; j++)
                    d += qd[i] * (Mp[i * nq + j] - Mm[i * nq + j]) * qd[j];
            lag[k] += 0.5 * d / (2 * h);
        }
        for (int i = 0; i < nq; i++)
            assert_near(Q[i] - Q0[i], lag[i], 1e-6, 1e-6);
    }
    engine_close(&e);
    free(q), free(qd), free(zero), free(Q), free(Q0), free(w), free(Mp), free(Mm), free(lag);
    pipeline_free(mech);
}

/* A spatial body whose centre of mass is its origin: M is constant in
   the translation (m on the diagonal, nothing coupling it to e). */
static void test_translation_constant(void **state)
{
    (void)state;
    Mech *mech = load_text(free_body, "free_body.mech");
    const Dynamics *dyn = &mech->kin.dyn;
    int coupled = 0, constant = 0;
    for (int k = 0; k < dyn->nnz; k++) {
        const JacEntry *en = &dyn->mass[k];
        double v;
        if ((en->row < 3) != (en->col < 3))
            coupled++;
        if (en->row < 3 && dag_is_const(&mech->model->dag, en->value, &v) && v == 1.7)
            constant++;
    }
    assert_int_equal(coupled, 0);
    assert_int_equal(constant, 3);
    assert_int_equal(dyn->nnz, 3 + 16);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_free_body_nikravesh),
        cmocka_unit_test(test_free_body_euler),
        cmocka_unit_test(test_velocity_terms_from_energy),
        cmocka_unit_test(test_translation_constant),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
