/* sim_state.c - the state of one simulation, its set-up and its failure messages. */
#include "sim_state.h"

#include "blame.h"
#include "rhs.h"

#include "../base/arena.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

/* The failure at t: status, cause and message start "t = T: WHAT: ". */
void sim_fail(Sim *s, MechrtStatus st, double t, const char *what)
{
    SimResult *res = s->res;
    res->status = ANALYSIS_FAILED;
    res->cause = st;
    res->t_fail = t;
    res->message[0] = '\0';
    msgf(s, "t = %.10g: %s failed: ", t, what);
}

/* Why mechrt_forward_dynamics failed, after sim_fail(). */
void sim_explain_dynamics(Sim *s, MechrtStatus st, const MechrtDynReport *rep, const double *y)
{
    SimResult *res = s->res;
    if (st == MECHRT_ENOTFINITE && y && s->o->model
        && blame_force(s->o->model, s->o->source, res->t_fail, y, y + s->nq, res->message,
                           sizeof res->message))
        return;
    switch (st) {
    case MECHRT_ESING:
        msgf(s, "the augmented matrix is singular: the mass matrix is singular on the motions "
             "the joints allow (reduced mass matrix, direction %d of %d): a body or coordinate "
             "free to move without mass or inertia?", rep->sing_index + 1,
             s->nq - rep->rank);
        break;
    case MECHRT_ENOTFINITE:
        msgf(s, "NaN or infinity in the mass matrix, the forces, the Jacobian, gamma or the "
             "solution (a function evaluated outside its domain, or the motion blew up)");
        break;
    default:
        msgf(s, "%s (an internal error)", mechrt_strerror(st));
        break;
    }
}

/* The dense method's arrays (nr x nq, nq x nq, the SVD): at the start on
   the dense path, at the first dense fallback on the sparse one, which
   otherwise never reads them (at 10 000 coordinates they are gigabytes).
   False when out of memory. */
bool sim_dense_ready(Sim *s)
{
    if (s->work)
        return s->nr == 0 || s->svd;
    size_t n = (size_t)s->nq, m = (size_t)s->nr;
    s->lwork = mechrt_dynamics_workspace_size(s->nq, s->nr);
    s->work = xcalloc(s->lwork, sizeof *s->work);
    s->jac = xcalloc(m * n + 1, sizeof *s->jac);
    s->mass = xcalloc(n * n, sizeof *s->mass);
    s->mass2 = xcalloc(n * n, sizeof *s->mass2);
    s->lqrw = m > 0 ? mechrt_qr_work_len(s->nr, s->nq) : 0;
    s->qrw = xcalloc(s->lqrw + 1, sizeof *s->qrw);
    s->svd = m > 0 ? mechrt_svd_new(s->nr, s->nq) : NULL;
    return m == 0 || s->svd;
}

/* GSL's stepper of each --method. */
static const gsl_odeiv2_step_type *step_type(SimMethod m)
{
    switch (m) {
    case SIM_RK8PD: return gsl_odeiv2_step_rk8pd;
    case SIM_RKF45: return gsl_odeiv2_step_rkf45;
    case SIM_RK4IMP: return gsl_odeiv2_step_rk4imp;
    case SIM_MSBDF: return gsl_odeiv2_step_msbdf;
    }
    return gsl_odeiv2_step_rk8pd;
}

/* The sparse path's kernels are there (and rows to constrain). */
bool sim_sparse_can(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                    const MechrtHostMassNz *mnz)
{
    return k->nh + k->nv > 0 && jnz && jnz->all_nz && jnz->jac.jac_nz && mnz && mnz->mass_nz;
}

/* The sparse path is taken: asked for, or auto on a large mechanism. */
bool sim_sparse_wanted(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                       const MechrtHostMassNz *mnz, const SimOptions *o)
{
    return sim_sparse_can(k, jnz, mnz)
           && (o->linear == ANALYSIS_LINEAR_SPARSE
               || (o->linear == ANALYSIS_LINEAR_AUTO && k->nq > ANALYSIS_DENSE_MAX_NQ));
}

/* Buffers, projection objects and the GSL driver; false when out of memory. */
bool sim_open(Sim *s, const MechrtKernels *k, const MechrtHostJacNz *jnz,
              const MechrtHostMassNz *mnz, const SimOptions *o, SimResult *res)
{
    size_t n = (size_t)k->nq, m = (size_t)(k->nh + k->nv);
    s->inner = k;
    s->o = o;
    s->res = res;
    s->nq = k->nq;
    s->nr = (int)m;
    s->dim = 2 * k->nq + (o->energy ? 1 : 0);
    s->kc = engine_counting(&s->counter, k, &res->calls);
    s->nu = xcalloc(m + 1, sizeof *s->nu);
    s->resid = xcalloc(m + 1, sizeof *s->resid);
    s->lambda = xcalloc(m + 1, sizeof *s->lambda);
    s->dqd = xcalloc(n, sizeof *s->dqd);
    s->qs = xcalloc(n, sizeof *s->qs);
    s->f0 = xcalloc((size_t)s->dim, sizeof *s->f0);
    s->f1 = xcalloc((size_t)s->dim, sizeof *s->f1);
    s->y = xcalloc((size_t)s->dim, sizeof *s->y);
    s->fail_y = xcalloc((size_t)s->dim, sizeof *s->fail_y);
    s->cy = xcalloc((size_t)s->dim, sizeof *s->cy);
    s->cf = xcalloc((size_t)s->dim, sizeof *s->cf);
    s->ya = xcalloc((size_t)s->dim, sizeof *s->ya);
    s->yc = xcalloc((size_t)s->dim, sizeof *s->yc);
    s->fc = xcalloc((size_t)s->dim, sizeof *s->fc);
    s->fa = xcalloc((size_t)s->dim, sizeof *s->fa);
    s->yi = xcalloc((size_t)s->dim, sizeof *s->yi);
    s->fb = xcalloc((size_t)s->dim, sizeof *s->fb);
    s->active = xcalloc(m + 1, sizeof *s->active);
    memset(s->active, 1, m + 1);
    s->active0 = xcalloc(m + 1, sizeof *s->active0);
    s->ys = xcalloc((size_t)s->dim, sizeof *s->ys);
    s->fold = xcalloc(n, sizeof *s->fold);
    s->fold2 = xcalloc(n, sizeof *s->fold2);
    s->fold_rows = xcalloc(m + 1, sizeof *s->fold_rows);
    s->dyn = o->dyn;
    s->dyn.active = s->active;
    if (sim_sparse_wanted(k, jnz, mnz, o)) {
        s->jnz = jnz;
        s->mnz = mnz;
        s->kkt = mechrt_host_kkt_new(k->nq, (int)m, jnz, mnz);
        if (!s->kkt)
            return false;
        s->res->sparse = true;
        s->sx = xcalloc(n + m, sizeof *s->sx);
        s->mq = xcalloc(n, sizeof *s->mq);
        s->sw = xcalloc(2 * (n + m), sizeof *s->sw);
        s->sphi = xcalloc(m, sizeof *s->sphi);
        s->sg = xcalloc(m, sizeof *s->sg);
        s->sforce = xcalloc(n, sizeof *s->sforce);
        s->smass = xcalloc((size_t)mnz->nnz + 1, sizeof *s->smass);
    }
    if (!s->kkt && !sim_dense_ready(s))
        return false;
    size_t watched = s->kkt ? (size_t)jnz->jac.nnz : m * n;   /* watch.c: Phi_q twice */
    s->wjac = xcalloc(watched + 1, sizeof *s->wjac);
    s->wjac0 = xcalloc(watched + 1, sizeof *s->wjac0);
    s->wturn = xcalloc(3 * m + 1, sizeof *s->wturn);
    /* W's error must not steer the step: its absolute scale is huge */
    double *scale = xcalloc((size_t)s->dim, sizeof *scale);
    for (int i = 0; i < s->dim; i++)
        scale[i] = i < 2 * s->nq ? 1.0 : 1e300;
    double span = fabs(o->t1 - o->t0), h0 = span / o->steps / 16;
    s->sys = (gsl_odeiv2_system){sim_rhs, sim_jacobian, (size_t)s->dim, s};
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    s->drv = gsl_odeiv2_driver_alloc_scaled_new(&s->sys, step_type(o->method),
                                                o->t1 > o->t0 ? h0 : -h0, o->atol, o->rtol,
                                                1.0, 0.0, scale);
    gsl_set_error_handler(old);
    free(scale);
    return s->drv != NULL;
}

/* Frees what sim_open made, the sparse path's counts kept in res. */
void sim_close(Sim *s)
{
    free(s->work), free(s->jac), free(s->nu), free(s->resid), free(s->lambda);
    free(s->dqd), free(s->mass), free(s->mass2), free(s->qs), free(s->f0), free(s->f1);
    free(s->y), free(s->fail_y), free(s->active), free(s->active0), free(s->ys);
    free(s->fold), free(s->fold2), free(s->fold_rows);
    free(s->cy), free(s->cf), free(s->ya), free(s->fa), free(s->fb), free(s->yi), free(s->yc), free(s->fc);
    free(s->qrw);
    free(s->wjac), free(s->wjac0), free(s->wturn);
    mechrt_svd_free(s->svd);
    if (s->kkt)
        mechrt_host_kkt_counts(s->kkt, &s->res->kkt_fresh, &s->res->kkt_refactored);
    mechrt_host_kkt_free(s->kkt);
    free(s->sx), free(s->mq), free(s->sw), free(s->sphi), free(s->sg), free(s->sforce), free(s->smass);
    if (s->drv)
        gsl_odeiv2_driver_free(s->drv);
}

