/* kkt.c - the sparse path of sim: accelerations from the augmented matrix [M Phi_A^T; Phi_A 0] on KLU. */
#include "kkt.h"

#include <math.h>
#include <string.h>

/* The right side's solve is refined once (mechrt_host_kkt_solve_refined)
   where [M Phi_A^T; Phi_A 0]'s pivot spread exceeds this: near a rank
   drop, where the multipliers dwarf the accelerations. Elsewhere (A02:
   spreads of 40 to 2000) one solve is as accurate. */
#define SIM_KKT_REFINE_SPREAD 1e4

/* y = Phi_q x over the Jacobian's nonzeros (nr rows). */
void sim_sparse_jac_times(const Sim *s, const double *x, double *y)
{
    const double *v = mechrt_host_kkt_jac(s->kkt);
    memset(y, 0, (size_t)s->nr * sizeof *y);
    for (int e = 0; e < s->jnz->jac.nnz; e++)
        y[s->jnz->jac.row[e]] += v[e] * x[s->jnz->jac.col[e]];
}

/* qd^T M x over M's nonzeros vals. */
double sim_sparse_mass_form(const Sim *s, const double *vals, const double *qd,
                               const double *x)
{
    double sum = 0;
    for (int e = 0; e < s->mnz->nnz; e++)
        sum += qd[s->mnz->row[e]] * vals[e] * x[s->mnz->col[e]];
    return sum;
}

/* M's nonzeros at q into vals (counted). */
void sim_sparse_mass(Sim *s, const double *q, double *vals)
{
    s->res->calls.mass_nz++;
    s->mnz->mass_nz(s->mnz->ctx, q, vals);
}

bool sim_all_finite(int n, const double *v)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

/* Phi, Phi_q's nonzeros, nu and gamma at the state (one all_nz call), and
   with dynamics M's nonzeros and Q. */
MechrtStatus sim_sparse_eval(Sim *s, const double *q, const double *qd, double t,
                                bool dynamics)
{
    double *jac = mechrt_host_kkt_jac(s->kkt);
    s->res->calls.all_nz++;
    s->jnz->all_nz(s->jnz->jac.ctx, q, qd, t, s->sphi, jac, s->nu, s->sg);
    if (!sim_all_finite(s->jnz->jac.nnz, jac) || !sim_all_finite(s->nr, s->nu) || !sim_all_finite(s->nr, s->sg))
        return MECHRT_ENOTFINITE;
    if (!dynamics)
        return MECHRT_OK;
    double *mass = mechrt_host_kkt_mass(s->kkt);
    sim_sparse_mass(s, q, mass);
    s->kc.force(s->kc.ctx, q, qd, t, s->sforce);
    return sim_all_finite(s->mnz->nnz, mass) && sim_all_finite(s->nq, s->sforce) ? MECHRT_OK
                                                                        : MECHRT_ENOTFINITE;
}

/* [M Phi_A^T; Phi_A 0] factored at (q, t) with the step's rows, M's and
   Phi_q's nonzeros at q in the buffers; skipped where the factors are
   already at the same q and t with these rows (the matrix depends on
   nothing else): the velocity projection's serve the step's first stage,
   its retries after a rejection, and the output state's solve. */
MechrtStatus sim_sparse_mass_factor(Sim *s, const double *q, double t)
{
    size_t bytes = (size_t)s->nq * sizeof *q;
    if (s->mq_valid && t == s->mq_t && memcmp(q, s->mq, bytes) == 0) {
        s->res->kkt_reused++;
        return MECHRT_OK;
    }
    s->mq_valid = false;
    MechrtStatus st = mechrt_host_kkt_factor(s->kkt, MECHRT_KKT_MASS,
                                             s->all_active ? NULL : s->active, s->nr,
                                             s->o->dyn.pivot_tol);
    if (st == MECHRT_OK) {
        memcpy(s->mq, q, bytes);
        s->mq_t = t;
        s->mq_valid = true;
    }
    return st;
}

/* qdd (and lambda, nr, when not NULL) from [M Phi_A^T; Phi_A 0] with the
   rows of active (NULL: all), gamma stabilised as dyn_eval does. */
MechrtStatus sim_sparse_accel(Sim *s, const double *q, const double *qd, double t,
                                 const unsigned char *active, double *qdd, double *lambda)
{
    int n = s->nq, m = s->nr;
    const MechrtDynOptions *o = &s->o->dyn;
    MechrtStatus st = sim_sparse_eval(s, q, qd, t, true);
    if (st != MECHRT_OK)
        return st;
    if (o->baumgarte_alpha != 0 || o->baumgarte_beta != 0) {
        sim_sparse_jac_times(s, qd, s->resid);
        for (int i = 0; i < m; i++)
            s->sg[i] -= 2 * o->baumgarte_alpha * (s->resid[i] - s->nu[i])
                      + (i < s->inner->nh ? o->baumgarte_beta * o->baumgarte_beta * s->sphi[i] : 0);
    }
    st = sim_sparse_mass_factor(s, q, t);     /* active is the step's rows, or all of them */
    if (st != MECHRT_OK)
        return st;
    memcpy(s->sx, s->sforce, (size_t)n * sizeof *s->sx);
    for (int i = 0; i < m; i++)
        s->sx[n + i] = !active || active[i] ? s->sg[i] : 0;
    st = mechrt_host_kkt_spread(s->kkt, MECHRT_KKT_MASS) > SIM_KKT_REFINE_SPREAD
             ? mechrt_host_kkt_solve_refined(s->kkt, MECHRT_KKT_MASS, s->sx, s->sw)
             : mechrt_host_kkt_solve(s->kkt, MECHRT_KKT_MASS, s->sx);
    if (st != MECHRT_OK)
        return st;
    memcpy(qdd, s->sx, (size_t)n * sizeof *qdd);
    if (lambda)
        memcpy(lambda, s->sx + n, (size_t)m * sizeof *lambda);
    return MECHRT_OK;
}

