/* design_loop.c - libmechc embedded in a program: a four-bar's coupler length edited, recompiled in process and run, in a loop.
 *
 * Build against an installed mechc (make install) and run from the
 * repository root:
 *
 *     cc examples/embed/design_loop.c $(pkg-config --cflags --libs mechc) -o design_loop
 *     ./design_loop [examples/four_bar.mech]
 *
 * For each coupler length b it rewrites the file's `param b = ...` line,
 * loads the text, compiles it with the jit, runs one crank turn (360
 * steps) and prints the rocker's swing and what the load and recompile
 * took. Then the same loop on examples/freudenstein.mech, the same
 * four-bar with its lengths as `design` parameters: there a length is set
 * without recompiling, and the swings are the same.
 */
#define _POSIX_C_SOURCE 200809L   /* clock_gettime */
#include <mechc.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 64);
    if (text && fread(text, 1, (size_t)n, f) != (size_t)n) {
        free(text);
        text = NULL;
    }
    if (text)
        text[n] = '\0';
    fclose(f);
    return text;
}

/* text with its line "param b ..." replaced by "param b = B" (malloc'd). */
static char *with_coupler(const char *text, double b)
{
    const char *line = strstr(text, "\nparam b ");
    if (!line)
        return NULL;
    line++;
    const char *end = strchr(line, '\n');
    size_t head = (size_t)(line - text), tail = strlen(end);
    char *out = malloc(head + tail + 64);
    memcpy(out, text, head);
    int n = snprintf(out + head, 64, "param b = %.17g", b);
    memcpy(out + head + n, end, tail + 1);
    return out;
}

/* The swing of coordinate i over the run's states, in degrees. */
static double swing(const mechc_result *r, int nq, int i)
{
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (int s = 0; s < mechc_result_states(r); s++) {
        double v = mechc_result_q(r)[s * nq + i];
        lo = v < lo ? v : lo;
        hi = v > hi ? v : hi;
    }
    return (hi - lo) * 180 / 3.14159265358979323846;
}

/* One crank turn, t from 0 to t1, in 360 steps; the rocker's swing, or a
   negative number (reported). */
static double turn(mechc_kernels *k, double t1)
{
    mechc_model *m = mechc_kernels_model(k);
    mechc_run_options o = mechc_run_defaults();
    o.steps = 360;
    o.t1 = t1;
    mechc_diag d;
    mechc_result *r = mechc_run(k, &o, &d);
    if (!r || mechc_result_status(r) != MECHC_OK) {
        printf("  run failed: %s\n", d.message);
        mechc_result_free(r);
        return -1;
    }
    double deg = swing(r, mechc_nq(m), mechc_coord_index(m, "rocker.phi"));
    mechc_result_free(r);
    return deg;
}

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "examples/four_bar.mech";
    char *text = read_text(path);
    if (!text) {
        fprintf(stderr, "design_loop: cannot read %s\n", path);
        return 1;
    }
    printf("libmechc %s: %s, coupler length b edited and recompiled\n", mechc_version(), path);
    static const double lengths[] = {2.6, 2.8, 3.0, 3.2, 3.4};
    double total = 0;
    for (int i = 0; i < 5; i++) {
        char *edited = with_coupler(text, lengths[i]);
        mechc_diag d;
        double t0 = now();
        mechc_model *m = edited ? mechc_load_string(edited, path, &d) : NULL;
        mechc_kernels *k = m ? mechc_compile(m, "jit", &d) : NULL;
        double dt = now() - t0;
        free(edited);
        if (!k) {
            fprintf(stderr, "%s:%d:%d: error: %s\n", d.file, d.line, d.column, d.message);
            return 1;
        }
        total += dt;
        printf("b = %.1f  rocker swing %.2f deg  load + recompile %.2f ms\n", lengths[i], turn(k, 1),
               1e3 * dt);
        mechc_kernels_free(k);
        mechc_model_free(m);
    }
    printf("mean load + recompile: %.2f ms\n", 1e3 * total / 5);
    free(text);

    /* design parameters: no recompiling (the crank turns at 1 rad/s there) */
    mechc_diag d;
    mechc_model *m = mechc_load_file("examples/freudenstein.mech", &d);
    mechc_kernels *k = m ? mechc_compile(m, "jit", &d) : NULL;
    if (!k) {
        fprintf(stderr, "examples/freudenstein.mech: %s\n", d.message);
        return 1;
    }
    for (int i = 0; i < 5; i++) {
        double t0 = now();
        mechc_set_design(m, "b", lengths[i]);
        double dt = now() - t0;
        printf("design b = %.1f  rocker swing %.2f deg  set without recompiling in %.3f ms\n",
               lengths[i], turn(k, 2 * 3.14159265358979323846), 1e3 * dt);
    }
    mechc_kernels_free(k);
    mechc_model_free(m);
    return 0;
}
