/* trace.c - the --trace argument: a point of a body (BODY(sx, sy), spatial BODY(sx, sy, sz), BODY) or a particle (POINT). */
#include "svg_anim.h"

#include "../base/arena.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *skip_blank(const char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    return s;
}

/* A number as strtod reads it, signed; *end after it. */
static bool parse_number(const char *s, double *v, const char **end)
{
    char *e;
    errno = 0;
    *v = strtod(s, &e);
    if (e == s || errno == ERANGE || !isfinite(*v))
        return false;
    /* strtod also takes "inf", "nan" and hex: numbers here are decimal */
    for (const char *p = s; p < e; p++)
        if (!(strchr("0123456789.eE+-", *p)))
            return false;
    *end = e;
    return true;
}

/* Reads "(sx, sy)" ("(sx, sy, sz)" when n is 3) at *s, blanks allowed
   around its parts; on success moves *s past it. */
static bool parse_offset(const char **s, const char *text, int n, double *v, char *err,
                         size_t errlen)
{
    static const char *const names[3] = {"sx", "sy", "sz"};
    const char *p = *s + 1, *e;
    for (int i = 0; i < n; i++) {
        p = skip_blank(p);
        if (!parse_number(p, &v[i], &e)) {
            snprintf(err, errlen, "--trace '%s': expected a number for %s at '%s'", text, names[i], p);
            return false;
        }
        p = skip_blank(e);
        if (i + 1 < n && *p != ',') {
            snprintf(err, errlen, "--trace '%s': expected ',' between %s and %s", text, names[i],
                     names[i + 1]);
            return false;
        }
        p += i + 1 < n;
    }
    if (*p != ')') {
        snprintf(err, errlen, "--trace '%s': expected ')' after %s", text, names[n - 1]);
        return false;
    }
    *s = skip_blank(p + 1);
    return true;
}

static bool is_scalar_coord(const Model *m, const char *name)
{
    for (int i = 0; i < m->nq; i++)
        if (strcmp(m->coord_names[i], name) == 0)
            return true;
    return false;
}

/* The body or point named by the identifier at *s (moved past it), or NULL
   with err filled. */
static const Body *parse_body(const Model *m, const char **s, const char *text, char *err,
                              size_t errlen)
{
    const char *name = *s, *p = name;
    if (!(*p == '_' || (*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z'))) {
        snprintf(err, errlen, "--trace '%s': expected BODY(sx, sy), BODY or POINT", text);
        return NULL;
    }
    while (*p == '_' || (*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9'))
        p++;
    size_t len = (size_t)(p - name);
    *s = p;
    if (len == 6 && strncmp(name, "ground", 6) == 0) {
        snprintf(err, errlen, "--trace '%s': ground does not move; name a body or a point", text);
        return NULL;
    }
    char *copy = xmalloc(len + 1);
    memcpy(copy, name, len);
    copy[len] = '\0';
    const Body *b = model_find_body(m, copy);
    if (!b)
        snprintf(err, errlen, "--trace '%s': '%s' is %s", text, copy,
                 is_scalar_coord(m, copy) ? "a scalar coordinate, not a body or a point"
                                          : "not a body or a point of the mechanism");
    free(copy);
    return b;
}

bool svg_parse_trace(const Model *m, const char *text, SvgTrace *out, char *err, size_t errlen)
{
    const char *s = skip_blank(text ? text : "");
    text = text ? text : "";
    const Body *b = parse_body(m, &s, text, err, errlen);
    if (!b)
        return false;
    bool turns = b->has_phi || (b->spatial && b->nq == 7);
    int n = b->spatial ? 3 : 2;
    double v[3] = {0, 0, 0};
    s = skip_blank(s);
    if (*s == '(') {
        if (!turns) {
            snprintf(err, errlen, "--trace '%s': '%s' is a point; it takes no offset", text, b->name);
            return false;
        }
        if (!parse_offset(&s, text, n, v, err, errlen))
            return false;
    }
    if (*s) {
        snprintf(err, errlen, "--trace '%s': unexpected '%s' (expected %s, BODY or POINT)", text, s,
                 b->spatial ? "BODY(sx, sy, sz)" : "BODY(sx, sy)");
        return false;
    }
    out->q = b->q;
    out->has_phi = turns;
    out->sx = v[0];
    out->sy = v[1];
    out->sz = v[2];
    out->spatial = b->spatial;
    out->label = text;
    return true;
}
