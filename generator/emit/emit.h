/* emit.h - C text for a differentiated mechanism, through the templates (spec section 4). */
#ifndef MECHC_EMIT_H
#define MECHC_EMIT_H

#include "../base/diag.h"
#include "../base/limits.h"
#include "../base/strbuf.h"
#include "../diff/kinematics.h"
#include "functions.h"

#include <stdbool.h>

typedef struct EmitOptions {
    const char *prefix;         /* NULL: the mechanism name, sanitized */
    bool real_float;            /* float kernels (sinf, 1.5f, ...) */
    const char *header_name;    /* non-NULL: the .c includes this header
                                   instead of carrying the interface */
    bool direct_jac;            /* dense jac with its own stores (fast
                                   under libtcc) rather than spread from
                                   jac_nz (half the code for gcc -O2) */
    bool declare_math;          /* declare libm functions instead of
                                   #include <math.h> (the in-process JIT
                                   needs no system headers) */
    bool libm_trig;             /* double kernels: sin and cos of <math.h>
                                   rather than the emitted P_sincos
                                   (templates/sincos.tmpl; float kernels
                                   always call sinf and cosf) */
    int chunk_nodes;            /* most operations plus stores per C function (default 150) */
    const char *source_name;    /* the input file, named in the banner */
    long max_ops;               /* most operations in all functions together
                                   (default: MechLimits max_code_ops); 0: no limit */
    bool all_nz;                /* also PREFIX_all_nz: Phi, the Jacobian's
                                   nonzeros, nu and gamma in one call (the
                                   sparse path of run; gen --sparse) */
    int roll;                   /* EmitRoll: loops for joints' rows of one
                                   shape (generator/emit/roll.c) */
    bool sparse_only;           /* no dense PREFIX_jac and PREFIX_all (NR*NQ
                                   entries), PREFIX_all_nz instead; the
                                   interface defines PREFIX_SPARSE_ONLY 1
                                   (gen --sparse-only; engines above
                                   EMIT_DENSE_MAX_ENTRIES) */
    bool lu;                    /* also PREFIX_lu_factor and PREFIX_lu_solve
                                   (emit_lu.c; gen --lu): the Jacobian's LU
                                   unrolled for its pattern */
} EmitOptions;

/* The most entries of a dense matrix a generated file indexes: its
   indices (row * NQ + col, and NR * NQ itself) are C ints. Above it only
   sparse-only files are written (emit_mechanism refuses the rest). */
#define EMIT_DENSE_MAX_ENTRIES 2147483647LL

/* gen --roll: auto rolls the kinematic functions of a mechanism with at
   least EMIT_ROLL_AUTO_ROWS rows, groups of EMIT_ROLL_AUTO_MEMBERS joints
   or more; always rolls every group of two or more; never writes
   straight-line code only. Rolled and straight-line kernels compute the
   same bits. */
typedef enum EmitRoll { EMIT_ROLL_AUTO, EMIT_ROLL_NEVER, EMIT_ROLL_ALWAYS } EmitRoll;
enum { EMIT_ROLL_AUTO_ROWS = 500, EMIT_ROLL_AUTO_MEMBERS = 8 };

/* gen --jac auto (the default): the direct dense Jacobian, faster under
   every compiler (no moves after the fill), unless its second copy of the
   Jacobian's expressions would be large: more than EMIT_DIRECT_JAC_NNZ
   nonzeros in straight-line code (a rolled file's copy is a loop). */
enum { EMIT_DIRECT_JAC_NNZ = 4000 };
bool emit_direct_jac_default(const Kinematics *kin, int roll);

/* The functions kin's file gets: the kinematic ones, and the dynamics
   ones when it has masses (EMIT_KINEMATIC_COUNT or EMIT_FUNCTION_COUNT). */
int emit_function_count(const Kinematics *kin);

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

/* The shortest decimal of v that reads back exactly (as a float with
   real_float), negative ones parenthesized: how constants are written. */
void emit_put_literal(StrBuf *sb, double v, bool real_float);

/* PREFIX_lu_factor and PREFIX_lu_solve (emit_lu.c) appended to decl and
   def when opt->lu is set and the mechanism is square, without velocity
   rows and small enough; nothing otherwise, with the reason in why ("":
   written, or not asked for). */
void emit_lu(const Kinematics *kin, const EmitOptions *opt, const char *prefix,
             const char *upper, StrBuf *decl, StrBuf *def, char *why, size_t why_size);

/* Writes the C source and header. Returns false (diag filled) for an
   unusable prefix or header name, code beyond max_ops, or a dense
   function beyond EMIT_DENSE_MAX_ENTRIES; everything else in the model is
   already valid. */
bool emit_mechanism(const Kinematics *kin, const EmitOptions *opt, EmitResult *out, Diag *diag);
void emit_result_free(EmitResult *out);

#endif
