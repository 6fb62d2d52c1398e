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
typedef void (*KernelEom)(const double *q, const double *qd, double t,
                          double *M, double *Q, double *jac, double *gamma);

/* The generated functions of one mechanism as the compiled unit exports
   them (libtcc, dlopen of a cc-built library): context-free, with jac_nz
   and its pattern. Engines evaluate through a MechrtKernels whose ctx is
   this struct (engine.c). all_nz (the fused kernel with the Jacobian's
   nonzeros, EmitOptions.all_nz) is NULL in a unit written without it;
   jac and all are NULL in a sparse-only one (EmitOptions.sparse_only). */
typedef struct Kernels {
    KernelPhi phi, jac, jac_nz, nu;
    KernelGamma gamma;
    KernelAll all, all_nz;
    const int *jac_row, *jac_col;
    /* Dynamics (doc/dynamics.md), NULL unless the file has masses: M (nq*nq dense),
       its nonzeros and their pattern, Q, and the fused M, Q, jac, gamma. */
    KernelMass mass, mass_nz;
    KernelGamma force;
    KernelEom eom;
    const int *mass_row, *mass_col;
    /* The Jacobian's LU unrolled for its pattern (emit_lu.c); NULL in a
       unit written without it or for a mechanism it does not serve. */
    KernelLuFactor lu_factor;
    KernelLuSolve lu_solve;
    KernelLuStep lu_step;   /* PREFIX_step: the kinematic step over them
                               (above 24 coordinates one that declines) */
} Kernels;

/* Looks a symbol up in a compiled unit (tcc_get_symbol, dlsym). */
typedef void *(*KernelFind)(void *handle, const char *symbol);

/* Fills k with the generated functions PREFIX_phi, PREFIX_jac, ... of
   handle; false when one is missing (PREFIX_all_nz may be, or PREFIX_jac
   and PREFIX_all together when PREFIX_all_nz is there). The dynamics
   functions are bound when the unit has them (all or none), NULL otherwise. */
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
