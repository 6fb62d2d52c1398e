/* batch.c - PREFIX_NAME_batch: a kinematic function at n states, PREFIX_LANES at a time in lock-step.
 *
 * Each block of LANES states is copied into local arrays, one row per
 * coordinate the function reads (qv[i][l]: coordinate i of lane l); each
 * chunk of the single-state function (sched.c) becomes a part whose loop
 * over the lanes holds the chunk's statements as written for one state,
 * with its leaves, stores and workspace indexed by the lane (expr.c), so
 * that gcc and clang vectorise the loop across the states; the part's
 * outputs go to a local array, then to the caller's rows. The operations
 * are the single-state function's, in its order: the same bits. An angle
 * that the file's own sincos would leave to libm (past 2^16 rad, NaN)
 * clears the lane's ok, and that state is evaluated again by the
 * single-state function; so are the n % LANES states of the tail.
 * Functions with loops (roll.c), without code of their own (the spread
 * Jacobian) or with cheap outputs (BATCH_MIN_OPS_PER_OUTPUT) get a plain
 * loop over the single-state function.
 *
 * PREFIX_NAME_batch_soa is the same function over arrays laid out by
 * coordinate (structure of arrays: q[j * n + i], the outputs alike): its
 * copies in and out are whole vectors rather than transposes, so every
 * function with code of its own gets lanes; a state that needs the
 * single-state function goes through a row (PREFIX_NAME_batch_soa_one).
 */
#include "emitter.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>

/* Lanes per block: eight doubles fill one AVX-512 register, two AVX2 ones. */
enum { BATCH_LANES = 8 };

/* Lanes pay for the copies in and out (an extra load and store per
   output) only where the outputs cost some arithmetic: below this many
   operations per output (the four-bar's all: 53 for 52; the Jacobian's
   entries, constants or one product) a plain loop over the single kernel
   is faster (doc/batch.md: all of the four-bar 0.63x and of the chain
   N = 10 0.70x as lanes, gcc -O2); gamma (2.7) gains. */
enum { BATCH_MIN_OPS_PER_OUTPUT = 2 };

/* The two layouts of the callers' arrays: a row per state (_batch), a
   row per coordinate or output entry (_batch_soa). */
typedef enum Layout { LAYOUT_ROWS, LAYOUT_COLS } Layout;
static const char *const layout_suffix[] = {"_batch", "_batch_soa"};

bool emit_batch_wanted(const Emitter *e, EmitFunction f)
{
    return e->opt->batch && (int)f < (int)EMIT_KINEMATIC_COUNT && emit_function_present(e->kin, f)
           && emit_function_written(e->opt, f);
}

/* The size of one state's row of array name (q, qd, an output) in the
   interface's macros, "(PU_NR * PU_NQ)" and the like (t has one value a
   state, p one for all). */
static void put_row_size(StrBuf *sb, const Emitter *e, const char *name)
{
    static const char *const sizes[][3] = {
        {"q", "NQ", NULL}, {"qd", "NQ", NULL}, {"phi", "NH", NULL}, {"jac", "NR", "NQ"},
        {"vals", "NNZ", NULL}, {"jac_vals", "NNZ", NULL}, {"nu", "NR", NULL}, {"gamma", "NR", NULL},
    };
    for (size_t i = 0; i < sizeof sizes / sizeof *sizes; i++)
        if (strcmp(sizes[i][0], name) == 0) {
            sb_printf(sb, "(%s_%s", e->prefix_upper, sizes[i][1]);
            if (sizes[i][2])
                sb_printf(sb, " * %s_%s", e->prefix_upper, sizes[i][2]);
            sb_putc(sb, ')');
        }
}

/* The batch signature: int n, then each parameter as an array over the
   states (t too), p shared. */
/* The arrays of the batch signature, without n. */
static void put_signature_arrays(StrBuf *sb, const Emitter *e, const Param *params)
{
    for (const Param *p = params; p->name; p++)
        sb_printf(sb, "%s%s%s_real *%s", p == params ? "" : ", ",
                  p->input || p->scalar ? "const " : "", e->prefix, p->name);
}

static void put_signature(StrBuf *sb, const Emitter *e, const Param *params)
{
    sb_puts(sb, "int n, ");
    put_signature_arrays(sb, e, params);
}

/* The single-state call for state s (C text) with the batch arguments. */
static void put_single_call(StrBuf *sb, const Emitter *e, EmitFunction which, const Param *params,
                            const char *s, const char *indent)
{
    sb_printf(sb, "%s%s_%s(", indent, e->prefix, emit_function_names[which]);
    for (const Param *p = params; p->name; p++) {
        sb_puts(sb, p == params ? "" : ", ");
        if (p->scalar)
            sb_printf(sb, "%s[%s]", p->name, s);
        else if (strcmp(p->name, "p") == 0)
            sb_puts(sb, "p");
        else {
            sb_printf(sb, "%s + (long)(%s) * ", p->name, s);
            put_row_size(sb, e, p->name);
        }
    }
    sb_puts(sb, ");\n");
}

/* Which leaves function fn reads: used[0] q's coordinates, used[1] qd's
   (nq each), *t whether it reads t. */
static void find_leaves(const Emitter *e, const SchedFunction *fn, bool *used[2], bool *t)
{
    const Dag *dag = e->dag;
    size_t count = (size_t)dag->count + 1;
    uint32_t *mark = xcalloc(count, sizeof *mark);
    NodeId *stack = xmalloc(count * sizeof *stack);
    NodeId *roots = xmalloc(((size_t)fn->noutputs + 1) * sizeof *roots);
    for (int i = 0; i < fn->noutputs; i++)
        roots[i] = fn->outputs[i].value;
    dag_mark_reachable(dag, roots, fn->noutputs, mark, 1, stack);
    *t = false;
    for (NodeId id = 0; id < dag->count; id++) {
        if (mark[id] != 1)
            continue;
        DagOp op = dag_op(dag, id);
        if (op == OP_VAR || op == OP_VARD)
            used[op == OP_VARD][dag_node(dag, id)->a] = true;
        *t |= op == OP_TIME;
    }
    free(mark);
    free(stack);
    free(roots);
}

/* The lane arrays a part takes, by what the function reads. */
typedef struct Lanes {
    bool q, qd, t, ws;
} Lanes;

/* The parameters of a part: the lane arrays, p, ok and the outputs'
   blocks, as its declaration (PART_DECL), the arguments of its call
   (PART_ARGS) or casts to void (PART_VOIDS: a chunk may use none of some). */
typedef enum PartText { PART_DECL, PART_ARGS, PART_VOIDS } PartText;

static void put_part_param(StrBuf *sb, const Emitter *e, PartText how, bool *first,
                           const char *type, const char *name)
{
    const char *sep = *first ? "" : ", ";
    *first = false;
    if (how == PART_VOIDS)
        sb_printf(sb, " (void)%s;", name);
    else if (how == PART_ARGS)
        sb_printf(sb, "%s%s", sep, name);
    else if (strcmp(type, "lanes") == 0)
        sb_printf(sb, "%s%s_real (*restrict %s)[%s_LANES]", sep, e->prefix, name, e->prefix_upper);
    else if (strcmp(type, "long") == 0)
        sb_printf(sb, "%slong %s", sep, name);
    else
        sb_printf(sb, "%s%s%s_real *restrict %s", sep, type, e->prefix, name);
}

static void put_part_params(StrBuf *sb, const Emitter *e, const Param *params, Lanes in,
                            PartText how, Layout layout)
{
    bool first = true;
    if (layout == LAYOUT_COLS && how == PART_DECL)
        put_part_param(sb, e, how, &first, "long", "ld");
    else if (layout == LAYOUT_COLS)
        put_part_param(sb, e, how, &first, "long", how == PART_ARGS ? "(long)n" : "ld");
    if (in.q)
        put_part_param(sb, e, how, &first, "lanes", "qv");
    if (in.qd)
        put_part_param(sb, e, how, &first, "lanes", "qdv");
    if (in.ws)
        put_part_param(sb, e, how, &first, "lanes", "ws");
    if (in.t)
        put_part_param(sb, e, how, &first, "const ", "tv");
    put_part_param(sb, e, how, &first, "", "ok");
    for (const Param *p = params; p->name; p++) {
        if (strcmp(p->name, "p") == 0)
            put_part_param(sb, e, how, &first, "const ", "p");
        else if (p->input || p->scalar)
            continue;
        else if (how != PART_ARGS)
            put_part_param(sb, e, how, &first, "", p->name);
        else if (layout == LAYOUT_COLS)
            sb_printf(sb, ", %s + b", p->name);
        else {
            sb_printf(sb, ", %s + (long)b * ", p->name);
            put_row_size(sb, e, p->name);
        }
    }
}

/* Appends text to sb with every line indented four more spaces. */
static void put_indented(StrBuf *sb, const char *text)
{
    for (const char *line = text; *line;) {
        const char *end = strchr(line, '\n');
        size_t n = end ? (size_t)(end - line) + 1 : strlen(line);
        if (n > 1)
            sb_puts(sb, "    ");
        sb_putn(sb, line, n);
        line += n;
    }
}

/* Part c of the batch function: the chunk's statements in a loop over
   the lanes, then its outputs to the callers' arrays. */
static void put_part(Emitter *e, const SchedFunction *fn, int c, EmitFunction which,
                     const Param *params, Lanes in, Layout layout, StrBuf *sb)
{
    const char *pre = e->prefix, *pu = e->prefix_upper, *name = emit_function_names[which];
    const SchedChunk *chunk = &fn->chunks[c];
    sb_printf(sb, "%s_PART void %s_%s%s_part%d(", pu, pre, name, layout_suffix[layout], c);
    put_part_params(sb, e, params, in, PART_DECL, layout);
    sb_puts(sb, ")\n{\n");
    if (chunk->count > 0)
        sb_printf(sb, "    %s_real o[%d][%s_LANES];\n", pre, chunk->count, pu);
    sb_puts(sb, "    int l;\n   ");
    put_part_params(sb, e, params, in, PART_VOIDS, layout);
    sb_puts(sb, "\n");
    sb_printf(sb, "    for (l = 0; l < %s_LANES; l++) {\n        %s_real okl = ok[l];\n", pu, pre);
    StrBuf body;
    sb_init(&body);
    sb_puts(&body, "");
    e->lanes = true;
    emit_put_chunk(e, &body, fn, c, which, false);
    e->lanes = false;
    put_indented(sb, body.data);
    sb_free(&body);
    sb_puts(sb, "        ok[l] = okl;\n    }\n");
    /* a loop per output: gcc -O2 vectorises each (scatter, or a store per
       lane; by coordinate one vector store), not one over the lanes (a
       group of stores with a stride) */
    for (int i = 0; i < chunk->count; i++) {
        const SchedOutput *o = &fn->outputs[chunk->first + i];
        sb_printf(sb, "    for (l = 0; l < %s_LANES; l++)\n        %s[", pu, o->array);
        if (layout == LAYOUT_COLS)
            sb_printf(sb, "%d * ld + l] = o[%d][l];\n", o->index, i);
        else {
            sb_puts(sb, "l * ");
            put_row_size(sb, e, o->array);
            sb_printf(sb, " + %d] = o[%d][l];\n", o->index, i);
        }
    }
    sb_puts(sb, "}\n\n");
}

/* The block's lane arrays, filled from the callers' arrays: a loop per
   coordinate, which gcc -O2 vectorises into one vector store (a loop over
   the lanes would store element by element, and the part's vector loads
   would wait for them: no store forwarding). */
static void put_gather(StrBuf *sb, const Emitter *e, bool *used[2], Lanes in, Layout layout)
{
    const char *pu = e->prefix_upper;
    int nq = e->kin->model->nq;
    for (int k = 0; k < 2; k++)
        for (int i = 0; i < nq; i++) {
            if (!used[k][i])
                continue;
            sb_printf(sb, "        for (l = 0; l < %s_LANES; l++)\n            %sv[%d][l] = ", pu,
                      k ? "qd" : "q", i);
            if (layout == LAYOUT_COLS)
                sb_printf(sb, "%s[%d * (long)n + b + l];\n", k ? "qd" : "q", i);
            else
                sb_printf(sb, "%s[(long)(b + l) * %s_NQ + %d];\n", k ? "qd" : "q", pu, i);
        }
    if (in.t)
        sb_printf(sb, "        for (l = 0; l < %s_LANES; l++)\n            tv[l] = t[b + l];\n", pu);
    sb_printf(sb, "        for (l = 0; l < %s_LANES; l++)\n            ok[l] = 1;\n", pu);
}

/* The evaluation of state s by the single-state function: a call on the
   callers' rows, or by coordinate a call of PREFIX_NAME_batch_soa_one. */
static void put_one(StrBuf *sb, const Emitter *e, EmitFunction which, const Param *params,
                    Layout layout, const char *s, const char *indent)
{
    if (layout == LAYOUT_ROWS) {
        put_single_call(sb, e, which, params, s, indent);
        return;
    }
    sb_printf(sb, "%s%s_%s_batch_soa_one(n, %s", indent, e->prefix, emit_function_names[which], s);
    for (const Param *p = params; p->name; p++)
        sb_printf(sb, ", %s", p->name);
    sb_puts(sb, ");\n");
}

/* PREFIX_NAME_batch_soa_one: state i of arrays by coordinate through the
   single-state function, its rows on the stack. */
static void put_soa_one(StrBuf *sb, const Emitter *e, EmitFunction which, const Param *params)
{
    const char *pre = e->prefix, *pu = e->prefix_upper, *name = emit_function_names[which];
    sb_printf(sb, "%s_PART void %s_%s_batch_soa_one(int n, int i, ", pu, pre, name);
    put_signature_arrays(sb, e, params);
    sb_puts(sb, ")\n{\n");
    for (const Param *p = params; p->name; p++)
        if (!p->scalar && strcmp(p->name, "p") != 0) {
            sb_printf(sb, "    %s_real %s_row[", pre, p->name);
            put_row_size(sb, e, p->name);
            sb_puts(sb, "];\n");
        }
    sb_puts(sb, "    long j;\n");
    for (const Param *p = params; p->name; p++)
        if (p->input && !p->scalar && strcmp(p->name, "p") != 0) {
            sb_printf(sb, "    for (j = 0; j < %s_NQ; j++)\n        %s_row[j] = %s[j * n + i];\n",
                      pu, p->name, p->name);
        }
    sb_printf(sb, "    %s_%s(", pre, name);
    for (const Param *p = params; p->name; p++)
        sb_printf(sb, "%s%s%s", p == params ? "" : ", ", p->name,
                  p->scalar ? "[i]" : strcmp(p->name, "p") == 0 ? "" : "_row");
    sb_puts(sb, ");\n");
    for (const Param *p = params; p->name; p++)
        if (!p->input && !p->scalar) {
            sb_puts(sb, "    for (j = 0; j < ");
            put_row_size(sb, e, p->name);
            sb_printf(sb, "; j++)\n        %s[j * n + i] = %s_row[j];\n", p->name, p->name);
        }
    sb_puts(sb, "}\n\n");
}

/* The batch function over its parts: blocks, the fallback to the single
   function, the tail. */
static void put_blocks(Emitter *e, const SchedFunction *fn, EmitFunction which,
                       const Param *params, Layout layout, StrBuf *sb)
{
    const char *pre = e->prefix, *pu = e->prefix_upper, *name = emit_function_names[which];
    int nq = e->kin->model->nq;
    bool *used[2] = {xcalloc((size_t)nq + 1, sizeof(bool)), xcalloc((size_t)nq + 1, sizeof(bool))};
    Lanes in = {.ws = fn->nslots > 0};
    find_leaves(e, fn, used, &in.t);
    for (int i = 0; i < nq; i++) {
        in.q |= used[0][i];
        in.qd |= used[1][i];
    }
    for (int c = 0; c < fn->nchunks; c++)
        put_part(e, fn, c, which, params, in, layout, sb);
    sb_printf(sb, "void %s_%s%s(", pre, name, layout_suffix[layout]);
    put_signature(sb, e, params);
    sb_puts(sb, ")\n{\n");
    const char *arrays[] = {in.q ? "qv[" : NULL, in.qd ? "qdv[" : NULL};
    for (int k = 0; k < 2; k++)
        if (arrays[k])
            sb_printf(sb, "    %s_real %s%s_NQ][%s_LANES];\n", pre, arrays[k], pu, pu);
    if (in.ws)
        sb_printf(sb, "    %s_real ws[%d][%s_LANES];\n", pre, fn->nslots, pu);
    if (in.t)
        sb_printf(sb, "    %s_real tv[%s_LANES];\n", pre, pu);
    sb_printf(sb, "    %s_real ok[%s_LANES];\n    int b, l;\n", pre, pu);
    bool dense = false;     /* the dense Jacobian's zeros */
    for (const Param *p = params; p->name; p++)
        dense |= strcmp(p->name, "jac") == 0;
    if (dense && layout == LAYOUT_COLS)
        sb_printf(sb, "    if (n > 0)\n        memset(jac, 0, sizeof(%s_real) * %s_NR * %s_NQ "
                  "* (unsigned)n);\n", pre, pu, pu);
    sb_printf(sb, "    for (b = 0; b + %s_LANES <= n; b += %s_LANES) {\n", pu, pu);
    put_gather(sb, e, used, in, layout);
    if (dense && layout == LAYOUT_ROWS)
        sb_printf(sb, "        memset(jac + (long)b * (%s_NR * %s_NQ), 0, sizeof(%s_real) "
                  "* %s_LANES * %s_NR * %s_NQ);\n", pu, pu, pre, pu, pu, pu);
    for (int c = 0; c < fn->nchunks; c++) {
        sb_printf(sb, "        %s_%s%s_part%d(", pre, name, layout_suffix[layout], c);
        put_part_params(sb, e, params, in, PART_ARGS, layout);
        sb_puts(sb, ");\n");
    }
    /* one test for the block: ok is 1 or 0 in every lane */
    sb_puts(sb, "        if (ok[0]");
    for (int l = 1; l < BATCH_LANES; l++)
        sb_printf(sb, " * ok[%d]", l);
    sb_printf(sb, " == 0)\n            for (l = 0; l < %s_LANES; l++)\n"
              "                if (ok[l] == 0)\n", pu);
    put_one(sb, e, which, params, layout, "b + l", "                    ");
    sb_puts(sb, "    }\n    for (; b < n; b++)\n");
    put_one(sb, e, which, params, layout, "b", "        ");
    sb_puts(sb, "}\n");
    free(used[0]);
    free(used[1]);
}

/* A batch function without lanes: state by state. */
static void put_loop(StrBuf *sb, const Emitter *e, EmitFunction which, const Param *params,
                     Layout layout)
{
    sb_printf(sb, "void %s_%s%s(", e->prefix, emit_function_names[which], layout_suffix[layout]);
    put_signature(sb, e, params);
    sb_puts(sb, ")\n{\n    int b;\n    for (b = 0; b < n; b++)\n");
    put_one(sb, e, which, params, layout, "b", "        ");
    sb_puts(sb, "}\n");
}

void emit_batch_function(Emitter *e, const SchedFunction *fn, EmitFunction which)
{
    Param buf[EMIT_MAX_PARAMS];
    const Param *params = emit_params_of(e, which, buf);
    const char *name = emit_function_names[which];
    for (int layout = 0; layout < 2; layout++) {
        sb_printf(e->batch_decl, "void %s_%s%s(", e->prefix, name, layout_suffix[layout]);
        put_signature(e->batch_decl, e, params);
        sb_puts(e->batch_decl, ");\n");
    }
    StrBuf *sb = e->batch_text;
    sb_printf(sb, "\n/* ---- begin %s_batch ---- */\n", name);
    int fused = e->fused;
    /* loops or no code of their own, or (by rows) cheap outputs: state by state */
    if (fn && fn->ops >= BATCH_MIN_OPS_PER_OUTPUT * fn->noutputs)
        put_blocks(e, fn, which, params, LAYOUT_ROWS, sb);
    else
        put_loop(sb, e, which, params, LAYOUT_ROWS);
    sb_puts(sb, "\n");
    put_soa_one(sb, e, which, params);
    if (fn)
        put_blocks(e, fn, which, params, LAYOUT_COLS, sb);
    else
        put_loop(sb, e, which, params, LAYOUT_COLS);
    e->fused = fused;
    sb_printf(sb, "/* ---- end %s_batch ---- */\n", name);
}

void emit_batch_interface(const Emitter *e, const char *decl, StrBuf *out)
{
    if (!e->opt->batch)
        return;
    sb_printf(out, "\n\n/* Batch kernels (gen --batch): each evaluates its kernel at n states,\n"
              "   the arrays row-major, a row per state (q, qd: n x NQ; t: n; the outputs\n"
              "   n x their single-state size; p, where there is one, for all states),\n"
              "   %s_LANES states at a time in lock-step so that compilers vectorise\n"
              "   across the states: the same bits as n calls of the single kernel.\n"
              "   NAME_batch_soa: the same over arrays by coordinate (structure of\n"
              "   arrays: q[j * n + i] is coordinate j of state i, an output's entry k\n"
              "   of state i at [k * n + i]; t: n), faster where the data is so. */\n"
              "#define %s_LANES %d\n", e->prefix_upper, e->prefix_upper, BATCH_LANES);
    sb_putn(out, decl, strlen(decl) - 1);  /* the interface's last line ends there */
}

void emit_batch_host_renames(const Emitter *e, StrBuf *sb)
{
    for (int f = 0; f < EMIT_KINEMATIC_COUNT; f++)
        for (int layout = 0; layout < 2 && emit_batch_wanted(e, (EmitFunction)f); layout++)
            sb_printf(sb, "#define %s_%s%s %s_%s%s_design\n", e->prefix, emit_function_names[f],
                      layout_suffix[layout], e->prefix, emit_function_names[f],
                      layout_suffix[layout]);
}

/* PREFIX_NAME_batch (or _batch_soa) of a design file's host: the function
   with the design's p. */
static void put_host_twin(const Emitter *e, StrBuf *sb, EmitFunction f, const char *suffix)
{
    Param buf[EMIT_MAX_PARAMS];
    const Param *params = emit_params_of(e, f, buf);
    const char *pre = e->prefix, *name = emit_function_names[f];
    sb_printf(sb, "#undef %s_%s%s\nvoid %s_%s%s(int n", pre, name, suffix, pre, name, suffix);
    for (const Param *p = params; p->name; p++)
        if (strcmp(p->name, "p") != 0)
            sb_printf(sb, ", %s%s_real *%s", p->input || p->scalar ? "const " : "", pre, p->name);
    sb_printf(sb, ")\n{\n    %s_%s%s_design(n", pre, name, suffix);
    for (const Param *p = params; p->name; p++)
        sb_printf(sb, ", %s%s", strcmp(p->name, "p") == 0 ? pre : "",
                  strcmp(p->name, "p") == 0 ? "_design_p" : p->name);
    sb_puts(sb, ");\n}\n");
}

void emit_batch_host_twins(const Emitter *e, StrBuf *sb)
{
    for (int f = 0; f < EMIT_KINEMATIC_COUNT; f++)
        for (int layout = 0; layout < 2 && emit_batch_wanted(e, (EmitFunction)f); layout++)
            put_host_twin(e, sb, (EmitFunction)f, layout_suffix[layout]);
}
