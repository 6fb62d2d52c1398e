/* svg_anim.c - an animated SVG of a mechanism's motion (SMIL, no script, any browser): the entry.
 *
 * Checks the run, keeps at most max_frames frames, sizes the picture from
 * the extent of the motion (symbols are drawn a fixed number of pixels
 * big, so the scale is estimated first), builds the scene (scene.c), keeps
 * fewer frames when the file would outgrow max_bytes, fits everything into
 * the drawing area and writes the document (svg_write.c).
 */
#include "svg_anim.h"

#include "scene.h"
#include "svg_write.h"

#include <errno.h>
#include <math.h>
#include <string.h>

SvgAnimOptions svg_anim_default_options(void)
{
    SvgAnimOptions o = {
        .max_frames = 200,
        .min_duration = 2,
        .max_duration = 60,
        .width = 760,
        .height = 520,
        .max_bytes = 4000000,
        .view = SVG_VIEW_ISO,
        .forces = NULL,
        .nforces = 0,
    };
    return o;
}

static bool valid_input(const Model *m, const double *t, const double *q, int n,
                        const SvgTrace *tr, int ntr)
{
    if (!m || !t || !q || n < 1 || m->nq < 1 || (ntr > 0 && !tr) || ntr < 0)
        return false;
    for (int k = 0; k < n; k++) {
        if (!isfinite(t[k]) || (k > 0 && t[k] < t[k - 1]))
            return false;
        for (int i = 0; i < m->nq; i++)
            if (!isfinite(q[(size_t)k * m->nq + i]))
                return false;
    }
    for (int i = 0; i < ntr; i++) {
        int need = tr[i].spatial ? (tr[i].has_phi ? 7 : 3) : tr[i].has_phi ? 3 : 2;
        if (tr[i].q < 0 || tr[i].q + need > m->nq || !isfinite(tr[i].sx) || !isfinite(tr[i].sy)
            || (tr[i].spatial && !isfinite(tr[i].sz)) || tr[i].spatial != m->spatial)
            return false;
    }
    return true;
}

/* Each moving vertex costs about 15 bytes per frame ("123.4,567.8 ", and
   the elements around): a big mechanism keeps fewer frames, 10 at least. */
static void fit_byte_budget(Scene *sc, const SvgAnimOptions *o)
{
    long moving = 0;
    for (int i = 0; i < sc->nv; i++)
        moving += sc->v[i].q >= 0;
    long budget = moving > 0 ? o->max_bytes / (15 * moving) : o->max_frames;
    if (budget < sc->nf)
        scene_keep_frames(sc, budget < 10 ? 10 : (int)budget);
}

bool svg_write_animation_opt(FILE *out, const Model *m, const double *t, const double *q,
                             int nframes, const SvgTrace *traces, int ntraces,
                             const char *title, const SvgAnimOptions *opt)
{
    SvgAnimOptions o = opt ? *opt : svg_anim_default_options();
    if (!out || !valid_input(m, t, q, nframes, traces, ntraces) || o.width < 50
        || o.height < 50 || (unsigned)o.view > SVG_VIEW_ISO) {
        errno = EINVAL;
        return false;
    }
    Scene sc;
    scene_init(&sc, m, t, q, nframes, traces, ntraces, o.max_frames);
    sc.view = o.view;
    if (!m->spatial && o.nforces > 0 && o.forces) {
        sc.forces = o.forces;
        sc.nforces = o.nforces;
    }
    SvgBox b = svg_scene_extent(&sc, false);
    sc.L = fmax(b.x1 - b.x0, b.y1 - b.y0);
    if (!(sc.L > 0))
        sc.L = 1;
    sc.px = 1 / svg_pixel_map(b, &o, 0).s;
    scene_build(&sc);
    fit_byte_budget(&sc, &o);

    scene_scale_forces(&sc);
    SvgBox all = svg_scene_extent(&sc, true);
    SvgBox first = svg_scene_extent(&sc, false);
    svg_box_add(&all, first.x0, first.y0);
    svg_box_add(&all, first.x1, first.y1);
    int footer = ntraces + (sc.force_max > 0);
    for (int j = 0; j < m->njoints; j++)
        footer += m->joints[j].kind == JOINT_DRIVER;
    SvgPixelMap pm = svg_pixel_map(all, &o, footer);

    clearerr(out);
    svg_write_scene(out, &sc, &pm, title ? title : m->name, &o);
    bool ok = fflush(out) == 0 && !ferror(out);
    scene_free(&sc);
    return ok;
}

bool svg_write_animation(FILE *out, const Model *m, const double *t, const double *q,
                         int nframes, const SvgTrace *traces, int ntraces, const char *title)
{
    return svg_write_animation_opt(out, m, t, q, nframes, traces, ntraces, title, NULL);
}
