/* data.h - the measurements `mechc fit` matches: a CSV of times and measured coordinates or outputs. */
#ifndef MECHC_FIT_DATA_H
#define MECHC_FIT_DATA_H

#include "../base/diag.h"
#include "../model/model.h"

/* The CSV's header names t, then measured variables (a coordinate or an
   `output` by name: crank.phi, P.x) and, optionally, a weight column
   w(NAME) for a measured NAME (default weight 1; a weight is the inverse
   variance of its measurements). Each row is one sample at time t (the
   driver values the file's drivers take at t), times non-decreasing; an
   empty field is a value not measured there. Lines starting with # are
   comments. */
typedef struct FitData {
    int nsamples;
    double *t;              /* nsamples */
    int *line;              /* each sample's line in the CSV */
    int ncols;              /* measured variables */
    int *var;               /* each one's variable: coordinate i < nq, else output i - nq */
    const char **names;     /* their names (the model's strings) */
    double *value;          /* nsamples x ncols, row-major; NaN: not measured */
    double *weight;         /* the same shape; 1 where the CSV gives none */
    int nmeasured;          /* values present */
    char *text;             /* the CSV (diag's messages point into it) */
} FitData;

/* Reads path for m; false with the error in diag (FILE:LINE:COL and the
   line with a caret where there is one): not readable, no t column, an
   unknown or repeated name, a weight without its variable, a field that is
   not a finite number (a weight: not positive), a row of the wrong width,
   times that go back, no value measured. */
bool fit_data_read(const char *path, const Model *m, FitData *d, Diag *diag);
void fit_data_free(FitData *d);

#endif
