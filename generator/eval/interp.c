/* interp.c - compiles expressions to an instruction list and runs it, with or without derivatives.
 *
 * Compiling: the nodes reachable from the roots are collected (iterative
 * depth-first walk) and sorted by id, which is a topological order of the
 * graph; node ids become register numbers. Running is one loop over the
 * instructions. Values come from dag_op_eval, the single definition of
 * every operation; derivatives are carried forward as jets
 * (v, d, dd) = (f, f', f'') along one direction of (q, qd, t):
 *
 *   unary f:  (f(x), f'(x) x', f'(x) x'' + f''(x) x'^2)
 *   a * b:    (ab, a'b + ab', a''b + 2a'b' + ab'')
 *   a / b:    q = a/b, q' = (a' - q b')/b, q'' = (a'' - 2q'b' - q b'')/b
 *   a ^ c:    power rule when c is a constant, else exp(b log a)
 *   atan2:    (x y' - y x')/(x^2 + y^2), differentiated once more
 *
 * These rules are written here from the calculus, not taken from the
 * symbolic differentiator (generator/diff/), so the two check each other.
 */
#include "interp.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void compile_scratch_init(CompileScratch *cs, const Dag *dag)
{
    memset(cs, 0, sizeof *cs);
    cs->cap = dag->count;
    cs->mark = xcalloc((size_t)cs->cap + 1, sizeof *cs->mark);
    cs->stack = xmalloc(((size_t)cs->cap + 1) * sizeof *cs->stack);
    cs->nodes = xmalloc(((size_t)cs->cap + 1) * sizeof *cs->nodes);
    cs->slot = xmalloc(((size_t)cs->cap + 1) * sizeof *cs->slot);
}

void compile_scratch_free(CompileScratch *cs)
{
    free(cs->mark);
    free(cs->stack);
    free(cs->nodes);
    free(cs->slot);
    memset(cs, 0, sizeof *cs);
}

static int compare_ids(const void *x, const void *y)
{
    NodeId a = *(const NodeId *)x, b = *(const NodeId *)y;
    return (a > b) - (a < b);
}

static int compare_ints(const void *x, const void *y)
{
    int a = *(const int *)x, b = *(const int *)y;
    return (a > b) - (a < b);
}

void tape_compile_roots(Tape *p, const Dag *dag, const NodeId *roots, int nroots,
                        CompileScratch *cs)
{
    memset(p, 0, sizeof *p);
    if (++cs->stamp == 0) {
        memset(cs->mark, 0, ((size_t)cs->cap + 1) * sizeof *cs->mark);
        cs->stamp = 1;
    }
    int top = 0, n = 0;
    for (int r = 0; r < nroots; r++)
        if (roots[r] >= 0 && cs->mark[roots[r]] != cs->stamp) {
            cs->mark[roots[r]] = cs->stamp;
            cs->stack[top++] = roots[r];
        }
    while (top > 0) {
        NodeId id = cs->stack[--top];
        cs->nodes[n++] = id;
        const DagNode *node = dag_node(dag, id);
        int arity = dag_op_info[node->op].arity;
        NodeId kids[2] = {node->a, node->b};
        for (int k = 0; k < arity; k++)
            if (cs->mark[kids[k]] != cs->stamp) {
                cs->mark[kids[k]] = cs->stamp;
                cs->stack[top++] = kids[k];
            }
    }
    qsort(cs->nodes, (size_t)n, sizeof *cs->nodes, compare_ids);

    p->n = n;
    p->code = xmalloc((size_t)n * sizeof *p->code);
    p->qcols = xmalloc((size_t)n * sizeof *p->qcols);
    p->qdcols = xmalloc((size_t)n * sizeof *p->qdcols);
    for (int k = 0; k < n; k++) {
        const DagNode *node = dag_node(dag, cs->nodes[k]);
        cs->slot[cs->nodes[k]] = k;
        Instr *in = &p->code[k];
        *in = (Instr){.op = node->op, .a = node->a, .b = node->a, .value = node->value};
        switch ((DagOp)node->op) {
        case OP_CONST:
            break;
        case OP_VAR:
            p->qcols[p->nqcols++] = node->a;
            break;
        case OP_VARD:
            p->qdcols[p->nqdcols++] = node->a;
            break;
        case OP_TIME:
            p->has_t = true;
            break;
        case OP_PARAM:
            p->params = dag->param_values;
            break;
        default:
            in->a = cs->slot[node->a];
            in->b = dag_op_info[node->op].arity == 2 ? cs->slot[node->b] : in->a;
            break;
        }
    }
    /* hash-consing makes every leaf unique: sorting is all that is needed */
    qsort(p->qcols, (size_t)p->nqcols, sizeof *p->qcols, compare_ints);
    qsort(p->qdcols, (size_t)p->nqdcols, sizeof *p->qdcols, compare_ints);
    p->nout = nroots;
    p->out = xmalloc((size_t)nroots * sizeof *p->out);
    for (int r = 0; r < nroots; r++)
        p->out[r] = roots[r] >= 0 ? cs->slot[roots[r]] : -1;
}

void tape_compile(Tape *p, const Dag *dag, NodeId root, CompileScratch *cs)
{
    tape_compile_roots(p, dag, &root, 1, cs);
}

void tape_free(Tape *p)
{
    free(p->code);
    free(p->out);
    free(p->qcols);
    free(p->qdcols);
    memset(p, 0, sizeof *p);
}

void tape_run(const Tape *p, const double *q, const double *qd, double t, double *reg)
{
    for (int k = 0; k < p->n; k++) {
        const Instr *in = &p->code[k];
        switch ((DagOp)in->op) {
        case OP_CONST: reg[k] = in->value; break;
        case OP_VAR:   reg[k] = q[in->a]; break;
        case OP_VARD:  reg[k] = qd ? qd[in->a] : 0.0; break;
        case OP_TIME:  reg[k] = t; break;
        case OP_PARAM: reg[k] = p->params[in->a]; break;
        default:       reg[k] = dag_op_eval((DagOp)in->op, reg[in->a], reg[in->b]); break;
        }
    }
}

double tape_value(const Tape *p, const double *q, const double *qd, double t, double *reg)
{
    tape_run(p, q, qd, t, reg);
    return reg[p->n - 1];
}

/* f(x) for a unary f with f' = f1 and f'' = f2 at x.v. */
static inline Jet chain(double f0, double f1, double f2, Jet x)
{
    return (Jet){f0, f1 * x.d, f1 * x.dd + f2 * x.d * x.d};
}

static Jet jet_unary(DagOp op, Jet x)
{
    double v = dag_op_eval(op, x.v, 0.0);
    switch (op) {
    case OP_SIN:  return chain(v, cos(x.v), -v, x);
    case OP_COS:  return chain(v, -sin(x.v), -v, x);
    case OP_TAN:  return chain(v, 1.0 + v * v, 2.0 * v * (1.0 + v * v), x);
    case OP_ASIN: {
        double f1 = 1.0 / sqrt(1.0 - x.v * x.v);
        return chain(v, f1, x.v * f1 * f1 * f1, x);
    }
    case OP_ACOS: {
        double f1 = 1.0 / sqrt(1.0 - x.v * x.v);
        return chain(v, -f1, -x.v * f1 * f1 * f1, x);
    }
    case OP_ATAN: {
        double f1 = 1.0 / (1.0 + x.v * x.v);
        return chain(v, f1, -2.0 * x.v * f1 * f1, x);
    }
    case OP_SQRT: {
        double f1 = 0.5 / v;
        return chain(v, f1, -f1 * f1 / v, x);
    }
    case OP_EXP:  return chain(v, v, v, x);
    case OP_LOG:  return chain(v, 1.0 / x.v, -1.0 / (x.v * x.v), x);
    case OP_SINH: return chain(v, cosh(x.v), v, x);
    case OP_COSH: return chain(v, sinh(x.v), v, x);
    case OP_TANH: return chain(v, 1.0 - v * v, -2.0 * v * (1.0 - v * v), x);
    default:      break;
    }
    return (Jet){NAN, NAN, NAN};
}

/* a ^ b: the power rule when the exponent is a constant of the program
   (as the symbolic rule does), else a^b = exp(u), u = b log a. */
static Jet jet_pow(Jet a, Jet b, bool constant_exponent)
{
    double v = dag_op_eval(OP_POW, a.v, b.v);
    if (constant_exponent) {
        double f1 = b.v * dag_op_eval(OP_POW, a.v, b.v - 1.0);
        double f2 = b.v * (b.v - 1.0) * dag_op_eval(OP_POW, a.v, b.v - 2.0);
        return chain(v, f1, f2, a);
    }
    double la = log(a.v), ra = a.d / a.v;
    double u1 = b.d * la + b.v * ra;
    double u2 = b.dd * la + 2.0 * b.d * ra + b.v * (a.dd / a.v - ra * ra);
    return (Jet){v, v * u1, v * (u2 + u1 * u1)};
}

Jet tape_jet(const Tape *p, const Seed *s, int order, Jet *reg)
{
    for (int k = 0; k < p->n; k++) {
        const Instr *in = &p->code[k];
        switch ((DagOp)in->op) {    /* leaves: a is a coordinate, not a register */
        case OP_CONST:
            reg[k] = (Jet){in->value, 0.0, 0.0};
            continue;
        case OP_VAR:
            reg[k] = (Jet){s->q[in->a], s->dq ? s->dq[in->a] : (in->a == s->col_q ? 1.0 : 0.0), 0.0};
            continue;
        case OP_VARD:
            reg[k] = (Jet){s->qd ? s->qd[in->a] : 0.0,
                           s->dqd ? s->dqd[in->a] : in->a == s->col_qd ? 1.0 : 0.0, 0.0};
            continue;
        case OP_TIME:
            reg[k] = (Jet){s->t, s->dt, 0.0};
            continue;
        case OP_PARAM:
            reg[k] = (Jet){p->params[in->a], s->dp ? s->dp[in->a] : 0.0, 0.0};
            continue;
        default:
            break;
        }
        Jet a = reg[in->a], b = reg[in->b], r;
        switch ((DagOp)in->op) {
        case OP_CONST: case OP_VAR: case OP_VARD: case OP_TIME: case OP_PARAM:
            r = a;      /* handled above */
            break;
        case OP_NEG:
            r = (Jet){-a.v, -a.d, -a.dd};
            break;
        case OP_ADD:
            r = (Jet){a.v + b.v, a.d + b.d, a.dd + b.dd};
            break;
        case OP_SUB:
            r = (Jet){a.v - b.v, a.d - b.d, a.dd - b.dd};
            break;
        case OP_MUL:
            r = (Jet){a.v * b.v, a.d * b.v + a.v * b.d, 0.0};
            if (order > 1)
                r.dd = a.dd * b.v + 2.0 * a.d * b.d + a.v * b.dd;
            break;
        case OP_DIV: {
            double q = a.v / b.v, q1 = (a.d - q * b.d) / b.v;
            r = (Jet){q, q1, 0.0};
            if (order > 1)
                r.dd = (a.dd - 2.0 * q1 * b.d - q * b.dd) / b.v;
            break;
        }
        case OP_POW:
            r = jet_pow(a, b, p->code[in->b].op == OP_CONST);
            break;
        case OP_ATAN2: {
            /* y = a, x = b: (atan2)' = N/M, N = x y' - y x', M = x^2 + y^2 */
            double m = a.v * a.v + b.v * b.v, n = b.v * a.d - a.v * b.d;
            double d1 = n / m;
            r = (Jet){dag_op_eval(OP_ATAN2, a.v, b.v), d1, 0.0};
            if (order > 1) {
                double n1 = b.v * a.dd - a.v * b.dd, m1 = 2.0 * (b.v * b.d + a.v * a.d);
                r.dd = (n1 - d1 * m1) / m;
            }
            break;
        }
        default:
            r = jet_unary((DagOp)in->op, a);
            break;
        }
        reg[k] = r;
    }
    return reg[p->n - 1];
}

/* ---- many roots, evaluated again and again ---- */

void node_values_init(NodeValues *nv, const Dag *dag, const NodeId *roots, int nroots)
{
    CompileScratch cs;
    compile_scratch_init(&cs, dag);
    tape_compile_roots(&nv->tape, dag, roots, nroots, &cs);
    compile_scratch_free(&cs);
    nv->reg = xcalloc((size_t)nv->tape.n, sizeof *nv->reg);
}

void node_values_free(NodeValues *nv)
{
    tape_free(&nv->tape);
    free(nv->reg);
    nv->reg = NULL;
}

void node_values_run(NodeValues *nv, const double *q, const double *qd, double t)
{
    tape_run(&nv->tape, q, qd, t, nv->reg);
}

double node_values_get(const NodeValues *nv, int k)
{
    int r = nv->tape.out[k];
    return r >= 0 ? nv->reg[r] : NAN;
}

double node_value_at(const Dag *dag, NodeId id, const double *q, const double *qd, double t)
{
    NodeValues nv;
    node_values_init(&nv, dag, &id, 1);
    node_values_run(&nv, q, qd, t);
    double v = node_values_get(&nv, 0);
    node_values_free(&nv);
    return v;
}
