/* svg_plot.h - line charts of coordinates, velocities or accelerations against time, as SVG. */
#ifndef MECHC_SVG_PLOT_H
#define MECHC_SVG_PLOT_H

#include "../model/model.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* One curve: n values values[k * stride] (stride 0 means 1), k = 0 .. n-1.
   NaN and infinite values leave a gap. name is escaped on output. */
typedef struct SvgSeries {
    const char *name;
    const double *values;
    int stride;
} SvgSeries;

typedef struct SvgPlotOptions {
    int width, height;      /* the plot area in px; default 640 x 400 */
    const char *xlabel;     /* default "t" */
    const char *ylabel;     /* default none */
} SvgPlotOptions;

SvgPlotOptions svg_plot_default_options(void);

/* Writes an SVG line chart of the series against t[0..n-1] (finite,
   non-decreasing): axes, 1-2-5 ticks with labels, grid, legend. Curves with
   more points than the plot has pixels are reduced to each pixel column's
   first, lowest, highest and last value, so peaks survive. Returns false,
   writing nothing, on unusable input (errno = EINVAL) or when writing fails. */
bool svg_write_plot(FILE *out, const char *title, const double *t, int n,
                    const SvgSeries *series, int nseries);
bool svg_write_plot_opt(FILE *out, const char *title, const double *t, int n,
                        const SvgSeries *series, int nseries, const SvgPlotOptions *opt);

/* A quantity to plot: coordinate coord (nq + k: the model's output k),
   derivative order 0 (q), 1 (qd) or 2 (qdd); or (run --forces) the
   multiplier of row coord (SVG_PLOT_LAMBDA) or the effort of the driver
   whose row is coord (SVG_PLOT_EFFORT); or (run --sens) the sensitivity
   column coord (SVG_PLOT_SENS). */
typedef struct SvgPlotVar {
    int coord;
    int order;
} SvgPlotVar;

enum { SVG_PLOT_LAMBDA = 3, SVG_PLOT_EFFORT = 4, SVG_PLOT_SENS = 5 };

/* Parses a --plot-vars list: comma-separated NAME (a coordinate or an output), d(NAME)
   (its velocity) or dd(NAME) (its acceleration), blanks allowed around
   items. Fills out[0..max) and returns the count; on error returns -1 with
   a one-line reason in err (an unknown name is reported with every
   coordinate and output that exists: give err svg_plot_err_size(m) bytes plus the list's length). */
int svg_plot_resolve(const Model *m, const char *list, SvgPlotVar *out, int max,
                     char *err, size_t errlen);
/* Bytes that hold any reason svg_plot_resolve gives for model m, besides
   the names quoted from the list. */
size_t svg_plot_err_size(const Model *m);
/* The same, also taking lambda(ROW) (a row's name) and effort(DRIVER) (a
   driver's name) when forces is true. */
int svg_plot_resolve_forces(const Model *m, const char *list, bool forces, SvgPlotVar *out,
                            int max, char *err, size_t errlen);

/* The same, also taking (sens) run --sens's columns d(NAME)/d(P),
   d(d(NAME))/d(P) and d(dd(NAME))/d(P): SVG_PLOT_SENS, coord their
   column (sens.h's order). */
int svg_plot_resolve_columns(const Model *m, const char *list, bool forces, bool sens,
                             SvgPlotVar *out, int max, char *err, size_t errlen);

/* The name of coordinate coord, or of output coord - nq. */
const char *svg_plot_var_label(const Model *m, int coord);

/* The display name of a variable: "crank.phi", "d(crank.phi)", "dd(crank.phi)",
   "lambda(O.x)", "effort(D)". */
void svg_plot_var_name(const Model *m, SvgPlotVar v, char *buf, size_t len);

#endif
