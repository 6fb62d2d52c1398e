/* test_fuzz_replay.c - replays the fuzzing corpus and every saved regression through the harness.
 *
 * tests/fuzz/fuzz_frontend.c is compiled in here without libFuzzer: each
 * file of tests/fuzz/corpus (the seeds), the .mech files of examples/ and
 * tests/fuzz/regressions (inputs that once crashed, hung or leaked, see
 * tests/fuzz/README.md) goes through fuzz_frontend(), which aborts on a
 * broken invariant. Each input
 * must also finish within a time bound, the fuzzer's hang criterion.
 */
#include "testutil.h"

#include "fuzz/fuzz_frontend.c"

#include <dirent.h>
#include <sys/stat.h>
#include <errno.h>
#include <time.h>

/* Seconds one input may take: libFuzzer's -timeout=1 under ASan, with
   room for valgrind, which runs everything some 20-50 times slower. */
enum { SECONDS_PER_INPUT = 60 };

/* The tests/fuzz folder: from the repository root (make check), else
   next to this source file. */
static const char *fuzz_dir(void)
{
    static char dir[1024];
    const char *candidates[] = {"tests/fuzz", NULL};
    struct stat st;
    for (int i = 0; candidates[i]; i++)
        if (stat(candidates[i], &st) == 0 && S_ISDIR(st.st_mode))
            return candidates[i];
    snprintf(dir, sizeof dir, "%s", __FILE__);
    char *slash = strrchr(dir, '/');
    snprintf(slash ? slash + 1 : dir, sizeof dir - (size_t)(slash ? slash + 1 - dir : 0), "fuzz");
    return dir;
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0) {
        n += got;
        if (n == cap)
            buf = realloc(buf, cap *= 2);
    }
    fclose(f);
    *size = n;
    return buf;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcmp(s + n - k, suffix) == 0;
}

/* Runs every file of tests/fuzz/SUB whose name ends with suffix ("" for
   all), in name order; returns the count. */
static int replay(const char *sub, const char *suffix)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/%s", fuzz_dir(), sub);
    DIR *d = opendir(path);
    if (!d)
        fail_msg("cannot open %s: %s", path, strerror(errno));
    char **names = NULL;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.' || strcmp(e->d_name, "README.md") == 0
            || !ends_with(e->d_name, suffix))
            continue;
        names = realloc(names, (size_t)(n + 1) * sizeof *names);
        names[n++] = strdup(e->d_name);
    }
    closedir(d);
    if (n > 1)
        qsort(names, (size_t)n, sizeof *names, compare_names);
    for (int i = 0; i < n; i++) {
        char file[4096];
        snprintf(file, sizeof file, "%s/%s", path, names[i]);
        size_t size = 0;
        char *data = read_all(file, &size);
        if (!data)
            fail_msg("cannot read %s", file);
        double t0 = now();
        assert_int_equal(fuzz_frontend((const uint8_t *)data, size), 0);
        double seconds = now() - t0;
        if (seconds > SECONDS_PER_INPUT)
            fail_msg("%s took %.1f s (more than %d s: a hang)", file, seconds, SECONDS_PER_INPUT);
        free(data);
        free(names[i]);
    }
    free(names);
    print_message("replayed %d inputs from %s\n", n, path);
    return n;
}

static void test_corpus(void **state)
{
    (void)state;
    assert_true(replay("corpus", "") > 0);
}

/* The examples are seeds too (make fuzz takes them from examples/, with
   what the generator scripts write: tests/fuzz/seeds.sh). */
static void test_examples(void **state)
{
    (void)state;
    assert_true(replay("../../examples", ".mech") > 30);
}

static void test_regressions(void **state)
{
    (void)state;
    assert_true(replay("regressions", "") > 0);
}

/* The harness itself must notice bad output: a sanity check of its guards. */
static void test_guards_detect(void **state)
{
    (void)state;
    Guarded g = guarded_new(3);
    for (int i = 0; i < 3; i++)
        g.v[i] = i;
    guarded_check(&g, "all written");
    put_bits(&g.v[1], unset_bits);
    bool unwritten = has_bits(&g.v[1], unset_bits);
    assert_true(unwritten);
    g.v[1] = 0.0;
    g.v[3] = 1.0;       /* one past the end */
    assert_false(has_bits(&g.v[3], guard_bits));
    free(g.base);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_corpus),
        cmocka_unit_test(test_examples),
        cmocka_unit_test(test_regressions),
        cmocka_unit_test(test_guards_detect),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
