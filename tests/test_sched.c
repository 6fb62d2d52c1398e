/* test_sched.c - the scheduler: each node computed once per function however it is cut, trig once per angle, post-order.
 *
 * A chain of four-bar loops (the shape of examples/chain.sh) cut into
 * small chunks is scheduled directly and checked for the invariants the
 * emitter relies on; then the written C is counted: one sin and one cos
 * per distinct angle and function, with the parts passing values through
 * the workspace.
 */
#include "testutil.h"

#include "../generator/base/diag.h"
#include "../generator/base/limits.h"
#include "../generator/base/strbuf.h"
#include "../generator/emit/emit.h"
#include "../generator/pipeline/pipeline.h"
#include "../generator/sched/sched.h"

#include <stdlib.h>
#include <string.h>

/* The chain of examples/chain.sh with n loops. */
static char *chain_text(int n)
{
    StrBuf sb;
    sb_init(&sb);
    sb_puts(&sb, "mechanism chain\nparam amp = 0.5\nparam omega = 2*pi\n"
                 "body rod0 x = 0 y = 0.5 phi = pi/2\n"
                 "revolute g0: ground(0, 0) rod0(-0.5, 0)\n"
                 "driver drive: rod0.phi = pi/2 + amp*sin(omega*t)\n");
    for (int i = 0; i < n; i++) {
        sb_printf(&sb, "body cpl%d x = %d.5 y = 1 phi = 0\n", i, i);
        sb_printf(&sb, "body rod%d x = %d y = 0.5 phi = pi/2\n", i + 1, i + 1);
        sb_printf(&sb, "revolute g%d: ground(%d, 0) rod%d(-0.5, 0)\n", i + 1, i + 1, i + 1);
        sb_printf(&sb, "revolute a%d: rod%d(0.5, 0) cpl%d(-0.5, 0)\n", i, i, i);
        sb_printf(&sb, "revolute b%d: cpl%d(0.5, 0) rod%d(0.5, 0)\n", i, i, i + 1);
    }
    return sb_take(&sb);
}

static Mech *load_chain(int n)
{
    char *text = chain_text(n);
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load_text(text, "chain.mech", &limits, &diag);
    if (!mech) {
        diag_print(&diag, stderr);
        fail_msg("the chain did not load");
    }
    free(text);
    return mech;
}

/* The Jacobian's nonzeros and gamma as one function's outputs. */
static SchedOutput *jac_gamma_outputs(const Kinematics *kin, int *n)
{
    int nr = kin->model->nr;
    SchedOutput *outs = malloc((size_t)(kin->nnz + nr) * sizeof *outs);
    *n = 0;
    for (int k = 0; k < kin->nnz; k++)
        outs[(*n)++] = (SchedOutput){"vals", k, kin->jac[k].value};
    for (int r = 0; r < nr; r++)
        outs[(*n)++] = (SchedOutput){"gamma", r, kin->gamma[r]};
    return outs;
}

/* Every operation node the outputs need is computed by exactly one chunk
   (its owner), before any use there; other chunks import it with a slot;
   the sin and cos of an angle have one owner; ops counts each node once. */
static void test_each_node_once(void **state)
{
    (void)state;
    Mech *mech = load_chain(10);
    const Dag *dag = &mech->model->dag;
    Scheduler s;
    sched_init(&s, dag, 40);
    int n;
    SchedOutput *outs = jac_gamma_outputs(&mech->kin, &n);
    SchedFunction fn;
    assert_true(sched_function(&s, outs, n, &fn));
    assert_true(fn.nchunks >= 4);       /* the cut is really exercised */
    assert_true(fn.nslots > 0);
    int *computed_by = calloc((size_t)dag->count, sizeof *computed_by);
    int total = 0;
    for (int c = 0; c < fn.nchunks; c++) {
        const SchedChunk *ch = &fn.chunks[c];
        char *seen = calloc((size_t)dag->count, 1);
        for (int i = 0; i < ch->nnodes; i++) {
            NodeId id = ch->nodes[i];
            assert_false(dag_is_leaf(dag, id));
            assert_int_equal(seen[id], 0);      /* once per chunk */
            seen[id] = 1;
            if (sched_is_import(&s, id, c)) {
                assert_true(s.owner[id] < c);
                assert_true(sched_slot(&s, id) >= 0 && sched_slot(&s, id) < fn.nslots);
                continue;
            }
            computed_by[id]++;
            total++;
            const DagNode *node = dag_node(dag, id);
            NodeId kids[2] = {node->a, node->b};
            for (int k = 0; k < dag_op_info[node->op].arity; k++)   /* post-order */
                assert_true(dag_is_leaf(dag, kids[k]) || seen[kids[k]]);
            DagOp op = (DagOp)node->op;
            if (op == OP_SIN || op == OP_COS) {
                NodeId partner = dag_find(dag, op == OP_SIN ? OP_COS : OP_SIN, node->a, -1);
                if (partner != DAG_NONE && s.owned[partner] == s.fn_stamp)
                    assert_int_equal(s.owner[partner], c);
            }
        }
        for (int i = 1; i < ch->count; i++)
            assert_true(ch->ends[i - 1] <= ch->ends[i]);
        assert_true(ch->count == 0 || ch->ends[ch->count - 1] <= ch->nnodes);
        free(seen);
    }
    for (NodeId id = 0; id < dag->count; id++)
        assert_true(computed_by[id] <= 1);
    assert_int_equal(total, fn.ops);
    /* the same outputs uncut: the same operations, nothing imported */
    Scheduler whole;
    sched_init(&whole, dag, 1 << 30);
    outs = jac_gamma_outputs(&mech->kin, &n);
    SchedFunction one;
    assert_true(sched_function(&whole, outs, n, &one));
    assert_int_equal(one.nchunks, 1);
    assert_int_equal(one.nslots, 0);
    assert_int_equal(one.ops, fn.ops);
    sched_function_free(&one);
    sched_free(&whole);
    free(computed_by);
    sched_function_free(&fn);
    sched_free(&s);
    pipeline_free(mech);
}

/* The text of generated function name and of its parts. */
static char *function_text(const char *c, const char *prefix, const char *name)
{
    StrBuf sb;
    sb_init(&sb);
    sb_puts(&sb, "");
    char head[200];
    snprintf(head, sizeof head, "void %s_%s(", prefix, name);
    char part[200];
    snprintf(part, sizeof part, "void %s_%s_part", prefix, name);
    for (const char *p = c; (p = strstr(p, "void ")) != NULL; p++) {
        bool whole = strncmp(p, head, strlen(head)) == 0;
        bool piece = strncmp(p, part, strlen(part)) == 0;
        if (!whole && !piece)
            continue;
        const char *open = strstr(p, ")\n{\n");
        if (!open || strchr(p, ';') < open)     /* a declaration */
            continue;
        const char *end = strstr(open, "\n}\n");
        sb_printf(&sb, "%.*s\n", (int)(end - p), p);
    }
    return sb_take(&sb);
}

/* Calls of fn ("sin(") in text, and how many distinct arguments they have. */
static int count_calls(const char *text, const char *fn, int *distinct)
{
    char args[512][64];
    int calls = 0;
    *distinct = 0;
    size_t len = strlen(fn);
    for (const char *p = text; (p = strstr(p, fn)) != NULL; p += len) {
        if (p > text && (p[-1] == '_' || (p[-1] >= 'a' && p[-1] <= 'z')))
            continue;       /* sincos(, asin( */
        const char *a = p + len, *close = strstr(a, ");");
        char arg[64];
        snprintf(arg, sizeof arg, "%.*s", (int)(close - a), a);
        calls++;
        int k = 0;
        while (k < *distinct && strcmp(args[k], arg) != 0)
            k++;
        if (k == *distinct && *distinct < 512)
            snprintf(args[(*distinct)++], 64, "%s", arg);
    }
    return calls;
}

/* With libm's sin and cos and parts of 40 operations, every function
   calls sin and cos once per distinct angle, and the pair sits together. */
static void test_trig_once_per_function(void **state)
{
    (void)state;
    Mech *mech = load_chain(10);
    const char *const *names = emit_function_names;
    for (int fl = 0; fl < 2; fl++) {
        EmitOptions opt = emit_default_options();
        opt.prefix = "ch";
        opt.libm_trig = true;
        opt.real_float = fl == 1;
        opt.chunk_nodes = 40;
        EmitResult res;
        Diag diag;
        diag_init(&diag, "emit", NULL, 0);
        assert_true(emit_mechanism(&mech->kin, &opt, &res, &diag));
        assert_non_null(strstr(res.c_text, "ws[0] = u"));        /* parts pass values */
        const char *sin_name = fl ? "sinf(" : "sin(", *cos_name = fl ? "cosf(" : "cos(";
        int angles_seen = 0;
        for (int f = 0; f < EMIT_FUNCTION_COUNT; f++) {
            if (f == EMIT_JAC)      /* spread from jac_nz */
                continue;
            char *text = function_text(res.c_text, "ch", names[f]);
            int ds, dc;
            int ns = count_calls(text, sin_name, &ds), nc = count_calls(text, cos_name, &dc);
            if (ns != ds || nc != dc)
                fail_msg("%s (%s): %d sin for %d angles, %d cos for %d angles", names[f],
                         fl ? "float" : "double", ns, ds, nc, dc);
            angles_seen += ds;
            free(text);
        }
        /* 21 body angles + the driver's 2 pi t, in phi, jac_nz, gamma, all */
        assert_true(angles_seen >= 4 * 21);
        emit_result_free(&res);
    }
    pipeline_free(mech);
}

/* The written file of mech with prefix ch, with libm's sin and cos or
   (libm false) the file's own. */
static void emit_ch(const Mech *mech, bool libm, EmitResult *res)
{
    EmitOptions opt = emit_default_options();
    opt.prefix = "ch";
    opt.libm_trig = libm;
    Diag diag;
    diag_init(&diag, "emit", NULL, 0);
    assert_true(emit_mechanism(&mech->kin, &opt, res, &diag));
}

/* -c*u and c*u are one product: in the chain of one loop, the Jacobian
   needs +-0.5 sin and +-0.5 cos of the three angles; each temporary is
   multiplied by 0.5 once, and the other sign is a negation of the shared
   product (or, where the product has no other use, the one product
   (-0.5)*u). */
static void test_signed_constants_share(void **state)
{
    (void)state;
    Mech *mech = load_chain(1);
    EmitResult res;
    emit_ch(mech, true, &res);
    char *text = function_text(res.c_text, "ch", "jac_nz");
    int times[64] = {0}, products = 0;
    for (const char *p = text; (p = strstr(p, "0.5")) != NULL; p++) {
        const char *u = p[3] == ')' ? p + 4 : p + 3;
        if (strncmp(u, " * u", 4) != 0)
            continue;
        int k = atoi(u + 4);
        assert_true(k >= 0 && k < 64);
        times[k]++;
        products++;
    }
    assert_int_equal(products, 6);     /* sin and cos of 3 angles */
    for (int k = 0; k < 64; k++)
        assert_true(times[k] <= 1);
    assert_non_null(strstr(text, "] = -u"));
    assert_null(strstr(text, "-(0.5 * "));
    free(text);
    assert_int_equal(res.ops[EMIT_JAC_NZ], 14);     /* 6 trig, 6 products, 2 negations */
    emit_result_free(&res);
    pipeline_free(mech);
}

/* A handmade function's outputs scheduled as one chunk and prepared. */
static void schedule_one(Scheduler *s, const Dag *dag, const NodeId *values, int n,
                         SchedFunction *fn)
{
    SchedOutput *outs = malloc((size_t)n * sizeof *outs);
    for (int i = 0; i < n; i++)
        outs[i] = (SchedOutput){"out", i, values[i]};
    sched_init(s, dag, 1 << 20);
    assert_true(sched_function(s, outs, n, fn));
    assert_int_equal(fn->nchunks, 1);
    sched_prepare_chunk(s, fn, 0);
}

static bool every_call_first(const void *ctx, NodeId id)
{
    (void)ctx;
    (void)id;
    return true;
}

/* Values across calls, counted by hand. First: a = q2 q3 stored with q4
   and, after sin(q0), with q5: left in place the sin call lies inside a's
   life (1); at the top, nothing is computed before the call but the call
   itself (0). Second: sin(q0) and cos(q1), each stored at once: in place
   neither lives across the other (0); at the top, sin(q0) lives across
   cos(q1)'s call (1). */
static void test_values_across_calls(void **state)
{
    (void)state;
    for (int which = 0; which < 2; which++) {
        Dag dag;
        dag_init(&dag, 1000);
        NodeId q[6];
        for (int i = 0; i < 6; i++)
            q[i] = dag_var(&dag, i);
        NodeId a = dag_mul(&dag, q[2], q[3]);
        NodeId first[3] = {dag_add(&dag, a, q[4]), dag_call(&dag, OP_SIN, q[0], DAG_NONE),
                           dag_sub(&dag, a, q[5])};
        NodeId second[2] = {dag_call(&dag, OP_SIN, q[0], DAG_NONE),
                            dag_call(&dag, OP_COS, q[1], DAG_NONE)};
        Scheduler s;
        SchedFunction fn;
        schedule_one(&s, &dag, which == 0 ? first : second, which == 0 ? 3 : 2, &fn);
        int in_place = sched_values_across_calls(&s, &fn, 0, NULL, NULL);
        int at_top = sched_values_across_calls(&s, &fn, 0, every_call_first, NULL);
        assert_int_equal(in_place, which == 0 ? 1 : 0);
        assert_int_equal(at_top, which == 0 ? 0 : 1);
        sched_function_free(&fn);
        sched_free(&s);
        dag_free(&dag);
    }
}

/* γ's (cos, sin) times one computed factor qd0² is a shared factor; phi's
   0.5 cos, 0.5 sin (a constant) and a lone sin are not. */
static void test_pair_shares_factor(void **state)
{
    (void)state;
    for (int which = 0; which < 3; which++) {
        Dag dag;
        dag_init(&dag, 1000);
        NodeId q0 = dag_var(&dag, 0), qd0 = dag_vard(&dag, 0);
        NodeId sn = dag_call(&dag, OP_SIN, q0, DAG_NONE), cs = dag_call(&dag, OP_COS, q0, DAG_NONE);
        NodeId factor = which == 1 ? dag_const(&dag, 0.5) : dag_mul(&dag, qd0, qd0);
        NodeId values[2] = {dag_mul(&dag, cs, factor),
                            which == 2 ? dag_add(&dag, sn, factor) : dag_mul(&dag, sn, factor)};
        Scheduler s;
        SchedFunction fn;
        schedule_one(&s, &dag, values, 2, &fn);
        assert_true(s.temp[sn] >= 0 && s.temp[cs] >= 0);
        assert_int_equal(sched_pair_shares_factor(&s, &fn, 0, sn), which == 0);
        assert_int_equal(sched_pair_shares_factor(&s, &fn, 0, cs), which == 0);
        sched_function_free(&fn);
        sched_free(&s);
        dag_free(&dag);
    }
}

/* The first part of name's function in c (a malloc'd copy). */
static char *first_part(const char *c, const char *name)
{
    char head[64];
    snprintf(head, sizeof head, "void ch_%s_part0(", name);
    const char *p = strstr(c, head);
    while (p && strstr(p, ")\n{\n") > strchr(p, ';'))     /* its declaration */
        p = strstr(p + 1, head);
    assert_non_null(p);
    const char *end = strstr(p, "\n}\n");
    return strndup(p, (size_t)(end - p));
}

/* The calls of call ("cos(q[") text makes before its first store to
   array. */
static int calls_before_store(const char *text, const char *call, const char *array)
{
    const char *store = strstr(text, array);
    int n = 0;
    for (const char *p = text; (p = strstr(p, call)) != NULL && p < store; p++)
        n++;
    return n;
}

/* Where sin and cos are real calls, libm's (chain of 10 loops, 21
   angles) or one noinline copy of the written file's pair (the default
   file over 64 calls: a chain of 20 loops, known to need that many before
   it is written, and of 14, found to once written and written again):
   phi's calls stay next to
   their first uses (in place, fewer values live across calls: one angle
   before the first store), and γ's, whose cos and sin share the factor
   qd², come first (copied out of the result slots rather than loaded
   from them as one vector). */
static void test_calls_placed(void **state)
{
    (void)state;
    static const int loops[3] = {10, 20, 14};
    for (int k = 0; k < 3; k++) {
        bool libm = k == 0;
        Mech *mech = load_chain(loops[k]);
        EmitResult res;
        emit_ch(mech, libm, &res);
        const char *call = libm ? "cos(q[" : "ch_sincos";
        if (!libm)
            assert_non_null(strstr(res.c_text, "#define CH_TRIG static __attribute__((noinline))"));
        char *phi = first_part(res.c_text, "phi"), *gamma = first_part(res.c_text, "gamma");
        assert_int_equal(calls_before_store(phi, call, "phi["), 1);
        assert_true(calls_before_store(gamma, call, "gamma[") >= (libm ? 10 : 5));
        free(phi);
        free(gamma);
        emit_result_free(&res);
        pipeline_free(mech);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_each_node_once),
        cmocka_unit_test(test_trig_once_per_function),
        cmocka_unit_test(test_signed_constants_share),
        cmocka_unit_test(test_values_across_calls),
        cmocka_unit_test(test_pair_shares_factor),
        cmocka_unit_test(test_calls_placed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
