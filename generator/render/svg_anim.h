/* svg_anim.h - an animated SVG (SMIL, no script) of a mechanism over a run. */
#ifndef MECHC_SVG_ANIM_H
#define MECHC_SVG_ANIM_H

#include "../model/model.h"
#include "view.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* A point whose path is drawn: P = r + A(phi) s of a body (has_phi), or a
   particle (has_phi false, sx = sy = 0). q is the index of the x coordinate.
   In a spatial mechanism (spatial true) P = r + A(p) s, s = (sx, sy, sz),
   and has_phi says the point turns with a body (Euler parameters at q + 3). */
typedef struct SvgTrace {
    int q;
    bool has_phi;
    double sx, sy;
    const char *label;      /* legend text (escaped on output); NULL: none */
    bool spatial;
    double sz;
} SvgTrace;

/* A force drawn as an arrow (run --forces: a joint's reaction on its
   second body): applied at attachment `at` (a planar mechanism's), global
   components f[k*stride], f[k*stride + 1] at frame k of the run. */
typedef struct SvgForce {
    Attach at;
    const double *f;
    int stride;
    const char *name;       /* tooltip */
} SvgForce;

/* Tunables with their defaults (svg_anim_default_options). */
typedef struct SvgAnimOptions {
    int max_frames;         /* frames kept after subsampling; default 200 */
    double min_duration;    /* seconds of playback at least (a run shorter
                               than this is slowed down); default 2 */
    double max_duration;    /* seconds of playback at most (a longer run is
                               sped up); default 60 */
    int width, height;      /* largest drawing area in px; default 760 x 520 */
    long max_bytes;         /* about the largest file: a big mechanism keeps
                               fewer frames (10 at least); default 4000000 */
    SvgView view;           /* a spatial mechanism's projection (view.h);
                               default iso; planar ones ignore it */
    /* forces drawn as arrows from their points, all to one scale: the
       largest over the run SVG_FORCE_PX pixels long, with a legend line
       giving the scale; planar only; default none */
    const SvgForce *forces;
    int nforces;
} SvgAnimOptions;

#define SVG_FORCE_PX 60

SvgAnimOptions svg_anim_default_options(void);

/* Writes the animation of nframes frames: t[k] (non-decreasing, finite) and
   q[k*nq + i] (the model's coordinates). The static attributes show the
   first frame, so viewers that do not animate show the start of the run;
   SMIL <animate> elements play the run in a loop. Frames are subsampled to
   at most 200, fewer for big mechanisms (the file stays under about 4 MB). traces may be NULL when ntraces is 0; title may be NULL (the
   mechanism name is used). Returns false, writing nothing, when the input is
   unusable (no frame, decreasing time, a non-finite coordinate; errno =
   EINVAL) or when writing fails (errno from stdio). */
bool svg_write_animation(FILE *out, const Model *m, const double *t, const double *q,
                         int nframes, const SvgTrace *traces, int ntraces, const char *title);
/* The same with options (NULL: defaults). */
bool svg_write_animation_opt(FILE *out, const Model *m, const double *t, const double *q,
                             int nframes, const SvgTrace *traces, int ntraces,
                             const char *title, const SvgAnimOptions *opt);

/* Parses a --trace argument: `BODY(sx, sy)` (a point fixed to the body, in
   its local frame; `BODY(sx, sy, sz)` in a spatial mechanism), `BODY` (its
   reference point) or `POINT` (a particle);
   sx and sy are decimal numbers, signed or not (`-0.15`, `2e-3`; no
   expressions or params). Blanks are allowed between the parts. On success
   fills *out (label = text, so text must outlive the trace) and returns
   true; otherwise writes a one-line reason starting "--trace 'TEXT': " into
   err (errlen bytes) and returns false. */
bool svg_parse_trace(const Model *m, const char *text, SvgTrace *out, char *err, size_t errlen);

#endif
