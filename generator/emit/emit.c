/* emit.c - writes a mechanism's generated functions as scheduled straight-line code (and loops).
 *
 * Each generated function is: one `const real uN = ...;` per node that
 * needs a temporary (see sched.c), the other nodes written inline (expr.c),
 * each store right after the temporaries it is first to need; a function
 * cut into parts passes values between them in its workspace ws. Sines and
 * cosines go in pairs (trig.c); the functions then fill the templates
 * (files.c). Constants are printed with the fewest digits that read back
 * to the same value (literal.c), so folded params round-trip exactly.
 * Text from the input reaches the output only as escaped string literals
 * (coordinate and row names) or as a sanitized identifier (the prefix).
 */
#include "emit.h"

#include "../base/arena.h"
#include "emitter.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool emit_function_present(const Kinematics *kin, EmitFunction f)
{
    switch (emit_function_family[f]) {
    case EMIT_DYN: return kin->dyn.present;
    case EMIT_DESIGN: return kin->model->np > 0;
    case EMIT_KIN: case EMIT_DENSE: case EMIT_SPARSE: case EMIT_LU: case EMIT_FAMILY_COUNT: break;
    }
    return true;
}

#define IN(name) {#name, true, false}
#define VALUE(name) {#name, false, true}
#define OUT(name) {#name, false, false}
#define NONE {NULL, false, false}
#define P(...) {__VA_ARGS__}
/* Parameters of each generated function (functions.def), in order, up to
   a NULL name (all are void-cast so no mechanism triggers an
   unused-parameter warning); none for the LU's, which emit_lu.c writes. */
static const Param function_params[EMIT_GENERATED_COUNT][12] = {
#define X(E, name, type, family, params) [EMIT_##E] = params,
#include "functions.def"
#undef X
};
#undef IN
#undef VALUE
#undef OUT
#undef NONE
#undef P

const Param *emit_params_of(const Emitter *e, EmitFunction which, Param out[EMIT_MAX_PARAMS])
{
    const Param *from = function_params[which];
    if (e->kin->model->np == 0)
        return from;
    int n = 0;
    for (; from->name && (from->input || from->scalar); from++)
        out[n++] = *from;
    out[n++] = (Param){"p", true, false};
    for (; from->name; from++)
        out[n++] = *from;
    out[n] = (Param){NULL, false, false};
    return out;
}

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

/* The runtime's names are mechrt_*, mechrtf_* (--real float) and MECHRT_*:
   a prefix P whose P_ or upper-cased P_ can begin one of them would make a
   generated name clash with the runtime's, so it is refused. */
static bool is_runtime_prefix(const char *p)
{
    static const char *const reserved[] = {"mechrt", "mechrtf"};
    for (size_t i = 0; i < sizeof reserved / sizeof *reserved; i++) {
        size_t n = strlen(reserved[i]), k = 0;
        while (k < n && tolower((unsigned char)p[k]) == reserved[i][k])
            k++;
        if (k == n && (p[n] == '\0' || p[n] == '_'))
            return true;
    }
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
    if (is_runtime_prefix(p))
        return "the runtime's names start with mechrt_, mechrtf_ and MECHRT_, which this prefix "
               "would clash with";
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

void emit_put_chunk(Emitter *e, StrBuf *sb, const SchedFunction *fn, int chunk,
                    EmitFunction which, bool workspace)
{
    e->fused += sched_prepare_chunk(&e->sched, fn, chunk);
    e->chunk = chunk;
    const SchedChunk *c = &fn->chunks[chunk];
    if (!e->roll && !e->lanes) {    /* a loop's parameters are the function's */
        Param buf[EMIT_MAX_PARAMS];
        const Param *params = emit_params_of(e, which, buf);
        sb_puts(sb, "    ");
        for (const Param *p = params; p->name; p++)
            sb_printf(sb, "%s(void)%s;", p == params ? "" : " ", p->name);
        sb_puts(sb, workspace ? " (void)ws;\n" : "\n");
    }
    trig_put_first(e, sb, fn, c);
    int at = 0;
    for (int i = 0; i < c->count; i++) {
        for (; at < c->ends[i]; at++)
            if (e->sched.temp[c->nodes[at]] >= 0 && !e->trig.written[c->nodes[at]])
                trig_put_temporary(e, sb, c, at, c->nodes[at]);
        const SchedOutput *o = &fn->outputs[c->first + i];
        if (e->roll)
            e->roll->store(e->roll->ctx, sb, o);
        else if (e->lanes)      /* the part's outputs, scattered after the loop */
            sb_printf(sb, "    o[%d][l] = ", i);
        else
            sb_printf(sb, "    %s[%d] = ", o->array, o->index);
        emit_put_expr(e, sb, o->value, false);
        sb_puts(sb, ";\n");
    }
    for (; at < c->nnodes; at++)    /* trig given to this chunk by a later one */
        if (e->sched.temp[c->nodes[at]] >= 0 && !e->trig.written[c->nodes[at]])
            trig_put_temporary(e, sb, c, at, c->nodes[at]);
    for (int i = 0; i < c->nnodes; i++) {   /* temporaries end with their chunk */
        e->sched.temp[c->nodes[i]] = -1;
        e->trig.written[c->nodes[i]] = false;
    }
}

/* q, qd, t, gamma -> "const P_real *q, const P_real *qd, P_real t, P_real *gamma" */
static void put_signature(StrBuf *sb, const char *prefix, const Param *params)
{
    for (const Param *p = params; p->name; p++)
        sb_printf(sb, "%s%s%s_real %s%s", p == params ? "" : ", ",
                  p->input ? "const " : "", prefix, p->scalar ? "" : "*", p->name);
}

/* q, qd, t, gamma -> "q, qd, t, gamma" */
static void put_arguments(StrBuf *sb, const Param *params)
{
    for (const Param *p = params; p->name; p++)
        sb_printf(sb, "%s%s", p == params ? "" : ", ", p->name);
}

/* Fills parts (static helpers, one per chunk) and body (the function's
   statements) for one generated function. */
static void put_function(Emitter *e, SchedFunction *fn, EmitFunction which,
                         StrBuf *parts, StrBuf *body)
{
    if (fn->nchunks == 1) {
        emit_put_chunk(e, body, fn, 0, which, false);
        return;
    }
    const char *p = e->prefix;
    Param buf[EMIT_MAX_PARAMS];
    const Param *params = emit_params_of(e, which, buf);
    bool workspace = fn->nslots > 0;    /* values that cross parts */
    if (workspace)
        sb_printf(body, "    %s_real ws[%d];\n", p, fn->nslots);
    for (int c = 0; c < fn->nchunks; c++) {
        sb_printf(parts, "%s_PART void %s_%s_part%d(", e->prefix_upper, p, emit_function_names[which], c);
        put_signature(parts, p, params);
        if (workspace)
            sb_printf(parts, ", %s_real *ws", p);
        sb_puts(parts, ")\n{\n");
        emit_put_chunk(e, parts, fn, c, which, workspace);
        sb_puts(parts, "}\n\n");
        sb_printf(body, "    %s_%s_part%d(", p, emit_function_names[which], c);
        put_arguments(body, params);
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

/* A design file's sensitivity functions: dense arrays, every entry
   written, in the parameters' order (functions.def). */
static void collect_design(const Kinematics *kin, EmitFunction which, SchedOutput **outs, int *n)
{
    const char *name[DESIGN_Y_COUNT];
    const NodeId *from[DESIGN_Y_COUNT];
    size_t count[DESIGN_Y_COUNT], total = 0;
    int k = 0;
    for (const Param *p = function_params[which]; p->name; p++)
        if (!p->input && !p->scalar)
            name[k++] = p->name;
    int arrays = design_arrays(kin, (DesignFn)(which - EMIT_PHI_P), from, count);
    for (int i = 0; i < arrays; i++)
        total += count[i];
    *outs = xrealloc(*outs, total + 1, sizeof **outs);
    for (int i = 0; i < arrays && i < k; i++)
        for (size_t e = 0; e < count[i]; e++)
            add_output(outs, n, name[i], (int)e, from[i][e]);
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
    if (emit_function_family[which] == EMIT_DESIGN) {
        collect_design(kin, which, outs, n);
        return;
    }
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
    trig_graph(&e.trig, dag->count);
    sched_init(&e.sched, dag, 1 << 28);     /* one chunk: a loop body is small */
    SchedFunction fn;
    sched_function(&e.sched, outs, n, &fn);
    e.fused = 0;
    emit_put_chunk(&e, sb, &fn, 0, EMIT_PHI, false);
    int ops = fn.ops - e.fused;
    sched_function_free(&fn);
    sched_free(&e.sched);
    trig_free(&e.trig);
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
        .real_float = opt->real_float, .sincos_name = e->trig.sincos_name,
        .sin_name = e->trig.sin_name, .cos_name = e->trig.cos_name,
        .sincos2_name = e->trig.sincos2_name,
        .min_members = opt->roll == EMIT_ROLL_ALWAYS ? 2 : EMIT_ROLL_AUTO_MEMBERS,
        .write_body = put_roll_body, .emitter = e,
        .sincos_used = &e->trig.sincos_used, .single_used = &e->trig.single_used,
        .sincos2_used = &e->trig.sincos2_used,
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
    case EMIT_KIN: case EMIT_DYN: case EMIT_DESIGN: case EMIT_FAMILY_COUNT: break;
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
    return emit_function_present(e->kin, f) && (f != EMIT_JAC || e->opt->direct_jac)
           && emit_function_written(e->opt, f);
}

/* Fewest calls of the file's own sin/cos functions the written functions
   can make (trig_least_calls). Above TRIG_INLINE_MAX the file is written
   once, its calls placed as real calls from the start. */
static long pair_calls_at_least(const Emitter *e)
{
    SchedOutput *outs[EMIT_FUNCTION_COUNT] = {0};
    int n[EMIT_FUNCTION_COUNT] = {0};
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
        if (is_written(e, (EmitFunction)f))
            collect_outputs(e->kin, (EmitFunction)f, &outs[f], &n[f]);
    long calls = trig_least_calls(e->dag, outs, n, EMIT_FUNCTION_COUNT);
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
        free(outs[f]);
    return calls;
}

/* Schedules and writes every function into parts and bodies (initialized
   here, freed by the caller); false when the code would pass max_ops. */
static bool put_functions(Emitter *e, StrBuf *parts, StrBuf *bodies, EmitResult *out)
{
    const EmitOptions *opt = e->opt;
    sched_init(&e->sched, e->dag,
               opt->chunk_nodes > 0 ? opt->chunk_nodes : emit_default_options().chunk_nodes);
    if (e->batch_text) {    /* written again after trig_pair_out_of_line */
        sb_clear(e->batch_text);
        sb_clear(e->batch_decl);
    }
    e->sched.max_ops = opt->max_ops;
    bool fits = true;
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++) {
        sb_init(&parts[f]);
        sb_init(&bodies[f]);
        sb_puts(&parts[f], "");
        sb_puts(&bodies[f], "");
        if (!is_written(e, (EmitFunction)f) || !fits) {
            if (fits && emit_batch_wanted(e, (EmitFunction)f))
                emit_batch_function(e, NULL, (EmitFunction)f);
            continue;
        }
        SchedOutput *outs;
        int n;
        collect_outputs(e->kin, (EmitFunction)f, &outs, &n);
        int all = n;
        long rolled = roll_outputs(e, (EmitFunction)f, &outs, &n, &parts[f], &bodies[f]);
        SchedFunction fn;
        /* gamma split into parts places its inline pairs as calls
           (calls_first) where they cannot all go first: chain N = 10
           1.04-1.05x its --trig libm twin under gcc -O0 rather than
           1.11-1.12x, and 3-5% faster under gcc -O2; the other functions
           lost up to 3% so, and one-part gammas up to 10% (Andrews',
           gcc -O2) (doc/figures.md, "Written files") */
        if (sched_function(&e->sched, outs, n, &fn)) {
            e->fused = 0;
            e->trig.place_as_calls = f == EMIT_GAMMA && e->trig.sin_name && fn.nchunks > 1;
            put_function(e, &fn, (EmitFunction)f, &parts[f], &bodies[f]);
            out->ops[f] = (int)(fn.ops - e->fused + rolled);
            out->chunks[f] = fn.nchunks;
            if (emit_batch_wanted(e, (EmitFunction)f))
                emit_batch_function(e, n == all ? &fn : NULL, (EmitFunction)f);
        } else {
            fits = false;
        }
        sched_function_free(&fn);
        e->trig.place_as_calls = false;
    }
    sched_free(&e->sched);
    if (!opt->direct_jac && !opt->sparse_only) {
        out->ops[EMIT_JAC] = out->ops[EMIT_JAC_NZ];
        out->chunks[EMIT_JAC] = out->chunks[EMIT_JAC_NZ];
    }
    return fits;
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

/* The file's source and header (files.c), the banner counting the
   operations of each function written. */
static void render_files(const Emitter *e, StrBuf *parts, StrBuf *bodies, EmitResult *out)
{
    StrBuf ops;
    sb_init(&ops);
    sb_puts(&ops, "");
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
        if (emit_function_present(e->kin, (EmitFunction)f)
            && emit_function_written(e->opt, (EmitFunction)f))
            sb_printf(&ops, "%s%s %d", f ? ", " : "", emit_function_names[f], out->ops[f]);
    emit_render_files(e, parts, bodies, ops.data, out);
    sb_free(&ops);
}

/* EmitOptions.host_design: the file's functions renamed PREFIX_NAME_design
   by macros before its text, and after it PREFIX_NAME without p, calling
   them with the design PREFIX_design_bind was given. The written file
   (gen) never has these: its p is an argument. */
static void put_host_design(const Emitter *e, EmitResult *out)
{
    const char *pre = e->prefix;
    StrBuf sb;
    sb_init(&sb);
    sb_puts(&sb, "");
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++)
        if (emit_function_present(e->kin, (EmitFunction)f)
            && emit_function_written(e->opt, (EmitFunction)f))
            sb_printf(&sb, "#define %s_%s %s_%s_design\n", pre, emit_function_names[f], pre,
                      emit_function_names[f]);
    emit_batch_host_renames(e, &sb);
    sb_puts(&sb, out->c_text);
    sb_printf(&sb, "\n/* ---- the host's context-free twins ---- */\n"
              "static const %s_real *%s_design_p;\n"
              "void %s_design_bind(const %s_real *p) { %s_design_p = p; }\n", pre, pre, pre, pre, pre);
    for (int f = 0; f < EMIT_FUNCTION_COUNT; f++) {
        if (!emit_function_present(e->kin, (EmitFunction)f)
            || !emit_function_written(e->opt, (EmitFunction)f))
            continue;
        const char *name = emit_function_names[f];
        sb_printf(&sb, "#undef %s_%s\nvoid %s_%s(", pre, name, pre, name);
        put_signature(&sb, pre, function_params[f]);
        sb_printf(&sb, ")\n{\n    %s_%s_design(", pre, name);
        Param buf[EMIT_MAX_PARAMS];
        const Param *params = emit_params_of(e, (EmitFunction)f, buf);
        for (const Param *p = params; p->name; p++)
            sb_printf(&sb, "%s%s%s", p == params ? "" : ", ",
                      strcmp(p->name, "p") == 0 ? pre : "", strcmp(p->name, "p") == 0 ? "_design_p" : p->name);
        sb_puts(&sb, ");\n}\n");
    }
    emit_batch_host_twins(e, &sb);
    free(out->c_text);
    out->c_text = sb_take(&sb);
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
    StrBuf batch[2];
    for (int i = 0; i < 2 && opt->batch; i++) {
        sb_init(&batch[i]);
        sb_puts(&batch[i], "");
    }
    if (opt->batch) {
        e.batch_text = &batch[0];
        e.batch_decl = &batch[1];
    }
    trig_init(&e.trig, opt, out->prefix, m->dag.count);
    StrBuf parts[EMIT_FUNCTION_COUNT], bodies[EMIT_FUNCTION_COUNT];
    if (trig_pair_inline(&e.trig) && pair_calls_at_least(&e) > TRIG_INLINE_MAX)
        trig_pair_out_of_line(&e.trig);
    bool fits = put_functions(&e, parts, bodies, out);
    if (fits && trig_pair_inline(&e.trig)
        && trig_pair_calls(&e.trig, parts, bodies, EMIT_FUNCTION_COUNT) > TRIG_INLINE_MAX) {
        /* Written again: the pair will be one out-of-line copy, so every
           call is a real call, placed as libm's are (calls_first). */
        trig_pair_out_of_line(&e.trig);
        free_functions(parts, bodies);
        fits = put_functions(&e, parts, bodies, out);
    }
    trig_free(&e.trig);
    if (!fits)
        diag_error_nopos(diag, "the generated code would have more than %ld operations, "
                         "the limit (see --max-code-ops)", opt->max_ops);
    if (fits)
        render_files(&e, parts, bodies, out);
    if (fits && opt->host_design && m->np > 0)
        put_host_design(&e, out);
    free_functions(parts, bodies);
    for (int i = 0; i < 2 && opt->batch; i++)
        sb_free(&batch[i]);
    return fits;
}

void emit_result_free(EmitResult *out)
{
    free(out->c_text);
    free(out->h_text);
    out->c_text = out->h_text = NULL;
}

