/* view.h - the orthographic views of a spatial mechanism: a 3D point to the drawing's 2D coordinates. */
#ifndef MECHC_VIEW_H
#define MECHC_VIEW_H

/* Each view is a right-handed frame (right, up, toward the viewer); the
   drawing shows right and up, toward the viewer is the depth.
     front  x right, z up (the viewer on the -y side, looking along +y)
     top    x right, y up (the viewer above, looking along -z)
     side   y right, z up (the viewer on the +x side, looking along -x)
     iso    the isometric view from the corner those three look from: the
            viewer along (1, -1, 1); right = (1, 1, 0)/sqrt 2, up =
            (-1, 1, 2)/sqrt 6: x points 30 degrees below the horizontal to
            the right, y 30 degrees above it to the right, z straight up. */
typedef enum SvgView { SVG_VIEW_FRONT, SVG_VIEW_TOP, SVG_VIEW_SIDE, SVG_VIEW_ISO } SvgView;

/* "front", "top", "side", "iso", NULL: indexed by SvgView (a CLI choice list). */
extern const char *const svg_view_names[];

/* The drawing coordinates (x right, y up, model units) of the point P. */
void svg_view_project(SvgView view, const double P[3], double *x, double *y);

/* How near P is to the viewer along the view's direction (larger: nearer). */
double svg_view_depth(SvgView view, const double P[3]);

#endif
