/* options.h - what a generated file is asked to be: EmitOptions and gen --roll's modes. */
#ifndef MECHC_EMIT_OPTIONS_H
#define MECHC_EMIT_OPTIONS_H

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
    bool host_design;           /* a file with design parameters also gets
                                   context-free twins of its functions that
                                   read p from PREFIX_design_bind's pointer
                                   (the engines': jit.h's Kernels have no p) */
    bool lu;                    /* also PREFIX_lu_factor and PREFIX_lu_solve
                                   (emit_lu.c; gen --lu): the Jacobian's LU
                                   unrolled for its pattern */
    bool batch;                 /* also PREFIX_NAME_batch for the kinematic
                                   functions: n states a call, PREFIX_LANES
                                   at a time in lock-step (batch.c; gen
                                   --batch, EngineOptions.batch) */
} EmitOptions;

/* gen --roll: auto rolls the kinematic functions of a mechanism with at
   least EMIT_ROLL_AUTO_ROWS rows, groups of EMIT_ROLL_AUTO_MEMBERS joints
   or more; always rolls every group of two or more; never writes
   straight-line code only. Rolled and straight-line kernels compute the
   same bits. */
typedef enum EmitRoll { EMIT_ROLL_AUTO, EMIT_ROLL_NEVER, EMIT_ROLL_ALWAYS } EmitRoll;
enum { EMIT_ROLL_AUTO_ROWS = 500, EMIT_ROLL_AUTO_MEMBERS = 8 };

#endif
