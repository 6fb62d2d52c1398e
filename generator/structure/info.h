/* info.h - the `mechc info` report: counts, assembly, rank, redundant rows, singularity, integrability. */
#ifndef MECHC_INFO_H
#define MECHC_INFO_H

#include "../pipeline/pipeline.h"
#include "../analysis/assemble.h"
#include "integrability.h"
#include "involutive.h"
#include "../analysis/options.h"

#include <stdbool.h>

typedef struct InfoRow {
    bool driver;            /* a driver row */
    bool redundant;         /* depends on the rows before it */
    Integrability integ;    /* velocity rows only */
} InfoRow;

/* What a rank deficiency of the holonomic rows at the configuration means. */
typedef enum Singularity {
    SING_NONE,          /* full row rank */
    SING_POSITION,      /* the undriven rows lose rank here only: dead-centre, toggle, branch point */
    SING_DRIVERS,       /* the undriven rows are independent, the drivers depend on them here */
    SING_PERMANENT,     /* the undriven rows have the same deficiency at nearby configurations */
    SING_UNKNOWN,       /* not classified (sampling failed, or not computed) */
} Singularity;

extern const char *const info_singularity_names[];  /* "none", "position", ... */

/* Where `info --at` / `--state` takes the rank: the motion followed from
   t = 0 to t, or a state given coordinate by coordinate. */
typedef struct InfoAt {
    bool follow;            /* assemble at t = 0, then follow the motion to t */
    const double *q;        /* or this state (nq values), used as it is */
} InfoAt;

/* Null-space directions kept for the report, at most. */
#define INFO_MAX_DIRECTIONS 64

/* The rank drop at a given state against the generic rank. */
typedef struct InfoState {
    bool asked;             /* --at or --state */
    bool given;             /* the state came from --state */
    int steps;              /* --at: steps taken from t = 0 (substeps included) */
    bool reached;           /* --at: the motion was followed to t */
    double residual;        /* ||Phi||_inf of the holonomic rows at the state */
    int ref_rank;           /* rank of the holonomic rows at the reference:
                               the largest at t = 0, at the last state Newton
                               reached before t (--at) and here; -1 */
    int drop;               /* ref_rank - rank, -1 when a rank is missing */
    int ndependent;         /* rows dependent here, independent at the reference */
    int *dependent;         /* their model row indices */
    int nnull;              /* null-space dimension of the holonomic rows here (QR) */
    int nshown;             /* vectors kept in null, <= INFO_MAX_DIRECTIONS */
    double *null;           /* nshown x nq: direction k is 1 at free[k], 0 at
                               the other free coordinates */
    int *free_coord;        /* nshown */
} InfoState;

typedef struct InfoReport {
    const Model *model;
    double t;               /* the time of the analysis (0) */
    /* counts */
    int nq, nh, nv, nr;
    int nh_drivers, nv_drivers;
    int dof;                /* nq - nh - nv */
    int mobility;           /* nq - rows without drivers */
    /* assembly */
    double *q;              /* the assembled configuration, or the best
                               point found (nq, malloc'd) */
    AssembleResult assembly;
    bool assembled;         /* converged, or nothing to assemble */
    char *violated;         /* not assembled: the rows violated at q, the
                               best point found (malloc'd); else NULL */
    char *loop;             /* not assembled: the loop that cannot close
                               (assemble_t0_loop; malloc'd, maybe ""); else NULL */
    int constructed;        /* coordinates placed by construction before
                               Newton (construct.h) */
    /* rank of the holonomic rows at q */
    bool dense;             /* rank computed (size within max_dense) */
    double rank_tol;
    int rank;               /* holonomic rows; -1 when not computed */
    double sigma_max, sigma_min, cond;
    int nredundant;
    /* all rows (velocity rows included): instantaneous mobility */
    int rank_all;
    int nredundant_velocity;
    /* drivers removed */
    int rank_undriven;      /* rank of the non-driver rows (all levels) */
    int generic_rank;       /* max rank of the undriven holonomic rows over sampled
                               assembled configurations; -1 if not sampled */
    int rank_undriven_h;    /* rank of the undriven holonomic rows at q */
    int dof_rank;           /* nq - rank - nv: DOF with the drivers, by rank */
    int mobility_rank;      /* nq - rank_undriven: DOF without drivers, by rank */
    Singularity singularity;
    InfoRow *rows;          /* nr */
    Involutivity system;    /* the velocity rows without drivers, with the holonomic ones */
    char *verdict;          /* plain words (malloc'd) */
    char *singular;         /* about the configuration's singularity (malloc'd) */
    InfoState state;        /* --at / --state only */
} InfoReport;

/* Analyses a loaded mechanism at time t. Returns false with diag filled only
   on an internal limit (graph size); an assembly that does not converge is
   reported in rep->assembled. */
bool info_analyse(Mech *mech, double t, const AnalysisOptions *opt, InfoReport *rep, Diag *diag);
/* The same at a state (at != NULL): the motion followed to t, or at->q;
   fills rep->state as well. */
bool info_analyse_at(Mech *mech, double t, const InfoAt *at, const AnalysisOptions *opt,
                     InfoReport *rep, Diag *diag);
void info_report_free(InfoReport *rep);

/* The textbook's row count for a joint kind (what each joint removes:
   revolute 2, prismatic 2, distance 1, pointline 1, weld 3, rolling 1,
   knife 1, constraint, driver and velocity 1), read from joints.def's row
   count and level; test_info holds the textbook values. */
int info_textbook_rows(JointKind kind, bool *velocity);

#endif
