/* output.c - the CSV and JSON of `mechc run` and `mechc sim`, and numbers printed to round-trip.
 *
 * CSV streams: a header row, then one row per time as the analysis
 * produces it, so a failed run still leaves every row computed before the
 * failure (the caller flushes). JSON keeps one array per key (spec section
 * 3: "t", "q", "qd", "qdd"), so the rows are collected in a MechrtTrace and
 * written at the end, also after a failure, with "ok": false and the error.
 */
#include "mechrt_host.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void put_real(FILE *out, double v, int digits)
{
    char buf[40];
    mechrt_format_real(buf, sizeof buf, v, digits, false);
    fputs(buf, out);
}

void mechrt_csv_header(FILE *out, int nq, const char *const *names)
{
    mechrt_csv_header_omega(out, nq, names, 0, NULL);
}

void mechrt_csv_header_omega(FILE *out, int nq, const char *const *names, int nw,
                             const char *const *wnames)
{
    mechrt_csv_header_extra(out, nq, names, nw, wnames, 0, NULL);
}

void mechrt_csv_header_extra(FILE *out, int nq, const char *const *names, int nw,
                             const char *const *wnames, int nx, const char *const *xnames)
{
    fputs("t", out);
    for (int i = 0; i < nq; i++)
        fprintf(out, ",%s", names[i]);
    for (int i = 0; i < nq; i++)
        fprintf(out, ",d(%s)", names[i]);
    for (int i = 0; i < nw; i++)
        fprintf(out, ",%s", wnames[i]);
    for (int i = 0; i < nq; i++)
        fprintf(out, ",dd(%s)", names[i]);
    for (int i = 0; i < nx; i++)
        fprintf(out, ",%s", xnames[i]);
    fputc('\n', out);
}

void mechrt_csv_row(FILE *out, int nq, double t, const double *q, const double *qd,
                    const double *qdd, int digits)
{
    mechrt_csv_row_omega(out, nq, t, q, qd, qdd, 0, NULL, digits);
}

/* A CSV row is formatted into this, written when nearly full: one fwrite
   per few hundred numbers instead of one stdio call per number and comma. */
typedef struct {
    FILE *out;
    size_t len;
    char buf[8192];
} RowBuf;

static void rowbuf_real(RowBuf *rb, char sep, double v, int digits)
{
    if (rb->len > sizeof rb->buf - 48) {
        fwrite(rb->buf, 1, rb->len, rb->out);
        rb->len = 0;
    }
    if (sep)
        rb->buf[rb->len++] = sep;
    rb->len += (size_t)mechrt_format_real(rb->buf + rb->len, 40, v, digits, false);
}

void mechrt_csv_row_omega(FILE *out, int nq, double t, const double *q, const double *qd,
                          const double *qdd, int nw, const double *w, int digits)
{
    mechrt_csv_row_extra(out, nq, t, q, qd, qdd, nw, w, 0, NULL, digits);
}

void mechrt_csv_row_extra(FILE *out, int nq, double t, const double *q, const double *qd,
                          const double *qdd, int nw, const double *w, int nx, const double *x,
                          int digits)
{
    RowBuf rb;
    rb.out = out;
    rb.len = 0;
    rowbuf_real(&rb, 0, t, digits);
    const double *v[3] = {q, qd, qdd};
    for (int k = 0; k < 3; k++) {
        for (int i = 0; i < nq; i++)
            rowbuf_real(&rb, ',', v[k][i], digits);
        for (int i = 0; k == 1 && i < nw; i++)
            rowbuf_real(&rb, ',', w[i], digits);
    }
    for (int i = 0; i < nx; i++)
        rowbuf_real(&rb, ',', x[i], digits);
    rb.buf[rb.len++] = '\n';
    fwrite(rb.buf, 1, rb.len, out);
}

void mechrt_trace_init(MechrtTrace *tr, int nq)
{
    tr->nq = nq;
    tr->rows = tr->cap = 0;
    tr->data = NULL;
    tr->nw = 0;
    tr->wnames = NULL;
    tr->wdata = NULL;
}

void mechrt_trace_set_omega(MechrtTrace *tr, int nw, const char *const *wnames)
{
    tr->nw = nw;
    tr->wnames = wnames;
}

/* Room for one more row (and its velocity-only values). */
static bool trace_reserve(MechrtTrace *tr)
{
    size_t w = 1 + 3 * (size_t)tr->nq, nw = (size_t)tr->nw;
    if (tr->rows < tr->cap)
        return true;
    size_t cap = tr->cap ? 2 * tr->cap : 64;
    if (cap > ((size_t)-1 / sizeof(double)) / w)
        return false;
    double *p = realloc(tr->data, cap * w * sizeof *p);
    if (!p)
        return false;
    tr->data = p;
    if (nw) {
        double *pw = realloc(tr->wdata, cap * nw * sizeof *pw);
        if (!pw)
            return false;
        tr->wdata = pw;
    }
    tr->cap = cap;
    return true;
}

bool mechrt_trace_push(MechrtTrace *tr, double t, const double *q, const double *qd,
                       const double *qdd)
{
    return mechrt_trace_push_omega(tr, t, q, qd, qdd, NULL);
}

bool mechrt_trace_push_omega(MechrtTrace *tr, double t, const double *q, const double *qd,
                             const double *qdd, const double *omega)
{
    size_t w = 1 + 3 * (size_t)tr->nq;
    if (!trace_reserve(tr))
        return false;
    if (tr->nw)
        memcpy(tr->wdata + tr->rows * (size_t)tr->nw, omega, (size_t)tr->nw * sizeof *omega);
    double *row = tr->data + tr->rows * w;
    size_t n = (size_t)tr->nq;
    row[0] = t;
    memcpy(row + 1, q, n * sizeof *q);
    memcpy(row + 1 + n, qd, n * sizeof *qd);
    memcpy(row + 1 + 2 * n, qdd, n * sizeof *qdd);
    tr->rows++;
    return true;
}

void mechrt_trace_free(MechrtTrace *tr)
{
    free(tr->data);
    free(tr->wdata);
    tr->data = NULL;
    tr->wdata = NULL;
    tr->rows = tr->cap = 0;
}

void mechrt_json_string(FILE *out, const char *s)
{
    fputc('"', out);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(out, "\\%c", *p);
        else if (*p < 0x20 || *p == 0x7f)
            fprintf(out, "\\u%04x", *p);
        else
            fputc(*p, out);
    }
    fputc('"', out);
}

static void json_num(FILE *out, double v, int digits)
{
    if (isfinite(v))
        put_real(out, v, digits);
    else
        fputs("null", out);
}

/* One group of columns [first, first + n) of the trace's q | qd | qdd as
   the JSON keys names_key (NULL: the names are not written) and keys[0..2]. */
static void json_group(FILE *out, const MechrtTrace *tr, const char *const *names, size_t first,
                       size_t n, const char *names_key, const char *const keys[3], int digits)
{
    size_t nq = (size_t)tr->nq, w = 1 + 3 * nq;
    if (names_key) {
        fprintf(out, ",\n \"%s\": [", names_key);
        for (size_t i = 0; i < n; i++) {
            fputs(i ? ", " : "", out);
            mechrt_json_string(out, names[first + i]);
        }
        fputs("]", out);
    }
    for (size_t k = 0; k < 3; k++) {
        fprintf(out, ",\n \"%s\": [", keys[k]);
        for (size_t r = 0; r < tr->rows; r++) {
            const double *v = tr->data + r * w + 1 + k * nq + first;
            fputs(r ? ",\n   [" : "[", out);
            for (size_t i = 0; i < n; i++) {
                fputs(i ? ", " : "", out);
                json_num(out, v[i], digits);
            }
            fputs("]", out);
        }
        fputs("]", out);
    }
}

/* "omega_names": [...], "omega": [[...] per row]: the velocity-only columns. */
static void json_omega(FILE *out, const MechrtTrace *tr, int digits)
{
    size_t nw = (size_t)tr->nw;
    fputs(",\n \"omega_names\": [", out);
    for (size_t i = 0; i < nw; i++) {
        fputs(i ? ", " : "", out);
        mechrt_json_string(out, tr->wnames[i]);
    }
    fputs("],\n \"omega\": [", out);
    for (size_t r = 0; r < tr->rows; r++) {
        fputs(r ? ",\n   [" : "[", out);
        for (size_t i = 0; i < nw; i++) {
            fputs(i ? ", " : "", out);
            json_num(out, tr->wdata[r * nw + i], digits);
        }
        fputs("]", out);
    }
    fputs("]", out);
}

void mechrt_json_write_outputs(FILE *out, const MechrtTrace *tr, int ncoords,
                               const char *const *names, int digits,
                               const char *error_message, double error_t)
{
    mechrt_json_write_lambda(out, tr, ncoords, names, digits, error_message, error_t, NULL);
}

/* "NAMES_KEY": [names], "KEY": [[n values] per trace row]. */
static void json_table(FILE *out, const char *names_key, const char *const *names, int n,
                       const char *key, const double *data, size_t rows, int digits)
{
    fprintf(out, ",\n \"%s\": [", names_key);
    for (int i = 0; i < n; i++) {
        fputs(i ? ", " : "", out);
        mechrt_json_string(out, names[i]);
    }
    fprintf(out, "],\n \"%s\": [", key);
    for (size_t r = 0; r < rows; r++) {
        fputs(r ? ",\n   [" : "[", out);
        for (int i = 0; i < n; i++) {
            fputs(i ? ", " : "", out);
            json_num(out, data[r * (size_t)n + (size_t)i], digits);
        }
        fputs("]", out);
    }
    fputs("]", out);
}

void mechrt_json_write_lambda(FILE *out, const MechrtTrace *tr, int ncoords,
                              const char *const *names, int digits, const char *error_message,
                              double error_t, const MechrtJsonLambda *lam)
{
    static const char *const qkeys[3] = {"q", "qd", "qdd"}, *const ykeys[3] = {"y", "yd", "ydd"};
    size_t w = 1 + 3 * (size_t)tr->nq, nc = (size_t)ncoords;
    fputs("{\"coords\": [", out);
    for (size_t i = 0; i < nc; i++) {
        fputs(i ? ", " : "", out);
        mechrt_json_string(out, names[i]);
    }
    fputs("],\n \"t\": [", out);
    for (size_t r = 0; r < tr->rows; r++) {
        fputs(r ? ", " : "", out);
        json_num(out, tr->data[r * w], digits);
    }
    fputs("]", out);
    size_t nq = (size_t)tr->nq;
    json_group(out, tr, names, 0, nc, NULL, qkeys, digits);
    if (nq > nc)
        json_group(out, tr, names, nc, nq - nc, "outputs", ykeys, digits);
    if (tr->nw)
        json_omega(out, tr, digits);
    fprintf(out, ",\n \"ok\": %s", error_message ? "false" : "true");
    if (error_message) {
        fputs(",\n \"error\": {\"t\": ", out);
        json_num(out, error_t, 0);
        fputs(", \"message\": ", out);
        mechrt_json_string(out, error_message);
        fputs("}", out);
    }
    if (lam && lam->nr > 0)
        json_table(out, "rows", lam->rows, lam->nr, "lambda", lam->lambda, tr->rows, digits);
    if (lam && lam->nd > 0)
        json_table(out, "drivers", lam->drivers, lam->nd, "efforts", lam->efforts, tr->rows,
                   digits);
    if (lam && lam->nx > 0)
        json_table(out, lam->xnames_key, lam->xnames, lam->nx, lam->x_key, lam->x, tr->rows, digits);
    fputs("}\n", out);
}

void mechrt_json_write(FILE *out, const MechrtTrace *tr, const char *const *names, int digits,
                       const char *error_message, double error_t)
{
    mechrt_json_write_outputs(out, tr, tr->nq, names, digits, error_message, error_t);
}
