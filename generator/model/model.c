/* model.c - statements to a resolved mechanism: names, coordinates, joints and rows.
 *
 * Walks the statements in order, so "declared before used" falls out of
 * the walk. Params and initial values are folded to constants through the
 * expression graph itself (a constant expression simplifies to one CONST
 * node); anything else is a position-carrying error. Rows are collected
 * holonomic first, velocity level after, each group in statement order.
 */
#include "builder.h"

#include "../parse/parse.h"
#include "orient.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *build_entity_word(EntityKind kind)
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
void build_grow(Arena *arena, void **p, int *cap, int need, size_t size)
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
void build_check_nodes(Builder *b)
{
    if (!dag_check_limit(&b->model->dag, b->diag))
        diag_throw(b->diag);
}

int build_line(const Builder *b, SrcPos pos)
{
    int line, col;
    diag_locate(b->diag, pos.offset, &line, &col);
    return line;
}

Entity *build_lookup(Builder *b, const char *name, SrcPos pos)
{
    int index;
    if (!strmap_get(&b->names, name, &index))
        diag_fail(b->diag, pos, "unknown name '%s' (names must be declared before use)", name);
    return &b->entities[index];
}

Entity *build_declare(Builder *b, EntityKind kind, const char *name, SrcPos pos)
{
    int index;
    if (strmap_get(&b->names, name, &index))
        diag_fail(b->diag, pos, "duplicate name '%s' (first declared as %s on line %d)",
                  name, build_entity_word(b->entities[index].kind),
                  build_line(b, b->entities[index].pos));
    build_grow(&b->scratch, (void **)&b->entities, &b->cap_entities, b->nentities + 1,
         sizeof *b->entities);
    int u = build_unit_index(name);
    if (u >= 0 && b->unit_use[u].offset >= 0)     /* one name, one meaning per file */
        diag_fail(b->diag, pos, "'%s' was used as the unit %s on line %d: declare it before "
                  "its first use, or choose another name", name, name,
                  build_line(b, b->unit_use[u]));
    Entity *e = &b->entities[b->nentities];
    *e = (Entity){.kind = kind, .name = name, .pos = pos, .q = -1};
    strmap_put(&b->names, name, b->nentities++);
    return e;
}

/* Rows x coordinates of the whole model: the dense Jacobian every engine
   fills (run's sparse path excepted: it asks for no check here,
   max_jac_entries 0). */
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
    int cap = b->cap_coords;    /* q0 shares the capacity of coord_names */
    build_grow(&m->arena, (void **)&m->coord_names, &b->cap_coords, m->nq + 1, sizeof *m->coord_names);
    build_grow(&m->arena, (void **)&m->q0, &cap, m->nq + 1, sizeof *m->q0);
    char *name = arena_alloc(&m->arena, strlen(owner) + strlen(suffix) + 1);
    strcpy(name, owner);
    strcat(name, suffix);
    m->coord_names[m->nq] = name;
    m->q0[m->nq] = q0;
    return m->nq++;
}

/* ---- statements ---- */

static void lower_joint(Builder *b, Joint *j);

/* A new joint at the end of the model's list (not yet counted). */
static Joint *new_joint(Builder *b)
{
    Model *m = b->model;
    build_grow(&m->arena, (void **)&m->joints, &b->cap_joints, m->njoints + 1, sizeof *m->joints);
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
        v[i] = build_nominal(b, s->init[i], what);
    }
    double arg[4] = {0, 0, 0, 0};
    int nargs = s->orient == ORIENT_AXIS ? 4 : s->orient == ORIENT_NONE ? 0 : 3;
    for (int i = 0; i < nargs; i++)
        arg[i] = build_nominal(b, s->orient_arg[i], "an orientation component");
    if (body && !orient_to_euler(s->orient, arg, v + 3))
        diag_fail(b->diag, s->orient_pos, "the orientation of body '%s' cannot be normalised: "
                  "its axis is zero", s->name);
    Entity *e = build_declare(b, body ? ENT_BODY : ENT_POINT, s->name, s->name_pos);
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
        Entity *e = build_declare(b, ENT_COORD, s->name, s->name_pos);
        double v = build_nominal(b, s->value, "the initial value");
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
        v[i] = build_nominal(b, s->init[i], what);
    }
    Entity *e = build_declare(b, s->kind == STMT_BODY ? ENT_BODY : ENT_POINT, s->name, s->name_pos);
    for (int i = 0; i < n; i++) {
        int q = add_coord(b, s->name, suffix[i], v[i], s->name_pos);
        if (i == 0)
            e->q = q;
    }
}

Attach build_attach(Builder *b, const AstAttach *at, AttachRule rule,
                             const char *keyword)
{
    Attach r = {.q = -1, .spatial = b->spatial};
    if (at->has_offset) {
        const Ast *ast[3] = {at->sx, at->sy, b->spatial ? at->sz : NULL};
        double *value[3] = {&r.sx, &r.sy, &r.sz};
        for (int k = 0; k < 3; k++) {
            r.s_node[k] = ast[k] ? build_design_value(b, ast[k], "an attachment offset", value[k])
                                 : DAG_ZERO;
            r.designed |= !dag_is_const(&b->model->dag, r.s_node[k], NULL);
        }
    }
    if (strcmp(at->name, "ground") == 0) {
        if (rule == ATTACH_BODY || rule == ATTACH_BODY_ONLY)
            diag_fail(b->diag, at->pos, "%s needs a body here, not ground", keyword);
        return r;
    }
    Entity *e = build_lookup(b, at->name, at->pos);
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
              e->name, build_entity_word(e->kind), keyword, takes[rule]);
}

static void push_row(Builder *b, const Joint *j, int index, NodeId expr)
{
    Model *m = b->model;
    const JointInfo *info = &joint_info[j->kind];
    if (b->npos + b->nvel >= b->limits->max_rows)
        diag_fail(b->diag, j->pos, "too many rows (the limit is %d)", b->limits->max_rows);
    const char *suffix = info->suffix[index];
    char *name = arena_alloc(&m->arena, strlen(j->name) + strlen(suffix) + 1);
    strcpy(name, j->name);
    strcat(name, suffix);
    Row row = {.name = name, .kind = j->kind, .velocity = j->velocity, .expr = expr,
               .joint = (int)(j - m->joints), .pos = j->pos};
    if (j->velocity) {
        build_grow(&b->scratch, (void **)&b->vel_rows, &b->cap_vel, b->nvel + 1, sizeof *b->vel_rows);
        b->vel_rows[b->nvel++] = row;
    } else {
        build_grow(&b->scratch, (void **)&b->pos_rows, &b->cap_pos, b->npos + 1, sizeof *b->pos_rows);
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

/* An axis that is not zero but whose squared length underflows to 0
   (axis(1e-200, 1e-200, 0): normalised, 0/0) or overflows (1e200: the
   unit axis would be 0), as joints_spatial_frame computes it; refused at
   the axis itself. */
static void check_normalisable(Builder *b, SrcPos pos, const double u[3])
{
    double n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(n > 0) || !isfinite(n))
        diag_fail(b->diag, pos, "this axis (%g, %g, %g) cannot be normalised: its squared "
                  "length %s, so the unit axis would be %s; write it nearer 1", u[0], u[1],
                  u[2], n > 0 ? "overflows past the largest double" : "underflows to 0",
                  n > 0 ? "0" : "NaN (0/0)");
}

/* A spatial joint's axes: A's (ux, uy, uz), B's (bx, by, bz), neither zero
   (at the file's design when design parameters give them: their nodes
   then make the rows, joints_spatial.c). */
static void spatial_axes(Builder *b, const Stmt *s, Joint *j)
{
    const JointInfo *info = &joint_info[s->joint];
    double u[2][3];
    NodeId *node[2] = {j->u_node, j->b_node};
    for (int k = 0; k < 2; k++) {
        Ast *const *ax = k == 0 || !s->axis_b[0] ? s->axis : s->axis_b;
        SrcPos pos = k == 0 || !s->axis_b[0] ? s->axis_pos : s->axis_b_pos;
        for (int i = 0; i < 3; i++) {
            u[k][i] = 0.0;
            node[k][i] = ax[i] ? build_design_value(b, ax[i], "an axis component", &u[k][i])
                               : DAG_ZERO;
            j->axis_designed |= !dag_is_const(&b->model->dag, node[k][i], NULL);
        }
        if (u[k][0] == 0.0 && u[k][1] == 0.0 && u[k][2] == 0.0)
            diag_fail(b->diag, pos, "the axis of %s '%s' is zero%s", info->keyword, s->name,
                      j->axis_designed ? " at the file's design" : "");
        check_normalisable(b, pos, u[k]);
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
    build_check_nodes(b);
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
        NodeId theta = build_lower(b, s->rhs, ctx);
        Entity *e = build_lookup(b, s->lhs->name, s->lhs->member_pos);
        const Joint *r = e->kind == ENT_JOINT ? &m->joints[e->q] : NULL;
        NodeId row = joints_spatial_angle_row(m, build_spatial_joint(b, s->lhs, e, r), theta);
        build_check_nodes(b);
        j->measures = e->q + 1, j->option = theta;  /* for the generic evaluator's formula */
        return row;
    }
    NodeId rhs = build_lower(b, s->rhs, ctx);     /* sequenced: see AST_BINARY */
    NodeId lhs = build_lower(b, s->lhs, ctx);
    if (b->spatial && s->joint == JOINT_DRIVER && s->lhs->kind == AST_SLIDE && ctx != EXPR_VELOCITY)
        j->measures = -(build_lookup(b, s->lhs->name, s->lhs->member_pos)->q + 1), j->option = rhs;
    return dag_sub(&m->dag, lhs, rhs);
}

static void build_joint(Builder *b, const Stmt *s)
{
    Model *m = b->model;
    const JointInfo *info = &joint_info[s->joint];
    build_declare(b, ENT_JOINT, s->name, s->name_pos)->q = m->njoints;
    Joint *j = new_joint(b);
    *j = (Joint){.kind = s->joint, .name = s->name, .pos = s->pos,
                 .option = DAG_ZERO, .expr = DAG_NONE};
    for (int i = 0; i < info->attachments; i++) {
        Attach at = build_attach(b, &s->attach[i], info->slot[i], info->keyword);
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
        NodeId ux = build_design_value(b, s->axis[0], "the axis component ux", &j->ux);
        NodeId uy = build_design_value(b, s->axis[1], "the axis component uy", &j->uy);
        j->axis_designed = !dag_is_const(&m->dag, ux, NULL) || !dag_is_const(&m->dag, uy, NULL);
        j->u_node[0] = ux;
        j->u_node[1] = uy;
        if (j->ux == 0.0 && j->uy == 0.0)
            diag_fail(b->diag, s->axis_pos, "the axis of %s '%s' is zero", info->keyword, s->name);
    }
    if (s->option) {
        j->option = build_lower(b, s->option, EXPR_TIMED);
        double r;
        /* a disk's contact point is R below its centre, on the plane */
        if (s->joint == JOINT_S_ROLLING && dag_is_const(&m->dag, j->option, &r) && !(r > 0))
            diag_fail(b->diag, s->option_pos, "the radius of rolling '%s' is %g: a disk's "
                      "radius must be positive", s->name, r);
    }
    switch (info->level) {
    case LEVEL_POSITION: j->velocity = false; break;
    case LEVEL_VELOCITY: j->velocity = true; break;
    case LEVEL_EITHER:   j->velocity = build_mentions_der(s->lhs) || build_mentions_der(s->rhs); break;
    }
    if (info->attachments == 0) {
        if (s->joint == JOINT_VELOCITY && !build_mentions_der(s->lhs) && !build_mentions_der(s->rhs))
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
    build_grow(&m->arena, (void **)&m->outputs, &b->cap_outputs, m->nout + 1, sizeof *m->outputs);
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
    build_declare(b, ENT_OUTPUT, s->name, s->name_pos);
    if (build_mentions_der(s->value))
        diag_fail(b->diag, s->pos, "output '%s' contains der(): an output is a value of the "
                  "coordinates and t, whose velocity run reports anyway", s->name);
    if (s->value) {
        push_output(b, s->name, "", build_lower_expr(b, s->value, EXPR_HOLONOMIC));
        return;
    }
    Attach at = build_attach(b, &s->attach[0], ATTACH_ANY, "output");
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

/* param NAME = value folds to a constant unless value uses a design
   parameter; design NAME = value is the leaf p[index] of every kernel. */
static void declare_param(Builder *b, const Stmt *s)
{
    Model *m = b->model;
    if (!s->design) {
        double v;
        NodeId node = build_design_value(b, s->value, "the param value", &v);
        Entity *e = build_declare(b, ENT_PARAM, s->name, s->name_pos);
        e->value = v;
        e->node = node;
        return;
    }
    double v = build_constant(b, s->value, "the design value");
    Entity *e = build_declare(b, ENT_PARAM, s->name, s->name_pos);
    int cap = b->cap_design;
    build_grow(&m->arena, (void **)&m->design_names, &cap, m->np + 1, sizeof *m->design_names);
    build_grow(&m->arena, (void **)&m->design_p0, &b->cap_design, m->np + 1,
               sizeof *m->design_p0);
    m->design_names[m->np] = arena_strdup(&m->arena, e->name);
    m->design_p0[m->np] = v;
    e->value = v;
    e->node = dag_param(&m->dag, m->np);
    m->np++;
    /* until model_set_design, the graph sees the file's design */
    m->dag.np = m->np;
    m->dag.param_values = m->design_p0;
    m->dag.param_names = m->design_names;
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
        case STMT_PARAM:
            declare_param(b, s);
            break;
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
    build_dynamics_check(b);
    m->dag.where = -1;
    if (m->np) {    /* the design evaluated from now on, apart from the file's */
        m->dag.param_values = arena_alloc_array(&m->arena, (size_t)m->np, sizeof(double));
        model_set_design(m, NULL);
    }
    collect_bodies(b);
    SrcPos where = last ? last->pos : (SrcPos){0};
    m->last_pos = where;
    /* on the whole model, at the statement about the mechanism as a whole */
    check_jacobian_size(b, (long long)b->npos + b->nvel, m->nq, where);
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

void model_set_design(Model *model, const double *p)
{
    if (model->np == 0)     /* no arrays to copy between (memcpy of NULL) */
        return;
    memcpy(model->dag.param_values, p ? p : model->design_p0, (size_t)model->np * sizeof *p);
}

const Body *model_find_body(const Model *m, const char *name)
{
    for (int i = 0; i < m->nbodies; i++)
        if (strcmp(m->bodies[i].name, name) == 0)
            return &m->bodies[i];
    return NULL;
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
