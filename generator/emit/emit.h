/* emit.h - C text for a differentiated mechanism, through the templates (spec section 4). */
#ifndef MECHC_EMIT_H
#define MECHC_EMIT_H

#include "../base/diag.h"
#include "../base/limits.h"
#include "../base/strbuf.h"
#include "../diff/kinematics.h"
#include "options.h"
#include "functions.h"

#include <stdbool.h>

/* The most entries of a dense matrix a generated file indexes: its
   indices (row * NQ + col, and NR * NQ itself) are C ints. Above it only
   sparse-only files are written (emit_mechanism refuses the rest). */
#define EMIT_DENSE_MAX_ENTRIES 2147483647LL

/* gen --jac auto (the default): the direct dense Jacobian, faster under
   every compiler (no moves after the fill), unless its second copy of the
   Jacobian's expressions would be large: more than EMIT_DIRECT_JAC_NNZ
   nonzeros in straight-line code (a rolled file's copy is a loop). */
enum { EMIT_DIRECT_JAC_NNZ = 4000 };
bool emit_direct_jac_default(const Kinematics *kin, int roll);

/* Whether kin's file gets function f by what the mechanism has: the
   dynamics ones with masses, phi_p with design parameters, the rest
   always (options decide further: emit_function_written). */
bool emit_function_present(const Kinematics *kin, EmitFunction f);

/* Whether a file emitted with opt gets function f (kin with masses
   permitting; for the LU's, a mechanism emit_lu serves): by its family,
   all_nz with all_nz or sparse_only, jac and all unless sparse_only. */
bool emit_function_written(const EmitOptions *opt, EmitFunction f);

typedef struct EmitResult {
    char *c_text;               /* malloc'ed */
    char *h_text;               /* malloc'ed; the header (always produced) */
    char prefix[128];           /* the prefix used */
    int ops[EMIT_FUNCTION_COUNT];
    int chunks[EMIT_FUNCTION_COUNT];
    char lu_skipped[128];       /* opt->lu set but no LU written: why; "" otherwise */
} EmitResult;

EmitOptions emit_default_options(void);

/* Checks a --prefix value: NULL when it is a usable C identifier, else
   the reason it is not. */
const char *emit_check_prefix(const char *prefix);

/* Checks a --header file name (the part after the last '/', which goes
   into #include "..."): NULL when usable, else the reason it is not. */
const char *emit_check_header_name(const char *name);

/* Writes the C source and header. Returns false (diag filled) for an
   unusable prefix or header name, code beyond max_ops, or a dense
   function beyond EMIT_DENSE_MAX_ENTRIES; everything else in the model is
   already valid. */
bool emit_mechanism(const Kinematics *kin, const EmitOptions *opt, EmitResult *out, Diag *diag);
void emit_result_free(EmitResult *out);

#endif
