/* builder.h - what model.c, expr.c and dynamics.c share: the builder's state, its names and its expressions. */
#ifndef MECHC_BUILDER_H
#define MECHC_BUILDER_H

#include "model.h"

#include "../base/hashmap.h"

typedef enum EntityKind {
    ENT_PARAM, ENT_BODY, ENT_POINT, ENT_COORD, ENT_JOINT, ENT_OUTPUT, ENT_MASS, ENT_FORCE
} EntityKind;

typedef struct Entity {
    EntityKind kind;
    const char *name;
    SrcPos pos;
    int q;              /* first coordinate (body, point, coord); joint: its index */
    double value;       /* param: its value (a design-dependent one's at the file's design) */
    NodeId node;        /* param: its node (a constant, or an expression of design parameters) */
} Entity;

typedef struct Builder {
    Model *model;
    Diag *diag;
    const MechLimits *limits;
    StrMap names;
    Arena scratch;      /* entities and rows until they are copied out */
    Entity *entities;
    int nentities, cap_entities;
    int cap_coords, cap_joints;
    Row *pos_rows, *vel_rows;
    int npos, nvel, cap_pos, cap_vel;
    int cap_outputs;
    SrcPos unit_use[2];     /* first use of deg, rpm as units (offset -1: none) */
    bool spatial;           /* the file says `spatial` */
    int cap_masses, cap_forces;
    const Stmt *first_force;    /* the first force or gravity statement */
    int gravity_line;           /* the gravity statement's line, 0 if none */
    int cap_design;             /* of model->design_names and design_p0 */
} Builder;

/* What an expression may use, from the most to the least restricted. */
typedef enum ExprContext {
    EXPR_CONSTANT,      /* params, initial values, offsets, axes */
    EXPR_TIMED,         /* length, angle, radius: may also use t */
    EXPR_MASS,          /* a mass element's position and angle: coordinates, not t */
    EXPR_HOLONOMIC,     /* may use coordinates and t */
    EXPR_VELOCITY,      /* may also use der() */
} ExprContext;

/* ---- names and arrays (model.c) ---- */

/* "a param", "a body", ...: what a name is, for messages. */
const char *build_entity_word(EntityKind kind);
/* Makes room for need elements of size bytes in *p (capacity *cap), in arena. */
void build_grow(Arena *arena, void **p, int *cap, int need, size_t size);
/* Fails at the statement when the graph has reached its node limit. */
void build_check_nodes(Builder *b);
int build_line(const Builder *b, SrcPos pos);
/* The entity a declared name names, or fails at pos. */
Entity *build_lookup(Builder *b, const char *name, SrcPos pos);
/* A new name, or fails when it is taken (or was used as a unit). */
Entity *build_declare(Builder *b, EntityKind kind, const char *name, SrcPos pos);
/* A joint's or force's operand, checked against rule; keyword names the statement. */
Attach build_attach(Builder *b, const AstAttach *at, AttachRule rule, const char *keyword);

/* ---- expressions (expr.c) ---- */

/* The index of a unit name (deg, rpm), or -1. */
int build_unit_index(const char *name);
/* The coordinate index an AST_NAME or AST_MEMBER names, or fails. */
int build_coordinate(Builder *b, const Ast *ast);
/* The joint of slide(T) or angle(R) in a spatial file (e names it, j its
   joint or NULL), or fails. */
const Joint *build_spatial_joint(Builder *b, const Ast *ast, const Entity *e, const Joint *j);
/* An expression's node, the node limit checked before each operand. */
NodeId build_lower_expr(Builder *b, const Ast *ast, ExprContext ctx);
/* The same, the node limit checked once the expression is built. */
NodeId build_lower(Builder *b, const Ast *ast, ExprContext ctx);
/* A constant expression's value (NULL: 0), or fails naming what (also
   when it depends on a design parameter, which what cannot). */
double build_constant(Builder *b, const Ast *ast, const char *what);
/* A constant that may depend on design parameters (an offset, a derived
   param): its node, and its value at the file's design in *nominal. */
NodeId build_design_value(Builder *b, const Ast *ast, const char *what, double *nominal);
/* A starting value (an initial position): a constant, or an expression of
   design parameters taken at the file's design. */
double build_nominal(Builder *b, const Ast *ast, const char *what);
bool build_mentions_der(const Ast *ast);

/* ---- masses, gravity and forces (dynamics.c) ---- */

/* A mass, gravity or force statement. */
void build_dynamics(Builder *b, const Stmt *s);
/* The checks once every statement is built. */
void build_dynamics_check(Builder *b);

#endif
