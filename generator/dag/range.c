/* range.c - constants a double or a float cannot hold, reported at the statement they come from.
 *
 * Folding keeps only finite results (dag.c), but a builder also combines
 * the file's numbers itself: an offset turned by an initial orientation,
 * an axis normalised, m |com|^2 + J, m g. Past the range of a double that
 * gives inf or NaN, which the generated C cannot spell and the engines
 * cannot use; gen --real float also turns a finite double past FLT_MAX
 * into HUGE_VALF and one below half the smallest float into 0. Each
 * constant node is noted once, when it is made, with the sub-expression
 * being lowered (Dag.where_expr: the number, or the operator or call that
 * folded to it) or, for what a builder combines, the statement being
 * built (Dag.where); the checks run after the graph is complete, so that
 * one message names the first such constant.
 */
#include "dag.h"

#include "../base/arena.h"
#include "../../runtime/host/format_real.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* Nonzero and finite, but inf or 0 once rounded to a float. */
static bool float_loses(double v)
{
    float f = (float)v;
    return isfinite(v) && (isinf(f) || (v != 0.0 && f == 0.0f));
}

void dag_range_note_nonfinite(Dag *dag, double v)
{
    if (isfinite(v) || dag->nonfinite)
        return;
    bool expr = dag->where_expr >= 0;
    dag->nonfinite = true;
    dag->nonfinite_where = expr ? dag->where_expr : dag->where;
    dag->nonfinite_expr = expr;
    dag->nonfinite_what = dag->what;
    dag->nonfinite_value = v;
}

void dag_range_note(Dag *dag, NodeId id)
{
    double v = dag->nodes[id].value;
    dag_range_note_nonfinite(dag, v);
    if (!float_loses(v))
        return;
    bool expr = dag->where_expr >= 0;
    int32_t where = expr ? dag->where_expr : dag->where;
    if (dag->nwide == dag->wide_cap) {
        dag->wide_cap = dag->wide_cap ? 2 * dag->wide_cap : 8;
        dag->wide = xrealloc(dag->wide, (size_t)dag->wide_cap, sizeof *dag->wide);
    }
    dag->wide[dag->nwide++] = (DagWide){id, where, expr, dag->what};
}

NodeId dag_const_named(Dag *dag, double value, const char *what)
{
    const char *outer = dag->what;
    dag->what = what;
    NodeId id = dag_const(dag, value);
    dag->what = outer;
    return id;
}

/* The message at where (-1: none), what is wrong and what to do; expr:
   where is the constant's own sub-expression, not its statement; named:
   what the builder combined (NULL: unnamed). */
static void report(Diag *diag, int32_t where, bool expr, const char *named, const char *what,
                   const char *advice)
{
    char name[160] = "";
    if (named)
        snprintf(name, sizeof name, " (%s)", named);
    if (where >= 0 && expr)
        diag_error(diag, (SrcPos){where}, "this constant %s; %s", what, advice);
    else if (where >= 0)
        diag_error(diag, (SrcPos){where}, "a constant mechc computes from this statement's "
                   "numbers%s %s; %s", name, what, advice);
    else
        diag_error_nopos(diag, "a constant mechc computes from the file's numbers%s %s; %s",
                         name, what, advice);
}

bool dag_check_finite(const Dag *dag, Diag *diag)
{
    if (!dag->nonfinite)
        return true;
    double v = dag->nonfinite_value;
    report(diag, dag->nonfinite_where, dag->nonfinite_expr, dag->nonfinite_what, isnan(v)
           ? "is NaN, not a number: a step of it overflowed past the largest double (about "
             "1.8e308) or underflowed to 0, as in inf - inf or 0/0"
           : v > 0 ? "is +inf: it overflows past the largest double (about 1.8e308)"
                   : "is -inf: it overflows past the largest double (about -1.8e308)",
           "write the numbers in other units, or nearer 1");
    return false;
}

bool dag_check_float(const Dag *dag, const NodeId *roots, int nroots, Diag *diag)
{
    if (dag->nwide == 0)
        return true;
    uint32_t *mark = xcalloc((size_t)dag->count, sizeof *mark);
    NodeId *stack = xmalloc((size_t)dag->count * sizeof *stack);
    dag_mark_reachable(dag, roots, nroots, mark, 1, stack);
    const DagWide *hit = NULL;
    for (int i = 0; i < dag->nwide && !hit; i++)
        if (mark[dag->wide[i].id] == 1)
            hit = &dag->wide[i];
    free(mark);
    free(stack);
    if (!hit)
        return true;
    double v = dag->nodes[hit->id].value;
    char num[40], what[200];
    mechrt_format_real(num, sizeof num, v, 0, false);
    snprintf(what, sizeof what, "is %s, which a float (--real float) cannot hold: it would "
             "become %s", num, isinf((float)v) ? (v > 0 ? "HUGE_VALF (about 3.4e38 is the largest "
             "float)" : "-HUGE_VALF (about -3.4e38 is the largest float)")
             : "0 (about 1.4e-45 is the smallest float)");
    report(diag, hit->where, hit->expr, hit->what, what,
           "use --real double, or write the numbers in other units");
    return false;
}
