/* model.c - libmechc's models: loading, diagnostics as values, sizes, names, initial values, design. */
#include "lib.h"

#include "../base/arena.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *mechc_version(void) { return MECHC_VERSION; }

const char *mechc_status_text(mechc_status status)
{
    switch (status) {
    case MECHC_OK: return "ok";
    case MECHC_EINPUT: return "bad mechanism input";
    case MECHC_EARG: return "bad argument";
    case MECHC_ENOTAVAIL: return "not available for this mechanism";
    case MECHC_ECOMPILE: return "the engine could not compile";
    case MECHC_EANALYSIS: return "the analysis failed";
    case MECHC_ENOTRUNNABLE: return "not runnable as it is";
    }
    return "unknown status";
}

void mechc_free(void *p) { free(p); }

int lib_name_index(const char *const *names, const char *name, int fallback)
{
    if (!name)
        return fallback;
    for (int i = 0; names[i]; i++)
        if (strcmp(names[i], name) == 0)
            return i;
    return -1;
}

void lib_ok(mechc_diag *d)
{
    if (d)
        memset(d, 0, sizeof *d);
}

mechc_status lib_fail(mechc_diag *d, mechc_status status, const char *fmt, ...)
{
    if (!d)
        return status;
    memset(d, 0, sizeof *d);
    d->status = status;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(d->message, sizeof d->message, fmt, ap);
    va_end(ap);
    return status;
}

mechc_status lib_fail_diag(mechc_diag *d, mechc_status status, const Diag *from)
{
    if (!d)
        return status;
    lib_fail(d, status, "%s", from->message);
    if (from->file)
        snprintf(d->file, sizeof d->file, "%s", from->file);
    if (from->has_pos) {
        d->line = from->line;
        d->column = from->col;
    }
    return status;
}

/* GSL's error handler is the process's: the drivers turn it off around
   their calls and restore it, which threads running analyses at once
   would interleave, restoring GSL's default (abort) under another's
   feet. Off once and for all, before the first model, every save and
   restore keeps it off (the drivers check every status). */
static pthread_once_t gsl_once = PTHREAD_ONCE_INIT;
static void gsl_quiet(void) { gsl_set_error_handler_off(); }

_Static_assert((int)MECHC_DIAG_LINE_MAX == (int)DIAG_LINE_MAX, "mechc_diag's source line is Diag's");

mechc_limits mechc_default_limits(void)
{
    MechLimits l = mech_default_limits();
    return (mechc_limits){
        .max_file_bytes = l.max_file_bytes, .max_line_length = l.max_line_length,
        .max_name_length = l.max_name_length, .max_depth = l.max_depth,
        .max_expr_tokens = l.max_expr_tokens, .max_coords = l.max_coords,
        .max_rows = l.max_rows, .max_jac_entries = l.max_jac_entries,
        .max_nodes = l.max_nodes, .max_code_ops = l.max_code_ops, .jac_advice = l.jac_advice};
}

static MechLimits mech_limits(const mechc_limits *l)
{
    return (MechLimits){
        .max_file_bytes = l->max_file_bytes, .max_line_length = l->max_line_length,
        .max_name_length = l->max_name_length, .max_depth = l->max_depth,
        .max_expr_tokens = l->max_expr_tokens, .max_coords = l->max_coords,
        .max_rows = l->max_rows, .max_jac_entries = l->max_jac_entries,
        .max_nodes = l->max_nodes, .max_code_ops = l->max_code_ops, .jac_advice = l->jac_advice};
}

/* Every limit within what the command's --max-... options accept
   (max_jac_entries 0 too: not checked while loading). */
static bool limits_valid(const mechc_limits *given)
{
    mechc_limits l = *given;
    if (l.max_jac_entries == 0)
        l.max_jac_entries = 1;
#define IN_RANGE(field, option, lo, hi) &&l.field >= (lo) && l.field <= (hi)
    return true MECH_LIMIT_RANGES(IN_RANGE);
#undef IN_RANGE
}

/* pipeline_load or pipeline_load_text into a new model; NULL with d (and
   source_line, when given) filled. */
static mechc_model *load(const char *path, const char *text, const char *name,
                         const mechc_limits *l, mechc_diag *d, char *source_line)
{
    pthread_once(&gsl_once, gsl_quiet);
    mechc_model *m = xcalloc(1, sizeof *m);
    const char *given = path ? path : name;
    size_t len = strlen(given) + 1;
    m->name = memcpy(xmalloc(len), given, len);
    mechc_limits defaults = mechc_default_limits();
    MechLimits limits = mech_limits(l ? l : &defaults);
    m->mech = path ? pipeline_load(m->name, &limits, &m->diag)
                   : pipeline_load_text(text, m->name, &limits, &m->diag);
    if (!m->mech) {
        lib_fail_diag(d, MECHC_EINPUT, &m->diag);
        if (source_line && m->diag.has_pos)
            snprintf(source_line, MECHC_DIAG_LINE_MAX, "%s", m->diag.source_line);
        free(m->name);
        free(m);
        return NULL;
    }
    lib_ok(d);
    return m;
}

mechc_model *mechc_load_file(const char *path, mechc_diag *d)
{
    return mechc_load_file_with(path, NULL, d, NULL);
}

mechc_model *mechc_load_file_with(const char *path, const mechc_limits *limits, mechc_diag *d,
                                  char *source_line)
{
    if (source_line)
        source_line[0] = '\0';
    if (!path) {
        lib_fail(d, MECHC_EARG, "mechc_load_file: no path");
        return NULL;
    }
    if (limits && !limits_valid(limits)) {
        lib_fail(d, MECHC_EARG, "mechc_load_file_with: a limit out of its range "
                 "(examples/README.md, Limits)");
        return NULL;
    }
    return load(path, NULL, NULL, limits, d, source_line);
}

mechc_model *mechc_load_string(const char *text, const char *name, mechc_diag *d)
{
    if (!text) {
        lib_fail(d, MECHC_EARG, "mechc_load_string: no text");
        return NULL;
    }
    return load(NULL, text, name ? name : "<string>", NULL, d, NULL);
}

void mechc_model_free(mechc_model *m)
{
    if (!m)
        return;
    pipeline_free(m->mech);
    free(m->name);
    free(m);
}

int mechc_nq(const mechc_model *m) { return m ? m->mech->model->nq : 0; }
int mechc_nh(const mechc_model *m) { return m ? m->mech->model->nh : 0; }
int mechc_nv(const mechc_model *m) { return m ? m->mech->model->nv : 0; }
int mechc_nr(const mechc_model *m) { return m ? m->mech->model->nr : 0; }
int mechc_nout(const mechc_model *m) { return m ? m->mech->model->nout : 0; }
int mechc_nbodies(const mechc_model *m) { return m ? m->mech->model->nbodies : 0; }
int mechc_np(const mechc_model *m) { return m ? m->mech->model->np : 0; }
int mechc_has_dynamics(const mechc_model *m) { return m ? m->mech->model->nmasses > 0 : 0; }
int mechc_is_spatial(const mechc_model *m) { return m ? m->mech->model->spatial : 0; }
const char *mechc_model_name(const mechc_model *m) { return m ? m->mech->model->name : NULL; }

const char *mechc_coord_name(const mechc_model *m, int i)
{
    if (!m)
        return NULL;
    const Model *mo = m->mech->model;
    return i >= 0 && i < mo->nq ? mo->coord_names[i] : NULL;
}

const char *mechc_row_name(const mechc_model *m, int i)
{
    if (!m)
        return NULL;
    const Model *mo = m->mech->model;
    return i >= 0 && i < mo->nr ? mo->rows[i].name : NULL;
}

const char *mechc_output_name(const mechc_model *m, int i)
{
    if (!m)
        return NULL;
    const Model *mo = m->mech->model;
    return i >= 0 && i < mo->nout ? mo->outputs[i].name : NULL;
}

const char *mechc_body_name(const mechc_model *m, int i)
{
    if (!m)
        return NULL;
    const Model *mo = m->mech->model;
    return i >= 0 && i < mo->nbodies ? mo->bodies[i].name : NULL;
}

const char *mechc_design_name(const mechc_model *m, int i)
{
    if (!m)
        return NULL;
    const Model *mo = m->mech->model;
    return i >= 0 && i < mo->np ? mo->design_names[i] : NULL;
}

int mechc_coord_index(const mechc_model *m, const char *name)
{
    if (!m)
        return -1;
    const Model *mo = m->mech->model;
    for (int i = 0; name && i < mo->nq; i++)
        if (strcmp(mo->coord_names[i], name) == 0)
            return i;
    return -1;
}

mechc_status mechc_body_coords(const mechc_model *m, int i, int *first, int *count)
{
    if (!m)
        return MECHC_EARG;
    const Model *mo = m->mech->model;
    if (i < 0 || i >= mo->nbodies)
        return MECHC_EARG;
    if (first)
        *first = mo->bodies[i].q;
    if (count)
        *count = mo->bodies[i].nq;
    return MECHC_OK;
}

const double *mechc_q0(const mechc_model *m) { return m ? m->mech->model->q0 : NULL; }

mechc_status mechc_qd0(const mechc_model *m, double *qd0)
{
    if (!m || !qd0)
        return MECHC_EARG;
    memset(qd0, 0, (size_t)m->mech->model->nq * sizeof *qd0);
    return MECHC_OK;
}

mechc_status mechc_design(const mechc_model *m, double *p)
{
    if (!m)
        return MECHC_EARG;
    const Model *mo = m->mech->model;
    if (!p && mo->np > 0)
        return MECHC_EARG;
    if (mo->np > 0)
        memcpy(p, mo->dag.param_values, (size_t)mo->np * sizeof *p);
    return MECHC_OK;
}

mechc_status mechc_set_design(mechc_model *m, const char *name, double value)
{
    if (!m)
        return MECHC_EARG;
    Model *mo = m->mech->model;
    if (mo->np == 0)
        return MECHC_ENOTAVAIL;
    if (!name || !isfinite(value))
        return MECHC_EARG;
    for (int j = 0; j < mo->np; j++)
        if (strcmp(mo->design_names[j], name) == 0) {
            mo->dag.param_values[j] = value;    /* what the kernels read (engine.c binds it) */
            return MECHC_OK;
        }
    return MECHC_EARG;
}

mechc_status mechc_set_design_vector(mechc_model *m, const double *p)
{
    if (!m)
        return MECHC_EARG;
    Model *mo = m->mech->model;
    if (mo->np == 0)
        return MECHC_ENOTAVAIL;
    for (int j = 0; p && j < mo->np; j++)
        if (!isfinite(p[j]))
            return MECHC_EARG;
    model_set_design(mo, p);
    return MECHC_OK;
}
