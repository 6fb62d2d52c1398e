/* state_csv.c - one state (t and the coordinates) read back from a CSV as `run` writes it. */
#include "state_csv.h"

#include "../base/arena.h"
#include "../base/limits.h"

/* A row is at time `at` when their times differ by at most this times
   max(1, |at|) (a relative tolerance on seconds): it absorbs the rounding
   between a time run computed (t0 + k h) and the decimal one typed. */
#define STATE_CSV_T_MATCH 1e-9

#include <limits.h>
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

/* Column of every coordinate (col[i]) and of t, from the header line
   (line starts at offset 0 of the file). */
static bool map_header(char *line, const Model *m, int *col, int *tcol, Diag *diag)
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
        diag_error(diag, (SrcPos){0}, "no column named t in the header");
        return false;
    }
    for (int i = 0; i < m->nq; i++)
        if (col[i] < 0) {
            diag_error(diag, (SrcPos){0}, "no column named %s in the header",
                       m->coord_names[i]);
            return false;
        }
    return true;
}

/* The row's fields as numbers into v (ncols), line at byte offset `offset`
   of the file; a field used (used[k]) must be finite. false with the
   error, at its field, in diag. */
static bool parse_row(char *line, int offset, double *v, int ncols, const bool *used, Diag *diag)
{
    char *start = line, *f;
    int k = 0, end_col = (int)strlen(line);     /* before next_field cuts it */
    while ((f = next_field(&line)) != NULL) {
        SrcPos pos = {offset + (int)(f - start)};
        if (k == ncols) {
            diag_error(diag, pos, "%d fields where the header has %d", k + 1, ncols);
            return false;
        }
        char *end;
        v[k] = strtod(f, &end);
        if (end == f || *end != '\0') {
            diag_error(diag, pos, "field %d ('%s') is not a number", k + 1, f);
            return false;
        }
        if (used[k] && !isfinite(v[k])) {
            diag_error(diag, pos, "field %d ('%s') is not a finite number", k + 1, f);
            return false;
        }
        k++;
    }
    if (k < ncols) {
        diag_error(diag, (SrcPos){offset + end_col},
                   "%d fields where the header has %d", k, ncols);
        return false;
    }
    return true;
}

/* Which fields are read: t and the coordinates. */
static bool *used_fields(const int *col, int nq, int tcol, int ncols)
{
    bool *used = xmalloc((size_t)ncols * sizeof *used);
    for (int k = 0; k < ncols; k++)
        used[k] = k == tcol;
    for (int i = 0; i < nq; i++)
        used[col[i]] = true;
    return used;
}

/* The data rows: the one nearest `at` (the first if at is NaN) into q and
   *t, their count in *rows, the distance of the chosen one in *best. */
static bool scan_rows(char *rest, const char *work, const Model *m, const int *col, int tcol,
                      int ncols, double at, double *q, double *t, int *rows, double *best,
                      Diag *diag)
{
    double *v = xmalloc((size_t)ncols * sizeof *v);
    bool *used = used_fields(col, m->nq, tcol, ncols), ok = true;
    char *line;
    *rows = 0;
    *best = INFINITY;
    while ((line = strsep(&rest, "\n")) != NULL) {
        if (line[0] == '\0' || line[0] == '\r')
            continue;
        if (!parse_row(line, (int)(line - work), v, ncols, used, diag)) {
            ok = false;
            break;
        }
        ++*rows;
        double d = isnan(at) ? 0.0 : fabs(v[tcol] - at);
        if (d < *best || (isnan(at) && *rows == 1)) {
            *best = d;
            *t = v[tcol];
            for (int i = 0; i < m->nq; i++)
                q[i] = v[col[i]];
        }
    }
    free(v), free(used);
    return ok;
}

bool state_csv_read(const char *path, const Model *m, double at, double *q, double *t,
                    Diag *diag)
{
    /* read as a .mech file is (model_read_file): a regular file or stdin
       ('-'), never a named pipe with no writer, which would block; any
       size an int holds */
    MechLimits limits = mech_default_limits();
    limits.max_file_bytes = INT_MAX - 1;
    int len = 0;
    diag_init(diag, path, NULL, 0);
    char *text = model_read_data_file(path, &limits, &len, diag);
    if (!text)
        return false;
    /* work is cut in place by strsep and next_field; text stays whole
       for the line echoed under an error */
    diag_init(diag, path, text, len);
    char *work = xmalloc((size_t)len + 1);
    memcpy(work, text, (size_t)len + 1);
    int *col = xmalloc(((size_t)m->nq + 1) * sizeof *col), tcol, rows = 0;
    char *rest = work, *line = strsep(&rest, "\n");
    int ncols = 1;
    for (const char *c = line; *c; c++)
        ncols += *c == ',';
    double best = INFINITY;
    bool ok = map_header(line, m, col, &tcol, diag)
              && scan_rows(rest, work, m, col, tcol, ncols, at, q, t, &rows, &best, diag);
    if (ok && rows == 0) {
        diag_error_nopos(diag, "no data row");
        ok = false;
    } else if (ok && isnan(at) && rows > 1) {
        diag_error_nopos(diag, "%d rows: give --at T to choose one", rows);
        ok = false;
    } else if (ok && !isnan(at) && best > STATE_CSV_T_MATCH * fmax(1.0, fabs(at))) {
        diag_error_nopos(diag, "no row at t = %g (the nearest is t = %.17g)", at, *t);
        ok = false;
    }
    free(text), free(work), free(col);
    diag->text = NULL, diag->text_len = 0;   /* the message and its line are copies */
    return ok;
}
