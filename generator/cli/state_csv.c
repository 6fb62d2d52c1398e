/* state_csv.c - one state (t and the coordinates) read back from a CSV as `run` writes it. */
#include "state_csv.h"

#include "../base/arena.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The next comma-separated field of *s (cut in place, surrounding quotes
   and blanks dropped); NULL at the end of the line. */
static char *next_field(char **s)
{
    if (!*s)
        return NULL;
    char *f = *s, *comma = strchr(f, ',');
    *s = comma ? comma + 1 : NULL;
    if (comma)
        *comma = '\0';
    while (*f == ' ' || *f == '"')
        f++;
    size_t n = strlen(f);
    while (n > 0 && (f[n - 1] == ' ' || f[n - 1] == '"' || f[n - 1] == '\r'))
        f[--n] = '\0';
    return f;
}

/* Column of every coordinate (col[i]) and of t, from the header line. */
static bool map_header(char *line, const Model *m, int *col, int *tcol, char *err, size_t errlen)
{
    *tcol = -1;
    for (int i = 0; i < m->nq; i++)
        col[i] = -1;
    char *f;
    for (int k = 0; (f = next_field(&line)) != NULL; k++) {
        if (strcmp(f, "t") == 0)
            *tcol = k;
        for (int i = 0; i < m->nq; i++)
            if (col[i] < 0 && strcmp(f, m->coord_names[i]) == 0)
                col[i] = k;
    }
    if (*tcol < 0) {
        snprintf(err, errlen, "no column named t in the header");
        return false;
    }
    for (int i = 0; i < m->nq; i++)
        if (col[i] < 0) {
            snprintf(err, errlen, "no column named %s in the header", m->coord_names[i]);
            return false;
        }
    return true;
}

/* The row's fields as numbers into v (ncols); false on a bad number. */
static bool parse_row(char *line, double *v, int ncols)
{
    char *f;
    int k = 0;
    while ((f = next_field(&line)) != NULL && k < ncols) {
        char *end;
        errno = 0;
        v[k++] = strtod(f, &end);
        if (end == f || *end != '\0')
            return false;
    }
    return k == ncols;
}

static char *read_all(const char *path)
{
    FILE *in = fopen(path, "rb");
    if (!in)
        return NULL;
    size_t cap = 1 << 16, n = 0;
    char *buf = xmalloc(cap);
    size_t got;
    while ((got = fread(buf + n, 1, cap - n - 1, in)) > 0) {
        n += got;
        if (cap - n < 2)
            buf = xrealloc(buf, cap *= 2, 1);
    }
    fclose(in);
    buf[n] = '\0';
    return buf;
}

bool state_csv_read(const char *path, const Model *m, double at, double *q, double *t,
                    char *err, size_t errlen)
{
    char *text = read_all(path);
    if (!text) {
        snprintf(err, errlen, "cannot read: %s", strerror(errno));
        return false;
    }
    int *col = xmalloc(((size_t)m->nq + 1) * sizeof *col), tcol;
    char *rest = text, *line = strsep(&rest, "\n");
    int ncols = 1;
    for (const char *c = line; *c; c++)
        ncols += *c == ',';
    double *v = xmalloc((size_t)ncols * sizeof *v);
    bool ok = map_header(line, m, col, &tcol, err, errlen);
    int rows = 0, lineno = 1;
    double best = INFINITY;
    while (ok && (line = strsep(&rest, "\n")) != NULL) {
        lineno++;
        if (line[0] == '\0' || line[0] == '\r')
            continue;
        if (!parse_row(line, v, ncols)) {
            snprintf(err, errlen, "line %d: expected %d numbers", lineno, ncols);
            ok = false;
            break;
        }
        rows++;
        double d = isnan(at) ? 0.0 : fabs(v[tcol] - at);
        if (d < best || (isnan(at) && rows == 1)) {
            best = d;
            *t = v[tcol];
            for (int i = 0; i < m->nq; i++)
                q[i] = v[col[i]];
        }
    }
    if (ok && rows == 0) {
        snprintf(err, errlen, "no data row");
        ok = false;
    } else if (ok && isnan(at) && rows > 1) {
        snprintf(err, errlen, "%d rows: give --at T to choose one", rows);
        ok = false;
    } else if (ok && !isnan(at) && best > 1e-9 * fmax(1.0, fabs(at))) {
        snprintf(err, errlen, "no row at t = %g (the nearest is t = %.17g)", at, *t);
        ok = false;
    }
    free(text), free(col), free(v);
    return ok;
}
