/* expr.c - a node of the graph as C: its temporary, or its expression with the fewest parentheses. */
#include "emitter.h"

#include "literal.h"

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

static void put_operand(const Emitter *e, StrBuf *sb, NodeId id, int parent, bool right)
{
    int p = c_precedence(e, id);
    /* Equal precedence on the right keeps the graph's grouping: a - (b - c),
       a * (b / c); floating point is not associative. */
    bool paren = p < parent || (right && p == parent);
    if (paren)
        sb_putc(sb, '(');
    emit_put_expr(e, sb, id, false);
    if (paren)
        sb_putc(sb, ')');
}

void emit_put_expr(const Emitter *e, StrBuf *sb, NodeId id, bool top)
{
    const DagNode *n = dag_node(e->dag, id);
    if (!top && e->sched.temp[id] >= 0) {
        sb_printf(sb, "u%d", e->sched.temp[id]);
        return;
    }
    DagOp op = (DagOp)n->op;
    switch (op) {
    case OP_CONST: emit_put_literal(sb, n->value, e->opt->real_float); return;
    case OP_VAR:
        if (e->roll)    /* a slot of a loop body */
            e->roll->leaf(e->roll->ctx, sb, n->a);
        else
            sb_printf(sb, e->lanes ? "qv[%d][l]" : "q[%d]", n->a);
        return;
    case OP_VARD:  sb_printf(sb, e->lanes ? "qdv[%d][l]" : "qd[%d]", n->a); return;
    case OP_TIME:  sb_puts(sb, e->lanes ? "tv[l]" : "t"); return;
    case OP_PARAM: sb_printf(sb, "p[%d]", n->a); return;
    case OP_NEG:
        if (sched_fused_negation(&e->sched, id)) {     /* (-c) * y */
            const DagNode *product = dag_node(e->dag, n->a);
            emit_put_literal(sb, -dag_node(e->dag, product->a)->value, e->opt->real_float);
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
        emit_put_expr(e, sb, n->a, false);
        if (dag_op_info[op].arity == 2) {
            sb_puts(sb, ", ");
            emit_put_expr(e, sb, n->b, false);
        }
        sb_putc(sb, ')');
        return;
    }
}

/* Stores the temporary of id into its workspace slot, if it has one (a
   later chunk of the function imports it). */
void emit_put_export(const Emitter *e, StrBuf *sb, NodeId id)
{
    int slot = id == DAG_NONE ? -1 : sched_slot(&e->sched, id);
    if (slot >= 0)
        sb_printf(sb, "    ws[%d]%s = u%d;\n", slot, e->lanes ? "[l]" : "", e->sched.temp[id]);
}
