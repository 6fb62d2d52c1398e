/* ast.h - the statements and expressions of a .mech file, as the parser produces them. */
#ifndef MECHC_AST_H
#define MECHC_AST_H

#include "../base/diag.h"
#include "../dag/dag_ops.h"

#include <stdbool.h>

/* ---- joint vocabulary (generator/parse/joints.def) ---- */

typedef enum AttachRule {
    ATTACH_NONE,        /* slot unused */
    ATTACH_ANY,         /* body(sx, sy), body, point, ground(x, y), ground */
    ATTACH_FRAME,       /* a body or ground, with optional offset */
    ATTACH_BODY,        /* a body (not ground), with optional offset */
    ATTACH_BODY_ONLY,   /* a body name alone, no offset */
} AttachRule;

typedef enum JointOption { OPTION_NONE, OPTION_ANGLE, OPTION_LENGTH, OPTION_RADIUS } JointOption;
typedef enum JointLevel { LEVEL_POSITION, LEVEL_VELOCITY, LEVEL_EITHER } JointLevel;
typedef enum JointDim { DIM_PLANAR, DIM_SPATIAL, DIM_BOTH, DIM_INTERNAL } JointDim;

enum { JOINT_MAX_ROWS = 6 };

typedef enum JointKind {
#define X(e, kw, dim, na, sa, sb, ax, opt, nr, lvl, ...) JOINT_##e,
#include "joints.def"
#undef X
    JOINT_KIND_COUNT
} JointKind;

typedef struct JointInfo {
    const char *keyword;
    JointDim dim;
    int attachments;            /* 0: "lhs = rhs" statement */
    AttachRule slot[2];
    int axis;                   /* 0 none; 1 required; 2 (spatial) both A's and B's */
    JointOption option;
    int rows;
    JointLevel level;
    const char *suffix[JOINT_MAX_ROWS];
} JointInfo;

extern const JointInfo joint_info[JOINT_KIND_COUNT];

/* Keyword lookup among the planar (and both-dimension) kinds: the joint
   kind, or -1. */
int joint_kind_from_keyword(const char *word, int len);
/* The same in a planar (spatial false) or spatial file. */
int joint_kind_lookup(const char *word, int len, bool spatial);
/* Whether kind may be written in a file of that dimension. */
bool joint_kind_in(JointKind kind, bool spatial);

/* ---- expressions ---- */

typedef enum AstKind {
    AST_NUM,        /* number literal or pi: num */
    AST_NAME,       /* a param or a coord: name */
    AST_MEMBER,     /* name.member: a body's or point's coordinate */
    AST_TIME,       /* t */
    AST_NEG,        /* -lhs (unary plus is dropped by the parser) */
    AST_BINARY,     /* lhs op rhs, op one of OP_ADD OP_SUB OP_MUL OP_DIV OP_POW */
    AST_CALL,       /* op(lhs) or op(lhs, rhs) for a function op (OP_SIN ...) */
    AST_DER,        /* der(lhs): lhs is AST_NAME or AST_MEMBER */
    AST_SLIDE,      /* slide(name): the sliding of a prismatic or pointline joint
                       (spatial: translational or cylindrical) */
    AST_ANGLE,      /* angle(name): the relative rotation of a spatial revolute */
} AstKind;

typedef struct Ast {
    AstKind kind;
    DagOp op;               /* AST_BINARY, AST_CALL */
    SrcPos pos;             /* first character of the construct; for a binary
                               operator, the operator itself */
    double num;             /* AST_NUM */
    const char *name;       /* AST_NAME, AST_MEMBER (the object) */
    const char *member;     /* AST_MEMBER (any identifier; checked later) */
    SrcPos member_pos;      /* AST_MEMBER: position of the member name */
    struct Ast *lhs, *rhs;
} Ast;

/* ---- statements ---- */

typedef enum StmtKind {
    STMT_MECHANISM,     /* mechanism NAME */
    STMT_SPATIAL,       /* spatial (first statement after mechanism) */
    STMT_PARAM,         /* param NAME = value; design NAME = value (design) */
    STMT_BODY,          /* body NAME [x = e] [y = e] [phi = e] */
    STMT_POINT,         /* point NAME [x = e] [y = e] */
    STMT_COORD,         /* coord NAME [= value] */
    STMT_JOINT,         /* KIND NAME: operands [axis(ux, uy)] [option = e] */
    STMT_OUTPUT,        /* output NAME = e  |  output NAME: attachment */
    STMT_MASS,          /* mass BODY m = .. [J = ..] [com(sx, sy)]  |  mass NAME: at(X, Y) m = .. [J = .. angle = ..] */
    STMT_GRAVITY,       /* gravity (gx, gy) */
    STMT_FORCE,         /* an applied force element (ForceKind) */
} StmtKind;

/* ---- dynamics statements: masses, gravity and applied forces (no rows) ---- */

/* The `key = value` options of the dynamics statements. */
typedef enum DynKey {
    DKEY_M, DKEY_J, DKEY_K, DKEY_C, DKEY_LENGTH, DKEY_ANGLE, DKEY_FORCE, DKEY_TORQUE,
    DKEY_JXY, DKEY_JXZ, DKEY_JYZ,   /* spatial: the inertia tensor's off-diagonal entries */
    DKEY_COUNT
} DynKey;

typedef enum ForceKind {
#define X(e, kw, own, na, frame, keys) FORCE_##e,
#include "forces.def"
#undef X
    FORCE_KIND_COUNT
} ForceKind;

typedef struct ForceInfo {
    const char *keyword;
    bool own;           /* the keyword names this kind (not a form of another's) */
    int attachments;
    bool frame;         /* its attachments are bodies' angles */
    unsigned keys;      /* 1 << DynKey for each key it takes */
} ForceInfo;

extern const ForceInfo force_info[FORCE_KIND_COUNT];

/* The force kind a statement keyword names, or -1. */
int force_kind_lookup(const char *word, int len);

extern const char *const dyn_key_names[DKEY_COUNT];

/* A spatial body's initial orientation, as written. */
enum { ORIENT_NONE, ORIENT_AXIS, ORIENT_XYZ, ORIENT_ZYX };

typedef struct AstAttach {
    const char *name;       /* "ground" for the ground frame */
    SrcPos pos;
    bool has_offset;        /* NAME(sx, sy) rather than NAME */
    bool at;                /* dynamics: at(X, Y), sx and sy expressions of
                               the coordinates (name is NULL) */
    Ast *sx, *sy, *sz;      /* sz: spatial files only */
} AstAttach;

typedef struct Stmt {
    StmtKind kind;
    SrcPos pos;             /* the keyword */
    const char *name;       /* declared name (NULL for none) */
    SrcPos name_pos;

    Ast *value;             /* PARAM, COORD (NULL: coord defaults to 0), OUTPUT
                               (NULL: a point, attach[0]) */
    Ast *init[3];           /* BODY x, y, phi; POINT x, y (NULL: 0);
                               spatial BODY and POINT: x, y, z */
    SrcPos init_pos[3];
    int orient;             /* spatial BODY: ORIENT_* */
    Ast *orient_arg[4];     /* axis: ux, uy, uz, angle; xyz, zyx: a, b, c */
    SrcPos orient_pos;

    JointKind joint;        /* JOINT */
    AstAttach attach[2];    /* JOINT: joint_info[joint].attachments used; OUTPUT: [0] */
    Ast *axis[3];           /* JOINT with axis: ux, uy (spatial: uz too) */
    SrcPos axis_pos;
    Ast *axis_b[3];         /* spatial: B's axis when given (NULL: A's) */
    SrcPos axis_b_pos;
    Ast *option;            /* JOINT: angle, length or radius (NULL: absent) */
    SrcPos option_pos;
    Ast *lhs, *rhs;         /* JOINT with attachments == 0 */
    SrcPos eq_pos;

    ForceKind force;        /* FORCE; attach[] its attachments, value its
                               torque or generalised force, lhs a torque's
                               angle(e) or gforce's coordinate */
    bool declares;          /* MASS, FORCE: name is declared (mass NAME: ...) */
    bool design;            /* PARAM: a design parameter, an input of the kernels */
    Ast *key[DKEY_COUNT];   /* MASS, FORCE: key = value (NULL: absent) */
    SrcPos key_pos[DKEY_COUNT];
    Ast *vec[3];            /* force (fx, fy), gravity (gx, gy), com(sx, sy);
                               spatial: three components, and a body's torque */
    Ast *inertia[3];        /* spatial mass: J = (Jxx, Jyy, Jzz) (NULL: absent) */
    SrcPos vec_pos;

    struct Stmt *next;
} Stmt;

typedef struct Program {
    bool spatial;           /* the file says `spatial` */
    Stmt *first;
    int count;
    int line_count;
} Program;

/* A readable name for an AST kind, for messages. */
const char *ast_describe(const Ast *ast);
/* The keyword of a mass, gravity or force statement, for messages. */
const char *dyn_keyword(const Stmt *s);

#endif
