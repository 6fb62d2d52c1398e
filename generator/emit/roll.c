/* roll.c - loop-rolled emission: the rows of joints of one shape written once, as a loop over tables.
 *
 * A member is one joint's run of rows (their outputs in the function:
 * phi, Jacobian entries, nu, gamma). Its shape is its subgraph written
 * out in post-order with every leaf made a slot: a constant, a
 * coordinate or velocity index, the sin or cos of an angle coordinate,
 * and each store's index. Members with the same shape (a chain's
 * thousand coupler joints) differ only in their slots' values, so one
 * loop body, printed by the emitter from a small graph of the shape,
 * serves them all: a slot whose value is the same for every member is
 * written as that value, one that grows by a fixed step through a pointer
 * that moves with the loop (q_6 = q + 6 * i, then q_6[3]), the rest read
 * a static const table; a group is cut into runs of steady steps, so that
 * an odd member (a chain's first joint) does not turn every index into a
 * table.
 *
 * The body computes exactly the operations of each member's straight-line
 * code, so the results are the same bits; what it does not repeat is the
 * trigonometry: an angle serves several joints (a chain's rod carries
 * three), so a first loop computes sin and cos of every angle the bodies
 * read, once, into arrays on the stack, through the same function the
 * straight-line code would call for it (the pair, or only the sin or cos
 * where the function uses only one of them).
 */
#include "roll.h"

#include "literal.h"
#include "../base/arena.h"
#include "../base/hashmap.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Shape words for leaves and stores (interior nodes are op, a, b). */
enum { W_CONST = -1, W_Q = -2, W_QD = -3, W_TIME = -4, W_SIN = -5, W_COS = -6, W_OUT = -7 };

static const char *const arrays[] = {"phi", "jac", "vals", "jac_vals", "nu", "gamma", NULL};

typedef struct Member {
    int first, count;       /* outputs[first .. first + count) */
    int code_at, code_len;  /* its shape in Roll.code */
    int val_at;             /* its slots' values in Roll.vals */
    int nslots;
    int group;              /* -1: alone */
    bool ok;                /* no trig of anything but a coordinate */
} Member;

typedef struct Group {
    int rep;                /* its first member */
    int count;
    int *members;
} Group;

typedef struct Roll {
    const RollContext *c;
    const Dag *dag;
    const SchedOutput *outs;
    int n;
    Member *members;
    int nmembers;
    int32_t *code;
    int ncode, capcode;
    double *vals;           /* slot values; a SIN/COS slot holds its node id */
    int nvals, capvals;
    uint32_t *stamp;        /* per node: == cur when it has a local id */
    int32_t *local;
    uint32_t cur;
    NodeId *stack;
    Group *groups;
    int ngroups;
    int *angle_pos;         /* per coordinate: its angle's position, or -1 */
} Roll;

static void put_code(Roll *r, int32_t w)
{
    if (r->ncode == r->capcode) {
        r->capcode = r->capcode ? 2 * r->capcode : 1024;
        r->code = xrealloc(r->code, (size_t)r->capcode, sizeof *r->code);
    }
    r->code[r->ncode++] = w;
}

/* A new slot of the member being read, with its value. */
static int new_slot(Roll *r, Member *m, double v)
{
    if (r->nvals == r->capvals) {
        r->capvals = r->capvals ? 2 * r->capvals : 1024;
        r->vals = xrealloc(r->vals, (size_t)r->capvals, sizeof *r->vals);
    }
    r->vals[r->nvals++] = v;
    return m->nslots++;
}

/* The row of each output, or -1 (the placeholder of an empty Jacobian).
   The dense Jacobian's k-th store is entry k (collect_outputs in emit.c):
   its index, row * NQ + col, is not read back. */
static int *output_rows(const Kinematics *kin, const SchedOutput *outs, int n)
{
    int *rows = xmalloc((size_t)(n ? n : 1) * sizeof *rows);
    int jac = 0;
    for (int k = 0; k < n; k++) {
        const char *a = outs[k].array;
        int i = outs[k].index;
        if (!strcmp(a, "jac"))
            i = jac++;
        if (!strcmp(a, "vals") || !strcmp(a, "jac_vals") || !strcmp(a, "jac"))
            rows[k] = i >= 0 && i < kin->nnz ? kin->jac[i].row : -1;
        else
            rows[k] = i >= 0 && i < kin->model->nr ? i : -1;
    }
    return rows;
}

static int array_id(const char *name)
{
    for (int i = 0; arrays[i]; i++)
        if (!strcmp(arrays[i], name))
            return i;
    return -1;
}

static bool is_trig(const Dag *dag, NodeId id)
{
    DagOp op = dag_op(dag, id);
    return op == OP_SIN || op == OP_COS;
}

/* A node's shape words, its operands already read: a leaf (or the sin or
   cos of a coordinate) takes a slot; the local id goes to the node. */
static void put_node(Roll *r, Member *m, NodeId e, int *nlocal)
{
    const DagNode *n = dag_node(r->dag, e);
    if (is_trig(r->dag, e)) {
        if (dag_op(r->dag, n->a) != OP_VAR)
            m->ok = false;
        put_code(r, n->op == OP_SIN ? W_SIN : W_COS);
        put_code(r, new_slot(r, m, e));
    } else if (n->op == OP_CONST) {
        put_code(r, W_CONST);
        put_code(r, new_slot(r, m, n->value));
    } else if (n->op == OP_VAR || n->op == OP_VARD) {
        put_code(r, n->op == OP_VAR ? W_Q : W_QD);
        put_code(r, new_slot(r, m, n->a));
    } else if (n->op == OP_TIME) {
        put_code(r, W_TIME);
    } else if (n->op == OP_PARAM) {    /* not rolled: a design is not a slot */
        m->ok = false;
        put_code(r, W_TIME);
    } else {
        put_code(r, n->op);
        put_code(r, r->local[n->a]);
        put_code(r, dag_op_info[n->op].arity == 2 ? r->local[n->b] : -1);
    }
    r->stamp[e] = r->cur;
    r->local[e] = (*nlocal)++;
}

/* Writes member m's shape: each output's new nodes in post-order, then
   its store. */
static void read_member(Roll *r, Member *m)
{
    const Dag *dag = r->dag;
    r->cur++;
    m->code_at = r->ncode;
    m->val_at = r->nvals;
    int nlocal = 0;
    for (int k = m->first; k < m->first + m->count; k++) {
        const SchedOutput *o = &r->outs[k];
        int top = 0;
        r->stack[top++] = o->value;
        while (top > 0) {
            NodeId e = r->stack[top - 1];
            if (e < 0) {                /* ~id: its operands are in */
                top--;
                put_node(r, m, ~e, &nlocal);
                continue;
            }
            if (r->stamp[e] == r->cur) {
                top--;
                continue;
            }
            if (dag_is_leaf(dag, e) || is_trig(dag, e)) {
                top--;
                put_node(r, m, e, &nlocal);
                continue;
            }
            const DagNode *n = dag_node(dag, e);
            r->stack[top - 1] = ~e;
            if (dag_op_info[n->op].arity == 2)
                r->stack[top++] = n->b;
            r->stack[top++] = n->a;
        }
        put_code(r, W_OUT);
        put_code(r, array_id(o->array));
        put_code(r, r->local[o->value]);
        put_code(r, new_slot(r, m, o->index));
    }
    m->code_len = r->ncode - m->code_at;
}

static uint64_t hash_code(const int32_t *w, int n)
{
    uint64_t h = 1469598103934665603ull;
    for (int i = 0; i < n; i++) {
        h ^= (uint32_t)w[i];
        h *= 1099511628211ull;
    }
    return h == UINT64_MAX ? 0 : h;     /* UINT64_MAX marks an empty slot */
}

/* Members: runs of outputs of one joint's rows; then groups of equal shape. */
static void find_groups(Roll *r, int n)
{
    const Model *model = r->c->kin->model;
    int *rows = output_rows(r->c->kin, r->outs, n);
    r->members = xmalloc((size_t)(n ? n : 1) * sizeof *r->members);
    for (int k = 0; k < n;) {
        int joint = rows[k] >= 0 ? model->rows[rows[k]].joint : -1;
        int end = k + 1;
        while (joint >= 0 && end < n && rows[end] >= 0 && model->rows[rows[end]].joint == joint)
            end++;
        Member *m = &r->members[r->nmembers++];
        *m = (Member){.first = k, .count = end - k, .group = -1, .ok = joint >= 0};
        read_member(r, m);
        k = end;
    }
    free(rows);
    U64Map map;
    u64map_init(&map);
    r->groups = xmalloc((size_t)(r->nmembers ? r->nmembers : 1) * sizeof *r->groups);
    for (int i = 0; i < r->nmembers; i++) {
        Member *m = &r->members[i];
        if (!m->ok)
            continue;
        uint64_t h = hash_code(r->code + m->code_at, m->code_len);
        int32_t g;
        if (!u64map_get(&map, h, &g)) {
            g = r->ngroups++;
            r->groups[g] = (Group){.rep = i};
            u64map_put(&map, h, g);
        }
        const Member *rep = &r->members[r->groups[g].rep];
        if (rep->code_len == m->code_len && !memcmp(r->code + rep->code_at, r->code + m->code_at,
                                                    (size_t)m->code_len * sizeof *r->code)) {
            m->group = g;
            r->groups[g].count++;
        }
    }
    u64map_free(&map);
    for (int g = 0; g < r->ngroups; g++)
        r->groups[g].members = xmalloc((size_t)r->groups[g].count * sizeof(int));
    for (int g = 0; g < r->ngroups; g++)
        r->groups[g].count = 0;
    for (int i = 0; i < r->nmembers; i++)
        if (r->members[i].group >= 0) {
            Group *g = &r->groups[r->members[i].group];
            g->members[g->count++] = i;
        }
    for (int g = 0; g < r->ngroups; g++)
        if (r->groups[g].count < r->c->min_members)
            for (int j = 0; j < r->groups[g].count; j++)
                r->members[r->groups[g].members[j]].group = -1;
}

static bool rolled(const Roll *r, int g)
{
    return r->groups[g].count >= r->c->min_members;
}

/* The length of the longest start of v[0 .. count) that grows by a fixed
   step (into *step; 0 for one value). */
static int affine_run(const int *v, int count, long long *step)
{
    *step = count > 1 ? (long long)v[1] - v[0] : 0;
    int i = 1;
    while (i < count && (long long)v[i] - v[i - 1] == *step)
        i++;
    return count < 1 ? 0 : i;
}

/* Whether all of v[0 .. count) grows by a fixed step (into *step). */
static bool affine_step(const int *v, int count, long long *step)
{
    return affine_run(v, count, step) == count;
}

/* Writes into text the int sequence v[0 .. count) as the loop's value for
   row i: a number, base + step * i, or a static table (written to parts). */
static void put_ints(const Roll *r, StrBuf *parts, StrBuf *text, const char *table,
                     const int *v, int count)
{
    long long step;
    bool affine = affine_step(v, count, &step);
    if (affine && step == 0) {
        sb_printf(text, "%d", v[0]);
        return;
    }
    if (affine) {
        if (v[0])
            sb_printf(text, "%d + ", v[0]);
        sb_printf(text, step == 1 ? "i" : "%lld * i", step);
        return;
    }
    sb_printf(parts, "static const int %s_%s[%d] = {\n", r->c->prefix, table, count);
    for (int i = 0; i < count; i++)
        sb_printf(parts, "%s%d,%s", i % 16 ? " " : "    ", v[i], i % 16 == 15 || i == count - 1 ? "\n" : "");
    sb_puts(parts, "};\n");
    sb_printf(text, "%s_%s[i]", r->c->prefix, table);
}

/* Writes into text the element of array that row i reads or writes,
   whose indices over the rows are v[0 .. count): array[v0] for one index,
   through a pointer that moves with i (declared in decls, once per array
   and step: libtcc then loads each element by one instruction) where they
   grow by a fixed step, else through a table. A falling index's pointer
   moves down from array + |step| (count - 1) to array, read at the last
   row's index: array + step * i would point before the array, undefined
   in C99 (6.5.6p8) even where the element read is inside it. */
static void put_element(const Roll *r, StrBuf *parts, StrBuf *text, StrBuf *decls,
                        const char *table, const char *array, bool output, const int *v,
                        int count)
{
    long long step;
    if (!affine_step(v, count, &step) || step == 0) {
        sb_printf(text, "%s[", array);
        put_ints(r, parts, text, table, v, count);
        sb_putc(text, ']');
        return;
    }
    char name[64];
    snprintf(name, sizeof name, "%s_%s%lld", array, step < 0 ? "m" : "", step < 0 ? -step : step);
    char decl[160];
    snprintf(decl, sizeof decl, " %s = ", name);
    if (!strstr(decls->data, decl)) {
        sb_printf(decls, "        %s%s_real *const%s%s + ", output ? "" : "const ", r->c->prefix,
                  decl, array);
        if (step > 0)
            sb_printf(decls, "%lld * i;\n", step);
        else
            sb_printf(decls, "%lld * (%d - i);\n", -step, count - 1);
    }
    sb_printf(text, "%s[%d]", name, step > 0 ? v[0] : v[count - 1]);
}

/* The angles of coordinates v[0 .. count) whose sin and cos are both
   used, two a call of the two-angle function (the same operations as the
   pair function, so the same bits), into roll_s and roll_c from first. */
static void put_pairs(const Roll *r, StrBuf *parts, StrBuf *loops, const char *table,
                      const int *v, int count, int first)
{
    int half = count / 2;
    int *even = xmalloc((size_t)half * sizeof *even), *odd = xmalloc((size_t)half * sizeof *odd);
    for (int i = 0; i < half; i++) {
        even[i] = v[2 * i];
        odd[i] = v[2 * i + 1];
    }
    StrBuf a, b;
    sb_init(&a);
    sb_init(&b);
    sb_puts(&a, "");
    sb_puts(&b, "");
    char name[96];
    snprintf(name, sizeof name, "%s_e", table);
    put_ints(r, parts, &a, name, even, half);
    snprintf(name, sizeof name, "%s_o", table);
    put_ints(r, parts, &b, name, odd, half);
    sb_printf(loops, "    for (int i = 0; i < %d; i++)\n        %s(q[%s], q[%s], &roll_s[%d + 2 * i], "
              "&roll_c[%d + 2 * i],\n            &roll_s[%d + 2 * i], &roll_c[%d + 2 * i]);\n", half,
              r->c->sincos2_name, a.data, b.data, first, first, first + 1, first + 1);
    if (count % 2)
        sb_printf(loops, "    %s(q[%d], &roll_s[%d], &roll_c[%d]);\n", r->c->sincos_name,
                  v[count - 1], first + count - 1, first + count - 1);
    *r->c->sincos_used = true;      /* sincos2 calls it for its rare case */
    *r->c->sincos2_used = true;
    sb_free(&a);
    sb_free(&b);
    free(even);
    free(odd);
}

/* Which angles the rolled groups read, into used[nq]: 1 sin, 2 cos, 3
   both, as the function's straight-line code would use them (the pair,
   or a single function); false when they read none. */
static bool angles_used(const Roll *r, uint8_t *used)
{
    const Dag *dag = r->dag;
    int nq = r->c->kin->model->nq;
    bool any = false;
    for (int g = 0; g < r->ngroups; g++) {
        if (!rolled(r, g))
            continue;
        for (int j = 0; j < r->groups[g].count; j++) {
            const Member *m = &r->members[r->groups[g].members[j]];
            for (int w = m->code_at; w < m->code_at + m->code_len;) {
                int32_t word = r->code[w];
                if (word == W_SIN || word == W_COS) {
                    NodeId id = (NodeId)r->vals[m->val_at + r->code[w + 1]];
                    used[dag_node(dag, dag_node(dag, id)->a)->a] |= 4;
                    any = true;
                }
                w += word == W_OUT ? 4 : word == W_TIME ? 1 : word < 0 ? 2 : 3;
            }
        }
    }
    if (!any)
        return false;
    /* which of sin and cos the whole function uses, as its straight-line
       code would choose the pair or a single function */
    uint32_t *mark = xcalloc((size_t)dag->count, sizeof *mark);
    NodeId *roots = xmalloc((size_t)(r->n ? r->n : 1) * sizeof *roots);
    for (int k = 0; k < r->n; k++)
        roots[k] = r->outs[k].value;
    dag_mark_reachable(dag, roots, r->n, mark, 1, r->stack);
    free(roots);
    for (int k = 0; k < nq; k++) {
        if (!(used[k] & 4))
            continue;
        NodeId var = dag_find(dag, OP_VAR, k, -1);
        NodeId s = dag_find(dag, OP_SIN, var, -1), c = dag_find(dag, OP_COS, var, -1);
        used[k] = (uint8_t)((s != DAG_NONE && mark[s] == 1) | (c != DAG_NONE && mark[c] == 1) << 1);
    }
    free(mark);
    return true;
}

/* The angles the rolled groups read: positions in the sin and cos arrays
   (pairs, then sin only, then cos only, each by coordinate), set in
   r->angle_pos; then the loops that fill them. Returns their operations. */
static long put_angles(Roll *r, StrBuf *parts, StrBuf *body)
{
    int nq = r->c->kin->model->nq;
    uint8_t *used = xcalloc((size_t)(nq ? nq : 1), 1);
    if (!angles_used(r, used)) {
        free(used);
        return 0;
    }
    int *coords = xmalloc((size_t)nq * sizeof *coords);
    int n = 0;
    StrBuf loops;
    sb_init(&loops);
    sb_puts(&loops, "");
    for (int cls = 3; cls >= 1; cls--) {    /* 3 pair, 1 sin only, 2 cos only */
        int kind = cls == 3 ? 0 : cls;
        int first = n;
        for (int k = 0; k < nq; k++)
            if (used[k] == (kind == 0 ? 3 : kind)) {
                r->angle_pos[k] = n;
                coords[n++] = k;
            }
        if (n == first)
            continue;
        char table[64];
        snprintf(table, sizeof table, "%s_ra%d", r->c->function, kind);
        if (kind == 0 && r->c->sincos2_name && n - first >= 2) {
            put_pairs(r, parts, &loops, table, coords + first, n - first, first);
            continue;
        }
        StrBuf at;
        sb_init(&at);
        sb_puts(&at, "");
        put_ints(r, parts, &at, table, coords + first, n - first);
        sb_printf(&loops, "    for (int i = 0; i < %d; i++) {\n", n - first);
        const char *name = r->c->sincos_name;
        if (name && kind != 0 && r->c->sin_name) {
            name = kind == 1 ? r->c->sin_name : r->c->cos_name;
            *r->c->single_used = true;
        }
        if (name) {
            *r->c->sincos_used = true;
            sb_printf(&loops, "        %s(q[%s], &roll_s[%d + i], &roll_c[%d + i]);\n", name, at.data,
                      first, first);
        } else {
            const char *sin = r->c->real_float ? "sinf" : "sin", *cos = r->c->real_float ? "cosf" : "cos";
            if (kind != 2)
                sb_printf(&loops, "        roll_s[%d + i] = %s(q[%s]);\n", first, sin, at.data);
            if (kind != 1)
                sb_printf(&loops, "        roll_c[%d + i] = %s(q[%s]);\n", first, cos, at.data);
        }
        sb_puts(&loops, "    }\n");
        sb_free(&at);
    }
    sb_printf(body, "    %s_real roll_s[%d], roll_c[%d];\n%s", r->c->prefix, n, n, loops.data);
    sb_free(&loops);
    long ops = 0;
    for (int k = 0; k < n; k++)
        ops += used[coords[k]] == 3 ? 2 : 1;
    free(coords);
    free(used);
    return ops;
}

/* What a group's hooks print: one text per slot. */
typedef struct SlotTexts {
    char **text;
} SlotTexts;

static void leaf_hook(void *ctx, StrBuf *sb, int slot)
{
    sb_puts(sb, ((SlotTexts *)ctx)->text[slot]);
}

static void store_hook(void *ctx, StrBuf *sb, const SchedOutput *o)
{
    sb_printf(sb, "    %s = ", ((SlotTexts *)ctx)->text[o->index]);
}

/* The kinds of a shape's slots (W_CONST, W_Q, ...), into kind[nslots]. */
static void slot_kinds(const Roll *r, const Member *rep, int32_t *kind)
{
    for (int w = rep->code_at; w < rep->code_at + rep->code_len;) {
        int32_t word = r->code[w];
        if (word == W_OUT)
            kind[r->code[w + 3]] = W_OUT;
        else if (word < 0 && word != W_TIME)
            kind[r->code[w + 1]] = word;
        w += word == W_OUT ? 4 : word == W_TIME ? 1 : word < 0 ? 2 : 3;
    }
}

/* Member m's value of an index slot s of kind k: the coordinate, the
   store's index, or the angle's position in roll_s and roll_c. */
static int slot_int(const Roll *r, int m, int s, int32_t k)
{
    double v = r->vals[r->members[m].val_at + s];
    if (k == W_SIN || k == W_COS)
        return r->angle_pos[dag_node(r->dag, dag_node(r->dag, (NodeId)v)->a)->a];
    return (int)v;
}

/* The texts of the slots of the loop over members[0 .. count): a
   constant the same for all (uniform[s]: the body's graph holds it, text
   NULL), a table of constants, an index (put_element: row pointers into
   decls, tables into parts). */
static char **slot_texts(const Roll *r, const int *members, int count, int number,
                         StrBuf *parts, StrBuf *decls, bool *uniform)
{
    const Member *rep = &r->members[members[0]];
    int ns = rep->nslots;
    const char *P = r->c->prefix;
    char **texts = xcalloc((size_t)(ns ? ns : 1), sizeof *texts);
    int *ints = xmalloc((size_t)count * sizeof *ints);
    int32_t *kind = xmalloc((size_t)(ns ? ns : 1) * sizeof *kind);
    slot_kinds(r, rep, kind);
    const char **array = xcalloc((size_t)(ns ? ns : 1), sizeof *array);  /* what a slot indexes */
    for (int w = rep->code_at; w < rep->code_at + rep->code_len;) {
        int32_t word = r->code[w];
        if (word == W_OUT)
            array[r->code[w + 3]] = arrays[r->code[w + 1]];
        else if (word < 0 && word != W_TIME)
            array[r->code[w + 1]] = word == W_Q ? "q" : word == W_QD ? "qd"
                                  : word == W_SIN ? "roll_s" : "roll_c";
        w += word == W_OUT ? 4 : word == W_TIME ? 1 : word < 0 ? 2 : 3;
    }
    for (int s = 0; s < ns; s++) {
        StrBuf t;
        sb_init(&t);
        sb_puts(&t, "");
        const double *v0 = &r->vals[rep->val_at + s];
        char table[96];
        if (kind[s] == W_CONST) {
            bool same = true;
            for (int j = 1; j < count && same; j++) {
                double v = r->vals[r->members[members[j]].val_at + s];
                same = memcmp(&v, v0, sizeof v) == 0;
            }
            uniform[s] = same;
            if (!same) {
                snprintf(table, sizeof table, "%s_%s_r%d_k%d", P, r->c->function, number, s);
                sb_printf(parts, "static const %s_real %s[%d] = {\n", P, table, count);
                for (int j = 0; j < count; j++) {
                    sb_puts(parts, j % 8 ? " " : "    ");
                    emit_put_literal(parts, r->vals[r->members[members[j]].val_at + s], r->c->real_float);
                    sb_puts(parts, j % 8 == 7 || j == count - 1 ? ",\n" : ",");
                }
                sb_puts(parts, "};\n");
                sb_printf(&t, "%s[i]", table);
            }
        } else {
            for (int j = 0; j < count; j++)
                ints[j] = slot_int(r, members[j], s, kind[s]);
            snprintf(table, sizeof table, "%s_r%d_x%d", r->c->function, number, s);
            put_element(r, parts, &t, decls, table, array[s], kind[s] == W_OUT, ints, count);
        }
        texts[s] = sb_take(&t);
    }
    free(array);
    free(ints);
    free(kind);
    return texts;
}

/* The loop body's graph: rep's shape with the slots as leaves (a uniform
   constant as itself), into graph and outs (*nouts). */
static void body_graph(const Roll *r, const Member *rep, const bool *uniform, Dag *graph,
                       SchedOutput *outs, int *nouts)
{
    int nnodes = 0;
    *nouts = 0;
    for (int w = rep->code_at; w < rep->code_at + rep->code_len;) {
        int32_t word = r->code[w];
        if (word == W_OUT) {
            outs[(*nouts)++] = (SchedOutput){arrays[r->code[w + 1]], r->code[w + 3], r->code[w + 2]};
            w += 4;
            continue;
        }
        DagNode *n = &graph->nodes[nnodes++];
        if (word == W_TIME) {
            *n = (DagNode){.op = OP_TIME, .a = -1, .b = -1};
            w += 1;
        } else if (word == W_CONST && uniform[r->code[w + 1]]) {
            *n = (DagNode){.op = OP_CONST, .a = -1, .b = -1,
                           .value = r->vals[rep->val_at + r->code[w + 1]]};
            w += 2;
        } else if (word < 0) {
            *n = (DagNode){.op = OP_VAR, .a = r->code[w + 1], .b = -1};
            w += 2;
        } else {
            *n = (DagNode){.op = (uint8_t)word, .a = r->code[w + 1], .b = r->code[w + 2]};
            w += 3;
        }
    }
    graph->count = nnodes;
}

/* The loop over members[0 .. count) (of one shape): its tables (parts)
   and loop (body); returns its operations per call. */
static long put_loop(Roll *r, const int *members, int count, int number, StrBuf *parts,
                     StrBuf *body)
{
    const Member *rep = &r->members[members[0]];
    int ns = rep->nslots;
    bool *uniform = xcalloc((size_t)(ns ? ns : 1), sizeof *uniform);
    StrBuf decls;      /* the loop's row pointers */
    sb_init(&decls);
    sb_puts(&decls, "");
    char **texts = slot_texts(r, members, count, number, parts, &decls, uniform);
    int nodes_cap = rep->code_len / 2 + 1, nouts = 0;
    Dag graph = {.nodes = xmalloc((size_t)nodes_cap * sizeof(DagNode)), .cap = nodes_cap};
    SchedOutput *outs = xmalloc((size_t)rep->count * sizeof *outs);     /* write_body's */
    body_graph(r, rep, uniform, &graph, outs, &nouts);
    SlotTexts st = {texts};
    RollHooks hooks = {leaf_hook, store_hook, &st};
    StrBuf stmts;
    sb_init(&stmts);
    sb_puts(&stmts, "");
    int ops = r->c->write_body(r->c->emitter, &graph, outs, nouts, &hooks, &stmts);
    sb_printf(body, "    /* %d joints' rows of one shape: one loop */\n"
              "    for (int i = 0; i < %d; i++) {\n%s", count, count, decls.data);
    sb_free(&decls);
    for (const char *line = stmts.data; *line;) {     /* one level deeper */
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) + 1 : strlen(line);
        sb_puts(body, "    ");
        sb_putn(body, line, len);
        line += len;
    }
    sb_puts(body, "    }\n");
    sb_free(&stmts);
    free(graph.nodes);
    for (int s = 0; s < ns; s++)
        free(texts[s]);
    free(texts);
    free(uniform);
    return (long)ops * count;
}

/* Group g as loops: each run of RUN_MIN or more members whose index
   slots all grow by fixed steps gets a loop without tables; the other
   members share one loop with tables, or go back to straight-line code
   (group -1) when fewer than min_members. Returns the operations. */
enum { RUN_MIN = 8 };
static long put_group(Roll *r, int g, int *number, StrBuf *parts, StrBuf *body)
{
    const Group *grp = &r->groups[g];
    const Member *rep = &r->members[grp->rep];
    int ns = rep->nslots, count = grp->count, nleft = 0;
    int32_t *kind = xmalloc((size_t)(ns ? ns : 1) * sizeof *kind);
    slot_kinds(r, rep, kind);
    int *left = xmalloc((size_t)count * sizeof *left);
    int *ints = xmalloc((size_t)(ns ? ns : 1) * (size_t)count * sizeof *ints);
    for (int s = 0; s < ns; s++)
        if (kind[s] != W_CONST)
            for (int j = 0; j < count; j++)
                ints[(size_t)s * count + j] = slot_int(r, grp->members[j], s, kind[s]);
    long ops = 0;
    for (int j = 0; j < count;) {
        int k = count;      /* the run from j: every index slot steady */
        long long step;
        for (int s = 0; s < ns; s++)
            if (kind[s] != W_CONST) {
                int run = affine_run(ints + (size_t)s * count + j, count - j, &step);
                k = j + run < k ? j + run : k;
            }
        if (k - j >= RUN_MIN || (j == 0 && k == count)) {
            ops += put_loop(r, grp->members + j, k - j, (*number)++, parts, body);
            j = k;
        } else {
            left[nleft++] = grp->members[j++];
        }
    }
    if (nleft >= r->c->min_members)
        ops += put_loop(r, left, nleft, (*number)++, parts, body);
    else
        for (int j = 0; j < nleft; j++)
            r->members[left[j]].group = -1;
    free(left);
    free(ints);
    free(kind);
    return ops;
}

int roll_function(const RollContext *c, const SchedOutput *outs, int n, StrBuf *parts,
                  StrBuf *body, SchedOutput **rest, int *nrest, long *ops)
{
    const Dag *dag = &c->kin->model->dag;
    Roll r = {.c = c, .dag = dag, .outs = outs, .n = n};
    size_t count = (size_t)dag->count;
    r.stamp = xcalloc(count, sizeof *r.stamp);
    r.local = xcalloc(count, sizeof *r.local);
    r.stack = xmalloc((2 * count + 1) * sizeof *r.stack);
    find_groups(&r, n);
    int nrolled = 0;
    for (int g = 0; g < r.ngroups; g++)
        if (rolled(&r, g))
            for (int j = 0; j < r.groups[g].count; j++)
                nrolled += r.members[r.groups[g].members[j]].count;
    *rest = NULL;
    *nrest = 0;
    *ops = 0;
    if (nrolled > 0) {
        int nq = c->kin->model->nq;
        r.angle_pos = xmalloc((size_t)(nq ? nq : 1) * sizeof *r.angle_pos);
        memset(r.angle_pos, 0xff, (size_t)nq * sizeof *r.angle_pos);
        *ops += put_angles(&r, parts, body);
        int number = 0;
        for (int g = 0; g < r.ngroups; g++)
            if (rolled(&r, g))
                *ops += put_group(&r, g, &number, parts, body);
        nrolled = 0;
        for (int i = 0; i < r.nmembers; i++)
            if (r.members[i].group >= 0)
                nrolled += r.members[i].count;
        *rest = xmalloc((size_t)(n - nrolled + 1) * sizeof **rest);
        for (int i = 0; i < r.nmembers; i++)
            if (r.members[i].group < 0)
                for (int k = r.members[i].first; k < r.members[i].first + r.members[i].count; k++)
                    (*rest)[(*nrest)++] = outs[k];
        free(r.angle_pos);
    }
    for (int g = 0; g < r.ngroups; g++)
        free(r.groups[g].members);
    free(r.groups);
    free(r.members);
    free(r.code);
    free(r.vals);
    free(r.stamp);
    free(r.local);
    free(r.stack);
    return nrolled;
}
