/* integrability.c - is a velocity-level row a disguised position constraint? Frobenius, then the law.
 *
 * A velocity row Psi = a(q,t)^T qd + b(q,t) = 0 restricts the motion
 * (q(t), t) to curves annihilated by the 1-form on (q, t) space
 *     omega = sum_i a_i dq_i + b dt.
 * By Frobenius' theorem (one form: the classical condition of Jacobi and
 * Clebsch; e.g. Flanders, Differential Forms, 1963, 7.4; Neimark and
 * Fufaev, Dynamics of Nonholonomic Systems, 1972, I.1) the row is
 * integrable, i.e. mu omega = dh for some factor mu and function h, so that
 * the row is the position law h(q, t) = const in disguise, iff
 *     omega ^ d omega = 0,
 * whose components, for every triple i < j < k of (q, t) coordinates, are
 *     a_i (d_j a_k - d_k a_j) + a_j (d_k a_i - d_i a_k) + a_k (d_i a_j - d_j a_i).
 * Only the coordinates the row mentions matter (a coefficient that is zero
 * and constant contributes through its partners only), so the test runs
 * over those and t.
 *
 * The components are built as graph nodes from the symbolic partials; if
 * every one simplifies to the constant 0 that is a proof. Otherwise they
 * are sampled at random states: a component clearly away from zero proves
 * the row nonholonomic; all of them zero at every sample is numerical
 * evidence of integrability (the simplifier does not know every identity).
 *
 * The law: try mu = 1, then mu = 1/a_p for each non-constant coefficient,
 * and integrate mu omega coordinate by coordinate,
 *     h <- h + integral of (mu a_k - d_k h) d x_k,
 * with a small table of antiderivatives (polynomials, sin, cos, exp, sinh,
 * cosh and powers of a linear argument, anything constant in x_k); the
 * result is accepted when d_k h = mu a_k for every k (symbolically or at
 * every sample).
 */
#include "integrability.h"

#include "../base/arena.h"
#include "../base/rng.h"
#include "../base/strbuf.h"
#include "../dag/support.h"
#include "../diff/diff.h"
#include "../eval/interp.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
    SYMBOLIC_MAX_VARS = 40,     /* beyond this the triples are only sampled */
    NUMERIC_MAX_VARS = 300,     /* beyond this the test is not run */
    INTEGRATE_MAX_DEPTH = 64,
};

/* Relative size below which a sampled quantity counts as zero (rounding in
   computing it from evaluated partials is a few eps times its terms). */
static const double ZERO_RTOL = 1e-9;

/* q around the centre (spread grows with the coordinate's size), t in [-1, 1). */
static double sample_state(uint64_t *s, const double *center, int nq, double *q)
{
    for (int i = 0; i < nq; i++)
        q[i] = center[i] + rng_symmetric(s) * (0.5 + 0.25 * fabs(center[i]));
    return rng_symmetric(s);
}

/* ---- the form omega on (q, t) space ---- */

typedef struct Form {
    Model *m;
    Dag *dag;
    Differ df;
    SupportScan scan;
    int *buf;           /* nq + 1 scratch for support_collect */
    int nq;
    int nv;             /* variables involved */
    int *var;           /* their codes: 0..nq-1 coordinates, nq = t */
    NodeId *coef;       /* omega's coefficient of each */
    NodeId *d;          /* d[k*nv + l] = d coef[k] / d var[l] */
} Form;

static NodeId var_node(Form *f, int code)
{
    return code < f->nq ? dag_var(f->dag, code) : dag_time(f->dag);
}

static NodeId deriv(Form *f, NodeId e, int code)
{
    return code < f->nq ? diff_by_q(&f->df, e, code) : diff_by_t(&f->df, e);
}

/* Does e depend on variable code? */
static bool depends(Form *f, NodeId e, int code)
{
    if (code == f->nq)
        return support_collect(&f->scan, f->dag, e, OP_TIME, f->buf) > 0;
    int n = support_collect(&f->scan, f->dag, e, OP_VAR, f->buf);
    for (int i = 0; i < n; i++)
        if (f->buf[i] == code)
            return true;
    return false;
}

static void add_vars(Form *f, bool *used, NodeId e)
{
    int n = support_collect(&f->scan, f->dag, e, OP_VAR, f->buf);
    for (int i = 0; i < n; i++)
        used[f->buf[i]] = true;
    if (support_collect(&f->scan, f->dag, e, OP_TIME, f->buf) > 0)
        used[f->nq] = true;
}

/* ---- antiderivatives ---- */

/* u is linear in x: du/dx does not depend on x and is not 0. */
static bool linear_in(Form *f, NodeId u, int code, NodeId *slope)
{
    *slope = deriv(f, u, code);
    return !dag_is_zero(f->dag, *slope) && !depends(f, *slope, code);
}

/* Degree n when e is x multiplied by itself n times, else 0. */
static int monomial_degree(Form *f, NodeId e, NodeId x, int depth)
{
    if (e == x)
        return 1;
    const DagNode *n = dag_node(f->dag, e);
    if (n->op != OP_MUL || depth > 16)
        return 0;
    int da = monomial_degree(f, n->a, x, depth + 1), db = monomial_degree(f, n->b, x, depth + 1);
    return da && db ? da + db : 0;
}

/* An antiderivative of e in variable code, or DAG_NONE when the table has none. */
static NodeId integrate(Form *f, NodeId e, int code, int depth)
{
    Dag *d = f->dag;
    NodeId x = var_node(f, code), s;
    if (!depends(f, e, code))
        return dag_mul(d, e, x);
    if (depth > INTEGRATE_MAX_DEPTH)
        return DAG_NONE;
    const DagNode n = *dag_node(d, e);
    DagOp op = (DagOp)n.op;
    NodeId ra, rb;
    double c;
    int deg = monomial_degree(f, e, x, 0);
    if (deg > 0)        /* x^n -> x^(n+1) / (n+1) */
        return dag_div(d, dag_pow(d, x, dag_const(d, deg + 1)), dag_const(d, deg + 1));
    switch (op) {
    case OP_NEG:
        ra = integrate(f, n.a, code, depth + 1);
        return ra == DAG_NONE ? DAG_NONE : dag_neg(d, ra);
    case OP_ADD:
    case OP_SUB:
        ra = integrate(f, n.a, code, depth + 1);
        rb = ra == DAG_NONE ? DAG_NONE : integrate(f, n.b, code, depth + 1);
        if (rb == DAG_NONE)
            return DAG_NONE;
        return op == OP_ADD ? dag_add(d, ra, rb) : dag_sub(d, ra, rb);
    case OP_MUL:
        if (!depends(f, n.a, code)) {
            rb = integrate(f, n.b, code, depth + 1);
            return rb == DAG_NONE ? DAG_NONE : dag_mul(d, n.a, rb);
        }
        if (!depends(f, n.b, code)) {
            ra = integrate(f, n.a, code, depth + 1);
            return ra == DAG_NONE ? DAG_NONE : dag_mul(d, ra, n.b);
        }
        return DAG_NONE;
    case OP_DIV:
        if (!depends(f, n.b, code)) {
            ra = integrate(f, n.a, code, depth + 1);
            return ra == DAG_NONE ? DAG_NONE : dag_div(d, ra, n.b);
        }
        /* c / u, u linear: (c / u') log u */
        if (!depends(f, n.a, code) && linear_in(f, n.b, code, &s))
            return dag_mul(d, dag_div(d, n.a, s), dag_call(d, OP_LOG, n.b, DAG_NONE));
        return DAG_NONE;
    case OP_POW:
        /* u^c, u linear: u^(c+1) / ((c+1) u'), or log(u) / u' for c = -1 */
        if (dag_is_const(d, n.b, &c) && linear_in(f, n.a, code, &s)) {
            if (c == -1.0)
                return dag_div(d, dag_call(d, OP_LOG, n.a, DAG_NONE), s);
            NodeId c1 = dag_const(d, c + 1.0);
            return dag_div(d, dag_pow(d, n.a, c1), dag_mul(d, c1, s));
        }
        return DAG_NONE;
    case OP_SQRT:       /* sqrt(u) = u^(1/2): (2/3) u sqrt(u) / u' */
        if (linear_in(f, n.a, code, &s))
            return dag_div(d, dag_mul(d, dag_const(d, 2.0 / 3.0), dag_mul(d, n.a, e)), s);
        return DAG_NONE;
    case OP_SIN: case OP_COS: case OP_EXP: case OP_SINH: case OP_COSH: {
        if (!linear_in(f, n.a, code, &s))
            return DAG_NONE;
        NodeId r;
        switch (op) {
        case OP_SIN:  r = dag_neg(d, dag_call(d, OP_COS, n.a, DAG_NONE)); break;
        case OP_COS:  r = dag_call(d, OP_SIN, n.a, DAG_NONE); break;
        case OP_EXP:  r = e; break;
        case OP_SINH: r = dag_call(d, OP_COSH, n.a, DAG_NONE); break;
        default:      r = dag_call(d, OP_SINH, n.a, DAG_NONE); break;
        }
        return dag_div(d, r, s);
    }
    default:
        return DAG_NONE;
    }
}

/* a with one factor b of its product tree removed, or DAG_NONE. */
static NodeId cancel_factor(Dag *d, NodeId a, NodeId b, int depth)
{
    if (a == b)
        return DAG_ONE;
    const DagNode n = *dag_node(d, a);
    if (depth > 32)
        return DAG_NONE;
    if (n.op == OP_NEG) {
        NodeId x = cancel_factor(d, n.a, b, depth + 1);
        return x == DAG_NONE ? DAG_NONE : dag_neg(d, x);
    }
    if (n.op == OP_MUL) {
        NodeId x = cancel_factor(d, n.a, b, depth + 1);
        if (x != DAG_NONE)
            return dag_mul(d, x, n.b);
        x = cancel_factor(d, n.b, b, depth + 1);
        if (x != DAG_NONE)
            return dag_mul(d, n.a, x);
    }
    return DAG_NONE;
}

/* a / b, cancelling b (or its non-constant factors) when a is a product
   containing it, so that the integrating factor 1/a_p leaves integrable
   coefficients: (exp(x) y) / exp(x) = y. */
static NodeId divide(Dag *d, NodeId a, NodeId b)
{
    const DagNode nb = *dag_node(d, b);
    if (nb.op == OP_NEG)
        return dag_neg(d, divide(d, a, nb.a));
    if (nb.op == OP_MUL && dag_is_const(d, nb.a, NULL))
        return dag_div(d, divide(d, a, nb.b), nb.a);
    NodeId x = cancel_factor(d, a, b, 0);
    if (x != DAG_NONE)
        return x;
    if (nb.op == OP_MUL) {              /* b = b1 b2: cancel both in turn */
        NodeId y = cancel_factor(d, a, nb.a, 0);
        if (y != DAG_NONE && (x = cancel_factor(d, y, nb.b, 0)) != DAG_NONE)
            return x;
    }
    return dag_div(d, a, b);
}

/* ---- sampling ---- */

typedef struct Sampler {
    uint64_t state;
    const double *center;
    int nq;
    double *q;
} Sampler;

/* Evaluates the n roots of ev at one random state; false if any is not finite. */
static bool sample(Sampler *s, NodeValues *ev, int n, double *values)
{
    double t = sample_state(&s->state, s->center, s->nq, s->q);
    node_values_run(ev, s->q, NULL, t);
    for (int i = 0; i < n; i++) {
        values[i] = node_values_get(ev, i);
        if (!isfinite(values[i]))
            return false;
    }
    return true;
}

/* ---- the law ---- */

/* Tries mu omega = dh for one factor mu (DAG_NONE: mu = 1, else the index p
   of the coefficient to divide by). Returns h or DAG_NONE; *symbolic when
   d_k h = mu a_k simplified exactly. */
static NodeId try_law(Form *f, int p, Sampler *smp, int samples, bool *symbolic)
{
    Dag *d = f->dag;
    int nv = f->nv;
    NodeId *c = xmalloc((size_t)nv * sizeof *c);
    NodeId *check = xmalloc(2 * (size_t)nv * sizeof *check);
    double *val = xmalloc(2 * (size_t)nv * sizeof *val);
    NodeId h = DAG_ZERO;
    for (int k = 0; k < nv; k++)
        c[k] = p < 0 ? f->coef[k] : divide(d, f->coef[k], f->coef[p]);
    for (int k = 0; k < nv && h != DAG_NONE; k++) {
        NodeId rem = dag_sub(d, c[k], deriv(f, h, f->var[k]));
        if (dag_is_zero(d, rem))
            continue;
        NodeId part = integrate(f, rem, f->var[k], 0);
        h = part == DAG_NONE ? DAG_NONE : dag_add(d, h, part);
    }
    *symbolic = false;
    if (h == DAG_NONE || dag_is_const(d, h, NULL))
        goto fail;
    /* verify d_k h = c_k */
    bool exact = true;
    for (int k = 0; k < nv; k++) {
        check[2 * k] = deriv(f, h, f->var[k]);
        check[2 * k + 1] = c[k];
        if (dag_sub(d, check[2 * k], c[k]) != DAG_ZERO)
            exact = false;
    }
    if (exact) {
        *symbolic = true;
    } else {
        NodeValues ev;
        node_values_init(&ev, d, check, 2 * nv);
        int good = 0;
        bool bad = false;
        for (int s = 0; s < samples && !bad; s++) {
            if (!sample(smp, &ev, 2 * nv, val))
                continue;
            good++;
            for (int k = 0; k < nv; k++) {
                double x = val[2 * k], y = val[2 * k + 1];
                if (fabs(x - y) > 1e-8 * (fabs(x) + fabs(y)) + 1e-12)
                    bad = true;
            }
        }
        node_values_free(&ev);
        if (bad || good == 0)
            goto fail;
    }
    free(c), free(check), free(val);
    return h;
fail:
    free(c), free(check), free(val);
    return DAG_NONE;
}

static void find_law(Form *f, Sampler *smp, int samples, Integrability *out)
{
    Dag *d = f->dag;
    bool symbolic = false;
    NodeId h = try_law(f, -1, smp, samples, &symbolic);
    int factor = -1;
    for (int p = 0; p < f->nv && h == DAG_NONE && !d->overflow; p++) {
        if (dag_is_zero(d, f->coef[p]) || dag_is_const(d, f->coef[p], NULL))
            continue;
        h = try_law(f, p, smp, samples, &symbolic);
        factor = p;
    }
    StrBuf sb;
    sb_init(&sb);
    sb_puts(&sb, out->note);
    free(out->note);
    if (h == DAG_NONE) {
        sb_puts(&sb, "; law not found in closed form");
        out->note = sb_take(&sb);
        return;
    }
    char *text = dag_format_string(d, h, f->m->coord_names);
    size_t len = strlen(text);
    out->law = xmalloc(len + sizeof " = const");
    memcpy(out->law, text, len);
    memcpy(out->law + len, " = const", sizeof " = const");
    free(text);
    if (factor >= 0) {
        char *fac = dag_format_string(d, f->coef[factor], f->m->coord_names);
        sb_printf(&sb, "; law with the integrating factor 1/(%s)", fac);
        free(fac);
    }
    sb_printf(&sb, "; law checked %s", symbolic ? "symbolically" : "at the sample states");
    out->note = sb_take(&sb);
}

/* ---- the test ---- */

static const char *var_name(const Form *f, int code)
{
    return code < f->nq ? f->m->coord_names[code] : "t";
}

/* Component (i, j, k) of omega ^ d omega from coefficients a and partials
   da (da[k*nv + l] = d a_k / d x_l); *scale gets the sum of the terms' sizes. */
static double wedge(const double *a, const double *da, int nv, int i, int j, int k, double *scale)
{
#define D(r, c) da[(r) * nv + (c)]
    double t1 = a[i] * (D(k, j) - D(j, k));
    double t2 = a[j] * (D(i, k) - D(k, i));
    double t3 = a[k] * (D(j, i) - D(i, j));
    *scale = fabs(a[i]) * (fabs(D(k, j)) + fabs(D(j, k))) + fabs(a[j]) * (fabs(D(i, k)) + fabs(D(k, i)))
             + fabs(a[k]) * (fabs(D(j, i)) + fabs(D(i, j)));
#undef D
    return t1 + t2 + t3;
}

static NodeId wedge_node(Form *f, int i, int j, int k)
{
    Dag *g = f->dag;
    int nv = f->nv;
    NodeId *c = f->coef;
#define D(r, s) f->d[(r) * nv + (s)]
    NodeId t1 = dag_mul(g, c[i], dag_sub(g, D(k, j), D(j, k)));
    NodeId t2 = dag_mul(g, c[j], dag_sub(g, D(i, k), D(k, i)));
    NodeId t3 = dag_mul(g, c[k], dag_sub(g, D(j, i), D(i, j)));
#undef D
    return dag_add(g, dag_add(g, t1, t2), t3);
}

/* The partials d[k*nv + l] = d coef[k] / d var[l]. */
static void form_partials(Form *f)
{
    int nv = f->nv;
    f->d = xmalloc((size_t)nv * (size_t)nv * sizeof *f->d);
    for (int k = 0; k < nv; k++)
        for (int l = 0; l < nv; l++)
            f->d[k * nv + l] = deriv(f, f->coef[k], f->var[l]);
}

/* Components of omega ^ d omega that do not simplify to 0 (stops early
   past the node limit, which the caller reports). */
static long symbolic_nonzero(Form *f)
{
    int nv = f->nv;
    long nonzero = 0;
    for (int i = 0; i < nv && !f->dag->overflow; i++)
        for (int j = i + 1; j < nv; j++)
            for (int k = j + 1; k < nv; k++)
                if (!dag_is_zero(f->dag, wedge_node(f, i, j, k)))
                    nonzero++;
    return nonzero;
}

/* The largest component of omega ^ d omega over the samples, relative to
   the size of its terms. */
typedef struct WedgeSample {
    int good;               /* samples evaluated */
    double worst, value;    /* largest |w| / scale, and that w */
    int i, j, k;            /* its triple (indices into var) */
} WedgeSample;

static WedgeSample sample_wedges(Form *f, Sampler *smp, int samples)
{
    int nv = f->nv, nn = nv + nv * nv;
    WedgeSample ws = {.i = -1, .j = -1, .k = -1};
    NodeId *nodes = xmalloc((size_t)nn * sizeof *nodes);
    double *val = xmalloc((size_t)nn * sizeof *val);
    memcpy(nodes, f->coef, (size_t)nv * sizeof *nodes);
    memcpy(nodes + nv, f->d, (size_t)nv * (size_t)nv * sizeof *nodes);
    NodeValues ev;
    node_values_init(&ev, f->dag, nodes, nn);
    for (int s = 0; s < samples; s++) {
        if (!sample(smp, &ev, nn, val))
            continue;
        ws.good++;
        for (int i = 0; i < nv; i++)
            for (int j = i + 1; j < nv; j++)
                for (int k = j + 1; k < nv; k++) {
                    double scale, w = wedge(val, val + nv, nv, i, j, k, &scale);
                    double ratio = scale > 0 ? fabs(w) / scale : 0.0;
                    if (ratio > ws.worst) {
                        ws.worst = ratio;
                        ws.value = w;
                        ws.i = i, ws.j = j, ws.k = k;
                    }
                }
    }
    node_values_free(&ev);
    free(nodes);
    free(val);
    return ws;
}

/* Fills out for the form f (everything except the law). Past the node
   limit it leaves out->note unset: the caller reports the limit. */
static void test_form(Form *f, Sampler *smp, int samples, Integrability *out)
{
    int nv = f->nv;
    StrBuf sb;
    sb_init(&sb);
    out->ncoords = nv;
    long triples = nv < 3 ? 0 : (long)nv * (nv - 1) * (nv - 2) / 6;
    out->triples = (int)triples;
    if (nv < 3) {
        out->integrable = out->symbolic = out->decided = true;
        sb_printf(&sb, "omega involves %d coordinate%s (t counted): a 1-form in fewer than three "
                  "variables is always integrable", nv, nv == 1 ? "" : "s");
        out->note = sb_take(&sb);
        return;
    }
    if (nv > NUMERIC_MAX_VARS) {
        out->decided = false;
        sb_printf(&sb, "not tested: omega involves %d coordinates (limit %d)", nv, NUMERIC_MAX_VARS);
        out->note = sb_take(&sb);
        return;
    }
    form_partials(f);
    long nonzero = nv <= SYMBOLIC_MAX_VARS ? symbolic_nonzero(f) : -1;
    if (f->dag->overflow) {
        sb_free(&sb);
        return;
    }
    if (nonzero == 0) {
        out->integrable = out->symbolic = out->decided = true;
        sb_printf(&sb, "omega ^ d omega simplifies to 0 (%ld component%s over %d coordinates): "
                  "a symbolic proof", triples, triples == 1 ? "" : "s", nv);
        out->note = sb_take(&sb);
        return;
    }
    WedgeSample ws = sample_wedges(f, smp, samples);
    out->samples = ws.good;
    out->decided = ws.good > 0;
    out->integrable = ws.good > 0 && ws.worst <= ZERO_RTOL;
    if (ws.good == 0)
        sb_printf(&sb, "undecided: omega ^ d omega has nonzero terms and could not be evaluated at "
                  "any of %d sample states", samples);
    else if (!out->integrable)
        sb_printf(&sb, "omega ^ d omega != 0: its (%s, %s, %s) component is %.6g at a sample state "
                  "(nonholonomic)", var_name(f, f->var[ws.i]), var_name(f, f->var[ws.j]),
                  var_name(f, f->var[ws.k]), ws.value);
    else
        sb_printf(&sb, "omega ^ d omega vanishes at %d random states (%ld component%s over %d "
                  "coordinates; %s): numerical evidence", ws.good, triples, triples == 1 ? "" : "s",
                  nv, nonzero < 0 ? "too many to simplify" : "not simplified to 0 symbolically");
    out->note = sb_take(&sb);
}

/* omega's variables and coefficients: a_i = dPsi/dqd_i, b = Psi(qd = 0)
   for dt, and every variable a nonzero coefficient depends on. */
static void collect_form(Form *f, NodeId psi)
{
    int nq = f->nq;
    NodeId *a = xmalloc(((size_t)nq + 1) * sizeof *a);
    bool *used = xcalloc((size_t)nq + 1, sizeof *used);
    for (int i = 0; i < nq; i++)
        a[i] = DAG_ZERO;
    int ns = support_collect(&f->scan, f->dag, psi, OP_VARD, f->buf);
    int *s = xmalloc(((size_t)ns + 1) * sizeof *s);
    memcpy(s, f->buf, (size_t)ns * sizeof *s);
    for (int k = 0; k < ns; k++) {
        a[s[k]] = diff_by_qd(&f->df, psi, s[k]);
        if (!dag_is_zero(f->dag, a[s[k]]))
            used[s[k]] = true;
    }
    free(s);
    a[nq] = diff_without_velocities(&f->df, psi);   /* b, the dt coefficient */
    if (!dag_is_zero(f->dag, a[nq]))
        used[nq] = true;
    for (int i = 0; i <= nq; i++)
        if (!dag_is_zero(f->dag, a[i]))
            add_vars(f, used, a[i]);
    for (int i = 0; i <= nq; i++)
        if (used[i]) {
            f->var[f->nv] = i;
            f->coef[f->nv++] = a[i];
        }
    free(a), free(used);
}

bool integrability_analyse(Model *m, int row, const double *q_center,
                           const AnalysisOptions *opt, Integrability *out, Diag *diag)
{
    memset(out, 0, sizeof *out);
    Form f = {.m = m, .dag = &m->dag, .nq = m->nq};
    differ_init(&f.df, f.dag, m->nq);
    support_init(&f.scan);
    f.buf = xmalloc(((size_t)m->nq + 2) * sizeof *f.buf);
    f.var = xmalloc(((size_t)m->nq + 1) * sizeof *f.var);
    f.coef = xmalloc(((size_t)m->nq + 1) * sizeof *f.coef);
    Sampler smp = {.state = opt->seed ^ (0x51ed2701u * (uint64_t)(row + 1)), .center = q_center,
                   .nq = m->nq};
    smp.q = xmalloc((size_t)m->nq * sizeof *smp.q);

    collect_form(&f, m->rows[row].expr);
    if (!f.dag->overflow)
        test_form(&f, &smp, opt->samples, out);
    if (out->integrable && !f.dag->overflow)
        find_law(&f, &smp, opt->samples, out);
    bool ok = dag_check_limit(f.dag, diag);     /* the node limit, once for the whole test */

    free(smp.q);
    free(f.buf), free(f.var), free(f.coef), free(f.d);
    support_free(&f.scan);
    differ_free(&f.df);
    return ok;
}

void integrability_free(Integrability *it)
{
    free(it->law);
    free(it->note);
    memset(it, 0, sizeof *it);
}
