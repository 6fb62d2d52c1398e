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
} Emitter;

/* Node id as C (expr.c): its temporary, or (top, or none) its expression. */
void emit_put_expr(const Emitter *e, StrBuf *sb, NodeId id, bool top);
/* Stores the temporary of id into its workspace slot, if it has one (a
   later chunk of the function imports it); nothing for DAG_NONE. */
void emit_put_export(const Emitter *e, StrBuf *sb, NodeId id);

/* Fills the templates with the written functions and ops, their
   operation counts for the banner (files.c): out's source and header. */
void emit_render_files(const Emitter *e, StrBuf *parts, StrBuf *bodies, const char *ops,
                       EmitResult *out);

#endif
