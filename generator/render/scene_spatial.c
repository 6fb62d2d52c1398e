/* scene_spatial.c - what an animation draws for a spatial mechanism, as shapes fixed to bodies and seen in one view.
 *
 * The same shapes as a planar scene (scene.c) with 3D vertices: a vertex is
 * P = r + A(p) s of a body, plus an offset turned with a body's Euler
 * parameters; svg_write.c projects every vertex with the scene's view
 * (view.c) per frame. What is drawn:
 *   body          its outline: the convex hull of its joints' local points,
 *                 its reference point and its traced points, taken in the
 *                 plane of those points (points off it keep their place on
 *                 the ring); a line for 2 points, a mark for 1
 *   point         a dot
 *   spherical, universal, revolute, weld
 *                 a pin at the joint (a ground pivot when one side is
 *                 ground); a revolute also a short dashed line along its axis
 *   translational, cylindrical
 *                 a guide along A's axis covering the slide (a hatched
 *                 support when A is ground) and a dot at P_B
 *   distance      a dashed line; pins at its body ends, pivots at ground ends
 *   pointplane    a dot at P_B
 *   rolling       the rim (32 points in the disk's plane) and a spoke
 *   parallel, perpendicular, rows only
 *                 nothing (they hold axes, not points)
 * Depth: SVG cannot reorder elements while it animates, so the order is
 * fixed: the links and points farthest first by their mean depth at the
 * first kept frame, then the pins over all of them.
 */
#include "scene.h"

#include "../base/arena.h"
#include "../eval/interp.h"
#include "hull.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- vertices ---- */

/* A vertex at attachment a plus offset o turned with frame attachment f
   (ground or a point: not turned). */
static Vtx vtx_off3(Attach a, Attach f, const double o[3])
{
    Vtx v = scene_vtx_at(a);
    v.fq = f.q >= 0 && f.has_p ? f.q : -1;
    v.ox = o[0], v.oy = o[1], v.oz = o[2];
    return v;
}

/* The vertex at a body's local point s. */
static Vtx vtx_local(int q, const double s[3])
{
    Vtx v = {.q = q, .fq = -1, .spatial = true, .has_p = true, .sx = s[0], .sy = s[1], .sz = s[2]};
    return v;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* A joint's axis on A as written, scaled to length len. */
static void axis_a(const Joint *jt, double len, double u[3])
{
    double n = sqrt(jt->ux * jt->ux + jt->uy * jt->uy + jt->uz * jt->uz);
    u[0] = len * jt->ux / n, u[1] = len * jt->uy / n, u[2] = len * jt->uz / n;
}

/* ---- bodies ---- */

/* The local points of body q: its reference point, the traced points on it
   and its joints' attachments. */
static int body_points(const Scene *sc, int q, double (*pts)[3])
{
    int n = 0;
    pts[n][0] = pts[n][1] = pts[n][2] = 0, n++;
    for (int i = 0; i < sc->ntraces; i++) {
        const SvgTrace *tr = &sc->traces[i];
        if (tr->q == q && tr->has_phi)
            pts[n][0] = tr->sx, pts[n][1] = tr->sy, pts[n][2] = tr->sz, n++;
    }
    for (int j = 0; j < sc->m->njoints; j++) {
        const Joint *jt = &sc->m->joints[j];
        const Attach *at[2] = {&jt->a, &jt->b};
        for (int k = 0; k < joint_info[jt->kind].attachments; k++)
            if (at[k]->q == q && at[k]->has_p)
                pts[n][0] = at[k]->sx, pts[n][1] = at[k]->sy, pts[n][2] = at[k]->sz, n++;
    }
    return n;
}

/* The index of the point farthest from p[0] along nothing (e == NULL) or
   across the unit direction e; its distance in *d. */
static int farthest(const double (*p)[3], int n, const double *e, double *d)
{
    int best = 0;
    *d = 0;
    for (int i = 1; i < n; i++) {
        double r[3] = {p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]};
        double along = e ? dot3(r, e) : 0, dd = sqrt(fmax(dot3(r, r) - along * along, 0));
        if (dd > *d)
            *d = dd, best = i;
    }
    return best;
}

/* The outline of points p (n >= 1) as indices into p, in ring order
   (hp: room for 2 n, h for n + 1):
   1 (all at one place), 2 (on a line: its ends) or the hull in the plane
   through p[0] spanned by the farthest point and the one farthest across. */
static int outline3(const double (*p)[3], int n, double tol, HullPoint *hp, HullPoint *h,
                    int *ring)
{
    double d, e1[3], e2[3];
    int a = farthest(p, n, NULL, &d);
    ring[0] = 0;
    if (d <= tol)
        return 1;
    for (int k = 0; k < 3; k++)
        e1[k] = (p[a][k] - p[0][k]) / d;
    int b = farthest(p, n, e1, &d);
    double rb[3] = {p[b][0] - p[0][0], p[b][1] - p[0][1], p[b][2] - p[0][2]};
    double along = dot3(rb, e1);
    for (int k = 0; k < 3; k++)
        e2[k] = d > tol ? (rb[k] - along * e1[k]) / d : 0;
    for (int i = 0; i < n; i++) {
        double r[3] = {p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]};
        hp[i] = (HullPoint){dot3(r, e1), dot3(r, e2)};
    }
    HullPoint *sorted = hp + n;         /* hull_convex reorders its input */
    memcpy(sorted, hp, (size_t)n * sizeof *hp);
    int m = hull_convex(sorted, n, h, tol);
    for (int k = 0; k < m; k++) {       /* the hull's points are copies: found exactly */
        ring[k] = 0;
        for (int i = 0; i < n; i++)
            if (hp[i].x == h[k].x && hp[i].y == h[k].y) {
                ring[k] = i;
                break;
            }
    }
    return m;
}

/* A rolling disk is drawn by its rim: its outline is left out when it is
   a single point. */
static bool body_is_disk(const Scene *sc, int q)
{
    for (int j = 0; j < sc->m->njoints; j++)
        if (sc->m->joints[j].kind == JOINT_S_ROLLING && sc->m->joints[j].a.q == q)
            return true;
    return false;
}

static void add_body(Scene *sc, const Body *b, double (*pts)[3], HullPoint *hp, HullPoint *h,
                     int *ring)
{
    const char *c = sc->colour[b->q];
    if (b->nq < 7) {                    /* a point */
        Shape *s = scene_add_shape(sc, SHAPE_CIRCLE, "particle");
        scene_add_vtx(sc, (Vtx){.q = b->q, .fq = -1, .spatial = true});
        s->r = 5.5;
        s->fill = c;
        s->name = b->name;
        scene_end_shape(sc, s);
        return;
    }
    int n = body_points(sc, b->q, pts);
    int m = outline3((const double (*)[3])pts, n, 1e-9 * sc->L, hp, h, ring);
    if (m == 1 && body_is_disk(sc, b->q))
        return;
    Shape *s = scene_add_shape(sc, m >= 3 ? SHAPE_POLYGON : m == 2 ? SHAPE_POLYLINE : SHAPE_MARK,
                               "link");
    for (int k = 0; k < m; k++)
        scene_add_vtx(sc, vtx_local(b->q, pts[ring[k]]));
    s->stroke = c;
    s->fill = m == 2 ? "none" : c;
    s->name = b->name;
    scene_end_shape(sc, s);
}

/* The mean depth of shape s's vertices at the first kept frame. */
static double shape_depth(const Scene *sc, const Shape *s)
{
    const double *q0 = scene_frame_q(sc, sc->frames[0]);
    double sum = 0, P[3];
    for (int v = s->v0; v < s->v0 + s->nv; v++) {
        scene_vtx_point(&sc->v[v], q0, P);
        sum += svg_view_depth(sc->view, P);
    }
    return s->nv > 0 ? sum / s->nv : 0;
}

/* Shapes [first, nsh) farthest first (insertion sort: stable, and the
   shapes are few). */
static void sort_by_depth(Scene *sc, int first)
{
    int n = sc->nsh - first;
    double *d = xmalloc((size_t)(n > 0 ? n : 1) * sizeof *d);
    for (int i = 0; i < n; i++)
        d[i] = shape_depth(sc, &sc->sh[first + i]);
    for (int i = 1; i < n; i++) {
        Shape s = sc->sh[first + i];
        double key = d[i];
        int j = i;
        for (; j > 0 && d[j - 1] > key; j--) {
            d[j] = d[j - 1];
            sc->sh[first + j] = sc->sh[first + j - 1];
        }
        d[j] = key;
        sc->sh[first + j] = s;
    }
    free(d);
}

static void build_bodies(Scene *sc)
{
    const Model *m = sc->m;
    size_t cap = (size_t)2 * m->njoints + (size_t)sc->ntraces + 3;
    double (*pts)[3] = xmalloc(cap * sizeof *pts);
    HullPoint *hp = xmalloc(2 * cap * sizeof *hp), *h = xmalloc((cap + 1) * sizeof *h);
    int *ring = xmalloc((cap + 1) * sizeof *ring);
    int first = sc->nsh;
    for (int i = 0; i < m->nbodies; i++)
        add_body(sc, &m->bodies[i], pts, hp, h, ring);
    sort_by_depth(sc, first);
    free(pts);
    free(hp);
    free(h);
    free(ring);
}

/* ---- joints under the bodies ---- */

/* The range of h_A . (P_B - P_A) over the kept frames, h_A the unit axis
   on A turned with A. */
static void slide_range(const Scene *sc, const Joint *jt, double *lo, double *hi)
{
    double u[3];
    axis_a(jt, 1, u);
    Vtx va = scene_vtx_at(jt->a), vb = scene_vtx_at(jt->b), vu = vtx_off3(jt->a, jt->a, u);
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int f = 0; f < sc->nf; f++) {
        const double *qk = scene_frame_q(sc, sc->frames[f]);
        double pa[3], pb[3], pu[3];
        scene_vtx_point(&va, qk, pa);
        scene_vtx_point(&vb, qk, pb);
        scene_vtx_point(&vu, qk, pu);
        double hw[3] = {pu[0] - pa[0], pu[1] - pa[1], pu[2] - pa[2]};
        double r[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        double d = dot3(hw, r);
        *lo = fmin(*lo, d);
        *hi = fmax(*hi, d);
    }
}

/* translational, cylindrical: a line on A along its axis through P_A
   covering where B goes, and a hatched support when A is ground. */
static void draw_guide(Scene *sc, const Joint *jt)
{
    double lo, hi, pad = 24 * sc->px, u0[3], u1[3];
    slide_range(sc, jt, &lo, &hi);
    axis_a(jt, lo - pad, u0);
    axis_a(jt, hi + pad, u1);
    Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "guide");
    int v0 = scene_add_vtx(sc, vtx_off3(jt->a, jt->a, u0));
    int v1 = scene_add_vtx(sc, vtx_off3(jt->a, jt->a, u1));
    s->name = jt->name;
    scene_end_shape(sc, s);
    if (jt->a.q < 0) {
        double x0, y0, x1, y1;
        const double *q0 = scene_frame_q(sc, sc->frames[0]);
        scene_vtx_xy(sc, &sc->v[v0], q0, &x0, &y0);
        scene_vtx_xy(sc, &sc->v[v1], q0, &x1, &y1);
        scene_add_ground(sc, (Ground){GROUND_LINE, x0, y0, x1, y1, 8 * sc->px});
    }
}

/* Unit f, g with (u, f, g) orthogonal, u a unit vector. */
static void perpendiculars(const double u[3], double f[3], double g[3])
{
    int k = fabs(u[0]) <= fabs(u[1]) && fabs(u[0]) <= fabs(u[2]) ? 0 : fabs(u[1]) <= fabs(u[2]) ? 1 : 2;
    double e[3] = {0, 0, 0};
    e[k] = 1;
    g[0] = u[1] * e[2] - u[2] * e[1], g[1] = u[2] * e[0] - u[0] * e[2], g[2] = u[0] * e[1] - u[1] * e[0];
    double n = sqrt(dot3(g, g));
    for (int i = 0; i < 3; i++)
        g[i] /= n;
    f[0] = g[1] * u[2] - g[2] * u[1], f[1] = g[2] * u[0] - g[0] * u[2], f[2] = g[0] * u[1] - g[1] * u[0];
}

/* rolling: the rim of radius R (its value at the first kept frame) in the
   disk's plane, perpendicular to its axle, and a spoke. */
static void draw_disk(Scene *sc, const Joint *jt)
{
    const double *q0 = scene_frame_q(sc, sc->frames[0]);
    double R = fabs(node_value_at(&sc->m->dag, jt->option, q0, NULL, sc->t[sc->frames[0]]));
    if (!isfinite(R) || R <= 0)
        return;
    double u[3], f[3], g[3], o[3];
    axis_a(jt, 1, u);
    perpendiculars(u, f, g);
    Attach centre = {.q = jt->a.q, .spatial = true, .has_p = true};
    Shape *s = scene_add_shape(sc, SHAPE_POLYGON, "disk");
    for (int k = 0; k < 32; k++) {
        double a = k * (6.28318530717958647692 / 32), c = R * cos(a), sn = R * sin(a);
        for (int i = 0; i < 3; i++)
            o[i] = c * f[i] + sn * g[i];
        scene_add_vtx(sc, vtx_off3(centre, centre, o));
    }
    s->name = jt->name;
    s->stroke = sc->colour[jt->a.q];
    scene_end_shape(sc, s);
    s = scene_add_shape(sc, SHAPE_POLYLINE, "spoke");
    scene_add_vtx(sc, scene_vtx_at(centre));
    for (int i = 0; i < 3; i++)
        o[i] = R * f[i];
    scene_add_vtx(sc, vtx_off3(centre, centre, o));
    scene_end_shape(sc, s);
}

/* Everything drawn under the bodies; kinds with no drawing of their own
   take the generic one (default). */
static void build_joints(Scene *sc)
{
    for (int j = 0; j < sc->m->njoints; j++) {
        const Joint *jt = &sc->m->joints[j];
        switch (jt->kind) {
        case JOINT_S_TRANSLATIONAL:
        case JOINT_S_CYLINDRICAL:
            draw_guide(sc, jt);
            break;
        case JOINT_S_DISTANCE:
            scene_draw_distance(sc, jt);
            break;
        case JOINT_S_ROLLING:
            draw_disk(sc, jt);
            break;
        case JOINT_S_SPHERICAL:     /* pins and dots, over the bodies */
        case JOINT_S_UNIVERSAL:
        case JOINT_S_REVOLUTE:
        case JOINT_S_WELD:
        case JOINT_S_POINTPLANE:
        case JOINT_S_PARALLEL:      /* axes only: nothing to draw */
        case JOINT_S_PERPENDICULAR:
        case JOINT_S_NORM:          /* rows only */
        case JOINT_S_CONTACT:
        case JOINT_CONSTRAINT:
        case JOINT_DRIVER:
        case JOINT_VELOCITY:
            break;
        default:
            scene_draw_generic(sc, jt, false);
            break;
        }
    }
}

/* ---- over the bodies: pins, dots, revolute axes ---- */

/* A ground pivot at a ground attachment (it does not move: projected once). */
static void mark_ground(Scene *sc, Attach a)
{
    if (a.q >= 0)
        return;
    double P[3] = {a.sx, a.sy, a.sz}, x, y;
    svg_view_project(sc->view, P, &x, &y);
    scene_add_ground(sc, (Ground){GROUND_PIVOT, x, y, 0, 0, 0});
}

/* A short dashed line along a revolute's axis through P_A, turning with A. */
static void draw_axis(Scene *sc, const Joint *jt)
{
    double u0[3], u1[3];
    axis_a(jt, -16 * sc->px, u0);
    axis_a(jt, 16 * sc->px, u1);
    Shape *s = scene_add_shape(sc, SHAPE_POLYLINE, "axis");
    scene_add_vtx(sc, vtx_off3(jt->a, jt->a, u0));
    scene_add_vtx(sc, vtx_off3(jt->a, jt->a, u1));
    s->stroke = "#444";
    s->fill = "none";
    s->extra = "stroke-width=\"1.5\" stroke-dasharray=\"4 2\"";
    scene_end_shape(sc, s);
}

/* A joint holding two points together: pivots at its ground sides and one
   pin (a weld dot) at the joint, on the ground side when there is one. */
static void draw_pins(Scene *sc, const Joint *jt)
{
    mark_ground(sc, jt->a);
    mark_ground(sc, jt->b);
    if (jt->kind == JOINT_S_REVOLUTE)
        draw_axis(sc, jt);
    Attach at = jt->a.q < 0 ? jt->a : jt->b.q < 0 ? jt->b : jt->a;
    bool weld = jt->kind == JOINT_S_WELD;
    scene_add_pin(sc, at, weld ? "weld" : "pin", weld ? 3.5 : 4.5, jt->name);
}

static void build_pins(Scene *sc)
{
    for (int j = 0; j < sc->m->njoints; j++) {
        const Joint *jt = &sc->m->joints[j];
        switch (jt->kind) {
        case JOINT_S_SPHERICAL:
        case JOINT_S_UNIVERSAL:
        case JOINT_S_REVOLUTE:
        case JOINT_S_WELD:
            draw_pins(sc, jt);
            break;
        case JOINT_S_DISTANCE:
            for (int k = 0; k < 2; k++) {
                Attach a = k ? jt->b : jt->a;
                if (a.q < 0)
                    mark_ground(sc, a);
                else if (a.has_p)
                    scene_add_pin(sc, a, "pin", 3, jt->name);
            }
            break;
        case JOINT_S_TRANSLATIONAL:
        case JOINT_S_CYLINDRICAL:
        case JOINT_S_POINTPLANE:
            scene_add_pin(sc, jt->b, "dot", 3.5, jt->name);
            break;
        case JOINT_S_ROLLING:       /* drawn under the bodies, or nothing */
        case JOINT_S_PARALLEL:
        case JOINT_S_PERPENDICULAR:
        case JOINT_S_NORM:
        case JOINT_S_CONTACT:
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

void scene_build_spatial(Scene *sc)
{
    build_joints(sc);
    build_bodies(sc);
    build_pins(sc);
}
