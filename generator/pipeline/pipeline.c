/* pipeline.c - loads: runs the stages up to the derivatives in order and times them; every command starts here. */
#include "pipeline.h"

#include "../base/arena.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

double pipeline_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static Mech *load(char *text, int len, const char *path, const MechLimits *limits, Diag *diag)
{
    double t0 = pipeline_now();
    Mech *mech = xcalloc(1, sizeof *mech);
    mech->text = text;
    mech->limits = *limits;
    Arena scratch;
    arena_init(&scratch);
    char *stem = model_file_stem(&scratch, path);
    mech->model = model_load(text, len, path, stem, limits, diag);
    arena_free(&scratch);
    if (!mech->model) {
        free(mech);     /* text stays alive through diag; the caller frees it */
        return NULL;
    }
    double t1 = pipeline_now();
    mech->load_seconds = t1 - t0;
    if (!kinematics_build(mech->model, &mech->kin, diag)) {
        model_free(mech->model);
        free(mech);
        return NULL;
    }
    mech->diff_seconds = pipeline_now() - t1;
    return mech;
}

Mech *pipeline_load(const char *path, const MechLimits *limits, Diag *diag)
{
    int len = 0;
    diag_init(diag, path, NULL, 0);
    char *text = model_read_file(path, limits, &len, diag);
    if (!text)
        return NULL;
    Mech *mech = load(text, len, path, limits, diag);
    if (!mech) {
        /* diag already copied the offending line: the text can go */
        free(text);
        diag->text = NULL;
    }
    return mech;
}

Mech *pipeline_load_text(const char *text, const char *name, const MechLimits *limits, Diag *diag)
{
    return pipeline_load_bytes(text, strlen(text), name, limits, diag);
}

Mech *pipeline_load_bytes(const char *data, size_t len, const char *name, const MechLimits *limits,
                          Diag *diag)
{
    diag_init(diag, name, NULL, 0);
    if (len > (size_t)limits->max_file_bytes) {
        diag_error_nopos(diag, "'%s' is larger than the limit of %d bytes", name, limits->max_file_bytes);
        return NULL;
    }
    char *copy = xmalloc(len + 1);
    memcpy(copy, data, len);
    copy[len] = '\0';
    Mech *mech = load(copy, (int)len, name, limits, diag);
    if (!mech) {
        free(copy);
        diag->text = NULL;
    }
    return mech;
}

void pipeline_free(Mech *mech)
{
    if (!mech)
        return;
    model_free(mech->model);
    free(mech->text);
    free(mech);
}
