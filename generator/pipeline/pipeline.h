/* pipeline.h - the whole front to back: file -> model -> derivatives -> C -> machine code. */
#ifndef MECHC_PIPELINE_H
#define MECHC_PIPELINE_H

#include "../base/limits.h"
#include "../diff/kinematics.h"
#include "../emit/emit.h"
#include "../jit/jit.h"

#include <stddef.h>

/* One loaded mechanism and whatever stages have been run on it. */
typedef struct Mech {
    char *text;             /* the input, owned */
    Model *model;
    Kinematics kin;
    MechLimits limits;      /* what it was loaded with; emission uses max_code_ops */
    double load_seconds;    /* read + parse + resolve */
    double diff_seconds;    /* derivatives */
} Mech;

/* Reads, parses, resolves and differentiates FILE. Returns NULL with diag
   filled (and its text kept valid) on bad input. diag must stay alive as
   long as the Mech, since it points into the text. */
Mech *pipeline_load(const char *path, const MechLimits *limits, Diag *diag);
/* The same from text in memory (tests). */
Mech *pipeline_load_text(const char *text, const char *name, const MechLimits *limits, Diag *diag);
/* The same from len bytes that may contain NUL bytes, as a file can (fuzzing). */
Mech *pipeline_load_bytes(const char *data, size_t len, const char *name, const MechLimits *limits,
                          Diag *diag);
void pipeline_free(Mech *mech);

/* Whether the engines' kernels of mech are sparse-only (no dense jac and
   all): where its dense Jacobian has more entries than a generated file
   indexes (EMIT_DENSE_MAX_ENTRIES), which only run's sparse path admits,
   and it calls neither. */
bool pipeline_sparse_only(const Mech *mech);

/* Emits double kernels for the JIT and compiles them with libtcc. */
Jit *pipeline_jit(const Mech *mech, EmitResult *emitted, double *emit_seconds,
                  double *tcc_seconds, Diag *diag);
/* The same with EmitOptions.roll = roll (an EmitRoll) and sparse_only (or
   pipeline_sparse_only): gen --stats --roll --sparse-only. */
Jit *pipeline_jit_roll(const Mech *mech, int roll, bool sparse_only, EmitResult *emitted,
                       double *emit_seconds, double *tcc_seconds, Diag *diag);

double pipeline_now(void);

#endif
