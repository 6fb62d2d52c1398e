/* lib.h - libmechc's handles as the library's own files see them (the public API: mechc.h). */
#ifndef MECHC_LIB_H
#define MECHC_LIB_H

#include "mechc.h"

#include "../engine/engine.h"
#include "../kin/outputs.h"
#include "../kin/run.h"
#include "../dyn/sim.h"
#include "../kin/sens.h"
#include "../pipeline/pipeline.h"

#include <stdbool.h>

struct mechc_model {
    Mech *mech;
    char *name;             /* the file name as given, owned: diag.file points here */
    Diag diag;              /* outlives mech (pipeline_load wants it) */
};

/* The batch calls, one pointer per kernel: n states, q n x nq, t nt
   values (1 or n). batch.c fills them with loops over the single-state
   kernel; generated P_*_batch kernels replace a slot where the engine's
   compiled unit has one (lib_batch_bind). */
typedef void (*LibBatchPhi)(mechc_kernels *k, size_t n, const double *q, const double *t,
                            size_t nt, double *out);
typedef void (*LibBatchGamma)(mechc_kernels *k, size_t n, const double *q, const double *qd,
                              const double *t, size_t nt, double *out);
typedef void (*LibBatchAll)(mechc_kernels *k, size_t n, const double *q, const double *qd,
                            const double *t, size_t nt, double *phi, double *jac, double *nu,
                            double *gamma);
typedef void (*LibBatchMass)(mechc_kernels *k, size_t n, const double *q, double *M);

typedef struct LibBatch {
    LibBatchPhi phi, jac, nu;
    LibBatchGamma gamma, force;
    LibBatchAll all;
    LibBatchMass mass;
} LibBatch;

struct mechc_kernels {
    mechc_model *model;
    Engine engine;
    OutputEval outputs;     /* the `output` statements, interpreted */
    double *scratch;        /* nr * nq + nh + 2 nr: what a call skips (NULL outputs);
                               NULL until a call needs it (kernels.c) */
    Sens sens;              /* mechc_sensitivities', made at its first call */
    int sens_state;         /* 0 not made, 1 made, -1 the model has none */
    LibBatch batch;
};

/* Fills d (may be NULL) with status and a message, no position. Returns status. */
mechc_status lib_fail(mechc_diag *d, mechc_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Fills d (may be NULL) from a stage's Diag. Returns status. */
mechc_status lib_fail_diag(mechc_diag *d, mechc_status status, const Diag *from);
/* Clears d (may be NULL): status MECHC_OK, nothing else. */
void lib_ok(mechc_diag *d);
/* The index of name in names (NULL-terminated); fallback when name is
   NULL, -1 when it is none of them. */
int lib_name_index(const char *const *names, const char *name, int fallback);

/* A run's options as run_analysis takes them (x NULL: the defaults);
   false when one is out of range. */
bool lib_run_options(const mechc_run_options *o, const mechc_run_tuning *x, RunOptions *ro);
/* mechc_run_with, the run lending its LU of Phi_q to `lend` at every
   step (RunOptions.lend_lu; NULL: nowhere): run --sens solves with it. */
mechc_result *lib_run_lending(mechc_kernels *k, const mechc_run_options *o,
                              const mechc_run_tuning *x, RunLu *lend, mechc_diag *d);
/* What run_analysis said of a result made by mechc_run_with (its
   statistics: mechc run --stats). */
const RunResult *lib_result_run(const mechc_result *r);
/* What sim_run said of a result made by mechc_sim_with (mechc sim --stats). */
const SimResult *lib_result_sim(const mechc_result *r);

/* The report behind a mechc_info_report (mechc info's text). */
struct InfoReport;
const struct InfoReport *lib_info_report(const mechc_info_report *r);

/* The loops behind the batch calls (batch.c); then what the engine's
   compiled unit has of its own. */
void lib_batch_bind(mechc_kernels *k);

#endif
