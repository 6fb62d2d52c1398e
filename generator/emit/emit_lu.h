/* emit_lu.h - P_lu_factor, P_lu_solve and P_step: the Jacobian's LU unrolled for its pattern (gen --lu). */
#ifndef MECHC_EMIT_LU_H
#define MECHC_EMIT_LU_H

#include "../base/strbuf.h"
#include "../diff/kinematics.h"
#include "options.h"

#include <stddef.h>

/* PREFIX_lu_factor and PREFIX_lu_solve (emit_lu.c) appended to decl and
   def when opt->lu is set and the mechanism is square, without velocity
   rows and small enough; nothing otherwise, with the reason in why ("":
   written, or not asked for). */
void emit_lu(const Kinematics *kin, const EmitOptions *opt, const char *prefix,
             const char *upper, StrBuf *decl, StrBuf *def, char *why, size_t why_size);

#endif
