/* cmd_bench.c - mechc bench: the engines timed side by side in one run.
 *
 * Every (engine, function) pair is timed in batches long enough for the
 * clock (about a millisecond each, calibrated once); the repeats are
 * interleaved (repeat 1 of every pair, then repeat 2, ...), so a change
 * of machine load touches all engines alike, and the median of the
 * repeats is reported. All buffers are allocated before timing.
 *
 * A file with masses adds the dynamics kernels: mass (M, dense), force
 * (Q), m+q (both, what a forward-dynamics step needs of them) and eom
 * (M, Q, Phi_q and gamma: the generated P_eom, which shares sin and cos;
 * for the generic engine, which has no fused kernel, its four calls) and
 * mass_nz (M's nonzeros in the generated kernel's pattern, what the
 * sparse path of sim calls; the generic engine's from its jets) and
 * m+q_nz (mass_nz and force).
 */
#include "cli.h"

#include "../render/progress.h"

#include "../base/arena.h"
#include "../engine/aot.h"

#include <stdlib.h>
#include <string.h>

/* What the command line asked for. */
typedef struct BenchCli {
    mechc_limits limits;
    int repeat;
    bool json, use_aot;
} BenchCli;

static const char usage[] =
    "usage: mechc bench FILE.mech [--repeat N] [--no-aot] [--json]\n"
    "\n"
    "Times phi, jac, nu, gamma (and all) of each engine side by side: generic (no\n"
    "code generation), jit (generated C compiled by libtcc) and aot (the same C built\n"
    "by the system compiler, $CC or cc, with " AOT_FLAGS "). Reports ns per call\n"
    "(median of interleaved repeats), the speed-up against generic, generation and\n"
    "compile times, code size and operation counts. With masses in the file also\n"
    "mass, force, m+q (both), eom (M, Q, Phi_q and gamma in one call), mass_nz\n"
    "(M's nonzeros, what sim's sparse path calls) and m+q_nz (mass_nz and force).\n"
    "\n";

static const CliOption options[] = {
    {"--repeat", CLI_INT_AT(BenchCli, repeat, 1, 100000), .metavar = "N",
     .help = "timed repeats per engine and function (default 15)"},
    {"--no-aot", CLI_CLEAR_AT(BenchCli, use_aot), .help = "leave the aot engine out"},
    {"--json", CLI_FLAG_AT(BenchCli, json),
     .help = "print JSON: engines{generic,jit,aot}{phi,jac,nu,gamma,all} in ns,\n"
             "gen_s, tcc_s, cc_s, ops{...}, speedup{...}"},
};

/* jac_nz (the sparse Jacobian) exists only in generated code; the
   dynamics rows only for a file with masses. */
enum { FN_PHI, FN_JAC, FN_NU, FN_GAMMA, FN_ALL, FN_JAC_NZ, FN_MASS, FN_FORCE, FN_MQ, FN_EOM,
       FN_MASS_NZ, FN_MQ_NZ, FN_PHI_P, FN_SENS_V, FN_SENS_G, FN_SENS_Y, FN_PHI_P_NZ, FN_COUNT };
static const char *const fn_names[FN_COUNT] = {"phi", "jac", "nu", "gamma", "all", "jac_nz",
                                               "mass", "force", "m+q", "eom", "mass_nz",
                                               "m+q_nz", "phi_p", "sens_v", "sens_g", "sens_y",
                                               "phi_p_nz"};

/* Functions only generated code has (no generic counterpart, no ratio). */
static bool generated_only(int fn)
{
    return fn == FN_JAC_NZ;
}
static const EngineKind order[ENGINE_KIND_COUNT] = {ENGINE_GENERIC, ENGINE_JIT, ENGINE_AOT};

typedef struct Bench {
    mechc_kernels *kernels[ENGINE_KIND_COUNT];  /* compiled through libmechc ... */
    const Engine *eng[ENGINE_KIND_COUNT];       /* ... their engines, timed directly */
    bool open[ENGINE_KIND_COUNT];
    double *q, *qd, t;
    double *phi, *jac, *nu, *gamma, *mass, *force;
    bool dynamics;                              /* the file has masses */
    bool design;                                /* the file has design parameters: */
    double *sens, *sens_out[DESIGN_Y_COUNT];    /* where its sensitivity functions write */
    long batch[ENGINE_KIND_COUNT][FN_COUNT];
    double *ns[ENGINE_KIND_COUNT][FN_COUNT];    /* one per repeat */
    double median[ENGINE_KIND_COUNT][FN_COUNT];
} Bench;

/* One call of a dynamics function; the generic engine's eom is its four calls. */
static void call_dynamics(Bench *b, const Engine *e, int fn)
{
    const MechrtKernels *k = &e->k;
    if (fn == FN_MASS || fn == FN_MQ)
        k->mass(k->ctx, b->q, b->mass);
    if (fn == FN_MASS_NZ || fn == FN_MQ_NZ) {
        const MechrtHostMassNz *mnz = engine_mass_nz(e);
        mnz->mass_nz(mnz->ctx, b->q, b->mass);
    }
    if (fn == FN_FORCE || fn == FN_MQ || fn == FN_MQ_NZ)
        k->force(k->ctx, b->q, b->qd, b->t, b->force);
    if (fn != FN_EOM)
        return;
    if (e->compiled) {
        e->kernels.eom(b->q, b->qd, b->t, b->mass, b->force, b->jac, b->gamma);
        return;
    }
    k->mass(k->ctx, b->q, b->mass);
    k->force(k->ctx, b->q, b->qd, b->t, b->force);
    k->jac(k->ctx, b->q, b->t, b->jac);
    k->gamma(k->ctx, b->q, b->qd, b->t, b->gamma);
}

/* Seconds taken by n calls of one function. */
static double time_batch(Bench *b, EngineKind k, int fn, long n)
{
    const Engine *e = b->eng[k];
    double t0 = pipeline_now();
    for (long i = 0; i < n; i++) {
        if (fn >= FN_PHI_P) {
            engine_design(e, (DesignFn)(fn - FN_PHI_P), b->q, b->qd, b->t, b->sens_out);
            continue;
        }
        if (fn >= FN_MASS) {
            call_dynamics(b, e, fn);
            continue;
        }
        switch (fn) {
        case FN_PHI:   engine_phi(e, b->q, b->t, b->phi); break;
        case FN_JAC:   engine_jac(e, b->q, b->t, b->jac); break;
        case FN_NU:    engine_nu(e, b->q, b->t, b->nu); break;
        case FN_GAMMA: engine_gamma(e, b->q, b->qd, b->t, b->gamma); break;
        case FN_ALL:   engine_all(e, b->q, b->qd, b->t, b->phi, b->jac, b->nu, b->gamma); break;
        default:       e->kernels.jac_nz(b->q, b->t, b->jac); break;
        }
    }
    return pipeline_now() - t0;
}

static int compare_doubles(const void *x, const void *y)
{
    double a = *(const double *)x, c = *(const double *)y;
    return (a > c) - (a < c);
}

/* A row of the tables: every function but the dynamics ones without masses, the design
   ones without design parameters. */
static bool shown(const Bench *b, int fn)
{
    return fn < FN_MASS || (fn < FN_PHI_P && b->dynamics) || (fn >= FN_PHI_P && b->design);
}

static bool has_fn(const Bench *b, int k, int fn)
{
    return b->open[k] && (!generated_only(fn) || b->eng[k]->compiled) && shown(b, fn);
}


static void measure(Bench *b, int repeat)
{
    const double target = 1e-3;     /* seconds per batch */
    for (int k = 0; k < ENGINE_KIND_COUNT; k++) {
        if (!b->open[k])
            continue;
        for (int fn = 0; fn < FN_COUNT; fn++) {
            if (!has_fn(b, k, fn))
                continue;
            long n = 1;
            double s;
            time_batch(b, (EngineKind)k, fn, 1);        /* warm the caches */
            while ((s = time_batch(b, (EngineKind)k, fn, n)) < target && n < (1L << 30))
                n = s <= 0 ? n * 8 : (long)((double)n * (1.2 * target / s)) + 1;
            b->batch[k][fn] = n;
        }
    }
    Progress progress;
    progress_start(&progress, "bench", repeat);
    for (int r = 0; r < repeat; r++, progress_update(&progress, r))
        for (int i = 0; i < ENGINE_KIND_COUNT; i++) {
            EngineKind k = order[i];
            if (!b->open[k])
                continue;
            for (int fn = 0; fn < FN_COUNT; fn++)
                if (has_fn(b, k, fn))
                    b->ns[k][fn][r] = 1e9 * time_batch(b, k, fn, b->batch[k][fn]) / (double)b->batch[k][fn];
        }
    progress_finish(&progress);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        for (int fn = 0; fn < FN_COUNT && b->open[k]; fn++) {
            if (!has_fn(b, k, fn))
                continue;
            qsort(b->ns[k][fn], (size_t)repeat, sizeof(double), compare_doubles);
            b->median[k][fn] = repeat % 2 ? b->ns[k][fn][repeat / 2]
                                          : 0.5 * (b->ns[k][fn][repeat / 2 - 1] + b->ns[k][fn][repeat / 2]);
        }
}

/* The emitted source's size and op counts: the jit's, else the aot's. */
static const EmitResult *emitted(const Bench *b)
{
    if (b->open[ENGINE_JIT])
        return &b->eng[ENGINE_JIT]->emitted;
    if (b->open[ENGINE_AOT])
        return &b->eng[ENGINE_AOT]->emitted;
    return NULL;
}

/* The operation count of a row (m+q: mass and force together). */
static int ops_of(const EmitResult *er, int fn)
{
    static const int map[FN_COUNT] = {EMIT_PHI, EMIT_JAC, EMIT_NU, EMIT_GAMMA, EMIT_ALL,
                                      EMIT_JAC_NZ, EMIT_MASS, EMIT_FORCE, -1, EMIT_EOM,
                                      EMIT_MASS_NZ, -1, EMIT_PHI_P, EMIT_SENS_V, EMIT_SENS_G,
                                      EMIT_SENS_Y, EMIT_PHI_P_NZ};
    if (fn == FN_MQ)
        return er->ops[EMIT_MASS] + er->ops[EMIT_FORCE];
    if (fn == FN_MQ_NZ)
        return er->ops[EMIT_MASS_NZ] + er->ops[EMIT_FORCE];
    return er->ops[map[fn]];
}

static void print_json(const Model *m, const Bench *b, int repeat)
{
    printf("{\"mechanism\": ");
    json_string(stdout, m->name);
    printf(", \"nq\": %d, \"nh\": %d, \"nv\": %d, \"nr\": %d, \"repeat\": %d,\n \"engines\": {",
           m->nq, m->nh, m->nv, m->nr, repeat);
    bool first = true;
    for (int i = 0; i < ENGINE_KIND_COUNT; i++) {
        EngineKind k = order[i];
        if (!b->open[k])
            continue;
        printf("%s\"%s\": {", first ? "" : ",\n             ", engine_names[k]);
        first = false;
        for (int fn = 0; fn < FN_COUNT; fn++) {
            if (!has_fn(b, k, fn))
                continue;
            printf("%s\"%s\": ", fn ? ", " : "", fn_names[fn]);
            json_number(stdout, b->median[k][fn]);
        }
        printf("}");
    }
    printf("},\n \"speedup\": {");
    first = true;
    for (int i = 1; i < ENGINE_KIND_COUNT; i++) {
        EngineKind k = order[i];
        if (!b->open[k] || !b->open[ENGINE_GENERIC])
            continue;
        printf("%s\"%s\": {", first ? "" : ", ", engine_names[k]);
        first = false;
        for (int fn = 0; fn < FN_COUNT; fn++) {
            if (generated_only(fn) || !shown(b, fn))
                continue;
            printf("%s\"%s\": ", fn ? ", " : "", fn_names[fn]);
            json_number(stdout, b->median[ENGINE_GENERIC][fn] / b->median[k][fn]);
        }
        printf("}");
    }
    printf("}");
    const EmitResult *er = emitted(b);
    if (b->open[ENGINE_JIT]) {
        printf(",\n \"gen_s\": ");
        json_number(stdout, b->eng[ENGINE_JIT]->gen_seconds);
        printf(", \"tcc_s\": ");
        json_number(stdout, b->eng[ENGINE_JIT]->compile_seconds);
    }
    if (b->open[ENGINE_AOT]) {
        printf(", \"cc_s\": ");
        json_number(stdout, b->eng[ENGINE_AOT]->compile_seconds);
    }
    if (b->open[ENGINE_GENERIC]) {
        printf(", \"generic_setup_s\": ");
        json_number(stdout, b->eng[ENGINE_GENERIC]->gen_seconds);
    }
    if (er) {
        printf(",\n \"code_bytes\": %zu, \"ops\": {", strlen(er->c_text));
        for (int fn = 0; fn < FN_COUNT; fn++)
            if (shown(b, fn))
                printf("%s\"%s\": %d", fn ? ", " : "", fn_names[fn], ops_of(er, fn));
        printf("}");
    }
    printf("}\n");
}

static void print_text(const Model *m, const Bench *b, int repeat)
{
    printf("bench %s: nq %d, nr %d (nh %d, nv %d); ns per call, median of %d interleaved repeats\n\n",
           m->name, m->nq, m->nr, m->nh, m->nv, repeat);
    printf("%-6s", "");
    for (int i = 0; i < ENGINE_KIND_COUNT; i++)
        if (b->open[order[i]])
            printf("  %10s", engine_names[order[i]]);
    for (int i = 1; i < ENGINE_KIND_COUNT; i++)
        if (b->open[order[i]] && b->open[ENGINE_GENERIC])
            printf("  %11s/gen", engine_names[order[i]]);
    const EmitResult *er = emitted(b);
    if (er)
        printf("  %8s", "ops");
    printf("\n");
    for (int fn = 0; fn < FN_COUNT; fn++) {
        if (!shown(b, fn))
            continue;
        printf("%-6s", fn_names[fn]);
        for (int i = 0; i < ENGINE_KIND_COUNT; i++)
            if (has_fn(b, order[i], fn))
                printf("  %10.1f", b->median[order[i]][fn]);
            else if (b->open[order[i]])
                printf("  %10s", "-");
        for (int i = 1; i < ENGINE_KIND_COUNT; i++)
            if (b->open[order[i]] && b->open[ENGINE_GENERIC] && !generated_only(fn))
                printf("  %14.2fx", b->median[ENGINE_GENERIC][fn] / b->median[order[i]][fn]);
            else if (b->open[order[i]] && b->open[ENGINE_GENERIC])
                printf("  %15s", "-");
        if (er)
            printf("  %8d", ops_of(er, fn));
        printf("\n");
    }
    printf("\n");
    if (b->open[ENGINE_JIT])
        printf("generation %.3f ms (%.1f kB of C), libtcc %.3f ms\n", 1e3 * b->eng[ENGINE_JIT]->gen_seconds,
               er ? (double)strlen(er->c_text) / 1024.0 : 0.0, 1e3 * b->eng[ENGINE_JIT]->compile_seconds);
    if (b->open[ENGINE_AOT])
        printf("cc %s: %.1f ms (compile and load)\n", AOT_FLAGS, 1e3 * b->eng[ENGINE_AOT]->compile_seconds);
    if (b->open[ENGINE_GENERIC])
        printf("generic evaluator set-up: %.3f ms\n", 1e3 * b->eng[ENGINE_GENERIC]->gen_seconds);
}

/* Compiles every engine asked for (aot only with a compiler); false
   (reported) when one fails. */
static bool open_engines(const Args *a, Bench *b, mechc_model *model, bool use_aot)
{
    mechc_compile_options co = mechc_compile_defaults();
    co.aot_fresh = 1;           /* time the compiler, not the cache */
    for (int i = 0; i < ENGINE_KIND_COUNT; i++) {
        EngineKind k = order[i];
        if (k == ENGINE_AOT && (!use_aot || !aot_compiler_available())) {
            if (use_aot)
                fprintf(stderr, "mechc bench: note: no C compiler found (set CC): aot left out\n");
            continue;
        }
        b->kernels[k] = cli_compile(a, model, k, &co);
        if (!b->kernels[k])
            return false;
        b->open[k] = true;
        b->eng[k] = &b->kernels[k]->engine;
    }
    return true;
}

/* Room for the sensitivity functions' outputs, each array as long as
   the longest, for a file with design parameters. */
static void open_design(Bench *b, const Model *m)
{
    b->design = m->np > 0;
    if (!b->design)
        return;
    size_t most = 0;
    const Kinematics *kin = NULL;
    for (int k = 0; k < ENGINE_KIND_COUNT && !kin; k++)
        kin = b->open[k] ? &b->eng[k]->mech->kin : NULL;
    for (int fn = 0; fn < DESIGN_FN_COUNT && kin; fn++) {
        const NodeId *from[DESIGN_Y_COUNT];
        size_t count[DESIGN_Y_COUNT];
        int arrays = design_arrays(kin, (DesignFn)fn, from, count);
        for (int i = 0; i < arrays; i++)
            most = count[i] > most ? count[i] : most;
    }
    b->sens = xcalloc(DESIGN_Y_COUNT * most + 1, sizeof *b->sens);
    for (int i = 0; i < DESIGN_Y_COUNT; i++)
        b->sens_out[i] = b->sens + (size_t)i * most;
}

/* Times the open engines at one fixed state and prints the report. */
static void run_bench(Bench *b, const Model *m, int repeat, bool json)
{
    size_t nq = (size_t)m->nq, nr = (size_t)m->nr;
    b->q = xcalloc(nq, sizeof *b->q);
    b->qd = xcalloc(nq, sizeof *b->qd);
    b->phi = xcalloc((size_t)m->nh + 1, sizeof *b->phi);
    b->jac = xcalloc(nr * nq + 1, sizeof *b->jac);
    b->nu = xcalloc(nr + 1, sizeof *b->nu);
    b->gamma = xcalloc(nr + 1, sizeof *b->gamma);
    b->mass = xcalloc(nq * nq, sizeof *b->mass);
    b->force = xcalloc(nq, sizeof *b->force);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        if (b->open[k])
            b->dynamics = b->eng[k]->k.mass != NULL && b->eng[k]->k.force != NULL;
    open_design(b, m);
    for (size_t i = 0; i < nq; i++) {
        b->q[i] = m->q0[i] + 0.01 * (double)((i * 7) % 5);
        b->qd[i] = 0.3 + 0.1 * (double)((i * 3) % 7);
    }
    b->t = 0.37;
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        for (int fn = 0; fn < FN_COUNT; fn++)
            b->ns[k][fn] = xcalloc((size_t)repeat, sizeof(double));
    measure(b, repeat);
    if (json)
        print_json(m, b, repeat);
    else
        print_text(m, b, repeat);
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        for (int fn = 0; fn < FN_COUNT; fn++)
            free(b->ns[k][fn]);
    free(b->q), free(b->qd), free(b->phi), free(b->jac), free(b->nu), free(b->gamma);
    free(b->mass), free(b->force), free(b->sens);
}

/* The engines timed and reported. */
static int bench_file(const Args *a, mechc_model *model, void *opts)
{
    Mech *mech = model->mech;
    const BenchCli *c = opts;
    Bench *b = xcalloc(1, sizeof *b);
    int status = EXIT_USAGE;
    if (open_engines(a, b, model, c->use_aot)) {
        run_bench(b, mech->model, c->repeat, c->json);
        status = EXIT_OK;
    }
    for (int k = 0; k < ENGINE_KIND_COUNT; k++)
        mechc_kernels_free(b->kernels[k]);
    free(b);
    return status;
}

static const CliCommand command = {
    .name = "bench", .usage = usage, CLI_OPTIONS(options), .column = 15,
    .limits_offset = offsetof(BenchCli, limits),
    .run = bench_file,
};

int cmd_bench(int argc, char **argv)
{
    BenchCli c = {.limits = mechc_default_limits(), .repeat = 15, .use_aot = true};
    return cli_main(&command, argc, argv, &c);
}
