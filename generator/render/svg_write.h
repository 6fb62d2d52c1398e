/* svg_write.h - a scene's extent, its world-to-pixel mapping, and the SMIL SVG document. */
#ifndef MECHC_SVG_WRITE_H
#define MECHC_SVG_WRITE_H

#include "scene.h"

#include <stdio.h>

typedef struct SvgBox { double x0, y0, x1, y1; } SvgBox;

/* World to pixels, y up: X = ox + s (x - xmin), Y = oy + s (ymax - y). */
typedef struct SvgPixelMap {
    double s, xmin, ymax, ox, oy;
    int width, height;      /* the whole picture in px */
} SvgPixelMap;

/* Grows b to hold (x, y); non-finite points are ignored. */
void svg_box_add(SvgBox *b, double x, double y);

/* The extent over the kept frames of what moves or is fixed: with shapes
   false, the bodies' and points' reference points, the joints' attachment
   points and the traces' paths; with shapes true, every shape's vertices
   (disks with their radius), the traces' paths and the ground symbols.
   Nothing at all: a unit square at the origin. */
SvgBox svg_scene_extent(const Scene *sc, bool shapes);

/* Fits box b into opt's drawing area at equal scales, with room for the
   header, margins and footer_lines legend lines below. */
SvgPixelMap svg_pixel_map(SvgBox b, const SvgAnimOptions *opt, int footer_lines);

/* Writes the whole document: header, time display, ground, trace paths,
   shapes (static first frame plus <animate> values when they move) and the
   legend. Stream errors are left for the caller to check. */
void svg_write_scene(FILE *out, const Scene *sc, const SvgPixelMap *pm, const char *title,
                     const SvgAnimOptions *opt);

#endif
