/* test_lib.c - libmechc's public API (generator/lib/mechc.h): loading, names, kernels, batches, run, sim, info, errors.
 *
 * Uses mechc.h, as a program embedding the library would (and
 * testcache.h for the aot engine's cache, run_all's). Runs from
 * the repository root (examples/ relative), like `make check`. The
 * reference values are what `mechc run` and `mechc sim` print for the
 * same files (their JSON, 17 digits).
 */
#include "testutil.h"

#include "../generator/lib/mechc.h"
#include "testcache.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

static mechc_model *load(const char *path)
{
    mechc_diag d;
    mechc_model *m = mechc_load_file(path, &d);
    if (!m)
        fail_msg("%s:%d:%d: %s", d.file, d.line, d.column, d.message);
    assert_int_equal(d.status, MECHC_OK);
    return m;
}

static mechc_kernels *compile(mechc_model *m, const char *engine)
{
    mechc_diag d;
    mechc_kernels *k = mechc_compile(m, engine, &d);
    if (!k)
        fail_msg("%s: %s", engine, d.message);
    return k;
}

static void sizes_and_names(void **state)
{
    (void)state;
    mechc_model *m = load("examples/four_bar.mech");
    assert_int_equal(mechc_nq(m), 9);
    assert_int_equal(mechc_nh(m), 9);
    assert_int_equal(mechc_nv(m), 0);
    assert_int_equal(mechc_nr(m), 9);
    assert_int_equal(mechc_nout(m), 0);
    assert_int_equal(mechc_nbodies(m), 3);
    assert_int_equal(mechc_np(m), 0);
    assert_int_equal(mechc_has_dynamics(m), 0);
    assert_string_equal(mechc_model_name(m), "four_bar");
    assert_string_equal(mechc_coord_name(m, 2), "crank.phi");
    assert_string_equal(mechc_coord_name(m, 8), "rocker.phi");
    assert_null(mechc_coord_name(m, 9));
    assert_null(mechc_coord_name(m, -1));
    assert_string_equal(mechc_row_name(m, 0), "O2.x");
    assert_string_equal(mechc_row_name(m, 8), "drive");
    assert_string_equal(mechc_body_name(m, 1), "coupler");
    assert_int_equal(mechc_coord_index(m, "coupler.phi"), 5);
    assert_int_equal(mechc_coord_index(m, "nothing"), -1);
    int first, count;
    assert_int_equal(mechc_body_coords(m, 2, &first, &count), MECHC_OK);
    assert_int_equal(first, 6);
    assert_int_equal(count, 3);
    assert_near(mechc_q0(m)[4], 1.2402, 0, 0);
    mechc_model_free(m);
}

/* Phi vanishes at the file's initial values to their 4 decimals, on every engine. */
static void phi_at_q0(void **state)
{
    (void)state;
    mechc_model *m = load("examples/four_bar.mech");
    const char *engines[] = {"jit", "generic", NULL};
    for (int e = 0; engines[e]; e++) {
        mechc_kernels *k = compile(m, engines[e]);
        assert_string_equal(mechc_kernels_engine(k), engines[e]);
        double phi[9];
        assert_int_equal(mechc_phi(k, mechc_q0(m), 0, phi), MECHC_OK);
        for (int i = 0; i < 9; i++)
            assert_near(phi[i], 0, 0, 2e-4);
        mechc_kernels_free(k);
    }
    mechc_model_free(m);
}

/* The Jacobian against central differences of phi, and its nonzeros against the dense one. */
static void jacobian(void **state)
{
    (void)state;
    mechc_model *m = load("examples/four_bar.mech");
    mechc_kernels *k = compile(m, "jit");
    double q[9], jac[81], pp[9], pm[9];
    memcpy(q, mechc_q0(m), sizeof q);
    q[2] = 0.3;
    double t = 0.1;
    assert_int_equal(mechc_jacobian(k, q, t, jac), MECHC_OK);
    for (int j = 0; j < 9; j++) {
        double h = 1e-6, keep = q[j];
        q[j] = keep + h;
        mechc_phi(k, q, t, pp);
        q[j] = keep - h;
        mechc_phi(k, q, t, pm);
        q[j] = keep;
        for (int i = 0; i < 9; i++)
            assert_near(jac[i * 9 + j], (pp[i] - pm[i]) / (2 * h), 0, 1e-8);
    }
    int nnz = mechc_jacobian_nz(k);
    assert_true(nnz > 9 && nnz < 81);
    int *rows = malloc((size_t)nnz * sizeof *rows), *cols = malloc((size_t)nnz * sizeof *cols);
    double *vals = malloc((size_t)nnz * sizeof *vals);
    assert_int_equal(mechc_jacobian_pattern(k, rows, cols), MECHC_OK);
    assert_int_equal(mechc_jacobian_values(k, q, t, vals), MECHC_OK);
    double sum = 0;
    for (int i = 0; i < nnz; i++) {
        assert_near(vals[i], jac[rows[i] * 9 + cols[i]], 1e-15, 0);
        sum += fabs(vals[i]);
    }
    double dense = 0;
    for (int i = 0; i < 81; i++)
        dense += fabs(jac[i]);
    assert_near(sum, dense, 1e-14, 0);      /* no nonzero outside the pattern */
    free(rows), free(cols), free(vals);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

static TestCache cache;

/* A batch call through engine equals the single calls, with one time for
   all or one each; N states: blocks of lanes, a tail and, on the aot
   engine (whose unit has the generated batch kernels), two runs of them
   (generator/lib/batch.c). */
static void check_batches(const char *engine)
{
    mechc_model *m = load("examples/four_bar.mech");
    mechc_kernels *k = compile(m, engine);
    enum { N = 301 };
    double *q = calloc(N * 9, sizeof *q), *qd = calloc(N * 9, sizeof *qd), t[N], g1[9], j1[81];
    double *g = calloc(N * 9, sizeof *g), *jac = calloc(N * 81, sizeof *jac);
    double *phi = calloc(N * 9, sizeof *phi), *nu = calloc(N * 9, sizeof *nu), p1[9], n1[9];
    double *g2 = calloc(N * 9, sizeof *g2);
    for (int i = 0; i < N; i++) {
        t[i] = 0.01 * i;
        for (int j = 0; j < 9; j++) {
            q[i * 9 + j] = mechc_q0(m)[j] + 0.001 * i * j;
            qd[i * 9 + j] = 0.5 + 0.1 * j - 0.002 * i;
        }
    }
    assert_int_equal(mechc_gamma_batch(k, N, q, qd, t, N, g), MECHC_OK);
    assert_int_equal(mechc_all_batch(k, N, q, qd, t, 1, phi, jac, nu, g2), MECHC_OK);
    for (int i = 0; i < N; i++) {
        mechc_gamma(k, q + i * 9, qd + i * 9, t[i], g1);
        for (int r = 0; r < 9; r++)
            assert_true(g[i * 9 + r] == g1[r]);
        mechc_all(k, q + i * 9, qd + i * 9, t[0], p1, j1, n1, g1);
        for (int r = 0; r < 81; r++)
            assert_true(jac[i * 81 + r] == j1[r]);
        for (int r = 0; r < 9; r++)
            assert_true(phi[i * 9 + r] == p1[r] && nu[i * 9 + r] == n1[r]
                        && g2[i * 9 + r] == g1[r]);
    }
    assert_int_equal(mechc_all_batch(k, N, q, qd, t, 1, phi, jac, NULL, NULL), MECHC_OK);
    assert_int_equal(mechc_phi_batch(k, N, q, t, N, phi), MECHC_OK);
    assert_int_equal(mechc_jacobian_batch(k, N, q, t, 1, jac), MECHC_OK);
    for (int i = 0; i < N; i += 50) {
        mechc_phi(k, q + i * 9, t[i], p1);
        mechc_jacobian(k, q + i * 9, t[0], j1);
        for (int r = 0; r < 9; r++)
            assert_true(phi[i * 9 + r] == p1[r]);
        for (int r = 0; r < 81; r++)
            assert_true(jac[i * 81 + r] == j1[r]);
    }
    assert_int_equal(mechc_gamma_batch(k, N, q, qd, t, 3, g), MECHC_EARG);
    assert_int_equal(mechc_phi_batch(k, 0, NULL, NULL, 0, NULL), MECHC_OK);
    free(q), free(qd), free(g), free(jac), free(phi), free(nu), free(g2);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

static void batches(void **state)
{
    (void)state;
    check_batches("jit");
    if (cache.have_cc && !getenv("MECHC_SKIP_GCC_ONLY"))
        check_batches("aot");
}

static int setup(void **state) { (void)state; return testcache_setup(&cache, "lib"); }
static int teardown(void **state) { (void)state; return testcache_teardown(&cache); }

/* The three engines agree: jit and aot to the last bits of their
   arithmetic, the interpreter to rounding. */
static void engines_agree(void **state)
{
    (void)state;
    mechc_model *m = load("examples/slider_crank_dynamics.mech");
    int nq = mechc_nq(m), nr = mechc_nr(m);
    const char *engines[] = {"jit", "generic", "aot"};
    /* one block per engine: phi, jac, nu, gamma, Q */
    enum { PHI = 0, JAC = 16, NU = JAC + 16 * 16, GAMMA = NU + 16, FORCE = GAMMA + 16,
           SIZE = FORCE + 16 };
    double q[16], qd[16], out[3][SIZE];
    assert_true(nq <= 16 && nr <= 16);
    for (int j = 0; j < nq; j++)
        q[j] = mechc_q0(m)[j] + 0.01 * j, qd[j] = 0.3 - 0.1 * j;
    int n = cache.have_cc && !getenv("MECHC_SKIP_GCC_ONLY") ? 3 : 2;
    for (int e = 0; e < n; e++) {
        mechc_kernels *k = compile(m, engines[e]);
        double *o = out[e];
        assert_int_equal(mechc_all(k, q, qd, 0.2, o + PHI, o + JAC, o + NU, NULL), MECHC_OK);
        assert_int_equal(mechc_gamma(k, q, qd, 0.2, o + GAMMA), MECHC_OK);
        assert_int_equal(mechc_force(k, q, qd, 0.2, o + FORCE), MECHC_OK);
        mechc_kernels_free(k);
    }
    for (int e = 1; e < n; e++) {
        for (int i = 0; i < mechc_nh(m); i++)
            assert_near(out[e][PHI + i], out[0][PHI + i], 1e-12, 1e-14);
        for (int i = 0; i < nr * nq; i++)
            assert_near(out[e][JAC + i], out[0][JAC + i], 1e-12, 1e-14);
        for (int i = 0; i < nr; i++) {
            assert_near(out[e][NU + i], out[0][NU + i], 1e-12, 1e-14);
            assert_near(out[e][GAMMA + i], out[0][GAMMA + i], 1e-12, 1e-12);
        }
        for (int i = 0; i < nq; i++)
            assert_near(out[e][FORCE + i], out[0][FORCE + i], 1e-12, 1e-12);
    }
    mechc_model_free(m);
}

/* mechc_compile_with: aot compiled afresh though its cache holds the
   library, the same kernels. */
static void compile_with_options(void **state)
{
    (void)state;
    mechc_compile_options o = mechc_compile_defaults();
    assert_int_equal(o.aot_fresh, 0);
    mechc_model *m = load("examples/four_bar.mech");
    mechc_diag d;
    assert_null(mechc_compile_with(m, "llvm", &o, &d));
    assert_int_equal(d.status, MECHC_EARG);
    o.aot_fresh = 1;
    const char *engine = cache.have_cc && !getenv("MECHC_SKIP_GCC_ONLY") ? "aot" : "generic";
    mechc_kernels *cached = compile(m, engine), *fresh = mechc_compile_with(m, engine, &o, &d);
    assert_non_null(fresh);
    assert_string_equal(mechc_kernels_engine(fresh), engine);
    double a[9], b[9];
    assert_int_equal(mechc_phi(cached, mechc_q0(m), 0.3, a), MECHC_OK);
    assert_int_equal(mechc_phi(fresh, mechc_q0(m), 0.3, b), MECHC_OK);
    assert_memory_equal(a, b, sizeof a);
    mechc_kernels_free(fresh);
    mechc_kernels_free(cached);
    mechc_model_free(m);
}

/* The outputs of examples/rssr.mech at a run's states, one by one and in one call. */
static void outputs(void **state)
{
    (void)state;
    mechc_model *m = load("examples/rssr.mech");
    int nq = mechc_nq(m), no = mechc_nout(m);
    assert_true(no > 0);
    mechc_kernels *k = compile(m, "jit");
    mechc_run_options o = mechc_run_defaults();
    o.steps = 6;
    mechc_result *r = mechc_run(k, &o, NULL);
    assert_non_null(r);
    int n = mechc_result_states(r);
    double *y = malloc((size_t)(3 * n * no) * sizeof *y), one[3][64];
    assert_true(no <= 64);
    assert_int_equal(mechc_outputs_batch(k, (size_t)n, mechc_result_q(r), mechc_result_qd(r),
                                         mechc_result_qdd(r), mechc_result_time(r), (size_t)n,
                                         y, y + n * no, y + 2 * n * no),
                     MECHC_OK);
    for (int i = 0; i < n; i++) {
        mechc_outputs(k, mechc_result_q(r) + i * nq, mechc_result_qd(r) + i * nq,
                      mechc_result_qdd(r) + i * nq, mechc_result_time(r)[i], one[0], one[1],
                      one[2]);
        for (int j = 0; j < no; j++) {
            assert_true(y[i * no + j] == mechc_result_y(r)[i * no + j]);
            assert_true(y[i * no + j] == one[0][j]);
            assert_true(y[(n + i) * no + j] == mechc_result_yd(r)[i * no + j]);
            assert_true(y[(2 * n + i) * no + j] == one[2][j]);
        }
    }
    assert_non_null(mechc_output_name(m, 0));
    free(y);
    mechc_result_free(r);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

/* The diagnostic of a broken text as a value: file, line, column, message. */
static void diagnostics(void **state)
{
    (void)state;
    mechc_diag d;
    mechc_model *m = mechc_load_string("mechanism m\nbody b x = 0 y = 0 phi = 0\n"
                                       "revolute R: ground(0, 0) b(0 0)\n", "bad.mech", &d);
    assert_null(m);
    assert_int_equal(d.status, MECHC_EINPUT);
    assert_string_equal(d.file, "bad.mech");
    assert_int_equal(d.line, 3);
    assert_int_equal(d.column, 30);
    assert_non_null(strstr(d.message, "expected ','"));
    assert_null(mechc_load_file("examples/no_such_file.mech", &d));
    assert_int_equal(d.status, MECHC_EINPUT);
    assert_true(d.message[0] != '\0');
    assert_null(mechc_load_file(NULL, NULL));
}

/* Loading with limits: the command's --max-... and the line a caret goes under. */
static void load_with_limits(void **state)
{
    (void)state;
    mechc_diag d;
    char line[MECHC_DIAG_LINE_MAX] = "x";
    mechc_limits l = mechc_default_limits();
    assert_int_equal(l.max_coords, 200000);
    assert_int_equal(l.max_file_bytes, 4 << 20);
    mechc_model *m = mechc_load_file_with("examples/four_bar.mech", &l, &d, line);
    assert_non_null(m);
    assert_string_equal(line, "");
    mechc_model_free(m);
    l.max_coords = 2;
    assert_null(mechc_load_file_with("examples/four_bar.mech", &l, &d, line));
    assert_int_equal(d.status, MECHC_EINPUT);
    assert_string_equal(d.message, "too many coordinates (the limit is 2)");
    assert_int_equal(d.line, 36);
    assert_int_equal(d.column, 6);
    assert_string_equal(line, "body crank   x = 0.5     y = 0       phi = 0");
    l.max_file_bytes = 100;     /* no place in the file: no line */
    assert_null(mechc_load_file_with("examples/four_bar.mech", &l, &d, line));
    assert_int_equal(d.line, 0);
    assert_string_equal(line, "");
    l = mechc_default_limits();
    l.max_depth = 0;            /* out of the option's range */
    assert_null(mechc_load_file_with("examples/four_bar.mech", &l, &d, NULL));
    assert_int_equal(d.status, MECHC_EARG);
    l.max_depth = 1001;
    assert_null(mechc_load_file_with("examples/four_bar.mech", &l, &d, NULL));
    assert_int_equal(d.status, MECHC_EARG);
    l.max_depth = 64;
    l.max_jac_entries = 0;      /* not checked while loading */
    m = mechc_load_file_with("examples/four_bar.mech", &l, &d, NULL);
    assert_non_null(m);
    mechc_model_free(m);
}

/* Failures come back as statuses, never as an exit. */
static void errors(void **state)
{
    (void)state;
    mechc_model *m = load("examples/four_bar.mech");
    mechc_diag d;
    assert_null(mechc_compile(m, "fast", &d));
    assert_int_equal(d.status, MECHC_EARG);
    mechc_kernels *k = compile(m, "generic");
    double M[81], q[9] = {0};
    assert_int_equal(mechc_mass(k, q, M), MECHC_ENOTAVAIL);
    assert_int_equal(mechc_phi_p(k, q, 0, M), MECHC_ENOTAVAIL);
    assert_int_equal(mechc_phi_p_nz(k), 0);
    assert_int_equal(mechc_phi_p_values(k, q, 0, M), MECHC_ENOTAVAIL);
    assert_int_equal(mechc_phi(k, NULL, 0, M), MECHC_EARG);
    assert_null(mechc_sim(k, NULL, &d));
    assert_int_equal(d.status, MECHC_ENOTRUNNABLE);
    assert_non_null(strstr(d.message, "no masses"));
    assert_int_equal(mechc_set_design(m, "a", 2), MECHC_ENOTAVAIL);
    mechc_run_options o = mechc_run_defaults();
    o.t1 = o.t0;
    assert_null(mechc_run(k, &o, &d));
    assert_int_equal(d.status, MECHC_EARG);
    mechc_kernels_free(k);
    mechc_model_free(m);
    /* an undriven mechanism cannot run */
    m = mechc_load_string("body b x = 1 y = 0 phi = 0\nrevolute R: ground(0, 0) b(-1, 0)\n",
                          "free.mech", &d);
    assert_non_null(m);
    k = compile(m, "generic");
    assert_null(mechc_run(k, NULL, &d));
    assert_int_equal(d.status, MECHC_ENOTRUNNABLE);
    mechc_kernels_free(k);
    mechc_model_free(m);    /* a driver past a limit position: the states before it, the status and the message */
    m = mechc_load_string("point p x = 0 y = 1\ndistance D: ground(0, 0) p length = 1\n"
                          "driver d: p.x = 2*t\n", "reach.mech", &d);
    assert_non_null(m);
    k = compile(m, "jit");
    mechc_run_options o10 = mechc_run_defaults();
    o10.steps = 10;
    mechc_result *r = mechc_run(k, &o10, &d);
    assert_non_null(r);
    assert_int_equal(mechc_result_status(r), MECHC_EANALYSIS);
    assert_int_equal(d.status, MECHC_EANALYSIS);
    assert_int_equal(mechc_result_states(r), 5);
    assert_near(mechc_result_t_fail(r), 0.5, 0, 1e-15);
    assert_non_null(strstr(mechc_result_message(r), "t = 0.5: the mechanism cannot reach"));
    assert_string_equal(d.message, mechc_result_message(r));
    mechc_result_free(r);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

static int states_seen;
static void count_state(void *ctx, double t, const double *q, const double *qd,
                        const double *qdd, const double *lambda)
{
    (void)t, (void)q, (void)qd, (void)qdd, (void)lambda;
    *(int *)ctx += 1;
}

/* mechc_run_with: the command's tuning; states streamed, not kept. */
static void run_with_tuning(void **state)
{
    (void)state;
    mechc_model *m = load("examples/four_bar.mech");
    mechc_kernels *k = compile(m, "jit");
    mechc_run_options o = mechc_run_defaults();
    o.steps = 4;
    int seen = 0;
    o.on_state = count_state;
    o.ctx = &seen;
    mechc_run_tuning x = mechc_run_tuning_defaults();
    assert_int_equal(x.max_substeps, 64);
    assert_int_equal(x.assembly_max_iter, 100);
    assert_int_equal(x.keep_states, 1);
    assert_null(x.linear);
    mechc_diag d;
    mechc_result *dense = mechc_run_with(k, &o, &x, &d);
    x.linear = "sparse";
    x.ode = "rkf45";
    x.keep_states = 0;
    mechc_result *sparse = mechc_run_with(k, &o, &x, &d);
    assert_non_null(dense);
    assert_non_null(sparse);
    assert_int_equal(mechc_result_status(sparse), MECHC_OK);
    assert_int_equal(mechc_result_states(sparse), 5);
    assert_int_equal(seen, 10);
    assert_null(mechc_result_q(sparse));
    assert_null(mechc_result_time(sparse));
    assert_near(mechc_result_q(dense)[9 + 8], 1.725386, 0, 1e-6);
    mechc_result_free(dense);
    mechc_result_free(sparse);
    x = mechc_run_tuning_defaults();
    x.max_dense_entries = 1;    /* the run's dense Jacobian, 81 entries: refused */
    assert_null(mechc_run_with(k, &o, &x, &d));
    assert_int_equal(d.status, MECHC_ENOTRUNNABLE);
    assert_non_null(strstr(d.message, "81 entries"));
    x = mechc_run_tuning_defaults();
    x.linear = "qr";
    assert_null(mechc_run_with(k, &o, &x, &d));
    assert_int_equal(d.status, MECHC_EARG);
    x = mechc_run_tuning_defaults();
    x.max_substeps = 0;
    assert_null(mechc_run_with(k, &o, &x, &d));
    assert_int_equal(d.status, MECHC_EARG);
    x = mechc_run_tuning_defaults();
    x.ode = "euler";
    assert_null(mechc_run_with(k, &o, &x, &d));
    assert_int_equal(d.status, MECHC_EARG);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

/* The run's last state is what `mechc run --steps 4 --json` prints. */
static void run_matches_cli(void **state)
{
    (void)state;
    static const double q1[9] = {0.5, -1.224646799076922e-16, 6.283185307179586, 1.84375,
                                 1.2401959270615266, 0.9733899101495465, 2.84375,
                                 1.2401959270615268, 1.696124157962962};
    static const double qdd1[9] = {-19.739208802178716, 4.834711775179833e-15, 0,
                                   -43.17951925476592, -15.387734283352568,
                                   -3.730359826267303, -23.44031045258721,
                                   -15.387734283352573, 20.14394306184335};
    mechc_model *m = load("examples/four_bar.mech");
    const char *engines[] = {"jit", "generic", NULL};
    for (int e = 0; engines[e]; e++) {
        mechc_kernels *k = compile(m, engines[e]);
        mechc_run_options o = mechc_run_defaults();
        o.steps = 4;
        states_seen = 0;
        o.on_state = count_state;
        o.ctx = &states_seen;
        mechc_diag d;
        mechc_result *r = mechc_run(k, &o, &d);
        assert_non_null(r);
        assert_int_equal(mechc_result_status(r), MECHC_OK);
        assert_int_equal(mechc_result_states(r), 5);
        assert_int_equal(states_seen, 5);
        assert_near(mechc_result_time(r)[4], 1, 0, 0);
        assert_null(mechc_result_lambda(r));
        const double *q = mechc_result_q(r) + 4 * 9, *qdd = mechc_result_qdd(r) + 4 * 9;
        for (int i = 0; i < 9; i++) {
            assert_near(q[i], q1[i], 1e-12, 1e-12);
            assert_near(qdd[i], qdd1[i], 1e-9, 1e-9);
        }
        /* the file's check: theta4(0.25) = 1.725386 */
        assert_near(mechc_result_q(r)[9 + 8], 1.725386, 0, 1e-6);
        mechc_result_free(r);
        mechc_kernels_free(k);
    }
    mechc_model_free(m);
}

/* A design parameter changed without recompiling: `mechc run --design a=1.1`'s last state. */
static void design_without_recompiling(void **state)
{
    (void)state;
    mechc_model *m = load("examples/freudenstein.mech");
    assert_int_equal(mechc_np(m), 3);
    assert_string_equal(mechc_design_name(m, 0), "a");
    mechc_kernels *k = compile(m, "jit");
    double p[3];
    assert_int_equal(mechc_set_design(m, "a", 1.1), MECHC_OK);
    assert_int_equal(mechc_set_design(m, "zz", 1.1), MECHC_EARG);
    assert_int_equal(mechc_design(m, p), MECHC_OK);
    assert_near(p[0], 1.1, 0, 0);
    assert_near(p[1], 3, 0, 0);
    mechc_run_options o = mechc_run_defaults();
    o.steps = 4;
    mechc_result *r = mechc_run(k, &o, NULL);
    assert_non_null(r);
    const double *q = mechc_result_q(r) + 4 * 9;
    assert_near(q[0], 0.2971662682274769, 1e-12, 1e-12);
    assert_near(q[8], 1.510430815824577, 1e-12, 1e-12);
    mechc_result_free(r);
    double phi_p[9 * 3];
    assert_int_equal(mechc_phi_p(k, mechc_q0(m), 0, phi_p), MECHC_OK);
    /* Phi_p's nonzeros: 12 (eval --json's phi_p_nz), each the dense entry */
    int rows[12], params[12];
    double vals[12];
    assert_int_equal(mechc_phi_p_nz(k), 12);
    assert_int_equal(mechc_phi_p_pattern(k, rows, params), MECHC_OK);
    assert_int_equal(mechc_phi_p_values(k, mechc_q0(m), 0, vals), MECHC_OK);
    for (int e = 0; e < 12; e++) {
        assert_true(vals[e] != 0);
        assert_true(vals[e] == phi_p[rows[e] * 3 + params[e]]);
    }
    assert_int_equal(rows[1], 1);
    assert_int_equal(params[3], 1);
    assert_int_equal(mechc_set_design_vector(m, NULL), MECHC_OK);
    assert_int_equal(mechc_design(m, p), MECHC_OK);
    assert_near(p[0], 1, 0, 0);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

/* rocker.phi at t = 1 (4 steps) with the design parameter a at a. */
static double rocker_at(mechc_kernels *k, double a, double *q, double *qd, double *qdd)
{
    mechc_set_design(mechc_kernels_model(k), "a", a);
    mechc_run_options o = mechc_run_defaults();
    o.steps = 4;
    mechc_result *r = mechc_run(k, &o, NULL);
    assert_non_null(r);
    if (q) {
        memcpy(q, mechc_result_q(r) + 4 * 9, 9 * sizeof *q);
        memcpy(qd, mechc_result_qd(r) + 4 * 9, 9 * sizeof *q);
        memcpy(qdd, mechc_result_qdd(r) + 4 * 9, 9 * sizeof *q);
    }
    double v = mechc_result_q(r)[4 * 9 + 8];
    mechc_result_free(r);
    return v;
}

/* d(rocker.phi)/d(a) at t = 1 against central differences of two runs. */
static void sensitivities(void **state)
{
    (void)state;
    mechc_model *m = load("examples/freudenstein.mech");
    mechc_kernels *k = compile(m, "jit");
    double q[9], qd[9], qdd[9], q_p[27], qd_p[27], qdd_p[27], h = 1e-6;
    rocker_at(k, 1, q, qd, qdd);
    assert_int_equal(mechc_sensitivities(k, q, qd, qdd, 1, q_p, qd_p, qdd_p, NULL, NULL, NULL),
                     MECHC_OK);
    double fd = (rocker_at(k, 1 + h, NULL, NULL, NULL) - rocker_at(k, 1 - h, NULL, NULL, NULL))
                / (2 * h);
    assert_near(q_p[8 * 3 + 0], fd, 1e-6, 1e-8);
    assert_true(fabs(fd) > 0.01);
    mechc_kernels_free(k);
    mechc_model_free(m);
    m = load("examples/four_bar.mech");
    k = compile(m, "generic");
    assert_int_equal(mechc_sensitivities(k, q, qd, qdd, 1, q_p, qd_p, qdd_p, NULL, NULL, NULL),
                     MECHC_ENOTAVAIL);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

/* Forward dynamics: `mechc sim examples/pendulum_dynamics.mech --steps 10 --json`. */
static void count_step(void *ctx, double t)
{
    (void)t;
    *(int *)ctx += 1;
}

/* The spatial four-bar with its redundant rows (24 holonomic for 21
   coordinates), its driver left out, with masses (tests/redundant_cli.sh's
   free_mass.mech): `mechc sim` simulates it, and so does mechc_sim. */
static void sim_redundant(void **state)
{
    (void)state;
    static const char masses[] =
        "mass crank   m = 1    J = (0.01, 1/12, 1/12)\n"
        "mass coupler m = 3    J = (0.01, 3*b^2/12, 3*b^2/12)\n"
        "mass rocker  m = 2.5  J = (0.01, 2.5*c^2/12, 2.5*c^2/12)\n"
        "gravity (0, -9.81, 0)\n";
    FILE *f = fopen("examples/four_bar_spatial_redundant.mech", "r");
    assert_non_null(f);
    char *text = calloc(1 << 16, 1), line[4096];
    size_t n = 0;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "driver", 6) != 0)
            n += (size_t)snprintf(text + n, (1 << 16) - n, "%s", line);
    fclose(f);
    snprintf(text + n, (1 << 16) - n, "%s", masses);
    mechc_diag d;
    mechc_model *m = mechc_load_string(text, "free_mass.mech", &d);
    free(text);
    assert_non_null(m);
    assert_true(mechc_nh(m) > mechc_nq(m));
    mechc_kernels *k = compile(m, "jit");
    mechc_sim_options o = mechc_sim_defaults();
    o.steps = 4;
    mechc_result *r = mechc_sim(k, &o, &d);
    assert_non_null(r);
    assert_int_equal(mechc_result_status(r), MECHC_OK);
    assert_int_equal(mechc_result_states(r), 5);
    mechc_result_free(r);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

/* mechc_sim_with: the command's tuning; states streamed, not kept. */
static void sim_with_tuning(void **state)
{
    (void)state;
    mechc_model *m = load("examples/pendulum_dynamics.mech");
    mechc_kernels *k = compile(m, "jit");
    mechc_sim_options o = mechc_sim_defaults();
    o.steps = 10;
    int seen = 0, steps = 0;
    o.on_state = count_state;
    o.ctx = &seen;
    mechc_sim_tuning x = mechc_sim_tuning_defaults();
    assert_int_equal(x.max_steps, 10000000);
    assert_int_equal(x.keep_states, 1);
    x.keep_states = 0;
    x.interpolate = 1;
    x.on_step = count_step;
    x.step_ctx = &steps;
    mechc_diag d;
    mechc_result *r = mechc_sim_with(k, &o, &x, &d);
    assert_non_null(r);
    assert_int_equal(mechc_result_status(r), MECHC_OK);
    assert_int_equal(mechc_result_states(r), 11);
    assert_int_equal(seen, 11);
    assert_true(steps > 0);
    assert_null(mechc_result_q(r));
    mechc_result_free(r);
    x = mechc_sim_tuning_defaults();
    x.max_steps = 2;            /* too few: fails part-way, the states before kept */
    r = mechc_sim_with(k, &o, &x, &d);
    assert_non_null(r);
    assert_int_equal(mechc_result_status(r), MECHC_EANALYSIS);
    assert_int_equal(d.status, MECHC_EANALYSIS);
    mechc_result_free(r);
    x = mechc_sim_tuning_defaults();
    x.baumgarte_alpha = -1;
    assert_null(mechc_sim_with(k, &o, &x, &d));
    assert_int_equal(d.status, MECHC_EARG);
    x = mechc_sim_tuning_defaults();
    x.linear = "lu";
    assert_null(mechc_sim_with(k, &o, &x, &d));
    assert_int_equal(d.status, MECHC_EARG);
    mechc_kernels_free(k);
    mechc_model_free(m);
}

static void sim_matches_cli(void **state)
{
    (void)state;
    mechc_model *m = load("examples/pendulum_dynamics.mech");
    assert_int_equal(mechc_has_dynamics(m), 1);
    mechc_kernels *k = compile(m, "jit");
    double M[9];
    assert_int_equal(mechc_mass(k, mechc_q0(m), M), MECHC_OK);
    assert_true(M[0] > 0);
    mechc_sim_options o = mechc_sim_defaults();
    o.steps = 10;
    mechc_diag d;
    mechc_result *r = mechc_sim(k, &o, &d);
    assert_non_null(r);
    assert_int_equal(mechc_result_status(r), MECHC_OK);
    assert_int_equal(mechc_result_states(r), 11);
    assert_non_null(mechc_result_lambda(r));
    assert_near(mechc_result_q(r)[10 * 3 + 2], -1.995101304134083, 1e-10, 0);
    assert_near(mechc_result_qd(r)[10 * 3 + 2], 1.1546296476978104, 1e-9, 0);
    mechc_result_free(r);
    o.method = "euler";
    assert_null(mechc_sim(k, &o, &d));
    assert_int_equal(d.status, MECHC_EARG);
    /* options the command refuses (the outside corpus): no
       tolerance at all, an infinite one, a NaN initial velocity */
    mechc_sim_options bad = mechc_sim_defaults();
    bad.rtol = bad.atol = 0;
    assert_null(mechc_sim(k, &bad, &d));
    assert_int_equal(d.status, MECHC_EARG);
    bad = mechc_sim_defaults();
    bad.atol = INFINITY;
    assert_null(mechc_sim(k, &bad, &d));
    assert_int_equal(d.status, MECHC_EARG);
    bad = mechc_sim_defaults();
    double qd[3] = {0, NAN, 0};
    bad.qd0 = qd;
    assert_null(mechc_sim(k, &bad, &d));
    assert_int_equal(d.status, MECHC_EARG);
    assert_string_equal(d.message, "mechc_sim: qd0[1] (rod.y) is not a finite number");
    mechc_kernels_free(k);
    mechc_model_free(m);
}

/* NULL handles: a status, a zero or NULL, never a crash (Python's
   methods on a closed Model pass NULL kernels). */
static void null_handles(void **state)
{
    (void)state;
    double q[4] = {0}, out[16];
    mechc_diag d;
    assert_int_equal(mechc_nq(NULL), 0);
    assert_int_equal(mechc_np(NULL), 0);
    assert_null(mechc_model_name(NULL));
    assert_null(mechc_q0(NULL));
    assert_null(mechc_coord_name(NULL, 0));
    assert_int_equal(mechc_coord_index(NULL, "b.x"), -1);
    assert_int_equal(mechc_body_coords(NULL, 0, NULL, NULL), MECHC_EARG);
    assert_int_equal(mechc_set_design(NULL, "a", 1), MECHC_EARG);
    assert_int_equal(mechc_qd0(NULL, out), MECHC_EARG);
    assert_null(mechc_kernels_engine(NULL));
    assert_null(mechc_kernels_model(NULL));
    assert_int_equal(mechc_jacobian_nz(NULL), 0);
    assert_int_equal(mechc_phi_p_nz(NULL), 0);
    assert_int_equal(mechc_phi_p_values(NULL, q, 0, out), MECHC_EARG);
    assert_null(mechc_compile_with(NULL, "jit", NULL, &d));
    assert_null(mechc_sim_with(NULL, NULL, NULL, &d));
    assert_null(mechc_info_with(NULL, NULL, &d));
    assert_null(mechc_info_report_json(NULL));
    assert_int_equal(mechc_phi(NULL, q, 0, out), MECHC_EARG);
    assert_int_equal(mechc_jacobian(NULL, q, 0, out), MECHC_EARG);
    assert_int_equal(mechc_gamma(NULL, q, q, 0, out), MECHC_EARG);
    assert_int_equal(mechc_mass(NULL, q, out), MECHC_EARG);
    assert_int_equal(mechc_outputs(NULL, q, NULL, NULL, 0, out, NULL, NULL), MECHC_EARG);
    assert_int_equal(mechc_phi_batch(NULL, 1, q, NULL, 0, out), MECHC_EARG);
    assert_int_equal(mechc_mass_batch(NULL, 0, q, out), MECHC_EARG);
    assert_int_equal(mechc_sensitivities(NULL, q, q, q, 0, out, out, out, NULL, NULL, NULL),
                     MECHC_EARG);
    assert_null(mechc_run(NULL, NULL, &d));
    assert_int_equal(d.status, MECHC_EARG);
    assert_int_equal(mechc_result_states(NULL), 0);
    assert_int_equal(mechc_result_status(NULL), MECHC_EARG);
    assert_null(mechc_result_q(NULL));
    assert_true(isnan(mechc_result_t_fail(NULL)));
    mechc_model_free(NULL);
    mechc_kernels_free(NULL);
    mechc_result_free(NULL);
}

/* mechc info's figures: as a struct and as its JSON. */
static void info(void **state)
{
    (void)state;
    mechc_model *m = load("examples/parallelogram_redundant.mech");
    mechc_info in;
    int redundant[64] = {0};
    mechc_diag d;
    assert_int_equal(mechc_info_at(m, 0, &in, redundant, NULL, &d), MECHC_OK);
    assert_int_equal(in.assembled, 1);
    assert_true(in.nredundant >= 1);
    assert_int_equal(in.rank, in.nh - in.nredundant);
    int flagged = 0;
    for (int i = 0; i < in.nr; i++)
        flagged += redundant[i];
    assert_int_equal(flagged, in.nredundant);
    char *json = mechc_info_json(m, &d);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"redundant\": ["));
    assert_true(json[0] == '{' && json[strlen(json) - 2] == '}');
    mechc_free(json);
    mechc_model_free(m);
}

/* mechc_info_with: `mechc info`'s options, the report in a handle. */
static void info_with_options(void **state)
{
    (void)state;
    mechc_model *m = load("examples/parallelogram_redundant.mech");
    mechc_info_options o = mechc_info_defaults();
    assert_int_equal(o.samples, 8);
    assert_true(o.rank_tol < 0);
    mechc_diag d;
    mechc_info_report *r = mechc_info_with(m, NULL, &d);    /* what mechc_info_json prints */
    char *json = mechc_info_report_json(r), *json0 = mechc_info_json(m, &d);
    assert_string_equal(json, json0);
    mechc_free(json), mechc_free(json0);
    mechc_info_report_free(r);
    o.t = 0.5;
    o.follow = 1;               /* info --at 0.5 */
    r = mechc_info_with(m, &o, &d);
    assert_non_null(r);
    json = mechc_info_report_json(r);
    assert_non_null(strstr(json, "\"t\": 0.5"));
    assert_non_null(strstr(json, "\"state\": {\"source\""));
    mechc_free(json);
    mechc_info in;
    double q[12];
    assert_int_equal(mechc_info_report_summary(r, &in, NULL, q), MECHC_OK);
    assert_int_equal(in.assembled, 1);
    assert_int_equal(in.rank, 11);
    mechc_info_report_free(r);
    o = mechc_info_defaults();
    o.q = q;                    /* info --state: the state reached, as it is */
    o.t = 0.5;
    r = mechc_info_with(m, &o, &d);
    assert_non_null(r);
    mechc_info_report_free(r);
    o.follow = 1;               /* both: refused */
    assert_null(mechc_info_with(m, &o, &d));
    assert_int_equal(d.status, MECHC_EARG);
    o = mechc_info_defaults();
    o.linear = "dense";
    o.max_dense = 10;           /* 12 x 12 rows by coordinates: beyond */
    assert_null(mechc_info_with(m, &o, &d));
    assert_int_equal(d.status, MECHC_EARG);
    o.linear = "sparse";        /* no dense SVD: no condition number */
    r = mechc_info_with(m, &o, &d);
    assert_non_null(r);
    assert_int_equal(mechc_info_report_summary(r, &in, NULL, NULL), MECHC_OK);
    assert_int_equal(in.rank, in.nh - in.nredundant);
    mechc_info_report_free(r);
    mechc_model_free(m);
}

/* One thread's work on a model of its own: load, jit, run; rocker.phi at t = 1. */
static void *run_alone(void *out)
{
    mechc_model *m = mechc_load_file("examples/four_bar.mech", NULL);
    mechc_kernels *k = m ? mechc_compile(m, "jit", NULL) : NULL;
    mechc_run_options o = mechc_run_defaults();
    o.steps = 50;
    mechc_result *r = k ? mechc_run(k, &o, NULL) : NULL;
    *(double *)out = r ? mechc_result_q(r)[50 * 9 + 8] : NAN;
    mechc_result_free(r);
    mechc_kernels_free(k);
    mechc_model_free(m);
    return NULL;
}

/* The same with a simulation (GSL's integrator): rod.phi at t = 1. */
static void *sim_alone(void *out)
{
    mechc_model *m = mechc_load_file("examples/pendulum_dynamics.mech", NULL);
    mechc_kernels *k = m ? mechc_compile(m, "generic", NULL) : NULL;
    mechc_sim_options o = mechc_sim_defaults();
    o.steps = 10;
    mechc_result *r = k ? mechc_sim(k, &o, NULL) : NULL;
    *(double *)out = r ? mechc_result_q(r)[10 * 3 + 2] : NAN;
    mechc_result_free(r);
    mechc_kernels_free(k);
    mechc_model_free(m);
    return NULL;
}

/* Distinct models in threads at the same time give what one alone gives. */
static void threads(void **state)
{
    (void)state;
    enum { T = 4 };
    double alone[2], got[T];
    run_alone(&alone[0]);
    sim_alone(&alone[1]);
    assert_near(alone[0], 1.696124157962962, 1e-12, 0);
    assert_near(alone[1], -1.995101304134083, 1e-10, 0);
    pthread_t th[T];
    for (int i = 0; i < T; i++)
        assert_int_equal(pthread_create(&th[i], NULL, i % 2 ? sim_alone : run_alone, &got[i]), 0);
    for (int i = 0; i < T; i++) {
        pthread_join(th[i], NULL);
        assert_true(got[i] == alone[i % 2]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sizes_and_names),
        cmocka_unit_test(phi_at_q0),
        cmocka_unit_test(jacobian),
        cmocka_unit_test(batches),
        cmocka_unit_test(engines_agree),
        cmocka_unit_test(compile_with_options),
        cmocka_unit_test(outputs),
        cmocka_unit_test(diagnostics),
        cmocka_unit_test(load_with_limits),
        cmocka_unit_test(errors),
        cmocka_unit_test(run_matches_cli),
        cmocka_unit_test(run_with_tuning),
        cmocka_unit_test(design_without_recompiling),
        cmocka_unit_test(sensitivities),
        cmocka_unit_test(sim_matches_cli),
        cmocka_unit_test(sim_with_tuning),
        cmocka_unit_test(sim_redundant),
        cmocka_unit_test(null_handles),
        cmocka_unit_test(info),
        cmocka_unit_test(info_with_options),
        cmocka_unit_test(threads),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
