/* diagnose.h - what a run says when it fails or nears a singular position: when, why, which rows and coordinates. */
#ifndef MECHC_KIN_DIAGNOSE_H
#define MECHC_KIN_DIAGNOSE_H

#include "run_state.h"

#include "../analysis/assemble_t0.h"

/* Fills res with ANALYSIS_FAILED and the message for status st at time t, the
   state q the runtime stopped at and its report. what: the phase. */
void run_fail(Run *r, MechrtStatus st, double t, const double *q, const MechrtReport *rep,
              const char *what);

/* A failed step ending at t with iterate q: Newton's failure or the
   velocity and acceleration analysis' after it. */
void run_fail_step(Run *r, MechrtStatus st, double t, const double *q, const MechrtReport *rep);

/* The message of an assembly that found no configuration: the rows left
   unsatisfied at the attempt that came closest (assemble_t0_describe). */
void run_fail_assembly(Run *r, const AssembleT0Report *ar);

/* A failed step after which the rank-revealing corrector could not go on
   either: what it found, after the LU's message. */
void run_note_rank_failure(Run *r);

/* After the assembly at t0: sigma_min / sigma_max < RUN_NEAR_SINGULAR (a
   toggle reached only approximately). */
bool run_nearly_singular(Run *r, double t);

/* Nearly singular stretches: a warning when one begins, a note when it ends. */
void run_watch_condition(Run *r, double t, const MechrtReport *rep);

#endif
