/* run_state.h - the state of one run, shared by its pieces (kin/). */
#ifndef MECHC_KIN_RUN_STATE_H
#define MECHC_KIN_RUN_STATE_H

#include "run.h"

#include "../analysis/common.h"
#include "../analysis/redundant.h"
#include "../dyn/inverse.h"

/* States before the current one that the rank corrector's predictor
   extrapolates the acceleration from (a cubic through four). */
#define RUN_HISTORY 3

typedef struct Run {
    const Model *m;
    const MechrtKernels *k;
    const MechrtHostJacNz *jnz;  /* the kernels' sparse Jacobian, or NULL */
    const RunOptions *o;
    RunResult *res;
    int nq, nr;
    double *q, *qd, *qdd;    /* one block of 3 nq: qd == q + nq, qdd == q + 2 nq */
    double *work;
    size_t lwork;
    MechrtHostSparse *sp;    /* the sparse path's factorisation; NULL: dense (with
                                velocity-level rows: the sparse host's) */
    bool sparse;             /* the sparse path (RunOptions.linear) */
    MechrtLup *lup;          /* the dense path's pattern LU (run_lup_new); NULL: lu.c's */
    /* holonomic stepping: the start of the last step (sq | sqd | sqdd, laid
       out like q | qd | qdd), the start of the interval being subdivided
       (iq, the same layout), the end of the previous subdivision level (lq)
       and a failed step's iterate (fq) */
    double *sq, *sqd, *sqdd, *iq, *lq, *fq, *rq;
    /* through singular positions (rank_step): the QR corrector's workspace
       (allocated at the first use), and the accelerations of the last RUN_HISTORY
       trusted states before the current one, for the predictor */
    double *rk_work;
    size_t rk_lwork;
    int hist_n;
    double hist_t[RUN_HISTORY];
    double *hist_qdd;       /* RUN_HISTORY nq: entry 0 the latest */
    /* run_analysis_forces: the state callback with lambda, and inverse
       dynamics' workspace and multipliers */
    RunForcesFn fstate;
    Inverse inv;
    /* more rows than coordinates: the run is on red's kept rows (m, k,
       jnz are its), red checks the others at every state */
    Redundant *red;
    /* a nearly singular stretch in progress */
    bool episode;
    double ep_start, ep_end, ep_worst, ep_worst_t;
} Run;

/* Appends to res->message, truncating quietly at its size. */
#define msgf(r, ...) analysis_msgf((r)->res->message, sizeof (r)->res->message, __VA_ARGS__)

/* A note or warning ("FILE: KIND: ...") to RunOptions.notes, when there is one. */
void run_notef(const Run *r, const char *kind, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* one or many, by n. */
const char *run_plural(int n, const char *one, const char *many);

#endif
