/* test_lu_gen.c - the unrolled LU (emit_lu.c, PREFIX_lu_factor/_lu_solve) against the runtime's dense LU, and the step on it.
 *
 * The generated factor and solve, compiled by the JIT, must give the dense
 * LU's solutions to rounding wherever their pivot checks pass, decline
 * (nonzero) where a pivot of their fixed order vanishes or an entry is not
 * finite, and mechrt_step_lup with them must step as without them: the
 * same states to 1e-12, every factorisation theirs along a smooth motion,
 * the pattern LU's (bit for bit the dense LU's) where they decline.
 */
#include "testutil.h"
#include "testload.h"

#include "../generator/base/arena.h"
#include "../generator/engine/engine.h"

#include <stdlib.h>
#include <string.h>

static int setup(void **s)
{
    (void)s;
    setenv("XDG_CACHE_HOME", "/tmp/mechc-test-cache", 1);
    return 0;
}

/* examples/file with its JIT engine in e, which has the unrolled LU. */
static Mech *open_example(const char *file, Engine *e)
{
    Mech *mech = load_example(file);
    Diag diag;
    assert_true(engine_open(e, ENGINE_JIT, mech, &diag));
    assert_non_null(e->kernels.lu_factor);
    assert_non_null(e->kernels.lu_solve);
    return mech;
}

/* x = A^-1 b by the runtime's dense LU (partial pivoting). */
static void dense_solve(int n, const double *jac, const double *b, double *x)
{
    double *a = xcalloc((size_t)n * (size_t)n, sizeof *a), *piv = xcalloc((size_t)n, sizeof *piv);
    memcpy(a, jac, (size_t)n * (size_t)n * sizeof *a);
    assert_int_equal(mechrt_lu_factor(n, a, n, piv, 1e-12, NULL), MECHRT_OK);
    memcpy(x, b, (size_t)n * sizeof *x);
    mechrt_lu_solve(n, a, n, piv, x);
    free(a), free(piv);
}

/* At states around q0, wherever the factor accepts its order, its solve
   is the dense LU's to 1e-12 (relative to the solution's size); it
   accepts most of them. */
static void test_solves_match_dense(void **s)
{
    (void)s;
    const char *files[] = {"slider_crank.mech", "four_bar.mech", "five_bar.mech",
                           "elliptical_trammel.mech"};
    for (size_t f = 0; f < sizeof files / sizeof *files; f++) {
        Engine e;
        Mech *mech = open_example(files[f], &e);
        const Model *m = mech->model;
        int n = m->nq, nnz = mech->kin.nnz, accepted = 0, trials = 200;
        double *q = xcalloc((size_t)n, sizeof *q), *jac = xcalloc((size_t)n * (size_t)n, sizeof *jac);
        double *vals = xcalloc((size_t)nnz, sizeof *vals), *lu = xcalloc((size_t)n * (size_t)n, sizeof *lu);
        double *b = xcalloc((size_t)n, sizeof *b), *x = xcalloc((size_t)n, sizeof *x);
        double *y = xcalloc((size_t)n, sizeof *y), spread;
        unsigned seed = 12345;
        for (int trial = 0; trial < trials; trial++) {
            for (int i = 0; i < n; i++) {
                seed = seed * 1103515245u + 12345u;
                q[i] = m->q0[i] + 0.6 * ((double)(seed >> 8 & 0xffff) / 65535.0 - 0.5);
                seed = seed * 1103515245u + 12345u;
                b[i] = (double)(seed >> 8 & 0xffff) / 65535.0 - 0.5;
            }
            e.kernels.jac(q, 0.3, jac);
            e.kernels.jac_nz(q, 0.3, vals);
            if (e.kernels.lu_factor(vals, lu, 1e-12, &spread) != 0)
                continue;
            accepted++;
            assert_true(spread >= 1);
            e.kernels.lu_solve(lu, b, x);
            dense_solve(n, jac, b, y);
            double size = 0;
            for (int i = 0; i < n; i++)
                size = fmax(size, fabs(y[i]));
            for (int i = 0; i < n; i++)
                assert_near(x[i], y[i], 0.0, 1e-12 * size);
        }
        assert_true(accepted >= trials * 3 / 4);
        free(q), free(jac), free(vals), free(lu), free(b), free(x), free(y);
        engine_close(&e);
        pipeline_free(mech);
    }
}

/* A pattern LU for e's Jacobian (one block: free it), with e's unrolled
   LU when gen > 0, and its step when gen > 1. */
static MechrtLup *lup_new(const Engine *e, const Mech *mech, int gen, MechrtLuGen *g)
{
    int n = mech->model->nq;
    size_t lw = mechrt_lup_work_size(n), liw = mechrt_lup_iwork_size(n);
    MechrtLup *f = xcalloc(1, sizeof *f + lw * sizeof(double) + liw * sizeof(int));
    double *w = (double *)(f + 1);
    assert_int_equal(mechrt_lup_init(f, n, mech->kin.nnz, e->kernels.jac_row, e->kernels.jac_col,
                                     w, lw, (int *)(w + lw), liw), MECHRT_OK);
    *g = engine_jac_nz(e)->lu;      /* the engine's unrolled LU and step */
    if (gen < 2)
        g->step = NULL;
    if (gen > 0)
        assert_int_equal(mechrt_lup_use(f, g), MECHRT_OK);
    return f;
}

/* Away from q0 the four-bar's fixed order meets pivots below a tenth of
   their column (a few percent of random states within 1 of q0): the
   factor declines there, and mechrt_lup_factor factors by the pattern LU,
   whose solve is the dense LU's bit for bit. A NaN entry: -1. */
static void test_declines(void **s)
{
    (void)s;
    Engine e;
    Mech *mech = open_example("four_bar.mech", &e);
    int n = mech->model->nq, declined = 0;
    double q[9], jac[81], vals[64], lu[81], spread, b[9], x[9], y[9];
    assert_int_equal(n, 9);
    assert_true(mech->kin.nnz <= 64);
    MechrtLuGen g;
    MechrtLup *f = lup_new(&e, mech, 1, &g);
    MechrtLuGen none = {n * n, NULL, NULL, NULL, NULL};
    assert_int_equal(mechrt_lup_use(f, &none), MECHRT_EINVAL);   /* no functions */
    unsigned seed = 777;
    for (int trial = 0; trial < 2000 && declined < 5; trial++) {
        for (int i = 0; i < n; i++) {
            seed = seed * 1103515245u + 12345u;
            q[i] = mech->model->q0[i] + 2.0 * ((double)(seed >> 8 & 0xffff) / 65535.0 - 0.5);
            b[i] = 1.0 + i;
        }
        e.kernels.jac_nz(q, 0, vals);
        if (e.kernels.lu_factor(vals, lu, 1e-12, &spread) == 0)
            continue;
        e.kernels.jac_nz(q, 0, mechrt_lup_values(f));
        if (mechrt_lup_factor(f, 1e-12, NULL) != MECHRT_OK)
            continue;   /* singular there: nothing to compare */
        declined++;
        assert_false(f->gen_now);
        mechrt_lup_solve(f, b, x);
        e.kernels.jac(q, 0, jac);
        dense_solve(n, jac, b, y);
        for (int i = 0; i < n; i++)
            assert_true(x[i] == y[i]);
    }
    assert_int_equal(declined, 5);

    memcpy(q, mech->model->q0, sizeof q);
    e.kernels.jac_nz(q, 0, vals);
    assert_int_equal(e.kernels.lu_factor(vals, lu, 1e-12, &spread), 0);
    for (int k = 0; k < mech->kin.nnz; k++) {   /* an entry that varies with q */
        double v;
        if (!dag_is_const(&mech->model->dag, mech->kin.jac[k].value, &v)) {
            vals[k] = NAN;
            break;
        }
    }
    assert_int_equal(e.kernels.lu_factor(vals, lu, 1e-12, &spread), -1);

    /* P_step declines without touching the state: a NaN velocity, and too
       few iterations allowed */
    double st[27], before[27], tol[4] = {1e-8, 1e-8, 1e-12, 1e4}, out[2];
    int iout[2];
    memcpy(st, mech->model->q0, 9 * sizeof *st);
    for (int i = 9; i < 27; i++)
        st[i] = 0;
    assert_int_equal(e.kernels.step(st, st + 9, st + 18, 0, 0, tol, 25, out, iout), 0);
    st[9] = NAN;
    memcpy(before, st, sizeof st);
    assert_true(e.kernels.step(st, st + 9, st + 18, 0, 0.01, tol, 25, out, iout) != 0);
    assert_memory_equal(st, before, sizeof st);
    st[9] = 0;
    memcpy(before, st, sizeof st);
    assert_true(e.kernels.step(st, st + 9, st + 18, 0, 0.01, tol, 0, out, iout) != 0);
    assert_memory_equal(st, before, sizeof st);
    free(f);
    engine_close(&e);
    pipeline_free(mech);
}

/* mechrt_step_lup with the unrolled LU steps as without it: the same
   Newton iterations and states to 1e-12, every factorisation the
   unrolled LU's; with the kernels' P_step too, the same numbers as with
   the unrolled LU alone, bit for bit, and the same reports. */
static void test_step(void **s)
{
    (void)s;
    const char *files[] = {"slider_crank.mech", "four_bar.mech", "five_bar.mech"};
    for (size_t c = 0; c < sizeof files / sizeof *files; c++) {
        Engine e;
        Mech *mech = open_example(files[c], &e);
        const Model *m = mech->model;
        int n = m->nq, steps = 400;
        MechrtLuGen g[3];
        MechrtLup *f[3];
        const MechrtJacNz *jnz = &engine_jac_nz(&e)->jac;
        size_t lwork = mechrt_workspace_size(n, n);
        double *work = xcalloc(lwork, sizeof *work), *st[3];
        for (int v = 0; v < 3; v++) {
            f[v] = lup_new(&e, mech, v, &g[v]);
            st[v] = xcalloc(3 * (size_t)n, sizeof *st[v]);
            memcpy(st[v], m->q0, (size_t)n * sizeof *st[v]);
        }
        for (int k = 0; k <= steps; k++) {
            double t = k == 0 ? 0 : (k - 1) / (double)steps, h = k == 0 ? 0 : 1.0 / steps;
            MechrtReport r[3];
            for (int v = 0; v < 3; v++)
                assert_int_equal(mechrt_step_lup(&e.k, jnz, f[v], NULL, st[v], st[v] + n,
                                                 st[v] + 2 * n, t, h, work, lwork, &r[v]),
                                 MECHRT_OK);
            assert_int_equal(r[0].iterations, r[1].iterations);
            assert_int_equal(r[1].iterations, r[2].iterations);
            assert_int_equal(r[1].worst_row, r[2].worst_row);
            assert_int_equal(r[1].factorisations, r[2].factorisations);
            assert_true(r[1].residual == r[2].residual && r[1].step == r[2].step);
            for (int i = 0; i < 3 * n; i++) {
                assert_near(st[1][i], st[0][i], 1e-12, 1e-12);
                assert_true(st[2][i] == st[1][i]);
            }
        }
        assert_true(f[1]->gen_factors >= 2 * steps);
        assert_int_equal(f[1]->analyses + f[1]->replays, 0);
        assert_int_equal(f[2]->gen_factors, f[1]->gen_factors);
        assert_int_equal(f[0]->gen_factors, 0);
        free(work);
        for (int v = 0; v < 3; v++)
            free(st[v]), free(f[v]);
        engine_close(&e);
        pipeline_free(mech);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_solves_match_dense),
        cmocka_unit_test(test_declines),
        cmocka_unit_test(test_step),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
