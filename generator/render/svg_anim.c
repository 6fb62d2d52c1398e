/* svg_anim.c - an animated SVG of a mechanism's motion: SMIL, no script, any browser.
 *
 * The picture is a list of shapes whose vertices are points fixed to a body
 * (or to ground): a vertex is P = r + A(phi) s of one body, plus an optional
 * offset turned with another body's angle (a slider block sits on body B's
 * joint point but lies along body A's axis). Each shape's vertices are mapped
 * to pixels for every kept frame; the first frame becomes the static
 * attributes and, when the shape moves, an <animate> element carries the
 * values of all frames. Pixels, not a flipping transform, carry y up:
 * strokes and marks keep their pixel size whatever the scale.
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
 *   traces        the path of chosen points and a dot running along it
 */
#include "svg_anim.h"

#include "../base/arena.h"
#include "../dag/support.h"
#include "../eval/interp.h"
#include "svg_common.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DRIVE_COLOUR "#d62728"

enum {
    HEADER_PX = 34,         /* title and time above the drawing */
    LINE_PX = 18,           /* one legend line below the drawing */
    MARGIN_PX = 26,         /* room for pivots, hatching and pins */
    PATH_POINTS_MAX = 2000, /* frames sampled for a trace's path */
    TIME_LABELS_MAX = 100,  /* distinct time texts */
};

SvgAnimOptions svg_anim_default_options(void)
{
    SvgAnimOptions o = {
        .max_frames = 200,
        .min_duration = 2,
        .max_duration = 60,
        .width = 760,
        .height = 520,
        .max_bytes = 4000000,
    };
    return o;
}

/* ---- vertices and shapes ---- */

/* P = r + A(phi) s of attachment (q, has_phi, sx, sy), then + A(q[fq]) o
   (fq: a phi coordinate, or -1 for a world offset). */
typedef struct Vtx {
    int q;
    bool has_phi;
    double sx, sy;
    int fq;
    double ox, oy;
} Vtx;

typedef enum ShapeKind {
    SHAPE_POLYLINE,
    SHAPE_POLYGON,
    SHAPE_CIRCLE,       /* centre = vertex 0; radius px or world */
    SHAPE_MARK,         /* small square at vertex 0 */
} ShapeKind;

typedef struct Shape {
    ShapeKind kind;
    const char *cls;        /* CSS class: what the shape is (tests count them) */
    const char *stroke;     /* colour, or NULL for the class's */
    const char *fill;       /* colour, or NULL for the class's / none */
    const char *name;       /* tooltip: body or joint name, or NULL */
    const char *extra;      /* further literal attributes, or NULL */
    int v0, nv;
    double r;               /* circle radius */
    bool r_world;           /* r in model units (a rolling disk) */
} Shape;

/* What owns coordinate i: a body (x, y, phi), a point (x, y) or a scalar. */
typedef enum CoordOwner { OWNER_SCALAR, OWNER_BODY, OWNER_POINT } CoordOwner;

typedef struct Scene {
    const Model *m;
    const double *t, *q;
    int n;                  /* frames given */
    const SvgTrace *traces;
    int ntraces;
    int *frames, nf;        /* kept frames (indices into t) */
    Vtx *v;
    int nv, vcap;
    Shape *sh;
    int nsh, shcap;
    CoordOwner *owner;      /* per coordinate */
    int *base;              /* per coordinate: its x coordinate (or itself) */
    bool *driven;           /* per coordinate */
    const char **colour;    /* per body or point (at its x coordinate) */
    double L;               /* characteristic size of the motion */
    double px;              /* model units per pixel, estimated before
                               symbols are sized (the final scale is a
                               little smaller: symbols come out a little
                               smaller than asked) */
    /* pixel mapping: X = ox + s (x - xmin), Y = oy + s (ymax - y) */
    double s, xmin, ymax, ox, oy;
    int width, height;
    Arena arena;            /* strings made here */
} Scene;

static int add_vtx(Scene *sc, Vtx v)
{
    if (sc->nv == sc->vcap) {
        sc->vcap = sc->vcap ? 2 * sc->vcap : 64;
        sc->v = xrealloc(sc->v, (size_t)sc->vcap, sizeof *sc->v);
    }
    sc->v[sc->nv] = v;
    return sc->nv++;
}

/* A vertex fixed to attachment a (no offset). */
static Vtx vtx_at(Attach a)
{
    Vtx v = {a.q, a.has_phi, a.sx, a.sy, -1, 0, 0};
    return v;
}

/* A vertex at attachment a plus offset o turned with the angle of frame
   attachment f (ground or a particle: not turned). */
static Vtx vtx_off(Attach a, Attach f, double ox, double oy)
{
    Vtx v = {a.q, a.has_phi, a.sx, a.sy, f.q >= 0 && f.has_phi ? f.q + 2 : -1, ox, oy};
    return v;
}

static Shape *add_shape(Scene *sc, ShapeKind kind, const char *cls)
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
static void end_shape(Scene *sc, Shape *s) { s->nv = sc->nv - s->v0; }

static void vtx_world(const Vtx *v, const double *qk, double *x, double *y)
{
    double px, py;
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

static const double *frame_q(const Scene *sc, int k) { return sc->q + (size_t)k * (size_t)sc->m->nq; }

/* The global position of attachment a at frame k. */
static void attach_world(const Scene *sc, Attach a, int k, double *x, double *y)
{
    Vtx v = vtx_at(a);
    vtx_world(&v, frame_q(sc, k), x, y);
}

/* ---- coordinates, bodies and drivers ---- */

static bool ends_with(const char *s, const char *suffix, size_t *stem)
{
    size_t n = strlen(s), k = strlen(suffix);
    if (n <= k || strcmp(s + n - k, suffix) != 0)
        return false;
    *stem = n - k;
    return true;
}

/* Recovers bodies and points from the coordinate names (spec section 2:
   a body adds NAME.x, NAME.y, NAME.phi; a point NAME.x, NAME.y; a scalar
   coord's name has no dot). */
static void map_coords(Scene *sc)
{
    const Model *m = sc->m;
    sc->owner = xcalloc((size_t)m->nq + 1, sizeof *sc->owner);
    sc->base = xcalloc((size_t)m->nq + 1, sizeof *sc->base);
    sc->driven = xcalloc((size_t)m->nq + 1, sizeof *sc->driven);
    sc->colour = xcalloc((size_t)m->nq + 1, sizeof *sc->colour);
    for (int i = 0; i < m->nq; i++) {
        sc->owner[i] = OWNER_SCALAR;
        sc->base[i] = i;
    }
    for (int i = 0; i + 1 < m->nq; i++) {
        size_t stem, stem_y, stem_phi;
        const char *nx = m->coord_names[i], *ny = m->coord_names[i + 1];
        if (!ends_with(nx, ".x", &stem) || !ends_with(ny, ".y", &stem_y) || stem != stem_y ||
            strncmp(nx, ny, stem) != 0)
            continue;
        bool body = i + 2 < m->nq && ends_with(m->coord_names[i + 2], ".phi", &stem_phi) &&
                    stem_phi == stem && strncmp(nx, m->coord_names[i + 2], stem) == 0;
        int count = body ? 3 : 2;
        for (int k = 0; k < count; k++) {
            sc->owner[i + k] = body ? OWNER_BODY : OWNER_POINT;
            sc->base[i + k] = i;
        }
        i += count - 1;
    }
}

/* The name of the body or point whose x coordinate is q ("crank"). */
static const char *owner_name(Scene *sc, int q)
{
    const char *nx = sc->m->coord_names[q];
    return arena_strndup(&sc->arena, nx, strlen(nx) - 2);
}

/* Marks the coordinates each driver's row depends on (velocity drivers:
   the velocities it prescribes). */
static void find_driven(Scene *sc)
{
    const Model *m = sc->m;
    SupportScan scan;
    support_init(&scan);
    int *cols = xmalloc(((size_t)m->nq + 1) * sizeof *cols);
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        if (jt->kind != JOINT_DRIVER || jt->nrows < 1 || jt->first_row < 0 || jt->first_row >= m->nr)
            continue;
        const Row *row = &m->rows[jt->first_row];
        int n = support_collect(&scan, &m->dag, row->expr, row->velocity ? OP_VARD : OP_VAR, cols);
        for (int k = 0; k < n; k++)
            if (cols[k] >= 0 && cols[k] < m->nq)
                sc->driven[cols[k]] = true;
    }
    free(cols);
    support_free(&scan);
}

static bool body_driven(const Scene *sc, int q, int count)
{
    for (int k = 0; k < count; k++)
        if (sc->driven[q + k])
            return true;
    return false;
}

/* One colour per body and point, in declaration order; red for driven ones. */
static void assign_colours(Scene *sc)
{
    int next = 0;
    for (int i = 0; i < sc->m->nq; i++) {
        if (sc->base[i] != i || sc->owner[i] == OWNER_SCALAR)
            continue;
        bool driven = body_driven(sc, i, sc->owner[i] == OWNER_BODY ? 3 : 2);
        sc->colour[i] = driven ? DRIVE_COLOUR : svg_palette[next++ % (SVG_PALETTE_SIZE - 1)];
    }
}

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

/* ---- convex hull of a body's local points (Andrew's monotone chain) ---- */

typedef struct P2 { double x, y; } P2;

static int cmp_p2(const void *pa, const void *pb)
{
    const P2 *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    return (a->y > b->y) - (a->y < b->y);
}

static double cross3(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/* Sorts p (deduplicated within tol) and writes its hull, counter-clockwise,
   into h (room for n + 1); returns the hull size: 1, 2 (collinear: the two
   extremes) or more. */
static int convex_hull(P2 *p, int n, P2 *h, double tol)
{
    qsort(p, (size_t)n, sizeof *p, cmp_p2);
    int m = 0;
    for (int i = 0; i < n; i++)
        if (m == 0 || fabs(p[i].x - p[m - 1].x) > tol || fabs(p[i].y - p[m - 1].y) > tol)
            p[m++] = p[i];
    if (m <= 2) {
        memcpy(h, p, (size_t)m * sizeof *p);
        return m;
    }
    int k = 0;
    double area_tol = tol * tol;
    for (int i = 0; i < m; i++) {
        while (k >= 2 && cross3(h[k - 2], h[k - 1], p[i]) <= area_tol)
            k--;
        h[k++] = p[i];
    }
    for (int i = m - 2, lo = k + 1; i >= 0; i--) {
        while (k >= lo && cross3(h[k - 2], h[k - 1], p[i]) <= area_tol)
            k--;
        h[k++] = p[i];
    }
    k--;                    /* the first point came round again */
    if (k < 2) {            /* all collinear: the chain collapsed */
        h[0] = p[0];
        h[1] = p[m - 1];
        return 2;
    }
    return k;
}

/* ---- building the scene ---- */

static void add_pin(Scene *sc, Attach a, const char *cls, double r, const char *name)
{
    Shape *s = add_shape(sc, SHAPE_CIRCLE, cls);
    add_vtx(sc, vtx_at(a));
    s->r = r;
    s->name = name;
    end_shape(sc, s);
}

/* The local points of body q: its joints' attachments, the reference point
   and the traced points on it (a coupler point makes the coupler a triangle). */
static int body_points(const Scene *sc, int q, P2 *pts)
{
    int n = 0;
    pts[n++] = (P2){0, 0};
    for (int i = 0; i < sc->ntraces; i++)
        if (sc->traces[i].q == q && sc->traces[i].has_phi)
            pts[n++] = (P2){sc->traces[i].sx, sc->traces[i].sy};
    for (int j = 0; j < sc->m->njoints; j++) {
        const Joint *jt = &sc->m->joints[j];
        const Attach *at[2] = {&jt->a, &jt->b};
        int na = jt->kind == JOINT_CONSTRAINT || jt->kind == JOINT_DRIVER ||
                 jt->kind == JOINT_VELOCITY ? 0 : jt->kind == JOINT_ROLLING || jt->kind == JOINT_KNIFE ? 1 : 2;
        for (int k = 0; k < na; k++)
            if (at[k]->q == q && at[k]->has_phi)
                pts[n++] = (P2){at[k]->sx, at[k]->sy};
    }
    return n;
}

static void build_bodies(Scene *sc)
{
    const Model *m = sc->m;
    size_t cap = (size_t)2 * m->njoints + (size_t)sc->ntraces + 3;
    P2 *pts = xmalloc(cap * sizeof *pts);
    P2 *hull = xmalloc((cap + 1) * sizeof *hull);
    for (int i = 0; i < m->nq; i++) {
        if (sc->base[i] != i || sc->owner[i] == OWNER_SCALAR)
            continue;
        bool body = sc->owner[i] == OWNER_BODY;
        const char *c = sc->colour[i];
        const char *name = owner_name(sc, i);
        if (!body) {
            Shape *s = add_shape(sc, SHAPE_CIRCLE, "particle");
            add_vtx(sc, (Vtx){i, false, 0, 0, -1, 0, 0});
            s->r = 5.5;
            s->fill = c;
            s->name = name;
            end_shape(sc, s);
            continue;
        }
        int n = body_points(sc, i, pts);
        int h = convex_hull(pts, n, hull, 1e-9 * sc->L);
        if (h == 1 && body_has_symbol(sc, i))
            continue;
        Shape *s = add_shape(sc, h >= 3 ? SHAPE_POLYGON : h == 2 ? SHAPE_POLYLINE : SHAPE_MARK, "link");
        for (int k = 0; k < h; k++)
            add_vtx(sc, (Vtx){i, true, hull[k].x, hull[k].y, -1, 0, 0});
        s->stroke = c;
        s->fill = h >= 3 ? c : h == 2 ? "none" : c;
        s->name = name;
        end_shape(sc, s);
    }
    free(pts);
    free(hull);
}

/* The range of u . (P_B - P_A) / |u|^2 over the kept frames, in A's frame:
   how far B slides along the axis (u as written, A's local frame). */
static void slide_range(const Scene *sc, const Joint *jt, double *lo, double *hi)
{
    double uu = jt->ux * jt->ux + jt->uy * jt->uy;
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int f = 0; f < sc->nf; f++) {
        int k = sc->frames[f];
        const double *qk = frame_q(sc, k);
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
    Shape *s = add_shape(sc, SHAPE_POLYLINE, "guide");
    add_vtx(sc, vtx_off(jt->a, jt->a, a * ex, a * ey));
    add_vtx(sc, vtx_off(jt->a, jt->a, b * ex, b * ey));
    s->name = jt->name;
    end_shape(sc, s);
    return s;
}

/* Ground symbols, drawn in pixels once the scale is known. */
typedef enum GroundKind { GROUND_PIVOT, GROUND_LINE } GroundKind;
typedef struct Ground {
    GroundKind kind;
    double x, y;            /* pivot: the point; line: one end (world) */
    double x2, y2;          /* line: the other end */
    double off;             /* line: drawn this far (world) on its hatched side */
} Ground;

typedef struct GroundList {
    Ground *g;
    int n, cap;
} GroundList;

static void add_ground(GroundList *gl, Ground g)
{
    if (gl->n == gl->cap) {
        gl->cap = gl->cap ? 2 * gl->cap : 16;
        gl->g = xrealloc(gl->g, (size_t)gl->cap, sizeof *gl->g);
    }
    gl->g[gl->n++] = g;
}

static void build_joints(Scene *sc, GroundList *gl)
{
    const Model *m = sc->m;
    double px = sc->px;
    double block_len = 52 * px, block_h = 30 * px;
    /* guides and blocks first, pins on top (second pass) */
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        switch (jt->kind) {
        case JOINT_PRISMATIC: {
            Shape *g = add_guide(sc, jt, 0.6 * block_len);
            if (jt->a.q < 0) {
                const Vtx *v0 = &sc->v[g->v0], *v1 = &sc->v[g->v0 + 1];
                add_ground(gl, (Ground){GROUND_LINE, v0->sx + v0->ox, v0->sy + v0->oy,
                                        v1->sx + v1->ox, v1->sy + v1->oy, 0.5 * block_h});
            }
            double ulen = hypot(jt->ux, jt->uy);
            double ex = jt->ux / ulen, ey = jt->uy / ulen;
            double nx = -ey, ny = ex;
            Shape *s = add_shape(sc, SHAPE_POLYGON, "slider");
            static const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
            for (int k = 0; k < 4; k++) {
                double a = 0.5 * block_len * corner[k][0], b = 0.5 * block_h * corner[k][1];
                add_vtx(sc, vtx_off(jt->b, jt->a, a * ex + b * nx, a * ey + b * ny));
            }
            s->name = jt->name;
            if (jt->b.q >= 0)
                s->stroke = sc->colour[jt->b.q];
            end_shape(sc, s);
            break;
        }
        case JOINT_POINTLINE:
            /* a slot, not a support: no hatching even on ground */
            add_guide(sc, jt, 24 * px);
            break;
        case JOINT_DISTANCE: {
            Shape *s = add_shape(sc, SHAPE_POLYLINE, "distance");
            add_vtx(sc, vtx_at(jt->a));
            add_vtx(sc, vtx_at(jt->b));
            s->name = jt->name;
            end_shape(sc, s);
            break;
        }
        case JOINT_ROLLING: {
            const double *q0 = frame_q(sc, sc->frames[0]);
            double R = fabs(node_value_at(&m->dag, jt->option, q0, NULL, sc->t[sc->frames[0]]));
            if (!isfinite(R) || R <= 0)
                break;
            Attach centre = {jt->a.q, true, 0, 0};
            Shape *s = add_shape(sc, SHAPE_CIRCLE, "disk");
            add_vtx(sc, vtx_at(centre));
            s->r = R;
            s->r_world = true;
            s->name = jt->name;
            s->stroke = sc->colour[jt->a.q];
            end_shape(sc, s);
            s = add_shape(sc, SHAPE_POLYLINE, "spoke");
            add_vtx(sc, vtx_at(centre));
            add_vtx(sc, vtx_off(centre, centre, R, 0));
            end_shape(sc, s);
            /* the ground line under the disk: frame 0's contact height */
            double xlo = INFINITY, xhi = -INFINITY, cx, cy;
            for (int f = 0; f < sc->nf; f++) {
                attach_world(sc, centre, sc->frames[f], &cx, &cy);
                xlo = fmin(xlo, cx);
                xhi = fmax(xhi, cx);
            }
            attach_world(sc, centre, sc->frames[0], &cx, &cy);
            add_ground(gl, (Ground){GROUND_LINE, xlo - 1.3 * R, cy - R, xhi + 1.3 * R, cy - R, 0});
            break;
        }
        case JOINT_KNIFE: {
            double ulen = hypot(jt->ux, jt->uy), h = 24 * px;
            double ex = jt->ux / ulen * h, ey = jt->uy / ulen * h;
            Shape *s = add_shape(sc, SHAPE_POLYLINE, "knife");
            add_vtx(sc, vtx_off(jt->a, jt->a, -ex, -ey));
            add_vtx(sc, vtx_off(jt->a, jt->a, ex, ey));
            s->name = jt->name;
            end_shape(sc, s);
            break;
        }
        case JOINT_REVOLUTE:
        case JOINT_WELD:
        case JOINT_CONSTRAINT:
        case JOINT_DRIVER:
        case JOINT_VELOCITY:
        case JOINT_KIND_COUNT:
            break;
        }
    }
}

/* Pins and dots go above the links: a second pass after the bodies. */
static void build_pins(Scene *sc, GroundList *gl)
{
    const Model *m = sc->m;
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        switch (jt->kind) {
        case JOINT_REVOLUTE:
        case JOINT_WELD:
        case JOINT_DISTANCE: {
            for (int k = 0; k < 2; k++) {
                Attach a = k ? jt->b : jt->a;
                if (a.q < 0)
                    add_ground(gl, (Ground){GROUND_PIVOT, a.sx, a.sy, 0, 0, 0});
            }
            if (jt->kind == JOINT_DISTANCE) {
                if (jt->a.q >= 0 && jt->a.has_phi)
                    add_pin(sc, jt->a, "pin", 3, jt->name);
                if (jt->b.q >= 0 && jt->b.has_phi)
                    add_pin(sc, jt->b, "pin", 3, jt->name);
                break;
            }
            /* a pin at the joint: the ground side when there is one (exact) */
            Attach at = jt->a.q < 0 ? jt->a : jt->b.q < 0 ? jt->b : jt->a;
            add_pin(sc, at, jt->kind == JOINT_WELD ? "weld" : "pin", jt->kind == JOINT_WELD ? 3.5 : 4.5,
                    jt->name);
            break;
        }
        case JOINT_POINTLINE:
            add_pin(sc, jt->b, "dot", 3.5, jt->name);
            break;
        case JOINT_PRISMATIC:
        case JOINT_CONSTRAINT:
        case JOINT_DRIVER:
        case JOINT_ROLLING:
        case JOINT_KNIFE:
        case JOINT_VELOCITY:
        case JOINT_KIND_COUNT:
            break;
        }
    }
}

/* An arrow turning with each body whose angle is driven, around its ground
   pivot when it has one, else around its reference point. */
static void build_drive_arrows(Scene *sc)
{
    const Model *m = sc->m;
    for (int i = 0; i + 2 < m->nq; i++) {
        if (sc->owner[i] != OWNER_BODY || sc->base[i] != i || !sc->driven[i + 2])
            continue;
        Attach centre = {i, true, 0, 0};
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
        double turn = frame_q(sc, sc->frames[sc->nf - 1])[i + 2] - frame_q(sc, sc->frames[0])[i + 2];
        Shape *s = add_shape(sc, SHAPE_POLYLINE, "drive");
        for (int k = 0; k <= 16; k++) {
            double a = (turn >= 0 ? 40.0 + 240.0 * k / 16 : 140.0 - 240.0 * k / 16) * (3.14159265358979323846 / 180);
            add_vtx(sc, vtx_off(centre, centre, rho * cos(a), rho * sin(a)));
        }
        s->extra = "marker-end=\"url(#arrow)\"";
        end_shape(sc, s);
    }
}

static void build_trace_dots(Scene *sc, const SvgTrace *tr, int ntr)
{
    for (int i = 0; i < ntr; i++) {
        Attach a = {tr[i].q, tr[i].has_phi, tr[i].sx, tr[i].sy};
        Shape *s = add_shape(sc, SHAPE_CIRCLE, "tracedot");
        add_vtx(sc, vtx_at(a));
        s->r = 3.5;
        s->fill = svg_palette[(i + 3) % (SVG_PALETTE_SIZE - 1)];
        s->name = tr[i].label;
        end_shape(sc, s);
    }
}

/* ---- extent and pixel mapping ---- */

typedef struct Box { double x0, y0, x1, y1; } Box;

static void box_add(Box *b, double x, double y)
{
    if (!isfinite(x) || !isfinite(y))
        return;
    b->x0 = fmin(b->x0, x);
    b->y0 = fmin(b->y0, y);
    b->x1 = fmax(b->x1, x);
    b->y1 = fmax(b->y1, y);
}

/* Frames sampled for a trace's static path: all when few, else evenly. */
static int path_frame(const Scene *sc, int j, int count)
{
    if (count >= sc->n)
        return j;
    return (int)((double)j * (sc->n - 1) / (count - 1) + 0.5);
}

/* Extent of everything that moves or is fixed (first pass: joint points,
   bodies, particles and traces; second pass: every shape). */
static Box scene_box(const Scene *sc, bool shapes, const SvgTrace *tr, int ntr, const GroundList *gl)
{
    Box b = {INFINITY, INFINITY, -INFINITY, -INFINITY};
    const Model *m = sc->m;
    double x, y;
    for (int f = 0; f < sc->nf; f++) {
        int k = sc->frames[f];
        const double *qk = frame_q(sc, k);
        if (shapes) {
            for (int s = 0; s < sc->nsh; s++) {
                const Shape *sh = &sc->sh[s];
                for (int v = sh->v0; v < sh->v0 + sh->nv; v++) {
                    vtx_world(&sc->v[v], qk, &x, &y);
                    double r = sh->r_world ? sh->r : 0;
                    box_add(&b, x - r, y - r);
                    box_add(&b, x + r, y + r);
                }
            }
            continue;
        }
        for (int i = 0; i < m->nq; i++)
            if (sc->owner[i] != OWNER_SCALAR && sc->base[i] == i)
                box_add(&b, qk[i], qk[i + 1]);
        for (int j = 0; j < m->njoints; j++) {
            const Joint *jt = &m->joints[j];
            const Attach *at[2] = {&jt->a, &jt->b};
            int na = jt->kind == JOINT_CONSTRAINT || jt->kind == JOINT_DRIVER ||
                     jt->kind == JOINT_VELOCITY ? 0 : jt->kind == JOINT_ROLLING || jt->kind == JOINT_KNIFE ? 1 : 2;
            for (int a = 0; a < na; a++) {
                attach_world(sc, *at[a], k, &x, &y);
                box_add(&b, x, y);
            }
        }
    }
    int count = sc->n < PATH_POINTS_MAX ? sc->n : PATH_POINTS_MAX;
    for (int i = 0; i < ntr; i++) {
        Vtx v = {tr[i].q, tr[i].has_phi, tr[i].sx, tr[i].sy, -1, 0, 0};
        for (int j = 0; j < count; j++) {
            vtx_world(&v, frame_q(sc, path_frame(sc, j, count)), &x, &y);
            box_add(&b, x, y);
        }
    }
    for (int i = 0; gl && i < gl->n; i++) {
        box_add(&b, gl->g[i].x, gl->g[i].y);
        if (gl->g[i].kind == GROUND_LINE)
            box_add(&b, gl->g[i].x2, gl->g[i].y2);
    }
    if (!(b.x0 <= b.x1)) {      /* nothing drawn: a unit square at the origin */
        b = (Box){-0.5, -0.5, 0.5, 0.5};
    }
    return b;
}

static void set_mapping(Scene *sc, Box b, const SvgAnimOptions *o, int footer_lines)
{
    double w = b.x1 - b.x0, h = b.y1 - b.y0;
    double size = fmax(w, h);
    if (!(size > 0))
        size = 1;
    /* a degenerate direction (a slider on a line) gets a little height */
    double minext = 0.15 * size;
    if (w < minext) {
        b.x0 -= 0.5 * (minext - w);
        w = minext;
    }
    if (h < minext) {
        b.y0 -= 0.5 * (minext - h);
        h = minext;
    }
    sc->s = fmin(o->width / w, o->height / h);
    sc->xmin = b.x0;
    sc->ymax = b.y0 + h;
    sc->ox = MARGIN_PX;
    sc->oy = HEADER_PX + MARGIN_PX;
    sc->width = (int)ceil(w * sc->s + 2 * MARGIN_PX);
    if (sc->width < 320)
        sc->width = 320;
    sc->ox = 0.5 * (sc->width - w * sc->s);
    sc->height = (int)ceil(HEADER_PX + h * sc->s + 2 * MARGIN_PX + LINE_PX * footer_lines + 6);
}

static double px_x(const Scene *sc, double x) { return sc->ox + sc->s * (x - sc->xmin); }
static double px_y(const Scene *sc, double y) { return sc->oy + sc->s * (sc->ymax - y); }

/* ---- output ---- */

typedef struct Writer {
    FILE *out;
    const Scene *sc;
    char *key_times;        /* keyTimes="..." attribute text, or "" when even */
    char dur[SVG_NUM_MAX];
    double *kt;             /* per kept frame, in [0, 1] */
} Writer;

static void put_num(FILE *out, double v)
{
    char buf[SVG_NUM_MAX];
    fputs(svg_fmt_fixed(buf, v, 1), out);
}

static void put_xy(FILE *out, double x, double y)
{
    put_num(out, x);
    fputc(',', out);
    put_num(out, y);
}

/* Pixel coordinates of shape sh at every kept frame: xy[(f*nv + v)*2 + 0/1]. */
static double *shape_pixels(const Scene *sc, const Shape *sh)
{
    double *xy = xmalloc((size_t)sc->nf * (size_t)sh->nv * 2 * sizeof *xy);
    for (int f = 0; f < sc->nf; f++) {
        const double *qk = frame_q(sc, sc->frames[f]);
        for (int v = 0; v < sh->nv; v++) {
            double x, y;
            vtx_world(&sc->v[sh->v0 + v], qk, &x, &y);
            /* rounded as printed, so "moves" means a visible change */
            xy[((size_t)f * sh->nv + v) * 2] = round(px_x(sc, x) * 10) / 10;
            xy[((size_t)f * sh->nv + v) * 2 + 1] = round(px_y(sc, y) * 10) / 10;
        }
    }
    return xy;
}

static bool shape_moves(const Scene *sc, const Shape *sh, const double *xy)
{
    size_t per = (size_t)sh->nv * 2;
    for (int f = 1; f < sc->nf; f++)
        if (memcmp(xy, xy + (size_t)f * per, per * sizeof *xy) != 0)
            return true;
    return false;
}

static void put_points(FILE *out, const double *xy, int nv)
{
    for (int v = 0; v < nv; v++) {
        if (v)
            fputc(' ', out);
        put_xy(out, xy[2 * v], xy[2 * v + 1]);
    }
}

static void put_timing(const Writer *w)
{
    fprintf(w->out, "%s dur=\"%ss\" repeatCount=\"indefinite\"", w->key_times, w->dur);
}

static void write_shape(const Writer *w, const Shape *sh)
{
    FILE *out = w->out;
    const Scene *sc = w->sc;
    double *xy = shape_pixels(sc, sh);
    bool moves = shape_moves(sc, sh, xy);
    size_t per = (size_t)sh->nv * 2;
    char buf[SVG_NUM_MAX];
    switch (sh->kind) {
    case SHAPE_POLYLINE:
    case SHAPE_POLYGON:
        fprintf(out, "<%s class=\"%s\" points=\"", sh->kind == SHAPE_POLYGON ? "polygon" : "polyline", sh->cls);
        put_points(out, xy, sh->nv);
        fputc('"', out);
        break;
    case SHAPE_CIRCLE: {
        double r = sh->r_world ? sh->r * sc->s : sh->r;
        fprintf(out, "<circle class=\"%s\" r=\"%s\" transform=\"translate(", sh->cls, svg_fmt_fixed(buf, r, 1));
        put_xy(out, xy[0], xy[1]);
        fputs(")\"", out);
        break;
    }
    case SHAPE_MARK:
        fprintf(out, "<rect class=\"%s\" x=\"-5\" y=\"-5\" width=\"10\" height=\"10\" transform=\"translate(", sh->cls);
        put_xy(out, xy[0], xy[1]);
        fputs(")\"", out);
        break;
    }
    /* a style attribute, since it wins over the class rules */
    if (sh->stroke || sh->fill)
        fprintf(out, " style=\"%s%s%s%s%s\"", sh->stroke ? "stroke:" : "", sh->stroke ? sh->stroke : "",
                sh->stroke && sh->fill ? ";" : "", sh->fill ? "fill:" : "", sh->fill ? sh->fill : "");
    if (sh->extra)
        fprintf(out, " %s", sh->extra);
    if (!moves && !sh->name) {
        fputs("/>\n", out);
        free(xy);
        return;
    }
    fputs(">", out);
    if (sh->name) {
        fputs("<title>", out);
        svg_put_escaped(out, sh->name);
        fputs("</title>", out);
    }
    if (moves) {
        bool poly = sh->kind == SHAPE_POLYLINE || sh->kind == SHAPE_POLYGON;
        fputs(poly ? "\n <animate attributeName=\"points\" values=\""
                   : "\n <animateTransform attributeName=\"transform\" type=\"translate\" values=\"", out);
        for (int f = 0; f < sc->nf; f++) {
            if (f)
                fputc(';', out);
            if (poly)
                put_points(out, xy + (size_t)f * per, sh->nv);
            else
                put_xy(out, xy[(size_t)f * per], xy[(size_t)f * per + 1]);
        }
        fputc('"', out);
        put_timing(w);
        fputs("/>\n", out);
    }
    fprintf(out, "</%s>\n", sh->kind == SHAPE_POLYGON ? "polygon" : sh->kind == SHAPE_POLYLINE ? "polyline"
                          : sh->kind == SHAPE_CIRCLE ? "circle" : "rect");
    free(xy);
}

/* Hatching: n short strokes below the segment (x0,y0)-(x1,y1) on the side
   of (nx, ny) (pixels). */
static void put_hatch(FILE *out, double x0, double y0, double x1, double y1, double nx, double ny)
{
    double len = hypot(x1 - x0, y1 - y0);
    int n = (int)(len / 7);
    if (n < 2)
        n = 2;
    if (n > 400)
        n = 400;
    fputs("<path class=\"hatch\" d=\"", out);
    for (int i = 0; i <= n; i++) {
        double x = x0 + (x1 - x0) * i / n, y = y0 + (y1 - y0) * i / n;
        fputs(i ? " M" : "M", out);
        put_xy(out, x, y);
        fputc('l', out);
        /* 45 degrees between the normal and the line's backward direction */
        double bx = -(x1 - x0) / len, by = -(y1 - y0) / len;
        put_xy(out, 6 * (nx + bx) / 1.414, 6 * (ny + by) / 1.414);
    }
    fputs("\"/>\n", out);
}

static void write_ground(FILE *out, const Scene *sc, const GroundList *gl)
{
    for (int i = 0; i < gl->n; i++) {
        const Ground *g = &gl->g[i];
        double x = px_x(sc, g->x), y = px_y(sc, g->y);
        if (g->kind == GROUND_PIVOT) {
            /* a triangle under the point, a base line and hatching */
            fputs("<g class=\"ground\"><polygon class=\"pivot\" points=\"", out);
            put_xy(out, x, y);
            fputc(' ', out);
            put_xy(out, x - 9, y + 15);
            fputc(' ', out);
            put_xy(out, x + 9, y + 15);
            fputs("\"/>\n", out);
            put_hatch(out, x - 14, y + 15, x + 14, y + 15, 0, 1);
            fputs("</g>\n", out);
        } else {
            double x2 = px_x(sc, g->x2), y2 = px_y(sc, g->y2);
            double len = hypot(x2 - x, y2 - y);
            if (!(len > 1))
                continue;
            /* hatch on the side below the line (screen y down) */
            double nx = -(y2 - y) / len, ny = (x2 - x) / len;
            if (ny < 0 || (ny == 0 && nx < 0)) {
                nx = -nx;
                ny = -ny;
            }
            double off = g->off * sc->s;
            x += off * nx;
            y += off * ny;
            x2 += off * nx;
            y2 += off * ny;
            fputs("<g class=\"ground\"><polyline class=\"base\" points=\"", out);
            put_xy(out, x, y);
            fputc(' ', out);
            put_xy(out, x2, y2);
            fputs("\"/>", out);
            put_hatch(out, x, y, x2, y2, nx, ny);
            fputs("</g>\n", out);
        }
    }
}

static void write_trace_paths(FILE *out, const Scene *sc, const SvgTrace *tr, int ntr)
{
    int count = sc->n < PATH_POINTS_MAX ? sc->n : PATH_POINTS_MAX;
    for (int i = 0; i < ntr; i++) {
        Vtx v = {tr[i].q, tr[i].has_phi, tr[i].sx, tr[i].sy, -1, 0, 0};
        fprintf(out, "<polyline class=\"trace\" stroke=\"%s\" points=\"",
                svg_palette[(i + 3) % (SVG_PALETTE_SIZE - 1)]);
        double px = NAN, py = NAN;
        int written = 0;
        for (int j = 0; j < count; j++) {
            double x, y;
            vtx_world(&v, frame_q(sc, path_frame(sc, j, count)), &x, &y);
            x = round(px_x(sc, x) * 10) / 10;
            y = round(px_y(sc, y) * 10) / 10;
            if (x == px && y == py)
                continue;
            if (written++)
                fputc(' ', out);
            put_xy(out, x, y);
            px = x;
            py = y;
        }
        if (written == 1) {     /* a point that does not move: a zero-length segment */
            fputc(' ', out);
            put_xy(out, px, py);
        }
        fputs("\">", out);
        if (tr[i].label) {
            fputs("<title>", out);
            svg_put_escaped(out, tr[i].label);
            fputs("</title>", out);
        }
        fputs("</polyline>\n", out);
    }
}

/* The time in the header: one text per shown instant, made visible in turn
   with discrete visibility animations (SMIL cannot animate text content). */
static void write_time(const Writer *w)
{
    FILE *out = w->out;
    const Scene *sc = w->sc;
    double t0 = sc->t[sc->frames[0]], t1 = sc->t[sc->frames[sc->nf - 1]];
    double span = fabs(t1 - t0) > 0 ? fabs(t1 - t0) : fmax(fabs(t0), 1);
    int decimals = 3 - (int)floor(log10(span));
    if (decimals < 0)
        decimals = 0;
    if (decimals > 9)
        decimals = 9;
    int step = (sc->nf + TIME_LABELS_MAX - 1) / TIME_LABELS_MAX;
    int nlab = (sc->nf - 1) / step + 1;
    double x = sc->width - 10.0;
    char kt_a[SVG_NUM_MAX], kt_b[SVG_NUM_MAX];
    fputs("<g class=\"time\">\n", out);
    for (int j = 0; j < nlab; j++) {
        int f = j * step;
        fprintf(out, "<text x=\"%s\" y=\"22\" text-anchor=\"end\" visibility=\"%s\">t = %.*f",
                svg_fmt_fixed(kt_a, x, 1), j == 0 ? "visible" : "hidden", decimals,
                sc->t[sc->frames[f]]);
        if (nlab > 1) {
            svg_fmt_fixed(kt_a, w->kt[f], 4);
            svg_fmt_fixed(kt_b, j + 1 < nlab ? w->kt[(j + 1) * step] : 1, 4);
            fputs("<animate attributeName=\"visibility\" calcMode=\"discrete\" ", out);
            if (j == 0)
                fprintf(out, "values=\"visible;hidden\" keyTimes=\"0;%s\"", kt_b);
            else if (j + 1 == nlab)
                fprintf(out, "values=\"hidden;visible\" keyTimes=\"0;%s\"", kt_a);
            else
                fprintf(out, "values=\"hidden;visible;hidden\" keyTimes=\"0;%s;%s\"", kt_a, kt_b);
            fprintf(out, " dur=\"%ss\" repeatCount=\"indefinite\"/>", w->dur);
        }
        fputs("</text>\n", out);
    }
    /* a bar under the header filling up over one playback */
    double y = HEADER_PX - 4;
    fprintf(out, "<rect class=\"bar\" x=\"0\" y=\"%s\" width=\"0\" height=\"3\">",
            svg_fmt_fixed(kt_a, y, 1));
    if (sc->nf > 1)
        fprintf(out, "<animate attributeName=\"width\" values=\"0;%d\"%s dur=\"%ss\" repeatCount=\"indefinite\"/>",
                sc->width, w->key_times[0] ? " keyTimes=\"0;1\"" : "", w->dur);
    fputs("</rect>\n</g>\n", out);
}

/* One line per driver (the coordinates it drives) and per trace. */
static void write_legend(FILE *out, const Scene *sc, const SvgTrace *tr, int ntr)
{
    const Model *m = sc->m;
    int nlines = 0;
    for (int j = 0; j < m->njoints; j++)
        nlines += m->joints[j].kind == JOINT_DRIVER;
    nlines += ntr;
    int l = 0;
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        if (jt->kind != JOINT_DRIVER)
            continue;
        double y = sc->height - 8 - LINE_PX * (nlines - 1 - l++);
        fprintf(out, "<g class=\"legend\"><rect x=\"10\" y=\"%.1f\" width=\"14\" height=\"4\" fill=\"%s\"/>"
                     "<text x=\"30\" y=\"%.1f\">driver ",
                y - 6, DRIVE_COLOUR, y);
        svg_put_escaped(out, jt->name);
        fputs(":", out);
        /* the coordinates its row depends on */
        SupportScan scan;
        support_init(&scan);
        int *cols = xmalloc(((size_t)m->nq + 1) * sizeof *cols);
        const Row *row = &m->rows[jt->first_row];
        int n = support_collect(&scan, &m->dag, row->expr, row->velocity ? OP_VARD : OP_VAR, cols);
        for (int k = 0; k < n; k++) {
            fputs(k ? ", " : " ", out);
            if (row->velocity)
                fputs("der(", out);
            svg_put_escaped(out, m->coord_names[cols[k]]);
            if (row->velocity)
                fputs(")", out);
        }
        free(cols);
        support_free(&scan);
        fputs("</text></g>\n", out);
    }
    for (int i = 0; i < ntr; i++) {
        double y = sc->height - 8 - LINE_PX * (nlines - 1 - l++);
        fprintf(out, "<g class=\"legend\"><rect x=\"10\" y=\"%.1f\" width=\"14\" height=\"4\" fill=\"%s\"/>"
                     "<text x=\"30\" y=\"%.1f\">path of ",
                y - 6, svg_palette[(i + 3) % (SVG_PALETTE_SIZE - 1)], y);
        svg_put_escaped(out, tr[i].label ? tr[i].label : "a point");
        fputs("</text></g>\n", out);
    }
}

/* keyTimes from the times of the kept frames: "" when they are evenly
   spaced (SMIL's default), else the attribute. */
static char *make_key_times(Scene *sc, double *kt)
{
    double t0 = sc->t[sc->frames[0]], t1 = sc->t[sc->frames[sc->nf - 1]];
    bool even = true;
    for (int f = 0; f < sc->nf; f++) {
        double u = sc->nf > 1 ? (double)f / (sc->nf - 1) : 0;
        kt[f] = t1 > t0 ? (sc->t[sc->frames[f]] - t0) / (t1 - t0) : u;
        kt[f] = round(kt[f] * 1e4) / 1e4;
        if (fabs(kt[f] - u) > 5e-5)
            even = false;
    }
    if (sc->nf > 1) {
        kt[0] = 0;
        kt[sc->nf - 1] = 1;
    }
    if (even)
        return arena_strdup(&sc->arena, "");
    size_t cap = (size_t)sc->nf * 8 + 16;
    char *s = arena_alloc(&sc->arena, cap), buf[SVG_NUM_MAX];
    size_t len = (size_t)snprintf(s, cap, " keyTimes=\"");
    for (int f = 0; f < sc->nf; f++)
        len += (size_t)snprintf(s + len, cap - len, "%s%s", f ? ";" : "", svg_fmt_fixed(buf, kt[f], 4));
    snprintf(s + len, cap - len, "\"");
    return s;
}

static const char style_sheet[] =
    "<style>\n"
    "text{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;font-size:13px;fill:#222}\n"
    ".title{font-size:15px;font-weight:bold}\n"
    ".link{stroke-width:6;stroke-linecap:round;stroke-linejoin:round;fill-opacity:.25}\n"
    "rect.link{stroke-width:2}\n"
    ".pin{fill:#fff;stroke:#222;stroke-width:1.6}\n"
    ".weld,.dot{fill:#222}\n"
    ".particle{stroke:#222;stroke-width:1}\n"
    ".tracedot{stroke:#fff;stroke-width:1}\n"
    ".guide{fill:none;stroke:#555;stroke-width:1.5}\n"
    ".slider{fill:#d9d9d9;stroke:#333;stroke-width:1.5}\n"
    ".distance{fill:none;stroke:#444;stroke-width:1.3;stroke-dasharray:6 3}\n"
    ".pivot{fill:#e8e8e8;stroke:#444;stroke-width:1.2}\n"
    ".hatch{fill:none;stroke:#444;stroke-width:1}\n"
    ".base{fill:none;stroke:#444;stroke-width:1.5}\n"
    ".disk{fill:#eee;fill-opacity:.6;stroke:#333;stroke-width:2}\n"
    ".spoke{fill:none;stroke:#333;stroke-width:2}\n"
    ".knife{fill:none;stroke:#111;stroke-width:5}\n"
    ".trace{fill:none;stroke-width:1.3;stroke-dasharray:5 2}\n"
    ".drive{fill:none;stroke:" DRIVE_COLOUR ";stroke-width:2}\n"
    ".bar{fill:#bbb}\n"
    "</style>\n";

static void write_scene(FILE *out, Scene *sc, const SvgTrace *tr, int ntr, const GroundList *gl,
                        const char *title, const SvgAnimOptions *o)
{
    Writer w = {out, sc, NULL, {0}, NULL};
    w.kt = xmalloc((size_t)sc->nf * sizeof *w.kt);
    w.key_times = make_key_times(sc, w.kt);
    double t0 = sc->t[sc->frames[0]], t1 = sc->t[sc->frames[sc->nf - 1]];
    double dur = fmin(fmax(t1 - t0, o->min_duration), o->max_duration);
    svg_fmt_sig(w.dur, dur, 4);

    fprintf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                 "viewBox=\"0 0 %d %d\">\n<title>",
            sc->width, sc->height, sc->width, sc->height);
    svg_put_escaped(out, title);
    fputs("</title>\n<desc>Made by mechc: the mechanism at the first instant; SMIL animations play the run "
          "(y up, equal scales).</desc>\n", out);
    fputs(style_sheet, out);
    fputs("<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"5\" refY=\"5\" markerWidth=\"5\" "
          "markerHeight=\"5\" orient=\"auto\"><path d=\"M0,0 L10,5 L0,10 z\" fill=\"" DRIVE_COLOUR
          "\"/></marker></defs>\n", out);
    fprintf(out, "<rect width=\"%d\" height=\"%d\" fill=\"#fff\"/>\n", sc->width, sc->height);
    fputs("<text class=\"title\" x=\"10\" y=\"22\">", out);
    svg_put_escaped(out, title);
    fputs("</text>\n", out);
    write_time(&w);
    write_ground(out, sc, gl);
    write_trace_paths(out, sc, tr, ntr);
    for (int s = 0; s < sc->nsh; s++)
        write_shape(&w, &sc->sh[s]);
    write_legend(out, sc, tr, ntr);
    fputs("</svg>\n", out);
    free(w.kt);
}

/* Frames kept: all when at most max, else about max indices including the
   first and the last. An exact stride is preferred when it keeps at least
   60 % of max (1001 frames: every 8th, 126 frames): evenly spaced frames of
   an evenly stepped run need no keyTimes lists, which saves a third of the
   file. */
static int pick_frames(int n, int max, int *out)
{
    if (max < 2)
        max = 2;
    if (n <= max) {
        for (int k = 0; k < n; k++)
            out[k] = k;
        return n;
    }
    for (int f = max; f >= 2 && 10 * f >= 6 * max; f--) {
        if ((n - 1) % (f - 1) == 0) {
            int stride = (n - 1) / (f - 1);
            for (int j = 0; j < f; j++)
                out[j] = j * stride;
            return f;
        }
    }
    for (int j = 0; j < max; j++)
        out[j] = (int)((double)j * (n - 1) / (max - 1) + 0.5);
    return max;
}

static bool valid_input(const Model *m, const double *t, const double *q, int n,
                        const SvgTrace *tr, int ntr)
{
    if (!m || !t || !q || n < 1 || m->nq < 1 || (ntr > 0 && !tr) || ntr < 0)
        return false;
    for (int k = 0; k < n; k++) {
        if (!isfinite(t[k]) || (k > 0 && t[k] < t[k - 1]))
            return false;
        for (int i = 0; i < m->nq; i++)
            if (!isfinite(q[(size_t)k * m->nq + i]))
                return false;
    }
    for (int i = 0; i < ntr; i++) {
        int need = tr[i].has_phi ? 3 : 2;
        if (tr[i].q < 0 || tr[i].q + need > m->nq || !isfinite(tr[i].sx) || !isfinite(tr[i].sy))
            return false;
    }
    return true;
}

bool svg_write_animation_opt(FILE *out, const Model *m, const double *t, const double *q,
                             int nframes, const SvgTrace *traces, int ntraces,
                             const char *title, const SvgAnimOptions *opt)
{
    SvgAnimOptions o = opt ? *opt : svg_anim_default_options();
    if (!out || !valid_input(m, t, q, nframes, traces, ntraces) || o.width < 50 || o.height < 50) {
        errno = EINVAL;
        return false;
    }
    Scene sc;
    memset(&sc, 0, sizeof sc);
    arena_init(&sc.arena);
    sc.m = m;
    sc.t = t;
    sc.q = q;
    sc.n = nframes;
    sc.traces = traces;
    sc.ntraces = ntraces;
    sc.frames = xmalloc((size_t)(o.max_frames > 2 ? o.max_frames : 2) * sizeof *sc.frames);
    sc.nf = pick_frames(nframes, o.max_frames, sc.frames);
    map_coords(&sc);
    find_driven(&sc);
    assign_colours(&sc);

    Box b = scene_box(&sc, false, traces, ntraces, NULL);
    sc.L = fmax(b.x1 - b.x0, b.y1 - b.y0);
    if (!(sc.L > 0))
        sc.L = 1;
    set_mapping(&sc, b, &o, 0);
    sc.px = 1 / sc.s;
    GroundList gl = {0};
    build_joints(&sc, &gl);
    build_bodies(&sc);
    build_drive_arrows(&sc);
    build_pins(&sc, &gl);
    build_trace_dots(&sc, traces, ntraces);

    /* each moving vertex costs about 15 bytes per frame ("123.4,567.8 ", and
       the elements around) */
    long moving = 0;
    for (int i = 0; i < sc.nv; i++)
        moving += sc.v[i].q >= 0;
    long budget = moving > 0 ? o.max_bytes / (15 * moving) : o.max_frames;
    if (budget < sc.nf)
        sc.nf = pick_frames(nframes, budget < 10 ? 10 : (int)budget, sc.frames);

    Box all = scene_box(&sc, true, traces, ntraces, &gl);
    Box first = scene_box(&sc, false, traces, ntraces, NULL);
    box_add(&all, first.x0, first.y0);
    box_add(&all, first.x1, first.y1);
    int footer = ntraces;
    for (int j = 0; j < m->njoints; j++)
        footer += m->joints[j].kind == JOINT_DRIVER;
    set_mapping(&sc, all, &o, footer);

    clearerr(out);
    write_scene(out, &sc, traces, ntraces, &gl, title ? title : m->name, &o);
    bool ok = fflush(out) == 0 && !ferror(out);

    free(gl.g);
    free(sc.frames);
    free(sc.v);
    free(sc.sh);
    free(sc.owner);
    free(sc.base);
    free(sc.driven);
    free(sc.colour);
    arena_free(&sc.arena);
    return ok;
}

bool svg_write_animation(FILE *out, const Model *m, const double *t, const double *q,
                         int nframes, const SvgTrace *traces, int ntraces, const char *title)
{
    return svg_write_animation_opt(out, m, t, q, nframes, traces, ntraces, title, NULL);
}

/* ---- --trace BODY(sx, sy) ---- */

static const char *skip_blank(const char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    return s;
}

/* A number as strtod reads it, signed; *end after it. */
static bool parse_number(const char *s, double *v, const char **end)
{
    char *e;
    errno = 0;
    *v = strtod(s, &e);
    if (e == s || errno == ERANGE || !isfinite(*v))
        return false;
    /* strtod also takes "inf", "nan" and hex: numbers here are decimal */
    for (const char *p = s; p < e; p++)
        if (!(strchr("0123456789.eE+-", *p)))
            return false;
    *end = e;
    return true;
}

bool svg_parse_trace(const Model *m, const char *text, SvgTrace *out, char *err, size_t errlen)
{
    const char *s = skip_blank(text ? text : "");
    const char *name = s;
    if (!(*s == '_' || (*s >= 'A' && *s <= 'Z') || (*s >= 'a' && *s <= 'z'))) {
        snprintf(err, errlen, "--trace '%s': expected BODY(sx, sy), BODY or POINT", text ? text : "");
        return false;
    }
    while (*s == '_' || (*s >= 'A' && *s <= 'Z') || (*s >= 'a' && *s <= 'z') || (*s >= '0' && *s <= '9'))
        s++;
    size_t len = (size_t)(s - name);
    if (len == 6 && strncmp(name, "ground", 6) == 0) {
        snprintf(err, errlen, "--trace '%s': ground does not move; name a body or a point", text);
        return false;
    }
    /* find NAME.x among the coordinates */
    int q = -1;
    for (int i = 0; i + 1 < m->nq; i++) {
        const char *c = m->coord_names[i];
        if (strncmp(c, name, len) == 0 && strcmp(c + len, ".x") == 0) {
            q = i;
            break;
        }
    }
    if (q < 0) {
        bool scalar = false;
        for (int i = 0; i < m->nq; i++)
            if (strlen(m->coord_names[i]) == len && strncmp(m->coord_names[i], name, len) == 0)
                scalar = true;
        snprintf(err, errlen, "--trace '%s': '%.*s' is %s", text, (int)len, name,
                 scalar ? "a scalar coordinate, not a body or a point" : "not a body or a point of the mechanism");
        return false;
    }
    bool has_phi = q + 2 < m->nq && strncmp(m->coord_names[q + 2], name, len) == 0 &&
                   strcmp(m->coord_names[q + 2] + len, ".phi") == 0;
    double sx = 0, sy = 0;
    s = skip_blank(s);
    if (*s == '(') {
        if (!has_phi) {
            snprintf(err, errlen, "--trace '%s': '%.*s' is a point; it takes no offset", text, (int)len, name);
            return false;
        }
        const char *e;
        s = skip_blank(s + 1);
        if (!parse_number(s, &sx, &e)) {
            snprintf(err, errlen, "--trace '%s': expected a number for sx at '%s'", text, s);
            return false;
        }
        s = skip_blank(e);
        if (*s != ',') {
            snprintf(err, errlen, "--trace '%s': expected ',' between sx and sy", text);
            return false;
        }
        s = skip_blank(s + 1);
        if (!parse_number(s, &sy, &e)) {
            snprintf(err, errlen, "--trace '%s': expected a number for sy at '%s'", text, s);
            return false;
        }
        s = skip_blank(e);
        if (*s != ')') {
            snprintf(err, errlen, "--trace '%s': expected ')' after sy", text);
            return false;
        }
        s = skip_blank(s + 1);
    }
    if (*s) {
        snprintf(err, errlen, "--trace '%s': unexpected '%s' (expected BODY(sx, sy), BODY or POINT)", text, s);
        return false;
    }
    out->q = q;
    out->has_phi = has_phi;
    out->sx = sx;
    out->sy = sy;
    out->label = text;
    return true;
}
