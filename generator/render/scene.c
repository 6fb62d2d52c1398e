/* scene.c - what an animation draws for each body, point and joint, as shapes fixed to bodies.
 *
 * The picture is a list of shapes whose vertices are points fixed to a body
 * (or to ground): a vertex is P = r + A(phi) s of one body, plus an optional
 * offset turned with another body's angle (a slider block sits on body B's
 * joint point but lies along body A's axis). Bodies and points come from the
 * model's body table; svg_write.c maps the vertices to pixels per frame.
 *
 * What is drawn (spec section 2 for the joints):
 *   body          the convex hull of its joints' local points, its reference
 *                 point and its traced points: a line (2 points), a polygon
 *                 (3+), a mark (1)
 *   point         a dot
 *   revolute      a pin (circle); a ground pivot (triangle, hatching) when
 *                 one side is ground
 *   prismatic     a guide along the axis on body A covering the slide, and a
 *                 block at P_B along that axis
 *   pointline     the line (a slot) on body A and a dot at P_B
 *   distance      a thin dashed line between the two points
 *   weld          a dot
 *   rolling       a disk of radius R with a spoke, on a hatched ground line
 *   knife         a short thick blade along the axis
 *   driver        the bodies whose coordinates it drives in red, an arrow
 *                 turning with a driven angle, and a legend line
 *   other kinds   a thin line between two attachments, a hollow square at
 *                 one (scene_draw_generic), so a new joint kind shows
 *   traces        the path of chosen points and a dot running along it
 */
#include "scene.h"

#include "../base/arena.h"
#include "../dag/support.h"
#include "../eval/interp.h"
#include "hull.h"
#include "svg_common.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- vertices and shapes ---- */

int scene_add_vtx(Scene *sc, Vtx v)
{
    if (sc->nv == sc->vcap) {
        sc->vcap = sc->vcap ? 2 * sc->vcap : 64;
        sc->v = xrealloc(sc->v, (size_t)sc->vcap, sizeof *sc->v);
    }
    sc->v[sc->nv] = v;
    return sc->nv++;
}

Vtx scene_vtx_at(Attach a)
{
    Vtx v = {a.q, a.has_phi, a.sx, a.sy, -1, 0, 0, a.spatial, a.has_p, a.sz, 0};
    return v;
}

Vtx scene_vtx_trace(const SvgTrace *tr)
{
    Vtx v = {tr->q, tr->has_phi && !tr->spatial, tr->sx, tr->sy, -1, 0, 0,
             tr->spatial, tr->has_phi && tr->spatial, tr->sz, 0};
    return v;
}

/* A vertex at attachment a plus offset o turned with the angle of frame
   attachment f (ground or a particle: not turned). */
static Vtx vtx_off(Attach a, Attach f, double ox, double oy)
{
    Vtx v = {a.q, a.has_phi, a.sx, a.sy, f.q >= 0 && f.has_phi ? f.q + 2 : -1, ox, oy, false, false, 0, 0};
    return v;
}

Shape *scene_add_shape(Scene *sc, ShapeKind kind, const char *cls)
{
    if (sc->nsh == sc->shcap) {
        sc->shcap = sc->shcap ? 2 * sc->shcap : 32;
        sc->sh = xrealloc(sc->sh, (size_t)sc->shcap, sizeof *sc->sh);
    }
    Shape *s = &sc->sh[sc->nsh++];
    memset(s, 0, sizeof *s);
    s->kind = kind;
    s->cls = cls;
    s->v0 = sc->nv;
    return s;
}

/* Call after adding the shape's vertices. */
void scene_end_shape(Scene *sc, Shape *s) { s->nv = sc->nv - s->v0; }

void scene_add_ground(Scene *sc, Ground g)
{
    if (sc->nground == sc->groundcap) {
        sc->groundcap = sc->groundcap ? 2 * sc->groundcap : 16;
        sc->ground = xrealloc(sc->ground, (size_t)sc->groundcap, sizeof *sc->ground);
    }
    sc->ground[sc->nground++] = g;
}

/* out = A(p) s, A(p) = (2 e0^2 - 1) I + 2 (e e^T + e0 e~) for the Euler
   parameters p[0..3] (left as they are: the run keeps them normalised). */
static void turn3(const double *p, const double s[3], double out[3])
{
    const double *e = p + 1;
    double es = e[0] * s[0] + e[1] * s[1] + e[2] * s[2], c = 2 * p[0] * p[0] - 1;
    double ex[3] = {e[1] * s[2] - e[2] * s[1], e[2] * s[0] - e[0] * s[2], e[0] * s[1] - e[1] * s[0]};
    for (int i = 0; i < 3; i++)
        out[i] = c * s[i] + 2 * e[i] * es + 2 * p[0] * ex[i];
}

/* P = r + A(p) s (+ A(p_f) o) of a spatial vertex. */
static void vtx_point3(const Vtx *v, const double *qk, double P[3])
{
    double s[3] = {v->sx, v->sy, v->sz}, o[3] = {v->ox, v->oy, v->oz}, w[3];
    for (int i = 0; i < 3; i++)
        P[i] = v->q < 0 ? s[i] : qk[v->q + i];
    if (v->q >= 0 && v->has_p) {
        turn3(qk + v->q + 3, s, w);
        for (int i = 0; i < 3; i++)
            P[i] += w[i];
    }
    if (v->fq >= 0)
        turn3(qk + v->fq + 3, o, w);
    for (int i = 0; i < 3; i++)
        P[i] += v->fq >= 0 ? w[i] : o[i];
}

void scene_vtx_point(const Vtx *v, const double *qk, double P[3])
{
    if (v->spatial) {
        vtx_point3(v, qk, P);
        return;
    }
    scene_vtx_world(v, qk, &P[0], &P[1]);
    P[2] = 0;
}

void scene_vtx_xy(const Scene *sc, const Vtx *v, const double *qk, double *x, double *y)
{
    if (!v->spatial) {
        scene_vtx_world(v, qk, x, y);
        return;
    }
    double P[3];
    vtx_point3(v, qk, P);
    svg_view_project(sc->view, P, x, y);
}

void scene_vtx_world(const Vtx *v, const double *qk, double *x, double *y)
{
    double px, py;
    if (v->spatial) {
        double P[3];
        vtx_point3(v, qk, P);
        *x = P[0];
        *y = P[1];
        return;
    }
    if (v->q < 0) {
        px = v->sx;
        py = v->sy;
    } else if (v->has_phi) {
        double c = cos(qk[v->q + 2]), s = sin(qk[v->q + 2]);
        px = qk[v->q] + c * v->sx - s * v->sy;
        py = qk[v->q + 1] + s * v->sx + c * v->sy;
    } else {
        px = qk[v->q];
        py = qk[v->q + 1];
    }
    if (v->fq >= 0) {
        double c = cos(qk[v->fq]), s = sin(qk[v->fq]);
        px += c * v->ox - s * v->oy;
        py += s * v->ox + c * v->oy;
    } else {
        px += v->ox;
        py += v->oy;
    }
    *x = px;
    *y = py;
}

const double *scene_frame_q(const Scene *sc, int k) { return sc->q + (size_t)k * (size_t)sc->m->nq; }

/* The global position of attachment a at frame k. */
static void attach_world(const Scene *sc, Attach a, int k, double *x, double *y)
{
    Vtx v = scene_vtx_at(a);
    scene_vtx_xy(sc, &v, scene_frame_q(sc, k), x, y);
}

const char *scene_trace_colour(int i) { return svg_palette[(i + 3) % (SVG_PALETTE_SIZE - 1)]; }

/* ---- frames, drivers and colours ---- */

/* An exact stride is preferred when it keeps at least 60 % of max (1001
   frames: every 8th, 126 frames): evenly spaced frames of an evenly stepped
   run need no keyTimes lists, which saves a third of the file. */
void scene_keep_frames(Scene *sc, int max)
{
    int n = sc->n, *out = sc->frames;
    if (max < 2)
        max = 2;
    if (n <= max) {
        for (int k = 0; k < n; k++)
            out[k] = k;
        sc->nf = n;
        return;
    }
    for (int f = max; f >= 2 && 10 * f >= 6 * max; f--) {
        if ((n - 1) % (f - 1) == 0) {
            int stride = (n - 1) / (f - 1);
            for (int j = 0; j < f; j++)
                out[j] = j * stride;
            sc->nf = f;
            return;
        }
    }
    for (int j = 0; j < max; j++)
        out[j] = (int)((double)j * (n - 1) / (max - 1) + 0.5);
    sc->nf = max;
}

int scene_driver_coords(const Model *m, const Joint *jt, int *cols)
{
    const Row *row = &m->rows[jt->first_row];
    SupportScan scan;
    support_init(&scan);
    int n = support_collect(&scan, &m->dag, row->expr, row->velocity ? OP_VARD : OP_VAR, cols);
    support_free(&scan);
    return n;
}

/* Marks the coordinates each driver's row depends on (velocity drivers:
   the velocities it prescribes). */
static void find_driven(Scene *sc)
{
    const Model *m = sc->m;
    int *cols = xmalloc(((size_t)m->nq + 1) * sizeof *cols);
    for (int j = 0; j < m->njoints; j++) {
        if (m->joints[j].kind != JOINT_DRIVER)
            continue;
        int n = scene_driver_coords(m, &m->joints[j], cols);
        for (int k = 0; k < n; k++)
            sc->driven[cols[k]] = true;
    }
    free(cols);
}

static bool body_driven(const Scene *sc, const Body *b)
{
    for (int k = 0; k < b->nq; k++)
        if (sc->driven[b->q + k])
            return true;
    return false;
}

/* One colour per body and point, in declaration order; red for driven ones. */
static void assign_colours(Scene *sc)
{
    int next = 0;
    for (int i = 0; i < sc->m->nbodies; i++) {
        const Body *b = &sc->m->bodies[i];
        sc->colour[b->q] = body_driven(sc, b) ? SCENE_DRIVE_COLOUR
                                              : svg_palette[next++ % (SVG_PALETTE_SIZE - 1)];
    }
}

void scene_init(Scene *sc, const Model *m, const double *t, const double *q, int n,
                const SvgTrace *traces, int ntraces, int max_frames)
{
    memset(sc, 0, sizeof *sc);
    sc->m = m;
    sc->t = t;
    sc->q = q;
    sc->n = n;
    sc->traces = traces;
    sc->ntraces = ntraces;
    sc->frames = xmalloc((size_t)(max_frames > 2 ? max_frames : 2) * sizeof *sc->frames);
    scene_keep_frames(sc, max_frames);
    sc->driven = xcalloc((size_t)m->nq + 1, sizeof *sc->driven);
    sc->colour = xcalloc((size_t)m->nq + 1, sizeof *sc->colour);
    find_driven(sc);
    assign_colours(sc);
}

void scene_free(Scene *sc)
{
    free(sc->frames);
    free(sc->v);
    free(sc->sh);
    free(sc->ground);
    free(sc->driven);
    free(sc->colour);
}

/* ---- bodies ---- */

/* A body drawn otherwise than by its outline: the slider of a prismatic
   joint, a rolling disk. Its outline is left out when it is a single point. */
static bool body_has_symbol(const Scene *sc, int q)
{
    for (int j = 0; j < sc->m->njoints; j++) {
        const Joint *jt = &sc->m->joints[j];
        if ((jt->kind == JOINT_PRISMATIC && jt->b.q == q) ||
            (jt->kind == JOINT_ROLLING && jt->a.q == q))
            return true;
    }
    return false;
}

/* The local points of body q: its joints' attachments, the reference point
   and the traced points on it (a coupler point makes the coupler a triangle). */
static int body_points(const Scene *sc, int q, HullPoint *pts)
{
    int n = 0;
    pts[n++] = (HullPoint){0, 0};
    for (int i = 0; i < sc->ntraces; i++)
        if (sc->traces[i].q == q && sc->traces[i].has_phi)
            pts[n++] = (HullPoint){sc->traces[i].sx, sc->traces[i].sy};
    for (int j = 0; j < sc->m->njoints; j++) {
        const Joint *jt = &sc->m->joints[j];
        const Attach *at[2] = {&jt->a, &jt->b};
        for (int k = 0; k < joint_info[jt->kind].attachments; k++)
            if (at[k]->q == q && at[k]->has_phi)
                pts[n++] = (HullPoint){at[k]->sx, at[k]->sy};
    }
    return n;
}

static void add_particle(Scene *sc, const Body *b)
{
    Shape *s = scene_add_shape(sc, SHAPE_CIRCLE, "particle");
    scene_add_vtx(sc, (Vtx){b->q, false, 0, 0, -1, 0, 0, false, false, 0, 0});
    s->r = 5.5;
    s->fill = sc->colour[b->q];
    s->name = b->name;
    scene_end_shape(sc, s);
}

static void build_bodies(Scene *sc)
{
    const Model *m = sc->m;
    size_t cap = (size_t)2 * m->njoints + (size_t)sc->ntraces + 3;
    HullPoint *pts = xmalloc(cap * sizeof *pts);
    HullPoint *hull = xmalloc((cap + 1) * sizeof *hull);
    for (int i = 0; i < m->nbodies; i++) {
        const Body *b = &m->bodies[i];
        if (!b->has_phi) {
            add_particle(sc, b);
            continue;
        }
        const char *c = sc->colour[b->q];
        int n = body_points(sc, b->q, pts);
        int h = hull_convex(pts, n, hull, 1e-9 * sc->L);
        if (h == 1 && body_has_symbol(sc, b->q))
            continue;
        Shape *s = scene_add_shape(sc, h >= 3 ? SHAPE_POLYGON : h == 2 ? SHAPE_POLYLINE : SHAPE_MARK, "link");
        for (int k = 0; k < h; k++)
            scene_add_vtx(sc, (Vtx){b->q, true, hull[k].x, hull[k].y, -1, 0, 0, false, false, 0, 0});
        s->stroke = c;
        s->fill = h >= 3 ? c : h == 2 ? "none" : c;
        s->name = b->name;
        scene_end_shape(sc, s);
    }
    free(pts);
    free(hull);
}

/* ---- joints under the bodies: guides, blocks, disks, blades ---- */

/* The range of u . (P_B - P_A) / |u|^2 over the kept frames, in A's frame:
   how far B slides along the axis (u as written, A's local frame). */
static void slide_range(const Scene *sc, const Joint *jt, double *lo, double *hi)
{
    double uu = jt->ux * jt->ux + jt->uy * jt->uy;
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int f = 0; f < sc->nf; f++) {
        int k = sc->frames[f];
        const double *qk = scene_frame_q(sc, k);
        double ax, ay, bx, by;
        attach_world(sc, jt->a, k, &ax, &ay);
        attach_world(sc, jt->b, k, &bx, &by);
        double phi = jt->a.q >= 0 && jt->a.has_phi ? qk[jt->a.q + 2] : 0;
        double c = cos(phi), s = sin(phi);
        double wx = c * jt->ux - s * jt->uy, wy = s * jt->ux + c * jt->uy;   /* A(phi) u */
        double d = ((bx - ax) * wx + (by - ay) * wy) / uu;
        *lo = fmin(*lo, d);
        *hi = fmax(*hi, d);
    }
}

/* A line on body A along its axis through P_A covering where B goes,
   extended by pad (model units) at each end. */
static Shape *add_guide(Scene *sc, const Joint *jt, double pad)
{
    double lo, hi;
    slide_range(sc, jt, &lo, &hi);
    double ulen = hypot(jt->ux, jt->uy);
    double ex = jt->ux / ulen, ey = jt->uy / ulen;
    double a = lo * ulen - pad, b = hi * ulen + pad;
    Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "guide");
    scene_add_vtx(sc, vtx_off(jt->a, jt->a, a * ex, a * ey));
    scene_add_vtx(sc, vtx_off(jt->a, jt->a, b * ex, b * ey));
    s->name = jt->name;
    scene_end_shape(sc, s);
    return s;
}

/* prismatic: the guide on A (a hatched support when A is ground) and a
   block at P_B lying along the axis. */
static void draw_prismatic(Scene *sc, const Joint *jt)
{
    double px = sc->px;
    double block_len = 52 * px, block_h = 30 * px;
    Shape *g = add_guide(sc, jt, 0.6 * block_len);
    if (jt->a.q < 0) {
        const Vtx *v0 = &sc->v[g->v0], *v1 = &sc->v[g->v0 + 1];
        scene_add_ground(sc, (Ground){GROUND_LINE, v0->sx + v0->ox, v0->sy + v0->oy,
                                v1->sx + v1->ox, v1->sy + v1->oy, 0.5 * block_h});
    }
    double ulen = hypot(jt->ux, jt->uy);
    double ex = jt->ux / ulen, ey = jt->uy / ulen;
    double nx = -ey, ny = ex;
    Shape *s = scene_add_shape(sc, SHAPE_POLYGON, "slider");
    static const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++) {
        double a = 0.5 * block_len * corner[k][0], b = 0.5 * block_h * corner[k][1];
        scene_add_vtx(sc, vtx_off(jt->b, jt->a, a * ex + b * nx, a * ey + b * ny));
    }
    s->name = jt->name;
    if (jt->b.q >= 0)
        s->stroke = sc->colour[jt->b.q];
    scene_end_shape(sc, s);
}

void scene_draw_distance(Scene *sc, const Joint *jt)
{
    Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "distance");
    scene_add_vtx(sc, scene_vtx_at(jt->a));
    scene_add_vtx(sc, scene_vtx_at(jt->b));
    s->name = jt->name;
    scene_end_shape(sc, s);
}

/* rolling: a disk of the radius at the first kept frame with a spoke, on a
   ground line at frame 0's contact height covering where the disk goes. */
static void draw_rolling(Scene *sc, const Joint *jt)
{
    const Model *m = sc->m;
    const double *q0 = scene_frame_q(sc, sc->frames[0]);
    double R = fabs(node_value_at(&m->dag, jt->option, q0, NULL, sc->t[sc->frames[0]]));
    if (!isfinite(R) || R <= 0)
        return;
    Attach centre = {.q = jt->a.q, .has_phi = true};
    Shape *s = scene_add_shape(sc, SHAPE_CIRCLE, "disk");
    scene_add_vtx(sc, scene_vtx_at(centre));
    s->r = R;
    s->r_world = true;
    s->name = jt->name;
    s->stroke = sc->colour[jt->a.q];
    scene_end_shape(sc, s);
    s = scene_add_shape(sc, SHAPE_POLYLINE, "spoke");
    scene_add_vtx(sc, scene_vtx_at(centre));
    scene_add_vtx(sc, vtx_off(centre, centre, R, 0));
    scene_end_shape(sc, s);
    double xlo = INFINITY, xhi = -INFINITY, cx, cy;
    for (int f = 0; f < sc->nf; f++) {
        attach_world(sc, centre, sc->frames[f], &cx, &cy);
        xlo = fmin(xlo, cx);
        xhi = fmax(xhi, cx);
    }
    attach_world(sc, centre, sc->frames[0], &cx, &cy);
    scene_add_ground(sc, (Ground){GROUND_LINE, xlo - 1.3 * R, cy - R, xhi + 1.3 * R, cy - R, 0});
}

static void draw_knife(Scene *sc, const Joint *jt)
{
    double ulen = hypot(jt->ux, jt->uy), h = 24 * sc->px;
    double ex = jt->ux / ulen * h, ey = jt->uy / ulen * h;
    Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "knife");
    scene_add_vtx(sc, vtx_off(jt->a, jt->a, -ex, -ey));
    scene_add_vtx(sc, vtx_off(jt->a, jt->a, ex, ey));
    s->name = jt->name;
    scene_end_shape(sc, s);
}

void scene_draw_generic(Scene *sc, const Joint *jt, bool over_bodies)
{
    int na = joint_info[jt->kind].attachments;
    /* no class rule in the style sheet: the colours come inline */
    if (!over_bodies && na == 2) {
        Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "joint");
        scene_add_vtx(sc, scene_vtx_at(jt->a));
        scene_add_vtx(sc, scene_vtx_at(jt->b));
        s->stroke = "#444";
        s->fill = "none";
        s->extra = "stroke-width=\"1.5\"";
        s->name = jt->name;
        scene_end_shape(sc, s);
    } else if (over_bodies && na == 1) {
        Shape *s = scene_add_shape(sc, SHAPE_MARK, "joint");
        scene_add_vtx(sc, scene_vtx_at(jt->a));
        s->stroke = "#444";
        s->fill = "none";
        s->name = jt->name;
        scene_end_shape(sc, s);
    }
}

/* Everything drawn under the bodies. Kinds with no drawing of their own
   take the generic one (default); the others are listed. */
static void build_joints(Scene *sc)
{
    const Model *m = sc->m;
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        switch (jt->kind) {
        case JOINT_PRISMATIC:
            draw_prismatic(sc, jt);
            break;
        case JOINT_POINTLINE:
            /* a slot, not a support: no hatching even on ground */
            add_guide(sc, jt, 24 * sc->px);
            break;
        case JOINT_DISTANCE:
            scene_draw_distance(sc, jt);
            break;
        case JOINT_ROLLING:
            draw_rolling(sc, jt);
            break;
        case JOINT_KNIFE:
            draw_knife(sc, jt);
            break;
        case JOINT_REVOLUTE:        /* pins, over the bodies */
        case JOINT_WELD:
        case JOINT_CONSTRAINT:      /* rows only: nothing at a joint */
        case JOINT_DRIVER:          /* red bodies, arrows and legend */
        case JOINT_VELOCITY:
            break;
        default:
            scene_draw_generic(sc, jt, false);
            break;
        }
    }
}

/* ---- over the bodies: pins, dots, arrows, trace dots ---- */

void scene_add_pin(Scene *sc, Attach a, const char *cls, double r, const char *name)
{
    Shape *s = scene_add_shape(sc, SHAPE_CIRCLE, cls);
    scene_add_vtx(sc, scene_vtx_at(a));
    s->r = r;
    s->name = name;
    scene_end_shape(sc, s);
}

/* revolute, weld, distance: a ground pivot at each ground side; pins on
   the bodies a distance joins, else one pin (or weld dot) at the joint,
   on the ground side when there is one (exact). */
static void draw_pins(Scene *sc, const Joint *jt)
{
    for (int k = 0; k < 2; k++) {
        Attach a = k ? jt->b : jt->a;
        if (a.q < 0)
            scene_add_ground(sc, (Ground){GROUND_PIVOT, a.sx, a.sy, 0, 0, 0});
    }
    if (jt->kind == JOINT_DISTANCE) {
        if (jt->a.q >= 0 && jt->a.has_phi)
            scene_add_pin(sc, jt->a, "pin", 3, jt->name);
        if (jt->b.q >= 0 && jt->b.has_phi)
            scene_add_pin(sc, jt->b, "pin", 3, jt->name);
        return;
    }
    Attach at = jt->a.q < 0 ? jt->a : jt->b.q < 0 ? jt->b : jt->a;
    scene_add_pin(sc, at, jt->kind == JOINT_WELD ? "weld" : "pin", jt->kind == JOINT_WELD ? 3.5 : 4.5,
            jt->name);
}

/* Pins and dots go above the links: a second pass after the bodies. */
static void build_pins(Scene *sc)
{
    const Model *m = sc->m;
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        switch (jt->kind) {
        case JOINT_REVOLUTE:
        case JOINT_WELD:
        case JOINT_DISTANCE:
            draw_pins(sc, jt);
            break;
        case JOINT_POINTLINE:
            scene_add_pin(sc, jt->b, "dot", 3.5, jt->name);
            break;
        case JOINT_PRISMATIC:       /* drawn under the bodies */
        case JOINT_ROLLING:
        case JOINT_KNIFE:
        case JOINT_CONSTRAINT:
        case JOINT_DRIVER:
        case JOINT_VELOCITY:
            break;
        default:
            scene_draw_generic(sc, jt, true);
            break;
        }
    }
}

/* An arrow turning with each body whose angle is driven, around its ground
   pivot when it has one, else around its reference point. */
static void build_drive_arrows(Scene *sc)
{
    const Model *m = sc->m;
    for (int b = 0; b < m->nbodies; b++) {
        int i = m->bodies[b].q;
        if (!m->bodies[b].has_phi || !sc->driven[i + 2])
            continue;
        Attach centre = {.q = i, .has_phi = true};
        for (int j = 0; j < m->njoints; j++) {
            const Joint *jt = &m->joints[j];
            if (jt->kind != JOINT_REVOLUTE)
                continue;
            if (jt->a.q < 0 && jt->b.q == i)
                centre = jt->b;
            else if (jt->b.q < 0 && jt->a.q == i)
                centre = jt->a;
        }
        double rho = 26 * sc->px;
        /* the arrow points the way the angle goes over the run */
        double turn = scene_frame_q(sc, sc->frames[sc->nf - 1])[i + 2] - scene_frame_q(sc, sc->frames[0])[i + 2];
        Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "drive");
        for (int k = 0; k <= 16; k++) {
            double a = (turn >= 0 ? 40.0 + 240.0 * k / 16 : 140.0 - 240.0 * k / 16) * (3.14159265358979323846 / 180);
            scene_add_vtx(sc, vtx_off(centre, centre, rho * cos(a), rho * sin(a)));
        }
        s->extra = "marker-end=\"url(#arrow)\"";
        scene_end_shape(sc, s);
    }
}

static void build_trace_dots(Scene *sc)
{
    for (int i = 0; i < sc->ntraces; i++) {
        const SvgTrace *tr = &sc->traces[i];
        Shape *s = scene_add_shape(sc, SHAPE_CIRCLE, "tracedot");
        scene_add_vtx(sc, scene_vtx_trace(tr));
        s->r = 3.5;
        s->fill = scene_trace_colour(i);
        s->name = tr->label;
        scene_end_shape(sc, s);
    }
}

void scene_build(Scene *sc)
{
    if (sc->m->spatial) {
        scene_build_spatial(sc);
        build_trace_dots(sc);
        return;
    }
    build_joints(sc);
    build_bodies(sc);
    build_drive_arrows(sc);
    build_pins(sc);
    build_trace_dots(sc);
}

/* ---- forces (run --forces) ---- */

void scene_scale_forces(Scene *sc)
{
    sc->force_max = 0;
    sc->force_scale = 0;
    for (int i = 0; i < sc->nforces; i++)
        for (int f = 0; f < sc->nf; f++) {
            const double *v = sc->forces[i].f + (size_t)sc->frames[f] * (size_t)sc->forces[i].stride;
            double len = hypot(v[0], v[1]);
            if (isfinite(len) && len > sc->force_max)
                sc->force_max = len;
        }
    if (sc->force_max > 0)
        sc->force_scale = SVG_FORCE_PX * sc->px / sc->force_max;
}

void scene_force_arrow(const Scene *sc, int i, int f, double *x0, double *y0, double *x1,
                       double *y1)
{
    const SvgForce *F = &sc->forces[i];
    int k = sc->frames[f];
    const double *v = F->f + (size_t)k * (size_t)F->stride;
    double fx = isfinite(v[0]) ? v[0] : 0, fy = isfinite(v[1]) ? v[1] : 0;
    attach_world(sc, F->at, k, x0, y0);
    *x1 = *x0 + sc->force_scale * fx;
    *y1 = *y0 + sc->force_scale * fy;
}
