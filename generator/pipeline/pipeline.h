/* pipeline.h - the front half: file -> model -> derivatives (the engines compile, engine.h). */
#ifndef MECHC_PIPELINE_H
#define MECHC_PIPELINE_H

#include "../base/limits.h"
#include "../diff/kinematics.h"

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

double pipeline_now(void);

#endif
