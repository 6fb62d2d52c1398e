/* blame.h - which force element makes the right side NaN or infinite at a state, and why. */
#ifndef MECHC_DYN_BLAME_H
#define MECHC_DYN_BLAME_H

#include "../analysis/common.h"
#include "../base/diag.h"
#include "../model/model.h"

#include <stdbool.h>
#include <stddef.h>

/* Appends to msg (size bytes) the first force element of m that cannot be
   evaluated at (q, qd, t): a spring of length 0 ("spring 'S'
   (FILE:LINE:COL) has length 0 here ...": the direction of its force is
   0/0) or an element whose nodes are NaN or infinite. src: the file's
   text, for the line and column (NULL: the name alone). False, nothing
   appended, when every element is finite there. */
bool blame_force(const Model *m, const Diag *src, double t, const double *q,
                     const double *qd, char *msg, size_t size);

#endif
