/* sim_state.h - the state of one simulation, its set-up and its failure messages (dyn/). */
#ifndef MECHC_DYN_SIM_STATE_H
#define MECHC_DYN_SIM_STATE_H

#include "sim.h"

#include "../analysis/common.h"

#include <gsl/gsl_odeiv2.h>

typedef struct Sim {
    const MechrtKernels *inner;  /* the caller's kernels */
    EngineCounter counter;
    MechrtKernels kc;            /* the same, counted (engine_counting) */
    const SimOptions *o;
    SimResult *res;
    int nq, nr, dim;             /* dim: 2 nq (+1 with energy) */
    double *work;                /* mechrt_forward_dynamics' workspace */
    size_t lwork;
    double *qrw;                 /* the projections' QR workspace (nr x nq) */
    size_t lqrw;
    MechrtSvd *svd;              /* the same near a rank drop */
    double *jac, *nu, *resid, *dqd, *lambda, *mass, *mass2, *qs, *f0, *f1, *y;
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *drv;
    MechrtStatus fail_status;    /* set by the right-hand side */
    double fail_t;
    MechrtDynReport fail_rep;
    double *fail_y;              /* q, qd there (2 nq) */
    double e0;                   /* E at t0 */
    MechrtDynOptions dyn;        /* the caller's, with the rows of this step */
    unsigned char *active;       /* nr: the rows kept during this step */
    /* sim_settle: the state and rows before it; fresh_f: it moved the
       state beyond SIM_FRESH_F_SHARE of the tolerance or changed the rows,
       so the next step's first stage takes f there, not GSL's f at the
       unprojected end of the last step */
    double *ys;
    unsigned char *active0;
    bool fresh_f;
    /* fold.c: qdd with every row minus with the step's rows at its start,
       added at its stages (fold_on); the scratch of its solves */
    double *fold, *fold2;
    unsigned char *fold_rows;
    bool fold_on;
    /* the sparse path (kkt NULL: dense) */
    MechrtHostKkt *kkt;
    const MechrtHostJacNz *jnz;
    const MechrtHostMassNz *mnz;
    double *sx, *sw, *sphi, *sg, *sforce, *smass;  /* nq + nr; 2 (nq + nr); nr; nr; nq; mass nnz */
    bool all_active;             /* every row kept in this step */
    double *mq, mq_t;            /* (q, t) of the factors of M's augmented matrix */
    bool mq_valid;               /* ... with this step's rows */
    bool vel_ready;              /* Phi_q's nonzeros and nu at the state, for the
                                    velocity projection */
    /* the last right side, (t, y) -> f, valid while the rows stay: GSL
       evaluates f at a step's start, where an output state or the
       interpolant's end has just solved it */
    double *cy, *cf, ct;
    bool cache_ok;
    double *yc, *fc, *ya, *fa;   /* --interpolate: the last two steps' starts, f there */
    double *fb, *yi;             /* f at the step's end, the output state */
    /* watch.c: Phi_q at the last two step ends (dense, or the sparse
       path's nonzeros), the rows' turns between them (3 nr: and room);
       the collapse test's window */
    double *wjac, *wjac0, *wturn;
    bool whave, wvalid;          /* one gradient taken; two */
    long wsteps, wrejected0;     /* steps in the window; rejections before it */
    double wt0, hmax;            /* its start; the largest step so far */
} Sim;

/* Appends to res->message, truncating quietly. */
#define msgf(s, ...) analysis_msgf((s)->res->message, sizeof (s)->res->message, __VA_ARGS__)

/* The sparse path's kernels are there (and rows to constrain). */
bool sim_sparse_can(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                    const MechrtHostMassNz *mnz);

/* The sparse path is taken: asked for, or auto on a large mechanism. */
bool sim_sparse_wanted(const MechrtKernels *k, const MechrtHostJacNz *jnz,
                       const MechrtHostMassNz *mnz, const SimOptions *o);

/* Buffers, projection objects and the GSL driver; false when out of memory. */
bool sim_open(Sim *s, const MechrtKernels *k, const MechrtHostJacNz *jnz,
              const MechrtHostMassNz *mnz, const SimOptions *o, SimResult *res);
void sim_close(Sim *s);

/* The dense method's arrays, allocated at the first need; false when out of memory. */
bool sim_dense_ready(Sim *s);

/* The failure at t: status, cause and message start "t = T: WHAT: ". */
void sim_fail(Sim *s, MechrtStatus st, double t, const char *what);

/* Why mechrt_forward_dynamics failed at y (q, qd; NULL: unknown), after
   sim_fail(). */
void sim_explain_dynamics(Sim *s, MechrtStatus st, const MechrtDynReport *rep, const double *y);

#endif
