/* view.c - orthographic projection of a spatial mechanism onto the drawing: one 3x3 frame per view. */
#include "view.h"

#include <stddef.h>

const char *const svg_view_names[] = {"front", "top", "side", "iso", NULL};

#define R2 0.70710678118654752440   /* 1/sqrt 2 */
#define R3 0.57735026918962576451   /* 1/sqrt 3 */
#define R6 0.40824829046386301637   /* 1/sqrt 6 */

/* Rows: right, up, toward the viewer (right x up), in world coordinates. */
static const double frames[4][3][3] = {
    [SVG_VIEW_FRONT] = {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    [SVG_VIEW_TOP] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    [SVG_VIEW_SIDE] = {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
    [SVG_VIEW_ISO] = {{R2, R2, 0}, {-R6, R6, 2 * R6}, {R3, -R3, R3}},
};

static double dot_row(SvgView view, int row, const double P[3])
{
    const double *f = frames[view][row];
    return f[0] * P[0] + f[1] * P[1] + f[2] * P[2];
}

void svg_view_project(SvgView view, const double P[3], double *x, double *y)
{
    *x = dot_row(view, 0, P);
    *y = dot_row(view, 1, P);
}

double svg_view_depth(SvgView view, const double P[3]) { return dot_row(view, 2, P); }
