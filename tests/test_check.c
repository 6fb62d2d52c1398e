/* test_check.c - mechc check passes on every example and fails when a kernel is wrong.
 *
 * A check that never fails proves nothing: the fault hook of
 * check_mechanism plants the classic textbook slips in the generated
 * kernels (a Jacobian entry with the wrong sign or factor, or missing; a
 * gamma without its -Phi_tt term or its velocity terms; nu with the wrong
 * sign) and each must be caught at the right row, with the right diagnosis.
 */
#include "testutil.h"
#include "testcache.h"

#include "../generator/verify/check.h"
#include "../generator/base/arena.h"
#include "../generator/engine/aot.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char cache_dir[256];

static int setup(void **state)
{
    (void)state;
    if (!testcache_make(cache_dir, sizeof cache_dir, "check"))
        return -1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    testcache_release(cache_dir);
    return 0;
}

static const char *examples_dir(void)
{
    const char *dir = getenv("MECHC_EXAMPLES");
    return dir ? dir : "examples";
}

static Mech *load_example(const char *name, Diag *diag)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s", examples_dir(), name);
    MechLimits limits = mech_default_limits();
    Mech *mech = pipeline_load(path, &limits, diag);
    if (!mech)
        fail_msg("%s: %s", path, diag->message);
    return mech;
}

static int row_index(const Model *m, const char *name)
{
    for (int r = 0; r < m->nr; r++)
        if (strcmp(m->rows[r].name, name) == 0)
            return r;
    fail_msg("no row %s", name);
    return -1;
}

static int coord_index(const Model *m, const char *name)
{
    for (int i = 0; i < m->nq; i++)
        if (strcmp(m->coord_names[i], name) == 0)
            return i;
    fail_msg("no coordinate %s", name);
    return -1;
}

static void test_examples_pass(void **state)
{
    (void)state;
    DIR *d = opendir(examples_dir());
    assert_non_null(d);
    struct dirent *e;
    int count = 0;
    bool cc = aot_compiler_available();
    while ((e = readdir(d))) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".mech") != 0)
            continue;
        char path[600];
        snprintf(path, sizeof path, "%s/%s", examples_dir(), e->d_name);
        MechLimits limits = mech_default_limits();
        Diag diag;
        Mech *mech = pipeline_load(path, &limits, &diag);
        if (!mech)
            continue;       /* examples of bad input */
        CheckOptions opt = check_default_options();
        opt.samples = 6;
        CheckReport rep;
        /* the sparse comparisons first (fewer samples), then the dense */
        opt.linear = ANALYSIS_LINEAR_SPARSE;
        opt.samples = 3;
        assert_true(check_mechanism(mech, &opt, &rep, &diag));
        if (!rep.ok || !rep.sparse)
            fail_msg("%s: --linear sparse: %s", path, rep.ok ? "not sparse" : "fails");
        opt.linear = ANALYSIS_LINEAR_DENSE;
        opt.samples = 6;
        assert_true(check_mechanism(mech, &opt, &rep, &diag));
        for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
            const CheckItem *it = &rep.items[w];
            if (it->checked && !(it->error <= it->tol))
                fail_msg("%s: %s error %.3g at row %d (value %.17g, reference %.17g): %s", path,
                         it->what, it->error, it->row, it->value, it->reference, it->hint);
            if (it->unsettled)      /* every comparison judged */
                fail_msg("%s: %d %s comparisons unsettled", path, it->unsettled, it->what);
        }
        assert_true(rep.ok);
        assert_true(rep.engine_used[ENGINE_JIT] && rep.engine_used[ENGINE_GENERIC]);
        assert_int_equal(rep.engine_used[ENGINE_AOT], cc);
        assert_true(rep.items[CHECK_JAC_FD].checked && rep.items[CHECK_GAMMA_FD].checked);
        pipeline_free(mech);
        count++;
    }
    closedir(d);
    assert_true(count >= 10);
}

/* The engines check compares, and the note saying why aot was left out:
   not asked for, or no compiler ($CC pointed at nothing). The pairs with
   aot are then not compared at all. */
static void test_aot_left_out(void **state)
{
    (void)state;
    Diag diag;
    Mech *mech = load_example("four_bar.mech", &diag);
    CheckOptions opt = check_default_options();
    opt.samples = 3;
    opt.use_aot = false;
    CheckReport rep;
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    assert_true(rep.ok && rep.assembled);
    assert_int_equal(rep.samples, 3);
    assert_true(rep.engine_used[ENGINE_JIT] && rep.engine_used[ENGINE_GENERIC]);
    assert_false(rep.engine_used[ENGINE_AOT]);
    assert_string_equal(rep.note, "aot not compared (not asked for)");
    for (int w = CHECK_PAIR_FIRST; w < CHECK_DYN_FIRST; w++)
        assert_int_equal(rep.items[w].checked, strstr(rep.items[w].what, "aot") == NULL);

    const char *cc = getenv("CC");
    char *saved = cc ? strdup(cc) : NULL;
    setenv("CC", "/nonexistent/mechc-test-cc", 1);
    opt.use_aot = true;
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    if (saved)
        setenv("CC", saved, 1);
    else
        unsetenv("CC");
    free(saved);
    assert_true(rep.ok);
    assert_false(rep.engine_used[ENGINE_AOT]);
    assert_string_equal(rep.note, "aot not compared: no C compiler found (set CC)");
    assert_false(rep.items[CHECK_PAIR_FIRST + 4].checked);     /* phi jit/aot */
    pipeline_free(mech);
}

/* Runs check (dense or sparse) on an example with one fault; returns the report. */
static void run_fault_linear(const char *file, CheckFaultKind kind, const char *row,
                             const char *col, double factor, AnalysisLinear linear, CheckReport *rep)
{
    Diag diag;
    Mech *mech = load_example(file, &diag);
    CheckOptions opt = check_default_options();
    opt.linear = linear;
    opt.samples = 4;
    opt.use_aot = false;
    opt.fault = (CheckFault){.kind = kind, .row = row_index(mech->model, row),
                             .col = col ? coord_index(mech->model, col) : -1, .factor = factor};
    assert_true(check_mechanism(mech, &opt, rep, &diag));
    /* the item's row index is checked against the fault's by the caller */
    assert_false(rep->ok);
    assert_int_equal(rep->sparse, linear == ANALYSIS_LINEAR_SPARSE);
    pipeline_free(mech);
}

static void run_fault(const char *file, CheckFaultKind kind, const char *row, const char *col,
                      double factor, CheckReport *rep)
{
    run_fault_linear(file, kind, row, col, factor, ANALYSIS_LINEAR_AUTO, rep);
}

static void expect(const CheckReport *rep, CheckWhat what, int row, const char *hint_part)
{
    const CheckItem *it = &rep->items[what];
    assert_true(it->checked);
    if (it->error <= it->tol)
        fail_msg("%s: error %.3g within tolerance: the fault went unnoticed", it->what, it->error);
    if (row >= 0)
        assert_int_equal(it->row, row);
    if (!strstr(it->hint, hint_part))
        fail_msg("%s: hint '%s' does not mention '%s'", it->what, it->hint, hint_part);
}

/* The index of a row of a loaded mechanism, which it frees. */
static int row_of_mech(Mech *mech, const char *row)
{
    int r = row_index(mech->model, row);
    pipeline_free(mech);
    return r;
}

static int row_of(const char *file, const char *row)
{
    Diag diag;
    return row_of_mech(load_example(file, &diag), row);
}

static void test_jacobian_sign(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("slider_crank.mech", CHECK_FAULT_JAC_SCALE, "A.x", "crank.phi", -1.0, &rep);
    expect(&rep, CHECK_JAC_FD, row_of("slider_crank.mech", "A.x"), "sign");
    assert_int_equal(rep.items[CHECK_JAC_FD].col, 2);
    /* the engine comparison sees it too, and blames the generated code */
    expect(&rep, CHECK_PAIR_FIRST + 1, -1, "fails against finite differences");
    /* nothing else was disturbed */
    assert_true(rep.items[CHECK_GAMMA_FD].error <= rep.items[CHECK_GAMMA_FD].tol);
    assert_true(rep.items[CHECK_NU_FD].error <= rep.items[CHECK_NU_FD].tol);
}

static void test_jacobian_factor_two(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("four_bar.mech", CHECK_FAULT_JAC_SCALE, "B.y", "rocker.phi", 2.0, &rep);
    expect(&rep, CHECK_JAC_FD, row_of("four_bar.mech", "B.y"), "factor 2 too many");
    run_fault("pendulum_distance.mech", CHECK_FAULT_JAC_SCALE, "rod", "m.x", 0.5, &rep);
    expect(&rep, CHECK_JAC_FD, 0, "factor 2 missing");
}

static void test_jacobian_missing_term(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("four_bar.mech", CHECK_FAULT_JAC_SCALE, "O2.y", "crank.phi", 0.0, &rep);
    expect(&rep, CHECK_JAC_FD, row_of("four_bar.mech", "O2.y"), "missing");
}

/* The sparse comparisons (the Jacobian's nonzeros against differences by
   column groups) catch the same Jacobian mistakes at the same row and
   column, with the same hints. */
static void test_sparse_jacobian_faults(void **state)
{
    (void)state;
    static const struct {
        const char *file, *row, *col;
        double factor;
        const char *hint;
    } f[] = {
        {"slider_crank.mech", "A.x", "crank.phi", -1.0, "sign"},
        {"four_bar.mech", "B.y", "rocker.phi", 2.0, "factor 2 too many"},
        {"four_bar.mech", "O2.y", "crank.phi", 0.0, "missing"},
        {"knife_cart.mech", "blade", "cart.y", -1.0, "sign"},
        {"rolling_wheel.mech", "roll", "wheel.phi", 2.0, "factor 2 too many"},
    };
    for (size_t i = 0; i < sizeof f / sizeof *f; i++) {
        CheckReport rep;
        run_fault_linear(f[i].file, CHECK_FAULT_JAC_SCALE, f[i].row, f[i].col, f[i].factor,
                         ANALYSIS_LINEAR_SPARSE, &rep);
        expect(&rep, CHECK_JAC_FD, row_of(f[i].file, f[i].row), f[i].hint);
        Diag diag;
        Mech *mech = load_example(f[i].file, &diag);
        assert_int_equal(rep.items[CHECK_JAC_FD].col, coord_index(mech->model, f[i].col));
        pipeline_free(mech);
        assert_true(rep.items[CHECK_NU_FD].error <= rep.items[CHECK_NU_FD].tol);
    }
}

static Mech *load_text(const char *text, Diag *diag);

/* A chain of 50 loops (303 coordinates) checked both ways: the same
   verdict, the Jacobian's worst error of the same size, the dense and the
   sparse assembly at the same state. */
static void test_sparse_chain_agrees(void **state)
{
    (void)state;
    char text[64 * 1024];
    FILE *p = popen("sh examples/chain.sh 50", "r");
    assert_non_null(p);
    size_t n = fread(text, 1, sizeof text - 1, p);
    text[n] = '\0';
    assert_int_equal(pclose(p), 0);
    CheckReport rep[2];
    for (int k = 0; k < 2; k++) {
        Diag diag;
        Mech *mech = load_text(text, &diag);
        assert_non_null(mech);
        CheckOptions opt = check_default_options();
        opt.samples = 4;
        opt.linear = k ? ANALYSIS_LINEAR_SPARSE : ANALYSIS_LINEAR_DENSE;
        assert_true(check_mechanism(mech, &opt, &rep[k], &diag));
        pipeline_free(mech);
        assert_true(rep[k].ok);
        assert_true(rep[k].assembled);
        assert_int_equal(rep[k].sparse, k == 1);
    }
    double ed = rep[0].items[CHECK_JAC_FD].error, es = rep[1].items[CHECK_JAC_FD].error;
    assert_true(es > 0 && es < 1e-8 && ed > 0 && ed < 1e-8);
    for (int w = CHECK_NU_FD; w <= CHECK_GAMMA_FD; w++)    /* the same samples: same values */
        assert_near(rep[1].items[w].value, rep[0].items[w].value, 1e-9, 1e-12);
    assert_true(rep[1].items[CHECK_PAIR_FIRST].checked);           /* phi jit/generic */
    assert_false(rep[1].items[CHECK_PAIR_FIRST + 1].checked);      /* jac jit/generic: dense */
}

static void test_velocity_row_jacobian(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("knife_cart.mech", CHECK_FAULT_JAC_SCALE, "blade", "cart.y", -1.0, &rep);
    expect(&rep, CHECK_JAC_FD, row_of("knife_cart.mech", "blade"), "sign");
}

static void test_gamma_velocity_terms_dropped(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("slider_crank.mech", CHECK_FAULT_GAMMA_DROP_QD, "A.x", NULL, 0.0, &rep);
    expect(&rep, CHECK_GAMMA_FD, row_of("slider_crank.mech", "A.x"), "quadratic velocity term");
    assert_true(rep.items[CHECK_JAC_FD].error <= rep.items[CHECK_JAC_FD].tol);
}

static void test_gamma_phi_tt_dropped(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("five_bar.mech", CHECK_FAULT_GAMMA_DROP_TT, "motorL", NULL, 0.0, &rep);
    expect(&rep, CHECK_GAMMA_FD, row_of("five_bar.mech", "motorL"), "-Phi_tt is missing");
}

static void test_gamma_zero(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("four_bar.mech", CHECK_FAULT_GAMMA_ZERO, "B.x", NULL, 0.0, &rep);
    expect(&rep, CHECK_GAMMA_FD, row_of("four_bar.mech", "B.x"), "");
}

static void test_nu_sign(void **state)
{
    (void)state;
    CheckReport rep;
    run_fault("slider_crank.mech", CHECK_FAULT_NU_SCALE, "D", NULL, -1.0, &rep);
    expect(&rep, CHECK_NU_FD, row_of("slider_crank.mech", "D"), "nu = -Phi_t");
}

/* ---- rows that vary fast: truncation error is not a mistake ---- */

static const char fast_sin[] =
    "point m x = 0.1 y = 0.2\n"
    "driver d: m.x = t\n"
    "constraint c: sin(100*m.x) = m.y\n";

/* sum_{i=1}^{n} sin(i*k*m.x) = m.y */
static char *fast_sum(int n, int k)
{
    size_t cap = 200 + 32 * (size_t)n;
    char *text = xmalloc(cap);
    size_t len = (size_t)snprintf(text, cap, "point m x = 0.1 y = 0.2\ndriver d: m.x = t\nconstraint c: ");
    for (int i = 1; i <= n; i++)
        len += (size_t)snprintf(text + len, cap - len, "%ssin(%d*m.x)", i > 1 ? " + " : "", i * k);
    snprintf(text + len, cap - len, " = m.y\n");
    return text;
}

static Mech *load_text(const char *text, Diag *diag)
{
    MechLimits limits = mech_default_limits();
    Mech *mech = pipeline_load_text(text, "fast.mech", &limits, diag);
    if (!mech)
        fail_msg("%s", diag->message);
    return mech;
}

/* check on text with the default options (no aot), the fault and the seed. */
static void run_text(const char *text, CheckFault fault, unsigned long seed, CheckReport *rep)
{
    Diag diag;
    Mech *mech = load_text(text, &diag);
    CheckOptions opt = check_default_options();
    opt.use_aot = false;
    opt.seed = seed;
    opt.fault = fault;
    assert_true(check_mechanism(mech, &opt, rep, &diag));
    pipeline_free(mech);
}

static void expect_pass(const char *name, const CheckReport *rep)
{
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        const CheckItem *it = &rep->items[w];
        if (it->checked && !(it->error <= it->tol))
            fail_msg("%s: %s error %.3g at row %d, step %.3g (value %.17g, reference %.17g)", name, it->what,
                     it->error, it->row, it->step, it->value, it->reference);
        if (w < CHECK_PAIR_FIRST && it->unsettled)
            fail_msg("%s: %d %s comparisons unsettled", name, it->unsettled, it->what);
    }
    assert_true(rep->ok);
}

static int fast_row(const char *text, const char *row)
{
    Diag diag;
    return row_of_mech(load_text(text, &diag), row);
}

/* sin(100 x): gamma = 100^2 sin(100 x) xd^2 is right, but the second
   difference at the default step is off by 1e-6 (it failed before the
   step ladder); the check passes, at a smaller step, on every seed. */
static void test_fast_sin_passes(void **state)
{
    (void)state;
    for (unsigned long seed = 1; seed <= 5; seed++) {
        CheckReport rep;
        run_text(fast_sin, (CheckFault){.kind = CHECK_FAULT_NONE}, seed, &rep);
        expect_pass("sin(100 m.x)", &rep);
    }
    CheckReport rep;
    run_text(fast_sin, (CheckFault){.kind = CHECK_FAULT_NONE}, 1, &rep);
    const CheckItem *g = &rep.items[CHECK_GAMMA_FD];
    /* seed 1 has a sample the default step cannot resolve (1.02e-6) */
    assert_true(g->refined > 0);
    /* the default step reported where it sufficed */
    assert_true(g->step > 0.0);
    assert_true(rep.items[CHECK_JAC_FD].step == check_default_options().fd_step);
}

/* sum_{i=1}^{30} sin(i x), and the faster sums (sin(10 i x): 1e-4 off at
   the default step before; sin(100 i x): 0.68 off), all correct. */
static void test_fast_sums_pass(void **state)
{
    (void)state;
    const int ks[] = {1, 10, 30, 100};
    for (size_t n = 0; n < sizeof ks / sizeof *ks; n++) {
        char *text = fast_sum(30, ks[n]);
        char name[64];
        snprintf(name, sizeof name, "sum of sin(%d i m.x)", ks[n]);
        for (unsigned long seed = 1; seed <= 3; seed++) {
            CheckReport rep;
            run_text(text, (CheckFault){.kind = CHECK_FAULT_NONE}, seed, &rep);
            expect_pass(name, &rep);
            if (ks[n] >= 10)
                assert_true(rep.items[CHECK_GAMMA_FD].refined > 0);
        }
        free(text);
    }
}

/* Time-dependent and velocity-level rows that vary fast pass too. */
static void test_fast_time_and_velocity_rows_pass(void **state)
{
    (void)state;
    static const char *const texts[] = {
        "point m x = 0.1 y = 0.2\ndriver d: m.x = t\nconstraint c: sin(300*t)*m.x = m.y\n",
        "point m x = 0.1 y = 0.2\ndriver d: m.x = sin(100*t)/100\nconstraint c: sin(100*(m.x + t)) = m.y\n",
        ("body b x = 0.1 y = 0.2 phi = 0\ndriver d: b.phi = t\nconstraint h: b.y = 0.2\n"
         "velocity v: sin(1000*b.x)*der(b.x) + cos(1000*t)*der(b.phi) = 0\n"),
    };
    for (size_t n = 0; n < sizeof texts / sizeof *texts; n++)
        for (unsigned long seed = 1; seed <= 3; seed++) {
            CheckReport rep;
            run_text(texts[n], (CheckFault){.kind = CHECK_FAULT_NONE}, seed, &rep);
            expect_pass(texts[n], &rep);
        }
}

/* The smaller steps do not excuse a mistake: on the same fast rows the
   planted faults fail at their row with their diagnosis. */
static void test_fast_rows_still_catch_mistakes(void **state)
{
    (void)state;
    int c = fast_row(fast_sin, "c");
    CheckReport rep;
    run_text(fast_sin, (CheckFault){.kind = CHECK_FAULT_GAMMA_DROP_QD, .row = c}, 1, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_GAMMA_FD, c, "quadratic velocity term");
    assert_true(rep.items[CHECK_JAC_FD].error <= rep.items[CHECK_JAC_FD].tol);

    run_text(fast_sin, (CheckFault){.kind = CHECK_FAULT_JAC_SCALE, .row = c, .col = 0, .factor = -1.0}, 1, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_JAC_FD, c, "sign");
    assert_int_equal(rep.items[CHECK_JAC_FD].col, 0);

    char *sum = fast_sum(30, 10);
    run_text(sum, (CheckFault){.kind = CHECK_FAULT_JAC_SCALE, .row = c, .col = 0, .factor = 2.0}, 2, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_JAC_FD, c, "factor 2 too many");
    /* the row has no t: its whole gamma is the quadratic velocity term */
    run_text(sum, (CheckFault){.kind = CHECK_FAULT_GAMMA_ZERO, .row = c}, 2, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_GAMMA_FD, c, "quadratic velocity term");
    /* a slip of a part in 10^4: small, but no step makes it go away */
    run_text(sum, (CheckFault){.kind = CHECK_FAULT_JAC_SCALE, .row = c, .col = 0, .factor = 1.0001}, 3, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_JAC_FD, c, "");
    free(sum);

    static const char timed[] = "point m x = 0.1 y = 0.2\ndriver d: m.x = t\nconstraint c: sin(300*t)*m.x = m.y\n";
    run_text(timed, (CheckFault){.kind = CHECK_FAULT_NU_SCALE, .row = c, .factor = -1.0}, 1, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_NU_FD, c, "nu = -Phi_t");
    run_text(timed, (CheckFault){.kind = CHECK_FAULT_GAMMA_DROP_TT, .row = c}, 1, &rep);
    assert_false(rep.ok);
    expect(&rep, CHECK_GAMMA_FD, c, "-Phi_tt is missing");
}

/* The steps are options: a coarse first step is refined down to what the
   row needs, and the report names the step used. */
static void test_fd_step_options(void **state)
{
    (void)state;
    CheckOptions def = check_default_options();
    assert_true(def.fd_step == 1e-4 && def.fd_step2 == 2e-3);
    assert_true(def.spread_q == 0.05 && def.spread_qd == 1.0);
    Diag diag;
    Mech *mech = load_text(fast_sin, &diag);
    CheckOptions opt = check_default_options();
    opt.use_aot = false;
    opt.fd_step = 1e-2;
    opt.fd_step2 = 1e-1;
    CheckReport rep;
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    expect_pass("sin(100 m.x), coarse steps", &rep);
    const CheckItem *g = &rep.items[CHECK_GAMMA_FD];
    assert_true(g->refined > 0);
    assert_true(g->step < opt.fd_step2);
    /* wider spreads: still correct, still passing */
    opt = check_default_options();
    opt.use_aot = false;
    opt.spread_q = 0.5;
    opt.spread_qd = 3.0;
    assert_true(check_mechanism(mech, &opt, &rep, &diag));
    expect_pass("sin(100 m.x), wide spreads", &rep);
    pipeline_free(mech);
}

/* Where no run of steps settles (|x| = 1000 leaves sin(1000 x) with more
   rounding than any step can beat), the comparison is reported
   unsettled: not a failure, not a pass. */
static void test_unresolvable_row_is_unsettled(void **state)
{
    (void)state;
    static const char big[] = "point m x = 1000 y = 0.2\ndriver d: m.x = 1000 + t\nconstraint c: sin(1000*m.x) = m.y\n";
    CheckReport rep;
    run_text(big, (CheckFault){.kind = CHECK_FAULT_NONE}, 1, &rep);
    assert_true(rep.ok);
    assert_true(rep.items[CHECK_GAMMA_FD].unsettled > 0);
    assert_int_equal(rep.items[CHECK_GAMMA_FD].unsettled_row, fast_row(big, "c"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_examples_pass),
        cmocka_unit_test(test_aot_left_out),
        cmocka_unit_test(test_jacobian_sign),
        cmocka_unit_test(test_jacobian_factor_two),
        cmocka_unit_test(test_jacobian_missing_term),
        cmocka_unit_test(test_velocity_row_jacobian),
        cmocka_unit_test(test_sparse_jacobian_faults),
        cmocka_unit_test(test_sparse_chain_agrees),
        cmocka_unit_test(test_gamma_velocity_terms_dropped),
        cmocka_unit_test(test_gamma_phi_tt_dropped),
        cmocka_unit_test(test_gamma_zero),
        cmocka_unit_test(test_nu_sign),
        cmocka_unit_test(test_fast_sin_passes),
        cmocka_unit_test(test_fast_sums_pass),
        cmocka_unit_test(test_fast_time_and_velocity_rows_pass),
        cmocka_unit_test(test_fast_rows_still_catch_mistakes),
        cmocka_unit_test(test_fd_step_options),
        cmocka_unit_test(test_unresolvable_row_is_unsettled),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
