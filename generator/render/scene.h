/* scene.h - what an animation draws: shapes whose vertices are points fixed to bodies or ground. */
#ifndef MECHC_SCENE_H
#define MECHC_SCENE_H

#include "svg_anim.h"

#include <stdbool.h>

#define SCENE_DRIVE_COLOUR "#d62728"

/* P = r + A(phi) s of attachment (q, has_phi, sx, sy), then + A(q[fq]) o
   (fq: a phi coordinate, or -1 for a world offset). A spatial vertex
   (spatial true) is P = r + A(p) s in 3D, s = (sx, sy, sz), p the Euler
   parameters at q + 3 when has_p, then + A(p) o with the Euler parameters
   of the body whose x is fq (or -1: a world offset), o = (ox, oy, oz). */
typedef struct Vtx {
    int q;
    bool has_phi;
    double sx, sy;
    int fq;
    double ox, oy;
    bool spatial, has_p;
    double sz, oz;
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
    int v0, nv;             /* its vertices: v[v0 .. v0 + nv) */
    double r;               /* circle radius */
    bool r_world;           /* r in model units (a rolling disk) */
} Shape;

/* Ground symbols, drawn in pixels once the scale is known. */
typedef enum GroundKind { GROUND_PIVOT, GROUND_LINE } GroundKind;
typedef struct Ground {
    GroundKind kind;
    double x, y;            /* pivot: the point; line: one end (world) */
    double x2, y2;          /* line: the other end */
    double off;             /* line: drawn this far (world) on its hatched side */
} Ground;

typedef struct Scene {
    const Model *m;
    SvgView view;           /* a spatial mechanism's projection */
    const double *t, *q;
    int n;                  /* frames given */
    const SvgTrace *traces;
    int ntraces;
    int *frames, nf;        /* kept frames (indices into t) */
    Vtx *v;
    int nv, vcap;
    Shape *sh;
    int nsh, shcap;
    Ground *ground;
    int nground, groundcap;
    bool *driven;           /* per coordinate */
    const char **colour;    /* per body or point, at its x coordinate */
    double L;               /* characteristic size of the motion */
    double px;              /* model units per pixel, estimated before
                               symbols are sized (the final scale is a
                               little smaller: symbols come out a little
                               smaller than asked) */
    const SvgForce *forces; /* arrows (SvgAnimOptions.forces); planar only */
    int nforces;
    double force_max;       /* the largest |f| over the kept frames (0: none drawn) */
    double force_scale;     /* model units per unit of force */
} Scene;

/* Starts a scene of frames t[k], q[k*nq + i] (checked by the caller):
   keeps at most max_frames of them, finds the driven coordinates and gives
   each body and point its colour. Nothing is drawn yet. */
void scene_init(Scene *sc, const Model *m, const double *t, const double *q, int n,
                const SvgTrace *traces, int ntraces, int max_frames);
void scene_free(Scene *sc);

/* Keeps at most max frames (2 at least) of the n given: all when n <= max,
   else about max indices including the first and the last. */
void scene_keep_frames(Scene *sc, int max);

/* The forces' scale: the largest over the kept frames SVG_FORCE_PX
   pixels long at sc->px; sc->force_max 0 when there is nothing to draw. */
void scene_scale_forces(Scene *sc);
/* Force i's arrow at kept frame f: from (*x0, *y0) to (*x1, *y1), world. */
void scene_force_arrow(const Scene *sc, int i, int f, double *x0, double *y0, double *x1,
                       double *y1);

/* Adds every shape and ground symbol, in drawing order; sc->L and sc->px
   must be set. */
void scene_build(Scene *sc);

/* The drawing of a joint kind with none of its own (a kind added to
   joints.def and not known here): with over_bodies false, a thin line
   between its two attachment points; with over_bodies true, a hollow
   square at its one attachment point. Nothing for a row statement. */
void scene_draw_generic(Scene *sc, const Joint *jt, bool over_bodies);

/* The spatial part of scene_build (scene_spatial.c): bodies, joints and
   ground points of a spatial mechanism, the links farthest first. */
void scene_build_spatial(Scene *sc);

/* Building blocks of a scene: a vertex (its index), a shape whose
   vertices are the ones added until scene_end_shape, a ground symbol. */
int scene_add_vtx(Scene *sc, Vtx v);
Shape *scene_add_shape(Scene *sc, ShapeKind kind, const char *cls);
void scene_end_shape(Scene *sc, Shape *s);
void scene_add_ground(Scene *sc, Ground g);
/* A distance joint: a line between its two attachments. */
void scene_draw_distance(Scene *sc, const Joint *jt);
/* A circle of radius r (pixels) at attachment a: a pin, weld or dot. */
void scene_add_pin(Scene *sc, Attach a, const char *cls, double r, const char *name);

/* The coordinates of frame k. */
const double *scene_frame_q(const Scene *sc, int k);
/* The world position of vertex v given coordinates qk (a spatial vertex:
   its x and y). */
void scene_vtx_world(const Vtx *v, const double *qk, double *x, double *y);
/* The world position in 3D (a planar vertex: z = 0). */
void scene_vtx_point(const Vtx *v, const double *qk, double P[3]);
/* Where the drawing shows vertex v: its world position, projected by the
   scene's view when it is spatial. */
void scene_vtx_xy(const Scene *sc, const Vtx *v, const double *qk, double *x, double *y);
/* The vertex at an attachment, and at a traced point. */
Vtx scene_vtx_at(Attach a);
Vtx scene_vtx_trace(const SvgTrace *tr);
/* The colour of the i-th trace (its path, dot and legend line). */
const char *scene_trace_colour(int i);

/* The coordinates (qd for a velocity driver) a driver's row depends on,
   into cols (room for m->nq); returns their count. */
int scene_driver_coords(const Model *m, const Joint *jt, int *cols);

#endif
