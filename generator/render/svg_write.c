/* svg_write.c - a scene to pixels, and pixels to an SVG document animated with SMIL.
 *
 * Each shape's vertices are mapped to pixels for every kept frame; the first
 * frame becomes the static attributes and, when the shape moves, an
 * <animate> element carries the values of all frames. Pixels, not a
 * flipping transform, carry y up: strokes and marks keep their pixel size
 * whatever the scale. Numbers are rounded to 0.1 px as printed, so a shape
 * "moves" only when the change is visible.
 */
#include "svg_write.h"

#include "../base/arena.h"
#include "svg_common.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
    HEADER_PX = 34,         /* title and time above the drawing */
    LINE_PX = 18,           /* one legend line below the drawing */
    MARGIN_PX = 26,         /* room for pivots, hatching and pins */
    PATH_POINTS_MAX = 2000, /* frames sampled for a trace's path */
    TIME_LABELS_MAX = 100,  /* distinct time texts */
};

/* ---- extent and pixel mapping ---- */

void svg_box_add(SvgBox *b, double x, double y)
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

/* The reference points of the bodies and points and the attachment points
   of the joints at frame k. */
static void extent_points(const Scene *sc, int k, SvgBox *b)
{
    const Model *m = sc->m;
    const double *qk = scene_frame_q(sc, k);
    double x, y;
    for (int i = 0; i < m->nbodies; i++) {
        const Body *bd = &m->bodies[i];
        if (bd->spatial) {
            Vtx v = {.q = bd->q, .fq = -1, .spatial = true};
            scene_vtx_xy(sc, &v, qk, &x, &y);
            svg_box_add(b, x, y);
        } else {
            svg_box_add(b, qk[bd->q], qk[bd->q + 1]);
        }
    }
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        const Attach *at[2] = {&jt->a, &jt->b};
        for (int a = 0; a < joint_info[jt->kind].attachments; a++) {
            Vtx v = scene_vtx_at(*at[a]);
            scene_vtx_xy(sc, &v, qk, &x, &y);
            svg_box_add(b, x, y);
        }
    }
}

/* Every vertex of every shape at frame k; a disk with its radius. */
static void extent_shapes(const Scene *sc, int k, SvgBox *b)
{
    const double *qk = scene_frame_q(sc, k);
    double x, y;
    for (int s = 0; s < sc->nsh; s++) {
        const Shape *sh = &sc->sh[s];
        for (int v = sh->v0; v < sh->v0 + sh->nv; v++) {
            scene_vtx_xy(sc, &sc->v[v], qk, &x, &y);
            double r = sh->r_world ? sh->r : 0;
            svg_box_add(b, x - r, y - r);
            svg_box_add(b, x + r, y + r);
        }
    }
}

SvgBox svg_scene_extent(const Scene *sc, bool shapes)
{
    SvgBox b = {INFINITY, INFINITY, -INFINITY, -INFINITY};
    double x, y;
    for (int f = 0; f < sc->nf; f++) {
        if (shapes)
            extent_shapes(sc, sc->frames[f], &b);
        else
            extent_points(sc, sc->frames[f], &b);
    }
    int count = sc->n < PATH_POINTS_MAX ? sc->n : PATH_POINTS_MAX;
    for (int i = 0; i < sc->ntraces; i++) {
        Vtx v = scene_vtx_trace(&sc->traces[i]);
        for (int j = 0; j < count; j++) {
            scene_vtx_xy(sc, &v, scene_frame_q(sc, path_frame(sc, j, count)), &x, &y);
            svg_box_add(&b, x, y);
        }
    }
    for (int i = 0; shapes && sc->force_max > 0 && i < sc->nforces; i++)
        for (int f = 0; f < sc->nf; f++) {
            double x0, y0, x1, y1;
            scene_force_arrow(sc, i, f, &x0, &y0, &x1, &y1);
            svg_box_add(&b, x1, y1);
        }
    for (int i = 0; shapes && i < sc->nground; i++) {
        const Ground *g = &sc->ground[i];
        svg_box_add(&b, g->x, g->y);
        if (g->kind == GROUND_LINE)
            svg_box_add(&b, g->x2, g->y2);
    }
    if (!(b.x0 <= b.x1))
        b = (SvgBox){-0.5, -0.5, 0.5, 0.5};
    return b;
}

SvgPixelMap svg_pixel_map(SvgBox b, const SvgAnimOptions *o, int footer_lines)
{
    SvgPixelMap pm;
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
    pm.s = fmin(o->width / w, o->height / h);
    pm.xmin = b.x0;
    pm.ymax = b.y0 + h;
    pm.oy = HEADER_PX + MARGIN_PX;
    pm.width = (int)ceil(w * pm.s + 2 * MARGIN_PX);
    if (pm.width < 320)
        pm.width = 320;
    pm.ox = 0.5 * (pm.width - w * pm.s);
    pm.height = (int)ceil(HEADER_PX + h * pm.s + 2 * MARGIN_PX + LINE_PX * footer_lines + 6);
    return pm;
}

static double px_x(const SvgPixelMap *pm, double x) { return pm->ox + pm->s * (x - pm->xmin); }
static double px_y(const SvgPixelMap *pm, double y) { return pm->oy + pm->s * (pm->ymax - y); }

/* ---- output ---- */

typedef struct Writer {
    FILE *out;
    const Scene *sc;
    const SvgPixelMap *pm;
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
static double *shape_pixels(const Scene *sc, const SvgPixelMap *pm, const Shape *sh)
{
    double *xy = xmalloc((size_t)sc->nf * (size_t)sh->nv * 2 * sizeof *xy);
    for (int f = 0; f < sc->nf; f++) {
        const double *qk = scene_frame_q(sc, sc->frames[f]);
        for (int v = 0; v < sh->nv; v++) {
            double x, y;
            scene_vtx_xy(sc, &sc->v[sh->v0 + v], qk, &x, &y);
            /* rounded as printed, so "moves" means a visible change */
            xy[((size_t)f * sh->nv + v) * 2] = round(px_x(pm, x) * 10) / 10;
            xy[((size_t)f * sh->nv + v) * 2 + 1] = round(px_y(pm, y) * 10) / 10;
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

/* The values of every kept frame: the points of a polyline or polygon, the
   translation of a circle or mark. */
static void put_animation(const Writer *w, const Shape *sh, const double *xy)
{
    FILE *out = w->out;
    size_t per = (size_t)sh->nv * 2;
    bool poly = sh->kind == SHAPE_POLYLINE || sh->kind == SHAPE_POLYGON;
    fputs(poly ? "\n <animate attributeName=\"points\" values=\""
               : "\n <animateTransform attributeName=\"transform\" type=\"translate\" values=\"", out);
    for (int f = 0; f < w->sc->nf; f++) {
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

/* One shape: its first frame as static attributes, its tooltip, and an
   animation when it moves. */
static void write_shape(const Writer *w, const Shape *sh)
{
    FILE *out = w->out;
    const Scene *sc = w->sc;
    double *xy = shape_pixels(sc, w->pm, sh);
    bool moves = shape_moves(sc, sh, xy);
    char buf[SVG_NUM_MAX];
    switch (sh->kind) {
    case SHAPE_POLYLINE:
    case SHAPE_POLYGON:
        fprintf(out, "<%s class=\"%s\" points=\"", sh->kind == SHAPE_POLYGON ? "polygon" : "polyline", sh->cls);
        put_points(out, xy, sh->nv);
        fputc('"', out);
        break;
    case SHAPE_CIRCLE: {
        double r = sh->r_world ? sh->r * w->pm->s : sh->r;
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
    if (moves)
        put_animation(w, sh, xy);
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

static void write_ground(FILE *out, const Scene *sc, const SvgPixelMap *pm)
{
    for (int i = 0; i < sc->nground; i++) {
        const Ground *g = &sc->ground[i];
        double x = px_x(pm, g->x), y = px_y(pm, g->y);
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
            double x2 = px_x(pm, g->x2), y2 = px_y(pm, g->y2);
            double len = hypot(x2 - x, y2 - y);
            if (!(len > 1))
                continue;
            /* hatch on the side below the line (screen y down) */
            double nx = -(y2 - y) / len, ny = (x2 - x) / len;
            if (ny < 0 || (ny == 0 && nx < 0)) {
                nx = -nx;
                ny = -ny;
            }
            double off = g->off * pm->s;
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

static void write_trace_paths(FILE *out, const Scene *sc, const SvgPixelMap *pm)
{
    int count = sc->n < PATH_POINTS_MAX ? sc->n : PATH_POINTS_MAX;
    for (int i = 0; i < sc->ntraces; i++) {
        const SvgTrace *tr = &sc->traces[i];
        Vtx v = scene_vtx_trace(tr);
        fprintf(out, "<polyline class=\"trace\" stroke=\"%s\" points=\"", scene_trace_colour(i));
        double px = NAN, py = NAN;
        int written = 0;
        for (int j = 0; j < count; j++) {
            double x, y;
            scene_vtx_xy(sc, &v, scene_frame_q(sc, path_frame(sc, j, count)), &x, &y);
            x = round(px_x(pm, x) * 10) / 10;
            y = round(px_y(pm, y) * 10) / 10;
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
        if (tr->label) {
            fputs("<title>", out);
            svg_put_escaped(out, tr->label);
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
    double x = w->pm->width - 10.0;
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
                w->pm->width, w->key_times[0] ? " keyTimes=\"0;1\"" : "", w->dur);
    fputs("</rect>\n</g>\n", out);
}

/* The forces' arrows (run --forces): one polyline each from its point,
   the arrowhead a marker, animated like a shape. */
static void write_forces(const Writer *w)
{
    const Scene *sc = w->sc;
    FILE *out = w->out;
    double *xy = xmalloc((size_t)sc->nf * 4 * sizeof *xy);
    for (int i = 0; sc->force_max > 0 && i < sc->nforces; i++) {
        for (int f = 0; f < sc->nf; f++) {
            double x0, y0, x1, y1;
            scene_force_arrow(sc, i, f, &x0, &y0, &x1, &y1);
            xy[4 * f] = round(px_x(w->pm, x0) * 10) / 10;
            xy[4 * f + 1] = round(px_y(w->pm, y0) * 10) / 10;
            xy[4 * f + 2] = round(px_x(w->pm, x1) * 10) / 10;
            xy[4 * f + 3] = round(px_y(w->pm, y1) * 10) / 10;
        }
        fputs("<polyline class=\"force\" marker-end=\"url(#force)\" points=\"", out);
        put_points(out, xy, 2);
        fputs("\"><title>reaction at ", out);
        svg_put_escaped(out, sc->forces[i].name ? sc->forces[i].name : "a joint");
        fputs("</title>", out);
        Shape sh = {.kind = SHAPE_POLYLINE, .nv = 2};
        if (shape_moves(sc, &sh, xy))
            put_animation(w, &sh, xy);
        fputs("</polyline>\n", out);
    }
    free(xy);
}

/* The legend line of the forces' scale: an arrow as long as the largest. */
static void put_force_line(FILE *out, const Scene *sc, const SvgPixelMap *pm, double y)
{
    char buf[SVG_NUM_MAX];
    double len = sc->force_max * sc->force_scale * pm->s;
    fprintf(out, "<g class=\"legend\"><polyline class=\"force\" marker-end=\"url(#force)\" "
                 "points=\"10,%.1f %.1f,%.1f\"/><text x=\"%.1f\" y=\"%.1f\">reaction forces on "
                 "the joints' second bodies: this arrow is %s (the largest)</text></g>\n",
            y - 4, 10 + len, y - 4, 20 + len, y, svg_fmt_sig(buf, sc->force_max, 4));
}

/* One legend line per driver, naming the coordinates its row depends on. */
static void put_driver_line(FILE *out, const Model *m, const Joint *jt, double y, int *cols)
{
    fprintf(out, "<g class=\"legend\"><rect x=\"10\" y=\"%.1f\" width=\"14\" height=\"4\" fill=\"%s\"/>"
                 "<text x=\"30\" y=\"%.1f\">driver ",
            y - 6, SCENE_DRIVE_COLOUR, y);
    svg_put_escaped(out, jt->name);
    fputs(":", out);
    bool velocity = m->rows[jt->first_row].velocity;
    int n = scene_driver_coords(m, jt, cols);
    for (int k = 0; k < n; k++) {
        fputs(k ? ", " : " ", out);
        if (velocity)
            fputs("der(", out);
        svg_put_escaped(out, m->coord_names[cols[k]]);
        if (velocity)
            fputs(")", out);
    }
    fputs("</text></g>\n", out);
}

/* One line per driver (the coordinates it drives) and per trace. */
static void write_legend(FILE *out, const Scene *sc, const SvgPixelMap *pm)
{
    const Model *m = sc->m;
    int nlines = 0;
    for (int j = 0; j < m->njoints; j++)
        nlines += m->joints[j].kind == JOINT_DRIVER;
    nlines += sc->ntraces + (sc->force_max > 0);
    int l = 0;
    int *cols = xmalloc(((size_t)m->nq + 1) * sizeof *cols);
    for (int j = 0; j < m->njoints; j++) {
        if (m->joints[j].kind == JOINT_DRIVER)
            put_driver_line(out, m, &m->joints[j], pm->height - 8 - LINE_PX * (nlines - 1 - l++), cols);
    }
    free(cols);
    for (int i = 0; i < sc->ntraces; i++) {
        const char *label = sc->traces[i].label;
        double y = pm->height - 8 - LINE_PX * (nlines - 1 - l++);
        fprintf(out, "<g class=\"legend\"><rect x=\"10\" y=\"%.1f\" width=\"14\" height=\"4\" fill=\"%s\"/>"
                     "<text x=\"30\" y=\"%.1f\">path of ",
                y - 6, scene_trace_colour(i), y);
        svg_put_escaped(out, label ? label : "a point");
        fputs("</text></g>\n", out);
    }
    if (sc->force_max > 0)
        put_force_line(out, sc, pm, pm->height - 8 - LINE_PX * (nlines - 1 - l++));
}

/* keyTimes from the times of the kept frames (kt, rounded as printed):
   "" when they are evenly spaced (SMIL's default), else the attribute.
   The caller frees the string. */
static char *make_key_times(const Scene *sc, double *kt)
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
    size_t cap = even ? 1 : (size_t)sc->nf * 8 + 16;
    char *s = xmalloc(cap), buf[SVG_NUM_MAX];
    s[0] = '\0';
    if (even)
        return s;
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
    ".drive{fill:none;stroke:" SCENE_DRIVE_COLOUR ";stroke-width:2}\n"
    ".bar{fill:#bbb}\n"
    "</style>\n";
/* run --forces only, so that other pictures keep every byte */
static const char force_style[] = "<style>.force{fill:none;stroke:#1f5fbf;stroke-width:2.5}</style>\n";

void svg_write_scene(FILE *out, const Scene *sc, const SvgPixelMap *pm, const char *title,
                     const SvgAnimOptions *o)
{
    Writer w = {out, sc, pm, NULL, {0}, NULL};
    w.kt = xmalloc((size_t)sc->nf * sizeof *w.kt);
    w.key_times = make_key_times(sc, w.kt);
    double t0 = sc->t[sc->frames[0]], t1 = sc->t[sc->frames[sc->nf - 1]];
    double dur = fmin(fmax(t1 - t0, o->min_duration), o->max_duration);
    svg_fmt_sig(w.dur, dur, 4);

    fprintf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                 "viewBox=\"0 0 %d %d\">\n<title>",
            pm->width, pm->height, pm->width, pm->height);
    svg_put_escaped(out, title);
    fputs("</title>\n<desc>Made by mechc: the mechanism at the first instant; SMIL animations play the run ", out);
    if (sc->m->spatial)
        fprintf(out, "(the %s view, orthographic, equal scales).</desc>\n", svg_view_names[sc->view]);
    else
        fputs("(y up, equal scales).</desc>\n", out);
    fputs(style_sheet, out);
    if (sc->force_max > 0)
        fputs(force_style, out);
    fputs("<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"5\" refY=\"5\" markerWidth=\"5\" "
          "markerHeight=\"5\" orient=\"auto\"><path d=\"M0,0 L10,5 L0,10 z\" fill=\"" SCENE_DRIVE_COLOUR
          "\"/></marker>", out);
    if (sc->force_max > 0)
        fputs("<marker id=\"force\" viewBox=\"0 0 10 10\" refX=\"9\" refY=\"5\" markerWidth=\"4\" "
              "markerHeight=\"4\" orient=\"auto\"><path d=\"M0,0 L10,5 L0,10 z\" fill=\"#1f5fbf\"/>"
              "</marker>", out);
    fputs("</defs>\n", out);
    fprintf(out, "<rect width=\"%d\" height=\"%d\" fill=\"#fff\"/>\n", pm->width, pm->height);
    fputs("<text class=\"title\" x=\"10\" y=\"22\">", out);
    svg_put_escaped(out, title);
    fputs("</text>\n", out);
    write_time(&w);
    write_ground(out, sc, pm);
    write_trace_paths(out, sc, pm);
    for (int s = 0; s < sc->nsh; s++)
        write_shape(&w, &sc->sh[s]);
    write_forces(&w);
    write_legend(out, sc, pm);
    fputs("</svg>\n", out);
    free(w.key_times);
    free(w.kt);
}
