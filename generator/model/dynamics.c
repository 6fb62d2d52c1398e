/* dynamics.c - the model's masses, gravity and applied forces: mass and force statements to elements over graph nodes.
 *
 * A mass statement becomes a MassElement (a point's position and an angle,
 * or a spatial body's centre of mass and inertia tensor), a force statement
 * an AppliedForce built by its kind's build_KIND (generator/parse/forces.def).
 * Neither adds rows: M and Q are differentiated from them later
 * (generator/diff/dynamics.c, and generator/eval/generic_dynamics.c for the
 * generic engine).
 */
#include "builder.h"

#include "../base/eigen3.h"
#include "../dag/support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A constant or design parameters' value (0 when absent): its node, and
   its number at the file's design. */
static double dyn_value(Builder *b, const Ast *ast, const char *what, NodeId *node)
{
    double v = 0.0;
    *node = ast ? build_design_value(b, ast, what, &v) : DAG_ZERO;
    return v;
}

/* A key's value (0 when absent), refused when negative (at the file's design). */
static double dyn_constant(Builder *b, const Stmt *s, DynKey key, const char *what,
                           bool nonnegative, NodeId *node)
{
    double v = dyn_value(b, s->key[key], what, node);
    if (nonnegative && v < 0)
        diag_fail(b->diag, s->key_pos[key], "%s of %s '%s' is negative (%g)%s", what,
                  dyn_keyword(s), s->name, v,
                  dag_is_const(&b->model->dag, *node, NULL) ? "" : " at the file's design");
    return v;
}

/* com(sx, sy[, sz]) of a body's mass: at's offset, designed or not. */
static void com_offset(Builder *b, const Stmt *s, Attach *at)
{
    double *value[3] = {&at->sx, &at->sy, &at->sz};
    for (int k = 0; k < (b->spatial ? 3 : 2); k++) {
        *value[k] = dyn_value(b, s->vec[k], "a centre-of-mass offset", &at->s_node[k]);
        at->designed |= !dag_is_const(&b->model->dag, at->s_node[k], NULL);
    }
}

/* A key's expression of q, der(q) and t (absent: 0). */
static NodeId dyn_expr(Builder *b, const Ast *ast)
{
    return ast ? build_lower(b, ast, EXPR_VELOCITY) : DAG_ZERO;
}

/* The global position of a dynamics attachment: a body point, a
   particle, ground, or at(x, y) (ctx: what at's expressions may use);
   in a spatial file xy[2] is z (xy has room for three). */
static void dyn_point(Builder *b, const AstAttach *at, ExprContext ctx, const char *keyword,
                      NodeId xy[3])
{
    if (at->at) {
        NodeId z = b->spatial ? build_lower(b, at->sz, ctx) : DAG_ZERO;
        NodeId y = build_lower(b, at->sy, ctx);    /* sequenced: see AST_BINARY */
        xy[0] = build_lower(b, at->sx, ctx);
        xy[1] = y;
        xy[2] = z;
        return;
    }
    Attach a = build_attach(b, at, ATTACH_ANY, keyword);
    xy[2] = DAG_ZERO;
    if (b->spatial)
        joints_spatial_point(b->model, a, xy);
    else
        joints_point(b->model, a, xy);
    build_check_nodes(b);
}

/* The angle of a body (ATTACH_FRAME, no offset): its phi, 0 for ground. */
static NodeId dyn_angle(Builder *b, const AstAttach *at, const char *keyword)
{
    Attach a = build_attach(b, at, ATTACH_FRAME, keyword);
    return a.has_phi ? dag_var(&b->model->dag, a.q + 2) : DAG_ZERO;
}

static MassElement *new_mass(Builder *b, const Stmt *s)
{
    Model *m = b->model;
    for (int i = 0; i < m->nmasses; i++)
        if (!s->declares && strcmp(m->masses[i].name, s->name) == 0)
            diag_fail(b->diag, s->name_pos, "'%s' already has a mass (line %d): give a body one "
                      "mass statement", s->name, build_line(b, m->masses[i].pos));
    build_grow(&m->arena, (void **)&m->masses, &b->cap_masses, m->nmasses + 1, sizeof *m->masses);
    MassElement *e = &m->masses[m->nmasses++];
    *e = (MassElement){.name = s->name, .pos = s->pos, .theta = DAG_ZERO, .body = -1,
                       .spatial = b->spatial, .pz = DAG_ZERO, .euler = -1};
    e->m = dyn_constant(b, s, DKEY_M, "the mass m", true, &e->m_node);
    if (!b->spatial)    /* a spatial J is a tensor: spatial_inertia */
        e->J = dyn_constant(b, s, DKEY_J, "the moment of inertia J", true, &e->J_node);
    return e;
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
        e->inertia[i] = dyn_value(b, s->inertia[i], what, &e->inertia_node[i]);
        if (e->inertia[i] < 0)
            diag_fail(b->diag, s->inertia[i]->pos, "%s of mass '%s' is negative (%g)", what,
                      s->name, e->inertia[i]);
    }
    for (int i = 0; i < 3; i++) {
        snprintf(what, sizeof what, "the product of inertia %s", dyn_key_names[product[i]]);
        e->inertia[3 + i] = dyn_constant(b, s, product[i], what, false, &e->inertia_node[3 + i]);
    }
    double ev[3];
    eigen3_symmetric(e->inertia, ev);
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
    if (s->vec[0])
        com_offset(b, s, &at);
    /* M's entries carry m |com|^2 as products of these numbers (the
       planar builder folds J + m |com|^2 into one constant): past the
       range of a double they would be inf at every call. */
    Dag *d = &b->model->dag;
    const char *outer = d->what;
    d->what = "its moment about the body's reference point, m |com|^2";
    dag_range_note_nonfinite(d, e->m * (at.sx * at.sx + at.sy * at.sy + at.sz * at.sz));
    d->what = outer;
    NodeId xyz[3];
    joints_spatial_point(b->model, at, xyz);
    e->px = xyz[0], e->py = xyz[1], e->pz = xyz[2];
    build_check_nodes(b);
    if (body) {
        e->euler = ent->q + 3;
        spatial_inertia(b, s, e);
    }
}

/* mass BODY m = .. [J = ..] [com(sx, sy)]: the body's centre of mass
   r + A(phi) s, J about it; mass POINT m = ..: the particle itself. */
static void build_body_mass(Builder *b, const Stmt *s)
{
    Entity *ent = build_lookup(b, s->name, s->name_pos);
    if (ent->kind != ENT_BODY && ent->kind != ENT_POINT)
        diag_fail(b->diag, s->name_pos, "'%s' is %s; 'mass NAME m = ...' gives a body or point its "
                  "mass (write 'mass NAME: at(x, y) m = ...' for a mass element)", s->name,
                  build_entity_word(ent->kind));
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
    if (s->vec[0])
        com_offset(b, s, &at);
    NodeId xy[2];
    joints_point(b->model, at, xy);
    e->px = xy[0], e->py = xy[1];
    if (body) {
        e->theta = dag_var(&b->model->dag, ent->q + 2);
        e->body = ent->q;
        e->sx = at.sx, e->sy = at.sy;
        e->s_node[0] = at.s_node[0], e->s_node[1] = at.s_node[1];
    }
    build_check_nodes(b);
}

/* mass NAME: at(x, y) m = .. [J = .. angle = ..]: a mass element given by
   expressions of the coordinates (not of t). */
static void build_element_mass(Builder *b, const Stmt *s)
{
    build_declare(b, ENT_MASS, s->name, s->name_pos);
    if (s->key[DKEY_J] && !s->key[DKEY_ANGLE])
        diag_fail(b->diag, s->key_pos[DKEY_J], "mass '%s' has J but no 'angle = ...': the "
                  "angle whose rate J multiplies", s->name);
    MassElement *e = new_mass(b, s);
    NodeId xy[3];
    dyn_point(b, &s->attach[0], EXPR_MASS, "mass", xy);
    e->px = xy[0], e->py = xy[1], e->pz = xy[2];
    if (s->key[DKEY_ANGLE])
        e->theta = build_lower(b, s->key[DKEY_ANGLE], EXPR_MASS);
}

static AppliedForce *new_force(Builder *b, const Stmt *s, ForceKind kind)
{
    Model *m = b->model;
    build_declare(b, ENT_FORCE, s->name, s->name_pos);
    build_grow(&m->arena, (void **)&m->forces, &b->cap_forces, m->nforces + 1, sizeof *m->forces);
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
        build_check_nodes(b);
        return a;
    }
    return build_lower(b, lhs, EXPR_HOLONOMIC);
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
    Attach a = build_attach(b, &s->attach[0], ATTACH_FRAME, dyn_keyword(s));
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
    f->k = dyn_constant(b, s, DKEY_K, "the stiffness k", true, &f->k_node);
    f->c = dyn_constant(b, s, DKEY_C, "the damping c", true, &f->c_node);
    f->free = dyn_constant(b, s, DKEY_LENGTH, "the free length", true, &f->free_node);
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
    f->k = dyn_constant(b, s, DKEY_K, "the stiffness k", true, &f->k_node);
    f->c = dyn_constant(b, s, DKEY_C, "the damping c", true, &f->c_node);
    f->free = dyn_constant(b, s, DKEY_ANGLE, "the free angle", false, &f->free_node);
    if (b->spatial) {
        Entity *e = build_lookup(b, s->attach[0].name, s->attach[0].pos);
        const Joint *j = e->kind == ENT_JOINT ? &b->model->joints[e->q] : NULL;
        if (!j || (j->kind != JOINT_S_REVOLUTE && j->kind != JOINT_S_CYLINDRICAL))
            diag_fail(b->diag, s->attach[0].pos, "a spatial rspring acts about a revolute's "
                      "or cylindrical's axis; '%s' is %s", e->name,
                      j ? joint_info[j->kind].keyword : build_entity_word(e->kind));
        f->bx = joints_spatial_angle(b->model, j);
        build_check_nodes(b);
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
    f->coord = build_coordinate(b, s->lhs);
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

void build_dynamics(Builder *b, const Stmt *s)
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
    b->gravity_line = build_line(b, s->pos);
    static const char *const what[3] = {"the gravity component gx", "the gravity component gy",
                                        "the gravity component gz"};
    Model *m = b->model;
    for (int c = 0; c < (b->spatial ? 3 : 2); c++)
        m->gravity[c] = dyn_value(b, s->vec[c], what[c], &m->gravity_node[c]);
}

/* After the statements: M is dense nq x nq in the engines and the
   generated P_mass (a limit of 0: run's sparse path, which asks for no
   check here), and a force needs a mass to move. */
void build_dynamics_check(Builder *b)
{
    const Model *m = b->model;
    if (m->nmasses > 0 && b->limits->max_jac_entries > 0
        && (long long)m->nq * m->nq > b->limits->max_jac_entries)
        diag_fail(b->diag, m->masses[0].pos, "the dense mass matrix would have %d x %d = %lld "
                  "entries, more than the limit of %d (--max-jac-entries)", m->nq, m->nq,
                  (long long)m->nq * m->nq, b->limits->max_jac_entries);
    if (b->first_force && m->nmasses == 0)
        diag_fail(b->diag, b->first_force->pos, "%s without masses: the file has no 'mass' "
                  "statement, so there is nothing for it to move", b->first_force->kind == STMT_GRAVITY
                  ? "gravity" : "a force");
}
