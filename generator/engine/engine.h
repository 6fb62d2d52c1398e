/* engine.h - one interface over the ways to evaluate Phi, Phi_q, nu and gamma (jit, generic, aot). */
#ifndef MECHC_ENGINE_H
#define MECHC_ENGINE_H

#include "../jit/jit.h"
#include "../pipeline/pipeline.h"

typedef enum EngineKind { ENGINE_JIT, ENGINE_GENERIC, ENGINE_AOT, ENGINE_KIND_COUNT } EngineKind;

extern const char *const engine_names[ENGINE_KIND_COUNT];

typedef struct Engine {
    EngineKind kind;
    const Mech *mech;
    int nq, nh, nv, nr;
    Kernels kernels;        /* jit and aot */
    Jit *jit;
    void *library;          /* aot: dlopen handle */
    void *generic;          /* generic evaluator state */
    EmitResult emitted;     /* jit and aot: the source compiled */
    double gen_seconds;     /* emission time (generic: set-up time) */
    double compile_seconds; /* libtcc or cc time (aot: with the cache lookup and dlopen) */
    bool aot_cached;        /* aot: the library came from the cache */
} Engine;

/* How to open an engine; engine_default_options() for the usual. */
typedef struct EngineOptions {
    bool aot_fresh;         /* aot: compile even when the cache has the library
                               (what bench does to time the compiler); default false */
} EngineOptions;

EngineOptions engine_default_options(void);

/* Parses an --engine value; -1 when unknown. */
int engine_from_name(const char *name);

/* Prepares an engine for mech. Returns false with diag filled when it
   cannot (no compiler for aot, a bug for jit). */
bool engine_open(Engine *engine, EngineKind kind, const Mech *mech, Diag *diag);
bool engine_open_with(Engine *engine, EngineKind kind, const Mech *mech,
                      const EngineOptions *options, Diag *diag);
void engine_close(Engine *engine);

/* The generic engine keeps scratch memory in its state: one Engine serves
   one thread at a time. */
void engine_phi(const Engine *e, const double *q, double t, double *phi);
void engine_jac(const Engine *e, const double *q, double t, double *jac);
void engine_nu(const Engine *e, const double *q, double t, double *nu);
void engine_gamma(const Engine *e, const double *q, const double *qd, double t, double *gamma);
void engine_all(const Engine *e, const double *q, const double *qd, double t,
                double *phi, double *jac, double *nu, double *gamma);

#endif
