/* groups.h - the sparse Jacobian's columns in groups that share no row (Curtis, Powell and Reid). */
#ifndef MECHC_VERIFY_GROUPS_H
#define MECHC_VERIFY_GROUPS_H

#include "checker.h"

/* The column groups of the jit's Jacobian pattern into c (group_start,
   group_cols, col_start, col_ent, ent), from c->buffers. */
void check_group_columns(Checker *c);

#endif
