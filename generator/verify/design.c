/* design.c - the check of dPhi/dp: finite differences in the design parameters, engines against each other. */
#include "design.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>

/* (Phi(p + h e_j) - Phi(p - h e_j)) / 2h of the jit at the sample into d
   (nh), with the model's design moved and put back (every engine reads it). */
static void central(Checker *c, int j, double h, double *plus, double *d)
{
    double *p = c->m->dag.param_values, pj = p[j];
    const Engine *e = &c->eng[ENGINE_JIT];
    p[j] = pj + h;
    engine_phi(e, c->q, c->t, plus);
    p[j] = pj - h;
    engine_phi(e, c->q, c->t, d);
    p[j] = pj;
    for (int r = 0; r < c->nh; r++)
        d[r] = (plus[r] - d[r]) / (2 * h);
}

/* Every value of the sensitivity functions fn of engine k at the sample,
   in one array (design_arrays' order); its length in *n. */
static double *sens_values(Checker *c, int k, DesignFn fn, size_t *n)
{
    const NodeId *from[DESIGN_Y_COUNT];
    size_t count[DESIGN_Y_COUNT];
    const Engine *e = &c->eng[k];
    int arrays = design_arrays(&e->mech->kin, fn, from, count);
    *n = 0;
    for (int i = 0; i < arrays; i++)
        *n += count[i];
    double *all = xcalloc(*n + 1, sizeof *all), *out[DESIGN_Y_COUNT], *at = all;
    for (int i = 0; i < arrays; i++, at += count[i - 1])
        out[i] = at;
    engine_design(e, fn, c->q, c->qd, c->t, out);
    return all;
}

/* Engine k's phi_p_nz against the other engine's dense phi_p, entry by
   entry of the pattern (the dense zeros elsewhere are the graph's),
   recorded with the pair's phi_p, k's value first when first. */
static void compare_phi_p_nz(Checker *c, int pair, EngineKind k, const double *dense, bool first)
{
    const DesignKin *dk = &c->eng[k].mech->kin.design;
    size_t n, np = (size_t)c->m->np;
    double *nz = sens_values(c, k, DESIGN_PHI_P_NZ, &n);
    for (int e = 0; e < dk->p_nnz; e++) {
        const JacEntry *at = &dk->p_nz[e];
        double d = dense[(size_t)at->row * np + (size_t)at->col];
        check_record(c, CHECK_PHI_P_PAIR_FIRST + pair, at->row, at->col, first ? nz[e] : d,
                     first ? d : nz[e], 0.0);
    }
    free(nz);
}

/* sens_v, sens_g, sens_y and phi_p_nz of every pair of engines. */
static void compare_sens(Checker *c)
{
    for (int pair = 0; pair < PAIR_COUNT; pair++) {
        EngineKind a = check_pair_engines[pair][0], b = check_pair_engines[pair][1];
        if (!c->open[a] || !c->open[b])
            continue;
        c->rep->items[CHECK_SENS_PAIR_FIRST + pair].checked = true;
        for (int fn = DESIGN_V; fn < DESIGN_FN_COUNT; fn++) {
            size_t n;
            double *va = sens_values(c, a, (DesignFn)fn, &n), *vb = sens_values(c, b, (DesignFn)fn, &n);
            for (size_t i = 0; i < n; i++)
                check_record(c, CHECK_SENS_PAIR_FIRST + pair, -1, -1, va[i], vb[i], 0.0);
            free(va), free(vb);
        }
    }
}

void check_design(Checker *c)
{
    const Model *m = c->m;
    size_t n = (size_t)m->nh * (size_t)m->np;
    double *phi_p[ENGINE_KIND_COUNT] = {0};
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (c->open[k]) {
            phi_p[k] = xcalloc(n + 1, sizeof(double));
            engine_phi_p(&c->eng[k], c->q, c->t, phi_p[k]);
        }
    size_t nh = (size_t)m->nh + 1;
    double *w = xcalloc(3 * nh, sizeof *w), *d1 = w + nh, *d2 = d1 + nh;
    for (int j = 0; j < m->np; j++) {
        /* central differences are O(h^2); (4 D(h/2) - D(h)) / 3 is O(h^4) */
        double h = c->opt->fd_step * fmax(1.0, fabs(m->dag.param_values[j]));
        central(c, j, h, w, d1);
        central(c, j, h / 2, w, d2);
        for (int r = 0; r < m->nh; r++)
            check_record(c, CHECK_PHI_P_FD, r, j, phi_p[ENGINE_JIT][(size_t)r * (size_t)m->np + (size_t)j],
                         (4 * d2[r] - d1[r]) / 3, h);
    }
    if (m->nh == 0)
        c->rep->items[CHECK_PHI_P_FD].checked = true;
    for (int pair = 0; pair < PAIR_COUNT; pair++) {
        EngineKind a = check_pair_engines[pair][0], b = check_pair_engines[pair][1];
        if (!phi_p[a] || !phi_p[b])
            continue;
        for (size_t i = 0; i < n; i++)
            check_record(c, CHECK_PHI_P_PAIR_FIRST + pair, (int)(i / (size_t)m->np),
                         (int)(i % (size_t)m->np), phi_p[a][i], phi_p[b][i], 0.0);
        compare_phi_p_nz(c, pair, a, phi_p[b], true);
        compare_phi_p_nz(c, pair, b, phi_p[a], false);
        if (n == 0)
            c->rep->items[CHECK_PHI_P_PAIR_FIRST + pair].checked = true;
    }
    free(w);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        free(phi_p[k]);
    compare_sens(c);
}
