/* svg_plot.c - a line chart of time series as SVG: axes, nice ticks, grid and legend.
 *
 * The y range is the data's range widened to whole tick steps (1, 2 or 5
 * times a power of ten, about six intervals); the x range is exactly the
 * run's time span, ticks falling inside it. Curves are polylines in pixel
 * coordinates rounded to 0.1 px; a long run is thinned per pixel column to
 * the column's first, lowest, highest and last points (the standard
 * min/max decimation: the picture does not change, the file shrinks).
 */
#include "svg_plot.h"

#include "../base/arena.h"
#include "svg_common.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
    LEFT_PX = 76,       /* y tick labels and the y label */
    RIGHT_PX = 16,
    TOP_PX = 40,        /* the title */
    BOTTOM_PX = 52,     /* x tick labels and the x label */
    LEGEND_GAP_PX = 14,
    LEGEND_LINE_PX = 18,
};

SvgPlotOptions svg_plot_default_options(void)
{
    SvgPlotOptions o = {.width = 640, .height = 400, .xlabel = "t", .ylabel = NULL};
    return o;
}

typedef struct Axis {
    double lo, hi;      /* the mapped range */
    double step;        /* tick step */
    double first;       /* first tick >= lo */
} Axis;

static double value_at(const SvgSeries *s, int k)
{
    return s->values[(size_t)k * (size_t)(s->stride > 0 ? s->stride : 1)];
}

/* Ticks over [lo, hi]: widen to whole steps when `widen`. */
static Axis make_axis(double lo, double hi, bool widen)
{
    Axis a;
    if (!(hi > lo)) {
        double c = lo, d = fabs(c) > 0 ? 0.1 * fabs(c) : 1;
        lo = c - d;
        hi = c + d;
    }
    a.step = svg_nice_step(hi - lo, 6);
    if (widen) {
        lo = floor(lo / a.step + 1e-9) * a.step;
        hi = ceil(hi / a.step - 1e-9) * a.step;
    }
    a.lo = lo;
    a.hi = hi;
    a.first = ceil(lo / a.step - 1e-9) * a.step;
    return a;
}

/* A tick label: as many decimals as the step needs. */
static void tick_label(char *buf, double v, double step)
{
    if (fabs(v) < step * 1e-9)
        v = 0;
    if (step >= 1e-4 && fabs(v) < 1e7 && step < 1e7) {
        int decimals = (int)ceil(-log10(step) - 1e-9);
        if (decimals < 0)
            decimals = 0;
        snprintf(buf, SVG_NUM_MAX, "%.*f", decimals, v);
    } else {
        snprintf(buf, SVG_NUM_MAX, "%.3g", v);
    }
}

typedef struct Frame {
    double x0, y0, w, h;    /* plot area in px */
    Axis ax, ay;
} Frame;

static double map_x(const Frame *f, double t) { return f->x0 + f->w * (t - f->ax.lo) / (f->ax.hi - f->ax.lo); }
static double map_y(const Frame *f, double v) { return f->y0 + f->h * (f->ay.hi - v) / (f->ay.hi - f->ay.lo); }

static void put_num(FILE *out, double v)
{
    char buf[SVG_NUM_MAX];
    fputs(svg_fmt_fixed(buf, v, 1), out);
}

/* One point of a polyline, with its separator. */
static void put_point(FILE *out, int *count, double x, double y)
{
    if ((*count)++)
        fputc(' ', out);
    put_num(out, x);
    fputc(',', out);
    put_num(out, y);
}

/* The curve of one series, thinned per pixel column; gaps at non-finite values. */
static void write_series(FILE *out, const Frame *f, const double *t, int n, const SvgSeries *s,
                         const char *colour)
{
    int count = 0;
    bool open = false;
    /* a bucket: the points of one pixel column (indices of its first,
       lowest, highest and last value) */
    int col = INT32_MIN;
    int first = -1, lo = -1, hi = -1, last = -1;
    /* two passes: pick the kept indices (-1: a gap), then print them */
    int *keep = xmalloc(((size_t)n * 4 + 4) * sizeof *keep);
    int nkeep = 0;
    for (int k = 0; k <= n; k++) {
        double v = k < n ? value_at(s, k) : NAN;
        int c = k < n ? (int)floor(map_x(f, t[k])) : INT32_MAX;
        bool gap = k < n && !isfinite(v);
        if (k == n || gap || c != col) {
            if (first >= 0) {
                int a = lo < hi ? lo : hi, b = lo < hi ? hi : lo;
                int idx[4] = {first, a, b, last};
                for (int i = 0; i < 4; i++)
                    if (nkeep == 0 || keep[nkeep - 1] != idx[i])
                        keep[nkeep++] = idx[i];
            }
            first = lo = hi = last = -1;
            col = c;
            if (gap) {
                if (nkeep > 0 && keep[nkeep - 1] != -1)
                    keep[nkeep++] = -1;     /* a break in the curve */
                continue;
            }
        }
        if (k == n)
            break;
        if (first < 0)
            first = lo = hi = k;
        if (v < value_at(s, lo))
            lo = k;
        if (v > value_at(s, hi))
            hi = k;
        last = k;
    }
    for (int i = 0; i < nkeep; i++) {
        if (keep[i] < 0) {
            if (open)
                fputs("\"/>\n", out);
            open = false;
            continue;
        }
        if (!open) {
            fprintf(out, "<polyline class=\"series\" style=\"stroke:%s\" points=\"", colour);
            count = 0;
            open = true;
        }
        put_point(out, &count, map_x(f, t[keep[i]]), map_y(f, value_at(s, keep[i])));
        /* a lone point: repeat it so the line cap shows a dot */
        if (count == 1 && (i + 1 == nkeep || keep[i + 1] < 0))
            put_point(out, &count, map_x(f, t[keep[i]]), map_y(f, value_at(s, keep[i])));
    }
    if (open)
        fputs("\"/>\n", out);
    free(keep);
}

static const char style_sheet[] =
    "<style>\n"
    "text{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;font-size:12px;fill:#222}\n"
    ".title{font-size:15px;font-weight:bold}\n"
    ".label{font-size:13px}\n"
    ".grid{stroke:#e6e6e6;stroke-width:1}\n"
    ".zero{stroke:#aaa;stroke-width:1}\n"
    ".axis{fill:none;stroke:#333;stroke-width:1.2}\n"
    ".tick{stroke:#333;stroke-width:1}\n"
    ".series{fill:none;stroke-width:1.8;stroke-linejoin:round;stroke-linecap:round}\n"
    ".legend line{stroke-width:3}\n"
    "</style>\n";

static bool valid_plot_input(FILE *out, const double *t, int n, const SvgSeries *series,
                             int nseries, const SvgPlotOptions *o)
{
    bool ok = out && t && n >= 1 && nseries >= 0 && (nseries == 0 || series) && o->width >= 100 &&
              o->height >= 60;
    for (int k = 0; ok && k < n; k++)
        ok = isfinite(t[k]) && (k == 0 || t[k] >= t[k - 1]);
    for (int i = 0; ok && i < nseries; i++)
        ok = series[i].values != NULL && series[i].stride >= 0;
    return ok;
}

/* The plot area and its axes: x over the run's time span, y over the
   finite values of all series, widened to whole ticks. */
static Frame plot_frame(const double *t, int n, const SvgSeries *series, int nseries,
                        const SvgPlotOptions *o)
{
    double vlo = INFINITY, vhi = -INFINITY;
    for (int i = 0; i < nseries; i++)
        for (int k = 0; k < n; k++) {
            double v = value_at(&series[i], k);
            if (isfinite(v)) {
                vlo = fmin(vlo, v);
                vhi = fmax(vhi, v);
            }
        }
    if (!(vlo <= vhi))
        vlo = vhi = 0;
    Frame f;
    f.ax = make_axis(t[0], t[n - 1], false);
    f.ay = make_axis(vlo, vhi, true);
    f.x0 = LEFT_PX;
    f.y0 = TOP_PX;
    f.w = o->width;
    f.h = o->height;
    return f;
}

/* The whole picture's size: the plot area, its margins and the legend to
   its right (about 7 px per character of the longest name). */
static void plot_size(const SvgSeries *series, int nseries, const SvgPlotOptions *o,
                      int *width, int *height)
{
    size_t longest = 0;
    for (int i = 0; i < nseries; i++)
        if (series[i].name && strlen(series[i].name) > longest)
            longest = strlen(series[i].name);
    if (longest > 60)
        longest = 60;
    int legend_w = nseries > 0 ? (int)(36 + 7.2 * (double)longest) : 0;
    *width = (int)(LEFT_PX + o->width + RIGHT_PX + (nseries > 0 ? LEGEND_GAP_PX + legend_w : 0));
    *height = TOP_PX + o->height + BOTTOM_PX;
    int legend_h = TOP_PX + 8 + LEGEND_LINE_PX * nseries;
    if (legend_h > *height)
        *height = legend_h;
}

static void write_head(FILE *out, const char *title, const Frame *f, int width, int height)
{
    fprintf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n"
                 "<title>",
            width, height, width, height);
    svg_put_escaped(out, title ? title : "");
    fputs("</title>\n", out);
    fputs(style_sheet, out);
    fprintf(out, "<rect width=\"%d\" height=\"%d\" fill=\"#fff\"/>\n", width, height);
    fprintf(out, "<text class=\"title\" x=\"%.1f\" y=\"24\" text-anchor=\"middle\">", f->x0 + 0.5 * f->w);
    svg_put_escaped(out, title ? title : "");
    fputs("</text>\n", out);
}

/* Grid lines, ticks and tick labels of both axes; the zero line stands out. */
static void write_ticks(FILE *out, const Frame *f)
{
    char buf[SVG_NUM_MAX];
    fputs("<g class=\"xticks\">\n", out);
    for (int i = 0; i < 100; i++) {
        double v = f->ax.first + i * f->ax.step;
        if (v > f->ax.hi + 1e-9 * f->ax.step)
            break;
        double x = map_x(f, v);
        fprintf(out, "<line class=\"grid\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", x, f->y0, x, f->y0 + f->h);
        fprintf(out, "<line class=\"tick\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", x, f->y0 + f->h, x,
                f->y0 + f->h + 5);
        tick_label(buf, v, f->ax.step);
        fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", x, f->y0 + f->h + 19, buf);
    }
    fputs("</g>\n<g class=\"yticks\">\n", out);
    for (int i = 0; i < 100; i++) {
        double v = f->ay.first + i * f->ay.step;
        if (v > f->ay.hi + 1e-9 * f->ay.step)
            break;
        double y = map_y(f, v);
        bool zero = fabs(v) < 1e-9 * f->ay.step;
        fprintf(out, "<line class=\"%s\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", zero ? "zero" : "grid",
                f->x0, y, f->x0 + f->w, y);
        fprintf(out, "<line class=\"tick\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", f->x0 - 5, y, f->x0, y);
        tick_label(buf, v, f->ay.step);
        fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n", f->x0 - 8, y + 4, buf);
    }
    fputs("</g>\n", out);
}

/* The frame around the plot area and the axis labels. */
static void write_axes(FILE *out, const Frame *f, const SvgPlotOptions *o)
{
    fprintf(out, "<rect class=\"axis\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/>\n", f->x0, f->y0, f->w,
            f->h);
    if (o->xlabel) {
        fprintf(out, "<text class=\"label\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">", f->x0 + 0.5 * f->w,
                f->y0 + f->h + 42);
        svg_put_escaped(out, o->xlabel);
        fputs("</text>\n", out);
    }
    if (o->ylabel) {
        double x = 18, y = f->y0 + 0.5 * f->h;
        fprintf(out, "<text class=\"label\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" "
                     "transform=\"rotate(-90 %.1f %.1f)\">", x, y, x, y);
        svg_put_escaped(out, o->ylabel);
        fputs("</text>\n", out);
    }
}

static void write_legend(FILE *out, const Frame *f, const SvgSeries *series, int nseries)
{
    double lx = f->x0 + f->w + LEGEND_GAP_PX;
    fputs("<g class=\"legend\">\n", out);
    for (int i = 0; i < nseries; i++) {
        double y = f->y0 + 8 + LEGEND_LINE_PX * i;
        fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" style=\"stroke:%s\"/>", lx, y,
                lx + 22, y, svg_palette[i % SVG_PALETTE_SIZE]);
        fprintf(out, "<text x=\"%.1f\" y=\"%.1f\">", lx + 28, y + 4);
        svg_put_escaped(out, series[i].name ? series[i].name : "");
        fputs("</text>\n", out);
    }
    fputs("</g>\n", out);
}

bool svg_write_plot_opt(FILE *out, const char *title, const double *t, int n,
                        const SvgSeries *series, int nseries, const SvgPlotOptions *opt)
{
    SvgPlotOptions o = opt ? *opt : svg_plot_default_options();
    if (!valid_plot_input(out, t, n, series, nseries, &o)) {
        errno = EINVAL;
        return false;
    }
    Frame f = plot_frame(t, n, series, nseries, &o);
    int width, height;
    plot_size(series, nseries, &o, &width, &height);

    clearerr(out);
    write_head(out, title, &f, width, height);
    write_ticks(out, &f);
    write_axes(out, &f, &o);
    /* curves, clipped to the plot area */
    fprintf(out, "<clipPath id=\"area\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/></clipPath>\n",
            f.x0 - 2, f.y0 - 2, f.w + 4, f.h + 4);
    fputs("<g clip-path=\"url(#area)\">\n", out);
    for (int i = 0; i < nseries; i++)
        write_series(out, &f, t, n, &series[i], svg_palette[i % SVG_PALETTE_SIZE]);
    fputs("</g>\n", out);
    if (nseries > 0)
        write_legend(out, &f, series, nseries);
    fputs("</svg>\n", out);
    return fflush(out) == 0 && !ferror(out);
}

bool svg_write_plot(FILE *out, const char *title, const double *t, int n,
                    const SvgSeries *series, int nseries)
{
    return svg_write_plot_opt(out, title, t, n, series, nseries, NULL);
}

/* ---- --plot-vars NAME,d(NAME),dd(NAME) ---- */

/* A coordinate's index, or nq + k for the model's output k; -1 when none. */
static int find_coord(const Model *m, const char *name, size_t len)
{
    for (int i = 0; i < m->nq + m->nout; i++) {
        const char *have = svg_plot_var_label(m, i);
        if (strlen(have) == len && strncmp(have, name, len) == 0)
            return i;
    }
    return -1;
}

size_t svg_plot_err_size(const Model *m)
{
    size_t size = 256;
    for (int i = 0; i < m->nq + m->nout; i++)
        size += strlen(svg_plot_var_label(m, i)) + 2;
    return size;
}

/* Explains an unknown name: a body or point named without a coordinate, or
   every coordinate and output there is, counted. */
static void unknown_name(const Model *m, const char *name, size_t len, char *err, size_t errlen)
{
    int nv = m->nq + m->nout;
    const char *what = m->nout ? "coordinate or output" : "coordinate";
    size_t used = 0;
    int n = snprintf(err, errlen, "--plot-vars: unknown %s '%.*s'", what, (int)len, name);
    used = n > 0 ? (size_t)n : 0;
    int members = 0;
    for (int i = 0; i < nv; i++) {
        const char *c = svg_plot_var_label(m, i);
        if (strncmp(c, name, len) == 0 && c[len] == '.') {
            n = snprintf(err + used, used < errlen ? errlen - used : 0, "%s%s", members++ ? ", " : "; did you mean ", c);
            used += n > 0 ? (size_t)n : 0;
        }
    }
    if (members > 0)
        return;
    if (nv == 1)
        n = snprintf(err + used, used < errlen ? errlen - used : 0, "; the only coordinate is ");
    else if (m->nout)
        n = snprintf(err + used, used < errlen ? errlen - used : 0,
                     "; the %d coordinates and %d output%s are ", m->nq, m->nout,
                     m->nout == 1 ? "" : "s");
    else
        n = snprintf(err + used, used < errlen ? errlen - used : 0, "; the %d coordinates are ", nv);
    used += n > 0 ? (size_t)n : 0;
    for (int i = 0; i < nv && used + 1 < errlen; i++) {
        n = snprintf(err + used, errlen - used, "%s%s", i ? ", " : "", svg_plot_var_label(m, i));
        used += n > 0 ? (size_t)n : 0;
    }
}

/* The row named [a, b) (wanting a driver when driver), or -1. */
static int find_row(const Model *m, const char *a, size_t len, bool driver)
{
    for (int i = 0; i < m->nr; i++)
        if (strlen(m->rows[i].name) == len && strncmp(m->rows[i].name, a, len) == 0
            && (!driver || m->rows[i].kind == JOINT_DRIVER))
            return i;
    return -1;
}

/* [a, b) without the blanks at either end. */
static void trim(const char **a, const char **b)
{
    while (*a < *b && (**a == ' ' || **a == '\t'))
        (*a)++;
    while (*b > *a && ((*b)[-1] == ' ' || (*b)[-1] == '\t'))
        (*b)--;
}

/* The design parameter named [a, b), or -1. */
static int find_design(const Model *m, const char *a, size_t len)
{
    for (int j = 0; j < m->np; j++)
        if (strlen(m->design_names[j]) == len && strncmp(m->design_names[j], a, len) == 0)
            return j;
    return -1;
}

/* [a, b) as a run --sens column d(X)/d(P), X = NAME, d(NAME) or dd(NAME):
   its column, or -1 when it is not one. */
static int find_sens(const Model *m, const char *a, const char *b)
{
    const char *sep = NULL;
    for (const char *s = a; s + 4 <= b; s++)
        if (strncmp(s, ")/d(", 4) == 0)
            sep = s;
    if (!sep || b - a < 9 || strncmp(a, "d(", 2) != 0 || b[-1] != ')')
        return -1;
    int j = find_design(m, sep + 4, (size_t)(b - 1 - (sep + 4)));
    const char *x = a + 2, *xe = sep;
    int level = 0;
    if (xe - x > 3 && xe[-1] == ')' && (strncmp(x, "d(", 2) == 0 || strncmp(x, "dd(", 3) == 0)) {
        level = x[1] == 'd' ? 2 : 1;
        x += level + 1;
        xe--;
    }
    int v = find_coord(m, x, (size_t)(xe - x));
    if (j < 0 || v < 0)
        return -1;
    return (level * (m->nq + m->nout) + v) * m->np + j;
}

/* One item [a, b) of a --plot-vars list into *v; false with the reason. */
static bool parse_item(const Model *m, const char *a, const char *b, bool forces, bool sens,
                       SvgPlotVar *v, char *err, size_t errlen)
{
    int column = sens ? find_sens(m, a, b) : -1;
    if (column >= 0) {
        *v = (SvgPlotVar){column, SVG_PLOT_SENS};
        return true;
    }
    for (const char *s = a; s + 4 <= b; s++)
        if (strncmp(s, ")/d(", 4) == 0) {    /* a sensitivity that cannot be */
            snprintf(err, errlen, "--plot-vars: '%.*s' %s", (int)(b - a), a,
                     sens ? "names no coordinate or output and design parameter of the file"
                          : "is a sensitivity: it needs --sens");
            return false;
        }
    static const char *const prefix[] = {"", "d(", "dd(", "lambda(", "effort("};
    int order = 0;
    for (int k = 1; k <= SVG_PLOT_EFFORT; k++) {
        size_t n = strlen(prefix[k]);
        if ((size_t)(b - a) > n && strncmp(a, prefix[k], n) == 0 && (k < 3 || forces))
            order = k;
    }
    if (order > 0) {
        if (b[-1] != ')') {
            snprintf(err, errlen, "--plot-vars: missing ')' in '%.*s'", (int)(b - a), a);
            return false;
        }
        a += strlen(prefix[order]);
        b--;
        trim(&a, &b);
    }
    int c = order >= SVG_PLOT_LAMBDA ? find_row(m, a, (size_t)(b - a), order == SVG_PLOT_EFFORT)
                                     : find_coord(m, a, (size_t)(b - a));
    if (c < 0 && order >= SVG_PLOT_LAMBDA) {
        snprintf(err, errlen, "--plot-vars: unknown %s '%.*s'",
                 order == SVG_PLOT_EFFORT ? "driver" : "row", (int)(b - a), a);
        return false;
    }
    if (c < 0) {
        unknown_name(m, a, (size_t)(b - a), err, errlen);
        return false;
    }
    *v = (SvgPlotVar){c, order};
    return true;
}

int svg_plot_resolve_forces(const Model *m, const char *list, bool forces, SvgPlotVar *out,
                            int max, char *err, size_t errlen)
{
    return svg_plot_resolve_columns(m, list, forces, false, out, max, err, errlen);
}

int svg_plot_resolve_columns(const Model *m, const char *list, bool forces, bool sens,
                             SvgPlotVar *out, int max, char *err, size_t errlen)
{
    if (!list) {
        snprintf(err, errlen, "--plot-vars: no names given");
        return -1;
    }
    int count = 0;
    const char *p = list;
    for (;;) {
        const char *end = strchr(p, ',');
        if (!end)
            end = p + strlen(p);
        const char *a = p, *b = end;
        trim(&a, &b);
        if (a == b) {
            snprintf(err, errlen, "--plot-vars '%s': empty name (expected NAME, d(NAME) or dd(NAME), "
                                  "comma-separated)", list);
            return -1;
        }
        SvgPlotVar v;
        if (!parse_item(m, a, b, forces, sens, &v, err, errlen))
            return -1;
        if (count >= max) {
            snprintf(err, errlen, "--plot-vars: more than %d names", max);
            return -1;
        }
        out[count++] = v;
        if (*end == '\0')
            break;
        p = end + 1;
    }
    return count;
}

int svg_plot_resolve(const Model *m, const char *list, SvgPlotVar *out, int max, char *err, size_t errlen)
{
    return svg_plot_resolve_forces(m, list, false, out, max, err, errlen);
}

const char *svg_plot_var_label(const Model *m, int coord)
{
    if (coord >= 0 && coord < m->nq)
        return m->coord_names[coord];
    if (coord >= m->nq && coord < m->nq + m->nout)
        return m->outputs[coord - m->nq].name;
    return "?";
}

void svg_plot_var_name(const Model *m, SvgPlotVar v, char *buf, size_t len)
{
    if (v.order == SVG_PLOT_SENS && m->np > 0) {
        int per = (m->nq + m->nout) * m->np, level = v.coord / per;
        SvgPlotVar x = {v.coord % per / m->np, level};
        char inner[160];
        svg_plot_var_name(m, x, inner, sizeof inner);
        snprintf(buf, len, "d(%s)/d(%s)", inner, m->design_names[v.coord % m->np]);
        return;
    }
    if (v.order >= SVG_PLOT_LAMBDA) {
        snprintf(buf, len, "%s(%s)", v.order == SVG_PLOT_LAMBDA ? "lambda" : "effort",
                 v.coord >= 0 && v.coord < m->nr ? m->rows[v.coord].name : "?");
        return;
    }
    const char *name = svg_plot_var_label(m, v.coord);
    if (v.order == 1)
        snprintf(buf, len, "d(%s)", name);
    else if (v.order == 2)
        snprintf(buf, len, "dd(%s)", name);
    else
        snprintf(buf, len, "%s", name);
}
