/* test_batch.c - batch kernels (P_NAME_batch, _batch_soa) give, bit for bit, what single calls give.
 *
 * For the four-bar, the Stewart platform (spatial, functions in several
 * parts), the N = 10 chain, Freudenstein's design file (p read through the
 * engine's design binding) and a sparse-only unit: 37 random states (four
 * blocks of eight lanes and a tail of five), one of them with an angle
 * past 2^16 rad, which the file's own sincos leaves to libm (the lane is
 * then evaluated again by the single-state kernel), through the aot
 * engine (cc -O2, the written file's own sin/cos inlined and vectorised)
 * and the JIT (libtcc), with the arrays by rows (_batch) and by
 * coordinate (_batch_soa: the same states transposed, the outputs read
 * transposed). The AOT cache goes to a private folder. Under valgrind
 * (MECHC_UNDER_VALGRIND) only the JIT: the aot batch unit is built with
 * -march=native, and valgrind 3.19 stops at its AVX-512 instructions
 * (SIGILL); ASan runs it natively.
 */
#include "testutil.h"
#include "testcache.h"
#include "testload.h"

#include "../generator/base/arena.h"
#include "../generator/base/rng.h"
#include "../generator/engine/aot.h"
#include "../generator/engine/engine.h"

#include <stdlib.h>
#include <string.h>

enum { N = 37 };

static TestCache cache;

static int setup(void **state)
{
    (void)state;
    return testcache_setup(&cache, "batch");
}

static int teardown(void **state)
{
    (void)state;
    return testcache_teardown(&cache);
}

/* N states around q0: q, qd (N x nq) and t (N); state 13's first
   coordinate 1e6, past the own sincos' range when it is an angle. q_soa
   and qd_soa hold them by coordinate (nq x N), the inputs of _batch_soa;
   soa says which a check is of. */
typedef struct States {
    int nq;
    double *q, *qd, t[N];
    double *q_soa, *qd_soa;
    bool soa;
} States;

/* The batch kernels' q and qd: by rows or by coordinate. */
static const double *q_in(const States *s) { return s->soa ? s->q_soa : s->q; }
static const double *qd_in(const States *s) { return s->soa ? s->qd_soa : s->qd; }

static States make_states(const Mech *mech)
{
    const Model *m = mech->model;
    States s = {.nq = m->nq};
    s.q = xcalloc((size_t)N * m->nq + 1, sizeof(double));
    s.qd = xcalloc((size_t)N * m->nq + 1, sizeof(double));
    uint64_t seed = 29;
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < m->nq; j++) {
            s.q[i * m->nq + j] = m->q0[j] + 0.3 * rng_symmetric(&seed);
            s.qd[i * m->nq + j] = 2.0 * rng_symmetric(&seed);
        }
        s.t[i] = rng_unit(&seed);
    }
    for (int j = 0; j < m->nq; j++)
        s.q[13 * m->nq + j] = 1e6 + j;
    s.q_soa = xcalloc((size_t)N * m->nq + 1, sizeof(double));
    s.qd_soa = xcalloc((size_t)N * m->nq + 1, sizeof(double));
    for (int i = 0; i < N; i++)
        for (int j = 0; j < m->nq; j++) {
            s.q_soa[j * N + i] = s.q[i * m->nq + j];
            s.qd_soa[j * N + i] = s.qd[i * m->nq + j];
        }
    return s;
}

static void free_states(States *s)
{
    free(s->q);
    free(s->qd);
    free(s->q_soa);
    free(s->qd_soa);
}

/* Output arrays of one function for N states, batch and single. */
typedef struct Outs {
    double *batch[4], *single[4];
    size_t size[4];     /* per state */
} Outs;

static Outs make_outs(size_t a, size_t b, size_t c, size_t d)
{
    Outs o = {.size = {a, b, c, d}};
    for (int i = 0; i < 4; i++) {
        o.batch[i] = xcalloc(N * o.size[i] + 1, sizeof(double));
        o.single[i] = xcalloc(N * o.size[i] + 1, sizeof(double));
        memset(o.batch[i], 0xa5, N * o.size[i] * sizeof(double));   /* every entry written */
    }
    return o;
}

/* Batch (by coordinate where soa) and single agree to the bit, and hold
   numbers (not the fill). */
static void check_outs(Outs *o, const char *what, bool soa)
{
    for (int i = 0; i < 4; i++) {
        for (size_t k = 0; k < N * o->size[i]; k++) {
            size_t state = k / o->size[i], entry = k % o->size[i];
            const double *b = &o->batch[i][soa ? entry * N + state : k];
            if (memcmp(b, &o->single[i][k], sizeof(double)) != 0)
                fail_msg("%s%s: output %d entry %zu (state %zu): batch %.17g, single %.17g", what,
                         soa ? " (soa)" : "", i, entry, state, *b, o->single[i][k]);
        }
        free(o->batch[i]);
        free(o->single[i]);
    }
}

static void check_phi_like(KernelPhiBatch batch, KernelPhi single, const States *s, size_t size,
                           const char *what)
{
    if (!batch)
        fail_msg("%s: no batch kernel", what);
    Outs o = make_outs(size, 0, 0, 0);
    batch(N, q_in(s), s->t, o.batch[0]);
    for (int i = 0; i < N; i++)
        single(s->q + i * s->nq, s->t[i], o.single[0] + i * size);
    check_outs(&o, what, s->soa);
}

static void check_gamma(KernelGammaBatch batch, const Kernels *k, const States *s, size_t nr)
{
    Outs o = make_outs(nr, 0, 0, 0);
    batch(N, q_in(s), qd_in(s), s->t, o.batch[0]);
    for (int i = 0; i < N; i++)
        k->gamma(s->q + i * s->nq, s->qd + i * s->nq, s->t[i], o.single[0] + i * nr);
    check_outs(&o, "gamma", s->soa);
}

/* all (dense) or all_nz (jac_size the nonzeros). */
static void check_all(KernelAllBatch batch, KernelAll single, const States *s, size_t nh,
                      size_t jac_size, size_t nr, const char *what)
{
    if (!batch)
        fail_msg("%s: no batch kernel", what);
    Outs o = make_outs(nh, jac_size, nr, nr);
    batch(N, q_in(s), qd_in(s), s->t, o.batch[0], o.batch[1], o.batch[2], o.batch[3]);
    for (int i = 0; i < N; i++)
        single(s->q + i * s->nq, s->qd + i * s->nq, s->t[i], o.single[0] + i * nh,
               o.single[1] + i * jac_size, o.single[2] + i * nr, o.single[3] + i * nr);
    check_outs(&o, what, s->soa);
}

/* Every batch kernel of one layout (b) against the single kernels. */
static void check_layout(const Engine *e, const BatchKernels *b, const States *s)
{
    assert_non_null(b);
    const Kernels *k = &e->kernels;
    const Model *m = e->mech->model;
    size_t nh = (size_t)m->nh, nr = (size_t)m->nr, nnz = (size_t)(e->mech->kin.nnz > 0 ? e->mech->kin.nnz : 1);
    check_phi_like(b->phi, k->phi, s, nh, "phi");
    check_phi_like(b->jac_nz, k->jac_nz, s, nnz, "jac_nz");
    check_phi_like(b->nu, k->nu, s, nr, "nu");
    check_gamma(b->gamma, k, s, nr);
    if (k->all) {
        check_phi_like(b->jac, k->jac, s, nr * (size_t)m->nq, "jac");
        check_all(b->all, k->all, s, nh, nr * (size_t)m->nq, nr, "all");
    } else {
        assert_null(b->jac);
        assert_null(b->all);
    }
    if (k->all_nz)
        check_all(b->all_nz, k->all_nz, s, nh, nnz, nr, "all_nz");
}

/* Every batch kernel the engine has against its single kernels. */
static void check_engine(const Engine *e)
{
    const BatchKernels *b = engine_batch(e);
    size_t nr = (size_t)e->mech->model->nr;
    States s = make_states(e->mech);
    check_layout(e, b, &s);
    s.soa = true;
    check_layout(e, engine_batch_soa(e), &s);
    /* a real value: the batch's gamma of state 0 is the model's (finite) */
    double *g = xcalloc(N * nr + 1, sizeof(double));
    b->gamma(N, s.q, s.qd, s.t, g);
    for (size_t r = 0; r < nr; r++)
        assert_true(isfinite(g[r]));
    free(g);
    free_states(&s);
}

static void check_example(Mech *mech)
{
    EngineOptions opt = engine_default_options();
    opt.batch = true;
    bool aot = cache.have_cc && !getenv("MECHC_UNDER_VALGRIND");
    for (int kind = 0; kind < ENGINE_KIND_COUNT; kind++) {
        if (kind == ENGINE_GENERIC || (kind == ENGINE_AOT && !aot))
            continue;
        Engine e;
        Diag diag;
        if (!engine_open_with(&e, (EngineKind)kind, mech, &opt, &diag))
            fail_msg("%s: %s", engine_names[kind], diag.message);
        check_engine(&e);
        engine_close(&e);
    }
    pipeline_free(mech);
}

static void test_four_bar(void **state)
{
    (void)state;
    check_example(load_example("four_bar.mech"));
}

static void test_stewart(void **state)
{
    (void)state;
    check_example(load_example("stewart.mech"));
}

static void test_chain_10(void **state)
{
    (void)state;
    check_example(load_script("chain.sh", 10));
}

static void test_design(void **state)
{
    (void)state;
    check_example(load_example("freudenstein.mech"));
}

/* Without EngineOptions.batch, and for the generic engine: none. */
static void test_absent(void **state)
{
    (void)state;
    Mech *mech = load_example("four_bar.mech");
    Engine e;
    Diag diag;
    for (int kind = 0; kind < ENGINE_KIND_COUNT; kind++) {
        if (kind == ENGINE_AOT && !cache.have_cc)
            continue;
        if (!engine_open(&e, (EngineKind)kind, mech, &diag))
            fail_msg("%s: %s", engine_names[kind], diag.message);
        assert_null(engine_batch(&e));
        assert_null(engine_batch_soa(&e));
        engine_close(&e);
    }
    EngineOptions opt = engine_default_options();
    opt.batch = true;
    assert_true(engine_open_with(&e, ENGINE_GENERIC, mech, &opt, &diag));
    assert_null(engine_batch(&e));
    engine_close(&e);
    pipeline_free(mech);
}

/* A sparse-only unit (gen --sparse-only): all_nz_batch, no jac or all. */
static void test_sparse_only(void **state)
{
    (void)state;
    Mech *mech = load_example("slider_crank.mech");
    Diag diag;
    EmitOptions eo = engine_emit_options(mech, ENGINE_JIT);
    eo.sparse_only = eo.batch = true;
    EmitResult src;
    Jit *jit = engine_jit_compile(mech, &eo, &src, NULL, NULL, &diag);
    if (!jit)
        fail_msg("jit: %s", diag.message);
    Engine e = {.mech = mech, .compiled = true, .kernels = *jit_kernels(jit)};
    assert_null(e.kernels.all);
    check_engine(&e);
    jit_free(jit);
    emit_result_free(&src);
    if (cache.have_cc) {
        eo = engine_emit_options(mech, ENGINE_AOT);
        eo.sparse_only = eo.batch = true;
        assert_true(emit_mechanism(&mech->kin, &eo, &src, &diag));
        AotResult res;
        Aot *aot = aot_load(src.c_text, src.prefix, false, &res, &diag);
        if (!aot)
            fail_msg("aot: %s", diag.message);
        e.kernels = *aot_kernels(aot);
        check_engine(&e);
        aot_unload(aot);
        emit_result_free(&src);
    }
    pipeline_free(mech);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_four_bar),
        cmocka_unit_test(test_stewart),
        cmocka_unit_test(test_chain_10),
        cmocka_unit_test(test_design),
        cmocka_unit_test(test_absent),
        cmocka_unit_test(test_sparse_only),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
