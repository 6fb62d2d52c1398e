/* info.c - libmechc's structure report: mechc info's analysis in a handle, as a struct, and its JSON as a string. */
#define _GNU_SOURCE 1     /* open_memstream */
#include "lib.h"

#include "../analysis/common.h"
#include "../base/arena.h"
#include "../cli/cli.h"
#include "../structure/info.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mechc_info_report {
    InfoReport rep;
};

mechc_info_options mechc_info_defaults(void)
{
    AnalysisOptions a = analysis_default_options();
    return (mechc_info_options){.rank_tol = a.rank_tol, .samples = a.samples,
                                .max_dense = a.max_dense};
}

/* o as info_analyse takes it; false when it cannot be used. Dense is
   allowed up to max_dense; auto dense up to ANALYSIS_DENSE_MAX_NQ
   coordinates as well. */
static bool info_options(const Model *m, const mechc_info_options *o, AnalysisOptions *a)
{
    int linear = lib_name_index(analysis_linear_names, o->linear, ANALYSIS_LINEAR_AUTO);
    if (linear < 0 || !isfinite(o->t) || o->samples < 1 || !(o->max_dense >= 0) || isnan(o->rank_tol)
        || (o->follow && o->q))
        return false;
    *a = analysis_default_options();
    a->rank_tol = o->rank_tol;
    a->samples = o->samples;
    a->max_dense = o->max_dense;
    bool fits = (double)m->nr * (double)m->nq <= o->max_dense;
    switch ((AnalysisLinear)linear) {
    case ANALYSIS_LINEAR_DENSE:
        return fits;
    case ANALYSIS_LINEAR_SPARSE:
        a->max_dense = -1;
        break;
    case ANALYSIS_LINEAR_AUTO:
        if (m->nq > ANALYSIS_DENSE_MAX_NQ)
            a->max_dense = -1;
        break;
    }
    return true;
}

mechc_info_report *mechc_info_with(mechc_model *m, const mechc_info_options *o, mechc_diag *d)
{
    mechc_info_options defaults = mechc_info_defaults();
    if (!o)
        o = &defaults;
    AnalysisOptions a;
    if (!m || !info_options(m->mech->model, o, &a)) {
        lib_fail(d, MECHC_EARG, "mechc_info_with: no model, an unknown linear algebra, "
                 "samples < 1, follow with q, or dense beyond max_dense");
        return NULL;
    }
    InfoAt at = {.follow = o->follow != 0, .q = o->q};
    mechc_info_report *r = xcalloc(1, sizeof *r);
    Diag diag;
    diag_init(&diag, m->name, NULL, 0);
    if (!info_analyse_at(m->mech, o->t, at.follow || at.q ? &at : NULL, &a, &r->rep, &diag)) {
        lib_fail_diag(d, MECHC_EARG, &diag);
        free(r);
        return NULL;
    }
    lib_ok(d);
    return r;
}

const InfoReport *lib_info_report(const mechc_info_report *r) { return &r->rep; }

mechc_status mechc_info_report_summary(const mechc_info_report *r, mechc_info *info,
                                       int *redundant, double *q)
{
    if (!r || !info)
        return MECHC_EARG;
    const InfoReport *rep = &r->rep;
    *info = (mechc_info){
        .nq = rep->nq, .nh = rep->nh, .nv = rep->nv, .nr = rep->nr, .dof = rep->dof,
        .mobility = rep->mobility, .assembled = rep->assembled, .rank = rep->rank,
        .nredundant = rep->nredundant, .rank_all = rep->rank_all, .dof_rank = rep->dof_rank,
        .mobility_rank = rep->mobility_rank, .generic_rank = rep->generic_rank,
        .sigma_max = rep->sigma_max, .sigma_min = rep->sigma_min, .cond = rep->cond};
    snprintf(info->singularity, sizeof info->singularity, "%s",
             info_singularity_names[rep->singularity]);
    for (int i = 0; redundant && i < rep->nr; i++)
        redundant[i] = rep->rows[i].redundant;
    if (q)
        memcpy(q, rep->q, (size_t)rep->nq * sizeof *q);
    return MECHC_OK;
}

char *mechc_info_report_json(const mechc_info_report *r)
{
    if (!r)
        return NULL;
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        abort();            /* out of memory, as xmalloc */
    info_print_json(f, &r->rep);
    fclose(f);
    return text;
}

void mechc_info_report_free(mechc_info_report *r)
{
    if (!r)
        return;
    info_report_free(&r->rep);
    free(r);
}

mechc_status mechc_info_at(mechc_model *m, double t, mechc_info *info, int *redundant,
                           double *q, mechc_diag *d)
{
    if (!m || !info)
        return lib_fail(d, MECHC_EARG, "mechc_info_at: no model or no info");
    mechc_info_options o = mechc_info_defaults();
    o.t = t;
    mechc_info_report *r = mechc_info_with(m, &o, d);
    if (!r)
        return d ? d->status : MECHC_EARG;
    mechc_info_report_summary(r, info, redundant, q);
    mechc_info_report_free(r);
    return MECHC_OK;
}

char *mechc_info_json(mechc_model *m, mechc_diag *d)
{
    if (!m) {
        lib_fail(d, MECHC_EARG, "mechc_info_json: no model");
        return NULL;
    }
    mechc_info_report *r = mechc_info_with(m, NULL, d);
    char *text = r ? mechc_info_report_json(r) : NULL;
    mechc_info_report_free(r);
    return text;
}
