/* data.c - the measurements `mechc fit` matches: a CSV of times and measured coordinates or outputs. */
#include "data.h"

#include "../base/arena.h"
#include "../base/limits.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* A field of the line being read: where it starts and how long it is. */
typedef struct Field {
    int offset, len;
} Field;

/* The fields of the line at text[at .. end), split at commas, spaces
   around them dropped; at most max. Returns their count (max + 1: more). */
static int split(const char *text, int at, int end, Field *f, int max)
{
    int n = 0;
    while (true) {
        int s = at, e;
        while (s < end && (text[s] == ' ' || text[s] == '\t'))
            s++;
        for (e = s; e < end && text[e] != ','; e++)
            ;
        int stop = e;
        while (e > s && (text[e - 1] == ' ' || text[e - 1] == '\t' || text[e - 1] == '\r'))
            e--;
        if (n == max)
            return max + 1;
        f[n++] = (Field){s, e - s};
        if (stop >= end)
            return n;
        at = stop + 1;
    }
}

/* The variable a header field names: coordinate index, nq + output index, or -1. */
static int lookup(const Model *m, const char *s, int len)
{
    for (int i = 0; i < m->nq; i++)
        if ((int)strlen(m->coord_names[i]) == len && strncmp(m->coord_names[i], s, (size_t)len) == 0)
            return i;
    for (int k = 0; k < m->nout; k++)
        if ((int)strlen(m->outputs[k].name) == len && strncmp(m->outputs[k].name, s, (size_t)len) == 0)
            return m->nq + k;
    return -1;
}

static bool fail(Diag *diag, const Field *f, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static bool fail(Diag *diag, const Field *f, const char *fmt, ...)
{
    char msg[DIAG_MESSAGE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    diag_error(diag, (SrcPos){f->offset}, "%s", msg);
    return false;
}

/* Header columns: which is t, which variable or weight each other one is. */
typedef struct Header {
    int ncol;           /* fields per row */
    int tcol;
    int *col_var;       /* per field: measured column index (d->var), or -1 */
    int *col_weight;    /* per field: the measured column it weighs, or -1 */
} Header;

static bool read_header(const char *text, const Field *f, int n, const Model *m, FitData *d,
                        Header *h, Diag *diag)
{
    h->ncol = n;
    h->tcol = -1;
    h->col_var = xcalloc((size_t)n, sizeof *h->col_var);
    h->col_weight = xcalloc((size_t)n, sizeof *h->col_weight);
    d->var = xcalloc((size_t)n, sizeof *d->var);
    d->names = xcalloc((size_t)n, sizeof *d->names);
    for (int c = 0; c < n; c++) {
        const char *s = text + f[c].offset;
        int len = f[c].len, v;
        h->col_var[c] = h->col_weight[c] = -1;
        if (len == 1 && s[0] == 't') {
            if (h->tcol >= 0)
                return fail(diag, &f[c], "a second column t");
            h->tcol = c;
        } else if (len > 3 && strncmp(s, "w(", 2) == 0 && s[len - 1] == ')') {
            continue;   /* matched once every variable is known */
        } else if ((v = lookup(m, s, len)) >= 0) {
            for (int k = 0; k < d->ncols; k++)
                if (d->var[k] == v)
                    return fail(diag, &f[c], "'%.*s' is measured in two columns", len, s);
            d->var[d->ncols] = v;
            d->names[d->ncols] = v < m->nq ? m->coord_names[v] : m->outputs[v - m->nq].name;
            h->col_var[c] = d->ncols++;
        } else {
            return fail(diag, &f[c], "'%.*s' is neither t, a coordinate, an output nor a weight "
                        "w(NAME) of %s", len, s, m->file);
        }
    }
    for (int c = 0; c < n; c++) {
        const char *s = text + f[c].offset;
        if (!(f[c].len > 3 && strncmp(s, "w(", 2) == 0 && s[f[c].len - 1] == ')'))
            continue;
        int v = lookup(m, s + 2, f[c].len - 3);
        for (int k = 0; k < d->ncols && v >= 0; k++)
            if (d->var[k] == v)
                h->col_weight[c] = k;
        if (h->col_weight[c] < 0)
            return fail(diag, &f[c], "the weight '%.*s' has no measured column", f[c].len, s);
    }
    if (h->tcol < 0)
        return fail(diag, &f[0], "the header has no column t (the time of each sample)");
    if (d->ncols == 0)
        return fail(diag, &f[0], "the header names no measured coordinate or output");
    return true;
}

/* A finite number filling the whole field; empty: NaN with *empty set. */
static bool number(const char *text, const Field *f, double *v, bool *empty)
{
    char buf[64];
    *empty = f->len == 0;
    if (*empty) {
        *v = NAN;
        return true;
    }
    if (f->len >= (int)sizeof buf)
        return false;
    memcpy(buf, text + f->offset, (size_t)f->len);
    buf[f->len] = '\0';
    char *end;
    errno = 0;
    *v = strtod(buf, &end);
    return *end == '\0' && errno != ERANGE && isfinite(*v);
}

static void grow(FitData *d, int *cap)
{
    if (d->nsamples < *cap)
        return;
    *cap = *cap ? 2 * *cap : 64;
    d->t = xrealloc(d->t, (size_t)*cap, sizeof *d->t);
    d->line = xrealloc(d->line, (size_t)*cap, sizeof *d->line);
    d->value = xrealloc(d->value, (size_t)*cap * (size_t)d->ncols, sizeof *d->value);
    d->weight = xrealloc(d->weight, (size_t)*cap * (size_t)d->ncols, sizeof *d->weight);
}

/* One data row into sample d->nsamples. */
static bool read_row(const char *text, const Field *f, const Header *h, int line, FitData *d,
                     Diag *diag)
{
    int s = d->nsamples;
    double *val = d->value + (size_t)s * (size_t)d->ncols, *w = d->weight + (size_t)s * (size_t)d->ncols;
    for (int k = 0; k < d->ncols; k++)
        val[k] = NAN, w[k] = 1.0;
    for (int c = 0; c < h->ncol; c++) {
        double v;
        bool empty;
        if (!number(text, &f[c], &v, &empty))
            return fail(diag, &f[c], "'%.*s' is not a finite number", f[c].len, text + f[c].offset);
        if (c == h->tcol) {
            if (empty)
                return fail(diag, &f[c], "the sample has no time t");
            if (s > 0 && v < d->t[s - 1])
                return fail(diag, &f[c], "t = %.17g comes after t = %.17g: samples go in "
                            "time order", v, d->t[s - 1]);
            d->t[s] = v;
        } else if (h->col_var[c] >= 0) {
            val[h->col_var[c]] = v;
            d->nmeasured += !empty;
        } else if (!empty) {
            if (!(v > 0))
                return fail(diag, &f[c], "a weight must be positive, not %.17g", v);
            w[h->col_weight[c]] = v;
        }
    }
    d->line[s] = line;
    d->nsamples++;
    return true;
}

bool fit_data_read(const char *path, const Model *m, FitData *d, Diag *diag)
{
    memset(d, 0, sizeof *d);
    diag_init(diag, path, "", 0);
    MechLimits limits = mech_default_limits();
    int len;
    char *text = model_read_data_file(path, &limits, &len, diag);
    if (!text)
        return false;
    diag_init(diag, path, text, len);
    enum { MAX_FIELDS = 4096 };
    Field *f = xcalloc(MAX_FIELDS + 1, sizeof *f);
    Header h = {0};
    bool ok = true, headed = false;
    int line = 0, cap = 0;
    for (int at = 0; at < len && ok;) {
        int end = at;
        while (end < len && text[end] != '\n')
            end++;
        line++;
        int first = at;
        while (first < end && (text[first] == ' ' || text[first] == '\t' || text[first] == '\r'))
            first++;
        if (first < end && text[first] != '#') {
            int n = split(text, at, end, f, MAX_FIELDS);
            if (n > MAX_FIELDS)
                ok = fail(diag, &f[0], "more than %d columns", MAX_FIELDS);
            else if (!headed)
                ok = headed = read_header(text, f, n, m, d, &h, diag);
            else if (n != h.ncol)
                ok = fail(diag, &f[n - 1], "%d fields where the header has %d", n, h.ncol);
            else {
                grow(d, &cap);
                ok = read_row(text, f, &h, line, d, diag);
            }
        }
        at = end + 1;
    }
    if (ok && !headed)
        ok = fail(diag, &(Field){0, 0}, "no header: the first line names t and the measured columns");
    if (ok && d->nmeasured == 0)
        ok = fail(diag, &(Field){len > 0 ? len - 1 : 0, 0}, "no measured value");
    free(f), free(h.col_var), free(h.col_weight);
    d->text = text;     /* diag's line points into it: freed by fit_data_free */
    return ok;
}

void fit_data_free(FitData *d)
{
    free(d->t), free(d->line), free(d->var), free(d->names), free(d->value), free(d->weight);
    free(d->text);
    memset(d, 0, sizeof *d);
}
