/* testout.h - the four kernel outputs (Phi, Phi_q dense, nu, gamma) of one evaluation, sized for a model. */
#ifndef MECHC_TESTOUT_H
#define MECHC_TESTOUT_H

#include <stdlib.h>

#include "../generator/base/arena.h"
#include "../generator/model/model.h"

typedef struct Out {
    double *phi, *jac, *nu, *gamma;
} Out;

static inline void out_alloc(Out *o, const Model *m)
{
    o->phi = xcalloc((size_t)m->nh + 1, sizeof(double));
    o->jac = xcalloc((size_t)m->nr * (size_t)m->nq + 1, sizeof(double));
    o->nu = xcalloc((size_t)m->nr + 1, sizeof(double));
    o->gamma = xcalloc((size_t)m->nr + 1, sizeof(double));
}

static inline void out_free(Out *o)
{
    free(o->phi), free(o->jac), free(o->nu), free(o->gamma);
}

#endif
