/* emit_lu.c - P_lu_factor and P_lu_solve: the Jacobian's LU unrolled for its sparsity pattern.
 *
 * A kinematic step factors the Jacobian of one pattern twice and solves
 * three times; a runtime LU over index lists spends most of its time on
 * the lists, and most of the entries of a linkage's Jacobian are
 * constants (the +-1 of a joint's position rows). With the pattern and
 * the constants known here, the elimination is done symbolically at
 * generation time (as KLU's and cs_lu's analyses do, but unrolled into
 * C): constants fold (a pivot of -1 is a negation, 1 - (-1)(1) is 2),
 * entries that are one graph node are loaded once, and only what varies
 * with q is left to run: a few dozen operations for a slider-crank.
 *
 * The pivot order is chosen from the pattern and the Jacobian's values at
 * the file's initial values q0 (Markowitz cost, among entries at least
 * half their column's largest; constants preferred), so it is a good
 * order near q0, not necessarily everywhere. The generated factor checks
 * at run time what makes it safe: every pivot at least LU_TAU times each
 * candidate below it (threshold partial pivoting, |l_ij| <= 1 / LU_TAU)
 * and above pivot_tol times the largest entry (the runtime's singularity
 * test), and every entry finite. When a check fails it returns nonzero
 * and the caller factors by the runtime's partial pivoting instead, so
 * results keep the runtime's robustness; where the checks pass they agree
 * with partial pivoting's to rounding.
 *
 * Interface (spec section 4 extension; firmware rules: C99, no heap):
 *   #define P_LU_NSLOTS  k        reals of the factors
 *   int  P_lu_factor(const P_real *a, P_real *lu, P_real pivot_tol, P_real *spread);
 *   void P_lu_solve(const P_real *lu, const P_real *b, P_real *x);
 *   int  P_step(P_real *q, P_real *qd, P_real *qdd, P_real t, P_real h,
 *               const P_real *tol, int max_iter, P_real *out, int *iout);
 * a: the P_NNZ values of P_jac_nz (read only); lu: P_LU_NSLOTS reals;
 * returns 0, or 1 + the elimination step whose check failed (-1: an
 * entry is NaN or infinite); *spread = max|u_kk| / min|u_kk| (the
 * condition estimate's screen). x may be b. P_step is the runtime's
 * kinematic step (runtime/step_lup.c) over these kernels and this LU, the
 * same operations in the same order, with the calls direct, the loops
 * unrolled and the factorisations and solves written in place: nonzero,
 * the state untouched, wherever the runtime must step instead.
 */
#include "emit_lu.h"

#include "../base/arena.h"
#include "../eval/interp.h"
#include "literal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Threshold of the run-time pivot check (UMFPACK's default; KLU's is
   1e-3): growth per step at most 1 + 1 / LU_TAU. */
#define LU_TAU 0.1
/* At generation time a pivot is taken among the entries at least this
   share of their column's largest at q0: the run-time check has room. */
#define LU_GEN_SHARE 0.5
/* Above these the runtime's pattern LU is used: the unrolled code would
   be large and the index lists cost little next to the arithmetic. */
enum { LU_MAX_N = 100, LU_MAX_OPS = 20000 };
/* P_step, whose factorisations and solves are written in place, is
   written up to this size: above it the function would take an
   optimising compiler several times as long as the kernels (the chain of
   10 loops, 63 coordinates: gcc -O2 1.3 s against 0.6 s without), for a
   step whose kernels outweigh the runtime's calls anyway. */
enum { LU_STEP_MAX_N = 24 };

/* A value of the elimination: a constant known here, or a temporary tN of
   the generated code, negated when neg. */
typedef struct LuVal {
    bool known;
    double c;
    int var;
    bool neg;
} LuVal;

typedef struct LuGen {
    int n;
    const EmitOptions *opt;
    const char *prefix, *upper;
    StrBuf *body;           /* the factor's statements */
    int ntemp;              /* temporaries tN written */
    long ops;               /* operations written */
    LuVal *a;               /* n*n: the active matrix, then L and U */
    double *num;            /* n*n: its values at q0 (the choice of pivots) */
    bool *present;          /* n*n: structurally nonzero (fill included) */
    int *slot;              /* per temporary: its slot in lu, -1 none */
    int nslots;
    int *prow, *pcol;       /* pivot k at (prow[k], pcol[k]) */
    bool *row_done, *col_done;
    bool inline_factors;    /* P_step: the solves read the factor's temporaries */
} LuGen;

static void lu_factor_text(LuGen *g, StrBuf *def, const StrBuf *loads, const StrBuf *steps,
                           double cmax, double cmin);

#define AT(g, r, c) ((size_t)(r) * (size_t)(g)->n + (size_t)(c))

static LuVal lu_const(double c)
{
    return (LuVal){true, c, -1, false};
}

static LuVal lu_negate(LuVal v)
{
    if (v.known)
        v.c = -v.c;
    else
        v.neg = !v.neg;
    return v;
}

static void lu_put_operand(LuGen *g, StrBuf *sb, LuVal v)
{
    if (v.known)
        emit_put_literal(sb, v.c, g->opt->real_float);
    else
        sb_printf(sb, "t%d", v.var);
}

/* A new temporary t = x op y (x, y without sign, or constants). */
static LuVal lu_temp(LuGen *g, LuVal x, const char *op, LuVal y, bool neg)
{
    int t = g->ntemp++;
    sb_printf(g->body, "    const %s_real t%d = ", g->prefix, t);
    lu_put_operand(g, g->body, x);
    sb_printf(g->body, " %s ", op);
    lu_put_operand(g, g->body, y);
    sb_puts(g->body, ";\n");
    g->ops++;
    return (LuVal){false, 0, t, neg};
}

static LuVal lu_abs_of(LuVal v)
{
    v.neg = false;
    if (v.known)
        v.c = fabs(v.c);
    return v;
}

static LuVal lu_mul(LuGen *g, LuVal x, LuVal y)
{
    if ((x.known && x.c == 0) || (y.known && y.c == 0))
        return lu_const(0);
    if (x.known && y.known)
        return lu_const(x.c * y.c);
    if (y.known) {
        LuVal s = x;
        x = y;
        y = s;
    }
    if (x.known) {   /* c * y */
        bool neg = (x.c < 0) != y.neg;
        if (fabs(x.c) == 1)
            return (LuVal){false, 0, y.var, neg};
        return lu_temp(g, lu_abs_of(x), "*", lu_abs_of(y), neg);
    }
    return lu_temp(g, lu_abs_of(x), "*", lu_abs_of(y), x.neg != y.neg);
}

static LuVal lu_div(LuGen *g, LuVal x, LuVal p)
{
    if (x.known && x.c == 0)
        return lu_const(0);
    if (x.known && p.known)
        return lu_const(x.c / p.c);
    if (p.known && fabs(p.c) == 1)
        return p.c < 0 ? lu_negate(x) : x;
    bool neg = (x.known ? x.c < 0 : x.neg) != (p.known ? p.c < 0 : p.neg);
    return lu_temp(g, lu_abs_of(x), "/", lu_abs_of(p), neg);
}

/* x - y */
static LuVal lu_sub(LuGen *g, LuVal x, LuVal y)
{
    if (y.known && y.c == 0)
        return x;
    if (x.known && x.c == 0)
        return lu_negate(y);
    if (x.known && y.known)
        return lu_const(x.c - y.c);
    if (x.known) {   /* c - (+-Y) */
        if (y.neg)
            return lu_temp(g, lu_abs_of(y), "+", x, false);
        return lu_temp(g, x, "-", y, false);
    }
    if (y.known) {   /* (+-X) - c */
        if (x.neg)
            return lu_temp(g, lu_abs_of(x), "+", y, true);
        return lu_temp(g, x, "-", y, false);
    }
    LuVal ax = lu_abs_of(x), ay = lu_abs_of(y);
    if (!x.neg && !y.neg)
        return lu_temp(g, ax, "-", ay, false);
    if (!x.neg && y.neg)
        return lu_temp(g, ax, "+", ay, false);
    if (x.neg && !y.neg)
        return lu_temp(g, ax, "+", ay, true);
    return lu_temp(g, ay, "-", ax, false);
}

/* The slot in lu of a temporary the solve reads (given on first need). */
static int lu_slot(LuGen *g, LuVal v)
{
    if (g->slot[v.var] < 0)
        g->slot[v.var] = g->nslots++;
    return g->slot[v.var];
}

/* Step k's pivot: among the active entries at least LU_GEN_SHARE of their
   column's largest at q0, the least Markowitz cost, then a constant, then
   the largest share; without one (a Jacobian singular at q0) the largest
   entry. False when no active entry is left (a structurally singular
   pattern). */
static bool lu_choose(const LuGen *g, int *pr, int *pc)
{
    int n = g->n, *rc = xcalloc((size_t)n, sizeof *rc), *cc = xcalloc((size_t)n, sizeof *cc);
    double *cmax = xcalloc((size_t)n, sizeof *cmax), best_share = -1, best_abs = -1;
    long best_cost = -1;
    bool best_const = false;
    for (int r = 0; r < n; r++)
        for (int c = 0; c < n; c++)
            if (!g->row_done[r] && !g->col_done[c] && g->present[AT(g, r, c)]) {
                rc[r]++;
                cc[c]++;
                cmax[c] = fmax(cmax[c], fabs(g->num[AT(g, r, c)]));
            }
    *pr = *pc = -1;
    for (int r = 0; r < n; r++)
        for (int c = 0; c < n; c++) {
            if (g->row_done[r] || g->col_done[c] || !g->present[AT(g, r, c)])
                continue;
            double v = fabs(g->num[AT(g, r, c)]);
            double share = cmax[c] > 0 ? v / cmax[c] : 0;
            if (!(share >= LU_GEN_SHARE))
                continue;
            long cost = (long)(rc[r] - 1) * (cc[c] - 1);
            bool cst = g->a[AT(g, r, c)].known;
            bool better = best_cost < 0 || cost < best_cost
                          || (cost == best_cost && cst && !best_const)
                          || (cost == best_cost && cst == best_const && share > best_share);
            if (better) {
                best_cost = cost;
                best_const = cst;
                best_share = share;
                *pr = r;
                *pc = c;
            }
        }
    for (int r = 0; *pr < 0 && r < n; r++)   /* singular at q0: the largest entry */
        for (int c = 0; c < n; c++)
            if (!g->row_done[r] && !g->col_done[c] && g->present[AT(g, r, c)]
                && fabs(g->num[AT(g, r, c)]) > best_abs) {
                best_abs = fabs(g->num[AT(g, r, c)]);
                *pr = r;
                *pc = c;
            }
    free(rc), free(cc), free(cmax);
    return *pr >= 0;
}

/* |v| in the generated code: a temporary's through P_LU_ABS. */
static void lu_put_abs(LuGen *g, StrBuf *sb, LuVal v)
{
    if (v.known) {
        emit_put_literal(sb, fabs(v.c), g->opt->real_float);
        return;
    }
    sb_printf(sb, "%s_LU_ABS(t%d)", g->upper, v.var);
}

/* The run-time checks of step k (pivot p, candidates of its column). */
static void lu_checks(LuGen *g, int k, LuVal p, const int *cand, int nc, double *cmin)
{
    int pc = g->pcol[k];
    StrBuf *b = g->body;
    bool any = false;
    if (p.known)
        *cmin = fmin(*cmin, fabs(p.c));
    else {
        sb_printf(b, "    ap = %s_LU_ABS(t%d);\n", g->upper, p.var);
        sb_puts(b, "    lo = ap < lo ? ap : lo;\n    hi = ap > hi ? ap : hi;\n");
        sb_puts(b, "    if (!(ap > thresh)");
        any = true;
        g->ops += 4;
    }
    for (int i = 0; i < nc; i++) {
        LuVal c = g->a[AT(g, cand[i], pc)];
        bool again = false;   /* one graph node in two rows: checked once */
        for (int j = 0; j < i; j++) {
            LuVal d = g->a[AT(g, cand[j], pc)];
            again |= !c.known && !d.known && c.var == d.var;
        }
        if ((c.known && p.known) || again)
            continue;   /* chosen here, and constant */
        sb_puts(b, any ? "\n        || !(" : "    if (!(");
        any = true;
        if (p.known) {
            lu_put_abs(g, b, c);
            sb_puts(b, " <= ");
            emit_put_literal(b, fabs(p.c) / LU_TAU, g->opt->real_float);
        } else {
            emit_put_literal(b, LU_TAU, g->opt->real_float);
            sb_puts(b, " * ");
            lu_put_abs(g, b, c);
            sb_puts(b, " <= ap");
        }
        sb_putc(b, ')');
        g->ops += 2;
    }
    if (any)
        sb_printf(b, ")\n        return %d;\n", k + 1);
}

/* One elimination step: pivot k, its checks, multipliers and updates. */
static void lu_step(LuGen *g, int k, double *cmin)
{
    int n = g->n, pr = g->prow[k], pc = g->pcol[k], nc = 0, *cand = xmalloc((size_t)n * sizeof *cand);
    LuVal p = g->a[AT(g, pr, pc)];
    double pn = g->num[AT(g, pr, pc)];
    for (int i = 0; i < n; i++)
        if (!g->row_done[i] && i != pr && g->present[AT(g, i, pc)])
            cand[nc++] = i;
    lu_checks(g, k, p, cand, nc, cmin);
    for (int c = 0; c < nc; c++) {
        int i = cand[c];
        LuVal l = lu_div(g, g->a[AT(g, i, pc)], p);
        double ln = pn != 0 ? g->num[AT(g, i, pc)] / pn : 0;
        g->a[AT(g, i, pc)] = l;
        g->num[AT(g, i, pc)] = ln;
        for (int j = 0; j < n; j++) {
            if (g->col_done[j] || j == pc || !g->present[AT(g, pr, j)])
                continue;
            if (!g->present[AT(g, i, j)]) {   /* fill */
                g->present[AT(g, i, j)] = true;
                g->a[AT(g, i, j)] = lu_const(0);
                g->num[AT(g, i, j)] = 0;
            }
            g->a[AT(g, i, j)] = lu_sub(g, g->a[AT(g, i, j)], lu_mul(g, l, g->a[AT(g, pr, j)]));
            g->num[AT(g, i, j)] -= ln * g->num[AT(g, pr, j)];
        }
    }
    g->row_done[pr] = g->col_done[pc] = true;
    free(cand);
}

/* lu[s] of a variable factor entry, or its constant; sign apart. */
static void lu_put_factor(LuGen *g, StrBuf *sb, LuVal v)
{
    if (v.known)
        emit_put_literal(sb, fabs(v.c), g->opt->real_float);
    else if (g->inline_factors)
        sb_printf(sb, "t%d", v.var);
    else
        sb_printf(sb, "lu[%d]", lu_slot(g, v));
}

static bool lu_is_negative(LuVal v)
{
    return v.known ? v.c < 0 : v.neg;
}

/* y_i -= f * y: the forward and backward substitutions' update. */
static void lu_put_update(LuGen *g, StrBuf *sb, const char *ind, const char *target, LuVal f,
                          const char *y)
{
    if (f.known && f.c == 0)
        return;
    sb_printf(sb, "%s%s %s= ", ind, target, lu_is_negative(f) ? "+" : "-");
    if (!(f.known && fabs(f.c) == 1)) {
        lu_put_factor(g, sb, f);
        sb_puts(sb, " * ");
    }
    sb_printf(sb, "%s;\n", y);
}

/* x = A^-1 b from the factors in lu: b read from the array in, L forward
   in the pivot order, U backward, into locals x0 .. x(n-1) (ind: the
   statements' indentation). */
static void lu_solve_text(LuGen *g, StrBuf *sb, const char *in, const char *ind)
{
    int n = g->n;
    char y[32], yr[32];
    bool *later = xcalloc((size_t)n, sizeof *later);
    for (int r = 0; r < n; r++)
        sb_printf(sb, "%s%s_real y%d = %s[%d];\n", ind, g->prefix, r, in, r);
    for (int k = 0; k < n; k++)
        later[g->prow[k]] = true;
    for (int k = 0; k < n; k++) {
        /* the rows eliminated after k hold L's entries in column pcol[k] */
        later[g->prow[k]] = false;
        snprintf(yr, sizeof yr, "y%d", g->prow[k]);
        for (int i = 0; i < n; i++)
            if (later[i] && g->present[AT(g, i, g->pcol[k])]) {
                snprintf(y, sizeof y, "y%d", i);
                lu_put_update(g, sb, ind, y, g->a[AT(g, i, g->pcol[k])], yr);
            }
    }
    free(later);
    for (int k = n - 1; k >= 0; k--) {
        int pr = g->prow[k], pc = g->pcol[k];
        snprintf(y, sizeof y, "x%d", pc);
        sb_printf(sb, "%s%s_real x%d = y%d;\n", ind, g->prefix, pc, pr);
        for (int m = k + 1; m < n; m++) {
            char xc[32];
            snprintf(xc, sizeof xc, "x%d", g->pcol[m]);
            if (g->present[AT(g, pr, g->pcol[m])])
                lu_put_update(g, sb, ind, y, g->a[AT(g, pr, g->pcol[m])], xc);
        }
        LuVal p = g->a[AT(g, pr, pc)];
        if (!(p.known && fabs(p.c) == 1)) {
            sb_printf(sb, "%sx%d /= ", ind, pc);
            lu_put_factor(g, sb, p);
            sb_puts(sb, ";\n");
        }
        if (lu_is_negative(p))
            sb_printf(sb, "%sx%d = -x%d;\n", ind, pc, pc);
    }
}

/* P_lu_solve's body. */
static void lu_solve_body(LuGen *g, StrBuf *sb)
{
    lu_solve_text(g, sb, "b", "    ");
    for (int c = 0; c < g->n; c++)
        sb_printf(sb, "    x[%d] = x%d;\n", c, c);
}

/* P_step (see the header's comment and runtime/step_lup.c, whose
   operations it repeats in the same order): the loops unrolled, the
   three solves written in place, so that their solutions stay in
   registers. */
static void lu_step_def(LuGen *g, StrBuf *def, const StrBuf *loads, const StrBuf *steps,
                        double cmax, double cmin)
{
    /* Finiteness by sums: fin adds the values checked and fin - fin is 0
       only when every one was finite (a sum that overflows declines a
       step the runtime then takes: safe, and never seen at sane scales). */
    const char *p = g->prefix, *u = g->upper;
    int n = g->n;
    sb_printf(def, "\nint %s_step(%s_real *q, %s_real *qd, %s_real *qdd, %s_real t, %s_real h,\n"
              "             const %s_real *tol, int max_iter, %s_real *out, int *iout)\n{\n",
              p, p, p, p, p, p, p, p);
    sb_printf(def, "    %s_real qq[%s_NQ], phi[%s_NQ], rhs[%s_NQ], v[%s_NQ], a[%s_NNZ];\n"
              "    %s_real res = 0, stp = -1, fin, m;\n    const %s_real pivot_tol = tol[2];\n"
              "    int it = 0, worst;\n\n", p, u, u, u, u, u, p, p);
    sb_printf(def, "    if (h != 0) {\n        const %s_real hh = (%s_real)0.5 * h * h;\n", p, p);
    for (int i = 0; i < n; i++)
        sb_printf(def, "        qq[%d] = q[%d] + (h * qd[%d] + hh * qdd[%d]);\n", i, i, i, i);
    sb_puts(def, "    } else {\n");
    for (int i = 0; i < n; i++)
        sb_printf(def, "        qq[%d] = q[%d];\n", i, i);
    sb_puts(def, "    }\n    t += h;\n    for (;;) {\n");
    sb_printf(def, "        %s_phi(qq, t, phi);\n        %s_jac_nz(qq, t, a);\n", p, p);
    /* the residual decides from the second evaluation on (before the
       first step the test fails anyway, and a value of Phi that is not
       finite makes the step's): max |Phi_i|, the row found afterwards */
    sb_puts(def, "        if (stp >= 0) {\n            res = 0;\n            fin = 0;\n");
    for (int i = 0; i < n; i++)
        sb_printf(def, "            m = %s_LU_ABS(phi[%d]);\n            fin += phi[%d];\n"
                  "            res = m > res ? m : res;\n", u, i, i);
    sb_puts(def, "            if (fin - fin != 0)\n                return 1;\n"
            "            if (res <= tol[0] && stp <= tol[1])\n                break;\n        }\n"
            "        if (it >= max_iter)\n            return 2;\n        {\n");
    lu_factor_text(g, def, loads, steps, cmax, cmin);
    sb_puts(def, "            if (!(hi / lo <= tol[3]))\n                return 2;\n"
            "            fin = 0;\n");
    lu_solve_text(g, def, "phi", "            ");
    sb_puts(def, "            stp = 0;\n");
    for (int i = 0; i < n; i++)
        sb_printf(def, "            m = %s_LU_ABS(x%d);\n            fin += x%d;\n"
                  "            stp = m > stp ? m : stp;\n", u, i, i);
    sb_puts(def, "            if (fin - fin != 0)\n                return 3;\n");
    for (int i = 0; i < n; i++)
        sb_printf(def, "            qq[%d] -= x%d;\n", i, i);
    sb_puts(def, "        }\n        it++;\n    }\n    {\n");
    lu_factor_text(g, def, loads, steps, cmax, cmin);
    sb_printf(def, "    if (!(hi / lo <= tol[3]))\n        return 2;\n    fin = 0;\n"
              "    %s_nu(qq, t, rhs);\n    {\n", p);
    lu_solve_text(g, def, "rhs", "        ");
    for (int i = 0; i < n; i++)
        sb_printf(def, "        v[%d] = x%d;\n        fin += x%d;\n", i, i, i);
    sb_printf(def, "    }\n    %s_gamma(qq, v, t, rhs);\n    {\n", p);
    lu_solve_text(g, def, "rhs", "        ");
    for (int i = 0; i < n; i++)
        sb_printf(def, "        fin += x%d;\n", i);
    sb_puts(def, "        if (fin - fin != 0)\n            return 3;\n");
    for (int i = 0; i < n; i++)
        sb_printf(def, "        q[%d] = qq[%d];\n        qd[%d] = v[%d];\n", i, i, i, i);
    for (int i = 0; i < n; i++)
        sb_printf(def, "        qdd[%d] = x%d;\n", i, i);
    /* the first row with the largest |Phi_i|, as the runtime reports it */
    sb_puts(def, "    }\n    }\n    for (worst = 0; worst < ");
    sb_printf(def, "%s_NQ - 1 && !(%s_LU_ABS(phi[worst]) == res); worst++)\n        ;\n", u, u);
    sb_puts(def, "    out[0] = res;\n    out[1] = stp;\n    iout[0] = it;\n"
            "    iout[1] = worst;\n    return 0;\n}\n");
}

/* The factor's loads: each distinct variable value of the Jacobian once
   (entries that are one graph node share it), its scale and finiteness. */
static double lu_loads(LuGen *g, const Kinematics *kin, NodeValues *nv)
{
    const Dag *dag = &kin->model->dag;
    double cmax = 0;
    int *first = xmalloc((size_t)kin->nnz * sizeof *first);
    for (int e = 0; e < kin->nnz; e++) {
        const JacEntry *j = &kin->jac[e];
        double v;
        size_t at = AT(g, j->row, j->col);
        g->present[at] = true;
        g->num[at] = node_values_get(nv, e);
        first[e] = e;
        for (int f = 0; f < e; f++)
            if (kin->jac[f].value == j->value) {
                first[e] = f;
                break;
            }
        if (dag_is_const(dag, j->value, &v)) {
            g->a[at] = lu_const(v);
            cmax = fmax(cmax, fabs(v));
        } else if (first[e] != e) {
            g->a[at] = g->a[AT(g, kin->jac[first[e]].row, kin->jac[first[e]].col)];
        } else {
            int t = g->ntemp++;
            g->a[at] = (LuVal){false, 0, t, false};
            sb_printf(g->body, "    const %s_real t%d = a[%d];\n", g->prefix, t, e);
            sb_printf(g->body, "    chk += t%d;\n    amax = %s_LU_ABS(t%d) > amax ? "
                      "%s_LU_ABS(t%d) : amax;\n", t, g->upper, t, g->upper, t);
            g->ops += 4;
        }
    }
    free(first);
    return cmax;
}

/* The elimination, symbolically: the factor's loads and steps into
   loads and steps; *cmax and *cmin the largest constant entry and the
   smallest constant pivot. False when the pattern is structurally
   singular or the code too long. */
static bool lu_eliminate(LuGen *g, const Kinematics *kin, StrBuf *loads, StrBuf *steps,
                         double *cmax, double *cmin)
{
    const Model *m = kin->model;
    NodeId *roots = xmalloc((size_t)kin->nnz * sizeof *roots);
    for (int e = 0; e < kin->nnz; e++)
        roots[e] = kin->jac[e].value;
    NodeValues nv;
    node_values_init(&nv, &m->dag, roots, kin->nnz);
    node_values_run(&nv, m->q0, NULL, 0);
    g->body = loads;
    *cmax = lu_loads(g, kin, &nv);
    *cmin = INFINITY;
    node_values_free(&nv);
    free(roots);
    g->body = steps;
    bool ok = true;
    for (int k = 0; k < g->n && ok && g->ops <= LU_MAX_OPS; k++) {
        ok = lu_choose(g, &g->prow[k], &g->pcol[k]);
        if (ok)
            lu_step(g, k, cmin);
    }
    return ok && g->ops <= LU_MAX_OPS;
}

/* P_lu_factor from the elimination's text, storing the temporaries the
   solve reads (their slots given by lu_solve_body). */
static void lu_factor_def(LuGen *g, StrBuf *def, const StrBuf *loads, const StrBuf *steps,
                          double cmax, double cmin)
{
    const char *p = g->prefix;
    sb_printf(def, "int %s_lu_factor(const %s_real *a, %s_real *lu, %s_real pivot_tol, "
              "%s_real *spread)\n{\n", p, p, p, p, p);
    lu_factor_text(g, def, loads, steps, cmax, cmin);
    for (int t = 0; t < g->ntemp; t++)
        if (g->slot[t] >= 0)
            sb_printf(def, "    lu[%d] = t%d;\n", g->slot[t], t);
    sb_puts(def, "    (void)lu;\n    *spread = hi / lo;\n    return 0;\n}\n");
}

/* The factor's statements (P_lu_factor's body, and P_step's in place):
   declarations, loads, the scale, the steps; nonzero returns where a
   check fails, lo and hi the pivots' extremes at the end. */
static void lu_factor_text(LuGen *g, StrBuf *def, const StrBuf *loads, const StrBuf *steps,
                           double cmax, double cmin)
{
    const char *p = g->prefix;
    bool f = g->opt->real_float, pivots = !isinf(cmin);
    sb_printf(def, "    %s_real chk = 0, amax = ", p);
    emit_put_literal(def, cmax, f);
    sb_puts(def, ", thresh, ap, lo, hi = ");
    emit_put_literal(def, pivots ? cmin : 0, f);
    sb_printf(def, ";\n    (void)a; (void)ap;\n%s", loads->data);
    /* chk sums the values: chk - chk is 0 only when all are finite (an
       overflowing sum declines a factorisation the runtime then does) */
    sb_puts(def, "    if (chk - chk != 0)\n        return -1;\n    thresh = pivot_tol * amax;\n");
    /* without constant pivots lo starts at amax: the spread is then an
       upper bound (a pivot above every entry is rare), the screen safe */
    sb_puts(def, "    lo = ");
    if (pivots)
        emit_put_literal(def, cmin, f);
    else
        sb_puts(def, "amax");
    sb_puts(def, ";\n");
    if (pivots) {
        sb_puts(def, "    if (!(");
        emit_put_literal(def, cmin, f);
        sb_puts(def, " > thresh))\n        return 1;\n");
    }
    sb_puts(def, steps->data);
}

static void lu_free(LuGen *g)
{
    free(g->a), free(g->num), free(g->present), free(g->slot), free(g->prow), free(g->pcol);
    free(g->row_done), free(g->col_done);
}

/* Why the mechanism gets no LU, into why (NULL: it qualifies). */
static bool lu_refused(const Kinematics *kin, char *why, size_t size)
{
    const Model *m = kin->model;
    if (m->nv != 0)
        snprintf(why, size, "the mechanism has %d velocity-level rows", m->nv);
    else if (m->nh != m->nq)
        snprintf(why, size, "the Jacobian is not square (%d rows, %d coordinates)", m->nh, m->nq);
    else if (m->nq > LU_MAX_N)
        snprintf(why, size, "%d coordinates, more than %d", m->nq, LU_MAX_N);
    else if (m->nq < 1 || kin->nnz < 1)
        snprintf(why, size, "the Jacobian has no nonzero entries");
    else if (m->np > 0)     /* PREFIX_step's signature has no p */
        snprintf(why, size, "the mechanism has design parameters");
    else
        return false;
    return true;
}

/* The interface's part: P_lu_factor, P_lu_solve and P_step declared,
   P_LU_NSLOTS defined. */
static void lu_declarations(StrBuf *decl, const char *prefix, const char *upper, int slots)
{
    sb_printf(decl, "/* The Jacobian's LU for its pattern (an extension of spec section 4):\n"
              "   %s_lu_factor factors the %s_NNZ values a of %s_jac_nz into lu\n"
              "   (%s_LU_NSLOTS reals) in a pivot order chosen when the file was\n"
              "   written; it returns 0, or nonzero when a pivot is below %g times\n"
              "   a candidate of its column or pivot_tol times the largest entry\n"
              "   (-1: an entry is not finite): then factor with partial pivoting\n"
              "   instead. *spread = max|u_kk| / min|u_kk|. %s_lu_solve: x = A^-1 b\n"
              "   (x may be b). */\n#define %s_LU_NSLOTS %d\n",
              prefix, upper, prefix, upper, LU_TAU, prefix, upper, slots);
    sb_printf(decl, "int %s_lu_factor(const %s_real *a, %s_real *lu, %s_real pivot_tol, "
              "%s_real *spread);\n", prefix, prefix, prefix, prefix, prefix);
    sb_printf(decl, "void %s_lu_solve(const %s_real *lu, const %s_real *b, %s_real *x);\n",
              prefix, prefix, prefix, prefix);
    sb_printf(decl, "/* One kinematic step over these kernels and this LU (the runtime's\n"
              "   mechrt_step_lup with every call direct): 0, or nonzero with the state\n"
              "   untouched when the runtime must take the step itself. tol: tol_phi,\n"
              "   tol_dq, pivot_tol, the largest pivot spread; out: ||Phi||_inf, the\n"
              "   last ||dq||_inf; iout: iterations, worst row. */\n"
              "int %s_step(%s_real *q, %s_real *qd, %s_real *qdd, %s_real t, %s_real h,\n"
              "            const %s_real *tol, int max_iter, %s_real *out, int *iout);\n",
              prefix, prefix, prefix, prefix, prefix, prefix, prefix, prefix);
}

/* Declarations (decl) and definitions (def) appended for the mechanism,
   when it is square without velocity rows and small enough. */
void emit_lu(const Kinematics *kin, const EmitOptions *opt, const char *prefix,
             const char *upper, StrBuf *decl, StrBuf *def, char *why, size_t why_size)
{
    const Model *m = kin->model;
    int n = m->nq;
    why[0] = '\0';
    if (!opt->lu || lu_refused(kin, why, why_size))
        return;
    size_t nn = (size_t)n * (size_t)n, ntemp = (size_t)kin->nnz + LU_MAX_OPS + 64;
    LuGen g = {.n = n, .opt = opt, .prefix = prefix, .upper = upper};
    g.a = xcalloc(nn, sizeof *g.a);
    g.num = xcalloc(nn, sizeof *g.num);
    g.present = xcalloc(nn, sizeof *g.present);
    g.slot = xmalloc(ntemp * sizeof *g.slot);
    for (size_t i = 0; i < ntemp; i++)
        g.slot[i] = -1;
    g.prow = xcalloc((size_t)n, sizeof *g.prow);
    g.pcol = xcalloc((size_t)n, sizeof *g.pcol);
    g.row_done = xcalloc((size_t)n, sizeof *g.row_done);
    g.col_done = xcalloc((size_t)n, sizeof *g.col_done);
    StrBuf loads, steps, solve;
    StrBuf *bufs[] = {&loads, &steps, &solve};
    for (int i = 0; i < 3; i++) {
        sb_init(bufs[i]);
        sb_puts(bufs[i], "");
    }
    double cmax, cmin;
    if (lu_eliminate(&g, kin, &loads, &steps, &cmax, &cmin)) {
        lu_solve_body(&g, &solve);
        lu_declarations(decl, prefix, upper, g.nslots > 0 ? g.nslots : 1);
        sb_printf(def, "\n\n/* ---- begin lu ---- */\n/* |x|: one instruction where "
                  "optimising, no libm call elsewhere */\n#if %s_OPTIMIZED\n"
                  "#define %s_LU_ABS(x) %s(x)\n#else\n"
                  "#define %s_LU_ABS(x) ((x) < 0 ? -(x) : (x))\n#endif\n\n",
                  upper, upper, opt->real_float ? "fabsf" : "fabs", upper);
        lu_factor_def(&g, def, &loads, &steps, cmax, cmin);
        sb_printf(def, "\nvoid %s_lu_solve(const %s_real *lu, const %s_real *b, %s_real *x)\n"
                  "{\n    (void)lu;\n%s}\n", prefix, prefix, prefix, prefix, solve.data);
        g.inline_factors = true;
        if (n <= LU_STEP_MAX_N)
            lu_step_def(&g, def, &loads, &steps, cmax, cmin);
        else   /* the interface stays whole: every step is the runtime's */
            sb_printf(def, "\nint %s_step(%s_real *q, %s_real *qd, %s_real *qdd, %s_real t, "
                      "%s_real h,\n             const %s_real *tol, int max_iter, %s_real *out, "
                      "int *iout)\n{\n    (void)q; (void)qd; (void)qdd; (void)t; (void)h; "
                      "(void)tol;\n    (void)max_iter; (void)out; (void)iout;\n"
                      "    return 1;   /* past %d coordinates: see the runtime's step */\n}\n",
                      prefix, prefix, prefix, prefix, prefix, prefix, prefix, prefix,
                      LU_STEP_MAX_N);
        sb_puts(def, "/* ---- end lu ---- */");
    } else if (g.ops > LU_MAX_OPS) {
        snprintf(why, why_size, "the elimination needs more than %d operations", LU_MAX_OPS);
    } else {
        snprintf(why, why_size, "the Jacobian's pattern is structurally singular");
    }
    for (int i = 0; i < 3; i++)
        sb_free(bufs[i]);
    lu_free(&g);
}
