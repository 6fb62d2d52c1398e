/* aot.h - generated C built by the system compiler into a cached shared library and loaded with dlopen. */
#ifndef MECHC_AOT_H
#define MECHC_AOT_H

#include "../base/diag.h"
#include "../jit/jit.h"

#include <stdbool.h>

/* The compiler command ($CC split at blanks, default "cc") and the flags
   every library is built with. */
#define AOT_FLAGS "-O2 -fPIC -shared"
/* Added for a unit with batch kernels (EngineOptions.batch): the vector
   instructions of this machine, which its lane loops need to gain (doc/
   batch.md), and no contraction into FMA, so that its kernels give the
   bits of the plain build; no basic-block vectorisation either, where
   GCC 12 makes FMA (vfmsubadd) of add/sub pairs whatever -ffp-contract
   says (the Stewart platform's single all). The cache key then holds this
   machine's vector extensions too. */
#define AOT_BATCH_FLAGS "-march=native -ffp-contract=off -fno-tree-slp-vectorize"

/* A loaded library and its kernels; the kernel pointers die with it. */
typedef struct Aot Aot;

typedef struct AotResult {
    double seconds;         /* compile (or cache lookup) plus load time */
    bool cached;            /* the library came from the cache */
    char path[1200];        /* the library's file */
} AotResult;

/* Builds source (double kernels emitted without declare_math, symbols
   starting with prefix) into $XDG_CACHE_HOME/mechc/HASH.so (~/.cache/mechc
   without XDG_CACHE_HOME), HASH being that of the source, compiler and
   flags; reuses the file when it exists, unless fresh. The library is
   written under a temporary name and renamed, so concurrent runs never see
   half a file. Returns the loaded library (aot_unload it), or NULL with
   diag filled when no compiler is found, it fails, or the library cannot
   be loaded. */
Aot *aot_load(const char *source, const char *prefix, bool fresh, AotResult *out, Diag *diag);
/* The same with AOT_BATCH_FLAGS added where batch. */
Aot *aot_load_with(const char *source, const char *prefix, bool fresh, bool batch, AotResult *out,
                   Diag *diag);
const Kernels *aot_kernels(const Aot *aot);
void aot_unload(Aot *aot);

/* The cache folder, created (mode 0700) when missing; false with diag
   filled when there is none. */
bool aot_cache_dir(char *dir, size_t size, Diag *diag);

/* Whether the compiler can be started at all (for tests and bench). */
bool aot_compiler_available(void);

#endif
