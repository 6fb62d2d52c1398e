/* emit.c - renders scheduled straight-line code into the templates.
 *
 * Each generated function is: one `const real uN = ...;` per node that
 * needs a temporary (see sched.c), the other nodes written inline, each
 * store right after the temporaries it is first to need; a function cut
 * into parts passes values between them in its workspace ws. Constants are printed with the fewest digits
 * that read back to the same value, so folded params round-trip exactly.
 * Text from the input reaches the output only as escaped string literals
 * (coordinate and row names) or as a sanitized identifier (the prefix).
 */
#include "emit.h"

#include "../base/arena.h"
#include "../sched/sched.h"
#include "roll.h"
#include "template.h"
#include "templates.h"

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int emit_function_count(const Kinematics *kin)
{
    return kin->dyn.present ? EMIT_FUNCTION_COUNT : EMIT_KINEMATIC_COUNT;
}

/* A parameter of the generated functions. */
typedef struct Param {
    const char *name;
    bool input;         /* read only: const P_real * (q, qd) */
    bool scalar;        /* by value: P_real (t); else written: P_real * */
} Param;

#define IN(name) {#name, true, false}
#define VALUE(name) {#name, false, true}
#define OUT(name) {#name, false, false}
#define NONE {NULL, false, false}
#define P(...) {__VA_ARGS__}
/* Parameters of each generated function (functions.def), in order, up to
   a NULL name (all are void-cast so no mechanism triggers an
   unused-parameter warning); none for the LU's, which emit_lu.c writes. */
static const Param function_params[EMIT_GENERATED_COUNT][8] = {
#define X(E, name, type, family, params) [EMIT_##E] = params,
#include "functions.def"
#undef X
};
#undef IN
#undef VALUE
#undef OUT
#undef NONE
#undef P

EmitOptions emit_default_options(void)
{
    return (EmitOptions){.chunk_nodes = 150, .source_name = "input.mech",
                         .max_ops = mech_default_limits().max_code_ops};
}

static const char *const c_keywords[] = {
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double",
    "else", "enum", "extern", "float", "for", "goto", "if", "inline", "int", "long",
    "register", "restrict", "return", "short", "signed", "sizeof", "static", "struct",
    "switch", "typedef", "union", "unsigned", "void", "volatile", "while", "asm",
    "fortran", "bool", "true", "false", "alignas", "alignof", "noreturn",
    "static_assert", "thread_local", NULL,
};

static bool is_keyword(const char *s)
{
    for (int i = 0; c_keywords[i]; i++)
        if (strcmp(s, c_keywords[i]) == 0)
            return true;
    return false;
}

const char *emit_check_prefix(const char *p)
{
    if (!p[0])
        return "it is empty";
    if (strlen(p) > 64)
        return "it is longer than 64 characters";
    if (!(isalpha((unsigned char)p[0]) || p[0] == '_'))
        return "it must start with a letter or '_'";
    for (const char *c = p; *c; c++)
        if (!(isalnum((unsigned char)*c) || *c == '_'))
            return "it may contain only letters, digits and '_'";
    if (p[0] == '_' && (p[1] == '_' || isupper((unsigned char)p[1])))
        return "identifiers starting with '__' or '_' and a capital are reserved for the C implementation";
    if (is_keyword(p))
        return "it is a C keyword";
    return NULL;
}

/* Header names are not string literals: escapes mean nothing there, and
   ', \, " and trigraphs (??/) are undefined or worse. Only a plain file
   name is accepted. */
const char *emit_check_header_name(const char *name)
{
    if (!name[0])
        return "it is empty";
    if (strlen(name) > 255)
        return "it is longer than 255 characters";
    for (const char *c = name; *c; c++)
        if (!(isalnum((unsigned char)*c) || strchr("._+-", *c)))
            return "it goes into #include \"...\" and may contain only letters, digits and . _ + -";
    return NULL;
}

/* The default prefix: the mechanism name made a safe identifier. */
static void sanitize_prefix(const char *name, char *out, size_t size)
{
    size_t n = 0;
    for (const char *c = name; *c && n + 1 < size && n < 64; c++)
        out[n++] = isalnum((unsigned char)*c) ? *c : '_';
    out[n] = '\0';
    /* a leading '_' is legal but reserved at file scope (C11 7.1.3) */
    if (emit_check_prefix(out) != NULL || out[0] == '_') {
        memmove(out + 2, out, strlen(out) + 1 < size - 2 ? strlen(out) + 1 : size - 2);
        out[size - 1] = '\0';
        out[0] = 'm';
        out[1] = '_';
    }
    if (emit_check_prefix(out) != NULL)
        snprintf(out, size, "mech");
}

/* Shortest decimal that reads back exactly (as double, or as float). */
static void put_literal(StrBuf *sb, double v, bool real_float)
{
    char buf[64];
    if (real_float && isinf((float)v)) {    /* finite as double, not as float */
        sb_puts(sb, v > 0 ? "HUGE_VALF" : "(-HUGE_VALF)");
        return;
    }
    for (int digits = real_float ? 6 : 15; digits <= (real_float ? 9 : 17); digits++) {
        snprintf(buf, sizeof buf, "%.*g", digits, real_float ? (double)(float)v : v);
        double back = strtod(buf, NULL);
        if (real_float ? (float)back == (float)v : back == v)
            break;
    }
    if (!strpbrk(buf, ".eEn"))
        strcat(buf, ".0");
    bool negative = buf[0] == '-';
    if (negative)
        sb_putc(sb, '(');
    sb_puts(sb, buf);
    if (real_float)
        sb_putc(sb, 'f');
    if (negative)
        sb_putc(sb, ')');
}

void emit_put_literal(StrBuf *sb, double v, bool real_float)
{
    put_literal(sb, v, real_float);
}

typedef struct Emitter {
    const Kinematics *kin;
    const Dag *dag;
    const EmitOptions *opt;
    const char *prefix;
    const char *prefix_upper;
    Scheduler sched;
    const char *sincos_name;    /* NULL: sin and cos of <math.h> as written */
    const char *sincos2_name;   /* two angles in one call; NULL: no such function */
    bool sincos_used;           /* some function called sincos_name */
    bool sincos2_used;          /* some function called sincos2_name */
    const char *sin_name;       /* the pair where only its sin is used (a macro:
                                   libm's sin alone where not optimising);
                                   NULL: sincos_name */
    const char *cos_name;       /* the pair where only its cos is used */
    const char *sincos2_some_name;  /* sincos2 where some values go unused */
    bool single_used;           /* some function called one of the three */
    bool *written;              /* per node: its sincos call was already written
                                   (paired with an earlier one) in this chunk */
    int chunk;                  /* the chunk being written */
    int fused;                  /* negations written into their product, this function */
    bool trig_calls;            /* sin and cos are calls, not inlined (calls_first) */
    bool place_as_calls;        /* this function, if split into parts,
                                   places its inline pairs as calls where
                                   they cannot all go first */
    bool pair_out_of_line;      /* the file calls one noinline copy of its pair */
    bool hoisting;              /* in put_calls_first */
    const RollHooks *roll;      /* a loop body's leaves and stores (roll.c) */
    bool rolled;                /* some function has loops (roll.c) */
    int *call_rank;             /* per node: its call's number among the chunk's
                                   sin/cos that may go first (rank_calls) */
    int hoist;                  /* how many of those go first */
} Emitter;

static int c_precedence(const Emitter *e, NodeId id)
{
    if (e->sched.temp[id] >= 0)
        return 4;
    switch (dag_op(e->dag, id)) {
    case OP_ADD: case OP_SUB: return 1;
    case OP_MUL: case OP_DIV: return 2;
    case OP_NEG: return 3;
    default: return 4;
    }
}

static void put_expr(Emitter *e, StrBuf *sb, NodeId id, bool top);

static void put_operand(Emitter *e, StrBuf *sb, NodeId id, int parent, bool right)
{
    int p = c_precedence(e, id);
    /* Equal precedence on the right keeps the graph's grouping: a - (b - c),
       a * (b / c); floating point is not associative. */
    bool paren = p < parent || (right && p == parent);
    if (paren)
        sb_putc(sb, '(');
    put_expr(e, sb, id, false);
    if (paren)
        sb_putc(sb, ')');
}

static void put_expr(Emitter *e, StrBuf *sb, NodeId id, bool top)
{
    const DagNode *n = dag_node(e->dag, id);
    if (!top && e->sched.temp[id] >= 0) {
        sb_printf(sb, "u%d", e->sched.temp[id]);
        return;
    }
    DagOp op = (DagOp)n->op;
    switch (op) {
    case OP_CONST: put_literal(sb, n->value, e->opt->real_float); return;
    case OP_VAR:
        if (e->roll)    /* a slot of a loop body */
            e->roll->leaf(e->roll->ctx, sb, n->a);
        else
            sb_printf(sb, "q[%d]", n->a);
        return;
    case OP_VARD:  sb_printf(sb, "qd[%d]", n->a); return;
    case OP_TIME:  sb_puts(sb, "t"); return;
    case OP_NEG:
        if (sched_fused_negation(&e->sched, id)) {     /* (-c) * y */
            const DagNode *product = dag_node(e->dag, n->a);
            put_literal(sb, -dag_node(e->dag, product->a)->value, e->opt->real_float);
            sb_puts(sb, " * ");
            put_operand(e, sb, product->b, 2, true);
            return;
        }
        sb_putc(sb, '-');
        put_operand(e, sb, n->a, 4, false);
        return;
    case OP_ADD: case OP_SUB: case OP_MUL: case OP_DIV: {
        int p = op == OP_ADD || op == OP_SUB ? 1 : 2;
        put_operand(e, sb, n->a, p, false);
        sb_printf(sb, " %s ", dag_op_info[op].spelling);
        put_operand(e, sb, n->b, p, true);
        return;
    }
    default:
        sb_printf(sb, "%s(", e->opt->real_float ? dag_op_info[op].c_float : dag_op_info[op].c_double);
        put_expr(e, sb, n->a, false);
        if (dag_op_info[op].arity == 2) {
            sb_puts(sb, ", ");
            put_expr(e, sb, n->b, false);
        }
        sb_putc(sb, ')');
        return;
    }
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
    if (!e->sincos_name || (op != OP_SIN && op != OP_COS) || e->sched.temp[id] < 0 ||
        e->written[id] || sched_is_import(&e->sched, id, e->chunk))
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

/* Stores the temporary of id into its workspace slot, if it has one (a
   later chunk of the function imports it). */
static void put_export(const Emitter *e, StrBuf *sb, NodeId id)
{
    int slot = id == DAG_NONE ? -1 : sched_slot(&e->sched, id);
    if (slot >= 0)
        sb_printf(sb, "    ws[%d] = u%d;\n", slot, e->sched.temp[id]);
}

/* True when the sin or cos id has no partner and goes through sin_name or
   cos_name: compilers that do not optimise then make one libm call for
   it, not two. */
static bool is_single(const Emitter *e, NodeId id)
{
    return e->sin_name && sincos_partner(e, id) == DAG_NONE;
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
    NodeId other = DAG_NONE;
    for (int j = at + 1; e->sincos2_name && j < c->nnodes && other == DAG_NONE; j++) {
        NodeId cand = sincos_leader(e, c->nodes[j]);
        if (cand == DAG_NONE)
            continue;
        NodeId cand_arg = dag_node(e->dag, cand)->a;
        if (e->hoisting ? at_hand(e, cand_arg)
                        : dag_is_leaf(e->dag, cand_arg) || e->sched.pos[cand_arg] < at)
            other = cand;
    }
    e->sincos_used = true;      /* sincos2 needs sincos for its rare case */
    e->written[id] = true;
    if (sincos_partner(e, id) != DAG_NONE)
        e->written[sincos_partner(e, id)] = true;
    if (other == DAG_NONE) {
        const char *name = e->sincos_name;
        if (is_single(e, id)) {
            e->single_used = true;
            name = dag_op(e->dag, id) == OP_SIN ? e->sin_name : e->cos_name;
        }
        sb_printf(sb, "    %s_real %s, %s;\n    %s(", e->prefix, ts, tc, name);
        put_expr(e, sb, arg, false);
        sb_printf(sb, ", &%s, &%s);\n", ts, tc);
        put_export(e, sb, id);
        put_export(e, sb, sincos_partner(e, id));
        return;
    }
    NodeId other_partner = sincos_partner(e, other);
    sincos_targets(e, other, other_partner, ts2, tc2);
    e->sincos2_used = true;
    e->written[other] = true;
    if (other_partner != DAG_NONE)
        e->written[other_partner] = true;
    /* the values used, 1 s0, 2 c0, 4 s1, 8 c1 (w temporaries go unused) */
    int used = (ts[0] == 'u') | (tc[0] == 'u') << 1 | (ts2[0] == 'u') << 2 | (tc2[0] == 'u') << 3;
    bool some = used != 15 && e->sincos2_some_name;
    e->single_used |= some;
    sb_printf(sb, "    %s_real %s, %s, %s, %s;\n    %s(", e->prefix, ts, tc, ts2, tc2,
              some ? e->sincos2_some_name : e->sincos2_name);
    put_expr(e, sb, arg, false);
    sb_puts(sb, ", ");
    put_expr(e, sb, dag_node(e->dag, other)->a, false);
    sb_printf(sb, ", &%s, &%s, &%s, &%s", ts, tc, ts2, tc2);
    if (some)
        sb_printf(sb, ", %d", used);
    sb_puts(sb, ");\n");
    put_export(e, sb, id);
    put_export(e, sb, sincos_partner(e, id));
    put_export(e, sb, other);
    put_export(e, sb, other_partner);
}

/* The statement that gives node id (at position at of chunk c) its
   temporary: an import's load, a sincos call for a group's leader, or an
   assignment (then its export). */
static void put_temporary(Emitter *e, StrBuf *sb, const SchedChunk *c, int at, NodeId id)
{
    int slot = sched_slot(&e->sched, id);
    if (sched_is_import(&e->sched, id, e->chunk)) {
        sb_printf(sb, "    const %s_real u%d = ws[%d];\n", e->prefix, e->sched.temp[id], slot);
        return;
    }
    DagOp op = dag_op(e->dag, id);
    if (e->sincos_name && (op == OP_SIN || op == OP_COS)) {
        if (sincos_leader(e, id) != DAG_NONE)   /* else written with its partner */
            put_sincos(e, sb, c, at, id);
        return;
    }
    if (e->written[id])     /* written right after its partner */
        return;
    NodeId partner = op == OP_SIN || op == OP_COS ? sincos_partner(e, id) : DAG_NONE;
    for (int k = 0; k < (partner == DAG_NONE ? 1 : 2); k++) {
        /* sin and cos of one angle side by side, with no store between
           that could alias the argument: gcc makes them one sincos call */
        NodeId x = k == 0 ? id : partner;
        sb_printf(sb, "    const %s_real u%d = ", e->prefix, e->sched.temp[x]);
        put_expr(e, sb, x, true);
        sb_puts(sb, ";\n");
        e->written[x] = true;
    }
    put_export(e, sb, id);
    put_export(e, sb, partner);
}

/* A sin or cos that put_calls_first writes at the top of its chunk. */
static bool goes_first(const void *ctx, NodeId id)
{
    const Emitter *e = ctx;
    return e->call_rank[id] < e->hoist || e->call_rank[id] < 0;
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
        e->call_rank[id] = INT_MAX;
        if ((op != OP_SIN && op != OP_COS) || e->sched.temp[id] < 0
            || sched_is_import(&e->sched, id, e->chunk) || !at_hand(e, dag_node(e->dag, id)->a))
            continue;
        NodeId partner = sincos_partner(e, id);
        if (partner != DAG_NONE && e->sched.pos[partner] < at)
            e->call_rank[id] = e->call_rank[partner];
        else if ((e->trig_calls || e->place_as_calls)
                 && sched_pair_shares_factor(&e->sched, fn, e->chunk, id))
            e->call_rank[id] = -1;      /* always first */
        else
            e->call_rank[id] = n++;
    }
    return n;
}

/* How many of the chunk's first sin/cos calls go to its top (put_calls_first).
   Where trigonometry is a call (libm, or the tool's sincos from the JIT),
   the number that carries the fewest values across calls (spill.c), none
   on a tie: hoisted, a sin or cos lives across the later calls (it
   returns through memory anyway, but gcc copies it out of the shared
   result slots); left next to its first use, what rows computed before it
   and reuse after it is spilled instead. Inline sincos (the written
   file's default) stays next to its first use, where it keeps few values
   live, unless the chunk has so few that they all stay in registers (then
   the evaluations overlap). */
enum { EMIT_TRIG_IN_REGISTERS = 8 };

static int calls_first(Emitter *e, const SchedFunction *fn, const SchedChunk *c)
{
    int ncalls = rank_calls(e, fn, c);
    if (!e->trig_calls) {
        int values = 0;
        for (int at = 0; at < c->nnodes; at++) {
            DagOp op = dag_op(e->dag, c->nodes[at]);
            if ((op == OP_SIN || op == OP_COS) && !sched_is_import(&e->sched, c->nodes[at], e->chunk))
                values++;
        }
        if (values <= EMIT_TRIG_IN_REGISTERS)
            return INT_MAX;
        if (!e->place_as_calls)
            return 0;
    }
    int best = 0, least = INT_MAX;
    for (e->hoist = 0; e->hoist <= ncalls; e->hoist++) {
        int across = sched_values_across_calls(&e->sched, fn, e->chunk, goes_first, e);
        if (across < least) {
            least = across;
            best = e->hoist;
        }
    }
    return best;
}

/* Writes the chunk's first e->hoist sin/cos calls (rank_calls). */
static void put_calls_first(Emitter *e, StrBuf *sb, const SchedChunk *c)
{
    e->hoisting = true;
    for (int at = 0; at < c->nnodes; at++) {
        NodeId id = c->nodes[at];
        if (goes_first(e, id) && !e->written[id])
            put_temporary(e, sb, c, at, id);
    }
    e->hoisting = false;
}

/* The statements of one chunk: each store right after the temporaries it
   is the first to need. */
static void put_chunk(Emitter *e, StrBuf *sb, const SchedFunction *fn, int chunk,
                      EmitFunction which, bool workspace)
{
    e->fused += sched_prepare_chunk(&e->sched, fn, chunk);
    e->chunk = chunk;
    const SchedChunk *c = &fn->chunks[chunk];
    if (!e->roll) {     /* a loop body's parameters are the function's */
        sb_puts(sb, "    ");
        for (const Param *p = function_params[which]; p->name; p++)
            sb_printf(sb, "%s(void)%s;", p == function_params[which] ? "" : " ", p->name);
        sb_puts(sb, workspace ? " (void)ws;\n" : "\n");
    }
    e->hoist = calls_first(e, fn, c);
    put_calls_first(e, sb, c);
    int at = 0;
    for (int i = 0; i < c->count; i++) {
        for (; at < c->ends[i]; at++)
            if (e->sched.temp[c->nodes[at]] >= 0 && !e->written[c->nodes[at]])
                put_temporary(e, sb, c, at, c->nodes[at]);
        const SchedOutput *o = &fn->outputs[c->first + i];
        if (e->roll)
            e->roll->store(e->roll->ctx, sb, o);
        else
            sb_printf(sb, "    %s[%d] = ", o->array, o->index);
        put_expr(e, sb, o->value, false);
        sb_puts(sb, ";\n");
    }
    for (; at < c->nnodes; at++)    /* trig given to this chunk by a later one */
        if (e->sched.temp[c->nodes[at]] >= 0 && !e->written[c->nodes[at]])
            put_temporary(e, sb, c, at, c->nodes[at]);
    for (int i = 0; i < c->nnodes; i++) {   /* temporaries end with their chunk */
        e->sched.temp[c->nodes[i]] = -1;
        e->written[c->nodes[i]] = false;
    }
}

/* q, qd, t, gamma -> "const P_real *q, const P_real *qd, P_real t, P_real *gamma" */
static void put_signature(StrBuf *sb, const char *prefix, EmitFunction which)
{
    for (const Param *p = function_params[which]; p->name; p++)
        sb_printf(sb, "%s%s%s_real %s%s", p == function_params[which] ? "" : ", ",
                  p->input ? "const " : "", prefix, p->scalar ? "" : "*", p->name);
}

/* q, qd, t, gamma -> "q, qd, t, gamma" */
static void put_arguments(StrBuf *sb, EmitFunction which)
{
    for (const Param *p = function_params[which]; p->name; p++)
        sb_printf(sb, "%s%s", p == function_params[which] ? "" : ", ", p->name);
}

/* Fills parts (static helpers, one per chunk) and body (the function's
   statements) for one generated function. */
static void put_function(Emitter *e, SchedFunction *fn, EmitFunction which,
                         StrBuf *parts, StrBuf *body)
{
    if (fn->nchunks == 1) {
        put_chunk(e, body, fn, 0, which, false);
        return;
    }
    const char *p = e->prefix;
    bool workspace = fn->nslots > 0;    /* values that cross parts */
    if (workspace)
        sb_printf(body, "    %s_real ws[%d];\n", p, fn->nslots);
    for (int c = 0; c < fn->nchunks; c++) {
        sb_printf(parts, "%s_PART void %s_%s_part%d(", e->prefix_upper, p, emit_function_names[which], c);
        put_signature(parts, p, which);
        if (workspace)
            sb_printf(parts, ", %s_real *ws", p);
        sb_puts(parts, ")\n{\n");
        put_chunk(e, parts, fn, c, which, workspace);
        sb_puts(parts, "}\n\n");
        sb_printf(body, "    %s_%s_part%d(", p, emit_function_names[which], c);
        put_arguments(body, which);
        sb_puts(body, workspace ? ", ws);\n" : ");\n");
    }
}

static void add_output(SchedOutput **outs, int *n, const char *array, int index, NodeId value)
{
    (*outs)[(*n)++] = (SchedOutput){array, index, value};
}

/* The dynamics functions' outputs: M's entries (dense, or its nonzeros),
   then Q. */
static void collect_dynamics(const Kinematics *kin, EmitFunction which, SchedOutput **outs, int *n)
{
    const Model *m = kin->model;
    const Dynamics *dyn = &kin->dyn;
    if (which != EMIT_FORCE)
        for (int k = 0; k < dyn->nnz; k++) {
            const JacEntry *e = &dyn->mass[k];
            if (which == EMIT_MASS_NZ)
                add_output(outs, n, "vals", k, e->value);
            else
                add_output(outs, n, "M", e->row * m->nq + e->col, e->value);
        }
    if (which == EMIT_MASS_NZ && dyn->nnz == 0)     /* the one placeholder slot */
        add_output(outs, n, "vals", 0, DAG_ZERO);
    if (which == EMIT_FORCE || which == EMIT_EOM)
        for (int j = 0; j < m->nq; j++)
            add_output(outs, n, "Q", j, dyn->force[j]);
}

/* The outputs of each function. The fused _all and _all_nz go row by row
   (phi, Jacobian row, nu, gamma of row r, then row r + 1) so that a chunk holds
   whole rows and shares their sin/cos and products across the four; _eom
   the same without phi and nu, then M and Q. */
static void collect_outputs(const Kinematics *kin, EmitFunction which, SchedOutput **outs, int *n)
{
    const Model *m = kin->model;
    *outs = xmalloc((size_t)(m->nh + 2 * m->nr + 2 * kin->nnz + 1 + kin->dyn.nnz + m->nq)
                    * sizeof **outs);
    *n = 0;
    bool all = which == EMIT_ALL || which == EMIT_ALL_NZ, eom = which == EMIT_EOM;
    if (which >= EMIT_MASS && !eom) {
        collect_dynamics(kin, which, outs, n);
        return;
    }
    for (int r = 0; r < m->nr; r++) {
        if ((which == EMIT_PHI || all) && r < m->nh)
            add_output(outs, n, "phi", r, kin->phi[r]);
        for (int k = kin->row_start[r]; k < kin->row_start[r + 1]; k++) {
            const JacEntry *j = &kin->jac[k];
            if (which == EMIT_ALL || eom || which == EMIT_JAC)
                add_output(outs, n, "jac", j->row * m->nq + j->col, j->value);
            else if (which == EMIT_JAC_NZ)
                add_output(outs, n, "vals", k, j->value);
            else if (which == EMIT_ALL_NZ)
                add_output(outs, n, "jac_vals", k, j->value);
        }
        if (which == EMIT_NU || all)
            add_output(outs, n, "nu", r, kin->nu[r]);
        if (which == EMIT_GAMMA || all || eom)
            add_output(outs, n, "gamma", r, kin->gamma[r]);
    }
    if (which == EMIT_JAC_NZ && kin->nnz == 0)     /* the one placeholder slot */
        add_output(outs, n, "vals", 0, DAG_ZERO);
    if (which == EMIT_ALL_NZ && kin->nnz == 0)
        add_output(outs, n, "jac_vals", 0, DAG_ZERO);
    if (eom)
        collect_dynamics(kin, which, outs, n);
}

static void put_string_list(StrBuf *sb, const char *const *names, int n)
{
    for (int i = 0; i < n; i++) {
        sb_puts(sb, "    ");
        sb_put_c_string(sb, names[i]);
        sb_puts(sb, ",\n");
    }
}

static void put_int_list(StrBuf *sb, const JacEntry *entries, int nnz, bool rows)
{
    for (int k = 0; k < nnz; k++) {
        sb_printf(sb, "%s%d,", k % 16 == 0 ? "    " : " ", rows ? entries[k].row : entries[k].col);
        if (k % 16 == 15 || k == nnz - 1)
            sb_putc(sb, '\n');
    }
    if (nnz == 0)
        sb_puts(sb, "    0\n");
}

/* The zero-fill of the dense Jacobian before its nonzeros are stored:
   one memset, which every compiler provides, freestanding or not (gcc and
   clang may call it for any fill loop); a loop as written runs element by
   element under libtcc, gcc -O0 and -O1. Optimizing compilers get a small
   matrix's structural zeros as stores instead (P_OPTIMIZED, put_math):
   gcc turns a short memset into rep stos, which costs more there. */
enum { EMIT_ZERO_STORES_MAX = 256 };
static void put_zero_fill(StrBuf *sb, const Kinematics *kin, const EmitOptions *opt,
                          const char *prefix, const char *upper)
{
    const Model *m = kin->model;
    bool stores = !opt->declare_math && (long)m->nr * m->nq <= EMIT_ZERO_STORES_MAX;
    if (stores)
        sb_printf(sb, "#if %s_OPTIMIZED\n", upper);
    /* eight stores a line */
    for (int r = 0, k = 0, n = 0; stores && r < m->nr; r++)
        for (int c = 0; c < m->nq; c++) {
            if (k < kin->nnz && kin->jac[k].row == r && kin->jac[k].col == c) {
                k++;
                continue;
            }
            const char *sep = n == 0 ? "    " : n % 8 == 0 ? "\n    " : " ";
            sb_printf(sb, "%sjac[%d] = 0;", sep, r * m->nq + c);
            n++;
        }
    if (stores)
        sb_puts(sb, "\n#else\n");
    sb_printf(sb, "    memset(jac, 0, sizeof(%s_real) * %s_NR * %s_NQ);", prefix, upper, upper);
    if (stores)
        sb_puts(sb, "\n#endif");
}

/* The spread Jacobian's moves, one statement each (jac_spread.tmpl): jac[at]
   = jac[base + k] for every entry k, in order, then a zero in each slot of
   the packed tail that no entry moved into. Eight a line. */
static void put_jac_moves(StrBuf *sb, const Kinematics *kin)
{
    const Model *m = kin->model;
    long total = (long)m->nr * m->nq, nnz = kin->nnz > 0 ? kin->nnz : 1, base = total - nnz;
    long n = 0, k = 0;
    for (; k < kin->nnz; k++, n++)
        sb_printf(sb, "%sjac[%ld] = jac[%ld];", n == 0 ? "    " : n % 8 == 0 ? "\n    " : " ",
                  (long)kin->jac[k].row * m->nq + kin->jac[k].col, base + k);
    k = 0;      /* the targets increase: walk them beside the tail's slots */
    for (long s = base; s < total; s++) {
        while (k < kin->nnz && (long)kin->jac[k].row * m->nq + kin->jac[k].col < s)
            k++;
        if (k < kin->nnz && (long)kin->jac[k].row * m->nq + kin->jac[k].col == s)
            continue;
        sb_printf(sb, "%sjac[%ld] = 0;", n == 0 ? "    " : n % 8 == 0 ? "\n    " : " ", s);
        n++;
    }
}

/* The banner names the input by its base name, with anything that could
   end the comment or confuse a reader replaced. */
static void put_banner(StrBuf *sb, const char *source)
{
    const char *base = strrchr(source, '/');
    base = base ? base + 1 : source;
    sb_printf(sb, "Code generated by mechc %s from ", MECHC_VERSION);
    for (const char *c = base; *c; c++)
        sb_putc(sb, isalnum((unsigned char)*c) || strchr("._+-", *c) ? *c : '_');
    sb_puts(sb, ". DO NOT EDIT.");
}

/* The prefix (out, from opt or the mechanism name) and the options that
   reach the C text: false with diag filled when one is unusable. */
static bool check_options(const Model *m, const EmitOptions *opt, EmitResult *out, Diag *diag)
{
    if (opt->prefix) {
        const char *why = emit_check_prefix(opt->prefix);
        if (why) {
            diag_error_nopos(diag, "--prefix '%s' cannot be used: %s", opt->prefix, why);
            return false;
        }
        snprintf(out->prefix, sizeof out->prefix, "%s", opt->prefix);
    } else {
        sanitize_prefix(m->name, out->prefix, sizeof out->prefix);
    }
    /* A nonzero constant that float rounds to zero would change the
       equations (x / 1e-50 becoming x / 0): refuse rather than emit it. */
    if (opt->real_float) {
        for (NodeId id = 0; id < m->dag.count; id++) {
            double v;
            if (dag_is_const(&m->dag, id, &v) && v != 0.0 && (float)v == 0.0f) {
                diag_error_nopos(diag, "the constant %.17g is too small for float (it would "
                                 "become 0); use --real double or rescale the mechanism", v);
                return false;
            }
        }
    }
    if (opt->header_name) {
        const char *why = emit_check_header_name(opt->header_name);
        if (why) {
            diag_error_nopos(diag, "the header name '%s' cannot be used: %s", opt->header_name, why);
            return false;
        }
    }
    return true;
}

/* A loop body of roll.c: the shape's graph scheduled as one chunk and
   written by the same printer as straight-line code, its slots and store
   indices through hooks. Returns its operations. */
static int put_roll_body(void *emitter, const Dag *dag, SchedOutput *outs, int n,
                         const RollHooks *hooks, StrBuf *sb)
{
    Emitter e = *(const Emitter *)emitter;
    e.dag = dag;
    e.roll = hooks;
    e.written = xcalloc((size_t)dag->count + 1, sizeof *e.written);
    e.call_rank = xcalloc((size_t)dag->count + 1, sizeof *e.call_rank);
    sched_init(&e.sched, dag, 1 << 28);     /* one chunk: a loop body is small */
    SchedFunction fn;
    sched_function(&e.sched, outs, n, &fn);
    e.fused = 0;
    put_chunk(&e, sb, &fn, 0, EMIT_PHI, false);
    int ops = fn.ops - e.fused;
    sched_function_free(&fn);
    sched_free(&e.sched);
    free(e.written);
    free(e.call_rank);
    return ops;
}

/* Rolls what roll.c finds in function f's outputs (writing its tables and
   loops into parts and body) when opt->roll asks for it; *outs and *n
   become the outputs left for straight-line code. Returns the rolled
   operations per call. */
static long roll_outputs(Emitter *e, EmitFunction f, SchedOutput **outs, int *n, StrBuf *parts,
                         StrBuf *body)
{
    const EmitOptions *opt = e->opt;
    if (opt->roll == EMIT_ROLL_NEVER || f >= EMIT_MASS
        || (opt->roll == EMIT_ROLL_AUTO && e->kin->model->nr < EMIT_ROLL_AUTO_ROWS))
        return 0;
    RollContext rc = {
        .kin = e->kin, .prefix = e->prefix, .function = emit_function_names[f],
        .real_float = opt->real_float, .sincos_name = e->sincos_name, .sin_name = e->sin_name,
        .cos_name = e->cos_name, .sincos2_name = e->sincos2_name,
        .min_members = opt->roll == EMIT_ROLL_ALWAYS ? 2 : EMIT_ROLL_AUTO_MEMBERS,
        .write_body = put_roll_body, .emitter = e,
        .sincos_used = &e->sincos_used, .single_used = &e->single_used,
        .sincos2_used = &e->sincos2_used,
    };
    SchedOutput *rest;
    int nrest;
    long ops;
    if (roll_function(&rc, *outs, *n, parts, body, &rest, &nrest, &ops) == 0)
        return 0;
    free(*outs);
    *outs = rest;
    *n = nrest;
    e->rolled = true;
    return ops;
}

bool emit_function_written(const EmitOptions *opt, EmitFunction f)
{
    switch (emit_function_family[f]) {
    case EMIT_DENSE: return !opt->sparse_only;
    case EMIT_SPARSE: return opt->all_nz || opt->sparse_only;
    case EMIT_LU: return opt->lu;
    case EMIT_KIN: case EMIT_DYN: case EMIT_FAMILY_COUNT: break;
    }
    return true;
}

bool emit_direct_jac_default(const Kinematics *kin, int roll)
{
    bool rolls = roll == EMIT_ROLL_ALWAYS
                 || (roll == EMIT_ROLL_AUTO && kin->model->nr >= EMIT_ROLL_AUTO_ROWS);
    return kin->nnz <= EMIT_DIRECT_JAC_NNZ || rolls;
}

/* True when function f has code of its own in the file (the dense
   Jacobian is spread from jac_nz, jac_spread.tmpl, unless direct). */
static bool is_written(const Emitter *e, EmitFunction f)
{
    return (int)f < emit_function_count(e->kin) && (f != EMIT_JAC || e->opt->direct_jac)
           && emit_function_written(e->opt, f);
}

/* Fewest calls of the file's own sin/cos functions the written functions
   can make: each evaluates every angle it uses, two at most a call. Above
   EMIT_INLINE_TRIG_MAX the file is written once, its calls placed as
   real calls from the start. */
static long pair_calls_at_least(const Emitter *e)
{
    const Dag *dag = e->dag;
    size_t n = (size_t)dag->count + 1;
    uint32_t *mark = xcalloc(n, sizeof *mark), *angle = xcalloc(n, sizeof *angle);
    NodeId *stack = xmalloc(n * sizeof *stack), *roots = NULL;
    long calls = 0;
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++) {
        if (!is_written(e, (EmitFunction)f))
            continue;
        SchedOutput *outs;
        int nout;
        collect_outputs(e->kin, (EmitFunction)f, &outs, &nout);
        roots = xrealloc(roots, (size_t)nout + 1, sizeof *roots);
        for (int i = 0; i < nout; i++)
            roots[i] = outs[i].value;
        dag_mark_reachable(dag, roots, nout, mark, (uint32_t)f + 1, stack);
        long angles = 0;
        for (NodeId id = 0; id < dag->count; id++) {
            DagOp op = dag_op(dag, id);
            if (mark[id] == (uint32_t)f + 1 && (op == OP_SIN || op == OP_COS)
                && angle[dag_node(dag, id)->a] != (uint32_t)f + 1) {
                angle[dag_node(dag, id)->a] = (uint32_t)f + 1;
                angles++;
            }
        }
        calls += (angles + 1) / 2;
        free(outs);
    }
    free(mark);
    free(angle);
    free(stack);
    free(roots);
    return calls;
}

/* Schedules and writes every function into parts and bodies (initialized
   here, freed by the caller); false when the code would pass max_ops. */
static bool put_functions(Emitter *e, StrBuf *parts, StrBuf *bodies, EmitResult *out)
{
    const EmitOptions *opt = e->opt;
    sched_init(&e->sched, e->dag,
               opt->chunk_nodes > 0 ? opt->chunk_nodes : emit_default_options().chunk_nodes);
    e->sched.max_ops = opt->max_ops;
    bool fits = true;
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++) {
        sb_init(&parts[f]);
        sb_init(&bodies[f]);
        sb_puts(&parts[f], "");
        sb_puts(&bodies[f], "");
        if (!is_written(e, (EmitFunction)f) || !fits)
            continue;
        SchedOutput *outs;
        int n;
        collect_outputs(e->kin, (EmitFunction)f, &outs, &n);
        long rolled = roll_outputs(e, (EmitFunction)f, &outs, &n, &parts[f], &bodies[f]);
        SchedFunction fn;
        /* gamma split into parts places its inline pairs as calls
           (calls_first) where they cannot all go first: chain N = 10
           1.04-1.05x its --trig libm twin under gcc -O0 rather than
           1.11-1.12x, and 3-5% faster under gcc -O2; the other functions
           lost up to 3% so, and one-part gammas up to 10% (Andrews',
           gcc -O2) (README, "Written files") */
        if (sched_function(&e->sched, outs, n, &fn)) {
            e->fused = 0;
            e->place_as_calls = f == EMIT_GAMMA && e->sin_name && fn.nchunks > 1;
            put_function(e, &fn, (EmitFunction)f, &parts[f], &bodies[f]);
            out->ops[f] = (int)(fn.ops - e->fused + rolled);
            out->chunks[f] = fn.nchunks;
        } else {
            fits = false;
        }
        sched_function_free(&fn);
        e->place_as_calls = false;
    }
    sched_free(&e->sched);
    if (!opt->direct_jac && !opt->sparse_only) {
        out->ops[EMIT_JAC] = out->ops[EMIT_JAC_NZ];
        out->chunks[EMIT_JAC] = out->chunks[EMIT_JAC_NZ];
    }
    return fits;
}

/* Calls of name in the written functions. */
static long count_calls(const StrBuf *parts, const StrBuf *bodies, const char *name)
{
    char call[170];
    snprintf(call, sizeof call, "%s(", name);
    long n = 0;
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
        for (int b = 0; b < 2; b++)
            for (const char *at = (b ? bodies : parts)[f].data; (at = strstr(at, call)); at++)
                n++;
    return n;
}

/* Calls of the written file's own sin/cos functions. Inlined at every
   call (gcc splits the pair function at its rare-case test and calls the
   rest out of line, through memory, unless forced), the pair takes gcc
   -O2 several times as long as libm calls would: files with more calls
   than EMIT_INLINE_TRIG_MAX call one copy. */
enum { EMIT_INLINE_TRIG_MAX = 64 };
static long pair_calls(const Emitter *e, const StrBuf *parts, const StrBuf *bodies)
{
    return count_calls(parts, bodies, e->sincos_name) + count_calls(parts, bodies, e->sincos2_name) +
           count_calls(parts, bodies, e->sin_name) + count_calls(parts, bodies, e->cos_name) +
           count_calls(parts, bodies, e->sincos2_some_name);
}

/* The calls that leave some values unused (sin_name, cos_name,
   sincos2_some_name) as macros, the firmware rules allowing no other
   static function: where optimising (opt) the pair itself, so the bits
   are the pair's and the compiler drops the unused work; elsewhere
   (plain) libm's functions of the values used, `used` a constant that
   even tcc and gcc -O0 fold. */
static void put_some_macros(const Emitter *e, StrBuf *opt, StrBuf *plain)
{
    sb_printf(opt, "\n/* angles some of whose values go unused (used: 1 s0, 2 c0, 4 s1,\n"
              "   8 c1): the pair here, libm's functions of the values used where\n"
              "   not optimising */\n"
              "#define %s(x, s, c) %s(x, s, c)\n#define %s(x, s, c) %s(x, s, c)\n"
              "#define %s(x0, x1, s0, c0, s1, c1, used) %s(x0, x1, s0, c0, s1, c1)\n",
              e->sin_name, e->sincos_name, e->cos_name, e->sincos_name,
              e->sincos2_some_name, e->sincos2_name);
    sb_printf(plain, "#define %s(x, s, c) ((void)(c), (void)(*(s) = sin(x)))\n"
              "#define %s(x, s, c) ((void)(s), (void)(*(c) = cos(x)))\n",
              e->sin_name, e->cos_name);
    sb_printf(plain, "#define %s(x0, x1, s0, c0, s1, c1, used) \\\n"
              "    ((void)((used) & 1 ? *(s0) = sin(x0) : 0), \\\n"
              "     (void)((used) & 2 ? *(c0) = cos(x0) : 0), \\\n"
              "     (void)((used) & 4 ? *(s1) = sin(x1) : 0), \\\n"
              "     (void)((used) & 8 ? *(c1) = cos(x1) : 0))\n", e->sincos2_some_name);
}

/* Every placeholder of a template is given a value: one without is a bug. */
static _Noreturn void placeholder_bug(const char *name)
{
    fprintf(stderr, "mechc: internal error: template placeholder '%.20s' has no value\n", name);
    abort();
}

/* What the kernels call for math: libm declared (JIT) or included, and
   the sincos functions the emitter used, for written files chosen by the
   compiler (templates/trig.tmpl), the pair inlined unless pair_out_of_line. */
static void put_math(StrBuf *math, const Emitter *e)
{
    const char *upper = e->prefix_upper;
    if (e->opt->declare_math) {
        sb_puts(math, "/* libm, declared rather than included: no system headers needed */\n");
        for (int op = OP_POW; op < OP_COUNT; op++)
            sb_printf(math, "double %s(double%s);\n", dag_op_info[op].c_double,
                      dag_op_info[op].arity == 2 ? ", double" : "");
        if (e->sincos_used) {
            sb_printf(math, "void %s(double, double *, double *);\n", e->sincos_name);
            if (e->sincos2_used)
                sb_printf(math, "void %s(double, double, double *, double *, double *, double *);\n",
                          e->sincos2_name);
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
    if (!e->sincos_used && !e->single_used)
        return;
    bool inline_pair = !e->pair_out_of_line;
    char trig[160];
    snprintf(trig, sizeof trig, "%s_TRIG ", upper);
    TemplateVar sv[] = {
        {"P", e->prefix}, {"PU", upper}, {"STATIC", trig}, {"SINCOS", ""}, {"SINGLE", ""},
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
    if (!bad && e->sincos2_used) {
        sb_puts(&sincos, "\n");
        bad = template_render(&sincos, template_sincos2, sv, nsv);
    }
    if (bad)
        placeholder_bug(bad);
    StrBuf single;
    sb_init(&single);
    sb_puts(&single, "");
    if (e->single_used)
        put_some_macros(e, &sincos, &single);
    template_set(sv, nsv, "SINGLE", single.data);
    template_set(sv, nsv, "SINCOS", sincos.data);
    sb_puts(math, "\n");
    bad = template_render(math, template_trig, sv, nsv);
    if (bad)
        placeholder_bug(bad);
    sb_free(&sincos);
    sb_free(&single);
}

/* The data section's lists: initial values, names, the Jacobian's
   structure and (a file with masses) M's, mrow and mcol. */
static void put_data(const Emitter *e, StrBuf *q0, StrBuf *coords, StrBuf *rows, StrBuf *jrow,
                     StrBuf *jcol, StrBuf *mrow, StrBuf *mcol)
{
    const Model *m = e->kin->model;
    for (int i = 0; i < m->nq; i++) {
        sb_puts(q0, "    ");
        put_literal(q0, m->q0[i], e->opt->real_float);
        sb_puts(q0, ",\n");
    }
    put_string_list(coords, m->coord_names, m->nq);
    for (int r = 0; r < m->nr; r++) {
        sb_puts(rows, "    ");
        sb_put_c_string(rows, m->rows[r].name);
        sb_puts(rows, ",\n");
    }
    put_int_list(jrow, e->kin->jac, e->kin->nnz, true);
    put_int_list(jcol, e->kin->jac, e->kin->nnz, false);
    put_int_list(mrow, e->kin->dyn.mass, e->kin->dyn.nnz, true);
    put_int_list(mcol, e->kin->dyn.mass, e->kin->dyn.nnz, false);
}

/* The dynamics part of the source (DYNAMICS) and of the interface
   (DYN_INTERFACE), rendered from vars without their last newline (the
   placeholder's line gives it back); both stay empty for a file without
   masses, whose output is what it always was. Returns a placeholder
   without value, or NULL. */
static const char *put_dynamics(const Emitter *e, TemplateVar *vars, int nvars, StrBuf *dyn_c,
                                StrBuf *dyn_h)
{
    if (!e->kin->dyn.present)
        return NULL;
    const char *bad = template_render(dyn_h, template_dynamics_h, vars, nvars);
    if (!bad)
        bad = template_render(dyn_c, template_dynamics, vars, nvars);
    if (bad)
        return bad;
    dyn_h->data[--dyn_h->len] = '\0';
    dyn_c->data[--dyn_c->len] = '\0';
    template_set(vars, nvars, "DYN_INTERFACE", dyn_h->data);
    template_set(vars, nvars, "DYNAMICS", dyn_c->data);
    return NULL;
}

/* PREFIX_all_nz's declaration and definition (templates/all_nz*.tmpl);
   both empty unless asked for, so that other files keep their bytes. */
static void put_all_nz(const Emitter *e, const StrBuf *parts, const StrBuf *bodies, StrBuf *decl,
                       StrBuf *def)
{
    if (!e->opt->all_nz)
        return;
    TemplateVar v[] = {
        {"P", e->prefix}, {"PU", e->prefix_upper},
        {"ALL_NZ_PARTS", parts[EMIT_ALL_NZ].data}, {"ALL_NZ_BODY", bodies[EMIT_ALL_NZ].data},
    };
    int nv = (int)(sizeof v / sizeof *v);
    const char *bad = template_render(decl, template_all_nz_decl, v, nv);
    if (!bad)
        bad = template_render(def, template_all_nz, v, nv);
    if (bad)
        placeholder_bug(bad);
    def->data[--def->len] = '\0';   /* mech.c.tmpl ends the line after it */
}

/* The dense jac and all (their declarations, JAC_DECL and ALL_DECL, the
   definitions JAC and ALL), or, sparse-only, the interface's mark
   (SPARSE_ONLY) and none of them. ALL is rendered without its last
   newline (mech.c.tmpl ends the line after it). Returns a placeholder
   without value, or NULL. */
static const char *put_dense(const Emitter *e, TemplateVar *vars, int nvars, StrBuf *bufs[5])
{
    const char *bad;
    if (e->opt->sparse_only) {
        bad = template_render(bufs[4], template_sparse_only, vars, nvars);
        template_set(vars, nvars, "SPARSE_ONLY", bufs[4]->data);
        return bad;
    }
    bad = template_render(bufs[0], template_jac_decl, vars, nvars);
    if (!bad)
        bad = template_render(bufs[1], template_all_decl, vars, nvars);
    if (!bad)
        bad = template_render(bufs[2], e->opt->direct_jac ? template_jac_direct
                                                          : template_jac_spread, vars, nvars);
    if (!bad)
        bad = template_render(bufs[3], template_all, vars, nvars);
    if (bad)
        return bad;
    bufs[3]->data[--bufs[3]->len] = '\0';
    template_set(vars, nvars, "JAC_DECL", bufs[0]->data);
    template_set(vars, nvars, "ALL_DECL", bufs[1]->data);
    template_set(vars, nvars, "JAC", bufs[2]->data);
    template_set(vars, nvars, "ALL", bufs[3]->data);
    return NULL;
}

/* The sizes and the include guard, as text for the templates. */
typedef struct EmitSizes {
    char nq[32], nh[32], nv[32], nnz[32], mnnz[32], guard[160];
} EmitSizes;

static void put_sizes(const Emitter *e, EmitSizes *z)
{
    const Model *m = e->kin->model;
    snprintf(z->nq, sizeof z->nq, "%d", m->nq);
    snprintf(z->nh, sizeof z->nh, "%d", m->nh);
    snprintf(z->nv, sizeof z->nv, "%d", m->nv);
    /* C has no zero-length arrays: a Jacobian with no nonzeros keeps one
       placeholder entry (row 0, column 0, value 0). */
    snprintf(z->nnz, sizeof z->nnz, "%d", e->kin->nnz > 0 ? e->kin->nnz : 1);
    snprintf(z->mnnz, sizeof z->mnnz, "%d", e->kin->dyn.nnz > 0 ? e->kin->dyn.nnz : 1);
    snprintf(z->guard, sizeof z->guard, "%s_MECHC_H", e->prefix_upper);
}

/* Fills the templates with the written functions: out's source and header. */
static void render_files(const Emitter *e, StrBuf *parts, StrBuf *bodies, EmitResult *out)
{
    const EmitOptions *opt = e->opt;
    const Model *m = e->kin->model;
    const char *upper = e->prefix_upper;
    StrBuf banner, ops, q0, coords, rows, jrow, jcol, math, iface, zero, jac, inc, moves, nzd, nzf;
    StrBuf mrow, mcol, dyn_c, dyn_h, jac_decl, all_decl, all_def, mark;
    StrBuf *all_bufs[] = {&banner, &ops, &q0, &coords, &rows, &jrow, &jcol, &math, &iface,
                          &zero, &jac, &inc, &moves, &nzd, &nzf, &mrow, &mcol, &dyn_c, &dyn_h,
                          &jac_decl, &all_decl, &all_def, &mark};
    StrBuf *dense_bufs[5] = {&jac_decl, &all_decl, &jac, &all_def, &mark};
    for (size_t i = 0; i < sizeof all_bufs / sizeof *all_bufs; i++) {
        sb_init(all_bufs[i]);
        sb_puts(all_bufs[i], "");
    }
    put_banner(&banner, opt->source_name ? opt->source_name : m->file);
    for (int f = 0; f < emit_function_count(e->kin); f++)
        if (emit_function_written(opt, (EmitFunction)f))
            sb_printf(&ops, "%s%s %d", f ? ", " : "", emit_function_names[f], out->ops[f]);
    put_data(e, &q0, &coords, &rows, &jrow, &jcol, &mrow, &mcol);
    put_zero_fill(&zero, e->kin, opt, out->prefix, upper);
    if (opt->sparse_only)
        ;   /* no dense jac to fill */
    else if (!opt->direct_jac && e->rolled)    /* a rolled file stays small: the loop everywhere */
        sb_printf(&moves, "    for (int k = 0; k < %s_NNZ; ++k) {\n        %s_real v = packed[k];\n"
                  "        packed[k] = 0;\n        jac[%s_jac_row[k] * %s_NQ + %s_jac_col[k]] = v;\n"
                  "    }", upper, out->prefix, out->prefix, upper, out->prefix);
    else if (!opt->direct_jac)
        put_jac_moves(&moves, e->kin);
    put_math(&math, e);
    put_all_nz(e, parts, bodies, &nzd, &nzf);
    emit_lu(e->kin, opt, out->prefix, upper, &nzd, &nzf, out->lu_skipped, sizeof out->lu_skipped);

    EmitSizes z;
    put_sizes(e, &z);
    TemplateVar vars[] = {
        {"BANNER", banner.data}, {"OPS", ops.data}, {"P", out->prefix}, {"PU", upper},
        {"REAL", opt->real_float ? "float" : "double"}, {"NQ", z.nq}, {"NH", z.nh}, {"NV", z.nv},
        {"NNZ", z.nnz}, {"GUARD", z.guard}, {"MATH", math.data}, {"INTERFACE", ""},
        {"Q0", q0.data}, {"COORD_NAMES", coords.data}, {"ROW_NAMES", rows.data},
        {"JAC_ROW", jrow.data}, {"JAC_COL", jcol.data},
        {"PHI_PARTS", parts[EMIT_PHI].data}, {"PHI_BODY", bodies[EMIT_PHI].data},
        {"JAC_NZ_PARTS", parts[EMIT_JAC_NZ].data}, {"JAC_NZ_BODY", bodies[EMIT_JAC_NZ].data},
        {"NU_PARTS", parts[EMIT_NU].data}, {"NU_BODY", bodies[EMIT_NU].data},
        {"GAMMA_PARTS", parts[EMIT_GAMMA].data}, {"GAMMA_BODY", bodies[EMIT_GAMMA].data},
        {"ALL_PARTS", parts[EMIT_ALL].data}, {"ALL_BODY", bodies[EMIT_ALL].data},
        {"JAC_PARTS", parts[EMIT_JAC].data}, {"JAC_BODY", bodies[EMIT_JAC].data},
        {"ZERO_JAC", zero.data}, {"JAC_MOVES", moves.data}, {"JAC", ""},
        {"ALL_NZ_DECL", nzd.data}, {"ALL_NZ", nzf.data}, {"M_NNZ", z.mnnz},
        {"MASS_ROW", mrow.data}, {"MASS_COL", mcol.data}, {"DYNAMICS", ""}, {"DYN_INTERFACE", ""},
        {"MASS_PARTS", parts[EMIT_MASS].data}, {"MASS_BODY", bodies[EMIT_MASS].data},
        {"MASS_NZ_PARTS", parts[EMIT_MASS_NZ].data}, {"MASS_NZ_BODY", bodies[EMIT_MASS_NZ].data},
        {"FORCE_PARTS", parts[EMIT_FORCE].data}, {"FORCE_BODY", bodies[EMIT_FORCE].data},
        {"EOM_PARTS", parts[EMIT_EOM].data}, {"EOM_BODY", bodies[EMIT_EOM].data},
        {"JAC_DECL", ""}, {"ALL_DECL", ""}, {"ALL", ""}, {"SPARSE_ONLY", ""},
    };
    int nvars = (int)(sizeof vars / sizeof *vars);
    /* DYNAMICS, DYN_INTERFACE, the dense functions and INTERFACE are
       rendered from the others, then filled in */
    const char *bad = put_dynamics(e, vars, nvars, &dyn_c, &dyn_h);
    if (!bad)
        bad = put_dense(e, vars, nvars, dense_bufs);
    if (!bad)
        bad = template_render(&iface, template_interface, vars, nvars);
    template_set(vars, nvars, "INTERFACE", iface.data);
    StrBuf header, source;
    sb_init(&header);
    sb_init(&source);
    if (!bad)
        bad = template_render(&header, template_mech_h, vars, nvars);
    if (opt->header_name) {     /* the source includes the header instead */
        sb_puts(&inc, "#include ");
        sb_put_c_string(&inc, opt->header_name);
        sb_puts(&inc, "\n");
        template_set(vars, nvars, "INTERFACE", inc.data);
    }
    if (!bad)
        bad = template_render(&source, template_mech_c, vars, nvars);
    for (size_t i = 0; i < sizeof all_bufs / sizeof *all_bufs; i++)
        sb_free(all_bufs[i]);
    if (bad)
        placeholder_bug(bad);
    out->c_text = sb_take(&source);
    out->h_text = sb_take(&header);
}

/* False (diag filled) when a dense function the file would get has more
   entries than its int indices reach: the Jacobian (jac, all, eom) and,
   with masses, M (mass, eom). */
static bool check_dense_size(const Kinematics *kin, const EmitOptions *opt, Diag *diag)
{
    const Model *m = kin->model;
    long long jac = (long long)m->nr * m->nq, mass = (long long)m->nq * m->nq;
    const char *what = NULL;
    long long n = 0;
    if (jac > EMIT_DENSE_MAX_ENTRIES && (!opt->sparse_only || kin->dyn.present))
        what = "Jacobian", n = jac;
    else if (kin->dyn.present && mass > EMIT_DENSE_MAX_ENTRIES)
        what = "mass matrix", n = mass;
    if (!what)
        return true;
    diag_error_nopos(diag, "the dense %s would have %lld entries, more than the %lld a generated "
                     "file indexes with C ints%s", what, n, EMIT_DENSE_MAX_ENTRIES,
                     kin->dyn.present ? " (a file with masses has dense M and _eom)"
                                      : ": write it --sparse-only");
    return false;
}

static void free_functions(StrBuf *parts, StrBuf *bodies)
{
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++) {
        sb_free(&parts[f]);
        sb_free(&bodies[f]);
    }
}

bool emit_mechanism(const Kinematics *kin, const EmitOptions *options, EmitResult *out, Diag *diag)
{
    const Model *m = kin->model;
    memset(out, 0, sizeof *out);
    EmitOptions sparse = *options;      /* sparse-only files get all_nz */
    sparse.all_nz |= sparse.sparse_only;
    const EmitOptions *opt = &sparse;
    if (!check_options(m, opt, out, diag) || !check_dense_size(kin, opt, diag))
        return false;
    char upper[128];
    size_t plen = strlen(out->prefix);
    for (size_t i = 0; i <= plen; i++)
        upper[i] = (char)toupper((unsigned char)out->prefix[i]);

    Emitter e = {.kin = kin, .dag = &m->dag, .opt = opt, .prefix = out->prefix,
                 .prefix_upper = upper};
    /* Double kernels compute sin and cos together, of two angles at once
       where they can: the JIT calls the tool's mechc_sincos and
       mechc_sincos2 (or the C library's sincos with libm_trig), file output
       its own P_sincos and P_sincos2 (templates/sincos*.tmpl) or, with
       libm_trig, sin and cos as written (sincos is not C99; gcc merges the
       pairs itself). */
    char sincos_name[160], sincos2_name[160], sin_name[160], cos_name[160];
    snprintf(sincos_name, sizeof sincos_name, "%s_sincos", out->prefix);
    snprintf(sincos2_name, sizeof sincos2_name, "%s_sincos2", out->prefix);
    snprintf(sin_name, sizeof sin_name, "%s_sincos_s", out->prefix);
    snprintf(cos_name, sizeof cos_name, "%s_sincos_c", out->prefix);
    char sincos2_some_name[160];
    snprintf(sincos2_some_name, sizeof sincos2_some_name, "%s_sincos2_some", out->prefix);
    if (!opt->real_float && opt->declare_math) {
        e.sincos_name = opt->libm_trig ? "sincos" : "mechc_sincos";
        e.sincos2_name = opt->libm_trig ? NULL : "mechc_sincos2";
    } else if (!opt->real_float && !opt->libm_trig) {
        e.sincos_name = sincos_name;
        e.sincos2_name = sincos2_name;
        e.sin_name = sin_name;  /* the JIT keeps the tool's pair: its results stay */
        e.cos_name = cos_name;
        e.sincos2_some_name = sincos2_some_name;
    }
    e.trig_calls = opt->declare_math || opt->libm_trig || opt->real_float;
    e.written = xcalloc((size_t)m->dag.count + 1, sizeof *e.written);
    e.call_rank = xcalloc((size_t)m->dag.count + 1, sizeof *e.call_rank);
    StrBuf parts[EMIT_FUNCTION_COUNT], bodies[EMIT_FUNCTION_COUNT];
    if (!e.trig_calls && e.sin_name && pair_calls_at_least(&e) > EMIT_INLINE_TRIG_MAX)
        e.pair_out_of_line = e.trig_calls = true;
    bool fits = put_functions(&e, parts, bodies, out);
    if (fits && !e.trig_calls && e.sin_name && pair_calls(&e, parts, bodies) > EMIT_INLINE_TRIG_MAX) {
        /* Written again: the pair will be one out-of-line copy, so every
           call is a real call, placed as libm's are (calls_first). */
        e.pair_out_of_line = e.trig_calls = true;
        e.sincos_used = e.sincos2_used = e.single_used = false;
        free_functions(parts, bodies);
        fits = put_functions(&e, parts, bodies, out);
    }
    free(e.written);
    free(e.call_rank);
    if (fits)
        render_files(&e, parts, bodies, out);
    else
        diag_error_nopos(diag, "the generated code would have more than %ld operations, "
                         "the limit (see --max-code-ops)", opt->max_ops);
    free_functions(parts, bodies);
    return fits;
}

void emit_result_free(EmitResult *out)
{
    free(out->c_text);
    free(out->h_text);
    out->c_text = out->h_text = NULL;
}
