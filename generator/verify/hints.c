/* hints.c - the check's verdict, and what mistake a failed comparison looks like.
 *
 * Where the worst error passes its tolerance, the two numbers are examined
 * for the classic textbook slips: a ratio of -1 or 2, a missing term, and
 * for gamma a decomposition of the finite difference into its
 * -(Phi_q qd)_q qd, -2 Phi_qt qd and -Phi_tt parts to name the one that
 * was dropped.
 */
#include "hints.h"

#include "fd.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static bool near(double a, double b, double tol)
{
    return fabs(a - b) <= tol * (1.0 + fabs(b));
}

/* The ratio patterns between value and reference. */
typedef enum Ratio { RATIO_NONE, RATIO_NEG, RATIO_TWO, RATIO_HALF } Ratio;

static Ratio ratio_of(double v, double r, double tol)
{
    if (r == 0.0)
        return RATIO_NONE;
    if (near(v, -r, 10 * tol))
        return RATIO_NEG;
    if (near(v, 2.0 * r, 10 * tol))
        return RATIO_TWO;
    if (near(v, 0.5 * r, 10 * tol))
        return RATIO_HALF;
    return RATIO_NONE;
}

static void hint_jac(const Checker *c, CheckItem *it)
{
    double tol = c->opt->tol;
    bool velocity = it->row >= c->nh;
    switch (ratio_of(it->value, it->reference, tol)) {
    case RATIO_NEG:
        snprintf(it->hint, sizeof it->hint, "the sign is wrong (value = -reference): e.g. d(P_A - P_B)/dq "
                 "written for P_B - P_A, or B = dA/dphi taken with the wrong sign");
        return;
    case RATIO_TWO:
        snprintf(it->hint, sizeof it->hint, "a factor 2 too many (value = 2 x reference): e.g. a term "
                 "added twice, or d(d.d)/dq taken as 4 d.d_q");
        return;
    case RATIO_HALF:
        snprintf(it->hint, sizeof it->hint, "a factor 2 missing (value = reference / 2): e.g. "
                 "d(d.d)/dq = 2 d.d_q with the 2 dropped");
        return;
    case RATIO_NONE:
        break;
    }
    if (it->value == 0.0)
        snprintf(it->hint, sizeof it->hint, "a Jacobian term is missing%s",
                 velocity ? " (a der() coefficient left out)"
                          : " (e.g. the B s column of a body-fixed point)");
    else if (fabs(it->reference) <= tol)
        snprintf(it->hint, sizeof it->hint,
                 "a spurious entry: the row does not change with this coordinate");
    else
        snprintf(it->hint, sizeof it->hint, "no classic pattern: compare the row's formula term by term");
}

static void hint_nu(const Checker *c, CheckItem *it)
{
    switch (ratio_of(it->value, it->reference, c->opt->tol)) {
    case RATIO_NEG:
        snprintf(it->hint, sizeof it->hint, "the sign is wrong: nu = -Phi_t (Phi_q qd = nu), not +Phi_t");
        return;
    case RATIO_TWO:
        snprintf(it->hint, sizeof it->hint, "a factor 2 too many (value = 2 x reference)");
        return;
    case RATIO_HALF:
        snprintf(it->hint, sizeof it->hint, "a factor 2 missing (value = reference / 2)");
        return;
    case RATIO_NONE:
        break;
    }
    if (it->value == 0.0)
        snprintf(it->hint, sizeof it->hint,
                 "Phi_t is missing: a time-dependent driver, length or angle treated as constant");
    else
        snprintf(it->hint, sizeof it->hint, "no classic pattern: check the row's time dependence");
}
static void hint_gamma(Checker *c, CheckItem *it, double *scratch, double *vec)
{
    double tol = 10 * c->opt->tol, v = it->value, r = it->reference;
    /* back to the worst state to split the reference into its parts */
    memcpy(c->q, c->save_q[CHECK_GAMMA_FD], (size_t)c->nq * sizeof *c->q);
    memcpy(c->qd, c->save_qd[CHECK_GAMMA_FD], (size_t)c->nq * sizeof *c->qd);
    c->t = it->t;
    double gq = check_gamma_part(c, it->row, true, false, it->step, scratch, vec);   /* -(Phi_q qd)_q qd */
    double gt = check_gamma_part(c, it->row, false, true, it->step, scratch, vec);   /* -Phi_tt */
    double gx = r - gq - gt;                                         /* -2 Phi_qt qd */
    bool velocity = it->row >= c->nh;
    struct { double value; const char *text; } cand[] = {
        {-r, velocity ? "the sign is wrong: gamma = -(Psi_q qd + Psi_t)"
                      : "the sign is wrong: Phi_q qdd = gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt"},
        {r - gt, velocity ? "the term -Psi_t is missing (the time derivative of a der() coefficient or right side)"
                          : "the term -Phi_tt is missing (the second time derivative of a driver, length or angle)"},
        {r - gq, velocity ? "the term -Psi_q qd is missing (the coefficients' change along the motion)"
                          : "the quadratic velocity term -(Phi_q qd)_q qd is missing (e.g. A s phi'^2 of a revolute)"},
        {r - gx, "the mixed term -2 Phi_qt qd is missing"},
        {r - 0.5 * gx, "the mixed term is counted once: -Phi_qt qd instead of -2 Phi_qt qd"},
        {r - 2.0 * gq, "the quadratic velocity term has the wrong sign"},
        {2.0 * r, "a factor 2 too many (value = 2 x reference)"},
        {0.5 * r, "a factor 2 missing (value = reference / 2)"},
    };
    for (size_t k = 0; k < sizeof cand / sizeof *cand; k++) {
        if (!near(cand[k].value, r, tol) && near(v, cand[k].value, tol)) {
            snprintf(it->hint, sizeof it->hint, "%s", cand[k].text);
            return;
        }
    }
    if (v == 0.0)
        snprintf(it->hint, sizeof it->hint, "gamma of this row is missing altogether");
    else
        snprintf(it->hint, sizeof it->hint, "no classic pattern: compare the row's gamma term by term");
}

static void hint_pair(const Checker *c, CheckItem *it, int pair, int qty)
{
    int fd = qty == QTY_JAC ? CHECK_JAC_FD : qty == QTY_NU ? CHECK_NU_FD : qty == QTY_GAMMA ? CHECK_GAMMA_FD : -1;
    const CheckItem *f = fd >= 0 ? &c->rep->items[fd] : NULL;
    const char *kind = joint_info[c->m->rows[it->row].kind].keyword;
    if (pair == 1)
        snprintf(it->hint, sizeof it->hint,
                 "the same C differs under libtcc and cc: suspect a compiler or math library difference");
    else if (f && f->checked && !(f->error <= f->tol))
        snprintf(it->hint, sizeof it->hint,
                 "the generated code fails against finite differences too (see above)");
    else if (f)
        snprintf(it->hint, sizeof it->hint, "the generated code agrees with finite differences: "
                 "suspect the generic evaluator's %s formula", kind);
    else
        snprintf(it->hint, sizeof it->hint, "suspect the generic evaluator's %s formula, "
                 "or the row's lowering in generator/model/joints.c", kind);
}

/* The verdict, and a hint for every item above its tolerance. */
void check_diagnose(Checker *c)
{
    CheckReport *rep = c->rep;
    rep->ok = true;
    for (int w = 0; w < CHECK_WHAT_COUNT; w++) {
        CheckItem *it = &rep->items[w];
        if (!it->checked || it->error <= it->tol)
            continue;
        rep->ok = false;
        if (w == CHECK_JAC_FD)
            hint_jac(c, it);
        else if (w == CHECK_NU_FD)
            hint_nu(c, it);
        else if (w == CHECK_GAMMA_FD)
            hint_gamma(c, it, c->scratch, c->vec);
    }
    for (int w = CHECK_PAIR_FIRST; w < CHECK_DYN_FIRST; w++) {
        CheckItem *it = &rep->items[w];
        if (it->checked && !(it->error <= it->tol))
            hint_pair(c, it, (w - CHECK_PAIR_FIRST) / QTY_COUNT, (w - CHECK_PAIR_FIRST) % QTY_COUNT);
    }
    static const char *const dyn_hints[] = {
        "the generated M or Q and the engine's differ: compare the mass element's or force's "
        "lowering (generator/diff/dynamics.c) with generic_dynamics.c",
        "M is not symmetric: an entry was added to one triangle only",
        "M has a negative eigenvalue: a negative mass or J, or a wrong sign in p_q",
        "the velocity terms disagree with the kinetic energy's: a dropped or doubled "
        "convective term (pdot_q qd)",
    };
    for (int w = CHECK_DYN_FIRST; w < CHECK_WHAT_COUNT; w++) {
        CheckItem *it = &rep->items[w];
        int h = w < CHECK_M_SYMMETRIC ? 0 : 1 + (w - CHECK_M_SYMMETRIC);
        if (it->checked && !(it->error <= it->tol))
            snprintf(it->hint, sizeof it->hint, "%s", dyn_hints[h]);
    }
}
