/* test_svg.c - the animated SVG, the plots, their name parsers and the progress bar.
 *
 * Every SVG written here goes through a small XML well-formedness checker
 * (balanced tags, one root, quoted attributes without '<', known entities
 * only), then its content is checked: how many links, pins and sliders, the
 * <animate> values, the viewBox against the drawing's size, equal x and y
 * scales (a crank keeps its pixel length while it turns), traces, escaping,
 * the generic drawing a joint kind gets when the renderer has none for it,
 * and the convex hull that outlines a body.
 * xmllint, when installed, checks the files again (the test does not need it).
 */
#include "testutil.h"

#include "../generator/pipeline/pipeline.h"
#include "../generator/render/hull.h"
#include "../generator/render/progress.h"
#include "../generator/render/scene.h"
#include "../generator/render/svg_anim.h"
#include "../generator/render/svg_common.h"
#include "../generator/render/svg_plot.h"
#include "../generator/render/svg_write.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- a minimal XML well-formedness checker ---- */

static char xml_msg[256];

static const char *xml_fail(const char *s, const char *at, const char *what)
{
    int line = 1;
    for (const char *p = s; p < at; p++)
        line += *p == '\n';
    snprintf(xml_msg, sizeof xml_msg, "line %d: %s near '%.30s'", line, what, at);
    return xml_msg;
}

/* An entity reference at p ('&'): &amp; &lt; &gt; &quot; &apos; &#N; &#xH;. */
static const char *entity_end(const char *p)
{
    static const char *const names[] = {"amp;", "lt;", "gt;", "quot;", "apos;"};
    p++;
    for (size_t i = 0; i < sizeof names / sizeof *names; i++)
        if (strncmp(p, names[i], strlen(names[i])) == 0)
            return p + strlen(names[i]);
    if (*p == '#') {
        p++;
        bool hex = *p == 'x';
        p += hex;
        const char *d = p;
        while (hex ? isxdigit((unsigned char)*p) : isdigit((unsigned char)*p))
            p++;
        if (p > d && *p == ';')
            return p + 1;
    }
    return NULL;
}

static bool name_start(char c) { return isalpha((unsigned char)c) || c == '_' || c == ':'; }
static bool name_char(char c) { return name_start(c) || isdigit((unsigned char)c) || c == '-' || c == '.'; }

/* NULL when s is well-formed XML, else a message. */
static const char *xml_check(const char *s)
{
    const char *stack[256];
    size_t stack_len[256];
    int depth = 0, roots = 0;
    const char *p = s;
    if (strncmp(p, "<?xml", 5) == 0) {
        p = strstr(p, "?>");
        if (!p)
            return xml_fail(s, s, "unterminated XML declaration");
        p += 2;
    }
    while (*p) {
        if (*p == '&') {
            const char *e = entity_end(p);
            if (!e)
                return xml_fail(s, p, "bad entity");
            p = e;
            continue;
        }
        if (*p != '<') {
            if (depth == 0 && !isspace((unsigned char)*p))
                return xml_fail(s, p, "text outside the root element");
            p++;
            continue;
        }
        if (strncmp(p, "<!--", 4) == 0) {
            const char *e = strstr(p + 4, "--");
            if (!e || e[2] != '>')
                return xml_fail(s, p, "bad comment");
            p = e + 3;
            continue;
        }
        if (p[1] == '/') {
            const char *n = p + 2, *e = n;
            while (name_char(*e))
                e++;
            if (depth == 0 || stack_len[depth - 1] != (size_t)(e - n) ||
                strncmp(stack[depth - 1], n, (size_t)(e - n)) != 0)
                return xml_fail(s, p, "mismatched end tag");
            while (isspace((unsigned char)*e))
                e++;
            if (*e != '>')
                return xml_fail(s, e, "expected '>'");
            depth--;
            p = e + 1;
            continue;
        }
        const char *n = p + 1, *e = n;
        if (!name_start(*e))
            return xml_fail(s, p, "bad element name");
        while (name_char(*e))
            e++;
        if (depth == 0 && roots++ > 0)
            return xml_fail(s, p, "a second root element");
        /* attributes */
        const char *attr_names[64];
        size_t attr_lens[64];
        int nattr = 0;
        for (;;) {
            const char *ws = e;
            while (isspace((unsigned char)*e))
                e++;
            if (*e == '/' && e[1] == '>') {
                p = e + 2;
                break;
            }
            if (*e == '>') {
                if (depth == 256)
                    return xml_fail(s, p, "too deep");
                stack[depth] = n;
                stack_len[depth] = 0;
                while (name_char(n[stack_len[depth]]))
                    stack_len[depth]++;
                depth++;
                p = e + 1;
                break;
            }
            if (e == ws || !name_start(*e))
                return xml_fail(s, e, "expected an attribute");
            const char *an = e;
            while (name_char(*e))
                e++;
            for (int k = 0; k < nattr; k++)
                if (attr_lens[k] == (size_t)(e - an) && strncmp(attr_names[k], an, attr_lens[k]) == 0)
                    return xml_fail(s, an, "duplicate attribute");
            if (nattr < 64) {
                attr_names[nattr] = an;
                attr_lens[nattr++] = (size_t)(e - an);
            }
            while (isspace((unsigned char)*e))
                e++;
            if (*e != '=')
                return xml_fail(s, e, "expected '=' after an attribute name");
            e++;
            while (isspace((unsigned char)*e))
                e++;
            char quote = *e;
            if (quote != '"' && quote != '\'')
                return xml_fail(s, e, "unquoted attribute value");
            e++;
            while (*e && *e != quote) {
                if (*e == '<')
                    return xml_fail(s, e, "'<' in an attribute value");
                if (*e == '&') {
                    const char *x = entity_end(e);
                    if (!x)
                        return xml_fail(s, e, "bad entity in an attribute value");
                    e = x;
                    continue;
                }
                e++;
            }
            if (!*e)
                return xml_fail(s, an, "unterminated attribute value");
            e++;
        }
    }
    if (depth != 0)
        return xml_fail(s, p, "unclosed element");
    if (roots != 1)
        return xml_fail(s, p, "no root element");
    return NULL;
}

static void assert_xml(const char *svg)
{
    const char *err = xml_check(svg);
    if (err)
        fail_msg("not well-formed XML: %s", err);
}

/* The checker itself, on good and bad documents. */
static void test_xml_checker(void **state)
{
    (void)state;
    assert_null(xml_check("<?xml version=\"1.0\"?>\n<a x=\"1\" y='2'><b/>t &amp; &#60; &#x3c;<!-- c --></a>\n"));
    const char *bad[] = {
        "<a><b></a>", "<a x=1/>", "<a>&foo;</a>", "<a>x & y</a>", "<a x=\"<\"/>", "<a/><b/>",
        "<a x=\"1\" x=\"2\"/>", "<a>", "text<a/>", "<a x=\"1\"y=\"2\"/>",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
        if (!xml_check(bad[i]))
            fail_msg("accepted bad XML: %s", bad[i]);
}

/* ---- helpers ---- */

static int count(const char *s, const char *needle)
{
    int n = 0;
    for (const char *p = strstr(s, needle); p; p = strstr(p + 1, needle))
        n++;
    return n;
}

/* Separators in the first points animation: frames kept - 1. */
static int frames_kept(const char *s)
{
    const char *v = strstr(strstr(s, "<animate attributeName=\"points\""), "values=\"") + 8;
    const char *e = strchr(v, '"');
    int semis = 0;
    for (const char *p = v; p < e; p++)
        semis += *p == ';';
    return semis + 1;
}

/* Whether the first points animation carries a keyTimes list. */
static bool points_have_key_times(const char *s)
{
    const char *a = strstr(s, "<animate attributeName=\"points\"");
    const char *e = strstr(a, "/>");
    const char *k = strstr(a, "keyTimes=");
    return k && k < e;
}

/* Captures what a writer prints (open_memstream). */
typedef struct Capture {
    char *text;
    size_t len;
    FILE *f;
} Capture;

static FILE *capture_open(Capture *c)
{
    memset(c, 0, sizeof *c);
    c->f = open_memstream(&c->text, &c->len);
    assert_non_null(c->f);
    return c->f;
}

static char *capture_close(Capture *c)
{
    fclose(c->f);
    return c->text;
}

/* Runs xmllint on the text when it is installed; silent otherwise. */
static void xmllint_if_present(const char *text)
{
    if (system("command -v xmllint >/dev/null 2>&1") != 0)
        return;
    char path[] = "/tmp/mechc_test_svg_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "w");
    fputs(text, f);
    fclose(f);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "xmllint --noout '%s'", path);
    int rc = system(cmd);
    unlink(path);
    assert_int_equal(rc, 0);
}

/* A numeric attribute of the first element that has `marker`: attr="N". */
static double attr_after(const char *s, const char *marker, const char *attr)
{
    const char *p = strstr(s, marker);
    assert_non_null(p);
    char key[64];
    snprintf(key, sizeof key, " %s=\"", attr);
    p = strstr(p, key);
    assert_non_null(p);
    return strtod(p + strlen(key), NULL);
}

/* ---- the slider-crank fixture: closed-form motion ---- */

static const char slider_crank[] =
    "mechanism slider_crank\n"
    "param r = 0.1\nparam l = 0.3\nparam omega = 2*pi\n"
    "body crank x = r/2 y = 0 phi = 0\n"
    "body rod x = r + l/2 y = 0 phi = 0\n"
    "body slider x = r + l y = 0 phi = 0\n"
    "revolute O: ground(0, 0) crank(-r/2, 0)\n"
    "revolute A: crank(r/2, 0) rod(-l/2, 0)\n"
    "revolute B: rod(l/2, 0) slider(0, 0)\n"
    "prismatic P: ground(0, 0) slider(0, 0) axis(1, 0)\n"
    "driver D: crank.phi = omega*t\n";

typedef struct Fixture {
    Diag diag;
    Mech *mech;
    int n;
    double *t, *q;
} Fixture;

/* n frames over t = 0 .. 1: theta = 2 pi t, slider.x = r cos + sqrt(l^2 - r^2 sin^2). */
static void fill_slider_crank(Fixture *fx, int n)
{
    const double r = 0.1, l = 0.3;
    fx->n = n;
    fx->t = realloc(fx->t, (size_t)n * sizeof *fx->t);
    fx->q = realloc(fx->q, (size_t)n * 9 * sizeof *fx->q);
    for (int k = 0; k < n; k++) {
        double t = n > 1 ? (double)k / (n - 1) : 0, th = 2 * M_PI * t;
        double ax = r * cos(th), ay = r * sin(th);
        double beta = -asin(r * sin(th) / l);
        double bx = ax + l * cos(beta);
        double *q = fx->q + (size_t)k * 9;
        fx->t[k] = t;
        q[0] = 0.5 * ax, q[1] = 0.5 * ay, q[2] = th;
        q[3] = 0.5 * (ax + bx), q[4] = 0.5 * ay, q[5] = beta;
        q[6] = bx, q[7] = 0, q[8] = 0;
    }
}

static Fixture *load_text(const char *text)
{
    Fixture *fx = calloc(1, sizeof *fx);
    MechLimits limits = mech_default_limits();
    fx->mech = pipeline_load_text(text, "test.mech", &limits, &fx->diag);
    if (!fx->mech) {
        diag_print(&fx->diag, stderr);
        fail_msg("fixture does not load");
    }
    return fx;
}

static int setup(void **state)
{
    Fixture *fx = load_text(slider_crank);
    fill_slider_crank(fx, 101);
    *state = fx;
    return 0;
}

static void fixture_free(Fixture *fx)
{
    pipeline_free(fx->mech);
    free(fx->t);
    free(fx->q);
    free(fx);
}

static int teardown(void **state)
{
    fixture_free(*state);
    return 0;
}

/* With MECHC_TEST_SVG_DIR set, keeps a copy of a picture to look at. */
static void keep_copy(const char *text, const char *name)
{
    const char *dir = getenv("MECHC_TEST_SVG_DIR");
    if (!dir)
        return;
    char path[512];
    snprintf(path, sizeof path, "%s/%s.svg", dir, name);
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

static char *animate(const Fixture *fx, const SvgTrace *tr, int ntr, const char *title)
{
    Capture c;
    FILE *f = capture_open(&c);
    assert_true(svg_write_animation(f, fx->mech->model, fx->t, fx->q, fx->n, tr, ntr, title));
    char *s = capture_close(&c);
    assert_xml(s);
    keep_copy(s, title ? "titled" : fx->mech->model->name);
    return s;
}

/* ---- animation ---- */

static void test_anim_structure(void **state)
{
    Fixture *fx = *state;
    char *s = animate(fx, NULL, 0, NULL);
    /* crank and rod are links; the slider (a single point) is its block */
    assert_int_equal(count(s, "class=\"link\""), 2);
    assert_int_equal(count(s, "class=\"slider\""), 1);
    assert_int_equal(count(s, "class=\"guide\""), 1);
    assert_int_equal(count(s, "class=\"pin\""), 3);         /* O, A, B */
    assert_int_equal(count(s, "class=\"pivot\""), 1);       /* O on ground */
    assert_int_equal(count(s, "class=\"drive\""), 1);       /* crank.phi is driven */
    assert_non_null(strstr(s, "driver D: crank.phi"));
    assert_non_null(strstr(s, "<animate attributeName=\"points\""));
    assert_non_null(strstr(s, "<animateTransform attributeName=\"transform\" type=\"translate\""));
    assert_non_null(strstr(s, "repeatCount=\"indefinite\""));
    /* t = 0 .. 1 plays in the minimum of 2 s; frames are evenly spaced */
    assert_non_null(strstr(s, "dur=\"2s\""));
    assert_false(points_have_key_times(s));
    assert_non_null(strstr(s, "<title>slider_crank</title>"));
    assert_null(strstr(s, "<script"));
    assert_null(strstr(s, "nan"));
    assert_null(strstr(s, "inf"));
    /* the time display: first text visible, the others hidden until their turn */
    assert_non_null(strstr(s, "visibility=\"visible\">t = 0.000"));
    assert_non_null(strstr(s, ">t = 1.000"));
    /* width/height and viewBox agree */
    double w = attr_after(s, "<svg", "width"), h = attr_after(s, "<svg", "height");
    char vb[64];
    snprintf(vb, sizeof vb, "viewBox=\"0 0 %d %d\"", (int)w, (int)h);
    assert_non_null(strstr(s, vb));
    xmllint_if_present(s);
    free(s);
}

/* Pixel length of the first `class="link"` polyline at frame f. */
static double link_length(const char *s, int which, int frame)
{
    const char *p = s;
    for (int i = 0; i <= which; i++) {
        p = strstr(p, "<polyline class=\"link\"");
        assert_non_null(p);
        p++;
    }
    const char *v = strstr(p, "values=\"");
    assert_non_null(v);
    v += 8;
    for (int i = 0; i < frame; i++) {
        v = strchr(v, ';');
        assert_non_null(v);
        v++;
    }
    double x0, y0, x1, y1;
    assert_int_equal(sscanf(v, "%lf,%lf %lf,%lf", &x0, &y0, &x1, &y1), 4);
    return hypot(x1 - x0, y1 - y0);
}

/* Equal scales: the crank (0.1) keeps its length whichever way it points,
   and the rod (0.3) is three times as long; y is up. */
static void test_anim_equal_scales(void **state)
{
    Fixture *fx = *state;
    char *s = animate(fx, NULL, 0, NULL);
    double c0 = link_length(s, 0, 0), c25 = link_length(s, 0, 25), c60 = link_length(s, 0, 60);
    double r0 = link_length(s, 1, 0);
    assert_true(c0 > 50);
    assert_near(c25, c0, 0, 0.3);
    assert_near(c60, c0, 0, 0.3);
    assert_near(r0, 3 * c0, 0, 0.5);
    /* at t = 0.25 the crank points up: its moving end has the smaller y */
    const char *p = strstr(s, "<polyline class=\"link\"");
    const char *v = strstr(p, "values=\"") + 8;
    for (int i = 0; i < 25; i++)
        v = strchr(v, ';') + 1;
    double x0, y0, x1, y1;
    assert_int_equal(sscanf(v, "%lf,%lf %lf,%lf", &x0, &y0, &x1, &y1), 4);
    assert_true(fabs(x1 - x0) < 0.5);
    assert_true(fmin(y0, y1) < fmax(y0, y1) - 50);
    free(s);
}

static void test_anim_subsample(void **state)
{
    Fixture *fx = load_text(slider_crank);
    (void)state;
    /* 1000 intervals: every 8th frame, evenly spaced, no keyTimes needed */
    fill_slider_crank(fx, 1001);
    char *s = animate(fx, NULL, 0, NULL);
    assert_int_equal(frames_kept(s), 126);
    assert_false(points_have_key_times(s));
    assert_true(strlen(s) < 150000);
    free(s);
    /* 997 intervals (a prime): 200 frames, their times in keyTimes */
    fill_slider_crank(fx, 998);
    s = animate(fx, NULL, 0, NULL);
    assert_int_equal(frames_kept(s), 200);
    assert_true(points_have_key_times(s));
    assert_non_null(strstr(s, "keyTimes=\"0;0.005;"));
    free(s);
    /* a byte budget keeps fewer frames (10 at least) */
    SvgAnimOptions o = svg_anim_default_options();
    o.max_bytes = 1000;
    Capture c;
    FILE *f = capture_open(&c);
    assert_true(svg_write_animation_opt(f, fx->mech->model, fx->t, fx->q, fx->n, NULL, 0, NULL, &o));
    s = capture_close(&c);
    assert_xml(s);
    assert_int_equal(frames_kept(s), 10);
    free(s);
    fixture_free(fx);
}

static void test_anim_traces_and_escaping(void **state)
{
    Fixture *fx = *state;
    const Model *m = fx->mech->model;
    SvgTrace tr[2];
    char err[256];
    assert_true(svg_parse_trace(m, "rod(0, 0)", &tr[0], err, sizeof err));
    assert_true(svg_parse_trace(m, " crank ( 0.05 , -0.01 ) ", &tr[1], err, sizeof err));
    assert_int_equal(tr[1].q, 0);
    assert_true(tr[1].has_phi);
    assert_near(tr[1].sx, 0.05, 0, 0);
    assert_near(tr[1].sy, -0.01, 0, 0);
    tr[1].label = "a<b & \"c\"";
    char *s = animate(fx, tr, 2, "run of <slider & crank>.mech");
    assert_int_equal(count(s, "class=\"trace\""), 2);
    assert_int_equal(count(s, "class=\"tracedot\""), 2);
    /* the point off the crank's line makes the crank a triangle */
    assert_int_equal(count(s, "<polygon class=\"link\""), 1);
    assert_int_equal(count(s, "<polyline class=\"link\""), 1);
    assert_non_null(strstr(s, "path of rod(0, 0)"));
    assert_non_null(strstr(s, "a&lt;b &amp; &quot;c&quot;"));
    assert_non_null(strstr(s, "run of &lt;slider &amp; crank&gt;.mech"));
    assert_null(strstr(s, "<slider"));
    /* the rod's middle traces an ellipse: its trace has many points */
    const char *p = strstr(strstr(s, "class=\"trace\""), "points=\"");
    assert_true(count(p, ",") > 50);
    xmllint_if_present(s);
    free(s);
}

static void test_parse_trace_errors(void **state)
{
    Fixture *fx = *state;
    const Model *m = fx->mech->model;
    SvgTrace tr;
    char err[256];
    struct { const char *text, *expect; } cases[] = {
        {"crnk(0, 0)", "'crnk' is not a body or a point"},
        {"ground(1, 2)", "ground does not move"},
        {"crank(0 0)", "expected ','"},
        {"crank(0, )", "expected a number for sy"},
        {"crank(x, 0)", "expected a number for sx"},
        {"crank(0, 0", "expected ')'"},
        {"crank(0, 0) extra", "unexpected 'extra'"},
        {"crank(nan, 0)", "expected a number for sx"},
        {"", "expected BODY(sx, sy)"},
        {"(0, 0)", "expected BODY(sx, sy)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        err[0] = '\0';
        if (svg_parse_trace(m, cases[i].text, &tr, err, sizeof err))
            fail_msg("accepted --trace '%s'", cases[i].text);
        if (!strstr(err, cases[i].expect))
            fail_msg("--trace '%s': message '%s' lacks '%s'", cases[i].text, err, cases[i].expect);
    }
    assert_true(svg_parse_trace(m, "slider", &tr, err, sizeof err));
    assert_int_equal(tr.q, 6);
    assert_near(tr.sx, 0, 0, 0);
}

static void test_anim_bad_input(void **state)
{
    Fixture *fx = *state;
    const Model *m = fx->mech->model;
    Capture c;
    FILE *f = capture_open(&c);
    double t_bad[3] = {0, 0.5, 0.4};
    errno = 0;
    assert_false(svg_write_animation(f, m, t_bad, fx->q, 3, NULL, 0, NULL));
    assert_int_equal(errno, EINVAL);
    double q_nan[9];
    memcpy(q_nan, fx->q, sizeof q_nan);
    q_nan[4] = NAN;
    assert_false(svg_write_animation(f, m, fx->t, q_nan, 1, NULL, 0, NULL));
    assert_false(svg_write_animation(f, m, fx->t, fx->q, 0, NULL, 0, NULL));
    SvgTrace bad = {.q = 40, .has_phi = true, .label = "x"};
    assert_false(svg_write_animation(f, m, fx->t, fx->q, 2, &bad, 1, NULL));
    char *s = capture_close(&c);
    assert_int_equal(strlen(s), 0);     /* nothing written on refusal */
    free(s);
}

/* One frame: a still picture, no animation, still a valid document. */
static void test_anim_single_frame(void **state)
{
    Fixture *fx = *state;
    Capture c;
    FILE *f = capture_open(&c);
    assert_true(svg_write_animation(f, fx->mech->model, fx->t + 30, fx->q + 30 * 9, 1, NULL, 0, NULL));
    char *s = capture_close(&c);
    assert_xml(s);
    assert_null(strstr(s, "<animate"));
    assert_int_equal(count(s, "class=\"link\""), 2);
    free(s);
}

/* Every statement kind: all_statements.mech moved by a made-up motion
   (the drawing does not need a consistent one). */
static const char all_statements[] =
    "mechanism all_statements\n"
    "param a = 0.5\nparam L0 = 1.2\nparam R = 0.25\nparam w = 2*pi\n"
    "body base x = 0 y = 0 phi = 0\n"
    "body slide x = 0.5 y = 0 phi = pi/6\n"
    "point tip x = 1.163325 y = 1\n"
    "coord theta = 0.985111\n"
    "body arm x = 1.301518 y = 1.208333 phi = 0.985111\n"
    "body wheel x = 2 y = R phi = 0\n"
    "body cart x = 0 y = -1 phi = 0\n"
    "weld fix: ground base\n"
    "prismatic guide: base slide axis(1, 0) angle = pi/6\n"
    "driver push: slide.x = 0.5 + 0.2*sin(w*t)\n"
    "pointline rail: ground(0, 1) tip axis(1, 0)\n"
    "distance act: slide tip length = L0 + 0.1*t\n"
    "constraint incl: (tip.x - slide.x)*sin(theta) - (tip.y - slide.y)*cos(theta) = 0\n"
    "revolute hinge: tip arm(-a/2, 0)\n"
    "driver swing: arm.phi = theta\n"
    "pointline floor: ground(0, R) wheel axis(1, 0)\n"
    "rolling roll: wheel radius = R\n"
    "driver spin: der(wheel.phi) = -w\n"
    "knife blade: cart(0.1, 0) axis(1, 0)\n"
    "velocity fwd: der(cart.x)*cos(cart.phi) + der(cart.y)*sin(cart.phi) = 1\n"
    "driver steer: cart.phi = 0.5*t\n";

/* all_statements moved by a made-up motion of n frames over t = 0 .. 0.025 (n - 1). */
static Fixture *load_all_statements(int n)
{
    Fixture *fx = load_text(all_statements);
    const Model *m = fx->mech->model;
    int nq = m->nq;
    fx->n = n;
    fx->t = malloc((size_t)n * sizeof *fx->t);
    fx->q = malloc((size_t)n * (size_t)nq * sizeof *fx->q);
    for (int k = 0; k < n; k++) {
        fx->t[k] = 0.025 * k;
        for (int i = 0; i < nq; i++)
            fx->q[(size_t)k * nq + i] = m->q0[i] + 0.1 * sin(0.7 * i + 0.15 * k);
    }
    return fx;
}

static void test_anim_all_kinds(void **state)
{
    (void)state;
    Fixture *fx = load_all_statements(41);
    const Model *m = fx->mech->model;
    SvgTrace tr;
    char err[256];
    assert_true(svg_parse_trace(m, "tip", &tr, err, sizeof err));
    assert_false(tr.has_phi);
    assert_false(svg_parse_trace(m, "tip(1, 0)", &tr, err, sizeof err));
    assert_non_null(strstr(err, "is a point; it takes no offset"));
    assert_false(svg_parse_trace(m, "theta", &tr, err, sizeof err));
    assert_non_null(strstr(err, "scalar coordinate"));
    assert_true(svg_parse_trace(m, "tip", &tr, err, sizeof err));
    char *s = animate(fx, &tr, 1, NULL);
    assert_int_equal(count(s, "class=\"disk\""), 1);
    assert_int_equal(count(s, "class=\"spoke\""), 1);
    assert_int_equal(count(s, "class=\"knife\""), 1);
    assert_int_equal(count(s, "class=\"distance\""), 1);
    assert_int_equal(count(s, "class=\"weld\""), 1);
    assert_int_equal(count(s, "class=\"particle\""), 1);
    assert_int_equal(count(s, "class=\"slider\""), 1);
    assert_int_equal(count(s, "class=\"guide\""), 3);       /* guide, rail, floor */
    assert_int_equal(count(s, "class=\"dot\""), 2);         /* on rail and floor */
    assert_int_equal(count(s, "class=\"trace\""), 1);
    /* every kind has a drawing of its own: none falls back to the generic one */
    assert_int_equal(count(s, "class=\"joint\""), 0);
    /* base (welded: reference point and the prismatic's point), arm (line),
       cart (its reference point and the knife point): wheel and slide are
       drawn as their disk and block */
    assert_int_equal(count(s, "class=\"link\""), 3);
    /* drivers: push (slide.x), swing (arm.phi, theta), spin (der(wheel.phi)), steer (cart.phi) */
    assert_non_null(strstr(s, "driver push: slide.x"));
    assert_non_null(strstr(s, "driver swing: theta, arm.phi") ? strstr(s, "driver swing: theta, arm.phi")
                                                               : strstr(s, "driver swing: arm.phi, theta"));
    assert_non_null(strstr(s, "driver spin: der(wheel.phi)"));
    assert_int_equal(count(s, "class=\"drive\""), 3);       /* arm, wheel, cart turn */
    /* time does not start at 0 */
    assert_non_null(strstr(s, ">t = 0.000"));
    assert_non_null(strstr(s, ">t = 1.000"));
    xmllint_if_present(s);
    free(s);
    fixture_free(fx);
}

/* P = r + A(phi) s of attachment a at coordinates q, written out. */
static void attach_at(Attach a, const double *q, double *x, double *y)
{
    if (a.q < 0) {
        *x = a.sx;
        *y = a.sy;
        return;
    }
    double phi = a.has_phi ? q[a.q + 2] : 0;
    *x = q[a.q] + cos(phi) * a.sx - sin(phi) * a.sy;
    *y = q[a.q + 1] + sin(phi) * a.sx + cos(phi) * a.sy;
}

/* The drawing a joint kind gets when the renderer has none for it: a line
   between two attachments (under the bodies), a square at one (over them),
   nothing for a row statement; it follows the attachments and is written
   as well-formed SVG. */
static void test_anim_generic_drawing(void **state)
{
    (void)state;
    Fixture *fx = load_all_statements(41);
    const Model *m = fx->mech->model;
    Scene sc;
    scene_init(&sc, m, fx->t, fx->q, fx->n, NULL, 0, 200);
    sc.L = 1;
    sc.px = 0.01;
    int lines = 0, marks = 0;
    const double *q7 = fx->q + (size_t)7 * m->nq;
    for (int j = 0; j < m->njoints; j++) {
        const Joint *jt = &m->joints[j];
        int na = joint_info[jt->kind].attachments;
        for (int over = 0; over < 2; over++) {
            int before = sc.nsh;
            scene_draw_generic(&sc, jt, over);
            bool drawn = over ? na == 1 : na == 2;
            assert_int_equal(sc.nsh - before, drawn);
            if (!drawn)
                continue;
            const Shape *sh = &sc.sh[before];
            assert_string_equal(sh->cls, "joint");
            assert_string_equal(sh->name, jt->name);
            assert_int_equal(sh->kind, over ? SHAPE_MARK : SHAPE_POLYLINE);
            assert_int_equal(sh->nv, na);
            for (int k = 0; k < na; k++) {
                double x, y, ex, ey;
                scene_vtx_world(&sc.v[sh->v0 + k], q7, &x, &y);
                attach_at(k ? jt->b : jt->a, q7, &ex, &ey);
                assert_near(x, ex, 0, 1e-12);
                assert_near(y, ey, 0, 1e-12);
            }
            lines += !over;
            marks += over;
        }
    }
    /* weld, prismatic, 2 pointlines, distance, revolute; rolling, knife */
    assert_int_equal(lines, 6);
    assert_int_equal(marks, 2);
    SvgAnimOptions o = svg_anim_default_options();
    SvgPixelMap pm = svg_pixel_map(svg_scene_extent(&sc, true), &o, 4);   /* 4 drivers */
    Capture c;
    FILE *f = capture_open(&c);
    svg_write_scene(f, &sc, &pm, "generic", &o);
    char *s = capture_close(&c);
    assert_xml(s);
    assert_int_equal(count(s, "<polyline class=\"joint\" points=\""), 6);
    assert_int_equal(count(s, "<rect class=\"joint\""), 2);
    assert_int_equal(count(s, "style=\"stroke:#444;fill:none\" stroke-width=\"1.5\">"), 6);
    assert_non_null(strstr(s, "<title>blade</title>"));
    keep_copy(s, "generic");
    free(s);
    scene_free(&sc);
    fixture_free(fx);
}

/* The outline of a body: hull of its local points, counter-clockwise, with
   repeated, interior and collinear points dropped. */
static void test_hull(void **state)
{
    (void)state;
    HullPoint h[8];
    HullPoint square[] = {{1, 1}, {0, 0}, {0.5, 0.4}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0}};
    assert_int_equal(hull_convex(square, 7, h, 1e-9), 4);
    static const HullPoint ccw[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; i++) {
        assert_near(h[i].x, ccw[i].x, 0, 0);
        assert_near(h[i].y, ccw[i].y, 0, 0);
    }
    HullPoint line[] = {{2, 1}, {0, 0}, {1, 0.5}, {-2, -1}};
    assert_int_equal(hull_convex(line, 4, h, 1e-9), 2);
    assert_near(h[0].x, -2, 0, 0);
    assert_near(h[1].x, 2, 0, 0);
    /* within tol: one point (a body drawn as a mark) */
    HullPoint one[] = {{0.3, 0.3}, {0.3, 0.3 + 1e-12}, {0.3, 0.3}};
    assert_int_equal(hull_convex(one, 3, h, 1e-9), 1);
    assert_near(h[0].x, 0.3, 0, 0);
    /* a triangle whose third point is barely off the line still counts */
    HullPoint tri[] = {{0, 0}, {1, 0}, {0.5, 1e-3}};
    assert_int_equal(hull_convex(tri, 3, h, 1e-9), 3);
}

/* ---- plots ---- */

static void test_plot(void **state)
{
    Fixture *fx = *state;
    SvgSeries ser[3] = {
        {"crank.phi", fx->q + 2, 9},
        {"slider.x", fx->q + 6, 9},
        {"<odd & name>", fx->q + 3, 9},
    };
    Capture c;
    FILE *f = capture_open(&c);
    assert_true(svg_write_plot(f, "slider_crank: q & more", fx->t, fx->n, ser, 3));
    char *s = capture_close(&c);
    assert_xml(s);
    xmllint_if_present(s);
    keep_copy(s, "plot");
    assert_int_equal(count(s, "class=\"series\""), 3);
    assert_non_null(strstr(s, "<g class=\"legend\">"));
    assert_non_null(strstr(s, ">crank.phi</text>"));
    assert_non_null(strstr(s, ">slider.x</text>"));
    assert_non_null(strstr(s, ">&lt;odd &amp; name&gt;</text>"));
    assert_non_null(strstr(s, "slider_crank: q &amp; more"));
    assert_non_null(strstr(s, "class=\"axis\""));
    /* x ticks 0, 0.2, ..., 1; y from 0 to 2 pi widened to whole steps: 0 .. 7 */
    assert_non_null(strstr(s, ">0.0</text>"));
    assert_non_null(strstr(s, ">0.2</text>"));
    assert_non_null(strstr(s, ">1.0</text>"));
    assert_non_null(strstr(s, ">7</text>"));
    assert_null(strstr(s, ">8</text>"));
    assert_non_null(strstr(s, ">t</text>"));
    free(s);
}

/* NaN makes a gap; a long series is thinned per pixel column. */
static void test_plot_gaps_and_thinning(void **state)
{
    (void)state;
    int n = 100001;
    double *t = malloc((size_t)n * sizeof *t), *v = malloc((size_t)n * sizeof *v);
    for (int k = 0; k < n; k++) {
        t[k] = 1e-4 * k;
        v[k] = sin(30 * t[k]) + (k == 50000 ? 5 : 0);     /* one spike */
    }
    v[20000] = NAN;
    SvgSeries ser = {"v", v, 1};
    Capture c;
    FILE *f = capture_open(&c);
    assert_true(svg_write_plot(f, "long", t, n, &ser, 1));
    char *s = capture_close(&c);
    assert_xml(s);
    assert_int_equal(count(s, "class=\"series\""), 2);     /* split at the NaN */
    assert_true(strlen(s) < 60000);
    /* the spike survives the thinning: y axis reaches 5 */
    assert_non_null(strstr(s, ">5</text>") ? strstr(s, ">5</text>") : strstr(s, ">5.0</text>"));
    free(s);
    /* constant and empty input */
    for (int k = 0; k < 10; k++)
        v[k] = 3;
    f = capture_open(&c);
    assert_true(svg_write_plot(f, NULL, t, 10, &ser, 1));
    assert_true(svg_write_plot(f, "none", t, 10, NULL, 0));
    s = capture_close(&c);
    free(s);
    f = capture_open(&c);
    double tb[2] = {1, 0};
    assert_false(svg_write_plot(f, "bad", tb, 2, &ser, 1));
    assert_false(svg_write_plot(f, "bad", t, 0, &ser, 1));
    s = capture_close(&c);
    assert_int_equal(strlen(s), 0);
    free(s);
    free(t);
    free(v);
}

static void test_plot_resolve(void **state)
{
    Fixture *fx = *state;
    const Model *m = fx->mech->model;
    SvgPlotVar v[8];
    char err[512], name[64];
    assert_int_equal(svg_plot_resolve(m, "crank.phi, d(rod.x),dd( slider.x )", v, 8, err, sizeof err), 3);
    assert_int_equal(v[0].coord, 2);
    assert_int_equal(v[0].order, 0);
    assert_int_equal(v[1].coord, 3);
    assert_int_equal(v[1].order, 1);
    assert_int_equal(v[2].coord, 6);
    assert_int_equal(v[2].order, 2);
    svg_plot_var_name(m, v[1], name, sizeof name);
    assert_string_equal(name, "d(rod.x)");
    svg_plot_var_name(m, v[2], name, sizeof name);
    assert_string_equal(name, "dd(slider.x)");
    struct { const char *list, *expect; } cases[] = {
        {"crnk.phi", "unknown coordinate 'crnk.phi'; the 9 coordinates are crank.x, crank.y, "
                     "crank.phi, rod.x, rod.y, rod.phi, slider.x, slider.y, slider.phi"},
        {"crank", "did you mean crank.x, crank.y, crank.phi"},
        {"d(crank.phi", "missing ')'"},
        {"crank.x,,rod.x", "empty name"},
        {"", "empty name"},
        {"d(nope)", "unknown coordinate 'nope'"},
        {"ddd(crank.x)", "unknown coordinate 'ddd(crank.x)'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        err[0] = '\0';
        if (svg_plot_resolve(m, cases[i].list, v, 8, err, sizeof err) != -1)
            fail_msg("accepted --plot-vars '%s'", cases[i].list);
        if (!strstr(err, cases[i].expect))
            fail_msg("--plot-vars '%s': message '%s' lacks '%s'", cases[i].list, err, cases[i].expect);
    }
    assert_int_equal(svg_plot_resolve(m, "crank.x,crank.y,crank.phi", v, 2, err, sizeof err), -1);
    assert_non_null(strstr(err, "more than 2"));
}

/* ---- formatting helpers ---- */

static void test_common(void **state)
{
    (void)state;
    char b[SVG_NUM_MAX];
    assert_string_equal(svg_fmt_fixed(b, 12.3456, 1), "12.3");
    assert_string_equal(svg_fmt_fixed(b, 12.0, 1), "12");
    assert_string_equal(svg_fmt_fixed(b, -0.04, 1), "0");
    assert_string_equal(svg_fmt_fixed(b, 1e300, 1), "1000000000000000");
    assert_string_equal(svg_fmt_sig(b, 0.0123456, 4), "0.01235");
    assert_string_equal(svg_fmt_sig(b, 123456, 4), "123456");
    assert_string_equal(svg_fmt_sig(b, 2.5, 4), "2.5");
    assert_near(svg_nice_step(1, 6), 0.2, 0, 1e-15);
    assert_near(svg_nice_step(6.3, 6), 1, 0, 1e-15);
    assert_near(svg_nice_step(0.03, 6), 0.005, 0, 1e-15);
    assert_near(svg_nice_step(170, 6), 20, 0, 1e-12);
    assert_near(svg_nice_step(400, 6), 50, 0, 1e-12);
}

/* ---- progress ---- */

static void test_progress(void **state)
{
    (void)state;
    Capture c;
    FILE *f = capture_open(&c);
    Progress p;
    /* the first second shows nothing */
    progress_start_on(&p, f, true, "run", 10);
    for (int i = 0; i <= 10; i++)
        progress_update(&p, i);
    progress_finish(&p);
    fflush(f);
    assert_int_equal(c.len, 0);
    /* without the delay: a bar, then a cleared line */
    progress_start_on(&p, f, true, "run", 10);
    p.delay = 0;
    p.interval = 0;
    progress_update(&p, 5);
    fflush(f);
    assert_non_null(strstr(c.text, "\rrun ["));
    assert_non_null(strstr(c.text, " 50%  5/10"));
    progress_finish(&p);
    char *s = capture_close(&c);
    size_t len = strlen(s);
    assert_true(len > 4 && strcmp(s + len - 4, "\r\033[K") == 0);
    assert_null(strchr(s, '\n'));
    free(s);
    /* disabled (not a terminal): nothing at all */
    f = capture_open(&c);
    progress_start_on(&p, f, false, "bench", 0);
    p.delay = 0;
    progress_update(&p, 3);
    progress_finish(&p);
    s = capture_close(&c);
    assert_int_equal(strlen(s), 0);
    free(s);
    /* stderr here is not a terminal under `make check`: progress_start is quiet */
    if (!isatty(STDERR_FILENO)) {
        progress_start(&p, "run", 5);
        assert_null(p.out);
        progress_update(&p, 1);
        progress_finish(&p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_xml_checker),
        cmocka_unit_test(test_anim_structure),
        cmocka_unit_test(test_anim_equal_scales),
        cmocka_unit_test(test_anim_subsample),
        cmocka_unit_test(test_anim_traces_and_escaping),
        cmocka_unit_test(test_parse_trace_errors),
        cmocka_unit_test(test_anim_bad_input),
        cmocka_unit_test(test_anim_single_frame),
        cmocka_unit_test(test_anim_all_kinds),
        cmocka_unit_test(test_anim_generic_drawing),
        cmocka_unit_test(test_hull),
        cmocka_unit_test(test_plot),
        cmocka_unit_test(test_plot_gaps_and_thinning),
        cmocka_unit_test(test_plot_resolve),
        cmocka_unit_test(test_common),
        cmocka_unit_test(test_progress),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
