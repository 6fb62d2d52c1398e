/* test_check.c - mechc check passes on every example and fails when a kernel is wrong.
 *
 * A check that never fails proves nothing: the fault hook of
 * check_mechanism plants the classic textbook slips in the generated
 * kernels (a Jacobian entry with the wrong sign or factor, or missing; a
 * gamma without its -Phi_tt term or its velocity terms; nu with the wrong
 * sign) and each must be caught at the right row, with the right diagnosis.
 */
#include "testutil.h"

#include "../generator/base/arena.h"
#include "../generator/eval/aot.h"
#include "../generator/eval/check.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char cache_dir[256];

static void remove_tree(const char *dir, int depth)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    char path[900];
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (unlink(path) != 0 && depth > 0)
            remove_tree(path, depth - 1);
    }
    closedir(d);
    rmdir(dir);
}

static int setup(void **state)
{
    (void)state;
    const char *tmp = getenv("TMPDIR");
    snprintf(cache_dir, sizeof cache_dir, "%s/mechc-test-check-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(cache_dir))
        return -1;
    setenv("XDG_CACHE_HOME", cache_dir, 1);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    remove_tree(cache_dir, 2);
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
        assert_true(check_mechanism(mech, &opt, &rep, &diag));
        for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
            const CheckItem *it = &rep.items[w];
            if (it->checked && !(it->error <= it->tol))
                fail_msg("%s: %s error %.3g at row %d (value %.17g, reference %.17g): %s", path,
                         it->what, it->error, it->row, it->value, it->reference, it->hint);
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

/* Runs check on an example with one fault; returns the report. */
static void run_fault(const char *file, CheckFaultKind kind, const char *row, const char *col,
                      double factor, CheckReport *rep)
{
    Diag diag;
    Mech *mech = load_example(file, &diag);
    CheckOptions opt = check_default_options();
    opt.samples = 4;
    opt.use_aot = false;
    opt.fault = (CheckFault){.kind = kind, .row = row_index(mech->model, row),
                             .col = col ? coord_index(mech->model, col) : -1, .factor = factor};
    assert_true(check_mechanism(mech, &opt, rep, &diag));
    /* the item's row index is checked against the fault's by the caller */
    assert_false(rep->ok);
    pipeline_free(mech);
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

static int row_of(const char *file, const char *row)
{
    Diag diag;
    Mech *mech = load_example(file, &diag);
    int r = row_index(mech->model, row);
    pipeline_free(mech);
    return r;
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_examples_pass),
        cmocka_unit_test(test_jacobian_sign),
        cmocka_unit_test(test_jacobian_factor_two),
        cmocka_unit_test(test_jacobian_missing_term),
        cmocka_unit_test(test_velocity_row_jacobian),
        cmocka_unit_test(test_gamma_velocity_terms_dropped),
        cmocka_unit_test(test_gamma_phi_tt_dropped),
        cmocka_unit_test(test_gamma_zero),
        cmocka_unit_test(test_nu_sign),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
