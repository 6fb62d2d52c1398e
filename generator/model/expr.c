/* expr.c - expressions to graph nodes: names resolved to params, coordinates and joints, each in the context it may appear in.
 *
 * A constant expression folds to one CONST node in the graph itself; the
 * contexts (ExprContext) say what else an expression may use: t, the
 * coordinates, der(), slide() and angle().
 */
#include "builder.h"

#include "../eval/interp.h"

#include <math.h>
#include <string.h>

/* Units textbook data is written in, as constants: 30*deg, 1500*rpm.
   They are not reserved: a file that declares one of these names (a param
   deg from before they existed) uses its own. */
static const struct { const char *name; double value; } units[2] = {
    {"deg", 3.14159265358979323846 / 180},   /* degree, in radians */
    {"rpm", 3.14159265358979323846 / 30},    /* revolution per minute, in rad/s */
};

/* The index of a unit name in units[], or -1. */
int build_unit_index(const char *name)
{
    for (int i = 0; i < (int)(sizeof units / sizeof *units); i++)
        if (strcmp(name, units[i].name) == 0)
            return i;
    return -1;
}

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
int build_coordinate(Builder *b, const Ast *ast)
{
    Entity *e = build_lookup(b, ast->name, ast->pos);
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
        diag_fail(b->diag, ast->pos, "'%s' is %s, not a coordinate", e->name, build_entity_word(e->kind));
    }
    if (e->kind != ENT_BODY && e->kind != ENT_POINT)
        diag_fail(b->diag, ast->pos, "'%s' is %s and has no components", e->name,
                  build_entity_word(e->kind));
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
const Joint *build_spatial_joint(Builder *b, const Ast *ast, const Entity *e, const Joint *j)
{
    bool slide = ast->kind == AST_SLIDE;
    JointKind want = slide ? JOINT_S_TRANSLATIONAL : JOINT_S_REVOLUTE;
    if (!j || (j->kind != want && j->kind != JOINT_S_CYLINDRICAL))
        diag_fail(b->diag, ast->member_pos, "%s() takes a %s or cylindrical joint; '%s' is %s",
                  slide ? "slide" : "angle", joint_info[want].keyword, e->name,
                  j ? joint_info[j->kind].keyword : build_entity_word(e->kind));
    return j;
}

static NodeId lower_node(Builder *b, const Ast *ast, ExprContext ctx);

/* The node of one sub-expression: a constant made there (a number, a fold)
   and out of range is reported at it (range.c). */
NodeId build_lower_expr(Builder *b, const Ast *ast, ExprContext ctx)
{
    Dag *dag = &b->model->dag;
    int32_t outer = dag->where_expr;
    dag->where_expr = ast->pos.offset;
    NodeId id = lower_node(b, ast, ctx);
    dag->where_expr = outer;
    return id;
}

static NodeId lower_node(Builder *b, const Ast *ast, ExprContext ctx)
{
    Dag *dag = &b->model->dag;
    build_check_nodes(b);         /* before this operand's names are looked up */
    switch (ast->kind) {
    case AST_NUM:
        return dag_const(dag, ast->num);
    case AST_TIME:
        if (ctx == EXPR_CONSTANT || ctx == EXPR_MASS)
            diag_fail(b->diag, ast->pos, "'t' cannot appear in %s", context_what(ctx));
        return dag_time(dag);
    case AST_NAME: {
        int declared, u = build_unit_index(ast->name);
        if (u >= 0 && !strmap_get(&b->names, ast->name, &declared)) {
            if (b->unit_use[u].offset < 0)
                b->unit_use[u] = ast->pos;
            return dag_const(dag, units[u].value);
        }
        Entity *e = build_lookup(b, ast->name, ast->pos);
        if (e->kind == ENT_PARAM)
            return e->node;
        if (ctx <= EXPR_TIMED)
            diag_fail(b->diag, ast->pos, "'%s' is %s; only params may appear in %s",
                      e->name, build_entity_word(e->kind), context_what(ctx));
        return dag_var(dag, build_coordinate(b, ast));
    }
    case AST_MEMBER:
        if (ctx <= EXPR_TIMED) {
            build_lookup(b, ast->name, ast->pos);
            diag_fail(b->diag, ast->pos, "coordinate '%s.%s' cannot appear in %s",
                      ast->name, ast->member, context_what(ctx));
        }
        return dag_var(dag, build_coordinate(b, ast));
    case AST_DER:
        if (ctx != EXPR_VELOCITY)
            diag_fail(b->diag, ast->pos, "der() cannot appear in %s", context_what(ctx));
        if (ast->lhs->kind != AST_NAME && ast->lhs->kind != AST_MEMBER)
            diag_fail(b->diag, ast->lhs->pos, "der() takes a coordinate, not %s",
                      ast_describe(ast->lhs));
        return dag_vard(dag, build_coordinate(b, ast->lhs));
    case AST_NEG:
        return dag_neg(dag, build_lower_expr(b, ast->lhs, ctx));
    case AST_BINARY: {
        /* right operand first, in sequenced statements: argument order is
           unspecified in C, and node ids (so the generated C) must not
           depend on the compiler; gcc had been lowering the right first */
        NodeId y = build_lower_expr(b, ast->rhs, ctx);
        NodeId x = build_lower_expr(b, ast->lhs, ctx);
        return dag_apply(dag, ast->op, x, y);
    }
    case AST_CALL: {
        NodeId x = build_lower_expr(b, ast->lhs, ctx);
        NodeId y = ast->rhs ? build_lower_expr(b, ast->rhs, ctx) : DAG_NONE;
        return dag_apply(dag, ast->op, x, y);
    }
    case AST_SLIDE: {
        if (ctx <= EXPR_TIMED)
            diag_fail(b->diag, ast->pos, "slide() depends on coordinates: it cannot appear in %s",
                      context_what(ctx));
        Entity *e = build_lookup(b, ast->name, ast->member_pos);
        const Joint *j = e->kind == ENT_JOINT ? &b->model->joints[e->q] : NULL;
        if (b->spatial)
            return joints_spatial_slide(b->model, build_spatial_joint(b, ast, e, j));
        if (!j || (j->kind != JOINT_PRISMATIC && j->kind != JOINT_POINTLINE))
            diag_fail(b->diag, ast->member_pos, "slide() takes a prismatic or pointline joint; "
                      "'%s' is %s", e->name, j ? joint_info[j->kind].keyword : build_entity_word(e->kind));
        return joints_slide(b->model, j);
    }
    case AST_ANGLE: {
        if (ctx <= EXPR_TIMED)
            diag_fail(b->diag, ast->pos, "angle() depends on coordinates: it cannot appear in %s",
                      context_what(ctx));
        Entity *e = build_lookup(b, ast->name, ast->member_pos);
        const Joint *j = e->kind == ENT_JOINT ? &b->model->joints[e->q] : NULL;
        return joints_spatial_angle(b->model, build_spatial_joint(b, ast, e, j));
    }
    }
    diag_fail(b->diag, ast->pos, "internal error: unknown expression kind");
}

/* A whole expression, the node limit checked once it is built. */
NodeId build_lower(Builder *b, const Ast *ast, ExprContext ctx)
{
    NodeId id = build_lower_expr(b, ast, ctx);
    build_check_nodes(b);
    return id;
}

/* The first design parameter e uses (e is no constant), for messages. */
static const char *first_design(const Dag *dag, NodeId e)
{
    const DagNode *n = dag_node(dag, e);
    if (n->op == OP_PARAM)
        return dag->param_names[n->a];
    if (dag_is_leaf(dag, e))
        return NULL;
    const char *a = first_design(dag, n->a);
    return a || dag_op_info[n->op].arity < 2 ? a : first_design(dag, n->b);
}

double build_constant(Builder *b, const Ast *ast, const char *what)
{
    if (!ast)
        return 0.0;
    Dag *dag = &b->model->dag;
    NodeId id = build_lower(b, ast, EXPR_CONSTANT);
    double v;
    if (!dag_is_const(dag, id, &v) && first_design(dag, id))
        diag_fail(b->diag, ast->pos, "%s cannot depend on design parameter '%s' (design "
                  "parameters may set offsets, axes, lengths, drivers, constraints, "
                  "outputs and initial values)", what, first_design(dag, id));
    if (!dag_is_const(dag, id, &v) || !isfinite(v))
        diag_fail(b->diag, ast->pos, "%s is not a finite number", what);
    return v;
}

NodeId build_design_value(Builder *b, const Ast *ast, const char *what, double *nominal)
{
    Dag *dag = &b->model->dag;
    NodeId id = build_lower(b, ast, EXPR_CONSTANT);
    if (dag_is_const(dag, id, nominal) && isfinite(*nominal))
        return id;
    *nominal = node_value_at(dag, id, NULL, NULL, 0.0);
    if (!isfinite(*nominal))
        diag_fail(b->diag, ast->pos, "%s is not a finite number%s", what,
                  first_design(dag, id) ? " at the file's design" : "");
    return id;
}

double build_nominal(Builder *b, const Ast *ast, const char *what)
{
    double v = 0.0;
    if (ast)
        build_design_value(b, ast, what, &v);
    return v;
}

bool build_mentions_der(const Ast *ast)
{
    if (!ast)
        return false;
    if (ast->kind == AST_DER)
        return true;
    return build_mentions_der(ast->lhs) || build_mentions_der(ast->rhs);
}
