/* generic_impl.h - what generic.c and generic_joints.c share: the evaluator's state and one call's outputs. */
#ifndef MECHC_GENERIC_IMPL_H
#define MECHC_GENERIC_IMPL_H

#include "generic.h"
#include "interp.h"

/* A joint's length, angle or radius: a constant, or a program of (q, t). */
typedef struct Option {
    bool constant;
    double value;       /* when constant */
    int prog;           /* index into Generic.progs, -1 when constant */
} Option;

typedef struct Call Call;

/* The dynamics part (generic_dynamics.c), NULL without masses. */
typedef struct GenericDyn GenericDyn;
GenericDyn *generic_dynamics_open(const Model *m);
void generic_dynamics_free(GenericDyn *d);

/* A spatial body's rotation at the current state: A(p), and when qd is
   given dA/dt and H, the part of d2A/dt2 without p'' (generic_spatial.c). */
typedef struct Rot {
    double a[9], ad[9], h[9];   /* row-major */
} Rot;
typedef struct Plan Plan;

/* A standard joint's rows by its formulas (generic_joints.c). */
typedef void GenericRows(const Call *c, const Plan *p);

/* One joint, ready to evaluate (a joint without formulas: one of its rows). */
struct Plan {
    const Joint *j;
    int row;            /* its first row (an interpreted row: its row) */
    bool velocity;      /* the joint's rows are velocity level */
    GenericRows *rows;  /* a standard joint's formulas; else NULL and: */
    const Joint *of;    /* the joint whose frames and sides the formulas use:
                           j, or the one a measuring driver measures */
    const double (*frame)[3];   /* spatial: of's local h, f, g of side A, then of B */
    int prog;           /* constraint, driver, velocity: the row's program; else -1 */
    Option opt;
};

struct Generic {
    const Model *m;
    int nq, nh, nv, nr;
    Plan *plans;
    int nplans;
    Tape *progs;
    int nprogs;
    int *angles;        /* body angles whose rotation A(phi) the joint formulas use: */
    int nangles;        /* all of them, */
    int nangles_pos;    /* of which the first nangles_pos serve position-level joints */
    double *cosq, *sinq;    /* per coordinate; valid for angles[] during a call */
    Rot *rots;          /* the spatial bodies the formulas turn, this call: */
    int *rot_q;         /* each one's x coordinate, */
    int *rot_of;        /* per x coordinate: its index into rots */
    int nrots;
    bool nu_rots;       /* a nu-only call needs them too (a contact's R(t),
                           an angle driver's theta(t)) */
    double (*frames)[3];    /* 6 per joint (Plan.frame) */
    Jet *jreg;          /* registers for the longest program */
    double *vreg;
    GenericDyn *dyn;    /* masses and forces, or NULL */
};

/* One evaluation: the state and where each requested quantity goes (NULL:
   not requested). jac is zero-filled by the caller; formulas add to it. */
struct Call {
    Generic *g;
    const double *q, *qd;   /* qd NULL unless gamma or psi is requested */
    double t;
    double *phi;        /* nh */
    double *jac;        /* nr*nq */
    double *nu;         /* nr */
    double *gamma;      /* nr */
    double *psi;        /* nv, indexed by row - nh */
};

/* Options (generic.c). */
double option_value(const Call *c, const Option *o);
/* d option/dt at fixed q. */
double option_dt(const Call *c, const Option *o);
/* The option along (qd, 1): value, D and D(D) with qdd = 0. */
Jet option_along(const Call *c, const Option *o, int order);
/* row[j] += coef * d option/dq_j for every coordinate the option reads. */
void option_jac(const Call *c, const Option *o, double coef, double *row);

/* The formulas of j's kind (generic_joints.c), NULL for a kind whose row
   is interpreted (constraint, driver, velocity). Raises need[k] (one per
   coordinate) for each angle q[k] whose A(phi) they rotate: to 2 for a
   position-level joint, to 1 for a velocity-level one. */
GenericRows *generic_joint_formula(const Joint *j, char *need);
/* need[k] of a spatial body's e0 (q + 3) when the formulas turn by its A(p). */
enum { NEED_ROT = 3 };

/* A kind's formulas and what they rotate, so that generic.c computes cos
   and sin of those angles, or A(p), before a call. */
enum {
    TURN_SA = 1,        /* A's offset: P_A = r_A + A(phi_A) s_A */
    TURN_SB = 2,        /* B's offset */
    TURN_AXIS = 4,      /* A's axis: n_A = A(phi_A) (-uy, ux) */
    TURN_P = 8,         /* spatial: both sides' A(p) */
};

typedef struct Formula {
    GenericRows *rows;  /* NULL: the row is interpreted (generic.c) */
    int turns;          /* TURN_* */
} Formula;

/* The spatial family's formulas (generic_spatial.c), one per spatial row
   of joints.def; the planar ones are generic_joints.c's own. */
extern const Formula formula_S_SPHERICAL, formula_S_UNIVERSAL, formula_S_REVOLUTE,
    formula_S_CYLINDRICAL, formula_S_TRANSLATIONAL, formula_S_WELD, formula_S_DISTANCE,
    formula_S_POINTPLANE, formula_S_PARALLEL, formula_S_PERPENDICULAR, formula_S_ROLLING,
    formula_S_NORM, formula_S_CONTACT;
/* A spatial `driver D: angle(R) = E` or `slide(T) = E` (driver->measures),
   R or T being of: its formulas, marking of's bodies in need; else NULL. */
GenericRows *generic_measure_rows(const Joint *driver, const Joint *of, char *need);
/* A, and with qd Ad and H, of every body in g->rots, for one call. */
void generic_spatial_rotations(const Call *c);

#endif
