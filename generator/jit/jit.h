/* jit.h - compiles generated C in memory with libtcc and hands back the kernels. */
#ifndef MECHC_JIT_H
#define MECHC_JIT_H

#include "../base/diag.h"

typedef void (*KernelPhi)(const double *q, double t, double *out);
typedef void (*KernelGamma)(const double *q, const double *qd, double t, double *gamma);
typedef void (*KernelAll)(const double *q, const double *qd, double t,
                          double *phi, double *jac, double *nu, double *gamma);
typedef void (*KernelMass)(const double *q, double *M);
typedef int (*KernelLuFactor)(const double *a, double *lu, double pivot_tol, double *spread);
typedef void (*KernelLuSolve)(const double *lu, const double *b, double *x);
typedef int (*KernelLuStep)(double *q, double *qd, double *qdd, double t, double h,
                            const double *tol, int max_iter, double *out, int *iout);
typedef void (*KernelSensV)(const double *q, const double *qd, double t, double *v_q, double *v_p);
typedef void (*KernelSensG)(const double *q, const double *qd, double t, double *g_q,
                            double *g_qd, double *g_p);
typedef void (*KernelSensY)(const double *q, const double *qd, double t, double *f_q,
                            double *f_p, double *df_q, double *df_qd, double *df_p,
                            double *ddf_q, double *ddf_qd, double *ddf_p);
typedef void (*KernelEom)(const double *q, const double *qd, double t,
                          double *M, double *Q, double *jac, double *gamma);

/* The batch kernels (EmitOptions.batch, generator/emit/batch.c): the
   kernel at n states, q and qd n x NQ, t n values, each output n rows of
   its single-state size, all row-major (PREFIX_NAME_batch), or the same
   arrays by coordinate, q[j * n + i] (PREFIX_NAME_batch_soa); bit for
   bit n single calls. */
typedef void (*KernelPhiBatch)(int n, const double *q, const double *t, double *out);
typedef void (*KernelGammaBatch)(int n, const double *q, const double *qd, const double *t,
                                 double *gamma);
typedef void (*KernelAllBatch)(int n, const double *q, const double *qd, const double *t,
                               double *phi, double *jac, double *nu, double *gamma);

/* A unit's PREFIX_NAME_batch (or _batch_soa), NULL where it has none: all of them
   without EmitOptions.batch, jac and all in a sparse-only unit, all_nz
   without EmitOptions.all_nz. */
typedef struct BatchKernels {
    KernelPhiBatch phi, jac, jac_nz, nu;
    KernelGammaBatch gamma;
    KernelAllBatch all, all_nz;         /* all_nz: phi, jac_vals (NNZ), nu, gamma */
} BatchKernels;

/* The generated functions of one mechanism as the compiled unit exports
   them (libtcc, dlopen of a cc-built library), one field per row of
   functions.def: context-free, with the patterns of jac_nz and mass_nz.
   Engines evaluate through a MechrtKernels whose ctx is this struct
   (engine.c). A family a unit was written without is NULL (EmitFamily):
   all_nz without EmitOptions.all_nz, jac and all in a sparse-only unit,
   the dynamics without masses (mass_row and mass_col with them), the
   unrolled LU (lu_factor, lu_solve and step, the kinematic step over
   them; above 24 coordinates one that declines) where it was not written.
   A unit with design parameters binds only with its context-free twins
   (EmitOptions.host_design), which read the design design_bind was given. */
typedef struct Kernels {
#define X(E, name, type, family, params) Kernel##type name;
#include "../emit/functions.def"
#undef X
    const int *jac_row, *jac_col;
    const int *mass_row, *mass_col;
    const int *phi_p_row, *phi_p_col;   /* phi_p_nz's pattern (design files) */
    /* a unit with design parameters (EmitOptions.host_design): where its
       functions read p from; NULL otherwise */
    void (*design_bind)(const double *p);
    BatchKernels batch;     /* PREFIX_NAME_batch, where compiled */
    BatchKernels batch_soa; /* PREFIX_NAME_batch_soa, where compiled */
} Kernels;

/* Looks a symbol up in a compiled unit (tcc_get_symbol, dlsym). */
typedef void *(*KernelFind)(void *handle, const char *symbol);

/* Fills k with the generated functions PREFIX_phi, PREFIX_jac, ... of
   handle, by family (functions.h); false when one is missing: a
   kinematic one, a dense one unless the unit is sparse-only (PREFIX_all_nz
   there and no dense one), some of the dynamics but not all. An LU
   family found in part is left out (NULL). */
bool kernels_bind(Kernels *k, KernelFind find, void *handle, const char *prefix);

typedef struct Jit Jit;

/* Compiles source (double kernels, emitted with declare_math) whose
   symbols start with prefix. On failure (a bug in mechc: generated code
   must always compile) the source is saved to a file named in diag's
   message and NULL is returned. */
Jit *jit_compile(const char *source, const char *prefix, Diag *diag);
const Kernels *jit_kernels(const Jit *jit);
/* Frees the compiled code: the kernel pointers die with it. */
void jit_free(Jit *jit);

#endif
