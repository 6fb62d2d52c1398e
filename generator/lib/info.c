/* info.c - libmechc's structure report: mechc info's analysis as a struct, and its JSON as a string. */
#define _GNU_SOURCE 1     /* open_memstream */
#include "lib.h"

#include "../analysis/common.h"
#include "../cli/cli.h"
#include "../structure/info.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* info_analyse with the command's default options (--linear auto). */
static bool analyse(mechc_model *m, double t, InfoReport *rep, mechc_diag *d)
{
    AnalysisOptions o = analysis_default_options();
    if (m->mech->model->nq > ANALYSIS_DENSE_MAX_NQ)
        o.max_dense = -1;       /* choose_linear's auto: sparse QR */
    Diag diag;
    diag_init(&diag, m->name, NULL, 0);
    if (!info_analyse(m->mech, t, &o, rep, &diag)) {
        lib_fail_diag(d, MECHC_EARG, &diag);
        return false;
    }
    lib_ok(d);
    return true;
}

mechc_status mechc_info_at(mechc_model *m, double t, mechc_info *info, int *redundant,
                           double *q, mechc_diag *d)
{
    if (!m || !info)
        return lib_fail(d, MECHC_EARG, "mechc_info_at: no model or no info");
    InfoReport rep;
    if (!analyse(m, t, &rep, d))
        return d ? d->status : MECHC_EARG;
    *info = (mechc_info){
        .nq = rep.nq, .nh = rep.nh, .nv = rep.nv, .nr = rep.nr, .dof = rep.dof,
        .mobility = rep.mobility, .assembled = rep.assembled, .rank = rep.rank,
        .nredundant = rep.nredundant, .rank_all = rep.rank_all, .dof_rank = rep.dof_rank,
        .mobility_rank = rep.mobility_rank, .generic_rank = rep.generic_rank,
        .sigma_max = rep.sigma_max, .sigma_min = rep.sigma_min, .cond = rep.cond};
    snprintf(info->singularity, sizeof info->singularity, "%s",
             info_singularity_names[rep.singularity]);
    for (int i = 0; redundant && i < rep.nr; i++)
        redundant[i] = rep.rows[i].redundant;
    if (q)
        memcpy(q, rep.q, (size_t)rep.nq * sizeof *q);
    info_report_free(&rep);
    return MECHC_OK;
}

char *mechc_info_json(mechc_model *m, mechc_diag *d)
{
    if (!m) {
        lib_fail(d, MECHC_EARG, "mechc_info_json: no model");
        return NULL;
    }
    InfoReport rep;
    if (!analyse(m, 0, &rep, d))
        return NULL;
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        abort();            /* out of memory, as xmalloc */
    info_print_json(f, &rep);
    fclose(f);
    info_report_free(&rep);
    return text;
}
