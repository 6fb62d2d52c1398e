/* jit.c - libtcc behind one owning wrapper: compile to memory, relocate, look the kernels up.
 *
 * The generated source declares the libm functions it uses instead of
 * including <math.h>, and is compiled with -nostdlib: nothing is read
 * from the file system, and every external symbol is one we add here.
 */
#define _GNU_SOURCE 1     /* sincos */
#include "jit.h"

#include "../base/arena.h"
#include "../base/sincos.h"
#include "../base/strbuf.h"
#include "../emit/functions.h"

#include <libtcc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct Jit {
    TCCState *state;
    Kernels kernels;
};

static void collect_error(void *opaque, const char *msg)
{
    StrBuf *sb = opaque;
    if (sb->len < 4000)
        sb_printf(sb, "%s\n", msg);
}

static void add_libm(TCCState *s)
{
    /* Casting through the exact prototype keeps the table honest. */
    double (*const unary[])(double) = {sin, cos, tan, asin, acos, atan, sqrt, exp, log, sinh, cosh, tanh};
    const char *const unary_names[] = {"sin", "cos", "tan", "asin", "acos", "atan", "sqrt",
                                       "exp", "log", "sinh", "cosh", "tanh"};
    for (size_t i = 0; i < sizeof unary / sizeof *unary; i++)
        tcc_add_symbol(s, unary_names[i], (const void *)unary[i]);
    tcc_add_symbol(s, "pow", (const void *)pow);
    tcc_add_symbol(s, "atan2", (const void *)atan2);
    tcc_add_symbol(s, "memset", (const void *)memset);
    tcc_add_symbol(s, "sincos", (const void *)sincos);
    tcc_add_symbol(s, "mechc_sincos", (const void *)mechc_sincos);
    tcc_add_symbol(s, "mechc_sincos2", (const void *)mechc_sincos2);
}

/* Keeps the source of a failed compile for the bug report. */
static void save_failed_source(const char *source, const char *prefix, char *path, size_t size)
{
    const char *dir = getenv("TMPDIR");
    snprintf(path, size, "%s/mechc-jit-%s-XXXXXX.c", dir && *dir ? dir : "/tmp", prefix);
    int fd = mkstemps(path, 2);
    if (fd < 0) {
        snprintf(path, size, "(could not save the source)");
        return;
    }
    FILE *f = fdopen(fd, "w");
    if (f) {
        fputs(source, f);
        fclose(f);
    } else {
        close(fd);
    }
}

static void *kernel(KernelFind find, void *handle, const char *prefix, const char *name)
{
    char symbol[256];
    snprintf(symbol, sizeof symbol, "%s_%s", prefix, name);
    return find(handle, symbol);
}

/* The unit's batch kernels NAME + suffix (optional: NULL where absent). */
static void bind_batch(BatchKernels *b, KernelFind find, void *handle, const char *prefix,
                       const char *suffix)
{
    void **slots[] = {(void **)&b->phi, (void **)&b->jac, (void **)&b->jac_nz, (void **)&b->nu,
                      (void **)&b->gamma, (void **)&b->all, (void **)&b->all_nz};
    static const char *const names[] = {"phi", "jac", "jac_nz", "nu", "gamma", "all", "all_nz"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        char name[32];
        snprintf(name, sizeof name, "%s%s", names[i], suffix);
        *slots[i] = kernel(find, handle, prefix, name);
    }
}

bool kernels_bind(Kernels *k, KernelFind find, void *handle, const char *prefix)
{
    int found[EMIT_FAMILY_COUNT] = {0}, rows[EMIT_FAMILY_COUNT] = {0};
    memset(k, 0, sizeof *k);
#define X(E, name, type, family, params) \
    k->name = (Kernel##type)kernel(find, handle, prefix, #name); \
    found[family] += k->name != NULL; \
    rows[family]++;
#include "../emit/functions.def"
#undef X
    if (found[EMIT_LU] < rows[EMIT_LU]) {
#define X(E, name, type, family, params) \
        if (family == EMIT_LU) \
            k->name = NULL;
#include "../emit/functions.def"
#undef X
    }
    bind_batch(&k->batch, find, handle, prefix, "_batch");
    bind_batch(&k->batch_soa, find, handle, prefix, "_batch_soa");
    k->jac_row = kernel(find, handle, prefix, "jac_row");
    k->jac_col = kernel(find, handle, prefix, "jac_col");
    k->mass_row = kernel(find, handle, prefix, "mass_row");
    k->mass_col = kernel(find, handle, prefix, "mass_col");
    k->phi_p_row = kernel(find, handle, prefix, "phi_p_row");
    k->phi_p_col = kernel(find, handle, prefix, "phi_p_col");
    *(void **)&k->design_bind = kernel(find, handle, prefix, "design_bind");
    /* a unit with design parameters but no context-free twins has
       functions that take p: calling them through k would be wrong */
    if (!k->design_bind && kernel(find, handle, prefix, "p0"))
        return false;
    bool mass_pattern = k->mass_row && k->mass_col;
    bool dynamics = found[EMIT_DYN] == rows[EMIT_DYN] && mass_pattern;
    bool none = found[EMIT_DYN] == 0 && !k->mass_row && !k->mass_col;
    /* a sparse-only unit has no dense function, and all_nz instead */
    bool dense = found[EMIT_DENSE] == rows[EMIT_DENSE];
    bool sparse_only = found[EMIT_DENSE] == 0 && k->all_nz;
    return found[EMIT_KIN] == rows[EMIT_KIN] && k->jac_row && k->jac_col
           && (dense || sparse_only) && (dynamics || none);
}

static void *tcc_find(void *s, const char *symbol) { return tcc_get_symbol(s, symbol); }

Jit *jit_compile(const char *source, const char *prefix, Diag *diag)
{
    StrBuf errors;
    sb_init(&errors);
    sb_puts(&errors, "");
    TCCState *s = tcc_new();
    if (!s) {
        diag_error_nopos(diag, "internal error: libtcc could not start");
        return NULL;
    }
    tcc_set_error_func(s, &errors, collect_error);
    tcc_set_options(s, "-nostdlib");
    tcc_set_output_type(s, TCC_OUTPUT_MEMORY);
    StrBuf unit;
    sb_init(&unit);
    sb_printf(&unit, "#line 1 \"<mechc:%s.c>\"\n", prefix);
    sb_puts(&unit, source);
    int rc = tcc_compile_string(s, unit.data);
    sb_free(&unit);
    if (rc == 0) {
        add_libm(s);
#ifdef TCC_RELOCATE_AUTO
        rc = tcc_relocate(s, TCC_RELOCATE_AUTO);       /* libtcc 0.9.27 (Debian) */
#else
        rc = tcc_relocate(s);                          /* libtcc after 0.9.27 */
#endif
    }
    Jit *jit = NULL;
    if (rc == 0) {
        jit = xcalloc(1, sizeof *jit);
        jit->state = s;
        if (!kernels_bind(&jit->kernels, tcc_find, s, prefix)) {
            sb_puts(&errors, "a generated function is missing after compilation\n");
            rc = -1;
            free(jit);
            jit = NULL;
        }
    }
    if (rc != 0) {
        char path[512];
        save_failed_source(source, prefix, path, sizeof path);
        diag_error_nopos(diag, "internal error: the generated C did not compile with libtcc "
                         "(a bug in mechc; source saved to %s):\n%s", path, errors.data);
        tcc_delete(s);
    }
    sb_free(&errors);
    return jit;
}

const Kernels *jit_kernels(const Jit *jit) { return &jit->kernels; }

void jit_free(Jit *jit)
{
    if (!jit)
        return;
    tcc_delete(jit->state);
    free(jit);
}
