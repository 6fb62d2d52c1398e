/* checker.c - the check's state: recording the worst error of each item, the working arrays. */
#include "checker.h"

#include <math.h>
#include <string.h>

const EngineKind check_pair_engines[PAIR_COUNT][2] = {
    {ENGINE_JIT, ENGINE_GENERIC}, {ENGINE_JIT, ENGINE_AOT}, {ENGINE_GENERIC, ENGINE_AOT},
};

double check_rel_error(double value, double ref)
{
    if (isnan(value) && isnan(ref))
        return 0.0;
    if (!isfinite(value) || !isfinite(ref))
        return value == ref ? 0.0 : INFINITY;
    return fabs(value - ref) / (1.0 + fabs(ref));
}

void check_record(Checker *c, int what, int row, int col, double value, double ref, double step)
{
    CheckItem *it = &c->rep->items[what];
    double err = check_rel_error(value, ref);
    if (it->checked && !(err > it->error))
        return;
    it->checked = true;
    it->error = err;
    it->row = row;
    it->col = col;
    it->value = value;
    it->reference = ref;
    it->sample = c->sample;
    it->t = c->t;
    it->step = step;
    if (what < CHECK_PAIR_FIRST) {
        memcpy(c->save_q[what], c->q, (size_t)c->nq * sizeof *c->q);
        memcpy(c->save_qd[what], c->qd, (size_t)c->nq * sizeof *c->qd);
    }
}

static double *take(Checker *c, size_t n)
{
    return arena_alloc_array(&c->buffers, n, sizeof(double));
}

void check_take_buffers(Checker *c)
{
    size_t nq = (size_t)c->nq, nr = (size_t)c->nr, nvec = (size_t)(c->nh > c->nv ? c->nh : c->nv) + 1;
    arena_init(&c->buffers);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        c->out[k][QTY_PHI] = take(c, nvec);
        c->out[k][QTY_JAC] = take(c, c->sparse ? (size_t)c->nnz + 1 : nr * nq);
        c->out[k][QTY_NU] = take(c, nr);
        c->out[k][QTY_GAMMA] = take(c, nr);
    }
    c->base = take(c, nq);
    c->q = take(c, nq);
    c->qd = take(c, nq);
    c->qw = take(c, nq);
    c->qdw = take(c, nq);
    for (int k = 0; k < 3; k++) {
        c->save_q[k] = take(c, nq);
        c->save_qd[k] = take(c, nq);
    }
    c->gamma0 = take(c, nr);
    for (int k = 0; k < 5; k++)
        c->d2[k] = take(c, nvec);
    for (int k = 0; k < FD_STEPS; k++)
        c->ladder[k] = take(c, nvec);
    c->vec = take(c, nvec);
    c->scratch = take(c, FD_CACHE * nvec);
    for (int k = 0; k < ENGINE_KIND_COUNT && c->dyn; k++) {
        c->mass[k] = take(c, nq * nq);
        c->force[k] = take(c, nq);
        c->mass_nz[k] = take(c, (size_t)engine_mass_nz(&c->eng[ENGINE_JIT])->nnz + 1);
    }
    if (c->dyn) {
        c->mw = take(c, nq * nq);
        c->mw2 = take(c, nq * nq);
        c->qv = take(c, nq);
        c->qv_fd = take(c, nq);
        c->eigen = gsl_eigen_symm_alloc(nq);
    }
}
