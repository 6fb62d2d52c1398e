/* run_table.c - the state of a mechanism at one instant as a table people read (mechc run --steps 0).
 *
 * What a textbook problem asks for: every coordinate's position, velocity
 * and acceleration, the spatial bodies' angular velocities and
 * accelerations (global frame), then the outputs', in aligned columns;
 * angles also in degrees. Entries smaller than 1e-12 of their column's largest are
 * round-off of an exact zero and are shown as 0, so that a pin's fixed
 * coordinates read 0, not 1e-17.
 */
#include "run_table.h"

#include <math.h>
#include <string.h>

enum { COLUMN = 17 };

/* Largest magnitude among v[0..n) (0 when none). */
static double column_scale(const double *v, int n)
{
    double big = 0;
    for (int i = 0; i < n; i++)
        if (isfinite(v[i]) && fabs(v[i]) > big)
            big = fabs(v[i]);
    return big;
}

static void put_value(FILE *out, double v, double scale, int width, int digits)
{
    if (isnan(v)) {
        fprintf(out, "  %*s", width, "nan");
        return;
    }
    if (v == 0 || fabs(v) < 1e-12 * scale)
        v = 0;      /* and -0 too */
    fprintf(out, "  %*.*g", width, digits, v);
}

/* Whether coordinate i is a body's angle. */
static bool is_angle(const Model *m, int i)
{
    for (int b = 0; b < m->nbodies; b++)
        if (m->bodies[b].has_phi && m->bodies[b].q + 2 == i)
            return true;
    return false;
}

static int name_width(const Model *m)
{
    size_t w = 10;
    for (int i = 0; i < m->nq; i++)
        w = strlen(m->coord_names[i]) > w ? strlen(m->coord_names[i]) : w;
    for (int k = 0; k < m->nout; k++)
        w = strlen(m->outputs[k].name) > w ? strlen(m->outputs[k].name) : w;
    return (int)w;
}

/* One block: a heading, then a row per name with value, rate and rate of rate. */
static void put_block(FILE *out, const Model *m, const char *heading, const char *const *names,
                      int n, const double *const v[3], bool angles, int width, int digits)
{
    double scale[3];
    for (int k = 0; k < 3; k++)
        scale[k] = column_scale(v[k], n);
    int column = digits + 7 > COLUMN ? digits + 7 : COLUMN;   /* -1.2345e-123 */
    fprintf(out, "%-*s  %*s  %*s  %*s\n", width, heading, column, "position", column, "velocity",
            column, "acceleration");
    for (int i = 0; i < n; i++) {
        fprintf(out, "%-*s", width, names[i]);
        for (int k = 0; k < 3; k++)
            put_value(out, v[k][i], scale[k], column, digits);
        if (angles && is_angle(m, i))
            fprintf(out, "   (%.*g deg)", digits < 8 ? digits : 8, v[0][i] * 180 / M_PI);
        fputc('\n', out);
    }
}

/* omega and alpha of the spatial bodies (global frame): no position column. */
static void put_angular(FILE *out, const RunInstant *s, int width, int digits)
{
    double scale[2] = {column_scale(s->w, s->nw), column_scale(s->wd, s->nw)};
    int column = digits + 7 > COLUMN ? digits + 7 : COLUMN;
    fprintf(out, "%-*s  %*s  %*s  %*s\n", width, "angular", column, "", column, "velocity", column,
            "acceleration");
    for (int i = 0; i < s->nw; i++) {
        fprintf(out, "%-*s  %*s", width, s->wnames[i], column, "");
        put_value(out, s->w[i], scale[0], column, digits);
        put_value(out, s->wd[i], scale[1], column, digits);
        fputc('\n', out);
    }
}

void run_table_print(FILE *out, const Model *m, const RunInstant *s, int digits)
{
    digits = digits > 0 ? digits : 10;
    int width = name_width(m);
    fprintf(out, "%s at t = %.10g", m->name, s->t);
    int it = s->assembly_iterations;
    const char *its = it == 1 ? "iteration" : "iterations";
    if (s->constructed > 0)
        fprintf(out, " (%d of %d coordinates placed by construction, then %d Newton %s%s)",
                s->constructed, m->nq, it, its, s->assembled_robustly ? " from rough values" : "");
    else if (s->assembled_robustly)
        fprintf(out, " (assembled from rough initial values in %d %s)", it, its);
    fputs("\n\n", out);
    const double *const qv[3] = {s->q, s->qd, s->qdd};
    put_block(out, m, "coordinate", m->coord_names, m->nq, qv, true, width, digits);
    if (s->nw > 0) {
        fputc('\n', out);
        put_angular(out, s, width, digits);
    }
    if (m->nout > 0 && s->y) {
        const double *const yv[3] = {s->y, s->yd, s->ydd};
        fputc('\n', out);
        put_block(out, m, "output", s->ynames, m->nout, yv, false, width, digits);
    }
    fputs("\nunits as in the file; angles in rad (velocity rad/s, acceleration rad/s^2)\n", out);
}
