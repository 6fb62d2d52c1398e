/* checker.h - the state of one `mechc check` run, shared by its pieces (verify/). */
#ifndef MECHC_CHECKER_H
#define MECHC_CHECKER_H

#include "check.h"

#include "../base/arena.h"
#include "../../runtime/host/mechrt_host.h"

#include <gsl/gsl_eigen.h>

enum { QTY_PHI, QTY_JAC, QTY_NU, QTY_GAMMA, QTY_COUNT = CHECK_QTY_COUNT, PAIR_COUNT = CHECK_PAIR_COUNT };

/* The ladder of finite-difference steps: index i is the step
   h * pi^(FD_COARSE - i), the default h at FD_COARSE, pi^2 h first, h/pi^8
   last. The ratio is irrational so that no step is a whole multiple of
   another: a row oscillating a whole number of times over one step (which
   the difference cannot see) does not do so over the next ones, and
   differences that agree across steps are not an aliasing artefact. With
   a ratio of 4, sin(10^4 x) at a qd that fits 10 periods in the default
   step settled, wrongly, at 16h, 4h and h. */
enum { FD_COARSE = 2, FD_FINE = 8, FD_STEPS = FD_COARSE + 1 + FD_FINE };
#define FD_RATIO 3.14159265358979323846
/* Neighbouring steps settle when they agree within this part of the tolerance. */
#define FD_SETTLE 0.5
/* Points cached per function of one variable: the four of gsl_deriv_central
   at each step of the ladder, shared by the rows of one column, and room
   for its adaptive ones. */
enum { FD_CACHE = 4 * FD_STEPS + 8 };

extern const EngineKind check_pair_engines[PAIR_COUNT][2];

/* The state of one check run. */
typedef struct Checker {
    const Model *m;
    const CheckOptions *opt;
    CheckReport *rep;
    int nq, nh, nv, nr;
    Engine eng[ENGINE_KIND_COUNT];
    bool open[ENGINE_KIND_COUNT];
    double *out[ENGINE_KIND_COUNT][QTY_COUNT];  /* each engine's results at the sample */
    double *base;                               /* the assembled state */
    double *q, *qd, t;                          /* the sample */
    int sample;
    double *qw, *qdw;                           /* perturbed copies */
    double *gamma0;                             /* fault hook scratch */
    double *save_q[3], *save_qd[3];             /* state of each FD item's worst */
    double *d2[5];                              /* second-difference points */
    double *ladder[FD_STEPS];                   /* gamma's second differences at each step */
    bool ladder_have[FD_STEPS];
    double *vec;                                /* one vector of rows */
    bool dyn;                                   /* the file has masses: */
    double *mass[ENGINE_KIND_COUNT];            /* each engine's M (nq*nq) */
    double *force[ENGINE_KIND_COUNT];           /* and Q (nq) at the sample */
    double *mass_nz[ENGINE_KIND_COUNT];         /* and M's nonzeros (engine_mass_nz) */
    double *mw, *mw2, *qv, *qv_fd;              /* M elsewhere; Q's velocity terms */
    gsl_eigen_symm_workspace *eigen;
    double *scratch;                            /* a VecFn's cache (FD_CACHE vectors) */
    /* the sparse comparisons (CheckOptions.linear) */
    bool sparse;
    const MechrtHostJacNz *jnz[ENGINE_KIND_COUNT];  /* jit's and aot's jac_nz */
    bool has_nz[ENGINE_KIND_COUNT];
    int nnz;
    int ngroups;
    int *group_start, *group_cols;              /* the column groups, CSR */
    int *col_start, *col_ent;                   /* each column's entries */
    int *ent;                                   /* nr: the group's entry in each row, or -1 */
    Arena buffers;                              /* owns every array above */
} Checker;

/* |value - ref| / (1 + |ref|); 0 for two NaNs, +inf for one. */
double check_rel_error(double value, double ref);

/* Keeps (value, ref) in item `what` when it is the worst so far. step: of
   the reference's finite difference (0: exact, or an engine). */
void check_record(Checker *c, int what, int row, int col, double value, double ref, double step);

/* Every working array, zero-filled, from c->buffers. */
void check_take_buffers(Checker *c);

#endif
