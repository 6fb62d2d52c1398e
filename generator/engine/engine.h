/* engine.h - one interface over the ways to evaluate Phi, Phi_q, nu and gamma (jit, generic, aot). */
#ifndef MECHC_ENGINE_H
#define MECHC_ENGINE_H

#include "../../runtime/host/mechrt_host.h"
#include "../../runtime/mechrt.h"
#include "../emit/emit.h"
#include "../eval/generic.h"
#include "../jit/jit.h"
#include "../pipeline/pipeline.h"
#include "aot.h"

/* The engines, one row each: X(ENUM, name); the name is --engine's
   value and the report's. */
#define ENGINE_KINDS(X) \
    X(JIT, "jit")         /* generated C compiled in memory by libtcc */ \
    X(GENERIC, "generic") /* formulas interpreted over the joint list */ \
    X(AOT, "aot")         /* generated C built by cc, cached, dlopen'ed */

typedef enum EngineKind {
#define X(E, name) ENGINE_##E,
    ENGINE_KINDS(X)
#undef X
    ENGINE_KIND_COUNT
} EngineKind;

/* The names, by kind, NULL after the last (an option's choices). */
extern const char *const engine_names[ENGINE_KIND_COUNT + 1];

typedef struct Engine {
    EngineKind kind;
    const Mech *mech;
    int nq, nh, nv, nr;
    bool compiled;          /* generated code behind the kernels (jit, aot):
                               kernels and emitted are filled */
    /* What every kind is evaluated through (engine_kernels). k.ctx is
       heap memory the engine owns (the compiled unit's Kernels for jit and
       aot, the evaluator's state for generic): copies of k, and the Engine
       moved, stay valid until engine_close. */
    MechrtKernels k;
    /* The Jacobian's nonzeros and its unrolled LU (engine_jac_nz), M's
       nonzeros (engine_mass_nz); their ctx is k.ctx. */
    MechrtHostJacNz jac_nz;
    MechrtHostMassNz mass_nz;
    Kernels kernels;        /* compiled: the functions themselves
                               (context-free; bench times them) */
    Jit *jit;
    Aot *aot;
    Generic *generic;       /* generic evaluator state (check uses its Psi) */
    int *pattern;           /* generic: its own copy of M's pattern */
    EmitResult emitted;     /* compiled: the source */
    double gen_seconds;     /* emission time (generic: set-up time) */
    double compile_seconds; /* libtcc or cc time (aot: with the cache lookup and dlopen) */
    bool aot_cached;        /* aot: the library came from the cache */
    /* generic with design parameters: the sensitivity functions
       interpreted from the graph, one program per DesignFn (design.c);
       NULL otherwise */
    struct NodeValues *design_values;
} Engine;

/* How to open an engine; engine_default_options() for the usual. */
typedef struct EngineOptions {
    bool aot_fresh;         /* aot: compile even when the cache has the library
                               (what bench does to time the compiler); default false */
    bool batch;             /* jit, aot: also compile the batch kernels
                               (engine_batch); default false: libtcc's
                               time of every run stays as it was */
} EngineOptions;

EngineOptions engine_default_options(void);

/* Prepares an engine for mech. Returns false with diag filled when it
   cannot (no compiler for aot, a bug for jit). */
bool engine_open(Engine *engine, EngineKind kind, const Mech *mech, Diag *diag);
bool engine_open_with(Engine *engine, EngineKind kind, const Mech *mech,
                      const EngineOptions *options, Diag *diag);
void engine_close(Engine *engine);

/* The options the engine of kind emits mech's kernels with (generic,
   which compiles nothing: the defaults). The one place that decides what
   the engines compile: jit all_nz, the unrolled LU and the direct
   Jacobian, with large parts for libtcc; aot the same with <math.h>, and
   the compact Jacobian for large mechanisms (EMIT_DIRECT_JAC_NNZ). */
EmitOptions engine_emit_options(const Mech *mech, EngineKind kind);

/* Emits mech's kernels with eo (double, declare_math) and compiles them
   with libtcc; NULL with diag filled on failure (emitted may hold the
   source). emit_seconds and tcc_seconds may be NULL. engine_jit: with
   engine_emit_options(mech, ENGINE_JIT). */
Jit *engine_jit_compile(const Mech *mech, const EmitOptions *eo, EmitResult *emitted,
                        double *emit_seconds, double *tcc_seconds, Diag *diag);
Jit *engine_jit(const Mech *mech, EmitResult *emitted, double *emit_seconds,
                double *tcc_seconds, Diag *diag);

/* Kernel calls by kind (engine_counting; the sparse path's counted by
   the driver that makes them). */
typedef struct EngineCalls {
    long phi, jac, nu, gamma, all, mass, force;
    long jac_nz, all_nz, mass_nz;
} EngineCalls;

/* A counting wrapper's state, the caller's: alive as long as its kernels. */
typedef struct EngineCounter {
    MechrtKernels inner;
    EngineCalls *calls;
} EngineCounter;

/* k's kernels (NULL ones staying NULL), each call counted in calls. */
MechrtKernels engine_counting(EngineCounter *counter, const MechrtKernels *k, EngineCalls *calls);

/* Nanoseconds per call of the fused `all` kernel (or phi + jac + nu + gamma
   when there is none; with jnz, phi + jac_nz + nu + gamma, the sparse
   path's, or all_nz where jnz has it) at (q, qd, t), timed over at least
   min_seconds. */
double engine_time_all(const MechrtKernels *k, const MechrtHostJacNz *jnz, const double *q,
                       const double *qd, double t, double min_seconds);

/* The kernels Newton should see: e->k, without the fused `all` when gamma,
   which Newton does not need, has at least as many operations as phi and
   jac together (the Stewart platform: 988 against 787; its step fell by
   14 % of its instructions), with it otherwise (a linkage's `all` shares
   the trigonometry of phi and jac and is the cheaper call). */
MechrtKernels engine_newton_kernels(const Engine *engine);

/* Evaluation through e->k (spec section 4's kernels). The generic engine
   keeps scratch memory in its state: one Engine serves one thread at a
   time. */
static inline void engine_phi(const Engine *e, const double *q, double t, double *phi)
{
    e->k.phi(e->k.ctx, q, t, phi);
}

static inline void engine_jac(const Engine *e, const double *q, double t, double *jac)
{
    e->k.jac(e->k.ctx, q, t, jac);
}

static inline void engine_nu(const Engine *e, const double *q, double t, double *nu)
{
    e->k.nu(e->k.ctx, q, t, nu);
}

/* dPhi/dp at (q, t) and the model's design: nh x np, row-major (design.c).
   Needs np > 0. */
void engine_phi_p(const Engine *e, const double *q, double t, double *phi_p);
/* A design file's sensitivity function fn at (q, qd, t) (qd unused by
   phi_p) and the model's design, into the arrays out (design_arrays'
   sizes): the generated PREFIX_phi_p, _sens_v, _sens_g, _sens_y (jit,
   aot) or the graph interpreted (generic). */
void engine_design(const Engine *e, DesignFn fn, const double *q, const double *qd, double t,
                   double *const *out);
/* The generic engine's interpreted programs (nothing without design
   parameters), and their release (engine_close). */
void engine_design_open(Engine *e);
void engine_design_free(Engine *e);

static inline void engine_gamma(const Engine *e, const double *q, const double *qd, double t,
                                double *gamma)
{
    e->k.gamma(e->k.ctx, q, qd, t, gamma);
}

static inline void engine_all(const Engine *e, const double *q, const double *qd, double t,
                              double *phi, double *jac, double *nu, double *gamma)
{
    e->k.all(e->k.ctx, q, qd, t, phi, jac, nu, gamma);
}

/* What a driver asks the engine for: its kernels (every engine), the
   Jacobian's nonzeros with its unrolled LU where generated (NULL for the
   generic engine), M's nonzeros for a file with masses (NULL without;
   the generic engine's from its jets, in the generated kernel's pattern). */
static inline const MechrtKernels *engine_kernels(const Engine *e)
{
    return &e->k;
}

static inline const MechrtHostJacNz *engine_jac_nz(const Engine *e)
{
    return e->jac_nz.jac.jac_nz ? &e->jac_nz : NULL;
}

/* The batch kernels (n states a call, generator/emit/batch.c) of an
   engine opened with EngineOptions.batch: jit or aot; NULL for the
   generic engine and without the option (callers loop over the single
   kernels). Fields the unit lacks are NULL (jac and all sparse-only). */
static inline const BatchKernels *engine_batch(const Engine *e)
{
    return e->compiled && e->kernels.batch.gamma ? &e->kernels.batch : NULL;
}

/* The same kernels over arrays by coordinate (q[j * n + i], the outputs
   alike: PREFIX_NAME_batch_soa). */
static inline const BatchKernels *engine_batch_soa(const Engine *e)
{
    return e->compiled && e->kernels.batch_soa.gamma ? &e->kernels.batch_soa : NULL;
}

static inline const MechrtHostMassNz *engine_mass_nz(const Engine *e)
{
    return e->mass_nz.mass_nz ? &e->mass_nz : NULL;
}

#endif
