/* engines.c - the check's engines: opening them, the one under test (with a planted fault), pairs compared. */
#include "engines.h"

#include "../engine/aot.h"

#include <stdio.h>
#include <string.h>

void check_under_test(Checker *c)
{
    const Engine *e = &c->eng[ENGINE_JIT];
    double **o = c->out[ENGINE_JIT];
    engine_phi(e, c->q, c->t, o[QTY_PHI]);
    if (c->sparse)
        c->jnz[ENGINE_JIT]->jac.jac_nz(c->jnz[ENGINE_JIT]->jac.ctx, c->q, c->t, o[QTY_JAC]);
    else
        engine_jac(e, c->q, c->t, o[QTY_JAC]);
    engine_nu(e, c->q, c->t, o[QTY_NU]);
    engine_gamma(e, c->q, c->qd, c->t, o[QTY_GAMMA]);
    if (c->dyn) {
        e->k.mass(e->k.ctx, c->q, c->mass[ENGINE_JIT]);
        e->k.force(e->k.ctx, c->q, c->qd, c->t, c->force[ENGINE_JIT]);
        const MechrtHostMassNz *mnz = engine_mass_nz(e);
        mnz->mass_nz(mnz->ctx, c->q, c->mass_nz[ENGINE_JIT]);
    }
    const CheckFault *f = &c->opt->fault;
    if (f->kind == CHECK_FAULT_MASS_SCALE && c->dyn && f->row >= 0 && f->row < c->nq
        && f->col >= 0 && f->col < c->nq)
        c->mass[ENGINE_JIT][(size_t)f->row * (size_t)c->nq + (size_t)f->col] *= f->factor;
    if (f->kind == CHECK_FAULT_NONE || f->row < 0 || f->row >= c->nr)
        return;
    switch (f->kind) {
    case CHECK_FAULT_NONE:
    case CHECK_FAULT_MASS_SCALE:
        break;
    case CHECK_FAULT_JAC_SCALE:
        for (int k = 0; c->sparse && k < c->nnz; k++)
            if (c->jnz[ENGINE_JIT]->jac.row[k] == f->row && c->jnz[ENGINE_JIT]->jac.col[k] == f->col)
                o[QTY_JAC][k] *= f->factor;
        if (!c->sparse && f->col >= 0 && f->col < c->nq)
            o[QTY_JAC][(size_t)f->row * (size_t)c->nq + (size_t)f->col] *= f->factor;
        break;
    case CHECK_FAULT_NU_SCALE:
        o[QTY_NU][f->row] *= f->factor;
        break;
    case CHECK_FAULT_GAMMA_ZERO:
        o[QTY_GAMMA][f->row] = 0.0;
        break;
    case CHECK_FAULT_GAMMA_DROP_TT:
    case CHECK_FAULT_GAMMA_DROP_QD:
        /* with qd = 0 only -Phi_tt is left of gamma */
        memset(c->qdw, 0, (size_t)c->nq * sizeof *c->qdw);
        engine_gamma(e, c->q, c->qdw, c->t, c->gamma0);
        if (f->kind == CHECK_FAULT_GAMMA_DROP_TT)
            o[QTY_GAMMA][f->row] -= c->gamma0[f->row];
        else
            o[QTY_GAMMA][f->row] = c->gamma0[f->row];
        break;
    }
}

void check_eval_engine(Checker *c, EngineKind k)
{
    double **o = c->out[k];
    engine_phi(&c->eng[k], c->q, c->t, o[QTY_PHI]);
    if (!c->sparse)
        engine_jac(&c->eng[k], c->q, c->t, o[QTY_JAC]);
    else if (c->has_nz[k])
        c->jnz[k]->jac.jac_nz(c->jnz[k]->jac.ctx, c->q, c->t, o[QTY_JAC]);
    engine_nu(&c->eng[k], c->q, c->t, o[QTY_NU]);
    engine_gamma(&c->eng[k], c->q, c->qd, c->t, o[QTY_GAMMA]);
    if (c->dyn) {
        const MechrtKernels *mk = &c->eng[k].k;
        mk->mass(mk->ctx, c->q, c->mass[k]);
        mk->force(mk->ctx, c->q, c->qd, c->t, c->force[k]);
        const MechrtHostMassNz *mnz = engine_mass_nz(&c->eng[k]);
        mnz->mass_nz(mnz->ctx, c->q, c->mass_nz[k]);
    }
}

void check_compare_pair(Checker *c, int pair)
{
    EngineKind a = check_pair_engines[pair][0], b = check_pair_engines[pair][1];
    int nq = c->nq;
    for (int qty = 0; qty < QTY_COUNT; qty++) {
        int what = CHECK_PAIR_FIRST + pair * QTY_COUNT + qty;
        bool nz = c->sparse && qty == QTY_JAC;
        if (nz && !(c->has_nz[a] && c->has_nz[b]))
            continue;   /* the generic interpreter's Jacobian is dense */
        int n = qty == QTY_PHI ? c->nh : nz ? c->nnz : qty == QTY_JAC ? c->nr * nq : c->nr;
        for (int i = 0; i < n; i++) {
            int row = nz ? c->jnz[ENGINE_JIT]->jac.row[i] : qty == QTY_JAC ? i / nq : i;
            int col = nz ? c->jnz[ENGINE_JIT]->jac.col[i] : qty == QTY_JAC ? i % nq : -1;
            check_record(c, what, row, col, c->out[a][qty][i], c->out[b][qty][i], 0.0);
        }
        if (n == 0)
            c->rep->items[what].checked = true;
    }
    for (int qty = 0; qty < 2 && c->dyn; qty++) {     /* M, then Q: col names the coordinate */
        int what = CHECK_DYN_FIRST + 2 * pair + qty;
        const double *va = qty == 0 ? c->mass[a] : c->force[a], *vb = qty == 0 ? c->mass[b] : c->force[b];
        for (int i = 0; i < (qty == 0 ? nq * nq : nq); i++)
            check_record(c, what, -1, i % nq, va[i], vb[i], 0.0);
    }
    /* M's nonzeros (what sim's sparse path calls) count under M: every
       engine writes them in the generated kernel's pattern. */
    const MechrtHostMassNz *mnz = c->dyn ? engine_mass_nz(&c->eng[a]) : NULL;
    for (int i = 0; mnz && i < mnz->nnz; i++)
        check_record(c, CHECK_DYN_FIRST + 2 * pair, -1, mnz->col[i], c->mass_nz[a][i],
                     c->mass_nz[b][i], 0.0);
}

/* ---- dynamics: M's symmetry and definiteness, Q's velocity terms ---- */

/* jit and generic always, aot when asked for and a compiler exists (else
   rep->note says why not). False with diag filled when one fails. */
bool check_open_engines(Checker *c, const Mech *mech, Diag *diag)
{
    CheckReport *rep = c->rep;
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        if (k == ENGINE_AOT && !c->opt->use_aot) {
            snprintf(rep->note, sizeof rep->note, "aot not compared (not asked for)");
            continue;
        }
        if (k == ENGINE_AOT && !aot_compiler_available()) {
            snprintf(rep->note, sizeof rep->note, "aot not compared: no C compiler found (set CC)");
            continue;
        }
        c->open[k] = engine_open(&c->eng[k], (EngineKind)k, mech, diag);
        rep->engine_used[k] = c->open[k];
        if (!c->open[k])
            return false;
    }
    return true;
}

void check_close_engines(Checker *c)
{
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (c->open[k])
            engine_close(&c->eng[k]);
}
