/* test_roll.c - loop-rolled kernels (gen --roll) compute the same bits as straight-line ones on every example, chains included, under the JIT and gcc -O2; small files stay straight-line under auto.
 *
 * Each mechanism is emitted twice, --roll never and --roll always, both
 * compiled (libtcc in process; for some also the system compiler through
 * aot_load), and every kinematic kernel evaluated at the same random
 * states into buffers prefilled with the same bytes: the outputs must be
 * equal byte for byte, and where the mechanism has joints of one shape
 * the rolled source must really contain loops.
 */
#include "testutil.h"

#include "../generator/emit/emit.h"
#include "../generator/engine/aot.h"
#include "../generator/pipeline/pipeline.h"
#include "testload.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static uint64_t rng_state = 12345;

static double uniform(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Emits mech's double kernels with roll (written for gcc unless jit). */
static void emit_real(const Mech *mech, int roll, bool jit, bool direct_jac, bool real_float,
                      EmitResult *res)
{
    EmitOptions opt = emit_default_options();
    opt.real_float = real_float;
    opt.declare_math = jit;
    opt.direct_jac = direct_jac;
    opt.all_nz = true;
    opt.roll = roll;
    opt.prefix = jit ? "mechc_jit" : "mechc_aot";
    opt.max_ops = 0;
    opt.host_design = true;     /* a design file's kernels read the model's design */
    Diag diag;
    if (!emit_mechanism(&mech->kin, &opt, res, &diag))
        fail_msg("%s: %s", mech->model->name, diag.message);
}

static void emit(const Mech *mech, int roll, bool jit, bool direct_jac, EmitResult *res)
{
    emit_real(mech, roll, jit, direct_jac, false, res);
}

/* Every kinematic kernel of a and b at a few random states: the same bytes. */
static void compare_kernels(const char *name, const Mech *mech, const Kernels *a, const Kernels *b)
{
    const Model *m = mech->model;
    int nq = m->nq, nr = m->nr, nh = m->nh, nnz = mech->kin.nnz > 0 ? mech->kin.nnz : 1;
    size_t cap = (size_t)nr * nq + (size_t)nnz + 3 * (size_t)nr + 4;
    double *q = malloc((size_t)(nq + 1) * sizeof *q), *qd = malloc((size_t)(nq + 1) * sizeof *qd);
    double *out[2];
    for (int k = 0; k < 2; k++)
        out[k] = malloc(cap * 4 * sizeof(double));
    for (int trial = 0; trial < 3; trial++) {
        for (int i = 0; i < nq; i++) {
            q[i] = m->q0[i] + (trial ? 2 * uniform() - 1 : 0);
            qd[i] = 4 * uniform() - 2;
        }
        double t = trial * 0.37;
        for (int k = 0; k < 2; k++) {
            const Kernels *kr = k ? b : a;
            double *o = out[k];
            memset(o, 0x5a, cap * 4 * sizeof(double));
            double *phi = o, *jac = phi + nh + 1, *vals = jac + (size_t)nr * nq + 1,
                   *nu = vals + nnz, *gamma = nu + nr, *rest = gamma + nr;
            kr->phi(q, t, phi);
            kr->jac(q, t, jac);
            kr->jac_nz(q, t, vals);
            kr->nu(q, t, nu);
            kr->gamma(q, qd, t, gamma);
            double *phi2 = rest, *jac2 = phi2 + nh + 1, *nu2 = jac2 + (size_t)nr * nq + 1,
                   *gamma2 = nu2 + nr, *phi3 = gamma2 + nr, *vals3 = phi3 + nh + 1,
                   *nu3 = vals3 + nnz, *gamma3 = nu3 + nr;
            kr->all(q, qd, t, phi2, jac2, nu2, gamma2);
            kr->all_nz(q, qd, t, phi3, vals3, nu3, gamma3);
        }
        for (size_t i = 0; i < cap * 4; i++)
            if (memcmp(&out[0][i], &out[1][i], sizeof(double)) != 0)
                fail_msg("%s: output word %zu differs: %.17g straight-line, %.17g rolled", name, i,
                         out[0][i], out[1][i]);
    }
    free(q);
    free(qd);
    free(out[0]);
    free(out[1]);
}

/* A compiled unit: libtcc (jit) or the system compiler (aot). */
typedef struct Unit {
    Jit *jit;
    Aot *aot;
} Unit;

static const Kernels *unit_open(Unit *u, const EmitResult *res, bool jit, const char *name)
{
    Diag diag;
    AotResult ar;
    *u = (Unit){0};
    if (jit)
        u->jit = jit_compile(res->c_text, res->prefix, &diag);
    else
        u->aot = aot_load(res->c_text, res->prefix, false, &ar, &diag);
    if (!u->jit && !u->aot)
        fail_msg("%s: %s", name, diag.message);
    return jit ? jit_kernels(u->jit) : aot_kernels(u->aot);
}

static void unit_close(Unit *u)
{
    jit_free(u->jit);
    if (u->aot)
        aot_unload(u->aot);
}

/* No row pointer of a rolled loop starts before its array: q + -3 * i
   would be undefined in C99 (6.5.6p8) even where the element read is in
   range. */
static void assert_pointers_in_range(const char *name, const char *c)
{
    for (const char *line = c; (line = strstr(line, "*const ")); line++) {
        const char *end = strchr(line, '\n');
        const char *minus = strstr(line, "+ -");
        if (minus && (!end || minus < end))
            fail_msg("%s: a row pointer before its array: %.*s", name,
                     (int)(end ? end - line : 80), line);
    }
}

/* mech never against always, under the JIT or (aot) the system compiler
   (gcc -O2, the file's own sincos); returns whether always rolled. */
static bool check(const char *name, const Mech *mech, bool jit, bool direct_jac)
{
    EmitResult straight, rolled;
    emit(mech, EMIT_ROLL_NEVER, jit, direct_jac, &straight);
    emit(mech, EMIT_ROLL_ALWAYS, jit, direct_jac, &rolled);
    assert_null(strstr(straight.c_text, "one shape: one loop"));
    bool loops = strstr(rolled.c_text, "one shape: one loop") != NULL;
    assert_pointers_in_range(name, rolled.c_text);
    Unit a, b;
    const Kernels *ka = unit_open(&a, &straight, jit, name);
    const Kernels *kb = unit_open(&b, &rolled, jit, name);
    for (int k = 0; k < 2; k++)
        if ((k ? kb : ka)->design_bind)
            (k ? kb : ka)->design_bind(mech->model->dag.param_values);
    compare_kernels(name, mech, ka, kb);
    unit_close(&a);
    unit_close(&b);
    emit_result_free(&straight);
    emit_result_free(&rolled);
    return loops;
}

static bool check_jit(const char *name, const Mech *mech)
{
    return check(name, mech, true, true);
}

static void check_aot(const char *name, const Mech *mech, bool direct_jac)
{
    if (!aot_compiler_available()) {
        print_message("no compiler: %s skipped under aot\n", name);
        return;
    }
    assert_true(check(name, mech, false, direct_jac));
}

static void test_every_example(void **state)
{
    (void)state;
    const char *dir = getenv("MECHC_EXAMPLES") ? getenv("MECHC_EXAMPLES") : "examples";
    DIR *d = opendir(dir);
    assert_non_null(d);
    int checked = 0, rolled = 0;
    for (struct dirent *ent; (ent = readdir(d));) {
        size_t len = strlen(ent->d_name);
        if (len < 6 || strcmp(ent->d_name + len - 5, ".mech") != 0)
            continue;
        Mech *mech = load_example(ent->d_name);
        rolled += check_jit(ent->d_name, mech);
        checked++;
        pipeline_free(mech);
    }
    closedir(d);
    assert_true(checked >= 30);
    assert_true(rolled >= 5);   /* the shapes do repeat in the examples */
}

static void test_chains(void **state)
{
    (void)state;
    static const struct { const char *script; int n; } chains[] = {
        {"chain.sh", 1}, {"chain.sh", 2}, {"chain.sh", 13}, {"chain_spatial.sh", 6},
        {"a02_four_bar.sh", 9},
    };
    for (size_t i = 0; i < sizeof chains / sizeof *chains; i++) {
        Mech *mech = load_script(chains[i].script, chains[i].n);
        bool loops = check_jit(chains[i].script, mech);
        if (chains[i].n > 2)
            assert_true(loops);
        pipeline_free(mech);
    }
}

static void test_gcc(void **state)
{
    (void)state;
    Mech *mech = load_script("chain.sh", 21);
    check_aot("chain 21", mech, true);
    check_aot("chain 21 (spread jac)", mech, false);
    pipeline_free(mech);
    mech = load_example("all_statements.mech");
    check_aot("all_statements", mech, true);
    pipeline_free(mech);
    mech = load_script("chain_spatial.sh", 5);
    check_aot("chain_spatial 5", mech, true);
    pipeline_free(mech);
}

/* Written files built by tcc (what firmware debug builds and quick
   builds see: libm's sin and cos, the pair only where the file's own
   function is needed) on every example: the same bytes too. */
static void test_unoptimised(void **state)
{
    (void)state;
    if (system("tcc -v > /dev/null 2>&1") != 0) {
        print_message("tcc not found: skipping\n");
        skip();
    }
    const char *old = getenv("CC");
    char *saved = old ? strdup(old) : NULL;
    setenv("CC", "tcc", 1);
    const char *dir = getenv("MECHC_EXAMPLES") ? getenv("MECHC_EXAMPLES") : "examples";
    DIR *d = opendir(dir);
    assert_non_null(d);
    for (struct dirent *ent; (ent = readdir(d));) {
        size_t len = strlen(ent->d_name);
        if (len < 6 || strcmp(ent->d_name + len - 5, ".mech") != 0)
            continue;
        Mech *mech = load_example(ent->d_name);
        check(ent->d_name, mech, false, false);
        pipeline_free(mech);
    }
    closedir(d);
    Mech *mech = load_script("chain.sh", 17);
    assert_true(check("chain 17", mech, false, false));
    pipeline_free(mech);
    /* b0's sin is read by the loop, its cos only by the straight-line
       rest: the two halves choose their trig calls apart */
    mech = load_text("mechanism pairs\n"
                     "body b0 x = 0 y = 0 phi = 0.1\nbody b1 x = 0 y = 0 phi = 0.2\n"
                     "body b2 x = 0 y = 0 phi = 0.3\nbody b3 x = 0 y = 0 phi = 0.4\n"
                     "constraint s0: b0.y = sin(b0.phi)\nconstraint s1: b1.y = sin(b1.phi)\n"
                     "constraint s2: b2.y = sin(b2.phi)\nconstraint s3: b3.y = sin(b3.phi)\n"
                     "constraint k: b0.x = cos(b0.phi) + 0.3*b0.y*b0.y\n", "pairs.mech");
    assert_true(check("pairs", mech, false, false));
    pipeline_free(mech);
    if (saved) {
        setenv("CC", saved, 1);
        free(saved);
    } else {
        unsetenv("CC");
    }
}

/* The float kernels of a and b (double-typed in Kernels, float in the
   file) at a few states: the same bytes. */
typedef void (*FloatPhi)(const float *, float, float *);
typedef void (*FloatGamma)(const float *, const float *, float, float *);
typedef void (*FloatAll)(const float *, const float *, float, float *, float *, float *, float *);

static void compare_float(const char *name, const Mech *mech, const Kernels *a, const Kernels *b)
{
    const Model *m = mech->model;
    int nq = m->nq, nr = m->nr, nnz = mech->kin.nnz > 0 ? mech->kin.nnz : 1;
    size_t cap = 2 * ((size_t)nr * nq + (size_t)nnz) + 10 * (size_t)nr + 8;
    float *q = malloc((size_t)nq * sizeof *q), *qd = malloc((size_t)nq * sizeof *qd);
    float *out[2] = {malloc(cap * sizeof(float)), malloc(cap * sizeof(float))};
    for (int trial = 0; trial < 3; trial++) {
        for (int i = 0; i < nq; i++) {
            q[i] = (float)(m->q0[i] + (trial ? 2 * uniform() - 1 : 0));
            qd[i] = (float)(4 * uniform() - 2);
        }
        float t = 0.37f * (float)trial;
        for (int k = 0; k < 2; k++) {
            const Kernels *kr = k ? b : a;
            float *o = out[k], *jac = o + nr + 1, *vals = jac + (size_t)nr * nq + 1, *nu = vals + nnz,
                  *gamma = nu + nr, *jac2 = gamma + nr, *rest = jac2 + (size_t)nr * nq;
            memset(o, 0x5a, cap * sizeof(float));
            ((FloatPhi)(uintptr_t)kr->phi)(q, t, o);
            ((FloatPhi)(uintptr_t)kr->jac)(q, t, jac);
            ((FloatPhi)(uintptr_t)kr->jac_nz)(q, t, vals);
            ((FloatPhi)(uintptr_t)kr->nu)(q, t, nu);
            ((FloatGamma)(uintptr_t)kr->gamma)(q, qd, t, gamma);
            ((FloatAll)(uintptr_t)kr->all)(q, qd, t, rest, jac2, rest + nr, rest + 2 * nr);
            ((FloatAll)(uintptr_t)kr->all_nz)(q, qd, t, rest + 3 * nr, rest + 4 * nr,
                                              rest + 4 * nr + nnz, rest + 5 * nr + nnz);
        }
        for (size_t i = 0; i < cap; i++)
            if (memcmp(&out[0][i], &out[1][i], sizeof(float)) != 0)
                fail_msg("%s (float): output word %zu differs: %.9g straight-line, %.9g rolled", name,
                         i, (double)out[0][i], (double)out[1][i]);
    }
    free(q);
    free(qd);
    free(out[0]);
    free(out[1]);
}

/* Float files (--real float: float tables and literals, sinf and cosf)
   built by gcc -O2: the same bytes rolled and straight-line. */
static void test_float(void **state)
{
    (void)state;
    if (!aot_compiler_available())
        skip();
    Mech *mechs[] = {load_script("chain.sh", 15), load_example("all_statements.mech"),
                     load_script("chain_spatial.sh", 5)};
    for (size_t i = 0; i < sizeof mechs / sizeof *mechs; i++) {
        EmitResult straight, rolled;
        emit_real(mechs[i], EMIT_ROLL_NEVER, false, true, true, &straight);
        emit_real(mechs[i], EMIT_ROLL_ALWAYS, false, true, true, &rolled);
        assert_non_null(strstr(rolled.c_text, "one shape: one loop"));
        Unit a, b;
        const Kernels *ka = unit_open(&a, &straight, false, mechs[i]->model->name);
        const Kernels *kb = unit_open(&b, &rolled, false, mechs[i]->model->name);
        compare_float(mechs[i]->model->name, mechs[i], ka, kb);
        unit_close(&a);
        unit_close(&b);
        emit_result_free(&straight);
        emit_result_free(&rolled);
        pipeline_free(mechs[i]);
    }
}

/* auto leaves small files straight-line (their text unchanged) and rolls
   a chain past EMIT_ROLL_AUTO_ROWS rows. */
static void test_auto(void **state)
{
    (void)state;
    Mech *mech = load_example("four_bar.mech");
    EmitResult a, b;
    emit(mech, EMIT_ROLL_AUTO, false, false, &a);
    emit(mech, EMIT_ROLL_NEVER, false, false, &b);
    assert_string_equal(a.c_text, b.c_text);
    emit_result_free(&a);
    emit_result_free(&b);
    pipeline_free(mech);
    mech = load_script("chain.sh", (EMIT_ROLL_AUTO_ROWS + 5) / 6);
    assert_true(mech->model->nr >= EMIT_ROLL_AUTO_ROWS);
    emit(mech, EMIT_ROLL_AUTO, false, false, &a);
    assert_non_null(strstr(a.c_text, "one shape: one loop"));
    emit_result_free(&a);
    pipeline_free(mech);
}

/* A rolled table's constants print as the straight-line code's do, the
   shortest decimal that reads back (emit_put_literal): 0.2, not
   0.20000000000000001. */
static void test_table_literals(void **state)
{
    (void)state;
    Mech *mech = load_example("suspension.mech");
    EmitResult rolled;
    emit(mech, EMIT_ROLL_ALWAYS, true, true, &rolled);
    assert_non_null(strstr(rolled.c_text, "_phi_r1_k2[2] = {\n    0.2, 0.32,\n};"));
    assert_null(strstr(rolled.c_text, "0000000000"));
    emit_result_free(&rolled);
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_example),
        cmocka_unit_test(test_chains),
        cmocka_unit_test(test_gcc),
        cmocka_unit_test(test_unoptimised),
        cmocka_unit_test(test_float),
        cmocka_unit_test(test_auto),
        cmocka_unit_test(test_table_literals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
