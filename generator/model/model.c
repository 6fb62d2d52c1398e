/* model.c - statements to a resolved mechanism: names, coordinates, joints and rows.
 *
 * Walks the statements in order, so "declared before used" falls out of
 * the walk. Params and initial values are folded to constants through the
 * expression graph itself (a constant expression simplifies to one CONST
 * node); anything else is a position-carrying error. Rows are collected
 * holonomic first, velocity level after, each group in statement order.
 */
#include "model.h"

#include "../base/hashmap.h"
#include "../dag/support.h"
#include "../parse/parse.h"
#include "orient.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum EntityKind {
    ENT_PARAM, ENT_BODY, ENT_POINT, ENT_COORD, ENT_JOINT, ENT_OUTPUT, ENT_MASS, ENT_FORCE
} EntityKind;

typedef struct Entity {
    EntityKind kind;
    const char *name;
    SrcPos pos;
    int q;              /* first coordinate (body, point, coord); joint: its index */
    double value;       /* param */
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
} Builder;

static const char *entity_word(EntityKind kind)
{
    switch (kind) {
    case ENT_PARAM: return "a param";
    case ENT_BODY:  return "a body";
    case ENT_POINT: return "a point";
    case ENT_COORD: return "a coord";
    case ENT_JOINT: return "a joint";
    case ENT_OUTPUT: return "an output";
    case ENT_MASS: return "a mass";
    case ENT_FORCE: return "a force";
    }
    return "a name";
}

/* Arrays grow in an arena (the model's, or the builder's scratch), so an
   input error's escape leaves nothing to free; the old copies stay until
   the arena goes, at most as much again. */
static void grow(Arena *arena, void **p, int *cap, int need, size_t size)
{
    if (need <= *cap)
        return;
    int c = *cap ? *cap * 2 : 16;
    while (c < need)
        c *= 2;
    void *bigger = arena_alloc_array(arena, (size_t)c, size);
    if (*cap)
        memcpy(bigger, *p, (size_t)*cap * size);
    *p = bigger;
    *cap = c;
}

/* The graph's node limit is sticky (dag.h): checked after each piece of
   lowering, before anything else in the statement can fail, so the error
   is the node limit at that statement, as when the graph jumped out. */
static void check_nodes(Builder *b)
{
    if (!dag_check_limit(&b->model->dag, b->diag))
        diag_throw(b->diag);
}

static int line_of(const Builder *b, SrcPos pos)
{
    int line, col;
    diag_locate(b->diag, pos.offset, &line, &col);
    return line;
}

/* Units textbook data is written in, as constants: 30*deg, 1500*rpm.
   They are not reserved: a file that declares one of these names (a param
   deg from before they existed) uses its own. */
static const struct { const char *name; double value; } units[2] = {
    {"deg", 3.14159265358979323846 / 180},   /* degree, in radians */
    {"rpm", 3.14159265358979323846 / 30},    /* revolution per minute, in rad/s */
};

/* The index of a unit name in units[], or -1. */
static int unit_index(const char *name)
{
    for (int i = 0; i < (int)(sizeof units / sizeof *units); i++)
        if (strcmp(name, units[i].name) == 0)
            return i;
    return -1;
}

static Entity *lookup(Builder *b, const char *name, SrcPos pos)
{
    int index;
    if (!strmap_get(&b->names, name, &index))
        diag_fail(b->diag, pos, "unknown name '%s' (names must be declared before use)", name);
    return &b->entities[index];
}

static Entity *declare(Builder *b, EntityKind kind, const char *name, SrcPos pos)
{
    int index;
    if (strmap_get(&b->names, name, &index))
        diag_fail(b->diag, pos, "duplicate name '%s' (first declared as %s on line %d)",
                  name, entity_word(b->entities[index].kind),
                  line_of(b, b->entities[index].pos));
    grow(&b->scratch, (void **)&b->entities, &b->cap_entities, b->nentities + 1,
         sizeof *b->entities);
    int u = unit_index(name);
    if (u >= 0 && b->unit_use[u].offset >= 0)     /* one name, one meaning per file */
        diag_fail(b->diag, pos, "'%s' was used as the unit %s on line %d: declare it before "
                  "its first use, or choose another name", name, name,
                  line_of(b, b->unit_use[u]));
    Entity *e = &b->entities[b->nentities];
    *e = (Entity){.kind = kind, .name = name, .pos = pos, .q = -1};
    strmap_put(&b->names, name, b->nentities++);
    return e;
}

/* Rows x coordinates: the dense Jacobian every engine fills (run's sparse
   path excepted: it asks for no check here, max_jac_entries 0). */
static void check_jacobian_size(Builder *b, long long nr, long long nq, SrcPos pos)
{
    if (b->limits->max_jac_entries > 0 && nr * nq > b->limits->max_jac_entries)
        diag_fail(b->diag, pos, "the dense Jacobian would have %lld row%s x %lld coordinate%s = "
                  "%lld entries, more than the limit of %d (--max-jac-entries)%s%s", nr,
                  nr == 1 ? "" : "s", nq, nq == 1 ? "" : "s", nr * nq,
                  b->limits->max_jac_entries, b->limits->jac_advice ? ": " : "",
                  b->limits->jac_advice ? b->limits->jac_advice : "");
}

static int add_coord(Builder *b, const char *owner, const char *suffix, double q0, SrcPos pos)
{
    Model *m = b->model;
    if (m->nq >= b->limits->max_coords)
        diag_fail(b->diag, pos, "too many coordinates (the limit is %d)", b->limits->max_coords);
    check_jacobian_size(b, b->npos + b->nvel, m->nq + 1, pos);
    int cap = b->cap_coords;    /* q0 shares the capacity of coord_names */
    grow(&m->arena, (void **)&m->coord_names, &b->cap_coords, m->nq + 1, sizeof *m->coord_names);
    grow(&m->arena, (void **)&m->q0, &cap, m->nq + 1, sizeof *m->q0);
    char *name = arena_alloc(&m->arena, strlen(owner) + strlen(suffix) + 1);
    strcpy(name, owner);
    strcat(name, suffix);
    m->coord_names[m->nq] = name;
    m->q0[m->nq] = q0;
    return m->nq++;
}

/* ---- expressions ---- */

typedef enum ExprContext {
    EXPR_CONSTANT,      /* params, initial values, offsets, axes */
    EXPR_TIMED,         /* length, angle, radius: may also use t */
    EXPR_MASS,          /* a mass element's position and angle: coordinates, not t */
    EXPR_HOLONOMIC,     /* may use coordinates and t */
    EXPR_VELOCITY,      /* may also use der() */
} ExprContext;

static const char *context_what(ExprContext ctx)
{
    if (ctx == EXPR_TIMED)
        return "a joint's length, angle or radius (numbers, params and t)";
    if (ctx == EXPR_MASS)
        return "a mass element's position or angle (coordinates, numbers and params)";
    return ctx == EXPR_CONSTANT ? "a constant expression (numbers, pi and earlier params)"
                                : "a holonomic row (use a 'velocity' or 'driver' statement for der())";
}

/* A spatial body's (x y z e0 e1 e2 e3) or point's (x y z) member. */
static int spatial_member(Builder *b, const Ast *ast, const Entity *e)
{
    static const char *const names[7] = {"x", "y", "z", "e0", "e1", "e2", "e3"};
    int n = e->kind == ENT_BODY ? 7 : 3;
    for (int i = 0; i < n; i++)
        if (strcmp(ast->member, names[i]) == 0)
            return e->q + i;
    diag_fail(b->diag, ast->member_pos, "%s '%s' has no coordinate '%s' (it has %s)",
              e->kind == ENT_BODY ? "body" : "point", e->name, ast->member,
              e->kind == ENT_BODY ? "x, y, z, e0, e1, e2 and e3" : "x, y and z");
}

/* The coordinate index an AST_NAME / AST_MEMBER names, or fails. */
static int coordinate_of(Builder *b, const Ast *ast)
{
    Entity *e = lookup(b, ast->name, ast->pos);
    if (b->spatial && ast->kind == AST_NAME && (e->kind == ENT_BODY || e->kind == ENT_POINT))
        diag_fail(b->diag, ast->pos, "'%s' is a %s: write %s.x, %s.y, %s.z%s", e->name,
                  e->kind == ENT_BODY ? "body" : "point", e->name, e->name, e->name,
                  e->kind == ENT_BODY ? " or its Euler parameters .e0 .. .e3" : "");
    if (b->spatial && ast->kind == AST_MEMBER && (e->kind == ENT_BODY || e->kind == ENT_POINT))
        return spatial_member(b, ast, e);
    if (ast->kind == AST_NAME) {
        if (e->kind == ENT_COORD)
            return e->q;
        if (e->kind == ENT_BODY)
            diag_fail(b->diag, ast->pos, "'%s' is a body: write %s.x, %s.y or %s.phi",
                      e->name, e->name, e->name, e->name);
        if (e->kind == ENT_POINT)
            diag_fail(b->diag, ast->pos, "'%s' is a point: write %s.x or %s.y",
                      e->name, e->name, e->name);
        diag_fail(b->diag, ast->pos, "'%s' is %s, not a coordinate", e->name, entity_word(e->kind));
    }
    if (e->kind != ENT_BODY && e->kind != ENT_POINT)
        diag_fail(b->diag, ast->pos, "'%s' is %s and has no components", e->name,
                  entity_word(e->kind));
    if (strcmp(ast->member, "x") == 0)
        return e->q;
    if (strcmp(ast->member, "y") == 0)
        return e->q + 1;
    if (e->kind == ENT_BODY && strcmp(ast->member, "phi") == 0)
        return e->q + 2;
    diag_fail(b->diag, ast->member_pos, "%s '%s' has no coordinate '%s' (it has %s)",
              e->kind == ENT_BODY ? "body" : "point", e->name, ast->member,
              e->kind == ENT_BODY ? "x, y and phi" : "x and y");
}

/* The joint of slide(T) (a translational or cylindrical) or angle(R) (a
   revolute or cylindrical) in a spatial file, or fails. */
static const Joint *spatial_joint_of(Builder *b, const Ast *ast, const Entity *e, const Joint *j)
{
    bool slide = ast->kind == AST_SLIDE;
    JointKind want = slide ? JOINT_S_TRANSLATIONAL : JOINT_S_REVOLUTE;
    if (!j || (j->kind != want && j->kind != JOINT_S_CYLINDRICAL))
        diag_fail(b->diag, ast->member_pos, "%s() takes a %s or cylindrical joint; '%s' is %s",
                  slide ? "slide" : "angle", joint_info[want].keyword, e->name,
                  j ? joint_info[j->kind].keyword : entity_word(e->kind));
    return j;
}

static NodeId lower_expr(Builder *b, const Ast *ast, ExprContext ctx)
{
    Dag *dag = &b->model->dag;
    check_nodes(b);         /* before this operand's names are looked up */
    switch (ast->kind) {
    case AST_NUM:
        return dag_const(dag, ast->num);
    case AST_TIME:
        if (ctx == EXPR_CONSTANT || ctx == EXPR_MASS)
            diag_fail(b->diag, ast->pos, "'t' cannot appear in %s", context_what(ctx));
        return dag_time(dag);
    case AST_NAME: {
        int declared, u = unit_index(ast->name);
        if (u >= 0 && !strmap_get(&b->names, ast->name, &declared)) {
            if (b->unit_use[u].offset < 0)
                b->unit_use[u] = ast->pos;
            return dag_const(dag, units[u].value);
        }
        Entity *e = lookup(b, ast->name, ast->pos);
        if (e->kind == ENT_PARAM)
            return dag_const(dag, e->value);
        if (ctx <= EXPR_TIMED)
            diag_fail(b->diag, ast->pos, "'%s' is %s; only params may appear in %s",
                      e->name, entity_word(e->kind), context_what(ctx));
        return dag_var(dag, coordinate_of(b, ast));
    }
    case AST_MEMBER:
        if (ctx <= EXPR_TIMED) {
            lookup(b, ast->name, ast->pos);
            diag_fail(b->diag, ast->pos, "coordinate '%s.%s' cannot appear in %s",
                      ast->name, ast->member, context_what(ctx));
        }
        return dag_var(dag, coordinate_of(b, ast));
    case AST_DER:
        if (ctx != EXPR_VELOCITY)
            diag_fail(b->diag, ast->pos, "der() cannot appear in %s", context_what(ctx));
        if (ast->lhs->kind != AST_NAME && ast->lhs->kind != AST_MEMBER)
            diag_fail(b->diag, ast->lhs->pos, "der() takes a coordinate, not %s",
                      ast_describe(ast->lhs));
        return dag_vard(dag, coordinate_of(b, ast->lhs));
    case AST_NEG:
        return dag_neg(dag, lower_expr(b, ast->lhs, ctx));
    case AST_BINARY: {
        /* right operand first, in sequenced statements: argument order is
           unspecified in C, and node ids (so the generated C) must not
           depend on the compiler; gcc had been lowering the right first */
        NodeId y = lower_expr(b, ast->rhs, ctx);
        NodeId x = lower_expr(b, ast->lhs, ctx);
        return dag_apply(dag, ast->op, x, y);
    }
    case AST_CALL: {
        NodeId x = lower_expr(b, ast->lhs, ctx);
        NodeId y = ast->rhs ? lower_expr(b, ast->rhs, ctx) : DAG_NONE;
        return dag_apply(dag, ast->op, x, y);
    }
    case AST_SLIDE: {
        if (ctx <= EXPR_TIMED)
            diag_fail(b->diag, ast->pos, "slide() depends on coordinates: it cannot appear in %s",
                      context_what(ctx));
        Entity *e = lookup(b, ast->name, ast->member_pos);
        const Joint *j = e->kind == ENT_JOINT ? &b->model->joints[e->q] : NULL;
        if (b->spatial)
            return joints_spatial_slide(b->model, spatial_joint_of(b, ast, e, j));
        if (!j || (j->kind != JOINT_PRISMATIC && j->kind != JOINT_POINTLINE))
            diag_fail(b->diag, ast->member_pos, "slide() takes a prismatic or pointline joint; "
                      "'%s' is %s", e->name, j ? joint_info[j->kind].keyword : entity_word(e->kind));
        return joints_slide(b->model, j);
    }
    case AST_ANGLE: {
        if (ctx <= EXPR_TIMED)
            diag_fail(b->diag, ast->pos, "angle() depends on coordinates: it cannot appear in %s",
                      context_what(ctx));
        Entity *e = lookup(b, ast->name, ast->member_pos);
        const Joint *j = e->kind == ENT_JOINT ? &b->model->joints[e->q] : NULL;
        return joints_spatial_angle(b->model, spatial_joint_of(b, ast, e, j));
    }
    }
    diag_fail(b->diag, ast->pos, "internal error: unknown expression kind");
}

/* A whole expression, the node limit checked once it is built. */
static NodeId lower(Builder *b, const Ast *ast, ExprContext ctx)
{
    NodeId id = lower_expr(b, ast, ctx);
    check_nodes(b);
    return id;
}

static double constant_value(Builder *b, const Ast *ast, const char *what)
{
    if (!ast)
        return 0.0;
    NodeId id = lower(b, ast, EXPR_CONSTANT);
    double v;
    if (!dag_is_const(&b->model->dag, id, &v) || !isfinite(v))
        diag_fail(b->diag, ast->pos, "%s is not a finite number", what);
    return v;
}

static bool mentions_der(const Ast *ast)
{
    if (!ast)
        return false;
    if (ast->kind == AST_DER)
        return true;
    return mentions_der(ast->lhs) || mentions_der(ast->rhs);
}

/* ---- statements ---- */

static void lower_joint(Builder *b, Joint *j);

/* A new joint at the end of the model's list (not yet counted). */
static Joint *new_joint(Builder *b)
{
    Model *m = b->model;
    grow(&m->arena, (void **)&m->joints, &b->cap_joints, m->njoints + 1, sizeof *m->joints);
    return &m->joints[m->njoints];
}

/* body NAME in a spatial file: x y z and the Euler parameters e0 .. e3 of
   its orientation (the identity unless orient = ... says otherwise), then
   its row NAME.norm; point NAME: x y z. */
static void declare_spatial(Builder *b, const Stmt *s)
{
    static const char *const suffix[7] = {".x", ".y", ".z", ".e0", ".e1", ".e2", ".e3"};
    static const char *const word[3] = {"x", "y", "z"};
    char what[64];
    bool body = s->kind == STMT_BODY;
    double v[7];
    for (int i = 0; i < 3; i++) {
        snprintf(what, sizeof what, "the initial %s", word[i]);
        v[i] = constant_value(b, s->init[i], what);
    }
    double arg[4] = {0, 0, 0, 0};
    int nargs = s->orient == ORIENT_AXIS ? 4 : s->orient == ORIENT_NONE ? 0 : 3;
    for (int i = 0; i < nargs; i++)
        arg[i] = constant_value(b, s->orient_arg[i], "an orientation component");
    if (body && !orient_to_euler(s->orient, arg, v + 3))
        diag_fail(b->diag, s->orient_pos, "the orientation of body '%s' cannot be normalised: "
                  "its axis is zero", s->name);
    Entity *e = declare(b, body ? ENT_BODY : ENT_POINT, s->name, s->name_pos);
    for (int i = 0; i < (body ? 7 : 3); i++) {
        int q = add_coord(b, s->name, suffix[i], v[i], s->name_pos);
        if (i == 0)
            e->q = q;
    }
    if (!body)
        return;
    Joint *j = new_joint(b);
    *j = (Joint){.kind = JOINT_S_NORM, .name = s->name, .pos = s->pos, .option = DAG_ZERO,
                 .expr = DAG_NONE, .a = {.q = e->q, .spatial = true, .has_p = true}};
    lower_joint(b, j);
}

static void declare_coordinates(Builder *b, const Stmt *s)
{
    static const char *const suffix[3] = {".x", ".y", ".phi"};
    static const char *const word[3] = {"x", "y", "phi"};
    char what[64];
    if (s->kind == STMT_COORD) {
        Entity *e = declare(b, ENT_COORD, s->name, s->name_pos);
        double v = constant_value(b, s->value, "the initial value");
        e->q = add_coord(b, s->name, "", v, s->name_pos);
        return;
    }
    if (b->spatial) {
        declare_spatial(b, s);
        return;
    }
    int n = s->kind == STMT_BODY ? 3 : 2;
    double v[3];
    for (int i = 0; i < n; i++) {
        snprintf(what, sizeof what, "the initial %s", word[i]);
        v[i] = constant_value(b, s->init[i], what);
    }
    Entity *e = declare(b, s->kind == STMT_BODY ? ENT_BODY : ENT_POINT, s->name, s->name_pos);
    for (int i = 0; i < n; i++) {
        int q = add_coord(b, s->name, suffix[i], v[i], s->name_pos);
        if (i == 0)
            e->q = q;
    }
}

static Attach resolve_attach(Builder *b, const AstAttach *at, AttachRule rule,
                             const char *keyword)
{
    Attach r = {.q = -1, .spatial = b->spatial};
    if (at->has_offset) {
        r.sx = constant_value(b, at->sx, "an attachment offset");
        r.sy = constant_value(b, at->sy, "an attachment offset");
        if (b->spatial)
            r.sz = constant_value(b, at->sz, "an attachment offset");
    }
    if (strcmp(at->name, "ground") == 0) {
        if (rule == ATTACH_BODY || rule == ATTACH_BODY_ONLY)
            diag_fail(b->diag, at->pos, "%s needs a body here, not ground", keyword);
        return r;
    }
    Entity *e = lookup(b, at->name, at->pos);
    switch (e->kind) {
    case ENT_BODY:
        if (rule == ATTACH_BODY_ONLY && at->has_offset)
            diag_fail(b->diag, at->pos, "%s takes the body name alone, without an offset", keyword);
        r.q = e->q;
        r.has_phi = !b->spatial;
        r.has_p = b->spatial;
        return r;
    case ENT_POINT:
        if (rule != ATTACH_ANY)
            diag_fail(b->diag, at->pos, "%s needs a body%s here; '%s' is a point (it has no angle)",
                      keyword, rule == ATTACH_FRAME ? " or ground" : "", e->name);
        if (at->has_offset)
            diag_fail(b->diag, at->pos, "'%s' is a point: it has no local frame, write '%s' without an offset",
                      e->name, e->name);
        r.q = e->q;
        return r;
    case ENT_PARAM: case ENT_COORD: case ENT_JOINT: case ENT_OUTPUT: case ENT_MASS:
    case ENT_FORCE:
        break;
    }
    static const char *const takes[] = {
        [ATTACH_ANY] = "bodies, points or ground", [ATTACH_FRAME] = "bodies or ground",
        [ATTACH_BODY] = "a body", [ATTACH_BODY_ONLY] = "a body", [ATTACH_NONE] = "nothing",
    };
    diag_fail(b->diag, at->pos, "'%s' is %s; %s attaches to %s",
              e->name, entity_word(e->kind), keyword, takes[rule]);
}

static void push_row(Builder *b, const Joint *j, int index, NodeId expr)
{
    Model *m = b->model;
    const JointInfo *info = &joint_info[j->kind];
    if (b->npos + b->nvel >= b->limits->max_rows)
        diag_fail(b->diag, j->pos, "too many rows (the limit is %d)", b->limits->max_rows);
    check_jacobian_size(b, b->npos + b->nvel + 1, m->nq, j->pos);
    const char *suffix = info->suffix[index];
    char *name = arena_alloc(&m->arena, strlen(j->name) + strlen(suffix) + 1);
    strcpy(name, j->name);
    strcat(name, suffix);
    Row row = {.name = name, .kind = j->kind, .velocity = j->velocity, .expr = expr,
               .joint = (int)(j - m->joints), .pos = j->pos};
    if (j->velocity) {
        grow(&b->scratch, (void **)&b->vel_rows, &b->cap_vel, b->nvel + 1, sizeof *b->vel_rows);
        b->vel_rows[b->nvel++] = row;
    } else {
        grow(&b->scratch, (void **)&b->pos_rows, &b->cap_pos, b->npos + 1, sizeof *b->pos_rows);
        b->pos_rows[b->npos++] = row;
    }
}

/* A side's axis u at the start, global: turned by its body's initial
   Euler parameters (ground and points do not turn). */
static void initial_axis(const Model *m, Attach at, const double u[3], double out[3])
{
    if (!at.has_p) {
        for (int i = 0; i < 3; i++)
            out[i] = u[i];
        return;
    }
    orient_rotate(m->q0 + at.q + 3, u, out);
}

/* A universal's or perpendicular's row hA^T hB = 0 has no gradient in the
   orientations where the two axes are parallel (d(hA^T hB) = (wA - wB)^T
   (hA x hB)): assembly cannot start there, and the joint as written is
   not what was meant. Parallel: |hA x hB| <= 1e-9 |hA| |hB|. */
static void check_not_parallel(Builder *b, const Stmt *s, const Joint *j, double u[2][3])
{
    double ha[3], hb[3];
    initial_axis(b->model, j->a, u[0], ha);
    initial_axis(b->model, j->b, u[1], hb);
    double c[3] = {ha[1] * hb[2] - ha[2] * hb[1], ha[2] * hb[0] - ha[0] * hb[2],
                   ha[0] * hb[1] - ha[1] * hb[0]};
    double na = sqrt(ha[0] * ha[0] + ha[1] * ha[1] + ha[2] * ha[2]);
    double nb = sqrt(hb[0] * hb[0] + hb[1] * hb[1] + hb[2] * hb[2]);
    double nc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    if (nc <= 1e-9 * na * nb)
        diag_fail(b->diag, s->axis_b_pos,
                  "the two axes of %s '%s' are parallel in the initial orientations: its "
                  "row keeps them perpendicular and has no gradient where they are parallel",
                  joint_info[s->joint].keyword, s->name);
}

/* A rolling disk lying flat (its axle vertical) has no lowest rim point:
   its rows divide by the axle's horizontal length (joints_spatial.c). */
static void check_not_flat(Builder *b, const Stmt *s, const Joint *j, const double u[3])
{
    double a[3];
    initial_axis(b->model, j->a, u, a);
    double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (sqrt(a[0] * a[0] + a[1] * a[1]) <= 1e-9 * n)
        diag_fail(b->diag, s->axis_pos,
                  "the disk of rolling '%s' lies flat in its initial orientation (its axle "
                  "is vertical): it has no lowest rim point, and its rows are not defined",
                  s->name);
}

/* A spatial joint's axes: A's (ux, uy, uz), B's (bx, by, bz), neither zero. */
static void spatial_axes(Builder *b, const Stmt *s, Joint *j)
{
    const JointInfo *info = &joint_info[s->joint];
    double u[2][3];
    for (int k = 0; k < 2; k++) {
        Ast *const *ax = k == 0 || !s->axis_b[0] ? s->axis : s->axis_b;
        SrcPos pos = k == 0 || !s->axis_b[0] ? s->axis_pos : s->axis_b_pos;
        for (int i = 0; i < 3; i++)
            u[k][i] = constant_value(b, ax[i], "an axis component");
        if (u[k][0] == 0.0 && u[k][1] == 0.0 && u[k][2] == 0.0)
            diag_fail(b->diag, pos, "the axis of %s '%s' is zero", info->keyword, s->name);
    }
    j->ux = u[0][0], j->uy = u[0][1], j->uz = u[0][2];
    j->bx = u[1][0], j->by = u[1][1], j->bz = u[1][2];
    if (s->joint == JOINT_S_UNIVERSAL || s->joint == JOINT_S_PERPENDICULAR)
        check_not_parallel(b, s, j, u);
    if (s->joint == JOINT_S_ROLLING)
        check_not_flat(b, s, j, u[0]);
}

/* A rolling disk's holonomic companion: its contact point on the plane
   (row J.h), a joint of its own kind after the rolling joint. */
static void add_contact(Builder *b, int rolling)
{
    Joint *j = new_joint(b);
    *j = b->model->joints[rolling];
    j->kind = JOINT_S_CONTACT;
    j->velocity = false;
    lower_joint(b, j);
}

/* Counts j (the next joint) and pushes its rows. */
static void lower_joint(Builder *b, Joint *j)
{
    Model *m = b->model;
    const JointInfo *info = &joint_info[j->kind];
    m->njoints++;
    NodeId rows[JOINT_MAX_ROWS];
    joints_lower(m, j, rows);
    check_nodes(b);
    j->nrows = info->rows;
    for (int i = 0; i < info->rows; i++)
        push_row(b, j, i, rows[i]);
}

/* lhs - rhs of a constraint, driver or velocity statement; in a spatial
   file, driver D: angle(R) = theta is the branch-free row of
   joints_spatial_angle_row. */
static NodeId statement_row(Builder *b, const Stmt *s, ExprContext ctx, Joint *j)
{
    Model *m = b->model;
    if (b->spatial && s->joint == JOINT_DRIVER && s->lhs->kind == AST_ANGLE && ctx != EXPR_VELOCITY) {
        NodeId theta = lower(b, s->rhs, ctx);
        Entity *e = lookup(b, s->lhs->name, s->lhs->member_pos);
        const Joint *r = e->kind == ENT_JOINT ? &m->joints[e->q] : NULL;
        NodeId row = joints_spatial_angle_row(m, spatial_joint_of(b, s->lhs, e, r), theta);
        check_nodes(b);
        j->measures = e->q + 1, j->option = theta;  /* for the generic evaluator's formula */
        return row;
    }
    NodeId rhs = lower(b, s->rhs, ctx);     /* sequenced: see AST_BINARY */
    NodeId lhs = lower(b, s->lhs, ctx);
    if (b->spatial && s->joint == JOINT_DRIVER && s->lhs->kind == AST_SLIDE && ctx != EXPR_VELOCITY)
        j->measures = -(lookup(b, s->lhs->name, s->lhs->member_pos)->q + 1), j->option = rhs;
    return dag_sub(&m->dag, lhs, rhs);
}

static void build_joint(Builder *b, const Stmt *s)
{
    Model *m = b->model;
    const JointInfo *info = &joint_info[s->joint];
    declare(b, ENT_JOINT, s->name, s->name_pos)->q = m->njoints;
    Joint *j = new_joint(b);
    *j = (Joint){.kind = s->joint, .name = s->name, .pos = s->pos,
                 .option = DAG_ZERO, .expr = DAG_NONE};
    for (int i = 0; i < info->attachments; i++) {
        Attach at = resolve_attach(b, &s->attach[i], info->slot[i], info->keyword);
        if (i == 0)
            j->a = at;
        else
            j->b = at;
    }
    /* A joint between a frame and itself constrains nothing (or is
       unsatisfiable): always a mistake in the joint list. */
    if (info->attachments == 2 && j->a.q == j->b.q)
        diag_fail(b->diag, s->attach[1].pos, j->a.q < 0
                  ? "%s '%s' joins ground to ground: its rows depend on no coordinate"
                  : "%s '%s' joins '%s' to itself: its rows depend on no relative motion",
                  info->keyword, s->name, s->attach[0].name);
    if (info->axis && b->spatial) {
        spatial_axes(b, s, j);
    } else if (info->axis) {
        j->ux = constant_value(b, s->axis[0], "the axis component ux");
        j->uy = constant_value(b, s->axis[1], "the axis component uy");
        if (j->ux == 0.0 && j->uy == 0.0)
            diag_fail(b->diag, s->axis_pos, "the axis of %s '%s' is zero", info->keyword, s->name);
    }
    if (s->option) {
        j->option = lower(b, s->option, EXPR_TIMED);
    }
    switch (info->level) {
    case LEVEL_POSITION: j->velocity = false; break;
    case LEVEL_VELOCITY: j->velocity = true; break;
    case LEVEL_EITHER:   j->velocity = mentions_der(s->lhs) || mentions_der(s->rhs); break;
    }
    if (info->attachments == 0) {
        if (s->joint == JOINT_VELOCITY && !mentions_der(s->lhs) && !mentions_der(s->rhs))
            diag_fail(b->diag, s->pos, "velocity row '%s' contains no der(): "
                      "write it as a 'constraint' or use der(coordinate)", s->name);
        j->expr = statement_row(b, s, j->velocity ? EXPR_VELOCITY : EXPR_HOLONOMIC, j);
    }
    lower_joint(b, j);
    if (s->joint == JOINT_S_ROLLING)
        add_contact(b, m->njoints - 1);
}

/* The body table: the bodies and points among the declared names. */
static void collect_bodies(Builder *b)
{
    Model *m = b->model;
    int n = 0;
    for (int i = 0; i < b->nentities; i++)
        n += b->entities[i].kind == ENT_BODY || b->entities[i].kind == ENT_POINT;
    m->bodies = arena_alloc_array(&m->arena, (size_t)n, sizeof *m->bodies);
    for (int i = 0; i < b->nentities; i++) {
        const Entity *e = &b->entities[i];
        if (e->kind != ENT_BODY && e->kind != ENT_POINT)
            continue;
        bool body = e->kind == ENT_BODY;
        int nq = b->spatial ? (body ? 7 : 3) : (body ? 3 : 2);
        m->bodies[m->nbodies++] = (Body){.name = e->name, .q = e->q, .nq = nq,
                                         .has_phi = body && !b->spatial, .spatial = b->spatial};
    }
}

static void push_output(Builder *b, const char *name, const char *suffix, NodeId expr)
{
    Model *m = b->model;
    grow(&m->arena, (void **)&m->outputs, &b->cap_outputs, m->nout + 1, sizeof *m->outputs);
    char *full = arena_alloc(&m->arena, strlen(name) + strlen(suffix) + 1);
    strcpy(full, name);
    strcat(full, suffix);
    m->outputs[m->nout++] = (ModelOutput){.name = full, .expr = expr};
}

static ModelOutput *last_output(Builder *b)
{
    return &b->model->outputs[b->model->nout - 1];
}

/* output NAME = e: one value; output NAME: attachment: the point's NAME.x,
   NAME.y, P = r + A(phi) s as in a joint. Outputs add no rows. */
static void build_output(Builder *b, const Stmt *s)
{
    declare(b, ENT_OUTPUT, s->name, s->name_pos);
    if (mentions_der(s->value))
        diag_fail(b->diag, s->pos, "output '%s' contains der(): an output is a value of the "
                  "coordinates and t, whose velocity run reports anyway", s->name);
    if (s->value) {
        push_output(b, s->name, "", lower_expr(b, s->value, EXPR_HOLONOMIC));
        return;
    }
    Attach at = resolve_attach(b, &s->attach[0], ATTACH_ANY, "output");
    if (b->spatial) {
        NodeId xyz[3];
        joints_spatial_point(b->model, at, xyz);
        push_output(b, s->name, ".x", xyz[0]);
        last_output(b)->point = s->name;    /* the animation draws its path */
        last_output(b)->at = at;
        push_output(b, s->name, ".y", xyz[1]);
        push_output(b, s->name, ".z", xyz[2]);
        return;
    }
    NodeId xy[2];
    joints_point(b->model, at, xy);
    push_output(b, s->name, ".x", xy[0]);
    last_output(b)->point = s->name;
    last_output(b)->at = at;
    push_output(b, s->name, ".y", xy[1]);
}

/* ---- dynamics statements: masses and applied forces ---- */

/* A constant key's value (0 when absent), refused when negative. */
static double dyn_constant(Builder *b, const Stmt *s, DynKey key, const char *what, bool nonnegative)
{
    double v = constant_value(b, s->key[key], what);
    if (nonnegative && v < 0)
        diag_fail(b->diag, s->key_pos[key], "%s of %s '%s' is negative (%g)", what,
                  dyn_keyword(s), s->name, v);
    return v;
}

/* A key's expression of q, der(q) and t (absent: 0). */
static NodeId dyn_expr(Builder *b, const Ast *ast)
{
    return ast ? lower(b, ast, EXPR_VELOCITY) : DAG_ZERO;
}

/* The global position of a dynamics attachment: a body point, a
   particle, ground, or at(x, y) (ctx: what at's expressions may use);
   in a spatial file xy[2] is z (xy has room for three). */
static void dyn_point(Builder *b, const AstAttach *at, ExprContext ctx, const char *keyword,
                      NodeId xy[3])
{
    if (at->at) {
        NodeId z = b->spatial ? lower(b, at->sz, ctx) : DAG_ZERO;
        NodeId y = lower(b, at->sy, ctx);    /* sequenced: see AST_BINARY */
        xy[0] = lower(b, at->sx, ctx);
        xy[1] = y;
        xy[2] = z;
        return;
    }
    Attach a = resolve_attach(b, at, ATTACH_ANY, keyword);
    xy[2] = DAG_ZERO;
    if (b->spatial)
        joints_spatial_point(b->model, a, xy);
    else
        joints_point(b->model, a, xy);
    check_nodes(b);
}

/* The angle of a body (ATTACH_FRAME, no offset): its phi, 0 for ground. */
static NodeId dyn_angle(Builder *b, const AstAttach *at, const char *keyword)
{
    Attach a = resolve_attach(b, at, ATTACH_FRAME, keyword);
    return a.has_phi ? dag_var(&b->model->dag, a.q + 2) : DAG_ZERO;
}

static MassElement *new_mass(Builder *b, const Stmt *s)
{
    Model *m = b->model;
    for (int i = 0; i < m->nmasses; i++)
        if (!s->declares && strcmp(m->masses[i].name, s->name) == 0)
            diag_fail(b->diag, s->name_pos, "'%s' already has a mass (line %d): give a body one "
                      "mass statement", s->name, line_of(b, m->masses[i].pos));
    grow(&m->arena, (void **)&m->masses, &b->cap_masses, m->nmasses + 1, sizeof *m->masses);
    MassElement *e = &m->masses[m->nmasses++];
    *e = (MassElement){.name = s->name, .pos = s->pos, .theta = DAG_ZERO, .body = -1,
                       .spatial = b->spatial, .pz = DAG_ZERO, .euler = -1};
    e->m = dyn_constant(b, s, DKEY_M, "the mass m", true);
    if (!b->spatial)    /* a spatial J is a tensor: spatial_inertia */
        e->J = dyn_constant(b, s, DKEY_J, "the moment of inertia J", true);
    return e;
}

/* The eigenvalues of the symmetric 3 x 3 matrix t (xx, yy, zz, xy, xz,
   yz), ascending, by the trigonometric closed form (Smith 1961) on t
   divided by its largest entry (squares of entries near 1e200 would
   overflow); a diagonal t gives its sorted diagonal exactly (the closed
   form leaves a rounding error there: (0, 1, 1) would read -1.1e-16). */
static void symmetric_eigenvalues(const double t[6], double ev[3])
{
    if (t[3] == 0 && t[4] == 0 && t[5] == 0) {
        double a = t[0], b = t[1], c = t[2], x;
        if (a > b)
            x = a, a = b, b = x;
        if (b > c)
            x = b, b = c, c = x;
        if (a > b)
            x = a, a = b, b = x;
        ev[0] = a, ev[1] = b, ev[2] = c;
        return;
    }
    double scale = 0;
    for (int i = 0; i < 6; i++)
        scale = fmax(scale, fabs(t[i]));
    double u[6];
    for (int i = 0; i < 6; i++)
        u[i] = t[i] / scale;
    double p1 = u[3] * u[3] + u[4] * u[4] + u[5] * u[5];
    double q = (u[0] + u[1] + u[2]) / 3;
    double p2 = (u[0] - q) * (u[0] - q) + (u[1] - q) * (u[1] - q) + (u[2] - q) * (u[2] - q) + 2 * p1;
    double p = sqrt(p2 / 6);
    double b[6];
    for (int i = 0; i < 6; i++)
        b[i] = (u[i] - (i < 3 ? q : 0)) / p;
    double det = b[0] * (b[1] * b[2] - b[5] * b[5]) - b[3] * (b[3] * b[2] - b[5] * b[4])
                 + b[4] * (b[3] * b[5] - b[1] * b[4]);
    double r = fmax(-1.0, fmin(1.0, det / 2));
    double phi = acos(r) / 3;
    ev[2] = q + 2 * p * cos(phi);
    ev[0] = q + 2 * p * cos(phi + 2 * 3.14159265358979323846 / 3);
    ev[1] = 3 * q - ev[0] - ev[2];
    for (int i = 0; i < 3; i++)
        ev[i] *= scale;
}

/* A spatial body's J = (Jxx, Jyy, Jzz) and products Jxy, Jxz, Jyz: the
   inertia tensor about the centre of mass in body axes (its entries, so
   Jxy = -sum m x y). Absent: 0 (a particle carried by the body). Given,
   it must be positive definite and its principal moments must satisfy
   the triangle inequality, as every mass distribution's do. */
static void spatial_inertia(Builder *b, const Stmt *s, MassElement *e)
{
    static const char *const diag_names[3] = {"Jxx", "Jyy", "Jzz"};
    static const DynKey product[3] = {DKEY_JXY, DKEY_JXZ, DKEY_JYZ};
    char what[64];
    if (!s->key[DKEY_J]) {
        for (int i = 0; i < 3; i++)
            if (s->key[product[i]])
                diag_fail(b->diag, s->key_pos[product[i]], "'%s' without J = (Jxx, Jyy, Jzz): "
                          "give the tensor's diagonal too", dyn_key_names[product[i]]);
        return;
    }
    for (int i = 0; i < 3; i++) {
        snprintf(what, sizeof what, "the moment of inertia %s", diag_names[i]);
        e->inertia[i] = constant_value(b, s->inertia[i], what);
        if (e->inertia[i] < 0)
            diag_fail(b->diag, s->inertia[i]->pos, "%s of mass '%s' is negative (%g)", what,
                      s->name, e->inertia[i]);
    }
    for (int i = 0; i < 3; i++) {
        snprintf(what, sizeof what, "the product of inertia %s", dyn_key_names[product[i]]);
        e->inertia[3 + i] = dyn_constant(b, s, product[i], what, false);
    }
    double ev[3];
    symmetric_eigenvalues(e->inertia, ev);
    double scale = fmax(fabs(ev[0]), fabs(ev[2]));
    if (!(ev[0] > 1e-12 * scale) || scale == 0)
        diag_fail(b->diag, s->key_pos[DKEY_J], "the inertia tensor of '%s' is not positive "
                  "definite: its principal moments are %g, %g, %g", s->name, ev[0], ev[1], ev[2]);
    if (ev[0] + ev[1] < ev[2] * (1 - 1e-12))
        diag_fail(b->diag, s->key_pos[DKEY_J], "the inertia tensor of '%s' is no body's: its "
                  "principal moments %g + %g < %g break the triangle inequality", s->name,
                  ev[0], ev[1], ev[2]);
}

/* mass BODY m = .. [J = (..) Jxy = ..] [com(sx, sy, sz)] in a spatial
   file: the centre of mass r + A(e) s, the tensor about it; a point's
   mass is at the point. */
static void spatial_body_mass(Builder *b, const Stmt *s, const Entity *ent, MassElement *e)
{
    bool body = ent->kind == ENT_BODY;
    Attach at = {.q = ent->q, .spatial = true, .has_p = body};
    if (s->vec[0]) {
        at.sx = constant_value(b, s->vec[0], "a centre-of-mass offset");
        at.sy = constant_value(b, s->vec[1], "a centre-of-mass offset");
        at.sz = constant_value(b, s->vec[2], "a centre-of-mass offset");
    }
    NodeId xyz[3];
    joints_spatial_point(b->model, at, xyz);
    e->px = xyz[0], e->py = xyz[1], e->pz = xyz[2];
    check_nodes(b);
    if (body) {
        e->euler = ent->q + 3;
        spatial_inertia(b, s, e);
    }
}

/* mass BODY m = .. [J = ..] [com(sx, sy)]: the body's centre of mass
   r + A(phi) s, J about it; mass POINT m = ..: the particle itself. */
static void build_body_mass(Builder *b, const Stmt *s)
{
    Entity *ent = lookup(b, s->name, s->name_pos);
    if (ent->kind != ENT_BODY && ent->kind != ENT_POINT)
        diag_fail(b->diag, s->name_pos, "'%s' is %s; 'mass NAME m = ...' gives a body or point its "
                  "mass (write 'mass NAME: at(x, y) m = ...' for a mass element)", s->name,
                  entity_word(ent->kind));
    bool body = ent->kind == ENT_BODY;
    if (!body && s->key[DKEY_J])
        diag_fail(b->diag, s->key_pos[DKEY_J], "'%s' is a point (a particle): it has no angle, "
                  "so no moment of inertia J", s->name);
    if (!body && s->vec[0])
        diag_fail(b->diag, s->vec_pos, "'%s' is a point (a particle): its mass is at the point, "
                  "no com(...)", s->name);
    MassElement *e = new_mass(b, s);
    if (b->spatial) {
        spatial_body_mass(b, s, ent, e);
        return;
    }
    Attach at = {.q = ent->q, .has_phi = body};
    if (s->vec[0]) {
        at.sx = constant_value(b, s->vec[0], "a centre-of-mass offset");
        at.sy = constant_value(b, s->vec[1], "a centre-of-mass offset");
    }
    NodeId xy[2];
    joints_point(b->model, at, xy);
    e->px = xy[0], e->py = xy[1];
    if (body) {
        e->theta = dag_var(&b->model->dag, ent->q + 2);
        e->body = ent->q;
        e->sx = at.sx, e->sy = at.sy;
    }
    check_nodes(b);
}

/* mass NAME: at(x, y) m = .. [J = .. angle = ..]: a mass element given by
   expressions of the coordinates (not of t). */
static void build_element_mass(Builder *b, const Stmt *s)
{
    declare(b, ENT_MASS, s->name, s->name_pos);
    if (s->key[DKEY_J] && !s->key[DKEY_ANGLE])
        diag_fail(b->diag, s->key_pos[DKEY_J], "mass '%s' has J but no 'angle = ...': the "
                  "angle whose rate J multiplies", s->name);
    MassElement *e = new_mass(b, s);
    NodeId xy[3];
    dyn_point(b, &s->attach[0], EXPR_MASS, "mass", xy);
    e->px = xy[0], e->py = xy[1], e->pz = xy[2];
    if (s->key[DKEY_ANGLE])
        e->theta = lower(b, s->key[DKEY_ANGLE], EXPR_MASS);
}

static AppliedForce *new_force(Builder *b, const Stmt *s, ForceKind kind)
{
    Model *m = b->model;
    declare(b, ENT_FORCE, s->name, s->name_pos);
    grow(&m->arena, (void **)&m->forces, &b->cap_forces, m->nforces + 1, sizeof *m->forces);
    AppliedForce *f = &m->forces[m->nforces++];
    *f = (AppliedForce){.kind = kind, .name = s->name, .pos = s->pos, .ax = DAG_ZERO,
                        .ay = DAG_ZERO, .bx = DAG_ZERO, .by = DAG_ZERO, .fx = DAG_ZERO,
                        .fy = DAG_ZERO, .coord = -1, .az = DAG_ZERO, .bz = DAG_ZERO,
                        .fz = DAG_ZERO};
    return f;
}

/* A spring's or a force's attachment must move: ground does no work. */
static void refuse_ground(Builder *b, const Stmt *s, int n)
{
    for (int i = 0; i < n; i++)
        if (s->attach[i].name && strcmp(s->attach[i].name, "ground") == 0
            && (n == 1 || (s->attach[1 - i].name && strcmp(s->attach[1 - i].name, "ground") == 0)))
            diag_fail(b->diag, s->attach[i].pos, "%s '%s' acts on ground only: it does no work",
                      dyn_keyword(s), s->name);
}

/* Whether any of the n expressions depends on a coordinate. A point or
   angle that depends on none has no virtual displacement (t is held), so
   a force applied there does no work: the same mistake as ground. */
static bool depends_on_q(Builder *b, const NodeId *e, int n)
{
    SupportScan scan;
    support_init(&scan);
    int *out = xmalloc(((size_t)b->model->nq + 1) * sizeof *out), found = 0;
    for (int i = 0; i < n && !found; i++)
        found = support_collect(&scan, &b->model->dag, e[i], OP_VAR, out);
    free(out);
    support_free(&scan);
    return found > 0;
}

/* The checks that need the lowered attachments: a force must move with
   the coordinates (refuse_ground catches ground by name), a spring needs
   two distinct points (nodes are hash-consed: the same point is the same
   ids, and its length would be 0 at every state). */
static void refuse_idle(Builder *b, const Stmt *s, const AppliedForce *f)
{
    const char *kw = dyn_keyword(s);
    NodeId a[3] = {f->ax, f->ay, f->az}, ab[6] = {f->ax, f->ay, f->bx, f->by, f->az, f->bz};
    if (f->kind == FORCE_POINT && !depends_on_q(b, a, 3))
        diag_fail(b->diag, s->attach[0].pos, "%s '%s' is applied at a fixed point (it depends "
                  "on no coordinate): it does no work", kw, s->name);
    if (f->kind == FORCE_TORQUE && s->lhs && !depends_on_q(b, a, 1))
        diag_fail(b->diag, s->lhs->pos, "%s '%s' acts on an angle that depends on no "
                  "coordinate: it does no work", kw, s->name);
    if (f->kind == FORCE_SPRING && f->ax == f->bx && f->ay == f->by && f->az == f->bz)
        diag_fail(b->diag, s->attach[1].pos, "%s '%s' joins a point to itself: its length is "
                  "always 0", kw, s->name);
    if (f->kind == FORCE_SPRING && !depends_on_q(b, ab, 6))
        diag_fail(b->diag, s->attach[0].pos, "%s '%s' joins two fixed points (they depend on no "
                  "coordinate): it does no work", kw, s->name);
}

/* torque NAME: angle(e) = tau: e, or in a spatial file a revolute's or
   cylindrical's name R alone for angle(R) (a motor between its bodies). */
static NodeId torque_angle(Builder *b, const Ast *lhs)
{
    int index;
    if (b->spatial && lhs->kind == AST_NAME && strmap_get(&b->names, lhs->name, &index)
        && b->entities[index].kind == ENT_JOINT) {
        const Joint *j = &b->model->joints[b->entities[index].q];
        if (j->kind != JOINT_S_REVOLUTE && j->kind != JOINT_S_CYLINDRICAL)
            diag_fail(b->diag, lhs->pos, "torque: angle(%s) takes a revolute or cylindrical "
                      "joint; '%s' is %s", lhs->name, lhs->name, joint_info[j->kind].keyword);
        NodeId a = joints_spatial_angle(b->model, j);
        check_nodes(b);
        return a;
    }
    return lower(b, lhs, EXPR_HOLONOMIC);
}

/* force NAME: ATTACHMENT (fx, fy): Q += p_q^T (fx, fy) */
static void build_POINT(Builder *b, const Stmt *s, AppliedForce *f)
{
    NodeId xy[3];
    dyn_point(b, &s->attach[0], EXPR_HOLONOMIC, dyn_keyword(s), xy);
    f->ax = xy[0], f->ay = xy[1], f->az = xy[2];
    refuse_idle(b, s, f);
    if (b->spatial)
        f->fz = dyn_expr(b, s->vec[2]);
    f->fy = dyn_expr(b, s->vec[1]);
    f->fx = dyn_expr(b, s->vec[0]);
}

/* torque NAME: BODY = tau | angle(e) = tau */
static void build_TORQUE(Builder *b, const Stmt *s, AppliedForce *f)
{
    f->ax = s->lhs ? torque_angle(b, s->lhs) : dyn_angle(b, &s->attach[0], dyn_keyword(s));
    refuse_idle(b, s, f);
    f->fx = dyn_expr(b, s->value);
}

/* torque NAME: BODY = (tx, ty, tz) in a spatial file: a torque in global
   axes on a body, Q[e] += 2 E(e)^T tau (the virtual work tau . w, w = 2 E ed). */
static void build_BODY_TORQUE(Builder *b, const Stmt *s, AppliedForce *f)
{
    Attach a = resolve_attach(b, &s->attach[0], ATTACH_FRAME, dyn_keyword(s));
    f->coord = a.q + 3;
    f->fz = dyn_expr(b, s->vec[2]);
    f->fy = dyn_expr(b, s->vec[1]);
    f->fx = dyn_expr(b, s->vec[0]);
}

/* spring NAME: A B k = .. c = .. length = .. force = .. */
static void build_SPRING(Builder *b, const Stmt *s, AppliedForce *f)
{
    const char *kw = dyn_keyword(s);
    NodeId xy[3];
    f->k = dyn_constant(b, s, DKEY_K, "the stiffness k", true);
    f->c = dyn_constant(b, s, DKEY_C, "the damping c", true);
    f->free = dyn_constant(b, s, DKEY_LENGTH, "the free length", true);
    dyn_point(b, &s->attach[0], EXPR_HOLONOMIC, kw, xy);
    f->ax = xy[0], f->ay = xy[1], f->az = xy[2];
    dyn_point(b, &s->attach[1], EXPR_HOLONOMIC, kw, xy);
    f->bx = xy[0], f->by = xy[1], f->bz = xy[2];
    refuse_idle(b, s, f);
    f->fx = dyn_expr(b, s->key[DKEY_FORCE]);
}

/* rspring NAME: A B k = .. c = .. angle = .. torque = ..: B's angle less
   A's; in a spatial file rspring NAME: R ..., about a joint's axis: B's
   angle is angle(R), A's 0. */
static void build_RSPRING(Builder *b, const Stmt *s, AppliedForce *f)
{
    f->k = dyn_constant(b, s, DKEY_K, "the stiffness k", true);
    f->c = dyn_constant(b, s, DKEY_C, "the damping c", true);
    f->free = dyn_constant(b, s, DKEY_ANGLE, "the free angle", false);
    if (b->spatial) {
        Entity *e = lookup(b, s->attach[0].name, s->attach[0].pos);
        const Joint *j = e->kind == ENT_JOINT ? &b->model->joints[e->q] : NULL;
        if (!j || (j->kind != JOINT_S_REVOLUTE && j->kind != JOINT_S_CYLINDRICAL))
            diag_fail(b->diag, s->attach[0].pos, "a spatial rspring acts about a revolute's "
                      "or cylindrical's axis; '%s' is %s", e->name,
                      j ? joint_info[j->kind].keyword : entity_word(e->kind));
        f->bx = joints_spatial_angle(b->model, j);
        check_nodes(b);
    } else {
        f->ax = dyn_angle(b, &s->attach[0], dyn_keyword(s));
        f->bx = dyn_angle(b, &s->attach[1], dyn_keyword(s));
    }
    f->fx = dyn_expr(b, s->key[DKEY_TORQUE]);
}

/* gforce NAME: COORDINATE = e: Q[coord] += e */
static void build_GENERAL(Builder *b, const Stmt *s, AppliedForce *f)
{
    if (s->lhs->kind != AST_NAME && s->lhs->kind != AST_MEMBER)
        diag_fail(b->diag, s->lhs->pos, "gforce '%s' acts on a coordinate (a coord, or a "
                  "body's x, y or phi), not on %s", s->name, ast_describe(s->lhs));
    f->coord = coordinate_of(b, s->lhs);
    f->fx = dyn_expr(b, s->value);
}

typedef void ForceBuilder(Builder *b, const Stmt *s, AppliedForce *f);

/* Every force kind's builder, by kind (forces.def). */
static ForceBuilder *const force_builders[FORCE_KIND_COUNT] = {
#define X(e, ...) [FORCE_##e] = build_##e,
#include "../parse/forces.def"
#undef X
};

/* One applied force: its attachments must move, then its kind's builder. */
static void build_force(Builder *b, const Stmt *s)
{
    refuse_ground(b, s, force_info[s->force].attachments);
    AppliedForce *f = new_force(b, s, s->force);
    force_builders[s->force](b, s, f);
}

static void build_dynamics(Builder *b, const Stmt *s)
{
    if (s->kind == STMT_MASS) {
        if (s->declares)
            build_element_mass(b, s);
        else
            build_body_mass(b, s);
        return;
    }
    if (!b->first_force)
        b->first_force = s;
    if (s->kind == STMT_FORCE) {
        build_force(b, s);
        return;
    }
    if (b->gravity_line)
        diag_fail(b->diag, s->pos, "a second gravity statement (the first is on line %d)",
                  b->gravity_line);
    b->gravity_line = line_of(b, s->pos);
    b->model->gravity[0] = constant_value(b, s->vec[0], "the gravity component gx");
    b->model->gravity[1] = constant_value(b, s->vec[1], "the gravity component gy");
    if (b->spatial)
        b->model->gravity[2] = constant_value(b, s->vec[2], "the gravity component gz");
}

static void build(Builder *b, const Program *prog, const char *default_name)
{
    Model *m = b->model;
    m->name = default_name;
    const Stmt *last = NULL;
    for (const Stmt *s = prog->first; s; s = s->next) {
        if (s->kind != STMT_OUTPUT && s->kind != STMT_MASS && s->kind != STMT_GRAVITY
            && s->kind != STMT_FORCE)   /* messages about the rows point at a row */
            last = s;
        m->dag.where = s->pos.offset;
        switch (s->kind) {
        case STMT_MECHANISM:
            m->name = s->name;
            break;
        case STMT_SPATIAL:
            m->spatial = b->spatial = true;
            break;
        case STMT_PARAM: {
            double v = constant_value(b, s->value, "the param value");
            declare(b, ENT_PARAM, s->name, s->name_pos)->value = v;
            break;
        }
        case STMT_BODY: case STMT_POINT: case STMT_COORD:
            declare_coordinates(b, s);
            break;
        case STMT_JOINT:
            build_joint(b, s);
            break;
        case STMT_OUTPUT:
            build_output(b, s);
            break;
        case STMT_MASS: case STMT_GRAVITY: case STMT_FORCE:
            build_dynamics(b, s);
            break;
        }
    }
    /* M is dense nq x nq in the engines and the generated P_mass (a limit
       of 0: run's sparse path, which asks for no check here) */
    if (m->nmasses > 0 && b->limits->max_jac_entries > 0
        && (long long)m->nq * m->nq > b->limits->max_jac_entries)
        diag_fail(b->diag, m->masses[0].pos, "the dense mass matrix would have %d x %d = %lld "
                  "entries, more than the limit of %d (--max-jac-entries)", m->nq, m->nq,
                  (long long)m->nq * m->nq, b->limits->max_jac_entries);
    if (b->first_force && m->nmasses == 0)
        diag_fail(b->diag, b->first_force->pos, "%s without masses: the file has no 'mass' "
                  "statement, so there is nothing for it to move", b->first_force->kind == STMT_GRAVITY
                  ? "gravity" : "a force");
    m->dag.where = -1;
    collect_bodies(b);
    SrcPos where = last ? last->pos : (SrcPos){0};
    m->last_pos = where;
    if (m->nq == 0)
        diag_fail(b->diag, where, "the mechanism has no coordinates: declare a body, point or coord");
    if (b->npos + b->nvel == 0)
        diag_fail(b->diag, where, "the mechanism has no constraint rows: add a joint, constraint or driver");
    /* Holonomic rows first, then velocity-level rows. */
    m->nh = b->npos;
    m->nv = b->nvel;
    m->nr = m->nh + m->nv;
    m->rows = arena_alloc_array(&m->arena, (size_t)m->nr, sizeof *m->rows);
    if (m->nh)
        memcpy(m->rows, b->pos_rows, (size_t)m->nh * sizeof *m->rows);
    if (m->nv)
        memcpy(m->rows + m->nh, b->vel_rows, (size_t)m->nv * sizeof *m->rows);
    /* first_row: position of each joint's first row in the final order */
    int pos_seen = 0, vel_seen = 0;
    for (int i = 0; i < m->njoints; i++) {
        Joint *j = &m->joints[i];
        j->first_row = j->velocity ? m->nh + vel_seen : pos_seen;
        if (j->velocity)
            vel_seen += j->nrows;
        else
            pos_seen += j->nrows;
    }
}

/* The builder's one escape (style R3): input errors longjmp here. The
   Builder belongs to the caller, so nothing local to this frame changes
   between setjmp and longjmp. */
static bool build_protected(Builder *b, const Program *prog, const char *default_name)
{
    jmp_buf escape, *saved = b->diag->escape;
    b->diag->escape = &escape;
    bool ok = false;
    if (setjmp(escape) == 0) {
        build(b, prog, default_name);
        ok = true;
    }
    b->diag->escape = saved;
    return ok;
}

Model *model_load(const char *text, int text_len, const char *file,
                  const char *default_name, const MechLimits *limits, Diag *diag)
{
    Model *m = xcalloc(1, sizeof *m);
    arena_init(&m->arena);
    dag_init(&m->dag, limits->max_nodes);
    m->file = arena_strdup(&m->arena, file);
    diag->file = file;
    diag->text = text;
    diag->text_len = text_len;
    Program prog;
    if (!parse_program(&m->arena, diag, limits, &prog)) {
        model_free(m);
        return NULL;
    }
    Builder b = {.model = m, .diag = diag, .limits = limits,
                 .unit_use = {{.offset = -1}, {.offset = -1}}};
    strmap_init(&b.names);
    arena_init(&b.scratch);
    bool ok = build_protected(&b, &prog, arena_strdup(&m->arena, default_name));
    strmap_free(&b.names);
    arena_free(&b.scratch);
    if (!ok) {
        model_free(m);
        return NULL;
    }
    return m;
}

void model_free(Model *model)
{
    if (!model)
        return;
    dag_free(&model->dag);
    arena_free(&model->arena);
    free(model);
}

const Body *model_find_body(const Model *m, const char *name)
{
    for (int i = 0; i < m->nbodies; i++)
        if (strcmp(m->bodies[i].name, name) == 0)
            return &m->bodies[i];
    return NULL;
}

char *model_read_file(const char *path, const MechLimits *limits, int *len, Diag *diag)
{
    FILE *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "rb");
    if (!f) {
        diag_error_nopos(diag, "cannot read '%s': %s", path, strerror(errno));
        return NULL;
    }
    size_t cap = 4096, n = 0;
    char *buf = xmalloc(cap);
    for (;;) {
        if (n + 1 >= cap) {
            cap *= 2;
            buf = xrealloc(buf, cap, 1);
        }
        size_t got = fread(buf + n, 1, cap - n - 1, f);
        n += got;
        if (n > (size_t)limits->max_file_bytes) {
            diag_error_nopos(diag, "'%s' is larger than the limit of %d bytes", path,
                             limits->max_file_bytes);
            free(buf);
            if (f != stdin)
                fclose(f);
            return NULL;
        }
        if (got == 0)
            break;
    }
    bool bad = ferror(f);
    int err = errno;
    if (f != stdin)
        fclose(f);
    if (bad) {
        diag_error_nopos(diag, "cannot read '%s': %s", path, strerror(err));
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    *len = (int)n;
    return buf;
}

char *model_file_stem(Arena *arena, const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    const char *dot = strrchr(base, '.');
    size_t n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    if (n == 0 || strcmp(path, "-") == 0)
        return arena_strdup(arena, "mechanism");
    return arena_strndup(arena, base, n);
}
