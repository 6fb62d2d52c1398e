/* model.h - a resolved mechanism: coordinates, joints and constraint rows as graph nodes. */
#ifndef MECHC_MODEL_H
#define MECHC_MODEL_H

#include "../base/arena.h"
#include "../base/diag.h"
#include "../base/limits.h"
#include "../dag/dag.h"
#include "../parse/ast.h"

/* A joint operand after name resolution: P = r + A(phi) s; in a spatial
   file P = r + A(p) s with Euler parameters p. */
typedef struct Attach {
    int q;              /* index of the x coordinate; -1 for ground */
    bool has_phi;       /* a planar body: phi is coordinate q + 2 */
    bool spatial;       /* spatial file: z is q + 2; a spatial body (has_p)
                           has e0..e3 at q + 3 .. q + 6 */
    bool has_p;         /* a spatial body (not a point, not ground) */
    double sx, sy;      /* body-local offset, or global point for ground */
    double sz;          /* spatial only */
    /* An offset that depends on design parameters: its nodes (sx, sy, sz
       are their values at the file's design, for drawings and first guesses) */
    bool designed;
    NodeId s_node[3];
} Attach;

typedef struct Joint {
    JointKind kind;
    const char *name;
    SrcPos pos;
    Attach a, b;
    double ux, uy;      /* axis, as written (a designed one's at the file's design) */
    double uz;          /* spatial: A's axis is (ux, uy, uz) in A's frame, */
    double bx, by, bz;  /* and B's (bx, by, bz) in B's (A's vector unless given) */
    bool axis_designed; /* an axis of design parameters (A's or B's): */
    NodeId u_node[3];   /* A's components as nodes (planar: u_node[0], [1]), */
    NodeId b_node[3];   /* B's (spatial) */
    NodeId option;      /* length, angle or radius (angle absent: 0); a
                           measuring driver's right side E (below) */
    int measures;       /* spatial `driver D: angle(R) = E`: 1 + R's index in
                           joints; `slide(T) = E`: -(1 + T's); 0 otherwise */
    NodeId expr;        /* expression statements: lhs - rhs */
    bool velocity;      /* its rows are velocity level */
    int first_row, nrows;
} Joint;

typedef struct Row {
    const char *name;   /* J, J.x, ... */
    JointKind kind;
    bool velocity;      /* velocity level (Pfaffian) */
    NodeId expr;        /* Phi (position) or Psi (velocity, with qd leaves) */
    int joint;          /* index into joints */
    SrcPos pos;         /* the statement, for diagnostics */
} Row;

/* A body or a point: the owner of the consecutive coordinates q .. q + nq - 1,
   named NAME.x, NAME.y, then NAME.phi for a body that turns; in a spatial
   file NAME.x, NAME.y, NAME.z, then a body's Euler parameters NAME.e0 ..
   NAME.e3. Scalar coords own no Body. Code that walks a body's coordinates
   uses nq. */
typedef struct Body {
    const char *name;
    int q;              /* index of its x coordinate */
    int nq;             /* coordinates it owns: 3 (body), 2 (point);
                           spatial: 7 (x y z e0 e1 e2 e3), 3 (point) */
    bool has_phi;       /* a body: phi is coordinate q + 2; a point (a
                           particle) has none (as Attach.has_phi) */
    bool spatial;       /* a spatial body or point (has_phi false) */
} Body;

/* A value reported beside the coordinates (an `output` statement): an
   expression of q and t; its velocity and acceleration come from its
   derivatives along the motion (generator/kin/outputs.h). */
typedef struct ModelOutput {
    const char *name;   /* NAME, or NAME.x and NAME.y for a point */
    NodeId expr;
    const char *point;  /* NAME.x of a point: NAME, the point in at (the
                           animation draws its path); otherwise NULL */
    Attach at;
} ModelOutput;

/* A mass element (doc/dynamics.md): mass m at the point p = (px, py), expressions of
   q (a body's centre of mass r + A(phi) s, a particle's position, or an
   element's at(x, y)), and moment of inertia J about p for the angle theta.
   Its kinetic energy is 1/2 m |p_q qd|^2 + 1/2 J (theta_q qd)^2.
   In a spatial file p = (px, py, pz), no theta, and a spatial body's own
   mass adds 1/2 w'^T J' w' with w' = 2 G(e) ed its angular velocity in
   body axes and J' the tensor `inertia` about the centre of mass. */
typedef struct MassElement {
    const char *name;   /* the body, point or element */
    SrcPos pos;
    double m, J;
    NodeId px, py;
    NodeId theta;       /* DAG_ZERO when there is no angle (J = 0) */
    int body;           /* a planar body's own mass: its x coordinate (then
                           p = r + A(phi) s, s = (sx, sy)); -1 otherwise */
    double sx, sy;
    bool spatial;       /* a spatial file's: pz below, theta DAG_ZERO */
    NodeId pz;
    int euler;          /* a spatial body's own mass: the index of its e0
                           (e0..e3 at euler .. euler + 3); -1 otherwise */
    double inertia[6];  /* J' in body axes: xx, yy, zz, xy, xz, yz */
    /* m, J, (sx, sy) and the tensor as nodes: constants, or expressions of
       design parameters (the numbers above are then their values at the
       file's design) */
    NodeId m_node, J_node, s_node[2], inertia_node[6];
} MassElement;

/* An applied force, every kind by virtual work (its kind's maths:
   generator/parse/forces.def). Expressions (fx, fy) may
   use q, der(q) and t. In a spatial file points and forces have z
   components too (az, bz, fz; DAG_ZERO in a planar file). */
typedef struct AppliedForce {
    ForceKind kind;
    const char *name;
    SrcPos pos;
    NodeId ax, ay;      /* POINT: the point; SPRING: A's point; TORQUE,
                           RSPRING: ax the angle (of A) */
    NodeId bx, by;      /* SPRING: B's point; RSPRING: bx B's angle */
    NodeId fx, fy;      /* POINT: components; otherwise fx the value (the
                           actuator's force or torque for a spring) */
    double k, c, free;  /* SPRING, RSPRING: stiffness, damping, free length or angle */
    NodeId k_node, c_node, free_node;   /* the same as nodes (as MassElement's) */
    int coord;          /* GENERAL: the coordinate; BODY_TORQUE: e0's */
    NodeId az, bz, fz;
} AppliedForce;

typedef struct Model {
    Arena arena;        /* owns every string and array below */
    Dag dag;            /* owns the expression graph (rows and derivatives) */
    const char *name;   /* mechanism name */
    const char *file;   /* input file name as given */
    bool spatial;       /* the file says `spatial` */
    int nq;
    const char **coord_names;
    double *q0;
    int nh, nv, nr;     /* rows: nh holonomic first, then nv velocity level */
    Row *rows;
    int njoints;
    Joint *joints;
    int nbodies;
    Body *bodies;       /* bodies and points in declaration order (which is
                           also the order of their coordinates) */
    int nout;
    ModelOutput *outputs;   /* in statement order */
    SrcPos last_pos;    /* the last statement: where diagnostics about the
                           mechanism as a whole point */
    int nmasses;        /* dynamics: none unless the file has masses */
    MassElement *masses;
    int nforces;
    AppliedForce *forces;
    double gravity[3];  /* (0, 0, 0) without a gravity statement; gz spatial only */
    NodeId gravity_node[3];     /* the same as nodes (as MassElement's) */
    /* Design parameters in statement order: names and the file's values.
       The design evaluated now is dag.param_values (model_set_design). */
    int np;
    const char **design_names;
    double *design_p0;
} Model;

/* Reads, parses and resolves a .mech text. Returns NULL with diag filled
   on bad input. default_name: the mechanism name when the file has no
   `mechanism` statement (the file stem). */
Model *model_load(const char *text, int text_len, const char *file,
                  const char *default_name, const MechLimits *limits, Diag *diag);
void model_free(Model *model);
/* Sets the design the model's graph is evaluated at (np values; NULL: the
   file's): every engine and interpreted expression of this model sees it. */
void model_set_design(Model *model, const double *p);

/* The body or point called name, or NULL (ground, a scalar coord, a param,
   a joint or an unknown name). */
const Body *model_find_body(const Model *m, const char *name);

/* Reads a whole file ("-" = stdin) into a NUL-terminated buffer (free()).
   Returns NULL with diag filled when it cannot be read or is too large. */
char *model_read_file(const char *path, const MechLimits *limits, int *len, Diag *diag);
/* model_read_file for a data file (a CSV): a NUL byte in it is refused at
   its FILE:LINE:COL (the readers parse C strings, which would end there:
   "1.4<NUL>" read as 1.4). */
char *model_read_data_file(const char *path, const MechLimits *limits, int *len, Diag *diag);

/* The file stem of a path: "dir/slider_crank.mech" -> "slider_crank". */
char *model_file_stem(Arena *arena, const char *path);

/* Lowers one joint's rows into the graph, by its kind's builder
   (generator/model/joints.c, joints_spatial.c). */
void joints_lower(Model *model, const Joint *joint, NodeId rows_out[JOINT_MAX_ROWS]);
/* A spatial axis (ux, uy, uz) made unit, h, and its perpendiculars f and g
   (the generic evaluator's formulas use the builder's very frame). */
void joints_spatial_frame(double ux, double uy, double uz, double h[3], double f[3], double g[3]);
/* A spatial attachment's global position P = r + A(p) s: xyz_out[0..2]. */
void joints_spatial_point(Model *model, Attach at, NodeId xyz_out[3]);
/* slide(T) of a spatial translational or cylindrical joint: h_A . (P_B - P_A), |h| = 1. */
NodeId joints_spatial_slide(Model *model, const Joint *joint);
/* angle(R) of a spatial revolute or cylindrical joint: atan2(g_A . f_B, f_A . f_B). */
NodeId joints_spatial_angle(Model *model, const Joint *joint);
/* The driver row angle(R) = theta, branch-free:
   cos(theta) (g_A . f_B) - sin(theta) (f_A . f_B) = sin(angle - theta). */
NodeId joints_spatial_angle_row(Model *model, const Joint *joint, NodeId theta);
/* The global position P = r + A(phi) s of an attachment: xy_out[0], [1]. */
void joints_point(Model *model, Attach at, NodeId xy_out[2]);
/* The sliding of a prismatic or pointline joint: the displacement of B's
   point from A's along A's axis, u_A . (P_B - P_A) / |u|. */
NodeId joints_slide(Model *model, const Joint *joint);

#endif
