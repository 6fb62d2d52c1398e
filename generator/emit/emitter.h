/* emitter.h - the emitter's state, shared by the files of emit/ that write one generated file. */
#ifndef MECHC_EMITTER_H
#define MECHC_EMITTER_H

#include "../sched/sched.h"
#include "emit.h"
#include "roll.h"
#include "trig.h"

typedef struct Emitter {
    const Kinematics *kin;
    const Dag *dag;
    const EmitOptions *opt;
    const char *prefix;
    const char *prefix_upper;
    Scheduler sched;
    EmitTrig trig;              /* sin and cos (trig.c) */
    int chunk;                  /* the chunk being written */
    int fused;                  /* negations written into their product, this function */
    const RollHooks *roll;      /* a loop body's leaves and stores (roll.c) */
    bool rolled;                /* some function has loops (roll.c) */
    bool lanes;                 /* writing a batch function's lane loop
                                   (batch.c): leaves qv[i][l], stores o[k][l],
                                   workspace ws[k][l] */
    StrBuf *batch_text;         /* EmitOptions.batch: the batch functions ... */
    StrBuf *batch_decl;         /* ... and their declarations (batch.c) */
} Emitter;

/* Node id as C (expr.c): its temporary, or (top, or none) its expression. */
void emit_put_expr(const Emitter *e, StrBuf *sb, NodeId id, bool top);
/* Stores the temporary of id into its workspace slot, if it has one (a
   later chunk of the function imports it); nothing for DAG_NONE. */
void emit_put_export(const Emitter *e, StrBuf *sb, NodeId id);

/* The statements of chunk `chunk` of fn (function which): each store
   right after the temporaries it is the first to need (emit.c). */
void emit_put_chunk(Emitter *e, StrBuf *sb, const SchedFunction *fn, int chunk,
                    EmitFunction which, bool workspace);

/* Fills the templates with the written functions and ops, their
   operation counts for the banner (files.c): out's source and header. */
void emit_render_files(const Emitter *e, StrBuf *parts, StrBuf *bodies, const char *ops,
                       EmitResult *out);

/* Whether e's file gets PREFIX_NAME_batch for f: with EmitOptions.batch,
   for the kinematic functions the file has (batch.c). */
bool emit_batch_wanted(const Emitter *e, EmitFunction f);
/* PREFIX_NAME_batch of function which, whose scheduled code fn (NULL:
   rolled, or no code of its own) was just written: its parts and
   definition to e->batch_text, its declaration to e->batch_decl. */
void emit_batch_function(Emitter *e, const SchedFunction *fn, EmitFunction which);
/* The interface's batch section (PREFIX_LANES and the declarations decl)
   into out; nothing without EmitOptions.batch. */
void emit_batch_interface(const Emitter *e, const char *decl, StrBuf *out);
/* EmitOptions.host_design: the batch functions' renames (before the text)
   and their context-free twins (after it). */
void emit_batch_host_renames(const Emitter *e, StrBuf *sb);
void emit_batch_host_twins(const Emitter *e, StrBuf *sb);

/* The parameters of function which in e's file (emit.c), into out
   (NULL-named end): functions.def's, with `const real *p` before the
   first output in a file with design parameters. */
typedef struct Param {
    const char *name;
    bool input;         /* read only: const P_real * (q, qd) */
    bool scalar;        /* by value: P_real (t); else written: P_real * */
} Param;
enum { EMIT_MAX_PARAMS = 13 };
const Param *emit_params_of(const Emitter *e, EmitFunction which, Param out[EMIT_MAX_PARAMS]);

#endif
