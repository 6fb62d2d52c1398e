/* parse.h - tokens to statements: the .mech grammar (spec section 2). */
#ifndef MECHC_PARSE_H
#define MECHC_PARSE_H

#include "../base/arena.h"
#include "../base/diag.h"
#include "../base/limits.h"
#include "ast.h"

/* Parses diag->text (diag_init'ed with the file name and whole text).
   Returns true on success; on failure diag holds the first error, with its
   position. Everything is allocated in arena. Checks here are purely
   syntactic plus the reserved-word and limit rules; names are resolved
   later by the model builder. */
bool parse_program(Arena *arena, Diag *diag, const MechLimits *limits, Program *out);

#endif
