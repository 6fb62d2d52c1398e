/* trig.c - sin and cos in the generated code: pairs in one call, calls placed first, the math preamble.
 *
 * A sin and a cos of one angle with temporaries in one chunk are one call
 * of the pair (P_sincos, or the tool's for the JIT); with a two-angle
 * function two groups share a call. Where trigonometry is a call, some
 * calls go to the top of their chunk (calls_first). The preamble declares
 * or includes libm and renders the pair functions the file used.
 */
#include "trig.h"

#include "../base/arena.h"
#include "emitter.h"
#include "template.h"
#include "templates.h"

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void trig_init(EmitTrig *t, const EmitOptions *opt, const char *prefix, int nnodes)
{
    *t = (EmitTrig){0};
    static const char *const suffix[6] = {"sincos", "sincos2", "sincos_s", "sincos_c",
                                          "sincos2_some", "sincos_lane"};
    for (int i = 0; i < 6; i++)
        snprintf(t->names[i], sizeof t->names[i], "%s_%s", prefix, suffix[i]);
    if (!opt->real_float && opt->declare_math) {
        t->sincos_name = opt->libm_trig ? "sincos" : "mechc_sincos";
        t->sincos2_name = opt->libm_trig ? NULL : "mechc_sincos2";
    } else if (!opt->real_float && !opt->libm_trig) {
        t->sincos_name = t->names[0];
        t->sincos2_name = t->names[1];
        t->sin_name = t->names[2];  /* the JIT keeps the tool's pair: its results stay */
        t->cos_name = t->names[3];
        t->sincos2_some_name = t->names[4];
        t->lane_name = t->names[5];
    }
    t->calls = opt->declare_math || opt->libm_trig || opt->real_float;
    trig_graph(t, nnodes);
}

void trig_graph(EmitTrig *t, int nnodes)
{
    t->written = xcalloc((size_t)nnodes + 1, sizeof *t->written);
    t->call_rank = xcalloc((size_t)nnodes + 1, sizeof *t->call_rank);
}

void trig_free(EmitTrig *t)
{
    free(t->written);
    free(t->call_rank);
    t->written = NULL;
    t->call_rank = NULL;
}

bool trig_pair_inline(const EmitTrig *t)
{
    return !t->calls && t->sin_name;
}

void trig_pair_out_of_line(EmitTrig *t)
{
    t->pair_out_of_line = t->calls = true;
    t->sincos_used = t->sincos2_used = t->single_used = false;
}

/* With a sincos function (sincos_name): the cos node of a sin node (or the
   reverse) when both have a temporary in this chunk, so one call computes
   the pair; DAG_NONE when there is none. */
static NodeId sincos_partner(const Emitter *e, NodeId id)
{
    NodeId other = dag_find(e->dag, dag_op(e->dag, id) == OP_SIN ? OP_COS : OP_SIN,
                            dag_node(e->dag, id)->a, -1);
    return other != DAG_NONE && e->sched.temp[other] >= 0
           && !sched_is_import(&e->sched, other, e->chunk) ? other : DAG_NONE;
}

/* The names that receive sin and cos of a sin or cos node's argument: the
   node's and its partner's temporaries (a lone sin or cos gets a discarded
   w temporary for the other). */
static void sincos_targets(const Emitter *e, NodeId id, NodeId partner, char ts[24], char tc[24])
{
    bool is_sin = dag_op(e->dag, id) == OP_SIN;
    int t = e->sched.temp[id];
    if (partner != DAG_NONE) {
        int tp = e->sched.temp[partner];
        snprintf(ts, 24, "u%d", is_sin ? t : tp);
        snprintf(tc, 24, "u%d", is_sin ? tp : t);
    } else {
        snprintf(ts, 24, "%c%d", is_sin ? 'u' : 'w', t);
        snprintf(tc, 24, "%c%d", is_sin ? 'w' : 'u', t);
    }
}

/* id itself when id is the first node of a sin/cos group whose call is
   still to be written (the call belongs there), else DAG_NONE. */
static NodeId sincos_leader(const Emitter *e, NodeId id)
{
    DagOp op = dag_op(e->dag, id);
    if (!e->trig.sincos_name || (op != OP_SIN && op != OP_COS) || e->sched.temp[id] < 0 ||
        e->trig.written[id] || sched_is_import(&e->sched, id, e->chunk))
        return DAG_NONE;
    NodeId partner = sincos_partner(e, id);
    return partner == DAG_NONE || e->sched.pos[partner] > e->sched.pos[id] ? id : DAG_NONE;
}

/* True when id can be written at the top of its chunk: a leaf, or an
   inline expression over leaves. */
static bool at_hand(const Emitter *e, NodeId id)
{
    if (dag_is_leaf(e->dag, id))
        return true;
    if (e->sched.temp[id] >= 0)
        return false;
    const DagNode *n = dag_node(e->dag, id);
    return at_hand(e, n->a) && (dag_op_info[n->op].arity < 2 || at_hand(e, n->b));
}

/* True when the sin or cos id has no partner and goes through sin_name or
   cos_name: compilers that do not optimise then make one libm call for
   it, not two. */
static bool is_single(const Emitter *e, NodeId id)
{
    return e->trig.sin_name && sincos_partner(e, id) == DAG_NONE;
}

/* A batch function's lane (emit_batch_function): the group led by id
   through the lane pair, which clears okl for an angle it leaves to the
   single-state kernel (templates/sincos_lane.tmpl). */
static void put_sincos_lane(Emitter *e, StrBuf *sb, NodeId id, const char *ts, const char *tc)
{
    NodeId partner = sincos_partner(e, id);
    e->trig.lane_used = true;
    e->trig.written[id] = true;
    if (partner != DAG_NONE)
        e->trig.written[partner] = true;
    sb_printf(sb, "    %s_real %s, %s;\n    okl = %s(", e->prefix, ts, tc, e->trig.lane_name);
    emit_put_expr(e, sb, dag_node(e->dag, id)->a, false);
    sb_printf(sb, ", &%s, &%s, okl);\n", ts, tc);
    emit_put_export(e, sb, id);
    emit_put_export(e, sb, partner);
}

/* The sin and cos temporaries of the group led by id, through one sincos
   call; with a two-angle function, a later group of the chunk whose
   argument is already at hand (a leaf, or a node written before this
   one) shares the call, so that both angles go through one instruction
   stream. Where a value goes unused the call names the ones used
   (sin_name, cos_name, sincos2_some_name), so that compilers that do not
   optimise make only their libm calls. */
static void put_sincos(Emitter *e, StrBuf *sb, const SchedChunk *c, int at, NodeId id)
{
    char ts[24], tc[24], ts2[24], tc2[24];
    NodeId arg = dag_node(e->dag, id)->a;
    sincos_targets(e, id, sincos_partner(e, id), ts, tc);
    if (e->lanes && e->trig.lane_name) {
        put_sincos_lane(e, sb, id, ts, tc);
        return;
    }
    NodeId other = DAG_NONE;
    for (int j = at + 1; e->trig.sincos2_name && j < c->nnodes && other == DAG_NONE; j++) {
        NodeId cand = sincos_leader(e, c->nodes[j]);
        if (cand == DAG_NONE)
            continue;
        NodeId cand_arg = dag_node(e->dag, cand)->a;
        if (e->trig.hoisting ? at_hand(e, cand_arg)
                        : dag_is_leaf(e->dag, cand_arg) || e->sched.pos[cand_arg] < at)
            other = cand;
    }
    e->trig.sincos_used = true;      /* sincos2 needs sincos for its rare case */
    e->trig.written[id] = true;
    if (sincos_partner(e, id) != DAG_NONE)
        e->trig.written[sincos_partner(e, id)] = true;
    if (other == DAG_NONE) {
        const char *name = e->trig.sincos_name;
        if (is_single(e, id)) {
            e->trig.single_used = true;
            name = dag_op(e->dag, id) == OP_SIN ? e->trig.sin_name : e->trig.cos_name;
        }
        sb_printf(sb, "    %s_real %s, %s;\n    %s(", e->prefix, ts, tc, name);
        emit_put_expr(e, sb, arg, false);
        sb_printf(sb, ", &%s, &%s);\n", ts, tc);
        emit_put_export(e, sb, id);
        emit_put_export(e, sb, sincos_partner(e, id));
        return;
    }
    NodeId other_partner = sincos_partner(e, other);
    sincos_targets(e, other, other_partner, ts2, tc2);
    e->trig.sincos2_used = true;
    e->trig.written[other] = true;
    if (other_partner != DAG_NONE)
        e->trig.written[other_partner] = true;
    /* the values used, 1 s0, 2 c0, 4 s1, 8 c1 (w temporaries go unused) */
    int used = (ts[0] == 'u') | (tc[0] == 'u') << 1 | (ts2[0] == 'u') << 2 | (tc2[0] == 'u') << 3;
    bool some = used != 15 && e->trig.sincos2_some_name;
    e->trig.single_used |= some;
    sb_printf(sb, "    %s_real %s, %s, %s, %s;\n    %s(", e->prefix, ts, tc, ts2, tc2,
              some ? e->trig.sincos2_some_name : e->trig.sincos2_name);
    emit_put_expr(e, sb, arg, false);
    sb_puts(sb, ", ");
    emit_put_expr(e, sb, dag_node(e->dag, other)->a, false);
    sb_printf(sb, ", &%s, &%s, &%s, &%s", ts, tc, ts2, tc2);
    if (some)
        sb_printf(sb, ", %d", used);
    sb_puts(sb, ");\n");
    emit_put_export(e, sb, id);
    emit_put_export(e, sb, sincos_partner(e, id));
    emit_put_export(e, sb, other);
    emit_put_export(e, sb, other_partner);
}

void trig_put_temporary(Emitter *e, StrBuf *sb, const SchedChunk *c, int at, NodeId id)
{
    int slot = sched_slot(&e->sched, id);
    if (sched_is_import(&e->sched, id, e->chunk)) {
        sb_printf(sb, "    const %s_real u%d = ws[%d]%s;\n", e->prefix, e->sched.temp[id], slot,
                  e->lanes ? "[l]" : "");
        return;
    }
    DagOp op = dag_op(e->dag, id);
    if (e->trig.sincos_name && (op == OP_SIN || op == OP_COS)) {
        if (sincos_leader(e, id) != DAG_NONE)   /* else written with its partner */
            put_sincos(e, sb, c, at, id);
        return;
    }
    if (e->trig.written[id])     /* written right after its partner */
        return;
    NodeId partner = op == OP_SIN || op == OP_COS ? sincos_partner(e, id) : DAG_NONE;
    for (int k = 0; k < (partner == DAG_NONE ? 1 : 2); k++) {
        /* sin and cos of one angle side by side, with no store between
           that could alias the argument: gcc makes them one sincos call */
        NodeId x = k == 0 ? id : partner;
        sb_printf(sb, "    const %s_real u%d = ", e->prefix, e->sched.temp[x]);
        emit_put_expr(e, sb, x, true);
        sb_puts(sb, ";\n");
        e->trig.written[x] = true;
    }
    emit_put_export(e, sb, id);
    emit_put_export(e, sb, partner);
}

/* A sin or cos that trig_put_first writes at the top of its chunk. */
static bool goes_first(const void *ctx, NodeId id)
{
    const Emitter *e = ctx;
    return e->trig.call_rank[id] < e->trig.hoist || e->trig.call_rank[id] < 0;
}

/* Numbers the chunk's sin/cos calls that could go to its top (their
   argument at hand), in order, a pair sharing its number; returns how
   many. Where trig is a call, a pair whose two values share a factor
   gets -1 instead: it always goes first (sched_pair_shares_factor). The
   other nodes of the chunk get INT_MAX. */
static int rank_calls(Emitter *e, const SchedFunction *fn, const SchedChunk *c)
{
    int n = 0;
    for (int at = 0; at < c->nnodes; at++) {
        NodeId id = c->nodes[at];
        DagOp op = dag_op(e->dag, id);
        e->trig.call_rank[id] = INT_MAX;
        if ((op != OP_SIN && op != OP_COS) || e->sched.temp[id] < 0
            || sched_is_import(&e->sched, id, e->chunk) || !at_hand(e, dag_node(e->dag, id)->a))
            continue;
        NodeId partner = sincos_partner(e, id);
        if (partner != DAG_NONE && e->sched.pos[partner] < at)
            e->trig.call_rank[id] = e->trig.call_rank[partner];
        else if ((e->trig.calls || e->trig.place_as_calls)
                 && sched_pair_shares_factor(&e->sched, fn, e->chunk, id))
            e->trig.call_rank[id] = -1;      /* always first */
        else
            e->trig.call_rank[id] = n++;
    }
    return n;
}

/* How many of the chunk's first sin/cos calls go to its top (trig_put_first).
   Where trigonometry is a call (libm, or the tool's sincos from the JIT),
   the number that carries the fewest values across calls (spill.c), none
   on a tie: hoisted, a sin or cos lives across the later calls (it
   returns through memory anyway, but gcc copies it out of the shared
   result slots); left next to its first use, what rows computed before it
   and reuse after it is spilled instead. Inline sincos (the written
   file's default) stays next to its first use, where it keeps few values
   live, unless the chunk has so few that they all stay in registers (then
   the evaluations overlap). */
enum { TRIG_IN_REGISTERS = 8 };

static int calls_first(Emitter *e, const SchedFunction *fn, const SchedChunk *c)
{
    int ncalls = rank_calls(e, fn, c);
    if (!e->trig.calls) {
        int values = 0;
        for (int at = 0; at < c->nnodes; at++) {
            DagOp op = dag_op(e->dag, c->nodes[at]);
            if ((op == OP_SIN || op == OP_COS) && !sched_is_import(&e->sched, c->nodes[at], e->chunk))
                values++;
        }
        if (values <= TRIG_IN_REGISTERS)
            return INT_MAX;
        if (!e->trig.place_as_calls)
            return 0;
    }
    int best = 0, least = INT_MAX;
    for (e->trig.hoist = 0; e->trig.hoist <= ncalls; e->trig.hoist++) {
        int across = sched_values_across_calls(&e->sched, fn, e->chunk, goes_first, e);
        if (across < least) {
            least = across;
            best = e->trig.hoist;
        }
    }
    return best;
}

/* Writes the chunk's first calls_first sin/cos calls (rank_calls). */
void trig_put_first(Emitter *e, StrBuf *sb, const SchedFunction *fn, const SchedChunk *c)
{
    e->trig.hoist = calls_first(e, fn, c);
    e->trig.hoisting = true;
    for (int at = 0; at < c->nnodes; at++) {
        NodeId id = c->nodes[at];
        if (goes_first(e, id) && !e->trig.written[id])
            trig_put_temporary(e, sb, c, at, id);
    }
    e->trig.hoisting = false;
}

/* Numbers each angle (a sin or cos argument) reached from function f's
   outputs once; mark and angle tell f's from earlier functions'. */
static long count_angles(const Dag *dag, const SchedOutput *outs, int n, uint32_t f,
                         uint32_t *mark, uint32_t *angle, NodeId *stack, NodeId *roots)
{
    for (int i = 0; i < n; i++)
        roots[i] = outs[i].value;
    dag_mark_reachable(dag, roots, n, mark, f, stack);
    long angles = 0;
    for (NodeId id = 0; id < dag->count; id++) {
        DagOp op = dag_op(dag, id);
        if (mark[id] == f && (op == OP_SIN || op == OP_COS) && angle[dag_node(dag, id)->a] != f) {
            angle[dag_node(dag, id)->a] = f;
            angles++;
        }
    }
    return angles;
}

long trig_least_calls(const Dag *dag, SchedOutput *const *outs, const int *n, int nfunctions)
{
    size_t count = (size_t)dag->count + 1;
    uint32_t *mark = xcalloc(count, sizeof *mark), *angle = xcalloc(count, sizeof *angle);
    NodeId *stack = xmalloc(count * sizeof *stack), *roots = NULL;
    long calls = 0;
    for (int f = 0; f < nfunctions; f++) {
        if (!outs[f])
            continue;
        roots = xrealloc(roots, (size_t)n[f] + 1, sizeof *roots);
        long angles = count_angles(dag, outs[f], n[f], (uint32_t)f + 1, mark, angle, stack, roots);
        calls += (angles + 1) / 2;
    }
    free(mark);
    free(angle);
    free(stack);
    free(roots);
    return calls;
}

/* Calls of name in the written functions. */
static long count_calls(const StrBuf *parts, const StrBuf *bodies, int nfunctions,
                        const char *name)
{
    char call[170];
    snprintf(call, sizeof call, "%s(", name);
    long n = 0;
    for (int f = 0; f < nfunctions; f++)
        for (int b = 0; b < 2; b++)
            for (const char *at = (b ? bodies : parts)[f].data; (at = strstr(at, call)); at++)
                n++;
    return n;
}

long trig_pair_calls(const EmitTrig *t, const StrBuf *parts, const StrBuf *bodies, int nfunctions)
{
    const char *names[] = {t->sincos_name, t->sincos2_name, t->sin_name, t->cos_name,
                           t->sincos2_some_name};
    long n = 0;
    for (int i = 0; i < 5; i++)
        n += count_calls(parts, bodies, nfunctions, names[i]);
    return n;
}

/* The calls that leave some values unused (sin_name, cos_name,
   sincos2_some_name) as macros, the firmware rules allowing no other
   static function: where optimising (opt) the pair itself, so the bits
   are the pair's and the compiler drops the unused work; elsewhere
   (plain) libm's functions of the values used, `used` a constant that
   even tcc and gcc -O0 fold. */
static void put_some_macros(const EmitTrig *t, StrBuf *opt, StrBuf *plain)
{
    sb_printf(opt, "\n/* angles some of whose values go unused (used: 1 s0, 2 c0, 4 s1,\n"
              "   8 c1): the pair here, libm's functions of the values used where\n"
              "   not optimising */\n"
              "#define %s(x, s, c) %s(x, s, c)\n#define %s(x, s, c) %s(x, s, c)\n"
              "#define %s(x0, x1, s0, c0, s1, c1, used) %s(x0, x1, s0, c0, s1, c1)\n",
              t->sin_name, t->sincos_name, t->cos_name, t->sincos_name,
              t->sincos2_some_name, t->sincos2_name);
    sb_printf(plain, "#define %s(x, s, c) ((void)(c), (void)(*(s) = sin(x)))\n"
              "#define %s(x, s, c) ((void)(s), (void)(*(c) = cos(x)))\n",
              t->sin_name, t->cos_name);
    sb_printf(plain, "#define %s(x0, x1, s0, c0, s1, c1, used) \\\n"
              "    ((void)((used) & 1 ? *(s0) = sin(x0) : 0), \\\n"
              "     (void)((used) & 2 ? *(c0) = cos(x0) : 0), \\\n"
              "     (void)((used) & 4 ? *(s1) = sin(x1) : 0), \\\n"
              "     (void)((used) & 8 ? *(c1) = cos(x1) : 0))\n", t->sincos2_some_name);
}

/* The batch functions' lane pair where optimising (opt), libm's sin and
   cos elsewhere (plain), which never leave a state to the single kernel. */
static void put_lane(const EmitTrig *t, const TemplateVar *sv, int nsv, StrBuf *opt, StrBuf *plain)
{
    const char *bad = template_render(opt, template_sincos_lane, sv, nsv);
    if (bad)
        template_placeholder_bug(bad);
    sb_printf(plain, "#define %s(x, s, c, ok) ((void)(*(s) = sin(x), *(c) = cos(x)), (ok))\n",
              t->lane_name);
}

/* The pair is inlined unless pair_out_of_line. */
void trig_put_math(StrBuf *math, const EmitTrig *t, const EmitOptions *opt, const char *prefix,
                   const char *upper)
{
    if (opt->declare_math) {
        sb_puts(math, "/* libm, declared rather than included: no system headers needed */\n");
        for (int op = OP_POW; op < OP_COUNT; op++)
            sb_printf(math, "double %s(double%s);\n", dag_op_info[op].c_double,
                      dag_op_info[op].arity == 2 ? ", double" : "");
        if (t->sincos_used) {
            sb_printf(math, "void %s(double, double *, double *);\n", t->sincos_name);
            if (t->sincos2_used)
                sb_printf(math, "void %s(double, double, double *, double *, double *, double *);\n",
                          t->sincos2_name);
        }
        sb_puts(math, "void *memset(void *, int, unsigned long);\n");
        sb_printf(math, "#define %s_OPTIMIZED 0   /* libtcc */\n", upper);
        return;
    }
    sb_printf(math, "#include <math.h>\n#include <string.h>\n\n"
              "/* Chosen when the file is compiled: optimizing compilers get the file's\n"
              "   own sin/cos, and a small Jacobian's zeros as stores rather than a\n"
              "   memset; libtcc and gcc -O0 (firmware debug builds), which compile the\n"
              "   sin/cos series into slow code, get sin and cos of <math.h>. */\n"
              "#if defined(__OPTIMIZE__) && !defined(__TINYC__)\n#define %s_OPTIMIZED 1\n"
              "#else\n#define %s_OPTIMIZED 0\n#endif\n", upper, upper);
    if (!t->sincos_used && !t->single_used && !t->lane_used)
        return;
    bool inline_pair = !t->pair_out_of_line;
    char trig[160];
    snprintf(trig, sizeof trig, "%s_TRIG ", upper);
    TemplateVar sv[] = {
        {"P", prefix}, {"PU", upper}, {"STATIC", trig}, {"SINCOS", ""}, {"SINGLE", ""},
        {"TRIG_X86", inline_pair ? "static inline __attribute__((always_inline))"
                                 : "static __attribute__((noinline))"},
        {"TRIG_WHY", inline_pair ? "x86-64 compilers vectorize the two-angle sincos only where "
                                   "they inline it;\n   elsewhere one copy serves all calls"
                                 : "one copy serves all calls: inlined at each of this file's "
                                   "many calls, the\n   pair would take gcc several times as "
                                   "long to compile"},
    };
    int nsv = (int)(sizeof sv / sizeof *sv);
    StrBuf sincos;
    sb_init(&sincos);
    const char *bad = template_render(&sincos, template_sincos, sv, nsv);
    if (!bad && t->sincos2_used) {
        sb_puts(&sincos, "\n");
        bad = template_render(&sincos, template_sincos2, sv, nsv);
    }
    if (bad)
        template_placeholder_bug(bad);
    StrBuf single;
    sb_init(&single);
    sb_puts(&single, "");
    if (t->single_used)
        put_some_macros(t, &sincos, &single);
    if (t->lane_used)
        put_lane(t, sv, nsv, &sincos, &single);
    template_set(sv, nsv, "SINGLE", single.data);
    template_set(sv, nsv, "SINCOS", sincos.data);
    sb_puts(math, "\n");
    bad = template_render(math, template_trig, sv, nsv);
    if (bad)
        template_placeholder_bug(bad);
    sb_free(&sincos);
    sb_free(&single);
}
