/* test_kinematics.c - every joint's rows through the whole pipeline and the JIT, against textbook formulas.
 *
 * Each test loads a small mechanism from text (pipeline_load_text), compiles
 * its kernels with libtcc (engine_jit) and evaluates Phi, Phi_q, nu and
 * gamma at a high-entropy state. The expected values are written here by
 * hand from the planar multibody formulas (Haug, Computer-Aided Kinematics
 * and Dynamics of Mechanical Systems, ch. 3; Nikravesh, ch. 4):
 *
 *   P = r + A(phi) s,  A = [[c, -s], [s, c]],  B = dA/dphi = [[-s, -c], [c, -s]]
 *   dP/dq = [I, B s],  dP/dt = rd + B s phid,
 *   d2P/dt2 = rdd + B s phidd - A s phid^2   (the last term goes to gamma)
 *   gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt   (position rows)
 *   gamma = -(Psi_q qd + Psi_t)                       (velocity rows)
 *
 * and compared at 1e-12 relative. Every mechanism also goes through the
 * generic checks: sparse against dense Jacobian, the fused _all against the
 * four separate kernels bit for bit, and every output entry written.
 */
#include "testutil.h"

#include "../generator/base/diag.h"
#include "../generator/base/limits.h"
#include "../generator/engine/engine.h"
#include "../generator/pipeline/pipeline.h"

#include <stdlib.h>
#include <string.h>

enum { MAXQ = 24, MAXR = 26 };

#define RTOL 1e-12
#define ATOL 1e-13

/* ---- loading and evaluating ---- */

typedef struct Loaded {
    Diag diag;              /* must outlive mech */
    Mech *mech;
    Jit *jit;
    EmitResult emitted;
    const Kernels *k;
    int nq, nh, nv, nr, nnz;
} Loaded;

typedef struct Eval {
    double phi[MAXR], jac[MAXR * MAXQ], nu[MAXR], gamma[MAXR], vals[MAXR * MAXQ];
} Eval;

static Loaded *load(const char *text)
{
    Loaded *L = calloc(1, sizeof *L);
    MechLimits limits = mech_default_limits();
    L->mech = pipeline_load_text(text, "test.mech", &limits, &L->diag);
    if (!L->mech) {
        diag_print(&L->diag, stderr);
        fail_msg("the test mechanism did not load:\n%s", text);
    }
    L->jit = engine_jit(L->mech, &L->emitted, NULL, NULL, &L->diag);
    if (!L->jit) {
        diag_print(&L->diag, stderr);
        fail_msg("the JIT failed");
    }
    L->k = jit_kernels(L->jit);
    const Model *m = L->mech->model;
    L->nq = m->nq;
    L->nh = m->nh;
    L->nv = m->nv;
    L->nr = m->nr;
    L->nnz = L->mech->kin.nnz;
    assert_true(L->nq <= MAXQ && L->nr <= MAXR);
    return L;
}

static void unload(Loaded *L)
{
    jit_free(L->jit);
    emit_result_free(&L->emitted);
    pipeline_free(L->mech);
    free(L);
}

/* A state that hides nothing: no zeros, ones or right angles. */
static const double Q[MAXQ] = {
    0.7371, 0.4123, 1.1391, 1.5347, -0.2861, -0.6143, 0.9127, 2.1089,
    -1.3171, 0.3319, 0.5813, -0.2749, 1.0637, -0.8821, 0.1543, 0.6607,
    -0.4411, 1.7213, 0.2297, -1.0913, 0.8389, 0.0731, -0.3467, 1.2953,
};
static const double QD[MAXQ] = {
    0.5813, -0.2749, 1.3171, -0.7433, 0.9127, 2.1089, -0.6607, 0.3319,
    1.0637, -1.2211, 0.4411, 0.8821, -0.1543, 0.7213, -0.9913, 0.2297,
    0.6389, -0.5731, 1.4467, 0.0953, -0.8123, 0.3371, 0.1249, -1.1767,
};
static const double T = 0.3217;

/* Evaluates the four kernels separately, after filling every output with
   garbage so that an entry the kernel forgets to write is noticed. */
static void evaluate(const Loaded *L, const double *q, const double *qd, double t, Eval *e)
{
    for (size_t i = 0; i < sizeof e->jac / sizeof *e->jac; i++)
        e->jac[i] = e->vals[i] = 12345.678;
    for (int i = 0; i < MAXR; i++)
        e->phi[i] = e->nu[i] = e->gamma[i] = 12345.678;
    L->k->phi(q, t, e->phi);
    L->k->jac(q, t, e->jac);
    L->k->nu(q, t, e->nu);
    L->k->gamma(q, qd, t, e->gamma);
    L->k->jac_nz(q, t, e->vals);
}

/* The generic checks every mechanism gets: sparse pattern and values,
   the fused kernel, and nothing written past the outputs. */
static void check_consistency(const Loaded *L, const double *q, const double *qd, double t)
{
    Eval e, f;
    evaluate(L, q, qd, t, &e);
    int nq = L->nq;
    const Kinematics *kin = &L->mech->kin;
    /* outputs end where they should */
    for (int i = L->nh; i < MAXR; i++)
        assert_true(e.phi[i] == 12345.678);
    for (int i = L->nr; i < MAXR; i++)
        assert_true(e.nu[i] == 12345.678 && e.gamma[i] == 12345.678);
    assert_true(e.jac[L->nr * nq] == 12345.678);
    /* sparse: the pattern is the model's, row-major, columns ascending,
       and each value is the dense entry; every other dense entry is 0 */
    bool structural[MAXR * MAXQ] = {false};
    for (int k = 0; k < L->nnz; k++) {
        int r = L->k->jac_row[k], c = L->k->jac_col[k];
        assert_int_equal(r, kin->jac[k].row);
        assert_int_equal(c, kin->jac[k].col);
        assert_true(r >= 0 && r < L->nr && c >= 0 && c < nq);
        assert_true(k >= kin->row_start[r] && k < kin->row_start[r + 1]);
        if (k > 0) {
            int pr = L->k->jac_row[k - 1], pc = L->k->jac_col[k - 1];
            assert_true(pr < r || (pr == r && pc < c));
        }
        assert_memory_equal(&e.vals[k], &e.jac[r * nq + c], sizeof(double));
        structural[r * nq + c] = true;
    }
    for (int i = 0; i < L->nr * nq; i++)
        if (!structural[i] && e.jac[i] != 0.0)
            fail_msg("jac[%d] = %.17g is not a structural nonzero but is not 0", i, e.jac[i]);
    /* the fused kernel: the same bits */
    for (size_t i = 0; i < sizeof f.jac / sizeof *f.jac; i++)
        f.jac[i] = -777.0;
    L->k->all(q, qd, t, f.phi, f.jac, f.nu, f.gamma);
    assert_memory_equal(f.phi, e.phi, (size_t)L->nh * sizeof(double));
    assert_memory_equal(f.jac, e.jac, (size_t)(L->nr * nq) * sizeof(double));
    assert_memory_equal(f.nu, e.nu, (size_t)L->nr * sizeof(double));
    assert_memory_equal(f.gamma, e.gamma, (size_t)L->nr * sizeof(double));
}

/* One row's expected values; jac is the full dense row. */
typedef struct Want {
    double phi, jac[MAXQ], nu, gamma;
} Want;

static void check_row(const Loaded *L, const Eval *e, int r, const Want *want, const char *name)
{
    const Want *w = want;
    const Model *m = L->mech->model;
    assert_true(r < L->nr);
    if (strcmp(m->rows[r].name, name) != 0)
        fail_msg("row %d is '%s', expected '%s'", r, m->rows[r].name, name);
    if (r < L->nh && !(fabs(e->phi[r] - w->phi) <= ATOL + RTOL * fabs(w->phi)))
        fail_msg("%s: phi = %.17g, expected %.17g", name, e->phi[r], w->phi);
    for (int c = 0; c < L->nq; c++) {
        double got = e->jac[r * L->nq + c];
        if (!(fabs(got - w->jac[c]) <= ATOL + RTOL * fabs(w->jac[c])))
            fail_msg("%s: jac[%s] = %.17g, expected %.17g", name, m->coord_names[c], got, w->jac[c]);
    }
    if (!(fabs(e->nu[r] - w->nu) <= ATOL + RTOL * fabs(w->nu)))
        fail_msg("%s: nu = %.17g, expected %.17g", name, e->nu[r], w->nu);
    if (!(fabs(e->gamma[r] - w->gamma) <= ATOL + RTOL * fabs(w->gamma)))
        fail_msg("%s: gamma = %.17g, expected %.17g", name, e->gamma[r], w->gamma);
}

/* ---- planar formulas ---- */

typedef struct V2 {
    double x, y;
} V2;

static V2 v2(double x, double y) { return (V2){x, y}; }
static V2 add(V2 a, V2 b) { return v2(a.x + b.x, a.y + b.y); }
static V2 sub(V2 a, V2 b) { return v2(a.x - b.x, a.y - b.y); }
static V2 scl(double k, V2 a) { return v2(k * a.x, k * a.y); }
static double dot(V2 a, V2 b) { return a.x * b.x + a.y * b.y; }
/* A(phi) s */
static V2 rotA(double phi, V2 s) { return v2(cos(phi) * s.x - sin(phi) * s.y, sin(phi) * s.x + cos(phi) * s.y); }
/* B(phi) s = dA/dphi s */
static V2 rotB(double phi, V2 s) { return v2(-sin(phi) * s.x - cos(phi) * s.y, cos(phi) * s.x - sin(phi) * s.y); }

/* An attachment as the test sees it: q < 0 is ground (s global), else
   coordinates q, q+1 and, for a body, phi = q+2. */
typedef struct Att {
    int q;
    bool body;
    V2 s;
} Att;

static Att ground(double x, double y) { return (Att){-1, false, v2(x, y)}; }
static Att body(int q, double sx, double sy) { return (Att){q, true, v2(sx, sy)}; }
static Att point(int q) { return (Att){q, false, v2(0, 0)}; }

static double phi_of(Att a, const double *q) { return a.body ? q[a.q + 2] : 0.0; }
static double phid_of(Att a, const double *qd) { return a.body ? qd[a.q + 2] : 0.0; }

/* P = r + A s */
static V2 pos(Att a, const double *q)
{
    if (a.q < 0)
        return a.s;
    V2 r = v2(q[a.q], q[a.q + 1]);
    return a.body ? add(r, rotA(q[a.q + 2], a.s)) : r;
}

/* dP/dt = rd + B s phid */
static V2 vel(Att a, const double *q, const double *qd)
{
    if (a.q < 0)
        return v2(0, 0);
    V2 v = v2(qd[a.q], qd[a.q + 1]);
    return a.body ? add(v, scl(qd[a.q + 2], rotB(q[a.q + 2], a.s))) : v;
}

/* d2P/dt2 without the qdd terms: -A s phid^2 */
static V2 acc_rest(Att a, const double *q, const double *qd)
{
    if (!a.body)
        return v2(0, 0);
    return scl(-qd[a.q + 2] * qd[a.q + 2], rotA(q[a.q + 2], a.s));
}

/* Adds k * (w . dP/dq) to a Jacobian row: w . [I, B s]. */
static void add_jac(double *row, double k, V2 w, Att a, const double *q)
{
    if (a.q < 0)
        return;
    row[a.q] += k * w.x;
    row[a.q + 1] += k * w.y;
    if (a.body)
        row[a.q + 2] += k * dot(w, rotB(q[a.q + 2], a.s));
}

/* The normal row n_A . (P_B - P_A), n_A = A(phi_A) (-uy, ux) (prismatic
   J.n and pointline), with its Jacobian and gamma:
     Phi_q: drA -n, dphiA (B n0).d - n.(B sA), drB n, dphiB n.(B sB)
     d2/dt2 (n.d) = n''.d + 2 n'.d' + n.d'',
     n' = B n0 phidA, n'' -> -n phidA^2, d'' -> -A sB phidB^2 + A sA phidA^2 */
static Want normal_row(Att a, Att b, double ux, double uy, const double *q, const double *qd)
{
    Want w = {0};
    V2 n0 = v2(-uy, ux);
    double pa = phi_of(a, q), wa = phid_of(a, qd);
    V2 n = a.body ? rotA(pa, n0) : n0;
    V2 nd = a.body ? scl(wa, rotB(pa, n0)) : v2(0, 0);
    V2 d = sub(pos(b, q), pos(a, q));
    V2 dd = sub(vel(b, q, qd), vel(a, q, qd));
    V2 ddd = sub(acc_rest(b, q, qd), acc_rest(a, q, qd));
    w.phi = dot(n, d);
    add_jac(w.jac, 1.0, n, b, q);
    add_jac(w.jac, -1.0, n, a, q);
    if (a.body)
        w.jac[a.q + 2] += dot(rotB(pa, n0), d);
    w.nu = 0.0;
    w.gamma = -(-dot(n, d) * wa * wa + 2.0 * dot(nd, dd) + dot(n, ddd));
    return w;
}

/* ---- revolute ---- */

static const char revolute_text[] =
    "body a x = 0.3 y = 0.1 phi = 0.2\n"
    "body b x = 1 y = 0.2 phi = 0.4\n"
    "point m x = 1.5 y = 0.4\n"
    "revolute O: ground(0.15, -0.35) a(-0.45, 0.125)\n"
    "revolute J: a(0.55, -0.0625) b(-0.3, 0.2)\n"
    "revolute K: b(0.25, 0.1) m\n";

static void test_revolute(void **state)
{
    (void)state;
    Loaded *L = load(revolute_text);
    assert_int_equal(L->nq, 8);
    assert_int_equal(L->nr, 6);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    const double *q = Q, *qd = QD;
    /* body a: q0..2, body b: q3..5, point m: q6, q7 */
    double pa = q[2], pb = q[5], wa = qd[2], wb = qd[5];
    V2 ra = v2(q[0], q[1]), rb = v2(q[3], q[4]), rm = v2(q[6], q[7]);

    /* O: ground g to body a: Phi = g - ra - A(pa) s;
       Jacobian [-I, -B(pa) s]; gamma = -A(pa) s wa^2 */
    V2 g = v2(0.15, -0.35), s = v2(-0.45, 0.125);
    V2 phi = sub(sub(g, ra), rotA(pa, s)), Bs = rotB(pa, s), As = rotA(pa, s);
    Want ox = {.phi = phi.x, .jac = {-1, 0, -Bs.x}, .nu = 0, .gamma = -As.x * wa * wa};
    Want oy = {.phi = phi.y, .jac = {0, -1, -Bs.y}, .nu = 0, .gamma = -As.y * wa * wa};
    check_row(L, &e, 0, &ox, "O.x");
    check_row(L, &e, 1, &oy, "O.y");

    /* J: body a to body b: Phi = ra + A(pa) sa - rb - A(pb) sb;
       Jacobian [I, B(pa) sa, -I, -B(pb) sb];
       gamma = A(pa) sa wa^2 - A(pb) sb wb^2 */
    V2 sa = v2(0.55, -0.0625), sb = v2(-0.3, 0.2);
    phi = sub(add(ra, rotA(pa, sa)), add(rb, rotA(pb, sb)));
    V2 Bsa = rotB(pa, sa), Bsb = rotB(pb, sb);
    V2 gam = sub(scl(wa * wa, rotA(pa, sa)), scl(wb * wb, rotA(pb, sb)));
    Want jx = {.phi = phi.x, .jac = {1, 0, Bsa.x, -1, 0, -Bsb.x}, .nu = 0, .gamma = gam.x};
    Want jy = {.phi = phi.y, .jac = {0, 1, Bsa.y, 0, -1, -Bsb.y}, .nu = 0, .gamma = gam.y};
    check_row(L, &e, 2, &jx, "J.x");
    check_row(L, &e, 3, &jy, "J.y");

    /* K: body b to point m: Phi = rb + A(pb) s - rm; gamma = A(pb) s wb^2 */
    s = v2(0.25, 0.1);
    phi = sub(add(rb, rotA(pb, s)), rm);
    Bs = rotB(pb, s);
    As = rotA(pb, s);
    Want kx = {.phi = phi.x, .jac = {0, 0, 0, 1, 0, Bs.x, -1, 0}, .nu = 0, .gamma = As.x * wb * wb};
    Want ky = {.phi = phi.y, .jac = {0, 0, 0, 0, 1, Bs.y, 0, -1}, .nu = 0, .gamma = As.y * wb * wb};
    check_row(L, &e, 4, &kx, "K.x");
    check_row(L, &e, 5, &ky, "K.y");
    /* time plays no part: another t, the same values */
    Eval e2;
    evaluate(L, Q, QD, 2.9, &e2);
    assert_memory_equal(e2.phi, e.phi, 6 * sizeof(double));
    assert_memory_equal(e2.gamma, e.gamma, 6 * sizeof(double));
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- prismatic ---- */

static void test_prismatic(void **state)
{
    (void)state;
    Loaded *L = load("body a x = 0.3 y = 0.1 phi = 0.2\n"
                     "body b x = 1 y = 0.2 phi = 0.4\n"
                     "prismatic P: ground(0.2, -0.1) a(0.15, 0.05) axis(0.8, 0.6)\n"
                     "prismatic Q: a(0.3, -0.2) b(-0.1, 0.25) axis(1.5, -0.5) angle = pi/6\n");
    assert_int_equal(L->nr, 4);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    /* without angle, ground to body: P.n = n0 . (P_a - g), P.phi = phi_a */
    Want w = normal_row(ground(0.2, -0.1), body(0, 0.15, 0.05), 0.8, 0.6, Q, QD);
    /* by hand once more for the simplest case: n0 = (-0.6, 0.8) */
    V2 pa = add(v2(Q[0], Q[1]), rotA(Q[2], v2(0.15, 0.05)));
    assert_near(w.phi, -0.6 * (pa.x - 0.2) + 0.8 * (pa.y + 0.1), 1e-15, 1e-16);
    check_row(L, &e, 0, &w, "P.n");
    Want pphi = {.phi = Q[2], .jac = {0, 0, 1}, .nu = 0, .gamma = 0};
    check_row(L, &e, 1, &pphi, "P.phi");
    /* with angle, body to body: Q.n = n_a . (P_b - P_a),
       Q.phi = phi_b - phi_a - pi/6 */
    w = normal_row(body(0, 0.3, -0.2), body(3, -0.1, 0.25), 1.5, -0.5, Q, QD);
    check_row(L, &e, 2, &w, "Q.n");
    Want qphi = {.phi = Q[5] - Q[2] - M_PI / 6, .jac = {0, 0, -1, 0, 0, 1}, .nu = 0, .gamma = 0};
    check_row(L, &e, 3, &qphi, "Q.phi");
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- distance ---- */

/* Phi = d.d - L^2, d = P_B - P_A;
   Phi_q = 2 d . (dP_B/dq - dP_A/dq); nu = -Phi_t = 2 L L';
   gamma = -(2 d'.d' + 2 d.d''_rest) + 2 (L'^2 + L L'') */
static Want distance_row(Att a, Att b, double len, double dlen, double ddlen,
                        const double *q, const double *qd)
{
    Want w = {0};
    V2 d = sub(pos(b, q), pos(a, q));
    V2 dd = sub(vel(b, q, qd), vel(a, q, qd));
    V2 ddd = sub(acc_rest(b, q, qd), acc_rest(a, q, qd));
    w.phi = dot(d, d) - len * len;
    add_jac(w.jac, 2.0, d, b, q);
    add_jac(w.jac, -2.0, d, a, q);
    w.nu = 2.0 * len * dlen;
    w.gamma = -(2.0 * dot(dd, dd) + 2.0 * dot(d, ddd)) + 2.0 * (dlen * dlen + len * ddlen);
    return w;
}

static void test_distance(void **state)
{
    (void)state;
    Loaded *L = load("param L0 = 1.2\n"
                     "body a x = 0.3 y = 0.1 phi = 0.2\n"
                     "point m x = 1 y = 0.2\n"
                     "body b x = 1 y = 0.2 phi = 0.4\n"
                     "distance D1: a(0.35, -0.15) m length = 1.5\n"
                     "distance D2: b(-0.2, 0.3) a(0.1, 0.4) length = L0 + 0.3*sin(2*t)\n"
                     "distance D3: ground(0.5, -0.25) b(0.1, 0.2) length = 0.5*t^2 + 1\n");
    assert_int_equal(L->nq, 8);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    /* constant length */
    Want w = distance_row(body(0, 0.35, -0.15), point(3), 1.5, 0, 0, Q, QD);
    check_row(L, &e, 0, &w, "D1");
    /* L = 1.2 + 0.3 sin 2t: L' = 0.6 cos 2t, L'' = -1.2 sin 2t */
    double len = 1.2 + 0.3 * sin(2 * T), dlen = 0.6 * cos(2 * T), ddlen = -1.2 * sin(2 * T);
    w = distance_row(body(5, -0.2, 0.3), body(0, 0.1, 0.4), len, dlen, ddlen, Q, QD);
    check_row(L, &e, 1, &w, "D2");
    /* L = 0.5 t^2 + 1: L' = t, L'' = 1 */
    w = distance_row(ground(0.5, -0.25), body(5, 0.1, 0.2), 0.5 * T * T + 1, T, 1.0, Q, QD);
    check_row(L, &e, 2, &w, "D3");
    assert_true(fabs(e.nu[2]) > 0.1);       /* the time terms are really there */
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- pointline ---- */

static void test_pointline(void **state)
{
    (void)state;
    Loaded *L = load("body a x = 0.3 y = 0.1 phi = 0.2\n"
                     "point m x = 1 y = 0.2\n"
                     "body b x = 1 y = 0.2 phi = 0.4\n"
                     "pointline L1: a(0.2, -0.3) m axis(0.6, 0.8)\n"
                     "pointline L2: ground(1, 2) b(0.3, 0.1) axis(-1, 2)\n"
                     "pointline L3: a b(-0.2, 0.4) axis(1, 0)\n");
    Eval e;
    evaluate(L, Q, QD, T, &e);
    Want w = normal_row(body(0, 0.2, -0.3), point(3), 0.6, 0.8, Q, QD);
    check_row(L, &e, 0, &w, "L1");
    w = normal_row(ground(1, 2), body(5, 0.3, 0.1), -1, 2, Q, QD);
    check_row(L, &e, 1, &w, "L2");
    /* L3: A's reference point (no offset), n0 = (0, 1); L2's axis is used
       as written, not normalized: n0 = (-2, -1) */
    w = normal_row(body(0, 0, 0), body(5, -0.2, 0.4), 1, 0, Q, QD);
    check_row(L, &e, 2, &w, "L3");
    /* explicitly: L3 = -sin(pa) (P_b - r_a).x + cos(pa) (P_b - r_a).y */
    V2 pb = add(v2(Q[5], Q[6]), rotA(Q[7], v2(-0.2, 0.4)));
    assert_near(e.phi[2], -sin(Q[2]) * (pb.x - Q[0]) + cos(Q[2]) * (pb.y - Q[1]), 1e-12, 1e-14);
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- weld ---- */

static void test_weld(void **state)
{
    (void)state;
    Loaded *L = load("body a x = 0.3 y = 0.1 phi = 0.2\n"
                     "body b x = 1 y = 0.2 phi = 0.4\n"
                     "weld W: a(0.2, 0.1) b(-0.3, 0.15) angle = 0.3 + 0.2*t^2\n"
                     "weld G: ground(1, -0.5) b(0.25, 0.05)\n");
    assert_int_equal(L->nr, 6);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    const double *q = Q, *qd = QD;
    double pa = q[2], pb = q[5], wa = qd[2], wb = qd[5];
    V2 sa = v2(0.2, 0.1), sb = v2(-0.3, 0.15);
    /* W.x, W.y as a revolute; W.phi = pb - pa - theta(t), theta = 0.3 + 0.2 t^2:
       nu = theta' = 0.4 t, gamma = theta'' = 0.4 */
    V2 phi = sub(add(v2(q[0], q[1]), rotA(pa, sa)), add(v2(q[3], q[4]), rotA(pb, sb)));
    V2 Bsa = rotB(pa, sa), Bsb = rotB(pb, sb);
    V2 gam = sub(scl(wa * wa, rotA(pa, sa)), scl(wb * wb, rotA(pb, sb)));
    Want wx = {.phi = phi.x, .jac = {1, 0, Bsa.x, -1, 0, -Bsb.x}, .nu = 0, .gamma = gam.x};
    Want wy = {.phi = phi.y, .jac = {0, 1, Bsa.y, 0, -1, -Bsb.y}, .nu = 0, .gamma = gam.y};
    Want wphi = {.phi = pb - pa - (0.3 + 0.2 * T * T), .jac = {0, 0, -1, 0, 0, 1},
                .nu = 0.4 * T, .gamma = 0.4};
    check_row(L, &e, 0, &wx, "W.x");
    check_row(L, &e, 1, &wy, "W.y");
    check_row(L, &e, 2, &wphi, "W.phi");
    /* G: ground to b, angle 0 */
    V2 s = v2(0.25, 0.05);
    phi = sub(v2(1, -0.5), add(v2(q[3], q[4]), rotA(pb, s)));
    V2 Bs = rotB(pb, s), As = rotA(pb, s);
    Want gx = {.phi = phi.x, .jac = {0, 0, 0, -1, 0, -Bs.x}, .gamma = -As.x * wb * wb};
    Want gy = {.phi = phi.y, .jac = {0, 0, 0, 0, -1, -Bs.y}, .gamma = -As.y * wb * wb};
    Want gphi = {.phi = pb, .jac = {0, 0, 0, 0, 0, 1}};
    check_row(L, &e, 3, &gx, "G.x");
    check_row(L, &e, 4, &gy, "G.y");
    check_row(L, &e, 5, &gphi, "G.phi");
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- constraint and position-level drivers ---- */

static void test_constraint_and_drivers(void **state)
{
    (void)state;
    Loaded *L = load("body crank x = 0.1 y = 0.2 phi = 0.3\n"
                     "point m x = 1 y = 2\n"
                     "constraint C: m.x*sin(crank.phi) - m.y^2*t = 0.25*crank.x\n"
                     "driver D: crank.phi*(1 + 0.5*t) = sin(2*t)\n"
                     "driver E: t^2 * m.x = 1\n");
    assert_int_equal(L->nh, 3);
    assert_int_equal(L->nv, 0);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    double cx = Q[0], p = Q[2], x = Q[3], y = Q[4];
    double cxd = QD[0], pd = QD[2], xd = QD[3], yd = QD[4], t = T;
    (void)cxd;
    /* C: Phi = x sin p - y^2 t - 0.25 cx
       Phi_q = [-0.25, 0, x cos p, sin p, -2 y t], nu = -Phi_t = y^2
       (Phi_q qd)_q qd = -x sin p pd^2 + 2 cos p xd pd - 2 t yd^2
       Phi_qt qd = -2 y yd, Phi_tt = 0 */
    Want c = {.phi = x * sin(p) - y * y * t - 0.25 * cx,
             .jac = {-0.25, 0, x * cos(p), sin(p), -2 * y * t},
             .nu = y * y,
             .gamma = -(-x * sin(p) * pd * pd + 2 * cos(p) * xd * pd - 2 * t * yd * yd)
                      - 2 * (-2 * y * yd) - 0};
    check_row(L, &e, 0, &c, "C");
    /* D: Phi = p (1 + 0.5 t) - sin 2t
       Phi_q = 1 + 0.5 t, Phi_t = 0.5 p - 2 cos 2t, Phi_qt = 0.5, Phi_tt = 4 sin 2t
       gamma = -0 - 2 (0.5) pd - 4 sin 2t */
    Want d = {.phi = p * (1 + 0.5 * t) - sin(2 * t), .jac = {0, 0, 1 + 0.5 * t},
             .nu = -(0.5 * p - 2 * cos(2 * t)), .gamma = -2 * 0.5 * pd - 4 * sin(2 * t)};
    check_row(L, &e, 1, &d, "D");
    /* E: Phi = t^2 x - 1; Phi_q = t^2, Phi_t = 2 t x, Phi_qt = 2 t, Phi_tt = 2 x
       gamma = -2 (2 t) xd - 2 x */
    Want dr = {.phi = t * t * x - 1, .jac = {0, 0, 0, t * t}, .nu = -2 * t * x,
              .gamma = -2 * (2 * t) * xd - 2 * x};
    check_row(L, &e, 2, &dr, "E");
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* The driver with time-dependent coefficients of the brief, alone: the
   -2 Phi_qt qd and -Phi_tt terms are the whole of gamma. */
static void test_driver_time_terms(void **state)
{
    (void)state;
    Loaded *L = load("body crank x = 0 y = 0 phi = 0\n"
                     "driver D: crank.phi*(1 + 0.5*t) = sin(2*t)\n");
    double q[3] = {0.1, 0.2, 0.7371}, qd[3] = {0.3, 0.4, 1.3171}, t = 0.4123;
    Eval e;
    evaluate(L, q, qd, t, &e);
    double phi_qt_qd = 0.5 * qd[2];         /* Phi_qt qd */
    double phi_tt = 4 * sin(2 * t);         /* d2/dt2 (-sin 2t) */
    Want d = {.phi = 0.7371 * (1 + 0.5 * t) - sin(2 * t), .jac = {0, 0, 1 + 0.5 * t},
             .nu = 2 * cos(2 * t) - 0.5 * 0.7371, .gamma = -2 * phi_qt_qd - phi_tt};
    check_row(L, &e, 0, &d, "D");
    /* t = 0 alone: gamma = -pd, nu = 2 - 0.5 phi */
    evaluate(L, q, qd, 0.0, &e);
    assert_near(e.gamma[0], -1.3171, 1e-15, 0);
    assert_near(e.nu[0], 2 - 0.5 * 0.7371, 1e-15, 0);
    unload(L);

    L = load("point m x = 1 y = 1\n"
             "driver D: t^2 * m.x = 1\n");
    double q2[2] = {0.7371, 0.4123}, qd2[2] = {0.5813, -0.2749};
    t = 1.3217;
    evaluate(L, q2, qd2, t, &e);
    Want d2 = {.phi = t * t * 0.7371 - 1, .jac = {t * t, 0}, .nu = -2 * t * 0.7371,
              .gamma = -2 * (2 * t * 0.5813) - 2 * 0.7371};
    check_row(L, &e, 0, &d2, "D");
    check_consistency(L, q2, qd2, t);
    unload(L);
}

/* ---- velocity-level rows ---- */

static const char velocity_text[] =
    "body cart x = 0.1 y = 0.2 phi = 0.3\n"
    "body wheel x = 1 y = 0.45 phi = 0\n"
    "point m x = 0.5 y = 0.5\n"
    "knife K: cart(0.35, -0.1) axis(0.8, 0.6)\n"
    "rolling R: wheel radius = 0.45\n"
    "velocity V: der(m.x)*m.y - der(m.y)*m.x*t = 0.5*t\n"
    "driver S: der(cart.x)*cos(cart.phi) + der(cart.y)*sin(cart.phi) = 0.7*(1 + t)\n"
    "driver H: cart.phi = 0.2*t\n"
    "constraint C: wheel.y = 0.45\n";

static void test_velocity_rows(void **state)
{
    (void)state;
    Loaded *L = load(velocity_text);
    assert_int_equal(L->nq, 8);
    assert_int_equal(L->nh, 2);
    assert_int_equal(L->nv, 4);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    const double *q = Q, *qd = QD;
    double t = T;
    /* holonomic rows first: H = cart.phi - 0.2 t, C = wheel.y - 0.45 */
    Want h = {.phi = q[2] - 0.2 * t, .jac = {0, 0, 1}, .nu = 0.2, .gamma = 0};
    Want c = {.phi = q[4] - 0.45, .jac = {0, 0, 0, 0, 1}, .nu = 0, .gamma = 0};
    check_row(L, &e, 0, &h, "H");
    check_row(L, &e, 1, &c, "C");

    /* K: Psi = n . dP/dt, n = A(p) (-uy, ux), dP/dt = rd + B(p) s pd
       Jacobian [n.x, n.y, n.(B s)], nu = 0,
       gamma = -Psi_q qd = -pd [(B n0).dP/dt - n.(A s) pd]   (dB/dp = -A) */
    double p = q[2], pd = qd[2];
    V2 n0 = v2(-0.6, 0.8), s = v2(0.35, -0.1);
    V2 n = rotA(p, n0), Bn0 = rotB(p, n0), Bs = rotB(p, s), As = rotA(p, s);
    V2 Pd = add(v2(qd[0], qd[1]), scl(pd, Bs));
    Want k = {.jac = {n.x, n.y, dot(n, Bs)}, .nu = 0,
             .gamma = -pd * (dot(Bn0, Pd) - dot(n, As) * pd)};
    check_row(L, &e, 2, &k, "K");

    /* R: Psi = wheel.xd + 0.45 wheel.phid: Jacobian [1, 0, 0.45], nu = gamma = 0 */
    Want r = {.jac = {0, 0, 0, 1, 0, 0.45}, .nu = 0, .gamma = 0};
    check_row(L, &e, 3, &r, "R");

    /* V: Psi = xd y - yd x t - 0.5 t: a = (y, -x t), b = -0.5 t, nu = 0.5 t;
       Psi_q qd = -yd t xd + xd yd, Psi_t = -yd x - 0.5 */
    double x = q[6], y = q[7], xd = qd[6], yd = qd[7];
    Want v = {.jac = {0, 0, 0, 0, 0, 0, y, -x * t}, .nu = 0.5 * t,
             .gamma = -((-yd * t * xd + xd * yd) + (-yd * x - 0.5))};
    check_row(L, &e, 4, &v, "V");

    /* S: Psi = xd cos p + yd sin p - 0.7 (1 + t): a = (cos p, sin p, 0),
       nu = 0.7 (1 + t), gamma = -((-xd sin p + yd cos p) pd - 0.7) */
    double cxd = qd[0], cyd = qd[1];
    Want sr = {.jac = {cos(p), sin(p), 0}, .nu = 0.7 * (1 + t),
              .gamma = -((-cxd * sin(p) + cyd * cos(p)) * pd - 0.7)};
    check_row(L, &e, 5, &sr, "S");
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* A velocity driver with a constant right side: spin at -w */
static void test_velocity_driver_constant(void **state)
{
    (void)state;
    Loaded *L = load("param w = 2*pi\n"
                     "body wheel x = 1 y = 0.5 phi = 0\n"
                     "driver spin: der(wheel.phi) = -w\n");
    assert_int_equal(L->nh, 0);
    assert_int_equal(L->nv, 1);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    /* Psi = phid + w: a = e_phi, nu = -b = -w, gamma = 0 */
    Want w = {.jac = {0, 0, 1}, .nu = -2 * M_PI, .gamma = 0};
    check_row(L, &e, 0, &w, "spin");
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- the worked examples ---- */

/* Textbook pendulum: rod L = 2 to the ground, mass at (1.732, 1.0). */
static void pendulum(const char *text, const char *kind)
{
    Loaded *L = load(text);
    const Model *m = L->mech->model;
    assert_int_equal(L->nq, 2);
    assert_int_equal(L->nr, 1);
    assert_string_equal(m->rows[0].name, "rod");
    assert_near(m->q0[0], 1.732, 0, 0);
    assert_near(m->q0[1], 1.0, 0, 0);
    Eval e;
    double zero[2] = {0, 0};
    evaluate(L, m->q0, zero, 0.0, &e);
    /* Phi = x^2 + y^2 - L^2 = 2.999824 + 1 - 4, Jacobian (2x, 2y) = (3.464, 2.0) */
    assert_near(e.phi[0], -0.000176, 1e-9, 0);
    assert_near(e.jac[0], 3.464, RTOL, 0);
    assert_near(e.jac[1], 2.0, RTOL, 0);
    assert_near(e.nu[0], 0.0, 0, 0);
    assert_near(e.gamma[0], 0.0, 0, 0);
    /* on the circle: (2 cos 30, 2 sin 30) = (sqrt 3, 1), at 3 m/s along the
       tangent (-sin 30, cos 30): qd = (-1.5, 2.598...), gamma = -2 |v|^2 = -18 */
    double c30 = cos(M_PI / 6), s30 = sin(M_PI / 6);
    double q[2] = {2 * c30, 2 * s30};
    double qd[2] = {-3 * s30, 3 * c30};
    assert_near(qd[0], -1.5, 1e-15, 0);
    assert_near(qd[1], 2.598, 0, 1e-3);
    evaluate(L, q, qd, 0.0, &e);
    assert_near(e.phi[0], 0.0, 0, 1e-14);
    assert_near(e.jac[0], 2 * sqrt(3.0), RTOL, 0);
    assert_near(e.jac[1], 2.0, RTOL, 0);
    assert_near(e.jac[0] * qd[0] + e.jac[1] * qd[1], 0.0, 0, 1e-14);   /* tangent */
    assert_near(e.gamma[0], -18.0, RTOL, 0);
    /* at 2 m/s: gamma = -2 * 4 = -8 */
    qd[0] = -2 * s30;
    qd[1] = 2 * c30;
    evaluate(L, q, qd, 0.0, &e);
    assert_near(e.gamma[0], -8.0, RTOL, 0);
    /* the row kind is the statement's */
    assert_int_equal(m->rows[0].kind, strcmp(kind, "distance") == 0 ? JOINT_DISTANCE : JOINT_CONSTRAINT);
    check_consistency(L, q, qd, 0.0);
    unload(L);
}

static void test_pendulum_distance(void **state)
{
    (void)state;
    pendulum("param L = 2\n"
             "point m x = 1.732 y = 1.0\n"
             "distance rod: ground m length = L\n", "distance");
}

static void test_pendulum_constraint(void **state)
{
    (void)state;
    pendulum("param L = 2\n"
             "point m x = 1.732 y = 1.0\n"
             "constraint rod: m.x^2 + m.y^2 - L^2 = 0\n", "constraint");
}

/* The point on the line x = 3: Phi = x - 3, Jacobian (1, 0); once as a
   constraint, once as a pointline through (3, 0) with axis (0, -1), whose
   normal (-uy, ux) = (1, 0) gives the same sign. */
static void test_point_on_line(void **state)
{
    (void)state;
    const char *texts[2] = {
        "point m x = 3 y = 0.5\nconstraint line: m.x = 3\n",
        "point m x = 3 y = 0.5\npointline line: ground(3, 0) m axis(0, -1)\n",
    };
    for (int i = 0; i < 2; i++) {
        Loaded *L = load(texts[i]);
        double q[2] = {3.4127, 0.5813}, qd[2] = {0.7371, -1.4123};
        Eval e;
        evaluate(L, q, qd, T, &e);
        assert_near(e.phi[0], 3.4127 - 3, RTOL, 0);
        assert_near(e.jac[0], 1.0, 0, 0);
        assert_near(e.jac[1], 0.0, 0, 0);
        assert_near(e.nu[0], 0.0, 0, 0);
        assert_near(e.gamma[0], 0.0, 0, 0);
        check_consistency(L, q, qd, T);
        unload(L);
    }
}

/* x^2 + y^2 - 25 at (3, 4): Phi = 0, Jacobian (6, 8); at 2 m/s: gamma = -8 */
static void test_circle_345(void **state)
{
    (void)state;
    Loaded *L = load("point m x = 3 y = 4\nconstraint c: m.x^2 + m.y^2 - 25 = 0\n");
    double q[2] = {3, 4}, qd[2] = {-1.6, 1.2};
    Eval e;
    evaluate(L, q, qd, 0, &e);
    assert_near(e.phi[0], 0.0, 0, 0);
    assert_near(e.jac[0], 6.0, 0, 0);
    assert_near(e.jac[1], 8.0, 0, 0);
    assert_near(e.gamma[0], -8.0, RTOL, 0);
    unload(L);
}

/* ---- spatial rows ---- */

/* Three bodies and a point (24 coordinates), every block: spherical and
   dot-1 (revolute R, universal U, perpendicular Pp), dot-2 (cylindrical
   C, translational T, pointplane PP), distance D and the bodies' .norm
   (24 rows). */
static const char spatial_text[] =
    "spatial\n"
    "body a x = 0.1 y = 0.2 z = 0.3\n"
    "body b x = 1 y = 0.5 z = -0.2\n"
    "body c x = -0.5 y = 1 z = 0.4\n"
    "point m x = 0.3 y = -0.4 z = 0.8\n"
    "revolute R: ground(0.1, 0.2, 0.3) a(0.2, -0.1, 0.3) axis(0.3, -1, 0.2)\n"
    "cylindrical C: a(0.1, 0.2, 0.3) b(-0.2, 0.1, 0) axis(1, 2, -0.5) axis(0.2, 0.1, 1)\n"
    "universal U: b(0.3, 0.1, -0.2) c(0.1, 0.4, 0.1) axis(1, 1, 0) axis(0, 1, 2)\n"
    "distance D: m c(0.1, 0.2, 0.3) length = 1.2\n"
    "pointplane PP: c(0.1, 0.2, 0.3) m axis(0.5, -1, 2)\n"
    "perpendicular Pp: a c axis(0.1, 0.9, -0.2) axis(1, 0, 0.3)\n"
    "translational T: b(0.2, 0.1, 0) ground(1, -1, 0.5) axis(-0.4, 0.3, 0.9)\n";

/* A(p) s = (2 e0^2 - 1) s + 2 e (e.s) + 2 e0 e x s, at any p */
static void rot_p(const double *p, const double s[3], double out[3])
{
    const double *e = p + 1;
    double es = e[0] * s[0] + e[1] * s[1] + e[2] * s[2];
    double exs[3] = {e[1] * s[2] - e[2] * s[1], e[2] * s[0] - e[0] * s[2], e[0] * s[1] - e[1] * s[0]};
    for (int i = 0; i < 3; i++)
        out[i] = (2 * p[0] * p[0] - 1) * s[i] + 2 * e[i] * es + 2 * p[0] * exs[i];
}

/* P = r + A(p) s of the body whose x is q[k] */
static void point_p(const double *q, int k, const double s[3], double out[3])
{
    rot_p(q + k + 3, s, out);
    for (int i = 0; i < 3; i++)
        out[i] += q[k + i];
}

/* Along a line q + h u every one of these rows is a polynomial of degree
   at most 4 in h (A(p) s is quadratic in p, each row at most a product
   of two such), and the five-point stencils are exact for those:
     f'(0)  = (f(-2h) - 8 f(-h) + 8 f(h) - f(2h)) / 12h,
     f''(0) = (-f(-2h) + 16 f(-h) - 30 f(0) + 16 f(h) - f(2h)) / 12h^2.
   So the Jacobian (u = a unit vector) and gamma = -f''(0) along u = qd
   (the rows have no t) come out of Phi alone, to round-off, with no
   formula: neither the symbolic one nor a hand one. */
static void stencil(const Loaded *L, const double *q, const double *u, double h, double d1[], double d2[])
{
    double f[5][MAXR], x[MAXQ];
    for (int k = 0; k < 5; k++) {
        for (int i = 0; i < L->nq; i++)
            x[i] = q[i] + (k - 2) * h * u[i];
        L->k->phi(x, 0.0, f[k]);
    }
    for (int r = 0; r < L->nh; r++) {
        d1[r] = (f[0][r] - 8 * f[1][r] + 8 * f[3][r] - f[4][r]) / (12 * h);
        d2[r] = (-f[0][r] + 16 * f[1][r] - 30 * f[2][r] + 16 * f[3][r] - f[4][r]) / (12 * h * h);
    }
}

static void test_spatial_rows(void **state)
{
    (void)state;
    Loaded *L = load(spatial_text);
    const Model *m = L->mech->model;
    assert_int_equal(L->nq, 24);
    assert_int_equal(L->nh, 24);
    /* libtcc gets parts of up to 1000 operations and stores (engine_jit):
       this `all` (2 506 operations, 648 stores) is 4 of them; at the
       written file's 150 a part it would be 25 */
    assert_true(L->emitted.ops[EMIT_ALL] > 2000);
    assert_in_range(L->emitted.chunks[EMIT_ALL], 3, 6);
    Eval e;
    evaluate(L, Q, QD, T, &e);
    /* Phi by hand (A, C = 0, 7, 14 and m = 21): R.x .. R.z = P_ground - P_a,
       D = |P_c - m|^2 - 1.2^2, PP = h_c . (m - P_c), the norms */
    static const double sa[3] = {0.2, -0.1, 0.3}, sc[3] = {0.1, 0.2, 0.3}, g[3] = {0.1, 0.2, 0.3};
    double pa[3], pc[3], d[3], hc[3];
    point_p(Q, 0, sa, pa);
    point_p(Q, 14, sc, pc);
    double n = sqrt(0.25 + 1 + 4), u[3] = {0.5 / n, -1 / n, 2 / n};
    rot_p(Q + 17, u, hc);
    for (int i = 0; i < 3; i++)
        d[i] = Q[21 + i] - pc[i];
    int row = 0;
    for (int r = 0; r < m->nr; r++)
        if (strcmp(m->rows[r].name, "R.x") == 0)
            row = r;
    for (int i = 0; i < 3; i++)
        assert_near(e.phi[row + i], g[i] - pa[i], RTOL, ATOL);
    for (int r = 0; r < m->nr; r++) {
        const char *name = m->rows[r].name;
        if (strcmp(name, "D") == 0)
            assert_near(e.phi[r], d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.44, RTOL, ATOL);
        if (strcmp(name, "PP") == 0)
            assert_near(e.phi[r], hc[0] * d[0] + hc[1] * d[1] + hc[2] * d[2], RTOL, ATOL);
        if (strcmp(name, "b.norm") == 0)
            assert_near(e.phi[r], Q[10] * Q[10] + Q[11] * Q[11] + Q[12] * Q[12] + Q[13] * Q[13] - 1, RTOL, ATOL);
        assert_near(e.nu[r], 0.0, 0, 0);
    }
    /* the Jacobian column by column and gamma along qd, from Phi alone */
    double d1[MAXR], d2[MAXR], unit[MAXQ] = {0};
    for (int c = 0; c < L->nq; c++) {
        unit[c] = 1.0;
        stencil(L, Q, unit, 0.5, d1, d2);
        unit[c] = 0.0;
        for (int r = 0; r < L->nh; r++)
            if (!(fabs(e.jac[r * L->nq + c] - d1[r]) <= 1e-12 * (1 + fabs(d1[r]))))
                fail_msg("%s: jac[%s] = %.17g, the stencil gives %.17g", m->rows[r].name,
                         m->coord_names[c], e.jac[r * L->nq + c], d1[r]);
    }
    stencil(L, Q, QD, 0.5, d1, d2);
    for (int r = 0; r < L->nh; r++)
        if (!(fabs(e.gamma[r] + d2[r]) <= 1e-11 * (1 + fabs(d2[r]))))
            fail_msg("%s: gamma = %.17g, the stencil gives %.17g", m->rows[r].name, e.gamma[r], -d2[r]);
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- rows: order, names, kinds ---- */

static void test_row_order_and_names(void **state)
{
    (void)state;
    Loaded *L = load("body a x = 0.3 y = 0.1 phi = 0.2\n"
                     "body b x = 1 y = 0.2 phi = 0.4\n"
                     "point m x = 1 y = 1\n"
                     "velocity V1: der(m.x) = 1\n"
                     "revolute J: ground a(-0.5, 0)\n"
                     "rolling R: b radius = 0.3\n"
                     "prismatic P: a b axis(1, 0)\n"
                     "driver Dv: der(a.phi) = 2\n"
                     "distance D: b m length = 1\n"
                     "weld W: ground b\n"
                     "driver Dp: a.phi = t\n");
    const Model *m = L->mech->model;
    static const char *const names[] = {
        "J.x", "J.y", "P.n", "P.phi", "D", "W.x", "W.y", "W.phi", "Dp",
        "V1", "R", "Dv",
    };
    static const JointKind kinds[] = {
        JOINT_REVOLUTE, JOINT_REVOLUTE, JOINT_PRISMATIC, JOINT_PRISMATIC, JOINT_DISTANCE,
        JOINT_WELD, JOINT_WELD, JOINT_WELD, JOINT_DRIVER, JOINT_VELOCITY, JOINT_ROLLING,
        JOINT_DRIVER,
    };
    assert_int_equal(m->nr, 12);
    assert_int_equal(m->nh, 9);
    assert_int_equal(m->nv, 3);
    for (int r = 0; r < m->nr; r++) {
        assert_string_equal(m->rows[r].name, names[r]);
        assert_int_equal(m->rows[r].kind, kinds[r]);
        assert_true(m->rows[r].velocity == (r >= 9));
    }
    static const char *const coords[] = {
        "a.x", "a.y", "a.phi", "b.x", "b.y", "b.phi", "m.x", "m.y",
    };
    assert_int_equal(m->nq, 8);
    for (int i = 0; i < m->nq; i++)
        assert_string_equal(m->coord_names[i], coords[i]);
    /* the kernels follow the same order: V1's row is e_{m.x}, Dv's e_{a.phi} */
    Eval e;
    evaluate(L, Q, QD, T, &e);
    assert_near(e.jac[9 * 8 + 6], 1.0, 0, 0);
    assert_near(e.nu[9], 1.0, 0, 0);
    assert_near(e.jac[11 * 8 + 2], 1.0, 0, 0);
    assert_near(e.nu[11], 2.0, 0, 0);
    assert_near(e.phi[8], Q[2] - T, RTOL, 0);
    check_consistency(L, Q, QD, T);
    unload(L);
}

/* ---- sparse Jacobian and fused kernel on the examples ---- */

static void test_examples_consistency(void **state)
{
    (void)state;
    static const char *const files[] = {
        "four_bar", "slider_crank", "five_bar", "elliptical_trammel", "all_statements",
        "knife_cart", "rolling_wheel", "skate_velocity", "parallelogram_redundant",
        "slider_crank_spatial", "rssr", "rolling_disk",
    };
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
        char path[256];
        snprintf(path, sizeof path, "examples/%s.mech", files[i]);
        FILE *fp = fopen(path, "rb");
        if (!fp) {
            snprintf(path, sizeof path, "../examples/%s.mech", files[i]);
            fp = fopen(path, "rb");
        }
        if (!fp)
            fail_msg("cannot open examples/%s.mech (run from the repository root)", files[i]);
        static char text[1 << 16];
        size_t n = fread(text, 1, sizeof text - 1, fp);
        fclose(fp);
        text[n] = '\0';
        Loaded *L = load(text);
        check_consistency(L, Q, QD, T);
        check_consistency(L, L->mech->model->q0, QD, 0.0);
        unload(L);
    }
}

/* The sparse pattern holds exactly the coordinates each row touches. */
static void test_sparse_pattern(void **state)
{
    (void)state;
    Loaded *L = load(revolute_text);
    /* O.x: a.x, a.phi; O.y: a.y, a.phi; J.x: a.x a.phi b.x b.phi; ... */
    static const int rows[] = {0, 0, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 5, 5, 5};
    static const int cols[] = {0, 2, 1, 2, 0, 2, 3, 5, 1, 2, 4, 5, 3, 5, 6, 4, 5, 7};
    assert_int_equal(L->nnz, 18);
    for (int k = 0; k < 18; k++) {
        assert_int_equal(L->k->jac_row[k], rows[k]);
        assert_int_equal(L->k->jac_col[k], cols[k]);
    }
    unload(L);
}

/* ---- rejected rows ---- */

static void expect_error(const char *text, int line, int col, const char *needle)
{
    Diag diag;
    MechLimits limits = mech_default_limits();
    Mech *mech = pipeline_load_text(text, "bad.mech", &limits, &diag);
    if (mech) {
        pipeline_free(mech);
        fail_msg("accepted, expected an error at %d:%d: %s", line, col, text);
    }
    assert_true(diag.failed);
    assert_true(diag.has_pos);
    if (diag.line != line || diag.col != col || !strstr(diag.message, needle))
        fail_msg("error at %d:%d '%s', expected %d:%d containing '%s'", diag.line, diag.col,
                 diag.message, line, col, needle);
}

static void test_rejected_rows(void **state)
{
    (void)state;
    /* a velocity row must be affine in der(): reported at the statement */
    expect_error("point m x = 1 y = 0\nvelocity v: der(m.x)^2 = 1\n", 2, 1, "not affine in der()");
    expect_error("point m x = 1 y = 0\n\n  driver d: der(m.x)*der(m.y) = 1\n", 3, 3, "not affine in der()");
    expect_error("point m x = 1 y = 0\nrevolute r: ground m\nvelocity v: sin(der(m.x)) = 1\n",
                 3, 1, "not affine");
    /* der() in a holonomic statement: at the der */
    expect_error("point m x = 1 y = 0\nconstraint c: m.x + der(m.y) = 0\n", 2, 21,
                 "der() cannot appear in a holonomic row");
    expect_error("body b\nconstraint c: der(b.phi) = 0\n", 2, 15, "der() cannot appear");
    /* a velocity row without der() */
    expect_error("point m x = 1 y = 0\nvelocity v: m.x = 1\n", 2, 1, "contains no der()");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_revolute),
        cmocka_unit_test(test_prismatic),
        cmocka_unit_test(test_distance),
        cmocka_unit_test(test_pointline),
        cmocka_unit_test(test_weld),
        cmocka_unit_test(test_constraint_and_drivers),
        cmocka_unit_test(test_driver_time_terms),
        cmocka_unit_test(test_velocity_rows),
        cmocka_unit_test(test_velocity_driver_constant),
        cmocka_unit_test(test_pendulum_distance),
        cmocka_unit_test(test_pendulum_constraint),
        cmocka_unit_test(test_point_on_line),
        cmocka_unit_test(test_circle_345),
        cmocka_unit_test(test_spatial_rows),
        cmocka_unit_test(test_row_order_and_names),
        cmocka_unit_test(test_examples_consistency),
        cmocka_unit_test(test_sparse_pattern),
        cmocka_unit_test(test_rejected_rows),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
