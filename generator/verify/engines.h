/* engines.h - the check's engines: opening them, the one under test (with a planted fault), pairs compared. */
#ifndef MECHC_VERIFY_ENGINES_H
#define MECHC_VERIFY_ENGINES_H

#include "checker.h"

/* jit and generic always, aot when asked for and a compiler exists (else
   rep->note says why not). False with diag filled when one fails. */
bool check_open_engines(Checker *c, const Mech *mech, Diag *diag);
void check_close_engines(Checker *c);

/* The engine under test (jit) at the sample, with the optional planted fault. */
void check_under_test(Checker *c);

/* Engine k at the sample. */
void check_eval_engine(Checker *c, EngineKind k);

/* Engines check_pair_engines[pair] against each other on every quantity. */
void check_compare_pair(Checker *c, int pair);

#endif
