/* run_table.h - the state of a mechanism at one instant as a table people read (mechc run --steps 0). */
#ifndef MECHC_RUN_TABLE_H
#define MECHC_RUN_TABLE_H

#include <stdio.h>

#include "../model/model.h"

/* One state: the coordinates (q, qd, qdd: nq each) and the outputs' values
   (y, yd, ydd: m->nout each, named ynames; NULL when there are none), with how assembly
   went. digits: significant digits, 0 for 10. */
typedef struct RunInstant {
    double t;
    const double *q, *qd, *qdd;
    const double *y, *yd, *ydd;
    const char *const *ynames;  /* the outputs' names (m->nout) */
    /* spatial bodies: angular velocity and acceleration (global frame),
       nw values each, named wnames (NAME.wx ...); nw = 0 for planar */
    int nw;
    const double *w, *wd;
    const char *const *wnames;
    int assembly_iterations;
    bool assembled_robustly;
    int constructed;        /* coordinates placed by construction first */
} RunInstant;

void run_table_print(FILE *out, const Model *m, const RunInstant *s, int digits);

#endif
