/* aot.c - builds the generated C with the system compiler into a cached shared library and loads it.
 *
 * The compiler is started directly (posix_spawnp, no shell): $CC is split
 * at blanks, so CC="ccache gcc" works, and nothing in it is interpreted.
 * Libraries are named by a 128-bit FNV-1a hash of the source, the compiler
 * command and the flags, so a changed mechanism, mechc version, compiler
 * or flag set never reuses a stale library. Each build writes a private
 * temporary file and renames it into place (atomic on POSIX file
 * systems), so processes racing to build the same library each load a
 * complete one.
 */
#define _GNU_SOURCE 1
#include "aot.h"

#include "../base/arena.h"
#include "../base/strbuf.h"
#include "../pipeline/pipeline.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

enum { AOT_MAX_WORDS = 32 };

/* Splits buf in place at blanks, appending at most max words; returns the new count. */
static int split_words(char *buf, char **words, int n, int max)
{
    char *save = NULL;
    for (char *tok = strtok_r(buf, " \t", &save); tok && n < max; tok = strtok_r(NULL, " \t", &save))
        words[n++] = tok;
    return n;
}

/* $CC split at blanks into words (stored in buf). */
static int compiler_words(char *buf, size_t size, char **words)
{
    const char *cc = getenv("CC");
    if (!cc || !*cc)
        cc = "cc";
    snprintf(buf, size, "%s", cc);
    return split_words(buf, words, 0, AOT_MAX_WORDS);
}

/* Two FNV-1a 64-bit lanes with different offsets: 32 hex digits. */
typedef struct Hash {
    uint64_t a, b;
} Hash;

static void hash_bytes(Hash *h, const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        h->a = (h->a ^ (unsigned char)s[i]) * 1099511628211ull;
        h->b = (h->b ^ (unsigned char)s[i]) * 1099511628211ull;
        h->b ^= h->b >> 31;
    }
    /* a separator, so ("ab", "c") and ("a", "bc") differ */
    h->a = (h->a ^ 0xffu) * 1099511628211ull;
    h->b = (h->b ^ 0xffu) * 1099511628211ull;
}

bool aot_cache_dir(char *dir, size_t size, Diag *diag)
{
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    char base[900];
    if (xdg && xdg[0] == '/') {             /* the XDG spec ignores relative paths */
        snprintf(base, sizeof base, "%s", xdg);
    } else if (home && home[0] == '/') {
        snprintf(base, sizeof base, "%s/.cache", home);
    } else {
        diag_error_nopos(diag, "the aot engine needs a cache folder: set XDG_CACHE_HOME or HOME");
        return false;
    }
    mkdir(base, 0700);                      /* may exist already */
    snprintf(dir, size, "%s/mechc", base);
    if (mkdir(dir, 0700) != 0 && errno != EEXIST) {
        diag_error_nopos(diag, "the aot engine cannot create its cache folder %s: %s", dir, strerror(errno));
        return false;
    }
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        diag_error_nopos(diag, "the aot engine's cache %s is not a folder", dir);
        return false;
    }
    return true;
}

/* Runs the compiler; its output goes to log. Returns the exit status,
   -1 when it could not be started (errno-style code in *spawn_error). */
static int run_compiler(char **argv, const char *log, int *spawn_error)
{
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    pid_t pid;
    int rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) {
        *spawn_error = rc;
        return -1;
    }
    int status;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) {
            *spawn_error = errno;
            return -1;
        }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127) {
        *spawn_error = ENOENT;              /* exec failed after the spawn */
        return -1;
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool aot_compiler_available(void)
{
    char buf[1024], *words[AOT_MAX_WORDS + 3];
    int n = compiler_words(buf, sizeof buf, words);
    if (n == 0)
        return false;
    char version[] = "--version";      /* exec wants writable strings */
    words[n++] = version;
    words[n] = NULL;
    int err = 0;
    return run_compiler(words, "/dev/null", &err) == 0;
}

static void read_log(const char *log, StrBuf *out)
{
    FILE *f = fopen(log, "r");
    if (!f)
        return;
    char line[512];
    while (out->len < 1500 && fgets(line, sizeof line, f))
        sb_puts(out, line);
    fclose(f);
}

static bool write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return false;
    bool ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok;
}

/* Compiles source into lib (via a temporary name). */
static bool build(const char *dir, const char *hex, const char *source, const char *lib,
                  bool batch, Diag *diag)
{
    char cc_buf[1024], *argv[AOT_MAX_WORDS + 19];
    int n = compiler_words(cc_buf, sizeof cc_buf, argv);
    if (n == 0) {
        diag_error_nopos(diag, "the aot engine needs a C compiler: CC is blank");
        return false;
    }
    char src[1200], tmp[1200], log[1200];
    int id = (int)getpid();
    snprintf(src, sizeof src, "%s/%s.%d.tmp.c", dir, hex, id);
    snprintf(tmp, sizeof tmp, "%s/%s.%d.tmp.so", dir, hex, id);
    snprintf(log, sizeof log, "%s/%s.%d.tmp.log", dir, hex, id);
    if (!write_file(src, source)) {
        diag_error_nopos(diag, "the aot engine cannot write %s: %s", src, strerror(errno));
        unlink(src);
        return false;
    }
    char flags[] = AOT_FLAGS, batch_flags[] = AOT_BATCH_FLAGS;
    n = split_words(flags, argv, n, AOT_MAX_WORDS + 10);
    if (batch)
        n = split_words(batch_flags, argv, n, AOT_MAX_WORDS + 13);
    char opt_o[] = "-o", opt_lm[] = "-lm";
    argv[n++] = opt_o;
    argv[n++] = tmp;
    argv[n++] = src;
    argv[n++] = opt_lm;
    argv[n] = NULL;
    int err = 0;
    int status = run_compiler(argv, log, &err);
    bool ok = false;
    if (status < 0) {
        diag_error_nopos(diag, "the aot engine needs a C compiler: '%s' could not be started (%s); "
                         "install one (cc, gcc or clang) or set CC", argv[0], strerror(err));
    } else if (status != 0) {
        StrBuf out;
        sb_init(&out);
        sb_puts(&out, "");
        read_log(log, &out);
        diag_error_nopos(diag, "internal error: the generated C did not compile with '%s' "
                         "(exit status %d; a bug in mechc, or a broken compiler):\n%s",
                         argv[0], status, out.data);
        sb_free(&out);
    } else if (rename(tmp, lib) != 0) {
        diag_error_nopos(diag, "the aot engine cannot move its library to %s: %s", lib, strerror(errno));
    } else {
        ok = true;
    }
    unlink(src);
    unlink(log);
    unlink(tmp);        /* gone after a successful rename */
    return ok;
}

struct Aot {
    void *handle;           /* dlopen's */
    Kernels kernels;
};

/* The vector extensions of this machine (x86: what -march=native may
   use), for the batch units' cache key. */
static void hash_machine(Hash *h)
{
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    char features[8] = {
        (char)('0' + !!__builtin_cpu_supports("sse4.2")),
        (char)('0' + !!__builtin_cpu_supports("avx")),
        (char)('0' + !!__builtin_cpu_supports("avx2")),
        (char)('0' + !!__builtin_cpu_supports("fma")),
        (char)('0' + !!__builtin_cpu_supports("avx512f")), 0};
    hash_bytes(h, features, strlen(features));
#else
    (void)h;
#endif
}

Aot *aot_load(const char *source, const char *prefix, bool fresh, AotResult *out, Diag *diag)
{
    return aot_load_with(source, prefix, fresh, false, out, diag);
}

Aot *aot_load_with(const char *source, const char *prefix, bool fresh, bool batch, AotResult *out,
                   Diag *diag)
{
    memset(out, 0, sizeof *out);
    double t0 = pipeline_now();
    char dir[1024];
    if (!aot_cache_dir(dir, sizeof dir, diag))
        return NULL;
    char cc_buf[1024], *words[AOT_MAX_WORDS];
    int n = compiler_words(cc_buf, sizeof cc_buf, words);
    Hash h = {14695981039346656037ull, 0x84222325cbf29ce4ull};
    hash_bytes(&h, source, strlen(source));
    for (int i = 0; i < n; i++)
        hash_bytes(&h, words[i], strlen(words[i]));
    hash_bytes(&h, AOT_FLAGS, strlen(AOT_FLAGS));
    if (batch) {
        hash_bytes(&h, AOT_BATCH_FLAGS, strlen(AOT_BATCH_FLAGS));
        hash_machine(&h);
    }
    char hex[40];
    snprintf(hex, sizeof hex, "%016llx%016llx", (unsigned long long)h.a, (unsigned long long)h.b);
    snprintf(out->path, sizeof out->path, "%s/%s.so", dir, hex);

    out->cached = !fresh && access(out->path, R_OK) == 0;
    if (!out->cached && !build(dir, hex, source, out->path, batch, diag))
        return NULL;
    void *handle = dlopen(out->path, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        diag_error_nopos(diag, "the aot engine cannot load %s: %s", out->path, dlerror());
        return NULL;
    }
    Aot *aot = xcalloc(1, sizeof *aot);
    aot->handle = handle;
    if (!kernels_bind(&aot->kernels, dlsym, handle, prefix)) {
        diag_error_nopos(diag, "internal error: %s lacks a generated function (remove it and retry)",
                         out->path);
        aot_unload(aot);
        return NULL;
    }
    out->seconds = pipeline_now() - t0;
    return aot;
}

const Kernels *aot_kernels(const Aot *aot) { return &aot->kernels; }

void aot_unload(Aot *aot)
{
    if (!aot)
        return;
    dlclose(aot->handle);
    free(aot);
}
