/* ast.c - the joint and force vocabularies expanded from joints.def and forces.def, and names for AST kinds. */
#include "ast.h"

#include <string.h>

const JointInfo joint_info[JOINT_KIND_COUNT] = {
#define X(e, kw, dim, na, sa, sb, ax, opt, nr, lvl, ...) \
    [JOINT_##e] = {kw, dim, na, {sa, sb}, ax, opt, nr, lvl, {__VA_ARGS__}},
#include "joints.def"
#undef X
};

const ForceInfo force_info[FORCE_KIND_COUNT] = {
#define KEY(k) (1u << DKEY_##k)
#define X(e, kw, own, na, frame, keys) [FORCE_##e] = {kw, own, na, frame, keys},
#include "forces.def"
#undef X
#undef KEY
};

const char *const dyn_key_names[DKEY_COUNT] = {
    [DKEY_M] = "m", [DKEY_J] = "J", [DKEY_K] = "k", [DKEY_C] = "c", [DKEY_LENGTH] = "length",
    [DKEY_ANGLE] = "angle", [DKEY_FORCE] = "force", [DKEY_TORQUE] = "torque",
    [DKEY_JXY] = "Jxy", [DKEY_JXZ] = "Jxz", [DKEY_JYZ] = "Jyz",
};

bool joint_kind_in(JointKind kind, bool spatial)
{
    JointDim dim = joint_info[kind].dim;
    return dim == DIM_BOTH || dim == (spatial ? DIM_SPATIAL : DIM_PLANAR);
}

int joint_kind_lookup(const char *word, int len, bool spatial)
{
    for (int k = 0; k < JOINT_KIND_COUNT; k++) {
        const char *kw = joint_info[k].keyword;
        if (joint_kind_in((JointKind)k, spatial) && (int)strlen(kw) == len
            && memcmp(kw, word, (size_t)len) == 0)
            return k;
    }
    return -1;
}

int force_kind_lookup(const char *word, int len)
{
    for (int k = 0; k < FORCE_KIND_COUNT; k++) {
        const char *kw = force_info[k].keyword;
        if (force_info[k].own && (int)strlen(kw) == len && memcmp(kw, word, (size_t)len) == 0)
            return k;
    }
    return -1;
}

const char *dyn_keyword(const Stmt *s)
{
    if (s->kind == STMT_FORCE)
        return force_info[s->force].keyword;
    return s->kind == STMT_MASS ? "mass" : "gravity";
}

int joint_kind_from_keyword(const char *word, int len)
{
    return joint_kind_lookup(word, len, false);
}

const char *ast_describe(const Ast *ast)
{
    switch (ast->kind) {
    case AST_NUM:    return "a number";
    case AST_NAME:   return "a name";
    case AST_MEMBER: return "a coordinate";
    case AST_TIME:   return "the time t";
    case AST_NEG:    return "a negation";
    case AST_BINARY:
        switch (ast->op) {
        case OP_ADD: return "a sum";
        case OP_SUB: return "a difference";
        case OP_MUL: return "a product";
        case OP_DIV: return "a quotient";
        case OP_POW: return "a power";
        default:     return "an operation";   /* not produced by the parser */
        }
    case AST_CALL:   return "a function call";
    case AST_DER:    return "der()";
    case AST_SLIDE:  return "slide()";
    case AST_ANGLE:  return "angle()";
    }
    return "an expression";
}
