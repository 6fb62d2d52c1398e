/* compile.c - what the engines compile: their emission options, and the JIT's emit-and-compile. */
#include "engine.h"

/* Where mech's dense Jacobian has more entries than a generated file
   indexes (EMIT_DENSE_MAX_ENTRIES): its kernels are sparse-only (no
   dense jac and all), which only run's sparse path admits, and it calls
   neither. */
static bool sparse_only(const Mech *mech)
{
    return (long long)mech->model->nr * mech->model->nq > EMIT_DENSE_MAX_ENTRIES;
}

EmitOptions engine_emit_options(const Mech *mech, EngineKind kind)
{
    EmitOptions eo = emit_default_options();
    eo.source_name = mech->model->file;
    eo.all_nz = true;       /* run's sparse path */
    eo.lu = true;           /* run's dense path: the unrolled LU */
    eo.sparse_only = sparse_only(mech);
    eo.host_design = true;  /* engine.c binds the design (model_set_design's) */
    switch (kind) {
    case ENGINE_JIT:
        eo.declare_math = true;
        eo.direct_jac = true;
        eo.prefix = "mechc_jit";
        /* Chunks exist for optimizing compilers, whose passes grow faster
           than the function; libtcc's time is linear, and a part boundary
           costs it a call and the workspace stores and loads of what
           crosses it (the RSSR's all: 165 -> 134 ns). 1000 keeps a
           function's temporaries (one stack slot each under libtcc) to a
           few kilobytes. */
        eo.chunk_nodes = 1000;
        eo.max_ops = mech->limits.max_code_ops;
        break;
    case ENGINE_AOT:
        eo.prefix = "mechc_aot";
        /* Stores in place are faster than the spread from jac_nz; only
           large mechanisms keep the compact form, for the compiler's sake. */
        eo.direct_jac = mech->kin.nnz <= EMIT_DIRECT_JAC_NNZ;
        break;
    case ENGINE_GENERIC:    /* compiles nothing */
    case ENGINE_KIND_COUNT:
        break;
    }
    return eo;
}

Jit *engine_jit_compile(const Mech *mech, const EmitOptions *eo, EmitResult *emitted,
                        double *emit_seconds, double *tcc_seconds, Diag *diag)
{
    double t0 = pipeline_now();
    if (!emit_mechanism(&mech->kin, eo, emitted, diag))
        return NULL;
    double t1 = pipeline_now();
    Jit *jit = jit_compile(emitted->c_text, emitted->prefix, diag);
    double t2 = pipeline_now();
    if (emit_seconds)
        *emit_seconds = t1 - t0;
    if (tcc_seconds)
        *tcc_seconds = t2 - t1;
    return jit;
}

Jit *engine_jit(const Mech *mech, EmitResult *emitted, double *emit_seconds,
                double *tcc_seconds, Diag *diag)
{
    EmitOptions eo = engine_emit_options(mech, ENGINE_JIT);
    return engine_jit_compile(mech, &eo, emitted, emit_seconds, tcc_seconds, diag);
}
