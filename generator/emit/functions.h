/* functions.h - the generated functions as one vocabulary (functions.def): their enum, names and families. */
#ifndef MECHC_FUNCTIONS_H
#define MECHC_FUNCTIONS_H

/* Which files have a function:
     EMIT_KIN     every file
     EMIT_DENSE   every file but a sparse-only one (EmitOptions.sparse_only)
     EMIT_SPARSE  one written with EmitOptions.all_nz or sparse_only
     EMIT_DYN     a file with masses (all of the family or none)
     EMIT_LU      one written with EmitOptions.lu, for a mechanism the
                  unrolled LU serves (all of the family or none)
     EMIT_DESIGN  a file with design parameters (dPhi/dp) */
typedef enum EmitFamily {
    EMIT_KIN, EMIT_DENSE, EMIT_SPARSE, EMIT_DYN, EMIT_LU, EMIT_DESIGN, EMIT_FAMILY_COUNT
} EmitFamily;

/* The spec's function order (jac and all count 0 in a sparse-only file);
   then all_nz, an extension (written only with EmitOptions.all_nz or
   sparse_only: its ops count 0 without), the dynamics functions, written
   only for a file with masses, and the unrolled LU's (emit_lu.c). */
typedef enum EmitFunction {
#define X(E, name, type, family, params) EMIT_##E,
#include "functions.def"
#undef X
    EMIT_GENERATED_COUNT    /* every row of functions.def */
} EmitFunction;

/* The functions scheduled from the graph (op counts, parts): those before
   the LU's; the kinematic ones among them: those before the dynamics'. */
enum { EMIT_FUNCTION_COUNT = EMIT_LU_FACTOR, EMIT_KINEMATIC_COUNT = EMIT_MASS };

extern const char *const emit_function_names[EMIT_GENERATED_COUNT];
extern const EmitFamily emit_function_family[EMIT_GENERATED_COUNT];

#endif
