/* design.c - the derivatives in the design parameters: Phi_p and what the sensitivities of velocities, accelerations and outputs need. */
#include "kinematics.h"

#include "../base/arena.h"
#include "diff.h"

/* n x cols nodes, d(e_r)/d(variable c) for each row's e_r. */
typedef NodeId (*ByFn)(Differ *df, NodeId e, int j);

static NodeId *partials(Model *m, Differ *df, const NodeId *e, int n, int cols, ByFn by)
{
    NodeId *out = arena_alloc_array(&m->arena, (size_t)n * (size_t)cols + 1, sizeof *out);
    for (int r = 0; r < n && !m->dag.overflow; r++)
        for (int c = 0; c < cols; c++)
            out[(size_t)r * (size_t)cols + (size_t)c] = by(df, e[r], c);
    return out;
}

/* The outputs' f, D f, D(D f) by q, p; by q, qd, p; by q, qd, p. */
static void output_partials(Model *m, Differ *df, DesignKin *dk)
{
    int n = m->nout, nq = m->nq, np = m->np;
    NodeId *f = arena_alloc_array(&m->arena, (size_t)n + 1, sizeof *f);
    NodeId *d1 = arena_alloc_array(&m->arena, (size_t)n + 1, sizeof *d1);
    NodeId *d2 = arena_alloc_array(&m->arena, (size_t)n + 1, sizeof *d2);
    for (int k = 0; k < n; k++) {
        f[k] = m->outputs[k].expr;
        d1[k] = diff_total(df, f[k]);
        d2[k] = diff_total(df, d1[k]);
    }
    const NodeId *of[DESIGN_Y_COUNT] = {f, f, d1, d1, d1, d2, d2, d2};
    const ByFn by[DESIGN_Y_COUNT] = {diff_by_q, diff_by_p, diff_by_q, diff_by_qd, diff_by_p,
                                     diff_by_q, diff_by_qd, diff_by_p};
    for (int k = 0; k < DESIGN_Y_COUNT; k++)
        dk->y[k] = partials(m, df, of[k], n, design_y_by_p(k) ? np : nq, by[k]);
}

/* Phi_p's structural nonzeros, row-major (a placeholder slot when none). */
static void collect_p_nz(Model *m, const NodeId *phi_p, DesignKin *dk)
{
    size_t n = (size_t)m->nh * (size_t)m->np;
    int count = 0;
    for (size_t i = 0; i < n; i++)
        count += phi_p[i] != DAG_ZERO;
    dk->p_nz = arena_alloc_array(&m->arena, (size_t)count + 1, sizeof *dk->p_nz);
    dk->p_nz_values = arena_alloc_array(&m->arena, (size_t)count + 1, sizeof *dk->p_nz_values);
    dk->p_nz[0] = (JacEntry){0, 0, DAG_ZERO};
    dk->p_nz_values[0] = DAG_ZERO;
    dk->p_nnz = 0;
    for (size_t i = 0; i < n; i++)
        if (phi_p[i] != DAG_ZERO) {
            dk->p_nz_values[dk->p_nnz] = phi_p[i];
            dk->p_nz[dk->p_nnz++] = (JacEntry){(int)(i / (size_t)m->np),
                                               (int)(i % (size_t)m->np), phi_p[i]};
        }
}

bool design_build(Model *m, Kinematics *kin, Diag *diag)
{
    Differ df;
    differ_init(&df, &m->dag, m->nq);
    int nh = m->nh, nq = m->nq, np = m->np;
    DesignKin *dk = &kin->design;
    kin->phi_p = partials(m, &df, kin->phi, nh, np, diff_by_p);
    NodeId *v = arena_alloc_array(&m->arena, (size_t)nh + 1, sizeof *v);
    for (int r = 0; r < nh; r++)
        v[r] = diff_total(&df, kin->phi[r]);
    dk->v_q = partials(m, &df, v, nh, nq, diff_by_q);
    dk->v_p = partials(m, &df, v, nh, np, diff_by_p);
    dk->g_q = partials(m, &df, kin->gamma, nh, nq, diff_by_q);
    dk->g_qd = partials(m, &df, kin->gamma, nh, nq, diff_by_qd);
    dk->g_p = partials(m, &df, kin->gamma, nh, np, diff_by_p);
    output_partials(m, &df, dk);
    if (!m->dag.overflow)
        collect_p_nz(m, kin->phi_p, dk);
    differ_free(&df);
    return dag_check_limit(&m->dag, diag);
}

int design_arrays(const Kinematics *kin, DesignFn fn, const NodeId *from[DESIGN_Y_COUNT],
                  size_t count[DESIGN_Y_COUNT])
{
    const Model *m = kin->model;
    const DesignKin *dk = &kin->design;
    size_t nq = (size_t)m->nq, np = (size_t)m->np, nh = (size_t)m->nh, ny = (size_t)m->nout;
    switch (fn) {
    case DESIGN_PHI_P:
        from[0] = kin->phi_p, count[0] = nh * np;
        return 1;
    case DESIGN_V:
        from[0] = dk->v_q, count[0] = nh * nq;
        from[1] = dk->v_p, count[1] = nh * np;
        return 2;
    case DESIGN_G:
        from[0] = dk->g_q, count[0] = nh * nq;
        from[1] = dk->g_qd, count[1] = nh * nq;
        from[2] = dk->g_p, count[2] = nh * np;
        return 3;
    case DESIGN_PHI_P_NZ:
        from[0] = dk->p_nz_values, count[0] = dk->p_nnz > 0 ? (size_t)dk->p_nnz : 1;
        return 1;
    case DESIGN_Y:
    case DESIGN_FN_COUNT:
        break;
    }
    for (int i = 0; i < DESIGN_Y_COUNT; i++)
        from[i] = dk->y[i], count[i] = ny * (design_y_by_p(i) ? np : nq);
    return DESIGN_Y_COUNT;
}
