/* test_step_lup.c - runtime/step_lup.c: steps through the pattern LU against mechrt_step. */
#include "testrt.h"

/* The slider crank's Jacobian has zeros at (1, 2), (2, 1) and (2, 2). */
static const int sc_row[6] = {0, 0, 0, 1, 1, 2}, sc_col[6] = {0, 1, 2, 0, 1, 0};

static void sc_jac_nz(void *ctx, const double *q, double t, double *vals)
{
    double jac[9];
    sc_jac(ctx, q, t, jac);
    for (int e = 0; e < 6; e++)
        vals[e] = jac[sc_row[e] * 3 + sc_col[e]];
}

static const MechrtJacNz sc_jnz = {6, sc_row, sc_col, NULL, sc_jac_nz};

static void report_equal(const MechrtReport *a, const MechrtReport *b)
{
    assert_int_equal(a->iterations, b->iterations);
    assert_true(a->residual == b->residual);
    assert_true(a->step == b->step);
    assert_int_equal(a->worst_row, b->worst_row);
    assert_int_equal(a->sing_index, b->sing_index);
    assert_true(a->cond == b->cond);
    assert_int_equal(a->cond_warning, b->cond_warning);
    assert_int_equal(a->factorisations, b->factorisations);
}

/* mechrt_step_lup against mechrt_step: the same states and reports, bit
   for bit, in coarse and fine steps, with the condition estimate always
   on, through jac_nz, `all` and phi + jac. */
static void test_step_lup(void **state)
{
    (void)state;
    static double lw[MECHRT_LUP_WORK_LEN(3)];
    static int liw[MECHRT_LUP_IWORK_LEN(3)];
    const MechrtJacNz *jn[3] = {&sc_jnz, NULL, NULL};
    const MechrtKernels *ks[3] = {&sc_kernels_noall, &sc_kernels, &sc_kernels_noall};
    MechrtOptions o = mechrt_default_options();
    double work[64], work2[64];

    o.cond_screen = 0;
    for (int v = 0; v < 3; v++) {
        for (int steps = 20; steps <= 2000; steps *= 100) {
            double q[3], qd[3], qdd[3], p[3], pd[3], pdd[3], t = 0, h = 1.0 / steps;
            MechrtReport rd, rp;
            MechrtLup f;
            assert_int_equal(mechrt_lup_init(&f, 3, 6, sc_row, sc_col, lw, MECHRT_LUP_WORK_LEN(3),
                                             liw, MECHRT_LUP_IWORK_LEN(3)), MECHRT_OK);
            sc_exact(0, q, qd, qdd);
            q[0] += 0.1;   /* assembly first: h = 0 */
            memcpy(p, q, sizeof q), memcpy(pd, qd, sizeof qd), memcpy(pdd, qdd, sizeof qdd);
            for (int s = 0; s <= steps; s++) {
                double hh = s == 0 ? 0 : h;
                assert_int_equal(mechrt_step_lup(ks[v], jn[v], &f, &o, p, pd, pdd, t, hh, work2,
                                                 64, &rp),
                                 mechrt_step(ks[v], &o, q, qd, qdd, t, hh, work, 64, &rd));
                report_equal(&rp, &rd);
                assert_true(rp.cond > 1);
                for (int i = 0; i < 3; i++)
                    assert_true(p[i] == q[i] && pd[i] == qd[i] && pdd[i] == qdd[i]);
                t += hh;
            }
            assert_true(f.replays > f.analyses);
        }
    }
    /* arguments */
    MechrtLup f;
    double q[3] = {1, 2, 3}, qd[3] = {0}, qdd[3] = {0};
    MechrtReport r;
    assert_int_equal(mechrt_lup_init(&f, 3, 6, sc_row, sc_col, lw, MECHRT_LUP_WORK_LEN(3), liw,
                                     MECHRT_LUP_IWORK_LEN(3)), MECHRT_OK);
    assert_int_equal(mechrt_step_lup(&sc_kernels, &sc_jnz, &f, NULL, q, qd, qdd, 0, 0, work, 10,
                                     &r), MECHRT_EBADLEN);
    assert_int_equal(mechrt_step_lup(&kn_kernels, NULL, &f, NULL, q, qd, qdd, 0, 0, work, 64, &r),
                     MECHRT_ENOTSQUARE);
    assert_int_equal(mechrt_step_lup(&sc_kernels, &sc_jnz, NULL, NULL, q, qd, qdd, 0, 0, work, 64,
                                     &r), MECHRT_EINVAL);
    assert_int_equal(mechrt_step_lup(&sc_kernels, &sc_jnz, &f, NULL, q, qd, qdd, 0, NAN, work, 64,
                                     &r), MECHRT_EINVAL);
}

/* Through a singular configuration (the circle's dead point at y = 0):
   the same statuses, reports and iterates as mechrt_step. */
static void test_step_lup_singular(void **state)
{
    (void)state;
    static const int row[3] = {0, 0, 1}, col[3] = {0, 1, 0};
    double lw[MECHRT_LUP_WORK_LEN(2)], work[32], work2[32];
    int liw[MECHRT_LUP_IWORK_LEN(2)];
    MechrtLup f;
    /* the dead point at t* = (pi - c) / w, where a step lands */
    double q[2], qd[2] = {0}, qdd[2] = {0}, p[2], pd[2] = {0}, pdd[2] = {0}, t = 0;
    double h = (3.14159265358979323846 - CI_C) / CI_W / 46;
    MechrtReport rd, rp;
    int fails = 0;

    assert_int_equal(mechrt_lup_init(&f, 2, 3, row, col, lw, MECHRT_LUP_WORK_LEN(2), liw,
                                     MECHRT_LUP_IWORK_LEN(2)), MECHRT_OK);
    q[0] = p[0] = CI_R * cos(CI_C);
    q[1] = p[1] = CI_R * sin(CI_C);
    for (int s = 0; s < 60; s++) {
        MechrtStatus sd = mechrt_step(&ci_kernels, NULL, q, qd, qdd, t, h, work, 32, &rd);
        MechrtStatus sp = mechrt_step_lup(&ci_kernels, NULL, &f, NULL, p, pd, pdd, t, h, work2, 32,
                                          &rp);
        assert_int_equal(sp, sd);
        report_equal(&rp, &rd);
        assert_true(p[0] == q[0] && p[1] == q[1]);
        if (sd != MECHRT_OK) {
            fails++;
            break;
        }
        assert_true(pd[0] == qd[0] && pd[1] == qd[1] && pdd[0] == qdd[0] && pdd[1] == qdd[1]);
        t += h;
    }
    assert_int_equal(fails, 1);   /* it does reach the dead point (EMAXITER) */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step_lup),
        cmocka_unit_test(test_step_lup_singular),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
