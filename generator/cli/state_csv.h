/* state_csv.h - one state (t and the coordinates) read back from a CSV as `run` writes it. */
#ifndef MECHC_CLI_STATE_CSV_H
#define MECHC_CLI_STATE_CSV_H

#include "../base/diag.h"
#include "../model/model.h"

#include <stdbool.h>
#include <stddef.h>

/* Reads the CSV at path: its header names t and every coordinate of m
   (other columns are ignored, in any order); the row whose t is nearest
   `at`, or the only row when at is NaN. Fills q (m->nq) and *t. The
   fields read must be finite numbers. On failure returns false with the
   error in diag, at its line and column of the CSV when it has one. */
bool state_csv_read(const char *path, const Model *m, double at, double *q, double *t,
                    Diag *diag);

#endif
