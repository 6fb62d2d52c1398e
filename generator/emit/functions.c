/* functions.c - the names and families of the generated functions, expanded from functions.def. */
#include "functions.h"

const char *const emit_function_names[EMIT_GENERATED_COUNT] = {
#define X(E, name, type, family, params) [EMIT_##E] = #name,
#include "functions.def"
#undef X
};

const EmitFamily emit_function_family[EMIT_GENERATED_COUNT] = {
#define X(E, name, type, family, params) [EMIT_##E] = family,
#include "functions.def"
#undef X
};
