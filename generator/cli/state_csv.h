/* state_csv.h - one state (t and the coordinates) read back from a CSV as `run` writes it. */
#ifndef MECHC_CLI_STATE_CSV_H
#define MECHC_CLI_STATE_CSV_H

#include "../model/model.h"

#include <stdbool.h>
#include <stddef.h>

/* Reads the CSV at path: its header names t and every coordinate of m
   (other columns are ignored, in any order); the row whose t is nearest
   `at`, or the only row when at is NaN. Fills q (m->nq) and *t. On
   failure returns false with the reason in err. */
bool state_csv_read(const char *path, const Model *m, double at, double *q, double *t,
                    char *err, size_t errlen);

#endif
